/* ref_vis: brute-force angular sweep for SPEC §3 (contract in ref_vis.h). */
#include "ref_vis.h"
#include "ref_scene.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#define REF_PI 3.141592653589793238462643383279502884L
#define TWO_PI (2.0L * REF_PI)
#define ANGLE_EPS 1e-12L  /* directions closer than this are one event */
#define TIE_EPS 1e-12L    /* relative distance tie for the nearest edge */
#define VERT_TOL 1e-10L   /* vertex merge tolerance, times the box size */

typedef struct lpt { long double x, y; } lpt;

/* An edge a->b; owner is the building index, or -1 for a box edge. */
typedef struct vedge { lpt a, b; long owner; } vedge;

typedef struct lvec { long double *v; size_t n, cap; } lvec;
typedef struct pvec { lpt *v; size_t n, cap; } pvec;

/* Everything the sweep reads and accumulates. */
typedef struct sweep {
    const scene *s;
    lpt p;
    vedge *e;
    size_t ne;
    unsigned char *vis;   /* per building: seen in some interval */
    pvec poly;            /* boundary points, ccw */
    long double area;
} sweep;

static lpt mk(long double x, long double y) { lpt r; r.x = x; r.y = y; return r; }
static lpt sub(lpt a, lpt b) { return mk(a.x - b.x, a.y - b.y); }
static long double cross(lpt u, lpt v) { return u.x * v.y - u.y * v.x; }
static long double dot(lpt u, lpt v) { return u.x * v.x + u.y * v.y; }
static lpt dir(long double th) { return mk(cosl(th), sinl(th)); }

/* Angle reduced into [0, 2pi). */
static long double norm_angle(long double a)
{
    a = fmodl(a, TWO_PI);
    if (a < 0.0L)
        a += TWO_PI;
    if (a >= TWO_PI)
        a -= TWO_PI;
    return a;
}

static int is_occluder(const scene_building *b)
{
    return !(b->min_height > 0.0);
}

static int lvec_push(lvec *a, long double x)
{
    if (a->n == a->cap) {
        size_t cap = a->cap ? 2 * a->cap : 64;
        long double *v = realloc(a->v, cap * sizeof *v);
        if (!v)
            return -1;
        a->v = v;
        a->cap = cap;
    }
    a->v[a->n++] = x;
    return 0;
}

static int pvec_push(pvec *a, lpt x)
{
    if (a->n == a->cap) {
        size_t cap = a->cap ? 2 * a->cap : 64;
        lpt *v = realloc(a->v, cap * sizeof *v);
        if (!v)
            return -1;
        a->v = v;
        a->cap = cap;
    }
    a->v[a->n++] = x;
    return 0;
}

/* 0 if p is free, -1 outside the box or inside a footprint, -2 on a
 * boundary (box or footprint) and in no footprint interior. */
static int classify_point(const scene *s, long double px, long double py)
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

/* All occluder ring edges plus the 4 box edges; NULL if malloc fails. */
static vedge *collect_edges(const scene *s, size_t *ne)
{
    size_t n = 4, k = 0;
    uint32_t i, r, j;
    vedge *e;
    const double *bb = s->bounds;
    lpt c[4];
    for (i = 0; i < s->nbld; i++)
        if (is_occluder(&s->bld[i]))
            for (r = 0; r < s->bld[i].ring_count; r++)
                n += s->rings[s->bld[i].ring_first + r].count;
    e = malloc(n * sizeof *e);
    if (!e)
        return NULL;
    for (i = 0; i < s->nbld; i++) {
        if (!is_occluder(&s->bld[i]))
            continue;
        for (r = 0; r < s->bld[i].ring_count; r++) {
            const scene_ring *rg = &s->rings[s->bld[i].ring_first + r];
            for (j = 0; j < rg->count; j++) {
                const vec2 *a = &s->pts[rg->first + j];
                const vec2 *b = &s->pts[rg->first + (j + 1) % rg->count];
                e[k].a = mk(a->x, a->y);
                e[k].b = mk(b->x, b->y);
                e[k].owner = (long)i;
                k++;
            }
        }
    }
    c[0] = mk(bb[0], bb[1]);
    c[1] = mk(bb[2], bb[1]);
    c[2] = mk(bb[2], bb[3]);
    c[3] = mk(bb[0], bb[3]);
    for (j = 0; j < 4; j++) {
        e[k].a = c[j];
        e[k].b = c[(j + 1) % 4];
        e[k].owner = -1;
        k++;
    }
    *ne = n;
    return e;
}

/* Pushes the direction from p to q (nothing if q == p). */
static int push_direction(lvec *ang, lpt p, lpt q)
{
    lpt d = sub(q, p);
    if (d.x == 0.0L && d.y == 0.0L)
        return 0;
    return lvec_push(ang, norm_angle(atan2l(d.y, d.x)));
}

