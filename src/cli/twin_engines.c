/* twin_engines: work over many items on the engine and its twins
 * (twin_engines.h). */
#include <pthread.h>
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
    if (threads > 1 && cli_is_bake(scene) && plx_indirect_frames(e) > 0)
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

/* One call's items, taken `chunk` at a time by every thread. */
typedef struct twin_job {
    pthread_mutex_t mu;
    size_t n, chunk, next, done;
    twin_fn fn;
    void *arg;
    int range_soft;     /* PLX_E_RANGE of a chunk is kept in `range`, not a failure */
    void (*progress)(void *arg, size_t done, size_t n);
    plx_status st;      /* the failure of the lowest chunk that failed (PLX_OK: none) */
    size_t st_at;       /* that chunk's first item */
    plx_engine *failed; /* its engine */
    int range;
} twin_job;

typedef struct twin_arg {
    twin_job *j;
    plx_engine *e;
} twin_arg;

/* Takes chunks until none is left or a failure stops the handing out
 * (chunks go out in order: every chunk before a failed one was taken). */
static void *twin_run(void *p)
{
    twin_arg *a = p;
    twin_job *j = a->j;
    for (;;) {
        size_t k, m;
        plx_status st;
        pthread_mutex_lock(&j->mu);
        k = j->next;
        m = j->st == PLX_OK && k < j->n ? (j->n - k < j->chunk ? j->n - k : j->chunk) : 0;
        j->next += m;
        pthread_mutex_unlock(&j->mu);
        if (m == 0)
            return NULL;
        st = j->fn(j->arg, a->e, k, k + m);
        pthread_mutex_lock(&j->mu);
        if (st == PLX_E_RANGE && j->range_soft) {
            j->range = 1;
        } else if (st != PLX_OK && (j->st == PLX_OK || k < j->st_at)) {
            j->st = st;
            j->st_at = k;
            j->failed = a->e;
        }
        j->done += m;
        if (j->progress)
            j->progress(j->arg, j->done, j->n);
        pthread_mutex_unlock(&j->mu);
    }
}

plx_status twin_for(twin_set *t, plx_engine *e, const twin_work *w, plx_engine **failed)
{
    pthread_t th[TWIN_MAX];
    twin_arg a[TWIN_MAX + 1];
    int started[TWIN_MAX], k, nt, ran;
    twin_job j;
    *failed = e;
    if (w->n >= w->min_items && t && t->want > 0 && !t->tried)
        twins_load(t);
    nt = w->n >= w->min_items && t ? t->n : 0;
    memset(&j, 0, sizeof j);
    j.n = w->n;
    j.chunk = w->chunk > 0 ? w->chunk : 1;
    j.fn = w->fn;
    j.arg = w->arg;
    j.range_soft = w->range_soft;
    j.progress = w->progress;
    j.st = PLX_OK;
    if (pthread_mutex_init(&j.mu, NULL) != 0) /* no lock: one call on the engine */
        return w->n > 0 ? w->fn(w->arg, e, 0, w->n) : PLX_OK;
    for (k = 0; k <= nt; k++) {
        a[k].j = &j;
        a[k].e = k == 0 ? e : t->tw[k - 1];
    }
    for (k = 0, ran = 1; k < nt; k++)
        ran += started[k] = pthread_create(&th[k], NULL, twin_run, &a[k + 1]) == 0;
    if (ran < nt + 1 && !t->thread_warned) {
        t->thread_warned = 1;
        cli_warn(t->cmd, t->c, "%d of %d threads could not be started: working on %d", nt + 1 - ran, nt + 1, ran);
    }
    twin_run(&a[0]);
    for (k = 0; k < nt; k++)
        if (started[k])
            pthread_join(th[k], NULL);
    if (t && ran > t->ran)
        t->ran = ran;
    pthread_mutex_destroy(&j.mu);
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
