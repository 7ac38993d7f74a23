/* test_atlas: the radiance atlas (src/render/texel.h, atlas.c, atlas_fill.c,
 * atlas_frame.c) against independent brute-force computations.
 *
 *  - texel codec: pack against a brute-force nearest-code search (every
 *    exponent tried), the documented error bounds, unpack against
 *    m 2^(e - 27), pack(unpack(t)) == t for canonical codes, monotonicity
 *    of each channel, the clamps (0, negatives, NaN, infinities,
 *    denormals, past TEXEL_MAX).
 *  - layout (eixample, Helsinki (lon/lat OSM), a hand-made scene): wall
 *    charts' corners and visible heights against a brute-force search of
 *    buildings with the same edge reversed; roof and underside charts on
 *    the footprint's box; spacing; every empty ground block sampled and
 *    found under ground footprints; every block inside one footprint
 *    found empty; tiles over every lamp's ground reach are fine; charts
 *    and blocks tile the value array; atlas_plan agrees; out of memory
 *    leaves the arena as it was.
 *  - vertex values: sites (atlas_vertex_site) against brute-force nearest
 *    boundary points; stored values against texel_pack of albedo / pi *
 *    E_ref (tests/ref/ref_light) at the site; then an indirect hook
 *    (smooth, not affine) filled on listed items only: values against the
 *    records interpolated independently.
 *  - frames: random cameras, every pixel recomputed in double (SPEC §5's
 *    ray, the hit on the pixel's surface plane, the chart coordinates,
 *    bilinear of the unpacked vertices) with an error bound derived from
 *    the frame's single-precision projective map; 2 workers give the same
 *    bytes; an atlas filled on demand (atlas_frame_missing) gives the same
 *    bytes.
 *  - determinism: 1 worker, 2 workers, items in random order: same bytes.
 *  - atlas_spacing_for: the returned spacing fits and the one a step
 *    finer does not.
 *
 * BUGS found by these tests (in commit f8951b5) are the tests named
 * test_bug_*: each is minimal, says what it shows, and fails where the
 * bug is (PLX_TEST_SKIP_KNOWN_BUGS=1 skips them). The other tests count
 * and print what those bugs touch without failing on it. PLX_TEST_QUICK=1
 * shortens the loops.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "fixture.h"
#include "base/engine.h"
#include "base/arena.h"
#include "light/light.h"
#include "light/illuminance.h"
#include "render/render.h"
#include "render/render_atlas.h"
#include "render/mesh.h"
#include "render/texel.h"
#include "render/atlas.h"
#include "render/atlas_fill.h"
#include "render/atlas_frame.h"
#include "ref_light.h"
#include "ref_scene.h"
#include "ref_indirect.h"
#include "photon/trace.h"
#include "photon/photon.h"
#include "photon/indirect.h"
#include "slow.h"

#define PI 3.14159265358979323846
#define MEM ((size_t)256 << 20)
#define EPSF (1.0 / 16777216.0) /* 2^-24: float's relative rounding */

/* ---- small tools ------------------------------------------------------------ */

typedef struct rng {
    uint64_t s;
} rng;

static uint64_t rnext(rng *r)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double runi(rng *r, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(rnext(r) >> 11) / 9007199254740992.0);
}

static uint32_t rpick(rng *r, uint32_t n)
{
    return (uint32_t)(rnext(r) % (uint64_t)n);
}

static int quick(void)
{
    return getenv("PLX_TEST_QUICK") != NULL;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* ---- scenes ------------------------------------------------------------------- */

/* A hand-made scene (metres): two buildings sharing an edge at different
 * heights (A, B); a wall with two stacked neighbours on its east side, the
 * lower listed first (W2, Q2, Q1); a courtyard (C); a raised building (R);
 * a wall 3 cm long (S); a building filling a ground block at 1 m exactly
 * (F) and one covering several blocks (G); a footprint with an acute
 * notch (N). Lamps of several colours around and inside the courtyard,
 * one under R. */
static const char *HAND =
    "{\"type\": \"FeatureCollection\", \"properties\": {\"units\": \"m\", \"ground_albedo\": 0.2},\n"
    " \"features\": [\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"A\", \"height\": 10, \"albedo\": 0.3},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[0,0],[10,0],[10,10],[0,10],[0,0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"B\", \"height\": 6, \"albedo\": 0.45},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[10,0],[20,0],[20,10],[10,10],[10,0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"W2\", \"height\": 20},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[30,20],[40,20],[40,30],[30,30],[30,20]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"Q2\", \"height\": 7},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[40,20],[50,20],[50,30],[40,30],[40,20]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"Q1\", \"height\": 10, \"min_height\": 7},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[40,20],[50,20],[50,30],[40,30],[40,20]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"C\", \"height\": 12, \"albedo\": 0.25},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[60,0],[90,0],[90,30],[60,30],[60,0]],\n"
    "      [[70,10],[70,20],[80,20],[80,10],[70,10]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"R\", \"height\": 8, \"min_height\": 3},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[0,30],[10,30],[10,40],[0,40],[0,30]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"S\", \"height\": 9},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[20,30],[28,30],[28,38],[20.03,38.01],[20,38],[20,30]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"F\", \"height\": 5},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[102,46],[110,46],[110,54],[102,54],[102,46]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"G\", \"height\": 15},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[101,61.5],[119,61.5],[119,80],[101,80],[101,61.5]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"N\", \"height\": 11},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[60,40],[90,40],[90,60],[76,60],[75,45],[74,60],[60,60],[60,40]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 6, \"intensity\": 2000, \"radius\": 30, \"color\": [1,1,1]},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [5, -6]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 5, \"intensity\": 1500, \"radius\": 30, \"color\": [1,0.6,0.3]},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [25, 15]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 7, \"intensity\": 3000, \"radius\": 35, \"color\": [0.8,0.9,1]},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [95, 45]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 6, \"intensity\": 1000, \"radius\": 25},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [75, 35]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 4, \"intensity\": 800, \"radius\": 20, \"color\": [0.5,1,0.5]},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [75, 15]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 1.5, \"intensity\": 500, \"radius\": 20},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [5, 35]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 8, \"intensity\": 2500, \"radius\": 40},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [45, 45]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 6, \"intensity\": 1200, \"radius\": 30},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [110, 58]}}\n"
    " ]}\n";

#define EIXAMPLE "fixtures/eixample-4x4.geojson"
#define HELSINKI "fixtures/helsinki-centre.geojson"

typedef struct world {
    const char *name;
    void *mem;
    plx_engine *e;
    const scene *s;
    const mesh *m;
} world;

static void world_open(world *w, const char *name, const char *path, const char *text)
{
    w->name = name;
    w->e = path ? fixture_file(path, MEM, &w->mem) : fixture_text(text, MEM, 0, &w->mem);
    assert_int_equal(eng_need(w->e, ENG_LIGHT, "test_atlas"), PLX_OK);
    assert_int_equal(eng_need_render(w->e), PLX_OK);
    w->s = w->e->sc;
    w->m = render_mesh(w->e->rd);
    assert_null(w->s->gimg); /* the ground albedo is the constant */
}

static void world_close(world *w)
{
    fixture_done(w->e, w->mem);
}

static atlas *make_atlas(world *w, double fine)
{
    atlas *A = NULL;
    assert_int_equal(atlas_create(&w->e->mem, w->s, w->m, fine, &A), PLX_OK);
    assert_non_null(A);
    return A;
}

/* ---- brute-force geometry ------------------------------------------------------ */

/* Where (x, y) lies relative to building b's footprint (REF_IN, REF_ON, REF_OUT). */
static int where_fp(const scene *s, uint32_t b, double x, double y)
{
    const double *bx = s->bld[b].box;
    if (x < bx[0] || x > bx[2] || y < bx[1] || y > bx[3])
        return REF_OUT;
    return ref_footprint_where(s, b, x, y);
}

/* The lowest building standing on the ground whose footprint holds (x, y)
 * strictly, -1 for none (every building tried). */
static int64_t solid_under(const scene *s, double x, double y)
{
    uint32_t b;
    for (b = 0; b < s->nbld; b++)
        if (s->bld[b].min_height == 0.0 && where_fp(s, b, x, y) == REF_IN)
            return b;
    return -1;
}

/* Whether (x, y) lies in the closed footprint of a building standing on the ground. */
static int under_closed(const scene *s, double x, double y)
{
    uint32_t b;
    for (b = 0; b < s->nbld; b++)
        if (s->bld[b].min_height == 0.0 && where_fp(s, b, x, y) != REF_OUT)
            return 1;
    return 0;
}

/* The closest point q of segment a-c to p, its distance. */
static double seg_near(vec2 a, vec2 c, double px, double py, double q[2])
{
    double ex = c.x - a.x, ey = c.y - a.y, l2 = ex * ex + ey * ey, t;
    t = l2 > 0.0 ? ((px - a.x) * ex + (py - a.y) * ey) / l2 : 0.0;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    q[0] = a.x + t * ex;
    q[1] = a.y + t * ey;
    return hypot(q[0] - px, q[1] - py);
}

/* Building b's nearest boundary points to p (every edge within 1e-9 m of
 * the minimum: ties), with the outward unit normal of their edge (right of
 * the ring's direction: outer rings run counter-clockwise, holes clockwise). */
typedef struct near_pt {
    double q[2], out[2];
} near_pt;

static int nearest_all(const scene *s, uint32_t b, double px, double py, near_pt *np, int cap, double *dmin)
{
    const scene_building *bd = &s->bld[b];
    double best = INFINITY, q[2];
    uint32_t r, k;
    int n = 0, pass;
    for (pass = 0; pass < 2; pass++)
        for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[r];
            for (k = 0; k < rg->count; k++) {
                vec2 a = s->pts[rg->first + k], c = s->pts[rg->first + (k + 1) % rg->count];
                double d = seg_near(a, c, px, py, q), l = hypot(c.x - a.x, c.y - a.y);
                if (pass == 0) {
                    best = d < best ? d : best;
                } else if (d <= best + 1e-9 && n < cap) {
                    np[n].q[0] = q[0];
                    np[n].q[1] = q[1];
                    np[n].out[0] = (c.y - a.y) / l;
                    np[n].out[1] = -(c.x - a.x) / l;
                    n++;
                }
            }
        }
    *dmin = best;
    return n;
}

/* Distance from (x, y) to building b's rings. */
static double boundary_dist(const scene *s, uint32_t b, double x, double y)
{
    near_pt np[1];
    double d;
    (void)nearest_all(s, b, x, y, np, 1, &d);
    return d;
}

/* ---- charts as a list -------------------------------------------------------------- */

typedef struct citem {
    atlas_chart c;
    uint32_t item, sid;
} citem;

typedef struct clist {
    citem *it;
    uint32_t n;
    uint32_t *kind[5], nkind[5]; /* indices into it by ATLAS_* kind */
} clist;

static void clist_make(const atlas *A, clist *L)
{
    uint32_t k, t, b, cap = A->nsurf + A->gx * A->gy * ATLAS_TB * ATLAS_TB + 1;
    memset(L, 0, sizeof *L);
    L->it = malloc(cap * sizeof *L->it);
    assert_non_null(L->it);
    for (k = 0; k < A->nsurf; k++)
        if (A->chart[k].kind != ATLAS_NONE) {
            L->it[L->n].c = A->chart[k];
            L->it[L->n].item = k;
            L->it[L->n].sid = k + 2u;
            L->n++;
        }
    for (t = 0; t < A->gx * A->gy; t++)
        for (b = 0; b < ATLAS_TB * ATLAS_TB; b++) {
            atlas_chart c;
            atlas_ground_block(A, t % A->gx, t / A->gx, b % ATLAS_TB, b / ATLAS_TB, &c);
            if (c.kind != ATLAS_GROUND)
                continue;
            L->it[L->n].c = c;
            L->it[L->n].item = atlas_block_item(A, t, b);
            L->it[L->n].sid = MESH_SURF_GROUND;
            L->n++;
        }
    for (k = 0; k < 5; k++) {
        L->kind[k] = malloc((L->n + 1) * sizeof(uint32_t));
        assert_non_null(L->kind[k]);
    }
    for (k = 0; k < L->n; k++) {
        uint32_t kd = L->it[k].c.kind;
        L->kind[kd][L->nkind[kd]++] = k;
    }
}

static void clist_free(clist *L)
{
    int k;
    free(L->it);
    for (k = 0; k < 5; k++)
        free(L->kind[k]);
}

/* The chart's vertex (i, j) as the atlas stores it (a pointer for surfaces). */
static uint32_t tex_at(const atlas *A, const atlas_chart *c, uint32_t i, uint32_t j)
{
    return A->tex[c->first + (size_t)j * c->nu + i];
}

/* The state item it (of L) must have once filled: ATLAS_DARK when every
 * one of its values is 0, else ATLAS_FILLED. */
static int filled_state(const atlas *A, const atlas_chart *c)
{
    uint32_t i, j;
    for (j = 0; j < c->nv; j++)
        for (i = 0; i < c->nu; i++)
            if (tex_at(A, c, i, j) != 0)
                return ATLAS_FILLED;
    return ATLAS_DARK;
}

static uint8_t item_state(const atlas *A, uint32_t it)
{
    return it < A->nsurf ? A->cdone[it] : A->gdone[it - A->nsurf];
}

/* Every item of L in the state its values give; the dark ones counted. */
static long states_check(const atlas *A, const clist *L)
{
    long dark = 0;
    uint32_t k;
    for (k = 0; k < L->n; k++) {
        int want = filled_state(A, &L->it[k].c);
        assert_int_equal(item_state(A, L->it[k].item), want);
        dark += want == ATLAS_DARK;
    }
    return dark;
}

/* ---- 1. the texel codec --------------------------------------------------------- */

static double round_half_up(double x) /* x >= 0, below 2^52 */
{
    double f = floor(x);
    return x - f >= 0.5 ? f + 1.0 : f;
}

/* The nearest code by brute force: channels clamped (NaN and negatives 0,
 * at most TEXEL_MAX), the smallest exponent whose step holds the largest
 * channel in 9 bits after rounding, every channel rounded to that step. */
static uint32_t ref_pack(double r, double g, double b)
{
    double c[3], mx, step = 0.0;
    uint32_t m[3], e;
    int k;
    c[0] = r;
    c[1] = g;
    c[2] = b;
    for (k = 0; k < 3; k++) {
        if (!(c[k] > 0.0))
            c[k] = 0.0;
        if (c[k] > TEXEL_MAX)
            c[k] = TEXEL_MAX;
    }
    mx = fmax(c[0], fmax(c[1], c[2]));
    for (e = 0; e < 32; e++) {
        step = ldexp(1.0, (int)e - 27);
        if (round_half_up(mx / step) <= 511.0)
            break;
    }
    assert_true(e < 32);
    for (k = 0; k < 3; k++)
        m[k] = (uint32_t)round_half_up(c[k] / step);
    if (m[0] == 0 && m[1] == 0 && m[2] == 0)
        return 0u;
    return m[0] | (m[1] << 9) | (m[2] << 18) | (e << 27);
}

static double special_value(rng *r)
{
    static const double v[] = { 0.0, -0.0, -1.0, -1e300, 1e300, 8176.0, 8180.0, 8184.0, 8200.0, 1e30,
                                DBL_MIN, 4.9406564584124654e-324, 1e-310, 3.7252902984619141e-09 /* 2^-28 */,
                                3.7252902984619137e-09, 7.4505805969238281e-09 /* 2^-27 */, 1.9073486328125e-06 /* 2^-19 */,
                                1.0, 0.5, 511.5, 255.75 };
    uint32_t k = rpick(r, (uint32_t)(sizeof v / sizeof v[0]) + 3);
    if (k == sizeof v / sizeof v[0])
        return NAN;
    if (k == sizeof v / sizeof v[0] + 1)
        return INFINITY;
    if (k == sizeof v / sizeof v[0] + 2)
        return -INFINITY;
    return v[k];
}

/* A random channel: mostly positive over the whole range, sometimes at a
 * rounding boundary (m + 0.5 steps, or the next double either side). */
static double random_channel(rng *r, double other)
{
    uint32_t k = rpick(r, 20);
    double x;
    if (k == 0)
        return special_value(r);
    if (k == 1)
        return -runi(r, 0.0, 100.0);
    if (k <= 4 && other > 0.0 && isfinite(other))
        return other * runi(r, 0.0, 1.0); /* below another channel */
    if (k <= 7) { /* a half step */
        int e = (int)rpick(r, 32) - 27;
        x = ldexp(rpick(r, 512) + 0.5, e);
        k = rpick(r, 3);
        return k == 0 ? x : k == 1 ? nextafter(x, 0.0) : nextafter(x, INFINITY);
    }
    return ldexp(runi(r, 0.5, 1.0), (int)rpick(r, 52) - 38);
}

/* Whether t differs from the nearest code tr only by a channel just below
 * half a step (c / step == 0.5 - 2^-54) rounded up by floor(x + 0.5):
 * test_bug_texel_below_half. */
static int below_half_case(const double c[3], uint32_t t, uint32_t tr)
{
    double step;
    int k, n = 0;
    if ((t >> 27) != (tr >> 27))
        return 0;
    step = ldexp(1.0, (int)(t >> 27) - 27);
    for (k = 0; k < 3; k++) {
        uint32_t a = (t >> (9 * k)) & 511u, b = (tr >> (9 * k)) & 511u;
        if (a == b)
            continue;
        if (a != 1u || b != 0u || c[k] / step != nextafter(0.5, 0.0))
            return 0;
        n++;
    }
    return n > 0;
}

