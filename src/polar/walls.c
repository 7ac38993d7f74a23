/* walls: the occluding footprints cut at their contacts into wall pieces
 * (see polar.h and polar_int.h): edges that touch, share or overlap are cut
 * at every contact with exact predicates, crossing points rounded, and the
 * pieces made consistent again after rounding; coinciding pieces merged,
 * party walls (cover 0) left out, the Bounds box added. */
#include "polar/polar_int.h"
#include "base/bucketgrid.h"

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


/* Uniform grid over the dirty pieces: cell c lists item[b.start[c] ..
 * b.start[c + 1]), the dirty pieces whose bounding boxes meet it, with their
 * boxes (read in the cell's order, not from the points). */
typedef struct ditem {
    double bx[4];
    uint32_t d;
} ditem;

typedef struct dgrid {
    bucketgrid b;     /* frame and offsets (b.item unused) */
    double x1, y1;    /* high corner of the frame */
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

/* Cells of about the area per dirty piece, at most 5 nd + 1 of them. */
static void dgrid_size(dgrid *g, const vec2 *P, const piece *pc, const uint32_t *dl, uint32_t nd)
{
    double bx[4], w, h, cs;
    uint32_t i;
    g->b.x0 = g->b.y0 = DBL_MAX;
    g->x1 = g->y1 = -DBL_MAX;
    for (i = 0; i < nd; i++) {
        piece_box(P, &pc[dl[i]], bx);
        g->b.x0 = fmin(g->b.x0, bx[0]);
        g->b.y0 = fmin(g->b.y0, bx[1]);
        g->x1 = fmax(g->x1, bx[2]);
        g->y1 = fmax(g->y1, bx[3]);
    }
    w = g->x1 - g->b.x0;
    h = g->y1 - g->b.y0;
    cs = sqrt(w * h / nd);
    if (!(cs > 0.0))
        cs = fmax(w, h) / nd;
    g->b.nx = cs > 0.0 ? (uint32_t)fmin(w / cs, 2.0 * nd) + 1 : 1;
    g->b.ny = cs > 0.0 ? (uint32_t)fmin(h / cs, 2.0 * nd) + 1 : 1;
    g->b.sx = w > 0.0 ? g->b.nx / w : 0.0;
    g->b.sy = h > 0.0 ? g->b.ny / h : 0.0;
}

static plx_status dgrid_build(arena *a, dgrid *g, const vec2 *P, const piece *pc,
                              const uint32_t *dl, uint32_t nd)
{
    uint32_t i, x, y, r[4], nc;
    size_t total;
    double bx[4];
    dgrid_size(g, P, pc, dl, nd);
    nc = g->b.nx * g->b.ny;
    g->b.start = scratch_n(a, (size_t)nc + 1, 4);
    if (!g->b.start)
        return PLX_E_NOMEM;
    memset(g->b.start, 0, ((size_t)nc + 1) * 4);
    for (i = 0; i < nd; i++) {
        piece_box(P, &pc[dl[i]], bx);
        bucketgrid_range(&g->b, bx, r);
        bucketgrid_count(&g->b, r);
    }
    total = bucketgrid_offsets(&g->b);
    g->item = total == SIZE_MAX ? NULL : scratch_n(a, total, sizeof(ditem));
    if (!g->item)
        return PLX_E_NOMEM;
    for (i = 0; i < nd; i++) {
        piece_box(P, &pc[dl[i]], bx);
        bucketgrid_range(&g->b, bx, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++) {
                ditem *t = &g->item[g->b.start[y * g->b.nx + x]++];
                memcpy(t->bx, bx, sizeof bx);
                t->d = dl[i];
            }
    }
    bucketgrid_rewind(&g->b);
    return PLX_OK;
}

/* Piece s against the dirty pieces of one cell: each pair once, in the
 * cell holding the low corner of the two boxes' intersection. */
static void meet_in_cell(split_ctx *c, const piece *pc, const uint8_t *dirty, const dgrid *g,
                         uint32_t s, const double *bs, uint32_t x, uint32_t y)
{
    uint32_t k, cl = y * g->b.nx + x;
    for (k = g->b.start[cl]; k < g->b.start[cl + 1]; k++) {
        uint32_t d = g->item[k].d;
        const double *bd = g->item[k].bx;
        if (d == s || (dirty[s] && s > d))
            continue;
        if (bd[2] < bs[0] || bd[0] > bs[2] || bd[3] < bs[1] || bd[1] > bs[3])
            continue;
        if (bucketgrid_index(dmax(bs[0], bd[0]), g->b.x0, g->b.sx, g->b.nx) != x ||
            bucketgrid_index(dmax(bs[1], bd[1]), g->b.y0, g->b.sy, g->b.ny) != y)
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
        if (bs[2] < g->b.x0 || bs[0] > g->x1 || bs[3] < g->b.y0 || bs[1] > g->y1)
            continue;
        bucketgrid_range(&g->b, bs, r);
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


/* The occluders' edges as pieces, uncut. */
static plx_status polar_make_walls_in(arena *a, polar *pd, const arena_mark *m0);

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

/* Cuts the occluders' edges into wall pieces (pd->pts, pd->seg filled);
 * gives back its scratch (contacts, pieces, sort keys) before the maps are
 * built. */
plx_status polar_make_walls(arena *a, polar *pd)
{
    arena_mark m0 = arena_get_mark(a), m1;
    plx_status st = polar_make_walls_in(a, pd, &m0);
    if (st != PLX_OK)
        return st;
    m1 = arena_get_mark(a);
    m1.hi = m0.hi;
    m1.used[PLX_PART_SCRATCH] = m0.used[PLX_PART_SCRATCH];
    arena_release(a, &m1);
    return PLX_OK;
}

/* Gives back the scratch taken since m0 except the n pieces pc, which
 * are moved to its start (scratch grows down from the top: the pieces end
 * where m0's scratch ends); returns where they are now. */
static piece *keep_only_pieces(arena *a, const arena_mark *m0, piece *pc, uint32_t n)
{
    size_t bytes = (size_t)n * sizeof(piece), top = a->cap - m0->hi, start;
    arena_mark mk = arena_get_mark(a);
    unsigned char *dst;
    start = (top - bytes) & ~(size_t)15;
    dst = a->base + start;
    PLX_ASSERT((unsigned char *)pc <= dst);
    if (bytes)
        memmove(dst, pc, bytes);
    mk.hi = a->cap - start;
    mk.used[PLX_PART_SCRATCH] = m0->used[PLX_PART_SCRATCH] + (mk.hi - m0->hi);
    arena_release(a, &mk);
    return (piece *)(void *)dst;
}

static plx_status polar_make_walls_in(arena *a, polar *pd, const arena_mark *m0)
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
    /* only the pieces are left to read: the contacts, edges and points
     * (about 90 bytes a vertex) given back before the pieces are sorted */
    pc = keep_only_pieces(a, m0, pc, np);
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

