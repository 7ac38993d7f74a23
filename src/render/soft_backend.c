/* soft_backend: the visibility pass (every pixel's surface id and depth):
 * the built-in backend over raster.h, bands of rows on the workers, a
 * backend's drawing, and the ground's id where nothing is drawn. */
#include <string.h>

#include "base/plx_assert.h"
#include "render/render_int.h"

#define RENDER_BAND_BYTES ((size_t)8 << 20) /* the band workers' buffers together at most */

static int band_frag(void *user, int32_t x, int32_t y, float depth, const float *attr, float rgba[4])
{
    band *bd = user;
    (void)depth;
    (void)attr;
    (void)rgba;
    bd->r->id[(size_t)y * (size_t)bd->r->w + (size_t)x] = bd->cur_id;
    return 1;
}

static int frag_id(void *user, int32_t x, int32_t y, float depth, const float *attr, float rgba[4])
{
    render *r = user;
    (void)depth;
    (void)attr;
    (void)rgba;
    r->id[(size_t)y * (size_t)r->w + (size_t)x] = r->cur_id;
    return 1;
}

#define GROUND_LANES 16

/* Row j's id where nothing is drawn: the ground's when the row looks
 * below the horizon, else none (sky). The camera's right vector is
 * horizontal (camera_setup: rt[2] = 0), so a pixel's direction has the
 * same height along a row, bit for bit: one camera_pixel_dir a row decides it,
 * as pixel_hit decides it for each pixel. */
static uint32_t row_background(const render *r, int32_t j)
{
    double d[3];
    PLX_ASSERT(r->rt[2] == 0.0);
    camera_pixel_dir(r, 0, j, d);
#ifdef PLX_DEBUG
    {
        int32_t i;
        for (i = 0; i < r->w; i++) {
            double di[3];
            camera_pixel_dir(r, i, j, di);
            PLX_ASSERT((di[2] < 0.0) == (d[2] < 0.0));
        }
    }
#endif
    return d[2] < 0.0 ? MESH_SURF_GROUND : MESH_SURF_NONE;
}

/* Rows y0 .. y1 - 1 of the ids before drawing: none, or with bg_fill
 * each row's background (the ids soft_ground_ids would give the pixels left
 * undrawn). */
static void ids_start(render *r, int32_t y0, int32_t y1)
{
    int32_t y, i, k, w = r->w;
    for (y = y0; y < y1; y++) {
        uint32_t *id = &r->id[(size_t)y * (size_t)w], v = r->bg_fill ? row_background(r, y) : MESH_SURF_NONE;
        if (v == MESH_SURF_NONE) {
            memset(id, 0, (size_t)w * sizeof *id);
            continue;
        }
        for (i = 0; i + GROUND_LANES <= w; i += GROUND_LANES) /* loops of fixed length: GCC vectorises them */
            for (k = 0; k < GROUND_LANES; k++)
                id[i + k] = v;
        for (; i < w; i++)
            id[i] = v;
    }
}

int soft_begin(void *user, int32_t w, int32_t h, int cull_back)
{
    render *r = user;
    raster_target tg;
    memset(&tg, 0, sizeof tg);
    tg.format = RASTER_RGBA8;
    tg.width = w;
    tg.height = h;
    tg.color = NULL;
    tg.depth = r->depth;
    if (raster_init(&r->rc, &tg, NULL) != PLX_OK)
        return -1;
    ids_start(r, 0, h);
    raster_clear_depth(&r->rc, 1.0f);
    raster_set_fragment(&r->rc, frag_id, r, 0);
    raster_set_cull(&r->rc, cull_back ? RASTER_CULL_BACK : RASTER_CULL_NONE);
    return 0;
}

void soft_draw(void *user, const float *clip, uint32_t nv, const mesh_tri *tri, uint32_t ntri,
               uint32_t v_base)
{
    render *r = user;
    uint32_t k;
    raster_prepare_n(&r->rc, clip, nv, r->pv);
    for (k = 0; k < ntri; k++) {
        const mesh_tri *t = &tri[k];
        uint32_t a = t->v[0] - v_base, b = t->v[1] - v_base, c = t->v[2] - v_base;
        if (raster_triangle_id(&r->rc, &r->pv[a], &r->pv[b], &r->pv[c], t->surf, r->id) >= 0)
            continue; /* inside every clip plane: drawn from the prepared vertices */
        r->cur_id = t->surf; /* clipped: the rasteriser's vertices made for it */
        memcpy(r->vbuf[a].pos, clip + 4 * (size_t)a, 4 * sizeof(float));
        memcpy(r->vbuf[b].pos, clip + 4 * (size_t)b, 4 * sizeof(float));
        memcpy(r->vbuf[c].pos, clip + 4 * (size_t)c, 4 * sizeof(float));
        raster_triangle(&r->rc, &r->vbuf[a], &r->vbuf[b], &r->vbuf[c]);
    }
}

