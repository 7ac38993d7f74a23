/* test_aa: automatic exposure (src/render/exposure.c) and anti-aliasing
 * (plx_render_opts.aa), through the public API.
 *
 *  - Automatic exposure: the chosen exposure maps the 99.5th percentile of
 *    the lit pixels' luminance (those within 12 stops of the 99.9th;
 *    ref_exposure.h, by sorting) to the key within
 *    the histogram's eighth of a stop, and every byte is the sRGB encoding
 *    (written here with pow) of the tone curve of exposure x radiance.
 *  - aa = N equals rendering N times larger with one sample per pixel and
 *    averaging each N x N block (the sample points are the same).
 *  - aa = 1 is the plain image, byte for byte.
 *  - Adaptive anti-aliasing (aa without aa_full): every pixel the later
 *    samples shaded (the engine's mask) is the full pass's value, bit for
 *    bit; every other one is its first sample's (taken from the image N
 *    times larger), and wherever the full pass differs from the first
 *    sample by more than 2% of white the pixel was shaded; in 8 bits the
 *    image is within 2 of the full pass everywhere.
 *  - The adaptive mask (render_aa_mask, without glows) on 1 and on 2
 *    workers equals a brute force: a pixel is marked when one of its 8
 *    neighbours has another surface id or a channel more than 2 steps
 *    apart in the 8-bit first sample; at sizes around its chunks of 64
 *    pixels, and rows of 1 and 2. Its count with the glows it marks is
 *    the marked bytes.
 *  - A later sample's mask update marks exactly the pixels whose surface
 *    is not the first sample's (and keeps the marks there), for ids
 *    sixteen at a time and jobs of 65,536 pixels, with the byte asked for
 *    new marks (1 or 2); and the pixels of the glows it sees, with that
 *    byte too.
 *  - The sums of the samples on the workers give the bits of one value at
 *    a time, for lengths around the lanes and the jobs.
 *  - A 2 x 2 frame's sums at the marked pixels only (render_aa_add_marked,
 *    render_tonemap_kept) give the dense sums' bits and bytes, for values
 *    of every kind (any bits, near FLT_MAX / 4 and beyond, 0, -0,
 *    infinite, NaN) and marks added at every sample; and a 2 x 2 frame
 *    into bytes gives the floats of the same frame into floats alone.
 *  - The rule behind it: four equal floats summed and scaled by 1/4 give
 *    the value's bits back up to FLT_MAX / 4, for all 2^32 floats (a
 *    sample and the edges in make check).
 *  - render_aa_mask with its marks elsewhere leaves the first sample's
 *    bytes in rgb: those of the plain frame.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "fixture.h"
#include "base/engine.h"
#include "render/render.h"
#include "render/render_aa.h"
#include "ref_exposure.h"

#define MEM ((size_t)256 << 20)

static plx_engine *open_eixample(void **mem)
{
    plx_config cfg;
    plx_config_default(&cfg);
    cfg.port = plx_port_posix();
    cfg.render_max_width = 480;
    cfg.render_max_height = 360;
    return fixture_load_file(fixture_engine_cfg(MEM, &cfg, mem), "fixtures/eixample-4x4.geojson");
}

static void street(plx_camera *cam, int w, int h)
{
    memset(cam, 0, sizeof *cam);
    cam->eye[0] = 298.6; cam->eye[1] = 265.5; cam->eye[2] = 1.7;
    cam->target[0] = 261.8; cam->target[1] = 302.3; cam->target[2] = 3.0;
    cam->fov_deg = 60;
    cam->width = w;
    cam->height = h;
}

/* street() as the renderer's camera. */
static void street_render(render_camera *cam, int w, int h)
{
    plx_camera pc;
    street(&pc, w, h);
    memcpy(cam->eye, pc.eye, sizeof cam->eye);
    memcpy(cam->target, pc.target, sizeof cam->target);
    cam->fov_deg = pc.fov_deg;
    cam->width = w;
    cam->height = h;
}

static double srgb(double v)
{
    double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return fmin(fmax(s, 0.0), 1.0);
}

static void test_auto_exposure(void **state)
{
    void *mem;
    plx_engine *e = open_eixample(&mem);
    plx_camera cam;
    plx_render_opts o;
    plx_render_info info;
    size_t px = 160 * 120, p, n = 0, off = 0;
    uint8_t *rgb8 = malloc(px * 3);
    float *lin = malloc(sizeof(float) * px * 3);
    double *y = malloc(sizeof(double) * px), yp, key = 1.0;
    (void)state;
    street(&cam, 160, 120);
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    o.no_glow = 1;
    o.exposure = 123.0; /* ignored */
    assert_int_equal(plx_render(e, &cam, &o, rgb8, lin, &info), PLX_OK);
    for (p = 0; p < px; p++) {
        double v = 0.2126 * lin[3 * p] + 0.7152 * lin[3 * p + 1] + 0.0722 * lin[3 * p + 2];
        if (v > 0)
            y[n++] = v;
    }
    assert_true(n > px / 4);
    yp = ref_exposure_luminance(y, n);
    assert_true(info.exposure * yp <= key * (1 + 1e-9));
    assert_true(info.exposure * yp > key * pow(2.0, -1.0 / 8.0) * (1 - 1e-6));
    for (p = 0; p < 3 * px; p++) {
        double v = info.exposure * lin[p], t = v > 0 ? v * (1 + v / 16.0) / (1 + v) : 0;
        long want = lround(255.0 * srgb(t));
        assert_true(labs((long)rgb8[p] - want) <= 1);
        off += (long)rgb8[p] != want;
    }
    assert_true(off * 1000 < 3 * px); /* off by one only at rounding ties */
    free(rgb8); free(lin); free(y);
    plx_engine_destroy(e);
    free(mem);
}

