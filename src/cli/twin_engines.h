/* twin_engines: work over many items (points, street edges) shared
 * between the engine and twins loaded from the same bake file, each on a
 * thread of its own (README: `dark-spots`, `annotate`, `route --network`).
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
#ifndef PLX_TWIN_ENGINES_H
#define PLX_TWIN_ENGINES_H

#include <stddef.h>
#include "cli.h"

#define TWIN_MAX 7          /* twins at most: 8 engines */
#define TWIN_MIN_POINTS 256 /* fewer points a call: on the engine alone */

typedef struct twin_set {
    const char *cmd, *scene;
    const cli_common *c;
    plx_engine *tw[TWIN_MAX];
    int n;          /* twins loaded */
    int want;       /* twins to load on first need (0: none) */
    int tried;      /* the load was tried */
    int ran;        /* the most threads one call ran on (0: none yet) */
} twin_set;

/* Sets up t for engine e, loaded by the last cli_open_scene from scene
 * (kept referenced, as c): twins for c->threads - 1 further threads,
 * loaded on first need, when scene was a bake (cli_bake_last) and e has
 * photon frames. Without
 * --threads, one for each further processor while all the engines (each
 * about e's bytes in use) stay within half of the machine's memory (a
 * note on stderr when that leaves fewer). */
void twin_set_init(twin_set *t, const char *cmd, const char *scene, const cli_common *c, plx_engine *e);

/* Work on items [k0, k1) with engine e: a status (twin_work). */
typedef plx_status (*twin_fn)(void *arg, plx_engine *e, size_t k0, size_t k1);

typedef struct twin_work {
    size_t n;          /* items */
    size_t chunk;      /* items a thread takes at a time */
    size_t min_items;  /* fewer items: on the engine alone (the twins not loaded for them) */
    int range_soft;    /* a chunk's PLX_E_RANGE is no failure: the call returns it at the end */
    twin_fn fn;        /* each chunk's work, on whichever engine takes it */
    void *arg;
    void (*progress)(void *arg, size_t done, size_t n); /* after each chunk (under a lock), or NULL */
} twin_work;

/* w->fn over items [0, w->n) in chunks, jobs of the port's parallel-for
 * (port_parallel_for: e's thread and a worker per twin, the twins
 * loaded on first need), each worker with its own engine; the items
 * must not depend on one another. Returns PLX_OK, the status of the
 * lowest failed chunk (chunks after it are skipped once it fails; *failed:
 * the engine whose plx_last_error says why), or PLX_E_RANGE with
 * range_soft when a chunk returned it. t NULL: on e alone. */
plx_status twin_for(twin_set *t, plx_engine *e, const twin_work *w, plx_engine **failed /* OUT */);

/* plx_illuminance(e, n, P, N, E_direct, E_indirect, NULL) (E_indirect
 * not NULL) with the points shared out in chunks between e and the
 * twins; the same values. Returns PLX_OK, PLX_E_RANGE (some point out of
 * range: its values NaN; with twins the engines' messages then name a
 * point by its place in a chunk, not in P) or another status, with
 * *failed the engine whose plx_last_error says why. */
plx_status twin_illuminance(twin_set *t, plx_engine *e, size_t n, const double *P, const double *N,
                            double *E_direct, double *E_indirect, plx_engine **failed /* OUT */);

/* Of `want` twins, how many the default allows: all engines, each of
 * `each` bytes, within half of `machine` bytes (0: unknown, all). */
int twin_fit(int want, unsigned long long each, unsigned long long machine);

/* The most threads a call of twin_for ran on (1 when none had twins). */
int twin_threads(const twin_set *t);

/* Frees the twins. */
void twin_set_free(twin_set *t);

#endif
