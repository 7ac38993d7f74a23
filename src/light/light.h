/* light: direct lamp light in 2.5D (SPEC §2), exact visibility.
 *
 *   E(P) = sum over lamps of V(L,P) I max(0, n.w) / d^2 W(d / R)
 *
 * Two ways to decide V, which agree (tests/unit/test_light.c checks both
 * against the brute-force tests/ref/ref_light):
 *
 * 1. The segment path (light_segment_blocked, light_illuminance_exact).
 *    Blocking is a union over buildings, so V = AND over buildings of
 *    "building k does not block". For building k and the 2D segment L'->P'
 *    (parameter t in [0, 1], the same parameter as the 3D segment), the
 *    footprint's open interior meets the segment's line in open t-intervals
 *    found from edge crossings with exact signs (geom_orient): a vertex on
 *    the line counts as lying on its left (an infinitesimal shift of the
 *    line to the right), which makes grazing a vertex a zero-length contact,
 *    and the t-ranges of edges lying on the line are then taken out (running
 *    along a wall is not interior). The height along the segment is linear,
 *    so min_height < z(t) < height is one open t-interval; k blocks when some
 *    interior interval overlaps it, inside (0, 1), by more than
 *    LIGHT_MIN_PIECE metres of 3D length (the reference's 1e-9 m rule; only
 *    the crossing parameters are rounded). A vertical segment (L' == P') is
 *    blocked when L' is strictly inside the footprint and the z-ranges
 *    overlap. Candidates come from a uniform grid of building boxes, walked
 *    row by row along the segment (each building tested once per segment).
 *
 * 2. The lit-region path (light_region, light_illuminance). Per lamp, the
 *    buildings whose box comes within the reach R (horizontally) are
 *    gathered from the same grid; the directions from the lamp's ground
 *    point O to all their vertices, sorted by pseudo-angle, cut the plane
 *    into angular sectors. Inside a sector every ray from O crosses the same
 *    edges in the same order (footprints are simple and the edge set changes
 *    only at vertex directions), so each building meets the ray in fixed
 *    intervals ("bands") bounded by two edge lines. A query point then finds
 *    its sector by binary search and tests only that sector's bands, with
 *    the same overlap rule as path 1 (t of a band end = c / cross(w, e) for
 *    the edge line, w = P' - O). On the ground a band of building (m, h)
 *    shadows the open interval (a zL/(zL-m), b zL/(zL-h)) of distances
 *    along the ray (b to infinity when h >= zL, none when m >= zL): the
 *    union of copies of the footprint scaled about O, as in the suggested
 *    construction; on a facade at horizontal parameter u the blocked heights
 *    form one open z-interval whose ends are affine in u.
 *
 *    Why not the polar diagram fan (polar.h, visibility.h): in 2.5D a lower
 *    building does not hide what is above it, so the first wall met by a 2D
 *    ray is not enough: every building in reach along the ray matters. The
 *    critical directions are still those of the fan (tangent rays through
 *    vertices) plus the crossings of scaled edges, and with a lamp reach of
 *    tens of metres the buildings in reach are few, so a grid and a sort of
 *    their vertex directions is simpler and cheaper than walking the
 *    diagram (which also treats buildings as infinitely tall and leaves out
 *    raised ones).
 *
 *    Lit polygons (the output of a region):
 *    - ground: rings, counter-clockwise, covering the lit ground
 *      within the reach polygon: the 360-gon inscribed in the circle of the
 *      ground reach Rg = sqrt(R^2 - zL^2), its vertices on the rays every
 *      1 degree. Inside a sector the bounds along a ray (scaled edge lines,
 *      the reach polygon) keep their order except where two lines cross or
 *      a line crosses the reach polygon (found from the side each line is
 *      on at the rays: within one chord's span it crosses that chord
 *      exactly when its side changes); those directions cut the sector into
 *      sub-sectors, and each lit interval of a sub-sector is one ring: a
 *      quad (a triangle from O) between two lines, or a ring from a line
 *      (or O) out to the reach polygon through the vertices of the rays in
 *      between. Rings following the reach polygon have at most 64 points
 *      (longer runs are split at a ray); runs of unshadowed sectors are
 *      one fan ring O, reach points... Crossings of two lines beyond the
 *      reach circle are not cuts (nothing there is kept). The ground
 *      between chord and arc (at most R (1 - cos 0.5 deg) ~ 3.8e-5 R deep)
 *      is left out, where W(d/R) <= 3e-8 (W(1) = 0), so the light missed
 *      there is nil; the visibility queries are not cut off.
 *    - facades: on every wall facing the lamp (O strictly on its outer
 *      side) that comes within R horizontally, quads in the wall's vertical
 *      plane (3D corners, counter-clockwise seen from outside) covering its
 *      lit part; horizontally clipped to the reach disk about O (the wall
 *      part within R horizontally; beyond the sphere d = R the light is 0
 *      anyway), vertically to [min_height, height].
 *    Degenerate pieces (zero width at their middle) are dropped.
 *
 * Degenerate cases (as tests/ref/ref_light.h): the solid is open; the
 * segment is open; contacts of at most LIGHT_MIN_PIECE are ignored; a
 * segment along a wall shared by two buildings is not blocked (buildings are
 * tested one by one); d == 0 or R <= 0 contributes 0. SPEC §2 lets points
 * within 1e-6 m of a shadow boundary go either way; both paths use rounded
 * crossing parameters (errors ~1e-15 relative) only there.
 *
 * Memory: everything comes from the arena. light_create takes the object,
 * the two grids, per-lamp cache entries and a pool of cache_bytes, all in
 * part PLX_PART_LIT. Regions live in the pool, least recently used evicted
 * first (then the pool is compacted). Queries cache index-only regions
 * (sectors, bands, lines: ~2 KiB a lamp); light_region replaces one by the
 * full region with polygons (~5-10 KiB). A lamp no query reaches is never
 * computed. Computing a region uses scratch
 * memory (arena_scratch, released before return): the working arrays, and
 * an output buffer of at most the pool's size. Queries allocate nothing
 * except when a region has to be computed. No global state; one light
 * object must not be used from two threads at once (queries update the
 * cache).
 */
