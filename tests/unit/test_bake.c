/* test_bake: bake files (src/api/bake.c, README "Bake files").
 *
 *  - Round trip: an engine prepared and traced (A), its twin (B), the bake
 *    written and loaded into a third block (C) at another address: vis,
 *    illum and render (street and aerial, with indirect light, bytes of the
 *    8-bit and float images) give identical bytes in A and C, and direct
 *    light and visibility equal an engine loaded from the GeoJSON (D).
 *  - Damaged files made from a real bake: every truncation length class,
 *    a flipped byte, another version, architecture and build, a block too
 *    small: the exact status and message, no engine.
 *  - The corpus tests/corpus/bake-*.plxb with exact outcomes.
 *  - A twin that is not laid out alike is refused.
 *  - The radiance atlas is filled while saving, its jobs reported to
 *    plx_port.progress: one start with the jobs, the workers' units
 *    summing to them, one end; frames of the loaded bake equal those of
 *    an engine that fills the atlas as its frames need it.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "../ref/ref_bake_sum.h"
#include "base/engine.h"
#include "render/render.h"
#include "render/atlas.h"
#include "photon/irradiance_cache.h"
#include "polarlux_port.h"
#include "ref_bake_sum.h"
#include "slow.h"

#define MEM ((size_t)64 << 20)
#define SCENE "fixtures/eixample-4x4.geojson"

typedef struct baked {
    void *ma, *mb;
    plx_engine *a, *b;
    unsigned char *file;
    size_t len;
} baked;

/* plx_port.progress counted (the workers call it: under a lock). */
static struct {
    pthread_mutex_t lock;
    uint64_t starts, ends, units, total, calls, bad;
} told = { PTHREAD_MUTEX_INITIALIZER, 0, 0, 0, 0, 0, 0 };

static void count_progress(void *ctx, const char *what, uint64_t n, uint64_t total)
{
    (void)ctx;
    pthread_mutex_lock(&told.lock);
    told.calls++;
    told.bad += strcmp(what, "radiance atlas") != 0;
    if (total == 0) {
        told.ends++;
    } else if (n == 0) {
        told.starts++;
        told.total = total;
    } else {
        told.units += n;
        told.bad += total != told.total;
    }
    pthread_mutex_unlock(&told.lock);
}

static plx_engine *make(void **mem, int twin, int aerial)
{
    static plx_port counting;
    plx_config cfg;
    plx_bake_opts o;
    plx_engine *e = NULL;
    assert_int_equal(posix_memalign(mem, 64, MEM), 0);
    memset(*mem, 0, MEM); /* the bake saves every byte of the used arena, padding included */
    plx_config_default(&cfg);
    counting = *plx_port_posix();
    counting.progress = count_progress;
    cfg.port = &counting;
    cfg.threads = 2; /* the atlas filled on two workers (test_atlas_in_bake) */
    cfg.render_max_width = 320;
    cfg.render_max_height = 240;
    cfg.lit_cache_bytes = 4u << 20;
    assert_int_equal(plx_engine_create(*mem, MEM, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, SCENE), PLX_OK);
    memset(&o, 0, sizeof o);
    o.aerial = aerial;
    o.aerial_m_per_texel = 2.0;
    o.twin = twin;
    assert_int_equal(plx_bake_prepare(e, &o), PLX_OK);
    return e;
}

static void bake_make(baked *k)
{
    size_t size = 0;
    uint64_t f;
    k->a = make(&k->ma, 0, 1);
    for (f = 1; f <= 3; f++)
        assert_int_equal(plx_indirect_step(k->a, 20000, f), PLX_OK);
    k->b = make(&k->mb, 1, 1);
    assert_int_equal(plx_bake_size(k->a, k->b, &size), PLX_OK);
    k->file = malloc(size);
    assert_non_null(k->file);
    assert_int_equal(plx_bake_save(k->a, k->b, k->file, size, &k->len), PLX_OK);
    assert_int_equal(k->len, size);
}

static void bake_free(baked *k)
{
    plx_engine_destroy(k->a);
    plx_engine_destroy(k->b);
    free(k->ma);
    free(k->mb);
    free(k->file);
}

/* One bake for the tests that read it (made once: the group's setup). */
static baked shared;

static int shared_make(void **state)
{
    (void)state;
    bake_make(&shared);
    return 0;
}

static int shared_free(void **state)
{
    (void)state;
    bake_free(&shared);
    return 0;
}

/* Loads a file into a fresh block at an address 16 bytes past 64-byte
 * alignment (the loader must shift it). */
static plx_engine *load(const unsigned char *file, size_t len, void **mem)
{
    size_t need = 0;
    char err[256];
    plx_config cfg;
    plx_engine *e = NULL;
    assert_int_equal(plx_bake_block_size(file, len, &need, err, sizeof err), PLX_OK);
    *mem = malloc(need + 64);
    assert_non_null(*mem);
    plx_config_default(&cfg);
    cfg.port = plx_port_posix();
    assert_int_equal(plx_bake_load((char *)*mem + 16, need + 48, &cfg, file, len, &e, err, sizeof err), PLX_OK);
    return e;
}

static const double pts[][2] = { { 298.6, 265.5 }, { 150.0, 3.0 }, { -30.0, 22.0 }, { 61.0, 61.0 }, { 400.0, 560.0 } };
#define NPTS (sizeof pts / sizeof pts[0])

static void same_vis(plx_engine *x, plx_engine *y)
{
    size_t i;
    for (i = 0; i < NPTS; i++) {
        plx_visibility u, v;
        plx_status s1 = plx_visibility_get(x, pts[i][0], pts[i][1], 30.0, 360.0, &u);
        double *xy;
        uint32_t *vis, n, nv;
        if (s1 != PLX_OK) {
            assert_int_equal(plx_visibility_get(y, pts[i][0], pts[i][1], 30.0, 360.0, &v), s1);
            continue;
        }
        n = u.nverts;
        nv = u.nvisible;
        xy = malloc(sizeof *xy * 2 * (n + 1));
        vis = malloc(sizeof *vis * (nv + 1));
        memcpy(xy, u.xy, sizeof *xy * 2 * n);
        memcpy(vis, u.visible, sizeof *vis * nv);
        assert_int_equal(plx_visibility_get(y, pts[i][0], pts[i][1], 30.0, 360.0, &v), PLX_OK);
        assert_memory_equal(&u.area, &v.area, sizeof u.area);
        assert_int_equal(v.nverts, n);
        assert_int_equal(v.nvisible, nv);
        assert_memory_equal(v.xy, xy, sizeof *xy * 2 * n);
        assert_memory_equal(v.visible, vis, sizeof *vis * nv);
        free(xy);
        free(vis);
    }
}

