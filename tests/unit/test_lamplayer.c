/* Lamp layers (plx_add_lamps) and the scene CRS (plx_scene_crs): lamps
 * added after the load light the scene exactly as the same lamps written
 * into the scene file (metres and lon/lat); buried lamps are left out and
 * lamps at the same position merged, as at load; the call is refused once
 * light was computed; a failed call adds nothing. */
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

#define MEM (32u << 20)

static const char *bld_m =
    "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
    "{\"type\":\"Feature\",\"properties\":{\"id\":\"A\",\"height\":10},"
    "\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}}";

static plx_engine *load(const char *json, int strict, void **mem)
{
    plx_engine *e;
    plx_config cfg;
    plx_config_default(&cfg);
    cfg.strict = strict;
    *mem = malloc(MEM);
    assert_int_equal(plx_engine_create(*mem, MEM, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_geojson(e, json, strlen(json), "t"), PLX_OK);
    return e;
}

static void done(plx_engine *e, void *mem)
{
    plx_engine_destroy(e);
    free(mem);
}

static void lamp(plx_lamp *l, double x, double y, double z, double I)
{
    memset(l, 0, sizeof *l);
    l->x = x;
    l->y = y;
    l->z = z;
    l->intensity = I;
    l->radius = 30;
    l->color[0] = l->color[1] = l->color[2] = 1.0f;
}

/* E at ground points of a grid around the building. */
static void grid_E(plx_engine *e, double x0, double y0, double *E)
{
    int i;
    for (i = 0; i < 100; i++) {
        double P[3], N[3] = { 0, 0, 1 };
        P[0] = x0 - 15 + 4.1 * (i % 10);
        P[1] = y0 - 15 + 4.1 * (i / 10);
        P[2] = 0;
        if (plx_illuminance(e, 1, P, N, &E[i], NULL, NULL) != PLX_OK)
            E[i] = -1; /* inside the building: the same in both scenes */
    }
}

static void test_layer_equals_scene_lamps_metres(void **state)
{
    char json[2048];
    void *m1, *m2;
    plx_engine *a, *b;
    plx_lamp l[2];
    plx_scene_info si;
    double Ea[100], Eb[100];
    int i;
    (void)state;
    snprintf(json, sizeof json, "%s,{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":6,\"intensity\":800,"
             "\"radius\":30,\"color\":[1,1,1]},\"geometry\":{\"type\":\"Point\",\"coordinates\":[15,5]}},"
             "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":4,\"intensity\":500,\"radius\":30,"
             "\"color\":[1,1,1]},\"geometry\":{\"type\":\"Point\",\"coordinates\":[-5,12]}}]}", bld_m);
    a = load(json, 0, &m1);
    snprintf(json, sizeof json, "%s]}", bld_m);
    b = load(json, 0, &m2);
    lamp(&l[0], 15, 5, 6, 800);
    lamp(&l[1], -5, 12, 4, 500);
    assert_int_equal(plx_add_lamps(b, l, 2, "layer"), PLX_OK);
    plx_scene_info_get(b, &si);
    assert_int_equal(si.lamps, 2);
    grid_E(a, 5, 5, Ea);
    grid_E(b, 5, 5, Eb);
    for (i = 0; i < 100; i++)
        assert_true(Ea[i] == Eb[i]);
    assert_true(Ea[0] > 0 || Ea[55] > 0);
    done(a, m1);
    done(b, m2);
}

static void test_layer_lonlat_projected_as_scene(void **state)
{
    static const char *bld_ll =
        "{\"type\":\"FeatureCollection\",\"features\":["
        "{\"type\":\"Feature\",\"properties\":{\"height\":10},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":"
        "[[[24.9400,60.1700],[24.9402,60.1700],[24.9402,60.1701],[24.9400,60.1701],[24.9400,60.1700]]]}}";
    char json[2048];
    void *m1, *m2;
    plx_engine *a, *b;
    plx_lamp l, la, lb;
    (void)state;
    snprintf(json, sizeof json, "%s,{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"color\":[1,1,1]},"
             "\"geometry\":{\"type\":\"Point\",\"coordinates\":[24.9403,60.17005]}}]}", bld_ll);
    a = load(json, 0, &m1);
    snprintf(json, sizeof json, "%s]}", bld_ll);
    b = load(json, 0, &m2);
    lamp(&l, 24.9403, 60.17005, 6, 1000);
    assert_int_equal(plx_add_lamps(b, &l, 1, NULL), PLX_OK);
    assert_int_equal(plx_lamp_get(a, 0, &la), PLX_OK);
    assert_int_equal(plx_lamp_get(b, 0, &lb), PLX_OK);
    { /* the same lon/lat back (each scene projects about its own centre) */
        plx_scene_info sa, sb;
        double ca, cb;
        plx_scene_info_get(a, &sa);
        plx_scene_info_get(b, &sb);
        ca = cos(sa.lat0 * 3.14159265358979323846 / 180.0);
        cb = cos(sb.lat0 * 3.14159265358979323846 / 180.0);
        assert_true(fabs(sa.lon0 + la.x / (111320.0 * ca) - 24.9403) < 1e-12);
        assert_true(fabs(sb.lon0 + lb.x / (111320.0 * cb) - 24.9403) < 1e-12);
        assert_true(fabs(sb.lat0 + lb.y / 110540.0 - 60.17005) < 1e-12);
        assert_true(fabs(lb.x - (24.9403 - 24.9401) * 111320.0 * cb) < 1e-6);
    }
    lamp(&l, 2000.0, 10.0, 6, 1000); /* not lon/lat: left out */
    assert_int_equal(plx_add_lamps(b, &l, 1, NULL), PLX_OK);
    {
        plx_scene_info si;
        plx_scene_info_get(b, &si);
        assert_int_equal(si.lamps, 1);
        assert_int_equal(si.skipped_lamps, 0);
        assert_int_equal(plx_warning_count(b), 1);
    }
    done(a, m1);
    done(b, m2);
}

static void test_buried_and_duplicates(void **state)
{
    char json[2048];
    void *mem;
    plx_engine *e;
    plx_lamp l[5], got;
    plx_scene_info si;
    uint32_t w0;
    (void)state;
    snprintf(json, sizeof json, "%s,{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"id\":\"S\"},"
             "\"geometry\":{\"type\":\"Point\",\"coordinates\":[20,20]}}]}", bld_m);
    e = load(json, 0, &mem);
    w0 = plx_warning_count(e);
    lamp(&l[0], 5, 5, 6, 1000);          /* inside A (10 m tall): left out */
    lamp(&l[1], 20.0004, 20, 6, 1000);   /* the scene's lamp S: merged */
    lamp(&l[2], 30, 30, 6, 1000);
    lamp(&l[3], 30, 30.0002, 7, 900);    /* the layer's own duplicate: merged */
    lamp(&l[4], 5, 5, 12, 1000);         /* above A: kept */
    l[2].id = "keep";
    assert_int_equal(plx_add_lamps(e, l, 5, "layer"), PLX_OK);
    plx_scene_info_get(e, &si);
    assert_int_equal(si.lamps, 3);
    assert_int_equal(si.skipped_lamps, 1);
    assert_int_equal(plx_warning_count(e) - w0, 3);
    assert_int_equal(plx_lamp_get(e, 1, &got), PLX_OK);
    assert_true(got.x == 30 && got.y == 30 && got.intensity == 1000);
    assert_string_equal(got.id, "keep");
    assert_true(got.id != l[2].id); /* copied */
    assert_int_equal(plx_lamp_get(e, 2, &got), PLX_OK);
    assert_true(got.z == 12);
    done(e, mem);
}

static void test_refused_after_light_and_strict(void **state)
{
    char json[2048];
    void *mem;
    plx_engine *e;
    plx_lamp l[2];
    plx_scene_info si;
    double P[3] = { 20, 20, 0 }, N[3] = { 0, 0, 1 }, E;
    (void)state;
    snprintf(json, sizeof json, "%s]}", bld_m);
    e = load(json, 1, &mem);
    lamp(&l[0], 20, 20, 6, 1000);
    lamp(&l[1], 5, 5, 6, 1000); /* buried: strict fails, nothing added */
    assert_int_equal(plx_add_lamps(e, l, 2, "layer"), PLX_E_SCENE);
    assert_non_null(strstr(plx_last_error(e), "layer: feature 0"));
    plx_scene_info_get(e, &si);
    assert_int_equal(si.lamps, 0);
    l[1].radius = -1; /* out of range: strict fails */
    assert_int_equal(plx_add_lamps(e, l, 2, "layer"), PLX_E_SCENE);
    assert_non_null(strstr(plx_last_error(e), "radius"));
    assert_int_equal(plx_add_lamps(e, l, 1, "layer"), PLX_OK);
    assert_int_equal(plx_illuminance(e, 1, P, N, &E, NULL, NULL), PLX_OK);
    assert_true(E > 0);
    assert_int_equal(plx_add_lamps(e, l, 1, "layer"), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(e), "already computed"));
    assert_int_equal(plx_add_lamps(e, NULL, 1, "layer"), PLX_E_INVALID);
    done(e, mem);
}

