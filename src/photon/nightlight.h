/* nightlight: munoz2013's night lighting of the ground (§3.3-3.4): per-lamp
 * floor photon maps in an LRU cache, refined near the viewer, and their
 * exchange with the aerial chart (nightlight.c). */
#ifndef PLX_NIGHTLIGHT_H
#define PLX_NIGHTLIGHT_H

#include "photon/photon.h"

/*
 * Makes lamp i's floor map available: on a hit it becomes the most recently
 * used; on a miss it is computed into the least recently used slot
 * (evicting that lamp), and the first time also pushed into I (see above).
 * Returns 1 on a hit, 0 on a miss, -1 when i is out of range or the cache
 * has no slot. Uses no memory.
 */
int photon_lamp_request(photon_sys *ps, uint32_t lamp);

/* Refines the lamps within cfg.near_radius (horizontally) of eye, nearest
 * first, at most the cache capacity. Returns the number of misses (maps
 * computed), or -1 when scratch memory runs out. */
int photon_lamps_update(photon_sys *ps, const double eye[3]);

/* Whether lamp i is in the cache (1/0), without touching the LRU order. */
int photon_lamp_cached(const photon_sys *ps, uint32_t lamp);

/* The cached lamps from most to least recently used: writes up to cap
 * lamp indices, returns how many are cached. */
uint32_t photon_lamp_lru(const photon_sys *ps, uint32_t *lamps /* OUT */, uint32_t cap);

/* The floor-map share of E_indirect at (x, y) on the ground or a roof of
 * surface key z (surface_key.h),
 * PHOTON_CH channels: I - sum D_i + sum C_i (lux), 0 when nothing is
 * refined. On covered ground (covered != 0) it is I_cov. */
void photon_night_horizontal(const photon_sys *ps, double x, double y, double z, int covered,
                             double e[PHOTON_CH] /* OUT */);

#endif
