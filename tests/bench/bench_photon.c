/* Photon benchmark (src/photon/photon.h, src/photon/trace.h), single thread:
 *  - the photon pass: ms per photon_step of 64K photons on
 *    `gen eixample 30 30` (generated in memory), target <= 10 ms;
 *  - rays per second of the grid caster against the brute-force caster
 *    (every building) on the same rays, run in the same process;
 *  - caster new vs old: ns per ray of the lamp tables (trace_lamp_ray),
 *    the grid walk (trace_ray) and the caster before them
 *    (tests/ref/ref_trace_old.c) on the same rays (street rays, and rays
 *    like a photon pass's: from lamps and bounces), thread CPU time, best
 *    of 5 alternated runs; a sweep of the grid's cell size;
 *  - memory of the photon buffers by kind;
 *  - lookup time of photon_indirect (ground and facade points);
 *  - error against photon count on fixtures/eixample-4x4.geojson, measured
 *    against a long run of the same estimator (convergence, not accuracy:
 *    tests/unit/test_photon.c checks accuracy against path tracing).
 *
 * Usage: bench_photon [FRAMES [pass]]   (default 20 timed passes; "pass":
 * stop after the photon pass, for profiling it)
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
#include "photon/nightlight.h"
#include "ref_trace_old.h"

#define BUDGET ((size_t)3 << 30)

#include "gen_text.h"

static uint64_t now_ns(void)
{
    return plx_port_posix()->clock_ns(NULL);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static plx_engine *engine_with(const char *text_or_path, size_t len, int is_file)
{
    plx_engine *e;
    plx_config cfg;
    plx_port port = *plx_port_posix();
    static plx_port keep;
    port.log = NULL;
    keep = port;
    plx_config_default(&cfg);
    cfg.port = &keep;
    if (plx_engine_new(BUDGET, &cfg, &e) != PLX_OK) {
        fprintf(stderr, "bench_photon: no memory for the engine\n");
        exit(1);
    }
    if ((is_file ? plx_load_file(e, text_or_path)
                 : plx_load_geojson(e, text_or_path, len, "eixample")) != PLX_OK) {
        fprintf(stderr, "bench_photon: load failed: %s\n", plx_last_error(e));
        exit(1);
    }
    return e;
}

static int free_point(tracer *T, const scene *s, uint64_t *rs, double o[3])
{
    int tries;
    for (tries = 0; tries < 1000; tries++) {
        o[0] = s->bounds[0] + (s->bounds[2] - s->bounds[0]) * photon_rand01(rs);
        o[1] = s->bounds[1] + (s->bounds[3] - s->bounds[1]) * photon_rand01(rs);
        o[2] = 0.5 + 10.0 * photon_rand01(rs);
        if (trace_top(T, o[0], o[1], NULL) == 0.0)
            return 1;
    }
    return 0;
}

static void sphere(uint64_t *rs, double d[3])
{
    double z = 1.0 - 2.0 * photon_rand01(rs), r = sqrt(1.0 - z * z);
    double p = 2.0 * 3.14159265358979323846 * photon_rand01(rs);
    d[0] = r * cos(p);
    d[1] = r * sin(p);
    d[2] = z;
}


/* Rays like those of a photon pass (photon_trace_lamp): lamps taken in
 * order like photon_step's stratified choice (NPH photons spread over the
 * lamps), from the lamp in a uniform direction up to its radius, then
 * diffuse bounces from each hit (albedo survival, 1e-5 m off the surface
 * like photon.c's BOUNCE_OFFSET). Stored as o, d, tmax and the lamp (or
 * -1 for a bounce) for replays. */
