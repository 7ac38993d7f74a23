/* blocks: grouping buildings into blocks, overlap counting, block outlines. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <stdio.h>
#include <time.h>
#include <cmocka.h>

#include "base/arena.h"
#include "base/scene.h"
#include "scene/blocks.h"

#define TOL 0.05

/* ---- fixture: a scene filled from arrays, in an arena on a malloc'd block - */

typedef struct fixture {
    void *mem;
    arena a;
    scene s;
    uint32_t cap_pts, cap_rings, cap_bld;
    arena_mark before; /* taken after the scene arrays, before blocks_build */
} fixture;

static void fx_init(fixture *f, size_t bytes, uint32_t max_pts, uint32_t max_rings,
                    uint32_t max_bld)
{
    memset(f, 0, sizeof(*f));
    f->mem = malloc(bytes);
    assert_non_null(f->mem);
    arena_init(&f->a, f->mem, bytes);
    f->s.pts = arena_alloc(&f->a, PLX_PART_SCENE, max_pts * sizeof(vec2), 16);
    f->s.rings = arena_alloc(&f->a, PLX_PART_SCENE, max_rings * sizeof(scene_ring), 16);
    f->s.bld = arena_alloc(&f->a, PLX_PART_SCENE, max_bld * sizeof(scene_building), 16);
    assert_non_null(f->s.pts);
    assert_non_null(f->s.rings);
    assert_non_null(f->s.bld);
    f->cap_pts = max_pts;
    f->cap_rings = max_rings;
    f->cap_bld = max_bld;
}

static void fx_free(fixture *f)
{
    free(f->mem);
    f->mem = NULL;
}

static double area_of(const vec2 *p, uint32_t n)
{
    double s = 0.0;
    uint32_t i;
    for (i = 0; i < n; i++) {
        vec2 a = p[i], b = p[(i + 1) % n];
        s += a.x * b.y - b.x * a.y;
    }
    return 0.5 * s;
}

/* Starts a new building (height 10) whose outer ring is xy[0..n). */
static void fx_building(fixture *f)
{
    scene *s = &f->s;
    scene_building *b;
    assert_true(s->nbld < f->cap_bld);
    b = &s->bld[s->nbld++];
    memset(b, 0, sizeof(*b));
    b->ring_first = s->nrings;
    b->ring_count = 0;
    b->height = 10.0;
    b->albedo = 0.35;
    b->feature = s->nbld - 1;
    b->box[0] = b->box[1] = 1e300;
    b->box[2] = b->box[3] = -1e300;
}

/* Adds a ring to the last building: the first ring is made CCW, the others CW. */
static void fx_ring(fixture *f, const double *xy, uint32_t n)
{
    scene *s = &f->s;
    scene_building *b = &s->bld[s->nbld - 1];
    scene_ring *r;
    uint32_t i;
    int outer = b->ring_count == 0;
    double ar;
    assert_true(s->nrings < f->cap_rings);
    assert_true(s->npts + n <= f->cap_pts);
    r = &s->rings[s->nrings++];
    r->first = s->npts;
    r->count = n;
    for (i = 0; i < n; i++) {
        s->pts[s->npts + i].x = xy[2 * i];
        s->pts[s->npts + i].y = xy[2 * i + 1];
    }
    ar = area_of(s->pts + s->npts, n);
    if ((outer && ar < 0) || (!outer && ar > 0))
        for (i = 0; i < n / 2; i++) {
            vec2 t = s->pts[s->npts + i];
            s->pts[s->npts + i] = s->pts[s->npts + n - 1 - i];
            s->pts[s->npts + n - 1 - i] = t;
        }
    if (outer)
        for (i = 0; i < n; i++) {
            vec2 p = s->pts[s->npts + i];
            if (p.x < b->box[0]) b->box[0] = p.x;
            if (p.y < b->box[1]) b->box[1] = p.y;
            if (p.x > b->box[2]) b->box[2] = p.x;
            if (p.y > b->box[3]) b->box[3] = p.y;
        }
    s->npts += n;
    b->ring_count++;
}

static void fx_poly(fixture *f, const double *xy, uint32_t n)
{
    fx_building(f);
    fx_ring(f, xy, n);
}

static void fx_rect(fixture *f, double x0, double y0, double x1, double y1)
{
    double xy[8];
    xy[0] = x0; xy[1] = y0; xy[2] = x1; xy[3] = y0;
    xy[4] = x1; xy[5] = y1; xy[6] = x0; xy[7] = y1;
    fx_poly(f, xy, 4);
}

static void fx_hole_rect(fixture *f, double x0, double y0, double x1, double y1)
{
    double xy[8];
    xy[0] = x0; xy[1] = y0; xy[2] = x1; xy[3] = y0;
    xy[4] = x1; xy[5] = y1; xy[6] = x0; xy[7] = y1;
    fx_ring(f, xy, 4);
}

