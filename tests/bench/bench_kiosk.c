/* bench_kiosk: bake once, then walk at frame rate (issue "Kiosk mode").
 *
 * City: gen eixample 30 30 (14,400 buildings). In one process:
 *  - baseline, today's render path from the GeoJSON: load, photon frames,
 *    one 640x480 street frame with indirect light, one 1024x768 aerial
 *    frame (which builds the light map);
 *  - the bake: load, plx_bake_prepare (polar, light, photons, renderer,
 *    light map), the same photon frames, the twin, plx_bake_save; on one
 *    thread, then again on two (the POSIX port's parallel-for): the
 *    ratio of their wall times, and whether the two files are the same
 *    bytes;
 *  - loading the bake into a block touched beforehand (median of 5);
 *  - a street walk (640x480, indirect, one sample per pixel) and an aerial
 *    walk (1024x768) from the loaded engine, its frames read from the
 *    radiance atlas: median and p95 per frame, with one thread and then
 *    with two (the POSIX port's parallel-for); beside them the same walks
 *    with every pixel shaded (plx_render_opts.per_pixel: the frames of
 *    before the atlas), the ratio of the medians; and the aerial cameras
 *    at 256x192, a sixteenth of the pixels: what a frame costs before its
 *    pixels (culling, vertices, triangle set-up), as a share of the
 *    1024x768 frame; and the street walk with 2 x 2 samples (walk's
 *    default, adaptive), against its one-sample frames; on two threads
 *    also with every sample (--aa-full);
 *  - the floor: the same cameras over the same city without its lamps and
 *    with no indirect light, a new engine from the GeoJSON, on 1 and 2
 *    threads: what a frame costs with no light to compute (culling,
 *    rasterising, hit points, exposure, tone mapping). PLX_BENCH_FLOOR_ONLY
 *    set: that alone.
 * Wall-clock and CPU times (the baseline's of its thread, the bakes' and
 * the walks' of the process, every thread): the build machine is shared,
 * CPU time is the steadier figure. PLX_BENCH_FRAMES photon frames (default
 * 64; bake's default is 16) of 65,536 for the baseline (render's per frame)
 * and of 16 a lamp for the bakes (bake's default, 295,680 here).
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "port.h"
#include "gen_text.h"

#define MEM ((size_t)1536 << 20)

static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

/* all threads of the process (the walks with 2 threads) */
static double proc_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static double wall_ms(void)
{
    return port_now_ns() / 1e6;
}

/* Whether line p (n bytes) holds the string k. */
static int line_has(const char *p, size_t n, const char *k)
{
    size_t i, m = strlen(k);
    for (i = 0; i + m <= n; i++)
        if (memcmp(p + i, k, m) == 0)
            return 1;
    return 0;
}

/* The generated city without its lamps: plx_gen_city writes the header, a
 * feature a line (a lamp's holds "lamp":true) and the closing line. */
static int without_lamps(const text *in, text *out)
{
    const char *p = in->buf, *end = in->buf + in->len;
    size_t kept = 0;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        size_t n = nl ? (size_t)(nl - p) : (size_t)(end - p);
        if (n >= 17 && strncmp(p, "{\"type\":\"Feature\"", 17) == 0) {
            if (!line_has(p, n, "\"lamp\":true")) {
                if ((kept++ > 0 && append(out, ",\n", 2) != 0) || append(out, p, p[n - 1] == ',' ? n - 1 : n) != 0)
                    return -1;
            }
        } else if ((kept > 0 && append(out, "\n", 1) != 0) || append(out, p, n) != 0 || append(out, "\n", 1) != 0) {
            return -1;
        }
        p += n + (nl ? 1 : 0);
    }
    return 0;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

static plx_engine *engine(void **mem, int max_w, int max_h, int quiet, int threads)
{
    plx_config cfg;
    static plx_port silent;
    plx_engine *e = NULL;
    if (!(*mem = calloc(1, MEM)))
        return NULL;
    plx_config_default(&cfg);
    silent = *plx_port_posix();
    if (quiet)
        silent.log = NULL;
    cfg.port = &silent;
    cfg.render_max_width = max_w;
    cfg.render_max_height = max_h;
    cfg.threads = threads; /* the baseline and the first bake on one thread (thread CPU times) */
    if (plx_engine_create(*mem, MEM, &cfg, &e) != PLX_OK)
        return NULL;
    return e;
}

