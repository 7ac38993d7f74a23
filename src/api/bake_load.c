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

/* The set bits among the first n of bits. */
static size_t popcount(const unsigned char *bits, size_t n)
{
    size_t i, c = 0;
    for (i = 0; i < n; i++)
        c += (bits[i / 8] >> (i % 8)) & 1u;
    return c;
}

#define BAKE_MAX_PLAUSIBLE_VERSION 255u /* a version field above this is damage, not another polarlux */

static uint32_t swap32(uint32_t v)
{
    return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

/* The layout the header's fields other than the length describe, checked
 * against a file of len bytes; 0 when they are not consistent. */
static int layout_of(const unsigned char *h, uint64_t len, bake_layout *L)
{
    uint64_t img = bake_get64(h + H_IMAGE);
    L->image = (size_t)img;
    L->nrel = (size_t)bake_get64(h + H_NREL);
    L->pages_present = (size_t)bake_get64(h + H_PAGES);
    if (img < sizeof(struct plx_engine) || img > ((uint64_t)1 << 34) || bake_get64(h + H_NREL) > len / 4 ||
        bake_get64(h + H_PAGES) > len / BAKE_PAGE || bake_get64(h + H_BASEMOD) >= BAKE_ALIGN ||
        bake_get64(h + H_BASEMOD) % PLX_ENGINE_ALIGN != 0)
        return 0;
    bake_layout_fill(L);
    return L->total == len && L->pages_present <= L->npages;
}

/* The version and byte-order fields: another polarlux's version or another
 * byte order is said as such; values no polarlux writes are damage (a
 * flipped bit there was blamed on the version or the architecture). */
static plx_status check_version(const unsigned char *h, char *err, size_t errlen)
{
    uint32_t v = bake_get32(h + H_VERSION), e = bake_get32(h + H_ENDIAN);
    if (e == swap32(BAKE_ENDIAN)) /* no single damaged bit makes it */
        return say(err, errlen, PLX_E_UNSUPPORTED, "bake made on another architecture (its byte order differs); "
                   "bake the scene again on this machine", 0, NULL, 0, NULL);
    if (v != BAKE_VERSION && v >= 1 && v <= BAKE_MAX_PLAUSIBLE_VERSION)
        return say(err, errlen, PLX_E_UNSUPPORTED, "bake format version ", v, ", this polarlux reads version ",
                   BAKE_VERSION, "; bake the scene again");
    if (v != BAKE_VERSION)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: damaged header (its version field reads ", v, ")",
                   0, NULL);
    if (e != BAKE_ENDIAN)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: damaged header (its byte-order field is neither "
                   "this machine's nor the other)", 0, NULL, 0, NULL);
    return PLX_OK;
}

/* Checks the header h (its first min(len, BAKE_HEADER) bytes read) of a
 * file of len bytes and fills L from it. *foreign is set when the file
 * is of this format version and byte order but names other sizes or
 * another build: such a file is from another build only when its
 * checksum holds (the caller's to check, header_verdict); a damaged
 * header byte there was blamed on the build. A length field that
 * disagrees with the file while the other fields describe exactly the
 * file's bytes is damage too, not a truncated file. */
static plx_status check_header(const unsigned char *h, uint64_t len, bake_layout *L, int *foreign, char *err,
                               size_t errlen)
{
    uint64_t flen;
    plx_status st;
    *foreign = 0;
    if (!h || len < 8 || memcmp(h, BAKE_MAGIC, 8) != 0)
        return say(err, errlen, PLX_E_PARSE, "not a polarlux bake file (no PLXBAKE magic)", 0, NULL, 0, NULL);
    if (len < BAKE_HEADER)
        return say(err, errlen, PLX_E_PARSE, "truncated bake file: ", len, " bytes, shorter than its ",
                   BAKE_HEADER, "-byte header");
    if ((st = check_version(h, err, errlen)) != PLX_OK)
        return st;
    *foreign = bake_get32(h + H_SIZES) != bake_arch_sizes() || bake_get32(h + H_LAYOUT) != bake_layout_print();
    if (bake_get32(h + H_SIZES) != bake_arch_sizes())
        return say(err, errlen, PLX_E_UNSUPPORTED,
                   "bake made on another architecture (its pointer, size_t, double or long "
                   "sizes differ); bake the scene again on this machine", 0, NULL, 0, NULL);
    if (bake_get32(h + H_LAYOUT) != bake_layout_print())
        return say(err, errlen, PLX_E_UNSUPPORTED,
                   "bake made by a different build of polarlux (its structures differ); bake the scene again",
                   0, NULL, 0, NULL);
    flen = bake_get64(h + H_LENGTH);
    if (flen != len && layout_of(h, len, L))
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: damaged header (its length field reads ", flen,
                   " bytes, its layout the file's ", len, ")");
    if (flen != len)
        return say(err, errlen, PLX_E_PARSE, flen > len ? "truncated bake file: " : "bake file too long: ",
                   len, " bytes, the header says ", flen, "");
    if (!layout_of(h, len, L))
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: inconsistent header", 0, NULL, 0, NULL);
    return PLX_OK;
}

