/* atlas_frame: a frame's pixels from the radiance atlas (atlas_frame.h). */
#include <math.h>
#include <string.h>

#include "render/atlas_frame.h"
#include "render/texel.h"

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The map of chart c: u, v and the denominator as affine functions of
 * (i, j), in double, stored as floats. */
static void make_map(const atlas_view *v, const atlas_chart *c, atlas_map *m)
{
    double n[3], gu[3] = { 0.0, 0.0, 0.0 }, gv[3] = { 0.0, 0.0, 0.0 }, eo[3], N, cu, cv;
    const double *D[3];
    int k;
    atlas_chart_normal(c, n);
    if (c->kind == ATLAS_WALL) {
        gu[0] = c->e[0] / c->tu;
        gu[1] = c->e[1] / c->tu;
        gv[2] = 1.0 / c->tv;
    } else {
        gu[0] = 1.0 / c->tu;
        gv[1] = 1.0 / c->tv;
    }
    for (k = 0; k < 3; k++)
        eo[k] = v->eye[k] - c->o[k];
    N = -dot3(n, eo);           /* n.(o - eye): the plane passes through o */
    cu = dot3(eo, gu);
    cv = dot3(eo, gv);
    D[0] = v->D0;
    D[1] = v->Dx;
    D[2] = v->Dy;
    for (k = 0; k < 3; k++) {
        double nd = dot3(n, D[k]);
        m->a[k] = (float)(cu * nd + N * dot3(D[k], gu));
        m->a[3 + k] = (float)(cv * nd + N * dot3(D[k], gv));
        m->a[6 + k] = (float)nd;
    }
    m->c = c;
}

static const atlas_map *map_of(const atlas *A, const atlas_view *v, atlas_cache *k, uint32_t sid)
{
    atlas_map *m = &k->slot[sid & (ATLAS_CACHE_SLOTS - 1)];
    const atlas_chart *c;
    if (m->sid == sid && m->stamp == v->stamp)
        return m;
    c = atlas_surface_chart(A, sid);
    m->sid = sid;
    m->stamp = v->stamp;
    if (c)
        make_map(v, c, m);
    else
        m->c = NULL;
    return m;
}

/* Cell index and weight along one axis: u clamped to [0, n - 1], the
 * cell's index in 0 .. n - 2 (truncation is floor for u >= 0). */
static inline uint32_t cell_of(float u, uint32_t n, float *f)
{
    uint32_t i;
    if (!(u > 0.0f))
        u = 0.0f;
    if (u > (float)(n - 1))
        u = (float)(n - 1);
    i = (uint32_t)u;
    if (i > n - 2)
        i = n - 2;
    *f = u - (float)i;
    return i;
}

/* The four values around the last cell read (a run's pixels mostly stay
 * in a cell or step to the next one: decoded once, reused): vertex (0, 0)
 * of the cell in the atlas (NULL: none yet), and the values of its
 * vertices (i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1), each channel
 * its mantissa times its scale (exact: a 9-bit whole number times a
 * power of two). A run starts with t NULL: the cell's rows are nu apart
 * only within one chart. */
typedef struct cell_vals {
    const uint32_t *t;
    float v[4][3];
    int zero;                 /* all four packed values 0 */
} cell_vals;

static void cell_load(cell_vals *cv, const uint32_t *t, uint32_t nu)
{
    if (cv->t && t == cv->t + 1) { /* the next cell along the row: its left side is the old right side */
        memcpy(cv->v[0], cv->v[1], sizeof cv->v[0]);
        memcpy(cv->v[2], cv->v[3], sizeof cv->v[2]);
        texel_unpack(t[1], cv->v[1]);
        texel_unpack(t[nu + 1], cv->v[3]);
    } else if (cv->t && t + 1 == cv->t) {
        memcpy(cv->v[1], cv->v[0], sizeof cv->v[1]);
        memcpy(cv->v[3], cv->v[2], sizeof cv->v[3]);
        texel_unpack(t[0], cv->v[0]);
        texel_unpack(t[nu], cv->v[2]);
    } else {
        texel_unpack(t[0], cv->v[0]);
        texel_unpack(t[1], cv->v[1]);
        texel_unpack(t[nu], cv->v[2]);
        texel_unpack(t[nu + 1], cv->v[3]);
    }
    cv->t = t;
    cv->zero = (t[0] | t[1] | t[nu] | t[nu + 1]) == 0u;
}

