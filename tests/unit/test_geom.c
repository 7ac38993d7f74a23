/* Tests of geom: the exact orientation predicate against an independent
 * integer evaluation, segment meeting, point in ring, ring simplicity (sweep
 * against brute force, big rings, scratch exhaustion), distances, areas.
 *
 * Build: gcc -std=c99 ... tests/unit/test_geom.c src/base/geom.c src/base/arena.c
 *        -lcmocka -lm
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <float.h>
#include <time.h>
#include <cmocka.h>

#include "base/geom.h"
#include "base/arena.h"
#include "base/bucketgrid.h"

__extension__ typedef __int128 i128;

/* ---- helpers --------------------------------------------------------------- */

typedef struct rng { uint64_t s; } rng;

static uint64_t rng_next(rng *r)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* uniform in [0, n) */
static uint64_t rng_below(rng *r, uint64_t n)
{
    return rng_next(r) % n;
}

/* uniform in [0, 1) with 53 random bits */
static double rng_unit(rng *r)
{
    return (double)(rng_next(r) >> 11) * 0x1p-53;
}

/* a random integer with |v| < 2^bits, bits random in [0, maxbits] */
static int64_t rng_int(rng *r, int maxbits)
{
    int bits = (int)rng_below(r, (uint64_t)maxbits + 1);
    int64_t v = bits == 0 ? 0 : (int64_t)(rng_next(r) >> (64 - bits));
    return (rng_next(r) & 1) ? -v : v;
}

static vec2 V(double x, double y)
{
    vec2 v;
    v.x = x;
    v.y = y;
    return v;
}

static int sign_i128(i128 v)
{
    return v > 0 ? 1 : v < 0 ? -1 : 0;
}

/* Exact orientation of integer points (|coordinates| < 2^62). */
static int orient_int(const int64_t x[3], const int64_t y[3])
{
    i128 d = (i128)(x[0] - x[2]) * (i128)(y[1] - y[2]) -
             (i128)(y[0] - y[2]) * (i128)(x[1] - x[2]);
    return sign_i128(d);
}

/* Writes v = m * 2^e with m odd (or v = 0). */
static void dyadic(double v, int64_t *m, int *e)
{
    int ex;
    double f;
    if (v == 0.0) {
        *m = 0;
        *e = 0;
        return;
    }
    f = frexp(v, &ex);
    *m = (int64_t)ldexp(f, 53);
    *e = ex - 53;
    while ((*m & 1) == 0) {
        *m /= 2;
        (*e)++;
    }
}

/* Independent reference: if the six doubles are integers times one common
 * power of two with magnitudes below 2^61, returns the exact orientation via
 * __int128 and sets *ok; otherwise *ok = 0. */
static int orient_dyadic(vec2 a, vec2 b, vec2 c, int *ok)
{
    double v[6];
    int64_t m[6], x[3], y[3];
    int e[6], emin = INT32_MAX, i;
    v[0] = a.x; v[1] = b.x; v[2] = c.x; v[3] = a.y; v[4] = b.y; v[5] = c.y;
    for (i = 0; i < 6; i++) {
        dyadic(v[i], &m[i], &e[i]);
        if (m[i] != 0 && e[i] < emin)
            emin = e[i];
    }
    *ok = 1;
    for (i = 0; i < 6; i++) {
        int sh = e[i] - emin;
        uint64_t mag = (uint64_t)(m[i] < 0 ? -m[i] : m[i]);
        if (m[i] != 0 && (sh > 60 || (mag >> (61 - sh)) != 0)) {
            *ok = 0;
            return 0;
        }
        if (m[i] != 0)
            m[i] = m[i] * ((int64_t)1 << sh);
    }
    x[0] = m[0]; x[1] = m[1]; x[2] = m[2];
    y[0] = m[3]; y[1] = m[4]; y[2] = m[5];
    return orient_int(x, y);
}

/* Every exact transform of the arguments that must give a known answer. */
static void check_orient_symmetries(vec2 a, vec2 b, vec2 c, int want)
{
    vec2 na = V(-a.x, -a.y), nb = V(-b.x, -b.y), nc = V(-c.x, -c.y);
    vec2 sa = V(a.y, a.x), sb = V(b.y, b.x), sc = V(c.y, c.x);
    assert_int_equal(geom_orient(a, b, c), want);
    assert_int_equal(geom_orient(b, c, a), want);
    assert_int_equal(geom_orient(c, a, b), want);
    assert_int_equal(geom_orient(b, a, c), -want);
    assert_int_equal(geom_orient(a, c, b), -want);
    assert_int_equal(geom_orient(na, nb, nc), want);   /* half turn */
    assert_int_equal(geom_orient(sa, sb, sc), -want);  /* mirror */
}

/* ---- orientation ----------------------------------------------------------- */

static void test_orient_basic(void **state)
{
    (void)state;
    assert_int_equal(geom_orient(V(0, 0), V(1, 0), V(0, 1)), 1);
    assert_int_equal(geom_orient(V(0, 0), V(0, 1), V(1, 0)), -1);
    assert_int_equal(geom_orient(V(0, 0), V(1, 1), V(2, 2)), 0);
    assert_int_equal(geom_orient(V(0, 0), V(1, 1), V(-3, -3)), 0);
    assert_int_equal(geom_orient(V(1, 1), V(1, 1), V(5, 7)), 0);
    assert_int_equal(geom_orient(V(0.1, 0.2), V(0.3, 0.6), V(0.5, 1.0)),
                     geom_orient_ref(V(0.1, 0.2), V(0.3, 0.6), V(0.5, 1.0)));
    /* -0.0 and 0.0 are the same value */
    assert_int_equal(geom_orient(V(-0.0, 0), V(0, -0.0), V(1, 0)), 0);
    check_orient_symmetries(V(0, 0), V(1, 0), V(0, 1), 1);
}

/* Random integer coordinates times powers of two (different for x and y,
 * from 2^-1074 to 2^917), compared with the exact __int128 determinant of the
 * integers: scaling all x by 2^kx and all y by 2^ky multiplies the
 * determinant by 2^(kx+ky), which keeps its sign. */
static void test_orient_random_vs_int128(void **state)
{
    rng r = { 12345 };
    int i, k, counts[3] = { 0, 0, 0 };
    (void)state;
    for (i = 0; i < 200000; i++) {
        int64_t x[3], y[3];
        int kx, ky, mode = (int)rng_below(&r, 4), want, got;
        vec2 p[3];
        for (k = 0; k < 3; k++) {
            x[k] = rng_int(&r, 53);
            y[k] = rng_int(&r, 53);
        }
        if (rng_below(&r, 3) == 0) {
            /* exactly collinear lattice points, sometimes nudged */
            int64_t dx = rng_int(&r, 26), dy = rng_int(&r, 26);
            int64_t i1 = rng_int(&r, 20), i2 = rng_int(&r, 20);
            x[0] = rng_int(&r, 51);
            y[0] = rng_int(&r, 51);
            x[1] = x[0] + i1 * dx;
            y[1] = y[0] + i1 * dy;
            x[2] = x[0] + i2 * dx + (rng_below(&r, 2) ? (int64_t)rng_below(&r, 3) - 1 : 0);
            y[2] = y[0] + i2 * dy;
        } else if (rng_below(&r, 2)) {
            /* nearly collinear: c close to the line ab */
            double t = rng_unit(&r);
            x[2] = x[0] + (int64_t)llround(t * (double)(x[1] - x[0]));
            y[2] = y[0] + (int64_t)llround(t * (double)(y[1] - y[0]));
            x[2] += (int64_t)rng_below(&r, 5) - 2;
            y[2] += (int64_t)rng_below(&r, 5) - 2;
            for (k = 0; k < 3; k++) {   /* stay within 2^53 */
                if (x[k] > ((int64_t)1 << 53) || x[k] < -((int64_t)1 << 53))
                    x[k] /= 2;
                if (y[k] > ((int64_t)1 << 53) || y[k] < -((int64_t)1 << 53))
                    y[k] /= 2;
            }
        }
        switch (mode) {
        case 0: kx = ky = 0; break;
        case 1: kx = ky = (int)rng_below(&r, 121) - 60; break;
        case 2: kx = (int)rng_below(&r, 2045) - 1074;
                ky = (int)rng_below(&r, 2045) - 1074; break;
        default: kx = (rng_next(&r) & 1) ? -1074 : 917;
                 ky = (rng_next(&r) & 1) ? -1074 : 917; break;
        }
        for (k = 0; k < 3; k++) {
            p[k].x = ldexp((double)x[k], kx);
            p[k].y = ldexp((double)y[k], ky);
            /* the scaled values are exact: check it */
            assert_true(ldexp(p[k].x, -kx) == (double)x[k]);
            assert_true(ldexp(p[k].y, -ky) == (double)y[k]);
        }
        want = orient_int(x, y);
        got = geom_orient(p[0], p[1], p[2]);
        if (got != want)
            fprintf(stderr, "case %d: mode %d kx %d ky %d got %d want %d\n",
                    i, mode, kx, ky, got, want);
        assert_int_equal(got, want);
        assert_int_equal(geom_orient_ref(p[0], p[1], p[2]), want);
        if (i % 16 == 0)
            check_orient_symmetries(p[0], p[1], p[2], want);
        counts[want + 1]++;
    }
    fprintf(stderr, "    random: %d cw, %d collinear, %d ccw\n",
            counts[0], counts[1], counts[2]);
    /* all three answers occur many times */
    assert_true(counts[0] > 10000 && counts[1] > 10000 && counts[2] > 10000);
}

