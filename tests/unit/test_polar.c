/* test_polar: polar diagrams and the fan of tangent rays against brute force.
 *
 * Visibility is compared with tests/ref/ref_vis (an angular sweep over every
 * edge): areas to 1e-9 relative, visible sets identical. On the small scenes
 * every reference answer is also asked of tests/ref/ref_vis_fast (the same
 * sweep with grid searches), which must give the same answer; the fixtures,
 * the real district among them, are then checked against ref_vis_fast at
 * thousands of points. Point location and ray shooting are compared with
 * plain scans over every footprint and edge.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "polarlux_port.h"
#include "base/scene.h"
#include "base/arena.h"
#include "base/engine.h"
#include "polar/polar.h"
#include "polar/locate.h"
#include "polar_faults.h"
#include "polar/visibility.h"
#include "ref_scene.h"
#include "ref_vis.h"
#include "ref_vis_fast.h"

#define PI 3.14159265358979323846
#define ARENA_BYTES ((size_t)32 << 20)
#define POLY_CAP 20000
#define VIS_CAP 4000

/* ---------------------------------------------------------------- helpers */

typedef struct fixture {
    scene s;
    void *mem;
    arena a;
    polar *pd;
    vec2 *poly;
    uint32_t *vis;
} fixture;

static uint32_t rnd_state;

static double urand(void)
{
    rnd_state = rnd_state * 1103515245u + 12345u;
    return ((rnd_state >> 8) & 0xffffff) / 16777216.0;
}

static fixture *fixture_new(void)
{
    fixture *f = calloc(1, sizeof *f);
    assert_non_null(f);
    ref_scene_init(&f->s);
    f->mem = malloc(ARENA_BYTES);
    f->poly = malloc(POLY_CAP * sizeof(vec2));
    f->vis = malloc(VIS_CAP * sizeof(uint32_t));
    assert_non_null(f->mem);
    assert_non_null(f->poly);
    assert_non_null(f->vis);
    arena_init(&f->a, f->mem, ARENA_BYTES);
    return f;
}

static void fixture_build(fixture *f)
{
    ref_scene_finish(&f->s);
    assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
    assert_non_null(f->pd);
}

static void fixture_free(fixture *f)
{
    ref_scene_free(&f->s);
    free(f->mem);
    free(f->poly);
    free(f->vis);
    free(f);
}

static int add_poly(fixture *f, const double *xy, uint32_t n)
{
    return ref_scene_add_building(&f->s, xy, &n, 1, 10.0, 0.0);
}

static void add_rotated_box(fixture *f, double x, double y, double w, double h, double ang)
{
    double c = cos(ang), s = sin(ang), xy[8];
    double ox[4] = { 0, w, w, 0 }, oy[4] = { 0, 0, h, h };
    int k;
    for (k = 0; k < 4; k++) {
        xy[2 * k] = x + c * ox[k] - s * oy[k];
        xy[2 * k + 1] = y + s * ox[k] + c * oy[k];
    }
    assert_true(add_poly(f, xy, 4) >= 0);
}

static void add_l_shape(fixture *f, double x, double y, double w, double h)
{
    double xy[12] = { x, y, x + w, y, x + w, y + h / 2, x + w / 2, y + h / 2,
                      x + w / 2, y + h, x, y + h };
    assert_true(add_poly(f, xy, 6) >= 0);
}

static void add_courtyard(fixture *f, double x, double y, double w, double h, double t)
{
    double xy[16] = { x, y, x + w, y, x + w, y + h, x, y + h,
                      x + t, y + t, x + t, y + h - t, x + w - t, y + h - t, x + w - t, y + t };
    uint32_t n[2] = { 4, 4 };
    assert_true(ref_scene_add_building(&f->s, xy, n, 2, 20.0, 0.0) >= 0);
}

/* Is p strictly inside or on some occluder footprint? 0 free, 1 in, 2 on. */
static int where(const scene *s, vec2 p)
{
    uint32_t b;
    int on = 0;
    for (b = 0; b < s->nbld; b++) {
        int w;
        if (s->bld[b].min_height > 0)
            continue;
        w = ref_footprint_where(s, b, p.x, p.y);
        if (w == REF_IN)
            return 1;
        if (w == REF_ON)
            on = 1;
    }
    return on ? 2 : 0;
}

/* Does ref_vis_fast give ref_vis's answer (return code rc, result *rr)?
 * Same intervals, same nearest edges: areas equal to rounding. */
static int fast_agrees(const scene *s, vec2 p, int full, double a0, double a1, int rc,
                       const ref_vis_result *rr)
{
    ref_vis_result ff;
    int rf, ok;
    uint32_t k;
    rf = full ? ref_vis_fast(s, p.x, p.y, &ff) : ref_vis_fast_range(s, p.x, p.y, a0, a1, &ff);
    ok = rf == rc;
    if (ok && rc == 0) {
        ok = fabs(ff.area - rr->area) <= 1e-12 * fmax(rr->area, 1.0) &&
             ff.nverts == rr->nverts && ff.nvisible == rr->nvisible;
        for (k = 0; ok && k < ff.nvisible; k++)
            ok = ff.visible[k] == rr->visible[k];
    }
    ref_vis_free(&ff);
    return ok;
}

