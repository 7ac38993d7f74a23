/* test_refine: near-viewer refinement along a real path (plx_indirect_refine,
 * munoz2013 §3.3-3.4). A viewer walks across the eixample-4x4 fixture; at
 * every step the lamps within the near radius, nearest first, up to the
 * cache capacity, are requested farthest first. An LRU cache written here
 * follows the same requests; after every step the engine's hits, misses,
 * evictions and LRU order must equal the model's, and along the whole path
 * there must be hits, misses and evictions. plx_indirect_refine_view
 * centres the same on the ground point a camera looks at. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "fixture.h"
#include "slow.h"

#define MEM ((size_t)256 << 20)

typedef struct model {
    uint32_t cap, n;
    uint32_t *lru;             /* most recent first */
    uint64_t hits, misses, evictions, distinct;
    uint8_t seen[65536];      /* lamps ever requested (the fixture has fewer) */
} model;

static void model_request(model *m, uint32_t lamp)
{
    uint32_t i, k;
    if (!m->seen[lamp & 0xffff]) {
        m->seen[lamp & 0xffff] = 1;
        m->distinct++;
    }
    for (i = 0; i < m->n && m->lru[i] != lamp; i++)
        ;
    if (i < m->n) {
        m->hits++;
    } else {
        m->misses++;
        if (m->n == m->cap) {
            m->evictions++;
            m->n--;
        }
        i = m->n++;
    }
    for (k = i; k > 0; k--)
        m->lru[k] = m->lru[k - 1];
    m->lru[0] = lamp;
}

typedef struct near { double d2; uint32_t id; } near;

