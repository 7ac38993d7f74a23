/* trace: a 2.5D ray caster over the scene's prisms (walls, roofs,
 * undersides of raised buildings, ground).
 *
 * Geometry. Building k is the solid (footprint_k) x [min_height_k, height_k],
 * footprint = inside the outer ring and outside the holes (even-odd over the
 * building's rings). The ground is the plane z = 0 (infinite). A ray is
 * o + t d with d a unit vector and t > 0; the caster returns the first
 * surface met with t < tmax:
 *   TRACE_WALL   a footprint edge's vertical face; 'edge' = index in
 *                scene.pts of the edge's first vertex (the edge runs to
 *                tracer.enext[edge]); normal horizontal, out of the solid
 *                (the solid lies to the left of every ring edge, so the
 *                normal is (e.y, -e.x)/|e| for the edge vector e).
 *   TRACE_ROOF   the top face z = height, normal +z.
 *   TRACE_UNDER  the bottom face z = min_height > 0, normal -z.
 *   TRACE_GROUND z = 0 (outside buildings standing on the ground: reaching
 *                the ground under one means passing a wall first), normal +z.
 *   TRACE_SKY    nothing before tmax.
 *
 * Method. One record per wall (footprint edge: first vertex, edge vector,
 * the building's [min_height, height], index and albedo; 64 bytes) and a
 * uniform grid over the Bounds box; each cell lists
 *   - its walls (indices of every edge that comes within a hair of the
 *     cell: segment clipped to the padded cell box, Liang-Barsky), and
 *   - its buildings (box overlap), with in its header the tallest top, the
 *     lowest roof and the highest underside among them.
 * The ray walks the cells in order (2D DDA, Amanatides-Woo, inverse
 * direction computed once, the next cell's list prefetched) and stops as
 * soon as the best hit lies before the current cell's exit. In a cell it
 * first compares the range of its heights there with the cell's top (the
 * whole cell is skipped when the ray passes above it), then tests the walls
 * whose height range meets the ray's, and, only if the ray crosses a roof
 * height (going down) or an underside height (going up) of the cell, its
 * buildings' roofs or undersides. A wall is hit when the ray enters the
 * solid through it (walls are one-sided: a ray leaving a solid through a
 * wall does not hit it), 0 < t, the crossing is on the closed edge and its
 * height in the closed [min_height, height]: a few multiplications and
 * sign tests, one division for a crossing. A roof or underside is hit when
 * the point where the ray meets its plane is inside the footprint (even-odd
 * over the building's rings, in its box) or on its outline.
 * The walk ends where the ray rises above the tallest building, leaves the
 * grid, or reaches tmax (the ground or the first hit).
 *
 * Lamp tables (trace_lamp_ray, the first ray of a photon). Per scene lamp
 * the walls that a ray from it can hit (facing it, tn < 0 as in the wall
 * test, and within its radius R, which bounds the ray) are listed per
 * sector of directions: 32 equal steps of a pseudo-angle that grows with
 * the azimuth (one division), each wall in the sectors between its two
 * ends plus one each side (so rounding at a sector border cannot lose
 * it), and the buildings whose roof is below the lamp or underside above
 * it within R. A ray from the lamp tests its sector's walls (two on
 * average on gen eixample) and those caps: no walk, no per-ray setup but
 * the ground. The same wall and cap tests as the walk, on a superset of
 * the faces it could hit, so the same answer (a tie may go the other
 * way).
 *
 * Tracing writes nothing in the tracer (trace_ray, trace_top and the
 * lamp rays only read it), so several threads may trace with one tracer
 * at once: the renderer's workers do (README "Threads"). Building it is
 * single-threaded.
 *
 * Degenerate cases: faces are closed (a ray touching an edge of a roof or a
 * wall exactly hits it; "on the outline" is to rounding, exact for
 * coordinates that are exact in binary), ties between coincident faces
 * (shared walls, a wall's top edge and its roof) go to either; a ray
 * running inside a wall's plane does not cross that edge (it meets the
 * neighbouring edges at their ends). A ray that
 * starts inside a solid (the caller offsets bounce origins along the
 * normal, so this happens only by rounding at corners) leaves it without a
 * hit and may hit it again further on. Hits are correct to rounding (about
 * 1e-12 relative): tests/unit/test_photon.c compares them with an
 * independent brute force (tolerance 1e-9 (1 + t) on t).
 *
 * Memory: trace_create takes everything from the arena (part given by the
 * caller, PLX_PART_PHOTON for the photon system) and no scratch: lists are
 * counted, then placed. On gen eixample 30 30 the grid takes 6 MiB (4 of
 * them the wall records) and the lamp tables 7 MiB. Tracing allocates
 * nothing.
 */