/* Ground points facing up on a grid over the scene: E_direct, E_indirect
 * and rgb byte for byte (the status too: points inside footprints fail). */
static void same_illum(plx_engine *x, plx_engine *y, int indirect)
{
    enum { N = 64 };
    double P[3 * N], Nn[3 * N], e1[N], i1[N], c1[3 * N], e2[N], i2[N], c2[3 * N];
    int k;
    for (k = 0; k < N; k++) {
        P[3 * k] = -30.0 + 590.0 * (k % 8) / 7.0 + 0.37;
        P[3 * k + 1] = -30.0 + 590.0 * (k / 8) / 7.0 + 0.61;
        P[3 * k + 2] = 0.0;
        Nn[3 * k] = Nn[3 * k + 1] = 0.0;
        Nn[3 * k + 2] = 1.0;
    }
    assert_int_equal(plx_illuminance(x, N, P, Nn, e1, indirect ? i1 : NULL, c1),
                     plx_illuminance(y, N, P, Nn, e2, indirect ? i2 : NULL, c2));
    assert_memory_equal(e1, e2, sizeof e1);
    assert_memory_equal(c1, c2, sizeof c1);
    if (indirect)
        assert_memory_equal(i1, i2, sizeof i1);
}

/* The tests' 160x120 cameras: aerial from (266, eye_y, eye_z) looking at
 * (266, 267, 0) (a view from above), or a street view by a lamp. */
static void fixed_camera(plx_camera *cam, int aerial, double eye_y, double eye_z)
{
    memset(cam, 0, sizeof *cam);
    cam->width = 160;
    cam->height = 120;
    cam->fov_deg = 60;
    if (aerial) {
        cam->eye[0] = cam->target[0] = 266.0;
        cam->eye[1] = eye_y;
        cam->target[1] = 267.0;
        cam->eye[2] = eye_z;
    } else {
        cam->eye[0] = 298.6; cam->eye[1] = 265.5; cam->eye[2] = 1.7;
        cam->target[0] = 261.8; cam->target[1] = 302.3; cam->target[2] = 3.0;
    }
}

static void same_render(plx_engine *x, plx_engine *y, int aerial, int no_indirect)
{
    plx_camera cam;
    plx_render_opts o;
    size_t px = 160 * 120;
    uint8_t *a8 = malloc(px * 3), *b8 = malloc(px * 3);
    float *af = malloc(sizeof(float) * px * 3), *bf = malloc(sizeof(float) * px * 3);
    fixed_camera(&cam, aerial, 266.0, 500.0);
    plx_render_opts_default(&o);
    o.aerial = aerial;
    o.aerial_m_per_texel = 2.0;
    o.no_indirect = no_indirect;
    assert_int_equal(plx_render(x, &cam, &o, a8, af, NULL), PLX_OK);
    assert_int_equal(plx_render(y, &cam, &o, b8, bf, NULL), PLX_OK);
    assert_memory_equal(a8, b8, px * 3);
    assert_memory_equal(af, bf, sizeof(float) * px * 3);
    free(a8); free(b8); free(af); free(bf);
}

static void test_round_trip(void **state)
{
    baked k = shared;
    void *mc, *md;
    plx_engine *c, *d;
    (void)state;
    int32_t w = 0, h = 0;
    c = load(k.file, k.len, &mc);
    assert_int_equal(plx_indirect_frames(c), 3);
    /* the largest frame is the bake's (its config's), not the default */
    assert_int_equal(plx_render_max_get(c, &w, &h), PLX_OK);
    assert_int_equal(w, 320);
    assert_int_equal(h, 240);
    assert_int_equal(plx_render_max_get(c, NULL, &h), PLX_E_INVALID);
    assert_int_equal(plx_render_max_get(NULL, &w, &h), PLX_E_INVALID);
    same_vis(k.a, c);
    same_illum(k.a, c, 1);
    same_render(k.a, c, 0, 0);
    same_render(k.a, c, 1, 0);
    /* against an engine that never saw a bake: direct light and visibility */
    d = make(&md, 0, 0);
    same_vis(d, c);
    same_illum(d, c, 0);
    same_render(d, c, 0, 1);
    /* a bake of the loaded engine's own twin-free state still loads alike twice */
    plx_engine_destroy(d);
    free(md);
    plx_engine_destroy(c);
    free(mc);
}

/* A bake file read through plx_bake_read_fn: bytes in memory, a read
 * that fails at call fail_at (0: none), and with flip_nth set, byte flip
 * changed (xor flip_mask) when a read reaches it the flip_nth time (the
 * file changed while the loader read it), and with flip_back, changed
 * back at the next read that reaches it (a change the loader's reading
 * saw that the file no longer holds). */
typedef struct mem_file {
    unsigned char *f;
    size_t len;
    int calls, fail_at, flip_nth, flip_back, seen;
    size_t flip, maxend; /* maxend: the furthest byte asked for, plus one */
    unsigned char flip_mask;
} mem_file;

static int mem_read(void *user, uint64_t off, void *buf, size_t n)
{
    mem_file *m = user;
    if (off + n > m->maxend)
        m->maxend = (size_t)(off + n);
    if (++m->calls == m->fail_at || off > m->len || n > m->len - off)
        return -1;
    if (m->flip_nth && off <= m->flip && m->flip < off + n) {
        ++m->seen;
        if (m->seen == m->flip_nth || (m->flip_back && m->seen == m->flip_nth + 1))
            m->f[m->flip] ^= m->flip_mask;
    }
    memcpy(buf, m->f + off, n);
    return 0;
}