static void test_texel_codec(void **state)
{
    rng r = { 0x7e4e1ull };
    long n = quick() ? 300000 : 3000000, i, canon = 0, mono = 0, below_half = 0;
    double worst_rel = 0.0, worst_abs = 0.0;
    (void)state;
    for (i = 0; i < n; i++) {
        double c[3], cl[3], mx, step;
        float out[3];
        uint32_t t, tr;
        int k, kmax = 0;
        c[0] = random_channel(&r, 0.0);
        c[1] = random_channel(&r, c[0]);
        c[2] = random_channel(&r, c[1]);
        t = texel_pack(c[0], c[1], c[2]);
        tr = ref_pack(c[0], c[1], c[2]);
        if (t != tr && below_half_case(c, t, tr)) {
            below_half++; /* test_bug_texel_below_half */
            continue;
        }
        if (t != tr)
            printf("  texel_pack(%.17g, %.17g, %.17g) = %08x, nearest %08x\n", c[0], c[1], c[2], t, tr);
        assert_true(t == tr);
        texel_unpack(t, out);
        for (k = 0; k < 3; k++) {
            cl[k] = c[k] > 0.0 ? (c[k] > TEXEL_MAX ? TEXEL_MAX : c[k]) : 0.0;
            if (cl[k] > cl[kmax])
                kmax = k;
        }
        mx = cl[kmax];
        step = texel_scale(t);
        /* unpack is m 2^(e - 27) exactly */
        for (k = 0; k < 3; k++) {
            double m = (double)((t >> (9 * k)) & 511u);
            assert_true((double)out[k] == m * ldexp(1.0, (int)(t >> 27) - 27));
            assert_true(out[k] >= 0.0f && out[k] <= TEXEL_MAX);
        }
        if (mx < ldexp(1.0, -28)) {
            assert_true(t == 0u); /* below half the smallest step: black */
            continue;
        }
        /* every channel within half a step of the shared exponent */
        for (k = 0; k < 3; k++) {
            double err = fabs((double)out[k] - cl[k]);
            assert_true(err <= 0.5 * step);
            if (err / step > worst_abs)
                worst_abs = err / step;
        }
        /* the largest channel: 9 significant bits, relative error <= 1/512 */
        if (mx >= ldexp(1.0, -19)) {
            double rel = fabs((double)out[kmax] - mx) / mx;
            assert_true(rel <= 1.0 / 512.0);
            assert_true(((t >> (9 * kmax)) & 511u) >= 256u);
            if (rel > worst_rel)
                worst_rel = rel;
        }
    }
    /* canonical codes (largest mantissa >= 256, or exponent 0) come back */
    for (i = 0; i < n / 4; i++) {
        uint32_t t = (uint32_t)rnext(&r), mm;
        float out[3];
        mm = t & 511u;
        mm = ((t >> 9) & 511u) > mm ? (t >> 9) & 511u : mm;
        mm = ((t >> 18) & 511u) > mm ? (t >> 18) & 511u : mm;
        if (mm < 256u && (t >> 27) != 0u)
            t |= 256u << (9 * rpick(&r, 3));
        if ((t & 0x07ffffffu) == 0u)
            t = 0u;
        texel_unpack(t, out);
        assert_true(texel_pack(out[0], out[1], out[2]) == t);
        canon++;
    }
    /* each channel non-decreasing in its input, the others fixed */
    for (i = 0; i < (quick() ? 300 : 3000); i++) {
        double base[3], x[257], prev = -1.0;
        int ch = (int)rpick(&r, 3), k, q;
        for (k = 0; k < 3; k++)
            base[k] = random_channel(&r, 0.0);
        for (q = 0; q < 257; q++)
            x[q] = q == 0 ? 0.0 : random_channel(&r, base[(ch + 1) % 3]);
        for (q = 0; q < 257; q++) { /* insertion sort (NaN first, as 0) */
            int p = q;
            double v = x[q] == x[q] ? x[q] : -INFINITY;
            while (p > 0 && (x[p - 1] == x[p - 1] ? x[p - 1] : -INFINITY) > v) {
                x[p] = x[p - 1];
                p--;
            }
            x[p] = v;
        }
        for (q = 0; q < 257; q++) {
            float out[3];
            base[ch] = x[q];
            texel_unpack(texel_pack(base[0], base[1], base[2]), out);
            assert_true((double)out[ch] >= prev);
            prev = out[ch];
            mono++;
        }
    }
    /* the clamps */
    {
        float out[3];
        texel_unpack(texel_pack(1e30, NAN, -5.0), out);
        assert_true(out[0] == TEXEL_MAX && out[1] == 0.0f && out[2] == 0.0f);
        texel_unpack(texel_pack(INFINITY, INFINITY, 8176.0), out);
        assert_true(out[0] == TEXEL_MAX && out[1] == TEXEL_MAX && out[2] == TEXEL_MAX);
        assert_true(texel_pack(NAN, NAN, NAN) == 0u && texel_pack(-1.0, -0.0, 0.0) == 0u);
        assert_true(texel_pack(4.9406564584124654e-324, 1e-300, 3.7e-9) == 0u);
        texel_unpack(texel_pack(ldexp(1.0, -28), 0.0, 0.0), out);
        assert_true(out[0] == (float)ldexp(1.0, -27)); /* a tie rounds up */
    }
    printf("  texel: %ld random triples (worst: largest channel %.3g relative, others %.3f steps; %ld with a channel "
           "0.5 - 2^-54 steps rounded up: test_bug_texel_below_half), %ld canonical codes back, %ld "
           "monotone steps\n",
           n, worst_rel, worst_abs, below_half, canon, mono);
}

/* ---- 2. layout ----------------------------------------------------------------- */

/* The visible heights of the wall over edge pt of building b by brute force:
 * [lo, hi] less the heights of every other building with the same edge the
 * other way round; returns the number of visible intervals (written to
 * iv[2 k], iv[2 k + 1], at most 8), 0 when none has positive length. */
static int visible_heights(const scene *s, uint32_t b, vec2 p, vec2 q, double iv[16])
{
    double cut[64][2];
    int nc = 0, n = 0, k;
    uint32_t o, r, i;
    double z = s->bld[b].min_height, top = s->bld[b].height;
    for (o = 0; o < s->nbld; o++) {
        const double *bo = s->bld[o].box;
        if (o == b || bo[0] > fmax(p.x, q.x) || bo[2] < fmin(p.x, q.x) || bo[1] > fmax(p.y, q.y) ||
            bo[3] < fmin(p.y, q.y))
            continue;
        for (r = s->bld[o].ring_first; r < s->bld[o].ring_first + s->bld[o].ring_count; r++)
            for (i = 0; i < s->rings[r].count; i++) {
                vec2 u = s->pts[s->rings[r].first + i], v = s->pts[s->rings[r].first + (i + 1) % s->rings[r].count];
                if (u.x == q.x && u.y == q.y && v.x == p.x && v.y == p.y && nc < 64) {
                    cut[nc][0] = s->bld[o].min_height;
                    cut[nc][1] = s->bld[o].height;
                    nc++;
                }
            }
    }
    /* sweep up from z: the lowest cut holding z moves z to its top; else the next cut's bottom ends a piece */
    while (z < top) {
        int moved = 0;
        double next = top;
        for (k = 0; k < nc; k++)
            if (cut[k][0] <= z && cut[k][1] > z) {
                z = cut[k][1];
                moved = 1;
            }
        if (moved)
            continue;
        for (k = 0; k < nc; k++)
            if (cut[k][0] > z && cut[k][0] < next)
                next = cut[k][0];
        if (n < 8) {
            iv[2 * n] = z;
            iv[2 * n + 1] = next;
            n++;
        }
        z = next;
    }
    return n;
}

typedef struct layout_tally {
    long walls, hidden, cut, hull, roofs, unders, blocks, empty, inside_one, samples, tiles_fine, ground_reads;
    long stacked_bug; /* walls whose chart covers heights another solid hides (test_bug_stacked_neighbours) */
    double worst_corner, worst_corner_rel;
} layout_tally;

/* Corner (i, j) of chart c against the expected point X, within 1e-6 m
 * plus float's rounding of tu, tv and e (2^-24 relative each, times the
 * chart's extent 'ext'). */
static void check_corner(const atlas_chart *c, uint32_t i, uint32_t j, const double X[3], double ext,
                         layout_tally *t)
{
    double P[3], d;
    atlas_vertex_point(c, i, j, P);
    d = sqrt((P[0] - X[0]) * (P[0] - X[0]) + (P[1] - X[1]) * (P[1] - X[1]) + (P[2] - X[2]) * (P[2] - X[2]));
    if (d > t->worst_corner)
        t->worst_corner = d;
    if (d / ext > t->worst_corner_rel)
        t->worst_corner_rel = d / ext;
    if (!(d <= 1e-6 + 4.0 * EPSF * ext))
        printf("  corner (%u, %u) of a chart kind %d at (%.9f %.9f %.9f), expected (%.9f %.9f %.9f)\n", i, j,
               c->kind, P[0], P[1], P[2], X[0], X[1], X[2]);
    assert_true(d <= 1e-6 + 4.0 * EPSF * ext);
}

/* The grid along a side of length len at most 'step' apart: the fewest vertices. */
static void check_side(uint32_t n, float t, double len, double step)
{
    assert_true(n >= 2);
    assert_true((double)t <= step * (1.0 + 1e-6));
    if (len > 0.0)
        assert_true(fabs((double)t * (n - 1) - len) <= 1e-9 + 4.0 * EPSF * len);
    if (n > 2)
        assert_true(len / (double)(n - 2) > step * (1.0 - 1e-6)); /* one vertex fewer would not do */
}

/* Whether the closed square q lies strictly inside footprint b: no boundary
 * point in the square (edge against box, Liang-Barsky) and its centre in. */
static int square_inside(const scene *s, uint32_t b, const double q[4])
{
    const scene_building *bd = &s->bld[b];
    uint32_t r, k;
    if (where_fp(s, b, 0.5 * (q[0] + q[2]), 0.5 * (q[1] + q[3])) != REF_IN)
        return 0;
    for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++)
        for (k = 0; k < s->rings[r].count; k++) {
            vec2 a = s->pts[s->rings[r].first + k], c = s->pts[s->rings[r].first + (k + 1) % s->rings[r].count];
            double t0 = 0.0, t1 = 1.0, d[2] = { c.x - a.x, c.y - a.y }, p0[2] = { a.x, a.y };
            int ax, ok = 1;
            for (ax = 0; ax < 2 && ok; ax++) {
                double lo = q[ax], hi = q[ax + 2];
                if (d[ax] == 0.0) {
                    ok = p0[ax] >= lo && p0[ax] <= hi;
                } else {
                    double ta = (lo - p0[ax]) / d[ax], tb = (hi - p0[ax]) / d[ax], tmp;
                    if (ta > tb) {
                        tmp = ta;
                        ta = tb;
                        tb = tmp;
                    }
                    t0 = ta > t0 ? ta : t0;
                    t1 = tb < t1 ? tb : t1;
                    ok = t0 <= t1 + 1e-12;
                }
            }
            if (ok)
                return 0; /* the edge meets the closed square (or nearly) */
        }
    return 1;
}

static void layout_check(world *w, double fine, rng *r, layout_tally *t)
{
    const scene *s = w->s;
    arena_mark mk = arena_get_mark(&w->e->mem);
    atlas *A = make_atlas(w, fine);
    uint32_t b, k, tx, ty, bx, by;
    uint64_t nplan = 0, nfine = 0, todo = 0, sum = 0;
    size_t bytes;
    clist L;
    uint64_t *iv;
    double gb[4];
    assert_true(A->fine == fine && A->coarse == fine * ATLAS_COARSE && A->tile == fine * ATLAS_TILE);
    assert_true(A->nsurf == s->npts + 2u * s->nbld);
    /* walls */
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        double box[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        uint32_t rr;
        for (rr = bd->ring_first; rr < bd->ring_first + bd->ring_count; rr++)
            for (k = 0; k < s->rings[rr].count; k++) {
                uint32_t pt = s->rings[rr].first + k;
                vec2 p = s->pts[pt], q = s->pts[s->rings[rr].first + (k + 1) % s->rings[rr].count];
                const atlas_chart *c = &A->chart[pt];
                double vis[16], len = hypot(q.x - p.x, q.y - p.y), lo, hi, X[3], n[3], step;
                int nv = visible_heights(s, b, p, q, vis);
                if (rr == bd->ring_first) {
                    box[0] = fmin(box[0], p.x);
                    box[1] = fmin(box[1], p.y);
                    box[2] = fmax(box[2], p.x);
                    box[3] = fmax(box[3], p.y);
                }
                t->walls++;
                assert_ptr_equal(atlas_surface_chart(A, mesh_wall_id(s, pt)), c->kind == ATLAS_NONE ? NULL : c);
                if (nv == 0) {
                    assert_int_equal(c->kind, ATLAS_NONE);
                    t->hidden++;
                    continue;
                }
                lo = vis[0];
                hi = vis[2 * nv - 1];
                t->cut += lo != bd->min_height || hi != bd->height;
                t->hull += nv > 1;
                assert_int_equal(c->kind, ATLAS_WALL);
                assert_int_equal(c->bld, b);
                if (c->o[2] < lo - 1e-9 || c->o[2] + (c->nv - 1) * (double)c->tv > hi + 1e-6 + 4.0 * EPSF * hi) {
                    /* the chart reaches heights another building's solid hides */
                    t->stacked_bug++;
                    if (t->stacked_bug <= 3)
                        printf("  %s: wall %u of building %u: chart %.6g .. %.6g, visible %.6g .. %.6g "
                               "(test_bug_stacked_neighbours)\n",
                               w->name, pt, b, c->o[2], c->o[2] + (c->nv - 1) * (double)c->tv, lo, hi);
                    continue;
                }
                assert_true(fabs(c->o[2] - lo) <= 1e-9);
                step = c->fine ? A->fine : A->coarse;
                assert_int_equal(c->fine, mesh_lit(w->m, mesh_wall_id(s, pt)));
                check_side(c->nu, c->tu, len, step);
                check_side(c->nv, c->tv, hi - lo, step);
                X[0] = p.x;
                X[1] = p.y;
                X[2] = lo;
                check_corner(c, 0, 0, X, len + hi, t);
                X[2] = hi;
                check_corner(c, 0, c->nv - 1, X, len + hi, t);
                X[0] = q.x;
                X[1] = q.y;
                check_corner(c, c->nu - 1, c->nv - 1, X, len + hi, t);
                X[2] = lo;
                check_corner(c, c->nu - 1, 0, X, len + hi, t);
                atlas_chart_normal(c, n);
                assert_true(fabs(n[0] - (q.y - p.y) / len) <= 1e-6 && fabs(n[1] + (q.x - p.x) / len) <= 1e-6 &&
                            n[2] == 0.0);
            }
        /* roof and underside: the footprint's box */
        for (k = 0; k < 2; k++) {
            uint32_t sid = k == 0 ? mesh_roof_id(s, b) : mesh_under_id(s, b);
            const atlas_chart *c = &A->chart[sid - 2u];
            double X[3], n[3], step, ext = box[2] - box[0] + box[3] - box[1] + fabs(box[0]) + fabs(box[1]);
            assert_true(box[0] == bd->box[0] && box[1] == bd->box[1] && box[2] == bd->box[2] &&
                        box[3] == bd->box[3]);
            if (k == 1 && !(bd->min_height > 0.0)) {
                assert_int_equal(c->kind, ATLAS_NONE);
                assert_null(atlas_surface_chart(A, sid));
                continue;
            }
            assert_int_equal(c->kind, k == 0 ? ATLAS_ROOF : ATLAS_UNDER);
            assert_ptr_equal(atlas_surface_chart(A, sid), c);
            assert_int_equal(c->bld, b);
            t->roofs += k == 0;
            t->unders += k == 1;
            step = c->fine ? A->fine : A->coarse;
            assert_int_equal(c->fine, mesh_lit(w->m, sid));
            check_side(c->nu, c->tu, box[2] - box[0], step);
            check_side(c->nv, c->tv, box[3] - box[1], step);
            X[0] = box[0];
            X[1] = box[1];
            X[2] = k == 0 ? bd->height : bd->min_height;
            check_corner(c, 0, 0, X, ext, t);
            X[0] = box[2];
            X[1] = box[3];
            check_corner(c, c->nu - 1, c->nv - 1, X, ext, t);
            atlas_chart_normal(c, n);
            assert_true(n[0] == 0.0 && n[1] == 0.0 && n[2] == (k == 0 ? 1.0 : -1.0));
        }
    }
    /* the ground tiles cover Bounds and every lamp's ground reach */
    memcpy(gb, s->bounds, sizeof gb);
    for (k = 0; k < s->nlamps; k++) {
        const scene_lamp *l = &s->lamps[k];
        double rg;
        if (!(l->intensity > 0.0) || !(l->z < l->radius))
            continue;
        rg = sqrt(l->radius * l->radius - l->z * l->z);
        gb[0] = fmin(gb[0], l->x - rg);
        gb[1] = fmin(gb[1], l->y - rg);
        gb[2] = fmax(gb[2], l->x + rg);
        gb[3] = fmax(gb[3], l->y + rg);
    }
    assert_true(A->g0[0] <= gb[0] && A->g0[1] <= gb[1]);
    assert_true(A->g0[0] + A->gx * A->tile >= gb[2] && A->g0[1] + A->gy * A->tile >= gb[3]);
    assert_true(A->g0[0] + (A->gx - 1) * A->tile < gb[2] + 1e-9 && A->g0[1] + (A->gy - 1) * A->tile < gb[3] + 1e-9);
    /* ground blocks */
    for (ty = 0; ty < A->gy; ty++)
        for (tx = 0; tx < A->gx; tx++) {
            uint32_t tile = ty * A->gx + tx, nb = A->gfine[tile] ? ATLAS_TB : 1;
            double step = A->gfine[tile] ? A->fine : A->coarse, tq[4];
            tq[0] = A->g0[0] + tx * A->tile;
            tq[1] = A->g0[1] + ty * A->tile;
            tq[2] = tq[0] + A->tile;
            tq[3] = tq[1] + A->tile;
            /* a tile some lamp's ground reach disk meets is fine */
            for (k = 0; k < s->nlamps && !A->gfine[tile]; k++) {
                const scene_lamp *l = &s->lamps[k];
                double rg, dx, dy;
                if (!(l->intensity > 0.0) || !(l->z < l->radius))
                    continue;
                rg = sqrt(l->radius * l->radius - l->z * l->z);
                dx = fmax(0.0, fmax(tq[0] - l->x, l->x - tq[2]));
                dy = fmax(0.0, fmax(tq[1] - l->y, l->y - tq[3]));
                assert_false(dx * dx + dy * dy < rg * rg * (1.0 - 1e-12));
            }
            t->tiles_fine += A->gfine[tile];
            for (by = 0; by < ATLAS_TB; by++)
                for (bx = 0; bx < ATLAS_TB; bx++) {
                    uint32_t first = A->gfirst[(size_t)tile * ATLAS_TB * ATLAS_TB + by * ATLAS_TB + bx];
                    double q[4];
                    atlas_chart c;
                    if (bx >= nb || by >= nb) {
                        assert_true(first == ATLAS_NOVERT); /* a coarse tile has one block */
                        continue;
                    }
                    q[0] = tq[0] + bx * ATLAS_BLOCK * step;
                    q[1] = tq[1] + by * ATLAS_BLOCK * step;
                    q[2] = q[0] + ATLAS_BLOCK * step;
                    q[3] = q[1] + ATLAS_BLOCK * step;
                    atlas_ground_block(A, tx, ty, bx, by, &c);
                    t->blocks++;
                    if (first == ATLAS_NOVERT) {
                        /* empty: every point of it under a ground footprint */
                        int p, np = quick() ? 24 : 96;
                        assert_int_equal(c.kind, ATLAS_NONE);
                        t->empty++;
                        for (p = 0; p < np + 5; p++) {
                            double x = p < 4 ? q[(p & 1) ? 2 : 0] : p == 4 ? 0.5 * (q[0] + q[2]) : runi(r, q[0], q[2]);
                            double y = p < 4 ? q[(p & 2) ? 3 : 1] : p == 4 ? 0.5 * (q[1] + q[3]) : runi(r, q[1], q[3]);
                            if (!under_closed(s, x, y))
                                printf("  %s: empty block (%u %u) of tile (%u %u): (%.9f, %.9f) under no footprint\n",
                                       w->name, bx, by, tx, ty, x, y);
                            assert_true(under_closed(s, x, y));
                            t->samples++;
                        }
                    } else {
                        /* not empty: not inside one footprint */
                        uint32_t o;
                        assert_int_equal(c.kind, ATLAS_GROUND);
                        assert_true(c.first == first && c.nu == ATLAS_BLOCK + 1 && c.nv == ATLAS_BLOCK + 1);
                        assert_true(fabs(c.o[0] - q[0]) <= 1e-9 * (1.0 + fabs(q[0])) &&
                                    fabs(c.o[1] - q[1]) <= 1e-9 * (1.0 + fabs(q[1])) && c.o[2] == 0.0);
                        assert_true(c.tu == (float)step && c.tv == (float)step && c.fine == A->gfine[tile]);
                        for (o = 0; o < s->nbld; o++)
                            if (s->bld[o].min_height == 0.0 && s->bld[o].box[0] < q[0] && s->bld[o].box[1] < q[1] &&
                                s->bld[o].box[2] > q[2] && s->bld[o].box[3] > q[3] && square_inside(s, o, q)) {
                                printf("  %s: block (%.9f %.9f %.9f %.9f) inside building %u holds vertices\n", w->name,
                                       q[0], q[1], q[2], q[3], o);
                                fail();
                            }
                    }
                }
        }
    /* blocks found inside one footprint (for the hand-made scene's G) */
    for (ty = 0; ty < A->gy; ty++)
        for (tx = 0; tx < A->gx; tx++)
            for (by = 0; by < ATLAS_TB; by++)
                for (bx = 0; bx < ATLAS_TB; bx++) {
                    atlas_chart c;
                    double q[4], step;
                    uint32_t o;
                    if (!A->gfine[ty * A->gx + tx] && (bx || by))
                        continue;
                    step = A->gfine[ty * A->gx + tx] ? A->fine : A->coarse;
                    q[0] = A->g0[0] + tx * A->tile + bx * ATLAS_BLOCK * step;
                    q[1] = A->g0[1] + ty * A->tile + by * ATLAS_BLOCK * step;
                    q[2] = q[0] + ATLAS_BLOCK * step;
                    q[3] = q[1] + ATLAS_BLOCK * step;
                    atlas_ground_block(A, tx, ty, bx, by, &c);
                    for (o = 0; o < s->nbld; o++)
                        if (s->bld[o].min_height == 0.0 && s->bld[o].box[0] < q[0] && s->bld[o].box[1] < q[1] &&
                            s->bld[o].box[2] > q[2] && s->bld[o].box[3] > q[3] && square_inside(s, o, q)) {
                            t->inside_one++;
                            break;
                        }
                }
    /* atlas_ground_chart at random points: the block holding the point */
    for (k = 0; k < (quick() ? 2000u : 20000u); k++) {
        double x = runi(r, A->g0[0] - 10.0, A->g0[0] + A->gx * A->tile + 10.0);
        double y = runi(r, A->g0[1] - 10.0, A->g0[1] + A->gy * A->tile + 10.0), fx, fy, step;
        atlas_chart c;
        int got = atlas_ground_chart(A, x, y, &c);
        fx = floor((x - A->g0[0]) / A->tile);
        fy = floor((y - A->g0[1]) / A->tile);
        if (fx < 0.0 || fy < 0.0 || fx >= A->gx || fy >= A->gy) {
            assert_int_equal(got, 0);
            continue;
        }
        step = A->gfine[(uint32_t)fy * A->gx + (uint32_t)fx] ? A->fine : A->coarse;
        if (got) {
            double side = ATLAS_BLOCK * step;
            assert_int_equal(c.kind, ATLAS_GROUND);
            assert_true(x >= c.o[0] - 1e-9 && x <= c.o[0] + side + 1e-9 && y >= c.o[1] - 1e-9 &&
                        y <= c.o[1] + side + 1e-9);
            t->ground_reads++;
        } else {
            assert_true(under_closed(s, x, y)); /* an empty block: under footprints */
        }
    }
    /* the charts and blocks tile tex: no gap, no overlap */
    clist_make(A, &L);
    iv = malloc((L.n + 1) * sizeof *iv);
    assert_non_null(iv);
    for (k = 0; k < L.n; k++) {
        iv[k] = ((uint64_t)L.it[k].c.first << 24) | k;
        nfine += L.it[k].c.fine ? (uint64_t)L.it[k].c.nu * L.it[k].c.nv : 0;
        todo++;
    }
    {
        /* sort by first (shell sort: first in the high bits) */
        uint32_t gap, i2, j2;
        assert_true(L.n < (1u << 24));
        for (gap = L.n / 2; gap > 0; gap /= 2)
            for (i2 = gap; i2 < L.n; i2++)
                for (j2 = i2; j2 >= gap && iv[j2 - gap] > iv[j2]; j2 -= gap) {
                    uint64_t tmp = iv[j2];
                    iv[j2] = iv[j2 - gap];
                    iv[j2 - gap] = tmp;
                }
    }
    for (k = 0; k < L.n; k++) {
        const atlas_chart *c = &L.it[iv[k] & 0xffffffu].c;
        assert_true(c->first == sum); /* starts where the one before ends */
        sum += (uint64_t)c->nu * c->nv;
    }
    assert_true(sum == A->ntex);
    assert_true(nfine == A->ntex_fine);
    assert_true(todo == A->todo && A->key == 0 && A->with_ind == 0);
    free(iv);
    clist_free(&L);
    /* atlas_plan lays it out alike */
    bytes = atlas_plan(&w->e->mem, s, w->m, fine, &nplan);
    assert_true(nplan == A->ntex && bytes == A->bytes);
    arena_release(&w->e->mem, &mk);
}

