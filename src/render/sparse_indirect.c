/* sparse_indirect: the indirect term of a frame (render_opts.indirect_sparse)
 * from the hook at the corners of blocks of pixels.
 *
 * The indirect hook is asked at the corners of blocks of IND_STEP pixels a
 * side, before the shading pass; a block whose pixels and corners all lie
 * on one surface takes its pixels' indirect term bilinearly from its
 * corners, and every other pixel asks the hook itself after the pass. The
 * hook is only ever called on this thread. With render_opts.indirect_try
 * and workers, the workers first try each row of corners (then of pixels)
 * left to right and stop at the first point the try cannot answer; this
 * thread then asks the hook from there on, row after row. The try gives
 * the hook's own bits, so the image is the same bytes for any number of
 * workers. */
#include <math.h>
#include <string.h>

#include "base/plx_assert.h"
#include "render/render_int.h"

static int32_t corner_x(const render *r, int32_t a)
{
    int32_t x = a * IND_STEP;
    return x < r->w ? x : r->w - 1;
}

static int32_t corner_y(const render *r, int32_t b)
{
    int32_t y = b * IND_STEP;
    return y < r->h ? y : r->h - 1;
}

/* The block of column i (row j): the last block takes the last pixels. */
static int32_t block_of(int32_t i, int32_t nb)
{
    int32_t a = i / IND_STEP;
    return a < nb ? a : nb - 1;
}

/* The hit points of the corners of row b of the grid. */
static void corner_row(render *r, int32_t b, corner_hit *row)
{
    int32_t a;
    uint32_t sid;
    for (a = 0; a <= r->nbx; a++)
        row[a].hit = pixel_hit(r, corner_x(r, a), corner_y(r, b), &sid, row[a].P, row[a].n);
}

/* Whether block (a, b), its far corners included, lies on one surface,
 * and its corners' hit points (top: row b, bot: row b + 1) lie within
 * span times the distance of the nearest of them from the eye (seen at a
 * grazing angle, a block spans far more of the surface than its
 * neighbours nearer the eye). */
static int block_one_surface(const render *r, int32_t a, int32_t b, double span, const corner_hit *top,
                             const corner_hit *bot)
{
    int32_t x0 = corner_x(r, a), x1 = corner_x(r, a + 1), y0 = corner_y(r, b), y1 = corner_y(r, b + 1), x, y;
    uint32_t sid = r->id[(size_t)y0 * (size_t)r->w + (size_t)x0];
    double lo[3], hi[3], dmin = HUGE_VAL, ext = 0.0;
    int c, k;
    if (sid == MESH_SURF_NONE)
        return 0;
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            if (r->id[(size_t)y * (size_t)r->w + (size_t)x] != sid)
                return 0;
    for (c = 0; c < 4; c++) {
        const double *C = (c & 2 ? bot : top)[a + (c & 1)].P;
        double d2 = 0.0;
        for (k = 0; k < 3; k++) {
            double dk = C[k] - r->eye[k];
            d2 += dk * dk;
            lo[k] = c ? fmin(lo[k], C[k]) : C[k];
            hi[k] = c ? fmax(hi[k], C[k]) : C[k];
        }
        dmin = fmin(dmin, sqrt(d2));
    }
    for (k = 0; k < 3; k++)
        ext = fmax(ext, hi[k] - lo[k]);
    return ext <= span * dmin;
}

/* Whether corner (a, b) is a corner of a one-surface block. */
static int corner_used(const render *r, int32_t a, int32_t b)
{
    int32_t da, db;
    for (db = -1; db <= 0; db++)
        for (da = -1; da <= 0; da++) {
            int32_t x = a + da, y = b + db;
            if (x >= 0 && y >= 0 && x < r->nbx && y < r->nby && r->blk[(size_t)y * (size_t)r->nbx + (size_t)x] == 1)
                return 1;
        }
    return 0;
}

/* Corner (a, b)'s value from the hook (try: from indirect_try; returns 0
 * when it cannot say), stored in r->ind. */
static int corner_value(render *r, const render_opts *o, int32_t a, int32_t b, const corner_hit *h, int try,
                        int worker)
{
    float *c = &r->ind[3 * ((size_t)b * (size_t)(r->nbx + 1) + (size_t)a)];
    double Ei[3] = { 0.0, 0.0, 0.0 };
    int k;
    if (try) {
        if (!o->indirect_try(o->indirect_user, worker, h->P, h->n, Ei))
            return 0;
    } else
        o->indirect(o->indirect_user, h->P, h->n, Ei);
    for (k = 0; k < 3; k++)
        c[k] = (float)Ei[k];
    return 1;
}

/* The hook at the used corners of row b (the blocks above and below it
 * known) from corner a0 on, left to right. */