/* Compares vis_query with ref_vis at p; returns 1 when they agree. */
static int vis_agrees(fixture *f, vec2 p, int full, double a0, double a1, int verbose)
{
    ref_vis_result rr;
    vis_result vr;
    int rc, ok;
    uint32_t k;
    plx_status st;
    arena_mark before = arena_get_mark(&f->a);
    rc = full ? ref_vis(&f->s, p.x, p.y, &rr) : ref_vis_range(&f->s, p.x, p.y, a0, a1, &rr);
    if (!fast_agrees(&f->s, p, full, a0, a1, rc, &rr)) {
        if (verbose)
            print_message("p = (%.17g, %.17g) full %d [%g, %g]: ref_vis_fast differs from "
                          "ref_vis\n", p.x, p.y, full, a0, a1);
        ref_vis_free(&rr);
        return 0;
    }
    memset(&vr, 0, sizeof vr);
    vr.poly = f->poly;
    vr.poly_cap = POLY_CAP;
    vr.vis = f->vis;
    vr.vis_cap = VIS_CAP;
    st = vis_query(f->pd, p, a0, a1, full, &f->a, &vr);
    /* scratch is given back */
    ok = f->a.hi == before.hi && f->a.lo == before.lo;
    if (rc == -3)
        return 1;
    if (rc != 0)
        return ok && st == PLX_E_RANGE;
    /* 1e-9 relative; slivers of a few 1e-7 m^2 (viewer 1e-9 m from a wall,
     * narrow range) are held to 1e-9 m^2 absolute: there both sides are only
     * as exact as doubles of coordinates ~10^2 m allow (test_viewer_near_wall
     * checks one such sliver by hand) */
    ok = ok && st == PLX_OK && fabs(vr.area - rr.area) <= 1e-9 * fmax(rr.area, 1.0) &&
         vr.nvis == rr.nvisible;
    for (k = 0; ok && k < vr.nvis; k++)
        ok = vr.vis[k] == rr.visible[k];
    if (!ok && verbose) {
        print_message("p = (%.17g, %.17g) full %d [%g, %g]: st %d area %.15g ref %.15g, "
                      "nvis %u ref %u\n", p.x, p.y, full, a0, a1, st, vr.area, rr.area,
                      vr.nvis, rr.nvisible);
    }
    ref_vis_free(&rr);
    return ok;
}

/* Random free points of the scene, full turn and random ranges. */
/* make check (PLX_TEST_QUICK) checks a quarter of the random points;
 * check-full all of them. */
static int quick_share(int npts)
{
    return getenv("PLX_TEST_QUICK") && npts >= 40 ? npts / 4 : npts;
}

static void random_vis(fixture *f, int npts_full)
{
    int i, n = 0, bad = 0, tries = 0, npts = quick_share(npts_full);
    const double *bx = f->s.bounds;
    while (n < npts && tries < 50 * npts) {
        vec2 p;
        double a0 = urand() * 4 * PI - 2 * PI, a1 = a0 + urand() * 2.2 * PI;
        tries++;
        p.x = bx[0] + urand() * (bx[2] - bx[0]);
        p.y = bx[1] + urand() * (bx[3] - bx[1]);
        if (where(&f->s, p) != 0)
            continue;
        n++;
        for (i = 0; i < 2; i++)
            if (!vis_agrees(f, p, i == 0, a0, a1, bad < 5))
                bad++;
    }
    assert_int_equal(n, npts);
    assert_int_equal(bad, 0);
}

/* ---------------------------------------------------- brute-force helpers */

/* First crossing of the ray p->q (parameter > 0) with any occluder edge,
 * in plain doubles; *bld gets the building or -1 (none). */
static double brute_first(const scene *s, vec2 p, vec2 q, int *bld)
{
    double best = 1e300;
    uint32_t i, r, k;
    *bld = -1;
    for (i = 0; i < s->nbld; i++) {
        if (s->bld[i].min_height > 0)
            continue;
        for (r = 0; r < s->bld[i].ring_count; r++) {
            const scene_ring *g = &s->rings[s->bld[i].ring_first + r];
            for (k = 0; k < g->count; k++) {
                vec2 a = s->pts[g->first + k], b = s->pts[g->first + (k + 1) % g->count];
                double rx = q.x - p.x, ry = q.y - p.y, sx = b.x - a.x, sy = b.y - a.y;
                double den = rx * sy - ry * sx, t, u;
                if (den == 0.0)
                    continue;
                t = ((a.x - p.x) * sy - (a.y - p.y) * sx) / den;
                u = ((a.x - p.x) * ry - (a.y - p.y) * rx) / den;
                if (t > 0 && u >= 0 && u <= 1 && t < best) {
                    best = t;
                    *bld = (int)i;
                }
            }
        }
    }
    return best;
}

/* Checks locate and shoot at random points (random directions avoid
 * degenerate grazing, which the hand-made tests cover). */
static void random_locate_shoot(fixture *f, int npts_full)
{
    int n, bad = 0, npts = quick_share(npts_full);
    const double *bx = f->s.bounds;
    static const double dirs[4][2] = { { 1, 0 }, { 0, 1 }, { -1, 0 }, { 0, -1 } };
    for (n = 0; n < npts; n++) {
        vec2 p, q;
        int w, q4, bb;
        double ang, bt;
        polar_hit h;
        p.x = bx[0] + urand() * (bx[2] - bx[0]);
        p.y = bx[1] + urand() * (bx[3] - bx[1]);
        w = where(&f->s, p);
        for (q4 = 0; q4 < 4; q4++) {
            int32_t own, r = polar_locate(f->pd, q4, p, &own);
            if (w == 1 && r != -3)
                bad++;
            if (w == 2 && r != -2)
                bad++;
            if (w == 0) {
                /* owner = first building met by the start ray of the quadrant */
                vec2 e;
                e.x = p.x + dirs[q4][0] * 1e4;
                e.y = p.y + dirs[q4][1] * 1e4;
                brute_first(&f->s, p, e, &bb);
                if (r < 0 || own != bb)
                    bad++;
            }
        }
        if (w != 0) {
            if (polar_shoot(f->pd, p, 1.0, 0.5, &h) != PLX_E_RANGE)
                bad++;
            continue;
        }
        ang = urand() * 2 * PI;
        q.x = p.x + cos(ang) * 1e4;
        q.y = p.y + sin(ang) * 1e4;
        bt = brute_first(&f->s, p, q, &bb);
        if (polar_shoot_to(f->pd, p, q, 0, &h) != PLX_OK) {
            bad++;
            continue;
        }
        if (bb < 0) {
            if (h.bld != -1)
                bad++;
        } else if (fabs(h.t - bt) > 1e-9 * (1 + bt) || (h.bld != bb && h.bld2 != bb)) {
            bad++;
        }
    }
    assert_int_equal(bad, 0);
}

