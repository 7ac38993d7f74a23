/* lightmap: the aerial light map (issue: aerial views): the exact ground
 * illuminance E_rgb of every lamp (through the renderer's shader, 2.5D
 * shadows, SPEC §2) stored once per texel over the lamps' reach, then read
 * by the aerial view's ground pixels, bilinear between texel centres
 * (munoz2013's precomputed ground lighting for views from above).
 * Optionally a second layer: E_indirect at the topmost surface over each
 * texel (ground or roof, as seen from above) and its height, read by the
 * aerial view's ground and roof pixels with weights only on texels of the
 * pixel's own surface (issue #13: no light across edges). */
#include <math.h>
#include <string.h>

#include "render/lightmap.h"
#include "light/illuminance.h"

/* A texel waiting for its light has t[1] = -1 (E is never negative). */
static void shade_row(lightmap *m, uint32_t j, lightmap_shade_fn shade, void *user)
{
    uint32_t i;
    for (i = 0; i < m->nx; i++) {
        float *t = &m->rgb[3 * ((size_t)j * m->nx + i)];
        double P[3], n[3] = { 0.0, 0.0, 1.0 }, E[3];
        if (!(t[1] < 0.0f))
            continue;
        P[0] = m->x0 + (i + 0.5) * m->cell;
        P[1] = m->y0 + (j + 0.5) * m->cell;
        P[2] = 0.0;
        shade(user, P, n, E);
        t[0] = (float)E[0];
        t[1] = (float)E[1];
        t[2] = (float)E[2];
    }
}

typedef struct band_job {
    lightmap *m;
    const struct light *lt;
    uint32_t j0;
} band_job;

/* A row on a worker: the light cache read only; stops at the first texel
 * it cannot answer (left waiting for shade_row). */
static void cached_row(void *arg, int worker, uint32_t k)
{
    band_job *jb = arg;
    lightmap *m = jb->m;
    uint32_t i, j = jb->j0 + k;
    (void)worker;
    for (i = 0; i < m->nx; i++) {
        float *t = &m->rgb[3 * ((size_t)j * m->nx + i)];
        double P[3], n[3] = { 0.0, 0.0, 1.0 }, E[3];
        if (!(t[1] < 0.0f))
            continue;
        P[0] = m->x0 + (i + 0.5) * m->cell;
        P[1] = m->y0 + (j + 0.5) * m->cell;
        P[2] = 0.0;
        if (light_illuminance_cached(jb->lt, P, n, E) != 0)
            return;
        t[0] = (float)E[0];
        t[1] = (float)E[1];
        t[2] = (float)E[2];
    }
}

/* Every row by bands: the band's lamp regions cached, its rows on the
 * workers, then what they left on this thread. */
static void shade_bands(lightmap *m, lightmap_shade_fn shade, void *user, const lightmap_par *p)
{
    uint32_t j0, j;
    for (j0 = 0; j0 < m->ny; j0 += LIGHTMAP_BAND) {
        uint32_t j1 = j0 + LIGHTMAP_BAND < m->ny ? j0 + LIGHTMAP_BAND : m->ny;
        band_job jb;
        light_cache_box(p->lt, m->x0, m->y0 + j0 * m->cell, m->x0 + m->nx * m->cell, m->y0 + j1 * m->cell);
        jb.m = m;
        jb.lt = p->lt;
        jb.j0 = j0;
        if (p->par(p->ctx, p->workers, j1 - j0, cached_row, &jb) != 0)
            for (j = j0; j < j1; j++)
                cached_row(&jb, 0, j - j0);
        for (j = j0; j < j1; j++)
            shade_row(m, j, shade, user);
    }
}

/* A float array of the map that keeps the memory its first build took:
 * later builds must fit it (the arena cannot grow an older block). */
