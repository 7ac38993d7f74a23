/* Polar diagram benchmark: construction time and memory of the four quadrant
 * diagrams (src/polar/polar.h), and full-turn visibility queries (src/polar/visibility.h)
 * at random free pedestrian points, against the brute-force reference
 * tests/ref/ref_vis_fast (ref_vis's angular sweep with grid searches; the
 * same answers as ref_vis, see test_polar) run in the same process on the
 * first of those points.
 *
 * Cities: the real district fixtures/helsinki-centre.geojson, then
 * `gen eixample 30 30` (14,400 buildings), `gen oldtown 110 110` (~12,100)
 * and `gen oldtown 317 317` (~100,000), generated in memory.
 *
 * The reference costs O(V log V) per query for V footprint vertices (one
 * interval per vertex direction, each ray walking a grid), so it runs on
 * the points that fit in a few seconds per city (at most 200). Its answers
 * are checked against the engine's (area 1e-9 relative, same visible set)
 * and any mismatch is reported and fails the benchmark.
 *
 * Point location: the search DAG (polar_locate_frame_ex) against the
 * former grid scan (polar_scan_locate_frame, built in the same process) at
 * the same random points of the Bounds box (free, in footprints, both
 * maps), ns per query side by side; every answer is compared (a mismatch
 * fails the benchmark). Construction is also timed without keeping the
 * DAGs (POLAR_BUILD_NO_DAG: the maps are still built by insertion, the
 * sweep reads them) to give the share of mapping and storing the nodes. A hostile scene for the grid
 * scan comes last: a comb (one long thin footprint and thousands of short
 * teeth above it, so thousands of regions sit on one wall).
 *
 * Usage: bench_polar [QUERIES [quick]]   (default 2000 query points per
 * city; "quick" leaves out the 100,000-building city)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "port.h"
#include "base/engine.h"
#include "polar/polar.h"
#include "polar/visibility.h"
#include "ref_polar_scan.h"
#include "ref_vis.h"
#include "ref_vis_fast.h"

#define BUDGET ((size_t)6 << 30)
#define REF_MAX 200
#define REF_SECONDS 6.0

#include "gen_text.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Quantile q of v[0..n-1] (sorts v). */
static double quantile(double *v, int n, double q)
{
    int i;
    if (n <= 0)
        return 0;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    i = (int)(q * (n - 1) + 0.5);
    return v[i];
}

static uint64_t rng = 0x2545f4914f6cdd1dull;

static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* Point location at nl random points of the Bounds box, both maps: DAG
 * against the grid scan, answers compared. Returns the mismatches. */
