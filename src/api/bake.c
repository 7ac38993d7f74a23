/* bake: everything a viewer needs, saved whole and loaded without rebuilding.
 *
 * A bake is the low end of the engine's arena (the engine object, the scene,
 * polar diagrams, lamp light, photon buffers, renderer and aerial light
 * map) copied byte for byte, with every pointer into the arena written as
 * its offset from the arena's base, plus the list of those words (the
 * relocations). Loading copies the image to the new block and adds the new
 * base to each listed word: no parsing, no rebuilding.
 *
 * Which words are pointers? The engine is built twice, in two blocks at
 * different addresses, with the same inputs (the twin skips the expensive
 * work that allocates nothing: photon frames and the light map's shading).
 * A word is a pointer exactly when it lies in the first engine's arena and
 * the twin's word at the same place is the same address moved by the
 * distance between the blocks; data words (the same in both, or numbers
 * that differ otherwise) never move by exactly that distance. Code
 * addresses (the renderer's shader and backend functions, the port) are
 * cleared before saving and set again after loading: they are the only
 * addresses outside the arena that the structures hold (strings the scene
 * keeps are copied into the arena).
 *
 * File layout (README "Bake files"): a 128-byte header, the image padded to
 * 8 bytes, then nrel 32-bit word indices. Native byte order: the header
 * says which, and a reader on another architecture refuses the file.
 */
#include <string.h>

#include "api/bake_file.h"
#include "base/engine.h"
#include "light/light.h"
#include "light/litregion.h"
#include "photon/photon.h"
#include "photon/irradiance_cache.h"
#include "polar/polar.h"
#include "render/render.h"
#include "render/atlas.h"
#include "render/atlas_frame.h"
#include "render/atlas_fill.h"

/* ---- preparing an engine --------------------------------------------------- */

plx_status plx_bake_prepare(plx_engine *e, const plx_bake_opts *o)
{
    double eye[3];
    plx_status st;
    if ((st = eng_need_scene(e, "plx_bake_prepare")) != PLX_OK)
        return st;
    if (!o)
        return eng_fail(e, PLX_E_INVALID, "plx_bake_prepare: options are NULL");
    if ((st = eng_texel_check(e, "plx_bake_prepare", o->aerial_m_per_texel)) != PLX_OK)
        return st;
    if ((!o->no_polar && (st = plx_polar_build(e)) != PLX_OK) ||
        (st = eng_need(e, ENG_LIGHT, "plx_bake_prepare")) != PLX_OK)
        return st;
    eye[0] = 0.5 * (e->sc->bounds[0] + e->sc->bounds[2]);
    eye[1] = 0.5 * (e->sc->bounds[1] + e->sc->bounds[3]);
    eye[2] = 1.7;
    if (!o->no_indirect && (st = plx_indirect_set_viewer(e, eye, NULL, 360.0)) != PLX_OK)
        return st;
    if ((st = eng_need_render(e)) != PLX_OK)
        return st;
    if (o->aerial && !o->no_indirect) {
        /* frames with indirect light read the radiance atlas: laid out
         * now (the twin alike), filled when saved, after the photons */
        e->atlas_fine = o->aerial_m_per_texel;
        if ((st = eng_need_atlas(e, o->aerial_m_per_texel)) != PLX_OK)
            return st;
    } else if (o->aerial && e->lightmap_cell == 0.0) {
        if ((st = eng_need_lightmap(e, o->aerial_m_per_texel, o->twin)) != PLX_OK)
            return st;
        if (!o->twin) /* its values when images gather over traced photons */
            eng_lightmap_layer(e);
    }
    eng_clear_error(e);
    return PLX_OK;
}

/* ---- saving ---------------------------------------------------------------- */

static plx_status scan(plx_engine *e, plx_engine *t, unsigned char *out, bake_layout *L);

