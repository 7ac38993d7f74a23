/* network: street lines joined at shared vertices, scored edges, Dijkstra. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "network.h"

#define NONE UINT32_MAX

/* ---- building the graph --------------------------------------------------- */

typedef struct vslot {
    double x, y;
    uint32_t count, node; /* count 0: empty slot */
} vslot;

static uint64_t pos_hash(double x, double y)
{
    uint64_t a, b;
    x += 0.0; /* -0 and +0 are one position */
    y += 0.0;
    memcpy(&a, &x, sizeof a);
    memcpy(&b, &y, sizeof b);
    a ^= b * 0x9E3779B97F4A7C15ull;
    a ^= a >> 29;
    a *= 0xBF58476D1CE4E5B9ull;
    return a ^ (a >> 32);
}

static vslot *slot_of(vslot *t, size_t mask, double x, double y)
{
    size_t i = (size_t)pos_hash(x, y) & mask;
    while (t[i].count && !(t[i].x == x && t[i].y == y))
        i = (i + 1) & mask;
    return &t[i];
}

static int is_node(const route_line *l, uint32_t k, const vslot *s)
{
    return k == 0 || k + 1 == l->n || s->count > 1;
}

static double piece_length(const double *xy, uint32_t n)
{
    double len = 0;
    uint32_t k;
    for (k = 0; k + 1 < n; k++)
        len += hypot(xy[2 * k + 2] - xy[2 * k], xy[2 * k + 3] - xy[2 * k + 1]);
    return len;
}

/* Counts the vertices at each position, then numbers the nodes in the order
 * the lines first reach them. */
static int number_nodes(network *net, vslot *t, size_t mask)
{
    size_t i;
    uint32_t k;
    for (i = 0; i < net->lines.n; i++) {
        const route_line *l = &net->lines.lines[i];
        for (k = 0; k < l->n; k++) {
            vslot *s = slot_of(t, mask, l->xy[2 * k] + 0.0, l->xy[2 * k + 1] + 0.0);
            if (!s->count) {
                s->x = l->xy[2 * k] + 0.0;
                s->y = l->xy[2 * k + 1] + 0.0;
                s->node = NONE;
            }
            s->count++;
        }
    }
    for (i = 0; i < net->lines.n; i++) {
        const route_line *l = &net->lines.lines[i];
        for (k = 0; k < l->n; k++) {
            vslot *s = slot_of(t, mask, l->xy[2 * k] + 0.0, l->xy[2 * k + 1] + 0.0);
            if (is_node(l, k, s) && s->node == NONE)
                s->node = net->nnodes++;
        }
    }
    net->node_xy = malloc(sizeof *net->node_xy * 2 * (net->nnodes + 2));
    if (!net->node_xy)
        return -1;
    for (i = 0; i <= mask; i++)
        if (t[i].count && t[i].node != NONE) {
            net->node_xy[2 * t[i].node] = t[i].x;
            net->node_xy[2 * t[i].node + 1] = t[i].y;
        }
    return 0;
}

/* Cuts each line at its nodes into edges. */
static int cut_edges(network *net, vslot *t, size_t mask, size_t nvert)
{
    size_t i;
    net->edges = calloc(nvert, sizeof *net->edges);
    if (!net->edges)
        return -1;
    for (i = 0; i < net->lines.n; i++) {
        const route_line *l = &net->lines.lines[i];
        uint32_t k, last = 0, last_node = NONE;
        for (k = 0; k < l->n; k++) {
            vslot *s = slot_of(t, mask, l->xy[2 * k] + 0.0, l->xy[2 * k + 1] + 0.0);
            if (!is_node(l, k, s))
                continue;
            if (last_node != NONE) {
                net_edge *ed = &net->edges[net->nedges++];
                ed->a = last_node;
                ed->b = s->node;
                ed->line = (uint32_t)i;
                ed->v0 = last;
                ed->v1 = k;
                ed->length = piece_length(l->xy + 2 * last, k - last + 1);
            }
            last = k;
            last_node = s->node;
        }
    }
    return 0;
}

