/* Lamp layers: lamps read from a GeoJSON or CSV file (README "Your own
 * data") and added to the loaded scene with plx_add_lamps. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cjson/cJSON.h>

#include "cli.h"
#include "lamp_layer.h"
#include "port.h"

/* Scene defaults (README "Scene format"). */
#define LAYER_Z 6.0
#define LAYER_INTENSITY 1000.0
#define LAYER_RADIUS 30.0
static const float layer_color[3] = { 1.0f, 0.62f, 0.28f };

static void lamp_default(plx_lamp *l, uint32_t record)
{
    memset(l, 0, sizeof *l);
    l->z = LAYER_Z;
    l->intensity = LAYER_INTENSITY;
    l->radius = LAYER_RADIUS;
    memcpy(l->color, layer_color, sizeof l->color);
    l->feature = record;
}

static int push(lamp_file *f, size_t *cap, const plx_lamp *l, const char *id)
{
    if (f->n == *cap) {
        size_t nc = *cap ? 2 * *cap : 256;
        plx_lamp *nl = realloc(f->lamps, nc * sizeof *nl);
        char **ni;
        if (!nl)
            return -1;
        f->lamps = nl;
        ni = realloc(f->ids, nc * sizeof *ni);
        if (!ni)
            return -1;
        f->ids = ni;
        *cap = nc;
    }
    f->ids[f->n] = NULL;
    f->lamps[f->n] = *l;
    f->lamps[f->n].id = NULL;
    if (id) {
        f->ids[f->n] = malloc(strlen(id) + 1);
        if (!f->ids[f->n])
            return -1;
        strcpy(f->ids[f->n], id);
        f->lamps[f->n].id = f->ids[f->n];
    }
    f->n++;
    return 0;
}

void lamp_file_free(lamp_file *f)
{
    size_t i;
    for (i = 0; f->ids && i < f->n; i++)
        free(f->ids[i]);
    free(f->ids);
    free(f->lamps);
    free(f->crs);
    memset(f, 0, sizeof *f);
}

/* A number or a numeric string ("8", "8 m"); 1 found, 0 absent, -1 other. */
static int number_of(const cJSON *it, double *v)
{
    char *end;
    if (!it || cJSON_IsNull(it))
        return 0;
    if (cJSON_IsNumber(it)) {
        *v = it->valuedouble;
        return 1;
    }
    if (!cJSON_IsString(it))
        return -1;
    errno = 0;
    *v = strtod(it->valuestring, &end);
    while (*end == ' ')
        end++;
    if (*end == 'm')
        end++;
    return end != it->valuestring && *end == '\0' && !errno ? 1 : -1;
}

/* ---- GeoJSON -------------------------------------------------------------- */

static int tagged_lamp(const cJSON *props)
{
    const cJSON *lamp = cJSON_GetObjectItemCaseSensitive(props, "lamp");
    const cJSON *hw = cJSON_GetObjectItemCaseSensitive(props, "highway");
    return cJSON_IsTrue(lamp) || (cJSON_IsString(hw) && strcmp(hw->valuestring, "street_lamp") == 0);
}

static const char *geojson_crs(const cJSON *root)
{
    const cJSON *c = cJSON_GetObjectItemCaseSensitive(root, "crs"), *name;
    if (!c)
        c = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "properties"), "crs");
    if (cJSON_IsString(c))
        return c->valuestring;
    name = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(c, "properties"), "name");
    return cJSON_IsString(name) && *name->valuestring ? name->valuestring : NULL;
}

static int crs_lonlat(const char *name)
{
    size_t n = strlen(name);
    return strstr(name, "CRS84") != NULL || (n >= 5 && strcmp(name + n - 5, ":4326") == 0);
}

static const char *feature_id(const cJSON *f, const cJSON *props, char *buf, size_t len)
{
    static const char *const keys[] = { "id", "@id", "osm_id" };
    const cJSON *it = NULL;
    size_t k;
    for (k = 0; k < 3 && !it; k++) {
        it = cJSON_GetObjectItemCaseSensitive(props, keys[k]);
        if (!cJSON_IsString(it) && !cJSON_IsNumber(it))
            it = NULL;
    }
    if (!it)
        it = cJSON_GetObjectItemCaseSensitive(f, "id");
    if (cJSON_IsString(it))
        return it->valuestring;
    if (cJSON_IsNumber(it)) {
        snprintf(buf, len, "%.17g", it->valuedouble);
        return buf;
    }
    return NULL;
}