/* frames photon frames of n photons */
static int trace(plx_engine *e, int frames, uint32_t n)
{
    int k;
    for (k = 0; k < frames; k++)
        if (plx_indirect_step(e, n, (uint64_t)k + 1) != PLX_OK)
            return -1;
    return 0;
}

/* The bake command's photons per frame (src/cli/common.c's cli_photons): 16 a
 * lamp, from 65,536 to 1,048,576; 295,680 on this city. */
static uint32_t bake_photons(plx_engine *e)
{
    plx_scene_info si;
    uint32_t n;
    if (plx_scene_info_get(e, &si) != PLX_OK)
        return 65536;
    n = si.lamps * 16u;
    return n < 65536u ? 65536u : n > 1048576u ? 1048576u : n;
}

static void street_cam(plx_camera *c, double s)
{
    memset(c, 0, sizeof *c);
    c->eye[0] = 133.0;
    c->eye[1] = 1000.0 + s;
    c->eye[2] = 1.7;
    c->target[0] = 133.0;
    c->target[1] = 1400.0 + s;
    c->target[2] = 6.0;
    c->fov_deg = 60;
    c->width = 640;
    c->height = 480;
}

static int aerial_w = 1024, aerial_h = 768; /* the aerial frames' size (the fixed-cost walk: 256x192) */

static void aerial_cam(plx_camera *c, double s)
{
    memset(c, 0, sizeof *c);
    c->eye[0] = 1900.0 + s;
    c->eye[1] = 1100.0;
    c->eye[2] = 700.0;
    c->target[0] = 1950.0 + s;
    c->target[1] = 1900.0;
    c->fov_deg = 50;
    c->width = aerial_w;
    c->height = aerial_h;
}

/* n frames along a path: median and p95 wall ms, mean CPU ms of the
 * process (every thread). A first frame before them (the aerial one
 * builds the indirect map) is timed alone into *first (wall ms). */
/* n frames along the street or aerial path: wall-clock median and p95,
 * process CPU per frame, and the first frame's wall-clock time before
 * them; aa x aa samples (full: every pixel all of them). */
static int per_pixel_walks; /* walk(): every pixel shaded, not read from the atlas */
static double atlas_mb;     /* the last bake's radiance atlas */

static void walk(plx_engine *e, int aerial, int aa, int full, int n, uint8_t *rgb8, double *med, double *p95,
                 double *cpu, double *first, int indirect)
{
    double *t = malloc(sizeof *t * (size_t)n), c0, f0 = wall_ms();
    plx_render_opts o;
    plx_camera cam0;
    int k;
    plx_render_opts_default(&o);
    o.aerial = aerial;
    o.auto_exposure = 1;
    o.aa = aa;
    o.aa_full = full;
    o.no_indirect = !indirect;
    o.per_pixel = per_pixel_walks;
    if (aerial)
        aerial_cam(&cam0, -4.0);
    else
        street_cam(&cam0, -1.4);
    if (plx_render(e, &cam0, &o, rgb8, NULL, NULL) != PLX_OK)
        printf("  render failed: %s\n", plx_last_error(e));
    *first = wall_ms() - f0;
    c0 = proc_ms();
    for (k = 0; k < n; k++) {
        plx_camera cam;
        double w0 = wall_ms();
        if (aerial)
            aerial_cam(&cam, 4.0 * k);
        else
            street_cam(&cam, 1.4 * k);
        if (plx_render(e, &cam, &o, rgb8, NULL, NULL) != PLX_OK)
            printf("  render failed: %s\n", plx_last_error(e));
        t[k] = wall_ms() - w0;
    }
    *cpu = (proc_ms() - c0) / n;
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    *med = t[n / 2];
    *p95 = t[(int)ceil(0.95 * n) - 1];
    free(t);
}

/* The twin: loaded and prepared (on a thread of its own when the bake
 * has more than one, as `polarlux bake` does). */
typedef struct twin_job {
    text city;
    plx_engine *b;
    int rc;
} twin_job;

static void *twin_prepare(void *p)
{
    twin_job *j = p;
    plx_bake_opts bo;
    memset(&bo, 0, sizeof bo);
    bo.aerial = 1;
    bo.twin = 1;
    j->rc = j->b && plx_load_geojson(j->b, j->city.buf, j->city.len, "eixample") == PLX_OK &&
                    plx_bake_prepare(j->b, &bo) == PLX_OK ? 0 : -1;
    return NULL;
}

