/* tonemap: linear RGB to sRGB bytes (tonemap.h, README "How SPEC §5
 * (images) is read").
 *
 * A frame's 921,600 values (640x480) each go through the exposure, the
 * tone curve's division and a search of the 255 thresholds. For one
 * exposure and curve the byte depends on the float alone and grows with
 * it, so the table holds, for each byte, the smallest float that reaches
 * it: found from the curve's inverse and checked float by float against
 * tonemap_value, so the bytes are the same by construction. A value then
 * costs a table read and a compare or two of its bits (with one threshold
 * at most per hint, runs of 32 values with no branch), and 32 values of
 * +0 (the dark half of an aerial frame) one test.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/bits.h"
#include "render/exposure.h"
#include "render/tonemap.h"

#define FLOAT_INF_BITS 0x7f800000u

static double srgb_decode(double e)
{
    return e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4);
}

void tonemap_thresholds(double thr[TONEMAP_LEVELS])
{
    int k;
    for (k = 0; k < TONEMAP_LEVELS; k++)
        thr[k] = srgb_decode((k + 0.5) / 255.0);
}

uint8_t tonemap_srgb8(const double thr[TONEMAP_LEVELS], double v)
{
    int lo = 0, hi = TONEMAP_LEVELS;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (v >= thr[mid])
            lo = mid + 1;
        else
            hi = mid;
    }
    return (uint8_t)lo;
}

uint8_t tonemap_value(const double thr[TONEMAP_LEVELS], float x, double ex, int curve)
{
    double v = (double)x * ex;
    if (curve)
        v = exposure_curve(v);
    if (!(v > 0.0))
        return 0;
    return tonemap_srgb8(thr, v);
}

/* Whether the positive float of bits u has a byte above k. */
static int above(const double thr[TONEMAP_LEVELS], double ex, int curve, uint32_t u, int k)
{
    return tonemap_value(thr, float_of_bits(u), ex, curve) > k;
}

/* The linear value whose curve is y (y < 1: the stable root of
 * v^2 / W^2 + (1 - y) v - y = 0). */
static double curve_inverse(double y)
{
    const double w2 = EXPOSURE_WHITE * EXPOSURE_WHITE;
    return 2.0 * y / ((1.0 - y) + sqrt((1.0 - y) * (1.0 - y) + 4.0 * y / w2));
}

/* The smallest bits in 1 .. FLOAT_INF_BITS (that: no finite float) whose
 * byte is above k, from a guess: steps doubling from it until they
 * bracket the change, then bisection. */