/* The checks after the header's: the bitmap's count of stored pages
 * (present of them), then the checksum (sum, the file's). */
static plx_status check_body(const bake_layout *L, size_t present, uint64_t sum, uint64_t want, char *err,
                             size_t errlen)
{
    if (present != L->pages_present)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: inconsistent header", 0, NULL, 0, NULL);
    if (sum != want)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: checksum mismatch", 0, NULL, 0, NULL);
    return PLX_OK;
}

/* A foreign header's verdict (check_header): another architecture or
 * build (st, its message kept) when the checksum over the file (sum)
 * holds, else a corrupt file. */
static plx_status header_verdict(plx_status st, const unsigned char *h, uint64_t sum, char *err, size_t errlen)
{
    if (sum != bake_get64(h + H_SUM))
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: checksum mismatch (in its header)", 0, NULL, 0,
                   NULL);
    return st;
}

/* Checks the header and the checksum; fills L. */
static plx_status check_file(const unsigned char *f, size_t len, bake_layout *L, char *err, size_t errlen)
{
    int foreign;
    plx_status st = check_header(f, len, L, &foreign, err, errlen);
    if (st != PLX_OK && foreign)
        return header_verdict(st, f, bake_file_sum(f, len), err, errlen);
    if (st != PLX_OK)
        return st;
    return check_body(L, popcount(f + L->bitmap_at, L->npages), bake_file_sum(f, len), bake_get64(f + H_SUM), err,
                      errlen);
}

/* The block plx_bake_block_size gives for a file of layout L, header h:
 * the image, the room the bake keeps beside it, and the alignment. */
static size_t block_for(const bake_layout *L, const unsigned char *h)
{
    return L->image + (size_t)bake_get64(h + H_SLACK) + 2 * BAKE_ALIGN;
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
    *block_bytes = block_for(&L, f);
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

/* Where the image goes in the block mem of size bytes: the same
 * alignment modulo 64 as where it was saved (the header h's); *base and
 * *cap, or PLX_E_NOMEM when it does not fit. */
static plx_status place(void *mem, size_t size, const unsigned char *h, const bake_layout *L, unsigned char **base,
                        size_t *cap, char *err, size_t errlen)
{
    size_t off = (size_t)((bake_get64(h + H_BASEMOD) - (uint64_t)(uintptr_t)mem) & (BAKE_ALIGN - 1));
    if (size < off || size - off < L->image || size - off < PLX_ENGINE_MIN_BYTES)
        return say(err, errlen, PLX_E_NOMEM, "the block is too small for the bake: it needs ",
                   (uint64_t)L->image + off, " bytes, the block has ", size, "");
    *base = (unsigned char *)mem + off;
    *cap = size - off;
    return PLX_OK;
}

/* Relocation k, the image's word index w: its offset becomes an address. */
static plx_status relocate(unsigned char *base, size_t img, uint64_t k, uint32_t w, char *err, size_t errlen)
{
    uint64_t at = (uint64_t)w * 8, v;
    if (at + 8 > img)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: relocation ", k, " points outside the image", 0,
                   NULL);
    memcpy(&v, base + at, 8);
    if (v > img)
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: relocated word ", k, " points outside the image",
                   0, NULL);
    v += (uint64_t)(uintptr_t)base;
    memcpy(base + at, &v, 8);
    return PLX_OK;
}

