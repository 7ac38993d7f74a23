/* render: night images on the CPU (see render.h). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/plx_assert.h"
#include "render/render.h"
#include "render/atlas_frame.h"
#include "base/bucketgrid.h"
#include "render/exposure.h"
#include "render/tonemap.h"
#include "render/raster.h"
#include "light/light.h"
#include "scene/photometry.h"
#include "render/lightmap.h"
#include "render/indmap.h"
#include "light/illuminance.h"
#include "light/litregion.h"
#include "base/geom.h"
#include "render/render_int.h"

#define R_ALIGN 16

/* ---- shaders ---------------------------------------------------------------- */

void render_shade_light(void *user, const double P[3], const double n[3], double rgb[3])
{
    double E;
    if (light_illuminance((light *)user, P, n, &E, rgb) != PLX_OK)
        rgb[0] = rgb[1] = rgb[2] = 0.0;
}

void render_opts_default(render_opts *o)
{
    memset(o, 0, sizeof *o);
    o->exposure = 1.0;
    o->cull = RENDER_CULL_ALL;
    o->near = 0.05;
}

/* ---- creation --------------------------------------------------------------- */

uint32_t render_surf_slots(const scene *s, int32_t max_w, int32_t max_h)
{
    size_t px = (size_t)max_w * (size_t)max_h, nsurf = 2 + (size_t)s->npts + 2 * (size_t)s->nbld;
    uint32_t n = 64;
    while (n < RENDER_SURF_CACHE && n < nsurf && n < px / 64)
        n *= 2;
    return n;
}

/* Rows of corners and of pixels of a frame max_h high (render.stop). */
static size_t stop_rows(int32_t max_h)
{
    return (size_t)(max_h / IND_STEP + 2) + (size_t)max_h;
}

size_t render_bytes(const scene *s, int32_t max_w, int32_t max_h)
{
    size_t px = (size_t)max_w * (size_t)max_h;
    size_t tiles = (size_t)((max_w + RENDER_TILE - 1) / RENDER_TILE) * (size_t)((max_h + RENDER_TILE - 1) / RENDER_TILE);
    size_t corners = (size_t)(max_w / IND_STEP + 2) * (size_t)(max_h / IND_STEP + 2);
    return px * 20 + tiles + (size_t)s->nbld * (2 * sizeof(cull_item) + 29) +
           (size_t)CULL_SIDE * CULL_SIDE * (6 * sizeof(double) + 4 + sizeof(cull_item)) + RENDER_BINS * 8 +
           (size_t)(CULL_SIDE / CULL_GROUP + 1) * (CULL_SIDE / CULL_GROUP + 1) * (6 * sizeof(double) + 1) + 16 +
           sizeof(tonemap_table) + 8 + sizeof(exposure_table) + 8 +
           corners * (1 + 3 * sizeof(float)) + 2 * (size_t)(max_w / IND_STEP + 2) * sizeof(corner_hit) + render_surf_slots(s, max_w, max_h) * (sizeof(uint32_t) + sizeof(mesh_surf)) +
           stop_rows(max_h) * sizeof(int32_t) + arena_mul((size_t)s->nlamps + 1, sizeof(uint32_t)) + 64 +
           arena_mul((size_t)s->nlamps + 1, sizeof(glow_seen)) + 16 +
           sizeof(render) + 4096;
}

const mesh *render_mesh(const render *r)
{
    return r->m;
}

const uint32_t *render_ids(const render *r)
{
    return r->id;
}

const char *render_error(const render *r)
{
    return r && r->err ? r->err : "";
}

uint8_t render_srgb8(const render *r, double v)
{
    return tonemap_srgb8(r->thr, v);
}

