/* Reading routes: GeoJSON LineString / MultiLineString features, projected
 * into the scene's frame (SPEC §1 coordinate rules, the scene's centre). */
#ifndef PLX_CLI_ROUTE_IO_H
#define PLX_CLI_ROUTE_IO_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"

typedef struct route_line {
    char name[32];     /* properties.name, id, or "#k" */
    double *xy;        /* n vertices in the scene's local metres */
    uint32_t n;
    char id[40];       /* properties.osm_id, @id, id or the feature's id; "" if none */
    uint32_t feature;  /* index of the feature in the file */
} route_line;

typedef struct route_set {
    route_line *lines;
    size_t n;
    char note[400];    /* a warning on how the file was read ("" if none): printed unless --quiet */
} route_set;

/* 0 on success; -1 with "FILE: feature k: why" in err. */
int route_read(const char *path, plx_engine *e, route_set *out, char *err, size_t errlen);
/* route_read, and the parsed GeoJSON in *doc (cJSON_Delete; NULL on
 * failure) for what else it holds (annotate's scores, net_scores.h). */
struct cJSON;
int route_read_doc(const char *path, plx_engine *e, route_set *out, struct cJSON **doc, char *err, size_t errlen);
/* route_read_doc from text. */
int route_parse_doc(const char *name, const char *text, size_t len, plx_engine *e, route_set *out, struct cJSON **doc,
                    char *err, size_t errlen);
/* The same from text (for tests and fuzzing). */
int route_parse(const char *name, const char *text, size_t len, plx_engine *e, route_set *out,
                char *err, size_t errlen);
void route_free(route_set *rs);

#endif