/* Bilinear over the vertices of a chart whose vertex (0, 0) is t0 and
 * rows nu long, at (u, w) in vertex steps, summed vertex by vertex
 * (value times weight: the same bits as mantissa times scale-and-weight,
 * the scale a power of two, unless scale times weight falls below 2^-126:
 * weights under 2^-99, a point within 1e-15 m of the ground tiles'
 * corner); black (+0) where all four are 0. */
static inline void bilerp(cell_vals *cv, const uint32_t *t0, uint32_t nu, uint32_t nv, float u, float w,
                          float out[3])
{
    float fu, fv, wa, wb, wc, wd, o0, o1, o2;
    uint32_t i = cell_of(u, nu, &fu), j = cell_of(w, nv, &fv);
    const uint32_t *t = t0 + (size_t)j * nu + i;
    const float *a, *b, *c, *d;
    if (t != cv->t)
        cell_load(cv, t, nu);
    if (cv->zero) {
        out[0] = out[1] = out[2] = 0.0f;
        return;
    }
    wa = (1.0f - fu) * (1.0f - fv);
    wb = fu * (1.0f - fv);
    wc = (1.0f - fu) * fv;
    wd = fu * fv;
    a = cv->v[0];
    b = cv->v[1];
    c = cv->v[2];
    d = cv->v[3];
    o0 = a[0] * wa + b[0] * wb + c[0] * wc + d[0] * wd; /* all read before out is written */
    o1 = a[1] * wa + b[1] * wb + c[1] * wc + d[1] * wd;
    o2 = a[2] * wa + b[2] * wb + c[2] * wc + d[2] * wd;
    out[0] = o0;
    out[1] = o1;
    out[2] = o2;
}

/* A row's ground: the hit point (x, y) relative to the tiles' corner at
 * pixel 0 and its step per pixel (the ray's height does not change
 * along a row: the camera's right vector is horizontal). */
typedef struct ground_row {
    int on;                   /* the row's rays go down */
    double x0, y0, dx, dy;
} ground_row;

static void ground_setup(const atlas *A, const atlas_view *v, int32_t j, ground_row *g)
{
    double dz = v->D0[2] + j * v->Dy[2], t;
    g->on = dz < 0.0;
    if (!g->on)
        return;
    t = -v->eye[2] / dz;
    g->x0 = v->eye[0] - A->g0[0] + t * (v->D0[0] + j * v->Dy[0]);
    g->y0 = v->eye[1] - A->g0[1] + t * (v->D0[1] + j * v->Dy[1]);
    g->dx = t * v->Dx[0];
    g->dy = t * v->Dx[1];
}

/* The ground block item (atlas.h) under (x, y) from the tiles' corner,
 * and (x, y) in steps within it; UINT32_MAX off the tiles. */
static uint32_t ground_block(const atlas *A, double x, double y, double *u, double *w)
{
    double fx = x * A->inv_tile, fy = y * A->inv_tile, step_inv, bx, by;
    uint32_t tx, ty, tile, nb;
    if (!(fx >= 0.0 && fx < A->gx && fy >= 0.0 && fy < A->gy))
        return UINT32_MAX;
    tx = (uint32_t)fx;
    ty = (uint32_t)fy;
    tile = ty * A->gx + tx;
    step_inv = A->gfine[tile] ? A->inv_fine : A->inv_coarse;
    x = (x - tx * A->tile) * step_inv; /* in steps within the tile */
    y = (y - ty * A->tile) * step_inv;
    bx = x < 0.0 ? 0.0 : x * (1.0 / ATLAS_BLOCK);
    by = y < 0.0 ? 0.0 : y * (1.0 / ATLAS_BLOCK);
    nb = A->gfine[tile] ? ATLAS_TB - 1 : 0; /* a coarse tile is one block */
    tx = bx < nb ? (uint32_t)bx : nb;
    ty = by < nb ? (uint32_t)by : nb;
    *u = x - tx * ATLAS_BLOCK;
    *w = y - ty * ATLAS_BLOCK;
    return tile * ATLAS_TB * ATLAS_TB + ty * ATLAS_TB + tx;
}

