/* twin_gather: illuminance at many points on the engine and its twins
 * (twin_gather.h). */
#include <pthread.h>
#include <string.h>

#include "twin_gather.h"
#include "port.h"

#define TWIN_CHUNK 32 /* points a thread takes at a time: gathers vary a lot in cost */

void twin_gather_init(twin_gather *t, const char *cmd, const char *scene, const cli_common *c, plx_engine *e)
{
    int threads = c->threads > 0 ? c->threads : port_cores(NULL);
    memset(t, 0, sizeof *t);
    t->cmd = cmd;
    t->scene = scene;
    t->c = c;
    if (threads > 1 && cli_is_bake(scene) && plx_indirect_frames(e) > 0)
        t->want = threads - 1 < TWIN_MAX ? threads - 1 : TWIN_MAX;
}

/* The twins, loaded quietly (the engine's warnings were printed once);
 * as many as load. */
static void twins_load(twin_gather *t)
{
    cli_common quiet = *t->c;
    t->tried = 1;
    quiet.quiet = 1;
    while (t->n < t->want && cli_open_scene(t->cmd, t->scene, &quiet, &t->tw[t->n]) == EXIT_OK)
        t->n++;
    if (t->n < t->want && !t->c->quiet)
        fprintf(stderr, "polarlux %s: warning: %s loaded %d time%s more of the %d asked for its threads; the "
                "rest of the work runs on %d thread%s\n", t->cmd, t->scene, t->n, t->n == 1 ? "" : "s", t->want,
                t->n + 1, t->n ? "s" : "");
}

/* One call's points, taken TWIN_CHUNK at a time by every thread. */
typedef struct twin_job {
    pthread_mutex_t mu;
    size_t n, next;
    const double *P, *N;
    double *E, *Ei;
    plx_status st;      /* the first failure other than PLX_E_RANGE (PLX_OK: none) */
    plx_engine *failed; /* its engine */
    int range;          /* some chunk had a point out of range */
} twin_job;

typedef struct twin_arg {
    twin_job *j;
    plx_engine *e;
} twin_arg;

/* Takes chunks until none is left or a failure stops the job. */
static void *twin_run(void *p)
{
    twin_arg *a = p;
    twin_job *j = a->j;
    for (;;) {
        size_t k, m;
        plx_status st;
        pthread_mutex_lock(&j->mu);
        k = j->next;
        m = j->st == PLX_OK && k < j->n ? (j->n - k < TWIN_CHUNK ? j->n - k : TWIN_CHUNK) : 0;
        j->next += m;
        pthread_mutex_unlock(&j->mu);
        if (m == 0)
            return NULL;
        st = plx_illuminance(a->e, m, j->P + 3 * k, j->N + 3 * k, j->E + k, j->Ei + k, NULL);
        if (st == PLX_OK)
            continue;
        pthread_mutex_lock(&j->mu);
        if (st == PLX_E_RANGE) {
            j->range = 1;
        } else if (j->st == PLX_OK) {
            j->st = st;
            j->failed = a->e;
        }
        pthread_mutex_unlock(&j->mu);
    }
}

plx_status twin_illuminance(twin_gather *t, plx_engine *e, size_t n, const double *P, const double *N,
                            double *E_direct, double *E_indirect, plx_engine **failed)
{
    pthread_t th[TWIN_MAX];
    twin_arg arg[TWIN_MAX + 1];
    int started[TWIN_MAX], k;
    twin_job j;
    *failed = e;
    if (n >= TWIN_MIN_POINTS && t->want > 0 && !t->tried)
        twins_load(t);
    if (n < TWIN_MIN_POINTS || t->n == 0)
        return plx_illuminance(e, n, P, N, E_direct, E_indirect, NULL);
    memset(&j, 0, sizeof j);
    if (pthread_mutex_init(&j.mu, NULL) != 0)
        return plx_illuminance(e, n, P, N, E_direct, E_indirect, NULL);
    j.n = n;
    j.P = P;
    j.N = N;
    j.E = E_direct;
    j.Ei = E_indirect;
    j.st = PLX_OK;
    for (k = 0; k <= t->n; k++) {
        arg[k].j = &j;
        arg[k].e = k == 0 ? e : t->tw[k - 1];
    }
    for (k = 0; k < t->n; k++)
        started[k] = pthread_create(&th[k], NULL, twin_run, &arg[k + 1]) == 0;
    twin_run(&arg[0]);
    for (k = 0; k < t->n; k++)
        if (started[k])
            pthread_join(th[k], NULL);
    pthread_mutex_destroy(&j.mu);
    if (j.st != PLX_OK) {
        *failed = j.failed;
        return j.st;
    }
    return j.range ? PLX_E_RANGE : PLX_OK;
}

void twin_gather_free(twin_gather *t)
{
    int k;
    for (k = 0; k < t->n; k++)
        plx_engine_free(t->tw[k]);
    t->n = 0;
}
