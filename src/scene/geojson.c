/* geojson: GeoJSON FeatureCollection -> scene (SPEC §1).
 *
 * The text is parsed by cJSON into scratch memory of the engine's arena
 * (cJSON's allocation hooks point at the arena for the length of the parse),
 * then read in two passes: one counts and finds the coordinate frame, one
 * fills the scene arrays. All scratch memory is given back before return;
 * on failure the scene part is given back too.
 *
 * Top-level properties: units, ground_albedo (fatal when wrong), and
 * ground_image / ground_image_bounds (README "Scene format"): the path is
 * kept as written (the core reads no files; the caller gives the pixels to
 * plx_set_ground_image, src/ground.c) and the bounds are projected like the
 * features once the frame is known; a bad value is fatal when strict and
 * ignored with a warning otherwise.
 *
 * cJSON's hooks are process-wide, so the hook functions must find the arena
 * through one static pointer: the single piece of mutable static state in
 * the core, forced by cJSON's API. The port's lock (when given) serialises
 * loads of different engines running in different threads.
 */
#include <string.h>
#include <stdlib.h> /* qsort */
#include <math.h>
#include <cjson/cJSON.h>

#include "base/engine.h"
#include "base/geom.h"
#include "scene/blocks.h"
#include "base/jsonscan.h"
#include "scene/loader.h"

#define BOUNDS_MARGIN 50.0
#define MAX_COORD 1.0e7
#define MAX_HEIGHT 1000.0
#define DEFAULT_HEIGHT 12.0
#define LEVEL_HEIGHT 3.0
#define DEFAULT_ALBEDO 0.35
#define DEFAULT_GROUND_ALBEDO 0.15
#define BLOCK_TOLERANCE 0.05
#define MAX_IMAGE_PATH 4096

static arena *json_arena; /* see the header comment */
static int json_oom;

static void *json_malloc(size_t n)
{
    void *p = json_arena ? arena_scratch(json_arena, n, 16) : NULL;
    if (!p)
        json_oom = 1;
    return p;
}

static void json_free(void *p)
{
    (void)p; /* scratch is given back as a whole after the load */
}

/* ---- messages ----------------------------------------------------------- */

static void msg_where(loader *ld, strbuf *b, uint32_t fi, const char *id)
{
    if (ld->name) {
        sb_str(b, ld->name);
        sb_str(b, ": ");
    }
    sb_str(b, "feature ");
    sb_uint(b, fi);
    if (id || (ld->feat_line && fi < ld->nfeat && ld->feat_line[fi])) {
        sb_str(b, " (");
        if (id) {
            sb_str(b, id);
            if (ld->feat_line && ld->feat_line[fi])
                sb_str(b, ", ");
        }
        if (ld->feat_line && fi < ld->nfeat && ld->feat_line[fi]) {
            sb_str(b, "line ");
            sb_uint(b, ld->feat_line[fi]);
            sb_str(b, ", column ");
            sb_uint(b, ld->feat_col[fi]);
        }
        sb_char(b, ')');
    }
    sb_str(b, ": ");
}

/* A feature-level problem: in strict mode the load fails, otherwise the
 * feature is skipped and reported. Returns PLX_OK to go on. */
plx_status ld_bad_feature(loader *ld, uint32_t fi, const char *id, const char *why)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    msg_where(ld, &b, fi, id);
    sb_str(&b, why);
    if (ld->e->cfg.strict)
        return eng_fail(ld->e, PLX_E_SCENE, msg);
    ld->s->skipped_features++;
    ld->e->warnings++;
    eng_log(ld->e, PLX_LOG_WARN, msg);
    return PLX_OK;
}

void ld_warn(loader *ld, uint32_t fi, const char *id, const char *why)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    msg_where(ld, &b, fi, id);
    sb_str(&b, why);
    ld->e->warnings++;
    eng_log(ld->e, PLX_LOG_WARN, msg);
}

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
    if (ld->e->cfg.strict)
        return fail_scene(ld, why);
    sb_init(&b, msg, sizeof msg);
    if (ld->name) {
        sb_str(&b, ld->name);
        sb_str(&b, ": ");
    }
    sb_str(&b, why);
    sb_str(&b, "; ignored");
    ld->e->warnings++;
    eng_log(ld->e, PLX_LOG_WARN, msg);
    return PLX_OK;
}

/* ---- parsing ------------------------------------------------------------ */

static int is_space(char c);

