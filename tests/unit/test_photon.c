/* photon: the 2.5D ray caster against brute force, energy balance in a
 * closed box, flux conservation through splatting, a one-bounce case with
 * an analytic (numerically integrated) answer, accuracy on the eixample
 * fixture against an independent path-traced estimate, the lamp cache
 * (LRU) and its exchange with the aerial chart, levels for a moving
 * viewer, histogram matching, and out-of-memory at creation.
 *
 * PLX_PHOTON_FULL=1 runs the accuracy tables with more photons and more
 * reference paths (slower). PLX_TEST_QUICK=1 (valgrind) runs them with far
 * fewer photons and checks only looser bounds (printed). */
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
#include "fixture.h"
#include "base/engine.h"
#include "base/arena.h"
#include "scene/blocks.h"
#include "photon/trace.h"
#include "photon/indirect.h"
#include "photon/nightlight.h"
#include "render/nightify.h"
#include "ref_scene.h"
#include "ref_indirect.h"
#include "slow.h"

#define PI 3.14159265358979323846

static int full_mode(void)
{
    const char *v = getenv("PLX_PHOTON_FULL");
    return v && v[0] && v[0] != '0';
}

static int quick_mode(void)
{
    const char *v = getenv("PLX_TEST_QUICK");
    return v && v[0] && v[0] != '0';
}

static uint64_t rng_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double urand(uint64_t *s)
{
    return (rng_next(s) >> 11) * (1.0 / 9007199254740992.0);
}

static void sphere_dir(uint64_t *s, double d[3])
{
    double z = 1.0 - 2.0 * urand(s), r = sqrt(1.0 - z * z), p = 2.0 * PI * urand(s);
    d[0] = r * cos(p);
    d[1] = r * sin(p);
    d[2] = z;
}

/* ---- a scene from arrays with its blocks, in an arena on the heap ------- */

typedef struct fixture {
    scene s;
    void *mem;
    arena a;
} fixture;

static void fx_open(fixture *f, size_t bytes)
{
    ref_scene_init(&f->s);
    f->mem = malloc(bytes);
    assert_non_null(f->mem);
    arena_init(&f->a, f->mem, bytes);
}

static void fx_finish(fixture *f)
{
    ref_scene_finish(&f->s);
    assert_int_equal(blocks_build(&f->a, &f->s, 0.05), PLX_OK);
}

static void fx_close(fixture *f)
{
    ref_scene_free(&f->s);
    free(f->mem);
}

/* ---- brute-force ray casting, written independently of src/photon/trace.c ------ */

/*
 * First hit by plane tests against every face of every building, with the
 * caster's contract: walls are one-sided (met from outside the solid, the
 * solid lying left of every ring edge: d x e < 0), faces closed (a roof is
 * hit on its outline too), 1e-12 < t. Returns the kind of the nearest hit
 * (TRACE_SKY if none) and in *tie the set (bit mask over kinds) of kinds
 * met within 'tol' of it: at a tie (a ray through the top edge of a wall
 * meets the wall and the roof at once) either is right.
 */
static int brute_cast_tie(const scene *s, const double o[3], const double d[3], double tol,
                          double *tout, unsigned *tie)
{
    double ts[64];
    int ks[64], n = 0, i, kind = TRACE_SKY;
    double best = INFINITY;
    uint32_t b;
    if (d[2] < 0.0 && o[2] > 0.0) {
        ts[n] = -o[2] / d[2];
        ks[n++] = TRACE_GROUND;
    }
    for (b = 0; b < s->nbld; b++) {
        const scene_building *B = &s->bld[b];
        uint32_t r;
        for (r = 0; r < B->ring_count; r++) {
            const scene_ring *R = &s->rings[B->ring_first + r];
            uint32_t k;
            for (k = 0; k < R->count; k++) {
                const vec2 *p = &s->pts[R->first + k];
                const vec2 *q = &s->pts[R->first + (k + 1) % R->count];
                /* o + t d = p + u (q - p) in the plane */
                double ex = q->x - p->x, ey = q->y - p->y;
                double den = d[0] * ey - d[1] * ex, t, u, z;
                if (!(den < 0.0))
                    continue;
                t = ((p->x - o[0]) * ey - (p->y - o[1]) * ex) / den;
                u = ((p->x - o[0]) * d[1] - (p->y - o[1]) * d[0]) / den;
                z = o[2] + t * d[2];
                if (t > 1e-12 && u >= 0.0 && u <= 1.0 && z >= B->min_height && z <= B->height &&
                    n < 64) {
                    ts[n] = t;
                    ks[n++] = TRACE_WALL;
                }
            }
        }
        if (d[2] != 0.0) {
            double zs[2];
            zs[0] = B->height;
            zs[1] = B->min_height;
            for (i = 0; i < 2; i++) {
                double t = (zs[i] - o[2]) / d[2];
                if (i == 1 && B->min_height <= 0.0)
                    continue;
                if ((i == 0) != (d[2] < 0.0))
                    continue; /* roofs are met going down, undersides going up */
                if (t > 1e-12 && n < 64 &&
                    ref_footprint_where(s, b, o[0] + t * d[0], o[1] + t * d[1]) != REF_OUT) {
                    ts[n] = t;
                    ks[n++] = i == 0 ? TRACE_ROOF : TRACE_UNDER;
                }
            }
        }
    }
    for (i = 0; i < n; i++)
        if (ts[i] < best) {
            best = ts[i];
            kind = ks[i];
        }
    *tie = 0;
    for (i = 0; i < n; i++)
        if (ts[i] <= best + tol * (1.0 + best))
            *tie |= 1u << ks[i];
    *tout = best;
    return kind;
}

static int brute_cast(const scene *s, const double o[3], const double d[3], double *tout)
{
    unsigned tie;
    return brute_cast_tie(s, o, d, 1e-9, tout, &tie);
}

/* Hit tolerance: |t - t_brute| <= TRACE_TOL (1 + t_brute). */
#define TRACE_TOL 1e-9

/* Whether the caster's answer h agrees with the brute force on o + t d,
 * t < tmax: no hit for no hit, else a kind among those tied first and the
 * same t within TRACE_TOL. Prints the first few disagreements. */
static int trace_agrees_tmax(const scene *s, const double o[3], const double d[3], double tmax,
                             const trace_hit *h, int *shown)
{
    double tb;
    unsigned tie;
    int kb = brute_cast_tie(s, o, d, TRACE_TOL, &tb, &tie);
    if (!(tb < tmax))
        kb = TRACE_SKY;
    if (kb == TRACE_SKY ? h->kind == TRACE_SKY
                        : ((tie >> h->kind) & 1u) && fabs(h->t - tb) <= TRACE_TOL * (1.0 + tb))
        return 1;
    if ((*shown)++ < 8)
        printf("mismatch: o %.17g %.17g %.17g d %.17g %.17g %.17g: brute %d t=%.12f (ties %x), "
               "trace %d t=%.12f\n",
               o[0], o[1], o[2], d[0], d[1], d[2], kb, tb, tie, h->kind, h->t);
    return 0;
}

static int in_solid(const scene *s, const double p[3])
{
    uint32_t b;
    for (b = 0; b < s->nbld; b++)
        if (p[2] >= s->bld[b].min_height - 1e-9 && p[2] <= s->bld[b].height + 1e-9 &&
            ref_footprint_where(s, b, p[0], p[1]) != REF_OUT)
            return 1;
    return 0;
}

/* Random city: boxes on a jittered grid (some touching, some raised, some
 * with a courtyard), an L-shape and a hexagon. */
static void random_city(fixture *f, uint64_t seed)
{
    uint64_t rs = seed;
    int i, j;
    for (j = 0; j < 6; j++)
        for (i = 0; i < 6; i++) {
            double x0 = i * 30.0 + 4.0 * urand(&rs), y0 = j * 30.0 + 4.0 * urand(&rs);
            double w = 10.0 + 16.0 * urand(&rs), h = 10.0 + 16.0 * urand(&rs);
            double ht = 5.0 + 30.0 * urand(&rs), mh = urand(&rs) < 0.2 ? 3.0 + 2.0 * urand(&rs) : 0.0;
            if ((i + j) % 7 == 3) {
                double xy[16] = {x0, y0, x0 + w, y0, x0 + w, y0 + h, x0, y0 + h,
                                 x0 + 3, y0 + 3, x0 + 3, y0 + h - 3, x0 + w - 3, y0 + h - 3,
                                 x0 + w - 3, y0 + 3};
                uint32_t rn[2] = {4, 4};
                assert_true(ref_scene_add_building(&f->s, xy, rn, 2, ht, 0.0) >= 0);
            } else {
                assert_true(ref_scene_add_box(&f->s, x0, y0, x0 + w, y0 + h, ht, mh) >= 0);
            }
        }
    {
        double xy[12] = {200, 0, 230, 0, 230, 10, 210, 10, 210, 40, 200, 40};
        uint32_t rn[1] = {6};
        assert_true(ref_scene_add_building(&f->s, xy, rn, 1, 22.0, 0.0) >= 0);
    }
    {
        double xy[12];
        uint32_t rn[1] = {6};
        int k;
        for (k = 0; k < 6; k++) {
            xy[2 * k] = 215.0 + 9.0 * cos(k * PI / 3.0 + 0.2);
            xy[2 * k + 1] = 100.0 + 9.0 * sin(k * PI / 3.0 + 0.2);
        }
        assert_true(ref_scene_add_building(&f->s, xy, rn, 1, 14.0, 0.0) >= 0);
    }
    /* two boxes sharing a wall, different heights */
    assert_true(ref_scene_add_box(&f->s, 200, 150, 215, 170, 12.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 215, 150, 230, 170, 20.0, 0.0) >= 0);
}

static int trace_agrees(const scene *s, const double o[3], const double d[3],
                        const trace_hit *h, int *shown)
{
    return trace_agrees_tmax(s, o, d, INFINITY, h, shown);
}

static void test_trace_vs_brute(void **state)
{
    fixture f;
    tracer *T;
    uint64_t rs = 77;
    int n = full_mode() ? 100000 : quick_mode() ? 1000 : 20000, done = 0, mism = 0, shown = 0;
    int kinds[5] = {0, 0, 0, 0, 0};
    (void)state;
    fx_open(&f, 8u << 20);
    random_city(&f, 5);
    fx_finish(&f);
    assert_int_equal(trace_create(&f.a, PLX_PART_PHOTON, &f.s, 0.0, &T), PLX_OK);
    while (done < n) {
        double o[3], d[3], dz;
        trace_hit h, h2;
        int kt;
        o[0] = f.s.bounds[0] + (f.s.bounds[2] - f.s.bounds[0]) * urand(&rs);
        o[1] = f.s.bounds[1] + (f.s.bounds[3] - f.s.bounds[1]) * urand(&rs);
        o[2] = 45.0 * urand(&rs);
        if (in_solid(&f.s, o))
            continue;
        sphere_dir(&rs, d);
        if (done % 10 == 0) { /* some horizontal and vertical rays */
            dz = d[2];
            d[2] = 0.0;
            if (done % 20 == 0) {
                d[0] = d[1] = 0.0;
                d[2] = dz < 0 ? -1.0 : 1.0;
            } else {
                double l = hypot(d[0], d[1]);
                d[0] /= l;
                d[1] /= l;
            }
        }
        kt = trace_ray(T, o, d, INFINITY, &h);
        trace_ray_brute(T, o, d, INFINITY, &h2);
        done++;
        kinds[kt]++;
        /* the walk finds what testing every building finds */
        if (!trace_agrees(&f.s, o, d, &h, &shown) || h2.kind != kt ||
            (kt != TRACE_SKY && fabs(h2.t - h.t) > 1e-12 * (1.0 + h.t)))
            mism++;
    }
    printf("trace vs brute force: %d rays, %d mismatches (sky %d ground %d wall %d roof %d "
           "under %d)\n",
           done, mism, kinds[0], kinds[1], kinds[2], kinds[3], kinds[4]);
    assert_int_equal(mism, 0);
    assert_true(kinds[TRACE_WALL] > n / 10 && kinds[TRACE_ROOF] > n / 50 &&
                kinds[TRACE_UNDER] > 0 && kinds[TRACE_GROUND] > n / 10);
    /* trace_top: roofs and ground */
    {
        int k;
        for (k = 0; k < 2000; k++) {
            double x = f.s.bounds[0] + (f.s.bounds[2] - f.s.bounds[0]) * urand(&rs);
            double y = f.s.bounds[1] + (f.s.bounds[3] - f.s.bounds[1]) * urand(&rs);
            double top = 0.0, o[3], d[3] = {0, 0, -1}, tb;
            uint32_t b;
            o[0] = x;
            o[1] = y;
            o[2] = 100.0;
            if (brute_cast(&f.s, o, d, &tb) == TRACE_ROOF)
                top = 100.0 - tb;
            for (b = 0; b < f.s.nbld; b++)
                if (ref_footprint_where(&f.s, b, x, y) == REF_ON)
                    break;
            if (b < f.s.nbld)
                continue; /* on an edge: either way */
            assert_true(fabs(trace_top(T, x, y, NULL) - top) < 1e-9);
        }
    }
    fx_close(&f);
}

/* ---- degenerate rays on a city with exact coordinates -------------------- */

/* Boxes sharing a wall (A, B), a raised box (C), a courtyard (D), an
 * L-shape (E), an octagon with 45-degree faces (F), a box as tall as A (G).
 * Integer coordinates: rays along walls, through corners and at roof
 * heights are computed exactly. */
