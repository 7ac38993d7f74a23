/* test_polar_locate: point location in the polar diagrams by the search
 * DAG (polar_locate_frame_ex) against the former grid scan (polar_scan,
 * kept for this) and, independently, against brute force:
 *   - a region answer: the region holds the point (between the axes of its
 *     points in the frame's lexicographic order, below its ceiling, above
 *     its floor, by geom_orient) and no footprint holds it;
 *   - -2: the point lies on a wall piece (exact scan over every piece);
 *   - -3: some footprint holds it (exact point-in-ring over every occluder)
 *     and it lies on no wall piece; a known owner holds it.
 * Points: uniform over the Bounds box, at vertices, on walls, on the
 * abscissa or the ordinate of a vertex, on the bundled fixtures and on
 * random scenes made to be degenerate (touching and overlapping boxes on a
 * lattice, collinear edges, walls vertical in both frames). Then a comb,
 * the grid scan's worst case, for the depth of the DAG, and fault
 * injection on a build large enough for several chunks of DAG nodes.
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

#include "polarlux_port.h"
#include "base/scene.h"
#include "base/arena.h"
#include "base/engine.h"
#include "base/geom.h"
#include "polar/polar.h"
#include "polar/locate.h"
#include "polar_faults.h"
#include "ref_polar_scan.h"
#include "ref_scene.h"
#include "slow.h"

#define ARENA_BYTES ((size_t)64 << 20)

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

/* Points wanted: n, or n / 20 with PLX_TEST_QUICK. */
static int quick(int n)
{
    return getenv("PLX_TEST_QUICK") ? (n + 19) / 20 : n;
}

/* ------------------------------------------------------- brute force */

/* Exact: where p lies relative to the footprint of building b. */
static int fp_where(const scene *s, uint32_t b, vec2 p)
{
    const scene_building *B = &s->bld[b];
    uint32_t r;
    int w = geom_point_in_ring(p, s->pts + s->rings[B->ring_first].first,
                               s->rings[B->ring_first].count);
    if (w != GEOM_INSIDE)
        return w;
    for (r = 1; r < B->ring_count; r++) {
        const scene_ring *g = &s->rings[B->ring_first + r];
        int h = geom_point_in_ring(p, s->pts + g->first, g->count);
        if (h == GEOM_ON_BOUNDARY)
            return GEOM_ON_BOUNDARY;
        if (h == GEOM_INSIDE)
            return GEOM_OUTSIDE;
    }
    return GEOM_INSIDE;
}

/* Does any occluder footprint hold p (inside or on its boundary)? */
static int in_any(const scene *s, vec2 p)
{
    uint32_t b;
    for (b = 0; b < s->nbld; b++)
        if (s->bld[b].min_height <= 0 && fp_where(s, b, p) != GEOM_OUTSIDE)
            return 1;
    return 0;
}

static int on_piece(const polar *pd, uint32_t k, vec2 p)
{
    vec2 a = pd->pts[pd->seg[k].a], b = pd->pts[pd->seg[k].b];
    return geom_orient(a, b, p) == 0 && p.x >= fmin(a.x, b.x) && p.x <= fmax(a.x, b.x) &&
           p.y >= fmin(a.y, b.y) && p.y <= fmax(a.y, b.y);
}

static int on_any_piece(const polar *pd, vec2 p)
{
    uint32_t k;
    for (k = 0; k < pd->nwall; k++)
        if (on_piece(pd, k, p))
            return 1;
    return 0;
}

static int lex(vec2 a, vec2 b);

/* Is piece (L, R) above piece (BL, BR), both spanning one frame abscissa
 * and not crossing? (Exact.) */
static int piece_over(vec2 L, vec2 R, vec2 BL, vec2 BR)
{
    int c = lex(L, BL), o;
    if (c > 0) {
        o = geom_orient(BL, BR, L);
        return (o ? o : geom_orient(BL, BR, R)) > 0;
    }
    if (c < 0) {
        o = geom_orient(L, R, BL);
        return (o ? o : geom_orient(L, R, BR)) < 0;
    }
    return geom_orient(BL, BR, R) > 0;
}

