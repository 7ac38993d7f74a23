/* texel: one packed RGB radiance in 32 bits (the radiance atlas, atlas.h).
 *
 * Shared exponent: three 9-bit mantissas and one 5-bit exponent e,
 *     channel = m / 512 * 2^(e - TEXEL_BIAS),   m in 0 .. 511, e in 0 .. 31,
 * bits 0-8 red, 9-17 green, 18-26 blue, 27-31 e. The exponent is the
 * largest channel's, so that channel keeps 9 significant bits (a relative
 * step of at most 1/256 after rounding) and the others the same absolute
 * step. Range: 2^-27 (7.5e-9) up to 511/512 * 2^13 (8176) W/(sr m^2):
 * radiance albedo / pi * E of 2.3e5 lx at albedo 0.35, within centimetres
 * of a lamp; larger values are clamped, smaller ones are 0.
 *
 * Decoding needs no table and no pow: the scale 2^(e - TEXEL_BIAS - 9) is
 * the float whose exponent field is e + 100.
 */
#ifndef PLX_TEXEL_H
#define PLX_TEXEL_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#define TEXEL_BIAS 18
#define TEXEL_MAX 8176.0f   /* 511/512 * 2^13: the largest channel value */

static inline float texel_scale(uint32_t t)
{
    uint32_t bits = ((t >> 27) + 100u) << 23;
    float s;
    memcpy(&s, &bits, sizeof s);
    return s;
}

/* The three channels of t. */
static inline void texel_unpack(uint32_t t, float out[3])
{
    float s = texel_scale(t);
    out[0] = (float)(t & 511u) * s;
    out[1] = (float)((t >> 9) & 511u) * s;
    out[2] = (float)((t >> 18) & 511u) * s;
}

/* x >= 0 rounded to the nearest whole number, ties up: the fraction is
 * compared with one half exactly (floor(x + 0.5) would round the double
 * just below 0.5 up, the sum rounding to 1). */
static inline double texel_round(double x)
{
    double f = floor(x);
    return x - f >= 0.5 ? f + 1.0 : f;
}

/* The nearest packed value to (r, g, b) (negative and NaN channels as 0,
 * the largest clamped to TEXEL_MAX). */
static inline uint32_t texel_pack(double r, double g, double b)
{
    double c[3], mx, step;
    uint32_t m[3];
    int e, k;
    c[0] = r > 0.0 ? r : 0.0; /* NaN compares false: 0 */
    c[1] = g > 0.0 ? g : 0.0;
    c[2] = b > 0.0 ? b : 0.0;
    mx = c[0] > c[1] ? c[0] : c[1];
    mx = mx > c[2] ? mx : c[2];
    if (mx > TEXEL_MAX)
        for (k = 0; k < 3; k++)
            c[k] = c[k] > TEXEL_MAX ? TEXEL_MAX : c[k];
    mx = mx > TEXEL_MAX ? TEXEL_MAX : mx;
    if (!(mx >= ldexp(0.5, -TEXEL_BIAS - 9)))
        return 0u;
    (void)frexp(mx, &e); /* mx = f 2^e, f in [0.5, 1) */
    e += TEXEL_BIAS;
    if (e < 0)
        e = 0;
    step = ldexp(1.0, e - TEXEL_BIAS - 9);
    if (texel_round(mx / step) > 511.0 && e < 31) { /* rounding carried into a new bit */
        e++;
        step *= 2.0;
    }
    for (k = 0; k < 3; k++) {
        double q = texel_round(c[k] / step);
        m[k] = q > 511.0 ? 511u : (uint32_t)q;
    }
    return m[0] | (m[1] << 9) | (m[2] << 18) | ((uint32_t)e << 27);
}

#endif