static int pass_rays(tracer *T, const scene *s, uint64_t *rs, int n, double (*o)[3],
                     double (*d)[3], double *tmax, int32_t *lamp)
{
    int k = 0, ph = 0;
    const int NPH = 65536;
    while (k < n) {
        uint32_t l = (uint32_t)((ph++ % NPH + photon_rand01(rs)) / NPH * s->nlamps);
        const scene_lamp *L = &s->lamps[l < s->nlamps ? l : s->nlamps - 1];
        trace_hit h;
        int b;
        o[k][0] = L->x;
        o[k][1] = L->y;
        o[k][2] = L->z;
        sphere(rs, d[k]);
        tmax[k] = L->radius;
        lamp[k] = (int32_t)(L - s->lamps);
        if (trace_ray(T, o[k], d[k], tmax[k], &h) == TRACE_SKY) {
            k++;
            continue;
        }
        k++;
        for (b = 0; b < 16 && k < n; b++) {
            double alb = h.kind == TRACE_GROUND ? s->ground_albedo : s->bld[h.bld].albedo;
            if (photon_rand01(rs) >= alb)
                break;
            photon_cosine_dir(rs, h.n, d[k]);
            o[k][0] = h.p[0] + 1e-5 * h.n[0];
            o[k][1] = h.p[1] + 1e-5 * h.n[1];
            o[k][2] = h.p[2] + 1e-5 * h.n[2];
            tmax[k] = INFINITY;
            lamp[k] = -1;
            if (trace_ray(T, o[k], d[k], tmax[k], &h) == TRACE_SKY) {
                k++;
                break;
            }
            k++;
        }
    }
    return k;
}

/* Thread CPU time: the machine is shared, so a run is timed by the time it
 * got, and the best of several runs is kept. */
static uint64_t cpu_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* The pass without its stores: photons like photon_step's (lamps taken
 * in order by equal flux shares, the same tracing and roulette through
 * photon_trace_lamp; not the lamp-table prefetch of photon_step) with a
 * store that only counts: what the pass costs apart from storing. Returns
 * thread CPU ms. */
static void count_store(photon_sys *ps, void *ctx, uint32_t lamp, const trace_hit *h,
                        const double f[PHOTON_CH])
{
    (void)ps;
    (void)lamp;
    (void)h;
    (void)f;
    ++*(uint64_t *)ctx;
}

static double pass_without_stores(photon_sys *ps, uint32_t n, uint64_t seed, uint64_t *stores)
{
    const scene *s = ps->s;
    uint64_t rng = seed ^ 0x5bd1e9955bd1e995ull, c0 = cpu_ns();
    photon_stats st;
    uint32_t k, lamp = 0;
    memset(&st, 0, sizeof st);
    for (k = 0; k < n; k++) {
        double u = (k + photon_rand01(&rng)) / n * ps->flux_total;
        while (lamp + 1 < s->nlamps && ps->lamp_cdf[lamp] <= u)
            lamp++;
        photon_trace_lamp(ps, lamp, ps->flux_total / n, &rng, &st, count_store, stores);
    }
    return (cpu_ns() - c0) / 1e6;
}

/* Which caster new_vs_old times: 0 trace_ray, 1 trace_lamp_ray where the
 * ray comes from a lamp (trace_ray for bounces), 2 the old caster. */
static void cast(int which, tracer *T, old_tracer *O, const double *o, const double *d,
                 double tmax, int32_t lamp, trace_hit *h)
{
    if (which == 2)
        old_trace_ray(O, o, d, tmax, h);
    else if (which == 1 && lamp >= 0)
        trace_lamp_ray(T, (uint32_t)lamp, d, h);
    else
        trace_ray(T, o, d, tmax, h);
}

/* ns per ray of the casters on the same rays (sel: -1 all, 0 lamp rays,
 * 1 bounces), best of 5 alternated runs; mismatches of kind or t (1e-9
 * relative) against the old caster. */
