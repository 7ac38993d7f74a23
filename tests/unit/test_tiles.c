/* Web-map tiles (src/cli/tiles.c, mbtiles.c, cmd_tiles.c): Web Mercator
 * arithmetic, tile pixels against 'polarlux heatmap' at the same ground
 * points, the folder and MBTiles outputs read back (sqlite3), errors. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>
#include <sqlite3.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "port.h"
#include "cli/cli.h"
#include "cli/tiles.h"
#include "png/image_write.h"
#include "slow.h"

#define SCENE "fixtures/helsinki-centre.geojson"

static plx_engine *load(void)
{
    plx_engine *e;
    plx_config cfg;
    static plx_port quiet;
    quiet = *plx_port_posix();
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    assert_int_equal(plx_engine_new((size_t)256 << 20, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, SCENE), PLX_OK);
    return e;
}

static int run(int (*cmd)(int, char **), int argc, const char **argv)
{
    return cmd(argc, (char **)argv);
}

static void test_mercator(void **state)
{
    double lon, lat;
    long x, y;
    (void)state;
    tile_pixel_lonlat(0, 128, 128, &lon, &lat);
    assert_true(fabs(lon) < 1e-12 && fabs(lat) < 1e-12);
    tile_pixel_lonlat(0, 0, 0, &lon, &lat);
    assert_true(fabs(lon + 180) < 1e-12 && fabs(lat - 85.0511287798066) < 1e-9);
    /* Helsinki's Senate Square at zoom 16 (x from lon by hand: (lon+180)/360 * 2^16) */
    tile_of_lonlat(16, 24.9525, 60.1694, &x, &y);
    assert_int_equal(x, (long)floor((24.9525 + 180) / 360 * 65536));
    assert_int_equal(y, 18969);
    /* the pixel corners of that tile hold the point */
    tile_pixel_lonlat(16, x * 256.0, y * 256.0, &lon, &lat);
    assert_true(lon <= 24.9525 && lat >= 60.1694);
    tile_pixel_lonlat(16, (x + 1) * 256.0, (y + 1) * 256.0, &lon, &lat);
    assert_true(lon > 24.9525 && lat < 60.1694);
}

/* A tile's pixels equal the heat map's pixel at the same ground point: the
 * heat map is drawn over a 1 cm box centred on the pixel's ground point,
 * at 1 cm a pixel, with the same top of scale and quantity (sc: E_sc at
 * 1.5 m, the least over every facing direction, both). n pixels, half lit. */
