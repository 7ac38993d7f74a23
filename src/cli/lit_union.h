/* The union of a lamp's lit ground rings into polygons with holes
 * (polarlux lit): see lit_union.c. */
#ifndef PLX_CLI_LIT_UNION_H
#define PLX_CLI_LIT_UNION_H

#include <stddef.h>
#include <stdint.h>

typedef struct lu_ring {
    double *xy;      /* n vertices, x,y pairs, no closing vertex */
    size_t n;
    double area;     /* signed: > 0 outer (counter-clockwise), < 0 hole */
    long outer;      /* a hole's outer ring (index), -1 for outer rings */
} lu_ring;

typedef struct lit_union {
    lu_ring *rings;
    size_t nrings;
} lit_union;

/* rings[k]: counts[k] vertices (x,y, counter-clockwise, interior-disjoint).
 * 0, or -1 when out of memory. */
int lit_union_build(const double *const *rings, const uint32_t *counts, size_t nrings, lit_union *out);
void lit_union_free(lit_union *u);

#endif
