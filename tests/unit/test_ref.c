/* test_ref: the brute-force references checked on hand-computable cases.
 *
 * Expected values are worked out here by plain geometry (shadow trapezoids,
 * shoelace areas of hand-listed polygons, the point-lamp formula), never by
 * calling the code under test another way.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <cmocka.h>

#include "base/scene.h"
#include "ref_scene.h"
#include "ref_vis.h"
#include "ref_light.h"

#define PI 3.14159265358979323846

/* ---------------------------------------------------------------- helpers */

static void check_close(double got, double want, double rel, const char *what)
{
    double tol = rel * (fabs(want) > 1.0 ? fabs(want) : 1.0);
    if (!(fabs(got - want) <= tol)) {
        print_error("%s: got %.17g, want %.17g (tol %.3g)\n", what, got, want, tol);
        fail();
    }
}

/* Shoelace area of a polygon given as n x,y pairs (absolute value). */
static double shoelace(const double *xy, int n)
{
    double a = 0.0;
    int i;
    for (i = 0; i < n; i++) {
        int j = (i + 1) % n;
        a += xy[2 * i] * xy[2 * j + 1] - xy[2 * j] * xy[2 * i + 1];
    }
    return fabs(0.5 * a);
}

static double bounds_area(const scene *s)
{
    return (s->bounds[2] - s->bounds[0]) * (s->bounds[3] - s->bounds[1]);
}

/* Shadow of a segment of width w facing p squarely at distance a, cut by a
 * box edge parallel to it at distance X: trapezoid w/(2a) (X^2 - a^2). */
static double trapezoid(double w, double a, double X)
{
    return w / (2.0 * a) * (X * X - a * a);
}

/* Runs ref_vis and checks area, vertex count and visible set. */
static void check_vis(const scene *s, double px, double py, double area,
                      uint32_t nverts, const uint32_t *vis, uint32_t nvis)
{
    ref_vis_result r;
    uint32_t i;
    assert_int_equal(ref_vis(s, px, py, &r), 0);
    check_close(r.area, area, 1e-12, "visibility area");
    assert_int_equal(r.nverts, nverts);
    assert_int_equal(r.nvisible, nvis);
    for (i = 0; i < nvis; i++)
        assert_int_equal(r.visible[i], vis[i]);
    ref_vis_free(&r);
}

static void check_range(const scene *s, double px, double py, double a0,
                        double a1, double area, uint32_t nverts)
{
    ref_vis_result r;
    assert_int_equal(ref_vis_range(s, px, py, a0, a1, &r), 0);
    check_close(r.area, area, 1e-12, "sector area");
    assert_int_equal(r.nverts, nverts);
    ref_vis_free(&r);
}

static int vis_code(const scene *s, double px, double py)
{
    ref_vis_result r;
    int rc = ref_vis(s, px, py, &r);
    ref_vis_free(&r);
    return rc;
}