/* What make_savable takes out of an engine, put back by restore_code. */
typedef struct savable_keep {
    plx_port port;
    uint64_t polar_ns, load_ns;   /* times measured while baking: not saved, so that
                                     two bakes of a scene are the same bytes */
    uint64_t ic_gathered, ic_direct, ic_flushes; /* the counters, given back */
    light_stats lt_st;
    size_t peak_total, peak[PLX_PART_COUNT]; /* the build's peaks: saved as the image's use, so that
                                                bakes made with any number of workers are the same bytes */
    uint64_t requests;
    plx_part failed_part;         /* the build's last refused request: not saved (its free */
    size_t failed_size, failed_free; /* figure depends on the workers' scratch) */
    int threads, layer_workers;
} savable_keep;

/* Clears what must not be saved: cached lamp regions (pointers inside the
 * pool, rebuilt on demand), code addresses (the renderer's, the port's),
 * the last region read, the build times. *keep gets them back for
 * restore_code. */
static void make_savable(plx_engine *e, savable_keep *keep)
{
    if (e->ic) { /* records do not depend on who gathers them: none saved */
        keep->ic_gathered = e->ic->gathered;
        keep->ic_direct = e->ic->direct;
        keep->ic_flushes = e->ic->flushes;
        icache_clear(e->ic);
    }
    if (e->lt) {
        keep->lt_st = e->lt->st;
        light_cache_reset(e->lt);
        if (e->lt->pool)
            memset(e->lt->pool, 0, e->lt->pool_cap);
    }
    if (e->rd) {
        int32_t w, h;
        size_t px;
        render_frame_clear(e->rd); /* what frames drawn before left: not saved */
        render_code_unbind(e->rd);
        eng_render_max(e, &w, &h);
        px = (size_t)w * (size_t)h;
        if (e->aa_sum)
            memset(e->aa_sum, 0, px * 3 * sizeof *e->aa_sum);
        if (e->aa_mask) {
            memset(e->aa_id, 0, px * sizeof *e->aa_id);
            memset(e->aa_rgb, 0, px * 3);
            memset(e->aa_mask, 0, px);
        }
    }
    if (e->atlas_cache) /* which worker met which surface: not saved */
        memset(e->atlas_cache, 0, PLX_MAX_THREADS * sizeof(atlas_cache));
    if (e->atlas_rec) /* the last chart's indirect records (whichever chart worker 0 filled last) */
        memset(e->atlas_rec, 0, atlas_fill_records(e->atlas) * sizeof *e->atlas_rec);
    if (e->atlas_list)
        memset(e->atlas_list, 0, ENG_ATLAS_LIST * sizeof *e->atlas_list);
    e->lit_last = NULL;
    keep->port = e->port;
    memset(&e->port, 0, sizeof e->port);
    keep->polar_ns = e->polar_ns;
    e->polar_ns = 0;
    keep->load_ns = e->sc ? e->sc->load_ns : 0;
    if (e->sc)
        e->sc->load_ns = 0;
    keep->peak_total = e->mem.peak_total;
    memcpy(keep->peak, e->mem.peak, sizeof keep->peak);
    e->mem.peak_total = e->mem.lo + e->mem.hi;
    memcpy(e->mem.peak, e->mem.used, sizeof e->mem.peak);
    keep->requests = e->mem.requests; /* the workers' arenas are requests too; plx_bake_load counts anew */
    e->mem.requests = 0;
    keep->failed_part = e->mem.failed_part;
    keep->failed_size = e->mem.failed_size;
    keep->failed_free = e->mem.failed_free;
    e->mem.failed_part = PLX_PART_ENGINE;
    e->mem.failed_size = e->mem.failed_free = 0;
    keep->threads = e->cfg.threads;
    e->cfg.threads = 0;   /* plx_bake_load sets the loaded engine's */
    keep->layer_workers = e->layer_workers;
    e->layer_workers = 0;
}

