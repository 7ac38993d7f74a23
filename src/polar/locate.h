/* locate: point location in the polar diagrams (the search DAG) and ray
 * shooting through their regions (locate.c). */
#ifndef PLX_LOCATE_H
#define PLX_LOCATE_H

#include "polar/polar.h"

/* Where p lies in the diagram of quadrant q (0..3).
 * Returns the region index (>= 0) and stores the region's label (the
 * building met first by the scan at the start direction q pi/2, or -1 for
 * the Bounds frame when that ray reaches the box) in *owner (may be NULL).
 * Returns -1 when p is outside the open Bounds box, -2 when p is on a wall,
 * -3 when p is inside a footprint (then *owner is a building whose footprint
 * the solid trapezoid holding p belongs to: the one entered across the wall
 * below p, which, where a party wall was left out, may be the neighbour of
 * the footprint holding p; -1 if unknown; callers that must name the
 * footprint look it up in the scene, as query.c does). */
int32_t polar_locate(const polar *pd, int q, vec2 p, int32_t *owner /* OUT */);

typedef struct polar_hit {
    int32_t bld;         /* building hit, -1 when the ray reaches the Bounds box */
    int32_t bld2;        /* second owner of a wall shared exactly, else -1 */
    uint32_t seg;        /* wall piece (index into pd->seg) */
    vec2 pt;             /* first point hit (rounded) */
    double t;            /* ray parameter of pt: pt = p + t * (q - p) */
    uint32_t steps;      /* regions walked (both one-sided rays past a
                          * corner on the exact ray, side 0) */
} polar_hit;

/* First wall met by the ray from the free point p through q (q != p).
 * side = +1 / -1: the ray turned by an infinitesimal angle counter-clockwise
 * / clockwise (the one-sided limits, used to look past a vertex on the ray);
 * side = 0: the exact ray, blocked where it first enters the interior of the
 * solid (grazing a corner does not block; sliding along a wall shared by two
 * footprints does, the shared wall being interior to their union). The
 * exact ray is walked once; where it passes exactly through a corner it
 * parts into the two one-sided rays, walked on from there, and is blocked
 * where the farther of them is (the counter-clockwise one on a tie).
 * Returns PLX_OK, PLX_E_RANGE when p is not free (outside the open Bounds
 * box, on a wall or inside a footprint), PLX_E_INVALID when q == p. */
plx_status polar_shoot_to(const polar *pd, vec2 p, vec2 q, int side, polar_hit *out /* OUT */);

/* The same for a direction (dx, dy) != (0, 0); the ray goes through the
 * rounded point p + L (dx, dy) for a length L beyond the Bounds box. */
plx_status polar_shoot(const polar *pd, vec2 p, double dx, double dy, polar_hit *out /* OUT */);

/* Internal, shared with visibility.c. polar_locate_frame: the free region
 * holding frame point f (>= 0), -2 when f is on a wall or a vertex (or has
 * the frame abscissa and ordinate of one), -3 inside a footprint. */
int32_t polar_locate_frame(const polar *pd, const polar_map *m, vec2 f);

/* ---- for tests and benchmarks only ---- */

/* polar_locate_frame, also giving the owner of a footprint for -3 (as
 * polar_locate; -1 otherwise) and the number of DAG nodes visited (both may
 * be NULL). */
int32_t polar_locate_frame_ex(const polar *pd, const polar_map *m, vec2 f, int32_t *owner,
                              uint32_t *depth);

/* Inner node n (< m->nnode) of map m's search DAG: w[0] the test, w[1],
 * w[2] the child words, in the 32-bit forms above. */
void polar_node(const polar_map *m, uint32_t n, uint32_t w[3] /* OUT */);

#endif
