/* bake_load: a bake file checked and loaded into the caller's block
 * (README "Bake files"): the image copied, its pointers relocated, the
 * engine made to fit the block. */
#include <string.h>

#include "api/bake_file.h"
#include "base/strbuf.h"
#include "light/light.h"
#include "photon/photon.h"
#include "render/render.h"
#include "base/scene.h"

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
    if (bake_get32(f + H_VERSION) != BAKE_VERSION)
        return say(err, errlen, PLX_E_UNSUPPORTED, "bake format version ", bake_get32(f + H_VERSION),
                   ", this polarlux reads version ", BAKE_VERSION, "; bake the scene again");
    if (bake_get32(f + H_ENDIAN) != BAKE_ENDIAN || bake_get32(f + H_SIZES) != bake_arch_sizes())
        return say(err, errlen, PLX_E_UNSUPPORTED,
                   "bake made on another architecture (byte order or pointer, size_t, double, long sizes "
                   "differ); bake the scene again on this machine", 0, NULL, 0, NULL);
    if (bake_get32(f + H_LAYOUT) != bake_layout_print())
        return say(err, errlen, PLX_E_UNSUPPORTED,
                   "bake made by a different build of polarlux (its structures differ); bake the scene again",
                   0, NULL, 0, NULL);
    flen = bake_get64(f + H_LENGTH);
    if (flen != len)
        return say(err, errlen, PLX_E_PARSE, flen > len ? "truncated bake file: " : "bake file too long: ",
                   len, " bytes, the header says ", flen, "");
    img = bake_get64(f + H_IMAGE);
    L->image = (size_t)img;
    L->nrel = (size_t)bake_get64(f + H_NREL);
    L->pages_present = (size_t)bake_get64(f + H_PAGES);
    if (img < sizeof(struct plx_engine) || img > ((uint64_t)1 << 34) || bake_get64(f + H_NREL) > len / 4 ||
        bake_get64(f + H_PAGES) > len / BAKE_PAGE || bake_get64(f + H_BASEMOD) >= BAKE_ALIGN ||
        bake_get64(f + H_BASEMOD) % PLX_ENGINE_ALIGN != 0)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: inconsistent header", 0, NULL, 0, NULL);
    bake_layout_fill(L);
    if (L->total != len || L->pages_present > L->npages || popcount(f + L->bitmap_at, L->npages) != L->pages_present)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: inconsistent header", 0, NULL, 0, NULL);
    if (bake_file_sum(f, len) != bake_get64(f + H_SUM))
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
    *block_bytes = L.image + (size_t)bake_get64(f + H_SLACK) + 2 * BAKE_ALIGN;
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
    bake_bind_code(e);
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
    off = (size_t)((bake_get64(f + H_BASEMOD) - (uint64_t)(uintptr_t)mem) & (BAKE_ALIGN - 1));
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
        uint64_t at = (uint64_t)bake_get32(rel + 4 * k) * 8, w;
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
