/* api: read access to the loaded scene. */
#include <string.h>
#include "base/engine.h"

static plx_status bad_index(plx_engine *e, const char *fn, uint32_t i, uint32_t n)
{
    char msg[160];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    sb_str(&b, fn);
    sb_str(&b, ": index ");
    sb_uint(&b, i);
    sb_str(&b, " is out of range (there are ");
    sb_uint(&b, n);
    sb_char(&b, ')');
    return eng_fail(e, PLX_E_RANGE, msg);
}

static double ring_area2(const vec2 *p, uint32_t n)
{
    double a = 0.0;
    uint32_t i;
    for (i = 0; i < n; i++) {
        vec2 u = p[i], v = p[(i + 1) % n];
        a += u.x * v.y - v.x * u.y;
    }
    return a;
}

plx_status plx_scene_info_get(plx_engine *e, plx_scene_info *out)
{
    const scene *s;
    uint32_t i;
    plx_status st = eng_need(e, ENG_SCENE, "plx_scene_info_get");
    if (st != PLX_OK)
        return st;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_scene_info_get: out is NULL");
    s = e->sc;
    memset(out, 0, sizeof *out);
    out->buildings = s->nbld;
    for (i = 0; i < s->nbld; i++) {
        out->raised += s->bld[i].min_height > 0.0;
        out->holes += s->bld[i].ring_count - 1;
    }
    out->blocks = s->nblocks;
    for (i = 0; i < s->nblocks; i++) {
        uint32_t r;
        for (r = 1; r < s->blocks[i].ring_count; r++) {
            const scene_ring *g = &s->block_rings[s->blocks[i].ring_first + r];
            out->courtyards += ring_area2(s->block_pts + g->first, g->count) < 0.0;
        }
    }
    out->lamps = s->nlamps;
    out->vertices = s->npts;
    out->skipped_features = s->skipped_features;
    out->skipped_lamps = s->skipped_lamps;
    out->merged_lamps = s->merged_lamps;
    out->overlapping_pairs = s->overlapping_pairs;
    out->lonlat = s->lonlat;
    out->lon0 = s->lon0;
    out->lat0 = s->lat0;
    memcpy(out->bounds, s->bounds, sizeof out->bounds);
    out->height_min = s->height_min;
    out->height_median = s->height_median;
    out->height_max = s->height_max;
    out->ground_albedo = s->ground_albedo;
    out->load_ns = s->load_ns;
    return PLX_OK;
}

plx_status plx_building_get(plx_engine *e, uint32_t i, plx_building *out)
{
    const scene_building *b;
    plx_status st = eng_need(e, ENG_SCENE, "plx_building_get");
    if (st != PLX_OK)
        return st;
    if (i >= e->sc->nbld)
        return bad_index(e, "plx_building_get", i, e->sc->nbld);
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_building_get: out is NULL");
    b = &e->sc->bld[i];
    out->nrings = b->ring_count;
    out->height = b->height;
    out->min_height = b->min_height;
    out->albedo = b->albedo;
    memcpy(out->box, b->box, sizeof out->box);
    out->feature = b->feature;
    out->block = b->block;
    out->id = b->id;
    return PLX_OK;
}

plx_status plx_lamp_get(plx_engine *e, uint32_t i, plx_lamp *out)
{
    const scene_lamp *l;
    plx_status st = eng_need(e, ENG_SCENE, "plx_lamp_get");
    if (st != PLX_OK)
        return st;
    if (i >= e->sc->nlamps)
        return bad_index(e, "plx_lamp_get", i, e->sc->nlamps);
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_lamp_get: out is NULL");
    l = &e->sc->lamps[i];
    out->x = l->x;
    out->y = l->y;
    out->z = l->z;
    out->intensity = l->intensity;
    out->radius = l->radius;
    memcpy(out->color, l->color, sizeof out->color);
    out->feature = l->feature;
    out->id = l->id;
    return PLX_OK;
}

plx_status plx_block_get(plx_engine *e, uint32_t i, plx_block *out)
{
    const scene_block *k;
    plx_status st = eng_need(e, ENG_SCENE, "plx_block_get");
    if (st != PLX_OK)
        return st;
    if (i >= e->sc->nblocks)
        return bad_index(e, "plx_block_get", i, e->sc->nblocks);
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_block_get: out is NULL");
    k = &e->sc->blocks[i];
    out->nbuildings = k->bld_count;
    out->buildings = e->sc->block_bld + k->bld_first;
    out->nrings = k->ring_count;
    memcpy(out->box, k->box, sizeof out->box);
    return PLX_OK;
}

static plx_status ring_out(const vec2 *pts, const scene_ring *r, const double **xy, uint32_t *n)
{
    *xy = &pts[r->first].x;
    *n = r->count;
    return PLX_OK;
}

plx_status plx_building_ring(plx_engine *e, uint32_t i, uint32_t r, const double **xy, uint32_t *n)
{
    const scene_building *b;
    plx_status st = eng_need(e, ENG_SCENE, "plx_building_ring");
    if (st != PLX_OK)
        return st;
    if (!xy || !n)
        return eng_fail(e, PLX_E_INVALID, "plx_building_ring: xy or n is NULL");
    if (i >= e->sc->nbld)
        return bad_index(e, "plx_building_ring", i, e->sc->nbld);
    b = &e->sc->bld[i];
    if (r >= b->ring_count)
        return bad_index(e, "plx_building_ring (ring)", r, b->ring_count);
    return ring_out(e->sc->pts, &e->sc->rings[b->ring_first + r], xy, n);
}

plx_status plx_block_ring(plx_engine *e, uint32_t i, uint32_t r, const double **xy, uint32_t *n)
{
    const scene_block *k;
    plx_status st = eng_need(e, ENG_SCENE, "plx_block_ring");
    if (st != PLX_OK)
        return st;
    if (!xy || !n)
        return eng_fail(e, PLX_E_INVALID, "plx_block_ring: xy or n is NULL");
    if (i >= e->sc->nblocks)
        return bad_index(e, "plx_block_ring", i, e->sc->nblocks);
    k = &e->sc->blocks[i];
    if (r >= k->ring_count)
        return bad_index(e, "plx_block_ring (ring)", r, k->ring_count);
    return ring_out(e->sc->block_pts, &e->sc->block_rings[k->ring_first + r], xy, n);
}

const char *plx_scene_crs(plx_engine *e)
{
    if (eng_need(e, ENG_SCENE, "plx_scene_crs") != PLX_OK)
        return NULL;
    return e->sc->crs;
}