int soft_finish(void *user, uint32_t *id, float *depth)
{
    render *r = user;
    size_t px = (size_t)r->w * (size_t)r->h;
    if (id != r->id)
        memcpy(id, r->id, px * sizeof *id);
    if (depth != r->depth)
        memcpy(depth, r->depth, px * sizeof *depth);
    return 0;
}

/* The band workers' buffers (RENDER_BANDS of each), when they take at
 * most RENDER_BAND_BYTES; r->band stays NULL otherwise. */
static size_t band_bytes(const mesh *m)
{
    size_t v = (size_t)m->max_bld_verts + 1, t = (size_t)m->max_bld_tris + 1;
    return sizeof(band) + v * (3 * sizeof(double) + 4 * sizeof(float) + sizeof(raster_vertex) + sizeof(raster_pvert)) +
           t * sizeof(mesh_tri) + 5 * 64;
}

void soft_bands_create(render *r, arena *a)
{
    size_t v = (size_t)r->m->max_bld_verts + 1, t = (size_t)r->m->max_bld_tris + 1;
    arena_mark m = arena_get_mark(a);
    int k;
    r->band = NULL;
    if (band_bytes(r->m) > RENDER_BAND_BYTES / RENDER_BANDS)
        return;
    r->band = arena_calloc(a, PLX_PART_FRAME, RENDER_BANDS, sizeof(band), 64);
    for (k = 0; r->band && k < RENDER_BANDS; k++) {
        band *bd = &r->band[k];
        bd->r = r;
        bd->gxyz = arena_alloc(a, PLX_PART_FRAME, v * 3 * sizeof(double), 64);
        bd->gtri = arena_alloc(a, PLX_PART_FRAME, t * sizeof(mesh_tri), 64);
        bd->clip = arena_alloc(a, PLX_PART_FRAME, v * 4 * sizeof(float), 64);
        bd->vbuf = arena_alloc(a, PLX_PART_FRAME, v * sizeof(raster_vertex), 64);
        bd->pv = arena_alloc(a, PLX_PART_FRAME, v * sizeof(raster_pvert), 64);
        if (!bd->gxyz || !bd->gtri || !bd->clip || !bd->vbuf || !bd->pv) {
            arena_release(a, &m);
            r->band = NULL;
            return;
        }
    }
}

/* to_clip rounded to floats, the rasteriser's vertex positions. */
static void clip_floats(const render *r, const double *X, float v[4])
{
    double c[4];
    to_clip(r, X, c);
    v[0] = (float)c[0];
    v[1] = (float)c[1];
    v[2] = (float)c[2];
    v[3] = (float)c[3];
}

/* One building through band bd: its triangles made, projected and drawn
 * (ids written through raster_triangle_id, or the fragment function). */
static void band_building(band *bd, uint32_t b)
{
    render *r = bd->r;
    const mesh *m = r->m;
    const mesh_bld *mb = &m->bld[b];
    uint32_t k;
    mesh_building(m, b, bd->gxyz, bd->gtri);
    for (k = 0; k < mb->v_count; k++) {
        clip_floats(r, &bd->gxyz[3 * (size_t)k], bd->vbuf[k].pos);
        raster_prepare(&bd->rc, bd->vbuf[k].pos, &bd->pv[k]);
    }
    for (k = 0; k < mb->t_count; k++) {
        const mesh_tri *t = &bd->gtri[k];
        if (raster_triangle_id(&bd->rc, &bd->pv[t->v[0]], &bd->pv[t->v[1]], &bd->pv[t->v[2]], t->surf, r->id) >= 0)
            continue;
        bd->cur_id = t->surf;
        raster_triangle(&bd->rc, &bd->vbuf[t->v[0]], &bd->vbuf[t->v[1]], &bd->vbuf[t->v[2]]);
    }
}

typedef struct bands_job {
    render *r;
    int32_t nb;          /* bands of rows */
    int cull_back;
} bands_job;

/* Band k of rows: cleared, then every drawn building whose rows meet it,
 * in index order (a pixel's triangles in the same order as one thread
 * draws them: the same ids and depths). */
