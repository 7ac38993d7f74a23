/* The streaming loader (src/scene/geojson.c, src/base/jsoncheck.c,
 * src/base/jsonscan.c):
 *  - jsonscan_check accepts exactly what cJSON parses and fails at the byte
 *    cJSON reports, on hand-written cases, every corpus and fixture file and
 *    random mutations of them; where cJSON parses, every value read in place
 *    (kinds, numbers bit for bit, unescaped strings, children, the member
 *    found for each key) equals cJSON's tree;
 *  - an application's own cJSON hooks are neither called nor changed by a
 *    load (issue #12);
 *  - the load peak on a generated scene (about 50 MB in the full run, 1 MB
 *    in the quick one): the engine's high-water mark is the scene plus a
 *    window of 8 bytes a feature, 32 bytes a vertex and 1 MiB, and the
 *    process's resident set grows by no more than that (issue #16). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <cmocka.h>
#include <cjson/cJSON.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "port.h"
#include "base/jsonscan.h"
#include "fixture.h"

/* ---- the same values as cJSON ----------------------------------------------- */

static void same_value(const char *t, size_t len, const cJSON *node, size_t off);

static void same_children(const char *t, size_t len, const cJSON *node, size_t off)
{
    const cJSON *c;
    size_t mine = jsonscan_first(t, len, off);
    int obj = cJSON_IsObject(node);
    for (c = node->child; c; c = c->next) {
        assert_true(mine != JSONSCAN_NONE);
        same_value(t, len, c, mine);
        if (obj) {
            /* the member found for this key: cJSON's first with it */
            const cJSON *want = cJSON_GetObjectItemCaseSensitive(node, c->string);
            size_t got = jsonscan_get(t, len, off, c->string), k = jsonscan_first(t, len, off);
            const cJSON *w = node->child;
            while (w != want) {
                w = w->next;
                k = jsonscan_next(t, len, k, 1);
            }
            assert_true(got == k);
        }
        mine = jsonscan_next(t, len, mine, obj);
    }
    assert_true(mine == JSONSCAN_NONE);
}

static void same_value(const char *t, size_t len, const cJSON *node, size_t off)
{
    js_kind k = jsonscan_kind(t, off);
    if (cJSON_IsNull(node))
        assert_int_equal(k, JS_NULL);
    else if (cJSON_IsFalse(node))
        assert_int_equal(k, JS_FALSE);
    else if (cJSON_IsTrue(node))
        assert_int_equal(k, JS_TRUE);
    else if (cJSON_IsNumber(node)) {
        size_t n = jsonscan_number_len(t, len, off);
        char buf[4096];
        double v;
        assert_int_equal(k, JS_NUMBER);
        assert_true(n > 0 && n < sizeof buf);
        memcpy(buf, t + off, n);
        buf[n] = '\0';
        v = strtod(buf, NULL);
        assert_memory_equal(&v, &node->valuedouble, sizeof v);
    } else if (cJSON_IsString(node)) {
        size_t n = strlen(node->valuestring);
        char *buf = malloc(n + 1);
        assert_int_equal(k, JS_STRING);
        assert_int_equal(jsonscan_string(t, len, off, buf, n + 1), n);
        assert_string_equal(buf, node->valuestring);
        assert_true(jsonscan_string_is(t, len, off, node->valuestring));
        free(buf);
    } else {
        assert_int_equal(k, cJSON_IsArray(node) ? JS_ARRAY : JS_OBJECT);
        same_children(t, len, node, off);
    }
    assert_true(jsonscan_skip(t, len, off) <= len);
}

static unsigned long checked, parsed;