static void corner_gather(render *r, const render_opts *o, render_stats *st, int32_t b, const corner_hit *row,
                          int32_t a0)
{
    int32_t a;
    for (a = a0; a <= r->nbx; a++)
        if (row[a].hit && corner_used(r, a, b)) {
            (void)corner_value(r, o, a, b, &row[a], 0, 0);
            st->indirect_calls++;
        }
}

/* The workers' share of the sparse indirect (render_opts.indirect_try). */
typedef struct try_job {
    render *r;
    const render_opts *o;
    uint64_t calls[RENDER_MAX_WORKERS];
} try_job;

/* Corner row b on a worker: tried left to right up to the first miss
 * (render_job_fn; r->stop[b] is where this thread goes on). */
static void corner_try_row(void *arg, int worker, uint32_t b)
{
    try_job *jb = arg;
    render *r = jb->r;
    int32_t a;
    for (a = 0; a <= r->nbx; a++) {
        corner_hit h;
        uint32_t sid;
        if (!corner_used(r, a, (int32_t)b))
            continue;
        /* the ground ids are in place: this pixel_hit writes nothing */
        h.hit = pixel_hit(r, corner_x(r, a), corner_y(r, (int32_t)b), &sid, h.P, h.n);
        if (!h.hit)
            continue;
        if (!corner_value(r, jb->o, a, (int32_t)b, &h, 1, worker))
            break;
        jb->calls[worker]++;
    }
    r->stop[b] = a;
}

/* How many workers may try the hook (0: none, the hook on this thread). */
static int try_workers(const render_opts *o)
{
    int nw = par_workers(o);
    return o->indirect_try && nw > 1 ? nw : 0;
}

/* fn on rows 0 .. n - 1 on the workers; 0 when the port could not run them. */
static int try_rows(render *r, const render_opts *o, render_stats *st, uint32_t n, render_job_fn fn)
{
    try_job jb;
    int nw = try_workers(o), k;
    memset(&jb, 0, sizeof jb);
    jb.r = r;
    jb.o = o;
    if (nw == 0 || o->par(o->par_ctx, nw, n, fn, &jb) != 0)
        return 0;
    for (k = 0; k < nw; k++)
        st->indirect_calls += jb.calls[k];
    return 1;
}

/* Each row of corners from where the workers stopped, on this thread. */
static void corners_rest(render *r, const render_opts *o, render_stats *st)
{
    int32_t a, b;
    for (b = 0; b <= r->nby; b++) {
        corner_hit h;
        uint32_t sid;
        for (a = r->stop[b]; a <= r->nbx; a++)
            if (corner_used(r, a, b)) {
                h.hit = pixel_hit(r, corner_x(r, a), corner_y(r, b), &sid, h.P, h.n);
                if (h.hit) {
                    (void)corner_value(r, o, a, b, &h, 0, 0);
                    st->indirect_calls++;
                }
            }
    }
}

/* Whether a pixel of block (a, b), its far corners included, is shaded
 * in this sample (render_opts.mask). */
static int block_masked(const render *r, const render_opts *o, int32_t a, int32_t b)
{
    int32_t x0 = corner_x(r, a), x1 = corner_x(r, a + 1), y0 = corner_y(r, b), y1 = corner_y(r, b + 1), x, y;
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            if (o->mask[(size_t)y * (size_t)r->w + (size_t)x])
                return 1;
    return 0;
}

/* Before the shading pass: ground ids, the one-surface blocks and the
 * hook's value at their corners, row by row (each corner's hit point
 * found once, two rows of them kept; with tries, the hook's values after
 * the blocks, on the workers first). A later anti-aliasing sample asks
 * only the corners of blocks holding a pixel it shades (blk 2: one
 * surface, none shaded). */
