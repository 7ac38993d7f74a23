/* render_aa: adaptive anti-aliasing's sums and marks on the workers
 * (render_aa.c; plx_render's --aa frames, renderapi.c). */
#ifndef PLX_RENDER_AA_H
#define PLX_RENDER_AA_H

#include <stddef.h>
#include <stdint.h>
#include "render/render.h"

/* 2 x 2 adaptive anti-aliasing's sums at the marked pixels only, for a
 * frame whose every pixel sum already holds the first sample's value
 * (the first sample's own image, render_swap_linear) and whose later samples have been added this way:
 * after later sample s (1 .. 3; before = s - 1), each pixel marked 2
 * (newly, render_opts.mask_new) first adds its first value before times,
 * as the samples that left it did, and becomes 1; then every marked
 * pixel adds lin. The same float operations, in the same order, as the
 * dense sums give those pixels. sum and lin must not overlap (they are
 * restrict-qualified inside). */
void render_aa_add_marked(const render_opts *o, float *sum, const float *lin, uint8_t *mask, size_t px,
                          int before);

/* The end of a 2 x 2 adaptive frame summed by render_aa_add_marked, whose
 * first sample render_aa_mask tone mapped into rgb8 (the same ex and
 * curve): each marked pixel's sums scaled by 1/4 and tone mapped again;
 * an unmarked pixel holds its first value v, which is already the dense
 * sums' ((v + v) + v) + v times 1/4 (v + v is exact; the rounded 3v is
 * within half a unit in 4v's last place of 3v, and when exactly half, v
 * is an odd multiple of that half unit, so 4v's last digit is even and
 * the tie in 3v + v rounds to 4v; under round to nearest even without
 * flushing subnormals to zero, C's default; all 2^32 floats checked), so
 * its bytes stay, except where 4v would
 * overflow or v is not finite: those values are summed as the dense sums
 * do and mapped again (looked for only when far, the first sample's
 * tone map's answer, render_aa_mask: else only the marked pixels are read).
 * Afterwards sum holds the frame's linear values. */
void render_tonemap_kept(render *r, float *sum, const uint8_t *mask, size_t px, int far, double ex, int curve,
                         uint8_t *rgb8 /* IN/OUT */, const render_opts *o);

/* Anti-aliasing's sums on o's workers: sum[p] = lin[p] (copy), sum[p] +=
 * lin[p] (add) for p < n, and sum[p] = (float)(sum[p] * inv) (scale);
 * each value the same float operations as one at a time. */
void render_aa_copy(const render_opts *o, float *sum, const float *lin, size_t n);
void render_aa_add(const render_opts *o, float *sum, const float *lin, size_t n);
void render_aa_scale(const render_opts *o, float *sum, size_t n, double inv);

/* Adaptive anti-aliasing, after the frame of the first sample (its exposure
 * ex, curve as render_opts.auto_exposure): tone maps the linear image into
 * rgb (3 bytes a pixel; kept unless marks is rgb), uses marks (1 byte a
 * pixel, scratch; may be rgb) for the marks, copies the surface ids into id0 and
 * marks in mask (1 byte a pixel) every pixel that differs from one of its
 * 8 neighbours: another surface id, or a channel more than level steps
 * apart in the 8-bit image (level taken into 0 .. 255: below 0 as 0), and
 * (without render_opts.no_glow) the pixels of the glows it sees.
 * Returns the pixels marked, and in *far (when not NULL) whether a
 * value of the linear image is beyond +-FLT_MAX / 4 or NaN (for
 * render_tonemap_kept). */
size_t render_aa_mask(render *r, const render_opts *o, double ex, int curve, int level, uint8_t *rgb,
                      uint8_t *marks, uint32_t *id0, uint8_t *mask, int *far /* OUT */);

#endif