/* Unblocked single-lamp term at P with normal n. */
static double lamp_formula(const double L[3], double I, double R,
                           const double P[3], const double n[3])
{
    double v[3] = { L[0] - P[0], L[1] - P[1], L[2] - P[2] };
    double d = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double c = (n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / d;
    double x = d / R, w = 1.0 - x * x * x * x;
    if (w < 0.0) w = 0.0;
    if (c < 0.0) c = 0.0;
    return I * c / (d * d) * w * w;
}

static const double UP[3] = { 0.0, 0.0, 1.0 };
static const double WEST[3] = { -1.0, 0.0, 0.0 };
static const double EAST[3] = { 1.0, 0.0, 0.0 };

static double E_at(const scene *s, double x, double y, double z, const double n[3])
{
    double P[3];
    P[0] = x; P[1] = y; P[2] = z;
    return ref_illuminance(s, P, n);
}

static int blocked(const scene *s, const double L[3], double x, double y, double z)
{
    double P[3];
    P[0] = x; P[1] = y; P[2] = z;
    return ref_segment_blocked(s, L, P);
}

/* ------------------------------------------------------------ ref_scene */

static void test_scene_builder(void **state)
{
    /* clockwise outer ring, closed, with a duplicate vertex */
    const double xy[] = { 0, 0, 0, 10, 0, 10, 10, 10, 10, 0, 0, 0,
                          /* counter-clockwise hole */ 2, 2, 4, 2, 4, 4, 2, 4 };
    const uint32_t rn[2] = { 6, 4 };
    scene s;
    const vec2 *p;
    (void)state;
    ref_scene_init(&s);
    assert_int_equal(ref_scene_add_building(&s, xy, rn, 2, 9.0, 0.0), 0);
    ref_scene_finish(&s);
    assert_int_equal(s.nrings, 2);
    assert_int_equal(s.rings[0].count, 4);
    assert_int_equal(s.rings[1].count, 4);
    p = s.pts + s.rings[0].first;
    /* outer made ccw: (10,0) -> (10,10) -> (0,10) -> (0,0) */
    assert_true(p[0].x == 10 && p[0].y == 0 && p[1].x == 10 && p[1].y == 10);
    assert_true(p[3].x == 0 && p[3].y == 0);
    p = s.pts + s.rings[1].first;
    /* hole made cw: (2,4) -> (4,4) -> (4,2) -> (2,2) */
    assert_true(p[0].x == 2 && p[0].y == 4 && p[1].x == 4 && p[1].y == 4);
    assert_true(s.bounds[0] == -50 && s.bounds[1] == -50 &&
                s.bounds[2] == 60 && s.bounds[3] == 60);
    assert_int_equal(ref_footprint_where(&s, 0, 1, 1), REF_IN);
    assert_int_equal(ref_footprint_where(&s, 0, 3, 3), REF_OUT);
    assert_int_equal(ref_footprint_where(&s, 0, 2, 3), REF_ON);
    assert_int_equal(ref_footprint_where(&s, 0, 10, 5), REF_ON);
    assert_int_equal(ref_footprint_where(&s, 0, 11, 5), REF_OUT);
    {
        const double bad[] = { 0, 0, 1, 1, 2, 2 };
        uint32_t n3 = 3;
        assert_int_equal(ref_scene_add_building(&s, bad, &n3, 1, 5, 0), -1);
        assert_int_equal(s.nbld, 1);
    }
    ref_scene_free(&s);
}

/* ------------------------------------------------------------ visibility */

static void test_vis_empty(void **state)
{
    scene s;
    (void)state;
    ref_scene_init(&s);
    s.bounds[0] = 0; s.bounds[1] = 0; s.bounds[2] = 100; s.bounds[3] = 60;
    check_vis(&s, 30, 20, 6000.0, 4, NULL, 0);
    check_vis(&s, 99.5, 0.25, 6000.0, 4, NULL, 0);
    assert_int_equal(vis_code(&s, 101, 20), -1);
    assert_int_equal(vis_code(&s, 100, 20), -2);
    assert_int_equal(vis_code(&s, 0, 0), -2);
    ref_scene_free(&s);
}

static void test_vis_range_empty(void **state)
{
    scene s;
    (void)state;
    ref_scene_init(&s);
    s.bounds[0] = 0; s.bounds[1] = 0; s.bounds[2] = 100; s.bounds[3] = 60;
    /* quarter of the box seen from its centre: p, (100,30), (100,60), (50,60) */
    check_range(&s, 50, 30, 0.0, PI / 2, 1500.0, 4);
    check_range(&s, 50, 30, PI, 1.5 * PI, 1500.0, 4);
    /* wrapping 90 degree sector around +x: right half minus two 30x30/2
     * triangles; p, (80,0), (100,0), (100,60), (80,60) */
    check_range(&s, 50, 30, 1.75 * PI, 0.25 * PI, 3000.0 - 900.0, 5);
    check_range(&s, 50, 30, -0.25 * PI, 0.25 * PI, 3000.0 - 900.0, 5);
    /* half turn: p lies on a straight edge and is no vertex */
    check_range(&s, 50, 30, 0.0, PI, 3000.0, 4);
    /* full turn and empty sector */
    check_range(&s, 50, 30, 0.0, 2 * PI, 6000.0, 4);
    check_range(&s, 50, 30, -PI, 3 * PI, 6000.0, 4);
    check_range(&s, 50, 30, 1.0, 1.0, 0.0, 0);
    ref_scene_free(&s);
}

static void test_vis_one_square(void **state)
{
    scene s;
    const uint32_t v0[1] = { 0 };
    double shadow[10];
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 10, -2, 14, 2, 10, 0);
    ref_scene_finish(&s);  /* bounds -40,-52,64,52: area 104 x 104 */
    assert_true(bounds_area(&s) == 10816.0);
    /* on the axis, facing the west wall: shadow to the east box edge */
    check_vis(&s, 0, 0, 10816.0 - trapezoid(4, 10, 64), 8, v0, 1);
    /* south of the square, facing the south wall: shadow to y = 52 */
    check_vis(&s, 12, -20, 10816.0 - trapezoid(4, 18, 72), 8, v0, 1);
    /* north-west: sees the west and north walls; the shadow is bounded by
     * the rays through (10,-2) and (14,2), which meet y = -52 at
     * x = 10 * 72 / 22 and x = 56 */
    shadow[0] = 10;            shadow[1] = -2;
    shadow[2] = 720.0 / 22.0;  shadow[3] = -52;
    shadow[4] = 56;            shadow[5] = -52;
    shadow[6] = 14;            shadow[7] = 2;
    shadow[8] = 10;            shadow[9] = 2;
    check_vis(&s, 0, 20, 10816.0 - shoelace(shadow, 5), 9, v0, 1);
    /* inside, on a wall, on a corner, outside the box, on the box */
    assert_int_equal(vis_code(&s, 12, 0), -1);
    assert_int_equal(vis_code(&s, 10, 0), -2);
    assert_int_equal(vis_code(&s, 14, 2), -2);
    assert_int_equal(vis_code(&s, 100, 0), -1);
    assert_int_equal(vis_code(&s, -40, 0), -2);
    ref_scene_free(&s);
}

