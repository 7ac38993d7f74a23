/* The POSIX port's parallel-for (plx_port.parallel_for): the calling
 * thread plus workers - 1 threads of a pool kept for the whole process,
 * each taking the next job from a counter under a mutex until none is
 * left. The pool's threads are started on first need and then wait on a
 * condition variable between calls, so a frame's several parallel-fors
 * start no thread. A call made while another one holds the pool (a
 * second engine on another thread, or a job that itself asks for a
 * parallel-for) starts threads of its own for the call, as before the
 * pool. Which worker runs which job varies from run to run; the core
 * makes its results depend on the job alone.
 *
 * A frame makes a few dozen parallel-fors with short serial parts between
 * them. A thread about to sleep on the condition variable (a pool thread
 * between calls, the caller waiting for the last jobs) first looks again
 * PAR_SPIN times, yielding the core between looks (about 55 us in all
 * on an idle core here), so that a call coming soon finds it awake
 * instead of having to wake it. Measured on a
 * 640x480 street frame with 2 x 2 samples on two threads: about 5 to 10%
 * less wall time (README "Threads"). */
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <sched.h>
#include <unistd.h>

#include "polarlux.h"
#include "port.h"

#define PAR_SPIN 300 /* looks before sleeping */

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

/* Jobs of run for worker id until none is left. */
static void par_loop(par_run *run, int id)
{
    for (;;) {
        uint32_t k;
        pthread_mutex_lock(&run->mu);
        k = run->next;
        if (k < run->njobs)
            run->next++;
        pthread_mutex_unlock(&run->mu);
        if (k >= run->njobs)
            return;
        run->job(run->arg, id, k);
    }
}

static void *spawned_loop(void *p)
{
    par_worker *w = p;
    par_loop(w->run, w->id);
    return NULL;
}

/* The pool: thread i (1 .. started) is worker i of every call that wants
 * more than i workers. gen counts the calls; a thread takes part in call
 * gen when its id is below want, and the caller waits until left is 0. */
typedef struct par_pool {
    pthread_mutex_t mu;
    pthread_cond_t wake, idle;
    pthread_t th[PLX_MAX_THREADS];
    unsigned long seen[PLX_MAX_THREADS]; /* the call each thread last saw */
    unsigned long gen;
    int started, busy, quit, want, left, hooks;
    par_run *run;
} par_pool;

static par_pool pool = { PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, PTHREAD_COND_INITIALIZER,
                         { 0 }, { 0 }, 0, 0, 0, 0, 0, 0, 0, NULL };

static void *pool_loop(void *p)
{
    int id = (int)(intptr_t)p;
    pthread_mutex_lock(&pool.mu);
    for (;;) {
        int spin;
        for (spin = 0; spin < PAR_SPIN && !pool.quit && pool.seen[id] == pool.gen; spin++) {
            pthread_mutex_unlock(&pool.mu);
            sched_yield();
            pthread_mutex_lock(&pool.mu);
        }
        while (!pool.quit && pool.seen[id] == pool.gen)
            pthread_cond_wait(&pool.wake, &pool.mu);
        if (pool.quit)
            break;
        pool.seen[id] = pool.gen;
        if (id < pool.want) {
            par_run *run = pool.run;
            pthread_mutex_unlock(&pool.mu);
            par_loop(run, id);
            pthread_mutex_lock(&pool.mu);
            if (--pool.left == 0)
                pthread_cond_signal(&pool.idle);
        }
    }
    pthread_mutex_unlock(&pool.mu);
    return NULL;
}

/* At exit: the waiting threads end and are joined (nothing left running
 * for valgrind to see). Left alone while a call holds the pool. */
