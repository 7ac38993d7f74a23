/* image_write: PNG (libpng) and PFM files, written safely.
 *
 * Port code: uses stdio, POSIX and libpng. Images are rows of pixels, row 0
 * at the top (SPEC.md §5), 3 channels R G B.
 *
 * Every writer goes through safe_out (port/posix/safe_out.h): a regular
 * file is written to a temporary file beside the output
 * ("<path>.tmp.<pid>.<n>", created exclusively with mode 0666 & ~umask),
 * flushed to disk (fsync), closed, and only then renamed over <path>; a
 * device, FIFO or "-" is written directly. A crash, a full disk or any
 * error therefore never leaves a partial output: <path> is either the
 * complete new image or whatever was there before. On failure the
 * temporary file is removed. The frame writers (image_write_png_frame,
 * image_write_apng) are the exception to the crash rule: outputs of a
 * batch, renamed unsynced and synced together by the caller at its end
 * (safe_out_batch_begin, _end), so a crash before then may leave a frame
 * empty or cut short.
 *
 * All functions return 0 on success, -1 on failure. On failure, when err is
 * not NULL and errlen > 0, err receives one line (NUL-terminated, truncated
 * to errlen) naming the operation, the file and the reason, e.g.
 *   "PNG: cannot create a temporary file for '/no/dir/a.png'
 *    ('/no/dir/a.png.tmp.42.0'): No such file or directory"
 * They never print and keep no state between calls.
 */
#ifndef PLX_IMAGE_WRITE_H
#define PLX_IMAGE_WRITE_H

#include <stddef.h>
#include <stdint.h>
#include "posix/safe_out.h"

/*
 * Writes an 8-bit RGB PNG (no interlace, tagged sRGB: the bytes are taken
 * to be sRGB-encoded). rgb holds height rows of width*3 bytes, each row
 * starting stride bytes after the previous one (stride 0 means width*3;
 * otherwise it must be >= width*3). width and height must be 1..1000000.
 */
int image_write_png_rgb8(const char *path, int width, int height, const uint8_t *rgb,
                         int stride, char *err, size_t errlen);

/* A frame of a batch (safe_out.h): the same at zlib's fastest level (1)
 * and with the "up" row filter only (libpng tries all five filters on
 * every row by default), for frames written one after another (walk),
 * where the default costs as much as the frame; renamed into place
 * unsynced, the caller syncs the batch at its end (safe_out_batch_begin,
 * _end). */
int image_write_png_frame(const char *path, int width, int height, const uint8_t *rgb,
                              int stride, char *err, size_t errlen);

/*
 * Writes an animated PNG (APNG, looping forever) at path from the n PNG
 * files frames[0..n-1], all of one size and format (as image_write_png_rgb8
 * writes them), each shown delay_num / delay_den seconds (each below
 * 65536). The frames' compressed data is copied, not encoded again; a
 * viewer without APNG shows the first frame (port/png/apng.c). Written as
 * one of the frames' batch, unsynced, as image_write_png_frame.
 */
int image_write_apng(const char *path, const char *const *frames, int n, unsigned delay_num, unsigned delay_den,
                     char *err, size_t errlen);

/*
 * Writes a colour PFM: header "PF\n<width> <height>\n-1.0\n" (negative
 * scale = little-endian), then width*height*3 IEEE floats in little-endian
 * byte order on every host, rows from the bottom of the image to the top as
 * PFM requires. rgb holds height packed rows of width*3 floats, top row
 * first; values are written unchanged (linear radiance). width and height
 * must be 1..1000000.
 */
int image_write_pfm(const char *path, int width, int height, const float *rgb,
                    char *err, size_t errlen);

/*
 * Reads any PNG libpng can decode (grey, grey+alpha, palette, RGB, RGBA;
 * 1 to 16 bits; interlaced or not) as packed 8-bit RGB, top row first:
 * palettes are expanded, grey is replicated to R G B, 16-bit samples are
 * scaled to 8 bits, alpha is dropped (not composited), no gamma correction
 * is applied.
 *
 * Buffer ownership:
 *  - buf != NULL: the caller's buffer of cap bytes receives the pixels if
 *    cap >= width*height*3; then *out = buf. If it is too small the call
 *    fails, but *width and *height are still set, so the caller can size a
 *    buffer and call again.
 *  - buf == NULL: the pixels go to a new buffer from malloc(), returned in
 *    *out; the caller releases it with free().
 * On failure *out is NULL, nothing stays allocated, and the contents of a
 * caller's buf are unspecified. width and height (OUT, may be NULL) are set
 * as soon as the header has been read.
 */
int image_read_png_rgb8(const char *path, uint8_t *buf, size_t cap, uint8_t **out,
                        int *width, int *height, char *err, size_t errlen);

/*
 * The same into a new malloc() buffer (*out, freed by the caller), refusing
 * an image wider or taller than max_dim (1..1000000) before any pixel
 * memory is taken: "PNG: 'big.png' is 20000x300 pixels, larger than
 * the 16384x16384 allowed". Other messages as above: "PNG: cannot
 * open 'x.png': No such file or directory", "PNG: 'x.png' is not a
 * PNG file (bad signature)", "PNG: cannot decode 'x.png': ...".
 */
int image_read_png_max(const char *path, int max_dim, uint8_t **out, int *width, int *height,
                       char *err, size_t errlen);

/*
 * The same limited also by bytes: an image whose decoded pixels
 * (width*height*3) exceed max_bytes is refused after reading the header,
 * before any pixel memory is taken: "PNG: 'big.png' is 1000000x1000000
 * pixels: decoding needs 3000000000000 bytes, more than the 1073741824 the
 * memory budget allows"; that refusal returns -2 (other failures -1). Every reader refuses a file that is not a regular
 * file (a FIFO, a device, a directory) without waiting on it.
 */
int image_read_png_budget(const char *path, int max_dim, size_t max_bytes, uint8_t **out, int *width,
                          int *height, char *err, size_t errlen);

/*
 * Encoders into an output opened with safe_out_open (path only names it in
 * messages): the caller commits (safe_out_commit) or aborts. Used to write
 * outputs that belong together (an image and its PFM) in one commit.
 */
int image_encode_png(safe_out *out, const char *path, int width, int height, const uint8_t *rgb,
                     int stride, char *err, size_t errlen);
/* image_encode_png at zlib level 0..9 (-1: the library's default, 6). */
int image_encode_png_level(safe_out *out, const char *path, int width, int height, const uint8_t *rgb,
                           int stride, int level, char *err, size_t errlen);
int image_encode_pfm(safe_out *out, const char *path, int width, int height, const float *rgb,
                     char *err, size_t errlen);

#endif
