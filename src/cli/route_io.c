#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cjson/cJSON.h>

#include "cli.h"
#include "points.h"
#include "port.h"
#include "route_io.h"

/* The bound of scene coordinates (README, "Scene format"). */

typedef struct frame {
    int lonlat;           /* the path file is in lon/lat */
    plx_engine *e;        /* for plx_lonlat_to_local */
} frame;

static int add_line(route_set *rs, size_t *cap, const char *name, const cJSON *coords, const frame *f,
                    char *why, size_t whylen)
{
    route_line *l;
    const cJSON *pos;
    uint32_t k = 0;
    int n = cJSON_GetArraySize(coords);
    if (!cJSON_IsArray(coords) || n < 2) {
        snprintf(why, whylen, "a line needs at least 2 positions");
        return -1;
    }
    if (rs->n == *cap) {
        size_t nc = *cap ? *cap * 2 : 16;
        route_line *nl = realloc(rs->lines, nc * sizeof *nl);
        if (!nl) {
            snprintf(why, whylen, "out of memory");
            return -1;
        }
        rs->lines = nl;
        *cap = nc;
    }
    l = &rs->lines[rs->n];
    memset(l, 0, sizeof *l);
    snprintf(l->name, sizeof l->name, "%s", name);
    l->xy = malloc(sizeof *l->xy * 2 * (size_t)n);
    if (!l->xy) {
        snprintf(why, whylen, "out of memory");
        return -1;
    }
    cJSON_ArrayForEach(pos, coords) {
        const cJSON *x = cJSON_GetArrayItem(pos, 0), *y = cJSON_GetArrayItem(pos, 1);
        double vx, vy;
        if (!cJSON_IsNumber(x) || !cJSON_IsNumber(y) || !isfinite(x->valuedouble) || !isfinite(y->valuedouble)) {
            snprintf(why, whylen, "position %u is not [x, y] of finite numbers", k);
            free(l->xy);
            return -1;
        }
        vx = x->valuedouble;
        vy = y->valuedouble;
        if (f->lonlat) {
            double ll[2], xy[2];
            ll[0] = vx;
            ll[1] = vy;
            plx_lonlat_to_local(f->e, 1, ll, xy);
            vx = xy[0];
            vy = xy[1];
        }
        if (fabs(vx) > CLI_MAX_COORD || fabs(vy) > CLI_MAX_COORD) {
            snprintf(why, whylen, "position %u (%g, %g) is more than 1e7 m from the origin", k, vx, vy);
            free(l->xy);
            return -1;
        }
        l->xy[2 * k] = vx;
        l->xy[2 * k + 1] = vy;
        k++;
    }
    l->n = k;
    rs->n++;
    return 0;
}

/* Checks every coordinate lies in lon/lat range. */
static int all_lonlat(const cJSON *c)
{
    const cJSON *it;
    if (cJSON_IsNumber(c))
        return 1;
    if (cJSON_IsArray(c) && cJSON_IsNumber(cJSON_GetArrayItem(c, 0))) {
        double x = cJSON_GetArrayItem(c, 0)->valuedouble, y = cJSON_IsNumber(cJSON_GetArrayItem(c, 1))
                                                                   ? cJSON_GetArrayItem(c, 1)->valuedouble
                                                                   : 0;
        return x >= -180 && x <= 180 && y >= -90 && y <= 90;
    }
    cJSON_ArrayForEach(it, c) if (!all_lonlat(it)) return 0;
    return 1;
}

/* The path's frame. properties.units "m": metres. Otherwise lon/lat when
 * every coordinate is in that range (refused on a metre scene, naming
 * units "m" for a metre path that happens to be in range), else metres:
 * on a lon/lat scene with a note (the scene file's own rule; a metre path
 * there was read with no word). */
/* The positions [x, y ...] in c (nested arrays). */
static int count_positions(const cJSON *c)
{
    const cJSON *it;
    int n = 0;
    if (cJSON_IsArray(c) && cJSON_IsNumber(cJSON_GetArrayItem(c, 0)))
        return 1;
    cJSON_ArrayForEach(it, c) n += count_positions(it);
    return n;
}

/* A feature's own properties.units: 1 "m", -1 another value, 0 none. */
static int feature_units(const cJSON *ft)
{
    const cJSON *u = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(ft, "properties"), "units");
    if (!u)
        return 0;
    return cJSON_IsString(u) && strcmp(u->valuestring, "m") == 0 ? 1 : -1;
}

