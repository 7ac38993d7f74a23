/* Camera paths for polarlux walk (README "Walking through a city"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cjson/cJSON.h>

#include "cli.h"
#include "points.h"
#include "port.h"
#include "walk_path.h"

#define EYE_HEIGHT 1.7   /* m, for positions without a height */
#define LOOK_AHEAD 10.0  /* m along the path */

static int lonlat_range(const cJSON *coords)
{
    const cJSON *pos;
    cJSON_ArrayForEach(pos, coords) {
        double x = cJSON_GetArrayItem(pos, 0) ? cJSON_GetArrayItem(pos, 0)->valuedouble : 1e9;
        double y = cJSON_GetArrayItem(pos, 1) ? cJSON_GetArrayItem(pos, 1)->valuedouble : 1e9;
        if (!(x >= -180 && x <= 180 && y >= -90 && y <= 90))
            return 0;
    }
    return 1;
}

/* Whether a position's first two members are numbers (else read_positions
 * says what is wrong with it). */
static int two_numbers(const cJSON *pos)
{
    return cJSON_IsNumber(cJSON_GetArrayItem(pos, 0)) && cJSON_IsNumber(cJSON_GetArrayItem(pos, 1));
}

/* The first position within lon/lat range (-180..180, -90..90), and the
 * first one outside it; -1 for none. */
static int lonlat_at(const cJSON *coords, int want)
{
    const cJSON *pos;
    int k = 0;
    cJSON_ArrayForEach(pos, coords) {
        const cJSON *x = cJSON_GetArrayItem(pos, 0), *y = cJSON_GetArrayItem(pos, 1);
        int in = two_numbers(pos) && x->valuedouble >= -180 && x->valuedouble <= 180 && y->valuedouble >= -90 &&
                 y->valuedouble <= 90;
        if (in == want)
            return k;
        k++;
    }
    return -1;
}

static int first_lonlat(const cJSON *coords)
{
    return lonlat_at(coords, 1);
}

static int first_not_lonlat(const cJSON *coords)
{
    return lonlat_at(coords, 0);
}

/* Reads n positions [x, y(, z)] into out (3 per position); eyes must be
 * above the ground, targets may lie on it (an aerial camera looking down).
 * The positions in their list's order (cJSON_GetArrayItem walks the list
 * from its start: a path of 160,000 positions took 48 s). */
static int read_positions(const cJSON *coords, int project, const plx_scene_info *si, double *out, int n,
                          int eyes, char *why, size_t whylen)
{
    double coslat = cos(si->lat0 * 3.14159265358979323846 / 180.0);
    const cJSON *pos;
    int k = 0;
    cJSON_ArrayForEach(pos, coords) {
        const cJSON *x = cJSON_GetArrayItem(pos, 0), *y = cJSON_GetArrayItem(pos, 1), *z = cJSON_GetArrayItem(pos, 2);
        if (!cJSON_IsNumber(x) || !cJSON_IsNumber(y) || (z && !cJSON_IsNumber(z)) || !isfinite(x->valuedouble) ||
            !isfinite(y->valuedouble) || (z && !isfinite(z->valuedouble)) || cJSON_GetArraySize(pos) > 3) {
            snprintf(why, whylen, "position %d is not [x, y] or [x, y, z] of finite numbers", k);
            return -1;
        }
        out[3 * k] = x->valuedouble;
        out[3 * k + 1] = y->valuedouble;
        out[3 * k + 2] = z ? z->valuedouble : EYE_HEIGHT;
        if (project) {
            out[3 * k] = (out[3 * k] - si->lon0) * 111320.0 * coslat;
            out[3 * k + 1] = (out[3 * k + 1] - si->lat0) * 110540.0;
        }
        if (fabs(out[3 * k]) > CLI_MAX_COORD || fabs(out[3 * k + 1]) > CLI_MAX_COORD ||
            fabs(out[3 * k + 2]) > CLI_MAX_COORD) {
            snprintf(why, whylen, "position %d (%g, %g, %g) is more than 1e7 m from the %s", k, x->valuedouble,
                     y->valuedouble, out[3 * k + 2],
                     project ? "scene's origin (read as lon/lat, as the scene is; a path in metres says "
                               "properties.units \"m\")" : "origin");
            return -1;
        }
        if (eyes && !(out[3 * k + 2] > 0)) {
            snprintf(why, whylen, "position %d: the eye must be above the ground (z > 0)", k);
            return -1;
        }
        if (++k == n)
            break;
    }
    return 0;
}

