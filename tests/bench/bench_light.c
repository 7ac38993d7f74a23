/* bench_light: lit regions per lamp and illuminance throughput (src/light/light.h),
 * side by side with the brute-force reference run in the same process.
 *
 * Scenes: `polarlux gen eixample 30 30` (generated here by plx_gen_city) and
 * the real district fixtures/helsinki-centre.geojson. Single thread.
 *   regions: microseconds per lamp (median, p95), sector index only (what the
 *            queries need) and full (with the lit ground and facade polygons),
 *            the latter twice: first into a fresh cache pool (page faults
 *            included), then again once its pages are mapped;
 *            baseline: the reference's segment test on a polar grid of the
 *            reach disk (1 degree x 1 m), the brute-force way to map a lit area.
 *   illuminance: a million ground points (1000 x 1000 raster, row order) by
 *            the region path (cold: regions computed on the way; warm: again)
 *            and by the segment path; baseline: ref_illuminance on a sample.
 * PLX_BENCH_LAMPS=N limits the lamps timed per scene (default 4000).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "base/engine.h"
#include "light/light.h"
#include "ref_light.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct textbuf { char *p; size_t n, cap; } textbuf;

static int append(void *ctx, const char *data, size_t len)
{
    textbuf *b = ctx;
    if (b->n + len > b->cap) {
        size_t cap = (b->cap + len) * 2;
        char *p = realloc(b->p, cap);
        if (!p)
            return 1;
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->n, data, len);
    b->n += len;
    return 0;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double quantile(double *v, size_t n, double q)
{
    size_t k = (size_t)(q * (double)(n - 1) + 0.5);
    return n ? v[k] : 0.0;
}

/* Times region computation for 'n' lamps spread over the scene. */
static double time_regions(light *L, uint32_t n, uint32_t stride, int polygons, double *t,
                           size_t *bytes, uint64_t *rings)
{
    uint32_t k;
    double mean = 0.0;
    *bytes = 0;
    *rings = 0;
    light_cache_clear(L);
    for (k = 0; k < n; k++) {
        const lit_region *r;
        uint32_t lamp = k * stride;
        double t0 = now_s();
        plx_status st = polygons ? light_region(L, lamp, &r) : light_region_index(L, lamp, &r);
        t[k] = (now_s() - t0) * 1e6;
        if (st != PLX_OK) {
            printf("  region of lamp %u failed: %s\n", lamp, plx_strerror(st));
            exit(1);
        }
        mean += t[k];
        *bytes += r->bytes;
        *rings += r->nground + r->nfacade;
    }
    qsort(t, n, sizeof *t, cmp_d);
    return mean / n;
}

static void bench_regions(light *L, const scene *s)
{
    uint32_t n = s->nlamps, stride = 1, k, nb;
    long limit = getenv("PLX_BENCH_LAMPS") ? atol(getenv("PLX_BENCH_LAMPS")) : 4000;
    double *t, mean, t0, brute = 0.0, full_med;
    size_t bytes;
    uint64_t rings, tests = 0, samples = 0;
    if (n > (uint32_t)limit) {
        stride = n / (uint32_t)limit;
        n = (uint32_t)limit;
    }
    t = malloc(n * sizeof *t);
    mean = time_regions(L, n, stride, 0, t, &bytes, &rings);
    printf("  region index  (%u lamps): median %.1f us, p95 %.1f us, mean %.1f us, %.1f KiB each\n",
           n, quantile(t, n, 0.5), quantile(t, n, 0.95), mean, bytes / 1024.0 / n);
    mean = time_regions(L, n, stride, 1, t, &bytes, &rings);
    full_med = quantile(t, n, 0.5);
    printf("  region full   (%u lamps): median %.1f us, p95 %.1f us, mean %.1f us, %.1f KiB, "
           "%.0f lit polygons each\n", n, full_med, quantile(t, n, 0.95), mean,
           bytes / 1024.0 / n, (double)rings / n);
    /* the same again: the cache pool's pages are now mapped (the first pass
     * pays the page faults of the pool it fills) */
    mean = time_regions(L, n, stride, 1, t, &bytes, &rings);
    printf("  region full, pool pages mapped: median %.1f us, p95 %.1f us, mean %.1f us\n",
           quantile(t, n, 0.5), quantile(t, n, 0.95), mean);
    /* brute force: the reference's segment test on a polar grid of the disk
     * (1 degree x 1 m); on a big scene each test costs milliseconds, so a
     * sample of the grid's tests is timed and scaled to the whole grid. */
    nb = n < 10 ? n : 10;
    for (k = 0; k < nb; k++) {
        const scene_lamp *lp = &s->lamps[k * stride];
        double Lp[3] = { lp->x, lp->y, lp->z };
        double Rg = lp->radius > lp->z ? sqrt(lp->radius * lp->radius - lp->z * lp->z) : 0.0;
        int a, d, grid = 0, done = 0;
        for (d = 1; d < Rg; d++)
            grid += 360;
        t0 = now_s();
        for (a = 0; a < 360; a += 7)
            for (d = 1; d < Rg; d += 3) {
                double P[3] = { lp->x + d * cos(a * 0.017453292519943295),
                                lp->y + d * sin(a * 0.017453292519943295), 0.0 };
                (void)ref_segment_blocked(s, Lp, P);
                done++;
            }
        if (done)
            brute += (now_s() - t0) * 1e6 / done * grid;
        tests += (uint64_t)grid;
        samples += (uint64_t)done;
    }
    brute /= nb;
    printf("  brute force   (%u lamps): %.0f us per lamp (%.0f reference segment tests each, "
           "%llu timed, scaled); ratio brute / full region (median) = %.0f\n", nb, brute,
           (double)tests / nb, (unsigned long long)samples, brute / full_med);
    free(t);
}

