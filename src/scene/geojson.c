/* geojson: GeoJSON FeatureCollection -> scene (SPEC §1).
 *
 * The text is streamed, never parsed into a tree: one pass checks it
 * (base/jsoncheck.c: the grammar and error positions of cJSON, which read
 * it before), then the features are read in place one at a time, in two
 * passes (features.c): one counts and finds the coordinate frame, one fills
 * the scene arrays. Besides the scene itself, the load holds a line index
 * of 8 bytes a feature and what one feature's checks need (rings are checked
 * where they lie in the scene's arrays); all of it scratch, given back
 * before return; on failure the scene part is given back too. Nothing
 * process-wide is touched (no cJSON hooks, no static state).
 *
 * Top-level properties: units, ground_albedo (fatal when wrong), and
 * ground_image / ground_image_bounds (README "Scene format"): the path is
 * kept as written (the core reads no files; the caller gives the pixels to
 * plx_set_ground_image, src/ground.c) and the bounds are projected like the
 * features once the frame is known; a bad value is fatal when strict and
 * ignored with a warning otherwise.
 */
#include <string.h>
#include <stdlib.h> /* qsort */
#include <math.h>

#include "base/geom.h"
#include "base/lonlat.h"
#include "scene/lampmerge.h"
#include "scene/blocks.h"
#include "base/jsonscan.h"
#include "scene/loader.h"
#include "scene/features.h"
#include "scene/geojson.h"

#define BOUNDS_MARGIN 50.0
#define MAX_COORD 1.0e7
#define MAX_HEIGHT 1000.0
#define DEFAULT_HEIGHT 12.0
#define LEVEL_HEIGHT 3.0
#define DEFAULT_ALBEDO 0.35
#define DEFAULT_GROUND_ALBEDO 0.15
#define BLOCK_TOLERANCE 0.05
#define MAX_IMAGE_PATH 4096

/* ---- messages ----------------------------------------------------------- */

static plx_status fail_scene(loader *ld, const char *why)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    if (ld->name) {
        sb_str(&b, ld->name);
        sb_str(&b, ": ");
    }
    sb_str(&b, why);
    return eng_fail(ld->e, PLX_E_SCENE, msg);
}

/* A top-level property with a bad value that the scene can do without
 * (properties.ground_image*): fatal when strict, else ignored with a
 * warning. Returns PLX_OK to go on. */
static plx_status bad_top_property(loader *ld, const char *why)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    if (eng_strict(ld->e))
        return fail_scene(ld, why);
    sb_init(&b, msg, sizeof msg);
    if (ld->name) {
        sb_str(&b, ld->name);
        sb_str(&b, ": ");
    }
    sb_str(&b, why);
    sb_str(&b, "; ignored");
    eng_warn(ld->e, msg);
    return PLX_OK;
}

/* ---- parsing ------------------------------------------------------------ */

static plx_status parse_error(loader *ld, const char *at)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    const char *tail;
    size_t off = jsonscan_error_at(ld->text, ld->len, at && at >= ld->text ? (size_t)(at - ld->text) : 0, &tail);
    uint32_t line, col;
    jsonscan_line_col(ld->text, ld->len, off, &line, &col);
    sb_init(&b, msg, sizeof msg);
    if (ld->name) {
        sb_str(&b, ld->name);
        sb_str(&b, ": ");
    }
    if (off < ld->len && (ld->text[off] == '[' || ld->text[off] == '{') &&
        jsonscan_depth_at(ld->text, ld->len, off) >= JSONSCAN_DEPTH) {
        /* well-formed maybe, but deeper than cJSON parses */
        sb_str(&b, "JSON nested deeper than ");
        sb_uint(&b, JSONSCAN_DEPTH);
        sb_str(&b, " levels at byte ");
        sb_uint(&b, off);
        sb_str(&b, " (line ");
        sb_uint(&b, line);
        sb_str(&b, ", column ");
        sb_uint(&b, col);
        sb_str(&b, ")");
        return eng_fail(ld->e, PLX_E_PARSE, msg);
    }
    sb_str(&b, "malformed JSON at byte ");
    sb_uint(&b, off);
    sb_str(&b, " (line ");
    sb_uint(&b, line);
    sb_str(&b, ", column ");
    sb_uint(&b, col);
    sb_str(&b, ")");
    sb_str(&b, tail);
    return eng_fail(ld->e, PLX_E_PARSE, msg);
}