#ifndef PLX_TRACE_H
#define PLX_TRACE_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"

#define TRACE_NONE 0xffffffffu

enum { TRACE_SKY = 0, TRACE_GROUND, TRACE_WALL, TRACE_ROOF, TRACE_UNDER };

typedef struct trace_hit {
    double t;          /* distance along d */
    double p[3];       /* hit point o + t d */
    double n[3];       /* unit normal out of the solid (+z for the ground) */
    uint32_t bld;      /* building, TRACE_NONE for ground and sky */
    double albedo;     /* the building's albedo (scene_building.albedo; 0 for ground
                          and sky): photons bounce on it, and it comes in the wall
                          record or the building the test read anyway */
    uint32_t edge;     /* wall: index in scene.pts of the edge's first vertex */
    int kind;          /* TRACE_SKY, TRACE_GROUND, ... */
} trace_hit;

/* Cell size (m) per sqrt(area per building) when trace_create chooses it.
 * On gen eixample 30 30 (bench_photon) the walk alone is fastest at 0.5
 * (17 m cells, 135 ns per photon-pass ray against 148 at 0.75), but the
 * photon pass (whose first rays use the lamp tables) and random probe rays
 * (photon_indirect) are faster at 0.75: the grid is half the size (cells,
 * lists), so it competes less for the cache. */
#define TRACE_CELL_FACTOR 0.75

/* Lamp tables: sectors of directions (equal steps of a pseudo-angle) and
 * the most wall references a lamp's table may hold (beyond, its rays walk
 * the grid). */
#define TRACE_SECTORS 32
#define TRACE_LAMP_REFS 128

/* A wall (footprint edge), as the ray test reads it: one record per edge,
 * indexed like scene.pts (by the edge's first vertex), so the records of a
 * building's walls lie together. */
typedef struct trace_wall {
    double px, py;     /* first vertex */
    double ex, ey;     /* edge vector (next vertex - first) */
    double zlo, zhi;   /* the building's min_height and height */
    uint32_t bld;      /* the building */
    uint32_t pad;
    double albedo;     /* the building's (a hit's albedo comes with its wall) */
} trace_wall;          /* 64 bytes: one cache line */

/* A cell: its walls are wids[w0 .. next cell's w0), its buildings
 * ids[r0 .. next cell's r0) (r0 = start[c]); the tallest top, the lowest
 * roof and the highest underside among them (0 if none) decide whether
 * a ray needs to look at the cell, and at its roofs. */
typedef struct trace_cell {
    uint32_t w0, r0;
    double top, roof_lo, under_hi;
    double pad;
} trace_cell;

typedef struct tracer {
    const scene *s;
    double x0, y0;         /* grid origin (Bounds min corner) */
    double cell, inv;      /* cell size (m) and its inverse */
    uint32_t nx, ny;
    trace_cell *cells;     /* nx*ny + 1 (the last one ends the lists) */
    uint32_t *wids;        /* wall (edge) indices per cell */
    trace_wall *walls;     /* per scene point: its edge's wall */
    double *hz;            /* per building: min_height, height */
    uint32_t *start;       /* nx*ny + 1 offsets into ids */
    uint32_t *ids;         /* building indices per cell (box overlap) */
    uint32_t *enext;       /* per scene point: the next vertex of its ring */
    /* lamp tables (trace_lamp_ray): per lamp TRACE_SECTORS + 2 offsets into
     * lref, the walls it can hit per sector of directions, then the
     * buildings whose roof or underside it can hit */
    uint32_t *lsec;
    uint32_t *lref;
    uint8_t *lfast;        /* per lamp: 1 if it has a table */
    double zmax;           /* tallest building */
} tracer;

/*
 * Builds the caster for scene s (which must not change while it lives).
 * cell_size <= 0 chooses the cell size from the density of buildings.
 * Returns PLX_OK, PLX_E_INVALID (NULL argument) or PLX_E_NOMEM (the arena
 * is then back where it was).
 */
plx_status trace_create(arena *a, plx_part part, const scene *s, double cell_size,
                        tracer **out /* OUT */);

/* Bytes trace_create takes at most for scene s and the given cell size
 * (same rule; the lamp tables are counted at TRACE_LAMP_REFS references
 * per lamp, a lamp needing more gets none). */
size_t trace_bytes(const scene *s, double cell_size);

