/* Street network benchmark on `gen eixample 30 30`: a generated walking
 * network (both sidewalks of every street, crossings at the corners and
 * mid-block: 13,144 edges) is built and scored, against scoring the same
 * lines whole with plx_route_score and plx_route_facial (what 'polarlux
 * route --path' does: E_h and the SPEC §6 minima of E_v, E_sc); then
 * route queries (snap both ends, score the partial end edges, Dijkstra with
 * a binary heap), against a Dijkstra that scans every node for the minimum,
 * on the same queries in the same process (same costs checked). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "port.h"
#include "cli/network.h"

#include "gen_text.h"

#define PITCH 133.0
#define SIDE 7.0 /* sidewalks 7 m from the street's centre line (3 m from the facades) */
#define N 30

static route_line *next_line(route_set *rs, uint32_t nv)
{
    route_line *l = &rs->lines[rs->n++];
    memset(l, 0, sizeof *l);
    l->xy = malloc(sizeof *l->xy * 2 * nv);
    l->n = nv;
    snprintf(l->id, sizeof l->id, "gen/%zu", rs->n);
    return l;
}

/* Positions along a sidewalk: both kerbs of every crossing street and the
 * middle of every block. */
static uint32_t stops(double *t)
{
    uint32_t n = 0;
    int j;
    for (j = 0; j <= N; j++) {
        t[n++] = PITCH * j - SIDE;
        t[n++] = PITCH * j + SIDE;
        if (j < N)
            t[n++] = PITCH * j + PITCH / 2;
    }
    return n;
}

static void make_network(route_set *rs)
{
    double t[3 * N + 3];
    uint32_t nt = stops(t), k;
    int i, j, o, d;
    rs->lines = calloc(4 * (N + 1) + 2 * (N + 1) * N, sizeof *rs->lines);
    rs->n = 0;
    for (d = 0; d < 2; d++)
        for (i = 0; i <= N; i++)
            for (o = -1; o <= 1; o += 2) {
                route_line *l = next_line(rs, nt);
                for (k = 0; k < nt; k++) {
                    l->xy[2 * k + d] = PITCH * i + o * SIDE;
                    l->xy[2 * k + 1 - d] = t[k];
                }
            }
    for (d = 0; d < 2; d++) /* mid-block crossings */
        for (i = 0; i <= N; i++)
            for (j = 0; j < N; j++) {
                route_line *l = next_line(rs, 2);
                l->xy[d] = PITCH * i - SIDE;
                l->xy[1 - d] = PITCH * j + PITCH / 2;
                l->xy[2 + d] = PITCH * i + SIDE;
                l->xy[3 - d] = PITCH * j + PITCH / 2;
            }
}

/* The baseline search: Dijkstra picking the nearest unsettled node by a scan. */
static double scan_dijkstra(const network *net, uint32_t s, uint32_t t, double w)
{
    double *d = malloc(sizeof *d * net->nnodes), res;
    char *done = calloc(net->nnodes, 1);
    uint32_t i, j;
    for (i = 0; i < net->nnodes; i++)
        d[i] = INFINITY;
    d[s] = 0;
    for (;;) {
        uint32_t u = UINT32_MAX;
        for (i = 0; i < net->nnodes; i++)
            if (!done[i] && d[i] < INFINITY && (u == UINT32_MAX || d[i] < d[u]))
                u = i;
        if (u == UINT32_MAX || u == t)
            break;
        done[u] = 1;
        for (j = net->adj_first[u]; j < net->adj_first[u + 1]; j++) {
            const net_edge *ed = &net->edges[net->adj[j]];
            uint32_t v = ed->a == u ? ed->b : ed->a;
            double c = d[u] + ed->length + w * (ed->dark + ed->s.blocked_length);
            if (c < d[v])
                d[v] = c;
        }
    }
    res = d[t];
    free(d);
    free(done);
    return res;
}