static void exact_city(fixture *f, const double (*lamps)[4], int nl)
{
    double dxy[16] = {0, 20, 30, 20, 30, 50, 0, 50, 10, 30, 10, 40, 20, 40, 20, 30};
    double exy[12] = {50, 0, 70, 0, 70, 10, 60, 10, 60, 30, 50, 30};
    double fxy[16] = {82, 0, 88, 0, 90, 2, 90, 8, 88, 10, 82, 10, 80, 8, 80, 2};
    uint32_t dn[2] = {4, 4}, en[1] = {6}, fn[1] = {8};
    int i;
    fx_open(f, 16u << 20);
    assert_true(ref_scene_add_box(&f->s, 0, 0, 10, 10, 10.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 10, 0, 20, 10, 15.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 30, 0, 40, 10, 12.0, 4.0) >= 0);
    assert_true(ref_scene_add_building(&f->s, dxy, dn, 2, 12.0, 0.0) >= 0);
    assert_true(ref_scene_add_building(&f->s, exy, en, 1, 20.0, 0.0) >= 0);
    assert_true(ref_scene_add_building(&f->s, fxy, fn, 1, 9.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 50, 40, 60, 50, 10.0, 0.0) >= 0);
    for (i = 0; i < nl; i++)
        assert_true(ref_scene_add_lamp(&f->s, lamps[i][0], lamps[i][1], lamps[i][2], 1000,
                                       lamps[i][3]) >= 0);
    fx_finish(f);
}

typedef struct ray_check {
    const scene *s;
    tracer *T[3];
    int nt, rays, mism, shown, kinds[5];
} ray_check;

/* One ray through every tracer (different cell sizes), each against the
 * brute force. */
static void check_ray(ray_check *c, const double o[3], const double d[3])
{
    int i;
    for (i = 0; i < c->nt; i++) {
        trace_hit h;
        trace_ray(c->T[i], o, d, INFINITY, &h);
        c->kinds[h.kind]++;
        if (!trace_agrees(c->s, o, d, &h, &c->shown))
            c->mism++;
    }
    c->rays++;
}

static const double exact_z[] = {0.0, 2.0, 4.0, 6.0, 9.0, 10.0, 12.0, 15.0, 20.0, 25.0};
#define NEXACT_Z (sizeof exact_z / sizeof exact_z[0])

/* Rays along the line of every edge (from outside its ends, both ways),
 * level and tilted, at the listed heights; and the same lines shifted to
 * pass exactly through the edge's ends diagonally. */
static void rays_along_edges(ray_check *c, uint64_t *rs)
{
    const scene *s = c->s;
    uint32_t e;
    for (e = 0; e < s->npts; e++) {
        uint32_t r, nxt = e + 1;
        const vec2 *p, *q;
        double ex, ey, l, o[3], d[3];
        unsigned z;
        int side, tilt;
        for (r = 0; r < s->nrings; r++)
            if (e + 1 == s->rings[r].first + s->rings[r].count)
                nxt = s->rings[r].first;
        p = &s->pts[e];
        q = &s->pts[nxt];
        ex = q->x - p->x;
        ey = q->y - p->y;
        l = sqrt(ex * ex + ey * ey);
        for (z = 0; z < NEXACT_Z; z++)
            for (side = 0; side < 2; side++)
                for (tilt = -1; tilt <= 1; tilt++) {
                    double sg = side ? -1.0 : 1.0, k = 3.0 + (double)(photon_rand(rs) % 4);
                    const vec2 *a = side ? q : p;
                    o[0] = a->x - sg * k * ex / l;
                    o[1] = a->y - sg * k * ey / l;
                    o[2] = exact_z[z];
                    d[0] = sg * ex / l;
                    d[1] = sg * ey / l;
                    d[2] = 0.25 * tilt;
                    if (tilt) {
                        double m = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                        d[0] /= m;
                        d[1] /= m;
                        d[2] /= m;
                    }
                    if (!in_solid(s, o))
                        check_ray(c, o, d);
                    /* diagonally through the end a (axis-aligned edges) */
                    if (ex == 0.0 || ey == 0.0) {
                        int qx, qy;
                        for (qx = -1; qx <= 1; qx += 2)
                            for (qy = -1; qy <= 1; qy += 2) {
                                o[0] = a->x + qx * k;
                                o[1] = a->y + qy * k;
                                o[2] = exact_z[z];
                                d[0] = -qx * sqrt(0.5);
                                d[1] = -qy * sqrt(0.5);
                                d[2] = 0.0;
                                if (!in_solid(s, o))
                                    check_ray(c, o, d);
                            }
                    }
                }
    }
}

/* Rays that start on a wall (edge midpoints, exact) and leave it: random
 * directions in the outer half space, and along the wall both ways. */
static void rays_from_walls(ray_check *c, uint64_t *rs)
{
    const scene *s = c->s;
    uint32_t e;
    for (e = 0; e < s->npts; e++) {
        uint32_t r, nxt = e + 1, b;
        const vec2 *p, *q;
        double ex, ey, l, n[2], o[3], d[3];
        int k;
        for (r = 0; r < s->nrings; r++)
            if (e + 1 == s->rings[r].first + s->rings[r].count)
                nxt = s->rings[r].first;
        for (b = 0; b < s->nbld; b++)
            if (e >= s->rings[s->bld[b].ring_first].first)
                r = b; /* the building of edge e (rings in building order) */
        b = r;
        p = &s->pts[e];
        q = &s->pts[nxt];
        ex = q->x - p->x;
        ey = q->y - p->y;
        l = sqrt(ex * ex + ey * ey);
        n[0] = ey / l;
        n[1] = -ex / l;
        for (k = 0; k < 24; k++) {
            o[0] = 0.5 * (p->x + q->x);
            o[1] = 0.5 * (p->y + q->y);
            o[2] = k < 4 ? exact_z[k + 2] : s->bld[b].min_height +
                                                 (s->bld[b].height - s->bld[b].min_height) *
                                                     urand(rs);
            if (k < 2) {
                d[0] = (k ? -1.0 : 1.0) * ex / l;
                d[1] = (k ? -1.0 : 1.0) * ey / l;
                d[2] = 0.0;
            } else {
                sphere_dir(rs, d);
                if (d[0] * n[0] + d[1] * n[1] < 0.0) {
                    double dn = d[0] * n[0] + d[1] * n[1];
                    d[0] -= 2.0 * dn * n[0];
                    d[1] -= 2.0 * dn * n[1];
                }
            }
            check_ray(c, o, d);
        }
    }
}

