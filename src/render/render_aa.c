/* render_aa: adaptive anti-aliasing (render_aa.h): the samples' sums, the
 * marks of the pixels to sample again, the 2 x 2 sums at the marked pixels. */
#include <string.h>

#include "render/render_aa.h"
#include "render/render_int.h"

/* A pixel's surface as the mask compares it: the ground and the sky are
 * one (a later sample's ground pixels may not carry the ground's id yet). */
static uint32_t mask_class(uint32_t id)
{
    return id == MESH_SURF_GROUND ? MESH_SURF_NONE : id;
}

/* sum[p] += lin[p] for the n values, eight at a time in a loop of fixed
 * length (GCC vectorises those at -O2, not loops of unknown length); each
 * sum the same float operation as one at a time. */
#define AA_LANES 8
static void aa_add(float *restrict sum, const float *restrict lin, size_t n)
{
    size_t p;
    int k;
    for (p = 0; p + AA_LANES <= n; p += AA_LANES)
        for (k = 0; k < AA_LANES; k++)
            sum[p + k] += lin[p + k];
    for (; p < n; p++)
        sum[p] += lin[p];
}

/* sum[p] times inv, rounded to float, as aa_add. */
static void aa_scale(float *restrict sum, size_t n, double inv)
{
    size_t p;
    int k;
    for (p = 0; p + AA_LANES <= n; p += AA_LANES)
        for (k = 0; k < AA_LANES; k++)
            sum[p + k] = (float)(sum[p + k] * inv);
    for (; p < n; p++)
        sum[p] = (float)(sum[p] * inv);
}

#define AA_CHUNK 65536          /* values a job of the sums and the mask's ids */

typedef struct aa_job {
    float *sum;
    const float *lin;           /* NULL: scale by inv */
    size_t n;
    double inv;
    int copy;                   /* with lin: sum = lin */
} aa_job;

/* sum[p] = lin[p] for the n values, eight at a time in a loop of fixed
 * length. */
static void aa_copy(float *restrict sum, const float *restrict lin, size_t n)
{
    size_t p;
    int k;
    for (p = 0; p + AA_LANES <= n; p += AA_LANES)
        for (k = 0; k < AA_LANES; k++)
            sum[p + k] = lin[p + k];
    for (; p < n; p++)
        sum[p] = lin[p];
}

static void aa_chunk(void *arg, int worker, uint32_t k)
{
    aa_job *jb = arg;
    size_t p0 = (size_t)k * AA_CHUNK, m = jb->n - p0 < AA_CHUNK ? jb->n - p0 : AA_CHUNK;
    (void)worker;
    if (jb->lin && jb->copy)
        aa_copy(jb->sum + p0, jb->lin + p0, m);
    else if (jb->lin)
        aa_add(jb->sum + p0, jb->lin + p0, m);
    else
        aa_scale(jb->sum + p0, m, jb->inv);
}

/* One of the sums over n values on the workers (aa_chunk). */
static void aa_run(const render_opts *o, float *sum, const float *lin, size_t n, double inv, int copy)
{
    aa_job jb;
    jb.sum = sum;
    jb.lin = lin;
    jb.n = n;
    jb.inv = inv;
    jb.copy = copy;
    run_jobs(o, (uint32_t)((n + AA_CHUNK - 1) / AA_CHUNK), aa_chunk, &jb);
}

void render_aa_copy(const render_opts *o, float *sum, const float *lin, size_t n)
{
    aa_run(o, sum, lin, n, 1.0, 1);
}

void render_aa_add(const render_opts *o, float *sum, const float *lin, size_t n)
{
    aa_run(o, sum, lin, n, 1.0, 0);
}

void render_aa_scale(const render_opts *o, float *sum, size_t n, double inv)
{
    aa_run(o, sum, NULL, n, inv, 0);
}

/* ---- 2 x 2 sums at the marked pixels (render_aa_add_marked, render_tonemap_kept) ---- */

#define KEPT_PIXELS 16384       /* pixels a job */

/* The first of i .. e - 1 whose byte is (not) 0 when want is 1 (0); e:
 * none. Eight bytes a test where they are all 0 (want 1), or all 1 (want
 * 0; bytes 0 or 1 then). */
