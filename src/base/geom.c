/* geom: robust 2D predicates and ring utilities, and a 3D orthonormal basis (contracts in geom.h).
 *
 * Arithmetic requirements. The exact predicates below need IEEE 754 binary64
 * arithmetic with round-to-nearest-even, every operation rounded to double on
 * its own (FLT_EVAL_METHOD == 0: SSE2 on x86_64, never the x87 unit), and NO
 * contraction of a*b + c into a fused multiply-add: the error-free
 * transformations (two_sum, two_prod) and the filter's error bound assume
 * that each product and each sum is rounded separately. The Makefile
 * compiles with -ffp-contract=off for this reason; keep it.
 *
 * geom_orient is adaptive, in three stages plus a last resort:
 *   A. a double-precision evaluation with a proven error bound (the filter);
 *   B. if the coordinate differences are exact, the exact value of
 *      dx1*dy2 - dy1*dx2 as a 4-component expansion;
 *   C. otherwise the exact value of the 6-product expansion of the
 *      determinant as a 12-component expansion;
 *   R. coordinates so large or so small that B and C could overflow or lose
 *      bits to underflow go to a fixed-point big-integer evaluation, which is
 *      exact for every finite double (geom_orient_ref).
 * The method is that of Shewchuk's 1997 adaptive predicates; the code, the
 * bound and its proof are written for this project.
 */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <string.h>
#include "base/geom.h"

#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD != 0
#error "geom.c needs double arithmetic evaluated in double (FLT_EVAL_METHOD 0)"
#endif

/* ------------------------------------------------------------------------ */
/* Error-free transformations and expansions                                 */
/* ------------------------------------------------------------------------ */

/* x = fl(a + b) and y = (a + b) - x exactly (Knuth's two-sum: no condition on
 * the magnitudes; exact whenever a + b does not overflow, underflow included,
 * since a sum that lands in the subnormal range is exact). */