/* Lists item it unless filled or listed this round (atlas.h's states). */
static void want(atlas *A, uint32_t it, uint32_t *list, uint32_t cap, uint32_t *n)
{
    uint8_t *d = it < A->nsurf ? &A->cdone[it] : &A->gdone[it - A->nsurf];
    if (*d || *n >= cap)
        return;
    *d = ATLAS_LISTED;
    list[(*n)++] = it;
}

/* Ground block item cur's corner (x, y) from the tiles' corner, and the
 * inverse of its steps' length. */
static void block_frame(const atlas *A, uint32_t cur, double *bx0, double *by0, double *inv)
{
    uint32_t tile = cur / (ATLAS_TB * ATLAS_TB), b = cur % (ATLAS_TB * ATLAS_TB);
    double step = A->gfine[tile] ? A->fine : A->coarse;
    *inv = 1.0 / step;
    *bx0 = (tile % A->gx) * A->tile + (b % ATLAS_TB) * ATLAS_BLOCK * step;
    *by0 = (tile / A->gx) * A->tile + (b / ATLAS_TB) * ATLAS_BLOCK * step;
}

/* The last ground block found along a row (atlas_frame_missing): its
 * corner, inverse step, and the open range of steps (lo, hi) taken as
 * inside it (empty: none). A point farther than ATLAS_EDGE steps inside a
 * block is in no other block (blocks meet only at their edges), so
 * ground_block's answer there is that block whatever run ground_run reads
 * it in: the same list, in the same order, as ground_block at every pixel. */
#define ATLAS_EDGE 1e-6
typedef struct block_memo {
    double bx0, by0, inv, lo, hi;
} block_memo;

static void missing_ground(atlas *A, const ground_row *g, int32_t i, block_memo *bm, uint32_t *list, uint32_t cap,
                           uint32_t *n)
{
    double x = g->x0 + i * g->dx, y = g->y0 + i * g->dy, u = (x - bm->bx0) * bm->inv, v = (y - bm->by0) * bm->inv;
    uint32_t b;
    if (u > bm->lo && u < bm->hi && v > bm->lo && v < bm->hi)
        return;
    b = ground_block(A, x, y, &u, &v);
    bm->lo = 1.0;
    bm->hi = -1.0;
    if (b == UINT32_MAX)
        return;
    block_frame(A, b, &bm->bx0, &bm->by0, &bm->inv);
    bm->lo = ATLAS_EDGE;
    bm->hi = ATLAS_BLOCK - ATLAS_EDGE;
    if (A->gfirst[b] != ATLAS_NOVERT)
        want(A, atlas_block_item(A, 0, 0) + b, list, cap, n);
}

uint32_t atlas_frame_missing(atlas *A, const atlas_view *v, const uint32_t *ids, uint32_t *list, uint32_t cap)
{
    uint32_t n = 0, last = MESH_SURF_NONE;
    int32_t i, j;
    if (A->todo == 0)
        return 0;
    for (j = 0; j < v->h && n < cap; j++) {
        block_memo bm = { 0.0, 0.0, 0.0, 1.0, -1.0 };
        ground_row g;
        ground_setup(A, v, j, &g);
        for (i = 0; i < v->w; i++) {
            uint32_t sid = ids[(size_t)j * v->w + i];
            if (sid == MESH_SURF_GROUND && g.on) {
                missing_ground(A, &g, i, &bm, list, cap, &n);
            } else if (sid != last && sid != MESH_SURF_NONE && sid != MESH_SURF_GROUND) {
                last = sid;
                if (atlas_surface_chart(A, sid))
                    want(A, sid - 2u, list, cap, &n);
            }
        }
    }
    return n;
}

/* A run of ground pixels i0 .. i1 - 1 of a row: the block under each hit
 * point, kept while the points stay in it (a row's points move by a
 * fixed step: runs of them share a block); black in a dark block. */