/* Bakes the city on `threads` workers: load, plx_bake_prepare (polar,
 * light, photons, renderer, light map), the photon frames, the twin
 * (alongside with 2 threads), plx_bake_save (which gathers the aerial
 * layer). Wall ms, CPU ms of the process (every thread), the engine's
 * memory. */
static int bake(text city, int frames, int threads, unsigned char **file, size_t *len, double *wall, double *cpu,
                plx_memory_report *m)
{
    void *ma, *mb;
    plx_engine *a;
    plx_bake_opts bo;
    twin_job tj;
    pthread_t th;
    int alongside, ok;
    size_t need = 0;
    double w0 = wall_ms(), c0 = proc_ms();
    memset(&bo, 0, sizeof bo);
    bo.aerial = 1;
    a = engine(&ma, 1024, 768, 1, threads);
    tj.city = city;
    tj.b = engine(&mb, 1024, 768, 1, threads);
    alongside = threads > 1 && pthread_create(&th, NULL, twin_prepare, &tj) == 0;
    ok = a && plx_load_geojson(a, city.buf, city.len, "eixample") == PLX_OK && plx_bake_prepare(a, &bo) == PLX_OK &&
         trace(a, frames, bake_photons(a)) == 0;
    if (alongside)
        pthread_join(th, NULL);
    else
        twin_prepare(&tj);
    if (!ok || tj.rc != 0 || plx_bake_size(a, tj.b, &need) != PLX_OK)
        return -1;
    *file = malloc(need);
    if (!*file || plx_bake_save(a, tj.b, *file, need, len) != PLX_OK)
        return -1;
    *wall = wall_ms() - w0;
    *cpu = proc_ms() - c0;
    plx_memory_get(a, m);
    {
        plx_atlas_info ai;
        if (plx_atlas_info_get(a, &ai) == PLX_OK)
            atlas_mb = ai.bytes / 1048576.0;
    }
    plx_engine_destroy(a);
    plx_engine_destroy(tj.b);
    free(ma);
    free(mb);
    return 0;
}

/* Whether two bake files are the same bytes, the header included. */
static int same_bake(const unsigned char *f, size_t n, const unsigned char *g, size_t m)
{
    return n == m && n > 128 && memcmp(f, g, n) == 0;
}

/* The floor: the same cameras over the same city without its lamps, no
 * indirect light: what a frame costs with no light to compute (culling,
 * rasterising, hit points, exposure, tone mapping), on 1 and 2 threads. */
static int floor_walks(const text *city, uint8_t *rgb8)
{
    text dark = { NULL, 0, 0 };
    plx_scene_info si;
    plx_engine *d;
    void *md;
    double sm, sp, sc, sf, am, ap, ac, af;
    int k;
    if (without_lamps(city, &dark) != 0)
        return -1;
    for (k = 1; k <= 2; k++) {
        if (!(d = engine(&md, 1024, 768, 1, k)) || plx_load_geojson(d, dark.buf, dark.len, "dark") != PLX_OK)
            return -1;
        plx_scene_info_get(d, &si);
        if (si.lamps != 0) {
            printf("floor: the city still has %u lamps\n", si.lamps);
            return -1;
        }
        walk(d, 0, 1, 0, 20, rgb8, &sm, &sp, &sc, &sf, 0);
        walk(d, 1, 1, 0, 10, rgb8, &am, &ap, &ac, &af, 0);
        printf("floor, %d thread%s (the city's %u buildings, no lamps, no indirect light): street 640x480 "
               "median %.1f ms, CPU %.1f ms/frame; aerial 1024x768 median %.1f ms, CPU %.1f ms/frame\n",
               k, k > 1 ? "s" : "", si.buildings, sm, sc, am, ac);
        plx_engine_destroy(d);
        free(md);
    }
    free(dark.buf);
    return 0;
}