/* Piece k in frame coordinates, left end first; returns the footprints
 * entered when crossing it upwards. */
static int32_t frame_piece(const polar *pd, int frame, uint32_t k, vec2 *l, vec2 *r)
{
    const polar_seg *g = &pd->seg[k];
    vec2 a = polar_fpt(pd, frame, g->a), b = polar_fpt(pd, frame, g->b);
    if (lex(a, b) < 0) {
        *l = a;
        *r = b;
        return g->cover;
    }
    *l = b;
    *r = a;
    return -g->cover;
}

/* The owner polar_locate gives for a point inside the solid, by its
 * definition: the building entered when crossing upwards (in the frame)
 * the nearest wall piece below f whose span holds f strictly (in the
 * lexicographic order), or -1 when that crossing enters no footprint.
 * (With a party wall left out in between, this is the neighbour across
 * it: query.c looks the building up itself.) Exact, O(pieces). */
static int32_t brute_owner(const polar *pd, int frame, vec2 f)
{
    uint32_t k, best = POLAR_NONE;
    vec2 BL = f, BR = f;
    int32_t bd = 0;
    for (k = 0; k < pd->nwall; k++) {
        vec2 l, r;
        int32_t d = frame_piece(pd, frame, k, &l, &r);
        if (!(lex(l, f) < 0 && lex(f, r) < 0) || geom_orient(l, r, f) <= 0)
            continue;
        if (best == POLAR_NONE || piece_over(l, r, BL, BR)) {
            best = k;
            BL = l;
            BR = r;
            bd = d;
        }
    }
    if (best == POLAR_NONE)
        return -1;
    return bd > 0 && pd->seg[best].bld[0] >= 0 ? pd->seg[best].bld[0] : -1;
}

/* Footprints covering f (not on a piece), counted exactly over the wall
 * pieces: going straight up from f (in the frame) to the Bounds box, every
 * piece crossed changes the count by its cover, and the count is 0 at the
 * top. Pieces are taken with half-open spans [l.x, r.x) (the ray-casting
 * rule: a vertex on the ray counts once), vertical ones not at all. */
static int32_t brute_cover(const polar *pd, int frame, vec2 f)
{
    uint32_t k;
    int32_t c = 0;
    for (k = 0; k < pd->nwall; k++) {
        vec2 l, r;
        int32_t d = frame_piece(pd, frame, k, &l, &r);
        if (l.x <= f.x && f.x < r.x && geom_orient(l, r, f) < 0)
            c -= d;
    }
    return c;
}

static int lex(vec2 a, vec2 b)
{
    if (a.x != b.x)
        return a.x < b.x ? -1 : 1;
    if (a.y != b.y)
        return a.y < b.y ? -1 : 1;
    return 0;
}

/* Orientation of f against piece k taken from its frame-left end. */
static int side_of(const polar *pd, int frame, uint32_t k, vec2 f)
{
    vec2 a = polar_fpt(pd, frame, pd->seg[k].a), b = polar_fpt(pd, frame, pd->seg[k].b);
    return lex(a, b) < 0 ? geom_orient(a, b, f) : geom_orient(b, a, f);
}

/* Does region t of map m hold frame point f strictly? */
static int region_holds(const polar *pd, const polar_map *m, uint32_t t, vec2 f)
{
    const polar_trap *r = &m->trap[t];
    return lex(polar_fpt(pd, m->frame, r->lp), f) < 0 &&
           lex(f, polar_fpt(pd, m->frame, r->rp)) < 0 &&
           side_of(pd, m->frame, r->top, f) < 0 && side_of(pd, m->frame, r->bot, f) > 0;
}

