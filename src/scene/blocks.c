/* blocks: touching groups of buildings and the outlines of their unions.
 * The rules (touch, overlap, outline) are written in blocks.h.
 *
 * Plan: a grid over the building boxes gives candidate pairs; each pair is
 * tested for touch and overlap; union-find makes the blocks. Each block is
 * then outlined on its own, in scratch memory given back after the block:
 * gather vertices, cluster them (grid), bend edges through nearby clusters
 * (hashed grid), split at crossings (hashed grid over pieces), merge equal
 * sub-edges (sort), classify them by a ray count (sweep with a Fenwick tree
 * plus a hashed grid), link and split loops. The hashed grids have cells
 * about the size of the items, so a thin ring around an empty middle or a
 * long band of teeth stays near linear; their finds are put in the order
 * the plain grid would give, so the results do not depend on them. The
 * outlines go to a scratch cache first; if it is too small they are
 * counted, and computed again straight into persistent arrays. */
#include <string.h>
#include <math.h>
#include <float.h>
#include <limits.h>
#include "scene/blocks.h"
#include "base/msort.h"
#include "base/bucketgrid.h"

#define BLK_NONE UINT32_MAX
#define BLK_ALIGN 8
/* Metres: outline vertices this close are one; a vertex this close to the
 * line through its neighbours is dropped. */
#define BLK_MERGE 1e-7
/* Metres: crossing points this close to each other or to an end of their
 * edges are taken as one point (several edges through one point). */
#define BLK_EPS 1e-9
/* Largest number of vertices one block may have (keeps uint32 sums safe). */
#define BLK_MAX_VERTS (UINT32_MAX / 16u)

/* A sub-edge of a block outline between vertices u < v, with the net number
 * of footprint edges running along it from u to v. */
typedef struct seg {
    uint32_t u, v;
    int32_t w;
} seg;

/* ---- small geometry ---------------------------------------------------- */

