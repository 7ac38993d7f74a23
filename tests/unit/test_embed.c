/* The embedding API (include/polarlux.h "Embedding"): the SPEC §1
 * projection both ways against the formula and the loader, and the
 * size-first memory estimate: plx_scene_size_scan against an independent
 * count over cJSON's parse tree, and plx_memory_estimate large enough to run
 * each use on every fixture and generated cities in a block of exactly that
 * size, yet within 4x of the measured high-water mark. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <cjson/cJSON.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "port.h"
#include "fixture.h"
#include "slow.h"

#define BIG ((size_t)256 << 20)

/* ---- projection ---------------------------------------------------------- */

static const char *lonlat_scene =
    "{\"type\":\"FeatureCollection\",\"features\":["
    "{\"type\":\"Feature\",\"properties\":{\"height\":10},\"geometry\":{\"type\":\"Polygon\","
    "\"coordinates\":[[[24.9400,60.1700],[24.9410,60.1700],[24.9410,60.1705],[24.9400,60.1705],[24.9400,60.1700]]]}},"
    "{\"type\":\"Feature\",\"properties\":{\"lamp\":true},\"geometry\":{\"type\":\"Point\","
    "\"coordinates\":[24.9420,60.1712]}}]}";

static plx_engine *new_engine(void)
{
    plx_engine *e = NULL;
    plx_config cfg;
    plx_config_default(&cfg);
    assert_int_equal(plx_engine_new(64u << 20, &cfg, &e), PLX_OK);
    return e;
}

static void test_projection_formula(void **state)
{
    plx_engine *e = new_engine();
    plx_scene_info si;
    plx_lamp lamp;
    const double ll[8] = { 24.9420, 60.1712, 24.9400, 60.1700, 25.0, 60.0, 24.0, 61.5 };
    double xy[8], back[8], c;
    int i;
    (void)state;
    assert_int_equal(plx_load_geojson(e, lonlat_scene, strlen(lonlat_scene), "t"), PLX_OK);
    assert_int_equal(plx_scene_info_get(e, &si), PLX_OK);
    assert_true(si.lonlat);
    assert_true(fabs(si.lon0 - 24.9410) < 1e-12 && fabs(si.lat0 - 60.1706) < 1e-12);
    assert_int_equal(plx_lonlat_to_local(e, 4, ll, xy), PLX_OK);
    /* SPEC §1, written out here */
    c = cos(si.lat0 * acos(-1.0) / 180.0);
    for (i = 0; i < 4; i++) {
        assert_true(fabs(xy[2 * i] - (ll[2 * i] - si.lon0) * 111320.0 * c) < 1e-9);
        assert_true(fabs(xy[2 * i + 1] - (ll[2 * i + 1] - si.lat0) * 110540.0) < 1e-9);
    }
    /* bit for bit what the loader did to the lamp */
    assert_int_equal(plx_lamp_get(e, 0, &lamp), PLX_OK);
    assert_true(xy[0] == lamp.x && xy[1] == lamp.y);
    /* and back, in place */
    memcpy(back, xy, sizeof xy);
    assert_int_equal(plx_local_to_lonlat(e, 4, back, back), PLX_OK);
    for (i = 0; i < 8; i++)
        assert_true(fabs(back[i] - ll[i]) < 1e-12);
    assert_int_equal(plx_lonlat_to_local(e, 4, back, back), PLX_OK);
    for (i = 0; i < 8; i++)
        assert_true(fabs(back[i] - xy[i]) < 1e-8);
    assert_int_equal(plx_lonlat_to_local(e, 0, NULL, NULL), PLX_OK);
    assert_int_equal(plx_lonlat_to_local(e, 1, NULL, xy), PLX_E_INVALID);
    plx_engine_free(e);
}

static void test_projection_errors(void **state)
{
    plx_engine *e = new_engine();
    const char *metres = "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[]}";
    double p[2] = { 1, 2 }, q[2];
    (void)state;
    assert_int_equal(plx_lonlat_to_local(e, 1, p, q), PLX_E_NOSCENE);
    assert_int_equal(plx_load_geojson(e, metres, strlen(metres), "m"), PLX_OK);
    assert_int_equal(plx_lonlat_to_local(e, 1, p, q), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(e), "plx_lonlat_to_local: the scene is in local metres"));
    assert_int_equal(plx_local_to_lonlat(e, 1, p, q), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(e), "no lon/lat frame"));
    plx_engine_free(e);
}

/* ---- the scan against cJSON's tree ---------------------------------------- */