/* The same with the lamp tables on (tables 1, what trace_create builds) or
 * off (0: no tables, every lamp ray walks the grid: the same hits, first
 * rays about 2x slower; README "Photon buffers"). */
plx_status trace_create_ex(arena *a, plx_part part, const scene *s, double cell_size, int tables,
                           tracer **out /* OUT */);
size_t trace_bytes_ex(const scene *s, double cell_size, int tables);

/*
 * First surface hit by o + t d, 0 < t < tmax (tmax may be INFINITY); d must
 * be a unit vector, o finite with o[2] >= 0. Fills h and returns its kind
 * (TRACE_SKY when nothing is hit; then h->t = tmax and only kind is
 * meaningful).
 */
int trace_ray(tracer *T, const double o[3], const double d[3], double tmax,
              trace_hit *h /* OUT */);

/*
 * trace_ray from lamp 'lamp' of the scene (o = its position, tmax = its
 * radius R), the same answer (ties aside) by its table: the walls that can
 * be hit from it (facing it, within R) listed per sector of directions
 * (each wall in the sectors its angular span meets, one more each side for
 * rounding), and the roofs below it and undersides above it within R. A
 * lamp without a table (radius not finite and positive, too many walls)
 * walks the grid.
 */
int trace_lamp_ray(tracer *T, uint32_t lamp, const double d[3], trace_hit *h /* OUT */);

/* Asks for the cache lines trace_lamp_ray will read for lamp (an index
 * past the last lamp is ignored): stage 0 its table's offsets, stage 1
 * (after stage 0 had time to arrive: it reads them) its wall and cap
 * references. A caller that takes lamps in order (the photon pass) calls
 * stage 1 for the next lamp and stage 0 for the one after. No effect on
 * results. */
void trace_lamp_prefetch(const tracer *T, uint32_t lamp, int stage);

/* The same answer by the same wall and roof tests over every building (no
 * grid): checks the walk. */
int trace_ray_brute(tracer *T, const double o[3], const double d[3], double tmax,
                    trace_hit *h /* OUT */);

/* Whether no wall can stop a horizontal ray at a height in [z0, z1] that
 * runs inside the box x0..x1, y0..y1 (closed): 1 when no wall whose
 * [min_height, height] meets [z0, z1] comes within TRACE_BOX_PAD
 * (relative) of the box, so trace_ray of such a ray returns TRACE_SKY; 0
 * when one may (conservative: the wall's facing is not looked at). Reads
 * the grid's lists only. */
int trace_box_clear(const tracer *T, double x0, double y0, double x1, double y1, double z0,
                    double z1);
#define TRACE_BOX_PAD 1e-6

/* The horizon from a point o for rays going up (final gathers at the
 * ground and roofs): per sector of directions (TRACE_HORIZON_SECTORS equal
 * steps of a pseudo-angle), an elevation tangent that every building
 * within r stays under (its height over o at the nearest point of its
 * box, the box's sectors and one more each side), so a ray above it in
 * its sector, and above the tallest building beyond r, meets nothing:
 * trace_ray would return TRACE_SKY. r is twice the tallest building's
 * height over o plus a cell. Conservative by TRACE_HORIZON_DZ in height
 * and TRACE_BOX_PAD (relative) in distance. */
#define TRACE_HORIZON_SECTORS 64
#define TRACE_HORIZON_DZ 1e-6

typedef struct trace_horizon {
    double r;          /* buildings within r are in the sectors */
    double rise2;      /* squared elevation tangent over the tallest building at r */
    int on;            /* 0: o is above every building, in a building's box, or on its edge */
    double tan2[TRACE_HORIZON_SECTORS]; /* squared tangents (a hair up) */
} trace_horizon;

/* The horizon from o (o[2] >= 0). Reads the grid's building lists. */
void trace_horizon_make(const tracer *T, const double o[3], trace_horizon *hz /* OUT */);

/* 1 when the ray o + t d (unit d, t > 0, o the horizon's point) certainly
 * meets nothing, 0 when it may (then trace it). */
int trace_horizon_sky(const trace_horizon *hz, const double d[3]);

/* Height of the topmost horizontal surface above (x, y): the tallest roof
 * over the point (point strictly inside the footprint, even-odd; on an edge
 * either way), 0 if none (the ground); *bld gets the building or TRACE_NONE
 * (may be NULL). One grid cell's buildings, no ray walk. */
double trace_top(tracer *T, double x, double y, uint32_t *bld /* OUT */);

/* Whether (x, y) lies inside the footprint of building b (even-odd over
 * its rings; on an edge either way). */
int trace_inside(const tracer *T, uint32_t b, double x, double y);

#endif
