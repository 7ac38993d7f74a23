/* atlas_frame: a frame's pixels from the radiance atlas (atlas_frame.h). */
#include <math.h>
#include <string.h>

#include "base/plx_assert.h"
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

/* Bilinear reads in lanes: a row's points are gathered ATLAS_LANES at a
 * time, each with its chart, and read together, each step a loop of fixed
 * length over the lanes (which compilers turn into vector instructions;
 * only the reads of the vertices are one lane at a time). A point (u, w)
 * in vertex steps is clamped to the chart per axis, [0, n - 1], its cell
 * is (i, j) with i in 0 .. n - 2, and its value is the four vertices'
 * values (texel_unpack's: each channel its mantissa times its scale)
 * times their weights, summed in the order (i, j), (i + 1, j), (i, j + 1),
 * (i + 1, j + 1): the bits of the read one point at a time it replaced
 * (a cell of four 0 values sums to +0, black). */
#define ATLAS_LANES 8

/* A batch of ATLAS_LANES reads whose vertices were read (gathered), to be
 * summed and written one batch later. The vertices of walls and roofs
 * often miss the caches: summed at once, the sums wait for them and fill
 * the processor's window of instructions in flight, so that nothing else
 * is done while they come, batch after batch; summing the batch before
 * instead gives that window work that needs nothing from memory. The
 * sums and the pixels they go to are the same; only when they are
 * written changes (each pixel of a row is written once, and
 * atlas_frame_row writes every batch before it returns). */
typedef struct batch {
    uint32_t qa[ATLAS_LANES], qb[ATLAS_LANES], qc[ATLAS_LANES], qd[ATLAS_LANES]; /* the four vertices */
    float fu[ATLAS_LANES], fv[ATLAS_LANES]; /* the weights' fractions */
    int32_t pix[ATLAS_LANES];   /* the pixels in the row */
    int32_t n;                  /* lanes to write (0: none) */
} batch;

typedef struct lanes {
    uint32_t n;                 /* points in use */
    int32_t pix[ATLAS_LANES];   /* their pixels in the row */
    const uint32_t *t0[ATLAS_LANES]; /* their chart's vertex (0, 0) */
    float u[ATLAS_LANES], w[ATLAS_LANES], nu[ATLAS_LANES], nv[ATLAS_LANES]; /* sides in vertices */
    uint32_t row[ATLAS_LANES];  /* the chart's row length */
    batch b[2];                 /* the batch gathered last (b[next ^ 1]) and the one gathered next */
    int32_t next;
} lanes;

/* Cell index and weight along one axis for every lane, n vertices along
 * it (n >= 2, exact as a float): u clamped to [0, n - 1] (NaN to 0), the
 * cell's index at most n - 2 (truncation is floor for u >= 0). */
static void cells_of(const float *restrict u, const float *restrict n, int32_t *restrict cell, float *restrict f)
{
    int32_t k;
    for (k = 0; k < ATLAS_LANES; k++) {
        float x = u[k], top = n[k] - 1.0f;
        int32_t i, last = (int32_t)n[k] - 2;
        x = x > 0.0f ? x : 0.0f; /* NaN compares false: 0 */
        x = x > top ? top : x;
        i = (int32_t)x;
        i = i > last ? last : i;
        cell[k] = i;
        f[k] = x - (float)i;
    }
}

/* The lanes' bilinear sums o[channel][lane] of their four vertices qa ..
 * qd with weights from (fu, fv). */