/* The engine at base, checked and made to fit the block. */
static plx_status finish(void *mem, unsigned char *base, size_t cap, size_t img, const plx_config *cfg,
                         plx_engine **out, char *err, size_t errlen)
{
    plx_engine *e = (plx_engine *)(void *)base;
    if (e->magic != ENGINE_MAGIC || e->mem.lo != img || !roots_inside(e, base, img))
        return say(err, errlen, PLX_E_PARSE, "corrupt bake file: no engine at the start of the image", 0, NULL,
                   0, NULL);
    rebase_engine(e, mem, base, cap, img, cfg);
    *out = e;
    if (err && errlen)
        err[0] = '\0';
    return PLX_OK;
}

plx_status plx_bake_load(void *mem, size_t size, const plx_config *cfg, const void *bake, size_t len,
                         plx_engine **out, char *err, size_t errlen)
{
    const unsigned char *f = bake;
    unsigned char *base;
    uint64_t k;
    size_t cap, p, present = 0;
    bake_layout L;
    plx_status st;
    if (out)
        *out = NULL;
    if (!mem || !out)
        return say(err, errlen, PLX_E_INVALID, "plx_bake_load: mem and out must not be NULL", 0, NULL, 0, NULL);
    if (cfg && (cfg->threads < 0 || cfg->threads > PLX_MAX_THREADS))
        return say(err, errlen, PLX_E_INVALID, "plx_bake_load: cfg->threads must be from 0 to PLX_MAX_THREADS", 0,
                   NULL, 0, NULL);
    /* the image is written over the block from its start: a file read
     * into the block would be overwritten before it is read (and memcpy
     * of overlapping bytes is undefined) */
    if ((uintptr_t)f < (uintptr_t)mem + size && (uintptr_t)mem < (uintptr_t)f + len)
        return say(err, errlen, PLX_E_INVALID, "plx_bake_load: the bake's bytes lie inside the block; read the "
                   "file into memory outside it (the load writes the block from its start)", 0, NULL, 0, NULL);
    if ((st = check_file(f, len, &L, err, errlen)) != PLX_OK ||
        (st = place(mem, size, f, &L, &base, &cap, err, errlen)) != PLX_OK)
        return st;
    for (p = 0; p < L.npages; p++) {
        size_t start = p * BAKE_PAGE, bytes = L.image - start < BAKE_PAGE ? L.image - start : BAKE_PAGE;
        if ((f[L.bitmap_at + p / 8] >> (p % 8)) & 1u)
            memcpy(base + start, f + L.pages_at + BAKE_PAGE * present++, bytes);
        else
            memset(base + start, 0, bytes);
    }
    for (k = 0; k < L.nrel; k++)
        if ((st = relocate(base, L.image, k, bake_get32(f + L.rel_at + 4 * k), err, errlen)) != PLX_OK)
            return st;
    return finish(mem, base, cap, L.image, cfg, out, err, errlen);
}

/* ---- through the caller's reads -------------------------------------------- */

#define READ_SMALL 512u              /* bytes a read into the stack (a multiple of 32) */
#define READ_BIG ((size_t)1 << 20)   /* at most a read into the block */

typedef struct bake_src {
    plx_bake_read_fn read;
    void *user;
    uint64_t len;
    char *err;
    size_t errlen;
} bake_src;

static plx_status src_read(const bake_src *s, uint64_t off, void *buf, size_t n)
{
    if (n == 0 || s->read(s->user, off, buf, n) == 0)
        return PLX_OK;
    return say(s->err, s->errlen, PLX_E_IO, "cannot read the bake file: ", n, " bytes at byte ", off, "");
}

/* The checksum over the file's bytes given in order in pieces of any
 * length: in groups of 32 from the header's end, as bake_file_sum takes
 * them in one piece. */
typedef struct sum_stream {
    bake_sum s;
    unsigned char tail[32];
    size_t nt;
} sum_stream;

static void ss_start(sum_stream *ss, const unsigned char *h)
{
    bake_sum_init(&ss->s);
    bake_sum_header(&ss->s, h);
    ss->nt = 0;
}

static void ss_add(sum_stream *ss, const unsigned char *p, size_t n)
{
    size_t whole;
    if (ss->nt) {
        size_t take = 32 - ss->nt < n ? 32 - ss->nt : n;
        memcpy(ss->tail + ss->nt, p, take);
        ss->nt += take;
        p += take;
        n -= take;
        if (ss->nt < 32)
            return;
        bake_sum_add(&ss->s, ss->tail, 32);
        ss->nt = 0;
    }
    whole = n & ~(size_t)31;
    bake_sum_add(&ss->s, p, whole);
    memcpy(ss->tail, p + whole, n - whole);
    ss->nt = n - whole;
}