/* Checks the whole text; a value followed by anything but white space (and
 * NUL bytes to the end) is malformed. */
static plx_status check_json(loader *ld)
{
    size_t end, p = 0;
    if (!jsonscan_check(ld->text, ld->len, &end))
        return parse_error(ld, ld->text + end);
    if ((end = jsonscan_trailing(ld->text, ld->len, end)) < ld->len)
        return parse_error(ld, ld->text + end);
    if (ld->len >= 5 && memcmp(ld->text, "\xEF\xBB\xBF", 3) == 0)
        p = 3; /* a UTF-8 byte order mark */
    ld->root = jsonscan_ws(ld->text, ld->len, p);
    return PLX_OK;
}

/* ---- top level ------------------------------------------------------------ */

/* properties.ground_image (a path, kept as written: the core reads no
 * files) and properties.ground_image_bounds (kept in scene coordinates
 * until the frame is known; place_ground_image). */
static plx_status read_ground_image(loader *ld, jv props)
{
    jv gi = ld_get(ld, props, "ground_image"), gb = ld_get(ld, props, "ground_image_bounds");
    if (gi != JV_NONE && ld_kind(ld, gi) != JS_NULL) {
        size_t n = ld_str(ld, gi, NULL, 0);
        if (n == 0 || n > MAX_IMAGE_PATH) {
            plx_status st = bad_top_property(ld, "properties.ground_image must be the path of a PNG file "
                                                 "(a non-empty string of at most 4096 bytes)");
            if (st != PLX_OK)
                return st;
        } else {
            char *path = arena_alloc(ld->mem, PLX_PART_SCENE, n + 1, 1);
            if (!path)
                return eng_nomem(ld->e, "loading the scene");
            ld_str(ld, gi, path, n + 1);
            ld->s->ground_image = path;
        }
    }
    if (gb != JV_NONE && ld_kind(ld, gb) != JS_NULL) {
        double v[4];
        int i, ok = ld_kind(ld, gb) == JS_ARRAY && ld_count(ld, gb) == 4;
        for (i = 0; ok && i < 4; i++) {
            jv it = ld_item(ld, gb, (uint32_t)i);
            ok = ld_kind(ld, it) == JS_NUMBER && isfinite(ld_double(ld, it));
            v[i] = ok ? ld_double(ld, it) : 0.0;
        }
        if (!ok || !(v[0] < v[2] && v[1] < v[3]))
            return bad_top_property(ld, "properties.ground_image_bounds must be [x0, y0, x1, y1]: "
                                        "4 finite numbers with x0 < x1 and y0 < y1");
        ld->gi_bounds_given = 1;
        memcpy(ld->gi_bounds, v, sizeof v);
    }
    return PLX_OK;
}

/* The ground image's box in local metres: the given bounds projected like
 * every coordinate of the scene (SPEC §1), else the Bounds box. */
