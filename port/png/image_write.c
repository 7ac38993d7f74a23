/* image_write: PNG and PFM files through a temporary file and rename.
 * See image_write.h for the contracts. */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>
#include <png.h>

#include "image_write.h"
#include "port.h"
#include "posix/safe_out.h"

/* Largest width or height accepted (libpng's default user limit). */
#define IMAGE_MAX_DIM 1000000

static int check_size(const char *op, const char *path, int width, int height,
                      const void *pixels, char *err, size_t errlen)
{
    if (path == NULL || pixels == NULL) {
        port_set_err(err, errlen, "%s: %s is NULL", op, path == NULL ? "path" : "pixel buffer");
        return -1;
    }
    if (width < 1 || width > IMAGE_MAX_DIM || height < 1 || height > IMAGE_MAX_DIM) {
        port_set_err(err, errlen, "%s: '%s': size %dx%d outside 1..%d", op, path, width, height,
                IMAGE_MAX_DIM);
        return -1;
    }
    return 0;
}

/* ---- libpng glue ---------------------------------------------------------- */

/* What went wrong inside libpng: the system error of our own I/O callbacks
 * if there was one, else libpng's message. */
typedef struct png_io {
    FILE *f;            /* reading */
    safe_out *out;      /* writing */
    int sys_errno;
    char msg[160];
} png_io;

static void png_io_error(png_structp png, png_const_charp msg)
{
    png_io *io = png_get_error_ptr(png);
    snprintf(io->msg, sizeof io->msg, "%s", msg);
    png_longjmp(png, 1);
}

static void png_io_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;      /* warnings are not errors; the library stays silent */
}

static void png_io_write(png_structp png, png_bytep data, size_t len)
{
    png_io *io = png_get_io_ptr(png);
    if (safe_out_write(io->out, data, len) != 0) {
        io->sys_errno = safe_out_errno(io->out);
        png_error(png, "write failed");
    }
}

static void png_io_flush(png_structp png)
{
    (void)png;          /* safe_out_commit flushes and syncs */
}

static const char *png_io_reason(const png_io *io)
{
    return io->sys_errno != 0 ? strerror(io->sys_errno) : io->msg;
}

/* ---- PNG writer ----------------------------------------------------------- */

/* Encodes the image into io->f. Returns 0, or -1 with the reason in io. */
static int png_encode(png_io *io, int width, int height, const uint8_t *rgb, size_t step, int level)
{
    png_structp png;
    png_infop info;
    int y;

    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, io, png_io_error, png_io_warning);
    info = png != NULL ? png_create_info_struct(png) : NULL;
    if (info == NULL) {
        png_destroy_write_struct(&png, NULL);
        snprintf(io->msg, sizeof io->msg, "libpng could not set up (out of memory)");
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    png_set_write_fn(png, io, png_io_write, png_io_flush);
    if (level >= 0)
        png_set_compression_level(png, level);
    if (level == 1) /* fast: one row filter instead of trying all five per row (up: as small here) */
        png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    for (y = 0; y < height; y++)
        png_write_row(png, (png_const_bytep)(rgb + (size_t)y * step));
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 0;
}

int image_encode_png(safe_out *out, const char *path, int width, int height, const uint8_t *rgb,
                     int stride, char *err, size_t errlen)
{
    return image_encode_png_level(out, path, width, height, rgb, stride, -1, err, errlen);
}

int image_encode_png_level(safe_out *out, const char *path, int width, int height, const uint8_t *rgb,
                           int stride, int level, char *err, size_t errlen)
{
    const char *op = "PNG";
    png_io io;

    if (check_size(op, path, width, height, rgb, err, errlen) != 0)
        return -1;
    if (stride == 0)
        stride = width * 3;     /* width <= 1e6: no overflow */
    if (stride < width * 3) {
        port_set_err(err, errlen, "%s: '%s': stride %d is shorter than a row of %d bytes",
                op, path, stride, width * 3);
        return -1;
    }
    memset(&io, 0, sizeof io);
    io.out = out;
    if (png_encode(&io, width, height, rgb, (size_t)stride, level) != 0) {
        port_set_err(err, errlen, "%s: cannot write '%s': %s", op, path, png_io_reason(&io));
        return -1;
    }
    return 0;
}

/* Opens path, runs one encoder, commits; the message prefixed with op. */
static int write_one(const char *op, const char *path, int width, int height, const void *pixels,
                     int stride, int pfm, int level, int batch, char *err, size_t errlen)
{
    char why[600];
    safe_out *o;
    if (check_size(op, path, width, height, pixels, err, errlen) != 0)
        return -1;
    o = batch ? safe_out_open_batch(path, why, sizeof why) : safe_out_open(path, why, sizeof why);
    if (!o) {
        port_set_err(err, errlen, "%s: %s", op, why);
        return -1;
    }
    if ((pfm ? image_encode_pfm(o, path, width, height, pixels, err, errlen)
             : image_encode_png_level(o, path, width, height, pixels, stride, level, err, errlen)) != 0) {
        safe_out_abort(o);
        return -1;
    }
    if (safe_out_commit(&o, 1, why, sizeof why) != 0) {
        port_set_err(err, errlen, "%s: %s", op, why);
        return -1;
    }
    return 0;
}

