/* visibility: fan of tangent rays by cone walking (see visibility.h). */
#include <float.h>
#include <math.h>
#include <string.h>
#include "polar/visibility.h"
#include "base/geom.h"
#include "base/plx_assert.h"

enum { UL = 0, LL = 1, UR = 2, LR = 3 };
#define CHUNK 256
/* Cones narrower than this give no visible building: a range limit given as
 * an angle is rounded, and must not turn a contact at one direction into a
 * sliver (the same rule as tests/ref/ref_vis: directions within 1e-12 rad
 * are one). Areas are not affected. */
#define VIS_MIN_WIDTH 1e-12

/* A hint to fetch memory soon to be read (no effect on results). */
#if defined(__GNUC__)
#define PREFETCH(p) __builtin_prefetch(p)
#else
#define PREFETCH(p) ((void)(p))
#endif

/* A pending cone: rays from p through A (clockwise limit) and B, in the
 * frame of its map, in region t, moving towards increasing (right) or
 * decreasing frame order. A cone pushed at a split has already been moved
 * past the splitting corner: shut is then the wall it closes on (else
 * POLAR_NONE). */
typedef struct cone {
    vec2 A, B;
    uint32_t t;
    uint32_t right;
    uint32_t shut;
} cone;

typedef struct chunk {
    struct chunk *prev;
    uint32_t n;
    cone c[CHUNK];
} chunk;

/* Buildings met by closed cones, in the order met (repeats kept but for
 * immediate ones); sorted and made unique at the end. */
#define HCHUNK 1024
typedef struct hchunk {
    struct hchunk *prev;
    uint32_t n;
    uint32_t v[HCHUNK];
} hchunk;

typedef struct walker {
    const polar *pd;
    const polar_map *m;
    arena *a;
    vec2 p;              /* world */
    vec2 P;              /* frame */
    chunk *top;
    int nomem;
    /* output */
    vis_result *out;
    int want_vis;        /* collect the visible buildings */
    hchunk *hits;
    uint32_t nhits;
    int32_t last_hit;
    double area2;        /* twice the area */
    vec2 last;           /* last polygon point */
    uint32_t last_seg;
    int has_last;
    uint32_t stop_first; /* vis_first: stop at the first wall */
    int32_t first_bld;
    int stopped;
} walker;

/* Point i in the frame (polar_fpt, inlined: it is read on every step). */
static vec2 fpt(const polar *pd, int frame, uint32_t i)
{
    vec2 w = pd->pts[i], f;
    if (frame == 0) {
        f.x = w.y;
        f.y = -w.x;
    } else {
        f = w;
    }
    return f;
}

/* polar_from_frame, inlined. */
static vec2 from_frame(int frame, vec2 f)
{
    vec2 r;
    if (frame == 0) {
        r.x = -f.y;
        r.y = f.x;
    } else {
        r = f;
    }
    return r;
}

/* Sign of geom_orient(P, X, R) given x = X - P and r = R - P (differences
 * rounded once, computed by the caller and reused across tests). These are
 * the products geom_orient(X, R, P) filters, the same sign (a cyclic turn of
 * the arguments); geom_orient decides when the filter cannot. */
static int orient_rel(double xx, double xy, double rx, double ry, vec2 P, vec2 X, vec2 R)
{
    int o = geom_orient_filter(xx * ry, xy * rx);
    return o ? o : geom_orient(P, X, R);
}

static int push(walker *w, const cone *c)
{
    chunk *k = w->top;
    if (!k || k->n == CHUNK) {
        chunk *nk = arena_scratch(w->a, sizeof(chunk), 16);
        if (!nk) {
            w->nomem = 1;
            return 0;
        }
        nk->prev = k;
        nk->n = 0;
        w->top = k = nk;
    }
    k->c[k->n++] = *c;
    return 1;
}

static void add_hit(walker *w, int32_t b)
{
    hchunk *k = w->hits;
    if (b == w->last_hit)
        return;
    if (!k || k->n == HCHUNK) {
        hchunk *nk = arena_scratch(w->a, sizeof(hchunk), 16);
        if (!nk) {
            w->nomem = 1;
            return;
        }
        nk->prev = k;
        nk->n = 0;
        w->hits = k = nk;
    }
    k->v[k->n++] = (uint32_t)b;
    w->nhits++;
    w->last_hit = b;
}