/* aa = n at W x H against one sample per pixel at n W x n H, averaged. */
static void aa_against_supersampling(plx_engine *e, int n, int W, int H)
{
    plx_camera cam;
    plx_render_opts o;
    float *small = malloc(sizeof(float) * W * H * 3), *big = malloc(sizeof(float) * W * H * 3 * n * n);
    size_t p, close = 0;
    double err = 0;
    int i, j, a, b, c;
    plx_render_opts_default(&o);
    o.no_glow = 1;
    o.aa = n;
    o.aa_full = 1;
    street(&cam, W, H);
    assert_int_equal(plx_render(e, &cam, &o, NULL, small, NULL), PLX_OK);
    o.aa = 1;
    street(&cam, W * n, H * n);
    assert_int_equal(plx_render(e, &cam, &o, NULL, big, NULL), PLX_OK);
    for (j = 0; j < H; j++)
        for (i = 0; i < W; i++)
            for (c = 0; c < 3; c++) {
                double sum = 0, got = small[((size_t)j * W + i) * 3 + c], d;
                for (b = 0; b < n; b++)
                    for (a = 0; a < n; a++)
                        sum += big[((size_t)(j * n + b) * W * n + (size_t)(i * n + a)) * 3 + c];
                sum /= n * n;
                d = fabs(got - sum);
                err += d;
                close += d <= 1e-5 * fmax(1.0, fabs(sum));
            }
    p = (size_t)W * H * 3;
    /* the same sample points: equal but for the last bits of the ray
     * directions, which may flip a sample exactly on an edge */
    assert_true(close * 1000 >= p * 998);
    assert_true(err / p < 1e-3);
    free(small);
    free(big);
}

static void test_aa(void **state)
{
    void *mem;
    plx_engine *e = open_eixample(&mem);
    plx_camera cam;
    plx_render_opts o;
    uint8_t *a8 = malloc(160 * 120 * 3), *b8 = malloc(160 * 120 * 3);
    (void)state;
    aa_against_supersampling(e, 2, 160, 120);
    aa_against_supersampling(e, 3, 160, 120);
    /* the sums by jobs of 65,536 values on the workers, and eight at a
     * time: two jobs, the second's last lanes short (203 x 111 x 3 =
     * 67,599 values) */
    aa_against_supersampling(e, 2, 203, 111);
    /* aa 1 is the plain image */
    street(&cam, 160, 120);
    plx_render_opts_default(&o);
    assert_int_equal(plx_render(e, &cam, &o, a8, NULL, NULL), PLX_OK);
    o.aa = 1;
    assert_int_equal(plx_render(e, &cam, &o, b8, NULL, NULL), PLX_OK);
    assert_memory_equal(a8, b8, 160 * 120 * 3);
    o.aa = 17;
    assert_int_equal(plx_render(e, &cam, &o, b8, NULL, NULL), PLX_E_INVALID);
    free(a8); free(b8);
    plx_engine_destroy(e);
    free(mem);
}

/* An engine for 480x360 frames draws 360x480 ones (a portrait screen's
 * from a landscape bake), and one for 360x480 draws 480x360 ones: the
 * same bytes as the engine for the frame's own size, read from the
 * radiance atlas or shaded pixel by pixel with indirect light looked up
 * sparsely (rows of corners as long as the frame's width, stop rows as
 * many as its height: buffers taken for the longer side; the debug
 * build asserts they hold the frame's), anti-aliased, and straight down;
 * 361x480 and 480x361 are refused. */
static void test_frame_turned(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    void *mem[2];
    plx_engine *e[2];
    plx_config cfg;
    plx_camera cam;
    plx_render_opts o;
    float *f[2];
    uint8_t *b[2];
    int k, view, turn, per_pixel;
    (void)state;
    plx_config_default(&cfg);
    cfg.port = plx_port_posix();
    for (k = 0; k < 2; k++) { /* e[0] for 480x360, e[1] for 360x480 */
        cfg.render_max_width = k ? 360 : 480;
        cfg.render_max_height = k ? 480 : 360;
        e[k] = fixture_load_file(fixture_engine_cfg(MEM, &cfg, &mem[k]), "fixtures/eixample-4x4.geojson");
        assert_int_equal(plx_indirect_step(e[k], 16384, 1), PLX_OK);
        f[k] = malloc(sizeof(float) * 480 * 360 * 3);
        b[k] = malloc((size_t)480 * 360 * 3);
    }
    for (turn = 0; turn < 2; turn++) /* frames 360x480, then 480x360 */
        for (per_pixel = 0; per_pixel < 2; per_pixel++)
            for (view = 0; view < 2; view++) {
                int w = turn ? 480 : 360, h = turn ? 360 : 480;
                plx_render_opts_default(&o);
                o.aa = 2;
                o.per_pixel = per_pixel;
                street(&cam, w, h);
                if (view == 1) {
                    o.aerial = 1;
                    cam.eye[0] = cam.target[0] = 266.0;
                    cam.eye[1] = cam.target[1] = 266.0;
                    cam.eye[2] = 800.0;
                    cam.target[2] = 0.0;
                }
                for (k = 0; k < 2; k++)
                    assert_int_equal(plx_render(e[k], &cam, &o, b[k], f[k], NULL), PLX_OK);
                assert_memory_equal(b[0], b[1], (size_t)w * h * 3);
                assert_memory_equal(f[0], f[1], sizeof(float) * w * h * 3);
            }
    street(&cam, 361, 480);
    assert_int_equal(plx_render(e[0], &cam, &o, b[0], NULL, NULL), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(e[0]), "a 361x480 frame is outside 1x1 .. 480x360 (or 360x480)"));
    street(&cam, 480, 361);
    assert_int_equal(plx_render(e[0], &cam, &o, b[0], NULL, NULL), PLX_E_INVALID);
    for (k = 0; k < 2; k++) {
        free(f[k]);
        free(b[k]);
        plx_engine_destroy(e[k]);
        free(mem[k]);
    }
}

