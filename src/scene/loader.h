/* loader: state shared by the GeoJSON reading steps (geojson.c, features.c). */
#ifndef PLX_LOADER_H
#define PLX_LOADER_H

#include <cjson/cJSON.h>
#include "base/engine.h"

typedef struct loader {
    plx_engine *e;
    scene *s;
    const char *name;      /* source name for messages, or NULL */
    const char *text;
    size_t len;
    uint32_t *feat_line;   /* line of each feature (scratch) */
    uint32_t *feat_col;    /* its column */
    uint32_t nfeat;
    int metres;            /* properties.units == "m", or a projected crs */
    double lon0, lat0, coslat;
    int gi_bounds_given;   /* properties.ground_image_bounds read (scene coordinates) */
    double gi_bounds[4];
} loader;

/* 1: a number (JSON number or numeric string with optional unit m),
 * 0: absent or null, -1: a value of another kind. */
int ld_number(const cJSON *item, double *out);
int ld_prop_number(loader *ld, uint32_t fi, const char *id, const cJSON *props,
                   const char *key, double *out);
/* Reports a bad feature; PLX_OK means skip it and go on (not strict). */
plx_status ld_bad_feature(loader *ld, uint32_t fi, const char *id, const char *why);
void ld_warn(loader *ld, uint32_t fi, const char *id, const char *why);

/* Reads every feature into ld->s (features.c). */
plx_status ld_features(loader *ld, cJSON *features);
/* Leaves out lamps inside a building's solid, reporting each (features.c). */
plx_status ld_drop_buried_lamps(loader *ld);
/* The same for lamps first.. only (lamps added by plx_add_lamps). */
plx_status ld_drop_buried_lamps_from(loader *ld, uint32_t first);

#endif
