/* ref_trace_old: the grid caster of src/photon/trace.c before the wall-grid
 * rewrite (see ref_trace_old.h). Kept verbatim but for the names. */
#include <math.h>
#include <string.h>

#include "ref_trace_old.h"

#define OLD_MAX_CELLS (1u << 22)

static double grid_cell_size(const scene *s, double cell_size)
{
    double w = s->bounds[2] - s->bounds[0], hgt = s->bounds[3] - s->bounds[1];
    double c = cell_size;
    if (!(w > 0.0))
        w = 1.0;
    if (!(hgt > 0.0))
        hgt = 1.0;
    if (!(c > 0.0)) {
        double per = w * hgt / (double)(s->nbld > 0 ? s->nbld : 1);
        c = 0.75 * sqrt(per);
        if (c < 2.0)
            c = 2.0;
    }
    /* at most OLD_MAX_CELLS cells */
    while ((w / c + 1.0) * (hgt / c + 1.0) > (double)OLD_MAX_CELLS)
        c *= 1.25;
    return c;
}

static void grid_dims(const scene *s, double c, uint32_t *nx, uint32_t *ny)
{
    double w = s->bounds[2] - s->bounds[0], hgt = s->bounds[3] - s->bounds[1];
    double fx = ceil(w / c), fy = ceil(hgt / c);
    *nx = fx < 1.0 ? 1u : (uint32_t)fx;
    *ny = fy < 1.0 ? 1u : (uint32_t)fy;
}

/* Cell range [i0, i1] covered by [lo, hi] along one axis, clamped. */
static void cell_range(double lo, double hi, double org, double inv, uint32_t n,
                       uint32_t *i0, uint32_t *i1)
{
    double a = floor((lo - org) * inv), b = floor((hi - org) * inv);
    if (a < 0.0)
        a = 0.0;
    if (b > (double)(n - 1))
        b = (double)(n - 1);
    if (b < 0.0)
        b = 0.0;
    if (a > (double)(n - 1))
        a = (double)(n - 1);
    *i0 = (uint32_t)a;
    *i1 = (uint32_t)b;
}

static size_t count_refs(const scene *s, double x0, double y0, double inv, uint32_t nx,
                         uint32_t ny)
{
    size_t refs = 0;
    uint32_t b;
    for (b = 0; b < s->nbld; b++) {
        uint32_t i0, i1, j0, j1;
        cell_range(s->bld[b].box[0], s->bld[b].box[2], x0, inv, nx, &i0, &i1);
        cell_range(s->bld[b].box[1], s->bld[b].box[3], y0, inv, ny, &j0, &j1);
        refs += (size_t)(i1 - i0 + 1) * (j1 - j0 + 1);
    }
    return refs;
}

size_t old_trace_bytes(const scene *s, double cell_size)
{
    double c;
    uint32_t nx, ny;
    size_t cells, refs;
    if (!s)
        return 0;
    c = grid_cell_size(s, cell_size);
    grid_dims(s, c, &nx, &ny);
    cells = (size_t)nx * ny;
    refs = count_refs(s, s->bounds[0], s->bounds[1], 1.0 / c, nx, ny);
    return sizeof(old_tracer) + 64 + (cells + 1) * sizeof(uint32_t) + 64 +
           refs * sizeof(uint32_t) + 64 + cells * sizeof(float) + 64 +
           (size_t)s->npts * sizeof(uint32_t) + 64 + (size_t)s->nbld * sizeof(uint32_t) + 64;
}