/* Equal within float rounding (the ray directions' last bits). */
static int near_equal(double a, double b)
{
    return fabs(a - b) <= 1e-5 * fmax(1.0, fabs(b));
}

/* Adaptive against full anti-aliasing at n x n, glows on, automatic
 * exposure; the first samples from one sample per pixel at n w x n h
 * (sparse: the indirect light is interpolated over blocks of 4 x 4 pixels
 * of each image, so the larger one's first samples are not the same
 * values; only the shaded pixels against the full pass are checked then). */
static void aa_adaptive(plx_engine *e, int n, int sparse)
{
    enum { W = 160, H = 120 };
    plx_camera cam;
    plx_render_opts o;
    plx_render_info ia, iff;
    size_t px = (size_t)W * H, p, full = 0, first = 0, far8 = 0;
    float *ad = malloc(sizeof(float) * px * 3), *fu = malloc(sizeof(float) * px * 3);
    float *big = malloc(sizeof(float) * px * 3 * n * n);
    uint8_t *ad8 = malloc(px * 3), *fu8 = malloc(px * 3), *mask = malloc(px);
    int i, j, c, maxd = 0;
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    o.aa = n;
    street(&cam, W, H);
    assert_int_equal(plx_render(e, &cam, &o, ad8, ad, &ia), PLX_OK);
    assert_true(ia.aa_adaptive == PLX_AA_ADAPTIVE && e->aa_mask);
    memcpy(mask, e->aa_mask, px);  /* the pixels the later samples shaded */
    o.aa_full = 1;
    assert_int_equal(plx_render(e, &cam, &o, fu8, fu, &iff), PLX_OK);
    assert_true(ia.exposure == iff.exposure);  /* the first sample's, both */
    o.aa = 1;
    o.aa_full = 0;
    street(&cam, W * n, H * n);
    assert_int_equal(plx_render(e, &cam, &o, NULL, big, NULL), PLX_OK);
    for (j = 0; j < H; j++)
        for (i = 0; i < W; i++) {
            const float *f0 = big + ((size_t)(j * n) * W * n + (size_t)(i * n)) * 3;
            int is_full = 1, is_first = 1, d8 = 0;
            p = (size_t)j * W + i;
            for (c = 0; c < 3; c++) {
                int d = abs((int)ad8[3 * p + c] - (int)fu8[3 * p + c]);
                is_full &= ad[3 * p + c] == fu[3 * p + c];   /* the same rays: the same bits */
                is_first &= near_equal(ad[3 * p + c], f0[c]);
                maxd = d > maxd ? d : maxd;
                d8 |= fabs(fu[3 * p + c] - f0[c]) * ia.exposure > 0.02;
            }
            /* shaded: the full pass's value; else the first sample's */
            if (mask[p])
                assert_true(is_full);
            else
                assert_true(is_first || sparse);
            full += mask[p] != 0;
            first += !mask[p];
            /* a pixel whose samples differ much took them all */
            if (d8 && !mask[p] && !sparse)
                far8++;
        }
    print_message("aa %d adaptive%s: %zu of %zu pixels took every sample, %zu the first only; "
                  "8-bit difference to the full pass at most %d; %zu pixels far from their "
                  "first sample left at it\n", n, sparse ? " (indirect)" : "", full, px, first, maxd, far8);
    assert_true(first > px / 4 && full > px / 50);  /* both kinds: the mask does something */
    assert_true(maxd <= 2);
    assert_int_equal(far8, 0);
    free(ad); free(fu); free(big); free(ad8); free(fu8); free(mask);
}

static void test_aa_adaptive(void **state)
{
    void *mem;
    plx_engine *e = open_eixample(&mem);
    (void)state;
    aa_adaptive(e, 2, 0);
    aa_adaptive(e, 3, 0);
    /* with indirect light (sparse street lookups) too */
    assert_int_equal(plx_indirect_step(e, 16384, 1), PLX_OK);
    aa_adaptive(e, 2, 1);
    plx_engine_destroy(e);
    free(mem);
}

