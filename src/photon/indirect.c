/* indirect: E_indirect at a surface point read from the photon buffers
 * (SPEC §4): the block's facade chart on a wall, the aerial chart plus the
 * lamps' floor maps (nightlight.c) on the ground and roofs, the block's
 * ambient term under a raised building. Contract in indirect.h. */
#include <math.h>
#include <string.h>

#include "photon/indirect.h"
#include "photon/nightlight.h"

#define HEIGHT_TOL 1e-3   /* m: as in photon.c */

/* ---- lookup ------------------------------------------------------------------------ */

/* A block's ambient term (level 4, undersides): mean facade irradiance. */
static void ambient(const photon_sys *ps, uint32_t k, double e[PHOTON_CH])
{
    int c;
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = 0.0;
    if (ps->amb_frames == 0 || !(ps->bfacade[k] > 0.0))
        return;
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = ps->bamb[(size_t)k * PHOTON_CH + (size_t)c] / (ps->bfacade[k] * ps->amb_frames);
}

static void facade_lookup(const photon_sys *ps, const trace_hit *h, double e[PHOTON_CH])
{
    const scene *s = ps->s;
    uint32_t k = s->bld[h->bld].block;
    int L, c;
    const photon_level *lv;
    size_t cs, base;
    uint32_t slot, fr;
    double fx, fy;
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = 0.0;
    if (k >= s->nblocks)
        return;
    L = ps->blevel[k];
    if (L >= PHOTON_LEVELS) {
        ambient(ps, k, e);
        return;
    }
    lv = &ps->lev[L];
    slot = ps->bslot[k];
    fr = lv->slot_frames[slot];
    if (fr == 0)
        return;
    cs = (size_t)lv->w * lv->h;
    base = (size_t)slot * 2 * cs + (ps->eclass[h->edge] == PHOTON_EDGE_INNER ? cs : 0);
    photon_chart_xy(ps, k, lv, h->p[0], h->p[1], h->p[2], &fx, &fy);
    photon_gather_wide(lv->flux + base * PHOTON_CH, lv->area + base, NULL, 0.0, lv->w, lv->h, 1,
                       fx, fy, ps->cfg.lookup_radius, e);
    for (c = 0; c < PHOTON_CH; c++)
        e[c] /= fr;
}

/* The ground or a roof: A / M + the floor-map share; covered ground reads
 * A_cov / M + I_cov. */
static void horizontal_lookup(const photon_sys *ps, const double P[3], double e[PHOTON_CH])
{
    double fx, fy, night[PHOTON_CH], key = surface_key(&ps->keys, ps->s, P[0], P[1], P[2]);
    int c, covered = P[2] <= HEIGHT_TOL && photon_covered_at(ps, P[0], P[1]);
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = 0.0;
    photon_aerial_xy(ps, P[0], P[1], &fx, &fy);
    if (ps->gframes > 0) {
        if (covered)
            photon_gather_sparse(ps->cov_flux, ps->cov_area, ps->gcov, ps->gw, ps->gh, fx, fy, e);
        else
            photon_gather_wide(ps->gflux, ps->garea, ps->gheight, key, ps->gw, ps->gh, 0, fx, fy,
                               ps->cfg.lookup_radius, e);
        for (c = 0; c < PHOTON_CH; c++)
            e[c] /= ps->gframes;
    }
    photon_night_horizontal(ps, P[0], P[1], key, covered, night);
    for (c = 0; c < PHOTON_CH; c++)
        e[c] += night[c];
}

/* A wall or an underside, found with a short probe ray. */
static void vertical_lookup(const photon_sys *ps, const double P[3], const double n[3],
                            double e[PHOTON_CH])
{
    trace_hit h;
    double o[3], d[3], l;
    int c;
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = 0.0;
    o[0] = P[0] + 0.005 * n[0];
    o[1] = P[1] + 0.005 * n[1];
    o[2] = P[2] + 0.005 * n[2];
    if (o[2] < 0.0)
        o[2] = 0.0;
    d[0] = -n[0];
    d[1] = -n[1];
    d[2] = -n[2];
    l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(l > 0.0))
        return;
    d[0] /= l;
    d[1] /= l;
    d[2] /= l;
    trace_ray(ps->T, o, d, 0.02, &h);
    if (h.kind == TRACE_WALL)
        facade_lookup(ps, &h, e);
    else if (h.kind == TRACE_UNDER && ps->s->bld[h.bld].block < ps->s->nblocks)
        ambient(ps, ps->s->bld[h.bld].block, e);
}

double photon_indirect_rgb(photon_sys *ps, const double P[3], const double n[3], double rgb[3])
{
    double e[PHOTON_CH] = {0.0, 0.0, 0.0, 0.0};
    if (ps && P && n) {
        if (n[2] > 0.5)
            horizontal_lookup(ps, P, e);
        else
            vertical_lookup(ps, P, n, e);
    }
    if (rgb) {
        rgb[0] = e[1];
        rgb[1] = e[2];
        rgb[2] = e[3];
    }
    return e[0];
}

/* E_indirect at a surface a ray found (final_gather.c): the same lookups
 * as photon_indirect_rgb, without the probe ray for walls. */
void photon_indirect_hit(photon_sys *ps, const trace_hit *h, double e[PHOTON_CH])
{
    int c;
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = 0.0;
    if (h->kind == TRACE_WALL)
        facade_lookup(ps, h, e);
    else if (h->kind == TRACE_GROUND || h->kind == TRACE_ROOF)
        horizontal_lookup(ps, h->p, e);
    else if (h->kind == TRACE_UNDER && ps->s->bld[h->bld].block < ps->s->nblocks)
        ambient(ps, ps->s->bld[h->bld].block, e);
}

double photon_indirect(photon_sys *ps, const double P[3], const double n[3])
{
    return photon_indirect_rgb(ps, P, n, NULL);
}