plx_status old_trace_create(arena *a, plx_part part, const scene *s, double cell_size,
                        old_tracer **out)
{
    arena_mark m;
    old_tracer *T;
    size_t cells, refs;
    uint32_t b, i;
    if (!a || !s || !out)
        return PLX_E_INVALID;
    *out = NULL;
    m = arena_get_mark(a);
    T = arena_calloc(a, part, 1, sizeof *T, 16);
    if (!T)
        goto nomem;
    T->s = s;
    T->cell = grid_cell_size(s, cell_size);
    T->inv = 1.0 / T->cell;
    T->x0 = s->bounds[0];
    T->y0 = s->bounds[1];
    grid_dims(s, T->cell, &T->nx, &T->ny);
    cells = (size_t)T->nx * T->ny;
    refs = count_refs(s, T->x0, T->y0, T->inv, T->nx, T->ny);
    T->start = arena_calloc(a, part, cells + 1, sizeof(uint32_t), 16);
    T->ids = arena_alloc(a, part, (refs ? refs : 1) * sizeof(uint32_t), 16);
    T->top = arena_calloc(a, part, cells, sizeof(float), 16);
    T->enext = arena_alloc(a, part, (s->npts ? s->npts : 1) * sizeof(uint32_t), 16);
    T->stamp = arena_calloc(a, part, s->nbld ? s->nbld : 1, sizeof(uint32_t), 16);
    if (!T->start || !T->ids || !T->top || !T->enext || !T->stamp)
        goto nomem;
    /* counting sort of (cell, building) references */
    for (b = 0; b < s->nbld; b++) {
        uint32_t i0, i1, j0, j1, ci, cj;
        cell_range(s->bld[b].box[0], s->bld[b].box[2], T->x0, T->inv, T->nx, &i0, &i1);
        cell_range(s->bld[b].box[1], s->bld[b].box[3], T->y0, T->inv, T->ny, &j0, &j1);
        for (cj = j0; cj <= j1; cj++)
            for (ci = i0; ci <= i1; ci++) {
                size_t c = (size_t)cj * T->nx + ci;
                T->start[c + 1]++;
                if ((float)s->bld[b].height > T->top[c])
                    T->top[c] = (float)s->bld[b].height;
            }
        if (s->bld[b].height > T->zmax)
            T->zmax = s->bld[b].height;
    }
    for (i = 0; i < cells; i++)
        T->start[i + 1] += T->start[i];
    for (b = 0; b < s->nbld; b++) {
        uint32_t i0, i1, j0, j1, ci, cj;
        cell_range(s->bld[b].box[0], s->bld[b].box[2], T->x0, T->inv, T->nx, &i0, &i1);
        cell_range(s->bld[b].box[1], s->bld[b].box[3], T->y0, T->inv, T->ny, &j0, &j1);
        for (cj = j0; cj <= j1; cj++)
            for (ci = i0; ci <= i1; ci++)
                T->ids[T->start[(size_t)cj * T->nx + ci]++] = b;
    }
    for (i = (uint32_t)cells; i > 0; i--)
        T->start[i] = T->start[i - 1];
    T->start[0] = 0;
    /* the float top is rounded: make it an upper bound */
    for (i = 0; i < cells; i++)
        if (T->top[i] > 0.0f)
            T->top[i] = nextafterf(T->top[i], INFINITY);
    for (i = 0; i < s->nrings; i++) {
        uint32_t f = s->rings[i].first, n = s->rings[i].count, k;
        for (k = 0; k < n; k++)
            T->enext[f + k] = f + (k + 1 == n ? 0 : k + 1);
    }
    *out = T;
    return PLX_OK;
nomem:
    arena_release(a, &m);
    return PLX_E_NOMEM;
}

/* The best hit so far. */
typedef struct best {
    double t;
    uint32_t bld, edge;
    int kind;
} best;

/*
 * Entry of o + t d into building b for t in (tlo, best->t): updates best.
 */