/* Runs blocks_build and checks the common invariants. */
static void fx_run_tol(fixture *f, double tol)
{
    scene *s = &f->s;
    uint32_t b, i, j, seen;
    size_t hi, used;
    f->before = arena_get_mark(&f->a);
    hi = f->a.hi;
    used = f->a.used[PLX_PART_SCRATCH];
    assert_int_equal(blocks_build(&f->a, s, tol), PLX_OK);
    /* scratch given back */
    assert_int_equal(f->a.hi, hi);
    assert_int_equal(f->a.used[PLX_PART_SCRATCH], used);
    /* every building in exactly one block, grouped, ascending */
    seen = 0;
    for (b = 0; b < s->nblocks; b++) {
        const scene_block *B = &s->blocks[b];
        assert_true(B->bld_count > 0);
        assert_int_equal(B->bld_first, seen);
        seen += B->bld_count;
        for (i = 0; i < B->bld_count; i++) {
            uint32_t k = s->block_bld[B->bld_first + i];
            assert_true(k < s->nbld);
            assert_int_equal(s->bld[k].block, b);
            if (i > 0)
                assert_true(s->block_bld[B->bld_first + i - 1] < k);
            assert_true(s->bld[k].box[0] >= B->box[0]);
            assert_true(s->bld[k].box[1] >= B->box[1]);
            assert_true(s->bld[k].box[2] <= B->box[2]);
            assert_true(s->bld[k].box[3] <= B->box[3]);
        }
        assert_true(B->ring_first + B->ring_count <= s->nblock_rings);
        for (i = 0; i < B->ring_count; i++) {
            const scene_ring *R = &s->block_rings[B->ring_first + i];
            double ar;
            assert_true(R->count >= 3);
            assert_true(R->first + R->count <= s->nblock_pts);
            ar = area_of(s->block_pts + R->first, R->count);
            if (i == 0)
                assert_true(ar > 0.0);
            /* no ring passes through a point twice */
            if (R->count <= 3000) {
                uint32_t q;
                for (j = 0; j < R->count; j++)
                    for (q = j + 1; q < R->count; q++)
                        assert_false(s->block_pts[R->first + j].x == s->block_pts[R->first + q].x &&
                                     s->block_pts[R->first + j].y == s->block_pts[R->first + q].y);
            }
            for (j = 0; j < R->count; j++) {
                vec2 p = s->block_pts[R->first + j];
                assert_true(p.x >= B->box[0] - 2 * TOL && p.x <= B->box[2] + 2 * TOL);
                assert_true(p.y >= B->box[1] - 2 * TOL && p.y <= B->box[3] + 2 * TOL);
            }
        }
    }
    assert_int_equal(seen, s->nbld);
}

static void fx_run(fixture *f)
{
    fx_run_tol(f, TOL);
}

static double ring_area(const scene *s, uint32_t b, uint32_t i)
{
    const scene_ring *R = &s->block_rings[s->blocks[b].ring_first + i];
    return area_of(s->block_pts + R->first, R->count);
}

static uint32_t ring_len(const scene *s, uint32_t b, uint32_t i)
{
    return s->block_rings[s->blocks[b].ring_first + i].count;
}

/* Signed area of all rings of block b (outer + extra outers - courtyards). */
static double block_area(const scene *s, uint32_t b)
{
    double t = 0.0;
    uint32_t i;
    for (i = 0; i < s->blocks[b].ring_count; i++)
        t += ring_area(s, b, i);
    return t;
}

static uint32_t count_cw(const scene *s, uint32_t b)
{
    uint32_t i, n = 0;
    for (i = 0; i < s->blocks[b].ring_count; i++)
        n += ring_area(s, b, i) < 0.0;
    return n;
}

/* Area of a union of axis-aligned rectangles (x0,y0,x1,y1 each), by
 * coordinate compression: independent of the code under test. */
static double rect_union_area(const double *r, uint32_t n)
{
    double *xs = malloc(2 * n * sizeof(double)), *ys = malloc(2 * n * sizeof(double)), t = 0;
    uint32_t i, j, k;
    assert_non_null(xs);
    assert_non_null(ys);
    for (i = 0; i < n; i++) {
        xs[2 * i] = r[4 * i];
        xs[2 * i + 1] = r[4 * i + 2];
        ys[2 * i] = r[4 * i + 1];
        ys[2 * i + 1] = r[4 * i + 3];
    }
    for (i = 0; i < 2 * n; i++)
        for (j = i + 1; j < 2 * n; j++) {
            double v;
            if (xs[j] < xs[i]) { v = xs[i]; xs[i] = xs[j]; xs[j] = v; }
            if (ys[j] < ys[i]) { v = ys[i]; ys[i] = ys[j]; ys[j] = v; }
        }
    for (i = 0; i + 1 < 2 * n; i++)
        for (j = 0; j + 1 < 2 * n; j++) {
            double cx = 0.5 * (xs[i] + xs[i + 1]), cy = 0.5 * (ys[j] + ys[j + 1]);
            if (xs[i + 1] == xs[i] || ys[j + 1] == ys[j])
                continue;
            for (k = 0; k < n; k++)
                if (cx > r[4 * k] && cx < r[4 * k + 2] && cy > r[4 * k + 1] && cy < r[4 * k + 3]) {
                    t += (xs[i + 1] - xs[i]) * (ys[j + 1] - ys[j]);
                    break;
                }
        }
    free(xs);
    free(ys);
    return t;
}

static void fx_rects(fixture *f, const double *r, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n; i++)
        fx_rect(f, r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3]);
}

#define FX_BYTES (8u << 20)

/* ---- tests ---------------------------------------------------------------- */

static void test_two_separate_squares(void **state)
{
    fixture f;
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_rect(&f, 0, 0, 10, 10);
    fx_rect(&f, 10.2, 0, 20, 10); /* 20 cm apart */
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 2);
    assert_int_equal(f.s.bld[0].block, 0);
    assert_int_equal(f.s.bld[1].block, 1);
    assert_int_equal(f.s.overlapping_pairs, 0);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_int_equal(ring_len(&f.s, 0, 0), 4);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 100.0) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 1, 0) - 98.0) < 1e-9);
    fx_free(&f);
}

