/* Georeferenced rasters: float32 GeoTIFF through libtiff + libgeotiff, and
 * world files for PNG maps.
 *
 * libgeotiff is opened with dlopen when the first GeoTIFF is written, as
 * port/osmesa/gl_api.c opens libOSMesa: linked at start-up, it brings libproj
 * and with it libcurl, GnuTLS, Kerberos and LDAP (47 libraries), 20 ms of
 * every command's start (`polarlux --version` 28 ms, 6 ms without it). The
 * headers still give the types: each pointer is checked against its
 * function's prototype at compile time (gt_load). */
#include <ctype.h>
#include <dlfcn.h>
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

#include "cli.h"
#include "geotiff.h"
#include "posix/safe_out.h"

/* The library's functions (libtiff's are reached through libgeotiff, which
 * depends on it). */
typedef struct gt_api {
    TIFF *(*Open)(const char *, const char *);
    void (*Close)(TIFF *);
    int (*SetField)(TIFF *, uint32_t, ...);
    int (*WriteScanline)(TIFF *, void *, uint32_t, uint16_t);
    GTIF *(*New)(void *);
    int (*KeySet)(GTIF *, geokey_t, tagtype_t, int, ...);
    int (*WriteKeys)(GTIF *);
    void (*Free)(GTIF *);
} gt_api;

/* The names dlopen tries: the library's SONAME, then the development link. */
static const char *const gt_names[] = { "libgeotiff.so.5", "libgeotiff.so" };

/* dlsym's object pointer copied into a function pointer (POSIX: the same
 * bytes; C99 has no cast between them). */
static int gt_find(void *lib, const char *name, void *fn, size_t size, char *err, size_t errlen)
{
    void *p = dlsym(lib, name);
    if (!p) {
        snprintf(err, errlen, "libgeotiff has no %s", name);
        return -1;
    }
    memcpy(fn, &p, size);
    return 0;
}

/* sizeof does not evaluate its operand: the assignment is type-checked
 * against the header's prototype and no reference to the symbol is made. */
