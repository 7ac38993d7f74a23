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

#define BAKE_MAGIC "PLXBAKE\0"
#define BAKE_VERSION 3u
#define BAKE_HEADER 128u
#define BAKE_ENDIAN 0x01020304u
#define BAKE_ALIGN 64u
#define BAKE_PAGE 4096u
#define BAKE_SLACK ((uint64_t)32 << 20) /* room for queries' scratch */

enum {
    H_MAGIC = 0, H_VERSION = 8, H_ENDIAN = 12, H_SIZES = 16, H_LAYOUT = 20, H_LENGTH = 24,
    H_SUM = 32, H_IMAGE = 40, H_NREL = 48, H_BASEMOD = 56, H_SLACK = 64, H_RESERVED = 72, H_PAGES = 80
};

/* ---- checksum: a multiply-rotate round over 64-bit words, four lanes ------ */

/* Each word enters its lane as acc = rotl(acc + w K2, 31) K1: for a fixed
 * word a bijection of acc, for a fixed acc a bijection of w (K1 and K2
 * odd), and the rotation carries every bit of the product into the low
 * bits of the next one. Format 2's FNV-1a step, (acc ^ w) P, carried a
 * word's bit 63 only into the sum's bit 63: two flipped top bits in one
 * lane cancelled, and one in a field nothing reads went unseen, so a
 * damaged file passed and crashed the frames (a hostile-input pass). */
#define SUM_K1 0x9e3779b97f4a7c15ull /* 2^64 / the golden ratio, odd */
#define SUM_K2 0xd6e8feb86659fd93ull
#define SUM_K3 0xff51afd7ed558ccdull

typedef struct bake_sum {
    uint64_t h[4];
} bake_sum;

static uint64_t rotl64(uint64_t x, unsigned r)
{
    return (x << r) | (x >> (64u - r));
}

static uint64_t sum_round(uint64_t acc, uint64_t w)
{
    return rotl64(acc + w * SUM_K2, 31) * SUM_K1;
}

static void sum_init(bake_sum *s)
{
    int k;
    for (k = 0; k < 4; k++)
        s->h[k] = SUM_K3 + (uint64_t)k;
}

/* Adds n bytes (n a multiple of 32 except for the last call). */
static void sum_add(bake_sum *s, const unsigned char *p, size_t n)
{
    size_t i = 0;
    uint64_t h0 = s->h[0], h1 = s->h[1], h2 = s->h[2], h3 = s->h[3], w[4];
    for (; i + 32 <= n; i += 32) {
        memcpy(w, p + i, 32);
        h0 = sum_round(h0, w[0]);
        h1 = sum_round(h1, w[1]);
        h2 = sum_round(h2, w[2]);
        h3 = sum_round(h3, w[3]);
    }
    for (; i < n; i++)
        h0 = sum_round(h0, p[i]);
    s->h[0] = h0;
    s->h[1] = h1;
    s->h[2] = h2;
    s->h[3] = h3;
}

/* The lanes folded in order through the same round, then mixed so that
 * every bit of the result depends on every bit of each lane. */
static uint64_t sum_end(const bake_sum *s)
{
    uint64_t h = s->h[0];
    int k;
    for (k = 1; k < 4; k++)
        h = sum_round(h, s->h[k]);
    h ^= h >> 33;
    h *= SUM_K3;
    h ^= h >> 29;
    h *= SUM_K2;
    h ^= h >> 32;
    return h;
}

/* The checksum of a whole file: the header with its checksum field as 0,
 * then everything after the header. */
static uint64_t file_sum(const unsigned char *f, size_t len)
{
    unsigned char h[BAKE_HEADER];
    bake_sum s;
    memcpy(h, f, BAKE_HEADER);
    memset(h + H_SUM, 0, 8);
    sum_init(&s);
    sum_add(&s, h, BAKE_HEADER);
    sum_add(&s, f + BAKE_HEADER, len - BAKE_HEADER);
    return sum_end(&s);
}

/* ---- header fields ------------------------------------------------------- */

static void put32(unsigned char *p, uint32_t v) { memcpy(p, &v, 4); }
static void put64(unsigned char *p, uint64_t v) { memcpy(p, &v, 8); }
static uint32_t get32(const unsigned char *p) { uint32_t v; memcpy(&v, p, 4); return v; }
static uint64_t get64(const unsigned char *p) { uint64_t v; memcpy(&v, p, 8); return v; }

/* Sizes of the saved structures: a bake from a build whose structures
 * differ is refused (a cheap guard; BAKE_VERSION is the real contract). */