static void test_vis_courtyard(void **state)
{
    const double xy[] = { 0, 0, 30, 0, 30, 30, 0, 30,
                          10, 10, 20, 10, 20, 20, 10, 20 };
    const uint32_t rn[2] = { 4, 4 };
    const uint32_t v0[1] = { 0 };
    scene s;
    (void)state;
    ref_scene_init(&s);
    assert_int_equal(ref_scene_add_building(&s, xy, rn, 2, 12, 0), 0);
    ref_scene_finish(&s);
    check_vis(&s, 15, 15, 100.0, 4, v0, 1);
    check_vis(&s, 11, 19.5, 100.0, 4, v0, 1);
    check_range(&s, 15, 15, 0.0, PI / 2, 25.0, 4);
    assert_int_equal(vis_code(&s, 10, 15), -2);
    assert_int_equal(vis_code(&s, 5, 5), -1);
    ref_scene_free(&s);
}

static void test_vis_shared_wall(void **state)
{
    scene s;
    const uint32_t both[2] = { 0, 1 }, first[1] = { 0 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 0, 0, 10, 10, 10, 0);
    ref_scene_add_box(&s, 10, 0, 20, 10, 20, 0);
    ref_scene_finish(&s);  /* bounds -50,-50,70,60 */
    assert_true(bounds_area(&s) == 13200.0);
    /* facing both south walls: one 20 m wide face at distance 20, box edge
     * y = 60 at distance 80 */
    check_vis(&s, 10, -20, 13200.0 - trapezoid(20, 20, 80), 8, both, 2);
    /* from the west the first hides the second */
    check_vis(&s, -20, 5, 13200.0 - trapezoid(10, 20, 90), 8, first, 1);
    /* on the shared wall's end point */
    assert_int_equal(vis_code(&s, 10, 0), -2);
    /* on the shared wall: on both boundaries, in neither open interior */
    assert_int_equal(vis_code(&s, 10, 5), -2);
    ref_scene_free(&s);
}

static void test_vis_overlap_collinear(void **state)
{
    scene s;
    const uint32_t both[2] = { 0, 1 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 0, 0, 10, 10, 10, 0);
    ref_scene_add_box(&s, 5, 0, 15, 10, 10, 0);
    ref_scene_finish(&s);  /* bounds -50,-50,65,60 */
    /* the union is [0,15] x [0,10]; the south walls overlap on [5,10] */
    check_vis(&s, 7.5, -20, 115.0 * 110.0 - trapezoid(15, 20, 80), 8, both, 2);
    /* a point on A's wall but inside B is inside */
    assert_int_equal(vis_code(&s, 10, 5), -1);
    ref_scene_free(&s);
}

