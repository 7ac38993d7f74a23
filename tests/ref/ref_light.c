/* ref_light: brute-force direct light for SPEC §2 (contract in ref_light.h). */
#include "ref_light.h"
#include "ref_scene.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>

#define MIN_PIECE 1e-9L  /* m: shorter contacts with a solid are grazing */

/* Break parameters of the segment for one building: at most 4 + 2 per edge. */
typedef struct tbuf { long double *t; size_t n, cap; } tbuf;

static void add_param(tbuf *b, long double t)
{
    if (t > 0.0L && t < 1.0L && b->n < b->cap)
        b->t[b->n++] = t;
}

static int cmp_ld(const void *a, const void *b)
{
    long double x = *(const long double *)a, y = *(const long double *)b;
    return (x > y) - (x < y);
}

/* Parameters where the 2D projection L + t D (D != 0) meets edge a->b: the
 * crossing, or for a parallel edge the projections of both end points (the
 * ends of a run along a collinear wall; extra breaks are harmless). */
static void edge_params(tbuf *b, const long double L[3], long double dx,
                        long double dy, const vec2 *a, const vec2 *c)
{
    long double ex = (long double)c->x - a->x, ey = (long double)c->y - a->y;
    long double wx = a->x - L[0], wy = a->y - L[1];
    long double den = dx * ey - dy * ex;
    if (den != 0.0L) {
        long double t = (wx * ey - wy * ex) / den;
        long double s = (wx * dy - wy * dx) / den;
        if (s >= 0.0L && s <= 1.0L)
            add_param(b, t);
    } else {
        long double dd = dx * dx + dy * dy;
        add_param(b, (wx * dx + wy * dy) / dd);
        add_param(b, ((c->x - L[0]) * dx + (c->y - L[1]) * dy) / dd);
    }
}

/* All break parameters of segment L + t D, t in [0, 1], for building bi:
 * the ends, the z-slab limits and the footprint boundary meetings. Between
 * two consecutive breaks, being in the slab and being inside the footprint
 * are both constant. */
static void collect_breaks(const scene *s, uint32_t bi, const long double L[3],
                           const long double D[3], tbuf *b)
{
    const scene_building *bd = &s->bld[bi];
    uint32_t r, j;
    b->n = 0;
    b->t[b->n++] = 0.0L;
    b->t[b->n++] = 1.0L;
    if (D[2] != 0.0L) {
        add_param(b, (bd->min_height - L[2]) / D[2]);
        add_param(b, (bd->height - L[2]) / D[2]);
    }
    /* vertical (D[0] == D[1] == 0): the footprint status is constant */
    for (r = 0; (D[0] != 0.0L || D[1] != 0.0L) && r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        for (j = 0; j < rg->count; j++)
            edge_params(b, L, D[0], D[1], &s->pts[rg->first + j],
                        &s->pts[rg->first + (j + 1) % rg->count]);
    }
    qsort(b->t, b->n, sizeof *b->t, cmp_ld);
}

/* 1 if some piece between consecutive breaks, longer than MIN_PIECE, has its
 * middle inside the open z-slab and strictly inside the footprint. */
static int blocked_by(const scene *s, uint32_t bi, const long double L[3],
                      const long double D[3], long double len, tbuf *b)
{
    const scene_building *bd = &s->bld[bi];
    size_t i;
    collect_breaks(s, bi, L, D, b);
    for (i = 0; i + 1 < b->n; i++) {
        long double m = 0.5L * (b->t[i] + b->t[i + 1]), z;
        if ((b->t[i + 1] - b->t[i]) * len <= MIN_PIECE)
            continue;
        z = L[2] + m * D[2];
        if (z > bd->min_height && z < bd->height &&
            ref_footprint_where(s, bi, L[0] + m * D[0], L[1] + m * D[1]) == REF_IN)
            return 1;
    }
    return 0;
}

/* Largest number of ring vertices of one building. */
static size_t max_building_vertices(const scene *s)
{
    size_t best = 0;
    uint32_t i, r;
    for (i = 0; i < s->nbld; i++) {
        size_t n = 0;
        for (r = 0; r < s->bld[i].ring_count; r++)
            n += s->rings[s->bld[i].ring_first + r].count;
        if (n > best)
            best = n;
    }
    return best;
}

/* Returns 1 blocked, 0 free, -1 if malloc fails. */
int ref_segment_blocked(const scene *s, const double L[3], const double P[3])
{
    long double l[3], d[3], len;
    tbuf b;
    uint32_t i;
    int hit = 0;
    for (i = 0; i < 3; i++) {
        l[i] = L[i];
        d[i] = (long double)P[i] - L[i];
    }
    len = sqrtl(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (len == 0.0L || s->nbld == 0)
        return 0;
    b.cap = 4 + 2 * max_building_vertices(s);
    b.n = 0;
    b.t = malloc(b.cap * sizeof *b.t);
    if (!b.t)
        return -1;
    for (i = 0; i < s->nbld && !hit; i++)
        hit = blocked_by(s, i, l, d, len, &b);
    free(b.t);
    return hit;
}

double ref_window(double x)
{
    long double x2 = (long double)x * x, c = 1.0L - x2 * x2;
    if (c < 0.0L) c = 0.0L;
    if (c > 1.0L) c = 1.0L;
    return (double)(c * c);
}

/* One lamp's uncoloured term at P (visibility included); NaN if malloc
 * fails in the segment test. */
static long double lamp_term(const scene *s, const scene_lamp *lp,
                             const double P[3], const double n[3])
{
    double L[3];
    long double v[3], d, cosw, w;
    int blk;
    L[0] = lp->x; L[1] = lp->y; L[2] = lp->z;
    v[0] = (long double)L[0] - P[0];
    v[1] = (long double)L[1] - P[1];
    v[2] = (long double)L[2] - P[2];
    d = sqrtl(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (d == 0.0L || !(lp->radius > 0.0))
        return 0.0L;
    w = ref_window((double)(d / lp->radius));
    cosw = (n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / d;
    if (w == 0.0L || cosw <= 0.0L)
        return 0.0L;
    blk = ref_segment_blocked(s, L, P);
    if (blk < 0)
        return NAN;
    if (blk)
        return 0.0L;
    return lp->intensity * cosw / (d * d) * w;
}

double ref_illuminance(const scene *s, const double P[3], const double n[3])
{
    long double e = 0.0L;
    uint32_t i;
    for (i = 0; i < s->nlamps; i++)
        e += lamp_term(s, &s->lamps[i], P, n);
    return (double)e;
}

void ref_illuminance_rgb(const scene *s, const double P[3], const double n[3],
                         double rgb[3])
{
    long double e[3] = { 0.0L, 0.0L, 0.0L };
    uint32_t i, c;
    for (i = 0; i < s->nlamps; i++) {
        long double t = lamp_term(s, &s->lamps[i], P, n);
        for (c = 0; c < 3; c++)
            e[c] += t * s->lamps[i].color[c];
    }
    for (c = 0; c < 3; c++)
        rgb[c] = (double)e[c];
}
