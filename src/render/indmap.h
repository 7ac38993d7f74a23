/* indmap: the aerial view's indirect ground map (indmap.c). */
#ifndef PLX_INDMAP_H
#define PLX_INDMAP_H

#include "polarlux.h"
#include "base/arena.h"
#include "render/lightmap.h"

/* A row job runner (the renderer's parallel-for, render.h): run(ctx,
 * workers, njobs, job, arg) returns 0 when every job ran, else -1. */
typedef void (*indmap_job_fn)(void *arg, int worker, uint32_t k);
typedef int (*indmap_par_fn)(void *ctx, int workers, uint32_t njobs, indmap_job_fn job, void *arg);

/* Height of the topmost horizontal surface over (x, y): a roof, or 0. */
typedef double (*indmap_top_fn)(void *user, double x, double y);

typedef struct indmap {
    float *rgb;                 /* E_indirect rgb at the texel centres, rows from y0 up */
    float *z;                   /* the height of the surface it was taken on (top(x, y)) */
    size_t cap;                 /* floats */
    uint32_t nx, ny;
    double x0, y0, cell;        /* texel (i, j) centre: x0 + (i + .5) cell, y0 + (j + .5) cell */
    uint64_t key;               /* the indirect light's state it was built for */
    int built;
} indmap;

/* Builds the map over the light map's box with texels of INDMAP_FACTOR
 * light-map texels a side: at every texel centre (x, y), z = top(top_user,
 * x, y) (NULL: 0) and hook(user, (x, y, z), up), by rows on par (NULL:
 * here; else hook and top must be safe to call from several threads).
 * The first build takes the memory from a (PLX_PART_FRAME); a later one
 * reuses it. Returns PLX_OK or PLX_E_NOMEM (the map is then not built). */
#define INDMAP_FACTOR 4
plx_status indmap_build(indmap *m, arena *a, const lightmap *lm, lightmap_shade_fn hook, void *user,
                        indmap_top_fn top, void *top_user, uint64_t key, indmap_par_fn par, void *par_ctx,
                        int workers);

/* E_indirect at P on a surface facing up (ground or roof), bilinear
 * between the four texel centres around it over those taken at P's
 * height (within 1 mm), the weights renormalised: 1, or 0 (rgb untouched)
 * when P is not among texel centres or no such texel has weight. */
int indmap_sample(const indmap *m, const double P[3], double rgb[3] /* OUT */);

#endif
