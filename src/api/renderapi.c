/* renderapi: the public face of the renderer (SPEC §5). */
#include <string.h>

#include "base/engine.h"
#include "base/strbuf.h"
#include "light/illuminance.h"
#include "light/litregion.h"
#include "render/render.h"
#include "render/render_aa.h"
#include "render/mesh.h"
#include "photon/indirect.h"
#include "photon/trace.h"
#include "photon/photon.h"
#include "photon/irradiance_cache.h"
#include "render/atlas.h"
#include "render/atlas_fill.h"
#include "render/atlas_frame.h"

#define AA_LEVEL 2  /* adaptive anti-aliasing: a step of more than this in the 8-bit image is an edge */
#define LIGHTMAP_MAX_BYTES ((size_t)48 << 20) /* plx_config.lightmap_bytes 0: at most this */

void plx_render_opts_default(plx_render_opts *o)
{
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->exposure = 1.0;
}

/* Whether images read the irradiance cache (shade_indirect) rather than
 * the photon buffers (plx_indirect_set_gather 0). */
static int icache_on(const plx_engine *e)
{
    return e->ic && e->lt && !(e->gather_set && e->gather_side == 0);
}

/* The photon hook of the renderer: the RGB indirect term (each lamp's light
 * weighted by its colour; SPEC §5) from the irradiance cache (final
 * gathers at sparse points of each surface, irradiance_cache.h), or the
 * photon buffers alone when gathering is off (plx_indirect_set_gather 0). */
static void shade_indirect(void *user, const double P[3], const double n[3], double rgb[3])
{
    plx_engine *e = user;
    if (icache_on(e))
        icache_lookup(e->ic, e->ph, e->lt, P, n, rgb);
    else
        eng_indirect_photons_rgb(e, P, n, rgb);
}

/* shade_indirect's value when it needs no gather (the cache's records
 * all there): changes nothing, so the workers may ask it at once; 0 when
 * only shade_indirect can say. */
static int shade_indirect_try(void *user, int worker, const double P[3], const double n[3], double rgb[3])
{
    plx_engine *e = user;
    if (icache_on(e))
        return icache_peek(e->ic, e->ph, worker, P, n, rgb);
    eng_indirect_photons_rgb(e, P, n, rgb);
    return 1;
}

/* The photon buffers alone: what the aerial indirect map is built from
 * (they do not depend on the eye, and are only read: safe on workers). */
static void shade_photons(void *user, const double P[3], const double n[3], double rgb[3])
{
    eng_indirect_photons_rgb(user, P, n, rgb);
}

/* shade_photons with the pixel's surface known: on a wall, the wall's own
 * facade chart at P, without the probe ray that finds the wall from P
 * (photon_indirect_hit; the same wall but where the probe would meet
 * another: a corner, a wall shared by two buildings). */
static void shade_photons_surf(void *user, uint32_t sid, uint32_t bld, const double P[3], const double n[3],
                               double rgb[3])
{
    plx_engine *e = user;
    const scene *s = e->sc;
    trace_hit h;
    double v[PHOTON_CH];
    if (!e->ph || plx_indirect_frames(e) == 0 || sid < mesh_wall_id(s, 0) || sid >= mesh_roof_id(s, 0) ||
        bld >= s->nbld) {
        shade_photons(user, P, n, rgb);
        return;
    }
    memset(&h, 0, sizeof h);
    h.kind = TRACE_WALL;
    h.bld = bld;
    h.edge = sid - mesh_wall_id(s, 0);
    memcpy(h.p, P, sizeof h.p);
    memcpy(h.n, n, sizeof h.n);
    photon_indirect_hit(e->ph, &h, v);
    rgb[0] = v[1];
    rgb[1] = v[2];
    rgb[2] = v[3];
}

/* The indirect ground map's surface height (the photon tracer's topmost
 * roof over the point, or 0: what the aerial chart is taken on). */
static double top_height(void *user, double x, double y)
{
    plx_engine *e = user;
    return e->ph ? trace_top(e->ph->T, x, y, NULL) : 0.0;
}

/* The port's parallel-for and the number of workers for a frame
 * (plx_config.threads; 0: the port's cores). */
static void set_workers(const plx_engine *e, render_opts *ro)
{
    int n = e->cfg.threads;
    if (!e->port.parallel_for)
        return;
    if (n <= 0)
        n = e->port.cores ? e->port.cores(e->port.ctx) : 1;
    ro->par = e->port.parallel_for;
    ro->par_ctx = e->port.ctx;
    ro->workers = n < 1 ? 1 : n > PLX_MAX_THREADS ? PLX_MAX_THREADS : n;
}