static size_t byte_next(const uint8_t *b, size_t i, size_t e, int want)
{
    const uint64_t all = want ? 0 : UINT64_C(0x0101010101010101);
    uint64_t q;
    while (i + 8 <= e && (memcpy(&q, b + i, sizeof q), q == all))
        i += 8;
    while (i < e && (b[i] != 0) != want)
        i++;
    return i;
}

typedef struct marked_job {
    const render *r;
    float *sum;
    const float *lin;
    uint8_t *mask;
    const uint8_t *cmask;
    size_t px;
    int before;
    int far;                    /* render_tonemap_kept: a value beyond +-TONEMAP_FAR or NaN somewhere */
    uint8_t *rgb8;
} marked_job;

static size_t job_end(size_t k, size_t px)
{
    return (k + 1) * KEPT_PIXELS < px ? (k + 1) * KEPT_PIXELS : px;
}

/* Job k of render_aa_add_marked: each run of marked pixels, its new
 * marks caught up, then its values' adds. */
static void add_marked_chunk(void *arg, int worker, uint32_t k)
{
    const marked_job *jb = arg;
    float *restrict s = jb->sum;
    const float *restrict lin = jb->lin;
    uint8_t *mask = jb->mask;
    size_t p1 = job_end(k, jb->px), i, e, q;
    (void)worker;
    for (i = byte_next(mask, (size_t)k * KEPT_PIXELS, p1, 1); i < p1; i = byte_next(mask, e, p1, 1)) {
        e = byte_next(mask, i, p1, 0);
        for (q = i; q < e; q++)
            if (mask[q] == 2) { /* newly marked: the samples before added its first value */
                int c, t;
                for (c = 0; c < 3; c++) {
                    float v = s[3 * q + (size_t)c];
                    for (t = 0; t < jb->before; t++)
                        s[3 * q + (size_t)c] += v;
                }
                mask[q] = 1;
            }
        for (q = 3 * i; q < 3 * e; q++)
            s[q] += lin[q];
    }
}

void render_aa_add_marked(const render_opts *o, float *sum, const float *lin, uint8_t *mask, size_t px,
                          int before)
{
    marked_job jb;
    memset(&jb, 0, sizeof jb);
    jb.sum = sum;
    jb.lin = lin;
    jb.mask = mask;
    jb.px = px;
    jb.before = before;
    run_jobs(o, (uint32_t)((px + KEPT_PIXELS - 1) / KEPT_PIXELS), add_marked_chunk, &jb);
}

/* An unmarked value v's dense sums: ((v + v) + v) + v times 1/4. */
static float dense_2x2(float v)
{
    float s = v;
    s += v;
    s += v;
    s += v;
    return (float)(s * 0.25);
}

/* Job k of render_tonemap_kept: each run of marked pixels scaled and
 * mapped again; with far, first each unmarked value beyond the limit
 * summed the dense way and mapped again (no real frame has one). */
static void kept_chunk(void *arg, int worker, uint32_t k)
{
    const marked_job *jb = arg;
    size_t p0 = (size_t)k * KEPT_PIXELS, p1 = job_end(k, jb->px), i, e, q;
    (void)worker;
    if (jb->far)
        for (q = 3 * p0; q < 3 * p1; q++)
            if (!jb->cmask[q / 3] && tonemap_far(jb->sum[q]) /* its four-fold sum need not give it back */) {
                jb->sum[q] = dense_2x2(jb->sum[q]);
                tonemap_apply(jb->r->tm, jb->r->thr, jb->sum, q, q + 1, jb->rgb8);
            }
    for (i = byte_next(jb->cmask, p0, p1, 1); i < p1; i = byte_next(jb->cmask, e, p1, 1)) {
        e = byte_next(jb->cmask, i, p1, 0);
        for (q = 3 * i; q < 3 * e; q++)
            jb->sum[q] = (float)(jb->sum[q] * 0.25);
        tonemap_apply(jb->r->tm, jb->r->thr, jb->sum, 3 * i, 3 * e, jb->rgb8);
    }
}

void render_tonemap_kept(render *r, float *sum, const uint8_t *mask, size_t px, int far, double ex, int curve,
                         uint8_t *rgb8, const render_opts *o)
{
    marked_job jb;
    memset(&jb, 0, sizeof jb);
    tonemap_table_set(r->tm, r->thr, ex, curve);
    jb.far = far;
    jb.r = r;
    jb.sum = sum;
    jb.cmask = mask;
    jb.px = px;
    jb.rgb8 = rgb8;
    run_jobs(o, (uint32_t)((px + KEPT_PIXELS - 1) / KEPT_PIXELS), kept_chunk, &jb);
}

