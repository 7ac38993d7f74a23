/* msort: one stable merge sort for the core's arrays of records.
 *
 * MSORT_DEFINE(name, type, ctx_type, before) defines
 *     static void name(type *v, type *tmp, size_t n, ctx_type ctx)
 * which sorts v[0 .. n-1] so that no element is followed by one that is
 * before(const type *a, const type *b, ctx_type ctx) it (a strictly before
 * b); equal elements keep their order (stable), so the result does not
 * depend on how the work is split. tmp holds n elements. Insertion sort in
 * runs of 16, then bottom-up merges: O(n log n), no recursion, no heap.
 * A macro rather than a function taking a comparison pointer so that the
 * comparison and the element copies inline (the sorts sit on the polar and
 * block construction paths). */
#ifndef PLX_MSORT_H
#define PLX_MSORT_H

#include <stddef.h>
#include <string.h>

#define MSORT_DEFINE(name, type, ctx_type, before)                                      \
    static void name(type *v, type *tmp, size_t n, ctx_type ctx)                       \
    {                                                                                  \
        type *src = v, *dst = tmp, *sw;                                                \
        size_t w, i, j;                                                                \
        for (i = 0; i < n; i += 16) {                                                  \
            size_t e = i + 16 < n ? i + 16 : n;                                        \
            for (j = i + 1; j < e; j++) {                                              \
                type t = v[j];                                                         \
                size_t k = j;                                                          \
                for (; k > i && before(&t, &v[k - 1], ctx); k--)                       \
                    v[k] = v[k - 1];                                                   \
                v[k] = t;                                                              \
            }                                                                          \
        }                                                                              \
        for (w = 16; w < n; w *= 2) {                                                  \
            for (i = 0; i < n; i += 2 * w) {                                           \
                size_t a = i, am = i + w < n ? i + w : n, b = am;                      \
                size_t bm = i + 2 * w < n ? i + 2 * w : n, o = i;                      \
                while (a < am && b < bm)                                               \
                    dst[o++] = before(&src[b], &src[a], ctx) ? src[b++] : src[a++];    \
                while (a < am)                                                         \
                    dst[o++] = src[a++];                                               \
                while (b < bm)                                                         \
                    dst[o++] = src[b++];                                               \
            }                                                                          \
            sw = src;                                                                  \
            src = dst;                                                                 \
            dst = sw;                                                                  \
        }                                                                              \
        if (src != v)                                                                  \
            memcpy(v, src, n * sizeof(type));                                          \
    }

#endif