plx_status eng_need_render(plx_engine *e)
{
    return eng_need(e, ENG_RENDER, "plx_render");
}

/* A shader giving no light: the bake's twin engine builds its light map
 * with it (same memory layout, none of the work; src/api/bake.c). */
static void shade_none(void *user, const double P[3], const double n[3], double rgb[3])
{
    (void)user;
    (void)P;
    (void)n;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
}

/* What one worker filling the aerial map's indirect layer reads through:
 * an irradiance cache and a light object of its own (both fill as they
 * are read), the engine's photon buffers and tracer (only read). */
typedef struct layer_worker {
    plx_engine *e;
    icache *ic;
    light *lt;
    arena mem;   /* the worker's own (workers > 0): its light computes regions in its scratch */
} layer_worker;

/* Bytes of a worker's arena: its light object (grids and a region cache
 * like the engine's), its cache's table, and scratch for computing a
 * region as large as the cache holds (litregion.c writes its output into
 * the free room, then keeps what fits the cache). */
static size_t layer_worker_bytes(const plx_engine *e)
{
    return light_base_bytes(e->sc) + 2 * e->lt->pool_cap + icache_bytes(e->ic->nrec) + ((size_t)8 << 20);
}

/* Worker k's arena, cache and light object, from the engine's block. */
static int layer_worker_new(plx_engine *e, layer_worker *w)
{
    size_t bytes = layer_worker_bytes(e);
    void *mem = arena_alloc(&e->mem, PLX_PART_LIT, bytes, 64);
    w->e = e;
    if (!mem)
        return -1;
    arena_init(&w->mem, mem, bytes);
    if (icache_create(&w->mem, e->ic->nrec, &w->ic) != PLX_OK || light_create(&w->mem, e->sc, e->lt->pool_cap, &w->lt) != PLX_OK)
        return -1;
    return 0;
}

/* The aerial light map's indirect layer (render_lightmap_fill_ind): the
 * irradiance cache at the topmost surface over (x, y), ground or roof, on
 * its ICACHE_AERIAL grid (records 4 m apart, none across a wall or a roof
 * edge: irradiance_cache.h). A record's value does not depend on which
 * cache gathers it, so the layer is the same for any number of workers. */
static int lightmap_indirect(void *user, double x, double y, double rgb[3], double *z)
{
    layer_worker *w = user;
    *z = icache_lookup_top(w->ic, w->e->ph, w->lt, x, y, rgb);
    return 1;
}

/* Whether the aerial map's indirect layer is filled: images gather over
 * traced photons. */
static int layer_on(const plx_engine *e)
{
    return icache_on(e) && e->ph && plx_indirect_frames(e) > 0;
}

/* Whether the aerial light map carries its indirect layer. */
static int aerial_layer(const plx_engine *e)
{
    render_lightmap_info li;
    if (e->lightmap_cell == 0.0 || !e->rd)
        return 0;
    render_lightmap_get(e->rd, &li);
    return li.has_ind;
}

/* The light map's budget when plx_config.lightmap_bytes is 0: half the
 * block's free bytes when it is built, at most LIGHTMAP_MAX_BYTES (its
 * texel grows until it fits, render_lightmap_build: 12 bytes a texel, 28
 * with the indirect layer). */
static size_t default_lightmap(const plx_engine *e)
{
    size_t half = arena_free_bytes(&e->mem) / 2, least = e->ic ? 28 : 12;
    return half < least ? least : half < LIGHTMAP_MAX_BYTES ? half : LIGHTMAP_MAX_BYTES;
}

plx_status eng_need_lightmap(plx_engine *e, double m_per_texel, int dark)
{
    double cell = m_per_texel > 0 ? m_per_texel : 1.0;
    size_t bytes;
    plx_status st = eng_need_render(e);
    if (st != PLX_OK)
        return st;
    bytes = e->cfg.lightmap_bytes ? e->cfg.lightmap_bytes : default_lightmap(e);
    if (dark)
        render_code_bind(e->rd, shade_none);
    {
        render_opts ro;
        render_opts_default(&ro);
        ro.workers = 1;
        set_workers(e, &ro);
        if (e->ic) /* the layer's memory in every engine with a cache (a bake's twin too) */
            st = render_lightmap_build_ind(e->rd, cell, bytes, lightmap_indirect, NULL, ro.par, ro.par_ctx,
                                           ro.workers);
        else
            st = render_lightmap_build_par(e->rd, cell, bytes, ro.par, ro.par_ctx, ro.workers);
    }
    if (dark)
        render_code_bind(e->rd, render_shade_light);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "building the aerial light map");
    if (st != PLX_OK)
        return eng_fail(e, st, render_error(e->rd));
    e->lightmap_cell = cell;
    return PLX_OK;
}

