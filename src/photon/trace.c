/* trace: 2.5D ray caster (see trace.h). */
#include <math.h>
#include <string.h>

#include "photon/trace.h"
#include "base/bucketgrid.h"

#define TRACE_MAX_CELLS (1u << 22)

/* A hint to fetch the cache line at p: the walk knows the next cell before
 * it tests the current one, and callers read a hit's building next.
 * Nothing on other compilers. */
#if defined(__GNUC__)
#define TRACE_PREFETCH(p) __builtin_prefetch(p)
#else
#define TRACE_PREFETCH(p) ((void)(p))
#endif

/* Slack of the per-cell height filters (m): they only skip work, so they
 * err on the side of testing (rounding of z at the cell's ends is far
 * smaller). */
#define TRACE_ZSLACK 1e-7

/* The grid's shape, shared by trace_bytes and trace_create. */
typedef struct gridspec {
    double x0, y0, cell, inv, pad;
    uint32_t nx, ny;
} gridspec;

static void grid_spec(const scene *s, double cell_size, gridspec *g)
{
    double w = s->bounds[2] - s->bounds[0], hgt = s->bounds[3] - s->bounds[1];
    double c = cell_size, fx, fy, big;
    if (!(w > 0.0))
        w = 1.0;
    if (!(hgt > 0.0))
        hgt = 1.0;
    if (!(c > 0.0)) {
        double per = w * hgt / (double)(s->nbld > 0 ? s->nbld : 1);
        c = TRACE_CELL_FACTOR * sqrt(per);
        if (c < 2.0)
            c = 2.0;
    }
    /* at most TRACE_MAX_CELLS cells */
    while ((w / c + 1.0) * (hgt / c + 1.0) > (double)TRACE_MAX_CELLS)
        c *= 1.25;
    fx = ceil(w / c);
    fy = ceil(hgt / c);
    g->nx = fx < 1.0 ? 1u : (uint32_t)fx;
    g->ny = fy < 1.0 ? 1u : (uint32_t)fy;
    g->cell = c;
    g->inv = 1.0 / c;
    g->x0 = s->bounds[0];
    g->y0 = s->bounds[1];
    /* records are listed in every cell they come this close to, so that
     * rounding in the walk (which cell holds a point on a cell border)
     * cannot hide them */
    big = fabs(s->bounds[0]);
    if (fabs(s->bounds[1]) > big)
        big = fabs(s->bounds[1]);
    if (fabs(s->bounds[2]) > big)
        big = fabs(s->bounds[2]);
    if (fabs(s->bounds[3]) > big)
        big = fabs(s->bounds[3]);
    g->pad = 1e-9 * (1.0 + big);
}

/* Cell range [i0, i1] covered by [lo - pad, hi + pad] along one axis, clamped. */
static void cell_range(const gridspec *g, double lo, double hi, double org, uint32_t n,
                       uint32_t *i0, uint32_t *i1)
{
    *i0 = bucketgrid_index(lo - g->pad, org, g->inv, n);
    *i1 = bucketgrid_index(hi + g->pad, org, g->inv, n);
}

/* Whether segment p + u e (0 <= u <= 1) comes into the box lo..hi
 * (Liang-Barsky on the parameter). */
static int seg_meets_box(double px, double py, double ex, double ey, const double lo[2],
                         const double hi[2])
{
    double a[2], e[2], u0 = 0.0, u1 = 1.0;
    int k;
    a[0] = px;
    a[1] = py;
    e[0] = ex;
    e[1] = ey;
    for (k = 0; k < 2; k++) {
        if (e[k] == 0.0) {
            if (a[k] < lo[k] || a[k] > hi[k])
                return 0;
        } else {
            double ua = (lo[k] - a[k]) / e[k], ub = (hi[k] - a[k]) / e[k];
            if (ua > ub) {
                double x = ua;
                ua = ub;
                ub = x;
            }
            if (ua > u0)
                u0 = ua;
            if (ub < u1)
                u1 = ub;
        }
    }
    return u0 <= u1;
}

/* Whether segment p->q comes within pad of cell (ci, cj): clipping of the
 * segment's parameter to the padded box (Liang-Barsky, seg_meets_box). */
static int seg_meets_cell(const gridspec *g, const vec2 *p, const vec2 *q, uint32_t ci,
                          uint32_t cj)
{
    double lo[2], hi[2];
    lo[0] = g->x0 + ci * g->cell - g->pad;
    hi[0] = g->x0 + (ci + 1) * g->cell + g->pad;
    lo[1] = g->y0 + cj * g->cell - g->pad;
    hi[1] = g->y0 + (cj + 1) * g->cell + g->pad;
    return seg_meets_box(p->x, p->y, q->x - p->x, q->y - p->y, lo, hi);
}

/*
 * The per-cell lists. With 'cnt' NULL only counts (returns the number of
 * building references, *nwalls the wall records). Else pass 0 counts into
 * cnt[c + 1] / cells[c + 1].w0 and pass 1 places records at the cursors
 * cnt[c] / cells[c].w0.
 */
