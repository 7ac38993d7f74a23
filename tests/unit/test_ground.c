/* ground: the ground's albedo from a day image (src/scene/ground.c, issue #6).
 *
 * The loader's properties.ground_image and ground_image_bounds (accepted,
 * every rejection with its exact message, strict and lenient, lon/lat
 * bounds projected by hand); the lookup at pixel centres, on pixel lines,
 * on the box's edges and outside it against an independent decoding of the
 * pixels (sRGB curve and mean-luminance scaling written here); the
 * normalisation to 1e-12; clamping; replacing, removing, bad arguments,
 * out of memory with the old image kept; photons dropped when the image
 * changes; a render of the fixture whose ground pixels are albedo / pi * E
 * per channel with E from plx_illuminance; and the photon tracer's ground
 * roulette: with a two-colour image the flux surviving ground bounces is
 * the first-hit flux (integrated numerically) times the albedo luminance
 * where it landed, and a uniform image gives the very same photons as no
 * image. */
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
#include <unistd.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "base/engine.h"
#include "base/arena.h"
#include "scene/blocks.h"
#include "scene/ground.h"
#include "photon/trace.h"
#include "photon/photon.h"
#include "ref_scene.h"
#include "png/image_write.h"

#define MEM (64u << 20)
#define PI 3.14159265358979323846

static int quick_mode(void)
{
    const char *v = getenv("PLX_TEST_QUICK");
    return v && v[0] && v[0] != '0';
}

/* A scene in metres with one building [0,10]^2 and a lamp; props is the
 * inside of the top-level properties object after "units". */
static plx_status load_props(fixture_log *f, const char *props)
{
    char json[2048];
    snprintf(json, sizeof json,
             "{\"type\": \"FeatureCollection\", \"properties\": {\"units\": \"m\"%s},\n"
             " \"features\": [\n"
             "  {\"type\": \"Feature\", \"properties\": {\"height\": 10}, \"geometry\": {\"type\": \"Polygon\",\n"
             "   \"coordinates\": [[[0, 0], [10, 0], [10, 10], [0, 10]]]}},\n"
             "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true}, \"geometry\": {\"type\": \"Point\",\n"
             "   \"coordinates\": [20, 5]}}]}",
             props);
    f->book.n = 0;
    f->book.all[0] = '\0';
    return plx_load_geojson(f->e, json, strlen(json), "t.geojson");
}

/* ---- the independent decoding of pixels --------------------------------- */

static double lin_ref(int v)
{
    double c = v / 255.0;
    if (c <= 0.04045)
        return c / 12.92;
    return exp(2.4 * log((c + 0.055) / 1.055));
}

static double lum_ref(const double c[3])
{
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

/* The scale ground_albedo / mean Y of an image of n pixels. */
static double scale_ref(const uint8_t *rgb, size_t n, double ground_albedo)
{
    double sum = 0.0;
    size_t i;
    for (i = 0; i < n; i++) {
        double c[3] = { lin_ref(rgb[3 * i]), lin_ref(rgb[3 * i + 1]), lin_ref(rgb[3 * i + 2]) };
        sum += lum_ref(c);
    }
    return ground_albedo / (sum / n);
}

static void albedo_ref(const uint8_t *px, double scale, double out[3])
{
    int c;
    for (c = 0; c < 3; c++) {
        out[c] = lin_ref(px[c]) * scale;
        if (out[c] > 0.95)
            out[c] = 0.95;
    }
}

static int near(double a, double b, double rel)
{
    return fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) + 1e-300;
}

/* ---- loader ---------------------------------------------------------------- */

static void test_loader_accepts(void **state)
{
    fixture_log *f = fixture_open(1, MEM);
    plx_ground_image_info gi;
    plx_scene_info si;
    double rgb[3];
    (void)state;
    assert_int_equal(load_props(f, ", \"ground_image\": \"day/ortho.png\", "
                                   "\"ground_image_bounds\": [-5.5, -6, 30, 12.25]"), PLX_OK);
    assert_int_equal(f->book.n, 0);
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
    assert_string_equal(gi.path, "day/ortho.png");
    assert_int_equal(gi.bounds_given, 1);
    assert_true(gi.bounds[0] == -5.5 && gi.bounds[1] == -6 && gi.bounds[2] == 30 && gi.bounds[3] == 12.25);
    assert_int_equal(gi.width, 0);
    assert_true(gi.mean_albedo[1] == 0.15 && gi.mean_luminance == 0.15);
    /* no pixels yet: the constant everywhere */
    assert_int_equal(plx_ground_albedo_at(f->e, 1.0, 2.0, rgb), PLX_OK);
    assert_true(rgb[0] == 0.15 && rgb[1] == 0.15 && rgb[2] == 0.15);
    /* without bounds: the Bounds box; null reads as absent */
    assert_int_equal(load_props(f, ", \"ground_image\": \"a.png\", \"ground_image_bounds\": null"), PLX_OK);
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(gi.bounds_given, 0);
    assert_memory_equal(gi.bounds, si.bounds, sizeof gi.bounds);
    assert_true(si.bounds[0] == -50 && si.bounds[2] == 60);
    /* neither */
    assert_int_equal(load_props(f, ""), PLX_OK);
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
    assert_null(gi.path);
    fixture_close(f);
}

