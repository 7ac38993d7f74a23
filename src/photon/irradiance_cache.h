/* irradiance_cache: E_indirect for images by final gathering at sparse
 * surface points, interpolated (Ward's irradiance caching, on a fixed grid
 * per surface instead of his adaptive record radii).
 *
 * WHAT IS COMPUTED. For a pixel's surface point P with normal n, the RGB
 * E_indirect that final_gather_rgb (final_gather.h: exact direct light at
 * the gathered surfaces, the photon buffers for the later bounces only)
 * would give at P, approximated by interpolating gathers ("records") made
 * at the vertices of a square grid laid on P's own surface:
 *  - the ground and each roof: the plane z = P.z, grid over (x, y) (a
 *    roof: its own building's, not others of the same height);
 *  - a wall: the plane of its edge (the edge a 2 cm probe ray from P meets),
 *    grid over (u, z), u the distance along the edge from its first vertex.
 * Records are keyed by (surface, level, grid cell): two surfaces never
 * share one, so light does not leak across a wall foot, a roof edge or a
 * building corner (the edges the interpolation respects).
 *
 * SPACING. The grid of level l has spacing s_l = ICACHE_S0 2^l. A point at
 * distance d from the eye wants s = max(kappa d, smin) (ICACHE_KAPPA 0.15,
 * an angle of about 9 degrees, and ICACHE_SMIN 2 m: indirect light changes
 * over metres, whatever the image size, and 16 x 16 directions per record
 * cost about 0.25 ms); l = log2(s / s0) is fractional and the two levels around it are
 * blended (trilinear, as a mip map), so there is no seam where the level
 * changes. Within a level, bilinear weights over the cell's four vertices.
 * The coarsest level is ICACHE_LEVEL_MAX (8 m): beyond the distance that
 * asks for it (53 m) the cache blends into the photon buffers' own lookup
 * (photon_indirect_rgb), which alone answers beyond twice that: records
 * farther apart would blur the light over whole streets and courtyards
 * (aerial views read the photon buffers).
 *
 * VIEWS FROM ABOVE (icache_set_spacing). The aerial light map's indirect
 * layer uses one level, ICACHE_AERIAL (8 m) everywhere, records of
 * ICACHE_AERIAL_SIDE^2 directions that read the photon buffers (E_later)
 * at one direction of each ICACHE_AERIAL_LATER^2 strata
 * (final_gather_rgb_later; E_direct at every direction), kept apart from
 * the street views' records of the same level (their own key bit), never the
 * photon buffers for points with a grid: light stays on the surface it was
 * gathered on (the records' grids respect walls and roof edges), where the
 * buffers' coarse records spread it 100 m. (Aerial frames read the layer
 * for the ground and roofs and the photon buffers for walls.)
 *
 * VALID VERTICES. A vertex is valid when it lies on the same surface: on
 * the ground or a roof, when the topmost surface over it (trace_top) has
 * the same height as over P (within 1 mm: open ground stays open ground,
 * a roof stays that roof's height, and the same building) and, on grids of 4 m and coarser, no
 * wall stands between P and it (a horizontal ray 5 cm above the surface:
 * a cell may span a small building, with the same ground beyond it; none
 * is cast in a cell where trace_box_clear finds no wall at that height); on a
 * wall, when a probe ray from 5 mm in front of it meets the same edge and
 * no building stands against it there. Invalid vertices get no weight and the
 * others are renormalised; a level whose four vertices are all invalid
 * (a sliver of a surface smaller than the cell) is replaced by the next
 * finer one, down to level 0, and below that P is gathered itself.
 * Undersides and points no probe finds read the photon buffers.
 *
 * RECORDS. Each record is a final gather of ICACHE_SIDE^2 directions at its
 * vertex (the seed and the vertex's coordinates seed its jitter, so a
 * record's value does not depend on which pixel asked first: the same
 * camera gives the same bytes). A record is computed when a pixel first
 * needs it and kept in an open-addressed table taken from the arena at
 * creation, its size chosen by the caller from its budget
 * (icache_records_for); a full table (3/4) is emptied and refilled, which
 * changes no value: a smaller table gives the same bytes, and only
 * gathers more records again. The table is emptied as well when the photon buffers
 * changed (new frames, a reset, refined lamps) or the light changed.
 *
 * Not for two threads at once (the table fills during lookups).
 */
#ifndef PLX_IRRADIANCE_CACHE_H
#define PLX_IRRADIANCE_CACHE_H

#include <stddef.h>
#include <stdint.h>
#include "base/arena.h"
#include "light/illuminance.h"
#include "photon/photon.h"

#define ICACHE_SIDE 16        /* gather directions per record: 16 x 16 */
#define ICACHE_S0 0.25        /* level 0 grid spacing, m */
#define ICACHE_SMIN 2.0       /* spacing asked for near the eye, m */
#define ICACHE_KAPPA 0.15     /* spacing asked for farther, per metre of distance */
#define ICACHE_LEVEL_MAX 5    /* coarsest level: 8 m (farther: photon buffers) */
#define ICACHE_LEVEL_SEG 4    /* from 4 m on, a ground vertex behind a wall is left out */
#define ICACHE_RECORDS 65536  /* table slots at most (a power of two: 2 MiB) */
#define ICACHE_RECORDS_MIN 1024 /* and at least (32 KiB); icache_records_for */
#define ICACHE_AERIAL 8.0     /* spacing for the aerial map's layer, m (icache_set_spacing) */
#define ICACHE_AERIAL_SIDE 24 /* and its records' gather side: 24 x 24 (README "Aerial
                                 views' indirect light": more accurate than 4 m and 16 x 16,
                                 and a third less work) */
