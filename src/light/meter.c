/* meter: the pedestrian quantities of SPEC §6 at a point (contract in
 * light.h, light_meter). */
#include "light/meter.h"
#include "light/illuminance.h"
#include "scene/photometry.h"

#include <math.h>

#define METER_PI 3.14159265358979323846

static double meter_window(double x)
{
    double x2 = x * x, c = 1.0 - x2 * x2;
    return c <= 0.0 ? 0.0 : c * c;
}

plx_status light_meter(light *L, const double P[3], const double u[2], double out[4])
{
    static const double up[3] = { 0.0, 0.0, 1.0 };
    const scene *s;
    const bucketgrid *g;
    uint32_t cell, k;
    plx_status st;
    if (!L || !P || !u || !out)
        return PLX_E_INVALID;
    s = L->s;
    g = &L->lgrid;
    out[1] = out[2] = out[3] = 0.0;
    if ((st = light_illuminance(L, P, up, &out[0], NULL)) != PLX_OK)
        return st;
    if (s->nlamps == 0 || g->nx == 0)
        return PLX_OK;
    cell = bucketgrid_cell(g, P[0], P[1]);
    for (k = g->start[cell]; k < g->start[cell + 1]; k++) {
        uint32_t i = g->item[k];
        const scene_lamp *lp = &s->lamps[i];
        double v[3], d2, d, w, om[3], back[3], I, base, h, ud, ev, esc, ehs;
        v[0] = lp->x - P[0];
        v[1] = lp->y - P[1];
        v[2] = lp->z - P[2];
        d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (d2 == 0.0 || !(lp->radius > 0.0) || !(d2 < lp->radius * lp->radius))
            continue;
        d = sqrt(d2);
        w = meter_window(d / lp->radius);
        om[0] = v[0] / d;
        om[1] = v[1] / d;
        om[2] = v[2] / d;
        back[0] = -om[0];
        back[1] = -om[1];
        back[2] = -om[2];
        I = lamp_intensity(lp, back);
        if (!(w > 0.0) || !(I > 0.0))
            continue;
        base = I * w / d2;
        h = sqrt(om[0] * om[0] + om[1] * om[1]);
        ud = u[0] * om[0] + u[1] * om[1];   /* sin(eps) cos(alpha) */
        ev = ud > 0.0 ? base * ud : 0.0;
        esc = h > 0.0 ? base * (h + ud) / METER_PI : 0.0;
        ehs = base * (1.0 + om[2]) / 4.0;
        if (!(ev > 0.0 || esc > 0.0 || ehs > 0.0) || !light_visible(L, i, P))
            continue;
        out[1] += ev;
        out[2] += esc;
        out[3] += ehs;
    }
    return PLX_OK;
}
