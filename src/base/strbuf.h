/* strbuf: bounded text building without stdio (the core has no printf).
 * Writes never overflow: text past the capacity is dropped and the buffer
 * stays NUL-terminated. */
#ifndef PLX_STRBUF_H
#define PLX_STRBUF_H

#include <stddef.h>
#include <stdint.h>

typedef struct strbuf {
    char *buf;
    size_t cap;   /* bytes of buf, including the NUL */
    size_t len;
} strbuf;

void sb_init(strbuf *b, char *buf, size_t cap);
void sb_str(strbuf *b, const char *s);
void sb_strn(strbuf *b, const char *s, size_t n);
void sb_char(strbuf *b, char c);
void sb_uint(strbuf *b, uint64_t v);
void sb_int(strbuf *b, int64_t v);
/* v with exactly 'decimals' digits after the point (0..9), rounded. */
void sb_fixed(strbuf *b, double v, int decimals);
/* v in a short readable form: up to 'sig' significant digits, no trailing
 * zeros, exponent form for very large or small magnitudes; nan/inf spelled. */
void sb_num(strbuf *b, double v, int sig);

#endif
