/* The arena (parts, marks, budgets, fault injection) and strbuf formatting. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "base/arena.h"
#include "base/strbuf.h"

static void test_arena_parts_and_marks(void **state)
{
    static unsigned char block[4096 + 16];
    arena a;
    arena_mark m;
    void *p, *q, *s;
    (void)state;
    arena_init(&a, block + 1, 4096); /* misaligned on purpose */
    assert_true(((uintptr_t)a.base & 15) == 0);
    p = arena_alloc(&a, PLX_PART_SCENE, 100, 16);
    assert_non_null(p);
    assert_true(((uintptr_t)p & 15) == 0);
    m = arena_get_mark(&a);
    q = arena_alloc(&a, PLX_PART_POLAR, 50, 8);
    s = arena_scratch(&a, 200, 16);
    assert_non_null(q);
    assert_non_null(s);
    assert_true((unsigned char *)s >= (unsigned char *)q + 50);
    assert_int_equal(a.used[PLX_PART_SCENE], 100);
    assert_true(a.used[PLX_PART_POLAR] >= 50);
    assert_true(a.used[PLX_PART_SCRATCH] >= 200);
    arena_release(&a, &m);
    assert_int_equal(a.used[PLX_PART_POLAR], 0);
    assert_int_equal(a.used[PLX_PART_SCRATCH], 0);
    assert_int_equal(a.lo, m.lo);
    assert_true(a.peak[PLX_PART_POLAR] >= 50);
    assert_true(a.peak_total >= 350);
}

static void test_arena_exhaustion(void **state)
{
    static unsigned char block[1024];
    arena a;
    (void)state;
    arena_init(&a, block, sizeof block);
    assert_null(arena_alloc(&a, PLX_PART_SCENE, 2000, 8));
    assert_int_equal(a.failed_part, PLX_PART_SCENE);
    assert_int_equal(a.failed_size, 2000);
    assert_non_null(arena_alloc(&a, PLX_PART_SCENE, 500, 8));
    assert_null(arena_scratch(&a, 600, 8));
    assert_non_null(arena_scratch(&a, 400, 8));
    assert_null(arena_alloc(&a, PLX_PART_SCENE, 200, 8)); /* the two ends may not cross */
    assert_null(arena_calloc(&a, PLX_PART_SCENE, SIZE_MAX / 2, 4, 8)); /* overflow */
}

/* A refused request records the bytes it could have had at that moment:
 * less than it asked for (the message "asked for N bytes; F of C bytes
 * free" read the free bytes after the failed step had released its memory,
 * so F came out larger than N), and the alignment's padding is not free to
 * it. */
static void test_arena_refusal_free(void **state)
{
    static unsigned char block[4096];
    arena a;
    arena_mark m;
    size_t f;
    (void)state;
    arena_init(&a, block, sizeof block);
    assert_non_null(arena_alloc(&a, PLX_PART_SCENE, 100, 8)); /* lo 100: 4 bytes to the next 8 */
    m = arena_get_mark(&a);
    assert_non_null(arena_scratch(&a, 1000, 16));
    f = arena_free_bytes(&a);
    assert_null(arena_alloc(&a, PLX_PART_POLAR, 3500, 8));
    assert_int_equal(a.failed_size, 3500);
    assert_int_equal(a.failed_free, f - 4);
    assert_true(a.failed_free < a.failed_size);
    arena_release(&a, &m); /* the failed step lets go of its scratch */
    assert_true(arena_free_bytes(&a) > a.failed_size);
    assert_int_equal(a.failed_free, f - 4); /* still the figure at the refusal */
    /* the padding to a 64-byte start (28 bytes) is not free to the request */
    f = arena_free_bytes(&a);
    assert_null(arena_alloc(&a, PLX_PART_POLAR, f - 10, 64));
    assert_int_equal(a.failed_free, f - 28);
    assert_non_null(arena_alloc(&a, PLX_PART_POLAR, a.failed_free, 64)); /* and that much fits */
    arena_release(&a, &m);
    /* scratch from the high end: the same figure, and that much fits */
    assert_null(arena_scratch(&a, f + 1, 16));
    assert_int_equal(a.failed_part, PLX_PART_SCRATCH);
    assert_true(a.failed_free < a.failed_size);
    assert_non_null(arena_scratch(&a, a.failed_free, 16));
    assert_null(arena_scratch(&a, 1, 16));
    assert_int_equal(a.failed_free, 0);
}

static void test_arena_budget_and_faults(void **state)
{
    static unsigned char block[4096];
    arena a;
    (void)state;
    arena_init(&a, block, sizeof block);
    a.budget[PLX_PART_LIT] = 100;
    assert_non_null(arena_alloc(&a, PLX_PART_LIT, 60, 1));
    assert_null(arena_alloc(&a, PLX_PART_LIT, 60, 1));
    assert_int_equal(a.failed_part, PLX_PART_LIT);
    assert_non_null(arena_alloc(&a, PLX_PART_SCENE, 60, 1));
    a.requests = 0;
    a.fail_at = 2;
    assert_non_null(arena_alloc(&a, PLX_PART_SCENE, 8, 8));
    assert_null(arena_alloc(&a, PLX_PART_SCENE, 8, 8));
    assert_non_null(arena_alloc(&a, PLX_PART_SCENE, 8, 8));
}

static const char *fmt_fixed(char *buf, double v, int d)
{
    strbuf b;
    sb_init(&b, buf, 64);
    sb_fixed(&b, v, d);
    return buf;
}

static const char *fmt_num(char *buf, double v, int sig)
{
    strbuf b;
    sb_init(&b, buf, 64);
    sb_num(&b, v, sig);
    return buf;
}

static void test_strbuf(void **state)
{
    char buf[64], small[8];
    strbuf b;
    (void)state;
    assert_string_equal(fmt_fixed(buf, 3.14159, 3), "3.142");
    assert_string_equal(fmt_fixed(buf, -0.0004, 3), "0.000");
    assert_string_equal(fmt_fixed(buf, -2.5, 0), "-3");
    assert_string_equal(fmt_fixed(buf, 1234567.0625, 2), "1234567.06");
    assert_string_equal(fmt_fixed(buf, 0.05, 1), "0.1");
    assert_string_equal(fmt_num(buf, 12.0, 6), "12");
    assert_string_equal(fmt_num(buf, 1200.0, 6), "1200");
    assert_string_equal(fmt_num(buf, -4.0, 6), "-4");
    assert_string_equal(fmt_num(buf, 1.5, 6), "1.5");
    assert_string_equal(fmt_num(buf, 0.001234, 3), "0.00123");
    assert_string_equal(fmt_num(buf, 1e300, 6), "1e300");
    assert_string_equal(fmt_num(buf, 2.5e-9, 6), "2.5e-9");
    assert_string_equal(fmt_num(buf, 1.0 / 0.0, 6), "inf");
    assert_string_equal(fmt_num(buf, 0.0 / 0.0, 6), "nan");
    sb_init(&b, small, sizeof small);
    sb_str(&b, "overflowing text");
    assert_string_equal(small, "overflo");
    sb_init(&b, buf, sizeof buf);
    sb_int(&b, INT64_MIN);
    assert_string_equal(buf, "-9223372036854775808");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_arena_parts_and_marks),
        cmocka_unit_test(test_arena_exhaustion),
        cmocka_unit_test(test_arena_refusal_free),
        cmocka_unit_test(test_arena_budget_and_faults),
        cmocka_unit_test(test_strbuf),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