typedef struct bad_case {
    const char *props;
    const char *msg;
} bad_case;

static const char *const msg_path = "properties.ground_image must be the path of a PNG file "
                                    "(a non-empty string of at most 4096 bytes)";
static const char *const msg_bounds = "properties.ground_image_bounds must be [x0, y0, x1, y1]: "
                                      "4 finite numbers with x0 < x1 and y0 < y1";

static void test_loader_rejects(void **state)
{
    static const char long_path_fmt[] = ", \"ground_image\": \"%s\"";
    bad_case cases[] = {
        { ", \"ground_image\": 12", NULL },
        { ", \"ground_image\": \"\"", NULL },
        { ", \"ground_image\": [\"a.png\"]", NULL },
        { ", \"ground_image\": true", NULL },
        { ", \"ground_image_bounds\": \"0 0 1 1\"", "b" },
        { ", \"ground_image_bounds\": [0, 0, 1]", "b" },
        { ", \"ground_image_bounds\": [0, 0, 1, 1, 2]", "b" },
        { ", \"ground_image_bounds\": [0, 0, 0, 1]", "b" },
        { ", \"ground_image_bounds\": [0, 1, 1, 0]", "b" },
        { ", \"ground_image_bounds\": [0, 0, 1e999, 1]", "b" },
        { ", \"ground_image_bounds\": [\"0\", 0, 1, 1]", "b" },
        { ", \"ground_image_bounds\": [0, 0, null, 1]", "b" },
        { ", \"ground_image_bounds\": [-2e7, 0, 0, 1]", "r" },
    };
    char *long_props;
    size_t k;
    int strict;
    (void)state;
    for (strict = 0; strict <= 1; strict++) {
        fixture_log *f = fixture_open(strict, MEM);
        for (k = 0; k < sizeof cases / sizeof cases[0]; k++) {
            const char *why = cases[k].msg == NULL ? msg_path
                              : cases[k].msg[0] == 'b'
                                  ? msg_bounds
                                  : "properties.ground_image_bounds is out of range (|coordinate| > 1e7 m)";
            char want[600];
            plx_status st = load_props(f, cases[k].props);
            if (strict) {
                snprintf(want, sizeof want, "t.geojson: %s", why);
                assert_int_equal(st, PLX_E_SCENE);
                assert_string_equal(plx_last_error(f->e), want);
            } else {
                plx_ground_image_info gi;
                plx_scene_info si;
                snprintf(want, sizeof want, "t.geojson: %s; ignored\n", why);
                assert_int_equal(st, PLX_OK);
                assert_string_equal(f->book.all, want);
                assert_int_equal(plx_warning_count(f->e), 1);
                assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
                assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
                assert_null(gi.path);
                assert_int_equal(gi.bounds_given, 0);
                assert_memory_equal(gi.bounds, si.bounds, sizeof gi.bounds);
            }
        }
        /* longer than 4096 bytes */
        long_props = malloc(5000);
        memset(long_props, 'a', 4097);
        long_props[4097] = '\0';
        {
            char *props = malloc(5200);
            snprintf(props, 5200, long_path_fmt, long_props);
            {
                char json[6000];
                snprintf(json, sizeof json,
                         "{\"type\": \"FeatureCollection\", \"properties\": {\"units\": \"m\"%s}, \"features\": []}",
                         props);
                assert_int_equal(plx_load_geojson(f->e, json, strlen(json), "t.geojson"),
                                 strict ? PLX_E_SCENE : PLX_OK);
            }
            free(props);
        }
        free(long_props);
        fixture_close(f);
    }
}

/* Lon/lat scenes: the bounds are projected about the scene's centre like
 * every coordinate (SPEC §1), by hand here; degrees out of range are
 * refused. */