/* Points on a line at 1e-16 relative, scaled by 2^-100 .. 2^100: either
 * c = a + t (b - a) rounded to double, or exactly collinear points (a with
 * 30 fraction bits, steps of 20 bits, so every sum is exact); then c is
 * nudged by up to 2 ulps. The answer is decided by the last bits. All these
 * coordinates are integers times a common power of two below 2^61, so the
 * __int128 reference applies to every case. */
static void near_collinear_case(rng *r, int exact, vec2 *a, vec2 *b, vec2 *c)
{
    int nudge = (int)rng_below(r, 5) - 2, k;
    double scale = ldexp(1.0, (int)rng_below(r, 201) - 100);
    if (!exact) {
        double t;
        *a = V(1.0 + rng_unit(r), 1.0 + rng_unit(r));
        *b = V(1.0 + rng_unit(r), 1.0 + rng_unit(r));
        t = rng_unit(r);
        *c = V(a->x + t * (b->x - a->x), a->y + t * (b->y - a->y));
    } else {
        double dx = (double)rng_int(r, 20) * 0x1p-24;
        double dy = (double)rng_int(r, 20) * 0x1p-24;
        int j1 = (int)rng_below(r, 33) - 16, j2 = (int)rng_below(r, 33) - 16;
        *a = V(1.0 + (double)(rng_next(r) >> 34) * 0x1p-30,
               1.0 + (double)(rng_next(r) >> 34) * 0x1p-30);
        *b = V(a->x + j1 * dx, a->y + j1 * dy);
        *c = V(a->x + j2 * dx, a->y + j2 * dy);
    }
    for (k = 0; k < (nudge < 0 ? -nudge : nudge); k++)
        c->y = nextafter(c->y, nudge < 0 ? -100.0 : 100.0);
    a->x *= scale; a->y *= scale;
    b->x *= scale; b->y *= scale;
    c->x *= scale; c->y *= scale;
}

static void test_orient_near_collinear(void **state)
{
    rng r = { 777 };
    int i, counts[3] = { 0, 0, 0 };
    (void)state;
    for (i = 0; i < 100000; i++) {
        vec2 a, b, c;
        int ok, want;
        near_collinear_case(&r, i % 2, &a, &b, &c);
        want = orient_dyadic(a, b, c, &ok);
        assert_true(ok);
        assert_int_equal(geom_orient(a, b, c), want);
        assert_int_equal(geom_orient(c, a, b), want);
        assert_int_equal(geom_orient_ref(a, b, c), want);
        counts[want + 1]++;
    }
    fprintf(stderr, "    near collinear: %d cw, %d collinear, %d ccw\n",
            counts[0], counts[1], counts[2]);
    assert_true(counts[0] > 5000 && counts[1] > 5000 && counts[2] > 5000);
}

/* Kettner et al., "Classroom examples of robustness problems in geometric
 * computations": p = (0.5 + x u, 0.5 + y u), q = (12, 12), r = (24, 24),
 * u = 2^-53. The naive determinant gets a large share of these wrong. */
static void test_orient_classroom(void **state)
{
    int i, j, naive_wrong = 0;
    const double u = 0x1p-53;
    (void)state;
    for (i = 0; i < 256; i++) {
        for (j = 0; j < 256; j++) {
            vec2 p = V(0.5 + i * u, 0.5 + j * u), q = V(12, 12), r = V(24, 24);
            int64_t x[3], y[3];
            double naive;
            int want;
            x[0] = ((int64_t)1 << 52) + i;
            y[0] = ((int64_t)1 << 52) + j;
            x[1] = y[1] = (int64_t)12 << 53;
            x[2] = y[2] = (int64_t)24 << 53;
            want = orient_int(x, y);
            assert_int_equal(want, i < j ? 1 : i > j ? -1 : 0);
            assert_int_equal(geom_orient(p, q, r), want);
            assert_int_equal(geom_orient(q, r, p), want);
            assert_int_equal(geom_orient(r, p, q), want);
            naive = (p.x - r.x) * (q.y - r.y) - (p.y - r.y) * (q.x - r.x);
            naive_wrong += (naive > 0) - (naive < 0) != want;
        }
    }
    /* the test is worth something only if the naive formula fails here */
    assert_true(naive_wrong > 1000);
    {
        /* the paper's second example, with inexact decimal inputs */
        vec2 p = V(0.50000000000002531, 0.5000000000000171);
        vec2 q = V(17.300000000000001, 17.300000000000001);
        vec2 r = V(24.00000000000005, 24.0000000000000053);
        int ok, want = orient_dyadic(p, q, r, &ok);
        assert_true(ok);
        assert_int_equal(geom_orient(p, q, r), want);
        assert_int_equal(geom_orient(q, r, p), want);
    }
}

/* Cases found by a random search in which the naive determinant has the
 * wrong sign although |det| is 1.5 to 1.9 u (|dl| + |dr|), u = 2^-53: close
 * to the filter's bound (3u + 64u^2)(|dl| + |dr|). */
static void test_orient_near_filter_bound(void **state)
{
    static const double c[][6] = {
        { 0.73984889803194531, -0.34359945288839122, -0.65627102765393852,
          0.38297835413970782, 1.3486316184770744, -0.66042611357824266 },
        { 0.48232395299487418, 0.10702458851893604, -0.57029802295406395,
          -0.51711033221634062, 1.461215285458537, 0.68744213456615511 },
        { -0.37620662191246645, -0.93003780128906355, 0.17286710561883312,
          0.16489109711487271, -0.9122315033831131, -1.998945497209188 },
        { -0.37050945728724538, -0.47267075872158126, 0.6660378505639013,
          0.61899166422181606, -1.3941458992246909, -1.5507358214105131 },
        { 0.031787905717400866, -0.043242386401965982, 0.10339068360544812,
          0.46974082116632188, -0.036990510452945033, -0.53599104195964842 },
        { -0.86086203556594842, -0.050393984818838389, 0.20594413960721902,
          0.99912654358977404, -1.89259555055565, -1.0654101414820663 },
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof c / sizeof c[0]; i++) {
        vec2 a = V(c[i][0], c[i][1]), b = V(c[i][2], c[i][3]), d = V(c[i][4], c[i][5]);
        double dl = (a.x - d.x) * (b.y - d.y), dr = (a.y - d.y) * (b.x - d.x);
        double det = dl - dr, ratio = fabs(det) / ((fabs(dl) + fabs(dr)) * 0x1p-53);
        int ok, want = orient_dyadic(a, b, d, &ok);
        if (!ok)
            want = geom_orient_ref(a, b, d);
        assert_true(ratio > 1.5 && ratio < 3.0);
        assert_int_not_equal((det > 0) - (det < 0), want);   /* naive is wrong */
        assert_int_not_equal(want, 0);
        check_orient_symmetries(a, b, d, want);
    }
}

