/* query: the public face of the polar diagrams and planar visibility. */
#include <math.h>
#include <string.h>

#include "base/engine.h"
#include "polar/polar.h"
#include "polar/locate.h"
#include "polar/visibility.h"
#include "base/geom.h"

#define DEG 0.017453292519943295

plx_status plx_polar_build(plx_engine *e)
{
    return eng_need(e, ENG_POLAR, "plx_polar_build");
}

plx_status plx_polar_info_get(plx_engine *e, plx_polar_info *out)
{
    size_t bytes[4];
    int q;
    uint32_t i;
    plx_status st = plx_polar_build(e);
    if (st != PLX_OK)
        return st;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_polar_info_get: out is NULL");
    memset(out, 0, sizeof *out);
    polar_memory(e->pd, bytes);
    out->build_ns = e->polar_ns;
    out->axes = bytes[0];
    out->regions = bytes[1];
    out->polygons = bytes[2];
    out->rest = bytes[3];
    out->total = bytes[0] + bytes[1] + bytes[2] + bytes[3];
    for (q = 0; q < 4; q++)
        out->nregions[q] = polar_region_count(e->pd, q);
    for (i = 0; i < e->sc->nbld; i++) {
        const scene_building *b = &e->sc->bld[i];
        uint32_t r;
        if (b->min_height > 0.0)
            continue;
        for (r = 0; r < b->ring_count; r++)
            out->vertices += e->sc->rings[b->ring_first + r].count;
    }
    return PLX_OK;
}

plx_status plx_polar_region_count(plx_engine *e, int q, uint32_t *count)
{
    plx_status st = plx_polar_build(e);
    if (st != PLX_OK)
        return st;
    if (q < 0 || q > 3 || !count)
        return eng_fail(e, PLX_E_INVALID, "plx_polar_region_count: q must be 0..3 and count not NULL");
    *count = polar_region_count(e->pd, q);
    return PLX_OK;
}

plx_status plx_polar_region(plx_engine *e, int q, uint32_t i, double xy[8], uint32_t *n,
                            int32_t *owner, int *solid)
{
    vec2 c[4];
    int k, got;
    plx_status st = plx_polar_build(e);
    if (st != PLX_OK)
        return st;
    if (q < 0 || q > 3 || !xy || !n || !owner || !solid)
        return eng_fail(e, PLX_E_INVALID, "plx_polar_region: q must be 0..3 and outputs not NULL");
    got = polar_region(e->pd, q, i, c, owner, solid);
    if (got <= 0)
        return eng_fail(e, PLX_E_RANGE, "plx_polar_region: region index out of range");
    for (k = 0; k < got; k++) {
        xy[2 * k] = c[k].x;
        xy[2 * k + 1] = c[k].y;
    }
    *n = (uint32_t)got;
    return PLX_OK;
}

/* The building whose footprint holds p strictly inside, or -1. */
static int32_t host_building(const scene *s, vec2 p)
{
    uint32_t i, r;
    for (i = 0; i < s->nbld; i++) {
        const scene_building *b = &s->bld[i];
        int in;
        if (b->min_height > 0.0 || p.x < b->box[0] || p.x > b->box[2] || p.y < b->box[1] || p.y > b->box[3])
            continue;
        in = geom_point_in_ring(p, s->pts + s->rings[b->ring_first].first, s->rings[b->ring_first].count) ==
             GEOM_INSIDE;
        for (r = 1; in && r < b->ring_count; r++) {
            const scene_ring *h = &s->rings[b->ring_first + r];
            in = geom_point_in_ring(p, s->pts + h->first, h->count) == GEOM_OUTSIDE;
        }
        if (in)
            return (int32_t)i;
    }
    return -1;
}