static void test_vis_overlap_crossing(void **state)
{
    scene s;
    const uint32_t both[2] = { 0, 1 };
    const double shadow[] = { 0, 0, 10, 0, 10, 5, 15, 5, 15, 15,
                              5, 65, -50, 65, -50, 25 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 0, 0, 10, 10, 10, 0);
    ref_scene_add_box(&s, 5, 5, 15, 15, 10, 0);
    ref_scene_finish(&s);  /* bounds -50,-50,65,65 */
    /* from (20,-10): walls y=0, x=10 (up to the crossing (10,5)), y=5, x=15;
     * rays through (15,15) and (0,0) reach (5,65) and (-50,25); the box
     * corner (-50,65) is hidden. Vertices: 3 box corners, 2 ray ends, 5
     * building corners including the wall crossing (10,5). */
    check_vis(&s, 20, -10, 115.0 * 115.0 - shoelace(shadow, 8), 10, both, 2);
    ref_scene_free(&s);
}

static void test_vis_raised_not_occluder(void **state)
{
    scene s;
    ref_vis_result r;
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 10, 10, 20, 20, 8, 3);
    ref_scene_finish(&s);
    assert_int_equal(ref_vis(&s, 15, 15, &r), 0);  /* beneath it */
    check_close(r.area, 110.0 * 110.0, 1e-12, "area under a canopy");
    assert_int_equal(r.nvisible, 0);
    assert_int_equal(r.nverts, 4);
    ref_vis_free(&r);
    ref_scene_free(&s);
}

/* Four quadrants add up to the full turn and see the same buildings. */
static void test_vis_quadrants_sum(void **state)
{
    const double xy[] = { 0, 0, 12, 3, 9, 14, -2, 8,
                          3, 4, 4, 9, 8, 8 };
    const uint32_t rn[2] = { 4, 3 };
    scene s;
    ref_vis_result full, q;
    unsigned char seen[4] = { 0, 0, 0, 0 };
    double sum = 0.0;
    int k;
    uint32_t i;
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_building(&s, xy, rn, 2, 10, 0);
    ref_scene_add_box(&s, 20, -5, 26, 30, 10, 0);
    ref_scene_add_box(&s, -20, 20, 5, 24, 10, 0);
    ref_scene_add_box(&s, 14, 0, 30, 4, 10, 0);  /* overlaps the second */
    ref_scene_finish(&s);
    assert_int_equal(ref_vis(&s, 13, 12, &full), 0);
    for (k = 0; k < 4; k++) {
        assert_int_equal(ref_vis_range(&s, 13, 12, 0.3 + k * PI / 2,
                                       0.3 + (k + 1) * PI / 2, &q), 0);
        sum += q.area;
        for (i = 0; i < q.nvisible; i++)
            seen[q.visible[i]] = 1;
        ref_vis_free(&q);
    }
    check_close(sum, full.area, 1e-12, "sum of quadrants");
    assert_int_equal(full.nvisible, (uint32_t)(seen[0] + seen[1] + seen[2] + seen[3]));
    for (i = 0; i < full.nvisible; i++)
        assert_true(seen[full.visible[i]]);
    assert_true(full.area > 0.0 && full.area < bounds_area(&s));
    ref_vis_free(&full);
    ref_scene_free(&s);
}

/* The two references agree: with buildings made very tall, a grid point q
 * of the box is visible from p iff the horizontal segment p->q at z = 1 is
 * not blocked. The grid estimate of the area must match within 0.5% (it is off by 0.08%). */