/* ------------------------------------------------------- random scenes */

static void scene_boxes(fixture *f, int n, int rotated)
{
    int i;
    for (i = 0; i < n; i++) {
        double x = urand() * 150, y = urand() * 150, w = 2 + urand() * 14, h = 2 + urand() * 14;
        if (rotated && urand() < 0.6)
            add_rotated_box(f, x, y, w, h, urand() * PI);
        else
            assert_true(ref_scene_add_box(&f->s, x, y, x + w, y + h, 10, 0) >= 0);
    }
}

static void test_random_boxes(void **state)
{
    int k;
    (void)state;
    for (k = 0; k < 4; k++) {
        fixture *f = fixture_new();
        rnd_state = 1000u + (uint32_t)k;
        scene_boxes(f, 25 + 10 * k, 0);
        fixture_build(f);
        random_vis(f, 150);
        random_locate_shoot(f, 400);
        fixture_free(f);
    }
}

static void test_random_rotated(void **state)
{
    int k;
    (void)state;
    for (k = 0; k < 4; k++) {
        fixture *f = fixture_new();
        rnd_state = 2000u + (uint32_t)k;
        scene_boxes(f, 25 + 10 * k, 1);
        fixture_build(f);
        random_vis(f, 150);
        random_locate_shoot(f, 400);
        fixture_free(f);
    }
}

/* Terraces of boxes sharing walls exactly, L-shapes, a courtyard with a
 * kiosk inside, a raised bridge. */
static void test_random_mixed_city(void **state)
{
    int k, i, j;
    (void)state;
    for (k = 0; k < 3; k++) {
        fixture *f = fixture_new();
        rnd_state = 3000u + (uint32_t)k;
        for (i = 0; i < 3; i++) {
            double y0 = 10 + 40 * i, x = 5 + urand() * 5;
            for (j = 0; j < 5; j++) {
                double w = 4 + floor(urand() * 6), h = 8 + floor(urand() * 8);
                assert_true(ref_scene_add_box(&f->s, x, y0, x + w, y0 + h, 10, 0) >= 0);
                x += w;                         /* next one shares the wall */
            }
            add_l_shape(f, 70 + urand() * 10, y0, 12, 14);
        }
        add_courtyard(f, 100, 20, 40, 40, 8);
        assert_true(ref_scene_add_box(&f->s, 115, 35, 120, 40, 5, 0) >= 0);  /* kiosk */
        assert_true(ref_scene_add_box(&f->s, 20, 25, 60, 30, 12, 6) >= 0);   /* raised */
        fixture_build(f);
        random_vis(f, 250);
        random_locate_shoot(f, 400);
        fixture_free(f);
    }
}

/* Buildings overlapping by centimetres, as in real map data. */
static void test_random_overlaps(void **state)
{
    fixture *f = fixture_new();
    int i;
    (void)state;
    rnd_state = 4000u;
    for (i = 0; i < 12; i++) {
        double x = 10 + 9.97 * i, y = 10 + urand() * 0.2;
        assert_true(ref_scene_add_box(&f->s, x, y, x + 10, y + 12, 10, 0) >= 0);
        add_rotated_box(f, x + 2, 40 + urand() * 0.1, 10.05, 8, 0.01 * (i - 6));
    }
    fixture_build(f);
    random_vis(f, 200);
    random_locate_shoot(f, 400);
    fixture_free(f);
}

/* Dense heaps of rotated boxes crossing each other everywhere: many
 * rounded crossing points, which the sweep must still accept. */
static void test_random_dense_overlaps(void **state)
{
    int k, i;
    (void)state;
    for (k = 0; k < 2; k++) {
        fixture *f = fixture_new();
        rnd_state = 4100u + (uint32_t)k;
        for (i = 0; i < 50; i++)
            add_rotated_box(f, urand() * 40, urand() * 40, 3 + urand() * 10, 3 + urand() * 10,
                            urand() * PI);
        fixture_build(f);
        random_vis(f, 40);
        random_locate_shoot(f, 300);
        fixture_free(f);
    }
}

/* ------------------------------------------------------ degenerate cases */

static void expect_all(fixture *f, const vec2 *pts, int n)
{
    int i, k, bad = 0;
    for (i = 0; i < n; i++) {
        if (!vis_agrees(f, pts[i], 1, 0, 0, 1))
            bad++;
        for (k = 0; k < 8; k++)
            if (!vis_agrees(f, pts[i], 0, k * PI / 4, k * PI / 4 + PI / 3, 1))
                bad++;
    }
    assert_int_equal(bad, 0);
}

static void test_viewer_on_edge_extension(void **state)
{
    fixture *f = fixture_new();
    vec2 p[4] = { { 20, 0 }, { -5, 10 }, { 0, -7 }, { 10, 33 } };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 30, -20, 40, 0, 10, 0) >= 0);  /* same line y=0 */
    fixture_build(f);
    expect_all(f, p, 4);
    fixture_free(f);
}

static void test_viewer_aligned_with_two_vertices(void **state)
{
    fixture *f = fixture_new();
    vec2 p[3] = { { 0, 0 }, { 45, 45 }, { 25, 25 } };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 10, 10, 20, 20, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 30, 30, 40, 40, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 50, 20, 60, 30, 10, 0) >= 0);
    fixture_build(f);
    expect_all(f, p, 3);
    fixture_free(f);
}

