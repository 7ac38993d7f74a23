/* exposure: automatic exposure and the tone curve of night images
 * (README "Automatic exposure").
 *
 * A night street is mostly black with small, very bright patches under the
 * lamps, so the mean says little. The exposure maps a high percentile of
 * the luminance of the lit surface pixels (EXPOSURE_PERCENTILE of the
 * pixels with Y > 0 that show a surface, not the sky, and are at most
 * EXPOSURE_RANGE stops below the EXPOSURE_ANCHOR percentile) to EXPOSURE_KEY; the
 * tone curve (extended Reinhard, white point EXPOSURE_WHITE) then rolls
 * off the highlights near lamps instead of clipping them. The percentile
 * comes from a histogram of log2 Y in eighth stops: O(pixels), no sort,
 * the same for any pixel order.
 */
#include <math.h>
#include <string.h>

#include "base/bits.h"
#include "render/exposure.h"

#define BINS EXPOSURE_BINS
#define LOG_MIN (-32.0)
#define PER_STOP 8.0

static double luminance(const float *c)
{
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

int exposure_bin(double y)
{
    double l = (log2(y) - LOG_MIN) * PER_STOP;
    return l < 0 ? 0 : l >= BINS ? BINS - 1 : (int)l;
}

void exposure_count(const float *lin, const uint32_t *id, size_t p0, size_t p1, uint32_t hist[EXPOSURE_BINS])
{
    size_t p;
    for (p = p0; p < p1; p++) {
        double y = luminance(lin + 3 * p);
        if (id[p] == EXPOSURE_SKY || !(y > 0.0) || !isfinite(y))
            continue;
        hist[exposure_bin(y)]++;
    }
}

/* The smallest positive double whose bin is at least k (1 .. BINS - 1),
 * by bisection of the bits between 2^-40 (bin 0) and 2^40 (the last). */
static double first_of_bin(int k)
{
    uint64_t lo = bits_of_double(0x1p-40), hi = bits_of_double(0x1p40);
    while (hi - lo > 1) {
        uint64_t mid = lo + (hi - lo) / 2;
        if (exposure_bin(double_of_bits(mid)) >= k)
            hi = mid;
        else
            lo = mid;
    }
    return double_of_bits(hi);
}

void exposure_table_init(exposure_table *et)
{
    uint32_t h;
    int k;
    et->t[0] = 0.0;
    for (k = 1; k < BINS; k++)
        et->t[k] = first_of_bin(k);
    for (h = 0, k = 1; h < EXPOSURE_HINTS; h++) {
        while (k < BINS && bits_of_double(et->t[k]) <= (uint64_t)h << 49)
            k++;
        et->hint[h] = (uint16_t)(k - 1);
    }
}

void exposure_count_table(const exposure_table *et, const float *lin, const uint32_t *id, size_t p0, size_t p1,
                          uint32_t hist[EXPOSURE_BINS])
{
    exposure_count_every(et, lin, id, p0, p1, 1, hist);
}

/* The search from y's hint, without a branch: the hint's bin, or the bin
 * after it when y reaches that bin's threshold. One step is the whole
 * search: the hints split each octave [2^e, 2^(e+1)) into eight equal
 * cells, and its thresholds 2^(e + k/8) fall at most one past the first
 * double of each (at 1, 1.09 | 1.19 | 1.30 | 1.41 | 1.54 | 1.68 | 1.83 |
 * none, in cells 1/8 wide from 1); test_exposure_table checks the table
 * itself. */
static inline uint32_t table_bin(const exposure_table *et, double y)
{
    uint32_t b = et->hint[bits_of_double(y) >> 49], more = b + 1 < BINS, next = more ? b + 1 : b;
    return b + (more & (y >= et->t[next]));
}

int exposure_table_bin(const exposure_table *et, double y)
{
    return (int)table_bin(et, y);
}

/* Pixels p0, p0 + step, ... below p1, each bin from exposure_table_bin
 * (a loop of steps from the hint mispredicted). */
void exposure_count_every(const exposure_table *et, const float *lin, const uint32_t *id, size_t p0, size_t p1,
                          size_t step, uint32_t hist[EXPOSURE_BINS])
{
    size_t p;
    for (p = p0; p < p1; p += step) {
        double y = luminance(lin + 3 * p);
        if (id[p] == EXPOSURE_SKY || !(y > 0.0) || !isfinite(y))
            continue;
        hist[table_bin(et, y)]++;
    }
}

/* exposure_from's exposure of bin b, and the bin of an exposure e > 0
 * (the nearest: e need not be one of them). */
static double exposure_of_bin(int b)
{
    return EXPOSURE_KEY / exp2(LOG_MIN + (b + 1) / PER_STOP);
}

static double bin_of_exposure(double e)
{
    return floor((log2(EXPOSURE_KEY / e) - LOG_MIN) * PER_STOP - 1.0 + 0.5);
}

int exposure_counted(const uint32_t hist[EXPOSURE_BINS])
{
    int b;
    for (b = 0; b < BINS; b++)
        if (hist[b])
            return 1;
    return 0;
}

/* The bin of the want-th pixel (1 ..) counted in bins lo .. in ascending
 * order; the last bin when fewer. */
static int bin_at(const uint32_t hist[EXPOSURE_BINS], int lo, size_t want)
{
    size_t acc = 0;
    int b;
    for (b = lo; b < BINS; b++) {
        acc += hist[b];
        if (acc >= want)
            return b;
    }
    return BINS - 1;
}

double exposure_from(const uint32_t hist[EXPOSURE_BINS])
{
    size_t n = 0, m = 0;
    int b, lo;
    for (b = 0; b < BINS; b++)
        n += hist[b];
    if (n == 0)
        return 1.0;
    /* the pixels more than EXPOSURE_RANGE stops below the anchor are left
     * out: near black at any exposure the rule picks, and how many there are
     * says how the dark was computed, not what the view shows */
    lo = bin_at(hist, 0, (size_t)ceil(EXPOSURE_ANCHOR * (double)n)) - EXPOSURE_RANGE * (int)PER_STOP;
    lo = lo > 0 ? lo : 0;
    for (b = lo; b < BINS; b++)
        m += hist[b];
    b = bin_at(hist, lo, (size_t)ceil(EXPOSURE_PERCENTILE * (double)m));
    if (b < EXPOSURE_MAX_BIN) /* at most EXPOSURE_MAX */
        b = EXPOSURE_MAX_BIN;
    /* the bin's upper edge, so the chosen pixel is at most the key */
    return exposure_of_bin(b);
}

double exposure_hold(double held, double chosen, int step)
{
    double bh, bc, d;
    if (!(held > 0.0) || !isfinite(held))
        return chosen;
    bh = bin_of_exposure(held);
    bc = bin_of_exposure(chosen);
    d = fabs(bc - bh) - EXPOSURE_HOLD; /* how far outside the band */
    if (d <= 0.0)
        return held;
    if (step > 0 && bc > bh) /* a brighter view: the exposure falls EXPOSURE_FALL times as fast */
        step *= EXPOSURE_FALL;
    if (step > 0 && d > step)
        d = step;
    return exposure_of_bin((int)(bc > bh ? bh + d : bh - d));
}

double exposure_auto(const float *lin, const uint32_t *id, size_t px)
{
    uint32_t hist[BINS];
    memset(hist, 0, sizeof hist);
    exposure_count(lin, id, 0, px, hist);
    return exposure_from(hist);
}

double exposure_curve(double v)
{
    const double w2 = EXPOSURE_WHITE * EXPOSURE_WHITE;
    if (!(v > 0.0))
        return 0.0;
    return v * (1.0 + v / w2) / (1.0 + v);
}
