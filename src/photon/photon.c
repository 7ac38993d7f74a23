/* photon: photon buffers, progressive pass, lookup, levels (see photon.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "photon/photon.h"
#include "base/geom.h"
#include "scene/photometry.h"

#define PI 3.14159265358979323846
#define HEIGHT_TOL 1e-3   /* m: a splat's texels are at the photon's height */
#define BOUNCE_OFFSET 1e-5 /* m: bounce origins are moved off the surface */
#define PROBE 0.01        /* m: exposure probes in front of a wall */

/* A hint to fetch the cache line at p (a splat's rows are fetched before
 * its weights are computed; nothing on other compilers). */
#if defined(__GNUC__)
#define PHOTON_PREFETCH(p) __builtin_prefetch(p)
#define PHOTON_PREFETCH_W(p) __builtin_prefetch(p, 1)
#else
#define PHOTON_PREFETCH(p) ((void)(p))
#define PHOTON_PREFETCH_W(p) ((void)(p))
#endif

void photon_config_default(photon_config *c)
{
    memset(c, 0, sizeof *c);
    c->chart_w = 256;
    c->chart_h = 32;
    c->level_blocks[0] = 10;
    c->level_blocks[1] = 40;
    c->level_blocks[2] = 160;
    c->level_blocks[3] = 640;
    c->aerial_res = 512;
    c->coverage_probes = 3;
    c->kernel_max = 4.0;
    c->kernel_min = 2.0;
    c->kernel_frames = 8.0;
    c->max_bounces = 16;
    c->lamp_res = 64;
    c->lamp_photons = 32768;
    c->lamp_kernel = 1.5;
    c->lamp_slots = 0;
    c->lamp_cache_bytes = (size_t)4 << 20;
    c->near_radius = 60.0;
    c->cell_size = 0.0;
    c->coarsest_level = PHOTON_LEVELS;
}

void photon_config_gather(photon_config *c, const scene *s)
{
    photon_config_default(c);
    c->coarsest_level = 2;
    c->kernel_min = c->kernel_max = 4.0;
    c->lookup_radius = 3.0;
    if (s && s->nblocks > c->level_blocks[2])
        c->level_blocks[2] = s->nblocks;
}

static int config_ok(const photon_config *c)
{
    int L;
    if (c->chart_w < 8 || c->chart_h < 8 || c->aerial_res < 2 || c->coverage_probes < 1 ||
        c->coverage_probes > 16 || c->lamp_res < 2 || c->chart_w > 65536 || c->chart_h > 65536 ||
        c->aerial_res > 65536 || c->lamp_res > 4096)
        return 0;
    if (!(c->kernel_max > 0.0 && c->kernel_max <= PHOTON_KERNEL_MAX) ||
        !(c->kernel_min > 0.0 && c->kernel_min <= c->kernel_max) ||
        !(c->kernel_frames >= 0.0) ||
        !(c->lamp_kernel > 0.0 && c->lamp_kernel <= PHOTON_KERNEL_MAX) ||
        !(c->near_radius >= 0.0) || c->coarsest_level > PHOTON_LEVELS ||
        !(c->lookup_radius >= 0.0 && c->lookup_radius <= PHOTON_LOOKUP_MAX))
        return 0;
    for (L = 0; L < PHOTON_LEVELS; L++)
        if ((c->chart_w >> L) < 1 || (c->chart_h >> L) < 1)
            return 0;
    return 1;
}

/* ---- small helpers ------------------------------------------------------ */

static double reach_window(double x)
{
    double x2, v;
    if (!(x < 1.0))
        return 0.0;
    if (x < 0.0)
        x = 0.0;
    x2 = x * x;
    v = 1.0 - x2 * x2;
    return v * v;
}

double photon_window(double x)
{
    return reach_window(x);
}

