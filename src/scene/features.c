/* features: reads buildings and lamps out of the FeatureCollection's text,
 * one feature at a time, in place (SPEC §1). Pass 1 counts, finds the
 * coordinate frame and where each feature starts (for messages); pass 2
 * fills the scene, checking every feature and skipping (or, strict, failing
 * on) bad ones. Values are read as cJSON read them before: a member is the
 * first with its key, and the children of an object are its members'
 * values. */
#include <string.h>
#include <math.h>

#include "scene/features.h"
#include "base/geom.h"
#include "scene/photometry.h"
#include "base/lonlat.h"

#define MAX_COORD 1.0e7
#define MAX_HEIGHT 1000.0
#define MAX_RADIUS 1.0e5
#define DEFAULT_HEIGHT 12.0
#define LEVEL_HEIGHT 3.0
#define DEFAULT_ALBEDO 0.35
#define DEFAULT_LAMP_Z 6.0
#define DEFAULT_INTENSITY 1000.0
#define DEFAULT_RADIUS 30.0
#define HOLE_PAIR_CHECK_LIMIT 4000000.0

static const float default_color[3] = { 1.0f, 0.62f, 0.28f };

typedef struct counts {
    size_t positions, rings, parts, lamps;
    double box[4];     /* of all coordinates */
    int any;
    int lonlat_ok;     /* every coordinate within lon/lat range */
    int feat_out;      /* the feature being counted has a coordinate outside it */
    uint32_t first_out; /* the first feature that has (when !lonlat_ok) */
    uint32_t feats, feats_in; /* features with coordinates; those wholly within the range */
} counts;

/* The members of a feature that the passes look at, found once. */
typedef struct feat {
    jv f, props, geom, type, coords;
} feat;

static void feat_find(const loader *ld, jv f, feat *m)
{
    m->f = f;
    m->props = ld_get(ld, f, "properties");
    m->geom = ld_get(ld, f, "geometry");
    m->type = ld_get(ld, m->geom, "type");
    if (ld_kind(ld, m->type) != JS_STRING)
        m->type = JV_NONE;
    m->coords = ld_get(ld, m->geom, "coordinates");
}

static int is_lamp(const loader *ld, jv props)
{
    jv lamp = ld_get(ld, props, "lamp");
    if (ld_kind(ld, lamp) == JS_TRUE)
        return 1;
    return ld_str_is(ld, ld_get(ld, props, "highway"), "street_lamp");
}

/* ---- pass 1 --------------------------------------------------------------- */

static void count_position(const loader *ld, counts *c, jv pos)
{
    jv x = ld_item(ld, pos, 0), y = ld_item(ld, pos, 1);
    double vx, vy;
    if (ld_kind(ld, x) != JS_NUMBER || ld_kind(ld, y) != JS_NUMBER)
        return;
    vx = ld_double(ld, x);
    vy = ld_double(ld, y);
    if (!isfinite(vx) || !isfinite(vy))
        return;
    if (!c->any) {
        c->box[0] = c->box[2] = vx;
        c->box[1] = c->box[3] = vy;
        c->any = 1;
    }
    c->box[0] = fmin(c->box[0], vx);
    c->box[1] = fmin(c->box[1], vy);
    c->box[2] = fmax(c->box[2], vx);
    c->box[3] = fmax(c->box[3], vy);
    if (vx < -180.0 || vx > 180.0 || vy < -90.0 || vy > 90.0)
        c->feat_out = 1;
}

static void count_polygon(const loader *ld, counts *c, jv poly)
{
    jv ring, pos;
    c->parts++;
    LD_EACH(ld, poly, ring) {
        c->rings++;
        LD_EACH(ld, ring, pos) {
            c->positions++;
            count_position(ld, c, pos);
        }
    }
}

/* Where the feature at f starts for messages: the first byte after the
 * '[' or ',' before it that is not a space, tab or line end. */
static size_t feature_start(const loader *ld, jv f)
{
    size_t p = f;
    while (p > 0 && ld->text[p - 1] != ',' && ld->text[p - 1] != '[')
        p--;
    while (p < f && (ld->text[p] == ' ' || ld->text[p] == '\t' || ld->text[p] == '\r' || ld->text[p] == '\n'))
        p++;
    return p;
}

/* Line and column of every feature, counted on from the previous one. */
typedef struct liner {
    size_t off, line_start;
    uint32_t line;
} liner;

static void liner_to(const loader *ld, liner *l, size_t off, uint32_t *line, uint32_t *col)
{
    for (; l->off < off; l->off++)
        if (ld->text[l->off] == '\n') {
            l->line++;
            l->line_start = l->off + 1;
        }
    *line = l->line;
    *col = (uint32_t)(off - l->line_start + 1);
}

