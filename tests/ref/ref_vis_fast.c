/* ref_vis_fast: ref_vis's angular sweep with grid searches (contract in
 * ref_vis_fast.h). Independent of src/polar.*: only the scene and the
 * reference point classification of ref_scene are used. */
#include "ref_vis_fast.h"
#include "ref_scene.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#define F_PI 3.141592653589793238462643383279502884L
#define F_TWO_PI (2.0L * F_PI)
#define F_ANGLE_EPS 1e-12L  /* directions closer than this are one event */
#define F_TIE_EPS 1e-12L    /* relative distance tie for the nearest edge */
#define F_VERT_TOL 1e-10L   /* vertex merge tolerance, times the box size */
#define F_HAIR 1e-9L        /* grid widening and ray slack, times the box size */

typedef struct fpt { long double x, y; } fpt;

/* An edge a->b; owner is the building index, or -1 for a box edge. */
typedef struct fedge { fpt a, b; long owner; } fedge;

typedef struct fhit { size_t e; long double t; } fhit;

/* What does not depend on the viewer: edges, grid, meeting points. */
struct ref_fast {
    const scene *s;
    fedge *e;
    size_t ne, nocc;          /* all edges; occluder edges come first */
    long double size, hair;
    /* grid over the box */
    long double x0, y0, cw, ch;
    long nx, ny;
    size_t *first;            /* nx ny + 1 */
    size_t *item;
    /* event points: every edge start and every point where two edges
     * meet, without repeats (equal points give equal directions) */
    fpt *mp;
    size_t nmp, capmp;
};

typedef struct fquery {
    const ref_fast *f;
    const scene *s;
    fpt p;
    const fedge *e;
    size_t ne, nocc;
    long double size, hair;
    long double x0, y0, cw, ch;
    long nx, ny;
    const size_t *first;
    const size_t *item;
    /* event directions */
    long double *ang;
    size_t nang, capang;
    /* per ray */
    fhit *hit;
    size_t nhit, caphit;
    uint32_t *seen;           /* per edge: last ray that tested it */
    uint32_t ray;
    /* result */
    unsigned char *vis;
    fpt *poly;
    size_t npoly, cappoly;
    long double area;
} fquery;

static fpt mk(long double x, long double y) { fpt r; r.x = x; r.y = y; return r; }
static fpt sub(fpt a, fpt b) { return mk(a.x - b.x, a.y - b.y); }
static long double cross(fpt u, fpt v) { return u.x * v.y - u.y * v.x; }
static long double dot(fpt u, fpt v) { return u.x * v.x + u.y * v.y; }
static fpt dir(long double th) { return mk(cosl(th), sinl(th)); }

static long double norm_angle(long double a)
{
    a = fmodl(a, F_TWO_PI);
    if (a < 0.0L)
        a += F_TWO_PI;
    if (a >= F_TWO_PI)
        a -= F_TWO_PI;
    return a;
}

static int is_occluder(const scene_building *b)
{
    return !(b->min_height > 0.0);
}

static int grow(void **v, size_t *cap, size_t need, size_t size)
{
    size_t c = *cap ? *cap : 64;
    void *nv;
    if (need <= *cap)
        return 0;
    while (c < need)
        c *= 2;
    nv = realloc(*v, c * size);
    if (!nv)
        return -1;
    *v = nv;
    *cap = c;
    return 0;
}

/* 0 free, -1 outside the box or inside a footprint, -2 on a boundary. */
static int classify(const scene *s, long double px, long double py)
{
    const double *bb = s->bounds;
    int on = 0;
    uint32_t i;
    if (px < bb[0] || px > bb[2] || py < bb[1] || py > bb[3])
        return -1;
    if (px == bb[0] || px == bb[2] || py == bb[1] || py == bb[3])
        on = 1;
    for (i = 0; i < s->nbld; i++) {
        int w;
        if (!is_occluder(&s->bld[i]))
            continue;
        w = ref_footprint_where(s, i, px, py);
        if (w == REF_IN)
            return -1;
        if (w == REF_ON)
            on = 1;
    }
    return on ? -2 : 0;
}