static void test_shared_wall(void **state)
{
    fixture f;
    double r[8] = {0, 0, 10, 10, 10, 0, 20, 10};
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_rects(&f, r, 2);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.overlapping_pairs, 0);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_int_equal(ring_len(&f.s, 0, 0), 4);
    assert_true(fabs(ring_area(&f.s, 0, 0) - rect_union_area(r, 2)) < 1e-9);
    fx_free(&f);
}

static void test_gap_3mm(void **state)
{
    fixture f;
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_rect(&f, 0, 0, 10, 10);
    fx_rect(&f, 10.003, 0, 20, 10);
    fx_rect(&f, 40, 0, 50, 10);
    fx_rect(&f, 50.003, 0.002, 60, 10.004); /* a gap and a shift of mm */
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 2);
    assert_int_equal(f.s.overlapping_pairs, 0);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_int_equal(ring_len(&f.s, 0, 0), 4);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 200.0) < 0.05);
    assert_int_equal(f.s.blocks[1].ring_count, 1);
    assert_true(fabs(ring_area(&f.s, 1, 0) - 200.0) < 0.05);
    fx_free(&f);
}

static void test_t_junction(void **state)
{
    fixture f;
    double r[12] = {0, 0, 20, 10, 0, 10, 10, 15, 10, 10, 20, 15};
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_rects(&f, r, 3);
    /* the same with millimetre errors: short buildings 2 mm off the wall */
    fx_rect(&f, 100, 0, 120, 10);
    fx_rect(&f, 100, 10.002, 110, 15);
    fx_rect(&f, 110.001, 9.998, 120, 15);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 2);
    assert_int_equal(f.s.overlapping_pairs, 0);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_true(fabs(ring_area(&f.s, 0, 0) - rect_union_area(r, 3)) < 1e-9);
    assert_int_equal(ring_len(&f.s, 0, 0), 4);
    assert_int_equal(f.s.blocks[1].ring_count, 1);
    assert_true(fabs(ring_area(&f.s, 1, 0) - 300.0) < 0.1);
    fx_free(&f);
}

static void test_courtyard_ring_of_8_and_4(void **state)
{
    fixture f;
    double r8[32], r4[16] = {100, 0, 130, 10, 100, 20, 130, 30, 100, 10, 110, 20, 120, 10, 130, 20};
    uint32_t i, j, n = 0;
    (void)state;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            if (i != 1 || j != 1) {
                r8[4 * n] = 10.0 * i;
                r8[4 * n + 1] = 10.0 * j;
                r8[4 * n + 2] = 10.0 * i + 10;
                r8[4 * n + 3] = 10.0 * j + 10;
                n++;
            }
    fx_init(&f, FX_BYTES, 128, 16, 16);
    fx_rects(&f, r8, 8);
    fx_rects(&f, r4, 4);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 2);
    assert_int_equal(f.s.overlapping_pairs, 0);
    for (i = 0; i < 2; i++) {
        assert_int_equal(f.s.blocks[i].bld_count, i == 0 ? 8 : 4);
        assert_int_equal(f.s.blocks[i].ring_count, 2);
        assert_int_equal(count_cw(&f.s, i), 1);
        assert_true(fabs(ring_area(&f.s, i, 0) - 900.0) < 1e-9);
        assert_true(fabs(ring_area(&f.s, i, 1) + 100.0) < 1e-9);
        assert_int_equal(ring_len(&f.s, i, 0), 4);
        assert_int_equal(ring_len(&f.s, i, 1), 4);
    }
    assert_true(fabs(block_area(&f.s, 0) - rect_union_area(r8, 8)) < 1e-9);
    assert_true(fabs(block_area(&f.s, 1) - rect_union_area(r4, 4)) < 1e-9);
    fx_free(&f);
}

/* An eixample-like block: 16 buildings around a chamfered square courtyard,
 * walls meeting within millimetres. */
static void test_eixample_ring_of_16(void **state)
{
    fixture f;
    uint32_t i, k;
    double c = 50.0, ro = 55.0, ri = 35.0, tot = 0.0;
    (void)state;
    fx_init(&f, FX_BYTES, 256, 32, 32);
    for (k = 0; k < 16; k++) {
        /* wedge k of an octagon-ish ring split radially: angles a0..a1 */
        double a0 = 2 * 3.14159265358979 * k / 16.0, a1 = 2 * 3.14159265358979 * (k + 1) / 16.0;
        double xy[8], e = (k % 2) ? 0.003 : -0.002; /* mm gaps/overlaps at the joints */
        xy[0] = c + ri * cos(a0);
        xy[1] = c + ri * sin(a0);
        xy[2] = c + ro * cos(a0);
        xy[3] = c + ro * sin(a0);
        xy[4] = c + ro * cos(a1 + e / ro);
        xy[5] = c + ro * sin(a1 + e / ro);
        xy[6] = c + ri * cos(a1 + e / ri);
        xy[7] = c + ri * sin(a1 + e / ri);
        fx_poly(&f, xy, 4);
        tot += area_of(f.s.pts + f.s.npts - 4, 4);
    }
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.overlapping_pairs, 0);
    assert_int_equal(f.s.blocks[0].ring_count, 2);
    assert_int_equal(count_cw(&f.s, 0), 1);
    assert_true(ring_area(&f.s, 0, 1) < -3000.0);
    assert_true(fabs(block_area(&f.s, 0) - tot) < 1.0);
    for (i = 0; i < 2; i++)
        assert_int_equal(ring_len(&f.s, 0, i), 16);
    fx_free(&f);
}

