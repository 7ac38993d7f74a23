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
 * Method. Per building, the exact ray/prism entry: the slab of t where
 * min_height <= z(t) <= height is cut to the search range; whether the
 * entry point of that range lies inside the footprint is the parity of the
 * crossings of the ray's 2D line with the ring edges before it (a vertex on
 * the line counts as lying on its left, so a line through a vertex crosses
 * the two edges there once in all); inside means a roof/underside hit at
 * the slab entry, else the first crossing inside the range is the wall hit.
 * A ray that starts strictly inside a solid does not hit that building (the
 * caller offsets bounce origins along the normal, so this happens only by
 * rounding at corners; the photon then leaves through the solid).
 * Candidates come from a uniform grid over the Bounds box, each cell listing
 * the buildings whose box overlaps it and the tallest top among them; the
 * ray walks the cells in order (2D DDA, Amanatides-Woo) and stops as soon
 * as the best hit lies before the current cell's exit. Cells the ray passes
 * above their tallest top are skipped, and the walk ends once the ray rises
 * above the tallest building. Each building is tested at most once per ray
 * (per-building stamps), so a tracer must not be used by two threads at
 * once (make one per thread: they share nothing but the scene).
 *
 * Degenerate cases: faces are closed (a ray touching an edge of a roof or a
 * wall exactly hits it), ties between coincident faces of two buildings
 * (shared walls) go to either; a ray running inside a wall's plane does not
 * cross that edge. Hits are correct to rounding (about 1e-12 relative).
 *
 * Memory: trace_create takes everything from the arena (part given by the
 * caller, PLX_PART_PHOTON for the photon system); construction scratch is
 * released before return. Tracing allocates nothing.
 */
#ifndef PLX_TRACE_H
#define PLX_TRACE_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "arena.h"
#include "scene.h"

#define TRACE_NONE 0xffffffffu

enum { TRACE_SKY = 0, TRACE_GROUND, TRACE_WALL, TRACE_ROOF, TRACE_UNDER };

typedef struct trace_hit {
    double t;          /* distance along d */
    double p[3];       /* hit point o + t d */
    double n[3];       /* unit normal out of the solid (+z for the ground) */
    uint32_t bld;      /* building, TRACE_NONE for ground and sky */
    uint32_t edge;     /* wall: index in scene.pts of the edge's first vertex */
    int kind;          /* TRACE_SKY, TRACE_GROUND, ... */
} trace_hit;

typedef struct tracer {
    const scene *s;
    double x0, y0;         /* grid origin (Bounds min corner) */
    double cell, inv;      /* cell size (m) and its inverse */
    uint32_t nx, ny;
    uint32_t *start;       /* nx*ny + 1 offsets into ids */
    uint32_t *ids;         /* building indices per cell */
    float *top;            /* tallest height per cell (0 for empty cells) */
    uint32_t *enext;       /* per scene point: the next vertex of its ring */
    uint32_t *stamp;       /* per building: last ray that tested it */
    uint32_t now;
    double zmax;           /* tallest building */
    uint64_t rays, tests;  /* counters: rays cast, prism tests */
} tracer;

/*
 * Builds the caster for scene s (which must not change while it lives).
 * cell_size <= 0 chooses the cell size from the density of buildings.
 * Returns PLX_OK, PLX_E_INVALID (NULL argument) or PLX_E_NOMEM (the arena
 * is then back where it was).
 */
plx_status trace_create(arena *a, plx_part part, const scene *s, double cell_size,
                        tracer **out /* OUT */);

/* Bytes trace_create takes for scene s and the given cell size (same rule). */
size_t trace_bytes(const scene *s, double cell_size);

/*
 * First surface hit by o + t d, 0 < t < tmax (tmax may be INFINITY); d must
 * be a unit vector, o finite with o[2] >= 0. Fills h and returns its kind
 * (TRACE_SKY when nothing is hit; then h->t = tmax and only kind is
 * meaningful).
 */
int trace_ray(tracer *T, const double o[3], const double d[3], double tmax,
              trace_hit *h /* OUT */);

/* The same answer by testing every building (no grid): the baseline for
 * benchmarks. */
int trace_ray_brute(tracer *T, const double o[3], const double d[3], double tmax,
                    trace_hit *h /* OUT */);

/* Height of the topmost horizontal surface above (x, y): the tallest roof
 * over the point (point strictly inside the footprint, even-odd; on an edge
 * either way), 0 if none (the ground); *bld gets the building or TRACE_NONE
 * (may be NULL). One grid cell's buildings, no ray walk. */
double trace_top(tracer *T, double x, double y, uint32_t *bld /* OUT */);

/* Whether (x, y) lies inside the footprint of building b (even-odd over
 * its rings; on an edge either way). */
int trace_inside(const tracer *T, uint32_t b, double x, double y);

#endif
