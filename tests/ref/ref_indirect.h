/* ref_indirect: an independent path-traced E_indirect (SPEC §4) for
 * checking the photon buffers and final gathering (tests/unit,
 * tests/bench).
 *
 * Paths start at P with a cosine-weighted direction (libm's cos and sin,
 * plain uniform random numbers: not the engine's sampler), and at every
 * surface Q they meet add a(Q) E_direct(Q), then continue with probability
 * a(Q) (Russian roulette; albedos grey, the scene's ground_albedo on the
 * ground). E_direct(Q) is SPEC §2 by shadow rays (the caster, which
 * test_photon checks against a brute force), not the engine's lit
 * regions. The mean over paths estimates E_indirect(P); its standard error
 * is returned too.
 *
 * The same file picks test points like test_photon's accuracy table:
 * ground points 2-8 m from random lamps, facade points where horizontal
 * rays from random lamps (1 m up to 0.5 m below the lamp) meet a wall
 * within 12 m. */
#ifndef REF_INDIRECT_H
#define REF_INDIRECT_H

#include <stdint.h>
#include "base/scene.h"
#include "photon/trace.h"

/* SPEC §2 at Q by shadow rays; rgb (may be NULL) gets the colour-weighted version. */
double ref_indirect_direct(tracer *T, const scene *s, const double Q[3], const double n[3],
                           double rgb[3] /* OUT */);

/* Path-traced E_indirect at P with paths paths (seeded by seed); *sd (may
 * be NULL) gets the standard error of the mean. */
double ref_indirect_paths(tracer *T, const scene *s, const double P[3], const double n[3],
                          int paths, uint64_t seed, double *sd /* OUT */);

/* The same paths; rgb (may be NULL) also gets the colour-weighted E_indirect
 * (each lamp's term weighted by its colour). */
double ref_indirect_paths_rgb(tracer *T, const scene *s, const double P[3], const double n[3],
                              int paths, uint64_t seed, double rgb[3] /* OUT */, double *sd /* OUT */);

/* nground ground points then nfacade facade points, as above, away from
 * the bounds by 60 m; P and N hold 3 doubles per point. Returns the number
 * written (fewer when 100,000 tries were not enough). */
int ref_indirect_points(tracer *T, const scene *s, int nground, int nfacade, uint64_t seed,
                        double *P /* OUT */, double *N /* OUT */);

#endif