static void test_own_inner_ring(void **state)
{
    fixture f;
    double sq[8] = {0, 0, 30, 0, 30, 30, 0, 30};
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_building(&f);
    fx_ring(&f, sq, 4);
    fx_hole_rect(&f, 10, 10, 20, 20);
    /* the same with a building filling half of the courtyard */
    sq[0] = sq[6] = 100;
    sq[2] = sq[4] = 130;
    fx_building(&f);
    fx_ring(&f, sq, 4);
    fx_hole_rect(&f, 110, 10, 120, 20);
    fx_rect(&f, 110, 10, 115, 20);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 2);
    assert_int_equal(f.s.overlapping_pairs, 0);
    assert_int_equal(f.s.blocks[0].ring_count, 2);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 900.0) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 0, 1) + 100.0) < 1e-9);
    assert_int_equal(f.s.blocks[1].bld_count, 2);
    assert_int_equal(f.s.blocks[1].ring_count, 2);
    assert_true(fabs(ring_area(&f.s, 1, 1) + 50.0) < 1e-9);
    assert_int_equal(ring_len(&f.s, 1, 1), 4);
    fx_free(&f);
}

static void test_overlap_2m(void **state)
{
    fixture f;
    double r1[8] = {0, 0, 10, 10, 8, 0, 18, 10};
    double r2[8] = {100, 0, 110, 10, 108, 3, 118, 13};
    double r3[8] = {200, 10, 230, 20, 210, 0, 220, 30}; /* a cross: no vertex inside */
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_rects(&f, r1, 2);
    fx_rects(&f, r2, 2);
    fx_rects(&f, r3, 2);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 3);
    assert_int_equal(f.s.overlapping_pairs, 3);
    assert_true(fabs(ring_area(&f.s, 0, 0) - rect_union_area(r1, 2)) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 1, 0) - rect_union_area(r2, 2)) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 2, 0) - rect_union_area(r3, 2)) < 1e-9);
    assert_int_equal(ring_len(&f.s, 0, 0), 4);
    assert_int_equal(ring_len(&f.s, 1, 0), 8);
    assert_int_equal(ring_len(&f.s, 2, 0), 12);
    fx_free(&f);
}

static void test_slight_overlap_2cm(void **state)
{
    fixture f;
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_rect(&f, 0, 0, 10, 10);
    fx_rect(&f, 9.98, 0, 20, 10);
    fx_rect(&f, 100, 0, 110, 10);
    fx_rect(&f, 109.98, 0.5, 120, 10.5); /* shifted along the wall too */
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 2);
    assert_int_equal(f.s.overlapping_pairs, 0);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 200.0) < 1e-9);
    assert_int_equal(f.s.blocks[1].ring_count, 1);
    /* union: 100 + 100.2 - 0.02 * 9.5; snapping closes the 2 cm sliver */
    assert_true(fabs(ring_area(&f.s, 1, 0) - (200.2 - 0.02 * 9.5)) < 0.05);
    fx_free(&f);
}

static void test_containment_and_duplicates(void **state)
{
    fixture f;
    (void)state;
    fx_init(&f, FX_BYTES, 64, 16, 16);
    fx_rect(&f, 0, 0, 40, 20);        /* cathedral */
    fx_rect(&f, 5, 5, 10, 10);        /* tower inside */
    fx_rect(&f, 0, 0, 10, 20);        /* part sharing three walls */
    fx_rect(&f, 100, 0, 110, 10);     /* duplicates */
    fx_rect(&f, 100, 0, 110, 10);
    fx_rect(&f, 200, 0, 210, 10);     /* near-duplicates, 1 cm apart */
    fx_rect(&f, 200.01, 0.01, 210.01, 10.01);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 3);
    /* cathedral-tower, cathedral-part, tower-part, two duplicate pairs */
    assert_int_equal(f.s.overlapping_pairs, 5);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 800.0) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 1, 0) - 100.0) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 2, 0) - 100.0) < 0.3);
    fx_free(&f);
}

static void test_raised_and_corner_touch(void **state)
{
    fixture f;
    (void)state;
    fx_init(&f, FX_BYTES, 64, 8, 8);
    fx_rect(&f, 0, 0, 10, 10);
    fx_rect(&f, 10, 0, 20, 10);
    f.s.bld[1].min_height = 5.0; /* a raised building joins like any other */
    fx_rect(&f, 100, 0, 110, 10);
    fx_rect(&f, 110, 10, 120, 20); /* touches at a corner only */
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 2);
    assert_int_equal(f.s.blocks[0].bld_count, 2);
    /* a pinch gives two counter-clockwise loops: outer + one extra outer */
    assert_int_equal(f.s.blocks[1].ring_count, 2);
    assert_int_equal(count_cw(&f.s, 1), 0);
    assert_true(fabs(block_area(&f.s, 1) - 200.0) < 1e-9);
    fx_free(&f);
}