static void new_vs_old(const char *what, tracer *T, old_tracer *O, int n, double (*o)[3],
                       double (*d)[3], const double *tmax, const int32_t *lamp, int sel)
{
    double best[3] = {1e30, 1e30, 1e30};
    uint64_t t0;
    int i, r, w, mism = 0, used = 0;
    trace_hit h, ho;
    for (r = 0; r < 5; r++)
        for (w = 0; w < 3; w++) {
            double v;
            if (w == 1 && sel == 1)
                continue;
            t0 = cpu_ns();
            for (i = 0; i < n; i++)
                if (sel < 0 || (lamp[i] >= 0) == (sel == 0))
                    cast(w, T, O, o[i], d[i], tmax[i], lamp[i], &h);
            v = (double)(cpu_ns() - t0);
            if (v < best[w])
                best[w] = v;
        }
    for (i = 0; i < n; i++) {
        if (!(sel < 0 || (lamp[i] >= 0) == (sel == 0)))
            continue;
        used++;
        cast(1, T, O, o[i], d[i], tmax[i], lamp[i], &h);
        old_trace_ray(O, o[i], d[i], tmax[i], &ho);
        if (h.kind != ho.kind || (h.kind != TRACE_SKY && fabs(h.t - ho.t) > 1e-9 * (1 + h.t)))
            mism++;
    }
    if (sel == 1)
        printf("caster new vs old (%s, %d rays): grid walk %.0f ns/ray, old %.0f ns/ray: %.2fx; "
               "%d mismatches\n",
               what, used, best[0] / used, best[2] / used, best[2] / best[0], mism);
    else
        printf("caster new vs old (%s, %d rays): lamp tables %.0f ns/ray, grid walk %.0f "
               "ns/ray, old %.0f ns/ray: %.2fx (walk %.2fx); %d mismatches\n",
               what, used, best[1] / used, best[0] / used, best[2] / used, best[2] / best[1],
               best[2] / best[0], mism);
}

/* ---- caster new vs old ---- */

enum { NR = 200000 };
static double o_st[NR][3], d_st[NR][3]; /* the street rays of the caster section */

/* The new casters against the old one (tests/ref/ref_trace_old.c) on the
 * street rays and on photon-pass rays, and a sweep of the cell size. Run
 * after the lookups: it takes memory (the old caster, sweep grids). */
static int compare_casters(plx_engine *e, photon_sys *ps, const scene *s, uint64_t *prs)
{
    double (*o)[3] = o_st, (*d)[3] = d_st;
    uint64_t rs = *prs, t0;
    trace_hit h;
    int i;
    {
        enum { NP = 200000 };
        static double po[NP][3], pd[NP][3], pt[NP], tm[NR];
        static int32_t pl[NP], nol[NR];
        old_tracer *O;
        static const double sizes[] = {0.3, 0.4, 0.5, 0.6, 0.75, 1.0};
        double per = (s->bounds[2] - s->bounds[0]) * (s->bounds[3] - s->bounds[1]) / s->nbld;
        uint32_t l, nfast = 0;
        unsigned z;
        if (old_trace_create(&e->mem, PLX_PART_PHOTON, s, 0.0, &O) != PLX_OK) {
            fprintf(stderr, "bench_photon: old caster: out of memory\n");
            return 1;
        }
        for (l = 0; l < s->nlamps; l++)
            nfast += ps->T->lfast[l];
        printf("lamp tables: %u of %u lamps, %u wall references (%.1f per lamp, %d sectors), "
               "%.1f MiB; grid %.1f MiB (walls, cells, lists)\n",
               nfast, s->nlamps, ps->T->lsec[(size_t)s->nlamps * (TRACE_SECTORS + 2)],
               ps->T->lsec[(size_t)s->nlamps * (TRACE_SECTORS + 2)] / (double)nfast,
               TRACE_SECTORS,
               (ps->T->lsec[(size_t)s->nlamps * (TRACE_SECTORS + 2)] * 4.0 +
                s->nlamps * ((TRACE_SECTORS + 2) * 4.0 + 1)) / 1048576.0,
               (ps->T->cells[(size_t)ps->T->nx * ps->T->ny].w0 * 4.0 +
                ((size_t)ps->T->nx * ps->T->ny + 1) * (sizeof(trace_cell) + 4.0) +
                s->npts * (sizeof(trace_wall) + 4.0) + s->nbld * 16.0 +
                ps->T->start[(size_t)ps->T->nx * ps->T->ny] * 4.0) / 1048576.0);
        for (i = 0; i < NR; i++) {
            tm[i] = INFINITY;
            nol[i] = -1;
        }
        new_vs_old("street rays", ps->T, O, NR, o, d, tm, nol, 1);
        pass_rays(ps->T, s, &rs, NP, po, pd, pt, pl);
        new_vs_old("photon-pass rays, all", ps->T, O, NP, po, pd, pt, pl, -1);
        new_vs_old("photon-pass rays, from lamps", ps->T, O, NP, po, pd, pt, pl, 0);
        new_vs_old("photon-pass rays, bounces", ps->T, O, NP, po, pd, pt, pl, 1);
        printf("cell size sweep, grid walk on the photon-pass rays (cell = factor x "
               "sqrt(area per building); default factor %.2f):\n",
               TRACE_CELL_FACTOR);
        for (z = 0; z < sizeof sizes / sizeof sizes[0]; z++) {
            arena_mark m = arena_get_mark(&e->mem);
            tracer *T2;
            double best = 1e30;
            int r;
            if (trace_create(&e->mem, PLX_PART_PHOTON, s, sizes[z] * sqrt(per), &T2) !=
                PLX_OK)
                return 1;
            for (r = 0; r < 3; r++) {
                double v;
                t0 = cpu_ns();
                for (i = 0; i < NP; i++)
                    trace_ray(T2, po[i], pd[i], pt[i], &h);
                v = (double)(cpu_ns() - t0) / NP;
                if (v < best)
                    best = v;
            }
            printf("  factor %.2f (%.1f m cells): %.0f ns/ray\n", sizes[z], T2->cell, best);
            arena_release(&e->mem, &m);
        }
    }
    *prs = rs;
    return 0;
}

