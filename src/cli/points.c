#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "points.h"
#include "port.h"

static int sep(char c)
{
    return c == ' ' || c == '\t' || c == ',' || c == '\r';
}

static int grow(points *p, size_t *cap)
{
    size_t ncap = *cap ? *cap * 2 : 256;
    double *v = realloc(p->v, ncap * (size_t)p->cols * sizeof *v);
    size_t *l;
    if (!v)
        return -1;
    p->v = v;
    l = realloc(p->line, ncap * sizeof *l);
    if (!l)
        return -1;
    p->line = l;
    *cap = ncap;
    return 0;
}

/* Parses one line [s, end) into row; returns the count of numbers or -1. */
static int parse_row(const char *s, const char *end, double *row, int cols, const char **bad)
{
    int k = 0;
    while (s < end) {
        char *stop;
        double v;
        while (s < end && sep(*s))
            s++;
        if (s >= end)
            break;
        errno = 0;
        v = strtod(s, &stop);
        if (stop == s || stop > end || (stop < end && !sep(*stop)) || !isfinite(v)) {
            *bad = s;
            return -1;
        }
        if (k < cols)
            row[k] = v;
        k++;
        s = stop;
    }
    return k;
}

/* "# crs: NAME" (spaces free, "crs:" in any case) copies NAME into crs;
 * 1 when the line is one. */
static int crs_line(const char *t, const char *end, char *crs, size_t len)
{
    size_t n;
    for (t++; t < end && (*t == ' ' || *t == '\t'); t++)
        ;
    if (end - t < 4 || tolower((unsigned char)t[0]) != 'c' || tolower((unsigned char)t[1]) != 'r' ||
        tolower((unsigned char)t[2]) != 's' || t[3] != ':')
        return 0;
    for (t += 4; t < end && (*t == ' ' || *t == '\t'); t++)
        ;
    for (n = (size_t)(end - t); n > 0 && (t[n - 1] == ' ' || t[n - 1] == '\r' || t[n - 1] == '\t'); n--)
        ;
    if (n >= len)
        n = len - 1;
    memcpy(crs, t, n);
    crs[n] = '\0';
    return 1;
}

/* A '# crs:' line holds for the whole file, so it comes before the first
 * point, once (a later one silently moved the points above it; two
 * different ones were taken without a word). 0, or -1 with the message. */
static int crs_place(const char *name, size_t lineno, const points *out, const char *crs, char *err, size_t errlen)
{
    if (out->n > 0) {
        snprintf(err, errlen, "%s:%zu: a '# crs:' line after the first point: it names the whole file's "
                 "coordinates, so it comes before the points", name, lineno);
        return -1;
    }
    if (out->crs[0] && strcmp(out->crs, crs) != 0) {
        snprintf(err, errlen, "%s:%zu: a second '# crs:' line (%.60s) differs from the first (%.60s)", name, lineno,
                 crs, out->crs);
        return -1;
    }
    return 0;
}