/* Occluder edges in building and ring order, then the 4 box edges. */
static int edges_make(ref_fast *q)
{
    const scene *s = q->s;
    const double *bb = s->bounds;
    size_t n = 4, k = 0;
    uint32_t i, r, j;
    fpt c[4];
    for (i = 0; i < s->nbld; i++)
        if (is_occluder(&s->bld[i]))
            for (r = 0; r < s->bld[i].ring_count; r++)
                n += s->rings[s->bld[i].ring_first + r].count;
    q->e = malloc(n * sizeof *q->e);
    if (!q->e)
        return -1;
    for (i = 0; i < s->nbld; i++) {
        if (!is_occluder(&s->bld[i]))
            continue;
        for (r = 0; r < s->bld[i].ring_count; r++) {
            const scene_ring *rg = &s->rings[s->bld[i].ring_first + r];
            for (j = 0; j < rg->count; j++) {
                const vec2 *a = &s->pts[rg->first + j];
                const vec2 *b = &s->pts[rg->first + (j + 1) % rg->count];
                q->e[k].a = mk(a->x, a->y);
                q->e[k].b = mk(b->x, b->y);
                q->e[k].owner = (long)i;
                k++;
            }
        }
    }
    q->nocc = k;
    c[0] = mk(bb[0], bb[1]);
    c[1] = mk(bb[2], bb[1]);
    c[2] = mk(bb[2], bb[3]);
    c[3] = mk(bb[0], bb[3]);
    for (j = 0; j < 4; j++) {
        q->e[k].a = c[j];
        q->e[k].b = c[(j + 1) % 4];
        q->e[k].owner = -1;
        k++;
    }
    q->ne = n;
    return 0;
}

/* Cell index along one axis: monotone in v (the quotient rounded to a
 * double, then truncated: no x87 rounding-mode switch as floorl needs). */
static long cell_of(long double v, long double v0, long double side, long n)
{
    double c = (double)((v - v0) / side);
    if (!(c >= 0.0))
        return 0;
    if (c >= (double)n)
        return n - 1;
    return (long)c;
}

static long cell_x(const ref_fast *q, long double x)
{
    return cell_of(x, q->x0, q->cw, q->nx);
}

static long cell_y(const ref_fast *q, long double y)
{
    return cell_of(y, q->y0, q->ch, q->ny);
}

/* Cell range of edge i's bounding box widened by the hair. */
static void edge_cells(const ref_fast *q, size_t i, long *xa, long *xb, long *ya, long *yb)
{
    const fedge *e = &q->e[i];
    *xa = cell_x(q, fminl(e->a.x, e->b.x) - q->hair);
    *xb = cell_x(q, fmaxl(e->a.x, e->b.x) + q->hair);
    *ya = cell_y(q, fminl(e->a.y, e->b.y) - q->hair);
    *yb = cell_y(q, fmaxl(e->a.y, e->b.y) + q->hair);
}

/* The occluder edges listed per cell, in increasing index order. */
static int grid_make(ref_fast *q)
{
    const double *bb = q->s->bounds;
    long double W = (long double)bb[2] - bb[0], H = (long double)bb[3] - bb[1];
    long double side = sqrtl(W * H / ((long double)q->nocc / 2.0L + 1.0L));
    size_t i, total = 0, ncell;
    long x, y, xa, xb, ya, yb;
    q->nx = (long)fminl(fmaxl(ceill(W / side), 1.0L), 1024.0L);
    q->ny = (long)fminl(fmaxl(ceill(H / side), 1.0L), 1024.0L);
    q->x0 = bb[0];
    q->y0 = bb[1];
    q->cw = W / (long double)q->nx;
    q->ch = H / (long double)q->ny;
    ncell = (size_t)q->nx * (size_t)q->ny;
    q->first = calloc(ncell + 1, sizeof *q->first);
    if (!q->first)
        return -1;
    for (i = 0; i < q->nocc; i++) {
        edge_cells(q, i, &xa, &xb, &ya, &yb);
        for (y = ya; y <= yb; y++)
            for (x = xa; x <= xb; x++)
                q->first[(size_t)y * (size_t)q->nx + (size_t)x + 1]++;
    }
    for (i = 0; i < ncell; i++)
        q->first[i + 1] += q->first[i];
    total = q->first[ncell];
    q->item = malloc((total ? total : 1) * sizeof *q->item);
    if (!q->item)
        return -1;
    for (i = 0; i < q->nocc; i++) {
        edge_cells(q, i, &xa, &xb, &ya, &yb);
        for (y = ya; y <= yb; y++)
            for (x = xa; x <= xb; x++)
                q->item[q->first[(size_t)y * (size_t)q->nx + (size_t)x]++] = i;
    }
    for (i = ncell; i > 0; i--)
        q->first[i] = q->first[i - 1];
    q->first[0] = 0;
    return 0;
}