static void pool_stop(void)
{
    int i, n;
    pthread_mutex_lock(&pool.mu);
    if (pool.busy) {
        pthread_mutex_unlock(&pool.mu);
        return;
    }
    pool.quit = 1;
    n = pool.started;
    pthread_cond_broadcast(&pool.wake);
    pthread_mutex_unlock(&pool.mu);
    for (i = 1; i <= n; i++)
        pthread_join(pool.th[i], NULL);
    pthread_mutex_lock(&pool.mu);
    pool.started = 0;
    pool.quit = 0;
    pthread_mutex_unlock(&pool.mu);
}

/* In a child after fork the pool's threads are not there: it starts anew. */
static void pool_after_fork(void)
{
    pthread_mutex_init(&pool.mu, NULL);
    pthread_cond_init(&pool.wake, NULL);
    pthread_cond_init(&pool.idle, NULL);
    pool.started = pool.busy = pool.quit = pool.want = pool.left = 0;
    pool.run = NULL;
}

/* Threads up to n - 1 (fewer if one cannot start); pool.mu held. */
static void pool_grow(int n)
{
    if (!pool.hooks) {
        if (atexit(pool_stop) != 0 || pthread_atfork(NULL, NULL, pool_after_fork) != 0)
            return; /* no pool without its hooks: the caller spawns */
        pool.hooks = 1;
    }
    while (pool.started < n - 1) {
        int id = pool.started + 1;
        pool.seen[id] = pool.gen;
        if (pthread_create(&pool.th[id], NULL, pool_loop, (void *)(intptr_t)id) != 0)
            return;
        pool.started = id;
    }
}

/* The call on threads started for it (the pool is taken). */
static void spawn_for(par_run *run, int n)
{
    pthread_t th[PLX_MAX_THREADS];
    par_worker wk[PLX_MAX_THREADS];
    int started = 0, i;
    for (i = 1; i < n; i++) {
        wk[i].run = run;
        wk[i].id = i;
        if (pthread_create(&th[i], NULL, spawned_loop, &wk[i]) != 0)
            break;
        started = i;
    }
    par_loop(run, 0);
    for (i = 1; i <= started; i++)
        pthread_join(th[i], NULL);
}

/* The call on the pool's threads; 0 when another call holds the pool. */
static int pool_for(par_run *run, int n)
{
    int m, spin;
    pthread_mutex_lock(&pool.mu);
    if (pool.busy) {
        pthread_mutex_unlock(&pool.mu);
        return 0;
    }
    pool.busy = 1;
    pool_grow(n);
    m = n < pool.started + 1 ? n : pool.started + 1;
    pool.run = run;
    pool.want = m;
    pool.left = m - 1;
    pool.gen++;
    if (m > 1)
        pthread_cond_broadcast(&pool.wake);
    pthread_mutex_unlock(&pool.mu);
    par_loop(run, 0);
    pthread_mutex_lock(&pool.mu);
    for (spin = 0; spin < PAR_SPIN && pool.left > 0; spin++) {
        pthread_mutex_unlock(&pool.mu);
        sched_yield();
        pthread_mutex_lock(&pool.mu);
    }
    while (pool.left > 0)
        pthread_cond_wait(&pool.idle, &pool.mu);
    pool.run = NULL;
    pool.want = 0;
    pool.busy = 0;
    pthread_mutex_unlock(&pool.mu);
    return 1;
}

int port_parallel_for(void *ctx, int workers, uint32_t njobs, void (*job)(void *arg, int worker, uint32_t k),
                      void *arg)
{
    par_run run;
    int n;
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
    if (n == 1)
        par_loop(&run, 0);
    else if (!pool_for(&run, n))
        spawn_for(&run, n);
    pthread_mutex_destroy(&run.mu);
    return 0;
}

int port_cores(void *ctx)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    (void)ctx;
    return n < 1 ? 1 : n > PLX_MAX_THREADS ? PLX_MAX_THREADS : (int)n;
}

unsigned long long port_memory_bytes(void)
{
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGESIZE)
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    return pages > 0 && size > 0 ? (unsigned long long)pages * (unsigned long long)size : 0;
#else
    return 0;
#endif
}