static double orient(vec2 a, vec2 b, vec2 c)
{
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

static double dist2(vec2 a, vec2 b)
{
    double dx = a.x - b.x, dy = a.y - b.y;
    return dx * dx + dy * dy;
}

static vec2 lerp(vec2 a, vec2 b, double t)
{
    vec2 r;
    r.x = a.x + t * (b.x - a.x);
    r.y = a.y + t * (b.y - a.y);
    return r;
}

/* Squared distance from p to the closed segment ab. */
static double pt_seg_dist2(vec2 p, vec2 a, vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t = 0.0;
    vec2 c;
    if (l2 > 0.0) {
        t = ((p.x - a.x) * dx + (p.y - a.y) * dy) / l2;
        if (t < 0.0)
            t = 0.0;
        else if (t > 1.0)
            t = 1.0;
    }
    c = lerp(a, b, t);
    return dist2(p, c);
}

/* Proper crossing of ab and cd (each strictly separates the other's ends);
 * *t is the parameter of the crossing along ab. */
static int seg_cross(vec2 a, vec2 b, vec2 c, vec2 d, double *t)
{
    double o1 = orient(a, b, c), o2 = orient(a, b, d), o3, o4;
    if (!((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0)))
        return 0;
    o3 = orient(c, d, a);
    o4 = orient(c, d, b);
    if (!((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0)))
        return 0;
    *t = o3 / (o3 - o4);
    return 1;
}

static double seg_seg_dist2(vec2 a, vec2 b, vec2 c, vec2 d)
{
    double t, m, v;
    if (seg_cross(a, b, c, d, &t))
        return 0.0;
    m = pt_seg_dist2(a, c, d);
    v = pt_seg_dist2(b, c, d);
    if (v < m)
        m = v;
    v = pt_seg_dist2(c, a, b);
    if (v < m)
        m = v;
    v = pt_seg_dist2(d, a, b);
    if (v < m)
        m = v;
    return m;
}

/* Do the boxes of segments ab and cd come within 'g' of each other? */
static int seg_boxes_near(vec2 a, vec2 b, vec2 c, vec2 d, double g)
{
    double ax0 = a.x < b.x ? a.x : b.x, ax1 = a.x < b.x ? b.x : a.x;
    double ay0 = a.y < b.y ? a.y : b.y, ay1 = a.y < b.y ? b.y : a.y;
    double cx0 = c.x < d.x ? c.x : d.x, cx1 = c.x < d.x ? d.x : c.x;
    double cy0 = c.y < d.y ? c.y : d.y, cy1 = c.y < d.y ? d.y : c.y;
    return !(ax0 > cx1 + g || cx0 > ax1 + g || ay0 > cy1 + g || cy0 > ay1 + g);
}

static int seg_box_near(vec2 a, vec2 b, const double box[4], double g)
{
    double x0 = a.x < b.x ? a.x : b.x, x1 = a.x < b.x ? b.x : a.x;
    double y0 = a.y < b.y ? a.y : b.y, y1 = a.y < b.y ? b.y : a.y;
    return !(x0 > box[2] + g || x1 < box[0] - g || y0 > box[3] + g || y1 < box[1] - g);
}

/* ---- footprints of the scene -------------------------------------------- */

/* Even-odd over all rings of building b (half-open crossing rule). */
static int bld_inside(const scene *s, uint32_t b, vec2 p)
{
    const scene_building *B = &s->bld[b];
    uint32_t r, j;
    int c = 0;
    for (r = 0; r < B->ring_count; r++) {
        const scene_ring *R = &s->rings[B->ring_first + r];
        const vec2 *P = s->pts + R->first;
        uint32_t n = R->count;
        for (j = 0; j < n; j++) {
            vec2 u = P[j], v = P[j + 1 < n ? j + 1 : 0];
            if ((u.y > p.y) != (v.y > p.y)) {
                double x = u.x + (p.y - u.y) * (v.x - u.x) / (v.y - u.y);
                if (p.x < x)
                    c ^= 1;
            }
        }
    }
    return c;
}

/* Squared distance from p to the boundary of building b. */
static double bld_bdist2(const scene *s, uint32_t b, vec2 p)
{
    const scene_building *B = &s->bld[b];
    double m = DBL_MAX, d;
    uint32_t r, j;
    for (r = 0; r < B->ring_count; r++) {
        const scene_ring *R = &s->rings[B->ring_first + r];
        const vec2 *P = s->pts + R->first;
        uint32_t n = R->count;
        for (j = 0; j < n; j++) {
            d = pt_seg_dist2(p, P[j], P[j + 1 < n ? j + 1 : 0]);
            if (d < m)
                m = d;
        }
    }
    return m;
}

/* Closed footprints of A and B within tol of each other. */
static int bld_touch(const scene *s, uint32_t A, uint32_t B, double tol)
{
    const scene_building *BA = &s->bld[A], *BB = &s->bld[B];
    double tol2 = tol * tol;
    uint32_t ra, rb, i, j;
    for (ra = 0; ra < BA->ring_count; ra++) {
        const scene_ring *R = &s->rings[BA->ring_first + ra];
        const vec2 *P = s->pts + R->first;
        for (i = 0; i < R->count; i++) {
            vec2 p = P[i], q = P[i + 1 < R->count ? i + 1 : 0];
            if (!seg_box_near(p, q, BB->box, tol))
                continue;
            for (rb = 0; rb < BB->ring_count; rb++) {
                const scene_ring *S = &s->rings[BB->ring_first + rb];
                const vec2 *Q = s->pts + S->first;
                for (j = 0; j < S->count; j++) {
                    vec2 c = Q[j], d = Q[j + 1 < S->count ? j + 1 : 0];
                    if (seg_boxes_near(p, q, c, d, tol) && seg_seg_dist2(p, q, c, d) <= tol2)
                        return 1;
                }
            }
        }
    }
    return bld_inside(s, B, s->pts[s->rings[BA->ring_first].first]) ||
           bld_inside(s, A, s->pts[s->rings[BB->ring_first].first]);
}

/* Is p inside B deeper than tol? */
static int probe_deep(const scene *s, uint32_t B, vec2 p, double tol)
{
    const double *bb = s->bld[B].box;
    if (!(p.x > bb[0] + tol && p.x < bb[2] - tol && p.y > bb[1] + tol && p.y < bb[3] - tol))
        return 0;
    return bld_inside(s, B, p) && bld_bdist2(s, B, p) > tol * tol;
}

/* Rule (a) of blocks.h for the probes of A against B. */
static int bld_penetrates(const scene *s, uint32_t A, uint32_t B, double tol)
{
    const scene_building *BA = &s->bld[A], *BB = &s->bld[B];
    uint32_t ra, rb, i, j;
    for (ra = 0; ra < BA->ring_count; ra++) {
        const scene_ring *R = &s->rings[BA->ring_first + ra];
        const vec2 *P = s->pts + R->first;
        for (i = 0; i < R->count; i++) {
            vec2 p = P[i], q = P[i + 1 < R->count ? i + 1 : 0];
            double tp = 0.0, tn, t;
            if (!seg_box_near(p, q, BB->box, 0.0))
                continue;
            if (probe_deep(s, B, p, tol))
                return 1;
            for (;;) {
                tn = 1.0;
                for (rb = 0; rb < BB->ring_count; rb++) {
                    const scene_ring *S = &s->rings[BB->ring_first + rb];
                    const vec2 *Q = s->pts + S->first;
                    for (j = 0; j < S->count; j++) {
                        vec2 c = Q[j], d = Q[j + 1 < S->count ? j + 1 : 0];
                        if (seg_boxes_near(p, q, c, d, 0.0) && seg_cross(p, q, c, d, &t) &&
                            t > tp && t < tn)
                            tn = t;
                    }
                }
                if (probe_deep(s, B, lerp(p, q, 0.5 * (tp + tn)), tol))
                    return 1;
                if (tn >= 1.0)
                    break;
                tp = tn;
            }
        }
    }
    return 0;
}

/* Every vertex and edge midpoint of A within tol of the boundary of B. */
static int bld_hugs(const scene *s, uint32_t A, uint32_t B, double tol)
{
    const scene_building *BA = &s->bld[A];
    double tol2 = tol * tol;
    uint32_t ra, i;
    for (ra = 0; ra < BA->ring_count; ra++) {
        const scene_ring *R = &s->rings[BA->ring_first + ra];
        const vec2 *P = s->pts + R->first;
        for (i = 0; i < R->count; i++) {
            vec2 p = P[i], q = P[i + 1 < R->count ? i + 1 : 0];
            if (bld_bdist2(s, B, p) > tol2 || bld_bdist2(s, B, lerp(p, q, 0.5)) > tol2)
                return 0;
        }
    }
    return 1;
}

/* Rule (b) of blocks.h: coinciding footprints. */
static int bld_coincide(const scene *s, uint32_t A, uint32_t B, double tol)
{
    const scene_ring *R = &s->rings[s->bld[A].ring_first];
    const vec2 *P = s->pts + R->first;
    uint32_t i, best = 0;
    double bl = -1.0, l, d;
    vec2 p, q, m;
    if (!bld_hugs(s, A, B, tol) || !bld_hugs(s, B, A, tol))
        return 0;
    for (i = 0; i < R->count; i++) {
        l = dist2(P[i], P[i + 1 < R->count ? i + 1 : 0]);
        if (l > bl) {
            bl = l;
            best = i;
        }
    }
    if (!(bl > 0.0))
        return 0;
    p = P[best];
    q = P[best + 1 < R->count ? best + 1 : 0];
    l = sqrt(bl);
    d = tol > 0.0 ? 2.0 * tol : 1e-6 * l;
    m = lerp(p, q, 0.5);
    m.x -= d * (q.y - p.y) / l;
    m.y += d * (q.x - p.x) / l;
    return bld_inside(s, A, m) && bld_inside(s, B, m);
}

/* ---- union-find (the root of a set is its smallest member) -------------- */

static uint32_t uf_find(uint32_t *p, uint32_t i)
{
    while (p[i] != i) {
        p[i] = p[p[i]];
        i = p[i];
    }
    return i;
}

static void uf_unite(uint32_t *p, uint32_t i, uint32_t j)
{
    i = uf_find(p, i);
    j = uf_find(p, j);
    if (i < j)
        p[j] = i;
    else if (j < i)
        p[i] = j;
}

/* ---- uniform grid over boxes or points ----------------------------------- */

typedef bucketgrid grid;

/* Cell range r = {x0, y0, x1, y1} covered by a box. */
static void grid_range(const grid *g, double minx, double miny, double maxx, double maxy,
                       uint32_t r[4])
{
    double b[4];
    b[0] = minx;
    b[1] = miny;
    b[2] = maxx;
    b[3] = maxy;
    bucketgrid_range(g, b, r);
}

static void item_box(const double *box, const vec2 *pts, uint32_t i, double b[4])
{
    if (box) {
        memcpy(b, box + 4 * (size_t)i, 4 * sizeof(double));
    } else {
        b[0] = b[2] = pts[i].x;
        b[1] = b[3] = pts[i].y;
    }
}

/* Builds a grid over n items given as boxes (4 doubles each) or as points.
 * Cells are at least min_cs wide; there are about n of them and the items
 * cover at most about 8n cells (the size grows until they do). */
static void grid_size(grid *g, const double *box, const vec2 *pts, uint32_t n, double min_cs)
{
    double bx0 = DBL_MAX, by0 = DBL_MAX, bx1 = -DBL_MAX, by1 = -DBL_MAX, w, h, cs, b[4];
    double cap_cells = 2.0 * n + 64.0, cap_items = 8.0 * n + 64.0;
    uint32_t i, r[4], iter;
    for (i = 0; i < n; i++) {
        item_box(box, pts, i, b);
        if (b[0] < bx0) bx0 = b[0];
        if (b[1] < by0) by0 = b[1];
        if (b[2] > bx1) bx1 = b[2];
        if (b[3] > by1) by1 = b[3];
    }
    if (n == 0)
        bx0 = by0 = bx1 = by1 = 0.0;
    w = bx1 - bx0;
    h = by1 - by0;
    if (!(w >= 0.0 && w <= 1e15 && h >= 0.0 && h <= 1e15))
        w = h = 0.0; /* not finite: one cell */
    cs = n > 0 ? sqrt(w * h / n) : 1.0;
    if (!(cs > 0.0))
        cs = (w > h ? w : h) / (n > 0 ? n : 1);
    if (cs < min_cs)
        cs = min_cs;
    if (!(cs > 0.0))
        cs = 1.0;
    g->x0 = bx0;
    g->y0 = by0;
    for (iter = 0;; iter++) {
        double dnx = floor(w / cs) + 1.0, dny = floor(h / cs) + 1.0, items = 0.0;
        if (dnx * dny > cap_cells && iter < 4000) {
            cs *= 1.5;
            continue;
        }
        if (dnx * dny > cap_cells)
            dnx = dny = 1.0;
        g->nx = (uint32_t)dnx;
        g->ny = (uint32_t)dny;
        g->sx = g->sy = 1.0 / cs;
        if (g->nx == 1 && g->ny == 1)
            break;
        for (i = 0; i < n; i++) {
            item_box(box, pts, i, b);
            grid_range(g, b[0], b[1], b[2], b[3], r);
            items += (double)(r[2] - r[0] + 1) * (double)(r[3] - r[1] + 1);
        }
        if (items <= cap_items)
            break;
        cs *= 1.5;
    }
}

static plx_status grid_build(arena *a, grid *g, const double *box, const vec2 *pts, uint32_t n,
                             double min_cs)
{
    grid_size(g, box, pts, n, min_cs);
    return bucketgrid_fill(g, a, PLX_PART_SCRATCH, BLK_ALIGN, box, pts, n);
}

/* Is cell c the one holding the low corner of the intersection of two
 * boxes? Then a pair met in several cells is handled once. */
static int grid_owns_pair(const grid *g, uint32_t c, const double *b1, const double *b2)
{
    double x = b1[0] > b2[0] ? b1[0] : b2[0];
    double y = b1[1] > b2[1] ? b1[1] : b2[1];
    uint32_t cx = bucketgrid_index(x, g->x0, g->sx, g->nx), cy = bucketgrid_index(y, g->y0, g->sy, g->ny);
    return (size_t)cy * g->nx + cx == c;
}

static int boxes_meet(const double *b1, const double *b2)
{
    return !(b1[0] > b2[2] || b2[0] > b1[2] || b1[1] > b2[3] || b2[1] > b1[3]);
}

/* ---- hashed grid over boxes, sized by the boxes themselves -------------- */

/* A uniform grid of square cells whose size follows the typical box (not the
 * area they spread over, so a thin ring of small edges around an empty
 * middle still gets small cells); only the cells boxes meet are stored, in
 * a hash table. A bucket may hold the boxes of several cells: users check
 * that a box covers the cell they look at. Each box is listed at most once
 * per bucket. */
typedef struct hgrid {
    double x0, y0, inv;
    uint32_t mask;    /* buckets - 1 (buckets: a power of two) */
    int shift;        /* 64 - log2(buckets) */
    uint32_t *start;  /* mask + 2 offsets into item */
    uint32_t *item;
} hgrid;

static uint32_t hgrid_cell(double v, double v0, double inv)
{
    double f = (v - v0) * inv;
    if (!(f >= 0.0))
        return 0;
    if (f >= 2147483647.0)
        return 2147483647u;
    return (uint32_t)f;
}

static uint32_t hgrid_bucket(const hgrid *h, uint32_t cx, uint32_t cy)
{
    /* mixed, then the top bits: regular cell numbers (all even, say)
     * still spread over all buckets */
    uint64_t v = (uint64_t)cx * 0x9E3779B97F4A7C15ull + (uint64_t)cy * 0xC2B2AE3D27D4EB4Full;
    v ^= v >> 29;
    v *= 0xBF58476D1CE4E5B9ull;
    return (uint32_t)(v >> h->shift);
}

/* Cell range r = {x0, y0, x1, y1} of a box. */
static void hgrid_range(const hgrid *h, const double *b, uint32_t r[4])
{
    r[0] = hgrid_cell(b[0], h->x0, h->inv);
    r[1] = hgrid_cell(b[1], h->y0, h->inv);
    r[2] = hgrid_cell(b[2], h->x0, h->inv);
    r[3] = hgrid_cell(b[3], h->y0, h->inv);
}

/* Counts (fill == 0) or stores the bucket entries of the n boxes (or
 * points); last[] keeps each box out of a bucket it is already in. */
static void hgrid_pass(hgrid *h, const double *box, const vec2 *pts, uint32_t n, uint32_t *last,
                       int fill)
{
    uint32_t i, x, y, b, r[4];
    double bb[4];
    for (b = 0; b <= h->mask; b++)
        last[b] = BLK_NONE;
    for (i = 0; i < n; i++) {
        item_box(box, pts, i, bb);
        hgrid_range(h, bb, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++) {
                b = hgrid_bucket(h, x, y);
                if (last[b] == i)
                    continue;
                last[b] = i;
                if (fill)
                    h->item[h->start[b]++] = i;
                else
                    h->start[b + 1]++;
            }
    }
}

/* Histogram of sizes by power of two, for a median within a factor 2. */
static void hist_add(uint32_t hist[64], double e)
{
    int ex = -32;
    if (e > 0.0 && e <= DBL_MAX)
        (void)frexp(e, &ex);
    ex += 32;
    hist[ex < 0 ? 0 : ex > 63 ? 63 : ex]++;
}

/* A power of two at least the median of the n sizes counted. */
static double hist_median(const uint32_t hist[64], uint32_t n)
{
    uint32_t t = 0, i;
    for (i = 0; i < 63; i++) {
        t += hist[i];
        if (2 * (uint64_t)t >= n)
            break;
    }
    return ldexp(1.0, (int)i - 32);
}

/* Builds the grid over n boxes (or points) with cells at least min_cs and
 * about the median box size; a box meets at most about 8n cells. */
static plx_status hgrid_build(arena *a, hgrid *h, const double *box, const vec2 *pts, uint32_t n,
                              double min_cs)
{
    double bx0 = DBL_MAX, by0 = DBL_MAX, bx1 = -DBL_MAX, by1 = -DBL_MAX, cs, e, cells, b[4];
    double cap = 8.0 * n + 64.0;
    uint32_t hist[64], i, nb, *last;
    memset(hist, 0, sizeof(hist));
    for (i = 0; i < n; i++) {
        item_box(box, pts, i, b);
        if (b[0] < bx0) bx0 = b[0];
        if (b[1] < by0) by0 = b[1];
        if (b[2] > bx1) bx1 = b[2];
        if (b[3] > by1) by1 = b[3];
        hist_add(hist, b[2] - b[0] > b[3] - b[1] ? b[2] - b[0] : b[3] - b[1]);
    }
    if (n == 0)
        bx0 = by0 = bx1 = by1 = 0.0;
    cs = hist_median(hist, n);
    if (cs < min_cs)
        cs = min_cs;
    e = (bx1 - bx0 > by1 - by0 ? bx1 - bx0 : by1 - by0) / 1073741824.0;
    if (cs < e)
        cs = e;
    if (!(cs > 0.0))
        cs = 1.0;
    h->x0 = bx0;
    h->y0 = by0;
    for (;;) {
        h->inv = 1.0 / cs;
        cells = 0.0;
        for (i = 0; i < n && cells <= cap; i++) {
            uint32_t r[4];
            item_box(box, pts, i, b);
            hgrid_range(h, b, r);
            cells += (double)(r[2] - r[0] + 1) * (double)(r[3] - r[1] + 1);
        }
        if (cells <= cap)
            break;
        cs *= 2.0;
    }
    for (nb = 64, h->shift = 58; nb < 2 * (uint64_t)n && nb < 0x40000000u; nb *= 2)
        h->shift--;
    h->mask = nb - 1;
    h->start = arena_scratch(a, arena_mul((size_t)nb + 1, sizeof(uint32_t)), BLK_ALIGN);
    last = arena_scratch(a, arena_mul(nb, sizeof(uint32_t)), BLK_ALIGN);
    if (!h->start || !last)
        return PLX_E_NOMEM;
    memset(h->start, 0, ((size_t)nb + 1) * sizeof(uint32_t));
    hgrid_pass(h, box, pts, n, last, 0);
    for (i = 0; i < nb; i++)
        h->start[i + 1] += h->start[i];
    h->item = arena_scratch(a, arena_mul(h->start[nb], sizeof(uint32_t)), BLK_ALIGN);
    if (!h->item)
        return PLX_E_NOMEM;
    hgrid_pass(h, box, pts, n, last, 1);
    for (i = nb; i > 0; i--)
        h->start[i] = h->start[i - 1];
    h->start[0] = 0;
    return PLX_OK;
}

/* ---- strips along one axis, for axis-parallel rays ---------------------- */

typedef struct strips {
    double v0, inv;
    uint32_t n;
    uint32_t *start, *item;
} strips;


static double seg_coord(const vec2 *pos, uint32_t i, int axis)
{
    return axis ? pos[i].y : pos[i].x;
}

/* Buckets the segments by their extent along 'axis' (0: x, 1: y), so that a
 * ray at a fixed coordinate meets only the segments of one strip. */
static plx_status strips_build(arena *a, strips *st, const vec2 *pos, const seg *sg,
                               uint32_t ns, int axis)
{
    double lo = DBL_MAX, hi = -DBL_MAX, u, v;
    double cap = 8.0 * ns + 64.0;
    uint32_t k, i, i0, i1;
    for (k = 0; k < ns; k++) {
        u = seg_coord(pos, sg[k].u, axis);
        v = seg_coord(pos, sg[k].v, axis);
        if (u < lo) lo = u;
        if (v < lo) lo = v;
        if (u > hi) hi = u;
        if (v > hi) hi = v;
    }
    if (ns == 0)
        lo = hi = 0.0;
    st->v0 = lo;
    st->n = (uint32_t)sqrt((double)ns) + 1;
    for (;;) {
        double items = 0.0;
        st->inv = hi > lo ? st->n / (hi - lo) : 0.0;
        if (st->n == 1)
            break;
        for (k = 0; k < ns; k++) {
            u = seg_coord(pos, sg[k].u, axis);
            v = seg_coord(pos, sg[k].v, axis);
            i0 = bucketgrid_index(u < v ? u : v, lo, st->inv, st->n);
            i1 = bucketgrid_index(u < v ? v : u, lo, st->inv, st->n);
            items += (double)(i1 - i0 + 1);
        }
        if (items <= cap)
            break;
        st->n /= 2;
    }
    st->start = arena_scratch(a, arena_mul((size_t)st->n + 1, sizeof(uint32_t)), BLK_ALIGN);
    if (!st->start)
        return PLX_E_NOMEM;
    memset(st->start, 0, ((size_t)st->n + 1) * sizeof(uint32_t));
    for (k = 0; k < ns; k++) {
        u = seg_coord(pos, sg[k].u, axis);
        v = seg_coord(pos, sg[k].v, axis);
        i0 = bucketgrid_index(u < v ? u : v, lo, st->inv, st->n);
        i1 = bucketgrid_index(u < v ? v : u, lo, st->inv, st->n);
        for (i = i0; i <= i1; i++)
            st->start[i + 1]++;
    }
    for (i = 0; i < st->n; i++)
        st->start[i + 1] += st->start[i];
    st->item = arena_scratch(a, arena_mul(st->start[st->n], sizeof(uint32_t)), BLK_ALIGN);
    if (!st->item)
        return PLX_E_NOMEM;
    for (k = 0; k < ns; k++) {
        u = seg_coord(pos, sg[k].u, axis);
        v = seg_coord(pos, sg[k].v, axis);
        i0 = bucketgrid_index(u < v ? u : v, lo, st->inv, st->n);
        i1 = bucketgrid_index(u < v ? v : u, lo, st->inv, st->n);
        for (i = i0; i <= i1; i++)
            st->item[st->start[i]++] = k;
    }
    for (i = st->n; i > 0; i--)
        st->start[i] = st->start[i - 1];
    st->start[0] = 0;
    return PLX_OK;
}

/* ---- sorting (no libc qsort in src/) ------------------------------------ */

static int seg_less(const seg *x, const seg *y, const void *ctx)
{
    (void)ctx;
    return x->u < y->u || (x->u == y->u && x->v < y->v);
}

/* Segments by (u, v). */
MSORT_DEFINE(seg_sort, seg, const void *, seg_less)

/* Insertion sort of ids by key (short lists: hits on one edge, edges at
 * one vertex). */
static void sort_by_key(uint32_t *id, double *key, uint32_t n)
{
    uint32_t i, j, ti;
    double tk;
    for (i = 1; i < n; i++) {
        ti = id[i];
        tk = key[i];
        for (j = i; j > 0 && key[j - 1] > tk; j--) {
            id[j] = id[j - 1];
            key[j] = key[j - 1];
        }
        id[j] = ti;
        key[j] = tk;
    }
}

/* ---- outline of one block ------------------------------------------------ */

/* Where outlines are written: when a ring does not fit, it is only counted
 * and 'overflow' is set. */
typedef struct outbuf {
    vec2 *pts;
    scene_ring *rings;
    size_t cap_pts, cap_rings;
    size_t npts, nrings;
    int overflow;
} outbuf;

typedef struct crossing {
    uint32_t i, j;    /* the two pieces */
    double ti, tj;    /* parameter along each */
    vec2 p;
} crossing;

/* Working state of one block; all arrays are scratch. */
typedef struct blk {
    arena *a;
    const scene *s;
    double tol, tol2;      /* snapping distance (0 when snapping is off) */
    uint32_t nv0;          /* footprint vertices */
    vec2 *vp;
    uint32_t *vnext;       /* next vertex in the same ring */
    uint32_t nc;           /* vertex clusters */
    vec2 *cp;
    uint32_t np;           /* pieces: footprint edges split at T-junctions */
    uint32_t *pa, *pb;
    uint32_t nv;           /* all vertices: clusters, then crossings */
    vec2 *pos;
    uint32_t ns;           /* distinct sub-edges with a non-zero net count */
    seg *sg;
    uint32_t nk;           /* kept sub-edges, union on the left */
    uint32_t *kf, *kt;
    double mina;           /* loops of smaller area are dropped */
    int fast;              /* cluster coordinates finite and <= 1e150: hashed grids */
    double cmax;           /* largest |coordinate| of a cluster */
    int broken;            /* some kept edges could not be linked */
} blk;

#define SCRATCH(ptr, n, T)                                                       \
    do {                                                                         \
        (ptr) = (T *)arena_scratch(k->a, arena_mul((size_t)(n), sizeof(T)), BLK_ALIGN); \
        if (!(ptr))                                                              \
            return PLX_E_NOMEM;                                                  \
    } while (0)

static plx_status blk_gather(blk *k, const uint32_t *bl, uint32_t nb)
{
    const scene *s = k->s;
    size_t nv = 0;
    uint32_t i, r, j, n = 0, first;
    for (i = 0; i < nb; i++) {
        const scene_building *B = &s->bld[bl[i]];
        for (r = 0; r < B->ring_count; r++)
            nv += s->rings[B->ring_first + r].count;
    }
    if (nv > BLK_MAX_VERTS)
        return PLX_E_NOMEM;
    k->nv0 = (uint32_t)nv;
    SCRATCH(k->vp, nv, vec2);
    SCRATCH(k->vnext, nv, uint32_t);
    for (i = 0; i < nb; i++) {
        const scene_building *B = &s->bld[bl[i]];
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            first = n;
            for (j = 0; j < R->count; j++) {
                k->vp[n] = s->pts[R->first + j];
                k->vnext[n] = j + 1 < R->count ? n + 1 : first;
                n++;
            }
        }
    }
    return PLX_OK;
}

