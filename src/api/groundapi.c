/* groundapi: the public face of the ground image (src/scene/ground.c):
 * setting it (which drops the photons traced with the old ground), the
 * albedo at a point, what the scene holds. */
#include <string.h>
#include <math.h>

#include "base/engine.h"
#include "scene/ground.h"
#include "photon/photon.h"

plx_status plx_set_ground_image(plx_engine *e, uint32_t width, uint32_t height, const uint8_t *rgb8,
                                const double bounds[4])
{
    const char *fn = "plx_set_ground_image";
    const double *box;
    plx_status st = eng_need(e, ENG_SCENE, fn);
    if (st != PLX_OK)
        return st;
    eng_clear_error(e);
    if (width == 0 && height == 0 && !rgb8) {
        e->sc->gimg = NULL; /* back to the constant albedo */
    } else {
        if (!rgb8 || width == 0 || height == 0 || width > GROUND_MAX_DIM || height > GROUND_MAX_DIM)
            return eng_fail(e, PLX_E_INVALID, "plx_set_ground_image: width and height must be 1..16384 and "
                                              "rgb8 not NULL (or 0, 0, NULL to remove the image)");
        box = bounds ? bounds : e->sc->ground_image_bounds;
        if (!(isfinite(box[0]) && isfinite(box[1]) && isfinite(box[2]) && isfinite(box[3]) &&
              box[0] < box[2] && box[1] < box[3]))
            return eng_fail(e, PLX_E_INVALID, "plx_set_ground_image: bounds must be 4 finite numbers "
                                              "x0 < x1, y0 < y1");
        st = ground_image_set(&e->mem, e->sc, width, height, rgb8, box);
        if (st == PLX_E_NOMEM)
            return eng_nomem(e, "storing the ground image");
        if (st != PLX_OK)
            return eng_fail(e, st, "plx_set_ground_image: the image is black (mean luminance 0): "
                                   "its albedo cannot be scaled to the ground albedo");
    }
    /* photons traced with the old ground are no longer right */
    if (e->ph)
        photon_reset(e->ph);
    e->indirect_gen++;
    return PLX_OK;
}

plx_status plx_ground_albedo_at(plx_engine *e, double x, double y, double rgb[3])
{
    plx_status st = eng_need(e, ENG_SCENE, "plx_ground_albedo_at");
    if (st != PLX_OK)
        return st;
    if (!rgb || !isfinite(x) || !isfinite(y))
        return eng_fail(e, PLX_E_INVALID, "plx_ground_albedo_at: x and y must be finite and rgb not NULL");
    scene_ground_albedo(e->sc, x, y, rgb);
    return PLX_OK;
}

plx_status plx_ground_image_get(plx_engine *e, plx_ground_image_info *out)
{
    const scene *s;
    plx_status st = eng_need(e, ENG_SCENE, "plx_ground_image_get");
    if (st != PLX_OK)
        return st;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_ground_image_get: out is NULL");
    s = e->sc;
    memset(out, 0, sizeof *out);
    out->path = s->ground_image;
    out->bounds_given = s->ground_image_bounds_given;
    memcpy(out->bounds, s->ground_image_bounds, sizeof out->bounds);
    if (s->gimg) {
        out->width = s->gimg->w;
        out->height = s->gimg->h;
        memcpy(out->bounds, s->gimg->box, sizeof out->bounds);
        memcpy(out->mean_albedo, s->gimg->mean_albedo, sizeof out->mean_albedo);
        out->mean_luminance = ground_luminance(out->mean_albedo);
    } else {
        out->mean_albedo[0] = out->mean_albedo[1] = out->mean_albedo[2] = s->ground_albedo;
        out->mean_luminance = s->ground_albedo;
    }
    return PLX_OK;
}
