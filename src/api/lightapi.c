/* lightapi: the public face of lamp light (SPEC §2): illuminance at points
 * (with the photon buffers' indirect term, scalar or RGB), which lamps light
 * a point, and lamp lit regions. */
#include <math.h>
#include <string.h>

#include "base/engine.h"
#include "light/light.h"

#define DEFAULT_LIT_CACHE ((size_t)16 << 20)

plx_status eng_need_light(plx_engine *e, const char *fn)
{
    plx_status st;
    size_t cache;
    if ((st = eng_need_scene(e, fn)) != PLX_OK)
        return st;
    if (e->lt)
        return PLX_OK;
    cache = e->cfg.lit_cache_bytes ? e->cfg.lit_cache_bytes : DEFAULT_LIT_CACHE;
    st = light_create(&e->mem, e->sc, cache, &e->lt);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "setting up lamp light");
    if (st != PLX_OK)
        return eng_fail(e, st, "setting up lamp light failed");
    return PLX_OK;
}

static void where_text(strbuf *b, const plx_engine *e, light_where w, uint32_t bld, int normal_ok)
{
    if (w == LIGHT_INSIDE || w == LIGHT_AIR) {
        sb_str(b, w == LIGHT_INSIDE ? "is inside a building's solid" : "is on no surface (in the air)");
        return;
    }
    (void)normal_ok;
    sb_str(b, "has a normal pointing into ");
    if (bld < e->sc->nbld) {
        sb_str(b, "building ");
        sb_uint(b, bld);
        if (e->sc->bld[bld].id) {
            sb_str(b, " (");
            sb_str(b, e->sc->bld[bld].id);
            sb_char(b, ')');
        }
    } else {
        sb_str(b, "the ground");
    }
}

/* 0 when P with normal n is a surface point facing out, 1 for any other
 * point that is not strictly inside a solid (free air, a normal facing
 * into a surface: a light meter), else -1 with the reason in the engine's
 * error message (for point k). */
static int check_point(plx_engine *e, size_t k, const double P[3], const double n[3])
{
    uint32_t bld = UINT32_MAX;
    int normal_ok = 0;
    light_where w;
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    double len;
    sb_init(&b, msg, sizeof msg);
    (void)k;
    sb_str(&b, "point (");
    sb_num(&b, P[0], 10);
    sb_str(&b, ", ");
    sb_num(&b, P[1], 10);
    sb_str(&b, ", ");
    sb_num(&b, P[2], 10);
    sb_str(&b, ") ");
    if (!isfinite(P[0]) || !isfinite(P[1]) || !isfinite(P[2]) || !isfinite(n[0]) || !isfinite(n[1]) ||
        !isfinite(n[2])) {
        sb_str(&b, "has a non-finite coordinate or normal");
        eng_fail(e, PLX_E_RANGE, msg);
        return -1;
    }
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (fabs(len - 1.0) > 1e-6) {
        sb_str(&b, "has a normal that is not a unit vector");
        eng_fail(e, PLX_E_RANGE, msg);
        return -1;
    }
    if (P[2] < -LIGHT_CLASSIFY_TOL) {
        sb_str(&b, "is below the ground");
        eng_fail(e, PLX_E_RANGE, msg);
        return -1;
    }
    w = light_classify_point(e->lt, P, n, &bld, &normal_ok);
    if (w != LIGHT_INSIDE)   /* SPEC §2: any other point, any unit normal */
        return w != LIGHT_AIR && normal_ok ? 0 : 1;
    where_text(&b, e, w, bld, normal_ok);
    eng_fail(e, PLX_E_RANGE, msg);
    return -1;
}

/* Where a point loop writes: direct (E_direct, rgb) or indirect only
 * (E_indirect, rgb_ind); NULL pointers are skipped. */
typedef struct point_out {
    double *E_direct, *rgb, *E_indirect, *rgb_ind;
} point_out;

static void point_nan(const point_out *o, size_t k)
{
    int c;
    if (o->E_direct)
        o->E_direct[k] = NAN;
    if (o->E_indirect)
        o->E_indirect[k] = NAN;
    for (c = 0; c < 3; c++) {
        if (o->rgb)
            o->rgb[3 * k + (size_t)c] = NAN;
        if (o->rgb_ind)
            o->rgb_ind[3 * k + (size_t)c] = NAN;
    }
}

/* Checks and fills every point; PLX_E_RANGE names the first bad one. */
static plx_status point_loop(plx_engine *e, size_t n, const double *P, const double *N,
                             const point_out *o)
{
    size_t k;
    int bad = 0;
    char first[ENGINE_ERR_BYTES];
    first[0] = '\0';
    for (k = 0; k < n; k++) {
        const double *p = P + 3 * k, *nn = N + 3 * k;
        int where = check_point(e, k, p, nn);
        if (where < 0) {
            point_nan(o, k);
            if (!bad++)
                memcpy(first, e->err, sizeof first);
            continue;
        }
        if (o->E_direct)
            light_illuminance(e->lt, p, nn, &o->E_direct[k], o->rgb ? o->rgb + 3 * k : NULL);
        if (o->E_indirect || o->rgb_ind) {
            double *ri = o->rgb_ind ? o->rgb_ind + 3 * k : NULL;
            double Ei = where == 0 ? eng_indirect_rgb(e, p, nn, ri) : eng_indirect_free(e, p, nn, ri);
            if (o->E_indirect)
                o->E_indirect[k] = Ei;
        }
    }
    if (bad) {
        memcpy(e->err, first, sizeof first);
        return PLX_E_RANGE;
    }
    eng_clear_error(e);
    return PLX_OK;
}

