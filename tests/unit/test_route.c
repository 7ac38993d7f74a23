/* Route scoring: hand-computed values (one lamp over a straight street; a
 * building's shadow across it), consistency with plx_illuminance at the same
 * points, and the EN 13201 P-class boundaries. */
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

#define MEM (64u << 20)

static plx_engine *load(const char *json, void **mem)
{
    return fixture_text(json, MEM, 0, mem);
}

static double window(double x)
{
    double t = 1.0 - x * x * x * x;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return t * t;
}

/* E at ground point (x, y) from a lamp at (lx, ly, lz), I cd, reach R, unblocked. */
static double lamp_E(double x, double y, double lx, double ly, double lz, double I, double R)
{
    double dx = lx - x, dy = ly - y, d = sqrt(dx * dx + dy * dy + lz * lz);
    return I * lz / (d * d * d) * window(d / R);
}

static void test_one_lamp_straight_street(void **state)
{
    void *mem;
    plx_engine *e = load("{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                         "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":6,\"intensity\":1000,\"radius\":30},"
                         "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,0]}}]}", &mem);
    double xy[4] = { -10, 0, 10, 0 }, sum = 0, mn = 1e9, mx = 0, dark = 0;
    plx_route_stats tot, seg[1];
    int i;
    (void)state;
    for (i = 0; i <= 20; i++) {
        double E = lamp_E(-10 + i, 0, 0, 0, 6, 1000, 30), w = (i == 0 || i == 20) ? 0.5 : 1.0;
        sum += w * E;
        mn = fmin(mn, E);
        mx = fmax(mx, E);
        if (E < 5.0)
            dark += w;
    }
    assert_int_equal(plx_route_score(e, xy, 2, 1.0, 5.0, &tot, seg), PLX_OK);
    assert_true(fabs(tot.length - 20.0) < 1e-12);
    assert_int_equal(tot.samples, 21);
    assert_true(fabs(tot.mean - sum / 20.0) < 1e-9 * tot.mean);
    assert_true(fabs(tot.min - mn) < 1e-9 * mn && fabs(tot.max - mx) < 1e-9 * mx);
    /* directly below: I z / z^3 W(z/R) = 1000/36 (1 - 0.2^4)^2 */
    assert_true(fabs(tot.max - 1000.0 / 36.0 * pow(1 - pow(0.2, 4), 2)) < 1e-9);
    assert_true(fabs(tot.uniformity - mn / (sum / 20.0)) < 1e-9);
    assert_true(fabs(tot.dark_share - dark / 20.0) < 1e-12);
    assert_true(fabs(seg[0].mean - tot.mean) < 1e-12);
    assert_int_equal(tot.p_class, plx_p_class(sum / 20.0, mn));
    plx_engine_destroy(e);
    free(mem);
}

/* A repeated vertex: the segment of no length is its one point, scored
 * with that point's lux against the formula (it read 0 lx, a false dark
 * segment), and changes nothing of the whole line's; a line of one
 * repeated point is that point too. */