plx_status render_create(arena *a, const scene *s, int32_t max_w, int32_t max_h,
                         render_shade_fn shade, void *user, render **out)
{
    arena_mark m0;
    render *r;
    size_t px;
    plx_status st;
    if (!a || !s || !shade || !out)
        return PLX_E_INVALID;
    *out = NULL;
    if (max_w < 1 || max_h < 1 || max_w > RASTER_MAX_DIM || max_h > RASTER_MAX_DIM)
        return PLX_E_INVALID;
    m0 = arena_get_mark(a);
    r = arena_calloc(a, PLX_PART_FRAME, 1, sizeof *r, R_ALIGN);
    if (!r)
        return PLX_E_NOMEM;
    r->a = a;
    r->s = s;
    r->shade = shade;
    r->user = user;
    r->max_w = max_w;
    r->max_h = max_h;
    st = mesh_build(a, s, &r->m);
    if (st != PLX_OK) {
        arena_release(a, &m0);
        return st;
    }
    px = (size_t)max_w * (size_t)max_h;
    r->depth = arena_alloc(a, PLX_PART_FRAME, arena_mul(px, sizeof(float)), 64);
    r->id = arena_alloc(a, PLX_PART_FRAME, arena_mul(px, sizeof(uint32_t)), 64);
    r->lin = arena_alloc(a, PLX_PART_FRAME, arena_mul(px, 3 * sizeof(float)), 64);
    r->vbuf = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->m->max_bld_verts + 1, sizeof(raster_vertex)), 64);
    r->pv = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->m->max_bld_verts + 1, sizeof(raster_pvert)), 64);
    r->clip = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->m->max_bld_verts + 1, 4 * sizeof(float)), 64);
    r->gxyz = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->m->max_bld_verts + 1, 3 * sizeof(double)), 64);
    r->gtri = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->m->max_bld_tris + 1, sizeof(mesh_tri)), 64);
    r->sc_mask = render_surf_slots(s, max_w, max_h) - 1u;
    r->sc_id = arena_calloc(a, PLX_PART_FRAME, r->sc_mask + 1u, sizeof(uint32_t), 64);
    r->sc = arena_calloc(a, PLX_PART_FRAME, r->sc_mask + 1u, sizeof(mesh_surf), 64);
    r->heap = arena_alloc(a, PLX_PART_FRAME, arena_mul(s->nbld + 1, sizeof(cull_item)), R_ALIGN);
    r->wmin = arena_alloc(a, PLX_PART_FRAME, arena_mul(s->nbld + 1, sizeof(double)), R_ALIGN);
    r->wmax = arena_alloc(a, PLX_PART_FRAME, arena_mul(s->nbld + 1, sizeof(double)), R_ALIGN);
    r->draw = arena_alloc(a, PLX_PART_FRAME, s->nbld + 1, R_ALIGN);
    r->glamp = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)s->nlamps + 1, sizeof(uint32_t)), R_ALIGN);
    r->gseen = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)s->nlamps + 1, sizeof(glow_seen)), R_ALIGN);
    r->bins = arena_alloc(a, PLX_PART_FRAME, RENDER_BINS * sizeof(double), R_ALIGN);
    {
        double x0, y0, cell;
        uint32_t n = cull_side(s, &x0, &y0, &cell);
        r->ncell = n * n;
        r->cside = n;
        r->gside = (n + CULL_GROUP - 1) / CULL_GROUP;
        r->group_box = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)r->gside * r->gside, 6 * sizeof(double)),
                                   R_ALIGN);
        r->group_out = arena_alloc(a, PLX_PART_FRAME, (size_t)r->gside * r->gside, R_ALIGN);
        r->cell_start = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->ncell + 1, sizeof(uint32_t)), R_ALIGN);
        r->cell_bld = arena_alloc(a, PLX_PART_FRAME, arena_mul(s->nbld + 1, sizeof(uint32_t)), R_ALIGN);
        r->cell_box = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->ncell, 6 * sizeof(double)), R_ALIGN);
        r->trav = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)s->nbld + r->ncell + 1, sizeof(cull_item)),
                              R_ALIGN);
    }
    if (!r->depth || !r->id || !r->lin || !r->vbuf || !r->pv || !r->clip || !r->gxyz || !r->gtri || !r->sc_id || !r->sc ||
        !r->heap || !r->wmin ||
        !r->wmax || !r->draw || !r->glamp || !r->bins || !r->cell_start || !r->cell_bld || !r->cell_box ||
        !r->trav || !r->group_box || !r->group_out || !r->gseen) {
        arena_release(a, &m0);
        return PLX_E_NOMEM;
    }
    cull_grid_fill(r);
    r->tm = arena_alloc(a, PLX_PART_FRAME, sizeof(tonemap_table), R_ALIGN);
    r->et = arena_alloc(a, PLX_PART_FRAME, sizeof(exposure_table), R_ALIGN);
    r->defer = arena_alloc(a, PLX_PART_FRAME,
                           (size_t)((max_w + RENDER_TILE - 1) / RENDER_TILE) *
                               (size_t)((max_h + RENDER_TILE - 1) / RENDER_TILE), R_ALIGN);
    r->blk = arena_alloc(a, PLX_PART_FRAME, (size_t)(max_w / IND_STEP + 2) * (size_t)(max_h / IND_STEP + 2),
                         R_ALIGN);
    r->ind = arena_alloc(a, PLX_PART_FRAME,
                         arena_mul((size_t)(max_w / IND_STEP + 2) * (size_t)(max_h / IND_STEP + 2),
                                   3 * sizeof(float)), R_ALIGN);
    r->crow = arena_alloc(a, PLX_PART_FRAME, 2 * (size_t)(max_w / IND_STEP + 2) * sizeof(corner_hit), R_ALIGN);
    r->stop = arena_alloc(a, PLX_PART_FRAME, stop_rows(max_h) * sizeof(int32_t), R_ALIGN);
    if (shade == render_shade_light && user)
        r->lt = user;
    if (!r->tm || !r->et || !r->defer || !r->blk || !r->ind || !r->crow || !r->stop) {
        arena_release(a, &m0);
        return PLX_E_NOMEM;
    }
    r->yr = arena_alloc(a, PLX_PART_FRAME, arena_mul(s->nbld + 1, 2 * sizeof(int32_t)), R_ALIGN);
    if (!r->yr) {
        arena_release(a, &m0);
        return PLX_E_NOMEM;
    }
    soft_bands_create(r, a); /* none when their buffers would be too large: one thread draws */
    tonemap_thresholds(r->thr);
    r->tm->usable = 0;
    exposure_table_init(r->et);
    render_code_bind(r, shade);
    *out = r;
    return PLX_OK;
}