/* The light map's indirect layer gathered now when images gather over
 * traced photons and the map was built without it (before the photons:
 * plx_bake_prepare, or a first aerial frame before plx_indirect_step).
 * Only the layer: the direct part stays. On the port's workers, each with
 * a cache and a light object of its own taken from the block for the
 * while (the first worker uses the engine's); as many as fit. */
void eng_lightmap_layer(plx_engine *e)
{
    layer_worker w[RENDER_MAX_WORKERS];
    void *users[RENDER_MAX_WORKERS];
    lightmap_progress pg;
    render_opts ro;
    arena_mark m;
    plx_status st;
    int n, k;
    if (e->lightmap_cell == 0.0 || !e->ic || !layer_on(e) || aerial_layer(e))
        return;
    render_opts_default(&ro);
    ro.workers = 1;
    set_workers(e, &ro);
    n = ro.workers > RENDER_MAX_WORKERS ? RENDER_MAX_WORKERS : ro.workers;
    m = arena_get_mark(&e->mem);
    w[0].e = e;
    w[0].ic = e->ic;
    w[0].lt = e->lt;
    for (k = 1; k < n; k++)
        if (layer_worker_new(e, &w[k]) != 0)
            break;
    n = k;
    e->layer_workers = n;
    for (k = 0; k < n; k++) {
        icache_set_spacing(w[k].ic, ICACHE_AERIAL);
        users[k] = &w[k];
    }
    pg.fn = e->port.progress;
    pg.ctx = e->port.ctx;
    st = render_lightmap_fill_ind(e->rd, lightmap_indirect, users, ro.par, ro.par_ctx, n, &pg);
    for (k = 1; k < n; k++) {
        e->ic->gathered += w[k].ic->gathered;
        e->ic->direct += w[k].ic->direct;
    }
    icache_set_spacing(e->ic, 0.0);
    arena_release(&e->mem, &m);
    if (st != PLX_OK)
        e->lightmap_cell = 0.0; /* no layer memory: the next aerial frame builds the map whole */
}

/* ---- the radiance atlas (render/atlas.h): frames with indirect light ---------- */

/* Whether a frame reads the atlas: indirect light asked for and traced. */
static int atlas_frames(const plx_engine *e, const plx_render_opts *o)
{
    return !o->no_indirect && !o->per_pixel && e->ph && plx_indirect_frames(e) > 0;
}

/* The atlas's indirect light at a vertex: the photon buffers (a wall's
 * own facade chart), read only, so on any worker. */
static void atlas_ind(void *user, const atlas_chart *c, uint32_t sid, const double P[3], const double n[3],
                      double rgb[3])
{
    if (c->kind == ATLAS_WALL)
        shade_photons_surf(user, sid, c->bld, P, n, rgb);
    else
        shade_photons(user, P, n, rgb);
}

/* The atlas's budget: plx_config.lightmap_bytes, else a quarter of the
 * block, at most PLX_ATLAS_MAX_BYTES: from the block, not from what is free
 * when it is made, so that a bake (which makes it before the photons)
 * and an engine that makes it at its first frame lay it out alike. */
static size_t atlas_budget(const plx_engine *e)
{
    size_t quarter = e->mem.cap / 4;
    if (e->cfg.lightmap_bytes)
        return e->cfg.lightmap_bytes;
    return quarter < PLX_ATLAS_MAX_BYTES ? quarter : PLX_ATLAS_MAX_BYTES;
}

plx_status eng_need_atlas(plx_engine *e, double fine)
{
    arena_mark m;
    double f;
    uint64_t ntex = 0;
    plx_status st;
    if (e->atlas)
        return PLX_OK;
    if ((st = eng_need_render(e)) != PLX_OK)
        return st;
    f = atlas_spacing_for(&e->mem, e->sc, render_mesh(e->rd), fine, atlas_budget(e), &ntex);
    if (f == 0.0) {
        char why[120]; /* the coarsest tried: ATLAS_COARSEST, or the spacing asked when coarser */
        strbuf b;
        sb_init(&b, why, sizeof why);
        sb_str(&b, "laying out the radiance atlas (even ");
        sb_num(&b, fine > ATLAS_COARSEST ? fine : ATLAS_COARSEST, 6);
        sb_str(&b, " m between its points does not fit)");
        return eng_nomem(e, why);
    }
    m = arena_get_mark(&e->mem);
    st = ntex == UINT64_MAX ? atlas_create(&e->mem, e->sc, render_mesh(e->rd), f, &e->atlas)
                            : atlas_create_counted(&e->mem, e->sc, render_mesh(e->rd), f, ntex, &e->atlas);
    e->atlas_cache = st == PLX_OK ? arena_calloc(&e->mem, PLX_PART_FRAME, PLX_MAX_THREADS, sizeof(atlas_cache), 64)
                                  : NULL;
    e->atlas_list = e->atlas_cache ? arena_calloc(&e->mem, PLX_PART_FRAME, ENG_ATLAS_LIST, sizeof(uint32_t), 64) : NULL;
    e->atlas_rec = e->atlas_list ? arena_calloc(&e->mem, PLX_PART_FRAME, atlas_fill_records(e->atlas), sizeof(double), 64)
                                 : NULL;
    if (!e->atlas_rec) {
        arena_release(&e->mem, &m);
        e->atlas = NULL;
        e->atlas_cache = NULL;
        e->atlas_list = NULL;
        return eng_nomem(e, "making the radiance atlas");
    }
    atlas_clear(e->atlas, e->indirect_gen);
    return PLX_OK;
}

