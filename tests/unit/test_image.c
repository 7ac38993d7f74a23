/* Tests of the PNG / PFM writers and the PNG reader: round trips, byte
 * layout, clean failures (no directory, full disk), no leftover files. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <signal.h>
#include <dirent.h>
#include <unistd.h>
#include <sys/stat.h>
#include <sys/resource.h>
#include <png.h>
#include <cmocka.h>

#include "png/image_write.h"

/* ---- fixtures ------------------------------------------------------------ */

typedef struct tdir {
    char dir[256];
    char path[512];
} tdir;

static int setup_dir(void **state)
{
    tdir *t = calloc(1, sizeof *t);
    const char *base = getenv("TMPDIR");
    if (t == NULL)
        return -1;
    snprintf(t->dir, sizeof t->dir, "%s/plx_test_image.XXXXXX",
             base != NULL && base[0] != '\0' ? base : "/tmp");
    if (mkdtemp(t->dir) == NULL) {
        free(t);
        return -1;
    }
    *state = t;
    return 0;
}

/* Removes the directory and everything in it (files and empty
 * directories, as a failed test may leave either). */
static int teardown_dir(void **state)
{
    tdir *t = *state;
    DIR *d = opendir(t->dir);
    struct dirent *e;
    char p[600];
    if (d != NULL) {
        while ((e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            snprintf(p, sizeof p, "%s/%s", t->dir, e->d_name);
            if (unlink(p) != 0)
                rmdir(p);
        }
        closedir(d);
    }
    rmdir(t->dir);
    free(t);
    return 0;
}

static const char *in_dir(tdir *t, const char *name)
{
    snprintf(t->path, sizeof t->path, "%s/%s", t->dir, name);
    return t->path;
}

/* Number of directory entries whose name contains s. */
static int count_names(const char *dir, const char *s)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, s) != NULL)
            n++;
    closedir(d);
    return n;
}

static void assert_no_tmp(const tdir *t)
{
    assert_int_equal(count_names(t->dir, ".tmp"), 0);
}

static int file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

/* stb's 6x5 "F", red on blue: asymmetric in both directions. */
static void make_f(uint8_t *rgb, size_t stride)
{
    static const char *rows[5] = { ".FFFF.", ".F....", ".FFF..", ".F....", ".F...." };
    int x, y;
    for (y = 0; y < 5; y++)
        for (x = 0; x < 6; x++) {
            uint8_t *p = rgb + (size_t)y * stride + (size_t)x * 3;
            int on = rows[y][x] == 'F';
            p[0] = on ? 255 : 0;
            p[1] = 0;
            p[2] = on ? 0 : 255;
        }
}

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    unsigned char *b;
    long n;
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    n = ftell(f);
    assert_true(n >= 0);
    rewind(f);
    b = malloc((size_t)n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return b;
}

/* ---- PNG round trips ------------------------------------------------------ */

static void test_png_roundtrip_f(void **state)
{
    tdir *t = *state;
    uint8_t img[5 * 6 * 3], small[10], exact[5 * 6 * 3];
    uint8_t *back = NULL;
    char err[256] = "";
    int w = 0, h = 0;
    const char *p = in_dir(t, "f.png");

    make_f(img, 18);
    assert_int_equal(image_write_png_rgb8(p, 6, 5, img, 0, err, sizeof err), 0);
    assert_true(file_exists(p));

    /* into a malloc'd buffer */
    assert_int_equal(image_read_png_rgb8(p, NULL, 0, &back, &w, &h, err, sizeof err), 0);
    assert_int_equal(w, 6);
    assert_int_equal(h, 5);
    assert_non_null(back);
    assert_memory_equal(back, img, sizeof img);
    /* the corner pixels are what the "F" says */
    assert_int_equal(back[0], 0);                  /* (0,0) blue */
    assert_int_equal(back[2], 255);
    assert_int_equal(back[3], 255);                /* (1,0) red */
    assert_int_equal(back[(4 * 6 + 5) * 3 + 2], 255); /* (5,4) blue */
    free(back);

    /* into the caller's buffer: too small, then exact */
    w = h = 0;
    back = (uint8_t *)1;
    assert_int_equal(image_read_png_rgb8(p, small, sizeof small, &back, &w, &h, err, sizeof err), -1);
    assert_null(back);
    assert_int_equal(w, 6);
    assert_int_equal(h, 5);
    assert_non_null(strstr(err, "buffer"));
    assert_non_null(strstr(err, "f.png"));
    assert_int_equal(image_read_png_rgb8(p, exact, sizeof exact, &back, NULL, NULL, err, sizeof err), 0);
    assert_ptr_equal(back, exact);
    assert_memory_equal(exact, img, sizeof img);
    assert_no_tmp(t);
}