static void bilinear(const uint32_t *restrict qa, const uint32_t *restrict qb, const uint32_t *restrict qc,
                     const uint32_t *restrict qd, const float *restrict fu, const float *restrict fv,
                     float o[3][ATLAS_LANES])
{
    int32_t k;
    for (k = 0; k < ATLAS_LANES; k++) {
        float wa = (1.0f - fu[k]) * (1.0f - fv[k]), wb = fu[k] * (1.0f - fv[k]);
        float wc = (1.0f - fu[k]) * fv[k], wd = fu[k] * fv[k];
        float sa = texel_scale(qa[k]), sb = texel_scale(qb[k]), sc = texel_scale(qc[k]), sd = texel_scale(qd[k]);
        o[0][k] = (float)(int32_t)(qa[k] & 511u) * sa * wa + (float)(int32_t)(qb[k] & 511u) * sb * wb +
                  (float)(int32_t)(qc[k] & 511u) * sc * wc + (float)(int32_t)(qd[k] & 511u) * sd * wd;
        o[1][k] = (float)(int32_t)((qa[k] >> 9) & 511u) * sa * wa + (float)(int32_t)((qb[k] >> 9) & 511u) * sb * wb +
                  (float)(int32_t)((qc[k] >> 9) & 511u) * sc * wc + (float)(int32_t)((qd[k] >> 9) & 511u) * sd * wd;
        o[2][k] = (float)(int32_t)((qa[k] >> 18) & 511u) * sa * wa +
                  (float)(int32_t)((qb[k] >> 18) & 511u) * sb * wb +
                  (float)(int32_t)((qc[k] >> 18) & 511u) * sc * wc + (float)(int32_t)((qd[k] >> 18) & 511u) * sd * wd;
    }
}

/* Batch b summed and written to its pixels of lin; empty after. */
static void batch_write(batch *b, float *lin)
{
    float o[3][ATLAS_LANES];
    int32_t k;
    if (b->n == 0)
        return;
    bilinear(b->qa, b->qb, b->qc, b->qd, b->fu, b->fv, o);
    for (k = 0; k < b->n; k++) {
        float *p = &lin[3 * (size_t)b->pix[k]];
        p[0] = o[0][k];
        p[1] = o[1][k];
        p[2] = o[2][k];
    }
    b->n = 0;
}

/* The batch just gathered (L->b[L->next]) in flight, and the one gathered
 * before it summed and written. */
static void batch_turn(lanes *L, float *lin)
{
    L->next ^= 1;
    batch_write(&L->b[L->next], lin);
}

/* The lanes' vertices gathered into the next batch (their pixels written
 * one batch later, batch_turn); none left. */
static void lanes_read(lanes *L, float *lin)
{
    batch *b = &L->b[L->next];
    int32_t ci[ATLAS_LANES], cj[ATLAS_LANES], k;
    if (L->n == 0)
        return;
    for (k = (int32_t)L->n; k < ATLAS_LANES; k++) { /* idle lanes read the first point */
        L->t0[k] = L->t0[0];
        L->u[k] = L->u[0];
        L->w[k] = L->w[0];
        L->nu[k] = L->nu[0];
        L->nv[k] = L->nv[0];
        L->row[k] = L->row[0];
    }
    cells_of(L->u, L->nu, ci, b->fu);
    cells_of(L->w, L->nv, cj, b->fv);
    for (k = 0; k < ATLAS_LANES; k++) {
        const uint32_t *t = L->t0[k] + (size_t)cj[k] * L->row[k] + (size_t)ci[k];
        b->qa[k] = t[0];
        b->qb[k] = t[1];
        b->qc[k] = t[L->row[k]];
        b->qd[k] = t[L->row[k] + 1];
        b->pix[k] = L->pix[k];
    }
    b->n = (int32_t)L->n;
    L->n = 0;
    batch_turn(L, lin);
}

/* Eight neighbouring pixels i .. i + 7 at (u[k], w[k]) of one chart at t0
 * (nu by nv vertices): the bits of lanes_read's, gathered into the next
 * batch without going through the lanes one by one. */
static void run_read(lanes *L, const uint32_t *t0, uint32_t nu, uint32_t nv, const float *u, const float *w,
                     int32_t i, float *lin)
{
    batch *b = &L->b[L->next];
    int32_t ci[ATLAS_LANES], cj[ATLAS_LANES], k;
    float su[ATLAS_LANES], sv[ATLAS_LANES];
    for (k = 0; k < ATLAS_LANES; k++) {
        su[k] = (float)nu;
        sv[k] = (float)nv;
    }
    cells_of(u, su, ci, b->fu);
    cells_of(w, sv, cj, b->fv);
    for (k = 0; k < ATLAS_LANES; k++) {
        const uint32_t *t = t0 + (size_t)cj[k] * nu + (size_t)ci[k];
        b->qa[k] = t[0];
        b->qb[k] = t[1];
        b->qc[k] = t[nu];
        b->qd[k] = t[nu + 1];
        b->pix[k] = i + k;
    }
    b->n = ATLAS_LANES;
    batch_turn(L, lin);
}

