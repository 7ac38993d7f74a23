/* raster: the minimal software rasteriser. See raster.h for the conventions,
 * the fixed-point format and the fill rule. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <math.h>
#include "render/raster.h"

/* Fixed-point window coordinates: RASTER_SUBPIXEL_BITS fraction bits. */
#define FIX_ONE  ((int64_t)1 << RASTER_SUBPIXEL_BITS)   /* one pixel */
#define FIX_HALF (FIX_ONE / 2)                          /* pixel centre offset */
/* Snapped coordinates are clamped to +-FIX_LIMIT. The guard band keeps valid
 * input within +-(RASTER_MAX_DIM + RASTER_GUARD_PX) pixels, about 2^22.6
 * units, so the clamp only guards against rounding at the guard planes. */
#define FIX_LIMIT ((int64_t)1 << 24)
/* draw_triangle_id tests every pixel of a box at most this many columns
 * wide (walls seen from afar are slivers a pixel or two wide, where the
 * spans' setup per row costs more than the pixels). */
#ifndef RASTER_NARROW
#define RASTER_NARROW 8
#endif

/* Clip planes, applied in this order. */
enum { PLANE_W = 0, PLANE_NEAR, PLANE_FAR, PLANE_LEFT, PLANE_RIGHT,
       PLANE_BOTTOM, PLANE_TOP, PLANE_COUNT };
/* A triangle clipped by PLANE_COUNT planes has at most 3 + PLANE_COUNT vertices. */
#define POLY_MAX (3 + PLANE_COUNT)

/* A vertex in window space: snapped position, depth, 1/w, attr/w. */
typedef struct svert {
    int64_t x, y;
    double z;
    float iw;
    float a[RASTER_MAX_ATTRS];
} svert;

/* ---- small helpers ---------------------------------------------------- */

static int64_t floor_div(int64_t a, int64_t b) /* b > 0 */
{
    int64_t q = a / b;
    if ((a % b != 0) && (a < 0))
        q--;
    return q;
}

static int64_t ceil_div(int64_t a, int64_t b) /* b > 0 */
{
    return -floor_div(-a, b);
}

/* floor(a / FIX_ONE) for |a| < FIX_OFFSET, by a shift of a + FIX_OFFSET
 * (>= 0, so the shift is a plain division by the power of two): the
 * same value as floor_div(a, FIX_ONE) without the division's branches. */
#define FIX_OFFSET ((int64_t)1 << 40)
static int64_t fix_floor(int64_t a)
{
    return ((a + FIX_OFFSET) >> RASTER_SUBPIXEL_BITS) - (FIX_OFFSET >> RASTER_SUBPIXEL_BITS);
}

static int64_t min64(int64_t a, int64_t b) { return a < b ? a : b; }
static int64_t max64(int64_t a, int64_t b) { return a > b ? a : b; }

/* Twice the signed area of a, b, c in fixed units squared; > 0 when c lies
 * on the interior side of every edge of the triangle a, b, c as defined by
 * the edge function below (clockwise on screen, as y points down). */
static int64_t area2(const svert *a, const svert *b, const svert *c)
{
    return (b->x - a->x) * (c->y - a->y) - (b->y - a->y) * (c->x - a->x);
}

static unsigned char to_u8(float v)
{
    if (!(v > 0.0f))            /* also NaN */
        return 0;
    if (v >= 1.0f)
        return 255;
    return (unsigned char)(v * 255.0f + 0.5f);
}

/* ---- per-format write paths ------------------------------------------ */

static void store_rgba8(unsigned char *row, int64_t x, const float c[4])
{
    unsigned char *p = row + (size_t)x * 4;
    p[0] = to_u8(c[0]);
    p[1] = to_u8(c[1]);
    p[2] = to_u8(c[2]);
    p[3] = to_u8(c[3]);
}

static void store_rgb_f32(unsigned char *row, int64_t x, const float c[4])
{
    float *p = (float *)(void *)row + (size_t)x * 3;
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
}

static void store_rgba_f32(unsigned char *row, int64_t x, const float c[4])
{
    float *p = (float *)(void *)row + (size_t)x * 4;
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
    p[3] = c[3];
}

static size_t format_bytes(raster_format f)
{
    switch (f) {
    case RASTER_RGBA8:    return 4;
    case RASTER_RGB_F32:  return 3 * sizeof(float);
    case RASTER_RGBA_F32: return 4 * sizeof(float);
    }
    return 0;
}

/* ---- set-up ------------------------------------------------------------ */

plx_status raster_init(raster_ctx *r, const raster_target *t, const char **why)
{
    const char *msg = NULL;
    raster_target tt;
    size_t bpp;

    if (r == NULL || t == NULL) {
        if (why) *why = "raster_init: context or target is NULL";
        return PLX_E_INVALID;
    }
    tt = *t;
    bpp = format_bytes(tt.format);
    if (bpp == 0)
        msg = "raster_init: unknown colour format";
    else if (tt.width < 1 || tt.width > RASTER_MAX_DIM)
        msg = "raster_init: width outside 1..RASTER_MAX_DIM";
    else if (tt.height < 1 || tt.height > RASTER_MAX_DIM)
        msg = "raster_init: height outside 1..RASTER_MAX_DIM";
    if (msg == NULL && tt.color != NULL) {
        if (tt.color_stride == 0)
            tt.color_stride = bpp * (size_t)tt.width;
        if (tt.color_stride < bpp * (size_t)tt.width)
            msg = "raster_init: colour stride is shorter than one row";
        else if (tt.format != RASTER_RGBA8 && tt.color_stride % sizeof(float) != 0)
            msg = "raster_init: float colour stride is not a multiple of sizeof(float)";
    }
    if (msg == NULL && tt.depth != NULL) {
        if (tt.depth_stride == 0)
            tt.depth_stride = (size_t)tt.width;
        if (tt.depth_stride < (size_t)tt.width)
            msg = "raster_init: depth stride is shorter than one row";
    }
    if (msg != NULL) {
        if (why) *why = msg;
        return PLX_E_INVALID;
    }

    memset(r, 0, sizeof *r);
    r->t = tt;
    r->sx0 = 0;
    r->sy0 = 0;
    r->sx1 = tt.width;
    r->sy1 = tt.height;
    r->nattr = 0;
    r->cull = RASTER_CULL_NONE;
    r->depth_test = 1;
    r->depth_write = 1;
    r->frag = NULL;
    r->user = NULL;
    /* x/w = gx maps to RASTER_GUARD_PX pixels beyond the right edge. */
    r->gx = (float)(1.0 + 2.0 * RASTER_GUARD_PX / (double)tt.width);
    r->gy = (float)(1.0 + 2.0 * RASTER_GUARD_PX / (double)tt.height);
    if (why) *why = NULL;
    return PLX_OK;
}