static uint32_t layout_print(void)
{
    const size_t sz[] = { sizeof(struct plx_engine), sizeof(scene), sizeof(scene_building),
                          sizeof(scene_lamp), sizeof(light), sizeof(lit_region), sizeof(photon_sys),
                          sizeof(photon_config), sizeof(photon_lamp_slot), sizeof(arena),
                          sizeof(plx_config), sizeof(render_opts), render_struct_bytes(),
                          sizeof(render_stats), sizeof(icache), sizeof(polar), sizeof(polar_trap),
                          PLX_PART_COUNT, sizeof(mesh), sizeof(mesh_bld),
                          sizeof(mesh_surf), RENDER_SURF_CACHE, sizeof(atlas), sizeof(atlas_chart),
                          sizeof(atlas_cache), sizeof(light_entry),
                          7 /* format changes that keep the sizes (bump on such changes): 2 the polar
                               DAG's wide nodes bit-packed, 3 aerial records keyed apart, 8 m, 4 the
                               radiance atlas, 5 a wall column's vertices shared by its two walls, the
                               roof and the underside (mesh_bld.v_count), 6 the renderer's buffers of
                               a row or a column for the longer side (it draws frames either way
                               round: an older bake's are too short for a turned frame), 7 the photon
                               charts' surface keys (courtyards apart) and own-texel rule. The atlas's dark state
                               (ATLAS_DARK, 2026-11-29) needs none: an older bake's charts read as
                               filled (no shortcut, the same
                               image), an older reader takes the state as done (a saved bake has
                               nothing left to fill) */ };
    uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a's basis and prime: the sizes are small */
    size_t i;
    for (i = 0; i < sizeof sz / sizeof sz[0]; i++)
        h = (h ^ (uint64_t)sz[i]) * 0x00000100000001b3ull;
    return (uint32_t)(h ^ (h >> 32));
}

static uint32_t arch_sizes(void)
{
    return (uint32_t)sizeof(void *) | (uint32_t)sizeof(size_t) << 8 | (uint32_t)sizeof(double) << 16 |
           (uint32_t)sizeof(long) << 24;
}

static size_t pad8(size_t n)
{
    return (n + 7) & ~(size_t)7;
}

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

/* Where a file's parts are: the page bitmap, the stored pages, the
 * relocations. */
typedef struct bake_layout {
    size_t image, npages, pages_present, nrel;
    size_t bitmap_at, pages_at, rel_at, total;
} bake_layout;

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
    if (e->rd)
        render_code_bind(e->rd, render_shade_light);
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


static void layout_fill(bake_layout *L)
{
    L->npages = (L->image + BAKE_PAGE - 1) / BAKE_PAGE;
    L->bitmap_at = BAKE_HEADER;
    L->pages_at = L->bitmap_at + pad8((L->npages + 7) / 8);
    L->rel_at = L->pages_at + L->pages_present * BAKE_PAGE;
    L->total = L->rel_at + 4 * L->nrel;
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
                    put32(out + L->rel_at + 4 * n, (uint32_t)(start / 8 + i));
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
    layout_fill(L);
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
    put32(f + H_VERSION, BAKE_VERSION);
    put32(f + H_ENDIAN, BAKE_ENDIAN);
    put32(f + H_SIZES, arch_sizes());
    put32(f + H_LAYOUT, layout_print());
    put64(f + H_LENGTH, L.total);
    put64(f + H_IMAGE, L.image);
    put64(f + H_NREL, L.nrel);
    put64(f + H_BASEMOD, (uintptr_t)e->mem.base & (BAKE_ALIGN - 1));
    put64(f + H_SLACK, bake_slack(e));
    /* 0: files of before 2026-11-25 hold the build's peak memory here, which
     * the layer's workers raised, so that bakes on 1 and N threads differed;
     * nothing reads it */
    put64(f + H_RESERVED, 0);
    put64(f + H_PAGES, L.pages_present);
    put64(f + H_SUM, file_sum(f, L.total));
    if (written)
        *written = L.total;
    eng_clear_error(e);
    return PLX_OK;
}

/* ---- loading ----------------------------------------------------------------- */

static plx_status say(char *err, size_t errlen, plx_status s, const char *a, uint64_t x, const char *b,
                      uint64_t y, const char *c)
{
    strbuf sb;
    if (err && errlen) {
        sb_init(&sb, err, errlen);
        sb_str(&sb, a);
        if (b) {
            sb_uint(&sb, x);
            sb_str(&sb, b);
            if (c) {
                sb_uint(&sb, y);
                sb_str(&sb, c);
            }
        }
    }
    return s;
}