static void check_tile_against_heatmap(plx_engine *e, int sc, int n)
{
    plx_scene_info si;
    tile_work w;
    uint8_t *rgba = malloc(TILE_SIZE * TILE_SIZE * 4);
    long x0, y0, x1, y1, lit;
    int k, lit_checked = 0, dark_checked = 0;
    plx_scene_info_get(e, &si);
    assert_int_equal(tile_work_init(&w), 0);
    if (sc)
        w.q.quantity = PLX_METER_SC; /* tile_work_init: 1.5 m, the least over directions */
    tile_range(e, 16, &x0, &y0, &x1, &y1);
    lit = tile_render(e, &w, 16, (x0 + x1) / 2, (y0 + y1) / 2, 100.0, rgba);
    assert_true(lit > 1000 && lit < TILE_SIZE * TILE_SIZE);
    for (k = 0; k < n; k++) {
        /* alternate lit and transparent pixels, spread over the tile */
        int want_lit = k % 2 == 0, p = (int)(((uint64_t)k * 2654435761u) % (TILE_SIZE * TILE_SIZE)), tries = 0;
        double lon, lat, gx, gy;
        char box[256], path[64];
        const char *argv[] = { "heatmap", SCENE, "--quiet", "--box", box, "--res", "0.01", "--max", "100", "-o",
                               path, "--quantity", "sc", "--facing", "min" };
        uint8_t *img;
        int iw, ih;
        while ((rgba[4 * p + 3] != 0) != want_lit && tries++ < TILE_SIZE * TILE_SIZE)
            p = (p + 97) % (TILE_SIZE * TILE_SIZE);
        if ((rgba[4 * p + 3] != 0) != want_lit)
            continue;
        tile_pixel_lonlat(16, ((x0 + x1) / 2) * 256.0 + p % TILE_SIZE + 0.5, ((y0 + y1) / 2) * 256.0 + p / TILE_SIZE + 0.5,
                          &lon, &lat);
        tile_local(&si, lon, lat, &gx, &gy);
        { /* --box takes the scene's own coordinates: lon/lat here */
            double bx0 = gx - 0.005, by0 = gy - 0.005, bx1 = gx + 0.005, by1 = gy + 0.005;
            cli_from_local(e, &bx0, &by0);
            cli_from_local(e, &bx1, &by1);
            snprintf(box, sizeof box, "%.17g,%.17g,%.17g,%.17g", bx0, by0, bx1, by1);
        }
        snprintf(path, sizeof path, "build/test_tiles_hm_%d.png", (int)getpid());
        assert_int_equal(run(cmd_heatmap, sc ? 15 : 11, argv), 0);
        assert_int_equal(image_read_png_rgb8(path, NULL, 0, &img, &iw, &ih, NULL, 0), 0);
        if (want_lit) {
            assert_memory_equal(img, rgba + 4 * p, 3);
            lit_checked++;
        } else {
            /* no light: the heat map shows black (the scale's bottom) or footprint grey */
            assert_true((img[0] == 0 && img[1] == 0 && img[2] == 0) || (img[0] == 60 && img[1] == 60 && img[2] == 66));
            dark_checked++;
        }
        free(img);
        unlink(path);
    }
    assert_true(lit_checked >= n / 2 - 1 && dark_checked >= n / 2 - 1);
    tile_work_free(&w);
    free(rgba);
}

static void test_tile_pixels_equal_heatmap(void **state)
{
    plx_engine *e = load();
    (void)state;
    check_tile_against_heatmap(e, 0, getenv("PLX_TEST_QUICK") ? 6 : 40);
    plx_engine_free(e);
}

static void test_sc_tile_pixels_equal_heatmap(void **state)
{
    plx_engine *e = load();
    (void)state;
    check_tile_against_heatmap(e, 1, getenv("PLX_TEST_QUICK") ? 6 : 40);
    plx_engine_free(e);
}

/* The sc reading of tiles ('--facing min'): the least E_sc over every
 * horizontal facing direction, against plx_meter facing 3600 directions
 * (E_sc is smooth in the direction, so the sampled minimum lies within
 * |V| (1 - cos(pi / 3600)) above the true one); a fixed direction is
 * plx_meter's own number. Points along Esplanadi, some under buildings. */
static void test_sc_least_over_directions(void **state)
{
    plx_engine *e = load();
    heat_quantity q = { PLX_METER_SC, 1.5, 0.0, 1 }, q30 = { PLX_METER_SC, 1.5, 30.0, 0 };
    int k, j, lit = 0, solid = 0;
    (void)state;
    for (k = 0; k < 24; k++) {
        double x = -120 + 25 * k, y = -430 + 7 * (k % 5), least, brute = INFINITY, bmax = 0, v30;
        double P[3] = { x, y, 1.5 }, m[PLX_METER_COUNT], u[2];
        plx_status st = heatmap_value(e, &q, x, y, &least);
        if (st == PLX_E_RANGE) {
            assert_true(least != least);
            solid++;
            continue;
        }
        assert_int_equal(st, PLX_OK);
        for (j = 0; j < 3600; j++) {
            u[0] = cos(j * 3.14159265358979323846 / 1800);
            u[1] = sin(j * 3.14159265358979323846 / 1800);
            assert_int_equal(plx_meter(e, 1, P, u, m), PLX_OK);
            brute = fmin(brute, m[PLX_METER_SC]);
            bmax = fmax(bmax, m[PLX_METER_SC]);
        }
        assert_true(least <= brute + 1e-9 * (1 + brute));
        assert_true(brute - least <= 1e-6 * (1 + bmax));
        lit += least > 0.5;
        u[0] = cos(30 * 3.14159265358979323846 / 180);
        u[1] = sin(30 * 3.14159265358979323846 / 180);
        assert_int_equal(plx_meter(e, 1, P, u, m), PLX_OK);
        assert_int_equal(heatmap_value(e, &q30, x, y, &v30), PLX_OK);
        assert_true(v30 == m[PLX_METER_SC]);
    }
    assert_true(lit >= 5);
    print_message("sc least: %d lit points, %d inside solids\n", lit, solid);
    plx_engine_free(e);
}