static void test_viewer_near_wall(void **state)
{
    fixture *f = fixture_new();
    vec2 p[4] = { { 10 + 1e-9, 5 }, { 5, -1e-9 }, { 10 + 1e-9, 10 + 1e-9 }, { 12, 5 } };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 20, 0, 30, 10, 10, 0) >= 0);
    fixture_build(f);
    expect_all(f, p, 4);
    /* sector [90, 150] degrees from (10 + d, 5): a strip of width d along the
     * wall up to the corner (10, 10) (area 5 d), then the wedge between the
     * vertical x = 10 + d and the ray through the corner up to y = 60, widths
     * d and 11 d (area 300 d); terms in d^2 are below 1e-18 */
    {
        double d = p[0].x - 10.0;
        vis_result r;
        memset(&r, 0, sizeof r);
        assert_int_equal(vis_query(f->pd, p[0], PI / 2, PI / 2 + PI / 3, 0, &f->a, &r), PLX_OK);
        assert_true(fabs(r.area - 305.0 * d) <= 1e-8 * 305.0 * d);
        assert_int_equal(r.nvis, 1);
    }
    fixture_free(f);
}

static void test_ray_grazing_vertex(void **state)
{
    fixture *f = fixture_new();
    vec2 p[2] = { { -10, -10 }, { -20, -30 } };
    polar_hit h;
    vec2 q = { 0, 10 };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10, 0) >= 0);   /* corner (0,10) */
    assert_true(ref_scene_add_box(&f->s, 5, 25, 15, 35, 10, 0) >= 0);  /* behind it */
    fixture_build(f);
    expect_all(f, p, 2);
    /* the exact ray through the corner passes and meets the second box */
    assert_int_equal(polar_shoot_to(f->pd, p[0], q, 0, &h), PLX_OK);
    assert_int_equal(h.bld, 1);
    assert_true(fabs(h.pt.x - 7.5) < 1e-9 && fabs(h.pt.y - 25) < 1e-9);
    /* turned clockwise it enters the first box at the corner */
    assert_int_equal(polar_shoot_to(f->pd, p[0], q, -1, &h), PLX_OK);
    assert_int_equal(h.bld, 0);
    assert_true(fabs(h.pt.x) < 1e-9 && fabs(h.pt.y - 10) < 1e-9);
    assert_int_equal(polar_shoot_to(f->pd, p[0], q, 1, &h), PLX_OK);
    assert_int_equal(h.bld, 1);
    fixture_free(f);
}

static void test_shared_walls(void **state)
{
    fixture *f = fixture_new();
    vec2 p[5] = { { 10, -5 }, { 10, 20 }, { 25, 5 }, { -3, 10 }, { 5, 12 } };
    polar_hit h;
    vec2 q = { 10, 50 };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 10, 0, 20, 10, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 20, 2, 24, 8, 10, 0) >= 0);   /* T-junction */
    fixture_build(f);
    expect_all(f, p, 5);
    /* a ray along the shared wall is blocked where the wall starts */
    assert_int_equal(polar_shoot_to(f->pd, p[0], q, 0, &h), PLX_OK);
    assert_true(h.bld == 0 || h.bld == 1);
    assert_true(fabs(h.pt.y) < 1e-9);
    fixture_free(f);
}

static void test_collinear_neighbour_edges(void **state)
{
    fixture *f = fixture_new();
    vec2 p[4] = { { -5, 0 }, { 30, 0 }, { 12.5, -3 }, { 12.5, 4 } };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 15, 0, 25, 10, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 0, -10, 25, -6, 10, 0) >= 0);
    fixture_build(f);
    expect_all(f, p, 4);
    fixture_free(f);
}

static void test_courtyard_and_kiosk(void **state)
{
    fixture *f = fixture_new();
    vec2 p[3] = { { 110, 50 }, { 125, 30 }, { 90, 10 } };
    vis_result r;
    (void)state;
    add_courtyard(f, 100, 20, 40, 40, 8);
    assert_true(ref_scene_add_box(&f->s, 115, 35, 120, 40, 5, 0) >= 0);
    fixture_build(f);
    expect_all(f, p, 3);
    /* inside the courtyard only the courtyard is seen: area 24^2 - 5^2
     * seen from beside the kiosk is less than that, but the total never more */
    memset(&r, 0, sizeof r);
    assert_int_equal(vis_query(f->pd, p[0], 0, 0, 1, &f->a, &r), PLX_OK);
    assert_true(r.area <= 24.0 * 24.0 - 25.0 + 1e-9);
    assert_true(r.nvis == 2);
    fixture_free(f);
}

/* A lattice of boxes with aligned corners, some sharing walls, some touching
 * at one corner only, and an octagon with chamfered corners: viewers on the
 * lines through two vertices, on the extensions of walls, on the axes of
 * vertices, and exactly diagonal to corners. Many cones get split by a
 * corner whose later half closes at once on that corner's wall, or walks
 * along a row of corners lying exactly on one of its limit rays. */
static vec2 lattice_scene(fixture *f)
{
    static const double oct[16] = { 62, 40, 66, 40, 68, 42, 68, 46, 66, 48, 62, 48, 60, 46,
                                    60, 42 };
    vec2 lo = { 0, 0 };
    int i, j;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 4; j++) {
            double x = 10.0 * i, y = 10.0 * j, w = (i == 1 ? 10.0 : 6.0);
            assert_true(ref_scene_add_box(&f->s, x, y, x + w, y + 6, 10, 0) >= 0);
        }
    /* touching the lattice at the corner (46, 36) only */
    assert_true(ref_scene_add_box(&f->s, 36, 36, 46, 46, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 46, 30, 52, 36, 10, 0) >= 0);
    assert_true(add_poly(f, oct, 8) >= 0);
    return lo;
}

static void test_lattice_alignments(void **state)
{
    fixture *f = fixture_new();
    vec2 p[] = {
        { -4, -4 }, { 8, 8 }, { 8, -2 }, { -2, 8 }, { 28, 28 }, { 48, 8 },  /* diagonals */
        { 8, 40 }, { -5, 6 }, { 48, 0 }, { 3, 48 },      /* wall extensions, vertex axes */
        { 58, 48 }, { 70, 40 }, { 56, 24 }, { 46, 50 },  /* chamfers, touching corner */
        { 52, 40 }, { 41, 29 }, { 9, 3 }, { 58.5, 29 },
    };
    (void)state;
    lattice_scene(f);
    fixture_build(f);
    expect_all(f, p, (int)(sizeof p / sizeof p[0]));
    fixture_free(f);
}