/* The CRS a file names, GeoJSON-2008 style ({"crs": {"type": "name",
 * "properties": {"name": ...}}}) or as properties.crs (that object or a
 * string), as the scene loader reads it; NULL when none. */
static const char *file_crs(const cJSON *root)
{
    const cJSON *c = cJSON_GetObjectItemCaseSensitive(root, "crs"), *n;
    if (!c)
        c = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "properties"), "crs");
    if (cJSON_IsString(c))
        return c->valuestring;
    n = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(c, "properties"), "name");
    return cJSON_IsString(n) ? n->valuestring : NULL;
}

/* A CRS the file names against the scene's: 0 when it names none, 1 when
 * it names the scene's (either way of writing it) or WGS 84 for a lon/lat
 * scene that names none; else -1 with why (a file tagged EPSG:2154 was
 * scored on an EPSG:3067 scene without a word). */
static int same_crs(const cJSON *root, plx_engine *e, const plx_scene_info *si, char *why, size_t whylen)
{
    const char *fc = file_crs(root), *sc = plx_scene_crs(e);
    if (!fc)
        return 0;
    if (sc && cli_same_crs(fc, sc))
        return 1;
    if (!sc && si->lonlat && (strstr(fc, "CRS84") || cli_crs_epsg(fc) == 4326))
        return 1;
    snprintf(why, whylen, "the file's crs is %.60s but the scene's is %.60s: give the lines in the scene's "
             "coordinates (ogr2ogr -t_srs reprojects them)", fc,
             sc ? sc : si->lonlat ? "WGS84 lon/lat (none named)" : "local metres (none named)");
    return -1;
}

static int set_frame(const cJSON *root, const cJSON *features, plx_engine *e, frame *f, char *note, size_t notelen,
                     char *why, size_t whylen)
{
    const cJSON *props = cJSON_GetObjectItemCaseSensitive(root, "properties");
    const cJSON *units = cJSON_GetObjectItemCaseSensitive(props, "units"), *ft;
    plx_scene_info si;
    int ll = 1, plain = 0, k = 0, lines = 0, lines_ll = 0, named;
    memset(f, 0, sizeof f[0]);
    note[0] = '\0';
    plx_scene_info_get(e, &si);
    named = same_crs(root, e, &si, why, whylen);
    if (named < 0)
        return -1;
    if (named && !si.lonlat) /* the scene's projected crs: metres, whatever their range */
        return 0;
    if (units && !(cJSON_IsString(units) && strcmp(units->valuestring, "m") == 0)) {
        snprintf(why, whylen, "properties.units must be \"m\" when given");
        return -1;
    }
    cJSON_ArrayForEach(ft, features) { /* another unit refused, on any feature */
        if (feature_units(ft) < 0) {
            snprintf(why, whylen, "feature %d: properties.units must be \"m\" when given", k);
            return -1;
        }
        k++;
    }
    if (units)
        return 0;
    cJSON_ArrayForEach(ft, features) { /* the features without units of their own decide */
        const cJSON *g = cJSON_GetObjectItemCaseSensitive(ft, "geometry");
        const cJSON *co = cJSON_GetObjectItemCaseSensitive(g, "coordinates");
        if (feature_units(ft) > 0)
            continue;
        plain += count_positions(co);
        if (count_positions(co) > 0) {
            lines++;
            lines_ll += all_lonlat(co);
        }
        if (!all_lonlat(co))
            ll = 0;
    }
    if (!plain) /* no position to judge by: the features' own errors come later */
        return 0;
    if (!si.lonlat) {
        if (ll) {
            snprintf(why, whylen,
                     "the path is in lon/lat but the scene is in local metres (properties.units \"m\" reads "
                     "it as metres)");
            return -1;
        }
        return 0;
    }
    if (!ll) {
        int n = snprintf(note, notelen,
                         "coordinates exceed the lon/lat range: read as metres of the scene's frame, where the scene "
                         "is in lon/lat (properties.units \"m\" says so and silences this)");
        if (lines_ll > 0 && n > 0 && (size_t)n < notelen) /* a line in lon/lat among them was read as metres */
            snprintf(note + n, notelen - (size_t)n, "; %d of the %d lines lie wholly within it: if those are "
                     "lon/lat, the file mixes coordinate systems", lines_ll, lines);
        return 0;
    }
    f->lonlat = 1;
    f->e = e;
    return 0;
}