static void test_png_stride_and_overwrite(void **state)
{
    tdir *t = *state;
    enum { S = 6 * 3 + 7 };
    uint8_t padded[5 * S], packed[5 * 18], other[5 * 18];
    uint8_t *back = NULL;
    char err[256] = "";
    int w, h, k;
    const char *p = in_dir(t, "stride.png");

    memset(padded, 0x5A, sizeof padded);
    make_f(padded, S);
    make_f(packed, 18);
    for (k = 0; k < (int)sizeof other; k++)
        other[k] = (uint8_t)(k * 7);
    /* first another image, then the padded F over it */
    assert_int_equal(image_write_png_rgb8(p, 6, 5, other, 18, err, sizeof err), 0);
    assert_int_equal(image_write_png_rgb8(p, 6, 5, padded, S, err, sizeof err), 0);
    assert_int_equal(image_read_png_rgb8(p, NULL, 0, &back, &w, &h, err, sizeof err), 0);
    assert_memory_equal(back, packed, sizeof packed);
    free(back);
    assert_int_equal(count_names(t->dir, "stride.png"), 1);
    assert_no_tmp(t);
}

/* ---- PFM -------------------------------------------------------------------- */

static void test_pfm_layout(void **state)
{
    tdir *t = *state;
    /* 3x2, row 0 (top) first in memory */
    float img[2 * 3 * 3];
    const char header[] = "PF\n3 2\n-1.0\n";
    const size_t hl = sizeof header - 1;
    char err[256] = "";
    unsigned char *b;
    size_t len, k;
    int x, y, c;
    const char *p = in_dir(t, "a.pfm");

    for (k = 0; k < 18; k++)
        img[k] = (float)k * 0.25f - 1.0f + (k == 7 ? 1e-3f : 0.0f);
    img[4] = 1e30f;
    img[5] = -0.0f;
    assert_int_equal(image_write_pfm(p, 3, 2, img, err, sizeof err), 0);
    b = slurp(p, &len);
    assert_int_equal(len, hl + 18 * 4);
    assert_memory_equal(b, header, hl);
    /* the bottom row (y = 1) comes first; each float little-endian */
    for (y = 0; y < 2; y++)
        for (x = 0; x < 3; x++)
            for (c = 0; c < 3; c++) {
                const unsigned char *q = b + hl + (((size_t)(1 - y) * 3 + (size_t)x) * 3 + (size_t)c) * 4;
                uint32_t u = (uint32_t)q[0] | (uint32_t)q[1] << 8 | (uint32_t)q[2] << 16 |
                             (uint32_t)q[3] << 24;
                uint32_t want;
                memcpy(&want, &img[((size_t)y * 3 + (size_t)x) * 3 + (size_t)c], 4);
                assert_int_equal(u, want);
            }
    /* 1.0f is 0x3F800000: stored 00 00 80 3F. img[8] = 1.0 is pixel (2,0)
     * channel 2, which lands in the second stored row. */
    assert_true(img[8] == 1.0f);
    assert_int_equal(b[hl + (3 * 3 + 2 * 3 + 2) * 4 + 2], 0x80);
    assert_int_equal(b[hl + (3 * 3 + 2 * 3 + 2) * 4 + 3], 0x3F);
    free(b);
    assert_no_tmp(t);
}

/* ---- failures ------------------------------------------------------------- */

