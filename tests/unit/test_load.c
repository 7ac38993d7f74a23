/* Scene loading (SPEC §1): the tiny fixture by hand, lon/lat projection,
 * every validation error with its exact message, numbers in strings, fault
 * injection at every allocation, blocks of the eixample fixture, the real
 * district. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "fixture.h"

#include "polarlux.h"
#include "port.h"

#define MEM (64u << 20)

static plx_status load_str(fixture_log *f, const char *json)
{
    return plx_load_geojson(f->e, json, strlen(json), "t.geojson");
}

/* ---- the tiny hand-made fixture ------------------------------------------------ */

static void test_tiny_counts(void **state)
{
    fixture_log *f = fixture_open(0, MEM);
    plx_scene_info si;
    plx_building b;
    plx_lamp l;
    (void)state;
    assert_int_equal(plx_load_file(f->e, "fixtures/tiny.geojson"), PLX_OK);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.buildings, 4);
    assert_int_equal(si.raised, 1);
    assert_int_equal(si.holes, 1);
    assert_int_equal(si.lamps, 3);
    assert_int_equal(si.skipped_lamps, 1);
    assert_int_equal(si.skipped_features, 0);
    assert_int_equal(si.vertices, 4 + 4 + 8 + 4);
    assert_int_equal(si.lonlat, 0);
    assert_true(si.bounds[0] == -50 && si.bounds[1] == -50 && si.bounds[2] == 110 && si.bounds[3] == 70);
    assert_true(si.height_min == 4 && si.height_median == 8 && si.height_max == 12);
    assert_true(si.ground_albedo == 0.2);
    assert_int_equal(plx_building_get(f->e, 1, &b), PLX_OK);
    assert_string_equal(b.id, "B");
    assert_true(b.height == 6.0 && b.albedo == 0.35 && b.min_height == 0.0);
    assert_int_equal(plx_building_get(f->e, 2, &b), PLX_OK);
    assert_true(b.height == 12.0 && b.albedo == 0.5 && b.nrings == 2);
    assert_int_equal(plx_building_get(f->e, 3, &b), PLX_OK);
    assert_true(b.min_height == 3.0 && b.height == 4.0);
    assert_int_equal(plx_lamp_get(f->e, 1, &l), PLX_OK);
    assert_string_equal(l.id, "L2");
    assert_true(l.z == 8.0 && l.intensity == 1000.0 && l.radius == 30.0 && l.color[1] == 1.0f);
    assert_int_equal(plx_lamp_get(f->e, 0, &l), PLX_OK);
    assert_true(l.color[0] == 1.0f && l.color[1] == 0.62f && l.color[2] == 0.28f);
    assert_int_equal(plx_lamp_get(f->e, 2, &l), PLX_OK);
    assert_string_equal(l.id, "L4"); /* under the canopy: kept */
    assert_non_null(strstr(f->book.all, "feature 6 (L3, line 18, column 3): lamp is inside building 0 (A); left out"));
    assert_int_equal(plx_lamp_get(f->e, 3, &l), PLX_E_RANGE);
    fixture_close(f);
}

static double ring_area(const double *xy, uint32_t n)
{
    double a = 0;
    uint32_t i;
    for (i = 0; i < n; i++) {
        uint32_t j = (i + 1) % n;
        a += xy[2 * i] * xy[2 * j + 1] - xy[2 * j] * xy[2 * i + 1];
    }
    return a / 2;
}