/* Rays from given points in random, level, vertical and axis directions. */
static void rays_from(ray_check *c, uint64_t *rs, double x, double y, double z, int nrand)
{
    static const double axis[8][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1},
                                      {1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
    double o[3], d[3];
    int k;
    o[0] = x;
    o[1] = y;
    o[2] = z;
    if (in_solid(c->s, o))
        return;
    for (k = 0; k < 8; k++) {
        double m = sqrt(axis[k][0] * axis[k][0] + axis[k][1] * axis[k][1]);
        d[0] = axis[k][0] / m;
        d[1] = axis[k][1] / m;
        d[2] = 0.0;
        check_ray(c, o, d);
    }
    d[0] = d[1] = 0.0;
    d[2] = 1.0;
    check_ray(c, o, d);
    d[2] = -1.0;
    check_ray(c, o, d);
    for (k = 0; k < nrand; k++) {
        sphere_dir(rs, d);
        if (k % 3 == 0) {
            double m = hypot(d[0], d[1]);
            d[0] /= m;
            d[1] /= m;
            d[2] = 0.0;
        }
        check_ray(c, o, d);
    }
}

/* trace_horizon_sky and trace_box_clear only ever claim what the walk
 * (and testing every building) finds: rays going up from points on the
 * ground and on roofs (as final gathers cast them: 1e-6 m above, some at
 * a wall's foot), and horizontal rays inside boxes said to be clear. */
static void test_trace_horizon(void **state)
{
    fixture f;
    tracer *T;
    uint64_t rs = 91;
    int pts = quick_mode() ? 150 : 1500, p, k, rays = 0, sky = 0, skipped = 0, boxes = 0, clear = 0;
    (void)state;
    fx_open(&f, 8u << 20);
    random_city(&f, 5);
    fx_finish(&f);
    assert_int_equal(trace_create(&f.a, PLX_PART_PHOTON, &f.s, 0.0, &T), PLX_OK);
    for (p = 0; p < pts; p++) {
        double o[3], d[3];
        trace_horizon hz;
        trace_hit h, h2;
        o[0] = f.s.bounds[0] + (f.s.bounds[2] - f.s.bounds[0]) * urand(&rs);
        o[1] = f.s.bounds[1] + (f.s.bounds[3] - f.s.bounds[1]) * urand(&rs);
        if (p % 5 == 0) { /* at a wall's foot */
            const vec2 *q = &f.s.pts[(uint32_t)(urand(&rs) * f.s.npts) % f.s.npts];
            o[0] = q->x + 1e-7 * (urand(&rs) - 0.5);
            o[1] = q->y + 1e-7 * (urand(&rs) - 0.5);
        }
        o[2] = trace_top(T, o[0], o[1], NULL) + 1e-6;
        trace_horizon_make(T, o, &hz);
        for (k = 0; k < 200; k++) {
            double u1 = urand(&rs), u2 = urand(&rs), r = sqrt(u1);
            d[0] = r * cos(2.0 * PI * u2);
            d[1] = r * sin(2.0 * PI * u2);
            d[2] = sqrt(1.0 - u1);
            rays++;
            if (!trace_horizon_sky(&hz, d))
                continue;
            skipped++;
            sky += trace_ray(T, o, d, INFINITY, &h) == TRACE_SKY &&
                   trace_ray_brute(T, o, d, INFINITY, &h2) == TRACE_SKY;
        }
    }
    for (p = 0; p < pts; p++) {
        double x0 = f.s.bounds[0] + (f.s.bounds[2] - f.s.bounds[0]) * urand(&rs), y0 =
            f.s.bounds[1] + (f.s.bounds[3] - f.s.bounds[1]) * urand(&rs), sz = 2.0 + 14.0 * urand(&rs);
        double z = p % 3 ? 25.0 * urand(&rs) : 0.05, o[3], q[3], d[3], l;
        trace_hit h;
        boxes++;
        if (!trace_box_clear(T, x0, y0, x0 + sz, y0 + sz, z, z))
            continue;
        clear++;
        for (k = 0; k < 20; k++) {
            o[0] = x0 + sz * urand(&rs);
            o[1] = y0 + sz * urand(&rs);
            q[0] = x0 + sz * (k & 1);
            q[1] = y0 + sz * ((k >> 1) & 1);
            if (k >= 4) {
                q[0] = x0 + sz * urand(&rs);
                q[1] = y0 + sz * urand(&rs);
            }
            d[0] = q[0] - o[0];
            d[1] = q[1] - o[1];
            d[2] = 0.0;
            l = hypot(d[0], d[1]);
            if (!(l > 1e-9))
                continue;
            d[0] /= l;
            d[1] /= l;
            o[2] = z;
            assert_int_equal(trace_ray_brute(T, o, d, l, &h), TRACE_SKY);
        }
    }
    printf("horizon: %d upward rays, %d said to meet nothing (all do: %d); boxes: %d of %d clear\n", rays,
           skipped, sky, clear, boxes);
    assert_int_equal(sky, skipped);
    assert_true(skipped > rays / 5);
    assert_true(clear > boxes / 10 && clear < boxes);
    fx_close(&f);
}

static void test_trace_degenerate(void **state)
{
    fixture f;
    ray_check c;
    uint64_t rs = 4242;
    static const double cells[3] = {0.0, 10.0, 5.0};
    static const double lamps[][2] = {{5, -5}, {25, 5}, {45, 5}, {55, 35}, {75, 20},
                                      {85, -3}, {-3, 15}, {35, 25}};
    int i, nr = quick_mode() ? 20 : 120;
    unsigned z;
    (void)state;
    exact_city(&f, NULL, 0);
    memset(&c, 0, sizeof c);
    c.s = &f.s;
    c.nt = 3;
    /* cells of 10 and 5 m put cell borders on the walls (bounds start at -50) */
    for (i = 0; i < c.nt; i++)
        assert_int_equal(trace_create(&f.a, PLX_PART_PHOTON, &f.s, cells[i], &c.T[i]), PLX_OK);
    rays_along_edges(&c, &rs);
    printf("  along edges and through corners: %d rays\n", c.rays);
    rays_from_walls(&c, &rs);
    printf("  + from walls outwards: %d rays\n", c.rays);
    /* lamps at roof height (A and G: 10 m) and at other exact heights */
    for (i = 0; i < (int)(sizeof lamps / sizeof lamps[0]); i++)
        for (z = 0; z < NEXACT_Z; z++)
            rays_from(&c, &rs, lamps[i][0], lamps[i][1], exact_z[z], nr / 4);
    printf("  + from street points at exact heights (roof heights too): %d rays\n", c.rays);
    /* under the raised box C (min_height 4), into the courtyard of D, above roofs */
    for (z = 0; z < 4; z++) {
        static const double under[4] = {0.5, 2.0, 3.5, 3.999};
        rays_from(&c, &rs, 35, 5, under[z], nr);
        rays_from(&c, &rs, 25, 5, under[z], nr / 4);
    }
    for (z = 0; z < NEXACT_Z; z++) {
        rays_from(&c, &rs, 15, 35, exact_z[z], nr / 2);
        rays_from(&c, &rs, 12, 38, exact_z[z], nr / 4);
    }
    rays_from(&c, &rs, 5, 5, 30, nr);
    rays_from(&c, &rs, 35, 5, 30, nr);
    rays_from(&c, &rs, 85, 5, 9.5, nr);
    printf("trace on degenerate rays (x3 cell sizes): %d rays, %d mismatches (sky %d ground %d "
           "wall %d roof %d under %d)\n",
           c.rays, c.mism, c.kinds[0], c.kinds[1], c.kinds[2], c.kinds[3], c.kinds[4]);
    assert_int_equal(c.mism, 0);
    assert_true(c.kinds[TRACE_WALL] > 0 && c.kinds[TRACE_ROOF] > 0 && c.kinds[TRACE_UNDER] > 0 &&
                c.kinds[TRACE_GROUND] > 0 && c.kinds[TRACE_SKY] > 0);
    /* a few answers fixed by hand: along A's bottom wall into A's corner,
     * level at A's roof height into its wall's top edge, under C at 2 m
     * (passes) and at 4 m (its wall's bottom edge), up into C's underside */
    {
        static const double cases[][7] = {{-5, 0, 3, 1, 0, 0, 5},   {5, -5, 10, 0, 1, 0, 5},
                                          {25, 5, 2, 1, 0, 0, 25},  {25, 5, 4, 1, 0, 0, 5},
                                          {35, 5, 1, 0, 0, 1, 3},   {15, 35, 6, 1, 0, 0, 5}};
        static const int kinds[] = {TRACE_WALL, TRACE_WALL, TRACE_WALL,
                                    TRACE_WALL, TRACE_UNDER, TRACE_WALL};
        for (i = 0; i < 6; i++) {
            trace_hit h;
            assert_int_equal(trace_ray(c.T[1], cases[i], cases[i] + 3, INFINITY, &h), kinds[i]);
            assert_true(fabs(h.t - cases[i][6]) < 1e-12);
        }
    }
    fx_close(&f);
}

/* ---- rays from lamps (trace_lamp_ray) ---------------------------------- */

/* trace_lamp_ray against the brute force (tmax = the lamp's radius) and
 * against trace_ray from the same point, on lamps of both test cities:
 * random ones at random heights and at roof heights, and exact ones at
 * the degenerate spots; directions random, level, vertical, axis and
 * exactly at building corners. */
static int lamp_rays(fixture *f, uint64_t *rs, int nrand, int *kinds, int *shown)
{
    tracer *T;
    uint32_t l, v, fast = 0;
    int mism = 0, k;
    assert_int_equal(trace_create(&f->a, PLX_PART_PHOTON, &f->s, 0.0, &T), PLX_OK);
    for (l = 0; l < f->s.nlamps; l++)
        fast += T->lfast[l];
    printf("  %u of %u lamps with a table\n", fast, f->s.nlamps);
    assert_true(fast * 4 >= f->s.nlamps * 3);
    for (l = 0; l < f->s.nlamps; l++) {
        const scene_lamp *L = &f->s.lamps[l];
        double o[3] = {L->x, L->y, L->z}, d[3];
        for (k = 0; k < nrand + 10 + (int)f->s.npts; k++) {
            trace_hit h, h2;
            if (k < nrand) {
                sphere_dir(rs, d);
                if (k % 4 == 0) {
                    double m = hypot(d[0], d[1]);
                    d[0] /= m;
                    d[1] /= m;
                    d[2] = 0.0;
                }
            } else if (k < nrand + 8) {
                static const double ax[8][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1},
                                                {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
                d[0] = ax[k - nrand][0] * ((k - nrand) % 2 ? sqrt(0.5) : 1.0);
                d[1] = ax[k - nrand][1] * ((k - nrand) % 2 ? sqrt(0.5) : 1.0);
                d[2] = 0.0;
            } else if (k < nrand + 10) {
                d[0] = d[1] = 0.0;
                d[2] = k == nrand + 8 ? 1.0 : -1.0;
            } else {
                /* at a vertex, level or tilted */
                double m;
                v = (uint32_t)(k - nrand - 10);
                d[0] = f->s.pts[v].x - o[0];
                d[1] = f->s.pts[v].y - o[1];
                d[2] = v % 2 ? 0.0 : -0.3 * hypot(d[0], d[1]);
                m = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                if (!(m > 0.0))
                    continue;
                d[0] /= m;
                d[1] /= m;
                d[2] /= m;
            }
            trace_lamp_ray(T, l, d, &h);
            trace_ray(T, o, d, L->radius, &h2);
            kinds[h.kind]++;
            if (!trace_agrees_tmax(&f->s, o, d, L->radius, &h, shown) ||
                (h.kind == TRACE_SKY) != (h2.kind == TRACE_SKY) ||
                (h.kind != TRACE_SKY && fabs(h.t - h2.t) > 1e-12 * (1.0 + h.t)))
                mism++;
        }
    }
    return mism;
}

static void test_trace_lamp_rays(void **state)
{
    fixture f;
    uint64_t rs = 99;
    int kinds[5] = {0, 0, 0, 0, 0}, mism, shown = 0, nl = 0, nrand = quick_mode() ? 40 : 400;
    (void)state;
    /* random city: lamps at random points outside the solids, some at the
     * height of a roof, radii 5 to 80 m */
    fx_open(&f, 16u << 20);
    random_city(&f, 5);
    while (nl < 40) {
        double o[3];
        o[0] = f.s.bounds[0] + 50.0 + (f.s.bounds[2] - f.s.bounds[0] - 100.0) * urand(&rs);
        o[1] = f.s.bounds[1] + 50.0 + (f.s.bounds[3] - f.s.bounds[1] - 100.0) * urand(&rs);
        o[2] = nl % 3 == 0 ? f.s.bld[nl % f.s.nbld].height : 40.0 * urand(&rs);
        if (in_solid(&f.s, o))
            continue;
        assert_true(ref_scene_add_lamp(&f.s, o[0], o[1], o[2], 1000, 5.0 + 75.0 * urand(&rs)) >= 0);
        nl++;
    }
    fx_finish(&f);
    mism = lamp_rays(&f, &rs, nrand, kinds, &shown);
    fx_close(&f);
    /* exact city: lamps at the degenerate spots (roof heights, on the line
     * of walls, under the raised box, in the courtyard) */
    {
        static const double L[][4] = {{5, -5, 10, 30},  {-5, 0, 3, 30},   {25, 5, 2, 40},
                                      {25, 5, 4, 40},   {35, 5, 1, 20},   {15, 35, 6, 25},
                                      {15, 35, 12, 25}, {55, 35, 10, 35}, {90, 12, 9, 15},
                                      {10, -3, 15, 40}, {45, 5, 12, 50},  {75, 20, 20, 60},
                                      {45, 25, 8, 900}}; /* the last one walks the grid */
        exact_city(&f, L, (int)(sizeof L / sizeof L[0]));
        mism += lamp_rays(&f, &rs, nrand, kinds, &shown);
        fx_close(&f);
    }
    printf("trace_lamp_ray vs brute force and trace_ray: %d rays, %d mismatches (sky %d ground "
           "%d wall %d roof %d under %d)\n",
           kinds[0] + kinds[1] + kinds[2] + kinds[3] + kinds[4], mism, kinds[0], kinds[1],
           kinds[2], kinds[3], kinds[4]);
    assert_int_equal(mism, 0);
    assert_true(kinds[TRACE_WALL] > 0 && kinds[TRACE_ROOF] > 0 && kinds[TRACE_UNDER] > 0 &&
                kinds[TRACE_GROUND] > 0 && kinds[TRACE_SKY] > 0);
}

/* ---- energy in a closed box --------------------------------------------- */

/* A courtyard closed by a canopy: donut [0,20]^2 minus [5,15]^2, height 10,
 * and a raised slab over [4,16]^2 from z = 10 to 11. Uniform albedo a. */
static void closed_box(fixture *f, double a)
{
    double xy[16] = {0, 0, 20, 0, 20, 20, 0, 20, 5, 5, 5, 15, 15, 15, 15, 5};
    uint32_t rn[2] = {4, 4};
    uint32_t i;
    fx_open(f, 64u << 20);
    assert_true(ref_scene_add_building(&f->s, xy, rn, 2, 10.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f->s, 4, 4, 16, 16, 11.0, 10.0) >= 0);
    assert_true(ref_scene_add_lamp(&f->s, 10, 9, 5, 1000, 1e6) >= 0);
    f->s.ground_albedo = a;
    for (i = 0; i < f->s.nbld; i++)
        f->s.bld[i].albedo = a;
    fx_finish(f);
}

/* Channel c of n texels of PHOTON_CH floats. */
static double sum_channel(const float *v, size_t n, int c)
{
    double s = 0.0;
    size_t i;
    for (i = 0; i < n; i++)
        s += v[i * PHOTON_CH + (size_t)c];
    return s;
}

static double chart_total(const photon_sys *ps, int c)
{
    double t = 0.0;
    int L;
    for (L = 0; L < PHOTON_LEVELS; L++) {
        const photon_level *lv = &ps->lev[L];
        t += sum_channel(lv->flux, (size_t)lv->nslots * 2 * lv->w * lv->h, c);
    }
    return t;
}

/* Flux of channel c in the level-4 ambient terms. */
static double ambient_total(const photon_sys *ps, int c)
{
    double t = 0.0;
    uint32_t k;
    for (k = 0; k < ps->s->nblocks; k++)
        if (ps->blevel[k] >= PHOTON_LEVELS)
            t += ps->bamb[(size_t)k * PHOTON_CH + (size_t)c];
    return t;
}

/* Every buffer of the progressive pass, channel c. */
static double buffers_total(const photon_sys *ps, int c)
{
    return chart_total(ps, c) + ambient_total(ps, c) +
           sum_channel(ps->gflux, (size_t)ps->gw * ps->gh, c) +
           sum_channel(ps->cov_flux, ps->ncov, c);
}

static void test_energy_closed_box(void **state)
{
    fixture f;
    photon_sys *ps;
    photon_config c;
    const photon_stats *st;
    double a = 0.5, ratio, ends, stored, tex;
    int k;
    (void)state;
    closed_box(&f, a);
    photon_config_default(&c);
    c.aerial_res = 128;
    c.max_bounces = 200;
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_OK);
    for (k = 0; k < (quick_mode() ? 1 : 4); k++)
        photon_step(ps, 50000, 100 + k);
    st = &ps->st;
    /* closed: nothing escapes, and every lumen that reached a first surface
     * ends absorbed (or cut) */
    assert_true(st->escaped == 0.0);
    assert_true(st->first > 0.99 * st->emitted); /* R is huge: W ~ 1 */
    ends = st->absorbed + st->cut;
    assert_true(fabs(ends - st->first) <= 1e-9 * st->first);
    /* later hits carry a + a^2 + ... = a / (1 - a) of the first */
    ratio = st->arrived / st->first;
    printf("closed box, albedo %.2f: arrived / first = %.4f (expected %.4f), escaped %g\n", a,
           ratio, a / (1 - a), st->escaped);
    assert_true(fabs(ratio - a / (1 - a)) < (quick_mode() ? 0.06 : 0.03) * a / (1 - a));
    /* bookkeeping of the later hits: stored somewhere or counted lost */
    stored = st->stored_chart + st->stored_aerial + st->stored_ambient + st->stored_covered +
             st->lost;
    assert_true(fabs(stored - st->arrived) <= 1e-9 * st->arrived);
    /* flux conservation through splatting, to float precision */
    tex = chart_total(ps, 0);
    assert_true(fabs(tex - st->stored_chart) <= 1e-5 * st->stored_chart);
    tex = sum_channel(ps->gflux, (size_t)ps->gw * ps->gh, 0);
    assert_true(fabs(tex - st->stored_aerial) <= 1e-5 * st->stored_aerial);
    tex = sum_channel(ps->cov_flux, ps->ncov, 0);
    assert_true(fabs(tex - st->stored_covered) <= 1e-5 * st->stored_covered);
    /* per channel (lamp colour 1, 0.62, 0.28; grey albedos): what arrives
     * and what is stored is the scalar times the colour, and the buffers
     * hold exactly what was stored */
    {
        const float *col = f.s.lamps[0].color;
        double sc = st->stored_chart + st->stored_aerial + st->stored_ambient +
                    st->stored_covered;
        int ch;
        for (ch = 0; ch < 3; ch++) {
            double buf = buffers_total(ps, 1 + ch);
            printf("closed box channel %d: arrived %.6g (scalar x colour %.6g), stored %.6g, "
                   "in buffers %.6g\n",
                   ch, st->arrived_rgb[ch], st->arrived * col[ch], st->stored_rgb[ch], buf);
            assert_true(fabs(st->arrived_rgb[ch] - st->arrived * col[ch]) <=
                        1e-9 * st->arrived);
            assert_true(fabs(st->stored_rgb[ch] - sc * col[ch]) <= 1e-9 * sc);
            assert_true(fabs(buf - st->stored_rgb[ch]) <= 1e-5 * st->stored_rgb[ch]);
        }
    }
    /* the floor (under the canopy) has its covered-ground chart; the
     * ceiling (an underside) has none; the walls have theirs */
    printf("closed box: stored chart %.4g aerial %.4g covered floor %.4g lost (ceiling) %.4g "
           "of %.4g; %u covered slots\n",
           st->stored_chart, st->stored_aerial, st->stored_covered, st->lost, st->arrived,
           ps->ncov);
    assert_true(st->stored_aerial == 0.0);
    assert_true(st->stored_chart > 0.4 * st->arrived && st->stored_covered > 0.1 * st->arrived &&
                st->lost > 0.1 * st->arrived);
    /* mean indirect irradiance on the courtyard walls against the room's
     * mean: the flux arriving at later hits over floor 100 + walls 400 +
     * ceiling 100 m^2 */
    {
        double sum = 0.0, expect = st->arrived / st->frames / 600.0;
        int n = 0, i, j, w;
        for (w = 0; w < 4; w++)
            for (j = 0; j < 10; j++)
                for (i = 0; i < 10; i++) {
                    double u = 5.5 + i, z = 0.5 + j, P[3], nn[3] = {0, 0, 0};
                    if (w == 0) { P[0] = 5; P[1] = u; nn[0] = 1; }
                    else if (w == 1) { P[0] = 15; P[1] = u; nn[0] = -1; }
                    else if (w == 2) { P[0] = u; P[1] = 5; nn[1] = 1; }
                    else { P[0] = u; P[1] = 15; nn[1] = -1; }
                    P[2] = z;
                    sum += photon_indirect(ps, P, nn);
                    n++;
                }
        printf("closed box walls: mean E_ind %.2f lx, room mean %.2f lx\n", sum / n, expect);
        assert_true(sum / n > 0.7 * expect && sum / n < 1.3 * expect);
        /* the floor under the canopy: read from the covered-ground layer */
        sum = 0.0;
        n = 0;
        for (j = 0; j < 10; j++)
            for (i = 0; i < 10; i++) {
                double P[3] = {5.5 + i, 5.5 + j, 0.0}, up[3] = {0, 0, 1};
                assert_true(photon_covered_at(ps, P[0], P[1]));
                sum += photon_indirect(ps, P, up);
                n++;
            }
        printf("closed box floor: mean E_ind %.2f lx, room mean %.2f lx\n", sum / n, expect);
        assert_true(sum / n > 0.7 * expect && sum / n < 1.3 * expect);
    }
    fx_close(&f);
}

/* ---- one bounce from the ground onto one wall: numeric integration -------- */

static double one_bounce_wall(double xl, double zl, double I, double R, double ag, double yp,
                              double zp)
{
    double h = 0.04, sum = 0.0, x, y, rg = sqrt(R * R - zl * zl);
    for (x = 0.5 * h; x < xl + rg; x += h)
        for (y = -rg + 0.5 * h; y < rg; y += h) {
            double dx = x - xl, d2 = dx * dx + y * y + zl * zl, d = sqrt(d2);
            double xr, e, r2;
            if (d >= R)
                continue;
            xr = d / R;
            e = I * zl / (d2 * d) * (1 - xr * xr * xr * xr) * (1 - xr * xr * xr * xr);
            r2 = x * x + (y - yp) * (y - yp) + zp * zp;
            sum += ag / PI * e * (zp / sqrt(r2)) * (x / sqrt(r2)) / r2;
        }
    return sum * h * h;
}

static void test_one_bounce_wall(void **state)
{
    fixture f;
    photon_sys *ps;
    photon_config c;
    double xl = 4.0, zl = 5.0, I = 1000.0, R = 30.0, ag = 0.5;
    double pts[6][2] = {{0, 1}, {-3, 2}, {4, 1.5}, {0, 4}, {6, 3}, {-8, 2}};
    double err_first = 0.0, err_last = 0.0;
    int frames = full_mode() ? 64 : quick_mode() ? 8 : 24, k, i, round;
    double bound = quick_mode() ? 0.15 : 0.10;
    double eye[3] = {3, 0, 1.7};
    (void)state;
    fx_open(&f, 256u << 20);
    assert_true(ref_scene_add_box(&f.s, -100, -100, 0, 100, 40.0, 0.0) >= 0);
    assert_true(ref_scene_add_lamp(&f.s, xl, 0, zl, I, R) >= 0);
    f.s.bld[0].albedo = 0.0;
    f.s.ground_albedo = ag;
    fx_finish(&f);
    photon_config_default(&c);
    c.chart_w = 1024;
    c.chart_h = 64;
    c.aerial_res = 256;
    c.kernel_min = 1.5;
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_OK);
    assert_int_equal(photon_set_viewer(ps, eye, NULL, 0.0), PLX_OK);
    assert_int_equal(photon_block_level(ps, 0), 0);
    printf("one bounce ground -> wall (lamp at x=%.0f z=%.0f):\n  photons   mean rel err\n", xl,
           zl);
    for (round = 0, k = 0; k < frames; k++) {
        photon_step(ps, 65536, 1000 + k);
        if (k + 1 == 2 || k + 1 == 8 || k + 1 == frames) {
            double err = 0.0;
            for (i = 0; i < 6; i++) {
                double P[3] = {0.0, pts[i][0], pts[i][1]}, n[3] = {1, 0, 0};
                double ref = one_bounce_wall(xl, zl, I, R, ag, pts[i][0], pts[i][1]);
                double est = photon_indirect(ps, P, n);
                if (k + 1 == frames)
                    printf("    y=%5.1f z=%4.1f: photons %8.3f lx, integral %8.3f lx\n", P[1],
                           P[2], est, ref);
                err += fabs(est - ref) / ref;
            }
            err /= 6;
            printf("  %8d   %.4f\n", (k + 1) * 65536, err);
            if (round++ == 0)
                err_first = err;
            err_last = err;
        }
    }
    /* the ground keeps nothing: wall-first photons die (albedo 0), and the
     * ground is never a later hit */
    assert_true(ps->st.stored_aerial == 0.0);
    assert_true(err_last < bound);
    assert_true(err_last < err_first);
    fx_close(&f);
}