/* A frame shaded pixel by pixel (not read from the radiance atlas) stays
 * adaptive however many pixels its mask marks: the dense rule
 * (PLX_AA_DENSE, test_bake's test_aa_dense) is for atlas frames only,
 * where a pixel costs little more than its rasterising. */
static void test_aa_dense_atlas_only(void **state)
{
    void *mem;
    plx_engine *e = open_eixample(&mem);
    plx_camera cam;
    plx_render_opts o;
    plx_render_info info;
    size_t px = 160 * 120, p, marked = 0;
    uint8_t *rgb8 = malloc(px * 3);
    (void)state;
    memset(&cam, 0, sizeof cam);
    cam.eye[0] = cam.target[0] = 266.0;
    cam.eye[1] = 200.0;
    cam.target[1] = 267.0;
    cam.eye[2] = 400.0;
    cam.fov_deg = 60;
    cam.width = 160;
    cam.height = 120;
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    o.aa = 2;
    o.aerial = 1;
    assert_int_equal(plx_render(e, &cam, &o, rgb8, NULL, &info), PLX_OK);
    for (p = 0; p < px; p++)
        marked += e->aa_mask[p] != 0;
    print_message("aerial, shaded per pixel: %zu of %zu pixels marked\n", marked, px);
    assert_true(marked > px / 2);
    assert_int_equal(info.aa_adaptive, PLX_AA_ADAPTIVE);
    plx_engine_destroy(e);
    free(mem);
    free(rgb8);
}

/* Brute force: pixel (i, j) against each of its 8 neighbours. */
static int brute_mark(const uint8_t *rgb, const uint32_t *id, int w, int h, int i, int j, int level)
{
    int di, dj, c;
    for (dj = -1; dj <= 1; dj++)
        for (di = -1; di <= 1; di++) {
            int x = i + di, y = j + dj;
            size_t p = (size_t)j * w + i, q = (size_t)y * w + x;
            if ((di == 0 && dj == 0) || x < 0 || y < 0 || x >= w || y >= h)
                continue;
            if (id[p] != id[q])
                return 1;
            for (c = 0; c < 3; c++)
                if (abs((int)rgb[3 * p + c] - (int)rgb[3 * q + c]) > level)
                    return 1;
        }
    return 0;
}

static void mask_against_brute(plx_engine *e, int w, int h, int workers)
{
    plx_camera cam;
    plx_render_opts o;
    plx_render_info info;
    render_opts ro;
    size_t px = (size_t)w * h, p, marked = 0, n;
    uint8_t *rgb8 = malloc(px * 3), *scratch = malloc(px * 3), *keep = malloc(px), *mask = malloc(px);
    uint32_t *id = malloc(px * sizeof *id), *id0 = malloc(px * sizeof *id0);
    int i, j, level;
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    street(&cam, w, h);
    assert_int_equal(plx_render(e, &cam, &o, rgb8, NULL, &info), PLX_OK);
    memcpy(id, render_ids(e->rd), px * sizeof *id);
    render_opts_default(&ro);
    ro.no_glow = 1;
    ro.par = e->port.parallel_for;
    ro.par_ctx = e->port.ctx;
    ro.workers = workers;
    for (level = 0; level <= 7; level += level < 2 ? 1 : 5) { /* 0, 1, 2 (AA_LEVEL), 7 */
        n = render_aa_mask(e->rd, &ro, info.exposure, 1, level, scratch, keep, id0, mask, NULL);
        assert_memory_equal(scratch, rgb8, px * 3); /* the first sample's bytes, kept */
        marked = 0;
        for (j = 0; j < h; j++)
            for (i = 0; i < w; i++) {
                p = (size_t)j * w + i;
                assert_int_equal(id0[p], id[p]);
                assert_int_equal(mask[p], brute_mark(rgb8, id, w, h, i, j, level));
                marked += mask[p];
            }
        assert_int_equal(n, marked);
        if (h > 2) /* a row or two of a street view may be all edges */
            assert_true(marked > 0 && marked < px); /* edges, and flat parts */
    }
    print_message("mask %dx%d on %d workers: %zu of %zu pixels marked (level 7), as the brute force at levels 0, 1, "
                  "2 and 7\n", w, h, workers, marked, px);
    free(rgb8); free(scratch); free(keep); free(mask); free(id); free(id0);
}

/* render_aa_mask_update (a later sample with render_opts.mask): every pixel whose
 * surface (the ground and the sky as one) is not mask_id's gets marked,
 * the marks already there stay, and no other pixel is marked (no glows);
 * on the given workers, at w x h (ids sixteen at a time, jobs of 65,536
 * pixels). */