void render_frame_clear(render *r)
{
    const scene *s = r->s;
    size_t px = (size_t)r->max_w * (size_t)r->max_h, v = (size_t)r->m->max_bld_verts + 1, nb = (size_t)s->nbld + 1;
    size_t tiles = (size_t)((r->max_w + RENDER_TILE - 1) / RENDER_TILE) * (size_t)((r->max_h + RENDER_TILE - 1) / RENDER_TILE);
    size_t corners = (size_t)(r->max_w / IND_STEP + 2) * (size_t)(r->max_h / IND_STEP + 2);
    int k;
    memset(r->depth, 0, px * sizeof *r->depth);
    memset(r->id, 0, px * sizeof *r->id);
    memset(r->lin, 0, px * 3 * sizeof *r->lin);
    memset(r->vbuf, 0, v * sizeof *r->vbuf);
    memset(r->pv, 0, v * sizeof *r->pv);
    memset(r->clip, 0, v * 4 * sizeof *r->clip);
    memset(r->gxyz, 0, v * 3 * sizeof *r->gxyz);
    memset(r->gtri, 0, ((size_t)r->m->max_bld_tris + 1) * sizeof *r->gtri);
    memset(r->sc_id, 0, ((size_t)r->sc_mask + 1) * sizeof *r->sc_id);
    memset(r->sc, 0, ((size_t)r->sc_mask + 1) * sizeof *r->sc);
    memset(r->heap, 0, nb * sizeof *r->heap);
    memset(r->wmin, 0, nb * sizeof *r->wmin);
    memset(r->wmax, 0, nb * sizeof *r->wmax);
    memset(r->draw, 0, nb);
    memset(r->yr, 0, nb * 2 * sizeof *r->yr);
    memset(r->bins, 0, RENDER_BINS * sizeof *r->bins);
    memset(r->trav, 0, (nb + r->ncell) * sizeof *r->trav);
    memset(r->group_out, 0, (size_t)r->gside * r->gside);
    memset(r->defer, 0, tiles);
    memset(r->blk, 0, corners);
    memset(r->ind, 0, corners * 3 * sizeof *r->ind);
    memset(r->crow, 0, 2 * (size_t)(r->max_w / IND_STEP + 2) * sizeof *r->crow);
    memset(r->stop, 0, stop_rows(r->max_h) * sizeof *r->stop);
    memset(r->tm, 0, sizeof *r->tm);
    memset(r->ws, 0, sizeof r->ws);
    memset(r->hist, 0, sizeof r->hist);
    memset(&r->rc, 0, sizeof r->rc);
    for (k = 0; r->band && k < RENDER_BANDS; k++) {
        band *bd = &r->band[k];
        memset(&bd->rc, 0, sizeof bd->rc);
        bd->cur_id = 0;
        memset(bd->gxyz, 0, v * 3 * sizeof *bd->gxyz);
        memset(bd->gtri, 0, ((size_t)r->m->max_bld_tris + 1) * sizeof *bd->gtri);
        memset(bd->clip, 0, v * 4 * sizeof *bd->clip);
        memset(bd->vbuf, 0, v * sizeof *bd->vbuf);
        memset(bd->pv, 0, v * sizeof *bd->pv);
    }
    r->w = r->h = 0;
    r->cur_id = 0;
    r->frames = 0;
    r->nheap = r->ntrav = 0;
    memset(r->eye, 0, sizeof r->eye);
    memset(r->f, 0, sizeof r->f);
    memset(r->rt, 0, sizeof r->rt);
    memset(r->up, 0, sizeof r->up);
    r->sx = r->sy = r->za = r->zb = r->tanh_ = r->aspect = r->near_ = r->far_ = 0.0;
    memset(r->far_eye, 0, sizeof r->far_eye);
    r->far_near = 0.0;
    r->shift[0] = r->shift[1] = r->shx = r->shy = 0.0;
    memset(r->cpad, 0, sizeof r->cpad);
    r->kept = r->kept_inside = 0;
    memset(r->kept_key, 0, sizeof r->kept_key);
    r->kept_frustum = r->kept_occlusion = 0;
    memset(r->glamp, 0, ((size_t)s->nlamps + 1) * sizeof *r->glamp);
    r->bg_fill = 0;
    r->nglamp = 0;
    r->glamp_ok = 0;
    memset(r->gseen, 0, ((size_t)s->nlamps + 1) * sizeof *r->gseen);
    r->ngseen = 0;
    r->gseen_ok = 0;
    r->nbx = r->nby = 0;
    r->sparse = 0;
}

size_t render_struct_bytes(void)
{
    return sizeof(render);
}

void render_code_unbind(render *r)
{
    r->shade = NULL;
    r->soft.name = NULL;
    r->soft.begin = NULL;
    r->soft.draw = NULL;
    r->soft.finish = NULL;
    memset(&r->rc, 0, sizeof r->rc);
    r->err = NULL;
}

void render_code_bind(render *r, render_shade_fn shade)
{
    r->shade = shade;
    r->soft.name = "soft";
    r->soft.user = r;
    r->soft.begin = soft_begin;
    r->soft.draw = soft_draw;
    r->soft.finish = soft_finish;
    r->err = "";
}

