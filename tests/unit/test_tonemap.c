/* test_tonemap: the tone map's table of float thresholds (src/render/
 * tonemap.c) gives the same byte as the direct computation (exposure, tone
 * curve, search of SPEC §5's thresholds: tonemap_value) for every value
 * tried: floats spread over the whole positive range, 300 floats each side
 * of every threshold the table found, and zero, negatives, subnormals,
 * the largest float, infinities and NaN; at exposures from 1e-30 to 1e120
 * (the last too large for the table: its values go the direct way), with
 * and without the curve. Runs of +0 (32 at once when all are) of every length
 * up to the window's end, beside -0, the smallest floats and NaN, in
 * random windows p0 .. p1 of a buffer: the same bytes, and none written
 * outside the window. Each batch's answer whether a value lies beyond
 * +-FLT_MAX / 4 or is NaN (the 2 x 2 sums' limit) against a scan. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <float.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "base/bits.h"
#include "render/tonemap.h"

#define SPREAD 4099u   /* a stride through the positive float bits */
#define NEAR 300u      /* floats each side of a threshold */
#define BUF 4096


typedef struct batch {
    float x[BUF];
    uint8_t got[BUF];
    size_t n;
    size_t checked, lit, far;
} batch;

/* The batch's bytes from the table against tonemap_value, one by one. */
static void flush(batch *b, const tonemap_table *t, const double *thr, double ex, int curve)
{
    size_t i;
    int far = tonemap_apply(t, thr, b->x, 0, b->n, b->got), want_far = 0;
    for (i = 0; i < b->n; i++)
        want_far |= !(fabsf(b->x[i]) <= FLT_MAX / 4.0f);
    if (far != want_far)
        fail_msg("ex %g curve %d: a batch of %zu values says far %d, not %d", ex, curve, b->n, far, want_far);
    b->far += far;
    for (i = 0; i < b->n; i++) {
        uint8_t want = tonemap_value(thr, b->x[i], ex, curve);
        if (b->got[i] != want)
            fail_msg("ex %g curve %d: %.9g (bits %08x) gives %u, not %u", ex, curve, (double)b->x[i],
                     (unsigned)bits_of_float(b->x[i]), b->got[i], want);
        b->lit += want > 0 && want < 255;
    }
    b->checked += b->n;
    b->n = 0;
}

static void add(batch *b, const tonemap_table *t, const double *thr, double ex, int curve, float x)
{
    b->x[b->n++] = x;
    if (b->n == BUF)
        flush(b, t, thr, ex, curve);
}

static void check_exposure(const double *thr, double ex, int curve, int usable)
{
    static tonemap_table t;
    static batch b;
    static const float special[] = { 0.0f, -0.0f, -1.0f, -FLT_MIN, FLT_MIN, 1e-45f, 1e-40f, FLT_MAX,
                                     1.0f, 0.5f, 1e-3f };
    uint64_t u;
    uint32_t k, d;
    size_t i;
    memset(&t, 0, sizeof t);
    b.n = b.checked = b.lit = b.far = 0;
    tonemap_table_set(&t, thr, ex, curve);
    assert_int_equal(t.usable, usable);
    for (u = 1; u < 0x7f800000u; u += SPREAD)
        add(&b, &t, thr, ex, curve, float_of_bits((uint32_t)u));
    if (usable)
        for (k = 0; k < TONEMAP_LEVELS; k++)
            for (d = 0; d < 2 * NEAR; d++) {
                int64_t v = (int64_t)t.f[k] - NEAR + d;
                if (v >= 1 && v < 0x7f800000)
                    add(&b, &t, thr, ex, curve, float_of_bits((uint32_t)v));
            }
    for (i = 0; i < sizeof special / sizeof special[0]; i++)
        add(&b, &t, thr, ex, curve, special[i]);
    add(&b, &t, thr, ex, curve, INFINITY);
    add(&b, &t, thr, ex, curve, -INFINITY);
    add(&b, &t, thr, ex, curve, NAN);
    flush(&b, &t, thr, ex, curve);
    /* the far limit's two sides (FLT_MAX / 4 and the float above it), each
     * inside a run of 32 ordinary values, alone in its batch */
    for (d = 0; d < 2; d++) {
        for (k = 0; k < 40; k++)
            add(&b, &t, thr, ex, curve, 1.0f);
        add(&b, &t, thr, ex, curve, float_of_bits(bits_of_float(FLT_MAX / 4.0f) + d));
        for (k = 0; k < 40; k++)
            add(&b, &t, thr, ex, curve, 0.5f);
        flush(&b, &t, thr, ex, curve);
    }
    assert_true(b.checked > 500000);
    /* far answered both ways: the batches past FLT_MAX / 4 and the last
     * (infinities, NaN), not the others */
    assert_true(b.far >= 2 && b.far * 4 < b.checked / BUF);
    /* the exposure's range of floats is crossed: bytes between 0 and 255
     * (1e120 takes every float but the smallest to 255) */
    if (usable)
        assert_true(b.lit > 1000);
}