static size_t grid_lists(const scene *s, const gridspec *g, int pass, uint32_t *cnt,
                         trace_cell *cells, uint32_t *ids, uint32_t *wids, size_t *nwalls)
{
    size_t refs = 0, nw = 0;
    uint32_t b;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *B = &s->bld[b];
        uint32_t i0, i1, j0, j1, ci, cj, r;
        cell_range(g, B->box[0], B->box[2], g->x0, g->nx, &i0, &i1);
        cell_range(g, B->box[1], B->box[3], g->y0, g->ny, &j0, &j1);
        refs += (size_t)(i1 - i0 + 1) * (j1 - j0 + 1);
        if (cnt)
            for (cj = j0; cj <= j1; cj++)
                for (ci = i0; ci <= i1; ci++) {
                    size_t c = (size_t)cj * g->nx + ci;
                    if (pass == 0)
                        cnt[c + 1]++;
                    else
                        ids[cnt[c]++] = b;
                }
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            uint32_t k;
            for (k = 0; k < R->count; k++) {
                uint32_t e = R->first + k, f = R->first + (k + 1 == R->count ? 0 : k + 1);
                const vec2 *p = &s->pts[e], *q = &s->pts[f];
                cell_range(g, p->x < q->x ? p->x : q->x, p->x < q->x ? q->x : p->x, g->x0,
                           g->nx, &i0, &i1);
                cell_range(g, p->y < q->y ? p->y : q->y, p->y < q->y ? q->y : p->y, g->y0,
                           g->ny, &j0, &j1);
                for (cj = j0; cj <= j1; cj++)
                    for (ci = i0; ci <= i1; ci++) {
                        size_t c = (size_t)cj * g->nx + ci;
                        if (!seg_meets_cell(g, p, q, ci, cj))
                            continue;
                        nw++;
                        if (!cnt)
                            continue;
                        if (pass == 0) {
                            cells[c + 1].w0++;
                            continue;
                        }
                        wids[cells[c].w0++] = e;
                    }
            }
        }
    }
    *nwalls = nw;
    return refs;
}

/* Bytes of the lamp tables for nl lamps and nref references. */
static size_t lamp_bytes(uint32_t nl, size_t nref)
{
    return ((size_t)nl * (TRACE_SECTORS + 2) + 1) * sizeof(uint32_t) + 64 +
           (nref ? nref : 1) * sizeof(uint32_t) + 64 + (nl ? nl : 1) + 64;
}

/* Sector of direction (x, y) (not both 0): TRACE_SECTORS equal steps of the
 * pseudo-angle in [0, 4) that grows counter-clockwise from +x (a quarter
 * turn per unit), so the sectors of a direction span are consecutive. */
static double pseudo_angle(double x, double y)
{
    double ax = fabs(x), ay = fabs(y);
    if (y >= 0.0)
        return x >= 0.0 ? ay / (ax + ay) : 1.0 + ax / (ax + ay);
    return x < 0.0 ? 2.0 + ay / (ax + ay) : 3.0 + ax / (ax + ay);
}

static uint32_t sector_of(double x, double y)
{
    uint32_t k = (uint32_t)(pseudo_angle(x, y) * (TRACE_SECTORS / 4.0));
    return k >= TRACE_SECTORS ? k - TRACE_SECTORS : k;
}

/* Distance from (x, y) to segment p + u e, 0 <= u <= 1. */
static double seg_dist(double x, double y, const trace_wall *w)
{
    double l2 = w->ex * w->ex + w->ey * w->ey, u = 0.0, px, py;
    if (l2 > 0.0) {
        u = ((x - w->px) * w->ex + (y - w->py) * w->ey) / l2;
        u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
    }
    px = w->px + u * w->ex - x;
    py = w->py + u * w->ey - y;
    return sqrt(px * px + py * py);
}

/*
 * The references of lamp l's table: (sector, wall) pairs and (TRACE_SECTORS,
 * building) for caps; returns their number. Mode 1 also counts them per
 * slot into cnt[k + 1], mode 2 places them at the cursors cnt[k].
 * Buildings come from the grid cells around the lamp, each once (in the
 * first cell of the range that lists it).
 */
static uint32_t lamp_refs(const tracer *T, const gridspec *g, uint32_t l, int mode,
                          uint32_t *cnt, uint32_t *ref)
{
    const scene *s = T->s;
    const scene_lamp *L = &s->lamps[l];
    double R = L->radius * (1.0 + 1e-9) + g->pad, o[3];
    uint32_t li0, li1, lj0, lj1, ci, cj, n = 0;
    o[0] = L->x;
    o[1] = L->y;
    o[2] = L->z;
    cell_range(g, o[0] - R, o[0] + R, g->x0, g->nx, &li0, &li1);
    cell_range(g, o[1] - R, o[1] + R, g->y0, g->ny, &lj0, &lj1);
    for (cj = lj0; cj <= lj1; cj++)
        for (ci = li0; ci <= li1; ci++) {
            size_t c = (size_t)cj * g->nx + ci;
            uint32_t k;
            for (k = T->start[c]; k < T->start[c + 1]; k++) {
                uint32_t b = T->ids[k], bi0, bi1, bj0, bj1, r;
                const scene_building *B = &s->bld[b];
                double bx = B->box[0] - o[0] > o[0] - B->box[2] ? B->box[0] - o[0]
                                                                : o[0] - B->box[2];
                double by = B->box[1] - o[1] > o[1] - B->box[3] ? B->box[1] - o[1]
                                                                : o[1] - B->box[3];
                cell_range(g, B->box[0], B->box[2], g->x0, g->nx, &bi0, &bi1);
                cell_range(g, B->box[1], B->box[3], g->y0, g->ny, &bj0, &bj1);
                if ((bi0 > li0 ? bi0 : li0) != ci || (bj0 > lj0 ? bj0 : lj0) != cj)
                    continue; /* listed in an earlier cell of the range */
                if ((bx > 0.0 ? bx * bx : 0.0) + (by > 0.0 ? by * by : 0.0) > R * R)
                    continue;
                if (B->height < o[2] || (B->min_height > 0.0 && B->min_height > o[2])) {
                    n++;
                    if (mode == 1)
                        cnt[TRACE_SECTORS + 1]++;
                    else if (mode == 2)
                        ref[cnt[TRACE_SECTORS]++] = b;
                }
                for (r = 0; r < B->ring_count; r++) {
                    const scene_ring *Rg = &s->rings[B->ring_first + r];
                    uint32_t e;
                    for (e = Rg->first; e < Rg->first + Rg->count; e++) {
                        const trace_wall *w = &T->walls[e];
                        double tn = (w->px - o[0]) * w->ey - (w->py - o[1]) * w->ex;
                        uint32_t s0, s1, span, j;
                        /* rays from o meet it only from its outer side
                         * (tn < 0, as in wall_test) and within R */
                        if (!(tn < 0.0) || seg_dist(o[0], o[1], w) > R)
                            continue;
                        s0 = sector_of(w->px + w->ex - o[0], w->py + w->ey - o[1]);
                        s1 = sector_of(w->px - o[0], w->py - o[1]);
                        span = (s1 + TRACE_SECTORS - s0) % TRACE_SECTORS + 3;
                        if (span > TRACE_SECTORS)
                            span = TRACE_SECTORS;
                        s0 = (s0 + TRACE_SECTORS - 1) % TRACE_SECTORS;
                        for (j = 0; j < span; j++) {
                            uint32_t sk = (s0 + j) % TRACE_SECTORS;
                            n++;
                            if (mode == 1)
                                cnt[sk + 1]++;
                            else if (mode == 2)
                                ref[cnt[sk]++] = e;
                        }
                    }
                }
            }
        }
    return n;
}