static void test_loader_lonlat(void **state)
{
    const char *json =
        "{\"type\": \"FeatureCollection\", \"properties\": {\"ground_image\": \"o.png\",\n"
        "  \"ground_image_bounds\": [24.9400, 60.1650, 24.9440, 60.1670]},\n"
        " \"features\": [\n"
        "  {\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"Polygon\",\n"
        "   \"coordinates\": [[[24.9410, 60.1655], [24.9420, 60.1655], [24.9420, 60.1660], [24.9410, 60.1660]]]}},\n"
        "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true}, \"geometry\": {\"type\": \"Point\",\n"
        "   \"coordinates\": [24.9430, 60.1665]}}]}";
    const char *bad =
        "{\"type\": \"FeatureCollection\", \"properties\": {\"ground_image_bounds\": [-50, -50, 50, 150]},\n"
        " \"features\": [\n"
        "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true}, \"geometry\": {\"type\": \"Point\",\n"
        "   \"coordinates\": [24.9430, 60.1665]}}]}";
    fixture_log *f = fixture_open(1, MEM);
    plx_ground_image_info gi;
    double lon0 = 0.5 * (24.9410 + 24.9430), lat0 = 0.5 * (60.1655 + 60.1665);
    double c = cos(lat0 * PI / 180.0), want[4];
    uint8_t px[2 * 2 * 3] = { 10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120 };
    double rgb[3], exp_rgb[3], scale;
    int i, j;
    (void)state;
    want[0] = (24.9400 - lon0) * 111320.0 * c;
    want[1] = (60.1650 - lat0) * 110540.0;
    want[2] = (24.9440 - lon0) * 111320.0 * c;
    want[3] = (60.1670 - lat0) * 110540.0;
    assert_int_equal(plx_load_geojson(f->e, json, strlen(json), "ll.geojson"), PLX_OK);
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
    assert_int_equal(gi.bounds_given, 1);
    for (i = 0; i < 4; i++)
        assert_true(near(gi.bounds[i], want[i], 1e-12));
    /* a 2x2 image over them: the pixel centres of the projected box */
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, px, NULL), PLX_OK);
    scale = scale_ref(px, 4, 0.15);
    for (j = 0; j < 2; j++)
        for (i = 0; i < 2; i++) {
            double x = want[0] + (i + 0.5) * (want[2] - want[0]) / 2;
            double y = want[3] - (j + 0.5) * (want[3] - want[1]) / 2;
            assert_int_equal(plx_ground_albedo_at(f->e, x, y, rgb), PLX_OK);
            albedo_ref(px + 3 * (2 * j + i), scale, exp_rgb);
            assert_true(near(rgb[0], exp_rgb[0], 1e-12) && near(rgb[1], exp_rgb[1], 1e-12) &&
                        near(rgb[2], exp_rgb[2], 1e-12));
        }
    /* metres given to a lon/lat scene */
    assert_int_equal(plx_load_geojson(f->e, bad, strlen(bad), "ll.geojson"), PLX_E_SCENE);
    assert_string_equal(plx_last_error(f->e),
                        "ll.geojson: properties.ground_image_bounds must be lon/lat degrees like the scene's "
                        "coordinates (lon -180..180, lat -90..90)");
    fixture_close(f);
}

/* ---- lookup ---------------------------------------------------------------- */

/* A 4 x 3 image of distinct pixels over [10, 18] x [20, 26] (2 m pixels). */
static const double box43[4] = { 10, 20, 18, 26 };

static void image43(uint8_t px[4 * 3 * 3])
{
    int k;
    for (k = 0; k < 12; k++) {
        px[3 * k] = (uint8_t)(20 + 19 * k);
        px[3 * k + 1] = (uint8_t)(230 - 17 * k);
        px[3 * k + 2] = (uint8_t)(60 + 7 * (k % 5));
    }
}

static void check_at(plx_engine *e, double x, double y, const uint8_t *px, double scale, int i, int j)
{
    double rgb[3], want[3];
    assert_int_equal(plx_ground_albedo_at(e, x, y, rgb), PLX_OK);
    if (i < 0) {
        want[0] = want[1] = want[2] = 0.15;
    } else {
        albedo_ref(px + 3 * (4 * j + i), scale, want);
    }
    if (!(near(rgb[0], want[0], 1e-12) && near(rgb[1], want[1], 1e-12) && near(rgb[2], want[2], 1e-12))) {
        printf("at (%.17g, %.17g), pixel (%d, %d): got %.17g %.17g %.17g, want %.17g %.17g %.17g\n", x, y, i,
               j, rgb[0], rgb[1], rgb[2], want[0], want[1], want[2]);
        fail();
    }
}

static void test_lookup(void **state)
{
    fixture_log *f = fixture_open(1, MEM);
    uint8_t px[36];
    double scale;
    int i, j;
    (void)state;
    image43(px);
    scale = scale_ref(px, 12, 0.15);
    assert_int_equal(load_props(f, ""), PLX_OK);
    assert_int_equal(plx_set_ground_image(f->e, 4, 3, px, box43), PLX_OK);
    for (j = 0; j < 3; j++)
        for (i = 0; i < 4; i++) {
            double x = 10 + 2 * i + 1, y = 26 - 2 * j - 1;
            check_at(f->e, x, y, px, scale, i, j);
            /* anywhere in the cell */
            check_at(f->e, x - 0.99, y + 0.99, px, scale, i, j);
            check_at(f->e, x + 0.99, y - 0.99, px, scale, i, j);
        }
    /* lines between pixels: the pixel east of / south of the line */
    check_at(f->e, 12.0, 25.0, px, scale, 1, 0);
    check_at(f->e, 16.0, 23.0, px, scale, 3, 1);
    check_at(f->e, 11.0, 24.0, px, scale, 0, 1);
    check_at(f->e, 11.0, 22.0, px, scale, 0, 2);
    /* the box's edges belong to the image: west/north edges to the first
     * column/row, east/south edges to the last */
    check_at(f->e, 10.0, 26.0, px, scale, 0, 0);
    check_at(f->e, 18.0, 26.0, px, scale, 3, 0);
    check_at(f->e, 18.0, 20.0, px, scale, 3, 2);
    check_at(f->e, 10.0, 20.0, px, scale, 0, 2);
    /* outside: the constant */
    check_at(f->e, nextafter(10.0, 0.0), 23.0, px, scale, -1, -1);
    check_at(f->e, nextafter(18.0, 99.0), 23.0, px, scale, -1, -1);
    check_at(f->e, 14.0, nextafter(26.0, 99.0), px, scale, -1, -1);
    check_at(f->e, 14.0, nextafter(20.0, 0.0), px, scale, -1, -1);
    check_at(f->e, -1e6, 1e6, px, scale, -1, -1);
    /* the internal hook answers NaN with the constant */
    {
        double rgb[3];
        scene_ground_albedo(f->e->sc, NAN, 23.0, rgb);
        assert_true(rgb[0] == 0.15 && rgb[2] == 0.15);
        assert_true(scene_ground_albedo_y(f->e->sc, 14.0, NAN) == 0.15);
    }
    /* the luminance hook is the luminance of the colour */
    {
        double rgb[3];
        scene_ground_albedo(f->e->sc, 13.0, 23.0, rgb);
        assert_true(near(scene_ground_albedo_y(f->e->sc, 13.0, 23.0), lum_ref(rgb), 1e-15));
    }
    /* API misuse */
    {
        double rgb[3];
        assert_int_equal(plx_ground_albedo_at(f->e, NAN, 0, rgb), PLX_E_INVALID);
        assert_int_equal(plx_ground_albedo_at(f->e, 0, 0, NULL), PLX_E_INVALID);
    }
    fixture_close(f);
}

