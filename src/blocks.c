/* blocks: touching groups of buildings and the outlines of their unions.
 * The rules (touch, overlap, outline) are written in blocks.h.
 *
 * Plan: a grid over the building boxes gives candidate pairs; each pair is
 * tested for touch and overlap; union-find makes the blocks. Each block is
 * then outlined on its own, in scratch memory given back after the block:
 * gather vertices, cluster them (grid), bend edges through nearby clusters
 * (grid), split at crossings (grid over pieces), merge equal sub-edges
 * (sort), classify them by a ray count (strips), link and split loops. The
 * outlines go to a scratch cache first; if it is too small they are
 * counted, and computed again straight into persistent arrays. */
#include <string.h>
#include <math.h>
#include <float.h>
#include <limits.h>
#include "blocks.h"

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

typedef struct grid {
    double x0, y0, inv;
    uint32_t nx, ny;
    uint32_t *start;  /* nx*ny + 1 offsets into item */
    uint32_t *item;
} grid;

static uint32_t grid_cell1(double v, double v0, double inv, uint32_t n)
{
    double f = (v - v0) * inv;
    if (!(f >= 0.0))
        return 0;
    if (f >= (double)n)
        return n - 1;
    return (uint32_t)f;
}

/* Cell range r = {x0, y0, x1, y1} covered by a box. */
static void grid_range(const grid *g, double minx, double miny, double maxx, double maxy,
                       uint32_t r[4])
{
    r[0] = grid_cell1(minx, g->x0, g->inv, g->nx);
    r[1] = grid_cell1(miny, g->y0, g->inv, g->ny);
    r[2] = grid_cell1(maxx, g->x0, g->inv, g->nx);
    r[3] = grid_cell1(maxy, g->y0, g->inv, g->ny);
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
static plx_status grid_build(arena *a, grid *g, const double *box, const vec2 *pts, uint32_t n,
                             double min_cs)
{
    double bx0 = DBL_MAX, by0 = DBL_MAX, bx1 = -DBL_MAX, by1 = -DBL_MAX, w, h, cs, b[4];
    double cap_cells = 2.0 * n + 64.0, cap_items = 8.0 * n + 64.0;
    size_t ncell, nitem;
    uint32_t i, c, r[4], x, y, iter;
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
        g->inv = 1.0 / cs;
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
    ncell = (size_t)g->nx * g->ny;
    g->start = arena_scratch(a, arena_mul(ncell + 1, sizeof(uint32_t)), BLK_ALIGN);
    if (!g->start)
        return PLX_E_NOMEM;
    memset(g->start, 0, (ncell + 1) * sizeof(uint32_t));
    for (i = 0; i < n; i++) {
        item_box(box, pts, i, b);
        grid_range(g, b[0], b[1], b[2], b[3], r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                g->start[(size_t)y * g->nx + x + 1]++;
    }
    for (c = 0; c < ncell; c++)
        g->start[c + 1] += g->start[c];
    nitem = g->start[ncell];
    g->item = arena_scratch(a, arena_mul(nitem, sizeof(uint32_t)), BLK_ALIGN);
    if (!g->item)
        return PLX_E_NOMEM;
    for (i = 0; i < n; i++) {
        item_box(box, pts, i, b);
        grid_range(g, b[0], b[1], b[2], b[3], r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                g->item[g->start[(size_t)y * g->nx + x]++] = i;
    }
    for (c = (uint32_t)ncell; c > 0; c--)
        g->start[c] = g->start[c - 1];
    g->start[0] = 0;
    return PLX_OK;
}

/* Is cell c the one holding the low corner of the intersection of two
 * boxes? Then a pair met in several cells is handled once. */
static int grid_owns_pair(const grid *g, uint32_t c, const double *b1, const double *b2)
{
    double x = b1[0] > b2[0] ? b1[0] : b2[0];
    double y = b1[1] > b2[1] ? b1[1] : b2[1];
    uint32_t cx = grid_cell1(x, g->x0, g->inv, g->nx), cy = grid_cell1(y, g->y0, g->inv, g->ny);
    return (size_t)cy * g->nx + cx == c;
}

static int boxes_meet(const double *b1, const double *b2)
{
    return !(b1[0] > b2[2] || b2[0] > b1[2] || b1[1] > b2[3] || b2[1] > b1[3]);
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
            i0 = grid_cell1(u < v ? u : v, lo, st->inv, st->n);
            i1 = grid_cell1(u < v ? v : u, lo, st->inv, st->n);
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
        i0 = grid_cell1(u < v ? u : v, lo, st->inv, st->n);
        i1 = grid_cell1(u < v ? v : u, lo, st->inv, st->n);
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
        i0 = grid_cell1(u < v ? u : v, lo, st->inv, st->n);
        i1 = grid_cell1(u < v ? v : u, lo, st->inv, st->n);
        for (i = i0; i <= i1; i++)
            st->item[st->start[i]++] = k;
    }
    for (i = st->n; i > 0; i--)
        st->start[i] = st->start[i - 1];
    st->start[0] = 0;
    return PLX_OK;
}

/* ---- sorting (no libc qsort in src/) ------------------------------------ */

static int seg_less(const seg *x, const seg *y)
{
    return x->u < y->u || (x->u == y->u && x->v < y->v);
}

/* Stable bottom-up merge sort of n segments by (u, v); tmp holds n. */
static void seg_sort(seg *a, seg *tmp, uint32_t n)
{
    seg *src = a, *dst = tmp, *t;
    size_t w, i, l, m, r, p, q, k;
    for (w = 1; w < n; w *= 2) {
        for (i = 0; i < n; i += 2 * w) {
            l = i;
            m = i + w < n ? i + w : n;
            r = i + 2 * w < n ? i + 2 * w : n;
            p = l;
            q = m;
            k = l;
            while (p < m && q < r)
                dst[k++] = seg_less(&src[q], &src[p]) ? src[q++] : src[p++];
            while (p < m)
                dst[k++] = src[p++];
            while (q < r)
                dst[k++] = src[q++];
        }
        t = src;
        src = dst;
        dst = t;
    }
    if (src != a)
        memcpy(a, src, (size_t)n * sizeof(seg));
}

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
static plx_status blk_cluster(blk *k, uint32_t *cid)
{
    grid g;
    uint32_t i, x, y, c, e, j, r[4];
    plx_status st = grid_build(k->a, &g, NULL, k->vp, k->nv0, k->tol);
    if (st != PLX_OK)
        return st;
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
        grid_range(&g, p.x - k->tol, p.y - k->tol, p.x + k->tol, p.y + k->tol, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++) {
                c = y * g.nx + x;
                for (e = g.start[c]; e < g.start[c + 1]; e++) {
                    j = g.item[e];
                    if (cid[j] == BLK_NONE && dist2(p, k->vp[j]) <= k->tol2)
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

/* Step 1b: footprint edges between clusters, bent through the clusters near
 * their interior (T-junctions), give the pieces. */
static plx_status blk_pieces(blk *k, const uint32_t *cid)
{
    grid g;
    uint32_t *ea, *eb, *hs, *hw, ne = 0, i, h, u, prev;
    double *ht;
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
    st = grid_build(k->a, &g, NULL, k->cp, k->nc, k->tol);
    if (st != PLX_OK)
        return st;
    SCRATCH(hs, (size_t)ne + 1, uint32_t);
    hs[0] = 0;
    for (i = 0; i < ne; i++) {
        h = edge_hits(k, &g, ea[i], eb[i], NULL, NULL);
        if (h > BLK_MAX_VERTS - hs[i])
            return PLX_E_NOMEM;
        hs[i + 1] = hs[i] + h;
    }
    if (hs[ne] > BLK_MAX_VERTS - ne)
        return PLX_E_NOMEM;
    SCRATCH(hw, hs[ne], uint32_t);
    SCRATCH(ht, hs[ne], double);
    for (i = 0; i < ne; i++) {
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

/* Proper crossings between pieces, each pair once; counts them, and stores
 * them when out is not NULL. */
static uint32_t cross_pass(const blk *k, const grid *g, const double *pbox, crossing *out)
{
    uint32_t c, e, f, i, j, n = 0;
    size_t ncell = (size_t)g->nx * g->ny;
    double t;
    for (c = 0; c < ncell; c++)
        for (e = g->start[c]; e < g->start[c + 1]; e++) {
            i = g->item[e];
            for (f = e + 1; f < g->start[c + 1]; f++) {
                vec2 a, b, p, q;
                j = g->item[f];
                if (k->pa[i] == k->pa[j] || k->pa[i] == k->pb[j] || k->pb[i] == k->pa[j] ||
                    k->pb[i] == k->pb[j])
                    continue;
                if (!boxes_meet(pbox + 4 * (size_t)i, pbox + 4 * (size_t)j) ||
                    !grid_owns_pair(g, c, pbox + 4 * (size_t)i, pbox + 4 * (size_t)j))
                    continue;
                a = k->cp[k->pa[i]];
                b = k->cp[k->pb[i]];
                p = k->cp[k->pa[j]];
                q = k->cp[k->pb[j]];
                if (!seg_cross(a, b, p, q, &t))
                    continue;
                if (out) {
                    double tj;
                    out[n].i = i;
                    out[n].j = j;
                    out[n].ti = t;
                    out[n].p = lerp(a, b, t);
                    if (!seg_cross(p, q, a, b, &tj))
                        tj = 0.5; /* cannot happen: the test is symmetric in sign */
                    out[n].tj = tj;
                }
                n++;
            }
        }
    return n;
}

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
    st = grid_build(k->a, &g, pbox, NULL, k->np, k->tol);
    if (st != PLX_OK)
        return st;
    nx = cross_pass(k, &g, pbox, NULL);
    if (nx > (BLK_MAX_VERTS - k->np) / 2)
        return PLX_E_NOMEM;
    SCRATCH(xr, nx, crossing);
    cross_pass(k, &g, pbox, xr);

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
    seg_sort(raw, tmp, n);
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

/* Step 2: keep the sub-edges with the union on exactly one side. */
static plx_status blk_classify(blk *k)
{
    strips rows, cols;
    uint32_t i, e, j, row;
    plx_status st = strips_build(k->a, &rows, k->pos, k->sg, k->ns, 1);
    if (st != PLX_OK)
        return st;
    st = strips_build(k->a, &cols, k->pos, k->sg, k->ns, 0);
    if (st != PLX_OK)
        return st;
    SCRATCH(k->kf, k->ns, uint32_t);
    SCRATCH(k->kt, k->ns, uint32_t);
    k->nk = 0;
    for (i = 0; i < k->ns; i++) {
        vec2 p = k->pos[k->sg[i].u], q = k->pos[k->sg[i].v], m;
        double dx = q.x - p.x, dy = q.y - p.y;
        long wl, wr, w = 0;
        if (dx == 0.0 && dy == 0.0)
            continue;
        m = lerp(p, q, 0.5);
        if (fabs(dy) >= fabs(dx)) {
            /* ray towards +x: the side it starts on is the right one when
             * the sub-edge goes up */
            row = grid_cell1(m.y, rows.v0, rows.inv, rows.n);
            for (e = rows.start[row]; e < rows.start[row + 1]; e++) {
                vec2 a, b;
                j = rows.item[e];
                if (j == i)
                    continue;
                a = k->pos[k->sg[j].u];
                b = k->pos[k->sg[j].v];
                if ((a.y > m.y) != (b.y > m.y)) {
                    double xc = a.x + (m.y - a.y) * (b.x - a.x) / (b.y - a.y);
                    if (xc > m.x)
                        w += b.y > a.y ? k->sg[j].w : -k->sg[j].w;
                }
            }
            if (dy > 0.0) {
                wr = w;
                wl = w + k->sg[i].w;
            } else {
                wl = w;
                wr = w - k->sg[i].w;
            }
        } else {
            /* ray towards +y: it starts on the left when the sub-edge goes
             * towards +x */
            row = grid_cell1(m.x, cols.v0, cols.inv, cols.n);
            for (e = cols.start[row]; e < cols.start[row + 1]; e++) {
                vec2 a, b;
                j = cols.item[e];
                if (j == i)
                    continue;
                a = k->pos[k->sg[j].u];
                b = k->pos[k->sg[j].v];
                if ((a.x > m.x) != (b.x > m.x)) {
                    double yc = a.y + (m.x - a.x) * (b.y - a.y) / (b.x - a.x);
                    if (yc > m.y)
                        w += b.x < a.x ? k->sg[j].w : -k->sg[j].w;
                }
            }
            if (dx > 0.0) {
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