/* Whether lamp l may get a table: a finite positive radius and a small
 * range of cells around it (then at most TRACE_LAMP_REFS references). */
static int lamp_small(const gridspec *g, const scene_lamp *L)
{
    double cells = 2.0 * L->radius * g->inv + 2.0;
    return L->radius > 0.0 && cells * cells <= 256.0;
}

/*
 * Builds the lamp tables (the grid is built). Per lamp its W offsets hold
 * first the counts per slot (cnt[k + 1]), then, once the references are
 * allocated, the starts, the cursors moved to the ends by placing, and the
 * starts again.
 */
static int lamp_tables(tracer *T, arena *a, plx_part part, const gridspec *g, int tables)
{
    const scene *s = T->s;
    const uint32_t W = TRACE_SECTORS + 2;
    size_t total = 0;
    uint32_t l, k;
    if (!tables) {   /* every lamp's rays walk the grid (the same hits) */
        T->lfast = arena_calloc(a, part, s->nlamps ? s->nlamps : 1, 1, 64);
        return T->lfast != NULL;
    }
    T->lsec = arena_calloc(a, part, (size_t)s->nlamps * W + 1, sizeof(uint32_t), 64);
    T->lfast = arena_calloc(a, part, s->nlamps ? s->nlamps : 1, 1, 64);
    if (!T->lsec || !T->lfast)
        return 0;
    for (l = 0; l < s->nlamps; l++) {
        uint32_t *cnt = &T->lsec[(size_t)l * W], n;
        if (!lamp_small(g, &s->lamps[l]))
            continue;
        n = lamp_refs(T, g, l, 1, cnt, NULL);
        if (n > TRACE_LAMP_REFS) {
            memset(cnt, 0, W * sizeof(uint32_t));
            continue;
        }
        T->lfast[l] = 1;
        total += n;
    }
    T->lref = arena_alloc(a, part, (total ? total : 1) * sizeof(uint32_t), 64);
    if (!T->lref)
        return 0;
    total = 0;
    for (l = 0; l < s->nlamps; l++) {
        uint32_t *cnt = &T->lsec[(size_t)l * W], first = (uint32_t)total;
        cnt[0] = first;
        for (k = 1; k < W; k++)
            cnt[k] += cnt[k - 1];
        total = cnt[W - 1];
        if (T->lfast[l]) {
            lamp_refs(T, g, l, 2, cnt, T->lref);
            for (k = W - 1; k > 0; k--)
                cnt[k] = cnt[k - 1];
            cnt[0] = first;
        }
    }
    T->lsec[(size_t)s->nlamps * W] = (uint32_t)total;
    return 1;
}

size_t trace_bytes(const scene *s, double cell_size)
{
    return trace_bytes_ex(s, cell_size, 1);
}

size_t trace_bytes_ex(const scene *s, double cell_size, int tables)
{
    gridspec g;
    size_t cells, refs, nw;
    if (!s)
        return 0;
    grid_spec(s, cell_size, &g);
    cells = (size_t)g.nx * g.ny;
    refs = grid_lists(s, &g, 0, NULL, NULL, NULL, NULL, &nw);
    return sizeof(tracer) + 64 + (cells + 1) * sizeof(trace_cell) + 64 +
           (nw ? nw : 1) * sizeof(uint32_t) + 64 +
           (size_t)(s->npts ? s->npts : 1) * (sizeof(trace_wall) + sizeof(uint32_t)) + 2 * 64 +
           (size_t)(s->nbld ? s->nbld : 1) * 2 * sizeof(double) + 64 +
           (cells + 1) * sizeof(uint32_t) + 64 + (refs ? refs : 1) * sizeof(uint32_t) + 64 +
           (tables ? lamp_bytes(s->nlamps, (size_t)s->nlamps * TRACE_LAMP_REFS)
                   : (size_t)(s->nlamps ? s->nlamps : 1) + 64);
}

/* Turns counts in cnt[1..cells] into starts in cnt[0..cells]; with
 * 'placed' (cursors moved to the ends by placing) shifts back to starts.
 * The same for the cells' w0. */
