/* apng: an animated PNG assembled from PNG files of one size (APNG: the
 * acTL, fcTL and fdAT chunks). The frames' compressed image data is taken
 * as it is: the first file's IDAT chunks stay IDAT (a viewer without APNG
 * shows the first frame), every later file's become fdAT chunks, each
 * frame preceded by its fcTL (whole canvas, no disposal, source blending).
 * Nothing is decoded or compressed again. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "png/image_write.h"
#include "port.h"

static const unsigned char sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n' };

/* CRC-32 of the PNG specification, zlib's (the same polynomial, the
 * chunks' CRC as libpng computes it), over n bytes in steps zlib's uInt
 * can count. */
static uint32_t crc_update(uint32_t c, const unsigned char *p, size_t n)
{
    uLong z = c ^ 0xffffffffu; /* zlib's crc32 takes and gives the CRC complemented */
    while (n > 0) {
        uInt k = n > 0x40000000u ? 0x40000000u : (uInt)n;
        z = crc32(z, p, k);
        p += k;
        n -= k;
    }
    return (uint32_t)z ^ 0xffffffffu;
}

static void be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

static uint32_t get32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* One chunk: length, type, the optional 4-byte prefix (a sequence number),
 * data, CRC over type, prefix and data. */
static int put_chunk(safe_out *o, const char *type, const unsigned char *pre, size_t npre,
                     const unsigned char *data, size_t n)
{
    unsigned char head[8], tail[4];
    uint32_t c;
    be32(head, (uint32_t)(npre + n));
    memcpy(head + 4, type, 4);
    c = crc_update(0xffffffffu, head + 4, 4);
    if (npre)
        c = crc_update(c, pre, npre);
    if (n)
        c = crc_update(c, data, n);
    be32(tail, c ^ 0xffffffffu);
    return safe_out_write(o, head, 8) | (npre ? safe_out_write(o, pre, npre) : 0) |
           (n ? safe_out_write(o, data, n) : 0) | safe_out_write(o, tail, 4);
}

static int put_fctl(safe_out *o, uint32_t *seq, const unsigned char *ihdr, unsigned dnum, unsigned dden)
{
    unsigned char f[26];
    be32(f, (*seq)++);
    memcpy(f + 4, ihdr, 8);      /* width, height */
    be32(f + 12, 0);             /* x offset */
    be32(f + 16, 0);             /* y offset */
    f[20] = (unsigned char)(dnum >> 8);
    f[21] = (unsigned char)dnum;
    f[22] = (unsigned char)(dden >> 8);
    f[23] = (unsigned char)dden;
    f[24] = 0;                   /* dispose: none */
    f[25] = 0;                   /* blend: source */
    return put_chunk(o, "fcTL", NULL, 0, f, sizeof f);
}

/* Copies frame k's chunks: before the first IDAT (k == 0 only: IHDR and
 * the ancillary chunks, then acTL), its image data (IDAT for k == 0, else
 * fdAT with sequence numbers). ihdr keeps the first frame's 13 bytes. */
static int put_frame(safe_out *o, const unsigned char *b, size_t len, int k, int n, uint32_t *seq,
                     unsigned char *ihdr, unsigned dnum, unsigned dden, char *err, size_t errlen)
{
    size_t p = 8;
    int fctl = 0;
    if (len < 8 || memcmp(b, sig, 8) != 0)
        return snprintf(err, errlen, "not a PNG file"), -1;
    while (p + 12 <= len) {
        uint32_t n32 = get32(b + p);
        const unsigned char *type = b + p + 4, *data = b + p + 8;
        if (n32 > len - p - 12)
            return snprintf(err, errlen, "a PNG chunk runs past the end of the file"), -1;
        if (memcmp(type, "IHDR", 4) == 0) {
            if (n32 != 13)
                return snprintf(err, errlen, "bad IHDR"), -1;
            if (k == 0) {
                unsigned char ac[8];
                memcpy(ihdr, data, 13);
                if (put_chunk(o, "IHDR", NULL, 0, data, 13) != 0)
                    return snprintf(err, errlen, "write failed"), -1;
                be32(ac, (uint32_t)n);
                be32(ac + 4, 0);   /* plays: forever */
                if (put_chunk(o, "acTL", NULL, 0, ac, 8) != 0)
                    return snprintf(err, errlen, "write failed"), -1;
            } else if (memcmp(ihdr, data, 13) != 0)
                return snprintf(err, errlen, "frame %d differs from the first in size or format", k + 1), -1;
        } else if (memcmp(type, "IDAT", 4) == 0) {
            unsigned char s4[4];
            if (!fctl && put_fctl(o, seq, ihdr, dnum, dden) != 0)
                return snprintf(err, errlen, "write failed"), -1;
            fctl = 1;
            be32(s4, *seq);
            if (k == 0 ? put_chunk(o, "IDAT", NULL, 0, data, n32) : put_chunk(o, "fdAT", s4, 4, data, n32))
                return snprintf(err, errlen, "write failed"), -1;
            if (k > 0)
                ++*seq;
        } else if (memcmp(type, "IEND", 4) == 0) {
            break;
        } else if (k == 0 && !fctl && (type[0] & 0x20)) {
            /* ancillary chunks of the first file before its data (sRGB, ...) */
            if (put_chunk(o, (const char *)type, NULL, 0, data, n32) != 0)
                return snprintf(err, errlen, "write failed"), -1;
        }
        p += 12 + (size_t)n32;
    }
    if (!fctl)
        return snprintf(err, errlen, "no image data"), -1;
    return 0;
}

/* A write to the animation failed: given up, the reason said as every
 * output's ("cannot write 'PATH': REASON"). */
static int write_failed(safe_out *o, const char *path, char *err, size_t errlen)
{
    int e = safe_out_errno(o);
    safe_out_abort(o);
    snprintf(err, errlen, "animated PNG: cannot write '%s': %s", path, e ? strerror(e) : "a write failed");
    return -1;
}

int image_write_apng(const char *path, const char *const *frames, int n, unsigned delay_num, unsigned delay_den,
                     char *err, size_t errlen)
{
    unsigned char ihdr[13];
    char why[512];
    uint32_t seq = 0;
    safe_out *o;
    int k;
    if (n < 1 || delay_num > 65535 || delay_den > 65535) {
        snprintf(err, errlen, "animated PNG: '%s': needs 1 or more frames and delays below 65536", path);
        return -1;
    }
    o = safe_out_open_batch(path, err, errlen);
    if (!o)
        return -1;
    if (safe_out_write(o, sig, 8) != 0)
        return write_failed(o, path, err, errlen);
    for (k = 0; k < n; k++) {
        size_t len;
        char *b = port_read_text(frames[k], &len, why, sizeof why);
        int rc = b ? put_frame(o, (const unsigned char *)b, len, k, n, &seq, ihdr, delay_num, delay_den, why,
                               sizeof why)
                   : -1;
        free(b);
        if (rc != 0 && safe_out_errno(o))
            return write_failed(o, path, err, errlen);
        if (rc != 0) {
            safe_out_abort(o);
            snprintf(err, errlen, "animated PNG: '%s': frame '%s': %s", path, frames[k], why);
            return -1;
        }
    }
    if (put_chunk(o, "IEND", NULL, 0, NULL, 0) != 0)
        return write_failed(o, path, err, errlen);
    if (safe_out_commit(&o, 1, why, sizeof why) != 0) {
        snprintf(err, errlen, "animated PNG: %s", why);
        return -1;
    }
    return 0;
}