static plx_status keep_floats(float **p, size_t *cap, arena *mem, size_t need, const char *what,
                              const char **err)
{
    if (*p && need <= *cap)
        return PLX_OK;
    if (*p) {
        *err = "render_lightmap_build: the new map does not fit the first one's memory";
        return PLX_E_NOMEM;
    }
    *p = arena_alloc(mem, PLX_PART_FRAME, arena_mul(need, sizeof(float)), 64);
    if (!*p) {
        *err = what;
        return PLX_E_NOMEM;
    }
    *cap = need;
    return PLX_OK;
}

/* The indirect layer: memory (as the first build took it) and values. */
static plx_status ind_alloc(lightmap *m, arena *mem, size_t need, const char **err)
{
    return keep_floats(&m->ind, &m->ind_cap, mem, need,
                       "render_lightmap_build: out of memory for the light map's indirect layer", err);
}

/* Row j of the indirect layer (-1: no value; user NULL: all empty). */
static void ind_row(lightmap *m, uint32_t j, lightmap_ind_fn fn, void *user)
{
    uint32_t i;
    for (i = 0; i < m->nx; i++) {
        size_t t = (size_t)j * m->nx + i;
        float *o = &m->ind[4 * t];
        double rgb[3], z;
        o[0] = -1.0f;
        o[1] = o[2] = o[3] = 0.0f;
        if (!user || !fn(user, m->x0 + (i + 0.5) * m->cell, m->y0 + (j + 0.5) * m->cell, rgb, &z))
            continue;
        o[0] = (float)rgb[0];
        o[1] = (float)rgb[1];
        o[2] = (float)rgb[2];
        o[3] = (float)z;
    }
}

static void ind_fill(lightmap *m, lightmap_ind_fn fn, void *user)
{
    uint32_t j;
    for (j = 0; j < m->ny; j++)
        ind_row(m, j, fn, user);
}

/* Bands of rows for the workers: a band is one job, its rows in order, so
 * a worker's cache keeps the records its next rows share. */
#define IND_BANDS_PER_WORKER 4

typedef struct ind_job {
    lightmap *m;
    lightmap_ind_fn fn;
    void *const *users;
    uint32_t rows;       /* per band */
    const lightmap_par *par;
} ind_job;

/* Row j for the user of the worker, reported done. */
static void ind_row_told(const ind_job *jb, uint32_t j, void *user)
{
    const lightmap_par *p = jb->par;
    ind_row(jb->m, j, jb->fn, user);
    if (p && p->progress.fn)
        p->progress.fn(p->progress.ctx, LIGHTMAP_LAYER_STAGE, 1, jb->m->ny);
}

static void ind_band(void *arg, int worker, uint32_t k)
{
    ind_job *jb = arg;
    uint32_t j, j1 = (k + 1) * jb->rows < jb->m->ny ? (k + 1) * jb->rows : jb->m->ny;
    for (j = k * jb->rows; j < j1; j++)
        ind_row_told(jb, j, jb->users[worker]);
}

plx_status lightmap_fill_ind(lightmap *m, lightmap_ind_fn ind_fn, void *const *users, int workers,
                             const lightmap_par *par)
{
    ind_job jb;
    uint32_t bands, j;
    int told = par && par->progress.fn;
    if (!m->built || !m->ind || !ind_fn || !users || workers < 1 ||
        (size_t)m->nx * m->ny * 4 > m->ind_cap)
        return PLX_E_INVALID;
    m->has_ind = 0;
    bands = (uint32_t)workers * IND_BANDS_PER_WORKER;
    jb.m = m;
    jb.fn = ind_fn;
    jb.users = users;
    jb.rows = (m->ny + bands - 1) / bands;
    jb.par = par;
    bands = jb.rows ? (m->ny + jb.rows - 1) / jb.rows : 0;
    if (told)
        par->progress.fn(par->progress.ctx, LIGHTMAP_LAYER_STAGE, 0, m->ny);
    if (workers < 2 || !par || !par->par || !users[0] ||
        par->par(par->ctx, workers, bands, ind_band, &jb) != 0)
        for (j = 0; j < m->ny; j++)
            ind_row_told(&jb, j, users[0]);
    if (told)
        par->progress.fn(par->progress.ctx, LIGHTMAP_LAYER_STAGE, 0, 0);
    m->has_ind = users[0] != NULL;
    return PLX_OK;
}