static int build_adjacency(network *net)
{
    uint32_t i, *fill;
    net->adj_first = calloc((size_t)net->nnodes + 1, sizeof *net->adj_first);
    net->adj = malloc(sizeof *net->adj * 2 * ((size_t)net->nedges + 1));
    fill = calloc((size_t)net->nnodes + 1, sizeof *fill);
    if (!net->adj_first || !net->adj || !fill) {
        free(fill);
        return -1;
    }
    for (i = 0; i < net->nedges; i++) {
        net->adj_first[net->edges[i].a + 1]++;
        net->adj_first[net->edges[i].b + 1]++;
    }
    for (i = 0; i < net->nnodes; i++)
        net->adj_first[i + 1] += net->adj_first[i];
    for (i = 0; i < net->nedges; i++) {
        uint32_t a = net->edges[i].a, b = net->edges[i].b;
        net->adj[net->adj_first[a] + fill[a]++] = i;
        net->adj[net->adj_first[b] + fill[b]++] = i;
    }
    free(fill);
    return 0;
}

static int alloc_search(network *net)
{
    size_t n = (size_t)net->nnodes + 2;
    net->heap_cap = 2 * ((size_t)net->nedges + 8) + n;
    net->dist = malloc(sizeof *net->dist * n);
    net->prev = malloc(sizeof *net->prev * n);
    net->heap = malloc(2 * sizeof(double) * net->heap_cap);
    net->scored = calloc((size_t)net->nedges + 1, 1);
    return net->dist && net->prev && net->heap && net->scored ? 0 : -1;
}

int net_build(network *net, route_set *lines, char *err, size_t errlen)
{
    size_t nvert = 0, cap = 16, i;
    vslot *t;
    int rc;
    memset(net, 0, sizeof *net);
    net->lines = *lines;
    memset(lines, 0, sizeof *lines);
    for (i = 0; i < net->lines.n; i++)
        nvert += net->lines.lines[i].n;
    while (cap < 2 * nvert)
        cap *= 2;
    t = calloc(cap, sizeof *t);
    rc = t ? number_nodes(net, t, cap - 1) : -1;
    if (rc == 0)
        rc = cut_edges(net, t, cap - 1, nvert);
    free(t);
    if (rc == 0)
        rc = build_adjacency(net);
    if (rc == 0)
        rc = alloc_search(net);
    if (rc != 0) {
        snprintf(err, errlen, "out of memory for a network of %zu vertices", nvert);
        net_free(net);
        return -1;
    }
    return 0;
}

#define NET_CHUNK 4       /* edges a thread scores at a time */
#define NET_MIN_EDGES 16  /* fewer edges: on the engine alone (a bake's edge costs about 4 ms, its twin some 30) */

typedef struct score_job {
    network *net;
    const uint32_t *list;  /* the edges to score (NULL: every edge, in order) */
    int progress;          /* on a terminal: the share done, in steps of 5% */
    uint32_t shown;
} score_job;

/* Edges list[k0 .. k1) (or k0 .. k1) scored with engine e. */
static plx_status score_edges(void *arg, plx_engine *e, size_t k0, size_t k1)
{
    score_job *j = arg;
    network *net = j->net;
    size_t k;
    for (k = k0; k < k1; k++) {
        size_t i = j->list ? j->list[k] : k;
        net_edge *ed = &net->edges[i];
        const route_line *l = &net->lines.lines[ed->line];
        plx_status st = plx_route_score(e, l->xy + 2 * ed->v0, ed->v1 - ed->v0 + 1, net->step, net->dark_lux,
                                        &ed->s, NULL);
        if (st == PLX_OK)
            st = plx_route_facial(e, l->xy + 2 * ed->v0, ed->v1 - ed->v0 + 1, net->step, net->height, NULL,
                                  ed->fac);
        if (st != PLX_OK)
            return st;
        ed->dark = ed->s.dark_share * ed->s.length;
        net->scored[i] = 1;
    }
    return PLX_OK;
}