/* ---- accuracy on the eixample fixture ------------------------------------- */

static plx_engine *open_fixture(const char *path, void **mem, size_t bytes)
{
    plx_engine *e = fixture_file(path, bytes, mem);
    e->cfg.port = NULL; /* what follows runs without a port */
    e->port.log = NULL;
    return e;
}

/* The reference: tests/ref/ref_indirect's path tracer (its own cosine
 * sampler with libm, SPEC §2 direct light by shadow rays). */
static double reference_indirect(tracer *T, const scene *s, const double P[3],
                                 const double n[3], int paths, uint64_t seed)
{
    return ref_indirect_paths(T, s, P, n, paths, seed, NULL);
}

static void test_accuracy_eixample(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    void *mem;
    plx_engine *e = open_fixture("fixtures/eixample-4x4.geojson", &mem, 512u << 20);
    const scene *s = e->sc;
    photon_sys *ps;
    double P[16][3], N[16][3], ref[16];
    int npts = 0, paths = full_mode() ? 160000 : quick_mode() ? 500 : 40000, k, i;
    int frames = full_mode() ? 512 : quick_mode() ? 16 : 256;
    double bound = quick_mode() ? 0.40 : 0.10;
    double first_err = -1.0, last_err = 0.0, eye[3];
    uint64_t rs = 4242;
    (void)state;
    assert_int_equal(photon_create(&e->mem, s, NULL, &ps), PLX_OK);
    /* 8 ground points and 8 facade points near lamps */
    while (npts < 16) {
        const scene_lamp *L = &s->lamps[rng_next(&rs) % s->nlamps];
        if (npts < 8) {
            double a = 2 * PI * urand(&rs), r = 2.0 + 6.0 * urand(&rs);
            double x = L->x + r * cos(a), y = L->y + r * sin(a);
            if (x < s->bounds[0] + 60 || x > s->bounds[2] - 60 || y < s->bounds[1] + 60 ||
                y > s->bounds[3] - 60 || trace_top(ps->T, x, y, NULL) != 0.0)
                continue;
            P[npts][0] = x;
            P[npts][1] = y;
            P[npts][2] = 0.0;
            N[npts][0] = N[npts][1] = 0.0;
            N[npts][2] = 1.0;
        } else {
            double a = 2 * PI * urand(&rs), o[3] = {L->x, L->y, 1.0 + (L->z - 1.5) * urand(&rs)};
            double d[3] = {cos(a), sin(a), 0.0};
            trace_hit h;
            if (trace_ray(ps->T, o, d, 12.0, &h) != TRACE_WALL)
                continue;
            if (ps->eclass[h.edge] == PHOTON_EDGE_INTERNAL)
                continue;
            memcpy(P[npts], h.p, sizeof P[npts]);
            memcpy(N[npts], h.n, sizeof N[npts]);
        }
        npts++;
    }
    for (i = 0; i < npts; i++)
        ref[i] = reference_indirect(ps->T, s, P[i], N[i], paths, 9000 + i);
    eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
    eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
    eye[2] = 1.7;
    assert_int_equal(photon_set_viewer(ps, eye, NULL, 0.0), PLX_OK);
    printf("eixample-4x4, %u lamps, %d reference paths per point\n"
           "  photons    mean rel err (ground, facade, all)\n",
           s->nlamps, paths);
    for (k = 0; k < frames; k++) {
        photon_step(ps, 65536, 77 + k);
        if (((k + 1) & k) == 0 || k + 1 == frames) {
            double eg = 0.0, ef = 0.0;
            for (i = 0; i < npts; i++) {
                double est = photon_indirect(ps, P[i], N[i]);
                double err = fabs(est - ref[i]) / ref[i];
                if (k + 1 == frames)
                    printf("    %s (%.1f %.1f %.1f): photons %7.3f lx, paths %7.3f lx\n",
                           i < 8 ? "ground" : "facade", P[i][0], P[i][1], P[i][2], est, ref[i]);
                if (i < 8)
                    eg += err;
                else
                    ef += err;
            }
            printf("  %9d  %.4f %.4f %.4f\n", (k + 1) * 65536, eg / 8, ef / 8,
                   (eg + ef) / npts);
            if (first_err < 0.0)
                first_err = (eg + ef) / npts;
            last_err = (eg + ef) / npts;
        }
    }
    printf("  bound on the last row: %.2f%s\n", bound, quick_mode() ? " (quick mode)" : "");
    assert_true(last_err <= bound);
    assert_true(last_err < first_err);
    plx_engine_destroy(e);
    free(mem);
}

/* The courtyard ring of block k holding (x, y): one of its outline's
 * clockwise rings after the first (blocks.h), by the even-odd rule and
 * the shoelace sign here, not geom.c's (nor surface_key.c's); its index
 * in scene.block_rings, UINT32_MAX when none. */
static uint32_t courtyard_ring_of(const scene *s, uint32_t k, double x, double y)
{
    const scene_block *K = &s->blocks[k];
    uint32_t r, i, j;
    for (r = 1; r < K->ring_count; r++) {
        const scene_ring *R = &s->block_rings[K->ring_first + r];
        const vec2 *p = &s->block_pts[R->first];
        double a2 = 0.0;
        int in = 0;
        for (i = 0, j = R->count - 1; i < R->count; j = i++) {
            a2 += p[j].x * p[i].y - p[i].x * p[j].y;
            if ((p[i].y > y) != (p[j].y > y) &&
                x < p[j].x + (p[i].x - p[j].x) * (y - p[j].y) / (p[i].y - p[j].y))
                in = !in;
        }
        if (a2 < 0.0 && in)
            return K->ring_first + r;
    }
    return UINT32_MAX;
}

/* 1 when (x, y) lies in a courtyard of block k. */
static int in_courtyard(const scene *s, uint32_t k, double x, double y)
{
    return courtyard_ring_of(s, k, x, y) != UINT32_MAX;
}

/* A random point on an outer wall of eixample-4x4 (z in the building's
 * height range) and the surface a ray from just in front of it meets;
 * *kind gets what lies in front of the wall, found without the engine's
 * wall classes: 0 open ground outside the block's courtyards (a street
 * facade), 1 a neighbour's roof below the point (the exposed strip of a
 * party wall), -1 neither (the point is hidden, faces a courtyard, or the
 * ray met another surface). */
static trace_hit strip_point(photon_sys *ps, const scene *s, uint64_t *rs, int *kind)
{
    const scene_building *B = &s->bld[rng_next(rs) % s->nbld];
    const scene_ring *R = &s->rings[B->ring_first];
    uint32_t i0 = R->first + (uint32_t)(rng_next(rs) % R->count), i1 = ps->T->enext[i0];
    double dx = s->pts[i1].x - s->pts[i0].x, dy = s->pts[i1].y - s->pts[i0].y, len = hypot(dx, dy);
    double t = 0.1 + 0.8 * urand(rs), z = B->min_height + (0.05 + 0.9 * urand(rs)) * (B->height - B->min_height);
    double n[2], o[3], d[3], top;
    trace_hit h;
    memset(&h, 0, sizeof h);
    *kind = -1;
    if (!(len > 1.0))
        return h;
    n[0] = dy / len; /* out of the solid: it lies to the left of the edge */
    n[1] = -dx / len;
    o[0] = s->pts[i0].x + t * dx + 0.05 * n[0];
    o[1] = s->pts[i0].y + t * dy + 0.05 * n[1];
    o[2] = z;
    top = trace_top(ps->T, o[0], o[1], NULL);
    if (top >= z - 0.5)
        return h; /* hidden by the neighbour, or too near its roof */
    d[0] = -n[0];
    d[1] = -n[1];
    d[2] = 0.0;
    if (trace_ray(ps->T, o, d, 0.2, &h) != TRACE_WALL || h.edge != i0)
        return h;
    if (top > 0.0)
        *kind = 1;
    else if (B->block < s->nblocks && !in_courtyard(s, B->block, o[0], o[1]))
        *kind = 0;
    return h;
}

/* Photon buffers of e's scene (cfg NULL: the defaults) with the viewer at
 * its centre, 16 frames of 65536 photons (the command's default). */
static photon_sys *traced_from_centre(plx_engine *e, const photon_config *cfg)
{
    const scene *s = e->sc;
    photon_sys *ps;
    double eye[3];
    int k;
    assert_int_equal(photon_create(&e->mem, s, cfg, &ps), PLX_OK);
    eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
    eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
    eye[2] = 1.7;
    assert_int_equal(photon_set_viewer(ps, eye, NULL, 0.0), PLX_OK);
    for (k = 0; k < 16; k++)
        photon_step(ps, 65536, (uint64_t)k + 1);
    return ps;
}

/* The exposed upper strip of a party wall (above a lower neighbour's roof)
 * sees roofs and sky, not the street. Its E_indirect from the block's
 * charts against the independent path tracer, beside street facades at
 * the same photons (16 x 65536, the command's default): the sums over
 * random points are within 0.5 to 1.5 times the truth for the strips (0.68
 * to 1.09 over six seeds of the points) and 0.75 to 1.33 for the street
 * facades (0.96 to 1.05). When the strips shared the street facade's chart
 * they read 1.7 to 3.0 times the truth here over the same seeds (8 to 9
 * times on gen eixample 8 8): the light of the street facade at the same
 * place around the block. The strips' low side is their chart's mixing
 * with the dark courtyard walls at the same place (README "Open work"),
 * so the lower bound holds for this fixture, not for every city. */
