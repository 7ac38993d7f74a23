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
enum { N_LEAF = 0, N_X = 1, N_Y = 2 };
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

typedef struct tbuild {
    const polar *pd;
    int frame;
    uint32_t cap;            /* trapezoid slots */
    uint32_t *top, *bot, *lp, *rp, (*nb)[4], *leaf;
    uint8_t *dead;
    uint32_t ntrap;
    uint32_t *freel;
    uint32_t nfree;
    uint32_t (*node)[3];
    uint32_t nnode, cap_node;
    uint32_t *list;          /* trapezoids crossed by the new segment */
    uint32_t *up, *lo;       /* per crossed trapezoid: new upper / lower part */
    uint32_t otop[2], obot[2];
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
    b->dead[t] = 0;
    b->nb[t][0] = b->nb[t][1] = b->nb[t][2] = b->nb[t][3] = POLAR_NONE;
    b->leaf[t] = POLAR_NONE;
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
            uint32_t l, r;
            int o;
            seg_ends(b->pd, b->frame, IDX(w), &l, &r);
            o = geom_orient(bpt(b, l), bpt(b, r), P);
            if (o == 0)
                o = geom_orient(bpt(b, l), bpt(b, r), Q);
            n = o > 0 ? b->node[n][2] : b->node[n][1];
        }
    }
}

/* Replaces the neighbour link 'old' of trapezoid x on side (f0, f1). */
static void relink(tbuild *b, uint32_t x, int f, uint32_t old, uint32_t nw)
{
    if (x != POLAR_NONE && b->nb[x][f] == old)
        b->nb[x][f] = nw;
}

static void set_trap(tbuild *b, uint32_t t, uint32_t lp, uint32_t rp, uint32_t top, uint32_t bot)
{
    b->lp[t] = lp;
    b->rp[t] = rp;
    b->top[t] = top;
    b->bot[t] = bot;
}