static void test_vis_matches_segments(void **state)
{
    const double tri[] = { 30, 5, 42, 12, 33, 20 };
    const uint32_t n3 = 3;
    scene s;
    ref_vis_result r;
    double L[3] = { 18, 15, 1 }, w, h;
    int i, j, n = 150, seen = 0;
    uint32_t b;
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 0, 0, 10, 10, 1e6, 0);
    ref_scene_add_box(&s, 5, 20, 25, 24, 1e6, 0);
    ref_scene_add_box(&s, 22, 18, 28, 40, 1e6, 0);    /* overlaps the second */
    ref_scene_add_building(&s, tri, &n3, 1, 1e6, 0);
    ref_scene_add_box(&s, 12, 0, 24, 12, 1e6, 2.0);   /* raised: above z = 1 */
    ref_scene_finish(&s);
    w = s.bounds[2] - s.bounds[0];
    h = s.bounds[3] - s.bounds[1];
    for (i = 0; i < n; i++) {
        for (j = 0; j < n; j++) {
            double P[3];
            int inside = 0;
            P[0] = s.bounds[0] + (i + 0.5) * w / n;
            P[1] = s.bounds[1] + (j + 0.5) * h / n;
            P[2] = 1;
            for (b = 0; b < s.nbld; b++)
                if (s.bld[b].min_height == 0 &&
                    ref_footprint_where(&s, b, P[0], P[1]) == REF_IN)
                    inside = 1;
            if (!inside && ref_segment_blocked(&s, L, P) == 0)
                seen++;
        }
    }
    assert_int_equal(ref_vis(&s, L[0], L[1], &r), 0);
    check_close(seen * w * h / (n * n), r.area, 5e-3, "grid vs sweep");
    assert_true(r.area < 0.9 * w * h);
    ref_vis_free(&r);
    ref_scene_free(&s);
}

/* ------------------------------------------------------------ direct light */

static void test_light_empty_plane(void **state)
{
    scene s;
    const double L[3] = { 0, 0, 6 };
    const double xs[4] = { 0, 5, 20, 29 };
    int i;
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_lamp(&s, 0, 0, 6, 1000, 30);
    ref_scene_finish(&s);
    for (i = 0; i < 4; i++) {
        double d = sqrt(xs[i] * xs[i] + 36.0);
        double want = 1000.0 * 6.0 / (d * d * d) * ref_window(d / 30.0);
        double x4 = pow(d / 30.0, 4);
        check_close(ref_window(d / 30.0), (1 - x4) * (1 - x4), 1e-14, "W");
        check_close(E_at(&s, xs[i], 0, 0, UP), want, 1e-12, "E on plane");
    }
    check_close(E_at(&s, 0, 0, 0, UP), 1000.0 / 36.0 * pow(1 - pow(0.2, 4), 2), 1e-12, "E below lamp");
    assert_true(E_at(&s, 31, 0, 0, UP) == 0.0);          /* beyond R */
    {
        double P[3] = { 5, 0, 0 };
        check_close(ref_illuminance(&s, P, WEST),
                    lamp_formula(L, 1000, 30, P, WEST), 1e-12, "vertical face");
    }
    assert_true(E_at(&s, 5, 0, 0, EAST) == 0.0);         /* faces away */
    {
        const double down[3] = { 0, 0, -1 };
        assert_true(E_at(&s, 5, 0, 0, down) == 0.0);
    }
    assert_true(E_at(&s, 0, 0, 6, UP) == 0.0);           /* at the lamp */
    assert_int_equal(blocked(&s, L, 10, 0, 0), 0);
    ref_scene_free(&s);
}

static void test_light_tall_box(void **state)
{
    scene s;
    const double L[3] = { 0, 0, 6 };
    double P[3] = { 10, 5, 0 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 5, -1, 7, 1, 20, 0);
    ref_scene_add_lamp(&s, 0, 0, 6, 1000, 30);
    ref_scene_finish(&s);
    assert_int_equal(blocked(&s, L, 10, 0, 0), 1);
    assert_true(E_at(&s, 10, 0, 0, UP) == 0.0);
    assert_true(E_at(&s, 40, 0, 0, UP) == 0.0);
    assert_int_equal(blocked(&s, L, 10, 5, 0), 0);
    check_close(ref_illuminance(&s, P, UP), lamp_formula(L, 1000, 30, P, UP),
                1e-12, "beside the shadow");
    /* the lamp's own facade is lit, the far facade is not */
    P[0] = 5; P[1] = 0; P[2] = 3;
    check_close(ref_illuminance(&s, P, WEST), lamp_formula(L, 1000, 30, P, WEST),
                1e-12, "front facade");
    P[0] = 7;
    assert_true(ref_illuminance(&s, P, EAST) == 0.0);
    ref_scene_free(&s);
}