static void score_progress(void *arg, size_t done, size_t n)
{
    score_job *j = arg;
    if (j->progress && done * 20u / n > j->shown) {
        j->shown = (uint32_t)(done * 20u / n);
        fprintf(stderr, "\rscoring edges: %3u%%", j->shown * 5);
    }
}

/* The n edges of list (NULL: every edge) scored on e and tg's twins. */
static plx_status score_list(network *net, plx_engine *e, twin_set *tg, const uint32_t *list, size_t n,
                             int progress, plx_engine **failed)
{
    score_job j;
    twin_work w;
    plx_status st;
    j.net = net;
    j.list = list;
    j.progress = progress && isatty(2);
    j.shown = 0;
    memset(&w, 0, sizeof w);
    w.n = n;
    w.chunk = NET_CHUNK;
    w.min_items = NET_MIN_EDGES;
    w.fn = score_edges;
    w.arg = &j;
    w.progress = score_progress;
    *failed = e;
    st = n > 0 ? twin_for(tg, e, &w, failed) : PLX_OK;
    if (j.progress && j.shown)
        fprintf(stderr, "\n");
    return st;
}

void net_set_scoring(network *net, double step, double dark_lux, double height)
{
    net->step = step;
    net->dark_lux = dark_lux;
    net->height = height;
}

plx_status net_score(network *net, plx_engine *e, twin_set *tg, double step, double dark_lux, double height,
                     int progress, plx_engine **failed)
{
    net_set_scoring(net, step, dark_lux, height);
    net->partial = 0;
    return score_list(net, e, tg, NULL, net->nedges, progress, failed);
}

void net_free(network *net)
{
    route_free(&net->lines);
    free(net->node_xy);
    free(net->edges);
    free(net->adj_first);
    free(net->adj);
    free(net->dist);
    free(net->prev);
    free(net->heap);
    free(net->scored);
    memset(net, 0, sizeof *net);
}

/* ---- snapping --------------------------------------------------------------- */

int net_snap_point(const network *net, double x, double y, net_snap *out)
{
    uint32_t i, k;
    double best = INFINITY;
    if (net->nedges == 0)
        return -1;
    for (i = 0; i < net->nedges; i++) {
        const net_edge *ed = &net->edges[i];
        const double *xy = net->lines.lines[ed->line].xy + 2 * ed->v0;
        for (k = 0; k < ed->v1 - ed->v0; k++) {
            double ax = xy[2 * k], ay = xy[2 * k + 1], dx = xy[2 * k + 2] - ax, dy = xy[2 * k + 3] - ay;
            double l2 = dx * dx + dy * dy, t = l2 > 0 ? ((x - ax) * dx + (y - ay) * dy) / l2 : 0.0, px, py, d;
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            px = ax + t * dx;
            py = ay + t * dy;
            d = hypot(x - px, y - py);
            if (d < best) {
                best = d;
                out->edge = i;
                out->seg = k;
                out->x = px;
                out->y = py;
                out->dist = d;
            }
        }
    }
    return 0;
}

/* ---- search ------------------------------------------------------------------ */

/* An edge the search can walk: a real one or a piece from a snapped point. */
typedef struct walk_edge {
    uint32_t u, v;
    double cost, length, dark;
    plx_route_stats s;
    double fac[4];
    double *xy; /* pieces only: their polyline from u to v */
    uint32_t n;
} walk_edge;

typedef struct query {
    walk_edge piece[5];
    uint32_t npiece;
    uint32_t S, T;
} query;

static double edge_cost(double length, double dark, const plx_route_stats *s, double weight)
{
    return length + weight * (dark + s->blocked_length);
}

/* The piece of edge 'ed' from a snapped point (x, y) on segment seg to the
 * vertex v0 (toward = 0) or v1 (toward = 1), or to another snapped point. */