/* Cells of a grid of 10 m squares, from a picture: '#' is a building. */
static void fx_cells(fixture *f, const char *const *rows, uint32_t n, double *r, uint32_t *nr)
{
    uint32_t i, j;
    *nr = 0;
    for (j = 0; j < n; j++)
        for (i = 0; rows[j][i]; i++)
            if (rows[j][i] == '#') {
                double *q = r + 4 * *nr;
                q[0] = 10.0 * i;
                q[1] = 10.0 * (n - 1 - j);
                q[2] = q[0] + 10.0;
                q[3] = q[1] + 10.0;
                fx_rect(f, q[0], q[1], q[2], q[3]);
                (*nr)++;
            }
}

/* Pinches: a courtyard touching the outer boundary at a point, and two
 * courtyards touching each other at a point, give simple rings. */
static void test_pinched_courtyards(void **state)
{
    static const char *const u[] = {"##.", "#.#", "###"};
    static const char *const two[] = {"####", "#.##", "##.#", "####"};
    fixture f;
    double r[4 * 16];
    uint32_t n;
    (void)state;
    fx_init(&f, FX_BYTES, 128, 32, 32);
    fx_cells(&f, u, 3, r, &n);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.blocks[0].ring_count, 2);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 800.0) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 0, 1) + 100.0) < 1e-9);
    assert_true(fabs(block_area(&f.s, 0) - rect_union_area(r, n)) < 1e-9);
    fx_free(&f);

    fx_init(&f, FX_BYTES, 128, 32, 32);
    fx_cells(&f, two, 4, r, &n);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.blocks[0].ring_count, 3);
    assert_int_equal(count_cw(&f.s, 0), 2);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 1600.0) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 0, 1) + 100.0) < 1e-9);
    assert_true(fabs(ring_area(&f.s, 0, 2) + 100.0) < 1e-9);
    assert_true(fabs(block_area(&f.s, 0) - rect_union_area(r, n)) < 1e-9);
    fx_free(&f);
}

/* A round tower drawn with vertices 3.8 cm apart keeps its shape (no
 * chain of snaps collapses it), and joins the building it touches. */
static void test_fine_curve(void **state)
{
    fixture f;
    double xy[2 * 500], sq[8] = {3, -3, 10, -3, 10, 3, 3, 3};
    uint32_t i;
    (void)state;
    for (i = 0; i < 500; i++) {
        double a = 2 * 3.14159265358979 * i / 500;
        xy[2 * i] = 3 * cos(a);
        xy[2 * i + 1] = 3 * sin(a);
    }
    fx_init(&f, FX_BYTES, 600, 8, 8);
    fx_poly(&f, xy, 500);
    fx_poly(&f, sq, 4);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.overlapping_pairs, 0); /* tangent at (3, 0) */
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_true(ring_len(&f.s, 0, 0) > 200);
    /* the square's wall is bent through the circle's vertices within tol of
     * it (about 1 m of arc): a thin wedge of up to tol along the 2.5 m to
     * each corner is added */
    assert_true(fabs(ring_area(&f.s, 0, 0) - (9 * 3.14159265358979 + 42)) < 0.2);
    fx_free(&f);
}

/* A # pattern: many crossings, more outline vertices than footprint ones
 * (exercises the recount path too). */
static void test_hash_pattern(void **state)
{
    fixture f;
    double r[4 * 20];
    uint32_t i, n = 0;
    (void)state;
    for (i = 0; i < 10; i++) {
        r[4 * n] = 0; r[4 * n + 1] = 10.0 * i; r[4 * n + 2] = 100; r[4 * n + 3] = 10.0 * i + 3;
        n++;
        r[4 * n] = 10.0 * i + 1; r[4 * n + 1] = -5; r[4 * n + 2] = 10.0 * i + 4; r[4 * n + 3] = 99;
        n++;
    }
    fx_init(&f, FX_BYTES, 128, 32, 32);
    fx_rects(&f, r, n);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.overlapping_pairs, 100);
    assert_int_equal(count_cw(&f.s, 0), 81);
    assert_int_equal(f.s.blocks[0].ring_count, 82);
    assert_true(f.s.nblock_pts > f.s.npts + f.s.npts / 4 + 64);
    assert_true(fabs(block_area(&f.s, 0) - rect_union_area(r, n)) < 1e-6);
    fx_free(&f);
}

/* Convex polygon clipping (Sutherland-Hodgman), for independent areas. */
static uint32_t clip_convex(const vec2 *p, uint32_t n, const vec2 *c, uint32_t m, vec2 *out)
{
    vec2 buf[2][64];
    uint32_t i, j, k = n, cur = 0;
    memcpy(buf[0], p, n * sizeof(vec2));
    for (j = 0; j < m && k > 0; j++) {
        vec2 a = c[j], b = c[(j + 1) % m];
        uint32_t nk = 0;
        for (i = 0; i < k; i++) {
            vec2 s = buf[cur][i], e = buf[cur][(i + 1) % k];
            double ds = (b.x - a.x) * (s.y - a.y) - (b.y - a.y) * (s.x - a.x);
            double de = (b.x - a.x) * (e.y - a.y) - (b.y - a.y) * (e.x - a.x);
            if (ds >= 0)
                buf[1 - cur][nk++] = s;
            if ((ds >= 0) != (de >= 0)) {
                double t = ds / (ds - de);
                buf[1 - cur][nk].x = s.x + t * (e.x - s.x);
                buf[1 - cur][nk].y = s.y + t * (e.y - s.y);
                nk++;
            }
        }
        k = nk;
        cur = 1 - cur;
    }
    memcpy(out, buf[cur], k * sizeof(vec2));
    return k;
}