static void test_light_low_box_tip(void **state)
{
    scene s;
    const double L[3] = { 0, 0, 6 };
    /* far wall at r = 7, lamp z = 6, roof h = 3: tip at 7 * 6 / (6 - 3) */
    const double tip = 7.0 * 6.0 / (6.0 - 3.0);
    double P[3] = { tip + 1e-3, 0, 0 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 5, -1, 7, 1, 3, 0);
    ref_scene_add_lamp(&s, 0, 0, 6, 1000, 30);
    ref_scene_finish(&s);
    assert_true(tip == 14.0);
    assert_int_equal(blocked(&s, L, 7.5, 0, 0), 1);
    assert_int_equal(blocked(&s, L, tip - 1e-3, 0, 0), 1);
    assert_int_equal(blocked(&s, L, tip + 1e-3, 0, 0), 0);
    assert_true(E_at(&s, tip - 1e-3, 0, 0, UP) == 0.0);
    check_close(ref_illuminance(&s, P, UP), lamp_formula(L, 1000, 30, P, UP),
                1e-12, "just past the tip");
    /* the roof itself is lit (segment leaves the roof upwards) */
    P[0] = 6; P[1] = 0; P[2] = 3;
    check_close(ref_illuminance(&s, P, UP), lamp_formula(L, 1000, 30, P, UP),
                1e-12, "roof");
    ref_scene_free(&s);
}

static void test_light_facade_over_low_roof(void **state)
{
    scene s;
    const double L[3] = { 0, 0, 8 };
    /* front roof edge x = 12, h = 6: P = (20, 0, z) shadowed for
     * 8 + (z - 8) * 12/20 < 6, i.e. z < 8 - 2 / 0.6 = 4.666... */
    const double zcut = 8.0 - 2.0 / 0.6;
    const double lit[3] = { 4.7, 10.0, 20.0 }, dark[3] = { 0.5, 3.0, 4.6 };
    int i;
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 10, -5, 12, 5, 6, 0);
    ref_scene_add_box(&s, 20, -5, 30, 5, 30, 0);
    ref_scene_add_lamp(&s, 0, 0, 8, 1000, 50);
    ref_scene_finish(&s);
    for (i = 0; i < 3; i++) {
        double P[3] = { 20, 0, 0 };
        P[2] = lit[i];
        check_close(ref_illuminance(&s, P, WEST),
                    lamp_formula(L, 1000, 50, P, WEST), 1e-12, "upper floor");
        assert_true(ref_illuminance(&s, P, WEST) > 0.0);
        P[2] = dark[i];
        assert_true(ref_illuminance(&s, P, WEST) == 0.0);
    }
    assert_int_equal(blocked(&s, L, 20, 0, zcut - 1e-4), 1);
    assert_int_equal(blocked(&s, L, 20, 0, zcut + 1e-4), 0);
    ref_scene_free(&s);
}

static void test_light_grazing_roof(void **state)
{
    scene s;
    const double L[3] = { 0, 0, 6 };
    double P[3] = { 10, 0, 6 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 5, -1, 7, 1, 6, 0);
    ref_scene_add_lamp(&s, 0, 0, 6, 1000, 30);
    ref_scene_finish(&s);
    assert_int_equal(ref_segment_blocked(&s, L, P), 0);  /* along the roof plane */
    check_close(ref_illuminance(&s, P, WEST), lamp_formula(L, 1000, 30, P, WEST),
                1e-12, "grazing roof");
    assert_int_equal(blocked(&s, L, 10, 0, 5.9), 1);
    assert_int_equal(blocked(&s, L, 10, 0, 6.1), 0);
    assert_int_equal(blocked(&s, L, 7, 0, 6), 0);       /* ends on the roof edge */
    assert_int_equal(blocked(&s, L, 6, 0.5, 6), 0);     /* ends on the roof */
    ref_scene_free(&s);
}