void raster_set_fragment(raster_ctx *r, raster_fragment_fn fn, void *user, int nattr)
{
    if (nattr < 0) nattr = 0;
    if (nattr > RASTER_MAX_ATTRS) nattr = RASTER_MAX_ATTRS;
    r->frag = fn;
    r->user = user;
    r->nattr = nattr;
}

void raster_set_scissor(raster_ctx *r, int32_t x0, int32_t y0, int32_t x1, int32_t y1)
{
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > r->t.width) x1 = r->t.width;
    if (y1 > r->t.height) y1 = r->t.height;
    if (x1 < x0) x1 = x0;
    if (y1 < y0) y1 = y0;
    r->sx0 = x0;
    r->sy0 = y0;
    r->sx1 = x1;
    r->sy1 = y1;
}

void raster_set_cull(raster_ctx *r, raster_cull cull)
{
    r->cull = cull;
}

void raster_set_depth(raster_ctx *r, int test, int write)
{
    r->depth_test = test != 0;
    r->depth_write = write != 0;
}

void raster_clear_color(raster_ctx *r, const float rgba[4])
{
    int32_t x, y;
    unsigned char *row;

    if (r->t.color == NULL)
        return;
    for (y = 0; y < r->t.height; y++) {
        row = (unsigned char *)r->t.color + (size_t)y * r->t.color_stride;
        for (x = 0; x < r->t.width; x++) {
            switch (r->t.format) {
            case RASTER_RGBA8:    store_rgba8(row, x, rgba); break;
            case RASTER_RGB_F32:  store_rgb_f32(row, x, rgba); break;
            case RASTER_RGBA_F32: store_rgba_f32(row, x, rgba); break;
            }
        }
    }
}

/* A row's depths set to d: CLEAR_LANES at a time in a loop of fixed
 * length (which GCC vectorises at -O2), then the rest. */
#define CLEAR_LANES 16
static void clear_row(float *restrict row, int32_t n, float d)
{
    int32_t x = 0;
    int k;
    for (; x + CLEAR_LANES <= n; x += CLEAR_LANES)
        for (k = 0; k < CLEAR_LANES; k++)
            row[x + k] = d;
    for (; x < n; x++)
        row[x] = d;
}

void raster_clear_depth(raster_ctx *r, float depth)
{
    int32_t y;

    if (r->t.depth == NULL)
        return;
    for (y = 0; y < r->t.height; y++)
        clear_row(r->t.depth + (size_t)y * r->t.depth_stride, r->t.width, depth);
}

/* ---- clipping ---------------------------------------------------------- */

/* Signed distance of clip-space point p to plane k; >= 0 is inside. */
static float plane_dist(const raster_ctx *r, int k, const float *p)
{
    switch (k) {
    case PLANE_W:      return p[3] - RASTER_W_EPSILON;
    case PLANE_NEAR:   return p[2] + p[3];
    case PLANE_FAR:    return p[3] - p[2];
    case PLANE_LEFT:   return p[0] + r->gx * p[3];
    case PLANE_RIGHT:  return r->gx * p[3] - p[0];
    case PLANE_BOTTOM: return p[1] + r->gy * p[3];
    default:           return r->gy * p[3] - p[1];
    }
}

/* The planes point p is outside of, a bit each: plane_dist's expressions
 * written out (the loop over its switch cost 75 instructions a vertex),
 * each distance stored in a float first as plane_dist's return rounds it
 * (the same bits where floats are evaluated wider, FLT_EVAL_METHOD 2). */
static inline unsigned outcode(const raster_ctx *r, const float *p)
{
    float gxw = r->gx * p[3], gyw = r->gy * p[3];
    float d[PLANE_COUNT];
    d[PLANE_W] = p[3] - RASTER_W_EPSILON;
    d[PLANE_NEAR] = p[2] + p[3];
    d[PLANE_FAR] = p[3] - p[2];
    d[PLANE_LEFT] = p[0] + gxw;
    d[PLANE_RIGHT] = gxw - p[0];
    d[PLANE_BOTTOM] = p[1] + gyw;
    d[PLANE_TOP] = gyw - p[1];
    return (unsigned)(d[PLANE_W] < 0.0f) << PLANE_W | (unsigned)(d[PLANE_NEAR] < 0.0f) << PLANE_NEAR |
           (unsigned)(d[PLANE_FAR] < 0.0f) << PLANE_FAR | (unsigned)(d[PLANE_LEFT] < 0.0f) << PLANE_LEFT |
           (unsigned)(d[PLANE_RIGHT] < 0.0f) << PLANE_RIGHT | (unsigned)(d[PLANE_BOTTOM] < 0.0f) << PLANE_BOTTOM |
           (unsigned)(d[PLANE_TOP] < 0.0f) << PLANE_TOP; /* written out: the loop cost 58 instructions a vertex */
}

/* The point where edge (in, out) crosses a plane, computed from the inside
 * end so that both triangles sharing the edge get the same bits. */
static void intersect(raster_vertex *o, const raster_vertex *in, const raster_vertex *out,
                      float din, float dout, int nattr)
{
    float t = din / (din - dout);
    int c;
    for (c = 0; c < 4; c++)
        o->pos[c] = in->pos[c] + t * (out->pos[c] - in->pos[c]);
    for (c = 0; c < nattr; c++)
        o->attr[c] = in->attr[c] + t * (out->attr[c] - in->attr[c]);
}

/* Clips polygon in[0..n) by plane k into out. Returns the new vertex count,
 * or -1 when every vertex is inside (out untouched). */