static void ground_run(const atlas *A, const ground_row *g, int32_t i0, int32_t i1, const uint8_t *mask, float *lin)
{
    double bx0 = 0.0, by0 = 0.0, inv = 0.0, lim = -1.0;
    const uint32_t *t0 = NULL;
    uint32_t cur = UINT32_MAX;
    int32_t i;
    cell_vals cv;
    cv.t = NULL;
    for (i = i0; i < i1; i++) {
        double x = g->x0 + i * g->dx, y = g->y0 + i * g->dy, u = (x - bx0) * inv, w = (y - by0) * inv;
        float *o = &lin[3 * (size_t)i];
        if (mask && !mask[i])
            continue;
        if (!(u >= 0.0 && u <= lim && w >= 0.0 && w <= lim)) { /* another block */
            cur = ground_block(A, x, y, &u, &w);
            t0 = NULL;
            lim = -1.0;
            cv.t = NULL;
            if (cur != UINT32_MAX && A->gfirst[cur] != ATLAS_NOVERT) {
                t0 = A->gdone[cur] == ATLAS_DARK ? NULL : &A->tex[A->gfirst[cur]];
                block_frame(A, cur, &bx0, &by0, &inv);
                lim = ATLAS_BLOCK;
            }
        }
        if (!t0) {
            o[0] = o[1] = o[2] = 0.0f;
            continue;
        }
        bilerp(&cv, t0, ATLAS_BLOCK + 1, ATLAS_BLOCK + 1, (float)u, (float)w, o);
    }
}

/* A run of pixels i0 .. i1 - 1 of row j on surface sid: its chart's map,
 * then each pixel's (u, v) and the bilinear read; black on a dark chart
 * (the same bits: a bilinear read of four 0 values is +0). */
static void surface_run(const atlas *A, const atlas_view *v, atlas_cache *k, uint32_t sid, int32_t j, int32_t i0,
                        int32_t i1, const uint8_t *mask, float *lin)
{
    const atlas_map *m = map_of(A, v, k, sid);
    const atlas_chart *c = m->c && A->cdone[sid - 2u] != ATLAS_DARK ? m->c : NULL;
    float fj = (float)j, bu, bv, bw, au, av, aw;
    const uint32_t *t0;
    uint32_t nu, nv;
    int32_t i;
    cell_vals cv;
    cv.t = NULL;
    if (!c) {
        for (i = i0; i < i1; i++)
            if (!mask || mask[i])
                lin[3 * (size_t)i] = lin[3 * (size_t)i + 1] = lin[3 * (size_t)i + 2] = 0.0f;
        return;
    }
    bu = m->a[0] + m->a[2] * fj;
    bv = m->a[3] + m->a[5] * fj;
    bw = m->a[6] + m->a[8] * fj;
    au = m->a[1];
    av = m->a[4];
    aw = m->a[7];
    t0 = &A->tex[c->first];
    nu = c->nu;
    nv = c->nv;
    for (i = i0; i < i1; i++) {
        float fi = (float)i, r = 1.0f / (bw + aw * fi);
        if (mask && !mask[i])
            continue;
        bilerp(&cv, t0, nu, nv, (bu + au * fi) * r, (bv + av * fi) * r, &lin[3 * (size_t)i]);
    }
}

void atlas_frame_row(const atlas *A, const atlas_view *v, atlas_cache *k, const uint32_t *ids, const uint8_t *mask,
                     int32_t j, float *lin, uint64_t count[3])
{
    ground_row g;
    int32_t i = 0, e;
    ground_setup(A, v, j, &g);
    while (i < v->w) {
        uint32_t sid = ids[i];
        uint64_t n;
        for (e = i + 1; e < v->w && ids[e] == sid; e++)
            ;
        if (mask) { /* only the marked pixels are written, and counted */
            int32_t q;
            for (n = 0, q = i; q < e; q++)
                n += mask[q] != 0;
        } else {
            n = (uint64_t)(e - i);
        }
        if (sid == MESH_SURF_NONE || (sid == MESH_SURF_GROUND && !g.on)) {
            int32_t q;
            for (q = i; q < e; q++)
                if (!mask || mask[q])
                    lin[3 * (size_t)q] = lin[3 * (size_t)q + 1] = lin[3 * (size_t)q + 2] = 0.0f;
            count[0] += n;
        } else if (sid == MESH_SURF_GROUND) {
            ground_run(A, &g, i, e, mask, lin);
            count[1] += n;
        } else {
            surface_run(A, v, k, sid, j, i, e, mask, lin);
            count[2] += n;
        }
        i = e;
    }
}