static void restore_code(plx_engine *e, const savable_keep *keep)
{
    bake_bind_code(e);
    if (keep) {
        if (e->ic) {
            e->ic->gathered = keep->ic_gathered;
            e->ic->direct = keep->ic_direct;
            e->ic->flushes = keep->ic_flushes;
        }
        if (e->lt)
            e->lt->st = keep->lt_st;
        e->port = keep->port;
        e->polar_ns = keep->polar_ns;
        if (e->sc)
            e->sc->load_ns = keep->load_ns;
        e->mem.peak_total = keep->peak_total;
        memcpy(e->mem.peak, keep->peak, sizeof e->mem.peak);
        e->mem.requests = keep->requests;
        e->mem.failed_part = keep->failed_part;
        e->mem.failed_size = keep->failed_size;
        e->mem.failed_free = keep->failed_free;
        e->cfg.threads = keep->threads;
        e->layer_workers = keep->layer_workers;
    }
}

/* Scans (and writes when out is given) with both engines made savable. */
static plx_status scan_savable(plx_engine *e, plx_engine *t, unsigned char *out, bake_layout *L)
{
    savable_keep pe, pt;
    plx_status st;
    make_savable(e, &pe);
    make_savable(t, &pt);
    st = scan(e, t, out, L);
    restore_code(e, &pe);
    restore_code(t, &pt);
    return st;
}


/* Walks the image page by page: pointers become offsets (and relocations),
 * all-zero pages are left out. Counts into L; writes the file's bitmap,
 * pages and relocations when out is given (L then holds the counts of a
 * first pass). */
static plx_status scan(plx_engine *e, plx_engine *t, unsigned char *out, bake_layout *L)
{
    const unsigned char *pa = e->mem.base, *pb = t->mem.base;
    uint64_t base_a = (uint64_t)(uintptr_t)pa, delta = (uint64_t)(uintptr_t)pb - base_a;
    size_t len = e->mem.lo, p, n = 0, present = 0;
    uint64_t page[BAKE_PAGE / 8];
    for (p = 0; p * BAKE_PAGE < len; p++) {
        size_t start = p * BAKE_PAGE, bytes = len - start < BAKE_PAGE ? len - start : BAKE_PAGE, i;
        uint64_t any = 0;
        memset(page, 0, sizeof page);
        memcpy(page, pa + start, bytes);
        for (i = 0; i < BAKE_PAGE / 8 && 8 * i + 8 <= bytes; i++) {
            uint64_t wa = page[i], wb;
            memcpy(&wb, pb + start + 8 * i, 8);
            if (wa - base_a <= len && wb == wa + delta) {
                page[i] = wa - base_a;
                if (out)
                    bake_put32(out + L->rel_at + 4 * n, (uint32_t)(start / 8 + i));
                n++;
                any = 1;
            }
        }
        for (i = 0; i < BAKE_PAGE / 8; i++)
            any |= page[i];
        if (!any)
            continue;
        if (out) {
            out[L->bitmap_at + p / 8] |= (unsigned char)(1u << (p % 8));
            memcpy(out + L->pages_at + present * BAKE_PAGE, page, BAKE_PAGE);
        }
        present++;
    }
    L->image = len;
    L->nrel = n;
    L->pages_present = present;
    bake_layout_fill(L);
    return PLX_OK;
}

static plx_status check_twin(plx_engine *e, plx_engine *t, const char *fn)
{
    char msg[400]; /* the whole sentence: 200 cut it mid-word */
    strbuf b;
    size_t k;
    int same = t && eng_ok(t) && t != e && t->mem.lo == e->mem.lo &&
               ((uintptr_t)t->mem.base & (BAKE_ALIGN - 1)) == ((uintptr_t)e->mem.base & (BAKE_ALIGN - 1));
    for (k = 0; same && k < PLX_PART_COUNT; k++)
        same = t->mem.used[k] == e->mem.used[k] || k == PLX_PART_SCRATCH;
    if (same && e->mem.lo / 8 <= 0xffffffffu && e->mem.hi == 0 && t->mem.hi == 0)
        return PLX_OK;
    sb_init(&b, msg, sizeof msg);
    sb_str(&b, fn);
    sb_str(&b, ": the twin engine is not laid out as this one (load the same scene and call "
               "plx_bake_prepare with the same options and twin = 1, in a block aligned alike; "
               "anti-aliased frames take memory: render them on both engines or on neither)");
    return eng_fail(e, PLX_E_INVALID, msg);
}

