/* What crossing footprints cost the construction of the polar diagrams.
 *
 * A city of n x n buildings on 10 m cells, every one turned by up to
 * 1e-3 rad. Three versions of it, built in the same process:
 *   - apart: each building shrunk to 9.95 m, no two footprints meet (the
 *     baseline: no cut at all);
 *   - overlapping: each grown by 0..2 cm over its neighbours, as in real
 *     map data at its worst: every wall crosses its neighbours' walls, so
 *     every crossing point is rounded and the pieces are searched again
 *     (src/polar/walls.c, settle_pieces) until they meet only at their ends;
 *   - some overlapping: one building in ten grown so, the others apart.
 * Printed per version: construction time (best of 3, with and without the
 * search DAGs), wall pieces, crossing points, rounds of the contact search
 * after the first cut, and the time per wall piece against the baseline.
 *
 * Usage: bench_polar_cross [N]   (default 100: 10,000 buildings)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "polarlux.h"
#include "port.h"
#include "base/arena.h"
#include "base/scene.h"
#include "polar/polar.h"
#include "ref_scene.h"

#define BUDGET ((size_t)2 << 30)

static uint32_t rs;

static double urand(void)
{
    rs = rs * 1103515245u + 12345u;
    return ((rs >> 8) & 0xffffff) / 16777216.0;
}

/* kind 0 apart, 1 overlapping, 2 one in ten overlapping */
static void city(scene *s, int n, int kind)
{
    int i, j, q;
    rs = 5;
    for (i = 0; i < n; i++) {
        for (j = 0; j < n; j++) {
            double a = (urand() - 0.5) * 2e-3, grow = 0.02 * urand(), sel = urand();
            double o = kind == 1 || (kind == 2 && sel < 0.1) ? grow : -0.05;
            double c = cos(a), sn = sin(a), xy[8], w = 10.0 + o;
            double ox[4] = { 0, w, w, 0 }, oy[4] = { 0, 0, w, w };
            uint32_t k = 4;
            for (q = 0; q < 4; q++) {
                xy[2 * q] = i * 10.0 + c * ox[q] - sn * oy[q];
                xy[2 * q + 1] = j * 10.0 + sn * ox[q] + c * oy[q];
            }
            if (ref_scene_add_building(s, xy, &k, 1, 10, 0) < 0) {
                fprintf(stderr, "bench_polar_cross: out of memory\n");
                exit(1);
            }
        }
    }
    ref_scene_finish(s);
}

/* Best of 3 of polar_build_flags(flags), in ms; *pd the last build. */
static double build_ms(void *mem, const scene *s, int flags, polar **pd, arena *a)
{
    double best = 1e300;
    int r;
    for (r = 0; r < 3; r++) {
        unsigned long long t0;
        double t;
        plx_status st;
        arena_init(a, mem, BUDGET);
        t0 = port_now_ns();
        st = polar_build_flags(a, s, flags, pd);
        t = (double)(port_now_ns() - t0) / 1e6;
        if (st != PLX_OK) {
            fprintf(stderr, "bench_polar_cross: polar_build: %s\n", plx_strerror(st));
            exit(1);
        }
        best = t < best ? t : best;
    }
    return best;
}

int main(int argc, char **argv)
{
    static const char *name[3] = { "apart", "overlapping", "some overlapping" };
    int n = argc > 1 ? atoi(argv[1]) : 100, kind;
    void *mem = malloc(BUDGET);
    double base = 0;
    if (!mem || n < 1) {
        fprintf(stderr, "bench_polar_cross: cannot allocate %zu bytes\n", (size_t)BUDGET);
        return 1;
    }
    printf("polar construction with crossing footprints: %d x %d buildings turned by up to "
           "1e-3 rad; one thread, best of 3\n", n, n);
    for (kind = 0; kind < 3; kind++) {
        scene s;
        arena a;
        polar *pd;
        double t_nodag, t, per;
        ref_scene_init(&s);
        city(&s, n, kind);
        t_nodag = build_ms(mem, &s, POLAR_BUILD_NO_DAG, &pd, &a);
        t = build_ms(mem, &s, 0, &pd, &a);
        per = 1e6 * t / pd->nwall;
        if (kind == 0)
            base = per;
        printf("  %-17s %7.1f ms (without DAGs %7.1f ms)  %7u wall pieces, %6u crossing points, "
               "%u rounds after the first cut;  %5.0f ns per piece = %.2fx apart\n",
               name[kind], t, t_nodag, pd->nwall, pd->npts - 4 - s.npts, pd->wall_rounds, per,
               per / base);
        ref_scene_free(&s);
    }
    free(mem);
    return 0;
}