static void mask_update_against_brute(plx_engine *e, int w, int h, int workers, uint8_t nw)
{
    render_camera cam;
    render_opts ro;
    render_stats st;
    size_t px = (size_t)w * h, p, marked = 0, changed = 0;
    uint32_t *id0 = malloc(px * sizeof *id0);
    uint8_t *mask = malloc(px), *before = malloc(px);
    street_render(&cam, w, h);
    render_opts_default(&ro);
    ro.no_glow = 1;
    ro.par = e->port.parallel_for;
    ro.par_ctx = e->port.ctx;
    ro.workers = workers;
    ro.shift[0] = ro.shift[1] = -0.25;
    assert_int_equal(render_frame(e->rd, &cam, &ro, NULL, NULL, &st), PLX_OK);
    memcpy(id0, render_ids(e->rd), px * sizeof *id0);
    for (p = 0; p < px; p++) {
        before[p] = mask[p] = p % 7 == 0;
        if (p % 5 == 0 || p + 3 >= px) /* surfaces of no frame, the last pixels among them */
            id0[p] = 0xfffff000u + (uint32_t)(p % 3);
    }
    ro.mask = mask;
    ro.mask_id = id0;
    ro.mask_new = nw;
    ro.shift[0] = 0.25;
    ro.shift[1] = 0.25;
    assert_int_equal(render_frame(e->rd, &cam, &ro, NULL, NULL, &st), PLX_OK);
    for (p = 0; p < px; p++) {
        uint32_t a = render_ids(e->rd)[p], b = id0[p];
        int other = (a == 1 ? 0 : a) != (b == 1 ? 0 : b);
        assert_int_equal(mask[p], before[p] ? before[p] : other * (nw ? nw : 1));
        marked += mask[p] != 0;
        changed += other;
    }
    print_message("mask update %dx%d on %d workers: %zu pixels meet another surface at the later sample, as the "
                  "brute force\n", w, h, workers, changed);
    assert_true(changed > 0 && marked < px);
    free(id0); free(mask); free(before);
}

/* render_aa_mask_update's glows: a later sample whose surfaces are all the first's
 * (mask_id: its own ids) marks the pixels of the glows it sees, with byte
 * render_opts.mask_new (2), and keeps the marks already there (1). */
static void mask_update_glows(plx_engine *e, int w, int h)
{
    render_camera cam;
    render_opts ro;
    render_stats st;
    size_t px = (size_t)w * h, p, news = 0, kept = 0;
    uint32_t *id0 = malloc(px * sizeof *id0);
    uint8_t *mask = malloc(px);
    street_render(&cam, w, h);
    render_opts_default(&ro);
    ro.shift[0] = ro.shift[1] = 0.25;
    assert_int_equal(render_frame(e->rd, &cam, &ro, NULL, NULL, &st), PLX_OK);
    memcpy(id0, render_ids(e->rd), px * sizeof *id0);
    for (p = 0; p < px; p++)
        mask[p] = p % 3 == 0;
    ro.mask = mask;
    ro.mask_id = id0;
    ro.mask_new = 2;
    assert_int_equal(render_frame(e->rd, &cam, &ro, NULL, NULL, &st), PLX_OK);
    for (p = 0; p < px; p++) {
        assert_true(p % 3 == 0 ? mask[p] == 1 : mask[p] == 0 || mask[p] == 2);
        news += mask[p] == 2;
        kept += mask[p] == 1;
    }
    assert_true(st.glows > 0 && news > 0);
    print_message("mask update %dx%d, glows only: %zu pixels newly marked 2 (%u glows), %zu marks kept\n", w, h, news,
                  (unsigned)st.glows, kept);
    free(id0); free(mask);
}

/* render_aa_mask's count with the glows it marks: the marked bytes. */
static void mask_count_with_glows(plx_engine *e, int w, int h)
{
    plx_camera cam;
    plx_render_opts o;
    plx_render_info info;
    render_opts ro;
    size_t px = (size_t)w * h, p, marked = 0, n, plain;
    uint8_t *scratch = malloc(px * 3), *mask = malloc(px);
    uint32_t *id0 = malloc(px * sizeof *id0);
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    street(&cam, w, h);
    assert_int_equal(plx_render(e, &cam, &o, NULL, NULL, &info), PLX_OK);
    render_opts_default(&ro);
    ro.no_glow = 1;
    ro.par = e->port.parallel_for;
    ro.par_ctx = e->port.ctx;
    ro.workers = 2;
    /* level 255: surface edges only, so that the glows mark pixels of their own */
    plain = render_aa_mask(e->rd, &ro, info.exposure, 1, 255, scratch, scratch, id0, mask, NULL);
    ro.no_glow = 0;
    n = render_aa_mask(e->rd, &ro, info.exposure, 1, 255, scratch, scratch, id0, mask, NULL);
    for (p = 0; p < px; p++)
        marked += mask[p];
    print_message("mask %dx%d with glows: %zu pixels marked, %zu without the glows\n", w, h, n, plain);
    assert_int_equal(n, marked);
    assert_true(n > plain); /* the street view sees glows */
    free(scratch); free(mask); free(id0);
}

/* The sums of the samples (render_aa_copy, render_aa_add,
 * render_aa_scale), eight values at a time in jobs of 65,536 on the
 * workers, against one value at a time: the same bits, for lengths around
 * the lanes and the jobs. */