static inline uint64_t rng_next(uint64_t *st)
{
    uint64_t z = (*st += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

uint64_t photon_rand(uint64_t *st)
{
    return rng_next(st);
}

static inline double rng01(uint64_t *st)
{
    return (double)(rng_next(st) >> 11) * (1.0 / 9007199254740992.0);
}

double photon_rand01(uint64_t *st)
{
    return rng01(st);
}

/* cos and sin of 2 pi u for u in [0, 1), without a libm call (sincos was
 * a tenth of the photon pass): u is split into quarter turns q and a
 * remainder f in [-1/2, 1/2] (both exact), t = f pi / 2 lies in
 * [-pi/4, pi/4] where the Taylor series of sin to t^15 and of cos to t^16
 * are within half an ulp; evaluated by Estrin's scheme (short dependency
 * chains), then rotated by q quarter turns. Within 2 ulps of libm's, so
 * the photon pass samples the same directions from the same random
 * numbers as it did with libm (tests/unit/test_photon.c compares). */
static inline void sincos_turn(double u, double *c, double *s)
{
    double x = 4.0 * u, qf = floor(x + 0.5), t = (x - qf) * (PI / 2.0);
    double t2 = t * t, t4 = t2 * t2, t8 = t4 * t4, sn, cs;
    int q = (int)qf & 3;
    sn = ((1.0 + (-1.0 / 6.0) * t2) + ((1.0 / 120.0) + (-1.0 / 5040.0) * t2) * t4) +
         (((1.0 / 362880.0) + (-1.0 / 39916800.0) * t2) +
          ((1.0 / 6227020800.0) + (-1.0 / 1307674368000.0) * t2) * t4) *
             t8;
    sn *= t;
    cs = ((1.0 + (-1.0 / 2.0) * t2) + ((1.0 / 24.0) + (-1.0 / 720.0) * t2) * t4) +
         (((1.0 / 40320.0) + (-1.0 / 3628800.0) * t2) +
          ((1.0 / 479001600.0) + (-1.0 / 87178291200.0) * t2) * t4) *
             t8 +
         (1.0 / 20922789888000.0) * (t8 * t8);
    switch (q) {
    case 0:
        *c = cs;
        *s = sn;
        break;
    case 1:
        *c = -sn;
        *s = cs;
        break;
    case 2:
        *c = -cs;
        *s = -sn;
        break;
    default:
        *c = sn;
        *s = -cs;
        break;
    }
}

void photon_sincos_turn(double u, double *c, double *s)
{
    sincos_turn(u, c, s);
}

static inline void sphere_dir(uint64_t *st, double d[3])
{
    double z = 1.0 - 2.0 * rng01(st), r = sqrt(1.0 - z * z > 0.0 ? 1.0 - z * z : 0.0);
    double c, s;
    sincos_turn(rng01(st), &c, &s);
    d[0] = r * c;
    d[1] = r * s;
    d[2] = z;
}

void photon_sphere_dir(uint64_t *st, double d[3])
{
    sphere_dir(st, d);
}

void photon_lamp_dir(const scene_lamp *Lp, uint64_t *rng, double d[3])
{
    uint32_t tries = 0;
    sphere_dir(rng, d);
    if (!Lp->photometry)
        return;
    /* rejection: directions uniform on the sphere kept with probability
     * I(d) / peak leave with the distribution of I (SPEC §2.1); a table
     * of (almost) no flux gives up after 2^24 tries */
    while (!(rng01(rng) * Lp->intensity < lamp_intensity(Lp, d)) && ++tries < (1u << 24))
        sphere_dir(rng, d);
}

static void cosine_dir(uint64_t *st, const double n[3], double d[3])
{
    double u1 = rng01(st), u2 = rng01(st);
    double r = sqrt(u1), cp, sp, a, b, c = sqrt(1.0 - u1);
    double t[3], bt[3], l;
    sincos_turn(u2, &cp, &sp);
    a = r * cp;
    b = r * sp;
    geom_basis3(n, t, bt);
    d[0] = a * t[0] + b * bt[0] + c * n[0];
    d[1] = a * t[1] + b * bt[1] + c * n[1];
    d[2] = a * t[2] + b * bt[2] + c * n[2];
    l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    d[0] /= l;
    d[1] /= l;
    d[2] /= l;
}

void photon_cosine_dir(uint64_t *st, const double n[3], double d[3])
{
    cosine_dir(st, n, d);
}

/* Storage slot of grid texel k: k itself, or idx[k] on a sparse grid
 * (-1 when not charted). */
static long slot_of(const uint32_t *idx, size_t k)
{
    if (!idx)
        return (long)k;
    return idx[k] == PHOTON_NONE ? -1 : (long)idx[k];
}

static int texel_ok(const float *area, const float *height, const uint32_t *idx, double z,
                    size_t k)
{
    long s = slot_of(idx, k);
    if (s < 0 || !(area[s] > 0.0f))
        return 0;
    if (height && fabs((double)height[k] - z) > HEIGHT_TOL)
        return 0;
    return 1;
}

/* Wraps or rejects column i; returns -1 when outside. */
static int column(int i, uint32_t w, int wrap)
{
    if (i >= 0 && i < (int)w)
        return i;
    if (!wrap)
        return -1;
    return ((i % (int)w) + (int)w) % (int)w;
}

/* A grid being splatted into or read: flux of the output (the whole grid,
 * a window of it, or the slots of a sparse grid), validity from area,
 * height and idx of the whole grid. */
typedef struct grid {
    const float *area, *height;
    const uint32_t *idx;
    double z;
    uint32_t w, h;
    int wrap;
    int win;                  /* output is the window (ow, oh, ox, oy) */
    uint32_t ow, oh;
    int32_t ox, oy;
} grid;

/* Output index (in texels) of grid texel (i, j), or -1. */
static long out_index(const grid *g, int i, int j)
{
    if (g->win) {
        int a = i - g->ox, b = j - g->oy;
        if (a < 0 || b < 0 || a >= (int)g->ow || b >= (int)g->oh)
            return -1;
        return (long)b * (long)g->ow + a;
    }
    return slot_of(g->idx, (size_t)j * g->w + (size_t)i);
}

/* Area of grid texel k (valid texels only). */
static double texel_area(const grid *g, size_t k)
{
    return (double)g->area[slot_of(g->idx, k)];
}

static int gvalid(const grid *g, int i, int j)
{
    return texel_ok(g->area, g->height, g->idx, g->z, (size_t)j * g->w + (size_t)i);
}

static void deposit(float *out, long o, const double phi[PHOTON_CH], double share)
{
    int c;
    if (o < 0)
        return;
    for (c = 0; c < PHOTON_CH; c++)
        out[(size_t)o * PHOTON_CH + (size_t)c] += (float)(phi[c] * share);
}

/* Nearest valid texel of the 3 x 3 around (fx, fy); returns 0 when none. */
static int nearest3(const grid *g, double fx, double fy, int *bi, int *bj)
{
    double bd = INFINITY;
    int ci = (int)floor(fx), cj = (int)floor(fy), i, j;
    for (j = cj - 1; j <= cj + 1; j++) {
        if (j < 0 || j >= (int)g->h)
            continue;
        for (i = ci - 1; i <= ci + 1; i++) {
            int ii = column(i, g->w, g->wrap);
            double dx = (i + 0.5) - fx, dy = (j + 0.5) - fy, d2 = dx * dx + dy * dy;
            if (ii < 0)
                continue;
            if (gvalid(g, ii, j) && d2 < bd) {
                bd = d2;
                *bi = ii;
                *bj = j;
            }
        }
    }
    return bd < INFINITY;
}

/* Output slot of valid grid texel (i, j) (k = j w + i): the texel itself,
 * its sparse slot or its window index; -1 when the texel is not valid
 * (TEXEL_INVALID) or valid but outside the window (TEXEL_OUTSIDE: it still
 * takes its share of the weights). Inlined in the splat's loop: it is the
 * pass's innermost test. */
#define TEXEL_INVALID (-2L)
#define TEXEL_OUTSIDE (-1L)
static long valid_slot(const grid *g, int i, int j, size_t k)
{
    long s = (long)k;
    if (g->idx) {
        if (g->idx[k] == PHOTON_NONE)
            return TEXEL_INVALID;
        s = (long)g->idx[k];
    }
    if (!(g->area[s] > 0.0f))
        return TEXEL_INVALID;
    if (g->height && fabs((double)g->height[k] - g->z) > HEIGHT_TOL)
        return TEXEL_INVALID;
    if (g->win) {
        int a = i - g->ox, b = j - g->oy;
        if (a < 0 || b < 0 || a >= (int)g->ow || b >= (int)g->oh)
            return TEXEL_OUTSIDE;
        return (long)b * (long)g->ow + a;
    }
    return s;
}

/* Asks for the cache lines of rows j0..j1, columns i0..i1 (clamped, not
 * wrapped) of the grid's area, height and (whole-grid output) flux: a
 * splat's texels are scattered over a few rows of big arrays and missed
 * the cache one after the other; fetched together they arrive together. */
static void prefetch_rows(const float *out, const grid *g, int i0, int i1, int j0, int j1)
{
    int j;
    if (g->idx)
        return;
    i0 = i0 < 0 ? 0 : i0;
    i1 = i1 >= (int)g->w ? (int)g->w - 1 : i1;
    j0 = j0 < 0 ? 0 : j0;
    j1 = j1 >= (int)g->h ? (int)g->h - 1 : j1;
    if (i1 < i0)
        return;
    for (j = j0; j <= j1; j++) {
        size_t a = (size_t)j * g->w + (size_t)i0, b = (size_t)j * g->w + (size_t)i1;
        PHOTON_PREFETCH(g->area + a);
        PHOTON_PREFETCH(g->area + b);
        if (g->height) {
            PHOTON_PREFETCH(g->height + a);
            PHOTON_PREFETCH(g->height + b);
        }
        if (!g->win) {
            size_t k;
            for (k = a; k <= b + 3; k += 4) /* 4 texels of 16 bytes a line */
                PHOTON_PREFETCH_W(out + (k < b ? k : b) * PHOTON_CH);
        }
    }
}

/* Whether a photon at (fx, fy) lands on a surface its chart holds: on a
 * chart of heights (the aerial chart, the lamps' floor maps), the texel
 * under it charted at the photon's height (off the grid: yes). A texel
 * holds one height, that of its centre, and its area counts the part of
 * it at that height; a photon on another surface (a roof of another
 * height, the ground beside a roof) is not represented, and splatted onto
 * the nearest texels of its height it would add to their flux light from
 * an area they do not count: with coarse texels (a small --mem) roofs took
 * the light of the roofs around them, several times what the fine chart
 * gives. So it is not stored (counted lost). */
static int own_texel(const grid *g, double fx, double fy)
{
    int i, j;
    if (!g->height || !(fx >= 0.0 && fy >= 0.0 && fx < (double)g->w && fy < (double)g->h))
        return 1;
    i = (int)floor(fx);
    j = (int)floor(fy);
    return gvalid(g, i, j);
}

/* The cone kernel over the texels within r of (fx, fy), weights normalised
 * over the valid ones. The square's columns (wrapped) and their dx^2 are
 * found once; a texel is looked at only when d^2 says it may be inside
 * (the exact test on the distance, as the weight uses it, follows), so
 * the corners of the square cost neither a read nor a square root. */
static int splat_any(float *out, const grid *g, double fx, double fy, double r,
                     const double phi[PHOTON_CH])
{
    enum { MAXK = 2 * PHOTON_KERNEL_MAXI + 3 };
    long to[MAXK * MAXK];
    int col[MAXK];
    double wt[MAXK * MAXK], dx2[MAXK], sum = 0.0, r2, rinv, sinv;
    int n = 0, i, j, i0, i1, j0, j1, c;
    if (r > PHOTON_KERNEL_MAX)
        r = PHOTON_KERNEL_MAX;
    if (!(fx > -r - 2.0 && fy > -r - 2.0 && fx < (double)g->w + r + 2.0 &&
          fy < (double)g->h + r + 2.0) ||
        !own_texel(g, fx, fy))
        return 0;
    i0 = (int)floor(fx - r);
    i1 = (int)floor(fx + r);
    j0 = (int)floor(fy - r);
    j1 = (int)floor(fy + r);
    r2 = r * r * (1.0 + 1e-9); /* a little wide: the exact test is on sqrt */
    rinv = 1.0 / r; /* two divisions per texel were a fifth of the splat */
    for (i = i0; i <= i1; i++) {
        double dx = (i + 0.5) - fx;
        col[i - i0] = column(i, g->w, g->wrap);
        dx2[i - i0] = dx * dx;
    }
    for (j = j0; j <= j1; j++) {
        double dy = (j + 0.5) - fy, dy2 = dy * dy;
        size_t row;
        if (j < 0 || j >= (int)g->h || !(dy2 < r2))
            continue;
        row = (size_t)j * g->w;
        for (c = 0; c <= i1 - i0; c++) {
            double d2 = dx2[c] + dy2, dist, wgt;
            long o;
            if (!(d2 < r2) || col[c] < 0)
                continue;
            dist = sqrt(d2);
            if (dist >= r)
                continue;
            o = valid_slot(g, col[c], j, row + (size_t)col[c]);
            if (o == TEXEL_INVALID)
                continue;
            wgt = 1.0 - dist * rinv;
            to[n] = o;
            wt[n] = wgt;
            sum += wgt;
            n++;
        }
    }
    if (n == 0 || !(sum > 0.0)) {
        int bi = 0, bj = 0;
        if (!nearest3(g, fx, fy, &bi, &bj))
            return 0;
        deposit(out, out_index(g, bi, bj), phi, 1.0);
        return 1;
    }
    sinv = 1.0 / sum;
    for (i = 0; i < n; i++)
        if (to[i] >= 0) {
            float *q = out + (size_t)to[i] * PHOTON_CH;
            double share = wt[i] * sinv;
            for (c = 0; c < PHOTON_CH; c++)
                q[c] += (float)(phi[c] * share);
        }
    return 1;
}

static grid grid_full(const float *area, const float *height, const uint32_t *idx, double z,
                      uint32_t w, uint32_t h, int wrap)
{
    grid g;
    memset(&g, 0, sizeof g);
    g.area = area;
    g.height = height;
    g.idx = idx;
    g.z = z;
    g.w = w;
    g.h = h;
    g.wrap = wrap;
    return g;
}

static grid grid_win(uint32_t ow, uint32_t oh, int32_t ox, int32_t oy, const float *area,
                     const float *height, double z, uint32_t w, uint32_t h)
{
    grid g = grid_full(area, height, NULL, z, w, h, 0);
    g.win = 1;
    g.ow = ow;
    g.oh = oh;
    g.ox = ox;
    g.oy = oy;
    return g;
}

int photon_splat(float *flux, const float *area, const float *height, double z, uint32_t w,
                 uint32_t h, int wrap, double fx, double fy, double r,
                 const double phi[PHOTON_CH])
{
    grid g = grid_full(area, height, NULL, z, w, h, wrap);
    return splat_any(flux, &g, fx, fy, r, phi);
}

int photon_splat_sparse(float *flux, const float *area, const uint32_t *idx, uint32_t w,
                        uint32_t h, double fx, double fy, double r, const double phi[PHOTON_CH])
{
    grid g = grid_full(area, NULL, idx, 0.0, w, h, 0);
    return splat_any(flux, &g, fx, fy, r, phi);
}

int photon_splat_win(float *out, uint32_t ow, uint32_t oh, int32_t ox, int32_t oy,
                     const float *area, const float *height, double z, uint32_t w, uint32_t h,
                     double fx, double fy, double r, const double phi[PHOTON_CH])
{
    grid g = grid_win(ow, oh, ox, oy, area, height, z, w, h);
    return splat_any(out, &g, fx, fy, r, phi);
}

static double gather_any(const float *out, const grid *g, double fx, double fy,
                         double e[PHOTON_CH])
{
    double gx = fx - 0.5, gy = fy - 0.5, sf[PHOTON_CH] = {0.0, 0.0, 0.0, 0.0}, sa = 0.0;
    int i0, j0, a, b, c, bi = 0, bj = 0;
    double tx, ty;
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = 0.0;
    if (!(fx > -2.0 && fy > -2.0 && fx < (double)g->w + 2.0 && fy < (double)g->h + 2.0))
        return 0.0;
    i0 = (int)floor(gx);
    j0 = (int)floor(gy);
    tx = gx - i0;
    ty = gy - j0;
    for (b = 0; b < 2; b++)
        for (a = 0; a < 2; a++) {
            int j = j0 + b, i = column(i0 + a, g->w, g->wrap);
            double wgt = (a ? tx : 1.0 - tx) * (b ? ty : 1.0 - ty);
            long o;
            if (j < 0 || j >= (int)g->h || i < 0 || wgt <= 0.0)
                continue;
            if (!gvalid(g, i, j))
                continue;
            o = out_index(g, i, j);
            if (o >= 0)
                for (c = 0; c < PHOTON_CH; c++)
                    sf[c] += wgt * out[(size_t)o * PHOTON_CH + (size_t)c];
            sa += wgt * texel_area(g, (size_t)j * g->w + (size_t)i);
        }
    if (sa > 0.0) {
        for (c = 0; c < PHOTON_CH; c++)
            e[c] = sf[c] / sa;
        return e[0];
    }
    /* no valid texel among the four: the nearest valid one of the 3 x 3 */
    if (nearest3(g, fx, fy, &bi, &bj)) {
        long o = out_index(g, bi, bj);
        double ar = texel_area(g, (size_t)bj * g->w + (size_t)bi);
        if (o >= 0)
            for (c = 0; c < PHOTON_CH; c++)
                e[c] = (double)out[(size_t)o * PHOTON_CH + (size_t)c] / ar;
    }
    return e[0];
}

double photon_gather(const float *flux, const float *area, const float *height, double z,
                     uint32_t w, uint32_t h, int wrap, double fx, double fy,
                     double e[PHOTON_CH])
{
    grid g = grid_full(area, height, NULL, z, w, h, wrap);
    return gather_any(flux, &g, fx, fy, e);
}

/* The wide lookup (cfg.lookup_radius r, 0 < r <= PHOTON_LOOKUP_MAX): e =
 * sum w F / sum w A over the valid texels (same surface: charted, same
 * height) whose centres lie within r texels, w = 1 - dist / r; else the
 * 2 x 2 lookup. */
double photon_gather_wide(const float *flux, const float *area, const float *height, double z,
                          uint32_t w, uint32_t h, int wrap, double fx, double fy, double r,
                          double e[PHOTON_CH])
{
    double sf[PHOTON_CH] = {0.0, 0.0, 0.0, 0.0}, sa = 0.0, r2 = r * r, dx2[2 * PHOTON_LOOKUP_MAXI + 1];
    int ri, ci, cj, a, b, c;
    if (r <= 0.0 || r > PHOTON_LOOKUP_MAX ||
        !(fx > -2.0 && fy > -2.0 && fx < (double)w + 2.0 && fy < (double)h + 2.0)) {
        grid g = grid_full(area, height, NULL, z, w, h, wrap);
        return gather_any(flux, &g, fx, fy, e);
    }
    /* converted once in range (a point far off the grid: a float-to-int
     * overflow, undefined, before the test moved above them) */
    ri = (int)ceil(r);
    ci = (int)floor(fx);
    cj = (int)floor(fy);
    /* each column's dx^2 once, for every row */
    for (a = ci - ri; a <= ci + ri; a++) {
        double dx = a + 0.5 - fx;
        dx2[a - ci + ri] = dx * dx;
    }
    /* rows in order, each texel's terms as gvalid and texel_area give them */
    for (b = cj - ri < 0 ? 0 : cj - ri; b <= cj + ri && b < (int)h; b++) {
        double dy = b + 0.5 - fy, dy2 = dy * dy;
        size_t row = (size_t)b * w;
        if (dy2 >= r2)
            continue; /* d2 >= dy2 for every texel of the row */
        for (a = ci - ri; a <= ci + ri; a++) {
            double d2 = dx2[a - ci + ri] + dy2, wt, ar;
            const float *f;
            int i;
            size_t k;
            if (d2 >= r2)
                continue;
            i = column(a, w, wrap);
            if (i < 0)
                continue;
            k = row + (size_t)i;
            ar = (double)area[k];
            if (!(area[k] > 0.0f) || (height && fabs((double)height[k] - z) > HEIGHT_TOL))
                continue;
            wt = 1.0 - sqrt(d2) / r;
            f = flux + k * PHOTON_CH;
            for (c = 0; c < PHOTON_CH; c++)
                sf[c] += wt * f[c];
            sa += wt * ar;
        }
    }
    if (!(sa > 0.0)) {
        grid g = grid_full(area, height, NULL, z, w, h, wrap);
        return gather_any(flux, &g, fx, fy, e);
    }
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = sf[c] / sa;
    return e[0];
}

double photon_gather_sparse(const float *flux, const float *area, const uint32_t *idx,
                            uint32_t w, uint32_t h, double fx, double fy, double e[PHOTON_CH])
{
    grid g = grid_full(area, NULL, idx, 0.0, w, h, 0);
    return gather_any(flux, &g, fx, fy, e);
}

double photon_gather_win(const float *out, uint32_t ow, uint32_t oh, int32_t ox, int32_t oy,
                         const float *area, const float *height, double z, uint32_t w,
                         uint32_t h, double fx, double fy, double e[PHOTON_CH])
{
    grid g = grid_win(ow, oh, ox, oy, area, height, z, w, h);
    return gather_any(out, &g, fx, fy, e);
}

static void aerial_xy(const photon_sys *ps, double x, double y, double *fx, double *fy)
{
    *fx = (x - ps->gx0) / ps->gtex;
    *fy = (y - ps->gy0) / ps->gtex;
}

void photon_aerial_xy(const photon_sys *ps, double x, double y, double *fx, double *fy)
{
    aerial_xy(ps, x, y, fx, fy);
}

static double kernel_radius(const photon_config *c, uint32_t frames)
{
    double m = frames > 0 ? (double)(frames - 1) : 0.0;
    if (c->kernel_frames <= 0.0)
        return c->kernel_min;
    return c->kernel_min + (c->kernel_max - c->kernel_min) * c->kernel_frames /
                               (c->kernel_frames + m);
}

/* ---- sizes -------------------------------------------------------------- */

/* Allocation or counting: with a == NULL only bytes are summed. */
typedef struct taker {
    arena *a;
    size_t bytes;
    int failed;
} taker;

static void *take(taker *t, size_t n, size_t size)
{
    size_t b = arena_mul(n ? n : 1, size);
    void *p;
    if (b == SIZE_MAX) {
        t->failed = 1;
        t->bytes = SIZE_MAX;
        return NULL;
    }
    if (t->bytes != SIZE_MAX)
        t->bytes = (t->bytes + b + 63 > t->bytes) ? t->bytes + b + 63 : SIZE_MAX;
    if (!t->a)
        return NULL;
    p = arena_calloc(t->a, PLX_PART_PHOTON, n ? n : 1, size, 16);
    if (!p)
        t->failed = 1;
    return p;
}

static uint32_t level_slots(const scene *s, const photon_config *c, int L)
{
    return c->level_blocks[L] < s->nblocks ? c->level_blocks[L] : s->nblocks;
}

static void aerial_dims(const scene *s, const photon_config *c, uint32_t *gw, uint32_t *gh,
                        double *tex)
{
    double w = s->bounds[2] - s->bounds[0], h = s->bounds[3] - s->bounds[1];
    double m = w > h ? w : h, t;
    if (!(m > 0.0))
        m = 1.0;
    t = m / c->aerial_res;
    *tex = t;
    *gw = (uint32_t)ceil(w / t - 1e-9);
    *gh = (uint32_t)ceil(h / t - 1e-9);
    if (*gw < 1)
        *gw = 1;
    if (*gh < 1)
        *gh = 1;
}

static double max_lamp_radius(const scene *s)
{
    double r = 0.0;
    uint32_t i;
    for (i = 0; i < s->nlamps; i++)
        if (s->lamps[i].radius > r)
            r = s->lamps[i].radius;
    return r;
}

static uint32_t dwin_side(const scene *s, const photon_config *c, double gtex)
{
    double side = 2.0 * max_lamp_radius(s) / gtex;
    return (uint32_t)ceil(side) + 2u * ((uint32_t)ceil(c->kernel_min) + 2u);
}

size_t photon_lamp_slot_bytes(const scene *s, const photon_config *cfg)
{
    photon_config c;
    uint32_t gw, gh, dn;
    double tex;
    size_t f;
    if (!s)
        return 0;
    if (!cfg)
        photon_config_default(&c);
    else
        c = *cfg;
    aerial_dims(s, &c, &gw, &gh, &tex);
    dn = dwin_side(s, &c, tex);
    f = (size_t)c.lamp_res * c.lamp_res;
    return sizeof(photon_lamp_slot) + 2 * (f * sizeof(float) + 63) +
           (f * PHOTON_CH * sizeof(float) + 63) + (size_t)dn * dn * PHOTON_CH * sizeof(float) +
           63;
}

static uint32_t cache_slots(const scene *s, const photon_config *c)
{
    size_t n;
    if (s->nlamps == 0)
        return 0;
    if (c->lamp_slots)
        n = c->lamp_slots;
    else
        n = c->lamp_cache_bytes / photon_lamp_slot_bytes(s, c);
    if (n > s->nlamps)
        n = s->nlamps;
    return (uint32_t)n;
}

/* Upper bound on the covered-ground slots, from the scene alone: the aerial
 * texels meeting the boxes of raised buildings (min_height > 0), at most
 * the whole grid. A texel with covered ground has a probe inside a raised
 * footprint, hence inside its box. */
static uint32_t covered_capacity(const scene *s, uint32_t gw, uint32_t gh, double tex)
{
    uint64_t n = 0, g = (uint64_t)gw * gh;
    uint32_t b;
    for (b = 0; b < s->nbld && n < g; b++) {
        const scene_building *B = &s->bld[b];
        double i0, i1, j0, j1;
        if (!(B->min_height > 0.0))
            continue;
        i0 = floor((B->box[0] - s->bounds[0]) / tex);
        i1 = floor((B->box[2] - s->bounds[0]) / tex);
        j0 = floor((B->box[1] - s->bounds[1]) / tex);
        j1 = floor((B->box[3] - s->bounds[1]) / tex);
        i0 = i0 < 0.0 ? 0.0 : i0;
        j0 = j0 < 0.0 ? 0.0 : j0;
        i1 = i1 > gw - 1.0 ? gw - 1.0 : i1;
        j1 = j1 > gh - 1.0 ? gh - 1.0 : j1;
        if (i1 >= i0 && j1 >= j0)
            n += (uint64_t)(i1 - i0 + 1.0) * (uint64_t)(j1 - j0 + 1.0);
    }
    if (n > g)
        n = g;
    return n < UINT32_MAX ? (uint32_t)n : UINT32_MAX - 1u;
}

/* Takes (or counts) every buffer of the system. */
static void layout(photon_sys *ps, taker *t, const scene *s, const photon_config *c)
{
    photon_sys dummy;
    int L;
    uint32_t i;
    size_t g;
    if (!ps) {
        memset(&dummy, 0, sizeof dummy);
        ps = &dummy;
    }
    ps->eclass = take(t, s->npts, 1);
    ps->ez0 = take(t, s->npts, sizeof(float));
    ps->ez1 = take(t, s->npts, sizeof(float));
    ps->blevel = take(t, s->nblocks, 1);
    ps->bslot = take(t, s->nblocks, sizeof(uint32_t));
    ps->bcx = take(t, s->nblocks, sizeof(double));
    ps->bcy = take(t, s->nblocks, sizeof(double));
    ps->bhmax = take(t, s->nblocks, sizeof(double));
    ps->bfacade = take(t, s->nblocks, sizeof(double));
    ps->bamb = take(t, arena_mul(s->nblocks, PHOTON_CH), sizeof(double));
    for (L = 0; L < PHOTON_LEVELS; L++) {
        photon_level *lv = &ps->lev[L];
        size_t tex;
        lv->w = c->chart_w >> L;
        lv->h = c->chart_h >> L;
        lv->nslots = level_slots(s, c, L);
        tex = arena_mul(arena_mul((size_t)lv->nslots * 2, lv->w), lv->h);
        lv->flux = take(t, arena_mul(tex, PHOTON_CH), sizeof(float));
        lv->area = take(t, tex, sizeof(float));
        lv->slot_block = take(t, lv->nslots, sizeof(uint32_t));
        lv->slot_frames = take(t, lv->nslots, sizeof(uint32_t));
        lv->free_slots = take(t, lv->nslots, sizeof(uint32_t));
    }
    aerial_dims(s, c, &ps->gw, &ps->gh, &ps->gtex);
    g = (size_t)ps->gw * ps->gh;
    surface_keys_dims(s, &ps->keys);
    ps->keys.ring = take(t, ps->keys.ncy, sizeof(uint32_t));
    ps->keys.box = take(t, arena_mul(ps->keys.ncy, 4), sizeof(double));
    ps->keys.first = take(t, (size_t)ps->keys.cyw * ps->keys.cyh + 1, sizeof(uint32_t));
    ps->keys.item = take(t, surface_keys_pairs(s, &ps->keys), sizeof(uint32_t));
    ps->gheight = take(t, g, sizeof(float));
    ps->garea = take(t, g, sizeof(float));
    ps->gflux = take(t, arena_mul(g, PHOTON_CH), sizeof(float));
    ps->gimp = take(t, arena_mul(g, PHOTON_CH), sizeof(float));
    ps->cov_cap = covered_capacity(s, ps->gw, ps->gh, ps->gtex);
    if (ps->cov_cap > 0) {
        ps->gcov = take(t, g, sizeof(uint32_t));
        ps->cov_area = take(t, ps->cov_cap, sizeof(float));
        ps->cov_flux = take(t, (size_t)ps->cov_cap * PHOTON_CH, sizeof(float));
        ps->cov_imp = take(t, (size_t)ps->cov_cap * PHOTON_CH, sizeof(float));
    }
    ps->lamp_cdf = take(t, s->nlamps, sizeof(double));
    ps->refined = take(t, s->nlamps, 1);
    ps->lamp_slot = take(t, s->nlamps, sizeof(uint32_t));
    ps->nslots = cache_slots(s, c);
    ps->dwin_n = dwin_side(s, c, ps->gtex);
    ps->slots = take(t, ps->nslots, sizeof(photon_lamp_slot));
    for (i = 0; i < ps->nslots; i++) {
        size_t f = (size_t)c->lamp_res * c->lamp_res;
        float *fl = take(t, f * PHOTON_CH, sizeof(float));
        float *ar = take(t, f, sizeof(float));
        float *hg = take(t, f, sizeof(float));
        float *dw = take(t, (size_t)ps->dwin_n * ps->dwin_n * PHOTON_CH, sizeof(float));
        if (ps != &dummy && ps->slots) {
            ps->slots[i].flux = fl;
            ps->slots[i].area = ar;
            ps->slots[i].height = hg;
            ps->slots[i].dwin = dw;
        }
    }
}

size_t photon_bytes(const scene *s, const photon_config *cfg)
{
    photon_config c;
    taker t;
    if (!s)
        return 0;
    if (!cfg)
        photon_config_default(&c);
    else
        c = *cfg;
    t.a = NULL;
    t.bytes = sizeof(photon_sys) + 63;
    t.failed = 0;
    layout(NULL, &t, s, &c);
    if (t.bytes == SIZE_MAX)
        return SIZE_MAX;
    {
        size_t tb = trace_bytes_ex(s, c.cell_size, !c.no_lamp_tables);
        return t.bytes + tb < t.bytes ? SIZE_MAX : t.bytes + tb;
    }
}

/* One quality step of photon_config_fit: 0 facade charts, 1 aerial chart,
 * 2 lamp cache (first: it serves refinement only); 0 when that one is at
 * its floor. */
static int fit_step(photon_config *c, const scene *s, int which)
{
    if (which == 0 && c->chart_h >= 2 * PHOTON_FIT_CHART_H && c->chart_w >= 16) {
        c->chart_w /= 2;
        c->chart_h /= 2;
        return 1;
    }
    if (which == 1 && c->aerial_res >= 2 * PHOTON_FIT_AERIAL) {
        c->aerial_res /= 2;
        return 1;
    }
    if (which == 2 && c->lamp_slots == 0 && c->lamp_cache_bytes >= 4 * photon_lamp_slot_bytes(s, c)) {
        c->lamp_cache_bytes /= 2;
        return 1;
    }
    return 0;
}

int photon_config_fit(photon_config *c, const scene *s, size_t budget)
{
    int steps = 0, turn = 2, tried;
    while (photon_bytes(s, c) > budget) {
        if (!c->no_lamp_tables) {
            c->no_lamp_tables = 1;
            steps++;
            continue;
        }
        for (tried = 0; tried < 3 && !fit_step(c, s, turn); tried++)
            turn = (turn + 1) % 3;
        if (tried == 3)
            return -1;
        turn = (turn + 1) % 3;
        steps++;
    }
    return steps;
}

/* ---- walls and blocks ----------------------------------------------------- */

/* Exposure and chart class of every wall. */
static void walls_classify(photon_sys *ps)
{
    const scene *s = ps->s;
    const tracer *T = ps->T;
    uint32_t b;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *B = &s->bld[b];
        uint32_t r;
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            uint32_t k;
            for (k = 0; k < R->count; k++) {
                uint32_t e = R->first + k;
                const vec2 *p = &s->pts[e], *q = &s->pts[T->enext[e]];
                double ex = q->x - p->x, ey = q->y - p->y, l = sqrt(ex * ex + ey * ey);
                double qx, qy, z0 = B->min_height, z1 = B->height, fx, fy;
                int cls = PHOTON_EDGE_OUTER, faced = 0;
                if (!(l > 0.0)) {
                    ps->eclass[e] = PHOTON_EDGE_INTERNAL;
                    continue;
                }
                qx = 0.5 * (p->x + q->x) + PROBE * ey / l;
                qy = 0.5 * (p->y + q->y) - PROBE * ex / l;
                fx = floor((qx - T->x0) * T->inv);
                fy = floor((qy - T->y0) * T->inv);
                if (fx >= 0.0 && fy >= 0.0 && fx < (double)T->nx && fy < (double)T->ny) {
                    uint32_t c = (uint32_t)fy * T->nx + (uint32_t)fx, j;
                    for (j = T->start[c]; j < T->start[c + 1]; j++) {
                        uint32_t o = T->ids[j];
                        const scene_building *O = &s->bld[o];
                        if (o == b || qx < O->box[0] || qx > O->box[2] || qy < O->box[1] ||
                            qy > O->box[3] || !trace_inside(T, o, qx, qy))
                            continue;
                        /* the covered range [O->min_height, O->height] */
                        if (O->min_height <= z0 && O->height > z0)
                            z0 = O->height;
                        else if (O->height >= z1 && O->min_height < z1)
                            z1 = O->min_height;
                        else if (O->min_height > z0 && O->height < z1) {
                            if (O->min_height - z0 >= z1 - O->height)
                                z1 = O->min_height;
                            else
                                z0 = O->height;
                        } else
                            continue;
                        faced = 1;
                    }
                }
                if (!(z1 > z0)) {
                    cls = PHOTON_EDGE_INTERNAL;
                    z0 = z1 = 0.0;
                } else if (r > 0 || faced) {
                    cls = PHOTON_EDGE_INNER; /* a courtyard, or a strip over a neighbour */
                } else if (B->block < s->nblocks) {
                    const scene_block *K = &s->blocks[B->block];
                    uint32_t rr;
                    vec2 probe;
                    probe.x = qx;
                    probe.y = qy;
                    for (rr = 1; rr < K->ring_count; rr++) {
                        const scene_ring *CR = &s->block_rings[K->ring_first + rr];
                        const vec2 *cp = &s->block_pts[CR->first];
                        if (geom_ring_area2(cp, CR->count) < 0.0 &&
                            geom_point_in_ring(probe, cp, CR->count) == GEOM_INSIDE) {
                            cls = PHOTON_EDGE_INNER;
                            break;
                        }
                    }
                }
                ps->eclass[e] = (uint8_t)cls;
                ps->ez0[e] = (float)z0;
                ps->ez1[e] = (float)z1;
            }
        }
    }
}