/* Says why p cannot be a viewer. */
static plx_status not_free(plx_engine *e, vec2 p)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    int32_t owner = -1;
    int32_t r = polar_locate(e->pd, 0, p, &owner);
    if (r == -3)
        owner = host_building(e->sc, p); /* the error path only: a scan is fine */
    const double *bx = e->sc->bounds;
    sb_init(&b, msg, sizeof msg);
    sb_str(&b, "point (");
    sb_num(&b, p.x, 10);
    sb_str(&b, ", ");
    sb_num(&b, p.y, 10);
    sb_str(&b, ") ");
    if (r == -3 && owner >= 0) {
        sb_str(&b, "is inside building ");
        sb_uint(&b, (uint32_t)owner);
        if (e->sc->bld[owner].id) {
            sb_str(&b, " (");
            sb_str(&b, e->sc->bld[owner].id);
            sb_char(&b, ')');
        }
    } else if (r == -3) {
        sb_str(&b, "lies on a wall shared by two buildings");
    } else if (r == -2) {
        sb_str(&b, "lies on a wall");
    } else {
        sb_str(&b, "is outside Bounds [");
        sb_num(&b, bx[0], 10);
        sb_str(&b, ", ");
        sb_num(&b, bx[1], 10);
        sb_str(&b, "] - [");
        sb_num(&b, bx[2], 10);
        sb_str(&b, ", ");
        sb_num(&b, bx[3], 10);
        sb_char(&b, ']');
    }
    sb_str(&b, ": not a free viewpoint");
    return eng_fail(e, PLX_E_RANGE, msg);
}

/* Distance from q to the segment ab. */
static double seg_dist(vec2 q, vec2 a, vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy, t;
    if (len2 == 0.0)
        return hypot(q.x - a.x, q.y - a.y);
    t = ((q.x - a.x) * dx + (q.y - a.y) * dy) / len2;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    return hypot(q.x - a.x - t * dx, q.y - a.y - t * dy);
}

/* Drops vertices lying on the segment joining their neighbours (within
 * 1e-10 of the larger side of Bounds, the rule of tests/ref/ref_vis.c), so a
 * square courtyard gives 4 vertices whatever rays split its walls. */
static uint32_t merge_collinear(vec2 *p, uint32_t n, double tol)
{
    int changed = 1;
    while (changed && n > 3) {
        uint32_t i, m = 0;
        changed = 0;
        for (i = 0; i < n; i++) {
            vec2 prev = m ? p[m - 1] : p[n - 1], next = p[(i + 1) % n];
            if (n - (i - m) > 3 && seg_dist(p[i], prev, next) <= tol) {
                changed = 1;
                continue;
            }
            p[m++] = p[i];
        }
        n = m;
    }
    return n;
}

plx_status plx_visibility_get(plx_engine *e, double x, double y, double dir_deg, double fov_deg,
                              plx_visibility *out)
{
    vis_result r;
    vec2 p;
    arena_mark m;
    int fresh;
    plx_status st = plx_polar_build(e);
    if (st != PLX_OK)
        return st;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_visibility_get: out is NULL");
    fresh = e->vis_poly == NULL;
    m = arena_get_mark(&e->mem);
    if ((st = eng_need_vis_buffers(e)) != PLX_OK)
        return st;
    memset(out, 0, sizeof *out);
    if (!isfinite(x) || !isfinite(y) || !isfinite(dir_deg) || !(fov_deg > 0.0))
        return eng_fail(e, PLX_E_INVALID, "plx_visibility_get: x, y, dir must be finite and fov > 0");
    memset(&r, 0, sizeof r);
    r.poly = e->vis_poly;
    r.poly_cap = e->vis_poly_cap;
    r.vis = e->vis_ids;
    r.vis_cap = e->vis_ids_cap;
    p.x = x;
    p.y = y;
    if (fov_deg >= 360.0)
        st = vis_query(e->pd, p, 0.0, 0.0, 1, &e->mem, &r);
    else
        st = vis_query(e->pd, p, (dir_deg - fov_deg / 2) * DEG, (dir_deg + fov_deg / 2) * DEG, 0, &e->mem, &r);
    if (st == PLX_E_RANGE)
        return not_free(e, p);
    if (st == PLX_E_NOMEM) {
        if (fresh) { /* a failed call leaves the engine as it was */
            arena_release(&e->mem, &m);
            e->vis_poly = NULL;
            e->vis_ids = NULL;
        }
        return eng_nomem(e, "computing visibility");
    }
    if (st != PLX_OK)
        return eng_fail(e, st, "plx_visibility_get: invalid query");
    eng_clear_error(e);
    {
        const double *bx = e->sc->bounds;
        double side = bx[2] - bx[0] > bx[3] - bx[1] ? bx[2] - bx[0] : bx[3] - bx[1];
        r.npoly = merge_collinear(e->vis_poly, r.npoly, 1e-10 * side);
    }
    out->area = r.area;
    out->nverts = r.npoly;
    out->xy = &e->vis_poly[0].x;
    out->nvisible = r.nvis;
    out->visible = e->vis_ids;
    return PLX_OK;
}
