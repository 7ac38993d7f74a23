/* The tests plain `make check` leaves out so that it stays within a minute
 * on two cores (PLX_TEST_SKIP_SLOW set and not empty, which only the
 * Makefile's check target does): check-full, asan, valgrind and
 * check-arm64 run them. */
#ifndef PLX_TEST_SLOW_H
#define PLX_TEST_SLOW_H

#include <stdlib.h>

static inline int slow_test_skipped(void)
{
    const char *s = getenv("PLX_TEST_SKIP_SLOW");
    return s && *s; /* as the shell's test -n in tests/run_tests.sh and tests/cli/run.sh */
}

#endif