static void blocks_setup(photon_sys *ps)
{
    const scene *s = ps->s;
    uint32_t k, j;
    double dsum = 0.0;
    for (k = 0; k < s->nblocks; k++) {
        const scene_block *K = &s->blocks[k];
        double hm = 0.0, area = 0.0;
        ps->bcx[k] = 0.5 * (K->box[0] + K->box[2]);
        ps->bcy[k] = 0.5 * (K->box[1] + K->box[3]);
        for (j = 0; j < K->bld_count; j++) {
            uint32_t b = s->block_bld[K->bld_first + j], r;
            const scene_building *B = &s->bld[b];
            if (B->height > hm)
                hm = B->height;
            for (r = 0; r < B->ring_count; r++) {
                const scene_ring *R = &s->rings[B->ring_first + r];
                uint32_t i;
                for (i = 0; i < R->count; i++) {
                    uint32_t e = R->first + i;
                    const vec2 *p = &s->pts[e], *q = &s->pts[ps->T->enext[e]];
                    if (ps->eclass[e] == PHOTON_EDGE_INTERNAL)
                        continue;
                    area += hypot(q->x - p->x, q->y - p->y) * (double)(ps->ez1[e] - ps->ez0[e]);
                }
            }
        }
        ps->bhmax[k] = hm > 0.0 ? hm : 1.0;
        ps->bfacade[k] = area;
        ps->blevel[k] = PHOTON_LEVELS;
        ps->bslot[k] = PHOTON_NONE;
        dsum += hypot(K->box[2] - K->box[0], K->box[3] - K->box[1]);
    }
    ps->mean_diam = s->nblocks ? dsum / s->nblocks : 1.0;
    if (!(ps->mean_diam > 0.0))
        ps->mean_diam = 1.0;
}

