/* A street network for walking routes: GeoJSON lines joined where they share
 * a vertex, each edge scored once for light, and the best-lit route between
 * two points (Dijkstra on length + weight x dark metres).
 *
 * Nodes are the positions (exact coordinates after projection) where a line
 * ends or that two or more line vertices share; an edge is the piece of a
 * line between two consecutive nodes along it. */
#ifndef PLX_CLI_NETWORK_H
#define PLX_CLI_NETWORK_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "route_io.h"
#include "twin_engines.h"

typedef struct net_edge {
    uint32_t a, b;          /* end nodes (a at vertex v0, b at v1) */
    uint32_t line, v0, v1;  /* the piece: vertices v0..v1 of line */
    double length;          /* geometric length in metres */
    double dark;            /* metres scored below the dark threshold */
    plx_route_stats s;      /* the piece scored as plx_route_score scores a line */
    double fac[4];          /* SPEC §6 at the network's height, as plx_route_facial's total: min E_v
                               facing v0 to v1 (fw), back (bw), min E_sc fw, bw; NaN: no sample */
} net_edge;

/* The ends net_score_route scored a network for (edge, segment, point). */
typedef struct net_snap_key {
    uint32_t edge, seg;
    double x, y;
} net_snap_key;

typedef struct network {
    route_set lines;        /* the source lines (owned) */
    double *node_xy;        /* 2 per node */
    uint32_t nnodes, nedges;
    net_edge *edges;
    uint32_t *adj_first;    /* node i's edges: adj[adj_first[i] .. adj_first[i+1]) */
    uint32_t *adj;
    double step, dark_lux;  /* how the edges were scored */
    double height;          /* the E_v and E_sc meters' height above the street */
    /* search scratch, sized for nnodes + 2 */
    double *dist;
    uint32_t *prev;
    void *heap;             /* heap_cap entries of the search's priority queue */
    size_t heap_cap;
    uint8_t *scored;        /* per edge: scored (net_score, net_score_route) */
    int partial;            /* net_score_route scored only the edges for these ends and weights up to part_w */
    net_snap_key part_a, part_b;
    double part_w;
} network;

/* Builds the graph from lines (taking them over: they are freed by
 * net_free, also on failure). 0, or -1 with a message in err. */
int net_build(network *net, route_set *lines, char *err, size_t errlen);
/* Scores every edge (plx_route_score over the piece, sampled every step
 * metres, and plx_route_facial with its meters 'height' above it);
 * progress on stderr when it is a terminal. The edges are shared out
 * between e and tg's twins (NULL: e alone), the same scores on any number
 * of threads. A plx_status; *failed the engine whose plx_last_error says
 * why. */
plx_status net_score(network *net, plx_engine *e, twin_set *tg, double step, double dark_lux, double height,
                     int progress, plx_engine **failed /* OUT */);
/* How edges are scored (net_score's step, dark_lux and height), for
 * net_score_route. */
void net_set_scoring(network *net, double step, double dark_lux, double height);
void net_free(network *net);

/* A route: its edges and the sums over them. min_ev and min_esc are the
 * minima over its edges facing both ways (NaN: no meter outside a solid);
 * p_class is the SPEC §6 class with every criterion (mean and min E_h, min
 * E_v, min E_sc), p_class_h the class of E_h alone (0: none). */
typedef struct net_route {
    double length, dark, blocked, scored, integral, min, max, cost;
    double min_ev, min_esc;
    int p_class, p_class_h;
    double *xy;            /* the polyline, n vertices, malloc'd */
    uint32_t n;
} net_route;

/* A point snapped onto the network: edge, segment k of the piece and the
 * position on it, at distance 'dist' from the point asked for. */
typedef struct net_snap {
    uint32_t edge, seg;
    double x, y, dist;
} net_snap;

/* The nearest point of the network to (x, y); -1 when there are no edges. */
int net_snap_point(const network *net, double x, double y, net_snap *out);

/* The cheapest route from a to b with cost = length + weight x (dark +
 * blocked metres). The partial edges from the snapped points to the ends of
 * their edges are scored with e. 0 on success, 1 when b cannot be reached
 * from a, -1 when out of memory or scoring failed (message in err). */
int net_route_find(network *net, plx_engine *e, const net_snap *a, const net_snap *b, double weight,
                   net_route *out, char *err, size_t errlen);
void net_route_free(net_route *r);

/* Scores only the edges a route from a to b at any weight up to 'weight'
 * can take (net_set_scoring's settings; e and tg's twins as net_score):
 * the shortest route's, then every edge with a walk from a through it to
 * b no longer than that route's cost at 'weight' (no cheaper route is
 * longer than its cost). The searches after it leave the rest out at
 * weights above 0 and find the routes, and their sums, that scoring every
 * edge gives (equal costs settled by node number). *nscored: the edges
 * scored. A plx_status, *failed as net_score's; unconnected ends, or ends
 * whose pieces fail to score, score nothing and return PLX_OK
 * (net_route_find then says why). Out of memory: PLX_E_NOMEM, *failed
 * NULL. net_route_find then refuses other ends or a higher weight. */
plx_status net_score_route(network *net, plx_engine *e, twin_set *tg, const net_snap *a, const net_snap *b,
                           double weight, int progress, size_t *nscored /* OUT */, plx_engine **failed /* OUT */);

/* The best-lit route from a to b no longer than 'cap' metres, when the
 * route at 'weight' is longer: the route at the largest weight in
 * [0, weight] whose route keeps within the cap (a route's length never
 * falls as the weight grows, so those weights are an interval from 0),
 * found by halving from 'weight' (at most NET_CAP_HALVINGS times, after
 * which the shortest route, weight 0, is taken) and then bisecting to
 * NET_CAP_PRECISION of the weight found. *out (net_route_free) and *wout
 * the weight; 'shortest' is the route at weight 0, copied when no weight
 * above 0 keeps within the cap (in practice never: at a weight small
 * enough the route is a shortest one). 0, or -1 with a message in err
 * (*wout then undefined). */
#define NET_CAP_HALVINGS 60
#define NET_CAP_PRECISION 1e-3
int net_route_capped(network *net, plx_engine *e, const net_snap *a, const net_snap *b, double weight, double cap,
                     const net_route *shortest, net_route *out /* OUT */, double *wout /* OUT */, char *err,
                     size_t errlen);

/* The number of connected parts of the network (for messages). */
uint32_t net_components(const network *net);
/* The length (m) of the streets of the part of the network node lies on. */
double net_part_length(const network *net, uint32_t node);

#endif