static int bench_locate(const polar *pd, arena *a, int nl, uint32_t nv)
{
    polar_scan *g;
    vec2 *fp;
    int32_t *ans;
    double tdag = 1e300, tscan = 1e300, dsum = 0;
    uint32_t dmax = 0, dep;
    int i, r, bad = 0;
    unsigned long long t0;
    arena_mark m0 = arena_get_mark(a);
    if (polar_scan_new(a, pd, &g) != PLX_OK) {
        fprintf(stderr, "bench_polar: polar_scan_new failed\n");
        exit(1);
    }
    fp = malloc((size_t)nl * 2 * sizeof *fp);
    ans = malloc((size_t)nl * 2 * sizeof *ans);
    if (!fp || !ans) {
        fprintf(stderr, "bench_polar: out of memory\n");
        exit(1);
    }
    for (i = 0; i < nl; i++) {
        vec2 p;
        p.x = pd->box[0] + urand() * (pd->box[2] - pd->box[0]);
        p.y = pd->box[1] + urand() * (pd->box[3] - pd->box[1]);
        fp[2 * i] = polar_to_frame(pd->map[0].frame, p);
        fp[2 * i + 1] = polar_to_frame(pd->map[1].frame, p);
    }
    for (r = 0; r < 3; r++) {
        double t;
        t0 = port_now_ns();
        for (i = 0; i < 2 * nl; i++)
            ans[i] = polar_locate_frame(pd, &pd->map[i & 1], fp[i]);
        t = (double)(port_now_ns() - t0) / (2.0 * nl);
        tdag = t < tdag ? t : tdag;
        t0 = port_now_ns();
        for (i = 0; i < 2 * nl; i++)
            ans[i] ^= polar_scan_locate_frame(g, i & 1, fp[i], NULL);
        t = (double)(port_now_ns() - t0) / (2.0 * nl);
        tscan = t < tscan ? t : tscan;
        for (i = 0; i < 2 * nl; i++)
            bad += ans[i] != 0;
    }
    for (i = 0; i < 2 * nl; i++) {
        polar_locate_frame_ex(pd, &pd->map[i & 1], fp[i], NULL, &dep);
        dsum += dep;
        dmax = dep > dmax ? dep : dmax;
    }
    printf("  locate       DAG %6.0f ns/query  grid scan %6.0f ns/query  ratio %.2fx  "
           "(%d points x 2 maps, best of 3; %s)\n", tdag, tscan, tscan / tdag, nl,
           bad ? "MISMATCH" : "same answers");
    printf("  search DAG   %u + %u nodes of %d + %d bytes = %.1f bytes/vertex; depth mean %.1f "
           "max %u (log2 of wall pieces %.1f)\n", pd->map[0].nnode, pd->map[1].nnode,
           pd->map[0].narrow ? 8 : 12, pd->map[1].narrow ? 8 : 12,
           ((pd->map[0].narrow ? 8.0 : 12.0) * pd->map[0].nnode +
            (pd->map[1].narrow ? 8.0 : 12.0) * pd->map[1].nnode) / (nv ? nv : 1),
           dsum / (2.0 * nl), dmax, log2((double)pd->nwall + 1));
    free(fp);
    free(ans);
    arena_release(a, &m0);
    return bad;
}

