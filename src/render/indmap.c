/* indmap: the indirect ground light of aerial views as a texture. The
 * photon buffers' ground estimate (the renderer's indirect hook) is smooth
 * at the scale of the aerial chart (SPEC §4; photon.h: 512 texels along
 * Bounds), so an aerial frame reads it from a map of texel centres,
 * bilinear, instead of one lookup per ground pixel -- munoz2013 §3.2's
 * light maps, built once and rebuilt when the indirect light changes
 * (key). The hook is called at each texel centre on the ground facing up,
 * as for a ground pixel there. */
#include <math.h>
#include <string.h>

#include "render/indmap.h"

typedef struct indmap_job {
    indmap *m;
    lightmap_shade_fn hook;
    void *user;
    indmap_top_fn top;
    void *top_user;
} indmap_job;

static void build_row(void *arg, int worker, uint32_t j)
{
    indmap_job *jb = arg;
    indmap *m = jb->m;
    uint32_t i;
    (void)worker;
    for (i = 0; i < m->nx; i++) {
        double P[3], n[3] = { 0.0, 0.0, 1.0 }, E[3] = { 0.0, 0.0, 0.0 };
        float *t = &m->rgb[3 * ((size_t)j * m->nx + i)];
        P[0] = m->x0 + (i + 0.5) * m->cell;
        P[1] = m->y0 + (j + 0.5) * m->cell;
        P[2] = jb->top ? jb->top(jb->top_user, P[0], P[1]) : 0.0;
        m->z[(size_t)j * m->nx + i] = (float)P[2];
        jb->hook(jb->user, P, n, E);
        t[0] = (float)E[0];
        t[1] = (float)E[1];
        t[2] = (float)E[2];
    }
}

plx_status indmap_build(indmap *m, arena *a, const lightmap *lm, lightmap_shade_fn hook, void *user,
                        indmap_top_fn top, void *top_user, uint64_t key, indmap_par_fn par, void *par_ctx,
                        int workers)
{
    uint32_t nx = (lm->nx + INDMAP_FACTOR - 1) / INDMAP_FACTOR, ny = (lm->ny + INDMAP_FACTOR - 1) / INDMAP_FACTOR;
    size_t need = (size_t)nx * ny * 3;
    indmap_job jb;
    uint32_t j;
    m->built = 0;
    if (!m->rgb || need > m->cap) {
        if (m->rgb)
            return PLX_E_NOMEM;
        arena_mark m0 = arena_get_mark(a);
        m->rgb = arena_alloc(a, PLX_PART_FRAME, arena_mul(need, sizeof(float)), 64);
        m->z = arena_alloc(a, PLX_PART_FRAME, arena_mul(need / 3, sizeof(float)), 64);
        if (!m->rgb || !m->z) {
            arena_release(a, &m0);
            m->rgb = m->z = NULL;
            return PLX_E_NOMEM;
        }
        m->cap = need;
    }
    m->nx = nx;
    m->ny = ny;
    m->cell = lm->cell * INDMAP_FACTOR;
    m->x0 = lm->x0;
    m->y0 = lm->y0;
    jb.m = m;
    jb.hook = hook;
    jb.user = user;
    jb.top = top;
    jb.top_user = top_user;
    if (!par || workers < 2 || par(par_ctx, workers, ny, build_row, &jb) != 0)
        for (j = 0; j < ny; j++)
            build_row(&jb, 0, j);
    m->key = key;
    m->built = 1;
    return PLX_OK;
}

int indmap_sample(const indmap *m, const double P[3], double rgb[3])
{
    double fx = (P[0] - m->x0) / m->cell - 0.5, fy = (P[1] - m->y0) / m->cell - 0.5, tx, ty, w[4], sw = 0.0;
    double acc[3] = { 0.0, 0.0, 0.0 };
    uint32_t i, j;
    int k, c;
    if (!(fx >= 0.0 && fy >= 0.0 && fx <= (double)(m->nx - 1) && fy <= (double)(m->ny - 1)))
        return 0;
    i = (uint32_t)fx;
    j = (uint32_t)fy;
    if (i == m->nx - 1 && i > 0)
        i--;
    if (j == m->ny - 1 && j > 0)
        j--;
    tx = fx - i;
    ty = fy - j;
    w[0] = (1 - tx) * (1 - ty);
    w[1] = tx * (1 - ty);
    w[2] = (1 - tx) * ty;
    w[3] = tx * ty;
    for (k = 0; k < 4; k++) {
        uint32_t a = i + (uint32_t)(k & 1), b = j + (uint32_t)(k >> 1);
        size_t t;
        if (a >= m->nx || b >= m->ny || !(w[k] > 0.0))
            continue;
        t = (size_t)b * m->nx + a;
        if (!(fabs((double)m->z[t] - P[2]) <= 1e-3))
            continue;
        sw += w[k];
        for (c = 0; c < 3; c++)
            acc[c] += w[k] * m->rgb[3 * t + (size_t)c];
    }
    if (!(sw > 0.0))
        return 0;
    for (c = 0; c < 3; c++)
        rgb[c] = acc[c] / sw;
    return 1;
}