plx_status plx_render_max_get(plx_engine *e, int32_t *w, int32_t *h)
{
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (!w || !h)
        return eng_fail(e, PLX_E_INVALID, "plx_render_max_get: w or h is NULL");
    eng_render_max(e, w, h);
    return PLX_OK;
}

plx_status plx_atlas_info_get(plx_engine *e, plx_atlas_info *out)
{
    const atlas *A;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_atlas_info_get: out is NULL");
    memset(out, 0, sizeof *out);
    if (!(A = e->atlas))
        return PLX_OK;
    out->made = 1;
    out->spacing = A->fine;
    out->coarse = A->coarse;
    out->points = A->ntex;
    out->points_fine = A->ntex_fine;
    out->bytes = A->bytes;
    out->unfilled = A->todo;
    out->indirect = A->with_ind;
    return PLX_OK;
}

/* Worker 0 of a fill: the engine's light object, the records buffer
 * taken with the atlas (a frame's fill needs no memory). */
static void atlas_worker0(plx_engine *e, atlas_worker *w)
{
    w->lt = e->lt;
    w->ind = e->ph && plx_indirect_frames(e) > 0 ? atlas_ind : NULL;
    w->ind_user = e;
    w->rec = e->atlas_rec;
}

/* A further worker: a light object of its own (it fills its region cache
 * as it reads) in an arena taken from the block for the while. */
static int atlas_worker_new(plx_engine *e, atlas_worker *w, arena *mem)
{
    size_t bytes = light_base_bytes(e->sc) + 2 * e->lt->pool_cap + ((size_t)8 << 20) +
                   atlas_fill_records(e->atlas) * sizeof(double) + 64;
    void *blk = arena_alloc(&e->mem, PLX_PART_LIT, bytes, 64);
    if (!blk)
        return -1;
    arena_init(mem, blk, bytes);
    memset(w, 0, sizeof *w);
    if (light_create(mem, e->sc, e->lt->pool_cap, &w->lt) != PLX_OK)
        return -1;
    w->ind = e->ph && plx_indirect_frames(e) > 0 ? atlas_ind : NULL;
    w->ind_user = e;
    w->rec = arena_alloc(mem, PLX_PART_LIT, arena_mul(atlas_fill_records(e->atlas), sizeof(double)), 8);
    return w->rec ? 0 : -1;
}

/* The atlas made current: cleared when the light changed since it was
 * filled (a new key). */
static void atlas_current(plx_engine *e)
{
    if (e->atlas->key != e->indirect_gen)
        atlas_clear(e->atlas, e->indirect_gen);
}

plx_status eng_atlas_fill_all(plx_engine *e)
{
    atlas_worker w[PLX_MAX_THREADS];
    arena wm[PLX_MAX_THREADS];
    atlas_par par;
    render_opts ro;
    arena_mark m;
    plx_status st;
    int n, k;
    if ((st = eng_need(e, ENG_LIGHT, "filling the radiance atlas")) != PLX_OK ||
        (st = eng_need_atlas(e, e->atlas_fine)) != PLX_OK)
        return st;
    atlas_current(e);
    if (e->atlas->todo == 0)
        return PLX_OK;
    render_opts_default(&ro);
    ro.workers = 1;
    set_workers(e, &ro);
    m = arena_get_mark(&e->mem);
    atlas_worker0(e, &w[0]);
    for (n = 1; n < ro.workers && n < PLX_MAX_THREADS; n++)
        if (atlas_worker_new(e, &w[n], &wm[n]) != 0)
            break;
    par.par = ro.par;
    par.ctx = ro.par_ctx;
    par.progress.fn = e->port.progress;
    par.progress.ctx = e->port.ctx;
    st = atlas_fill(e->atlas, w, n, &par);
    for (k = 1; k < n; k++)
        e->lt->st.computed += w[k].lt->st.computed;
    arena_release(&e->mem, &m);
    return st;
}

