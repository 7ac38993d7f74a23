/* engine: the object every public call hangs off. Internal layout. */
#ifndef PLX_ENGINE_H
#define PLX_ENGINE_H

#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"
#include "base/strbuf.h"
#include "base/context.h"

struct plx_engine {
    uint32_t magic;
    void *block;            /* the caller's block, as given */
    arena mem;
    plx_config cfg;
    plx_port port;          /* copy of the caller's port, or all NULL */
    arena_mark base;        /* the arena just after the engine object */
    char err[ENGINE_ERR_BYTES];
    uint32_t warnings;
    scene *sc;              /* NULL until a scene is loaded */
    struct polar *pd;       /* polar diagrams, built on first need */
    uint64_t polar_ns;
    vec2 *vis_poly;         /* visibility query results (PLX_PART_FRAME) */
    uint32_t vis_poly_cap;
    uint32_t *vis_ids;
    uint32_t vis_ids_cap;
    struct light *lt;       /* lamp light, created on first need */
    const struct lit_region *lit_last; /* region of the last plx_lit_region_get */
    struct render *rd;      /* renderer, created on first need */
    struct photon_sys *ph;  /* photon buffers, created on first need */
    size_t ph_full, ph_budget; /* their default-quality size and the budget they fit */
    uint32_t ph_reductions; /* quality steps taken to fit it (need.c) */
    struct icache *ic;      /* images' irradiance cache, created with the photon buffers */
    double lightmap_cell;   /* light map texel size when built, else 0 */
    int layer_workers;      /* workers that gathered the map's indirect layer last (eng_lightmap_layer) */
    uint64_t indirect_gen;  /* +1 at every change of the photon buffers (the indirect map's key) */
    float *aa_sum;          /* anti-aliasing sum (PLX_PART_FRAME), taken on first need */
    uint32_t *aa_id;        /* adaptive anti-aliasing: the first sample's surface ids, */
    uint8_t *aa_mask;       /* the pixels the later samples shade (1 byte each) and */
    uint8_t *aa_rgb;        /* the first sample's 8-bit image (PLX_PART_FRAME, on first need) */
    struct atlas *atlas;    /* the radiance atlas of frames with indirect light (on first need) */
    struct atlas_cache *atlas_cache; /* its per-worker map caches (PLX_MAX_THREADS) */
    uint32_t *atlas_list;   /* what a frame lists to fill (ENG_ATLAS_LIST items) */
    double *atlas_rec;      /* its fills' indirect records (atlas_fill_records) */
    double atlas_fine;      /* the spacing asked for (0: the default) */
    int atlas_off;          /* the atlas did not fit: frames shade every pixel */
    uint32_t gather_side;   /* final gathering at points: side^2 directions
                               (0 = photon buffers only); set by
                               plx_indirect_set_gather, else FINAL_GATHER_SIDE */
    int gather_set;         /* plx_indirect_set_gather was called */
};

#define ENGINE_MAGIC 0x504c5831u /* "PLX1" */

/* PLX_OK when e is a valid engine with a scene loaded; else PLX_E_INVALID,
 * or PLX_E_NOSCENE with the error "FN: no scene is loaded". */
plx_status eng_need_scene(plx_engine *e, const char *fn);
/* What a call needs built first (api/need.c, the one place deciding it). */
typedef enum eng_what { ENG_SCENE, ENG_POLAR, ENG_LIGHT, ENG_PHOTON, ENG_RENDER } eng_what;
/* Builds what is missing of WHAT and what it depends on; PLX_OK when all is
 * there. Errors name fn ("fn: no scene is loaded"), or the part that ran
 * out of memory. */
plx_status eng_need(plx_engine *e, eng_what what, const char *fn);
/* E_indirect at a checked surface point, 0 without photon frames (indirectapi.c). */
double eng_indirect(plx_engine *e, const double P[3], const double n[3]);
/* The same, also writing its RGB version to rgb (may be NULL); returns the scalar. */
double eng_indirect_rgb(plx_engine *e, const double P[3], const double n[3], double rgb[3] /* OUT */);
/* The visibility results' buffers (4 points a footprint vertex, an id a
 * building), taken at the first visibility query (need.c). */
plx_status eng_need_vis_buffers(plx_engine *e);
/* Creates the renderer on first need (renderapi.c). */
plx_status eng_need_render(plx_engine *e);
/* The largest frame the engine's renderer draws (plx_config.render_max_*,
 * their defaults for 0; a bake's as it was made). */
void eng_render_max(const plx_engine *e, int32_t *w, int32_t *h);
/* PLX_E_INVALID, said by the call fn, unless the atlas spacing t is 0
 * (the default) or PLX_TEXEL_MIN .. PLX_TEXEL_MAX; PLX_OK otherwise. */
plx_status eng_texel_check(plx_engine *e, const char *fn, double t);
/* Builds the aerial light map at m_per_texel metres (0: 1 m) unless built;
 * dark: with a shader giving no light (the bake's twin, bake.c). Its
 * indirect layer is left to eng_lightmap_layer: only frames with indirect
 * light read it. */
plx_status eng_need_lightmap(plx_engine *e, double m_per_texel, int dark);
/* The radiance atlas (render/atlas.h) made on first need at spacing fine
 * (0: the default), not filled (renderapi.c). */
#define ENG_ATLAS_LIST 16384
plx_status eng_need_atlas(plx_engine *e, double fine);
/* Every chart of the atlas filled (a bake), on the port's workers, with
 * progress: PLX_OK or PLX_E_NOMEM. */
plx_status eng_atlas_fill_all(plx_engine *e);
/* The aerial map's indirect layer gathered when photons came after the map
 * (renderapi.c). */
void eng_lightmap_layer(plx_engine *e);
/* The indirect estimate at a free point (not on a surface facing out):
 * final gathering there, else the buffers' value on the horizontal surface
 * below it (indirectapi.c). */
double eng_indirect_free(plx_engine *e, const double P[3], const double n[3], double rgb[3] /* OUT */);
/* E_indirect read from the photon buffers alone (images; indirectapi.c). */
double eng_indirect_photons_rgb(plx_engine *e, const double P[3], const double n[3],
                                double rgb[3] /* OUT */);

/* Debug builds (PLX_DEBUG): asserts the invariants of a loaded scene (rings
 * of at least 3 vertices inside the point array, buildings' and blocks'
 * rings inside the ring arrays, every building in its block, lamps finite).
 * Release builds: nothing. */
void eng_check_scene(const scene *s);
/* Checks the engine handle for API misuse. */
int eng_ok(const plx_engine *e);

#endif
