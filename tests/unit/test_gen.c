/* Procedural cities: counts, determinism, validity (every feature loads
 * without a warning, no overlapping footprints, no lamp inside a building)
 * and the eixample block structure, through the public API. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"

typedef struct text {
    char *buf;
    size_t len, cap;
} text;

static int append(void *ctx, const char *data, size_t len)
{
    text *t = ctx;
    if (t->len + len + 1 > t->cap) {
        t->cap = (t->len + len + 1) * 2;
        t->buf = realloc(t->buf, t->cap);
        if (!t->buf)
            return -1;
    }
    memcpy(t->buf + t->len, data, len);
    t->len += len;
    return 0;
}

static int refuse(void *ctx, const char *data, size_t len)
{
    (void)ctx, (void)data, (void)len;
    return 1;
}

static text gen(const char *style, int nx, int ny, uint64_t seed)
{
    text t = { NULL, 0, 0 };
    assert_int_equal(plx_gen_city(style, nx, ny, seed, append, &t), PLX_OK);
    return t;
}

static void load_info(const text *t, plx_scene_info *si, uint32_t *warnings)
{
    size_t mem = (size_t)512 << 20;
    void *block = malloc(mem);
    plx_engine *e;
    assert_int_equal(plx_engine_create(block, mem, NULL, &e), PLX_OK);
    assert_int_equal(plx_load_geojson(e, t->buf, t->len, "gen"), PLX_OK);
    assert_int_equal(plx_scene_info_get(e, si), PLX_OK);
    *warnings = plx_warning_count(e);
    plx_engine_destroy(e);
    free(block);
}

static void test_eixample_30(void **state)
{
    text t = gen("eixample", 30, 30, 1);
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
    free(t.buf);
}

static void test_styles_valid(void **state)
{
    static const char *const styles[] = { "grid", "eixample", "oldtown" };
    size_t k;
    (void)state;
    for (k = 0; k < 3; k++) {
        text t = gen(styles[k], 12, 9, 7);
        plx_scene_info si;
        uint32_t w;
        load_info(&t, &si, &w);
        if (w != 0 || si.skipped_features || si.skipped_lamps || si.overlapping_pairs)
            fail_msg("%s: %u warnings, %u skipped, %u lamps inside, %u overlaps", styles[k], w,
                     si.skipped_features, si.skipped_lamps, si.overlapping_pairs);
        assert_true(si.buildings > 0 && si.lamps > 0);
        if (k == 0)
            assert_int_equal(si.buildings, 12 * 9);
        free(t.buf);
    }
}

static void test_oldtown_110(void **state)
{
    text t = gen("oldtown", 110, 110, 1);
    plx_scene_info si;
    uint32_t w;
    (void)state;
    load_info(&t, &si, &w);
    assert_true(si.buildings >= 11000 && si.buildings <= 13500);
    assert_int_equal(w, 0);
    assert_int_equal(si.overlapping_pairs, 0);
    /* mixed heights around the default 12 m */
    assert_true(si.height_min < 12.0 && si.height_max > 12.0);
    free(t.buf);
}

static void test_determinism(void **state)
{
    text a = gen("oldtown", 6, 5, 42), b = gen("oldtown", 6, 5, 42), c = gen("oldtown", 6, 5, 43);
    (void)state;
    assert_true(a.len == b.len && memcmp(a.buf, b.buf, a.len) == 0);
    assert_false(a.len == c.len && memcmp(a.buf, c.buf, a.len) == 0);
    free(a.buf);
    free(b.buf);
    free(c.buf);
}

static void test_errors(void **state)
{
    text t = { NULL, 0, 0 };
    (void)state;
    assert_int_equal(plx_gen_city("paris", 3, 3, 1, append, &t), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 0, 3, 1, append, &t), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 3, 1001, 1, append, &t), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 3, 3, 1, NULL, &t), PLX_E_INVALID);
    assert_int_equal(plx_gen_city("grid", 3, 3, 1, refuse, NULL), PLX_E_IO);
    free(t.buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_eixample_30),
        cmocka_unit_test(test_styles_valid),
        cmocka_unit_test(test_oldtown_110),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
