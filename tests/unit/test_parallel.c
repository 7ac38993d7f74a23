/* test_parallel: the POSIX port's parallel-for (port/posix/parallel.c), whose
 * threads stay in a pool between calls.
 *
 * Every job runs exactly once, on a worker id below the workers asked,
 * over many calls of changing sizes (the pool grows, and calls that want
 * fewer workers leave some of its threads idle); a job that itself asks
 * for a parallel-for (the pool is taken: threads of its own); two threads
 * calling at once; and a child after fork, whose pool starts anew
 * (skipped when PLX_NO_FORK_THREADS gives a reason: check-arm64, whose
 * qemu-user aborts with an assertion of its own when a child of a
 * threaded process starts threads). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "polarlux.h"
#include "port.h"
#include "slow.h"

#define MAXJOBS 4096

typedef struct tally {
    uint32_t njobs;
    int workers;
    unsigned char runs[MAXJOBS]; /* each job's own byte: no two workers share one */
    int worker_of[MAXJOBS];
    uint32_t spin[MAXJOBS];      /* some work, so that the workers overlap */
} tally;

static void count_job(void *arg, int worker, uint32_t k)
{
    tally *t = arg;
    uint32_t i, x = k;
    for (i = 0; i < (k % 64) * 40; i++)
        x = x * 1664525u + 1013904223u;
    t->spin[k] = x;
    t->runs[k]++;
    t->worker_of[k] = worker;
}

/* One call of njobs jobs on workers; every job once, on a worker id below
 * the workers asked (and below the jobs, as the port caps them). */
static void check_call(tally *t, int workers, uint32_t njobs)
{
    uint32_t k;
    int cap = workers < 1 ? 1 : workers > PLX_MAX_THREADS ? PLX_MAX_THREADS : workers;
    memset(t->runs, 0, njobs);
    t->njobs = njobs;
    t->workers = workers;
    assert_int_equal(port_parallel_for(NULL, workers, njobs, count_job, t), 0);
    for (k = 0; k < njobs; k++) {
        assert_int_equal(t->runs[k], 1);
        assert_true(t->worker_of[k] >= 0 && t->worker_of[k] < cap);
        assert_true((uint32_t)t->worker_of[k] < njobs);
    }
}

static void test_every_job_once(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    static tally t;
    int c;
    (void)state;
    for (c = 0; c < 600; c++) {
        int workers = 1 + (c * 7) % 20; /* 1 .. 20: above PLX_MAX_THREADS too */
        uint32_t njobs = (uint32_t)((c * 131) % MAXJOBS);
        check_call(&t, workers, njobs);
    }
    check_call(&t, 0, 5);
    check_call(&t, -3, 5);
    assert_int_equal(port_parallel_for(NULL, 4, 3, NULL, &t), -1);
}

/* A job that asks for a parallel-for of its own (bad: jobs that did not
 * run once; asserted on the calling thread, not in the workers). */
typedef struct nest {
    tally inner[8];
    int bad[8];
} nest;

static void nest_job(void *arg, int worker, uint32_t k)
{
    nest *n = arg;
    tally *t = &n->inner[k];
    uint32_t j, njobs = 200 + k;
    (void)worker;
    memset(t->runs, 0, njobs);
    n->bad[k] = port_parallel_for(NULL, 3, njobs, count_job, t) != 0;
    for (j = 0; j < njobs; j++)
        n->bad[k] += t->runs[j] != 1 || t->worker_of[j] < 0 || t->worker_of[j] >= 3;
}

static void test_nested(void **state)
{
    static nest n;
    int r, k;
    (void)state;
    for (r = 0; r < 20; r++) {
        memset(n.bad, 0xff, sizeof n.bad);
        assert_int_equal(port_parallel_for(NULL, 4, 8, nest_job, &n), 0);
        for (k = 0; k < 8; k++)
            assert_int_equal(n.bad[k], 0);
    }
}

/* Two threads calling at once: one has the pool, the other its own threads. */
static void *caller(void *p)
{
    tally *t = p;
    int c;
    for (c = 0; c < 300; c++) {
        uint32_t k, njobs = 50 + (uint32_t)(c % 200);
        memset(t->runs, 0, njobs);
        if (port_parallel_for(NULL, 2 + c % 3, njobs, count_job, t) != 0)
            return "call failed";
        for (k = 0; k < njobs; k++)
            if (t->runs[k] != 1)
                return "a job did not run once";
    }
    return NULL;
}

static void test_two_callers(void **state)
{
    static tally a, b;
    pthread_t ta, tb;
    void *ra = NULL, *rb = NULL;
    (void)state;
    assert_int_equal(pthread_create(&ta, NULL, caller, &a), 0);
    assert_int_equal(pthread_create(&tb, NULL, caller, &b), 0);
    pthread_join(ta, &ra);
    pthread_join(tb, &rb);
    assert_null(ra);
    assert_null(rb);
}

/* After fork the child has none of the pool's threads: its calls still
 * run every job (and return, rather than wait for threads not there). */
static void test_after_fork(void **state)
{
    static tally t;
    pid_t pid;
    int status = 0;
    const char *why = getenv("PLX_NO_FORK_THREADS");
    (void)state;
    if (why && *why) { /* check-arm64: qemu-user aborts on this itself */
        printf("test_after_fork skipped: %s\n", why);
        skip();
    }
    check_call(&t, 4, 100); /* the pool has threads now */
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        uint32_t k;
        int c;
        alarm(60); /* a child waiting for threads that are not there dies */
        for (c = 0; c < 20; c++) {
            memset(t.runs, 0, 300);
            if (port_parallel_for(NULL, 4, 300, count_job, &t) != 0)
                _exit(2);
            for (k = 0; k < 300; k++)
                if (t.runs[k] != 1)
                    _exit(3);
        }
        _exit(0);
    }
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
    check_call(&t, 4, 100);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_job_once),
        cmocka_unit_test(test_nested),
        cmocka_unit_test(test_two_callers),
        cmocka_unit_test(test_after_fork),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