/* render_opts.atlas_need: what rows j0 .. j1 - 1 read and is not filled yet,
 * filled on this thread (the engine's light object), round after round
 * of at most ENG_ATLAS_LIST items. */
static int atlas_need(void *user, const atlas_view *v, const uint32_t *ids, const uint8_t *mask, int32_t j0,
                      int32_t j1)
{
    plx_engine *e = user;
    atlas_worker w;
    uint32_t n;
    if (e->atlas->todo == 0) /* made current by plx_render before the frame */
        return 0;
    atlas_worker0(e, &w);
    while ((n = atlas_frame_missing(e->atlas, v, ids, mask, j0, j1, e->atlas_list, ENG_ATLAS_LIST)) > 0)
        if (atlas_fill_items(e->atlas, &w, 1, NULL, e->atlas_list, n) != PLX_OK)
            return -1;
    return 0;
}

/* The adaptive anti-aliasing's buffers (PLX_PART_FRAME, on first need,
 * all three or none): whether they are there. Taken after the first
 * sample's frame, so that what that frame builds (the indirect ground map)
 * comes first; a block with no room for them takes every sample. */
static int aa_adaptive_buffers(plx_engine *e, size_t maxpx)
{
    arena_mark m;
    if (e->aa_mask)
        return 1;
    m = arena_get_mark(&e->mem);
    e->aa_id = arena_alloc(&e->mem, PLX_PART_FRAME, arena_mul(maxpx, sizeof(uint32_t)), 64);
    e->aa_rgb = e->aa_id ? arena_alloc(&e->mem, PLX_PART_FRAME, arena_mul(maxpx, 3), 64) : NULL;
    e->aa_mask = e->aa_rgb ? arena_alloc(&e->mem, PLX_PART_FRAME, maxpx, 64) : NULL;
    if (e->aa_mask)
        return 1;
    arena_release(&e->mem, &m);
    e->aa_id = NULL;
    e->aa_rgb = NULL;
    return 0;
}

/* Anti-aliasing: n x n frames with the sample point moved within the
 * pixel on a regular grid, their linear images averaged (summed in sample
 * order, so the bytes are the same every time), then tone mapped with the
 * exposure of the first sample's frame. The sum lives in PLX_PART_FRAME,
 * taken on first use for the largest frame. Adaptive (not full, and
 * room for its buffers in the block, else every sample): the
 * later samples shade only the pixels render_aa_mask marks (an edge in the
 * first sample's 3 x 3 neighbourhood) and those where they meet another
 * surface; every other pixel keeps the first sample's value for them. The
 * pixels shaded are the same values a full pass gives them (README
 * "Anti-aliasing"). A frame read from the radiance atlas whose mask marks
 * more than half its pixels takes every sample instead (PLX_AA_DENSE):
 * there a pixel costs about its rasterising, which the later samples pay
 * for every pixel anyway, and the mask's bookkeeping costs more than the
 * reads it saves (README "Anti-aliasing"). */
