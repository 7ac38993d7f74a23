/* twin_engines: work over many items on the engine and its twins
 * (twin_engines.h). */
#include <pthread.h>
#include <stdint.h>
#include <string.h>

#include "twin_engines.h"
#include "port.h"

#define TWIN_CHUNK 32 /* points a thread takes at a time: gathers vary a lot in cost */

int twin_fit(int want, unsigned long long each, unsigned long long machine)
{
    unsigned long long fit;
    if (machine == 0 || each == 0)
        return want;
    fit = machine / 2 / each;
    return fit < 1 ? 0 : fit - 1 < (unsigned long long)want ? (int)(fit - 1) : want;
}

void twin_set_init(twin_set *t, const char *cmd, const char *scene, const cli_common *c, plx_engine *e)
{
    int threads = c->threads > 0 ? c->threads : port_cores(NULL), allowed;
    unsigned long long each, machine;
    plx_memory_report m;
    memset(t, 0, sizeof *t);
    t->cmd = cmd;
    t->scene = scene;
    t->c = c;
    if (threads > 1 && cli_bake_last.loaded && plx_indirect_frames(e) > 0) /* e came from a bake */
        t->want = threads - 1 < TWIN_MAX ? threads - 1 : TWIN_MAX;
    if (t->want == TWIN_MAX && c->threads > TWIN_MAX + 1)
        cli_warn(cmd, c, "--threads %d: this work runs on at most %d threads (a copy of the bake each)", c->threads,
                 TWIN_MAX + 1);
    if (t->want == 0 || c->threads > 0) /* --threads N: as asked */
        return;
    plx_memory_get(e, &m);
    each = m.peak_total;
    machine = port_memory_bytes();
    allowed = twin_fit(t->want, each, machine);
    if (allowed < t->want && !c->quiet)
        fprintf(stderr, "polarlux %s: note: %d thread%s of the %d processors: each further thread loads the bake "
                "again (%.0f MB), and more would pass half of the machine's %.0f MB (--threads N asks for N)\n",
                cmd, allowed + 1, allowed ? "s" : "", threads, each / 1e6, machine / 1e6);
    t->want = allowed;
}

/* The twins, loaded quietly (cli_open_twin); as many as load, and a
 * warning with the reason when fewer. */
static void twins_load(twin_set *t)
{
    char why[512];
    why[0] = '\0';
    t->tried = 1;
    while (t->n < t->want && cli_open_twin(t->scene, t->c, &t->tw[t->n], why, sizeof why) == EXIT_OK)
        t->n++;
    if (t->n < t->want)
        cli_warn(t->cmd, t->c, "%d of the %d further copies of %s for --threads could not be loaded (%s): "
                 "working on %d thread%s", t->want - t->n, t->want, t->scene, why, t->n + 1, t->n ? "s" : "");
}

/* One call's items, `chunk` a job of the port's parallel-for (worker w
 * works with engine e[w]). */
typedef struct twin_job {
    pthread_mutex_t mu;
    plx_engine *e[TWIN_MAX + 1];
    const twin_work *w;
    size_t done;
    plx_status st;      /* the failure of the lowest chunk that failed (PLX_OK: none) */
    size_t st_at;       /* that chunk's first item */
    plx_engine *failed; /* its engine */
    int range;          /* a chunk said PLX_E_RANGE (range_soft) */
    int ran;            /* the highest worker that took a chunk, plus one */
} twin_job;

/* Chunk k on worker's engine; skipped when a chunk before it has
 * failed (one after a failed chunk still runs: the port hands the jobs
 * out in order, but a chunk taken earlier may start after a later one
 * failed, and it may fail too, lower). */