#ifndef PLX_LIGHT_H
#define PLX_LIGHT_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/scene.h"
#include "base/arena.h"
#include "base/bucketgrid.h"

#define LIGHT_MIN_PIECE 1e-9  /* m: shorter contacts with a solid are grazing */
#define LIT_NONE 0xffffffffu

/* ---- the light object -------------------------------------------------- */

typedef struct light_entry {
    struct lit_region *reg;   /* NULL when not cached */
    uint32_t prev, next;      /* LRU list, most recent first */
    uint32_t aprev, anext;    /* address order in the pool */
} light_entry;

typedef struct light_stats {
    uint64_t hits, misses, evictions, compactions, computed;
    uint64_t fallbacks;       /* queries answered by the segment path because
                                 a region could not be computed */
    uint64_t failed;          /* region computations that ran out of memory
                                 (a lamp's is not tried again until more
                                 memory is free: light.failed) */
} light_stats;

typedef struct light {
    arena *a;
    const scene *s;
    bucketgrid bgrid;         /* buildings, by box */
    bucketgrid lgrid;         /* lamps, by the box of their reach disk */
    double bcell;             /* bgrid's cell size (m) */
    uint32_t *stamp;          /* per building: last visit */
    uint32_t stamp_now;
    uint32_t maxv;            /* most ring vertices of one building */
    double *cross_t;          /* segment test buffers, maxv each */
    int *cross_d;
    double *col;              /* 2 maxv */
    /* cache */
    unsigned char *pool;
    size_t pool_cap, pool_end, pool_live;
    light_entry *ent;         /* one per lamp */
    unsigned char *failed;    /* a bit per lamp: its region ran out of
                                 memory, with at most fail_free bytes free
                                 in the arena; not tried again until more
                                 is free (then every bit is cleared) */
    size_t fail_free;
    uint32_t lru_head, lru_tail, addr_head, addr_tail;
    uint32_t ncached;
    light_stats st;
    /* the 360 rays of the reach polygon: unit directions, pseudo-angles */
    double ray_dir[360][2];
    double ray_ang[360];
} light;

/* Creates the light object for scene s (which must stay unchanged while the
 * object lives) with a region cache of cache_bytes (0: no cache; the
 * illuminance then always takes the segment path). All memory from a, part
 * PLX_PART_LIT; construction scratch is released before return.
 * Returns PLX_OK, PLX_E_INVALID (NULL argument), or PLX_E_NOMEM (then the
 * arena is back where it was). */
plx_status light_create(arena *a, const scene *s, size_t cache_bytes, light **out /* OUT */);

/* Bytes light_create takes besides the pool (for budgets and reports). */
size_t light_base_bytes(const scene *s);

/* 1 if the open segment A->B meets some building's solid interior by more
 * than LIGHT_MIN_PIECE, else 0 (segment path). */
int light_segment_blocked(light *L, const double A[3], const double B[3]);

/* Where a query point lies (for clear API errors), with a tolerance of
 * LIGHT_CLASSIFY_TOL metres:
 *   GROUND   z = 0 and not under the footprint of a building standing on
 *            the ground;
 *   FACADE   on a wall (within tol of a footprint edge, z within its
 *            building's [min_height, height]);
 *   ROOF     z = height over the footprint; UNDERSIDE z = min_height > 0
 *            under it;
 *   INSIDE   strictly inside some solid (farther than tol from its surface);
 *   AIR      none of these.
 * For a surface (GROUND, FACADE, ROOF, UNDERSIDE) *bld (may be NULL) gets
 * the building (UINT32_MAX for the ground), and *normal_ok whether n faces
 * out of the solid (n.outward > 0: up on ground and roofs, down under a
 * raised building, away from the footprint on a wall). */
#define LIGHT_CLASSIFY_TOL 1e-6
typedef enum light_where {
    LIGHT_GROUND = 0, LIGHT_FACADE, LIGHT_ROOF, LIGHT_UNDERSIDE,
    LIGHT_INSIDE, LIGHT_AIR
} light_where;
light_where light_classify_point(light *L, const double P[3], const double n[3],
                                 uint32_t *bld /* OUT */, int *normal_ok /* OUT */);

/* Pseudo-angle of direction (dx, dy) != 0: a value in [0, 4) increasing
 * with the angle from +x counter-clockwise (no trigonometry). */
double light_pseudo_angle(double dx, double dy);

/* The number of lamps whose light can reach P: intensity > 0 and P inside
 * the sphere of radius R about the lamp (d < R), visibility aside. Walks
 * only the lamps of P's cell of the lamp grid (cost: the lamps in reach). */
uint32_t light_lamps_reaching(const light *L, const double P[3]);

/* Internal, shared by light.c and litregion.c. */
int light_seg_blocked_by(light *L, uint32_t b, const double A[3], const double B[3],
                         double len3);

#endif