static void count_features(loader *ld, jv features, counts *c)
{
    jv f, part;
    uint32_t fi = 0;
    liner l = { 0, 0, 1 };
    memset(c, 0, sizeof *c);
    c->lonlat_ok = 1;
    LD_EACH(ld, features, f) {
        feat m;
        liner_to(ld, &l, feature_start(ld, f), &ld->feat_line[fi], &ld->feat_col[fi]);
        fi++;
        feat_find(ld, f, &m);
        if (m.type == JV_NONE || ld_kind(ld, m.coords) != JS_ARRAY)
            continue;
        c->feat_out = 0;
        if (ld_str_is(ld, m.type, "Polygon")) {
            count_polygon(ld, c, m.coords);
        } else if (ld_str_is(ld, m.type, "MultiPolygon")) {
            LD_EACH(ld, m.coords, part)
                count_polygon(ld, c, part);
        } else if (ld_str_is(ld, m.type, "Point") && is_lamp(ld, m.props)) {
            c->lamps++;
            count_position(ld, c, m.coords);
        } else {
            continue;
        }
        c->feats++;
        if (!c->feat_out)
            c->feats_in++;
        else if (c->lonlat_ok) {
            c->lonlat_ok = 0;
            c->first_out = fi - 1;
        }
    }
}

/* ---- ids ---------------------------------------------------------------------- */

static const char *copy_id(loader *ld, jv item)
{
    char tmp[201];
    size_t n;
    char *dst;
    strbuf b;
    if (ld_kind(ld, item) == JS_STRING) {
        n = ld_str(ld, item, tmp, sizeof tmp);
    } else if (ld_kind(ld, item) == JS_NUMBER) {
        sb_init(&b, tmp, 64);
        sb_num(&b, ld_double(ld, item), 17);
        n = strlen(tmp);
    } else {
        return NULL;
    }
    if (n > 200)
        n = 200;
    dst = arena_alloc(ld->mem, PLX_PART_SCENE, n + 1, 1);
    if (!dst)
        return NULL;
    memcpy(dst, tmp, n);
    dst[n] = '\0';
    return dst;
}

static jv id_item(const loader *ld, jv f, jv props)
{
    static const char *const keys[] = { "id", "@id", "osm_id" };
    size_t i;
    for (i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        jv it = ld_get(ld, props, keys[i]);
        if (ld_kind(ld, it) == JS_STRING || ld_kind(ld, it) == JS_NUMBER)
            return it;
    }
    return ld_get(ld, f, "id");
}

/* ---- coordinates -------------------------------------------------------------- */

/* Reads one position into p; 0 on success, else writes why. */
static int read_position(loader *ld, jv pos, vec2 *p, strbuf *why)
{
    jv x = ld_first(ld, pos), y = x != JV_NONE ? ld_next(ld, pos, x) : JV_NONE;
    double vx, vy;
    if (ld_kind(ld, pos) != JS_ARRAY || ld_kind(ld, x) != JS_NUMBER || ld_kind(ld, y) != JS_NUMBER) {
        sb_str(why, "is not a position [x, y] of numbers");
        return -1;
    }
    vx = ld_double(ld, x);
    vy = ld_double(ld, y);
    if (!isfinite(vx) || !isfinite(vy)) {
        sb_str(why, "has a non-finite number");
        return -1;
    }
    if (!ld->metres && ld->coslat != 0.0) {
        lonlat_to_local(ld->lon0, ld->lat0, ld->coslat, &vx, &vy);
    }
    if (fabs(vx) > MAX_COORD || fabs(vy) > MAX_COORD) {
        sb_str(why, "is out of range (|coordinate| > 1e7 m)");
        return -1;
    }
    p->x = vx;
    p->y = vy;
    return 0;
}

static void why_ring(strbuf *why, uint32_t ring)
{
    sb_str(why, ring == 0 ? "outer ring" : "inner ring ");
    if (ring)
        sb_uint(why, ring);
}

/* Reads, cleans and checks ring number 'ring' of a polygon into s->pts.
 * Returns PLX_OK, PLX_E_SCENE with 'why' filled, or PLX_E_NOMEM. */
