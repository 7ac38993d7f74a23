/* jsonscan: values read in place from checked JSON text (jsonscan.h).
 * Strings are unescaped as cJSON does (\uXXXX to UTF-8, surrogate pairs, a
 * bad hex digit reading as 0) so a key or a value compares and copies the
 * same as cJSON's parsed string did. */
#include <string.h>

#include "base/jsonscan.h"

size_t jsonscan_ws(const char *text, size_t len, size_t off)
{
    while (off < len && (unsigned char)text[off] <= 32)
        off++;
    return off;
}

size_t jsonscan_trailing(const char *text, size_t len, size_t end)
{
    size_t k;
    while (end < len && (text[end] == ' ' || text[end] == '\t' || text[end] == '\r' || text[end] == '\n'))
        end++;
    for (k = end; k < len && text[k] == '\0'; k++) /* NULs to the end: a C string's terminator, padding */
        ;
    return k < len ? end : len;
}

js_kind jsonscan_kind(const char *text, size_t off)
{
    if (off == JSONSCAN_NONE)
        return JS_NONE;
    switch (text[off]) {
    case '{':
        return JS_OBJECT;
    case '[':
        return JS_ARRAY;
    case '"':
        return JS_STRING;
    case 't':
        return JS_TRUE;
    case 'f':
        return JS_FALSE;
    case 'n':
        return JS_NULL;
    default:
        return JS_NUMBER;
    }
}

/* The closing quote of the string opening at off (len when none): a
 * backslash takes the byte after it, whatever it is. */
static size_t string_end(const char *text, size_t len, size_t off)
{
    size_t e = off + 1;
    while (e < len && text[e] != '"')
        e += text[e] == '\\' ? 2 : 1;
    return e < len ? e : len;
}

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static int number_char(char c)
{
    return is_digit(c) || c == '+' || c == '-' || c == 'e' || c == 'E' || c == '.';
}

size_t jsonscan_number_len(const char *text, size_t len, size_t off)
{
    size_t run = off, p = off, digits = 0, q;
    while (run < len && number_char(text[run]))
        run++;
    if (p < run && (text[p] == '+' || text[p] == '-'))
        p++;
    for (; p < run && is_digit(text[p]); p++)
        digits++;
    if (p < run && text[p] == '.')
        for (p++; p < run && is_digit(text[p]); p++)
            digits++;
    if (digits == 0)
        return 0;
    if (p < run && (text[p] == 'e' || text[p] == 'E')) {
        q = p + 1;
        if (q < run && (text[q] == '+' || text[q] == '-'))
            q++;
        if (q < run && is_digit(text[q])) {
            while (q < run && is_digit(text[q]))
                q++;
            p = q;
        }
    }
    return p - off;
}

/* Bytes that matter when skipping a container: 1 brackets, 2 a quote. */
static const unsigned char skip_class[256] = {
    ['"'] = 2, ['['] = 1, [']'] = 1, ['{'] = 1, ['}'] = 1,
};

size_t jsonscan_skip(const char *text, size_t len, size_t off)
{
    size_t i = off;
    long depth = 0;
    switch (jsonscan_kind(text, off)) {
    case JS_STRING:
        return string_end(text, len, off) + 1;
    case JS_TRUE:
    case JS_NULL:
        return off + 4;
    case JS_FALSE:
        return off + 5;
    case JS_NUMBER:
        return off + jsonscan_number_len(text, len, off);
    default:
        break;
    }
    while (i < len) {
        unsigned char c = (unsigned char)text[i];
        if (!skip_class[c]) {
            i++;
            continue;
        }
        if (c == '"') {
            i = string_end(text, len, i) + 1;
            continue;
        }
        if (c == '[' || c == '{') {
            depth++;
        } else if (--depth == 0) {
            return i + 1;
        }
        i++;
    }
    return len;
}

/* The value of the member whose key starts at off. */
static size_t member_value(const char *text, size_t len, size_t off)
{
    size_t p = jsonscan_ws(text, len, string_end(text, len, off) + 1);
    return jsonscan_ws(text, len, p + 1); /* past the ':' */
}

size_t jsonscan_first(const char *text, size_t len, size_t c)
{
    js_kind k = jsonscan_kind(text, c);
    size_t p;
    if (k != JS_ARRAY && k != JS_OBJECT)
        return JSONSCAN_NONE;
    p = jsonscan_ws(text, len, c + 1);
    if (p >= len || text[p] == ']' || text[p] == '}')
        return JSONSCAN_NONE;
    return k == JS_OBJECT ? member_value(text, len, p) : p;
}

size_t jsonscan_next(const char *text, size_t len, size_t off, int in_object)
{
    size_t p = jsonscan_ws(text, len, jsonscan_skip(text, len, off));
    if (p >= len || text[p] != ',')
        return JSONSCAN_NONE;
    p = jsonscan_ws(text, len, p + 1);
    return in_object ? member_value(text, len, p) : p;
}