/* A bake's first stored page's offset in the file (after the bitmap). */
static size_t pages_at(const unsigned char *f)
{
    uint64_t img;
    size_t npages;
    memcpy(&img, f + 40, 8);
    npages = (size_t)((img + 4095) / 4096);
    return 128 + (((npages + 7) / 8 + 7) & ~(size_t)7);
}

/* mf's file loaded through reads into mem (size bytes) with its byte
 * mf->flip changed at the nth reading that reaches it: refused, and read
 * once more for the verdict (the load reads a file once, and again only
 * when that reading fails). Changed for good, the file is damaged
 * (checksum mismatch); changed back at that next reading, the file
 * changed while it was read. */
static void expect_changed(void *mem, size_t size, mem_file *mf, int nth)
{
    char err[256];
    plx_engine *e = NULL;
    int back;
    for (back = 0; back <= 1; back++) {
        mf->flip_nth = nth;
        mf->flip_back = back;
        mf->calls = mf->seen = 0;
        e = NULL;
        assert_int_equal(plx_bake_load_read(mem, size, NULL, mem_read, mf, mf->len, &e, err, sizeof err),
                         PLX_E_PARSE);
        assert_null(e);
        assert_string_equal(err, back ? "corrupt bake file: it changed while it was read"
                                      : "corrupt bake file: checksum mismatch");
        assert_int_equal(mf->seen, nth + 1);
        if (!back)
            mf->f[mf->flip] ^= mf->flip_mask; /* the file as it was */
    }
}

/* The bake read through the caller's reads (plx_bake_load_read), at an
 * address 16 bytes past 64-byte alignment: the same answers and frames
 * as the loaded buffer's; its size-first call gives plx_bake_block_size's.
 * A read that fails says which bytes (PLX_E_IO), at every call of the
 * load's; a file changed between the two readings is refused. */
static void test_load_read(void **state)
{
    baked k = shared;
    void *mc, *mem;
    plx_engine *c, *d = NULL;
    size_t need = 0, need2 = 0;
    char err[256];
    mem_file mf;
    int calls, at;
    (void)state;
    memset(&mf, 0, sizeof mf);
    mf.f = malloc(k.len);
    memcpy(mf.f, k.file, k.len);
    mf.len = k.len;
    assert_int_equal(plx_bake_block_size(k.file, k.len, &need, err, sizeof err), PLX_OK);
    assert_int_equal(plx_bake_block_size_read(mem_read, &mf, k.len, NULL, 0, &need2, err, sizeof err), PLX_OK);
    assert_true(need2 == need);
    need2 = 0;
    {
        char scratch[1000]; /* not a multiple of 32: the reads' pieces need not be */
        assert_int_equal(plx_bake_block_size_read(mem_read, &mf, k.len, scratch, sizeof scratch, &need2, err, sizeof err),
                         PLX_OK);
    }
    assert_true(need2 == need);
    mem = malloc(need + 64);
    mf.calls = 0;
    assert_int_equal(plx_bake_load_read((char *)mem + 16, need + 48, NULL, mem_read, &mf, k.len, &d, err, sizeof err),
                     PLX_OK);
    assert_string_equal(err, "");
    calls = mf.calls;
    assert_true(calls > 3);
    c = load(k.file, k.len, &mc);
    assert_int_equal(plx_indirect_frames(d), 3);
    same_vis(c, d);
    same_illum(c, d, 1);
    same_render(c, d, 0, 0);
    same_render(c, d, 1, 0);
    plx_engine_destroy(d);
    for (at = 1; at <= calls; at++) {
        mf.calls = 0;
        mf.fail_at = at;
        d = (plx_engine *)&need;
        assert_int_equal(plx_bake_load_read(mem, need + 64, NULL, mem_read, &mf, k.len, &d, err, sizeof err), PLX_E_IO);
        assert_null(d);
        assert_non_null(strstr(err, "cannot read the bake file: "));
    }
    mf.fail_at = 0;
    /* the first byte of the second stored page (a word's lowest: 16 more
     * or less, inside the image if it is a pointer) changed as it is read */
    mf.flip = pages_at(k.file) + 4096;
    mf.flip_mask = 0x10;
    expect_changed(mem, need + 64, &mf, 1);
    /* a stored page's bit moved to a page not stored, in the bitmap the
     * pages are placed by (its second reading, after the checksum's),
     * the pages' bytes the same: it loaded as sound, the page's data one
     * page on */
    memcpy(mf.f, k.file, k.len);
    {
        size_t b;
        for (b = 0; b < (size_t)(pages_at(k.file) - 128) && (k.file[128 + b] == 0 || k.file[128 + b] == 0xff); b++)
            ;
        assert_true(b < (size_t)(pages_at(k.file) - 128)); /* a byte with stored and empty pages */
        mf.flip = 128 + b;
        mf.flip_mask = 0;
        for (at = 0; at < 7; at++) /* a stored page followed by one not stored: both bits flip */
            if (((k.file[128 + b] >> at) & 3u) == 1u)
                mf.flip_mask = (unsigned char)(3u << at);
        assert_true(mf.flip_mask != 0);
    }
    expect_changed(mem, need + 64, &mf, 2);
    plx_engine_destroy(c);
    free(mc);
    free(mem);
    free(mf.f);
}

/* A small file whose header names a large image, none of its pages
 * stored and a wrong checksum (a reviewer's: 64 KiB that named 2 GiB):
 * refused as damaged before the block is written (its pages left out
 * were zeroed first, 2 GiB touched in 8.6 s, before the checksum was
 * found wrong); resealed, the same image loads no further than its first
 * page ("no engine"). */