static void test_aa_sums(void **state)
{
    static const size_t lens[] = { 0, 1, 7, 8, 9, 65535, 65536, 65537, 131079, 200003 };
    const plx_port *port = plx_port_posix();
    size_t i, p, n = 200003;
    float *lin = malloc(n * sizeof *lin), *sum = malloc(n * sizeof *sum), *ref = malloc(n * sizeof *ref);
    uint64_t seed = 7;
    int workers;
    (void)state;
    for (p = 0; p < n; p++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        lin[p] = (float)((double)(seed >> 11) / 9007199254740992.0 * 1000.0);
    }
    for (workers = 1; workers <= 2; workers++)
        for (i = 0; i < sizeof lens / sizeof *lens; i++) {
            size_t m = lens[i];
            render_opts ro;
            render_opts_default(&ro);
            ro.par = port->parallel_for;
            ro.par_ctx = port->ctx;
            ro.workers = workers;
            for (p = 0; p < n; p++)
                sum[p] = ref[p] = -1.0f;
            render_aa_copy(&ro, sum, lin, m);
            render_aa_add(&ro, sum, lin + 1, m > 0 ? m - 1 : 0);
            render_aa_add(&ro, sum, lin, m);
            render_aa_scale(&ro, sum, m, 1.0 / 3.0);
            for (p = 0; p < m; p++) {
                ref[p] = lin[p];
                if (p + 1 < m)
                    ref[p] += lin[p + 1];
                ref[p] += lin[p];
                ref[p] = (float)(ref[p] * (1.0 / 3.0));
            }
            assert_memory_equal(sum, ref, n * sizeof *sum); /* and nothing past m written */
        }
    print_message("anti-aliasing sums: the same bits as one value at a time for 10 lengths from 0 to 200,003 "
                  "on 1 and 2 workers\n");
    free(lin); free(sum); free(ref);
}

/* A random float for the 2 x 2 sums: mostly any finite bits (of either
 * sign, every exponent), some near FLT_MAX / 4 and beyond, some 0, -0,
 * infinite or NaN. */
static float any_float(uint64_t *seed)
{
    uint32_t u;
    float v;
    *seed = *seed * 6364136223846793005ull + 1442695040888963407ull;
    u = (uint32_t)(*seed >> 32);
    switch ((*seed >> 24) & 15) {
    case 0: return 0.0f;
    case 1: return -0.0f;
    case 2: /* infinite, quiet or signalling NaN */
        if ((u & 3) == 3) {
            u = 0x7fa00000u | (u >> 12);
            memcpy(&v, &u, sizeof v);
            return v;
        }
        return (u & 3) == 0 ? INFINITY : (u & 3) == 1 ? -INFINITY : NAN;
    case 3: return FLT_MAX / 4.0f * (1.0f + (float)(u & 1023) / 4096.0f); /* about the limit */
    default: break;
    }
    memcpy(&v, &u, sizeof v);
    return isnan(v) ? 1.0f : v;
}

/* The 2 x 2 sums at the marked pixels (render_aa_add_marked, then
 * render_tonemap_kept) against the dense sums, at 150x111 (two jobs of
 * 16,384 pixels, the last 64 short by 54) on 1 and 2 workers: random
 * values of every kind (any_float; tame: all finite and within FLT_MAX
 * / 4, where the first sample's tone map says so and the end reads only the marked
 * pixels), a quarter of the pixels marked after
 * the first sample and more at each later one (as a sliver or a glow
 * marks them: byte 2); a later sample's value is its own at the pixels
 * marked by then and the first sample's elsewhere, as the renderer leaves
 * them. The sums end with the dense sums' bits, scaled, at every pixel,
 * and the bytes are the dense sums' tone map where the first sample's
 * bytes (the mask's) were in place. */
static void marked_sums_against_dense(plx_engine *e, int workers, int tame)
{
    const int w = 150, h = 111;
    plx_camera cam;
    plx_render_opts o;
    plx_render_info info;
    render_opts ro;
    size_t px = (size_t)w * h, p, v, kept = 0, again = 0;
    float *smp = malloc(px * 3 * 4 * sizeof *smp), *lin = malloc(px * 3 * sizeof *lin);
    float *dense = malloc(px * 3 * sizeof *dense), *sum = malloc(px * 3 * sizeof *sum);
    uint8_t *rgb8 = malloc(px * 3), *ref = malloc(px * 3), *first = malloc(px * 3);
    uint8_t *mask = calloc(px, 1), *when = malloc(px);
    uint64_t seed = 5;
    int s, far;
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    street(&cam, w, h);
    assert_int_equal(plx_render(e, &cam, &o, rgb8, NULL, &info), PLX_OK); /* the tone map's tables */
    for (v = 0; v < px * 3 * 4; v++) {
        smp[v] = any_float(&seed);
        if (tame && !(fabsf(smp[v]) <= 1e30f)) /* tame: all finite, within the limit */
            smp[v] = (float)v;
    }
    for (p = 0; p < px; p++) { /* the sample that marks it: 0 .. 3, or 4: never */
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        when[p] = (uint8_t)((seed >> 60) < 4 ? 0 : (seed >> 60) < 7 ? 1 + (seed >> 60) % 3 : 4);
    }
    render_opts_default(&ro);
    ro.par = e->port.parallel_for;
    ro.par_ctx = e->port.ctx;
    ro.workers = workers;
    /* dense: every value of every sample added, then scaled */
    memcpy(dense, smp, px * 3 * sizeof *dense);
    for (s = 1; s < 4; s++) {
        for (v = 0; v < px * 3; v++)
            lin[v] = when[v / 3] <= s ? smp[(size_t)s * px * 3 + v] : smp[v];
        render_aa_add(&ro, dense, lin, px * 3);
    }
    render_aa_scale(&ro, dense, px * 3, 0.25);
    render_tonemap_par(e->rd, dense, px, info.exposure, 1, ref, &ro);
    /* marked: the first sample's bytes in place, then the marked sums */
    far = render_tonemap_par(e->rd, smp, px, info.exposure, 1, first, &ro);
    memcpy(rgb8, first, px * 3);
    render_aa_copy(&ro, sum, smp, px * 3);
    assert_int_equal(far, !tame);
    for (p = 0; p < px; p++)
        mask[p] = when[p] == 0;
    for (s = 1; s < 4; s++) {
        for (p = 0; p < px; p++)
            if (when[p] == s)
                mask[p] = 2;
        for (v = 0; v < px * 3; v++)
            lin[v] = when[v / 3] <= s ? smp[(size_t)s * px * 3 + v] : smp[v];
        render_aa_add_marked(&ro, sum, lin, mask, px, s - 1);
    }
    for (p = 0; p < px; p++)
        assert_int_equal(mask[p], when[p] < 4);
    render_tonemap_kept(e->rd, sum, mask, px, far, info.exposure, 1, rgb8, &ro);
    for (v = 0; v < px * 3; v++) /* the same bits; a NaN's payload and sign are C's to choose (an add
                                    of two NaNs keeps either, by the order the compiler gives them) */
        if (!(isnan(sum[v]) && isnan(dense[v])))
            assert_memory_equal(sum + v, dense + v, sizeof *sum);
    assert_memory_equal(rgb8, ref, px * 3);
    for (v = 0; v < px * 3; v++) {
        kept += when[v / 3] == 4;
        again += when[v / 3] < 4;
    }
    assert_true(kept > px && again > px);
    print_message("2x2 sums at the marked pixels 150x111 on %d workers%s: the dense sums' bits and bytes (%zu "
                  "values marked, %zu kept)\n", workers, tame ? ", all values within the limit" : "", again, kept);
    free(smp); free(lin); free(dense); free(sum); free(rgb8); free(ref); free(first); free(mask); free(when);
}