static void test_party_wall_strips(void **state)
{
    void *mem;
    plx_engine *e = open_fixture("fixtures/eixample-4x4.geojson", &mem, 512u << 20);
    const scene *s = e->sc;
    photon_sys *ps;
    int want = quick_mode() ? 48 : 96, paths = quick_mode() ? 1000 : 4000, n[2] = { 0, 0 }, k, tries = 0;
    double est[2] = { 0.0, 0.0 }, ref[2] = { 0.0, 0.0 };
    uint64_t rs = 0x57219u;
    const char *name[2] = { "street facades", "party-wall strips" };
    (void)state;
    ps = traced_from_centre(e, NULL);
    while ((n[0] < want || n[1] < want) && tries++ < 200000) {
        int kind;
        trace_hit h = strip_point(ps, s, &rs, &kind);
        double v[PHOTON_CH];
        if (kind < 0 || n[kind] >= want || ps->blevel[s->bld[h.bld].block] >= PHOTON_LEVELS)
            continue;
        photon_indirect_hit(ps, &h, v);
        est[kind] += v[0];
        ref[kind] += ref_indirect_paths(ps->T, s, h.p, h.n, paths, 0x5000u + (uint64_t)tries, NULL);
        n[kind]++;
    }
    for (k = 0; k < 2; k++) {
        printf("  %s: %d points, mean E_indirect %.3f lx from the charts, %.3f lx by %d paths: ratio %.2f\n",
               name[k], n[k], est[k] / n[k], ref[k] / n[k], paths, est[k] / ref[k]);
        assert_int_equal(n[k], want);
        if (k == 0)
            assert_true(est[k] >= 0.75 * ref[k] && est[k] <= 1.33 * ref[k]);
        else
            assert_true(est[k] >= 0.5 * ref[k] && est[k] <= 1.5 * ref[k]);
    }
    plx_engine_destroy(e);
    free(mem);
}

/* 1 when (x, y) lies in a courtyard of any block (in_courtyard). */
static int in_any_courtyard(const scene *s, double x, double y)
{
    uint32_t k;
    for (k = 0; k < s->nblocks; k++)
        if (in_courtyard(s, k, x, y))
            return 1;
    return 0;
}

/* The courtyard ring holding (x, y), block by block (courtyard_ring_of):
 * its index in scene.block_rings, UINT32_MAX when none. */
static uint32_t courtyard_ring_at(const scene *s, double x, double y)
{
    uint32_t k, r;
    for (k = 0; k < s->nblocks; k++)
        if ((r = courtyard_ring_of(s, k, x, y)) != UINT32_MAX)
            return r;
    return UINT32_MAX;
}

/* surface_key against the courtyards found ring by ring
 * (courtyard_ring_at) at random points of two cities, eixample-4x4 and
 * the Helsinki district: on the ground a courtyard's key -1 - c exactly
 * when a courtyard holds the point, c naming that ring (keys.ring[c]), 0
 * elsewhere; a roof's height passes through. */
static void surface_key_city(const char *path, int n, int *in_out)
{
    void *mem;
    plx_engine *e = open_fixture(path, &mem, 512u << 20);
    const scene *s = e->sc;
    photon_sys *ps;
    uint64_t rs = 0x5eedu;
    int k, inside = 0;
    assert_int_equal(photon_create(&e->mem, s, NULL, &ps), PLX_OK);
    for (k = 0; k < n; k++) {
        double x = s->bounds[0] + (s->bounds[2] - s->bounds[0]) * urand(&rs);
        double y = s->bounds[1] + (s->bounds[3] - s->bounds[1]) * urand(&rs), key;
        uint32_t ring = courtyard_ring_at(s, x, y);
        key = surface_key(&ps->keys, ps->s, x, y, 0.0);
        assert_true(surface_key(&ps->keys, ps->s, x, y, 12.5) == 12.5);
        if (ring == UINT32_MAX) {
            assert_true(key == 0.0);
            continue;
        }
        inside++;
        assert_true(key <= -1.0 && key == floor(key) && -1.0 - key < (double)ps->keys.ncy);
        assert_int_equal(ps->keys.ring[(uint32_t)(-1.0 - key)], ring);
    }
    printf("  %s: %u courtyards, %d of %d random points in one, every key as the ring-by-ring test\n", path,
           ps->keys.ncy, inside, n);
    *in_out = inside;
    plx_engine_destroy(e);
    free(mem);
}

static void test_surface_key_vs_brute(void **state)
{
    int in0, in1;
    (void)state;
    surface_key_city("fixtures/eixample-4x4.geojson", quick_mode() ? 4000 : 20000, &in0);
    surface_key_city("fixtures/helsinki-centre.geojson", quick_mode() ? 4000 : 20000, &in1);
    assert_true(in0 > 100 && in1 > 10);
}

/* Roofs, courtyards and streets from coarse aerial charts against the
 * independent path tracer, beside the default chart. A texel holds the
 * surface at its centre; a photon landing on another surface in it (the
 * street beside a roof, a roof of another height, a courtyard beside the
 * street) used to be splatted onto the nearest texels of its height, so a
 * roof texel took the light of the roofs around it, and a courtyard's
 * ground, at the street's height, the street's: at 16 and 32 texels a
 * side here (29 and 15 m) courtyards read 3.78 and 0.83 lx where the
 * truth is under 0.01, roofs at 32 1.84 times the truth. Such photons are
 * not stored now (splat_any's own_texel) and courtyards are surfaces of
 * their own (surface_key.h). Means over random points of each kind
 * (0 roofs, 1 courtyards, 2 open ground), one photon run a chart. */
static void kinds_vs_paths(plx_engine *e, uint32_t res, int want, int paths, double est[3], double ref[3])
{
    const scene *s = e->sc;
    photon_config c;
    photon_sys *ps;
    arena_mark m = arena_get_mark(&e->mem);
    uint64_t rs = 0x600fu;
    int n[3] = { 0, 0, 0 }, k, tries = 0;
    photon_config_default(&c);
    c.aerial_res = res;
    ps = traced_from_centre(e, &c);
    for (k = 0; k < 3; k++)
        est[k] = ref[k] = 0.0;
    while ((n[0] < want || n[1] < want || n[2] < want) && tries++ < 400000) {
        double P[3], up[3] = { 0.0, 0.0, 1.0 };
        uint32_t b;
        P[0] = s->bounds[0] + (s->bounds[2] - s->bounds[0]) * urand(&rs);
        P[1] = s->bounds[1] + (s->bounds[3] - s->bounds[1]) * urand(&rs);
        P[2] = trace_top(ps->T, P[0], P[1], &b);
        k = P[2] > 0.0 ? 0 : P[2] == 0.0 && in_any_courtyard(s, P[0], P[1]) ? 1 : P[2] == 0.0 ? 2 : -1;
        if (k < 0 || n[k] >= want)
            continue;
        est[k] += photon_indirect(ps, P, up);
        ref[k] += ref_indirect_paths(ps->T, s, P, up, paths, 0x7000u + (uint64_t)tries, NULL);
        n[k]++;
    }
    for (k = 0; k < 3; k++) {
        assert_int_equal(n[k], want);
        est[k] /= want;
        ref[k] /= want;
    }
    arena_release(&e->mem, &m);
}

static void test_coarse_charts(void **state)
{
    if (quick_mode()) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    void *mem;
    plx_engine *e = open_fixture("fixtures/eixample-4x4.geojson", &mem, 512u << 20);
    int want = quick_mode() ? 48 : 96, paths = quick_mode() ? 1000 : 4000, kind, k;
    uint32_t res[4] = { 16, 32, 512, 8 };
    const char *name[3] = { "roofs", "courtyards", "open ground" };
    double est[4][3], ref[4][3];
    (void)state;
    for (k = 0; k < 4; k++) {
        kinds_vs_paths(e, res[k], want, paths, est[k], ref[k]);
        for (kind = 0; kind < 3; kind++)
            printf("  aerial chart %u texels a side, %s: mean E_indirect %.4f lx from the chart, %.4f lx by "
                   "paths: ratio %.2f\n", res[k], name[kind], est[k][kind], ref[k][kind],
                   est[k][kind] / ref[k][kind]);
    }
    for (k = 0; k < 3; k++) {
        /* roofs: a hundredth of a lux here, read low or about right */
        assert_true(est[k][0] >= 0.25 * ref[k][0] && est[k][0] <= 1.5 * ref[k][0]);
        /* courtyards, nearly dark here (under a thousandth of a lux):
         * within 0.5% of the open ground's light of the truth */
        assert_true(fabs(est[k][1] - ref[k][1]) <= 0.005 * ref[k][2]);
        /* the open ground (streets and the border) */
        assert_true(est[k][2] >= 0.8 * ref[k][2] && est[k][2] <= 1.25 * ref[k][2]);
    }
    /* 8 texels a side (59 m each, the whole city under a splat of 2 to 4
     * texels): the open ground reads low, 0.34 to 0.45 of the truth (1.11 before
     * the own-texel rule, which then dropped most street photons: they
     * land in texels centred on roofs and courtyards, while the splats
     * spread the rest over the empty border); photon.h says so. Held
     * from falling further; the courtyards stay dark. */
    assert_true(est[3][2] >= 0.25 * ref[3][2] && est[3][2] <= 1.25 * ref[3][2]);
    assert_true(fabs(est[3][1] - ref[3][1]) <= 0.005 * ref[3][2]);
    plx_engine_destroy(e);
    free(mem);
}

/* ---- splat kernel and direction samplers ---------------------------------------- */

/* The splat by its definition, texel by texel over the whole square: cone
 * weights 1 - dist / r of the valid texels (sparse slot with area,
 * area > 0, height within 1 mm), normalised (with photon.c's arithmetic:
 * times 1 / r, shares times 1 / sum, so the floats compare exactly);
 * else the nearest valid texel of the 3 x 3; window texels outside the
 * window take their share and drop it. Points more than r + 2 texels
 * outside the grid deposit nothing (even with wrap), nor, on a grid of
 * heights, a point on the grid whose own texel is not valid (a surface
 * the chart does not hold). Returns 1 when deposited. */
static int ref_splat(float *out, const float *area, const float *height, const uint32_t *idx,
                     double z, int w, int h, int wrap, int win, int ow, int oh, int ox, int oy,
                     double fx, double fy, double r, const double phi[PHOTON_CH])
{
    long slot[400];
    double wt[400], sum = 0.0, bd = INFINITY;
    int n = 0, i, j, c, best = -1;
    if (!(fx > -r - 2.0 && fy > -r - 2.0 && fx < w + r + 2.0 && fy < h + r + 2.0))
        return 0;
    if (height && fx >= 0.0 && fy >= 0.0 && fx < w && fy < h) { /* on the grid: its own texel must hold it */
        long k0 = (long)floor(fy) * w + (long)floor(fx);
        long s0 = idx ? (idx[k0] == PHOTON_NONE ? -1 : (long)idx[k0]) : k0;
        if (s0 < 0 || !(area[s0] > 0.0f) || fabs(height[k0] - z) > 1e-3)
            return 0;
    }
    for (j = (int)floor(fy - r) - 2; j <= (int)floor(fy + r) + 2; j++)
        for (i = (int)floor(fx - r) - 2; i <= (int)floor(fx + r) + 2; i++) {
            double dx = (i + 0.5) - fx, dy = (j + 0.5) - fy, dist = sqrt(dx * dx + dy * dy);
            int ii = wrap ? ((i % w) + w) % w : i;
            long k, s, o;
            if (j < 0 || j >= h || ii < 0 || ii >= w)
                continue;
            k = (long)j * w + ii;
            s = idx ? (idx[k] == PHOTON_NONE ? -1 : (long)idx[k]) : k;
            if (s < 0 || !(area[s] > 0.0f) || (height && fabs(height[k] - z) > 1e-3))
                continue;
            o = s;
            if (win)
                o = (ii - ox < 0 || j - oy < 0 || ii - ox >= ow || j - oy >= oh)
                        ? -1
                        : (long)(j - oy) * ow + (ii - ox);
            if (abs(i - (int)floor(fx)) <= 1 && abs(j - (int)floor(fy)) <= 1 &&
                dx * dx + dy * dy < bd) {
                bd = dx * dx + dy * dy;
                best = (int)o;
            }
            if (i < (int)floor(fx - r) || i > (int)floor(fx + r) || j < (int)floor(fy - r) ||
                j > (int)floor(fy + r) || dist >= r)
                continue;
            slot[n] = o;
            wt[n] = 1.0 - dist * (1.0 / r);
            sum += wt[n];
            n++;
        }
    if (n == 0 || !(sum > 0.0)) {
        if (bd == INFINITY)
            return 0;
        if (best >= 0)
            for (c = 0; c < PHOTON_CH; c++)
                out[(size_t)best * PHOTON_CH + c] += (float)(phi[c] * 1.0);
        return 1;
    }
    for (i = 0; i < n; i++)
        if (slot[i] >= 0)
            for (c = 0; c < PHOTON_CH; c++)
                out[(size_t)slot[i] * PHOTON_CH + c] += (float)(phi[c] * (wt[i] * (1.0 / sum)));
    return 1;
}

/* photon_splat, photon_splat_sparse and photon_splat_win give exactly the
 * floats of the texel-by-texel definition: grids with holes, two heights,
 * wrap, sparse slots, windows, every radius up to the largest. */