static int push_angle(fquery *q, long double a)
{
    if (grow((void **)&q->ang, &q->capang, q->nang + 1, sizeof *q->ang) != 0)
        return -1;
    q->ang[q->nang++] = a;
    return 0;
}

static int push_direction(fquery *q, fpt x)
{
    fpt d = sub(x, q->p);
    if (d.x == 0.0L && d.y == 0.0L)
        return 0;
    return push_angle(q, norm_angle(atan2l(d.y, d.x)));
}

/* If the closed segments e and f meet at a single point, stores it in *x
 * (the formula of ref_vis, with e the edge of lower index). */
static int edge_crossing(const fedge *e, const fedge *f, fpt *x)
{
    fpt d1 = sub(e->b, e->a), d2 = sub(f->b, f->a), w = sub(f->a, e->a);
    long double den = cross(d1, d2), s, u;
    if (den == 0.0L)
        return 0;
    s = cross(w, d2) / den;
    u = cross(w, d1) / den;
    if (s < 0.0L || s > 1.0L || u < 0.0L || u > 1.0L)
        return 0;
    *x = mk(e->a.x + s * d1.x, e->a.y + s * d1.y);
    return 1;
}

static int meet(ref_fast *q, size_t i, size_t j)
{
    fpt x;
    if (!edge_crossing(&q->e[i], &q->e[j], &x))
        return 0;
    if (grow((void **)&q->mp, &q->capmp, q->nmp + 1, sizeof *q->mp) != 0)
        return -1;
    q->mp[q->nmp++] = x;
    return 0;
}

/* Every meeting point of two edges sharing a cell (and of any edge with a
 * box edge). Pairs met in several cells give the same point several times:
 * their directions are merged with the rest. */
static int meeting_points(ref_fast *q)
{
    size_t i, j, k, ncell = (size_t)q->nx * (size_t)q->ny;
    for (k = 0; k < ncell; k++)
        for (i = q->first[k]; i < q->first[k + 1]; i++)
            for (j = i + 1; j < q->first[k + 1]; j++)
                if (meet(q, q->item[i], q->item[j]) != 0)
                    return -1;
    for (i = 0; i < q->ne; i++)
        for (j = q->nocc; j < q->ne; j++)
            if (i < j && meet(q, i, j) != 0)
                return -1;
    return 0;
}

static int cmp_fpt(const void *a, const void *b)
{
    const fpt *u = a, *v = b;
    if (u->x != v->x)
        return (u->x > v->x) - (u->x < v->x);
    return (u->y > v->y) - (u->y < v->y);
}

/* The edge starts joined to the meeting points, sorted, repeats removed. */
static int event_points(ref_fast *q)
{
    size_t i, m = 0;
    for (i = 0; i < q->ne; i++) {
        if (grow((void **)&q->mp, &q->capmp, q->nmp + 1, sizeof *q->mp) != 0)
            return -1;
        q->mp[q->nmp++] = q->e[i].a;
    }
    qsort(q->mp, q->nmp, sizeof *q->mp, cmp_fpt);
    for (i = 0; i < q->nmp; i++)
        if (m == 0 || cmp_fpt(&q->mp[i], &q->mp[m - 1]) != 0)
            q->mp[m++] = q->mp[i];
    q->nmp = m;
    return 0;
}

/* Event directions: from p to every event point. */
static int events(fquery *q)
{
    size_t i;
    for (i = 0; i < q->f->nmp; i++)
        if (push_direction(q, q->f->mp[i]) != 0)
            return -1;
    return 0;
}

static int cmp_ld(const void *a, const void *b)
{
    long double x = *(const long double *)a, y = *(const long double *)b;
    return (x > y) - (x < y);
}

static void sort_merge(fquery *q)
{
    size_t i, m = 0;
    if (q->nang == 0)
        return;
    qsort(q->ang, q->nang, sizeof *q->ang, cmp_ld);
    for (i = 0; i < q->nang; i++)
        if (m == 0 || q->ang[i] - q->ang[m - 1] > F_ANGLE_EPS)
            q->ang[m++] = q->ang[i];
    while (m > 1 && q->ang[m - 1] >= q->ang[0] + F_TWO_PI - F_ANGLE_EPS)
        m--;
    q->nang = m;
}

static int line_t(const fedge *e, fpt p, fpt u, long double *t)
{
    fpt d = sub(e->b, e->a), w = sub(e->a, p);
    long double den = cross(u, d);
    if (den == 0.0L)
        return 0;
    *t = cross(w, d) / den;
    return 1;
}

