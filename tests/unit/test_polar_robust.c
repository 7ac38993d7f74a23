/* test_polar_robust: polar_build on scenes whose footprints cross (SPEC §1:
 * footprints may overlap; real map data overlaps by centimetres).
 *
 * Rounded crossing points bend the wall pieces by an ulp; src/polar/walls.c cuts
 * the pieces again at the contacts that makes until none is left. Here, on
 * hundreds of random scenes made to be hard for that (rotated boxes
 * crossing lattice boxes and their collinear walls, near-collinear
 * crossings, three walls through nearly one point, overlaps of 1e-9 to
 * 1e-3 m, dense heaps of rotated boxes, a city grid of boxes and
 * courtyards turned and grown by tiny amounts over their neighbours):
 *   - polar_build returns PLX_OK, every time;
 *   - the pieces it keeps form a planar subdivision, checked pair by pair
 *     with geom_orient_ref (the stack-expansion orientation, independent of
 *     the filter the build uses): two pieces meet at most at a common end
 *     (no crossing, no end inside another piece, no collinear overlap);
 *   - at random free points at least 1e-6 m from every scene edge,
 *     vis_query agrees with the brute force tests/ref/ref_vis: areas to
 *     1e-9 relative, visible sets identical. A rounded crossing moves the
 *     geometry by about 1e-14 m at these coordinates, far below 1e-6 m, so
 *     such a point is free in both and sees the same walls up to that; the
 *     visible set is compared only where ref_vis is unambiguous: ref_vis
 *     at the point moved by 1e-7 m in four directions gives the same set.
 * Then fault injection: each allocation of a build that needs several
 * rounds fails in turn, giving PLX_E_NOMEM with the arena unchanged.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "base/scene.h"
#include "base/arena.h"
#include "base/engine.h"
#include "base/geom.h"
#include "polar/polar.h"
#include "polar_faults.h"
#include "polar/visibility.h"
#include "ref_scene.h"
#include "ref_vis.h"
#include "slow.h"

#define PI 3.14159265358979323846
#define ARENA_BYTES ((size_t)32 << 20)
#define POLY_CAP 20000
#define VIS_CAP 4000

static uint32_t rnd_state;

static double urand(void)
{
    rnd_state = rnd_state * 1103515245u + 12345u;
    return ((rnd_state >> 8) & 0xffffff) / 16777216.0;
}

static uint32_t irand(uint32_t n)
{
    return (uint32_t)(urand() * n) % (n ? n : 1);
}

/* 10^-9 .. 10^-3, log-uniform */
static double tiny(void)
{
    return pow(10.0, -9.0 + 6.0 * urand());
}

typedef struct fix {
    scene s;
    void *mem;
    arena a;
    polar *pd;
    vec2 *poly;
    uint32_t *vis;
} fix;