static void test_missing_directory(void **state)
{
    tdir *t = *state;
    uint8_t img[5 * 18];
    float fimg[5 * 18];
    char err[256];
    char p[600];

    make_f(img, 18);
    memset(fimg, 0, sizeof fimg);
    snprintf(p, sizeof p, "%s/no/such/dir/out.png", t->dir);
    strcpy(err, "");
    assert_int_equal(image_write_png_rgb8(p, 6, 5, img, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "PNG: "));
    assert_non_null(strstr(err, "/no/such/dir/out.png"));
    assert_non_null(strstr(err, "/no/such/dir' does not exist")); /* the folder named, not errno */
    assert_false(file_exists(p));

    snprintf(p, sizeof p, "%s/no/such/dir/out.pfm", t->dir);
    strcpy(err, "");
    assert_int_equal(image_write_pfm(p, 6, 5, fimg, err, sizeof err), -1);
    assert_non_null(strstr(err, "PFM: "));
    assert_non_null(strstr(err, "out.pfm"));
    assert_non_null(strstr(err, "/no/such/dir' does not exist"));
    assert_false(file_exists(p));

    /* the output path is an existing directory: refused, nothing left */
    snprintf(p, sizeof p, "%s/adir", t->dir);
    assert_int_equal(mkdir(p, 0700), 0);
    strcpy(err, "");
    assert_int_equal(image_write_png_rgb8(p, 6, 5, img, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "is a directory"));
    assert_no_tmp(t);
    assert_int_equal(rmdir(p), 0);
    /* a small err buffer is filled and terminated, never overrun */
    {
        char tiny[8];
        memset(tiny, 'X', sizeof tiny);
        snprintf(p, sizeof p, "%s/no/such/dir/out.png", t->dir);
        assert_int_equal(image_write_png_rgb8(p, 6, 5, img, 0, tiny, 6), -1);
        assert_int_equal(strlen(tiny), 5);
        assert_int_equal(tiny[6], 'X');
        assert_int_equal(image_write_png_rgb8(p, 6, 5, img, 0, NULL, 0), -1);
    }
    assert_int_equal(count_names(t->dir, "out"), 0);
}

static void test_invalid_arguments(void **state)
{
    tdir *t = *state;
    uint8_t img[5 * 18];
    char err[256];
    const char *p = in_dir(t, "bad.png");

    make_f(img, 18);
    strcpy(err, "");
    assert_int_equal(image_write_png_rgb8(p, 0, 5, img, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "0x5"));
    strcpy(err, "");
    assert_int_equal(image_write_png_rgb8(p, 6, 5, NULL, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "NULL"));
    strcpy(err, "");
    assert_int_equal(image_write_png_rgb8(p, 6, 5, img, 17, err, sizeof err), -1);
    assert_non_null(strstr(err, "stride"));
    strcpy(err, "");
    assert_int_equal(image_write_pfm(p, 6, -1, (const float *)(const void *)img, err, sizeof err), -1);
    assert_non_null(strstr(err, "6x-1"));
    assert_int_equal(image_write_png_rgb8(NULL, 6, 5, img, 0, err, sizeof err), -1);
    assert_false(file_exists(p));
    assert_no_tmp(t);
}

/* A full disk, simulated with a file size limit: the write fails with the
 * system's reason, the old output stays intact, no temporary file is left. */
static void test_full_disk(void **state)
{
    tdir *t = *state;
    enum { N = 256 };
    uint8_t *noise = malloc(N * N * 3), old[5 * 18], *back = NULL;
    float *fnoise = malloc(N * N * 3 * sizeof(float));
    struct rlimit saved, lim;
    void (*prev)(int);
    char err[256];
    char pfm[600];
    uint32_t s = 12345u;
    int k, w, h, rc_png, rc_pfm;
    const char *p = in_dir(t, "full.png");

    assert_non_null(noise);
    assert_non_null(fnoise);
    for (k = 0; k < N * N * 3; k++) {
        s = s * 1664525u + 1013904223u;
        noise[k] = (uint8_t)(s >> 24);
        fnoise[k] = (float)(s >> 8);
    }
    make_f(old, 18);
    assert_int_equal(image_write_png_rgb8(p, 6, 5, old, 0, err, sizeof err), 0);
    snprintf(pfm, sizeof pfm, "%s/full.pfm", t->dir);
    assert_int_equal(image_write_pfm(pfm, 2, 2, fnoise, err, sizeof err), 0);

    assert_int_equal(getrlimit(RLIMIT_FSIZE, &saved), 0);
    lim = saved;
    lim.rlim_cur = 8192;
    prev = signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    strcpy(err, "");
    rc_png = image_write_png_rgb8(p, N, N, noise, 0, err, sizeof err);
    {
        char err2[256] = "";
        rc_pfm = image_write_pfm(pfm, N, N, fnoise, err2, sizeof err2);
        assert_int_equal(setrlimit(RLIMIT_FSIZE, &saved), 0);
        signal(SIGXFSZ, prev);
        assert_int_equal(rc_pfm, -1);
        assert_non_null(strstr(err2, "full.pfm"));
        assert_non_null(strstr(err2, strerror(EFBIG)));
    }
    assert_int_equal(rc_png, -1);
    assert_non_null(strstr(err, "full.png"));
    assert_non_null(strstr(err, strerror(EFBIG)));

    /* the earlier outputs are untouched */
    assert_int_equal(image_read_png_rgb8(p, NULL, 0, &back, &w, &h, err, sizeof err), 0);
    assert_int_equal(w, 6);
    assert_int_equal(h, 5);
    assert_memory_equal(back, old, sizeof old);
    free(back);
    {
        size_t len;
        unsigned char *b = slurp(pfm, &len);
        assert_int_equal(len, strlen("PF\n2 2\n-1.0\n") + 12 * 4);
        free(b);
    }
    assert_no_tmp(t);
    /* with the limit lifted the same write succeeds */
    assert_int_equal(image_write_png_rgb8(p, N, N, noise, 0, err, sizeof err), 0);
    assert_int_equal(image_read_png_rgb8(p, NULL, 0, &back, &w, &h, err, sizeof err), 0);
    assert_memory_equal(back, noise, N * N * 3);
    free(back);
    free(noise);
    free(fnoise);
    assert_no_tmp(t);
}

