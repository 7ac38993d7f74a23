/* The tests plain `make check` leaves out so that it stays within a minute
 * on two cores (PLX_TEST_SKIP_SLOW=1, which only the Makefile's check
 * target sets): check-full, asan and valgrind run them. */
#ifndef PLX_TEST_SLOW_H
#define PLX_TEST_SLOW_H

#include <stdlib.h>

static inline int slow_test_skipped(void)
{
    const char *s = getenv("PLX_TEST_SKIP_SLOW");
    return s && *s && *s != '0';
}

#endif
