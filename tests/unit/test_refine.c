/* test_refine: near-viewer refinement along a real path (plx_indirect_refine,
 * munoz2013 §3.3-3.4). A viewer walks across the eixample-4x4 fixture; at
 * every step the lamps within the near radius, nearest first, up to the
 * cache capacity, are requested farthest first. An LRU cache written here
 * follows the same requests; after every step the engine's hits, misses,
 * evictions and LRU order must equal the model's, and along the whole path
 * there must be hits, misses and evictions. */
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lru_along_path),
        cmocka_unit_test(test_hits_keep_atlas),
        cmocka_unit_test(test_recompute_refreshes_cache),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