static void prefix(uint32_t *cnt, trace_cell *cl, size_t cells, int placed)
{
    size_t i;
    if (placed) {
        for (i = cells; i > 0; i--) {
            cnt[i] = cnt[i - 1];
            cl[i].w0 = cl[i - 1].w0;
        }
        cnt[0] = 0;
        cl[0].w0 = 0;
        return;
    }
    for (i = 0; i < cells; i++) {
        cnt[i + 1] += cnt[i];
        cl[i + 1].w0 += cl[i].w0;
    }
}

plx_status trace_create(arena *a, plx_part part, const scene *s, double cell_size,
                        tracer **out)
{
    return trace_create_ex(a, part, s, cell_size, 1, out);
}

plx_status trace_create_ex(arena *a, plx_part part, const scene *s, double cell_size, int tables,
                           tracer **out)
{
    arena_mark m;
    tracer *T;
    gridspec g;
    size_t cells, refs, nw, i;
    uint32_t b;
    if (!a || !s || !out)
        return PLX_E_INVALID;
    *out = NULL;
    m = arena_get_mark(a);
    grid_spec(s, cell_size, &g);
    cells = (size_t)g.nx * g.ny;
    refs = grid_lists(s, &g, 0, NULL, NULL, NULL, NULL, &nw);
    T = arena_calloc(a, part, 1, sizeof *T, 16);
    if (!T)
        goto nomem;
    T->s = s;
    T->x0 = g.x0;
    T->y0 = g.y0;
    T->cell = g.cell;
    T->inv = g.inv;
    T->nx = g.nx;
    T->ny = g.ny;
    T->cells = arena_calloc(a, part, cells + 1, sizeof(trace_cell), 64);
    T->wids = arena_alloc(a, part, (nw ? nw : 1) * sizeof(uint32_t), 64);
    T->walls = arena_alloc(a, part, (s->npts ? s->npts : 1) * sizeof(trace_wall), 64);
    T->enext = arena_alloc(a, part, (s->npts ? s->npts : 1) * sizeof(uint32_t), 64);
    T->hz = arena_alloc(a, part, (s->nbld ? s->nbld : 1) * 2 * sizeof(double), 64);
    T->start = arena_calloc(a, part, cells + 1, sizeof(uint32_t), 64);
    T->ids = arena_alloc(a, part, (refs ? refs : 1) * sizeof(uint32_t), 64);
    if (!T->cells || !T->wids || !T->walls || !T->enext || !T->hz || !T->start ||
        !T->ids)
        goto nomem;
    /* counting sort of the (cell, building) and (cell, wall) references */
    grid_lists(s, &g, 0, T->start, T->cells, NULL, NULL, &nw);
    prefix(T->start, T->cells, cells, 0);
    grid_lists(s, &g, 1, T->start, T->cells, T->ids, T->wids, &nw);
    prefix(T->start, T->cells, cells, 1);
    for (b = 0; b < s->nbld; b++) {
        const scene_building *B = &s->bld[b];
        uint32_t r;
        T->hz[2 * b] = B->min_height;
        T->hz[2 * b + 1] = B->height;
        if (B->height > T->zmax)
            T->zmax = B->height;
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            uint32_t k;
            for (k = 0; k < R->count; k++) {
                uint32_t e = R->first + k, f = R->first + (k + 1 == R->count ? 0 : k + 1);
                trace_wall *w = &T->walls[e];
                T->enext[e] = f;
                w->px = s->pts[e].x;
                w->py = s->pts[e].y;
                w->ex = s->pts[f].x - s->pts[e].x;
                w->ey = s->pts[f].y - s->pts[e].y;
                w->zlo = B->min_height;
                w->zhi = B->height;
                w->bld = b;
                w->pad = 0;
                w->albedo = s->bld[b].albedo;
            }
        }
    }
    for (i = 0; i <= cells; i++)
        T->cells[i].r0 = T->start[i];
    if (!lamp_tables(T, a, part, &g, tables))
        goto nomem;
    for (i = 0; i < cells; i++) {
        trace_cell *C = &T->cells[i];
        uint32_t k;
        C->roof_lo = INFINITY;
        for (k = T->start[i]; k < T->start[i + 1]; k++) {
            const double *hz = &T->hz[2 * T->ids[k]];
            if (hz[1] > C->top)
                C->top = hz[1];
            if (hz[1] < C->roof_lo)
                C->roof_lo = hz[1];
            if (hz[0] > C->under_hi)
                C->under_hi = hz[0];
        }
    }
    *out = T;
    return PLX_OK;
nomem:
    arena_release(a, &m);
    return PLX_E_NOMEM;
}

/* The best hit so far, with what finish needs (no scene lookups). */
typedef struct best {
    double t;
    double ex, ey;     /* wall: its edge vector */
    const scene_building *bldv; /* the scene's buildings (prefetched at a hit) */
    double zc;         /* roof or underside: its height */
    double albedo;     /* the building's */
    uint32_t bld, edge;
    int kind;
} best;

/*
 * Wall w against o + t d: a hit when the ray enters the solid through the
 * face (walls are one-sided: the solid lies to the left of the edge, so
 * den = d x e < 0), 0 < t < best, the crossing lies on the closed edge
 * (0 <= u <= 1) and its height on the closed [zlo, zhi]. The formulas are
 * those of the plane/segment intersection t = ((p - o) x e) / (d x e),
 * u = ((p - o) x d) / (d x e); the signs are compared without dividing and
 * combined without branching (they are unpredictable; a crossing is rare).
 */
