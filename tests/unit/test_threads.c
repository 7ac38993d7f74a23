/* test_threads: a frame is the same bytes for any number of threads
 * (plx_config.threads, plx_port.parallel_for; src/render/shade_tiles.c's
 * shading pass).
 *
 * The eixample fixture with photon frames (indirect light from the photon
 * buffers: final gathering off; test_gather_same_bytes: on, through the
 * irradiance cache), a street view
 * and an aerial view, rendered with threads = 1 (the calling thread only),
 * 2 through the POSIX port's pthreads, and 3 through a port whose
 * parallel-for runs the jobs backwards on changing worker ids (a fixed
 * adversarial schedule); then 1 and 2 (backwards) with a lamp-region cache
 * too small for the frame (tiles whose regions are not cached are left to
 * the serial pass). The 8-bit image, the linear image and the counters must be equal. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "slow.h"

#define MEM ((size_t)192 << 20)
#define W 200
#define H 150

/* jobs from the last to the first, worker k % workers: every job on a
 * worker id that differs from a front-to-back run */
static int backwards_for(void *ctx, int workers, uint32_t njobs, void (*job)(void *arg, int worker, uint32_t k),
                         void *arg)
{
    uint32_t k;
    (void)ctx;
    for (k = njobs; k-- > 0;)
        job(arg, (int)(k % (uint32_t)workers), k);
    return 0;
}

typedef struct frame {
    uint8_t rgb8[W * H * 3];
    float rgbf[W * H * 3];
    plx_render_info info;
} frame;

/* Renders the street and the aerial view with the given threads and port;
 * small_cache: a lamp-region cache of 64 KiB; gather: 0 frames read the
 * radiance atlas (the default), 1 every pixel is shaded and gathers with
 * the irradiance cache, and only the street view is drawn (out[1]
 * zeroed), 2 every pixel is shaded and reads the photon buffers. */
static void render_pair_g(int threads, const plx_port *port, int small_cache, int gather, frame *out)
{
    plx_config cfg;
    plx_engine *e = NULL;
    plx_camera cam;
    plx_render_opts o;
    void *mem = calloc(1, MEM);
    int v, k;
    assert_non_null(mem);
    plx_config_default(&cfg);
    cfg.port = port;
    cfg.threads = threads;
    cfg.render_max_width = W;
    cfg.render_max_height = H;
    if (small_cache)
        cfg.lit_cache_bytes = 64 << 10;
    assert_int_equal(plx_engine_create(mem, MEM, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, "fixtures/eixample-4x4.geojson"), PLX_OK);
    for (k = 0; k < 2; k++)
        assert_int_equal(plx_indirect_step(e, 20000, 7), PLX_OK);
    if (gather != 1)
        assert_int_equal(plx_indirect_set_gather(e, 0), PLX_OK);
    memset(&out[1], 0, sizeof out[1]);
    for (v = 0; v < (gather == 1 ? 1 : 2); v++) { /* gathering: the street view */
        memset(&cam, 0, sizeof cam);
        if (v == 0) {
            cam.eye[0] = 298.6; cam.eye[1] = 265.5; cam.eye[2] = 1.7;
            cam.target[0] = 261.8; cam.target[1] = 302.3; cam.target[2] = 3.0;
        } else {
            cam.eye[0] = 150.0; cam.eye[1] = 50.0; cam.eye[2] = 250.0;
            cam.target[0] = 260.0; cam.target[1] = 280.0; cam.target[2] = 0.0;
        }
        cam.fov_deg = 60;
        cam.width = W;
        cam.height = H;
        plx_render_opts_default(&o);
        o.aerial = v;
        o.auto_exposure = 1;
        o.per_pixel = gather != 0;
        assert_int_equal(plx_render(e, &cam, &o, out[v].rgb8, out[v].rgbf, &out[v].info), PLX_OK);
    }
    plx_engine_destroy(e);
    free(mem);
}

static void render_pair(int threads, const plx_port *port, int small_cache, frame *out)
{
    render_pair_g(threads, port, small_cache, 0, out);
}

static void check_same(const frame *a, const frame *b)
{
    int v;
    for (v = 0; v < 2; v++) {
        assert_memory_equal(a[v].rgb8, b[v].rgb8, sizeof a[v].rgb8);
        assert_memory_equal(a[v].rgbf, b[v].rgbf, sizeof a[v].rgbf);
        assert_int_equal(a[v].info.shaded_pixels, b[v].info.shaded_pixels);
        assert_int_equal(a[v].info.drawn, b[v].info.drawn);
        assert_true(a[v].info.exposure == b[v].info.exposure);
    }
}

