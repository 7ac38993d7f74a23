/* meterapi: SPEC §6 pedestrian metrics at points and along routes, and the
 * P classes with the facial-recognition criterion. */
#include <math.h>
#include <string.h>

#include "base/engine.h"
#include "light/light.h"
#include "light/illuminance.h"
#include "light/meter.h"
#include "light/litregion.h"

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
    plx_status st = eng_need(e, ENG_LIGHT, "plx_meter");
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

/* The unit vector from a to b into u; 0 (u unchanged) when they are one point. */
static int unit_along(const double *a, const double *b, double u[2])
{
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    if (!(len > 0.0))
        return 0;
    u[0] = (b[0] - a[0]) / len;
    u[1] = (b[1] - a[1]) / len;
    return 1;
}

/* min E_v and E_sc both ways over one segment's samples (NaN: none),
 * facing along fw (a unit vector) and back. */
static void facial_segment(plx_engine *e, const double *a, const double *b, const double fw[2], double step,
                           double height, double out[4])
{
    double len = hypot(b[0] - a[0], b[1] - a[1]), u[2][2];
    uint32_t k = (uint32_t)fmin(ceil(len / step), 1e7), i;
    int d;
    out[0] = out[1] = out[2] = out[3] = NAN;
    if (k < 1)
        k = 1;
    u[0][0] = fw[0];
    u[0][1] = fw[1];
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

/* The walker's direction along segment i of the polyline xy (n vertices):
 * its own, or for a segment of no length (a repeated vertex) the next
 * segment's with a length, else the previous one's (east when the line
 * has none): such a segment's point is met walking that way, and facing
 * east gave it an arbitrary E_v. */
static void walking_direction(const double *xy, uint32_t n, uint32_t i, double fw[2])
{
    uint32_t j;
    fw[0] = 1.0;
    fw[1] = 0.0;
    for (j = i; j + 1 < n; j++)
        if (unit_along(xy + 2 * j, xy + 2 * j + 2, fw))
            return;
    for (j = i; j-- > 0;)
        if (unit_along(xy + 2 * j, xy + 2 * j + 2, fw))
            return;
}

plx_status plx_route_facial(plx_engine *e, const double *xy, uint32_t n, double step, double height,
                            double *seg, double total[4])
{
    uint32_t i;
    int c;
    double all[4] = { NAN, NAN, NAN, NAN };
    plx_status st = eng_need(e, ENG_LIGHT, "plx_route_facial");
    if (st != PLX_OK)
        return st;
    if (!xy || n < 2 || !(step > 0) || !isfinite(step) || !(height >= 0) || !isfinite(height))
        return eng_fail(e, PLX_E_INVALID, "plx_route_facial: needs 2 or more vertices, step > 0, height >= 0");
    for (i = 0; i < 2 * n; i++)
        if (!isfinite(xy[i]))
            return eng_fail(e, PLX_E_INVALID, "plx_route_facial: a vertex is not finite");
    for (i = 0; i + 1 < n; i++) {
        double s4[4], fw[2];
        walking_direction(xy, n, i, fw);
        facial_segment(e, xy + 2 * i, xy + 2 * i + 2, fw, step, height, s4);
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