static int make_piece(network *net, plx_engine *e, const net_snap *p, const net_snap *q, int toward, double weight,
                      walk_edge *w, uint32_t u, uint32_t v)
{
    const net_edge *ed = &net->edges[p->edge];
    const double *lxy = net->lines.lines[ed->line].xy + 2 * ed->v0;
    uint32_t n = 0, k, cap = ed->v1 - ed->v0 + 3;
    plx_status st;
    w->xy = malloc(sizeof *w->xy * 2 * cap);
    if (!w->xy)
        return -1;
    w->xy[n * 2] = p->x;
    w->xy[n++ * 2 + 1] = p->y;
    if (q) { /* p and q on one edge, p first along it */
        for (k = p->seg + 1; k <= q->seg; k++) {
            w->xy[2 * n] = lxy[2 * k];
            w->xy[2 * n++ + 1] = lxy[2 * k + 1];
        }
        w->xy[2 * n] = q->x;
        w->xy[2 * n++ + 1] = q->y;
    } else if (toward == 0) {
        for (k = p->seg + 1; k-- > 0;) {
            w->xy[2 * n] = lxy[2 * k];
            w->xy[2 * n++ + 1] = lxy[2 * k + 1];
        }
    } else {
        for (k = p->seg + 1; k <= ed->v1 - ed->v0; k++) {
            w->xy[2 * n] = lxy[2 * k];
            w->xy[2 * n++ + 1] = lxy[2 * k + 1];
        }
    }
    w->n = n;
    w->u = u;
    w->v = v;
    st = plx_route_score(e, w->xy, n, net->step, net->dark_lux, &w->s, NULL);
    if (st == PLX_OK)
        st = plx_route_facial(e, w->xy, n, net->step, net->height, NULL, w->fac);
    if (st != PLX_OK)
        return -1;
    w->length = piece_length(w->xy, n);
    w->dark = w->s.dark_share * w->s.length;
    w->cost = edge_cost(w->length, w->dark, &w->s, weight);
    return 0;
}

/* Orders two snapped points along their common edge. */
static int snap_before(const net_snap *a, const net_snap *b, const double *lxy)
{
    if (a->seg != b->seg)
        return a->seg < b->seg;
    return hypot(a->x - lxy[2 * a->seg], a->y - lxy[2 * a->seg + 1]) <=
           hypot(b->x - lxy[2 * b->seg], b->y - lxy[2 * b->seg + 1]);
}

static int make_pieces(network *net, plx_engine *e, const net_snap *a, const net_snap *b, double weight, query *q)
{
    const net_edge *ea = &net->edges[a->edge], *eb = &net->edges[b->edge];
    int rc = 0;
    q->S = net->nnodes;
    q->T = net->nnodes + 1;
    q->npiece = 0;
    rc |= make_piece(net, e, a, NULL, 0, weight, &q->piece[q->npiece++], q->S, ea->a);
    rc |= make_piece(net, e, a, NULL, 1, weight, &q->piece[q->npiece++], q->S, ea->b);
    rc |= make_piece(net, e, b, NULL, 0, weight, &q->piece[q->npiece++], q->T, eb->a);
    rc |= make_piece(net, e, b, NULL, 1, weight, &q->piece[q->npiece++], q->T, eb->b);
    if (a->edge == b->edge) {
        const double *lxy = net->lines.lines[ea->line].xy + 2 * ea->v0;
        if (snap_before(a, b, lxy))
            rc |= make_piece(net, e, a, b, 0, weight, &q->piece[q->npiece++], q->S, q->T);
        else
            rc |= make_piece(net, e, b, a, 0, weight, &q->piece[q->npiece++], q->T, q->S);
    }
    return rc;
}

static void free_pieces(query *q)
{
    uint32_t i;
    for (i = 0; i < q->npiece; i++)
        free(q->piece[i].xy);
}

/* A binary min-heap of nodes keyed by net->dist at push time (lazy),
 * equal keys by node number: the order nodes are settled in, and so the
 * route among routes of equal cost, depends only on their distances, not
 * on which other nodes the search pushed (net_score_route). */
typedef struct hentry {
    double d;
    uint32_t node;
} hentry;

static int hless(double d, uint32_t node, const hentry *b)
{
    return d < b->d || (d == b->d && node < b->node);
}