/* Exact rays (side 0) against the two one-sided rays, each walked alone:
 * the exact ray is blocked where the farther of them is (the one turned
 * counter-clockwise on a tie), to the bit. Rays at random, through
 * vertices, along walls, along the axes of vertices. */
static int shoot_same(fixture *f, vec2 p, vec2 q, int *parted)
{
    polar_hit h, hp, hm;
    const polar_hit *w;
    plx_status st = polar_shoot_to(f->pd, p, q, 0, &h);
    if (polar_shoot_to(f->pd, p, q, 1, &hp) != st || polar_shoot_to(f->pd, p, q, -1, &hm) != st)
        return 0;
    if (st != PLX_OK)
        return 1;
    w = hm.t > hp.t ? &hm : &hp;
    if (hp.seg != hm.seg)
        (*parted)++;
    return h.bld == w->bld && h.bld2 == w->bld2 && h.seg == w->seg && h.t == w->t &&
           h.pt.x == w->pt.x && h.pt.y == w->pt.y && h.steps <= hp.steps + hm.steps;
}

static void test_shoot_exact_once(void **state)
{
    fixture *f = fixture_new();
    int n, bad = 0, parted = 0, rays = 0;
    (void)state;
    rnd_state = 6000u;
    lattice_scene(f);
    add_rotated_box(f, 75, 5, 8, 5, 0.6);
    fixture_build(f);
    for (n = 0; n < 3000; n++) {
        const vec2 *v = f->pd->pts;
        uint32_t nv = f->pd->npts, a = (uint32_t)(urand() * nv), b = (uint32_t)(urand() * nv);
        vec2 p, q;
        double t = urand();
        switch (n % 5) {
        case 0:                         /* random */
            p.x = -8 + urand() * 96;
            p.y = -8 + urand() * 66;
            q.x = p.x + urand() * 20 - 10;
            q.y = p.y + urand() * 20 - 10;
            break;
        case 1:                         /* towards a vertex */
            p.x = -8 + urand() * 96;
            p.y = -8 + urand() * 66;
            q = v[a];
            break;
        case 2:                         /* on the line through two vertices */
            p.x = v[a].x + (t * 3 - 1) * (v[b].x - v[a].x);
            p.y = v[a].y + (t * 3 - 1) * (v[b].y - v[a].y);
            q = urand() < 0.5 ? v[a] : v[b];
            break;
        case 3:                         /* on a vertex's axis, along the axis */
            p = v[a];
            if (urand() < 0.5)
                p.x += urand() * 20 - 10;
            else
                p.y += urand() * 20 - 10;
            q = v[a];
            break;
        default:                        /* exactly diagonal from a vertex */
            t = floor(urand() * 12) - 6;
            p.x = v[a].x + t;
            p.y = v[a].y + (urand() < 0.5 ? t : -t);
            q = v[a];
            break;
        }
        if (p.x == q.x && p.y == q.y)
            continue;
        rays++;
        if (!shoot_same(f, p, q, &parted)) {
            if (bad < 5)
                print_message("ray (%.17g, %.17g) -> (%.17g, %.17g) differs\n", p.x, p.y, q.x,
                              q.y);
            bad++;
        }
    }
    assert_int_equal(bad, 0);
    /* the one-sided rays parted at a vertex on hundreds of the rays */
    assert_true(parted > 300);
    assert_true(rays > 2900);
    fixture_free(f);
}

static void test_errors(void **state)
{
    fixture *f = fixture_new();
    vis_result r;
    polar_hit h;
    vec2 in = { 5, 5 }, out = { -1000, 0 }, on = { 10, 5 }, yard = { 120, 40 };
    vec2 corner = { 10, 10 };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10, 0) >= 0);
    add_courtyard(f, 100, 20, 40, 40, 8);
    fixture_build(f);
    memset(&r, 0, sizeof r);
    assert_int_equal(vis_query(f->pd, in, 0, 0, 1, &f->a, &r), PLX_E_RANGE);
    assert_int_equal(vis_query(f->pd, out, 0, 0, 1, &f->a, &r), PLX_E_RANGE);
    assert_int_equal(vis_query(f->pd, on, 0, 0, 1, &f->a, &r), PLX_E_RANGE);
    assert_int_equal(vis_query(f->pd, corner, 0, 0, 1, &f->a, &r), PLX_E_RANGE);
    assert_int_equal(vis_query(f->pd, yard, 0, 0, 1, &f->a, &r), PLX_OK);
    assert_true(fabs(r.area - 24.0 * 24.0) < 1e-9);
    assert_int_equal(r.nvis, 1);
    assert_int_equal(polar_shoot(f->pd, in, 1, 0, &h), PLX_E_RANGE);
    assert_int_equal(polar_shoot(f->pd, out, 1, 0, &h), PLX_E_RANGE);
    assert_int_equal(polar_shoot(f->pd, yard, 0, 0, &h), PLX_E_INVALID);
    assert_int_equal(polar_locate(f->pd, 0, in, NULL), -3);
    assert_int_equal(polar_locate(f->pd, 0, out, NULL), -1);
    assert_int_equal(polar_locate(f->pd, 0, on, NULL), -2);
    assert_true(polar_locate(f->pd, 0, yard, NULL) >= 0);
    /* too small a caller buffer: counted, NOMEM, area still right */
    {
        vec2 small[3];
        memset(&r, 0, sizeof r);
        r.poly = small;
        r.poly_cap = 3;
        assert_int_equal(vis_query(f->pd, yard, 0, 0, 1, &f->a, &r), PLX_E_NOMEM);
        assert_true(r.npoly >= 4);
        assert_true(fabs(r.area - 24.0 * 24.0) < 1e-9);
    }
    fixture_free(f);
}