static void band_rows(void *arg, int worker, uint32_t k)
{
    bands_job *jb = arg;
    render *r = jb->r;
    band *bd = &r->band[worker];
    raster_target tg;
    int32_t y0 = (int32_t)((int64_t)r->h * k / jb->nb), y1 = (int32_t)((int64_t)r->h * (k + 1) / jb->nb), y;
    uint32_t b;
    memset(&tg, 0, sizeof tg);
    tg.format = RASTER_RGBA8;
    tg.width = r->w;
    tg.height = r->h;
    tg.depth = r->depth;
    if (y1 <= y0 || raster_init(&bd->rc, &tg, NULL) != PLX_OK)
        return;
    raster_set_fragment(&bd->rc, band_frag, bd, 0);
    raster_set_cull(&bd->rc, jb->cull_back ? RASTER_CULL_BACK : RASTER_CULL_NONE);
    raster_set_scissor(&bd->rc, 0, y0, r->w, y1);
    ids_start(r, y0, y1);
    for (y = y0; y < y1; y++) {
        size_t p0 = (size_t)y * (size_t)r->w, i;
        for (i = 0; i < (size_t)r->w; i++)
            r->depth[p0 + i] = 1.0f;
    }
    for (b = 0; b < r->m->nbld; b++)
        if (r->draw[b] && r->yr[2 * (size_t)b] < y1 && r->yr[2 * (size_t)b + 1] >= y0)
            band_building(bd, b);
}

/* The visibility pass on the workers: the frame cut into bands of rows,
 * RENDER_BANDS_PER_WORKER a worker (rows of sky cost little), each drawn
 * by one worker from the drawn buildings that reach it. */
#define RENDER_BANDS_PER_WORKER 4
void soft_draw_bands(render *r, const render_opts *o, int cull_back, render_stats *st)
{
    bands_job jb;
    uint32_t b;
    int nw = par_workers(o) < RENDER_BANDS ? par_workers(o) : RENDER_BANDS;
    for (b = 0; b < r->m->nbld; b++)
        if (r->draw[b]) {
            st->drawn++;
            st->triangles_drawn += r->m->bld[b].t_count;
        }
    jb.r = r;
    jb.nb = nw * RENDER_BANDS_PER_WORKER < r->h ? nw * RENDER_BANDS_PER_WORKER : r->h;
    jb.cull_back = cull_back;
    if (o->par(o->par_ctx, nw, (uint32_t)jb.nb, band_rows, &jb) != 0) {
        uint32_t k;
        for (k = 0; k < (uint32_t)jb.nb; k++)
            band_rows(&jb, 0, k);
    }
}

void soft_draw_buildings(render *r, const render_backend *be, render_stats *st)
{
    const mesh *m = r->m;
    uint32_t b, k;
    for (b = 0; b < m->nbld; b++) {
        const mesh_bld *mb = &m->bld[b];
        if (!r->draw[b])
            continue;
        st->drawn++;
        st->triangles_drawn += mb->t_count;
        mesh_building(m, b, r->gxyz, r->gtri);
        for (k = 0; k < mb->v_count; k++)
            clip_floats(r, &r->gxyz[3 * (size_t)k], &r->clip[4 * (size_t)k]);
        be->draw(be->user, r->clip, mb->v_count, r->gtri, mb->t_count, 0);
    }
}

/* The ids of GROUND_LANES pixels: the ground's where none (sky). */
static void ground_lanes(uint32_t *restrict id)
{
    int k;
    for (k = 0; k < GROUND_LANES; k++)
        id[k] = id[k] == MESH_SURF_NONE ? MESH_SURF_GROUND : id[k];
}

/* Pixel row j's ground pixels get the ground's id (pixel_hit writes it;
 * each pixel on its own), when the row looks below the horizon
 * (row_background). */
static void ground_row(render *r, int32_t j)
{
    uint32_t *id = &r->id[(size_t)j * (size_t)r->w];
    int32_t i;
    if (row_background(r, j) != MESH_SURF_GROUND)
        return;
    for (i = 0; i + GROUND_LANES <= r->w; i += GROUND_LANES) /* a loop of fixed length: GCC vectorises it */
        ground_lanes(id + i);
    for (; i < r->w; i++)
        id[i] = id[i] == MESH_SURF_NONE ? MESH_SURF_GROUND : id[i];
}

/* Rows k RENDER_TILE .. of the frame (render_job_fn; arg the render). */
static void ground_rows(void *arg, int worker, uint32_t k)
{
    render *r = arg;
    int32_t j, j1 = ((int32_t)k + 1) * RENDER_TILE < r->h ? ((int32_t)k + 1) * RENDER_TILE : r->h;
    (void)worker;
    for (j = (int32_t)k * RENDER_TILE; j < j1; j++)
        ground_row(r, j);
}

/* Every row's ground pixels, rows on the workers (each row on its own);
 * nothing to do when the rows started at their background (bg_fill). */
void soft_ground_ids(render *r, const render_opts *o)
{
    if (r->bg_fill)
        return;
    run_jobs(o, (uint32_t)((r->h + RENDER_TILE - 1) / RENDER_TILE), ground_rows, r);
}
