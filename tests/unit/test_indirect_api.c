/* The public indirect-light API: nothing before the first frame, a positive
 * and deterministic E_indirect after, reset, its RGB version, the render
 * hook, nightify, and
 * memory exhaustion while creating the photon buffers. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "fixture.h"

#define MEM (128u << 20)

static plx_engine *open_tiny(void **mem)
{
    return fixture_file("fixtures/tiny.geojson", MEM, mem);
}

static void test_frames_and_values(void **state)
{
    void *m1, *m2;
    plx_engine *a = open_tiny(&m1), *b = open_tiny(&m2);
    /* a courtyard ground point under lamp L2 and a courtyard wall facing in */
    double P[6] = { 50, 10, 0, 45, 10, 3 }, N[6] = { 0, 0, 1, 1, 0, 0 }, Ed[2], Ei[2], Eb[2], Ebi[2];
    int k;
    (void)state;
    assert_int_equal(plx_illuminance(a, 2, P, N, Ed, Ei, NULL), PLX_OK);
    assert_true(Ei[0] == 0.0 && Ei[1] == 0.0);
    assert_int_equal(plx_indirect_frames(a), 0);
    for (k = 0; k < 4; k++) {
        assert_int_equal(plx_indirect_step(a, 20000, (uint64_t)k + 1), PLX_OK);
        assert_int_equal(plx_indirect_step(b, 20000, (uint64_t)k + 1), PLX_OK);
    }
    assert_int_equal(plx_indirect_frames(a), 4);
    assert_int_equal(plx_illuminance(a, 2, P, N, Ed, Ei, NULL), PLX_OK);
    assert_int_equal(plx_illuminance(b, 2, P, N, Eb, Ebi, NULL), PLX_OK);
    /* light bounces off the courtyard's walls and ground: both get some */
    assert_true(Ei[0] > 0.0 && Ei[1] > 0.0);
    /* the 10 x 10 m courtyard with 12 m walls of albedo 0.5 is nearly a
     * closed box, whose indirect/direct ratio is at most rho / (1 - rho) = 1 */
    assert_true(Ei[0] < Ed[0]);
    /* deterministic */
    assert_true(Ei[0] == Ebi[0] && Ei[1] == Ebi[1]);
    assert_int_equal(plx_indirect_reset(a), PLX_OK);
    assert_int_equal(plx_indirect_frames(a), 0);
    assert_int_equal(plx_illuminance(a, 2, P, N, Ed, Ei, NULL), PLX_OK);
    assert_true(Ei[0] == 0.0);
    assert_int_equal(plx_indirect_step(a, 0, 1), PLX_E_INVALID);
    plx_engine_destroy(a);
    plx_engine_destroy(b);
    free(m1);
    free(m2);
}

/* plx_indirect_rgb: the same scalar as plx_illuminance, and colour per
 * channel: tiny's lamps are white (L2) or (1, 0.62, 0.28), so red equals
 * the scalar bit for bit and green and blue lie between the two colours. */
static void test_indirect_rgb(void **state)
{
    void *mem;
    plx_engine *e = open_tiny(&mem);
    double P[9] = { 50, 10, 0, 45, 10, 3, 50, 10, -5 }, N[9] = { 0, 0, 1, 1, 0, 0, 0, 0, 1 };
    double Ed[2], Ei[2], Ej[3], rgb[9];
    int k;
    (void)state;
    assert_int_equal(plx_indirect_rgb(e, 2, P, N, Ej, rgb), PLX_OK);
    for (k = 0; k < 6; k++)
        assert_true(rgb[k] == 0.0);
    assert_int_equal(plx_indirect_step(e, 20000, 1), PLX_OK);
    assert_int_equal(plx_indirect_step(e, 20000, 2), PLX_OK);
    assert_int_equal(plx_illuminance(e, 2, P, N, Ed, Ei, NULL), PLX_OK);
    assert_int_equal(plx_indirect_rgb(e, 2, P, N, Ej, rgb), PLX_OK);
    for (k = 0; k < 2; k++) {
        double *c = rgb + 3 * k;
        assert_true(Ej[k] == Ei[k] && Ei[k] > 0.0);
        assert_true(c[0] == Ei[k]);
        assert_true(c[1] >= 0.62 * Ei[k] * (1 - 1e-6) && c[1] <= Ei[k] * (1 + 1e-6));
        assert_true(c[2] >= 0.28 * Ei[k] * (1 - 1e-6) && c[2] <= c[1]);
    }
    /* E_indirect may be NULL; rgb may not */
    assert_int_equal(plx_indirect_rgb(e, 1, P, N, NULL, rgb), PLX_OK);
    assert_int_equal(plx_indirect_rgb(e, 1, P, N, Ej, NULL), PLX_E_INVALID);
    /* a point under the ground: NaN and PLX_E_RANGE, the others filled */
    assert_int_equal(plx_indirect_rgb(e, 3, P, N, Ej, rgb), PLX_E_RANGE);
    assert_true(isnan(Ej[2]) && isnan(rgb[6]) && isnan(rgb[8]) && rgb[0] == Ei[0]);
    plx_engine_destroy(e);
    free(mem);
}

