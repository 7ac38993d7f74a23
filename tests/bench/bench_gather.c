/* Final gathering against the photon buffers alone (src/photon/final_gather.h),
 * single thread: mean relative error of E_indirect against the path tracer
 * (tests/ref/ref_indirect.c) and time, side by side, on the same points of
 * fixtures/eixample-4x4.geojson and of `gen oldtown 40 40` (generated in
 * memory), over six seeds.
 *
 * Usage: bench_gather [PATHS [NPTS]]  (reference paths per point, default
 * 20000; points per scene, half ground and half facade, default 16)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "base/engine.h"
#include "photon/trace.h"
#include "photon/photon.h"
#include "photon/final_gather.h"
#include "ref_indirect.h"

#define BUDGET ((size_t)2 << 30)
#define NSEEDS 6

#include "gen_text.h"

static uint64_t now_ns(void)
{
    return plx_port_posix()->clock_ns(NULL);
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
    uint32_t frames, photons, side; /* side 0: photon buffers alone */
} method;

/* Mean relative error over the points and the seeds, and seconds per run
 * (photon pass + the points). */
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
            photon_step(e->ph, m->photons, 1000u * (uint64_t)sd + k + 1);
        for (i = 0; i < np; i++) {
            double est = m->side ? final_gather_rgb(e->ph, e->ph->T, e->lt, P + 3 * i,
                                                    N + 3 * i, m->side, (uint64_t)sd + 1, NULL)
                                 : photon_indirect(e->ph, P + 3 * i, N + 3 * i);
            esum += fabs(est - ref[i]) / ref[i];
            if (getenv("SHOW") && sd == 0)
                printf("    %d %s %.3f %.3f\n", i, N[3 * i + 2] > 0.5 ? "g" : "f", est, ref[i]);
        }
        t += now_ns() - t0;
    }
    *err = esum / (np * NSEEDS);
    *sec = t / 1e9 / NSEEDS;
}

static void bench_scene(const char *name, plx_engine *e, int paths, int npts)
{
    static const method ms[] = {
        {"gather 32x32 + 256K photons", 4, 65536, 32},
        {"gather 32x32 + 512K photons", 8, 65536, 32},
    };
    const scene *s = e->sc;
    double *P = malloc(sizeof *P * 3 * npts), *N = malloc(sizeof *N * 3 * npts);
    double *ref = malloc(sizeof *ref * npts), noise = 0.0, eye[3];
    int np, i;
    size_t j;
    uint64_t t0;
    if (!P || !N || !ref || plx_indirect_step(e, 1, 1) != PLX_OK ||
        eng_need_light(e, "bench_gather") != PLX_OK) {
        fprintf(stderr, "bench_gather: setup failed\n");
        exit(1);
    }
    eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
    eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
    eye[2] = 1.7;
    photon_set_viewer(e->ph, eye, NULL, 360.0);
    np = ref_indirect_points(e->ph->T, s, npts / 2, npts - npts / 2, 4242, P, N);
    t0 = now_ns();
    for (i = 0; i < np; i++) {
        double se;
        ref[i] = ref_indirect_paths(e->ph->T, s, P + 3 * i, N + 3 * i, paths, 9000 + i, &se);
        noise += se / ref[i];
    }
    printf("%s: %u buildings, %u lamps; %d points (half ground, half facade), reference %d paths "
           "each (its own noise: mean relative standard error %.4f; %.1f s)\n",
           name, s->nbld, s->nlamps, np, paths, noise / np, (now_ns() - t0) / 1e9);
    printf("  %-30s %10s %12s\n", "method", "mean err", "s per run");
    for (j = 0; j < sizeof ms / sizeof ms[0]; j++) {
        double err, sec;
        run(e, &ms[j], np, P, N, ref, &err, &sec);
        printf("  %-30s %10.4f %12.3f\n", ms[j].name, err, sec);
        fflush(stdout);
    }
    free(P);
    free(N);
    free(ref);
}

int main(int argc, char **argv)
{
    int paths = argc > 1 ? atoi(argv[1]) : 20000, npts = argc > 2 ? atoi(argv[2]) : 16;
    text t = {NULL, 0, 0};
    plx_engine *e;
    if (!getenv("SKIPEIX")) {
    e = engine_with("fixtures/eixample-4x4.geojson", 0, 1);
    bench_scene("eixample-4x4", e, paths, npts);
    plx_engine_free(e);
    }
    if (plx_gen_city("oldtown", 40, 40, 1, append, &t) != PLX_OK) {
        fprintf(stderr, "bench_gather: gen failed\n");
        return 1;
    }
    e = engine_with(t.buf, t.len, 0);
    bench_scene("gen oldtown 40 40", e, paths, npts);
    plx_engine_free(e);
    free(t.buf);
    return 0;
}