/* ---- reading other PNG kinds ------------------------------------------------ */

/* Writes a PNG with libpng directly: rows are given already packed for the
 * colour type and bit depth. */
static void raw_png(const char *path, int w, int h, int color_type, int depth, int interlace,
                    const uint8_t *data, size_t row_bytes, const png_color *pal, int npal,
                    const png_byte *trns, int ntrns)
{
    FILE *f = fopen(path, "wb");
    png_structp png;
    png_infop info;
    int y, passes, pass;
    assert_non_null(f);
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    assert_non_null(png);
    info = png_create_info_struct(png);
    assert_non_null(info);
    if (setjmp(png_jmpbuf(png)))
        fail_msg("libpng failed writing the fixture %s", path);
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, color_type,
                 interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (pal != NULL)
        png_set_PLTE(png, info, pal, npal);
    if (trns != NULL)
        png_set_tRNS(png, info, trns, ntrns, NULL);
    png_write_info(png, info);
    passes = png_set_interlace_handling(png);
    for (pass = 0; pass < passes; pass++)
        for (y = 0; y < h; y++)
            png_write_row(png, data + (size_t)y * row_bytes);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    assert_int_equal(fclose(f), 0);
}

static void read_expect(const char *path, int w, int h, const uint8_t *want)
{
    uint8_t *back = NULL;
    int gw = 0, gh = 0;
    char err[256] = "";
    assert_int_equal(image_read_png_rgb8(path, NULL, 0, &back, &gw, &gh, err, sizeof err), 0);
    assert_int_equal(gw, w);
    assert_int_equal(gh, h);
    assert_memory_equal(back, want, (size_t)w * (size_t)h * 3);
    free(back);
}

static void test_read_png_kinds(void **state)
{
    tdir *t = *state;
    enum { W = 9, H = 7 };
    uint8_t rgb[W * H * 3], data[W * H * 8], want[W * H * 3];
    int x, y, k;
    const char *p = in_dir(t, "kind.png");

    for (k = 0; k < W * H * 3; k++)
        rgb[k] = (uint8_t)(k * 37 + 11);

    /* 8-bit grey */
    for (k = 0; k < W * H; k++) {
        data[k] = (uint8_t)(k * 4);
        want[3 * k] = want[3 * k + 1] = want[3 * k + 2] = data[k];
    }
    raw_png(p, W, H, PNG_COLOR_TYPE_GRAY, 8, 0, data, W, NULL, 0, NULL, 0);
    read_expect(p, W, H, want);

    /* 1-bit grey: 0 -> 0, 1 -> 255; pattern x + y odd */
    memset(data, 0, sizeof data);
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            int on = (x + y) & 1;
            if (on)
                data[y * 2 + x / 8] |= (uint8_t)(0x80 >> (x % 8));
            want[(y * W + x) * 3] = want[(y * W + x) * 3 + 1] = want[(y * W + x) * 3 + 2] =
                on ? 255 : 0;
        }
    raw_png(p, W, H, PNG_COLOR_TYPE_GRAY, 1, 0, data, 2, NULL, 0, NULL, 0);
    read_expect(p, W, H, want);

    /* grey + alpha: alpha dropped */
    for (k = 0; k < W * H; k++) {
        data[2 * k] = (uint8_t)(250 - k);
        data[2 * k + 1] = (uint8_t)(k * 3);
        want[3 * k] = want[3 * k + 1] = want[3 * k + 2] = data[2 * k];
    }
    raw_png(p, W, H, PNG_COLOR_TYPE_GRAY_ALPHA, 8, 0, data, W * 2, NULL, 0, NULL, 0);
    read_expect(p, W, H, want);

    /* 4-bit palette with transparency */
    {
        png_color pal[5] = { { 255, 0, 0 }, { 0, 255, 0 }, { 0, 0, 255 }, { 10, 20, 30 }, { 200, 100, 50 } };
        png_byte trns[2] = { 0, 128 };
        memset(data, 0, sizeof data);
        for (y = 0; y < H; y++)
            for (x = 0; x < W; x++) {
                int i = (x * 3 + y) % 5;
                data[y * 5 + x / 2] |= (uint8_t)(x % 2 == 0 ? i << 4 : i);
                want[(y * W + x) * 3] = pal[i].red;
                want[(y * W + x) * 3 + 1] = pal[i].green;
                want[(y * W + x) * 3 + 2] = pal[i].blue;
            }
        raw_png(p, W, H, PNG_COLOR_TYPE_PALETTE, 4, 0, data, 5, pal, 5, trns, 2);
        read_expect(p, W, H, want);
    }

    /* RGBA 8: alpha dropped */
    for (k = 0; k < W * H; k++) {
        memcpy(&data[4 * k], &rgb[3 * k], 3);
        data[4 * k + 3] = (uint8_t)k;
    }
    raw_png(p, W, H, PNG_COLOR_TYPE_RGB_ALPHA, 8, 0, data, W * 4, NULL, 0, NULL, 0);
    read_expect(p, W, H, rgb);

    /* RGB 16: v * 257 scales back to v exactly; 0x00FF rounds to 1 (a
     * plain high-byte strip would give 0) */
    for (k = 0; k < W * H * 3; k++) {
        unsigned v = k % 5 == 0 ? 0x00FFu : rgb[k] * 257u;
        data[2 * k] = (uint8_t)(v >> 8);
        data[2 * k + 1] = (uint8_t)(v & 0xFF);
        want[k] = k % 5 == 0 ? 1 : rgb[k];
    }
    raw_png(p, W, H, PNG_COLOR_TYPE_RGB, 16, 0, data, W * 6, NULL, 0, NULL, 0);
    read_expect(p, W, H, want);

    /* Adam7-interlaced RGB 8 */
    raw_png(p, W, H, PNG_COLOR_TYPE_RGB, 8, 1, rgb, W * 3, NULL, 0, NULL, 0);
    read_expect(p, W, H, rgb);
    assert_no_tmp(t);
}

