/* polar: quadrant polar diagrams as trapezoidal subdivisions (see polar.h).
 *
 * Construction, per subdivision: wall pieces are inserted in a random order
 * (fixed seed) into a trapezoidal map with a search DAG (randomized
 * incremental construction in the manner of Seidel 1991 / Mulmuley, as
 * taught in de Berg et al., "Computational Geometry", ch. 6), in a frame
 * where the axes are "vertical" and points are ordered lexicographically by
 * (u, v). Then every trapezoid learns whether it is solid by counting the
 * footprints above its floor wall.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "polar.h"
#include "geom.h"

enum { UL = 0, LL = 1, UR = 2, LR = 3 };
/* search nodes: a leaf, a point (x) test, a segment (y) test whose frame-left
 * end is seg.a (N_Y) or seg.b (N_YB) */
enum { N_LEAF = 0, N_X = 1, N_Y = 2, N_YB = 3 };
#define KIND(w) ((w) >> 30)
#define IDX(w) ((w) & 0x3fffffffu)
#define PACK(k, i) (((uint32_t)(k) << 30) | (uint32_t)(i))

/* ---- frames and small helpers ----------------------------------------- */

vec2 polar_to_frame(int frame, vec2 w)
{
    vec2 f;
    if (frame == 0) {
        f.x = w.y;
        f.y = -w.x;
    } else {
        f = w;
    }
    return f;
}

vec2 polar_from_frame(int frame, vec2 f)
{
    vec2 w;
    if (frame == 0) {
        w.x = -f.y;
        w.y = f.x;
    } else {
        w = f;
    }
    return w;
}

vec2 polar_fpt(const polar *pd, int frame, uint32_t i)
{
    return polar_to_frame(frame, pd->pts[i]);
}

static int lex_cmp(vec2 a, vec2 b)
{
    if (a.x < b.x)
        return -1;
    if (a.x > b.x)
        return 1;
    if (a.y < b.y)
        return -1;
    if (a.y > b.y)
        return 1;
    return 0;
}

/* Left and right end (frame order) of segment s. */
static void seg_ends(const polar *pd, int frame, uint32_t s, uint32_t *l, uint32_t *r)
{
    const polar_seg *g = &pd->seg[s];
    if (lex_cmp(polar_fpt(pd, frame, g->a), polar_fpt(pd, frame, g->b)) < 0) {
        *l = g->a;
        *r = g->b;
    } else {
        *l = g->b;
        *r = g->a;
    }
}

/* Footprints entered when crossing segment s upwards in the frame. */
static int32_t seg_delta(const polar *pd, int frame, uint32_t s)
{
    const polar_seg *g = &pd->seg[s];
    int fwd = lex_cmp(polar_fpt(pd, frame, g->a), polar_fpt(pd, frame, g->b)) < 0;
    return fwd ? g->cover : -g->cover;
}

static uint32_t rng_next(uint64_t *st)
{
    uint64_t x = *st;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *st = x;
    return (uint32_t)(x >> 32);
}

/* ---- wall pieces ------------------------------------------------------- */

typedef struct split {
    uint32_t seg;   /* original edge index */
    uint32_t pt;    /* point index */
} split;

typedef struct edges {
    uint32_t n;           /* original edges */
    uint32_t *a, *b;      /* point indices */
    int32_t *bld;
    uint32_t *first;      /* per occluder building: first edge */
    uint32_t *count;
} edges;

static int is_occluder(const scene_building *b)
{
    return b->min_height <= 0.0;
}

/* Counts the edges of the occluders. */
static uint32_t count_edges(const scene *s)
{
    uint32_t i, r, n = 0;
    for (i = 0; i < s->nbld; i++) {
        if (!is_occluder(&s->bld[i]))
            continue;
        for (r = 0; r < s->bld[i].ring_count; r++)
            n += s->rings[s->bld[i].ring_first + r].count;
    }
    return n;
}

static void fill_edges(const scene *s, edges *e)
{
    uint32_t i, r, k, n = 0;
    for (i = 0; i < s->nbld; i++) {
        e->first[i] = n;
        e->count[i] = 0;
        if (!is_occluder(&s->bld[i]))
            continue;
        for (r = 0; r < s->bld[i].ring_count; r++) {
            const scene_ring *g = &s->rings[s->bld[i].ring_first + r];
            for (k = 0; k < g->count; k++) {
                e->a[n] = g->first + k;
                e->b[n] = g->first + (k + 1) % g->count;
                e->bld[n] = (int32_t)i;
                n++;
            }
        }
        e->count[i] = n - e->first[i];
    }
    e->n = n;
}

/* Is c strictly inside segment ab, knowing the three are collinear? */
static int strictly_between(vec2 a, vec2 b, vec2 c)
{
    int ca = lex_cmp(c, a), cb = lex_cmp(c, b);
    return ca != 0 && cb != 0 && ca != cb;
}

typedef struct split_ctx {
    polar *pd;
    const edges *e;
    split *sp;        /* NULL: count only */
    uint32_t nsp;
    uint32_t npts;    /* next free point index */
    uint32_t cap_pts;
} split_ctx;

static void add_split(split_ctx *c, uint32_t seg, uint32_t pt)
{
    if (c->sp) {
        c->sp[c->nsp].seg = seg;
        c->sp[c->nsp].pt = pt;
    }
    c->nsp++;
}

static uint32_t add_point(split_ctx *c, vec2 p)
{
    uint32_t i = c->npts++;
    if (c->sp && i < c->cap_pts)
        c->pd->pts[i] = p;
    return i;
}

static vec2 cross_point(vec2 a, vec2 b, vec2 c, vec2 d)
{
    double rx = b.x - a.x, ry = b.y - a.y, sx = d.x - c.x, sy = d.y - c.y;
    double den = rx * sy - ry * sx;
    double t = ((c.x - a.x) * sy - (c.y - a.y) * sx) / den;
    vec2 p;
    if (t < 0.0)
        t = 0.0;
    if (t > 1.0)
        t = 1.0;
    p.x = a.x + t * rx;
    p.y = a.y + t * ry;
    return p;
}