static double lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* Random triples of overlapping rotated quads: outline area against
 * inclusion-exclusion with convex clipping. */
static void test_random_rotated_triples(void **state)
{
    uint64_t seed = 12345;
    uint32_t t, i, inexact = 0;
    (void)state;
    for (t = 0; t < 200; t++) {
        fixture f;
        vec2 q[3][4], x1[64], x2[64];
        double want = 0.0, xy[8], got;
        uint32_t n;
        fx_init(&f, 1u << 20, 64, 8, 8);
        for (i = 0; i < 3; i++) {
            double cx = 10 * lcg(&seed), cy = 10 * lcg(&seed), a = 6.28 * lcg(&seed);
            double w = 3 + 8 * lcg(&seed), h = 3 + 8 * lcg(&seed), ca = cos(a), sa = sin(a);
            uint32_t j;
            for (j = 0; j < 4; j++) {
                double u = (j == 1 || j == 2) ? w / 2 : -w / 2, v = (j >= 2) ? h / 2 : -h / 2;
                q[i][j].x = cx + ca * u - sa * v;
                q[i][j].y = cy + sa * u + ca * v;
                xy[2 * j] = q[i][j].x;
                xy[2 * j + 1] = q[i][j].y;
            }
            fx_poly(&f, xy, 4);
            want += area_of(q[i], 4);
        }
        for (i = 0; i < 3; i++) {
            n = clip_convex(q[i], 4, q[(i + 1) % 3], 4, x1);
            want -= n >= 3 ? area_of(x1, n) : 0.0;
        }
        n = clip_convex(q[0], 4, q[1], 4, x1);
        if (n >= 3) {
            n = clip_convex(x1, n, q[2], 4, x2);
            want += n >= 3 ? area_of(x2, n) : 0.0;
        }
        /* with a tiny tolerance the outline is the exact union */
        fx_run_tol(&f, 1e-9);
        got = 0.0;
        for (i = 0; i < f.s.nblocks; i++)
            got += block_area(&f.s, i);
        assert_true(fabs(got - want) < 1e-6);
        /* with 5 cm, snapping moves vertices by up to tol: the area moves by
         * at most about tol times the length of the edges moved */
        arena_release(&f.a, &f.before);
        fx_run(&f);
        got = 0.0;
        for (i = 0; i < f.s.nblocks; i++)
            got += block_area(&f.s, i);
        assert_true(fabs(got - want) < TOL * 40.0);
        inexact += fabs(got - want) > 1e-6;
        fx_free(&f);
    }
    /* snapping changes the area only when vertices come within tol */
    printf("random rotated triples: with tol 5 cm %u of 200 differ by more than 1e-6 m2\n", inexact);
}

/* Random rectangles on an integer lattice: exact areas, and blocks equal to
 * the components of "closed boxes meet". */
static void test_random_rects(void **state)
{
    uint64_t seed = 777;
    uint32_t t, i, j;
    (void)state;
    for (t = 0; t < 60; t++) {
        fixture f;
        double r[4 * 40], got = 0.0;
        uint32_t n = 5 + (uint32_t)(35 * lcg(&seed)), comp[40], nb = 0;
        fx_init(&f, 4u << 20, 4 * 40, 40, 40);
        for (i = 0; i < n; i++) {
            r[4 * i] = floor(40 * lcg(&seed));
            r[4 * i + 1] = floor(40 * lcg(&seed));
            r[4 * i + 2] = r[4 * i] + 1 + floor(8 * lcg(&seed));
            r[4 * i + 3] = r[4 * i + 1] + 1 + floor(8 * lcg(&seed));
            comp[i] = i;
        }
        fx_rects(&f, r, n);
        fx_run(&f);
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++)
                if (r[4 * i] <= r[4 * j + 2] && r[4 * j] <= r[4 * i + 2] &&
                    r[4 * i + 1] <= r[4 * j + 3] && r[4 * j + 1] <= r[4 * i + 3]) {
                    uint32_t a = comp[i], b = comp[j], k;
                    for (k = 0; k < n; k++)
                        if (comp[k] == b)
                            comp[k] = a;
                }
        for (i = 0; i < n; i++) {
            for (j = 0; j < i; j++)
                if (comp[j] == comp[i])
                    break;
            nb += j == i;
            for (j = 0; j < n; j++)
                assert_int_equal(f.s.bld[i].block == f.s.bld[j].block, comp[i] == comp[j]);
        }
        assert_int_equal(f.s.nblocks, nb);
        for (i = 0; i < f.s.nblocks; i++) {
            assert_true(f.s.blocks[i].ring_count >= 1);
            got += block_area(&f.s, i);
        }
        assert_true(fabs(got - rect_union_area(r, n)) < 1e-6);
        fx_free(&f);
    }
}

static void test_grid_100x100_fast(void **state)
{
    fixture f;
    uint32_t i, j, n = getenv("PLX_TEST_QUICK") ? 30 : 100;
    clock_t c0;
    double secs;
    (void)state;
    fx_init(&f, 64u << 20, 4 * n * n, n * n, n * n);
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++)
            fx_rect(&f, 20.0 * i, 20.0 * j, 20.0 * i + 12 + (i % 3), 20.0 * j + 9 + (j % 4));
    c0 = clock();
    fx_run(&f);
    secs = (double)(clock() - c0) / CLOCKS_PER_SEC;
    printf("blocks_build: %ux%u separate squares in %.3f s, scratch peak %zu bytes\n", n, n,
           secs, f.a.peak[PLX_PART_SCRATCH]);
    assert_int_equal(f.s.nblocks, n * n);
    assert_int_equal(f.s.nblock_rings, n * n);
    assert_int_equal(f.s.nblock_pts, 4 * n * n);
    assert_true(secs < 2.0);
    fx_free(&f);
}