/* Over all pixels the mean luminance of the albedo is the ground albedo;
 * a bright pixel is clamped to 0.95 and then pulls the mean down. */
static void test_normalisation(void **state)
{
    fixture_log *f = fixture_open(1, MEM);
    enum { W = 37, H = 23 };
    static uint8_t px[W * H * 3];
    double sum = 0.0, bx[4] = { -37, -23, 37, 23 };
    uint64_t s = 12345;
    int i, j;
    plx_ground_image_info gi;
    (void)state;
    for (i = 0; i < W * H * 3; i++) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        px[i] = (uint8_t)((s >> 33) % 200);
    }
    assert_int_equal(load_props(f, ", \"ground_albedo\": 0.23"), PLX_OK);
    assert_int_equal(plx_set_ground_image(f->e, W, H, px, bx), PLX_OK);
    for (j = 0; j < H; j++)
        for (i = 0; i < W; i++) {
            double rgb[3];
            assert_int_equal(plx_ground_albedo_at(f->e, -37 + 2 * i + 1, 23 - 2 * j - 1, rgb), PLX_OK);
            assert_true(rgb[0] < 0.95 && rgb[1] < 0.95 && rgb[2] < 0.95);
            sum += lum_ref(rgb);
        }
    printf("mean luminance of the albedo: %.17g (ground albedo 0.23)\n", sum / (W * H));
    assert_true(fabs(sum / (W * H) - 0.23) <= 1e-12);
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
    assert_true(gi.width == W && gi.height == H);
    assert_true(fabs(gi.mean_luminance - 0.23) <= 1e-12);
    assert_memory_equal(gi.bounds, bx, sizeof bx);
    /* clamping: one white pixel among nine dark ones */
    {
        uint8_t ten[30];
        double rgb[3], want_dark;
        memset(ten, 10, sizeof ten);
        ten[0] = ten[1] = ten[2] = 255;
        want_dark = lin_ref(10) * 0.23 / ((lin_ref(255) + 9 * lin_ref(10)) / 10 * (0.2126 + 0.7152 + 0.0722));
        assert_int_equal(plx_set_ground_image(f->e, 10, 1, ten, bx), PLX_OK);
        assert_int_equal(plx_ground_albedo_at(f->e, -36, 0, rgb), PLX_OK);
        assert_true(rgb[0] == 0.95 && rgb[1] == 0.95 && rgb[2] == 0.95);
        assert_int_equal(plx_ground_albedo_at(f->e, 30, 0, rgb), PLX_OK);
        assert_true(near(rgb[1], want_dark, 1e-12));
        assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
        printf("one white pixel clamped: mean luminance %.4f\n", gi.mean_luminance);
        assert_true(gi.mean_luminance < 0.23 * 0.9);
    }
    fixture_close(f);
}