static void bench(const char *name, const char *buf, size_t len, int nq)
{
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    plx_engine *e;
    scene *s;
    polar *pd = NULL;
    arena_mark m0;
    size_t by[4], tot, kept;
    uint32_t i, nocc = 0, nv = 0;
    double tb = 1e300, tb0 = 1e300, *tq, *tr, vis_frac = 0, steps = 0, ref_prep = 0;
    vec2 *pts;
    uint32_t *visbuf;
    int reps, r, n = 0, tries = 0, nref = 0, bad = 0;
    unsigned long long t0;

    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    if (plx_engine_new(BUDGET, &cfg, &e) != PLX_OK) {
        fprintf(stderr, "bench_polar: cannot create an engine of %zu bytes\n", (size_t)BUDGET);
        exit(1);
    }
    if (plx_load_geojson(e, buf, len, name) != PLX_OK) {
        fprintf(stderr, "bench_polar: %s: %s\n", name, plx_last_error(e));
        exit(1);
    }
    s = e->sc;
    for (i = 0; i < s->nbld; i++) {
        uint32_t k;
        if (s->bld[i].min_height > 0)
            continue;
        nocc++;
        for (k = 0; k < s->bld[i].ring_count; k++)
            nv += s->rings[s->bld[i].ring_first + k].count;
    }
    /* construction: best of a few */
    reps = nv > 200000 ? 2 : 4;
    m0 = arena_get_mark(&e->mem);
    for (r = 0; r < reps; r++) {
        plx_status st;
        double t;
        if (r > 0)
            arena_release(&e->mem, &m0);
        t0 = port_now_ns();
        st = polar_build(&e->mem, s, &pd);
        t = (port_now_ns() - t0) / 1e6;
        if (st != PLX_OK) {
            fprintf(stderr, "bench_polar: %s: polar_build: %s\n", name, plx_strerror(st));
            exit(1);
        }
        if (t < tb)
            tb = t;
        arena_release(&e->mem, &m0);
        t0 = port_now_ns();
        st = polar_build_flags(&e->mem, s, POLAR_BUILD_NO_DAG, &pd);
        t = (port_now_ns() - t0) / 1e6;
        if (st != PLX_OK) {
            fprintf(stderr, "bench_polar: %s: polar_build_flags: %s\n", name, plx_strerror(st));
            exit(1);
        }
        if (t < tb0)
            tb0 = t;
    }
    arena_release(&e->mem, &m0);
    if (polar_build(&e->mem, s, &pd) != PLX_OK)
        exit(1);
    polar_memory(pd, by);
    tot = by[0] + by[1] + by[2] + by[3];
    kept = e->mem.used[PLX_PART_POLAR] - m0.used[PLX_PART_POLAR];

    printf("%-20s %6u buildings (%u occluders), %7u footprint vertices, %u wall pieces\n",
           name, s->nbld, nocc, nv, pd->nwall);
    printf("  construction %8.1f ms  (%.2f us per vertex; best of %d); without keeping the "
           "search DAGs %.1f ms: keeping them %.0f%%\n", tb, 1e3 * tb / nv, reps, tb0, 100.0 * (tb - tb0) / tb);
    printf("  memory       %8.2f MB = %5.1f bytes/vertex (arena part polar %.2f MB)\n",
           tot / 1048576.0, (double)tot / nv, kept / 1048576.0);
    printf("    axes %5.1f  regions %5.1f  polygons %5.1f  rest (search DAGs) %5.1f  bytes/vertex"
           "  (regions %u + %u)\n", (double)by[0] / nv, (double)by[1] / nv,
           (double)by[2] / nv, (double)by[3] / nv, pd->map[0].ntrap, pd->map[1].ntrap);

    if (bench_locate(pd, &e->mem, nv > 200000 ? 100000 : 200000, nv) != 0) {
        fprintf(stderr, "bench_polar: %s: DAG and grid scan disagree\n", name);
        exit(1);
    }
    if (nq <= 0) {
        plx_engine_free(e);
        return;
    }

    /* queries at random free points of the building box (Bounds less 50 m) */
    tq = malloc((size_t)nq * sizeof *tq);
    tr = malloc(REF_MAX * sizeof *tr);
    pts = malloc((size_t)nq * sizeof *pts);
    visbuf = malloc((s->nbld + 1) * sizeof *visbuf);
    if (!tq || !tr || !pts || !visbuf) {
        fprintf(stderr, "bench_polar: out of memory\n");
        exit(1);
    }
    while (n < nq && tries < 100 * nq) {
        vis_result vr;
        vec2 p;
        double t;
        plx_status st;
        tries++;
        p.x = s->bounds[0] + 50 + urand() * (s->bounds[2] - s->bounds[0] - 100);
        p.y = s->bounds[1] + 50 + urand() * (s->bounds[3] - s->bounds[1] - 100);
        memset(&vr, 0, sizeof vr);
        t0 = port_now_ns();
        st = vis_query(pd, p, 0, 0, 1, &e->mem, &vr);
        t = (port_now_ns() - t0) / 1e3;
        if (st == PLX_E_RANGE)
            continue;
        if (st != PLX_OK) {
            fprintf(stderr, "bench_polar: %s: vis_query: %s\n", name, plx_strerror(st));
            exit(1);
        }
        pts[n] = p;
        tq[n++] = t;
        vis_frac += (double)vr.nvis / (nocc ? nocc : 1);
        steps += vr.nsteps;
    }

    /* the reference on the first points, within a time budget */
    {
        double spent = 0;
        ref_fast *rf;
        t0 = port_now_ns();
        rf = ref_fast_new(s);
        ref_prep = (port_now_ns() - t0) / 1e6;
        if (!rf) {
            fprintf(stderr, "bench_polar: %s: ref_fast_new: out of memory\n", name);
            exit(1);
        }
        while (nref < REF_MAX && nref < n && (nref == 0 || spent + spent / nref < REF_SECONDS)) {
            ref_vis_result rr;
            vis_result vr;
            int rc;
            uint32_t k;
            double t;
            t0 = port_now_ns();
            rc = ref_fast_vis(rf, pts[nref].x, pts[nref].y, &rr);
            t = (port_now_ns() - t0) / 1e3;
            memset(&vr, 0, sizeof vr);
            vr.vis = visbuf;
            vr.vis_cap = s->nbld + 1;
            vis_query(pd, pts[nref], 0, 0, 1, &e->mem, &vr);
            if (rc != 0 || fabs(vr.area - rr.area) > 1e-9 * fmax(rr.area, 1.0) ||
                vr.nvis != rr.nvisible) {
                bad++;
            } else {
                for (k = 0; k < vr.nvis; k++)
                    if (vr.vis[k] != rr.visible[k]) {
                        bad++;
                        break;
                    }
            }
            ref_vis_free(&rr);
            tr[nref++] = t;
            spent += t / 1e6;
        }
        ref_fast_free(rf);
    }
    {
        double med = quantile(tq, n, 0.5), p95 = quantile(tq, n, 0.95);
        printf("  360 query    median %8.1f us  p95 %8.1f us  (%d free points, %.0f regions "
               "crossed, %.2f%% of buildings visible on average)\n",
               med, p95, n, steps / (n ? n : 1), 100.0 * vis_frac / (n ? n : 1));
        if (nref > 0) {
            double rmed = quantile(tr, nref, 0.5), rp95 = quantile(tr, nref, 0.95);
            printf("  ref_vis_fast median %8.0f us  p95 %8.0f us  (prepared in %.0f ms; %d points) "
                   "ratio %.0fx; %s\n", rmed, rp95, ref_prep, nref, rmed / med,
                   bad ? "MISMATCH" : "same areas and visible sets");
        }
    }
    free(tq);
    free(tr);
    free(pts);
    free(visbuf);
    plx_engine_free(e);
    if (bad) {
        fprintf(stderr, "bench_polar: %s: %d reference mismatches\n", name, bad);
        exit(1);
    }
}