/* Step 1: clusters. In index order, each vertex not yet taken becomes a
 * cluster and takes every free vertex within tol of it (not transitively,
 * so a finely drawn curve keeps its shape: cluster centres end up more
 * than tol apart and each vertex moves by at most tol). */
static int pts_fast(const vec2 *p, uint32_t n, double *mx);

static plx_status blk_cluster(blk *k, uint32_t *cid)
{
    grid g;
    hgrid h;
    uint32_t i, x, y, c, e, j, r[4], ro[4];
    double mx, widen, q[4];
    int fast = pts_fast(k->vp, k->nv0, &mx);
    plx_status st;
    if (fast) {
        /* a hashed grid finds the same candidates as the plain one: those
         * in the plain cells of the query (any order will do) */
        grid_size(&g, NULL, k->vp, k->nv0, k->tol);
        st = hgrid_build(k->a, &h, NULL, k->vp, k->nv0, 4.0 * k->tol);
    } else {
        st = grid_build(k->a, &g, NULL, k->vp, k->nv0, k->tol);
    }
    if (st != PLX_OK)
        return st;
    widen = k->tol + 1e-6 * k->tol + 64.0 * DBL_EPSILON * mx + DBL_MIN;
    for (i = 0; i < k->nv0; i++)
        cid[i] = BLK_NONE;
    SCRATCH(k->cp, k->nv0, vec2);
    k->nc = 0;
    for (i = 0; i < k->nv0; i++) {
        vec2 p = k->vp[i];
        if (cid[i] != BLK_NONE)
            continue;
        cid[i] = k->nc;
        k->cp[k->nc] = p;
        grid_range(&g, p.x - k->tol, p.y - k->tol, p.x + k->tol, p.y + k->tol, ro);
        if (!fast) {
            for (y = ro[1]; y <= ro[3]; y++)
                for (x = ro[0]; x <= ro[2]; x++) {
                    c = y * g.nx + x;
                    for (e = g.start[c]; e < g.start[c + 1]; e++) {
                        j = g.item[e];
                        if (cid[j] == BLK_NONE && dist2(p, k->vp[j]) <= k->tol2)
                            cid[j] = k->nc;
                    }
                }
            k->nc++;
            continue;
        }
        q[0] = p.x - widen;
        q[1] = p.y - widen;
        q[2] = p.x + widen;
        q[3] = p.y + widen;
        hgrid_range(&h, q, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++) {
                uint32_t bk = hgrid_bucket(&h, x, y);
                for (e = h.start[bk]; e < h.start[bk + 1]; e++) {
                    vec2 v;
                    uint32_t ox, oy;
                    j = h.item[e];
                    if (cid[j] != BLK_NONE)
                        continue;
                    v = k->vp[j];
                    if (hgrid_cell(v.x, h.x0, h.inv) != x || hgrid_cell(v.y, h.y0, h.inv) != y)
                        continue;
                    ox = bucketgrid_index(v.x, g.x0, g.sx, g.nx);
                    oy = bucketgrid_index(v.y, g.y0, g.sy, g.ny);
                    if (ox < ro[0] || ox > ro[2] || oy < ro[1] || oy > ro[3])
                        continue; /* the plain grid would not look at it */
                    if (dist2(p, v) <= k->tol2)
                        cid[j] = k->nc;
                }
            }
        k->nc++;
    }
    return PLX_OK;
}