static plx_status read_ring(loader *ld, jv jr, uint32_t ring, scene_ring *out, strbuf *why)
{
    scene *s = ld->s;
    vec2 *p = s->pts + s->npts;
    uint32_t n = 0, k = 0, ei, ej;
    jv pos;
    int simple;
    if (ld_kind(ld, jr) != JS_ARRAY) {
        why_ring(why, ring);
        sb_str(why, " is not an array of positions");
        return PLX_E_SCENE;
    }
    LD_EACH(ld, jr, pos) {
        vec2 v;
        if (read_position(ld, pos, &v, why) != 0) {
            char tmp[160];
            strbuf t;
            sb_init(&t, tmp, sizeof tmp);
            sb_str(&t, why->buf);
            why->len = 0;
            why->buf[0] = '\0';
            sb_str(why, "position ");
            sb_uint(why, k);
            sb_str(why, " of ");
            why_ring(why, ring);
            sb_char(why, ' ');
            sb_str(why, tmp);
            return PLX_E_SCENE;
        }
        k++;
        if (n > 0 && v.x == p[n - 1].x && v.y == p[n - 1].y)
            continue;
        p[n++] = v;
    }
    while (n > 1 && p[n - 1].x == p[0].x && p[n - 1].y == p[0].y)
        n--;
    if (n < 3) {
        why_ring(why, ring);
        sb_str(why, " has ");
        sb_uint(why, n);
        sb_str(why, n == 1 ? " distinct vertex" : " distinct vertices");
        sb_str(why, " (a ring needs at least 3)");
        return PLX_E_SCENE;
    }
    simple = geom_ring_is_simple(ld->mem, p, n, &ei, &ej);
    if (simple < 0)
        return PLX_E_NOMEM;
    if (!simple) {
        why_ring(why, ring);
        sb_str(why, " intersects itself (edges ");
        sb_uint(why, ei);
        sb_str(why, " and ");
        sb_uint(why, ej);
        sb_str(why, " meet)");
        return PLX_E_SCENE;
    }
    if ((geom_ring_area2(p, n) > 0.0) != (ring == 0)) {
        uint32_t i;
        for (i = 0; i < n / 2; i++) {
            vec2 t = p[i];
            p[i] = p[n - 1 - i];
            p[n - 1 - i] = t;
        }
    }
    out->first = s->npts;
    out->count = n;
    s->npts += n;
    return PLX_OK;
}

/* No edge of a crosses or overlaps an edge of b (touching at points is fine). */
static int rings_disjoint(const scene *s, const scene_ring *a, const scene_ring *b)
{
    uint32_t i, j;
    if ((double)a->count * b->count > HOLE_PAIR_CHECK_LIMIT)
        return 1;
    for (i = 0; i < a->count; i++) {
        vec2 a0 = s->pts[a->first + i], a1 = s->pts[a->first + (i + 1) % a->count];
        for (j = 0; j < b->count; j++) {
            vec2 b0 = s->pts[b->first + j], b1 = s->pts[b->first + (j + 1) % b->count];
            int m = geom_seg_meet(a0, a1, b0, b1);
            if (m == GEOM_SEG_CROSS || m == GEOM_SEG_OVERLAP)
                return 0;
        }
    }
    return 1;
}

/* Where the points of ring a lie relative to ring b, given that no edges of
 * the two cross or overlap (rings_disjoint): bit SIDE_IN when some point of a
 * is strictly inside b, SIDE_OUT when some is strictly outside. Each edge of a
 * is tested at its start vertex and at the midpoint of every piece between
 * the vertices of b lying on it: with no crossings, a piece's interior does
 * not meet b, so its midpoint tells on which side the whole piece is. */
#define SIDE_IN 1
#define SIDE_OUT 2

static int side_bit(int where)
{
    return where == GEOM_INSIDE ? SIDE_IN : where == GEOM_OUTSIDE ? SIDE_OUT : 0;
}

static int ring_sides(const scene *s, const scene_ring *a, const scene_ring *b)
{
    const vec2 *q = s->pts + b->first;
    uint32_t i, j;
    int sides = 0;
    if ((double)a->count * b->count > HOLE_PAIR_CHECK_LIMIT) {
        for (i = 0; i < a->count && !sides; i++) /* too large: the first vertex off b */
            sides = side_bit(geom_point_in_ring(s->pts[a->first + i], q, b->count));
        return sides;
    }
    for (i = 0; i < a->count; i++) {
        vec2 p0 = s->pts[a->first + i], p1 = s->pts[a->first + (i + 1) % a->count], cur = p0;
        int along_x = fabs(p1.x - p0.x) >= fabs(p1.y - p0.y);
        double end = along_x ? p1.x : p1.y;
        double dir = end > (along_x ? p0.x : p0.y) ? 1.0 : -1.0;
        sides |= side_bit(geom_point_in_ring(p0, q, b->count));
        for (;;) {
            /* the next vertex of b on the edge after cur, else the edge's end */
            vec2 next = p1, mid;
            double c = along_x ? cur.x : cur.y, best = end;
            for (j = 0; j < b->count; j++) {
                double t = along_x ? q[j].x : q[j].y;
                if ((t - c) * dir > 0.0 && (best - t) * dir > 0.0 && geom_orient(p0, p1, q[j]) == 0) {
                    best = t;
                    next = q[j];
                }
            }
            mid.x = 0.5 * cur.x + 0.5 * next.x;
            mid.y = 0.5 * cur.y + 0.5 * next.y;
            sides |= side_bit(geom_point_in_ring(mid, q, b->count));
            if (next.x == p1.x && next.y == p1.y)
                break;
            cur = next;
        }
        if (sides == (SIDE_IN | SIDE_OUT))
            break;
    }
    return sides;
}

/* Holes must lie inside the outer ring (touching it at points at most) and
 * must not cross, overlap or contain each other. */
