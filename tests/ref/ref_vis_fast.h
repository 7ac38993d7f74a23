/* ref_vis_fast: the brute-force reference of ref_vis.h, made fast enough
 * for thousands of points on a real district.
 *
 * Same contract, same rules for degenerate cases and the same results as
 * ref_vis (ref_vis.h): the same event directions (every occluder vertex,
 * every box corner, every point where two edges meet), merged within
 * 1e-12 rad, the same open intervals between them, and per interval the
 * nearest edge along the bisector ray with the same long double formulas
 * (ties to the lower edge index, owners within a relative 1e-12 visible).
 * Only the searches differ, and neither uses src/polar.*:
 *  - pairs of edges that may meet are those listed in a common cell of a
 *    uniform grid over the box (each edge in the cells its bounding box,
 *    widened by a hair, meets), instead of all pairs;
 *  - the bisector ray walks the grid cell by cell from p (a 2D DDA) and
 *    stops once the nearest hit so far (times 1 + 1e-12, plus a hair)
 *    lies before the cell it leaves, instead of testing every edge.
 * Cost O((V + X) (log(V + X) + k)) per query for V vertices, X meeting
 * points and k edges met on average along a ray's cells, against ref_vis's
 * O(E^2). The edges, the grid and the meeting points do not depend on the
 * viewer: ref_fast_new prepares them once per scene (read only afterwards,
 * so several threads may query one prepared scene).
 */
#ifndef REF_VIS_FAST_H
#define REF_VIS_FAST_H

#include "ref_vis.h"

/* As ref_vis and ref_vis_range (ref_vis.h): 0 on success, -1 outside the
 * box or inside a footprint, -2 on a boundary, -3 when malloc fails. Free
 * out->visible with ref_vis_free. */
int ref_vis_fast(const scene *s, double px, double py, ref_vis_result *out);

/* The same with the viewer-independent part prepared once. ref_fast_new
 * returns NULL when malloc fails; the scene must outlive the result. */
typedef struct ref_fast ref_fast;
ref_fast *ref_fast_new(const scene *s);
void ref_fast_free(ref_fast *f);
int ref_fast_vis(const ref_fast *f, double px, double py, ref_vis_result *out);
int ref_fast_vis_range(const ref_fast *f, double px, double py, double a0, double a1,
                       ref_vis_result *out);
int ref_vis_fast_range(const scene *s, double px, double py, double a0, double a1,
                       ref_vis_result *out);

#endif