/* The mark a pixel's byte m takes when its surface is (d = 1) or is not
 * (d = 0) another than the first sample's: a marked pixel keeps its
 * byte, an unmarked one takes nw when d. */
static inline uint8_t mark_new(uint8_t m, uint8_t d, uint8_t nw)
{
    return (uint8_t)(m | (uint8_t)((m == 0) & d) * nw);
}

/* Marks (mark_new, byte nw) the n pixels whose surface in id is not the
 * one in id0, sixteen at a time in a loop of fixed length (vectorised by
 * GCC at -O2). */
#define MASK_LANES 16
static void mask_ids(uint8_t *restrict mask, const uint32_t *restrict id, const uint32_t *restrict id0, size_t n,
                     uint8_t nw)
{
    size_t p;
    int k;
    for (p = 0; p + MASK_LANES <= n; p += MASK_LANES)
        for (k = 0; k < MASK_LANES; k++)
            mask[p + k] = mark_new(mask[p + k], (uint8_t)(mask_class(id[p + k]) != mask_class(id0[p + k])), nw);
    for (; p < n; p++)
        mask[p] = mark_new(mask[p], (uint8_t)(mask_class(id[p]) != mask_class(id0[p])), nw);
}

typedef struct ids_job {
    const render *r;
    const render_opts *o;
} ids_job;

static void mask_ids_chunk(void *arg, int worker, uint32_t k)
{
    const ids_job *jb = arg;
    size_t px = (size_t)jb->r->w * (size_t)jb->r->h, p0 = (size_t)k * AA_CHUNK;
    (void)worker;
    mask_ids(jb->o->mask + p0, jb->r->id + p0, jb->o->mask_id + p0, px - p0 < AA_CHUNK ? px - p0 : AA_CHUNK,
             jb->o->mask_new ? jb->o->mask_new : 1);
}

/* Marks the pixels whose surface is not the first sample's (by chunks on
 * the workers), and those of the glows this sample sees. */
void render_aa_mask_update(render *r, const render_opts *o)
{
    size_t px = (size_t)r->w * (size_t)r->h;
    if (o->mask_id) {
        ids_job jb;
        jb.r = r;
        jb.o = o;
        run_jobs(o, (uint32_t)((px + AA_CHUNK - 1) / AA_CHUNK), mask_ids_chunk, &jb);
    }
    if (!o->no_glow)
        (void)glow_mark(r, o->mask, o->mask_new ? o->mask_new : 1);
}

/* The pairs of 8-neighbours a pixel starts (each pair once, from its
 * upper or left pixel), as bits of the first pass. */
#define MASK_RIGHT 1u
#define MASK_DOWN 2u
#define MASK_DOWN_RIGHT 4u
#define MASK_DOWN_LEFT 8u
#define MASK_ROWS 16    /* rows a job */

typedef struct mask_job {
    const render *r;
    const uint8_t *rgb;
    const uint32_t *id;         /* the frame's ids (render.id) */
    uint32_t *id0;              /* their copy, row by row */
    uint8_t *bits, *out;
    unsigned level;
    size_t marked[RENDER_MAX_WORKERS]; /* marks, by worker */
} mask_job;

/* Whether bytes a and b are more than level L apart. */
static inline uint8_t far8(uint8_t a, uint8_t b, uint8_t L)
{
    uint8_t d = a > b ? (uint8_t)(a - b) : (uint8_t)(b - a);
    return d > L;
}

/* Whether the pixels at bytes a and b differ: surface ids ia and ib, or a
 * channel more than level apart. */
static int px_differ(const uint8_t *a, const uint8_t *b, uint32_t ia, uint32_t ib, uint8_t level)
{
    return ia != ib || far8(a[0], b[0], level) || far8(a[1], b[1], level) || far8(a[2], b[2], level);
}

/* The pairs pixel i of a row starts (c: the row's bytes, ic: its ids; n,
 * in: the row below, when down) that differ (px_differ). */