/* The lamp's properties; -1 with why when one is of the wrong kind. */
static int lamp_props(const cJSON *props, plx_lamp *l, char *why, size_t whylen)
{
    static const char *const keys[] = { "z", "intensity", "radius" };
    double *dst[3];
    const cJSON *col = cJSON_GetObjectItemCaseSensitive(props, "color");
    int k;
    const cJSON *phot = cJSON_GetObjectItemCaseSensitive(props, "photometry");
    if (phot && !cJSON_IsNull(phot)) { /* taken as isotropic, it lit the sky: refused, not read wrong */
        snprintf(why, whylen, "property \"photometry\": a lamp layer's lamps are isotropic (intensity in cd); "
                 "a lamp with an IES or EULUMDAT file belongs in the scene file");
        return -1;
    }
    dst[0] = &l->z;
    dst[1] = &l->intensity;
    dst[2] = &l->radius;
    for (k = 0; k < 3; k++)
        if (number_of(cJSON_GetObjectItemCaseSensitive(props, keys[k]), dst[k]) < 0) {
            snprintf(why, whylen, "property \"%s\" is not a number", keys[k]);
            return -1;
        }
    if (col && !cJSON_IsNull(col)) {
        if (!cJSON_IsArray(col) || cJSON_GetArraySize(col) != 3) {
            snprintf(why, whylen, "property \"color\" is not [r, g, b]");
            return -1;
        }
        for (k = 0; k < 3; k++) {
            const cJSON *v = cJSON_GetArrayItem(col, k);
            if (!cJSON_IsNumber(v)) {
                snprintf(why, whylen, "property \"color\" is not [r, g, b] of numbers");
                return -1;
            }
            l->color[k] = (float)v->valuedouble;
        }
    }
    return 0;
}

static int geojson_lamps(const char *name, const cJSON *features, int tagged_only, lamp_file *out,
                         char *err, size_t errlen)
{
    const cJSON *f;
    size_t cap = 0;
    uint32_t fi = 0;
    cJSON_ArrayForEach(f, features) {
        const cJSON *props = cJSON_GetObjectItemCaseSensitive(f, "properties");
        const cJSON *geom = cJSON_GetObjectItemCaseSensitive(f, "geometry");
        const cJSON *type = cJSON_GetObjectItemCaseSensitive(geom, "type");
        const cJSON *pos = cJSON_GetObjectItemCaseSensitive(geom, "coordinates");
        const cJSON *x = cJSON_GetArrayItem(pos, 0), *y = cJSON_GetArrayItem(pos, 1);
        char idbuf[32], why[192];
        plx_lamp l;
        fi++;
        if (!cJSON_IsString(type) || strcmp(type->valuestring, "Point") != 0 ||
            cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(props, "lamp")) || (tagged_only && !tagged_lamp(props))) {
            out->ignored++;
            continue;
        }
        if (!cJSON_IsNumber(x) || !cJSON_IsNumber(y)) {
            snprintf(err, errlen, "%s: feature %u: the point is not a position [x, y] of numbers", name, fi - 1);
            return -1;
        }
        lamp_default(&l, fi - 1);
        l.x = x->valuedouble;
        l.y = y->valuedouble;
        if (lamp_props(props, &l, why, sizeof why) != 0) {
            snprintf(err, errlen, "%s: feature %u: %s", name, fi - 1, why);
            return -1;
        }
        if (push(out, &cap, &l, feature_id(f, props, idbuf, sizeof idbuf)) != 0) {
            snprintf(err, errlen, "%s: out of memory", name);
            return -1;
        }
    }
    return 0;
}