/* Overflow and underflow of the naive formula. */
static void test_orient_extremes(void **state)
{
    const double M = DBL_MAX, t = 0x1p-1074;
    (void)state;
    /* differences overflow: the line y = x across the whole range */
    assert_int_equal(geom_orient(V(M, M), V(-M, -M), V(0, t)), -1);
    assert_int_equal(geom_orient(V(M, M), V(-M, -M), V(0, -t)), 1);
    assert_int_equal(geom_orient(V(M, M), V(-M, -M), V(0, 0)), 0);
    assert_int_equal(geom_orient(V(M, M), V(-M, -M), V(t, t)), 0);
    assert_int_equal(geom_orient(V(-M, M), V(M, -M), V(M, M)), 1);
    /* subnormals only: products underflow to 0 in the naive formula */
    assert_int_equal(geom_orient(V(0, 0), V(3 * t, t), V(6 * t, 2 * t)), 0);
    assert_int_equal(geom_orient(V(0, 0), V(3 * t, t), V(6 * t, 3 * t)), 1);
    assert_int_equal(geom_orient(V(0, 0), V(3 * t, t), V(6 * t, t)), -1);
    assert_int_equal(geom_orient(V(t, t), V(2 * t, 2 * t), V(3 * t, 3 * t)), 0);
    /* huge and tiny together */
    assert_int_equal(geom_orient(V(0, 0), V(0x1p1000, 0), V(0, t)), 1);
    assert_int_equal(geom_orient(V(0, 0), V(0x1p1000, 0), V(-0x1p1000, t)), 1);
    assert_int_equal(geom_orient(V(0, 0), V(0x1p1000, t), V(-0x1p1000, -t)), 0);
    assert_int_equal(geom_orient(V(0, 0), V(0x1p1000, t), V(-0x1p1000, 0)), 1);
    assert_int_equal(geom_orient(V(0, 0), V(0x1p1000, t), V(-0x1p1000, -2 * t)), -1);
    assert_int_equal(geom_orient(V(1e300, 1e-300), V(-1e300, -1e-300), V(0, 0)),
                     geom_orient_ref(V(1e300, 1e-300), V(-1e300, -1e-300), V(0, 0)));
    /* naive evaluation of this one is NaN */
    check_orient_symmetries(V(M, M), V(-M, -M), V(0, t), -1);
    check_orient_symmetries(V(0, 0), V(3 * t, t), V(6 * t, 3 * t), 1);
    /* a line of slope 1/3 with coordinates near 2^600: exact zero */
    {
        double s = 0x1p600;
        assert_int_equal(geom_orient(V(0, 0), V(3 * s, s), V(-6 * s, -2 * s)), 0);
        assert_int_equal(geom_orient(V(s, s), V(4 * s, 2 * s),
                                     V(-5 * s, nextafter(-s, 0))), 1);
    }
}

/* ---- segments ------------------------------------------------------------ */

/* All 8 equivalent argument orders give the same answer. */
static void check_meet(vec2 a, vec2 b, vec2 c, vec2 d, int want)
{
    assert_int_equal(geom_seg_meet(a, b, c, d), want);
    assert_int_equal(geom_seg_meet(b, a, c, d), want);
    assert_int_equal(geom_seg_meet(a, b, d, c), want);
    assert_int_equal(geom_seg_meet(b, a, d, c), want);
    assert_int_equal(geom_seg_meet(c, d, a, b), want);
    assert_int_equal(geom_seg_meet(d, c, a, b), want);
    assert_int_equal(geom_seg_meet(c, d, b, a), want);
    assert_int_equal(geom_seg_meet(d, c, b, a), want);
}

static void test_seg_meet_cases(void **state)
{
    (void)state;
    check_meet(V(0, 0), V(2, 2), V(0, 2), V(2, 0), GEOM_SEG_CROSS);
    check_meet(V(0, 0), V(4, 0), V(2, 0), V(2, 3), GEOM_SEG_TOUCH);  /* T */
    check_meet(V(0, 0), V(4, 0), V(2, -1), V(2, 3), GEOM_SEG_CROSS);
    check_meet(V(0, 0), V(4, 0), V(4, 0), V(5, 3), GEOM_SEG_TOUCH);  /* shared end */
    check_meet(V(0, 0), V(4, 0), V(2, 0), V(6, 0), GEOM_SEG_OVERLAP);
    check_meet(V(0, 0), V(4, 0), V(1, 0), V(3, 0), GEOM_SEG_OVERLAP); /* inside */
    check_meet(V(0, 0), V(4, 0), V(0, 0), V(4, 0), GEOM_SEG_OVERLAP); /* same */
    check_meet(V(0, 0), V(4, 0), V(4, 0), V(6, 0), GEOM_SEG_TOUCH);   /* end to end */
    check_meet(V(0, 0), V(4, 0), V(5, 0), V(6, 0), GEOM_SEG_DISJOINT); /* collinear gap */
    check_meet(V(0, 0), V(0, 4), V(0, 5), V(0, 6), GEOM_SEG_DISJOINT); /* vertical */
    check_meet(V(0, 0), V(0, 4), V(0, 3), V(0, 6), GEOM_SEG_OVERLAP);
    check_meet(V(0, 0), V(3, 1), V(6, 2), V(9, 3), GEOM_SEG_DISJOINT); /* slanted */
    check_meet(V(0, 0), V(3, 1), V(3, 1), V(9, 3), GEOM_SEG_TOUCH);
    check_meet(V(0, 0), V(4, 0), V(0, 1), V(4, 1), GEOM_SEG_DISJOINT); /* parallel */
    check_meet(V(0, 0), V(4, 0), V(5, -1), V(5, 1), GEOM_SEG_DISJOINT); /* line hit */
    check_meet(V(0, 0), V(4, 4), V(1, 0), V(5, 4), GEOM_SEG_DISJOINT);
    /* degenerate (point) segments */
    check_meet(V(1, 1), V(1, 1), V(0, 0), V(2, 2), GEOM_SEG_TOUCH);
    check_meet(V(1, 1), V(1, 1), V(0, 0), V(2, 3), GEOM_SEG_DISJOINT);
    check_meet(V(3, 3), V(3, 3), V(0, 0), V(2, 2), GEOM_SEG_DISJOINT);
    check_meet(V(1, 1), V(1, 1), V(1, 1), V(1, 1), GEOM_SEG_TOUCH);
    check_meet(V(1, 1), V(1, 1), V(1, 2), V(1, 2), GEOM_SEG_DISJOINT);
    /* one ulp decides */
    {
        double y = 1.0 / 3.0;   /* the line from (0,0) to (3,1) at x = 1 */
        vec2 a = V(0, 0), b = V(3, 1);
        int at = geom_orient(a, b, V(1, y));
        int above = geom_orient(a, b, V(1, nextafter(y, 1)));
        int below = geom_orient(a, b, V(1, nextafter(y, 0)));
        assert_int_equal(at, -1);       /* 1/3 rounds down: just below */
        assert_int_equal(above, 1);
        assert_int_equal(below, -1);
        check_meet(a, b, V(1, nextafter(y, 1)), V(1, 5), GEOM_SEG_DISJOINT);
        check_meet(a, b, V(1, y), V(1, 5), GEOM_SEG_CROSS);
        check_meet(V(0, 0), V(4, 4), V(2, nextafter(2.0, 3)), V(2, 5), GEOM_SEG_DISJOINT);
        check_meet(V(0, 0), V(4, 4), V(2, 2), V(2, 5), GEOM_SEG_TOUCH);
    }
}

/* Segment meeting classified with __int128 orientations and integer
 * interval arithmetic, written apart from geom's own code.
 * P: ax ay bx by cx cy dx dy. */