static int clip_plane(const raster_ctx *r, int k, const raster_vertex *in, int n,
                      raster_vertex *out)
{
    float d[POLY_MAX];
    int i, m = 0, any_out = 0;

    for (i = 0; i < n; i++) {
        d[i] = plane_dist(r, k, in[i].pos);
        if (d[i] < 0.0f)
            any_out = 1;
    }
    if (!any_out)
        return -1;
    for (i = 0; i < n; i++) {
        int j = (i + 1 == n) ? 0 : i + 1;
        int iin = d[i] >= 0.0f, jin = d[j] >= 0.0f;
        if (iin)
            out[m++] = in[i];
        if (iin && !jin) {
            if (d[i] > 0.0f)      /* d == 0: the crossing is in[i] itself */
                intersect(&out[m++], &in[i], &in[j], d[i], d[j], r->nattr);
        } else if (!iin && jin) {
            if (d[j] > 0.0f)      /* d == 0: in[j] is emitted next */
                intersect(&out[m++], &in[j], &in[i], d[j], d[i], r->nattr);
        }
    }
    return m;
}

/* ---- window space -------------------------------------------------------- */

/* floor(v FIX_ONE + 0.5) clamped to +-FIX_LIMIT: past a limit, the
 * limit (floor's value there is at or past it too); within them, the
 * truncation less one where it rounded up (a negative fraction), which
 * is floor's value without floor's test of the magnitude. */
static int64_t snap(double v)
{
    double f = v * (double)FIX_ONE + 0.5;
    int64_t t;
    if (f > (double)FIX_LIMIT)
        return FIX_LIMIT;
    if (f < -(double)FIX_LIMIT)
        return -FIX_LIMIT;
    t = (int64_t)f;
    return t - ((double)t > f);
}

/* Clip-space pos to the snapped window position and the depth in [0, 1]. */
static inline void window_xyz(const raster_ctx *r, const float *pos, int64_t *x, int64_t *y, double *z)
{
    double w = (double)pos[3];
    double d = ((double)pos[2] / w + 1.0) * 0.5;
    *x = snap(((double)pos[0] / w + 1.0) * 0.5 * (double)r->t.width);
    *y = snap((1.0 - (double)pos[1] / w) * 0.5 * (double)r->t.height);
    if (!(d > 0.0)) d = 0.0;
    if (d > 1.0) d = 1.0;
    *z = d;
}

static void project(const raster_ctx *r, const raster_vertex *v, svert *s)
{
    int k;
    window_xyz(r, v->pos, &s->x, &s->y, &s->z);
    s->iw = (float)(1.0 / (double)v->pos[3]);
    for (k = 0; k < r->nattr; k++)
        s->a[k] = v->attr[k] * s->iw;
}

/* ---- triangle setup and pixel loop ---------------------------------------- */

/* Edge a -> b of a triangle with positive area2: E(p) > 0 inside. */
typedef struct edge {
    int64_t dx, dy;      /* b - a */
    int64_t ax, ay;
    int64_t step_x;      /* change of E for one pixel to the right */
    int64_t bias;        /* 0 for top-left edges, -1 otherwise */
} edge;

static void edge_setup(edge *e, const svert *a, const svert *b)
{
    e->dx = b->x - a->x;
    e->dy = b->y - a->y;
    e->ax = a->x;
    e->ay = a->y;
    e->step_x = -e->dy * FIX_ONE;
    /* y points down. The interior normal is (-dy, dx): a left edge has the
     * interior to its right (dy < 0); a top edge is horizontal with the
     * interior below (dy == 0, dx > 0). Centres exactly on other edges are
     * left to the neighbour: E + bias >= 0 is the coverage test. */
    e->bias = (e->dy < 0 || (e->dy == 0 && e->dx > 0)) ? 0 : -1;
}

static int64_t edge_eval(const edge *e, int64_t px, int64_t py)
{
    return e->dx * (py - e->ay) - e->dy * (px - e->ax);
}

/* The pixels whose centre lies in the triangle's bounding box, within
 * the scissor: columns i0 .. i1, rows j0 .. j1; 0 when there are none. */
static inline int pixel_box(const raster_ctx *r, const svert *v0, const svert *v1, const svert *v2, int64_t *i0,
                     int64_t *i1, int64_t *j0, int64_t *j1)
{
    int64_t xmin = min64(v0->x, min64(v1->x, v2->x)), xmax = max64(v0->x, max64(v1->x, v2->x));
    int64_t ymin = min64(v0->y, min64(v1->y, v2->y)), ymax = max64(v0->y, max64(v1->y, v2->y));
    *i0 = max64(fix_floor(xmin + (FIX_HALF - 1)), r->sx0); /* ceil((xmin - FIX_HALF) / FIX_ONE) */
    *i1 = min64(fix_floor(xmax - FIX_HALF), (int64_t)r->sx1 - 1);
    *j0 = max64(fix_floor(ymin + (FIX_HALF - 1)), r->sy0);
    *j1 = min64(fix_floor(ymax - FIX_HALF), (int64_t)r->sy1 - 1);
    return *i0 <= *i1 && *j0 <= *j1;
}