static void test_layout(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    static const struct {
        const char *name, *path;
        double fine[3];
    } sc[3] = { { "hand", NULL, { 1.0, 0.7, 0.37 } },
                { "eixample", EIXAMPLE, { 1.3, 0.5, 2.9 } },
                { "helsinki", HELSINKI, { 2.0, 0.9, 4.1 } } };
    rng r = { 0x1a70u };
    int k, f;
    (void)state;
    for (k = 0; k < 3; k++) {
        world w;
        double t0 = now_s();
        world_open(&w, sc[k].name, sc[k].path, HAND);
        for (f = 0; f < (quick() ? 2 : 3); f++) {
            layout_tally t;
            memset(&t, 0, sizeof t);
            layout_check(&w, sc[k].fine[f], &r, &t);
            printf("  %s at %.2f m: %ld walls (%ld hidden whole, %ld cut, %ld with a middle hidden), %ld roofs, %ld "
                   "undersides, %ld blocks (%ld empty, %ld points sampled in them; %ld inside one footprint), %ld fine "
                   "tiles, worst corner %.2g m (%.2g of the extent), %ld walls over hidden heights, %.2f s\n",
                   sc[k].name, sc[k].fine[f], t.walls, t.hidden, t.cut, t.hull, t.roofs, t.unders, t.blocks, t.empty,
                   t.samples, t.inside_one, t.tiles_fine, t.worst_corner, t.worst_corner_rel, t.stacked_bug,
                   now_s() - t0);
            if (k == 0) {
                assert_true(t.hidden >= 1 && t.cut >= 2 && t.unders == 2 && t.inside_one >= 1);
                assert_true(t.empty >= t.inside_one && t.empty >= 1);
            }
            assert_true(t.walls == (long)w.s->npts && t.roofs == (long)w.s->nbld);
            assert_true(t.stacked_bug == 0 || k > 0); /* the fixtures: reported, see test_bug_stacked_neighbours */
        }
        world_close(&w);
    }
}

/* atlas_create_counted with atlas_plan's count lays out the atlas
 * atlas_create does (charts, ground blocks, sizes), and a count that is
 * not that layout's is refused with the arena where it was. */
static void test_create_counted(void **state)
{
    if (quick()) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    world w;
    atlas *A = NULL, *B = NULL;
    uint64_t n = 0;
    arena_mark m0, m1;
    size_t nb;
    int f;
    (void)state;
    for (f = 0; f < 2; f++) {
        world_open(&w, f ? "helsinki" : "eixample", f ? HELSINKI : EIXAMPLE, NULL);
        assert_true(atlas_plan(&w.e->mem, w.s, w.m, 1.5, &n) != SIZE_MAX && n > 0);
        m0 = arena_get_mark(&w.e->mem);
        assert_int_equal(atlas_create_counted(&w.e->mem, w.s, w.m, 1.5, n + 1, &B), PLX_E_INVALID);
        m1 = arena_get_mark(&w.e->mem);
        assert_true(m0.lo == m1.lo && m0.hi == m1.hi);
        A = make_atlas(&w, 1.5);
        assert_int_equal(atlas_create_counted(&w.e->mem, w.s, w.m, 1.5, n, &B), PLX_OK);
        nb = (size_t)A->gx * A->gy;
        assert_true(A->ntex == n && B->ntex == n && A->bytes == B->bytes && A->ntex_fine == B->ntex_fine);
        assert_true(A->gx == B->gx && A->gy == B->gy && A->nsurf == B->nsurf);
        assert_memory_equal(A->chart, B->chart, A->nsurf * sizeof(atlas_chart));
        assert_memory_equal(A->gfirst, B->gfirst, nb * 4 * ATLAS_TB * ATLAS_TB);
        assert_memory_equal(A->gfine, B->gfine, nb);
        world_close(&w);
    }
}

/* atlas_create: invalid arguments; out of memory leaves the arena as it was. */
static void test_create_errors(void **state)
{
    world w;
    atlas *A = NULL;
    size_t size, need;
    int nomem = 0, ok = 0;
    (void)state;
    world_open(&w, "hand", NULL, HAND);
    assert_int_equal(atlas_create(&w.e->mem, w.s, w.m, 0.0, &A), PLX_E_INVALID);
    assert_int_equal(atlas_create(&w.e->mem, w.s, w.m, -1.0, &A), PLX_E_INVALID);
    assert_int_equal(atlas_create(&w.e->mem, w.s, w.m, NAN, &A), PLX_E_INVALID);
    assert_int_equal(atlas_create(&w.e->mem, w.s, w.m, INFINITY, &A), PLX_E_INVALID);
    assert_int_equal(atlas_create(&w.e->mem, NULL, w.m, 1.0, &A), PLX_E_INVALID);
    assert_int_equal(atlas_create(&w.e->mem, w.s, NULL, 1.0, &A), PLX_E_INVALID);
    assert_int_equal(atlas_create(&w.e->mem, w.s, w.m, 1.0, NULL), PLX_E_INVALID);
    need = atlas_plan(&w.e->mem, w.s, w.m, 1.0, NULL);
    assert_true(need != SIZE_MAX);
    for (size = 1024; size < 4 * need + (1u << 20); size = size * 5 / 4) {
        void *buf = malloc(size);
        arena a;
        arena_mark m0, m1;
        plx_status st;
        int p;
        assert_non_null(buf);
        arena_init(&a, buf, size);
        m0 = arena_get_mark(&a);
        st = atlas_create(&a, w.s, w.m, 1.0, &A);
        m1 = arena_get_mark(&a);
        if (st == PLX_OK) {
            ok++;
            assert_true(A->ntex > 0 && (size_t)((char *)A->tex - (char *)buf) < size);
        } else {
            assert_int_equal(st, PLX_E_NOMEM);
            nomem++;
            assert_true(m0.lo == m1.lo && m0.hi == m1.hi);
            for (p = 0; p < PLX_PART_COUNT; p++)
                assert_true(m0.used[p] == m1.used[p]);
        }
        free(buf);
    }
    assert_true(nomem > 5 && ok > 0);
    world_close(&w);
}

/* ---- 3. vertex values ------------------------------------------------------------ */

/* The nearest point to (x, y) among the closest points of every ground
 * footprint's edges moved 1 mm out along the edge's outward normal that
 * lies strictly inside no solid (visible ground), by trying them all;
 * returns its distance (INFINITY: none, Q = (x, y)). */
static double visible_site(const scene *s, double x, double y, double Q[3])
{
    double best = INFINITY, q[2];
    uint32_t b, r, k;
    Q[0] = x;
    Q[1] = y;
    Q[2] = 0.0;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        if (bd->min_height != 0.0)
            continue;
        for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++)
            for (k = 0; k < s->rings[r].count; k++) {
                vec2 a = s->pts[s->rings[r].first + k], c = s->pts[s->rings[r].first + (k + 1) % s->rings[r].count];
                double l = hypot(c.x - a.x, c.y - a.y), px, py, d;
                (void)seg_near(a, c, x, y, q);
                px = q[0] + 1e-3 * (c.y - a.y) / l;
                py = q[1] - 1e-3 * (c.x - a.x) / l;
                d = hypot(px - x, py - y);
                if (!(d < best) || solid_under(s, px, py) >= 0)
                    continue;
                best = d;
                Q[0] = px;
                Q[1] = py;
            }
    }
    return best;
}

/* Checks atlas_vertex_site's point and normal for vertex (i, j) of c by
 * brute force (atlas_fill.h): the vertex on walls; on roofs and undersides
 * the vertex in the closed footprint, else one of the nearest points of
 * its rings; on the ground the vertex unless strictly inside a footprint
 * standing on the ground (the lowest such building), else one of that
 * footprint's nearest boundary points moved 1 mm along its edge's outward
 * normal, or, when all of those lie inside solids, the nearest point 1 mm
 * off any ground footprint's edge inside none (visible_site). Returns 0
 * when the site is the vertex, 1 when moved, 2 when moved into a solid
 * (test_bug_ground_site_in_solid), 3 when moved to visible_site. */
static int check_site(const scene *s, const atlas_chart *c, uint32_t i, uint32_t j, const double P[3],
                      const double n[3])
{
    double V[3], u = (double)i * c->tu, v = (double)j * c->tv, dmin;
    near_pt np[16];
    int k, m, ok = 0, all_in = 1;
    if (c->kind == ATLAS_WALL) {
        V[0] = c->o[0] + u * c->e[0];
        V[1] = c->o[1] + u * c->e[1];
        V[2] = c->o[2] + v;
        /* the edge's normal in double (atlas_fill.c's wall_site): the chart's float one within its rounding */
        assert_true(fabs(n[0] - (double)c->e[1]) <= 1e-6 && fabs(n[1] + (double)c->e[0]) <= 1e-6 && n[2] == 0.0);
    } else {
        V[0] = c->o[0] + u;
        V[1] = c->o[1] + v;
        V[2] = c->o[2];
        assert_true(n[0] == 0.0 && n[1] == 0.0 && n[2] == (c->kind == ATLAS_UNDER ? -1.0 : 1.0));
    }
    assert_true(P[2] == V[2]);
    if (c->kind == ATLAS_WALL) {
        /* the vertex moved onto its footprint edge's line (o + u e drifts
         * off it: test_rotated_walls_lit), at the same distance along it */
        uint32_t r;
        int found = 0;
        for (r = s->bld[c->bld].ring_first; r < s->bld[c->bld].ring_first + s->bld[c->bld].ring_count; r++)
            for (k = 0; k < (int)s->rings[r].count; k++) {
                vec2 a = s->pts[s->rings[r].first + (uint32_t)k],
                     q = s->pts[s->rings[r].first + ((uint32_t)k + 1) % s->rings[r].count];
                double ex = q.x - a.x, ey = q.y - a.y, len = hypot(ex, ey), t;
                if (!(len > 0.0) || a.x != c->o[0] || a.y != c->o[1] || fabs(n[0] - ey / len) > 1e-15 ||
                    fabs(n[1] + ex / len) > 1e-15)
                    continue; /* not this wall's edge: the one from the chart's origin, with its normal */
                found = 1;
                /* on the edge's line, at V's distance along it clamped to the edge */
                t = ((V[0] - a.x) * ex + (V[1] - a.y) * ey) / (len * len);
                t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
                assert_true(fabs((P[0] - a.x) * ey - (P[1] - a.y) * ex) / len <= 1e-9);
                assert_true(fabs(P[0] - (a.x + t * ex)) <= 1e-9 && fabs(P[1] - (a.y + t * ey)) <= 1e-9);
            }
        assert_true(found);
        return 0;
    }
    if (c->kind == ATLAS_ROOF || c->kind == ATLAS_UNDER) {
        if (where_fp(s, c->bld, V[0], V[1]) != REF_OUT) {
            assert_true(P[0] == V[0] && P[1] == V[1]);
            return 0;
        }
        m = nearest_all(s, c->bld, V[0], V[1], np, 16, &dmin);
        for (k = 0; k < m && !ok; k++)
            ok = fabs(P[0] - np[k].q[0]) <= 1e-9 && fabs(P[1] - np[k].q[1]) <= 1e-9;
        ok = ok || (dmin <= 1e-9 && P[0] == V[0] && P[1] == V[1]);
        if (!ok)
            printf("  roof site (%.12g %.12g) of vertex (%.12g %.12g), nearest boundary at %.12g\n", P[0], P[1], V[0],
                   V[1], dmin);
        assert_true(ok);
        return P[0] != V[0] || P[1] != V[1];
    }
    {
        int64_t b = solid_under(s, V[0], V[1]);
        if (b < 0) {
            if (!(P[0] == V[0] && P[1] == V[1]))
                printf("  ground site (%.12g %.12g) of vertex (%.12g %.12g) under no solid\n", P[0], P[1], V[0], V[1]);
            assert_true(P[0] == V[0] && P[1] == V[1]);
            return 0;
        }
        m = nearest_all(s, (uint32_t)b, V[0], V[1], np, 16, &dmin);
        if (dmin <= 1e-9 && P[0] == V[0] && P[1] == V[1])
            return 0; /* on the boundary within rounding: strict or not */
        for (k = 0; k < m; k++) {
            double cx = np[k].q[0] + 1e-3 * np[k].out[0], cy = np[k].q[1] + 1e-3 * np[k].out[1];
            int open = solid_under(s, cx, cy) < 0;
            all_in = all_in && !open;
            if (fabs(P[0] - cx) <= 1e-9 && fabs(P[1] - cy) <= 1e-9)
                ok = open ? 1 : 2; /* 2: inside a solid (test_bug_ground_site_in_solid) */
        }
        if (!ok && all_in) {
            /* every nearest point 1 mm out lies in a solid: the nearest
             * point 1 mm off any ground footprint's edge in none */
            double Q[3], dv = visible_site(s, V[0], V[1], Q);
            ok = fabs(hypot(P[0] - V[0], P[1] - V[1]) - dv) <= 1e-9 && solid_under(s, P[0], P[1]) < 0 ? 3 : 0;
        }
        if (!ok)
            printf("  ground site (%.12g %.12g) of vertex (%.12g %.12g) inside building %u, nearest boundary at %.12g\n",
                   P[0], P[1], V[0], V[1], (unsigned)b, dmin);
        assert_true(ok);
        return ok;
    }
}

/* Two packed values that differ by rounding only: each channel within one
 * step of the larger exponent (each is within half a step of nearly the
 * same value). */
static int texel_near(uint32_t a, uint32_t b)
{
    float x[3], y[3];
    double st = fmax(texel_scale(a), texel_scale(b));
    int k;
    texel_unpack(a, x);
    texel_unpack(b, y);
    for (k = 0; k < 3; k++)
        if (fabs((double)x[k] - (double)y[k]) > st * 1.0001)
            return 0;
    return 1;
}

/* Whether some lamp reaching P changes visibility by the reference when P
 * moves by up to 1e-6 m (SPEC §2 lets such points go either way). */
static int near_shadow_edge(const scene *s, const double P[3])
{
    static const double off[14][3] = { { 1, 0, 0 },      { -1, 0, 0 },      { 0, 1, 0 },      { 0, -1, 0 },
                                       { 0, 0, 1 },      { 0, 0, -1 },      { 0.7, 0.7, 0 },  { -0.7, 0.7, 0 },
                                       { 0.7, -0.7, 0 }, { -0.7, -0.7, 0 }, { 0.6, 0.6, 0.5 }, { -0.6, 0.6, -0.5 },
                                       { 0.6, -0.6, -0.5 }, { -0.6, -0.6, 0.5 } };
    uint32_t i;
    int k, q;
    for (i = 0; i < s->nlamps; i++) {
        double L[3] = { s->lamps[i].x, s->lamps[i].y, s->lamps[i].z }, X[3];
        int v0;
        if (hypot(hypot(L[0] - P[0], L[1] - P[1]), L[2] - P[2]) >= s->lamps[i].radius)
            continue;
        v0 = ref_segment_blocked(s, L, P);
        for (k = 0; k < 14; k++) {
            for (q = 0; q < 3; q++)
                X[q] = P[q] + 1e-6 * off[k][q];
            if (ref_segment_blocked(s, L, X) != v0)
                return 1;
        }
    }
    return 0;
}

static double site_albedo(const scene *s, const atlas_chart *c)
{
    return c->kind == ATLAS_GROUND ? s->ground_albedo : s->bld[c->bld].albedo;
}

/* A random vertex of a random chart: kinds in turn, lit (fine) charts
 * first, boundary rows and columns often. */
static const citem *pick_vertex(const clist *L, rng *r, uint32_t *i, uint32_t *j)
{
    static const int kinds[4] = { ATLAS_WALL, ATLAS_ROOF, ATLAS_UNDER, ATLAS_GROUND };
    const citem *it = NULL;
    int kd, tries;
    do {
        kd = kinds[rpick(r, 4)];
    } while (L->nkind[kd] == 0);
    for (tries = 0; tries < 20; tries++) {
        it = &L->it[L->kind[kd][rpick(r, L->nkind[kd])]];
        if (it->c.fine || rpick(r, 4) == 0)
            break;
    }
    *i = rpick(r, 4) == 0 ? (rpick(r, 2) ? it->c.nu - 1 : 0) : rpick(r, it->c.nu);
    *j = rpick(r, 4) == 0 ? (rpick(r, 2) ? it->c.nv - 1 : 0) : rpick(r, it->c.nv);
    return it;
}

typedef struct vtally {
    long n, exact, near, edge, lit, moved, in_solid, open, kinds[5];
} vtally;

/* The hook of the indirect fill: smooth and positive over the scene, not
 * affine (so the records' places matter), checking what it is given. */