static void prism(const old_tracer *T, uint32_t b, const double o[3], const double d[3],
                  double tlo, best *bs)
{
    const scene *s = T->s;
    const scene_building *B = &s->bld[b];
    double ta, tb, lo, hi;
    double dx = d[0], dy = d[1];
    uint32_t r, parity = 0, first_edge = TRACE_NONE;
    double first_t = INFINITY;
    int vertical;
    if (d[2] != 0.0) {
        double inv = 1.0 / d[2];
        ta = (B->min_height - o[2]) * inv;
        tb = (B->height - o[2]) * inv;
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
    } else {
        if (!(o[2] >= B->min_height && o[2] <= B->height))
            return;
        ta = -INFINITY;
        tb = INFINITY;
    }
    lo = ta > tlo ? ta : tlo;
    hi = tb < bs->t ? tb : bs->t;
    if (!(lo <= hi) || lo >= bs->t)
        return;
    vertical = (dx == 0.0 && dy == 0.0);
    if (vertical) {
        /* crossing number of a ray from (o.x, o.y) towards +x */
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            uint32_t k;
            for (k = 0; k < R->count; k++) {
                const vec2 *p = &s->pts[R->first + k];
                const vec2 *q = &s->pts[R->first + (k + 1 == R->count ? 0 : k + 1)];
                int sp = p->y >= o[1], sq = q->y >= o[1];
                if (sp != sq) {
                    double xc = p->x + (o[1] - p->y) * (q->x - p->x) / (q->y - p->y);
                    if (xc > o[0])
                        parity ^= 1u;
                }
            }
        }
        if (parity && lo == ta && ta > tlo) {
            bs->t = ta;
            bs->bld = b;
            bs->edge = TRACE_NONE;
            bs->kind = d[2] < 0.0 ? TRACE_ROOF : TRACE_UNDER;
        }
        return;
    }
    for (r = 0; r < B->ring_count; r++) {
        const scene_ring *R = &s->rings[B->ring_first + r];
        uint32_t k, n = R->count;
        const vec2 *pp = &s->pts[R->first + n - 1];
        double sp = dx * (pp->y - o[1]) - dy * (pp->x - o[0]);
        for (k = 0; k < n; k++) {
            const vec2 *q = &s->pts[R->first + k];
            double sq = dx * (q->y - o[1]) - dy * (q->x - o[0]);
            if ((sp >= 0.0) != (sq >= 0.0)) {
                /* the line crosses edge pp->q */
                double ex = q->x - pp->x, ey = q->y - pp->y;
                double den = dx * ey - dy * ex;
                double t = ((pp->x - o[0]) * ey - (pp->y - o[1]) * ex) / den;
                if (t < lo)
                    parity ^= 1u;
                else if (t < first_t) {
                    first_t = t;
                    first_edge = R->first + (k == 0 ? n - 1 : k - 1);
                }
            }
            pp = q;
            sp = sq;
        }
    }
    if (parity) {
        /* inside the footprint at lo */
        if (lo == ta && ta > tlo && ta < bs->t) {
            bs->t = ta;
            bs->bld = b;
            bs->edge = TRACE_NONE;
            bs->kind = d[2] < 0.0 ? TRACE_ROOF : TRACE_UNDER;
        }
        return; /* else the ray starts inside the solid: ignored */
    }
    if (first_edge != TRACE_NONE && first_t <= hi && first_t < bs->t && first_t > tlo) {
        bs->t = first_t;
        bs->bld = b;
        bs->edge = first_edge;
        bs->kind = TRACE_WALL;
    }
}

static int finish(const old_tracer *T, const double o[3], const double d[3], const best *bs,
                  trace_hit *h)
{
    h->t = bs->t;
    h->bld = bs->bld;
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
        h->p[2] = T->s->bld[bs->bld].height;
        h->n[2] = 1.0;
        break;
    case TRACE_UNDER:
        h->p[2] = T->s->bld[bs->bld].min_height;
        h->n[2] = -1.0;
        break;
    case TRACE_WALL: {
        const vec2 *p = &T->s->pts[bs->edge], *q = &T->s->pts[T->enext[bs->edge]];
        double ex = q->x - p->x, ey = q->y - p->y, l = sqrt(ex * ex + ey * ey);
        h->n[0] = ey / l;
        h->n[1] = -ex / l;
        break;
    }
    default:
        break;
    }
    return bs->kind;
}

/* Starts a ray: the ground candidate and the stamp. */
static void ray_begin(old_tracer *T, const double o[3], const double d[3], double tmax,
                      best *bs)
{
    bs->t = tmax;
    bs->bld = TRACE_NONE;
    bs->edge = TRACE_NONE;
    bs->kind = TRACE_SKY;
    if (d[2] < 0.0) {
        double tg = -o[2] / d[2];
        if (tg < tmax && tg > 0.0) {
            bs->t = tg;
            bs->kind = TRACE_GROUND;
        }
    }
    T->rays++;
    if (++T->now == 0) {
        memset(T->stamp, 0, (size_t)(T->s->nbld ? T->s->nbld : 1) * sizeof(uint32_t));
        T->now = 1;
    }
}