static int check_holes(const scene *s, uint32_t first, uint32_t count, strbuf *why)
{
    const scene_ring *outer = &s->rings[first];
    uint32_t h, g;
    for (h = 1; h < count; h++) {
        const scene_ring *r = &s->rings[first + h];
        if (!rings_disjoint(s, outer, r) || ring_sides(s, r, outer) != SIDE_IN) {
            sb_str(why, "inner ring ");
            sb_uint(why, h);
            sb_str(why, " is not inside the outer ring");
            return 0;
        }
        for (g = 1; g < h; g++) {
            const scene_ring *o = &s->rings[first + g];
            if (!rings_disjoint(s, o, r) || (ring_sides(s, r, o) & SIDE_IN) ||
                (ring_sides(s, o, r) & SIDE_IN)) {
                sb_str(why, "inner rings ");
                sb_uint(why, g);
                sb_str(why, " and ");
                sb_uint(why, h);
                sb_str(why, " overlap");
                return 0;
            }
        }
    }
    return 1;
}

/* ---- buildings ------------------------------------------------------------------ */

typedef struct bprops {
    double height, min_height, albedo;
} bprops;

static plx_status read_bprops(loader *ld, uint32_t fi, const char *id, jv props,
                              bprops *bp, int *ok)
{
    char why[200];
    strbuf b;
    double levels;
    int from_levels = 0;
    sb_init(&b, why, sizeof why);
    *ok = 0;
    bp->height = DEFAULT_HEIGHT;
    bp->min_height = 0.0;
    bp->albedo = DEFAULT_ALBEDO;
    if (!ld_prop_number(ld, fi, id, props, "height", &bp->height) &&
        ld_prop_number(ld, fi, id, props, "building:levels", &levels)) {
        bp->height = levels * LEVEL_HEIGHT;
        from_levels = 1;
    }
    ld_prop_number(ld, fi, id, props, "min_height", &bp->min_height);
    ld_prop_number(ld, fi, id, props, "albedo", &bp->albedo);
    if (!isfinite(bp->height) || bp->height <= 0.0 || bp->height > MAX_HEIGHT) {
        sb_str(&b, "height ");
        sb_num(&b, bp->height, 6);
        sb_str(&b, " m");
        if (from_levels)
            sb_str(&b, " (from building:levels)");
        sb_str(&b, " is out of range (must be > 0 and <= 1000 m)");
    } else if (!isfinite(bp->min_height) || bp->min_height < 0.0) {
        sb_str(&b, "min_height ");
        sb_num(&b, bp->min_height, 6);
        sb_str(&b, " m is negative or not finite");
    } else if (bp->min_height >= bp->height) {
        sb_str(&b, "min_height ");
        sb_num(&b, bp->min_height, 6);
        sb_str(&b, " m is not below height ");
        sb_num(&b, bp->height, 6);
        sb_str(&b, " m");
        if (from_levels)
            sb_str(&b, " (from building:levels)");
        else if (ld_get(ld, props, "height") == JV_NONE)
            sb_str(&b, " (the default)");
    } else if (!isfinite(bp->albedo) || bp->albedo < 0.0 || bp->albedo > 1.0) {
        sb_str(&b, "albedo ");
        sb_num(&b, bp->albedo, 6);
        sb_str(&b, " is outside 0..1");
    } else {
        *ok = 1;
        return PLX_OK;
    }
    return ld_bad_feature(ld, fi, id, why);
}

/* Reads one polygon (outer ring + holes) as a building. On PLX_E_SCENE 'why'
 * says what is wrong and nothing was added. */
static plx_status read_polygon(loader *ld, jv poly, const bprops *bp,
                               uint32_t fi, const char *id, strbuf *why)
{
    scene *s = ld->s;
    uint32_t npts0 = s->npts, nrings0 = s->nrings, r = 0, i;
    scene_building *bd;
    jv jr;
    plx_status st;
    if (ld_kind(ld, poly) != JS_ARRAY || ld_first(ld, poly) == JV_NONE) {
        sb_str(why, "a polygon has no rings");
        return PLX_E_SCENE;
    }
    LD_EACH(ld, poly, jr) {
        st = read_ring(ld, jr, r, &s->rings[s->nrings], why);
        if (st != PLX_OK) {
            s->npts = npts0;
            s->nrings = nrings0;
            return st;
        }
        s->nrings++;
        r++;
    }
    if (r > 1 && !check_holes(s, nrings0, r, why)) {
        s->npts = npts0;
        s->nrings = nrings0;
        return PLX_E_SCENE;
    }
    bd = &s->bld[s->nbld++];
    memset(bd, 0, sizeof *bd);
    bd->ring_first = nrings0;
    bd->ring_count = r;
    bd->height = bp->height;
    bd->min_height = bp->min_height;
    bd->albedo = bp->albedo;
    bd->feature = fi;
    bd->id = id;
    bd->box[0] = bd->box[2] = s->pts[npts0].x;
    bd->box[1] = bd->box[3] = s->pts[npts0].y;
    for (i = npts0; i < npts0 + s->rings[nrings0].count; i++) {
        bd->box[0] = fmin(bd->box[0], s->pts[i].x);
        bd->box[1] = fmin(bd->box[1], s->pts[i].y);
        bd->box[2] = fmax(bd->box[2], s->pts[i].x);
        bd->box[3] = fmax(bd->box[3], s->pts[i].y);
    }
    return PLX_OK;
}