static void line_name(const cJSON *ft, size_t k, char *out, size_t len)
{
    const cJSON *props = cJSON_GetObjectItemCaseSensitive(ft, "properties");
    const cJSON *nm = cJSON_GetObjectItemCaseSensitive(props, "name");
    const cJSON *id = cJSON_GetObjectItemCaseSensitive(props, "id");
    if (cJSON_IsString(nm))
        snprintf(out, len, "%s", nm->valuestring);
    else if (cJSON_IsString(id))
        snprintf(out, len, "%s", id->valuestring);
    else if (cJSON_IsNumber(id))
        snprintf(out, len, "%.0f", id->valuedouble);
    else
        snprintf(out, len, "#%zu", k);
}

/* The feature's id for keyed outputs: osm_id, @id, id (properties), then
 * the feature's own id; strings as they are, numbers as integers. */
static void line_id(const cJSON *ft, char *out, size_t len)
{
    static const char *const keys[3] = { "osm_id", "@id", "id" };
    const cJSON *props = cJSON_GetObjectItemCaseSensitive(ft, "properties"), *v = NULL;
    int k;
    for (k = 0; k < 3 && !v; k++)
        v = cJSON_GetObjectItemCaseSensitive(props, keys[k]);
    if (!v)
        v = cJSON_GetObjectItemCaseSensitive(ft, "id");
    out[0] = '\0';
    if (cJSON_IsString(v))
        snprintf(out, len, "%s", v->valuestring);
    else if (cJSON_IsNumber(v))
        snprintf(out, len, "%.0f", v->valuedouble);
}

/* A note when no position of the lines lies within the scene's bounds
 * (nothing of the scene lights them: a file of another place, or metres
 * read as lon/lat), unless a note on the frame was made already. */
static void outside_note(route_set *rs, plx_engine *e, int lonlat)
{
    plx_scene_info si;
    size_t i;
    uint32_t k;
    if (rs->note[0])
        return;
    plx_scene_info_get(e, &si);
    for (i = 0; i < rs->n; i++)
        for (k = 0; k < rs->lines[i].n; k++) {
            const double *p = &rs->lines[i].xy[2 * k];
            if (p[0] >= si.bounds[0] && p[0] <= si.bounds[2] && p[1] >= si.bounds[1] && p[1] <= si.bounds[3])
                return;
        }
    snprintf(rs->note, sizeof rs->note, "no position lies within the scene's bounds, so no lamp of it lights the "
             "lines%s", lonlat ? " (read as lon/lat: properties.units \"m\" if they are metres)" : "");
}

/* A collection of one made of root (a Feature, or a bare geometry given
 * a Feature around it with its "properties" member), by reference: the
 * result is deleted before root, and deletes nothing of root. NULL when
 * out of memory. */
static cJSON *wrap_one(cJSON *root)
{
    cJSON *list = cJSON_CreateArray(), *ft;
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(root, "type");
    cJSON *props = cJSON_GetObjectItemCaseSensitive(root, "properties");
    if (!list)
        return NULL;
    if (strcmp(type->valuestring, "Feature") == 0) {
        if (!cJSON_AddItemReferenceToArray(list, root)) {
            cJSON_Delete(list);
            return NULL;
        }
        return list;
    }
    ft = cJSON_CreateObject();
    if (!ft || !cJSON_AddItemToArray(list, ft)) {
        cJSON_Delete(ft);
        cJSON_Delete(list);
        return NULL;
    }
    /* from here ft is the list's: deleting the list deletes it, and
     * leaves what the references point to */
    if (!cJSON_AddItemReferenceToObject(ft, "geometry", root) ||
        (props && !cJSON_AddItemReferenceToObject(ft, "properties", props))) {
        cJSON_Delete(list);
        return NULL;
    }
    return list;
}

/* route_parse, the parsed document kept in *keep (when not NULL) on
 * success. */
