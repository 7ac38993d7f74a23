/* ref_polar_scan: the former point location of the polar diagrams (grid
 * scan), a reference for tests and benchmarks only. */
#ifndef REF_POLAR_SCAN_H
#define REF_POLAR_SCAN_H

#include "polar/polar.h"

/* The former point location, kept as a reference (the construction uses
 * no grid; tests/ref/ref_polar_scan.c): the nearest wall below
 * the point found by scanning a column of a grid of the wall pieces, then
 * the regions above that wall walked to the point (O(1) expected for evenly
 * spread walls, O(n) worst case). polar_scan_new keeps its grid and tables
 * in arena memory (part PLX_PART_POLAR, not counted in polar_memory);
 * polar_scan_locate_frame answers as polar_locate_frame_ex (owner may be
 * NULL), for map mi (0 or 1). */
typedef struct polar_scan polar_scan;
plx_status polar_scan_new(arena *a, const polar *pd, polar_scan **out /* OUT */);
int32_t polar_scan_locate_frame(const polar_scan *g, int mi, vec2 f, int32_t *owner);

#endif