static uint64_t ss_end(sum_stream *ss)
{
    bake_sum_add(&ss->s, ss->tail, ss->nt);
    return bake_sum_end(&ss->s);
}

/* The stored pages' bits among the file's n bytes from off in buf. */
static size_t bitmap_bits(const bake_layout *L, uint64_t off, const unsigned char *buf, size_t n)
{
    uint64_t lo = off > L->bitmap_at ? off : L->bitmap_at, hi = off + n < L->pages_at ? off + n : L->pages_at, o;
    size_t c = 0;
    unsigned b;
    for (o = lo; o < hi; o++)
        for (b = 0; b < 8; b++)
            c += (o - L->bitmap_at) * 8 + b < L->npages && ((buf[o - off] >> b) & 1u);
    return c;
}

/* The whole file read through buf (n bytes) and checked as check_file
 * checks a file in memory: a block too small's first reading, and the
 * verdict on a file whose loading failed (load_once). */
static plx_status check_read(const bake_src *s, const unsigned char *h, const bake_layout *L, unsigned char *buf,
                             size_t n)
{
    sum_stream ss;
    size_t present = 0;
    uint64_t off;
    plx_status st;
    ss_start(&ss, h);
    for (off = BAKE_HEADER; off < s->len; off += n) {
        n = s->len - off < n ? (size_t)(s->len - off) : n;
        if ((st = src_read(s, off, buf, n)) != PLX_OK)
            return st;
        ss_add(&ss, buf, n);
        present += bitmap_bits(L, off, buf, n);
    }
    return check_body(L, present, ss_end(&ss), bake_get64(h + H_SUM), s->err, s->errlen);
}

/* The bitmap's bytes from first, READ_SMALL of them at most, read when a
 * page's bit lies outside them. */
typedef struct bit_window {
    unsigned char b[READ_SMALL];
    size_t first;
    int have;
    bake_sum used;              /* the windows' bytes as read, in order (each once: p only grows) */
} bit_window;

static plx_status page_stored(const bake_src *s, const bake_layout *L, bit_window *w, size_t p, int *stored)
{
    size_t byte = p / 8, nb = (L->npages + 7) / 8;
    if (!w->have || byte < w->first || byte >= w->first + READ_SMALL) {
        plx_status st;
        w->first = byte - byte % READ_SMALL;
        size_t n = nb - w->first < READ_SMALL ? nb - w->first : READ_SMALL;
        if ((st = src_read(s, L->bitmap_at + w->first, w->b, n)) != PLX_OK)
            return st;
        bake_sum_add(&w->used, w->b, n);
        w->have = 1;
    }
    *stored = (w->b[byte - w->first] >> (p % 8)) & 1u;
    return PLX_OK;
}

/* n bytes at off read and summed, READ_SMALL at a time through the stack
 * (the bitmap, a last page's bytes past the image); with mine, its first
 * upto bytes summed into it too, READ_SMALL at a time as page_stored
 * reads them; with bits, the stored pages' bits among them (L's bitmap)
 * counted into it. */
static plx_status sum_read_bits(const bake_src *s, sum_stream *ss, uint64_t off, uint64_t n, bake_sum *mine,
                                uint64_t upto, const bake_layout *L, size_t *bits)
{
    unsigned char buf[READ_SMALL];
    uint64_t done = 0;
    while (n > 0) {
        size_t k = n < READ_SMALL ? (size_t)n : READ_SMALL;
        plx_status st = src_read(s, off, buf, k);
        if (st != PLX_OK)
            return st;
        ss_add(ss, buf, k);
        if (mine && done < upto)
            bake_sum_add(mine, buf, upto - done < k ? (size_t)(upto - done) : k);
        if (bits)
            *bits += bitmap_bits(L, off, buf, k);
        off += k;
        n -= k;
        done += k;
    }
    return PLX_OK;
}

static plx_status sum_read(const bake_src *s, sum_stream *ss, uint64_t off, uint64_t n, bake_sum *mine, uint64_t upto)
{
    return sum_read_bits(s, ss, off, n, mine, upto, NULL, NULL);
}