static void test_render_hook(void **state)
{
    void *mem;
    plx_engine *e = open_tiny(&mem);
    plx_camera cam = { { 30, 30, 1.7 }, { 50, 10, 2 }, 60, 64, 48 };
    plx_render_opts o;
    float with[64 * 48 * 3], without[64 * 48 * 3];
    double sum_with = 0, sum_without = 0;
    int i;
    (void)state;
    plx_render_opts_default(&o);
    o.no_glow = 1;
    o.per_pixel = 1; /* the same exact direct light in both: shaded at every pixel */
    assert_int_equal(plx_indirect_step(e, 20000, 1), PLX_OK);
    assert_int_equal(plx_render(e, &cam, &o, NULL, with, NULL), PLX_OK);
    o.no_indirect = 1;
    assert_int_equal(plx_render(e, &cam, &o, NULL, without, NULL), PLX_OK);
    for (i = 0; i < 64 * 48 * 3; i++) {
        assert_true(with[i] >= without[i]);
        sum_with += with[i];
        sum_without += without[i];
    }
    assert_true(sum_with > sum_without);
    plx_engine_destroy(e);
    free(mem);
}

static void test_nightify(void **state)
{
    uint8_t day[4 * 3] = { 10, 10, 10, 20, 20, 20, 30, 30, 30, 40, 40, 40 };
    uint8_t night[4 * 3] = { 0, 0, 0, 100, 50, 20, 200, 100, 40, 250, 125, 50 };
    uint8_t out[12];
    (void)state;
    /* with the black pixel left out, the three brightest night colours remain */
    assert_int_equal(plx_nightify(day, 4, night, 4, 10.0, out), PLX_OK);
    assert_true(out[0] == 100 && out[1] == 50 && out[2] == 20);
    assert_true(out[9] == 250 && out[10] == 125 && out[11] == 50);
    assert_int_equal(plx_nightify(day, 0, night, 4, 10.0, out), PLX_E_INVALID);
}

static void test_nomem(void **state)
{
    void *mem;
    plx_engine *e = open_tiny(&mem);
    plx_memory_report before, after;
    plx_status st = PLX_E_NOMEM;
    uint64_t k;
    (void)state;
    plx_memory_get(e, &before);
    for (k = 1; st == PLX_E_NOMEM; k++) {
        plx_debug_fail_alloc(e, k);
        st = plx_indirect_step(e, 1000, 1);
        if (st == PLX_E_NOMEM) {
            plx_memory_get(e, &after);
            assert_int_equal(after.used_total, before.used_total);
            assert_non_null(strstr(plx_last_error(e), "creating the photon buffers"));
        }
    }
    assert_int_equal(st, PLX_OK);
    assert_true(k > 3);
    plx_debug_fail_alloc(e, 0);
    plx_engine_destroy(e);
    free(mem);
}

/* Arguments the API used to take and go wrong with later or silently:
 * a render maximum beyond the rasteriser's (refused at the first frame
 * with no reason), a fixed exposure of 0 or less (a black frame), a NaN
 * eye for the refinement (lamps refined around NaN); and the frame's
 * report of an eye inside a building. */