typedef struct stats {
    long points, dag_scan_diff, brute_bad;
    long n_region, n_on, n_in, owner_elsewhere, ring_diff;
    double depth_sum;
    uint32_t depth_max;
} stats;

/* Prints a disagreement with the brute force and the footprints holding p. */
static void report_bad(const polar *pd, int mi, vec2 p, int32_t r, int32_t od, int on, int in)
{
    uint32_t b, q;
    print_message("map %d p = (%.17g, %.17g): answer %d owner %d (brute %d), on a wall %d, "
                  "in a footprint %d\n", mi, p.x, p.y, r, od,
                  brute_owner(pd, pd->map[mi].frame, polar_to_frame(pd->map[mi].frame, p)), on, in);
    for (b = 0; b < pd->s->nbld; b++) {
        const scene_ring *rg = &pd->s->rings[pd->s->bld[b].ring_first];
        if (pd->s->bld[b].min_height > 0 || fp_where(pd->s, b, p) == GEOM_OUTSIDE)
            continue;
        print_message("  building %u (%d), outer ring:", b, fp_where(pd->s, b, p));
        for (q = 0; q < rg->count; q++)
            print_message(" (%.17g, %.17g)", pd->s->pts[rg->first + q].x,
                          pd->s->pts[rg->first + q].y);
        print_message("\n");
    }
}

/* Checks world point p (inside the open Bounds box) in both maps. */
static void check_point(const polar *pd, const polar_scan *g, vec2 p, stats *st)
{
    int mi;
    int on = -1, in = -1;
    for (mi = 0; mi < 2; mi++) {
        const polar_map *m = &pd->map[mi];
        vec2 f = polar_to_frame(m->frame, p);
        int32_t od, os, r, rs;
        uint32_t depth;
        int ok;
        r = polar_locate_frame_ex(pd, m, f, &od, &depth);
        rs = polar_scan_locate_frame(g, mi, f, &os);
        if (r != rs || od != os || r != polar_locate_frame(pd, m, f)) {
            if (st->dag_scan_diff++ < 5)
                print_message("map %d p = (%.17g, %.17g): DAG %d (owner %d), scan %d (owner %d)\n",
                              mi, p.x, p.y, r, od, rs, os);
        }
        st->depth_sum += depth;
        if (depth > st->depth_max)
            st->depth_max = depth;
        if (on < 0)
            on = on_any_piece(pd, p);
        if (r >= 0) {
            ok = !on && brute_cover(pd, m->frame, f) == 0 && (uint32_t)r < m->ntrap &&
                 region_holds(pd, m, (uint32_t)r, f);
            st->n_region++;
        } else if (r == -2) {
            ok = on;
            st->n_on++;
        } else if (r == -3) {
            ok = !on && brute_cover(pd, m->frame, f) > 0 && od == brute_owner(pd, m->frame, f);
            if (ok && od >= 0 && fp_where(pd->s, (uint32_t)od, p) == GEOM_OUTSIDE)
                st->owner_elsewhere++;
            st->n_in++;
        } else {
            ok = 0;
        }
        if (r >= 0 || r == -3) {
            if (in < 0)
                in = in_any(pd->s, p);
            if ((r >= 0) == in)
                st->ring_diff++;
        }
        if (!ok && st->brute_bad++ < 5)
            report_bad(pd, mi, p, r, od, on, in);
    }
    st->points++;
}

static int inside_open_box(const polar *pd, vec2 p)
{
    return p.x > pd->box[0] && p.x < pd->box[2] && p.y > pd->box[1] && p.y < pd->box[3];
}

/* n points of each kind: uniform, at a vertex, on a wall, with a vertex's
 * x (or y) and the other coordinate uniform or another vertex's. */
