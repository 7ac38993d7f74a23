/* Tests of plx_gen_city: arguments, streaming and write failures, JSON
 * validity, counts, determinism, and exact geometric checks of the output
 * (simple rings, no overlapping footprints, shared walls, open courtyards,
 * lamps outside buildings).
 *
 * The last tests load the output into an engine: no warning, nothing
 * skipped, no overlapping pair, the eixample's 900 blocks and courtyards.
 *
 * Geometry is checked in exact integer arithmetic: every coordinate is a
 * whole number of millimetres, scaled by 6 so that edge midpoints (/2) and
 * triangle centroids (/3) are integers too.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <cjson/cJSON.h>

#include "polarlux.h"
#include "fixture.h"

static int quick(void); /* PLX_TEST_QUICK: skip exact checks of big cities */

/* ---- capture ------------------------------------------------------------ */

typedef struct buf {
    char *data;
    size_t len, cap;
    size_t calls;      /* callback calls */
    size_t fail_at;    /* 1-based call that returns non-zero; 0: never */
    size_t empty_calls; /* calls with len == 0 */
} buf;

static int buf_write(void *ctx, const char *data, size_t len)
{
    buf *b = ctx;
    b->calls++;
    if (len == 0)
        b->empty_calls++;
    if (b->fail_at != 0 && b->calls >= b->fail_at)
        return 1;
    if (b->len + len + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + len + 1)
            cap *= 2;
        b->data = realloc(b->data, cap);
        assert_non_null(b->data);
        b->cap = cap;
    }
    memcpy(b->data + b->len, data, len);
    b->len += len;
    b->data[b->len] = '\0';
    return 0;
}

static buf gen(const char *style, int nx, int ny, uint64_t seed)
{
    buf b;
    memset(&b, 0, sizeof b);
    assert_int_equal(plx_gen_city(style, nx, ny, seed, buf_write, &b), PLX_OK);
    assert_non_null(b.data);
    assert_int_equal(b.empty_calls, 0);
    return b;
}

/* ---- parsed city -------------------------------------------------------- */

typedef struct pt {
    long long x, y;
} pt;

typedef struct bld {
    pt *v;  /* n distinct vertices, scaled mm, ring not closed */
    int n;
    long long minx, miny, maxx, maxy;
    double height; /* metres, from height or levels * 3 */
    int has_levels;
} bld;

typedef struct lamp {
    pt p;
    double z;
} lamp;

typedef struct city {
    bld *b;
    size_t nb;
    lamp *l;
    size_t nl;
} city;

#define SCALE 6

static long long to_scaled(double metres)
{
    double mm = metres * 1000.0;
    long long r = llround(mm);
    assert_true(fabs(mm - (double)r) < 1e-6); /* whole millimetres */
    return r * SCALE;
}