/* Draws triangle v0 v1 v2 with area2 == area > 0. */
static size_t draw_triangle(raster_ctx *r, const svert *v0, const svert *v1,
                            const svert *v2, int64_t area)
{
    const raster_target *t = &r->t;
    edge e[3];
    int64_t i0, i1, j0, j1, j;
    double inv_area = 1.0 / (double)area;
    double z0 = v0->z, dz1 = v1->z - v0->z, dz2 = v2->z - v0->z;
    float iw0 = v0->iw, diw1 = v1->iw - v0->iw, diw2 = v2->iw - v0->iw;
    float a0[RASTER_MAX_ATTRS], da1[RASTER_MAX_ATTRS], da2[RASTER_MAX_ATTRS];
    float attr[RASTER_MAX_ATTRS];
    int nattr = r->nattr, k;
    int need_attr = nattr > 0;
    int use_depth_test = r->depth_test && t->depth != NULL;
    int use_depth_write = r->depth_write && t->depth != NULL;
    size_t written = 0;

    for (k = 0; k < nattr; k++) {
        a0[k] = v0->a[k];
        da1[k] = v1->a[k] - v0->a[k];
        da2[k] = v2->a[k] - v0->a[k];
    }
    edge_setup(&e[0], v1, v2);  /* opposite v0 */
    edge_setup(&e[1], v2, v0);  /* opposite v1: gives the weight of v1 */
    edge_setup(&e[2], v0, v1);  /* opposite v2: gives the weight of v2 */

    if (!pixel_box(r, v0, v1, v2, &i0, &i1, &j0, &j1))
        return 0;

    for (j = j0; j <= j1; j++) {
        int64_t py = j * FIX_ONE + FIX_HALF;
        int64_t px = i0 * FIX_ONE + FIX_HALF;
        int64_t ev[3], lo = i0, hi = i1, e1, e2, x;
        unsigned char *crow = NULL;
        float *drow = NULL;

        /* The exact span of covered centres on this row, from each edge:
         * E(i) = ev + (i - i0) * step_x, covered when E(i) + bias >= 0. */
        for (k = 0; k < 3; k++) {
            int64_t eb, s = e[k].step_x;
            ev[k] = edge_eval(&e[k], px, py);
            eb = ev[k] + e[k].bias;
            if (s > 0) {
                if (eb < 0)
                    lo = max64(lo, i0 + ceil_div(-eb, s));
            } else if (s < 0) {
                if (eb < 0)
                    hi = i0 - 1;
                else
                    hi = min64(hi, i0 + eb / -s);
            } else if (eb < 0) {
                hi = i0 - 1;
            }
        }
        if (lo > hi)
            continue;

        if (t->color != NULL)
            crow = (unsigned char *)t->color + (size_t)j * t->color_stride;
        if (t->depth != NULL)
            drow = t->depth + (size_t)j * t->depth_stride;
        e1 = ev[1] + (lo - i0) * e[1].step_x;
        e2 = ev[2] + (lo - i0) * e[2].step_x;

        for (x = lo; x <= hi; x++, e1 += e[1].step_x, e2 += e[2].step_x) {
            double l1 = (double)e1 * inv_area, l2 = (double)e2 * inv_area;
            float z = (float)(z0 + l1 * dz1 + l2 * dz2);
            float rgba[4] = { 0.0f, 0.0f, 0.0f, 1.0f };

            if (use_depth_test && !(z < drow[x]))
                continue;
            if (need_attr) {
                float f1 = (float)l1, f2 = (float)l2;
                float w = 1.0f / (iw0 + f1 * diw1 + f2 * diw2);
                for (k = 0; k < nattr; k++)
                    attr[k] = (a0[k] + f1 * da1[k] + f2 * da2[k]) * w;
            }
            if (r->frag != NULL) {
                r->stats.fragments_shaded++;
                if (!r->frag(r->user, (int32_t)x, (int32_t)j, z, attr, rgba))
                    continue;
            } else {
                for (k = 0; k < nattr && k < 4; k++)
                    rgba[k] = attr[k];
            }
            if (crow != NULL) {
                switch (t->format) {
                case RASTER_RGBA8:    store_rgba8(crow, x, rgba); break;
                case RASTER_RGB_F32:  store_rgb_f32(crow, x, rgba); break;
                case RASTER_RGBA_F32: store_rgba_f32(crow, x, rgba); break;
                }
            }
            if (use_depth_write)
                drow[x] = z;
            written++;
        }
    }
    r->stats.pixels_written += written;
    return written;
}

/* Draws the convex polygon p[0..n) (clip space, inside every plane). */
static size_t draw_polygon(raster_ctx *r, const raster_vertex *const *p, int n)
{
    svert s[POLY_MAX];
    int64_t a[POLY_MAX], total = 0;
    size_t written = 0;
    int k;

    for (k = 0; k < n; k++)
        project(r, p[k], &s[k]);
    for (k = 1; k + 1 < n; k++) {
        a[k] = area2(&s[0], &s[k], &s[k + 1]);
        total += a[k];
    }
    if (total == 0) {
        r->stats.triangles_rejected++;
        return 0;
    }
    /* total > 0 is clockwise on screen (y down), i.e. clockwise in NDC. */
    if ((r->cull == RASTER_CULL_BACK && total > 0) ||
        (r->cull == RASTER_CULL_FRONT && total < 0)) {
        r->stats.triangles_culled++;
        return 0;
    }
    for (k = 1; k + 1 < n; k++) {
        if (total > 0 && a[k] > 0)
            written += draw_triangle(r, &s[0], &s[k], &s[k + 1], a[k]);
        else if (total < 0 && a[k] < 0)
            written += draw_triangle(r, &s[0], &s[k + 1], &s[k], -a[k]);
    }
    return written;
}

static int valid_position(const float *p)
{
    return fabsf(p[0]) <= RASTER_MAX_COORD && fabsf(p[1]) <= RASTER_MAX_COORD && /* false for NaN */
           fabsf(p[2]) <= RASTER_MAX_COORD && fabsf(p[3]) <= RASTER_MAX_COORD;
}

size_t raster_triangle(raster_ctx *r, const raster_vertex *v0,
                       const raster_vertex *v1, const raster_vertex *v2)
{
    raster_vertex buf[2][POLY_MAX];
    const raster_vertex *tri[3];
    const raster_vertex *poly[POLY_MAX];
    unsigned m0, m1, m2;
    int n, k, cur;

    r->stats.triangles_in++;
    if (!valid_position(v0->pos) || !valid_position(v1->pos) || !valid_position(v2->pos)) {
        r->stats.triangles_rejected++;
        return 0;
    }
    m0 = outcode(r, v0->pos);
    m1 = outcode(r, v1->pos);
    m2 = outcode(r, v2->pos);
    if ((m0 & m1 & m2) != 0) {              /* all outside one plane */
        r->stats.triangles_rejected++;
        return 0;
    }
    if ((m0 | m1 | m2) == 0) {              /* all inside: no clipping */
        tri[0] = v0;
        tri[1] = v1;
        tri[2] = v2;
        return draw_polygon(r, tri, 3);
    }

    /* Clip by every plane in a fixed order (see raster.h for why). */
    r->stats.triangles_clipped++;
    buf[0][0] = *v0;
    buf[0][1] = *v1;
    buf[0][2] = *v2;
    n = 3;
    cur = 0;
    for (k = 0; k < PLANE_COUNT; k++) {
        int m = clip_plane(r, k, buf[cur], n, buf[1 - cur]);
        if (m < 0)
            continue;
        cur = 1 - cur;
        n = m;
        if (n < 3) {
            r->stats.triangles_rejected++;
            return 0;
        }
    }
    for (k = 0; k < n; k++)
        poly[k] = &buf[cur][k];
    return draw_polygon(r, poly, n);
}

