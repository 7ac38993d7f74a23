/* jsoncheck: one pass over JSON text that accepts exactly what cJSON 1.7.15
 * (Debian's, with its security fixes) parses and fails at the byte cJSON
 * reports, without building anything: a loop over three states (a value is
 * due, an object member is due, a value just ended) and a stack of one bit
 * per open container (array or object), at most JSONSCAN_DEPTH deep.
 *
 * cJSON's habits kept: white space is every byte 0..32; a UTF-8 byte order
 * mark is skipped; numbers are the run of 0-9 + - e E . that strtod reads a
 * prefix of; a key that is not a string fails one byte after its start; a
 * string's bad escape fails at its backslash and an unterminated string one
 * byte after its opening quote; running off the end reports the last byte.
 * tests/unit/test_jsoncheck.c compares it with cJSON itself. */
#include <string.h>

#include "base/jsonscan.h"

enum { WANT_VALUE, WANT_MEMBER, AFTER_VALUE };

typedef struct chk {
    const char *t;
    size_t len, pos;
    unsigned depth;
    unsigned char is_obj[JSONSCAN_DEPTH / 8 + 1];
} chk;

static int byte_at(const chk *c, size_t p)
{
    return (unsigned char)c->t[p];
}

/* cJSON's buffer_skip_whitespace: stops on the last byte rather than past
 * the end. */
static size_t skip_ws(const chk *c, size_t p)
{
    if (p >= c->len)
        return p;
    while (p < c->len && byte_at(c, p) <= 32)
        p++;
    return p == c->len ? p - 1 : p;
}

static int top_is_obj(const chk *c)
{
    unsigned d = c->depth - 1;
    return (c->is_obj[d / 8] >> (d % 8)) & 1;
}

static void push(chk *c, int obj)
{
    unsigned d = c->depth++;
    if (obj)
        c->is_obj[d / 8] |= (unsigned char)(1u << (d % 8));
    else
        c->is_obj[d / 8] &= (unsigned char)~(1u << (d % 8));
}

static int check_escapes(chk *c, size_t p, size_t e)
{
    while (p < e) {
        unsigned long cp;
        size_t n;
        if (c->t[p] != '\\') {
            p++;
            continue;
        }
        switch (c->t[p + 1]) {
        case 'b': case 'f': case 'n': case 'r': case 't': case '"': case '\\': case '/':
            p += 2;
            break;
        case 'u':
            n = jsonscan_utf16(c->t + p, e - p, &cp);
            if (n == 0) {
                c->pos = p;
                return 0;
            }
            p += n;
            break;
        default:
            c->pos = p;
            return 0;
        }
    }
    return 1;
}

/* A string at c->pos (a key when called for a member). */
static int check_string(chk *c)
{
    size_t start = c->pos, e = start + 1;
    c->pos = start + 1; /* where cJSON fails when the string does not end */
    if (c->t[start] != '"')
        return 0;
    while (e < c->len && c->t[e] != '"') {
        if (c->t[e] == '\\') {
            if (e + 1 >= c->len)
                return 0;
            e++;
        }
        e++;
    }
    if (e >= c->len)
        return 0;
    if (!check_escapes(c, start + 1, e))
        return 0;
    c->pos = e + 1;
    return 1;
}

static int matches(const chk *c, const char *word, size_t n)
{
    return c->pos + n <= c->len && memcmp(c->t + c->pos, word, n) == 0;
}

/* An array or object opens at c->pos. Returns the next state, or -1. */
static int open_container(chk *c, char open)
{
    char close = open == '[' ? ']' : '}';
    size_t p;
    if (c->depth >= JSONSCAN_DEPTH)
        return -1;
    push(c, open == '{');
    p = skip_ws(c, c->pos + 1);
    if (p < c->len && c->t[p] == close) {
        c->pos = p + 1;
        c->depth--;
        return AFTER_VALUE;
    }
    if (p >= c->len) {
        c->pos = p - 1;
        return -1;
    }
    if (open == '[') {
        c->pos = skip_ws(c, p);
        return WANT_VALUE;
    }
    c->pos = p - 1; /* the byte before the first key, as cJSON steps back */
    return WANT_MEMBER;
}

static int want_value(chk *c)
{
    char ch = c->pos < c->len ? c->t[c->pos] : '\0';
    size_t n;
    if (matches(c, "null", 4) || matches(c, "true", 4)) {
        c->pos += 4;
        return AFTER_VALUE;
    }
    if (matches(c, "false", 5)) {
        c->pos += 5;
        return AFTER_VALUE;
    }
    if (c->pos >= c->len)
        return -1;
    if (ch == '"')
        return check_string(c) ? AFTER_VALUE : -1;
    if (ch == '-' || (ch >= '0' && ch <= '9')) {
        n = jsonscan_number_len(c->t, c->len, c->pos);
        if (n == 0)
            return -1;
        c->pos += n;
        return AFTER_VALUE;
    }
    if (ch == '[' || ch == '{')
        return open_container(c, ch);
    return -1;
}

/* c->pos is the byte before a key: '{', ',' or white space. */
static int want_member(chk *c)
{
    if (c->pos + 1 >= c->len)
        return -1; /* nothing after the comma */
    c->pos = skip_ws(c, c->pos + 1);
    if (!check_string(c))
        return -1;
    c->pos = skip_ws(c, c->pos);
    if (c->pos >= c->len || c->t[c->pos] != ':')
        return -1;
    c->pos = skip_ws(c, c->pos + 1);
    return WANT_VALUE;
}

/* A value ended at c->pos: a comma or the end of its container follows.
 * Returns the next state, 1 + AFTER_VALUE when the top value is done. */
static int after_value(chk *c)
{
    int obj;
    if (c->depth == 0)
        return AFTER_VALUE + 1;
    c->pos = skip_ws(c, c->pos);
    obj = top_is_obj(c);
    if (c->pos < c->len && c->t[c->pos] == ',') {
        if (obj)
            return WANT_MEMBER;
        c->pos = skip_ws(c, c->pos + 1);
        return WANT_VALUE;
    }
    if (c->pos >= c->len || c->t[c->pos] != (obj ? '}' : ']'))
        return -1;
    c->pos++;
    c->depth--;
    return AFTER_VALUE;
}

int jsonscan_check(const char *text, size_t len, size_t *at)
{
    chk c;
    int state = WANT_VALUE;
    *at = 0;
    if (!text || len == 0)
        return 0;
    memset(&c, 0, sizeof c);
    c.t = text;
    c.len = len;
    if (len >= 5 && memcmp(text, "\xEF\xBB\xBF", 3) == 0)
        c.pos = 3;
    c.pos = skip_ws(&c, c.pos);
    while (state >= 0 && state <= AFTER_VALUE) {
        if (state == WANT_VALUE)
            state = want_value(&c);
        else if (state == WANT_MEMBER)
            state = want_member(&c);
        else
            state = after_value(&c);
    }
    *at = c.pos < len ? c.pos : len - 1;
    if (state < 0)
        return 0;
    *at = c.pos; /* just after the value (len at most) */
    return 1;
}