/* plx_render at 2 x 2 into bytes (the sums at the marked pixels) against
 * the same frame into floats alone (the dense sums), n street cameras
 * along the 4 x 4 Eixample with glows: the same floats, and the bytes are
 * their tone map; the pixels the later samples shaded (aa_later) between
 * the marked pixels and three times them. */
static void marked_frames_against_dense(plx_engine *e, int n)
{
    const int w = 160, h = 120;
    plx_camera cam;
    plx_render_opts o;
    plx_render_info ia, ib;
    render_opts ro;
    size_t px = (size_t)w * h;
    float *fa = malloc(px * 3 * sizeof *fa), *fb = malloc(px * 3 * sizeof *fb);
    uint8_t *a8 = malloc(px * 3), *b8 = malloc(px * 3);
    int k;
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    o.aa = 2;
    render_opts_default(&ro);
    for (k = 0; k < n; k++) {
        size_t marked = 0, p;
        street(&cam, w, h);
        cam.eye[0] -= 3.0 * k;
        cam.eye[1] += 1.5 * k;
        cam.target[0] -= 3.0 * k;
        cam.target[1] += 1.5 * k;
        assert_int_equal(plx_render(e, &cam, &o, a8, fa, &ia), PLX_OK);
        assert_int_equal(ia.aa_adaptive, PLX_AA_ADAPTIVE);
        for (p = 0; p < px; p++)
            marked += e->aa_mask[p] != 0;
        assert_true(marked > 0 && ia.aa_later >= marked && ia.aa_later <= 3 * marked);
        assert_int_equal(plx_render(e, &cam, &o, NULL, fb, &ib), PLX_OK);
        assert_memory_equal(fa, fb, px * 3 * sizeof *fa);
        render_tonemap_par(e->rd, fb, px, ib.exposure, 1, b8, &ro);
        assert_memory_equal(a8, b8, px * 3);
    }
    print_message("2x2 frames into bytes%s: the floats of the frames into floats alone, and their bytes (%d "
                  "cameras)\n", plx_indirect_frames(e) > 0 ? " (from the radiance atlas)" : "", n);
    free(fa); free(fb); free(a8); free(b8);
}

/* The first sample's tone map's answer (render_tonemap_par), which the
 * 2 x 2 sums at the marked pixels take as whether a value is past
 * FLT_MAX / 4 or NaN: one such value at places across its jobs of 65,536
 * values, on 1 and 2 workers, against none; the limit itself is not past. */
static void tonemap_far_answers(plx_engine *e)
{
    static const size_t at[] = { 0, 7, 65535, 65536, 65539, 3 * 320 * 240 - 1 };
    const size_t px = 320 * 240;
    float *lin = malloc(px * 3 * sizeof *lin);
    uint8_t *rgb8 = malloc(px * 3);
    render_opts ro;
    size_t v, i;
    int workers;
    for (v = 0; v < px * 3; v++)
        lin[v] = (float)(v % 977) * 0.01f;
    render_opts_default(&ro);
    ro.par = e->port.parallel_for;
    ro.par_ctx = e->port.ctx;
    for (workers = 1; workers <= 2; workers++) {
        ro.workers = workers;
        assert_int_equal(render_tonemap_par(e->rd, lin, px, 2.0, 1, rgb8, &ro), 0);
        for (i = 0; i < sizeof at / sizeof *at; i++) {
            float keep = lin[at[i]];
            lin[at[i]] = i % 3 == 0 ? NAN : i % 3 == 1 ? FLT_MAX / 3.0f : -FLT_MAX / 3.0f;
            assert_int_equal(render_tonemap_par(e->rd, lin, px, 2.0, 1, rgb8, &ro), 1);
            lin[at[i]] = FLT_MAX / 4.0f;
            assert_int_equal(render_tonemap_par(e->rd, lin, px, 2.0, 1, rgb8, &ro), 0);
            lin[at[i]] = keep;
        }
    }
    free(lin);
    free(rgb8);
}

