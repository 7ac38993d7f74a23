/* indirect: E_indirect at surface points from the photon buffers (indirect.c). */
#ifndef PLX_INDIRECT_H
#define PLX_INDIRECT_H

#include "photon/photon.h"

/*
 * E_indirect (lux) at surface point P with outward unit normal n: the
 * ground or a roof when n points up (n[2] > 0.5), an underside when down,
 * else a wall (P within a few mm of it). O(1) apart from the lamp cache
 * term (one test per cached lamp). Points on no surface, or with no frames
 * yet, give 0.
 */
double photon_indirect(photon_sys *ps, const double P[3], const double n[3]);

/* The same, also writing the RGB version of E_indirect to rgb (may be NULL):
 * each lamp's light weighted by its colour (equals the scalar for white
 * lamps and grey albedos). Returns the scalar. */
double photon_indirect_rgb(photon_sys *ps, const double P[3], const double n[3],
                           double rgb[3] /* OUT */);

/* E_indirect (PHOTON_CH channels: scalar, RGB) at the surface of hit h
 * (a wall, the ground, a roof or an underside), as photon_indirect_rgb
 * answers at h->p with h->n but without the probe ray. */
void photon_indirect_hit(photon_sys *ps, const trace_hit *h, double e[PHOTON_CH] /* OUT */);

#endif
