/* photon_select: photons only from the lamps that can matter for a region
 * (photon.h, photon_select_lamps). */
#include <math.h>

#include "photon/photon.h"
#include "light/photometry.h"

/* Horizontal distance from (x, y) to the box (0 inside). */
static double box_distance(const double box[4], double x, double y)
{
    double dx = x < box[0] ? box[0] - x : (x > box[2] ? x - box[2] : 0.0);
    double dy = y < box[1] ? box[1] - y : (y > box[3] ? y - box[3] : 0.0);
    return sqrt(dx * dx + dy * dy);
}

uint32_t photon_select_lamps(photon_sys *ps, const double box[4], double margin)
{
    const scene *s = ps->s;
    uint32_t i, n = 0;
    ps->flux_total = 0.0;
    for (i = 0; i < s->nlamps; i++) {
        const scene_lamp *L = &s->lamps[i];
        /* SPEC §2.1: the integral of I (4 pi I when isotropic) */
        double f = L->intensity > 0.0 && L->radius > 0.0 ? lamp_flux(L) : 0.0;
        if (f > 0.0 && box && !(box_distance(box, L->x, L->y) <= L->radius + margin))
            f = 0.0;
        n += f > 0.0;
        ps->flux_total += f;
        ps->lamp_cdf[i] = ps->flux_total;
    }
    photon_reset(ps);
    return n;
}