static void twin_chunk(void *arg, int worker, uint32_t k)
{
    twin_job *j = arg;
    const twin_work *w = j->w;
    size_t k0 = (size_t)k * w->chunk, k1 = w->n - k0 < w->chunk ? w->n : k0 + w->chunk;
    plx_status st;
    int skip;
    pthread_mutex_lock(&j->mu);
    skip = j->st != PLX_OK && j->st_at < k0;
    j->ran = worker + 1 > j->ran ? worker + 1 : j->ran;
    pthread_mutex_unlock(&j->mu);
    if (skip)
        return;
    st = w->fn(w->arg, j->e[worker], k0, k1);
    pthread_mutex_lock(&j->mu);
    if (st == PLX_E_RANGE && w->range_soft) {
        j->range = 1;
    } else if (st != PLX_OK && (j->st == PLX_OK || k0 < j->st_at)) {
        j->st = st;
        j->st_at = k0;
        j->failed = j->e[worker];
    }
    j->done += k1 - k0;
    if (w->progress)
        w->progress(w->arg, j->done, w->n);
    pthread_mutex_unlock(&j->mu);
}

plx_status twin_for(twin_set *t, plx_engine *e, const twin_work *w, plx_engine **failed)
{
    twin_job j;
    size_t chunks, c;
    int k, nt;
    *failed = e;
    if (w->n == 0)
        return PLX_OK;
    if (w->chunk == 0)
        return w->fn(w->arg, e, 0, w->n);
    if (w->n >= w->min_items && t && t->want > 0 && !t->tried)
        twins_load(t);
    nt = w->n >= w->min_items && t ? t->n : 0;
    chunks = (w->n + w->chunk - 1) / w->chunk;
    memset(&j, 0, sizeof j);
    j.w = w;
    j.st = PLX_OK;
    j.e[0] = e;
    for (k = 0; k < nt; k++)
        j.e[k + 1] = t->tw[k];
    if (chunks > UINT32_MAX || pthread_mutex_init(&j.mu, NULL) != 0)
        return w->fn(w->arg, e, 0, w->n); /* one call on the engine */
    if (port_parallel_for(NULL, nt + 1, (uint32_t)chunks, twin_chunk, &j) != 0)
        for (c = 0; c < chunks; c++) /* the port could not run it: here, on e */
            twin_chunk(&j, 0, (uint32_t)c);
    pthread_mutex_destroy(&j.mu);
    if (t && j.ran > t->ran)
        t->ran = j.ran;
    if (j.st != PLX_OK) {
        *failed = j.failed;
        return j.st;
    }
    return j.range ? PLX_E_RANGE : PLX_OK;
}

typedef struct illum_arg {
    const double *P, *N;
    double *E, *Ei;
} illum_arg;

static plx_status illum_chunk(void *arg, plx_engine *e, size_t k0, size_t k1)
{
    illum_arg *a = arg;
    return plx_illuminance(e, k1 - k0, a->P + 3 * k0, a->N + 3 * k0, a->E + k0, a->Ei + k0, NULL);
}

plx_status twin_illuminance(twin_set *t, plx_engine *e, size_t n, const double *P, const double *N,
                            double *E_direct, double *E_indirect, plx_engine **failed)
{
    illum_arg a;
    twin_work w;
    a.P = P;
    a.N = N;
    a.E = E_direct;
    a.Ei = E_indirect;
    if (n < TWIN_MIN_POINTS || !t || t->want == 0) { /* one call: its message names the point by its place in P */
        *failed = e;
        return plx_illuminance(e, n, P, N, E_direct, E_indirect, NULL);
    }
    memset(&w, 0, sizeof w);
    w.n = n;
    w.chunk = TWIN_CHUNK;
    w.min_items = TWIN_MIN_POINTS;
    w.range_soft = 1;
    w.fn = illum_chunk;
    w.arg = &a;
    return twin_for(t, e, &w, failed);
}

int twin_threads(const twin_set *t)
{
    return t && t->ran > 1 ? t->ran : 1;
}

void twin_set_free(twin_set *t)
{
    int k;
    for (k = 0; k < t->n; k++)
        plx_engine_free(t->tw[k]);
    t->n = 0;
}
