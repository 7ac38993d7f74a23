/* Lamp layers (--lamps FILE): lamps from another GeoJSON or CSV file added
 * to a loaded scene (README "Your own data"). */
#ifndef PLX_CLI_LAMP_LAYER_H
#define PLX_CLI_LAMP_LAYER_H

#include <stddef.h>
#include "polarlux.h"

/* The lamps of a file, positions as written (lon/lat or metres). */
typedef struct lamp_file {
    plx_lamp *lamps;
    size_t n;
    int lonlat;        /* positions are WGS84 lon/lat */
    char *crs;         /* the CRS the file names, or NULL */
    char **ids;        /* id strings (owned) */
    size_t ignored;    /* features or rows that are not lamps */
} lamp_file;

/* Parses GeoJSON (text starting with '{') or CSV text. 0, or -1 with
 * "NAME: why" (CSV: "NAME:LINE: why") in err. */
int lamp_file_parse(const char *name, const char *text, lamp_file *out, char *err, size_t errlen);
void lamp_file_free(lamp_file *f);
/* Reads the file and adds its lamps to e's scene (plx_add_lamps) after
 * checking its coordinates match the scene's. Prints what went wrong and
 * returns an exit code. */
int lamp_layer_add(const char *cmd, const char *path, plx_engine *e, int quiet);

#endif