static void two_sum(double a, double b, double *x, double *y)
{
    double s = a + b;
    double bv = s - a;
    double av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

/* Veltkamp/Dekker split: a = hi + lo with hi, lo of at most 26 significant
 * bits each. 2^27 + 1 is the splitter for 53-bit significands. Needs
 * |a| < 2^995 so that the scaled value cannot overflow. */
static void split(double a, double *hi, double *lo)
{
    const double splitter = 134217729.0; /* 2^27 + 1 */
    double c = splitter * a;
    double big = c - a;
    *hi = c - big;
    *lo = a - *hi;
}

/* x = fl(a * b) and y = a*b - x exactly (Dekker's product). Exact when the
 * product does not overflow and the error term is representable, i.e. the
 * product of the two operands' quanta (weights of their last significant
 * bits) is at least 2^-1074; stage C's range check guarantees both. */
static void two_prod(double a, double b, double *x, double *y)
{
    double p = a * b, ah, al, bh, bl, e;
    split(a, &ah, &al);
    split(b, &bh, &bl);
    e = p - ah * bh;
    e -= al * bh;
    e -= ah * bl;
    *x = p;
    *y = al * bl - e;
}

/* Adds b to the expansion e[0..n): the components of e are nonoverlapping and
 * of increasing magnitude, zeros removed. The result keeps these properties
 * (the classical grow-expansion theorem, which relies on round-to-nearest
 * two_sum being exact) and has at most n + 1 components; written in place. */
static int grow(double *e, int n, double b)
{
    double q = b, h;
    int i, m = 0;
    for (i = 0; i < n; i++) {
        two_sum(q, e[i], &q, &h);
        if (h != 0.0)
            e[m++] = h;
    }
    if (q != 0.0)
        e[m++] = q;
    return m;
}

/* The sign of a nonoverlapping expansion is that of its largest component,
 * which is the last one. */
static int expansion_sign(const double *e, int n)
{
    if (n == 0)
        return 0;
    return e[n - 1] > 0.0 ? 1 : -1;
}

/* ------------------------------------------------------------------------ */
/* Last resort: fixed-point big integer, exact for all finite doubles        */
/* ------------------------------------------------------------------------ */

/* A finite double is m * 2^e with m an integer, |m| < 2^53 and
 * -1126 <= e <= 971 (frexp normalises subnormals too). A product of two is
 * below 2^106 * 2^(e1+e2) with -2252 <= e1+e2 <= 1942. Aligned on the
 * smallest exponent present, six such terms need at most
 * 4194 + 106 + 3 = 4303 bits plus a sign: 70 limbs of 64 bits (4480 bits),
 * held in two's complement. */
#define REF_LIMBS 70

static void ref_decompose(double v, uint64_t *mag, int *neg, int *ex)
{
    int e2 = 0;
    double f;
    if (v == 0.0) {
        *mag = 0;
        *neg = 0;
        *ex = 0;
        return;
    }
    f = frexp(v, &e2);             /* v = f * 2^e2, 0.5 <= |f| < 1 */
    *neg = f < 0.0;
    *mag = (uint64_t)ldexp(fabs(f), 53); /* exact: an integer below 2^53 */
    *ex = e2 - 53;
}

/* 53 x 53 -> 106-bit product, as hi:lo. */
static void ref_mul(uint64_t a, uint64_t b, uint64_t *lo, uint64_t *hi)
{
    uint64_t a0 = a & 0xffffffffu, a1 = a >> 32;
    uint64_t b0 = b & 0xffffffffu, b1 = b >> 32;
    uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    uint64_t mid = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu);
    *lo = (mid << 32) | (p00 & 0xffffffffu);
    *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

/* acc += (neg ? -1 : 1) * (hi:lo) * 2^shift, modulo 2^(64 * REF_LIMBS). */
static void ref_accumulate(uint64_t *acc, uint64_t lo, uint64_t hi,
                           unsigned shift, int neg)
{
    uint64_t w[3], carry = 0;
    unsigned q = shift / 64, r = shift % 64, i;
    w[0] = lo << r;
    w[1] = r ? (hi << r) | (lo >> (64 - r)) : hi;
    w[2] = r ? hi >> (64 - r) : 0;
    for (i = q; i < REF_LIMBS; i++) {
        uint64_t x, s, t, c1, c2;
        if (i - q >= 3 && carry == 0)
            break;
        x = i - q < 3 ? w[i - q] : 0;
        if (!neg) {
            s = acc[i] + x;
            c1 = s < x;
            t = s + carry;
            c2 = t < s;
        } else {
            s = acc[i] - x;
            c1 = acc[i] < x;
            t = s - carry;
            c2 = s < carry;
        }
        acc[i] = t;
        carry = c1 | c2;
    }
}

int geom_orient_ref(vec2 a, vec2 b, vec2 c)
{
    /* det = ax*by - ax*cy - bx*ay + bx*cy + cx*ay - cx*by */
    static const unsigned char tx[6] = {0, 0, 1, 1, 2, 2};
    static const unsigned char ty[6] = {1, 2, 0, 2, 0, 1};
    static const unsigned char tneg[6] = {0, 1, 1, 0, 0, 1};
    double xs[3], ys[3];
    uint64_t xm[3], ym[3], acc[REF_LIMBS];
    int xn[3], yn[3], xe[3], ye[3], k, base = INT_MAX;
    xs[0] = a.x; xs[1] = b.x; xs[2] = c.x;
    ys[0] = a.y; ys[1] = b.y; ys[2] = c.y;
    for (k = 0; k < 3; k++) {
        ref_decompose(xs[k], &xm[k], &xn[k], &xe[k]);
        ref_decompose(ys[k], &ym[k], &yn[k], &ye[k]);
    }
    for (k = 0; k < 6; k++) {
        int i = tx[k], j = ty[k];
        if (xm[i] != 0 && ym[j] != 0 && xe[i] + ye[j] < base)
            base = xe[i] + ye[j];
    }
    if (base == INT_MAX)
        return 0;
    memset(acc, 0, sizeof acc);
    for (k = 0; k < 6; k++) {
        int i = tx[k], j = ty[k];
        uint64_t lo, hi;
        if (xm[i] == 0 || ym[j] == 0)
            continue;
        ref_mul(xm[i], ym[j], &lo, &hi);
        ref_accumulate(acc, lo, hi, (unsigned)(xe[i] + ye[j] - base),
                       (xn[i] ^ yn[j] ^ tneg[k]) != 0);
    }
    if (acc[REF_LIMBS - 1] >> 63)
        return -1;
    for (k = 0; k < REF_LIMBS; k++)
        if (acc[k] != 0)
            return 1;
    return 0;
}

/* ------------------------------------------------------------------------ */
/* geom_orient                                                               */
/* ------------------------------------------------------------------------ */

/* Filter bound. Let u = 2^-53 and S = fl(|dl| + |dr|) where
 * dl = fl(fl(ax-cx) * fl(by-cy)), dr = fl(fl(ay-cy) * fl(bx-cx)) and
 * det = fl(dl - dr); D is the exact determinant L - R, with L, R the exact
 * products of the exact differences.
 * - A difference is (x - y)(1 + d), |d| <= u (a difference that falls in the
 *   subnormal range is exact). A product is xy(1 + d) + h with |d| <= u and
 *   |h| <= 2^-1075 (h only under gradual underflow). Hence
 *   dl = L(1 + t) + h1 with |t| <= g3 = 3u/(1 - 3u), |h1| <= 2^-1075, and
 *   |L| <= (|dl| + 2^-1075)/(1 - g3); the same for dr and R.
 * - |det - (dl - dr)| <= u|det| (round to nearest), so
 *   |det - D| <= u|det| + g3(|L| + |R|) + 2^-1074
 *             <= u|det| + 3u/(1-6u) (S/(1-u) + 2^-1074) + 2^-1074.
 * - When S >= 2^-900, 2^-1073 <= u^2 2^-67 S, and the right-hand side is
 *   below u|det| + (3u + 23u^2) S. The sign of det is then right as soon as
 *   (1 - u)|det| > (3u + 23u^2) S, i.e. |det| > (3u + 26u^2) S.
 * - The test computes B = fl(C S) with C = (3 + 64u)u, exact as written;
 *   B >= (1 - u) C S >= (3u + 60u^2) S, so |det| > B is sufficient.
 * - No overflow: S finite implies every intermediate is finite (an inf in a
 *   difference makes a product inf or NaN, so S is inf or NaN and the test
 *   fails). If dl - dr overflows, det is an infinity of the right sign. */
/* (The test itself is geom_orient_filter in geom.h, inline for hot loops.) */

/* Stages B and C are exact when every coordinate is 0 or has magnitude in
 * [2^-480, 2^480]: then every nonzero coordinate has quantum >= 2^-532, so do
 * the differences, and every product of two of them has quantum >= 2^-1064
 * >= 2^-1074 (error terms representable) and magnitude < 2^963 (no overflow,
 * splitter safe, sums of 12 terms below 2^967). */
static int in_expansion_range(double v)
{
    double m = fabs(v);
    return m == 0.0 || (m >= 0x1p-480 && m <= 0x1p480);
}

static int orient_exact(vec2 a, vec2 b, vec2 c)
{
    double e[12], s1, s1t, t1, t1t, s2, s2t, t2, t2t, x, y;
    int n;
    if (!(in_expansion_range(a.x) && in_expansion_range(a.y) &&
          in_expansion_range(b.x) && in_expansion_range(b.y) &&
          in_expansion_range(c.x) && in_expansion_range(c.y)))
        return geom_orient_ref(a, b, c);

    /* Stage B: D = s1*t1 - s2*t2 when all four differences are exact. */
    two_sum(a.x, -c.x, &s1, &s1t);
    two_sum(b.y, -c.y, &t1, &t1t);
    two_sum(a.y, -c.y, &s2, &s2t);
    two_sum(b.x, -c.x, &t2, &t2t);
    if (s1t == 0.0 && t1t == 0.0 && s2t == 0.0 && t2t == 0.0) {
        n = 0;
        two_prod(s1, t1, &x, &y);
        n = grow(e, n, y);
        n = grow(e, n, x);
        two_prod(s2, t2, &x, &y);
        n = grow(e, n, -y);
        n = grow(e, n, -x);
        return expansion_sign(e, n);
    }

    /* Stage C: D = ax*by - ax*cy - bx*ay + bx*cy + cx*ay - cx*by. */
    n = 0;
    two_prod(a.x, b.y, &x, &y);  n = grow(e, n, y);  n = grow(e, n, x);
    two_prod(a.x, c.y, &x, &y);  n = grow(e, n, -y); n = grow(e, n, -x);
    two_prod(b.x, a.y, &x, &y);  n = grow(e, n, -y); n = grow(e, n, -x);
    two_prod(b.x, c.y, &x, &y);  n = grow(e, n, y);  n = grow(e, n, x);
    two_prod(c.x, a.y, &x, &y);  n = grow(e, n, y);  n = grow(e, n, x);
    two_prod(c.x, b.y, &x, &y);  n = grow(e, n, -y); n = grow(e, n, -x);
    return expansion_sign(e, n);
}

int geom_orient(vec2 a, vec2 b, vec2 c)
{
    int o = geom_orient_filter((a.x - c.x) * (b.y - c.y), (a.y - c.y) * (b.x - c.x));
    return o ? o : orient_exact(a, b, c);
}

/* ------------------------------------------------------------------------ */
/* Segments and rings                                                        */
/* ------------------------------------------------------------------------ */

static int vec_eq(vec2 a, vec2 b)
{
    return a.x == b.x && a.y == b.y;
}

/* Lexicographic order (x, then y). On a line it is the order along the line,
 * and it is the order of the sweep in geom_ring_is_simple. */
static int lex_less(vec2 a, vec2 b)
{
    return a.x < b.x || (a.x == b.x && a.y < b.y);
}

/* q on the closed segment cd (c != d). */
static int on_segment(vec2 q, vec2 c, vec2 d)
{
    vec2 lo = lex_less(c, d) ? c : d, hi = lex_less(c, d) ? d : c;
    return geom_orient(c, d, q) == 0 && !lex_less(q, lo) && !lex_less(hi, q);
}

int geom_seg_meet(vec2 a, vec2 b, vec2 c, vec2 d)
{
    int o1, o2, o3, o4, ab_pt = vec_eq(a, b), cd_pt = vec_eq(c, d);
    if (ab_pt || cd_pt) {
        if (ab_pt && cd_pt)
            return vec_eq(a, c) ? GEOM_SEG_TOUCH : GEOM_SEG_DISJOINT;
        if (ab_pt)
            return on_segment(a, c, d) ? GEOM_SEG_TOUCH : GEOM_SEG_DISJOINT;
        return on_segment(c, a, b) ? GEOM_SEG_TOUCH : GEOM_SEG_DISJOINT;
    }
    o1 = geom_orient(a, b, c);
    o2 = geom_orient(a, b, d);
    if (o1 != 0 && o1 == o2)
        return GEOM_SEG_DISJOINT;
    if (o1 == 0 && o2 == 0) {
        /* All four collinear: compare the intervals along the line. */
        vec2 lo1 = lex_less(a, b) ? a : b, hi1 = lex_less(a, b) ? b : a;
        vec2 lo2 = lex_less(c, d) ? c : d, hi2 = lex_less(c, d) ? d : c;
        vec2 lo = lex_less(lo1, lo2) ? lo2 : lo1;
        vec2 hi = lex_less(hi1, hi2) ? hi1 : hi2;
        if (lex_less(lo, hi))
            return GEOM_SEG_OVERLAP;
        return vec_eq(lo, hi) ? GEOM_SEG_TOUCH : GEOM_SEG_DISJOINT;
    }
    o3 = geom_orient(c, d, a);
    o4 = geom_orient(c, d, b);
    if (o3 != 0 && o3 == o4)
        return GEOM_SEG_DISJOINT;
    /* Each segment now meets the other's line, and the lines are distinct:
     * they meet at one point, which is an endpoint iff some sign is 0. */
    if (o1 == 0 || o2 == 0 || o3 == 0 || o4 == 0)
        return GEOM_SEG_TOUCH;
    return GEOM_SEG_CROSS;
}

int geom_point_in_ring(vec2 q, const vec2 *p, uint32_t n)
{
    /* Winding number of the ring around q, counting signed crossings of the
     * ray from q towards +x with half-open edges: every non-horizontal edge
     * includes its lower end and excludes its upper end, and horizontal
     * edges never count. A ray through a vertex is thus counted once when
     * the ring crosses it there and zero or two times when the ring only
     * touches it. Points on the ring are found first and exactly. All
     * decisions are comparisons of coordinates and exact orientations. */
    long wn = 0;
    uint32_t k;
    for (k = 0; k < n; k++) {
        vec2 u = p[k], v = p[k + 1 == n ? 0 : k + 1];
        double ylo = u.y < v.y ? u.y : v.y, yhi = u.y < v.y ? v.y : u.y;
        int o;
        if (q.y < ylo || q.y > yhi)
            continue;
        if (q.x > u.x && q.x > v.x)
            continue;                        /* edge entirely left of q */
        if (u.y == v.y) {                    /* horizontal, at q's height */
            if (!(q.x < u.x && q.x < v.x))
                return GEOM_ON_BOUNDARY;     /* between its ends */
            continue;
        }
        o = geom_orient(u, v, q);
        if (o == 0)
            return GEOM_ON_BOUNDARY;         /* on the line, within y range */
        if (u.y <= q.y && q.y < v.y && o > 0)
            wn++;
        else if (v.y <= q.y && q.y < u.y && o < 0)
            wn--;
    }
    return wn != 0 ? GEOM_INSIDE : GEOM_OUTSIDE;
}

double geom_ring_area2(const vec2 *p, uint32_t n)
{
    /* Shoelace about p[0], which keeps the terms small for rings far from
     * the origin. */
    double s = 0.0;
    uint32_t k;
    if (n < 3)
        return 0.0;
    for (k = 1; k + 1 < n; k++) {
        double ux = p[k].x - p[0].x, uy = p[k].y - p[0].y;
        double vx = p[k + 1].x - p[0].x, vy = p[k + 1].y - p[0].y;
        s += ux * vy - uy * vx;
    }
    return s;
}

static double point_seg_dist2(vec2 q, vec2 a, vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y;
    double len2 = dx * dx + dy * dy;
    double t = 0.0, ex, ey;
    if (len2 > 0.0)
        t = ((q.x - a.x) * dx + (q.y - a.y) * dy) / len2;
    if (t <= 0.0) {
        ex = q.x - a.x;
        ey = q.y - a.y;
    } else if (t >= 1.0) {
        ex = q.x - b.x;
        ey = q.y - b.y;
    } else {
        ex = q.x - (a.x + t * dx);
        ey = q.y - (a.y + t * dy);
    }
    return ex * ex + ey * ey;
}

double geom_seg_dist2(vec2 a, vec2 b, vec2 c, vec2 d)
{
    double m, t;
    if (geom_seg_meet(a, b, c, d) != GEOM_SEG_DISJOINT)
        return 0.0;
    /* Disjoint closed segments: the minimum is reached at an endpoint. */
    m = point_seg_dist2(a, c, d);
    t = point_seg_dist2(b, c, d);
    if (t < m)
        m = t;
    t = point_seg_dist2(c, a, b);
    if (t < m)
        m = t;
    t = point_seg_dist2(d, a, b);
    if (t < m)
        m = t;
    return m;
}

/* ------------------------------------------------------------------------ */
/* geom_ring_is_simple: a Shamos-Hoey sweep with exact predicates            */
/* ------------------------------------------------------------------------ */

/* Plan.
 * 1. Linear checks: finite coordinates, no zero-length edge, and adjacent
 *    edges k-1, k meet only at vertex k (not collinear folding back).
 * 2. Sort the vertices lexicographically; two vertices at the same point
 *    (a pinch) make the ring not simple. From here on every point is the
 *    vertex of exactly two edges.
 * 3. Sweep the vertices in that order (a vertical line tilted infinitesimally,
 *    so vertical edges need no special case). Each edge has a lower end
 *    ('lo', lexicographically smaller) and an upper end. The status is a
 *    treap of the edges cut by the sweep, ordered bottom to top. At a vertex,
 *    edges ending there are removed first, then edges starting there are
 *    inserted. Every pair of edges that becomes neighbours in the status is
 *    tested with geom_seg_meet (pairs of adjacent edges excepted: step 1
 *    settled them).
 * Why it finds any meeting of non-adjacent edges: let q be the
 * lexicographically first point where two non-adjacent edges meet. Before q
 * the status order is consistent. The edges in the status just before q
 * whose closure contains q are contiguous in it; among k of them the k - 1
 * neighbour pairs were tested when they became neighbours, before q, and at
 * most one of them (the two edges of the vertex at q) is allowed. Otherwise
 * an offending pair involves an edge e starting at q and an edge t passing
 * through q; t is in the status when e is inserted, and the insertion descent
 * either compares q with t (orientation 0, reported at once) or places e
 * right beside the block of edges through q, so that a neighbour test of e,
 * or of the other edge starting at q inserted just before it, reports it. */

#define NIL UINT32_MAX

typedef struct sweep {
    const vec2 *p;
    uint32_t n;
    uint32_t *lc, *rc, *up;   /* treap links per edge, NIL when none */
    uint32_t root;
    uint32_t bad_a, bad_b;    /* offending pair, once found */
} sweep;

static uint32_t ring_next(uint32_t k, uint32_t n)
{
    return k + 1 == n ? 0 : k + 1;
}

static uint32_t ring_prev(uint32_t k, uint32_t n)
{
    return k == 0 ? n - 1 : k - 1;
}

static int edges_adjacent(uint32_t e, uint32_t f, uint32_t n)
{
    return ring_next(e, n) == f || ring_next(f, n) == e;
}

static void edge_ends(const sweep *s, uint32_t e, vec2 *lo, vec2 *hi)
{
    vec2 a = s->p[e], b = s->p[ring_next(e, s->n)];
    if (lex_less(a, b)) {
        *lo = a;
        *hi = b;
    } else {
        *lo = b;
        *hi = a;
    }
}

/* Heap priority of an edge: a fixed mix of its index (treap balance only
 * needs priorities unrelated to the geometric order). */
static uint32_t treap_prio(uint32_t k)
{
    k ^= k >> 16;
    k *= 0x7feb352dU;
    k ^= k >> 15;
    k *= 0x846ca68bU;
    k ^= k >> 16;
    return k;
}

static void treap_replace(sweep *s, uint32_t parent, uint32_t old, uint32_t nw)
{
    if (parent == NIL)
        s->root = nw;
    else if (s->lc[parent] == old)
        s->lc[parent] = nw;
    else
        s->rc[parent] = nw;
    if (nw != NIL)
        s->up[nw] = parent;
}

/* Lifts x above its parent, keeping the in-order sequence. */
static void treap_rotate_up(sweep *s, uint32_t x)
{
    uint32_t y = s->up[x], g = s->up[y], b;
    if (s->lc[y] == x) {
        b = s->rc[x];
        s->lc[y] = b;
        s->rc[x] = y;
    } else {
        b = s->lc[x];
        s->rc[y] = b;
        s->lc[x] = y;
    }
    if (b != NIL)
        s->up[b] = y;
    s->up[y] = x;
    treap_replace(s, g, y, x);
}

static uint32_t treap_pred(const sweep *s, uint32_t x)
{
    if (s->lc[x] != NIL) {
        x = s->lc[x];
        while (s->rc[x] != NIL)
            x = s->rc[x];
        return x;
    }
    while (s->up[x] != NIL && s->lc[s->up[x]] == x)
        x = s->up[x];
    return s->up[x];
}

static uint32_t treap_succ(const sweep *s, uint32_t x)
{
    if (s->rc[x] != NIL) {
        x = s->rc[x];
        while (s->lc[x] != NIL)
            x = s->lc[x];
        return x;
    }
    while (s->up[x] != NIL && s->rc[s->up[x]] == x)
        x = s->up[x];
    return s->up[x];
}

static int sweep_bad(sweep *s, uint32_t e, uint32_t f)
{
    s->bad_a = e < f ? e : f;
    s->bad_b = e < f ? f : e;
    return 0;
}

/* 1 if e and f (either may be NIL) are allowed to be neighbours. */
static int sweep_pair_ok(sweep *s, uint32_t e, uint32_t f)
{
    vec2 a, b, c, d;
    if (e == NIL || f == NIL || edges_adjacent(e, f, s->n))
        return 1;
    edge_ends(s, e, &a, &b);
    edge_ends(s, f, &c, &d);
    /* cheap rejection before the exact test (both cut the sweep line, so
     * their x ranges overlap already) */
    if ((a.y < b.y ? b.y : a.y) < (c.y < d.y ? c.y : d.y) ||
        (c.y < d.y ? d.y : c.y) < (a.y < b.y ? a.y : b.y))
        return 1;
    if (geom_seg_meet(a, b, c, d) == GEOM_SEG_DISJOINT)
        return 1;
    return sweep_bad(s, e, f);
}

/* Inserts edge e at its lower end q. Returns 0 when an offending pair is
 * found. */
static int sweep_insert(sweep *s, uint32_t e)
{
    vec2 q, qh;
    uint32_t cur = s->root, parent = NIL;
    int right = 0;
    edge_ends(s, e, &q, &qh);
    while (cur != NIL) {
        vec2 lo, hi;
        int o;
        edge_ends(s, cur, &lo, &hi);
        o = geom_orient(lo, hi, q);
        if (o == 0) {
            /* q lies on cur. Allowed only for the other edge starting at
             * the same vertex; order the two by direction. */
            if (!edges_adjacent(cur, e, s->n) || !vec_eq(lo, q))
                return sweep_bad(s, cur, e);
            o = geom_orient(q, hi, qh);
            if (o == 0)                  /* a spike: step 1 excludes it */
                return sweep_bad(s, cur, e);
        }
        parent = cur;
        right = o > 0;
        cur = right ? s->rc[cur] : s->lc[cur];
    }
    s->lc[e] = s->rc[e] = NIL;
    s->up[e] = parent;
    if (parent == NIL)
        s->root = e;
    else if (right)
        s->rc[parent] = e;
    else
        s->lc[parent] = e;
    while (s->up[e] != NIL && treap_prio(e) > treap_prio(s->up[e]))
        treap_rotate_up(s, e);
    return sweep_pair_ok(s, e, treap_pred(s, e)) &&
           sweep_pair_ok(s, e, treap_succ(s, e));
}

/* Removes edge e; its two neighbours meet. Returns 0 on an offending pair. */
static int sweep_remove(sweep *s, uint32_t e)
{
    uint32_t below = treap_pred(s, e), above = treap_succ(s, e), c;
    while (s->lc[e] != NIL && s->rc[e] != NIL) {
        uint32_t l = s->lc[e], r = s->rc[e];
        treap_rotate_up(s, treap_prio(l) > treap_prio(r) ? l : r);
    }
    c = s->lc[e] != NIL ? s->lc[e] : s->rc[e];
    treap_replace(s, s->up[e], e, c);
    return sweep_pair_ok(s, below, above);
}

/* Stable bottom-up merge sort of vertex indices by lexicographic order of
 * the points. */
static void sort_vertices(const vec2 *p, uint32_t *idx, uint32_t *tmp, size_t n)
{
    uint32_t *src = idx, *dst = tmp, *sw;
    size_t width, i;
    for (width = 1; width < n; width *= 2) {
        for (i = 0; i < n; i += 2 * width) {
            size_t mid = i + width < n ? i + width : n;
            size_t end = mid + width < n ? mid + width : n;
            size_t l = i, r = mid, o = i;
            while (l < mid && r < end)
                dst[o++] = lex_less(p[src[r]], p[src[l]]) ? src[r++] : src[l++];
            while (l < mid)
                dst[o++] = src[l++];
            while (r < end)
                dst[o++] = src[r++];
        }
        sw = src;
        src = dst;
        dst = sw;
    }
    if (src != idx)
        memcpy(idx, src, n * sizeof *idx);
}

static int ring_bad(uint32_t e, uint32_t f, uint32_t *ei, uint32_t *ej)
{
    if (ei)
        *ei = e < f ? e : f;
    if (ej)
        *ej = e < f ? f : e;
    return 0;
}

int geom_ring_is_simple(arena *a, const vec2 *p, uint32_t n, uint32_t *ei, uint32_t *ej)
{
    arena_mark mark;
    sweep s;
    uint32_t *mem, *order, k;
    size_t bytes;
    int ok = 1;

    if (n < 3)
        return ring_bad(0, 0, ei, ej);

    /* 1. Linear checks. */
    for (k = 0; k < n; k++) {
        if (!(fabs(p[k].x) <= DBL_MAX && fabs(p[k].y) <= DBL_MAX))
            return ring_bad(ring_prev(k, n), k, ei, ej);
    }
    for (k = 0; k < n; k++) {
        if (vec_eq(p[k], p[ring_next(k, n)]))
            return ring_bad(k, k, ei, ej);
    }
    for (k = 0; k < n; k++) {
        vec2 u = p[ring_prev(k, n)], v = p[k], w = p[ring_next(k, n)];
        /* collinear and u, w on the same side of v: the edges overlap */
        if (geom_orient(u, v, w) == 0 && lex_less(u, v) == lex_less(w, v))
            return ring_bad(ring_prev(k, n), k, ei, ej);
    }
    if (n == 3)
        return 1;                 /* every pair of edges is adjacent */

    /* 2. Sort; a repeated point is a pinch. */
    mark = arena_get_mark(a);
    bytes = arena_mul(n, 4 * sizeof(uint32_t));
    mem = bytes == SIZE_MAX ? NULL : arena_scratch(a, bytes, sizeof(uint32_t));
    if (!mem) {
        arena_release(a, &mark);
        return -1;
    }
    order = mem;
    s.p = p;
    s.n = n;
    s.lc = mem + (size_t)n;
    s.rc = mem + 2 * (size_t)n;
    s.up = mem + 3 * (size_t)n;
    s.root = NIL;
    s.bad_a = s.bad_b = 0;
    for (k = 0; k < n; k++)
        order[k] = k;
    sort_vertices(p, order, s.lc, n);   /* lc doubles as the merge buffer */
    for (k = 1; k < n; k++) {
        if (vec_eq(p[order[k - 1]], p[order[k]])) {
            /* edges starting at the two vertices touch there; they are not
             * adjacent, as no edge has zero length */
            arena_release(a, &mark);
            return ring_bad(order[k - 1], order[k], ei, ej);
        }
    }

    /* 3. Sweep. */
    for (k = 0; k < n && ok; k++) {
        uint32_t v = order[k];
        uint32_t ea = ring_prev(v, n), eb = v;   /* edges (v-1,v) and (v,v+1) */
        int a_ends = lex_less(p[ea], p[v]);
        int b_ends = lex_less(p[ring_next(v, n)], p[v]);
        if (ok && a_ends)
            ok = sweep_remove(&s, ea);
        if (ok && b_ends)
            ok = sweep_remove(&s, eb);
        if (ok && !a_ends)
            ok = sweep_insert(&s, ea);
        if (ok && !b_ends)
            ok = sweep_insert(&s, eb);
    }
    arena_release(a, &mark);
    if (!ok)
        return ring_bad(s.bad_a, s.bad_b, ei, ej);
    return 1;
}

void geom_basis3(const double n[3], double t[3], double b[3])
{
    double l;
    if (fabs(n[2]) < 0.9) {
        t[0] = -n[1];
        t[1] = n[0];
        t[2] = 0.0;
    } else {
        t[0] = 0.0;
        t[1] = -n[2];
        t[2] = n[1];
    }
    l = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    t[0] /= l;
    t[1] /= l;
    t[2] /= l;
    b[0] = n[1] * t[2] - n[2] * t[1];
    b[1] = n[2] * t[0] - n[0] * t[2];
    b[2] = n[0] * t[1] - n[1] * t[0];
}