typedef struct hook_ctx {
    const atlas *A;
    double c0[3], a[3], b[3][3], q[3];
    int dark;                 /* no indirect light on roofs and on the ground west of c0: dark
                                 charts and blocks where no lamp reaches, and cells between
                                 dark and lit points at the edges of the lamps' pools */
    long calls, bad;
} hook_ctx;

static void hook_value(const hook_ctx *h, const double P[3], double rgb[3])
{
    double d[3] = { P[0] - h->c0[0], P[1] - h->c0[1], P[2] - h->c0[2] };
    int k;
    for (k = 0; k < 3; k++)
        rgb[k] = h->a[k] + dot3(h->b[k], d) + h->q[k] * dot3(d, d);
}

static void hook_fn(void *user, const atlas_chart *c, uint32_t sid, const double P[3], const double n[3],
                    double rgb[3])
{
    hook_ctx *h = user;
    double cn[3];
    h->calls++;
    atlas_chart_normal(c, cn);
    if (c->kind == ATLAS_GROUND) {
        h->bad += sid != MESH_SURF_GROUND || P[2] != 0.0;
    } else {
        h->bad += sid < 2 || sid - 2u >= h->A->nsurf || c != &h->A->chart[sid - 2u];
        if (c->kind == ATLAS_WALL)
            h->bad += fabs(n[0] * (P[0] - c->o[0]) + n[1] * (P[1] - c->o[1])) > 1e-9 || P[2] < c->o[2] - 1e-9 ||
                      P[2] > c->o[2] + (c->nv - 1) * (double)c->tv + 1e-6;
        else
            h->bad += P[2] != c->o[2];
    }
    if (c->kind == ATLAS_WALL) /* on the wall's line (above) with the edge's normal in double: the chart's
                                  float one within its rounding */
        h->bad += !(fabs(n[0] - cn[0]) <= 1e-6 && fabs(n[1] - cn[1]) <= 1e-6 && n[2] == 0.0 &&
                    fabs(hypot(n[0], n[1]) - 1.0) <= 1e-15);
    else
        h->bad += n[0] != cn[0] || n[1] != cn[1] || n[2] != cn[2];
    hook_value(h, P, rgb);
    if (h->dark && (c->kind == ATLAS_ROOF || (c->kind == ATLAS_GROUND && P[0] < h->c0[0])))
        rgb[0] = rgb[1] = rgb[2] = 0.0;
}

