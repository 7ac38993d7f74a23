/* twin_gather: illuminance with indirect light at many points, shared
 * between the engine and twins loaded from the same bake file, each on a
 * thread of its own (README "dark-spots").
 *
 * An engine answers one query at a time (its light and tracer keep
 * caches and counters), and a final gather costs about a thousand times
 * a point's direct light. A bake loads in milliseconds, so a twin per
 * further thread is the cheap way to spread the gathers: each point's
 * answer depends only on the point (final_gather.h: deterministic for
 * the point and its normal), so the values are the same bits whichever
 * engine computes them, on any number of threads.
 *
 * Memory: each twin is a second block of the bake's size (or --mem): the
 * price of the threads, said in the command's help. Only bakes with
 * photon frames get twins (a scene file has no indirect light to
 * gather, and tracing its photons again would cost more than it saves).
 */
#ifndef PLX_TWIN_GATHER_H
#define PLX_TWIN_GATHER_H

#include <stddef.h>
#include "cli.h"

#define TWIN_MAX 7          /* twins at most: 8 engines */
#define TWIN_MIN_POINTS 256 /* fewer points a call: on the engine alone */

typedef struct twin_gather {
    const char *cmd, *scene;
    const cli_common *c;
    plx_engine *tw[TWIN_MAX];
    int n;          /* twins loaded */
    int want;       /* twins to load on first need (0: none) */
    int tried;      /* the load was tried */
} twin_gather;

/* Sets up t for engine e, loaded by cli_open_scene from scene (kept
 * referenced, as c): twins for c->threads - 1 further threads (the
 * processors' number - 1 when 0), loaded on first need, when scene is a
 * bake and e has photon frames. */
void twin_gather_init(twin_gather *t, const char *cmd, const char *scene, const cli_common *c, plx_engine *e);

/* plx_illuminance(e, n, P, N, E_direct, E_indirect, NULL) (E_indirect
 * not NULL) with the points shared out in chunks between e and the
 * twins; the same values. Returns PLX_OK, PLX_E_RANGE (some point out of
 * range: its values NaN; the engines' messages then name a point by its
 * place in a chunk, not in P) or another status, with *failed the engine
 * whose plx_last_error says why. */
plx_status twin_illuminance(twin_gather *t, plx_engine *e, size_t n, const double *P, const double *N,
                            double *E_direct, double *E_indirect, plx_engine **failed /* OUT */);

/* Frees the twins. */
void twin_gather_free(twin_gather *t);

#endif
