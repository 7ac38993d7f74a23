/* Street networks (src/cli/network.c): lines joined at shared vertices,
 * edges scored as plx_route_score scores lines, and Dijkstra's routes
 * against hand-computed answers and an independent Bellman-Ford. And
 * twin_for (src/cli/twin_engines.c), which shares the edges' scoring out
 * between threads: every item done once, a failure's status and engine
 * with every chunk before it done, PLX_E_RANGE kept to the end, and the
 * default's memory rule. */
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
#include "cli/network.h"
#include "cli/net_scores.h"
#include <cjson/cJSON.h>

#define MEM ((size_t)256 << 20)

static plx_engine *load_file(const char *path, void **mem)
{
    return fixture_file(path, MEM, mem);
}

static plx_engine *load_text(const char *json, void **mem)
{
    return fixture_text(json, MEM, 0, mem);
}

static void open_net(plx_engine *e, const char *path, network *net)
{
    route_set rs;
    plx_engine *failed;
    char err[512];
    if (route_read(path, e, &rs, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_int_equal(net_build(net, &rs, err, sizeof err), 0);
    assert_int_equal(net_score(net, e, NULL, 1.0, 1.0, 1.5, 0, &failed), PLX_OK);
}

static void snap(const network *net, double x, double y, net_snap *s)
{
    assert_int_equal(net_snap_point(net, x, y, s), 0);
}

/* fixtures/net-detour: a dark straight street (0,0)-(200,0) and a detour
 * over y = 50 under a row of lamps. The detour wins exactly when the
 * weight passes (L_detour - L_short) / (D_short - D_detour). */
static void test_detour_only_when_weight_says_so(void **state)
{
    void *mem;
    plx_engine *e = load_file("fixtures/net-detour.geojson", &mem);
    network net;
    net_snap a, b;
    net_route r0, rbig, rlo, rhi;
    char err[256];
    double wstar;
    (void)state;
    open_net(e, "fixtures/net-detour-streets.geojson", &net);
    assert_int_equal(net.nedges, 6); /* shortcut and detour cut at the spur's ends, spur, island */
    assert_int_equal(net.nnodes, 8 - 2); /* (0,0) (100,0) (200,0) (100,50), island ends */
    snap(&net, 0, 0, &a);
    snap(&net, 200, 0, &b);
    assert_int_equal(net_route_find(&net, e, &a, &b, 0.0, &r0, err, sizeof err), 0);
    assert_true(fabs(r0.length - 200.0) < 1e-9);
    assert_true(fabs(r0.dark - 200.0) < 1e-6); /* no lamp reaches y = 0 (all 50 m away, R 30) */
    assert_true(fabs(r0.cost - 200.0) < 1e-9);
    assert_int_equal(net_route_find(&net, e, &a, &b, 100.0, &rbig, err, sizeof err), 0);
    assert_true(fabs(rbig.length - 300.0) < 1e-9);
    assert_true(rbig.dark > 10 && rbig.dark < 100); /* the two legs down to y = 0 */
    assert_true(fabs(rbig.cost - (rbig.length + 100.0 * rbig.dark)) < 1e-6);
    wstar = (rbig.length - r0.length) / (r0.dark - rbig.dark);
    assert_int_equal(net_route_find(&net, e, &a, &b, 0.99 * wstar, &rlo, err, sizeof err), 0);
    assert_int_equal(net_route_find(&net, e, &a, &b, 1.01 * wstar, &rhi, err, sizeof err), 0);
    assert_true(fabs(rlo.length - 200.0) < 1e-9);
    assert_true(fabs(rhi.length - 300.0) < 1e-9);
    assert_true(rhi.min == 0.0 && rhi.integral > 0);
    net_route_free(&r0);
    net_route_free(&rbig);
    net_route_free(&rlo);
    net_route_free(&rhi);
    net_free(&net);
    plx_engine_destroy(e);
    free(mem);
}

/* Each line's edges add up to the line scored whole by plx_route_score
 * (what 'polarlux route --path' prints), on the real Helsinki network. */
static void test_edges_equal_route_scores(void **state)
{
    void *mem;
    plx_engine *e = load_file("fixtures/helsinki-centre.geojson", &mem);
    network net;
    size_t i;
    uint32_t k, checked = 0, cut = 0, facial = 0;
    (void)state;
    open_net(e, "fixtures/helsinki-streets.geojson", &net);
    assert_true(net.nedges > net.lines.n);
    for (i = 0; i < net.lines.n; i++) {
        const route_line *l = &net.lines.lines[i];
        plx_route_stats whole;
        double len = 0, dark = 0, integral = 0, blocked = 0, mn = INFINITY, geo = 0, fac[4], efac[4];
        uint32_t pieces = 0;
        int c;
        if (getenv("PLX_TEST_QUICK") && i % 4)
            continue;
        assert_int_equal(plx_route_score(e, l->xy, l->n, 1.0, 1.0, &whole, NULL), PLX_OK);
        assert_int_equal(plx_route_facial(e, l->xy, l->n, 1.0, 1.5, NULL, fac), PLX_OK);
        for (c = 0; c < 4; c++)
            efac[c] = NAN;
        for (k = 0; k < net.nedges; k++) {
            const net_edge *ed = &net.edges[k];
            if (ed->line != i)
                continue;
            pieces++;
            len += ed->s.length;
            dark += ed->dark;
            integral += ed->s.mean * ed->s.length;
            blocked += ed->s.blocked_length;
            geo += ed->length;
            if (ed->s.length > 0)
                mn = fmin(mn, ed->s.min);
            for (c = 0; c < 4; c++) /* fw, bw along the line's own order in both */
                efac[c] = fmin(efac[c], ed->fac[c]);
        }
        for (c = 0; c < 4; c++) /* the same samples: exactly equal (or both without a meter) */
            assert_true(fac[c] == efac[c] || (fac[c] != fac[c] && efac[c] != efac[c]));
        if (fac[2] == fac[2])
            facial++;
        assert_true(pieces >= 1);
        cut += pieces > 1;
        assert_true(fabs(len - whole.length) <= 1e-9 * (1 + whole.length));
        assert_true(fabs(blocked - whole.blocked_length) <= 1e-9 * (1 + whole.length));
        assert_true(fabs(dark - whole.dark_share * whole.length) <= 1e-9 * (1 + whole.length));
        assert_true(fabs(integral - whole.mean * whole.length) <= 1e-9 * (1 + whole.mean * whole.length));
        if (whole.length > 0)
            assert_true(mn == whole.min);
        assert_true(fabs(geo - (whole.length + whole.blocked_length)) <= 1e-6 * (1 + geo));
        checked++;
    }
    assert_true(checked > 100);
    assert_true(facial > 100);
    assert_true(cut > 100); /* real ways meet in the middle of other ways */
    net_free(&net);
    plx_engine_destroy(e);
    free(mem);
}

/* A route's sums equal plx_route_score over its own polyline, also when it
 * starts and ends inside edges. */
static void test_route_equals_its_polyline(void **state)
{
    void *mem;
    plx_engine *e = load_file("fixtures/net-detour.geojson", &mem);
    network net;
    net_snap a, b;
    net_route r;
    plx_route_stats s;
    char err[256];
    double fac[4];
    static const double ends[4][4] = { { 50, 0, 150, 0 }, { 20, 1, 80, -1 }, { 80, 0, 20, 0 }, { 30, 45, 170, 5 } };
    static const double expect_len[4] = { 100, 60, 60, -1 };
    int i;
    (void)state;
    open_net(e, "fixtures/net-detour-streets.geojson", &net);
    for (i = 0; i < 4; i++) {
        snap(&net, ends[i][0], ends[i][1], &a);
        snap(&net, ends[i][2], ends[i][3], &b);
        assert_int_equal(net_route_find(&net, e, &a, &b, i == 3 ? 50.0 : 0.0, &r, err, sizeof err), 0);
        if (expect_len[i] > 0)
            assert_true(fabs(r.length - expect_len[i]) < 1e-9);
        assert_true(r.xy[0] == a.x && r.xy[1] == a.y);
        assert_true(r.xy[2 * r.n - 2] == b.x && r.xy[2 * r.n - 1] == b.y);
        assert_int_equal(plx_route_score(e, r.xy, r.n, 1.0, 1.0, &s, NULL), PLX_OK);
        assert_true(fabs(s.length - r.scored) < 1e-9);
        assert_true(fabs(s.dark_share * s.length - r.dark) < 1e-9);
        assert_true(fabs(s.mean * s.length - r.integral) < 1e-9 * (1 + r.integral));
        /* SPEC §6 minima over both ways: the route's edges against the polyline */
        assert_int_equal(plx_route_facial(e, r.xy, r.n, 1.0, 1.5, NULL, fac), PLX_OK);
        assert_true(r.min_ev == fmin(fac[0], fac[1]) && r.min_esc == fmin(fac[2], fac[3]));
        assert_int_equal(r.p_class, plx_p_class_facial(s.mean, s.min, r.min_ev, r.min_esc));
        assert_int_equal(r.p_class_h, s.p_class);
        net_route_free(&r);
    }
    net_free(&net);
    plx_engine_destroy(e);
    free(mem);
}

/* ---- the facial-recognition criterion decides the class ------------------- */

/* A street (0,0)-(20,0)-(40,0) and its lamps (isotropic, 5 m high, reach
 * 30 m): 1000 cd on the street's axis at x = 0, 10, .., 40, and with
 * 'sides' also 100 cd on both sides at y = +-6 from x = -20 to 60. */
static char *lamp_scene(int sides)
{
    char *buf = malloc(1 << 14);
    size_t n = 0;
    int x, y, pass;
    n += (size_t)sprintf(buf + n, "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                                  "{\"type\":\"Feature\",\"properties\":{},\"geometry\":{\"type\":\"Polygon\","
                                  "\"coordinates\":[[[100,100],[110,100],[110,110],[100,110]]]}}");
    for (pass = 0; pass <= sides; pass++)
        for (x = pass ? -20 : 0; x <= (pass ? 60 : 40); x += 10)
            for (y = pass ? -6 : 0; y <= (pass ? 6 : 0); y += 12)
                n += (size_t)sprintf(buf + n, ",{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":5,"
                                              "\"intensity\":%d,\"radius\":30},\"geometry\":{\"type\":"
                                              "\"Point\",\"coordinates\":[%d,%d]}}", pass ? 100 : 1000, x, y);
    sprintf(buf + n, "]}");
    return buf;
}

/* EN 13201-2 Table 3 as SPEC §6 prints it: mean, min E_h, min E_v, min E_sc. */
static int table_class(double mean, double min, double ev, double esc)
{
    static const double t[6][4] = { { 15, 3, 5, 5 }, { 10, 2, 3, 2 }, { 7.5, 1.5, 2.5, 1.5 },
                                    { 5, 1, 1.5, 1 }, { 3, 0.6, 1, 0.6 }, { 2, 0.4, 0.6, 0.2 } };
    int k;
    for (k = 0; k < 6; k++)
        if (mean >= t[k][0] && min >= t[k][1] && ev >= t[k][2] && esc >= t[k][3])
            return k + 1;
    return 0;
}

/* The route from (0,0) to (40,0) against the meters taken by hand at its
 * 41 samples (x = 0, 1, .., 40: two segments of 20 m at step 1 m): E_h on
 * the ground (trapezoid mean), E_v and E_sc at 1.5 m facing +x and -x. */
static void test_class_depends_on_facial_criterion(void **state)
{
    int sides;
    plx_engine *failed;
    (void)state;
    for (sides = 0; sides < 2; sides++) {
        void *mem;
        char *scene = lamp_scene(sides), err[256];
        plx_engine *e = load_text(scene, &mem);
        network net;
        route_set rs;
        net_snap a, b;
        net_route r;
        double integral = 0, mn = INFINITY, ev = INFINITY, esc = INFINITY;
        int x, d;
        memset(&rs, 0, sizeof rs);
        rs.lines = calloc(1, sizeof *rs.lines);
        rs.n = 1;
        rs.lines[0].n = 3;
        rs.lines[0].xy = calloc(6, sizeof(double));
        rs.lines[0].xy[2] = 20;
        rs.lines[0].xy[4] = 40;
        assert_int_equal(net_build(&net, &rs, err, sizeof err), 0);
        assert_int_equal(net_score(&net, e, NULL, 1.0, 1.0, 1.5, 0, &failed), PLX_OK);
        snap(&net, 0, 0, &a);
        snap(&net, 40, 0, &b);
        assert_int_equal(net_route_find(&net, e, &a, &b, 3.0, &r, err, sizeof err), 0);
        for (x = 0; x <= 40; x++) {
            double P[3] = { x, 0, 0 }, N[3] = { 0, 0, 1 }, Ed, Ei, m[4];
            assert_int_equal(plx_illuminance(e, 1, P, N, &Ed, &Ei, NULL), PLX_OK);
            integral += (x == 0 || x == 40 ? 0.5 : 1.0) * (Ed + Ei); /* x = 20: 1/2 from each segment */
            mn = fmin(mn, Ed + Ei);
            P[2] = 1.5;
            for (d = -1; d <= 1; d += 2) {
                double u[2] = { d, 0 };
                assert_int_equal(plx_meter(e, 1, P, u, m), PLX_OK);
                ev = fmin(ev, m[PLX_METER_V]);
                esc = fmin(esc, m[PLX_METER_SC]);
            }
        }
        assert_true(fabs(r.length - 40) < 1e-12 && fabs(r.integral - integral) < 1e-9 * integral);
        assert_true(r.min == mn && fabs(r.min_ev - ev) < 1e-12 && fabs(r.min_esc - esc) < 1e-12);
        assert_int_equal(r.p_class_h, table_class(integral / 40, mn, INFINITY, INFINITY)); /* E_h alone */
        assert_int_equal(r.p_class, table_class(integral / 40, mn, ev, esc));
        if (!sides) { /* at either end, facing out, every lamp is behind (or overhead): no light on a face */
            assert_true(r.min_ev == 0 && r.min_esc == 0);
            assert_int_equal(r.p_class_h, 1);
            assert_int_equal(r.p_class, 0);
        } else { /* faint lamps ahead and beside everywhere: the face is lit, less well than the ground */
            assert_true(r.min_ev > 0.6 && r.min_esc > 0.2);
            assert_int_equal(r.p_class_h, 1);
            assert_true(r.p_class > 1 && r.p_class < 6);
        }
        net_route_free(&r);
        net_free(&net);
        plx_engine_destroy(e);
        free(mem);
        free(scene);
    }
}

/* ---- random grids against Bellman-Ford -------------------------------------- */

static uint64_t rng;
static double rnd(void)
{
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static char *grid_scene(int seed)
{
    char *buf = malloc(1 << 16);
    size_t n = 0;
    int k;
    rng = 1000 + (uint64_t)seed;
    n += (size_t)sprintf(buf + n, "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                                  "{\"type\":\"Feature\",\"properties\":{},\"geometry\":{\"type\":\"Polygon\","
                                  "\"coordinates\":[[[-12,-12],[-10,-12],[-10,-10],[-12,-10]]]}},"
                                  "{\"type\":\"Feature\",\"properties\":{},\"geometry\":{\"type\":\"Polygon\","
                                  "\"coordinates\":[[[23,23],[37,23],[37,37],[23,37]]]}},"
                                  "{\"type\":\"Feature\",\"properties\":{},\"geometry\":{\"type\":\"Polygon\","
                                  "\"coordinates\":[[[110,110],[112,110],[112,112],[110,112]]]}}");
    for (k = 0; k < 6; k++)
        n += (size_t)sprintf(buf + n, ",{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"radius\":25},"
                                      "\"geometry\":{\"type\":\"Point\",\"coordinates\":[%.1f,%.1f]}}",
                             rnd() * 100, rnd() * 100);
    sprintf(buf + n, "]}");
    return buf;
}

/* A 6 x 6 grid, 20 m apart, each grid edge present with probability 0.75,
 * some with a middle vertex, some lines running over two grid edges. */
static void grid_lines(int seed, route_set *rs)
{
    size_t cap = 128;
    int i, j, d;
    rng = 7 + (uint64_t)seed * 31;
    rs->lines = calloc(cap, sizeof *rs->lines);
    rs->n = 0;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++)
            for (d = 0; d < 2; d++) {
                int i2 = i + (d == 0), j2 = j + (d == 1), two = rnd() < 0.2, mid = rnd() < 0.3, m = 0;
                route_line *l;
                if (i2 + two * (d == 0) > 5 || j2 + two * (d == 1) > 5 || rnd() > 0.75)
                    continue;
                l = &rs->lines[rs->n++];
                l->xy = malloc(sizeof *l->xy * 8);
                l->xy[m++] = 20.0 * i;
                l->xy[m++] = 20.0 * j;
                if (mid) {
                    l->xy[m++] = 20.0 * i + 10.0 * (d == 0) + 3.0 * (d == 1);
                    l->xy[m++] = 20.0 * j + 10.0 * (d == 1) + 3.0 * (d == 0);
                }
                l->xy[m++] = 20.0 * i2;
                l->xy[m++] = 20.0 * j2;
                if (two) {
                    l->xy[m++] = 20.0 * (i2 + (d == 0));
                    l->xy[m++] = 20.0 * (j2 + (d == 1));
                }
                l->n = (uint32_t)m / 2;
                snprintf(l->name, sizeof l->name, "g%zu", rs->n);
            }
    { /* an island: its two nodes are numbered last */
        route_line *l = &rs->lines[rs->n++];
        static const double island[4] = { 91, 95, 97, 95 };
        l->xy = malloc(sizeof island);
        memcpy(l->xy, island, sizeof island);
        l->n = 2;
    }
}

static double bellman_ford(const network *net, uint32_t s, uint32_t t, double w)
{
    double *d = malloc(sizeof *d * net->nnodes), res;
    uint32_t it, k;
    for (k = 0; k < net->nnodes; k++)
        d[k] = INFINITY;
    d[s] = 0;
    for (it = 0; it < net->nnodes; it++)
        for (k = 0; k < net->nedges; k++) {
            const net_edge *ed = &net->edges[k];
            double c = ed->length + w * (ed->s.dark_share * ed->s.length + ed->s.blocked_length);
            if (d[ed->a] + c < d[ed->b])
                d[ed->b] = d[ed->a] + c;
            if (d[ed->b] + c < d[ed->a])
                d[ed->a] = d[ed->b] + c;
        }
    res = d[t];
    free(d);
    return res;
}

/* Grid case seed: its scene's engine (freed with *mem and *scene) and its
 * network built, every edge scored. */
static plx_engine *grid_case(int seed, void **mem, char **scene, network *net)
{
    plx_engine *e, *failed;
    route_set rs;
    char err[256];
    *scene = grid_scene(seed);
    e = load_text(*scene, mem);
    grid_lines(seed, &rs);
    assert_int_equal(net_build(net, &rs, err, sizeof err), 0);
    assert_int_equal(net_score(net, e, NULL, 1.0, 1.0, 1.5, 0, &failed), PLX_OK);
    return e;
}

static void test_random_grids_against_bellman_ford(void **state)
{
    int seed, rounds = getenv("PLX_TEST_QUICK") ? 6 : 30, reached = 0, unreached = 0;
    static const double weights[3] = { 0.0, 0.7, 4.0 };
    (void)state;
    for (seed = 0; seed < rounds; seed++) {
        void *mem;
        char *scene, err[256];
        network net;
        plx_engine *e = grid_case(seed, &mem, &scene, &net);
        uint32_t q;
        for (q = 0; q < 12; q++) {
            uint32_t s = (uint32_t)(rnd() * net.nnodes), t = q == 11 ? net.nnodes - 1 : (uint32_t)(rnd() * net.nnodes);
            double w = weights[q % 3], want = bellman_ford(&net, s, t, w);
            net_snap a, b;
            net_route r;
            int rc;
            snap(&net, net.node_xy[2 * s], net.node_xy[2 * s + 1], &a);
            snap(&net, net.node_xy[2 * t], net.node_xy[2 * t + 1], &b);
            assert_true(a.dist == 0 && b.dist == 0);
            rc = net_route_find(&net, e, &a, &b, w, &r, err, sizeof err);
            if (want == INFINITY) {
                assert_int_equal(rc, 1);
                unreached++;
                continue;
            }
            assert_int_equal(rc, 0);
            assert_true(fabs(r.cost - want) <= 1e-9 * (1 + want));
            assert_true(fabs(r.cost - (r.length + w * (r.dark + r.blocked))) <= 1e-9 * (1 + want));
            reached++;
            net_route_free(&r);
        }
        net_free(&net);
        plx_engine_destroy(e);
        free(mem);
        free(scene);
    }
    assert_true(reached > 10);
    assert_true(unreached > 0);
}

/* net_route_capped (route --max-detour) against a sweep of weights, on
 * the random grids: for ends anywhere on the network, weights W of 3, 100
 * and 10^6 and caps 5% and 20% over the shortest route, whenever the
 * route at W is longer than the cap: the route found keeps within it, its
 * weight is at least the largest of 131 weights from W down to 10^-13 W
 * (ten a decade) whose route keeps within it, less the bisection's
 * precision, and it has no more dark metres than that route when its
 * weight is at least that one; and the
 * route at its weight plus twice the precision no longer keeps within
 * the cap (the weight found is the largest, to the precision). A step of
 * W / 1000 from 0, the bisection before, failed this at W = 10^6 (its
 * weight stayed 0 below 1000, the shortest route). */
static void test_capped_route_against_sweep(void **state)
{
    static const double weights[3] = { 3.0, 100.0, 1e6 }, detours[2] = { 0.05, 0.2 };
    int seed, rounds = getenv("PLX_TEST_QUICK") ? 4 : 16, capped = 0, lowered = 0;
    (void)state;
    for (seed = 0; seed < rounds; seed++) {
        void *mem;
        char *scene, err[256];
        network net;
        plx_engine *e = grid_case(seed + 100, &mem, &scene, &net);
        uint32_t q;
        for (q = 0; q < 12; q++) {
            uint32_t s = (uint32_t)(rnd() * net.nnodes), t = (uint32_t)(rnd() * net.nnodes);
            double W = weights[q % 3], cap, wb = -1.0, ws = 0.0;
            net_snap a, b;
            net_route r0, rW, best, rs, over;
            int k;
            snap(&net, net.node_xy[2 * s], net.node_xy[2 * s + 1], &a);
            snap(&net, net.node_xy[2 * t], net.node_xy[2 * t + 1], &b);
            if (net_route_find(&net, e, &a, &b, 0.0, &r0, err, sizeof err) != 0)
                continue; /* unconnected ends */
            cap = (1.0 + detours[(q / 3) % 2]) * r0.length;
            assert_int_equal(net_route_find(&net, e, &a, &b, W, &rW, err, sizeof err), 0);
            if (rW.length <= cap) {
                net_route_free(&r0);
                net_route_free(&rW);
                continue;
            }
            assert_int_equal(net_route_capped(&net, e, &a, &b, W, cap, &r0, &best, &wb, err, sizeof err), 0);
            assert_true(best.length <= cap);
            assert_true(wb >= 0.0 && wb < W);
            memset(&rs, 0, sizeof rs);
            for (k = 0; k <= 130; k++) { /* the sweep, from W down: its first route within the cap */
                double w = W * pow(10.0, -0.1 * k);
                assert_int_equal(net_route_find(&net, e, &a, &b, w, &rs, err, sizeof err), 0);
                if (rs.length <= cap) {
                    ws = w;
                    break;
                }
                net_route_free(&rs);
            }
            assert_true(wb >= ws * (1.0 - 2.0 * NET_CAP_PRECISION));
            if (ws > 0.0) {
                if (wb >= ws) /* dark metres never grow with the weight */
                    assert_true(best.dark + best.blocked <= rs.dark + rs.blocked + 1e-9);
                net_route_free(&rs);
            }
            if (wb > 0.0) {
                assert_int_equal(net_route_find(&net, e, &a, &b, wb * (1.0 + 2.0 * NET_CAP_PRECISION), &over, err,
                                                sizeof err), 0);
                assert_true(over.length > cap);
                net_route_free(&over);
                lowered++;
            }
            capped++;
            net_route_free(&best);
            net_route_free(&r0);
            net_route_free(&rW);
        }
        net_free(&net);
        plx_engine_destroy(e);
        free(mem);
        free(scene);
    }
    print_message("capped routes: %d, %d with a weight above 0\n", capped, lowered);
    assert_true(capped >= rounds);
    assert_true(lowered > 0);
}

static void assert_same_route(const net_route *x, const net_route *y);

/* The network as annotate writes it (net_scores_edge_props and the
 * header; coordinates in metres), as text (free). */
static char *scores_doc(const network *net, plx_engine *e)
{
    cJSON *root = cJSON_CreateObject(), *props, *fs;
    char *text;
    uint32_t i, k;
    cJSON_AddStringToObject(root, "type", "FeatureCollection");
    props = cJSON_AddObjectToObject(root, "properties");
    cJSON_AddStringToObject(props, "units", "m");
    fs = cJSON_AddArrayToObject(root, "features");
    for (i = 0; i < net->nedges; i++) {
        const net_edge *ed = &net->edges[i];
        const double *xy = net->lines.lines[ed->line].xy;
        cJSON *ft = cJSON_CreateObject(), *g, *co;
        cJSON_AddStringToObject(ft, "type", "Feature");
        cJSON_AddItemToObject(ft, "properties", net_scores_edge_props(net, i, "way", "street", 3.0));
        g = cJSON_AddObjectToObject(ft, "geometry");
        cJSON_AddStringToObject(g, "type", "LineString");
        co = cJSON_AddArrayToObject(g, "coordinates");
        for (k = ed->v0; k <= ed->v1; k++) { /* exact: cJSON's 15 digits may move a vertex by a bit */
            cJSON *pos = cJSON_CreateArray();
            char num[32];
            int c;
            for (c = 0; c < 2; c++) {
                snprintf(num, sizeof num, "%.17g", xy[2 * k + c]);
                cJSON_AddItemToArray(pos, cJSON_CreateRaw(num));
            }
            cJSON_AddItemToArray(co, pos);
        }
        cJSON_AddItemToArray(fs, ft);
    }
    cJSON_AddItemToObject(root, NET_SCORES_MEMBER, net_scores_header(net, e));
    text = cJSON_PrintUnformatted(root);
    assert_non_null(text);
    cJSON_Delete(root);
    return text;
}

/* text read back as route --network reads it (settings step 1, dark_lux,
 * height 1.5); net_scores_read's result. */
static int read_back(const char *text, plx_engine *e, double dark_lux, network *back, int *usage, char *err,
                     size_t errlen)
{
    route_set rs;
    cJSON *doc;
    int rc;
    assert_int_equal(route_parse_doc("scores", text, strlen(text), e, &rs, &doc, err, errlen), 0);
    assert_int_equal(net_build(back, &rs, err, errlen), 0);
    net_set_scoring(back, 1.0, dark_lux, 1.5);
    rc = net_scores_read(back, doc, e, usage, err, errlen);
    cJSON_Delete(doc);
    return rc;
}

/* annotate's scores read back (route --network over annotate's output):
 * on the random grids, every edge's light the same bytes as net_score
 * gave it, and the routes over the network read back the same bytes as
 * over the scored one, for ends anywhere on the streets and weights 0,
 * 0.7 and 4; another --dark-lux, another scene, a property missing, a
 * value edited and a file with no scores answered as net_scores.h says. */
static void test_scores_read_back(void **state)
{
    int seed, rounds = getenv("PLX_TEST_QUICK") ? 4 : 12, routes = 0;
    static const double weights[3] = { 0.0, 0.7, 4.0 };
    (void)state;
    for (seed = 0; seed < rounds; seed++) {
        void *mem;
        char *scene, *text, err[256];
        network net, back;
        int usage;
        uint32_t i, q;
        plx_engine *e = grid_case(seed + 200, &mem, &scene, &net);
        text = scores_doc(&net, e);
        assert_int_equal(read_back(text, e, 1.0, &back, &usage, err, sizeof err), 0);
        assert_int_equal(back.nedges, net.nedges);
        assert_int_equal(back.nnodes, net.nnodes);
        for (i = 0; i < net.nedges; i++) { /* one line a feature, in order: edge i is edge i */
            const net_edge *x = &net.edges[i], *y = &back.edges[i];
            assert_memory_equal(&x->length, &y->length, sizeof x->length);
            assert_memory_equal(&x->dark, &y->dark, sizeof x->dark);
            assert_memory_equal(&x->s.length, &y->s.length, sizeof x->s.length);
            assert_memory_equal(&x->s.blocked_length, &y->s.blocked_length, sizeof x->s.blocked_length);
            assert_memory_equal(&x->s.mean, &y->s.mean, sizeof x->s.mean);
            assert_memory_equal(&x->s.min, &y->s.min, sizeof x->s.min);
            assert_memory_equal(&x->s.max, &y->s.max, sizeof x->s.max);
            assert_int_equal(x->s.p_class, y->s.p_class);
            assert_memory_equal(x->fac, y->fac, sizeof x->fac); /* NaN read back as the same NaN */
            assert_true(back.scored[i]);
        }
        for (q = 0; q < 9; q++) {
            net_snap a, b, a2, b2;
            net_route x, y;
            int rx, ry;
            double px = rnd() * 110 - 5, py = rnd() * 110 - 5, tx = rnd() * 110 - 5, ty = rnd() * 110 - 5;
            snap(&net, px, py, &a);
            snap(&net, tx, ty, &b);
            snap(&back, px, py, &a2);
            snap(&back, tx, ty, &b2);
            rx = net_route_find(&net, e, &a, &b, weights[q % 3], &x, err, sizeof err);
            ry = net_route_find(&back, e, &a2, &b2, weights[q % 3], &y, err, sizeof err);
            assert_int_equal(rx, ry);
            if (rx != 0)
                continue;
            assert_same_route(&x, &y);
            routes++;
            net_route_free(&x);
            net_route_free(&y);
        }
        net_free(&back);
        assert_int_equal(read_back(text, e, 2.0, &back, &usage, err, sizeof err), -1); /* another --dark-lux */
        assert_int_equal(usage, 1);
        assert_non_null(strstr(err, "--dark-lux 1, not 2"));
        net_free(&back);
        {
            char *hole = strstr(text, "\"mean_lux\""); /* a property renamed */
            assert_non_null(hole);
            hole[1] = 'M';
            assert_int_equal(read_back(text, e, 1.0, &back, &usage, err, sizeof err), -1);
            assert_int_equal(usage, 0);
            assert_non_null(strstr(err, "no number 'mean_lux'"));
            net_free(&back);
            hole[1] = 'm';
        }
        {
            char *v = strstr(text, "\"max_lux\":") + 10, was = *v; /* a value edited: the edges' hash */
            *v = *v == '1' ? '2' : '1';
            assert_int_equal(read_back(text, e, 1.0, &back, &usage, err, sizeof err), -1);
            assert_non_null(strstr(err, "not those annotate wrote (edges_hash"));
            net_free(&back);
            *v = was;
        }
        {
            char *h = strstr(text, "\"" NET_SCORES_MEMBER "\""), *lamps; /* another scene */
            assert_non_null(h);
            lamps = strstr(h, "\"lamps\":");
            assert_non_null(lamps);
            lamps[8] = lamps[8] == '9' ? '8' : '9';
            assert_int_equal(read_back(text, e, 1.0, &back, &usage, err, sizeof err), -1);
            assert_non_null(strstr(err, "another scene or light"));
            net_free(&back);
            h[1] = 'q'; /* no scores: a plain network */
            assert_int_equal(read_back(text, e, 1.0, &back, &usage, err, sizeof err), 1);
            assert_false(back.scored[0]);
            net_free(&back);
        }
        cJSON_free(text);
        net_free(&net);
        plx_engine_destroy(e);
        free(mem);
        free(scene);
    }
    print_message("routes compared: %d\n", routes);
    assert_true(routes > 5 * rounds);
}

/* Two routes the same bytes: polyline and every sum. */
static void assert_same_route(const net_route *x, const net_route *y)
{
    assert_int_equal(x->n, y->n);
    assert_memory_equal(x->xy, y->xy, sizeof *x->xy * 2 * x->n);
    assert_memory_equal(&x->length, &y->length, sizeof x->length);
    assert_memory_equal(&x->dark, &y->dark, sizeof x->dark);
    assert_memory_equal(&x->blocked, &y->blocked, sizeof x->blocked);
    assert_memory_equal(&x->integral, &y->integral, sizeof x->integral);
    assert_memory_equal(&x->min, &y->min, sizeof x->min);
    assert_memory_equal(&x->cost, &y->cost, sizeof x->cost);
    assert_memory_equal(&x->min_esc, &y->min_esc, sizeof x->min_esc);
    assert_int_equal(x->p_class, y->p_class);
}

/* net_score_route against scoring every edge, on the random grids (20 m
 * apart: many routes of exactly equal cost): for ends snapped anywhere on
 * the streets and weights up to the one it was given, the same routes to
 * the byte, its edges the same scores, and fewer edges scored where the
 * shortest route is cheap; other ends or a higher weight refused. */
static void test_route_scoring_against_every_edge(void **state)
{
    int seed, rounds = getenv("PLX_TEST_QUICK") ? 6 : 30, fewer = 0, compared = 0;
    static const double weights[5] = { 0.0, 0.05, 0.3, 4.0, 1e6 };
    plx_engine *failed;
    (void)state;
    for (seed = 0; seed < rounds; seed++) {
        void *mem;
        char *scene, err[256];
        network all, some;
        plx_engine *e = grid_case(seed, &mem, &scene, &all);
        route_set rs;
        uint32_t q, i;
        for (q = 0; q < 10; q++) {
            double w = weights[q % 5];
            net_snap a, b;
            size_t n;
            int k;
            grid_lines(seed, &rs);
            assert_int_equal(net_build(&some, &rs, err, sizeof err), 0);
            net_set_scoring(&some, 1.0, 1.0, 1.5);
            snap(&all, rnd() * 110 - 5, rnd() * 110 - 5, &a);
            snap(&all, rnd() * 110 - 5, rnd() * 110 - 5, &b);
            assert_int_equal(net_score_route(&some, e, NULL, &a, &b, w, 0, &n, &failed), PLX_OK);
            fewer += w > 0 && n < some.nedges; /* weighted searches that leave edges out */
            for (i = 0; i < some.nedges; i++)
                if (some.scored[i]) {
                    assert_memory_equal(&some.edges[i].s, &all.edges[i].s, sizeof all.edges[i].s);
                    assert_memory_equal(some.edges[i].fac, all.edges[i].fac, sizeof all.edges[i].fac);
                }
            for (k = 0; k < 6; k++) { /* the weight asked for and below, down to the least that
                                       * net_route_capped's halvings try (W / 2^60), and 0 */
                static const double part[6] = { 1.0, 0.5, 0.123, 0x1p-20, 0x1p-60, 0.0 };
                double wk = w * part[k];
                net_route x, y;
                int rx = net_route_find(&all, e, &a, &b, wk, &x, err, sizeof err);
                int ry = net_route_find(&some, e, &a, &b, wk, &y, err, sizeof err);
                assert_int_equal(rx, ry);
                if (rx != 0)
                    continue;
                assert_same_route(&x, &y);
                compared++;
                net_route_free(&x);
                net_route_free(&y);
            }
            { /* another weight above, or other ends: refused, not a route over unscored edges */
                net_route r;
                net_snap c = b;
                c.x += 0.5;
                assert_int_equal(net_route_find(&some, e, &a, &b, 2.0 * w + 1.0, &r, err, sizeof err), -1);
                assert_string_equal(err, "the network's edges were scored for other ends or a lower --dark-weight");
                assert_int_equal(net_route_find(&some, e, &a, &c, w, &r, err, sizeof err), -1);
            }
            net_free(&some);
        }
        net_free(&all);
        plx_engine_destroy(e);
        free(mem);
        free(scene);
    }
    print_message("routes compared: %d\n", compared);
    assert_true(compared > 100);
    assert_true(fewer > 5);
}

static void test_snap_and_empty(void **state)
{
    void *mem;
    plx_engine *e = load_file("fixtures/net-detour.geojson", &mem);
    network net;
    net_snap s;
    route_set rs;
    char err[256];
    static const char empty[] = "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[]}";
    (void)state;
    open_net(e, "fixtures/net-detour-streets.geojson", &net);
    snap(&net, 50, -30, &s);
    assert_true(fabs(s.dist - 30) < 1e-12 && s.x == 50 && s.y == 0);
    snap(&net, 430, 404, &s);
    assert_true(fabs(s.dist - hypot(10, 4)) < 1e-12);
    net_free(&net);
    assert_int_equal(route_parse("empty.geojson", empty, strlen(empty), e, &rs, err, sizeof err), -1);
    assert_string_equal(err, "empty.geojson: no LineString features");
    memset(&rs, 0, sizeof rs);
    assert_int_equal(net_build(&net, &rs, err, sizeof err), 0);
    assert_int_equal(net_snap_point(&net, 0, 0, &s), -1);
    net_free(&net);
    plx_engine_destroy(e);
    free(mem);
}

/* ---- twin_for (src/cli/twin_engines.c): the items shared out between an
 * engine's thread and its twins' ---------------------------------------- */

/* Stand-in engines: twin_for only hands their pointers to the work. */
static char fake_engine[4];

typedef struct fake_job {
    int done[1000];         /* times each item was done */
    int by[1000];           /* which engine did it (0 .. 3) */
    long fail_at;           /* an item whose chunk fails (-1: none) */
    long range_at;          /* an item whose chunk says PLX_E_RANGE (-1: none) */
    size_t last_done;       /* progress: the last count seen */
    int progress_calls, progress_back;
} fake_job;

static plx_status fake_work(void *arg, plx_engine *e, size_t k0, size_t k1)
{
    fake_job *j = arg;
    size_t k;
    int range = 0;
    for (k = k0; k < k1; k++) { /* as plx_illuminance: a point out of range ends nothing */
        j->done[k]++;
        j->by[k] = (int)((char *)e - fake_engine);
        if ((long)k == j->fail_at)
            return PLX_E_NOMEM;
        range |= (long)k == j->range_at;
    }
    return range ? PLX_E_RANGE : PLX_OK;
}

static void fake_progress(void *arg, size_t done, size_t n)
{
    fake_job *j = arg;
    j->progress_back += done < j->last_done || done > n;
    j->last_done = done;
    j->progress_calls++;
}

/* n items in chunks of 7 on the engine and 3 twins. */
static plx_status fake_run(fake_job *j, size_t n, int range_soft, plx_engine **failed)
{
    twin_set t;
    twin_work w;
    int k;
    static cli_common c;
    memset(&t, 0, sizeof t);
    t.cmd = "test_network";
    t.c = &c;
    t.tried = 1; /* the twins are "loaded": no bake is read */
    t.n = 3;
    for (k = 0; k < 3; k++)
        t.tw[k] = (plx_engine *)(void *)&fake_engine[k + 1];
    memset(&w, 0, sizeof w);
    w.n = n;
    w.chunk = 7;
    w.min_items = 16;
    w.range_soft = range_soft;
    w.fn = fake_work;
    w.arg = j;
    w.progress = fake_progress;
    return twin_for(&t, (plx_engine *)(void *)&fake_engine[0], &w, failed);
}

static void fake_init(fake_job *j)
{
    memset(j, 0, sizeof *j);
    j->fail_at = j->range_at = -1;
}

static void test_twin_for(void **state)
{
    static fake_job j;
    plx_engine *failed = NULL;
    size_t k, n;
    (void)state;
    /* every item once, whatever the count (0, below min_items, around the chunks) */
    for (n = 0; n <= 1000; n += n < 40 ? 1 : 137) {
        fake_init(&j);
        assert_int_equal(fake_run(&j, n, 0, &failed), PLX_OK);
        for (k = 0; k < 1000; k++)
            assert_int_equal(j.done[k], k < n);
        assert_int_equal(j.progress_back, 0);
        if (n > 0)
            assert_true(j.last_done == n);
        if (n > 0 && n < 16) /* below min_items: the engine alone */
            for (k = 0; k < n; k++)
                assert_int_equal(j.by[k], 0);
    }
    /* a failure: its status and engine, every chunk before it done, none
     * handed out after it was seen; the lowest failed chunk wins */
    for (k = 0; k < 1000; k += 97) {
        fake_init(&j);
        j.fail_at = (long)k;
        assert_int_equal(fake_run(&j, 1000, 0, &failed), PLX_E_NOMEM);
        assert_ptr_equal(failed, (plx_engine *)(void *)&fake_engine[j.by[k]]);
        for (n = 0; n < k / 7 * 7; n++)
            assert_int_equal(j.done[n], 1);
    }
    /* PLX_E_RANGE with range_soft: every item done, the status at the end */
    fake_init(&j);
    j.range_at = 500;
    assert_int_equal(fake_run(&j, 1000, 1, &failed), PLX_E_RANGE);
    for (k = 0; k < 1000; k++)
        assert_int_equal(j.done[k], 1);
    /* the default's memory rule: all engines within half the machine */
    assert_int_equal(twin_fit(7, 100, 0), 7);          /* memory unknown: as many as asked */
    assert_int_equal(twin_fit(7, 100, 1600), 7);       /* 8 x 100 <= 800 */
    assert_int_equal(twin_fit(7, 100, 1599), 6);
    assert_int_equal(twin_fit(3, 400, 1000), 0);       /* one engine already passes half */
    assert_int_equal(twin_fit(3, 250, 1000), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_detour_only_when_weight_says_so),
        cmocka_unit_test(test_edges_equal_route_scores),
        cmocka_unit_test(test_route_equals_its_polyline),
        cmocka_unit_test(test_class_depends_on_facial_criterion),
        cmocka_unit_test(test_random_grids_against_bellman_ford),
        cmocka_unit_test(test_route_scoring_against_every_edge),
        cmocka_unit_test(test_capped_route_against_sweep),
        cmocka_unit_test(test_scores_read_back),
        cmocka_unit_test(test_snap_and_empty),
        cmocka_unit_test(test_twin_for),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
