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

/* Parses text (NUL-terminated). Each row needs at least 'need' numbers.
 * Without fill (vis), numbers past 'cols' are ignored and missing ones up
 * to 'cols' are an error. With fill (illum, meter), missing ones take
 * fill[k], but the numbers after the third are given whole (a normal or a
 * facing) and none past 'cols' (with cols 6, a row of 4, 5 or more than 6
 * numbers is an error; with cols 5, of 4 or more than 5). Returns 0, or
 * -1 with
 * "NAME:LINE: why" in err. */
int points_parse(const char *name, const char *text, int need, int cols, const double *fill,
                 points *out, char *err, size_t errlen);
/* Text inputs are read whole or refused: a NUL byte, a line longer than
 * POINTS_MAX_LINE bytes or a last line without its newline is an error
 * "NAME:LINE: why" (never the silent end of the file). Standard input is
 * read up to POINTS_MAX_STDIN bytes. */
#define POINTS_MAX_LINE 4096
#define POINTS_MAX_STDIN (1 << 30)
int points_check_text(const char *name, const char *text, size_t len, char *err, size_t errlen);
/* Reads, checks and parses a file ("-" is standard input; a FIFO, a device
 * or a directory is refused). */
int points_read(const char *path, int need, int cols, const double *fill, points *out,
                char *err, size_t errlen);
void points_free(points *p);

/* A text input read whole: "-" is standard input (up to POINTS_MAX_STDIN
 * bytes), else the file (port_read_text: a FIFO, a device or a directory
 * is refused). NULL with "NAME: why" in err. Free with free(). */
char *cli_read_input(const char *path, size_t *len /* OUT, may be NULL */, char *err, size_t errlen);
/* The name messages give an input: "<stdin>" for "-". */
const char *cli_input_name(const char *path);

#endif