static unsigned pair_bits(const uint8_t *c, const uint8_t *n, const uint32_t *ic, const uint32_t *in, int32_t i,
                          int32_t w, int down, uint8_t level)
{
    const uint8_t *pc = c + 3 * (size_t)i, *pn = down ? n + 3 * (size_t)i : pc;
    unsigned b = 0;
    if (i + 1 < w && px_differ(pc, pc + 3, ic[i], ic[i + 1], level))
        b |= MASK_RIGHT;
    if (down) {
        if (i + 1 < w && px_differ(pc, pn + 3, ic[i], in[i + 1], level))
            b |= MASK_DOWN_RIGHT;
        if (px_differ(pc, pn, ic[i], in[i], level))
            b |= MASK_DOWN;
        if (i > 0 && px_differ(pc, pn - 3, ic[i], in[i - 1], level))
            b |= MASK_DOWN_LEFT;
    }
    return b;
}

/* pair_bits for MASK_CHUNK pixels of a row with a row below, none on the
 * frame's left or right edge (c, n, ic, in and bt at the first of them):
 * the channels' tests byte by byte and the ids' pixel by pixel, in loops
 * of fixed length that GCC vectorises at -O2, then each pixel's three
 * channels or-ed together. */
#define MASK_CHUNK 64
static void pair_bits_chunk(const uint8_t *restrict c, const uint8_t *restrict n, const uint32_t *restrict ic,
                            const uint32_t *restrict in, uint8_t level, uint8_t *restrict bt)
{
    uint8_t f[3 * MASK_CHUNK + 2], g[3 * MASK_CHUNK];
    uint32_t t[MASK_CHUNK];
    int k;
    for (k = 0; k < 3 * MASK_CHUNK; k++) {
        uint8_t a = c[k];
        f[k] = (uint8_t)(far8(a, c[k + 3], level) | far8(a, n[k], level) << 1 | far8(a, n[k + 3], level) << 2 |
                         far8(a, n[k - 3], level) << 3);
    }
    for (k = 0; k < MASK_CHUNK; k++) { /* in 32-bit lanes, narrowed once below */
        uint32_t x = ic[k];
        t[k] = (uint32_t)(x != ic[k + 1]) | (uint32_t)(x != in[k]) << 1 | (uint32_t)(x != in[k + 1]) << 2 |
               (uint32_t)(x != in[k - 1]) << 3;
    }
    f[3 * MASK_CHUNK] = f[3 * MASK_CHUNK + 1] = 0;
    for (k = 0; k < 3 * MASK_CHUNK; k++) /* each byte's with the next two: one read a pixel below */
        g[k] = (uint8_t)(f[k] | f[k + 1] | f[k + 2]);
    for (k = 0; k < MASK_CHUNK; k++)
        bt[k] = (uint8_t)(t[k] | g[3 * k]);
}

/* Rows of job k: for each pixel, which of the pairs it starts (right,
 * down, down-right, down-left) differ (pair_bits): chunks of MASK_CHUNK
 * pixels inside the frame with a row below, the rest one by one. */
static void mask_bits_rows(void *arg, int worker, uint32_t k)
{
    const mask_job *jb = arg;
    int32_t w = jb->r->w, h = jb->r->h, i, j, j1 = (int32_t)(k + 1) * MASK_ROWS;
    uint8_t level = (uint8_t)jb->level;
    (void)worker;
    for (j = (int32_t)k * MASK_ROWS; j < j1 && j < h; j++) {
        const uint8_t *c = jb->rgb + 3 * (size_t)j * (size_t)w, *n = c + 3 * (size_t)w;
        const uint32_t *ic = jb->id + (size_t)j * (size_t)w, *in = ic + w;
        uint8_t *bt = jb->bits + (size_t)j * (size_t)w;
        int down = j + 1 < h;
        memcpy(jb->id0 + (size_t)j * (size_t)w, ic, (size_t)w * sizeof *ic);
        i = 0;
        if (down && w >= MASK_CHUNK + 2) {
            bt[0] = (uint8_t)pair_bits(c, n, ic, in, 0, w, down, level);
            for (i = 1; i < w - 1; i += MASK_CHUNK) {
                i = i + MASK_CHUNK <= w - 1 ? i : w - 1 - MASK_CHUNK; /* the last overlaps the one before */
                pair_bits_chunk(c + 3 * (size_t)i, n + 3 * (size_t)i, ic + i, in + i, level, bt + i);
            }
        }
        for (; i < w; i++)
            bt[i] = (uint8_t)pair_bits(c, n, ic, in, i, w, down, level);
    }
}