static int brute_meet(const int64_t *P)
{
    int64_t ax = P[0], ay = P[1], bx = P[2], by = P[3];
    int64_t cx = P[4], cy = P[5], dx = P[6], dy = P[7];
    int64_t x[3], y[3];
    int o1, o2, o3, o4;
    int ab_pt = ax == bx && ay == by, cd_pt = cx == dx && cy == dy;
    if (ab_pt && cd_pt)
        return ax == cx && ay == cy ? GEOM_SEG_TOUCH : GEOM_SEG_DISJOINT;
    x[0] = ax; y[0] = ay; x[1] = bx; y[1] = by; x[2] = cx; y[2] = cy;
    o1 = orient_int(x, y);
    x[2] = dx; y[2] = dy;
    o2 = orient_int(x, y);
    x[0] = cx; y[0] = cy; x[1] = dx; y[1] = dy; x[2] = ax; y[2] = ay;
    o3 = orient_int(x, y);
    x[2] = bx; y[2] = by;
    o4 = orient_int(x, y);
    if (ab_pt || cd_pt) {
        /* a point p on segment st: collinear and within the box */
        int64_t px = ab_pt ? ax : cx, py = ab_pt ? ay : cy;
        int64_t sx = ab_pt ? cx : ax, sy = ab_pt ? cy : ay;
        int64_t tx = ab_pt ? dx : bx, ty = ab_pt ? dy : by;
        int col = ab_pt ? o3 == 0 : o1 == 0;
        int inbox = px >= (sx < tx ? sx : tx) && px <= (sx < tx ? tx : sx) &&
                    py >= (sy < ty ? sy : ty) && py <= (sy < ty ? ty : sy);
        return col && inbox ? GEOM_SEG_TOUCH : GEOM_SEG_DISJOINT;
    }
    if (o1 == 0 && o2 == 0) {
        /* project on the axis along which ab is longer: on a line that
         * keeps the order of the points */
        int useX = (ax > bx ? ax - bx : bx - ax) >= (ay > by ? ay - by : by - ay);
        int64_t p0 = useX ? ax : ay, p1 = useX ? bx : by;
        int64_t q0 = useX ? cx : cy, q1 = useX ? dx : dy;
        int64_t lo1 = p0 < p1 ? p0 : p1, hi1 = p0 < p1 ? p1 : p0;
        int64_t lo2 = q0 < q1 ? q0 : q1, hi2 = q0 < q1 ? q1 : q0;
        int64_t lo = lo1 > lo2 ? lo1 : lo2, hi = hi1 < hi2 ? hi1 : hi2;
        return lo < hi ? GEOM_SEG_OVERLAP : lo == hi ? GEOM_SEG_TOUCH : GEOM_SEG_DISJOINT;
    }
    if (o1 * o2 > 0 || o3 * o4 > 0)
        return GEOM_SEG_DISJOINT;
    return (o1 == 0 || o2 == 0 || o3 == 0 || o4 == 0) ? GEOM_SEG_TOUCH : GEOM_SEG_CROSS;
}

/* Every configuration of 4 points with coordinates in 0..3 (2^16 of them),
 * as given and moved far from the origin. */
static void test_seg_meet_exhaustive_grid(void **state)
{
    int64_t P[8];
    uint32_t code, n = 1u << 16;   /* 8 coordinates of 2 bits */
    int seen[4] = { 0, 0, 0, 0 };
    (void)state;
    for (code = 0; code < n; code++) {
        int k, want, got;
        for (k = 0; k < 8; k++)
            P[k] = (code >> (2 * k)) & 3;
        want = brute_meet(P);
        got = geom_seg_meet(V((double)P[0], (double)P[1]), V((double)P[2], (double)P[3]),
                            V((double)P[4], (double)P[5]), V((double)P[6], (double)P[7]));
        assert_int_equal(got, want);
        /* a big offset with exact differences changes nothing */
        got = geom_seg_meet(V(P[0] + 0x1p40, P[1] - 0x1p41), V(P[2] + 0x1p40, P[3] - 0x1p41),
                            V(P[4] + 0x1p40, P[5] - 0x1p41), V(P[6] + 0x1p40, P[7] - 0x1p41));
        assert_int_equal(got, want);
        seen[want]++;
    }
    assert_true(seen[0] > 0 && seen[1] > 0 && seen[2] > 0 && seen[3] > 0);
}

/* ---- point in ring --------------------------------------------------------- */

static void reverse_ring(vec2 *p, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n / 2; i++) {
        vec2 t = p[i];
        p[i] = p[n - 1 - i];
        p[n - 1 - i] = t;
    }
}

/* Checks q against the ring in both orientations and every starting vertex. */
static void check_pir(vec2 q, const vec2 *ring, uint32_t n, int want)
{
    vec2 buf[16];
    uint32_t s, i;
    assert_true(n <= 16);
    for (s = 0; s < n; s++) {
        for (i = 0; i < n; i++)
            buf[i] = ring[(s + i) % n];
        assert_int_equal(geom_point_in_ring(q, buf, n), want);
        reverse_ring(buf, n);
        assert_int_equal(geom_point_in_ring(q, buf, n), want);
    }
}

static void test_point_in_ring_cases(void **state)
{
    const vec2 sq[4] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 } };
    const vec2 dia[4] = { { 2, 0 }, { 4, 2 }, { 2, 4 }, { 0, 2 } };
    /* a notch whose tip (3,2) touches the ray from (1,2) */
    const vec2 notch[7] = { { 0, 0 }, { 6, 0 }, { 6, 4 }, { 4, 4 },
                            { 3, 2 }, { 2, 4 }, { 0, 4 } };
    (void)state;
    check_pir(V(2, 2), sq, 4, GEOM_INSIDE);
    check_pir(V(0, 0), sq, 4, GEOM_ON_BOUNDARY);      /* vertex */
    check_pir(V(4, 4), sq, 4, GEOM_ON_BOUNDARY);
    check_pir(V(2, 0), sq, 4, GEOM_ON_BOUNDARY);      /* edges */
    check_pir(V(4, 1), sq, 4, GEOM_ON_BOUNDARY);
    check_pir(V(2, 4), sq, 4, GEOM_ON_BOUNDARY);
    check_pir(V(0, 3), sq, 4, GEOM_ON_BOUNDARY);
    check_pir(V(5, 0), sq, 4, GEOM_OUTSIDE);          /* edge extensions */
    check_pir(V(-1, 0), sq, 4, GEOM_OUTSIDE);
    check_pir(V(-1, 4), sq, 4, GEOM_OUTSIDE);
    check_pir(V(0, 5), sq, 4, GEOM_OUTSIDE);
    check_pir(V(4, -1), sq, 4, GEOM_OUTSIDE);
    check_pir(V(-1, 2), sq, 4, GEOM_OUTSIDE);
    check_pir(V(0x1p-1074, 2), sq, 4, GEOM_INSIDE);
    check_pir(V(-0x1p-1074, 2), sq, 4, GEOM_OUTSIDE);
    check_pir(V(2, nextafter(4, 5)), sq, 4, GEOM_OUTSIDE);
    check_pir(V(2, nextafter(4, 0)), sq, 4, GEOM_INSIDE);

    check_pir(V(-1, 2), dia, 4, GEOM_OUTSIDE);        /* ray through 2 vertices */
    check_pir(V(1, 2), dia, 4, GEOM_INSIDE);          /* ray through 1 vertex */
    check_pir(V(3, 2), dia, 4, GEOM_INSIDE);
    check_pir(V(5, 2), dia, 4, GEOM_OUTSIDE);
    check_pir(V(0, 2), dia, 4, GEOM_ON_BOUNDARY);
    check_pir(V(1, 1), dia, 4, GEOM_ON_BOUNDARY);
    check_pir(V(3, 3), dia, 4, GEOM_ON_BOUNDARY);
    check_pir(V(-1, 4), dia, 4, GEOM_OUTSIDE);        /* ray through top vertex */
    check_pir(V(-1, 0), dia, 4, GEOM_OUTSIDE);        /* ray through bottom vertex */
    check_pir(V(3, 4), dia, 4, GEOM_OUTSIDE);         /* extension of nothing */
    check_pir(V(5, -1), dia, 4, GEOM_OUTSIDE);        /* extension of an edge */

    check_pir(V(1, 2), notch, 7, GEOM_INSIDE);
    check_pir(V(5, 2), notch, 7, GEOM_INSIDE);
    check_pir(V(3, 2), notch, 7, GEOM_ON_BOUNDARY);
    check_pir(V(3, 3), notch, 7, GEOM_OUTSIDE);
    check_pir(V(2.5, 3), notch, 7, GEOM_ON_BOUNDARY);
    check_pir(V(3, 4), notch, 7, GEOM_OUTSIDE);       /* between the notch corners */
    check_pir(V(-1, 4), notch, 7, GEOM_OUTSIDE);      /* ray along top edges */
    check_pir(V(-1, 2), notch, 7, GEOM_OUTSIDE);
    check_pir(V(5, 4), notch, 7, GEOM_ON_BOUNDARY);
    check_pir(V(1, 0), notch, 7, GEOM_ON_BOUNDARY);
    check_pir(V(7, 0), notch, 7, GEOM_OUTSIDE);

    /* degenerate rings */
    assert_int_equal(geom_point_in_ring(V(0, 0), sq, 0), GEOM_OUTSIDE);
    assert_int_equal(geom_point_in_ring(V(0, 0), sq, 1), GEOM_ON_BOUNDARY);
    assert_int_equal(geom_point_in_ring(V(2, 0), sq, 2), GEOM_ON_BOUNDARY);
    assert_int_equal(geom_point_in_ring(V(2, 1), sq, 2), GEOM_OUTSIDE);
}