static plx_status read_building(loader *ld, const feat *m, jv props, int multi,
                                uint32_t fi, const char *id)
{
    scene *s = ld->s;
    uint32_t npts0 = s->npts, nrings0 = s->nrings, nbld0 = s->nbld;
    jv co = m->coords, part;
    char whybuf[300];
    strbuf why;
    bprops bp;
    plx_status st;
    int ok;
    st = read_bprops(ld, fi, id, props, &bp, &ok);
    if (st != PLX_OK || !ok)
        return st;
    sb_init(&why, whybuf, sizeof whybuf);
    if (ld_kind(ld, co) != JS_ARRAY) {
        sb_str(&why, "geometry has no \"coordinates\" array");
        st = PLX_E_SCENE;
    } else if (!multi) {
        st = read_polygon(ld, co, &bp, fi, id, &why);
    } else {
        uint32_t k = 0;
        st = ld_first(ld, co) != JV_NONE ? PLX_OK : PLX_E_SCENE;
        if (st != PLX_OK)
            sb_str(&why, "MultiPolygon has no polygons");
        LD_EACH(ld, co, part) {
            st = read_polygon(ld, part, &bp, fi, id, &why);
            if (st != PLX_OK) {
                char tmp[300];
                strbuf t;
                sb_init(&t, tmp, sizeof tmp);
                sb_str(&t, "polygon ");
                sb_uint(&t, k);
                sb_str(&t, ": ");
                sb_str(&t, whybuf);
                sb_init(&why, whybuf, sizeof whybuf);
                sb_str(&why, tmp);
                break;
            }
            k++;
        }
    }
    if (st == PLX_OK)
        return PLX_OK;
    s->npts = npts0;
    s->nrings = nrings0;
    s->nbld = nbld0;
    if (st == PLX_E_NOMEM)
        return eng_nomem(ld->e, "checking rings");
    return ld_bad_feature(ld, fi, id, whybuf);
}

/* ---- lamps ------------------------------------------------------------------------ */

static void read_color(loader *ld, uint32_t fi, const char *id, jv props, float c[3])
{
    jv col = ld_get(ld, props, "color"), v;
    float tmp[3];
    int k = 0;
    memcpy(c, default_color, sizeof tmp);
    if (col == JV_NONE || ld_kind(ld, col) == JS_NULL)
        return;
    if (ld_kind(ld, col) == JS_ARRAY && ld_count(ld, col) == 3) {
        LD_EACH(ld, col, v) {
            double d = ld_kind(ld, v) == JS_NUMBER ? ld_double(ld, v) : -1.0;
            if (!isfinite(d) || d < 0.0 || d > 1.0e6)
                break;
            tmp[k++] = (float)d;
        }
        if (k == 3) {
            memcpy(c, tmp, sizeof tmp);
            return;
        }
    }
    ld_warn(ld, fi, id, "property \"color\" is not [r, g, b] of numbers >= 0; ignored, the default applies");
}

/* properties.photometry (a path, kept as written: the core reads no files;
 * the table comes through plx_set_photometry), azimuth (else OSM's compass
 * "direction": azimuth = 90 - direction), tilt and dimming (SPEC §2.1).
 * Returns PLX_E_NOMEM, or PLX_OK with a reason in why for a bad value. */
static plx_status read_lamp_photometry(loader *ld, uint32_t fi, const char *id, jv props,
                                       scene_lamp *l, strbuf *why)
{
    jv ph = ld_get(ld, props, "photometry");
    size_t n = ld_str(ld, ph, NULL, 0);
    double dir;
    l->dimming = 1.0;
    if (!ld_prop_number(ld, fi, id, props, "azimuth", &l->azimuth) &&
        ld_prop_number(ld, fi, id, props, "direction", &dir))
        l->azimuth = 90.0 - dir;
    ld_prop_number(ld, fi, id, props, "tilt", &l->tilt);
    ld_prop_number(ld, fi, id, props, "dimming", &l->dimming);
    if (!(l->dimming >= 0.0 && l->dimming <= 1.0)) {
        sb_str(why, "lamp dimming ");
        sb_num(why, l->dimming, 6);
        sb_str(why, " is out of range (0 to 1)");
    } else if (!(fabs(l->azimuth) <= 1e6) || !(fabs(l->tilt) <= 180.0)) {
        sb_str(why, "lamp azimuth or tilt is out of range (|azimuth| <= 1e6, |tilt| <= 180 degrees)");
    }
    photometry_lamp_frame(l);
    if (n > 0) {
        char *dst = arena_alloc(ld->mem, PLX_PART_SCENE, n + 1, 1);
        if (!dst)
            return eng_nomem(ld->e, "copying photometry paths");
        ld_str(ld, ph, dst, n + 1);
        l->photometry = dst;
        l->intensity = 0.0;   /* dark until the table is given */
        if (ld_get(ld, props, "intensity") != JV_NONE) /* SPEC §2.1: I is dimming x the table */
            ld_warn(ld, fi, id, "property \"intensity\" is ignored: the lamp's photometry file gives its "
                    "candelas (\"dimming\" scales them)");
    } else if (ph != JV_NONE && ld_kind(ld, ph) != JS_NULL) {
        ld_warn(ld, fi, id, "property \"photometry\" is not a file path; ignored, the lamp is isotropic");
    }
    return PLX_OK;
}