static void hook_init(hook_ctx *h, const atlas *A, const scene *s, rng *r)
{
    double R = hypot(s->bounds[2] - s->bounds[0], s->bounds[3] - s->bounds[1]) + 200.0;
    int k, q;
    memset(h, 0, sizeof *h);
    h->A = A;
    h->c0[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
    h->c0[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
    h->c0[2] = 0.0;
    for (k = 0; k < 3; k++) {
        double sb = 0.0;
        for (q = 0; q < 3; q++) {
            h->b[k][q] = runi(r, -0.02, 0.02);
            sb += fabs(h->b[k][q]);
        }
        h->q[k] = runi(r, 0.0, 2e-4);
        h->a[k] = runi(r, 2.0, 10.0) + sb * R; /* positive everywhere within R */
    }
}

/* The records around vertex i along a side of n vertices, every k-th vertex
 * and the last (atlas_fill.h), by walking them. */
static void rec_span(uint32_t i, uint32_t n, uint32_t k, uint32_t *lo, uint32_t *hi, double *f)
{
    uint32_t a = 0, b;
    for (;;) {
        b = a + k < n - 1 ? a + k : n - 1;
        if (i <= b)
            break;
        a = b;
    }
    *lo = a;
    *hi = b;
    *f = (double)(i - a) / (double)(b - a);
}

/* E_indirect at vertex (i, j) as the records give it: the hook at the
 * sites of the four records around, bilinear. *moved: one of them moved. */
static void expect_ind(const atlas *A, light *lt, const hook_ctx *h, const atlas_chart *c, uint32_t i, uint32_t j,
                       double out[3], int *moved)
{
    uint32_t k = c->fine ? ATLAS_IND_EVERY : ATLAS_IND_EVERY / ATLAS_COARSE, ilo, ihi, jlo, jhi, q;
    double fu, fv, rec[4][3], P[3], n[3], V[3];
    k = k < 1 ? 1 : k;
    rec_span(i, c->nu, k, &ilo, &ihi, &fu);
    rec_span(j, c->nv, k, &jlo, &jhi, &fv);
    *moved = 0;
    for (q = 0; q < 4; q++) {
        uint32_t a = (q & 1) ? ihi : ilo, b = (q & 2) ? jhi : jlo;
        atlas_vertex_site(A, lt, c, a, b, P, n);
        atlas_vertex_point(c, a, b, V);
        *moved |= P[0] != V[0] || P[1] != V[1] || P[2] != V[2];
        hook_value(h, P, rec[q]);
    }
    for (q = 0; q < 3; q++)
        out[q] = (1.0 - fv) * ((1.0 - fu) * rec[0][q] + fu * rec[1][q]) + fv * ((1.0 - fu) * rec[2][q] + fu * rec[3][q]);
}

static void values_check(world *w, double fine, long nsamp, rng *r)
{
    const scene *s = w->s;
    arena_mark mk = arena_get_mark(&w->e->mem);
    atlas *A = make_atlas(w, fine);
    atlas_worker wk;
    clist L;
    vtally t;
    hook_ctx h;
    long k, nitems, dark;
    int pass;
    uint32_t *items, q;
    uint64_t todo0;
    double t0 = now_s(), t1;
    memset(&t, 0, sizeof t);
    memset(&wk, 0, sizeof wk);
    wk.lt = w->e->lt;
    wk.rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
    assert_non_null(wk.rec);
    assert_int_equal(atlas_fill(A, &wk, 1, NULL), PLX_OK);
    assert_true(A->todo == 0 && A->with_ind == 0);
    clist_make(A, &L);
    dark = states_check(A, &L); /* roofs no lamp reaches are dark */
    assert_true(dark > 0 && dark < (long)L.n);
    /* direct light: the stored value against the reference at the site */
    for (k = 0; k < nsamp; k++) {
        uint32_t i, j, got, want;
        const citem *it = pick_vertex(&L, r, &i, &j);
        const atlas_chart *c = &it->c;
        double P[3], n[3], E[3], a, v[3];
        int m;
        atlas_vertex_site(A, w->e->lt, c, i, j, P, n);
        m = check_site(s, c, i, j, P, n);
        t.moved += m != 0;
        t.in_solid += m == 2;
        t.open += m == 3;
        ref_illuminance_rgb(s, P, n, E);
        a = site_albedo(s, c);
        for (m = 0; m < 3; m++)
            v[m] = a / PI * E[m];
        want = texel_pack(v[0], v[1], v[2]);
        got = tex_at(A, c, i, j);
        t.n++;
        t.kinds[c->kind]++;
        t.lit += want != 0u;
        if (c->kind == ATLAS_GROUND && !c->fine)
            assert_true(want == 0u); /* coarse ground: no lamp reaches it */
        if (got == want) {
            t.exact++;
            continue;
        }
        if (texel_near(got, want)) {
            t.near++;
            continue;
        }
        if (near_shadow_edge(s, P)) {
            t.edge++;
            continue;
        }
        {
            float g[3], x[3];
            texel_unpack(got, g);
            texel_unpack(want, x);
            printf("  %s: vertex (%u, %u) of chart kind %d (item %u) at (%.12g %.12g %.12g) n (%g %g %g): stored %g %g "
                   "%g, reference %g %g %g\n",
                   w->name, i, j, c->kind, it->item, P[0], P[1], P[2], n[0], n[1], n[2], g[0], g[1], g[2], x[0], x[1],
                   x[2]);
        }
        fail();
    }
    t1 = now_s();
    printf("  %s at %.2f m: %ld vertices (walls %ld, roofs %ld, undersides %ld, ground %ld; %ld sites moved, %ld of "
           "them past a solid to open ground, %ld into a solid; %ld lit): %ld same bits, %ld one step apart, %ld at a "
           "shadow edge; %.2f s\n",
           w->name, fine, t.n, t.kinds[ATLAS_WALL], t.kinds[ATLAS_ROOF], t.kinds[ATLAS_UNDER], t.kinds[ATLAS_GROUND],
           t.moved, t.open, t.in_solid, t.lit, t.exact, t.near, t.edge, t1 - t0);
    assert_true(t.lit >= t.n / 10);
    assert_true(t.edge <= 3 + t.n / 100);
    assert_true(t.exact >= t.n * 9 / 10);

    /* indirect light on listed items only: a random quarter (at most 400),
     * a chart listed twice, a wall hidden whole and an empty block listed
     * too. Twice: an affine hook (then a vertex whose four records did not
     * move holds exactly albedo / pi (E_direct + hook(vertex)), bilinear
     * interpolation being exact for affine functions on a planar chart),
     * and a hook with a quadratic term (the records' places matter: the
     * value is the bilinear of the hook at the records' sites, computed
     * here by walking the records). */
    nitems = (long)(L.n / 4 < 400 ? L.n / 4 : 400) + 1;
    items = malloc((size_t)(nitems + 3) * sizeof *items);
    assert_non_null(items);
    for (k = 0; k < nitems; k++)
        items[k] = L.it[rpick(r, L.n)].item;
    items[nitems++] = items[0];
    for (q = 0; q < A->nsurf; q++)
        if (A->chart[q].kind == ATLAS_NONE) {
            items[nitems++] = q;
            break;
        }
    for (q = 0; q < A->gx * A->gy * ATLAS_TB * ATLAS_TB; q++)
        if (A->gfirst[q] == ATLAS_NOVERT) {
            items[nitems++] = A->nsurf + q;
            break;
        }
    for (pass = 0; pass < 2; pass++) {
        long nvert = 0, exact2 = 0, unmoved = 0;
        atlas_clear(A, 77 + (uint64_t)pass);
        assert_true(A->key == 77u + (uint64_t)pass && A->todo == L.n && A->with_ind == 0);
        for (k = 0; k < (long)L.n; k++)
            assert_int_equal(item_state(A, L.it[k].item), ATLAS_UNFILLED);
        hook_init(&h, A, s, r);
        if (pass == 0)
            h.q[0] = h.q[1] = h.q[2] = 0.0; /* affine */
        wk.ind = hook_fn;
        wk.ind_user = &h;
        todo0 = A->todo;
        assert_int_equal(atlas_fill_items(A, &wk, 1, NULL, items, (uint32_t)nitems), PLX_OK);
        assert_true(A->with_ind == 1);
        assert_true(h.bad == 0 && h.calls > 0);
        {
            uint64_t distinct = 0;
            for (k = 0; k < (long)L.n; k++) {
                uint32_t it = L.it[k].item, d = item_state(A, it);
                long z;
                int listed = 0;
                for (z = 0; z < nitems && !listed; z++)
                    listed = items[z] == it;
                assert_int_equal(atlas_filled((uint8_t)d), listed);
                if (listed)
                    assert_int_equal(d, filled_state(A, &L.it[k].c));
                distinct += listed;
            }
            assert_true(A->todo == todo0 - distinct);
        }
        /* every vertex of the listed charts (up to a budget) */
        for (k = 0; k < nitems && nvert < 20 * nsamp; k++) {
            const citem *it = NULL;
            uint32_t z, i, j;
            for (z = 0; z < L.n; z++)
                if (L.it[z].item == items[k])
                    it = &L.it[z];
            if (!it)
                continue;
            for (j = 0; j < it->c.nv; j++)
                for (i = 0; i < it->c.nu; i++) {
                    const atlas_chart *c = &it->c;
                    double P[3], n[3], V[3], E = 0.0, Ed[3] = { 0.0, 0.0, 0.0 }, I[3], a = site_albedo(s, c), v[3];
                    uint32_t want, got = tex_at(A, c, i, j);
                    int m, moved;
                    atlas_vertex_site(A, w->e->lt, c, i, j, P, n);
                    if (!(c->kind == ATLAS_GROUND && !c->fine))
                        assert_int_equal(light_illuminance(w->e->lt, P, n, &E, Ed), PLX_OK);
                    expect_ind(A, w->e->lt, &h, c, i, j, I, &moved);
                    if (pass == 0 && !moved) {
                        atlas_vertex_point(c, i, j, V);
                        hook_value(&h, V, I); /* the hook at the vertex itself */
                        unmoved++;
                    }
                    for (m = 0; m < 3; m++)
                        v[m] = a / PI * (Ed[m] + I[m]);
                    want = texel_pack(v[0], v[1], v[2]);
                    nvert++;
                    exact2 += got == want;
                    if (!texel_near(got, want)) {
                        float g[3], x[3];
                        texel_unpack(got, g);
                        texel_unpack(want, x);
                        printf("  %s: indirect (pass %d): vertex (%u, %u) of item %u (kind %d, %u x %u): stored %g %g %g, "
                               "expected %g %g %g\n",
                               w->name, pass, i, j, it->item, c->kind, c->nu, c->nv, g[0], g[1], g[2], x[0], x[1], x[2]);
                        fail();
                    }
                }
        }
        if (pass == 0)
            printf("  %s: indirect (affine hook) on %ld listed items: %ld vertices (%ld of them against the hook at the "
                   "vertex: their four records unmoved), %ld same bits, the rest one step apart; %ld hook calls\n",
                   w->name, nitems, nvert, unmoved, exact2, h.calls);
        else
            printf("  %s: indirect (quadratic hook) on the same items: %ld vertices, %ld same bits, the rest one step "
                   "apart; %ld hook calls\n",
                   w->name, nvert, exact2, h.calls);
        assert_true(nvert > 0 && exact2 >= nvert * 9 / 10);
        assert_true(pass == 1 || unmoved > nvert / 4);
    }
    free(items);
    free(wk.rec);
    clist_free(&L);
    arena_release(&w->e->mem, &mk);
}

static void test_values(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    rng r = { 0x5a1e5u };
    world w;
    int q = quick();
    (void)state;
    world_open(&w, "hand", NULL, HAND);
    values_check(&w, 0.7, q ? 2500 : 30000, &r);
    values_check(&w, 1.9, q ? 500 : 8000, &r);
    world_close(&w);
    world_open(&w, "eixample", EIXAMPLE, NULL);
    values_check(&w, 1.3, q ? 1000 : 20000, &r);
    world_close(&w);
    world_open(&w, "helsinki", HELSINKI, NULL);
    values_check(&w, 2.0, q ? 400 : 10000, &r);
    world_close(&w);
}

/* ---- 4. frames -------------------------------------------------------------------- */

typedef struct ftally {
    long px, sky, ground, surf, compared, skipped, nochart, worst_n;
    double worst; /* largest error over its tolerance */
} ftally;

/* Bilinear of chart c at (u, v) in double, clamped; the largest difference
 * of neighbouring vertices and the largest value in the 4 x 4 vertices
 * around (per channel). */
static void ref_bilinear(const atlas *A, const atlas_chart *c, double u, double v, double out[3], double G[3],
                         double vmax[3])
{
    double fu, fv;
    uint32_t i, j, a, b;
    float x[4][3];
    int k, q;
    u = u > 0.0 ? (u < c->nu - 1.0 ? u : c->nu - 1.0) : 0.0;
    v = v > 0.0 ? (v < c->nv - 1.0 ? v : c->nv - 1.0) : 0.0;
    i = (uint32_t)floor(u);
    j = (uint32_t)floor(v);
    i = i > c->nu - 2 ? c->nu - 2 : i;
    j = j > c->nv - 2 ? c->nv - 2 : j;
    fu = u - i;
    fv = v - j;
    for (q = 0; q < 4; q++)
        texel_unpack(tex_at(A, c, i + (q & 1), j + (q >> 1)), x[q]);
    for (k = 0; k < 3; k++) {
        out[k] = (1.0 - fv) * ((1.0 - fu) * x[0][k] + fu * x[1][k]) + fv * ((1.0 - fu) * x[2][k] + fu * x[3][k]);
        G[k] = 0.0;
        vmax[k] = 0.0;
    }
    for (b = j > 0 ? j - 1 : 0; b <= j + 2 && b < c->nv; b++)
        for (a = i > 0 ? i - 1 : 0; a <= i + 2 && a < c->nu; a++) {
            float y[3], z[3];
            texel_unpack(tex_at(A, c, a, b), y);
            for (k = 0; k < 3; k++)
                vmax[k] = fmax(vmax[k], y[k]);
            if (a + 1 < c->nu && a + 1 <= i + 2) {
                texel_unpack(tex_at(A, c, a + 1, b), z);
                for (k = 0; k < 3; k++)
                    G[k] = fmax(G[k], fabs((double)z[k] - y[k]));
            }
            if (b + 1 < c->nv && b + 1 <= j + 2) {
                texel_unpack(tex_at(A, c, a, b + 1), z);
                for (k = 0; k < 3; k++)
                    G[k] = fmax(G[k], fabs((double)z[k] - y[k]));
            }
        }
}

/* SPEC §5's camera: pixel (i, j)'s ray d = D0 + i Dx + j Dy (pixel centres). */
typedef struct cam3 {
    double eye[3], D0[3], Dx[3], Dy[3];
} cam3;

static void cam_setup(const render_camera *cam, cam3 *c)
{
    double f[3], r[3], u[3], l, th = tan(cam->fov_deg * PI / 360.0), W = cam->width, H = cam->height;
    int k;
    for (k = 0; k < 3; k++)
        f[k] = cam->target[k] - cam->eye[k];
    l = sqrt(dot3(f, f));
    for (k = 0; k < 3; k++)
        f[k] /= l;
    r[0] = f[1];
    r[1] = -f[0];
    r[2] = 0.0;
    l = hypot(r[0], r[1]);
    if (l == 0.0) {
        r[0] = 1.0;
        r[1] = 0.0;
    } else {
        r[0] /= l;
        r[1] /= l;
    }
    u[0] = r[1] * f[2] - r[2] * f[1];
    u[1] = r[2] * f[0] - r[0] * f[2];
    u[2] = r[0] * f[1] - r[1] * f[0];
    for (k = 0; k < 3; k++) {
        c->eye[k] = cam->eye[k];
        /* d = f + ((2 (i + .5) / W - 1) th W / H) r + ((1 - 2 (j + .5) / H) th) u */
        c->D0[k] = f[k] + (1.0 / W - 1.0) * th * W / H * r[k] + (1.0 - 1.0 / H) * th * u[k];
        c->Dx[k] = 2.0 / W * th * W / H * r[k];
        c->Dy[k] = -2.0 / H * th * u[k];
    }
}

/* The expected linear value of pixel (i, j) of surface sid, and its
 * tolerance; 0 when the pixel is skipped (a ground point within 1e-6
 * steps of a block's side: the frame may read the block next door). */
static int expect_px(const atlas *A, const cam3 *cm, int32_t i, int32_t j, uint32_t sid, double out[3],
                     double tol[3], ftally *t)
{
    double d[3], G[3], vmax[3], du, dv;
    int k;
    for (k = 0; k < 3; k++) {
        d[k] = cm->D0[k] + i * cm->Dx[k] + j * cm->Dy[k];
        out[k] = 0.0;
        tol[k] = 0.0;
    }
    /* nothing drawn: sky where the ray does not go down, ground where it
     * does (beyond rounding at the horizon) */
    if ((sid == MESH_SURF_NONE && d[2] < -1e-9) || (sid == MESH_SURF_GROUND && d[2] > 1e-9)) {
        printf("  pixel (%d, %d): %s, its ray's height %.9g\n", i, j, sid ? "ground" : "sky", d[2]);
        fail();
    }
    if (sid == MESH_SURF_NONE) {
        t->sky++;
        return 1;
    }
    if (sid == MESH_SURF_GROUND) {
        double tt, x, y, fx, fy, step, lx, ly, bx, by, u, v;
        uint32_t tile, first, ibx, iby;
        atlas_chart c;
        t->ground++;
        if (!(d[2] < 0.0))
            return 1;
        tt = -cm->eye[2] / d[2];
        x = cm->eye[0] + tt * d[0];
        y = cm->eye[1] + tt * d[1];
        fx = (x - A->g0[0]) / A->tile;
        fy = (y - A->g0[1]) / A->tile;
        if (fabs(fx - floor(fx + 0.5)) < 1e-7 || fabs(fy - floor(fy + 0.5)) < 1e-7) {
            t->skipped++;
            return 0;
        }
        if (fx < 0.0 || fy < 0.0 || fx >= A->gx || fy >= A->gy)
            return 1; /* off the tiles: black */
        tile = (uint32_t)fy * A->gx + (uint32_t)fx;
        step = A->gfine[tile] ? A->fine : A->coarse;
        lx = (x - A->g0[0] - floor(fx) * A->tile) / step;
        ly = (y - A->g0[1] - floor(fy) * A->tile) / step;
        bx = lx / ATLAS_BLOCK;
        by = ly / ATLAS_BLOCK;
        if (A->gfine[tile] && (fabs(bx - floor(bx + 0.5)) < 1e-6 || fabs(by - floor(by + 0.5)) < 1e-6)) {
            t->skipped++;
            return 0;
        }
        ibx = A->gfine[tile] ? (uint32_t)floor(bx) : 0;
        iby = A->gfine[tile] ? (uint32_t)floor(by) : 0;
        ibx = ibx > ATLAS_TB - 1 ? ATLAS_TB - 1 : ibx;
        iby = iby > ATLAS_TB - 1 ? ATLAS_TB - 1 : iby;
        first = A->gfirst[(size_t)tile * ATLAS_TB * ATLAS_TB + iby * ATLAS_TB + ibx];
        if (first == ATLAS_NOVERT) {
            t->nochart++;
            return 1;
        }
        atlas_ground_block(A, (uint32_t)fx, (uint32_t)fy, ibx, iby, &c);
        u = lx - ibx * ATLAS_BLOCK;
        v = ly - iby * ATLAS_BLOCK;
        ref_bilinear(A, &c, u, v, out, G, vmax);
        /* the frame: the hit in double, then u, v in float (8 steps at most) */
        du = dv = 2.0 * ATLAS_BLOCK * EPSF + 1e-9;
    } else {
        const atlas_chart *c = atlas_surface_chart(A, sid);
        double n[3], gu[3] = { 0, 0, 0 }, gv[3] = { 0, 0, 0 }, eo[3], N, nd, tt, P[3], u, v;
        double Su = 0.0, Sv = 0.0, Sw = 0.0, Wd = 0.0, cu, cv, w3[3] = { 1.0, (double)i, (double)j };
        const double *D[3];
        t->surf++;
        if (!c) {
            t->nochart++;
            return 1;
        }
        atlas_chart_normal(c, n);
        if (c->kind == ATLAS_WALL) {
            n[0] = c->e[1];
            n[1] = -(double)c->e[0];
            gu[0] = c->e[0] / (double)c->tu;
            gu[1] = c->e[1] / (double)c->tu;
            gv[2] = 1.0 / c->tv;
        } else {
            gu[0] = 1.0 / c->tu;
            gv[1] = 1.0 / c->tv;
        }
        for (k = 0; k < 3; k++)
            eo[k] = cm->eye[k] - c->o[k];
        nd = dot3(n, d);
        if (nd == 0.0) {
            t->skipped++;
            return 0;
        }
        tt = -dot3(n, eo) / nd;
        for (k = 0; k < 3; k++)
            P[k] = cm->eye[k] + tt * d[k];
        if (c->kind == ATLAS_WALL) {
            u = ((P[0] - c->o[0]) * c->e[0] + (P[1] - c->o[1]) * c->e[1]) / c->tu;
            v = (P[2] - c->o[2]) / c->tv;
        } else {
            u = (P[0] - c->o[0]) / c->tu;
            v = (P[1] - c->o[1]) / c->tv;
        }
        ref_bilinear(A, c, u, v, out, G, vmax);
        /* The frame takes u = (Au + Bu i + Cu j) / (Aw + Bw i + Cw j) with
         * the nine coefficients rounded to float and the sums, the
         * reciprocal and the product in float: each of its terms carries a
         * relative error of a few 2^-24, so |du| <= k eps (Su + |u| Sw) / |W|
         * with Su, Sw the sums of the terms' magnitudes (k = 16: twice the
         * roundings counted). */
        N = -dot3(n, eo);
        cu = dot3(eo, gu);
        cv = dot3(eo, gv);
        D[0] = cm->D0;
        D[1] = cm->Dx;
        D[2] = cm->Dy;
        for (k = 0; k < 3; k++) {
            double ndk = dot3(n, D[k]);
            Su += fabs(cu * ndk + N * dot3(D[k], gu)) * w3[k];
            Sv += fabs(cv * ndk + N * dot3(D[k], gv)) * w3[k];
            Sw += fabs(ndk) * w3[k];
            Wd += ndk * w3[k];
        }
        du = 16.0 * EPSF * (Su + fabs(u) * Sw) / fabs(Wd) + 4.0 * EPSF * fabs(u);
        dv = 16.0 * EPSF * (Sv + fabs(v) * Sw) / fabs(Wd) + 4.0 * EPSF * fabs(v);
    }
    /* The value: Lipschitz in u and v by the largest step between vertices
     * around; the frame's bilinear in float adds a few 2^-24 of the values. */
    for (k = 0; k < 3; k++)
        tol[k] = G[k] * (du + dv) + 16.0 * EPSF * vmax[k] + 1e-30;
    return 1;
}

static void frame_check(const atlas *A, const render_camera *cam, const float *lin, const uint32_t *ids,
                        ftally *t)
{
    cam3 cm;
    int32_t i, j;
    cam_setup(cam, &cm);
    for (j = 0; j < cam->height; j++)
        for (i = 0; i < cam->width; i++) {
            size_t p = (size_t)j * cam->width + i;
            double want[3], tol[3];
            int k;
            t->px++;
            if (!expect_px(A, &cm, i, j, ids[p], want, tol, t))
                continue;
            t->compared++;
            for (k = 0; k < 3; k++) {
                double err = fabs((double)lin[3 * p + k] - want[k]);
                if (tol[k] > 0.0 && err / tol[k] > t->worst)
                    t->worst = err / tol[k];
                if (!(err <= tol[k])) {
                    printf("  pixel (%d, %d) of a %dx%d frame, surface %u: %.9g, expected %.9g (tolerance %.3g)\n", i, j,
                           cam->width, cam->height, ids[p], lin[3 * p + k], want[k], tol[k]);
                    fail();
                }
            }
        }
}

/* render_opts.atlas_need as the engine's: what the frame reads and is not
 * filled, listed a few at a time and filled. */
typedef struct lazy {
    atlas *A;
    atlas_worker *w;
    uint32_t list[7];
    long rounds, listed, checked, masked, some_rows, masked_fills, masked_frames;
} lazy;

/* The list atlas_frame_missing must give, from the block under every
 * ground pixel found afresh (the frame's ground point as ground_run's row
 * setup computes it, then the tile and block it falls in), on copies of
 * the items' states: a per-pixel reference for its remembered block. */
static uint32_t ref_block(const atlas *A, double x, double y)
{
    double fx = x * A->inv_tile, fy = y * A->inv_tile, inv, bx, by;
    uint32_t tx, ty, tile, nb;
    if (!(fx >= 0.0 && fx < A->gx && fy >= 0.0 && fy < A->gy))
        return UINT32_MAX;
    tx = (uint32_t)fx;
    ty = (uint32_t)fy;
    tile = ty * A->gx + tx;
    inv = A->gfine[tile] ? A->inv_fine : A->inv_coarse;
    x = (x - tx * A->tile) * inv;
    y = (y - ty * A->tile) * inv;
    bx = x < 0.0 ? 0.0 : x * (1.0 / ATLAS_BLOCK);
    by = y < 0.0 ? 0.0 : y * (1.0 / ATLAS_BLOCK);
    nb = A->gfine[tile] ? ATLAS_TB - 1 : 0;
    tx = bx < nb ? (uint32_t)bx : nb;
    ty = by < nb ? (uint32_t)by : nb;
    return tile * ATLAS_TB * ATLAS_TB + ty * ATLAS_TB + tx;
}

static void ref_want(uint8_t *st, uint32_t it, uint32_t *list, uint32_t cap, uint32_t *n)
{
    if (st[it] || *n >= cap)
        return;
    st[it] = ATLAS_LISTED;
    list[(*n)++] = it;
}

static uint32_t ref_missing(const atlas *A, const atlas_view *v, const uint32_t *ids, const uint8_t *mask, int32_t j0,
                            int32_t j1, uint8_t *st, uint32_t *list, uint32_t cap)
{
    uint32_t n = 0, last = MESH_SURF_NONE;
    int32_t i, j;
    if (A->todo == 0)
        return 0;
    for (j = j0; j < j1 && j < v->h && n < cap; j++) {
        double dz = v->D0[2] + j * v->Dy[2], t = -v->eye[2] / dz, x0, y0, dx, dy;
        x0 = v->eye[0] - A->g0[0] + t * (v->D0[0] + j * v->Dy[0]);
        y0 = v->eye[1] - A->g0[1] + t * (v->D0[1] + j * v->Dy[1]);
        dx = t * v->Dx[0];
        dy = t * v->Dx[1];
        for (i = 0; i < v->w; i++) {
            uint32_t sid = ids[(size_t)j * v->w + i];
            if (mask && !mask[(size_t)j * v->w + i])
                continue;
            if (sid == MESH_SURF_GROUND && dz < 0.0) {
                uint32_t b = ref_block(A, x0 + i * dx, y0 + i * dy);
                if (b != UINT32_MAX && A->gfirst[b] != ATLAS_NOVERT)
                    ref_want(st, (uint32_t)A->nsurf + b, list, cap, &n);
            } else if (sid != last && sid != MESH_SURF_NONE && sid != MESH_SURF_GROUND) {
                last = sid;
                if (atlas_surface_chart(A, sid))
                    ref_want(st, sid - 2u, list, cap, &n);
            }
        }
    }
    return n;
}

/* atlas_frame_missing with a mask against the reference on the same
 * mask, the items' states put back after: a mask of 0, 1 and 2 bytes (2:
 * marked by a later sample) from the pixel's index, and the frame's
 * first row left unmarked. */
static void masked_check(lazy *z, const atlas_view *v, const uint32_t *ids, int32_t j0, int32_t j1, uint8_t *st,
                         size_t nst)
{
    size_t px = (size_t)v->w * (size_t)v->h, p;
    uint8_t *mask = malloc(px), *keep = malloc(nst);
    uint32_t n, k, ref[7];
    assert_true(mask && keep);
    for (p = 0; p < px; p++)
        mask[p] = p < (size_t)v->w ? 0 : (uint8_t)(((p * 2654435761u) >> 13) % 3);
    memcpy(keep, z->A->cdone, z->A->nsurf);
    memcpy(keep + z->A->nsurf, z->A->gdone, nst - z->A->nsurf);
    memcpy(st, keep, nst);
    k = ref_missing(z->A, v, ids, mask, j0, j1, st, ref, 7);
    n = atlas_frame_missing(z->A, v, ids, mask, j0, j1, z->list, 7);
    assert_int_equal(n, k);
    assert_memory_equal(z->list, ref, n * sizeof ref[0]);
    z->masked += n;
    memcpy(z->A->cdone, keep, z->A->nsurf);
    memcpy(z->A->gdone, keep + z->A->nsurf, nst - z->A->nsurf);
    free(mask);
    free(keep);
}

static int lazy_need(void *user, const atlas_view *v, const uint32_t *ids, const uint8_t *mask, int32_t j0,
                     int32_t j1)
{
    lazy *z = user;
    size_t nst = z->A->nsurf + (size_t)z->A->gx * z->A->gy * ATLAS_TB * ATLAS_TB;
    uint8_t *st = malloc(nst);
    uint32_t n, ref[7];
    assert_non_null(st);
    assert_true(j0 >= 0 && j0 < j1 && j0 < v->h);
    z->some_rows += j0 > 0 || j1 < v->h;
    if (!mask)
        masked_check(z, v, ids, j0, j1, st, nst);
    for (;;) {
        uint32_t k;
        memcpy(st, z->A->cdone, z->A->nsurf);
        memcpy(st + z->A->nsurf, z->A->gdone, nst - z->A->nsurf);
        k = ref_missing(z->A, v, ids, mask, j0, j1, st, ref, 7);
        n = atlas_frame_missing(z->A, v, ids, mask, j0, j1, z->list, 7);
        assert_int_equal(n, k);
        assert_memory_equal(z->list, ref, n * sizeof ref[0]);
        z->checked += n;
        if (n == 0)
            break;
        for (k = 0; k < n; k++) /* listed once, marked listed */
            assert_int_equal(item_state(z->A, z->list[k]), ATLAS_LISTED);
        assert_int_equal(atlas_fill_items(z->A, z->w, 1, NULL, z->list, n), PLX_OK);
        z->rounds++;
        z->listed += n;
        z->masked_fills += mask ? (long)n : 0;
    }
    free(st);
    return 0;
}

static int eye_in_solid(const scene *s, const double eye[3])
{
    uint32_t b;
    for (b = 0; b < s->nbld; b++)
        if (eye[2] >= s->bld[b].min_height - 0.5 && eye[2] <= s->bld[b].height + 0.5 &&
            (where_fp(s, b, eye[0], eye[1]) != REF_OUT || boundary_dist(s, b, eye[0], eye[1]) < 0.5))
            return 1;
    return 0;
}

static void random_camera(const scene *s, rng *r, int k, render_camera *cam)
{
    double a;
    do {
        if (k % 3 == 0) { /* street level */
            cam->eye[0] = runi(r, s->bounds[0] + 40.0, s->bounds[2] - 40.0);
            cam->eye[1] = runi(r, s->bounds[1] + 40.0, s->bounds[3] - 40.0);
            cam->eye[2] = runi(r, 1.2, 4.0);
        } else { /* from above */
            cam->eye[0] = runi(r, s->bounds[0], s->bounds[2]);
            cam->eye[1] = runi(r, s->bounds[1], s->bounds[3]);
            cam->eye[2] = runi(r, 30.0, 400.0);
        }
    } while (eye_in_solid(s, cam->eye));
    a = runi(r, 0.0, 2.0 * PI);
    if (k % 3 == 0) {
        cam->target[0] = cam->eye[0] + 10.0 * cos(a);
        cam->target[1] = cam->eye[1] + 10.0 * sin(a);
        cam->target[2] = cam->eye[2] + runi(r, -4.0, 1.5);
    } else if (k % 6 == 1) { /* straight down */
        cam->target[0] = cam->eye[0];
        cam->target[1] = cam->eye[1];
        cam->target[2] = 0.0;
    } else {
        cam->target[0] = runi(r, s->bounds[0], s->bounds[2]);
        cam->target[1] = runi(r, s->bounds[1], s->bounds[3]);
        cam->target[2] = runi(r, 0.0, 20.0);
    }
    cam->fov_deg = runi(r, 15.0, 100.0);
    cam->width = k == 0 ? 97 : (int32_t)(16 + rpick(r, 150));
    cam->height = k == 0 ? 61 : (int32_t)(12 + rpick(r, 110));
}

/* An anti-aliasing later sample (shifted sample points, a mask of about
 * half the pixels): from the complete atlas A, then from B filled as the
 * frames need it (z: lazy_need, which lists through the mask), the same
 * marked pixels and counts; the others keep what the buffer held. */
static void masked_frame(world *w, const render_camera *cam, atlas *A, atlas *B, atlas_cache *ca, atlas_cache *cb,
                         lazy *z, rng *r)
{
    size_t px = (size_t)cam->width * cam->height, p;
    uint8_t *mask = malloc(px);
    float *want = malloc(3 * px * sizeof(float));
    render_opts o;
    render_stats sa, sb;
    long before = z->masked_fills;
    int k;
    assert_true(mask && want);
    for (p = 0; p < px; p++)
        mask[p] = (uint8_t)rpick(r, 2);
    for (k = 0; k < 2; k++) {
        render_opts_default(&o);
        o.no_glow = 1;
        o.shift[0] = 0.25 - 0.5 * k;
        o.shift[1] = -0.25;
        o.mask = mask;
        o.atlas = A;
        o.atlas_cache = ca;
        assert_int_equal(render_frame(w->e->rd, cam, &o, NULL, NULL, &sa), PLX_OK);
        memcpy(want, render_linear(w->e->rd), 3 * px * sizeof(float));
        o.atlas = B;
        o.atlas_cache = cb;
        o.atlas_need = lazy_need;
        o.atlas_user = z;
        assert_int_equal(render_frame(w->e->rd, cam, &o, NULL, NULL, &sb), PLX_OK);
        for (p = 0; p < px; p++)
            if (mask[p])
                assert_memory_equal(&want[3 * p], &render_linear(w->e->rd)[3 * p], 3 * sizeof(float));
        assert_true(sa.sky_pixels == sb.sky_pixels && sa.ground_pixels == sb.ground_pixels &&
                    sa.building_pixels == sb.building_pixels);
    }
    z->masked_frames += z->masked_fills > before;
    free(mask);
    free(want);
}

static void frames_check(world *w, double fine, int nframes, rng *r)
{
    arena_mark mk = arena_get_mark(&w->e->mem);
    atlas *A = make_atlas(w, fine), *B = make_atlas(w, fine);
    atlas_worker wk, wkb;
    hook_ctx h, hb;
    atlas_cache *cache = calloc(2, sizeof *cache), *cache2 = calloc(1, sizeof *cache2);
    const plx_port *port = plx_port_posix();
    ftally t;
    lazy z;
    float *lin1 = malloc(3 * 200 * 200 * sizeof(float));
    size_t nst = A->nsurf + (size_t)A->gx * A->gy * ATLAS_TB * ATLAS_TB, q;
    uint8_t *st0 = malloc(nst);
    long dark = 0, dark_ground = 0;
    int f, partial = 0;
    double t0 = now_s();
    assert_true(cache && cache2 && lin1);
    memset(&t, 0, sizeof t);
    memset(&wk, 0, sizeof wk);
    wk.lt = w->e->lt;
    wk.rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
    assert_non_null(wk.rec);
    hook_init(&h, A, w->s, r);
    h.dark = 1;
    wk.ind = hook_fn;
    wk.ind_user = &h;
    assert_int_equal(atlas_fill(A, &wk, 1, NULL), PLX_OK);
    assert_non_null(st0);
    for (q = 0; q < nst; q++) {
        int d = (q < A->nsurf ? A->cdone[q] : A->gdone[q - A->nsurf]) == ATLAS_DARK;
        dark += d;
        dark_ground += d && q >= A->nsurf;
    }
    assert_true(dark > dark_ground && dark_ground > 0);
    memset(&z, 0, sizeof z);
    hb = h;
    hb.A = B;
    wkb = wk;
    wkb.ind_user = &hb;
    z.A = B;
    z.w = &wkb;
    for (f = 0; f < nframes; f++) {
        render_camera cam;
        render_opts o;
        render_stats st, st1;
        size_t px;
        random_camera(w->s, r, f, &cam);
        px = (size_t)cam.width * cam.height;
        render_opts_default(&o);
        o.no_glow = 1;
        o.atlas = A;
        o.atlas_cache = cache;
        assert_int_equal(render_frame(w->e->rd, &cam, &o, NULL, NULL, &st), PLX_OK);
        st1 = st;
        frame_check(A, &cam, render_linear(w->e->rd), render_ids(w->e->rd), &t);
        memcpy(lin1, render_linear(w->e->rd), 3 * px * sizeof(float));
        /* no chart or block marked dark (each read): the same bytes */
        memcpy(st0, A->cdone, A->nsurf);
        memcpy(st0 + A->nsurf, A->gdone, nst - A->nsurf);
        for (q = 0; q < nst; q++) {
            uint8_t *d = q < A->nsurf ? &A->cdone[q] : &A->gdone[q - A->nsurf];
            *d = *d == ATLAS_DARK ? ATLAS_FILLED : *d;
        }
        assert_int_equal(render_frame(w->e->rd, &cam, &o, NULL, NULL, &st), PLX_OK);
        assert_memory_equal(lin1, render_linear(w->e->rd), 3 * px * sizeof(float));
        memcpy(A->cdone, st0, A->nsurf);
        memcpy(A->gdone, st0 + A->nsurf, nst - A->nsurf);
        /* on two workers: the same bytes */
        o.par = port->parallel_for;
        o.par_ctx = port->ctx;
        o.workers = 2;
        assert_int_equal(render_frame(w->e->rd, &cam, &o, NULL, NULL, &st), PLX_OK);
        assert_memory_equal(lin1, render_linear(w->e->rd), 3 * px * sizeof(float));
        /* from an atlas filled as the frames need it: the same bytes */
        render_opts_default(&o);
        o.no_glow = 1;
        o.atlas = B;
        o.atlas_cache = cache2;
        o.atlas_need = lazy_need;
        o.atlas_user = &z;
        assert_int_equal(render_frame(w->e->rd, &cam, &o, NULL, NULL, &st), PLX_OK);
        assert_memory_equal(lin1, render_linear(w->e->rd), 3 * px * sizeof(float));
        assert_true(st.sky_pixels == st1.sky_pixels && st.ground_pixels == st1.ground_pixels &&
                    st.building_pixels == st1.building_pixels); /* each row counted once */
        partial += B->todo > 0;
        masked_frame(w, &cam, A, B, cache, cache2, &z, r);
    }
    printf("  %s at %.2f m: %d frames, %ld pixels (sky %ld, ground %ld, buildings %ld, %ld on no chart): %ld compared, "
           "%ld skipped at block sides; worst error %.3g of its tolerance; on demand %ld items in %ld rounds (each "
           "list the per-pixel reference's; %ld listed through masks; %ld calls for some rows only; %ld filled "
           "for masked later samples, in %ld frames); %ld dark "
           "items (%ld ground blocks); %.2f s\n",
           w->name, fine, nframes, t.px, t.sky, t.ground, t.surf, t.nochart, t.compared, t.skipped, t.worst, z.listed,
           z.rounds, z.masked, z.some_rows, z.masked_fills, z.masked_frames, dark, dark_ground, now_s() - t0);
    assert_true(t.compared >= t.px * 99 / 100);
    assert_true(t.ground > t.px / 20 && t.surf > t.px / 20);
    assert_true(partial > 0 && z.rounds > nframes && z.masked > 0 && z.some_rows > 0 && z.masked_fills > 0);
    assert_true(h.bad == 0 && hb.bad == 0);
    free(lin1);
    free(st0);
    free(cache);
    free(cache2);
    free(wk.rec);
    arena_release(&w->e->mem, &mk);
}

static void test_frames(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    rng r = { 0xf4a3e5u };
    world w;
    int q = quick();
    (void)state;
    world_open(&w, "hand", NULL, HAND);
    frames_check(&w, 0.7, q ? 8 : 100, &r);
    world_close(&w);
    world_open(&w, "eixample", EIXAMPLE, NULL);
    frames_check(&w, 1.3, q ? 8 : 100, &r);
    world_close(&w);
    world_open(&w, "helsinki", HELSINKI, NULL);
    frames_check(&w, 2.0, q ? 4 : 50, &r);
    world_close(&w);
}

/* atlas_frame_row reads a run of eight or more pixels on one surface,
 * or in one ground block, eight at a time (run_read); scattered marked
 * pixels go through the lanes one by one. The two must give the same
 * bits: every row of random frames read whole (mask NULL), then again
 * as the union of two rows with every other pixel marked (runs of one:
 * the lanes), and once with every pixel marked. The ground's block
 * cache restarts at a skipped pixel, and a fresh lookup agrees with it
 * only at power-of-two spacings (atlas_frame.c), hence 1 and 0.5 m. */
static void runs_check(world *w, double fine, int nframes, rng *r, long *runs)
{
    arena_mark mk = arena_get_mark(&w->e->mem);
    atlas *A = make_atlas(w, fine);
    atlas_worker wk;
    hook_ctx h;
    atlas_cache *cache = calloc(1, sizeof *cache);
    float *row = malloc(3 * 200 * sizeof(float));
    uint8_t mask[3][200];
    int f, m;
    assert_true(cache && row);
    memset(&wk, 0, sizeof wk);
    wk.lt = w->e->lt;
    wk.rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
    assert_non_null(wk.rec);
    hook_init(&h, A, w->s, r);
    wk.ind = hook_fn;
    wk.ind_user = &h;
    assert_int_equal(atlas_fill(A, &wk, 1, NULL), PLX_OK);
    for (m = 0; m < 200; m++) {
        mask[0][m] = (uint8_t)(m % 2);
        mask[1][m] = (uint8_t)(2 * (1 - m % 2)); /* any nonzero byte marks */
        mask[2][m] = 1;
    }
    for (f = 0; f < nframes; f++) {
        render_camera cam;
        render_opts o;
        render_stats st;
        atlas_view v;
        const float *lin;
        const uint32_t *ids;
        int32_t j, i;
        random_camera(w->s, r, f, &cam);
        render_opts_default(&o);
        o.no_glow = 1;
        o.atlas = A;
        o.atlas_cache = cache;
        assert_int_equal(render_frame(w->e->rd, &cam, &o, NULL, NULL, &st), PLX_OK);
        render_atlas_view(w->e->rd, &v);
        lin = render_linear(w->e->rd);
        ids = render_ids(w->e->rd);
        for (j = 0; j < cam.height; j++) {
            const uint32_t *rid = &ids[(size_t)j * cam.width];
            const float *want = &lin[3 * (size_t)j * cam.width];
            uint64_t c0[3] = { 0, 0, 0 }, c1[3] = { 0, 0, 0 };
            for (i = 0; i + 8 <= cam.width; i++) /* runs the eight-at-a-time path can take */
                if (rid[i] != MESH_SURF_NONE && rid[i + 7] == rid[i])
                    (*runs)++;
            atlas_frame_row(A, &v, cache, rid, NULL, j, row, c0);
            assert_memory_equal(row, want, 3 * (size_t)cam.width * sizeof(float));
            memset(row, 0xff, 3 * (size_t)cam.width * sizeof(float)); /* NaN: every pixel must be written */
            atlas_frame_row(A, &v, cache, rid, mask[0], j, row, c1);
            atlas_frame_row(A, &v, cache, rid, mask[1], j, row, c1);
            assert_memory_equal(row, want, 3 * (size_t)cam.width * sizeof(float));
            assert_memory_equal(c0, c1, sizeof c0);
            memset(row, 0xff, 3 * (size_t)cam.width * sizeof(float));
            atlas_frame_row(A, &v, cache, rid, mask[2], j, row, c1);
            assert_memory_equal(row, want, 3 * (size_t)cam.width * sizeof(float));
        }
    }
    free(row);
    free(cache);
    free(wk.rec);
    arena_release(&w->e->mem, &mk);
}

static void test_runs_equal_lanes(void **state)
{
    if (quick()) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    rng r = { 0x5eed81u };
    world w;
    long runs = 0;
    int q = quick();
    (void)state;
    world_open(&w, "eixample", EIXAMPLE, NULL);
    runs_check(&w, 1.0, q ? 12 : 60, &r, &runs);
    world_close(&w);
    world_open(&w, "helsinki", HELSINKI, NULL);
    runs_check(&w, 0.5, q ? 6 : 30, &r, &runs);
    world_close(&w);
    printf("  %ld places a run of eight pixels starts: whole rows, every other pixel, and every pixel marked give the "
           "same bits\n", runs);
    assert_true(runs > 1000);
}

/* atlas_frame_missing at block edges: rows of two ground points, the
 * first well inside one block and the second d steps across its edge
 * into the next (d from 1e-9 to 0.3 steps, on either side, along x and
 * along y, at an edge inside a fine tile and at the side of a coarse
 * tile), each against ref_missing: a point just across the edge must
 * list the next block however close it lies. */
static void edge_row(atlas *A, double x0, double y0, double sx, double sy, uint8_t *st, size_t nst, long *rows)
{
    atlas_view v;
    uint32_t ids[2] = { MESH_SURF_GROUND, MESH_SURF_GROUND }, list[8], ref[8], n, k;
    memset(&v, 0, sizeof v);
    v.w = 2;
    v.h = 1;
    v.eye[2] = 1.0;                      /* t = 1: a point is eye + D0 + i Dx */
    v.D0[0] = A->g0[0] + x0;
    v.D0[1] = A->g0[1] + y0;
    v.D0[2] = -1.0;
    v.Dx[0] = sx;
    v.Dx[1] = sy;
    memcpy(st, A->cdone, A->nsurf);
    memcpy(st + A->nsurf, A->gdone, nst - A->nsurf);
    k = ref_missing(A, &v, ids, NULL, 0, v.h, st, ref, 8);
    n = atlas_frame_missing(A, &v, ids, NULL, 0, v.h, list, 8);
    assert_int_equal(n, k);
    assert_int_equal(n, 2);              /* two blocks, both unfilled */
    assert_memory_equal(list, ref, n * sizeof ref[0]);
    for (k = 0; k < n; k++)              /* unlisted again for the next row */
        A->gdone[list[k] - A->nsurf] = ATLAS_UNFILLED;
    (*rows)++;
}

/* The rows of test_missing_edges over world w's atlas at spacing fine;
 * seen[0], seen[1]: a fine, a coarse tile was found and crossed. */
static void edges_in(world *w, double fine, int seen[2], long *rows)
{
    const double d[] = { 1e-9, 1e-7, 1e-6, 2e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.3 };
    arena_mark mk = arena_get_mark(&w->e->mem);
    atlas *A = make_atlas(w, fine);
    size_t nst = A->nsurf + (size_t)A->gx * A->gy * ATLAS_TB * ATLAS_TB, q;
    uint8_t *st = malloc(nst);
    uint32_t t, tf = UINT32_MAX, tc = UINT32_MAX;
    int kind, axis, side;
    assert_non_null(st);
    /* a fine tile whose blocks (0, 0), (1, 0) and (0, 1) have vertices, and a
     * coarse tile whose neighbours along x and y are coarse, all with vertices */
    for (t = 0; t < A->gx * A->gy; t++) {
        const uint32_t *g = &A->gfirst[(size_t)t * ATLAS_TB * ATLAS_TB];
        uint32_t tx = t % A->gx, ty = t / A->gx;
        if (tx + 1 >= A->gx || ty + 1 >= A->gy)
            continue;
        if (A->gfine[t] && tf == UINT32_MAX && g[0] != ATLAS_NOVERT && g[1] != ATLAS_NOVERT &&
            g[ATLAS_TB] != ATLAS_NOVERT)
            tf = t;
        if (!A->gfine[t] && !A->gfine[t + 1] && !A->gfine[t + A->gx] && tc == UINT32_MAX && g[0] != ATLAS_NOVERT &&
            A->gfirst[(size_t)(t + 1) * ATLAS_TB * ATLAS_TB] != ATLAS_NOVERT &&
            A->gfirst[(size_t)(t + A->gx) * ATLAS_TB * ATLAS_TB] != ATLAS_NOVERT)
            tc = t;
    }
    for (q = 0; q < nst - A->nsurf; q++)
        assert_int_equal(A->gdone[q], ATLAS_UNFILLED);
    for (kind = 0; kind < 2; kind++) {
        uint32_t tile = kind ? tc : tf;
        double step = kind ? A->coarse : A->fine, e, ox, oy, mid;
        size_t k;
        if (tile == UINT32_MAX)
            continue;
        seen[kind] = 1;
        /* the edge: between the tile's first two blocks (fine), or the tile's far side (coarse) */
        e = kind ? A->tile : ATLAS_BLOCK * A->fine;
        ox = (tile % A->gx) * A->tile;
        oy = (tile / A->gx) * A->tile;
        mid = 0.5 * ATLAS_BLOCK * step;
        for (axis = 0; axis < 2; axis++)
            for (side = 0; side < 2; side++)
                for (k = 0; k < sizeof d / sizeof d[0]; k++) {
                    /* from 2 steps before the edge to d steps after it, or back from 2 steps after it */
                    double a = side ? e + 2.0 * step : e - 2.0 * step;
                    double b = side ? e - d[k] * step : e + d[k] * step;
                    if (axis == 0)
                        edge_row(A, ox + a, oy + mid, b - a, 0.0, st, nst, rows);
                    else
                        edge_row(A, ox + mid, oy + a, 0.0, b - a, st, nst, rows);
                }
    }
    free(st);
    arena_release(&w->e->mem, &mk);
}

static void test_missing_edges(void **state)
{
    world w;
    int seen[2] = { 0, 0 };
    long rows = 0;
    (void)state;
    world_open(&w, "eixample", EIXAMPLE, NULL);
    edges_in(&w, 1.3, seen, &rows);
    world_close(&w);
    world_open(&w, "helsinki", HELSINKI, NULL);
    edges_in(&w, 2.0, seen, &rows);
    world_close(&w);
    printf("  %ld rows across block edges, in fine and coarse tiles: the lists of the per-pixel reference\n", rows);
    assert_true(seen[0] && seen[1]);
}

/* atlas_sample (the public read) against the bilinear in double. */
static void test_sample(void **state)
{
    rng r = { 0x5a3b1eu };
    world w;
    arena_mark mk;
    atlas *A;
    atlas_worker wk;
    hook_ctx h;
    clist L;
    long k, n = quick() ? 20000 : 200000, ground = 0;
    (void)state;
    world_open(&w, "eixample", EIXAMPLE, NULL);
    mk = arena_get_mark(&w.e->mem);
    A = make_atlas(&w, 1.7);
    memset(&wk, 0, sizeof wk);
    wk.lt = w.e->lt;
    wk.rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
    hook_init(&h, A, w.s, &r);
    wk.ind = hook_fn;
    wk.ind_user = &h;
    assert_int_equal(atlas_fill(A, &wk, 1, NULL), PLX_OK);
    clist_make(A, &L);
    for (k = 0; k < n; k++) {
        const citem *it = &L.it[rpick(&r, L.n)];
        const atlas_chart *c = &it->c;
        double u = runi(&r, -0.5, c->nu - 0.5), v = runi(&r, -0.5, c->nv - 0.5), P[3], want[3], G[3], vm[3];
        float got[3];
        int q;
        if (rpick(&r, 8) == 0)
            u = floor(u + 0.5); /* on a vertex column */
        if (c->kind == ATLAS_WALL) {
            P[0] = c->o[0] + u * c->tu * c->e[0];
            P[1] = c->o[1] + u * c->tu * c->e[1];
            P[2] = c->o[2] + v * c->tv;
        } else {
            P[0] = c->o[0] + u * c->tu;
            P[1] = c->o[1] + v * c->tv;
            P[2] = c->o[2];
        }
        if (c->kind == ATLAS_GROUND) {
            atlas_chart g;
            /* the block holding P: this one unless P lies beyond its sides */
            if (!atlas_ground_chart(A, P[0], P[1], &g) || g.first != c->first)
                continue;
            ground++;
        }
        atlas_sample(A, it->sid, P, got);
        atlas_chart_uv(c, P, &u, &v);
        ref_bilinear(A, c, u, v, want, G, vm);
        for (q = 0; q < 3; q++)
            assert_true(fabs((double)got[q] - want[q]) <= 1e-6 * G[q] + 16.0 * EPSF * vm[q] + 1e-30);
    }
    printf("  atlas_sample: %ld points (%ld on the ground)\n", n, ground);
    assert_true(ground > n / 20);
    /* no seam: blocks side by side hold the same values on their common side
     * (up to one step: the vertices are laid by float steps) */
    {
        uint32_t tx, ty, b, same = 0, near = 0, q;
        for (ty = 0; ty < A->gy; ty++)
            for (tx = 0; tx < A->gx; tx++)
                for (b = 0; b < ATLAS_TB * ATLAS_TB; b++) {
                    atlas_chart c, d;
                    uint32_t bx = b % ATLAS_TB, by = b / ATLAS_TB;
                    atlas_ground_block(A, tx, ty, bx, by, &c);
                    if (c.kind != ATLAS_GROUND || !c.fine)
                        continue;
                    if (bx + 1 < ATLAS_TB)
                        atlas_ground_block(A, tx, ty, bx + 1, by, &d);
                    else if (tx + 1 < A->gx && A->gfine[ty * A->gx + tx + 1])
                        atlas_ground_block(A, tx + 1, ty, 0, by, &d);
                    else
                        continue;
                    if (d.kind != ATLAS_GROUND)
                        continue;
                    for (q = 0; q <= ATLAS_BLOCK; q++) {
                        uint32_t x = tex_at(A, &c, ATLAS_BLOCK, q), y = tex_at(A, &d, 0, q);
                        same += x == y;
                        near += x != y && texel_near(x, y);
                        assert_true(texel_near(x, y));
                    }
                }
        printf("  block sides: %u vertex pairs the same, %u one step apart\n", same, near);
        assert_true(same > 1000 && near <= same / 100);
    }
    clist_free(&L);
    free(wk.rec);
    arena_release(&w.e->mem, &mk);
    world_close(&w);
}

/* ---- 5. determinism ------------------------------------------------------------------ */

typedef struct told {
    long starts, ends, units, total, other;
} told;

static void count_progress(void *ctx, const char *what, uint64_t n, uint64_t total)
{
    told *t = ctx;
    if (strcmp(what, ATLAS_STAGE) != 0)
        t->other++;
    if (total == 0) {
        t->ends++;
    } else if (n == 0) {
        t->starts++;
        t->total = (long)total;
    } else {
        __atomic_add_fetch(&t->units, (long)n, __ATOMIC_SEQ_CST);
    }
}

static void determinism_check(world *w, double fine, rng *r)
{
    arena_mark mk = arena_get_mark(&w->e->mem);
    atlas *A = make_atlas(w, fine);
    atlas_worker wk[2];
    hook_ctx h[2];
    atlas_par par;
    told tl;
    void *blk = malloc((size_t)64 << 20);
    arena a2;
    uint32_t *one, *items, n, k;
    clist L;
    assert_non_null(blk);
    arena_init(&a2, blk, (size_t)64 << 20);
    memset(wk, 0, sizeof wk);
    wk[0].lt = w->e->lt;
    assert_int_equal(light_create(&a2, w->s, (size_t)8 << 20, &wk[1].lt), PLX_OK);
    hook_init(&h[0], A, w->s, r);
    h[1] = h[0];
    for (k = 0; k < 2; k++) {
        wk[k].ind = hook_fn;
        wk[k].ind_user = &h[k];
        wk[k].rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
        assert_non_null(wk[k].rec);
    }
    /* one worker */
    assert_int_equal(atlas_fill(A, wk, 1, NULL), PLX_OK);
    one = malloc(A->ntex * sizeof *one);
    assert_non_null(one);
    memcpy(one, A->tex, A->ntex * sizeof *one);
    /* two workers on the port's parallel-for, with progress */
    atlas_clear(A, 1);
    memset(A->tex, 0x5a, A->ntex * sizeof *one);
    memset(&tl, 0, sizeof tl);
    par.par = plx_port_posix()->parallel_for;
    par.ctx = plx_port_posix()->ctx;
    par.progress.fn = count_progress;
    par.progress.ctx = &tl;
    assert_int_equal(atlas_fill(A, wk, 2, &par), PLX_OK);
    assert_memory_equal(one, A->tex, A->ntex * sizeof *one);
    assert_true(A->todo == 0 && A->with_ind == 1);
    assert_true(tl.starts == 1 && tl.ends == 1 && tl.other == 0 && tl.units == tl.total && tl.total > 1);
    assert_true(h[0].bad == 0 && h[1].bad == 0 && h[0].calls + h[1].calls > 0); /* (which worker ran what varies) */
    /* every item in random order, a few at a time, on the second light object */
    clist_make(A, &L);
    items = malloc((L.n + 1) * sizeof *items);
    assert_non_null(items);
    for (k = 0; k < L.n; k++)
        items[k] = L.it[k].item;
    for (k = L.n; k > 1; k--) {
        uint32_t j = rpick(r, k), tmp = items[k - 1];
        items[k - 1] = items[j];
        items[j] = tmp;
    }
    atlas_clear(A, 2);
    memset(A->tex, 0xa5, A->ntex * sizeof *one);
    for (k = 0; k < L.n; k += n) {
        n = 1 + rpick(r, 200);
        n = k + n > L.n ? L.n - k : n;
        assert_int_equal(atlas_fill_items(A, &wk[1], 1, NULL, &items[k], n), PLX_OK);
    }
    assert_true(A->todo == 0);
    assert_memory_equal(one, A->tex, A->ntex * sizeof *one);
    printf("  %s at %.2f m: %llu values, the same bytes on 1 worker, 2 workers (%ld jobs; worker 1 made %ld hook "
           "calls) and %u items in random order\n",
           w->name, fine, (unsigned long long)A->ntex, tl.total, h[1].calls, L.n);
    clist_free(&L);
    free(items);
    free(one);
    free(wk[0].rec);
    free(wk[1].rec);
    free(blk);
    arena_release(&w->e->mem, &mk);
}

/* ---- frames through the engine: memory faults, the eye in a building --------------- */

#define FW 120
#define FH 90

static plx_engine *fault_engine(void **mem)
{
    plx_config cfg;
    plx_engine *e = NULL;
    *mem = calloc(1, (size_t)64 << 20);
    assert_non_null(*mem);
    plx_config_default(&cfg);
    cfg.port = fixture_quiet_port();
    cfg.threads = 1;
    cfg.render_max_width = FW;
    cfg.render_max_height = FH;
    assert_int_equal(plx_engine_create(*mem, (size_t)64 << 20, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, "fixtures/grid-4x4.geojson"), PLX_OK);
    assert_int_equal(plx_indirect_step(e, 5000, 1), PLX_OK);
    return e;
}

static plx_status fault_shot(plx_engine *e, int per_pixel, const double eye[3], float *out)
{
    plx_camera c;
    plx_render_opts o;
    memset(&c, 0, sizeof c);
    memcpy(c.eye, eye, sizeof c.eye);
    c.target[0] = 100;
    c.target[1] = 80;
    c.fov_deg = 60;
    c.width = FW;
    c.height = FH;
    plx_render_opts_default(&o);
    o.no_glow = 1;
    o.per_pixel = per_pixel;
    o.aerial_m_per_texel = 2.0; /* a coarse atlas: the fill is not what is tested here */
    return plx_render(e, &c, &o, NULL, out, NULL);
}

/* The radiance atlas made with an allocation refused at every point,
 * under a budget of SIZE_MAX (plx_config.lightmap_bytes: no limit), where
 * a spacing search's plan that found no scratch still "fits": the atlas
 * is made at the spacing asked with the layout of an engine without
 * faults, or the engine runs out of memory (helper-49 found the count of
 * such a plan, never made, passed on uninitialised: PLX_E_NOMEM where
 * the layout fitted). */
static void test_atlas_faults_no_budget(void **state)
{
    uint64_t n0 = 0;
    int k, n, ok = 0, nomem = 0, search = 0;
    (void)state;
    for (k = 0; k <= 200; k++) {
        plx_config cfg;
        plx_engine *e = NULL;
        plx_status st;
        void *mem = calloc(1, (size_t)64 << 20);
        assert_non_null(mem);
        plx_config_default(&cfg);
        cfg.port = fixture_quiet_port();
        cfg.threads = 1;
        cfg.lightmap_bytes = SIZE_MAX;
        assert_int_equal(plx_engine_create(mem, (size_t)64 << 20, &cfg, &e), PLX_OK);
        assert_int_equal(plx_load_file(e, "fixtures/grid-4x4.geojson"), PLX_OK);
        assert_int_equal(eng_need_render(e), PLX_OK);
        if (k == 0) { /* the requests of the spacing search alone */
            (void)plx_debug_fail_alloc(e, 0);
            assert_true(atlas_spacing_for(&e->mem, e->sc, render_mesh(e->rd), 1.0, SIZE_MAX, NULL) == 1.0);
            search = (int)plx_debug_fail_alloc(e, 0);
        }
        (void)plx_debug_fail_alloc(e, (uint64_t)k); /* k = 0: none refused */
        st = eng_need_atlas(e, 1.0);
        n = (int)plx_debug_fail_alloc(e, 0);
        if (k == 0) {
            assert_int_equal(st, PLX_OK);
            n0 = e->atlas->ntex;
        }
        if (k <= search) /* a plan without scratch: counted again by atlas_create */
            assert_int_equal(st, PLX_OK);
        if (st == PLX_OK) {
            assert_true(e->atlas->fine == 1.0 && e->atlas->ntex == n0);
            ok++;
        } else {
            assert_int_equal(st, PLX_E_NOMEM);
            nomem++;
        }
        plx_engine_destroy(e);
        free(mem);
        if (k > n)
            break; /* past every request: this one made without a fault */
    }
    printf("  atlas with no budget, allocation k refused: %d made as without faults (the first %d in the spacing "
           "search), %d out of memory\n", ok, search, nomem);
    assert_true(search > 0 && nomem > 0);
}

/* An allocation refused at every point of a first atlas frame (the
 * atlas made and filled for it): the frame fails with an error, or gives
 * the image of an engine without faults, or (the atlas did not fit, said
 * in a warning) the image of every pixel shaded; never another image
 * with PLX_OK. */
static void test_frame_faults(void **state)
{
    if (quick()) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    static float ref[FW * FH * 3], pp[FW * FH * 3], img[FW * FH * 3];
    const double eye[3] = { 200, 250, 60 };
    void *m;
    plx_engine *e = fault_engine(&m);
    int k, n, failed = 0, same = 0, shaded = 0, stride = quick() ? 4 : 1; /* quick: every fourth request */
    (void)state;
    assert_int_equal(fault_shot(e, 1, eye, pp), PLX_OK);
    (void)plx_debug_fail_alloc(e, 0); /* counts from here */
    assert_int_equal(fault_shot(e, 0, eye, ref), PLX_OK);
    n = (int)plx_debug_fail_alloc(e, 0) + 1; /* every request of the first atlas frame, and one past them */
    assert_true(n > 1);
    {
        size_t p, lit = 0;
        for (p = 0; p < FW * FH * 3; p++)
            lit += ref[p] > 0.0f;
        assert_true(lit > FW * FH); /* a view worth comparing */
    }
    fixture_done(e, m);
    for (k = 1; k <= n; k += stride) {
        uint32_t warned;
        plx_status st;
        e = fault_engine(&m);
        /* the renderer and the lamps' light made by a first frame without the atlas */
        assert_int_equal(fault_shot(e, 1, eye, img), PLX_OK);
        warned = plx_warning_count(e);
        (void)plx_debug_fail_alloc(e, (uint64_t)k);
        memset(img, 0, sizeof img);
        st = fault_shot(e, 0, eye, img);
        (void)plx_debug_fail_alloc(e, 0);
        if (st != PLX_OK) {
            failed++;
        } else if (memcmp(img, ref, sizeof img) == 0) {
            same++;
        } else {
            assert_true(plx_warning_count(e) > warned);
            assert_memory_equal(img, pp, sizeof img);
            shaded++;
        }
        fixture_done(e, m);
    }
    printf("  first atlas frame with allocation %d..%d (every %d) refused: %d errors, %d the same image, %d every pixel "
           "shaded (warned)\n", 1, n, stride, failed, same, shaded);
    assert_true(same > 0);
}

/* The eye inside a building: frames shade every pixel (the atlas holds
 * no inner faces), so they equal per_pixel frames. */
static void test_eye_inside(void **state)
{
    static float a[FW * FH * 3], b[FW * FH * 3];
    double eye[3];
    void *m;
    plx_engine *e = fault_engine(&m);
    const scene_building *bd = &e->sc->bld[5];
    (void)state;
    eye[0] = 0.5 * (bd->box[0] + bd->box[2]); /* the middle of a (convex) footprint, half way up */
    eye[1] = 0.5 * (bd->box[1] + bd->box[3]);
    eye[2] = 0.5 * (bd->min_height + bd->height);
    assert_int_equal(fault_shot(e, 0, eye, a), PLX_OK);
    assert_true(render_eye_inside(e->rd, eye));
    assert_int_equal(fault_shot(e, 1, eye, b), PLX_OK);
    assert_memory_equal(a, b, sizeof a);
    fixture_done(e, m);
}

/* ---- the atlas's indirect light against the path tracer ------------------------- */

#define AW 320
#define AH 240

/* The ray through the centre of pixel (i, j) of the street camera below. */
static void acc_ray(const double eye[3], const double tg[3], int i, int j, double d[3])
{
    double f[3], rt[3], up[3], l, x, y, th = tan(60.0 * PI / 360.0);
    int k;
    for (k = 0; k < 3; k++)
        f[k] = tg[k] - eye[k];
    l = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (k = 0; k < 3; k++)
        f[k] /= l;
    l = sqrt(f[0] * f[0] + f[1] * f[1]);
    rt[0] = f[1] / l;
    rt[1] = -f[0] / l;
    rt[2] = 0.0;
    up[0] = rt[1] * f[2] - rt[2] * f[1];
    up[1] = rt[2] * f[0] - rt[0] * f[2];
    up[2] = rt[0] * f[1] - rt[1] * f[0];
    x = ((i + 0.5) / AW * 2.0 - 1.0) * th * AW / AH;
    y = (1.0 - (j + 0.5) / AH * 2.0) * th;
    for (k = 0; k < 3; k++)
        d[k] = f[k] + x * rt[k] + y * up[k];
}

/* The surface met through pixel (i, j) within 60 m: a key, 0 for none. */
static uint64_t acc_surface(tracer *T, const double eye[3], const double tg[3], int i, int j, trace_hit *h)
{
    double d[3];
    acc_ray(eye, tg, i, j, d);
    if (trace_ray(T, eye, d, 60.0 * sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), h) == TRACE_SKY)
        return 0;
    if (h->kind == TRACE_WALL)
        return ((uint64_t)1 << 40) | h->edge;
    return h->kind == TRACE_GROUND ? (uint64_t)2 << 40 : 0;
}

/* The atlas's indirect part at a hit point: the atlas filled with and
 * without indirect light, read there (as a frame reads it), the
 * difference times pi / albedo (red: the lamps' default colour has red 1,
 * so red E_indirect is the colour-blind one the path tracer gives). */
static void acc_hook(void *user, const atlas_chart *c, uint32_t sid, const double P[3], const double n[3],
                     double rgb[3])
{
    plx_engine *e = user;
    if (c->kind == ATLAS_WALL) {
        trace_hit h;
        double v[PHOTON_CH];
        memset(&h, 0, sizeof h);
        h.kind = TRACE_WALL;
        h.bld = c->bld;
        h.edge = sid - 2u;
        memcpy(h.p, P, sizeof h.p);
        memcpy(h.n, n, sizeof h.n);
        photon_indirect_hit(e->ph, &h, v);
        rgb[0] = v[1];
        rgb[1] = v[2];
        rgb[2] = v[3];
    } else {
        photon_indirect_rgb(e->ph, P, n, rgb);
    }
}

/* A street view of eixample-4x4 with the command's photons (4 x 65536):
 * at sample pixels away from edges, within 60 m, the atlas's E_indirect
 * against the independent path tracer (tests/ref/ref_indirect.c).
 * Printed and bounded: the mean relative error (what README "The
 * radiance atlas" quotes). The hook is the engine's (renderapi.c's
 * atlas_ind: a wall's own facade chart, else the buffers' lookup). */
static void test_indirect_accuracy(void **state)
{
    if (quick()) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    const double eye[3] = { 298.6, 265.5, 1.7 }, tg[3] = { 261.8, 302.3, 3.0 };
    int paths = quick() ? 4000 : 8000, maxn = quick() ? 20 : 60, n = 0, i, j, k, walls = 0;
    double ref[60], err = 0.0, bias = 0.0, noise = 0.0, bound = 0.25;
    trace_hit hit[60];
    atlas *A0, *A1;
    atlas_worker w;
    void *m;
    plx_engine *e = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    (void)state;
    (void)m;
    for (k = 0; k < 4; k++)
        assert_int_equal(plx_indirect_step(e, 65536, (uint64_t)k + 1), PLX_OK);
    assert_int_equal(eng_need_render(e), PLX_OK);
    assert_int_equal(eng_need(e, ENG_LIGHT, "test"), PLX_OK);
    assert_int_equal(atlas_create(&e->mem, e->sc, render_mesh(e->rd), 0.5, &A0), PLX_OK);
    assert_int_equal(atlas_create(&e->mem, e->sc, render_mesh(e->rd), 0.5, &A1), PLX_OK);
    memset(&w, 0, sizeof w);
    w.lt = e->lt;
    w.rec = malloc(sizeof(double) * atlas_fill_records(A0));
    w.ind_user = e;
    assert_non_null(w.rec);
    assert_int_equal(atlas_fill(A0, &w, 1, NULL), PLX_OK);
    w.ind = acc_hook;
    assert_int_equal(atlas_fill(A1, &w, 1, NULL), PLX_OK);
    for (j = 10; j < AH && n < maxn; j += 16)
        for (i = 10; i < AW && n < maxn; i += 16) {
            trace_hit h, h2;
            uint64_t id = acc_surface(e->ph->T, eye, tg, i, j, &h);
            int di, dj, same = id != 0;
            double se, r;
            for (dj = -2; dj <= 2 && same; dj += 2)
                for (di = -2; di <= 2 && same; di += 2)
                    same = acc_surface(e->ph->T, eye, tg, i + di, j + dj, &h2) == id;
            if (!same)
                continue;
            r = ref_indirect_paths(e->ph->T, e->sc, h.p, h.n, paths, 500u + (uint64_t)n, &se);
            if (!(r > 0.05))
                continue; /* too dark for a relative error */
            noise += se / r;
            ref[n] = r;
            hit[n++] = h;
        }
    assert_true(n >= maxn / 2);
    for (k = 0; k < n; k++) {
        const trace_hit *h = &hit[k];
        uint32_t sid = h->kind == TRACE_WALL ? mesh_wall_id(e->sc, h->edge) : MESH_SURF_GROUND;
        float a[3], b[3];
        double alb = h->kind == TRACE_WALL ? h->albedo : e->sc->ground_albedo, img;
        atlas_sample(A0, sid, h->p, a);
        atlas_sample(A1, sid, h->p, b);
        img = (b[0] - a[0]) * PI / alb;
        err += fabs(img - ref[k]) / ref[k];
        bias += (img - ref[k]) / ref[k];
        walls += h->kind == TRACE_WALL;
    }
    err /= n;
    bias /= n;
    noise /= n;
    printf("  street view %dx%d of eixample-4x4, %d pixels (%d on walls), reference %d paths (its noise %.4f), "
           "4 x 65536 photons: the atlas's E_indirect (records every 8 points, 0.5 m apart) mean relative error "
           "%.4f, mean bias %+.4f; bound %.2f\n",
           AW, AH, n, walls, paths, noise, err, bias, bound);
    assert_true(noise < 0.05);
    assert_true(err <= bound);
    free(w.rec);
    plx_engine_free(e);
}

static void test_determinism(void **state)
{
    rng r = { 0xde7e4u };
    world w;
    (void)state;
    world_open(&w, "hand", NULL, HAND);
    determinism_check(&w, 0.6, &r);
    world_close(&w);
    world_open(&w, "eixample", EIXAMPLE, NULL);
    determinism_check(&w, 1.1, &r);
    world_close(&w);
}

/* ---- atlas_spacing_for -------------------------------------------------------------- */

static void test_spacing(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    rng r = { 0x59ac1u };
    world w;
    int f, k, n = quick() ? 6 : 25, coarser = 0, total = 0;
    const double step = 1.189207115002721;
    (void)state;
    for (f = 0; f < 2; f++) {
        size_t lo, hi;
        world_open(&w, f ? "helsinki" : "eixample", f ? HELSINKI : EIXAMPLE, NULL);
        lo = atlas_plan(&w.e->mem, w.s, w.m, 16.0, NULL);
        hi = atlas_plan(&w.e->mem, w.s, w.m, 0.5, NULL);
        for (k = 0; k <= n; k++) {
            /* the last: a spacing far finer than the budget allows (--texel
             * 0.01), whose first plan is made at ATLAS_GUESS, not at 4 cm */
            double fine = k < n ? runi(&r, 0.3, 2.0) : 0.01, e;
            size_t budget = k < n ? (size_t)exp(runi(&r, log((double)lo), log((double)hi))) : hi;
            uint64_t nt = 0, nplan = 1;
            double got = atlas_spacing_for(&w.e->mem, w.s, w.m, fine, budget, &nt), prev;
            assert_true(got > 0.0);
            e = log(got / fine) / log(step);
            assert_true(fabs(e - floor(e + 0.5)) < 1e-6 && e > -1e-6); /* fine 2^(k/4) */
            assert_true(atlas_plan(&w.e->mem, w.s, w.m, got, &nplan) <= budget);
            assert_true(nt == nplan); /* the count it gives is the plan's at that spacing */
            total++;
            prev = got / step;
            if (k == n) /* the step finer does not fit */
                assert_true(atlas_plan(&w.e->mem, w.s, w.m, prev, NULL) > budget);
            if (prev >= fine * (1.0 - 1e-9) && atlas_plan(&w.e->mem, w.s, w.m, prev, NULL) <= budget) {
                coarser++;
                if (coarser <= 2)
                    printf("  %s: atlas_spacing_for(%.4f, %zu bytes) = %.4f, but %.4f fits (%zu bytes)\n", w.name, fine,
                           budget, got, prev, atlas_plan(&w.e->mem, w.s, w.m, prev, NULL));
            }
        }
        world_close(&w);
    }
    printf("  atlas_spacing_for: %d budgets, %d answers coarser than needed "
           "(test_bug_spacing_too_coarse)\n",
           total, coarser);
}

/* ---- known bugs ------------------------------------------------------------------------ */

/* Each test below is the minimal case of a bug these tests found in
 * commit f8951b5, where it fails (the values it printed there are quoted);
 * it passes once the bug is fixed. PLX_TEST_SKIP_KNOWN_BUGS=1 skips them
 * (to see the rest green on a tree without the fixes). */
static int skip_known_bug(void)
{
    return getenv("PLX_TEST_SKIP_KNOWN_BUGS") != NULL;
}

/* BUG (src/render/atlas.c:150-159 cut_wall, called at :195 per neighbour in
 * vertex order by wall_heights): a wall with two
 * buildings against it over the same edge (stacked parts: one from 0 to 7
 * m, one from 7 to 10 m) is cut by each in turn in the order of their
 * vertices; when the upper part comes first it cuts nothing (it does not
 * reach an end of the wall yet), the lower then cuts up to 7 m, and the
 * chart covers 7 .. 20 m although 7 .. 10 m is hidden by the upper part.
 * Its vertices there are black (inside a solid), so the visible wall
 * above 10 m is darkened by the bilinear mix. Expected: the chart starts
 * at 10 m. */
static const char *STACKED =
    "{\"type\": \"FeatureCollection\", \"properties\": {\"units\": \"m\"},\n"
    " \"features\": [\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"W\", \"height\": 20},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[0,0],[10,0],[10,10],[0,10],[0,0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"upper\", \"height\": 10, \"min_height\": 7},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[10,0],[20,0],[20,10],[10,10],[10,0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"id\": \"lower\", \"height\": 7},\n"
    "   \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[10,0],[20,0],[20,10],[10,10],[10,0]]]}},\n"
    "  {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 15, \"intensity\": 2000, \"radius\": 40},\n"
    "   \"geometry\": {\"type\": \"Point\", \"coordinates\": [30, 5]}}\n"
    " ]}\n";

static void test_bug_stacked_neighbours(void **state)
{
    world w;
    arena_mark mk;
    atlas *A;
    uint32_t pt, found = 0;
    int kind = ATLAS_NONE;
    double bottom = 0.0;
    (void)state;
    if (skip_known_bug())
        skip();
    world_open(&w, "stacked", NULL, STACKED);
    assert_int_equal(w.s->nbld, 3);
    mk = arena_get_mark(&w.e->mem);
    A = make_atlas(&w, 0.7);
    for (pt = w.s->rings[w.s->bld[0].ring_first].first;
         pt < w.s->rings[w.s->bld[0].ring_first].first + w.s->rings[w.s->bld[0].ring_first].count; pt++) {
        uint32_t rf = w.s->rings[w.s->bld[0].ring_first].first, nx = rf + (pt - rf + 1) % 4;
        if (w.s->pts[pt].x == 10.0 && w.s->pts[nx].x == 10.0) { /* W's east wall */
            const atlas_chart *c = &A->chart[pt];
            found = 1;
            printf("  stacked: W's east wall chart from %g m to %g m (visible: 10 .. 20 m)\n", c->o[2],
                   c->o[2] + (c->nv - 1) * (double)c->tv);
            uint32_t j;
            atlas_worker wk;
            kind = c->kind;
            bottom = c->o[2];
            memset(&wk, 0, sizeof wk);
            wk.lt = w.e->lt;
            wk.rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
            assert_int_equal(atlas_fill(A, &wk, 1, NULL), PLX_OK);
            printf("  stacked: its middle column, bottom up:");
            for (j = 0; j < c->nv && c->kind == ATLAS_WALL; j++) {
                float x[3];
                texel_unpack(tex_at(A, c, c->nu / 2, j), x);
                printf(" %.4g m: %.3g;", c->o[2] + j * (double)c->tv, (double)(x[0] + x[1] + x[2]));
            }
            printf("\n");
            {
                /* the visible wall just above the upper part: the mix with a black vertex below */
                double P[3], n[3], E[3];
                float got[3];
                P[0] = 10.0;
                P[1] = 5.0;
                P[2] = 10.1;
                atlas_chart_normal(c, n);
                atlas_sample(A, mesh_wall_id(w.s, pt), P, got);
                ref_illuminance_rgb(w.s, P, n, E);
                printf("  stacked: at (10, 5, 10.1) the atlas gives %.4g, the exact radiance is %.4g\n",
                       (double)(got[0] + got[1] + got[2]), w.s->bld[0].albedo / PI * (E[0] + E[1] + E[2]));
            }
            free(wk.rec);
        }
    }
    arena_release(&w.e->mem, &mk);
    world_close(&w);
    assert_true(found && kind == ATLAS_WALL);
    assert_true(bottom == 10.0); /* f8951b5: 7 (and 0.4504 against 0.8383 at 10.1 m) */
}

/* Walls at a slant get their lamps' light (fixed 2026-11-30). Two
 * buildings, each turned by ten angles about the origin: a box of 40 x 20
 * x 12 m with a lamp 1.5 m in front of the middle of its long wall, and
 * an L (40 x 30, arms 10 m wide) with a lamp in its inner corner. Every
 * vertex of every wall chart against the reference light
 * (tests/ref/ref_light) at the point of its footprint edge computed here
 * from the scene's two corners, a + f (q - a) with f = i / (nu - 1), and
 * the edge's normal: no atlas_vertex_site involved. The chart's
 * direction is a float; the wall's vertices at o + u e lay up to 2.4 um
 * off the wall, half of them inside the building, where its own wall
 * shadows them: at 3 and 10 degrees 71% of the box's lit pixels read
 * under half their light (a new user's report). The L's last vertex of a
 * wall, (nu - 1) tu with a float tu, could pass its reflex corner into
 * the building (a review). Also checks every wall site lies on its
 * edge's line within 1e-9 m, within the edge. */
static void test_rotated_walls_lit(void **state)
{
    static const double deg[] = { 0.0, 1.0, 3.0, 10.0, 27.0, 45.0, 63.0, 89.0, 137.0, 200.0 };
    static const double box[2][6][2] = { { { 0, 0 }, { 40, 0 }, { 40, 20 }, { 0, 20 } },
                                         { { 0, 0 }, { 40, 0 }, { 40, 10 }, { 10, 10 }, { 10, 30 }, { 0, 30 } } };
    static const int npt[2] = { 4, 6 };
    static const double lamp[2][2] = { { 20.0, -1.5 }, { 15.0, 15.0 } };
    static const int lit_wall[2][2] = { { 0, 0 }, { 2, 3 } }; /* walls the lamp lights: most of their vertices */
    size_t d;
    int f;
    (void)state;
    for (f = 0; f < 2; f++)
        for (d = 0; d < sizeof deg / sizeof deg[0]; d++) {
            double t = deg[d] * PI / 180.0, c0 = cos(t), s0 = sin(t), X[6], Y[6], lx, ly;
            char text[4096], *o = text;
            world w;
            atlas *A;
            atlas_worker wk;
            const atlas_chart *c;
            const scene_ring *rg;
            uint32_t i, j, lit[6] = { 0 }, all[6] = { 0 };
            int k, m;
            for (k = 0; k < npt[f]; k++) {
                X[k] = c0 * box[f][k][0] - s0 * box[f][k][1];
                Y[k] = s0 * box[f][k][0] + c0 * box[f][k][1];
            }
            lx = c0 * lamp[f][0] - s0 * lamp[f][1];
            ly = s0 * lamp[f][0] + c0 * lamp[f][1];
            o += sprintf(o, "{\"type\": \"FeatureCollection\", \"properties\": {\"units\": \"m\"}, \"features\": ["
                            "{\"type\": \"Feature\", \"properties\": {\"height\": 12}, \"geometry\": "
                            "{\"type\": \"Polygon\", \"coordinates\": [[");
            for (k = 0; k <= npt[f]; k++)
                o += sprintf(o, "%s[%.17g,%.17g]", k ? "," : "", X[k % npt[f]], Y[k % npt[f]]);
            sprintf(o, "]]}}, {\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 5, \"intensity\": 1000, "
                       "\"radius\": 25}, \"geometry\": {\"type\": \"Point\", \"coordinates\": [%.17g,%.17g]}}]}",
                    lx, ly);
            world_open(&w, f ? "rotated L" : "rotated box", NULL, text);
            A = make_atlas(&w, 0.5);
            memset(&wk, 0, sizeof wk);
            wk.lt = w.e->lt;
            wk.rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
            assert_non_null(wk.rec);
            assert_int_equal(atlas_fill(A, &wk, 1, NULL), PLX_OK);
            rg = &w.s->rings[w.s->bld[0].ring_first];
            assert_int_equal(rg->count, npt[f]);
            for (k = 0; k < (int)rg->count; k++) {
                vec2 a = w.s->pts[rg->first + (uint32_t)k], q = w.s->pts[rg->first + ((uint32_t)k + 1) % rg->count];
                double ex = q.x - a.x, ey = q.y - a.y, len = hypot(ex, ey), n[3] = { ey / len, -ex / len, 0.0 };
                double alb = w.s->bld[0].albedo;
                c = atlas_surface_chart(A, mesh_wall_id(w.s, rg->first + (uint32_t)k));
                assert_non_null(c);
                /* the values against the reference at the edge's own points */
                for (j = 0; j < c->nv; j++)
                    for (i = 0; i < c->nu; i++) {
                        double fr = (double)i / (double)(c->nu - 1), P[3], E[3], v[3];
                        uint32_t got, want;
                        P[0] = a.x + fr * ex;
                        P[1] = a.y + fr * ey;
                        P[2] = c->o[2] + (double)j * c->tv;
                        ref_illuminance_rgb(w.s, P, n, E);
                        for (m = 0; m < 3; m++)
                            v[m] = alb / PI * E[m];
                        want = texel_pack(v[0], v[1], v[2]);
                        got = tex_at(A, c, i, j);
                        lit[k] += want != 0u;
                        all[k]++;
                        if (!(got == want || texel_near(got, want))) {
                            float g[3], x[3];
                            texel_unpack(got, g);
                            texel_unpack(want, x);
                            printf("  %s at %g degrees: wall %d vertex (%u, %u) of (%u, %u) at (%.9g %.9g %.9g): stored "
                                   "%g, reference %g\n",
                                   w.name, deg[d], k, i, j, c->nu, c->nv, P[0], P[1], P[2], g[0], x[0]);
                        }
                        assert_true(got == want || texel_near(got, want));
                    }
                /* every site on the edge's line, within the edge (the bottom and top rows) */
                for (j = 0; j < c->nv; j += c->nv - 1)
                    for (i = 0; i < c->nu; i++) {
                        double P[3], nn[3], off, along;
                        atlas_vertex_site(A, w.e->lt, c, i, j, P, nn);
                        off = fabs((P[0] - a.x) * ey - (P[1] - a.y) * ex) / len;
                        along = ((P[0] - a.x) * ex + (P[1] - a.y) * ey) / len;
                        if (!(off <= 1e-9 && along >= -1e-9 && along <= len + 1e-9))
                            printf("  %s at %g degrees: wall %d vertex (%u, %u) %.3g m off its edge, %.17g along "
                                   "it of %.17g\n", w.name, deg[d], k, i, j, off, along, len);
                        assert_true(off <= 1e-9 && along >= -1e-9 && along <= len + 1e-9);
                        assert_true(fabs(nn[0] - n[0]) <= 1e-15 && fabs(nn[1] - n[1]) <= 1e-15 && nn[2] == 0.0);
                    }
            }
            for (m = 0; m < 2; m++)
                assert_true(lit[lit_wall[f][m]] > all[lit_wall[f][m]] / 2); /* the lamp reaches most of it */
            free(wk.rec);
            world_close(&w);
        }
}

/* BUG (src/render/atlas_fill.c:95-101, atlas_vertex_site): a ground
 * vertex strictly inside a footprint moves to that footprint's nearest
 * boundary point 1 mm out; that point may lie strictly inside another
 * solid (a building sharing the wall: every party wall of a city block),
 * or, past a reflex corner whose outside wedge is narrower than a right
 * angle, inside the same footprint (hand-made N). Its direct light is
 * then 0 (the lamps' segments enter the solid), and visible ground in
 * the cells around the vertex is darkened by the bilinear mix.
 * atlas_fill.h promises "a point on (or 1 mm off) its own surface".
 * Expected: no site strictly inside a solid. */
static void test_bug_ground_site_in_solid(void **state)
{
    world w;
    arena_mark mk;
    atlas *A;
    atlas_worker wk;
    clist L;
    uint32_t k, i, j;
    long inside_all = 0;
    int f;
    (void)state;
    if (skip_known_bug())
        skip();
    for (f = 0; f < 2; f++) {
        long moved = 0, inside = 0, same = 0, shown = 0;
        double worst = 1.0, wx[2] = { 0.0, 0.0 }, wex = 0.0;
        atlas_chart wc;
        float wgot = 0.0f;
        int wci = 0, wcj = 0;
        world_open(&w, f ? "eixample" : "hand", f ? EIXAMPLE : NULL, HAND);
        mk = arena_get_mark(&w.e->mem);
        A = make_atlas(&w, f ? 1.3 : 0.7);
        memset(&wk, 0, sizeof wk);
        wk.lt = w.e->lt;
        wk.rec = malloc((atlas_fill_records(A) + 1) * sizeof(double));
        assert_int_equal(atlas_fill(A, &wk, 1, NULL), PLX_OK);
        clist_make(A, &L);
        for (k = 0; k < L.nkind[ATLAS_GROUND]; k++) {
            const atlas_chart *c = &L.it[L.kind[ATLAS_GROUND][k]].c;
            for (j = 0; j < c->nv; j++)
                for (i = 0; i < c->nu; i++) {
                    double P[3], n[3], V[3];
                    int64_t b, o;
                    atlas_vertex_point(c, i, j, V);
                    b = solid_under(w.s, V[0], V[1]);
                    if (b < 0)
                        continue;
                    atlas_vertex_site(A, w.e->lt, c, i, j, P, n);
                    moved++;
                    o = solid_under(w.s, P[0], P[1]);
                    if (o < 0)
                        continue;
                    inside++;
                    same += o == b;
                    if (shown < 2 || (o == b && same == 1)) {
                        double E[3];
                        ref_illuminance_rgb(w.s, P, n, E);
                        printf("  %s: ground vertex (%.4f, %.4f) inside building %lld: site (%.4f, %.4f) inside "
                               "building %lld, E there %g lx\n",
                               w.name, V[0], V[1], (long long)b, P[0], P[1], (long long)o, E[0] + E[1] + E[2]);
                        shown++;
                    }
                    /* the darkening: visible ground in the four cells around,
                     * atlas against the exact radiance there */
                    {
                        int cq, sq;
                        for (cq = 0; cq < 4; cq++) {
                            int ci = (int)i - (cq & 1), cj = (int)j - (cq >> 1);
                            if (ci < 0 || cj < 0 || ci + 1 >= (int)c->nu || cj + 1 >= (int)c->nv)
                                continue;
                            for (sq = 0; sq < 16; sq++) {
                                double X[3], E[3], ex;
                                float got[3];
                                X[0] = c->o[0] + (ci + (sq % 4 + 0.5) / 4.0) * c->tu;
                                X[1] = c->o[1] + (cj + (sq / 4 + 0.5) / 4.0) * c->tv;
                                X[2] = 0.0;
                                if (under_closed(w.s, X[0], X[1]))
                                    continue;
                                ref_illuminance_rgb(w.s, X, n, E);
                                ex = w.s->ground_albedo / PI * (E[0] + E[1] + E[2]);
                                atlas_sample(A, MESH_SURF_GROUND, X, got);
                                if (ex > 0.05 && (got[0] + got[1] + got[2]) / ex < worst) {
                                    worst = (got[0] + got[1] + got[2]) / ex;
                                    wx[0] = X[0];
                                    wx[1] = X[1];
                                    wex = ex;
                                    wgot = got[0] + got[1] + got[2];
                                    wc = *c;
                                    wci = ci;
                                    wcj = cj;
                                }
                            }
                        }
                    }
                }
        }
        if (worst < 1.0) {
            /* the same bilinear with the vertices whose site lies in a solid
             * taking the light of the nearest visible ground instead */
            double fixedv = 0.0, fu = (wx[0] - wc.o[0]) / wc.tu - wci, fv = (wx[1] - wc.o[1]) / wc.tv - wcj;
            int cq;
            for (cq = 0; cq < 4; cq++) {
                uint32_t vi = (uint32_t)wci + (cq & 1), vj = (uint32_t)wcj + (cq >> 1);
                double P[3], n[3], E[3], wgt = ((cq & 1) ? fu : 1.0 - fu) * ((cq >> 1) ? fv : 1.0 - fv);
                float x[3];
                atlas_vertex_site(A, w.e->lt, &wc, vi, vj, P, n);
                if (solid_under(w.s, P[0], P[1]) >= 0) {
                    double V[3];
                    uint32_t tt;
                    atlas_vertex_point(&wc, vi, vj, V);
                    visible_site(w.s, V[0], V[1], P);
                    ref_illuminance_rgb(w.s, P, n, E);
                    tt = texel_pack(w.s->ground_albedo / PI * E[0], w.s->ground_albedo / PI * E[1],
                                    w.s->ground_albedo / PI * E[2]);
                    texel_unpack(tex_at(A, &wc, vi, vj), x);
                    printf("  %s: vertex (%.4f, %.4f) holds %g (its site lies in a solid); at (%.4f, %.4f), 1 mm off "
                           "the nearest visible facade foot, it would hold ",
                           w.name, V[0], V[1], (double)(x[0] + x[1] + x[2]), P[0], P[1]);
                    texel_unpack(tt, x);
                    printf("%g\n", (double)(x[0] + x[1] + x[2]));
                } else {
                    texel_unpack(tex_at(A, &wc, vi, vj), x);
                }
                fixedv += wgt * (x[0] + x[1] + x[2]);
            }
            printf("  %s: visible ground (%.3f, %.3f): atlas %.4g, exact %.4g, with visible sites %.4g W/(sr m^2)\n",
                   w.name, wx[0], wx[1], wgot, wex, fixedv);
        }
        printf("  %s: %ld ground vertices under solids, %ld of their sites inside a solid (%ld inside their own); "
               "visible ground next to them down to %.0f%% of its exact radiance\n",
               w.name, moved, inside, same, 100.0 * worst);
        inside_all += inside;
        free(wk.rec);
        clist_free(&L);
        arena_release(&w.e->mem, &mk);
        world_close(&w);
    }
    assert_int_equal(inside_all, 0); /* f8951b5: hand 112, eixample 17287 of 47918 */
}

/* BUG (src/render/atlas.c:527-544, atlas_spacing_for): the first guess
 * from a plan at four times the spacing assumes bytes ~ 1 / spacing^2
 * and backs off one step only; the charts' fixed bytes (and the walls',
 * ~ 1 / spacing) make it overshoot, so a spacing coarser than needed is
 * returned even when the one asked for fits. Documented: 'fine' grown by
 * steps of 2^(1/4) until atlas_plan fits. Expected: the spacing asked for
 * when its plan fits the budget exactly. */
static void test_bug_spacing_too_coarse(void **state)
{
    world w;
    const double fine = 1.6;
    size_t budget;
    double got;
    (void)state;
    if (skip_known_bug())
        skip();
    world_open(&w, "helsinki", HELSINKI, NULL);
    budget = atlas_plan(&w.e->mem, w.s, w.m, fine, NULL);
    got = atlas_spacing_for(&w.e->mem, w.s, w.m, fine, budget, NULL);
    printf("  helsinki: atlas_plan(%.2f m) = %zu bytes; atlas_spacing_for(%.2f m, %zu bytes) = %.4f m (plan %zu "
           "bytes)\n",
           fine, budget, fine, budget, got, atlas_plan(&w.e->mem, w.s, w.m, got, NULL));
    world_close(&w);
    assert_true(got == fine); /* f8951b5: 2.6909 (3 steps coarser) */
}

/* BUG (src/render/texel.h:70, texel_pack): floor(c / step + 0.5) rounds
 * c / step = 0.5 - 2^-54 up to 1 (the sum rounds to 1.0), so the code is
 * not the nearest one documented: that channel's error is 0.5 + 2^-54
 * steps. Harmless in size; round-to-nearest would need the fraction
 * compared with 0.5. Expected: blue 0. */
static void test_bug_texel_below_half(void **state)
{
    double b = nextafter(ldexp(1.0, -28), 0.0); /* 0.5 - 2^-54 of the smallest step */
    uint32_t t = texel_pack(1e-6, 0.0, b);
    float out[3];
    (void)state;
    if (skip_known_bug())
        skip();
    texel_unpack(t, out);
    printf("  texel_pack(1e-6, 0, %.17g): blue %g (the nearest code has 0)\n", b, out[2]);
    assert_true(out[2] == 0.0f); /* f8951b5: 7.45058e-09 */
}

/* BUG (src/render/atlas.c:549, atlas_create): arena_get_mark(a) runs in
 * the declarations, before the NULL check that should return
 * PLX_E_INVALID: a NULL arena crashes (SIGSEGV). */
static void test_bug_create_null_arena(void **state)
{
    world w;
    atlas *A = NULL;
    (void)state;
    if (skip_known_bug())
        skip();
    world_open(&w, "hand", NULL, HAND);
    assert_int_equal(atlas_create(NULL, w.s, w.m, 1.0, &A), PLX_E_INVALID); /* f8951b5: SIGSEGV */
    world_close(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_texel_codec),     cmocka_unit_test(test_layout),
        cmocka_unit_test(test_create_errors),   cmocka_unit_test(test_create_counted),
        cmocka_unit_test(test_values),
        cmocka_unit_test(test_frames),          cmocka_unit_test(test_missing_edges),
        cmocka_unit_test(test_sample),          cmocka_unit_test(test_runs_equal_lanes),
        cmocka_unit_test(test_determinism),     cmocka_unit_test(test_frame_faults),
        cmocka_unit_test(test_atlas_faults_no_budget),
        cmocka_unit_test(test_eye_inside),      cmocka_unit_test(test_indirect_accuracy),     cmocka_unit_test(test_spacing),
        cmocka_unit_test(test_bug_stacked_neighbours), cmocka_unit_test(test_bug_ground_site_in_solid),
        cmocka_unit_test(test_bug_spacing_too_coarse), cmocka_unit_test(test_bug_texel_below_half),
        cmocka_unit_test(test_bug_create_null_arena), cmocka_unit_test(test_rotated_walls_lit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