/* Facade chart coordinates of (x, y, z) for block k at level L. */
static void chart_xy(const photon_sys *ps, uint32_t k, const photon_level *lv, double x, double y,
                     double z, double *fx, double *fy)
{
    double u = (atan2(y - ps->bcy[k], x - ps->bcx[k]) + PI) / (2.0 * PI);
    if (u >= 1.0)
        u -= 1.0;
    *fx = u * lv->w;
    *fy = z / ps->bhmax[k] * lv->h;
}

void photon_chart_xy(const photon_sys *ps, uint32_t k, const photon_level *lv, double x, double y,
                     double z, double *fx, double *fy)
{
    chart_xy(ps, k, lv, x, y, z, fx, fy);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Texel areas of the two charts of block k in slot 'slot' of level L; tb
 * is scratch for chart_w + 2 doubles. The area of a texel is exact: each
 * wall is cut where the rays from the centre at the column boundaries
 * cross it. */
static void chart_build(photon_sys *ps, uint32_t k, int L, uint32_t slot, double *tb)
{
    const scene *s = ps->s;
    photon_level *lv = &ps->lev[L];
    const scene_block *K = &s->blocks[k];
    size_t csize = (size_t)lv->w * lv->h, base = (size_t)slot * 2 * csize;
    double H = ps->bhmax[k];
    uint32_t j;
    memset(lv->flux + base * PHOTON_CH, 0, 2 * csize * PHOTON_CH * sizeof(float));
    memset(lv->area + base, 0, 2 * csize * sizeof(float));
    lv->slot_frames[slot] = 0;
    for (j = 0; j < K->bld_count; j++) {
        uint32_t b = s->block_bld[K->bld_first + j], r;
        const scene_building *B = &s->bld[b];
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            uint32_t i;
            for (i = 0; i < R->count; i++) {
                uint32_t e = R->first + i, np, pc;
                const vec2 *p = &s->pts[e], *q = &s->pts[ps->T->enext[e]];
                double len, z0, z1;
                float *area;
                if (ps->eclass[e] == PHOTON_EDGE_INTERNAL)
                    continue;
                area = lv->area + base + (ps->eclass[e] == PHOTON_EDGE_INNER ? csize : 0);
                z0 = ps->ez0[e];
                z1 = ps->ez1[e];
                /* exact pieces: the edge cut by the rays from the centre at
                 * every column boundary */
                np = 0;
                tb[np++] = 0.0;
                tb[np++] = 1.0;
                {
                    double ex = q->x - p->x, ey = q->y - p->y;
                    double cpx = ps->bcx[k] - p->x, cpy = ps->bcy[k] - p->y;
                    uint32_t cb;
                    for (cb = 0; cb < lv->w; cb++) {
                        double th = -PI + 2.0 * PI * cb / lv->w, ux = cos(th), uy = sin(th);
                        double den = ux * ey - uy * ex, t, sr;
                        if (den == 0.0)
                            continue;
                        t = (ux * cpy - uy * cpx) / den;
                        sr = (ex * (-cpy) - ey * (-cpx)) / (ex * uy - ey * ux);
                        if (t > 0.0 && t < 1.0 && sr > 0.0)
                            tb[np++] = t;
                    }
                }
                qsort(tb, np, sizeof *tb, cmp_double);
                len = hypot(q->x - p->x, q->y - p->y);
                for (pc = 0; pc + 1 < np; pc++) {
                    double t = 0.5 * (tb[pc] + tb[pc + 1]), fx, fy, x, y, plen;
                    int row, r0, r1;
                    plen = (tb[pc + 1] - tb[pc]) * len;
                    if (!(plen > 0.0))
                        continue;
                    x = p->x + t * (q->x - p->x);
                    y = p->y + t * (q->y - p->y);
                    chart_xy(ps, k, lv, x, y, 0.0, &fx, &fy);
                    {
                        int col = (int)floor(fx);
                        if (col < 0)
                            col = 0;
                        if (col >= (int)lv->w)
                            col = (int)lv->w - 1;
                        r0 = (int)floor(z0 / H * lv->h);
                        r1 = (int)ceil(z1 / H * lv->h);
                        if (r0 < 0)
                            r0 = 0;
                        if (r1 > (int)lv->h)
                            r1 = (int)lv->h;
                        for (row = r0; row < r1; row++) {
                            double lo = H * row / lv->h, hi = H * (row + 1) / lv->h;
                            double ov = (z1 < hi ? z1 : hi) - (z0 > lo ? z0 : lo);
                            if (ov > 0.0)
                                area[(size_t)row * lv->w + (size_t)col] += (float)(plen * ov);
                        }
                    }
                }
            }
        }
    }
}