plx_status lightmap_build(lightmap *m, arena *mem, const scene *s, double cell, size_t max_bytes,
                          lightmap_shade_fn shade, void *user, const lightmap_par *par, const char **err)
{
    return lightmap_build_ind(m, mem, s, cell, max_bytes, shade, user, par, NULL, NULL, err);
}

plx_status lightmap_build_ind(lightmap *m, arena *mem, const scene *s, double cell, size_t max_bytes,
                              lightmap_shade_fn shade, void *user, const lightmap_par *par,
                              lightmap_ind_fn ind_fn, void *ind_user, const char **err)
{
    double per = ind_fn ? 28.0 : 12.0; /* bytes a texel */
    plx_status st;
    size_t t, ntex;
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
    uint32_t l, nx, ny, j;
    size_t need;
    if (!(cell > 0.0) || !isfinite(cell) || (double)max_bytes < per) {
        *err = "render_lightmap_build: m_per_texel must be > 0 and max_bytes >= 12 (28 with indirect light)";
        return PLX_E_INVALID;
    }
    for (l = 0; l < s->nlamps; l++) {
        const scene_lamp *lp = &s->lamps[l];
        double rg;
        if (!(lp->radius > lp->z) || !(lp->intensity > 0))
            continue;
        rg = sqrt(lp->radius * lp->radius - lp->z * lp->z);
        x0 = fmin(x0, lp->x - rg);
        y0 = fmin(y0, lp->y - rg);
        x1 = fmax(x1, lp->x + rg);
        y1 = fmax(y1, lp->y + rg);
    }
    if (!(x1 > x0)) {
        x0 = y0 = 0.0;
        x1 = y1 = cell;
    }
    for (;;) {
        double fx = ceil((x1 - x0) / cell), fy = ceil((y1 - y0) / cell);
        if (fx < 1) fx = 1;
        if (fy < 1) fy = 1;
        if (fx * fy * per <= (double)max_bytes && fx < 1e8 && fy < 1e8) {
            nx = (uint32_t)fx;
            ny = (uint32_t)fy;
            break;
        }
        cell *= 1.05;
    }
    need = (size_t)nx * ny * 3;
    st = keep_floats(&m->rgb, &m->cap, mem, need, "render_lightmap_build: out of memory for the light map", err);
    if (st != PLX_OK)
        return st;
    if (ind_fn && (st = ind_alloc(m, mem, (size_t)nx * ny * 4, err)) != PLX_OK)
        return st;
    m->nx = nx;
    m->ny = ny;
    m->cell = cell;
    /* centre the grid on the reach box */
    m->x0 = 0.5 * (x0 + x1) - 0.5 * nx * cell;
    m->y0 = 0.5 * (y0 + y1) - 0.5 * ny * cell;
    m->shaded = 0;
    memset(m->rgb, 0, need * sizeof(float));
    /* mark texels some lamp reaches, using the map itself (channel 0 = 1) */
    for (l = 0; l < s->nlamps; l++) {
        const scene_lamp *lp = &s->lamps[l];
        double rg;
        int64_t a0, a1, b0, b1, a, b;
        if (!(lp->radius > lp->z) || !(lp->intensity > 0))
            continue;
        rg = sqrt(lp->radius * lp->radius - lp->z * lp->z) * (1.0 + 1e-9) + 1e-9;
        a0 = (int64_t)floor((lp->x - rg - m->x0) / cell - 0.5);
        a1 = (int64_t)ceil((lp->x + rg - m->x0) / cell - 0.5);
        b0 = (int64_t)floor((lp->y - rg - m->y0) / cell - 0.5);
        b1 = (int64_t)ceil((lp->y + rg - m->y0) / cell - 0.5);
        if (a0 < 0) a0 = 0;
        if (b0 < 0) b0 = 0;
        if (a1 > (int64_t)nx - 1) a1 = (int64_t)nx - 1;
        if (b1 > (int64_t)ny - 1) b1 = (int64_t)ny - 1;
        for (b = b0; b <= b1; b++)
            for (a = a0; a <= a1; a++) {
                double dx = m->x0 + (a + 0.5) * cell - lp->x, dy = m->y0 + (b + 0.5) * cell - lp->y;
                if (dx * dx + dy * dy <= rg * rg)
                    m->rgb[3 * ((size_t)b * nx + (size_t)a) + 1] = -1.0f;
            }
    }
    /* the indirect layer (on this thread: the irradiance cache fills its table) */
    m->has_ind = 0;
    if (ind_fn) {
        ind_fill(m, ind_fn, ind_user);
        m->has_ind = ind_user != NULL;
    }
    ntex = (size_t)nx * ny;
    for (t = 0; t < ntex; t++)
        m->shaded += m->rgb[3 * t + 1] < 0.0f;
    if (par && par->par && par->lt && par->workers >= 2)
        shade_bands(m, shade, user, par);
    else
        for (j = 0; j < ny; j++)
            shade_row(m, j, shade, user);
    m->built = 1;
    *err = "";
    return PLX_OK;
}


