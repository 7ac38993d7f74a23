/* geojson: a GeoJSON FeatureCollection read into a scene (SPEC §1). */
#ifndef PLX_GEOJSON_H
#define PLX_GEOJSON_H

#include "base/context.h"

/* Reads text (len bytes; NULL reads as empty) into a new scene in arena a
 * (part PLX_PART_SCENE; scratch from a is not given back: the caller
 * releases it). Messages name 'name' (may be NULL); errors and warnings go
 * to e (base/context.h). *out is the scene, NULL on failure. */
plx_status geojson_load(plx_engine *e, arena *a, const char *text, size_t len, const char *name,
                        scene **out /* OUT */);

#endif
