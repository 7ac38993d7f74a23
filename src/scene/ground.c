/* ground: the ground's albedo, constant or from a day image (issue #6;
 * README "Scene format", munoz2013 §3.1 for the orthophoto).
 *
 * The scene names the image (properties.ground_image, a path) and where it
 * lies (properties.ground_image_bounds, else the Bounds box); the core reads
 * no files, so the caller decodes the PNG and hands the pixels over with
 * plx_set_ground_image. They are kept as the caller's 8-bit sRGB bytes
 * (3 bytes a pixel, not 12 or 24 of floats) plus a 256-entry table.
 *
 * From pixel to albedo. A photo's brightness depends on exposure, not on
 * the ground's reflectance, so only its relative colours are kept: each
 * byte is decoded from sRGB to linear (IEC 61966-2-1) and scaled so that
 * the image's mean linear luminance Y = 0.2126 R + 0.7152 G + 0.0722 B
 * equals the scene's ground albedo (properties.ground_albedo, 0.15 by
 * default): albedo_c = lin(v_c) * ground_albedo / mean Y, clamped to
 * [0, 0.95] (a clamped pixel lowers the mean a little; with the default
 * 0.15 that needs a pixel 6 times brighter than the mean). The scale is the
 * same for all three channels, so the table lut[v] holds the final albedo
 * of byte value v. A black image (mean Y = 0) cannot be scaled and is
 * refused.
 *
 * Lookup (scene_ground_albedo, O(1)): the nearest pixel, i.e. the pixel
 * whose cell contains (x, y). The image spans [x0, x1] x [y0, y1] exactly,
 * its top row at the north edge y1; pixel (i, j) covers
 * x0 + [i, i+1) (x1-x0)/w and y1 - [j, j+1) (y1-y0)/h. A point on a line
 * between two pixels takes the one east or south of it; the east and south
 * edges of the box belong to the last column and row. Outside the box (and
 * for NaN) the constant ground_albedo applies.
 *
 * Who reads it: the photon tracer (Russian roulette at a ground hit uses the
 * luminance of the albedo there, photon.c) and the renderer (ground pixels
 * are albedo_c / pi * E_c per channel, shade_tiles.c). Nothing else reads the
 * ground's albedo; the photon buffers hold what was traced with the image
 * of the time, so setting an image drops them (plx_set_ground_image in
 * src/api/groundapi.c).
 */
#include <string.h>
#include <math.h>

#include "scene/ground.h"

#define GROUND_MAX_ALBEDO 0.95
#define LUM_R 0.2126
#define LUM_G 0.7152
#define LUM_B 0.0722

/* sRGB transfer curve inverted, for byte value v. */
static double srgb_to_linear(int v)
{
    double c = v / 255.0;
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

/* The pixel under (x, y), or NULL outside the image. */
static const uint8_t *ground_pixel(const scene_ground_image *g, double x, double y)
{
    double u, v;
    uint32_t i, j;
    if (!(x >= g->box[0] && x <= g->box[2] && y >= g->box[1] && y <= g->box[3]))
        return NULL;
    u = (x - g->box[0]) * g->fx;
    v = (g->box[3] - y) * g->fy;
    i = u < (double)g->w ? (uint32_t)u : g->w - 1;
    j = v < (double)g->h ? (uint32_t)v : g->h - 1;
    return g->rgb + 3 * ((size_t)j * g->w + i);
}

void scene_ground_albedo(const scene *s, double x, double y, double rgb[3])
{
    const uint8_t *px = s->gimg ? ground_pixel(s->gimg, x, y) : NULL;
    if (!px) {
        rgb[0] = rgb[1] = rgb[2] = s->ground_albedo;
        return;
    }
    rgb[0] = s->gimg->lut[px[0]];
    rgb[1] = s->gimg->lut[px[1]];
    rgb[2] = s->gimg->lut[px[2]];
}

double scene_ground_albedo_y(const scene *s, double x, double y)
{
    const uint8_t *px = s->gimg ? ground_pixel(s->gimg, x, y) : NULL;
    const double *lut;
    if (!px)
        return s->ground_albedo;
    lut = s->gimg->lut;
    return LUM_R * lut[px[0]] + LUM_G * lut[px[1]] + LUM_B * lut[px[2]];
}

/* Counts of each byte value per channel (histograms make the means exact
 * sums of 256 terms, whatever the image size). */
static void histograms(const uint8_t *rgb, size_t npx, uint32_t hist[3][256])
{
    size_t i;
    memset(hist, 0, 3 * 256 * sizeof hist[0][0]);
    for (i = 0; i < npx; i++) {
        hist[0][rgb[3 * i]]++;
        hist[1][rgb[3 * i + 1]]++;
        hist[2][rgb[3 * i + 2]]++;
    }
}

plx_status ground_image_set(arena *a, scene *s, uint32_t w, uint32_t h, const uint8_t *rgb,
                            const double box[4])
{
    static const double lum[3] = { LUM_R, LUM_G, LUM_B };
    uint32_t hist[3][256];
    double lin[256], lut[256], sum_y = 0.0, mean_y, mean[3] = { 0, 0, 0 };
    size_t npx, need;
    scene_ground_image *g = s->gimg;
    int v, c;
    if (w == 0 || h == 0 || w > GROUND_MAX_DIM || h > GROUND_MAX_DIM || !rgb)
        return PLX_E_INVALID;
    npx = (size_t)w * h;
    need = arena_mul(npx, 3);
    histograms(rgb, npx, hist);
    for (v = 0; v < 256; v++) {
        lin[v] = srgb_to_linear(v);
        for (c = 0; c < 3; c++)
            sum_y += lum[c] * lin[v] * (double)hist[c][v];
    }
    mean_y = sum_y / (double)npx;
    if (!(mean_y > 0.0))
        return PLX_E_INVALID;
    for (v = 0; v < 256; v++) {
        double al = lin[v] * s->ground_albedo / mean_y;
        lut[v] = al < GROUND_MAX_ALBEDO ? al : GROUND_MAX_ALBEDO;
        for (c = 0; c < 3; c++)
            mean[c] += lut[v] * (double)hist[c][v];
    }
    if (!g || g->cap < need) {
        /* nothing changes until both allocations succeed */
        arena_mark m = arena_get_mark(a);
        scene_ground_image *ng = arena_calloc(a, PLX_PART_SCENE, 1, sizeof *ng, 16);
        uint8_t *px = ng ? arena_alloc(a, PLX_PART_SCENE, need, 16) : NULL;
        if (!px) {
            arena_release(a, &m);
            return PLX_E_NOMEM;
        }
        ng->rgb = px;
        ng->cap = need;
        g = ng;
    }
    memcpy(g->rgb, rgb, need);
    g->w = w;
    g->h = h;
    memcpy(g->box, box, sizeof g->box);
    g->fx = w / (box[2] - box[0]);
    g->fy = h / (box[3] - box[1]);
    g->mean_y = mean_y;
    for (c = 0; c < 3; c++)
        g->mean_albedo[c] = mean[c] / (double)npx;
    memcpy(g->lut, lut, sizeof lut);
    s->gimg = g;
    return PLX_OK;
}

double ground_luminance(const double rgb[3])
{
    return LUM_R * rgb[0] + LUM_G * rgb[1] + LUM_B * rgb[2];
}