/* Parses and checks the feature structure; fills c. */
static void city_parse(const buf *text, city *c)
{
    cJSON *root = cJSON_ParseWithLength(text->data, text->len);
    cJSON *props, *features, *f;
    size_t nf;
    assert_non_null(root);
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(root, "type")->valuestring,
                        "FeatureCollection");
    props = cJSON_GetObjectItemCaseSensitive(root, "properties");
    assert_non_null(props);
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(props, "units")->valuestring, "m");
    features = cJSON_GetObjectItemCaseSensitive(root, "features");
    assert_true(cJSON_IsArray(features));
    nf = (size_t)cJSON_GetArraySize(features);
    memset(c, 0, sizeof *c);
    c->b = calloc(nf + 1, sizeof *c->b);
    c->l = calloc(nf + 1, sizeof *c->l);
    assert_non_null(c->b);
    assert_non_null(c->l);
    cJSON_ArrayForEach(f, features) {
        cJSON *g = cJSON_GetObjectItemCaseSensitive(f, "geometry");
        cJSON *p = cJSON_GetObjectItemCaseSensitive(f, "properties");
        cJSON *gt = cJSON_GetObjectItemCaseSensitive(g, "type");
        cJSON *coords = cJSON_GetObjectItemCaseSensitive(g, "coordinates");
        cJSON *id = cJSON_GetObjectItemCaseSensitive(p, "id");
        char want[32];
        assert_string_equal(cJSON_GetObjectItemCaseSensitive(f, "type")->valuestring, "Feature");
        assert_true(cJSON_IsString(id));
        if (strcmp(gt->valuestring, "Polygon") == 0) {
            bld *b = &c->b[c->nb];
            cJSON *ring, *h, *lv, *q;
            int n, k;
            snprintf(want, sizeof want, "b%zu", c->nb);
            assert_string_equal(id->valuestring, want);
            assert_int_equal(cJSON_GetArraySize(coords), 1);
            ring = cJSON_GetArrayItem(coords, 0);
            n = cJSON_GetArraySize(ring);
            assert_true(n >= 4);
            b->v = calloc((size_t)n, sizeof *b->v);
            assert_non_null(b->v);
            k = 0;
            cJSON_ArrayForEach(q, ring) {
                assert_int_equal(cJSON_GetArraySize(q), 2);
                b->v[k].x = to_scaled(cJSON_GetArrayItem(q, 0)->valuedouble);
                b->v[k].y = to_scaled(cJSON_GetArrayItem(q, 1)->valuedouble);
                k++;
            }
            /* closed ring */
            assert_true(b->v[0].x == b->v[n - 1].x && b->v[0].y == b->v[n - 1].y);
            b->n = n - 1;
            b->minx = b->maxx = b->v[0].x;
            b->miny = b->maxy = b->v[0].y;
            for (k = 1; k < b->n; k++) {
                if (b->v[k].x < b->minx) b->minx = b->v[k].x;
                if (b->v[k].x > b->maxx) b->maxx = b->v[k].x;
                if (b->v[k].y < b->miny) b->miny = b->v[k].y;
                if (b->v[k].y > b->maxy) b->maxy = b->v[k].y;
            }
            h = cJSON_GetObjectItemCaseSensitive(p, "height");
            lv = cJSON_GetObjectItemCaseSensitive(p, "building:levels");
            assert_true((h != NULL) != (lv != NULL)); /* exactly one of them */
            if (h) {
                assert_true(cJSON_IsNumber(h));
                b->height = h->valuedouble;
            } else {
                assert_true(cJSON_IsNumber(lv));
                assert_true(lv->valuedouble == floor(lv->valuedouble));
                b->height = 3.0 * lv->valuedouble;
                b->has_levels = 1;
            }
            c->nb++;
        } else {
            lamp *l = &c->l[c->nl];
            cJSON *z = cJSON_GetObjectItemCaseSensitive(p, "z");
            assert_string_equal(gt->valuestring, "Point");
            snprintf(want, sizeof want, "l%zu", c->nl);
            assert_string_equal(id->valuestring, want);
            assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(p, "lamp")));
            assert_true(cJSON_IsNumber(z));
            assert_true(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(p, "intensity")));
            assert_true(cJSON_GetObjectItemCaseSensitive(p, "intensity")->valuedouble > 0);
            assert_true(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(p, "radius")));
            assert_true(cJSON_GetObjectItemCaseSensitive(p, "radius")->valuedouble > 0);
            assert_int_equal(cJSON_GetArraySize(coords), 2);
            l->p.x = to_scaled(cJSON_GetArrayItem(coords, 0)->valuedouble);
            l->p.y = to_scaled(cJSON_GetArrayItem(coords, 1)->valuedouble);
            l->z = z->valuedouble;
            c->nl++;
        }
    }
    cJSON_Delete(root);
}

static void city_free(city *c)
{
    size_t i;
    for (i = 0; i < c->nb; i++)
        free(c->b[i].v);
    free(c->b);
    free(c->l);
}