/* ---- aerial chart ---------------------------------------------------------- */

/* Whether the ground at (x, y) is open (no building standing on the ground
 * contains it) and under a raised building. */
static int ground_covered(const photon_sys *ps, double x, double y)
{
    const tracer *T = ps->T;
    const scene *s = ps->s;
    double fx = floor((x - T->x0) * T->inv), fy = floor((y - T->y0) * T->inv);
    uint32_t c, j;
    int raised = 0;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < (double)T->nx && fy < (double)T->ny))
        return 0;
    c = (uint32_t)fy * T->nx + (uint32_t)fx;
    for (j = T->start[c]; j < T->start[c + 1]; j++) {
        const scene_building *B = &s->bld[T->ids[j]];
        if (x < B->box[0] || x > B->box[2] || y < B->box[1] || y > B->box[3] ||
            !trace_inside(T, T->ids[j], x, y))
            continue;
        if (!(B->min_height > 0.0))
            return 0;
        raised = 1;
    }
    return raised;
}

/* Slots of the covered-ground layer: every aerial texel under the box of a
 * raised building with covered probes gets one, its area the covered
 * fraction of the texel. */
static void covered_build(photon_sys *ps)
{
    const scene *s = ps->s;
    uint32_t b, k = ps->cfg.coverage_probes;
    size_t g = (size_t)ps->gw * ps->gh, q;
    double t = ps->gtex;
    ps->ncov = 0;
    if (!ps->gcov)
        return;
    for (q = 0; q < g; q++)
        ps->gcov[q] = PHOTON_NONE;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *B = &s->bld[b];
        double fx0, fy0, fx1, fy1;
        int i, j, i0, i1, j0, j1;
        if (!(B->min_height > 0.0))
            continue;
        aerial_xy(ps, B->box[0], B->box[1], &fx0, &fy0);
        aerial_xy(ps, B->box[2], B->box[3], &fx1, &fy1);
        i0 = fx0 < 0.0 ? 0 : (int)floor(fx0);
        j0 = fy0 < 0.0 ? 0 : (int)floor(fy0);
        i1 = fx1 >= ps->gw - 1.0 ? (int)ps->gw - 1 : (int)floor(fx1);
        j1 = fy1 >= ps->gh - 1.0 ? (int)ps->gh - 1 : (int)floor(fy1);
        for (j = j0; j <= j1; j++)
            for (i = i0; i <= i1; i++) {
                size_t at = (size_t)j * ps->gw + (size_t)i;
                uint32_t a, c, m = 0;
                if (ps->gcov[at] != PHOTON_NONE || ps->ncov >= ps->cov_cap)
                    continue;
                for (c = 0; c < k; c++)
                    for (a = 0; a < k; a++)
                        m += (uint32_t)ground_covered(ps, ps->gx0 + (i + (a + 0.5) / k) * t,
                                                      ps->gy0 + (j + (c + 0.5) / k) * t);
                if (m == 0)
                    continue;
                ps->gcov[at] = ps->ncov;
                ps->cov_area[ps->ncov] = (float)(t * t * m / (double)(k * k));
                ps->ncov++;
            }
    }
}