static void test_splat_vs_brute(void **state)
{
    enum { W = 13, H = 9, OW = 6, OH = 5 };
    float area[W * H], height[W * H], sarea[W * H];
    float a[W * H * PHOTON_CH], b[W * H * PHOTON_CH];
    uint32_t idx[W * H];
    uint64_t rs = 99;
    int trial, k, ns = 0, moved = 0, refused = 0;
    (void)state;
    for (k = 0; k < W * H; k++) {
        area[k] = urand(&rs) < 0.2 ? 0.0f : (float)(0.5 + urand(&rs));
        height[k] = urand(&rs) < 0.3 ? 5.0f : 0.0f;
        idx[k] = urand(&rs) < 0.4 ? PHOTON_NONE : (uint32_t)ns++;
    }
    for (k = 0; k < ns; k++)
        sarea[k] = urand(&rs) < 0.1 ? 0.0f : (float)(0.5 + urand(&rs));
    for (trial = 0; trial < 20000; trial++) {
        double fx = -4.0 + (W + 8.0) * urand(&rs), fy = -4.0 + (H + 8.0) * urand(&rs);
        double r = trial % 5 == 0 ? (double)(1 + trial % 6) : 0.3 + 5.7 * urand(&rs);
        double z = urand(&rs) < 0.5 ? 0.0 : 5.0 + (urand(&rs) - 0.5) * 3e-3, phi[PHOTON_CH];
        int mode = trial % 4, ox = (int)(urand(&rs) * W) - 2, oy = (int)(urand(&rs) * H) - 2;
        int ra, rb;
        for (k = 0; k < PHOTON_CH; k++)
            phi[k] = 0.1 + urand(&rs);
        memset(a, 0, sizeof a);
        memset(b, 0, sizeof b);
        if (mode == 0 || mode == 1) {
            ra = photon_splat(a, area, mode ? height : NULL, z, W, H, mode == 0, fx, fy, r, phi);
            rb = ref_splat(b, area, mode ? height : NULL, NULL, z, W, H, mode == 0, 0, 0, 0, 0,
                           0, fx, fy, r, phi);
        } else if (mode == 2) {
            ra = photon_splat_sparse(a, sarea, idx, W, H, fx, fy, r, phi);
            rb = ref_splat(b, sarea, NULL, idx, 0.0, W, H, 0, 0, 0, 0, 0, 0, fx, fy, r, phi);
        } else {
            ra = photon_splat_win(a, OW, OH, ox, oy, area, height, z, W, H, fx, fy, r, phi);
            rb = ref_splat(b, area, height, NULL, z, W, H, 0, 1, OW, OH, ox, oy, fx, fy, r, phi);
        }
        assert_int_equal(ra, rb);
        assert_memory_equal(a, b, sizeof a);
        moved += ra;
        if ((mode == 1 || mode == 3) && fx >= 0.0 && fy >= 0.0 && fx < W && fy < H) {
            int k0 = (int)floor(fy) * W + (int)floor(fx);
            if (!(area[k0] > 0.0f) || fabs(height[k0] - z) > 1e-3) {
                assert_int_equal(ra, 0); /* its own texel holds another surface: not stored */
                refused++;
            }
        }
    }
    printf("splat: 20000 splats (%d deposited, %d refused on another surface's texel) equal to the "
           "texel-by-texel definition\n", moved, refused);
    assert_true(moved > 10000);
    assert_true(refused > 1000);
}

/* cos and sin of a turn fraction against libm; uniform sphere and
 * cosine-weighted hemisphere directions: unit length,
 * the right side, and moments within 5 standard errors: E[d] = 0 and
 * E[d_i d_j] = delta_ij / 3 on the sphere; E[cos] = 2/3, E[cos^2] = 1/2 and
 * tangential means 0 about n (the ground, an underside, walls, a tilted n). */
static void test_direction_samplers(void **state)
{
    const double ns[5][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-0.6, 0.8, 0}, {0.48, 0.6, 0.64}};
    enum { N = 200000 };
    uint64_t rs = 5;
    double m[3] = {0, 0, 0}, mm[3][3] = {{0}}, se1 = 5.0 / sqrt((double)N);
    int k, i, j, q;
    (void)state;
    /* the polynomial cos and sin against libm's (whose argument 2 pi u is
     * itself rounded: 1e-15 is a few ulps of the angle) */
    for (k = 0; k <= 4 * N; k++) {
        double u = k < 4 * N ? urand(&rs) : 1.0 - 0x1p-53, c, s;
        photon_sincos_turn(u, &c, &s);
        assert_true(fabs(c - cos(2.0 * PI * u)) < 1e-15);
        assert_true(fabs(s - sin(2.0 * PI * u)) < 1e-15);
    }
    for (i = 0; i < 64; i++) {
        double c, s;
        photon_sincos_turn(i / 64.0, &c, &s);
        assert_true(fabs(c - cos(2.0 * PI * i / 64.0)) < 1e-15);
        assert_true(fabs(s - sin(2.0 * PI * i / 64.0)) < 1e-15);
    }
    for (k = 0; k < N; k++) {
        double d[3];
        photon_sphere_dir(&rs, d);
        assert_true(fabs(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.0) < 1e-12);
        for (i = 0; i < 3; i++) {
            m[i] += d[i] / N;
            for (j = 0; j < 3; j++)
                mm[i][j] += d[i] * d[j] / N;
        }
    }
    for (i = 0; i < 3; i++) {
        assert_true(fabs(m[i]) < se1 * sqrt(1.0 / 3.0));
        for (j = 0; j < 3; j++)
            assert_true(fabs(mm[i][j] - (i == j ? 1.0 / 3.0 : 0.0)) < se1 * 0.35);
    }
    for (q = 0; q < 5; q++) {
        const double *n = ns[q];
        double c1 = 0.0, c2 = 0.0, tm[3] = {0, 0, 0};
        for (k = 0; k < N; k++) {
            double d[3], c;
            photon_cosine_dir(&rs, n, d);
            c = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
            assert_true(fabs(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.0) < 1e-12);
            assert_true(c >= 0.0);
            c1 += c / N;
            c2 += c * c / N;
            for (i = 0; i < 3; i++)
                tm[i] += (d[i] - c * n[i]) / N;
        }
        printf("cosine directions about (%.2f %.2f %.2f): E[cos] %.4f (2/3), E[cos^2] %.4f "
               "(1/2)\n",
               n[0], n[1], n[2], c1, c2);
        assert_true(fabs(c1 - 2.0 / 3.0) < se1 * sqrt(1.0 / 18.0));
        assert_true(fabs(c2 - 0.5) < se1 * sqrt(1.0 / 12.0));
        for (i = 0; i < 3; i++)
            assert_true(fabs(tm[i]) < se1 * 0.5);
    }
}

/* ---- colour ---------------------------------------------------------------------- */

/* Russian roulette with one scalar survival probability keeps every channel
 * unbiased: with stratified u the survivors' mean weights are f_c alb_c per
 * RGB channel and f_0 p for the scalar; grey albedos leave weights alone. */
static void test_bounce_weights(void **state)
{
    double alb[3] = {0.8, 0.4, 0.1}, grey[3] = {0.3, 0.3, 0.3};
    double f0[PHOTON_CH] = {2.0, 1.0, 0.5, 0.25}, mean[PHOTON_CH] = {0, 0, 0, 0};
    double p = photon_albedo_scalar(alb);
    int N = 100000, k, c;
    (void)state;
    assert_true(fabs(p - (0.2126 * 0.8 + 0.7152 * 0.4 + 0.0722 * 0.1)) < 1e-15);
    assert_true(photon_albedo_scalar(grey) == 0.3);
    for (k = 0; k < N; k++) {
        double f[PHOTON_CH];
        memcpy(f, f0, sizeof f);
        if (photon_bounce(f, alb, (k + 0.5) / N))
            for (c = 0; c < PHOTON_CH; c++)
                mean[c] += f[c] / N;
    }
    printf("bounce, albedo (0.8 0.4 0.1), p %.4f: mean weights %.5f %.5f %.5f %.5f, "
           "expected %.5f %.5f %.5f %.5f\n",
           p, mean[0], mean[1], mean[2], mean[3], f0[0] * p, f0[1] * alb[0], f0[2] * alb[1],
           f0[3] * alb[2]);
    assert_true(fabs(mean[0] - f0[0] * p) <= 2.0 * f0[0] / N);
    for (c = 0; c < 3; c++)
        assert_true(fabs(mean[1 + c] - f0[1 + c] * alb[c]) <= 2.0 * f0[1 + c] / (p * N));
    for (k = 0; k < 1000; k++) {
        double f[PHOTON_CH];
        memcpy(f, f0, sizeof f);
        if (photon_bounce(f, grey, k / 1000.0))
            assert_memory_equal(f, f0, sizeof f);
        else
            assert_true(k / 1000.0 >= 0.3);
    }
}

/* White lamps: the RGB channels are the scalar, bit for bit, through the
 * charts, the ambient terms, A, I and the floor maps. */
static void test_white_lamps_equal(void **state)
{
    void *mem;
    plx_engine *e = open_fixture("fixtures/eixample-4x4.geojson", &mem, 256u << 20);
    scene *s = e->sc;
    photon_sys *ps;
    photon_config c;
    double eye[3];
    uint64_t rs = 99;
    uint32_t i;
    int k, n = 0, nonzero = 0;
    (void)state;
    for (i = 0; i < s->nlamps; i++)
        s->lamps[i].color[0] = s->lamps[i].color[1] = s->lamps[i].color[2] = 1.0f;
    photon_config_default(&c);
    c.aerial_res = 128;
    c.lamp_photons = 4096;
    c.lamp_slots = 4;
    c.level_blocks[0] = 2;
    c.level_blocks[1] = 2;
    c.level_blocks[2] = 2;
    c.level_blocks[3] = 2; /* some blocks at level 4: ambient terms */
    assert_int_equal(photon_create(&e->mem, s, &c, &ps), PLX_OK);
    eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
    eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
    eye[2] = 1.7;
    for (k = 0; k < 3; k++)
        photon_step(ps, 20000, 300 + k);
    assert_true(photon_lamps_update(ps, eye) > 0);
    photon_step(ps, 20000, 400);
    while (n < 400) {
        double P[3], N[3] = {0, 0, 1}, rgb[3], E;
        const scene_lamp *L = &s->lamps[rng_next(&rs) % s->nlamps];
        if (n % 2 == 0) {
            double a = 2 * PI * urand(&rs), r = 1.0 + 10.0 * urand(&rs);
            P[0] = L->x + r * cos(a);
            P[1] = L->y + r * sin(a);
            P[2] = trace_top(ps->T, P[0], P[1], NULL);
        } else {
            double a = 2 * PI * urand(&rs), o[3] = {L->x, L->y, 1.0 + 8.0 * urand(&rs)};
            double d[3] = {cos(a), sin(a), 0.0};
            trace_hit h;
            if (trace_ray(ps->T, o, d, 30.0, &h) != TRACE_WALL)
                continue;
            memcpy(P, h.p, sizeof P);
            memcpy(N, h.n, sizeof N);
        }
        E = photon_indirect_rgb(ps, P, N, rgb);
        assert_true(rgb[0] == E && rgb[1] == E && rgb[2] == E);
        nonzero += E > 0.0;
        n++;
    }
    printf("white lamps: %d points (ground, roofs, facades), %d lit, RGB == scalar at all; "
           "%u lamps refined, level-4 blocks %u\n",
           n, nonzero, (unsigned)ps->st.lamp_refined, ps->level_count[PHOTON_LEVELS]);
    assert_true(nonzero > n / 2 && ps->level_count[PHOTON_LEVELS] > 0);
    plx_engine_destroy(e);
    free(mem);
}

/* A wall's facade chart read with the wall known (photon_indirect_hit with
 * its building and edge: what aerial frames ask for a wall pixel) against
 * the probe ray from the point (photon_indirect_rgb): the same value at
 * points inside every wall of the fixture, away from its ends. */
static void test_wall_hit_same(void **state)
{
    void *mem;
    plx_engine *e = open_fixture("fixtures/eixample-4x4.geojson", &mem, 256u << 20);
    const scene *s = e->sc;
    photon_sys *ps;
    photon_config c;
    uint32_t b, r, k, n = 0, same = 0, lit = 0;
    (void)state;
    photon_config_default(&c);
    c.aerial_res = 128;
    assert_int_equal(photon_create(&e->mem, e->sc, &c, &ps), PLX_OK);
    for (k = 0; k < 4; k++)
        photon_step(ps, 20000, 900 + k);
    for (b = 0; b < s->nbld; b++)
        for (r = 0; r < s->bld[b].ring_count; r++) {
            const scene_ring *g = &s->rings[s->bld[b].ring_first + r];
            for (k = 0; k < g->count; k++) {
                uint32_t i0 = g->first + k, i1 = g->first + (k + 1) % g->count, q;
                vec2 a = s->pts[i0], d = { s->pts[i1].x - a.x, s->pts[i1].y - a.y };
                double len = sqrt(d.x * d.x + d.y * d.y);
                if (!(len > 0.5))
                    continue;
                for (q = 0; q < 6; q++) {
                    double u = 0.2 + 0.3 * (q % 3), t = q < 3 ? 0.3 : 0.7, P[3], N[3], rgb[3], v[PHOTON_CH], E;
                    trace_hit h;
                    int ok;
                    P[0] = a.x + u * d.x;
                    P[1] = a.y + u * d.y;
                    P[2] = s->bld[b].min_height + t * (s->bld[b].height - s->bld[b].min_height);
                    N[0] = d.y / len;   /* out of the solid: it lies to the left of the edge */
                    N[1] = -d.x / len;
                    N[2] = 0.0;
                    E = photon_indirect_rgb(ps, P, N, rgb);
                    memset(&h, 0, sizeof h);
                    h.kind = TRACE_WALL;
                    h.bld = b;
                    h.edge = i0;
                    memcpy(h.p, P, sizeof P);
                    memcpy(h.n, N, sizeof N);
                    photon_indirect_hit(ps, &h, v);
                    ok = fabs(v[0] - E) <= 1e-9 * fmax(1.0, E);
                    for (i1 = 0; i1 < 3; i1++)
                        ok &= fabs(v[1 + i1] - rgb[i1]) <= 1e-9 * fmax(1.0, rgb[i1]);
                    same += ok;
                    lit += E > 0.0;
                    n++;
                }
            }
        }
    printf("walls known against the probe ray: %u of %u points the same (%u lit)\n", same, n, lit);
    /* a wall shared by two buildings of a block may answer from either side */
    assert_true(n > 500 && lit > n / 2 && same * 100 >= n * 99);
    plx_engine_destroy(e);
    free(mem);
}

/* Two lamps of different colours light the two sides of a street (red on
 * the south side at x = -20, blue on the north side at x = +20): the
 * indirect colour on each side follows its lamp, as the path tracer says.
 * The old mean-lamp-colour tint gave both sides the same colour. */