static inline void wall_test(const trace_wall *w, uint32_t e, const double o[3], const double d[3],
                      best *bs)
{
    double den = d[0] * w->ey - d[1] * w->ex;
    double wx = w->px - o[0], wy = w->py - o[1];
    double tn = wx * w->ey - wy * w->ex, un = wx * d[1] - wy * d[0], t, z;
    if (!((den < 0.0) & (tn < 0.0) & (un <= 0.0) & (un >= den)))
        return;
    t = tn / den;
    z = o[2] + t * d[2];
    if (!((t < bs->t) & (z >= w->zlo) & (z <= w->zhi)))
        return;
    bs->t = t;
    bs->ex = w->ex;
    bs->ey = w->ey;
    bs->bld = w->bld;
    bs->albedo = w->albedo;
    bs->edge = e;
    TRACE_PREFETCH(bs->bldv + w->bld);
    bs->kind = TRACE_WALL;
}

/* Even-odd test of (x, y) against every ring of building b. */
static int inside_footprint(const scene *s, uint32_t b, double x, double y)
{
    const scene_building *B = &s->bld[b];
    uint32_t r, in = 0;
    for (r = 0; r < B->ring_count; r++) {
        const scene_ring *R = &s->rings[B->ring_first + r];
        uint32_t k;
        const vec2 *p = &s->pts[R->first + R->count - 1];
        for (k = 0; k < R->count; k++) {
            const vec2 *q = &s->pts[R->first + k];
            if ((p->y > y) != (q->y > y)) {
                double xc = p->x + (y - p->y) * (q->x - p->x) / (q->y - p->y);
                if (x < xc)
                    in ^= 1u;
            }
            p = q;
        }
    }
    return (int)in;
}

/* Whether (x, y) lies on an edge of building b's rings (to rounding: the
 * cross product of the edge and the point vanishes, within the edge's box).
 * Makes roofs closed like walls: a ray grazing a roof along its outline
 * hits it. */
static int on_outline(const scene *s, uint32_t b, double x, double y)
{
    const scene_building *B = &s->bld[b];
    uint32_t r;
    for (r = 0; r < B->ring_count; r++) {
        const scene_ring *R = &s->rings[B->ring_first + r];
        uint32_t k;
        const vec2 *p = &s->pts[R->first + R->count - 1];
        for (k = 0; k < R->count; k++) {
            const vec2 *q = &s->pts[R->first + k];
            if (x >= (p->x < q->x ? p->x : q->x) && x <= (p->x < q->x ? q->x : p->x) &&
                y >= (p->y < q->y ? p->y : q->y) && y <= (p->y < q->y ? q->y : p->y) &&
                (q->x - p->x) * (y - p->y) - (q->y - p->y) * (x - p->x) == 0.0)
                return 1;
            p = q;
        }
    }
    return 0;
}

/*
 * The horizontal faces of building b whose height lies in [zlo, zhi] (the
 * ray's heights over the part of its path being searched): the roof going
 * down, the underside (min_height > 0) going up. A hit when the ray meets
 * the plane at 0 < t < best inside the footprint or on its outline.
 */
static void cap_test(const tracer *T, uint32_t b, double zlo, double zhi, const double o[3],
                     const double d[3], best *bs)
{
    const scene_building *B;
    double zc, t, x, y;
    int kind;
    if (d[2] < 0.0) {
        zc = T->hz[2 * b + 1];
        kind = TRACE_ROOF;
    } else {
        zc = T->hz[2 * b];
        kind = TRACE_UNDER;
        if (!(zc > 0.0))
            return;
    }
    if (zc < zlo || zc > zhi)
        return;
    t = (zc - o[2]) / d[2];
    if (!(t > 0.0 && t < bs->t))
        return;
    x = o[0] + t * d[0];
    y = o[1] + t * d[1];
    B = &T->s->bld[b];
    if (x < B->box[0] || x > B->box[2] || y < B->box[1] || y > B->box[3] ||
        !(inside_footprint(T->s, b, x, y) || on_outline(T->s, b, x, y)))
        return;
    bs->t = t;
    bs->zc = zc;
    bs->bld = b;
    bs->albedo = B->albedo;
    bs->edge = TRACE_NONE;
    bs->kind = kind;
}

/* Every record of cell c, for the ray's heights za (entry) and zb (exit). */
static void cell_test(tracer *T, size_t c, double za, double zb, const double o[3],
                      const double d[3], best *bs)
{
    const trace_cell *C = &T->cells[c];
    double zlo = (za < zb ? za : zb) - TRACE_ZSLACK, zhi = (za < zb ? zb : za) + TRACE_ZSLACK;
    uint32_t k, k1;
    if (zlo > C->top)
        return; /* above every roof in the cell */
    k1 = C[1].w0;
    for (k = C->w0; k < k1; k++) {
        uint32_t e = T->wids[k];
        const trace_wall *w = &T->walls[e];
        if (w->zhi >= zlo && w->zlo <= zhi)
            wall_test(w, e, o, d, bs);
    }
    if (d[2] < 0.0 ? zhi < C->roof_lo : !(d[2] > 0.0 && zlo <= C->under_hi))
        return; /* no roof (going down) or underside (up) at the ray's heights */
    k1 = C[1].r0;
    for (k = C->r0; k < k1; k++)
        cap_test(T, T->ids[k], zlo, zhi, o, d, bs);
}

static int finish(const double o[3], const double d[3], const best *bs, trace_hit *h)
{
    h->t = bs->t;
    h->bld = bs->bld;
    h->albedo = bs->albedo;
    h->edge = bs->edge;
    h->kind = bs->kind;
    h->p[0] = o[0] + bs->t * d[0];
    h->p[1] = o[1] + bs->t * d[1];
    h->p[2] = o[2] + bs->t * d[2];
    h->n[0] = h->n[1] = h->n[2] = 0.0;
    switch (bs->kind) {
    case TRACE_GROUND:
        h->p[2] = 0.0;
        h->n[2] = 1.0;
        break;
    case TRACE_ROOF:
        h->p[2] = bs->zc;
        h->n[2] = 1.0;
        break;
    case TRACE_UNDER:
        h->p[2] = bs->zc;
        h->n[2] = -1.0;
        break;
    case TRACE_WALL: {
        double l = sqrt(bs->ex * bs->ex + bs->ey * bs->ey);
        h->n[0] = bs->ey / l;
        h->n[1] = -bs->ex / l;
        break;
    }
    default:
        break;
    }
    return bs->kind;
}