/* Clusters within tol of the interior of edge u-v (not u or v): counts them,
 * and when hw is not NULL stores them with their parameter. */
static uint32_t edge_hits(const blk *k, const grid *g, uint32_t u, uint32_t v, uint32_t *hw,
                          double *ht)
{
    vec2 a = k->cp[u], b = k->cp[v];
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t;
    uint32_t r[4], x, y, c, e, w, n = 0;
    if (!(l2 > 0.0))
        return 0;
    grid_range(g, (a.x < b.x ? a.x : b.x) - k->tol, (a.y < b.y ? a.y : b.y) - k->tol,
               (a.x < b.x ? b.x : a.x) + k->tol, (a.y < b.y ? b.y : a.y) + k->tol, r);
    for (y = r[1]; y <= r[3]; y++)
        for (x = r[0]; x <= r[2]; x++) {
            c = y * g->nx + x;
            for (e = g->start[c]; e < g->start[c + 1]; e++) {
                vec2 p;
                w = g->item[e];
                if (w == u || w == v)
                    continue;
                p = k->cp[w];
                t = ((p.x - a.x) * dx + (p.y - a.y) * dy) / l2;
                if (!(t > 0.0 && t < 1.0) || dist2(p, lerp(a, b, t)) > k->tol2)
                    continue;
                if (hw) {
                    hw[n] = w;
                    ht[n] = t;
                }
                n++;
            }
        }
    return n;
}

/* The cells of h, across the axis 'mn', that segment a + t*d (0 <= t <= 1)
 * widened by m can reach within the slab of cells number c along the axis
 * 'ax' (m also covers rounding: give it a cell more); r clips the range. */
static void hgrid_span(const hgrid *h, int ax, const double A[2], const double D[2], double m,
                       uint32_t c, const uint32_t r[4], uint32_t *lo, uint32_t *hi)
{
    int mn = 1 - ax;
    double o0 = ax ? h->y0 : h->x0, o1 = ax ? h->x0 : h->y0, t0, t1, v0, v1, sw;
    t0 = (o0 + c / h->inv - m - A[ax]) / D[ax];
    t1 = (o0 + (c + 1.0) / h->inv + m - A[ax]) / D[ax];
    if (t0 > t1) {
        sw = t0;
        t0 = t1;
        t1 = sw;
    }
    t0 = t0 < 0.0 ? 0.0 : t0 > 1.0 ? 1.0 : t0;
    t1 = t1 < 0.0 ? 0.0 : t1 > 1.0 ? 1.0 : t1;
    v0 = A[mn] + t0 * D[mn];
    v1 = A[mn] + t1 * D[mn];
    if (v0 > v1) {
        sw = v0;
        v0 = v1;
        v1 = sw;
    }
    *lo = hgrid_cell(v0 - m, o1, h->inv);
    *hi = hgrid_cell(v1 + m, o1, h->inv);
    if (*lo < r[mn])
        *lo = r[mn];
    if (*hi > r[mn + 2])
        *hi = r[mn + 2];
}

/* The same hits as edge_hits() over a plain grid with the geometry of og,
 * in the same order (by plain cell, then cluster), found through the hashed
 * grid h within 'widen' of the edge (> tol plus rounding: every hit lies
 * there). Only the cells along the edge are looked at, so a long slanted
 * edge costs about its length in cells, not its box. */
static uint32_t edge_hits_h(const blk *k, const hgrid *h, const grid *og, double widen,
                            uint32_t u, uint32_t v, uint32_t *hw, double *ht)
{
    vec2 a = k->cp[u], b = k->cp[v];
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t, q[4], A[2], D[2], m;
    uint32_t ro[4], r[4], cc[2], c, lo, hi, e, w, n = 0, i, j;
    int ax = fabs(dx) >= fabs(dy) ? 0 : 1;
    if (!(l2 > 0.0))
        return 0;
    grid_range(og, (a.x < b.x ? a.x : b.x) - k->tol, (a.y < b.y ? a.y : b.y) - k->tol,
               (a.x < b.x ? b.x : a.x) + k->tol, (a.y < b.y ? b.y : a.y) + k->tol, ro);
    q[0] = (a.x < b.x ? a.x : b.x) - widen;
    q[1] = (a.y < b.y ? a.y : b.y) - widen;
    q[2] = (a.x < b.x ? b.x : a.x) + widen;
    q[3] = (a.y < b.y ? b.y : a.y) + widen;
    hgrid_range(h, q, r);
    A[0] = a.x;
    A[1] = a.y;
    D[0] = dx;
    D[1] = dy;
    m = widen + 1.0 / h->inv + 64.0 * DBL_EPSILON * k->cmax;
    for (c = r[ax]; c <= r[ax + 2]; c++) {
        hgrid_span(h, ax, A, D, m, c, r, &lo, &hi);
        cc[ax] = c;
        for (cc[1 - ax] = lo; cc[1 - ax] <= hi; cc[1 - ax]++) {
            uint32_t bk = hgrid_bucket(h, cc[0], cc[1]);
            for (e = h->start[bk]; e < h->start[bk + 1]; e++) {
                vec2 p;
                uint32_t ox, oy;
                w = h->item[e];
                p = k->cp[w];
                if (w == u || w == v || hgrid_cell(p.x, h->x0, h->inv) != cc[0] ||
                    hgrid_cell(p.y, h->y0, h->inv) != cc[1])
                    continue;
                ox = bucketgrid_index(p.x, og->x0, og->sx, og->nx);
                oy = bucketgrid_index(p.y, og->y0, og->sy, og->ny);
                if (ox < ro[0] || ox > ro[2] || oy < ro[1] || oy > ro[3])
                    continue; /* the plain grid would not look at it */
                t = ((p.x - a.x) * dx + (p.y - a.y) * dy) / l2;
                if (!(t > 0.0 && t < 1.0) || dist2(p, lerp(a, b, t)) > k->tol2)
                    continue;
                if (hw) {
                    hw[n] = w;
                    ht[n] = t;
                }
                n++;
            }
        }
    }
    /* the plain grid's order: by cell (rows of x), then cluster */
    for (i = 1; hw && i < n; i++) {
        uint32_t ti = hw[i];
        double tt = ht[i];
        uint64_t ki;
        vec2 p = k->cp[ti];
        ki = ((uint64_t)bucketgrid_index(p.y, og->y0, og->sy, og->ny) * og->nx +
              bucketgrid_index(p.x, og->x0, og->sx, og->nx)) << 32 | ti;
        for (j = i; j > 0; j--) {
            vec2 o = k->cp[hw[j - 1]];
            uint64_t kj = ((uint64_t)bucketgrid_index(o.y, og->y0, og->sy, og->ny) * og->nx +
                           bucketgrid_index(o.x, og->x0, og->sx, og->nx)) << 32 | hw[j - 1];
            if (kj <= ki)
                break;
            hw[j] = hw[j - 1];
            ht[j] = ht[j - 1];
        }
        hw[j] = ti;
        ht[j] = tt;
    }
    return n;
}

/* Are the n coordinates all finite and at most 1e150 (the rounding bounds
 * of the hashed-grid searches hold)? *mx: the largest |coordinate|. */
static int pts_fast(const vec2 *p, uint32_t n, double *mx)
{
    uint32_t i;
    double v;
    *mx = 0.0;
    for (i = 0; i < n; i++) {
        v = fabs(p[i].x) > fabs(p[i].y) ? fabs(p[i].x) : fabs(p[i].y);
        if (!(v <= 1e150) || p[i].x != p[i].x || p[i].y != p[i].y)
            return 0;
        if (v > *mx)
            *mx = v;
    }
    return 1;
}

/* Sets k->fast and k->cmax for the clusters. */
static void blk_check_fast(blk *k)
{
    k->fast = pts_fast(k->cp, k->nc, &k->cmax);
}

/* Step 1b: footprint edges between clusters, bent through the clusters near
 * their interior (T-junctions), give the pieces. */
static plx_status blk_pieces(blk *k, const uint32_t *cid)
{
    grid g;
    hgrid hg;
    uint32_t *ea, *eb, *hs, *hw, ne = 0, i, h, u, prev;
    double *ht, widen = 0.0;
    plx_status st;
    SCRATCH(ea, k->nv0, uint32_t);
    SCRATCH(eb, k->nv0, uint32_t);
    for (i = 0; i < k->nv0; i++) {
        uint32_t p = cid[i], q = cid[k->vnext[i]];
        if (p != q) {
            ea[ne] = p;
            eb[ne] = q;
            ne++;
        }
    }
    blk_check_fast(k);
    if (k->fast) {
        /* cells about the length of an edge (plus tol), so an edge looks
         * at a few cells; their order is that of the plain grid */
        uint32_t hist[64];
        memset(hist, 0, sizeof(hist));
        for (i = 0; i < ne; i++) {
            vec2 a = k->cp[ea[i]], b = k->cp[eb[i]];
            double ex = fabs(b.x - a.x), ey = fabs(b.y - a.y);
            hist_add(hist, (ex > ey ? ex : ey) + 2.0 * k->tol);
        }
        grid_size(&g, NULL, k->cp, k->nc, k->tol);
        st = hgrid_build(k->a, &hg, NULL, k->cp, k->nc, hist_median(hist, ne));
        widen = k->tol + 1e-6 * k->tol + 64.0 * DBL_EPSILON * k->cmax + DBL_MIN;
    } else {
        st = grid_build(k->a, &g, NULL, k->cp, k->nc, k->tol);
    }
    if (st != PLX_OK)
        return st;
    SCRATCH(hs, (size_t)ne + 1, uint32_t);
    hs[0] = 0;
    for (i = 0; i < ne; i++) {
        h = k->fast ? edge_hits_h(k, &hg, &g, widen, ea[i], eb[i], NULL, NULL)
                    : edge_hits(k, &g, ea[i], eb[i], NULL, NULL);
        if (h > BLK_MAX_VERTS - hs[i])
            return PLX_E_NOMEM;
        hs[i + 1] = hs[i] + h;
    }
    if (hs[ne] > BLK_MAX_VERTS - ne)
        return PLX_E_NOMEM;
    SCRATCH(hw, hs[ne], uint32_t);
    SCRATCH(ht, hs[ne], double);
    for (i = 0; i < ne; i++) {
        if (k->fast)
            edge_hits_h(k, &hg, &g, widen, ea[i], eb[i], hw + hs[i], ht + hs[i]);
        else
            edge_hits(k, &g, ea[i], eb[i], hw + hs[i], ht + hs[i]);
        sort_by_key(hw + hs[i], ht + hs[i], hs[i + 1] - hs[i]);
    }
    k->np = ne + hs[ne];
    SCRATCH(k->pa, k->np, uint32_t);
    SCRATCH(k->pb, k->np, uint32_t);
    u = 0;
    for (i = 0; i < ne; i++) {
        prev = ea[i];
        for (h = hs[i]; h < hs[i + 1]; h++) {
            k->pa[u] = prev;
            k->pb[u] = hw[h];
            prev = hw[h];
            u++;
        }
        k->pa[u] = prev;
        k->pb[u] = eb[i];
        u++;
    }
    return PLX_OK;
}