void sparse_corners(render *r, const render_opts *o, render_stats *st)
{
    int32_t a, b;
    corner_hit *row[2];
    r->nbx = r->w > 1 ? (r->w - 1 + IND_STEP - 1) / IND_STEP : 1;
    r->nby = r->h > 1 ? (r->h - 1 + IND_STEP - 1) / IND_STEP : 1;
    /* the buffers sized for the largest frame hold this one's, either way
     * round (render_frame_fits) */
    PLX_ASSERT((size_t)(r->nbx + 1) * (size_t)(r->nby + 1) <= r->corner_cap);
    PLX_ASSERT(2 * (size_t)(r->nbx + 1) <= r->crow_cap);
    PLX_ASSERT((size_t)(r->nby + 1) + (size_t)r->h <= r->stop_cap);
    row[0] = r->crow;
    row[1] = r->crow + r->nbx + 1;
    int tries = try_workers(o) > 0;
    soft_ground_ids(r, o);
    corner_row(r, 0, row[0]);
    for (b = 0; b < r->nby; b++) {
        corner_row(r, b + 1, row[(b + 1) & 1]);
        for (a = 0; a < r->nbx; a++) {
            uint8_t one = (uint8_t)block_one_surface(r, a, b, o->indirect_span, row[b & 1], row[(b + 1) & 1]);
            st->indirect_blocks += one;
            if (one && o->mask && !block_masked(r, o, a, b))
                one = 2; /* one surface, no pixel shaded in this sample: corners not asked */
            r->blk[(size_t)b * (size_t)r->nbx + (size_t)a] = one;
        }
        if (!tries)
            corner_gather(r, o, st, b, row[b & 1], 0);
    }
    if (!tries)
        corner_gather(r, o, st, r->nby, row[r->nby & 1], 0);
    else if (try_rows(r, o, st, (uint32_t)r->nby + 1, corner_try_row))
        corners_rest(r, o, st);
    else { /* the port could not run them: every corner here */
        for (b = 0; b <= r->nby; b++)
            r->stop[b] = 0;
        corners_rest(r, o, st);
    }
    st->indirect_nblocks = (uint64_t)r->nbx * (uint64_t)r->nby;
}

/* Pixel (i, j)'s indirect term added to E when its block lies on one
 * surface (bilinear over the block's corners). */
void sparse_at(const render *r, int32_t i, int32_t j, double E[3])
{
    int32_t a = block_of(i, r->nbx), b = block_of(j, r->nby);
    int32_t x0 = corner_x(r, a), x1 = corner_x(r, a + 1), y0 = corner_y(r, b), y1 = corner_y(r, b + 1);
    const float *c00, *c10, *c01, *c11;
    double fx, fy;
    size_t row = (size_t)(r->nbx + 1);
    int k;
    if (!r->blk[(size_t)b * (size_t)r->nbx + (size_t)a])
        return;
    fx = x1 > x0 ? (double)(i - x0) / (double)(x1 - x0) : 0.0;
    fy = y1 > y0 ? (double)(j - y0) / (double)(y1 - y0) : 0.0;
    c00 = &r->ind[3 * ((size_t)b * row + (size_t)a)];
    c10 = c00 + 3;
    c01 = c00 + 3 * row;
    c11 = c01 + 3;
    for (k = 0; k < 3; k++)
        E[k] += (1.0 - fy) * ((1.0 - fx) * c00[k] + fx * c10[k]) + fy * ((1.0 - fx) * c01[k] + fx * c11[k]);
}

/* After the shading pass: the pixels of the other blocks ask the hook. */
/* Pixel row j's pixels the blocks leave, from pixel i0 on: the hook's
 * term added (try: stops at the first the try cannot answer); returns
 * where it stopped (r->w: the row is done) and counts the calls. */
static int32_t rest_row(render *r, const render_opts *o, int32_t j, int32_t i0, int try, int worker,
                        uint64_t *calls)
{
    int32_t i;
    for (i = i0; i < r->w; i++) {
        size_t p = (size_t)j * (size_t)r->w + (size_t)i;
        float *out = &r->lin[3 * p];
        double P[3], n[3], Ei[3] = { 0, 0, 0 }, alb[3];
        uint32_t sid;
        int k;
        if (r->blk[(size_t)block_of(j, r->nby) * (size_t)r->nbx + (size_t)block_of(i, r->nbx)] ||
            (o->mask && !o->mask[p]) || !pixel_hit(r, i, j, &sid, P, n))
            continue;
        if (!try)
            o->indirect(o->indirect_user, P, n, Ei);
        else if (!o->indirect_try(o->indirect_user, worker, P, n, Ei))
            break;
        (*calls)++;
        if (sid == MESH_SURF_GROUND)
            scene_ground_albedo(r->s, P[0], P[1], alb);
        else
            alb[0] = alb[1] = alb[2] = surf_albedo(r, sid);
        for (k = 0; k < 3; k++)
            out[k] = (float)((double)out[k] + alb[k] / PI * Ei[k]);
    }
    return i;
}

/* Pixel row j on a worker (render_job_fn; r->stop after the corner rows). */
static void rest_try_row(void *arg, int worker, uint32_t j)
{
    try_job *jb = arg;
    render *r = jb->r;
    r->stop[r->nby + 1 + (int32_t)j] = rest_row(r, jb->o, (int32_t)j, 0, 1, worker, &jb->calls[worker]);
}

void sparse_rest(render *r, const render_opts *o, render_stats *st)
{
    int32_t j, *stop = r->stop + r->nby + 1;
    if (!try_rows(r, o, st, (uint32_t)r->h, rest_try_row))
        for (j = 0; j < r->h; j++)
            stop[j] = 0;
    for (j = 0; j < r->h; j++)
        (void)rest_row(r, o, j, stop[j], 0, 0, &st->indirect_calls);
}
