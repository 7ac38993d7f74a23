/* meterapi: SPEC §6 pedestrian metrics at points and along routes, and the
 * P classes with the facial-recognition criterion. */
#include <math.h>
#include <string.h>

#include "base/engine.h"
#include "light/light.h"

static const double p_mean[6] = { 15.0, 10.0, 7.5, 5.0, 3.0, 2.0 };
static const double p_min[6] = { 3.0, 2.0, 1.5, 1.0, 0.6, 0.4 };
static const double p_ev[6] = { 5.0, 3.0, 2.5, 1.5, 1.0, 0.6 };
static const double p_esc[6] = { 5.0, 2.0, 1.5, 1.0, 0.6, 0.2 };

int plx_p_class_facial(double mean, double min, double min_ev, double min_esc)
{
    int k;
    for (k = 0; k < 6; k++)
        if (mean >= p_mean[k] && min >= p_min[k] && min_ev >= p_ev[k] && min_esc >= p_esc[k])
            return k + 1;
    return 0;
}

/* A point is a meter unless strictly inside a solid or below the ground
 * (plx_illuminance's check: it fails with PLX_E_RANGE and NaN). */
static int meter_ok(plx_engine *e, const double P[3])
{
    static const double up[3] = { 0.0, 0.0, 1.0 };
    double E;
    return plx_illuminance(e, 1, P, up, &E, NULL, NULL) == PLX_OK;
}

plx_status plx_meter(plx_engine *e, size_t n, const double *P, const double *U, double *out)
{
    size_t k;
    int bad = 0;
    char first[ENGINE_ERR_BYTES];
    plx_status st = eng_need_light(e, "plx_meter");
    if (st != PLX_OK)
        return st;
    if (n && (!P || !out))
        return eng_fail(e, PLX_E_INVALID, "plx_meter: P and out must not be NULL");
    first[0] = '\0';
    for (k = 0; k < n; k++) {
        double u[2] = { 1.0, 0.0 }, l;
        int c;
        if (U) {
            l = hypot(U[2 * k], U[2 * k + 1]);
            if (!(l > 0.0) || !isfinite(l))
                return eng_fail(e, PLX_E_INVALID, "plx_meter: a facing direction is zero or not finite");
            u[0] = U[2 * k] / l;
            u[1] = U[2 * k + 1] / l;
        }
        if (!meter_ok(e, P + 3 * k)) {
            for (c = 0; c < PLX_METER_COUNT; c++)
                out[4 * k + (size_t)c] = NAN;
            if (!bad++)
                memcpy(first, e->err, sizeof first);
            continue;
        }
        light_meter(e->lt, P + 3 * k, u, out + 4 * k);
    }
    if (bad) {
        memcpy(e->err, first, sizeof first);
        return PLX_E_RANGE;
    }
    eng_clear_error(e);
    return PLX_OK;
}

/* min E_v and E_sc both ways over one segment's samples (NaN: none). */
static void facial_segment(plx_engine *e, const double *a, const double *b, double step, double height,
                           double out[4])
{
    double len = hypot(b[0] - a[0], b[1] - a[1]), u[2][2];
    uint32_t k = (uint32_t)fmin(ceil(len / step), 1e7), i;
    int d;
    out[0] = out[1] = out[2] = out[3] = NAN;
    if (k < 1)
        k = 1;
    u[0][0] = len > 0.0 ? (b[0] - a[0]) / len : 1.0;
    u[0][1] = len > 0.0 ? (b[1] - a[1]) / len : 0.0;
    u[1][0] = -u[0][0];
    u[1][1] = -u[0][1];
    for (i = 0; i <= k; i++) {
        double t = (double)i / k, P[3], m[4];
        P[0] = a[0] + t * (b[0] - a[0]);
        P[1] = a[1] + t * (b[1] - a[1]);
        P[2] = height;
        if (!meter_ok(e, P))
            continue;
        for (d = 0; d < 2; d++) {
            light_meter(e->lt, P, u[d], m);
            out[d] = out[d] == out[d] ? fmin(out[d], m[PLX_METER_V]) : m[PLX_METER_V];
            out[2 + d] = out[2 + d] == out[2 + d] ? fmin(out[2 + d], m[PLX_METER_SC]) : m[PLX_METER_SC];
        }
    }
}

plx_status plx_route_facial(plx_engine *e, const double *xy, uint32_t n, double step, double height,
                            double *seg, double total[4])
{
    uint32_t i;
    int c;
    double all[4] = { NAN, NAN, NAN, NAN };
    plx_status st = eng_need_light(e, "plx_route_facial");
    if (st != PLX_OK)
        return st;
    if (!xy || n < 2 || !(step > 0) || !isfinite(step) || !(height >= 0) || !isfinite(height))
        return eng_fail(e, PLX_E_INVALID, "plx_route_facial: needs 2 or more vertices, step > 0, height >= 0");
    for (i = 0; i < 2 * n; i++)
        if (!isfinite(xy[i]))
            return eng_fail(e, PLX_E_INVALID, "plx_route_facial: a vertex is not finite");
    for (i = 0; i + 1 < n; i++) {
        double s4[4];
        facial_segment(e, xy + 2 * i, xy + 2 * i + 2, step, height, s4);
        for (c = 0; c < 4; c++)
            if (s4[c] == s4[c])
                all[c] = all[c] == all[c] ? fmin(all[c], s4[c]) : s4[c];
        if (seg)
            memcpy(seg + 4 * (size_t)i, s4, sizeof s4);
    }
    if (total)
        memcpy(total, all, sizeof all);
    eng_clear_error(e);
    return PLX_OK;
}