static const cJSON *first_line(const cJSON *root, const cJSON **props)
{
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(root, "type"), *ft;
    *props = NULL;
    if (cJSON_IsString(type) && strcmp(type->valuestring, "LineString") == 0) {
        /* a bare LineString's own "properties" (a foreign member in
         * GeoJSON) count as a Feature's would: units already did */
        *props = cJSON_GetObjectItemCaseSensitive(root, "properties");
        return root;
    }
    if (cJSON_IsString(type) && strcmp(type->valuestring, "Feature") == 0) {
        const cJSON *g = cJSON_GetObjectItemCaseSensitive(root, "geometry");
        *props = cJSON_GetObjectItemCaseSensitive(root, "properties");
        return first_line(g, &ft) ? g : NULL;
    }
    cJSON_ArrayForEach(ft, cJSON_GetObjectItemCaseSensitive(root, "features")) {
        const cJSON *p, *g = first_line(ft, &p);
        if (g) {
            *props = p;
            return g;
        }
    }
    return NULL;
}

/* properties.units = "m": the path is in local metres (as for scenes). */
static int metres_props(const cJSON *props)
{
    const cJSON *u = cJSON_GetObjectItemCaseSensitive(props, "units");
    return cJSON_IsString(u) && strcmp(u->valuestring, "m") == 0;
}

static int metres(const cJSON *root)
{
    return root && metres_props(cJSON_GetObjectItemCaseSensitive(root, "properties"));
}

/* properties.units given and not "m" (route and the scene loader refuse
 * it; walk read such a path as metres, or projected it, without a word). */
static int other_units(const cJSON *props)
{
    const cJSON *u = cJSON_GetObjectItemCaseSensitive(props, "units");
    return u && !metres_props(props);
}

/* No keyframe looks at its own eye (the camera would have no direction:
 * render refuses such a camera; walk looked 1 m east). */
static int check_targets(const walk_path *wp, int n, char *why, size_t whylen)
{
    int k;
    for (k = 0; k < n; k++) {
        const double *p = &wp->eye[3 * k], *t = &wp->target[3 * k];
        if (p[0] == t[0] && p[1] == t[1] && p[2] == t[2]) {
            snprintf(why, whylen, "properties.targets: position %d's target is its eye (%g, %g, %g): the camera "
                     "would look nowhere", k, p[0], p[1], p[2]);
            return -1;
        }
    }
    return 0;
}