/* Sorts v[0..n-1] ascending; tmp holds n more. Radix sort by bytes, only
 * as many passes as the largest value needs (two below 65536 buildings):
 * a few hundred hits per query, where qsort's calls cost more. Returns the
 * array holding the result (v or tmp). */
static uint32_t *sort_u32(uint32_t *v, uint32_t *tmp, uint32_t n)
{
    uint32_t all = 0, i, sh;
    for (i = 0; i < n; i++)
        all |= v[i];
    for (sh = 0; sh < 32 && (all >> sh) != 0; sh += 8) {
        uint32_t cnt[256], sum = 0, *t;
        memset(cnt, 0, sizeof cnt);
        for (i = 0; i < n; i++)
            cnt[(v[i] >> sh) & 255]++;
        for (i = 0; i < 256; i++) {
            uint32_t c = cnt[i];
            cnt[i] = sum;
            sum += c;
        }
        for (i = 0; i < n; i++)
            tmp[cnt[(v[i] >> sh) & 255]++] = v[i];
        t = v;
        v = tmp;
        tmp = t;
    }
    return v;
}

static int pop(walker *w, cone *c)
{
    while (w->top && w->top->n == 0)
        w->top = w->top->prev;    /* chunk memory is released at the end */
    if (!w->top)
        return 0;
    *c = w->top->c[--w->top->n];
    return 1;
}

static void add_point(walker *w, vec2 q)
{
    vis_result *o = w->out;
    if (w->has_last && q.x == w->last.x && q.y == w->last.y)
        return;
    if (o->poly && o->npoly < o->poly_cap)
        o->poly[o->npoly] = q;
    o->npoly++;
    w->last = q;
    w->has_last = 1;
}

/* Replaces the last point (the same wall continues). */
static void move_last(walker *w, vec2 q)
{
    vis_result *o = w->out;
    if (o->poly && o->npoly - 1 < o->poly_cap)
        o->poly[o->npoly - 1] = q;
    w->last = q;
}