/* A long row of 2000 buildings sharing walls: one block, one ring. */
static void test_long_row(void **state)
{
    fixture f;
    uint32_t i, n = 2000;
    clock_t c0;
    double secs, want = 0.0;
    (void)state;
    fx_init(&f, 64u << 20, 4 * n, n, n);
    for (i = 0; i < n; i++) {
        fx_rect(&f, 8.0 * i, (i % 2) * 0.001, 8.0 * i + 8.0, 15.0 + (i % 3));
        want += 8.0 * (15.0 + (i % 3) - (i % 2) * 0.001);
    }
    c0 = clock();
    fx_run(&f);
    secs = (double)(clock() - c0) / CLOCKS_PER_SEC;
    printf("blocks_build: a row of %u buildings in %.3f s\n", n, secs);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_true(fabs(ring_area(&f.s, 0, 0) - want) < 0.01);
    assert_true(secs < 2.0);
    fx_free(&f);
}

/* A comb: the bottom edge (0,0)-(W,0), then back along a zigzag top at
 * y = 10 or 15, so every edge shares one horizontal band. The outline used
 * to take time quadratic in the vertices here (a ray across all teeth). */
static void test_comb_one_band_fast(void **state)
{
    fixture f;
    uint32_t n = getenv("PLX_TEST_QUICK") ? 10000 : 100000, w = n - 3, x, k = 0;
    double *xy = malloc(2 * (size_t)n * sizeof(double));
    clock_t c0;
    double secs;
    (void)state;
    assert_non_null(xy);
    fx_init(&f, 64u << 20, n, 1, 1);
    xy[k++] = 0;
    xy[k++] = 0;
    xy[k++] = w;
    xy[k++] = 0;
    for (x = w + 1; x-- > 0;) {
        xy[k++] = x;
        xy[k++] = x % 2 ? 15 : 10;
    }
    fx_poly(&f, xy, n);
    free(xy);
    c0 = clock();
    fx_run(&f);
    secs = (double)(clock() - c0) / CLOCKS_PER_SEC;
    printf("blocks_build: a comb of %u vertices in one band in %.3f s, scratch peak %zu bytes\n",
           n, secs, f.a.peak[PLX_PART_SCRATCH]);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_int_equal(ring_len(&f.s, 0, 0), n);
    assert_true(ring_area(&f.s, 0, 0) == 12.5 * w);
    assert_true(secs < 2.0);
    fx_free(&f);
}

/* The same comb turned by 0.3 rad: its long bottom edge is slanted, so its
 * box covers the whole comb. */
static void test_slanted_comb_fast(void **state)
{
    fixture f;
    uint32_t n = getenv("PLX_TEST_QUICK") ? 10000 : 100000, w = n - 3, x, k;
    double *xy = malloc(2 * (size_t)n * sizeof(double)), ca = cos(0.3), sa = sin(0.3), want;
    clock_t c0;
    double secs;
    (void)state;
    assert_non_null(xy);
    fx_init(&f, 64u << 20, n, 1, 1);
    xy[0] = 0;
    xy[1] = 0;
    xy[2] = w;
    xy[3] = 0;
    for (k = 4, x = w + 1; x-- > 0;) {
        xy[k++] = x;
        xy[k++] = x % 2 ? 15 : 10;
    }
    for (k = 0; k < n; k++) {
        double px = xy[2 * k], py = xy[2 * k + 1];
        xy[2 * k] = ca * px - sa * py;
        xy[2 * k + 1] = sa * px + ca * py;
    }
    fx_poly(&f, xy, n);
    free(xy);
    want = area_of(f.s.pts, n);
    c0 = clock();
    fx_run(&f);
    secs = (double)(clock() - c0) / CLOCKS_PER_SEC;
    printf("blocks_build: a slanted comb of %u vertices in %.3f s\n", n, secs);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_int_equal(ring_len(&f.s, 0, 0), n);
    assert_true(fabs(ring_area(&f.s, 0, 0) - want) <= 1e-9 * want);
    assert_true(fabs(want - 12.5 * w) <= 1e-6 * want);
    assert_true(secs < 2.0);
    fx_free(&f);
}

/* A fine circle of 50000 vertices 250 m across an empty middle: the same
 * ring back, nothing dropped or added. */
static void test_fine_circle(void **state)
{
    fixture f;
    uint32_t n = getenv("PLX_TEST_QUICK") ? 5000 : 50000, i;
    double *xy = malloc(2 * (size_t)n * sizeof(double)), want;
    (void)state;
    assert_non_null(xy);
    fx_init(&f, 64u << 20, n, 1, 1);
    for (i = 0; i < n; i++) {
        double a = 2.0 * 3.14159265358979323846 * i / n;
        xy[2 * i] = floor(2e5 * cos(a) + 0.5);
        xy[2 * i + 1] = floor(2e5 * sin(a) + 0.5);
    }
    fx_poly(&f, xy, n);
    free(xy);
    want = area_of(f.s.pts, n);
    fx_run(&f);
    assert_int_equal(f.s.nblocks, 1);
    assert_int_equal(f.s.blocks[0].ring_count, 1);
    assert_true(fabs(ring_area(&f.s, 0, 0) - want) <= 1e-9 * want);
    fx_free(&f);
}