int old_trace_ray(old_tracer *T, const double o[3], const double d[3], double tmax,
                  trace_hit *h)
{
    best bs;
    double t0 = 0.0, t1;
    double gx1, gy1;
    ray_begin(T, o, d, tmax, &bs);
    t1 = bs.t;
    /* above the tallest building and not going down: nothing to hit */
    if (d[2] >= 0.0 && o[2] >= T->zmax)
        return finish(T, o, d, &bs, h);
    if (d[2] > 0.0) {
        double tt = (T->zmax - o[2]) / d[2];
        if (tt < t1)
            t1 = tt;
    } else if (d[2] < 0.0 && o[2] > T->zmax) {
        double tt = (T->zmax - o[2]) / d[2];
        if (tt > t0)
            t0 = tt;
    }
    gx1 = T->x0 + T->nx * T->cell;
    gy1 = T->y0 + T->ny * T->cell;
    /* clip to the grid box */
    if (d[0] != 0.0) {
        double a = (T->x0 - o[0]) / d[0], b = (gx1 - o[0]) / d[0];
        if (a > b) {
            double x = a;
            a = b;
            b = x;
        }
        if (a > t0)
            t0 = a;
        if (b < t1)
            t1 = b;
    } else if (o[0] < T->x0 || o[0] > gx1) {
        return finish(T, o, d, &bs, h);
    }
    if (d[1] != 0.0) {
        double a = (T->y0 - o[1]) / d[1], b = (gy1 - o[1]) / d[1];
        if (a > b) {
            double x = a;
            a = b;
            b = x;
        }
        if (a > t0)
            t0 = a;
        if (b < t1)
            t1 = b;
    } else if (o[1] < T->y0 || o[1] > gy1) {
        return finish(T, o, d, &bs, h);
    }
    if (!(t0 <= t1))
        return finish(T, o, d, &bs, h);
    {
        double px = o[0] + t0 * d[0], py = o[1] + t0 * d[1];
        double fx = floor((px - T->x0) * T->inv), fy = floor((py - T->y0) * T->inv);
        int32_t ix, iy, sx, sy;
        double tnx, tny, tdx, tdy, tc = t0;
        if (fx < 0.0)
            fx = 0.0;
        if (fx > (double)(T->nx - 1))
            fx = (double)(T->nx - 1);
        if (fy < 0.0)
            fy = 0.0;
        if (fy > (double)(T->ny - 1))
            fy = (double)(T->ny - 1);
        ix = (int32_t)fx;
        iy = (int32_t)fy;
        if (d[0] > 0.0) {
            sx = 1;
            tdx = T->cell / d[0];
            tnx = (T->x0 + (ix + 1) * T->cell - o[0]) / d[0];
        } else if (d[0] < 0.0) {
            sx = -1;
            tdx = -T->cell / d[0];
            tnx = (T->x0 + ix * T->cell - o[0]) / d[0];
        } else {
            sx = 0;
            tdx = INFINITY;
            tnx = INFINITY;
        }
        if (d[1] > 0.0) {
            sy = 1;
            tdy = T->cell / d[1];
            tny = (T->y0 + (iy + 1) * T->cell - o[1]) / d[1];
        } else if (d[1] < 0.0) {
            sy = -1;
            tdy = -T->cell / d[1];
            tny = (T->y0 + iy * T->cell - o[1]) / d[1];
        } else {
            sy = 0;
            tdy = INFINITY;
            tny = INFINITY;
        }
        for (;;) {
            size_t c = (size_t)iy * T->nx + (uint32_t)ix;
            double te = tnx < tny ? tnx : tny;
            double za, zb;
            if (te > t1)
                te = t1;
            za = o[2] + tc * d[2];
            zb = o[2] + te * d[2];
            if ((za < zb ? za : zb) <= (double)T->top[c]) {
                uint32_t k, k1 = T->start[c + 1];
                for (k = T->start[c]; k < k1; k++) {
                    uint32_t b = T->ids[k];
                    if (T->stamp[b] == T->now)
                        continue;
                    T->stamp[b] = T->now;
                    T->tests++;
                    prism(T, b, o, d, 0.0, &bs);
                }
            }
            if (bs.t <= te || te >= t1)
                break;
            tc = te;
            if (tnx < tny) {
                ix += sx;
                tnx += tdx;
                if (ix < 0 || ix >= (int32_t)T->nx)
                    break;
            } else {
                iy += sy;
                tny += tdy;
                if (iy < 0 || iy >= (int32_t)T->ny)
                    break;
            }
        }
    }
    return finish(T, o, d, &bs, h);
}

int old_trace_ray_brute(old_tracer *T, const double o[3], const double d[3], double tmax,
                        trace_hit *h)
{
    best bs;
    uint32_t b;
    ray_begin(T, o, d, tmax, &bs);
    for (b = 0; b < T->s->nbld; b++) {
        T->tests++;
        prism(T, b, o, d, 0.0, &bs);
    }
    return finish(T, o, d, &bs, h);
}