int image_write_png_rgb8(const char *path, int width, int height, const uint8_t *rgb,
                         int stride, char *err, size_t errlen)
{
    return write_one("PNG", path, width, height, rgb, stride, 0, -1, 0, err, errlen);
}

int image_write_png_frame(const char *path, int width, int height, const uint8_t *rgb,
                              int stride, char *err, size_t errlen)
{
    return write_one("PNG", path, width, height, rgb, stride, 0, 1, 1, err, errlen);
}

/* ---- PFM writer ------------------------------------------------------------ */

int image_encode_pfm(safe_out *out, const char *path, int width, int height, const float *rgb,
                     char *err, size_t errlen)
{
    const char *op = "PFM";
    size_t row_floats, i;
    unsigned char *row;
    char head[64];
    int y, n;

    if (check_size(op, path, width, height, rgb, err, errlen) != 0)
        return -1;
    row_floats = (size_t)width * 3;
    row = malloc(row_floats * 4);
    if (row == NULL) {
        port_set_err(err, errlen, "%s: '%s': out of memory for a row of %zu bytes", op, path,
                row_floats * 4);
        return -1;
    }
    n = snprintf(head, sizeof head, "PF\n%d %d\n-1.0\n", width, height);
    safe_out_write(out, head, (size_t)n);
    /* PFM stores the bottom row first. */
    for (y = height - 1; y >= 0; y--) {
        const float *src = rgb + (size_t)y * row_floats;
        for (i = 0; i < row_floats; i++) {
            uint32_t u;
            memcpy(&u, &src[i], 4);
            row[4 * i + 0] = (unsigned char)(u & 0xFFu);
            row[4 * i + 1] = (unsigned char)((u >> 8) & 0xFFu);
            row[4 * i + 2] = (unsigned char)((u >> 16) & 0xFFu);
            row[4 * i + 3] = (unsigned char)((u >> 24) & 0xFFu);
        }
        if (safe_out_write(out, row, row_floats * 4) != 0)
            break;
    }
    free(row);
    if (safe_out_errno(out) != 0) {
        port_set_err(err, errlen, "%s: cannot write '%s': %s", op, path, strerror(safe_out_errno(out)));
        return -1;
    }
    return 0;
}

int image_write_pfm(const char *path, int width, int height, const float *rgb,
                    char *err, size_t errlen)
{
    return write_one("PFM", path, width, height, rgb, 0, 1, -1, 0, err, errlen);
}

/* ---- PNG reader ------------------------------------------------------------ */

/* Opens a file for reading without waiting on it: a FIFO, a device or a
 * directory is refused (open with O_NONBLOCK, then fstat). */
static FILE *open_input(const char *op, const char *path, char *err, size_t errlen)
{
    struct stat st;
    FILE *f;
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY);
    if (fd < 0) {
        port_set_err(err, errlen, "%s: cannot open '%s': %s", op, path, strerror(errno));
        return NULL;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        port_set_err(err, errlen, "%s: '%s' is not a regular file", op, path);
        close(fd);
        return NULL;
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    f = fdopen(fd, "rb");
    if (f == NULL) {
        port_set_err(err, errlen, "%s: cannot open '%s': %s", op, path, strerror(errno));
        close(fd);
    }
    return f;
}