/* Records where edges i and j (of different buildings) must be cut. */
static void meet_edges(split_ctx *c, uint32_t i, uint32_t j)
{
    const vec2 *P = c->pd->pts;
    uint32_t ia = c->e->a[i], ib = c->e->b[i], ja = c->e->a[j], jb = c->e->b[j];
    vec2 a = P[ia], b = P[ib], d0 = P[ja], d1 = P[jb];
    int m;
    if (fmax(a.x, b.x) < fmin(d0.x, d1.x) || fmax(d0.x, d1.x) < fmin(a.x, b.x) ||
        fmax(a.y, b.y) < fmin(d0.y, d1.y) || fmax(d0.y, d1.y) < fmin(a.y, b.y))
        return;
    m = geom_seg_meet(a, b, d0, d1);
    if (m == GEOM_SEG_DISJOINT)
        return;
    if (m == GEOM_SEG_CROSS) {
        uint32_t x = add_point(c, cross_point(a, b, d0, d1));
        add_split(c, i, x);
        add_split(c, j, x);
        return;
    }
    /* touch or overlap: cut each at the other's ends lying inside it */
    if (geom_orient(a, b, d0) == 0 && strictly_between(a, b, d0))
        add_split(c, i, ja);
    if (geom_orient(a, b, d1) == 0 && strictly_between(a, b, d1))
        add_split(c, i, jb);
    if (geom_orient(d0, d1, a) == 0 && strictly_between(d0, d1, a))
        add_split(c, j, ia);
    if (geom_orient(d0, d1, b) == 0 && strictly_between(d0, d1, b))
        add_split(c, j, ib);
}

static void meet_buildings(split_ctx *c, uint32_t p, uint32_t q)
{
    const edges *e = c->e;
    uint32_t i, j;
    for (i = e->first[p]; i < e->first[p] + e->count[p]; i++)
        for (j = e->first[q]; j < e->first[q] + e->count[q]; j++)
            meet_edges(c, i, j);
}

/* qsort has no context argument: sort (minx, index) pairs instead. */
typedef struct keyed {
    double key;
    uint32_t idx;
} keyed;

static int cmp_keyed(const void *x, const void *y)
{
    const keyed *a = x, *b = y;
    if (a->key != b->key)
        return (a->key > b->key) - (a->key < b->key);
    return (a->idx > b->idx) - (a->idx < b->idx);
}

/* Sweep over x of building boxes: every pair of occluders whose closed
 * boxes meet has its edges compared. */
static void find_contacts(split_ctx *c, const scene *s, keyed *order, uint32_t nocc,
                          uint32_t *active)
{
    uint32_t i, k, nact = 0;
    for (i = 0; i < nocc; i++) {
        uint32_t b = order[i].idx, w = 0;
        const double *bb = s->bld[b].box;
        for (k = 0; k < nact; k++) {
            const double *ab = s->bld[active[k]].box;
            if (ab[2] < bb[0])
                continue;        /* ends before: drop */
            active[w++] = active[k];
            if (ab[1] <= bb[3] && bb[1] <= ab[3])
                meet_buildings(c, active[k], b);
        }
        nact = w;
        active[nact++] = b;
    }
}

static int cmp_split(const void *x, const void *y)
{
    const split *a = x, *b = y;
    return (a->seg > b->seg) - (a->seg < b->seg);
}

typedef struct piece {
    uint32_t a, b;   /* point indices, oriented as the original edge */
    int32_t bld;
    uint32_t lo, hi; /* lex-min, lex-max ends, for merging */
} piece;

static int cmp_piece_pts(const piece *a, const piece *b, const vec2 *P)
{
    int c = lex_cmp(P[a->lo], P[b->lo]);
    if (c)
        return c;
    return lex_cmp(P[a->hi], P[b->hi]);
}

/* Heap sort of pieces by their ends (qsort cannot see the points). */
static void sift(piece *v, uint32_t i, uint32_t n, const vec2 *P)
{
    for (;;) {
        uint32_t c = 2 * i + 1, m = i;
        piece t;
        if (c < n && cmp_piece_pts(&v[c], &v[m], P) > 0)
            m = c;
        if (c + 1 < n && cmp_piece_pts(&v[c + 1], &v[m], P) > 0)
            m = c + 1;
        if (m == i)
            return;
        t = v[i];
        v[i] = v[m];
        v[m] = t;
        i = m;
    }
}

static void sort_pieces(piece *v, uint32_t n, const vec2 *P)
{
    uint32_t i;
    if (n < 2)
        return;
    for (i = n / 2; i-- > 0;)
        sift(v, i, n, P);
    for (i = n - 1; i > 0; i--) {
        piece t = v[0];
        v[0] = v[i];
        v[i] = t;
        sift(v, 0, i, P);
    }
}

/* Sorts the cut points of one edge along it (insertion sort: few cuts). */
static void sort_cuts(split *v, uint32_t n, const vec2 *P, int fwd)
{
    uint32_t i, j;
    for (i = 1; i < n; i++) {
        split t = v[i];
        for (j = i; j > 0; j--) {
            int c = lex_cmp(P[v[j - 1].pt], P[t.pt]);
            if (fwd ? c <= 0 : c >= 0)
                break;
            v[j] = v[j - 1];
        }
        v[j] = t;
    }
}

static void emit_piece(piece *out, uint32_t *n, const vec2 *P, uint32_t a, uint32_t b, int32_t bld)
{
    piece *q;
    if (lex_cmp(P[a], P[b]) == 0)
        return;
    q = &out[(*n)++];
    q->a = a;
    q->b = b;
    q->bld = bld;
    if (lex_cmp(P[a], P[b]) < 0) {
        q->lo = a;
        q->hi = b;
    } else {
        q->lo = b;
        q->hi = a;
    }
}

/* ---- trapezoidal map construction ------------------------------------- */

/* A trapezoid during construction (one cache line holds most of it). */
typedef struct btrap {
    uint32_t lp, rp, top, bot;
    uint32_t nb[4];
    uint32_t leaf;           /* its leaf node */
    uint32_t dead;
} btrap;

typedef struct tbuild {
    const polar *pd;
    int frame;
    uint32_t cap;            /* trapezoid slots */
    btrap *T;
    uint32_t ntrap;
    uint32_t *freel;
    uint32_t nfree;
    uint32_t (*node)[3];
    uint32_t nnode, cap_node;
    uint32_t *list;          /* trapezoids crossed by the new segment */
    uint32_t *up, *lo;       /* per crossed trapezoid: new upper / lower part */
    uint32_t (*lr)[2];       /* per segment: frame-left and frame-right end */
    int fail;
} tbuild;