/* Starts a ray: the ground candidate. */
static void ray_begin(tracer *T, const double o[3], const double d[3], double tmax, best *bs)
{
    bs->t = tmax;
    bs->ex = bs->ey = bs->zc = 0.0;
    bs->bldv = T->s->bld;
    bs->bld = TRACE_NONE;
    bs->albedo = 0.0;
    bs->edge = TRACE_NONE;
    bs->kind = TRACE_SKY;
    if (d[2] < 0.0) {
        double tg = -o[2] / d[2];
        if (tg < tmax && tg > 0.0) {
            bs->t = tg;
            bs->kind = TRACE_GROUND;
        }
    }
}

/* Cuts [*t0, *t1] to the slab lo <= o + t d <= hi of one axis (inv = 1 / d);
 * 0 when the ray misses it. */
static int clip_axis(double o, double d, double inv, double lo, double hi, double *t0,
                     double *t1)
{
    double a, b;
    if (d == 0.0)
        return o >= lo && o <= hi;
    a = (lo - o) * inv;
    b = (hi - o) * inv;
    if (a > b) {
        double x = a;
        a = b;
        b = x;
    }
    if (a > *t0)
        *t0 = a;
    if (b < *t1)
        *t1 = b;
    return 1;
}

/* One axis of the walk: the cell index step, the t of the next border and
 * the t between borders (inv = 1 / d). */
static void dda_axis(double o, double d, double inv, double org, double cell, int32_t i,
                     int32_t *step, double *tnext, double *tdelta)
{
    if (d > 0.0) {
        *step = 1;
        *tdelta = cell * inv;
        *tnext = (org + (i + 1) * cell - o) * inv;
    } else if (d < 0.0) {
        *step = -1;
        *tdelta = -cell * inv;
        *tnext = (org + i * cell - o) * inv;
    } else {
        *step = 0;
        *tdelta = INFINITY;
        *tnext = INFINITY;
    }
}

/* Cell index of coordinate v, clamped to [0, n - 1]. */
static int32_t cell_of(double v, double org, double inv, uint32_t n)
{
    double f = floor((v - org) * inv);
    if (f < 0.0)
        f = 0.0;
    if (f > (double)(n - 1))
        f = (double)(n - 1);
    return (int32_t)f;
}

/* Walks the cells met by o + t d for t in [t0, t1] (2D DDA), testing each
 * one's records, until the best hit lies before the cell being left or the
 * ray leaves the grid. */
static void walk(tracer *T, const double o[3], const double d[3], const double inv[2],
                 double t0, double t1, best *bs)
{
    int32_t ix = cell_of(o[0] + t0 * d[0], T->x0, T->inv, T->nx);
    int32_t iy = cell_of(o[1] + t0 * d[1], T->y0, T->inv, T->ny);
    int32_t sx, sy, nx = (int32_t)T->nx, ny = (int32_t)T->ny;
    double tnx, tny, tdx, tdy, za = o[2] + t0 * d[2];
    dda_axis(o[0], d[0], inv[0], T->x0, T->cell, ix, &sx, &tnx, &tdx);
    dda_axis(o[1], d[1], inv[1], T->y0, T->cell, iy, &sy, &tny, &tdy);
    for (;;) {
        double te = tnx < tny ? tnx : tny, zb;
        size_t c = (size_t)iy * T->nx + (uint32_t)ix;
        int alongx = tnx < tny;
        int32_t jx = ix + (alongx ? sx : 0), jy = iy + (alongx ? 0 : sy);
        int inside = jx >= 0 && jx < nx && jy >= 0 && jy < ny;
        if (te > t1)
            te = t1;
        else if (inside)
            TRACE_PREFETCH(T->wids + T->cells[(size_t)jy * T->nx + (uint32_t)jx].w0);
        zb = o[2] + te * d[2];
        cell_test(T, c, za, zb, o, d, bs);
        if (bs->t <= te || te >= t1 || !inside)
            return;
        za = zb;
        ix = jx;
        iy = jy;
        if (alongx)
            tnx += tdx;
        else
            tny += tdy;
    }
}

int trace_ray(tracer *T, const double o[3], const double d[3], double tmax, trace_hit *h)
{
    best bs;
    double t0 = 0.0, t1, inv[2];
    double gx1 = T->x0 + T->nx * T->cell, gy1 = T->y0 + T->ny * T->cell;
    ray_begin(T, o, d, tmax, &bs);
    t1 = bs.t;
    /* above the tallest building and not going down: nothing to hit */
    if (d[2] >= 0.0 && o[2] > T->zmax)
        return finish(o, d, &bs, h);
    if (d[2] > 0.0) {
        double tt = (T->zmax - o[2]) / d[2];
        if (tt < t1)
            t1 = tt;
    } else if (d[2] < 0.0 && o[2] > T->zmax) {
        double tt = (T->zmax - o[2]) / d[2];
        if (tt > t0)
            t0 = tt;
    }
    inv[0] = d[0] != 0.0 ? 1.0 / d[0] : 0.0;
    inv[1] = d[1] != 0.0 ? 1.0 / d[1] : 0.0;
    /* a ray from inside the grid leaves it through the walk's index checks;
     * one from outside is first cut to the grid box */
    if (!(t0 == 0.0 && o[0] >= T->x0 && o[0] <= gx1 && o[1] >= T->y0 && o[1] <= gy1) &&
        !(clip_axis(o[0], d[0], inv[0], T->x0, gx1, &t0, &t1) &&
          clip_axis(o[1], d[1], inv[1], T->y0, gy1, &t0, &t1)))
        return finish(o, d, &bs, h);
    if (t0 <= t1)
        walk(T, o, d, inv, t0, t1, &bs);
    return finish(o, d, &bs, h);
}