/* s set up for the file of len bytes read through read(user, ...), its
 * header read into h and checked (check_header), L filled. */
static plx_status src_open(bake_src *s, plx_bake_read_fn read, void *user, uint64_t len, char *err, size_t errlen,
                           unsigned char h[BAKE_HEADER], bake_layout *L)
{
    plx_status st;
    s->read = read;
    s->user = user;
    s->len = len;
    s->err = err;
    s->errlen = errlen;
    int foreign;
    sum_stream ss;
    plx_status sr;
    st = src_read(s, 0, h, len < BAKE_HEADER ? (size_t)len : BAKE_HEADER);
    if (st != PLX_OK)
        return st;
    st = check_header(h, len, L, &foreign, err, errlen);
    if (st == PLX_OK || !foreign)
        return st;
    ss_start(&ss, h); /* the whole file summed: another build's, or damaged */
    if ((sr = sum_read(s, &ss, BAKE_HEADER, len - BAKE_HEADER, NULL, 0)) != PLX_OK)
        return sr;
    return header_verdict(st, h, ss_end(&ss), err, errlen);
}

/* The stored pages p .. q - 1 (the present-th stored page first) read
 * into the image at base (img bytes) and summed; a last page's bytes past
 * the image only summed. */
static plx_status read_pages(const bake_src *s, const bake_layout *L, sum_stream *ss, unsigned char *base, size_t p,
                             size_t q, size_t present)
{
    uint64_t at = L->pages_at + (uint64_t)BAKE_PAGE * present;
    size_t start = p * BAKE_PAGE, end = q * BAKE_PAGE < L->image ? q * BAKE_PAGE : L->image;
    plx_status st = src_read(s, at, base + start, end - start);
    if (st != PLX_OK)
        return st;
    ss_add(ss, base + start, end - start);
    return sum_read(s, ss, at + (end - start), (uint64_t)(q - p) * BAKE_PAGE - (end - start), NULL, 0);
}

/* The loading reading: the pages into the image at base, the relocations
 * applied, the checksum taken (the stored pages counted before any is
 * read); the bitmap that placed the pages (read again in windows as they pass) must be the
 * one summed (a file that moved a stored page's bit between them kept its
 * checksum). */
static plx_status copy_read(const bake_src *s, const unsigned char *h, const bake_layout *L, unsigned char *base)
{
    sum_stream ss;
    bit_window w;
    bake_sum summed;
    unsigned char buf[READ_SMALL];
    size_t p = 0, q, present = 0, bits = 0;
    uint64_t k;
    int stored;
    plx_status st;
    w.have = 0;
    bake_sum_init(&w.used);
    bake_sum_init(&summed);
    ss_start(&ss, h);
    if ((st = sum_read_bits(s, &ss, L->bitmap_at, L->pages_at - L->bitmap_at, &summed, (L->npages + 7) / 8, L,
                            &bits)) != PLX_OK)
        return st;
    if (bits != L->pages_present) /* before any page: no read past the stored pages */
        return say(s->err, s->errlen, PLX_E_PARSE, "corrupt bake file: inconsistent header", 0, NULL, 0, NULL);
    while (p < L->npages) {
        if ((st = page_stored(s, L, &w, p, &stored)) != PLX_OK)
            return st;
        if (!stored) {
            memset(base + p * BAKE_PAGE, 0, L->image - p * BAKE_PAGE < BAKE_PAGE ? L->image - p * BAKE_PAGE : BAKE_PAGE);
            p++;
            continue;
        }
        for (q = p + 1; q < L->npages; q++)
            if ((st = page_stored(s, L, &w, q, &stored)) != PLX_OK || !stored)
                break;
        if (st != PLX_OK || (st = read_pages(s, L, &ss, base, p, q, present)) != PLX_OK)
            return st;
        present += q - p;
        p = q;
    }
    for (k = 0; k < L->nrel; k += READ_SMALL / 4) {
        size_t m = L->nrel - k < READ_SMALL / 4 ? (size_t)(L->nrel - k) : READ_SMALL / 4, i;
        if ((st = src_read(s, L->rel_at + 4 * k, buf, 4 * m)) != PLX_OK)
            return st;
        ss_add(&ss, buf, 4 * m);
        for (i = 0; i < m; i++)
            if ((st = relocate(base, L->image, k + i, bake_get32(buf + 4 * i), s->err, s->errlen)) != PLX_OK)
                return st;
    }
    if (ss_end(&ss) != bake_get64(h + H_SUM) || bake_sum_end(&w.used) != bake_sum_end(&summed))
        return say(s->err, s->errlen, PLX_E_PARSE, "corrupt bake file: it changed while it was read", 0, NULL, 0,
                   NULL);
    return PLX_OK;
}

