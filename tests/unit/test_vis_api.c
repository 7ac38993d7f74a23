/* The public visibility API (plx_visibility_get) against the brute-force
 * reference tests/ref/ref_vis on the fixtures: area to 1e-9 relative, the
 * vertex count under the reference's merging rule, identical visible sets,
 * fields of view, and the errors for points that are not free. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "fixture.h"
#include "base/engine.h"
#include "ref_vis.h"
#include "slow.h"

#define MEM (256u << 20)

static plx_engine *open_scene(const char *path, void **mem)
{
    return fixture_file(path, MEM, mem);
}

static uint64_t rng_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double rng_unit(uint64_t *s)
{
    return (rng_next(s) >> 11) * (1.0 / 9007199254740992.0);
}

static void compare_fixture(const char *path, int npoints, uint64_t seed)
{
    void *mem;
    plx_engine *e = open_scene(path, &mem);
    const double *b = e->sc->bounds;
    int done = 0, tries = 0, ranged = 0;
    while (done < npoints && tries < 100 * npoints) {
        double x = b[0] + (b[2] - b[0]) * rng_unit(&seed);
        double y = b[1] + (b[3] - b[1]) * rng_unit(&seed);
        int full = rng_unit(&seed) < 0.5;
        double dir = 360.0 * rng_unit(&seed), fov = full ? 360.0 : 10.0 + 170.0 * rng_unit(&seed);
        ref_vis_result r;
        plx_visibility v;
        int rr;
        plx_status st;
        tries++;
        memset(&r, 0, sizeof r);
        if (full)
            rr = ref_vis(e->sc, x, y, &r);
        else
            rr = ref_vis_range(e->sc, x, y, (dir - fov / 2) * 0.017453292519943295, (dir + fov / 2) * 0.017453292519943295, &r);
        st = plx_visibility_get(e, x, y, dir, fov, &v);
        if (rr != 0) {
            assert_int_equal(st, PLX_E_RANGE);
            ref_vis_free(&r);
            continue;
        }
        assert_int_equal(st, PLX_OK);
        if (fabs(v.area - r.area) > 1e-9 * fmax(r.area, 1.0) || v.nverts != r.nverts ||
            v.nvisible != r.nvisible ||
            (v.nvisible && memcmp(v.visible, r.visible, v.nvisible * sizeof *v.visible) != 0))
            fail_msg("%s at (%.17g, %.17g) dir %g fov %g: area %.17g vs %.17g, nverts %u vs %u, visible %u vs %u",
                     path, x, y, dir, fov, v.area, r.area, v.nverts, r.nverts, v.nvisible, r.nvisible);
        ranged += !full;
        ref_vis_free(&r);
        done++;
    }
    assert_int_equal(done, npoints);
    assert_true(ranged > 0);
    plx_engine_destroy(e);
    free(mem);
}

static void test_tiny(void **state)
{
    (void)state;
    compare_fixture("fixtures/tiny.geojson", 300, 1);
}

static void test_grid(void **state)
{
    (void)state;
    compare_fixture("fixtures/grid-4x4.geojson", 150, 2);
}

static void test_eixample(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    (void)state;
    compare_fixture("fixtures/eixample-4x4.geojson", 40, 3);
}

static void test_oldtown(void **state)
{
    (void)state;
    compare_fixture("fixtures/oldtown-8x8.geojson", 60, 4);
}

static void test_courtyard_and_errors(void **state)
{
    void *mem;
    plx_engine *e = open_scene("fixtures/tiny.geojson", &mem);
    plx_visibility v;
    (void)state;
    /* from the courtyard of C only the 10 x 10 courtyard is visible */
    assert_int_equal(plx_visibility_get(e, 50, 10, 0, 360, &v), PLX_OK);
    assert_true(fabs(v.area - 100.0) < 1e-9);
    assert_int_equal(v.nverts, 4);
    assert_int_equal(v.nvisible, 1);
    assert_int_equal(v.visible[0], 2);
    /* a quarter view of it: a right triangle and a square's corner */
    assert_int_equal(plx_visibility_get(e, 50, 10, 45, 90, &v), PLX_OK);
    assert_true(fabs(v.area - 25.0) < 1e-9);
    assert_int_equal(plx_visibility_get(e, 5, 5, 0, 360, &v), PLX_E_RANGE);
    assert_string_equal(plx_last_error(e), "point (5, 5) is inside building 0 (A): not a free viewpoint");
    assert_int_equal(plx_visibility_get(e, 10, 5, 0, 360, &v), PLX_E_RANGE);
    /* the wall shared by A and B is inside their union */
    assert_string_equal(plx_last_error(e), "point (10, 5) lies on a wall shared by two buildings: not a free viewpoint");
    assert_int_equal(plx_visibility_get(e, 0, 5, 0, 360, &v), PLX_E_RANGE);
    assert_string_equal(plx_last_error(e), "point (0, 5) lies on a wall: not a free viewpoint");
    assert_int_equal(plx_visibility_get(e, 500, 5, 0, 360, &v), PLX_E_RANGE);
    assert_string_equal(plx_last_error(e), "point (500, 5) is outside Bounds [-50, -50] - [110, 70]: not a free viewpoint");
    assert_int_equal(plx_visibility_get(e, NAN, 5, 0, 360, &v), PLX_E_INVALID);
    assert_int_equal(plx_visibility_get(e, 1, 5, 0, 0, &v), PLX_E_INVALID);
    /* under the raised canopy D: free, and D is no occluder */
    assert_int_equal(plx_visibility_get(e, 27, 2, 0, 360, &v), PLX_OK);
    plx_engine_destroy(e);
    free(mem);
}

static void test_fault_injection(void **state)
{
    void *mem;
    plx_engine *e = open_scene("fixtures/eixample-4x4.geojson", &mem);
    plx_memory_report before, after;
    plx_visibility v;
    plx_status st = PLX_E_NOMEM;
    uint64_t k;
    (void)state;
    /* building the diagrams: every failure gives everything back */
    plx_memory_get(e, &before);
    for (k = 1; st == PLX_E_NOMEM; k++) {
        plx_debug_fail_alloc(e, k);
        st = plx_polar_build(e);
        if (st == PLX_E_NOMEM) {
            plx_memory_get(e, &after);
            assert_int_equal(after.used_total, before.used_total);
            assert_non_null(strstr(plx_last_error(e), "out of memory while"));
        }
    }
    assert_int_equal(st, PLX_OK);
    assert_true(k > 10);
    /* a query on built diagrams: its scratch memory comes back too */
    plx_memory_get(e, &before);
    st = PLX_E_NOMEM;
    for (k = 1; st == PLX_E_NOMEM; k++) {
        plx_debug_fail_alloc(e, k);
        st = plx_visibility_get(e, 0.5, 0.5, 0, 360, &v);
        if (st == PLX_E_NOMEM) {
            plx_memory_get(e, &after);
            assert_int_equal(after.used_total, before.used_total);
        }
    }
    plx_debug_fail_alloc(e, 0);
    assert_true(st == PLX_OK || st == PLX_E_RANGE);
    plx_engine_destroy(e);
    free(mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tiny),
        cmocka_unit_test(test_grid),
        cmocka_unit_test(test_eixample),
        cmocka_unit_test(test_oldtown),
        cmocka_unit_test(test_courtyard_and_errors),
        cmocka_unit_test(test_fault_injection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