static uint8_t *read_file(const char *path, size_t *len)
{
    char err[256];
    return (uint8_t *)port_read_text(path, len, err, sizeof err);
}

/* The scene file's top-level "attribution", read with cJSON (not the
 * command's reader). */
static const char *fixture_attribution(const char *path, char *buf, size_t len)
{
    size_t n;
    char *text = (char *)read_file(path, &n);
    cJSON *root, *a;
    assert_non_null(text);
    root = cJSON_ParseWithLength(text, n);
    assert_non_null(root);
    a = cJSON_GetObjectItemCaseSensitive(root, "attribution");
    assert_true(cJSON_IsString(a) && strlen(a->valuestring) > 20);
    snprintf(buf, len, "%s", a->valuestring);
    cJSON_Delete(root);
    free(text);
    return buf;
}

static const char *meta(sqlite3 *db, const char *name, char *buf, size_t len)
{
    sqlite3_stmt *s;
    buf[0] = '\0';
    assert_int_equal(sqlite3_prepare_v2(db, "SELECT value FROM metadata WHERE name = ?", -1, &s, NULL), SQLITE_OK);
    sqlite3_bind_text(s, 1, name, -1, SQLITE_STATIC);
    if (sqlite3_step(s) == SQLITE_ROW)
        snprintf(buf, len, "%s", (const char *)sqlite3_column_text(s, 0));
    sqlite3_finalize(s);
    return buf;
}

/* The same tiles to a folder and to MBTiles: every row reads back through
 * sqlite3, its PNG bytes equal the folder's file (TMS row = 2^z - 1 - y),
 * and the metadata says what the spec asks. */