static void test_tiny_rings_and_blocks(void **state)
{
    fixture_log *f = fixture_open(0, MEM);
    plx_scene_info si;
    const double *xy;
    uint32_t n, i, found_ab = 0, found_c = 0;
    (void)state;
    assert_int_equal(plx_load_file(f->e, "fixtures/tiny.geojson"), PLX_OK);
    /* B was given clockwise: stored counter-clockwise, closing vertex gone */
    assert_int_equal(plx_building_ring(f->e, 1, 0, &xy, &n), PLX_OK);
    assert_int_equal(n, 4);
    assert_true(ring_area(xy, n) == 100.0);
    assert_int_equal(plx_building_ring(f->e, 2, 1, &xy, &n), PLX_OK);
    assert_true(ring_area(xy, n) == -100.0);
    assert_int_equal(plx_building_ring(f->e, 2, 2, &xy, &n), PLX_E_RANGE);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.blocks, 3);
    assert_int_equal(si.courtyards, 1);
    assert_int_equal(si.overlapping_pairs, 0);
    for (i = 0; i < si.blocks; i++) {
        plx_block k;
        assert_int_equal(plx_block_get(f->e, i, &k), PLX_OK);
        assert_int_equal(plx_block_ring(f->e, i, 0, &xy, &n), PLX_OK);
        if (k.nbuildings == 2) {
            found_ab = 1;
            assert_true(fabs(ring_area(xy, n) - 200.0) < 1e-9);
        }
        if (k.nrings == 2) {
            found_c = 1;
            assert_true(fabs(ring_area(xy, n) - 400.0) < 1e-9);
            assert_int_equal(plx_block_ring(f->e, i, 1, &xy, &n), PLX_OK);
            assert_true(fabs(ring_area(xy, n) + 100.0) < 1e-9);
        }
    }
    assert_true(found_ab && found_c);
    fixture_close(f);
}

/* ---- lon/lat projection ---------------------------------------------------------- */

static void test_lonlat_projection(void **state)
{
    fixture_log *f = fixture_open(0, MEM);
    plx_scene_info si;
    plx_lamp l;
    const double *xy;
    uint32_t n;
    const char *json =
        "{\"type\":\"FeatureCollection\",\"features\":["
        "{\"type\":\"Feature\",\"properties\":{},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":"
        "[[[24.950,60.160],[24.952,60.160],[24.952,60.161],[24.950,60.161],[24.950,60.160]]]}},"
        "{\"type\":\"Feature\",\"properties\":{\"highway\":\"street_lamp\"},\"geometry\":"
        "{\"type\":\"Point\",\"coordinates\":[24.954,60.162]}}]}";
    /* Hand computation: the box of all coordinates is lon 24.950..24.954,
     * lat 60.160..60.162, so lon0 = 24.952, lat0 = 60.161.
     * x = (lon - lon0) * 111320 * cos(60.161 deg), y = (lat - lat0) * 110540. */
    double c = cos(60.161 * 3.14159265358979323846 / 180.0);
    (void)state;
    assert_int_equal(load_str(f, json), PLX_OK);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.lonlat, 1);
    assert_true(fabs(si.lon0 - 24.952) < 1e-12 && fabs(si.lat0 - 60.161) < 1e-12);
    assert_int_equal(plx_lamp_get(f->e, 0, &l), PLX_OK);
    assert_true(fabs(l.x - 0.002 * 111320 * c) < 1e-6);
    assert_true(fabs(l.y - 0.001 * 110540) < 1e-6);
    assert_true(fabs(l.x - 110.77776) < 1e-4); /* 0.002 * 111320 * 0.4975646... */
    assert_int_equal(plx_building_ring(f->e, 0, 0, &xy, &n), PLX_OK);
    assert_true(fabs(xy[0] - (-0.002 * 111320 * c)) < 1e-6);
    assert_true(fabs(xy[1] - (-0.001 * 110540)) < 1e-6);
    fixture_close(f);
}

/* ---- validation errors, each with its exact message ----------------------------- */

typedef struct bad_case {
    const char *geometry;   /* geometry JSON */
    const char *props;      /* properties JSON */
    const char *message;    /* expected last error in strict mode */
} bad_case;