static plx_status read_lamp(loader *ld, const feat *m, jv props, uint32_t fi, const char *id)
{
    scene_lamp *l = &ld->s->lamps[ld->s->nlamps];
    char whybuf[200];
    strbuf why;
    vec2 p;
    sb_init(&why, whybuf, sizeof whybuf);
    memset(l, 0, sizeof *l);
    l->z = DEFAULT_LAMP_Z;
    l->intensity = DEFAULT_INTENSITY;
    l->radius = DEFAULT_RADIUS;
    if (read_position(ld, m->coords, &p, &why) != 0) {
        char tmp[200];
        strbuf t;
        sb_init(&t, tmp, sizeof tmp);
        sb_str(&t, "the point ");
        sb_str(&t, whybuf);
        return ld_bad_feature(ld, fi, id, tmp);
    }
    ld_prop_number(ld, fi, id, props, "z", &l->z);
    ld_prop_number(ld, fi, id, props, "intensity", &l->intensity);
    ld_prop_number(ld, fi, id, props, "radius", &l->radius);
    if (!isfinite(l->z) || l->z < 0.0 || l->z > MAX_HEIGHT) {
        sb_str(&why, "lamp z ");
        sb_num(&why, l->z, 6);
        sb_str(&why, " m is out of range (0 to 1000 m)");
    } else if (!(l->intensity >= 0.0 && l->intensity <= PHOTOMETRY_MAX_CD)) {
        /* above it, every lux and the photons' sums overflowed (1e308 cd gave E_indirect inf) */
        sb_str(&why, "lamp intensity ");
        sb_num(&why, l->intensity, 6);
        sb_str(&why, " cd is negative, not finite or above 1e12 cd");
    } else if (!isfinite(l->radius) || l->radius <= 0.0 || l->radius > MAX_RADIUS) {
        sb_str(&why, "lamp radius ");
        sb_num(&why, l->radius, 6);
        sb_str(&why, " m is out of range (> 0 and <= 100000 m)");
    }
    if (why.len == 0 && read_lamp_photometry(ld, fi, id, props, l, &why) != PLX_OK)
        return PLX_E_NOMEM;
    if (why.len)
        return ld_bad_feature(ld, fi, id, whybuf);
    if (l->intensity == 0.0 && !l->photometry)
        ld_warn(ld, fi, id, "lamp intensity is 0 cd: it gives no light");
    read_color(ld, fi, id, props, l->color);
    l->x = p.x;
    l->y = p.y;
    l->feature = fi;
    l->id = id;
    ld->s->nlamps++;
    return PLX_OK;
}

/* ---- pass 2 ------------------------------------------------------------------------- */

static plx_status read_feature(loader *ld, jv f, uint32_t fi)
{
    feat m;
    jv props, lamp;
    const char *id = NULL;
    char why[200], type[41];
    strbuf b;
    if (ld_kind(ld, f) != JS_OBJECT)
        return ld_bad_feature(ld, fi, NULL, "is not a JSON object");
    feat_find(ld, f, &m);
    props = m.props;
    if (props != JV_NONE && ld_kind(ld, props) != JS_OBJECT && ld_kind(ld, props) != JS_NULL) {
        ld_warn(ld, fi, NULL, "\"properties\" is not an object; ignored");
        props = JV_NONE;
    }
    if (id_item(ld, f, props) != JV_NONE) {
        id = copy_id(ld, id_item(ld, f, props));
        if (!id)
            return eng_nomem(ld->e, "copying feature ids");
    }
    if (ld_kind(ld, m.geom) != JS_OBJECT)
        return ld_bad_feature(ld, fi, id, "has no geometry object");
    if (m.type == JV_NONE)
        return ld_bad_feature(ld, fi, id, "geometry has no \"type\" string");
    if (ld_str_is(ld, m.type, "Polygon"))
        return read_building(ld, &m, props, 0, fi, id);
    if (ld_str_is(ld, m.type, "MultiPolygon"))
        return read_building(ld, &m, props, 1, fi, id);
    if (ld_str_is(ld, m.type, "Point")) {
        lamp = ld_get(ld, props, "lamp");
        if (is_lamp(ld, props))
            return read_lamp(ld, &m, props, fi, id);
        if (lamp != JV_NONE && ld_kind(ld, lamp) != JS_TRUE && ld_kind(ld, lamp) != JS_FALSE &&
            ld_kind(ld, lamp) != JS_NULL)
            ld_warn(ld, fi, id, "property \"lamp\" is not true or false; ignored, the point is not a lamp");
        return PLX_OK;
    }
    ld_str(ld, m.type, type, sizeof type);
    sb_init(&b, why, sizeof why);
    sb_str(&b, "geometry type \"");
    sb_str(&b, type);
    sb_str(&b, "\" is not used in scenes (Polygon, MultiPolygon or Point)");
    return ld_bad_feature(ld, fi, id, why);
}