static void test_two_colour_street(void **state)
{
    fixture f;
    photon_sys *ps;
    photon_config c;
    double red[3] = {1.0, 0.25, 0.1}, blue[3] = {0.1, 0.35, 1.0};
    double eye[3] = {0, 0, 1.7};
    int paths = full_mode() ? 20000 : quick_mode() ? 300 : 3000;
    int frames = full_mode() ? 64 : quick_mode() ? 4 : 24, side, k, i;
    double bound = quick_mode() ? 0.5 : 0.05; /* relative, plus 0.01 */
    (void)state;
    fx_open(&f, 256u << 20);
    assert_true(ref_scene_add_box(&f.s, -60, -25, 60, -6, 15.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f.s, -60, 6, 60, 25, 15.0, 0.0) >= 0);
    assert_true(ref_scene_add_lamp_rgb(&f.s, -20, -4.5, 5, 1000, 20, red[0], red[1], red[2]) >= 0);
    assert_true(ref_scene_add_lamp_rgb(&f.s, 20, 4.5, 5, 1000, 20, blue[0], blue[1], blue[2]) >=
                0);
    f.s.ground_albedo = 0.3;
    f.s.bld[0].albedo = f.s.bld[1].albedo = 0.4;
    fx_finish(&f);
    photon_config_default(&c);
    c.aerial_res = 128;
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_OK);
    assert_int_equal(photon_set_viewer(ps, eye, NULL, 0.0), PLX_OK);
    for (k = 0; k < frames; k++)
        photon_step(ps, 65536, 500 + k);
    printf("two-colour street: chromaticity rgb / E (photons | paths)\n");
    for (side = 0; side < 2; side++) {
        double sgn = side ? 1.0 : -1.0, ph[4] = {0, 0, 0, 0}, rf[4] = {0, 0, 0, 0};
        /* facade points facing the street near the side's lamp, and ground
         * points between the lamp and the facade */
        for (i = 0; i < 8; i++) {
            double P[3], N[3], rgb[3], E;
            if (i < 6) {
                P[0] = sgn * (16.0 + 4.0 * (i % 3));
                P[1] = sgn * 6.0;
                P[2] = 2.0 + 2.0 * (i / 3);
                N[0] = 0.0;
                N[1] = -sgn;
                N[2] = 0.0;
            } else {
                P[0] = sgn * (18.0 + 4.0 * (i - 6));
                P[1] = sgn * 3.0;
                P[2] = 0.0;
                N[0] = N[1] = 0.0;
                N[2] = 1.0;
            }
            E = photon_indirect_rgb(ps, P, N, rgb);
            ph[0] += E;
            for (k = 0; k < 3; k++)
                ph[1 + k] += rgb[k];
            E = ref_indirect_paths_rgb(ps->T, &f.s, P, N, paths, 700 + 10 * side + i, rgb, NULL);
            rf[0] += E;
            for (k = 0; k < 3; k++)
                rf[1 + k] += rgb[k];
        }
        printf("  %s side: E %.3f | %.3f lx; r %.3f g %.3f b %.3f | r %.3f g %.3f b %.3f\n",
               side ? "north (blue lamp)" : "south (red lamp)", ph[0] / 8, rf[0] / 8,
               ph[1] / ph[0], ph[2] / ph[0], ph[3] / ph[0], rf[1] / rf[0], rf[2] / rf[0],
               rf[3] / rf[0]);
        assert_true(ph[0] > 0.0 && rf[0] > 0.0);
        /* each side is the colour of its lamp */
        if (side == 0)
            assert_true(ph[1] > 3.0 * ph[3] && rf[1] > 3.0 * rf[3]);
        else
            assert_true(ph[3] > 3.0 * ph[1] && rf[3] > 3.0 * rf[1]);
        /* and its chromaticity matches the reference's */
        for (k = 1; k < 4; k++)
            assert_true(fabs(ph[k] / ph[0] - rf[k] / rf[0]) <= bound * rf[k] / rf[0] + 0.01);
    }
    fx_close(&f);
}

/* Ground under a canopy (a raised building) gets indirect light from the
 * covered-ground layer; it matches the path tracer within its error (it was
 * 0 without a chart there). */
static void test_covered_canopy(void **state)
{
    fixture f;
    photon_sys *ps;
    photon_config c;
    double pts[6][2] = {{5, 3}, {10, 5}, {15, 7}, {10, 2}, {3, 8}, {17, 4}}, up[3] = {0, 0, 1};
    int paths = full_mode() ? 40000 : quick_mode() ? 500 : 8000;
    int frames = full_mode() ? 64 : quick_mode() ? 4 : 24, k, i;
    double err = 0.0, bound = quick_mode() ? 0.4 : 0.12, prog[6], night_err = 0.0;
    (void)state;
    fx_open(&f, 256u << 20);
    assert_true(ref_scene_add_box(&f.s, 0, 0, 20, 10, 5.0, 4.0) >= 0);   /* canopy */
    assert_true(ref_scene_add_box(&f.s, -5, 14, 25, 20, 10.0, 0.0) >= 0); /* a wall behind */
    assert_true(ref_scene_add_lamp(&f.s, 10, 12, 3, 1000, 25) >= 0);
    f.s.ground_albedo = 0.3;
    f.s.bld[0].albedo = 0.5;
    f.s.bld[1].albedo = 0.4;
    fx_finish(&f);
    photon_config_default(&c);
    c.aerial_res = 128;
    c.lamp_photons = quick_mode() ? 1u << 17 : 1u << 20;
    c.kernel_min = 2.5; /* I_cov uses kernel_min; A is at r(24) = 2.5 */
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_OK);
    assert_true(ps->ncov > 0 && ps->ncov <= ps->cov_cap);
    for (k = 0; k < frames; k++)
        photon_step(ps, 65536, 800 + k);
    printf("covered ground under a canopy (%u slots of %u): photons vs paths (+- 1 sd)\n",
           ps->ncov, ps->cov_cap);
    for (i = 0; i < 6; i++) {
        double P[3] = {pts[i][0], pts[i][1], 0.0}, sd, ref, est;
        assert_true(photon_covered_at(ps, P[0], P[1]));
        est = prog[i] = photon_indirect(ps, P, up);
        ref = ref_indirect_paths_rgb(ps->T, &f.s, P, up, paths, 900 + i, NULL, &sd);
        printf("  (%4.1f %4.1f): %7.3f lx, %7.3f +- %.3f lx\n", P[0], P[1], est, ref, sd);
        assert_true(ref > 0.0 && est > 0.5 * ref);
        err += fabs(est - ref) / ref;
    }
    err /= 6;
    printf("  mean rel err %.4f (bound %.2f); stored covered %.1f%% of the later-hit flux, "
           "lost %.2f%%\n",
           err, bound, 100.0 * ps->st.stored_covered / ps->st.arrived,
           100.0 * ps->st.lost / ps->st.arrived);
    assert_true(err <= bound);
    assert_true(ps->st.stored_covered > 0.0);
    assert_true(fabs(ps->st.stored_chart + ps->st.stored_aerial + ps->st.stored_ambient +
                     ps->st.stored_covered + ps->st.lost - ps->st.arrived) <=
                1e-9 * ps->st.arrived);
    /* the lamp refined (floor map, push into I and I_cov; A and A_cov
     * restart): covered ground now reads I_cov, with the same answer */
    assert_int_equal(photon_lamp_request(ps, 0), 0);
    assert_int_equal(ps->gframes, 0);
    for (i = 0; i < 6; i++) {
        double P[3] = {pts[i][0], pts[i][1], 0.0}, est = photon_indirect(ps, P, up);
        night_err += fabs(est - prog[i]) / prog[i] / 6;
    }
    printf("  after refining the lamp: mean rel diff to the progressive answer %.4f\n",
           night_err);
    assert_true(night_err <= (quick_mode() ? 0.4 : 0.1));
    fx_close(&f);
}

/* ---- lamp cache ---------------------------------------------------------------- */

static void lamp_row(fixture *f, int nl)
{
    int i;
    fx_open(f, 64u << 20);
    assert_true(ref_scene_add_box(&f->s, 0, 10, 200, 30, 15.0, 0.0) >= 0);
    for (i = 0; i < nl; i++)
        assert_true(ref_scene_add_lamp(&f->s, 10.0 + 20.0 * i, 5.0, 6.0, 1000, 20.0) >= 0);
    f->s.ground_albedo = 0.3;
    fx_finish(f);
}

/* The photon buffers of a row of 6 lamps 20 m apart (lamp_row) with a
 * cache of 3 floor maps of 16 x 16 texels, photons photons a lamp. */
static photon_sys *lamp_cache(fixture *f, photon_config *c, uint32_t photons)
{
    photon_sys *ps = NULL;
    lamp_row(f, 6);
    photon_config_default(c);
    c->aerial_res = 128;
    c->lamp_slots = 3;
    c->lamp_res = 16;
    c->lamp_photons = photons;
    assert_int_equal(photon_create(&f->a, &f->s, c, &ps), PLX_OK);
    return ps;
}

static void test_lamp_lru(void **state)
{
    fixture f;
    photon_sys *ps;
    photon_config c;
    uint32_t order[8], n;
    (void)state;
    ps = lamp_cache(&f, &c, 500);
    assert_int_equal(ps->nslots, 3);
    assert_int_equal(photon_lamp_request(ps, 0), 0);
    assert_int_equal(photon_lamp_request(ps, 1), 0);
    assert_int_equal(photon_lamp_request(ps, 2), 0);
    assert_int_equal(photon_lamp_request(ps, 0), 1);
    n = photon_lamp_lru(ps, order, 8);
    assert_int_equal(n, 3);
    assert_int_equal(order[0], 0);
    assert_int_equal(order[1], 2);
    assert_int_equal(order[2], 1);
    /* a miss evicts the least recently used: lamp 1 */
    assert_int_equal(photon_lamp_request(ps, 3), 0);
    assert_false(photon_lamp_cached(ps, 1));
    assert_true(photon_lamp_cached(ps, 0) && photon_lamp_cached(ps, 2) &&
                photon_lamp_cached(ps, 3));
    n = photon_lamp_lru(ps, order, 8);
    assert_int_equal(order[0], 3);
    assert_int_equal(order[1], 0);
    assert_int_equal(order[2], 2);
    assert_int_equal(photon_lamp_request(ps, 2), 1);
    assert_int_equal(photon_lamp_request(ps, 1), 0); /* evicts 0 */
    assert_false(photon_lamp_cached(ps, 0));
    assert_int_equal(ps->st.lamp_hits, 2);
    assert_int_equal(ps->st.lamp_misses, 5);
    assert_int_equal(ps->st.lamp_evictions, 2);
    assert_int_equal(ps->st.lamp_refined, 4); /* 0, 1, 2, 3; 1 again is not new */
    assert_int_equal(photon_lamp_request(ps, 99), -1);
    /* near the viewer: lamps within 25 m of x = 50 are 2 (x=50), 1 and 3 */
    {
        double eye[3] = {50.0, 5.0, 1.7};
        ps->cfg.near_radius = 25.0;
        photon_lamps_update(ps, eye);
        n = photon_lamp_lru(ps, order, 8);
        assert_int_equal(n, 3);
        assert_int_equal(order[0], 2);
        assert_true((order[1] == 1 && order[2] == 3) || (order[1] == 3 && order[2] == 1));
    }
    fx_close(&f);
    /* capacity from the budget */
    lamp_row(&f, 6);
    c.lamp_slots = 0;
    c.lamp_cache_bytes = (size_t)(2.5 * (double)photon_lamp_slot_bytes(&f.s, &c));
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_OK);
    assert_int_equal(ps->nslots, 2);
    fx_close(&f);
}

/* The night lighting sums the cached floor maps in slot order, so a hit,
 * which reorders the LRU list but moves no slot, leaves every bit of it
 * unchanged (plx_indirect_refine keeps the frames' atlas on hits alone);
 * a miss changes it. Points on a 1 m grid along the row of lamps, where
 * the floor maps of neighbouring lamps overlap. */
static void night_grid(const photon_sys *ps, double *e, int n)
{
    int i;
    for (i = 0; i < n; i++)
        photon_night_horizontal(ps, 10.0 + 0.37 * i, 1.0 + (i % 7), 0.0, 0, &e[PHOTON_CH * (size_t)i]);
}

static void test_lamp_hits_keep_bits(void **state)
{
    enum { N = 160 };
    fixture f;
    photon_sys *ps;
    photon_config c;
    uint32_t order[8];
    static double before[N * PHOTON_CH], after[N * PHOTON_CH];
    int i, overlap = 0;
    (void)state;
    ps = lamp_cache(&f, &c, 2000);
    photon_step(ps, 5000, 1);
    assert_int_equal(photon_lamp_request(ps, 0), 0);
    assert_int_equal(photon_lamp_request(ps, 1), 0);
    assert_int_equal(photon_lamp_request(ps, 2), 0);
    night_grid(ps, before, N);
    for (i = 0; i < N; i++) { /* points in more than one floor map: the order could matter */
        double x = 10.0 + 0.37 * i;
        int k, in = 0;
        for (k = 0; k < 3; k++)
            in += fabs(x - (10.0 + 20.0 * k)) < 20.0;
        overlap += in > 1 && before[PHOTON_CH * (size_t)i] > 0.0;
    }
    assert_true(overlap > 20);
    assert_int_equal(photon_lamp_request(ps, 0), 1); /* hits: LRU 2 1 0 becomes 1 0 2 */
    assert_int_equal(photon_lamp_request(ps, 1), 1);
    assert_int_equal(photon_lamp_lru(ps, order, 8), 3);
    assert_int_equal(order[0], 1);
    assert_int_equal(order[1], 0);
    assert_int_equal(order[2], 2);
    night_grid(ps, after, N);
    assert_memory_equal(before, after, sizeof before);
    assert_int_equal(photon_lamp_request(ps, 3), 0); /* a miss: lamp 2 evicted, 3 pushed */
    night_grid(ps, after, N);
    assert_memory_not_equal(before, after, sizeof before);
    fx_close(&f);
}

/* Push-pull: a lamp's ground indirect is the same whether it comes from the
 * progressive aerial chart (never refined), from its cached floor map, or
 * from the improved map after eviction; eviction and recomputation leave
 * the answer unchanged. */