static void bench_gen(const char *style, int nx, int ny, int nq)
{
    text t = { NULL, 0, 0 };
    char name[64];
    if (plx_gen_city(style, nx, ny, 1, append, &t) != PLX_OK) {
        fprintf(stderr, "bench_polar: gen %s failed\n", style);
        exit(1);
    }
    snprintf(name, sizeof name, "gen %s %d %d", style, nx, ny);
    bench(name, t.buf, t.len, nq);
    free(t.buf);
}

/* The comb: one footprint 2000 m x 1 m, n teeth 1 m x (2000 / n / 2) m
 * above it (1 m gap), and a few boxes elsewhere. Visibility queries are
 * left out (nq = 0). */
static void bench_comb(int n)
{
    text t = { NULL, 0, 0 };
    char line[512], name[64];
    int i;
    double w = 2000.0 / n;
    snprintf(line, sizeof line, "{\"type\": \"FeatureCollection\", \"properties\": "
             "{\"units\": \"m\"}, \"features\": [\n");
    append(&t, line, strlen(line));
    snprintf(line, sizeof line, "{\"type\": \"Feature\", \"properties\": {\"height\": 10}, "
             "\"geometry\": {\"type\": \"Polygon\", \"coordinates\": "
             "[[[0,0],[2000,0],[2000,1],[0,1],[0,0]]]}}");
    append(&t, line, strlen(line));
    for (i = 0; i < n; i++) {
        double x0 = i * w, x1 = x0 + w / 2;
        snprintf(line, sizeof line, ",\n{\"type\": \"Feature\", \"properties\": {\"height\": "
                 "10}, \"geometry\": {\"type\": \"Polygon\", \"coordinates\": "
                 "[[[%.6f,2],[%.6f,2],[%.6f,3],[%.6f,3],[%.6f,2]]]}}", x0, x1, x1, x0, x0);
        append(&t, line, strlen(line));
    }
    append(&t, "]}\n", 3);
    if (!t.buf) {
        fprintf(stderr, "bench_polar: out of memory\n");
        exit(1);
    }
    snprintf(name, sizeof name, "comb %d teeth", n);
    bench(name, t.buf, t.len, 0);
    free(t.buf);
}

int main(int argc, char **argv)
{
    char err[256];
    size_t len;
    int nq = argc > 1 ? atoi(argv[1]) : 2000;
    char *h = port_read_text("fixtures/helsinki-centre.geojson", &len, err, sizeof err);
    if (!h) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    if (nq < 1)
        nq = 1;
    printf("polar diagrams: one thread; times by the port clock\n");
    bench("helsinki-centre", h, len, nq);
    free(h);
    bench_gen("eixample", 30, 30, nq);
    bench_gen("oldtown", 110, 110, nq);
    if (argc < 3)
        bench_gen("oldtown", 317, 317, nq);
    bench_comb(2000);
    bench_comb(16000);
    return 0;
}