static void test_same_bytes(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    static frame one[2], other[2];
    plx_port back = *plx_port_posix();
    size_t p, lit = 0;
    (void)state;
    back.parallel_for = backwards_for;
    render_pair(1, plx_port_posix(), 0, one);
    /* a frame worth comparing: lit pixels in both views */
    for (p = 0; p < sizeof one[0].rgb8; p++)
        lit += one[0].rgb8[p] > 0 && one[1].rgb8[p] > 0;
    assert_true(lit > W * H / 10);
    render_pair(2, plx_port_posix(), 0, other);
    check_same(one, other);
    if (!getenv("PLX_TEST_QUICK")) {   /* make check: the other three */
        render_pair(3, &back, 0, other);
        check_same(one, other);
    }
    /* every pixel shaded: the lamp regions the workers need, left to the
     * calling thread with the small cache */
    render_pair_g(1, plx_port_posix(), 0, 2, one);
    render_pair_g(2, plx_port_posix(), 0, 2, other);
    check_same(one, other);
    render_pair_g(1, plx_port_posix(), 1, 2, one);
    render_pair_g(2, &back, 1, 2, other);
    check_same(one, other);
}

/* Street frames gathering with the irradiance cache: the cache is asked on
 * the calling thread only (at the corners of the sparse blocks, then the
 * pixels they leave), the direct light on the workers: the same bytes. */
static void test_gather_same_bytes(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    static frame one[2], other[2];
    plx_port back = *plx_port_posix();
    (void)state;
    back.parallel_for = backwards_for;
    render_pair_g(1, plx_port_posix(), 0, 1, one);
    assert_true(one[0].info.shaded_pixels > W * H / 4);
    render_pair_g(3, &back, 0, 1, other);
    check_same(one, other);
    if (!getenv("PLX_TEST_QUICK")) {
        render_pair_g(2, plx_port_posix(), 0, 1, other);
        check_same(one, other);
    }
}

/* The aerial map's indirect layer gathered by the irradiance cache on the
 * workers (renderapi.c: a cache and a light object each): the aerial frame
 * that reads it is the same bytes for 1, 2 and 3 (backwards) threads.
 * photon_frames 0: the same frame without indirect light. */
static void render_aerial_gathered(int threads, const plx_port *port, int photon_frames, frame *out)
{
    plx_config cfg;
    plx_engine *e = NULL;
    plx_camera cam;
    plx_render_opts o;
    void *mem = calloc(1, MEM);
    int k;
    assert_non_null(mem);
    plx_config_default(&cfg);
    cfg.port = port;
    cfg.threads = threads;
    cfg.render_max_width = W;
    cfg.render_max_height = H;
    assert_int_equal(plx_engine_create(mem, MEM, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, "fixtures/eixample-4x4.geojson"), PLX_OK);
    for (k = 0; k < photon_frames; k++)
        assert_int_equal(plx_indirect_step(e, 20000, 7), PLX_OK);
    memset(&cam, 0, sizeof cam);
    cam.eye[0] = 150.0; cam.eye[1] = 50.0; cam.eye[2] = 250.0;
    cam.target[0] = 260.0; cam.target[1] = 280.0; cam.target[2] = 0.0;
    cam.fov_deg = 60;
    cam.width = W;
    cam.height = H;
    plx_render_opts_default(&o);
    o.aerial = 1;
    o.aerial_m_per_texel = 2.0;
    o.no_glow = 1;
    o.per_pixel = 1; /* the light map's layer, not the radiance atlas */
    assert_int_equal(plx_render(e, &cam, &o, out->rgb8, out->rgbf, &out->info), PLX_OK);
    plx_engine_destroy(e);
    free(mem);
}

static void test_aerial_layer_same_bytes(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    static frame one, other;
    plx_port back = *plx_port_posix();
    size_t p, differ = 0;
    (void)state;
    back.parallel_for = backwards_for;
    render_aerial_gathered(1, plx_port_posix(), 1, &one);
    render_aerial_gathered(2, plx_port_posix(), 1, &other);
    assert_memory_equal(one.rgbf, other.rgbf, sizeof one.rgbf);
    assert_memory_equal(one.rgb8, other.rgb8, sizeof one.rgb8);
    render_aerial_gathered(3, &back, 1, &other);
    assert_memory_equal(one.rgbf, other.rgbf, sizeof one.rgbf);
    /* the layer is in the frame: without photons the ground is darker */
    render_aerial_gathered(1, plx_port_posix(), 0, &other);
    for (p = 0; p < W * H * 3; p++)
        differ += one.rgbf[p] > other.rgbf[p];
    assert_true(differ > W * H / 10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_bytes),
        cmocka_unit_test(test_gather_same_bytes),
        cmocka_unit_test(test_aerial_layer_same_bytes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
