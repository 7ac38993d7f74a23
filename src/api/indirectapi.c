/* indirectapi: the public face of the photon buffers (SPEC §4). */
#include <math.h>
#include <string.h>

#include "base/engine.h"
#include "photon/photon.h"
#include "photon/trace.h"
#include "photon/indirect.h"
#include "photon/nightlight.h"
#include "photon/photon_select.h"
#include "photon/final_gather.h"
#include "render/nightify.h"

plx_status plx_indirect_step(plx_engine *e, uint32_t photons, uint64_t seed)
{
    plx_status st = eng_need(e, ENG_PHOTON, "plx_indirect_step");
    if (st != PLX_OK)
        return st;
    if (photons == 0)
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_step: photons must be > 0");
    photon_step(e->ph, photons, seed);
    e->indirect_gen++;
    return PLX_OK;
}

uint64_t plx_indirect_frames(const plx_engine *e)
{
    if (!eng_ok(e) || !e->ph)
        return 0;
    return e->ph->st.frames;
}

uint64_t plx_indirect_photons(const plx_engine *e)
{
    if (!eng_ok(e) || !e->ph)
        return 0;
    return e->ph->st.photons;
}

plx_status plx_indirect_set_viewer(plx_engine *e, const double eye[3], const double dir[3], double fov_deg)
{
    double u[3];
    plx_status st = eng_need(e, ENG_PHOTON, "plx_indirect_set_viewer");
    if (st != PLX_OK)
        return st;
    if (!eye)
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_set_viewer: eye is NULL");
    if (!isfinite(eye[0]) || !isfinite(eye[1]) || !isfinite(eye[2]))
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_set_viewer: the eye must be finite");
    if (dir && (!isfinite(dir[0]) || !isfinite(dir[1]) || !isfinite(dir[2]) ||
                !(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2] > 0.0)))
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_set_viewer: dir must be finite and not zero (NULL: all around)");
    if (!isfinite(fov_deg))
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_set_viewer: fov_deg must be finite");
    if (dir) { /* made unit: the cone test takes a cosine */
        double l = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        u[0] = dir[0] / l;
        u[1] = dir[1] / l;
        u[2] = dir[2] / l;
    }
    st = photon_set_viewer(e->ph, eye, dir ? u : NULL, fov_deg);
    e->indirect_gen++;
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "assigning chart levels");
    return st;
}

plx_status plx_indirect_refine(plx_engine *e, const double eye[3], plx_refine_stats *out)
{
    int misses;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (!eye)
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_refine: eye is NULL");
    /* as plx_indirect_refine_view's camera (a NaN eye refined lamps) */
    if (!isfinite(eye[0]) || !isfinite(eye[1]) || !isfinite(eye[2]))
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_refine: the eye must be finite");
    if (!e->ph)
        return eng_fail(e, PLX_E_NOSCENE, "plx_indirect_refine: no photon buffers (trace indirect light first)");
    misses = photon_lamps_update(e->ph, eye);
    if (misses < 0) /* before any request: nothing changed */
        return eng_nomem(e, "choosing the lamps near the viewer");
    /* Only a miss changes the indirect light: a floor map computed (and,
     * the first time, pushed, restarting the progressive chart) or one
     * evicted. Hits reorder the LRU list alone, which the sum does not
     * follow (photon_night_horizontal sums in slot order), so the atlas
     * and the indirect map of the last frame stay valid. */
    if (misses > 0)
        e->indirect_gen++;
    if (out) {
        memset(out, 0, sizeof *out);
        out->misses_now = (uint32_t)misses;
        out->hits = e->ph->st.lamp_hits;
        out->misses = e->ph->st.lamp_misses;
        out->evictions = e->ph->st.lamp_evictions;
        out->refined = e->ph->st.lamp_refined;
        out->slots = e->ph->nslots;
        out->near_radius = e->ph->cfg.near_radius;
        out->cached = photon_lamp_lru(e->ph, out->lru, PLX_REFINE_LRU_MAX);
        out->centre[0] = eye[0];
        out->centre[1] = eye[1];
    }
    return PLX_OK;
}

/* How far ahead of the eye, horizontally, a view's refinement is centred:
 * where the centre ray (direction d, horizontal length h > 0) meets the
 * ground, at most limit; 0 for an eye at or below the ground. */
static double refine_ahead(const double eye[3], const double d[3], double h, double limit)
{
    double s;
    if (!(eye[2] > 0.0))
        return 0.0;             /* at or below the ground: its own ground point */
    if (!(d[2] < 0.0))
        return limit;           /* level or upward from above: the ground is never met */
    s = eye[2] * h / -d[2];
    return s < limit ? s : limit;
}

plx_status plx_indirect_refine_view(plx_engine *e, const plx_camera *cam, plx_refine_stats *out)
{
    double c[3], d[3], h, a = 0.0;
    int k;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (!cam)
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_refine_view: camera is NULL");
    for (k = 0; k < 3; k++) {
        if (!isfinite(cam->eye[k]) || !isfinite(cam->target[k]))
            return eng_fail(e, PLX_E_INVALID, "plx_indirect_refine_view: the camera's eye or target is not finite");
        d[k] = cam->target[k] - cam->eye[k];
    }
    if (!e->ph)
        return eng_fail(e, PLX_E_NOSCENE, "plx_indirect_refine_view: no photon buffers (trace indirect light first)");
    h = hypot(d[0], d[1]); /* no underflow or overflow of the squares */
    if (h > 0.0 && isfinite(h))
        a = refine_ahead(cam->eye, d, h, 0.5 * e->ph->cfg.near_radius);
    c[0] = a > 0.0 ? cam->eye[0] + d[0] / h * a : cam->eye[0];
    c[1] = a > 0.0 ? cam->eye[1] + d[1] / h * a : cam->eye[1];
    c[2] = 0.0;
    return plx_indirect_refine(e, c, out);
}

