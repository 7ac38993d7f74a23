/* Georeferenced rasters of the command: float32 GeoTIFF (libtiff +
 * libgeotiff) and world files (.pgw) beside PNG maps. */
#ifndef PLX_CLI_GEOTIFF_H
#define PLX_CLI_GEOTIFF_H

#include <stddef.h>
#include "polarlux.h"
#include "posix/safe_out.h"

/* Where a north-up raster lies: the upper-left corner of its upper-left
 * pixel (x0, y0) and the pixel size (sx, sy > 0) in the CRS's units. */
typedef struct raster_frame {
    int kind;          /* RASTER_LOCAL, RASTER_LONLAT, RASTER_EPSG */
    int epsg;          /* the projected CRS's EPSG code (RASTER_EPSG) */
    const char *name;  /* the scene's CRS name, or NULL */
    double x0, y0, sx, sy;
} raster_frame;

enum { RASTER_LOCAL = 0, RASTER_LONLAT = 1, RASTER_EPSG = 2 };

/* The frame of a map of the local box [x0, x1] x [y0, y1] (metres) at res
 * metres per pixel in the scene's own coordinates: WGS84 lon/lat for a
 * lon/lat scene (the projection is linear, so the grid is regular in
 * degrees), the EPSG code of the scene's crs when it names one, else
 * local metres. */
void raster_frame_of(plx_engine *e, const double box[4], double res, raster_frame *f);
/* Writes w x h pixels of nb float32 bands (pixel-interleaved, top row
 * first) to path (through a temporary file renamed into place); band_names
 * (may be NULL) go to the image description. 0, or -1 with err. */
int geotiff_write(const char *path, const float *v, int w, int h, int nb, const raster_frame *f,
                  const char *description, char *err, size_t errlen);
/* Whether png_path names a regular file or a name not yet taken (a
 * symlink followed): only then is there a folder to put a world file in
 * beside it; "-", a device or a FIFO get none. */
int world_file_wanted(const char *png_path);
/* The world file's name for a PNG (its extension replaced by .pgw;
 * malloc'd, NULL when out of memory). */
char *world_file_path(const char *png_path);
/* The world file (the pixel size and the centre of the upper-left pixel)
 * written to out; 0, or -1 (sticky in out: safe_out_commit reports it). */
int world_file_encode(safe_out *out, const raster_frame *f);
/* 1 when path ends in .tif or .tiff (any case). */
int is_tiff_path(const char *path);

#endif