int trace_lamp_ray(tracer *T, uint32_t lamp, const double d[3], trace_hit *h)
{
    const scene_lamp *L = &T->s->lamps[lamp];
    const uint32_t *sec;
    double o[3];
    best bs;
    uint32_t k, k1;
    o[0] = L->x;
    o[1] = L->y;
    o[2] = L->z;
    if (!T->lfast[lamp])
        return trace_ray(T, o, d, L->radius, h);
    sec = &T->lsec[(size_t)lamp * (TRACE_SECTORS + 2)];
    ray_begin(T, o, d, L->radius, &bs);
    if (d[0] != 0.0 || d[1] != 0.0) {
        uint32_t sk = sector_of(d[0], d[1]);
        k1 = sec[sk + 1];
        for (k = sec[sk]; k < k1; k++)
            wall_test(&T->walls[T->lref[k]], T->lref[k], o, d, &bs);
    }
    if (d[2] != 0.0) {
        k1 = sec[TRACE_SECTORS + 1];
        for (k = sec[TRACE_SECTORS]; k < k1; k++)
            cap_test(T, T->lref[k], -INFINITY, INFINITY, o, d, &bs);
    }
    return finish(o, d, &bs, h);
}

void trace_lamp_prefetch(const tracer *T, uint32_t lamp, int stage)
{
    const uint32_t *sec;
    uint32_t k, k1;
    if (lamp >= T->s->nlamps || !T->lsec)
        return;
    sec = &T->lsec[(size_t)lamp * (TRACE_SECTORS + 2)];
    if (stage == 0) {
        TRACE_PREFETCH(sec);
        TRACE_PREFETCH(sec + TRACE_SECTORS + 1);
        TRACE_PREFETCH(T->lfast + lamp);
        return;
    }
    if (!T->lfast[lamp])
        return;
    k1 = sec[TRACE_SECTORS + 1];
    if (stage == 1) {
        for (k = sec[0]; k < k1; k += 16)
            TRACE_PREFETCH(T->lref + k);
        if (k1 > sec[0])
            TRACE_PREFETCH(T->lref + k1 - 1);
        return;
    }
    k1 = sec[TRACE_SECTORS];
    for (k = sec[0]; k < k1; k++)
        TRACE_PREFETCH(T->walls + T->lref[k]);
}

int trace_ray_brute(tracer *T, const double o[3], const double d[3], double tmax, trace_hit *h)
{
    const scene *s = T->s;
    best bs;
    uint32_t b;
    ray_begin(T, o, d, tmax, &bs);
    for (b = 0; b < s->nbld; b++) {
        const scene_building *B = &s->bld[b];
        uint32_t r;
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            uint32_t k;
            for (k = 0; k < R->count; k++) {
                wall_test(&T->walls[R->first + k], R->first + k, o, d, &bs);
            }
        }
        if (d[2] != 0.0)
            cap_test(T, b, -INFINITY, INFINITY, o, d, &bs);
    }
    return finish(o, d, &bs, h);
}

int trace_box_clear(const tracer *T, double x0, double y0, double x1, double y1, double z0,
                    double z1)
{
    double lo[2], hi[2], big = fabs(x0), m;
    uint32_t i0, i1, j0, j1, ci, cj, k;
    if (fabs(y0) > big)
        big = fabs(y0);
    if (fabs(x1) > big)
        big = fabs(x1);
    if (fabs(y1) > big)
        big = fabs(y1);
    m = TRACE_BOX_PAD * (1.0 + big);
    lo[0] = x0 - m;
    lo[1] = y0 - m;
    hi[0] = x1 + m;
    hi[1] = y1 + m;
    if (!(z0 <= T->zmax))
        return 1; /* above every wall (a horizontal ray there meets none) */
    i0 = (uint32_t)cell_of(lo[0], T->x0, T->inv, T->nx);
    i1 = (uint32_t)cell_of(hi[0], T->x0, T->inv, T->nx);
    j0 = (uint32_t)cell_of(lo[1], T->y0, T->inv, T->ny);
    j1 = (uint32_t)cell_of(hi[1], T->y0, T->inv, T->ny);
    for (cj = j0; cj <= j1; cj++)
        for (ci = i0; ci <= i1; ci++) {
            const trace_cell *C = &T->cells[(size_t)cj * T->nx + ci];
            for (k = C->w0; k < C[1].w0; k++) {
                const trace_wall *w = &T->walls[T->wids[k]];
                if (z1 >= w->zlo && z0 <= w->zhi && seg_meets_box(w->px, w->py, w->ex, w->ey, lo, hi))
                    return 0;
            }
        }
    return 1;
}

/* Horizon sector of pseudo-angle a (any real: taken modulo 4). */
static uint32_t horizon_sector(double a)
{
    int64_t k = (int64_t)floor(a * (TRACE_HORIZON_SECTORS / 4.0));
    k %= TRACE_HORIZON_SECTORS;
    return (uint32_t)(k < 0 ? k + TRACE_HORIZON_SECTORS : k);
}

/* Building b's share of the horizon from o: the sectors its box spans
 * (one more each side) get at least the tangent over its nearest point;
 * 0 when o lies within pad of the box (no shortcut then). */
