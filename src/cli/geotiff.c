/* Georeferenced rasters: float32 GeoTIFF through libtiff + libgeotiff, and
 * world files for PNG maps. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <tiffio.h>
#include <geotiff.h>
#include <geotiffio.h>
#include <geo_normalize.h>
#include <xtiffio.h>
#include <sys/stat.h>

#include "geotiff.h"
#include "posix/safe_out.h"

#define M_PER_DEG_LON 111320.0
#define M_PER_DEG_LAT 110540.0

/* The EPSG code at the end of a CRS name ("EPSG:2154",
 * "urn:ogc:def:crs:EPSG::2154"), or 0. */
static int epsg_code(const char *name)
{
    const char *p = strstr(name, "EPSG");
    const char *d;
    long v;
    if (!p)
        return 0;
    d = name + strlen(name);
    while (d > p && isdigit((unsigned char)d[-1]))
        d--;
    if (!*d || d[-1] != ':')
        return 0;
    v = strtol(d, NULL, 10);
    return v > 0 && v < 1000000 ? (int)v : 0;
}

void raster_frame_of(plx_engine *e, const double box[4], double res, raster_frame *f)
{
    plx_scene_info si;
    plx_scene_info_get(e, &si);
    memset(f, 0, sizeof *f);
    f->name = plx_scene_crs(e);
    f->x0 = box[0];
    f->y0 = box[3];
    f->sx = f->sy = res;
    if (si.lonlat) {
        double cl = cos(si.lat0 * 3.14159265358979323846 / 180.0);
        f->kind = RASTER_LONLAT;
        f->x0 = si.lon0 + box[0] / (M_PER_DEG_LON * cl);
        f->y0 = si.lat0 + box[3] / M_PER_DEG_LAT;
        f->sx = res / (M_PER_DEG_LON * cl);
        f->sy = res / M_PER_DEG_LAT;
    } else if (f->name && (f->epsg = epsg_code(f->name)) != 0) {
        f->kind = RASTER_EPSG;
    }
}

int is_tiff_path(const char *path)
{
    size_t n = strlen(path);
    const char *a = n >= 4 ? path + n - 4 : "", *b = n >= 5 ? path + n - 5 : "";
    return (tolower((unsigned char)a[0]) == '.' && tolower((unsigned char)a[1]) == 't' &&
            tolower((unsigned char)a[2]) == 'i' && tolower((unsigned char)a[3]) == 'f') ||
           (b[0] == '.' && tolower((unsigned char)b[1]) == 't' && tolower((unsigned char)b[2]) == 'i' &&
            tolower((unsigned char)b[3]) == 'f' && tolower((unsigned char)b[4]) == 'f');
}

static void set_keys(GTIF *g, const raster_frame *f)
{
    GTIFKeySet(g, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
    if (f->kind == RASTER_LONLAT) {
        GTIFKeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeGeographic);
        GTIFKeySet(g, GeographicTypeGeoKey, TYPE_SHORT, 1, 4326);
        GTIFKeySet(g, GTCitationGeoKey, TYPE_ASCII, 0, "WGS 84");
    } else if (f->kind == RASTER_EPSG) {
        GTIFKeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
        GTIFKeySet(g, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, f->epsg);
        GTIFKeySet(g, GTCitationGeoKey, TYPE_ASCII, 0, f->name);
    } else {
        GTIFKeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
        GTIFKeySet(g, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, KvUserDefined);
        GTIFKeySet(g, ProjLinearUnitsGeoKey, TYPE_SHORT, 1, Linear_Meter);
        GTIFKeySet(g, GTCitationGeoKey, TYPE_ASCII, 0,
                   f->name ? f->name : "polarlux local metres (the scene's own x, y)");
    }
}

