/* lightmap: the aerial light map, ground illuminance per texel (lightmap.c). */
#ifndef PLX_LIGHTMAP_H
#define PLX_LIGHTMAP_H

#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"

typedef struct lightmap {
    float *rgb;                 /* E_rgb, 3 floats a texel, rows from y0 up */
    size_t cap;                 /* floats */
    uint32_t nx, ny;
    double x0, y0, cell;
    uint64_t shaded;            /* texels shaded by the last build */
    int built;
    float *ind;                 /* E_indirect RGB at the topmost surface and that
                                   surface's height, 4 floats a texel (ind[0] < 0:
                                   none); NULL when built without lightmap_ind_fn */
    size_t ind_cap;             /* floats */
    int has_ind;                /* the last build filled ind */
} lightmap;

/* E_rgb at ground point P with unit normal n (the renderer's shader). */
typedef void (*lightmap_shade_fn)(void *user, const double P[3], const double n[3],
                                  double rgb[3]);

/* E_indirect RGB (lux) at the topmost surface over ground point (x, y)
 * (the ground, or a roof seen from above) and that surface's height *z;
 * 0 when there is no value there (the caller's point reads elsewhere). */
typedef int (*lightmap_ind_fn)(void *user, double x, double y, double rgb[3] /* OUT */,
                               double *z /* OUT */);

/* Building on several threads: par runs jobs (render.h's parallel-for),
 * lt is the light object when the shader is the light module's (else
 * NULL: one thread). */
/* A progress hook (plx_port.progress) and its ctx: lightmap_fill_ind
 * reports its rows (fn NULL: none). */
typedef struct lightmap_progress {
    void (*fn)(void *ctx, const char *what, uint64_t n, uint64_t total);
    void *ctx;
} lightmap_progress;

typedef struct lightmap_par {
    int (*par)(void *ctx, int workers, uint32_t njobs, void (*job)(void *arg, int worker, uint32_t k),
               void *arg);
    void *ctx;
    int workers;
    struct light *lt;
    lightmap_progress progress;
} lightmap_par;

/* Builds the map of scene s with texels of cell metres (grown by 5% steps
 * until the map fits max_bytes) over the box of every lamp's ground reach,
 * shading each texel some lamp reaches with shade(user, ...). The first
 * build takes the memory from mem (part PLX_PART_FRAME); a later one must fit
 * it. With par (workers >= 2 and lt): by bands of LIGHTMAP_BAND rows, the
 * regions of the lamps reaching a band cached first on this thread, then
 * its rows on the workers through light_illuminance_cached; a texel it
 * cannot answer is left, with the rest of its row, to this thread after
 * them (the shader). The same map for any number of workers. Returns
 * PLX_OK, PLX_E_INVALID or PLX_E_NOMEM with *err set. */
#define LIGHTMAP_BAND 16
plx_status lightmap_build(lightmap *m, arena *mem, const scene *s, double cell, size_t max_bytes,
                          lightmap_shade_fn shade, void *user, const lightmap_par *par /* may be NULL */,
                          const char **err /* OUT */);

/* The same, and with ind_fn non-NULL also the indirect layer (ind): for
 * each texel some lamp reaches, ind_fn at its centre (16 more bytes a
 * texel, counted in max_bytes; filled on the calling thread before the
 * direct part, which par may spread). ind_user NULL: the layer is allocated and
 * left empty (a bake's twin engine: same memory, none of the work). */
plx_status lightmap_build_ind(lightmap *m, arena *mem, const scene *s, double cell, size_t max_bytes,
                              lightmap_shade_fn shade, void *user, const lightmap_par *par /* may be NULL */,
                              lightmap_ind_fn ind_fn, void *ind_user, const char **err /* OUT */);

/* Fills the indirect layer of a built map again (its memory as built):
 * ind_fn at every texel centre, the direct part left alone. For the light
 * gathered after the map was built (photon frames added since). With
 * workers >= 2 and par, bands of rows run on the workers, worker w
 * calling ind_fn with users[w] (each its own state: ind_fn must give a
 * texel the same value whoever asks, and the layer is then the same for
 * any number of workers); otherwise users[0] on this thread. Each row
 * done is reported to par->progress (LIGHTMAP_LAYER_STAGE). Returns
 * PLX_E_INVALID when the map was built without a layer. */
#define LIGHTMAP_LAYER_STAGE "aerial indirect layer"
plx_status lightmap_fill_ind(lightmap *m, lightmap_ind_fn ind_fn, void *const *users, int workers,
                             const lightmap_par *par /* may be NULL */);

/* E_indirect at P (a horizontal surface point seen from above, P[2] its
 * height) from the indirect layer: bilinear over the four texel centres
 * around P whose topmost surface has P's height (within 1 cm), weights
 * renormalised, so light does not cross a roof edge or a wall foot; 0
 * when no lamp reaches any of them (beyond every lamp's reach: no light
 * spreads there). Returns 0 (rgb 0) when the map cannot say: no layer, or
 * the texels around are reached but none is on P's surface (a surface
 * narrower than a texel). */
int lightmap_sample_ind(const lightmap *m, const double P[3], double rgb[3] /* OUT */);

/* Ground E_rgb at P from the map, bilinear between texel centres (0 off
 * the map). */
void lightmap_sample(const lightmap *m, const double P[3], double rgb[3] /* OUT */);

#endif
