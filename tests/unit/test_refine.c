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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lru_along_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