/* Whether pieces i and j share an end (then they do not cross properly). */
static int share_end(const blk *k, uint32_t i, uint32_t j)
{
    return k->pa[i] == k->pa[j] || k->pa[i] == k->pb[j] || k->pb[i] == k->pa[j] ||
           k->pb[i] == k->pb[j];
}

/* Tests pieces i and j for a proper crossing; counts it in *n and, when out
 * is not NULL, stores it at out[*n]. */
static void pair_cross(const blk *k, uint32_t i, uint32_t j, crossing *out, uint32_t *n)
{
    vec2 a = k->cp[k->pa[i]], b = k->cp[k->pb[i]], p = k->cp[k->pa[j]], q = k->cp[k->pb[j]];
    double t, tj;
    if (!seg_cross(a, b, p, q, &t))
        return;
    if (out) {
        out[*n].i = i;
        out[*n].j = j;
        out[*n].ti = t;
        out[*n].p = lerp(a, b, t);
        if (!seg_cross(p, q, a, b, &tj))
            tj = 0.5; /* cannot happen: the test is symmetric in sign */
        out[*n].tj = tj;
    }
    (*n)++;
}

/* Proper crossings between pieces, each pair once; counts them, and stores
 * them when out is not NULL. */
static uint32_t cross_pass(const blk *k, const grid *g, const double *pbox, crossing *out)
{
    uint32_t c, e, f, i, j, n = 0;
    size_t ncell = (size_t)g->nx * g->ny;
    for (c = 0; c < ncell; c++)
        for (e = g->start[c]; e < g->start[c + 1]; e++) {
            i = g->item[e];
            for (f = e + 1; f < g->start[c + 1]; f++) {
                j = g->item[f];
                if (share_end(k, i, j) || !boxes_meet(pbox + 4 * (size_t)i, pbox + 4 * (size_t)j) ||
                    !grid_owns_pair(g, c, pbox + 4 * (size_t)i, pbox + 4 * (size_t)j))
                    continue;
                pair_cross(k, i, j, out, &n);
            }
        }
    return n;
}

/* cross_pass() over the hashed grid: the same crossings, in another order. */
static uint32_t cross_pass_h(const blk *k, const hgrid *h, const double *pbox, crossing *out)
{
    uint32_t bk, e, f, i, j, n = 0;
    for (bk = 0; bk <= h->mask; bk++)
        for (e = h->start[bk]; e < h->start[bk + 1]; e++) {
            i = h->item[e];
            for (f = e + 1; f < h->start[bk + 1]; f++) {
                const double *b1 = pbox + 4 * (size_t)i, *b2;
                j = h->item[f];
                b2 = pbox + 4 * (size_t)j;
                if (share_end(k, i, j) || !boxes_meet(b1, b2) ||
                    hgrid_bucket(h, hgrid_cell(b1[0] > b2[0] ? b1[0] : b2[0], h->x0, h->inv),
                                 hgrid_cell(b1[1] > b2[1] ? b1[1] : b2[1], h->y0, h->inv)) != bk)
                    continue;
                pair_cross(k, i, j, out, &n);
            }
        }
    return n;
}

/* The cell of og where cross_pass() meets crossing x. */
static size_t cross_cell(const grid *og, const double *pbox, const crossing *x)
{
    const double *b1 = pbox + 4 * (size_t)x->i, *b2 = pbox + 4 * (size_t)x->j;
    uint32_t cx = bucketgrid_index(b1[0] > b2[0] ? b1[0] : b2[0], og->x0, og->sx, og->nx);
    uint32_t cy = bucketgrid_index(b1[1] > b2[1] ? b1[1] : b2[1], og->y0, og->sy, og->ny);
    return (size_t)cy * og->nx + cx;
}

/* The plain grid whose pass order cross_sort() reproduces. */
typedef struct cross_order {
    const grid *og;
    const double *pbox;
} cross_order;

/* Is crossing x found before y by cross_pass() over a plain grid with the
 * geometry of og: by cell, then by pieces? */
static int cross_before(const crossing *x, const crossing *y, const cross_order *c)
{
    size_t cx = cross_cell(c->og, c->pbox, x), cy = cross_cell(c->og, c->pbox, y);
    return cx < cy || (cx == cy && (x->i < y->i || (x->i == y->i && x->j < y->j)));
}

/* Sorts the crossings into the order cross_pass() over a plain grid finds
 * them. */
MSORT_DEFINE(cross_sort, crossing, const cross_order *, cross_before)

static void seg_push(seg *sg, uint32_t *n, uint32_t u, uint32_t v)
{
    if (u == v)
        return;
    if (u < v) {
        sg[*n].u = u;
        sg[*n].v = v;
        sg[*n].w = 1;
    } else {
        sg[*n].u = v;
        sg[*n].v = u;
        sg[*n].w = -1;
    }
    (*n)++;
}

/* Step 1c: split the pieces where they cross, then merge equal sub-edges. */
static plx_status blk_segments(blk *k)
{
    grid g;
    hgrid hg;
    double *pbox, *ct, best, d;
    crossing *xr;
    uint32_t *xmap, *xuf, *cs, *cx, nx, i, j, c, prev, id, n, e;
    seg *raw, *tmp;
    plx_status st;
    SCRATCH(pbox, 4 * (size_t)k->np, double);
    for (i = 0; i < k->np; i++) {
        vec2 a = k->cp[k->pa[i]], b = k->cp[k->pb[i]];
        double *bx = pbox + 4 * (size_t)i;
        bx[0] = a.x < b.x ? a.x : b.x;
        bx[1] = a.y < b.y ? a.y : b.y;
        bx[2] = a.x < b.x ? b.x : a.x;
        bx[3] = a.y < b.y ? b.y : a.y;
    }
    if (k->fast) {
        /* hashed cells about the size of a piece; the crossings are then
         * put in the order of the plain grid */
        grid_size(&g, pbox, NULL, k->np, k->tol);
        st = hgrid_build(k->a, &hg, pbox, NULL, k->np, 0.0);
    } else {
        st = grid_build(k->a, &g, pbox, NULL, k->np, k->tol);
    }
    if (st != PLX_OK)
        return st;
    nx = k->fast ? cross_pass_h(k, &hg, pbox, NULL) : cross_pass(k, &g, pbox, NULL);
    if (nx > (BLK_MAX_VERTS - k->np) / 2)
        return PLX_E_NOMEM;
    SCRATCH(xr, nx, crossing);
    if (k->fast) {
        crossing *xt;
        cross_pass_h(k, &hg, pbox, xr);
        SCRATCH(xt, nx, crossing);
        {
            cross_order co;
            co.og = &g;
            co.pbox = pbox;
            cross_sort(xr, xt, nx, &co);
        }
    } else {
        cross_pass(k, &g, pbox, xr);
    }

    /* A crossing within BLK_EPS of an end of its two pieces becomes that
     * end (only rounding; moving crossings further could make new ones). */
    SCRATCH(xmap, nx, uint32_t);
    SCRATCH(xuf, nx, uint32_t);
    for (c = 0; c < nx; c++) {
        uint32_t ends[4];
        ends[0] = k->pa[xr[c].i];
        ends[1] = k->pb[xr[c].i];
        ends[2] = k->pa[xr[c].j];
        ends[3] = k->pb[xr[c].j];
        xmap[c] = BLK_NONE;
        xuf[c] = c;
        best = BLK_EPS * BLK_EPS;
        for (j = 0; j < 4; j++) {
            d = dist2(xr[c].p, k->cp[ends[j]]);
            if (d <= best) {
                best = d;
                xmap[c] = ends[j];
            }
        }
    }
    /* Crossings of each piece, in order along it. */
    SCRATCH(cs, (size_t)k->np + 1, uint32_t);
    memset(cs, 0, ((size_t)k->np + 1) * sizeof(uint32_t));
    for (c = 0; c < nx; c++) {
        cs[xr[c].i + 1]++;
        cs[xr[c].j + 1]++;
    }
    for (i = 0; i < k->np; i++)
        cs[i + 1] += cs[i];
    SCRATCH(cx, 2 * (size_t)nx, uint32_t);
    SCRATCH(ct, 2 * (size_t)nx, double);
    for (c = 0; c < nx; c++) {
        cx[cs[xr[c].i]] = c;
        ct[cs[xr[c].i]++] = xr[c].ti;
        cx[cs[xr[c].j]] = c;
        ct[cs[xr[c].j]++] = xr[c].tj;
    }
    for (i = k->np; i > 0; i--)
        cs[i] = cs[i - 1];
    cs[0] = 0;
    for (i = 0; i < k->np; i++) {
        sort_by_key(cx + cs[i], ct + cs[i], cs[i + 1] - cs[i]);
        /* Crossings within BLK_EPS of each other along a piece are one. */
        for (e = cs[i] + 1; e < cs[i + 1]; e++) {
            uint32_t c0 = cx[e - 1], c1 = cx[e];
            if (xmap[c0] == BLK_NONE && xmap[c1] == BLK_NONE &&
                dist2(xr[c0].p, xr[c1].p) <= BLK_EPS * BLK_EPS)
                uf_unite(xuf, c0, c1);
        }
    }
    k->nv = k->nc + nx;
    SCRATCH(k->pos, k->nv, vec2);
    memcpy(k->pos, k->cp, (size_t)k->nc * sizeof(vec2));
    for (c = 0; c < nx; c++)
        k->pos[k->nc + c] = xr[c].p;

    /* Sub-edges. */
    SCRATCH(raw, (size_t)k->np + 2 * (size_t)nx, seg);
    SCRATCH(tmp, (size_t)k->np + 2 * (size_t)nx, seg);
    n = 0;
    for (i = 0; i < k->np; i++) {
        prev = k->pa[i];
        for (e = cs[i]; e < cs[i + 1]; e++) {
            c = cx[e];
            id = xmap[c] != BLK_NONE ? xmap[c] : k->nc + uf_find(xuf, c);
            seg_push(raw, &n, prev, id);
            prev = id;
        }
        seg_push(raw, &n, prev, k->pb[i]);
    }
    seg_sort(raw, tmp, n, NULL);
    k->ns = 0;
    for (i = 0; i < n; i = j) {
        int32_t w = 0;
        for (j = i; j < n && raw[j].u == raw[i].u && raw[j].v == raw[i].v; j++)
            w += raw[j].w;
        if (w != 0) {
            raw[k->ns] = raw[i];
            raw[k->ns].w = w;
            k->ns++;
        }
    }
    k->sg = raw;
    return PLX_OK;
}