size_t raster_triangles(raster_ctx *r, const raster_vertex *verts, size_t nvert,
                        const uint32_t *idx, size_t ntri)
{
    size_t k, written = 0;

    for (k = 0; k < ntri; k++) {
        size_t i0 = 3 * k, i1 = 3 * k + 1, i2 = 3 * k + 2;
        if (idx != NULL) {
            i0 = idx[i0];
            i1 = idx[i1];
            i2 = idx[i2];
        }
        if (i0 >= nvert || i1 >= nvert || i2 >= nvert) {
            r->stats.triangles_in++;
            r->stats.triangles_rejected++;
            continue;
        }
        written += raster_triangle(r, &verts[i0], &verts[i1], &verts[i2]);
    }
    return written;
}

/* ---- surface ids without fragment calls ------------------------------- */

static inline void prepare_one(const raster_ctx *r, const float *pos, raster_pvert *out)
{
    if (!valid_position(pos)) {
        out->code = ~0u;
        return;
    }
    out->code = outcode(r, pos);
    if (out->code != 0)
        return;
    window_xyz(r, pos, &out->x, &out->y, &out->z); /* as project: the same bits */
}

void raster_prepare(const raster_ctx *r, const float *pos, raster_pvert *out)
{
    prepare_one(r, pos, out);
}

void raster_prepare_n(const raster_ctx *r, const float *pos, size_t n, raster_pvert *out)
{
    size_t k;
    for (k = 0; k < n; k++)
        prepare_one(r, pos + 4 * k, &out[k]);
}

/* One edge's bound along the rows of draw_triangle_id: with s = |step_x|
 * and eb the edge function plus bias at the row's first pixel, q =
 * floor(eb / s) and the remainder r (0 <= r < s), carried from row to row
 * by the change of eb per row (dq, dr: its quotient and remainder,
 * taken on the second row): the same bounds as the divisions of
 * draw_triangle at every row, without them. */
typedef struct edge_walk {
    int64_t s, q, r, dq, dr;
} edge_walk;

/* rows: the triangle has more than one row (only then the step per row,
 * a division, is taken). */
static void walk_start(edge_walk *w, const edge *e, int64_t eb, int rows)
{
    int64_t d = e->dx * FIX_ONE;
    w->s = e->step_x < 0 ? -e->step_x : e->step_x;
    if (w->s == 0)
        return;
    w->q = floor_div(eb, w->s);
    w->r = eb - w->q * w->s;
    if (rows) {
        w->dq = floor_div(d, w->s);
        w->dr = d - w->dq * w->s;
    }
}

static void walk_row(edge_walk *w)
{
    int64_t carry;
    if (w->s == 0)
        return;
    w->q += w->dq;
    w->r += w->dr;
    carry = -(int64_t)(w->r >= w->s); /* all ones or 0: no branch (it mispredicted) */
    w->r -= w->s & carry;
    w->q -= carry;
}

/* A span's pixels SPAN_LANES at a time (draw_triangle_id): the edge
 * values as doubles, the one at the span's first pixel plus k steps. An
 * edge value is an integer within 2^51 in magnitude (snapped coordinates
 * within +-2^24, so each of its two products within 2^50), k steps are
 * within 2^36 (k < 8, a step within 2^33), and their sum is an edge value
 * too: all exact in a double, so the sum is the same double as the int64
 * value converted, and the depth the same expression as one at a time. */
#define SPAN_LANES 8
#if RASTER_NARROW > SPAN_LANES
#error "draw_narrow_id takes a box's columns as at most SPAN_LANES lanes"
#endif

static void span_offsets(int64_t s1, int64_t s2, double off1[SPAN_LANES], double off2[SPAN_LANES])
{
    int k;
    for (k = 0; k < SPAN_LANES; k++) {
        off1[k] = (double)k * (double)s1;
        off2[k] = (double)k * (double)s2;
    }
}

/* The depths of SPAN_LANES pixels (zc: z0, dz1, dz2, 1 / area) from the
 * edge values e1 + off1[k], e2 + off2[k]. */
static inline void lanes_depth(double e1, double e2, const double *restrict off1, const double *restrict off2,
                        const double zc[4], float *restrict z)
{
    int k;
    for (k = 0; k < SPAN_LANES; k++) {
        double l1 = (e1 + off1[k]) * zc[3], l2 = (e2 + off2[k]) * zc[3];
        z[k] = (float)(zc[0] + l1 * zc[1] + l2 * zc[2]);
    }
}

/* The lanes whose mask m[k] is all ones written with depth z[k] and the
 * id, and counted in c[k]; the others written back unchanged. The
 * selects as bit masks: written as conditions, GCC branches. */
static inline void lanes_store(float *restrict drow, uint32_t *restrict irow, const float *restrict z,
                        const uint32_t *restrict m, uint32_t id, uint32_t *restrict c)
{
    uint32_t zb[SPAN_LANES], db[SPAN_LANES];
    int k;
    memcpy(zb, z, sizeof zb);
    memcpy(db, drow, sizeof db);
    for (k = 0; k < SPAN_LANES; k++) {
        db[k] = (zb[k] & m[k]) | (db[k] & ~m[k]);
        irow[k] = (id & m[k]) | (irow[k] & ~m[k]);
        c[k] -= m[k]; /* one more in lane k */
    }
    memcpy(drow, db, sizeof db);
}

