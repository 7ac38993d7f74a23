/* Final gathering against the photon buffers alone (src/photon/final_gather.h),
 * single thread: mean relative error of E_indirect against the path tracer
 * (tests/ref/ref_indirect.c) and time, side by side, on the same points of
 * fixtures/eixample-4x4.geojson and of `gen oldtown 40 40` (generated in
 * memory), over six seeds.
 *
 * Methods: the photon buffers alone with the old configuration (levels
 * around a viewer, 2 x 2 lookup) at the old default of 256 x 65,536
 * photons and at 16 x 65,536; the new configuration (every block charted,
 * wide lookup: what images read) at 16 x 65,536; final gathering at
 * 16 x 16 and 32 x 32 directions; what images show at the points now:
 * the irradiance cache over 4 frames (irradiance_cache.h; before, they
 * read the wide lookup at 16 frames, the third line). Each line: the mean relative error over
 * the points and six seeds, CPU seconds per run (photon pass + lookups or
 * gathers at the points; loading not counted), and both as a ratio to the
 * first line, measured in the same process.
 *
 * Usage: bench_gather [PATHS [NPTS]]  (reference paths per point, default
 * 60000; points per scene, half ground and half facade, default 32)
 *        bench_gather points N      (N points of `gen oldtown 40 40` for
 *                                    timing `polarlux illum`; README)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "base/engine.h"
#include "photon/trace.h"
#include "photon/indirect.h"
#include "photon/final_gather.h"
#include "photon/irradiance_cache.h"
#include "ref_indirect.h"

#define BUDGET ((size_t)2 << 30)
#define NSEEDS 6

#include "gen_text.h"

/* Thread CPU time (the machine is shared: wall time is noisy). */
static uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static plx_engine *engine_with(const char *text_or_path, size_t len, int is_file)
{
    plx_engine *e;
    plx_config cfg;
    static plx_port keep;
    keep = *plx_port_posix();
    keep.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &keep;
    if (plx_engine_new(BUDGET, &cfg, &e) != PLX_OK) {
        fprintf(stderr, "bench_gather: no memory for the engine\n");
        exit(1);
    }
    if ((is_file ? plx_load_file(e, text_or_path)
                 : plx_load_geojson(e, text_or_path, len, "oldtown")) != PLX_OK) {
        fprintf(stderr, "bench_gather: load failed: %s\n", plx_last_error(e));
        exit(1);
    }
    return e;
}

typedef struct method {
    const char *name;
    uint32_t frames, side; /* side 0: photon buffers alone */
    int old;               /* the old configuration (plx_indirect_set_gather 0) */
    int cache;             /* images' irradiance cache (red channel: the lamps' default
                              colour has red 1), the eye 20 m in front of the point */
} method;

/* What an image shows at P: the irradiance cache seen from 20 m along n
 * (records 3 m apart there; each point gathers its own 4-8 records, as
 * the first pixel of a surface does). */
static double cached(plx_engine *e, const double *P, const double *N)
{
    double eye[3], rgb[3];
    int k;
    for (k = 0; k < 3; k++)
        eye[k] = P[k] + 20.0 * N[k];
    icache_set_view(e->ic, eye);
    icache_lookup(e->ic, e->ph, e->lt, P, N, rgb);
    return rgb[0];
}

/* Mean relative error over the points and the seeds, and CPU seconds per
 * run (photon pass + the points). */
static void run(plx_engine *e, const method *m, int np, const double *P, const double *N,
                const double *ref, double *err, double *sec)
{
    int sd, i;
    uint32_t k;
    double esum = 0.0;
    uint64_t t = 0;
    for (sd = 0; sd < NSEEDS; sd++) {
        uint64_t t0 = now_ns();
        plx_indirect_reset(e);
        for (k = 0; k < m->frames; k++)
            photon_step(e->ph, 65536, 1000u * (uint64_t)sd + k + 1);
        for (i = 0; i < np; i++) {
            double est = m->cache  ? cached(e, P + 3 * i, N + 3 * i)
                         : m->side ? final_gather_rgb(e->ph, e->ph->T, e->lt, P + 3 * i,
                                                      N + 3 * i, m->side, (uint64_t)sd + 1, NULL)
                                   : photon_indirect(e->ph, P + 3 * i, N + 3 * i);
            esum += fabs(est - ref[i]) / ref[i];
        }
        t += now_ns() - t0;
    }
    *err = esum / (np * NSEEDS);
    *sec = t / 1e9 / NSEEDS;
}

/* An engine on the scene with its photon system, old or new configuration. */
static plx_engine *prepared(const char *text_or_path, size_t len, int is_file, int old)
{
    plx_engine *e = engine_with(text_or_path, len, is_file);
    const scene *s = e->sc;
    double eye[3];
    if ((old && plx_indirect_set_gather(e, 0) != PLX_OK) || plx_indirect_step(e, 1, 1) != PLX_OK ||
        eng_need(e, ENG_LIGHT, "bench_gather") != PLX_OK) {
        fprintf(stderr, "bench_gather: setup failed\n");
        exit(1);
    }
    eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
    eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
    eye[2] = 1.7;
    photon_set_viewer(e->ph, eye, NULL, 360.0);
    return e;
}

