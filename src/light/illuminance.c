/* illuminance: E at surface points from every lamp in reach (SPEC §2),
 * visibility through the lamps' lit regions when the cache holds them
 * (litregion.c) or by the exact segment test (light.c); which lamps light
 * a point. Contract in illuminance.h. */
#include "light/illuminance.h"
#include "light/litregion.h"
#include "scene/photometry.h"

#include <math.h>
#include <string.h>

/* The smooth cut-off of a lamp's reach (SPEC §2). */
static double window(double x)
{
    double x2 = x * x, c = 1.0 - x2 * x2;
    if (c <= 0.0)
        return 0.0;
    return c * c;
}

/* ---- illuminance ------------------------------------------------------------ */

/* Lamp i's uncoloured term at P without visibility; 0 when it cannot
 * contribute. */
static double lamp_geom_term(const scene_lamp *lp, const double P[3], const double n[3])
{
    double v[3], d2, d, x, cw, w, u[3], dot;
    v[0] = lp->x - P[0];
    v[1] = lp->y - P[1];
    v[2] = lp->z - P[2];
    d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if (d2 == 0.0 || !(lp->radius > 0.0) || !(d2 < lp->radius * lp->radius))
        return 0.0;
    dot = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
    if (!(dot > 0.0)) /* behind the surface (cw below would not be > 0) */
        return 0.0;
    d = sqrt(d2);
    x = d / lp->radius;
    w = window(x);
    cw = dot / d;
    if (w == 0.0 || !(cw > 0.0))
        return 0.0;
    if (!lp->photometry)
        return lp->intensity * cw / d2 * w;
    u[0] = -v[0] / d;   /* from the lamp toward P */
    u[1] = -v[1] / d;
    u[2] = -v[2] / d;
    return lamp_intensity(lp, u) * cw / d2 * w;
}

/* Whether lamp_geom_term's first two tests pass (within the reach, in
 * front of the surface), with its arithmetic: 0 means its term is 0. Most
 * lamps listed in a point's cell fail them; this spares them the call. */
static inline int lamp_in_front(const scene_lamp *lp, const double P[3], const double n[3])
{
    double v0 = lp->x - P[0], v1 = lp->y - P[1], v2 = lp->z - P[2];
    double d2 = v0 * v0 + v1 * v1 + v2 * v2;
    return d2 < lp->radius * lp->radius && n[0] * v0 + n[1] * v1 + n[2] * v2 > 0.0;
}

/* Visibility of P from lamp i by the segment path. */
static int visible_exact(light *L, uint32_t i, const double P[3])
{
    double Lp[3];
    Lp[0] = L->s->lamps[i].x;
    Lp[1] = L->s->lamps[i].y;
    Lp[2] = L->s->lamps[i].z;
    return !light_segment_blocked(L, Lp, P);
}

int light_visible(light *L, uint32_t lamp, const double P[3])
{
    const lit_region *r;
    int v = lamp < L->s->nlamps ? light_lamp_visible_cached(L, lamp, P) : -1;
    if (v >= 0)
        return v;
    if (L->pool_cap && light_region_index(L, lamp, &r) == PLX_OK)
        return light_region_visible(L, r, P);
    if (L->pool_cap)
        L->st.fallbacks++;
    return visible_exact(L, lamp, P);
}