static int parse(const cJSON *root, plx_engine *e, walk_path *wp, char *why, size_t whylen)
{
    const cJSON *props, *line = first_line(root, &props), *coords, *targets;
    plx_scene_info si;
    int n, project, k;
    if (!line) {
        snprintf(why, whylen, "no LineString (a Feature, a FeatureCollection or a bare geometry)");
        return -1;
    }
    if (other_units(cJSON_GetObjectItemCaseSensitive(root, "properties")) || other_units(props)) {
        snprintf(why, whylen, "properties.units must be \"m\" when given (positions in local metres; without "
                 "it, lon/lat on a lon/lat scene)");
        return -1;
    }
    coords = cJSON_GetObjectItemCaseSensitive(line, "coordinates");
    n = cJSON_GetArraySize(coords);
    if (!cJSON_IsArray(coords) || n < 2) {
        snprintf(why, whylen, "the LineString needs at least 2 positions");
        return -1;
    }
    plx_scene_info_get(e, &si);
    project = si.lonlat && lonlat_range(coords) && !metres(root) && !metres(props ? root : NULL);
    if (props && metres_props(props))
        project = 0;
    /* a lon/lat scene, a path not declared in metres, some positions lon/lat
     * and some not: a typo, not a path in metres (it was read as metres) */
    if (si.lonlat && !project && !metres(root) && !(props && metres_props(props)) &&
        (k = first_lonlat(coords)) >= 0) {
        snprintf(why, whylen, "position %d is lon/lat (the scene's coordinates) but position %d is not: give "
                 "every position in lon/lat, or all in local metres with properties.units \"m\"", k,
                 first_not_lonlat(coords));
        return -1;
    }
    wp->n = (uint32_t)n;
    wp->eye = malloc(sizeof(double) * 3 * (size_t)n);
    targets = cJSON_GetObjectItemCaseSensitive(props, "targets");
    if (cJSON_IsNull(targets)) /* null: none given, as GeoJSON writes an absent member (the eye looks ahead) */
        targets = NULL;
    if (targets && (!cJSON_IsArray(targets) || cJSON_GetArraySize(targets) != n)) {
        snprintf(why, whylen, "properties.targets must hold one [x, y] or [x, y, z] per position (%d)", n);
        return -1;
    }
    if (targets)
        wp->target = malloc(sizeof(double) * 3 * (size_t)n);
    if (!wp->eye || (targets && !wp->target)) {
        snprintf(why, whylen, "out of memory");
        return -1;
    }
    if (read_positions(coords, project, &si, wp->eye, n, 1, why, whylen) != 0)
        return -1;
    /* positions in lon/lat: so are the targets (a latitude of 95 was
     * projected far north, and render refused the camera walk wrote) */
    if (targets && project && (k = first_not_lonlat(targets)) >= 0 && two_numbers(cJSON_GetArrayItem(targets, k))) {
        snprintf(why, whylen, "properties.targets: position %d is not lon/lat (-180..180, -90..90) and the "
                 "path's positions are: give the targets in the positions' coordinates", k);
        return -1;
    }
    if (targets && read_positions(targets, project, &si, wp->target, n, 0, why, whylen) != 0) {
        char inner[320];
        snprintf(inner, sizeof inner, "%s", why);
        snprintf(why, whylen, "properties.targets: %.200s", inner);
        return -1;
    }
    return targets ? check_targets(wp, n, why, whylen) : 0;
}

/* Whether feature ft's geometry is a LineString or a MultiLineString. */
static int has_lines(const cJSON *ft)
{
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(ft, "geometry"), "type");
    return cJSON_IsString(t) && (strcmp(t->valuestring, "LineString") == 0 ||
                                 strcmp(t->valuestring, "MultiLineString") == 0);
}

/* The line features of root: 1 for a bare LineString or a Feature's, a
 * collection's features with a LineString or a MultiLineString (the walk
 * follows the first LineString). */
static uint32_t count_lines(const cJSON *root)
{
    const cJSON *ft, *props;
    uint32_t n = 0;
    if (!cJSON_GetObjectItemCaseSensitive(root, "features"))
        return first_line(root, &props) ? 1 : 0;
    cJSON_ArrayForEach(ft, cJSON_GetObjectItemCaseSensitive(root, "features")) n += has_lines(ft);
    return n;
}

int walk_path_read(const char *path, plx_engine *e, walk_path *wp, char *err, size_t errlen)
{
    size_t len;
    char why[300];
    char *text;
    cJSON *root;
    int rc;
    memset(wp, 0, sizeof *wp);
    text = cli_read_input(path, &len, err, errlen);
    if (!text)
        return -1;
    path = cli_input_name(path);
    root = cli_json_parse(path, text, len, err, errlen);
    free(text);
    if (!root)
        return -1;
    rc = parse(root, e, wp, why, sizeof why);
    wp->lines = count_lines(root);
    cJSON_Delete(root);
    if (rc != 0) {
        snprintf(err, errlen, "%s: %s", path, why);
        walk_path_free(wp);
        return -1;
    }
    return 0;
}

void walk_path_free(walk_path *wp)
{
    free(wp->eye);
    free(wp->target);
    memset(wp, 0, sizeof *wp);
}

/* A segment's length under this moves the eye too little to look along
 * (m). */
#define WALK_FLAT 1e-6

static double dist3(const double *a, const double *b)
{
    return hypot(hypot(b[0] - a[0], b[1] - a[1]), b[2] - a[2]);
}

/* Segment k's (1 .. n - 1) share of the walk: the eye's metres, or, where
 * the eye stays put and targets turn the view (a pan on the spot: it gave
 * one frame, its targets unused), the target's metres. */
