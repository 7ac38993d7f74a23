/* need: the one place that decides what must be built before a call, and
 * builds it on first need. Every public call that reads something built
 * from the scene asks eng_need(e, WHAT, fn) first:
 *
 *   ENG_SCENE   a scene is loaded (else PLX_E_NOSCENE "fn: no scene is loaded")
 *   ENG_POLAR   the polar diagrams (the visibility result buffers come with
 *               the first visibility query: eng_need_vis_buffers)
 *   ENG_LIGHT   the lamp light object (grids, lit region cache)
 *   ENG_PHOTON  the photon buffers
 *   ENG_RENDER  the renderer, which needs ENG_LIGHT first
 *
 * Each part is kept in the engine until the next load drops them all
 * (loadapi.c); a failed build leaves the engine as it was. */
#include "base/engine.h"
#include "polar/polar.h"
#include "light/light.h"
#include "photon/photon.h"
#include "photon/irradiance_cache.h"
#include "render/render.h"

#define DEFAULT_MAX_W 1920
#define DEFAULT_MAX_H 1080

static plx_status need_polar(plx_engine *e)
{
    uint64_t t0 = eng_clock(e);
    plx_status st;
    polar *pd;
    st = polar_build(&e->mem, e->sc, &pd);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "building the polar diagrams");
    if (st != PLX_OK)
        return eng_fail(e, st, "building the polar diagrams failed (empty or non-finite bounds)");
    e->polar_ns = eng_clock(e) - t0;
    e->pd = pd;
    return PLX_OK;
}

plx_status eng_need_vis_buffers(plx_engine *e)
{
    arena_mark m = arena_get_mark(&e->mem);
    if (e->vis_poly)
        return PLX_OK;
    e->vis_poly_cap = 4 * e->sc->npts + 64;
    e->vis_ids_cap = e->sc->nbld + 1;
    e->vis_poly = arena_alloc(&e->mem, PLX_PART_FRAME, arena_mul(e->vis_poly_cap, sizeof *e->vis_poly), 16);
    e->vis_ids = arena_alloc(&e->mem, PLX_PART_FRAME, arena_mul(e->vis_ids_cap, sizeof *e->vis_ids), 16);
    if (!e->vis_poly || !e->vis_ids) {
        plx_status r = eng_nomem(e, "reserving visibility results");
        arena_release(&e->mem, &m);
        e->vis_poly = NULL;
        e->vis_ids = NULL;
        return r;
    }
    return PLX_OK;
}

/* The lit-region pool when plx_config.lit_cache_bytes is 0: sized from the
 * budget, an eighth of the block's free bytes when light is first needed,
 * at least LIT_CACHE_MIN and at most LIT_CACHE_MAX. A lamp whose region does
 * not fit is answered by the segment path (same light, slower). */
#define LIT_CACHE_MIN ((size_t)256 << 10)
#define LIT_CACHE_MAX ((size_t)16 << 20)

static size_t default_lit_cache(const arena *a)
{
    size_t c = arena_free_bytes(a) / 8;
    return c < LIT_CACHE_MIN ? LIT_CACHE_MIN : c > LIT_CACHE_MAX ? LIT_CACHE_MAX : c;
}

static plx_status need_light(plx_engine *e)
{
    size_t cache = e->cfg.lit_cache_bytes ? e->cfg.lit_cache_bytes : default_lit_cache(&e->mem);
    plx_status st = light_create(&e->mem, e->sc, cache, &e->lt);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "setting up lamp light");
    if (st != PLX_OK)
        return eng_fail(e, st, "setting up lamp light failed");
    return PLX_OK;
}

/* The photon buffers' budget when plx_config.photon_bytes is 0: half the
 * block's free bytes when they are first needed, after setting aside what
 * a frame still needs when it is not built yet: the renderer (its buffers,
 * render_bytes, and its mesh, about MESH_PT bytes a footprint vertex and
 * MESH_BLD a building: 739,178 bytes measured on gen eixample 30 30's
 * 64,800 vertices and 14,400 buildings, 1,065,600 reckoned) and the
 * lamp light's grids. The other half stays for the lit-region cache and a
 * frame's scratch; when even the lowest quality does not fit the half, it
 * may take more of that room (the lit cache is sized from what is left). */
#define MESH_PT 12
#define MESH_BLD 20

/* The free bytes once the renderer and the lamp grids are set aside; when
 * those would take more than half of them (the default 1920x1080 frame
 * alone is 41.5 MB), half the free bytes, as when they do not fit at all
 * (no jump down as the renderer's reckoning shrinks). */
static size_t photon_room(const plx_engine *e)
{
    const scene *s = e->sc;
    size_t free_b = arena_free_bytes(&e->mem), keep = 0;
    if (!e->rd) {
        int32_t w, h;
        eng_render_max(e, &w, &h);
        keep += render_bytes(s, w, h) + (size_t)MESH_PT * s->npts + (size_t)MESH_BLD * s->nbld;
    }
    if (!e->lt)
        keep += light_base_bytes(s);
    return free_b > keep && free_b - keep > free_b / 2 ? free_b - keep : free_b / 2;
}