/* As ref_vis's ray_hits (same values), the divisions skipped when the
 * signs alone already say no: t = tn / den and s = sn / den have the signs
 * of their quotients, and |sn| > 2 |den| puts s above 1 whatever the
 * rounding. */
static int ray_hits(const fedge *e, fpt p, fpt u, long double *t)
{
    fpt d = sub(e->b, e->a), w = sub(e->a, p);
    long double den = cross(u, d), s, tn, sn;
    if (den == 0.0L)
        return 0;
    tn = cross(w, d);
    sn = cross(w, u);
    if (tn == 0.0L || (tn > 0.0L) != (den > 0.0L))
        return 0;
    if (sn != 0.0L && (sn > 0.0L) != (den > 0.0L))
        return 0;
    if (fabsl(sn) > 2.0L * fabsl(den))
        return 0;
    *t = tn / den;
    s = sn / den;
    return *t > 0.0L && s >= 0.0L && s <= 1.0L;
}

/* Tests edge i against the ray; keeps the nearest (lowest index on an exact
 * tie, as ref_vis's scan in index order) and records the hit. */
static int try_edge(fquery *q, size_t i, fpt u, long *best, long double *tmin)
{
    long double t;
    if (q->seen[i] == q->ray)
        return 0;           /* listed in an earlier cell of this ray */
    q->seen[i] = q->ray;
    if (!ray_hits(&q->e[i], q->p, u, &t))
        return 0;
    if (*best < 0 || t < *tmin || (t == *tmin && (long)i < *best)) {
        *best = (long)i;
        *tmin = t;
    }
    if (grow((void **)&q->hit, &q->caphit, q->nhit + 1, sizeof *q->hit) != 0)
        return -1;
    q->hit[q->nhit].e = i;
    q->hit[q->nhit].t = t;
    q->nhit++;
    return 0;
}

/* Index of the edge first met by the ray from p along u (-1 if none, -2 if
 * malloc fails); the owners of all edges met at that distance are marked. */
static long nearest_edge(fquery *q, fpt u)
{
    long best = -1, ix = cell_x(q->f, q->p.x), iy = cell_y(q->f, q->p.y), sx, sy;
    long double tmin = 0.0L;
    double tx, ty, dx, dy, ux = (double)u.x, uy = (double)u.y;
    size_t i;
    q->nhit = 0;
    q->ray++;
    /* the cell walk in doubles: its errors are far below the hair */
    sx = ux > 0.0 ? 1 : ux < 0.0 ? -1 : 0;
    sy = uy > 0.0 ? 1 : uy < 0.0 ? -1 : 0;
    tx = sx > 0 ? (double)((q->x0 + (long double)(ix + 1) * q->cw - q->p.x) / u.x)
         : sx < 0 ? (double)((q->x0 + (long double)ix * q->cw - q->p.x) / u.x) : HUGE_VAL;
    ty = sy > 0 ? (double)((q->y0 + (long double)(iy + 1) * q->ch - q->p.y) / u.y)
         : sy < 0 ? (double)((q->y0 + (long double)iy * q->ch - q->p.y) / u.y) : HUGE_VAL;
    dx = sx ? (double)(q->cw / fabsl(u.x)) : HUGE_VAL;
    dy = sy ? (double)(q->ch / fabsl(u.y)) : HUGE_VAL;
    for (;;) {
        size_t c = (size_t)iy * (size_t)q->nx + (size_t)ix;
        double texit = tx < ty ? tx : ty;
        for (i = q->first[c]; i < q->first[c + 1]; i++)
            if (try_edge(q, q->item[i], u, &best, &tmin) != 0)
                return -2;
        if (best >= 0 && (double)(tmin * (1.0L + F_TIE_EPS) + q->hair) < texit)
            break;
        if (tx < ty) {
            ix += sx;
            tx += dx;
        } else {
            iy += sy;
            ty += dy;
        }
        if (ix < 0 || ix >= q->nx || iy < 0 || iy >= q->ny) {
            /* out of the box: its edges, which have the highest indices
             * (they never win an exact tie) and no owner; inside, the walk
             * stops before the box when an edge is nearer */
            for (i = q->nocc; i < q->ne; i++)
                if (try_edge(q, i, u, &best, &tmin) != 0)
                    return -2;
            break;
        }
    }
    if (best < 0)
        return -1;
    for (i = 0; i < q->nhit; i++)
        if (q->e[q->hit[i].e].owner >= 0 && q->hit[i].t <= tmin * (1.0L + F_TIE_EPS))
            q->vis[q->e[q->hit[i].e].owner] = 1;
    return best;
}

