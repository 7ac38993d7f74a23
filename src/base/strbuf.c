#include "base/strbuf.h"
#include <math.h>

void sb_init(strbuf *b, char *buf, size_t cap)
{
    b->buf = buf;
    b->cap = cap;
    b->len = 0;
    if (cap)
        buf[0] = '\0';
}

void sb_char(strbuf *b, char c)
{
    if (b->cap == 0 || b->len + 1 >= b->cap)
        return;
    b->buf[b->len++] = c;
    b->buf[b->len] = '\0';
}

void sb_strn(strbuf *b, const char *s, size_t n)
{
    size_t i;
    for (i = 0; i < n && s[i]; i++)
        sb_char(b, s[i]);
}

void sb_str(strbuf *b, const char *s)
{
    while (s && *s)
        sb_char(b, *s++);
}

void sb_uint(strbuf *b, uint64_t v)
{
    char tmp[24];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (n)
        sb_char(b, tmp[--n]);
}

void sb_int(strbuf *b, int64_t v)
{
    if (v < 0) {
        sb_char(b, '-');
        sb_uint(b, (uint64_t)(-(v + 1)) + 1);
    } else {
        sb_uint(b, (uint64_t)v);
    }
}

static int special(strbuf *b, double v)
{
    if (v != v) {
        sb_str(b, "nan");
        return 1;
    }
    if (isinf(v)) {
        sb_str(b, v < 0 ? "-inf" : "inf");
        return 1;
    }
    return 0;
}

/* Digits of an integer-valued magnitude m < 1e18, zero-padded to width. */
static void digits(strbuf *b, uint64_t m, int width)
{
    char tmp[24];
    int n = 0;
    while (m || n < width) {
        tmp[n++] = (char)('0' + m % 10);
        m /= 10;
        if (n >= 20)
            break;
    }
    while (n)
        sb_char(b, tmp[--n]);
}

void sb_fixed(strbuf *b, double v, int decimals)
{
    double scale = 1.0, m;
    uint64_t q, ip, fp, p10 = 1;
    int i;
    if (special(b, v))
        return;
    if (decimals < 0)
        decimals = 0;
    if (decimals > 9)
        decimals = 9;
    for (i = 0; i < decimals; i++) {
        scale *= 10.0;
        p10 *= 10;
    }
    m = fabs(v) * scale + 0.5;
    if (m >= 9.0e18) {
        sb_num(b, v, 17);
        return;
    }
    q = (uint64_t)m;
    if (v < 0 && q != 0)
        sb_char(b, '-');
    ip = q / p10;
    fp = q % p10;
    sb_uint(b, ip);
    if (decimals > 0) {
        sb_char(b, '.');
        digits(b, fp, decimals);
    }
}

void sb_num(strbuf *b, double v, int sig)
{
    double a, p;
    int e, i, dec;
    uint64_t q;
    char tmp[24];
    int n;
    if (special(b, v))
        return;
    if (sig < 1)
        sig = 1;
    if (sig > 17)
        sig = 17;
    if (v == 0.0) {
        sb_char(b, '0');
        return;
    }
    a = fabs(v);
    e = (int)floor(log10(a));
    if (e >= -4 && e < sig) {
        dec = sig - 1 - e;
        if (dec > 9) dec = 9;
        /* fixed form, then strip trailing zeros */
        {
            char fb[64];
            strbuf f;
            size_t len;
            sb_init(&f, fb, sizeof fb);
            sb_fixed(&f, v, dec);
            len = f.len;
            if (dec > 0) {
                while (len > 0 && fb[len - 1] == '0')
                    len--;
                if (len > 0 && fb[len - 1] == '.')
                    len--;
            }
            sb_strn(b, fb, len);
        }
        return;
    }
    /* exponent form: d.ddddde±x */
    p = a / pow(10.0, e);
    if (p >= 10.0) { p /= 10.0; e++; }
    if (p < 1.0) { p *= 10.0; e--; }
    q = (uint64_t)(p * pow(10.0, sig - 1) + 0.5);
    if (q >= (uint64_t)pow(10.0, sig)) { q /= 10; e++; }
    n = 0;
    for (i = 0; i < sig; i++) {
        tmp[n++] = (char)('0' + q % 10);
        q /= 10;
    }
    if (v < 0)
        sb_char(b, '-');
    sb_char(b, tmp[--n]);
    /* strip trailing zeros of the mantissa */
    i = 0;
    while (i < n && tmp[i] == '0')
        i++;
    if (n > i) {
        sb_char(b, '.');
        while (n > i)
            sb_char(b, tmp[--n]);
    }
    sb_char(b, 'e');
    sb_int(b, e);
}