static plx_status place_ground_image(loader *ld)
{
    scene *s = ld->s;
    double b[4];
    int i;
    memcpy(s->ground_image_bounds, s->bounds, sizeof s->bounds);
    if (!ld->gi_bounds_given)
        return PLX_OK;
    memcpy(b, ld->gi_bounds, sizeof b);
    if (s->lonlat) {
        if (!(b[0] >= -180.0 && b[2] <= 180.0 && b[1] >= -90.0 && b[3] <= 90.0))
            return bad_top_property(ld, "properties.ground_image_bounds must be lon/lat degrees like the "
                                        "scene's coordinates (lon -180..180, lat -90..90)");
        for (i = 0; i < 4; i += 2) {
            lonlat_to_local(ld->lon0, ld->lat0, ld->coslat, &b[i], &b[i + 1]);
        }
    }
    for (i = 0; i < 4; i++)
        if (!(fabs(b[i]) <= MAX_COORD))
            return bad_top_property(ld, "properties.ground_image_bounds is out of range (|coordinate| > 1e7 m)");
    if (!(b[0] < b[2] && b[1] < b[3]))
        return bad_top_property(ld, "properties.ground_image_bounds is empty once projected to metres");
    memcpy(s->ground_image_bounds, b, sizeof b);
    s->ground_image_bounds_given = 1;
    return PLX_OK;
}

/* The CRS name of a GeoJSON 2008 "crs" member ({"type": "name",
 * "properties": {"name": "urn:ogc:def:crs:EPSG::2154"}}) or of
 * properties.crs (that object, or the name as a string): the string value,
 * JV_NONE if none. */
static jv crs_name(const loader *ld, jv crs)
{
    jv name;
    if (ld_kind(ld, crs) == JS_STRING)
        return crs;
    name = ld_get(ld, ld_get(ld, crs, "properties"), "name");
    return ld_kind(ld, name) == JS_STRING ? name : JV_NONE;
}

/* Geographic CRSs (degrees of longitude and latitude) by EPSG code: WGS 84
 * (2D and 3D), ETRS89 (2D and 3D), NAD83, NAD83(CSRS), NAD83(NSRS2007),
 * NAD83(2011), GDA94, GDA2020, NZGD2000, JGD2000, JGD2011, CGCS2000,
 * SIRGAS 2000, SIRGAS 1995, RGF93, WGS 72, ED50, OSGB36, DHDN, MGI, NTF,
 * RT90, SWEREF99, ITRF2014 (3D) and NAD27. Their datums differ by metres at
 * most from WGS 84 (ED50, OSGB36, NAD27 and WGS 72 by up to a few hundred),
 * which a local frame of a district does not notice; the name is kept for
 * the outputs. */
static const long geographic_epsg[] = {
    4326, 4979, 4258, 4937, 4269, 4617, 4759, 6318, 4283, 7844, 4167, 4612, 6668, 4490,
    4674, 4170, 4171, 4322, 4230, 4277, 4314, 4312, 4275, 4124, 4619, 7912, 4267,
};

/* The EPSG code at the end of a name ("EPSG:4258", "urn:ogc:def:crs:EPSG::4258"), or 0. */
static long crs_epsg(const char *name)
{
    size_t n = strlen(name), d = n;
    long v = 0;
    while (d > 0 && name[d - 1] >= '0' && name[d - 1] <= '9' && n - d < 7)
        d--;
    if (d == n || d == 0 || name[d - 1] != ':' || !strstr(name, "EPSG"))
        return 0;
    for (; d < n; d++)
        v = v * 10 + (name[d] - '0');
    return v;
}

/* 1 when the CRS names lon/lat degrees: OGC CRS84 (or CRS83, CRS27) or one
 * of the geographic EPSG codes above. */
static int crs_is_lonlat(const char *name)
{
    long code = crs_epsg(name);
    size_t i;
    if (strstr(name, "CRS84") || strstr(name, "CRS83") || strstr(name, "CRS27"))
        return 1;
    for (i = 0; code && i < sizeof geographic_epsg / sizeof geographic_epsg[0]; i++)
        if (code == geographic_epsg[i])
            return 1;
    return 0;
}

/* Keeps the scene's CRS (copied into the scene) and reads a projected one
 * as metres. */
