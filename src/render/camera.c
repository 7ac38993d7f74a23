/* camera: a frame's camera (the view, the projection, the sample point
 * within the pixel, the far plane) and a pixel's sample ray. */
#include <math.h>
#include <string.h>

#include "render/render_int.h"

int camera_setup(render *r, const render_camera *c, const render_opts *o)
{
    double f[3], len, rl, t;
    int k;
    const double *b = r->s->bounds;
    for (k = 0; k < 3; k++)
        if (!isfinite(c->eye[k]) || !isfinite(c->target[k]))
            return r->err = "render_frame: eye and target must be finite", 0;
    if (!(c->fov_deg > 0.0 && c->fov_deg < 180.0))
        return r->err = "render_frame: fov must be in (0, 180) degrees", 0;
    if (!render_frame_fits(c->width, c->height, r->max_w, r->max_h))
        return r->err = "render_frame: image size outside 1 .. the render object's maximum", 0;
    if (!(c->eye[2] > 0.0))
        return r->err = "render_frame: the eye must be above the ground (z > 0)", 0;
    if (!(o->near > 0.0) || !isfinite(o->near) || !isfinite(o->exposure))
        return r->err = "render_frame: near must be > 0 and exposure finite", 0;
    for (k = 0; k < 3; k++)
        f[k] = c->target[k] - c->eye[k];
    len = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    if (!(len > 0.0))
        return r->err = "render_frame: eye and target are the same point", 0;
    for (k = 0; k < 3; k++)
        r->f[k] = f[k] / len;
    /* right = f x z */
    r->rt[0] = r->f[1];
    r->rt[1] = -r->f[0];
    r->rt[2] = 0.0;
    rl = sqrt(r->rt[0] * r->rt[0] + r->rt[1] * r->rt[1]);
    if (rl < 1e-12) {
        r->rt[0] = 1.0;
        r->rt[1] = 0.0;
    } else {
        r->rt[0] /= rl;
        r->rt[1] /= rl;
    }
    /* up = right x f */
    r->up[0] = r->rt[1] * r->f[2] - r->rt[2] * r->f[1];
    r->up[1] = r->rt[2] * r->f[0] - r->rt[0] * r->f[2];
    r->up[2] = r->rt[0] * r->f[1] - r->rt[1] * r->f[0];
    for (k = 0; k < 3; k++)
        r->eye[k] = c->eye[k];
    r->w = c->width;
    r->h = c->height;
    r->tanh_ = tan(c->fov_deg * PI / 360.0);
    r->aspect = (double)c->width / (double)c->height;
    r->sx = 1.0 / (r->tanh_ * r->aspect);
    r->sy = 1.0 / r->tanh_;
    r->near_ = o->near;
    /* the sample point within each pixel (anti-aliasing), as a shift of
     * the image in normalised device coordinates */
    r->shift[0] = isfinite(o->shift[0]) ? o->shift[0] : 0.0;
    r->shift[1] = isfinite(o->shift[1]) ? o->shift[1] : 0.0;
    r->shx = 2.0 * r->shift[0] / c->width;
    r->shy = 2.0 * r->shift[1] / c->height;
    /* culling for every sample point within the pixel: a sample point
     * moves a point's clip x by less than 2 / width times w from this
     * one's, y by 2 / height, its row by less than one */
    r->cpad[0] = o->cull_samples ? 2.0 / c->width : 0.0;
    r->cpad[1] = o->cull_samples ? 2.0 / c->height : 0.0;
    r->cpad[2] = o->cull_samples ? 1.0 : 0.0;
    /* far: beyond every corner of the scene box (buildings, lamps' reach);
     * the same eye and near plane as the last frame's (its later sample
     * points): the last far */
    if (!(r->far_ > 0.0 && memcmp(r->far_eye, c->eye, sizeof r->far_eye) == 0 && r->far_near == o->near)) {
        double hx = fmax(fabs(b[0] - c->eye[0]), fabs(b[2] - c->eye[0]));
        double hy = fmax(fabs(b[1] - c->eye[1]), fabs(b[3] - c->eye[1]));
        double hz = fmax(fabs(c->eye[2]), fabs(r->s->height_max - c->eye[2]));
        uint32_t i;
        /* fmax's values without a call a lamp: the maximum so far is
         * finite (the bounds and the eye are), and a NaN, not above it,
         * leaves it as fmax does */
        for (i = 0; i < r->s->nlamps; i++) {
            const scene_lamp *l = &r->s->lamps[i];
            double ax = fabs(l->x - c->eye[0]) + l->radius, ay = fabs(l->y - c->eye[1]) + l->radius;
            double az = fabs(l->z - c->eye[2]) + l->radius;
            hx = ax > hx ? ax : hx;
            hy = ay > hy ? ay : hy;
            hz = az > hz ? az : hz;
        }
        t = sqrt(hx * hx + hy * hy + hz * hz);
        r->far_ = 2.0 * t + 10.0 * o->near + 1.0;
        memcpy(r->far_eye, c->eye, sizeof r->far_eye);
        r->far_near = o->near;
    }
    r->za = (r->far_ + r->near_) / (r->far_ - r->near_);
    r->zb = -2.0 * r->far_ * r->near_ / (r->far_ - r->near_);
    return 1;
}

/* Pixel (i, j)'s sample ray direction (not unit). */
void camera_pixel_dir(const render *r, int32_t i, int32_t j, double d[3])
{
    double ta = r->tanh_ * r->aspect, tb = r->tanh_;
    double bj = (1.0 - 2.0 * (j + 0.5 + r->shift[1]) / r->h) * tb;
    double ai = (2.0 * (i + 0.5 + r->shift[0]) / r->w - 1.0) * ta;
    d[0] = r->f[0] + ai * r->rt[0] + bj * r->up[0];
    d[1] = r->f[1] + ai * r->rt[1] + bj * r->up[1];
    d[2] = r->f[2] + ai * r->rt[2] + bj * r->up[2];
}
