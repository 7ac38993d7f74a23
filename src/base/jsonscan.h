/* jsonscan: finds where each element of the top-level "features" array starts
 * in the raw text, so messages can give a line number (cJSON keeps none). */
#ifndef PLX_JSONSCAN_H
#define PLX_JSONSCAN_H

#include <stddef.h>
#include <stdint.h>

/* Line (1-based) and column (1-based) of byte offset 'off'. */
void jsonscan_line_col(const char *text, size_t len, size_t off, uint32_t *line, uint32_t *col);

/* Fills line[k] and col[k] with where the k-th element of the top-level
 * object's "features" array starts, for k < n (0 where not found). Text must
 * be valid JSON. */
void jsonscan_feature_lines(const char *text, size_t len, uint32_t *line, uint32_t *col, uint32_t n);

/* 1 when the text ends inside a string or with brackets still open. */
int jsonscan_truncated(const char *text, size_t len);

#endif