static void test_marked_sums(void **state)
{
    void *mem;
    plx_engine *e = open_eixample(&mem);
    (void)state;
    marked_sums_against_dense(e, 1, 0);
    tonemap_far_answers(e); /* the renderer's tables made by the frame above */
    marked_sums_against_dense(e, 2, 0);
    marked_sums_against_dense(e, 2, 1); /* no value past the limit: only the marked pixels read */
    marked_frames_against_dense(e, 24);
    assert_int_equal(plx_indirect_step(e, 16384, 1), PLX_OK); /* frames from the radiance atlas */
    marked_frames_against_dense(e, 8);
    plx_engine_destroy(e);
    free(mem);
}

/* The rule the 2 x 2 sums at the marked pixels rest on: the dense sums
 * of four equal values v, ((v + v) + v) + v scaled by 1/4 as aa_add and
 * aa_scale do, give v's bits back for every float with |v| <= FLT_MAX /
 * 4: all 2^32 bit patterns (PLX_TEST_QUICK: every 4,099th, and every
 * pattern near 0, near FLT_MAX / 4 and among the subnormals' top). */
static int four_equal_back(uint32_t u)
{
    float v, s;
    uint32_t b;
    memcpy(&v, &u, sizeof v);
    if (!(fabsf(v) <= FLT_MAX / 4.0f))
        return 1;
    s = v;
    s += v;
    s += v;
    s += v;
    s = (float)(s * 0.25);
    memcpy(&b, &s, sizeof b);
    return b == u;
}

static void test_four_equal_values(void **state)
{
    const int quick = getenv("PLX_TEST_QUICK") != NULL;
    const uint32_t lim = 0x7e800000u; /* FLT_MAX / 4's bits, rounded up to its binade's end */
    uint64_t n = 0, bad = 0, u;
    uint32_t sign, k;
    (void)state;
    for (u = 0; u <= UINT32_MAX; u += quick ? 4099u : 1u) {
        n++;
        bad += !four_equal_back((uint32_t)u);
    }
    for (sign = 0; sign < 2; sign++) /* the edges, every pattern */
        for (k = 0; k < 65536; k++) {
            uint32_t s = sign << 31;
            bad += !four_equal_back(s | k);                     /* 0 and the smallest subnormals */
            bad += !four_equal_back(s | (0x00800000u - 1u - k)); /* the largest subnormals */
            bad += !four_equal_back(s | (0x00800000u + k));      /* the smallest normals */
            bad += !four_equal_back(s | (lim - 1u - k));         /* up to FLT_MAX / 4 */
            n += 4;
        }
    print_message("four equal values summed and scaled by 1/4: %llu bit patterns, %llu not given back (%s)\n",
                  (unsigned long long)n, (unsigned long long)bad, quick ? "a sample and the edges" : "all 2^32");
    assert_true(bad == 0);
}

static void test_aa_mask(void **state)
{
    void *mem;
    plx_engine *e = open_eixample(&mem);
    (void)state;
    /* bands of 16 rows: a height that is not a multiple, and one band */
    mask_against_brute(e, 160, 120, 1);
    mask_against_brute(e, 160, 120, 2);
    mask_against_brute(e, 97, 45, 2);
    mask_against_brute(e, 31, 9, 2);
    /* the vector chunks of 64 pixels inside a row: exactly two (130), the
     * smallest row that takes one (66), one too short (65), and a last
     * chunk overlapping the one before (200) */
    mask_against_brute(e, 130, 20, 1);
    mask_against_brute(e, 66, 17, 2);
    mask_against_brute(e, 65, 17, 1);
    mask_against_brute(e, 200, 33, 2);
    mask_against_brute(e, 66, 1, 2);
    mask_against_brute(e, 130, 2, 1);
    mask_update_against_brute(e, 160, 120, 1, 0);
    mask_update_against_brute(e, 203, 111, 2, 2); /* new marks 2 (2 x 2 sums at the marked pixels) */
    mask_update_against_brute(e, 300, 230, 2, 1); /* two jobs of ids */
    mask_update_glows(e, 160, 120);
    mask_count_with_glows(e, 160, 120);
    plx_engine_destroy(e);
    free(mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_auto_exposure),
        cmocka_unit_test(test_aa),
        cmocka_unit_test(test_frame_turned),
        cmocka_unit_test(test_aa_adaptive),
        cmocka_unit_test(test_aa_dense_atlas_only),
        cmocka_unit_test(test_aa_sums),
        cmocka_unit_test(test_aa_mask),
        cmocka_unit_test(test_marked_sums),
        cmocka_unit_test(test_four_equal_values),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
