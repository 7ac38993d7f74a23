/* PLX_ASSERT (src/base/plx_assert.h): in a debug build (PLX_DEBUG, as
 * `make asan` builds) a broken invariant stops the program with a trap; in a
 * release build the same check costs nothing and does nothing. The broken
 * invariant here is an arena mark released outside its block, run in a
 * child process. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "base/arena.h"
#include "base/plx_assert.h"

static unsigned char block[4096];

/* Runs a broken-invariant call in a child; returns its wait status. */
static int child_status(void (*fn)(void))
{
    int status = 0;
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        fn();
        _exit(0);
    }
    assert_int_equal(waitpid(pid, &status, 0), pid);
    return status;
}

static void release_outside_block(void)
{
    arena a;
    arena_mark m;
    arena_init(&a, block, sizeof block);
    m = arena_get_mark(&a);
    m.lo = a.cap + 1; /* a mark no arena_get_mark can give */
    arena_release(&a, &m);
}

static void odd_alignment(void)
{
    arena a;
    arena_init(&a, block, sizeof block);
    (void)arena_alloc(&a, PLX_PART_SCENE, 8, 24); /* not a power of two */
}

static void test_invariants_trap_in_debug_builds(void **state)
{
    int s1 = child_status(release_outside_block), s2 = child_status(odd_alignment);
    (void)state;
#ifdef PLX_DEBUG
    assert_true(WIFSIGNALED(s1) && WTERMSIG(s1) == SIGILL);
    assert_true(WIFSIGNALED(s2) && WTERMSIG(s2) == SIGILL);
#else
    assert_true(WIFEXITED(s1) && WEXITSTATUS(s1) == 0);
    assert_true(WIFEXITED(s2) && WEXITSTATUS(s2) == 0);
#endif
}

static void test_invariants_hold_in_normal_use(void **state)
{
    arena a;
    arena_mark m;
    unsigned char *p, *q;
    (void)state;
    arena_init(&a, block, sizeof block);
    m = arena_get_mark(&a);
    p = arena_alloc(&a, PLX_PART_SCENE, 100, 16);
    q = arena_scratch(&a, 200, 64);
    assert_non_null(p);
    assert_non_null(q);
    assert_int_equal((size_t)(q - a.base) % 64, 0);
    assert_null(arena_alloc(&a, PLX_PART_SCENE, sizeof block, 16)); /* refused, not asserted */
    arena_release(&a, &m);
    assert_int_equal(a.lo + a.hi, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_invariants_trap_in_debug_builds),
        cmocka_unit_test(test_invariants_hold_in_normal_use),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
