/* exposure: automatic exposure and the tone curve (exposure.c). */
#ifndef PLX_EXPOSURE_H
#define PLX_EXPOSURE_H

#include <stddef.h>
#include <stdint.h>

#define EXPOSURE_PERCENTILE 0.995 /* of the lit surface pixels' luminance ... */
/* (the lit pixels: Y > 0 and Y's bin at most EXPOSURE_RANGE stops below
 * the bin of the EXPOSURE_ANCHOR percentile of all with Y > 0. Light far
 * below the view's brightest is near black at any exposure the rule picks, and
 * the number of such pixels depends on how the dark was computed: the
 * per-pixel gather gives 1e-4 cd/m^2 where the atlas's photon charts give
 * 0, and counting them moved the percentile a stop.) */
#define EXPOSURE_ANCHOR 0.999
#define EXPOSURE_RANGE 12
#define EXPOSURE_KEY 1.0         /* ... mapped to this value before the curve */
#define EXPOSURE_WHITE 4.0       /* the tone curve reaches 1 here */
#define EXPOSURE_SKY 0u          /* the id of sky pixels (MESH_SURF_NONE) */

#define EXPOSURE_BINS 512        /* log2 Y from -32 to +32 in eighth stops */
/* The largest automatic exposure, 1024: a frame whose lit surfaces are
 * all darker than about 0.001 cd/m^2 is shown dark, as it is (the
 * percentile of such a frame is photon noise: a courtyard's 1e-7 cd/m^2
 * was exposed 7e6 times to white). The bin whose upper edge is 2^-10. */
#define EXPOSURE_MAX 1024.0
#define EXPOSURE_MAX_BIN 175

/* The exposure for px pixels of linear RGB lin with surface ids id. */
double exposure_auto(const float *lin, const uint32_t *id, size_t px);
/* exposure_auto in parts: pixels p0 .. p1 - 1 counted into hist (added to
 * it), and the exposure from the sum of the parts' counts. */
void exposure_count(const float *lin, const uint32_t *id, size_t p0, size_t p1, uint32_t hist[EXPOSURE_BINS]);
double exposure_from(const uint32_t hist[EXPOSURE_BINS]);
/* Whether hist counted any pixel (exposure_from is 1 for none). */
int exposure_counted(const uint32_t hist[EXPOSURE_BINS]);
/* A walk's exposure without flicker: the exposure chosen from the image,
 * exposure_from's, held at the last frame's, held, while they are at
 * most EXPOSURE_HOLD eighths of a stop apart (in exposure_from's steps,
 * held read to the nearest step); else moved from held to the edge of
 * the band around chosen, or, when step > 0 and the edge is farther, by
 * step eighths of a stop as the exposure rises (a darker view) and
 * EXPOSURE_FALL times that as it falls (a brighter view, which would
 * otherwise stay blown out: ten stops took 3 s at 25 fps). A view where
 * a few dozen pixels set the percentile jumped 3.5 stops for one frame and
 * back. A frame that reached the band, drawn again with its own exposure
 * as held, keeps it. */
#define EXPOSURE_HOLD 4
#define EXPOSURE_FALL 4
double exposure_hold(double held, double chosen, int step);
/* The tone curve: v (1 + v / W^2) / (1 + v), 0 for v <= 0 or NaN. */
double exposure_curve(double v);

/* The bin of a luminance y > 0: floor of 8 (log2 y + 32), within
 * 0 .. EXPOSURE_BINS - 1 (what exposure_count counts). */
int exposure_bin(double y);

#define EXPOSURE_HINTS 16384     /* positive double bits >> 49 */
#define EXPOSURE_HINT_STEPS 1    /* thresholds at most in a hint's cell past its first double
                                    (exposure_table_bin takes one step) */

/* exposure_bin without the logarithm: t[k] (k >= 1) is the smallest
 * double whose bin is k or more, hint[h] the number of them at or below
 * the bits h << 49; a luminance's bin is the number of t[k] at or below
 * it (exposure_bin grows with y). Made once (exposure_table_init). */
typedef struct exposure_table {
    double t[EXPOSURE_BINS];     /* t[0] unused */
    uint16_t hint[EXPOSURE_HINTS];
} exposure_table;

void exposure_table_init(exposure_table *et);
/* exposure_bin(y) from the table, for a positive finite y. */
int exposure_table_bin(const exposure_table *et, double y);
/* exposure_count with the table: the same counts. */
void exposure_count_table(const exposure_table *et, const float *lin, const uint32_t *id, size_t p0, size_t p1,
                          uint32_t hist[EXPOSURE_BINS]);
/* The same counting only pixels p0, p0 + step, ... below p1. */
void exposure_count_every(const exposure_table *et, const float *lin, const uint32_t *id, size_t p0, size_t p1,
                          size_t step, uint32_t hist[EXPOSURE_BINS]);

#endif