static void test_light_raised(void **state)
{
    scene s;
    const double L[3] = { 0, 0, 6 };
    double P[3] = { 10, 0, 0 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 5, -1, 7, 1, 5, 4);  /* canopy from 4 m to 5 m */
    ref_scene_add_lamp(&s, 0, 0, 6, 1000, 30);
    ref_scene_finish(&s);
    /* over x in (5,7) the segment to the ground is at z in (1.8, 3): beneath */
    check_close(ref_illuminance(&s, P, UP), lamp_formula(L, 1000, 30, P, UP),
                1e-12, "beneath canopy");
    /* to (10,0,3) it is at z in (3.9, 4.5): through the canopy */
    assert_int_equal(blocked(&s, L, 10, 0, 3), 1);
    /* lamp below the canopy */
    {
        const double L2[3] = { 0, 0, 2 };
        assert_int_equal(blocked(&s, L2, 10, 0, 0), 0);
        assert_int_equal(blocked(&s, L2, 10, 0, 3.9), 0);  /* z < 4 over it */
    }
    /* along the underside plane z = 4: boundary, not blocked */
    {
        const double L3[3] = { 0, 0, 4 };
        assert_int_equal(blocked(&s, L3, 10, 0, 4), 0);
    }
    ref_scene_free(&s);
}

static void test_light_vertical_and_walls(void **state)
{
    scene s;
    const double above[3] = { 3, 3, 10 }, onwall[3] = { 0, 3, 10 };
    const double west[3] = { -5, 0, 3 }, mid[3] = { -5, 5, 3 };
    double P[3] = { 3, 3, 5 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 0, 0, 6, 6, 5, 0);      /* roof at 5 */
    ref_scene_add_box(&s, 20, 0, 30, 10, 10, 0);
    ref_scene_add_box(&s, 40, 0, 46, 6, 7, 6);    /* canopy 6..7 */
    ref_scene_add_lamp(&s, 3, 3, 10, 1000, 30);
    ref_scene_finish(&s);
    /* vertical segment down to the roof */
    assert_int_equal(ref_segment_blocked(&s, above, P), 0);
    check_close(ref_illuminance(&s, P, UP), 1000.0 / 25.0 * ref_window(5.0 / 30.0),
                1e-12, "roof under lamp");
    P[2] = 2;
    assert_int_equal(ref_segment_blocked(&s, above, P), 1);  /* into the solid */
    /* vertical segment along a wall plane */
    assert_int_equal(blocked(&s, onwall, 0, 3, 0), 0);
    /* vertical segment through a canopy */
    {
        const double L[3] = { 43, 3, 10 };
        assert_int_equal(blocked(&s, L, 43, 3, 0), 1);
        assert_int_equal(blocked(&s, L, 43, 3, 7), 0);   /* stops on its roof */
        const double L4[3] = { 46, 3, 10 };
        assert_int_equal(blocked(&s, L4, 46, 3, 0), 0);  /* along its wall */
    }
    /* along the south wall of [20,30]x[0,10] (y = 0), and through it */
    {
        const double L[3] = { 15, 0, 3 };
        assert_int_equal(blocked(&s, L, 35, 0, 0), 0);
        assert_int_equal(blocked(&s, L, 35, 5, 0), 1);
    }
    assert_int_equal(blocked(&s, west, -5, 0, 0), 0);  /* no building in between */
    assert_int_equal(blocked(&s, mid, 10, 1, 0), 1);   /* through [0,6]^2 low */
    /* through the corner (20,0) exactly, from outside both walls */
    {
        const double L[3] = { 15, -5, 3 };
        assert_int_equal(blocked(&s, L, 25, 5, 3), 1);   /* enters the box */
        const double Lhigh[3] = { 15, -5, 12 };
        assert_int_equal(blocked(&s, Lhigh, 25, 5, 12), 0);  /* over its roof */
    }
    ref_scene_free(&s);
}