static void heap_push(hentry *h, size_t *n, double d, uint32_t node)
{
    size_t i = (*n)++;
    while (i > 0 && hless(d, node, &h[(i - 1) / 2])) {
        h[i] = h[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h[i].d = d;
    h[i].node = node;
}

static hentry heap_pop(hentry *h, size_t *n)
{
    hentry top = h[0], last = h[--(*n)];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= *n)
            break;
        if (c + 1 < *n && hless(h[c + 1].d, h[c + 1].node, &h[c]))
            c++;
        if (!hless(h[c].d, h[c].node, &last))
            break;
        h[i] = h[c];
        i = c;
    }
    if (*n > 0)
        h[i] = last;
    return top;
}

/* Edge id x: real edges 0..nedges-1, pieces nedges + j. */
static void relax(network *net, hentry *h, size_t *nh, uint32_t u, uint32_t x, double cost, uint32_t v)
{
    double d = net->dist[u] + cost;
    if (d < net->dist[v]) {
        net->dist[v] = d;
        net->prev[v] = x;
        heap_push(h, nh, d, v);
    }
}

/* From q->S until q->T is settled (every node with all: net->dist, net->prev). */
static void dijkstra(network *net, const query *q, double weight, hentry *h, int all)
{
    uint32_t i, n = net->nnodes + 2;
    size_t nh = 0;
    for (i = 0; i < n; i++) {
        net->dist[i] = INFINITY;
        net->prev[i] = NONE;
    }
    net->dist[q->S] = 0;
    heap_push(h, &nh, 0, q->S);
    while (nh > 0) {
        hentry top = heap_pop(h, &nh);
        uint32_t u = top.node, j;
        if (top.d > net->dist[u])
            continue;
        if (u == q->T && !all)
            break;
        if (u < net->nnodes)
            for (j = net->adj_first[u]; j < net->adj_first[u + 1]; j++) {
                const net_edge *ed = &net->edges[net->adj[j]];
                /* an edge left unscored (net_score_route) is one no route at this weight takes */
                double c = net->scored[net->adj[j]] || weight == 0.0 ? edge_cost(ed->length, ed->dark, &ed->s, weight)
                                                                     : INFINITY;
                relax(net, h, &nh, u, net->adj[j], c, ed->a == u ? ed->b : ed->a);
            }
        for (j = 0; j < q->npiece; j++) {
            const walk_edge *w = &q->piece[j];
            if (w->u == u || w->v == u)
                relax(net, h, &nh, u, net->nedges + j, w->cost, w->u == u ? w->v : w->u);
        }
    }
}

/* Appends an edge's polyline walked from node 'from'. */
static int append_xy(net_route *r, const double *xy, uint32_t n, int reverse)
{
    uint32_t k;
    double *nx = realloc(r->xy, sizeof *nx * 2 * (r->n + n));
    if (!nx)
        return -1;
    r->xy = nx;
    for (k = 0; k < n; k++) {
        uint32_t j = reverse ? n - 1 - k : k;
        if (r->n > 0 && k == 0 && r->xy[2 * r->n - 2] == xy[2 * j] && r->xy[2 * r->n - 1] == xy[2 * j + 1])
            continue;
        r->xy[2 * r->n] = xy[2 * j];
        r->xy[2 * r->n++ + 1] = xy[2 * j + 1];
    }
    return 0;
}

/* fmin ignores a NaN argument: NaN stays only while no edge had a meter. */
static void add_stats(net_route *r, double length, double dark, const plx_route_stats *s, const double fac[4])
{
    r->min_ev = fmin(r->min_ev, fmin(fac[0], fac[1]));
    r->min_esc = fmin(r->min_esc, fmin(fac[2], fac[3]));
    r->length += length;
    r->dark += dark;
    r->blocked += s->blocked_length;
    r->scored += s->length;
    r->integral += s->mean * s->length;
    if (s->length > 0) {
        r->min = fmin(r->min, s->min);
        r->max = fmax(r->max, s->max);
    }
}

/* The node at the other end of edge or piece x from v. */
static uint32_t other_end(const network *net, const query *q, uint32_t x, uint32_t v)
{
    const walk_edge *w = x >= net->nedges ? &q->piece[x - net->nedges] : NULL;
    if (w)
        return w->u == v ? w->v : w->u;
    return net->edges[x].a == v ? net->edges[x].b : net->edges[x].a;
}