/* 1 when the text from off to the end holds only white space. */
static int only_space(const loader *ld, size_t off)
{
    for (; off < ld->len; off++)
        if (!is_space(ld->text[off]))
            return 0;
    return 1;
}

/* Arrays and objects open before byte off (outside strings). */
static long depth_at(const loader *ld, size_t off)
{
    size_t i;
    long depth = 0;
    int in_string = 0;
    for (i = 0; i < off && i < ld->len; i++) {
        char c = ld->text[i];
        if (in_string) {
            if (c == '\\')
                i++;
            else if (c == '"')
                in_string = 0;
        } else if (c == '"') {
            in_string = 1;
        } else if (c == '[' || c == '{') {
            depth++;
        } else if (c == ']' || c == '}') {
            depth--;
        }
    }
    return depth;
}

static plx_status parse_error(loader *ld, const char *at)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    size_t off = at && at >= ld->text ? (size_t)(at - ld->text) : 0;
    uint32_t line, col;
    int truncated = jsonscan_truncated(ld->text, ld->len), empty = only_space(ld, 0);
    /* cJSON reports the last byte when it runs off the end */
    if (off > ld->len || (truncated && off + 1 >= ld->len) || empty)
        off = ld->len;
    jsonscan_line_col(ld->text, ld->len, off, &line, &col);
    sb_init(&b, msg, sizeof msg);
    if (ld->name) {
        sb_str(&b, ld->name);
        sb_str(&b, ": ");
    }
    if (off < ld->len && (ld->text[off] == '[' || ld->text[off] == '{') &&
        depth_at(ld, off) >= CJSON_NESTING_LIMIT) {
        /* well-formed maybe, but deeper than cJSON parses */
        sb_str(&b, "JSON nested deeper than ");
        sb_uint(&b, CJSON_NESTING_LIMIT);
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
    if (off >= ld->len)
        sb_str(&b, truncated || empty ? ": the text ends early" : ": unexpected end");
    return eng_fail(ld->e, PLX_E_PARSE, msg);
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

static plx_status parse_json(loader *ld, cJSON **root)
{
    const char *end = NULL;
    cJSON_Hooks hooks;
    const plx_port *port = &ld->e->port;
    int oom;
    if (port->lock)
        port->lock(port->ctx);
    json_arena = &ld->e->mem;
    json_oom = 0;
    hooks.malloc_fn = json_malloc;
    hooks.free_fn = json_free;
    cJSON_InitHooks(&hooks);
    *root = cJSON_ParseWithLengthOpts(ld->text, ld->len, &end, 0);
    cJSON_InitHooks(NULL);
    json_arena = NULL;
    oom = json_oom;
    if (port->unlock)
        port->unlock(port->ctx);
    if (oom)
        return eng_nomem(ld->e, "parsing JSON");
    if (!*root)
        return parse_error(ld, end);
    while (end && (size_t)(end - ld->text) < ld->len && is_space(*end))
        end++;
    if (end && (size_t)(end - ld->text) < ld->len && *end != '\0')
        return parse_error(ld, end);
    return PLX_OK;
}

/* ---- top level ------------------------------------------------------------ */

/* properties.ground_image (a path, kept as written: the core reads no
 * files) and properties.ground_image_bounds (kept in scene coordinates
 * until the frame is known; place_ground_image). */
static plx_status read_ground_image(loader *ld, const cJSON *props)
{
    const cJSON *gi = cJSON_GetObjectItemCaseSensitive(props, "ground_image");
    const cJSON *gb = cJSON_GetObjectItemCaseSensitive(props, "ground_image_bounds");
    if (gi && !cJSON_IsNull(gi)) {
        size_t n = cJSON_IsString(gi) ? strlen(gi->valuestring) : 0;
        if (n == 0 || n > MAX_IMAGE_PATH) {
            plx_status st = bad_top_property(ld, "properties.ground_image must be the path of a PNG file "
                                                 "(a non-empty string of at most 4096 bytes)");
            if (st != PLX_OK)
                return st;
        } else {
            char *path = arena_alloc(&ld->e->mem, PLX_PART_SCENE, n + 1, 1);
            if (!path)
                return eng_nomem(ld->e, "loading the scene");
            memcpy(path, gi->valuestring, n + 1);
            ld->s->ground_image = path;
        }
    }
    if (gb && !cJSON_IsNull(gb)) {
        double v[4];
        int i, ok = cJSON_IsArray(gb) && cJSON_GetArraySize(gb) == 4;
        for (i = 0; ok && i < 4; i++) {
            const cJSON *it = cJSON_GetArrayItem(gb, i);
            ok = cJSON_IsNumber(it) && isfinite(it->valuedouble);
            v[i] = ok ? it->valuedouble : 0.0;
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
            b[i] = (b[i] - ld->lon0) * 111320.0 * ld->coslat;
            b[i + 1] = (b[i + 1] - ld->lat0) * 110540.0;
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
 * properties.crs (that object, or the name as a string); NULL if none. */
static const char *crs_name(const cJSON *crs)
{
    const cJSON *name;
    if (cJSON_IsString(crs))
        return crs->valuestring;
    name = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(crs, "properties"), "name");
    return cJSON_IsString(name) ? name->valuestring : NULL;
}

/* 1 when the CRS names WGS84 lon/lat (EPSG:4326, OGC CRS84). */
static int crs_is_lonlat(const char *name)
{
    size_t n = strlen(name);
    return strstr(name, "CRS84") != NULL || (n >= 5 && strcmp(name + n - 5, ":4326") == 0);
}

/* Keeps the scene's CRS (copied into the scene) and reads a projected one
 * as metres. */
static plx_status read_crs(loader *ld, const cJSON *root, const cJSON *props)
{
    const cJSON *c = cJSON_GetObjectItemCaseSensitive(root, "crs");
    const char *name = c ? crs_name(c) : NULL;
    char *copy;
    size_t n;
    if (!name && cJSON_IsObject(props))
        name = crs_name(cJSON_GetObjectItemCaseSensitive(props, "crs"));
    if (!name || !*name)
        return PLX_OK;
    n = strlen(name);
    if (n > 1000)
        return bad_top_property(ld, "the crs name is longer than 1000 bytes");
    copy = arena_alloc(&ld->e->mem, PLX_PART_SCENE, n + 1, 1);
    if (!copy)
        return eng_nomem(ld->e, "keeping the scene's crs");
    memcpy(copy, name, n + 1);
    ld->s->crs = copy;
    if (!crs_is_lonlat(name))
        ld->metres = 1;
    return PLX_OK;
}

static plx_status read_collection(loader *ld, cJSON *root, cJSON **features)
{
    cJSON *type, *props;
    if (!cJSON_IsObject(root))
        return fail_scene(ld, "the top-level value is not a JSON object (expected a GeoJSON FeatureCollection)");
    type = cJSON_GetObjectItemCaseSensitive(root, "type");
    if (!cJSON_IsString(type) || strcmp(type->valuestring, "FeatureCollection") != 0)
        return fail_scene(ld, "the top-level object is not a FeatureCollection (\"type\" must be \"FeatureCollection\")");
    *features = cJSON_GetObjectItemCaseSensitive(root, "features");
    if (!cJSON_IsArray(*features))
        return fail_scene(ld, "the FeatureCollection has no \"features\" array");
    props = cJSON_GetObjectItemCaseSensitive(root, "properties");
    ld->metres = 0;
    ld->s->ground_albedo = DEFAULT_GROUND_ALBEDO;
    {
        plx_status st = read_crs(ld, root, props);
        if (st != PLX_OK)
            return st;
    }
    if (cJSON_IsObject(props)) {
        cJSON *units = cJSON_GetObjectItemCaseSensitive(props, "units");
        cJSON *ga = cJSON_GetObjectItemCaseSensitive(props, "ground_albedo");
        if (units) {
            if (cJSON_IsString(units) && strcmp(units->valuestring, "m") == 0)
                ld->metres = 1;
            else
                return fail_scene(ld, "properties.units must be \"m\" (metres) when given; leave it out for WGS84 lon/lat");
        }
        if (ga) {
            double v;
            if (ld_number(ga, &v) != 1 || !(v >= 0.0 && v <= 1.0))
                return fail_scene(ld, "properties.ground_albedo must be a number from 0 to 1");
            ld->s->ground_albedo = v;
        }
        return read_ground_image(ld, props);
    }
    return PLX_OK;
}

/* ---- numbers in properties ------------------------------------------------ */

/* Parses "12", "12.5", "-3e2", "12.5 m", "12m" (surrounding spaces allowed).
 * Returns 1 and the value, or 0 when the text is anything else. */
static int parse_number_text(const char *s, double *out)
{
    double mant = 0.0;
    int digits = 0, exp10 = 0, neg = 0, eneg = 0, e = 0, edigits = 0;
    while (is_space(*s))
        s++;
    if (*s == '+' || *s == '-')
        neg = (*s++ == '-');
    /* digits past the 18th only scale the value (they are below its
     * precision), so a long mantissa cannot overflow to inf */
    for (; *s >= '0' && *s <= '9'; s++, digits = 1) {
        if (mant < 1e18)
            mant = mant * 10.0 + (*s - '0');
        else if (exp10 < 10000)
            exp10++;
    }
    if (*s == '.') {
        for (s++; *s >= '0' && *s <= '9'; s++, digits = 1) {
            if (mant < 1e18 && exp10 > -10000) {
                mant = mant * 10.0 + (*s - '0');
                exp10--;
            }
        }
    }
    if (digits == 0)
        return 0;
    if (*s == 'e' || *s == 'E') {
        s++;
        if (*s == '+' || *s == '-')
            eneg = (*s++ == '-');
        for (; *s >= '0' && *s <= '9'; s++, edigits = 1)
            if (e < 10000)
                e = e * 10 + (*s - '0');
        if (edigits == 0)
            return 0;
        exp10 += eneg ? -e : e;
    }
    while (is_space(*s))
        s++;
    if (*s == 'm') {
        s++;
        while (is_space(*s))
            s++;
    }
    if (*s != '\0')
        return 0;
    if (mant == 0.0)
        exp10 = 0; /* "0e99999" is 0, not 0 * inf */
    if (exp10 < 0)
        mant /= pow(10.0, -exp10);
    else if (exp10 > 0)
        mant *= pow(10.0, exp10);
    *out = neg ? -mant : mant;
    return 1;
}

/* 1: a number (JSON number or numeric string), 0: absent/null, -1: other. */
int ld_number(const cJSON *item, double *out)
{
    if (!item || cJSON_IsNull(item))
        return 0;
    if (cJSON_IsNumber(item)) {
        *out = item->valuedouble;
        return 1;
    }
    if (cJSON_IsString(item) && parse_number_text(item->valuestring, out))
        return 1;
    return -1;
}

/* A numeric property: 1 found, 0 absent; a value of the wrong kind is
 * ignored with a warning (SPEC §1) and reads as absent. */
int ld_prop_number(loader *ld, uint32_t fi, const char *id, const cJSON *props,
                   const char *key, double *out)
{
    const cJSON *item = props ? cJSON_GetObjectItemCaseSensitive(props, key) : NULL;
    int r = ld_number(item, out);
    if (r == -1) {
        char why[200];
        strbuf b;
        sb_init(&b, why, sizeof why);
        sb_str(&b, "property \"");
        sb_str(&b, key);
        sb_str(&b, "\" is not a number");
        if (cJSON_IsString(item)) {
            sb_str(&b, " (\"");
            sb_strn(&b, item->valuestring, 40);
            sb_str(&b, "\")");
        }
        sb_str(&b, "; ignored, the default applies");
        ld_warn(ld, fi, id, why);
        return 0;
    }
    return r;
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
static plx_status height_stats(plx_engine *e, scene *s)
{
    arena_mark m = arena_get_mark(&e->mem);
    double *h;
    uint32_t i, n = s->nbld;
    if (n == 0)
        return PLX_OK;
    h = arena_scratch(&e->mem, arena_mul(n, sizeof *h), 8);
    if (!h)
        return eng_nomem(e, "computing height statistics");
    for (i = 0; i < n; i++)
        h[i] = s->bld[i].height;
    qsort(h, n, sizeof *h, cmp_double);
    s->height_min = h[0];
    s->height_max = h[n - 1];
    s->height_median = n % 2 ? h[n / 2] : 0.5 * (h[n / 2 - 1] + h[n / 2]);
    arena_release(&e->mem, &m);
    return PLX_OK;
}

static plx_status load(plx_engine *e, loader *ld)
{
    cJSON *root = NULL, *features = NULL;
    plx_status st;
    scene *s = arena_calloc(&e->mem, PLX_PART_SCENE, 1, sizeof *s, 16);
    if (!s)
        return eng_nomem(e, "loading the scene");
    ld->s = s;
    st = parse_json(ld, &root);
    if (st != PLX_OK)
        return st;
    st = read_collection(ld, root, &features);
    if (st != PLX_OK)
        return st;
    ld->nfeat = (uint32_t)cJSON_GetArraySize(features);
    ld->feat_line = arena_scratch(&e->mem, arena_mul(ld->nfeat + 1u, sizeof(uint32_t)), 4);
    ld->feat_col = arena_scratch(&e->mem, arena_mul(ld->nfeat + 1u, sizeof(uint32_t)), 4);
    if (!ld->feat_line || !ld->feat_col)
        return eng_nomem(e, "indexing feature lines");
    jsonscan_feature_lines(ld->text, ld->len, ld->feat_line, ld->feat_col, ld->nfeat);
    st = ld_features(ld, features);
    if (st != PLX_OK)
        return st;
    finish_info(s);
    st = place_ground_image(ld);
    if (st != PLX_OK)
        return st;
    st = height_stats(e, s);
    if (st != PLX_OK)
        return st;
    st = ld_drop_buried_lamps(ld);
    if (st != PLX_OK)
        return st;
    st = blocks_build(&e->mem, s, BLOCK_TOLERANCE);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "grouping buildings into blocks");
    if (st != PLX_OK)
        return eng_fail(e, st, "grouping buildings into blocks failed");
    e->sc = s;
    return PLX_OK;
}

static void drop_scene(plx_engine *e)
{
    e->sc = NULL;
    e->pd = NULL;
    e->vis_poly = NULL;
    e->vis_ids = NULL;
    e->lt = NULL;
    e->lit_last = NULL;
    e->rd = NULL;
    e->ph = NULL;
    e->lightmap_cell = 0.0;
    e->warnings = 0;
    eng_clear_error(e);
    e->mem.lo = e->base.lo;
    {
        size_t i;
        for (i = 0; i < PLX_PART_COUNT; i++)
            if (i != PLX_PART_SCRATCH)
                e->mem.used[i] = e->base.used[i];
    }
}

/* Loads text that may itself sit in scratch memory; gives back all scratch
 * memory taken after entry. */
static plx_status load_text(plx_engine *e, const char *text, size_t len, const char *name)
{
    loader ld;
    arena_mark m = arena_get_mark(&e->mem);
    plx_status st;
    uint64_t t0 = eng_clock(e);
    memset(&ld, 0, sizeof ld);
    ld.e = e;
    ld.name = name;
    ld.text = text ? text : "";
    ld.len = len;
    st = load(e, &ld);
    if (st != PLX_OK) {
        arena_release(&e->mem, &m);
        e->sc = NULL;
        return st;
    }
    e->mem.hi = m.hi;
    e->mem.used[PLX_PART_SCRATCH] = m.used[PLX_PART_SCRATCH];
    e->sc->load_ns = eng_clock(e) - t0;
    eng_check_scene(e->sc);
    return PLX_OK;
}

plx_status plx_load_geojson(plx_engine *e, const char *text, size_t len, const char *name)
{
    if (!eng_ok(e))
        return PLX_E_INVALID;
    drop_scene(e);
    if (!text && len)
        return eng_fail(e, PLX_E_INVALID, "plx_load_geojson: text is NULL");
    return load_text(e, text, len, name);
}

plx_status plx_load_file(plx_engine *e, const char *path)
{
    char why[256];
    size_t size = 0;
    char *buf;
    plx_status st;
    arena_mark m;
    strbuf b;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    drop_scene(e);
    if (!path)
        return eng_fail(e, PLX_E_INVALID, "plx_load_file: path is NULL");
    if (!e->port.file_size || !e->port.file_read)
        return eng_fail(e, PLX_E_UNSUPPORTED, "plx_load_file: this engine's port has no file system; use plx_load_geojson");
    why[0] = '\0';
    sb_init(&b, e->err, sizeof e->err);
    if (e->port.file_size(e->port.ctx, path, &size, why, sizeof why) != 0) {
        sb_str(&b, path);
        sb_str(&b, ": ");
        sb_str(&b, why);
        return PLX_E_IO;
    }
    m = arena_get_mark(&e->mem);
    buf = arena_scratch(&e->mem, size + 1, 16);
    if (!buf)
        return eng_nomem(e, "reading the scene file");
    if (e->port.file_read(e->port.ctx, path, buf, size, why, sizeof why) != 0) {
        arena_release(&e->mem, &m);
        sb_str(&b, path);
        sb_str(&b, ": ");
        sb_str(&b, why);
        return PLX_E_IO;
    }
    buf[size] = '\0';
    st = load_text(e, buf, size, path);
    e->mem.hi = m.hi;
    e->mem.used[PLX_PART_SCRATCH] = m.used[PLX_PART_SCRATCH];
    return st;
}
