/* lit_union: the exact union of a lamp's lit ground rings (interior-
 * disjoint counter-clockwise rings that share edges or parts of edges).
 * Vertices within a tolerance are one; every edge is split at the vertices
 * lying on it; an edge and its reverse cancel (shared boundary); what is
 * left is chained into rings, outer rings counter-clockwise and holes
 * clockwise, each hole given to the smallest outer ring around it. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lit_union.h"

typedef struct uedge {
    size_t a, b;
    int dead;
} uedge;

typedef struct ubuild {
    double *v;          /* vertices, x,y */
    size_t nv;
    uedge *e;
    size_t ne, cap;
    double tol;
} ubuild;

static size_t vertex_id(ubuild *u, double x, double y)
{
    size_t i;
    for (i = 0; i < u->nv; i++)
        if (fabs(u->v[2 * i] - x) <= u->tol && fabs(u->v[2 * i + 1] - y) <= u->tol)
            return i;
    u->v[2 * u->nv] = x;
    u->v[2 * u->nv + 1] = y;
    return u->nv++;
}

static int push_edge(ubuild *u, size_t a, size_t b)
{
    if (a == b)
        return 0;
    if (u->ne == u->cap) {
        size_t nc = u->cap ? 2 * u->cap : 256;
        uedge *ne = realloc(u->e, nc * sizeof *ne);
        if (!ne)
            return -1;
        u->e = ne;
        u->cap = nc;
    }
    u->e[u->ne].a = a;
    u->e[u->ne].b = b;
    u->e[u->ne++].dead = 0;
    return 0;
}

/* Parameter of vertex p on edge a-b when it lies on its inside, else -1. */
static double on_edge(const ubuild *u, size_t a, size_t b, size_t p)
{
    const double *A = u->v + 2 * a, *B = u->v + 2 * b, *P = u->v + 2 * p;
    double dx = B[0] - A[0], dy = B[1] - A[1], l2 = dx * dx + dy * dy, t, cx, cy;
    if (p == a || p == b || !(l2 > 0))
        return -1;
    t = ((P[0] - A[0]) * dx + (P[1] - A[1]) * dy) / l2;
    if (!(t > 0 && t < 1))
        return -1;
    cx = A[0] + t * dx - P[0];
    cy = A[1] + t * dy - P[1];
    return cx * cx + cy * cy <= u->tol * u->tol ? t : -1;
}

typedef struct tpt {
    double t;
    size_t p;
} tpt;

static int cmp_tpt(const void *x, const void *y)
{
    const tpt *a = x, *b = y;
    return (a->t > b->t) - (a->t < b->t);
}

/* Adds edge a-b split at every vertex on it. */
static int add_split(ubuild *u, size_t a, size_t b, tpt *tmp)
{
    size_t p, n = 0, k, prev = a;
    for (p = 0; p < u->nv; p++) {
        double t = on_edge(u, a, b, p);
        if (t > 0) {
            tmp[n].t = t;
            tmp[n++].p = p;
        }
    }
    qsort(tmp, n, sizeof *tmp, cmp_tpt);
    for (k = 0; k < n; k++) {
        if (push_edge(u, prev, tmp[k].p) != 0)
            return -1;
        prev = tmp[k].p;
    }
    return push_edge(u, prev, b);
}

static int cmp_edge(const void *x, const void *y)
{
    const uedge *a = x, *b = y;
    size_t a0 = a->a < a->b ? a->a : a->b, a1 = a->a ^ a->b ^ a0, b0 = b->a < b->b ? b->a : b->b, b1 = b->a ^ b->b ^ b0;
    if (a0 != b0)
        return a0 < b0 ? -1 : 1;
    return (a1 > b1) - (a1 < b1);
}

/* Cancels every edge against a reverse copy (same undirected edge). */
static void cancel(ubuild *u)
{
    size_t i, j;
    qsort(u->e, u->ne, sizeof *u->e, cmp_edge);
    for (i = 0; i < u->ne; i = j) {
        size_t k, m;
        for (j = i + 1; j < u->ne && cmp_edge(&u->e[i], &u->e[j]) == 0; j++)
            ;
        for (k = i; k < j; k++)
            for (m = k + 1; m < j && !u->e[k].dead; m++)
                if (!u->e[m].dead && u->e[m].a == u->e[k].b && u->e[m].b == u->e[k].a)
                    u->e[k].dead = u->e[m].dead = 1;
    }
}

/* Clockwise angle from direction (ux, uy) to (wx, wy), in (0, 2 pi]. */
static double cw_angle(double ux, double uy, double wx, double wy)
{
    double a = atan2(ux * wy - uy * wx, ux * wx + uy * wy); /* ccw, in (-pi, pi] */
    double cw = -a;
    return cw <= 0 ? cw + 2 * 3.14159265358979323846 : cw;
}

/* The live edge out of vertex v that comes first turning clockwise from the
 * reverse of the edge arriving along (dx, dy): the face on the left goes on. */
static long next_edge(const ubuild *u, size_t v, double dx, double dy)
{
    size_t i;
    long best = -1;
    double ba = 1e300;
    for (i = 0; i < u->ne; i++) {
        const uedge *e = &u->e[i];
        double wx, wy, a;
        if (e->dead || e->a != v)
            continue;
        wx = u->v[2 * e->b] - u->v[2 * v];
        wy = u->v[2 * e->b + 1] - u->v[2 * v + 1];
        a = cw_angle(-dx, -dy, wx, wy);
        if (a < ba) {
            ba = a;
            best = (long)i;
        }
    }
    return best;
}