static uint32_t new_trap(tbuild *b)
{
    uint32_t t;
    if (b->nfree > 0) {
        t = b->freel[--b->nfree];
    } else {
        if (b->ntrap >= b->cap) {
            b->fail = 1;
            return 0;
        }
        t = b->ntrap++;
    }
    b->T[t].dead = 0;
    b->T[t].nb[0] = b->T[t].nb[1] = b->T[t].nb[2] = b->T[t].nb[3] = POLAR_NONE;
    b->T[t].leaf = POLAR_NONE;
    return t;
}

static uint32_t new_node(tbuild *b, uint32_t kind, uint32_t idx, uint32_t c0, uint32_t c1)
{
    uint32_t n;
    if (b->nnode >= b->cap_node) {
        b->fail = 1;
        return 0;
    }
    n = b->nnode++;
    b->node[n][0] = PACK(kind, idx);
    b->node[n][1] = c0;
    b->node[n][2] = c1;
    return n;
}

static vec2 bpt(const tbuild *b, uint32_t i)
{
    return polar_fpt(b->pd, b->frame, i);
}

/* Descends the DAG with the left end P of a new segment PQ. */
static uint32_t find_first(const tbuild *b, vec2 P, vec2 Q)
{
    uint32_t n = 0;
    for (;;) {
        uint32_t w = b->node[n][0];
        if (KIND(w) == N_LEAF)
            return IDX(w);
        if (KIND(w) == N_X) {
            n = lex_cmp(P, bpt(b, IDX(w))) < 0 ? b->node[n][1] : b->node[n][2];
        } else {
            const uint32_t *e = b->lr[IDX(w)];
            vec2 L = bpt(b, e[0]), R = bpt(b, e[1]);
            int o = geom_orient(L, R, P);
            if (o == 0)
                o = geom_orient(L, R, Q);
            n = o > 0 ? b->node[n][2] : b->node[n][1];
        }
    }
}

static uint32_t ykind(const tbuild *b, uint32_t s)
{
    return b->lr[s][0] == b->pd->seg[s].a ? N_Y : N_YB;
}

/* Replaces the neighbour link 'old' of trapezoid x on side (f0, f1). */
static void relink(tbuild *b, uint32_t x, int f, uint32_t old, uint32_t nw)
{
    if (x != POLAR_NONE && b->T[x].nb[f] == old)
        b->T[x].nb[f] = nw;
}

static void set_trap(tbuild *b, uint32_t t, uint32_t lp, uint32_t rp, uint32_t top, uint32_t bot)
{
    b->T[t].lp = lp;
    b->T[t].rp = rp;
    b->T[t].top = top;
    b->T[t].bot = bot;
}

/* Follows the new segment s (ends l < r) through the map; returns k. */
static uint32_t follow(tbuild *b, uint32_t s, uint32_t l, uint32_t r)
{
    vec2 P = bpt(b, l), Q = bpt(b, r);
    uint32_t k = 0;
    (void)s;
    b->list[0] = find_first(b, P, Q);
    while (lex_cmp(Q, bpt(b, b->T[b->list[k]].rp)) > 0) {
        uint32_t t = b->list[k], nx;
        int o = geom_orient(P, Q, bpt(b, b->T[t].rp));
        nx = o > 0 ? b->T[t].nb[LR] : b->T[t].nb[UR];
        if (nx == POLAR_NONE || k + 1 >= b->cap) {
            b->fail = 2;
            return k;
        }
        b->list[++k] = nx;
    }
    return k;
}

/* Builds the chain of new trapezoids above (up = 1) or below the segment. */
static void make_chain(tbuild *b, uint32_t s, uint32_t l, uint32_t r, uint32_t k, int up)
{
    vec2 P = bpt(b, l), Q = bpt(b, r);
    uint32_t *part = up ? b->up : b->lo;
    uint32_t j, cur = new_trap(b);
    int fo = up ? UL : LL, fc = up ? UR : LR;     /* outer-side links */
    int fi_l = up ? LL : UL, fi_r = up ? LR : UR;  /* links along s */
    (void)fi_l;
    if (up)
        set_trap(b, cur, l, r, b->T[b->list[0]].top, s);
    else
        set_trap(b, cur, l, r, s, b->T[b->list[0]].bot);
    part[0] = cur;
    for (j = 0; j < k; j++) {
        uint32_t t = b->list[j], t1 = b->list[j + 1], R = b->T[t].rp, nx, x;
        int o = geom_orient(P, Q, bpt(b, R));
        if ((o > 0) != (up != 0)) {
            part[j + 1] = cur;        /* the axis at R is cut away: merge */
            continue;
        }
        b->T[cur].rp = R;
        nx = new_trap(b);
        if (up)
            set_trap(b, nx, R, r, b->T[t1].top, s);
        else
            set_trap(b, nx, R, r, s, b->T[t1].bot);
        x = b->T[t].nb[fc];
        b->T[cur].nb[fc] = x;
        relink(b, x, fo, t, cur);
        b->T[cur].nb[fi_r] = nx;
        b->T[nx].nb[up ? LL : UL] = cur;
        x = b->T[t1].nb[fo];
        b->T[nx].nb[fo] = x;
        relink(b, x, fc, t1, nx);
        cur = nx;
        part[j + 1] = cur;
    }
}