/* Every '.' in the text starts exactly three decimals (the text has no
 * other dots). */
static void check_three_decimals(const buf *b)
{
    const char *s = b->data;
    size_t i, dots = 0;
    for (i = 0; i < b->len; i++) {
        if (s[i] != '.')
            continue;
        dots++;
        assert_true(i > 0 && s[i - 1] >= '0' && s[i - 1] <= '9');
        assert_true(i + 4 <= b->len);
        assert_true(s[i + 1] >= '0' && s[i + 1] <= '9');
        assert_true(s[i + 2] >= '0' && s[i + 2] <= '9');
        assert_true(s[i + 3] >= '0' && s[i + 3] <= '9');
        assert_false(s[i + 4] >= '0' && s[i + 4] <= '9');
    }
    assert_true(dots > 0);
    assert_null(strstr(s, "-0.000"));
}

/* ---- exact geometry ----------------------------------------------------- */

static int orient(pt a, pt b, pt c)
{
    long long d = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    return (d > 0) - (d < 0);
}

static int on_seg(pt p, pt a, pt b)
{
    return orient(a, b, p) == 0 &&
           p.x >= (a.x < b.x ? a.x : b.x) && p.x <= (a.x > b.x ? a.x : b.x) &&
           p.y >= (a.y < b.y ? a.y : b.y) && p.y <= (a.y > b.y ? a.y : b.y);
}

static int cross_proper(pt a, pt b, pt c, pt d)
{
    int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
    return o1 * o2 < 0 && o3 * o4 < 0;
}

static int seg_meet(pt a, pt b, pt c, pt d)
{
    return cross_proper(a, b, c, d) || on_seg(a, c, d) || on_seg(b, c, d) ||
           on_seg(c, a, b) || on_seg(d, a, b);
}

enum { OUTSIDE = 0, INSIDE = 1, ON_EDGE = 2 };

static int point_in(pt q, const bld *b)
{
    int i, in = 0;
    if (q.x < b->minx || q.x > b->maxx || q.y < b->miny || q.y > b->maxy)
        return OUTSIDE;
    for (i = 0; i < b->n; i++) {
        pt a = b->v[i], c = b->v[(i + 1) % b->n];
        if (on_seg(q, a, c))
            return ON_EDGE;
        if ((a.y > q.y) != (c.y > q.y)) {
            int o = orient(a, c, q);
            if (c.y > a.y ? o > 0 : o < 0)
                in = !in;
        }
    }
    return in ? INSIDE : OUTSIDE;
}

static long long area2(const bld *b)
{
    long long s = 0;
    int i;
    for (i = 0; i < b->n; i++) {
        pt a = b->v[i], c = b->v[(i + 1) % b->n];
        s += a.x * c.y - c.x * a.y;
    }
    return s;
}

static int is_simple(const bld *b)
{
    int i, j, n = b->n;
    if (n < 3 || area2(b) == 0)
        return 0;
    for (i = 0; i < n; i++)
        for (j = i + 1; j < n; j++)
            if (b->v[i].x == b->v[j].x && b->v[i].y == b->v[j].y)
                return 0;
    for (i = 0; i < n; i++) {
        pt a = b->v[i], a2 = b->v[(i + 1) % n];
        for (j = i + 1; j < n; j++) {
            pt c = b->v[j], c2 = b->v[(j + 1) % n];
            if (j == i + 1) { /* a2 == c: the far ends must not lie on the other edge */
                if (on_seg(c2, a, a2) || on_seg(a, c, c2))
                    return 0;
            } else if (i == 0 && j == n - 1) { /* c2 == a */
                if (on_seg(c, a, a2) || on_seg(a2, c, c2))
                    return 0;
            } else if (seg_meet(a, a2, c, c2)) {
                return 0;
            }
        }
    }
    return 1;
}

