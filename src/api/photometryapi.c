/* photometryapi: the public face of photometric lamps (SPEC §2.1): which
 * files the scene names, handing their bytes over, reading a lamp's
 * distribution back. */
#include <math.h>
#include <string.h>

#include "base/engine.h"
#include "light/light.h"
#include "light/illuminance.h"
#include "light/litregion.h"
#include "scene/photometry.h"
#include "photon/photon.h"

/* Lamp i is the first to name its path. */
static int first_of_path(const scene *s, uint32_t i)
{
    uint32_t j;
    if (!s->lamps[i].photometry)
        return 0;
    for (j = 0; j < i; j++)
        if (s->lamps[j].photometry && strcmp(s->lamps[j].photometry, s->lamps[i].photometry) == 0)
            return 0;
    return 1;
}

uint32_t plx_photometry_count(plx_engine *e)
{
    uint32_t i, n = 0;
    if (eng_need_scene(e, "plx_photometry_count") != PLX_OK)
        return 0;
    for (i = 0; i < e->sc->nlamps; i++)
        n += (uint32_t)first_of_path(e->sc, i);
    return n;
}

plx_status plx_photometry_path(plx_engine *e, uint32_t k, const char **path)
{
    uint32_t i, n = 0;
    plx_status st = eng_need_scene(e, "plx_photometry_path");
    if (st != PLX_OK)
        return st;
    if (!path)
        return eng_fail(e, PLX_E_INVALID, "plx_photometry_path: path is NULL");
    for (i = 0; i < e->sc->nlamps; i++)
        if (first_of_path(e->sc, i) && n++ == k) {
            *path = e->sc->lamps[i].photometry;
            return PLX_OK;
        }
    return eng_fail(e, PLX_E_RANGE, "plx_photometry_path: no such photometry path");
}

plx_status plx_set_photometry(plx_engine *e, const char *path, const char *data, size_t len, const char *name)
{
    const photometry *p;
    char err[ENGINE_ERR_BYTES];
    uint32_t i, used = 0;
    plx_status st = eng_need_scene(e, "plx_set_photometry");
    if (st != PLX_OK)
        return st;
    if (!path || (!data && len > 0))
        return eng_fail(e, PLX_E_INVALID, "plx_set_photometry: path or data is NULL");
    for (i = 0; i < e->sc->nlamps; i++)
        used += e->sc->lamps[i].photometry && strcmp(e->sc->lamps[i].photometry, path) == 0;
    if (!used)
        return eng_fail(e, PLX_E_INVALID, "plx_set_photometry: no lamp of the scene names this path");
    st = photometry_parse(&e->mem, PLX_PART_SCENE, data, len, name ? name : path, &p, err, sizeof err);
    if (st == PLX_E_NOMEM)
        return eng_nomem(e, "storing a photometry table");
    if (st != PLX_OK)
        return eng_fail(e, st, err);
    if (err[0]) /* the header's flux and the table's disagree */
        eng_warn(e, err);
    for (i = 0; i < e->sc->nlamps; i++) {
        scene_lamp *lp = &e->sc->lamps[i];
        if (lp->photometry && strcmp(lp->photometry, path) == 0) {
            lp->phot = p;
            lp->intensity = lp->dimming * p->peak;
        }
    }
    /* light computed with the old distribution is no longer right */
    if (e->lt)
        light_cache_clear(e->lt);
    if (e->ph)
        photon_lamps_changed(e->ph);
    e->indirect_gen++;
    e->lightmap_cell = 0.0;
    eng_clear_error(e);
    return PLX_OK;
}

static plx_status need_lamp(plx_engine *e, uint32_t lamp, const char *fn)
{
    plx_status st = eng_need_scene(e, fn);
    if (st != PLX_OK)
        return st;
    if (lamp >= e->sc->nlamps) {
        char msg[128];
        strbuf b;
        sb_init(&b, msg, sizeof msg);
        sb_str(&b, fn);
        sb_str(&b, ": lamp ");
        sb_uint(&b, lamp);
        sb_str(&b, " is out of range");
        return eng_fail(e, PLX_E_RANGE, msg);
    }
    return PLX_OK;
}

plx_status plx_lamp_photometry_get(plx_engine *e, uint32_t lamp, plx_lamp_photometry *out)
{
    const scene_lamp *lp;
    plx_status st = need_lamp(e, lamp, "plx_lamp_photometry_get");
    if (st != PLX_OK)
        return st;
    if (!out)
        return eng_fail(e, PLX_E_INVALID, "plx_lamp_photometry_get: out is NULL");
    lp = &e->sc->lamps[lamp];
    memset(out, 0, sizeof *out);
    out->path = lp->photometry;
    out->loaded = lp->phot != NULL;
    out->format = lp->phot ? lp->phot->format : 0;
    out->azimuth = lp->azimuth;
    out->tilt = lp->tilt;
    out->dimming = lp->dimming;
    out->peak_cd = lp->intensity;
    out->flux_lm = lamp_flux(lp);
    out->gamma_lit = lp->photometry ? (lp->phot ? lp->phot->gamma_lit : 0.0) : 180.0;
    return PLX_OK;
}

plx_status plx_lamp_intensity(plx_engine *e, uint32_t lamp, const double dir[3], double *cd, double *c_deg,
                              double *gamma_deg)
{
    const scene_lamp *lp;
    double d[3], l, c, g;
    plx_status st = need_lamp(e, lamp, "plx_lamp_intensity");
    if (st != PLX_OK)
        return st;
    if (!dir || !cd)
        return eng_fail(e, PLX_E_INVALID, "plx_lamp_intensity: dir or cd is NULL");
    l = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    if (!(l > 0.0) || !isfinite(l))
        return eng_fail(e, PLX_E_INVALID, "plx_lamp_intensity: dir must be finite and not zero");
    d[0] = dir[0] / l;
    d[1] = dir[1] / l;
    d[2] = dir[2] / l;
    lp = &e->sc->lamps[lamp];
    lamp_direction_angles(lp, d, &c, &g);
    if (c < 0.0)
        c += 360.0;
    *cd = lamp_intensity(lp, d);
    if (c_deg)
        *c_deg = c;
    if (gamma_deg)
        *gamma_deg = g;
    return PLX_OK;
}
