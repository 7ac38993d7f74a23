/* project: the SPEC §1 projection of a loaded lon/lat scene, both ways.
 *   x = (lon - lon0) * 111320 * cos(lat0),  y = (lat - lat0) * 110540
 * with (lon0, lat0) the centre the loader chose (plx_scene_info). */
#include <math.h>
#include "base/engine.h"

#define M_PER_DEG_LON 111320.0
#define M_PER_DEG_LAT 110540.0

static plx_status need_lonlat(plx_engine *e, const char *fn, size_t n, const double *in, const double *out)
{
    char msg[200];
    strbuf b;
    plx_status st = eng_need_scene(e, fn);
    if (st != PLX_OK)
        return st;
    sb_init(&b, msg, sizeof msg);
    sb_str(&b, fn);
    if (n > 0 && (!in || !out)) {
        sb_str(&b, ": an array is NULL");
        return eng_fail(e, PLX_E_INVALID, msg);
    }
    if (!e->sc->lonlat) {
        sb_str(&b, ": the scene is in local metres (properties.units = \"m\"): it has no lon/lat frame");
        return eng_fail(e, PLX_E_INVALID, msg);
    }
    eng_clear_error(e);
    return PLX_OK;
}

static double cos_lat0(const scene *s)
{
    return cos(s->lat0 * 3.14159265358979323846 / 180.0);
}

plx_status plx_lonlat_to_local(plx_engine *e, size_t n, const double *lonlat, double *xy)
{
    size_t i;
    double c;
    plx_status st = need_lonlat(e, "plx_lonlat_to_local", n, lonlat, xy);
    if (st != PLX_OK)
        return st;
    c = cos_lat0(e->sc);
    for (i = 0; i < n; i++) {
        double lon = lonlat[2 * i], lat = lonlat[2 * i + 1];
        xy[2 * i] = (lon - e->sc->lon0) * M_PER_DEG_LON * c;
        xy[2 * i + 1] = (lat - e->sc->lat0) * M_PER_DEG_LAT;
    }
    return PLX_OK;
}

plx_status plx_local_to_lonlat(plx_engine *e, size_t n, const double *xy, double *lonlat)
{
    size_t i;
    double c;
    plx_status st = need_lonlat(e, "plx_local_to_lonlat", n, xy, lonlat);
    if (st != PLX_OK)
        return st;
    c = cos_lat0(e->sc);
    for (i = 0; i < n; i++) {
        double x = xy[2 * i], y = xy[2 * i + 1];
        lonlat[2 * i] = e->sc->lon0 + x / (M_PER_DEG_LON * c);
        lonlat[2 * i + 1] = e->sc->lat0 + y / M_PER_DEG_LAT;
    }
    return PLX_OK;
}