/* 1 when the file's points are in lon/lat. */
static int geojson_lonlat(const cJSON *root, const cJSON *features)
{
    const cJSON *units = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "properties"),
                                                          "units");
    const char *crs = geojson_crs(root);
    const cJSON *f;
    if (cJSON_IsString(units) && strcmp(units->valuestring, "m") == 0)
        return 0;
    if (crs)
        return crs_lonlat(crs);
    cJSON_ArrayForEach(f, features) {
        const cJSON *pos = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(f, "geometry"),
                                                            "coordinates");
        const cJSON *x = cJSON_GetArrayItem(pos, 0), *y = cJSON_GetArrayItem(pos, 1);
        if (cJSON_IsNumber(x) && cJSON_IsNumber(y) && !(fabs(x->valuedouble) <= 180 && fabs(y->valuedouble) <= 90))
            return 0;
    }
    return 1;
}

static int parse_geojson(const char *name, const char *text, lamp_file *out, char *err, size_t errlen)
{
    cJSON *root = cli_json_parse(name, text, strlen(text), err, errlen), *features, *f;
    int tagged = 0, rc;
    const char *crs;
    if (!root) { /* where, as for scenes and paths (text after the value too: it was taken) */
        size_t n = strlen(err);
        snprintf(err + n, errlen > n ? errlen - n : 0, " (a lamp file is GeoJSON or CSV)");
        return -1;
    }
    features = cJSON_GetObjectItemCaseSensitive(root, "features");
    if (!cJSON_IsArray(features)) {
        cJSON_Delete(root);
        snprintf(err, errlen, "%s: not a GeoJSON FeatureCollection (no \"features\" array)", name);
        return -1;
    }
    cJSON_ArrayForEach(f, features)
        tagged |= tagged_lamp(cJSON_GetObjectItemCaseSensitive(f, "properties"));
    out->lonlat = geojson_lonlat(root, features);
    crs = geojson_crs(root);
    if (crs && !(out->crs = malloc(strlen(crs) + 1))) {
        cJSON_Delete(root);
        snprintf(err, errlen, "%s: out of memory", name);
        return -1;
    }
    if (crs)
        strcpy(out->crs, crs);
    rc = geojson_lamps(name, features, tagged, out, err, errlen);
    cJSON_Delete(root);
    return rc;
}

/* ---- CSV -------------------------------------------------------------------- */

enum { COL_X, COL_Y, COL_LON, COL_LAT, COL_Z, COL_INT, COL_RAD, COL_ID, COL_N };

/* Copies field k of line [s, end) split by sep into buf, trimmed and
 * unquoted; -1 when the line has fewer fields. */
static int field(const char *s, const char *end, char sep, int k, char *buf, size_t len)
{
    const char *a, *b;
    size_t n;
    for (; k > 0 && s < end; s++)
        if (*s == sep)
            k--;
    if (k > 0)
        return -1;
    for (b = s; b < end && *b != sep; b++)
        ;
    for (a = s; a < b && isspace((unsigned char)*a); a++)
        ;
    while (b > a && isspace((unsigned char)b[-1]))
        b--;
    if (b - a >= 2 && *a == '"' && b[-1] == '"')
        a++, b--;
    n = (size_t)(b - a) < len - 1 ? (size_t)(b - a) : len - 1;
    memcpy(buf, a, n);
    buf[n] = '\0';
    return 0;
}

static int column_kind(const char *h)
{
    static const char *const names[][4] = {
        { "x", "easting", NULL, NULL },          { "y", "northing", NULL, NULL },
        { "lon", "lng", "longitude", "long" },   { "lat", "latitude", NULL, NULL },
        { "z", "height", NULL, NULL },           { "intensity", "cd", NULL, NULL },
        { "radius", NULL, NULL, NULL },          { "id", NULL, NULL, NULL },
    };
    int k, j;
    for (k = 0; k < COL_N; k++)
        for (j = 0; j < 4 && names[k][j]; j++) {
            const char *a = h, *b = names[k][j];
            while (*a && *b && tolower((unsigned char)*a) == *b)
                a++, b++;
            if (!*a && !*b)
                return k;
        }
    return -1;
}