static fix *fix_new(void)
{
    fix *f = calloc(1, sizeof *f);
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

static void fix_free(fix *f)
{
    ref_scene_free(&f->s);
    free(f->mem);
    free(f->poly);
    free(f->vis);
    free(f);
}

static void add_rotated(fix *f, double x, double y, double w, double h, double ang)
{
    double c = cos(ang), sn = sin(ang), xy[8];
    double ox[4] = { 0, w, w, 0 }, oy[4] = { 0, 0, h, h };
    uint32_t n = 4;
    int k;
    for (k = 0; k < 4; k++) {
        xy[2 * k] = x + c * ox[k] - sn * oy[k];
        xy[2 * k + 1] = y + sn * ox[k] + c * oy[k];
    }
    assert_true(ref_scene_add_building(&f->s, xy, &n, 1, 10, 0) >= 0);
}

static void add_box(fix *f, double x0, double y0, double x1, double y1)
{
    assert_true(ref_scene_add_box(&f->s, x0, y0, x1, y1, 10, 0) >= 0);
}

/* ------------------------------------------------------------ scenes */

/* Lattice boxes (shared walls, collinear edges) and rotated boxes across
 * them, some at angles of 1e-9..1e-3 rad (near-collinear crossings). */
static void scene_lattice_rotated(fix *f, int n)
{
    int i;
    double cell = urand() < 0.5 ? 1.0 : 0.25 + urand();
    for (i = 0; i < n; i++) {
        double x = irand(16) * cell, y = irand(16) * cell;
        double w = (1 + irand(4)) * cell, h = (1 + irand(4)) * cell;
        if (urand() < 0.6) {
            add_box(f, x, y, x + w, y + h);
        } else {
            double r = urand(), ang = r < 0.3 ? tiny() * (urand() < 0.5 ? 1 : -1)
                                    : r < 0.4 ? PI / 2 + tiny() : urand() * PI;
            add_rotated(f, x + urand() * cell, y + (r < 0.2 ? 0.0 : urand() * cell), w, h, ang);
        }
    }
}

/* Walls through nearly one point: boxes with a corner within 1e-9..1e-3 of
 * a common point, at random angles, and boxes rotated about one corner by
 * tiny angles. */
static void scene_one_point(fix *f, int n)
{
    int i;
    double cx = 20 + urand() * 10, cy = 20 + urand() * 10;
    for (i = 0; i < n; i++) {
        double ang = urand() * 2 * PI, d = tiny(), da = urand() * 2 * PI;
        double w = 2 + urand() * 8, h = 2 + urand() * 8;
        if (i % 3 == 2)
            ang = (i / 3) * tiny();
        /* start a little back so that the walls pass near (cx, cy) */
        add_rotated(f, cx + d * cos(da) - 0.5 * w * cos(ang), cy + d * sin(da) - 0.5 * w * sin(ang),
                    w, h, ang);
    }
}

/* Rows of boxes overlapping by 1e-9..1e-3 m, slightly rotated, like
 * neighbouring footprints of real data; a second row across the first. */
static void scene_tiny_overlaps(fix *f, int n)
{
    int i;
    double x = 0;
    for (i = 0; i < n; i++) {
        double w = 3 + urand() * 6, h = 8 + urand() * 4, y = urand() * tiny();
        if (urand() < 0.5)
            add_box(f, x, y, x + w, y + h);
        else
            add_rotated(f, x, y, w, h, (urand() - 0.5) * tiny());
        x += w - tiny();
    }
    for (i = 0; i < n / 3; i++) {
        double x0 = urand() * x, y0 = 12 - tiny();
        add_rotated(f, x0, y0, 4 + urand() * 4, 6, PI / 2 * (urand() < 0.5) + tiny());
    }
}

/* Dense heaps of rotated boxes crossing each other everywhere. */
static void scene_heap(fix *f, int n)
{
    int i;
    for (i = 0; i < n; i++)
        add_rotated(f, urand() * 30, urand() * 30, 2 + urand() * 10, 2 + urand() * 10,
                    urand() * PI);
}

/* A courtyard building (outer ring, one hole t inside it), rotated. */
static void add_rotated_courtyard(fix *f, double x, double y, double w, double h, double t,
                                  double ang)
{
    double c = cos(ang), sn = sin(ang), xy[16];
    double ox[8] = { 0, w, w, 0, t, t, w - t, w - t }, oy[8] = { 0, 0, h, h, t, h - t, h - t, t };
    uint32_t n[2] = { 4, 4 };
    int k;
    for (k = 0; k < 8; k++) {
        xy[2 * k] = x + c * ox[k] - sn * oy[k];
        xy[2 * k + 1] = y + sn * ox[k] + c * oy[k];
    }
    assert_true(ref_scene_add_building(&f->s, xy, n, 2, 20, 0) >= 0);
}

/* A city block grid of 10 m cells: exact boxes sharing walls, boxes and
 * courtyards turned by 1e-9..1e-3 rad and grown by 1e-9..1e-2 m over
 * their neighbours (real data), a few turned at random. */
static void scene_tilted_city(fix *f, int n)
{
    int i, j, side = 3 + n / 12;
    for (i = 0; i < side; i++)
        for (j = 0; j < side; j++) {
            double x = i * 10.0, y = j * 10.0, r = urand(), o = tiny() * (urand() < 0.5 ? 1 : 10);
            double ang = (urand() - 0.5) * tiny();
            if (r < 0.3)
                add_box(f, x, y, x + 10, y + 10);
            else if (r < 0.7)
                add_rotated(f, x - o, y - o, 10 + 2 * o, 10 + 2 * o, ang);
            else if (r < 0.9)
                add_rotated_courtyard(f, x - o, y - o, 10 + 2 * o, 10 + 2 * o, 3, ang);
            else
                add_rotated(f, x + 2, y + 1, 6, 4, urand() * PI);
        }
}

static void make_scene(fix *f, int kind, int n)
{
    switch (kind) {
    case 4:
        scene_tilted_city(f, n);
        break;
    case 0:
        scene_lattice_rotated(f, n);
        break;
    case 1:
        scene_one_point(f, n / 2);
        break;
    case 2:
        scene_tiny_overlaps(f, n);
        break;
    default:
        scene_heap(f, n);
        break;
    }
    ref_scene_finish(&f->s);
}

/* ------------------------------------------------------------ checks */

static int lex(vec2 a, vec2 b)
{
    if (a.x != b.x)
        return a.x < b.x ? -1 : 1;
    if (a.y != b.y)
        return a.y < b.y ? -1 : 1;
    return 0;
}

/* c strictly inside segment ab, the three collinear */
static int inside(vec2 a, vec2 b, vec2 c)
{
    int ca = lex(c, a), cb = lex(c, b);
    return ca != 0 && cb != 0 && ca != cb;
}

/* Do pieces ab and cd meet elsewhere than at a common end? */
static int bad_pair(vec2 a, vec2 b, vec2 c, vec2 d)
{
    int o1 = geom_orient_ref(a, b, c), o2 = geom_orient_ref(a, b, d);
    int o3 = geom_orient_ref(c, d, a), o4 = geom_orient_ref(c, d, b);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return 1;                                   /* proper crossing */
    if ((o1 == 0 && inside(a, b, c)) || (o2 == 0 && inside(a, b, d)) ||
        (o3 == 0 && inside(c, d, a)) || (o4 == 0 && inside(c, d, b)))
        return 1;                                   /* end inside, overlap */
    return lex(a, c) == 0 && lex(b, d) == 0;        /* the same piece twice */
}

static uint32_t bad_pieces(const polar *pd)
{
    uint32_t i, j, bad = 0;
    for (i = 0; i < pd->nwall; i++) {
        vec2 a = pd->pts[pd->seg[i].a], b = pd->pts[pd->seg[i].b];
        if (lex(a, b) > 0) {
            vec2 t = a;
            a = b;
            b = t;
        }
        for (j = i + 1; j < pd->nwall; j++) {
            vec2 c = pd->pts[pd->seg[j].a], d = pd->pts[pd->seg[j].b];
            if (lex(c, d) > 0) {
                vec2 t = c;
                c = d;
                d = t;
            }
            if (fmax(a.x, b.x) < fmin(c.x, d.x) || fmax(c.x, d.x) < fmin(a.x, b.x) ||
                fmax(a.y, b.y) < fmin(c.y, d.y) || fmax(c.y, d.y) < fmin(a.y, b.y))
                continue;
            bad += (uint32_t)bad_pair(a, b, c, d);
        }
    }
    return bad;
}

static double seg_dist(vec2 p, vec2 a, vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l = dx * dx + dy * dy, t = 0;
    if (l > 0)
        t = fmin(1.0, fmax(0.0, ((p.x - a.x) * dx + (p.y - a.y) * dy) / l));
    return hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

/* Free (in no footprint, by ref_footprint_where) and at least 1e-6 m from
 * every occluder edge. */
static int clear_point(const scene *s, vec2 p)
{
    uint32_t b, r, k;
    for (b = 0; b < s->nbld; b++) {
        if (s->bld[b].min_height > 0)
            continue;
        if (ref_footprint_where(s, b, p.x, p.y) != REF_OUT)
            return 0;
        for (r = 0; r < s->bld[b].ring_count; r++) {
            const scene_ring *g = &s->rings[s->bld[b].ring_first + r];
            for (k = 0; k < g->count; k++)
                if (seg_dist(p, s->pts[g->first + k], s->pts[g->first + (k + 1) % g->count]) <
                    1e-6)
                    return 0;
        }
    }
    return 1;
}

typedef struct counts {
    int scenes, points, area_bad, vis_bad, ambiguous, third, rounds_max, hist[8];
    long pieces;
} counts;

static int same_set(const ref_vis_result *a, const ref_vis_result *b)
{
    uint32_t k;
    if (a->nvisible != b->nvisible)
        return 0;
    for (k = 0; k < a->nvisible; k++)
        if (a->visible[k] != b->visible[k])
            return 0;
    return 1;
}

/* Does an edge of building m overlap (collinear, over a positive length)
 * edges of two other buildings? A wall piece keeps two owners (polar.h),
 * so a third footprint with the same wall is not named by vis_query. */
static int third_owner(const scene *s, uint32_t m)
{
    const scene_ring *g = &s->rings[s->bld[m].ring_first];
    uint32_t k, b, r, j;
    for (k = 0; k < g->count; k++) {
        vec2 a = s->pts[g->first + k], e = s->pts[g->first + (k + 1) % g->count];
        int others = 0;
        for (b = 0; b < s->nbld && others < 2; b++) {
            int hit = 0;
            if (b == m || s->bld[b].min_height > 0)
                continue;
            for (r = 0; r < s->bld[b].ring_count && !hit; r++) {
                const scene_ring *h = &s->rings[s->bld[b].ring_first + r];
                for (j = 0; j < h->count && !hit; j++) {
                    vec2 c = s->pts[h->first + j], d = s->pts[h->first + (j + 1) % h->count];
                    vec2 lo = lex(a, e) < 0 ? a : e, hi = lex(a, e) < 0 ? e : a;
                    vec2 l2 = lex(c, d) < 0 ? c : d, h2 = lex(c, d) < 0 ? d : c;
                    hit = geom_orient_ref(a, e, c) == 0 && geom_orient_ref(a, e, d) == 0 &&
                          lex(lo, h2) < 0 && lex(l2, hi) < 0;
                }
            }
            others += hit;
        }
        if (others >= 2)
            return 1;
    }
    return 0;
}

/* Is every building ref_vis names and vis_query does not one with a third
 * owner of a wall, and none the other way? */
static int only_third_owners(const scene *s, const vis_result *vr, const ref_vis_result *rr)
{
    uint32_t i = 0, k;
    for (k = 0; k < rr->nvisible; k++) {
        if (i < vr->nvis && vr->vis[i] == rr->visible[k])
            i++;
        else if (!third_owner(s, rr->visible[k]))
            return 0;
    }
    return i == vr->nvis;
}

/* Is ref_vis's visible set at p the same a little away from p? */
static int unambiguous(const scene *s, vec2 p, int full, double a0, double a1,
                       const ref_vis_result *rr)
{
    static const double d[4][2] = { { 1, 0 }, { 0, 1 }, { -1, 0 }, { 0, -1 } };
    int k, ok = 1;
    for (k = 0; k < 4 && ok; k++) {
        ref_vis_result r2;
        double x = p.x + 1e-7 * d[k][0], y = p.y + 1e-7 * d[k][1];
        int rc = full ? ref_vis(s, x, y, &r2) : ref_vis_range(s, x, y, a0, a1, &r2);
        ok = rc == 0 && same_set(rr, &r2);
        ref_vis_free(&r2);
    }
    return ok;
}

static void check_vis(fix *f, vec2 p, int full, double a0, double a1, counts *c)
{
    ref_vis_result rr;
    vis_result vr;
    uint32_t k;
    int rc, same;
    plx_status st;
    rc = full ? ref_vis(&f->s, p.x, p.y, &rr) : ref_vis_range(&f->s, p.x, p.y, a0, a1, &rr);
    assert_int_equal(rc, 0);
    memset(&vr, 0, sizeof vr);
    vr.poly = f->poly;
    vr.poly_cap = POLY_CAP;
    vr.vis = f->vis;
    vr.vis_cap = VIS_CAP;
    st = vis_query(f->pd, p, a0, a1, full, &f->a, &vr);
    c->points++;
    if (st != PLX_OK || fabs(vr.area - rr.area) > 1e-9 * fmax(rr.area, 1.0)) {
        if (c->area_bad++ < 5)
            print_message("p = (%.17g, %.17g) full %d: st %d area %.15g ref %.15g\n", p.x, p.y,
                          full, st, vr.area, rr.area);
    }
    same = vr.nvis == rr.nvisible;
    for (k = 0; same && k < vr.nvis; k++)
        same = vr.vis[k] == rr.visible[k];
    if (!same && only_third_owners(&f->s, &vr, &rr)) {
        c->third++;
    } else if (!same) {
        if (!unambiguous(&f->s, p, full, a0, a1, &rr)) {
            c->ambiguous++;
        } else if (c->vis_bad++ < 5) {
            print_message("p = (%.17g, %.17g) full %d [%g %g]: nvis %u ref %u\n", p.x, p.y, full,
                          a0, a1, vr.nvis, rr.nvisible);
        }
    }
    ref_vis_free(&rr);
}

static void check_scene(fix *f, int npts, counts *c)
{
    const double *bx = f->s.bounds;
    int n = 0, tries = 0;
    uint32_t r = f->pd->wall_rounds;
    c->scenes++;
    c->pieces += f->pd->nwall;
    c->hist[r < 7 ? r : 7]++;
    if ((int)r > c->rounds_max)
        c->rounds_max = (int)r;
    assert_int_equal(bad_pieces(f->pd), 0);
    while (n < npts && tries < 100 * npts) {
        vec2 p;
        double a0 = urand() * 4 * PI - 2 * PI, a1 = a0 + urand() * 2.2 * PI;
        tries++;
        /* near the buildings: the box without most of its 50 m margin */
        p.x = bx[0] + 45 + urand() * (bx[2] - bx[0] - 90);
        p.y = bx[1] + 45 + urand() * (bx[3] - bx[1] - 90);
        if (!clear_point(&f->s, p))
            continue;
        n++;
        check_vis(f, p, 1, 0, 0, c);
        check_vis(f, p, 0, a0, a1, c);
    }
}

static int quick(int n)
{
    return getenv("PLX_TEST_QUICK") ? (n + 9) / 10 : n;
}

static void test_crossing_scenes(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    counts c;
    int k, kind, nsc = quick(100);
    static const char *name[5] = { "lattice + rotated", "near one point", "tiny overlaps",
                                   "dense heaps", "tilted city" };
    (void)state;
    for (kind = 0; kind < 5; kind++) {
        memset(&c, 0, sizeof c);
        for (k = 0; k < nsc; k++) {
            fix *f = fix_new();
            rnd_state = 7000u + 1000u * (uint32_t)kind + (uint32_t)k;
            make_scene(f, kind, 12 + (int)irand(40));
            assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
            check_scene(f, k % 4 == 0 ? 6 : 2, &c);
            fix_free(f);
        }
        print_message("%s: %d scenes, %ld pieces, rounds after the first cut: max %d, "
                      "scenes with 0..7+: %d %d %d %d %d %d %d %d; %d points x 2: "
                      "area differs %d, visible set differs %d (+%d ambiguous, +%d third "
                      "owners of a wall)\n",
                      name[kind], c.scenes, c.pieces, c.rounds_max, c.hist[0], c.hist[1],
                      c.hist[2], c.hist[3], c.hist[4], c.hist[5], c.hist[6], c.hist[7],
                      c.points / 2, c.area_bad, c.vis_bad, c.ambiguous, c.third);
        assert_int_equal(c.area_bad, 0);
        assert_int_equal(c.vis_bad, 0);
        assert_true((c.ambiguous + c.third) * 20 <= c.points);
        assert_true(c.points >= 2 * nsc);
        if (kind != 2)
            assert_true(c.hist[0] < c.scenes);   /* crossings were rounded */
    }
}

/* Each allocation of a build needing several rounds fails in turn. */
static void test_fault_injection(void **state)
{
    fix *f = fix_new();
    uint64_t k;
    int done = 0, kind = 0;
    (void)state;
    /* the first scene (of a few kinds) whose build takes two rounds or more */
    for (k = 0; !done && k < 400; k++) {
        fix_free(f);
        f = fix_new();
        kind = (int)(k % 4);
        rnd_state = 7000u + 1000u * (uint32_t)kind + (uint32_t)(k / 4);
        make_scene(f, kind, 12 + (int)irand(40));
        assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
        done = f->pd->wall_rounds >= 2;
        arena_init(&f->a, f->mem, ARENA_BYTES);
    }
    assert_true(done);
    k = polar_build_each_failure(&f->a, &f->s, &f->pd, 99999);
    print_message("fault injection: scene kind %d, %u rounds, %d requests, %u wall pieces\n",
                  kind, f->pd->wall_rounds, (int)k, f->pd->nwall);
    assert_true(k > 20);
    fix_free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crossing_scenes),
        cmocka_unit_test(test_fault_injection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