static int push_poly(fquery *q, fpt x)
{
    if (grow((void **)&q->poly, &q->cappoly, q->npoly + 1, sizeof *q->poly) != 0)
        return -1;
    q->poly[q->npoly++] = x;
    return 0;
}

static int do_interval(fquery *q, long double th1, long double th2, fpt u1, fpt u2)
{
    long e = nearest_edge(q, dir(0.5L * (th1 + th2)));
    long double r1, r2;
    if (e == -2)
        return -1;
    if (e < 0 || !line_t(&q->e[e], q->p, u1, &r1) || !line_t(&q->e[e], q->p, u2, &r2))
        return 0;
    q->area += 0.5L * r1 * r2 * sinl(th2 - th1);
    if (push_poly(q, mk(q->p.x + r1 * u1.x, q->p.y + r1 * u1.y)) != 0 ||
        push_poly(q, mk(q->p.x + r2 * u2.x, q->p.y + r2 * u2.y)) != 0)
        return -1;
    return 0;
}

static long double seg_dist(fpt x, fpt a, fpt c)
{
    fpt d = sub(c, a), w = sub(x, a);
    long double dd = dot(d, d), t = 0.0L;
    if (dd > 0.0L) {
        t = dot(w, d) / dd;
        if (t < 0.0L)
            t = 0.0L;
        if (t > 1.0L)
            t = 1.0L;
    }
    w = mk(x.x - (a.x + t * d.x), x.y - (a.y + t * d.y));
    return sqrtl(dot(w, w));
}

/* ref_vis's vertex counting rule (repeated passes in array order, a point
 * within tol of the segment of its two neighbours removed), on a circular
 * linked list instead of an array. */
static uint32_t count_vertices(const fpt *v, size_t n, long double tol)
{
    size_t *nx, *pv, i, head = 0;
    int changed = 1;
    if (n < 3)
        return 0;
    nx = malloc(n * sizeof *nx);
    pv = malloc(n * sizeof *pv);
    if (!nx || !pv) {
        free(nx);
        free(pv);
        return 0;
    }
    for (i = 0; i < n; i++) {
        nx[i] = (i + 1) % n;
        pv[i] = (i + n - 1) % n;
    }
    while (changed && n >= 3) {
        size_t cur = head;
        int end = 0;
        changed = 0;
        while (!end && n >= 3) {
            size_t next = nx[cur];
            end = next == head;        /* cur is the last in array order */
            if (seg_dist(v[cur], v[pv[cur]], v[next]) <= tol) {
                nx[pv[cur]] = next;
                pv[next] = pv[cur];
                if (cur == head)
                    head = next;
                n--;
                changed = 1;
            }
            cur = next;
        }
    }
    free(nx);
    free(pv);
    return n >= 3 ? (uint32_t)n : 0;
}

static int in_sector(int full, long double a0, long double w, long double mid)
{
    return full || norm_angle(mid - a0) < w;
}

static int run_intervals(fquery *q, int *full, long double a0, long double w)
{
    size_t m = q->nang, k, j, k0 = 0, nin = 0;
    unsigned char *inc = malloc(m ? m : 1);
    int rc = 0, have = 0;
    long double last_t = 0.0L;
    fpt u1, last_u = mk(0.0L, 0.0L);
    if (!inc)
        return -1;
    for (k = 0; k < m; k++) {
        long double t1 = q->ang[k];
        long double t2 = k + 1 < m ? q->ang[k + 1] : q->ang[0] + F_TWO_PI;
        inc[k] = (unsigned char)in_sector(*full, a0, w, 0.5L * (t1 + t2));
        nin += inc[k];
    }
    if (nin == m)
        *full = 1;
    for (k = 0; !*full && k < m; k++)
        if (inc[k] && !inc[(k + m - 1) % m])
            k0 = k;
    if (!*full && nin > 0 && push_poly(q, q->p) != 0)
        rc = -1;
    for (j = 0; rc == 0 && j < m; j++) {
        long double t2;
        k = (k0 + j) % m;
        if (!inc[k])
            continue;
        /* dir(t1) is the previous interval's dir(t2) when they join (same
         * argument, same value) */
        t2 = k + 1 < m ? q->ang[k + 1] : q->ang[0] + F_TWO_PI;
        if (!have || last_t != q->ang[k])
            u1 = dir(q->ang[k]);
        else
            u1 = last_u;
        last_u = dir(t2);
        last_t = t2;
        have = 1;
        rc = do_interval(q, q->ang[k], t2, u1, last_u);
    }
    free(inc);
    return rc;
}

