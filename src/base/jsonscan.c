#include "base/jsonscan.h"
#include <string.h>

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

typedef struct scan {
    const char *t;
    size_t len, i;
    size_t line_start;
    uint32_t line;
} scan;

static void advance(scan *s)
{
    if (s->t[s->i] == '\n') {
        s->line++;
        s->line_start = s->i + 1;
    }
    s->i++;
}

/* Skips a string starting at its opening quote; reports whether it equals key. */
static int skip_string(scan *s, const char *key)
{
    size_t start = s->i + 1, end;
    advance(s);
    while (s->i < s->len && s->t[s->i] != '"') {
        if (s->t[s->i] == '\\')
            advance(s);
        if (s->i < s->len)
            advance(s);
    }
    end = s->i;
    if (s->i < s->len)
        advance(s);
    return key && end - start == strlen(key) && memcmp(s->t + start, key, end - start) == 0;
}

void jsonscan_feature_lines(const char *text, size_t len, uint32_t *line, uint32_t *col, uint32_t n)
{
    scan s;
    int depth = 0, feat_depth = -1, key_is_features = 0, expect_value = 0;
    uint32_t k = 0;
    memset(line, 0, sizeof *line * n);
    memset(col, 0, sizeof *col * n);
    s.t = text;
    s.len = len;
    s.i = 0;
    s.line = 1;
    s.line_start = 0;
    while (s.i < s.len) {
        char c = text[s.i];
        if (feat_depth >= 0 && depth == feat_depth && c != ' ' && c != '\t' &&
            c != '\r' && c != '\n' && c != ',' && c != ']' && expect_value) {
            if (k < n) {
                line[k] = s.line;
                col[k] = (uint32_t)(s.i - s.line_start + 1);
            }
            k++;
            expect_value = 0;
        }
        if (c == '"') {
            int is_key = skip_string(&s, "features");
            if (depth == 1 && feat_depth < 0)
                key_is_features = is_key;
            continue;
        }
        if (c == '{' || c == '[') {
            if (c == '[' && depth == 1 && key_is_features && feat_depth < 0) {
                feat_depth = 2;
                expect_value = 1;
                depth++;
                advance(&s);
                continue;
            }
            depth++;
        } else if (c == '}' || c == ']') {
            depth--;
            if (feat_depth >= 0 && depth < feat_depth)
                return;
        } else if (c == ',' && depth == feat_depth) {
            expect_value = 1;
        } else if (c == ',' && depth == 1) {
            key_is_features = 0;
        }
        advance(&s);
    }
}

int jsonscan_truncated(const char *text, size_t len)
{
    size_t i;
    long depth = 0;
    int in_string = 0;
    for (i = 0; i < len; i++) {
        char c = text[i];
        if (in_string) {
            if (c == '\\')
                i++;
            else if (c == '"')
                in_string = 0;
        } else if (c == '"') {
            in_string = 1;
        } else if (c == '{' || c == '[') {
            depth++;
        } else if (c == '}' || c == ']') {
            depth--;
        }
    }
    return in_string || depth > 0;
}