static int n_reflex(const bld *b)
{
    int i, s = area2(b) > 0 ? 1 : -1, r = 0;
    for (i = 0; i < b->n; i++)
        if (orient(b->v[(i + b->n - 1) % b->n], b->v[i], b->v[(i + 1) % b->n]) == -s)
            r++;
    return r;
}

/* A point strictly inside the footprint: the centroid of an ear. */
static pt interior_point(const bld *b)
{
    int i, j, n = b->n, s = area2(b) > 0 ? 1 : -1;
    for (i = 0; i < n; i++) {
        pt p = b->v[(i + n - 1) % n], q = b->v[i], r = b->v[(i + 1) % n];
        int ear = orient(p, q, r) == s;
        for (j = 0; j < n && ear; j++) {
            pt t = b->v[j];
            if (j == i || j == (i + 1) % n || j == (i + n - 1) % n)
                continue;
            if (orient(p, q, t) * s >= 0 && orient(q, r, t) * s >= 0 && orient(r, p, t) * s >= 0)
                ear = 0;
        }
        if (ear) {
            pt c;
            c.x = (p.x + q.x + r.x) / 3;
            c.y = (p.y + q.y + r.y) / 3;
            return c;
        }
    }
    fail_msg("no ear found");
    return b->v[0];
}

/* Checks that the interiors of a and b do not meet; they may share walls. */
static int interiors_disjoint(const bld *a, const bld *b)
{
    int i, j, w;
    for (w = 0; w < 2; w++) {
        const bld *p = w ? b : a, *q = w ? a : b;
        for (i = 0; i < p->n; i++) {
            pt u = p->v[i], u2 = p->v[(i + 1) % p->n], mid;
            mid.x = (u.x + u2.x) / 2;
            mid.y = (u.y + u2.y) / 2;
            if (point_in(u, q) == INSIDE || point_in(mid, q) == INSIDE)
                return 0;
            if (w == 0)
                for (j = 0; j < q->n; j++)
                    if (cross_proper(u, u2, q->v[j], q->v[(j + 1) % q->n]))
                        return 0;
        }
        if (point_in(interior_point(p), q) != OUTSIDE)
            return 0;
    }
    return 1;
}

static const city *sort_city;

static int cmp_minx(const void *x, const void *y)
{
    long long a = sort_city->b[*(const size_t *)x].minx, b = sort_city->b[*(const size_t *)y].minx;
    return (a > b) - (a < b);
}

static int cmp_lamp_x(const void *x, const void *y)
{
    long long a = ((const lamp *)x)->p.x, b = ((const lamp *)y)->p.x;
    return (a > b) - (a < b);
}

/* Every ring simple, interiors pairwise disjoint (a sweep over x), no lamp
 * inside or on a footprint. Returns the number of pairs that touch. */
static size_t check_geometry(city *c)
{
    size_t *order = malloc((c->nb + 1) * sizeof *order);
    size_t i, k, touching = 0;
    assert_non_null(order);
    for (i = 0; i < c->nb; i++) {
        if (!is_simple(&c->b[i]))
            fail_msg("building b%zu is not simple", i);
        order[i] = i;
    }
    sort_city = c;
    qsort(order, c->nb, sizeof *order, cmp_minx);
    for (i = 0; i < c->nb; i++) {
        const bld *a = &c->b[order[i]];
        for (k = i + 1; k < c->nb && c->b[order[k]].minx <= a->maxx; k++) {
            const bld *b = &c->b[order[k]];
            if (b->miny > a->maxy || b->maxy < a->miny)
                continue;
            if (!interiors_disjoint(a, b))
                fail_msg("buildings b%zu and b%zu overlap", order[i], order[k]);
            touching++;
        }
    }
    free(order);
    /* lamps, sorted by x */
    qsort(c->l, c->nl, sizeof *c->l, cmp_lamp_x);
    for (i = 0; i < c->nb; i++) {
        const bld *b = &c->b[i];
        size_t lo = 0, hi = c->nl;
        while (lo < hi) {
            size_t m = (lo + hi) / 2;
            if (c->l[m].p.x < b->minx)
                lo = m + 1;
            else
                hi = m;
        }
        for (k = lo; k < c->nl && c->l[k].p.x <= b->maxx; k++)
            if (point_in(c->l[k].p, b) != OUTSIDE)
                fail_msg("a lamp at (%lld, %lld) mm is in building b%zu", c->l[k].p.x / SCALE,
                         c->l[k].p.y / SCALE, i);
    }
    return touching;
}