static void test_read_errors(void **state)
{
    tdir *t = *state;
    uint8_t *back = (uint8_t *)1, img[64 * 64 * 3];
    char err[256];
    unsigned char *b;
    size_t len;
    FILE *f;
    int k;
    const char *p;

    /* missing file */
    p = in_dir(t, "missing.png");
    strcpy(err, "");
    assert_int_equal(image_read_png_rgb8(p, NULL, 0, &back, NULL, NULL, err, sizeof err), -1);
    assert_null(back);
    assert_non_null(strstr(err, "missing.png"));
    assert_non_null(strstr(err, strerror(ENOENT)));

    /* not a PNG */
    p = in_dir(t, "text.png");
    f = fopen(p, "wb");
    assert_non_null(f);
    fputs("this is not a picture at all\n", f);
    fclose(f);
    strcpy(err, "");
    assert_int_equal(image_read_png_rgb8(p, NULL, 0, &back, NULL, NULL, err, sizeof err), -1);
    assert_non_null(strstr(err, "not a PNG"));

    /* truncated: the header reads, the pixels do not (nothing leaks) */
    for (k = 0; k < (int)sizeof img; k++)
        img[k] = (uint8_t)((k * 2654435761u) >> 24);
    p = in_dir(t, "cut.png");
    assert_int_equal(image_write_png_rgb8(p, 64, 64, img, 0, err, sizeof err), 0);
    b = slurp(p, &len);
    f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, len / 2, f), len / 2);
    fclose(f);
    free(b);
    strcpy(err, "");
    back = (uint8_t *)1;
    assert_int_equal(image_read_png_rgb8(p, NULL, 0, &back, NULL, NULL, err, sizeof err), -1);
    assert_null(back);
    assert_non_null(strstr(err, "cut.png"));
    assert_true(strlen(err) > strlen("PNG: cannot decode ''") + 7);
    /* and into a caller buffer */
    back = (uint8_t *)1;
    assert_int_equal(image_read_png_rgb8(p, img, sizeof img, &back, NULL, NULL, err, sizeof err), -1);
    assert_null(back);
    assert_no_tmp(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_png_roundtrip_f, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_png_stride_and_overwrite, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_pfm_layout, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_missing_directory, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_invalid_arguments, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_full_disk, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_read_png_kinds, setup_dir, teardown_dir),
        cmocka_unit_test_setup_teardown(test_read_errors, setup_dir, teardown_dir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