int render_eye_inside(const render *r, const double eye[3])
{
    const scene *s = r->s;
    uint32_t b, k;
    vec2 p;
    p.x = eye[0];
    p.y = eye[1];
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        const scene_ring *rg;
        int in;
        if (p.x < bd->box[0] || p.x > bd->box[2] || p.y < bd->box[1] || p.y > bd->box[3])
            continue;
        if (!(eye[2] >= bd->min_height && eye[2] <= bd->height))
            continue;
        rg = &s->rings[bd->ring_first];
        in = geom_point_in_ring(p, s->pts + rg->first, rg->count) != GEOM_OUTSIDE;
        for (k = 1; in && k < bd->ring_count; k++) {
            rg = &s->rings[bd->ring_first + k];
            if (geom_point_in_ring(p, s->pts + rg->first, rg->count) == GEOM_INSIDE)
                in = 0;
        }
        if (in)
            return 1;
    }
    return 0;
}

/* ---- sparse indirect (render_opts.indirect_sparse) ---------------------
 * The indirect hook is asked at the corners of blocks of IND_STEP pixels a
 * side, before the shading pass; a block whose pixels and corners all lie
 * on one surface takes its pixels' indirect term bilinearly from its
 * corners, and every other pixel asks the hook itself after the pass. The
 * hook is only ever called on this thread. With render_opts.indirect_try
 * and workers, the workers first try each row of corners (then of pixels)
 * left to right and stop at the first point the try cannot answer; this
 * thread then asks the hook from there on, row after row. The try gives
 * the hook's own bits, so the image is the same bytes for any number of
 * workers. */

static int32_t corner_x(const render *r, int32_t a)
{
    int32_t x = a * IND_STEP;
    return x < r->w ? x : r->w - 1;
}

static int32_t corner_y(const render *r, int32_t b)
{
    int32_t y = b * IND_STEP;
    return y < r->h ? y : r->h - 1;
}

/* The block of column i (row j): the last block takes the last pixels. */
static int32_t block_of(int32_t i, int32_t nb)
{
    int32_t a = i / IND_STEP;
    return a < nb ? a : nb - 1;
}

/* The hit points of the corners of row b of the grid. */
static void corner_row(render *r, int32_t b, corner_hit *row)
{
    int32_t a;
    uint32_t sid;
    for (a = 0; a <= r->nbx; a++)
        row[a].hit = shade_pixel_hit(r, corner_x(r, a), corner_y(r, b), &sid, row[a].P, row[a].n);
}

/* Whether block (a, b), its far corners included, lies on one surface,
 * and its corners' hit points (top: row b, bot: row b + 1) lie within
 * span times the distance of the nearest of them from the eye (seen at a
 * grazing angle, a block spans far more of the surface than its
 * neighbours nearer the eye). */
static int block_one_surface(const render *r, int32_t a, int32_t b, double span, const corner_hit *top,
                             const corner_hit *bot)
{
    int32_t x0 = corner_x(r, a), x1 = corner_x(r, a + 1), y0 = corner_y(r, b), y1 = corner_y(r, b + 1), x, y;
    uint32_t sid = r->id[(size_t)y0 * (size_t)r->w + (size_t)x0];
    double lo[3], hi[3], dmin = HUGE_VAL, ext = 0.0;
    int c, k;
    if (sid == MESH_SURF_NONE)
        return 0;
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            if (r->id[(size_t)y * (size_t)r->w + (size_t)x] != sid)
                return 0;
    for (c = 0; c < 4; c++) {
        const double *C = (c & 2 ? bot : top)[a + (c & 1)].P;
        double d2 = 0.0;
        for (k = 0; k < 3; k++) {
            double dk = C[k] - r->eye[k];
            d2 += dk * dk;
            lo[k] = c ? fmin(lo[k], C[k]) : C[k];
            hi[k] = c ? fmax(hi[k], C[k]) : C[k];
        }
        dmin = fmin(dmin, sqrt(d2));
    }
    for (k = 0; k < 3; k++)
        ext = fmax(ext, hi[k] - lo[k]);
    return ext <= span * dmin;
}

/* Whether corner (a, b) is a corner of a one-surface block. */
static int corner_used(const render *r, int32_t a, int32_t b)
{
    int32_t da, db;
    for (db = -1; db <= 0; db++)
        for (da = -1; da <= 0; da++) {
            int32_t x = a + da, y = b + db;
            if (x >= 0 && y >= 0 && x < r->nbx && y < r->nby && r->blk[(size_t)y * (size_t)r->nbx + (size_t)x] == 1)
                return 1;
        }
    return 0;
}

/* Corner (a, b)'s value from the hook (try: from indirect_try; returns 0
 * when it cannot say), stored in r->ind. */
static int corner_value(render *r, const render_opts *o, int32_t a, int32_t b, const corner_hit *h, int try,
                        int worker)
{
    float *c = &r->ind[3 * ((size_t)b * (size_t)(r->nbx + 1) + (size_t)a)];
    double Ei[3] = { 0.0, 0.0, 0.0 };
    int k;
    if (try) {
        if (!o->indirect_try(o->indirect_user, worker, h->P, h->n, Ei))
            return 0;
    } else
        o->indirect(o->indirect_user, h->P, h->n, Ei);
    for (k = 0; k < 3; k++)
        c[k] = (float)Ei[k];
    return 1;
}

/* The hook at the used corners of row b (the blocks above and below it
 * known) from corner a0 on, left to right. */