/* A million ground points in row order over the lamps' area. */
static void raster_point(const scene *s, int i, int j, int n, double P[3])
{
    double x0 = s->bounds[0] + 50.0, y0 = s->bounds[1] + 50.0;
    double x1 = s->bounds[2] - 50.0, y1 = s->bounds[3] - 50.0;
    P[0] = x0 + (x1 - x0) * (i + 0.5) / n;
    P[1] = y0 + (y1 - y0) * (j + 0.5) / n;
    P[2] = 0.0;
}

static double run_points(light *L, const scene *s, int n, int exact, double *sum)
{
    static const double up[3] = { 0.0, 0.0, 1.0 };
    double t0 = now_s(), e, acc = 0.0, P[3];
    int i, j;
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            raster_point(s, i, j, n, P);
            if (exact)
                light_illuminance_exact(L, P, up, &e, NULL);
            else
                light_illuminance(L, P, up, &e, NULL);
            acc += e;
        }
    *sum = acc;
    return (double)n * n / (now_s() - t0);
}

static void bench_points(light *L, const scene *s)
{
    static const double up[3] = { 0.0, 0.0, 1.0 };
    const int n = 1000, nref = 12;
    double cold, warm, exact, ref, sum1, sum2, sum3, t0, P[3];
    uint64_t computed, evicted;
    int i, j, bad = 0;
    light_cache_clear(L);
    computed = L->st.computed;
    evicted = L->st.evictions;
    cold = run_points(L, s, n, 0, &sum1);
    computed = L->st.computed - computed;
    evicted = L->st.evictions - evicted;
    warm = run_points(L, s, n, 0, &sum2);
    exact = run_points(L, s, n, 1, &sum3);
    t0 = now_s();
    for (j = 0; j < nref; j++)
        for (i = 0; i < nref; i++) {
            double e, er;
            raster_point(s, i * (n / nref), j * (n / nref), n, P);
            er = ref_illuminance(s, P, up);
            light_illuminance(L, P, up, &e, NULL);
            bad += fabs(e - er) > 1e-9 * fabs(er);
        }
    ref = nref * nref / (now_s() - t0);
    printf("  illuminance, %d ground points (%dx%d raster, row order):\n", n * n, n, n);
    printf("    region path cold %.0f points/s (%llu regions computed on the way, %llu evictions)\n",
           cold, (unsigned long long)computed, (unsigned long long)evicted);
    printf("    region path warm %.0f points/s\n", warm);
    printf("    segment path     %.0f points/s\n", exact);
    printf("    reference        %.0f points/s (%d points, %d disagreeing)\n", ref,
           nref * nref, bad);
    printf("    ratio warm / reference = %.0f, cold / reference = %.0f; sums %.6g %.6g %.6g\n",
           warm / ref, cold / ref, sum1, sum2, sum3);
}

static void bench_scene(const char *name, const scene *s, size_t cache)
{
    size_t size = cache + (256u << 20);
    void *mem = malloc(size);
    arena a;
    light *L;
    double t0;
    if (!mem) {
        printf("no memory\n");
        exit(1);
    }
    arena_init(&a, mem, size);
    t0 = now_s();
    if (light_create(&a, s, cache, &L) != PLX_OK) {
        printf("light_create failed\n");
        exit(1);
    }
    printf("== %s: %u buildings, %u lamps; light_create %.1f ms, %.1f MiB + cache %.0f MiB\n",
           name, s->nbld, s->nlamps, (now_s() - t0) * 1e3,
           (a.used[PLX_PART_LIT] - L->pool_cap) / 1048576.0, cache / 1048576.0);
    bench_regions(L, s);
    bench_points(L, s);
    free(mem);
}

static plx_engine *open_engine(void **mem, size_t size, plx_port *port)
{
    plx_config cfg;
    plx_engine *e;
    plx_config_default(&cfg);
    *port = *plx_port_posix();
    port->log = NULL;
    cfg.port = port;
    *mem = malloc(size);
    if (!*mem || plx_engine_create(*mem, size, &cfg, &e) != PLX_OK) {
        printf("engine creation failed\n");
        exit(1);
    }
    return e;
}

int main(void)
{
    textbuf tb = { NULL, 0, 0 };
    void *mem;
    plx_port port;
    plx_engine *e;
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (plx_gen_city("eixample", 30, 30, 1, append, &tb) != PLX_OK) {
        printf("gen failed\n");
        return 1;
    }
    e = open_engine(&mem, (size_t)1 << 30, &port);
    if (plx_load_geojson(e, tb.p, tb.n, "eixample-30x30") != PLX_OK) {
        printf("load failed: %s\n", plx_last_error(e));
        return 1;
    }
    free(tb.p);
    bench_scene("eixample 30x30 (plx_gen_city seed 1)", e->sc, (size_t)256 << 20);
    plx_engine_destroy(e);
    free(mem);

    e = open_engine(&mem, (size_t)256 << 20, &port);
    if (plx_load_file(e, "fixtures/helsinki-centre.geojson") != PLX_OK) {
        printf("load failed: %s\n", plx_last_error(e));
        return 1;
    }
    bench_scene("helsinki-centre (real district)", e->sc, (size_t)256 << 20);
    plx_engine_destroy(e);
    free(mem);
    return 0;
}