static void test_api_errors(void **state)
{
    fixture_log *f = fixture_open(1, MEM);
    uint8_t px[12] = { 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12 };
    uint8_t black[12] = { 0 };
    double bad[4] = { 0, 0, -1, 1 }, inf[4] = { 0, 0, INFINITY, 1 }, rgb[3];
    plx_ground_image_info gi;
    (void)state;
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, px, NULL), PLX_E_NOSCENE);
    assert_string_equal(plx_last_error(f->e), "plx_set_ground_image: no scene is loaded");
    assert_int_equal(plx_ground_albedo_at(f->e, 0, 0, rgb), PLX_E_NOSCENE);
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_E_NOSCENE);
    assert_int_equal(plx_set_ground_image(NULL, 2, 2, px, NULL), PLX_E_INVALID);
    assert_int_equal(load_props(f, ""), PLX_OK);
    assert_int_equal(plx_set_ground_image(f->e, 0, 2, px, NULL), PLX_E_INVALID);
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, NULL, NULL), PLX_E_INVALID);
    assert_int_equal(plx_set_ground_image(f->e, 16385, 1, px, NULL), PLX_E_INVALID);
    assert_string_equal(plx_last_error(f->e), "plx_set_ground_image: width and height must be 1..16384 and "
                                              "rgb8 not NULL (or 0, 0, NULL to remove the image)");
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, px, bad), PLX_E_INVALID);
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, px, inf), PLX_E_INVALID);
    assert_string_equal(plx_last_error(f->e), "plx_set_ground_image: bounds must be 4 finite numbers x0 < x1, y0 < y1");
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, black, NULL), PLX_E_INVALID);
    assert_string_equal(plx_last_error(f->e), "plx_set_ground_image: the image is black (mean luminance 0): "
                                              "its albedo cannot be scaled to the ground albedo");
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
    assert_int_equal(gi.width, 0);
    assert_int_equal(plx_ground_image_get(f->e, NULL), PLX_E_INVALID);
    /* set, then remove */
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, px, NULL), PLX_OK);
    assert_int_equal(plx_ground_albedo_at(f->e, 0, 0, rgb), PLX_OK);
    assert_true(rgb[0] != 0.15);
    assert_int_equal(plx_set_ground_image(f->e, 0, 0, NULL, NULL), PLX_OK);
    assert_int_equal(plx_ground_albedo_at(f->e, 0, 0, rgb), PLX_OK);
    assert_true(rgb[0] == 0.15 && rgb[1] == 0.15 && rgb[2] == 0.15);
    assert_int_equal(plx_ground_image_get(f->e, &gi), PLX_OK);
    assert_int_equal(gi.width, 0);
    /* a new load drops the image */
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, px, NULL), PLX_OK);
    assert_int_equal(load_props(f, ""), PLX_OK);
    assert_int_equal(plx_ground_albedo_at(f->e, 0, 0, rgb), PLX_OK);
    assert_true(rgb[0] == 0.15);
    fixture_close(f);
}

/* Out of memory at either allocation: PLX_E_NOMEM, the memory back where
 * it was, the old image still answering; a smaller image then reuses the
 * memory. */
static void test_nomem_and_replace(void **state)
{
    fixture_log *f = fixture_open(1, MEM);
    uint8_t a[2 * 2 * 3] = { 200, 10, 10, 10, 200, 10, 10, 10, 200, 100, 100, 100 };
    uint8_t *big = malloc(100 * 100 * 3);
    double rgb_a[3], rgb[3];
    plx_memory_report m0, m1;
    uint64_t k;
    (void)state;
    memset(big, 77, 100 * 100 * 3);
    assert_int_equal(load_props(f, ""), PLX_OK);
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, a, NULL), PLX_OK);
    assert_int_equal(plx_ground_albedo_at(f->e, -40, 60, rgb_a), PLX_OK);
    for (k = 1; k <= 2; k++) {
        plx_memory_get(f->e, &m0);
        plx_debug_fail_alloc(f->e, k);
        assert_int_equal(plx_set_ground_image(f->e, 64, 64, big, NULL), PLX_E_NOMEM);
        plx_debug_fail_alloc(f->e, 0);
        assert_non_null(strstr(plx_last_error(f->e), "out of memory while storing the ground image: part 'scene'"));
        plx_memory_get(f->e, &m1);
        assert_int_equal(m1.used_total, m0.used_total);
        assert_int_equal(plx_ground_albedo_at(f->e, -40, 60, rgb), PLX_OK);
        assert_memory_equal(rgb, rgb_a, sizeof rgb);
    }
    /* a per-part budget too small for the pixels */
    {
        void *mem = malloc(MEM);
        plx_engine *e;
        plx_config cfg;
        plx_config_default(&cfg);
        cfg.part_budget[PLX_PART_SCENE] = 20000;
        assert_int_equal(plx_engine_create(mem, MEM, &cfg, &e), PLX_OK);
        assert_int_equal(plx_load_file(e, "fixtures/tiny.geojson"), PLX_E_UNSUPPORTED); /* no port */
        {
            const char *json = "{\"type\": \"FeatureCollection\", \"features\": []}";
            assert_int_equal(plx_load_geojson(e, json, strlen(json), NULL), PLX_OK);
        }
        assert_int_equal(plx_set_ground_image(e, 100, 100, big, NULL), PLX_E_NOMEM);
        assert_non_null(strstr(plx_last_error(e), "(its budget is 20000 bytes)"));
        assert_int_equal(plx_set_ground_image(e, 2, 2, a, NULL), PLX_OK);
        plx_engine_destroy(e);
        free(mem);
    }
    /* replace with a larger one (new memory), then a smaller one (same memory) */
    assert_int_equal(plx_set_ground_image(f->e, 64, 64, big, NULL), PLX_OK);
    plx_memory_get(f->e, &m0);
    assert_int_equal(plx_set_ground_image(f->e, 2, 2, a, NULL), PLX_OK);
    plx_memory_get(f->e, &m1);
    assert_int_equal(m1.used_total, m0.used_total);
    assert_int_equal(plx_ground_albedo_at(f->e, -40, 60, rgb), PLX_OK);
    assert_memory_equal(rgb, rgb_a, sizeof rgb);
    free(big);
    fixture_close(f);
}

