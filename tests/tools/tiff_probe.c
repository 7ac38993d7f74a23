/* tiff_probe FILE [COL,ROW]...: reads a GeoTIFF back with libtiff and
 * libgeotiff (independently of the writer in src/cli/geotiff.c) and prints
 * its size, sample format, georeferencing (pixel scale, tie point, the
 * model, raster type, geographic / projected CRS and linear units keys) and
 * the values of the pixels asked for, one line each:
 *   size W H bands B bits N format F
 *   scale SX SY
 *   tie I J X Y
 *   keys model M raster R geographic G projected P units U
 *   pixel COL ROW V1 [V2 ...]
 * Exit 1 when the file cannot be read. Used by tests/cli/gis.sh. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <tiffio.h>
#include <geotiff.h>
#include <geotiffio.h>
#include <xtiffio.h>

static int key_short(GTIF *g, geokey_t k)
{
    unsigned short v = 0;
    return GTIFKeyGet(g, k, &v, 0, 1) == 1 ? (int)v : -1;
}

static int print_pixel(TIFF *t, const char *arg, uint32_t w, uint32_t h, uint16_t nb, float *row)
{
    int col, r, b;
    if (sscanf(arg, "%d,%d", &col, &r) != 2 || col < 0 || r < 0 || (uint32_t)col >= w || (uint32_t)r >= h) {
        fprintf(stderr, "tiff_probe: bad pixel '%s'\n", arg);
        return -1;
    }
    if (TIFFReadScanline(t, row, (uint32_t)r, 0) < 0) {
        fprintf(stderr, "tiff_probe: cannot read row %d\n", r);
        return -1;
    }
    printf("pixel %d %d", col, r);
    for (b = 0; b < nb; b++)
        printf(" %.9g", row[(size_t)col * nb + b]);
    printf("\n");
    return 0;
}

int main(int argc, char **argv)
{
    TIFF *t;
    GTIF *g;
    uint32_t w = 0, h = 0;
    uint16_t nb = 0, bits = 0, fmt = 0, n = 0;
    double *scale = NULL, *tie = NULL;
    const char *desc = NULL;
    float *row;
    int i, rc = 0;
    if (argc < 2 || !(t = XTIFFOpen(argv[1], "r"))) {
        fprintf(stderr, "usage: tiff_probe FILE [COL,ROW]... (cannot open)\n");
        return 1;
    }
    TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &w);
    TIFFGetField(t, TIFFTAG_IMAGELENGTH, &h);
    TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &nb);
    TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &fmt);
    printf("size %u %u bands %u bits %u format %s\n", w, h, nb, bits,
           fmt == SAMPLEFORMAT_IEEEFP ? "float" : "other");
    if (TIFFGetField(t, TIFFTAG_GEOPIXELSCALE, &n, &scale) && n >= 2)
        printf("scale %.17g %.17g\n", scale[0], scale[1]);
    if (TIFFGetField(t, TIFFTAG_GEOTIEPOINTS, &n, &tie) && n >= 6)
        printf("tie %.17g %.17g %.17g %.17g\n", tie[0], tie[1], tie[3], tie[4]);
    if (TIFFGetField(t, TIFFTAG_IMAGEDESCRIPTION, &desc) && desc)
        printf("description %s\n", desc);
    g = GTIFNew(t);
    if (g) {
        printf("keys model %d raster %d geographic %d projected %d units %d\n", key_short(g, GTModelTypeGeoKey),
               key_short(g, GTRasterTypeGeoKey), key_short(g, GeographicTypeGeoKey),
               key_short(g, ProjectedCSTypeGeoKey), key_short(g, ProjLinearUnitsGeoKey));
        GTIFFree(g);
    }
    row = bits == 32 && fmt == SAMPLEFORMAT_IEEEFP ? malloc(TIFFScanlineSize(t)) : NULL;
    for (i = 2; i < argc && row; i++)
        if (print_pixel(t, argv[i], w, h, nb, row) != 0)
            rc = 1;
    free(row);
    XTIFFClose(t);
    return rc;
}
