/* nightify: a day orthophoto turned into night colours by histogram
 * matching (munoz2013 §3.1; nightify.c). */
#ifndef PLX_NIGHTIFY_H
#define PLX_NIGHTIFY_H

#include <stddef.h>
#include <stdint.h>

/*
 * Histogram matching of an RGB8 image to a reference, channel by channel:
 * each value v of channel c of src becomes the smallest w whose cumulative
 * frequency in the reference channel reaches v's in src. Reference pixels
 * whose luminance (0.2126 R + 0.7152 G + 0.0722 B, 0..255) is below
 * dark_threshold are left out of the reference histograms (if that leaves
 * none, all are used). src and out hold npx packed RGB pixels and may be
 * the same buffer; ref holds nref pixels. Pure: no memory, no state.
 * Returns 0, or -1 when a pointer is NULL or npx or nref is 0 (out
 * untouched).
 */
int photon_hist_match(const uint8_t *src, size_t npx, const uint8_t *ref, size_t nref,
                      double dark_threshold, uint8_t *out /* OUT */);

#endif
