/* final_gather: E_indirect by final gathering over exact direct light
 * (final_gather.h). */
#include <math.h>
#include <string.h>

#include "photon/final_gather.h"
#include "photon/indirect.h"
#include "base/geom.h"

static uint64_t mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* The stream's start: the seed and the bits of the point and its normal. */
static uint64_t point_seed(uint64_t seed, const double P[3], const double n[3])
{
    uint64_t h = mix64(seed ^ 0x6a09e667f3bcc909ull), b;
    int k;
    for (k = 0; k < 3; k++) {
        memcpy(&b, &P[k], sizeof b);
        h = mix64(h ^ b);
        memcpy(&b, &n[k], sizeof b);
        h = mix64(h ^ b);
    }
    return h;
}

/* RGB albedo of the surface a ray hit. */
static void hit_albedo(const scene *s, const trace_hit *h, double a[3])
{
    if (h->kind == TRACE_GROUND)
        scene_ground_albedo(s, h->p[0], h->p[1], a);
    else
        a[0] = a[1] = a[2] = h->albedo;
}

/* Side of the small gather that stands in for the photon buffers at an
 * underside (photon.h keeps no chart there, only the block's mean facade
 * term, far too low under a canopy lit from below). */
#define UNDER_SIDE 4

static void gather(photon_sys *ps, tracer *T, light *L, const double P[3], const double n[3],
                   uint32_t side, uint32_t later, uint64_t rs, int depth, double sum[4]);

/* Radiance times pi leaving the surface at h: a (E_direct + wl E_later),
 * scalar in out[0], RGB in out[1..3]; E_later from the photon buffers, or
 * at an underside (first level only) from a small gather of its own; not
 * looked up when wl is 0. */
static void hit_exitance(photon_sys *ps, tracer *T, light *L, const trace_hit *h,
                         uint64_t rs, int depth, double wl, double out[4])
{
    double a[3], ed, ed_rgb[3], ei[PHOTON_CH] = {0.0, 0.0, 0.0, 0.0};
    int c;
    hit_albedo(T->s, h, a);
    light_illuminance(L, h->p, h->n, &ed, ed_rgb);
    if (ps && ps->st.frames > 0 && wl > 0.0) {
        if (h->kind == TRACE_UNDER && depth == 0) {
            gather(ps, T, L, h->p, h->n, UNDER_SIDE, 1, rs, 1, ei);
            for (c = 0; c < PHOTON_CH; c++)
                ei[c] /= UNDER_SIDE * UNDER_SIDE;
        } else {
            photon_indirect_hit(ps, h, ei);
        }
        if (wl != 1.0)
            for (c = 0; c < PHOTON_CH; c++)
                ei[c] *= wl;
    }
    out[0] = photon_albedo_scalar(a) * (ed + ei[0]);
    for (c = 0; c < 3; c++)
        out[1 + c] = a[c] * (ed_rgb[c] + ei[1 + c]);
}

/* Which cell of each later x later block of strata reads E_later: one
 * chosen uniformly per block by its own stream (the directions' stream is
 * not touched), so the blocks' sums estimate E_later without bias. */
static int later_cell(uint64_t lseed, uint32_t later, uint32_t i, uint32_t j)
{
    uint64_t k = mix64(lseed ^ (((uint64_t)(i / later) << 32) | (j / later)));
    return (uint32_t)(k % ((uint64_t)later * later)) == (i % later) * later + j % later;
}

/* Sums over side^2 stratified cosine-weighted directions from P of the
 * exitance (times pi) of the surfaces met; E_later (the photon buffers)
 * at one direction of each later x later block of strata, weighted
 * later^2 (later 1: at every direction; side must be a multiple). */
static void gather(photon_sys *ps, tracer *T, light *L, const double P[3], const double n[3],
                   uint32_t side, uint32_t later, uint64_t rs, int depth, double sum[4])
{
    double t[3], b[3], o[3], inv = 1.0 / side, wl = (double)later * later;
    trace_horizon hz;
    uint64_t lseed = mix64(rs ^ 0x3c6ef372fe94f82bull);
    uint32_t i, j;
    int c;
    geom_basis3(n, t, b);
    for (c = 0; c < 3; c++)
        o[c] = P[c] + 1e-6 * n[c];
    if (o[2] < 0.0)
        o[2] = 0.0;
    if (n[2] == 1.0) /* every ray goes up: those over the horizon need no walk */
        trace_horizon_make(T, o, &hz);
    else
        hz.on = 0;
    for (c = 0; c < 4; c++)
        sum[c] = 0.0;
    for (i = 0; i < side; i++)
        for (j = 0; j < side; j++) {
            double u1 = (i + (mix64(rs++) >> 11) * 0x1p-53) * inv;
            double u2 = (j + (mix64(rs++) >> 11) * 0x1p-53) * inv;
            double r = sqrt(u1), cz = sqrt(1.0 - u1), cx, cy, d[3], x[4];
            trace_hit h;
            photon_sincos_turn(u2, &cx, &cy);
            cx *= r;
            cy *= r;
            for (c = 0; c < 3; c++)
                d[c] = cx * t[c] + cy * b[c] + cz * n[c];
            if (trace_horizon_sky(&hz, d) || trace_ray(T, o, d, INFINITY, &h) == TRACE_SKY)
                continue;
            hit_exitance(ps, T, L, &h, mix64(rs++), depth,
                         later == 1 ? 1.0 : later_cell(lseed, later, i, j) ? wl : 0.0, x);
            for (c = 0; c < 4; c++)
                sum[c] += x[c];
        }
}

double final_gather_rgb(photon_sys *ps, tracer *T, light *L, const double P[3],
                        const double n[3], uint32_t side, uint64_t seed, double rgb[3])
{
    return final_gather_rgb_later(ps, T, L, P, n, side, 1, seed, rgb);
}

double final_gather_rgb_later(photon_sys *ps, tracer *T, light *L, const double P[3],
                              const double n[3], uint32_t side, uint32_t later, uint64_t seed,
                              double rgb[3])
{
    double sum[4], inv = 1.0 / ((double)side * side);
    int c;
    if (later < 1 || side % later != 0)
        later = 1;
    gather(ps, T, L, P, n, side, later, point_seed(seed, P, n), 0, sum);
    if (rgb)
        for (c = 0; c < 3; c++)
            rgb[c] = sum[1 + c] * inv;
    return sum[0] * inv;
}