/* The octagon with integer vertices against half-plane tests in integers,
 * on every point of a quarter-integer grid around it; and an L shape against
 * its two rectangles. */
static void test_point_in_ring_grid(void **state)
{
    const vec2 oct[8] = { { 3, 0 }, { 7, 0 }, { 10, 3 }, { 10, 7 },
                          { 7, 10 }, { 3, 10 }, { 0, 7 }, { 0, 3 } };
    const vec2 ell[6] = { { 0, 0 }, { 6, 0 }, { 6, 2 }, { 2, 2 }, { 2, 6 }, { 0, 6 } };
    int i, j, k, counts[3] = { 0, 0, 0 };
    (void)state;
    for (i = -8; i <= 48; i++) {
        for (j = -8; j <= 48; j++) {
            /* q = (i/4, j/4); half-planes in units of 1/4 */
            int64_t qx = i, qy = j, neg = 0, zero = 0, want;
            vec2 q = V(i / 4.0, j / 4.0);
            for (k = 0; k < 8; k++) {
                int64_t x[3], y[3];
                int o;
                x[0] = (int64_t)oct[k].x * 4;
                y[0] = (int64_t)oct[k].y * 4;
                x[1] = (int64_t)oct[(k + 1) % 8].x * 4;
                y[1] = (int64_t)oct[(k + 1) % 8].y * 4;
                x[2] = qx;
                y[2] = qy;
                o = orient_int(x, y);
                neg += o < 0;
                zero += o == 0;
            }
            want = neg ? GEOM_OUTSIDE : zero ? GEOM_ON_BOUNDARY : GEOM_INSIDE;
            assert_int_equal(geom_point_in_ring(q, oct, 8), (int)want);
            counts[want]++;
            {
                /* L = [0,6]x[0,2] union [0,2]x[0,6] */
                double x = q.x, y = q.y;
                int inA = x > 0 && x < 6 && y > 0 && y < 2;
                int inB = x > 0 && x < 2 && y > 0 && y < 6;
                int inJ = x > 0 && x < 2 && y >= 2 && y <= 2; /* the shared side */
                int clA = x >= 0 && x <= 6 && y >= 0 && y <= 2;
                int clB = x >= 0 && x <= 2 && y >= 0 && y <= 6;
                int w = (inA || inB || inJ) ? GEOM_INSIDE
                        : (clA || clB) ? GEOM_ON_BOUNDARY : GEOM_OUTSIDE;
                assert_int_equal(geom_point_in_ring(q, ell, 6), w);
            }
        }
    }
    assert_true(counts[0] > 100 && counts[1] > 100 && counts[2] > 20);
}

/* Random points close to the edges of random triangles, compared with the
 * classification by three exact orientations. */
static void test_point_in_ring_near_edges(void **state)
{
    rng r = { 99 };
    int i, counts[3] = { 0, 0, 0 };
    (void)state;
    for (i = 0; i < 50000; i++) {
        vec2 t[3], q;
        int o[3], k, want, e = (int)rng_below(&r, 3), n;
        double s;
        for (k = 0; k < 3; k++)
            t[k] = V(rng_unit(&r) * 100, rng_unit(&r) * 100);
        if (geom_orient(t[0], t[1], t[2]) == 0)
            continue;
        s = rng_unit(&r);
        q = V(t[e].x + s * (t[(e + 1) % 3].x - t[e].x),
              t[e].y + s * (t[(e + 1) % 3].y - t[e].y));
        n = (int)rng_below(&r, 7) - 3;
        for (k = 0; k < (n < 0 ? -n : n); k++)
            q.x = nextafter(q.x, n < 0 ? -1.0 : 200.0);
        if (rng_below(&r, 8) == 0)
            q = t[e];   /* exactly a vertex */
        for (k = 0; k < 3; k++)
            o[k] = geom_orient_ref(t[k], t[(k + 1) % 3], q);
        if (geom_orient(t[0], t[1], t[2]) < 0)
            for (k = 0; k < 3; k++)
                o[k] = -o[k];
        want = (o[0] < 0 || o[1] < 0 || o[2] < 0) ? GEOM_OUTSIDE
               : (o[0] == 0 || o[1] == 0 || o[2] == 0) ? GEOM_ON_BOUNDARY : GEOM_INSIDE;
        assert_int_equal(geom_point_in_ring(q, t, 3), want);
        counts[want]++;
    }
    assert_true(counts[0] > 1000 && counts[1] > 1000 && counts[2] > 1000);
}

/* ---- simple rings ---------------------------------------------------------- */

typedef struct arena_fx {
    void *mem;
    arena a;
} arena_fx;

static int arena_setup(void **state)
{
    arena_fx *f = calloc(1, sizeof *f);
    size_t size = (size_t)64 << 20;
    if (!f)
        return -1;
    f->mem = malloc(size);
    if (!f->mem) {
        free(f);
        return -1;
    }
    arena_init(&f->a, f->mem, size);
    *state = f;
    return 0;
}

static int arena_teardown(void **state)
{
    arena_fx *f = *state;
    free(f->mem);
    free(f);
    return 0;
}

static int simple(arena *a, const vec2 *p, uint32_t n, uint32_t *ei, uint32_t *ej)
{
    size_t hi = a->hi, lo = a->lo;
    int r = geom_ring_is_simple(a, p, n, ei, ej);
    /* scratch is always given back */
    assert_true(a->hi == hi && a->lo == lo);
    assert_true(a->used[PLX_PART_SCRATCH] == 0);
    return r;
}

/* Brute force: 1 if simple, else 0 with the first offending pair. */
static int simple_brute(const vec2 *p, uint32_t n, uint32_t *bi, uint32_t *bj)
{
    uint32_t i, j;
    for (i = 0; i < n; i++) {
        for (j = i + 1; j < n; j++) {
            int adj = (i + 1) % n == j || (j + 1) % n == i;
            int m = geom_seg_meet(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]);
            if (adj ? m == GEOM_SEG_OVERLAP : m != GEOM_SEG_DISJOINT) {
                *bi = i;
                *bj = j;
                return 0;
            }
        }
    }
    return 1;
}

/* Is (i, j) an offending pair by the brute-force rule? */
static int pair_offends(const vec2 *p, uint32_t n, uint32_t i, uint32_t j)
{
    int adj = (i + 1) % n == j || (j + 1) % n == i;
    int m = geom_seg_meet(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]);
    if (i == j)   /* a zero-length edge */
        return p[i].x == p[(i + 1) % n].x && p[i].y == p[(i + 1) % n].y;
    return adj ? m == GEOM_SEG_OVERLAP : m != GEOM_SEG_DISJOINT;
}

/* Expects geom_ring_is_simple(a, arr) == want and, when 0, the pair wi, wj
 * (uses the arena 'a' of the calling test). */
#define CHECK_SIMPLE(arr, want, wi, wj) do {                                  \
        uint32_t ei_ = 99, ej_ = 99;                                          \
        int r_ = simple(a, arr, (uint32_t)(sizeof arr / sizeof arr[0]), &ei_, &ej_); \
        assert_int_equal(r_, want);                                           \
        if (!(want)) {                                                        \
            assert_int_equal(ei_, wi);                                        \
            assert_int_equal(ej_, wj);                                        \
        }                                                                     \
    } while (0)