/* The room a loaded bake's block keeps beside the image: queries' scratch,
 * and with a renderer, anti-aliasing's buffers for its largest frame (20
 * bytes a pixel: the sum and the adaptive buffers, README "Anti-aliasing"). */
static uint64_t bake_slack(const plx_engine *e)
{
    int32_t w = 0, h = 0;
    if (!e->rd)
        return BAKE_SLACK;
    eng_render_max(e, &w, &h);
    return BAKE_SLACK + (uint64_t)20 * (uint64_t)w * (uint64_t)h;
}

static plx_status measure(plx_engine *e, plx_engine *twin, const char *fn, bake_layout *L)
{
    plx_status st;
    if ((st = eng_need_scene(e, fn)) != PLX_OK)
        return st;
    if ((st = check_twin(e, twin, fn)) != PLX_OK)
        return st;
    /* photon frames came after plx_bake_prepare: the radiance atlas is
     * filled now (and an aerial light map's indirect layer gathered), so
     * the bake's frames start at once */
    if (e->atlas && (st = eng_atlas_fill_all(e)) != PLX_OK)
        return st;
    eng_lightmap_layer(e);
    return scan_savable(e, twin, NULL, L);
}

plx_status plx_bake_size(plx_engine *e, plx_engine *twin, size_t *bytes)
{
    bake_layout L;
    plx_status st;
    if (eng_ok(e) && !bytes)
        return eng_fail(e, PLX_E_INVALID, "plx_bake_size: bytes is NULL");
    st = measure(e, twin, "plx_bake_size", &L);
    if (st == PLX_OK)
        *bytes = L.total;
    return st;
}

plx_status plx_bake_save(plx_engine *e, plx_engine *twin, void *buf, size_t cap, size_t *written)
{
    unsigned char *f = buf;
    bake_layout L;
    plx_status st = measure(e, twin, "plx_bake_save", &L);
    if (st != PLX_OK)
        return st;
    if (!buf || cap < L.total)
        return eng_fail(e, PLX_E_INVALID, "plx_bake_save: the buffer is smaller than plx_bake_size says");
    memset(f, 0, L.pages_at);
    st = scan_savable(e, twin, f, &L);
    if (st != PLX_OK)
        return st;
    memcpy(f + H_MAGIC, BAKE_MAGIC, 8);
    bake_put32(f + H_VERSION, BAKE_VERSION);
    bake_put32(f + H_ENDIAN, BAKE_ENDIAN);
    bake_put32(f + H_SIZES, bake_arch_sizes());
    bake_put32(f + H_LAYOUT, bake_layout_print());
    bake_put64(f + H_LENGTH, L.total);
    bake_put64(f + H_IMAGE, L.image);
    bake_put64(f + H_NREL, L.nrel);
    bake_put64(f + H_BASEMOD, (uintptr_t)e->mem.base & (BAKE_ALIGN - 1));
    bake_put64(f + H_SLACK, bake_slack(e));
    /* 0: files of before 2026-11-25 hold the build's peak memory here, which
     * the layer's workers raised, so that bakes on 1 and N threads differed;
     * nothing reads it */
    bake_put64(f + H_RESERVED, 0);
    bake_put64(f + H_PAGES, L.pages_present);
    bake_put64(f + H_SUM, bake_file_sum(f, L.total));
    if (written)
        *written = L.total;
    eng_clear_error(e);
    return PLX_OK;
}