/* Ground E_rgb from the light map, bilinear between texel centres. */
void lightmap_sample(const lightmap *m, const double P[3], double rgb[3])
{
    double fx = (P[0] - m->x0) / m->cell - 0.5, fy = (P[1] - m->y0) / m->cell - 0.5;
    double ix, iy, tx, ty, wgt[4];
    int64_t i0, j0;
    int k, c;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(fx > -1.0 && fy > -1.0 && fx < (double)m->nx && fy < (double)m->ny))
        return;
    ix = floor(fx);
    iy = floor(fy);
    tx = fx - ix;
    ty = fy - iy;
    i0 = (int64_t)ix;
    j0 = (int64_t)iy;
    wgt[0] = (1 - tx) * (1 - ty);
    wgt[1] = tx * (1 - ty);
    wgt[2] = (1 - tx) * ty;
    wgt[3] = tx * ty;
    for (k = 0; k < 4; k++) {
        int64_t i = i0 + (k & 1), j = j0 + (k >> 1);
        const float *t;
        if (i < 0 || j < 0 || i >= (int64_t)m->nx || j >= (int64_t)m->ny)
            continue;
        t = &m->rgb[3 * ((size_t)j * m->nx + (size_t)i)];
        for (c = 0; c < 3; c++)
            rgb[c] += wgt[k] * t[c];
    }
}


int lightmap_sample_ind(const lightmap *m, const double P[3], double rgb[3])
{
    double fx, fy, tx, ty, ws = 0.0;
    int64_t i0, j0;
    int k, c, reached = 0;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!m->has_ind)
        return 0;
    fx = (P[0] - m->x0) / m->cell - 0.5;
    fy = (P[1] - m->y0) / m->cell - 0.5;
    if (!(fx > -1.0 && fy > -1.0 && fx < (double)m->nx && fy < (double)m->ny))
        return 1; /* off the map: beyond every lamp's reach */
    i0 = (int64_t)floor(fx);
    j0 = (int64_t)floor(fy);
    tx = fx - (double)i0;
    ty = fy - (double)j0;
    for (k = 0; k < 4; k++) {
        int64_t i = i0 + (k & 1), j = j0 + (k >> 1);
        double w = ((k & 1) ? tx : 1.0 - tx) * ((k >> 1) ? ty : 1.0 - ty);
        const float *t;
        if (i < 0 || j < 0 || i >= (int64_t)m->nx || j >= (int64_t)m->ny)
            continue;
        t = &m->ind[4 * ((size_t)j * m->nx + (size_t)i)];
        if (t[0] < 0.0f)
            continue;
        reached = 1;
        if (fabs(t[3] - P[2]) > 0.01 || !(w > 0.0))
            continue;
        ws += w;
        for (c = 0; c < 3; c++)
            rgb[c] += w * t[c];
    }
    if (!(ws > 1e-6)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        return !reached;
    }
    for (c = 0; c < 3; c++)
        rgb[c] /= ws;
    return 1;
}