plx_status plx_illuminance(plx_engine *e, size_t n, const double *P, const double *N,
                           double *E_direct, double *E_indirect, double *rgb)
{
    point_out o;
    plx_status st = eng_need_light(e, "plx_illuminance");
    if (st != PLX_OK)
        return st;
    if (n && (!P || !N || !E_direct))
        return eng_fail(e, PLX_E_INVALID, "plx_illuminance: P, N and E_direct must not be NULL");
    o.E_direct = E_direct;
    o.rgb = rgb;
    o.E_indirect = E_indirect;
    o.rgb_ind = NULL;
    if (E_indirect) {
        size_t k;
        for (k = 0; k < n; k++)
            E_indirect[k] = 0.0;
    }
    return point_loop(e, n, P, N, &o);
}

plx_status plx_indirect_rgb(plx_engine *e, size_t n, const double *P, const double *N,
                            double *E_indirect, double *rgb)
{
    point_out o;
    plx_status st = eng_need_light(e, "plx_indirect_rgb");
    if (st != PLX_OK)
        return st;
    if (n && (!P || !N || !rgb))
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_rgb: P, N and rgb must not be NULL");
    o.E_direct = NULL;
    o.rgb = NULL;
    o.E_indirect = E_indirect;
    o.rgb_ind = rgb;
    return point_loop(e, n, P, N, &o);
}

plx_status plx_lamps_at(plx_engine *e, const double P[3], const double n[3], uint32_t *ids,
                        double *lux, uint32_t cap, uint32_t *count)
{
    int got;
    plx_status st = eng_need_light(e, "plx_lamps_at");
    if (st != PLX_OK)
        return st;
    if (!P || !n || !count || (cap && (!ids || !lux)))
        return eng_fail(e, PLX_E_INVALID, "plx_lamps_at: NULL argument");
    if (check_point(e, 0, P, n) < 0)
        return PLX_E_RANGE;
    got = light_lamps_at(e->lt, P, n, ids, lux, (int)(cap > 0x7fffffffu ? 0x7fffffff : cap));
    *count = got < 0 ? 0 : (uint32_t)got;
    return PLX_OK;
}

plx_status plx_lit_region_get(plx_engine *e, uint32_t lamp, plx_lit_region *out)
{
    const lit_region *r;
    plx_status st = eng_need_light(e, "plx_lit_region_get");
    if (st != PLX_OK)
        return st;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_lit_region_get: out is NULL");
    if (lamp >= e->sc->nlamps) {
        char msg[128];
        strbuf b;
        sb_init(&b, msg, sizeof msg);
        sb_str(&b, "plx_lit_region_get: lamp ");
        sb_uint(&b, lamp);
        sb_str(&b, " is out of range (there are ");
        sb_uint(&b, e->sc->nlamps);
        sb_char(&b, ')');
        return eng_fail(e, PLX_E_RANGE, msg);
    }
    st = light_region(e->lt, lamp, &r);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "computing a lit region (raise plx_config.lit_cache_bytes)");
    if (st == PLX_E_UNSUPPORTED)
        return eng_fail(e, st, "plx_lit_region_get: along some direction this lamp's reach crosses more than 64 "
                               "building intervals; its lit polygons are not built (illuminance is unaffected)");
    if (st != PLX_OK)
        return eng_fail(e, st, "plx_lit_region_get failed");
    e->lit_last = r;
    out->lamp = lamp;
    out->nground = r->nground;
    out->nfacade = r->nfacade;
    return PLX_OK;
}

plx_status plx_lit_ground(plx_engine *e, uint32_t k, const double **xy, uint32_t *n)
{
    const lit_region *r = eng_ok(e) ? e->lit_last : NULL;
    if (!r || !xy || !n || k >= r->nground)
        return eng_ok(e) ? eng_fail(e, PLX_E_RANGE, "plx_lit_ground: no such polygon (call plx_lit_region_get first)")
                         : PLX_E_INVALID;
    *xy = &r->gpts[r->ground[k].first].x;
    *n = r->ground[k].count;
    return PLX_OK;
}

/* The building whose footprint ring holds vertex index v of scene.pts. */
static uint32_t building_of_vertex(const scene *s, uint32_t v)
{
    uint32_t lo = 0, hi = s->nbld;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->rings[s->bld[mid].ring_first].first <= v)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

plx_status plx_lit_facade(plx_engine *e, uint32_t k, const double **xyz, uint32_t *n, uint32_t *bld)
{
    const lit_region *r = eng_ok(e) ? e->lit_last : NULL;
    if (!r || !xyz || !n || !bld || k >= r->nfacade)
        return eng_ok(e) ? eng_fail(e, PLX_E_RANGE, "plx_lit_facade: no such polygon (call plx_lit_region_get first)")
                         : PLX_E_INVALID;
    *xyz = &r->fpts[r->facade[k].first].x;
    *n = r->facade[k].count;
    *bld = building_of_vertex(e->sc, r->facade[k].wall);
    return PLX_OK;
}