static int write_tags(TIFF *t, int w, int h, int nb, const raster_frame *f, const char *description)
{
    double scale[3], tie[6];
    scale[0] = f->sx;
    scale[1] = f->sy;
    scale[2] = 0.0;
    tie[0] = tie[1] = tie[2] = 0.0;
    tie[3] = f->x0;
    tie[4] = f->y0;
    tie[5] = 0.0;
    return !(TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)w) && TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)h) &&
             TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)nb) &&
             TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)32) &&
             TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)SAMPLEFORMAT_IEEEFP) &&
             TIFFSetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG) &&
             TIFFSetField(t, TIFFTAG_PHOTOMETRIC, (uint16_t)PHOTOMETRIC_MINISBLACK) &&
             TIFFSetField(t, TIFFTAG_COMPRESSION, (uint16_t)COMPRESSION_ADOBE_DEFLATE) &&
             TIFFSetField(t, TIFFTAG_PREDICTOR, (uint16_t)PREDICTOR_FLOATINGPOINT) &&
             TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)1) &&
             TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, description ? description : "") &&
             TIFFSetField(t, TIFFTAG_SOFTWARE, "polarlux " PLX_VERSION_STRING) &&
             TIFFSetField(t, TIFFTAG_GEOPIXELSCALE, 3, scale) && TIFFSetField(t, TIFFTAG_GEOTIEPOINTS, 6, tie));
}

static int write_file(const char *path, const float *v, int w, int h, int nb, const raster_frame *f,
                      const char *description, char *err, size_t errlen)
{
    TIFF *t = XTIFFOpen(path, "w");
    GTIF *g;
    int y, rc = 0;
    if (!t) {
        snprintf(err, errlen, "%s: cannot create the GeoTIFF", path);
        return -1;
    }
    if (write_tags(t, w, h, nb, f, description) != 0) {
        snprintf(err, errlen, "%s: libtiff refused the GeoTIFF tags", path);
        XTIFFClose(t);
        return -1;
    }
    g = GTIFNew(t);
    if (!g) {
        snprintf(err, errlen, "%s: libgeotiff could not start the keys", path);
        XTIFFClose(t);
        return -1;
    }
    set_keys(g, f);
    GTIFWriteKeys(g);
    GTIFFree(g);
    for (y = 0; y < h && rc == 0; y++)
        if (TIFFWriteScanline(t, (void *)(v + (size_t)y * w * nb), (uint32_t)y, 0) < 0) {
            snprintf(err, errlen, "%s: writing row %d failed", path, y);
            rc = -1;
        }
    XTIFFClose(t);
    return rc;
}

int geotiff_write(const char *path, const float *v, int w, int h, int nb, const raster_frame *f,
                  const char *description, char *err, size_t errlen)
{
    size_t n = strlen(path);
    char *tmp = malloc(n + 16);
    int rc;
    if (!tmp) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    snprintf(tmp, n + 16, "%s.tmp%d", path, (int)(n % 97));
    rc = write_file(tmp, v, w, h, nb, f, description, err, errlen);
    if (rc == 0 && rename(tmp, path) != 0) {
        snprintf(err, errlen, "%s: cannot rename the written file into place: %s", path, strerror(errno));
        rc = -1;
    }
    if (rc != 0)
        remove(tmp);
    free(tmp);
    return rc;
}

int world_file_wanted(const char *png_path)
{
    struct stat st;
    if (strcmp(png_path, "-") == 0)
        return 0;
    if (stat(png_path, &st) != 0)
        return 1;
    return S_ISREG(st.st_mode);
}

char *world_file_path(const char *png_path)
{
    size_t n = strlen(png_path);
    const char *dot = strrchr(png_path, '.'), *slash = strrchr(png_path, '/');
    char *path = malloc(n + 8);
    if (!path)
        return NULL;
    if (dot && (!slash || dot > slash))
        n = (size_t)(dot - png_path);
    memcpy(path, png_path, n);
    strcpy(path + n, ".pgw");
    return path;
}

int world_file_encode(safe_out *out, const raster_frame *f)
{
    char text[256];
    int len = snprintf(text, sizeof text, "%.17g\n0\n0\n%.17g\n%.17g\n%.17g\n", f->sx, -f->sy,
                       f->x0 + 0.5 * f->sx, f->y0 - 0.5 * f->sy);
    return safe_out_write(out, text, (size_t)len); /* a failure is sticky: the commit reports it */
}
