/* The POSIX port's parallel-for (plx_port.parallel_for): workers - 1
 * threads started for the call plus the calling thread, taking the next
 * job from a counter under a mutex until none is left. Which worker runs
 * which job varies from run to run; the core makes its results depend on
 * the job alone. */
#include <pthread.h>
#include <unistd.h>

#include "polarlux.h"
#include "port.h"

typedef struct par_run {
    pthread_mutex_t mu;
    uint32_t next, njobs;
    void (*job)(void *arg, int worker, uint32_t k);
    void *arg;
} par_run;

typedef struct par_worker {
    par_run *run;
    int id;
} par_worker;

static void *par_loop(void *p)
{
    par_worker *w = p;
    par_run *run = w->run;
    for (;;) {
        uint32_t k;
        pthread_mutex_lock(&run->mu);
        k = run->next;
        if (k < run->njobs)
            run->next++;
        pthread_mutex_unlock(&run->mu);
        if (k >= run->njobs)
            return NULL;
        run->job(run->arg, w->id, k);
    }
}

int port_parallel_for(void *ctx, int workers, uint32_t njobs, void (*job)(void *arg, int worker, uint32_t k),
                      void *arg)
{
    pthread_t th[PLX_MAX_THREADS];
    par_worker wk[PLX_MAX_THREADS];
    par_run run;
    int n, started = 0, i;
    (void)ctx;
    if (!job)
        return -1;
    n = workers < 1 ? 1 : workers > PLX_MAX_THREADS ? PLX_MAX_THREADS : workers;
    if ((uint32_t)n > njobs)
        n = njobs > 0 ? (int)njobs : 1;
    if (pthread_mutex_init(&run.mu, NULL) != 0)
        return -1;
    run.next = 0;
    run.njobs = njobs;
    run.job = job;
    run.arg = arg;
    for (i = 0; i < n; i++) {
        wk[i].run = &run;
        wk[i].id = i;
    }
    /* workers 1 .. n-1 on new threads (fewer if one cannot start), 0 here */
    for (i = 1; i < n; i++) {
        if (pthread_create(&th[i], NULL, par_loop, &wk[i]) != 0)
            break;
        started = i;
    }
    par_loop(&wk[0]);
    for (i = 1; i <= started; i++)
        pthread_join(th[i], NULL);
    pthread_mutex_destroy(&run.mu);
    return 0;
}

int port_cores(void *ctx)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    (void)ctx;
    return n < 1 ? 1 : n > PLX_MAX_THREADS ? PLX_MAX_THREADS : (int)n;
}
