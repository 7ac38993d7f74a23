/* ref_trace_old: the 2.5D ray caster of src/trace.c as it was before the
 * wall grid (commit 80afb97), kept as the baseline of bench_photon
 * ("caster new vs old") and as a second opinion in tests.
 *
 * Method: a uniform grid of cells listing the buildings whose box overlaps
 * them; the ray walks the cells (2D DDA) and tests each building once
 * (per-building stamps) with an exact ray/prism entry: the z slab cut to
 * the search range, then the parity of the ray line's crossings with the
 * ring edges before the entry (inside: roof or underside hit; else the
 * first crossing in range is the wall hit). Same hit contract as trace.h
 * (trace_hit, TRACE_* kinds). Not thread safe (stamps), like the old one.
 */
#ifndef REF_TRACE_OLD_H
#define REF_TRACE_OLD_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"
#include "photon/trace.h"

typedef struct old_tracer {
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
} old_tracer;

plx_status old_trace_create(arena *a, plx_part part, const scene *s, double cell_size,
                            old_tracer **out /* OUT */);
size_t old_trace_bytes(const scene *s, double cell_size);
int old_trace_ray(old_tracer *T, const double o[3], const double d[3], double tmax,
                  trace_hit *h /* OUT */);
int old_trace_ray_brute(old_tracer *T, const double o[3], const double d[3], double tmax,
                        trace_hit *h /* OUT */);

#endif
