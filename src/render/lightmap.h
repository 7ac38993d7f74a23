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
} lightmap;

/* E_rgb at ground point P with unit normal n (the renderer's shader). */
typedef void (*lightmap_shade_fn)(void *user, const double P[3], const double n[3],
                                  double rgb[3]);

/* Building on several threads: par runs jobs (render.h's parallel-for),
 * lt is the light object when the shader is the light module's (else
 * NULL: one thread). */
typedef struct lightmap_par {
    int (*par)(void *ctx, int workers, uint32_t njobs, void (*job)(void *arg, int worker, uint32_t k),
               void *arg);
    void *ctx;
    int workers;
    struct light *lt;
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

/* Ground E_rgb at P from the map, bilinear between texel centres (0 off
 * the map). */
void lightmap_sample(const lightmap *m, const double P[3], double rgb[3] /* OUT */);

#endif