static const bad_case bad_cases[] = {
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[0,0]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): outer ring has 2 distinct vertices (a ring needs at least 3)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[0,0],[0,0],[0,0]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): outer ring has 1 distinct vertex (a ring needs at least 3)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[10,10],[10,0],[0,10],[0,0]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): outer ring intersects itself (edges 0 and 2 meet)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[10,0],[20,0],[0,0]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): outer ring intersects itself (edges 0 and 2 meet)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1e999,0],[1,1],[0,0]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): position 1 of outer ring has a non-finite number" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[2e7,0],[1,1],[0,0]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): position 1 of outer ring is out of range (|coordinate| > 1e7 m)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[\"a\",0],[1,1],[0,0]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): position 1 of outer ring is not a position [x, y] of numbers" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}", "{\"height\":0}",
      "t.geojson: feature 0 (line 1, column 68): height 0 m is out of range (must be > 0 and <= 1000 m)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}", "{\"height\":-4}",
      "t.geojson: feature 0 (line 1, column 68): height -4 m is out of range (must be > 0 and <= 1000 m)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}", "{\"height\":1500}",
      "t.geojson: feature 0 (line 1, column 68): height 1500 m is out of range (must be > 0 and <= 1000 m)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}", "{\"building:levels\":\"400\"}",
      "t.geojson: feature 0 (line 1, column 68): height 1200 m (from building:levels) is out of range (must be > 0 and <= 1000 m)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}", "{\"min_height\":\"18\"}",
      "t.geojson: feature 0 (line 1, column 68): min_height 18 m is not below height 12 m (the default)" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}", "{\"albedo\":1.5}",
      "t.geojson: feature 0 (line 1, column 68): albedo 1.5 is outside 0..1" },
    { "{\"type\":\"LineString\",\"coordinates\":[[0,0],[1,0]]}", "{\"id\":\"way/7\"}",
      "t.geojson: feature 0 (way/7, line 1, column 68): geometry type \"LineString\" is not used in scenes (Polygon, MultiPolygon or Point)" },
    { "null", "{\"id\":7}",
      "t.geojson: feature 0 (7, line 1, column 68): has no geometry object" },
    { "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[10,0],[10,10],[0,10]],[[20,20],[21,20],[21,21]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): inner ring 1 is not inside the outer ring" },
    { "{\"type\":\"Point\",\"coordinates\":[0,0]}", "{\"lamp\":true,\"radius\":-3}",
      "t.geojson: feature 0 (line 1, column 68): lamp radius -3 m is out of range (> 0 and <= 100000 m)" },
    { "{\"type\":\"Point\",\"coordinates\":[0,0]}", "{\"lamp\":true,\"z\":-1}",
      "t.geojson: feature 0 (line 1, column 68): lamp z -1 m is out of range (0 to 1000 m)" },
    { "{\"type\":\"Point\",\"coordinates\":[0,0]}", "{\"lamp\":true,\"intensity\":-5}",
      "t.geojson: feature 0 (line 1, column 68): lamp intensity -5 cd is negative, not finite or above 1e12 cd" },
    /* helper-65: 1e308 cd made E_indirect inf */
    { "{\"type\":\"Point\",\"coordinates\":[0,0]}", "{\"lamp\":true,\"intensity\":1e308}",
      "t.geojson: feature 0 (line 1, column 68): lamp intensity 1e308 cd is negative, not finite or above 1e12 cd" },
    { "{\"type\":\"MultiPolygon\",\"coordinates\":[[[[0,0],[1,0],[1,1]]],[[[5,5],[6,5]]]]}", "{}",
      "t.geojson: feature 0 (line 1, column 68): polygon 1: outer ring has 2 distinct vertices (a ring needs at least 3)" },
};

static char *collection_of(const bad_case *c)
{
    static const char head[] = "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[";
    size_t n = strlen(head) + strlen(c->geometry) + strlen(c->props) + 200;
    char *s = malloc(n);
    snprintf(s, n, "%s{\"type\":\"Feature\",\"properties\":%s,\"geometry\":%s}]}", head, c->props, c->geometry);
    return s;
}

static void test_bad_features_strict(void **state)
{
    size_t i;
    (void)state;
    for (i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
        fixture_log *f = fixture_open(1, MEM);
        char *json = collection_of(&bad_cases[i]);
        plx_status st = load_str(f, json);
        if (st != PLX_E_SCENE || strcmp(plx_last_error(f->e), bad_cases[i].message) != 0)
            fail_msg("case %zu: status %d, message\n  got:  %s\n  want: %s", i, st,
                     plx_last_error(f->e), bad_cases[i].message);
        free(json);
        fixture_close(f);
    }
}