/* Every read of the lanes and batches written. */
static void lanes_finish(lanes *L, float *lin)
{
    lanes_read(L, lin);
    batch_write(&L->b[0], lin);
    batch_write(&L->b[1], lin);
}

/* Pixel i's read at (u, w) of the chart at t0 (nu by nv vertices), read
 * when the lanes are full. */
static inline void lanes_add(lanes *L, int32_t i, const uint32_t *t0, uint32_t nu, uint32_t nv, float u, float w,
                             float *lin)
{
    uint32_t k = L->n;
    L->pix[k] = i;
    L->t0[k] = t0;
    L->u[k] = u;
    L->w[k] = w;
    L->nu[k] = (float)nu;
    L->nv[k] = (float)nv;
    L->row[k] = nu;
    if (++L->n == ATLAS_LANES)
        lanes_read(L, lin);
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
    g->x0 = g->y0 = g->dx = g->dy = 0.0; /* unread when off; set for the compiler's flow analysis */
    if (!g->on)
        return;
    t = -v->eye[2] / dz;
    g->x0 = v->eye[0] - A->g0[0] + t * (v->D0[0] + j * v->Dy[0]);
    g->y0 = v->eye[1] - A->g0[1] + t * (v->D0[1] + j * v->Dy[1]);
    g->dx = t * v->Dx[0];
    g->dy = t * v->Dx[1];
}

/* A ground block's frame: its corner (x, y) from the tiles' corner, and
 * the inverse of its steps' length. */
typedef struct block_frame {
    double x0, y0, inv;
} block_frame;

/* The ground block item (atlas.h) under (x, y) from the tiles' corner,
 * (x, y) in steps within it, and its frame (*f, from the tile's and the
 * block's indices at hand, without dividing: tx A->tile + ix ATLAS_BLOCK
 * step is the same double as from the item's indices); UINT32_MAX off the
 * tiles (*f not written). */
static uint32_t ground_block(const atlas *A, double x, double y, double *u, double *w, block_frame *f)
{
    double fx = x * A->inv_tile, fy = y * A->inv_tile, step_inv, step, bx, by;
    uint32_t tx, ty, tile, nb, ix, iy;
    if (!(fx >= 0.0 && fx < A->gx && fy >= 0.0 && fy < A->gy))
        return UINT32_MAX;
    tx = (uint32_t)fx;
    ty = (uint32_t)fy;
    tile = ty * A->gx + tx;
    step_inv = A->gfine[tile] ? A->inv_fine : A->inv_coarse; /* 1.0 / step (atlas.c) */
    step = A->gfine[tile] ? A->fine : A->coarse;
    x = (x - tx * A->tile) * step_inv; /* in steps within the tile */
    y = (y - ty * A->tile) * step_inv;
    bx = x < 0.0 ? 0.0 : x * (1.0 / ATLAS_BLOCK);
    by = y < 0.0 ? 0.0 : y * (1.0 / ATLAS_BLOCK);
    nb = A->gfine[tile] ? ATLAS_TB - 1 : 0; /* a coarse tile is one block */
    ix = bx < nb ? (uint32_t)bx : nb;
    iy = by < nb ? (uint32_t)by : nb;
    *u = x - ix * ATLAS_BLOCK;
    *w = y - iy * ATLAS_BLOCK;
    f->inv = step_inv;
    f->x0 = tx * A->tile + ix * ATLAS_BLOCK * step;
    f->y0 = ty * A->tile + iy * ATLAS_BLOCK * step;
    return tile * ATLAS_TB * ATLAS_TB + iy * ATLAS_TB + ix;
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
    block_frame f;
    uint32_t b;
    if (u > bm->lo && u < bm->hi && v > bm->lo && v < bm->hi)
        return;
    b = ground_block(A, x, y, &u, &v, &f);
    bm->lo = 1.0;
    bm->hi = -1.0;
    if (b == UINT32_MAX)
        return;
    bm->bx0 = f.x0;
    bm->by0 = f.y0;
    bm->inv = f.inv;
    bm->lo = ATLAS_EDGE;
    bm->hi = ATLAS_BLOCK - ATLAS_EDGE;
    if (A->gfirst[b] != ATLAS_NOVERT)
        want(A, atlas_block_item(A, 0, 0) + b, list, cap, n);
}