/* ---- strings ------------------------------------------------------------- */

/* Where unescaped bytes go: copied into buf (up to cap - 1), or compared
 * with cmp. n counts the bytes of the C string so far. */
typedef struct sink {
    char *buf;
    size_t cap, n;
    const char *cmp;
    int differs;
} sink;

/* 0 when the string ends here (a NUL byte, or a difference from cmp). */
static int put(sink *k, unsigned b)
{
    if (b == 0)
        return 0;
    if (k->cmp) {
        if ((unsigned char)k->cmp[k->n] != b) {
            k->differs = 1;
            return 0;
        }
    } else if (k->n + 1 < k->cap) {
        k->buf[k->n] = (char)b;
    }
    k->n++;
    return 1;
}

static unsigned hex4(const char *s)
{
    unsigned h = 0;
    int i;
    for (i = 0; i < 4; i++) {
        char c = s[i];
        if (c >= '0' && c <= '9')
            h = h * 16 + (unsigned)(c - '0');
        else if (c >= 'A' && c <= 'F')
            h = h * 16 + 10 + (unsigned)(c - 'A');
        else if (c >= 'a' && c <= 'f')
            h = h * 16 + 10 + (unsigned)(c - 'a');
        else
            return 0; /* as cJSON: the whole escape reads as U+0000 */
    }
    return h;
}

size_t jsonscan_utf16(const char *s, size_t avail, unsigned long *cp)
{
    unsigned first, second;
    if (avail < 6)
        return 0;
    first = hex4(s + 2);
    if (first >= 0xDC00 && first <= 0xDFFF)
        return 0;
    if (first < 0xD800 || first > 0xDBFF) {
        *cp = first;
        return 6;
    }
    if (avail < 12 || s[6] != '\\' || s[7] != 'u')
        return 0;
    second = hex4(s + 8);
    if (second < 0xDC00 || second > 0xDFFF)
        return 0;
    *cp = 0x10000ul + (((unsigned long)(first & 0x3FF) << 10) | (second & 0x3FF));
    return 12;
}

static int put_utf8(sink *k, unsigned long cp)
{
    if (cp < 0x80)
        return put(k, (unsigned)cp);
    if (cp < 0x800)
        return put(k, 0xC0 | (unsigned)(cp >> 6)) && put(k, 0x80 | (unsigned)(cp & 0x3F));
    if (cp < 0x10000)
        return put(k, 0xE0 | (unsigned)(cp >> 12)) && put(k, 0x80 | (unsigned)((cp >> 6) & 0x3F)) &&
               put(k, 0x80 | (unsigned)(cp & 0x3F));
    return put(k, 0xF0 | (unsigned)(cp >> 18)) && put(k, 0x80 | (unsigned)((cp >> 12) & 0x3F)) &&
           put(k, 0x80 | (unsigned)((cp >> 6) & 0x3F)) && put(k, 0x80 | (unsigned)(cp & 0x3F));
}

static unsigned short_escape(char c)
{
    switch (c) {
    case 'b':
        return '\b';
    case 'f':
        return '\f';
    case 'n':
        return '\n';
    case 'r':
        return '\r';
    case 't':
        return '\t';
    default:
        return (unsigned char)c; /* " \ / */
    }
}

static void unescape(const char *text, size_t len, size_t off, sink *k)
{
    size_t e = string_end(text, len, off), p = off + 1;
    while (p < e) {
        unsigned long cp = 0;
        size_t n;
        if (text[p] != '\\') {
            if (!put(k, (unsigned char)text[p]))
                return;
            p++;
            continue;
        }
        if (p + 1 >= len)
            return; /* only in text that failed the check */
        if (text[p + 1] != 'u') {
            if (!put(k, short_escape(text[p + 1])))
                return;
            p += 2;
            continue;
        }
        n = jsonscan_utf16(text + p, e - p, &cp);
        if (n == 0 || !put_utf8(k, cp))
            return; /* n == 0 only in text that failed the check */
        p += n;
    }
}

size_t jsonscan_string(const char *text, size_t len, size_t off, char *buf, size_t cap)
{
    sink k;
    memset(&k, 0, sizeof k);
    k.buf = buf;
    k.cap = cap;
    unescape(text, len, off, &k);
    if (cap > 0)
        buf[k.n < cap ? k.n : cap - 1] = '\0';
    return k.n;
}

int jsonscan_string_is(const char *text, size_t len, size_t off, const char *s)
{
    sink k;
    if (jsonscan_kind(text, off) != JS_STRING)
        return 0;
    memset(&k, 0, sizeof k);
    k.cmp = s;
    unescape(text, len, off, &k);
    return !k.differs && s[k.n] == '\0';
}

/* 1 when the key string at off equals key: byte for byte when the text has
 * no escape or NUL there, else unescaped. */