static void test_empty_and_invalid(void **state)
{
    fixture f;
    (void)state;
    fx_init(&f, FX_BYTES, 8, 2, 2);
    assert_int_equal(blocks_build(NULL, &f.s, TOL), PLX_E_INVALID);
    assert_int_equal(blocks_build(&f.a, NULL, TOL), PLX_E_INVALID);
    assert_int_equal(blocks_build(&f.a, &f.s, -1.0), PLX_E_INVALID);
    assert_int_equal(blocks_build(&f.a, &f.s, NAN), PLX_E_INVALID);
    assert_int_equal(blocks_build(&f.a, &f.s, TOL), PLX_OK);
    assert_int_equal(f.s.nblocks, 0);
    assert_int_equal(f.s.nblock_rings, 0);
    fx_rect(&f, 0, 0, 1, 1);
    assert_int_equal(blocks_build(&f.a, &f.s, 0.0), PLX_OK); /* tol 0: exact */
    assert_int_equal(f.s.nblocks, 1);
    assert_true(fabs(ring_area(&f.s, 0, 0) - 1.0) < 1e-12);
    fx_free(&f);
}

/* Fails the k-th arena request for k = 1, 2, ... until blocks_build
 * succeeds: each failure is PLX_E_NOMEM with the scratch end untouched. */
static void fault_loop(void (*fill)(fixture *), size_t bytes)
{
    fixture f;
    uint64_t k;
    plx_status st = PLX_E_NOMEM;
    arena_mark m;
    size_t hi, used;
    fx_init(&f, bytes, 512, 64, 64);
    fill(&f);
    m = arena_get_mark(&f.a);
    hi = f.a.hi;
    used = f.a.used[PLX_PART_SCRATCH];
    for (k = 1; k < 100000; k++) {
        f.a.requests = 0;
        f.a.fail_at = k;
        st = blocks_build(&f.a, &f.s, TOL);
        f.a.fail_at = 0;
        assert_int_equal(f.a.hi, hi);
        assert_int_equal(f.a.used[PLX_PART_SCRATCH], used);
        if (st == PLX_OK)
            break;
        assert_int_equal(st, PLX_E_NOMEM);
        arena_release(&f.a, &m); /* the caller gives back the persistent part */
    }
    assert_int_equal(st, PLX_OK);
    printf("fault injection: %llu requests to succeed\n", (unsigned long long)k);
    fx_free(&f);
}

static void fill_mixed(fixture *f)
{
    double sq[8] = {0, 0, 30, 0, 30, 30, 0, 30};
    uint32_t i;
    fx_building(f);
    fx_ring(f, sq, 4);
    fx_hole_rect(f, 10, 10, 20, 20);
    fx_rect(f, 30, 0, 40, 10);
    fx_rect(f, 35, 5, 45, 15);
    fx_rect(f, 100, 0, 110, 10);
    for (i = 0; i < 10; i++) {
        fx_rect(f, 200, 10.0 * i, 300, 10.0 * i + 3);
        fx_rect(f, 200 + 10.0 * i, -5, 203 + 10.0 * i, 99);
    }
}

static void test_fault_injection(void **state)
{
    (void)state;
    fault_loop(fill_mixed, FX_BYTES);
}

static void test_small_block_nomem(void **state)
{
    fixture f;
    size_t hi;
    (void)state;
    /* Just enough for the scene: blocks_build must fail cleanly. */
    fx_init(&f, 800, 12, 3, 3);
    fx_rect(&f, 0, 0, 10, 10);
    fx_rect(&f, 10, 0, 20, 10);
    fx_rect(&f, 30, 0, 40, 10);
    hi = f.a.hi;
    assert_int_equal(blocks_build(&f.a, &f.s, TOL), PLX_E_NOMEM);
    assert_int_equal(f.a.hi, hi);
    fx_free(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_separate_squares),
        cmocka_unit_test(test_shared_wall),
        cmocka_unit_test(test_gap_3mm),
        cmocka_unit_test(test_t_junction),
        cmocka_unit_test(test_courtyard_ring_of_8_and_4),
        cmocka_unit_test(test_eixample_ring_of_16),
        cmocka_unit_test(test_own_inner_ring),
        cmocka_unit_test(test_overlap_2m),
        cmocka_unit_test(test_slight_overlap_2cm),
        cmocka_unit_test(test_containment_and_duplicates),
        cmocka_unit_test(test_raised_and_corner_touch),
        cmocka_unit_test(test_pinched_courtyards),
        cmocka_unit_test(test_fine_curve),
        cmocka_unit_test(test_hash_pattern),
        cmocka_unit_test(test_random_rotated_triples),
        cmocka_unit_test(test_random_rects),
        cmocka_unit_test(test_grid_100x100_fast),
        cmocka_unit_test(test_long_row),
        cmocka_unit_test(test_comb_one_band_fast),
        cmocka_unit_test(test_slanted_comb_fast),
        cmocka_unit_test(test_fine_circle),
        cmocka_unit_test(test_empty_and_invalid),
        cmocka_unit_test(test_fault_injection),
        cmocka_unit_test(test_small_block_nomem),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
