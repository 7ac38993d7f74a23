/* ref_scene: build a `scene` (src/scene.h) from plain arrays, for tests.
 *
 * Test code: uses malloc/realloc, not the engine's arena. A scene built here
 * has the layout the loader promises (rings without closing vertex, no
 * duplicate consecutive vertices, outer rings CCW, holes CW, building boxes)
 * but no blocks (nblocks = 0, block_* arrays NULL, building.block = UINT32_MAX).
 *
 * Typical use:
 *     scene s; ref_scene_init(&s);
 *     ref_scene_add_box(&s, 0, 0, 10, 10, 20.0, 0.0);
 *     ref_scene_add_lamp(&s, -5, 5, 6, 1000, 30);
 *     ref_scene_finish(&s);          (bounds = building box grown by 50 m)
 *     ... ref_scene_free(&s);
 *
 * Also the one shared geometric helper of the references: where a point lies
 * relative to a building footprint (outer ring minus holes).
 */
#ifndef REF_SCENE_H
#define REF_SCENE_H

#include <stdint.h>
#include "base/scene.h"

/* Empty scene: no buildings, no lamps, ground albedo 0.15, bounds zero. */
void ref_scene_init(scene *s);

/* Adds a building. xy holds the rings one after another as x,y pairs; ring_n[k]
 * is the number of vertices of ring k; ring 0 is the outer ring, the others
 * holes. Rings may be given in either orientation and closed or not;
 * consecutive duplicates are dropped, outer rings made CCW and holes CW.
 * Albedo 0.35. Returns the building index, or -1 if a ring has fewer than 3
 * distinct vertices or zero area, or memory runs out (scene unchanged). */
int ref_scene_add_building(scene *s, const double *xy, const uint32_t *ring_n,
                           uint32_t nrings, double height, double min_height);

/* Adds the axis-aligned rectangle [x0,x1] x [y0,y1] as a building. */
int ref_scene_add_box(scene *s, double x0, double y0, double x1, double y1,
                      double height, double min_height);

/* Adds a lamp with the default colour (1.0, 0.62, 0.28). Returns the lamp
 * index or -1 when memory runs out. */
int ref_scene_add_lamp(scene *s, double x, double y, double z,
                       double intensity, double radius);

/* Same with an explicit colour. */
int ref_scene_add_lamp_rgb(scene *s, double x, double y, double z,
                           double intensity, double radius,
                           double r, double g, double b);

/* Sets s->bounds to the box of all building vertices grown by 50 m (SPEC §1).
 * With no building: the box of the lamps grown by 50 m; with neither:
 * [-50, -50, 50, 50]. Tests may overwrite s->bounds afterwards. */
void ref_scene_finish(scene *s);

/* Frees what the ref_scene_add_* calls allocated and re-initialises s. */
void ref_scene_free(scene *s);

/* Where (x, y) lies relative to the footprint of building b, the closed
 * outer ring minus the open holes: REF_IN = strictly inside the footprint,
 * REF_ON = on an edge of the outer ring or of a hole, REF_OUT = elsewhere
 * (outside, or strictly inside a courtyard). Long double arithmetic; exact
 * for coordinates with few significant bits, as in hand-made tests. */
enum { REF_OUT = 0, REF_IN = 1, REF_ON = 2 };
int ref_footprint_where(const scene *s, uint32_t b, long double x, long double y);

#endif