static void test_mbtiles_read_back(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    char dir[64], mbt[64], buf[256], path[256];
    const char *to_dir[] = { "tiles", SCENE, "--quiet", "--zoom", "14-15", "--max", "100", "-o", dir };
    const char *to_mbt[] = { "tiles", SCENE, "--quiet", "--zoom", "14-15", "--max", "100", "-o", mbt };
    plx_engine *e = load();
    sqlite3 *db;
    sqlite3_stmt *s;
    long x0, y0, x1, y1, want = 0, rows = 0;
    double b[4];
    int z;
    (void)state;
    snprintf(dir, sizeof dir, "build/test_tiles_%d", (int)getpid());
    snprintf(mbt, sizeof mbt, "build/test_tiles_%d.mbtiles", (int)getpid());
    assert_int_equal(run(cmd_tiles, 9, to_dir), 0);
    assert_int_equal(run(cmd_tiles, 9, to_mbt), 0);
    for (z = 14; z <= 15; z++) {
        tile_range(e, z, &x0, &y0, &x1, &y1);
        want += (x1 - x0 + 1) * (y1 - y0 + 1);
    }
    assert_int_equal(sqlite3_open_v2(mbt, &db, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
    assert_string_equal(meta(db, "format", buf, sizeof buf), "png");
    assert_string_equal(meta(db, "minzoom", buf, sizeof buf), "14");
    assert_string_equal(meta(db, "maxzoom", buf, sizeof buf), "15");
    assert_string_equal(meta(db, "type", buf, sizeof buf), "overlay");
    assert_string_equal(meta(db, "name", buf, sizeof buf), "helsinki-centre");
    assert_int_equal(sscanf(meta(db, "bounds", buf, sizeof buf), "%lf,%lf,%lf,%lf", &b[0], &b[1], &b[2], &b[3]), 4);
    assert_true(b[0] > 24.93 && b[0] < 24.94 && b[2] > 24.95 && b[2] < 24.96 && b[1] > 60.16 && b[3] < 60.18);
    assert_int_equal(sscanf(meta(db, "center", buf, sizeof buf), "%lf,%lf,%d", &b[0], &b[1], &z), 3);
    assert_string_equal(meta(db, "attribution", buf, sizeof buf), fixture_attribution(SCENE, path, sizeof path));
    assert_int_equal(sqlite3_prepare_v2(db, "SELECT zoom_level, tile_column, tile_row, tile_data FROM tiles", -1, &s,
                                        NULL), SQLITE_OK);
    while (sqlite3_step(s) == SQLITE_ROW) {
        int zz = sqlite3_column_int(s, 0);
        long x = sqlite3_column_int(s, 1), y = (1L << zz) - 1 - sqlite3_column_int(s, 2);
        size_t len;
        uint8_t *file, rgba[TILE_SIZE * TILE_SIZE * 4];
        snprintf(path, sizeof path, "%s/%d/%ld/%ld.png", dir, zz, x, y);
        file = read_file(path, &len);
        assert_non_null(file);
        assert_int_equal(len, (size_t)sqlite3_column_bytes(s, 3));
        assert_memory_equal(file, sqlite3_column_blob(s, 3), len);
        assert_int_equal(tile_png_decode(sqlite3_column_blob(s, 3), len, rgba), 0);
        free(file);
        rows++;
    }
    sqlite3_finalize(s);
    sqlite3_close(db);
    assert_int_equal(rows, want);
    snprintf(buf, sizeof buf, "rm -rf '%s' '%s'", dir, mbt);
    assert_int_equal(system(buf), 0);
    plx_engine_free(e);
}

/* --attribution gives the MBTiles attribution, '' none; a bake, which
 * keeps no attribution, gives none unless given. */
static void test_mbtiles_attribution(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    char mbt[64], buf[256];
    const char *given[] = { "tiles", SCENE, "--quiet", "--zoom", "13", "--attribution", "Lights: the city's survey", "-o", mbt };
    const char *none[] = { "tiles", SCENE, "--quiet", "--zoom", "13", "--attribution", "", "-o", mbt };
    sqlite3 *db;
    (void)state;
    snprintf(mbt, sizeof mbt, "build/test_tiles_attr_%d.mbtiles", (int)getpid());
    assert_int_equal(run(cmd_tiles, 9, given), 0);
    assert_int_equal(sqlite3_open_v2(mbt, &db, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
    assert_string_equal(meta(db, "attribution", buf, sizeof buf), "Lights: the city's survey");
    sqlite3_close(db);
    assert_int_equal(unlink(mbt), 0);
    assert_int_equal(run(cmd_tiles, 9, none), 0);
    assert_int_equal(sqlite3_open_v2(mbt, &db, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
    assert_string_equal(meta(db, "attribution", buf, sizeof buf), "");
    assert_string_equal(meta(db, "format", buf, sizeof buf), "png");
    sqlite3_close(db);
    assert_int_equal(unlink(mbt), 0);
}

static void test_errors(void **state)
{
    const char *metres[] = { "tiles", "fixtures/tiny.geojson", "--quiet", "--zoom", "15", "-o", "build/never" };
    const char *zoom[] = { "tiles", SCENE, "--zoom", "16-15", "-o", "build/never" };
    const char *many[] = { "tiles", SCENE, "--quiet", "--zoom", "0-22", "-o", "build/never" };
    (void)state;
    assert_int_equal(run(cmd_tiles, 7, metres), EXIT_FAIL);
    assert_int_equal(run(cmd_tiles, 6, zoom), EXIT_USAGE);
    assert_int_equal(run(cmd_tiles, 7, many), EXIT_USAGE);
    assert_int_equal(access("build/never", F_OK), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mercator),
        cmocka_unit_test(test_tile_pixels_equal_heatmap),
        cmocka_unit_test(test_sc_tile_pixels_equal_heatmap),
        cmocka_unit_test(test_sc_least_over_directions),
        cmocka_unit_test(test_mbtiles_read_back),
        cmocka_unit_test(test_mbtiles_attribution),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