/* If the closed segments e and f meet at a single point, stores it in *x. */
static int edge_crossing(const vedge *e, const vedge *f, lpt *x)
{
    lpt d1 = sub(e->b, e->a), d2 = sub(f->b, f->a), w = sub(f->a, e->a);
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

/* Event directions: every edge start (each vertex starts one edge) and every
 * crossing of two edges. */
static int collect_events(const sweep *sw, lvec *ang)
{
    size_t i, j;
    for (i = 0; i < sw->ne; i++)
        if (push_direction(ang, sw->p, sw->e[i].a) != 0)
            return -1;
    for (i = 0; i < sw->ne; i++) {
        for (j = i + 1; j < sw->ne; j++) {
            lpt x;
            if (edge_crossing(&sw->e[i], &sw->e[j], &x) &&
                push_direction(ang, sw->p, x) != 0)
                return -1;
        }
    }
    return 0;
}

static int cmp_ld(const void *a, const void *b)
{
    long double x = *(const long double *)a, y = *(const long double *)b;
    return (x > y) - (x < y);
}

/* Sorts the angles and merges those within ANGLE_EPS (also across 2pi). */
static void sort_merge(lvec *ang)
{
    size_t i, m = 0;
    if (ang->n == 0)
        return;
    qsort(ang->v, ang->n, sizeof *ang->v, cmp_ld);
    for (i = 0; i < ang->n; i++)
        if (m == 0 || ang->v[i] - ang->v[m - 1] > ANGLE_EPS)
            ang->v[m++] = ang->v[i];
    while (m > 1 && ang->v[m - 1] >= ang->v[0] + TWO_PI - ANGLE_EPS)
        m--;
    ang->n = m;
}

/* Distance along unit direction u from p to the supporting line of e;
 * returns 0 when the line is parallel to u. */
static int line_t(const vedge *e, lpt p, lpt u, long double *t)
{
    lpt d = sub(e->b, e->a), w = sub(e->a, p);
    long double den = cross(u, d);
    if (den == 0.0L)
        return 0;
    *t = cross(w, d) / den;
    return 1;
}

/* 1 if the ray p + t u, t > 0, meets the closed edge e; *t is where. */
static int ray_hits(const vedge *e, lpt p, lpt u, long double *t)
{
    lpt d = sub(e->b, e->a), w = sub(e->a, p);
    long double den = cross(u, d), s;
    if (den == 0.0L)
        return 0;
    *t = cross(w, d) / den;
    s = cross(w, u) / den;
    return *t > 0.0L && s >= 0.0L && s <= 1.0L;
}

/* Index of the edge first met by the ray from p along u (-1 if none), and
 * the owners of all edges met at that distance are marked visible. */
static long nearest_edge(sweep *sw, lpt u)
{
    long best = -1;
    long double tmin = 0.0L, t;
    size_t i;
    for (i = 0; i < sw->ne; i++)
        if (ray_hits(&sw->e[i], sw->p, u, &t) && (best < 0 || t < tmin)) {
            best = (long)i;
            tmin = t;
        }
    if (best < 0)
        return -1;
    for (i = 0; i < sw->ne; i++)
        if (sw->e[i].owner >= 0 && ray_hits(&sw->e[i], sw->p, u, &t) &&
            t <= tmin * (1.0L + TIE_EPS))
            sw->vis[sw->e[i].owner] = 1;
    return best;
}

/* The open interval (th1, th2): its triangle's area and its two boundary
 * points. */
static int do_interval(sweep *sw, long double th1, long double th2)
{
    lpt u1 = dir(th1), u2 = dir(th2);
    long e = nearest_edge(sw, dir(0.5L * (th1 + th2)));
    long double r1, r2;
    if (e < 0 || !line_t(&sw->e[e], sw->p, u1, &r1) ||
        !line_t(&sw->e[e], sw->p, u2, &r2))
        return 0;  /* cannot happen with p strictly inside the box */
    sw->area += 0.5L * r1 * r2 * sinl(th2 - th1);
    if (pvec_push(&sw->poly, mk(sw->p.x + r1 * u1.x, sw->p.y + r1 * u1.y)) != 0 ||
        pvec_push(&sw->poly, mk(sw->p.x + r2 * u2.x, sw->p.y + r2 * u2.y)) != 0)
        return -1;
    return 0;
}

/* Distance from q to the closed segment ac. */
static long double seg_dist(lpt q, lpt a, lpt c)
{
    lpt d = sub(c, a), w = sub(q, a);
    long double dd = dot(d, d), t = 0.0L;
    if (dd > 0.0L) {
        t = dot(w, d) / dd;
        if (t < 0.0L) t = 0.0L;
        if (t > 1.0L) t = 1.0L;
    }
    w = mk(q.x - (a.x + t * d.x), q.y - (a.y + t * d.y));
    return sqrtl(dot(w, w));
}

/* The vertex counting rule of ref_vis.h; edits v in place. */
static uint32_t count_vertices(lpt *v, size_t n, long double tol)
{
    int changed = 1;
    while (changed && n >= 3) {
        size_t i = 0;
        changed = 0;
        while (i < n && n >= 3) {
            lpt a = v[(i + n - 1) % n], c = v[(i + 1) % n];
            if (seg_dist(v[i], a, c) <= tol) {
                memmove(v + i, v + i + 1, (n - i - 1) * sizeof *v);
                n--;
                changed = 1;
            } else {
                i++;
            }
        }
    }
    return n >= 3 ? (uint32_t)n : 0;
}

/* Whether the interval with middle direction mid lies in the sector. */
static int in_sector(int full, long double a0, long double w, long double mid)
{
    return full || norm_angle(mid - a0) < w;
}

/* Runs the intervals of the sorted events in ccw order, starting after a
 * gap of the sector when there is one; *full is set when every interval
 * is inside. */
static int run_intervals(sweep *sw, const lvec *ang, int *full,
                         long double a0, long double w)
{
    size_t m = ang->n, k, j, k0 = 0, nin = 0;
    unsigned char *inc = malloc(m ? m : 1);
    int rc = 0;
    if (!inc)
        return -1;
    for (k = 0; k < m; k++) {
        long double t1 = ang->v[k];
        long double t2 = k + 1 < m ? ang->v[k + 1] : ang->v[0] + TWO_PI;
        inc[k] = (unsigned char)in_sector(*full, a0, w, 0.5L * (t1 + t2));
        nin += inc[k];
    }
    if (nin == m)
        *full = 1;
    for (k = 0; !*full && k < m; k++)
        if (inc[k] && !inc[(k + m - 1) % m])
            k0 = k;
    if (!*full && nin > 0 && pvec_push(&sw->poly, sw->p) != 0)
        rc = -1;
    for (j = 0; rc == 0 && j < m; j++) {
        k = (k0 + j) % m;
        if (inc[k])
            rc = do_interval(sw, ang->v[k],
                             k + 1 < m ? ang->v[k + 1] : ang->v[0] + TWO_PI);
    }
    free(inc);
    return rc;
}

/* Fills out from the finished sweep. */
static int fill_result(const sweep *sw, ref_vis_result *out)
{
    const double *bb = sw->s->bounds;
    double size = bb[2] - bb[0] > bb[3] - bb[1] ? bb[2] - bb[0] : bb[3] - bb[1];
    uint32_t i, n = 0;
    for (i = 0; i < sw->s->nbld; i++)
        n += sw->vis[i];
    out->area = (double)sw->area;
    out->nverts = count_vertices(sw->poly.v, sw->poly.n, VERT_TOL * size);
    out->nvisible = n;
    out->visible = NULL;
    if (n == 0)
        return 0;
    out->visible = malloc(n * sizeof *out->visible);
    if (!out->visible)
        return -1;
    for (i = 0, n = 0; i < sw->s->nbld; i++)
        if (sw->vis[i])
            out->visible[n++] = i;
    return 0;
}

static int vis_core(const scene *s, double px, double py, int full,
                    long double a0, long double w, ref_vis_result *out)
{
    sweep sw;
    lvec ang = { NULL, 0, 0 };
    int rc;
    memset(out, 0, sizeof *out);
    rc = classify_point(s, px, py);
    if (rc != 0)
        return rc;
    memset(&sw, 0, sizeof sw);
    sw.s = s;
    sw.p = mk(px, py);
    sw.e = collect_edges(s, &sw.ne);
    sw.vis = calloc(s->nbld ? s->nbld : 1, 1);
    rc = (!sw.e || !sw.vis) ? -1 : collect_events(&sw, &ang);
    if (rc == 0 && !full)
        rc = lvec_push(&ang, a0) || lvec_push(&ang, norm_angle(a0 + w)) ? -1 : 0;
    if (rc == 0) {
        sort_merge(&ang);
        rc = run_intervals(&sw, &ang, &full, a0, w);
    }
    if (rc == 0)
        rc = fill_result(&sw, out);
    free(sw.e);
    free(sw.vis);
    free(sw.poly.v);
    free(ang.v);
    if (rc != 0) {
        ref_vis_free(out);
        return -3;
    }
    return 0;
}

int ref_vis(const scene *s, double px, double py, ref_vis_result *out)
{
    return vis_core(s, px, py, 1, 0.0L, TWO_PI, out);
}

int ref_vis_range(const scene *s, double px, double py, double a0, double a1,
                  ref_vis_result *out)
{
    long double diff = (long double)a1 - (long double)a0;
    if (diff >= TWO_PI)
        return vis_core(s, px, py, 1, 0.0L, TWO_PI, out);
    return vis_core(s, px, py, 0, norm_angle(a0), norm_angle(diff), out);
}

void ref_vis_free(ref_vis_result *out)
{
    free(out->visible);
    memset(out, 0, sizeof *out);
}
