/* Shared by the polar tests: builds the diagrams of s while the k-th arena
 * request fails, for k = 1, 2, ... until the build succeeds (at most
 * max_k); every failure must be PLX_E_NOMEM with nothing kept (*pd NULL)
 * and the arena exactly as before (both ends, the scratch and polar
 * parts). Returns k, the number of the request at which the build first
 * succeeded; *pd is then the diagrams. Include after cmocka.h. */
#ifndef PLX_TEST_POLAR_FAULTS_H
#define PLX_TEST_POLAR_FAULTS_H

#include "base/arena.h"
#include "polar/polar.h"

static uint64_t polar_build_each_failure(arena *a, const scene *s, polar **pd, uint64_t max_k)
{
    arena_mark m0 = arena_get_mark(a);
    size_t scratch0 = a->used[PLX_PART_SCRATCH];
    uint64_t k;
    for (k = 1; k <= max_k; k++) {
        plx_status st;
        a->requests = 0;
        a->fail_at = k;
        st = polar_build(a, s, pd);
        a->fail_at = 0;
        if (st == PLX_OK)
            return k;
        assert_int_equal(st, PLX_E_NOMEM);
        assert_null(*pd);
        assert_int_equal(a->lo, m0.lo);
        assert_int_equal(a->hi, m0.hi);
        assert_int_equal(a->used[PLX_PART_SCRATCH], scratch0);
        assert_int_equal(a->used[PLX_PART_POLAR], m0.used[PLX_PART_POLAR]);
    }
    fail_msg("polar_build still failing after %u injected failures", (unsigned)max_k);
    return 0;
}

#endif