int jsonscan_key_is(const char *text, size_t len, size_t off, const char *key)
{
    size_t i = off + 1, k = 0;
    while (i < len && key[k] != '\0' && text[i] == key[k] && text[i] != '\\') {
        i++;
        k++;
    }
    if (i < len && key[k] == '\0' && text[i] == '"')
        return 1;
    if (i < len && text[i] != '\\' && text[i] != '\0')
        return 0; /* a plain byte differs (or the key ended early, or the string did) */
    return jsonscan_string_is(text, len, off, key);
}

size_t jsonscan_get(const char *text, size_t len, size_t obj, const char *key)
{
    size_t p;
    if (jsonscan_kind(text, obj) != JS_OBJECT)
        return JSONSCAN_NONE;
    p = jsonscan_ws(text, len, obj + 1);
    while (p < len && text[p] == '"') {
        size_t v = member_value(text, len, p);
        if (jsonscan_key_is(text, len, p, key))
            return v;
        p = jsonscan_ws(text, len, jsonscan_skip(text, len, v));
        if (p >= len || text[p] != ',')
            break;
        p = jsonscan_ws(text, len, p + 1);
    }
    return JSONSCAN_NONE;
}

/* ---- positions -------------------------------------------------------------- */

void jsonscan_line_col(const char *text, size_t len, size_t off, uint32_t *line, uint32_t *col)
{
    size_t i;
    uint32_t l = 1, c = 1;
    for (i = 0; i < off && i < len; i++) {
        if (text[i] == '\n') {
            l++;
            c = 1;
        } else {
            c++;
        }
    }
    *line = l;
    *col = c;
}

/* The containers open before offset off (at most len), strings skipped;
 * *in_string: whether off lies inside a string. */
static long open_before(const char *text, size_t len, size_t off, int *in_string)
{
    size_t i;
    long depth = 0;
    *in_string = 0;
    for (i = 0; i < off && i < len; i++) {
        char c = text[i];
        if (*in_string) {
            if (c == '\\')
                i++;
            else if (c == '"')
                *in_string = 0;
        } else if (c == '"') {
            *in_string = 1;
        } else if (c == '{' || c == '[') {
            depth++;
        } else if (c == ']' || c == '}') {
            depth--;
        }
    }
    return depth;
}

int jsonscan_truncated(const char *text, size_t len)
{
    int in_string;
    long depth = open_before(text, len, len, &in_string);
    return in_string || depth > 0;
}

/* 1 when the text at 'at' starts with word w. */
static int starts(const char *text, size_t len, size_t at, const char *w)
{
    size_t n = strlen(w);
    return at + n <= len && memcmp(text + at, w, n) == 0;
}

/* Why the text is malformed at 'at' (before it: white space skipped back),
 * for the common slips of text written by hand or by other tools: "" when
 * none of them. */
static const char *slip_at(const char *text, size_t len, size_t at)
{
    size_t b = at;
    while (b > 0 && (unsigned char)text[b - 1] <= 32)
        b--;
    if (starts(text, len, at, "NaN") || starts(text, len, at, "nan") || starts(text, len, at, "Infinity") ||
        starts(text, len, at, "-Infinity") || starts(text, len, at, "inf") || starts(text, len, at, "-inf"))
        return ": JSON has no NaN or Infinity (write null, or leave the value out)";
    if (text[at] == '\'' || (at > 0 && text[at - 1] == '\'')) /* a key fails one byte after its start */
        return ": JSON strings take double quotes";
    if ((text[at] == ']' || text[at] == '}') && b > 0 && text[b - 1] == ',')
        return ": a comma before the closing bracket";
    if (starts(text, len, at, "//") || starts(text, len, at, "/*") ||
        (at > 0 && text[at - 1] == '/' && (text[at] == '/' || text[at] == '*')))
        return ": JSON has no comments";
    return "";
}

size_t jsonscan_error_at(const char *text, size_t len, size_t at, const char **tail)
{
    int truncated = jsonscan_truncated(text, len), empty = 1;
    size_t bom = len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0, k; /* a UTF-8 byte-order mark */
    for (k = bom; k < len && empty; k++)
        empty = text[k] == ' ' || text[k] == '\t' || text[k] == '\r' || text[k] == '\n';
    if (at > len || (truncated && at + 1 >= len) || empty)
        at = len;
    *tail = at < len ? slip_at(text, len, at)
            : empty ? (len == 0      ? ": the file is empty"
                       : len == bom  ? ": the text holds only a UTF-8 byte-order mark"
                       : bom         ? ": the text holds only a UTF-8 byte-order mark and white space"
                                     : ": the text holds only white space")
            : truncated ? ": the text ends early" : ": unexpected end";
    return at;
}

long jsonscan_depth_at(const char *text, size_t len, size_t off)
{
    int in_string;
    return open_before(text, len, off, &in_string);
}
