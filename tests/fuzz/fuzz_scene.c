/* libFuzzer target: scene validation. The bytes are read as a recipe for a
 * small scene on a half-metre grid (rings of random or rectangular shape,
 * closed or not, with repeated vertices, holes, MultiPolygons, lamps, and
 * property values valid, invalid or of the wrong kind), written out as
 * GeoJSON text and loaded. An independent exact oracle (64-bit integer
 * arithmetic on the grid, brute force) says which features are valid, which
 * lamps are inside a building, how every kept ring must come out (cleaned,
 * outer counter-clockwise, holes clockwise) and how many warnings the load
 * gives; the loader must agree in lenient and strict mode, besides the
 * checks of fuzz_common.h. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define MAX_FEATURES 10
#define MAX_RINGS 3
#define MAX_VERTS 12

typedef struct pt { int64_t x, y; } pt; /* half-metre units */

typedef struct ring {
    pt v[MAX_VERTS + 2];
    int n;          /* as written (with a closing vertex when closed) */
} ring;

typedef struct poly {
    ring r[MAX_RINGS];
    int nr;
} poly;

typedef struct feature {
    int lamp;
    int npoly;          /* 1 for a Polygon, 2 for a MultiPolygon */
    poly p[2];
    int hi, mi;         /* building: height and min_height choices */
    pt at;              /* lamp */
    int zi, ii, ri;     /* lamp: z, intensity, radius choices */
} feature;

/* Property choices: JSON text, value (NAN = absent or ignored), valid. */
typedef struct choice { const char *json; double value; int wrong_kind; } choice;

static const choice heights[] = {
    { NULL, 12.0, 0 }, { "10", 10.0, 0 }, { "\"4 m\"", 4.0, 0 }, { "0", 0.0, 0 },
    { "\"3;4\"", 12.0, 1 }, { "2000", 2000.0, 0 },
};
static const choice min_heights[] = { { NULL, 0.0, 0 }, { "3", 3.0, 0 }, { "10", 10.0, 0 }, { "-1", -1.0, 0 } };
static const choice lamp_z[] = {
    { NULL, 6.0, 0 }, { "0", 0.0, 0 }, { "4", 4.0, 0 }, { "10", 10.0, 0 }, { "12", 12.0, 0 }, { "-2", -2.0, 0 },
};
static const choice intensities[] = { { NULL, 1000.0, 0 }, { "0", 0.0, 0 }, { "50", 50.0, 0 }, { "-1", -1.0, 0 } };
static const choice radii[] = { { NULL, 30.0, 0 }, { "5", 5.0, 0 }, { "0", 0.0, 0 }, { "true", 30.0, 1 } };

#define COUNT(a) ((int)(sizeof a / sizeof a[0]))

typedef struct reader { const uint8_t *d; size_t n, i; } reader;

static int more(const reader *r) { return r->i < r->n; }
static unsigned get(reader *r) { return r->i < r->n ? r->d[r->i++] : 0; }
static int64_t coord(reader *r) { return (int64_t)(get(r) % 33) - 16; }

static void read_ring(reader *r, ring *g, int hole)
{
    unsigned mode = get(r) % 4, k;
    g->n = 0;
    if (mode == 3) { /* an axis-aligned rectangle, either way round */
        int64_t x0 = coord(r), y0 = coord(r), w = 1 + get(r) % (hole ? 6 : 16), h = 1 + get(r) % (hole ? 6 : 16);
        pt c[4];
        unsigned s = get(r), i;
        c[0].x = x0; c[0].y = y0; c[1].x = x0 + w; c[1].y = y0;
        c[2].x = x0 + w; c[2].y = y0 + h; c[3].x = x0; c[3].y = y0 + h;
        for (i = 0; i < 4; i++)
            g->v[g->n++] = c[(s & 4 ? 4 - i + s : i + s) % 4];
    } else {
        unsigned n = get(r) % 16 == 0 ? get(r) % 3 : 3 + get(r) % 7;
        for (k = 0; k < n && g->n < MAX_VERTS; k++) {
            if (g->n > 0 && get(r) % 8 == 0)
                g->v[g->n] = g->v[g->n - 1]; /* a repeated vertex */
            else {
                g->v[g->n].x = coord(r);
                g->v[g->n].y = coord(r);
            }
            g->n++;
        }
    }
    if (g->n > 0 && get(r) % 2)
        g->v[g->n++] = g->v[0];
}