/* Setting an image drops photons traced with the old ground. */
static void test_photons_dropped(void **state)
{
    fixture_log *f = fixture_open(1, MEM);
    uint8_t px[3] = { 120, 130, 140 };
    (void)state;
    assert_int_equal(load_props(f, ""), PLX_OK);
    assert_int_equal(plx_indirect_step(f->e, 2000, 1), PLX_OK);
    assert_true(plx_indirect_frames(f->e) == 1);
    assert_int_equal(plx_set_ground_image(f->e, 1, 1, px, NULL), PLX_OK);
    assert_true(plx_indirect_frames(f->e) == 0);
    assert_int_equal(plx_indirect_step(f->e, 2000, 1), PLX_OK);
    assert_true(plx_indirect_frames(f->e) == 1);
    fixture_close(f);
}

/* ---- render of the fixture ---------------------------------------------- */

/* Straight down from 100 m over fixtures/ground-image.geojson, direct light
 * only, no glows: every ground pixel is albedo / pi * E_rgb with the albedo
 * decoded here from the PNG and E_rgb from plx_illuminance at the pixel's
 * ground point (SPEC §5: right is +x, up is +y looking down). */
static void test_render_fixture(void **state)
{
    fixture_log *f = fixture_open(1, MEM);
    plx_camera cam;
    plx_render_opts o;
    uint8_t *png = NULL;
    float *img;
    int w = 0, h = 0, i, j, checked = 0, colours = 0;
    double scale, t, ratio_sum[2][3] = { { 0 } };
    int ratio_n[2] = { 0, 0 };
    char err[300];
    (void)state;
    assert_int_equal(plx_load_file(f->e, "fixtures/ground-image.geojson"), PLX_OK);
    assert_int_equal(image_read_png_rgb8("fixtures/ground-day.png", NULL, 0, &png, &w, &h, err, sizeof err), 0);
    assert_true(w == 64 && h == 64);
    assert_int_equal(plx_set_ground_image(f->e, (uint32_t)w, (uint32_t)h, png, NULL), PLX_OK);
    scale = scale_ref(png, 64 * 64, 0.2);
    memset(&cam, 0, sizeof cam);
    cam.eye[2] = 100.0;
    cam.fov_deg = 40.0;
    cam.width = 160;
    cam.height = 120;
    plx_render_opts_default(&o);
    o.no_glow = 1;
    o.no_indirect = 1;
    img = malloc(sizeof(float) * 3 * 160 * 120);
    assert_int_equal(plx_render(f->e, &cam, &o, NULL, img, NULL), PLX_OK);
    t = tan(20.0 * PI / 180.0);
    for (j = 0; j < 120; j++)
        for (i = 0; i < 160; i++) {
            double a = (2.0 * (i + 0.5) / 160 - 1.0) * t * 160.0 / 120.0;
            double b = (1.0 - 2.0 * (j + 0.5) / 120) * t;
            double P[3] = { 100.0 * a, 100.0 * b, 0.0 }, n[3] = { 0, 0, 1 }, E, rgbE[3], alb[3];
            double u = P[0] + 32.0, v = 32.0 - P[1];
            const float *out = img + 3 * ((size_t)j * 160 + i);
            int k, side;
            /* leave out what roofs and walls may hide (the footprints seen
             * from 100 m grow by 100 / 88 about the eye's foot) and points
             * within 1e-6 px of a pixel line */
            if ((P[0] > -20 * 1.14 - 1 && P[0] < -8 + 1 && P[1] > 8 - 1 && P[1] < 20 * 1.14 + 1) ||
                (P[0] > 8 - 1 && P[0] < 20 * 1.14 + 1 && P[1] > -20 * 1.14 - 1 && P[1] < -8 + 1))
                continue;
            if (fabs(u - floor(u + 0.5)) < 1e-6 || fabs(v - floor(v + 0.5)) < 1e-6)
                continue;
            assert_int_equal(plx_illuminance(f->e, 1, P, n, &E, NULL, rgbE), PLX_OK);
            if (u >= 0 && u < 64 && v >= 0 && v < 64)
                albedo_ref(png + 3 * ((size_t)floor(v) * 64 + (size_t)floor(u)), scale, alb);
            else
                alb[0] = alb[1] = alb[2] = 0.2;
            for (k = 0; k < 3; k++) {
                double want = alb[k] / PI * rgbE[k];
                if (!(fabs(out[k] - want) <= 1e-6 * want + 1e-30)) {
                    printf("pixel (%d, %d) at (%.3f, %.3f) channel %d: %.9g, want %.9g\n", i, j, P[0], P[1], k,
                           out[k], want);
                    fail();
                }
            }
            checked++;
            /* the colour ratio follows the image: grass (west) and paving (east) */
            side = P[1] > 6 || P[1] < -6 ? (P[0] < -1 ? 0 : P[0] > 1 ? 1 : -1) : -1;
            if (side >= 0 && E > 1.0 && fabs(P[0]) < 30 && fabs(P[1]) < 30) {
                for (k = 0; k < 3; k++)
                    ratio_sum[side][k] += out[k] / rgbE[k];
                ratio_n[side]++;
            }
            colours += alb[0] != alb[1];
        }
    printf("render of the fixture: %d ground pixels checked (%d with a coloured albedo)\n", checked, colours);
    assert_true(checked > 5000 && colours > 1000);
    /* the grass is greener than red, the paving redder than green */
    assert_true(ratio_n[0] > 100 && ratio_n[1] > 100);
    assert_true(ratio_sum[0][1] > 1.5 * ratio_sum[0][0]);
    assert_true(ratio_sum[1][0] > 1.5 * ratio_sum[1][1]);
    free(img);
    free(png);
    fixture_close(f);
}