static void test_bad_features_skipped(void **state)
{
    char want[512];
    size_t i;
    (void)state;
    for (i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
        fixture_log *f = fixture_open(0, MEM);
        char *json = collection_of(&bad_cases[i]);
        plx_scene_info si;
        assert_int_equal(load_str(f, json), PLX_OK);
        assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
        assert_int_equal(si.skipped_features, 1);
        assert_int_equal(si.buildings + si.lamps, 0);
        /* the strict load's message, and that the feature was dropped */
        snprintf(want, sizeof want, "%s; left out", bad_cases[i].message);
        assert_string_equal(f->book.last, want);
        free(json);
        fixture_close(f);
    }
}

/* ---- malformed JSON and the collection itself ------------------------------------ */

static void test_malformed_json(void **state)
{
    fixture_log *f = fixture_open(0, MEM);
    (void)state;
    assert_int_equal(load_str(f, "{\"type\": \"FeatureCollection\",\n  \"features\": [1, 2,, 3]}"), PLX_E_PARSE);
    assert_string_equal(plx_last_error(f->e), "t.geojson: malformed JSON at byte 50 (line 2, column 21)");
    assert_int_equal(load_str(f, "{\"type\": \"FeatureCollection\", \"features\": ["), PLX_E_PARSE);
    assert_string_equal(plx_last_error(f->e),
                        "t.geojson: malformed JSON at byte 43 (line 1, column 44): the text ends early");
    assert_int_equal(load_str(f, "{\"a\": NaN}"), PLX_E_PARSE);
    assert_int_equal(load_str(f, "{} x"), PLX_E_PARSE);
    assert_string_equal(plx_last_error(f->e), "t.geojson: malformed JSON at byte 3 (line 1, column 4)");
    assert_int_equal(load_str(f, "[1]"), PLX_E_SCENE);
    assert_string_equal(plx_last_error(f->e),
                        "t.geojson: the top-level value is not a JSON object (expected a GeoJSON FeatureCollection)");
    assert_int_equal(load_str(f, "{\"type\":\"Feature\"}"), PLX_E_SCENE);
    assert_int_equal(load_str(f, "{\"type\":\"FeatureCollection\"}"), PLX_E_SCENE);
    assert_string_equal(plx_last_error(f->e), "t.geojson: the FeatureCollection has no \"features\" array");
    assert_int_equal(load_str(f, "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"ft\"},\"features\":[]}"),
                     PLX_E_SCENE);
    /* after all that the engine still loads a good scene */
    assert_int_equal(plx_load_file(f->e, "fixtures/tiny.geojson"), PLX_OK);
    fixture_close(f);
}

static void test_deep_nesting(void **state)
{
    fixture_log *f = fixture_open(0, MEM);
    size_t n = 100000, i;
    char *s = malloc(2 * n + 1);
    (void)state;
    for (i = 0; i < n; i++) {
        s[i] = '[';
        s[n + i] = ']';
    }
    s[2 * n] = '\0';
    assert_int_equal(load_str(f, s), PLX_E_PARSE);
    free(s);
    fixture_close(f);
}

/* ---- numbers in properties ----------------------------------------------------------- */

