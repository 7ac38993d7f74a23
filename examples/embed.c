/* embed.c: polarlux inside an application, the way a phone app or a board
 * would use it. Everything the engine uses comes from the caller:
 *   - one static block of memory (no malloc anywhere, here or in the engine),
 *     checked against plx_memory_estimate before the engine is made;
 *   - a scene loaded from memory (a GeoJSON string compiled in);
 *   - a route scored (how well lit is a walk along the street);
 *   - a frame rendered into the caller's own pixel buffer.
 * It links libpolarlux.a alone (+ libm): no port, no files, no threads, no
 * libpng, no cJSON. It checks its own results and exits non-zero when
 * something is off, so `make check` runs it as a test.
 *
 *   cc examples/embed.c -Iinclude build/libpolarlux.a -lm     (from the repository's root)
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "polarlux.h"

/* A street 20 m wide between two buildings, in local metres; three lamps
 * 6 m high, 25 m apart, down its middle. */
static const char scene_json[] =
    "{\"type\": \"FeatureCollection\", \"properties\": {\"units\": \"m\"},\n"
    " \"features\": [\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"north\", \"height\": 15},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[0,10],[80,10],[80,30],[0,30],[0,10]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"south\", \"height\": 9},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[0,-30],[80,-30],[80,-10],[0,-10],[0,-30]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 6, \"intensity\": 1000, \"radius\": 20},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [15, 0]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 6, \"intensity\": 1000, \"radius\": 20},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [40, 0]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 6, \"intensity\": 1000, \"radius\": 20},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [65, 0]}}\n"
    " ]}\n";

#define FRAME_W 160
#define FRAME_H 120

/* The application's memory: the engine lives in it and never asks for more. */
static unsigned char engine_block[3u << 20];
/* The application's frame buffer. */
static uint8_t frame[FRAME_W * FRAME_H * 3];

static int failures;

static void check(int ok, const char *what)
{
    printf("%s %s\n", ok ? "ok  " : "FAIL", what);
    failures += !ok;
}

static int stop(plx_engine *e, const char *call, plx_status st)
{
    fprintf(stderr, "embed: %s: %s: %s\n", call, plx_strerror(st), e ? plx_last_error(e) : "");
    return 1;
}

/* SPEC §2 for one lamp straight above a ground point: E = I / z^2 * W(z/R). */
static double under_lamp(double I, double z, double R)
{
    double x = z / R, w = 1.0 - x * x * x * x;
    return I / (z * z) * w * w;
}

int main(void)
{
    plx_config cfg;
    plx_scene_size size;
    plx_engine *e = NULL;
    plx_status st;
    size_t need;
    const double walk[4] = { 5.0, 0.0, 75.0, 0.0 };
    const double P[3] = { 40.0, 0.0, 0.0 }, N[3] = { 0.0, 0.0, 1.0 };
    plx_route_stats total, seg[1];
    plx_camera cam = { { 2.0, -3.0, 1.7 }, { 40.0, 0.0, 0.0 }, 60.0, FRAME_W, FRAME_H };
    plx_render_opts opts;
    double E, expect;
    size_t i, lit = 0;

    /* 1. Size the block first, then make the engine in it. */
    plx_config_default(&cfg);             /* no port: no clock, no log, no files */
    cfg.lit_cache_bytes = 512u << 10;
    cfg.render_max_width = FRAME_W;
    cfg.render_max_height = FRAME_H;
    plx_scene_size_scan(scene_json, sizeof scene_json - 1, &size);
    need = plx_memory_estimate(&size, &cfg, PLX_USE_LIGHT | PLX_USE_RENDER);
    printf("scene: %lu bytes, %lu positions; estimate %lu bytes, block %lu bytes\n",
           (unsigned long)size.text_bytes, (unsigned long)size.positions, (unsigned long)need,
           (unsigned long)sizeof engine_block);
    check(need > 0 && need <= sizeof engine_block, "the static block is large enough for the estimate");
    if ((st = plx_engine_create(engine_block, sizeof engine_block, &cfg, &e)) != PLX_OK)
        return stop(NULL, "plx_engine_create", st);

    /* 2. The scene, from memory. */
    if ((st = plx_load_geojson(e, scene_json, sizeof scene_json - 1, "street")) != PLX_OK)
        return stop(e, "plx_load_geojson", st);

    /* 3. Light under the middle lamp: the two others are 25 m away, beyond
     *    their 20 m reach, so SPEC §2 for one lamp gives the exact value. */
    if ((st = plx_illuminance(e, 1, P, N, &E, NULL, NULL)) != PLX_OK)
        return stop(e, "plx_illuminance", st);
    expect = under_lamp(1000.0, 6.0, 20.0);
    printf("under the middle lamp: %.6f lx (SPEC §2: %.6f lx)\n", E, expect);
    check(fabs(E - expect) <= 1e-9 * expect, "illuminance under a lamp matches SPEC §2");

    /* 4. A walk down the street, scored every metre. */
    if ((st = plx_route_score(e, walk, 2, 1.0, 1.0, &total, seg)) != PLX_OK)
        return stop(e, "plx_route_score", st);
    printf("walk: %.1f m, mean %.2f lx, min %.3f lx, max %.2f lx, P-class %d\n", total.length, total.mean,
           total.min, total.max, total.p_class);
    check(fabs(total.length - 70.0) < 1e-9 && total.samples == 71, "the walk is 70 m in 71 samples");
    check(fabs(total.max - expect) <= 1e-9 * expect, "the brightest sample is under a lamp");
    check(total.min < total.mean && total.mean < total.max, "min < mean < max");
    check(total.p_class == plx_p_class(total.mean, total.min), "the P-class follows mean and min");

    /* 5. A frame into the application's buffer: a pedestrian looking down the
     *    street. */
    plx_render_opts_default(&opts);
    memset(frame, 0, sizeof frame);
    if ((st = plx_render(e, &cam, &opts, frame, NULL, NULL)) != PLX_OK)
        return stop(e, "plx_render", st);
    for (i = 0; i < sizeof frame; i += 3)
        lit += frame[i] + frame[i + 1] + frame[i + 2] > 30;
    printf("frame: %dx%d, %lu of %d pixels lit\n", FRAME_W, FRAME_H, (unsigned long)lit, FRAME_W * FRAME_H);
    check(lit > 0 && lit < (size_t)FRAME_W * FRAME_H, "the frame has lit and dark pixels");

    plx_engine_destroy(e);
    printf("%s\n", failures ? "embed: FAILED" : "embed: all checks passed");
    return failures != 0;
}