static void test_sparse_header(void **state)
{
    baked k = shared;
    const uint64_t img = (uint64_t)16 << 20;
    size_t npages = (size_t)(img / 4096), len = 128 + (((npages + 7) / 8 + 7) & ~(size_t)7), need, i, touched = 0;
    uint64_t zero = 0, len64 = len;
    unsigned char *f = calloc(1, len), *mem;
    char err[256];
    plx_engine *e = NULL;
    mem_file mf;
    (void)state;
    memcpy(f, k.file, 128);
    memcpy(f + 24, &len64, 8);
    memcpy(f + 40, &img, 8);
    memcpy(f + 48, &zero, 8); /* no relocations */
    memcpy(f + 80, &zero, 8); /* no stored pages */
    assert_int_equal(plx_bake_block_size_read(mem_read, &(mem_file){ .f = f, .len = len }, len, NULL, 0, &need, err,
                                              sizeof err), PLX_OK);
    assert_true(need > img);
    mem = malloc(need);
    memset(mem, 0xab, need);
    memset(&mf, 0, sizeof mf);
    mf.f = f;
    mf.len = len;
    assert_int_equal(plx_bake_load_read(mem, need, NULL, mem_read, &mf, len, &e, err, sizeof err), PLX_E_PARSE);
    assert_null(e);
    assert_string_equal(err, "corrupt bake file: checksum mismatch");
    for (i = 0; i < need; i++)
        touched += mem[i] != 0xab;
    assert_true(touched <= ((size_t)1 << 20)); /* the check's reads go through the block: 1 MiB at most */
    ref_bake_reseal(f, len);
    assert_int_equal(plx_bake_load_read(mem, need, NULL, mem_read, &mf, len, &e, err, sizeof err), PLX_E_PARSE);
    assert_string_equal(err, "corrupt bake file: no engine at the start of the image");
    free(mem);
    free(f);
}

/* A bitmap that names one stored page more than the file holds: refused
 * from the bitmap's count before any page is read (the pages were read
 * on, and the last read asked for bytes past the file's end, which a
 * caller's read need not guard against). */
static void test_bitmap_extra_bit(void **state)
{
    baked k = shared;
    size_t b, need;
    int bit;
    char err[256];
    plx_engine *e = NULL;
    mem_file mf;
    void *mem;
    (void)state;
    memset(&mf, 0, sizeof mf);
    mf.f = malloc(k.len);
    memcpy(mf.f, k.file, k.len);
    mf.len = k.len;
    for (b = 128; b < pages_at(k.file) && mf.f[b] == 0xff; b++)
        ;
    assert_true(b < pages_at(k.file) && mf.f[b] != 0xff);
    for (bit = 0; (mf.f[b] >> bit) & 1; bit++)
        ;
    mf.f[b] |= (unsigned char)(1u << bit);
    assert_int_equal(plx_bake_block_size(k.file, k.len, &need, err, sizeof err), PLX_OK);
    mem = malloc(need);
    assert_int_equal(plx_bake_load_read(mem, need, NULL, mem_read, &mf, k.len, &e, err, sizeof err), PLX_E_PARSE);
    assert_null(e);
    assert_string_equal(err, "corrupt bake file: inconsistent header");
    assert_true(mf.maxend <= k.len);
    free(mem);
    free(mf.f);
}

/* A bake whose last page, a part page, is stored (the saver leaves an
 * all-zero page out; a file may hold it): its bytes in the file past the
 * image are summed but not copied. Both loads read it as the file
 * without the page, and a byte changed there as it is read is
 * seen. */
static void test_last_page_stored(void **state)
{
    baked k = shared;
    uint64_t img, pages, total;
    size_t npages, pa, present = 0, p, nlen, need;
    unsigned char *g;
    void *mc, *mem;
    plx_engine *c, *d = NULL;
    char err[256];
    mem_file mf;
    (void)state;
    memcpy(&img, k.file + 40, 8);
    memcpy(&pages, k.file + 80, 8);
    npages = (size_t)((img + 4095) / 4096);
    pa = pages_at(k.file);
    assert_true(img % 4096 != 0);                                  /* a part page */
    assert_false((k.file[128 + (npages - 1) / 8] >> ((npages - 1) % 8)) & 1); /* left out by the saver */
    for (p = 0; p + 1 < npages; p++)
        present += (k.file[128 + p / 8] >> (p % 8)) & 1u;
    nlen = k.len + 4096;
    g = calloc(1, nlen);
    memcpy(g, k.file, pa + present * 4096);
    memset(g + pa + present * 4096 + (size_t)(img % 4096), 0x5a, 4096 - (size_t)(img % 4096)); /* past the image */
    memcpy(g + pa + (present + 1) * 4096, k.file + pa + present * 4096, k.len - pa - present * 4096);
    g[128 + (npages - 1) / 8] |= (unsigned char)(1u << ((npages - 1) % 8));
    pages++;
    total = nlen;
    memcpy(g + 80, &pages, 8);
    memcpy(g + 24, &total, 8);
    ref_bake_reseal(g, nlen);
    assert_int_equal(plx_bake_block_size(g, nlen, &need, err, sizeof err), PLX_OK);
    c = load(g, nlen, &mc);
    memset(&mf, 0, sizeof mf);
    mf.f = g;
    mf.len = nlen;
    mem = malloc(need);
    assert_int_equal(plx_bake_load_read(mem, need, NULL, mem_read, &mf, nlen, &d, err, sizeof err), PLX_OK);
    same_render(c, d, 1, 0);
    same_render(k.a, d, 0, 0);
    plx_engine_destroy(d);
    /* a byte past the image changed as it is read */
    mf.flip = pa + present * 4096 + 4095;
    mf.flip_mask = 0x01;
    expect_changed(mem, need, &mf, 1);
    plx_engine_destroy(c);
    free(mc);
    free(mem);
    free(g);
}

/* The radiance atlas: a bake made before its photons fills it whole while
 * saving (on two workers, its jobs reported to plx_port.progress), so the
 * loaded engine's frames fill nothing, and they equal, byte for byte,
 * those of an engine that never saw a bake and fills the charts each
 * frame reads as it draws it (atlas_frame_missing): a chart's values do
 * not depend on when, or by which worker, it was filled. */
