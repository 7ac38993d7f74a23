/* visibility: the fan of tangent rays over the polar diagrams.
 *
 * SPEC §3: the visibility polygon of a free point p is the set of points of
 * the Bounds box joined to p by a segment meeting no footprint interior
 * (buildings infinitely tall; raised buildings are no occluders). Reported as
 * the closure of its interior: zero-width spikes (a ray along a wall, through
 * the corner where two buildings touch) are not part of it.
 *
 * Method (robles2014 Alg. 1 on the quadrant diagrams of polar.h): each
 * quadrant of directions is a cone of rays from p that starts in p's region
 * of that quadrant's diagram and walks the regions. A cone reaching the axis
 * side of a region is split by the ray through the region's corner vertex
 * when that vertex lies strictly inside the cone (the tangent ray of the
 * fan); a cone leaving a region through a wall is closed: every ray of it
 * meets that wall first. The closed cones, in counter-clockwise order, give
 * the polygon (per cone: where its two limit rays meet the wall's line, or
 * the Bounds box with its corners) and the visible set. Every split and every
 * closing decision is a geom_orient sign; only the output points are rounded.
 * Cost: locating p (polar.h: a grid scan, O(1) expected for evenly spread
 * walls), then O(1) per region a cone crosses: one or two orientation tests
 * of the region's corner against the cone's limit rays, on differences from
 * p computed once per cone and per corner, decided by geom_orient's filter
 * inline (the exact fallback only near collinearity). The later half of a
 * split is moved past the splitting corner at once rather than testing that
 * corner against its own limit ray (an exact zero) when it is popped.
 *
 * Visible set: building i is visible iff a closed cone of positive angular
 * width (at least 1e-12 rad, so that a rounded range limit passing a hair
 * beside a vertex does not count) meets a wall piece of i (both owners when
 * two footprints have the same wall piece facing p).
 */
#ifndef PLX_VISIBILITY_H
#define PLX_VISIBILITY_H

#include <stdint.h>
#include "polarlux.h"
#include "polar/polar.h"

typedef struct vis_result {
    double area;          /* m^2 */
    /* caller buffers (either may be NULL: then only counted) */
    vec2 *poly;           /* polygon, counter-clockwise; for a range it starts at p */
    uint32_t poly_cap;
    uint32_t npoly;       /* vertices of the polygon (always set) */
    uint32_t *vis;        /* visible buildings, ascending */
    uint32_t vis_cap;
    uint32_t nvis;        /* number of visible buildings (always set) */
    /* statistics */
    uint32_t ncones;      /* closed cones (pairs of fan rays) */
    uint32_t nsteps;      /* regions crossed by all cones */
} vis_result;

/*
 * Visibility from p over the full turn (full_circle != 0; a0, a1 ignored) or
 * over the directions from a0 counter-clockwise to a1 (radians, any values;
 * the width a1 - a0 is reduced into [0, 2 pi), a1 - a0 >= 2 pi is the full
 * turn, a0 == a1 is empty).
 *
 * Fills out->area, out->npoly, out->nvis, the statistics, and as much of the
 * caller's arrays out->poly (poly_cap points) and out->vis (vis_cap indices)
 * as they hold. Temporary memory comes from arena_scratch(a) and is released
 * before return (one small block per 256 pending cones).
 *
 * Returns PLX_OK; PLX_E_RANGE when p is not in the open Bounds box, lies on
 * a wall or inside a footprint (out->area = 0); PLX_E_NOMEM when scratch runs
 * out, or when a non-NULL array was too small (the counts then say how much
 * is needed, the area is valid); PLX_E_INVALID for NULL arguments or
 * non-finite input.
 */
plx_status vis_query(const polar *pd, vec2 p, double a0, double a1, int full_circle,
                     arena *a, vis_result *out /* IN/OUT */);

/* The polar-diagram label of p in quadrant q (0..3): the building met first
 * by the counter-clockwise scan of directions [q pi/2, (q+1) pi/2] from p
 * (ties: the nearest), or -1 when that quadrant of directions sees no
 * building before Bounds. Returns -2 if p is not free, -3 without scratch. */
int32_t vis_first(const polar *pd, int q, vec2 p, arena *a);

#endif