/* ---- photons: the ground's roulette ---------------------------------------- */

typedef struct scene_fx {
    scene s;
    void *mem;
    arena a;
} scene_fx;

/* A lamp at (3, 0, 5) under a raised slab (z 20..21 over +-1000 m, albedo
 * 0): every photon leaving the ground upward ends at the slab's underside,
 * where the store function counts it; photons going up first die there. */
static void slab_scene(scene_fx *f)
{
    ref_scene_init(&f->s);
    f->mem = malloc(256u << 20);
    assert_non_null(f->mem);
    arena_init(&f->a, f->mem, 256u << 20);
    assert_true(ref_scene_add_box(&f->s, -1000, -1000, 1000, 1000, 21.0, 20.0) >= 0);
    assert_true(ref_scene_add_lamp(&f->s, 3, 0, 5, 1000, 30) >= 0);
    f->s.bld[0].albedo = 0.0;
    f->s.ground_albedo = 0.3;
    ref_scene_finish(&f->s);
    assert_int_equal(blocks_build(&f->a, &f->s, 0.05), PLX_OK);
}

static void slab_close(scene_fx *f)
{
    ref_scene_free(&f->s);
    free(f->mem);
}

typedef struct tally {
    double stored;
    uint64_t n;
} tally;

static void count_store(photon_sys *ps, void *ctx, uint32_t lamp, const trace_hit *h,
                        const double f[PHOTON_CH])
{
    tally *t = ctx;
    (void)ps;
    (void)lamp;
    (void)h;
    t->stored += f[0]; /* the colour-blind channel */
    t->n++;
}

/* Traces n photons of lamp 0 (flux 4 pi I shared) with one bounce. */
static void trace_n(scene_fx *f, uint32_t n, uint64_t seed, photon_stats *st, tally *t)
{
    photon_sys *ps;
    photon_config c;
    arena_mark m = arena_get_mark(&f->a);
    uint64_t rng = seed;
    uint32_t k;
    double phi = 4.0 * PI * 1000.0 / n;
    photon_config_default(&c);
    c.aerial_res = 64;
    c.chart_w = 16;
    c.chart_h = 8;
    c.max_bounces = 1;
    assert_int_equal(photon_create(&f->a, &f->s, &c, &ps), PLX_OK);
    memset(st, 0, sizeof *st);
    memset(t, 0, sizeof *t);
    for (k = 0; k < n; k++)
        photon_trace_lamp(ps, 0, phi, &rng, st, count_store, t);
    arena_release(&f->a, &m);
}

/* First-hit flux on the ground west and east of x = 0 (lm): the integral of
 * SPEC §2's E = I z / d^3 W(d/R) over each half-plane (midpoint rule). */
static void first_flux(double flux[2])
{
    double hstep = 0.02, x, y, xl = 3, zl = 5, I = 1000, R = 30, rg = sqrt(R * R - zl * zl);
    flux[0] = flux[1] = 0.0;
    for (x = xl - rg + 0.5 * hstep; x < xl + rg; x += hstep)
        for (y = -rg + 0.5 * hstep; y < rg; y += hstep) {
            double dx = x - xl, d2 = dx * dx + y * y + zl * zl, d = sqrt(d2), q, wv;
            if (d >= R)
                continue;
            q = d / R;
            wv = 1.0 - q * q * q * q;
            flux[x < 0 ? 0 : 1] += I * zl / (d2 * d) * wv * wv * hstep * hstep;
        }
}