static int parse_lines(const char *name, const char *text, size_t len, plx_engine *e, route_set *out, cJSON **keep,
                       char *err, size_t errlen)
{
    cJSON *root = cli_json_parse(name, text, len, err, errlen), *wrap = NULL;
    const cJSON *features, *ft, *type;
    frame f, metres;
    size_t cap = 0, k = 0, first = 0;
    char why[256];
    memset(out, 0, sizeof *out);
    if (!root)
        return -1;
    type = cJSON_GetObjectItemCaseSensitive(root, "type");
    features = cJSON_GetObjectItemCaseSensitive(root, "features");
    if (cJSON_IsString(type) && (strcmp(type->valuestring, "Feature") == 0 ||
                                 strcmp(type->valuestring, "LineString") == 0 ||
                                 strcmp(type->valuestring, "MultiLineString") == 0)) {
        /* one Feature (walk's path files) or a bare geometry: a collection of one */
        if (!(wrap = wrap_one(root))) {
            snprintf(err, errlen, "%s: out of memory", name);
            cJSON_Delete(root);
            return -1;
        }
        features = wrap;
    } else if (!cJSON_IsString(type) || strcmp(type->valuestring, "FeatureCollection") != 0 ||
               !cJSON_IsArray(features)) {
        snprintf(err, errlen, "%s: not a GeoJSON FeatureCollection, Feature or LineString", name);
        cJSON_Delete(root);
        return -1;
    }
    if (set_frame(root, features, e, &f, out->note, sizeof out->note, why, sizeof why) != 0) {
        snprintf(err, errlen, "%s: %s", name, why);
        cJSON_Delete(wrap);
        cJSON_Delete(root);
        return -1;
    }
    memset(&metres, 0, sizeof metres);
    cJSON_ArrayForEach(ft, features) {
        const cJSON *g = cJSON_GetObjectItemCaseSensitive(ft, "geometry");
        const cJSON *gt = cJSON_GetObjectItemCaseSensitive(g, "type");
        const cJSON *co = cJSON_GetObjectItemCaseSensitive(g, "coordinates"), *part;
        char nm[32];
        int bad = 0;
        const frame *ff = feature_units(ft) > 0 ? &metres : &f; /* a feature's own units "m" */
        line_name(ft, k, nm, sizeof nm);
        if (cJSON_IsString(gt) && strcmp(gt->valuestring, "LineString") == 0) {
            bad = add_line(out, &cap, nm, co, ff, why, sizeof why);
        } else if (cJSON_IsString(gt) && strcmp(gt->valuestring, "MultiLineString") == 0 && cJSON_IsArray(co)) {
            cJSON_ArrayForEach(part, co) if (!bad) bad = add_line(out, &cap, nm, part, ff, why, sizeof why);
        } else {
            snprintf(why, sizeof why, "geometry is not a LineString or MultiLineString");
            bad = 1;
        }
        for (; !bad && first < out->n; first++) {
            line_id(ft, out->lines[first].id, sizeof out->lines[first].id);
            out->lines[first].feature = (uint32_t)k;
        }
        if (bad) {
            snprintf(err, errlen, "%s: feature %zu: %s", name, k, why);
            cJSON_Delete(wrap);
            cJSON_Delete(root);
            route_free(out);
            return -1;
        }
        k++;
    }
    cJSON_Delete(wrap);
    if (out->n == 0) {
        snprintf(err, errlen, "%s: no LineString features", name);
        cJSON_Delete(root);
        return -1;
    }
    outside_note(out, e, f.lonlat);
    if (keep)
        *keep = root;
    else
        cJSON_Delete(root);
    return 0;
}

int route_parse(const char *name, const char *text, size_t len, plx_engine *e, route_set *out,
                char *err, size_t errlen)
{
    return parse_lines(name, text, len, e, out, NULL, err, errlen);
}

int route_parse_doc(const char *name, const char *text, size_t len, plx_engine *e, route_set *out, cJSON **doc,
                    char *err, size_t errlen)
{
    *doc = NULL;
    return parse_lines(name, text, len, e, out, doc, err, errlen);
}

int route_read_doc(const char *path, plx_engine *e, route_set *out, cJSON **doc, char *err, size_t errlen)
{
    size_t len;
    char *text = cli_read_input(path, &len, err, errlen);
    int rc;
    memset(out, 0, sizeof *out);
    if (doc)
        *doc = NULL;
    if (!text)
        return -1;
    rc = parse_lines(cli_input_name(path), text, len, e, out, doc, err, errlen);
    free(text);
    return rc;
}

int route_read(const char *path, plx_engine *e, route_set *out, char *err, size_t errlen)
{
    return route_read_doc(path, e, out, NULL, err, errlen);
}

void route_free(route_set *rs)
{
    size_t i;
    for (i = 0; i < rs->n; i++)
        free(rs->lines[i].xy);
    free(rs->lines);
    rs->lines = NULL;
    rs->n = 0;
}