/* The first marked pixel of i .. e - 1 (e: none), eight unmarked bytes a
 * test where it can. */
static int32_t next_marked(const uint8_t *mask, int32_t i, int32_t e)
{
    uint64_t q;
    while (i + 8 <= e && (memcpy(&q, mask + i, sizeof q), q == 0))
        i += 8;
    while (i < e && !mask[i])
        i++;
    return i;
}

/* With a mask, the pixels atlas_frame_row reads with it: a building
 * pixel reads its own chart; a ground pixel the block under it, or the
 * block an earlier marked pixel of its run read (ground_run's carried
 * block), listed there. */
uint32_t atlas_frame_missing(atlas *A, const atlas_view *v, const uint32_t *ids, const uint8_t *mask, int32_t j0,
                             int32_t j1, uint32_t *list, uint32_t cap)
{
    uint32_t n = 0, last = MESH_SURF_NONE;
    int32_t i, j;
    if (A->todo == 0)
        return 0;
    for (j = j0 > 0 ? j0 : 0; j < j1 && j < v->h && n < cap; j++) {
        const uint32_t *row = &ids[(size_t)j * v->w];
        const uint8_t *mrow = mask ? &mask[(size_t)j * v->w] : NULL;
        block_memo bm = { 0.0, 0.0, 0.0, 1.0, -1.0 };
        ground_row g;
        ground_setup(A, v, j, &g);
        for (i = 0; i < v->w; i++) {
            uint32_t sid;
            if (mrow && (i = next_marked(mrow, i, v->w)) == v->w)
                break;
            sid = row[i];
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

/* The end of the run of pixels from i with pixel i's id (the first pixel
 * after it, or w): two ids a test, read as one 64-bit word (memcpy: no
 * alignment or aliasing assumed), where it can. */
static int32_t run_end(const uint32_t *ids, int32_t i, int32_t w)
{
    uint32_t sid = ids[i];
    uint64_t two = (uint64_t)sid << 32 | sid, q;
    int32_t e = i + 1;
    while (e + 2 <= w && (memcpy(&q, &ids[e], sizeof q), q == two))
        e += 2;
    if (e < w && ids[e] == sid)
        e++;
    return e;
}

/* Whether the 8 pixels from i are all marked (all are without a mask). */
static int all_marked(const uint8_t *mask, int32_t i)
{
    int32_t k, all = 1;
    if (!mask)
        return 1;
    for (k = 0; k < ATLAS_LANES; k++)
        all &= mask[i + k] != 0;
    return all;
}

/* Pixel i's ground point (x, y) from the tiles' corner, as ground_run
 * computes it. */
static void ground_xy(const ground_row *g, int32_t i, double *x, double *y)
{
    *x = g->x0 + i * g->dx;
    *y = g->y0 + i * g->dy;
}

/* Pixel i's ground point in steps of the block at (bx0, by0). Along a row
 * it is monotone in i (each step a rounding of a monotone function, and
 * inv > 0). */
static void ground_uw(const ground_row *g, int32_t i, double bx0, double by0, double inv, double *u, double *w)
{
    double x, y;
    ground_xy(g, i, &x, &y);
    *u = (x - bx0) * inv;
    *w = (y - by0) * inv;
}

/* The 8 ground pixels from i when all their hit points lie in the block
 * at (bx0, by0) (u and w in [0, lim], as ground_run's test: by the
 * monotony, when the first and the last do), read at once: ground_run's
 * reads, with the same doubles. 0 and nothing read when not. */
static int ground_eight(const ground_row *g, int32_t i, double bx0, double by0, double inv, double lim,
                        const uint32_t *t0, lanes *L, float *lin)
{
    double ua, wa, ub, wb;
    float uf[ATLAS_LANES], wf[ATLAS_LANES];
    int32_t k;
    ground_uw(g, i, bx0, by0, inv, &ua, &wa);
    ground_uw(g, i + ATLAS_LANES - 1, bx0, by0, inv, &ub, &wb);
    if (!(ua >= 0.0 && ua <= lim && wa >= 0.0 && wa <= lim && ub >= 0.0 && ub <= lim && wb >= 0.0 && wb <= lim))
        return 0;
    for (k = 0; k < ATLAS_LANES; k++) {
        double u, w;
        ground_uw(g, i + k, bx0, by0, inv, &u, &w);
        uf[k] = (float)u;
        wf[k] = (float)w;
    }
    run_read(L, t0, ATLAS_BLOCK + 1, ATLAS_BLOCK + 1, uf, wf, i, lin);
    return 1;
}

/* A run of ground pixels i0 .. i1 - 1 of a row: the block under each hit
 * point, kept while the points stay in it (a row's points move by a
 * fixed step: runs of them share a block); black in a dark block. Eight
 * marked pixels in the block are read at once; eight that are not, one
 * by one. */
static int ground_run(const atlas *A, const ground_row *g, int32_t i0, int32_t i1, const uint8_t *mask, lanes *L,
                      float *lin)
{
    double bx0 = 0.0, by0 = 0.0, inv = 0.0, lim = -1.0;
    const uint32_t *t0 = NULL;
    uint32_t cur = UINT32_MAX;
    int32_t i, e;
    int unfilled = 0;
    for (i = i0; i < i1; ) {
        if (i + ATLAS_LANES <= i1 && t0 && all_marked(mask, i) &&
            ground_eight(g, i, bx0, by0, inv, lim, t0, L, lin)) {
            i += ATLAS_LANES;
            continue;
        }
        for (e = i + ATLAS_LANES < i1 ? i + ATLAS_LANES : i1; i < e; i++) {
            double x, y, u, w;
            block_frame f;
            float *o = &lin[3 * (size_t)i];
            if (mask && !mask[i])
                continue;
            ground_uw(g, i, bx0, by0, inv, &u, &w);
            if (!(u >= 0.0 && u <= lim && w >= 0.0 && w <= lim)) { /* another block */
                ground_xy(g, i, &x, &y);
                cur = ground_block(A, x, y, &u, &w, &f);
                t0 = NULL;
                lim = -1.0;
                if (cur != UINT32_MAX && A->gfirst[cur] != ATLAS_NOVERT) {
                    unfilled |= !atlas_filled(A->gdone[cur]);
                    t0 = A->gdone[cur] == ATLAS_DARK ? NULL : &A->tex[A->gfirst[cur]];
                    bx0 = f.x0;
                    by0 = f.y0;
                    inv = f.inv;
                    lim = ATLAS_BLOCK;
                }
            }
            if (!t0) {
                o[0] = o[1] = o[2] = 0.0f;
                continue;
            }
            lanes_add(L, i, t0, ATLAS_BLOCK + 1, ATLAS_BLOCK + 1, (float)u, (float)w, lin);
        }
    }
    return unfilled;
}

/* Pixels i0 .. i1 - 1 black (+0, all bits zero), or only the marked ones
 * with a mask. */
static void black_run(float *lin, int32_t i0, int32_t i1, const uint8_t *mask)
{
    int32_t i;
    if (!mask) {
        memset(&lin[3 * (size_t)i0], 0, 3 * sizeof *lin * (size_t)(i1 - i0));
        return;
    }
    for (i = i0; i < i1; i++)
        if (mask[i])
            lin[3 * (size_t)i] = lin[3 * (size_t)i + 1] = lin[3 * (size_t)i + 2] = 0.0f;
}

/* A run of pixels i0 .. i1 - 1 of row j on surface sid, all marked when
 * there is a mask (atlas_frame_row ends a building's run at its first
 * unmarked pixel): its chart's map, then each pixel's (u, v) and the
 * bilinear read, eight neighbours at once and the rest through the
 * lanes; black on a dark chart (the same bits: a bilinear read of four 0
 * values is +0). */
static int surface_run(const atlas *A, const atlas_view *v, atlas_cache *k, uint32_t sid, int32_t j, int32_t i0,
                       int32_t i1, const uint8_t *mask, lanes *L, float *lin)
{
    const atlas_map *m;
    const atlas_chart *c;
    float fj = (float)j, bu, bv, bw, au, av, aw;
    const uint32_t *t0;
    uint32_t nu, nv;
    int32_t i;
    uint8_t state = sid - 2u < A->nsurf ? A->cdone[sid - 2u] : ATLAS_UNFILLED; /* no chart past nsurf */
    if (state == ATLAS_DARK) { /* no map: one byte decides */
        black_run(lin, i0, i1, mask);
        return 0;
    }
    m = map_of(A, v, k, sid);
    c = m->c;
    if (!c) {
        black_run(lin, i0, i1, mask);
        return 0;
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
#ifdef PLX_DEBUG
    for (i = i0; i < i1; i++) /* every pixel marked: atlas_frame_row's building runs end at an unmarked one */
        PLX_ASSERT(!mask || mask[i]);
#endif
    for (i = i0; i + ATLAS_LANES <= i1; i += ATLAS_LANES) {
        float u[ATLAS_LANES], w[ATLAS_LANES];
        int32_t q;
        for (q = 0; q < ATLAS_LANES; q++) {
            float fi = (float)(i + q), r = 1.0f / (bw + aw * fi);
            u[q] = (bu + au * fi) * r;
            w[q] = (bv + av * fi) * r;
        }
        run_read(L, t0, nu, nv, u, w, i, lin);
    }
    for (; i < i1; i++) {
        float fi = (float)i, r = 1.0f / (bw + aw * fi);
        lanes_add(L, i, t0, nu, nv, (bu + au * fi) * r, (bv + av * fi) * r, lin);
    }
    return !atlas_filled(state);
}

int atlas_frame_row(const atlas *A, const atlas_view *v, atlas_cache *k, const uint32_t *ids, const uint8_t *mask,
                    int32_t j, float *lin, uint64_t count[3])
{
    ground_row g;
    lanes L;
    int32_t i = 0, e;
    int unfilled = 0;
    L.n = 0;
    L.next = 0;
    L.b[0].n = L.b[1].n = 0;
    ground_setup(A, v, j, &g);
    while (i < v->w) {
        uint32_t sid;
        uint64_t n;
        /* with a mask, from the next marked pixel: on a building or the
         * sky to the end of its run of marked pixels (a building pixel's
         * read depends only on the pixel), on the ground to the end of its
         * run of ground, the marked pixels only (the ground's block cache
         * carries on over the unmarked ones as in a full row, whose
         * reads at a block's edge or at a spacing not a power of two can
         * differ in the last bits from a fresh lookup's) */
        if (mask && (i = next_marked(mask, i, v->w)) == v->w)
            break;
        sid = ids[i];
        if (mask && sid != MESH_SURF_GROUND)
            for (e = i + 1; e < v->w && ids[e] == sid && mask[e]; e++)
                ;
        else
            e = run_end(ids, i, v->w);
        if (mask && sid == MESH_SURF_GROUND) { /* only the marked pixels are written, and counted */
            int32_t q;
            for (n = 0, q = i; q < e; q++)
                n += mask[q] != 0;
        } else {
            n = (uint64_t)(e - i);
        }
        if (sid == MESH_SURF_NONE || (sid == MESH_SURF_GROUND && !g.on)) {
            black_run(lin, i, e, mask);
            count[0] += n;
        } else if (sid == MESH_SURF_GROUND) {
            unfilled |= ground_run(A, &g, i, e, mask, &L, lin);
            count[1] += n;
        } else {
            unfilled |= surface_run(A, v, k, sid, j, i, e, mask, &L, lin);
            count[2] += n;
        }
        i = e;
    }
    lanes_finish(&L, lin);
    return unfilled;
}