/* SPAN_LANES pixels from drow, irow: depth z (zc: z0, dz1, dz2, 1 /
 * area) from the edge values e1 + off1[k], e2 + off2[k]; where it is
 * nearer, written with the id, and counted in c[k]; in loops of fixed
 * length (vectorised by GCC at -O2). */
static void span_lanes_id(float *restrict drow, uint32_t *restrict irow, double e1, double e2,
                          const double *restrict off1, const double *restrict off2, const double zc[4], float zlo,
                          uint32_t id, uint32_t *restrict c)
{
    float z[SPAN_LANES];
    uint32_t m[SPAN_LANES], hidden = 1;
    int k;
    for (k = 0; k < SPAN_LANES; k++)
        hidden &= drow[k] <= zlo;
    if (hidden) /* no lane can be nearer (depth_floor) */
        return;
    lanes_depth(e1, e2, off1, off2, zc, z);
    for (k = 0; k < SPAN_LANES; k++)
        m[k] = 0u - (uint32_t)(z[k] < drow[k]); /* NaN: not nearer */
    lanes_store(drow, irow, z, m, id, c);
}

/* Lanes klo .. khi of SPAN_LANES pixels from drow, irow, as
 * span_lanes_id draws them (the other lanes written back unchanged): a
 * span's part shorter than SPAN_LANES, in lanes too, as one at a time
 * its variable end and the branches per pixel cost more. */
static void span_part_id(float *restrict drow, uint32_t *restrict irow, double e1, double e2,
                         const double *restrict off1, const double *restrict off2, const double zc[4], int32_t klo,
                         int32_t khi, uint32_t id, uint32_t *restrict c)
{
    float z[SPAN_LANES];
    uint32_t m[SPAN_LANES];
    int32_t k;
    lanes_depth(e1, e2, off1, off2, zc, z);
    for (k = 0; k < SPAN_LANES; k++)
        m[k] = 0u - ((uint32_t)(z[k] < drow[k]) & (uint32_t)(k >= klo) & (uint32_t)(k <= khi));
    lanes_store(drow, irow, z, m, id, c);
}

/* One pixel inside a triangle, its edge values e1, e2: the depth from
 * them (zc: z0, dz1, dz2, 1 / area) and, where nearer, written with the
 * id. Returns 1 when written. */
static int pixel_id(float *drow, uint32_t *irow, double e1, double e2, const double zc[4], float zlo, uint32_t id)
{
    double l1, l2;
    float z;
    if (*drow <= zlo) /* hidden (depth_floor) */
        return 0;
    l1 = e1 * zc[3];
    l2 = e2 * zc[3];
    z = (float)(zc[0] + l1 * zc[1] + l2 * zc[2]);
    if (!(z < *drow))
        return 0;
    *drow = z;
    *irow = id;
    return 1;
}

/* A narrow triangle's pixels (draw_triangle_id) one at a time, where the
 * scissor is narrower than SPAN_LANES columns: every centre of its box
 * tested against the three edges, E + bias >= 0 each, the test the spans
 * of draw_triangle solve row by row, so the same pixels, with the same
 * edge values for the depth. zc: z0, dz1, dz2, 1 / area. */
static size_t draw_narrow_scalar(raster_ctx *r, const edge e[3], int64_t i0, int64_t i1, int64_t j0, int64_t j1,
                                 const double zc[4], float zlo, uint32_t id, uint32_t *ids)
{
    const raster_target *t = &r->t;
    int64_t px = i0 * FIX_ONE + FIX_HALF, py = j0 * FIX_ONE + FIX_HALF;
    int64_t b0 = edge_eval(&e[0], px, py) + e[0].bias, b1 = edge_eval(&e[1], px, py) + e[1].bias;
    int64_t b2 = edge_eval(&e[2], px, py) + e[2].bias, j, x;
    int64_t s0 = e[0].step_x, s1 = e[1].step_x, s2 = e[2].step_x;
    size_t written = 0;
    for (j = j0; j <= j1; j++) {
        float *drow = t->depth + (size_t)j * t->depth_stride;
        uint32_t *irow = ids + (size_t)j * (size_t)t->width;
        int64_t c0 = b0, c1 = b1, c2 = b2;
        for (x = i0; x <= i1; x++, c0 += s0, c1 += s1, c2 += s2)
            if ((c0 | c1 | c2) >= 0) /* inside */
                written += pixel_id(drow + x, irow + x, (double)(c1 - e[1].bias), (double)(c2 - e[2].bias), zc, zlo, id);
        b0 += e[0].dx * FIX_ONE;
        b1 += e[1].dx * FIX_ONE;
        b2 += e[2].dx * FIX_ONE;
    }
    return written;
}

/* A narrow triangle's row (draw_narrow_id) QUAD_LANES pixels at a time:
 * a box at most QUAD_LANES columns wide is one quad, a wider one two. */
#define QUAD_LANES 4

/* QUAD_LANES pixels of a narrow triangle's row from drow, irow: the
 * edge values v = ev[i] + off[i QUAD_LANES + k] (exact doubles, see
 * span_offsets), a lane inside when every v + bias >= 0, i.e. v >=
 * lim[i] = -bias (the values are integers), tested on v rounded to
 * float (rounding is monotone and lim is a float: the same answer, in
 * lanes of the depths' width); inside and nearer, written with the id
 * and counted in c[k]; in loops of fixed length (vectorised by GCC). The
 * selects as bit masks, as lanes_store. */