static int covered_at(const photon_sys *ps, double x, double y)
{
    double fx, fy;
    if (!ps->gcov)
        return 0;
    aerial_xy(ps, x, y, &fx, &fy);
    if (!(fx >= 0.0 && fy >= 0.0 && fx < (double)ps->gw && fy < (double)ps->gh))
        return 0;
    if (ps->gcov[(size_t)floor(fy) * ps->gw + (size_t)floor(fx)] == PHOTON_NONE)
        return 0;
    return trace_top(ps->T, x, y, NULL) > HEIGHT_TOL;
}

int photon_covered_at(const photon_sys *ps, double x, double y)
{
    return covered_at(ps, x, y);
}

static void aerial_build(photon_sys *ps)
{
    uint32_t i, j, a, b, k = ps->cfg.coverage_probes;
    double t = ps->gtex;
    for (j = 0; j < ps->gh; j++)
        for (i = 0; i < ps->gw; i++) {
            double cx = ps->gx0 + (i + 0.5) * t, cy = ps->gy0 + (j + 0.5) * t;
            double hc = surface_key(&ps->keys, ps->s, cx, cy, trace_top(ps->T, cx, cy, NULL));
            uint32_t match = 0;
            for (b = 0; b < k; b++)
                for (a = 0; a < k; a++) {
                    double x = ps->gx0 + (i + (a + 0.5) / k) * t;
                    double y = ps->gy0 + (j + (b + 0.5) / k) * t;
                    if (fabs(surface_key(&ps->keys, ps->s, x, y, trace_top(ps->T, x, y, NULL)) - hc) <= HEIGHT_TOL)
                        match++;
                }
            if (match == 0)
                match = 1; /* an even k misses the centre */
            ps->gheight[(size_t)j * ps->gw + i] = (float)hc;
            ps->garea[(size_t)j * ps->gw + i] = (float)(t * t * match / (double)(k * k));
        }
    covered_build(ps);
}

/* ---- creation ---------------------------------------------------------------- */

/* Each lamp's flux (SPEC §2.1: the integral of I, 4 pi I when isotropic)
 * as the cumulative table the photons are shared by. */
static void lamp_fluxes(photon_sys *ps)
{
    const scene *s = ps->s;
    uint32_t i;
    ps->flux_total = 0.0;
    for (i = 0; i < s->nlamps; i++) {
        double f = s->lamps[i].intensity > 0.0 && s->lamps[i].radius > 0.0 ? lamp_flux(&s->lamps[i]) : 0.0;
        ps->flux_total += f;
        ps->lamp_cdf[i] = ps->flux_total;
    }
}

void photon_lamps_changed(photon_sys *ps)
{
    lamp_fluxes(ps);
    photon_reset(ps);
}

plx_status photon_create(arena *a, const scene *s, const photon_config *cfg, photon_sys **out)
{
    arena_mark m;
    photon_sys *ps;
    taker t;
    plx_status st;
    photon_config c;
    uint32_t i;
    int L;
    double eye[3];
    if (!a || !s || !out)
        return PLX_E_INVALID;
    *out = NULL;
    if (!cfg)
        photon_config_default(&c);
    else
        c = *cfg;
    if (!config_ok(&c) || (s->nbld > 0 && s->nblocks == 0))
        return PLX_E_INVALID;
    m = arena_get_mark(a);
    ps = arena_calloc(a, PLX_PART_PHOTON, 1, sizeof *ps, 16);
    if (!ps)
        return PLX_E_NOMEM;
    ps->a = a;
    ps->s = s;
    ps->cfg = c;
    st = trace_create_ex(a, PLX_PART_PHOTON, s, c.cell_size, !c.no_lamp_tables, &ps->T);
    if (st != PLX_OK) {
        arena_release(a, &m);
        return st;
    }
    t.a = a;
    t.bytes = 0;
    t.failed = 0;
    layout(ps, &t, s, &c);
    if (t.failed) {
        arena_release(a, &m);
        return PLX_E_NOMEM;
    }
    ps->gx0 = s->bounds[0];
    ps->gy0 = s->bounds[1];
    walls_classify(ps);
    blocks_setup(ps);
    for (L = 0; L < PHOTON_LEVELS; L++) {
        photon_level *lv = &ps->lev[L];
        for (i = 0; i < lv->nslots; i++) {
            lv->slot_block[i] = PHOTON_NONE;
            lv->free_slots[i] = lv->nslots - 1 - i;
        }
        lv->nfree = lv->nslots;
    }
    surface_keys_build(s, &ps->keys);
    aerial_build(ps);
    lamp_fluxes(ps);
    for (i = 0; i < s->nlamps; i++)
        ps->lamp_slot[i] = PHOTON_NONE;
    for (i = 0; i < ps->nslots; i++) {
        ps->slots[i].lamp = PHOTON_NONE;
        ps->slots[i].prev = i == 0 ? PHOTON_NONE : i - 1;
        ps->slots[i].next = i + 1 == ps->nslots ? PHOTON_NONE : i + 1;
    }
    ps->lru_head = ps->nslots ? 0 : PHOTON_NONE;
    ps->lru_tail = ps->nslots ? ps->nslots - 1 : PHOTON_NONE;
    eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
    eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
    eye[2] = 1.7;
    st = photon_set_viewer(ps, eye, NULL, 0.0);
    if (st != PLX_OK) {
        arena_release(a, &m);
        return st;
    }
    *out = ps;
    return PLX_OK;
}

