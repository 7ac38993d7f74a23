/* litregion: the lit region of one lamp (its ground and facade polygons,
 * and the sector index the visibility queries read), computed on demand and
 * kept in the light object's cache (litregion.c). */
#ifndef PLX_LITREGION_H
#define PLX_LITREGION_H

#include "light/light.h"

/* ---- lit regions ------------------------------------------------------ */

/* An edge line relative to the lamp's ground point O: the points O + t w
 * of the line satisfy cross(t w, e) = c, so along a direction w the line is
 * met at t = c / cross(w, e). */
typedef struct lit_line { double ex, ey, c; } lit_line;

/* One interval of one building along the rays of a sector: from line lo
 * (LIT_NONE: from O itself, O inside the footprint) to line hi. */
typedef struct lit_band { uint32_t bld, lo, hi; } lit_band;

typedef struct lit_ring { uint32_t first, count; uint32_t wall; } lit_ring;
/* wall: for facade rings the wall id = index in scene.pts of the wall's
 * first vertex (the wall runs to the next vertex of its ring); LIT_NONE for
 * ground rings. */

typedef struct lit_pt3 { double x, y, z; } lit_pt3;

typedef struct lit_region {
    uint32_t lamp;
    double o[3];              /* lamp position */
    double reach;             /* R */
    double ground_reach;      /* Rg = sqrt(R^2 - zL^2), 0 if zL >= R */
    uint32_t ncand;           /* buildings in reach */
    /* sector index: sector i starts at pseudo-angle sec_ang[i] (ascending,
     * in [0, 4)); the last sector wraps round to sec_ang[0] + 4. */
    uint32_t nsec;
    const double *sec_ang;
    const uint32_t *sec_first; /* nsec + 1 offsets into band */
    const lit_band *band;      uint32_t nband;
    const lit_line *line;      uint32_t nline;
    /* output polygons (polygons == 1; an array is NULL when its count is 0) */
    const lit_ring *ground;    uint32_t nground;
    const vec2 *gpts;          uint32_t ngpts;
    const lit_ring *facade;    uint32_t nfacade;
    const lit_pt3 *fpts;       uint32_t nfpts;
    int polygons;              /* 0: sector index only (what queries need) */
    size_t bytes;              /* size of the region in the pool */
} lit_region;

/* The lit region of lamp i, from the cache or computed now (which may evict
 * other lamps' regions). The pointer stays valid until the next call on L
 * that computes a region (light_region, light_illuminance, light_lamps_at,
 * light_visible). Returns PLX_OK; PLX_E_INVALID (NULL argument, lamp out of
 * range); PLX_E_NOMEM when the region is larger than the whole pool, or
 * scratch memory runs out (the cache keeps what it held, L stays usable). */
plx_status light_region(light *L, uint32_t lamp, const lit_region **out /* OUT */);

/* The same without the polygons (only the sector index, about a tenth of
 * the size and time): what the visibility queries use. A cached full region
 * serves too; light_region replaces an index-only entry by a full one. */
plx_status light_region_index(light *L, uint32_t lamp, const lit_region **out /* OUT */);

/* Visibility of P from the lamp of region r through its sector index. */
int light_region_visible(light *L, const lit_region *r, const double P[3]);
/* The same through lamp's region when the cache holds it (counted as a
 * hit and made the most recent, as light_region_index does); -1 when it
 * does not (ask light_region_index). The illuminance's path at every
 * lamp of every point: none of light_region_index's checks. */
int light_lamp_visible_cached(light *L, uint32_t lamp, const double P[3]);

/* Drops every cached region. */
void light_cache_clear(light *L);
/* The same, and the counters and visit marks back to zero: the object as
 * a fresh one (a bake saves it so, whatever was computed before). */
void light_cache_reset(light *L);

#endif
