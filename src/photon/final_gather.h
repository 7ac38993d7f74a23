/* final_gather: E_indirect at a point by final gathering (Jensen 1996) over
 * exact direct light, the photon buffers only for the later bounces.
 *
 * WHAT IS COMPUTED. E_indirect(P) with normal n is the cosine-weighted
 * integral over the hemisphere of n of the radiance L(Q) coming from the
 * first surface Q seen in each direction; surfaces are Lambertian (SPEC
 * §4), so L(Q) = a(Q) / pi (E_direct(Q) + E_indirect(Q)) and
 *
 *   E_indirect(P) = integral of a(Q) (E_direct(Q) + E_indirect(Q)) cos / pi
 *                 ~ (1/N) sum_k a(Q_k) (E_direct(Q_k) + E_ind_photons(Q_k))
 *
 * with N cosine-distributed directions. E_direct(Q) is exact (light.h: the
 * same 2.5D visibility as every direct answer), so the first bounce, most
 * of the indirect light, carries no photon noise; only E_indirect(Q), the
 * light that already bounced once before reaching Q, comes from the photon
 * buffers (photon_indirect_hit), and its noise is averaged over the N
 * gather points (which fall in many different texels).
 *
 * SAMPLING. The N = side^2 directions are stratified: the unit square of
 * (u1, u2) is cut into side x side cells, one jittered sample per cell,
 * mapped to the hemisphere by radius sqrt(u1), azimuth 2 pi u2 (cosine
 * weighted, so each sample weighs 1/N). The jitter comes from a
 * splitmix64 stream seeded by the seed and the bits of P and n: the answer
 * at a point does not depend on which points were asked before, and the
 * same (seed, P, n) gives the same bytes.
 *
 * ALBEDO. a(Q) is the building's albedo on walls, roofs and undersides and
 * the ground's (scene_ground_albedo: a ground image's pixel or the scene's
 * ground_albedo) on the ground, per channel for the RGB answer; the scalar
 * answer uses its luminance, as the photon pass does.
 *
 * POINTS IN FREE AIR. The integral is the same for a light meter held in
 * the air (the hemisphere above its normal); nothing here needs P to be on
 * a surface.
 *
 * RAYS. At a point facing straight up every ray goes up; those over the
 * point's horizon (trace_horizon_sky, made once per gather) meet nothing
 * and are not walked: the same answers, most of the rays of a ground
 * point in a street.
 *
 * MEMORY. None: one ray and one direct-light answer per direction (the
 * light object's region cache is filled on demand from its own pool). Not
 * for two threads at once (the tracer's counters, the light cache).
 */
#ifndef PLX_FINAL_GATHER_H
#define PLX_FINAL_GATHER_H

#include <stdint.h>
#include "light/illuminance.h"
#include "photon/photon.h"

/* Default side of the direction grid: 32 x 32 = 1024 directions. */
#define FINAL_GATHER_SIDE 32

/*
 * E_indirect (lux) at P with unit normal n from side^2 gathered directions
 * (side >= 1), writing its RGB version to rgb (may be NULL). The later
 * bounces come from ps's buffers when it has frames (ps may be NULL: first
 * bounce only). Deterministic for (seed, P, n).
 */
double final_gather_rgb(photon_sys *ps, tracer *T, light *L, const double P[3],
                        const double n[3], uint32_t side, uint64_t seed,
                        double rgb[3] /* OUT */);

/*
 * The same with E_later read at one direction of each later x later block
 * of strata (one chosen uniformly per block from a stream of its own),
 * weighted later^2: an unbiased estimate of the same integral with later^2
 * times fewer photon lookups (E_later is the smooth, small part; the exact
 * E_direct is still taken at every direction, the directions are those of
 * final_gather_rgb). later 1 (or a later side is not a multiple of) is
 * final_gather_rgb itself.
 */
double final_gather_rgb_later(photon_sys *ps, tracer *T, light *L, const double P[3],
                              const double n[3], uint32_t side, uint32_t later, uint64_t seed,
                              double rgb[3] /* OUT */);

#endif
