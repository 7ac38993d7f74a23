/* features: the features of a GeoJSON FeatureCollection read into the
 * scene (features.c). */
#ifndef PLX_FEATURES_H
#define PLX_FEATURES_H

#include "scene/loader.h"

/* Reads every feature into ld->s (features.c). */
plx_status ld_features(loader *ld, jv features);
/* Leaves out lamps inside a building's solid, reporting each (features.c). */
plx_status ld_drop_buried_lamps(loader *ld);

/* The same for lamps first.. only (lamps added by plx_add_lamps). */
plx_status ld_drop_buried_lamps_from(loader *ld, uint32_t first);

#endif
