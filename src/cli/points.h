/* Points files: one point per line, numbers separated by spaces, tabs or
 * commas; blank lines and lines starting with '#' are skipped. */
#ifndef PLX_CLI_POINTS_H
#define PLX_CLI_POINTS_H

#include <stddef.h>

typedef struct points {
    double *v;        /* n rows of 'cols' numbers */
    size_t n;
    int cols;
    size_t *line;     /* source line of each row */
    char crs[64];     /* a '# crs: NAME' line's NAME ("" if none) */
} points;

/* Parses text (NUL-terminated). Each row needs at least 'need' numbers;
 * numbers past 'cols' are ignored, missing ones up to 'cols' are an error
 * unless fill is given (then they take fill[k]). Returns 0, or -1 with
 * "NAME:LINE: why" in err. */
int points_parse(const char *name, const char *text, int need, int cols, const double *fill,
                 points *out, char *err, size_t errlen);
/* Reads and parses a file ("-" is standard input). */
int points_read(const char *path, int need, int cols, const double *fill, points *out,
                char *err, size_t errlen);
void points_free(points *p);

#endif