static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(void)
{
    text txt = { NULL, 0, 0 };
    plx_engine *e, *failed;
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    route_set rs;
    network net;
    char err[256];
    double t_build, t_score, t_base, metres = 0, q_ms[200], q_cpu[200], base_ms = 0, w = 3.0, c0, cpu_base, cpu_score;
    unsigned long long t0;
    size_t i;
    int q, nq = 200, nbase = 5, mism = 0;
    uint64_t rng = 12345;
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    /* room for every lamp's lit region: with the default 16 MiB pool a
     * city-wide network overflows the cache, and each miss then compacts the
     * whole pool (see README, "Street networks") */
    if (!getenv("BENCH_DEFAULT_CACHE")) cfg.lit_cache_bytes = (size_t)256 << 20;
    if (plx_gen_city("eixample", N, N, 1, append, &txt) != PLX_OK ||
        plx_engine_new((size_t)1 << 30, &cfg, &e) != PLX_OK ||
        plx_load_geojson(e, txt.buf, txt.len, "eixample") != PLX_OK) {
        fprintf(stderr, "setup failed\n");
        return 1;
    }
    free(txt.buf);
    make_network(&rs);
    /* warm the lit-region cache (every lamp the network reaches), untimed,
     * so that the baseline and the network scoring both find it warm */
    for (i = 0; i < rs.n; i++) {
        plx_route_stats s;
        plx_route_score(e, rs.lines[i].xy, rs.lines[i].n, 1.0, 1.0, &s, NULL);
    }
    /* baseline: every line scored whole, as 'polarlux route --path' would
     * (E_h, then the SPEC §6 minima of E_v and E_sc at 1.5 m) */
    t0 = port_now_ns();
    c0 = cpu_ms();
    for (i = 0; i < rs.n; i++) {
        plx_route_stats s;
        double fac[4];
        if (plx_route_score(e, rs.lines[i].xy, rs.lines[i].n, 1.0, 1.0, &s, NULL) != PLX_OK ||
            plx_route_facial(e, rs.lines[i].xy, rs.lines[i].n, 1.0, 1.5, NULL, fac) != PLX_OK)
            return 1;
        metres += s.length + s.blocked_length;
    }
    t_base = (port_now_ns() - t0) / 1e9;
    cpu_base = cpu_ms() - c0;
    t0 = port_now_ns();
    if (net_build(&net, &rs, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    t_build = (port_now_ns() - t0) / 1e9;
    t0 = port_now_ns();
    c0 = cpu_ms();
    if (net_score(&net, e, NULL, 1.0, 1.0, 1.5, 0, &failed) != PLX_OK)
        return 1;
    t_score = (port_now_ns() - t0) / 1e9;
    cpu_score = cpu_ms() - c0;
    printf("street network on gen eixample 30 30: %zu lines, %u nodes, %u edges, %.0f m, 1 m steps\n", net.lines.n,
           net.nnodes, net.nedges, metres);
    printf("  build (join at shared vertices)  %8.3f s\n", t_build);
    printf("  score every edge (E_h, E_v, E_sc) %7.3f s = %.0f m/s (thread CPU %.3f s)\n", t_score, metres / t_score,
           cpu_score / 1e3);
    printf("  baseline: the lines scored whole %8.3f s (thread CPU %.3f s); ratio %.2fx\n", t_base, cpu_base / 1e3,
           (t_build + t_score) / t_base);
    for (q = 0; q < nq; q++) {
        net_snap a, b;
        net_route r;
        double x[4];
        int k;
        for (k = 0; k < 4; k++) {
            rng = rng * 6364136223846793005ull + 1442695040888963407ull;
            x[k] = (double)(rng >> 11) / 9007199254740992.0 * PITCH * N;
        }
        t0 = port_now_ns();
        c0 = cpu_ms();
        net_snap_point(&net, x[0], x[1], &a);
        net_snap_point(&net, x[2], x[3], &b);
        if (net_route_find(&net, e, &a, &b, w, &r, err, sizeof err) != 0) {
            fprintf(stderr, "query %d: %s\n", q, err);
            return 1;
        }
        q_ms[q] = (port_now_ns() - t0) / 1e6;
        q_cpu[q] = cpu_ms() - c0;
        if (q < nbase) { /* the baseline from the nodes the route passes first and last */
            net_snap a2, b2;
            uint32_t s_node = net.edges[a.edge].a, t_node = net.edges[b.edge].b;
            net_route r2;
            double want;
            a2.edge = a.edge, a2.seg = 0, a2.x = net.node_xy[2 * s_node], a2.y = net.node_xy[2 * s_node + 1];
            b2.edge = b.edge, b2.seg = net.edges[b.edge].v1 - net.edges[b.edge].v0 - 1;
            b2.x = net.node_xy[2 * t_node], b2.y = net.node_xy[2 * t_node + 1];
            a2.dist = b2.dist = 0;
            net_route_find(&net, e, &a2, &b2, w, &r2, err, sizeof err);
            t0 = port_now_ns();
            want = scan_dijkstra(&net, s_node, t_node, w);
            base_ms += (port_now_ns() - t0) / 1e6;
            mism += fabs(want - r2.cost) > 1e-6 * (1 + want);
            net_route_free(&r2);
        }
        net_route_free(&r);
    }
    qsort(q_ms, (size_t)nq, sizeof q_ms[0], cmp_double);
    qsort(q_cpu, (size_t)nq, sizeof q_cpu[0], cmp_double);
    printf("  route query (snap, end pieces, Dijkstra, W %g), %d random pairs: wall median %.3f ms, p95 %.3f ms;"
           " thread CPU median %.3f ms, p95 %.3f ms\n", w, nq, q_ms[nq / 2], q_ms[nq * 95 / 100], q_cpu[nq / 2],
           q_cpu[nq * 95 / 100]);
    printf("  baseline: node-scan Dijkstra      %.3f ms a query (%d queries, %d cost mismatches), ratio %.0fx\n",
           base_ms / nbase, nbase, mism, base_ms / nbase / q_ms[nq / 2]);
    net_free(&net);
    plx_engine_free(e);
    return mism != 0;
}