static plx_status read_crs(loader *ld, jv props)
{
    jv c = ld_get(ld, ld->root, "crs");
    jv name = c != JV_NONE ? crs_name(ld, c) : JV_NONE;
    char *copy;
    size_t n;
    if (name == JV_NONE && ld_kind(ld, props) == JS_OBJECT)
        name = crs_name(ld, ld_get(ld, props, "crs"));
    n = name != JV_NONE ? ld_str(ld, name, NULL, 0) : 0;
    if (n == 0)
        return PLX_OK;
    if (n > 1000)
        return bad_top_property(ld, "the crs name is longer than 1000 bytes");
    copy = arena_alloc(ld->mem, PLX_PART_SCENE, n + 1, 1);
    if (!copy)
        return eng_nomem(ld->e, "keeping the scene's crs");
    ld_str(ld, name, copy, n + 1);
    ld->s->crs = copy;
    ld->crs_lonlat = crs_is_lonlat(copy);
    if (!ld->crs_lonlat)
        ld->metres = 1;
    return PLX_OK;
}

static plx_status read_collection(loader *ld, jv *features)
{
    jv props, units, ga;
    plx_status st;
    if (ld_kind(ld, ld->root) != JS_OBJECT)
        return fail_scene(ld, "the top-level value is not a JSON object (expected a GeoJSON FeatureCollection)");
    if (!ld_str_is(ld, ld_get(ld, ld->root, "type"), "FeatureCollection"))
        return fail_scene(ld, "the top-level object is not a FeatureCollection (\"type\" must be \"FeatureCollection\")");
    *features = ld_get(ld, ld->root, "features");
    if (ld_kind(ld, *features) != JS_ARRAY)
        return fail_scene(ld, "the FeatureCollection has no \"features\" array");
    props = ld_get(ld, ld->root, "properties");
    ld->metres = 0;
    ld->s->ground_albedo = DEFAULT_GROUND_ALBEDO;
    st = read_crs(ld, props);
    if (st != PLX_OK || ld_kind(ld, props) != JS_OBJECT)
        return st;
    units = ld_get(ld, props, "units");
    ga = ld_get(ld, props, "ground_albedo");
    if (units != JV_NONE) {
        if (ld_str_is(ld, units, "m"))
            ld->metres = 1;
        else
            return fail_scene(ld, "properties.units must be \"m\" (metres) when given; leave it out for WGS84 lon/lat");
    }
    if (ga != JV_NONE) {
        double v;
        if (ld_number(ld, ga, &v) != 1 || !(v >= 0.0 && v <= 1.0))
            return ld->oom ? eng_nomem(ld->e, "loading the scene")
                           : fail_scene(ld, "properties.ground_albedo must be a number from 0 to 1");
        ld->s->ground_albedo = v;
    }
    return read_ground_image(ld, props);
}

/* ---- the load --------------------------------------------------------------- */

