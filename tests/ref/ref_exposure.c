/* ref_exposure: the automatic exposure's percentile by sorting (ref_exposure.h). */
#include <math.h>
#include <stdlib.h>

#include "ref_exposure.h"

static int cmp_y(const void *a, const void *b)
{
    double x = *(const double *)a, z = *(const double *)b;
    return (x > z) - (x < z);
}

/* y's eighth of a stop from 2^-32 (written from the definition, with
 * log2). */
static long eighth(double y)
{
    return (long)floor(8.0 * (log2(y) + 32.0));
}

double ref_exposure_luminance(double *y, size_t n)
{
    size_t first = 0, m;
    long floor8;
    if (n == 0)
        return 0.0;
    qsort(y, n, sizeof *y, cmp_y);
    floor8 = eighth(y[(size_t)ceil(0.999 * (double)n) - 1]) - 12 * 8;
    while (first < n && eighth(y[first]) < floor8)
        first++;
    m = n - first;
    return y[first + (size_t)ceil(0.995 * (double)m) - 1];
}
