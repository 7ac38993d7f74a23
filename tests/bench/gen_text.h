/* A growing text buffer for plx_gen_city's output, shared by the benches:
 * they generate cities in memory rather than reading files. */
#ifndef PLX_BENCH_GEN_TEXT_H
#define PLX_BENCH_GEN_TEXT_H

#include <stdlib.h>
#include <string.h>

typedef struct text {
    char *buf;
    size_t len, cap;
} text;

/* plx_write_fn: appends and keeps the text NUL-terminated; -1 when out of
 * memory (the buffer so far is kept, to be freed by the caller). */
static int append(void *ctx, const char *data, size_t len)
{
    text *t = ctx;
    if (t->len + len + 1 > t->cap) {
        size_t cap = (t->len + len + 1) * 2;
        char *nb = realloc(t->buf, cap);
        if (!nb)
            return -1;
        t->buf = nb;
        t->cap = cap;
    }
    memcpy(t->buf + t->len, data, len);
    t->len += len;
    t->buf[t->len] = '\0';
    return 0;
}

#endif