static void corner_gather(render *r, const render_opts *o, render_stats *st, int32_t b, const corner_hit *row,
                          int32_t a0)
{
    int32_t a;
    for (a = a0; a <= r->nbx; a++)
        if (row[a].hit && corner_used(r, a, b)) {
            (void)corner_value(r, o, a, b, &row[a], 0, 0);
            st->indirect_calls++;
        }
}

/* The workers' share of the sparse indirect (render_opts.indirect_try). */
typedef struct try_job {
    render *r;
    const render_opts *o;
    uint64_t calls[RENDER_MAX_WORKERS];
} try_job;

/* Corner row b on a worker: tried left to right up to the first miss
 * (render_job_fn; r->stop[b] is where this thread goes on). */
static void corner_try_row(void *arg, int worker, uint32_t b)
{
    try_job *jb = arg;
    render *r = jb->r;
    int32_t a;
    for (a = 0; a <= r->nbx; a++) {
        corner_hit h;
        uint32_t sid;
        if (!corner_used(r, a, (int32_t)b))
            continue;
        /* the ground ids are in place: this shade_pixel_hit writes nothing */
        h.hit = shade_pixel_hit(r, corner_x(r, a), corner_y(r, (int32_t)b), &sid, h.P, h.n);
        if (!h.hit)
            continue;
        if (!corner_value(r, jb->o, a, (int32_t)b, &h, 1, worker))
            break;
        jb->calls[worker]++;
    }
    r->stop[b] = a;
}

/* How many workers may try the hook (0: none, the hook on this thread). */
static int try_workers(const render_opts *o)
{
    int nw = par_workers(o);
    return o->indirect_try && nw > 1 ? nw : 0;
}

/* fn on rows 0 .. n - 1 on the workers; 0 when the port could not run them. */
static int try_rows(render *r, const render_opts *o, render_stats *st, uint32_t n, render_job_fn fn)
{
    try_job jb;
    int nw = try_workers(o), k;
    memset(&jb, 0, sizeof jb);
    jb.r = r;
    jb.o = o;
    if (nw == 0 || o->par(o->par_ctx, nw, n, fn, &jb) != 0)
        return 0;
    for (k = 0; k < nw; k++)
        st->indirect_calls += jb.calls[k];
    return 1;
}

/* Each row of corners from where the workers stopped, on this thread. */
static void corners_rest(render *r, const render_opts *o, render_stats *st)
{
    int32_t a, b;
    for (b = 0; b <= r->nby; b++) {
        corner_hit h;
        uint32_t sid;
        for (a = r->stop[b]; a <= r->nbx; a++)
            if (corner_used(r, a, b)) {
                h.hit = shade_pixel_hit(r, corner_x(r, a), corner_y(r, b), &sid, h.P, h.n);
                if (h.hit) {
                    (void)corner_value(r, o, a, b, &h, 0, 0);
                    st->indirect_calls++;
                }
            }
    }
}

/* Whether a pixel of block (a, b), its far corners included, is shaded
 * in this sample (render_opts.mask). */
static int block_masked(const render *r, const render_opts *o, int32_t a, int32_t b)
{
    int32_t x0 = corner_x(r, a), x1 = corner_x(r, a + 1), y0 = corner_y(r, b), y1 = corner_y(r, b + 1), x, y;
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            if (o->mask[(size_t)y * (size_t)r->w + (size_t)x])
                return 1;
    return 0;
}

/* Before the shading pass: ground ids, the one-surface blocks and the
 * hook's value at their corners, row by row (each corner's hit point
 * found once, two rows of them kept; with tries, the hook's values after
 * the blocks, on the workers first). A later anti-aliasing sample asks
 * only the corners of blocks holding a pixel it shades (blk 2: one
 * surface, none shaded). */
static void sparse_corners(render *r, const render_opts *o, render_stats *st)
{
    int32_t a, b;
    corner_hit *row[2];
    r->nbx = r->w > 1 ? (r->w - 1 + IND_STEP - 1) / IND_STEP : 1;
    r->nby = r->h > 1 ? (r->h - 1 + IND_STEP - 1) / IND_STEP : 1;
    row[0] = r->crow;
    row[1] = r->crow + r->nbx + 1;
    int tries = try_workers(o) > 0;
    soft_ground_ids(r, o);
    corner_row(r, 0, row[0]);
    for (b = 0; b < r->nby; b++) {
        corner_row(r, b + 1, row[(b + 1) & 1]);
        for (a = 0; a < r->nbx; a++) {
            uint8_t one = (uint8_t)block_one_surface(r, a, b, o->indirect_span, row[b & 1], row[(b + 1) & 1]);
            st->indirect_blocks += one;
            if (one && o->mask && !block_masked(r, o, a, b))
                one = 2; /* one surface, no pixel shaded in this sample: corners not asked */
            r->blk[(size_t)b * (size_t)r->nbx + (size_t)a] = one;
        }
        if (!tries)
            corner_gather(r, o, st, b, row[b & 1], 0);
    }
    if (!tries)
        corner_gather(r, o, st, r->nby, row[r->nby & 1], 0);
    else if (try_rows(r, o, st, (uint32_t)r->nby + 1, corner_try_row))
        corners_rest(r, o, st);
    else { /* the port could not run them: every corner here */
        for (b = 0; b <= r->nby; b++)
            r->stop[b] = 0;
        corners_rest(r, o, st);
    }
    st->indirect_nblocks = (uint64_t)r->nbx * (uint64_t)r->nby;
}