static int fill_result(const fquery *q, ref_vis_result *out)
{
    uint32_t i, n = 0;
    for (i = 0; i < q->s->nbld; i++)
        n += q->vis[i];
    out->area = (double)q->area;
    out->nverts = count_vertices(q->poly, q->npoly, F_VERT_TOL * q->size);
    out->nvisible = n;
    out->visible = NULL;
    if (n == 0)
        return 0;
    out->visible = malloc(n * sizeof *out->visible);
    if (!out->visible)
        return -1;
    for (i = 0, n = 0; i < q->s->nbld; i++)
        if (q->vis[i])
            out->visible[n++] = i;
    return 0;
}

ref_fast *ref_fast_new(const scene *s)
{
    const double *bb = s->bounds;
    ref_fast *f = calloc(1, sizeof *f);
    if (!f)
        return NULL;
    f->s = s;
    f->size = bb[2] - bb[0] > bb[3] - bb[1] ? bb[2] - bb[0] : bb[3] - bb[1];
    f->hair = F_HAIR * f->size;
    if (edges_make(f) != 0 || grid_make(f) != 0 || meeting_points(f) != 0 ||
        event_points(f) != 0) {
        ref_fast_free(f);
        return NULL;
    }
    return f;
}

void ref_fast_free(ref_fast *f)
{
    if (!f)
        return;
    free(f->e);
    free(f->first);
    free(f->item);
    free(f->mp);
    free(f);
}

static int fast_core(const ref_fast *f, double px, double py, int full, long double a0,
                     long double w, ref_vis_result *out)
{
    fquery q;
    const scene *s = f->s;
    int rc;
    memset(out, 0, sizeof *out);
    rc = classify(s, px, py);
    if (rc != 0)
        return rc;
    memset(&q, 0, sizeof q);
    q.f = f;
    q.s = s;
    q.p = mk(px, py);
    q.e = f->e;
    q.ne = f->ne;
    q.nocc = f->nocc;
    q.size = f->size;
    q.hair = f->hair;
    q.x0 = f->x0;
    q.y0 = f->y0;
    q.cw = f->cw;
    q.ch = f->ch;
    q.nx = f->nx;
    q.ny = f->ny;
    q.first = f->first;
    q.item = f->item;
    q.vis = calloc(s->nbld ? s->nbld : 1, 1);
    q.seen = calloc(q.ne, sizeof *q.seen);
    rc = (!q.vis || !q.seen || events(&q) != 0) ? -1 : 0;
    if (rc == 0 && !full)
        rc = push_angle(&q, a0) || push_angle(&q, norm_angle(a0 + w)) ? -1 : 0;
    if (rc == 0) {
        sort_merge(&q);
        rc = run_intervals(&q, &full, a0, w);
    }
    if (rc == 0)
        rc = fill_result(&q, out);
    free(q.ang);
    free(q.hit);
    free(q.seen);
    free(q.vis);
    free(q.poly);
    if (rc != 0) {
        ref_vis_free(out);
        return -3;
    }
    return 0;
}

int ref_fast_vis(const ref_fast *f, double px, double py, ref_vis_result *out)
{
    return fast_core(f, px, py, 1, 0.0L, F_TWO_PI, out);
}

int ref_fast_vis_range(const ref_fast *f, double px, double py, double a0, double a1,
                       ref_vis_result *out)
{
    long double diff = (long double)a1 - (long double)a0;
    if (diff >= F_TWO_PI)
        return fast_core(f, px, py, 1, 0.0L, F_TWO_PI, out);
    return fast_core(f, px, py, 0, norm_angle(a0), norm_angle(diff), out);
}

int ref_vis_fast(const scene *s, double px, double py, ref_vis_result *out)
{
    ref_fast *f = ref_fast_new(s);
    int rc;
    if (!f) {
        memset(out, 0, sizeof *out);
        return -3;
    }
    rc = ref_fast_vis(f, px, py, out);
    ref_fast_free(f);
    return rc;
}

int ref_vis_fast_range(const scene *s, double px, double py, double a0, double a1,
                       ref_vis_result *out)
{
    ref_fast *f = ref_fast_new(s);
    int rc;
    if (!f) {
        memset(out, 0, sizeof *out);
        return -3;
    }
    rc = ref_fast_vis_range(f, px, py, a0, a1, out);
    ref_fast_free(f);
    return rc;
}