/* A hand-checkable view: one 10 x 10 box, viewer due west at distance 10.
 * Bounds [-50, 60]^2; hidden: the trapezoid between the rays through (0,0)
 * and (0,10) from x = 0 to x = 60. */
static void test_hand_area(void **state)
{
    fixture *f = fixture_new();
    vec2 p = { -10, 5 };
    vis_result r;
    double box = 110.0 * 110.0, shadow;
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10, 0) >= 0);
    fixture_build(f);
    /* the rays through (0,0) and (0,10) open by 0.5 m per metre: everything
     * between them beyond x = 0 is hidden (the box included), a trapezoid of
     * widths 10 (x = 0) and 70 (x = 60) */
    shadow = 0.5 * (10.0 + 70.0) * 60.0;
    memset(&r, 0, sizeof r);
    assert_int_equal(vis_query(f->pd, p, 0, 0, 1, &f->a, &r), PLX_OK);
    assert_true(fabs(r.area - (box - shadow)) < 1e-9 * box);
    assert_int_equal(r.nvis, 1);
    fixture_free(f);
}

/* -------------------------------------------------------- the structure */

/* The free regions of every quadrant tile the free space: their areas add
 * up to the box minus the footprints (no overlap in this scene). */
static void test_regions_tile_free_space(void **state)
{
    fixture *f = fixture_new();
    int q;
    double want, fp = 0;
    uint32_t i;
    (void)state;
    rnd_state = 77u;
    add_courtyard(f, 0, 0, 30, 30, 6);
    add_l_shape(f, 40, 0, 10, 12);
    add_rotated_box(f, 60, 5, 8, 4, 0.7);
    fixture_build(f);
    for (i = 0; i < f->s.nbld; i++) {
        uint32_t r;
        for (r = 0; r < f->s.bld[i].ring_count; r++) {
            const scene_ring *g = &f->s.rings[f->s.bld[i].ring_first + r];
            double a = 0;
            uint32_t k;
            for (k = 0; k < g->count; k++) {
                vec2 u = f->s.pts[g->first + k], v = f->s.pts[g->first + (k + 1) % g->count];
                a += u.x * v.y - v.x * u.y;
            }
            fp += 0.5 * a;      /* holes are clockwise: they subtract */
        }
    }
    want = (f->s.bounds[2] - f->s.bounds[0]) * (f->s.bounds[3] - f->s.bounds[1]) - fp;
    for (q = 0; q < 4; q++) {
        double got = 0;
        uint32_t n = polar_region_count(f->pd, q);
        assert_true(n > 10);
        for (i = 0; i < n; i++) {
            vec2 c[4];
            int32_t own;
            int solid, k;
            double a = 0;
            assert_int_equal(polar_region(f->pd, q, i, c, &own, &solid), 4);
            for (k = 0; k < 4; k++)
                a += c[k].x * c[(k + 1) % 4].y - c[(k + 1) % 4].x * c[k].y;
            assert_true(a >= -1e-6);
            if (!solid)
                got += 0.5 * a;
        }
        assert_true(fabs(got - want) < 1e-9 * want);
    }
    fixture_free(f);
}

/* Every region of every quadrant carries a label, and it is the object met
 * first by the quadrant's start ray from the region's points (a building,
 * or -1: the Bounds frame), checked by brute force at each region's
 * centroid, which polar_locate must also place in that region. */
static void test_every_region_labelled(void **state)
{
    static const double dirs[4][2] = { { 1, 0 }, { 0, 1 }, { -1, 0 }, { 0, -1 } };
    fixture *f = fixture_new();
    int q, frame_regions = 0, bld_regions = 0, bad = 0, checked = 0;
    uint32_t i;
    (void)state;
    rnd_state = 4711u;
    add_courtyard(f, 0, 0, 30, 30, 6);
    add_l_shape(f, 40, 0, 10, 12);
    add_rotated_box(f, 60, 5, 8, 4, 0.7);
    scene_boxes(f, 30, 1);
    fixture_build(f);
    for (q = 0; q < 4; q++) {
        uint32_t n = polar_region_count(f->pd, q);
        for (i = 0; i < n; i++) {
            vec2 c[4], m, e;
            int32_t own, own2;
            int solid, k, bb;
            double a = 0;
            assert_int_equal(polar_region(f->pd, q, i, c, &own, &solid), 4);
            assert_int_equal(solid, 0);
            assert_true(own >= -1 && own < (int32_t)f->s.nbld);
            for (k = 0; k < 4; k++)
                a += c[k].x * c[(k + 1) % 4].y - c[(k + 1) % 4].x * c[k].y;
            if (0.5 * a < 1e-6)
                continue;          /* a sliver: its centroid may sit on a side */
            m.x = 0.25 * (c[0].x + c[1].x + c[2].x + c[3].x);
            m.y = 0.25 * (c[0].y + c[1].y + c[2].y + c[3].y);
            if (where(&f->s, m) != 0)
                continue;
            checked++;
            if (polar_locate(f->pd, q, m, &own2) != (int32_t)i || own2 != own)
                bad++;
            e.x = m.x + dirs[q][0] * 1e4;
            e.y = m.y + dirs[q][1] * 1e4;
            brute_first(&f->s, m, e, &bb);
            if (bb != own)
                bad++;
            if (own < 0)
                frame_regions++;
            else
                bld_regions++;
        }
    }
    print_message("every region labelled: %d regions checked (%d by a building, %d by the frame)\n",
                  checked, bld_regions, frame_regions);
    assert_int_equal(bad, 0);
    assert_true(frame_regions > 0 && bld_regions > 0);
    assert_true(checked > 400);
    fixture_free(f);
}