#define ICACHE_AERIAL_LATER 3 /* and E_later read at one direction of each 3 x 3 strata
                                 (final_gather_rgb_later; README "Aerial views'
                                 indirect light") */

/* A record: one vertex's final gather (tests read the keys). */
typedef struct icache_rec {
    uint64_t k1, k2;      /* surface; level and vertex */
    float e[3];           /* RGB E_indirect at the vertex */
    uint32_t flags;       /* REC_USED, REC_VALID */
} icache_rec;

/* The last cell looked up at one level, and the records of its four
 * vertices fetched so far (0: not yet): neighbouring pixels share
 * cells, and reuse them without hashing. Emptied with the table. */
typedef struct icache_cell {
    uint64_t code;            /* the surface */
    int64_t i, j;             /* the cell */
    int set;                  /* 0: none; else ICACHE_CELL_SET, and on ground and roof
                               * cells of 4 m and more whether a wall may stand in it at
                               * the height of the segment tests (trace_box_clear):
                               * ICACHE_CELL_CLEAR none, ICACHE_CELL_WALLS one may */
    uint32_t r[4];            /* vertices (i, j), (i+1, j), (i, j+1), (i+1, j+1): the
                               * slot plus one (indices, not pointers: bakes move it) */
} icache_cell;

enum { ICACHE_CELL_SET = 1, ICACHE_CELL_CLEAR = 2, ICACHE_CELL_WALLS = 3 };

#define ICACHE_PEEK_WORKERS 16 /* PLX_MAX_THREADS */

typedef struct icache {
    icache_rec *tab;          /* nrec slots */
    uint32_t nrec;            /* a power of two, ICACHE_RECORDS_MIN..ICACHE_RECORDS */
    uint32_t used;
    uint32_t side;            /* gather side per record */
    double eye[3];            /* the viewer: spacing grows with distance from it */
    double kappa;             /* spacing per metre of distance (ICACHE_KAPPA) */
    double smin;              /* smallest spacing asked for, m (ICACHE_SMIN) */
    double fixed;             /* > 0: this spacing everywhere (icache_set_spacing) */
    uint64_t stamp;           /* state of the photon buffers the records belong to */
    uint64_t gathered;        /* records computed since creation */
    uint64_t direct;          /* points gathered themselves (no valid vertex) */
    uint64_t flushes;         /* times the table was emptied */
    icache_cell last[ICACHE_LEVEL_MAX + 1]; /* per level: the last cell looked up */
    /* the peeks' own last cells, one set per worker (icache_peek): a slot
     * they remember is used again only while it holds the same vertex's
     * record (the table may have been emptied and filled since) */
    icache_cell peek_last[ICACHE_PEEK_WORKERS][ICACHE_LEVEL_MAX + 1];
} icache;

/* The table's slots for a budget of 'budget' bytes (the photon buffers'
 * and the cache's together): the largest power of two whose table takes
 * at most 1/16 of it, within ICACHE_RECORDS_MIN..ICACHE_RECORDS. */
uint32_t icache_records_for(size_t budget);

/* Bytes icache_create takes from part PLX_PART_PHOTON for nrec slots. */
size_t icache_bytes(uint32_t nrec);

/* The cache, empty, with nrec slots (a power of two, at least
 * ICACHE_RECORDS_MIN, at most ICACHE_RECORDS; else PLX_E_INVALID) in the
 * arena; PLX_E_NOMEM when it does not fit. */
plx_status icache_create(arena *a, uint32_t nrec, icache **out /* OUT */);

/* Empty, as created (records, counters, the peeks' cells): what a bake
 * saves, so that the file does not depend on which worker gathered or
 * peeked at what. */
void icache_clear(icache *c);

/* The viewer for the lookups that follow: the grid spacing asked for at
 * distance d from it is kappa d, at least smin. Records already made stay
 * valid. */
void icache_set_view(icache *c, const double eye[3]);

/* Views from above (the aerial light map and frames): every lookup uses
 * the level of spacing s (rounded down to a power of two times ICACHE_S0,
 * at most ICACHE_LEVEL_MAX), whatever the distance to the eye, and never
 * the photon buffers' own lookup for points that have a surface grid.
 * s = 0: back to spacing by distance (icache_set_view). Records stay valid. */
void icache_set_spacing(icache *c, double s);

/* RGB E_indirect (lux) at surface point P with unit normal n (a pixel's
 * point), from the records around it (computed as needed). ps must have
 * frames; L is the lamp light the gathers read. */
void icache_lookup(icache *c, photon_sys *ps, light *L, const double P[3], const double n[3],
                   double rgb[3] /* OUT */);

/* The same at the topmost surface over (x, y), the ground or a roof
 * (trace_top), facing up; returns its height. What the aerial light map's
 * layer asks (one trace_top for both). */
double icache_lookup_top(icache *c, photon_sys *ps, light *L, double x, double y,
                         double rgb[3] /* OUT */);

/* icache_lookup's value when every record it reads is in the table (and
 * the photons are those the table was gathered from): 1 with rgb, the
 * same bits icache_lookup gives; else 0 (it would gather). Changes
 * nothing but worker's own last cells (peek_last[worker]), so several
 * threads may peek at once, each with its own worker (0 ..
 * ICACHE_PEEK_WORKERS - 1), while nothing looks up. */
int icache_peek(icache *c, photon_sys *ps, int worker, const double P[3], const double n[3],
                double rgb[3] /* OUT */);

#endif