static void narrow_quad_id(float *restrict drow, uint32_t *restrict irow, const double ev[3],
                           const double *restrict off, const float lim[3], const double zc[4], uint32_t id,
                           uint32_t *restrict c)
{
    float z[QUAD_LANES], f0[QUAD_LANES], f1[QUAD_LANES], f2[QUAD_LANES];
    uint32_t m[QUAD_LANES], zb[QUAD_LANES], db[QUAD_LANES];
    int k;
    for (k = 0; k < QUAD_LANES; k++) {
        double v0 = ev[0] + off[k], v1 = ev[1] + off[QUAD_LANES + k], v2 = ev[2] + off[2 * QUAD_LANES + k];
        double l1 = v1 * zc[3], l2 = v2 * zc[3];
        z[k] = (float)(zc[0] + l1 * zc[1] + l2 * zc[2]);
        f0[k] = (float)v0;
        f1[k] = (float)v1;
        f2[k] = (float)v2;
    }
    for (k = 0; k < QUAD_LANES; k++)
        m[k] = 0u - ((uint32_t)(f0[k] >= lim[0]) & (uint32_t)(f1[k] >= lim[1]) & (uint32_t)(f2[k] >= lim[2]) &
                     (uint32_t)(z[k] < drow[k]));
    memcpy(zb, z, sizeof zb);
    memcpy(db, drow, sizeof db);
    for (k = 0; k < QUAD_LANES; k++) {
        db[k] = (zb[k] & m[k]) | (db[k] & ~m[k]);
        irow[k] = (id & m[k]) | (irow[k] & ~m[k]);
        c[k] -= m[k]; /* one more in lane k */
    }
    memcpy(drow, db, sizeof db);
}

/* Whether the QUAD_LANES depths from drow are all at or below zlo (no
 * lane can be nearer: depth_floor). */
static int quad_hidden(const float *drow, float zlo)
{
    uint32_t hidden = 1;
    int k;
    for (k = 0; k < QUAD_LANES; k++)
        hidden &= drow[k] <= zlo;
    return (int)hidden;
}

/* A narrow triangle's pixels (draw_triangle_id): its box (at most
 * SPAN_LANES columns) a row at a time in nq quads of QUAD_LANES lanes,
 * from column xs, the box's first or further left so that the lanes stay
 * within the scissor; every centre tested against the three edges, E +
 * bias >= 0 each, the test the spans of draw_triangle solve row by row,
 * so the same pixels (a centre outside the box is outside the triangle:
 * the lanes beyond it draw nothing), with the same edge values for the
 * depth (the second quad's from ev + QUAD_LANES steps: exact, as every
 * edge value; the first, E at (xs, j0), evaluated there). zc: z0, dz1,
 * dz2, 1 / area. */
static size_t draw_narrow_id(raster_ctx *r, const edge e[3], int64_t i0, int64_t i1, int64_t j0, int64_t j1,
                             const double zc[4], float zlo, uint32_t id, uint32_t *ids)
{
    const raster_target *t = &r->t;
    int nq = i1 - i0 < QUAD_LANES ? 1 : 2, q;
    int64_t nl = (int64_t)nq * QUAD_LANES, xs = i0 + nl <= r->sx1 ? i0 : (int64_t)r->sx1 - nl, j;
    double ev[2][3], dv[3], off[3 * QUAD_LANES];
    float lim[3];
    uint32_t cnt[QUAD_LANES]; /* pixels written in lane k of either quad */
    size_t written = 0;
    int i, k;
    if (r->sx1 - r->sx0 < SPAN_LANES)
        return draw_narrow_scalar(r, e, i0, i1, j0, j1, zc, zlo, id, ids);
    for (i = 0; i < 3; i++) {
        int64_t e0 = edge_eval(&e[i], xs * FIX_ONE + FIX_HALF, j0 * FIX_ONE + FIX_HALF);
        ev[0][i] = (double)e0;
        ev[1][i] = (double)(e0 + QUAD_LANES * e[i].step_x);
        lim[i] = (float)-e[i].bias;
        dv[i] = (double)(e[i].dx * FIX_ONE);
        for (k = 0; k < QUAD_LANES; k++)
            off[i * QUAD_LANES + k] = (double)k * (double)e[i].step_x;
    }
    memset(cnt, 0, sizeof cnt);
    for (j = j0; j <= j1; j++) {
        float *drow = t->depth + (size_t)j * t->depth_stride + xs;
        uint32_t *irow = ids + (size_t)j * (size_t)t->width + xs;
        for (q = 0; q < nq; q++)
            if (!quad_hidden(drow + q * QUAD_LANES, zlo))
                narrow_quad_id(drow + q * QUAD_LANES, irow + q * QUAD_LANES, ev[q], off, lim, zc, id, cnt);
        for (q = 0; q < nq; q++)
            for (i = 0; i < 3; i++)
                ev[q][i] += dv[i]; /* an edge value again: exact */
    }
    for (k = 0; k < QUAD_LANES; k++)
        written += cnt[k];
    return written;
}

/* Row span lo .. hi of draw_triangle_id in lanes (e1, e2: the edge
 * values at lo; s1, s2 their steps): whole groups of SPAN_LANES, then the
 * rest as a part, its lanes moved left where they would pass the
 * scissor's right end sx1 (at least SPAN_LANES columns wide), so no lane
 * leaves it. */
static void span_id(float *drow, uint32_t *irow, int64_t lo, int64_t hi, int64_t e1, int64_t e2, int64_t s1,
                    int64_t s2, int64_t sx1, const double *off1, const double *off2, const double zc[4], float zlo,
                    uint32_t id, uint32_t *c)
{
    int64_t x = lo, xs;
    for (; x + SPAN_LANES - 1 <= hi; x += SPAN_LANES, e1 += SPAN_LANES * s1, e2 += SPAN_LANES * s2)
        span_lanes_id(drow + x, irow + x, (double)e1, (double)e2, off1, off2, zc, zlo, id, c);
    if (x > hi)
        return;
    xs = x + SPAN_LANES <= sx1 ? x : sx1 - SPAN_LANES;
    span_part_id(drow + xs, irow + xs, (double)(e1 + (xs - x) * s1), (double)(e2 + (xs - x) * s2), off1, off2, zc,
                 (int32_t)(x - xs), (int32_t)(hi - xs), id, c);
}

/* Row span lo .. hi of draw_triangle_id one pixel at a time, where the
 * scissor is narrower than SPAN_LANES columns. Returns the pixels
 * written. */
static size_t span_scalar_id(float *drow, uint32_t *irow, int64_t lo, int64_t hi, int64_t e1, int64_t e2, int64_t s1,
                             int64_t s2, const double zc[4], float zlo, uint32_t id)
{
    int64_t x;
    size_t written = 0;
    for (x = lo; x <= hi; x++, e1 += s1, e2 += s2)
        written += pixel_id(drow + x, irow + x, (double)e1, (double)e2, zc, zlo, id);
    return written;
}