static void test_light_courtyard(void **state)
{
    const double xy[] = { 0, 0, 30, 0, 30, 30, 0, 30,
                          10, 10, 20, 10, 20, 20, 10, 20 };
    const uint32_t rn[2] = { 4, 4 };
    const double in[3] = { 15, 15, 6 }, high[3] = { 15, 15, 20 };
    scene s;
    double P[3] = { 10, 15, 3 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_building(&s, xy, rn, 2, 10, 0);
    ref_scene_add_lamp(&s, 15, 15, 6, 1000, 30);
    ref_scene_finish(&s);
    check_close(ref_illuminance(&s, P, EAST), lamp_formula(in, 1000, 30, P, EAST),
                1e-12, "courtyard wall");
    assert_int_equal(blocked(&s, in, 12, 15, 0), 0);
    assert_int_equal(blocked(&s, in, -5, 15, 0), 1);
    /* from 20 m up: the ground east at x = 40 is hidden by the east wing
     * (z < 10 for x > 22.5); at x = 50 the segment clears x = 30 at 11.43 m */
    assert_int_equal(blocked(&s, high, 40, 15, 0), 1);
    assert_int_equal(blocked(&s, high, 50, 15, 0), 0);
    ref_scene_free(&s);
}

static void test_light_shared_wall(void **state)
{
    scene s;
    const double L[3] = { 10, -5, 5 };
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_box(&s, 0, 0, 10, 10, 10, 0);
    ref_scene_add_box(&s, 10, 0, 20, 10, 10, 0);
    ref_scene_finish(&s);
    /* documented rule: along the shared wall the segment is in neither
     * building's open interior, so it is not blocked (zero-width leak,
     * within SPEC's 1e-6 m tolerance) */
    assert_int_equal(blocked(&s, L, 10, 15, 5), 0);
    assert_int_equal(blocked(&s, L, 10.001, 15, 5), 1);
    assert_int_equal(blocked(&s, L, 9.999, 15, 5), 1);
    ref_scene_free(&s);
}

static void test_light_rgb(void **state)
{
    scene s;
    const double L1[3] = { 0, 0, 6 }, L2[3] = { 10, 0, 8 };
    double P[3] = { 4, 2, 0 }, rgb[3], e1, e2;
    (void)state;
    ref_scene_init(&s);
    ref_scene_add_lamp_rgb(&s, 0, 0, 6, 1000, 30, 1.0, 0.0, 0.0);
    ref_scene_add_lamp_rgb(&s, 10, 0, 8, 500, 20, 0.0, 0.5, 1.0);
    ref_scene_add_lamp(&s, 4, 2, 0, 1e6, 30);   /* at P: contributes 0 */
    ref_scene_finish(&s);
    e1 = lamp_formula(L1, 1000, 30, P, UP);
    e2 = lamp_formula(L2, 500, 20, P, UP);
    ref_illuminance_rgb(&s, P, UP, rgb);
    check_close(ref_illuminance(&s, P, UP), e1 + e2, 1e-12, "E sum");
    check_close(rgb[0], e1, 1e-12, "red");
    check_close(rgb[1], 0.5 * e2, 1e-12, "green");
    check_close(rgb[2], e2, 1e-12, "blue");
    ref_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_builder),
        cmocka_unit_test(test_vis_empty),
        cmocka_unit_test(test_vis_range_empty),
        cmocka_unit_test(test_vis_one_square),
        cmocka_unit_test(test_vis_courtyard),
        cmocka_unit_test(test_vis_shared_wall),
        cmocka_unit_test(test_vis_overlap_collinear),
        cmocka_unit_test(test_vis_overlap_crossing),
        cmocka_unit_test(test_vis_raised_not_occluder),
        cmocka_unit_test(test_vis_quadrants_sum),
        cmocka_unit_test(test_vis_matches_segments),
        cmocka_unit_test(test_light_empty_plane),
        cmocka_unit_test(test_light_tall_box),
        cmocka_unit_test(test_light_low_box_tip),
        cmocka_unit_test(test_light_facade_over_low_roof),
        cmocka_unit_test(test_light_grazing_roof),
        cmocka_unit_test(test_light_raised),
        cmocka_unit_test(test_light_vertical_and_walls),
        cmocka_unit_test(test_light_courtyard),
        cmocka_unit_test(test_light_shared_wall),
        cmocka_unit_test(test_light_rgb),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