static void read_poly(reader *r, poly *p)
{
    unsigned b = get(r);
    int i;
    p->nr = b % 4 == 3 ? 2 + (int)(b / 4) % 2 : 1;
    for (i = 0; i < p->nr; i++)
        read_ring(r, &p->r[i], i > 0);
}

static int read_scene(reader *r, feature *f)
{
    int n = 0;
    while (more(r) && n < MAX_FEATURES) {
        feature *x = &f[n++];
        unsigned kind = get(r) % 10;
        memset(x, 0, sizeof *x);
        if (kind >= 7) {
            x->lamp = 1;
            x->at.x = coord(r);
            x->at.y = coord(r);
            x->zi = (int)(get(r) % COUNT(lamp_z));
            x->ii = (int)(get(r) % COUNT(intensities));
            x->ri = (int)(get(r) % COUNT(radii));
        } else {
            x->npoly = kind == 6 ? 2 : 1;
            read_poly(r, &x->p[0]);
            if (x->npoly == 2)
                read_poly(r, &x->p[1]);
            x->hi = (int)(get(r) % COUNT(heights));
            x->mi = (int)(get(r) % COUNT(min_heights));
        }
    }
    return n;
}

/* ---- the GeoJSON text ------------------------------------------------------- */

typedef struct text { char *s; size_t n, cap; } text;

static void put(text *t, const char *s)
{
    size_t k = strlen(s);
    CHECK(t->n + k < t->cap);
    memcpy(t->s + t->n, s, k + 1);
    t->n += k;
}

static void put_num(text *t, int64_t half)
{
    char b[32];
    snprintf(b, sizeof b, "%.1f", (double)half / 2.0);
    put(t, b);
}

static void put_ring(text *t, const ring *g)
{
    int i;
    put(t, "[");
    for (i = 0; i < g->n; i++) {
        put(t, i ? ",[" : "[");
        put_num(t, g->v[i].x);
        put(t, ",");
        put_num(t, g->v[i].y);
        put(t, "]");
    }
    put(t, "]");
}

static void put_poly(text *t, const poly *p)
{
    int i;
    put(t, "[");
    for (i = 0; i < p->nr; i++) {
        if (i)
            put(t, ",");
        put_ring(t, &p->r[i]);
    }
    put(t, "]");
}

static void put_prop(text *t, const char *key, const choice *c, int *first)
{
    if (!c->json)
        return;
    put(t, *first ? "\"" : ",\"");
    put(t, key);
    put(t, "\":");
    put(t, c->json);
    *first = 0;
}