/* A float at or below every depth draw_triangle_id computes inside the
 * triangle of vertex depths z0, z1, z2 (doubles in [0, 1]): inside, the
 * edge values are >= 0 and sum to the area, so the exact depth is a
 * convex combination, at least their minimum m; the computed one (l1, l2
 * each a product with 1 / area, then two products and two sums, all in
 * double) is within 1e-14 of it, so at least m - 1e-9, and rounding to
 * float is monotone: the depth's float is at least this one. So a pixel
 * whose stored depth is at most this float fails the depth test, and
 * skipping it changes nothing. */
static float depth_floor(double z0, double z1, double z2)
{
    double m = z0 < z1 ? z0 : z1;
    return (float)((m < z2 ? m : z2) - 1e-9);
}

/* draw_triangle with no attributes, depth test and write, and the id
 * stored: the same spans and the same depth expression per pixel (a
 * triangle at most RASTER_NARROW columns wide by its box). */
static size_t draw_triangle_id(raster_ctx *r, const svert *v0, const svert *v1, const svert *v2, int64_t area,
                               uint32_t id, uint32_t *ids)
{
    const raster_target *t = &r->t;
    edge e[3];
    edge_walk wk[3];
    int64_t i0, i1, j0, j1, j, eb0[3], ev1, ev2;
    double inv_area = 1.0 / (double)area;
    double z0 = v0->z, dz1 = v1->z - v0->z, dz2 = v2->z - v0->z, zc[4], off1[SPAN_LANES], off2[SPAN_LANES];
    uint32_t cnt[SPAN_LANES]; /* pixels the lanes wrote */
    float zlo;
    size_t written = 0;
    int k, lanes = r->sx1 - r->sx0 >= SPAN_LANES;
    if (!pixel_box(r, v0, v1, v2, &i0, &i1, &j0, &j1)) /* no centre: no edges to set up */
        return 0;
    edge_setup(&e[0], v1, v2);
    edge_setup(&e[1], v2, v0);
    edge_setup(&e[2], v0, v1);
    zc[0] = z0;
    zc[1] = dz1;
    zc[2] = dz2;
    zc[3] = inv_area;
    zlo = depth_floor(z0, v1->z, v2->z);
    if (i1 - i0 < RASTER_NARROW)
        return draw_narrow_id(r, e, i0, i1, j0, j1, zc, zlo, id, ids);
    for (k = 0; k < 3; k++)
        eb0[k] = edge_eval(&e[k], i0 * FIX_ONE + FIX_HALF, j0 * FIX_ONE + FIX_HALF) + e[k].bias;
    for (k = 0; k < 3; k++)
        walk_start(&wk[k], &e[k], eb0[k], j1 > j0);
    span_offsets(e[1].step_x, e[2].step_x, off1, off2);
    memset(cnt, 0, sizeof cnt);
    ev1 = eb0[1] - e[1].bias;
    ev2 = eb0[2] - e[2].bias;
    for (j = j0; j <= j1; j++) {
        int64_t lo = i0, hi = i1, e1, e2, s1 = e[1].step_x, s2 = e[2].step_x;
        float *drow = t->depth + (size_t)j * t->depth_stride;
        uint32_t *irow = ids + (size_t)j * (size_t)t->width;
        if (j > j0) {
            for (k = 0; k < 3; k++)
                walk_row(&wk[k]);
            ev1 += e[1].dx * FIX_ONE;
            ev2 += e[2].dx * FIX_ONE;
            eb0[0] += e[0].dx * FIX_ONE;
        }
        for (k = 0; k < 3; k++) {
            int64_t sx = e[k].step_x;
            if (sx > 0) /* from ceil(-eb / s) = -floor(eb / s); no bound while eb >= 0 */
                lo = max64(lo, i0 - wk[k].q);
            else if (sx < 0) /* eb < 0 leaves hi < i0: no pixel */
                hi = min64(hi, i0 + wk[k].q);
            else if ((k == 0 ? eb0[0] : k == 1 ? ev1 + e[1].bias : ev2 + e[2].bias) < 0)
                hi = i0 - 1;
        }
        if (lo > hi)
            continue;
        e1 = ev1 + (lo - i0) * s1;
        e2 = ev2 + (lo - i0) * s2;
        if (lanes)
            span_id(drow, irow, lo, hi, e1, e2, s1, s2, r->sx1, off1, off2, zc, zlo, id, cnt);
        else
            written += span_scalar_id(drow, irow, lo, hi, e1, e2, s1, s2, zc, zlo, id);
    }
    for (k = 0; k < SPAN_LANES; k++)
        written += cnt[k];
    return written;
}

long raster_triangle_id(raster_ctx *r, const raster_pvert *p0, const raster_pvert *p1, const raster_pvert *p2,
                        uint32_t id, uint32_t *ids)
{
    svert s[3];
    int64_t a;
    size_t n;
    if ((p0->code | p1->code | p2->code) != 0 || !r->depth_test || !r->depth_write || !r->t.depth ||
        r->nattr != 0)
        return -1;
    r->stats.triangles_in++;
    a = (p1->x - p0->x) * (p2->y - p0->y) - (p1->y - p0->y) * (p2->x - p0->x); /* area2, before any copy */
    if (a == 0) {
        r->stats.triangles_rejected++;
        return 0;
    }
    if ((r->cull == RASTER_CULL_BACK && a > 0) || (r->cull == RASTER_CULL_FRONT && a < 0)) {
        r->stats.triangles_culled++;
        return 0;
    }
    s[0].x = p0->x; s[0].y = p0->y; s[0].z = p0->z;
    s[1].x = p1->x; s[1].y = p1->y; s[1].z = p1->z;
    s[2].x = p2->x; s[2].y = p2->y; s[2].z = p2->z;
    n = a > 0 ? draw_triangle_id(r, &s[0], &s[1], &s[2], a, id, ids)
              : draw_triangle_id(r, &s[0], &s[2], &s[1], -a, id, ids);
    r->stats.pixels_written += n;
    r->stats.fragments_shaded += n;
    return (long)n;
}