static void test_atlas_in_bake(void **state)
{
    baked k = shared;
    void *mc, *md;
    plx_engine *c, *d;
    uint64_t f;
    int aerial;
    (void)state;
    assert_non_null(k.a->atlas);
    assert_true(k.a->atlas->todo == 0 && k.a->atlas->with_ind);
    assert_true(k.b->atlas->todo > 0); /* the twin: laid out alike, never filled */
    assert_true(k.a->atlas->fine == 2.0 && k.b->atlas->fine == 2.0);
    /* the fill, reported job by job (the twin reports none) */
    assert_int_equal(told.starts, 1);
    assert_int_equal(told.ends, 1);
    assert_int_equal(told.units, told.total);
    assert_int_equal(told.bad, 0);
    assert_true(told.calls == told.total + 2);
    c = load(k.file, k.len, &mc);
    assert_true(c->atlas->todo == 0);
    d = make(&md, 0, 0);
    for (f = 1; f <= 3; f++)
        assert_int_equal(plx_indirect_step(d, 20000, f), PLX_OK);
    for (aerial = 0; aerial <= 1; aerial++) {
        uint64_t before = d->atlas ? d->atlas->todo : 0;
        same_render(d, c, aerial, 0);
        assert_true(c->atlas->todo == 0);
        assert_true(d->atlas->fine == 2.0);
        assert_true(d->atlas->todo > 0 && (aerial == 0 || d->atlas->todo < before)); /* filled on demand */
    }
    plx_engine_destroy(d);
    free(md);
    plx_engine_destroy(c);
    free(mc);
}

/* A bake made after frames were drawn (street and aerial from the atlas,
 * a street view shading every pixel, on two workers) is the same bytes as
 * one made without them: what frames leave behind (frame buffers, the
 * bands' rasteriser state, the surfaces' maps, the cache's records) is
 * not saved. (Frames that take memory, anti-aliased ones or an aerial
 * view's light map, would need the twin to draw them too.) */
static void test_bake_after_frames(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    baked k;
    size_t size = 0;
    uint64_t f;
    int v;
    (void)state;
    k.a = make(&k.ma, 0, 1);
    for (f = 1; f <= 3; f++)
        assert_int_equal(plx_indirect_step(k.a, 20000, f), PLX_OK);
    for (v = 0; v < 3; v++) {
        plx_camera cam;
        plx_render_opts o;
        static uint8_t rgb[320 * 240 * 3];
        memset(&cam, 0, sizeof cam);
        cam.width = 320;
        cam.height = 240;
        cam.fov_deg = 60;
        cam.eye[0] = 298.6; cam.eye[1] = 265.5; cam.eye[2] = v == 2 ? 300.0 : 1.7;
        cam.target[0] = 261.8; cam.target[1] = 302.3; cam.target[2] = 3.0;
        plx_render_opts_default(&o);
        o.aerial = v == 2;
        o.per_pixel = v == 1;
        o.auto_exposure = 1;
        assert_int_equal(plx_render(k.a, &cam, &o, rgb, NULL, NULL), PLX_OK);
    }
    k.b = make(&k.mb, 1, 1);
    assert_int_equal(plx_bake_size(k.a, k.b, &size), PLX_OK);
    k.file = malloc(size);
    assert_non_null(k.file);
    assert_int_equal(plx_bake_save(k.a, k.b, k.file, size, &k.len), PLX_OK);
    assert_int_equal(k.len, shared.len);
    assert_memory_equal(k.file, shared.file, k.len);
    bake_free(&k);
}

/* Anti-aliasing of frames read from the radiance atlas (a loaded bake):
 * an aerial frame whose first sample has edges at more than half its
 * pixels takes every sample (PLX_AA_DENSE), and its bytes are aa_full's;
 * a street frame with fewer edges stays adaptive, and only the marked
 * pixels took the later samples. */
static void aa_frame(plx_engine *e, int aerial, double height, int full, uint8_t *rgb8, float *rgbf,
                     plx_render_info *info)
{
    plx_camera cam;
    plx_render_opts o;
    fixed_camera(&cam, aerial, 200.0, height);
    plx_render_opts_default(&o);
    o.auto_exposure = 1;
    o.aa = 2;
    o.aa_full = full;
    assert_int_equal(plx_render(e, &cam, &o, rgb8, rgbf, info), PLX_OK);
}

static size_t marked(const plx_engine *e, size_t px)
{
    size_t p, n = 0;
    for (p = 0; p < px; p++)
        n += e->aa_mask[p] != 0;
    return n;
}

static void test_aa_dense(void **state)
{
    baked k = shared;
    void *mc;
    plx_engine *c;
    plx_render_info ia, iff;
    size_t px = 160 * 120;
    uint8_t *a8 = malloc(px * 3), *f8 = malloc(px * 3);
    float *af = malloc(sizeof(float) * px * 3), *ff = malloc(sizeof(float) * px * 3);
    (void)state;
    c = load(k.file, k.len, &mc);
    /* aerial, from high enough that the blocks' edges fill the frame */
    aa_frame(c, 1, 400.0, 0, a8, af, &ia);
    print_message("aerial: %zu of %zu pixels marked\n", marked(c, px), px);
    assert_int_equal(ia.aa_adaptive, PLX_AA_DENSE);
    assert_true(marked(c, px) > px / 2);
    assert_true(ia.aa_later == 3 * px);
    aa_frame(c, 1, 400.0, 1, f8, ff, &iff);
    assert_int_equal(iff.aa_adaptive, PLX_AA_EVERY);
    assert_memory_equal(a8, f8, px * 3);
    assert_memory_equal(af, ff, sizeof(float) * px * 3);
    assert_true(ia.exposure == iff.exposure);
    /* a street frame: adaptive, the later samples at the marked pixels only */
    aa_frame(c, 0, 0.0, 0, a8, af, &ia);
    print_message("street: %zu of %zu pixels marked\n", marked(c, px), px);
    assert_int_equal(ia.aa_adaptive, PLX_AA_ADAPTIVE);
    assert_true(marked(c, px) <= px / 2 && marked(c, px) > 0);
    assert_true(ia.aa_later >= 3 * marked(c, px)); /* and the slivers the later samples found */
    aa_frame(c, 0, 0.0, 1, f8, ff, &iff);
    assert_true(memcmp(af, ff, sizeof(float) * px * 3) != 0); /* not the full pass: some pixels kept their first sample */
    plx_engine_destroy(c);
    free(mc);
    free(a8); free(f8); free(af); free(ff);
}

/* Anti-aliased frames from an atlas filled as they need it, against the
 * bake's complete one: bytes, floats and the later samples' pixel count.
 * The later samples fill what their marked pixels read (atlas_frame_missing
 * with the mask), which the first sample may not have met: a sliver seen
 * between pixel centres, a ground block a shifted sample point falls in
 * (test_atlas counts those fills). The cameras move 9 m apart along the
 * street, so each frame starts with some charts not filled. */
