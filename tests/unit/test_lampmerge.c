/* Duplicate lamps (src/scene/lampmerge.c): lamps at one spot with one
 * radius become one lamp with the summed intensity and the
 * intensity-weighted colour; the merged scene's direct light (scalar and
 * per channel) equals the unmerged sum, computed here independently from
 * single-lamp scenes; 100,000 lamps at one spot load as one lamp with one
 * warning line per spot; different radii stay apart. */
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
#include "fixture.h"

#define MEM (256u << 20)

static plx_engine *load(const char *json, void **mem, fixture_book *lb, plx_port *port)
{
    memset(port, 0, sizeof *port);
    memset(lb, 0, sizeof *lb);
    port->ctx = lb;
    port->log = fixture_book_log;
    return fixture_load_text(fixture_engine(MEM, 0, port, mem), json, "t");
}

static void done(plx_engine *e, void *mem)
{
    plx_engine_destroy(e);
    free(mem);
}

/* A scene of one building and the given lamp features (a JSON list body). */
static char *scene(const char *lamps)
{
    static const char head[] =
        "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
        "{\"type\":\"Feature\",\"properties\":{\"height\":10},\"geometry\":{\"type\":\"Polygon\","
        "\"coordinates\":[[[4,4],[8,4],[8,8],[4,8],[4,4]]]}}";
    char *s = malloc(strlen(head) + strlen(lamps) + 8);
    assert_non_null(s);
    sprintf(s, "%s%s%s]}", head, lamps[0] ? "," : "", lamps);
    return s;
}

static const char *lamp(char *buf, double x, double y, double z, double I, double R, const char *rgb)
{
    sprintf(buf, "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":%g,\"intensity\":%g,\"radius\":%g,"
                 "\"color\":[%s]},\"geometry\":{\"type\":\"Point\",\"coordinates\":[%g,%g]}}", z, I, R, rgb, x, y);
    return buf;
}

#define NP 6
static const double P[3 * NP] = { 0, 0, 0, 12, 0, 0, 0, 12, 0, 10, 10, 0, 6, 12, 0, -5, -5, 0 };
static const double N[3 * NP] = { 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1 };

/* E and rgb at the points for a scene text. */
static void light(const char *json, double *E, double *rgb, uint32_t *nlamps, uint32_t *merged, int *warnings)
{
    void *mem;
    fixture_book lb;
    plx_port port;
    plx_scene_info si;
    plx_engine *e = load(json, &mem, &lb, &port);
    plx_status st = plx_illuminance(e, NP, P, N, E, NULL, rgb);
    assert_true(st == PLX_OK || st == PLX_E_RANGE);
    assert_int_equal(plx_scene_info_get(e, &si), PLX_OK);
    *nlamps = si.lamps;
    *merged = si.merged_lamps;
    *warnings = lb.warnings;
    done(e, mem);
}

static void near(double a, double b)
{
    if (!(fabs(a - b) <= 1e-12 * fmax(1.0, fabs(b)) || (a != a && b != b)))
        fail_msg("%.17g != %.17g", a, b);
}

static void test_two_lamps_coloured(void **state)
{
    char a[400], b[400], both[900];
    char *s1, *s2, *s12;
    double E1[NP], E2[NP], E12[NP], c1[3 * NP], c2[3 * NP], c12[3 * NP];
    uint32_t n, m;
    int w, k;
    (void)state;
    lamp(a, 2, 1, 6, 1000, 30, "1,0,0");
    lamp(b, 2, 1, 6, 3000, 30, "0,0.5,1");
    sprintf(both, "%s,%s", a, b);
    s1 = scene(a);
    s2 = scene(b);
    s12 = scene(both);
    light(s1, E1, c1, &n, &m, &w);
    assert_int_equal(n, 1);
    light(s2, E2, c2, &n, &m, &w);
    light(s12, E12, c12, &n, &m, &w);
    assert_int_equal(n, 1);
    assert_int_equal(m, 1);
    assert_int_equal(w, 1);
    for (k = 0; k < NP; k++)
        near(E12[k], E1[k] + E2[k]);
    for (k = 0; k < 3 * NP; k++)
        near(c12[k], c1[k] + c2[k]);
    {   /* the merged lamp: intensities summed, colour weighted by intensity */
        void *mem;
        fixture_book lb;
        plx_port port;
        plx_lamp l;
        plx_engine *e = load(s12, &mem, &lb, &port);
        assert_int_equal(plx_lamp_get(e, 0, &l), PLX_OK);
        near(l.intensity, 4000);
        near(l.color[0], (float)0.25);
        near(l.color[1], (float)0.375);
        near(l.color[2], (float)0.75);
        assert_non_null(strstr(lb.last_warn, "2 lamps at one spot (2, 1, 6) merged into this one: 4000 cd"));
        done(e, mem);
    }
    free(s1);
    free(s2);
    free(s12);
}