/* A pixel's mark from the pairs' bits bt (at it, its row's stride w): a
 * pair it starts differs, or one that ends at it (from its left, upper,
 * upper-left or upper-right neighbour). */
static uint8_t mark_at(const uint8_t *bt, int32_t i, int32_t j, int32_t w)
{
    size_t ws = (size_t)w;
    unsigned m = bt[0] != 0;
    if (i > 0)
        m |= (bt[-1] & MASK_RIGHT) != 0;
    if (j > 0) {
        m |= (bt[-(ptrdiff_t)ws] & MASK_DOWN) != 0;
        if (i > 0)
            m |= (bt[-(ptrdiff_t)ws - 1] & MASK_DOWN_RIGHT) != 0;
        if (i + 1 < w)
            m |= (bt[-(ptrdiff_t)ws + 1] & MASK_DOWN_LEFT) != 0;
    }
    return (uint8_t)m;
}

/* mark_at for MASK_CHUNK pixels of a row with a row above, none on the
 * frame's left or right edge (bt, up: the row's bits and the row above's,
 * and out at the first of them), in a loop of fixed length. */
static void marks_chunk(const uint8_t *restrict bt, const uint8_t *restrict up, uint8_t *restrict out)
{
    int k;
    for (k = 0; k < MASK_CHUNK; k++)
        out[k] = (uint8_t)((bt[k] != 0) | ((bt[k - 1] & MASK_RIGHT) != 0) | ((up[k] & MASK_DOWN) != 0) |
                           ((up[k - 1] & MASK_DOWN_RIGHT) != 0) | ((up[k + 1] & MASK_DOWN_LEFT) != 0));
}

/* Rows of job k: each pixel's mark (mark_at), chunks inside the frame
 * below its first row, the rest one by one. */
static void mask_or_rows(void *arg, int worker, uint32_t k)
{
    mask_job *jb = arg;
    int32_t w = jb->r->w, h = jb->r->h, i, j, j1 = (int32_t)(k + 1) * MASK_ROWS;
    size_t n = 0;
    for (j = (int32_t)k * MASK_ROWS; j < j1 && j < h; j++) {
        const uint8_t *bt = jb->bits + (size_t)j * (size_t)w;
        uint8_t *out = jb->out + (size_t)j * (size_t)w;
        i = 0;
        if (j > 0 && w >= MASK_CHUNK + 2) {
            out[0] = mark_at(bt, 0, j, w);
            for (i = 1; i < w - 1; i += MASK_CHUNK) {
                i = i + MASK_CHUNK <= w - 1 ? i : w - 1 - MASK_CHUNK; /* the last overlaps the one before */
                marks_chunk(bt + i, bt + i - w, out + i);
            }
        }
        for (; i < w; i++)
            out[i] = mark_at(bt + i, i, j, w);
        for (i = 0; i < w; i++)
            n += out[i];
    }
    jb->marked[worker] += n;
}

size_t render_aa_mask(render *r, const render_opts *o, double ex, int curve, int level, uint8_t *rgb,
                      uint8_t *marks, uint32_t *id0, uint8_t *mask, int *far)
{
    size_t px = (size_t)r->w * (size_t)r->h, n = 0;
    uint32_t jobs = (uint32_t)((r->h + MASK_ROWS - 1) / MASK_ROWS);
    mask_job jb;
    int k, f = render_tonemap_par(r, r->lin, px, ex, curve, rgb, o);
    if (far)
        *far = f;
    memset(&jb, 0, sizeof jb);
    jb.r = r;
    jb.rgb = rgb;
    jb.id = r->id;
    jb.id0 = id0;
    jb.level = level < 0 ? 0u : level > 255 ? 255u : (unsigned)level; /* 255: no channel step is an edge */
    /* two passes on the workers, each pixel writing only its own byte: the
     * pairs' bits into mask, then the marks into marks (which may be rgb:
     * the first pass is its last reader), copied back to mask */
    jb.bits = mask;
    jb.out = marks;
    run_jobs(o, jobs, mask_bits_rows, &jb);
    run_jobs(o, jobs, mask_or_rows, &jb);
    memcpy(mask, marks, px);
    for (k = 0; k < RENDER_MAX_WORKERS; k++)
        n += jb.marked[k];
    if (!o->no_glow)
        n += glow_mark(r, mask, 1); /* a glow the first sample sees: every sample adds its own */
    return n;
}