/* Step 2: keep the sub-edges with the union on exactly one side.
 *
 * The ray of sub-edge i goes towards +x from its midpoint m when the
 * sub-edge is steep (|dy| >= |dx|), else towards +y. ray_hit() is the one
 * test of a sub-edge j against such a ray; the count of a side is the sum of
 * ray_hit() over all j != i. Summing it edge by edge within a strip is
 * quadratic when many edges share one band (a comb), so the sum is split:
 *  - D: the sub-edges active on the ray's line (half-open, exactly as in
 *    ray_hit) that start beyond m by more than 'delta', a bound on the
 *    rounding of the crossing coordinate: ray_hit() counts each of them for
 *    sure. Their sum comes from a sweep along the line coordinate with a
 *    Fenwick tree over the sub-edges' low ends.
 *  - the rest whose range along the ray comes within delta of its start:
 *    ray_hit() itself, on the candidates a hashed grid over the sub-edge
 *    boxes gives.
 * Every other sub-edge is missed by ray_hit() for sure, so the sum is the
 * same integer as the plain one, in O(n log n) for a comb or a circle.
 * (Coordinates not finite or beyond 1e150: the plain count in strips.) */

/* Contribution of sub-edge j to the count along the ray from m: towards +x
 * (dir 0) or +y (dir 1). */