plx_status plx_indirect_info_get(plx_engine *e, plx_indirect_info *out)
{
    const photon_sys *ps;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_info_get: out is NULL");
    memset(out, 0, sizeof *out);
    if (!e->ph)
        return eng_fail(e, PLX_E_NOSCENE, "plx_indirect_info_get: no photon buffers (trace indirect light first)");
    ps = e->ph;
    out->bytes = e->mem.used[PLX_PART_PHOTON];
    out->full_bytes = e->ph_full;
    out->budget = e->ph_budget;
    out->reductions = e->ph_reductions;
    out->lamp_tables = !ps->cfg.no_lamp_tables;
    out->chart_w = ps->cfg.chart_w;
    out->chart_h = ps->cfg.chart_h;
    out->aerial_w = ps->gw;
    out->aerial_h = ps->gh;
    out->aerial_texel = ps->gtex;
    out->lamp_slots = ps->nslots;
    return PLX_OK;
}

plx_status plx_indirect_reset(plx_engine *e)
{
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (e->ph)
        photon_reset(e->ph);
    e->lightmap_cell = 0.0; /* the aerial map's indirect layer was gathered over the old photons */
    e->indirect_gen++;
    return PLX_OK;
}

/* E_indirect at a checked surface point (0 without frames). */
double eng_indirect(plx_engine *e, const double P[3], const double n[3])
{
    return eng_indirect_rgb(e, P, n, NULL);
}

/* The same with its RGB version: final gathering unless it is off
 * (final_gather.h), else the photon buffers' own estimate. */
double eng_indirect_rgb(plx_engine *e, const double P[3], const double n[3], double rgb[3])
{
    uint32_t side = e->gather_set ? e->gather_side : FINAL_GATHER_SIDE;
    if (!e->ph || plx_indirect_frames(e) == 0 || side == 0 || !e->lt)
        return eng_indirect_photons_rgb(e, P, n, rgb);
    return final_gather_rgb(e->ph, e->ph->T, e->lt, P, n, side, 1, rgb);
}

/* The photon buffers alone (what images read). */
double eng_indirect_photons_rgb(plx_engine *e, const double P[3], const double n[3],
                                double rgb[3])
{
    if (!e->ph || plx_indirect_frames(e) == 0) {
        if (rgb)
            rgb[0] = rgb[1] = rgb[2] = 0.0;
        return 0.0;
    }
    return photon_indirect_rgb(e->ph, P, n, rgb);
}

/* The indirect estimate at a point that is not on a surface facing out (a
 * light meter in free air, README "How SPEC §2 is read"): final gathering
 * at the point itself when it is on (it needs no surface); without it the
 * photon buffers' E_indirect on the horizontal surface straight below the
 * point (the topmost roof under it, else the ground), facing up. */
double eng_indirect_free(plx_engine *e, const double P[3], const double n[3], double rgb[3])
{
    static const double up[3] = { 0.0, 0.0, 1.0 };
    uint32_t side = e->gather_set ? e->gather_side : FINAL_GATHER_SIDE;
    double Q[3];
    if (e->ph && plx_indirect_frames(e) > 0 && side > 0 && e->lt)
        return eng_indirect_rgb(e, P, n, rgb);
    if (!e->ph || plx_indirect_frames(e) == 0) {
        if (rgb)
            rgb[0] = rgb[1] = rgb[2] = 0.0;
        return 0.0;
    }
    Q[0] = P[0];
    Q[1] = P[1];
    Q[2] = trace_top(e->ph->T, P[0], P[1], NULL);
    if (!(Q[2] <= P[2]))
        Q[2] = 0.0;   /* under a raised building: its ground */
    return photon_indirect_rgb(e->ph, Q, up, rgb);
}

plx_status plx_indirect_select_lamps(plx_engine *e, const double box[4], double margin,
                                      uint32_t *count)
{
    plx_status st = eng_need(e, ENG_PHOTON, "plx_indirect_select_lamps");
    uint32_t n;
    if (st != PLX_OK)
        return st;
    if ((box && !(box[0] <= box[2] && box[1] <= box[3])) || !(margin >= 0.0 && isfinite(margin)))
        return eng_fail(e, PLX_E_INVALID,
                        "plx_indirect_select_lamps: the box needs x0 <= x1, y0 <= y1 and a "
                        "finite margin >= 0");
    n = photon_select_lamps(e->ph, box, margin);
    e->indirect_gen++;
    if (count)
        *count = n;
    return PLX_OK;
}

plx_status plx_indirect_set_gather(plx_engine *e, uint32_t side)
{
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (side > 1024)
        return eng_fail(e, PLX_E_INVALID, "plx_indirect_set_gather: side must be at most 1024");
    e->gather_side = side;
    e->gather_set = 1;
    e->indirect_gen++;
    return PLX_OK;
}

plx_status plx_nightify(const uint8_t *day, size_t npx, const uint8_t *night, size_t nnight,
                        double dark_threshold, uint8_t *out)
{
    return photon_hist_match(day, npx, night, nnight, dark_threshold, out) == 0 ? PLX_OK : PLX_E_INVALID;
}
