/* render: night images on the CPU (see render.h): the render object, the
 * frame driver and the light map's builds; the passes in the files
 * render_int.h names. */
#include <string.h>

#include "render/render.h"
#include "light/illuminance.h"
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

/* The longer side of max_w x max_h: a frame of either orientation is
 * drawn (render_frame_fits), so the buffers of a row or a column of the
 * frame take this many. The buffers of the whole frame (pixels, tiles,
 * corners) are the same for both. */
static int32_t long_side(int32_t max_w, int32_t max_h)
{
    return max_w > max_h ? max_w : max_h;
}

/* Entries of the sparse indirect light's buffers (render.corner_cap,
 * crow_cap, stop_cap) for frames up to max_w x max_h either way round. */
static size_t corner_entries(int32_t max_w, int32_t max_h)
{
    return (size_t)(max_w / IND_STEP + 2) * (size_t)(max_h / IND_STEP + 2);
}

static size_t crow_entries(int32_t max_w, int32_t max_h)
{
    return 2 * (size_t)(long_side(max_w, max_h) / IND_STEP + 2);
}

static size_t stop_entries(int32_t max_w, int32_t max_h)
{
    return stop_rows(long_side(max_w, max_h));
}

int render_frame_fits(int32_t w, int32_t h, int32_t max_w, int32_t max_h)
{
    return w >= 1 && h >= 1 && ((w <= max_w && h <= max_h) || (w <= max_h && h <= max_w));
}

size_t render_bytes(const scene *s, int32_t max_w, int32_t max_h)
{
    size_t px = (size_t)max_w * (size_t)max_h;
    size_t tiles = (size_t)((max_w + RENDER_TILE - 1) / RENDER_TILE) * (size_t)((max_h + RENDER_TILE - 1) / RENDER_TILE);
    size_t corners = corner_entries(max_w, max_h);
    return px * 20 + tiles + (size_t)s->nbld * (2 * sizeof(cull_item) + 29) +
           (size_t)CULL_SIDE * CULL_SIDE * (6 * sizeof(double) + 4 + sizeof(cull_item)) + RENDER_BINS * 8 +
           (size_t)(CULL_SIDE / CULL_GROUP + 1) * (CULL_SIDE / CULL_GROUP + 1) * (6 * sizeof(double) + 1) + 16 +
           sizeof(tonemap_table) + 8 + sizeof(exposure_table) + 8 +
           corners * (1 + 3 * sizeof(float)) + crow_entries(max_w, max_h) * sizeof(corner_hit) + render_surf_slots(s, max_w, max_h) * (sizeof(uint32_t) + sizeof(mesh_surf)) +
           stop_entries(max_w, max_h) * sizeof(int32_t) + arena_mul((size_t)s->nlamps + 1, sizeof(uint32_t)) + 64 +
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
    r->corner_cap = corner_entries(max_w, max_h);
    r->crow_cap = crow_entries(max_w, max_h);
    r->stop_cap = stop_entries(max_w, max_h);
    r->blk = arena_alloc(a, PLX_PART_FRAME, r->corner_cap, R_ALIGN);
    r->ind = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->corner_cap, 3 * sizeof(float)), R_ALIGN);
    r->crow = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->crow_cap, sizeof(corner_hit)), R_ALIGN);
    r->stop = arena_alloc(a, PLX_PART_FRAME, arena_mul(r->stop_cap, sizeof(int32_t)), R_ALIGN);
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
    memset(r->blk, 0, r->corner_cap);
    memset(r->ind, 0, r->corner_cap * 3 * sizeof *r->ind);
    memset(r->crow, 0, r->crow_cap * sizeof *r->crow);
    memset(r->stop, 0, r->stop_cap * sizeof *r->stop);
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

/* ---- the frame -------------------------------------------------------------- */

int render_eye_inside(const render *r, const double eye[3])
{
    const scene *s = r->s;
    uint32_t b, k;
    vec2 p;
    if (eye[2] > s->height_max) /* above every building (the loader's maximum): in none */
        return 0;
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
    pixel_surf_cache_fill(r);
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
    if (o->auto_exposure == RENDER_EXPOSURE_FIXED || o->auto_exposure == RENDER_EXPOSURE_TONE)
        st.exposure = o->exposure;
    else
        st.exposure = o->atlas ? exposure_sum(r) : exposure_par(r, o);
    if (o->auto_exposure == RENDER_EXPOSURE_ADAPT) /* no lit surface counted: nothing to move to */
        st.exposure = fmin(exposure_counted(r->hist[0]) ? exposure_hold(o->exposure, st.exposure, o->exposure_step)
                                                        : o->exposure,
                           EXPOSURE_MAX);
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
