/* polar: quadrant polar diagrams as trapezoidal subdivisions (see polar.h).
 *
 * Construction, per subdivision, in a frame where the axes are "vertical"
 * and points are ordered lexicographically by (u, v) (the trapezoidal map
 * of de Berg et al., "Computational Geometry", ch. 6):
 * 1. the map and its search DAG by randomized incremental insertion of the
 *    wall pieces (see "the search DAG" below; expected O(n log n));
 * 2. a plane sweep over the wall ends (see "a plane sweep"), which reads
 *    from that map the piece below every event where pieces only start
 *    (O(1); the piece below is the floor of the map's trapezoid below the
 *    lowest piece starting there), checks that the pieces form a planar
 *    subdivision and that every gap it opens is a trapezoid of the map with
 *    the same sides, and makes the free regions (whether a gap is solid is
 *    known when its floor enters the sweep) in a deterministic order with
 *    their adjacency, setting the DAG leaf of each: O(n log n) worst case;
 * 3. the DAG kept, its leaves as child words (a free region or the owner
 *    of a solid trapezoid).
 * Before that, the footprints are cut at their contacts (make_walls).
 * No grid is used; polar_scan keeps one, with the former grid-scan point
 * location, as a reference for tests and benchmarks. pd->steps counts the
 * searching work (DAG nodes and trapezoids visited by the insertions,
 * status pieces walked and sorted by the sweeps) for the tests.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "polar/polar.h"
#include "base/msort.h"
#include "base/geom.h"
#include "base/plx_assert.h"

enum { UL = 0, LL = 1, UR = 2, LR = 3 };
/* search nodes: a leaf, a point (x) test, a segment (y) test whose frame-left
 * end is seg.a (N_Y) or seg.b (N_YB); the same kinds as POLAR_NODE_* */
enum { N_LEAF = 0, N_X = POLAR_NODE_X, N_Y = POLAR_NODE_Y, N_YB = POLAR_NODE_YB };
#define KIND(w) ((w) >> 30)
#define IDX(w) ((w) & 0x3fffffffu)
#define PACK(k, i) (((uint32_t)(k) << 30) | (uint32_t)(i))

/* ---- frames and small helpers ----------------------------------------- */

static vec2 to_frame(int frame, vec2 w)
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