static void test_memory_accounting(void **state)
{
    fixture *f = fixture_new();
    size_t by[4], used0, scratch0;
    (void)state;
    rnd_state = 5u;
    scene_boxes(f, 40, 1);
    ref_scene_finish(&f->s);
    used0 = f->a.used[PLX_PART_POLAR];
    scratch0 = f->a.used[PLX_PART_SCRATCH];
    assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
    polar_memory(f->pd, by);
    assert_true(by[0] > 0 && by[1] > 0 && by[2] > 0 && by[3] > 0);
    assert_true(by[0] + by[1] + by[2] + by[3] <= f->a.used[PLX_PART_POLAR] - used0);
    assert_true(by[0] + by[1] + by[2] + by[3] + 64 * 16 >= f->a.used[PLX_PART_POLAR] - used0);
    assert_int_equal(f->a.used[PLX_PART_SCRATCH], scratch0);
    assert_int_equal(f->a.hi, 0);
    fixture_free(f);
}

/* Every memory request failing in turn: NOMEM and nothing kept, until the
 * build succeeds. */
static void test_fault_injection(void **state)
{
    fixture *f = fixture_new();
    uint64_t k;
    (void)state;
    rnd_state = 9u;
    scene_boxes(f, 8, 1);
    ref_scene_finish(&f->s);
    k = polar_build_each_failure(&f->a, &f->s, &f->pd, 199);
    assert_true(k > 5);
    fixture_free(f);
}

static void test_first_object(void **state)
{
    fixture *f = fixture_new();
    vec2 p = { 0, 0 };
    (void)state;
    assert_true(ref_scene_add_box(&f->s, 10, 20, 12, 22, 10, 0) >= 0);  /* 0: NE, steep */
    assert_true(ref_scene_add_box(&f->s, 30, 5, 32, 40, 10, 0) >= 0);   /* 1: NE, shallow */
    assert_true(ref_scene_add_box(&f->s, -20, -5, -18, 5, 10, 0) >= 0); /* 2: due west */
    fixture_build(f);
    assert_int_equal(vis_first(f->pd, 0, p, &f->a), 1);   /* smallest angle from east */
    assert_int_equal(vis_first(f->pd, 1, p, &f->a), 2);   /* from north: reaches west */
    assert_int_equal(vis_first(f->pd, 2, p, &f->a), 2);
    assert_int_equal(vis_first(f->pd, 3, p, &f->a), -1);
    fixture_free(f);
}

/* ------------------------------------------------------- the fixtures */

/* Random free points over the bundled fixtures, full-turn visibility (and a
 * range for one point in eight) compared with ref_vis_fast (checked against
 * ref_vis on every small scene above, and on the real district by
 * test_fixture_helsinki_slow_ref): areas to 1e-9 relative, identical visible
 * sets. ref_vis_fast costs from 0.1 ms (grid-4x4) to about 7 ms
 * (helsinki-centre) per query; the default run holds 12,000 points, 2,000
 * of them on the real district. PLX_TEST_POINTS=N asks for about N points in
 * all (same proportions), PLX_TEST_QUICK for 1/20. The reference runs in two
 * threads (the diagrams and the prepared reference are read only; each
 * thread has its own scratch arena). */

#define FIX_THREADS 2
#define FIX_SCRATCH ((size_t)4 << 20)

typedef struct fix_job {
    const scene *s;
    const ref_fast *rf;
    const polar *pd;
    const vec2 *pts;
    int n, tid;
    int bad, checked;
    char msg[512];
} fix_job;

static int fix_check(fix_job *j, arena *a, vec2 p, int full, double a0, double a1)
{
    ref_vis_result rr;
    vis_result vr;
    uint32_t k, vis[4096];
    plx_status st;
    int rc, ok;
    rc = full ? ref_fast_vis(j->rf, p.x, p.y, &rr)
              : ref_fast_vis_range(j->rf, p.x, p.y, a0, a1, &rr);
    memset(&vr, 0, sizeof vr);
    vr.vis = vis;
    vr.vis_cap = 4096;
    st = vis_query(j->pd, p, a0, a1, full, a, &vr);
    ok = rc == 0 && st == PLX_OK && fabs(vr.area - rr.area) <= 1e-9 * fmax(rr.area, 1.0) &&
         vr.nvis == rr.nvisible && a->hi == 0;
    for (k = 0; ok && k < vr.nvis; k++)
        ok = vr.vis[k] == rr.visible[k];
    if (!ok && j->msg[0] == '\0')
        snprintf(j->msg, sizeof j->msg, "p = (%.17g, %.17g) full %d [%.17g, %.17g]: rc %d st %d "
                 "area %.15g ref %.15g, nvis %u ref %u", p.x, p.y, full, a0, a1, rc, st,
                 vr.area, rr.area, vr.nvis, rr.nvisible);
    ref_vis_free(&rr);
    return ok;
}

static void *fix_worker(void *arg)
{
    fix_job *j = arg;
    void *mem = malloc(FIX_SCRATCH);
    arena a;
    int i;
    if (!mem) {
        j->bad = -1;
        return NULL;
    }
    arena_init(&a, mem, FIX_SCRATCH);
    for (i = j->tid; i < j->n; i += FIX_THREADS) {
        double a0 = (i % 13) * 0.5 - 3.0, a1 = a0 + 0.3 + (i % 7) * 0.9;
        j->checked++;
        if (!fix_check(j, &a, j->pts[i], 1, 0, 0))
            j->bad++;
        if (i % 8 == 3 && !fix_check(j, &a, j->pts[i], 0, a0, a1))
            j->bad++;
    }
    free(mem);
    return NULL;
}

/* Points wanted for a fixture whose default share is n. */
static int fix_points(int n)
{
    const char *e = getenv("PLX_TEST_POINTS");
    if (e && atoi(e) > 0)
        n = (int)((double)n * atoi(e) / 12000.0 + 0.5);
    else if (getenv("PLX_TEST_QUICK"))
        n /= 20;
    return n < 1 ? 1 : n;
}