static uint32_t first_above(const double thr[TONEMAP_LEVELS], double ex, int curve, int k, uint32_t guess)
{
    uint32_t lo, hi, step = 1; /* lo: not above (or 0), hi: above (or FLOAT_INF_BITS) */
    guess = guess < 1 ? 1 : guess >= FLOAT_INF_BITS ? FLOAT_INF_BITS - 1 : guess;
    if (above(thr, ex, curve, guess, k)) {
        hi = guess;
        for (;;) {
            lo = hi > step ? hi - step : 0;
            if (lo == 0 || !above(thr, ex, curve, lo, k))
                break;
            hi = lo;
            step *= 2;
        }
    } else {
        lo = guess;
        for (;;) {
            hi = FLOAT_INF_BITS - lo > step ? lo + step : FLOAT_INF_BITS;
            if (hi == FLOAT_INF_BITS || above(thr, ex, curve, hi, k))
                break;
            lo = hi;
            step *= 2;
        }
    }
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (above(thr, ex, curve, mid, k))
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

/* The float whose value times ex reaches threshold y after the curve. */
static uint32_t guess_bits(double y, double ex, int curve)
{
    double x = (curve ? curve_inverse(y) : y) / ex;
    if (!(x > 0.0))
        return 1;
    if (!(x < (double)FLT_MAX))
        return FLOAT_INF_BITS - 1;
    return bits_of_float((float)x);
}

/* Each hint h the first level k whose bits pass h << TONEMAP_HINT_SHIFT
 * (the levels from the last hint's on; TONEMAP_LEVELS past them all):
 * level k's run of hints, those below it, ends at the first h with h <<
 * TONEMAP_HINT_SHIFT at or above f[k], ceil(f[k] / 2^TONEMAP_HINT_SHIFT),
 * and is set at once. */
static void hints_fill(tonemap_table *t)
{
    uint32_t h = 0;
    int k;
    for (k = 0; k < TONEMAP_LEVELS && h < TONEMAP_HINTS; k++) {
        uint64_t end = ((uint64_t)t->f[k] + ((uint64_t)1 << TONEMAP_HINT_SHIFT) - 1) >> TONEMAP_HINT_SHIFT;
        end = end < TONEMAP_HINTS ? end : TONEMAP_HINTS;
        if (end > h) {
            memset(&t->hint[h], k, (size_t)(end - h));
            h = (uint32_t)end;
        }
    }
    if (h < TONEMAP_HINTS)
        memset(&t->hint[h], TONEMAP_LEVELS, TONEMAP_HINTS - h);
}

void tonemap_table_set(tonemap_table *t, const double thr[TONEMAP_LEVELS], double ex, int curve)
{
    int k;
    curve = curve != 0;
    if (t->usable && t->ex == ex && t->curve == curve)
        return;
    t->ex = ex;
    t->curve = curve;
    /* an exposure so large that the curve's square overflows for some
     * float (or none at all) is left to tonemap_value */
    t->usable = ex > 0.0 && ex * (double)FLT_MAX < 1e150;
    if (!t->usable)
        return;
    for (k = 0; k < TONEMAP_LEVELS; k++)
        t->f[k] = first_above(thr, ex, curve, k, guess_bits(thr[k], ex, curve));
    t->f[TONEMAP_LEVELS] = UINT32_MAX; /* no float reaches it */
    hints_fill(t);
    t->single = 1;
    for (k = 0; k + 1 < TONEMAP_LEVELS; k++)
        if ((t->f[k] >> TONEMAP_HINT_SHIFT) == (t->f[k + 1] >> TONEMAP_HINT_SHIFT))
            t->single = 0;
}

/* The bytes of values whose bits u are above FAR_BITS (beyond
 * TONEMAP_FAR, negative, infinite, NaN) come from tonemap_value, and
 * there the far values are noticed at no cost to the others. +0 needs no
 * case of its own (its hint is byte 0 and f[0] >= 1). */
#define FAR_BITS 0x7e7fffffu /* TONEMAP_FAR */
/* Bits u are above FAR_BITS when negative (bit 31) or when u's other 31
 * bits plus FAR_GAP reach bit 31 (no carry out: at most 2^31 - 1 + FAR_GAP). */
#define FAR_GAP (0x7fffffffu - FAR_BITS)

/* The byte of the bits u (at most FAR_BITS) in the single-threshold
 * case: the hint, plus one when u reaches the threshold above it. */
static inline uint8_t single_byte(const tonemap_table *t, uint32_t u)
{
    uint32_t b = t->hint[u >> TONEMAP_HINT_SHIFT];
    return (uint8_t)(b + (u >= t->f[b]));
}

/* Values p .. p + TONEMAP_RUN - 1 in the single-threshold case, when
 * none is above FAR_BITS (else 0, nothing written): all +0 (the dark
 * half of an aerial frame) at once, else a hint and a compare each, four
 * to a step, with no branch. */
#define TONEMAP_RUN 32
static int single_run(const tonemap_table *t, const float *lin, size_t p, uint8_t *rgb8)
{
    uint32_t any = 0, far = 0;
    int k;
    for (k = 0; k < TONEMAP_RUN; k++) { /* adds, ors and shifts only: vectorised */
        uint32_t u = bits_of_float(lin[p + k]);
        any |= u;
        far |= ((u & 0x7fffffffu) + FAR_GAP) | u; /* bit 31: above FAR_BITS */
    }
    if (far >> 31)
        return 0;
    if (!any) {
        memset(rgb8 + p, 0, TONEMAP_RUN);
        return 1;
    }
    for (k = 0; k < TONEMAP_RUN; k += 4) {
        rgb8[p + k] = single_byte(t, bits_of_float(lin[p + k]));
        rgb8[p + k + 1] = single_byte(t, bits_of_float(lin[p + k + 1]));
        rgb8[p + k + 2] = single_byte(t, bits_of_float(lin[p + k + 2]));
        rgb8[p + k + 3] = single_byte(t, bits_of_float(lin[p + k + 3]));
    }
    return 1;
}

int tonemap_apply(const tonemap_table *t, const double thr[TONEMAP_LEVELS], const float *lin, size_t p0,
                  size_t p1, uint8_t *rgb8)
{
    const uint32_t *f = t->f;
    const uint8_t *hint = t->hint;
    size_t p;
    int far = 0;
    if (!t->usable) {
        for (p = p0; p < p1; p++) {
            rgb8[p] = tonemap_value(thr, lin[p], t->ex, t->curve);
            far |= tonemap_far(lin[p]);
        }
        return far;
    }
    if (t->single) { /* one threshold at most above the hint: runs of TONEMAP_RUN, else one by one */
        for (p = p0; p < p1;) {
            size_t e;
            if (p + TONEMAP_RUN <= p1 && single_run(t, lin, p, rgb8)) {
                p += TONEMAP_RUN;
                continue;
            }
            for (e = p + TONEMAP_RUN < p1 ? p + TONEMAP_RUN : p1; p < e; p++) {
                uint32_t u = bits_of_float(lin[p]);
                if (u > FAR_BITS) {
                    rgb8[p] = tonemap_value(thr, lin[p], t->ex, t->curve);
                    far |= tonemap_far(lin[p]);
                    continue;
                }
                rgb8[p] = single_byte(t, u);
            }
        }
        return far;
    }
    for (p = p0; p < p1; p++) {
        uint32_t u = bits_of_float(lin[p]), b;
        if (u > FAR_BITS) {
            rgb8[p] = tonemap_value(thr, lin[p], t->ex, t->curve);
            far |= tonemap_far(lin[p]);
            continue;
        }
        b = hint[u >> TONEMAP_HINT_SHIFT];
        while (b < TONEMAP_LEVELS && u >= f[b])
            b++;
        rgb8[p] = (uint8_t)b;
    }
    return far;
}