static int horizon_add(const tracer *T, uint32_t b, const double o[3], double pad,
                       trace_horizon *hz)
{
    const scene_building *B = &T->s->bld[b];
    double hgt = T->hz[2 * b + 1], dx, dy, dist, tn, a[4], lo, hi;
    uint32_t k, k0, n;
    int c;
    if (hgt < o[2])
        return 1; /* a ray going up from o stays above it */
    dx = fmax(fmax(B->box[0] - o[0], o[0] - B->box[2]), 0.0);
    dy = fmax(fmax(B->box[1] - o[1], o[1] - B->box[3]), 0.0);
    dist = sqrt(dx * dx + dy * dy);
    if (!(dist < hz->r))
        return 1;
    if (!(dist > 2.0 * pad))
        return 0;
    tn = (hgt - o[2] + TRACE_HORIZON_DZ) / (dist - pad);
    tn *= tn * (1.0 + 1e-9); /* kept squared, and a hair up */
    for (c = 0; c < 4; c++)
        a[c] = pseudo_angle(B->box[c & 1 ? 2 : 0] - o[0], B->box[c & 2 ? 3 : 1] - o[1]);
    lo = fmin(fmin(a[0], a[1]), fmin(a[2], a[3]));
    hi = fmax(fmax(a[0], a[1]), fmax(a[2], a[3]));
    if (hi - lo > 2.0) { /* the span crosses pseudo-angle 0: from hi to lo + 4 */
        double l2 = 4.0, h2 = 0.0;
        for (c = 0; c < 4; c++) {
            if (a[c] >= 2.0 && a[c] < l2)
                l2 = a[c];
            if (a[c] < 2.0 && a[c] > h2)
                h2 = a[c];
        }
        lo = l2;
        hi = h2 + 4.0;
    }
    k0 = horizon_sector(lo);
    n = (horizon_sector(hi) + TRACE_HORIZON_SECTORS - k0) % TRACE_HORIZON_SECTORS + 3;
    k0 += TRACE_HORIZON_SECTORS - 1;
    if (n > TRACE_HORIZON_SECTORS)
        n = TRACE_HORIZON_SECTORS;
    for (k = 0; k < n; k++) {
        double *t = &hz->tan2[(k0 + k) % TRACE_HORIZON_SECTORS];
        if (tn > *t)
            *t = tn;
    }
    return 1;
}

void trace_horizon_make(const tracer *T, const double o[3], trace_horizon *hz)
{
    double big = fmax(fmax(fabs(o[0]), fabs(o[1])), 1.0), pad = TRACE_BOX_PAD * big;
    uint32_t i0, i1, j0, j1, ci, cj, k;
    memset(hz, 0, sizeof *hz);
    if (!(o[2] >= 0.0 && o[2] <= T->zmax))
        return; /* above every building trace_ray answers at once */
    hz->r = 2.0 * (T->zmax - o[2]) + T->cell;
    hz->rise2 = (T->zmax + TRACE_HORIZON_DZ - o[2]) / hz->r;
    hz->rise2 *= hz->rise2 * (1.0 + 1e-9);
    i0 = (uint32_t)cell_of(o[0] - hz->r, T->x0, T->inv, T->nx);
    i1 = (uint32_t)cell_of(o[0] + hz->r, T->x0, T->inv, T->nx);
    j0 = (uint32_t)cell_of(o[1] - hz->r, T->y0, T->inv, T->ny);
    j1 = (uint32_t)cell_of(o[1] + hz->r, T->y0, T->inv, T->ny);
    for (cj = j0; cj <= j1; cj++)
        for (ci = i0; ci <= i1; ci++) {
            size_t c = (size_t)cj * T->nx + ci;
            for (k = T->start[c]; k < T->start[c + 1]; k++)
                if (!horizon_add(T, T->ids[k], o, pad, hz))
                    return; /* o on or in a building's box */
        }
    hz->on = 1;
}

int trace_horizon_sky(const trace_horizon *hz, const double d[3])
{
    double h2 = d[0] * d[0] + d[1] * d[1], z2 = d[2] * d[2];
    uint32_t k;
    if (!hz->on || !(d[2] > 0.0) || !(h2 > 0.0))
        return 0;
    /* above the tallest building beyond r: o_z + r d_z / |d_xy| over it */
    if (!(z2 > hz->rise2 * h2))
        return 0;
    /* and above every building within r in its sector */
    k = (uint32_t)(pseudo_angle(d[0], d[1]) * (TRACE_HORIZON_SECTORS / 4.0));
    return z2 > hz->tan2[k >= TRACE_HORIZON_SECTORS ? k - TRACE_HORIZON_SECTORS : k] * h2;
}

double trace_top(tracer *T, double x, double y, uint32_t *bld)
{
    double fx = floor((x - T->x0) * T->inv), fy = floor((y - T->y0) * T->inv);
    double top = 0.0;
    uint32_t k, k1, c, who = TRACE_NONE;
    if (bld)
        *bld = TRACE_NONE;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < (double)T->nx && fy < (double)T->ny))
        return 0.0;
    c = (uint32_t)fy * T->nx + (uint32_t)fx;
    k1 = T->start[c + 1];
    for (k = T->start[c]; k < k1; k++) {
        uint32_t b = T->ids[k];
        const scene_building *B = &T->s->bld[b];
        if (B->height <= top || x < B->box[0] || x > B->box[2] || y < B->box[1] ||
            y > B->box[3])
            continue;
        if (inside_footprint(T->s, b, x, y)) {
            top = B->height;
            who = b;
        }
    }
    if (bld)
        *bld = who;
    return top;
}

int trace_inside(const tracer *T, uint32_t b, double x, double y)
{
    return inside_footprint(T->s, b, x, y);
}
