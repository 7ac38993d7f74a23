/* surface_key: the surfaces of the horizontal photon charts (the aerial
 * chart, the lamps' floor maps). A texel holds the surface at its centre;
 * a roof is told by its height, the open ground is 0, and each courtyard
 * (a clockwise ring of a block's outline, blocks.h) is a surface of its
 * own, -1 - c, found through a grid of cells listing the courtyards whose
 * boxes meet them. Kept apart, a courtyard's ground no longer shares a
 * coarse texel's light with the street beside it (at the street's
 * height, it took the streets' light). */
#ifndef PLX_SURFACE_KEY_H
#define PLX_SURFACE_KEY_H

#include <stddef.h>
#include <stdint.h>

#include "base/scene.h"

typedef struct surface_keys {
    uint32_t ncy;       /* courtyards */
    uint32_t cyw, cyh;  /* the grid's cells */
    double x0, y0, cell;
    uint32_t *ring;     /* ncy: each courtyard's ring (scene.block_rings) */
    double *box;        /* ncy x 4: x0 y0 x1 y1 */
    uint32_t *first;    /* cyw cyh + 1: each cell's first item (32 bits:
                           a scene with 4G items could not take them) */
    uint32_t *item;     /* courtyards, cell by cell */
} surface_keys;

/* The courtyard count and the grid over the scene's bounds (ncy, cyw,
 * cyh, x0, y0, cell). */
void surface_keys_dims(const scene *s, surface_keys *k);
/* The grid's items: courtyard boxes times the cells they meet (dims set). */
size_t surface_keys_pairs(const scene *s, const surface_keys *k);
/* Fills ring, box, first and item (taken at those sizes). */
void surface_keys_build(const scene *s, surface_keys *k);
/* The key of the surface at (x, y) at height z (a roof's height, or 0 on
 * the ground): z on a roof and on open ground, -1 - c in courtyard c. */
double surface_key(const surface_keys *k, const scene *s, double x, double y, double z);

#endif
