/* Georeferenced rasters of the command: float32 GeoTIFF (libtiff +
 * libgeotiff) and world files (.pgw) beside PNG maps. */
#ifndef PLX_CLI_GEOTIFF_H
#define PLX_CLI_GEOTIFF_H

#include <stddef.h>
#include "polarlux.h"

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
/* Writes the world file of a PNG (path with its extension replaced by
 * .pgw): the pixel size and the centre of the upper-left pixel, through
 * a safe output (port/posix/safe_out.h). 0; 1 when the PNG goes to "-",
 * a device or a FIFO (no folder beside it: nothing written); -1 with err. */
/* Whether png_path names a regular file or a name not yet taken (a
 * symlink followed): only then is there a folder to put a world file in
 * beside it; "-", a device or a FIFO get none. */
int world_file_wanted(const char *png_path);
int world_file_write(const char *png_path, const raster_frame *f, char *err, size_t errlen);
/* 1 when path ends in .tif or .tiff (any case). */
int is_tiff_path(const char *path);

#endif