/* Inserts wall piece s into the map. */
static void insert_seg(tbuild *b, uint32_t s)
{
    uint32_t l, r, k, j, first, last, A = POLAR_NONE, B = POLAR_NONE;
    uint32_t U0, L0, Uk, Lk, fnb[4], lnb[4], flp, lrp;
    l = b->lr[s][0];
    r = b->lr[s][1];
    k = follow(b, s, l, r);
    if (b->fail)
        return;
    first = b->list[0];
    last = b->list[k];
    for (j = 0; j < 4; j++) {
        fnb[j] = b->T[first].nb[j];
        lnb[j] = b->T[last].nb[j];
    }
    flp = b->T[first].lp;
    lrp = b->T[last].rp;
    if (lex_cmp(bpt(b, l), bpt(b, flp)) > 0) {
        A = new_trap(b);
        set_trap(b, A, flp, l, b->T[first].top, b->T[first].bot);
    }
    if (lex_cmp(bpt(b, r), bpt(b, lrp)) < 0) {
        B = new_trap(b);
        set_trap(b, B, r, lrp, b->T[last].top, b->T[last].bot);
    }
    make_chain(b, s, l, r, k, 1);
    make_chain(b, s, l, r, k, 0);
    if (b->fail)
        return;
    U0 = b->up[0];
    L0 = b->lo[0];
    Uk = b->up[k];
    Lk = b->lo[k];
    /* left end */
    if (A != POLAR_NONE) {
        b->T[A].nb[UL] = fnb[UL];
        b->T[A].nb[LL] = fnb[LL];
        relink(b, fnb[UL], UR, first, A);
        relink(b, fnb[UL], LR, first, A);
        relink(b, fnb[LL], UR, first, A);
        relink(b, fnb[LL], LR, first, A);
        b->T[A].nb[UR] = U0;
        b->T[A].nb[LR] = L0;
        b->T[U0].nb[UL] = A;
        b->T[L0].nb[LL] = A;
    } else {
        b->T[U0].nb[UL] = fnb[UL];
        b->T[L0].nb[LL] = fnb[LL];
        relink(b, fnb[UL], UR, first, U0);
        relink(b, fnb[UL], LR, first, L0);
        relink(b, fnb[LL], UR, first, U0);
        relink(b, fnb[LL], LR, first, L0);
    }
    /* right end */
    if (B != POLAR_NONE) {
        b->T[B].nb[UR] = lnb[UR];
        b->T[B].nb[LR] = lnb[LR];
        relink(b, lnb[UR], UL, last, B);
        relink(b, lnb[UR], LL, last, B);
        relink(b, lnb[LR], UL, last, B);
        relink(b, lnb[LR], LL, last, B);
        b->T[B].nb[UL] = Uk;
        b->T[B].nb[LL] = Lk;
        b->T[Uk].nb[UR] = B;
        b->T[Lk].nb[LR] = B;
    } else {
        b->T[Uk].nb[UR] = lnb[UR];
        b->T[Lk].nb[LR] = lnb[LR];
        relink(b, lnb[UR], UL, last, Uk);
        relink(b, lnb[UR], LL, last, Lk);
        relink(b, lnb[LR], UL, last, Uk);
        relink(b, lnb[LR], LL, last, Lk);
    }
    /* leaves for the new trapezoids */
    if (A != POLAR_NONE)
        b->T[A].leaf = new_node(b, N_LEAF, A, 0, 0);
    if (B != POLAR_NONE)
        b->T[B].leaf = new_node(b, N_LEAF, B, 0, 0);
    for (j = 0; j <= k; j++) {
        if (b->T[b->up[j]].leaf == POLAR_NONE)
            b->T[b->up[j]].leaf = new_node(b, N_LEAF, b->up[j], 0, 0);
        if (b->T[b->lo[j]].leaf == POLAR_NONE)
            b->T[b->lo[j]].leaf = new_node(b, N_LEAF, b->lo[j], 0, 0);
    }
    if (b->fail)
        return;
    /* the old leaves become search nodes */
    for (j = 0; j <= k; j++) {
        uint32_t t = b->list[j], n = b->T[t].leaf;
        uint32_t y0 = b->T[b->lo[j]].leaf, y1 = b->T[b->up[j]].leaf;
        uint32_t inner;
        int xa = (j == 0 && A != POLAR_NONE), xb = (j == k && B != POLAR_NONE);
        if (!xa && !xb) {
            b->node[n][0] = PACK(ykind(b, s), s);
            b->node[n][1] = y0;
            b->node[n][2] = y1;
        } else {
            inner = new_node(b, ykind(b, s), s, y0, y1);
            if (xb) {
                uint32_t xq = xa ? new_node(b, N_X, r, inner, b->T[B].leaf) : POLAR_NONE;
                if (xa) {
                    b->node[n][0] = PACK(N_X, l);
                    b->node[n][1] = b->T[A].leaf;
                    b->node[n][2] = xq;
                } else {
                    b->node[n][0] = PACK(N_X, r);
                    b->node[n][1] = inner;
                    b->node[n][2] = b->T[B].leaf;
                }
            } else {
                b->node[n][0] = PACK(N_X, l);
                b->node[n][1] = b->T[A].leaf;
                b->node[n][2] = inner;
            }
        }
        b->T[t].dead = 1;
        b->freel[b->nfree++] = t;
    }
}

/* ---- coverage ---------------------------------------------------------- */

/* Footprints covering the space just above each segment (frame). */
static int compute_cover(tbuild *b, int32_t *cov, uint32_t *below,
                         uint32_t *stack)
{
    const polar *pd = b->pd;
    uint32_t t, s, nseg = pd->nseg;
    const int32_t UNSET = INT32_MIN;
    for (s = 0; s < nseg; s++) {
        cov[s] = UNSET;
        below[s] = POLAR_NONE;
    }
    for (s = pd->nwall; s < nseg; s++)
        cov[s] = 0;
    for (t = 0; t < b->ntrap; t++)
        if (!b->T[t].dead && below[b->T[t].top] == POLAR_NONE)
            below[b->T[t].top] = b->T[t].bot;
    for (s = 0; s < nseg; s++) {
        uint32_t n = 0, x = s;
        while (cov[x] == UNSET) {
            if (below[x] == POLAR_NONE || n >= nseg)
                return -1;
            stack[n++] = x;
            x = below[x];
        }
        while (n > 0) {
            uint32_t y = stack[--n];
            cov[y] = cov[below[y]] + seg_delta(pd, b->frame, y);
        }
    }
    return 0;
}

/* ---- build ------------------------------------------------------------- */

static int finite_box(const double *bx)
{
    int i;
    for (i = 0; i < 4; i++)
        if (!isfinite(bx[i]))
            return 0;
    return bx[0] < bx[2] && bx[1] < bx[3];
}

/* Adds the 4 box corners and the 4 box sides; returns 0 or -1. */
static void add_box(polar *pd, uint32_t p0)
{
    const double *bx = pd->box;
    uint32_t i, s0 = pd->nwall;
    pd->pts[p0 + 0].x = bx[0]; pd->pts[p0 + 0].y = bx[1];
    pd->pts[p0 + 1].x = bx[2]; pd->pts[p0 + 1].y = bx[1];
    pd->pts[p0 + 2].x = bx[2]; pd->pts[p0 + 2].y = bx[3];
    pd->pts[p0 + 3].x = bx[0]; pd->pts[p0 + 3].y = bx[3];
    for (i = 0; i < 4; i++) {
        polar_seg *g = &pd->seg[s0 + i];
        g->a = p0 + i;
        g->b = p0 + (i + 1) % 4;
        g->bld[0] = -2;
        g->bld[1] = -1;
        g->cover = 0;
    }
    pd->npts = p0 + 4;
    pd->nseg = s0 + 4;
}