int main(void)
{
    text city = { NULL, 0, 0 };
    void *mc, *md;
    plx_engine *c, *d;
    plx_render_opts o;
    plx_camera cam;
    plx_memory_report m;
    uint8_t *rgb8 = malloc(1024 * 768 * 3);
    const char *env = getenv("PLX_BENCH_FRAMES");
    int frames = env ? atoi(env) : 64, k;
    double w0, cb, cl = 0, base_load, base_ph, base_street, base_aerial, bake_w, bake_c, bake2_w, bake2_c, loads[5];
    double sm, sp, sc, am, ap, ac, dm = 0, dp, dc = 0, df;
    size_t len = 0, len2 = 0, need = 0;
    unsigned char *file, *file2;
    char err[256];
    if (plx_gen_city("eixample", 30, 30, 1, append, &city) != PLX_OK || !rgb8)
        return 1;
    printf("city: gen eixample 30 30 (%.1f MB of GeoJSON); photons: %d frames of 65,536 for the baseline (render's "
           "default), of 16 a lamp for the bakes (bake's)\n", city.len / 1e6, frames);
    if (getenv("PLX_BENCH_FLOOR_ONLY")) /* the floor alone (a minute, not several) */
        return floor_walks(&city, rgb8) != 0;

    /* baseline: today's render path from the GeoJSON */
    d = engine(&md, 1024, 768, 1, 1);
    cb = cpu_ms();
    w0 = wall_ms();
    if (!d || plx_load_geojson(d, city.buf, city.len, "eixample") != PLX_OK)
        return 1;
    base_load = wall_ms() - w0;
    w0 = wall_ms();
    trace(d, frames, 65536); /* render's photons per frame when the issue was filed (since 2026-11-30
                                  render traces 16 a lamp from a scene, 295,680 a frame here) */
    base_ph = wall_ms() - w0;
    plx_render_opts_default(&o);
    o.per_pixel = 1; /* the render path of before the radiance atlas */
    street_cam(&cam, 0);
    w0 = wall_ms();
    plx_render(d, &cam, &o, rgb8, NULL, NULL);
    base_street = wall_ms() - w0;
    o.aerial = 1;
    aerial_cam(&cam, 0);
    w0 = wall_ms();
    plx_render(d, &cam, &o, rgb8, NULL, NULL);
    base_aerial = wall_ms() - w0;
    cb = cpu_ms() - cb;
    plx_memory_get(d, &m);
    printf("baseline (render from the GeoJSON, every pixel shaded): load %.0f ms, photons %.0f ms, first street "
           "frame %.0f ms, first aerial frame %.0f ms (light map and its layer included), wall; %.2f s CPU in all; "
           "engine memory %.1f MiB\n",
           base_load, base_ph, base_street, base_aerial, cb / 1e3, m.used_total / 1048576.0);
    plx_engine_destroy(d);
    free(md);

    /* the bake, on one thread, then on two (the POSIX port's parallel-for) */
    if (bake(city, frames, 1, &file, &len, &bake_w, &bake_c, &m) != 0)
        return 1;
    printf("bake, 1 thread: %.2f s wall, %.2f s CPU (target 10 s); file %.1f MiB; engine memory %.1f MiB, of it "
           "the radiance atlas %.1f MiB\n",
           bake_w / 1e3, bake_c / 1e3, len / 1048576.0, m.used_total / 1048576.0, atlas_mb);
    if (bake(city, frames, 2, &file2, &len2, &bake2_w, &bake2_c, &m) != 0)
        return 1;
    printf("bake, 2 threads: %.2f s wall, %.2f s CPU of the process; %.2fx the 1-thread wall time; "
           "the file %s\n",
           bake2_w / 1e3, bake2_c / 1e3, bake_w / bake2_w,
           same_bake(file, len, file2, len2) ? "the same bytes as with 1 thread" : "DIFFERS from the 1-thread file");
    free(file2);

    /* loading, into a block touched beforehand */
    if (plx_bake_block_size(file, len, &need, err, sizeof err) != PLX_OK || posix_memalign(&mc, 1 << 21, need) != 0)
        return 1;
    memset(mc, 0, need);
    for (k = 0; k < 5; k++) {
        double c1 = cpu_ms();
        w0 = wall_ms();
        if (plx_bake_load(mc, need, NULL, file, len, &c, err, sizeof err) != PLX_OK) {
            printf("load failed: %s\n", err);
            return 1;
        }
        loads[k] = wall_ms() - w0;
        cl += cpu_ms() - c1;
        if (k < 4)
            plx_engine_destroy(c);
    }
    qsort(loads, 5, sizeof *loads, cmp_double);
    printf("load: median %.1f ms of 5 wall, %.1f ms CPU mean (target 50 ms), a %zu-byte block touched beforehand\n",
           loads[2], cl / 5, need);

    /* walks from the loaded engine: one thread (no port: no parallel-for),
     * then the same bake loaded again with the POSIX port and 2 threads */
    for (k = 0; k < 2; k++) {
        double sf, af;
        if (k == 1) {
            plx_config cfg;
            plx_engine_destroy(c);
            plx_config_default(&cfg);
            cfg.port = plx_port_posix();
            cfg.threads = 2;
            memset(mc, 0, need);
            if (plx_bake_load(mc, need, &cfg, file, len, &c, err, sizeof err) != PLX_OK) {
                printf("load failed: %s\n", err);
                return 1;
            }
        }
        double pm, pp, pc, pf, qm, qp, qc, qf, xm, xp, xc, xf;
        walk(c, 0, 1, 0, 20, rgb8, &sm, &sp, &sc, &sf, 1);
        walk(c, 1, 1, 0, 10, rgb8, &am, &ap, &ac, &af, 1);
        aerial_w = 256; /* the same cameras with a sixteenth of the pixels: what a frame costs before them */
        aerial_h = 192;
        walk(c, 1, 1, 0, 30, rgb8, &xm, &xp, &xc, &xf, 1);
        aerial_w = 1024;
        aerial_h = 768;
        per_pixel_walks = 1;
        walk(c, 0, 1, 0, 20, rgb8, &pm, &pp, &pc, &pf, 1);
        walk(c, 1, 1, 0, 10, rgb8, &qm, &qp, &qc, &qf, 1);
        per_pixel_walks = 0;
        printf("%d thread%s:\n", k + 1, k ? "s" : "");
        printf("  every pixel shaded (per_pixel, the frames of before the atlas): street median %.1f ms, aerial "
               "median %.1f ms; the atlas's frames %.1fx and %.1fx faster\n",
               pm, qm, pm / sm, qm / am);
        printf("  street walk 640x480 with indirect, 20 frames: median %.1f ms, p95 %.1f ms, CPU %.1f ms/frame "
               "(target 10 ms); %.1fx the baseline's first frame (%.0f ms), %.0fx its load + photons + frame; "
               "first frame %.0f ms\n",
               sm, sp, sc, base_street / sm, base_street, (base_load + base_ph + base_street) / sm, sf);
        printf("  aerial walk 1024x768 with indirect, 10 frames: median %.1f ms, p95 %.1f ms, CPU %.1f ms/frame "
               "(target 5 ms); %.1fx the baseline's first aerial frame (%.0f ms); first frame (builds the "
               "indirect map) %.0f ms\n",
               am, ap, ac, base_aerial / am, base_aerial, af);
        printf("  the same aerial cameras at 256x192 (a sixteenth of the pixels: the frame's fixed cost), 30 "
               "frames: median %.1f ms, CPU %.1f ms/frame; %.0f%% of the 1024x768 frame's median\n",
               xm, xc, 100.0 * xm / am);
        /* walk's default: 2 x 2 samples, adaptive */
        walk(c, 0, 2, 0, 20, rgb8, &dm, &dp, &dc, &df, 1);
        printf("  street walk 640x480 with --aa 2 (walk's default: 2 x 2 samples, adaptive), 20 frames: median "
               "%.1f ms, p95 %.1f ms, CPU %.1f ms/frame (target 10 ms); %.1fx the one-sample frame\n",
               dm, dp, dc, dm / sm);
        {
            /* the aerial walk as `walk --view aerial` makes it by default:
             * the mask marks over half the pixels, so every sample */
            double gm, gp, gc, gf;
            walk(c, 1, 2, 0, 6, rgb8, &gm, &gp, &gc, &gf, 1);
            printf("  aerial walk 1024x768 with --aa 2 (walk's default; every sample: edges at over half the "
                   "pixels), 6 frames: median %.1f ms, p95 %.1f ms, CPU %.1f ms/frame; %.1fx the one-sample "
                   "frame\n",
                   gm, gp, gc, gm / am);
        }
    }
    {
        /* walk's default against every sample (2 threads, the last of the loop's) */
        double fm, fp, fc, ff;
        walk(c, 0, 2, 1, 20, rgb8, &fm, &fp, &fc, &ff, 1);
        printf("2 threads, street walk 640x480 with --aa 2: adaptive median %.1f ms, CPU %.1f ms/frame; every "
               "sample (--aa-full) median %.1f ms, CPU %.1f ms/frame; %.2fx\n",
               dm, dc, fm, fc, fc / dc);
    }
    plx_engine_destroy(c);
    free(mc);
    free(file);

    if (floor_walks(&city, rgb8) != 0)
        return 1;
    free(rgb8);
    free(city.buf);
    return 0;
}
