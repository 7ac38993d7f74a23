/* tiles: Web Mercator XYZ tile geometry and ground illuminance tiles. */
#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "tiles.h"

#define PI 3.14159265358979323846

void tile_pixel_lonlat(int z, double px, double py, double *lon, double *lat)
{
    double world = TILE_SIZE * ldexp(1.0, z);
    *lon = px / world * 360.0 - 180.0;
    *lat = atan(sinh(PI * (1.0 - 2.0 * py / world))) * 180.0 / PI;
}

void tile_of_lonlat(int z, double lon, double lat, long *tx, long *ty)
{
    double n = ldexp(1.0, z), phi = lat * PI / 180.0;
    double fx = (lon + 180.0) / 360.0 * n, fy = (1.0 - log(tan(phi) + 1.0 / cos(phi)) / PI) / 2.0 * n;
    *tx = (long)floor(fmin(fmax(fx, 0.0), n - 1));
    *ty = (long)floor(fmin(fmax(fy, 0.0), n - 1));
}

void tile_local(const plx_scene_info *si, double lon, double lat, double *x, double *y)
{
    *x = (lon - si->lon0) * 111320.0 * cos(si->lat0 * PI / 180.0);
    *y = (lat - si->lat0) * 110540.0;
}

void tile_range(plx_engine *e, int z, long *x0, long *y0, long *x1, long *y1)
{
    plx_scene_info si;
    double c;
    plx_scene_info_get(e, &si);
    c = 111320.0 * cos(si.lat0 * PI / 180.0);
    tile_of_lonlat(z, si.lon0 + si.bounds[0] / c, si.lat0 + si.bounds[3] / 110540.0, x0, y0);
    tile_of_lonlat(z, si.lon0 + si.bounds[2] / c, si.lat0 + si.bounds[1] / 110540.0, x1, y1);
}

int tile_work_init(tile_work *w)
{
    size_t n = TILE_SIZE * TILE_SIZE;
    w->P = malloc(sizeof *w->P * 3 * n);
    w->N = malloc(sizeof *w->N * 3 * n);
    w->E = malloc(sizeof *w->E * n);
    memset(&w->q, 0, sizeof w->q);
    w->q.quantity = PLX_METER_H;
    w->q.height = 1.5;
    w->q.facing_min = 1;
    if (w->P && w->N && w->E)
        return 0;
    tile_work_free(w);
    return -1;
}

void tile_work_free(tile_work *w)
{
    free(w->P);
    free(w->N);
    free(w->E);
    memset(w, 0, sizeof *w);
}

long tile_render(plx_engine *e, tile_work *w, int z, long x, long y, double top, uint8_t *rgba)
{
    plx_scene_info si;
    size_t n = TILE_SIZE * TILE_SIZE, k;
    long lit = 0;
    plx_status st;
    plx_scene_info_get(e, &si);
    for (k = 0; k < n; k++) {
        double lon, lat;
        tile_pixel_lonlat(z, (double)x * TILE_SIZE + (double)(k % TILE_SIZE) + 0.5,
                          (double)y * TILE_SIZE + (double)(k / TILE_SIZE) + 0.5, &lon, &lat);
        tile_local(&si, lon, lat, &w->P[3 * k], &w->P[3 * k + 1]);
        w->P[3 * k + 2] = 0.0;
        w->N[3 * k] = w->N[3 * k + 1] = 0.0;
        w->N[3 * k + 2] = 1.0;
    }
    if (w->q.quantity == PLX_METER_H)
        st = plx_illuminance(e, n, w->P, w->N, w->E, NULL, NULL);
    else
        for (k = 0, st = PLX_OK; k < n && (st == PLX_OK || st == PLX_E_RANGE); k++)
            st = heatmap_value(e, &w->q, w->P[3 * k], w->P[3 * k + 1], &w->E[k]);
    if (st != PLX_OK && st != PLX_E_RANGE) /* RANGE: pixels under buildings */
        return -1;
    for (k = 0; k < n; k++) {
        uint8_t *px = rgba + 4 * k;
        if (w->E[k] == w->E[k] && heatmap_colour(w->E[k], top, px)) {
            px[3] = 255;
            lit++;
        } else {
            memset(px, 0, 4);
        }
    }
    return lit;
}

double tile_default_top(plx_engine *e, const heat_quantity *q)
{
    plx_scene_info si;
    double res, top = 0, P[3 * 1024], N[3 * 1024], E[1024];
    size_t w, h, k, n, i;
    plx_scene_info_get(e, &si);
    res = fmax(si.bounds[2] - si.bounds[0], si.bounds[3] - si.bounds[1]) / 1200.0;
    w = (size_t)ceil((si.bounds[2] - si.bounds[0]) / res);
    h = (size_t)ceil((si.bounds[3] - si.bounds[1]) / res);
    for (k = 0; k < w * h; k += n) {
        n = w * h - k < 1024 ? w * h - k : 1024;
        for (i = 0; i < n; i++) {
            P[3 * i] = si.bounds[0] + ((k + i) % w + 0.5) * res;
            P[3 * i + 1] = si.bounds[3] - ((k + i) / w + 0.5) * res;
            P[3 * i + 2] = 0;
            N[3 * i] = N[3 * i + 1] = 0;
            N[3 * i + 2] = 1;
        }
        if (q->quantity == PLX_METER_H)
            plx_illuminance(e, n, P, N, E, NULL, NULL);
        else
            for (i = 0; i < n; i++)
                heatmap_value(e, q, P[3 * i], P[3 * i + 1], &E[i]);
        for (i = 0; i < n; i++)
            if (E[i] == E[i] && E[i] > top)
                top = E[i];
    }
    return pow(10.0, ceil(log10(fmax(top, 1.0))));
}

int tile_png(const uint8_t *rgba, uint8_t **png, size_t *len)
{
    png_image im;
    png_alloc_size_t size = 0;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = TILE_SIZE;
    im.height = TILE_SIZE;
    im.format = PNG_FORMAT_RGBA;
    *png = NULL;
    if (!png_image_write_to_memory(&im, NULL, &size, 0, rgba, 0, NULL))
        return -1;
    *png = malloc(size);
    if (!*png)
        return -1;
    if (!png_image_write_to_memory(&im, *png, &size, 0, rgba, 0, NULL)) {
        free(*png);
        *png = NULL;
        return -1;
    }
    *len = size;
    return 0;
}

int tile_png_decode(const uint8_t *png, size_t len, uint8_t *rgba)
{
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&im, png, len))
        return -1;
    if (im.width != TILE_SIZE || im.height != TILE_SIZE) {
        png_image_free(&im);
        return -1;
    }
    im.format = PNG_FORMAT_RGBA;
    if (!png_image_finish_read(&im, NULL, rgba, 0, NULL)) {
        png_image_free(&im);
        return -1;
    }
    return 0;
}