/* Walks prev back from T, then the edges forward from S. */
static int collect(network *net, const query *q, net_route *r)
{
    uint32_t count = 0, v = q->T, *path, i;
    while (v != q->S) {
        v = other_end(net, q, net->prev[v], v);
        count++;
    }
    path = malloc(sizeof *path * (count + 1));
    if (!path)
        return -1;
    for (v = q->T, i = count; v != q->S;) {
        uint32_t x = net->prev[v];
        path[--i] = x;
        v = other_end(net, q, x, v);
    }
    for (i = 0, v = q->S; i < count; i++) {
        uint32_t x = path[i];
        int rc;
        if (x >= net->nedges) {
            const walk_edge *w = &q->piece[x - net->nedges];
            rc = append_xy(r, w->xy, w->n, w->u != v);
            add_stats(r, w->length, w->dark, &w->s, w->fac);
        } else {
            const net_edge *ed = &net->edges[x];
            rc = append_xy(r, net->lines.lines[ed->line].xy + 2 * ed->v0, ed->v1 - ed->v0 + 1, ed->a != v);
            add_stats(r, ed->length, ed->dark, &ed->s, ed->fac);
        }
        v = other_end(net, q, x, v);
        if (rc != 0) {
            free(path);
            return -1;
        }
    }
    free(path);
    return 0;
}

static void snap_key(net_snap_key *k, const net_snap *s)
{
    memset(k, 0, sizeof *k);
    k->edge = s->edge;
    k->seg = s->seg;
    k->x = s->x;
    k->y = s->y;
}

static int same_ends(const net_snap_key *k, const net_snap *s)
{
    net_snap_key t;
    snap_key(&t, s);
    return memcmp(k, &t, sizeof t) == 0;
}

int net_route_find(network *net, plx_engine *e, const net_snap *a, const net_snap *b, double weight,
                   net_route *out, char *err, size_t errlen)
{
    query q;
    int rc = 0;
    memset(out, 0, sizeof *out);
    memset(&q, 0, sizeof q);
    out->min = INFINITY;
    out->max = -INFINITY;
    out->min_ev = out->min_esc = NAN;
    if (net->partial && !(weight <= net->part_w && same_ends(&net->part_a, a) && same_ends(&net->part_b, b))) {
        snprintf(err, errlen, "the network's edges were scored for other ends or a lower --dark-weight");
        return -1;
    }
    if (make_pieces(net, e, a, b, weight, &q) != 0) {
        snprintf(err, errlen, "scoring the ends of the route failed: %s", plx_last_error(e));
        free_pieces(&q);
        return -1;
    }
    dijkstra(net, &q, weight, (hentry *)net->heap, 0);
    if (net->dist[q.T] == INFINITY) {
        rc = 1;
    } else if (collect(net, &q, out) != 0) {
        net_route_free(out); /* the polyline as far as it got */
        snprintf(err, errlen, "out of memory for the route");
        rc = -1;
    } else {
        out->cost = net->dist[q.T];
        if (out->scored > 0) {
            double mean = out->integral / out->scored;
            out->p_class_h = plx_p_class(mean, out->min);
            if (out->min_ev == out->min_ev && out->min_esc == out->min_esc)
                out->p_class = plx_p_class_facial(mean, out->min, out->min_ev, out->min_esc);
        } else {
            out->min = out->max = 0;
        }
    }
    free_pieces(&q);
    return rc;
}

/* The edges (not the pieces) of the route net->prev holds from q->T back to
 * q->S into list; their number. */
static size_t path_edges(const network *net, const query *q, uint32_t *list)
{
    uint32_t v = q->T;
    size_t n = 0;
    while (v != q->S) {
        uint32_t x = net->prev[v];
        if (x < net->nedges)
            list[n++] = x;
        v = other_end(net, q, x, v);
    }
    return n;
}