int main(int argc, char **argv)
{
    int frames = argc > 1 ? atoi(argv[1]) : 20;
    text t = {NULL, 0, 0};
    plx_engine *e;
    const scene *s;
    photon_sys *ps;
    plx_memory_report mr;
    uint64_t t0, rs = 12345;
    double *ms;
    int i;
    if (frames < 1)
        frames = 1;
    if (plx_gen_city("eixample", 30, 30, 1, append, &t) != PLX_OK) {
        fprintf(stderr, "bench_photon: gen failed\n");
        return 1;
    }
    e = engine_with(t.buf, t.len, 0);
    s = e->sc;
    printf("city: gen eixample 30 30: %u buildings, %u blocks, %u lamps, %u vertices\n", s->nbld,
           s->nblocks, s->nlamps, s->npts);
    t0 = now_ns();
    if (photon_create(&e->mem, s, NULL, &ps) != PLX_OK) {
        fprintf(stderr, "bench_photon: photon_create: out of memory\n");
        return 1;
    }
    printf("photon_create: %.1f ms (tracer grid %ux%u cells of %.1f m, aerial %ux%u texels of "
           "%.2f m)\n",
           (now_ns() - t0) / 1e6, ps->T->nx, ps->T->ny, ps->T->cell, ps->gw, ps->gh, ps->gtex);

    /* ---- memory ---- */
    plx_memory_get(e, &mr);
    {
        /* aerial: height, area, A and I (PHOTON_CH each); covered ground:
         * its texel index and its slots (area, A_cov, I_cov) */
        size_t g = (size_t)ps->gw * ps->gh * (2 + 2 * PHOTON_CH) * sizeof(float), lv = 0;
        size_t cov = ps->gcov ? (size_t)ps->gw * ps->gh * sizeof(uint32_t) +
                                    (size_t)ps->cov_cap * (1 + 2 * PHOTON_CH) * sizeof(float)
                              : 0;
        size_t cache = ps->nslots * photon_lamp_slot_bytes(s, &ps->cfg);
        int L;
        for (L = 0; L < PHOTON_LEVELS; L++)
            lv += (size_t)ps->lev[L].nslots * 2 * ps->lev[L].w * ps->lev[L].h *
                  (1 + PHOTON_CH) * sizeof(float);
        printf("memory (part photon): %.1f MiB total; facade atlases %.1f MiB (4 levels), "
               "aerial charts %.1f MiB, covered ground %.2f MiB (%u of %u slots), lamp cache "
               "%.1f MiB (%u slots), tracer and tables %.1f MiB; scene itself %.1f MiB\n",
               mr.used[PLX_PART_PHOTON] / 1048576.0, lv / 1048576.0, g / 1048576.0,
               cov / 1048576.0, ps->ncov, ps->cov_cap, cache / 1048576.0, ps->nslots,
               (mr.used[PLX_PART_PHOTON] - lv - g - cov - cache) / 1048576.0,
               mr.used[PLX_PART_SCENE] / 1048576.0);
    }

    /* ---- the photon pass ---- */
    {
        double eye[3];
        eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
        eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
        eye[2] = 1.7;
        photon_set_viewer(ps, eye, NULL, 0.0);
    }
    ms = malloc(sizeof *ms * (size_t)frames);
    photon_step(ps, 65536, 1); /* warm-up */
    {
        uint64_t traced0 = ps->st.traced;
        double cpu_min = 1e30;
        for (i = 0; i < frames; i++) {
            uint64_t c0 = cpu_ns();
            t0 = now_ns();
            photon_step(ps, 65536, 2 + (uint64_t)i);
            ms[i] = (now_ns() - t0) / 1e6;
            if ((cpu_ns() - c0) / 1e6 < cpu_min)
                cpu_min = (cpu_ns() - c0) / 1e6;
        }
        printf("photon pass, thread CPU time: %.2f ms min over %d passes\n", cpu_min, frames);
        qsort(ms, (size_t)frames, sizeof *ms, cmp_double);
        printf("photon pass: 65536 photons in %.2f ms median (min %.2f, max %.2f) over %d "
               "passes; %.2f rays per photon; target 10 ms: %s\n",
               ms[frames / 2], ms[0], ms[frames - 1], frames,
               (double)(ps->st.traced - traced0) / (65536.0 * frames),
               ms[frames / 2] <= 10.0 ? "met" : "NOT met");
        printf("  per photon %.0f ns; stored %.0f%% of the flux reaching later hits "
               "(chart %.0f%%, aerial %.0f%%, ambient %.0f%%, covered ground %.1f%%, "
               "lost %.1f%%)\n",
               ms[frames / 2] * 1e6 / 65536.0,
               100.0 * (ps->st.stored_chart + ps->st.stored_aerial + ps->st.stored_ambient +
                        ps->st.stored_covered) /
                   ps->st.arrived,
               100.0 * ps->st.stored_chart / ps->st.arrived,
               100.0 * ps->st.stored_aerial / ps->st.arrived,
               100.0 * ps->st.stored_ambient / ps->st.arrived,
               100.0 * ps->st.stored_covered / ps->st.arrived,
               100.0 * ps->st.lost / ps->st.arrived);
    }
    {
        double best = 1e30;
        uint64_t stores = 0;
        for (i = 0; i < frames; i++) {
            double c = pass_without_stores(ps, 65536, 2 + (uint64_t)i, &stores);
            if (c < best)
                best = c;
        }
        printf("  photons without storing (photon_trace_lamp, a store that only counts): "
               "%.2f ms thread CPU min; %.0f stores per pass\n",
               best, (double)stores / frames);
    }
    if (argc > 2 && strcmp(argv[2], "pass") == 0)
        return 0;

    /* ---- the caster ---- */
    {
        enum { NB = 300 };
        double (*o)[3] = o_st, (*d)[3] = d_st;
        trace_hit h, hb;
        double fast, brute;
        int mism = 0;
        for (i = 0; i < NR; i++) {
            free_point(ps->T, s, &rs, o[i]);
            sphere(&rs, d[i]);
        }
        t0 = now_ns();
        for (i = 0; i < NR; i++)
            trace_ray(ps->T, o[i], d[i], INFINITY, &h);
        fast = NR / ((now_ns() - t0) / 1e9);
        printf("caster: %.2f M rays/s (random rays from street points, any direction)\n", fast / 1e6);
        t0 = now_ns();
        for (i = 0; i < NB; i++)
            trace_ray_brute(ps->T, o[i], d[i], INFINITY, &hb);
        brute = NB / ((now_ns() - t0) / 1e9);
        for (i = 0; i < NB; i++) {
            trace_ray(ps->T, o[i], d[i], INFINITY, &h);
            trace_ray_brute(ps->T, o[i], d[i], INFINITY, &hb);
            if (h.kind != hb.kind || (h.kind != TRACE_SKY && fabs(h.t - hb.t) > 1e-9 * (1 + h.t)))
                mism++;
        }
        printf("brute-force caster (every building): %.0f rays/s on %d of the rays; grid is "
               "%.0fx faster; %d mismatches\n",
               brute, NB, fast / brute, mism);
        if (mism)
            return 1;
    }

    /* ---- lookups ---- */
    {
        enum { NQ = 100000 };
        static double P[NQ][3], N[NQ][3];
        int nq = 0, nf = 0;
        double sum = 0.0, tg, tf;
        while (nq < NQ) {
            double o[3], dd[3];
            trace_hit h;
            free_point(ps->T, s, &rs, o);
            if (nq % 2 == 0) {
                P[nq][0] = o[0];
                P[nq][1] = o[1];
                P[nq][2] = 0.0;
                N[nq][0] = N[nq][1] = 0.0;
                N[nq][2] = 1.0;
                nq++;
                continue;
            }
            sphere(&rs, dd);
            dd[2] = 0.0;
            {
                double l = hypot(dd[0], dd[1]);
                dd[0] /= l;
                dd[1] /= l;
            }
            if (trace_ray(ps->T, o, dd, 50.0, &h) != TRACE_WALL)
                continue;
            memcpy(P[nq], h.p, sizeof P[nq]);
            memcpy(N[nq], h.n, sizeof N[nq]);
            nq++;
            nf++;
        }
        t0 = now_ns();
        for (i = 0; i < NQ; i += 2)
            sum += photon_indirect(ps, P[i], N[i]);
        tg = (now_ns() - t0) / (NQ / 2.0);
        t0 = now_ns();
        for (i = 1; i < NQ; i += 2)
            sum += photon_indirect(ps, P[i], N[i]);
        tf = (now_ns() - t0) / (NQ / 2.0);
        printf("lookup: ground %.0f ns, facade %.0f ns (probe ray + chart) per point; %d "
               "points, mean E %.3f lx\n",
               tg, tf, NQ, sum / NQ);
    }
    if (compare_casters(e, ps, s, &rs))
        return 1;
    plx_engine_free(e);
    free(t.buf);
    free(ms);

    /* ---- error vs photons on eixample-4x4 (convergence) ---- */
    {
        enum { NP = 64 };
        static double P[NP][3], N[NP][3], ref[NP];
        int np = 0, k, marks[6] = {1, 4, 16, 64, 0, 0}, m;
        photon_sys *p2;
        photon_config c;
        double eye[3];
        e = engine_with("fixtures/eixample-4x4.geojson", 0, 1);
        s = e->sc;
        photon_config_default(&c);
        eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
        eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
        eye[2] = 1.7;
        if (photon_create(&e->mem, s, &c, &p2) != PLX_OK)
            return 1;
        photon_set_viewer(p2, eye, NULL, 0.0);
        while (np < NP) {
            const scene_lamp *L = &s->lamps[photon_rand(&rs) % s->nlamps];
            double a = 6.283185307179586 * photon_rand01(&rs), dd[3] = {cos(a), sin(a), 0};
            double o[3] = {L->x, L->y, 2.0};
            trace_hit h;
            if (np % 2 == 0) {
                double x = L->x + 4 * cos(a), y = L->y + 4 * sin(a);
                if (trace_top(p2->T, x, y, NULL) != 0.0)
                    continue;
                P[np][0] = x;
                P[np][1] = y;
                P[np][2] = 0;
                N[np][0] = N[np][1] = 0;
                N[np][2] = 1;
            } else {
                if (trace_ray(p2->T, o, dd, 12.0, &h) != TRACE_WALL)
                    continue;
                memcpy(P[np], h.p, sizeof P[np]);
                memcpy(N[np], h.n, sizeof N[np]);
            }
            np++;
        }
        /* baseline: 512 passes (33.5 M photons) */
        for (k = 0; k < 512; k++)
            photon_step(p2, 65536, 100000 + (uint64_t)k);
        for (i = 0; i < NP; i++)
            ref[i] = photon_indirect(p2, P[i], N[i]);
        photon_reset(p2);
        printf("error vs photons (eixample-4x4, %d ground+facade points near lamps, against "
               "512 passes = 33.5 M photons):\n  photons     mean rel diff\n",
               NP);
        for (m = 0, k = 0; marks[m]; k++) {
            photon_step(p2, 65536, 7 + (uint64_t)k);
            if (k + 1 == marks[m]) {
                double err = 0.0;
                int used = 0;
                for (i = 0; i < NP; i++)
                    if (ref[i] > 0.0) {
                        err += fabs(photon_indirect(p2, P[i], N[i]) - ref[i]) / ref[i];
                        used++;
                    }
                printf("  %9d   %.4f\n", marks[m] * 65536, used ? err / used : 0.0);
                m++;
            }
        }
        plx_engine_free(e);
    }
    return 0;
}