static void tree_count(const cJSON *n, plx_scene_size *c)
{
    const cJSON *k;
    c->json_values++;
    if (cJSON_IsString(n)) {
        c->features += strcmp(n->valuestring, "Feature") == 0;
        c->points += strcmp(n->valuestring, "Point") == 0;
    }
    if (cJSON_IsArray(n) && n->child) {
        if (cJSON_IsNumber(n->child))
            c->positions++;
        else if (cJSON_IsArray(n->child) && n->child->child && cJSON_IsNumber(n->child->child))
            c->rings++;
    }
    for (k = n->child; k; k = k->next)
        tree_count(k, c);
}

static void check_scan(const char *text, size_t len, const char *name)
{
    plx_scene_size s, t;
    cJSON *root = cJSON_ParseWithLength(text, len);
    assert_non_null(root);
    memset(&t, 0, sizeof t);
    tree_count(root, &t);
    cJSON_Delete(root);
    assert_int_equal(plx_scene_size_scan(text, len, &s), PLX_OK);
    if (s.json_values != t.json_values || s.positions != t.positions || s.rings != t.rings ||
        s.features != t.features || s.points != t.points)
        fail_msg("%s: scan %llu values %llu positions %llu rings %llu features %llu points; "
                 "tree %llu %llu %llu %llu %llu", name, (unsigned long long)s.json_values,
                 (unsigned long long)s.positions, (unsigned long long)s.rings,
                 (unsigned long long)s.features, (unsigned long long)s.points,
                 (unsigned long long)t.json_values, (unsigned long long)t.positions,
                 (unsigned long long)t.rings, (unsigned long long)t.features, (unsigned long long)t.points);
    assert_int_equal(s.text_bytes, len);
}

/* ---- the estimate ----------------------------------------------------------- */

#define FRAME_W 320
#define FRAME_H 240

/* Runs the uses on an engine in a block of 'size' bytes; returns the first
 * failing status and the high-water mark in *peak. */
static plx_status workflow(const char *text, size_t len, const plx_config *cfg, unsigned uses, size_t size,
                           size_t *peak)
{
    void *mem = malloc(size);
    plx_engine *e = NULL;
    plx_scene_info si;
    plx_memory_report r;
    plx_status st;
    assert_non_null(mem);
    /* the engine must not read its block before writing it: filled with
     * garbage, except the roomy BIG block (filling 256 MiB for each of its
     * many runs cost most of this test's time; its pages stay untouched) */
    if (size != BIG)
        memset(mem, 0xa5, size);
    st = plx_engine_create(mem, size, cfg, &e);
    if (st == PLX_OK)
        st = plx_load_geojson(e, text, len, "estimate");
    if (st == PLX_OK)
        st = plx_scene_info_get(e, &si);
    if (st == PLX_OK && (uses & PLX_USE_VISIBILITY))
        st = plx_polar_build(e);
    if (st == PLX_OK && (uses & (PLX_USE_LIGHT | PLX_USE_RENDER))) {
        double cy = 0.5 * (si.bounds[1] + si.bounds[3]);
        double line[4] = { si.bounds[0] + 40.0, cy, si.bounds[2] - 40.0, cy };
        plx_route_stats total;
        uint32_t i;
        st = plx_route_score(e, line, 2, 1.0, 1.0, &total, NULL);
        for (i = 0; st == PLX_OK && i < si.lamps && i < 20; i++) {
            plx_lit_region lr;
            st = plx_lit_region_get(e, i, &lr);
        }
    }
    if (st == PLX_OK && (uses & PLX_USE_RENDER)) {
        double cx = 0.5 * (si.bounds[0] + si.bounds[2]), cy = 0.5 * (si.bounds[1] + si.bounds[3]);
        plx_camera cam = { { cx, cy, 400.0 }, { cx, cy + 1.0, 0.0 }, 60.0, FRAME_W, FRAME_H };
        plx_render_opts o;
        uint8_t *px = malloc((size_t)FRAME_W * FRAME_H * 3);
        plx_render_opts_default(&o);
        st = plx_render(e, &cam, &o, px, NULL, NULL);
        o.aa = 2; /* anti-aliasing takes buffers of its own (walk's default) */
        if (st == PLX_OK)
            st = plx_render(e, &cam, &o, px, NULL, NULL);
        free(px);
    }
    if (e) {
        plx_memory_get(e, &r);
        *peak = r.peak_total;
        if (st != PLX_OK)
            print_message("  %s\n", plx_last_error(e));
        plx_engine_destroy(e);
    }
    free(mem);
    return st;
}

static double worst_ratio;