/* Checks the header and the checksum; fills the image length. */
static size_t popcount(const unsigned char *bits, size_t n)
{
    size_t i, c = 0;
    for (i = 0; i < n; i++)
        c += (bits[i / 8] >> (i % 8)) & 1u;
    return c;
}

static plx_status check_file(const unsigned char *f, size_t len, bake_layout *L, char *err, size_t errlen)
{
    uint64_t flen, img;
    if (!f || len < 8 || memcmp(f, BAKE_MAGIC, 8) != 0)
        return say(err, errlen, PLX_E_PARSE, "not a polarlux bake file (no PLXBAKE magic)", 0, NULL, 0, NULL);
    if (len < BAKE_HEADER)
        return say(err, errlen, PLX_E_PARSE, "truncated bake file: ", len, " bytes, shorter than its ",
                   BAKE_HEADER, "-byte header");
    if (get32(f + H_VERSION) != BAKE_VERSION)
        return say(err, errlen, PLX_E_UNSUPPORTED, "bake format version ", get32(f + H_VERSION),
                   ", this polarlux reads version ", BAKE_VERSION, "; bake the scene again");
    if (get32(f + H_ENDIAN) != BAKE_ENDIAN || get32(f + H_SIZES) != arch_sizes())
        return say(err, errlen, PLX_E_UNSUPPORTED,
                   "bake made on another architecture (byte order or pointer, size_t, double, long sizes "
                   "differ); bake the scene again on this machine", 0, NULL, 0, NULL);
    if (get32(f + H_LAYOUT) != layout_print())
        return say(err, errlen, PLX_E_UNSUPPORTED,
                   "bake made by a different build of polarlux (its structures differ); bake the scene again",
                   0, NULL, 0, NULL);
    flen = get64(f + H_LENGTH);
    if (flen != len)
        return say(err, errlen, PLX_E_PARSE, flen > len ? "truncated bake file: " : "bake file too long: ",
                   len, " bytes, the header says ", flen, "");
    img = get64(f + H_IMAGE);
    L->image = (size_t)img;
    L->nrel = (size_t)get64(f + H_NREL);
    L->pages_present = (size_t)get64(f + H_PAGES);
    if (img < sizeof(struct plx_engine) || img > ((uint64_t)1 << 34) || get64(f + H_NREL) > len / 4 ||
        get64(f + H_PAGES) > len / BAKE_PAGE || get64(f + H_BASEMOD) >= BAKE_ALIGN ||
        get64(f + H_BASEMOD) % PLX_ENGINE_ALIGN != 0)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: inconsistent header", 0, NULL, 0, NULL);
    layout_fill(L);
    if (L->total != len || L->pages_present > L->npages || popcount(f + L->bitmap_at, L->npages) != L->pages_present)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: inconsistent header", 0, NULL, 0, NULL);
    if (file_sum(f, len) != get64(f + H_SUM))
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: checksum mismatch", 0, NULL, 0, NULL);
    return PLX_OK;
}

plx_status plx_bake_block_size(const void *bake, size_t len, size_t *block_bytes, char *err, size_t errlen)
{
    const unsigned char *f = bake;
    bake_layout L;
    plx_status st;
    if (!block_bytes)
        return say(err, errlen, PLX_E_INVALID, "plx_bake_block_size: block_bytes is NULL", 0, NULL, 0, NULL);
    st = check_file(f, len, &L, err, errlen);
    if (st != PLX_OK)
        return st;
    *block_bytes = L.image + (size_t)get64(f + H_SLACK) + 2 * BAKE_ALIGN;
    if (err && errlen) /* no stale line from an earlier call */
        err[0] = '\0';
    return PLX_OK;
}

/* p is NULL, or lies in the image with 'bytes' after it and on an 8-byte
 * boundary (the load places the image as the baking engine's block lay,
 * modulo BAKE_ALIGN, so its structures keep their alignment; they hold
 * doubles and pointers: a misaligned renderer made the load itself fault,
 * found by a survey of forged bakes). */
static int inside(const void *p, size_t bytes, const unsigned char *base, size_t len)
{
    const unsigned char *q = p;
    return !q || (q >= base && (size_t)(q - base) <= len && bytes <= len - (size_t)(q - base) &&
                  (uintptr_t)q % 8 == 0);
}

/* The engine's own pointers lie in the image, aligned, with room for what
 * they point at where loading touches it (the renderer). */
static int roots_inside(const plx_engine *e, const unsigned char *base, size_t len)
{
    return inside(e->sc, sizeof(scene), base, len) && inside(e->pd, 1, base, len) &&
           inside(e->lt, sizeof(light), base, len) && inside(e->rd, render_struct_bytes(), base, len) &&
           inside(e->ph, sizeof(photon_sys), base, len) && inside(e->vis_poly, 1, base, len) &&
           inside(e->vis_ids, 1, base, len);
}

