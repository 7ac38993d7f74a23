/* glow: the lamps' glow discs, added to a frame and marked for adaptive
 * anti-aliasing. */
#include <math.h>

#include "render/render_int.h"

/* The clip coordinates c of lamp lp's centre. */
static void lamp_clip(const render *r, const scene_lamp *lp, double c[4])
{
    double X[3];
    X[0] = lp->x;
    X[1] = lp->y;
    X[2] = lp->z;
    to_clip(r, X, c);
}

/* lamp_centre from the lamp's clip coordinates c (lamp_clip). */
static int centre_of(const render *r, const scene_lamp *lp, const double c[4], double *px, double *py)
{
    if (!(c[3] > r->near_) || !(lp->intensity > 0))
        return 0;
    *px = (c[0] / c[3] + 1.0) * 0.5 * r->w;
    *py = (1.0 - c[1] / c[3]) * 0.5 * r->h;
    return 1;
}

/* A lit lamp's centre in front of the near plane: its clip coordinates c
 * and its place (px, py) in pixels of this sample point; 0 otherwise. */
static int lamp_centre(const render *r, const scene_lamp *lp, double c[4], double *px, double *py)
{
    lamp_clip(r, lp, c);
    return centre_of(r, lp, c, px, py);
}

/* Lamp lp's glow disc g: centre (px, py) and radius rad in pixels, when
 * the lamp is in front of the eye, inside the frame and not hidden at its
 * own pixel (the depth buffer); else 0. */
static int glow_disc(const render *r, const scene_lamp *lp, double g[3])
{
    double c[4], px, py, rad;
    size_t p;
    float dz;
    if (!lamp_centre(r, lp, c, &px, &py))
        return 0;
    if (!(px >= 0 && py >= 0 && px < r->w && py < r->h))
        return 0;
    p = (size_t)(int32_t)py * (size_t)r->w + (size_t)(int32_t)px;
    dz = (float)((r->za * c[3] + r->zb) / c[3] * 0.5 + 0.5);
    if (!(dz < r->depth[p]))
        return 0;
    rad = 0.3 * r->sy * 0.5 * r->h / c[3]; /* a division only for the discs seen */
    rad = fmin(fmax(rad, 1.5), 48.0);
    g[0] = px;
    g[1] = py;
    g[2] = rad;
    return 1;
}

/* The pixels box[4] (x0, y0, x1, y1) glow disc g may touch. */
static void glow_box(const render *r, const double g[3], int32_t box[4])
{
    box[0] = (int32_t)floor(g[0] - g[2]);
    box[2] = (int32_t)ceil(g[0] + g[2]);
    box[1] = (int32_t)floor(g[1] - g[2]);
    box[3] = (int32_t)ceil(g[1] + g[2]);
    if (box[0] < 0) box[0] = 0;
    if (box[1] < 0) box[1] = 0;
    if (box[2] > r->w - 1) box[2] = r->w - 1;
    if (box[3] > r->h - 1) box[3] = r->h - 1;
}

/* Pixel (x, y)'s place in glow disc g: (d / rad)^2, 1 or more outside. */
static double glow_q(const double g[3], int32_t x, int32_t y)
{
    double dx = x + 0.5 - g[0], dy = y + 0.5 - g[1];
    return (dx * dx + dy * dy) / (g[2] * g[2]);
}

/* The lamps whose glow a sample point within the pixel may draw, for the
 * frame's later sample points (render_opts.cull_samples): lit, in front
 * of the near plane, their centre within two pixels of the frame at this
 * sample point (a later one moves it by less than one); in index order,
 * so that the glows add up in the same order. glow_disc gives every other
 * lamp no disc at any of them. */
void glow_candidates(render *r)
{
    uint32_t l;
    double mx = 1.0 + 8.0 / r->w, my = 1.0 + 8.0 / r->h;
    r->nglamp = 0;
    for (l = 0; l < r->s->nlamps; l++) {
        const scene_lamp *lp = &r->s->lamps[l];
        double c[4], px, py;
        lamp_clip(r, lp, c);
        /* in front and more than four pixels out of the frame (|x / w| >
         * 1 + 8 / width: far beyond any rounding): out, without the
         * divisions */
        if (c[3] > r->near_ && (fabs(c[0]) > c[3] * mx || fabs(c[1]) > c[3] * my))
            continue;
        if (!centre_of(r, lp, c, &px, &py))
            continue;
        if (px >= -2.0 && py >= -2.0 && px < r->w + 2.0 && py < r->h + 2.0)
            r->glamp[r->nglamp++] = l;
    }
    r->glamp_ok = 1;
}

/* The lamps glow_draw and glow_mark go through: the candidates when there are
 * some for this frame, else every lamp. */
static uint32_t glow_count(const render *r)
{
    return r->glamp_ok ? r->nglamp : r->s->nlamps;
}

static uint32_t glow_lamp(const render *r, uint32_t k)
{
    return r->glamp_ok ? r->glamp[k] : k;
}

/* The glow discs of the last frame drawn (its camera and depth buffer),
 * of the lamps glow_count and glow_lamp give, in their order: found once
 * for glow_draw and glow_mark, which both go through them. */
static void glow_discs(render *r)
{
    uint32_t k, n = glow_count(r);
    if (r->gseen_ok)
        return;
    r->ngseen = 0;
    for (k = 0; k < n; k++) {
        glow_seen *v = &r->gseen[r->ngseen];
        v->lamp = glow_lamp(r, k);
        r->ngseen += (uint32_t)glow_disc(r, &r->s->lamps[v->lamp], v->g);
    }
    r->gseen_ok = 1;
}

void glow_draw(render *r, const render_opts *o, render_stats *st)
{
    const scene *s = r->s;
    uint32_t q0;
    glow_discs(r);
    for (q0 = 0; q0 < r->ngseen; q0++) {
        const scene_lamp *lp = &s->lamps[r->gseen[q0].lamp];
        const double *g = r->gseen[q0].g;
        double peak;
        int32_t b[4], x, y;
        glow_box(r, g, b);
        st->glows++;
        peak = lp->intensity / 250.0;
        for (y = b[1]; y <= b[3]; y++)
            for (x = b[0]; x <= b[2]; x++) {
                size_t p = (size_t)y * (size_t)r->w + (size_t)x;
                double q = glow_q(g, x, y), v;
                float *out;
                int k;
                if (q >= 1.0 || (o->mask && !o->mask[p]))
                    continue;
                v = peak * (1.0 - q) * (1.0 - q);
                out = &r->lin[3 * p];
                for (k = 0; k < 3; k++)
                    out[k] += (float)(v * lp->color[k]);
            }
    }
}

/* Marks in mask the pixels of every glow disc seen in this frame (an
 * unmarked pixel's byte set to nw, a marked one's kept); returns how many
 * were not marked before. */
size_t glow_mark(render *r, uint8_t *mask, uint8_t nw)
{
    uint32_t k;
    size_t added = 0;
    glow_discs(r);
    for (k = 0; k < r->ngseen; k++) {
        const double *g = r->gseen[k].g;
        int32_t b[4], x, y;
        glow_box(r, g, b);
        for (y = b[1]; y <= b[3]; y++)
            for (x = b[0]; x <= b[2]; x++)
                if (glow_q(g, x, y) < 1.0) {
                    uint8_t *m = &mask[(size_t)y * (size_t)r->w + (size_t)x];
                    added += *m == 0;
                    *m = *m ? *m : nw;
                }
    }
    return added;
}