/* The header's columns into col[] (-1: absent); the separator into *sep. */
static int csv_header(const char *name, const char *s, const char *end, int col[COL_N], char *sep,
                      char *err, size_t errlen)
{
    char buf[64];
    int k;
    *sep = memchr(s, ';', (size_t)(end - s)) ? ';' : memchr(s, '\t', (size_t)(end - s)) ? '\t' : ',';
    for (k = 0; k < COL_N; k++)
        col[k] = -1;
    for (k = 0; field(s, end, *sep, k, buf, sizeof buf) == 0; k++) {
        int kind = column_kind(buf);
        if (kind >= 0 && col[kind] < 0)
            col[kind] = k;
        if (strcmp(buf, "photometry") == 0) { /* as a GeoJSON layer's: refused, not read as isotropic */
            snprintf(err, errlen, "%s: column %d \"photometry\": a lamp layer's lamps are isotropic (intensity in "
                     "cd); a lamp with an IES or EULUMDAT file belongs in the scene file", name, k + 1);
            return -1;
        }
    }
    if ((col[COL_X] < 0 || col[COL_Y] < 0) && (col[COL_LON] < 0 || col[COL_LAT] < 0)) {
        snprintf(err, errlen, "%s: the CSV header names no x,y or lon,lat columns (first line: '%.60s')", name, s);
        return -1;
    }
    return 0;
}

/* One number field (empty keeps *v); -1 when it is not a finite number. */
static int csv_number(const char *s, const char *end, char sep, int col, double *v)
{
    char buf[64], *stop;
    double d;
    if (col < 0 || field(s, end, sep, col, buf, sizeof buf) != 0 || !buf[0])
        return 0;
    errno = 0;
    d = strtod(buf, &stop);
    if (stop == buf || *stop || errno || !isfinite(d))
        return -1;
    *v = d;
    return 0;
}

static int csv_row(const char *s, const char *end, char sep, const int col[COL_N], int lonlat, plx_lamp *l,
                   char *id, size_t idlen)
{
    int cx = lonlat ? col[COL_LON] : col[COL_X], cy = lonlat ? col[COL_LAT] : col[COL_Y];
    double nan = NAN;
    l->x = l->y = nan;
    if (csv_number(s, end, sep, cx, &l->x) || csv_number(s, end, sep, cy, &l->y) ||
        csv_number(s, end, sep, col[COL_Z], &l->z) || csv_number(s, end, sep, col[COL_INT], &l->intensity) ||
        csv_number(s, end, sep, col[COL_RAD], &l->radius) || !isfinite(l->x) || !isfinite(l->y))
        return -1;
    id[0] = '\0';
    if (col[COL_ID] >= 0)
        field(s, end, sep, col[COL_ID], id, idlen);
    return 0;
}

/* "# crs: NAME" comment lines name the file's CRS. */
static int crs_comment(const char *s, const char *end, lamp_file *out)
{
    const char *p = s + 1;
    size_t n;
    while (p < end && *p == ' ')
        p++;
    if (end - p < 4 || strncmp(p, "crs:", 4) != 0)
        return 0;
    for (p += 4; p < end && *p == ' '; p++)
        ;
    for (n = (size_t)(end - p); n > 0 && isspace((unsigned char)p[n - 1]); n--)
        ;
    free(out->crs);
    out->crs = malloc(n + 1);
    if (!out->crs)
        return -1;
    memcpy(out->crs, p, n);
    out->crs[n] = '\0';
    return 0;
}

static int parse_csv(const char *name, const char *text, lamp_file *out, char *err, size_t errlen)
{
    const char *s = text;
    int col[COL_N], have_header = 0;
    char sep = ',';
    size_t line = 0, cap = 0;
    while (*s) {
        const char *end = strchr(s, '\n');
        char id[128];
        plx_lamp l;
        if (!end)
            end = s + strlen(s);
        line++;
        if (*s == '#' && crs_comment(s, end, out) != 0) {
            snprintf(err, errlen, "%s: out of memory", name);
            return -1;
        }
        if (*s != '#' && end > s && !(end == s + 1 && *s == '\r')) {
            if (!have_header) {
                if (csv_header(name, s, end, col, &sep, err, errlen) != 0)
                    return -1;
                out->lonlat = col[COL_X] < 0;
                have_header = 1;
            } else {
                lamp_default(&l, (uint32_t)line);
                if (csv_row(s, end, sep, col, out->lonlat, &l, id, sizeof id) != 0) {
                    snprintf(err, errlen, "%s:%zu: a position or number is missing or not a finite number", name,
                             line);
                    return -1;
                }
                if (push(out, &cap, &l, id[0] ? id : NULL) != 0) {
                    snprintf(err, errlen, "%s: out of memory", name);
                    return -1;
                }
            }
        }
        s = *end ? end + 1 : end;
    }
    if (!have_header) {
        snprintf(err, errlen, "%s: empty: a CSV lamp file needs a header line (x,y or lon,lat ...)", name);
        return -1;
    }
    return 0;
}

