/* pixel_hit: the surface a frame's pixel shows, where its sample ray
 * meets it and the normal there (the shading pass and the sparse indirect
 * term ask it), and the cache of the surfaces a frame shows. */
#include <math.h>

#include "base/geom.h"
#include "render/render_int.h"

/* Puts the surfaces of the frame's pixels (and the ground) in the cache,
 * before the shading pass (whose workers only read it): a surface's slot
 * is its id modulo the cache's slots, the last one seen keeps it. */
void pixel_surf_cache_fill(render *r)
{
    size_t p, px = (size_t)r->w * (size_t)r->h;
    uint32_t last = MESH_SURF_NONE, sid, k;
    for (p = 0; p <= px; p++) {
        sid = p < px ? r->id[p] : MESH_SURF_GROUND;
        if (sid == last)
            continue;
        last = sid;
        k = sid & r->sc_mask;
        if (r->sc_id[k] != sid) {
            mesh_surface(r->m, sid, &r->sc[k]);
            r->sc_id[k] = sid;
        }
    }
}

/* Pixel (i, j)'s sample ray and what it meets: the surface (a pixel no
 * building covers that looks down is the ground, and its id is set so),
 * the hit point and the normal facing the eye. Returns 0 for the sky. */
int pixel_hit(render *r, int32_t i, int32_t j, uint32_t *sid_out, double P[3], double n[3])
{
    size_t p = (size_t)j * (size_t)r->w + (size_t)i;
    double d[3], tt, nd;
    uint32_t sid = r->id[p];
    mesh_surf sfv;
    const mesh_surf *sf;
    int k;
    camera_pixel_dir(r, i, j, d);
    if (sid == MESH_SURF_NONE) {
        if (!(d[2] < 0.0))
            return 0;
        sid = MESH_SURF_GROUND;
        r->id[p] = sid;
    }
    sf = pixel_surf(r, sid, &sfv);
    nd = sf->n[0] * d[0] + sf->n[1] * d[1] + sf->n[2] * d[2];
    if (sid == MESH_SURF_GROUND)
        tt = -r->eye[2] / d[2];
    else
        tt = (sf->d - (sf->n[0] * r->eye[0] + sf->n[1] * r->eye[1] + sf->n[2] * r->eye[2])) / nd;
    if (!isfinite(tt) || tt < 0.0)
        tt = 0.0;
    for (k = 0; k < 3; k++) {
        P[k] = r->eye[k] + tt * d[k];
        n[k] = nd > 0.0 ? -sf->n[k] : sf->n[k];
    }
    if (sid == MESH_SURF_GROUND)
        P[2] = 0.0;
    else if (sf->n[2] == 0.0) {
        /* a wall: the point moved towards the eye by geom_round_margin
         * (far from the origin a third of a slanted wall's points were
         * rounded inside their building, in its own shadow) */
        double m = geom_round_margin(P[0], P[1]);
        P[0] += m * n[0];
        P[1] += m * n[1];
    }
    *sid_out = sid;
    return 1;
}
