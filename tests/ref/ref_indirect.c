/* ref_indirect: path-traced E_indirect (ref_indirect.h). */
#include <math.h>
#include <string.h>

#include "ref_indirect.h"

#define REF_PI 3.14159265358979323846

static uint64_t next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double uni(uint64_t *s)
{
    return (next(s) >> 11) * (1.0 / 9007199254740992.0);
}

static void cosine_dir(uint64_t *s, const double n[3], double d[3])
{
    double u1 = uni(s), u2 = uni(s), r = sqrt(u1), p = 2.0 * REF_PI * u2;
    double a = r * cos(p), b = r * sin(p), c = sqrt(1.0 - u1), t[3], bt[3], l;
    int k;
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
    for (k = 0; k < 3; k++)
        t[k] /= l;
    bt[0] = n[1] * t[2] - n[2] * t[1];
    bt[1] = n[2] * t[0] - n[0] * t[2];
    bt[2] = n[0] * t[1] - n[1] * t[0];
    for (k = 0; k < 3; k++)
        d[k] = a * t[k] + b * bt[k] + c * n[k];
    l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (k = 0; k < 3; k++)
        d[k] /= l;
}

double ref_indirect_direct(tracer *T, const scene *s, const double Q[3], const double n[3],
                           double rgb[3])
{
    double e = 0.0;
    uint32_t i;
    if (rgb)
        rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (i = 0; i < s->nlamps; i++) {
        const scene_lamp *L = &s->lamps[i];
        double w[3] = {L->x - Q[0], L->y - Q[1], L->z - Q[2]}, d, c, o[3], x;
        trace_hit h;
        int k;
        if (fabs(w[0]) >= L->radius || fabs(w[1]) >= L->radius)
            continue;
        d = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        if (d >= L->radius || d == 0.0)
            continue;
        for (k = 0; k < 3; k++)
            w[k] /= d;
        c = w[0] * n[0] + w[1] * n[1] + w[2] * n[2];
        if (c <= 0.0)
            continue;
        for (k = 0; k < 3; k++)
            o[k] = Q[k] + 1e-6 * n[k];
        if (trace_ray(T, o, w, d - 1e-6, &h) != TRACE_SKY)
            continue;
        x = d / L->radius;
        c = L->intensity * c / (d * d) * (1 - x * x * x * x) * (1 - x * x * x * x);
        e += c;
        if (rgb)
            for (k = 0; k < 3; k++)
                rgb[k] += c * L->color[k];
    }
    return e;
}

double ref_indirect_paths_rgb(tracer *T, const scene *s, const double P[3], const double n[3],
                              int paths, uint64_t seed, double rgb[3], double *sd)
{
    double sum = 0.0, sum2 = 0.0, srgb[3] = {0.0, 0.0, 0.0};
    uint64_t rs = seed * 0x2545f4914f6cdd1dull + 0x1234567ull;
    int k, c;
    for (k = 0; k < paths; k++) {
        double p[3] = {P[0], P[1], P[2]}, nn[3] = {n[0], n[1], n[2]}, x = 0.0;
        int depth;
        for (depth = 0; depth < 30; depth++) {
            double d[3], o[3], a, drgb[3];
            trace_hit h;
            cosine_dir(&rs, nn, d);
            for (c = 0; c < 3; c++)
                o[c] = p[c] + 1e-6 * nn[c];
            if (o[2] < 0.0)
                o[2] = 0.0;
            if (trace_ray(T, o, d, INFINITY, &h) == TRACE_SKY)
                break;
            a = h.kind == TRACE_GROUND ? s->ground_albedo : s->bld[h.bld].albedo;
            x += a * ref_indirect_direct(T, s, h.p, h.n, rgb ? drgb : NULL);
            if (rgb)
                for (c = 0; c < 3; c++)
                    srgb[c] += a * drgb[c];
            if (uni(&rs) >= a)
                break;
            memcpy(p, h.p, sizeof p);
            memcpy(nn, h.n, sizeof nn);
        }
        sum += x;
        sum2 += x * x;
    }
    if (rgb)
        for (c = 0; c < 3; c++)
            rgb[c] = srgb[c] / paths;
    if (sd) {
        double m = sum / paths, var = sum2 / paths - m * m;
        *sd = sqrt((var > 0.0 ? var : 0.0) / paths);
    }
    return sum / paths;
}

double ref_indirect_paths(tracer *T, const scene *s, const double P[3], const double n[3],
                          int paths, uint64_t seed, double *sd)
{
    return ref_indirect_paths_rgb(T, s, P, n, paths, seed, NULL, sd);
}

int ref_indirect_points(tracer *T, const scene *s, int nground, int nfacade, uint64_t seed,
                        double *P, double *N)
{
    uint64_t rs = seed;
    int np = 0, tries;
    if (s->nlamps == 0)
        return 0;
    for (tries = 0; tries < 100000 && np < nground + nfacade; tries++) {
        const scene_lamp *L = &s->lamps[next(&rs) % s->nlamps];
        double a = 2 * REF_PI * uni(&rs), *p = P + 3 * np, *q = N + 3 * np;
        if (np < nground) {
            double r = 2.0 + 6.0 * uni(&rs), x = L->x + r * cos(a), y = L->y + r * sin(a);
            if (x < s->bounds[0] + 60 || x > s->bounds[2] - 60 || y < s->bounds[1] + 60 ||
                y > s->bounds[3] - 60 || trace_top(T, x, y, NULL) != 0.0)
                continue;
            p[0] = x;
            p[1] = y;
            p[2] = 0.0;
            q[0] = q[1] = 0.0;
            q[2] = 1.0;
        } else {
            double o[3] = {L->x, L->y, 1.0 + (L->z - 1.5) * uni(&rs)};
            double d[3] = {cos(a), sin(a), 0.0};
            trace_hit h;
            if (trace_ray(T, o, d, 12.0, &h) != TRACE_WALL)
                continue;
            memcpy(p, h.p, 3 * sizeof *p);
            memcpy(q, h.n, 3 * sizeof *q);
        }
        np++;
    }
    return np;
}