static void test_different_radius_kept(void **state)
{
    char a[400], b[400], both[900];
    char *s;
    double E[NP], c[3 * NP];
    uint32_t n, m;
    int w;
    (void)state;
    lamp(a, 2, 1, 6, 1000, 30, "1,1,1");
    lamp(b, 2, 1, 6, 1000, 20, "1,1,1");
    sprintf(both, "%s,%s", a, b);
    s = scene(both);
    light(s, E, c, &n, &m, &w);
    assert_int_equal(n, 2);
    assert_int_equal(m, 0);
    assert_int_equal(w, 0);
    free(s);
    /* same x, y but another height: two lamps */
    lamp(b, 2, 1, 7, 1000, 30, "1,1,1");
    sprintf(both, "%s,%s", a, b);
    s = scene(both);
    light(s, E, c, &n, &m, &w);
    assert_int_equal(n, 2);
    free(s);
}

static void test_hundred_thousand_at_one_spot(void **state)
{
    enum { K = 100000 };
    char one[400], other[400];
    size_t len = strlen(lamp(one, 2, 1, 6, 10, 30, "1,0.62,0.28"));
    char *body = malloc((len + 1) * K + 8 * 400), *p = body, *s1, *sk;
    double E1[NP], Ek[NP], c1[3 * NP], ck[3 * NP];
    uint32_t n, m;
    int w, k;
    (void)state;
    assert_non_null(body);
    for (k = 0; k < K; k++) {
        memcpy(p, one, len);
        p += len;
        *p++ = ',';
    }
    /* and two more spots with 2 lamps each, and one lone lamp */
    lamp(other, -3, -3, 5, 10, 30, "1,1,1");
    p += sprintf(p, "%s,%s,", other, other);
    lamp(other, -3, 12, 5, 10, 30, "1,1,1");
    p += sprintf(p, "%s,%s,", other, other);
    lamp(other, 12, 12, 5, 10, 30, "1,1,1");
    p += sprintf(p, "%s", other);
    sk = scene(body);
    s1 = scene(one);
    light(s1, E1, c1, &n, &m, &w);
    light(sk, Ek, ck, &n, &m, &w);
    assert_int_equal(n, 4);
    assert_int_equal(m, K - 1 + 2);
    assert_int_equal(w, 3);
    /* the same light as a scene written with the merged lamps by hand */
    {
        char only[2000];
        double Eo[NP], co[3 * NP];
        p = only;
        p += sprintf(p, "%s,", lamp(other, 2, 1, 6, 10.0 * K, 30, "1,0.62,0.28"));
        p += sprintf(p, "%s,", lamp(other, -3, -3, 5, 20, 30, "1,1,1"));
        p += sprintf(p, "%s,", lamp(other, -3, 12, 5, 20, 30, "1,1,1"));
        sprintf(p, "%s", lamp(other, 12, 12, 5, 10, 30, "1,1,1"));
        free(s1);
        s1 = scene(only);
        light(s1, Eo, co, &n, &m, &w);
        assert_int_equal(n, 4);
        assert_int_equal(m, 0);
        for (k = 0; k < NP; k++)
            if (fabs(Ek[k] - Eo[k]) > 1e-9 * fmax(1.0, Eo[k]) && !(Ek[k] != Ek[k] && Eo[k] != Eo[k]))
                fail_msg("point %d: %.17g merged vs %.17g written merged", k, Ek[k], Eo[k]);
        for (k = 0; k < 3 * NP; k++)
            if (fabs(ck[k] - co[k]) > 1e-6 * fmax(1.0, co[k]) && !(ck[k] != ck[k] && co[k] != co[k]))
                fail_msg("channel %d: %.17g merged vs %.17g written merged", k, ck[k], co[k]);
        /* and at least K times one lamp's light where the lamp shines */
        assert_true(E1[0] > 0);
        assert_true(Eo[0] >= K * E1[0] * (1 - 1e-12));
    }
    free(s1);
    free(sk);
    free(body);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_lamps_coloured),
        cmocka_unit_test(test_different_radius_kept),
        cmocka_unit_test(test_hundred_thousand_at_one_spot),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