static void write_scene(text *t, const feature *f, int n)
{
    int i, first;
    put(t, "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[\n");
    for (i = 0; i < n; i++) {
        const feature *x = &f[i];
        put(t, i ? ",\n{\"type\":\"Feature\",\"properties\":{" : "{\"type\":\"Feature\",\"properties\":{");
        first = 1;
        if (x->lamp) {
            put(t, "\"lamp\":true");
            first = 0;
            put_prop(t, "z", &lamp_z[x->zi], &first);
            put_prop(t, "intensity", &intensities[x->ii], &first);
            put_prop(t, "radius", &radii[x->ri], &first);
            put(t, "},\"geometry\":{\"type\":\"Point\",\"coordinates\":[");
            put_num(t, x->at.x);
            put(t, ",");
            put_num(t, x->at.y);
            put(t, "]}}");
        } else {
            put_prop(t, "height", &heights[x->hi], &first);
            put_prop(t, "min_height", &min_heights[x->mi], &first);
            if (x->npoly == 1) {
                put(t, "},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":");
                put_poly(t, &x->p[0]);
            } else {
                put(t, "},\"geometry\":{\"type\":\"MultiPolygon\",\"coordinates\":[");
                put_poly(t, &x->p[0]);
                put(t, ",");
                put_poly(t, &x->p[1]);
                put(t, "]");
            }
            put(t, "}}");
        }
    }
    put(t, "]}\n");
}

/* ---- the oracle: exact integer geometry, brute force ------------------------- */

static int sgn(int64_t v) { return (v > 0) - (v < 0); }

static int orient(pt a, pt b, pt c)
{
    return sgn((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

static int eq(pt a, pt b) { return a.x == b.x && a.y == b.y; }

/* p on the closed segment ab */
static int on_seg(pt p, pt a, pt b)
{
    return orient(a, b, p) == 0 && p.x >= (a.x < b.x ? a.x : b.x) && p.x <= (a.x > b.x ? a.x : b.x) &&
           p.y >= (a.y < b.y ? a.y : b.y) && p.y <= (a.y > b.y ? a.y : b.y);
}

static int segs_meet(pt a, pt b, pt c, pt d)
{
    int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return 1;
    return on_seg(c, a, b) || on_seg(d, a, b) || on_seg(a, c, d) || on_seg(b, c, d);
}

/* A crossing of interiors or a collinear overlap of positive length. */
static int segs_cross_or_overlap(pt a, pt b, pt c, pt d)
{
    int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return 1;
    if (o1 == 0 && o2 == 0) { /* collinear: overlap when the projections share an interval */
        int ax = a.x != b.x;
        int64_t lo1 = ax ? (a.x < b.x ? a.x : b.x) : (a.y < b.y ? a.y : b.y);
        int64_t hi1 = ax ? (a.x > b.x ? a.x : b.x) : (a.y > b.y ? a.y : b.y);
        int64_t lo2 = ax ? (c.x < d.x ? c.x : d.x) : (c.y < d.y ? c.y : d.y);
        int64_t hi2 = ax ? (c.x > d.x ? c.x : d.x) : (c.y > d.y ? c.y : d.y);
        int64_t lo = lo1 > lo2 ? lo1 : lo2, hi = hi1 < hi2 ? hi1 : hi2;
        return hi > lo;
    }
    return 0;
}

/* Cleans a ring as the loader does: duplicate consecutive and closing
 * vertices dropped. */
static int clean(const ring *g, pt *out)
{
    int i, n = 0;
    for (i = 0; i < g->n; i++)
        if (n == 0 || !eq(g->v[i], out[n - 1]))
            out[n++] = g->v[i];
    while (n > 1 && eq(out[n - 1], out[0]))
        n--;
    return n;
}

static int simple(const pt *v, int n)
{
    int i, j;
    if (n < 3)
        return 0;
    for (i = 0; i < n; i++) {
        for (j = i + 1; j < n; j++) {
            pt a = v[i], b = v[(i + 1) % n], c = v[j], d = v[(j + 1) % n];
            if (j == i + 1 || (i == 0 && j == n - 1)) {
                /* adjacent: they must not fold back along each other */
                pt s = j == i + 1 ? b : a, p = j == i + 1 ? a : b, q = j == i + 1 ? d : c;
                if (orient(s, p, q) == 0 && (p.x - s.x) * (q.x - s.x) + (p.y - s.y) * (q.y - s.y) > 0)
                    return 0;
                if (n == 3 && orient(v[0], v[1], v[2]) == 0)
                    return 0;
            } else if (segs_meet(a, b, c, d)) {
                return 0;
            }
        }
    }
    return 1;
}

static int64_t area2(const pt *v, int n)
{
    int64_t s = 0;
    int i;
    for (i = 0; i < n; i++)
        s += v[i].x * v[(i + 1) % n].y - v[(i + 1) % n].x * v[i].y;
    return s;
}

enum { OUT = 0, IN = 1, ON = 2 };

static int pip(pt q, const pt *v, int n)
{
    int i, c = 0;
    for (i = 0; i < n; i++) {
        pt a = v[i], b = v[(i + 1) % n];
        if (on_seg(q, a, b))
            return ON;
        if ((a.y > q.y) != (b.y > q.y)) {
            int o = orient(a, b, q);
            if ((b.y > a.y) ? o > 0 : o < 0)
                c ^= 1;
        }
    }
    return c ? IN : OUT;
}

/* Bits 1 (some point of a strictly inside b) and 2 (some strictly outside),
 * by the vertices of a and the midpoints of the pieces of its edges between
 * the vertices of b on them; coordinates doubled so midpoints stay exact. */
static int sides(const pt *a, int na, const pt *b, int nb)
{
    pt a2[MAX_VERTS + 2], b2[MAX_VERTS + 2];
    int i, j, k, res = 0;
    for (i = 0; i < na; i++) { a2[i].x = 2 * a[i].x; a2[i].y = 2 * a[i].y; }
    for (i = 0; i < nb; i++) { b2[i].x = 2 * b[i].x; b2[i].y = 2 * b[i].y; }
    for (i = 0; i < na; i++) {
        pt p0 = a2[i], p1 = a2[(i + 1) % na], cut[MAX_VERTS + 4];
        int nc = 0, w;
        cut[nc++] = p0;
        for (j = 0; j < nb; j++)
            if (on_seg(b2[j], p0, p1) && !eq(b2[j], p0) && !eq(b2[j], p1))
                cut[nc++] = b2[j];
        cut[nc++] = p1;
        /* sort the cuts by distance from p0 (insertion sort) */
        for (j = 2; j < nc - 1; j++)
            for (k = j; k > 1; k--) {
                int64_t dk = llabs(cut[k].x - p0.x) + llabs(cut[k].y - p0.y);
                int64_t dp = llabs(cut[k - 1].x - p0.x) + llabs(cut[k - 1].y - p0.y);
                pt t = cut[k];
                if (dk >= dp)
                    break;
                cut[k] = cut[k - 1];
                cut[k - 1] = t;
            }
        w = pip(p0, b2, nb);
        res |= w == IN ? 1 : w == OUT ? 2 : 0;
        for (j = 0; j + 1 < nc; j++) {
            pt m;
            m.x = (cut[j].x + cut[j + 1].x) / 2;
            m.y = (cut[j].y + cut[j + 1].y) / 2;
            CHECK(2 * m.x == cut[j].x + cut[j + 1].x && 2 * m.y == cut[j].y + cut[j + 1].y);
            w = pip(m, b2, nb);
            res |= w == IN ? 1 : w == OUT ? 2 : 0;
        }
    }
    return res;
}

static int rings_clear(const pt *a, int na, const pt *b, int nb)
{
    int i, j;
    for (i = 0; i < na; i++)
        for (j = 0; j < nb; j++)
            if (segs_cross_or_overlap(a[i], a[(i + 1) % na], b[j], b[(j + 1) % nb]))
                return 0;
    return 1;
}

typedef struct cpoly {
    pt v[MAX_RINGS][MAX_VERTS + 2];
    int n[MAX_RINGS];
    int nr;
} cpoly;

/* 1 when the polygon is valid; fills the cleaned rings in stored order. */
static int poly_ok(const poly *p, cpoly *c)
{
    int r, g;
    c->nr = p->nr;
    for (r = 0; r < p->nr; r++) {
        c->n[r] = clean(&p->r[r], c->v[r]);
        if (!simple(c->v[r], c->n[r]))
            return 0;
        if ((area2(c->v[r], c->n[r]) > 0) != (r == 0)) { /* stored outer ccw, holes cw */
            int i, n = c->n[r];
            for (i = 0; i < n / 2; i++) {
                pt t = c->v[r][i];
                c->v[r][i] = c->v[r][n - 1 - i];
                c->v[r][n - 1 - i] = t;
            }
        }
    }
    for (r = 1; r < p->nr; r++) {
        if (!rings_clear(c->v[0], c->n[0], c->v[r], c->n[r]) || sides(c->v[r], c->n[r], c->v[0], c->n[0]) != 1)
            return 0;
        for (g = 1; g < r; g++)
            if (!rings_clear(c->v[g], c->n[g], c->v[r], c->n[r]) ||
                (sides(c->v[r], c->n[r], c->v[g], c->n[g]) & 1) || (sides(c->v[g], c->n[g], c->v[r], c->n[r]) & 1))
                return 0;
    }
    return 1;
}

typedef struct expect {
    uint32_t buildings, lamps, skipped_features, skipped_lamps, vertices, holes, raised, warnings;
    uint32_t merged;
    cpoly kept[2 * MAX_FEATURES];
    pt lamp_at[MAX_FEATURES];
    double lamp_z[MAX_FEATURES], lamp_r[MAX_FEATURES];
    double height[2 * MAX_FEATURES], min_height[2 * MAX_FEATURES];
} expect;

/* README "Duplicate lamps": kept lamps with the same x, y, z and radius
 * become one; each such spot is one warning (there are never more than
 * LAMPMERGE_WARN spots here, so no summary line). */
static void merge_lamps(expect *ex)
{
    uint32_t a, b, n = ex->lamps, groups = 0, gone = 0;
    for (a = 0; a < n; a++) {
        int first = 1, dup = 0;
        for (b = 0; b < n; b++) {
            int same = ex->lamp_at[a].x == ex->lamp_at[b].x && ex->lamp_at[a].y == ex->lamp_at[b].y &&
                       ex->lamp_z[a] == ex->lamp_z[b] && ex->lamp_r[a] == ex->lamp_r[b];
            if (!same || a == b)
                continue;
            dup = 1;
            if (b < a)
                first = 0;
        }
        if (dup && first)
            groups++;
        if (dup && !first)
            gone++;
    }
    ex->lamps -= gone;
    ex->merged = gone;
    ex->warnings += groups;
}

static void oracle(const feature *f, int n, expect *ex)
{
    int i, k, r;
    memset(ex, 0, sizeof *ex);
    for (i = 0; i < n; i++) {
        const feature *x = &f[i];
        if (x->lamp)
            continue;
        {
            double h = heights[x->hi].value, m = min_heights[x->mi].value;
            int ok = h > 0 && h <= 1000 && m >= 0 && m < h;
            cpoly c[2];
            ex->warnings += (uint32_t)(heights[x->hi].wrong_kind + min_heights[x->mi].wrong_kind);
            for (k = 0; ok && k < x->npoly; k++)
                ok = poly_ok(&x->p[k], &c[k]);
            if (!ok) {
                ex->skipped_features++;
                ex->warnings++;
                continue;
            }
            for (k = 0; k < x->npoly; k++) {
                uint32_t b = ex->buildings++;
                ex->kept[b] = c[k];
                ex->height[b] = h;
                ex->min_height[b] = m;
                ex->raised += m > 0;
                ex->holes += (uint32_t)c[k].nr - 1;
                for (r = 0; r < c[k].nr; r++)
                    ex->vertices += (uint32_t)c[k].n[r];
            }
        }
    }
    for (i = 0; i < n; i++) {
        const feature *x = &f[i];
        double z = lamp_z[x->zi].value, in = intensities[x->ii].value, rad = radii[x->ri].value;
        uint32_t b;
        int buried = 0;
        if (!x->lamp)
            continue;
        ex->warnings += (uint32_t)(lamp_z[x->zi].wrong_kind + intensities[x->ii].wrong_kind + radii[x->ri].wrong_kind);
        if (!(z >= 0 && z <= 1000 && in >= 0 && rad > 0 && rad <= 1e5)) {
            ex->skipped_features++;
            ex->warnings++;
            continue;
        }
        ex->warnings += in == 0;
        for (b = 0; b < ex->buildings && !buried; b++) {
            const cpoly *c = &ex->kept[b];
            if (!(z > ex->min_height[b] && z < ex->height[b]))
                continue;
            if (pip(x->at, c->v[0], c->n[0]) != IN)
                continue;
            buried = 1;
            for (r = 1; r < c->nr; r++)
                if (pip(x->at, c->v[r], c->n[r]) != OUT)
                    buried = 0;
        }
        if (buried) {
            ex->skipped_lamps++;
            ex->warnings++;
        } else {
            uint32_t l = ex->lamps++;
            ex->lamp_at[l] = x->at;
            ex->lamp_z[l] = z;
            ex->lamp_r[l] = rad;
        }
    }
    merge_lamps(ex);
}

static void compare(fuzz_engine *f, const expect *ex)
{
    plx_scene_info si;
    uint32_t b;
    int r, i;
    CHECK(plx_scene_info_get(f->e, &si) == PLX_OK);
    CHECK(si.buildings == ex->buildings);
    CHECK(si.skipped_features == ex->skipped_features);
    CHECK(si.skipped_lamps == ex->skipped_lamps);
    CHECK(si.lamps == ex->lamps);
    CHECK(si.merged_lamps == ex->merged);
    CHECK(si.vertices == ex->vertices);
    CHECK(si.holes == ex->holes);
    CHECK(si.raised == ex->raised);
    CHECK(plx_warning_count(f->e) == ex->warnings);
    for (b = 0; b < ex->buildings; b++) {
        plx_building pb;
        CHECK(plx_building_get(f->e, b, &pb) == PLX_OK);
        CHECK(pb.height == ex->height[b] && pb.min_height == ex->min_height[b]);
        CHECK((int)pb.nrings == ex->kept[b].nr);
        for (r = 0; r < ex->kept[b].nr; r++) {
            const double *xy;
            uint32_t n;
            CHECK(plx_building_ring(f->e, b, (uint32_t)r, &xy, &n) == PLX_OK);
            CHECK((int)n == ex->kept[b].n[r]);
            for (i = 0; i < (int)n; i++)
                CHECK(xy[2 * i] == (double)ex->kept[b].v[r][i].x / 2.0 &&
                      xy[2 * i + 1] == (double)ex->kept[b].v[r][i].y / 2.0);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fuzz_engine lenient, strict;
    static int ready;
    static char buf[1 << 16];
    feature f[MAX_FEATURES];
    static expect ex;
    reader rd;
    text t;
    int n;
    if (!ready) {
        fuzz_engine_open(&lenient, 0);
        fuzz_engine_open(&strict, 1);
        ready = 1;
    }
    rd.d = data;
    rd.n = size;
    rd.i = 0;
    n = read_scene(&rd, f);
    t.s = buf;
    t.n = 0;
    t.cap = sizeof buf;
    buf[0] = '\0';
    write_scene(&t, f, n);
    oracle(f, n, &ex);
    fuzz_check_text(&lenient, &strict, t.s, t.n, fuzz_hash(data, size));
    /* fuzz_check_text leaves the lenient engine with the scene loaded */
    CHECK(plx_load_geojson(lenient.e, t.s, t.n, "scene") == PLX_OK);
    compare(&lenient, &ex);
    CHECK(plx_load_geojson(strict.e, t.s, t.n, "scene") ==
          (ex.skipped_features + ex.skipped_lamps ? PLX_E_SCENE : PLX_OK));
    return 0;
}