static plx_status set_frame(loader *ld, const counts *c)
{
    char why[400];
    strbuf b;
    if (ld->metres || !c->any)
        return PLX_OK;
    if (!c->lonlat_ok && ld->crs_lonlat) {
        /* read as metres, the file's geographic crs would place every output wrong */
        sb_init(&b, why, sizeof why);
        sb_str(&b, "coordinates exceed the lon/lat range (-180..180, -90..90), but the crs ");
        sb_str(&b, ld->s->crs);
        sb_str(&b, " names lon/lat degrees: give the crs the coordinates are in (or none, with properties.units "
                   "= \"m\", for local metres)");
        return ld_fail(ld, c->first_out, why);
    }
    if (!c->lonlat_ok) {
        sb_init(&b, why, sizeof why);
        sb_str(&b, "coordinates exceed the lon/lat range and properties.units is not given: reading them as metres "
                   "(set properties.units = \"m\" to silence this)");
        if (c->feats_in > 0) {
            sb_str(&b, "; ");
            sb_uint(&b, c->feats_in);
            sb_str(&b, " of the ");
            sb_uint(&b, c->feats);
            sb_str(&b, " features lie wholly within it: if those are lon/lat, the file mixes coordinate systems");
        }
        ld_warn(ld, c->first_out, NULL, why);
        ld->metres = 1;
        return PLX_OK;
    }
    ld->s->lonlat = 1;
    ld->lon0 = ld->s->lon0 = 0.5 * (c->box[0] + c->box[2]);
    ld->lat0 = ld->s->lat0 = 0.5 * (c->box[1] + c->box[3]);
    ld->coslat = lonlat_cos(ld->lat0);
    return PLX_OK;
}

static void *alloc_array(loader *ld, size_t n, size_t size)
{
    return arena_alloc(ld->mem, PLX_PART_SCENE, arena_mul(n ? n : 1, size), 16);
}

plx_status ld_features(loader *ld, jv features)
{
    scene *s = ld->s;
    counts c;
    jv f;
    uint32_t fi = 0;
    plx_status st;
    ld->nfeat = ld_count(ld, features);
    ld->feat_line = arena_scratch(ld->mem, arena_mul(ld->nfeat + 1u, sizeof(uint32_t)), 4);
    ld->feat_col = arena_scratch(ld->mem, arena_mul(ld->nfeat + 1u, sizeof(uint32_t)), 4);
    if (!ld->feat_line || !ld->feat_col)
        return eng_nomem(ld->e, "indexing feature lines");
    count_features(ld, features, &c);
    if (c.positions > 0xfffffff0u || c.rings > 0xfffffff0u)
        return eng_fail(ld->e, PLX_E_SCENE, "the scene has more than 4e9 vertices");
    st = set_frame(ld, &c);
    if (st != PLX_OK)
        return st;
    s->pts = alloc_array(ld, c.positions, sizeof *s->pts);
    s->rings = alloc_array(ld, c.rings, sizeof *s->rings);
    s->bld = alloc_array(ld, c.parts, sizeof *s->bld);
    s->lamps = alloc_array(ld, c.lamps, sizeof *s->lamps);
    if (!s->pts || !s->rings || !s->bld || !s->lamps)
        return eng_nomem(ld->e, "loading the scene");
    LD_EACH(ld, features, f) {
        st = read_feature(ld, f, fi++);
        if (st == PLX_OK && ld->oom)
            st = eng_nomem(ld->e, "reading a numeric property");
        if (st != PLX_OK)
            return st;
    }
    return PLX_OK;
}

/* ---- lamps inside buildings ----------------------------------------------------------- */

static int inside_footprint(const scene *s, const scene_building *b, vec2 p)
{
    uint32_t r;
    const scene_ring *outer = &s->rings[b->ring_first];
    if (geom_point_in_ring(p, s->pts + outer->first, outer->count) != GEOM_INSIDE)
        return 0;
    for (r = 1; r < b->ring_count; r++) {
        const scene_ring *h = &s->rings[b->ring_first + r];
        if (geom_point_in_ring(p, s->pts + h->first, h->count) != GEOM_OUTSIDE)
            return 0;
    }
    return 1;
}

/* The building whose solid holds the lamp, or -1. Buildings are bucketed in
 * a grid of cells so each lamp is tested against few of them. */