static void od_camera(plx_camera *cam, plx_render_opts *o, int q, int aa)
{
    fixed_camera(cam, 0, 0.0, 0.0);
    cam->eye[0] += 9.0 * q - 20.0 + 40.0 * (aa - 2);
    cam->target[0] += 9.0 * q - 20.0 + 40.0 * (aa - 2);
    cam->eye[1] += 5.0 * (q % 3) - 5.0;
    cam->target[1] += 5.0 * (q % 3) - 5.0;
    plx_render_opts_default(o);
    o->aerial_m_per_texel = 2.0; /* the bake's spacing: the on-demand atlas laid out alike */
    o->auto_exposure = q % 2;
    o->aa = aa;
}

static plx_engine *od_engine(void **mem)
{
    plx_engine *d = make(mem, 0, 0);
    uint64_t f;
    for (f = 1; f <= 3; f++)
        assert_int_equal(plx_indirect_step(d, 20000, f), PLX_OK);
    return d;
}

static void test_aa_on_demand(void **state)
{
    baked k = shared;
    void *mc, *md;
    plx_engine *c, *d;
    size_t px = 160 * 120;
    uint8_t *a8 = malloc(px * 3), *b8 = malloc(px * 3);
    float *af = malloc(sizeof(float) * px * 3), *bf = malloc(sizeof(float) * px * 3);
    uint64_t later = 0;
    int q, aa;
    (void)state;
    c = load(k.file, k.len, &mc);
    d = od_engine(&md);
    for (q = 0; q < 6; q++)
        for (aa = 2; aa <= 3; aa++) {
            plx_camera cam;
            plx_render_opts o;
            plx_render_info ic, id;
            od_camera(&cam, &o, q, aa);
            assert_int_equal(plx_render(c, &cam, &o, a8, af, &ic), PLX_OK);
            assert_int_equal(plx_render(d, &cam, &o, b8, bf, &id), PLX_OK);
            assert_int_equal(ic.aa_adaptive, id.aa_adaptive);
            assert_int_equal(ic.aa_later, id.aa_later);
            assert_memory_equal(a8, b8, px * 3);
            assert_memory_equal(af, bf, sizeof(float) * px * 3);
            later += id.aa_adaptive == PLX_AA_ADAPTIVE ? id.aa_later : 0;
        }
    print_message("on demand: 12 frames, %llu later-sample pixels shaded adaptively; %llu items left unfilled\n",
                  (unsigned long long)later, (unsigned long long)d->atlas->todo);
    assert_true(later > 0 && d->atlas->todo > 0);
    plx_engine_destroy(d);
    free(md);
    plx_engine_destroy(c);
    free(mc);
    free(a8); free(b8); free(af); free(bf);
}

/* ---- damaged files ----------------------------------------------------------- */

/* plx_bake_load_read of f (len bytes) into mem (size bytes): status want,
 * line msg, no engine. */
static void expect_read(void *mem, size_t size, const unsigned char *f, size_t len, plx_status want, const char *msg)
{
    char err[256];
    char want_msg[256];
    plx_engine *e = (plx_engine *)&want_msg;
    mem_file mf;
    snprintf(want_msg, sizeof want_msg, "%s", msg); /* msg may be the caller's err */
    memset(&mf, 0, sizeof mf);
    mf.f = malloc(len ? len : 1);
    memcpy(mf.f, f, len);
    mf.len = len;
    err[0] = '\0';
    assert_int_equal(plx_bake_load_read(mem, size, NULL, mem_read, &mf, len, &e, err, sizeof err), want);
    assert_null(e);
    assert_string_equal(err, want_msg);
    free(mf.f);
}

/* Every way of reading f: the same error and line (plx_bake_block_size_read
 * without scratch checks the header only: past it, it passes). */
static void expect_fail(const unsigned char *f, size_t len, plx_status want, const char *msg)
{
    char err[256];
    size_t need = 12345;
    void *mem = malloc(1 << 20);
    plx_engine *e = (plx_engine *)&need;
    mem_file mf;
    plx_status st;
    err[0] = '\0';
    assert_int_equal(plx_bake_block_size(f, len, &need, err, sizeof err), want);
    assert_string_equal(err, msg);
    err[0] = '\0';
    assert_int_equal(plx_bake_load(mem, 1 << 20, NULL, f, len, &e, err, sizeof err), want);
    assert_null(e);
    assert_string_equal(err, msg);
    expect_read(mem, 1 << 20, f, len, want, msg);
    memset(&mf, 0, sizeof mf);
    mf.f = malloc(len ? len : 1);
    memcpy(mf.f, f, len);
    mf.len = len;
    err[0] = '\0';
    st = plx_bake_block_size_read(mem_read, &mf, len, NULL, 0, &need, err, sizeof err);
    if (st != PLX_OK) {
        assert_int_equal(st, want);
        assert_string_equal(err, msg);
    }
    err[0] = '\0';
    {
        unsigned char scratch[4096];
        assert_int_equal(plx_bake_block_size_read(mem_read, &mf, len, scratch, sizeof scratch, &need, err, sizeof err),
                         want);
        assert_string_equal(err, msg);
    }
    free(mf.f);
    free(mem);
}

/* Two flipped bits pass no longer: format 2's checksum carried a word's
 * top bit only into its own top bit, so the top bits of two words of one
 * lane (32 bytes apart), or one of them in the unread bytes 72..79,
 * cancelled and the damaged file loaded (and crashed the frames: a
 * hostile-input pass). Those cases through the loader, then 300 random
 * pairs of bits through the README's checksum (ref_bake_sum). */
