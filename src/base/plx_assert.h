/* PLX_ASSERT: the core's invariants, checked in debug builds (SQLite's
 * habit). Compiled out unless PLX_DEBUG is defined (`make asan` defines it,
 * and the fuzz builds); release builds carry no check and no cost.
 *
 * The core has no stdio and no <assert.h>: a broken invariant calls
 * plx_assert_fail, which traps (the compiler's trap instruction; SIGILL on
 * POSIX, a fault handler on a board). The condition, file and line are its
 * arguments, so a debugger's backtrace shows them; the sanitizers print the
 * stack. An assertion states what must hold whatever the input: bad input is
 * an error status, never an assertion. */
#ifndef PLX_ASSERT_H
#define PLX_ASSERT_H

#ifdef PLX_DEBUG
void plx_assert_fail(const char *cond, const char *file, int line);
#define PLX_ASSERT(c) ((c) ? (void)0 : plx_assert_fail(#c, __FILE__, __LINE__))
#else
#define PLX_ASSERT(c) ((void)0)
#endif

#endif