static void test_segment_of_no_length(void **state)
{
    void *mem;
    plx_engine *e = load("{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                         "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":6,\"intensity\":1000,\"radius\":30},"
                         "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,0]}}]}", &mem);
    double xy[6] = { -10, 0, -10, 0, 10, 0 }, plain[4] = { -10, 0, 10, 0 }, far[4] = { 100, 0, 100, 0 };
    double E = lamp_E(-10, 0, 0, 0, 6, 1000, 30);
    plx_route_stats tot, ref, seg[2], one;
    (void)state;
    assert_int_equal(plx_route_score(e, xy, 3, 1.0, 5.0, &tot, seg), PLX_OK);
    assert_true(seg[0].length == 0.0 && seg[0].samples == 2);
    assert_true(fabs(seg[0].mean - E) < 1e-12 * E && seg[0].min == seg[0].mean && seg[0].max == seg[0].mean);
    assert_true(seg[0].uniformity == 1.0 && seg[0].dark_share == (E < 5.0 ? 1.0 : 0.0));
    assert_int_equal(seg[0].p_class, plx_p_class(E, E));
    assert_int_equal(plx_route_score(e, plain, 2, 1.0, 5.0, &ref, NULL), PLX_OK);
    assert_true(tot.length == ref.length && tot.mean == ref.mean && tot.min == ref.min && tot.max == ref.max);
    assert_true(tot.dark_share == ref.dark_share && tot.p_class == ref.p_class);
    assert_int_equal(plx_route_score(e, xy, 2, 1.0, 5.0, &one, NULL), PLX_OK);
    assert_true(one.length == 0.0 && fabs(one.mean - E) < 1e-12 * E);
    assert_int_equal(plx_route_score(e, far, 2, 1.0, 5.0, &one, NULL), PLX_OK); /* out of reach: dark */
    assert_true(one.mean == 0.0 && one.dark_share == 1.0 && one.p_class == 0);
    { /* the facing meters of the repeated vertex look along the next segment (+x), not east by default: the
       * line is walked west to east here, so build it east to west to tell the two apart */
        double back[6] = { 10, 0, 10, 0, -10, 0 }, fac[8], tot4[4], P[3] = { 10, 0, 1.5 }, U[2], m[4];
        assert_int_equal(plx_route_facial(e, back, 3, 1.0, 1.5, fac, tot4), PLX_OK);
        U[0] = -1.0;
        U[1] = 0.0;
        assert_int_equal(plx_meter(e, 1, P, U, m), PLX_OK);
        assert_true(fac[0] == m[PLX_METER_V] && fac[2] == m[PLX_METER_SC]);
        U[0] = 1.0;
        assert_int_equal(plx_meter(e, 1, P, U, m), PLX_OK);
        assert_true(fac[1] == m[PLX_METER_V] && fac[3] == m[PLX_METER_SC]);
    }
    plx_engine_destroy(e);
    free(mem);
}