int lamp_file_parse(const char *name, const char *text, lamp_file *out, char *err, size_t errlen)
{
    const char *t = text;
    int rc;
    memset(out, 0, sizeof *out);
    while (isspace((unsigned char)*t))
        t++;
    rc = *t == '{' ? parse_geojson(name, t, out, err, errlen) : parse_csv(name, text, out, err, errlen);
    if (rc == 0 && out->crs && crs_lonlat(out->crs) != out->lonlat) {
        snprintf(err, errlen, "%s: the file names the CRS %s but its positions are %s", name, out->crs,
                 out->lonlat ? "lon/lat" : "x,y");
        rc = -1;
    }
    if (rc != 0)
        lamp_file_free(out);
    return rc;
}

/* ---- adding to the scene -------------------------------------------------------- */

static int same_frame(const char *cmd, const char *path, plx_engine *e, const lamp_file *f)
{
    plx_scene_info si;
    const char *crs = plx_scene_crs(e);
    plx_scene_info_get(e, &si);
    if (f->crs && crs && !cli_same_crs(f->crs, crs)) {
        fprintf(stderr, "polarlux %s: %s: the lamps are in %s but the scene in %s; give them in the scene's CRS\n",
                cmd, path, f->crs, crs);
        return -1;
    }
    if (f->lonlat != si.lonlat) {
        fprintf(stderr, "polarlux %s: %s: the lamps are in %s but the scene is in %s; give them in the scene's "
                        "coordinates\n", cmd, path, f->lonlat ? "lon/lat" : "metres (x,y)",
                si.lonlat ? "lon/lat" : "metres");
        return -1;
    }
    return 0;
}

int lamp_layer_add(const char *cmd, const char *path, plx_engine *e, int quiet)
{
    char err[512], why[256];
    char *text = port_read_text(path, NULL, why, sizeof why);
    lamp_file f;
    plx_status st;
    uint32_t before;
    plx_scene_info si;
    if (!text) {
        fprintf(stderr, "polarlux %s: --lamps %s: %s\n", cmd, path, why);
        return EXIT_FAIL;
    }
    if (lamp_file_parse(path, text, &f, err, sizeof err) != 0) {
        free(text);
        fprintf(stderr, "polarlux %s: --lamps %s\n", cmd, err);
        return EXIT_FAIL;
    }
    free(text);
    if (same_frame(cmd, path, e, &f) != 0) {
        lamp_file_free(&f);
        return EXIT_FAIL;
    }
    plx_scene_info_get(e, &si);
    before = si.lamps;
    st = f.n > 0xfffffff0u ? PLX_E_INVALID : plx_add_lamps(e, f.lamps, (uint32_t)f.n, path);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: --lamps %s: %s\n", cmd, path, plx_last_error(e));
        lamp_file_free(&f);
        return st == PLX_E_NOMEM ? EXIT_NOMEM : EXIT_FAIL;
    }
    plx_scene_info_get(e, &si);
    if (!quiet && si.lamps - before < f.n)
        fprintf(stderr, "polarlux %s: --lamps %s: %u of %zu lamps added (see the warnings above)\n", cmd, path,
                si.lamps - before, f.n);
    if (!quiet && f.n == 0)
        fprintf(stderr, "polarlux %s: warning: --lamps %s holds no lamps (%zu features or rows are not lamps)\n",
                cmd, path, f.ignored);
    lamp_file_free(&f);
    return EXIT_OK;
}
