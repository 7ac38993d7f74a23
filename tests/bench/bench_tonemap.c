/* bench_tonemap: a frame's tone mapping, the table of float thresholds
 * (src/render/tonemap.c: tonemap_table_set once a frame, then
 * tonemap_apply) against the direct computation of each value
 * (tonemap_value: exposure, tone curve, search of the thresholds), the
 * baseline, in the same process.
 *
 * Work: frames of 640x480 linear RGB (921,600 values) like a night street
 * view: a fifth zero (sky), the rest log-uniform over 1e-6 .. 1e2; each
 * frame its own exposure (automatic exposure changes it every frame),
 * through the tone curve. Both give the same bytes (checked, printed). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/tonemap.h"

#define W 640
#define H 480
#define N ((size_t)W * H * 3)
#define FRAMES 40

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

/* The method before the table (a baseline): the exposure and the curve
 * for each value, a hint from the bits of the result's float, then exact
 * compares against the thresholds. */
static void hinted(const double *thr, const uint8_t *hint, const float *lin, size_t n, double ex, uint8_t *out)
{
    size_t p;
    for (p = 0; p < n; p++) {
        double v = (double)lin[p] * ex;
        union { uint32_t u; float f; } cv;
        int k;
        v = v > 0.0 ? v * (1.0 + v / 16.0) / (1.0 + v) : 0.0;
        cv.f = (float)v;
        if (!(v > 0.0)) {
            out[p] = 0;
            continue;
        }
        k = hint[cv.u >> 16];
        while (k > 0 && v < thr[k - 1])
            k--;
        while (k < TONEMAP_LEVELS && v >= thr[k])
            k++;
        out[p] = (uint8_t)k;
    }
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int main(void)
{
    static tonemap_table t;
    double thr[TONEMAP_LEVELS], direct[FRAMES], before[FRAMES], table[FRAMES];
    float *lin = malloc(N * sizeof *lin);
    uint8_t *a = malloc(N), *b = malloc(N), *c = malloc(N), *hint = malloc(65536);
    uint64_t z = 0x9e3779b97f4a7c15ull;
    size_t p, differ = 0;
    int f;
    if (!lin || !a || !b || !c || !hint)
        return 1;
    tonemap_thresholds(thr);
    for (p = 0; p < 65536; p++) {
        union { uint32_t u; float f; } cv;
        cv.u = (uint32_t)p << 16;
        hint[p] = tonemap_srgb8(thr, (double)cv.f);
    }
    for (p = 0; p < N; p++) {
        z = z * 6364136223846793005ull + 1442695040888963407ull;
        lin[p] = (z >> 61) == 0 ? 0.0f : (float)pow(10.0, -6.0 + 8.0 * (double)(z >> 11) / 9007199254740992.0);
    }
    memset(&t, 0, sizeof t);
    for (f = 0; f < FRAMES; f++) {
        double ex = 0.5 * pow(1.07, f), t0 = now_ms();
        for (p = 0; p < N; p++)
            a[p] = tonemap_value(thr, lin[p], ex, 1);
        direct[f] = now_ms() - t0;
        t0 = now_ms();
        hinted(thr, hint, lin, N, ex, c);
        before[f] = now_ms() - t0;
        t0 = now_ms();
        tonemap_table_set(&t, thr, ex, 1);
        tonemap_apply(&t, thr, lin, 0, N, b);
        table[f] = now_ms() - t0;
        for (p = 0; p < N; p++)
            differ += (a[p] != b[p]) + (a[p] != c[p]);
    }
    qsort(direct, FRAMES, sizeof direct[0], cmp_d);
    qsort(table, FRAMES, sizeof table[0], cmp_d);
    qsort(before, FRAMES, sizeof before[0], cmp_d);
    printf("bench_tonemap: %d frames of %dx%d (%zu values), each its own exposure, tone curve on\n", FRAMES, W,
           H, N);
    printf("  direct (reference): median %.2f ms a frame (%.2f ns a value)\n", direct[FRAMES / 2],
           direct[FRAMES / 2] * 1e6 / (double)N);
    printf("  before (baseline):  median %.2f ms a frame (%.2f ns a value): curve, hint, compares\n",
           before[FRAMES / 2], before[FRAMES / 2] * 1e6 / (double)N);
    printf("  table:              median %.2f ms a frame (%.2f ns a value), the table included\n",
           table[FRAMES / 2], table[FRAMES / 2] * 1e6 / (double)N);
    printf("  ratio before / table: %.2f; bytes that differ from the reference: %zu of %zu\n",
           before[FRAMES / 2] / table[FRAMES / 2], differ, 2 * N * FRAMES);
    free(lin);
    free(a);
    free(b);
    free(c);
    free(hint);
    return differ != 0;
}
