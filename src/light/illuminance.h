/* illuminance: lamp light at surface points (SPEC §2), illuminance.c. */
#ifndef PLX_ILLUMINANCE_H
#define PLX_ILLUMINANCE_H

#include "light/light.h"

/* E(P) in lux at surface point P with unit normal n (colour ignored) and,
 * when rgb is not NULL, the colour-weighted version. Visibility through the
 * lamps' lit regions (computed and cached on demand); a lamp whose region
 * cannot be had (larger than the pool, no scratch) is answered by the
 * segment path instead (counted in stats.fallbacks), so the result does not
 * depend on the cache. Returns PLX_OK or PLX_E_INVALID (NULL argument).
 * P is taken as given: see light_classify_point for checking it. */
plx_status light_illuminance(light *L, const double P[3], const double n[3],
                             double *E /* OUT */, double rgb[3] /* OUT, may be NULL */);

/* The same by the segment path only (no cache, no memory). */
plx_status light_illuminance_exact(light *L, const double P[3], const double n[3],
                                   double *E /* OUT */, double rgb[3] /* OUT, may be NULL */);

/* Which lamps light P (facing n): writes up to cap lamp ids and their
 * uncoloured terms (lux) in lamp order, returns how many lamps light P
 * (may exceed cap; then only cap were written). Same visibility as
 * light_illuminance; ids and contrib may be NULL when cap is 0. */
int light_lamps_at(light *L, const double P[3], const double n[3],
                   uint32_t *ids /* OUT */, double *contrib /* OUT */, int cap);

/* Visibility of P from lamp i: 1 visible, 0 blocked (whatever the distance
 * and the normal). By the lamp's region when it can be had, else by the
 * segment path. */
int light_visible(light *L, uint32_t lamp, const double P[3]);

/* light_illuminance's rgb at P (pool_cap > 0) reading the region cache
 * only: nothing in L changes, so several threads may call it at once
 * (while no one else uses L). Returns 0 with rgb written, the same values
 * as light_illuminance; or -1 (rgb undefined) when a lamp that reaches P
 * has no region in the cache or P lies straight under it (the segment
 * path, which uses L's buffers). */
int light_illuminance_cached(const light *L, const double P[3], const double n[3], double rgb[3] /* OUT */);

/* Puts in the cache the region of every lamp whose ground reach box meets
 * the box x0 <= x <= x1, y0 <= y <= y1 (as light_visible would on first
 * need), from the lamp grid's cells over the box. */
void light_cache_box(light *L, double x0, double y0, double x1, double y1);

#endif
