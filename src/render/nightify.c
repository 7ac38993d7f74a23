/* nightify: histogram matching of RGB8 images (munoz2013 §3.1; see
 * nightify.h). */
#include <stddef.h>
#include <stdint.h>

#include "render/nightify.h"

int photon_hist_match(const uint8_t *src, size_t npx, const uint8_t *ref, size_t nref,
                      double dark_threshold, uint8_t *out)
{
    double hs[3][256], hr[3][256], ns = (double)npx, nr = 0.0;
    uint8_t map[3][256];
    size_t i;
    int c, v, use_all = 0;
    if (!src || !ref || !out || npx == 0 || nref == 0)
        return -1;
    for (c = 0; c < 3; c++)
        for (v = 0; v < 256; v++)
            hs[c][v] = hr[c][v] = 0.0;
    for (i = 0; i < npx; i++)
        for (c = 0; c < 3; c++)
            hs[c][src[3 * i + (size_t)c]] += 1.0;
    for (;;) {
        for (i = 0; i < nref; i++) {
            const uint8_t *p = ref + 3 * i;
            double lum = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            if (!use_all && lum < dark_threshold)
                continue;
            for (c = 0; c < 3; c++)
                hr[c][p[c]] += 1.0;
            nr += 1.0;
        }
        if (nr > 0.0 || use_all)
            break;
        use_all = 1; /* every reference pixel is dark: use them all */
    }
    for (c = 0; c < 3; c++) {
        double cs = 0.0, cr = hr[c][0];
        int w = 0;
        for (v = 0; v < 256; v++) {
            cs += hs[c][v];
            /* smallest w with cdf_ref(w) >= cdf_src(v), compared as
             * count_ref * n_src >= count_src * n_ref (exact while the products
             * stay below 2^53) */
            while (w < 255 && cr * ns < cs * nr) {
                w++;
                cr += hr[c][w];
            }
            map[c][v] = (uint8_t)w;
        }
    }
    for (i = 0; i < npx; i++)
        for (c = 0; c < 3; c++)
            out[3 * i + (size_t)c] = map[c][src[3 * i + (size_t)c]];
    return 0;
}