/* Pixel (i, j)'s indirect term added to E when its block lies on one
 * surface (bilinear over the block's corners). */
void sparse_at(const render *r, int32_t i, int32_t j, double E[3])
{
    int32_t a = block_of(i, r->nbx), b = block_of(j, r->nby);
    int32_t x0 = corner_x(r, a), x1 = corner_x(r, a + 1), y0 = corner_y(r, b), y1 = corner_y(r, b + 1);
    const float *c00, *c10, *c01, *c11;
    double fx, fy;
    size_t row = (size_t)(r->nbx + 1);
    int k;
    if (!r->blk[(size_t)b * (size_t)r->nbx + (size_t)a])
        return;
    fx = x1 > x0 ? (double)(i - x0) / (double)(x1 - x0) : 0.0;
    fy = y1 > y0 ? (double)(j - y0) / (double)(y1 - y0) : 0.0;
    c00 = &r->ind[3 * ((size_t)b * row + (size_t)a)];
    c10 = c00 + 3;
    c01 = c00 + 3 * row;
    c11 = c01 + 3;
    for (k = 0; k < 3; k++)
        E[k] += (1.0 - fy) * ((1.0 - fx) * c00[k] + fx * c10[k]) + fy * ((1.0 - fx) * c01[k] + fx * c11[k]);
}

/* After the shading pass: the pixels of the other blocks ask the hook. */
/* Pixel row j's pixels the blocks leave, from pixel i0 on: the hook's
 * term added (try: stops at the first the try cannot answer); returns
 * where it stopped (r->w: the row is done) and counts the calls. */
static int32_t rest_row(render *r, const render_opts *o, int32_t j, int32_t i0, int try, int worker,
                        uint64_t *calls)
{
    int32_t i;
    for (i = i0; i < r->w; i++) {
        size_t p = (size_t)j * (size_t)r->w + (size_t)i;
        float *out = &r->lin[3 * p];
        double P[3], n[3], Ei[3] = { 0, 0, 0 }, alb[3];
        uint32_t sid;
        int k;
        if (r->blk[(size_t)block_of(j, r->nby) * (size_t)r->nbx + (size_t)block_of(i, r->nbx)] ||
            (o->mask && !o->mask[p]) || !shade_pixel_hit(r, i, j, &sid, P, n))
            continue;
        if (!try)
            o->indirect(o->indirect_user, P, n, Ei);
        else if (!o->indirect_try(o->indirect_user, worker, P, n, Ei))
            break;
        (*calls)++;
        if (sid == MESH_SURF_GROUND)
            scene_ground_albedo(r->s, P[0], P[1], alb);
        else
            alb[0] = alb[1] = alb[2] = surf_albedo(r, sid);
        for (k = 0; k < 3; k++)
            out[k] = (float)((double)out[k] + alb[k] / PI * Ei[k]);
    }
    return i;
}

/* Pixel row j on a worker (render_job_fn; r->stop after the corner rows). */
static void rest_try_row(void *arg, int worker, uint32_t j)
{
    try_job *jb = arg;
    render *r = jb->r;
    r->stop[r->nby + 1 + (int32_t)j] = rest_row(r, jb->o, (int32_t)j, 0, 1, worker, &jb->calls[worker]);
}

static void sparse_rest(render *r, const render_opts *o, render_stats *st)
{
    int32_t j, *stop = r->stop + r->nby + 1;
    if (!try_rows(r, o, st, (uint32_t)r->h, rest_try_row))
        for (j = 0; j < r->h; j++)
            stop[j] = 0;
    for (j = 0; j < r->h; j++)
        (void)rest_row(r, o, j, stop[j], 0, 0, &st->indirect_calls);
}

#define TONEMAP_CHUNK 65536     /* values a job */

typedef struct tonemap_job {
    const render *r;
    const float *lin;
    size_t n;
    uint8_t *rgb8;
    int far[RENDER_MAX_WORKERS]; /* tonemap_apply's answers, by worker */
} tonemap_job;

static void tonemap_chunk(void *arg, int worker, uint32_t k)
{
    tonemap_job *jb = arg;
    size_t p0 = (size_t)k * TONEMAP_CHUNK, p1 = p0 + TONEMAP_CHUNK < jb->n ? p0 + TONEMAP_CHUNK : jb->n;
    jb->far[worker] |= tonemap_apply(jb->r->tm, jb->r->thr, jb->lin, p0, p1, jb->rgb8);
}

int render_tonemap_par(render *r, const float *lin, size_t px, double ex, int curve, uint8_t *rgb8,
                       const render_opts *o)
{
    tonemap_job jb;
    int k, far = 0;
    tonemap_table_set(r->tm, r->thr, ex, curve);
    memset(&jb, 0, sizeof jb);
    jb.r = r;
    jb.lin = lin;
    jb.n = 3 * px;
    jb.rgb8 = rgb8;
    run_jobs(o, (uint32_t)((3 * px + TONEMAP_CHUNK - 1) / TONEMAP_CHUNK), tonemap_chunk, &jb);
    for (k = 0; k < RENDER_MAX_WORKERS; k++)
        far |= jb.far[k];
    return far;
}

/* Part k of RENDER_MAX_WORKERS of the exposure's pixels counted into
 * hist[k] (render_job_fn). */