static void check_scene(const polar *pd, arena *a, int n, stats *st)
{
    polar_scan *g;
    arena_mark m0 = arena_get_mark(a);
    const double *bx = pd->box;
    int i, k;
    assert_int_equal(polar_scan_new(a, pd, &g), PLX_OK);
    for (i = 0; i < n; i++) {
        for (k = 0; k < 5; k++) {
            vec2 p, u, v;
            p.x = bx[0] + urand() * (bx[2] - bx[0]);
            p.y = bx[1] + urand() * (bx[3] - bx[1]);
            if (pd->nwall > 0) {
                const polar_seg *w = &pd->seg[irand(pd->nwall)];
                double t = urand();
                u = pd->pts[w->a];
                v = pd->pts[pd->seg[irand(pd->nwall)].b];
                if (k == 1)
                    p = u;
                else if (k == 2) {
                    vec2 b = pd->pts[w->b];
                    p.x = u.x + t * (b.x - u.x);
                    p.y = u.y + t * (b.y - u.y);
                    if (urand() < 0.3) {    /* the exact midpoint of axis-parallel walls */
                        p.x = 0.5 * (u.x + b.x);
                        p.y = 0.5 * (u.y + b.y);
                    }
                } else if (k == 3) {
                    p.x = u.x;
                    if (urand() < 0.5)
                        p.y = v.y;
                } else if (k == 4) {
                    p.y = u.y;
                    if (urand() < 0.5)
                        p.x = v.x;
                }
            }
            if (inside_open_box(pd, p))
                check_point(pd, g, p, st);
        }
    }
    arena_release(a, &m0);
}

static void report(const char *name, const stats *st)
{
    print_message("%s: %ld points x 2 maps: %ld in regions, %ld on walls, %ld in footprints; "
                  "depth mean %.1f max %u; DAG/scan differ %ld, brute force differs %ld; owner "
                  "across a party wall %ld; scene rings say otherwise %ld\n",
                  name, st->points, st->n_region, st->n_on, st->n_in,
                  st->depth_sum / (2.0 * (st->points ? st->points : 1)), st->depth_max,
                  st->dag_scan_diff, st->brute_bad, st->owner_elsewhere, st->ring_diff);
}

/* ---------------------------------------------------------- fixtures */

static long fixture_file(const char *path, int n)
{
    plx_engine *e;
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    polar *pd;
    stats st;
    memset(&st, 0, sizeof st);
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    assert_int_equal(plx_engine_new((size_t)256 << 20, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, path), PLX_OK);
    assert_int_equal(polar_build(&e->mem, e->sc, &pd), PLX_OK);
    check_scene(pd, &e->mem, n, &st);
    report(path, &st);
    assert_int_equal(st.dag_scan_diff, 0);
    assert_int_equal(st.brute_bad, 0);
    assert_true(st.n_region > 0 && st.n_on > 0 && st.n_in > 0);
    plx_engine_free(e);
    return st.points;
}

static void test_fixtures(void **state)
{
    long total = 0;
    (void)state;
    rnd_state = 4242u;
    total += fixture_file("fixtures/tiny.geojson", quick(400));
    total += fixture_file("fixtures/grid-4x4.geojson", quick(700));
    total += fixture_file("fixtures/oldtown-8x8.geojson", quick(700));
    total += fixture_file("fixtures/eixample-4x4.geojson", quick(700));
    total += fixture_file("fixtures/helsinki-centre.geojson", quick(1000));
    print_message("fixtures: %ld points in all\n", total);
    assert_true(total >= quick(15000));
}

/* ------------------------------------------------------ random scenes */

typedef struct fix {
    scene s;
    void *mem;
    arena a;
    polar *pd;
} fix;

static fix *fix_new(void)
{
    fix *f = calloc(1, sizeof *f);
    assert_non_null(f);
    ref_scene_init(&f->s);
    f->mem = malloc(ARENA_BYTES);
    assert_non_null(f->mem);
    arena_init(&f->a, f->mem, ARENA_BYTES);
    return f;
}