static void test_refusals(void **state)
{
    static unsigned char blk[1 << 16];
    plx_config cfg;
    plx_engine *e;
    plx_render_opts o;
    plx_render_info info;
    plx_refine_stats rs;
    plx_camera in = { { 5, 5, 3 }, { 15, 6, 3 }, 60, 32, 24 }, out = { { -5, -5, 1.7 }, { 5, 5, 1 }, 60, 32, 24 }, bad;
    double nan_eye[3] = { 0.0, 0.0, 1.7 };
    uint8_t rgb[32 * 24 * 3];
    void *mem;
    (void)state;
    plx_config_default(&cfg);
    cfg.render_max_width = -1;
    assert_int_equal(plx_engine_create(blk, sizeof blk, &cfg, &e), PLX_E_INVALID);
    cfg.render_max_width = PLX_RENDER_MAX_DIM + 1;
    assert_int_equal(plx_engine_create(blk, sizeof blk, &cfg, &e), PLX_E_INVALID);
    cfg.render_max_width = PLX_RENDER_MAX_DIM;
    cfg.render_max_height = PLX_RENDER_MAX_DIM + 1;
    assert_int_equal(plx_engine_create(blk, sizeof blk, &cfg, &e), PLX_E_INVALID);
    cfg.render_max_height = PLX_RENDER_MAX_DIM;
    cfg.threads = -3; /* threads outside 0 .. PLX_MAX_THREADS were taken (2026-12-03, an embedder's pass) */
    assert_int_equal(plx_engine_create(blk, sizeof blk, &cfg, &e), PLX_E_INVALID);
    cfg.threads = PLX_MAX_THREADS + 1;
    assert_int_equal(plx_engine_create(blk, sizeof blk, &cfg, &e), PLX_E_INVALID);
    cfg.threads = PLX_MAX_THREADS;
    assert_int_equal(plx_engine_create(blk, sizeof blk, &cfg, &e), PLX_OK);
    plx_engine_destroy(e);

    e = open_tiny(&mem);
    plx_render_opts_default(&o);
    o.no_indirect = 1;
    o.exposure = 0.0;
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, NULL), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(e), "exposure must be a finite number above 0"));
    o.exposure = -1.0;
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, NULL), PLX_E_INVALID);
    o.auto_exposure = PLX_EXPOSURE_ADAPT; /* held from exposure: it must be one */
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, NULL), PLX_E_INVALID);
    o.auto_exposure = PLX_EXPOSURE_TONE;
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, NULL), PLX_E_INVALID);
    o.auto_exposure = 7;
    o.exposure = 1.0;
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, NULL), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(e), "auto_exposure must be PLX_EXPOSURE_FIXED, _AUTO, _ADAPT or _TONE"));
    o.auto_exposure = PLX_EXPOSURE_TONE; /* applied as given */
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, &info), PLX_OK);
    assert_true(info.exposure == 1.0);
    o.exposure = NAN;
    o.auto_exposure = 1; /* the fixed exposure is not read (NaN was refused deeper, as "near must be > 0") */
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, &info), PLX_OK);
    o.exposure = -1.0;
    assert_int_equal(plx_render(e, &out, &o, rgb, NULL, &info), PLX_OK);
    assert_int_equal(info.eye_inside, 0);
    /* an atlas spacing far below a centimetre laid out for minutes (0.001 m:
     * 133 s), NaN and negatives were taken as the default: refused */
    {
        const double spacing[] = { 0.001, 0.0099, -1.0, NAN, INFINITY, 2e4 };
        size_t k;
        for (k = 0; k < sizeof spacing / sizeof spacing[0]; k++) {
            o.aerial_m_per_texel = spacing[k];
            assert_int_equal(plx_render(e, &out, &o, rgb, NULL, NULL), PLX_E_INVALID);
            assert_non_null(strstr(plx_last_error(e), "aerial_m_per_texel must be 0 (the default) or 0.01 .. 1e4 m"));
        }
        o.aerial_m_per_texel = PLX_TEXEL_MIN;
        assert_int_equal(plx_render(e, &out, &o, rgb, NULL, NULL), PLX_OK);
        o.aerial_m_per_texel = 0.0;
    }
    assert_int_equal(plx_render(e, &in, &o, rgb, NULL, &info), PLX_OK);
    assert_int_equal(info.eye_inside, 1);

    /* bad cameras: what is wrong, with the values (it said "render_frame: ..." without them) */
    bad = out;
    bad.fov_deg = 0.0;
    assert_int_equal(plx_render(e, &bad, &o, rgb, NULL, NULL), PLX_E_INVALID);
    assert_string_equal(plx_last_error(e), "plx_render: fov_deg 0 is outside (0, 180) degrees");
    bad = out;
    bad.eye[2] = -2.5;
    assert_int_equal(plx_render(e, &bad, &o, rgb, NULL, NULL), PLX_E_INVALID);
    assert_string_equal(plx_last_error(e), "plx_render: the eye is at z = -2.5 m, not above the ground (z > 0)");
    bad = out;
    memcpy(bad.target, bad.eye, sizeof bad.eye);
    assert_int_equal(plx_render(e, &bad, &o, rgb, NULL, NULL), PLX_E_INVALID);
    assert_string_equal(plx_last_error(e),
                        "plx_render: the eye and the target are the same point (-5, -5, 1.7): the camera looks nowhere");
    bad = out;
    bad.target[1] = nan("");
    assert_int_equal(plx_render(e, &bad, &o, rgb, NULL, NULL), PLX_E_INVALID);
    assert_string_equal(plx_last_error(e), "plx_render: the camera's eye or target is not finite");

    assert_int_equal(plx_indirect_step(e, 2000, 1), PLX_OK);
    nan_eye[0] = nan("");
    assert_int_equal(plx_indirect_refine(e, nan_eye, &rs), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(e), "the eye must be finite"));
    nan_eye[0] = 0.0;
    nan_eye[2] = INFINITY;
    assert_int_equal(plx_indirect_refine(e, nan_eye, &rs), PLX_E_INVALID);
    /* the viewer's chart levels, the lamp choice and the getters: every
     * refusal says why (a NaN eye was taken, and NULL outs left the last
     * call's message) */
    {
        double eye[3] = { 5.0, 5.0, 1.7 }, dir[3] = { 1.0, 0.0, 0.0 }, zero[3] = { 0.0, 0.0, 0.0 };
        double box[4] = { 0.0, 0.0, 10.0, 10.0 };
        plx_lamp lamp;
        assert_int_equal(plx_indirect_set_viewer(e, nan_eye, dir, 60.0), PLX_E_INVALID);
        assert_string_equal(plx_last_error(e), "plx_indirect_set_viewer: the eye must be finite");
        assert_int_equal(plx_indirect_set_viewer(e, eye, zero, 60.0), PLX_E_INVALID);
        assert_non_null(strstr(plx_last_error(e), "dir must be finite and not zero"));
        assert_int_equal(plx_indirect_set_viewer(e, eye, dir, NAN), PLX_E_INVALID);
        assert_non_null(strstr(plx_last_error(e), "fov_deg must be finite"));
        assert_int_equal(plx_indirect_set_viewer(e, eye, dir, 60.0), PLX_OK);
        assert_int_equal(plx_indirect_set_viewer(e, eye, NULL, 0.0), PLX_OK); /* all around */
        assert_int_equal(plx_indirect_select_lamps(e, NULL, -1.0, NULL), PLX_E_INVALID);
        assert_int_equal(plx_indirect_select_lamps(e, box, NAN, NULL), PLX_E_INVALID);
        assert_int_equal(plx_lamp_get(e, 999999, &lamp), PLX_E_RANGE); /* a message to be replaced */
        assert_int_equal(plx_scene_info_get(e, NULL), PLX_E_INVALID);
        assert_string_equal(plx_last_error(e), "plx_scene_info_get: out is NULL");
        assert_int_equal(plx_indirect_info_get(e, NULL), PLX_E_INVALID);
        assert_string_equal(plx_last_error(e), "plx_indirect_info_get: out is NULL");
        assert_int_equal(plx_atlas_info_get(e, NULL), PLX_E_INVALID);
        assert_string_equal(plx_last_error(e), "plx_atlas_info_get: out is NULL");
        assert_int_equal(plx_render_max_get(e, NULL, NULL), PLX_E_INVALID);
        assert_string_equal(plx_last_error(e), "plx_render_max_get: w or h is NULL");
        /* a bake handed to the GeoJSON loader says what it is */
        assert_int_equal(plx_load_geojson(e, "PLXBAKE\0\1\2\3\4", 12, "city.plxb"), PLX_E_PARSE);
        assert_string_equal(plx_last_error(e), "city.plxb: a bake file (polarlux bake), not GeoJSON: load it with "
                                               "plx_bake_load or plx_bake_load_read");
    }
    fixture_done(e, mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frames_and_values),
        cmocka_unit_test(test_indirect_rgb),
        cmocka_unit_test(test_render_hook),
        cmocka_unit_test(test_nightify),
        cmocka_unit_test(test_nomem),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