/* jsonscan_check against cJSON on one text. */
static void compare(const char *t, size_t len)
{
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(len ? t : "", len, &end, 0);
    size_t at = 12345;
    int ok = jsonscan_check(len ? t : "", len, &at);
    checked++;
    if (ok != (root != NULL) || (end && at != (size_t)(end - t) && len))
        fail_msg("jsonscan_check %d at %zu, cJSON %d at %ld, on %zu bytes: %.*s", ok, at, root != NULL,
                 end ? (long)(end - t) : -1L, len, (int)(len < 200 ? len : 200), t);
    if (root) {
        size_t p = len >= 5 && memcmp(t, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
        parsed++;
        same_value(t, len, root, jsonscan_ws(t, len, p));
        cJSON_Delete(root);
    }
}

static const char *const cases[] = {
    "", " ", "\n\t ", "null", "nul", "true", "tru", "false", "fals", "[", "]", "{", "}", "[]", "{}", "[ ]",
    "{ }", "[1,]", "[1 2]", "[,1]", "{\"a\"}", "{\"a\":}", "{\"a\":1,}", "{\"a\":1,", "{\"a\":1, ", "{a:1}",
    "{\"a\" 1}", "{1:2}", "[\"abc", "[\"ab\\", "[\"a\\q\"]", "[\"\\u12\"]", "[\"\\u12G4\"]", "[\"\\uZZZZ\"]",
    "[\"\\uD800\"]", "[\"\\uD800\\u0041\"]", "[\"\\uD83D\\uDE00\"]", "[\"\\uDE00\"]", "[\"\\u0000abc\"]",
    "[\"a\\u00e9\\u20AC\"]", "[\"\\u005\\\\\"]", "[\"\\u12\\\"x\"]", "[\"\\/\\b\\f\\n\\r\\t\\\"\\\\\"]",
    "[-]", "[--1]", "[-+1]", "[+1]", "[.5]", "[-.5]", "[1.]", "[01]", "[1.2.3]", "[1e]", "[1e+]", "[1e5e5]",
    "[1E-3]", "[0x10]", "[-inf]", "[1-2]", "[1e999]", "[-0]", "1 2", "1x", "[1]x", "{}\0garbage",
    "\xEF\xBB\xBF{}", "\xEF\xBB\xBF[]", "\xEF\xBB\xBF", "\xEF\xBB\xBF 1", "[\x01\x02 1\x1f]", "[\"\x01\n\"]",
    "[1,\0002]", "{\"a\":[{\"b\":[[[]]]}],\"a\":2}", "{\"a\\u0000x\":1,\"a\":2}", "{\"\":{\"\":\"\"}}",
    "[\"\xff\xfe\"]", "[123456789012345678901234567890123456789012345678901234567890123456789012345678901234567890]",
    "[1.00000000000000011102230246251565404236316680908203125]", "[true false]", "[nulll]", "[truex]",
};

static void test_check_cases(void **state)
{
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t n = strlen(cases[i]);
        compare(cases[i], n);
        /* every prefix: where a truncated text fails */
        while (n-- > 0)
            compare(cases[i], n);
    }
    compare("{}\0garbage", 10);
    compare("[1,\0002]", 6);
}

static char *nested(int depth, int objects, size_t *len)
{
    char *t = malloc((size_t)depth * 8 + 16);
    size_t n = 0;
    int i;
    for (i = 0; i < depth; i++)
        n += (size_t)sprintf(t + n, objects && i % 2 ? "{\"k\":" : "[");
    t[n++] = '1';
    for (i = depth - 1; i >= 0; i--)
        t[n++] = objects && i % 2 ? '}' : ']';
    *len = n;
    return t;
}

static void test_check_depth(void **state)
{
    static const int depths[] = { 999, 1000, 1001, 1500 };
    size_t i, len;
    (void)state;
    for (i = 0; i < sizeof depths / sizeof depths[0]; i++) {
        char *t = nested(depths[i], 0, &len);
        compare(t, len);
        free(t);
        t = nested(depths[i], 1, &len);
        compare(t, len);
        compare(t, len / 2);
        free(t);
    }
}

static uint64_t rng_state = 88172645463325252ull;

static uint32_t rnd(uint32_t n)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint32_t)(rng_state % n);
}

/* A random edit of text: a byte replaced, inserted or removed, or the end cut. */
static size_t mutate(char *t, size_t len, size_t cap)
{
    static const char alphabet[] = "[]{}\",:\\u0123456789eE.+-DdCcFfbnrt/ \t\n\001x";
    uint32_t op = rnd(4), k = len ? rnd((uint32_t)len) : 0;
    char c = alphabet[rnd(sizeof alphabet)]; /* the final NUL too */
    if (op == 0 && len > 0) {
        t[k] = c;
    } else if (op == 1 && len + 1 < cap) {
        memmove(t + k + 1, t + k, len - k);
        t[k] = c;
        len++;
    } else if (op == 2 && len > 0) {
        memmove(t + k, t + k + 1, len - k - 1);
        len--;
    } else {
        len = k;
    }
    return len;
}

static void mutate_file(const char *path, int rounds)
{
    char err[256], *buf;
    size_t len, cap;
    char *text = port_read_text(path, &len, err, sizeof err);
    int r, e;
    assert_non_null(text);
    compare(text, len);
    cap = len + 64;
    buf = malloc(cap);
    for (r = 0; r < rounds; r++) {
        size_t n = len;
        memcpy(buf, text, len);
        for (e = 0; e <= (int)rnd(3); e++)
            n = mutate(buf, n, cap);
        compare(buf, n);
    }
    free(buf);
    free(text);
}