static void test_ring_simple_cases(void **state)
{
    arena *a = &((arena_fx *)*state)->a;
    const vec2 square[] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 } };
    const vec2 tri[] = { { 0, 0 }, { 4, 0 }, { 0, 4 } };
    const vec2 tri_flat[] = { { 0, 0 }, { 4, 0 }, { 2, 0 } };
    const vec2 bowtie[] = { { 0, 0 }, { 2, 2 }, { 2, 0 }, { 0, 2 } };
    const vec2 spike[] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 4, 2 }, { 0, 4 } };
    /* vertex 3 touches the interior of edge 0 */
    const vec2 pinch[] = { { 0, 0 }, { 6, 0 }, { 6, 4 }, { 3, 0 }, { 0, 4 } };
    /* vertices 1 and 4 coincide: a figure of eight */
    const vec2 eight[] = { { 0, 0 }, { 2, 2 }, { 4, 0 }, { 4, 4 }, { 2, 2 }, { 0, 4 } };
    /* straight-through vertices are fine */
    const vec2 straight[] = { { 0, 0 }, { 1, 0 }, { 2, 0 }, { 2, 1 }, { 2, 2 }, { 0, 2 } };
    /* a non-adjacent edge runs along edge 0 */
    const vec2 along[] = { { 0, 0 }, { 6, 0 }, { 6, 3 }, { 5, 3 },
                           { 5, 0 }, { 1, 0 }, { 1, 3 }, { 0, 3 } };
    const vec2 flat[] = { { 0, 0 }, { 1, 0 }, { 2, 0 }, { 3, 0 } };
    const vec2 dup[] = { { 0, 0 }, { 1, 0 }, { 1, 0 }, { 0, 1 } };
    /* vertical edges and equal x everywhere, simple */
    const vec2 comb[] = { { 0, 0 }, { 5, 0 }, { 5, 3 }, { 4, 3 }, { 4, 1 },
                          { 3, 1 }, { 3, 3 }, { 2, 3 }, { 2, 1 }, { 1, 1 },
                          { 1, 3 }, { 0, 3 } };
    /* the same comb with one tooth leaning onto the next one */
    const vec2 comb_touch[] = { { 0, 0 }, { 5, 0 }, { 5, 3 }, { 4, 3 }, { 4, 1 },
                                { 3, 1 }, { 4, 3 - 1e-300 }, { 2, 3 }, { 2, 1 },
                                { 1, 1 }, { 1, 3 }, { 0, 3 } };
    /* a vertex one ulp above, on, and one ulp below another edge */
    vec2 near[] = { { 0, 0 }, { 3, 1 }, { 3, 3 }, { 1.5, 0.5 }, { 0, 3 } };
    /* an edge whose interior passes exactly through a vertex (not its
     * neighbour): the descent must see orientation 0 */
    const vec2 through[] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 2, 2 }, { 0, 4 }, { 0, 2 },
                             { 4, 2 } };
    uint32_t ei = 7, ej = 7;
    CHECK_SIMPLE(square, 1, 0, 0);
    CHECK_SIMPLE(tri, 1, 0, 0);
    CHECK_SIMPLE(tri_flat, 0, 0, 2);
    CHECK_SIMPLE(bowtie, 0, 0, 2);
    CHECK_SIMPLE(spike, 0, 1, 2);
    CHECK_SIMPLE(straight, 1, 0, 0);
    CHECK_SIMPLE(comb, 1, 0, 0);
    CHECK_SIMPLE(dup, 0, 1, 1);
    {
        int r = simple(a, pinch, 5, &ei, &ej);
        assert_int_equal(r, 0);
        assert_true(pair_offends(pinch, 5, ei, ej));
        assert_int_equal(ei, 0);
        r = simple(a, eight, 6, &ei, &ej);
        assert_int_equal(r, 0);
        assert_true(ei == 1 && ej == 4);
        assert_true(pair_offends(eight, 6, ei, ej));
        r = simple(a, along, 8, &ei, &ej);
        assert_int_equal(r, 0);
        assert_true(pair_offends(along, 8, ei, ej));
        r = simple(a, flat, 4, &ei, &ej);
        assert_int_equal(r, 0);
        assert_true(pair_offends(flat, 4, ei, ej));
        r = simple(a, comb_touch, 12, &ei, &ej);
        assert_int_equal(r, 0);
        assert_true(pair_offends(comb_touch, 12, ei, ej));
        r = simple(a, through, 7, &ei, &ej);
        assert_int_equal(r, 0);
        assert_true(pair_offends(through, 7, ei, ej));
    }
    near[3].y = nextafter(0.5, 1);
    assert_int_equal(simple(a, near, 5, &ei, &ej), 1);
    near[3].y = 0.5;
    assert_int_equal(simple(a, near, 5, &ei, &ej), 0);
    assert_int_equal(ei, 0);
    near[3].y = nextafter(0.5, 0);
    assert_int_equal(simple(a, near, 5, &ei, &ej), 0);
    assert_int_equal(ei, 0);
    /* n < 3 and non-finite input; NULL out-pointers are allowed */
    assert_int_equal(simple(a, square, 2, &ei, &ej), 0);
    assert_int_equal(simple(a, square, 0, NULL, NULL), 0);
    {
        vec2 bad[4] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 } };
        bad[2].x = NAN;
        assert_int_equal(simple(a, bad, 4, &ei, &ej), 0);
        assert_true(ei == 1 && ej == 2);
        bad[2].x = 4;
        bad[0].y = -INFINITY;
        assert_int_equal(simple(a, bad, 4, &ei, &ej), 0);
        assert_true(ei == 0 && ej == 3);
    }
}

/* Random small rings on a 5x5 lattice (plenty of collinear, vertical,
 * touching and overlapping edges), sometimes nudged by one ulp: the sweep
 * agrees with the all-pairs check, and every reported pair offends. */
static void test_ring_simple_vs_brute(void **state)
{
    arena *a = &((arena_fx *)*state)->a;
    rng r = { 2024 };
    int t, simple_count = 0, not_count = 0;
    for (t = 0; t < 300000; t++) {
        vec2 p[12];
        uint32_t n = 3 + (uint32_t)rng_below(&r, 9), k, ei = 0, ej = 0, bi = 0, bj = 0;
        int got, want, dup = 0;
        int nudge = t % 3 == 0;
        for (k = 0; k < n; k++) {
            p[k] = V((double)rng_below(&r, 5), (double)rng_below(&r, 5));
            if (nudge && rng_below(&r, 3) == 0)
                p[k].x = nextafter(p[k].x, rng_below(&r, 2) ? 9.0 : -9.0);
            if (nudge && rng_below(&r, 3) == 0)
                p[k].y = nextafter(p[k].y, rng_below(&r, 2) ? 9.0 : -9.0);
        }
        if (t % 5 == 0) {
            /* star-like: sort by angle around the centre for more simple rings */
            uint32_t i2, j2;
            for (i2 = 0; i2 < n; i2++)
                for (j2 = i2 + 1; j2 < n; j2++)
                    if (atan2(p[j2].y - 2, p[j2].x - 2) < atan2(p[i2].y - 2, p[i2].x - 2)) {
                        vec2 tmp = p[i2];
                        p[i2] = p[j2];
                        p[j2] = tmp;
                    }
        }
        for (k = 0; k < n; k++)
            dup |= p[k].x == p[(k + 1) % n].x && p[k].y == p[(k + 1) % n].y;
        if (dup)
            continue;
        want = simple_brute(p, n, &bi, &bj);
        got = simple(a, p, n, &ei, &ej);
        if (got != want) {
            fprintf(stderr, "ring %d (n %u): sweep %d brute %d (%u %u)\n", t, n, got,
                    want, bi, bj);
            for (k = 0; k < n; k++)
                fprintf(stderr, "  %.17g %.17g\n", p[k].x, p[k].y);
        }
        assert_int_equal(got, want);
        if (!got) {
            assert_true(ei < ej);
            assert_true(pair_offends(p, n, ei, ej));
            not_count++;
        } else {
            simple_count++;
        }
    }
    assert_true(simple_count > 10000 && not_count > 10000);
}

/* Bigger rings on a 21x21 lattice: points sorted by angle around a centre
 * off the lattice (often simple, with many collinear and vertical edges),
 * then 0 to 2 vertices moved to random lattice points. */
static void test_ring_simple_vs_brute_lattice(void **state)
{
    arena *a = &((arena_fx *)*state)->a;
    rng r = { 31337 };
    int t, counts[2] = { 0, 0 };
    vec2 p[160];
    double ang[160];
    for (t = 0; t < 1500; t++) {
        uint32_t n = 12 + (uint32_t)rng_below(&r, 140), k, j, moves, ei = 0, ej = 0, bi, bj;
        int got, want, dup = 0;
        unsigned char used[21 * 21];
        memset(used, 0, sizeof used);
        for (k = 0; k < n; k++) {   /* distinct lattice points */
            uint32_t cell;
            do
                cell = (uint32_t)rng_below(&r, 21 * 21);
            while (used[cell]);
            used[cell] = 1;
            p[k] = V((double)(cell % 21), (double)(cell / 21));
            ang[k] = atan2(p[k].y - 10.3, p[k].x - 10.6);
        }
        for (k = 1; k < n; k++) {   /* insertion sort by angle */
            for (j = k; j > 0 && ang[j] < ang[j - 1]; j--) {
                double ta = ang[j];
                vec2 tp = p[j];
                ang[j] = ang[j - 1];
                p[j] = p[j - 1];
                ang[j - 1] = ta;
                p[j - 1] = tp;
            }
        }
        moves = (uint32_t)rng_below(&r, 3);
        for (k = 0; k < moves; k++)
            p[rng_below(&r, n)] = V((double)rng_below(&r, 21), (double)rng_below(&r, 21));
        for (k = 0; k < n; k++)
            dup |= p[k].x == p[(k + 1) % n].x && p[k].y == p[(k + 1) % n].y;
        if (dup)
            continue;
        want = simple_brute(p, n, &bi, &bj);
        got = simple(a, p, n, &ei, &ej);
        assert_int_equal(got, want);
        if (!got)
            assert_true(pair_offends(p, n, ei, ej));
        counts[got]++;
    }
    fprintf(stderr, "    lattice rings: %d simple, %d not\n", counts[1], counts[0]);
    assert_true(counts[0] > 200 && counts[1] > 200);
}