static double cross2(vec2 o, vec2 a, vec2 b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/* Where the ray from p through r meets the line ab (world). */
static vec2 ray_line(vec2 p, vec2 r, vec2 a, vec2 b)
{
    double rx = r.x - p.x, ry = r.y - p.y, sx = b.x - a.x, sy = b.y - a.y;
    double den = rx * sy - ry * sx, t;
    vec2 q;
    t = den == 0.0 ? 0.0 : ((a.x - p.x) * sy - (a.y - p.y) * sx) / den;
    q.x = p.x + t * rx;
    q.y = p.y + t * ry;
    return q;
}

/* Where the ray from p through r leaves the box. */
static vec2 ray_box(const double *bx, vec2 p, vec2 r)
{
    double dx = r.x - p.x, dy = r.y - p.y, t = DBL_MAX;
    vec2 q;
    if (dx > 0)
        t = fmin(t, (bx[2] - p.x) / dx);
    if (dx < 0)
        t = fmin(t, (bx[0] - p.x) / dx);
    if (dy > 0)
        t = fmin(t, (bx[3] - p.y) / dy);
    if (dy < 0)
        t = fmin(t, (bx[1] - p.y) / dy);
    q.x = p.x + t * dx;
    q.y = p.y + t * dy;
    /* land exactly on the side that was met */
    if (q.x < bx[0]) q.x = bx[0];
    if (q.x > bx[2]) q.x = bx[2];
    if (q.y < bx[1]) q.y = bx[1];
    if (q.y > bx[3]) q.y = bx[3];
    return q;
}

static void add_piece(walker *w, vec2 xa, vec2 xb, uint32_t seg)
{
    if (w->has_last && seg != POLAR_NONE && seg == w->last_seg &&
        xa.x == w->last.x && xa.y == w->last.y) {
        move_last(w, xb);
    } else {
        add_point(w, xa);
        add_point(w, xb);
    }
    w->last_seg = seg;
    w->area2 += cross2(w->p, xa, xb);
}

/* A closed cone meeting the Bounds box. A, B world points. */
static void close_box(walker *w, vec2 A, vec2 B)
{
    const double *bx = w->pd->box;
    vec2 c[4], in[4], prev;
    int i, j, n = 0;
    c[0].x = bx[0]; c[0].y = bx[1];
    c[1].x = bx[2]; c[1].y = bx[1];
    c[2].x = bx[2]; c[2].y = bx[3];
    c[3].x = bx[0]; c[3].y = bx[3];
    for (i = 0; i < 4; i++)
        if (geom_orient(w->p, A, c[i]) > 0 && geom_orient(w->p, B, c[i]) < 0)
            in[n++] = c[i];
    for (i = 1; i < n; i++)             /* counter-clockwise order */
        for (j = i; j > 0 && geom_orient(w->p, in[j], in[j - 1]) > 0; j--) {
            vec2 t = in[j];
            in[j] = in[j - 1];
            in[j - 1] = t;
        }
    prev = ray_box(bx, w->p, A);
    for (i = 0; i < n; i++) {
        add_piece(w, prev, in[i], POLAR_NONE);
        prev = in[i];
    }
    add_piece(w, prev, ray_box(bx, w->p, B), POLAR_NONE);
    w->last_seg = POLAR_NONE;
}

/* Angle between the rays from P through A and B (radians, plain doubles). */
static double cone_width(vec2 P, vec2 A, vec2 B)
{
    double ax = A.x - P.x, ay = A.y - P.y, bx = B.x - P.x, by = B.y - P.y;
    return atan2(ax * by - ay * bx, ax * bx + ay * by);
}

/* Is the angle from ray PA to ray PB surely above 1e-6 rad, so that
 * cone_width need not be asked? cr is the rounded cross product (error below
 * 3 ulp of |a|_1 |b|_1), and |a| |b| <= |a|_1 |b|_1 bounds the sine from
 * below. When no, cone_width decides, as before. */
static int clearly_wide(vec2 P, vec2 A, vec2 B)
{
    double ax = A.x - P.x, ay = A.y - P.y, bx = B.x - P.x, by = B.y - P.y;
    return ax * by - ay * bx > 1e-6 * (fabs(ax) + fabs(ay)) * (fabs(bx) + fabs(by));
}

/* A closed cone c meeting wall piece s. (By pointer: its points passed as
 * values were packed through the stack on every call.) */
static void close_cone(walker *w, uint32_t s, const cone *c)
{
    const polar *pd = w->pd;
    const vec2 A = c->A, B = c->B;
    const polar_seg *g = &pd->seg[s];
    int frame = w->m->frame;
    vec2 wa = from_frame(frame, A), wb = from_frame(frame, B);
    int k;
    w->out->ncones++;
    if (g->bld[0] == -2) {
        close_box(w, wa, wb);
        return;
    }
    if (w->stop_first) {
        w->first_bld = g->bld[0];
        w->stopped = 1;
        return;
    }
    add_piece(w, ray_line(w->p, wa, pd->pts[g->a], pd->pts[g->b]),
              ray_line(w->p, wb, pd->pts[g->a], pd->pts[g->b]), s);
    if (!w->want_vis || (!clearly_wide(w->P, A, B) && cone_width(w->P, A, B) < VIS_MIN_WIDTH))
        return;
    for (k = 0; k < 2; k++)
        if (g->bld[k] >= 0)
            add_hit(w, g->bld[k]);
}

/* Has every ray of cone c already crossed the floor (below = 1) or ceiling
 * wall of region t before the abscissa of R? Then the cone is closed on that
 * wall now instead of being carried along it (the answer would be the same
 * wall). Floating test with a wide margin: when in doubt, say no. */
static int past_wall(const walker *w, const cone *c, vec2 R, int below)
{
    const polar_map *m = w->m;
    const polar_seg *g = &w->pd->seg[below ? m->trap[c->t].bot : m->trap[c->t].top];
    vec2 a = fpt(w->pd, m->frame, g->a), b = fpt(w->pd, m->frame, g->b), X;
    double cy, cr, xx, xy, cx2, cy2;
    int sgn;
    if (a.x == b.x)
        return 0;
    cy = a.y + (b.y - a.y) * ((R.x - a.x) / (b.x - a.x));
    X = (below == (int)c->right) ? c->B : c->A;
    xx = X.x - w->P.x;
    xy = X.y - w->P.y;
    cx2 = R.x - w->P.x;
    cy2 = cy - w->P.y;
    cr = xx * cy2 - xy * cx2;
    sgn = (below == (int)c->right) ? 1 : -1;
    return sgn * cr > 1e-9 * (fabs(xx) + fabs(xy)) * (fabs(cx2) + fabs(cy2));
}

/* The region after region c->t past its corner R, below R in the frame
 * (low = 1) or above it; POLAR_NONE when the cone closes there, on *wall. */
static uint32_t advance(const walker *w, const cone *c, vec2 R, int low, uint32_t *wall)
{
    const polar_trap *tr = &w->m->trap[c->t];
    uint32_t nx = tr->nb[low ? (c->right ? LR : LL) : (c->right ? UR : UL)];
    if (nx == POLAR_NONE || past_wall(w, c, R, low)) {
        *wall = low ? tr->bot : tr->top;
        return POLAR_NONE;
    }
    return nx;
}

/* Walks one cone until it is closed; pushes the later half at a split.
 * The limit rays are kept as differences from P (a, b), and the corner of
 * each region as r = R - P, so that each orientation test costs two
 * products and the filter. */
static void step(walker *w, cone c)
{
    const polar_map *m = w->m;
    const polar_trap *trap = m->trap;
    const vec2 *pts = w->pd->pts;
    const vec2 P = w->P;
    const int frame = m->frame;
    const uint32_t end = c.right ? m->box_hi : m->box_lo;
    double ax = c.A.x - P.x, ay = c.A.y - P.y, bx = c.B.x - P.x, by = c.B.y - P.y;
    uint32_t steps = 0;
    for (;;) {
        uint32_t r = c.right ? trap[c.t].rp : trap[c.t].lp, nx, wall;
        vec2 R;
        double rx, ry;
        int low;
        steps++;
        /* the next region is one of these two: fetch both while the
         * orientation tests run (large cities do not fit in the cache) */
        {
            const uint32_t *nb = trap[c.t].nb + (c.right ? UR : UL);
            if (nb[0] != POLAR_NONE)
                PREFETCH(&trap[nb[0]]);
            if (nb[1] != POLAR_NONE)
                PREFETCH(&trap[nb[1]]);
            PREFETCH(&w->pd->seg[trap[c.t].top]);
            PREFETCH(&w->pd->seg[trap[c.t].bot]);
        }
        if (r == end) {
            w->out->ncones++;
            close_box(w, from_frame(frame, c.A), from_frame(frame, c.B));
            break;
        }
        if (frame == 0) {
            R.x = pts[r].y;
            R.y = -pts[r].x;
        } else {
            R = pts[r];
        }
        rx = R.x - P.x;
        ry = R.y - P.y;
        /* "low" = the cone passes below R in the frame; the limit ray A is
         * only looked at when B does not decide */
        if (orient_rel(bx, by, rx, ry, P, c.B, R) >= 0) {
            low = (int)c.right;
        } else if (orient_rel(ax, ay, rx, ry, P, c.A, R) <= 0) {
            low = !c.right;
        } else {
            /* R splits the cone: clockwise half first. The later half is
             * moved past R now (its next step would test R against its own
             * limit ray, an exact zero) and walked when popped. */
            cone hi = c;
            hi.A = R;
            c.B = R;
            bx = rx;
            by = ry;
            steps++;
            nx = advance(w, &hi, R, !c.right, &wall);
            if (nx == POLAR_NONE)
                hi.shut = wall;
            else
                hi.t = nx;
            if (!push(w, &hi))
                break;
            /* the clockwise half is below R when moving right */
            low = (int)c.right;
        }
        nx = advance(w, &c, R, low, &wall);
        if (nx == POLAR_NONE) {
            close_cone(w, wall, &c);
            break;
        }
        c.t = nx;
    }
    w->out->nsteps += steps;
}

static void run(walker *w, cone c)
{
    step(w, c);
    while (!w->nomem && !w->stopped && pop(w, &c)) {
        if (c.shut != POLAR_NONE)
            close_cone(w, c.shut, &c);
        else
            step(w, c);
    }
}

/* A ray point for world direction angle ang within quadrant q. */
static vec2 dir_point(const polar *pd, vec2 p, double ang, int q, int exact_axis)
{
    double L = 2.0 * ((pd->box[2] - pd->box[0]) + (pd->box[3] - pd->box[1]));
    static const int ax[5][2] = { { 1, 0 }, { 0, 1 }, { -1, 0 }, { 0, -1 }, { 1, 0 } };
    vec2 r;
    if (exact_axis >= 0) {
        r.x = p.x + ax[exact_axis][0] * L;
        r.y = p.y + ax[exact_axis][1] * L;
        if (ax[exact_axis][0] == 0)
            r.x = p.x;
        if (ax[exact_axis][1] == 0)
            r.y = p.y;
        return r;
    }
    r.x = p.x + cos(ang) * L;
    r.y = p.y + sin(ang) * L;
    /* keep the rounded ray inside the closed quadrant */
    if ((q == 0 && (r.x < p.x || r.y < p.y)) || (q == 1 && (r.x > p.x || r.y < p.y)) ||
        (q == 2 && (r.x > p.x || r.y > p.y)) || (q == 3 && (r.x < p.x || r.y > p.y))) {
        r = p;
        if (q == 0 || q == 2)
            r.x = (r.x - p.x) != 0 ? r.x : p.x + (q == 0 ? L : -L);
        else
            r.y = p.y + (q == 1 ? L : -L);
    }
    return r;
}

/* Walks the cone of world directions [A, B] (inside quadrant q) in the
 * diagram mi: there the rays all move towards increasing frame order
 * (right) when their frame abscissa grows, else towards decreasing. */
static void walk_cone(walker *w, int mi, int q, vec2 A, vec2 B, const uint32_t t0[2])
{
    cone c;
    w->m = &w->pd->map[mi];
    w->P = polar_to_frame(w->m->frame, w->p);
    c.A = polar_to_frame(w->m->frame, A);
    c.B = polar_to_frame(w->m->frame, B);
    c.t = t0[mi];
    c.shut = POLAR_NONE;
    c.right = mi == 0 ? (q == 0 || q == 1) : (q == 0 || q == 3);
    run(w, c);
}

/* Walks the cone of world directions [A, B] lying in quadrant q. Its rays
 * near the quadrant's start axis go through the diagram whose axes are
 * parallel to that axis (diagram q & 1), those past the diagonal through
 * the other one: a ray crosses the axes of a diagram the faster the more it
 * turns away from them, so each half crosses fewer regions this way. The
 * split ray is one exact ray shared by both halves. */
static void quadrant_cone(walker *w, int q, vec2 A, vec2 B, const uint32_t t0[2])
{
    static const int sg[4][2] = { { 1, 1 }, { -1, 1 }, { -1, -1 }, { 1, -1 } };
    double L = 2.0 * ((w->pd->box[2] - w->pd->box[0]) + (w->pd->box[3] - w->pd->box[1]));
    int m0 = q & 1, m1 = 1 - m0;
    vec2 D;
    if (geom_orient(w->p, A, B) <= 0)
        return;                 /* empty */
    D.x = w->p.x + sg[q][0] * L;
    D.y = w->p.y + sg[q][1] * L;
    if (geom_orient(w->p, A, D) <= 0) {
        walk_cone(w, m1, q, A, B, t0);
    } else if (geom_orient(w->p, D, B) <= 0) {
        walk_cone(w, m0, q, A, B, t0);
    } else {
        walk_cone(w, m0, q, A, D, t0);
        if (!w->nomem && !w->stopped)
            walk_cone(w, m1, q, D, B, t0);
    }
}

static int locate_free(const polar *pd, vec2 p, uint32_t t0[2])
{
    int i;
    if (!(p.x > pd->box[0] && p.x < pd->box[2] && p.y > pd->box[1] && p.y < pd->box[3]))
        return -1;
    for (i = 0; i < 2; i++) {
        const polar_map *m = &pd->map[i];
        int32_t t = polar_locate_frame(pd, m, polar_to_frame(m->frame, p));
        if (t < 0)
            return -1;
        t0[i] = (uint32_t)t;
    }
    return 0;
}

/* Splits the turn from a0 by width wd (< 2 pi) into quadrant cones, or
 * the full turn into the four quadrants. */
static void range_cones(walker *w, double a0, double wd, int full, const uint32_t t0[2])
{
    const double H = 1.5707963267948966;
    double s, e;
    int q, k;
    vec2 A, B;
    if (full) {
        for (q = 0; q < 4 && !w->nomem; q++)
            quadrant_cone(w, q, dir_point(w->pd, w->p, 0, q, q),
                          dir_point(w->pd, w->p, 0, q, q + 1), t0);
        return;
    }
    s = fmod(a0, 4 * H);
    if (s < 0)
        s += 4 * H;
    if (s >= 4 * H)
        s = 0;
    e = s + wd;
    q = (int)floor(s / H);
    if (q > 3)
        q = 3;
    for (k = 0; k < 5 && !w->nomem; k++) {
        int qi = q + k, qq = qi % 4;
        double qbeg = qi * H, qend = (qi + 1) * H;
        if (k == 0 && s != qbeg)
            A = dir_point(w->pd, w->p, s, qq, -1);
        else
            A = dir_point(w->pd, w->p, 0, qq, qq);
        if (e < qend)
            B = dir_point(w->pd, w->p, e, qq, -1);
        else
            B = dir_point(w->pd, w->p, 0, qq, qq + 1);
        quadrant_cone(w, qq, A, B, t0);
        if (e <= qend)
            break;
    }
}

plx_status vis_query(const polar *pd, vec2 p, double a0, double a1, int full_circle,
                     arena *a, vis_result *out)
{
    walker w;
    arena_mark mk;
    uint32_t t0[2], i;
    double wd = 0;
    plx_status st = PLX_OK;
    if (!pd || !a || !out || !isfinite(p.x) || !isfinite(p.y))
        return PLX_E_INVALID;
    out->area = 0;
    out->npoly = out->nvis = out->ncones = out->nsteps = 0;
    if (!full_circle) {
        if (!isfinite(a0) || !isfinite(a1))
            return PLX_E_INVALID;
        if (a1 - a0 >= 2 * 3.14159265358979323846) {
            full_circle = 1;
        } else {
            wd = fmod(a1 - a0, 2 * 3.14159265358979323846);
            if (wd < 0)
                wd += 2 * 3.14159265358979323846;
        }
    }
    if (locate_free(pd, p, t0) != 0)
        return PLX_E_RANGE;
    if (!full_circle && wd == 0.0)
        return PLX_OK;
    mk = arena_get_mark(a);
    memset(&w, 0, sizeof w);
    w.pd = pd;
    w.a = a;
    w.p = p;
    w.out = out;
    w.last_seg = POLAR_NONE;
    w.want_vis = 1;
    w.last_hit = -1;
    if (!full_circle)
        add_point(&w, p);
    range_cones(&w, a0, wd, full_circle, t0);
    /* close the ring: drop a last point equal to the first */
    if (out->npoly > 1 && out->poly && out->npoly <= out->poly_cap &&
        out->poly[0].x == w.last.x && out->poly[0].y == w.last.y)
        out->npoly--;
    out->area = 0.5 * w.area2;
    if (!w.nomem && w.nhits > 0) {
        uint32_t *all = arena_scratch(a, (size_t)w.nhits * 8, 16), n = 0;
        hchunk *k;
        if (!all) {
            w.nomem = 1;
        } else {
            for (k = w.hits; k; k = k->prev) {
                memcpy(all + n, k->v, k->n * 4);
                n += k->n;
            }
            all = sort_u32(all, all + n, n);
            for (i = 0; i < n; i++) {
                if (i > 0 && all[i] == all[i - 1])
                    continue;
                if (out->vis && out->nvis < out->vis_cap)
                    out->vis[out->nvis] = all[i];
                out->nvis++;
            }
        }
    }
#ifdef PLX_DEBUG
    /* the visible set is strictly ascending building indices */
    for (i = 1; !w.nomem && out->vis && i < out->nvis && i < out->vis_cap; i++)
        PLX_ASSERT(out->vis[i - 1] < out->vis[i] && out->vis[i] < pd->nbld);
#endif
    if (w.nomem)
        st = PLX_E_NOMEM;
    if ((out->poly && out->npoly > out->poly_cap) || (out->vis && out->nvis > out->vis_cap))
        st = PLX_E_NOMEM;
    arena_release(a, &mk);
    return st;
}

int32_t vis_first(const polar *pd, int q, vec2 p, arena *a)
{
    walker w;
    vis_result r;
    arena_mark mk;
    uint32_t t0[2];
    if (!pd || !a || q < 0 || q > 3)
        return -2;
    if (locate_free(pd, p, t0) != 0)
        return -2;
    mk = arena_get_mark(a);
    memset(&w, 0, sizeof w);
    memset(&r, 0, sizeof r);
    w.pd = pd;
    w.a = a;
    w.p = p;
    w.out = &r;
    w.last_seg = POLAR_NONE;
    w.stop_first = 1;
    w.first_bld = -1;
    quadrant_cone(&w, q, dir_point(pd, p, 0, q, q), dir_point(pd, p, 0, q, q + 1), t0);
    arena_release(a, &mk);
    if (w.nomem)
        return -3;
    return w.stopped ? w.first_bld : -1;
}