#define GT_FIND(field, sym)                                                          \
    ((void)sizeof(api->field = sym), gt_find(lib, #sym, &api->field, sizeof api->field, err, errlen))

static int gt_load(gt_api *api, char *err, size_t errlen)
{
    void *lib = NULL;
    size_t k;
    for (k = 0; k < sizeof gt_names / sizeof gt_names[0] && !lib; k++)
        lib = dlopen(gt_names[k], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        snprintf(err, errlen, "cannot load %s for GeoTIFF output (%s); install libgeotiff5", gt_names[0], dlerror());
        return -1;
    }
    if (GT_FIND(Open, XTIFFOpen) || GT_FIND(Close, XTIFFClose) || GT_FIND(SetField, TIFFSetField) ||
        GT_FIND(WriteScanline, TIFFWriteScanline) || GT_FIND(New, GTIFNew) || GT_FIND(KeySet, GTIFKeySet) ||
        GT_FIND(WriteKeys, GTIFWriteKeys) || GT_FIND(Free, GTIFFree))
        return -1;
    return 0;
}

#define M_PER_DEG_LON 111320.0
#define M_PER_DEG_LAT 110540.0

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
        f->epsg = f->name ? cli_crs_epsg(f->name) : 0; /* a geographic crs of its own (ETRS89, ...), else WGS 84 */
    } else if (f->name && (f->epsg = cli_crs_epsg(f->name)) != 0) {
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

static void set_keys(const gt_api *gt, GTIF *g, const raster_frame *f)
{
    gt->KeySet(g, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
    if (f->kind == RASTER_LONLAT) {
        gt->KeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeGeographic);
        gt->KeySet(g, GeographicTypeGeoKey, TYPE_SHORT, 1, f->epsg ? f->epsg : 4326);
        gt->KeySet(g, GTCitationGeoKey, TYPE_ASCII, 0, f->epsg && f->name ? f->name : "WGS 84");
    } else if (f->kind == RASTER_EPSG) {
        gt->KeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
        gt->KeySet(g, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, f->epsg);
        gt->KeySet(g, GTCitationGeoKey, TYPE_ASCII, 0, f->name);
    } else {
        gt->KeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
        gt->KeySet(g, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, KvUserDefined);
        gt->KeySet(g, ProjLinearUnitsGeoKey, TYPE_SHORT, 1, Linear_Meter);
        gt->KeySet(g, GTCitationGeoKey, TYPE_ASCII, 0,
                   f->name ? f->name : "polarlux local metres (the scene's own x, y)");
    }
}

static int write_tags(const gt_api *gt, TIFF *t, int w, int h, int nb, const raster_frame *f, const char *description)
{
    double scale[3], tie[6];
    scale[0] = f->sx;
    scale[1] = f->sy;
    scale[2] = 0.0;
    tie[0] = tie[1] = tie[2] = 0.0;
    tie[3] = f->x0;
    tie[4] = f->y0;
    tie[5] = 0.0;
    return !(gt->SetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)w) && gt->SetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)h) &&
             gt->SetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)nb) &&
             gt->SetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)32) &&
             gt->SetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)SAMPLEFORMAT_IEEEFP) &&
             gt->SetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG) &&
             gt->SetField(t, TIFFTAG_PHOTOMETRIC, (uint16_t)PHOTOMETRIC_MINISBLACK) &&
             gt->SetField(t, TIFFTAG_COMPRESSION, (uint16_t)COMPRESSION_ADOBE_DEFLATE) &&
             gt->SetField(t, TIFFTAG_PREDICTOR, (uint16_t)PREDICTOR_FLOATINGPOINT) &&
             gt->SetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)1) &&
             gt->SetField(t, TIFFTAG_IMAGEDESCRIPTION, description ? description : "") &&
             gt->SetField(t, TIFFTAG_SOFTWARE, "polarlux " PLX_VERSION_STRING) &&
             gt->SetField(t, TIFFTAG_GEOPIXELSCALE, 3, scale) && gt->SetField(t, TIFFTAG_GEOTIEPOINTS, 6, tie));
}

static int write_file(const gt_api *gt, const char *path, const float *v, int w, int h, int nb,
                      const raster_frame *f, const char *description, char *err, size_t errlen)
{
    TIFF *t = gt->Open(path, "w");
    GTIF *g;
    int y, rc = 0;
    if (!t) {
        snprintf(err, errlen, "%s: cannot create the GeoTIFF", path);
        return -1;
    }
    if (write_tags(gt, t, w, h, nb, f, description) != 0) {
        snprintf(err, errlen, "%s: libtiff refused the GeoTIFF tags", path);
        gt->Close(t);
        return -1;
    }
    g = gt->New(t);
    if (!g) {
        snprintf(err, errlen, "%s: libgeotiff could not start the keys", path);
        gt->Close(t);
        return -1;
    }
    set_keys(gt, g, f);
    gt->WriteKeys(g);
    gt->Free(g);
    for (y = 0; y < h && rc == 0; y++)
        if (gt->WriteScanline(t, (void *)(v + (size_t)y * w * nb), (uint32_t)y, 0) < 0) {
            snprintf(err, errlen, "%s: writing row %d failed", path, y);
            rc = -1;
        }
    gt->Close(t);
    return rc;
}

int geotiff_write(const char *path, const float *v, int w, int h, int nb, const raster_frame *f,
                  const char *description, char *err, size_t errlen)
{
    size_t n = strlen(path);
    char *tmp;
    gt_api gt;
    int rc;
    if (gt_load(&gt, err, errlen) != 0)
        return -1;
    tmp = malloc(n + 16);
    if (!tmp) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    snprintf(tmp, n + 16, "%s.tmp%d", path, (int)(n % 97));
    rc = write_file(&gt, tmp, v, w, h, nb, f, description, err, errlen);
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