int points_parse(const char *name, const char *text, int need, int cols, const double *fill,
                 points *out, char *err, size_t errlen)
{
    size_t cap = 0, lineno = 0;
    const char *s = text;
    memset(out, 0, sizeof *out);
    out->cols = cols;
    while (*s) {
        const char *end = strchr(s, '\n'), *t, *bad = NULL;
        double *row;
        int k, j;
        if (!end)
            end = s + strlen(s);
        lineno++;
        for (t = s; t < end && sep(*t); t++)
            ;
        if (t < end && *t == '#') {
            char crs[sizeof out->crs];
            if (crs_line(t, end, crs, sizeof crs)) {
                if (crs_place(name, lineno, out, crs, err, errlen) != 0) {
                    points_free(out);
                    return -1;
                }
                memcpy(out->crs, crs, sizeof crs);
            }
        }
        if (t == end || *t == '#') {
            s = *end ? end + 1 : end;
            continue;
        }
        if (out->n == cap && grow(out, &cap) != 0) {
            snprintf(err, errlen, "%s: out of memory", name);
            points_free(out);
            return -1;
        }
        row = out->v + out->n * (size_t)cols;
        k = parse_row(t, end, row, cols, &bad);
        if (fill && (k > cols || (k > 3 && k < cols))) { /* a normal or a facing is given whole, nothing after */
            snprintf(err, errlen, "%s:%zu: expected 2, 3 or %d numbers ('x y', 'x y z' or %s), found %d", name,
                     lineno, cols, cols == 6 ? "'x y z nx ny nz'" : "'x y z ux uy'", k);
            points_free(out);
            return -1;
        }
        if (k < 0 || k < need || (k < cols && !fill)) {
            int len = 0;
            if (bad)
                while (bad + len < end && !sep(bad[len]) && len < 30)
                    len++;
            if (k < 0)
                snprintf(err, errlen, "%s:%zu: '%.*s' is not a finite number", name, lineno, len, bad);
            else
                snprintf(err, errlen, "%s:%zu: expected %d numbers, found %d", name, lineno,
                         fill ? need : cols, k);
            points_free(out);
            return -1;
        }
        for (j = k; j < cols; j++)
            row[j] = fill[j];
        out->line[out->n++] = lineno;
        s = *end ? end + 1 : end;
    }
    return 0;
}

int points_check_text(const char *name, const char *text, size_t len, char *err, size_t errlen)
{
    size_t i, line = 1, start = 0;
    for (i = 0; i < len; i++) {
        if (text[i] == '\0') {
            snprintf(err, errlen, "%s:%zu: a NUL byte at byte %zu (not a text file?)", name, line, i);
            return -1;
        }
        if (i - start >= POINTS_MAX_LINE) {
            snprintf(err, errlen, "%s:%zu: line longer than %d bytes", name, line, POINTS_MAX_LINE);
            return -1;
        }
        if (text[i] == '\n') {
            line++;
            start = i + 1;
        }
    }
    if (len > 0 && text[len - 1] != '\n') {
        snprintf(err, errlen, "%s:%zu: the last line does not end with a newline (truncated file?)", name, line);
        return -1;
    }
    return 0;
}

static char *read_stdin(size_t *lenp, char *err, size_t errlen)
{
    size_t len = 0, cap = 1 << 16, got;
    char *buf = malloc(cap);
    while (buf && (got = fread(buf + len, 1, cap - len - 1, stdin)) > 0) {
        len += got;
        if (len + 1 == cap && cap >= POINTS_MAX_STDIN) {
            snprintf(err, errlen, "standard input: more than %d MiB", POINTS_MAX_STDIN >> 20);
            free(buf);
            return NULL;
        }
        if (len + 1 == cap) {
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = nb;
            cap *= 2;
        }
    }
    if (!buf) {
        snprintf(err, errlen, "standard input: out of memory");
        return NULL;
    }
    buf[len] = '\0';
    *lenp = len;
    return buf;
}

char *cli_read_input(const char *path, size_t *lenp, char *err, size_t errlen)
{
    char why[256];
    char *text;
    size_t len = 0;
    if (strcmp(path, "-") == 0)
        text = read_stdin(&len, err, errlen);
    else if ((text = port_read_text(path, &len, why, sizeof why)) == NULL)
        snprintf(err, errlen, "%s: %s", path, why);
    if (text && lenp)
        *lenp = len;
    return text;
}

const char *cli_input_name(const char *path)
{
    return strcmp(path, "-") == 0 ? "<stdin>" : path;
}

int points_read(const char *path, int need, int cols, const double *fill, points *out,
                char *err, size_t errlen)
{
    char *text;
    int rc;
    size_t len = 0;
    const char *name = cli_input_name(path);
    memset(out, 0, sizeof *out);
    text = cli_read_input(path, &len, err, errlen);
    if (!text)
        return -1;
    if (points_check_text(name, text, len, err, errlen) != 0) {
        free(text);
        return -1;
    }
    rc = points_parse(name, text, need, cols, fill, out, err, errlen);
    free(text);
    return rc;
}

void points_free(points *p)
{
    free(p->v);
    free(p->line);
    p->v = NULL;
    p->line = NULL;
    p->n = 0;
}