void photon_reset(photon_sys *ps)
{
    int L;
    uint32_t i;
    size_t g = (size_t)ps->gw * ps->gh;
    for (L = 0; L < PHOTON_LEVELS; L++) {
        photon_level *lv = &ps->lev[L];
        size_t cs = (size_t)lv->w * lv->h * 2;
        for (i = 0; i < lv->nslots; i++) {
            memset(lv->flux + (size_t)i * cs * PHOTON_CH, 0, cs * PHOTON_CH * sizeof(float));
            lv->slot_frames[i] = 0;
        }
    }
    for (i = 0; i < ps->s->nblocks * PHOTON_CH; i++)
        ps->bamb[i] = 0.0;
    ps->amb_frames = 0;
    memset(ps->gflux, 0, g * PHOTON_CH * sizeof(float));
    memset(ps->gimp, 0, g * PHOTON_CH * sizeof(float));
    if (ps->cov_cap > 0) {
        memset(ps->cov_flux, 0, (size_t)ps->cov_cap * PHOTON_CH * sizeof(float));
        memset(ps->cov_imp, 0, (size_t)ps->cov_cap * PHOTON_CH * sizeof(float));
    }
    ps->gframes = 0;
    for (i = 0; i < ps->s->nlamps; i++) {
        ps->refined[i] = 0;
        ps->lamp_slot[i] = PHOTON_NONE;
    }
    for (i = 0; i < ps->nslots; i++)
        ps->slots[i].lamp = PHOTON_NONE;
    memset(&ps->st, 0, sizeof ps->st);
}

/* ---- levels ------------------------------------------------------------------- */

typedef struct keyed {
    double key;
    uint32_t id;
} keyed;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

int photon_block_level(const photon_sys *ps, uint32_t b)
{
    if (!ps || b >= ps->s->nblocks)
        return PHOTON_LEVELS;
    return ps->blevel[b];
}

plx_status photon_set_viewer(photon_sys *ps, const double eye[3], const double dir[3],
                             double fov_deg)
{
    const scene *s = ps->s;
    arena_mark m = arena_get_mark(ps->a);
    keyed *order;
    uint8_t *want;
    double *tb;
    uint32_t k, cnt[PHOTON_LEVELS];
    double bsz = ps->mean_diam, half = 0.5 * fov_deg * PI / 180.0;
    int L;
    ps->eye[0] = eye[0];
    ps->eye[1] = eye[1];
    ps->eye[2] = eye[2];
    if (s->nblocks == 0)
        return PLX_OK;
    order = arena_scratch(ps->a, (size_t)s->nblocks * sizeof *order, 16);
    want = arena_scratch(ps->a, s->nblocks, 16);
    tb = arena_scratch(ps->a, ((size_t)ps->cfg.chart_w + 2) * sizeof *tb, 16);
    if (!order || !want || !tb) {
        arena_release(ps->a, &m);
        return PLX_E_NOMEM;
    }
    for (k = 0; k < s->nblocks; k++) {
        const double *bx = s->blocks[k].box;
        double dx = eye[0] < bx[0] ? bx[0] - eye[0] : (eye[0] > bx[2] ? eye[0] - bx[2] : 0.0);
        double dy = eye[1] < bx[1] ? bx[1] - eye[1] : (eye[1] > bx[3] ? eye[1] - bx[3] : 0.0);
        double dz = eye[2] < 0.0 ? -eye[2] : (eye[2] > ps->bhmax[k] ? eye[2] - ps->bhmax[k] : 0.0);
        double d = sqrt(dx * dx + dy * dy + dz * dz);
        int lvl = d < 3 * bsz ? 0 : d < 6 * bsz ? 1 : d < 12 * bsz ? 2 : d < 24 * bsz ? 3 : 4;
        if (dir && fov_deg > 0.0 && fov_deg < 360.0) {
            double cx = ps->bcx[k] - eye[0], cy = ps->bcy[k] - eye[1];
            double cz = 0.5 * ps->bhmax[k] - eye[2];
            double cl = sqrt(cx * cx + cy * cy + cz * cz);
            double rad = 0.5 * sqrt((bx[2] - bx[0]) * (bx[2] - bx[0]) +
                                    (bx[3] - bx[1]) * (bx[3] - bx[1]) +
                                    ps->bhmax[k] * ps->bhmax[k]);
            if (cl > rad) {
                double cosang = (cx * dir[0] + cy * dir[1] + cz * dir[2]) / cl;
                double ang = acos(cosang > 1.0 ? 1.0 : cosang < -1.0 ? -1.0 : cosang);
                double angr = asin(rad / cl);
                if (ang - angr > half)
                    lvl = d < 3 * bsz ? 2 : 4;
            }
        }
        if (lvl > (int)ps->cfg.coarsest_level)
            lvl = (int)ps->cfg.coarsest_level;
        want[k] = (uint8_t)lvl;
        order[k].key = d;
        order[k].id = k;
    }
    qsort(order, s->nblocks, sizeof *order, cmp_keyed);
    for (L = 0; L < PHOTON_LEVELS; L++)
        cnt[L] = 0;
    for (k = 0; k < s->nblocks; k++) {
        uint32_t b = order[k].id;
        int lvl = want[b];
        while (lvl < PHOTON_LEVELS && cnt[lvl] >= ps->lev[lvl].nslots)
            lvl++;
        if (lvl < PHOTON_LEVELS)
            cnt[lvl]++;
        want[b] = (uint8_t)lvl;
    }
    /* free the slots of blocks that move, then give them new ones */
    for (k = 0; k < s->nblocks; k++)
        if (want[k] != ps->blevel[k] && ps->bslot[k] != PHOTON_NONE) {
            photon_level *lv = &ps->lev[ps->blevel[k]];
            lv->slot_block[ps->bslot[k]] = PHOTON_NONE;
            lv->free_slots[lv->nfree++] = ps->bslot[k];
            ps->bslot[k] = PHOTON_NONE;
        }
    for (k = 0; k < s->nblocks; k++)
        if (want[k] != ps->blevel[k]) {
            ps->blevel[k] = want[k];
            if (want[k] < PHOTON_LEVELS) {
                photon_level *lv = &ps->lev[want[k]];
                uint32_t slot = lv->free_slots[--lv->nfree];
                lv->slot_block[slot] = k;
                ps->bslot[k] = slot;
                chart_build(ps, k, want[k], slot, tb);
            }
        }
    for (L = 0; L <= PHOTON_LEVELS; L++)
        ps->level_count[L] = 0;
    for (k = 0; k < s->nblocks; k++)
        ps->level_count[ps->blevel[k]]++;
    arena_release(ps->a, &m);
    return PLX_OK;
}

/* ---- tracing ---------------------------------------------------------------------- */

/* The ground's RGB albedo at (x, y): every ground albedo read of the
 * photon pass goes through here (a ground image's pixel or the scene's
 * ground_albedo, src/ground.c). */
static void ground_albedo_rgb(const scene *s, double x, double y, double rgb[3])
{
    scene_ground_albedo(s, x, y, rgb);
}

/* RGB albedo of the surface at hit h: the ground's, or the building's
 * scalar albedo (grey) on walls, roofs and undersides (the caster hands it
 * over with the hit: reading the scene's building record missed the
 * cache at most bounces). */
static void hit_albedo_rgb(const photon_sys *ps, const trace_hit *h, double rgb[3])
{
    if (h->kind == TRACE_GROUND)
        ground_albedo_rgb(ps->s, h->p[0], h->p[1], rgb);
    else
        rgb[0] = rgb[1] = rgb[2] = h->albedo;
}