static double now_s(void)
{
    return (double)clock() / CLOCKS_PER_SEC;
}

/* A star-shaped ring around the origin: vertex k at angle 2 pi k / n,
 * radius from rad(). Simple whatever the radii (each edge stays in its own
 * angular sector). */
static vec2 *star(uint32_t n, int wild, rng *r)
{
    vec2 *p = malloc(sizeof *p * n);
    uint32_t k;
    assert_non_null(p);
    for (k = 0; k < n; k++) {
        double th = 6.283185307179586 * k / n;
        double rad = wild ? 0.5 + 0.5 * rng_unit(r)
                          : 1.0 + 0.3 * sin(5 * th) + 1e-9 * rng_unit(r);
        p[k] = V(1000.0 + rad * cos(th), -2000.0 + rad * sin(th));
    }
    return p;
}

static void test_ring_simple_big(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    arena *a = &((arena_fx *)*state)->a;
    const uint32_t n = 1000000;
    rng r = { 5 };
    vec2 *p = star(n, 0, &r), *q;
    uint32_t ei = 0, ej = 0;
    double t0 = now_s(), t1;
    int res = simple(a, p, n, &ei, &ej);
    t1 = now_s() - t0;
    fprintf(stderr, "    10^6-vertex star: %.3f s\n", t1);
    assert_int_equal(res, 1);
    /* memory: 16 bytes per vertex, released */
    assert_true(a->peak[PLX_PART_SCRATCH] >= (size_t)16 * n);

    /* move one vertex across the ring: only its two edges can offend */
    p[n / 2] = V(1000.0 + 2.0, -2000.0 + 1e-3);
    res = simple(a, p, n, &ei, &ej);
    assert_int_equal(res, 0);
    assert_true(ei == n / 2 - 1 || ei == n / 2 || ej == n / 2 - 1 || ej == n / 2);
    {
        vec2 pa = p[ei], pb = p[(ei + 1) % n], pc = p[ej], pd = p[(ej + 1) % n];
        assert_int_not_equal(geom_seg_meet(pa, pb, pc, pd), GEOM_SEG_DISJOINT);
    }
    /* put it back, then onto vertex n/2 + 2: edges n/2 and n/2 + 1 fold */
    p[n / 2] = p[n / 2 + 2];
    res = simple(a, p, n, &ei, &ej);
    assert_int_equal(res, 0);
    assert_true(ei == n / 2 && ej == n / 2 + 1);
    assert_true(pair_offends(p, n, ei, ej));
    free(p);

    /* long radial edges: the sweep status holds ~10^5 edges at a time */
    q = star(n, 1, &r);
    t0 = now_s();
    res = simple(a, q, n, &ei, &ej);
    t1 = now_s() - t0;
    fprintf(stderr, "    10^6-vertex spiky star: %.3f s\n", t1);
    assert_int_equal(res, 1);
    free(q);
}

/* A rectilinear spiral path (legs 2, 2, 4, 4, 6, 6, ... turning left, so
 * parallel legs are 2 apart) thickened by d on each side: simple for
 * d < 1, touching for d = 1. Long nested edges in every direction. */
static uint32_t spiral(uint32_t legs, double d, vec2 *out)
{
    static const double nx[4] = { 0, -1, 0, 1 }, ny[4] = { 1, 0, -1, 0 };
    static const double dx[4] = { 1, 0, -1, 0 }, dy[4] = { 0, 1, 0, -1 };
    uint32_t k, m = 0;
    vec2 c = V(0, 0);
    vec2 *left = out, *right = out + legs + 1;
    left[0] = V(c.x + d * nx[0], c.y + d * ny[0]);
    right[0] = V(c.x - d * nx[0], c.y - d * ny[0]);
    for (k = 0; k < legs; k++) {
        double len = 2.0 * (k / 2 + 1);
        double ox, oy;
        c = V(c.x + len * dx[k % 4], c.y + len * dy[k % 4]);
        if (k + 1 < legs) {
            ox = d * (nx[k % 4] + nx[(k + 1) % 4]);
            oy = d * (ny[k % 4] + ny[(k + 1) % 4]);
        } else {
            ox = d * nx[k % 4];
            oy = d * ny[k % 4];
        }
        left[k + 1] = V(c.x + ox, c.y + oy);
        right[k + 1] = V(c.x - ox, c.y - oy);
    }
    /* ring: left side forwards, then right side backwards */
    for (k = 0; k < (legs + 1) / 2; k++) {
        vec2 t = right[k];
        right[k] = right[legs - k];
        right[legs - k] = t;
    }
    m = 2 * (legs + 1);
    return m;
}

static void test_ring_simple_spiral(void **state)
{
    arena *a = &((arena_fx *)*state)->a;
    const uint32_t legs = 20000;
    vec2 *p = malloc(sizeof *p * (2 * (size_t)legs + 2));
    vec2 sp[2 * 41 + 2];
    uint32_t n, m, ei, ej, bi, bj, k;
    double t0;
    int res, want, i;
    static const double ds[4] = { 0.5, 0.999, 1.0, 1.25 };
    assert_non_null(p);
    /* small spirals: sweep agrees with brute force */
    for (i = 0; i < 4; i++) {
        for (m = 1; m <= 41; m += 4) {
            uint32_t cnt = spiral(m, ds[i], sp);
            want = simple_brute(sp, cnt, &bi, &bj);
            assert_int_equal(simple(a, sp, cnt, &ei, &ej), want);
            if (m >= 5)
                assert_int_equal(want, ds[i] < 1.0);
            if (!want)
                assert_true(pair_offends(sp, cnt, ei, ej));
        }
    }
    /* a big one: 40002 vertices, edges up to 20000 long */
    n = spiral(legs, 0.5, p);
    t0 = now_s();
    res = simple(a, p, n, &ei, &ej);
    fprintf(stderr, "    %u-vertex spiral: %.3f s\n", n, now_s() - t0);
    assert_int_equal(res, 1);
    for (k = 0; k < n; k++)
        p[k].x = -p[k].x;   /* mirrored: same answer */
    assert_int_equal(simple(a, p, n, &ei, &ej), 1);
    n = spiral(legs, 1.0, p);
    assert_int_equal(simple(a, p, n, &ei, &ej), 0);
    assert_true(pair_offends(p, n, ei, ej));
    free(p);
}

/* Scratch exhaustion: -1 and nothing kept; fault injection on every request
 * until the call succeeds. */
static void test_ring_simple_scratch(void **state)
{
    const vec2 square[] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 } };
    const vec2 bowtie[] = { { 0, 0 }, { 2, 2 }, { 2, 0 }, { 0, 2 } };
    const vec2 spike[] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 4, 2 }, { 0, 4 } };
    unsigned char mem[256];
    arena a;
    uint32_t ei, ej;
    uint64_t k;
    int r;
    (void)state;
    /* too small a block */
    arena_init(&a, mem, 48);
    assert_int_equal(simple(&a, square, 4, &ei, &ej), -1);
    assert_int_equal(simple(&a, bowtie, 4, &ei, &ej), -1);
    /* a cheap check needs no scratch */
    assert_int_equal(simple(&a, spike, 5, &ei, &ej), 0);
    /* big enough */
    arena_init(&a, mem, sizeof mem);
    assert_int_equal(simple(&a, square, 4, &ei, &ej), 1);
    assert_int_equal(simple(&a, bowtie, 4, &ei, &ej), 0);
    /* part budget */
    a.budget[PLX_PART_SCRATCH] = 16;
    assert_int_equal(simple(&a, square, 4, &ei, &ej), -1);
    a.budget[PLX_PART_SCRATCH] = 0;
    /* with a persistent allocation below, it is left alone */
    assert_non_null(arena_alloc(&a, PLX_PART_SCENE, 40, 8));
    /* fault injection: fail the k-th request, k = 1, 2, ... */
    for (k = 1;; k++) {
        a.requests = 0;
        a.fail_at = k;
        r = simple(&a, square, 4, &ei, &ej);
        if (r != -1)
            break;
        assert_true(k < 10);
    }
    assert_int_equal(r, 1);
    assert_true(k == 2);   /* exactly one request */
    assert_int_equal(a.used[PLX_PART_SCENE], 40);
    a.fail_at = 0;
}