/* Box sides and corners as seen in a frame: top, bottom, lowest, highest. */
static void frame_box(const polar *pd, polar_map *m)
{
    uint32_t i, s0 = pd->nwall, p0 = pd->npts - 4;
    double vmax = -DBL_MAX, vmin = DBL_MAX;
    for (i = 0; i < 4; i++) {
        const polar_seg *g = &pd->seg[s0 + i];
        vec2 a = polar_fpt(pd, m->frame, g->a), b = polar_fpt(pd, m->frame, g->b);
        if (a.y == b.y && a.y > vmax) {
            vmax = a.y;
            m->box_top = s0 + i;
        }
        if (a.y == b.y && a.y < vmin) {
            vmin = a.y;
            m->box_bot = s0 + i;
        }
    }
    m->box_lo = m->box_hi = p0;
    for (i = 1; i < 4; i++) {
        vec2 f = polar_fpt(pd, m->frame, p0 + i);
        if (lex_cmp(f, polar_fpt(pd, m->frame, m->box_lo)) < 0)
            m->box_lo = p0 + i;
        if (lex_cmp(f, polar_fpt(pd, m->frame, m->box_hi)) > 0)
            m->box_hi = p0 + i;
    }
}

static void *scratch_n(arena *a, size_t n, size_t size)
{
    size_t bytes = arena_mul(n ? n : 1, size);
    if (bytes == SIZE_MAX)
        return NULL;
    return arena_scratch(a, bytes, 16);
}

static void *keep_n(arena *a, size_t n, size_t size, size_t *acc)
{
    size_t bytes = arena_mul(n ? n : 1, size);
    void *p;
    if (bytes == SIZE_MAX)
        return NULL;
    p = arena_alloc(a, PLX_PART_POLAR, bytes, 16);
    if (p)
        *acc += bytes;
    return p;
}

/* The child word (polar.h) for build node c. */
static uint32_t child_word(const tbuild *b, uint32_t c, const uint32_t *renum,
                           const uint32_t *nrenum, const int32_t *cov)
{
    uint32_t w = b->node[c][0], t;
    if (KIND(w) != N_LEAF)
        return PACK(POLAR_CHILD_NODE, nrenum[c]);
    t = IDX(w);
    if (cov[b->T[t].bot] == 0)
        return PACK(POLAR_CHILD_FREE, renum[t]);
    /* solid: the wall with the footprint on the trapezoid's side */
    return PACK(POLAR_CHILD_SOLID, seg_delta(b->pd, b->frame, b->T[t].bot) > 0 ? b->T[t].bot
                                                                             : b->T[t].top);
}

/* Builds the trapezoidal map of one frame into scratch, then copies it. */
static plx_status build_map(arena *a, polar *pd, polar_map *m, uint32_t *order)
{
    tbuild b;
    uint32_t nw = pd->nwall, i, t, n;
    uint32_t *renum, *nrenum, *queue, nq;
    int32_t *cov;
    uint32_t *below, *stack;
    memset(&b, 0, sizeof b);
    b.pd = pd;
    b.frame = m->frame;
    b.cap = 4 * nw + 64;
    b.cap_node = 16 * nw + 64;
    b.T = scratch_n(a, b.cap, sizeof(btrap));
    b.freel = scratch_n(a, b.cap, 4);
    b.list = scratch_n(a, b.cap, 4);
    b.up = scratch_n(a, b.cap, 4);
    b.lo = scratch_n(a, b.cap, 4);
    b.node = scratch_n(a, b.cap_node, 12);
    b.lr = scratch_n(a, pd->nseg, 8);
    if (!b.lr)
        return PLX_E_NOMEM;
    for (i = 0; i < pd->nseg; i++)
        seg_ends(pd, m->frame, i, &b.lr[i][0], &b.lr[i][1]);
    if (!b.T || !b.freel ||
        !b.list || !b.up || !b.lo || !b.node)
        return PLX_E_NOMEM;
    frame_box(pd, m);
    t = new_trap(&b);
    set_trap(&b, t, m->box_lo, m->box_hi, m->box_top, m->box_bot);
    b.T[t].leaf = new_node(&b, N_LEAF, t, 0, 0);
    for (i = 0; i < nw && !b.fail; i++)
        insert_seg(&b, order[i]);
    if (b.fail)
        return b.fail == 1 ? PLX_E_NOMEM : PLX_E_SCENE;
    /* solid or free */
    cov = scratch_n(a, pd->nseg, 4);
    below = scratch_n(a, pd->nseg, 4);
    stack = scratch_n(a, pd->nseg, 4);
    renum = scratch_n(a, b.ntrap, 4);
    if (!cov || !below || !stack || !renum)
        return PLX_E_NOMEM;
    if (compute_cover(&b, cov, below, stack) != 0)
        return PLX_E_SCENE;
    /* keep the free trapezoids only; inner search nodes in breadth-first
     * order from the root (the top levels, visited by every search, share
     * cache lines); leaves folded into child words */
    n = 0;
    for (t = 0; t < b.ntrap; t++)
        renum[t] = (b.T[t].dead || cov[b.T[t].bot] != 0) ? POLAR_NONE : n++;
    nrenum = scratch_n(a, b.nnode, 4);
    queue = scratch_n(a, b.nnode, 4);
    if (!nrenum || !queue)
        return PLX_E_NOMEM;
    for (i = 0; i < b.nnode; i++)
        nrenum[i] = POLAR_NONE;
    nq = 0;
    if (KIND(b.node[0][0]) != N_LEAF) {
        nrenum[0] = 0;
        queue[nq++] = 0;
    }
    for (i = 0; i < nq; i++) {
        uint32_t j;
        for (j = 1; j < 3; j++) {
            uint32_t c = b.node[queue[i]][j];
            if (KIND(b.node[c][0]) != N_LEAF && nrenum[c] == POLAR_NONE) {
                nrenum[c] = nq;
                queue[nq++] = c;
            }
        }
    }
    m->ntrap = n;
    m->nnode = nq;
    m->trap = keep_n(a, n, sizeof(polar_trap), &pd->bytes[0]);
    m->node = keep_n(a, nq, 12, &pd->bytes[3]);
    if (!m->trap || !m->node)
        return PLX_E_NOMEM;
    /* polar_memory: the axes (lp, rp, nb) and the regions (top, bot) */
    pd->bytes[0] -= (size_t)n * 8;
    pd->bytes[1] += (size_t)n * 8;
    for (t = 0; t < b.ntrap; t++) {
        uint32_t u = renum[t], j;
        polar_trap *q;
        if (u == POLAR_NONE)
            continue;
        q = &m->trap[u];
        q->top = b.T[t].top;
        q->bot = b.T[t].bot;
        q->lp = b.T[t].lp;
        q->rp = b.T[t].rp;
        for (j = 0; j < 4; j++) {
            uint32_t x = b.T[t].nb[j];
            if (x != POLAR_NONE && renum[x] == POLAR_NONE)
                return PLX_E_SCENE;    /* a solid neighbour: cannot happen */
            q->nb[j] = x == POLAR_NONE ? POLAR_NONE : renum[x];
        }
    }
    m->root = child_word(&b, 0, renum, nrenum, cov);
    for (i = 0; i < nq; i++) {
        uint32_t o = queue[i];
        m->node[i][0] = b.node[o][0];
        m->node[i][1] = child_word(&b, b.node[o][1], renum, nrenum, cov);
        m->node[i][2] = child_word(&b, b.node[o][2], renum, nrenum, cov);
    }
    return PLX_OK;
}