vec2 polar_to_frame(int frame, vec2 w)
{
    return to_frame(frame, w);
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

/* Point i in a frame (the inline twin of polar_fpt, for the hot loops). */
static vec2 fpt(const polar *pd, int frame, uint32_t i)
{
    vec2 w = pd->pts[i], f;
    if (frame == 0) {
        f.x = w.y;
        f.y = -w.x;
    } else {
        f = w;
    }
    return f;
}

vec2 polar_fpt(const polar *pd, int frame, uint32_t i)
{
    return fpt(pd, frame, i);
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
    if (lex_cmp(fpt(pd, frame, g->a), fpt(pd, frame, g->b)) < 0) {
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
    int fwd = lex_cmp(fpt(pd, frame, g->a), fpt(pd, frame, g->b)) < 0;
    return fwd ? g->cover : -g->cover;
}

/* n items of size bytes of arena scratch. */
static void *scratch_n(arena *a, size_t n, size_t size)
{
    size_t bytes = arena_mul(n ? n : 1, size);
    if (bytes == SIZE_MAX)
        return NULL;
    return arena_scratch(a, bytes, 16);
}

/* ---- wall pieces ------------------------------------------------------- */

typedef struct split {
    uint32_t seg;     /* edge (first pass) or piece index */
    uint32_t pt;      /* point index */
    uint32_t rounded; /* a crossing: pt is off the line, the pieces bend */
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

/* fmin and fmax are library calls (NaN rules); coordinates are finite */
static double dmin(double a, double b)
{
    return a < b ? a : b;
}

static double dmax(double a, double b)
{
    return a > b ? a : b;
}

/* Is c strictly inside segment ab, knowing the three are collinear? */
static int strictly_between(vec2 a, vec2 b, vec2 c)
{
    int ca = lex_cmp(c, a), cb = lex_cmp(c, b);
    return ca != 0 && cb != 0 && ca != cb;
}

/* Cuts and crossing points are recorded in one pass over the contacts,
 * in chunks of scratch memory (their number is not known beforehand). */
#define SPLIT_CHUNK 1024
typedef struct split_chunk {
    struct split_chunk *next;
    uint32_t n;
    split v[SPLIT_CHUNK];
} split_chunk;

typedef struct point_chunk {
    struct point_chunk *next;
    uint32_t n;
    vec2 v[SPLIT_CHUNK];
} point_chunk;

typedef struct split_ctx {
    polar *pd;
    const edges *e;
    arena *a;
    split_chunk *sp0, *sp;    /* first and last chunk of cuts */
    point_chunk *pt0, *pt;    /* first and last chunk of crossing points */
    uint32_t nsp;
    uint32_t npts;            /* next free point index */
    int nomem;
} split_ctx;

static void add_split(split_ctx *c, uint32_t seg, uint32_t pt, uint32_t rounded)
{
    if (!c->sp || c->sp->n == SPLIT_CHUNK) {
        split_chunk *k = arena_scratch(c->a, sizeof(split_chunk), 16);
        if (!k) {
            c->nomem = 1;
            return;
        }
        k->next = NULL;
        k->n = 0;
        if (c->sp)
            c->sp->next = k;
        else
            c->sp0 = k;
        c->sp = k;
    }
    c->sp->v[c->sp->n].seg = seg;
    c->sp->v[c->sp->n].pt = pt;
    c->sp->v[c->sp->n].rounded = rounded;
    c->sp->n++;
    c->nsp++;
}

static uint32_t add_point(split_ctx *c, vec2 p)
{
    if (!c->pt || c->pt->n == SPLIT_CHUNK) {
        point_chunk *k = arena_scratch(c->a, sizeof(point_chunk), 16);
        if (!k) {
            c->nomem = 1;
            return 0;
        }
        k->next = NULL;
        k->n = 0;
        if (c->pt)
            c->pt->next = k;
        else
            c->pt0 = k;
        c->pt = k;
    }
    c->pt->v[c->pt->n++] = p;
    return c->npts++;
}

/* The crossing point of segments ab and cd (crossing properly), rounded,
 * then clamped into the intersection of their bounding boxes (which holds
 * the exact crossing): a cut there stays within both pieces' boxes, so a
 * piece cut near its end folds back, if at all, by no more than rounding. */
static vec2 cross_point(vec2 a, vec2 b, vec2 c, vec2 d)
{
    double rx = b.x - a.x, ry = b.y - a.y, sx = d.x - c.x, sy = d.y - c.y;
    double den = rx * sy - ry * sx;
    double t = ((c.x - a.x) * sy - (c.y - a.y) * sx) / den;
    double x0 = fmax(fmin(a.x, b.x), fmin(c.x, d.x)), x1 = fmin(fmax(a.x, b.x), fmax(c.x, d.x));
    double y0 = fmax(fmin(a.y, b.y), fmin(c.y, d.y)), y1 = fmin(fmax(a.y, b.y), fmax(c.y, d.y));
    vec2 p;
    if (t < 0.0)
        t = 0.0;
    if (t > 1.0)
        t = 1.0;
    p.x = fmin(fmax(a.x + t * rx, x0), x1);
    p.y = fmin(fmax(a.y + t * ry, y0), y1);
    return p;
}

/* The point where pieces (ia, ib) and (ja, jb) cross: one of the four ends
 * when the rounded crossing falls on it, else a new point. */
static uint32_t crossing(split_ctx *c, uint32_t ia, uint32_t ib, uint32_t ja, uint32_t jb)
{
    const vec2 *P = c->pd->pts;
    vec2 x = cross_point(P[ia], P[ib], P[ja], P[jb]);
    if (lex_cmp(x, P[ia]) == 0)
        return ia;
    if (lex_cmp(x, P[ib]) == 0)
        return ib;
    if (lex_cmp(x, P[ja]) == 0)
        return ja;
    if (lex_cmp(x, P[jb]) == 0)
        return jb;
    return add_point(c, x);
}

/* Records the cuts that contact between segments i (ia, ib) and j (ja, jb)
 * asks for: both at their crossing point when they cross properly (the only
 * rounded step), else each at the other's ends lying strictly inside it
 * (touching, overlapping collinear). */
static void meet_segs(split_ctx *c, uint32_t i, uint32_t ia, uint32_t ib, uint32_t j,
                      uint32_t ja, uint32_t jb)
{
    const vec2 *P = c->pd->pts;
    vec2 a = P[ia], b = P[ib], d0 = P[ja], d1 = P[jb];
    int o1, o2, o3, o4;
    if (dmax(a.x, b.x) < dmin(d0.x, d1.x) || dmax(d0.x, d1.x) < dmin(a.x, b.x) ||
        dmax(a.y, b.y) < dmin(d0.y, d1.y) || dmax(d0.y, d1.y) < dmin(a.y, b.y))
        return;
    /* a common end (pieces of one edge, corners shared by neighbours): they
     * meet elsewhere only when collinear, then where one's other end lies
     * inside the other (the cuts the four signs below would give) */
    if (lex_cmp(a, d0) == 0 || lex_cmp(a, d1) == 0 || lex_cmp(b, d0) == 0 ||
        lex_cmp(b, d1) == 0) {
        uint32_t u = lex_cmp(a, d0) == 0 || lex_cmp(a, d1) == 0 ? ib : ia;
        uint32_t v = lex_cmp(d0, a) == 0 || lex_cmp(d0, b) == 0 ? jb : ja;
        if (geom_orient(a, b, P[v]) != 0)
            return;
        if (strictly_between(a, b, P[v]))
            add_split(c, i, v, 0);
        if (strictly_between(d0, d1, P[u]))
            add_split(c, j, u, 0);
        return;
    }
    /* the four signs once (geom_seg_meet would take them again below) */
    o1 = geom_orient(a, b, d0);
    o2 = geom_orient(a, b, d1);
    if ((o1 > 0 && o2 > 0) || (o1 < 0 && o2 < 0))
        return;
    o3 = geom_orient(d0, d1, a);
    o4 = geom_orient(d0, d1, b);
    if ((o3 > 0 && o4 > 0) || (o3 < 0 && o4 < 0))
        return;
    if (o1 != 0 && o2 != 0 && o3 != 0 && o4 != 0) {
        uint32_t x = crossing(c, ia, ib, ja, jb);
        add_split(c, i, x, 1);
        add_split(c, j, x, 1);
        return;
    }
    /* touch or overlap: cut each at the other's ends lying inside it */
    if (o1 == 0 && strictly_between(a, b, d0))
        add_split(c, i, ja, 0);
    if (o2 == 0 && strictly_between(a, b, d1))
        add_split(c, i, jb, 0);
    if (o3 == 0 && strictly_between(d0, d1, a))
        add_split(c, j, ia, 0);
    if (o4 == 0 && strictly_between(d0, d1, b))
        add_split(c, j, ib, 0);
}

/* Records where edges i and j (of different buildings) must be cut. */
static void meet_edges(split_ctx *c, uint32_t i, uint32_t j)
{
    meet_segs(c, i, c->e->a[i], c->e->b[i], j, c->e->a[j], c->e->b[j]);
}

/* The edges of building p whose bounding boxes meet the closed box bx,
 * into out[0..cap-1]; returns their count, or cap + 1 when they do not fit. */
static uint32_t edges_near(const split_ctx *c, uint32_t p, const double *bx, uint32_t *out,
                           uint32_t cap)
{
    const edges *e = c->e;
    const vec2 *P = c->pd->pts;
    uint32_t i, n = 0;
    for (i = e->first[p]; i < e->first[p] + e->count[p]; i++) {
        vec2 a = P[e->a[i]], b = P[e->b[i]];
        if (dmax(a.x, b.x) < bx[0] || dmin(a.x, b.x) > bx[2] || dmax(a.y, b.y) < bx[1] ||
            dmin(a.y, b.y) > bx[3])
            continue;
        if (n == cap)
            return cap + 1;
        out[n++] = i;
    }
    return n;
}

/* Every edge of p against every edge of q, those far from the other
 * building's box left out first. */
static void meet_buildings(split_ctx *c, uint32_t p, uint32_t q)
{
    enum { CAP = 48 };
    const edges *e = c->e;
    const scene *s = c->pd->s;
    uint32_t ep[CAP], eq[CAP], np, nq, i, j;
    np = edges_near(c, p, s->bld[q].box, ep, CAP);
    nq = edges_near(c, q, s->bld[p].box, eq, CAP);
    if (np <= CAP && nq <= CAP) {
        for (i = 0; i < np; i++)
            for (j = 0; j < nq; j++)
                meet_edges(c, ep[i], eq[j]);
        return;
    }
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

/* The active boxes of find_contacts: a complete binary tree over the
 * ranks of the occluders' lower y, each node holding the greatest upper y
 * of the active boxes below it (-DBL_MAX: none). */
typedef struct ytree {
    uint32_t size;           /* leaves, a power of two */
    double *mx;              /* nodes 1 .. 2 size - 1, leaves from size */
    uint32_t *who;           /* per rank: its building */
} ytree;

static void ytree_set(ytree *t, uint32_t rank, double v)
{
    uint32_t n = t->size + rank;
    t->mx[n] = v;
    for (n /= 2; n > 0; n /= 2)
        t->mx[n] = fmax(t->mx[2 * n], t->mx[2 * n + 1]);
}

/* Meets building b with the active ones of rank < lim whose upper y is at
 * least ylo, below node n (covering ranks [lo, lo + w)). */
static void ytree_meet(split_ctx *c, const ytree *t, uint32_t n, uint32_t lo, uint32_t w,
                       uint32_t lim, double ylo, uint32_t b)
{
    if (lo >= lim || t->mx[n] < ylo)
        return;
    if (w == 1) {
        meet_buildings(c, t->who[lo], b);
        return;
    }
    ytree_meet(c, t, 2 * n, lo, w / 2, lim, ylo, b);
    ytree_meet(c, t, 2 * n + 1, lo + w / 2, w / 2, lim, ylo, b);
}

/* Sweep over x of building boxes: every pair of occluders whose closed
 * boxes meet has its edges compared. order: the nocc occluders by lower
 * x. A box meets the active boxes (begun before it, not ended before its
 * lower x) whose y ranges meet its own: those with lower y <= its upper y
 * (a prefix of the ranks) and upper y >= its lower y (subtrees below that
 * skipped). O(log n) per box and per pair of boxes that meet, whatever the
 * layout. */
static plx_status find_contacts(split_ctx *c, const scene *s, const keyed *order, uint32_t nocc)
{
    arena *a = c->a;
    keyed *byy = scratch_n(a, nocc, sizeof(keyed)), *byx1 = scratch_n(a, nocc, sizeof(keyed));
    uint32_t *rank = scratch_n(a, s->nbld, 4), i, k, e = 0;
    ytree t;
    t.size = 1;
    while (t.size < nocc)
        t.size *= 2;
    t.mx = scratch_n(a, 2 * (size_t)t.size, sizeof(double));
    t.who = scratch_n(a, t.size, 4);
    if (!byy || !byx1 || !rank || !t.mx || !t.who)
        return PLX_E_NOMEM;
    for (i = 0; i < nocc; i++) {
        uint32_t b = order[i].idx;
        byy[i].key = s->bld[b].box[1];
        byy[i].idx = b;
        byx1[i].key = s->bld[b].box[2];
        byx1[i].idx = b;
    }
    qsort(byy, nocc, sizeof(keyed), cmp_keyed);
    qsort(byx1, nocc, sizeof(keyed), cmp_keyed);
    for (i = 0; i < nocc; i++) {
        rank[byy[i].idx] = i;
        t.who[i] = byy[i].idx;
    }
    for (i = 1; i < 2 * t.size; i++)
        t.mx[i] = -DBL_MAX;
    for (i = 0; i < nocc; i++) {
        uint32_t b = order[i].idx, lim = 0, hi = nocc;
        const double *bb = s->bld[b].box;
        for (; e < nocc && byx1[e].key < bb[0]; e++)   /* ended before: drop */
            ytree_set(&t, rank[byx1[e].idx], -DBL_MAX);
        while (lim < hi) {                            /* ranks with lower y <= bb[3] */
            k = lim + (hi - lim) / 2;
            if (byy[k].key <= bb[3])
                lim = k + 1;
            else
                hi = k;
        }
        ytree_meet(c, &t, 1, 0, t.size, lim, bb[1], b);
        ytree_set(&t, rank[b], bb[3]);
    }
    return PLX_OK;
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

/* Pieces sorted by their ends: keys with the coordinates inline, bottom-up
 * merge sort (stable: equal pieces keep the order of their edges). */
typedef struct pkey {
    vec2 lo, hi;
    uint32_t k;
} pkey;

static int pkey_before(const pkey *a, const pkey *b, const void *ctx)
{
    (void)ctx;
    int c = lex_cmp(a->lo, b->lo);
    if (c == 0)
        c = lex_cmp(a->hi, b->hi);
    return c < 0 || (c == 0 && a->k < b->k);
}

MSORT_DEFINE(sort_pkeys, pkey, const void *, pkey_before)

/* The direction of an edge for sorting its cuts: its points, and whether it
 * runs in lexicographic order. */
typedef struct cut_order {
    const vec2 *P;
    int fwd;
} cut_order;

/* Is cut a before cut b along the edge? */
static int cut_before(const split *a, const split *b, const cut_order *o)
{
    int c = lex_cmp(o->P[a->pt], o->P[b->pt]);
    return o->fwd ? c < 0 : c > 0;
}

/* Sorts the cut points of one edge along it (a long wall cut by many
 * footprints: O(c log c)). */
MSORT_DEFINE(sort_cuts, split, const cut_order *, cut_before)

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

/* ---- pieces made consistent after rounding ---------------------------- */

/* A rounded crossing point lies off its edges' lines by up to an ulp: the
 * pieces of such an edge bend there, and a bent piece can cross, touch or
 * overlap another piece again (three walls through nearly one point, a
 * crossing rounded onto a collinear wall's line, a crossing an ulp from a
 * vertex). So contacts are looked for again among the pieces and cut as in
 * the first pass, in rounds, until none is left. A round compares the
 * pieces cut in the round before ("dirty") with all pieces: two pieces
 * neither of which was cut had no contact a round before (or it would have
 * cut one of them), so they have none now. For the first round the dirty
 * pieces are those of edges with a rounded cut: edges cut at scene points
 * only are cut exactly (on their lines) at every end lying inside them, and
 * their pieces touch nothing but at shared ends, as without crossings. */
#define WALL_ROUNDS 64

static void *scratch_n(arena *a, size_t n, size_t size);

/* Uniform grid over the dirty pieces: cell c lists item[cell[c] ..
 * cell[c + 1]), the dirty pieces whose bounding boxes meet it, with their
 * boxes (read in the cell's order, not from the points). */
typedef struct ditem {
    double bx[4];
    uint32_t d;
} ditem;

typedef struct dgrid {
    double x0, y0, x1, y1, sx, sy;
    uint32_t nx, ny;
    uint32_t *cell;
    ditem *item;
} dgrid;

static void piece_box(const vec2 *P, const piece *q, double *bx)
{
    vec2 a = P[q->a], b = P[q->b];
    bx[0] = dmin(a.x, b.x);
    bx[1] = dmin(a.y, b.y);
    bx[2] = dmax(a.x, b.x);
    bx[3] = dmax(a.y, b.y);
}

/* Monotone in v, so a point of two boxes falls in a cell of both ranges. */
static uint32_t dcell(double v, double v0, double scale, uint32_t n)
{
    double c = floor((v - v0) * scale);
    if (!(c > 0.0))
        return 0;
    if (c >= (double)n)
        return n - 1;
    return (uint32_t)c;
}

static void dgrid_range(const dgrid *g, const double *bx, uint32_t *r)
{
    r[0] = dcell(bx[0], g->x0, g->sx, g->nx);
    r[1] = dcell(bx[1], g->y0, g->sy, g->ny);
    r[2] = dcell(bx[2], g->x0, g->sx, g->nx);
    r[3] = dcell(bx[3], g->y0, g->sy, g->ny);
}

/* Cells of about the area per dirty piece, at most 5 nd + 1 of them. */
static void dgrid_size(dgrid *g, const vec2 *P, const piece *pc, const uint32_t *dl, uint32_t nd)
{
    double bx[4], w, h, cs;
    uint32_t i;
    g->x0 = g->y0 = DBL_MAX;
    g->x1 = g->y1 = -DBL_MAX;
    for (i = 0; i < nd; i++) {
        piece_box(P, &pc[dl[i]], bx);
        g->x0 = fmin(g->x0, bx[0]);
        g->y0 = fmin(g->y0, bx[1]);
        g->x1 = fmax(g->x1, bx[2]);
        g->y1 = fmax(g->y1, bx[3]);
    }
    w = g->x1 - g->x0;
    h = g->y1 - g->y0;
    cs = sqrt(w * h / nd);
    if (!(cs > 0.0))
        cs = fmax(w, h) / nd;
    g->nx = cs > 0.0 ? (uint32_t)fmin(w / cs, 2.0 * nd) + 1 : 1;
    g->ny = cs > 0.0 ? (uint32_t)fmin(h / cs, 2.0 * nd) + 1 : 1;
    g->sx = w > 0.0 ? g->nx / w : 0.0;
    g->sy = h > 0.0 ? g->ny / h : 0.0;
}

static plx_status dgrid_build(arena *a, dgrid *g, const vec2 *P, const piece *pc,
                              const uint32_t *dl, uint32_t nd)
{
    uint32_t i, x, y, r[4], nc;
    double bx[4];
    dgrid_size(g, P, pc, dl, nd);
    nc = g->nx * g->ny;
    g->cell = scratch_n(a, (size_t)nc + 1, 4);
    if (!g->cell)
        return PLX_E_NOMEM;
    memset(g->cell, 0, ((size_t)nc + 1) * 4);
    for (i = 0; i < nd; i++) {
        piece_box(P, &pc[dl[i]], bx);
        dgrid_range(g, bx, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                g->cell[y * g->nx + x + 1]++;
    }
    for (i = 0; i < nc; i++)
        g->cell[i + 1] += g->cell[i];
    g->item = scratch_n(a, g->cell[nc], sizeof(ditem));
    if (!g->item)
        return PLX_E_NOMEM;
    for (i = 0; i < nd; i++) {
        piece_box(P, &pc[dl[i]], bx);
        dgrid_range(g, bx, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++) {
                ditem *t = &g->item[g->cell[y * g->nx + x]++];
                memcpy(t->bx, bx, sizeof bx);
                t->d = dl[i];
            }
    }
    for (i = nc; i > 0; i--)
        g->cell[i] = g->cell[i - 1];
    g->cell[0] = 0;
    return PLX_OK;
}

/* Piece s against the dirty pieces of one cell: each pair once, in the
 * cell holding the low corner of the two boxes' intersection. */
static void meet_in_cell(split_ctx *c, const piece *pc, const uint8_t *dirty, const dgrid *g,
                         uint32_t s, const double *bs, uint32_t x, uint32_t y)
{
    uint32_t k, cl = y * g->nx + x;
    for (k = g->cell[cl]; k < g->cell[cl + 1]; k++) {
        uint32_t d = g->item[k].d;
        const double *bd = g->item[k].bx;
        if (d == s || (dirty[s] && s > d))
            continue;
        if (bd[2] < bs[0] || bd[0] > bs[2] || bd[3] < bs[1] || bd[1] > bs[3])
            continue;
        if (dcell(dmax(bs[0], bd[0]), g->x0, g->sx, g->nx) != x ||
            dcell(dmax(bs[1], bd[1]), g->y0, g->sy, g->ny) != y)
            continue;
        meet_segs(c, s, pc[s].a, pc[s].b, d, pc[d].a, pc[d].b);
    }
}

/* Every piece against the dirty pieces near it. */
static void meet_pieces(split_ctx *c, const piece *pc, uint32_t np, const uint8_t *dirty,
                        const dgrid *g)
{
    const vec2 *P = c->pd->pts;
    uint32_t s, x, y, r[4];
    double bs[4];
    for (s = 0; s < np && !c->nomem; s++) {
        piece_box(P, &pc[s], bs);
        if (bs[2] < g->x0 || bs[0] > g->x1 || bs[3] < g->y0 || bs[1] > g->y1)
            continue;
        dgrid_range(g, bs, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                meet_in_cell(c, pc, dirty, g, s, bs, x, y);
    }
}

/* The points gathered in c's chunks appended to the nold points of
 * c->pd->pts, in a new scratch array that c->pd->pts then points to. */
static plx_status flat_points(arena *a, split_ctx *c, uint32_t nold)
{
    vec2 *P = scratch_n(a, c->npts, sizeof(vec2));
    point_chunk *k;
    uint32_t n = nold;
    if (!P)
        return PLX_E_NOMEM;
    if (nold)
        memcpy(P, c->pd->pts, (size_t)nold * sizeof(vec2));
    for (k = c->pt0; k; k = k->next) {
        memcpy(P + n, k->v, k->n * sizeof(vec2));
        n += k->n;
    }
    c->pd->pts = P;
    return PLX_OK;
}

/* Cuts in[0..n-1] at the cuts recorded in c into *out (*nout pieces, in
 * the order of in, each one's along it). (*dirty)[k]: piece k comes from a
 * piece with a rounded cut, or with any cut when all_cuts. */
static plx_status cut_pieces(arena *a, split_ctx *c, const piece *in, uint32_t n, int all_cuts,
                             piece **out, uint32_t *nout, uint8_t **dirty)
{
    const vec2 *P = c->pd->pts;
    split *sp = scratch_n(a, c->nsp, sizeof(split)), *sptmp = scratch_n(a, c->nsp, sizeof(split));
    uint32_t *first = scratch_n(a, (size_t)n + 1, 4), i, j, k, m = 0;
    piece *pc = scratch_n(a, (size_t)n + c->nsp, sizeof(piece));
    uint8_t *dy = scratch_n(a, (size_t)n + c->nsp, 1);
    split_chunk *q;
    if (!sp || !sptmp || !first || !pc || !dy)
        return PLX_E_NOMEM;
    /* the cuts grouped by piece (counting sort) */
    memset(first, 0, ((size_t)n + 1) * 4);
    for (q = c->sp0; q; q = q->next)
        for (i = 0; i < q->n; i++)
            first[q->v[i].seg + 1]++;
    for (i = 0; i < n; i++)
        first[i + 1] += first[i];
    for (q = c->sp0; q; q = q->next)
        for (i = 0; i < q->n; i++)
            sp[first[q->v[i].seg]++] = q->v[i];
    for (i = 0, j = 0; i < n; i++) {
        uint32_t j0 = j, prev = in[i].a, m0 = m;
        uint8_t bent = 0;
        for (; j < c->nsp && sp[j].seg == i; j++)
            bent |= (uint8_t)(all_cuts || sp[j].rounded);
        cut_order co;
        co.P = P;
        co.fwd = lex_cmp(P[in[i].a], P[in[i].b]) < 0;
        sort_cuts(sp + j0, sptmp, j - j0, &co);
        for (k = j0; k < j; k++) {
            emit_piece(pc, &m, P, prev, sp[k].pt, in[i].bld);
            prev = sp[k].pt;
        }
        emit_piece(pc, &m, P, prev, in[i].b, in[i].bld);
        for (k = m0; k < m; k++)
            dy[k] = bent;
    }
    *out = pc;
    *nout = m;
    *dirty = dy;
    return PLX_OK;
}

static void reset_cuts(split_ctx *c)
{
    c->sp0 = c->sp = NULL;
    c->pt0 = c->pt = NULL;
    c->nsp = 0;
}

/* Rounds of cuts at the contacts left among the pieces, until none is left.
 * A round's new crossings lie within a few ulps of the points rounded the
 * round before and only pieces near them are cut; a crossing rounded onto
 * a piece's end joins the pieces there, and a contact of two pieces always
 * really cuts one of them, so the bends die out within a few rounds (at
 * most 3 in the tests, see test_polar_robust). PLX_E_SCENE after
 * WALL_ROUNDS rounds is a safety net that no scene is known to reach. */
static plx_status settle_pieces(arena *a, split_ctx *c, piece **pc, uint32_t *np,
                                uint8_t **dirty, uint32_t *rounds)
{
    uint32_t r, i, nd;
    for (r = 0; r < WALL_ROUNDS; r++) {
        uint32_t *dl = scratch_n(a, *np, 4), nold = c->npts;
        dgrid g;
        plx_status st;
        if (!dl)
            return PLX_E_NOMEM;
        for (i = 0, nd = 0; i < *np; i++)
            if ((*dirty)[i])
                dl[nd++] = i;
        if (nd == 0)
            return PLX_OK;
        *rounds = r + 1;
        reset_cuts(c);
        st = dgrid_build(a, &g, c->pd->pts, *pc, dl, nd);
        if (st != PLX_OK)
            return st;
        meet_pieces(c, *pc, *np, *dirty, &g);
        if (c->nomem)
            return PLX_E_NOMEM;
        if (c->nsp == 0)
            return PLX_OK;
        st = flat_points(a, c, nold);
        if (st == PLX_OK)
            st = cut_pieces(a, c, *pc, *np, 1, pc, np, dirty);
        if (st != PLX_OK)
            return st;
    }
    return PLX_E_SCENE;
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
        vec2 a = fpt(pd, m->frame, g->a), b = fpt(pd, m->frame, g->b);
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
        vec2 f = fpt(pd, m->frame, p0 + i);
        if (lex_cmp(f, fpt(pd, m->frame, m->box_lo)) < 0)
            m->box_lo = p0 + i;
        if (lex_cmp(f, fpt(pd, m->frame, m->box_hi)) > 0)
            m->box_hi = p0 + i;
    }
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

/* ---- the grid of wall pieces ------------------------------------------ */

/* Cell (x, y) lists the pieces whose bounding boxes meet it,
 * wall[cell[y nx + x] .. cell[.. + 1]). Only for the reference locator
 * polar_scan (the construction uses none). */
typedef struct wgrid {
    uint32_t nx, ny;
    double sx, sy;           /* cells per metre */
    uint32_t *cell, *wall;
} wgrid;

/* n items of size bytes, scratch or kept (PLX_PART_POLAR, uncounted). */
static void *grid_n(arena *a, size_t n, size_t size, int keep)
{
    size_t bytes = arena_mul(n ? n : 1, size);
    if (bytes == SIZE_MAX)
        return NULL;
    return keep ? arena_alloc(a, PLX_PART_POLAR, bytes, 16) : arena_scratch(a, bytes, 16);
}

static uint32_t grid_cell(double v, double v0, double scale, uint32_t n)
{
    double c = floor((v - v0) * scale);
    if (!(c >= 0.0))
        return 0;
    if (c >= (double)n)
        return n - 1;
    return (uint32_t)c;
}

static uint32_t grid_x(const polar *pd, const wgrid *g, double x)
{
    return grid_cell(x, pd->box[0], g->sx, g->nx);
}

static uint32_t grid_y(const polar *pd, const wgrid *g, double y)
{
    return grid_cell(y, pd->box[1], g->sy, g->ny);
}

/* Every wall piece listed in the cells its bounding box meets (about two
 * pieces per cell). Cell functions are monotone, which is all wall_below
 * needs to stop its scan exactly. */
static plx_status build_grid(arena *a, const polar *pd, wgrid *g, int keep)
{
    double W = pd->box[2] - pd->box[0], H = pd->box[3] - pd->box[1];
    double side = sqrt(W * H / ((double)pd->nwall / 2.0 + 1.0));
    uint32_t nx = (uint32_t)fmin(fmax(ceil(W / side), 1.0), 2048.0);
    uint32_t ny = (uint32_t)fmin(fmax(ceil(H / side), 1.0), 2048.0);
    uint32_t ncell = nx * ny, s, i, x, y;
    uint32_t *cell;
    size_t total = 0;
    g->nx = nx;
    g->ny = ny;
    g->sx = (double)nx / W;
    g->sy = (double)ny / H;
    cell = grid_n(a, (size_t)ncell + 1, 4, keep);
    if (!cell)
        return PLX_E_NOMEM;
    memset(cell, 0, ((size_t)ncell + 1) * 4);
    for (s = 0; s < pd->nwall; s++) {
        vec2 p = pd->pts[pd->seg[s].a], q = pd->pts[pd->seg[s].b];
        uint32_t x0 = grid_x(pd, g, fmin(p.x, q.x)), x1 = grid_x(pd, g, fmax(p.x, q.x));
        uint32_t y0 = grid_y(pd, g, fmin(p.y, q.y)), y1 = grid_y(pd, g, fmax(p.y, q.y));
        for (y = y0; y <= y1; y++)
            for (x = x0; x <= x1; x++)
                cell[y * nx + x + 1]++;
        total += (size_t)(x1 - x0 + 1) * (y1 - y0 + 1);
    }
    if (total >= 0xffffffffu)
        return PLX_E_NOMEM;
    for (i = 0; i < ncell; i++)
        cell[i + 1] += cell[i];
    g->wall = grid_n(a, total, 4, keep);
    if (!g->wall)
        return PLX_E_NOMEM;
    for (s = 0; s < pd->nwall; s++) {
        vec2 p = pd->pts[pd->seg[s].a], q = pd->pts[pd->seg[s].b];
        uint32_t x0 = grid_x(pd, g, fmin(p.x, q.x)), x1 = grid_x(pd, g, fmax(p.x, q.x));
        uint32_t y0 = grid_y(pd, g, fmin(p.y, q.y)), y1 = grid_y(pd, g, fmax(p.y, q.y));
        for (y = y0; y <= y1; y++)
            for (x = x0; x <= x1; x++)
                g->wall[cell[y * nx + x]++] = s;
    }
    for (i = ncell; i > 0; i--)
        cell[i] = cell[i - 1];
    cell[0] = 0;
    g->cell = cell;
    return PLX_OK;
}

/* Is wall LR above wall BL-BR where both span a common frame abscissa
 * (lexicographically) and do not cross? */
static int seg_over(vec2 L, vec2 R, vec2 BL, vec2 BR)
{
    int c = lex_cmp(L, BL), o;
    if (c > 0) {
        o = geom_orient(BL, BR, L);
        return (o ? o : geom_orient(BL, BR, R)) > 0;
    }
    if (c < 0) {
        o = geom_orient(L, R, BL);
        return (o ? o : geom_orient(L, R, BR)) < 0;
    }
    return geom_orient(BL, BR, R) > 0;
}

/* The nearest wall piece below frame point f (frame "below": smaller v)
 * among those whose span holds f strictly (lexicographically), found by
 * scanning the grid column of f downwards and stopping as soon as no unseen
 * piece can be higher; POLAR_NONE when there is none (the Bounds side).
 * Sets *on and returns POLAR_NONE when f is on a piece or is the end of
 * one. O(1) expected for evenly spread walls, O(n) worst case. */
static uint32_t wall_below(const polar *pd, const wgrid *g, int frame, vec2 f, int *on)
{
    vec2 wp = polar_from_frame(frame, f), BL = f, BR = f;
    uint32_t best = POLAR_NONE, fixed, nx = g->nx;
    int32_t k, end, step;
    *on = 0;
    if (frame) {
        fixed = grid_x(pd, g, wp.x);
        k = (int32_t)grid_y(pd, g, wp.y);
        step = -1;
        end = -1;
    } else {
        fixed = grid_y(pd, g, wp.y);
        k = (int32_t)grid_x(pd, g, wp.x);
        step = 1;
        end = (int32_t)nx;
    }
    for (; k != end; k += step) {
        uint32_t cell = frame ? (uint32_t)k * nx + fixed : fixed * nx + (uint32_t)k, e;
        for (e = g->cell[cell]; e < g->cell[cell + 1]; e++) {
            uint32_t s = g->wall[e];
            vec2 L, R, wa = pd->pts[pd->seg[s].a], wb = pd->pts[pd->seg[s].b];
            int cl, cr, o;
            if (frame ? (wa.x < wp.x && wb.x < wp.x) || (wa.x > wp.x && wb.x > wp.x)
                      : (wa.y < wp.y && wb.y < wp.y) || (wa.y > wp.y && wb.y > wp.y))
                continue;      /* its frame abscissae miss f's */
            L = to_frame(frame, wa);
            R = to_frame(frame, wb);
            if (lex_cmp(L, R) > 0) {
                vec2 x = L;
                L = R;
                R = x;
            }
            cl = lex_cmp(f, L);
            cr = lex_cmp(f, R);
            if (cl == 0 || cr == 0) {
                *on = 1;
                return POLAR_NONE;
            }
            if (cl < 0 || cr > 0 || s == best)
                continue;
            o = geom_orient(L, R, f);
            if (o == 0) {
                *on = 1;
                return POLAR_NONE;
            }
            if (o > 0 && (best == POLAR_NONE || seg_over(L, R, BL, BR))) {
                best = s;
                BL = L;
                BR = R;
            }
        }
        if (best != POLAR_NONE) {
            double low = fmin(BL.y, BR.y);
            int32_t lim = frame ? (int32_t)grid_y(pd, g, low) : (int32_t)grid_x(pd, g, -low);
            if (frame ? k <= lim : k >= lim)
                break;
        }
    }
    return best;
}

/* ---- trapezoidal map construction: a plane sweep ---------------------- */

/* The sweep runs over the wall ends in frame order (lexicographic (u, v),
 * i.e. a sweep line turned by an infinitesimal angle, so equal u needs no
 * special case). The status is the list of wall pieces crossing the sweep
 * line, bottom to top, headed by the Bounds side at the bottom; between two
 * consecutive pieces lies one open trapezoid, which the next event between
 * them closes with the axis of that event's point. An event where pieces
 * end finds its place in the list through them; an event where pieces only
 * start reads the piece below it from the DAG's map, already built: the
 * floor of the trapezoid below the lowest piece starting there, at its
 * left end, which is the status piece below the point (no piece ends
 * there); it is checked to be in the status and strictly below the point,
 * and the piece above to be strictly above it. Pieces starting together
 * are sorted by merge sort (O(d log d) at a point of degree d), so the
 * sweep is O(n log n) worst case. Every gap it opens is looked up in the
 * DAG's map the same way and must be a trapezoid there with the same left
 * axis, floor and ceiling (and right axis, for free regions), each once,
 * all of them. Only free trapezoids are made: whether the gap above a
 * piece is solid is known when the piece enters the status (footprints
 * counted from the bottom, as the piece below plus the piece's own change).
 * Every decision is a geom_orient sign or a lexicographic comparison. */

/* A trapezoid of the search DAG's map (see "the search DAG" below). */
typedef struct btrap {
    vec2 rc;                 /* frame coordinates of rp (walks read them) */
    uint32_t lp, rp, top, bot;
    uint32_t nb[4];
    uint32_t leaf;           /* its leaf node (below 2^30); POLAR_NONE: slot
                              * free; once the map is built, the sweep
                              * replaces it by the trapezoid's child word
                              * (tag 1 or 2: set) */
} btrap;

/* The live trapezoids of the DAG's map by role (see walk_at), packed so
 * that one record serves a whole update. Per piece: its canonical ends
 * and the trapezoids above / below it at them; index 0: left end, 1:
 * right end. Per point: a trapezoid whose left (0) / right (1) axis is the
 * point's. POLAR_NONE: none yet. */
typedef struct sroles {
    uint32_t end[2], up[2], down[2];
} sroles;

typedef struct proles {
    uint32_t side[2];
} proles;

typedef struct snode {
    vec2 l, r;          /* frame ends, l before r */
    int32_t cov;        /* footprints covering the gap above it */
    uint32_t open;      /* the free region open above it, or POLAR_NONE */
    uint32_t prev, next; /* status list; prev == POLAR_NONE: not in it */
    uint32_t li, ri;    /* point indices of l and r */
    uint32_t solid;     /* child word of a solid trapezoid on it (search DAG) */
    uint32_t yk;        /* its search node kind: N_Y (l is seg.a) or N_YB */
} snode;

typedef struct fpoint {
    vec2 f;             /* frame coordinates */
    uint32_t i;         /* point index */
} fpoint;

typedef struct sweep {
    const polar *pd;
    polar_map *m;
    snode *N;           /* per segment (walls and Bounds sides) */
    polar_trap *T;
    uint32_t ntrap, cap;
    const uint32_t *inc_first, *inc; /* walls incident to each point */
    uint32_t *start, *tmp; /* scratch: pieces starting at the event */
    /* the final map of the search DAG: per piece the trapezoid below /
     * above it at its left end, per point one trapezoid with that left
     * axis; each gap the sweep opens is one of them, whose child word it
     * sets in word[], and regd[] keeps it per region */
    btrap *DT;
    const sroles *SR;
    const proles *PR;
    uint32_t *regd;
    uint32_t ngap;      /* gaps opened, free or solid */
    uint64_t steps;     /* status pieces walked and start pieces sorted */
} sweep;

static int fp_before(const fpoint *a, const fpoint *b, const void *ctx)
{
    (void)ctx;
    int c = lex_cmp(a->f, b->f);
    return c < 0 || (c == 0 && a->i < b->i);
}

MSORT_DEFINE(sort_fpoints, fpoint, const void *, fp_before)

static uint32_t new_region(sweep *w, uint32_t lp, uint32_t top, uint32_t bot)
{
    polar_trap *t;
    if (w->ntrap >= w->cap)
        return POLAR_NONE;
    t = &w->T[w->ntrap];
    t->lp = lp;
    t->rp = POLAR_NONE;
    t->top = top;
    t->bot = bot;
    t->nb[0] = t->nb[1] = t->nb[2] = t->nb[3] = POLAR_NONE;
    return w->ntrap++;
}

/* The gap above bot opened at point pi (below top) is trapezoid d of the
 * DAG's map: checked, and its child word set (region h, or solid).
 * Returns 0, or -1 when the two maps differ. */
static int open_gap(sweep *w, uint32_t d, uint32_t pi, uint32_t top, uint32_t bot, uint32_t h)
{
    btrap *t;
    if (d == POLAR_NONE)
        return -1;
    t = &w->DT[d];
    if (t->lp != pi || t->top != top || t->bot != bot || POLAR_TAG(t->leaf) != 0)
        return -1;
    t->leaf = h != POLAR_NONE ? PACK(POLAR_CHILD_FREE, h) : w->N[bot].solid;
    if (h != POLAR_NONE)
        w->regd[h] = d;
    w->ngap++;
    return 0;
}

/* Does piece y start below piece x (both starting at the same point)?
 * Sets *flat when they are collinear. */
static int start_below(const snode *N, uint32_t y, uint32_t x, int *flat)
{
    int o = geom_orient(N[y].l, N[y].r, N[x].r);
    if (o == 0)
        *flat = 1;
    return o > 0;
}

/* Sorts the n pieces w->start[] starting at one point bottom to top
 * (insertion sort for a few, else bottom-up merge sort: O(n log n) at a
 * point of any degree). Returns 0, or -1 when two are collinear (two
 * neighbours in the order are always compared, so it is seen). */
static int sort_starts(sweep *w, uint32_t n)
{
    const snode *N = w->N;
    uint32_t *src = w->start, *dst = w->tmp, i, j, wd;
    int flat = 0;
    for (i = 0; i < n; i += 8) {
        uint32_t e = i + 8 < n ? i + 8 : n;
        for (j = i + 1; j < e; j++) {
            uint32_t t = src[j], k = j;
            while (k > i && start_below(N, t, src[k - 1], &flat)) {
                src[k] = src[k - 1];
                k--;
            }
            src[k] = t;
        }
    }
    for (wd = 8; wd < n; wd *= 2) {
        for (i = 0; i < n; i += 2 * wd) {
            uint32_t a = i, am = i + wd < n ? i + wd : n, b = am, bm = i + 2 * wd < n ? i + 2 * wd : n;
            uint32_t o = i;
            while (a < am && b < bm)
                dst[o++] = start_below(N, src[b], src[a], &flat) ? src[b++] : src[a++];
            while (a < am)
                dst[o++] = src[a++];
            while (b < bm)
                dst[o++] = src[b++];
        }
        {
            uint32_t *t = src;
            src = dst;
            dst = t;
        }
    }
    if (src != w->start)
        memcpy(w->start, src, (size_t)n * 4);
    w->steps += n;
    return flat ? -1 : 0;
}

/* One event: the walls ending and starting at frame point P (point index
 * pi, the points pts[0..npts-1] all at P). Returns 0, or -1 when the walls
 * are not a planar subdivision (pieces crossing after rounding). */
static int sweep_event(sweep *w, vec2 P, uint32_t pi, const fpoint *pts, uint32_t npts)
{
    snode *N = w->N;
    const polar_map *m = w->m;
    uint32_t x, y, B, A, last = POLAR_NONE, some_end = POLAR_NONE, k = 0, nend = 0, ns = 0;
    uint32_t G0, Gk, H0 = POLAR_NONE, Hm = POLAR_NONE, i, j;
    /* the walls starting here, bottom to top; those ending here counted */
    for (i = 0; i < npts; i++) {
        uint32_t p = pts[i].i;
        for (j = w->inc_first[p]; j < w->inc_first[p + 1]; j++) {
            uint32_t s = w->inc[j];
            if (lex_cmp(N[s].l, P) == 0) {
                w->start[ns++] = s;
            } else {
                nend++;
                some_end = s;
            }
        }
    }
    if (ns > 1 && sort_starts(w, ns) != 0)
        return -1;
    /* B: the status piece below P */
    if (nend > 0) {
        x = some_end;
        if (N[x].prev == POLAR_NONE)
            return -1;
        while ((y = N[x].prev) != m->box_bot && lex_cmp(N[y].r, P) == 0)
            x = y;
        B = N[x].prev;
    } else {
        /* only starts: the floor of the trapezoid below the lowest piece
         * starting here, at its left end, in the DAG's map (the map has
         * every piece: that floor is the piece below P just right of P,
         * and no piece ends at P, so it is the status piece below P);
         * checked to be in the status and strictly below P */
        uint32_t d = ns ? w->SR[w->start[0]].down[0] : POLAR_NONE;
        if (d == POLAR_NONE)
            return -1;
        B = w->DT[d].bot;
        if (B != m->box_bot &&
            (B >= w->pd->nseg || N[B].prev == POLAR_NONE || geom_orient(N[B].l, N[B].r, P) <= 0))
            return -1;
    }
    /* the pieces ending at P follow B */
    for (y = N[B].next; y != POLAR_NONE && lex_cmp(N[y].r, P) == 0; y = N[y].next) {
        last = y;
        k++;
    }
    w->steps += k + ns;
    if (k != nend)
        return -1;
    A = y;
    if (A != POLAR_NONE && geom_orient(N[A].l, N[A].r, P) >= 0)
        return -1;
    /* close the gaps B..e1, e1..e2, ..., ek..A */
    G0 = N[B].open;
    Gk = k ? N[last].open : G0;
    if (G0 != POLAR_NONE)
        w->T[G0].rp = pi;
    for (y = N[B].next, i = 0; i < k; i++) {
        x = N[y].next;
        if (N[y].open != POLAR_NONE)
            w->T[N[y].open].rp = pi;
        N[y].prev = N[y].next = POLAR_NONE;
        y = x;
    }
    /* open the gaps B..s1, s1..s2, ..., sm..A and link s1..sm in */
    for (j = 0; j <= ns; j++) {
        uint32_t bot = j ? w->start[j - 1] : B;
        uint32_t top = j < ns ? w->start[j] : (A == POLAR_NONE ? m->box_top : A);
        uint32_t h = POLAR_NONE;
        if (j > 0) {
            const polar_seg *g = &w->pd->seg[bot];
            int32_t d = lex_cmp(fpt(w->pd, m->frame, g->a), P) == 0 ? g->cover : -g->cover;
            uint32_t below = j > 1 ? w->start[j - 2] : B;
            N[bot].cov = N[below].cov + d;
            N[bot].prev = below;
            N[below].next = bot;
        }
        if (N[bot].cov == 0) {
            h = new_region(w, pi, top, bot);
            if (h == POLAR_NONE)
                return -1;
        }
        if (open_gap(w, j ? w->SR[bot].up[0] : ns ? w->SR[w->start[0]].down[0] : w->PR[pi].side[0],
                     pi, top, bot, h) != 0)
            return -1;
        N[bot].open = h;
        if (j == 0)
            H0 = h;
        if (j == ns) {
            Hm = h;
            N[bot].next = A;
            if (A != POLAR_NONE)
                N[A].prev = bot;
        }
    }
    if (G0 != POLAR_NONE)
        w->T[G0].nb[LR] = H0;
    if (Gk != POLAR_NONE)
        w->T[Gk].nb[UR] = Hm;
    if (H0 != POLAR_NONE)
        w->T[H0].nb[LL] = G0;
    if (Hm != POLAR_NONE)
        w->T[Hm].nb[UL] = Gk;
    return 0;
}

/* Walls incident to each point (both frames), and the points that are
 * wall ends: the events of the sweeps. */
static plx_status build_incidence(arena *a, const polar *pd, uint32_t **inc_first,
                                  uint32_t **inc, uint32_t **evp, uint32_t *nev)
{
    uint32_t i, s, n = 0, *f, *v, *e;
    f = scratch_n(a, (size_t)pd->npts + 1, 4);
    v = scratch_n(a, (size_t)pd->nwall * 2, 4);
    e = scratch_n(a, pd->npts, 4);
    if (!f || !v || !e)
        return PLX_E_NOMEM;
    memset(f, 0, ((size_t)pd->npts + 1) * 4);
    for (s = 0; s < pd->nwall; s++) {
        f[pd->seg[s].a + 1]++;
        f[pd->seg[s].b + 1]++;
    }
    for (i = 0; i < pd->npts; i++) {
        if (f[i + 1] > 0)
            e[n++] = i;
        f[i + 1] += f[i];
    }
    for (s = 0; s < pd->nwall; s++) {
        v[f[pd->seg[s].a]++] = s;
        v[f[pd->seg[s].b]++] = s;
    }
    for (i = pd->npts; i > 0; i--)
        f[i] = f[i - 1];
    f[0] = 0;
    *inc_first = f;
    *inc = v;
    *evp = e;
    *nev = n;
    return PLX_OK;
}

/* ---- the search DAG ---------------------------------------------------- */

/* The trapezoidal map of the wall pieces built by randomized incremental
 * insertion (de Berg et al., ch. 6): every piece is located by its
 * frame-left end in the DAG built so far (a left end shared with an
 * earlier piece goes right at that point's x node, and at a y node of a
 * piece sharing it the other ends decide, i.e. the slopes), followed
 * through the trapezoids it crosses, and those are replaced by the pieces
 * left, right, above and below it (runs of pieces above or below whose
 * separating axis the new piece cuts away are merged, so one leaf may have
 * several parents). The order is random from a fixed seed (see
 * insertion_order), so the build is deterministic while the expected bounds
 * hold: O(n) nodes, O(log n) nodes on a search path, O(n log n) time. A
 * piece with an end already in the map (about two thirds: polygon edges
 * share their ends) is not searched in the DAG: the trapezoid holding its
 * start is found among the few around that end (walk_at: the map's live
 * trapezoids are kept by role, per point and per piece end, updated by
 * every insertion; a walk longer than WALK_MAX falls back to the DAG from
 * that end's x node), the others are searched from the root.
 * Measured (bench_polar): 4.4 to 4.9 inner nodes per piece (8 or 12
 * bytes each, see polar_map), search paths of about 2 log2 n nodes on
 * average. It runs first, on pieces not yet checked: a walk only moves to
 * a live neighbour sharing the axis it crosses (so it moves strictly
 * along the frame order and ends), every index stays in range, and a
 * failure is PLX_E_SCENE; the sweep then checks the result. Point indices
 * are canonical (the first of the points sharing a position, as the
 * sweep's events are). In the end every leaf becomes a child word, set by
 * the sweep when it opens that trapezoid as a gap: its free region, or the
 * owner that polar_locate reports inside a solid one. */

#define NODE_BITS 14
#define NODE_CHUNK (1u << NODE_BITS)

typedef struct dbuild {
    const polar *pd;
    arena *a;
    int frame;
    btrap *T;
    uint32_t ntrap, cap;     /* slots used, slots available */
    uint32_t *freel, nfree;  /* slots of replaced trapezoids */
    uint32_t (**chunk)[3];   /* nodes in chunks of NODE_CHUNK (scratch) */
    uint32_t nchunk, maxchunk, nnode;
    uint32_t *list, *up, *lo; /* per crossed trapezoid: it, its new upper / lower part */
    const uint32_t *canon;   /* per point: the first point at its position */
    const snode *N;          /* per piece: the sweep's data (y test kind) */
    const vec2 *E;           /* per piece: frame ends, left then right */
    /* the live trapezoids by role, kept up to date by every insertion */
    sroles *SR;
    proles *PR;
    vec2 P, Q;               /* the piece being inserted: its frame ends */
    uint32_t *hint;          /* per canonical point: its x node, POLAR_NONE */
    int fail;                /* 1: out of memory, 2: pieces not planar */
    uint64_t steps;          /* search nodes and trapezoids visited */
} dbuild;

static uint32_t *dnode(const dbuild *b, uint32_t n)
{
    return b->chunk[n >> NODE_BITS][n & (NODE_CHUNK - 1)];
}

static vec2 bpt(const dbuild *b, uint32_t i)
{
    return fpt(b->pd, b->frame, i);
}

static uint32_t new_trap(dbuild *b)
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
    b->T[t].nb[0] = b->T[t].nb[1] = b->T[t].nb[2] = b->T[t].nb[3] = POLAR_NONE;
    b->T[t].leaf = POLAR_NONE;
    return t;
}

static uint32_t new_node(dbuild *b, uint32_t kind, uint32_t idx, uint32_t c0, uint32_t c1)
{
    uint32_t n = b->nnode, *nd;
    if (n == b->nchunk * NODE_CHUNK) {
        if (b->nchunk == b->maxchunk ||
            !(b->chunk[b->nchunk] = arena_scratch(b->a, (size_t)NODE_CHUNK * 12, 16))) {
            b->fail = 1;
            return 0;
        }
        b->nchunk++;
    }
    b->nnode++;
    nd = dnode(b, n);
    nd[0] = PACK(kind, idx);
    nd[1] = c0;
    nd[2] = c1;
    return n;
}

/* The y test of piece s: its kind by which end is frame-left. */
static uint32_t ykind(const dbuild *b, uint32_t s)
{
    return b->N[s].yk;
}

/* One insertion, its data gathered beforehand (in insertion order). */
typedef struct irec {
    vec2 P, Q;               /* frame ends, left first */
    uint32_t s, l, r;        /* the piece, its canonical end points */
} irec;

/* Descends the DAG with the left end P of a new piece PQ, from node n:
 * the root, or the x node of P if P is already in the map (its cell, the
 * trapezoid that held P when it came in, holds everything just right of P). */
static uint32_t find_first(dbuild *b, uint32_t n, vec2 P, vec2 Q)
{
    for (;; b->steps++) {
        const uint32_t *nd = dnode(b, n);
        uint32_t w = nd[0];
        if (KIND(w) == N_LEAF)
            return IDX(w);
        if (KIND(w) == N_X) {
            n = lex_cmp(P, bpt(b, IDX(w))) < 0 ? nd[1] : nd[2];
        } else {
            const vec2 *g = &b->E[2 * (size_t)IDX(w)];
            int o = geom_orient(g[0], g[1], P);
            if (o == 0)
                o = geom_orient(g[0], g[1], Q);   /* a shared left end: the slopes */
            if (o == 0) {
                b->fail = 2;
                return POLAR_NONE;
            }
            n = o > 0 ? nd[2] : nd[1];
        }
    }
}

/* The same from the right end Q of the new piece, known to the map: from
 * its x node, with Q pushed towards P (ties at Q go left). */
static uint32_t find_last(dbuild *b, uint32_t n, vec2 Q, vec2 P)
{
    for (;; b->steps++) {
        const uint32_t *nd = dnode(b, n);
        uint32_t w = nd[0];
        if (KIND(w) == N_LEAF)
            return IDX(w);
        if (KIND(w) == N_X) {
            n = lex_cmp(Q, bpt(b, IDX(w))) <= 0 ? nd[1] : nd[2];
        } else {
            const vec2 *g = &b->E[2 * (size_t)IDX(w)];
            int o = geom_orient(g[0], g[1], Q);
            if (o == 0)
                o = geom_orient(g[0], g[1], P);
            if (o == 0) {
                b->fail = 2;
                return POLAR_NONE;
            }
            n = o > 0 ? nd[2] : nd[1];
        }
    }
}

/* Replaces the neighbour link 'old' of trapezoid x on side f. */
static void relink(dbuild *b, uint32_t x, int f, uint32_t old, uint32_t nw)
{
    if (x != POLAR_NONE && b->T[x].nb[f] == old)
        b->T[x].nb[f] = nw;
}

static void set_trap(dbuild *b, uint32_t t, uint32_t lp, uint32_t rp, vec2 rc, uint32_t top,
                     uint32_t bot)
{
    b->T[t].lp = lp;
    b->T[t].rp = rp;
    b->T[t].rc = rc;
    b->T[t].top = top;
    b->T[t].bot = bot;
}

/* Records trapezoid t (just made, its sides final) in the roles it holds. */
static void note_trap(dbuild *b, uint32_t t)
{
    const btrap *x = &b->T[t];
    sroles *top = &b->SR[x->top], *bot = &b->SR[x->bot];
    b->PR[x->lp].side[0] = t;
    b->PR[x->rp].side[1] = t;
    if (top->end[0] == x->lp)
        top->down[0] = t;
    if (top->end[1] == x->rp)
        top->down[1] = t;
    if (bot->end[0] == x->lp)
        bot->up[0] = t;
    if (bot->end[1] == x->rp)
        bot->up[1] = t;
}

/* The trapezoid holding the points just right of end point p of the new
 * piece (p = its left end, towards D = its right end Q) or just left of it
 * (right end, towards D = P), p being in the map already: from one
 * trapezoid whose axis on that side is p's, up or down across the pieces
 * ending at p (the trapezoids by role), in O(1) per piece at p; at most
 * WALK_MAX of them, else (or on anything unexpected) POLAR_NONE and the
 * DAG is searched instead. */
#define WALK_MAX 12
static uint32_t walk_at(dbuild *b, uint32_t p, vec2 D, int right)
{
    int k = right ? 0 : 1;
    uint32_t t = b->PR[p].side[k], n;
    for (n = 0; n < WALK_MAX && t != POLAR_NONE; n++) {
        const btrap *x = &b->T[t];
        uint32_t e = right ? x->lp : x->rp;
        const vec2 *g;
        int o;
        if (x->leaf == POLAR_NONE || e != p)
            return POLAR_NONE;
        b->steps++;
        if (b->SR[x->top].end[k] == p) {
            g = &b->E[2 * (size_t)x->top];
            o = geom_orient(g[0], g[1], D);
            if (o == 0)
                return POLAR_NONE;    /* overlapping pieces: the DAG says so */
            if (o > 0) {
                t = b->SR[x->top].up[k];
                continue;
            }
        }
        if (b->SR[x->bot].end[k] == p) {
            g = &b->E[2 * (size_t)x->bot];
            o = geom_orient(g[0], g[1], D);
            if (o == 0)
                return POLAR_NONE;
            if (o < 0) {
                t = b->SR[x->bot].down[k];
                continue;
            }
        }
        return t;
    }
    return POLAR_NONE;
}

/* Follows the new piece leftwards from the trapezoid t holding its right
 * end r; returns k, the trapezoids crossed being list[0..k], left first. */
static uint32_t follow_back(dbuild *b, uint32_t t, vec2 P, vec2 Q)
{
    uint32_t k = 0, i;
    b->list[0] = t;
    while (lex_cmp(P, bpt(b, b->T[t].lp)) < 0) {
        int o = geom_orient(P, Q, bpt(b, b->T[t].lp));
        uint32_t nx = o > 0 ? b->T[t].nb[LL] : b->T[t].nb[UL];
        /* the neighbour must be live and share the axis: the walk moves
         * strictly leftwards, whatever the input */
        if (o == 0 || nx == POLAR_NONE || k + 1 >= b->cap || b->T[nx].leaf == POLAR_NONE ||
            b->T[nx].rp != b->T[t].lp) {
            b->fail = 2;
            return k;
        }
        b->list[++k] = t = nx;
    }
    for (i = 0; i < k - i; i++) {
        uint32_t x = b->list[i];
        b->list[i] = b->list[k - i];
        b->list[k - i] = x;
    }
    return k;
}

/* Follows the new piece (ends l < r) through the map; returns k, the
 * trapezoids crossed being list[0..k]. The search starts at the x node of
 * l, or of r when only r is in the map (then the piece is followed
 * leftwards), or at the root. */
static uint32_t follow(dbuild *b, uint32_t l, uint32_t r)
{
    vec2 P = b->P, Q = b->Q;
    uint32_t k = 0;
    if (b->hint[l] == POLAR_NONE && b->hint[r] != POLAR_NONE) {
        uint32_t t = walk_at(b, r, P, 0);
        if (t == POLAR_NONE)
            t = find_last(b, b->hint[r], Q, P);
        return b->fail ? 0 : follow_back(b, t, P, Q);
    }
    b->list[0] = b->hint[l] != POLAR_NONE ? walk_at(b, l, Q, 1) : POLAR_NONE;
    if (b->list[0] == POLAR_NONE)
        b->list[0] = find_first(b, b->hint[l] != POLAR_NONE ? b->hint[l] : 0, P, Q);
    if (b->fail)
        return 0;
    while (lex_cmp(Q, b->T[b->list[k]].rc) > 0) {
        uint32_t t = b->list[k], nx;
        int o = geom_orient(P, Q, b->T[t].rc);
        nx = o > 0 ? b->T[t].nb[LR] : b->T[t].nb[UR];
        if (o == 0 || nx == POLAR_NONE || k + 1 >= b->cap || b->T[nx].leaf == POLAR_NONE ||
            b->T[nx].lp != b->T[t].rp) {
            b->fail = 2;
            return k;
        }
        b->list[++k] = nx;
    }
    return k;
}

/* Builds the chain of new trapezoids above (up = 1) or below the piece. */
static void make_chain(dbuild *b, uint32_t s, uint32_t l, uint32_t r, uint32_t k, int up)
{
    vec2 P = b->P, Q = b->Q;
    uint32_t *part = up ? b->up : b->lo;
    uint32_t j, cur = new_trap(b);
    int fo = up ? UL : LL, fc = up ? UR : LR;     /* outer-side links */
    if (b->fail)
        return;
    if (up)
        set_trap(b, cur, l, r, Q, b->T[b->list[0]].top, s);
    else
        set_trap(b, cur, l, r, Q, s, b->T[b->list[0]].bot);
    part[0] = cur;
    for (j = 0; j < k; j++) {
        uint32_t t = b->list[j], t1 = b->list[j + 1], R = b->T[t].rp, nx, x;
        int o = geom_orient(P, Q, b->T[t].rc);
        if ((o > 0) != (up != 0)) {
            part[j + 1] = cur;        /* the axis at R is cut away: merge */
            continue;
        }
        b->T[cur].rp = R;
        b->T[cur].rc = b->T[t].rc;
        nx = new_trap(b);
        if (b->fail)
            return;
        if (up)
            set_trap(b, nx, R, r, Q, b->T[t1].top, s);
        else
            set_trap(b, nx, R, r, Q, s, b->T[t1].bot);
        x = b->T[t].nb[fc];
        b->T[cur].nb[fc] = x;
        relink(b, x, fo, t, cur);
        b->T[cur].nb[up ? LR : UR] = nx;
        b->T[nx].nb[up ? LL : UL] = cur;
        x = b->T[t1].nb[fo];
        b->T[nx].nb[fo] = x;
        relink(b, x, fc, t1, nx);
        cur = nx;
        part[j + 1] = cur;
    }
}

/* Links the new trapezoids at one end of the inserted piece: E (the old
 * first / last crossed trapezoid) had neighbours enb on that side; X is
 * the new trapezoid beyond the end or POLAR_NONE; U, L the new parts above
 * and below at that end. left: the left end. */
static void link_end(dbuild *b, int left, uint32_t E, const uint32_t *enb, uint32_t X,
                     uint32_t U, uint32_t L)
{
    int ou = left ? UL : UR, ol = left ? LL : LR;     /* outer sides */
    int iu = left ? UR : UL, il = left ? LR : LL;     /* their far sides */
    if (X != POLAR_NONE) {
        b->T[X].nb[ou] = enb[ou];
        b->T[X].nb[ol] = enb[ol];
        relink(b, enb[ou], iu, E, X);
        relink(b, enb[ou], il, E, X);
        relink(b, enb[ol], iu, E, X);
        relink(b, enb[ol], il, E, X);
        b->T[X].nb[iu] = U;
        b->T[X].nb[il] = L;
        b->T[U].nb[ou] = X;
        b->T[L].nb[ol] = X;
    } else {
        b->T[U].nb[ou] = enb[ou];
        b->T[L].nb[ol] = enb[ol];
        relink(b, enb[ou], iu, E, U);
        relink(b, enb[ou], il, E, L);
        relink(b, enb[ol], iu, E, U);
        relink(b, enb[ol], il, E, L);
    }
}

static void leaf_of(dbuild *b, uint32_t t)
{
    if (t != POLAR_NONE && b->T[t].leaf == POLAR_NONE)
        b->T[t].leaf = new_node(b, N_LEAF, t, 0, 0);
}

/* The old leaf n of crossed trapezoid j becomes the search for its parts:
 * x tests at new ends (A left, B right), then the y test of s. */
static void replace_leaf(dbuild *b, uint32_t s, uint32_t l, uint32_t r, uint32_t n, uint32_t j,
                         uint32_t A, uint32_t B)
{
    uint32_t y0 = b->T[b->lo[j]].leaf, y1 = b->T[b->up[j]].leaf, inner, xq, *nd;
    uint32_t ky = ykind(b, s);
    if (A == POLAR_NONE && B == POLAR_NONE) {
        nd = dnode(b, n);
        nd[0] = PACK(ky, s);
        nd[1] = y0;
        nd[2] = y1;
        return;
    }
    inner = new_node(b, ky, s, y0, y1);
    if (A != POLAR_NONE) {
        xq = B != POLAR_NONE ? new_node(b, N_X, r, inner, b->T[B].leaf) : inner;
        if (b->fail)
            return;
        nd = dnode(b, n);
        nd[0] = PACK(N_X, l);
        nd[1] = b->T[A].leaf;
        nd[2] = xq;
        b->hint[l] = n;
        if (B != POLAR_NONE)
            b->hint[r] = xq;
    } else if (!b->fail) {
        nd = dnode(b, n);
        nd[0] = PACK(N_X, r);
        nd[1] = inner;
        nd[2] = b->T[B].leaf;
        b->hint[r] = n;
    }
}

/* Inserts wall piece s (raw ends rl < rr in the frame). */
static void insert_seg(dbuild *b, const irec *in)
{
    uint32_t s = in->s, l = in->l, r = in->r, k, j, first, last;
    uint32_t A = POLAR_NONE, B = POLAR_NONE, fnb[4], lnb[4];
    b->P = in->P;
    b->Q = in->Q;
    k = follow(b, l, r);
    if (b->fail)
        return;
    b->steps += k + 1;
    first = b->list[0];
    last = b->list[k];
    for (j = 0; j < 4; j++) {
        fnb[j] = b->T[first].nb[j];
        lnb[j] = b->T[last].nb[j];
    }
    /* the first trapezoid holds l (its left axis at or before l), the
     * last r: A, B are needed unless those axes are l's and r's own
     * (canonical indices: one index per position) */
    if (l != b->T[first].lp) {
        A = new_trap(b);
        if (!b->fail)
            set_trap(b, A, b->T[first].lp, l, b->P, b->T[first].top, b->T[first].bot);
    }
    if (!b->fail && r != b->T[last].rp) {
        B = new_trap(b);
        if (!b->fail)
            set_trap(b, B, r, b->T[last].rp, b->T[last].rc, b->T[last].top, b->T[last].bot);
    }
    if (!b->fail)
        make_chain(b, s, l, r, k, 1);
    if (!b->fail)
        make_chain(b, s, l, r, k, 0);
    if (b->fail)
        return;
    link_end(b, 1, first, fnb, A, b->up[0], b->lo[0]);
    link_end(b, 0, last, lnb, B, b->up[k], b->lo[k]);
    leaf_of(b, A);
    leaf_of(b, B);
    for (j = 0; j <= k; j++) {
        leaf_of(b, b->up[j]);
        leaf_of(b, b->lo[j]);
    }
    for (j = 0; j <= k && !b->fail; j++) {
        uint32_t t = b->list[j];
        replace_leaf(b, s, l, r, b->T[t].leaf, j, j == 0 ? A : POLAR_NONE,
                     j == k ? B : POLAR_NONE);
        b->T[t].leaf = POLAR_NONE;
        b->freel[b->nfree++] = t;
    }
    if (A != POLAR_NONE)
        note_trap(b, A);
    if (B != POLAR_NONE)
        note_trap(b, B);
    for (j = 0; j <= k; j++) {
        if (j == 0 || b->up[j] != b->up[j - 1])
            note_trap(b, b->up[j]);
        if (j == 0 || b->lo[j] != b->lo[j - 1])
            note_trap(b, b->lo[j]);
    }
}

static uint64_t rng_step(uint64_t *st)
{
    uint64_t x = *st;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *st = x;
    return x;
}

/* Child word c (tag << 30 | index) in the narrow form, tag << 19 | index. */
static uint64_t narrow_child(uint32_t c)
{
    return (uint64_t)(POLAR_TAG(c) << 19 | POLAR_IDX(c));
}

/* Stores inner node j of m: test t, children c0, c1 (32-bit forms). */
static void put_node(polar_map *m, uint32_t j, uint32_t t, uint32_t c0, uint32_t c1)
{
    if (m->narrow) {
        uint64_t x = (uint64_t)(KIND(t) << 20 | IDX(t)) | narrow_child(c0) << 22 |
                     narrow_child(c1) << 43;
        m->node[2 * (size_t)j] = (uint32_t)x;
        m->node[2 * (size_t)j + 1] = (uint32_t)(x >> 32);
    } else {
        m->node[3 * (size_t)j] = t;
        m->node[3 * (size_t)j + 1] = c0;
        m->node[3 * (size_t)j + 2] = c1;
    }
}

/* Leaves to child words (set by the sweep in the trapezoids' leaf field),
 * the inner nodes kept in the order they were made (the top levels first;
 * with the insertion order, nodes made together lie together), narrow when
 * every index fits, and counted in polar_memory (rest). */
static plx_status dag_keep(arena *a, polar *pd, polar_map *m, dbuild *b, int flags)
{
    uint32_t i, j, nq = 0, *fw = scratch_n(a, b->nnode, 4);
    if (!fw)
        return PLX_E_NOMEM;
    /* fw: per build node its child word */
    for (i = 0; i < b->nnode; i++) {
        uint32_t w0 = dnode(b, i)[0];
        if (KIND(w0) != N_LEAF)
            fw[i] = PACK(POLAR_CHILD_NODE, nq++);
        else if (POLAR_TAG(fw[i] = b->T[IDX(w0)].leaf) == POLAR_CHILD_NODE)
            return PLX_E_SCENE;
    }
    m->nnode = nq;
    m->narrow = !(flags & POLAR_BUILD_WIDE_DAG) && nq < (1u << 19) && m->ntrap < (1u << 19) &&
                pd->nbld < (1u << 19) - 1 && pd->npts < (1u << 20) && pd->nseg < (1u << 20);
    m->node = keep_n(a, nq, m->narrow ? 8 : 12, &pd->bytes[3]);
    if (!m->node)
        return PLX_E_NOMEM;
    for (i = 0, j = 0; i < b->nnode; i++) {
        const uint32_t *nd = dnode(b, i);
        if (KIND(nd[0]) == N_LEAF)
            continue;
        put_node(m, j++, nd[0], fw[nd[1]], fw[nd[2]]);
    }
    m->root = fw[0];
    return PLX_OK;
}

static uint32_t spread16(uint32_t x)
{
    x &= 0xffffu;
    x = (x | (x << 8)) & 0x00ff00ffu;
    x = (x | (x << 4)) & 0x0f0f0f0fu;
    x = (x | (x << 2)) & 0x33333333u;
    x = (x | (x << 1)) & 0x55555555u;
    return x;
}

/* The insertion order of the wall pieces, shared by both maps: a biased
 * randomized insertion order (Amenta, Choi, Rote 2003). Every piece draws
 * a round from a seeded generator (the last round holds about half of
 * them, the one before a quarter, ...); rounds go in order and, within a
 * round, pieces follow a Z-order curve of their midpoints. The rounds are
 * random samples, which keeps the expected bounds of randomized
 * incremental construction (size, search path length); the spatial order
 * within a round makes consecutive insertions walk the same nodes (cache
 * hits). Sorted by a stable radix sort on 64-bit keys (ties: piece
 * order). Deterministic: no global state. */
static plx_status insertion_order(arena *a, const polar *pd, uint32_t **out)
{
    uint32_t i, n = pd->nwall, d, *order = scratch_n(a, n, 4), *o2 = scratch_n(a, n, 4);
    uint64_t *key = scratch_n(a, n, 8), *k2 = scratch_n(a, n, 8);
    uint32_t *cnt = scratch_n(a, 65536, 4);
    uint64_t seed = 0x9e3779b97f4a7c15ull;
    double sx = 65535.0 / (pd->box[2] - pd->box[0]), sy = 65535.0 / (pd->box[3] - pd->box[1]);
    if (!order || !o2 || !key || !k2 || !cnt)
        return PLX_E_NOMEM;
    for (i = 0; i < n; i++) {
        const polar_seg *g = &pd->seg[i];
        vec2 pa = pd->pts[g->a], pb = pd->pts[g->b];
        uint64_t r = rng_step(&seed) >> 20;
        uint32_t round = 0, ux, uy;
        double mx = 0.5 * (pa.x + pb.x) - pd->box[0], my = 0.5 * (pa.y + pb.y) - pd->box[1];
        while (round < 40 && (r & 1u)) {   /* round 40 - t with probability 2^-(t+1) */
            round++;
            r >>= 1;
        }
        ux = (uint32_t)fmin(fmax(mx * sx, 0.0), 65535.0);
        uy = (uint32_t)fmin(fmax(my * sy, 0.0), 65535.0);
        /* round (6 bits), then the Z-order of the midpoint (32) */
        key[i] = (uint64_t)(40 - round) << 32 | (uint64_t)(spread16(ux) | (spread16(uy) << 1));
        order[i] = i;
    }
    for (d = 0; d < 48; d += 16) {          /* LSD radix sort, 16 bits a pass */
        memset(cnt, 0, 65536 * 4);
        for (i = 0; i < n; i++)
            cnt[(key[i] >> d) & 0xffff]++;
        {
            uint32_t sum = 0, c;
            for (i = 0; i < 65536; i++) {
                c = cnt[i];
                cnt[i] = sum;
                sum += c;
            }
        }
        for (i = 0; i < n; i++) {
            uint32_t at = cnt[(key[i] >> d) & 0xffff]++;
            k2[at] = key[i];
            o2[at] = order[i];
        }
        {
            uint64_t *tk = key;
            uint32_t *to = order;
            key = k2;
            k2 = tk;
            order = o2;
            o2 = to;
        }
    }
    *out = order;
    return PLX_OK;
}

/* Asks the cache for what insertion in will read first (a hint only;
 * nothing where the compiler offers no prefetch). */
static void prefetch_roles(const dbuild *b, const irec *in)
{
#if defined(__GNUC__)
    __builtin_prefetch(&b->PR[in->l]);
    __builtin_prefetch(&b->PR[in->r]);
    __builtin_prefetch(&b->hint[in->l]);
#else
    (void)b;
    (void)in;
#endif
}

/* Builds the trapezoidal map of the wall pieces of m and its search DAG by
 * randomized incremental insertion, into b (scratch). N: the pieces' frame
 * ends (the sweep's snodes). */
static plx_status build_dag(arena *a, polar *pd, polar_map *m, dbuild *b, const snode *N,
                            const uint32_t *canon, const uint32_t *order, uint32_t nends)
{
    uint32_t nw = pd->nwall, i, t;
    vec2 *E;
    irec *rec;
    if (nw >= (1u << 26) || pd->npts >= (1u << 26))
        return PLX_E_NOMEM;   /* indices must fit in 30 bits */
    memset(b, 0, sizeof *b);
    b->pd = pd;
    b->a = a;
    b->frame = m->frame;
    b->canon = canon;
    b->N = N;
    /* trapezoid slots: at most 3 i + 1 live after i pieces; a new piece
     * crosses one trapezoid more than the axes it cuts, at most one per
     * wall end, and makes two per crossed one plus two: 3 n + 2 ends + 64 */
    b->cap = 3 * nw + 2 * nends + 64;
    /* expected about 8 nodes per piece; beyond 64 the shuffle has failed
     * beyond any reasonable chance (reported as out of memory) */
    b->maxchunk = (uint32_t)(((uint64_t)64 * nw + 1024) >> NODE_BITS) + 1;
    if (b->maxchunk > (1u << (30 - NODE_BITS)))
        b->maxchunk = 1u << (30 - NODE_BITS);
    b->T = scratch_n(a, b->cap, sizeof(btrap));
    b->freel = scratch_n(a, b->cap, 4);
    b->list = scratch_n(a, b->cap, 4);
    b->up = scratch_n(a, b->cap, 4);
    b->lo = scratch_n(a, b->cap, 4);
    b->chunk = scratch_n(a, b->maxchunk, sizeof *b->chunk);
    b->hint = scratch_n(a, pd->npts, 4);
    b->E = E = scratch_n(a, 2 * (size_t)pd->nseg, sizeof(vec2));
    b->SR = scratch_n(a, pd->nseg, sizeof(sroles));
    b->PR = scratch_n(a, pd->npts, sizeof(proles));
    rec = scratch_n(a, nw, sizeof(irec));
    if (!b->T || !b->freel || !b->list || !b->up || !b->lo || !b->chunk || !b->hint || !E ||
        !b->SR || !b->PR || !rec)
        return PLX_E_NOMEM;
    memset(b->SR, 0xff, (size_t)pd->nseg * sizeof(sroles));
    memset(b->PR, 0xff, (size_t)pd->npts * sizeof(proles));
    /* what the insertions read, packed: the ends of every piece, and per
     * insertion its piece (gathered here, where the loads do not wait on
     * one another) */
    for (i = 0; i < pd->nseg; i++) {
        E[2 * (size_t)i] = N[i].l;
        E[2 * (size_t)i + 1] = N[i].r;
        b->SR[i].end[0] = canon[N[i].li];
        b->SR[i].end[1] = canon[N[i].ri];
    }
    for (i = 0; i < nw; i++) {
        const snode *g = &N[order[i]];
        rec[i].P = g->l;
        rec[i].Q = g->r;
        rec[i].s = order[i];
        rec[i].l = canon[g->li];
        rec[i].r = canon[g->ri];
    }
    memset(b->hint, 0xff, (size_t)pd->npts * 4);
    t = new_trap(b);
    set_trap(b, t, m->box_lo, m->box_hi, bpt(b, m->box_hi), m->box_top, m->box_bot);
    b->T[t].leaf = new_node(b, N_LEAF, t, 0, 0);
    note_trap(b, t);
    for (i = 0; i < nw && !b->fail; i++) {
        if (i + 8 < nw)
            prefetch_roles(b, &rec[i + 8]);
        insert_seg(b, &rec[i]);
    }
    if (b->fail)
        return b->fail == 1 ? PLX_E_NOMEM : PLX_E_SCENE;
    return PLX_OK;
}

/* Builds the trapezoidal map of one frame: the search DAG's map by
 * randomized insertion, then the sweep, which uses it to place the events
 * where pieces only start, checks that the pieces form a planar
 * subdivision and that both maps agree, and makes the free regions (kept,
 * in sweep order, with their adjacency); then the DAG is kept with its
 * leaves mapped to those regions (unless flags say otherwise). */
static plx_status build_map(arena *a, polar *pd, polar_map *m, const uint32_t *inc_first,
                            const uint32_t *inc, const uint32_t *evp, uint32_t nev,
                            const uint32_t *order, int flags, uint64_t *steps)
{
    sweep w;
    dbuild b;
    fpoint *ev, *tmp;
    uint32_t i, j, s, t, *canon, nlive;
    plx_status st;
    memset(&w, 0, sizeof w);
    w.pd = pd;
    w.m = m;
    w.inc_first = inc_first;
    w.inc = inc;
    w.cap = 3 * pd->nwall + 8;
    w.N = scratch_n(a, pd->nseg, sizeof(snode));
    w.T = scratch_n(a, w.cap, sizeof(polar_trap));
    w.start = scratch_n(a, pd->nwall + 1, 4);
    w.tmp = scratch_n(a, pd->nwall + 1, 4);
    ev = scratch_n(a, nev, sizeof(fpoint));
    tmp = scratch_n(a, nev, sizeof(fpoint));
    canon = scratch_n(a, pd->npts, 4);
    if (!w.N || !w.T || !w.start || !w.tmp || !ev || !tmp || !canon)
        return PLX_E_NOMEM;
    frame_box(pd, m);
    for (s = 0; s < pd->nseg; s++) {
        uint32_t l, r;
        seg_ends(pd, m->frame, s, &l, &r);
        w.N[s].l = fpt(pd, m->frame, l);
        w.N[s].r = fpt(pd, m->frame, r);
        w.N[s].li = l;
        w.N[s].ri = r;
        {
            /* polar_locate's owner inside the solid above s: the footprint
             * entered across s, if any (see locate in polar_scan) */
            const polar_seg *gs = &pd->seg[s];
            int32_t own = (l == gs->a ? gs->cover : -gs->cover) > 0 && gs->bld[0] >= 0 ? gs->bld[0]
                                                                                     : -1;
            w.N[s].solid = PACK(POLAR_CHILD_SOLID, (uint32_t)(own + 1));
            w.N[s].yk = l == gs->a ? N_Y : N_YB;
        }
        w.N[s].cov = 0;
        w.N[s].open = POLAR_NONE;
        w.N[s].prev = w.N[s].next = POLAR_NONE;
    }
    for (i = 0; i < nev; i++) {
        ev[i].f = fpt(pd, m->frame, evp[i]);
        ev[i].i = evp[i];
    }
    sort_fpoints(ev, tmp, nev, NULL);
    for (i = 0; i < pd->npts; i++)
        canon[i] = i;
    for (i = 0; i < nev; i = j)
        for (j = i + 1; j < nev && lex_cmp(ev[j].f, ev[i].f) == 0; j++)
            canon[ev[j].i] = ev[i].i;
    st = build_dag(a, pd, m, &b, w.N, canon, order, nev);
    if (st != PLX_OK)
        return st;
    w.DT = b.T;
    w.SR = b.SR;
    w.PR = b.PR;
    nlive = b.ntrap - b.nfree;
    w.regd = scratch_n(a, w.cap, 4);
    if (!w.regd)
        return PLX_E_NOMEM;
    w.N[m->box_bot].open = new_region(&w, m->box_lo, m->box_top, m->box_bot);
    if (open_gap(&w, b.SR[m->box_bot].up[0], m->box_lo, m->box_top, m->box_bot,
                 w.N[m->box_bot].open) != 0)
        return PLX_E_SCENE;
    for (i = 0; i < nev; i = j) {
        for (j = i + 1; j < nev && lex_cmp(ev[j].f, ev[i].f) == 0; j++)
            ;
        if (sweep_event(&w, ev[i].f, ev[i].i, ev + i, j - i) != 0)
            return PLX_E_SCENE;
    }
    if (w.N[m->box_bot].next != POLAR_NONE || w.N[m->box_bot].open == POLAR_NONE)
        return PLX_E_SCENE;
    w.T[w.N[m->box_bot].open].rp = m->box_hi;
    /* both maps the same: every live trapezoid of the DAG's map is one gap
     * of the sweep, with the same sides */
    for (t = 0; t < w.ntrap; t++)
        if (w.T[t].rp == POLAR_NONE || b.T[w.regd[t]].rp != w.T[t].rp)
            return PLX_E_SCENE;
    if (w.ngap != nlive)
        return PLX_E_SCENE;
    *steps += w.steps + b.steps;
    m->ntrap = w.ntrap;
    m->trap = keep_n(a, w.ntrap, sizeof(polar_trap), &pd->bytes[0]);
    if (!m->trap)
        return PLX_E_NOMEM;
    memcpy(m->trap, w.T, (size_t)w.ntrap * sizeof(polar_trap));
    /* polar_memory: the axes (lp, rp, nb) and the regions (top, bot) */
    pd->bytes[0] -= (size_t)w.ntrap * 8;
    pd->bytes[1] += (size_t)w.ntrap * 8;
    if (flags & POLAR_BUILD_NO_DAG)
        return PLX_OK;
    return dag_keep(a, pd, m, &b, flags);
}

/* The occluders' edges as pieces, uncut. */
static piece *edge_pieces(arena *a, const edges *e)
{
    piece *pc = scratch_n(a, e->n, sizeof(piece));
    uint32_t i;
    if (!pc)
        return NULL;
    for (i = 0; i < e->n; i++) {
        pc[i].a = pc[i].lo = e->a[i];
        pc[i].b = pc[i].hi = e->b[i];
        pc[i].bld = e->bld[i];
    }
    return pc;
}

/* Cuts the occluders' edges into wall pieces that meet only at their ends:
 * first at every contact of two buildings' edges, then at the contacts the
 * rounded crossing points make among the pieces (settle_pieces). */
static plx_status cut_edges(arena *a, polar *pd, piece **pc, uint32_t *np)
{
    const scene *s = pd->s;
    edges e;
    split_ctx c;
    keyed *order;
    uint32_t i, nocc = 0;
    uint8_t *dirty;
    piece *ep;
    plx_status st;
    e.n = count_edges(s);
    e.a = scratch_n(a, e.n, 4);
    e.b = scratch_n(a, e.n, 4);
    e.bld = scratch_n(a, e.n, 4);
    e.first = scratch_n(a, s->nbld, 4);
    e.count = scratch_n(a, s->nbld, 4);
    order = scratch_n(a, s->nbld, sizeof(keyed));
    if (!e.a || !e.b || !e.bld || !e.first || !e.count || !order)
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
    /* the contacts, with the scene's points (edges end at scene points) */
    memset(&c, 0, sizeof c);
    c.pd = pd;
    c.e = &e;
    c.a = a;
    pd->pts = (vec2 *)s->pts;   /* read only meanwhile */
    c.npts = s->npts;
    st = find_contacts(&c, s, order, nocc);
    if (st != PLX_OK)
        return st;
    if (c.nomem)
        return PLX_E_NOMEM;
    st = flat_points(a, &c, s->npts);
    ep = st == PLX_OK ? edge_pieces(a, &e) : NULL;
    if (!ep)
        return PLX_E_NOMEM;
    /* piece i is edge i (cut_pieces leaves zero-length pieces out) */
    st = cut_pieces(a, &c, ep, e.n, 0, pc, np, &dirty);
    if (st == PLX_OK && c.npts > s->npts)
        st = settle_pieces(a, &c, pc, np, &dirty, &pd->wall_rounds);
    pd->npts = c.npts;
    return st;
}

/* Cuts the occluders' edges into wall pieces (pd->pts, pd->seg filled). */
static plx_status make_walls(arena *a, polar *pd)
{
    uint32_t i, j, np = 0, nm = 0;
    piece *pc;
    vec2 *P;
    plx_status st = cut_edges(a, pd, &pc, &np);
    if (st != PLX_OK)
        return st;
    P = pd->pts;
    pd->pts = keep_n(a, (size_t)pd->npts + 4, sizeof(vec2), &pd->bytes[2]);
    if (!pd->pts)
        return PLX_E_NOMEM;
    if (pd->npts)
        memcpy(pd->pts, P, (size_t)pd->npts * sizeof(vec2));
    {
        pkey *ky = scratch_n(a, np, sizeof(pkey)), *tmp = scratch_n(a, np, sizeof(pkey));
        piece *pc2 = scratch_n(a, np, sizeof(piece));
        if (!ky || !tmp || !pc2)
            return PLX_E_NOMEM;
        for (i = 0; i < np; i++) {
            ky[i].lo = pd->pts[pc[i].lo];
            ky[i].hi = pd->pts[pc[i].hi];
            ky[i].k = i;
        }
        sort_pkeys(ky, tmp, np, NULL);
        for (i = 0; i < np; i++)
            pc2[i] = pc[ky[i].k];
        pc = pc2;
    }
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
    add_box(pd, pd->npts);
    return PLX_OK;
}

plx_status polar_build(arena *a, const scene *s, polar **out)
{
    return polar_build_flags(a, s, 0, out);
}

plx_status polar_build_flags(arena *a, const scene *s, int flags, polar **out)
{
    arena_mark m0, m1;
    polar *pd;
    plx_status st;
    uint32_t *inc_first = NULL, *inc = NULL, *evp = NULL, *order = NULL, nev = 0, i;
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
    if (st == PLX_OK)
        st = build_incidence(a, pd, &inc_first, &inc, &evp, &nev);
    if (st == PLX_OK)
        st = insertion_order(a, pd, &order);
    for (i = 0; st == PLX_OK && i < 2; i++) {
        arena_mark mm = arena_get_mark(a);
        pd->map[i].frame = (int)i;
        st = build_map(a, pd, &pd->map[i], inc_first, inc, evp, nev, order, flags, &pd->steps);
        /* give back this map's scratch (kept memory grows from the other end) */
        mm.lo = a->lo;
        mm.used[PLX_PART_POLAR] = a->used[PLX_PART_POLAR];
        if (st == PLX_OK)
            arena_release(a, &mm);
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

static int32_t seg_owner(const polar *pd, uint32_t s)
{
    return pd->seg[s].bld[0] < 0 ? -1 : pd->seg[s].bld[0];
}

/* Node n of m unpacked (see polar_map). */
static void node_get(const polar_map *m, uint32_t n, uint32_t w[3])
{
    if (m->narrow) {
        uint64_t x = (uint64_t)m->node[2 * (size_t)n] | (uint64_t)m->node[2 * (size_t)n + 1] << 32;
        uint32_t t = (uint32_t)(x & 0x3fffffu), c0 = (uint32_t)(x >> 22) & 0x1fffffu,
                 c1 = (uint32_t)(x >> 43) & 0x1fffffu;
        w[0] = PACK(t >> 20, t & 0xfffffu);
        w[1] = PACK(c0 >> 19, c0 & 0x7ffffu);
        w[2] = PACK(c1 >> 19, c1 & 0x7ffffu);
    } else {
        w[0] = m->node[3 * (size_t)n];
        w[1] = m->node[3 * (size_t)n + 1];
        w[2] = m->node[3 * (size_t)n + 2];
    }
}

void polar_node(const polar_map *m, uint32_t n, uint32_t w[3])
{
    node_get(m, n, w);
}

/* The free region holding frame point f: the search DAG descended from
 * its root. -2 as soon as a test is a tie: f at a vertex (x test) or on a
 * wall piece (y test: the nodes met are those whose regions hold f, so f
 * lies within the piece's span). -3 at a solid leaf, whose child word
 * carries the owner. */
static int32_t dag_locate(const polar *pd, const polar_map *m, vec2 f, int32_t *owner,
                          uint32_t *depth)
{
    uint32_t c = m->root, d = 0;
    int32_t r;
    while (POLAR_TAG(c) == POLAR_CHILD_NODE) {
        uint32_t nd[3], w;
        int k;
        node_get(m, c, nd);
        w = nd[0];
        d++;
        if (KIND(w) == N_X) {
            k = lex_cmp(f, fpt(pd, m->frame, IDX(w)));
        } else {
            const polar_seg *g = &pd->seg[IDX(w)];
            vec2 a = fpt(pd, m->frame, g->a), b = fpt(pd, m->frame, g->b);
            k = KIND(w) == N_Y ? geom_orient(a, b, f) : geom_orient(b, a, f);
        }
        if (k == 0) {
            c = POLAR_NONE;
            break;
        }
        c = nd[k > 0 ? 2 : 1];
    }
    if (depth)
        *depth = d;
    if (c == POLAR_NONE)
        r = -2;
    else if (POLAR_TAG(c) == POLAR_CHILD_FREE)
        r = (int32_t)POLAR_IDX(c);
    else
        r = -3;
    if (owner)
        *owner = r == -3 ? (int32_t)POLAR_IDX(c) - 1 : -1;
    return r;
}

int32_t polar_locate_frame(const polar *pd, const polar_map *m, vec2 f)
{
    return dag_locate(pd, m, f, NULL, NULL);
}

int32_t polar_locate_frame_ex(const polar *pd, const polar_map *m, vec2 f, int32_t *owner,
                              uint32_t *depth)
{
    return dag_locate(pd, m, f, owner, depth);
}

/* ---- the former point location (tests and benchmarks) ----------------- */

struct polar_scan {
    const polar *pd;
    wgrid g;
    uint32_t *above[2];      /* per wall piece: the first (frame-leftmost)
                              * region above it, POLAR_NONE when solid */
    uint32_t *col_start[2];  /* per grid column of frame abscissae: the first
                              * region above the Bounds side at the bottom
                              * reaching that column */
    uint32_t ncol[2];
};

static plx_status scan_tables(arena *a, polar_scan *g, int mi)
{
    const polar *pd = g->pd;
    const polar_map *m = &pd->map[mi];
    uint32_t *above, *col, ncol = m->frame ? g->g.nx : g->g.ny, t, c, s;
    above = grid_n(a, pd->nwall, 4, 1);
    col = grid_n(a, ncol, 4, 1);
    if (!above || !col)
        return PLX_E_NOMEM;
    for (s = 0; s < pd->nwall; s++)
        above[s] = POLAR_NONE;
    for (t = 0; t < m->ntrap; t++) {
        uint32_t b = m->trap[t].bot;
        if (b < pd->nwall && (above[b] == POLAR_NONE ||
                              lex_cmp(fpt(pd, m->frame, m->trap[t].lp),
                                      fpt(pd, m->frame, m->trap[above[b]].lp)) < 0))
            above[b] = t;
    }
    /* the regions above the bottom side, left to right (region 0 first):
     * per column the first one reaching into it */
    for (t = 0, c = 0; t != POLAR_NONE && c < ncol; t = m->trap[t].nb[LR]) {
        double u = fpt(pd, m->frame, m->trap[t].rp).x;
        uint32_t last = m->frame ? grid_x(pd, &g->g, u) : grid_y(pd, &g->g, u);
        if (m->trap[t].rp == m->box_hi)
            last = ncol - 1;
        while (c <= last && c < ncol)
            col[c++] = t;
    }
    if (c < ncol)
        return PLX_E_SCENE;
    g->above[mi] = above;
    g->col_start[mi] = col;
    g->ncol[mi] = ncol;
    return PLX_OK;
}

plx_status polar_scan_new(arena *a, const polar *pd, polar_scan **out)
{
    polar_scan *g;
    plx_status st;
    if (!a || !pd || !out)
        return PLX_E_INVALID;
    g = arena_calloc(a, PLX_PART_POLAR, 1, sizeof *g, 16);
    if (!g)
        return PLX_E_NOMEM;
    g->pd = pd;
    st = build_grid(a, pd, &g->g, 1);
    if (st == PLX_OK)
        st = scan_tables(a, g, 0);
    if (st == PLX_OK)
        st = scan_tables(a, g, 1);
    *out = st == PLX_OK ? g : NULL;
    return st;
}

/* The nearest wall below f (frame) by scanning the grid column of f
 * downwards, stopping as soon as no unseen wall can be higher; then the
 * regions above that wall walked to f's abscissa. */
int32_t polar_scan_locate_frame(const polar_scan *g, int mi, vec2 f, int32_t *owner)
{
    const polar *pd = g->pd;
    const polar_map *m = &pd->map[mi];
    int on;
    uint32_t t, best = wall_below(pd, &g->g, m->frame, f, &on);
    if (owner)
        *owner = -1;
    if (on)
        return -2;
    if (best == POLAR_NONE) {
        vec2 wp = polar_from_frame(m->frame, f);
        t = g->col_start[mi][m->frame ? grid_x(pd, &g->g, wp.x) : grid_y(pd, &g->g, wp.y)];
    } else {
        t = g->above[mi][best];
        if (t == POLAR_NONE) {
            if (owner)
                *owner = seg_delta(pd, m->frame, best) > 0 ? seg_owner(pd, best) : -1;
            return -3;
        }
    }
    for (;;) {
        int c = lex_cmp(f, fpt(pd, m->frame, m->trap[t].rp));
        if (c < 0)
            return (int32_t)t;
        if (c == 0)
            return -2;
        t = m->trap[t].nb[LR];
        if (t == POLAR_NONE)
            return -2;
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
    t = dag_locate(pd, m, to_frame(m->frame, p), owner, NULL);
    PLX_ASSERT(t >= -3 && (t < 0 || (uint32_t)t < m->ntrap)); /* a region of this map */
    if (t >= 0 && owner)
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

/* Walks the ray from frame point P through Q from region *t of map m, until
 * it leaves through a wall (*hit) or reaches the Bounds box (*hit =
 * POLAR_NONE); returns 1. side = +1 / -1: the one-sided ray, a corner on the
 * ray counted as passed on the other side. side = 0: the exact ray, which
 * stops at the first corner lying exactly on it and returns 0 with *t the
 * region whose corner that is (the two one-sided rays part there, and walk
 * on from *t). *steps counts the regions left behind. */
static int walk(const polar *pd, const polar_map *m, uint32_t *t, vec2 P, vec2 Q, int side,
                uint32_t *hit, uint32_t *steps)
{
    const polar_trap *trap = m->trap;
    int right = lex_cmp(Q, P) > 0;
    uint32_t end = right ? m->box_hi : m->box_lo, k = *t, n = 0;
    double qx = Q.x - P.x, qy = Q.y - P.y;
    for (;;) {
        uint32_t r = right ? trap[k].rp : trap[k].lp, nx;
        vec2 R;
        int o;
        n++;
        if (r == end) {
            *hit = POLAR_NONE;
            break;
        }
        R = fpt(pd, m->frame, r);
        /* geom_orient(P, Q, R), filtered on the differences from P */
        o = geom_orient_filter(qx * (R.y - P.y), qy * (R.x - P.x));
        if (o == 0)
            o = geom_orient(P, Q, R);
        if (o == 0) {
            if (side == 0) {
                *t = k;
                *steps += n - 1;
                return 0;
            }
            o = side > 0 ? -1 : 1;
        }
        if (!right)
            o = -o;
        /* o > 0: the ray passes below r (in the frame) */
        nx = trap[k].nb[o > 0 ? (right ? LR : LL) : (right ? UR : UL)];
        if (nx == POLAR_NONE) {
            *hit = o > 0 ? trap[k].bot : trap[k].top;
            break;
        }
        k = nx;
    }
    *t = k;
    *steps += n;
    return 1;
}

/* Fills the hit record of the ray p->q that left through wall piece hit
 * (POLAR_NONE: through the Bounds box). */
static void hit_record(const polar *pd, vec2 p, vec2 q, uint32_t hit, uint32_t steps,
                       polar_hit *h)
{
    h->steps = steps;
    if (hit == POLAR_NONE || pd->seg[hit].bld[0] == -2) {
        h->bld = h->bld2 = -1;
        h->seg = hit;
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

/* The exact ray (side 0) is walked once; only where it passes exactly
 * through a corner does it part into the two one-sided rays, each walked on
 * from there, and the one blocked farther wins (the exact ray enters the
 * solid only where both sides of it are solid). */
plx_status polar_shoot_to(const polar *pd, vec2 p, vec2 q, int side, polar_hit *out)
{
    const polar_map *m;
    int32_t t;
    uint32_t k, hit, steps = 0;
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
    P = to_frame(m->frame, p);
    Q = to_frame(m->frame, q);
    t = polar_locate_frame(pd, m, P);
    if (t < 0)
        return PLX_E_RANGE;
    k = (uint32_t)t;
    if (walk(pd, m, &k, P, Q, side, &hit, &steps)) {
        hit_record(pd, p, q, hit, steps, out);
    } else {
        polar_hit h2;
        uint32_t k2 = k, hit2, steps2 = 0;
        walk(pd, m, &k, P, Q, 1, &hit, &steps);
        walk(pd, m, &k2, P, Q, -1, &hit2, &steps2);
        hit_record(pd, p, q, hit, steps + steps2, out);
        hit_record(pd, p, q, hit2, steps + steps2, &h2);
        if (h2.t > out->t)
            *out = h2;
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
    A = fpt(pd, frame, l);
    B = fpt(pd, frame, r);
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
    ul = fpt(pd, m->frame, m->trap[i].lp).x;
    ur = fpt(pd, m->frame, m->trap[i].rp).x;
    c[0] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].bot, ul));
    c[1] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].bot, ur));
    c[2] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].top, ur));
    c[3] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].top, ul));
    if (owner)
        *owner = seg_owner(pd, top ? m->trap[i].top : m->trap[i].bot);
    PLX_ASSERT(!owner || (*owner >= -1 && *owner < (int32_t)pd->nbld)); /* a building or the frame */
    if (solid)
        *solid = 0;
    return 4;
}
