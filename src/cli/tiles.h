/* Web-map raster tiles (Web Mercator, XYZ, 256 x 256) of ground
 * illuminance in the heat map's colours, written to a folder z/x/y.png or
 * an MBTiles file (mbtiles.c). */
#ifndef PLX_CLI_TILES_H
#define PLX_CLI_TILES_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "cli.h"

#define TILE_SIZE 256

/* Longitude, latitude (degrees) of a point of the Web Mercator square at
 * zoom z, in pixels from its top-left corner (fractions allowed). */
void tile_pixel_lonlat(int z, double px, double py, double *lon, double *lat);
/* The tile holding lon, lat at zoom z. */
void tile_of_lonlat(int z, double lon, double lat, long *tx, long *ty);
/* The tiles covering the scene's Bounds at zoom z (inclusive ranges).
 * The scene must be lon/lat. */
void tile_range(plx_engine *e, int z, long *x0, long *y0, long *x1, long *y1);
/* The scene's local metres of a lon/lat point (SPEC §1 projection). */
void tile_local(const plx_scene_info *si, double lon, double lat, double *x, double *y);

/* Scratch for rendering one tile (points, normals, lux) and what the tiles
 * map (tile_work_init: E_h on the ground; for sc, E_sc at 1.5 m, the least
 * over every facing direction, as 'polarlux heatmap --quantity sc --facing
 * min'). */
typedef struct tile_work {
    double *P, *N, *E;
    heat_quantity q;
} tile_work;
int tile_work_init(tile_work *w);
void tile_work_free(tile_work *w);

/* Renders tile (z, x, y) as RGBA: each pixel's centre is a ground point
 * whose w->q (heatmap_value: E_h, or E_sc above it) takes the heat map's
 * colour on a scale topped at 'top',
 * opaque; pixels with no light (at or below the scale's bottom, inside a
 * footprint) are transparent (0, 0, 0, 0). Returns the number of lit
 * pixels, or -1 (the engine's error) on failure. */
long tile_render(plx_engine *e, tile_work *w, int z, long x, long y, double top, uint8_t *rgba);

/* The heat map's default top of scale: the next power of ten above the
 * brightest pixel of 'polarlux heatmap' (of quantity q) with its default
 * resolution. */
double tile_default_top(plx_engine *e, const heat_quantity *q);

/* PNG (RGBA, 8-bit) of a tile in memory: *png malloc'd; 0 or -1. */
int tile_png(const uint8_t *rgba, uint8_t **png, size_t *len);
/* Decodes an RGBA PNG from memory into rgba (TILE_SIZE^2 * 4); 0 or -1. */
int tile_png_decode(const uint8_t *png, size_t len, uint8_t *rgba);

/* MBTiles output (mbtiles.c, libsqlite3). */
typedef struct mbtiles mbtiles;
/* Creates path (through a temporary file renamed into place by
 * mbtiles_close) with the spec's metadata (the description names 'what' is
 * mapped; attribution, when not NULL or empty, the data's credit line);
 * NULL and err on failure. */
mbtiles *mbtiles_open(const char *path, const char *name, const double bounds[4], int z0, int z1,
                      const char *what, double top, const char *attribution, char *err, size_t errlen);
/* Adds tile (z, x, y) in XYZ numbering (stored as TMS rows). 0 or -1. */
int mbtiles_put(mbtiles *m, int z, long x, long y, const uint8_t *png, size_t len, char *err, size_t errlen);
/* commit != 0: commits and renames into place; else discards. 0 or -1. */
int mbtiles_close(mbtiles *m, int commit, char *err, size_t errlen);

#endif