static void test_lamp_push_pull(void **state)
{
    fixture f;
    photon_sys *ps;
    photon_config c;
    double P[4][3] = {{30, 6, 0}, {24, 4, 0}, {36, 8, 0}, {30, 2, 0}}, n[3] = {0, 0, 1};
    double prog[4], cached[4], pushed[4], again[4];
    int i, k;
    (void)state;
    fx_open(&f, 64u << 20);
    assert_true(ref_scene_add_box(&f.s, 0, 10, 60, 30, 15.0, 0.0) >= 0);
    assert_true(ref_scene_add_lamp(&f.s, 30.0, 5.0, 6.0, 1000, 20.0) >= 0);
    assert_true(ref_scene_add_lamp(&f.s, 150.0, 5.0, 6.0, 1000, 20.0) >= 0);
    f.s.ground_albedo = 0.3;
    fx_finish(&f);
    photon_config_default(&c);
    c.aerial_res = 128;
    c.lamp_slots = 1;
    c.lamp_res = 32;
    c.lamp_photons = quick_mode() ? 100000 : 400000;
    c.kernel_min = 1.5;
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_OK);
    for (k = 0; k < (quick_mode() ? 10 : 40); k++)
        photon_step(ps, 20000, 5 + k);
    for (i = 0; i < 4; i++)
        prog[i] = photon_indirect(ps, P[i], n);
    assert_int_equal(photon_lamp_request(ps, 0), 0);
    assert_int_equal(ps->gframes, 0); /* A restarted */
    for (i = 0; i < 4; i++)
        cached[i] = photon_indirect(ps, P[i], n);
    assert_int_equal(photon_lamp_request(ps, 1), 0); /* evicts lamp 0: I keeps it */
    for (i = 0; i < 4; i++)
        pushed[i] = photon_indirect(ps, P[i], n);
    assert_int_equal(photon_lamp_request(ps, 0), 0); /* recomputed, same photons */
    for (i = 0; i < 4; i++)
        again[i] = photon_indirect(ps, P[i], n);
    printf("push-pull (ground near a refined lamp): progressive / cached / pushed / again\n");
    for (i = 0; i < 4; i++) {
        printf("  (%.0f,%.0f): %.4f %.4f %.4f %.4f\n", P[i][0], P[i][1], prog[i], cached[i],
               pushed[i], again[i]);
        assert_true(prog[i] > 0.0);
        assert_true(fabs(cached[i] - prog[i]) < (quick_mode() ? 0.3 : 0.15) * prog[i]);
        assert_true(fabs(pushed[i] - prog[i]) < (quick_mode() ? 0.3 : 0.15) * prog[i]);
        assert_true(fabs(again[i] - cached[i]) <= 1e-4 * cached[i]);
    }
    /* the progressive pass no longer splats lamp 0 into A */
    photon_step(ps, 20000, 999);
    assert_true(ps->st.skipped_refined > 0.0);
    fx_close(&f);
}

/* ---- levels --------------------------------------------------------------------- */

static void test_levels_moving_viewer(void **state)
{
    void *mem;
    plx_engine *e = open_fixture("fixtures/eixample-4x4.geojson", &mem, 256u << 20);
    const scene *s = e->sc;
    photon_sys *ps;
    photon_config c;
    double eye[3];
    int step;
    uint32_t k;
    (void)state;
    assert_int_equal(s->nblocks, 16);
    photon_config_default(&c);
    c.level_blocks[0] = 2;
    c.level_blocks[1] = 3;
    c.level_blocks[2] = 4;
    c.level_blocks[3] = 3;
    c.aerial_res = 64;
    assert_int_equal(photon_create(&e->mem, s, &c, &ps), PLX_OK);
    for (step = 0; step < 12; step++) {
        uint32_t cnt[5] = {0, 0, 0, 0, 0}, a, b;
        eye[0] = s->bounds[0] + (s->bounds[2] - s->bounds[0]) * step / 11.0;
        eye[1] = s->bounds[1] + 0.3 * (s->bounds[3] - s->bounds[1]);
        eye[2] = 1.7;
        assert_int_equal(photon_set_viewer(ps, eye, NULL, 0.0), PLX_OK);
        for (k = 0; k < s->nblocks; k++)
            cnt[photon_block_level(ps, k)]++;
        for (k = 0; k < 4; k++)
            assert_true(cnt[k] <= c.level_blocks[k]);
        /* 16 blocks, 12 slots: 4 at level 4, and the levels fill in order */
        assert_int_equal(cnt[4], 4);
        /* nearer blocks never get a coarser level */
        for (a = 0; a < s->nblocks; a++)
            for (b = 0; b < s->nblocks; b++) {
                const double *ba = s->blocks[a].box, *bb = s->blocks[b].box;
                double da = hypot(fmax(0, fmax(ba[0] - eye[0], eye[0] - ba[2])),
                                  fmax(0, fmax(ba[1] - eye[1], eye[1] - ba[3])));
                double db = hypot(fmax(0, fmax(bb[0] - eye[0], eye[0] - bb[2])),
                                  fmax(0, fmax(bb[1] - eye[1], eye[1] - bb[3])));
                if (da < db - 1e-9)
                    assert_true(photon_block_level(ps, a) <= photon_block_level(ps, b));
            }
        /* slots are distinct per level */
        for (a = 0; a < s->nblocks; a++)
            for (b = a + 1; b < s->nblocks; b++)
                if (ps->blevel[a] == ps->blevel[b] && ps->blevel[a] < PHOTON_LEVELS)
                    assert_true(ps->bslot[a] != ps->bslot[b]);
    }
    /* buffers are kept while the level does not change */
    {
        uint32_t b0 = PHOTON_NONE, fr;
        photon_step(ps, 4096, 1);
        for (k = 0; k < s->nblocks; k++)
            if (ps->blevel[k] == 0)
                b0 = k;
        assert_true(b0 != PHOTON_NONE);
        fr = ps->lev[0].slot_frames[ps->bslot[b0]];
        assert_int_equal(fr, 1);
        eye[0] += 0.5; /* a small move: same levels */
        assert_int_equal(photon_set_viewer(ps, eye, NULL, 0.0), PLX_OK);
        assert_int_equal(ps->blevel[b0], 0);
        assert_int_equal(ps->lev[0].slot_frames[ps->bslot[b0]], 1);
        /* far away: it leaves level 0 and its new chart starts empty */
        eye[0] = s->bounds[0];
        eye[1] = s->bounds[1];
        assert_int_equal(photon_set_viewer(ps, eye, NULL, 0.0), PLX_OK);
        if (ps->blevel[b0] < PHOTON_LEVELS && ps->blevel[b0] != 0)
            assert_int_equal(ps->lev[ps->blevel[b0]].slot_frames[ps->bslot[b0]], 0);
        assert_true(ps->blevel[b0] != 0);
    }
    /* a view cone: blocks behind the viewer are not at level 0 or 1 */
    {
        double dir[3] = {1, 0, 0};
        eye[0] = 0.5 * (s->bounds[0] + s->bounds[2]);
        eye[1] = 0.5 * (s->bounds[1] + s->bounds[3]);
        assert_int_equal(photon_set_viewer(ps, eye, dir, 60.0), PLX_OK);
        for (k = 0; k < s->nblocks; k++)
            if (s->blocks[k].box[2] < eye[0] - 1.0)
                assert_true(photon_block_level(ps, k) >= 2);
    }
    plx_engine_destroy(e);
    free(mem);
}

/* ---- histogram matching ----------------------------------------------------------- */

static void test_hist_match(void **state)
{
    enum { N = 1000 };
    static uint8_t src[N * 3], ref[N * 3], out[N * 3];
    uint64_t rs = 3;
    int i, c;
    (void)state;
    for (i = 0; i < N; i++)
        for (c = 0; c < 3; c++) {
            src[3 * i + c] = (uint8_t)(rng_next(&rs) % 256);
            ref[3 * i + c] = (uint8_t)(rng_next(&rs) % 256);
        }
    /* to itself: identity */
    assert_int_equal(photon_hist_match(src, N, src, N, 0.0, out), 0);
    assert_memory_equal(src, out, sizeof src);
    /* a uniform source onto a reference with values only 100 and 200 in
     * equal parts: the lower half of each channel goes to 100, the rest to
     * 200; the mapping is monotone */
    for (i = 0; i < N; i++)
        for (c = 0; c < 3; c++) {
            src[3 * i + c] = (uint8_t)(i * 256 / N);
            ref[3 * i + c] = (uint8_t)(i % 2 ? 200 : 100);
        }
    assert_int_equal(photon_hist_match(src, N, ref, N, 0.0, out), 0);
    for (i = 0; i < N; i++)
        for (c = 0; c < 3; c++) {
            assert_true(out[3 * i + c] == 100 || out[3 * i + c] == 200);
            assert_int_equal(out[3 * i + c], i < N / 2 ? 100 : 200);
        }
    /* a dark reference: pixels below the threshold are left out */
    for (i = 0; i < N; i++) {
        int dark = i % 4 != 0;
        ref[3 * i] = dark ? 2 : 250;
        ref[3 * i + 1] = dark ? 1 : 150;
        ref[3 * i + 2] = dark ? 0 : 60;
    }
    assert_int_equal(photon_hist_match(src, N, ref, N, 0.0, out), 0);
    assert_int_equal(out[0], 2); /* dark pixels count: the darkest go dark */
    assert_int_equal(photon_hist_match(src, N, ref, N, 20.0, out), 0);
    for (i = 0; i < N; i++) {
        assert_int_equal(out[3 * i], 250);
        assert_int_equal(out[3 * i + 1], 150);
        assert_int_equal(out[3 * i + 2], 60);
    }
    /* all dark and a threshold above them: all are used */
    assert_int_equal(photon_hist_match(src, N, ref + 3, 1, 200.0, out), 0);
    assert_int_equal(out[0], 2);
    /* in place */
    memcpy(out, src, sizeof src);
    assert_int_equal(photon_hist_match(out, N, ref, N, 20.0, out), 0);
    assert_int_equal(out[5], 60);
    assert_int_equal(photon_hist_match(NULL, N, ref, N, 0.0, out), -1);
    assert_int_equal(photon_hist_match(src, 0, ref, N, 0.0, out), -1);
}

/* ---- memory ----------------------------------------------------------------------- */

static void test_create_nomem(void **state)
{
    fixture f;
    photon_sys *ps = NULL;
    photon_config c;
    uint64_t k;
    arena_mark m;
    plx_status st = PLX_E_NOMEM;
    int i;
    (void)state;
    /* a row of lamps by a block, and a canopy (covered ground) */
    fx_open(&f, 64u << 20);
    assert_true(ref_scene_add_box(&f.s, 0, 10, 200, 30, 15.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f.s, 50, 0, 60, 8, 5.0, 3.0) >= 0);
    for (i = 0; i < 4; i++)
        assert_true(ref_scene_add_lamp(&f.s, 10.0 + 20.0 * i, 5.0, 6.0, 1000, 20.0) >= 0);
    fx_finish(&f);
    photon_config_default(&c);
    c.aerial_res = 64;
    c.lamp_slots = 2;
    c.lamp_res = 8;
    m = arena_get_mark(&f.a);
    for (k = 1; k < 1000 && st != PLX_OK; k++) {
        f.a.requests = 0;
        f.a.fail_at = k;
        st = photon_create(&f.a, &f.s, &c, &ps);
        if (st != PLX_OK) {
            assert_int_equal(st, PLX_E_NOMEM);
            assert_int_equal(f.a.lo, m.lo);
            assert_int_equal(f.a.hi, m.hi);
            assert_int_equal(f.a.used[PLX_PART_PHOTON], m.used[PLX_PART_PHOTON]);
        }
    }
    f.a.fail_at = 0;
    assert_int_equal(st, PLX_OK);
    assert_true(ps->ncov > 0 && ps->gcov != NULL);
    printf("photon_create: succeeded at request %llu; %zu bytes (photon_bytes %zu)\n",
           (unsigned long long)(k - 1), f.a.used[PLX_PART_PHOTON] - m.used[PLX_PART_PHOTON],
           photon_bytes(&f.s, &c));
    assert_true(f.a.used[PLX_PART_PHOTON] - m.used[PLX_PART_PHOTON] <= photon_bytes(&f.s, &c));
    /* a budget too small for the part */
    {
        photon_sys *p2;
        f.a.budget[PLX_PART_PHOTON] = f.a.used[PLX_PART_PHOTON] + 1000;
        assert_int_equal(photon_create(&f.a, &f.s, &c, &p2), PLX_E_NOMEM);
        f.a.budget[PLX_PART_PHOTON] = 0;
    }
    /* bad configurations */
    c.kernel_min = 3.0;
    c.kernel_max = 2.0;
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_E_INVALID);
    photon_config_default(&c);
    c.chart_h = 4;
    assert_int_equal(photon_create(&f.a, &f.s, &c, &ps), PLX_E_INVALID);
    fx_close(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trace_vs_brute),
        cmocka_unit_test(test_trace_horizon),
        cmocka_unit_test(test_trace_degenerate),
        cmocka_unit_test(test_trace_lamp_rays),
        cmocka_unit_test(test_energy_closed_box),
        cmocka_unit_test(test_one_bounce_wall),
        cmocka_unit_test(test_accuracy_eixample),
        cmocka_unit_test(test_party_wall_strips),
        cmocka_unit_test(test_surface_key_vs_brute),
        cmocka_unit_test(test_coarse_charts),
        cmocka_unit_test(test_splat_vs_brute),
        cmocka_unit_test(test_direction_samplers),
        cmocka_unit_test(test_bounce_weights),
        cmocka_unit_test(test_white_lamps_equal),
        cmocka_unit_test(test_wall_hit_same),
        cmocka_unit_test(test_two_colour_street),
        cmocka_unit_test(test_covered_canopy),
        cmocka_unit_test(test_lamp_lru),
        cmocka_unit_test(test_lamp_hits_keep_bits),
        cmocka_unit_test(test_lamp_push_pull),
        cmocka_unit_test(test_levels_moving_viewer),
        cmocka_unit_test(test_hist_match),
        cmocka_unit_test(test_create_nomem),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