/* Cuts the occluders' edges into wall pieces (pd->pts, pd->seg filled). */
static plx_status make_walls(arena *a, polar *pd)
{
    const scene *s = pd->s;
    edges e;
    split_ctx c;
    keyed *order;
    uint32_t *active, i, j, nocc = 0, nextra, np = 0, nm = 0;
    split *sp;
    piece *pc;
    e.n = count_edges(s);
    e.a = scratch_n(a, e.n, 4);
    e.b = scratch_n(a, e.n, 4);
    e.bld = scratch_n(a, e.n, 4);
    e.first = scratch_n(a, s->nbld, 4);
    e.count = scratch_n(a, s->nbld, 4);
    order = scratch_n(a, s->nbld, sizeof(keyed));
    active = scratch_n(a, s->nbld, 4);
    if (!e.a || !e.b || !e.bld || !e.first || !e.count || !order || !active)
        return PLX_E_NOMEM;
    fill_edges(s, &e);
    for (i = 0; i < s->nbld; i++) {
        if (!is_occluder(&s->bld[i]) || e.count[i] == 0)
            continue;
        order[nocc].key = s->bld[i].box[0];
        order[nocc].idx = i;
        nocc++;
    }
    qsort(order, nocc, sizeof(keyed), cmp_keyed);
    /* pass 1: count cuts and new points, with the scene's points */
    memset(&c, 0, sizeof c);
    c.pd = pd;
    c.e = &e;
    pd->pts = (vec2 *)s->pts;   /* read only during the count */
    c.npts = s->npts;
    find_contacts(&c, s, order, nocc, active);
    nextra = c.npts - s->npts;
    /* pass 2: for real */
    pd->npts = s->npts + nextra + 4;
    pd->pts = keep_n(a, pd->npts, sizeof(vec2), &pd->bytes[2]);
    sp = scratch_n(a, c.nsp, sizeof(split));
    if (!pd->pts || !sp)
        return PLX_E_NOMEM;
    if (s->npts)
        memcpy(pd->pts, s->pts, s->npts * sizeof(vec2));
    c.sp = sp;
    c.nsp = 0;
    c.npts = s->npts;
    c.cap_pts = s->npts + nextra;
    find_contacts(&c, s, order, nocc, active);
    qsort(sp, c.nsp, sizeof(split), cmp_split); /* stable enough: grouped by edge */
    pc = scratch_n(a, e.n + c.nsp, sizeof(piece));
    if (!pc)
        return PLX_E_NOMEM;
    for (i = 0, j = 0; i < e.n; i++) {
        uint32_t j0 = j, prev = e.a[i], q;
        while (j < c.nsp && sp[j].seg == i)
            j++;
        sort_cuts(sp + j0, j - j0, pd->pts, lex_cmp(pd->pts[e.a[i]], pd->pts[e.b[i]]) < 0);
        for (q = j0; q < j; q++) {
            emit_piece(pc, &np, pd->pts, prev, sp[q].pt, e.bld[i]);
            prev = sp[q].pt;
        }
        emit_piece(pc, &np, pd->pts, prev, e.b[i], e.bld[i]);
    }
    sort_pieces(pc, np, pd->pts);
    pd->seg = keep_n(a, np + 4, sizeof(polar_seg), &pd->bytes[2]);
    if (!pd->seg)
        return PLX_E_NOMEM;
    for (i = 0; i < np; i++) {
        if (nm > 0 && cmp_piece_pts(&pc[i], &pc[i - 1], pd->pts) == 0) {
            polar_seg *g = &pd->seg[nm - 1];
            int same = lex_cmp(pd->pts[g->a], pd->pts[pc[i].a]) == 0;
            g->cover += same ? 1 : -1;
            if (g->bld[1] < 0 && g->bld[0] != pc[i].bld)
                g->bld[1] = pc[i].bld;
            continue;
        }
        pd->seg[nm].a = pc[i].a;
        pd->seg[nm].b = pc[i].b;
        pd->seg[nm].bld[0] = pc[i].bld;
        pd->seg[nm].bld[1] = -1;
        pd->seg[nm].cover = 1;
        nm++;
    }
    /* pieces cancelling out (cover 0: a party wall, two footprints on
     * either side) separate solid from solid: no ray of a free point meets
     * them first, and they change no count of footprints, so they are left
     * out of the diagrams (fewer axes, regions and search nodes) */
    for (i = 0, j = 0; i < nm; i++)
        if (pd->seg[i].cover != 0)
            pd->seg[j++] = pd->seg[i];
    nm = j;
    pd->nwall = nm;
    pd->nseg = nm;
    add_box(pd, s->npts + nextra);
    return PLX_OK;
}

/* Biased randomized insertion order (Amenta, Choi, Rote 2003): every wall
 * piece draws a round at random (the last round holds about half of them,
 * the one before a quarter, ...); rounds go in order and, within a round,
 * pieces follow a Z-order curve of their midpoints. The randomness of the
 * rounds keeps the expected O(n log n) of randomized incremental
 * construction; the spatial order within a round makes consecutive searches
 * in the DAG run through the same nodes (cache hits). Deterministic. */
static uint32_t spread16(uint32_t x)
{
    x &= 0xffffu;
    x = (x | (x << 8)) & 0x00ff00ffu;
    x = (x | (x << 4)) & 0x0f0f0f0fu;
    x = (x | (x << 2)) & 0x33333333u;
    x = (x | (x << 1)) & 0x55555555u;
    return x;
}

