/* The polar build's memory per footprint vertex on growing rings (one
 * building, a star polygon of n vertices): the arena's high-water mark
 * during polar_build beyond what the diagrams keep (its scratch, and the
 * trapezoid slots it takes from the low end for a while) over n stays
 * under POLAR_SCRATCH_PER_VERTEX (polar.h, README "Polar build scratch")
 * plus a constant. Rings of 1,000 to 100,000 vertices (PLX_TEST_QUICK: to
 * 10,000); the 10^6-vertex ring of the issue is printed with
 * PLX_POLAR_RING_BIG=1. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "base/engine.h"
#include "base/arena.h"
#include "polar/polar.h"
#include "ref_scene.h"

#define PI 3.14159265358979323846

static int quick_mode(void)
{
    const char *v = getenv("PLX_TEST_QUICK");
    return v && v[0] && v[0] != '0';
}

/* Builds the diagrams of a star of n vertices in a block of 'bytes';
 * returns the status and the scratch and kept bytes. */
static plx_status ring_build(uint32_t n, size_t bytes, size_t *scratch, size_t *kept)
{
    scene s;
    arena a;
    void *mem = malloc(bytes);
    double *xy = malloc(sizeof(double) * 2 * n);
    polar *pd;
    plx_status st;
    uint32_t i;
    assert_non_null(mem);
    assert_non_null(xy);
    for (i = 0; i < n; i++) {
        double t = 2.0 * PI * i / n, r = i % 2 ? 800.0 : 1000.0;
        xy[2 * i] = r * cos(t);
        xy[2 * i + 1] = r * sin(t);
    }
    ref_scene_init(&s);
    assert_true(ref_scene_add_building(&s, xy, &n, 1, 10.0, 0.0) >= 0);
    ref_scene_finish(&s);
    arena_init(&a, mem, bytes);
    st = polar_build(&a, &s, &pd);
    /* the block's high-water mark beyond what is kept: the scratch and the
     * trapezoid slots the build takes in the low end for a while */
    *kept = a.used[PLX_PART_POLAR];
    *scratch = a.peak_total - *kept;
    assert_true(a.peak[PLX_PART_SCRATCH] <= *scratch);
    ref_scene_free(&s);
    free(xy);
    free(mem);
    return st;
}

static void test_scratch_per_vertex(void **state)
{
    uint32_t n, nmax = quick_mode() ? 10000 : 100000;
    (void)state;
    for (n = 1000; n <= nmax; n *= 10) {
        size_t scratch, kept;
        assert_int_equal(ring_build(n, (size_t)1 << 30, &scratch, &kept), PLX_OK);
        printf("ring of %u vertices: scratch %zu bytes (%.1f a vertex), kept %zu (%.1f a vertex)\n", n, scratch,
               (double)scratch / n, kept, (double)kept / n);
        assert_true(scratch <= (size_t)POLAR_SCRATCH_PER_VERTEX * n + POLAR_SCRATCH_FIXED);
    }
}

typedef struct text {
    char *p;
    size_t n, cap;
} text;

static int put(void *ctx, const char *data, size_t len)
{
    text *t = ctx;
    if (t->n + len + 1 > t->cap) {
        t->cap = 2 * (t->n + len + 1);
        t->p = realloc(t->p, t->cap);
        assert_non_null(t->p);
    }
    memcpy(t->p + t->n, data, len);
    t->n += len;
    return 0;
}

/* The same bound on generated cities (footprints touching their
 * neighbours: walls cut at contacts), measured through the engine: the
 * scratch high-water mark of plx_polar_build after the load. */
static void test_scratch_cities(void **state)
{
    static const char *style[] = { "eixample", "oldtown", "grid" };
    int k, side = quick_mode() ? 8 : 24;
    (void)state;
    for (k = 0; k < 3; k++) {
        text t = { NULL, 0, 0 };
        plx_engine *e;
        plx_scene_info si;
        size_t scratch, base, kept0;
        assert_int_equal(plx_gen_city(style[k], side, side, 1, put, &t), PLX_OK);
        assert_int_equal(plx_engine_new((size_t)512 << 20, NULL, &e), PLX_OK);
        assert_int_equal(plx_load_geojson(e, t.p, t.n, style[k]), PLX_OK);
        assert_int_equal(plx_scene_info_get(e, &si), PLX_OK);
        base = e->mem.lo + e->mem.hi;
        kept0 = e->mem.used[PLX_PART_POLAR];
        e->mem.peak_total = base;
        assert_int_equal(plx_polar_build(e), PLX_OK);
        /* the high-water mark beyond what was in use before and what the
         * diagrams keep (the visibility buffers come after the build) */
        scratch = e->mem.peak_total - base - (e->mem.used[PLX_PART_POLAR] - kept0);
        printf("gen %s %d %d (%u vertices): scratch %zu bytes (%.1f a vertex)\n", style[k], side, side,
               si.vertices, scratch, (double)scratch / si.vertices);
        assert_true(scratch <= (size_t)POLAR_SCRATCH_PER_VERTEX * si.vertices + POLAR_SCRATCH_FIXED);
        plx_engine_free(e);
        free(t.p);
    }
}

/* The block the issue asks for: a 10^6-vertex ring in 256 MiB. Not met:
 * it needs about 405 MB (202 of them kept), so the ring is built in a
 * 400 MiB block (asserted) and tried in 256 MiB (printed); see README
 * "Polar build scratch". */
static void test_big_ring(void **state)
{
    const char *v = getenv("PLX_POLAR_RING_BIG");
    size_t scratch, kept;
    plx_status st;
    (void)state;
    if (!v || v[0] != '1') {
        printf("10^6-vertex ring: PLX_POLAR_RING_BIG=1 runs it\n");
        return;
    }
    st = ring_build(1000000, (size_t)400 << 20, &scratch, &kept);
    printf("10^6-vertex ring in 400 MiB: status %d, scratch %zu bytes, kept %zu, both %zu\n", (int)st,
           scratch, kept, scratch + kept);
    assert_int_equal(st, PLX_OK);
    assert_true(scratch <= (size_t)POLAR_SCRATCH_PER_VERTEX * 1000000 + POLAR_SCRATCH_FIXED);
    st = ring_build(1000000, (size_t)256 << 20, &scratch, &kept);
    printf("10^6-vertex ring in 256 MiB: status %d (%s)\n", (int)st, st == PLX_OK ? "built" : "does not fit");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scratch_per_vertex),
        cmocka_unit_test(test_scratch_cities),
        cmocka_unit_test(test_big_ring),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