static void fixture_points(const char *path, int npts)
{
    plx_engine *e;
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    const scene *s;
    polar *pd;
    ref_fast *rf;
    vec2 *pts;
    fix_job job[FIX_THREADS];
    pthread_t th[FIX_THREADS];
    int i, n = 0, tries = 0, bad = 0, checked = 0;
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    assert_int_equal(plx_engine_new((size_t)256 << 20, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, path), PLX_OK);
    s = e->sc;
    assert_int_equal(polar_build(&e->mem, s, &pd), PLX_OK);
    rf = ref_fast_new(s);
    assert_non_null(rf);
    pts = malloc((size_t)npts * sizeof *pts);
    assert_non_null(pts);
    while (n < npts && tries < 100 * npts) {
        vec2 p;
        tries++;
        p.x = s->bounds[0] + urand() * (s->bounds[2] - s->bounds[0]);
        p.y = s->bounds[1] + urand() * (s->bounds[3] - s->bounds[1]);
        if (where(s, p) == 0)
            pts[n++] = p;
    }
    assert_int_equal(n, npts);
    for (i = 0; i < FIX_THREADS; i++) {
        memset(&job[i], 0, sizeof job[i]);
        job[i].s = s;
        job[i].rf = rf;
        job[i].pd = pd;
        job[i].pts = pts;
        job[i].n = n;
        job[i].tid = i;
        assert_int_equal(pthread_create(&th[i], NULL, fix_worker, &job[i]), 0);
    }
    for (i = 0; i < FIX_THREADS; i++) {
        pthread_join(th[i], NULL);
        if (job[i].msg[0])
            print_message("%s: %s\n", path, job[i].msg);
        bad += job[i].bad;
        checked += job[i].checked;
    }
    print_message("%s: %d free points, %d mismatches\n", path, checked, bad);
    assert_int_equal(checked, n);
    assert_int_equal(bad, 0);
    free(pts);
    ref_fast_free(rf);
    plx_engine_free(e);
}

static void test_fixture_grid(void **state)
{
    (void)state;
    rnd_state = 6001u;
    fixture_points("fixtures/grid-4x4.geojson", fix_points(8700));
}

static void test_fixture_oldtown(void **state)
{
    (void)state;
    rnd_state = 6002u;
    fixture_points("fixtures/oldtown-8x8.geojson", fix_points(1100));
}

static void test_fixture_eixample(void **state)
{
    (void)state;
    rnd_state = 6003u;
    fixture_points("fixtures/eixample-4x4.geojson", fix_points(200));
}

static void test_fixture_helsinki(void **state)
{
    (void)state;
    rnd_state = 6004u;
    fixture_points("fixtures/helsinki-centre.geojson", fix_points(2000));
}

/* The fast reference against the O(E^2) one on the real district (about
 * 2 s per point): the same answer, and the engine's. */
static void test_fixture_helsinki_slow_ref(void **state)
{
    plx_engine *e;
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    const scene *s;
    polar *pd;
    int n = 0, tries = 0;
    (void)state;
    if (getenv("PLX_TEST_QUICK")) /* about 2 s a point: check-full only */
        skip();
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    assert_int_equal(plx_engine_new((size_t)256 << 20, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, "fixtures/helsinki-centre.geojson"), PLX_OK);
    s = e->sc;
    assert_int_equal(polar_build(&e->mem, s, &pd), PLX_OK);
    rnd_state = 6005u;
    while (n < 1 && tries < 100) {
        ref_vis_result rr;
        vis_result vr;
        uint32_t k, vis[4096];
        vec2 p;
        tries++;
        p.x = s->bounds[0] + urand() * (s->bounds[2] - s->bounds[0]);
        p.y = s->bounds[1] + urand() * (s->bounds[3] - s->bounds[1]);
        if (where(s, p) != 0)
            continue;
        n++;
        assert_int_equal(ref_vis(s, p.x, p.y, &rr), 0);
        assert_true(fast_agrees(s, p, 1, 0, 0, 0, &rr));
        memset(&vr, 0, sizeof vr);
        vr.vis = vis;
        vr.vis_cap = 4096;
        assert_int_equal(vis_query(pd, p, 0, 0, 1, &e->mem, &vr), PLX_OK);
        assert_true(fabs(vr.area - rr.area) <= 1e-9 * rr.area);
        assert_int_equal(vr.nvis, rr.nvisible);
        for (k = 0; k < vr.nvis; k++)
            assert_int_equal(vr.vis[k], rr.visible[k]);
        ref_vis_free(&rr);
    }
    assert_int_equal(n, 1);
    plx_engine_free(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hand_area),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_viewer_on_edge_extension),
        cmocka_unit_test(test_viewer_aligned_with_two_vertices),
        cmocka_unit_test(test_viewer_near_wall),
        cmocka_unit_test(test_ray_grazing_vertex),
        cmocka_unit_test(test_shared_walls),
        cmocka_unit_test(test_collinear_neighbour_edges),
        cmocka_unit_test(test_courtyard_and_kiosk),
        cmocka_unit_test(test_lattice_alignments),
        cmocka_unit_test(test_shoot_exact_once),
        cmocka_unit_test(test_first_object),
        cmocka_unit_test(test_regions_tile_free_space),
        cmocka_unit_test(test_every_region_labelled),
        cmocka_unit_test(test_memory_accounting),
        cmocka_unit_test(test_fault_injection),
        cmocka_unit_test(test_random_boxes),
        cmocka_unit_test(test_random_rotated),
        cmocka_unit_test(test_random_mixed_city),
        cmocka_unit_test(test_random_overlaps),
        cmocka_unit_test(test_random_dense_overlaps),
        cmocka_unit_test(test_fixture_grid),
        cmocka_unit_test(test_fixture_oldtown),
        cmocka_unit_test(test_fixture_eixample),
        cmocka_unit_test(test_fixture_helsinki),
        cmocka_unit_test(test_fixture_helsinki_slow_ref),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