/* Does a have the edge (p, q) in either direction? */
static int has_edge(const bld *a, pt p, pt q)
{
    int i;
    for (i = 0; i < a->n; i++) {
        pt u = a->v[i], v = a->v[(i + 1) % a->n];
        if ((u.x == p.x && u.y == p.y && v.x == q.x && v.y == q.y) ||
            (u.x == q.x && u.y == q.y && v.x == p.x && v.y == p.y))
            return 1;
    }
    return 0;
}

/* Number of edges of a that are also edges of b. */
static int shared_edges(const bld *a, const bld *b)
{
    int i, s = 0;
    for (i = 0; i < a->n; i++)
        s += has_edge(b, a->v[i], a->v[(i + 1) % a->n]);
    return s;
}

/* ---- tests: arguments and streaming ------------------------------------ */

static void test_bad_arguments(void **state)
{
    buf b;
    (void)state;
    memset(&b, 0, sizeof b);
    assert_int_equal(plx_gen_city(NULL, 2, 2, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("", 2, 2, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("Grid", 2, 2, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("manhattan", 2, 2, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 0, 2, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 2, 0, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("eixample", -1, 2, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("oldtown", 1001, 2, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("oldtown", 2, 1001, 1, buf_write, &b), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 2, 2, 1, NULL, &b), PLX_E_INVALID);
    assert_int_equal(b.calls, 0); /* nothing written on a refusal */
    /* the limits themselves are accepted */
    assert_int_equal(plx_gen_city("grid", 1000, 1, 1, buf_write, &b), PLX_OK);
    assert_int_equal(plx_gen_city("grid", 1, 1000, 1, buf_write, &b), PLX_OK);
    free(b.data);
}

static int refuse(void *ctx, const char *data, size_t len);

static void test_null_ctx(void **state)
{
    (void)state;
    /* ctx is passed through untouched: NULL is fine */
    assert_int_equal(plx_gen_city("grid", 1, 1, 1, NULL, NULL), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 3, 3, 1, refuse, NULL), PLX_E_IO);
}

/* A write that fails at call k stops the generator: PLX_E_IO, no further
 * calls, and what was accepted is a prefix of the full output. */
static void test_write_failure(void **state)
{
    static const char *const styles[] = { "grid", "eixample", "oldtown" };
    size_t s;
    (void)state;
    for (s = 0; s < 3; s++) {
        buf full = gen(styles[s], 6, 5, 5);
        size_t k;
        assert_true(full.calls >= 2);
        for (k = 1; k <= full.calls; k++) {
            buf b;
            memset(&b, 0, sizeof b);
            b.fail_at = k;
            assert_int_equal(plx_gen_city(styles[s], 6, 5, 5, buf_write, &b), PLX_E_IO);
            assert_int_equal(b.calls, k);
            assert_true(b.len < full.len);
            if (b.len)
                assert_memory_equal(b.data, full.data, b.len);
            free(b.data);
        }
        free(full.data);
    }
}

static void test_determinism(void **state)
{
    static const char *const styles[] = { "grid", "eixample", "oldtown" };
    size_t s;
    (void)state;
    for (s = 0; s < 3; s++) {
        buf a = gen(styles[s], 7, 5, 42), b = gen(styles[s], 7, 5, 42), c = gen(styles[s], 7, 5, 43);
        assert_int_equal(a.len, b.len);
        assert_memory_equal(a.data, b.data, a.len);
        assert_true(a.len != c.len || memcmp(a.data, c.data, a.len) != 0);
        free(a.data);
        free(b.data);
        free(c.data);
    }
}

/* Text is well-formed: three decimals everywhere, negative values too. */
static void test_number_format(void **state)
{
    static const char *const styles[] = { "grid", "eixample", "oldtown" };
    size_t s;
    (void)state;
    for (s = 0; s < 3; s++) {
        buf b = gen(styles[s], 4, 3, 11);
        check_three_decimals(&b);
        if (s == 2)
            assert_non_null(strchr(b.data, '-')); /* jittered nodes below 0 */
        free(b.data);
    }
}

/* ---- tests: styles ------------------------------------------------------- */

static void test_grid(void **state)
{
    const int nx = 5, ny = 4;
    buf b = gen("grid", nx, ny, 3);
    city c;
    size_t i;
    (void)state;
    city_parse(&b, &c);
    assert_int_equal(c.nb, (size_t)(nx * ny));
    assert_int_equal(c.nl, (size_t)(2 * ((nx + 1) * ny + (ny + 1) * nx)));
    for (i = 0; i < c.nb; i++) {
        assert_int_equal(c.b[i].n, 4);
        assert_true(c.b[i].height >= 9.0 && c.b[i].height <= 40.0);
    }
    assert_int_equal(check_geometry(&c), 0); /* streets between all blocks */
    city_free(&c);
    free(b.data);
}

static void check_eixample_blocks(const city *c, int nblocks)
{
    int k, m, j;
    for (k = 0; k < nblocks; k++) {
        const bld *ring = &c->b[16 * k];
        long long minx = ring[0].minx, maxx = ring[0].maxx, miny = ring[0].miny, maxy = ring[0].maxy;
        pt centre;
        for (m = 0; m < 16; m++) {
            const bld *a = &ring[m];
            /* one exact shared wall with each ring neighbour, none with others */
            for (j = 0; j < 16; j++) {
                int want = (j == (m + 1) % 16 || j == (m + 15) % 16) ? 1 : 0;
                if (j != m)
                    assert_int_equal(shared_edges(a, &ring[j]), want);
            }
            if (a->minx < minx) minx = a->minx;
            if (a->maxx > maxx) maxx = a->maxx;
            if (a->miny < miny) miny = a->miny;
            if (a->maxy > maxy) maxy = a->maxy;
        }
        /* the block is 113 m square */
        assert_true(maxx - minx == 113000LL * SCALE && maxy - miny == 113000LL * SCALE);
        centre.x = (minx + maxx) / 2;
        centre.y = (miny + maxy) / 2;
        /* the courtyard centre is open, and the ring closes around it: rays
         * east, north, west and south each meet a building of the block */
        for (m = 0; m < 16; m++)
            assert_int_equal(point_in(centre, &ring[m]), OUTSIDE);
        for (j = 0; j < 4; j++) {
            int hit = 0;
            long long step;
            for (step = 1; step <= 60 && !hit; step++) {
                pt q = centre;
                long long d = step * 1000LL * SCALE;
                if (j == 0) q.x += d;
                else if (j == 1) q.y += d;
                else if (j == 2) q.x -= d;
                else q.y -= d;
                for (m = 0; m < 16 && !hit; m++)
                    hit = point_in(q, &ring[m]) == INSIDE;
            }
            assert_true(hit);
        }
    }
}

static void test_eixample_small(void **state)
{
    buf b = gen("eixample", 3, 2, 9);
    city c;
    size_t i, touching;
    (void)state;
    city_parse(&b, &c);
    assert_int_equal(c.nb, 3 * 2 * 16);
    for (i = 0; i < c.nb; i++)
        assert_true(c.b[i].n >= 4 && c.b[i].n <= 6);
    touching = check_geometry(&c);
    assert_true(touching >= 16 * 6); /* at least the ring walls */
    check_eixample_blocks(&c, 6);
    city_free(&c);
    free(b.data);
}

static void test_eixample_30(void **state)
{
    buf b = gen("eixample", 30, 30, 1);
    city c;
    size_t i, levels = 0, corners = 0;
    double hmin = 1e9, hmax = 0, zmin = 1e9, zmax = 0;
    (void)state;
    city_parse(&b, &c);
    assert_int_equal(c.nb, 14400);
    assert_true(c.nl >= 15000 && c.nl <= 25000);
    for (i = 0; i < c.nb; i++) {
        const bld *a = &c.b[i];
        assert_true(a->n >= 4 && a->n <= 6);
        corners += a->n == 6;
        levels += (size_t)a->has_levels;
        if (a->height < hmin) hmin = a->height;
        if (a->height > hmax) hmax = a->height;
    }
    assert_int_equal(corners, 4 * 900);
    assert_true(levels > 1000 && levels < c.nb - 1000); /* both properties */
    assert_true(hmin >= 15.0 && hmax <= 28.0);
    for (i = 0; i < c.nl; i++) {
        if (c.l[i].z < zmin) zmin = c.l[i].z;
        if (c.l[i].z > zmax) zmax = c.l[i].z;
    }
    assert_true(zmin >= 6.0 && zmax <= 9.0);
    if (!quick())
        check_geometry(&c);
    city_free(&c);
    free(b.data);
}

static void check_oldtown(int nx, int ny, uint64_t seed, double lo, double hi)
{
    buf b = gen("oldtown", nx, ny, seed);
    city c;
    size_t i, j, reflex = 0, levels = 0, walls = 0;
    double hmin = 1e9, hmax = 0, zmin = 1e9, zmax = 0;
    city_parse(&b, &c);
    assert_true((double)c.nb >= lo * nx * ny && (double)c.nb <= hi * nx * ny);
    for (i = 0; i < c.nb; i++) {
        reflex += n_reflex(&c.b[i]) > 0;
        levels += (size_t)c.b[i].has_levels;
        if (c.b[i].height < hmin) hmin = c.b[i].height;
        if (c.b[i].height > hmax) hmax = c.b[i].height;
    }
    for (i = 0; i < c.nl; i++) {
        if (c.l[i].z < zmin) zmin = c.l[i].z;
        if (c.l[i].z > zmax) zmax = c.l[i].z;
    }
    /* houses sharing an exact wall: neighbours in output order */
    for (i = 0; i + 1 < c.nb; i++)
        walls += shared_edges(&c.b[i], &c.b[i + 1]) == 1;
    assert_true(reflex > c.nb / 5);   /* L, U and Z shapes */
    assert_true(walls > c.nb / 20);   /* some touch */
    assert_true(levels > 0 && levels < c.nb);
    assert_true(hmin >= 4.0 && hmax <= 30.0 && hmin < 6.0 && hmax > 24.0);
    assert_true(zmin >= 3.0 && zmax <= 12.0 && zmin < 4.0 && zmax > 11.0);
    assert_true(c.nl >= c.nb);
    if (!quick() || c.nb < 2000)
        check_geometry(&c);
    /* every building is more than one wall: only split pairs share walls */
    for (i = 0; i < c.nb && c.nb < 2000; i++)
        for (j = i + 2; j < c.nb; j++)
            assert_int_equal(shared_edges(&c.b[i], &c.b[j]), 0);
    city_free(&c);
    free(b.data);
}

static void test_oldtown_small(void **state)
{
    (void)state;
    check_oldtown(12, 12, 2, 0.8, 1.2);
    check_oldtown(20, 7, 99, 0.8, 1.2);
}

static void test_oldtown_110(void **state)
{
    (void)state;
    check_oldtown(110, 110, 1, 0.95, 1.05);
}

static void test_single_block(void **state)
{
    static const char *const styles[] = { "grid", "eixample", "oldtown" };
    size_t s;
    (void)state;
    for (s = 0; s < 3; s++) {
        buf b = gen(styles[s], 1, 1, 0);
        city c;
        city_parse(&b, &c);
        assert_true(c.nl > 0);
        check_geometry(&c);
        city_free(&c);
        free(b.data);
    }
}

/* ---- tests through the engine: the output loads cleanly -------------------- */

static int quick(void)
{
    return getenv("PLX_TEST_QUICK") != NULL;
}

static void load_info(const buf *t, plx_scene_info *si, uint32_t *warnings)
{
    void *block;
    plx_engine *e = fixture_engine_cfg((size_t)512 << 20, NULL, &block);
    assert_int_equal(plx_load_geojson(e, t->data, t->len, "gen"), PLX_OK);
    assert_int_equal(plx_scene_info_get(e, si), PLX_OK);
    *warnings = plx_warning_count(e);
    fixture_done(e, block);
}

static void test_engine_eixample_30(void **state)
{
    buf t = gen("eixample", 30, 30, 1);
    plx_scene_info si;
    uint32_t w;
    (void)state;
    load_info(&t, &si, &w);
    assert_int_equal(si.buildings, 14400);
    assert_int_equal(si.blocks, 900);
    assert_int_equal(si.courtyards, 900);
    assert_int_equal(si.overlapping_pairs, 0);
    assert_true(si.lamps >= 15000 && si.lamps <= 25000);
    assert_int_equal(si.skipped_features + si.skipped_lamps, 0);
    assert_int_equal(w, 0);
    free(t.data);
}

static void test_engine_styles_valid(void **state)
{
    static const char *const styles[] = { "grid", "eixample", "oldtown" };
    size_t k;
    (void)state;
    for (k = 0; k < 3; k++) {
        buf t = gen(styles[k], 12, 9, 7);
        plx_scene_info si;
        uint32_t w;
        load_info(&t, &si, &w);
        if (w != 0 || si.skipped_features || si.skipped_lamps || si.overlapping_pairs)
            fail_msg("%s: %u warnings, %u skipped, %u lamps inside, %u overlaps", styles[k], w,
                     si.skipped_features, si.skipped_lamps, si.overlapping_pairs);
        assert_true(si.buildings > 0 && si.lamps > 0);
        if (k == 0)
            assert_int_equal(si.buildings, 12 * 9);
        free(t.data);
    }
}

static void test_engine_oldtown_110(void **state)
{
    buf t = gen("oldtown", 110, 110, 1);
    plx_scene_info si;
    uint32_t w;
    (void)state;
    load_info(&t, &si, &w);
    assert_true(si.buildings >= 11000 && si.buildings <= 13500);
    assert_int_equal(w, 0);
    assert_int_equal(si.overlapping_pairs, 0);
    assert_int_equal(si.skipped_features + si.skipped_lamps, 0);
    /* mixed heights around the default 12 m */
    assert_true(si.height_min < 12.0 && si.height_max > 12.0);
    free(t.data);
}

static int refuse(void *ctx, const char *data, size_t len)
{
    (void)ctx, (void)data, (void)len;
    return 1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_arguments),
        cmocka_unit_test(test_null_ctx),
        cmocka_unit_test(test_write_failure),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_number_format),
        cmocka_unit_test(test_grid),
        cmocka_unit_test(test_single_block),
        cmocka_unit_test(test_eixample_small),
        cmocka_unit_test(test_eixample_30),
        cmocka_unit_test(test_oldtown_small),
        cmocka_unit_test(test_oldtown_110),
        cmocka_unit_test(test_engine_eixample_30),
        cmocka_unit_test(test_engine_styles_valid),
        cmocka_unit_test(test_engine_oldtown_110),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
