/* tonemap: linear RGB to sRGB bytes, times an exposure and through the
 * tone curve when asked (exposure.h), against SPEC §5's exact thresholds
 * (tonemap.c). */
#ifndef PLX_TONEMAP_H
#define PLX_TONEMAP_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#define TONEMAP_LEVELS 255          /* thresholds between the 256 bytes */
#define TONEMAP_HINT_SHIFT 15       /* a hint for every 2^15 positive float bit patterns */
#define TONEMAP_HINTS (1u << (31 - TONEMAP_HINT_SHIFT))

/* The thresholds: thr[k] is the linear value from which a pixel's byte
 * is above k (the middle between the sRGB codes k and k + 1). */
void tonemap_thresholds(double thr[TONEMAP_LEVELS]);
/* The byte of v: the number of thresholds <= v (0 for NaN). */
uint8_t tonemap_srgb8(const double thr[TONEMAP_LEVELS], double v);
/* The byte of one linear value x: v = x * ex, through the tone curve when
 * curve, then tonemap_srgb8 (0 for v <= 0 or NaN). */
uint8_t tonemap_value(const double thr[TONEMAP_LEVELS], float x, double ex, int curve);

/* For one exposure and curve, the same bytes as tonemap_value from the
 * float's bits alone: f[k] is the smallest float (its bits) whose byte is
 * above k (f[255]: beyond every float), hint[h] the number of them at or
 * below the bits h << TONEMAP_HINT_SHIFT. single: no two thresholds fall
 * in one hint's range (a relative width of at most 2^-8, where SPEC §5's
 * thresholds are at least 0.9% apart, and the tone curve only widens the
 * gaps: checked when the table is made), so a value's byte is its hint
 * plus one compare.
 * tonemap_value is monotone in a positive float (the curve's slope keeps
 * one float step above its rounding), so the byte of a float is the
 * number of f[k] at or below it. */
typedef struct tonemap_table {
    double ex;
    int curve;
    int usable;                     /* 0: tonemap_apply takes tonemap_value */
    int single;                     /* at most one threshold in a hint's range */
    uint32_t f[TONEMAP_LEVELS + 1];
    uint8_t hint[TONEMAP_HINTS];
} tonemap_table;

/* The table of ex and curve (kept when t already has them). */
void tonemap_table_set(tonemap_table *t, const double thr[TONEMAP_LEVELS], double ex, int curve);
/* Values p0 .. p1 - 1 of lin into bytes: the same as tonemap_value.
 * Returns whether one of them is beyond +-TONEMAP_FAR or NaN (where four
 * equal values no longer sum to four times one: render_tonemap_kept). */
#define TONEMAP_FAR (FLT_MAX / 4.0f)
/* Whether x is beyond +-TONEMAP_FAR or NaN. */
static inline int tonemap_far(float x)
{
    return !(fabsf(x) <= TONEMAP_FAR);
}
int tonemap_apply(const tonemap_table *t, const double thr[TONEMAP_LEVELS], const float *lin, size_t p0,
                  size_t p1, uint8_t *rgb8);

#endif