/* The file read once into the image at base (cap bytes), checked as it
 * is read (copy_read); when that fails, read again through the block
 * (check_read) for check_file's verdict on a damaged file, the first
 * reading's error kept when the file passes (a failed read, or a file
 * that changed). */
static plx_status load_once(const bake_src *s, const unsigned char *h, const bake_layout *L, unsigned char *base,
                            size_t cap)
{
    char first[256];
    plx_status st = copy_read(s, h, L, base), st2;
    if (st == PLX_OK)
        return st;
    say(first, sizeof first, st, s->err && s->errlen ? s->err : "", 0, NULL, 0, NULL);
    st2 = check_read(s, h, L, base, cap < READ_BIG ? cap : READ_BIG);
    if (st2 != PLX_OK)
        return st2;
    return say(s->err, s->errlen, st, first, 0, NULL, 0, NULL);
}

plx_status plx_bake_block_size_read(plx_bake_read_fn read, void *user, uint64_t len, void *scratch, size_t scratch_len,
                                    size_t *block_bytes, char *err, size_t errlen)
{
    unsigned char h[BAKE_HEADER];
    bake_layout L;
    bake_src s;
    plx_status st;
    if (!read || !block_bytes)
        return say(err, errlen, PLX_E_INVALID, "plx_bake_block_size_read: read and block_bytes must not be NULL", 0,
                   NULL, 0, NULL);
    if ((st = src_open(&s, read, user, len, err, errlen, h, &L)) != PLX_OK)
        return st;
    if (scratch && scratch_len >= READ_SMALL &&
        (st = check_read(&s, h, &L, scratch, scratch_len & ~(size_t)31)) != PLX_OK)
        return st;
    *block_bytes = block_for(&L, h);
    if (err && errlen)
        err[0] = '\0';
    return PLX_OK;
}

plx_status plx_bake_load_read(void *mem, size_t size, const plx_config *cfg, plx_bake_read_fn read, void *user,
                              uint64_t len, plx_engine **out, char *err, size_t errlen)
{
    unsigned char h[BAKE_HEADER], small[READ_SMALL], *base = NULL;
    size_t cap = 0;
    bake_layout L;
    bake_src s;
    plx_status st, fits;
    if (out)
        *out = NULL;
    if (!mem || !out || !read)
        return say(err, errlen, PLX_E_INVALID, "plx_bake_load_read: mem, read and out must not be NULL", 0, NULL, 0,
                   NULL);
    if (cfg && (cfg->threads < 0 || cfg->threads > PLX_MAX_THREADS))
        return say(err, errlen, PLX_E_INVALID, "plx_bake_load_read: cfg->threads must be from 0 to PLX_MAX_THREADS",
                   0, NULL, 0, NULL);
    if ((st = src_open(&s, read, user, len, err, errlen, h, &L)) != PLX_OK)
        return st;
    /* when the image fits, read once into it and checked as it is read
     * (checked first, through the block, when the image is over four
     * times the file: its pages left out are zeroed as they pass, and a
     * damaged header of a small file asked to zero gigabytes before its
     * checksum was found wrong); else checked through the stack first,
     * then the block's error, as plx_bake_load */
    fits = place(mem, size, h, &L, &base, &cap, NULL, 0);
    if (fits == PLX_OK) {
        if (L.image / 4 > len)
            st = check_read(&s, h, &L, base, cap < READ_BIG ? cap : READ_BIG);
        if (st == PLX_OK)
            st = load_once(&s, h, &L, base, cap);
    } else if ((st = check_read(&s, h, &L, small, sizeof small)) == PLX_OK) {
        st = place(mem, size, h, &L, &base, &cap, err, errlen);
    }
    if (st != PLX_OK)
        return st;
    return finish(mem, base, cap, L.image, cfg, out, err, errlen);
}