/* The default quality: final gathering reads the later bounces all around
 * its points, so every block gets a chart (photon.h, coarsest_level). */
static void photon_config_pick(const plx_engine *e, photon_config *cfg)
{
    if (!e->gather_set || e->gather_side > 0)
        photon_config_gather(cfg, e->sc);
    else
        photon_config_default(cfg);
}

static plx_status need_photon(plx_engine *e)
{
    photon_config cfg;
    plx_status st;
    arena_mark m;
    int steps;
    uint32_t nrec;
    size_t icb;
    photon_config_pick(e, &cfg);
    /* full quality: the buffers at their default size, the largest table */
    e->ph_full = photon_bytes(e->sc, &cfg) + icache_bytes(ICACHE_RECORDS);
    e->ph_budget = e->cfg.photon_bytes ? e->cfg.photon_bytes : photon_room(e) / 2;
    /* the images' irradiance cache comes with them, its table sized from
     * the same budget (icache_records_for) */
    nrec = icache_records_for(e->ph_budget);
    icb = icache_bytes(nrec);
    steps = photon_config_fit(&cfg, e->sc, e->ph_budget > icb ? e->ph_budget - icb : 0);
    if (steps < 0 && !e->cfg.photon_bytes &&
        photon_bytes(e->sc, &cfg) + icache_bytes(ICACHE_RECORDS_MIN) <= photon_room(e)) {
        /* the lowest quality, beyond the half; the table keeps its share
         * of the half when that fits too */
        while (nrec > ICACHE_RECORDS_MIN && photon_bytes(e->sc, &cfg) + icache_bytes(nrec) > photon_room(e))
            nrec /= 2;
        icb = icache_bytes(nrec);
        e->ph_budget = photon_bytes(e->sc, &cfg) + icb;
        photon_config_pick(e, &cfg);
        steps = photon_config_fit(&cfg, e->sc, e->ph_budget - icb);
    }
    if (steps < 0) {
        strbuf b;
        sb_init(&b, e->err, sizeof e->err);
        sb_str(&b, "out of memory while creating the photon buffers: ");
        sb_uint(&b, photon_bytes(e->sc, &cfg) + icache_bytes(ICACHE_RECORDS_MIN));
        sb_str(&b, " bytes at their lowest quality, more than their budget of ");
        sb_uint(&b, e->ph_budget);
        sb_str(&b, e->cfg.photon_bytes ? " (plx_config.photon_bytes)" : " (the free memory left after the renderer)");
        return PLX_E_NOMEM;
    }
    e->ph_reductions = (uint32_t)steps;
    m = arena_get_mark(&e->mem);
    st = photon_create(&e->mem, e->sc, &cfg, &e->ph);
    if (st == PLX_OK && (st = icache_create(&e->mem, nrec, &e->ic)) != PLX_OK) {
        arena_release(&e->mem, &m); /* as it was: no photon buffers */
        e->ph = NULL;
    }
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "creating the photon buffers");
    if (st != PLX_OK)
        return eng_fail(e, st, "creating the photon buffers failed");
    return PLX_OK;
}

void eng_render_max(const plx_engine *e, int32_t *w, int32_t *h)
{
    *w = e->cfg.render_max_width ? e->cfg.render_max_width : DEFAULT_MAX_W;
    *h = e->cfg.render_max_height ? e->cfg.render_max_height : DEFAULT_MAX_H;
}

plx_status eng_texel_check(plx_engine *e, const char *fn, double t)
{
    strbuf b;
    char msg[160];
    if (t == 0.0 || (t >= PLX_TEXEL_MIN && t <= PLX_TEXEL_MAX))
        return PLX_OK;
    sb_init(&b, msg, sizeof msg);
    sb_str(&b, fn);
    sb_str(&b, ": aerial_m_per_texel must be 0 (the default) or 0.01 .. 1e4 m");
    return eng_fail(e, PLX_E_INVALID, msg);
}

static plx_status need_render(plx_engine *e)
{
    int32_t w, h;
    plx_status st;
    eng_render_max(e, &w, &h);
    st = render_create(&e->mem, e->sc, w, h, render_shade_light, e->lt, &e->rd);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "creating the renderer (frame buffers and mesh)");
    if (st != PLX_OK)
        return eng_fail(e, st, "creating the renderer failed");
    return PLX_OK;
}

plx_status eng_need(plx_engine *e, eng_what what, const char *fn)
{
    plx_status st = eng_need_scene(e, fn);
    if (st != PLX_OK)
        return st;
    switch (what) {
    case ENG_SCENE:
        return PLX_OK;
    case ENG_POLAR:
        return e->pd ? PLX_OK : need_polar(e);
    case ENG_LIGHT:
        return e->lt ? PLX_OK : need_light(e);
    case ENG_PHOTON:
        return e->ph ? PLX_OK : need_photon(e);
    case ENG_RENDER:
        if (e->rd)
            return PLX_OK;
        st = eng_need(e, ENG_LIGHT, fn);
        return st != PLX_OK ? st : need_render(e);
    }
    return PLX_E_INVALID;
}