static plx_status render_aa(plx_engine *e, const render_camera *rc, render_opts *ro, int n, int full,
                            uint8_t *rgb8, float *rgbf, render_stats *rs, plx_render_info *info)
{
    size_t px = (size_t)rc->width * (size_t)rc->height, maxpx;
    double ex = 1.0, inv = 1.0 / ((double)n * n);
    plx_status st = PLX_OK;
    uint64_t lookups = 0, later = 0, calls = 0;
    int a, b, curve = ro->auto_exposure, adaptive = 0, marked_sums = 0, far = 1;
    int32_t mw, mh;
    float *sum;
    if (rc->width < 1 || rc->height < 1)
        px = 0;
    eng_render_max(e, &mw, &mh);
    maxpx = (size_t)mw * (size_t)mh;
    if (!e->aa_sum)
        e->aa_sum = arena_alloc(&e->mem, PLX_PART_FRAME, arena_mul(maxpx, 3 * sizeof(float)), 64);
    if (!e->aa_sum)
        return PLX_E_NOMEM;
    sum = e->aa_sum;
    for (b = 0; b < n && st == PLX_OK; b++)
        for (a = 0; a < n && st == PLX_OK; a++) {
            const float *lin;
            ro->shift[0] = (a + 0.5) / n - 0.5;
            ro->shift[1] = (b + 0.5) / n - 0.5;
            /* one culling for all the sample points: made by the first */
            ro->cull_samples = n < 2 ? 0 : a == 0 && b == 0 ? RENDER_SAMPLE_FIRST : RENDER_SAMPLE_LATER;
            st = render_frame(e->rd, rc, ro, NULL, NULL, rs);
            if (st != PLX_OK)
                break;
            lookups += rs->indirect_calls;
            calls += rs->shader_calls;
            lin = render_linear(e->rd);
            if (a == 0 && b == 0) {
                ex = rs->exposure;
                /* the later samples: the first one's exposure */
                ro->auto_exposure = 0;
                adaptive = !full && aa_adaptive_buffers(e, maxpx) ? PLX_AA_ADAPTIVE : PLX_AA_EVERY;
                if (adaptive && px > 0) {
                    /* the first sample's bytes into the caller's image, where
                     * the pixels that keep them stay (render_tonemap_kept) */
                    uint8_t *first = rgb8 ? rgb8 : e->aa_rgb;
                    size_t marked = render_aa_mask(e->rd, ro, ex, curve, AA_LEVEL, first, e->aa_rgb, e->aa_id,
                                                   e->aa_mask, &far);
                    if (ro->atlas && marked > px / 2) {
                        adaptive = PLX_AA_DENSE;
                    } else {
                        ro->mask = e->aa_mask;
                        ro->mask_id = e->aa_id;
                        /* 2 x 2 into bytes: the sums at the marked pixels only */
                        marked_sums = n == 2 && rgb8 != NULL;
                        ro->mask_new = marked_sums ? 2 : 1;
                    }
                }
                if (marked_sums) /* the first sample stays where it was drawn, as the sums' start; the later
                                  * ones write only the marked pixels, into the sums' buffer lent */
                    sum = render_swap_linear(e->rd, e->aa_sum);
                else
                    render_aa_copy(ro, sum, lin, 3 * px);
            } else {
                if (marked_sums)
                    render_aa_add_marked(ro, sum, lin, e->aa_mask, px, b * n + a - 1);
                else
                    render_aa_add(ro, sum, lin, 3 * px);
                later += rs->sky_pixels + rs->ground_pixels + rs->building_pixels;
            }
        }
    ro->auto_exposure = curve;
    ro->mask = NULL;
    ro->mask_id = NULL;
    ro->mask_new = 0;
    ro->cull_samples = 0;
    if (sum != e->aa_sum) /* the renderer's own buffer back, holding the sums */
        (void)render_swap_linear(e->rd, sum);
    if (st != PLX_OK)
        return st;
    if (marked_sums) {
        /* the first sample's bytes stay where no later sample shaded */
        render_tonemap_kept(e->rd, sum, e->aa_mask, px, far, ex, curve, rgb8, ro);
        if (rgbf)
            memcpy(rgbf, sum, px * 3 * sizeof(float));
    } else {
        render_aa_scale(ro, sum, 3 * px, inv);
        if (rgbf)
            memcpy(rgbf, sum, px * 3 * sizeof(float));
        if (rgb8)
            (void)render_tonemap_par(e->rd, sum, px, ex, curve, rgb8, ro);
    }
    rs->exposure = ex;
    rs->indirect_calls = lookups;
    rs->shader_calls = calls;
    if (info) {
        info->aa_later = later;
        info->aa_adaptive = adaptive;
    }
    return PLX_OK;
}

/* PLX_E_INVALID, saying the sizes, when the camera's frame is empty or
 * larger than the engine's renderer draws. */
static plx_status frame_fits(plx_engine *e, const plx_camera *cam)
{
    int32_t w, h;
    strbuf b;
    eng_render_max(e, &w, &h);
    if (render_frame_fits(cam->width, cam->height, w, h))
        return PLX_OK;
    sb_init(&b, e->err, sizeof e->err);
    sb_str(&b, "plx_render: a ");
    sb_int(&b, cam->width);
    sb_str(&b, "x");
    sb_int(&b, cam->height);
    sb_str(&b, " frame is outside 1x1 .. ");
    sb_int(&b, w);
    sb_str(&b, "x");
    sb_int(&b, h);
    if (w != h) {
        sb_str(&b, " (or ");
        sb_int(&b, h);
        sb_str(&b, "x");
        sb_int(&b, w);
        sb_str(&b, ")");
    }
    sb_str(&b, ", the largest this engine draws (plx_config.render_max_width/height; a bake's --max-size)");
    return PLX_E_INVALID;
}

/* PLX_E_INVALID, saying what and the values, for a camera the renderer
 * cannot take (it said "render_frame: ..." without them). */