static void finish_info(scene *s)
{
    uint32_t i;
    double b[4] = { 1e300, 1e300, -1e300, -1e300 };
    int any = 0;
    for (i = 0; i < s->nbld; i++) {
        const double *bx = s->bld[i].box;
        b[0] = fmin(b[0], bx[0]);
        b[1] = fmin(b[1], bx[1]);
        b[2] = fmax(b[2], bx[2]);
        b[3] = fmax(b[3], bx[3]);
        any = 1;
    }
    for (i = 0; !any && i < s->nlamps; i++) {
        b[0] = fmin(b[0], s->lamps[i].x);
        b[1] = fmin(b[1], s->lamps[i].y);
        b[2] = fmax(b[2], s->lamps[i].x);
        b[3] = fmax(b[3], s->lamps[i].y);
    }
    if (!any && s->nlamps == 0)
        b[0] = b[1] = b[2] = b[3] = 0.0;
    s->bounds[0] = b[0] - BOUNDS_MARGIN;
    s->bounds[1] = b[1] - BOUNDS_MARGIN;
    s->bounds[2] = b[2] + BOUNDS_MARGIN;
    s->bounds[3] = b[3] + BOUNDS_MARGIN;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Minimum, median and maximum building height (scratch memory). */
static plx_status height_stats(plx_engine *e, arena *a, scene *s)
{
    arena_mark m = arena_get_mark(a);
    double *h;
    uint32_t i, n = s->nbld;
    if (n == 0)
        return PLX_OK;
    h = arena_scratch(a, arena_mul(n, sizeof *h), 8);
    if (!h)
        return eng_nomem(e, "computing height statistics");
    for (i = 0; i < n; i++)
        h[i] = s->bld[i].height;
    qsort(h, n, sizeof *h, cmp_double);
    s->height_min = h[0];
    s->height_max = h[n - 1];
    s->height_median = n % 2 ? h[n / 2] : 0.5 * (h[n / 2 - 1] + h[n / 2]);
    arena_release(a, &m);
    return PLX_OK;
}

/* A key the loader read that its object holds twice (ld_get): cJSON and we
 * read the first, other readers may read the last, so the scene may not be
 * the one its author meant. Fatal when strict, else a warning. */
static plx_status report_duplicate(loader *ld)
{
    char why[ENGINE_ERR_BYTES], key[64];
    uint32_t line, col;
    strbuf b;
    if (!ld->cache || ld->cache->dup == JV_NONE)
        return PLX_OK;
    jsonscan_line_col(ld->text, ld->len, ld->cache->dup, &line, &col);
    ld_str(ld, ld->cache->dup, key, sizeof key);
    sb_init(&b, why, sizeof why);
    if (ld->name) {
        sb_str(&b, ld->name);
        sb_str(&b, ": ");
    }
    sb_str(&b, "line ");
    sb_uint(&b, line);
    sb_str(&b, ", column ");
    sb_uint(&b, col);
    sb_str(&b, ": an object holds \"");
    sb_str(&b, key);
    sb_str(&b, "\" twice; the first is read (as cJSON reads), where other readers may take the last");
    if (eng_strict(ld->e))
        return eng_fail(ld->e, PLX_E_SCENE, why);
    eng_warn(ld->e, why);
    return PLX_OK;
}

static plx_status load(plx_engine *e, loader *ld, scene **out)
{
    jv features = JV_NONE;
    plx_status st;
    scene *s = arena_calloc(ld->mem, PLX_PART_SCENE, 1, sizeof *s, 16);
    if (!s)
        return eng_nomem(e, "loading the scene");
    ld->s = s;
    st = check_json(ld);
    if (st != PLX_OK)
        return st;
    st = read_collection(ld, &features);
    if (st != PLX_OK)
        return st;
    st = ld_features(ld, features);
    if (st != PLX_OK)
        return st;
    st = report_duplicate(ld);
    if (st != PLX_OK)
        return st;
    finish_info(s);
    st = place_ground_image(ld);
    if (st != PLX_OK)
        return st;
    st = height_stats(e, ld->mem, s);
    if (st != PLX_OK)
        return st;
    st = ld_drop_buried_lamps(ld);
    if (st != PLX_OK)
        return st;
    st = ld_merge_duplicate_lamps(ld);
    if (st != PLX_OK)
        return st;
    st = blocks_build(ld->mem, s, BLOCK_TOLERANCE);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "grouping buildings into blocks");
    if (st != PLX_OK)
        return eng_fail(e, st, "grouping buildings into blocks failed");
    *out = s;
    return PLX_OK;
}

plx_status geojson_load(plx_engine *e, arena *a, const char *text, size_t len, const char *name,
                        scene **out)
{
    loader ld;
    ld_cache cache;
    int i;
    memset(&ld, 0, sizeof ld);
    memset(&cache, 0, sizeof cache);
    for (i = 0; i < LD_OBJECTS; i++)
        cache.obj[i].obj = JV_NONE;
    cache.dup = JV_NONE;
    ld.cache = &cache;
    ld.e = e;
    ld.mem = a;
    ld.name = name;
    ld.text = text ? text : "";
    ld.len = len;
    *out = NULL;
    return load(e, &ld, out);
}
