/* GeoJSON output of the command (visibility polygons, lit regions, routes):
 * coordinates go back to WGS84 lon/lat when the scene came in lon/lat, and
 * the scene's crs (plx_scene_crs) is written back as a top-level "crs". */
#ifndef PLX_CLI_GEO_OUT_H
#define PLX_CLI_GEO_OUT_H

#include <cjson/cJSON.h>
#include "polarlux.h"

typedef struct geo_out {
    cJSON *root, *features;
    int lonlat;
    plx_engine *e;        /* for plx_local_to_lonlat */
} geo_out;

/* Starts a FeatureCollection in the scene's frame; 0 on success. */
int geo_begin(geo_out *g, plx_engine *e);
/* A position [x, y] or [x, y, z] in the output frame. */
cJSON *geo_position(const geo_out *g, double x, double y, const double *z);
/* geo_position without z, each number in the fewest digits that read back
 * as the same double (cJSON's 15 digits may move a vertex by a bit;
 * annotate's networks are read back: net_scores.h). */
cJSON *geo_position_exact(const geo_out *g, double x, double y);
/* A closed linear ring from n x,y pairs (z per vertex may be NULL). */
cJSON *geo_ring(const geo_out *g, const double *xy, uint32_t n, const double *z);
/* Adds a feature with the geometry and properties (both owned by g after). */
void geo_add(geo_out *g, cJSON *geometry, cJSON *props);
cJSON *geo_geometry(const char *type, cJSON *coordinates);
/* Writes the collection atomically; 0 on success, else message on stderr. */
int geo_write(geo_out *g, const char *cmd, const char *path);
void geo_free(geo_out *g);

#endif