static void test_photon_two_colours(void **state)
{
    scene_fx f;
    photon_stats st;
    tally t;
    uint8_t px[6] = { 40, 45, 50, 235, 225, 215 }; /* west dark, east bright */
    double box[4] = { -40, -40, 40, 40 }, flux[2], lw[3], le[3], sc, yw, ye, want, sd, tol, survived;
    uint32_t n = quick_mode() ? 200000u : 2000000u;
    int c;
    (void)state;
    slab_scene(&f);
    assert_int_equal(ground_image_set(&f.a, &f.s, 2, 1, px, box), PLX_OK);
    /* the albedo luminance of each half, decoded here */
    for (c = 0; c < 3; c++) {
        lw[c] = lin_ref(px[c]);
        le[c] = lin_ref(px[3 + c]);
    }
    sc = 0.3 / (0.5 * (lum_ref(lw) + lum_ref(le)));
    for (c = 0; c < 3; c++) {
        lw[c] = fmin(lw[c] * sc, 0.95);
        le[c] = fmin(le[c] * sc, 0.95);
    }
    yw = lum_ref(lw);
    ye = lum_ref(le);
    assert_true(yw < 0.1 && ye > 0.45);
    first_flux(flux);
    want = yw * flux[0] + ye * flux[1];
    trace_n(&f, n, 99, &st, &t);
    /* photons whose first hit is the slab die there (albedo 0): what
     * survives a bounce left the ground, and either reached the slab's
     * underside (stored) or slipped out beside it at a grazing angle */
    survived = t.stored + st.escaped;
    /* each photon adds at most phi with probability at most max(Y): the
     * standard deviation of the sum is at most phi sqrt(n ye) */
    sd = 4.0 * PI * 1000.0 / n * sqrt(n * ye);
    tol = 5.0 * sd + 1e-3 * want;
    printf("two-colour ground (Y %.4f west, %.4f east): first-hit ground flux %.2f + %.2f lm,\n"
           "  after ground bounces %.3f lm (%.3f stored, %.3f escaped), expected %.3f lm (+- %.3f);"
           " with the constant %.3f\n",
           yw, ye, flux[0], flux[1], survived, t.stored, st.escaped, want, tol, 0.3 * (flux[0] + flux[1]));
    assert_true(st.escaped < 0.01 * survived);
    assert_true(fabs(survived - want) <= tol);
    /* the wrong side or the constant would be far off */
    assert_true(fabs(0.3 * (flux[0] + flux[1]) - want) > 3 * tol);
    assert_true(fabs(ye * flux[0] + yw * flux[1] - want) > 3 * tol);
    slab_close(&f);
}

/* A uniform image (grey, scaled to the ground albedo) traces the same
 * photons as no image, and an image outside the lamp's reach changes
 * nothing either. */
static void test_photon_uniform(void **state)
{
    scene_fx f;
    photon_stats a, b;
    tally ta, tb;
    uint8_t grey[4 * 3];
    double box[4] = { -40, -40, 40, 40 }, far[4] = { 500, 500, 600, 600 };
    uint32_t n = quick_mode() ? 20000u : 200000u;
    (void)state;
    memset(grey, 128, sizeof grey);
    slab_scene(&f);
    trace_n(&f, n, 7, &a, &ta);
    assert_int_equal(ground_image_set(&f.a, &f.s, 2, 2, grey, box), PLX_OK);
    assert_true(fabs(scene_ground_albedo_y(&f.s, 1, 1) - 0.3) < 1e-15);
    trace_n(&f, n, 7, &b, &tb);
    printf("uniform image: stored %.6f lm (%llu photons), no image %.6f lm (%llu)\n", tb.stored,
           (unsigned long long)tb.n, ta.stored, (unsigned long long)ta.n);
    assert_true(ta.n == tb.n && ta.stored == tb.stored && a.absorbed == b.absorbed && a.first == b.first);
    {
        uint8_t red[3] = { 250, 0, 0 };
        assert_int_equal(ground_image_set(&f.a, &f.s, 1, 1, red, far), PLX_OK);
        trace_n(&f, n, 7, &b, &tb);
        assert_true(ta.n == tb.n && ta.stored == tb.stored);
    }
    slab_close(&f);
}

/* The port's reader refuses an image above the cap before taking pixel
 * memory, and reads one at the cap. */
static void test_png_cap(void **state)
{
    char path[64], err[300];
    uint8_t *row = calloc(16385 * 3, 1), *out = NULL;
    int w = 0, h = 0;
    (void)state;
    row[0] = 255;
    snprintf(path, sizeof path, "/tmp/plx_ground_cap_%ld.png", (long)getpid());
    assert_int_equal(image_write_png_rgb8(path, 16385, 1, row, 0, err, sizeof err), 0);
    assert_int_equal(image_read_png_max(path, 16384, &out, &w, &h, err, sizeof err), -1);
    assert_null(out);
    assert_true(w == 16385 && h == 1);
    {
        char want[300];
        snprintf(want, sizeof want, "PNG: '%s' is 16385x1 pixels, larger than the 16384x16384 allowed", path);
        assert_string_equal(err, want);
    }
    assert_int_equal(image_read_png_max(path, 16385, &out, &w, &h, err, sizeof err), 0);
    assert_true(out[0] == 255 && out[3] == 0);
    free(out);
    remove(path);
    free(row);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_loader_accepts),
        cmocka_unit_test(test_loader_rejects),
        cmocka_unit_test(test_loader_lonlat),
        cmocka_unit_test(test_lookup),
        cmocka_unit_test(test_normalisation),
        cmocka_unit_test(test_api_errors),
        cmocka_unit_test(test_nomem_and_replace),
        cmocka_unit_test(test_photons_dropped),
        cmocka_unit_test(test_render_fixture),
        cmocka_unit_test(test_photon_two_colours),
        cmocka_unit_test(test_photon_uniform),
        cmocka_unit_test(test_png_cap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