static double ring_area(const double *xy, size_t n)
{
    double s = 0;
    size_t i;
    for (i = 0; i < n; i++) {
        size_t j = (i + 1) % n;
        s += xy[2 * i] * xy[2 * j + 1] - xy[2 * j] * xy[2 * i + 1];
    }
    return 0.5 * s;
}

static int add_ring(lit_union *out, const double *xy, size_t n)
{
    lu_ring *nr = realloc(out->rings, (out->nrings + 1) * sizeof *nr);
    if (!nr)
        return -1;
    out->rings = nr;
    nr[out->nrings].xy = malloc(sizeof *xy * 2 * n);
    if (!nr[out->nrings].xy)
        return -1;
    memcpy(nr[out->nrings].xy, xy, sizeof *xy * 2 * n);
    nr[out->nrings].n = n;
    nr[out->nrings].area = ring_area(xy, n);
    nr[out->nrings].outer = -1;
    out->nrings++;
    return 0;
}

/* Chains the live edges into rings. */
static int chain(ubuild *u, lit_union *out)
{
    double *xy = malloc(sizeof *xy * 2 * (u->ne + 1));
    size_t i;
    if (!xy)
        return -1;
    for (i = 0; i < u->ne; i++) {
        size_t n = 0, start = u->e[i].a;
        long k = (long)i;
        if (u->e[i].dead)
            continue;
        while (k >= 0) {
            uedge *e = &u->e[k];
            e->dead = 1;
            xy[2 * n] = u->v[2 * e->a];
            xy[2 * n + 1] = u->v[2 * e->a + 1];
            n++;
            if (e->b == start)
                break;
            k = next_edge(u, e->b, u->v[2 * e->b] - u->v[2 * e->a], u->v[2 * e->b + 1] - u->v[2 * e->a + 1]);
        }
        if (n >= 3 && add_ring(out, xy, n) != 0) {
            free(xy);
            return -1;
        }
    }
    free(xy);
    return 0;
}

static int inside(const lu_ring *r, double x, double y)
{
    size_t i, j;
    int in = 0;
    for (i = 0, j = r->n - 1; i < r->n; j = i++) {
        double xi = r->xy[2 * i], yi = r->xy[2 * i + 1], xj = r->xy[2 * j], yj = r->xy[2 * j + 1];
        if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi)
            in = !in;
    }
    return in;
}

/* Each hole's outer ring: the smallest one holding its first edge's middle. */
static void assign_holes(lit_union *out)
{
    size_t h, o;
    for (h = 0; h < out->nrings; h++) {
        lu_ring *r = &out->rings[h];
        double mx, my, best = 1e300;
        if (r->area > 0)
            continue;
        mx = 0.5 * (r->xy[0] + r->xy[2]);
        my = 0.5 * (r->xy[1] + r->xy[3]);
        for (o = 0; o < out->nrings; o++)
            if (out->rings[o].area > 0 && out->rings[o].area < best && inside(&out->rings[o], mx, my)) {
                best = out->rings[o].area;
                r->outer = (long)o;
            }
    }
}

int lit_union_build(const double *const *rings, const uint32_t *counts, size_t nrings, lit_union *out)
{
    ubuild u;
    size_t r, i, total = 0, first;
    double scale = 1.0;
    tpt *tmp;
    int rc = 0;
    memset(out, 0, sizeof *out);
    memset(&u, 0, sizeof u);
    for (r = 0; r < nrings; r++)
        for (i = 0; i < counts[r]; i++, total++)
            scale = fmax(scale, fmax(fabs(rings[r][2 * i]), fabs(rings[r][2 * i + 1])));
    u.tol = 1e-9 * scale;
    u.v = malloc(sizeof *u.v * 2 * (total + 1));
    tmp = malloc(sizeof *tmp * (total + 1));
    if (!u.v || !tmp) {
        free(u.v);
        free(tmp);
        return -1;
    }
    /* all vertices first, so every edge is split at all of them */
    for (r = 0; r < nrings; r++)
        for (i = 0; i < counts[r]; i++)
            vertex_id(&u, rings[r][2 * i], rings[r][2 * i + 1]);
    for (r = 0; r < nrings && rc == 0; r++) {
        first = u.ne;
        for (i = 0; i < counts[r] && rc == 0; i++) {
            size_t j = (i + 1) % counts[r];
            rc = add_split(&u, vertex_id(&u, rings[r][2 * i], rings[r][2 * i + 1]),
                           vertex_id(&u, rings[r][2 * j], rings[r][2 * j + 1]), tmp);
        }
        (void)first;
    }
    if (rc == 0) {
        cancel(&u);
        rc = chain(&u, out);
    }
    if (rc == 0)
        assign_holes(out);
    free(u.v);
    free(u.e);
    free(tmp);
    if (rc != 0)
        lit_union_free(out);
    return rc;
}

void lit_union_free(lit_union *u)
{
    size_t i;
    for (i = 0; i < u->nrings; i++)
        free(u->rings[i].xy);
    free(u->rings);
    memset(u, 0, sizeof *u);
}