static int insertion_order(arena *a, const polar *pd, uint32_t *order, uint64_t *seed)
{
    uint32_t i, n = pd->nwall;
    keyed *k = scratch_n(a, n, sizeof(keyed));
    double sx = 65535.0 / (pd->box[2] - pd->box[0]), sy = 65535.0 / (pd->box[3] - pd->box[1]);
    if (!k)
        return -1;
    for (i = 0; i < n; i++) {
        const polar_seg *g = &pd->seg[i];
        vec2 pa = pd->pts[g->a], pb = pd->pts[g->b];
        uint32_t r = rng_next(seed), round = 0, ux, uy;
        double mx = 0.5 * (pa.x + pb.x) - pd->box[0], my = 0.5 * (pa.y + pb.y) - pd->box[1];
        while (round < 24 && (r & 1u)) {   /* round 24 - t with probability 2^-(t+1) */
            round++;
            r >>= 1;
        }
        ux = (uint32_t)fmin(fmax(mx * sx, 0.0), 65535.0);
        uy = (uint32_t)fmin(fmax(my * sy, 0.0), 65535.0);
        k[i].key = (double)(24 - round) * 4294967296.0 + (double)(spread16(ux) | (spread16(uy) << 1));
        k[i].idx = i;
    }
    qsort(k, n, sizeof(keyed), cmp_keyed);
    for (i = 0; i < n; i++)
        order[i] = k[i].idx;
    return 0;
}

plx_status polar_build(arena *a, const scene *s, polar **out)
{
    arena_mark m0, m1;
    polar *pd;
    plx_status st;
    uint32_t *order, i;
    uint64_t seed = 0x9e3779b97f4a7c15ull;
    if (!a || !s || !out)
        return PLX_E_INVALID;
    *out = NULL;
    if (!finite_box(s->bounds))
        return PLX_E_INVALID;
    m0 = arena_get_mark(a);
    pd = arena_calloc(a, PLX_PART_POLAR, 1, sizeof(polar), 16);
    if (!pd)
        return PLX_E_NOMEM;
    pd->s = s;
    pd->nbld = s->nbld;
    memcpy(pd->box, s->bounds, sizeof pd->box);
    pd->bytes[3] = sizeof(polar);
    st = make_walls(a, pd);
    if (st == PLX_OK) {
        order = scratch_n(a, pd->nwall, 4);
        if (!order || insertion_order(a, pd, order, &seed) != 0)
            st = PLX_E_NOMEM;
        for (i = 0; st == PLX_OK && i < 2; i++) {
            pd->map[i].frame = i;
            st = build_map(a, pd, &pd->map[i], order);
        }
    }
    if (st != PLX_OK) {
        arena_release(a, &m0);
        return st;
    }
    /* release the scratch only, keep what was allocated for the diagrams */
    m1 = arena_get_mark(a);
    m1.hi = m0.hi;
    m1.used[PLX_PART_SCRATCH] = m0.used[PLX_PART_SCRATCH];
    arena_release(a, &m1);
    *out = pd;
    return PLX_OK;
}

/* ---- queries ----------------------------------------------------------- */

/* The child word of the leaf holding frame point f, or POLAR_NONE when f
 * is on a wall or has the abscissa and ordinate of a vertex. */
static uint32_t locate_word(const polar *pd, const polar_map *m, vec2 f)
{
    uint32_t c = m->root;
    while (POLAR_TAG(c) == POLAR_CHILD_NODE) {
        const uint32_t *nd = m->node[c];
        uint32_t w = nd[0];
        if (KIND(w) == N_X) {
            int k = lex_cmp(f, polar_fpt(pd, m->frame, IDX(w)));
            if (k == 0)
                return POLAR_NONE;
            c = k < 0 ? nd[1] : nd[2];
        } else {
            const polar_seg *g = &pd->seg[IDX(w)];
            uint32_t l = KIND(w) == N_Y ? g->a : g->b, r = KIND(w) == N_Y ? g->b : g->a;
            int o = geom_orient(polar_fpt(pd, m->frame, l), polar_fpt(pd, m->frame, r), f);
            if (o == 0)
                return POLAR_NONE;
            c = o > 0 ? nd[2] : nd[1];
        }
    }
    return c;
}

int32_t polar_locate_frame(const polar *pd, const polar_map *m, vec2 f)
{
    uint32_t c = locate_word(pd, m, f);
    if (c == POLAR_NONE)
        return -2;
    return POLAR_TAG(c) == POLAR_CHILD_FREE ? (int32_t)POLAR_IDX(c) : -3;
}

static int inside_box(const polar *pd, vec2 p)
{
    return p.x > pd->box[0] && p.x < pd->box[2] && p.y > pd->box[1] && p.y < pd->box[3];
}

/* Which map and which side (1 = top, 0 = bottom) hold quadrant q's start wall. */
static void quadrant_side(int q, int *map, int *top)
{
    *map = q & 1;
    *top = (q == 1 || q == 2);
}

static int32_t seg_owner(const polar *pd, uint32_t s)
{
    return pd->seg[s].bld[0] < 0 ? -1 : pd->seg[s].bld[0];
}

int32_t polar_locate(const polar *pd, int q, vec2 p, int32_t *owner)
{
    int mi, top;
    const polar_map *m;
    int32_t t;
    uint32_t c;
    if (owner)
        *owner = -1;
    if (!pd || q < 0 || q > 3 || !inside_box(pd, p))
        return -1;
    quadrant_side(q, &mi, &top);
    m = &pd->map[mi];
    c = locate_word(pd, m, polar_to_frame(m->frame, p));
    if (c == POLAR_NONE)
        return -2;
    if (POLAR_TAG(c) == POLAR_CHILD_SOLID) {
        if (owner)
            *owner = seg_owner(pd, POLAR_IDX(c));
        return -3;
    }
    t = (int32_t)POLAR_IDX(c);
    if (owner)
        *owner = seg_owner(pd, top ? m->trap[t].top : m->trap[t].bot);
    return t;
}

/* Intersection parameter of line p->q with the line of segment s. */
static double line_param(vec2 p, vec2 q, vec2 a, vec2 b)
{
    double rx = q.x - p.x, ry = q.y - p.y, sx = b.x - a.x, sy = b.y - a.y;
    double den = rx * sy - ry * sx;
    if (den == 0.0)
        return 0.0;
    return ((a.x - p.x) * sy - (a.y - p.y) * sx) / den;
}

