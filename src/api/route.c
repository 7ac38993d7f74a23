/* route: how well lit is a path (EN 13201 P-classes over SPEC §2 light). */
#include <math.h>
#include <string.h>

#include "base/engine.h"

/* EN 13201-2 P-classes: average and minimum maintained illuminance. */
static const double p_mean[6] = { 15.0, 10.0, 7.5, 5.0, 3.0, 2.0 };
static const double p_min[6] = { 3.0, 2.0, 1.5, 1.0, 0.6, 0.4 };

int plx_p_class(double mean, double min)
{
    int k;
    for (k = 0; k < 6; k++)
        if (mean >= p_mean[k] && min >= p_min[k])
            return k + 1;
    return 0;
}

/* Running sums of one stretch of path. */
typedef struct acc {
    double integral, length, min, max, dark, blocked;
    uint32_t samples;
    int dark_at_point; /* a sample below dark_lux (a stretch of no length weighs none) */
} acc;

static void acc_init(acc *a)
{
    memset(a, 0, sizeof *a);
    a->min = INFINITY;
    a->max = -INFINITY;
}

static void acc_merge(acc *to, const acc *a)
{
    to->integral += a->integral;
    to->length += a->length;
    to->dark += a->dark;
    to->blocked += a->blocked;
    to->samples += a->samples;
    to->dark_at_point |= a->dark_at_point;
    to->min = fmin(to->min, a->min);
    to->max = fmax(to->max, a->max);
}

static void acc_stats(const acc *a, plx_route_stats *out)
{
    memset(out, 0, sizeof *out);
    out->length = a->length;
    out->samples = a->samples;
    out->blocked_length = a->blocked;
    if (a->length > 0) {
        out->mean = a->integral / a->length;
        out->min = a->min;
        out->max = a->max;
        out->uniformity = out->mean > 0 ? out->min / out->mean : 0.0;
        out->dark_share = a->dark / a->length;
        out->p_class = plx_p_class(out->mean, out->min);
    } else if (a->samples > 0) {
        /* a stretch of no length (a repeated vertex) that was scored: its
         * samples are one point, so its mean is that point's light, the
         * limit of a short stretch's (it read 0 lx: a false dark segment) */
        out->mean = out->min = a->min;
        out->max = a->max;
        out->uniformity = out->mean > 0 ? 1.0 : 0.0;
        out->dark_share = a->dark_at_point ? 1.0 : 0.0;
        out->p_class = plx_p_class(out->mean, out->min);
    }
}

/* Samples one segment: k+1 points, trapezoid weights. */
static plx_status score_segment(plx_engine *e, const double *a, const double *b, double step,
                                double dark_lux, acc *out)
{
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    uint32_t k, i;
    arena_mark m = arena_get_mark(&e->mem);
    double *P, *N, *Ed, *Ei, w;
    plx_status st;
    if (!(ceil(len / step) <= 1e7)) /* never sampled more coarsely than asked */
        return eng_fail(e, PLX_E_INVALID, "plx_route_score: a segment needs more than 1e7 samples at this step");
    k = (uint32_t)ceil(len / step);
    if (k < 1)
        k = 1;
    w = len / k;
    P = arena_scratch(&e->mem, arena_mul(k + 1, 8 * sizeof(double)), 16);
    if (!P)
        return eng_nomem(e, "sampling a route");
    N = P + 3 * (k + 1);
    Ed = N + 3 * (k + 1);
    Ei = Ed + (k + 1);
    for (i = 0; i <= k; i++) {
        double t = (double)i / k;
        P[3 * i] = a[0] + t * (b[0] - a[0]);
        P[3 * i + 1] = a[1] + t * (b[1] - a[1]);
        P[3 * i + 2] = 0.0;
        N[3 * i] = N[3 * i + 1] = 0.0;
        N[3 * i + 2] = 1.0;
    }
    st = plx_illuminance(e, k + 1, P, N, Ed, Ei, NULL);
    if (st != PLX_OK && st != PLX_E_RANGE) {
        arena_release(&e->mem, &m);
        return st;
    }
    acc_init(out);
    for (i = 0; i <= k; i++) {
        double wi = (i == 0 || i == k) ? w / 2 : w, E = Ed[i] + Ei[i];
        if (len == 0.0)
            wi = 0.0;
        if (E != E) { /* inside a footprint */
            out->blocked += wi;
            continue;
        }
        out->samples++;
        out->integral += wi * E;
        out->length += wi;
        if (E < dark_lux) {
            out->dark += wi;
            out->dark_at_point = 1;
        }
        out->min = fmin(out->min, E);
        out->max = fmax(out->max, E);
    }
    arena_release(&e->mem, &m);
    eng_clear_error(e);
    return PLX_OK;
}

plx_status plx_route_score(plx_engine *e, const double *xy, uint32_t n, double step, double dark_lux,
                           plx_route_stats *total, plx_route_stats *segments)
{
    acc all, seg;
    uint32_t i;
    plx_status st;
    arena_mark m0;
    int built;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (!xy || n < 2 || !(step > 0) || !isfinite(step) || !(dark_lux >= 0))
        return eng_fail(e, PLX_E_INVALID, "plx_route_score: needs 2 or more vertices, step > 0, dark_lux >= 0");
    for (i = 0; i < 2 * n; i++)
        if (!isfinite(xy[i]))
            return eng_fail(e, PLX_E_INVALID, "plx_route_score: a vertex is not finite");
    /* the light object is built here, before score_segment takes its arena
     * mark: built inside plx_illuminance it would lie above the mark, and the
     * release would hand its memory out again while e->lt still points at it */
    built = e->lt == NULL;
    m0 = arena_get_mark(&e->mem);
    st = eng_need(e, ENG_LIGHT, "plx_route_score");
    if (st != PLX_OK)
        return st;
    acc_init(&all);
    for (i = 0; i + 1 < n; i++) {
        st = score_segment(e, xy + 2 * i, xy + 2 * i + 2, step, dark_lux, &seg);
        if (st != PLX_OK) {
            if (built) { /* a failed call leaves the engine as it was */
                e->lt = NULL;
                arena_release(&e->mem, &m0);
            }
            return st;
        }
        if (segments)
            acc_stats(&seg, &segments[i]);
        acc_merge(&all, &seg);
    }
    if (total)
        acc_stats(&all, total);
    return PLX_OK;
}
