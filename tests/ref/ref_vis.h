/* ref_vis: brute-force reference for SPEC §3, planar visibility.
 *
 * Occluders: the buildings with min_height <= 0 (a raised building,
 * min_height > 0, is no occluder); the footprint of one is its outer ring
 * minus its holes, treated as infinitely tall. Region: the box s->bounds
 * (minx, miny, maxx, maxy). The visibility polygon of p is the set of points
 * of the box joined to p by a segment meeting no footprint interior.
 *
 * Method (slow on purpose, O(E^2 log E + (V + X) E) for E edges, V vertices,
 * X edge crossings): event directions = directions from p to every occluder
 * vertex, every box corner and every crossing point of two edges (occluder
 * or box edges: overlapping buildings' walls cross, and the nearest edge can
 * change there). Between two consecutive events the nearest edge met by a ray
 * from p is one fixed edge; it is found by shooting the bisector ray against
 * all edges, and the interval adds the triangle p, hit(a), hit(b) cut from
 * that edge's supporting line by the interval's two limit rays.
 *
 * Rules for degenerate cases:
 *  - p strictly outside the box, or strictly inside some occluder footprint:
 *    return -1. p on the box boundary or on an occluder boundary (outer ring
 *    or hole edge) while in no footprint interior: return -2. A point inside
 *    a courtyard (strictly) is free.
 *  - Directions within 1e-12 rad of each other are one event (atan2 in long
 *    double). Intervals are therefore open and at least 1e-12 rad wide, and
 *    rays through vertices are never shot.
 *  - Zero-width parts of the visibility polygon (a ray through the common
 *    corner of two buildings that touch at a corner, along a wall seen
 *    edge-on) add no area and are ignored: the polygon is the closure of the
 *    union of the open-interval sectors.
 *  - Visible buildings: building i is visible iff, for some interval (inside
 *    the sector, for the range variant), an edge of i is met by the bisector
 *    ray at the nearest distance (ties within a relative 1e-12 all count: two
 *    overlapping buildings with a common collinear wall seen by p are both
 *    visible). Buildings seen only edge-on or only through a zero-width gap
 *    are not visible.
 *  - Vertex count: the boundary is listed as, per interval in ccw order, the
 *    two points where the interval's limit rays meet its nearest edge's line
 *    (for the range variant, preceded by p itself unless the sector is the
 *    full turn). Then, repeatedly until nothing changes, any point lying
 *    within tol of the segment joining its two neighbours is removed, where
 *    tol = 1e-10 * max(box width, box height). What remains is counted; so
 *    duplicates and straight-angle points are not vertices, a shadow edge
 *    along a ray gives two vertices (its ends), and for a sector of exactly
 *    pi the apex p is not a vertex. A polygon left with fewer than 3 points
 *    counts 0.
 */
#ifndef REF_VIS_H
#define REF_VIS_H

#include <stdint.h>
#include "base/scene.h"

typedef struct ref_vis_result {
    double area;         /* m^2 */
    uint32_t nverts;     /* vertices of the visibility polygon, rule above */
    uint32_t nvisible;   /* number of visible buildings */
    uint32_t *visible;   /* malloc'd, ascending building indices (s->bld), or NULL */
} ref_vis_result;

/* Full-turn visibility from (px, py). Returns 0 on success, -1 or -2 as
 * described above (out zeroed), -3 when malloc fails. On success free
 * out->visible with ref_vis_free. */
int ref_vis(const scene *s, double px, double py, ref_vis_result *out);

/* Visibility polygon intersected with the angular sector of directions from
 * a0 ccw to a1 (radians, any real values, may wrap through 0). The sector
 * width is w = (a1 - a0) reduced into [0, 2pi), except that a1 - a0 >= 2pi
 * means the full turn; so a0 == a1 is the empty sector (area 0, nverts 0,
 * nothing visible). Return codes as ref_vis. */
int ref_vis_range(const scene *s, double px, double py, double a0, double a1,
                  ref_vis_result *out);

/* Frees out->visible and zeroes *out. */
void ref_vis_free(ref_vis_result *out);

#endif