/* That route's cost at weight, its edges scored. */
static double path_cost(const network *net, const query *q, double weight)
{
    uint32_t v = q->T;
    double c = 0.0;
    while (v != q->S) {
        uint32_t x = net->prev[v];
        if (x >= net->nedges) {
            const walk_edge *w = &q->piece[x - net->nedges];
            c += edge_cost(w->length, w->dark, &w->s, weight);
        } else {
            const net_edge *ed = &net->edges[x];
            c += edge_cost(ed->length, ed->dark, &ed->s, weight);
        }
        v = other_end(net, q, x, v);
    }
    return c;
}

/* The unscored edges of list[0 .. n) kept, in order; their number. */
static size_t unscored(const network *net, uint32_t *list, size_t n)
{
    size_t i, m = 0;
    for (i = 0; i < n; i++)
        if (!net->scored[list[i]])
            list[m++] = list[i];
    return m;
}

plx_status net_score_route(network *net, plx_engine *e, twin_set *tg, const net_snap *a, const net_snap *b,
                           double weight, int progress, size_t *nscored, plx_engine **failed)
{
    query q, back;
    uint32_t *list = malloc(sizeof *list * ((size_t)net->nedges + 1)), i;
    double *ds = malloc(sizeof *ds * ((size_t)net->nnodes + 2)), bound;
    size_t n = 0;
    plx_status st = PLX_OK;
    *failed = e;
    *nscored = 0;
    memset(&q, 0, sizeof q);
    net->partial = 1;
    net->part_w = weight;
    snap_key(&net->part_a, a);
    snap_key(&net->part_b, b);
    if (!list || !ds) {
        *failed = NULL;
        st = PLX_E_NOMEM;
        goto done;
    }
    /* the ends' pieces failing to score: net_route_find says so */
    if (make_pieces(net, e, a, b, 0.0, &q) != 0)
        goto done;
    /* the shortest route (no score needed) and every node's length from --from */
    dijkstra(net, &q, 0.0, (hentry *)net->heap, 1);
    if (net->dist[q.T] == INFINITY) /* unconnected: net_route_find says so */
        goto done;
    memcpy(ds, net->dist, sizeof *ds * ((size_t)net->nnodes + 2));
    n = unscored(net, list, path_edges(net, &q, list));
    st = score_list(net, e, tg, list, n, 0, failed);
    *nscored += n;
    if (st != PLX_OK)
        goto done;
    /* no route of a lower weight costs more than the shortest does at this
     * one, and none is longer than its cost: an edge on such a route lies
     * within that length of walking from --from through it to --to (a
     * margin for the sums' rounding) */
    bound = path_cost(net, &q, weight);
    bound += bound * 1e-9 + 1e-6;
    back = q;
    back.S = q.T;
    back.T = q.S;
    dijkstra(net, &back, 0.0, (hentry *)net->heap, 1); /* net->dist: every node's length to --to */
    for (i = 0, n = 0; i < net->nedges; i++) {
        const net_edge *ed = &net->edges[i];
        double via = fmin(ds[ed->a] + ed->length + net->dist[ed->b], ds[ed->b] + ed->length + net->dist[ed->a]);
        if (!net->scored[i] && via <= bound)
            list[n++] = i;
    }
    st = score_list(net, e, tg, list, n, progress, failed);
    *nscored += n;
done:
    free_pieces(&q);
    free(list);
    free(ds);
    return st;
}

/* One test of net_route_capped: the route at weight w, kept in *best (and
 * w in *wbest) when it is within the cap. 1 within, 0 not, -1 failed. */
static int capped_try(network *net, plx_engine *e, const net_snap *a, const net_snap *b, double w, double cap,
                      net_route *best, double *wbest, char *err, size_t errlen)
{
    net_route r;
    int rc = net_route_find(net, e, a, b, w, &r, err, errlen);
    if (rc == 1) /* no route at a lower weight than one that found it: not expected (the weights are bounded
                  * and the shortest route's edges scored), but named if it happens */
        snprintf(err, errlen, "no route at --dark-weight %g while capping the detour", w);
    if (rc != 0)
        return -1;
    if (!(r.length <= cap)) {
        net_route_free(&r);
        return 0;
    }
    net_route_free(best);
    *best = r;
    *wbest = w;
    return 1;
}

