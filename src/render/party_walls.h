/* party_walls: walls that buildings share.
 *
 * Two buildings whose footprints have the same edge the other way round
 * (the same two points, bit for bit) stand against each other there: each
 * one's wall on that edge is hidden where the other's solid (its heights
 * min_height .. height) stands against it. What is left of a wall is one
 * range of heights: the part above (or below) the solids against it that
 * reach an end of it, again until nothing changes (solids stacked one over
 * another reach it one after the other); a wall they cover from bottom to
 * top is hidden whole.
 *
 * Used by the radiance atlas (a chart covers only a wall's open part; a
 * wall hidden whole has none) and by the mesh (a wall hidden whole is not
 * drawn: it lies inside the union of the solids, where only rays exactly
 * along a shared edge could reach it, and there the neighbours' surfaces
 * meet at the same points).
 */
#ifndef PLX_PARTY_WALLS_H
#define PLX_PARTY_WALLS_H

#include "base/arena.h"
#include "base/scene.h"

/* Each wall's open heights [zlo[pt], zhi[pt]] (pt its first footprint
 * vertex, arrays of s->npts; zlo == zhi: hidden whole): its building's
 * heights less those of the solids against it. Scratch from a (two arrays
 * of about 40 bytes a footprint vertex, released by the caller); -1 when
 * short. */
int party_wall_heights(arena *a, const scene *s, double *zlo, double *zhi);

#endif
