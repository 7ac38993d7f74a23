/* ref_exposure: brute-force reference for the automatic exposure's
 * percentile (README "Automatic exposure"), by sorting, without the
 * engine's histogram.
 *
 * Of the n luminances y (each > 0 and finite: the lit surface pixels),
 * the anchor is the one at rank ceil(0.999 n) in ascending order; the
 * pixels counted are those within 12 stops of it, measured in the
 * histogram's eighths of a stop (floor(8 (log2 y + 32)) at least 96 less
 * than the anchor's); the answer is the counted luminance at rank
 * ceil(0.995 m) of the m counted. The exposure maps it to within an
 * eighth of a stop below the key (1), unless capped. y is sorted in
 * place.
 */
#ifndef REF_EXPOSURE_H
#define REF_EXPOSURE_H

#include <stddef.h>

double ref_exposure_luminance(double *y, size_t n);

#endif