/* Follows the new segment s (ends l < r) through the map; returns k. */
static uint32_t follow(tbuild *b, uint32_t s, uint32_t l, uint32_t r)
{
    vec2 P = bpt(b, l), Q = bpt(b, r);
    uint32_t k = 0;
    (void)s;
    b->list[0] = find_first(b, P, Q);
    while (lex_cmp(Q, bpt(b, b->rp[b->list[k]])) > 0) {
        uint32_t t = b->list[k], nx;
        int o = geom_orient(P, Q, bpt(b, b->rp[t]));
        nx = o > 0 ? b->nb[t][LR] : b->nb[t][UR];
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
        set_trap(b, cur, l, r, b->top[b->list[0]], s);
    else
        set_trap(b, cur, l, r, s, b->bot[b->list[0]]);
    part[0] = cur;
    for (j = 0; j < k; j++) {
        uint32_t t = b->list[j], t1 = b->list[j + 1], R = b->rp[t], nx, x;
        int o = geom_orient(P, Q, bpt(b, R));
        if ((o > 0) != (up != 0)) {
            part[j + 1] = cur;        /* the axis at R is cut away: merge */
            continue;
        }
        b->rp[cur] = R;
        nx = new_trap(b);
        if (up)
            set_trap(b, nx, R, r, b->top[t1], s);
        else
            set_trap(b, nx, R, r, s, b->bot[t1]);
        x = b->nb[t][fc];
        b->nb[cur][fc] = x;
        relink(b, x, fo, t, cur);
        b->nb[cur][fi_r] = nx;
        b->nb[nx][up ? LL : UL] = cur;
        x = b->nb[t1][fo];
        b->nb[nx][fo] = x;
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
    seg_ends(b->pd, b->frame, s, &l, &r);
    k = follow(b, s, l, r);
    if (b->fail)
        return;
    first = b->list[0];
    last = b->list[k];
    for (j = 0; j < 4; j++) {
        fnb[j] = b->nb[first][j];
        lnb[j] = b->nb[last][j];
    }
    flp = b->lp[first];
    lrp = b->rp[last];
    if (lex_cmp(bpt(b, l), bpt(b, flp)) > 0) {
        A = new_trap(b);
        set_trap(b, A, flp, l, b->top[first], b->bot[first]);
    }
    if (lex_cmp(bpt(b, r), bpt(b, lrp)) < 0) {
        B = new_trap(b);
        set_trap(b, B, r, lrp, b->top[last], b->bot[last]);
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
        b->nb[A][UL] = fnb[UL];
        b->nb[A][LL] = fnb[LL];
        relink(b, fnb[UL], UR, first, A);
        relink(b, fnb[UL], LR, first, A);
        relink(b, fnb[LL], UR, first, A);
        relink(b, fnb[LL], LR, first, A);
        b->nb[A][UR] = U0;
        b->nb[A][LR] = L0;
        b->nb[U0][UL] = A;
        b->nb[L0][LL] = A;
    } else {
        b->nb[U0][UL] = fnb[UL];
        b->nb[L0][LL] = fnb[LL];
        relink(b, fnb[UL], UR, first, U0);
        relink(b, fnb[UL], LR, first, L0);
        relink(b, fnb[LL], UR, first, U0);
        relink(b, fnb[LL], LR, first, L0);
    }
    /* right end */
    if (B != POLAR_NONE) {
        b->nb[B][UR] = lnb[UR];
        b->nb[B][LR] = lnb[LR];
        relink(b, lnb[UR], UL, last, B);
        relink(b, lnb[UR], LL, last, B);
        relink(b, lnb[LR], UL, last, B);
        relink(b, lnb[LR], LL, last, B);
        b->nb[B][UL] = Uk;
        b->nb[B][LL] = Lk;
        b->nb[Uk][UR] = B;
        b->nb[Lk][LR] = B;
    } else {
        b->nb[Uk][UR] = lnb[UR];
        b->nb[Lk][LR] = lnb[LR];
        relink(b, lnb[UR], UL, last, Uk);
        relink(b, lnb[UR], LL, last, Lk);
        relink(b, lnb[LR], UL, last, Uk);
        relink(b, lnb[LR], LL, last, Lk);
    }
    /* leaves for the new trapezoids */
    if (A != POLAR_NONE)
        b->leaf[A] = new_node(b, N_LEAF, A, 0, 0);
    if (B != POLAR_NONE)
        b->leaf[B] = new_node(b, N_LEAF, B, 0, 0);
    for (j = 0; j <= k; j++) {
        if (b->leaf[b->up[j]] == POLAR_NONE)
            b->leaf[b->up[j]] = new_node(b, N_LEAF, b->up[j], 0, 0);
        if (b->leaf[b->lo[j]] == POLAR_NONE)
            b->leaf[b->lo[j]] = new_node(b, N_LEAF, b->lo[j], 0, 0);
    }
    if (b->fail)
        return;
    /* the old leaves become search nodes */
    for (j = 0; j <= k; j++) {
        uint32_t t = b->list[j], n = b->leaf[t];
        uint32_t y0 = b->leaf[b->lo[j]], y1 = b->leaf[b->up[j]];
        uint32_t inner;
        int xa = (j == 0 && A != POLAR_NONE), xb = (j == k && B != POLAR_NONE);
        if (!xa && !xb) {
            b->node[n][0] = PACK(N_Y, s);
            b->node[n][1] = y0;
            b->node[n][2] = y1;
        } else {
            inner = new_node(b, N_Y, s, y0, y1);
            if (xb) {
                uint32_t xq = xa ? new_node(b, N_X, r, inner, b->leaf[B]) : POLAR_NONE;
                if (xa) {
                    b->node[n][0] = PACK(N_X, l);
                    b->node[n][1] = b->leaf[A];
                    b->node[n][2] = xq;
                } else {
                    b->node[n][0] = PACK(N_X, r);
                    b->node[n][1] = inner;
                    b->node[n][2] = b->leaf[B];
                }
            } else {
                b->node[n][0] = PACK(N_X, l);
                b->node[n][1] = b->leaf[A];
                b->node[n][2] = inner;
            }
        }
        b->dead[t] = 1;
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
        if (!b->dead[t] && below[b->top[t]] == POLAR_NONE)
            below[b->top[t]] = b->bot[t];
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

/* Builds the trapezoidal map of one frame into scratch, then copies it. */
static plx_status build_map(arena *a, polar *pd, polar_map *m, uint32_t *order)
{
    tbuild b;
    uint32_t nw = pd->nwall, i, t, n;
    uint32_t *renum;
    int32_t *cov;
    uint32_t *below, *stack;
    memset(&b, 0, sizeof b);
    b.pd = pd;
    b.frame = m->frame;
    b.cap = 4 * nw + 64;
    b.cap_node = 16 * nw + 64;
    b.top = scratch_n(a, b.cap, 4);
    b.bot = scratch_n(a, b.cap, 4);
    b.lp = scratch_n(a, b.cap, 4);
    b.rp = scratch_n(a, b.cap, 4);
    b.nb = scratch_n(a, b.cap, 16);
    b.leaf = scratch_n(a, b.cap, 4);
    b.dead = scratch_n(a, b.cap, 1);
    b.freel = scratch_n(a, b.cap, 4);
    b.list = scratch_n(a, b.cap, 4);
    b.up = scratch_n(a, b.cap, 4);
    b.lo = scratch_n(a, b.cap, 4);
    b.node = scratch_n(a, b.cap_node, 12);
    if (!b.top || !b.bot || !b.lp || !b.rp || !b.nb || !b.leaf || !b.dead || !b.freel ||
        !b.list || !b.up || !b.lo || !b.node)
        return PLX_E_NOMEM;
    frame_box(pd, m);
    t = new_trap(&b);
    set_trap(&b, t, m->box_lo, m->box_hi, m->box_top, m->box_bot);
    b.leaf[t] = new_node(&b, N_LEAF, t, 0, 0);
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
    n = 0;
    for (t = 0; t < b.ntrap; t++)
        renum[t] = b.dead[t] ? POLAR_NONE : n++;
    m->ntrap = n;
    m->nnode = b.nnode;
    m->root = 0;
    m->top = keep_n(a, n, 4, &pd->bytes[1]);
    m->bot = keep_n(a, n, 4, &pd->bytes[1]);
    m->solid = keep_n(a, n, 1, &pd->bytes[1]);
    m->lp = keep_n(a, n, 4, &pd->bytes[0]);
    m->rp = keep_n(a, n, 4, &pd->bytes[0]);
    m->nb = keep_n(a, n, 16, &pd->bytes[0]);
    m->node = keep_n(a, b.nnode, 12, &pd->bytes[3]);
    if (!m->top || !m->bot || !m->solid || !m->lp || !m->rp || !m->nb || !m->node)
        return PLX_E_NOMEM;
    for (t = 0; t < b.ntrap; t++) {
        uint32_t u = renum[t], j;
        if (u == POLAR_NONE)
            continue;
        m->top[u] = b.top[t];
        m->bot[u] = b.bot[t];
        m->lp[u] = b.lp[t];
        m->rp[u] = b.rp[t];
        m->solid[u] = cov[b.bot[t]] != 0;
        for (j = 0; j < 4; j++)
            m->nb[u][j] = b.nb[t][j] == POLAR_NONE ? POLAR_NONE : renum[b.nb[t][j]];
    }
    for (i = 0; i < b.nnode; i++) {
        m->node[i][0] = b.node[i][0];
        m->node[i][1] = b.node[i][1];
        m->node[i][2] = b.node[i][2];
        if (KIND(b.node[i][0]) == N_LEAF)
            m->node[i][0] = PACK(N_LEAF, renum[IDX(b.node[i][0])]);
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
    /* pieces cancelling out (cover 0) separate solid from solid: keep them,
     * they are still walls of the diagram */
    pd->nwall = nm;
    pd->nseg = nm;
    add_box(pd, s->npts + nextra);
    return PLX_OK;
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
        if (!order)
            st = PLX_E_NOMEM;
        for (i = 0; st == PLX_OK && i < pd->nwall; i++)
            order[i] = i;
        for (i = pd->nwall; st == PLX_OK && i > 1; i--) {
            uint32_t j = rng_next(&seed) % i, t = order[i - 1];
            order[i - 1] = order[j];
            order[j] = t;
        }
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

/* Region of frame point f: index, or -2 when f is on a wall or a vertex. */
int32_t polar_locate_frame(const polar *pd, const polar_map *m, vec2 f)
{
    uint32_t n = m->root;
    for (;;) {
        uint32_t w = m->node[n][0];
        if (KIND(w) == N_LEAF)
            return (int32_t)IDX(w);
        if (KIND(w) == N_X) {
            int c = lex_cmp(f, polar_fpt(pd, m->frame, IDX(w)));
            if (c == 0)
                return -2;
            n = c < 0 ? m->node[n][1] : m->node[n][2];
        } else {
            uint32_t l, r;
            int o;
            seg_ends(pd, m->frame, IDX(w), &l, &r);
            o = geom_orient(polar_fpt(pd, m->frame, l), polar_fpt(pd, m->frame, r), f);
            if (o == 0)
                return -2;
            n = o > 0 ? m->node[n][2] : m->node[n][1];
        }
    }
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
    if (owner)
        *owner = -1;
    if (!pd || q < 0 || q > 3 || !inside_box(pd, p))
        return -1;
    quadrant_side(q, &mi, &top);
    m = &pd->map[mi];
    t = polar_locate_frame(pd, m, polar_to_frame(m->frame, p));
    if (t < 0)
        return -2;
    if (m->solid[t]) {
        if (owner) {
            uint32_t s = seg_delta(pd, m->frame, m->bot[t]) > 0 ? m->bot[t] : m->top[t];
            *owner = seg_owner(pd, s);
        }
        return -3;
    }
    if (owner)
        *owner = seg_owner(pd, top ? m->top[t] : m->bot[t]);
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
        uint32_t r = right ? m->rp[t] : m->lp[t], nx;
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
            nx = m->nb[t][right ? LR : LL];
            if (nx == POLAR_NONE) {
                hit = m->bot[t];
                break;
            }
        } else {
            nx = m->nb[t][right ? UR : UL];
            if (nx == POLAR_NONE) {
                hit = m->top[t];
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
    if (t < 0 || m->solid[t])
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
    ul = polar_fpt(pd, m->frame, m->lp[i]).x;
    ur = polar_fpt(pd, m->frame, m->rp[i]).x;
    c[0] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->bot[i], ul));
    c[1] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->bot[i], ur));
    c[2] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->top[i], ur));
    c[3] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->top[i], ul));
    if (owner)
        *owner = m->solid[i] ? -1 : seg_owner(pd, top ? m->top[i] : m->bot[i]);
    if (solid)
        *solid = m->solid[i];
    return 4;
}
