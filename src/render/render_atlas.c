/* render_atlas: frames from the radiance atlas (render_atlas.h, atlas_frame.h). */
#include <string.h>

#include "base/plx_assert.h"
#include "render/atlas_frame.h"
#include "render/render_atlas.h"
#include "render/render_int.h"

typedef struct atlas_job {
    render *r;
    const render_opts *o;
    atlas_view v;
    int count;      /* count the exposure's histogram (automatic exposure) */
    int again;      /* read only the jobs that met an item not filled, filled since */
    uint64_t px[RENDER_MAX_WORKERS][3]; /* sky, ground and building pixels, by worker */
} atlas_job;

/* Rows k RENDER_TILE .. of the frame from the atlas, then counted into
 * the worker's exposure histogram while they are in the cache: every
 * other pixel of every other row (all of them in frames under 64 pixels
 * a side), enough for the percentile; the sums do not depend on which
 * worker counted what. A first read that met a chart or block not filled
 * yet (with an atlas_need to fill it) is not counted: r->defer[k] says
 * the job is read again, and counted then (a frame's tiles outnumber its
 * jobs of rows); the second read always counts. */
static void atlas_rows(void *arg, int worker, uint32_t k)
{
    atlas_job *jb = arg;
    render *r = jb->r;
    int32_t j, j0 = (int32_t)k * RENDER_TILE, j1 = j0 + RENDER_TILE < r->h ? j0 + RENDER_TILE : r->h;
    uint64_t px[3] = { 0, 0, 0 };
    int unfilled = 0, c;
    if (jb->again && !r->defer[k])
        return;
    for (j = j0; j < j1; j++) {
        const uint32_t *ids = &r->id[(size_t)j * (size_t)r->w];
        float *lin = &r->lin[3 * (size_t)j * (size_t)r->w];
        const uint8_t *mask = jb->o->mask ? &jb->o->mask[(size_t)j * (size_t)r->w] : NULL;
        unfilled |= atlas_frame_row(jb->o->atlas, &jb->v, &jb->o->atlas_cache[worker], ids, mask, j, lin, px);
    }
    if (jb->again) {
        PLX_ASSERT(!unfilled); /* the list held every item the rows read */
    } else {
        r->defer[k] = (uint8_t)(unfilled && jb->o->atlas_need);
        if (r->defer[k])
            return;
    }
    for (c = 0; c < 3; c++)
        jb->px[worker][c] += px[c];
    if (jb->count)
        for (j = j0; j < j1; j++)
            if (j % 2 == 0 || r->h < 64) /* every other pixel of every other row */
                exposure_count_every(r->et, &r->lin[3 * (size_t)j * (size_t)r->w], &r->id[(size_t)j * (size_t)r->w],
                                     0, (size_t)r->w, r->w < 64 ? 1 : 2, r->hist[worker]);
}

/* atlas_need for each run of jobs that met an item not filled: what
 * their rows read, filled. Returns the runs filled, or -1 when one could
 * not be. */
static int atlas_fill_rows(render *r, const render_opts *o, const atlas_view *v, uint32_t jobs)
{
    uint32_t k = 0, e;
    int runs = 0;
    while (k < jobs) {
        if (!r->defer[k]) {
            k++;
            continue;
        }
        for (e = k + 1; e < jobs && r->defer[e]; e++)
            ;
        if (o->atlas_need(o->atlas_user, v, r->id, o->mask, (int32_t)k * RENDER_TILE, (int32_t)e * RENDER_TILE) != 0)
            return -1;
        runs++;
        k = e;
    }
    return runs;
}

void render_atlas_view(const render *r, atlas_view *v)
{
    double ta = r->tanh_ * r->aspect, tb = r->tanh_, a0, b0;
    int k;
    a0 = (2.0 * (0.5 + r->shift[0]) / r->w - 1.0) * ta;
    b0 = (1.0 - 2.0 * (0.5 + r->shift[1]) / r->h) * tb;
    for (k = 0; k < 3; k++) {
        v->eye[k] = r->eye[k];
        v->D0[k] = r->f[k] + a0 * r->rt[k] + b0 * r->up[k];
        v->Dx[k] = 2.0 * ta / r->w * r->rt[k];
        v->Dy[k] = -2.0 * tb / r->h * r->up[k];
    }
    v->w = r->w;
    v->h = r->h;
    v->stamp = r->frames;
}

/* Every pixel from the atlas: the ground's ids set, then rows of pixels
 * (RENDER_TILE a job) on the workers, each with its own map cache. */
int render_atlas_pass(render *r, const render_opts *o, render_stats *st)
{
    atlas_job jb;
    uint32_t jobs = (uint32_t)((r->h + RENDER_TILE - 1) / RENDER_TILE);
    int k, runs;
    soft_ground_ids(r, o);
    if (o->mask) /* adaptive anti-aliasing's later samples: only the marked pixels */
        render_aa_mask_update(r, o);
    if (++r->frames == 0) /* 2^32 frames: a stale map could carry stamp 0 */
        ++r->frames;
    render_atlas_view(r, &jb.v);
    jb.r = r;
    jb.o = o;
    jb.count = o->auto_exposure == RENDER_EXPOSURE_AUTO || o->auto_exposure == RENDER_EXPOSURE_ADAPT;
    jb.again = 0;
    if (jb.count)
        memset(r->hist, 0, sizeof r->hist);
    memset(jb.px, 0, sizeof jb.px);
    /* the rows read first; only a frame that met a chart or block not
     * filled yet lists what it reads (atlas_need, atlas_frame_missing),
     * fills it, and reads those rows again: the same bytes as filling
     * first, a chart's values being its own whenever it is filled */
    run_jobs(o, jobs, atlas_rows, &jb);
    if ((runs = atlas_fill_rows(r, o, &jb.v, jobs)) < 0)
        return -1;
    if (runs > 0) {
        jb.again = 1;
        run_jobs(o, jobs, atlas_rows, &jb);
    }
    for (k = 0; k < RENDER_MAX_WORKERS; k++) {
        st->sky_pixels += jb.px[k][0];
        st->ground_pixels += jb.px[k][1];
        st->building_pixels += jb.px[k][2];
    }
    return 0;
}