static void test_check_files(void **state)
{
    static const char *const small[] = {
        "fixtures/tiny.geojson", "fixtures/ground-image.geojson", "fixtures/net-detour.geojson",
        "tests/corpus/control-characters.geojson", "tests/corpus/truncated-in-escape.geojson",
        "tests/corpus/truncated-in-number.geojson", "tests/corpus/nan-infinity-strings.geojson",
        "tests/corpus/huge-numbers.geojson", "tests/corpus/wrong-types-structure.geojson",
        "tests/corpus/wrong-types-lamp.geojson", "tests/corpus/deep-nesting-within-limit.geojson",
    };
    static const char *const whole[] = {
        "fixtures/helsinki-centre.geojson", "fixtures/eixample-4x4.geojson", "fixtures/oldtown-8x8.geojson",
        "tests/corpus/deep-nesting-arrays.geojson", "tests/corpus/deep-nesting-objects.geojson",
        "tests/corpus/truncated-in-string.geojson", "tests/corpus/truncated-after-key.geojson",
        "tests/corpus/empty.geojson", "tests/corpus/whitespace-only.geojson", "tests/corpus/infinity-bare.geojson",
    };
    int rounds = getenv("PLX_TEST_QUICK") ? 300 : 20000;
    size_t i;
    (void)state;
    for (i = 0; i < sizeof whole / sizeof whole[0]; i++)
        mutate_file(whole[i], 0);
    for (i = 0; i < sizeof small / sizeof small[0]; i++)
        mutate_file(small[i], rounds);
    print_message("%lu texts checked against cJSON, %lu of them parsed and read in place\n", checked, parsed);
}

/* ---- the application's cJSON hooks (#12) ------------------------------------------ */

static unsigned long app_mallocs, app_frees;

static void *app_malloc(size_t n)
{
    app_mallocs++;
    return malloc(n);
}

static void app_free(void *p)
{
    app_frees++;
    free(p);
}

static void test_app_hooks_survive_a_load(void **state)
{
    cJSON_Hooks hooks = { app_malloc, app_free };
    plx_engine *e;
    plx_config cfg;
    cJSON *j;
    char err[256];
    size_t len;
    char *text = port_read_text("fixtures/helsinki-centre.geojson", &len, err, sizeof err);
    unsigned long before;
    (void)state;
    assert_non_null(text);
    cJSON_InitHooks(&hooks);
    j = cJSON_Parse("{\"a\":[1,2]}");
    assert_non_null(j);
    cJSON_Delete(j);
    assert_true(app_mallocs > 0 && app_frees == app_mallocs);
    plx_config_default(&cfg);
    assert_int_equal(plx_engine_new(64u << 20, &cfg, &e), PLX_OK);
    before = app_mallocs;
    assert_int_equal(plx_load_geojson(e, text, len, "h"), PLX_OK);
    assert_int_equal(plx_load_geojson(e, "[", 1, "bad"), PLX_E_PARSE);
    assert_int_equal(app_mallocs, before); /* the load did not use them */
    /* and they are still the application's */
    j = cJSON_Parse("{\"b\":\"x\"}");
    assert_non_null(j);
    cJSON_Delete(j);
    assert_true(app_mallocs > before && app_frees == app_mallocs);
    cJSON_InitHooks(NULL);
    plx_engine_free(e);
    free(text);
}

/* ---- the load peak (#16) ------------------------------------------------------------ */

static long max_rss_kib(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;
}

static void test_load_peak(void **state)
{
    int quick = getenv("PLX_TEST_QUICK") != NULL, n = quick ? 12 : 86;
    size_t block = quick ? (size_t)8 << 20 : (size_t)64 << 20; /* the --mem stated */
    fixture_city g;
    plx_scene_size sz;
    plx_memory_report m;
    plx_engine *e;
    plx_config cfg;
    size_t window;
    long rss0, rss1;
    (void)state;
    fixture_gen("eixample", n, n, 1, &g);
    assert_int_equal(plx_scene_size_scan(g.buf, g.len, &sz), PLX_OK);
    plx_config_default(&cfg);
    assert_int_equal(plx_engine_new(block, &cfg, &e), PLX_OK);
    rss0 = max_rss_kib();
    assert_int_equal(plx_load_geojson(e, g.buf, g.len, "gen"), PLX_OK);
    rss1 = max_rss_kib();
    plx_memory_get(e, &m);
    window = 8 * (size_t)sz.features + 32 * (size_t)sz.positions + ((size_t)1 << 20);
    print_message("gen eixample %d %d: %zu bytes of text, %llu features, %llu vertices; in a %zu-byte block the "
                  "load peaks at %zu bytes = scene %zu + %zu (window allowed %zu); resident set +%ld KiB\n",
                  n, n, g.len, (unsigned long long)sz.features, (unsigned long long)sz.positions, block,
                  m.peak_total, m.used[PLX_PART_SCENE], m.peak_total - m.used_total, window, rss1 - rss0);
    assert_true(m.peak_total <= m.used_total + window);
    /* the parse tree of the old loader alone was about 9x the text */
    assert_true(m.peak_total < g.len + g.len / 2);
    /* nothing outside the block grew either (4 MiB for the C library) */
    assert_true((size_t)(rss1 - rss0) * 1024 <= m.peak_total + ((size_t)4 << 20));
    plx_engine_free(e);
    free(g.buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_load_peak), /* first: the process's resident set is measured */
        cmocka_unit_test(test_check_cases),
        cmocka_unit_test(test_check_depth),
        cmocka_unit_test(test_check_files),
        cmocka_unit_test(test_app_hooks_survive_a_load),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