static int32_t ray_hit(const blk *k, uint32_t j, vec2 m, int dir)
{
    vec2 a = k->pos[k->sg[j].u], b = k->pos[k->sg[j].v];
    if (dir == 0) {
        if ((a.y > m.y) != (b.y > m.y)) {
            double xc = a.x + (m.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (xc > m.x)
                return b.y > a.y ? k->sg[j].w : -k->sg[j].w;
        }
    } else if ((a.x > m.x) != (b.x > m.x)) {
        double yc = a.y + (m.x - a.x) * (b.y - a.y) / (b.x - a.x);
        if (yc > m.y)
            return b.x < a.x ? k->sg[j].w : -k->sg[j].w;
    }
    return 0;
}

/* Direction of the ray of sub-edge i (-1: zero length, no ray) and its
 * start, the midpoint. */
static int ray_of(const blk *k, uint32_t i, vec2 *m)
{
    vec2 p = k->pos[k->sg[i].u], q = k->pos[k->sg[i].v];
    double dx = q.x - p.x, dy = q.y - p.y;
    if (dx == 0.0 && dy == 0.0)
        return -1;
    *m = lerp(p, q, 0.5);
    return fabs(dy) >= fabs(dx) ? 0 : 1;
}

/* The plain count within strips: used when the coordinates are not finite
 * or too large for the rounding bound of the sweep. */
static plx_status ray_counts_strips(blk *k, int64_t *wsum)
{
    strips rows, cols;
    uint32_t i, e, row;
    vec2 m;
    int dir;
    plx_status st = strips_build(k->a, &rows, k->pos, k->sg, k->ns, 1);
    if (st != PLX_OK)
        return st;
    st = strips_build(k->a, &cols, k->pos, k->sg, k->ns, 0);
    if (st != PLX_OK)
        return st;
    for (i = 0; i < k->ns; i++) {
        const strips *sp;
        int64_t w = 0;
        dir = ray_of(k, i, &m);
        wsum[i] = 0;
        if (dir < 0)
            continue;
        sp = dir == 0 ? &rows : &cols;
        row = bucketgrid_index(dir == 0 ? m.y : m.x, sp->v0, sp->inv, sp->n);
        for (e = sp->start[row]; e < sp->start[row + 1]; e++)
            if (sp->item[e] != i)
                w += ray_hit(k, sp->item[e], m, dir);
        wsum[i] = w;
    }
    return PLX_OK;
}

/* A key with the id it belongs to, for sorting. */
typedef struct keyid {
    double key;
    uint32_t id;
} keyid;

static int keyid_before(const keyid *a, const keyid *b, const void *ctx)
{
    (void)ctx;
    return a->key < b->key;
}

/* Keys in increasing order, stable (no NaN). */
MSORT_DEFINE(keyid_sort, keyid, const void *, keyid_before)

/* What the sweep of one direction shares. box[4j..4j+3] is the box of
 * sub-edge j (minx, miny, maxx, maxy). */
typedef struct sweep {
    blk *k;
    const double *box;
    const hgrid *g;
    double delta;
    int64_t *wsum;
} sweep;

/* Adds the counts along the rays of direction 'dir' (0: +x, the sweep runs
 * along y; 1: +y, along x) to wsum. Scratch is given back on success. */
static plx_status ray_counts_dir(const sweep *sw, int dir)
{
    blk *k = sw->k;
    arena_mark mk = arena_get_mark(k->a);
    const double *box = sw->box;
    const hgrid *g = sw->g;
    /* in box: the line coordinate is s, the ray coordinate r */
    int s0 = dir == 0 ? 1 : 0, r0 = dir == 0 ? 0 : 1;
    keyid *qs, *ins, *del, *rl, *tmp;
    uint32_t *rank, nq = 0, ne = 0, i, j, qi, pi = 0, pd = 0, c, lo, hi, mid, x, e;
    int32_t *cj;
    int64_t *fen, tot = 0, sum;
    vec2 m;
    SCRATCH(qs, k->ns, keyid);
    SCRATCH(ins, k->ns, keyid);
    SCRATCH(del, k->ns, keyid);
    SCRATCH(rl, k->ns, keyid);
    SCRATCH(tmp, k->ns, keyid);
    SCRATCH(rank, k->ns, uint32_t);
    SCRATCH(cj, k->ns, int32_t);
    for (i = 0; i < k->ns; i++) {
        const double *b = box + 4 * (size_t)i;
        vec2 p = k->pos[k->sg[i].u], q = k->pos[k->sg[i].v];
        if (ray_of(k, i, &m) == dir) {
            qs[nq].key = dir == 0 ? m.y : m.x;
            qs[nq].id = i;
            nq++;
        }
        if (dir == 0)
            cj[i] = q.y > p.y ? k->sg[i].w : -k->sg[i].w;
        else
            cj[i] = q.x < p.x ? k->sg[i].w : -k->sg[i].w;
        if (b[s0] < b[s0 + 2]) { /* never on a line otherwise */
            ins[ne].key = b[s0];
            ins[ne].id = i;
            del[ne].key = b[s0 + 2];
            del[ne].id = i;
            rl[ne].key = b[r0];
            rl[ne].id = i;
            ne++;
        }
    }
    if (nq == 0) {
        arena_release(k->a, &mk);
        return PLX_OK;
    }
    keyid_sort(qs, tmp, nq, NULL);
    keyid_sort(ins, tmp, ne, NULL);
    keyid_sort(del, tmp, ne, NULL);
    keyid_sort(rl, tmp, ne, NULL);
    for (j = 0; j < ne; j++)
        rank[rl[j].id] = j;
    SCRATCH(fen, (size_t)ne + 1, int64_t);
    memset(fen, 0, ((size_t)ne + 1) * sizeof(int64_t));
    for (qi = 0; qi < nq; qi++) {
        double Y, X, thi, tlo;
        const double *bi;
        uint32_t r[4], a0, a1, fix;
        i = qs[qi].id;
        Y = qs[qi].key;
        ray_of(k, i, &m);
        X = dir == 0 ? m.x : m.y;
        /* the sub-edges active on the line: low end <= Y < high end */
        for (; pi < ne && ins[pi].key <= Y; pi++) {
            j = ins[pi].id;
            tot += cj[j];
            for (x = rank[j] + 1; x <= ne; x += x & (0u - x))
                fen[x] += cj[j];
        }
        for (; pd < ne && del[pd].key <= Y; pd++) {
            j = del[pd].id;
            tot -= cj[j];
            for (x = rank[j] + 1; x <= ne; x += x & (0u - x))
                fen[x] -= cj[j];
        }
        /* D: active ones whose low ray coordinate is > thi */
        thi = X + sw->delta;
        tlo = X - sw->delta;
        lo = 0;
        hi = ne;
        while (lo < hi) {
            mid = lo + (hi - lo) / 2;
            if (rl[mid].key > thi)
                hi = mid;
            else
                lo = mid + 1;
        }
        sum = 0;
        for (x = lo; x > 0; x -= x & (0u - x))
            sum += fen[x];
        sum = tot - sum;
        bi = box + 4 * (size_t)i;
        if (bi[s0] <= Y && Y < bi[s0 + 2] && bi[r0] > thi)
            sum -= cj[i];
        /* the others near the ray's start, from the grid */
        if (dir == 0) {
            a0 = hgrid_cell(tlo, g->x0, g->inv);
            a1 = hgrid_cell(thi, g->x0, g->inv);
            fix = hgrid_cell(Y, g->y0, g->inv);
        } else {
            a0 = hgrid_cell(tlo, g->y0, g->inv);
            a1 = hgrid_cell(thi, g->y0, g->inv);
            fix = hgrid_cell(Y, g->x0, g->inv);
        }
        for (c = a0; c <= a1; c++) {
            uint32_t bk = dir == 0 ? hgrid_bucket(g, c, fix) : hgrid_bucket(g, fix, c);
            for (e = g->start[bk]; e < g->start[bk + 1]; e++) {
                const double *bj;
                j = g->item[e];
                if (j == i)
                    continue;
                bj = box + 4 * (size_t)j;
                hgrid_range(g, bj, r);
                /* on cell c of the line, and met there first */
                if (fix < r[s0] || fix > r[s0 + 2] || c < r[r0] || c > r[r0 + 2] ||
                    (r[r0] > a0 ? r[r0] : a0) != c)
                    continue;
                if (bj[s0] <= Y && Y < bj[s0 + 2] && bj[r0] > thi)
                    continue; /* in D */
                sum += ray_hit(k, j, m, dir);
            }
        }
        sw->wsum[i] += sum;
    }
    arena_release(k->a, &mk);
    return PLX_OK;
}

/* wsum[i]: the sum of ray_hit() over all sub-edges j != i along the ray of
 * sub-edge i (0 for a sub-edge of zero length). */
static plx_status ray_counts(blk *k, int64_t *wsum)
{
    double *box, mx = 0.0, dmin = DBL_MAX, v;
    uint32_t i, t;
    hgrid g;
    sweep sw;
    plx_status st;
    for (i = 0; i < k->ns; i++) {
        vec2 p = k->pos[k->sg[i].u], q = k->pos[k->sg[i].v];
        double c[4];
        c[0] = p.x;
        c[1] = p.y;
        c[2] = q.x;
        c[3] = q.y;
        for (t = 0; t < 4; t++) {
            v = fabs(c[t]);
            if (!(v <= 1e150)) /* not finite, or products could overflow */
                return ray_counts_strips(k, wsum);
            if (v > mx)
                mx = v;
        }
        for (t = 0; t < 2; t++) {
            v = fabs(c[t + 2] - c[t]);
            if (v > 0.0 && v < dmin)
                dmin = v;
        }
    }
    /* The crossing coordinate ray_hit() computes lies within about
     * 5*DBL_EPSILON*mx of the sub-edge's range, plus what underflow in the
     * product and quotient can lose (divided by the smallest difference). */
    sw.delta = 64.0 * DBL_EPSILON * mx + DBL_MIN / dmin + DBL_MIN;
    SCRATCH(box, 4 * (size_t)k->ns, double);
    for (i = 0; i < k->ns; i++) {
        vec2 p = k->pos[k->sg[i].u], q = k->pos[k->sg[i].v];
        double *b = box + 4 * (size_t)i;
        b[0] = p.x < q.x ? p.x : q.x;
        b[1] = p.y < q.y ? p.y : q.y;
        b[2] = p.x < q.x ? q.x : p.x;
        b[3] = p.y < q.y ? q.y : p.y;
        wsum[i] = 0;
    }
    st = hgrid_build(k->a, &g, box, NULL, k->ns, 0.0);
    if (st != PLX_OK)
        return st;
    sw.k = k;
    sw.box = box;
    sw.g = &g;
    sw.wsum = wsum;
    st = ray_counts_dir(&sw, 0);
    if (st == PLX_OK)
        st = ray_counts_dir(&sw, 1);
    return st;
}

static plx_status blk_classify(blk *k)
{
    arena_mark mk;
    int64_t *wsum, w, wl, wr;
    uint32_t i;
    vec2 m;
    int dir;
    plx_status st;
    SCRATCH(k->kf, k->ns, uint32_t);
    SCRATCH(k->kt, k->ns, uint32_t);
    mk = arena_get_mark(k->a);
    SCRATCH(wsum, k->ns, int64_t);
    st = ray_counts(k, wsum);
    if (st != PLX_OK)
        return st;
    k->nk = 0;
    for (i = 0; i < k->ns; i++) {
        vec2 p = k->pos[k->sg[i].u], q = k->pos[k->sg[i].v];
        dir = ray_of(k, i, &m);
        if (dir < 0)
            continue;
        w = wsum[i];
        if (dir == 0) {
            /* ray towards +x: the side it starts on is the right one when
             * the sub-edge goes up */
            if (q.y - p.y > 0.0) {
                wr = w;
                wl = w + k->sg[i].w;
            } else {
                wl = w;
                wr = w - k->sg[i].w;
            }
        } else {
            /* ray towards +y: it starts on the left when the sub-edge goes
             * towards +x */
            if (q.x - p.x > 0.0) {
                wl = w;
                wr = w - k->sg[i].w;
            } else {
                wr = w;
                wl = w + k->sg[i].w;
            }
        }
        if ((wl > 0) != (wr > 0)) {
            k->kf[k->nk] = wl > 0 ? k->sg[i].u : k->sg[i].v;
            k->kt[k->nk] = wl > 0 ? k->sg[i].v : k->sg[i].u;
            k->nk++;
        }
    }
    arena_release(k->a, &mk);
    return PLX_OK;
}

static int near_pt(vec2 a, vec2 b)
{
    return dist2(a, b) <= BLK_MERGE * BLK_MERGE;
}

/* Is b within BLK_MERGE of the line through a and c (or a == c)? */
static int straight(vec2 a, vec2 b, vec2 c)
{
    double l2 = dist2(a, c), o = orient(a, c, b);
    return o * o <= BLK_MERGE * BLK_MERGE * l2;
}

/* Merges close and collinear consecutive vertices of a loop in place;
 * returns the new count (0 when fewer than 3 remain). */
static uint32_t loop_simplify(uint32_t *v, uint32_t n, const vec2 *pos)
{
    uint32_t i, m = 0, changed = 1;
    for (i = 0; i < n; i++) {
        vec2 c = pos[v[i]];
        if (m > 0 && near_pt(pos[v[m - 1]], c))
            continue;
        while (m >= 2 && straight(pos[v[m - 2]], pos[v[m - 1]], c))
            m--;
        if (m > 0 && near_pt(pos[v[m - 1]], c))
            continue;
        v[m++] = v[i];
    }
    while (changed && m >= 3) {
        changed = 0;
        if (near_pt(pos[v[m - 1]], pos[v[0]]) || straight(pos[v[m - 2]], pos[v[m - 1]], pos[v[0]])) {
            m--;
            changed = 1;
        } else if (straight(pos[v[m - 1]], pos[v[0]], pos[v[1]])) {
            memmove(v, v + 1, (size_t)(m - 1) * sizeof(uint32_t));
            m--;
            changed = 1;
        }
    }
    return m >= 3 ? m : 0;
}

static double loop_area(const uint32_t *v, uint32_t n, const vec2 *pos)
{
    vec2 o = pos[v[0]];
    double s = 0.0;
    uint32_t i;
    for (i = 0; i < n; i++) {
        vec2 a = pos[v[i]], b = pos[v[i + 1 < n ? i + 1 : 0]];
        s += (a.x - o.x) * (b.y - o.y) - (b.x - o.x) * (a.y - o.y);
    }
    return 0.5 * s;
}

static void out_ring(outbuf *o, const uint32_t *v, uint32_t n, const vec2 *pos)
{
    uint32_t i;
    if (o->npts + n <= o->cap_pts && o->nrings < o->cap_rings) {
        o->rings[o->nrings].first = (uint32_t)o->npts;
        o->rings[o->nrings].count = n;
        for (i = 0; i < n; i++)
            o->pts[o->npts + i] = pos[v[i]];
    } else {
        o->overflow = 1;
    }
    o->npts += n;
    o->nrings++;
}

/* Loops kept so far: vertex ids in lv, one run per loop. */
typedef struct loops {
    uint32_t *lv, *lfirst, *lcount;
    double *larea;
    uint32_t nl, used;
    const vec2 *pos;
    double mina;
} loops;

/* Simplifies the loop v[0..n) into lv and keeps it unless it is negligible. */
static void loop_keep(loops *lp, const uint32_t *v, uint32_t n)
{
    uint32_t *dst = lp->lv + lp->used;
    double ar;
    memmove(dst, v, (size_t)n * sizeof(uint32_t));
    n = loop_simplify(dst, n, lp->pos);
    if (n == 0)
        return;
    ar = loop_area(dst, n, lp->pos);
    if (fabs(ar) < lp->mina)
        return;
    lp->lfirst[lp->nl] = lp->used;
    lp->lcount[lp->nl] = n;
    lp->larea[lp->nl] = ar;
    lp->nl++;
    lp->used += n;
}

/* Step 3 and 4: link kept edges into loops and write them out in order. */
static plx_status blk_loops(blk *k, outbuf *o)
{
    uint32_t *os, *oe, *nxt, *lv, *lfirst, *lcount, *tr, *stk, *at, i, e, v, nl, outer;
    double *oa, *larea, best;
    unsigned char *seen;
    loops lp;
    SCRATCH(os, (size_t)k->nv + 1, uint32_t);
    SCRATCH(oe, k->nk, uint32_t);
    SCRATCH(oa, k->nk, double);
    memset(os, 0, ((size_t)k->nv + 1) * sizeof(uint32_t));
    for (e = 0; e < k->nk; e++)
        os[k->kf[e] + 1]++;
    for (v = 0; v < k->nv; v++)
        os[v + 1] += os[v];
    for (e = 0; e < k->nk; e++) {
        vec2 a = k->pos[k->kf[e]], b = k->pos[k->kt[e]];
        oa[os[k->kf[e]]] = atan2(b.y - a.y, b.x - a.x);
        oe[os[k->kf[e]]++] = e;
    }
    for (v = k->nv; v > 0; v--)
        os[v] = os[v - 1];
    os[0] = 0;
    for (v = 0; v < k->nv; v++)
        sort_by_key(oe + os[v], oa + os[v], os[v + 1] - os[v]);
    /* next edge: the first outgoing one clockwise from the way back */
    SCRATCH(nxt, k->nk, uint32_t);
    for (e = 0; e < k->nk; e++) {
        vec2 a = k->pos[k->kf[e]], b = k->pos[k->kt[e]];
        double back = atan2(a.y - b.y, a.x - b.x);
        uint32_t lo = os[k->kt[e]], hi = os[k->kt[e] + 1], pick = BLK_NONE;
        for (i = lo; i < hi; i++)
            if (oa[i] < back)
                pick = oe[i];
        if (pick == BLK_NONE && hi > lo)
            pick = oe[hi - 1];
        nxt[e] = pick;
    }
    SCRATCH(seen, k->nk, unsigned char);
    SCRATCH(tr, k->nk, uint32_t);
    SCRATCH(stk, k->nk, uint32_t);
    SCRATCH(at, k->nv, uint32_t);
    SCRATCH(lv, k->nk, uint32_t);
    SCRATCH(lfirst, k->nk, uint32_t);
    SCRATCH(lcount, k->nk, uint32_t);
    SCRATCH(larea, k->nk, double);
    memset(seen, 0, k->nk);
    for (v = 0; v < k->nv; v++)
        at[v] = BLK_NONE;
    lp.lv = lv;
    lp.lfirst = lfirst;
    lp.lcount = lcount;
    lp.larea = larea;
    lp.nl = 0;
    lp.used = 0;
    lp.pos = k->pos;
    lp.mina = k->mina;
    for (e = 0; e < k->nk; e++) {
        uint32_t cur = e, n = 0, ok = 1, top = 0, j, q;
        if (seen[e])
            continue;
        do {
            seen[cur] = 1;
            tr[n++] = k->kf[cur];
            cur = nxt[cur];
            if (cur == BLK_NONE || (seen[cur] && cur != e)) {
                ok = 0;
                k->broken = 1;
                break;
            }
        } while (cur != e);
        if (!ok)
            continue;
        /* Split the loop where it comes back to a vertex it has visited
         * (a courtyard touching itself, or the outer boundary touching a
         * courtyard): the pieces are simple loops. */
        for (i = 0; i < n; i++) {
            v = tr[i];
            if (at[v] == BLK_NONE) {
                at[v] = top;
                stk[top++] = v;
                continue;
            }
            j = at[v];
            loop_keep(&lp, stk + j, top - j);
            for (q = j + 1; q < top; q++)
                at[stk[q]] = BLK_NONE;
            top = j + 1;
        }
        loop_keep(&lp, stk, top);
        for (q = 0; q < top; q++)
            at[stk[q]] = BLK_NONE;
    }
    nl = lp.nl;
    outer = BLK_NONE;
    best = 0.0;
    for (i = 0; i < nl; i++)
        if (larea[i] > best) {
            best = larea[i];
            outer = i;
        }
    if (outer == BLK_NONE)
        return PLX_OK;
    out_ring(o, lv + lfirst[outer], lcount[outer], k->pos);
    for (i = 0; i < nl; i++)
        if (larea[i] < 0.0)
            out_ring(o, lv + lfirst[i], lcount[i], k->pos);
    for (i = 0; i < nl; i++)
        if (larea[i] > 0.0 && i != outer)
            out_ring(o, lv + lfirst[i], lcount[i], k->pos);
    return PLX_OK;
}

/* Gives back the scratch of steps 1 to 1c (taken since m), keeping only the
 * vertices and sub-edges, which are moved up to the freed end: the
 * classification then needs no more memory than the steps before it. The
 * moves cannot clobber what is still to be moved (pos lies above sg and
 * both only move up). */
static plx_status blk_compact(blk *k, const arena_mark *m)
{
    vec2 *pos;
    seg *sg;
    arena_release(k->a, m);
    k->vp = k->cp = NULL;
    k->vnext = k->pa = k->pb = NULL;
    SCRATCH(pos, k->nv, vec2);
    memmove(pos, k->pos, (size_t)k->nv * sizeof(vec2));
    k->pos = pos;
    SCRATCH(sg, k->ns, seg);
    memmove(sg, k->sg, (size_t)k->ns * sizeof(seg));
    k->sg = sg;
    return PLX_OK;
}

/* One outline pass with snapping distance 'snap'; sets *broken when some
 * kept edges could not be linked into loops. Scratch is given back. */
static plx_status outline_pass(arena *a, const scene *s, double snap, double tol,
                               const uint32_t *bl, uint32_t nb, outbuf *o, int *broken)
{
    arena_mark m = arena_get_mark(a);
    blk kb, *k = &kb;
    uint32_t *cid;
    plx_status st;
    memset(k, 0, sizeof(*k));
    k->a = a;
    k->s = s;
    k->tol = snap;
    k->tol2 = snap * snap;
    k->mina = 10.0 * tol * tol;
    if (k->mina < 1e-12)
        k->mina = 1e-12;
    st = blk_gather(k, bl, nb);
    if (st == PLX_OK) {
        cid = arena_scratch(a, arena_mul(k->nv0, sizeof(uint32_t)), BLK_ALIGN);
        st = cid ? blk_cluster(k, cid) : PLX_E_NOMEM;
        if (st == PLX_OK)
            st = blk_pieces(k, cid);
    }
    if (st == PLX_OK)
        st = blk_segments(k);
    if (st == PLX_OK)
        st = blk_compact(k, &m);
    if (st == PLX_OK)
        st = blk_classify(k);
    if (st == PLX_OK)
        st = blk_loops(k, o);
    *broken = k->broken;
    arena_release(a, &m);
    return st;
}

/* Appends the outline rings of the block of buildings bl[0..nb) to o. When
 * the snapped edges cannot all be linked into loops (inconsistent snapping;
 * not seen in tests), the block is outlined again without snapping. */
static plx_status block_outline(arena *a, const scene *s, double tol, const uint32_t *bl,
                                uint32_t nb, outbuf *o)
{
    size_t p0 = o->npts, r0 = o->nrings;
    int of = o->overflow, broken = 0;
    plx_status st = outline_pass(a, s, tol, tol, bl, nb, o, &broken);
    if (st != PLX_OK || !broken || tol == 0.0)
        return st;
    o->npts = p0;
    o->nrings = r0;
    o->overflow = of;
    return outline_pass(a, s, 0.0, tol, bl, nb, o, &broken);
}

/* ---- blocks -------------------------------------------------------------- */

/* Gives back the scratch memory taken since m, keeping persistent memory. */
static void release_scratch(arena *a, const arena_mark *m)
{
    arena_mark cur = arena_get_mark(a);
    cur.hi = m->hi;
    cur.used[PLX_PART_SCRATCH] = m->used[PLX_PART_SCRATCH];
    arena_release(a, &cur);
}

/* Finds touching pairs (union-find in 'uf') and counts overlapping ones. */
static plx_status find_pairs(arena *a, scene *s, double tol, uint32_t *uf)
{
    uint32_t n = s->nbld, i, c, e, f, A, B;
    double *ebox, h = 0.5 * tol;
    size_t ncell;
    grid g;
    plx_status st;
    ebox = arena_scratch(a, arena_mul(4 * (size_t)n, sizeof(double)), BLK_ALIGN);
    if (!ebox)
        return PLX_E_NOMEM;
    for (i = 0; i < n; i++) {
        uf[i] = i;
        ebox[4 * (size_t)i + 0] = s->bld[i].box[0] - h;
        ebox[4 * (size_t)i + 1] = s->bld[i].box[1] - h;
        ebox[4 * (size_t)i + 2] = s->bld[i].box[2] + h;
        ebox[4 * (size_t)i + 3] = s->bld[i].box[3] + h;
    }
    st = grid_build(a, &g, ebox, NULL, n, tol);
    if (st != PLX_OK)
        return st;
    ncell = (size_t)g.nx * g.ny;
    for (c = 0; c < ncell; c++)
        for (e = g.start[c]; e < g.start[c + 1]; e++)
            for (f = e + 1; f < g.start[c + 1]; f++) {
                const double *b1, *b2;
                A = g.item[e];
                B = g.item[f];
                b1 = ebox + 4 * (size_t)A;
                b2 = ebox + 4 * (size_t)B;
                if (!boxes_meet(b1, b2) || !grid_owns_pair(&g, c, b1, b2))
                    continue;
                if (bld_penetrates(s, A, B, tol) || bld_penetrates(s, B, A, tol) ||
                    bld_coincide(s, A, B, tol)) {
                    s->overlapping_pairs++;
                    uf_unite(uf, A, B);
                } else if (uf_find(uf, A) != uf_find(uf, B) && bld_touch(s, A, B, tol)) {
                    uf_unite(uf, A, B);
                }
            }
    return PLX_OK;
}

static plx_status build(arena *a, scene *s, double tol)
{
    uint32_t n = s->nbld, i, b, *uf, *lab, *cur;
    size_t npts = 0, nrings = 0;
    outbuf o;
    plx_status st;

    uf = arena_scratch(a, arena_mul(n, sizeof(uint32_t)), BLK_ALIGN);
    if (!uf)
        return PLX_E_NOMEM;
    st = find_pairs(a, s, tol, uf);
    if (st != PLX_OK)
        return st;

    /* Blocks numbered by their smallest building. */
    lab = arena_scratch(a, arena_mul(n, sizeof(uint32_t)), BLK_ALIGN);
    if (!lab)
        return PLX_E_NOMEM;
    s->nblocks = 0;
    for (i = 0; i < n; i++) {
        uint32_t r = uf_find(uf, i);
        lab[i] = r == i ? s->nblocks++ : lab[r];
        s->bld[i].block = lab[i];
    }
    s->blocks = arena_alloc(a, PLX_PART_SCENE, arena_mul(s->nblocks, sizeof(scene_block)),
                            BLK_ALIGN);
    s->block_bld = arena_alloc(a, PLX_PART_SCENE, arena_mul(n, sizeof(uint32_t)), BLK_ALIGN);
    if (!s->blocks || !s->block_bld)
        return PLX_E_NOMEM;
    for (b = 0; b < s->nblocks; b++) {
        s->blocks[b].bld_first = 0;
        s->blocks[b].bld_count = 0;
        s->blocks[b].ring_first = 0;
        s->blocks[b].ring_count = 0;
    }
    for (i = 0; i < n; i++) {
        scene_block *B = &s->blocks[s->bld[i].block];
        const double *bx = s->bld[i].box;
        if (B->bld_count == 0) {
            memcpy(B->box, bx, sizeof(B->box));
        } else {
            if (bx[0] < B->box[0]) B->box[0] = bx[0];
            if (bx[1] < B->box[1]) B->box[1] = bx[1];
            if (bx[2] > B->box[2]) B->box[2] = bx[2];
            if (bx[3] > B->box[3]) B->box[3] = bx[3];
        }
        B->bld_count++;
    }
    for (b = 1; b < s->nblocks; b++)
        s->blocks[b].bld_first = s->blocks[b - 1].bld_first + s->blocks[b - 1].bld_count;
    cur = lab; /* reused as a fill cursor per block */
    for (b = 0; b < s->nblocks; b++)
        cur[b] = s->blocks[b].bld_first;
    for (i = 0; i < n; i++)
        s->block_bld[cur[s->bld[i].block]++] = i;

    /* Outlines: first into a scratch cache; if it overflows, count, then
     * compute again straight into persistent arrays of the exact size. */
    for (i = 0; i < n; i++) {
        nrings += s->bld[i].ring_count;
        for (b = 0; b < s->bld[i].ring_count; b++)
            npts += s->rings[s->bld[i].ring_first + b].count;
    }
    memset(&o, 0, sizeof(o));
    o.cap_pts = npts + npts / 4 + 64;
    o.cap_rings = nrings + nrings / 4 + 64;
    o.pts = arena_scratch(a, arena_mul(o.cap_pts, sizeof(vec2)), BLK_ALIGN);
    o.rings = arena_scratch(a, arena_mul(o.cap_rings, sizeof(scene_ring)), BLK_ALIGN);
    if (!o.pts || !o.rings)
        return PLX_E_NOMEM;
    for (b = 0; b < s->nblocks; b++) {
        scene_block *B = &s->blocks[b];
        size_t r0 = o.nrings;
        st = block_outline(a, s, tol, s->block_bld + B->bld_first, B->bld_count, &o);
        if (st != PLX_OK)
            return st;
        if (o.npts > UINT32_MAX || o.nrings > UINT32_MAX)
            return PLX_E_NOMEM;
        B->ring_first = (uint32_t)r0;
        B->ring_count = (uint32_t)(o.nrings - r0);
    }
    s->nblock_pts = (uint32_t)o.npts;
    s->nblock_rings = (uint32_t)o.nrings;
    s->block_pts = NULL;
    s->block_rings = NULL;
    if (o.npts > 0) {
        s->block_pts = arena_alloc(a, PLX_PART_SCENE, arena_mul(o.npts, sizeof(vec2)), BLK_ALIGN);
        s->block_rings = arena_alloc(a, PLX_PART_SCENE,
                                     arena_mul(o.nrings, sizeof(scene_ring)), BLK_ALIGN);
        if (!s->block_pts || !s->block_rings)
            return PLX_E_NOMEM;
    }
    if (!o.overflow) {
        if (o.npts > 0) {
            memcpy(s->block_pts, o.pts, o.npts * sizeof(vec2));
            memcpy(s->block_rings, o.rings, o.nrings * sizeof(scene_ring));
        }
        return PLX_OK;
    }
    memset(&o, 0, sizeof(o));
    o.pts = s->block_pts;
    o.rings = s->block_rings;
    o.cap_pts = s->nblock_pts;
    o.cap_rings = s->nblock_rings;
    for (b = 0; b < s->nblocks; b++) {
        scene_block *B = &s->blocks[b];
        st = block_outline(a, s, tol, s->block_bld + B->bld_first, B->bld_count, &o);
        if (st != PLX_OK)
            return st;
    }
    /* The same computation again: it cannot disagree with the count. */
    return o.overflow || o.npts != s->nblock_pts ? PLX_E_NOMEM : PLX_OK;
}

plx_status blocks_build(arena *a, scene *s, double tol)
{
    arena_mark m;
    plx_status st;
    if (!a || !s || !(tol >= 0.0) || !(tol <= DBL_MAX))
        return PLX_E_INVALID;
    s->blocks = NULL;
    s->nblocks = 0;
    s->block_bld = NULL;
    s->block_pts = NULL;
    s->nblock_pts = 0;
    s->block_rings = NULL;
    s->nblock_rings = 0;
    s->overlapping_pairs = 0;
    if (s->nbld == 0)
        return PLX_OK;
    m = arena_get_mark(a);
    st = build(a, s, tol);
    release_scratch(a, &m);
    return st;
}
