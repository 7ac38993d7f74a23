/* plx_assert_fail: where a broken invariant of a debug build stops. */
#include "base/plx_assert.h"

#ifdef PLX_DEBUG
/* Kept out of line so a backtrace shows cond, file and line. */
void plx_assert_fail(const char *cond, const char *file, int line)
{
    volatile const char *c = cond, *f = file;
    volatile int l = line;
    (void)c;
    (void)f;
    (void)l;
#if defined(__GNUC__) || defined(__clang__)
    __builtin_trap();
#else
    for (;;) {
    }
#endif
}
#else
typedef int plx_assert_unused; /* ISO C wants something in every file */
#endif