static void two_bit_flips(const baked *k, unsigned char *f)
{
    size_t body = k->len - 128, i, a, b;
    uint64_t seed = 0x2545f4914f6cdd1dull, sum = ref_bake_sum(k->file, k->len);
    for (i = 0; i < 2; i++) {
        a = i == 0 ? 79 : 128 + (body / 64) * 32 + 7; /* the reserved field, or a word of the body */
        b = a + 32;                                   /* the same lane's next word */
        memcpy(f, k->file, k->len);
        f[a] ^= 0x80;
        f[b] ^= 0x80;
        expect_fail(f, k->len, PLX_E_PARSE, "corrupt bake file: checksum mismatch");
    }
    for (i = 0; i < 300; i++) {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        a = (size_t)(seed % (k->len * 8));
        b = (size_t)((seed >> 21) % (k->len * 8));
        if (a == b || (a / 8 >= 32 && a / 8 < 40) || (b / 8 >= 32 && b / 8 < 40)) /* the checksum's own field */
            continue;
        memcpy(f, k->file, k->len);
        f[a / 8] ^= (unsigned char)(1u << (a % 8));
        f[b / 8] ^= (unsigned char)(1u << (b % 8));
        assert_true(ref_bake_sum(f, k->len) != sum);
    }
}

static void test_damaged(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    baked k = shared;
    unsigned char *f;
    char msg[200];
    size_t need;
    char err[256];
    void *mem;
    plx_engine *e = NULL;
    uint64_t sum;
    (void)state;
    f = malloc(k.len);
    /* the checksum is what the README says */
    memcpy(&sum, k.file + 32, 8);
    assert_true(sum == ref_bake_sum(k.file, k.len));
    expect_fail(k.file, 0, PLX_E_PARSE, "not a polarlux bake file (no PLXBAKE magic)");
    /* a success empties err (an earlier call's line stayed) */
    strcpy(err, "stale");
    assert_int_equal(plx_bake_block_size(k.file, k.len, &need, err, sizeof err), PLX_OK);
    assert_string_equal(err, "");
    expect_fail(k.file, 100, PLX_E_PARSE, "truncated bake file: 100 bytes, shorter than its 128-byte header");
    snprintf(msg, sizeof msg, "truncated bake file: %zu bytes, the header says %zu", k.len / 2, k.len);
    expect_fail(k.file, k.len / 2, PLX_E_PARSE, msg);
    snprintf(msg, sizeof msg, "truncated bake file: %zu bytes, the header says %zu", k.len - 1, k.len);
    expect_fail(k.file, k.len - 1, PLX_E_PARSE, msg);
    /* a flipped bit anywhere in the body */
    memcpy(f, k.file, k.len);
    f[k.len / 3] ^= 0x10;
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: checksum mismatch");
    memcpy(f, k.file, k.len);
    f[k.len - 1] ^= 0x01;
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: checksum mismatch");
    two_bit_flips(&k, f);
    /* header fields */
    memcpy(f, k.file, k.len);
    f[8] = 4;
    expect_fail(f, k.len, PLX_E_UNSUPPORTED, "bake format version 4, this polarlux reads version 3; bake the scene again");
    /* a damaged version, byte-order or length field is a damaged file (a
     * kiosk pass's flipped bits there read "version 16777219", "another
     * architecture" and "truncated") */
    memcpy(f, k.file, k.len);
    f[11] ^= 0x01;
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: damaged header (its version field reads 16777219)");
    memcpy(f, k.file, k.len);
    f[12] ^= 0xff;
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: damaged header (its byte-order field is neither this "
                "machine's nor the other)");
    memcpy(f, k.file, k.len);
    f[12] = 1, f[13] = 2, f[14] = 3, f[15] = 4; /* written in the other byte order */
    expect_fail(f, k.len, PLX_E_UNSUPPORTED, "bake made on another architecture (its byte order differs); bake the "
                "scene again on this machine");
    memcpy(f, k.file, k.len);
    f[26] ^= 0x40;
    snprintf(msg, sizeof msg, "corrupt bake file: damaged header (its length field reads %zu bytes, its layout the "
             "file's %zu)", k.len ^ ((size_t)0x40 << 16), k.len);
    expect_fail(f, k.len, PLX_E_PARSE, msg);
    /* other sizes or another build: so only when the checksum holds
     * (the file resealed, as that build would have written it); a
     * damaged byte there is a damaged file (a kiosk pass's flipped byte
     * at 20 was blamed on the build) */
    memcpy(f, k.file, k.len);
    f[16] = 4;
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: checksum mismatch (in its header)");
    ref_bake_reseal(f, k.len);
    expect_fail(f, k.len, PLX_E_UNSUPPORTED, "bake made on another architecture (its pointer, size_t, double or "
                "long sizes differ); bake the scene again on this machine");
    memcpy(f, k.file, k.len);
    f[20] ^= 1;
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: checksum mismatch (in its header)");
    ref_bake_reseal(f, k.len);
    expect_fail(f, k.len, PLX_E_UNSUPPORTED, "bake made by a different build of polarlux (its structures differ); "
                "bake the scene again");
    memcpy(f, k.file, k.len);
    f[48] ^= 1; /* relocation count: the layout no longer adds up */
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: inconsistent header");
    /* the saved alignment of the block is not one an engine can start at
     * (found by fuzz_bake: the engine was read from a misaligned address) */
    memcpy(f, k.file, k.len);
    f[56] = (unsigned char)(f[56] + 7) & 63;
    ref_bake_reseal(f, k.len);
    expect_fail(f, k.len, PLX_E_PARSE, "corrupt bake file: inconsistent header");
    /* the renderer's root pointer moved off its alignment, resealed (a
     * forged file: the load itself then bound the renderer's code at a
     * misaligned address, a fault under UBSan and on strict machines) */
    {
        uint64_t img, w;
        size_t npages, pages_at, at;
        memcpy(f, k.file, k.len);
        memcpy(&img, f + 40, 8);
        npages = (size_t)((img + 4095) / 4096);
        pages_at = 128 + (((npages + 7) / 8 + 7) & ~(size_t)7);
        assert_true(f[128] & 1); /* page 0, the engine's, is stored */
        at = pages_at + offsetof(struct plx_engine, rd);
        memcpy(&w, f + at, 8);
        assert_true(w != 0 && w % 8 == 0); /* an offset into the image */
        w += 4;
        memcpy(f + at, &w, 8);
        ref_bake_reseal(f, k.len);
        assert_int_equal(plx_bake_block_size(f, k.len, &need, err, sizeof err), PLX_OK); /* the header is sound */
        mem = malloc(need);
        e = (plx_engine *)&need;
        assert_int_equal(plx_bake_load(mem, need, NULL, f, k.len, &e, err, sizeof err), PLX_E_PARSE);
        assert_null(e);
        assert_string_equal(err, "corrupt bake file: no engine at the start of the image");
        expect_read(mem, need, f, k.len, PLX_E_PARSE, "corrupt bake file: no engine at the start of the image");
        free(mem);
    }
    /* a block too small */
    assert_int_equal(plx_bake_block_size(k.file, k.len, &need, err, sizeof err), PLX_OK);
    mem = malloc(1 << 20);
    assert_int_equal(plx_bake_load(mem, 1 << 20, NULL, k.file, k.len, &e, err, sizeof err), PLX_E_NOMEM);
    assert_null(e);
    assert_non_null(strstr(err, "the block is too small for the bake: it needs "));
    expect_read(mem, 1 << 20, k.file, k.len, PLX_E_NOMEM, err);
    free(mem);
    free(f);
}