static void test_number_strings(void **state)
{
    static const struct { const char *value; double height; int warns; } cases[] = {
        { "12", 12.0, 0 }, { "\"12\"", 12.0, 0 }, { "\"12.5 m\"", 12.5, 0 }, { "\"12.5m\"", 12.5, 0 },
        { "\" 7 \"", 7.0, 0 }, { "\"3;4\"", 12.0, 1 }, { "\"tall\"", 12.0, 1 }, { "\"12,5\"", 12.0, 1 },
        { "true", 12.0, 1 }, { "null", 12.0, 0 }, { "\"1e1\"", 10.0, 0 },
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        fixture_log *f = fixture_open(0, MEM);
        char json[512];
        plx_building b;
        snprintf(json, sizeof json,
                 "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                 "{\"type\":\"Feature\",\"properties\":{\"height\":%s},\"geometry\":"
                 "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}}]}", cases[i].value);
        assert_int_equal(load_str(f, json), PLX_OK);
        assert_int_equal(plx_building_get(f->e, 0, &b), PLX_OK);
        if (b.height != cases[i].height || (int)plx_warning_count(f->e) != cases[i].warns)
            fail_msg("height %s: got %g with %u warnings", cases[i].value, b.height, plx_warning_count(f->e));
        if (cases[i].warns)
            assert_non_null(strstr(f->book.last, "property \"height\" is not a number"));
        fixture_close(f);
    }
}

/* ---- memory: fault injection at every allocation, budgets, no port --------------- */

static void fault_inject_file(const char *path)
{
    fixture_log *f = fixture_open(0, MEM);
    plx_memory_report before, after;
    uint64_t k;
    plx_status st = PLX_E_NOMEM;
    plx_memory_get(f->e, &before);
    for (k = 1; st == PLX_E_NOMEM; k++) {
        plx_debug_fail_alloc(f->e, k);
        st = plx_load_file(f->e, path);
        plx_memory_get(f->e, &after);
        if (st == PLX_E_NOMEM) {
            assert_non_null(strstr(plx_last_error(f->e), "out of memory"));
            /* nothing leaked: the arena is back where it started */
            assert_int_equal(after.used_total, before.used_total);
        }
        assert_true(k < 1000000);
    }
    assert_int_equal(st, PLX_OK);
    assert_true(k > 3);
    plx_debug_fail_alloc(f->e, 0);
    assert_int_equal(plx_load_file(f->e, path), PLX_OK);
    fixture_close(f);
}

static void test_fault_injection_tiny(void **state)
{
    (void)state;
    fault_inject_file("fixtures/tiny.geojson");
}

static void test_fault_injection_eixample(void **state)
{
    (void)state;
    /* thousands of loads: skipped in the quick mode used under valgrind,
     * where the tiny fixture and tests/unit/test_corpus.c cover every path */
    if (getenv("PLX_TEST_QUICK"))
        skip();
    fault_inject_file("fixtures/eixample-4x4.geojson");
}

static void test_small_budget(void **state)
{
    void *mem = malloc(1u << 16);
    plx_engine *e;
    plx_config cfg;
    char *text;
    size_t len;
    char err[256];
    (void)state;
    plx_config_default(&cfg);
    assert_int_equal(plx_engine_create(mem, 1u << 16, &cfg, &e), PLX_OK);
    text = port_read_text("fixtures/helsinki-centre.geojson", &len, err, sizeof err);
    assert_non_null(text);
    assert_int_equal(plx_load_geojson(e, text, len, "h"), PLX_E_NOMEM);
    /* no parse tree: the first thing that does not fit is the scene itself */
    assert_non_null(strstr(plx_last_error(e), "out of memory while loading the scene: part 'scene' asked for"));
    /* a per-part budget: the scene part may not exceed 1000 bytes */
    plx_engine_destroy(e);
    free(mem);
    mem = malloc(MEM);
    cfg.part_budget[PLX_PART_SCENE] = 1000;
    assert_int_equal(plx_engine_create(mem, MEM, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_geojson(e, text, len, "h"), PLX_E_NOMEM);
    assert_non_null(strstr(plx_last_error(e), "part 'scene' asked for"));
    assert_non_null(strstr(plx_last_error(e), "(its budget is 1000 bytes)"));
    plx_engine_destroy(e);
    free(mem);
    free(text);
}

static void test_no_port(void **state)
{
    void *mem = malloc(MEM);
    plx_engine *e;
    plx_scene_info si;
    const char *json = "{\"type\":\"FeatureCollection\",\"features\":[]}";
    (void)state;
    assert_int_equal(plx_engine_create(mem, MEM, NULL, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, "fixtures/tiny.geojson"), PLX_E_UNSUPPORTED);
    assert_int_equal(plx_load_geojson(e, json, strlen(json), NULL), PLX_OK);
    assert_int_equal(plx_scene_info_get(e, &si), PLX_OK);
    assert_int_equal(si.buildings, 0);
    assert_int_equal(si.load_ns, 0);
    plx_engine_destroy(e);
    assert_int_equal(plx_engine_create(mem, 100, NULL, &e), PLX_E_INVALID);
    assert_int_equal(plx_engine_create(NULL, MEM, NULL, &e), PLX_E_INVALID);
    free(mem);
}

static void test_two_engines(void **state)
{
    fixture_log *a = fixture_open(0, MEM), *b = fixture_open(0, MEM);
    plx_scene_info sa, sb;
    (void)state;
    assert_int_equal(plx_load_file(a->e, "fixtures/tiny.geojson"), PLX_OK);
    assert_int_equal(plx_load_file(b->e, "fixtures/grid-4x4.geojson"), PLX_OK);
    assert_int_equal(plx_scene_info_get(a->e, &sa), PLX_OK);
    assert_int_equal(plx_scene_info_get(b->e, &sb), PLX_OK);
    assert_int_equal(sa.buildings, 4);
    assert_int_equal(sb.buildings, 16);
    assert_int_equal(load_str(a, "{"), PLX_E_PARSE);
    assert_int_equal(plx_scene_info_get(a->e, &sa), PLX_E_NOSCENE);
    assert_int_equal(plx_scene_info_get(b->e, &sb), PLX_OK);
    fixture_close(a);
    fixture_close(b);
}

/* ---- generated and real districts ------------------------------------------------- */

static void test_eixample_blocks(void **state)
{
    fixture_log *f = fixture_open(0, MEM);
    plx_scene_info si;
    uint32_t i;
    (void)state;
    assert_int_equal(plx_load_file(f->e, "fixtures/eixample-4x4.geojson"), PLX_OK);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.buildings, 16 * 16);
    assert_int_equal(si.blocks, 16);
    assert_int_equal(si.courtyards, 16);
    assert_int_equal(si.overlapping_pairs, 0);
    for (i = 0; i < si.blocks; i++) {
        plx_block k;
        assert_int_equal(plx_block_get(f->e, i, &k), PLX_OK);
        assert_int_equal(k.nbuildings, 16);
        assert_int_equal(k.nrings, 2);
    }
    fixture_close(f);
}

static void test_helsinki(void **state)
{
    fixture_log *f = fixture_open(0, MEM);
    plx_scene_info si;
    (void)state;
    assert_int_equal(plx_load_file(f->e, "fixtures/helsinki-centre.geojson"), PLX_OK);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.lonlat, 1);
    /* 444 building features, 4 church parts invalid (min_height 18, default
     * height 12); the MultiPolygon's parts count one building each */
    assert_int_equal(si.skipped_features, 4);
    assert_true(si.buildings >= 440);
    assert_int_equal(si.skipped_lamps, 2);
    assert_int_equal(si.lamps, 584);
    /* The data README counts 11 pairs overlapping by more than a few cm; 4 of
     * them involve the skipped church towers. An independent check (sampling
     * every pair's box intersection on a 10 cm grid, outside this suite)
     * found 7 pairs overlapping by 2.2 m^2 or more among the loaded
     * buildings, and the next largest only 0.43 m^2 (a sliver of a few cm). */
    assert_int_equal(si.overlapping_pairs, 7);
    assert_non_null(strstr(f->book.all, "(way/234871779, line "));
    assert_non_null(strstr(f->book.all, "min_height 18 m is not below height 12 m (the default)"));
    fixture_close(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tiny_counts),
        cmocka_unit_test(test_tiny_rings_and_blocks),
        cmocka_unit_test(test_lonlat_projection),
        cmocka_unit_test(test_bad_features_strict),
        cmocka_unit_test(test_bad_features_skipped),
        cmocka_unit_test(test_malformed_json),
        cmocka_unit_test(test_deep_nesting),
        cmocka_unit_test(test_number_strings),
        cmocka_unit_test(test_fault_injection_tiny),
        cmocka_unit_test(test_fault_injection_eixample),
        cmocka_unit_test(test_small_budget),
        cmocka_unit_test(test_no_port),
        cmocka_unit_test(test_two_engines),
        cmocka_unit_test(test_eixample_blocks),
        cmocka_unit_test(test_helsinki),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