static int read_png(const char *path, uint8_t *buf, size_t cap, uint8_t **out, int *width,
                    int *height, png_uint_32 max_dim, size_t max_bytes, char *err, size_t errlen)
{
    const char *op = "PNG";
    png_structp png;
    png_infop info;
    png_io io;
    unsigned char sig[8];
    uint8_t *volatile pixels = NULL;
    volatile int owned = 0;
    png_uint_32 w, h, y;
    int bit_depth, color_type, passes, pass;
    size_t row_bytes, need;
    FILE *f;

    if (out != NULL)
        *out = NULL;
    if (path == NULL || out == NULL) {
        port_set_err(err, errlen, "%s: %s is NULL", op, path == NULL ? "path" : "out");
        return -1;
    }
    f = open_input(op, path, err, errlen);
    if (f == NULL)
        return -1;
    if (fread(sig, 1, sizeof sig, f) != sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
        fclose(f);
        port_set_err(err, errlen, "%s: '%s' is not a PNG file (bad signature)", op, path);
        return -1;
    }

    memset(&io, 0, sizeof io);
    io.f = f;
    png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, png_io_error, png_io_warning);
    info = png != NULL ? png_create_info_struct(png) : NULL;
    if (info == NULL) {
        png_destroy_read_struct(&png, NULL, NULL);
        fclose(f);
        port_set_err(err, errlen, "%s: '%s': libpng could not set up (out of memory)", op, path);
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(f);
        if (owned)
            free(pixels);
        port_set_err(err, errlen, "%s: cannot decode '%s': %s", op, path, png_io_reason(&io));
        return -1;
    }
    png_init_io(png, f);
    png_set_sig_bytes(png, (int)sizeof sig);
    png_read_info(png, info);
    png_get_IHDR(png, info, &w, &h, &bit_depth, &color_type, NULL, NULL, NULL);
    if (width != NULL) *width = (int)w;
    if (height != NULL) *height = (int)h;

    /* Everything to 8-bit RGB. */
    if (color_type == PNG_COLOR_TYPE_PALETTE)
        png_set_palette_to_rgb(png);
    if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8)
        png_set_expand_gray_1_2_4_to_8(png);
    if (bit_depth == 16)
        png_set_scale_16(png);
    if (color_type == PNG_COLOR_TYPE_GRAY || color_type == PNG_COLOR_TYPE_GRAY_ALPHA)
        png_set_gray_to_rgb(png);
    png_set_strip_alpha(png);
    passes = png_set_interlace_handling(png);
    png_read_update_info(png, info);

    row_bytes = png_get_rowbytes(png, info);
    if (png_get_channels(png, info) != 3 || png_get_bit_depth(png, info) != 8 ||
        row_bytes != (size_t)w * 3) {
        png_error(png, "could not convert to 8-bit RGB");
    }
    if (w > max_dim || h > max_dim) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(f);
        port_set_err(err, errlen, "%s: '%s' is %lux%lu pixels, larger than the %lux%lu allowed", op, path,
                (unsigned long)w, (unsigned long)h, (unsigned long)max_dim, (unsigned long)max_dim);
        return -1;
    }
    need = row_bytes * (size_t)h;           /* <= 3e12: fits a 64-bit size_t */
    if (need / row_bytes != (size_t)h)
        png_error(png, "image too large for memory");
    if (need > max_bytes) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(f);
        port_set_err(err, errlen, "%s: '%s' is %lux%lu pixels: decoding needs %zu bytes, more than the %zu "
                "the memory budget allows", op, path, (unsigned long)w, (unsigned long)h, need, max_bytes);
        return -2;
    }
    if (buf != NULL) {
        if (cap < need) {
            png_destroy_read_struct(&png, &info, NULL);
            fclose(f);
            port_set_err(err, errlen, "%s: '%s': buffer of %zu bytes given, the %lux%lu image needs %zu",
                    op, path, cap, (unsigned long)w, (unsigned long)h, need);
            return -1;
        }
        pixels = buf;
    } else {
        pixels = malloc(need);
        if (pixels == NULL)
            png_error(png, "out of memory for the pixels");
        owned = 1;
    }
    for (pass = 0; pass < passes; pass++)
        for (y = 0; y < h; y++)
            png_read_row(png, (png_bytep)(pixels + (size_t)y * row_bytes), NULL);
    png_read_end(png, NULL);
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
    *out = pixels;
    return 0;
}

int image_read_png_rgb8(const char *path, uint8_t *buf, size_t cap, uint8_t **out,
                        int *width, int *height, char *err, size_t errlen)
{
    return read_png(path, buf, cap, out, width, height, IMAGE_MAX_DIM, (size_t)-1, err, errlen);
}

int image_read_png_max(const char *path, int max_dim, uint8_t **out, int *width, int *height,
                       char *err, size_t errlen)
{
    if (max_dim < 1 || max_dim > IMAGE_MAX_DIM) {
        if (out != NULL)
            *out = NULL;
        port_set_err(err, errlen, "PNG: max_dim %d is not 1..%d", max_dim, IMAGE_MAX_DIM);
        return -1;
    }
    return read_png(path, NULL, 0, out, width, height, (png_uint_32)max_dim, (size_t)-1, err, errlen);
}

int image_read_png_budget(const char *path, int max_dim, size_t max_bytes, uint8_t **out, int *width,
                          int *height, char *err, size_t errlen)
{
    if (max_dim < 1 || max_dim > IMAGE_MAX_DIM) {
        if (out != NULL)
            *out = NULL;
        port_set_err(err, errlen, "PNG: max_dim %d is not 1..%d", max_dim, IMAGE_MAX_DIM);
        return -1;
    }
    return read_png(path, NULL, 0, out, width, height, (png_uint_32)max_dim, max_bytes, err, errlen);
}