static double albedo_scalar(const double rgb[3])
{
    if (rgb[0] == rgb[1] && rgb[1] == rgb[2])
        return rgb[0];
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

double photon_albedo_scalar(const double rgb[3])
{
    return albedo_scalar(rgb);
}

static int bounce(double f[PHOTON_CH], const double alb[3], double u)
{
    double p = albedo_scalar(alb);
    int c;
    if (!(u < p))
        return 0;
    /* f[0] *= a_Y / p = 1; x / x is exactly 1, so grey albedos change nothing */
    for (c = 0; c < 3; c++)
        f[1 + c] *= alb[c] / p;
    return 1;
}

int photon_bounce(double f[PHOTON_CH], const double alb[3], double u)
{
    return bounce(f, alb, u);
}

static void add_rgb(double acc[3], const double f[PHOTON_CH])
{
    acc[0] += f[1];
    acc[1] += f[2];
    acc[2] += f[3];
}

/* A stored photon, decided but not yet splatted: the progressive pass
 * works out where a photon goes (chart, coordinates, radius) when it
 * arrives and asks for the texel rows then, and splats it a few photons
 * later (store_queue), when the rows have arrived; the splats and every
 * sum they touch still happen in arrival order, so the results are the
 * same bytes as splatting at once. */
enum { OP_LOST, OP_SKIPPED, OP_AMBIENT, OP_SPLAT };
typedef struct store_op {
    int what;                 /* OP_* */
    uint32_t block;           /* wall photons: the block (PHOTON_NONE otherwise) */
    double *stored;           /* OP_SPLAT: the stats sum of its chart kind */
    float *out;               /* OP_SPLAT: flux of the grid */
    grid g;
    double fx, fy, r;
    double f[PHOTON_CH];
} store_op;

static void prepare_splat(store_op *op, double *stored, float *out, grid g, double fx,
                          double fy, double r)
{
    double rr = r > PHOTON_KERNEL_MAX ? PHOTON_KERNEL_MAX : r;
    op->what = OP_SPLAT;
    op->stored = stored;
    op->out = out;
    op->g = g;
    op->fx = fx;
    op->fy = fy;
    op->r = r;
    if (fx > -rr - 2.0 && fy > -rr - 2.0 && fx < (double)g.w + rr + 2.0 &&
        fy < (double)g.h + rr + 2.0)
        prefetch_rows(out, &op->g, (int)floor(fx - rr), (int)floor(fx + rr),
                      (int)floor(fy - rr), (int)floor(fy + rr));
}

/* A photon on a wall: its block's facade chart or ambient term. */
static void prepare_wall(photon_sys *ps, const trace_hit *h, store_op *op)
{
    const scene *s = ps->s;
    uint32_t k = s->bld[h->bld].block;
    photon_level *lv;
    size_t cs, base;
    double fx, fy;
    int L;
    if (k >= s->nblocks || ps->eclass[h->edge] == PHOTON_EDGE_INTERNAL) {
        op->what = OP_LOST;
        return;
    }
    op->block = k;
    L = ps->blevel[k];
    if (L >= PHOTON_LEVELS) {
        op->what = OP_AMBIENT;
        return;
    }
    lv = &ps->lev[L];
    cs = (size_t)lv->w * lv->h;
    base = (size_t)ps->bslot[k] * 2 * cs + (ps->eclass[h->edge] == PHOTON_EDGE_INNER ? cs : 0);
    chart_xy(ps, k, lv, h->p[0], h->p[1], h->p[2], &fx, &fy);
    prepare_splat(op, &ps->st.stored_chart, lv->flux + base * PHOTON_CH,
                  grid_full(lv->area + base, NULL, NULL, 0.0, lv->w, lv->h, 1), fx, fy,
                  kernel_radius(&ps->cfg, lv->slot_frames[ps->bslot[k]]));
}

/* Where the progressive pass puts a photon arriving at h with weights f. */
static void prepare_progressive(photon_sys *ps, uint32_t lamp, const trace_hit *h,
                                const double f[PHOTON_CH], store_op *op)
{
    double fx, fy, r = kernel_radius(&ps->cfg, ps->gframes);
    int c;
    for (c = 0; c < PHOTON_CH; c++)
        op->f[c] = f[c];
    op->block = PHOTON_NONE;
    if (h->kind == TRACE_WALL) {
        prepare_wall(ps, h, op);
        return;
    }
    if (h->kind != TRACE_GROUND && h->kind != TRACE_ROOF) {
        op->what = OP_LOST;
        return;
    }
    if (ps->refined[lamp]) {
        op->what = OP_SKIPPED;
        return;
    }
    aerial_xy(ps, h->p[0], h->p[1], &fx, &fy);
    if (h->kind == TRACE_GROUND && covered_at(ps, h->p[0], h->p[1])) {
        prepare_splat(op, &ps->st.stored_covered, ps->cov_flux,
                      grid_full(ps->cov_area, NULL, ps->gcov, 0.0, ps->gw, ps->gh, 0), fx, fy, r);
    } else {
        double key = surface_key(&ps->keys, ps->s, h->p[0], h->p[1], h->p[2]);
        prepare_splat(op, &ps->st.stored_aerial, ps->gflux,
                      grid_full(ps->garea, ps->gheight, NULL, key, ps->gw, ps->gh, 0), fx, fy, r);
    }
}

/* Splats a prepared photon and counts it. */
static void commit_store(photon_sys *ps, const store_op *op)
{
    photon_stats *st = &ps->st;
    const double *f = op->f;
    int c;
    if (op->block != PHOTON_NONE)
        for (c = 0; c < PHOTON_CH; c++)
            ps->bamb[(size_t)op->block * PHOTON_CH + (size_t)c] += f[c];
    switch (op->what) {
    case OP_LOST:
        st->lost += f[0];
        break;
    case OP_SKIPPED:
        st->skipped_refined += f[0];
        break;
    case OP_AMBIENT:
        st->stored_ambient += f[0];
        add_rgb(st->stored_rgb, f);
        break;
    default:
        if (splat_any(op->out, &op->g, op->fx, op->fy, op->r, f)) {
            *op->stored += f[0];
            add_rgb(st->stored_rgb, f);
        } else
            st->lost += f[0];
        break;
    }
}

/* The photons prepared and not yet splatted (oldest at head). */
#define STORE_QUEUE 4
typedef struct store_queue {
    store_op op[STORE_QUEUE];
    unsigned head, n;
} store_queue;

static void store_step(photon_sys *ps, void *ctx, uint32_t lamp, const trace_hit *h,
                       const double f[PHOTON_CH])
{
    store_queue *q = ctx;
    if (q->n == STORE_QUEUE) {
        commit_store(ps, &q->op[q->head]);
        q->head = (q->head + 1) % STORE_QUEUE;
        q->n--;
    }
    prepare_progressive(ps, lamp, h, f, &q->op[(q->head + q->n) % STORE_QUEUE]);
    q->n++;
}

static void store_flush(photon_sys *ps, store_queue *q)
{
    while (q->n > 0) {
        commit_store(ps, &q->op[q->head]);
        q->head = (q->head + 1) % STORE_QUEUE;
        q->n--;
    }
}

static void trace_lamp(photon_sys *ps, uint32_t lamp, double phi, uint64_t *rng,
                       photon_stats *st, photon_store_fn store, void *ctx)
{
    const scene_lamp *Lp = &ps->s->lamps[lamp];
    double o[3], d[3], f[PHOTON_CH], alb[3];
    trace_hit h;
    uint32_t b;
    int c;
    o[0] = Lp->x;
    o[1] = Lp->y;
    o[2] = Lp->z;
    photon_lamp_dir(Lp, rng, d);
    st->photons++;
    st->emitted += phi;
    st->traced++;
    if (trace_lamp_ray(ps->T, lamp, d, &h) == TRACE_SKY)
        return;
    f[0] = phi * reach_window(h.t / Lp->radius);
    if (!(f[0] > 0.0))
        return;
    for (c = 0; c < 3; c++)
        f[1 + c] = f[0] * (double)Lp->color[c];
    st->first += f[0];
    for (b = 0; b < ps->cfg.max_bounces; b++) {
        hit_albedo_rgb(ps, &h, alb);
        if (!bounce(f, alb, rng01(rng))) {
            st->absorbed += f[0];
            return;
        }
        cosine_dir(rng, h.n, d);
        o[0] = h.p[0] + BOUNCE_OFFSET * h.n[0];
        o[1] = h.p[1] + BOUNCE_OFFSET * h.n[1];
        o[2] = h.p[2] + BOUNCE_OFFSET * h.n[2];
        st->traced++;
        if (trace_ray(ps->T, o, d, INFINITY, &h) == TRACE_SKY) {
            st->escaped += f[0];
            return;
        }
        st->arrived += f[0];
        add_rgb(st->arrived_rgb, f);
        store(ps, ctx, lamp, &h, f);
    }
    st->cut += f[0];
}

void photon_trace_lamp(photon_sys *ps, uint32_t lamp, double phi, uint64_t *rng,
                       photon_stats *st, photon_store_fn store, void *ctx)
{
    trace_lamp(ps, lamp, phi, rng, st, store, ctx);
}

void photon_step(photon_sys *ps, uint32_t n, uint64_t seed)
{
    const scene *s = ps->s;
    /* the state is the seed hashed: frames with neighbouring seeds must
     * not share stream positions (stratified photons of one lamp take the
     * same indices every frame, and correlated streams froze their noise) */
    uint64_t rng = seed ^ 0x5bd1e9955bd1e995ull;
    rng = rng_next(&rng);
    rng = rng_next(&rng);
    uint32_t k, lamp = 0, prev = PHOTON_NONE;
    int L;
    double phi;
    store_queue q;
    q.head = q.n = 0;
    if (!ps || n == 0 || s->nlamps == 0 || !(ps->flux_total > 0.0))
        return;
    trace_lamp_prefetch(ps->T, 0, 0);
    trace_lamp_prefetch(ps->T, 1, 0);
    trace_lamp_prefetch(ps->T, 2, 0);
    for (L = 0; L < PHOTON_LEVELS; L++) {
        photon_level *lv = &ps->lev[L];
        uint32_t i;
        for (i = 0; i < lv->nslots; i++)
            if (lv->slot_block[i] != PHOTON_NONE)
                lv->slot_frames[i]++;
    }
    ps->amb_frames++;
    ps->gframes++;
    ps->st.frames++;
    phi = ps->flux_total / n;
    for (k = 0; k < n; k++) {
        /* stratified choice of the lamp: the k-th of n equal flux shares */
        double u = (k + rng01(&rng)) / n * ps->flux_total;
        while (lamp + 1 < s->nlamps && ps->lamp_cdf[lamp] <= u)
            lamp++;
        if (ps->lamp_cdf[lamp] <= u || (lamp > 0 && ps->lamp_cdf[lamp - 1] > u)) {
            /* rounding at the end of the cdf: search */
            uint32_t lo = 0, hi = s->nlamps - 1;
            while (lo < hi) {
                uint32_t mid = lo + (hi - lo) / 2;
                if (ps->lamp_cdf[mid] > u)
                    hi = mid;
                else
                    lo = mid + 1;
            }
            lamp = lo;
        }
        if (lamp != prev) {
            /* lamps come in order: fetch the next ones' tables early */
            trace_lamp_prefetch(ps->T, lamp + 1, 2);
            trace_lamp_prefetch(ps->T, lamp + 2, 1);
            trace_lamp_prefetch(ps->T, lamp + 3, 0);
            prev = lamp;
        }
        trace_lamp(ps, lamp, phi, &rng, &ps->st, store_step, &q);
    }
    store_flush(ps, &q);
}