/* Parameter where the ray p->q leaves the box. */
static double box_exit(const polar *pd, vec2 p, vec2 q)
{
    double dx = q.x - p.x, dy = q.y - p.y, t = DBL_MAX;
    if (dx > 0)
        t = fmin(t, (pd->box[2] - p.x) / dx);
    if (dx < 0)
        t = fmin(t, (pd->box[0] - p.x) / dx);
    if (dy > 0)
        t = fmin(t, (pd->box[3] - p.y) / dy);
    if (dy < 0)
        t = fmin(t, (pd->box[1] - p.y) / dy);
    return t;
}

/* Walks one-sided ray (side +1 / -1) from region t0 of map m. */
static void walk(const polar *pd, const polar_map *m, uint32_t t, vec2 p, vec2 q, int side,
                 polar_hit *h)
{
    vec2 P = polar_to_frame(m->frame, p), Q = polar_to_frame(m->frame, q);
    int right = lex_cmp(Q, P) > 0;
    uint32_t hit = POLAR_NONE, steps = 0;
    int box = 0;
    for (;;) {
        uint32_t r = right ? m->trap[t].rp : m->trap[t].lp, nx;
        int o;
        steps++;
        if (r == (right ? m->box_hi : m->box_lo)) {
            box = 1;
            break;
        }
        o = geom_orient(P, Q, polar_fpt(pd, m->frame, r));
        if (o == 0)
            o = side > 0 ? -1 : 1;
        if (!right)
            o = -o;
        /* o > 0: the ray passes below r (in the frame) */
        if (o > 0) {
            nx = m->trap[t].nb[right ? LR : LL];
            if (nx == POLAR_NONE) {
                hit = m->trap[t].bot;
                break;
            }
        } else {
            nx = m->trap[t].nb[right ? UR : UL];
            if (nx == POLAR_NONE) {
                hit = m->trap[t].top;
                break;
            }
        }
        t = nx;
    }
    h->steps = steps;
    h->ring_edge = -1;
    if (box || pd->seg[hit].bld[0] == -2) {
        h->bld = h->bld2 = -1;
        h->seg = box ? POLAR_NONE : hit;
        h->t = box_exit(pd, p, q);
    } else {
        const polar_seg *g = &pd->seg[hit];
        h->bld = g->bld[0];
        h->bld2 = g->bld[1];
        h->seg = hit;
        h->t = line_param(p, q, pd->pts[g->a], pd->pts[g->b]);
    }
    h->pt.x = p.x + h->t * (q.x - p.x);
    h->pt.y = p.y + h->t * (q.y - p.y);
}

plx_status polar_shoot_to(const polar *pd, vec2 p, vec2 q, int side, polar_hit *out)
{
    const polar_map *m;
    int32_t t;
    vec2 P, Q;
    if (!pd || !out)
        return PLX_E_INVALID;
    if (p.x == q.x && p.y == q.y)
        return PLX_E_INVALID;
    if (!inside_box(pd, p))
        return PLX_E_RANGE;
    /* the diagram of the quadrant holding the direction */
    {
        double dx = q.x - p.x, dy = q.y - p.y;
        int qd = (dx > 0 && dy >= 0) ? 0 : (dx <= 0 && dy > 0) ? 1 : (dx < 0) ? 2 : 3;
        m = &pd->map[qd & 1];
    }
    P = polar_to_frame(m->frame, p);
    Q = polar_to_frame(m->frame, q);
    (void)Q;
    t = polar_locate_frame(pd, m, P);
    if (t < 0)
        return PLX_E_RANGE;
    if (side != 0) {
        walk(pd, m, (uint32_t)t, p, q, side, out);
    } else {
        polar_hit h2;
        walk(pd, m, (uint32_t)t, p, q, 1, out);
        walk(pd, m, (uint32_t)t, p, q, -1, &h2);
        if (h2.t > out->t) {
            h2.steps += out->steps;
            *out = h2;
        } else {
            out->steps += h2.steps;
        }
    }
    return PLX_OK;
}

plx_status polar_shoot(const polar *pd, vec2 p, double dx, double dy, polar_hit *out)
{
    vec2 q;
    double L, n;
    if (!pd || !out || !(dx != 0.0 || dy != 0.0) || !isfinite(dx) || !isfinite(dy))
        return PLX_E_INVALID;
    L = 2.0 * ((pd->box[2] - pd->box[0]) + (pd->box[3] - pd->box[1]));
    n = sqrt(dx * dx + dy * dy);
    q.x = p.x + dx / n * L;
    q.y = p.y + dy / n * L;
    return polar_shoot_to(pd, p, q, 0, out);
}

void polar_memory(const polar *pd, size_t bytes[4])
{
    int i;
    for (i = 0; i < 4; i++)
        bytes[i] = pd ? pd->bytes[i] : 0;
}

uint32_t polar_region_count(const polar *pd, int q)
{
    if (!pd || q < 0 || q > 3)
        return 0;
    return pd->map[q & 1].ntrap;
}

/* Point of segment s at frame abscissa u (its end if s is vertical). */
static vec2 seg_at(const polar *pd, int frame, uint32_t s, double u)
{
    uint32_t l, r;
    vec2 A, B, c;
    seg_ends(pd, frame, s, &l, &r);
    A = polar_fpt(pd, frame, l);
    B = polar_fpt(pd, frame, r);
    c.x = u;
    if (B.x == A.x)
        c.y = A.y;
    else
        c.y = A.y + (B.y - A.y) * ((u - A.x) / (B.x - A.x));
    return c;
}

int polar_region(const polar *pd, int q, uint32_t i, vec2 c[4], int32_t *owner, int *solid)
{
    const polar_map *m;
    int mi, top;
    double ul, ur;
    if (!pd || q < 0 || q > 3 || i >= pd->map[q & 1].ntrap)
        return 0;
    quadrant_side(q, &mi, &top);
    m = &pd->map[mi];
    ul = polar_fpt(pd, m->frame, m->trap[i].lp).x;
    ur = polar_fpt(pd, m->frame, m->trap[i].rp).x;
    c[0] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].bot, ul));
    c[1] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].bot, ur));
    c[2] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].top, ur));
    c[3] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].top, ul));
    if (owner)
        *owner = seg_owner(pd, top ? m->trap[i].top : m->trap[i].bot);
    if (solid)
        *solid = 0;
    return 4;
}