/* Walks the lamps reaching P; calls back with each lit lamp's term. */
static int lamps_walk(light *L, const double P[3], const double n[3], int exact,
                      double *E, double rgb[3], uint32_t *ids, double *contrib, int cap)
{
    const scene *s = L->s;
    const bucketgrid *g = &L->lgrid;
    uint32_t cell, k;
    int count = 0;
    double e = 0.0, c[3] = { 0.0, 0.0, 0.0 };
    if (s->nlamps == 0 || g->nx == 0)
        cell = UINT32_MAX;
    else
        cell = bucketgrid_cell(g, P[0], P[1]);
    for (k = cell == UINT32_MAX ? 0 : g->start[cell];
         cell != UINT32_MAX && k < g->start[cell + 1]; k++) {
        uint32_t i = g->item[k];
        double term;
        if (!lamp_in_front(&s->lamps[i], P, n))
            continue;
        term = lamp_geom_term(&s->lamps[i], P, n);
        if (term == 0.0)
            continue;
        if (!(exact ? visible_exact(L, i, P) : light_visible(L, i, P)))
            continue;
        if (count < cap) {
            if (ids) ids[count] = i;
            if (contrib) contrib[count] = term;
        }
        count++;
        e += term;
        c[0] += term * s->lamps[i].color[0];
        c[1] += term * s->lamps[i].color[1];
        c[2] += term * s->lamps[i].color[2];
    }
    if (E)
        *E = e;
    if (rgb)
        memcpy(rgb, c, sizeof c);
    return count;
}

int light_illuminance_cached(const light *L, const double P[3], const double n[3], double rgb[3])
{
    const scene *s = L->s;
    const bucketgrid *g = &L->lgrid;
    uint32_t cell, k;
    double c[3] = { 0.0, 0.0, 0.0 };
    if (L->pool_cap == 0)
        return -1;
    cell = s->nlamps == 0 || g->nx == 0 ? UINT32_MAX : bucketgrid_cell(g, P[0], P[1]);
    for (k = cell == UINT32_MAX ? 0 : g->start[cell]; cell != UINT32_MAX && k < g->start[cell + 1]; k++) {
        uint32_t i = g->item[k];
        const lit_region *r = L->ent[i].reg;
        double term = lamp_geom_term(&s->lamps[i], P, n);
        if (term == 0.0)
            continue;
        if (!r || (P[0] == r->o[0] && P[1] == r->o[1]))
            return -1;
        if (!light_region_visible((light *)L, r, P))
            continue;
        c[0] += term * s->lamps[i].color[0];
        c[1] += term * s->lamps[i].color[1];
        c[2] += term * s->lamps[i].color[2];
    }
    memcpy(rgb, c, sizeof c);
    return 0;
}

void light_cache_box(light *L, double x0, double y0, double x1, double y1)
{
    const scene *s = L->s;
    const bucketgrid *g = &L->lgrid;
    uint32_t c0, c1, cx, cy, k;
    if (s->nlamps == 0 || g->nx == 0 || L->pool_cap == 0)
        return;
    c0 = bucketgrid_cell(g, x0, y0);
    c1 = bucketgrid_cell(g, x1, y1);
    for (cy = c0 / g->nx; cy <= c1 / g->nx; cy++)
        for (cx = c0 % g->nx; cx <= c1 % g->nx; cx++)
            for (k = g->start[cy * g->nx + cx]; k < g->start[cy * g->nx + cx + 1]; k++) {
                const lit_region *r;
                uint32_t i = g->item[k];
                if (!L->ent[i].reg && s->lamps[i].radius > 0.0 && s->lamps[i].intensity > 0.0)
                    (void)light_region_index(L, i, &r);
            }
}

plx_status light_illuminance(light *L, const double P[3], const double n[3],
                             double *E, double rgb[3])
{
    if (!L || !P || !n || !E)
        return PLX_E_INVALID;
    lamps_walk(L, P, n, L->pool_cap == 0, E, rgb, NULL, NULL, 0);
    return PLX_OK;
}

plx_status light_illuminance_exact(light *L, const double P[3], const double n[3],
                                   double *E, double rgb[3])
{
    if (!L || !P || !n || !E)
        return PLX_E_INVALID;
    lamps_walk(L, P, n, 1, E, rgb, NULL, NULL, 0);
    return PLX_OK;
}

int light_lamps_at(light *L, const double P[3], const double n[3],
                   uint32_t *ids, double *contrib, int cap)
{
    if (!L || !P || !n)
        return 0;
    return lamps_walk(L, P, n, L->pool_cap == 0, NULL, NULL, ids, contrib, cap);
}