static void test_shadow_across_street(void **state)
{
    /* lamp at (0, 5, 6); a 20 m tall box x in [-2, 2], y in [2, 3]; the street
     * y = 0 from x = -10 to 10. The segment from the lamp to (x, 0) meets the
     * box's top side y = 3 at x' = 0.4 x, so |x| < 5 is in the shadow and
     * |x| = 5 grazes the corner (lit). */
    void *mem;
    plx_engine *e = load("{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                         "{\"type\":\"Feature\",\"properties\":{\"height\":20},\"geometry\":{\"type\":\"Polygon\","
                         "\"coordinates\":[[[-2,2],[2,2],[2,3],[-2,3],[-2,2]]]}},"
                         "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":6,\"intensity\":1000,\"radius\":30},"
                         "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,5]}}]}", &mem);
    double xy[4] = { -10, 0, 10, 0 }, sum = 0, dark = 0;
    plx_route_stats tot;
    int i;
    (void)state;
    for (i = 0; i <= 20; i++) {
        double x = -10 + i, w = (i == 0 || i == 20) ? 0.5 : 1.0;
        double E = fabs(x) < 5 ? 0.0 : lamp_E(x, 0, 0, 5, 6, 1000, 30);
        sum += w * E;
        if (E < 1.0)
            dark += w;
    }
    assert_int_equal(plx_route_score(e, xy, 2, 1.0, 1.0, &tot, NULL), PLX_OK);
    assert_true(tot.min == 0.0);
    assert_true(fabs(tot.mean - sum / 20.0) < 1e-9 * tot.mean);
    assert_true(fabs(tot.dark_share - dark / 20.0) < 1e-12);
    assert_true(fabs(dark - 9.0) < 1e-12); /* x = -4 .. 4 */
    assert_int_equal(tot.p_class, 0);
    assert_true(tot.uniformity == 0.0);
    plx_engine_destroy(e);
    free(mem);
}

static void test_route_through_building(void **state)
{
    void *mem;
    plx_engine *e = load("{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                         "{\"type\":\"Feature\",\"properties\":{\"height\":10},\"geometry\":{\"type\":\"Polygon\","
                         "\"coordinates\":[[[-2.5,-5],[2.5,-5],[2.5,5],[-2.5,5],[-2.5,-5]]]}},"
                         "{\"type\":\"Feature\",\"properties\":{\"lamp\":true},"
                         "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,10]}}]}", &mem);
    double xy[4] = { -10, 0, 10, 0 };
    plx_route_stats tot;
    (void)state;
    assert_int_equal(plx_route_score(e, xy, 2, 1.0, 1.0, &tot, NULL), PLX_OK);
    /* samples x = -2 .. 2 are inside the footprint: 5 m not scored */
    assert_true(fabs(tot.blocked_length - 5.0) < 1e-12);
    assert_true(fabs(tot.length - 15.0) < 1e-12);
    assert_int_equal(tot.samples, 16);
    plx_engine_destroy(e);
    free(mem);
}

static void test_consistent_with_illuminance(void **state)
{
    void *mem = malloc(MEM);
    plx_engine *e;
    plx_config cfg;
    double xy[6] = { -200, -300, 100, -250, 150, 100 }, P[3 * 400], N[3 * 400], E[400], Ei[400];
    plx_route_stats tot, seg[2];
    int s;
    (void)state;
    plx_config_default(&cfg);
    assert_int_equal(plx_engine_create(mem, MEM, &cfg, &e), PLX_OK);
    {
        FILE *f = fopen("fixtures/helsinki-centre.geojson", "rb");
        static char text[400000];
        size_t len = fread(text, 1, sizeof text, f);
        fclose(f);
        assert_int_equal(plx_load_geojson(e, text, len, "h"), PLX_OK);
    }
    assert_int_equal(plx_route_score(e, xy, 3, 2.0, 1.0, &tot, seg), PLX_OK);
    for (s = 0; s < 2; s++) {
        const double *a = xy + 2 * s, *b = a + 2;
        double len = hypot(b[0] - a[0], b[1] - a[1]), w, sum = 0, L = 0, mn = INFINITY;
        int k = (int)ceil(len / 2.0), i;
        assert_true(k + 1 <= 400);
        for (i = 0; i <= k; i++) {
            P[3 * i] = a[0] + (b[0] - a[0]) * i / k;
            P[3 * i + 1] = a[1] + (b[1] - a[1]) * i / k;
            P[3 * i + 2] = 0;
            N[3 * i] = N[3 * i + 1] = 0;
            N[3 * i + 2] = 1;
        }
        plx_illuminance(e, (size_t)k + 1, P, N, E, Ei, NULL);
        w = len / k;
        for (i = 0; i <= k; i++) {
            double wi = (i == 0 || i == k) ? w / 2 : w;
            if (E[i] != E[i])
                continue;
            sum += wi * (E[i] + Ei[i]);
            L += wi;
            mn = fmin(mn, E[i] + Ei[i]);
        }
        assert_true(fabs(seg[s].length - L) < 1e-9);
        assert_true(fabs(seg[s].mean - sum / L) <= 1e-12 * fmax(1.0, sum / L));
        assert_true(seg[s].min == mn);
    }
    plx_engine_destroy(e);
    free(mem);
}

static void test_p_class_boundaries(void **state)
{
    (void)state;
    assert_int_equal(plx_p_class(15.0, 3.0), 1);
    assert_int_equal(plx_p_class(14.99, 3.0), 2);
    assert_int_equal(plx_p_class(15.0, 2.99), 2);
    assert_int_equal(plx_p_class(10.0, 2.0), 2);
    assert_int_equal(plx_p_class(7.5, 1.5), 3);
    assert_int_equal(plx_p_class(7.49, 1.5), 4);
    assert_int_equal(plx_p_class(5.0, 1.0), 4);
    assert_int_equal(plx_p_class(3.0, 0.6), 5);
    assert_int_equal(plx_p_class(2.0, 0.4), 6);
    assert_int_equal(plx_p_class(100.0, 0.39), 0);
    assert_int_equal(plx_p_class(1.99, 1.0), 0);
}

static void test_errors(void **state)
{
    void *mem;
    plx_engine *e = load("{\"type\":\"FeatureCollection\",\"features\":[]}", &mem);
    double xy[4] = { 0, 0, 1, 0 };
    plx_route_stats t;
    (void)state;
    assert_int_equal(plx_route_score(e, xy, 1, 1.0, 1.0, &t, NULL), PLX_E_INVALID);
    assert_int_equal(plx_route_score(e, xy, 2, 0.0, 1.0, &t, NULL), PLX_E_INVALID);
    xy[2] = NAN;
    assert_int_equal(plx_route_score(e, xy, 2, 1.0, 1.0, &t, NULL), PLX_E_INVALID);
    plx_engine_destroy(e);
    free(mem);
}

/* Every memory request of a first route score (lamp light set-up, lit
 * regions, sample scratch) and of a first illuminance call fails in turn:
 * PLX_E_NOMEM, the arena back where it was, the engine still usable. */
static void test_fault_injection(void **state)
{
    static const char scene[] = "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                                "{\"type\":\"Feature\",\"properties\":{\"height\":20},\"geometry\":{\"type\":\"Polygon\","
                                "\"coordinates\":[[[-2,2],[2,2],[2,3],[-2,3],[-2,2]]]}},"
                                "{\"type\":\"Feature\",\"properties\":{\"lamp\":true},"
                                "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,5]}}]}";
    double xy[4] = { -10, 0, 10, 0 }, P[3] = { 0, 8, 0 }, N[3] = { 0, 0, 1 }, E, Ei, want;
    int which;
    (void)state;
    for (which = 0; which < 2; which++) {
        void *mem;
        plx_engine *e = load(scene, &mem);
        plx_memory_report before, after;
        plx_route_stats t;
        plx_status st = PLX_E_NOMEM;
        uint64_t k;
        plx_memory_get(e, &before);
        for (k = 1; st == PLX_E_NOMEM; k++) {
            plx_debug_fail_alloc(e, k);
            st = which == 0 ? plx_route_score(e, xy, 2, 1.0, 1.0, &t, NULL)
                            : plx_illuminance(e, 1, P, N, &E, &Ei, NULL);
            plx_memory_get(e, &after);
            if (st == PLX_E_NOMEM)
                assert_int_equal(after.used_total, before.used_total);
            assert_true(k < 100000);
        }
        plx_debug_fail_alloc(e, 0);
        assert_int_equal(st, PLX_OK);
        assert_true(k > 2);
        if (which == 1) {
            want = lamp_E(0, 8, 0, 5, 6, 1000, 30);
            assert_true(fabs(E - want) < 1e-9 * want);
        }
        plx_engine_destroy(e);
        free(mem);
    }
}

/* A first route score builds the lamp light and keeps it: the engine holds
 * the same bytes of lit-region memory as after a first plx_illuminance (a
 * build inside the per-segment arena mark was released with the samples,
 * leaving e->lt pointing at memory the renderer then reused). */
static void test_light_kept_after_first_score(void **state)
{
    static const char scene[] = "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                                "{\"type\":\"Feature\",\"properties\":{\"lamp\":true},"
                                "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,5]}}]}";
    double xy[4] = { -10, 0, 10, 0 }, P[3] = { 0, 8, 0 }, N[3] = { 0, 0, 1 }, E, Ei;
    void *mem1, *mem2;
    plx_engine *e1 = load(scene, &mem1), *e2 = load(scene, &mem2);
    plx_memory_report r1, r2, again;
    plx_route_stats t;
    (void)state;
    assert_int_equal(plx_route_score(e1, xy, 2, 1.0, 1.0, &t, NULL), PLX_OK);
    assert_int_equal(plx_illuminance(e2, 1, P, N, &E, &Ei, NULL), PLX_OK);
    plx_memory_get(e1, &r1);
    plx_memory_get(e2, &r2);
    assert_true(r2.used[PLX_PART_LIT] > 0);
    assert_int_equal(r1.used[PLX_PART_LIT], r2.used[PLX_PART_LIT]);
    /* a second score builds nothing more */
    assert_int_equal(plx_route_score(e1, xy, 2, 1.0, 1.0, &t, NULL), PLX_OK);
    plx_memory_get(e1, &again);
    assert_int_equal(again.used_total, r1.used_total);
    plx_engine_destroy(e1);
    plx_engine_destroy(e2);
    free(mem1);
    free(mem2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_lamp_straight_street),
        cmocka_unit_test(test_shadow_across_street),
        cmocka_unit_test(test_segment_of_no_length),
        cmocka_unit_test(test_route_through_building),
        cmocka_unit_test(test_consistent_with_illuminance),
        cmocka_unit_test(test_p_class_boundaries),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_fault_injection),
        cmocka_unit_test(test_light_kept_after_first_score),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