static double seg_len(const walk_path *wp, uint32_t k)
{
    double d = dist3(wp->eye + 3 * (k - 1), wp->eye + 3 * k);
    if (!(d > WALK_FLAT) && wp->target)
        return dist3(wp->target + 3 * (k - 1), wp->target + 3 * k);
    return d;
}

double walk_path_length(const walk_path *wp)
{
    double L = 0;
    uint32_t k;
    for (k = 1; k < wp->n; k++)
        L += seg_len(wp, k);
    return L;
}

/* The segment k (1 .. n - 1, from position k - 1 to k) of the path
 * holding arc length s (seg_len's), the last one beyond the end; *acc the
 * length before it, *seg its own. */
static uint32_t segment_at(const walk_path *wp, double s, double *acc, double *seg)
{
    uint32_t k;
    *acc = 0.0;
    for (k = 1;; k++) {
        *seg = seg_len(wp, k);
        if (!(s > *acc + *seg) || k + 1 >= wp->n)
            return k;
        *acc += *seg;
    }
}

/* The point at arc length s (clamped to the path; beyond its end it goes on
 * along the last segment), of the eye polyline or, with the same
 * parameter, of the targets. */
static void at(const walk_path *wp, const double *pts, double s, double out[3])
{
    double acc, seg, t;
    uint32_t k = segment_at(wp, s, &acc, &seg);
    int c;
    t = seg > 0 ? (s - acc) / seg : 0;
    if (t < 0)
        t = 0;
    if (pts != wp->eye && t > 1)
        t = 1;
    for (c = 0; c < 3; c++)
        out[c] = pts[3 * (k - 1) + c] + t * (pts[3 * k + c] - pts[3 * (k - 1) + c]);
}

/* Segment k's (1 .. n - 1) horizontal direction, unit; 0 when it hardly
 * moves horizontally. */
static int seg_dir(const walk_path *wp, uint32_t k, double d[2])
{
    const double *a = wp->eye + 3 * (k - 1), *b = wp->eye + 3 * k;
    double dx = b[0] - a[0], dy = b[1] - a[1], h = hypot(dx, dy);
    if (!(h > WALK_FLAT))
        return 0;
    d[0] = dx / h;
    d[1] = dy / h;
    return 1;
}

/* The horizontal direction the eye walks at arc length s: its segment's,
 * else the next segment's that moves horizontally, else the last one's
 * before it; 0 when none does. */
static int walk_dir(const walk_path *wp, double s, double d[2])
{
    double acc, seg;
    uint32_t k, here = segment_at(wp, s, &acc, &seg);
    for (k = here; k < wp->n; k++)
        if (seg_dir(wp, k, d))
            return 1;
    for (k = here; k-- > 1;)
        if (seg_dir(wp, k, d))
            return 1;
    return 0;
}

int walk_path_moves(const walk_path *wp)
{
    double d[2];
    return wp->target != NULL || walk_dir(wp, 0.0, d);
}

void walk_path_camera(const walk_path *wp, double s, double eye[3], double target[3])
{
    double d[2], h;
    at(wp, wp->eye, s, eye);
    if (wp->target) {
        at(wp, wp->target, s, target);
        if (hypot(hypot(target[0] - eye[0], target[1] - eye[1]), target[2] - eye[2]) > WALK_FLAT)
            return;
    } else {
        at(wp, wp->eye, s + LOOK_AHEAD, target);
        h = hypot(target[0] - eye[0], target[1] - eye[1]);
        target[2] = eye[2] - wp->pitch_tan * h;
        if (h > WALK_FLAT)
            return;
    }
    /* no direction there (a vertical or repeated stretch, the point ahead
     * back at the eye, a keyframe's target crossing its eye): along the
     * walk, or east when the path never moves horizontally (said once) */
    target[2] = eye[2] - wp->pitch_tan * LOOK_AHEAD;
    if (walk_dir(wp, s, d)) {
        target[0] = eye[0] + LOOK_AHEAD * d[0];
        target[1] = eye[1] + LOOK_AHEAD * d[1];
    } else {
        target[0] = eye[0] + LOOK_AHEAD;
        target[1] = eye[1];
    }
}