static plx_status camera_ok(plx_engine *e, const plx_camera *cam)
{
    strbuf b;
    int k;
    for (k = 0; k < 3; k++)
        if (!isfinite(cam->eye[k]) || !isfinite(cam->target[k]))
            return eng_fail(e, PLX_E_INVALID, "plx_render: the camera's eye or target is not finite");
    sb_init(&b, e->err, sizeof e->err);
    if (!(cam->fov_deg > 0.0 && cam->fov_deg < 180.0)) {
        sb_str(&b, "plx_render: fov_deg ");
        sb_num(&b, cam->fov_deg, 6);
        sb_str(&b, " is outside (0, 180) degrees");
        return PLX_E_INVALID;
    }
    if (!(cam->eye[2] > 0.0)) {
        sb_str(&b, "plx_render: the eye is at z = ");
        sb_num(&b, cam->eye[2], 6);
        sb_str(&b, " m, not above the ground (z > 0)");
        return PLX_E_INVALID;
    }
    if (cam->eye[0] == cam->target[0] && cam->eye[1] == cam->target[1] && cam->eye[2] == cam->target[2]) {
        sb_str(&b, "plx_render: the eye and the target are the same point (");
        for (k = 0; k < 3; k++) {
            sb_num(&b, cam->eye[k], 9);
            sb_str(&b, k < 2 ? ", " : "): the camera looks nowhere");
        }
        return PLX_E_INVALID;
    }
    return PLX_OK;
}