static int cmp_near(const void *a, const void *b)
{
    const near *x = a, *y = b;
    if (x->d2 != y->d2)
        return x->d2 < y->d2 ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

static void model_update(model *m, plx_engine *e, const double eye[3], double radius)
{
    plx_scene_info si;
    near *c;
    uint32_t i, n = 0, use;
    plx_scene_info_get(e, &si);
    c = malloc(sizeof *c * (si.lamps + 1));
    for (i = 0; i < si.lamps; i++) {
        plx_lamp l;
        double d2;
        plx_lamp_get(e, i, &l);
        d2 = (l.x - eye[0]) * (l.x - eye[0]) + (l.y - eye[1]) * (l.y - eye[1]);
        if (d2 <= radius * radius) {
            c[n].d2 = d2;
            c[n].id = i;
            n++;
        }
    }
    qsort(c, n, sizeof *c, cmp_near);
    use = n < m->cap ? n : m->cap;
    for (i = use; i > 0; i--)
        model_request(m, c[i - 1].id);
    free(c);
}

static void test_lru_along_path(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    void *mem;
    plx_engine *e = fixture_load_file(fixture_engine(MEM, 0, plx_port_posix(), &mem), "fixtures/eixample-4x4.geojson");
    plx_refine_stats rs;
    static model m;
    double eye[3] = { 0, 0, 1.7 };
    int k, steps = getenv("PLX_TEST_QUICK") ? 40 : 80;
    (void)state;
    assert_int_equal(plx_indirect_refine(e, eye, &rs), PLX_E_NOSCENE);
    assert_int_equal(plx_indirect_step(e, 5000, 1), PLX_OK);
    memset(&m, 0, sizeof m);
    /* the street along y = 266 from west to east, then back along x = 266 */
    for (k = 0; k <= steps; k++) {
        uint32_t i;
        if (k <= steps / 2) {
            eye[0] = -30.0 + 590.0 * k / (steps / 2);
            eye[1] = 266.0;
        } else {
            eye[0] = 266.0;
            eye[1] = 560.0 - 590.0 * (k - steps / 2) / (steps / 2);
        }
        assert_int_equal(plx_indirect_refine(e, eye, &rs), PLX_OK);
        if (!m.lru) {
            assert_true(rs.slots > 0);
            m.cap = rs.slots;
            m.lru = malloc(sizeof *m.lru * m.cap);
        }
        model_update(&m, e, eye, rs.near_radius);
        assert_int_equal(rs.hits, m.hits);
        assert_int_equal(rs.misses, m.misses);
        assert_int_equal(rs.evictions, m.evictions);
        assert_int_equal(rs.cached, m.n);
        for (i = 0; i < m.n && i < PLX_REFINE_LRU_MAX; i++)
            assert_int_equal(rs.lru[i], m.lru[i]);
    }
    assert_true(m.hits > 0);
    assert_true(m.misses > m.cap);
    assert_true(m.evictions > 0);
    /* a lamp is pushed into the improved aerial map once, when first computed */
    assert_int_equal(rs.refined, m.distinct);
    printf("along %d steps: %llu hits, %llu misses, %llu evictions, %llu lamps refined, %u slots\n", steps,
           (unsigned long long)rs.hits, (unsigned long long)rs.misses, (unsigned long long)rs.evictions,
           (unsigned long long)rs.refined, rs.slots);
    free(m.lru);
    fixture_done(e, mem);
}

/* The frames' radiance atlas along a refined walk: a refinement that only
 * hits (the same lamps cached, in another LRU order) keeps the atlas, so
 * what an earlier frame filled stays filled; one that misses changes the
 * indirect light and empties it. Either way a frame equals, byte for byte,
 * the same camera on a fresh engine given the same refinements with no
 * frame between them (its atlas filled for that frame alone). A narrow
 * view fills charts and blocks that the wide one's pixel centres miss.
 * The order of the floor maps' sum is guarded in test_photon
 * (test_lamp_hits_keep_bits): the atlas's 9-bit values hide its last
 * bits, so these frames are the same under either order. */
#define RW 160
#define RH 120

static plx_engine *walk_engine(void **mem)
{
    plx_engine *e = fixture_load_file(fixture_engine(MEM, 0, plx_port_posix(), mem), "fixtures/eixample-4x4.geojson");
    assert_int_equal(plx_indirect_step(e, 5000, 1), PLX_OK);
    assert_int_equal(plx_indirect_step(e, 5000, 2), PLX_OK);
    return e;
}

static void walk_camera(plx_camera *cam, double fov)
{
    memset(cam, 0, sizeof *cam);
    cam->width = RW;
    cam->height = RH;
    cam->fov_deg = fov;
    cam->eye[0] = 266.0; cam->eye[1] = 150.0; cam->eye[2] = 300.0;
    cam->target[0] = 266.0; cam->target[1] = 267.0; cam->target[2] = 0.0;
}

static uint64_t unfilled(plx_engine *e)
{
    plx_atlas_info ai;
    assert_int_equal(plx_atlas_info_get(e, &ai), PLX_OK);
    assert_true(ai.made);
    return ai.unfilled;
}

static void frame(plx_engine *e, double fov, float *rgbf)
{
    plx_camera cam;
    plx_render_opts o;
    plx_render_info info;
    walk_camera(&cam, fov);
    plx_render_opts_default(&o);
    o.aerial = 1;
    assert_int_equal(plx_render(e, &cam, &o, NULL, rgbf, &info), PLX_OK);
    assert_int_equal(info.shaded_pixels, 0); /* read from the atlas */
}

static void test_hits_keep_atlas(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    double A[3] = { 200.0, 266.0, 1.7 }, A2[3] = { 198.0, 266.0, 1.7 }, B[3] = { 560.0, 266.0, 1.7 };
    size_t n = (size_t)RW * RH * 3;
    float *walk = malloc(n * sizeof(float)), *fresh = malloc(n * sizeof(float));
    void *m1, *m2;
    plx_engine *e = walk_engine(&m1), *f;
    plx_refine_stats rs, r1;
    uint64_t kept, alone;
    (void)state;
    assert_int_equal(plx_indirect_refine(e, A, &rs), PLX_OK);
    assert_true(rs.misses_now > 0);
    r1 = rs;
    frame(e, 20.0, walk);
    assert_int_equal(plx_indirect_refine(e, A2, &rs), PLX_OK);
    assert_int_equal(rs.misses_now, 0);
    assert_true(rs.hits > r1.hits);
    assert_int_equal(rs.cached, r1.cached);
    assert_true(memcmp(rs.lru, r1.lru, rs.cached * sizeof rs.lru[0]) != 0); /* reordered */
    frame(e, 60.0, walk);
    kept = unfilled(e);
    f = walk_engine(&m2);
    assert_int_equal(plx_indirect_refine(f, A, &rs), PLX_OK);
    assert_int_equal(plx_indirect_refine(f, A2, &rs), PLX_OK);
    frame(f, 60.0, fresh);
    alone = unfilled(f);
    assert_true(kept < alone);     /* the narrow frame's fills were kept */
    assert_memory_equal(walk, fresh, n * sizeof(float));
    /* a miss: the atlas starts again */
    assert_int_equal(plx_indirect_refine(e, B, &rs), PLX_OK);
    assert_true(rs.misses_now > 0);
    frame(e, 60.0, walk);
    assert_int_equal(plx_indirect_refine(f, B, &rs), PLX_OK);
    frame(f, 60.0, fresh);
    assert_int_equal(unfilled(e), unfilled(f));
    assert_memory_equal(walk, fresh, n * sizeof(float));
    printf("after a refinement of hits alone: %llu charts and blocks unfilled (the narrow frame's fills kept), "
           "%llu on a fresh engine\n", (unsigned long long)kept, (unsigned long long)alone);
    free(walk);
    free(fresh);
    fixture_done(f, m2);
    fixture_done(e, m1);
}

/* A miss that computes an evicted lamp's floor map again (no new lamp
 * refined, no progressive chart restarted) changes the light near it:
 * frames that shade every pixel through the irradiance cache must see
 * it. Along y = 266 the cache evicts the lamps of the walk's start; back
 * at the start they miss again, and a per-pixel frame there equals the
 * same camera on a fresh engine given the same refinements. */
static void street_frame(plx_engine *e, float *rgbf)
{
    plx_camera cam;
    plx_render_opts o;
    memset(&cam, 0, sizeof cam);
    cam.width = 80;
    cam.height = 60;
    cam.fov_deg = 60;
    cam.eye[0] = 200.0; cam.eye[1] = 266.0; cam.eye[2] = 1.7;
    cam.target[0] = 240.0; cam.target[1] = 270.0; cam.target[2] = 3.0;
    plx_render_opts_default(&o);
    o.per_pixel = 1;
    assert_int_equal(plx_render(e, &cam, &o, NULL, rgbf, NULL), PLX_OK);
}

static void refine_along(plx_engine *e, plx_refine_stats *rs)
{
    double eye[3] = { 0.0, 266.0, 1.7 };
    int k;
    for (k = 0; k <= 18; k++) {
        eye[0] = 200.0 + 20.0 * k;
        assert_int_equal(plx_indirect_refine(e, eye, rs), PLX_OK);
    }
}

static void test_recompute_refreshes_cache(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    double A[3] = { 200.0, 266.0, 1.7 };
    size_t n = 80 * 60 * 3;
    float *before = malloc(n * sizeof(float)), *after = malloc(n * sizeof(float)), *fresh = malloc(n * sizeof(float));
    void *m1, *m2;
    plx_engine *e = walk_engine(&m1), *f;
    plx_refine_stats rs;
    uint64_t refined, evictions;
    (void)state;
    assert_int_equal(plx_indirect_refine(e, A, &rs), PLX_OK);
    refine_along(e, &rs);
    street_frame(e, before);
    refined = rs.refined;
    evictions = rs.evictions;
    assert_true(evictions > 0);
    assert_int_equal(plx_indirect_refine(e, A, &rs), PLX_OK);
    assert_true(rs.misses_now > 0);
    assert_int_equal(rs.refined, refined); /* computed again, none new */
    street_frame(e, after);
    f = walk_engine(&m2);
    assert_int_equal(plx_indirect_refine(f, A, &rs), PLX_OK);
    refine_along(f, &rs);
    assert_int_equal(plx_indirect_refine(f, A, &rs), PLX_OK);
    street_frame(f, fresh);
    assert_memory_equal(after, fresh, n * sizeof(float));
    assert_memory_not_equal(before, after, n * sizeof(float));
    printf("back at the start: %u floor maps computed again (%llu evictions before), the per-pixel frame as a "
           "fresh engine's\n", rs.misses_now, (unsigned long long)evictions);
    free(before);
    free(after);
    free(fresh);
    fixture_done(f, m2);
    fixture_done(e, m1);
}

/* plx_indirect_refine_view: the centre, computed here another way (the
 * point eye + t d at height 0, if any, and its horizontal distance from
 * the eye, else half the radius along the view), and the lamps requested
 * around it, nearest first, as the LRU model has them. */
static void view_centre(const plx_camera *c, double radius, double out[2])
{
    double d[3], h, t, ahead = 0.5 * radius;
    int k;
    for (k = 0; k < 3; k++)
        d[k] = c->target[k] - c->eye[k];
    h = hypot(d[0], d[1]);
    out[0] = c->eye[0];
    out[1] = c->eye[1];
    if (h == 0.0 || c->eye[2] <= 0.0) /* straight down, or no height to look from */
        return;
    if (d[2] < 0.0) {
        t = c->eye[2] / -d[2];  /* eye + t d is on the ground */
        if (t * h < ahead)
            ahead = t * h;
    }
    out[0] += d[0] / h * ahead;
    out[1] += d[1] / h * ahead;
}

static void set_camera(plx_camera *c, double ex, double ey, double ez, double tx, double ty, double tz)
{
    memset(c, 0, sizeof *c);
    c->eye[0] = ex; c->eye[1] = ey; c->eye[2] = ez;
    c->target[0] = tx; c->target[1] = ty; c->target[2] = tz;
    c->fov_deg = 60.0;
    c->width = 640;
    c->height = 480;
}

static void test_view_centre(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    static const double cams[][6] = {
        { 100, 266, 1.7, 110, 266, 1.7 },   /* level: half the radius ahead */
        { 100, 266, 40, 180, 266, 0 },      /* meets the ground 80 m ahead: clamped */
        { 100, 266, 40, 110, 266, 0 },      /* meets it 10 m ahead */
        { 100, 266, 40, 100, 266, 0 },      /* straight down */
        { 300, 200, 20, 303, 204, -20 },    /* 2.5 m ahead, on a diagonal */
        { 266, 100, 1.7, 266, 110, 50 },    /* looking up */
        { 266, 400, 0, 276, 400, -5 },      /* the eye on the ground */
        { 266, 400, -5, 276, 400, 10 },     /* below it, looking up: its ground point */
        { 266, 400, -5, 276, 400, -9 },     /* below it, looking down */
        { 0, 0, 40, 1e-200, 0, 40 },        /* level, a direction too short to square */
    };
    void *mem;
    plx_engine *e = fixture_load_file(fixture_engine(MEM, 0, plx_port_posix(), &mem), "fixtures/eixample-4x4.geojson");
    plx_refine_stats rs;
    plx_camera c;
    static model m;
    size_t k;
    (void)state;
    set_camera(&c, 100, 266, 40, 180, 266, 0);
    assert_int_equal(plx_indirect_refine_view(e, &c, &rs), PLX_E_NOSCENE);
    assert_int_equal(plx_indirect_step(e, 5000, 1), PLX_OK);
    assert_int_equal(plx_indirect_refine_view(e, NULL, &rs), PLX_E_INVALID);
    assert_int_equal(plx_indirect_refine_view(NULL, &c, &rs), PLX_E_INVALID);
    c.eye[1] = NAN;
    assert_int_equal(plx_indirect_refine_view(e, &c, &rs), PLX_E_INVALID);
    c.target[1] = INFINITY;
    c.eye[1] = 266;
    assert_int_equal(plx_indirect_refine_view(e, &c, &rs), PLX_E_INVALID);
    memset(&m, 0, sizeof m);
    for (k = 0; k < sizeof cams / sizeof cams[0]; k++) {
        double want[2], centre[3];
        uint32_t i;
        set_camera(&c, cams[k][0], cams[k][1], cams[k][2], cams[k][3], cams[k][4], cams[k][5]);
        assert_int_equal(plx_indirect_refine_view(e, &c, &rs), PLX_OK);
        if (!m.lru) {
            m.cap = rs.slots;
            m.lru = malloc(sizeof *m.lru * m.cap);
        }
        view_centre(&c, rs.near_radius, want);
        assert_true(fabs(rs.centre[0] - want[0]) < 1e-9 && fabs(rs.centre[1] - want[1]) < 1e-9);
        centre[0] = want[0];
        centre[1] = want[1];
        centre[2] = 0.0;
        model_update(&m, e, centre, rs.near_radius);
        assert_int_equal(rs.hits, m.hits);
        assert_int_equal(rs.misses, m.misses);
        assert_int_equal(rs.cached, m.n);
        for (i = 0; i < m.n && i < PLX_REFINE_LRU_MAX; i++)
            assert_int_equal(rs.lru[i], m.lru[i]);
    }
    free(m.lru);
    fixture_done(e, mem);
}

/* Whether lamp l's foot is inside camera c's frame (up is +z). */
static int in_frame(const plx_camera *c, const plx_lamp *l)
{
    double f[3], r[3], u[3], q[3], n, z, x, y, t = tan(c->fov_deg * 3.14159265358979323846 / 360.0);
    int k;
    for (k = 0; k < 3; k++)
        f[k] = c->target[k] - c->eye[k];
    n = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (k = 0; k < 3; k++)
        f[k] /= n;
    n = hypot(f[0], f[1]);
    r[0] = f[1] / n; r[1] = -f[0] / n; r[2] = 0.0;
    u[0] = r[1] * f[2] - r[2] * f[1];
    u[1] = r[2] * f[0] - r[0] * f[2];
    u[2] = r[0] * f[1] - r[1] * f[0];
    q[0] = l->x - c->eye[0];
    q[1] = l->y - c->eye[1];
    q[2] = -c->eye[2];
    z = q[0] * f[0] + q[1] * f[1] + q[2] * f[2];
    if (!(z > 0.0))
        return 0;
    x = (q[0] * r[0] + q[1] * r[1] + q[2] * r[2]) / (z * t * c->width / c->height);
    y = (q[0] * u[0] + q[1] * u[1] + q[2] * u[2]) / (z * t);
    return fabs(x) <= 1.0 && fabs(y) <= 1.0;
}

/* The lamps chosen around centre (nearest first, up to cap, within the
 * radius) whose feet the camera shows. */
static uint32_t chosen_in_frame(plx_engine *e, const plx_camera *c, const double centre[3], const model *m,
                                double radius, uint32_t *chosen)
{
    model one;
    uint32_t i, shown = 0;
    memset(&one, 0, sizeof one);
    one.cap = m->cap;
    one.lru = malloc(sizeof *one.lru * one.cap);
    model_update(&one, e, centre, radius);
    for (i = 0; i < one.n; i++) {
        plx_lamp l;
        assert_int_equal(plx_lamp_get(e, one.lru[i], &l), PLX_OK);
        shown += (uint32_t)in_frame(c, &l);
    }
    *chosen += one.n;
    free(one.lru);
    return shown;
}

/* A flight at 40 m along y = 266 looking 120 m ahead at the ground: the
 * lamps refined around the view's centre are more often in the frame
 * than those around the eye, most of them under or behind it. */
static void test_view_refines_what_it_shows(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    void *mem;
    plx_engine *e = fixture_load_file(fixture_engine(MEM, 0, plx_port_posix(), &mem), "fixtures/eixample-4x4.geojson");
    plx_refine_stats rs;
    plx_camera c;
    model m;
    uint32_t by_view = 0, by_eye = 0, n_view = 0, n_eye = 0;
    int k;
    (void)state;
    assert_int_equal(plx_indirect_step(e, 5000, 1), PLX_OK);
    memset(&m, 0, sizeof m);
    for (k = 0; k < 20; k++) {
        double x = 20.0 * k;
        set_camera(&c, x, 266, 40, x + 120, 266, 0);
        assert_int_equal(plx_indirect_refine_view(e, &c, &rs), PLX_OK);
        m.cap = rs.slots;
        by_view += chosen_in_frame(e, &c, rs.centre, &m, rs.near_radius, &n_view);
        by_eye += chosen_in_frame(e, &c, c.eye, &m, rs.near_radius, &n_eye);
    }
    printf("along 20 views from 40 m: %u of %u lamps refined around the view's centre in the frame, %u of %u "
           "around the eye\n", by_view, n_view, by_eye, n_eye);
    assert_true(by_view > 0);
    assert_true((double)by_view / n_view > 1.5 * (double)by_eye / n_eye);
    fixture_done(e, mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lru_along_path),
        cmocka_unit_test(test_hits_keep_atlas),
        cmocka_unit_test(test_recompute_refreshes_cache),
        cmocka_unit_test(test_view_centre),
        cmocka_unit_test(test_view_refines_what_it_shows),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