/* ---- distances and areas ---------------------------------------------------- */

static void test_seg_dist2(void **state)
{
    (void)state;
    assert_true(geom_seg_dist2(V(0, 0), V(2, 2), V(0, 2), V(2, 0)) == 0.0);
    assert_true(geom_seg_dist2(V(0, 0), V(4, 0), V(2, 0), V(2, 3)) == 0.0);
    assert_true(geom_seg_dist2(V(0, 0), V(4, 0), V(0, 3), V(4, 3)) == 9.0);
    assert_true(geom_seg_dist2(V(0, 0), V(4, 0), V(6, 0), V(9, 0)) == 4.0);
    assert_true(geom_seg_dist2(V(0, 0), V(4, 0), V(2, 1), V(2, 5)) == 1.0);
    assert_true(geom_seg_dist2(V(0, 0), V(4, 0), V(5, 1), V(5, 1)) == 2.0);
    assert_true(geom_seg_dist2(V(1, 1), V(1, 1), V(4, 5), V(4, 5)) == 25.0);
    assert_true(fabs(geom_seg_dist2(V(0, 0), V(4, 4), V(4, 0), V(3, 1)) - 2.0) < 1e-12);
    /* a touch one ulp away is not zero */
    assert_true(geom_seg_dist2(V(0, 0), V(4, 0), V(2, 1e-150), V(2, 3)) > 0.0);
    assert_true(geom_seg_dist2(V(0, 0), V(4, 0), V(2, 1e-150), V(2, 3)) < 1.0001e-300);
    /* below the smallest square, a touch-free pair may round to 0 */
    assert_true(geom_seg_meet(V(0, 0), V(4, 0), V(2, 0x1p-1074), V(2, 3)) ==
                GEOM_SEG_DISJOINT);
}

static void test_ring_area2(void **state)
{
    const vec2 sq[4] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 } };
    vec2 far[4], rev[4];
    int k;
    (void)state;
    assert_true(geom_ring_area2(sq, 4) == 32.0);
    for (k = 0; k < 4; k++) {
        far[k] = V(sq[k].x + 6.0e6, sq[k].y - 4.0e6);
        rev[k] = sq[3 - k];
    }
    assert_true(geom_ring_area2(rev, 4) == -32.0);
    assert_true(geom_ring_area2(far, 4) == 32.0);
    assert_true(geom_ring_area2(sq, 2) == 0.0);
    {
        const vec2 ell[6] = { { 0, 0 }, { 6, 0 }, { 6, 2 }, { 2, 2 }, { 2, 6 }, { 0, 6 } };
        assert_true(geom_ring_area2(ell, 6) == 2.0 * 20.0);
    }
}

/* ---- the bucket grid (base/bucketgrid.h) against brute force ------------ */

static double rnd_unit(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* Every item whose box meets query box q is listed in a cell of q's range
 * (brute force over all items), each cell's ids ascend, and a cell lists
 * only items whose boxes meet it. */
static void check_bucketgrid(const bucketgrid *g, const double *box, uint32_t n, const double q[4])
{
    uint32_t r[4], x, y, k, i;
    bucketgrid_range(g, q, r);
    for (i = 0; i < n; i++) {
        const double *b = box + 4 * (size_t)i;
        int meets = b[0] <= b[2] && !(b[2] < q[0] || b[0] > q[2] || b[3] < q[1] || b[1] > q[3]), found = 0;
        for (y = r[1]; y <= r[3] && !found; y++)
            for (x = r[0]; x <= r[2] && !found; x++)
                for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++)
                    found |= g->item[k] == i;
        if (meets)
            assert_true(found);
    }
    for (y = 0; y < g->ny; y++)
        for (x = 0; x < g->nx; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                const double *b = box + 4 * (size_t)g->item[k];
                uint32_t br[4];
                bucketgrid_range(g, b, br);
                assert_true(b[0] <= b[2]);
                assert_true(x >= br[0] && x <= br[2] && y >= br[1] && y <= br[3]);
                if (k > g->start[y * g->nx + x])
                    assert_true(g->item[k] > g->item[k - 1]);
            }
}

static void test_bucketgrid_vs_brute(void **state)
{
    static unsigned char block[1 << 20];
    double box[4 * 300], q[4];
    uint32_t n = 300, i, t;
    uint64_t seed = 7;
    arena a;
    bucketgrid g;
    (void)state;
    for (i = 0; i < n; i++) {
        double x = rnd_unit(&seed) * 100.0, y = rnd_unit(&seed) * 60.0;
        double w = rnd_unit(&seed) * 8.0, h = rnd_unit(&seed) * 8.0;
        box[4 * i] = x;
        box[4 * i + 1] = y;
        box[4 * i + 2] = i % 17 == 0 ? x - 1.0 : x + w; /* some empty boxes, left out */
        box[4 * i + 3] = y + h;
    }
    for (t = 0; t < 2; t++) {
        arena_init(&a, block, sizeof block);
        memset(&g, 0, sizeof g);
        bucketgrid_frame(&g, t ? 10.0 : 0.0, 0.0, t ? 3.7 : 10.0, t ? 20 : 11, t ? 12 : 7);
        assert_int_equal(bucketgrid_fill(&g, &a, t ? PLX_PART_LIT : PLX_PART_SCRATCH, 16, box, NULL, n), PLX_OK);
        for (i = 0; i < 200; i++) {
            q[0] = rnd_unit(&seed) * 140.0 - 20.0;
            q[1] = rnd_unit(&seed) * 100.0 - 20.0;
            q[2] = q[0] + rnd_unit(&seed) * 30.0;
            q[3] = q[1] + rnd_unit(&seed) * 30.0;
            check_bucketgrid(&g, box, n, q);
        }
    }
    /* points: each in exactly one cell, the clamped one */
    {
        vec2 p[50];
        arena_init(&a, block, sizeof block);
        for (i = 0; i < 50; i++) {
            p[i].x = rnd_unit(&seed) * 200.0 - 50.0;
            p[i].y = rnd_unit(&seed) * 200.0 - 50.0;
        }
        bucketgrid_frame(&g, 0.0, 0.0, 25.0, 4, 4);
        assert_int_equal(bucketgrid_fill(&g, &a, PLX_PART_SCRATCH, 16, NULL, p, 50), PLX_OK);
        assert_int_equal(g.start[16], 50);
        for (i = 0; i < 50; i++) {
            uint32_t c = bucketgrid_cell(&g, p[i].x, p[i].y), k, hits = 0;
            for (k = g.start[c]; k < g.start[c + 1]; k++)
                hits += g.item[k] == i;
            assert_int_equal(hits, 1);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bucketgrid_vs_brute),
        cmocka_unit_test(test_orient_basic),
        cmocka_unit_test(test_orient_random_vs_int128),
        cmocka_unit_test(test_orient_near_collinear),
        cmocka_unit_test(test_orient_classroom),
        cmocka_unit_test(test_orient_near_filter_bound),
        cmocka_unit_test(test_orient_extremes),
        cmocka_unit_test(test_seg_meet_cases),
        cmocka_unit_test(test_seg_meet_exhaustive_grid),
        cmocka_unit_test(test_point_in_ring_cases),
        cmocka_unit_test(test_point_in_ring_grid),
        cmocka_unit_test(test_point_in_ring_near_edges),
        cmocka_unit_test_setup_teardown(test_ring_simple_cases, arena_setup, arena_teardown),
        cmocka_unit_test_setup_teardown(test_ring_simple_vs_brute, arena_setup, arena_teardown),
        cmocka_unit_test_setup_teardown(test_ring_simple_vs_brute_lattice, arena_setup, arena_teardown),
        cmocka_unit_test_setup_teardown(test_ring_simple_big, arena_setup, arena_teardown),
        cmocka_unit_test_setup_teardown(test_ring_simple_spiral, arena_setup, arena_teardown),
        cmocka_unit_test(test_ring_simple_scratch),
        cmocka_unit_test(test_seg_dist2),
        cmocka_unit_test(test_ring_area2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