int net_route_capped(network *net, plx_engine *e, const net_snap *a, const net_snap *b, double weight, double cap,
                     const net_route *shortest, net_route *out, double *wout, char *err, size_t errlen)
{
    double lo = 0.0, hi = weight, w;
    int k, rc = 0;
    *out = *shortest;
    out->xy = malloc(sizeof *out->xy * 2 * ((size_t)shortest->n + 1));
    if (!out->xy) {
        snprintf(err, errlen, "out of memory while capping the detour");
        return -1;
    }
    memcpy(out->xy, shortest->xy, sizeof *out->xy * 2 * shortest->n);
    *wout = 0.0;
    /* halving from 'weight' down to the first weight within the cap (the
     * feasible weights are an interval from 0, as a route's length never
     * falls as the weight grows), then bisecting between it and the one
     * above to a thousandth of it: the same relative precision at any
     * 'weight' (a step of weight / 1000 from 0 left weights under it at
     * 0, the shortest route, when 'weight' was large) */
    for (k = 0, w = 0.5 * weight; k < NET_CAP_HALVINGS && rc == 0; k++, w *= 0.5) {
        rc = capped_try(net, e, a, b, w, cap, out, wout, err, errlen);
        if (rc == 0)
            hi = w;
        else if (rc == 1)
            lo = w;
    }
    while (rc >= 0 && lo > 0.0 && hi - lo > lo * NET_CAP_PRECISION) {
        w = 0.5 * (lo + hi);
        rc = capped_try(net, e, a, b, w, cap, out, wout, err, errlen);
        if (rc == 0)
            hi = w;
        else if (rc == 1)
            lo = w;
    }
    if (rc < 0) {
        net_route_free(out);
        return -1;
    }
    return 0;
}

void net_route_free(net_route *r)
{
    free(r->xy);
    r->xy = NULL;
    r->n = 0;
}

double net_part_length(const network *net, uint32_t node)
{
    uint32_t *stack = malloc(sizeof *stack * ((size_t)net->nnodes + 1)), top = 0, j;
    unsigned char *seen = calloc((size_t)net->nnodes + 1, 1);
    double len = 0.0;
    if (!stack || !seen || node >= net->nnodes) {
        free(stack);
        free(seen);
        return 0.0;
    }
    seen[node] = 1;
    stack[top++] = node;
    while (top > 0) {
        uint32_t u = stack[--top];
        for (j = net->adj_first[u]; j < net->adj_first[u + 1]; j++) {
            const net_edge *ed = &net->edges[net->adj[j]];
            uint32_t v = ed->a == u ? ed->b : ed->a;
            if (ed->a == u && (ed->b != u || j == net->adj_first[u] || net->adj[j - 1] != net->adj[j]))
                len += ed->length; /* each edge once: from its end a */
            if (!seen[v]) {
                seen[v] = 1;
                stack[top++] = v;
            }
        }
    }
    free(stack);
    free(seen);
    return len;
}

uint32_t net_components(const network *net)
{
    uint32_t *stack = malloc(sizeof *stack * ((size_t)net->nnodes + 1)), i, parts = 0;
    unsigned char *seen = calloc((size_t)net->nnodes + 1, 1);
    if (!stack || !seen) {
        free(stack);
        free(seen);
        return 0;
    }
    for (i = 0; i < net->nnodes; i++) {
        uint32_t top = 0, j;
        if (seen[i])
            continue;
        parts++;
        seen[i] = 1;
        stack[top++] = i;
        while (top > 0) {
            uint32_t u = stack[--top];
            for (j = net->adj_first[u]; j < net->adj_first[u + 1]; j++) {
                const net_edge *ed = &net->edges[net->adj[j]];
                uint32_t v = ed->a == u ? ed->b : ed->a;
                if (!seen[v]) {
                    seen[v] = 1;
                    stack[top++] = v;
                }
            }
        }
    }
    free(stack);
    free(seen);
    return parts;
}