typedef struct bgrid {
    double x0, y0, cell;
    uint32_t nx, ny;
    uint32_t *start;  /* nx*ny+1 offsets into items */
    uint32_t *items;
} bgrid;

static void cell_range(const bgrid *g, const double *box, uint32_t r[4])
{
    double v[4];
    int i;
    v[0] = (box[0] - g->x0) / g->cell;
    v[1] = (box[1] - g->y0) / g->cell;
    v[2] = (box[2] - g->x0) / g->cell;
    v[3] = (box[3] - g->y0) / g->cell;
    for (i = 0; i < 4; i++) {
        double lim = (i % 2 == 0 ? g->nx : g->ny) - 1;
        r[i] = (uint32_t)(v[i] < 0 ? 0 : v[i] > lim ? lim : v[i]);
    }
}

static int bgrid_build(arena *a, const scene *s, bgrid *g)
{
    uint32_t i, x, y, r[4], n = s->nbld;
    double w = s->bounds[2] - s->bounds[0], h = s->bounds[3] - s->bounds[1];
    size_t total = 0, cells;
    g->x0 = s->bounds[0];
    g->y0 = s->bounds[1];
    g->cell = sqrt(w * h / (n + 1.0));
    if (!(g->cell > 0.0))
        g->cell = 1.0;
    g->nx = (uint32_t)fmin(4096.0, w / g->cell + 1.0);
    g->ny = (uint32_t)fmin(4096.0, h / g->cell + 1.0);
    g->cell = fmax(w / g->nx, h / g->ny) * 1.000001;
    cells = (size_t)g->nx * g->ny;
    g->start = arena_scratch(a, (cells + 1) * sizeof *g->start, 4);
    if (!g->start)
        return 0;
    memset(g->start, 0, (cells + 1) * sizeof *g->start);
    for (i = 0; i < n; i++) {
        cell_range(g, s->bld[i].box, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                g->start[y * g->nx + x + 1]++;
    }
    for (i = 0; i < cells; i++)
        g->start[i + 1] += g->start[i];
    total = g->start[cells];
    g->items = arena_scratch(a, (total + 1) * sizeof *g->items, 4);
    if (!g->items)
        return 0;
    for (i = 0; i < n; i++) {
        cell_range(g, s->bld[i].box, r);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                g->items[g->start[y * g->nx + x]++] = i;
    }
    for (i = (uint32_t)cells; i > 0; i--)
        g->start[i] = g->start[i - 1];
    g->start[0] = 0;
    return 1;
}

static long lamp_host(const scene *s, const bgrid *g, const scene_lamp *l)
{
    double box[4];
    uint32_t r[4], k;
    vec2 p;
    p.x = l->x;
    p.y = l->y;
    box[0] = box[2] = l->x;
    box[1] = box[3] = l->y;
    cell_range(g, box, r);
    for (k = g->start[r[1] * g->nx + r[0]]; k < g->start[r[1] * g->nx + r[0] + 1]; k++) {
        const scene_building *b = &s->bld[g->items[k]];
        if (l->z <= b->min_height || l->z >= b->height)
            continue;
        if (l->x < b->box[0] || l->x > b->box[2] || l->y < b->box[1] || l->y > b->box[3])
            continue;
        if (inside_footprint(s, b, p))
            return (long)g->items[k];
    }
    return -1;
}

plx_status ld_drop_buried_lamps(loader *ld)
{
    return ld_drop_buried_lamps_from(ld, 0);
}

plx_status ld_drop_buried_lamps_from(loader *ld, uint32_t first)
{
    scene *s = ld->s;
    arena_mark m = arena_get_mark(ld->mem);
    bgrid g;
    uint32_t i, kept = first;
    if (s->nlamps <= first || s->nbld == 0)
        return PLX_OK;
    if (!bgrid_build(ld->mem, s, &g)) {
        arena_release(ld->mem, &m);
        return eng_nomem(ld->e, "checking lamps against buildings");
    }
    for (i = first; i < s->nlamps; i++) {
        long host = lamp_host(s, &g, &s->lamps[i]);
        if (host >= 0) {
            char why[200];
            strbuf b;
            sb_init(&b, why, sizeof why);
            sb_str(&b, "lamp is inside building ");
            sb_uint(&b, (uint64_t)host);
            if (s->bld[host].id) {
                sb_str(&b, " (");
                sb_str(&b, s->bld[host].id);
                sb_char(&b, ')');
            }
            if (eng_strict(ld->e)) { /* the load fails: nothing is left out */
                arena_release(ld->mem, &m);
                return ld_bad_feature(ld, s->lamps[i].feature, s->lamps[i].id, why);
            }
            sb_str(&b, "; left out");
            ld_warn(ld, s->lamps[i].feature, s->lamps[i].id, why);
            s->skipped_lamps++;
            continue;
        }
        s->lamps[kept++] = s->lamps[i];
    }
    s->nlamps = kept;
    arena_release(ld->mem, &m);
    return PLX_OK;
}