static void test_same_bytes(void **state)
{
    /* the last two: tables with more than one threshold in a hint's range
     * (the loop that steps past several) */
    static const double ex[] = { 1.0, 0.15, 3.7e-3, 250.0, 1e-30, 7.3e20, 0.999999, 1e6, 1e-40, 1e38 };
    static tonemap_table t;
    double thr[TONEMAP_LEVELS];
    size_t i;
    int curve, several = 0;
    (void)state;
    tonemap_thresholds(thr);
    for (i = 0; i < sizeof ex / sizeof ex[0]; i++)
        for (curve = 0; curve < 2; curve++) {
            check_exposure(thr, ex[i], curve, 1);
            memset(&t, 0, sizeof t);
            tonemap_table_set(&t, thr, ex[i], curve);
            several += !t.single;
        }
    assert_true(several >= 2);
    check_exposure(thr, 1e120, 1, 0);
    check_exposure(thr, 1e120, 0, 0);
}

/* The thresholds themselves: between each float below f[k] and f[k] the
 * byte steps past k (so the table is the exact boundary, not near it). */
static void test_boundaries(void **state)
{
    static tonemap_table t;
    double thr[TONEMAP_LEVELS];
    int k;
    (void)state;
    tonemap_thresholds(thr);
    memset(&t, 0, sizeof t);
    tonemap_table_set(&t, thr, 0.37, 1);
    assert_true(t.usable);
    for (k = 0; k < TONEMAP_LEVELS; k++) {
        assert_true(tonemap_value(thr, float_of_bits(t.f[k]), 0.37, 1) > k);
        assert_true(tonemap_value(thr, float_of_bits(t.f[k] - 1), 0.37, 1) <= k);
        if (k > 0)
            assert_true(t.f[k] >= t.f[k - 1]);
    }
    /* the same exposure again keeps the table; another makes a new one */
    t.f[0] ^= 1;
    tonemap_table_set(&t, thr, 0.37, 1);
    assert_true(tonemap_value(thr, float_of_bits(t.f[0]), 0.37, 1) == 0 ||
                tonemap_value(thr, float_of_bits(t.f[0] - 1), 0.37, 1) > 0);
    tonemap_table_set(&t, thr, 0.38, 1);
    assert_true(tonemap_value(thr, float_of_bits(t.f[0]), 0.38, 1) > 0);
    assert_true(tonemap_value(thr, float_of_bits(t.f[0] - 1), 0.38, 1) == 0);
}

/* Runs of +0 among other values: 20,000 random buffers of ZN values,
 * each run of +0 1 to 48 long, tone mapped through a random window
 * (sentinels around it must stay); many windows hold 32 zeros in a row,
 * the all-dark runs the tone map writes at once. */
#define ZN 100 /* values a trial */
static void test_zero_runs(void **state)
{
    static const float other[] = { -0.0f, 1e-45f, 2e-45f, FLT_MIN, 0.02f, 1.0f, 400.0f, -3.0f };
    static tonemap_table t;
    double thr[TONEMAP_LEVELS];
    uint64_t seed = 12345;
    long trial, zeros = 0, dark = 0;
    (void)state;
    tonemap_thresholds(thr);
    memset(&t, 0, sizeof t);
    tonemap_table_set(&t, thr, 0.05, 1);
    assert_true(t.usable && t.single);
    for (trial = 0; trial < 20000; trial++) {
        float x[ZN];
        uint8_t got[ZN];
        size_t n = 0, p0, p1, i;
        while (n < ZN) {
            size_t run, k;
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            run = 1 + (size_t)(seed >> 58) % 48;
            if ((seed >> 40) & 1) {
                for (k = 0; k < run && n < ZN; k++)
                    x[n++] = 0.0f;
            } else {
                x[n++] = other[(seed >> 33) % (sizeof other / sizeof other[0])];
            }
        }
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        p0 = (size_t)(seed >> 58) % 40;
        p1 = p0 + (size_t)(seed >> 40) % (ZN + 1 - p0);
        memset(got, 0xAB, sizeof got);
        assert_int_equal(tonemap_apply(&t, thr, x, p0, p1, got), 0); /* none beyond FLT_MAX / 4 */
        for (i = p0, n = 0; i < p1 && n < 32; i++)
            n = bits_of_float(x[i]) == 0 ? n + 1 : 0;
        dark += n == 32;
        for (i = 0; i < ZN; i++) {
            if (i < p0 || i >= p1) {
                if (got[i] != 0xAB)
                    fail_msg("trial %ld: byte %zu outside %zu .. %zu written", trial, i, p0, p1);
            } else if (got[i] != tonemap_value(thr, x[i], 0.05, 1)) {
                fail_msg("trial %ld: value %zu (%g) gives %u, not %u", trial, i, (double)x[i], got[i],
                         tonemap_value(thr, x[i], 0.05, 1));
            } else {
                zeros += bits_of_float(x[i]) == 0;
            }
        }
    }
    assert_true(zeros > 100000 && dark > 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_bytes),
        cmocka_unit_test(test_boundaries),
        cmocka_unit_test(test_zero_runs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