static void check_estimate(const char *text, size_t len, const char *name)
{
    static const unsigned uses[] = { PLX_USE_LOAD, PLX_USE_VISIBILITY, PLX_USE_LIGHT,
                                     PLX_USE_VISIBILITY | PLX_USE_RENDER };
    plx_scene_size sz;
    plx_config cfg;
    size_t k;
    plx_config_default(&cfg);
    cfg.lit_cache_bytes = 1u << 20;
    cfg.render_max_width = FRAME_W;
    cfg.render_max_height = FRAME_H;
    assert_int_equal(plx_scene_size_scan(text, len, &sz), PLX_OK);
    for (k = 0; k < sizeof uses / sizeof uses[0]; k++) {
        size_t est = plx_memory_estimate(&sz, &cfg, uses[k]), peak = 0, peak_big = 0;
        plx_status st = workflow(text, len, &cfg, uses[k], est, &peak);
        double ratio;
        if (st != PLX_OK)
            fail_msg("%s uses %u: estimate %zu bytes is not enough (%s)", name, uses[k], est, plx_strerror(st));
        assert_int_equal(workflow(text, len, &cfg, uses[k], BIG, &peak_big), PLX_OK);
        ratio = (double)est / (double)peak_big;
        print_message("%-32s uses %u: estimate %10zu, high-water %10zu, %.2fx\n", name, uses[k], est, peak_big, ratio);
        if (ratio > worst_ratio)
            worst_ratio = ratio;
        assert_true(ratio >= 1.0);
        /* the loosest: 3.82x for visibility on gen eixample 20 20 (full run) */
        assert_true(ratio <= 4.5);
    }
}

static void test_scan_and_estimate_fixtures(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    static const char *const files[] = { "fixtures/tiny.geojson", "fixtures/grid-4x4.geojson",
                                         "fixtures/eixample-4x4.geojson", "fixtures/oldtown-8x8.geojson",
                                         "fixtures/ground-image.geojson", "fixtures/helsinki-centre.geojson" };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof files / sizeof files[0]; i++) {
        char err[256];
        size_t len;
        char *text = port_read_text(files[i], &len, err, sizeof err);
        if (!text)
            fail_msg("%s", err);
        check_scan(text, len, files[i]);
        check_estimate(text, len, files[i]);
        free(text);
    }
}

static void test_scan_and_estimate_generated(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    static const char *const styles[] = { "grid", "eixample", "oldtown" };
    int quick = getenv("PLX_TEST_QUICK") != NULL;
    const int n[] = { quick ? 12 : 30, quick ? 8 : 20, quick ? 16 : 40 };
    size_t i;
    (void)state;
    for (i = 0; i < 3; i++) {
        fixture_city b;
        char name[64];
        fixture_gen(styles[i], n[i], n[i], 7, &b);
        snprintf(name, sizeof name, "gen %s %d %d", styles[i], n[i], n[i]);
        check_scan(b.buf, b.len, name);
        check_estimate(b.buf, b.len, name);
        free(b.buf);
    }
    print_message("worst estimate / high-water: %.2fx\n", worst_ratio);
}

static void test_estimate_defaults_and_counts(void **state)
{
    plx_scene_size sz, byhand;
    size_t a, b;
    char err[256];
    size_t len, peak = 0;
    char *text = port_read_text("fixtures/helsinki-centre.geojson", &len, err, sizeof err);
    (void)state;
    assert_non_null(text);
    assert_int_equal(plx_scene_size_scan(text, len, &sz), PLX_OK);
    /* the default config: a 16 MiB lit cache and 1920x1080 frames */
    a = plx_memory_estimate(&sz, NULL, PLX_USE_RENDER);
    assert_int_equal(workflow(text, len, NULL, PLX_USE_RENDER, a, &peak), PLX_OK);
    assert_true(a <= 4 * peak);
    /* counts known by other means: buildings 442, vertices 6,592 + 584 lamps */
    memset(&byhand, 0, sizeof byhand);
    byhand.positions = 6592 + 584;
    byhand.rings = 442;
    byhand.points = 584;
    byhand.features = 442 + 584;
    b = plx_memory_estimate(&byhand, NULL, PLX_USE_VISIBILITY);
    assert_int_equal(workflow(text, len, NULL, PLX_USE_VISIBILITY, b, &peak), PLX_OK);
    assert_true(b <= 4 * peak);
    assert_int_equal(plx_memory_estimate(NULL, NULL, 0), 0);
    assert_int_equal(plx_scene_size_scan(NULL, 3, &sz), PLX_E_INVALID);
    assert_int_equal(plx_scene_size_scan("", 0, &sz), PLX_OK);
    assert_int_equal(sz.json_values, 0);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_projection_formula),
        cmocka_unit_test(test_projection_errors),
        cmocka_unit_test(test_scan_and_estimate_fixtures),
        cmocka_unit_test(test_scan_and_estimate_generated),
        cmocka_unit_test(test_estimate_defaults_and_counts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