static void fix_free(fix *f)
{
    ref_scene_free(&f->s);
    free(f->mem);
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

/* Boxes with corners on a coarse lattice: shared walls, T-junctions,
 * collinear edges, overlaps, vertices with equal x or y everywhere; L
 * shapes and diamonds (45-degree walls) with corners on the lattice (half
 * steps); one courtyard building; some raised buildings (no occluders). */
static void lattice_scene(fix *f, int n, double cell)
{
    int i;
    for (i = 0; i < n; i++) {
        double x = irand(24) * cell, y = irand(24) * cell;
        double w = (1 + irand(4)) * cell, h = (1 + irand(4)) * cell;
        double r = urand();
        if (r < 0.7) {
            assert_true(ref_scene_add_box(&f->s, x, y, x + w, y + h, 10, 0) >= 0);
        } else if (r < 0.85) {
            double xy[12] = { x, y, x + w, y, x + w, y + h / 2, x + w / 2, y + h / 2,
                              x + w / 2, y + h, x, y + h };
            uint32_t k = 6;
            assert_true(ref_scene_add_building(&f->s, xy, &k, 1, 10, 0) >= 0);
        } else if (r < 0.95) {
            /* a diamond with its corners on the lattice: 45-degree walls */
            double xy[8] = { x + w / 2, y, x + w, y + w / 2, x + w / 2, y + w, x, y + w / 2 };
            uint32_t k = 4;
            assert_true(ref_scene_add_building(&f->s, xy, &k, 1, 10, 0) >= 0);
        } else {
            /* a raised building: no occluder */
            assert_true(ref_scene_add_box(&f->s, x, y, x + w, y + h, 10, 3) >= 0);
        }
    }
    {
        double xy[16] = { 30 * cell, 0, 40 * cell, 0, 40 * cell, 10 * cell, 30 * cell, 10 * cell,
                          32 * cell, 2 * cell, 32 * cell, 8 * cell, 38 * cell, 8 * cell,
                          38 * cell, 2 * cell };
        uint32_t k[2] = { 4, 4 };
        assert_true(ref_scene_add_building(&f->s, xy, k, 2, 20, 0) >= 0);
    }
}

/* Rotated boxes across the lattice: rounded crossing points, some with
 * walls of the lattice nearly collinear (angles of 1e-9 .. 1e-3 rad). */
static void rotated_across(fix *f, int n, double cell)
{
    int i;
    for (i = 0; i < n; i++) {
        double x = irand(24) * cell, y = irand(24) * cell, r = urand();
        double ang = r < 0.3 ? pow(10.0, -9.0 + 6.0 * urand()) : urand() * 3.14159;
        add_rotated(f, x + (r < 0.15 ? 0.0 : urand() * cell), y, (1 + irand(4)) * cell,
                    (1 + irand(4)) * cell, ang);
    }
}

static void test_random_degenerate(void **state)
{
    int k;
    stats st;
    (void)state;
    memset(&st, 0, sizeof st);
    rnd_state = 31337u;
    for (k = 0; k < 14; k++) {
        fix *f = fix_new();
        double cell = k % 3 == 0 ? 1.0 : k % 3 == 1 ? 0.25 : 8.0;
        lattice_scene(f, 10 + 12 * k, cell);
        rotated_across(f, 3 + 2 * k, cell);
        ref_scene_finish(&f->s);
        {
            /* rotated boxes crossing others have rounded crossing points;
             * the build cuts the pieces again where those make them touch:
             * no scene is left out */
            arena_mark mk = arena_get_mark(&f->a);
            plx_status s0 = polar_build_flags(&f->a, &f->s, POLAR_BUILD_NO_DAG, &f->pd);
            arena_release(&f->a, &mk);
            assert_int_equal(s0, PLX_OK);
            assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
        }
        check_scene(f->pd, &f->a, quick(150), &st);
        fix_free(f);
    }
    /* "scene rings say otherwise" counts points taken on the rotated walls
     * of the scene, which the pieces follow only to the rounding of their
     * crossing points (the brute force here is over the pieces) */
    report("lattice scenes", &st);
    assert_int_equal(st.dag_scan_diff, 0);
    assert_int_equal(st.brute_bad, 0);
    assert_true(st.n_region > 0 && st.n_on > 0 && st.n_in > 0);
    assert_true(st.points >= quick(8000));
}

/* Points on a fine lattice over a lattice scene: they fall on walls, at
 * vertices and on the axes of vertices in both frames far more often than
 * random points do. Once with nodes of 8 bytes, once packed (with the
 * nodes packed while built too). */
static void lattice_points(int flags)
{
    fix *f = fix_new();
    polar_scan *g;
    stats st;
    int i, j, step = getenv("PLX_TEST_QUICK") ? 4 : 1;
    memset(&st, 0, sizeof st);
    rnd_state = 99u;
    lattice_scene(f, 60, 1.0);
    ref_scene_finish(&f->s);
    assert_int_equal(polar_build_flags(&f->a, &f->s, flags, &f->pd), PLX_OK);
    assert_int_equal(f->pd->map[0].narrow, !(flags & POLAR_BUILD_WIDE_DAG));
    assert_int_equal(f->pd->map[1].narrow, !(flags & POLAR_BUILD_WIDE_DAG));
    assert_int_equal(polar_scan_new(&f->a, f->pd, &g), PLX_OK);
    for (i = -8; i <= 4 * 44; i += step) {
        for (j = -8; j <= 4 * 30; j += step) {
            vec2 p;
            p.x = i * 0.25;
            p.y = j * 0.25;
            check_point(f->pd, g, p, &st);
        }
    }
    report(flags & POLAR_BUILD_WIDE_DAG ? "lattice points, packed nodes"
                                        : "lattice points, 8-byte nodes", &st);
    assert_int_equal(st.dag_scan_diff, 0);
    assert_int_equal(st.brute_bad, 0);
    assert_true(st.n_on > 100 && st.n_in > 100 && st.n_region > 100);
    fix_free(f);
}

static void test_lattice_points(void **state)
{
    (void)state;
    lattice_points(0);
    lattice_points(POLAR_BUILD_WIDE_DAG);
}

/* --------------------------------------------------------- the comb */

/* One long thin footprint and n teeth above it: every region between the
 * teeth's axes sits on the long wall, which the grid scan walks one by one
 * (O(n) per point); the DAG's search paths stay O(log n). */
static void comb_depth(int n, double *mean, uint32_t *max)
{
    fix *f = fix_new();
    polar_scan *g;
    stats st;
    int i;
    double w = 2000.0 / n;
    memset(&st, 0, sizeof st);
    assert_true(ref_scene_add_box(&f->s, 0, 0, 2000, 1, 10, 0) >= 0);
    for (i = 0; i < n; i++)
        assert_true(ref_scene_add_box(&f->s, i * w, 2, i * w + w / 2, 3, 10, 0) >= 0);
    ref_scene_finish(&f->s);
    assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
    assert_int_equal(polar_scan_new(&f->a, f->pd, &g), PLX_OK);
    for (i = 0; i < quick(4000); i++) {
        vec2 p;
        p.x = urand() * 2000;
        p.y = urand() < 0.5 ? 1 + urand() : -40 + urand() * 80;
        /* the brute force is O(n) per point: every fourth point only */
        if (i % 4 == 0) {
            check_point(f->pd, g, p, &st);
        } else {
            int mi;
            for (mi = 0; mi < 2; mi++) {
                const polar_map *m = &f->pd->map[mi];
                vec2 q = polar_to_frame(m->frame, p);
                uint32_t d;
                int32_t r = polar_locate_frame_ex(f->pd, m, q, NULL, &d);
                if (r != polar_scan_locate_frame(g, mi, q, NULL))
                    st.dag_scan_diff++;
                st.depth_sum += d;
                if (d > st.depth_max)
                    st.depth_max = d;
            }
            st.points++;
        }
    }
    print_message("comb of %d teeth (%u wall pieces): DAG %u + %u nodes, depth mean %.1f max %u, "
                  "8 log2(pieces) = %.1f\n", n, f->pd->nwall, f->pd->map[0].nnode,
                  f->pd->map[1].nnode, st.depth_sum / (2.0 * st.points), st.depth_max,
                  8 * log2((double)f->pd->nwall));
    assert_int_equal(st.dag_scan_diff, 0);
    assert_int_equal(st.brute_bad, 0);
    assert_true(st.depth_max <= 8 * log2((double)f->pd->nwall));
    *mean = st.depth_sum / (2.0 * st.points);
    *max = st.depth_max;
    fix_free(f);
}

static void test_comb_depth(void **state)
{
    double m1, m2;
    uint32_t x1, x2;
    (void)state;
    rnd_state = 7u;
    comb_depth(250, &m1, &x1);
    comb_depth(4000, &m2, &x2);
    /* 16 times the pieces: the mean path grows by a few steps per doubling
     * (4 doublings), far from the 16-fold of a linear structure */
    assert_true(m2 < m1 + 4 * 6.0);
    assert_true(m2 < 3.0 * m1);
}

/* ------------------------------------------------ construction work */

/* Scenes hostile to a grid of walls, by kind. 1, "stack": n thin boxes
 * stacked in a 1 m column and n side by side in a 1 m row (1 m x 1/(2n) m each, gaps
 * between them), in a Bounds box of 10 km set by two far boxes: a grid
 * sized for the 8 n walls has cells of about 100 m, so one cell holds all
 * of them, and finding the wall below each event by scanning cells (the
 * former sweep) examines O(n) walls per event, O(n^2) in all. 0, "comb": the
 * comb above (n teeth over one long wall); 2, "terrace": the teeth standing
 * on it. */
static void work_scene(fix *f, int kind, int n)
{
    int i;
    double w = kind == 1 ? 1.0 / n : 2000.0 / n;
    if (kind != 1) {
        /* kind 2: the teeth stand on the long wall (a terrace: its top
         * wall cut at every tooth's corners, the shared stretches left out) */
        double y0 = kind ? 1 : 2;
        assert_true(ref_scene_add_box(&f->s, 0, 0, 2000, 1, 10, 0) >= 0);
        for (i = 0; i < n; i++)
            assert_true(ref_scene_add_box(&f->s, i * w, y0, i * w + w / 2, y0 + 1, 10, 0) >= 0);
        return;
    }
    assert_true(ref_scene_add_box(&f->s, -5000, -5000, -4999, -4999, 10, 0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 4999, 4999, 5000, 5000, 10, 0) >= 0);
    for (i = 0; i < n; i++) {
        assert_true(ref_scene_add_box(&f->s, 0, i * w, 1, i * w + w / 2, 10, 0) >= 0);
        assert_true(ref_scene_add_box(&f->s, 2 + i * w, 0, 2 + i * w + w / 2, 1, 10, 0) >= 0);
    }
}

/* Builds the scene; returns the construction steps per piece and per
 * log2(pieces), and checks a few points against the brute force. */
static double work_per_piece(int kind, int n)
{
    fix *f = fix_new();
    polar_scan *g;
    stats st;
    double per, lg;
    int i;
    memset(&st, 0, sizeof st);
    work_scene(f, kind, n);
    ref_scene_finish(&f->s);
    assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
    lg = log2((double)f->pd->nwall);
    per = (double)f->pd->steps / f->pd->nwall / lg;
    print_message("%s of %d: %u wall pieces, %llu construction steps = %.2f per piece "
                  "per log2(pieces)\n", kind == 1 ? "stack" : kind ? "terrace" : "comb", n,
                  f->pd->nwall,
                  (unsigned long long)f->pd->steps, per);
    assert_int_equal(polar_scan_new(&f->a, f->pd, &g), PLX_OK);
    for (i = 0; i < quick(400); i++) {
        vec2 p;
        if (kind == 1) {
            p.x = -0.5 + 4 * urand();
            p.y = -0.5 + 2 * urand();
        } else {
            p.x = urand() * 2000;
            p.y = -2 + 6 * urand();
        }
        check_point(f->pd, g, p, &st);
    }
    assert_int_equal(st.dag_scan_diff, 0);
    assert_int_equal(st.brute_bad, 0);
    fix_free(f);
    return per;
}

/* The construction does O(n log n) expected steps on scenes where a grid
 * scan per event would do O(n^2): steps per piece per log2(pieces) stay
 * under a constant as n grows 16-fold (measured about 2.2). The former
 * sweep's grid scan examined every wall of the one cell for each event
 * where walls only start (thousands per piece at the larger stack: its
 * build took 2.2 s for 4000 stacked pairs, 35 s for 16,000). */
static void test_construction_work(void **state)
{
    int kind;
    (void)state;
    rnd_state = 5u;
    for (kind = 0; kind < 3; kind++) {
        double w1 = work_per_piece(kind, 250), w2 = work_per_piece(kind, 4000);
        assert_true(w1 < 6.0);
        assert_true(w2 < 6.0);
        assert_true(w2 < 2.0 * w1);
    }
}

/* ------------------------------------------------------- fault injection */

/* Every memory request failing in turn on a scene whose DAGs need several
 * chunks of nodes: NOMEM, the arena as it was, until the build succeeds;
 * then a build in an arena too small by a little fails the same way. */
static void test_fault_injection(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    fix *f = fix_new();
    uint64_t k;
    size_t need;
    arena_mark m0;
    (void)state;
    rnd_state = 12u;
    {
        /* 50 x 50 cells of 10 m: a box filling the cell (walls shared with
         * the neighbours), a smaller box, or a rotated box inside it */
        int i, j;
        for (i = 0; i < 50; i++)
            for (j = 0; j < 50; j++) {
                double x = i * 10.0, y = j * 10.0, r = urand();
                if (r < 0.3)
                    assert_true(ref_scene_add_box(&f->s, x, y, x + 10, y + 10, 10, 0) >= 0);
                else if (r < 0.7)
                    assert_true(ref_scene_add_box(&f->s, x + 1, y + 2, x + 8, y + 9, 10, 0) >= 0);
                else
                    add_rotated(f, x + 5, y + 1, 4, 3, 0.3 + urand());
            }
    }
    ref_scene_finish(&f->s);
    m0 = arena_get_mark(&f->a);
    k = polar_build_each_failure(&f->a, &f->s, &f->pd, 99999);
    print_message("fault injection: %d requests, %u wall pieces, DAG nodes %u + %u\n", (int)k,
                  f->pd->nwall, f->pd->map[0].nnode, f->pd->map[1].nnode);
    assert_true(f->pd->map[0].nnode > 2 * 16384 && f->pd->map[1].nnode > 2 * 16384);
    assert_true(k > 20);
    /* a budget on the polar part a little short of what it needs */
    need = f->a.used[PLX_PART_POLAR] - m0.used[PLX_PART_POLAR];
    arena_release(&f->a, &m0);
    f->a.budget[PLX_PART_POLAR] = m0.used[PLX_PART_POLAR] + need - 16;
    assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_E_NOMEM);
    assert_int_equal(f->a.lo, m0.lo);
    assert_int_equal(f->a.hi, m0.hi);
    f->a.budget[PLX_PART_POLAR] = m0.used[PLX_PART_POLAR] + need;
    assert_int_equal(polar_build(&f->a, &f->s, &f->pd), PLX_OK);
    fix_free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fixtures),
        cmocka_unit_test(test_random_degenerate),
        cmocka_unit_test(test_lattice_points),
        cmocka_unit_test(test_comb_depth),
        cmocka_unit_test(test_construction_work),
        cmocka_unit_test(test_fault_injection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
