#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "geo_out.h"
#include "port.h"

int geo_begin(geo_out *g, plx_engine *e)
{
    plx_scene_info si;
    memset(g, 0, sizeof *g);
    if (plx_scene_info_get(e, &si) != PLX_OK)
        return -1;
    g->lonlat = si.lonlat;
    g->e = e;
    g->root = cJSON_CreateObject();
    cJSON_AddStringToObject(g->root, "type", "FeatureCollection");
    if (!g->lonlat) {
        cJSON *p = cJSON_AddObjectToObject(g->root, "properties");
        cJSON_AddStringToObject(p, "units", "m");
    }
    if (plx_scene_crs(e)) { /* the scene's CRS, GeoJSON 2008 style */
        cJSON *crs = cJSON_AddObjectToObject(g->root, "crs");
        cJSON_AddStringToObject(crs, "type", "name");
        cJSON_AddStringToObject(cJSON_AddObjectToObject(crs, "properties"), "name", plx_scene_crs(e));
    }
    g->features = cJSON_AddArrayToObject(g->root, "features");
    return g->root && g->features ? 0 : -1;
}

/* (x, y) local into the output frame (lon/lat when the scene was). */
static void out_frame(const geo_out *g, double *x, double *y)
{
    double xy[2], ll[2];
    if (!g->lonlat)
        return;
    xy[0] = *x;
    xy[1] = *y;
    plx_local_to_lonlat(g->e, 1, xy, ll);
    *x = ll[0];
    *y = ll[1];
}

cJSON *geo_position(const geo_out *g, double x, double y, const double *z)
{
    cJSON *a = cJSON_CreateArray();
    out_frame(g, &x, &y);
    cJSON_AddItemToArray(a, cJSON_CreateNumber(x));
    cJSON_AddItemToArray(a, cJSON_CreateNumber(y));
    if (z)
        cJSON_AddItemToArray(a, cJSON_CreateNumber(*z));
    return a;
}

cJSON *geo_position_exact(const geo_out *g, double x, double y)
{
    cJSON *a = cJSON_CreateArray();
    char num[40];
    out_frame(g, &x, &y);
    cli_shortest(x, num, sizeof num);
    cJSON_AddItemToArray(a, cJSON_CreateRaw(num));
    cli_shortest(y, num, sizeof num);
    cJSON_AddItemToArray(a, cJSON_CreateRaw(num));
    return a;
}

cJSON *geo_ring(const geo_out *g, const double *xy, uint32_t n, const double *z)
{
    cJSON *ring = cJSON_CreateArray();
    uint32_t i;
    for (i = 0; i <= n; i++) {
        uint32_t k = i % n;
        cJSON_AddItemToArray(ring, geo_position(g, xy[2 * k], xy[2 * k + 1], z ? &z[k] : NULL));
    }
    return ring;
}

cJSON *geo_geometry(const char *type, cJSON *coordinates)
{
    cJSON *geom = cJSON_CreateObject();
    cJSON_AddStringToObject(geom, "type", type);
    cJSON_AddItemToObject(geom, "coordinates", coordinates);
    return geom;
}

void geo_add(geo_out *g, cJSON *geometry, cJSON *props)
{
    cJSON *f = cJSON_CreateObject();
    cJSON_AddStringToObject(f, "type", "Feature");
    cJSON_AddItemToObject(f, "properties", props ? props : cJSON_CreateObject());
    cJSON_AddItemToObject(f, "geometry", geometry ? geometry : cJSON_CreateNull());
    cJSON_AddItemToArray(g->features, f);
}

int geo_write(geo_out *g, const char *cmd, const char *path)
{
    char err[512];
    char *text = cJSON_PrintUnformatted(g->root), *nl;
    size_t n;
    int rc;
    if (!text || !(nl = realloc(text, (n = strlen(text)) + 2))) {
        free(text);
        fprintf(stderr, "polarlux %s: %s: out of memory formatting GeoJSON\n", cmd, path);
        return -1;
    }
    text = nl;
    text[n] = '\n'; /* a text file's last line ends: on standard output the shell's prompt followed it */
    text[n + 1] = '\0';
    rc = port_write_atomic(path, text, n + 1, err, sizeof err);
    if (rc != 0)
        fprintf(stderr, "polarlux %s: %s\n", cmd, err);
    free(text);
    return rc;
}

void geo_free(geo_out *g)
{
    cJSON_Delete(g->root);
    g->root = NULL;
}