static void exposure_part(void *arg, int worker, uint32_t k)
{
    render *r = arg;
    size_t px = (size_t)r->w * (size_t)r->h, p0 = px * k / RENDER_MAX_WORKERS, p1 = px * (k + 1) / RENDER_MAX_WORKERS;
    (void)worker;
    memset(r->hist[k], 0, sizeof r->hist[k]);
    exposure_count_table(r->et, r->lin, r->id, p0, p1, r->hist[k]);
}

/* The exposure from the parts' counts (hist[0 .. RENDER_MAX_WORKERS-1]),
 * summed into hist[0]. */
static double exposure_sum(render *r)
{
    uint32_t k, b;
    for (k = 1; k < RENDER_MAX_WORKERS; k++)
        for (b = 0; b < EXPOSURE_BINS; b++)
            r->hist[0][b] += r->hist[k][b];
    return exposure_from(r->hist[0]);
}

/* exposure_auto over the frame, its parts counted on the workers (the
 * counts are summed: the same exposure for any number of them). */
static double exposure_par(render *r, const render_opts *o)
{
    run_jobs(o, RENDER_MAX_WORKERS, exposure_part, r);
    return exposure_sum(r);
}

const float *render_linear(const render *r)
{
    return r->lin;
}

float *render_swap_linear(render *r, float *lin)
{
    float *old = r->lin;
    r->lin = lin;
    return old;
}

/* What a frame's culling depends on besides the sample point: the
 * camera, the near and far planes, the culling mode and the drawing path
 * (bands take the buildings' rows). */
static void culling_key(const render *r, const render_opts *o, int bands, double key[16])
{
    int k;
    for (k = 0; k < 3; k++) {
        key[k] = r->eye[k];
        key[3 + k] = r->f[k];
        key[6 + k] = r->up[k];
    }
    key[9] = r->tanh_;
    key[10] = r->aspect;
    key[11] = r->near_;
    key[12] = r->far_;
    key[13] = (double)r->w * 65536.0 + r->h;
    key[14] = o->cull;
    key[15] = bands;
}

/* Whether this sample reuses the culling kept by the frame's first
 * (render_opts.cull_samples), with the eye's inside test it made;
 * otherwise the test is made here. */
static int kept_culling(render *r, const render_opts *o, int bands, int *inside)
{
    double key[16];
    culling_key(r, o, bands, key);
    if (o->cull_samples == RENDER_SAMPLE_LATER && r->kept && memcmp(key, r->kept_key, sizeof key) == 0) {
        *inside = r->kept_inside;
        return 1;
    }
    r->kept = 0;
    *inside = render_eye_inside(r, r->eye);
    if (o->cull_samples) {
        memcpy(r->kept_key, key, sizeof key);
        r->kept_inside = *inside;
    }
    return 0;
}

/* The frame's culling (cull_buildings), or the one kept for its sample points, its
 * counts with it. */
static void frame_cull(render *r, const render_opts *o, int inside, int rows, int kept, render_stats *st)
{
    if (kept) {
        st->cull_kept = 1;
        st->frustum_culled = r->kept_frustum;
        st->occlusion_culled = r->kept_occlusion;
        return;
    }
    cull_buildings(r, o, inside, rows, st);
    r->glamp_ok = 0;
    if (o->cull_samples) {
        if (!o->no_glow)
            glow_candidates(r);
        r->kept = 1;
        r->kept_frustum = st->frustum_culled;
        r->kept_occlusion = st->occlusion_culled;
    }
}