static void bench_scene(const char *name, const char *text_or_path, size_t len, int is_file,
                        int paths, int npts)
{
    static const method ms[] = {
        {"photons alone, old default (256 frames, 2x2 lookup)", 256, 0, 1, 0},
        {"photons alone, old configuration, 16 frames", 16, 0, 1, 0},
        {"photons alone, new configuration (images before), 16 frames", 16, 0, 0, 0},
        {"final gathering 16x16, 16 frames", 16, 16, 0, 0},
        {"final gathering 32x32, 8 frames", 8, 32, 0, 0},
        {"final gathering 32x32, 16 frames (new default)", 16, 32, 0, 0},
        {"images now: irradiance cache 16x16, 4 frames", 4, 0, 0, 1},
    };
    plx_engine *eo = prepared(text_or_path, len, is_file, 1);
    plx_engine *en = prepared(text_or_path, len, is_file, 0);
    const scene *s = eo->sc;
    double *P = malloc(sizeof *P * 3 * npts), *N = malloc(sizeof *N * 3 * npts);
    double *ref = malloc(sizeof *ref * npts), noise = 0.0, base_err = 0.0, base_sec = 0.0;
    int np, i;
    size_t j;
    uint64_t t0;
    if (!P || !N || !ref) {
        fprintf(stderr, "bench_gather: out of memory\n");
        exit(1);
    }
    np = ref_indirect_points(eo->ph->T, s, npts / 2, npts - npts / 2, 4242, P, N);
    t0 = now_ns();
    for (i = 0; i < np; i++) {
        double se;
        ref[i] = ref_indirect_paths(eo->ph->T, s, P + 3 * i, N + 3 * i, paths, 9000 + i, &se);
        noise += se / ref[i];
    }
    printf("%s: %u buildings, %u lamps; %d points (half ground, half facade); reference %d "
           "paths each (its own noise: mean relative standard error %.4f; %.1f s)\n",
           name, s->nbld, s->nlamps, np, paths, noise / np, (now_ns() - t0) / 1e9);
    printf("  %-62s %9s %9s %9s %9s\n", "method (x 65,536 photons)", "mean err", "s/run",
           "err/old", "time/old");
    for (j = 0; j < sizeof ms / sizeof ms[0]; j++) {
        double err, sec;
        run(ms[j].old ? eo : en, &ms[j], np, P, N, ref, &err, &sec);
        if (j == 0) {
            base_err = err;
            base_sec = sec;
        }
        printf("  %-62s %9.4f %9.3f %9.3f %9.3f\n", ms[j].name, err, sec, err / base_err,
               sec / base_sec);
        fflush(stdout);
    }
    free(P);
    free(N);
    free(ref);
    plx_engine_free(eo);
    plx_engine_free(en);
}

/* "bench_gather points N": N points (half ground, half facade) of `gen
 * oldtown 40 40` as lines 'x y z nx ny nz', for timing `polarlux illum`. */
static int write_points(int n)
{
    text t = {NULL, 0, 0};
    plx_engine *e;
    double *P = malloc(sizeof *P * 3 * (size_t)n), *N = malloc(sizeof *N * 3 * (size_t)n);
    int np, i;
    if (!P || !N || plx_gen_city("oldtown", 40, 40, 1, append, &t) != PLX_OK)
        return 1;
    e = prepared(t.buf, t.len, 0, 0);
    np = ref_indirect_points(e->ph->T, e->sc, n / 2, n - n / 2, 77, P, N);
    for (i = 0; i < np; i++)
        printf("%.17g %.17g %.17g %.17g %.17g %.17g\n", P[3 * i], P[3 * i + 1], P[3 * i + 2],
               N[3 * i], N[3 * i + 1], N[3 * i + 2]);
    plx_engine_free(e);
    free(t.buf);
    free(P);
    free(N);
    return np == n ? 0 : 1;
}

int main(int argc, char **argv)
{
    int paths = argc > 1 ? atoi(argv[1]) : 60000, npts = argc > 2 ? atoi(argv[2]) : 32;
    text t = {NULL, 0, 0};
    if (argc > 2 && strcmp(argv[1], "points") == 0)
        return write_points(atoi(argv[2]));
    bench_scene("eixample-4x4", "fixtures/eixample-4x4.geojson", 0, 1, paths, npts);
    if (plx_gen_city("oldtown", 40, 40, 1, append, &t) != PLX_OK) {
        fprintf(stderr, "bench_gather: gen failed\n");
        return 1;
    }
    bench_scene("gen oldtown 40 40", t.buf, t.len, 0, paths, npts);
    free(t.buf);
    return 0;
}