plx_status plx_render(plx_engine *e, const plx_camera *cam, const plx_render_opts *o, uint8_t *rgb8,
                      float *rgbf, plx_render_info *info)
{
    render_camera rc;
    render_opts ro;
    render_stats rs;
    plx_render_opts def;
    plx_status st;
    int use_atlas, inside;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (!e->sc)
        return eng_fail(e, PLX_E_NOSCENE, "plx_render: no scene is loaded");
    if (!cam)
        return eng_fail(e, PLX_E_INVALID, "plx_render: camera is NULL");
    if (o && (o->aa < 0 || o->aa > PLX_RENDER_MAX_AA))
        return eng_fail(e, PLX_E_INVALID, "plx_render: aa must be 0..16 (samples per pixel side)");
    /* a fixed exposure of 0 or less gave a black (or negative) frame; NaN
     * and inf were refused deeper, as "near must be > 0" */
    if (o && eng_texel_check(e, "plx_render", o->aerial_m_per_texel) != PLX_OK)
        return PLX_E_INVALID;
    if (o && (o->exposure_step < 0 || o->exposure_step > PLX_EXPOSURE_STEP_MAX))
        return eng_fail(e, PLX_E_INVALID, "plx_render: exposure_step must be 0 .. 4096 (eighths of a stop)");
    if (o && (o->auto_exposure < PLX_EXPOSURE_FIXED || o->auto_exposure > PLX_EXPOSURE_TONE))
        return eng_fail(e, PLX_E_INVALID, "plx_render: auto_exposure must be PLX_EXPOSURE_FIXED, _AUTO, _ADAPT or _TONE");
    if (o && o->auto_exposure != PLX_EXPOSURE_AUTO && !(o->exposure > 0.0 && isfinite(o->exposure)))
        return eng_fail(e, PLX_E_INVALID, "plx_render: exposure must be a finite number above 0 (or auto_exposure)");
    if (!o) {
        plx_render_opts_default(&def);
        o = &def;
    }
    st = eng_need(e, ENG_RENDER, "plx_render");
    if (st != PLX_OK)
        return st;
    if ((st = frame_fits(e, cam)) != PLX_OK || (st = camera_ok(e, cam)) != PLX_OK)
        return st;
    inside = render_eye_inside(e->rd, cam->eye);
    use_atlas = atlas_frames(e, o) && !e->atlas_off && !inside;
    if (use_atlas && (st = eng_need_atlas(e, e->atlas_fine > 0.0 ? e->atlas_fine : o->aerial_m_per_texel)) != PLX_OK) {
        if (st != PLX_E_NOMEM)
            return st;
        /* too large for the block: every pixel shaded instead, said once */
        eng_warn(e, "the radiance atlas does not fit in the block (plx_config.lightmap_bytes, --mem, --texel): "
                    "frames with indirect light shade every pixel instead (much slower: seconds a frame "
                    "for an aerial view; no_indirect, --no-indirect, for direct light alone)");
        e->atlas_off = 1;
        use_atlas = 0;
        eng_clear_error(e);
    }
    if (use_atlas) {
        /* from the atlas: no light map, no indirect hook */
    } else if (o->aerial && e->lightmap_cell != 0.0 && !o->no_indirect && e->ic && e->ph && plx_indirect_frames(e) > 0) {
        /* built before the photons: its indirect layer gathered now;
         * gathering switched off since: the map again, without the layer */
        eng_lightmap_layer(e);
        if (aerial_layer(e) && !layer_on(e))
            e->lightmap_cell = 0.0;
    }
    if (o->aerial && e->lightmap_cell == 0.0 && !use_atlas) {
        st = eng_need_lightmap(e, o->aerial_m_per_texel, 0);
        if (st != PLX_OK)
            return st;
        /* the indirect layer only for a frame that reads it: a frame
         * without indirect light does not (shade_tiles.c), and the first
         * one with it gathers the layer above (16 s before a 1024x768
         * frame without indirect light from a gen eixample 30 30 bake) */
        if (!o->no_indirect)
            eng_lightmap_layer(e);
    }
    memcpy(rc.eye, cam->eye, sizeof rc.eye);
    memcpy(rc.target, cam->target, sizeof rc.target);
    rc.fov_deg = cam->fov_deg;
    rc.width = cam->width;
    rc.height = cam->height;
    render_opts_default(&ro);
    ro.exposure = o->auto_exposure == PLX_EXPOSURE_AUTO ? 1.0 : o->exposure; /* not read with _AUTO */
    ro.no_glow = o->no_glow;
    ro.lightmap = o->aerial;
    ro.cull = o->no_cull ? RENDER_CULL_NONE : RENDER_CULL_ALL;
    ro.backend = o->backend;
    ro.auto_exposure = o->auto_exposure;
    ro.exposure_step = o->exposure_step;
    if (use_atlas) {
        atlas_current(e); /* cleared when the light changed: the frames read what is filled */
        ro.lightmap = 0;
        ro.atlas = e->atlas;
        ro.atlas_cache = e->atlas_cache;
        ro.atlas_need = atlas_need;
        ro.atlas_user = e;
    } else if (!o->no_indirect && e->ph && plx_indirect_frames(e) > 0) {
        ro.indirect = shade_indirect;
        ro.indirect_user = e;
        if (e->ic) {
            icache_set_view(e->ic, rc.eye);
            /* from above: the aerial grid for the pixels the map's layer leaves (walls) */
            icache_set_spacing(e->ic, o->aerial ? ICACHE_AERIAL : 0.0);
        }
        /* the photon buffers are only read (indirect.c), so that hook may run
         * on several workers; the irradiance cache fills its table and asks
         * the light object as it reads: one thread */
        ro.indirect_mt = !icache_on(e);
        /* the cache at the corners of 4 x 4 blocks on one surface, each
         * block within one record spacing of the cache at its distance */
        ro.indirect_sparse = icache_on(e);
        ro.indirect_span = ICACHE_KAPPA;
        /* and tried on the workers first: the records already there */
        ro.indirect_try = shade_indirect_try;
        /* aerial ground and roofs: the light map's indirect layer; without one
         * (not gathering) the indirect ground map (render/indmap.h) */
        ro.indirect_map = 1;
        ro.indirect_far = shade_photons;
        ro.indirect_key = e->indirect_gen;
        ro.top = top_height;
        if (o->aerial && aerial_layer(e)) {
            /* from above, the map's layer gives the ground and the roofs;
             * the walls left (seen at a slant, a few pixels each) read the
             * photon buffers: read only, so on every worker, and no
             * gathering while the view moves */
            ro.indirect = shade_photons;
            ro.indirect_surf = shade_photons_surf;
            ro.indirect_mt = 1;
            /* (not sparse, README "Images: an irradiance cache") */
            ro.indirect_sparse = 0;
            ro.indirect_try = NULL;
        }
    }
    set_workers(e, &ro);
    if (info) {
        info->aa_later = 0;
        info->aa_adaptive = PLX_AA_EVERY;
        info->eye_inside = inside;
    }
    if (o->aa > 1)
        st = render_aa(e, &rc, &ro, o->aa, o->aa_full, rgb8, rgbf, &rs, info);
    else
        st = render_frame(e->rd, &rc, &ro, rgb8, rgbf, &rs);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "rendering a frame");
    if (st != PLX_OK)
        return eng_fail(e, st, render_error(e->rd));
    if (info) {
        info->buildings = rs.buildings;
        info->drawn = rs.drawn;
        info->drawn_fraction = rs.drawn_fraction;
        info->shaded_pixels = rs.shader_calls;
        info->exposure = rs.exposure;
        info->indirect_lookups = rs.indirect_calls;
    }
    eng_clear_error(e);
    return PLX_OK;
}