plx_status render_frame(render *r, const render_camera *cam, const render_opts *o,
                        uint8_t *rgb8, float *rgbf, render_stats *stats)
{
    render_stats st;
    render_opts def;
    const render_backend *be;
    size_t px;
    int inside, bands, kept;
    if (!r)
        return PLX_E_INVALID;
    if (!cam) {
        r->err = "render_frame: camera is NULL";
        return PLX_E_INVALID;
    }
    if (!o) {
        render_opts_default(&def);
        o = &def;
    }
    r->gseen_ok = 0; /* the glow discs are the frame's (glow_discs) */
    if (!camera_setup(r, cam, o))
        return PLX_E_INVALID;
    memset(&st, 0, sizeof st);
    st.buildings = r->s->nbld;
    st.triangles = r->m->ntri;
    px = (size_t)r->w * (size_t)r->h;
    be = o->backend ? o->backend : &r->soft;
    if (!be->begin || !be->draw || !be->finish) {
        r->err = "render_frame: the backend lacks a function";
        return PLX_E_INVALID;
    }
    bands = be == &r->soft && r->band && par_workers(o) >= 2;
    /* atlas frames from the built-in rasteriser: the ground's ids as the rows start */
    r->bg_fill = be == &r->soft && o->atlas != NULL;
    kept = kept_culling(r, o, bands, &inside);
    st.eye_inside = inside;
    if (bands) {
        /* the built-in rasteriser on the workers, by bands of rows */
        frame_cull(r, o, inside, 1, kept, &st);
        soft_draw_bands(r, o, !inside, &st);
    } else {
        if (be->begin(be->user, r->w, r->h, !inside) != 0) {
            r->err = "render_frame: the backend could not start the frame";
            return PLX_E_UNSUPPORTED;
        }
        frame_cull(r, o, inside, 0, kept, &st);
        soft_draw_buildings(r, be, &st);
        if (be->finish(be->user, r->id, r->depth) != 0) {
            r->err = "render_frame: the backend could not read the frame back";
            return PLX_E_UNSUPPORTED;
        }
    }
    st.drawn_fraction = st.triangles ? (double)st.triangles_drawn / (double)st.triangles : 1.0;
    if (o->atlas) {
        if (render_atlas_pass(r, o, &st) != 0) {
            r->err = "render_frame: the radiance atlas could not be filled for this frame";
            return PLX_E_NOMEM;
        }
        goto finish;
    }
    shade_surf_cache_fill(r);
    if (o->mask)
        render_aa_mask_update(r, o);
    if (o->lightmap && r->lm.built && !r->lm.has_ind && o->indirect && o->indirect_map &&
        (!r->im.built || r->im.key != o->indirect_key))
        /* out of memory: the frame takes the hook per pixel (indmap_usable) */
        (void)indmap_build(&r->im, r->a, &r->lm, o->indirect_far ? o->indirect_far : o->indirect,
                           o->indirect_user, o->top, o->indirect_user, o->indirect_key,
                           o->indirect_far || o->indirect_mt ? o->par : NULL, o->par_ctx, o->workers);
    r->sparse = o->indirect && o->indirect_sparse && !o->lightmap && o->indirect_span > 0.0;
    if (r->sparse)
        sparse_corners(r, o, &st);
    shade_pass(r, o, &st);
    if (r->sparse)
        sparse_rest(r, o, &st);
finish:
    /* the exposure from the lit surfaces, before the glows (counted by
     * the atlas's rows as they were read) */
    if (o->atlas && o->auto_exposure)
        st.exposure = exposure_sum(r);
    else
        st.exposure = o->auto_exposure ? exposure_par(r, o) : o->exposure;
    if (!o->no_glow)
        glow_draw(r, o, &st);
    if (rgbf)
        memcpy(rgbf, r->lin, px * 3 * sizeof(float));
    if (rgb8)
        render_tonemap_par(r, r->lin, px, st.exposure, o->auto_exposure, rgb8, o);
    r->err = "";
    if (stats)
        *stats = st;
    return PLX_OK;
}

/* ---- light map (lightmap.c) ------------------------------------------------------ */

plx_status render_lightmap_build(render *r, double cell, size_t max_bytes)
{
    return render_lightmap_build_par(r, cell, max_bytes, NULL, NULL, 1);
}

plx_status render_lightmap_build_par(render *r, double cell, size_t max_bytes, render_par_fn par, void *ctx,
                                     int workers)
{
    lightmap_par lp;
    if (!r)
        return PLX_E_INVALID;
    memset(&lp, 0, sizeof lp);
    r->im.built = 0;   /* over the old map's box */
    lp.par = par;
    lp.ctx = ctx;
    lp.workers = workers > RENDER_MAX_WORKERS ? RENDER_MAX_WORKERS : workers;
    lp.lt = r->shade == render_shade_light ? r->lt : NULL;
    return lightmap_build(&r->lm, r->a, r->s, cell, max_bytes, r->shade, r->user, &lp, &r->err);
}

plx_status render_lightmap_build_ind(render *r, double cell, size_t max_bytes, lightmap_ind_fn ind, void *user,
                                     render_par_fn par, void *ctx, int workers)
{
    lightmap_par lp;
    if (!r || !ind)
        return PLX_E_INVALID;
    memset(&lp, 0, sizeof lp);
    r->im.built = 0;   /* over the old map's box */
    lp.par = par;
    lp.ctx = ctx;
    lp.workers = workers > RENDER_MAX_WORKERS ? RENDER_MAX_WORKERS : workers;
    lp.lt = r->shade == render_shade_light ? r->lt : NULL;
    return lightmap_build_ind(&r->lm, r->a, r->s, cell, max_bytes, r->shade, r->user, &lp, ind, user, &r->err);
}

plx_status render_lightmap_fill_ind(render *r, lightmap_ind_fn ind, void *const *users, render_par_fn par,
                                    void *ctx, int workers, const lightmap_progress *pg)
{
    lightmap_par lp;
    if (!r)
        return PLX_E_INVALID;
    memset(&lp, 0, sizeof lp);
    if (pg)
        lp.progress = *pg;
    lp.par = par;
    lp.ctx = ctx;
    lp.workers = workers > RENDER_MAX_WORKERS ? RENDER_MAX_WORKERS : workers;
    lp.lt = NULL;
    return lightmap_fill_ind(&r->lm, ind, users, lp.workers, &lp);
}

void render_lightmap_get(const render *r, render_lightmap_info *out)
{
    memset(out, 0, sizeof *out);
    if (!r || !r->lm.built)
        return;
    out->built = 1;
    out->nx = r->lm.nx;
    out->ny = r->lm.ny;
    out->x0 = r->lm.x0;
    out->y0 = r->lm.y0;
    out->cell = r->lm.cell;
    out->bytes = (size_t)r->lm.nx * r->lm.ny * 3 * sizeof(float);
    out->shaded = r->lm.shaded;
    out->rgb = r->lm.rgb;
    out->has_ind = r->lm.has_ind;
    out->ind = r->lm.ind;
}