/* ---- the corpus ----------------------------------------------------------------- */

typedef struct corpus_row {
    const char *file;
    plx_status st;
    const char *msg;
} corpus_row;

static const corpus_row corpus[] = {
    { "bake-empty.plxb", PLX_E_PARSE, "not a polarlux bake file (no PLXBAKE magic)" },
    { "bake-geojson.plxb", PLX_E_PARSE, "not a polarlux bake file (no PLXBAKE magic)" },
    { "bake-magic-only.plxb", PLX_E_PARSE, "truncated bake file: 8 bytes, shorter than its 128-byte header" },
    { "bake-version-99.plxb", PLX_E_UNSUPPORTED,
      "bake format version 99, this polarlux reads version 3; bake the scene again" },
    /* a bake of before 2026-11-30 evening (its slanted walls too dark: atlas_fill.c's wall_site) */
    { "bake-version-1.plxb", PLX_E_UNSUPPORTED,
      "bake format version 1, this polarlux reads version 3; bake the scene again" },
    /* a bake of before the checksum's rotation (2026-11-30 night) */
    { "bake-version-2.plxb", PLX_E_UNSUPPORTED,
      "bake format version 2, this polarlux reads version 3; bake the scene again" },
    { "bake-big-endian.plxb", PLX_E_UNSUPPORTED,
      "bake made on another architecture (its byte order differs); bake the scene again on this machine" },
    { "bake-32bit.plxb", PLX_E_UNSUPPORTED,
      "bake made on another architecture (its pointer, size_t, double or long sizes differ); "
      "bake the scene again on this machine" },
};

static void test_corpus(void **state)
{
    size_t i;
    (void)state;
    for (i = 0; i < sizeof corpus / sizeof corpus[0]; i++) {
        char path[256];
        unsigned char buf[4096];
        size_t n;
        FILE *fp;
        snprintf(path, sizeof path, "tests/corpus/%s", corpus[i].file);
        fp = fopen(path, "rb");
        if (!fp)
            fail_msg("cannot open %s", path);
        n = fread(buf, 1, sizeof buf, fp);
        fclose(fp);
        expect_fail(buf, n, corpus[i].st, corpus[i].msg);
    }
}

static void test_twin_mismatch(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    void *ma, *mb;
    plx_engine *a, *b;
    size_t size;
    (void)state;
    a = make(&ma, 0, 1);
    b = make(&mb, 1, 0); /* no light map: laid out otherwise */
    assert_int_equal(plx_bake_size(a, b, &size), PLX_E_INVALID);
    assert_non_null(strstr(plx_last_error(a), "the twin engine is not laid out as this one"));
    /* the whole sentence (a 200-byte buffer cut it before its end) */
    assert_non_null(strstr(plx_last_error(a), "render them on both engines or on neither)"));
    assert_int_equal(plx_bake_size(a, a, &size), PLX_E_INVALID);
    assert_int_equal(plx_bake_size(a, NULL, &size), PLX_E_INVALID);
    plx_engine_destroy(a);
    plx_engine_destroy(b);
    free(ma);
    free(mb);
}

/* The bake's bytes inside the block the engine is loaded into: refused
 * before a byte of the block is written (the load copies the image over
 * the block from its start: it read the file after overwriting it, and
 * reported a corrupt bake), the file's bytes as they were. */
static void test_file_inside_block(void **state)
{
    size_t need = 0;
    char err[256];
    unsigned char *blk;
    plx_engine *e = NULL;
    (void)state;
    assert_int_equal(plx_bake_block_size(shared.file, shared.len, &need, err, sizeof err), PLX_OK);
    blk = malloc(need + shared.len);
    assert_non_null(blk);
    memcpy(blk, shared.file, shared.len); /* at the block's start */
    assert_int_equal(plx_bake_load(blk, need, NULL, blk, shared.len, &e, err, sizeof err), PLX_E_INVALID);
    assert_null(e);
    assert_non_null(strstr(err, "the bake's bytes lie inside the block"));
    assert_memory_equal(blk, shared.file, shared.len);
    memcpy(blk + need - 8, shared.file, shared.len); /* straddling its end */
    assert_int_equal(plx_bake_load(blk, need, NULL, blk + need - 8, shared.len, &e, err, sizeof err),
                     PLX_E_INVALID);
    memcpy(blk + need, shared.file, shared.len); /* just past it: loads */
    assert_int_equal(plx_bake_load(blk, need, NULL, blk + need, shared.len, &e, err, sizeof err), PLX_OK);
    plx_engine_destroy(e);
    free(blk);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_load_read),
        cmocka_unit_test(test_last_page_stored),
        cmocka_unit_test(test_sparse_header),
        cmocka_unit_test(test_bitmap_extra_bit),
        cmocka_unit_test(test_atlas_in_bake),
        cmocka_unit_test(test_bake_after_frames),
        cmocka_unit_test(test_aa_dense),
        cmocka_unit_test(test_aa_on_demand),
        cmocka_unit_test(test_damaged),
        cmocka_unit_test(test_corpus),
        cmocka_unit_test(test_twin_mismatch),
        cmocka_unit_test(test_file_inside_block),
    };
    return cmocka_run_group_tests(tests, shared_make, shared_free);
}
