/* geom: robust 2D predicates and ring utilities.
 *
 * Orientation and in-circle style decisions are exact: a floating-point
 * filter with a proven error bound answers most calls, and an exact
 * expansion-arithmetic fallback answers the rest (adaptive predicates in the
 * manner of Shewchuk 1997, written for this project). Everything else
 * (areas, intersection points) is plain double arithmetic.
 */
#ifndef PLX_GEOM_H
#define PLX_GEOM_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include "base/scene.h"
#include "base/arena.h"

/* Sign of the area of triangle a,b,c: +1 counter-clockwise (c left of a->b),
 * -1 clockwise, 0 exactly collinear. Exact for all finite doubles. */
int geom_orient(vec2 a, vec2 b, vec2 c);

/* The first stage of geom_orient, for hot loops that compute the two
 * products themselves: dl = fl(fl(ax - cx) fl(by - cy)) and
 * dr = fl(fl(ay - cy) fl(bx - cx)), each difference and product rounded once
 * (the differences may be computed once and reused). Returns the sign of the
 * exact determinant when the filter proves it, else 0: then ask geom_orient.
 * geom_orient itself runs this very test (the bound is derived in geom.c). */
static inline int geom_orient_filter(double dl, double dr)
{
    const double bound_a = (3.0 + 64.0 * 0x1p-53) * 0x1p-53;
    double det = dl - dr, s = fabs(dl) + fabs(dr);
    if (s >= 0x1p-900 && s <= DBL_MAX) {
        double bound = bound_a * s;
        if (det > bound)
            return 1;
        if (-det > bound)
            return -1;
    }
    return 0;
}

/* The same sign, computed only by the slow exact path (a fixed-point big
 * integer holding the determinant for any finite doubles, about 600 bytes of
 * stack). Always agrees with geom_orient; meant for tests and cross-checks.
 * Needs finite coordinates. */
int geom_orient_ref(vec2 a, vec2 b, vec2 c);

/* Twice the signed area of a ring of n vertices (no closing vertex). */
double geom_ring_area2(const vec2 *p, uint32_t n);
/* Details: positive for counter-clockwise rings, 0 when n < 3. Plain double
 * arithmetic (shoelace about the first vertex), not exact. */

/* How two closed segments ab and cd meet, decided exactly. */
enum {
    GEOM_SEG_DISJOINT = 0,
    GEOM_SEG_CROSS,      /* interiors cross at one point */
    GEOM_SEG_TOUCH,      /* they share a point, an endpoint of one lying on the other */
    GEOM_SEG_OVERLAP     /* collinear with a common part of positive length */
};
int geom_seg_meet(vec2 a, vec2 b, vec2 c, vec2 d);
/* Details: a segment may be a single point (a == b); two collinear segments
 * meeting at one common end are TOUCH; coordinates must be finite. */

/* Where a point lies relative to a ring (either orientation), exactly. */
enum { GEOM_OUTSIDE = 0, GEOM_INSIDE = 1, GEOM_ON_BOUNDARY = 2 };
int geom_point_in_ring(vec2 q, const vec2 *p, uint32_t n);
/* Details: the ring is closed (its vertices and edges are ON_BOUNDARY); for a
 * ring that is not simple, INSIDE means nonzero winding number. n = 0 gives
 * OUTSIDE. O(n), no memory. */

/* Checks that a ring of n vertices (no closing vertex, no duplicate
 * consecutive vertices) is simple: non-adjacent edges do not meet, adjacent
 * edges meet only at their shared vertex (no spikes folding back).
 * Returns 1 if simple. Otherwise returns 0 and stores in *ei, *ej the indices
 * of two offending edges (edge k joins vertex k and k+1 mod n).
 * Runs in O(n log n) expected time, using scratch memory from 'a' (released
 * before return); returns -1 if that scratch memory is not available. */
int geom_ring_is_simple(arena *a, const vec2 *p, uint32_t n, uint32_t *ei, uint32_t *ej);
/* Details: a sweep over the vertices in lexicographic order (merge sort,
 * then a treap with hashed priorities: O(n log n) expected whatever the
 * shape, long edges included), with 16 bytes of scratch per vertex in one
 * request. ei and ej may be NULL; when set, *ei <= *ej. The cheap checks
 * come first and need no scratch (so a ring can be reported not simple even
 * when scratch is short):
 *   n < 3                          -> 0, edges 0, 0;
 *   non-finite vertex k            -> 0, edges k-1, k (mod n);
 *   zero-length edge k (duplicate) -> 0, edges k, k;
 *   edges k-1, k fold back (spike) -> 0, edges k-1, k (mod n);
 *   two vertices at one point      -> 0, the edges starting at them.
 * A triangle with three distinct, non-collinear vertices is simple. */

/* Two unit vectors t, b completing the unit vector n to a right-handed
 * orthonormal basis (t horizontal unless n is nearly vertical). */
void geom_basis3(const double n[3], double t[3], double b[3]);

/* Squared distance between closed segments ab and cd. */
double geom_seg_dist2(vec2 a, vec2 b, vec2 c, vec2 d);
/* Details: exactly 0 when geom_seg_meet says they meet; otherwise the
 * smallest endpoint-to-segment distance in plain double arithmetic (it may
 * underflow to 0 for segments closer than about 1e-154). */

/* The margin by which a point computed at (x, y) in double moves off
 * the surface it was computed on, so that it lies on the side it faces:
 * 2^-48 times its largest coordinate (4 units in the last place), m.
 * Near the origin under 1e-11 m; far from it (a projected CRS, y near
 * 6.7e6 m) 2.4e-8 m, where the point's rounding (about 1e-9 m) reaches
 * the visibility's 1e-9 m tolerance and could put a wall point in its
 * own building's shadow (pixel_hit.c, atlas_fill.c). */
static inline double geom_round_margin(double x, double y)
{
    return fmax(fabs(x), fabs(y)) * (1.0 / 281474976710656.0);
}

#endif