static void test_nomem_adds_nothing(void **state)
{
    char json[2048];
    void *mem;
    plx_engine *e;
    plx_lamp l[3];
    plx_scene_info si;
    uint64_t k;
    (void)state;
    snprintf(json, sizeof json, "%s]}", bld_m);
    e = load(json, 0, &mem);
    lamp(&l[0], 20, 20, 6, 1000);
    lamp(&l[1], 30, 20, 6, 1000);
    lamp(&l[2], 40, 20, 6, 1000);
    l[1].id = "x";
    for (k = 1; k < 100; k++) {
        plx_status st;
        plx_debug_fail_alloc(e, k);
        st = plx_add_lamps(e, l, 3, NULL);
        plx_debug_fail_alloc(e, 0);
        plx_scene_info_get(e, &si);
        if (st == PLX_OK) {
            assert_int_equal(si.lamps, 3);
            break;
        }
        assert_int_equal(st, PLX_E_NOMEM);
        assert_int_equal(si.lamps, 0);
    }
    assert_true(k > 1 && k < 100);
    done(e, mem);
}

static void test_crs_kept(void **state)
{
    static const char *j1 =
        "{\"type\":\"FeatureCollection\",\"crs\":{\"type\":\"name\",\"properties\":{\"name\":"
        "\"urn:ogc:def:crs:EPSG::2154\"}},\"features\":[{\"type\":\"Feature\",\"properties\":{\"height\":10},"
        "\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[650000,6860000],[650010,6860000],[650010,6860010],"
        "[650000,6860000]]]}}]}";
    static const char *j2 = "{\"type\":\"FeatureCollection\",\"properties\":{\"crs\":\"EPSG:4326\"},\"features\":[]}";
    void *mem;
    plx_engine *e;
    plx_scene_info si;
    (void)state;
    e = load(j1, 1, &mem); /* strict: no warning about metres without units */
    assert_string_equal(plx_scene_crs(e), "urn:ogc:def:crs:EPSG::2154");
    plx_scene_info_get(e, &si);
    assert_int_equal(si.lonlat, 0);
    assert_true(si.bounds[0] == 650000 - 50.0);
    assert_int_equal(plx_load_geojson(e, j2, strlen(j2), "t"), PLX_OK);
    assert_string_equal(plx_scene_crs(e), "EPSG:4326");
    assert_int_equal(plx_load_geojson(e, bld_m, strlen(bld_m), "t"), PLX_E_PARSE);
    assert_null(plx_scene_crs(e));
    done(e, mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layer_equals_scene_lamps_metres),
        cmocka_unit_test(test_layer_lonlat_projected_as_scene),
        cmocka_unit_test(test_buried_and_duplicates),
        cmocka_unit_test(test_refused_after_light_and_strict),
        cmocka_unit_test(test_nomem_adds_nothing),
        cmocka_unit_test(test_crs_kept),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