/* The engine object of a loaded image, made to fit its new block. */
static void rebase_engine(plx_engine *e, void *mem, unsigned char *base, size_t cap, size_t lo,
                          const plx_config *cfg)
{
    plx_config saved = e->cfg;
    size_t k;
    e->block = mem;
    e->mem.base = base;
    e->mem.cap = cap;
    e->mem.lo = lo;
    e->mem.hi = 0;
    e->mem.peak_total = lo;
    e->mem.requests = 0;
    e->mem.fail_at = 0;
    e->mem.used[PLX_PART_SCRATCH] = 0;
    if (cfg)
        e->cfg = *cfg;
    else
        plx_config_default(&e->cfg);
    /* what the saved structures were sized by stays */
    e->cfg.lit_cache_bytes = saved.lit_cache_bytes;
    e->cfg.render_max_width = saved.render_max_width;
    e->cfg.render_max_height = saved.render_max_height;
    memset(&e->port, 0, sizeof e->port);
    if (e->cfg.port)
        e->port = *e->cfg.port;
    e->cfg.port = &e->port;
    for (k = 0; k < PLX_PART_COUNT; k++)
        e->mem.budget[k] = e->cfg.part_budget[k];
    e->lit_last = NULL;
    eng_clear_error(e);
    restore_code(e, NULL);
}

plx_status plx_bake_load(void *mem, size_t size, const plx_config *cfg, const void *bake, size_t len,
                         plx_engine **out, char *err, size_t errlen)
{
    const unsigned char *f = bake, *rel;
    unsigned char *base;
    uint64_t img, k;
    size_t off, cap, p, present = 0;
    bake_layout L;
    plx_engine *e;
    plx_status st;
    if (out)
        *out = NULL;
    if (!mem || !out)
        return say(err, errlen, PLX_E_INVALID, "plx_bake_load: mem and out must not be NULL", 0, NULL, 0, NULL);
    /* the image is written over the block from its start: a file read
     * into the block would be overwritten before it is read (and memcpy
     * of overlapping bytes is undefined) */
    if ((uintptr_t)f < (uintptr_t)mem + size && (uintptr_t)mem < (uintptr_t)f + len)
        return say(err, errlen, PLX_E_INVALID, "plx_bake_load: the bake's bytes lie inside the block; read the "
                   "file into memory outside it (the load writes the block from its start)", 0, NULL, 0, NULL);
    st = check_file(f, len, &L, err, errlen);
    if (st != PLX_OK)
        return st;
    img = L.image;
    /* the same alignment modulo 64 as where it was saved */
    off = (size_t)((get64(f + H_BASEMOD) - (uint64_t)(uintptr_t)mem) & (BAKE_ALIGN - 1));
    if (size < off || size - off < img || size - off < PLX_ENGINE_MIN_BYTES)
        return say(err, errlen, PLX_E_NOMEM, "the block is too small for the bake: it needs ",
                   img + off, " bytes, the block has ", size, "");
    base = (unsigned char *)mem + off;
    cap = size - off;
    for (p = 0; p < L.npages; p++) {
        size_t start = p * BAKE_PAGE, bytes = img - start < BAKE_PAGE ? (size_t)img - start : BAKE_PAGE;
        if ((f[L.bitmap_at + p / 8] >> (p % 8)) & 1u)
            memcpy(base + start, f + L.pages_at + BAKE_PAGE * present++, bytes);
        else
            memset(base + start, 0, bytes);
    }
    rel = f + L.rel_at;
    for (k = 0; k < L.nrel; k++) {
        uint64_t at = (uint64_t)get32(rel + 4 * k) * 8, w;
        if (at + 8 > img)
            return say(err, errlen, PLX_E_PARSE, "corrupt bake file: relocation ", k, " points outside the image",
                       0, NULL);
        memcpy(&w, base + at, 8);
        if (w > img)
            return say(err, errlen, PLX_E_PARSE, "corrupt bake file: relocated word ", k,
                       " points outside the image", 0, NULL);
        w += (uint64_t)(uintptr_t)base;
        memcpy(base + at, &w, 8);
    }
    e = (plx_engine *)(void *)base;
    if (e->magic != ENGINE_MAGIC || e->mem.lo != img || !roots_inside(e, base, (size_t)img))
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: no engine at the start of the image", 0, NULL,
                   0, NULL);
    rebase_engine(e, mem, base, cap, (size_t)img, cfg);
    *out = e;
    if (err && errlen)
        err[0] = '\0';
    return PLX_OK;
}
