/* bucketgrid: a uniform grid of buckets over the plane, for finding the
 * items (boxes or points) near a place.
 *
 * Cell (ix, iy) covers [x0 + ix / sx, x0 + (ix + 1) / sx) by the like in y;
 * places outside the frame fall in the nearest border cell, so a query of
 * any box is answered. The lists are one array in counting-sort (CSR)
 * order: cell c = iy * nx + ix lists item[start[c] .. start[c + 1]), the
 * ids of the items whose boxes meet it, ascending. Each user sizes the
 * frame by its own rule (bucketgrid_frame, or sx and sy set directly) and
 * then fills the lists: bucketgrid_fill for plain ids, or the three steps
 * bucketgrid_count / bucketgrid_offsets / bucketgrid_rewind around its own
 * placing loop when an item carries more than its id.
 */
#ifndef PLX_BUCKETGRID_H
#define PLX_BUCKETGRID_H

#include <stddef.h>
#include <stdint.h>
#include "base/arena.h"
#include "base/geom.h"

typedef struct bucketgrid {
    double x0, y0;    /* low corner of the frame */
    double sx, sy;    /* cells per metre along x and y */
    uint32_t nx, ny;
    uint32_t *start;  /* nx * ny + 1 offsets into item */
    uint32_t *item;
} bucketgrid;

/* Index along one axis of coordinate v (origin v0, s cells per metre, n
 * cells), clamped to [0, n - 1]; NaN gives 0. Monotone in v, so a point of
 * two boxes falls in a cell of both their ranges. */
static inline uint32_t bucketgrid_index(double v, double v0, double s, uint32_t n)
{
    double f = (v - v0) * s;
    if (!(f > 0.0))
        return 0;
    if (f >= (double)n)
        return n - 1;
    return (uint32_t)f;
}

/* The cell holding (x, y) (clamped into the frame). */
static inline uint32_t bucketgrid_cell(const bucketgrid *g, double x, double y)
{
    return bucketgrid_index(y, g->y0, g->sy, g->ny) * g->nx + bucketgrid_index(x, g->x0, g->sx, g->nx);
}

/* Cell range r = {ix0, iy0, ix1, iy1} covered by box b = {minx, miny, maxx, maxy}. */
static inline void bucketgrid_range(const bucketgrid *g, const double b[4], uint32_t r[4])
{
    r[0] = bucketgrid_index(b[0], g->x0, g->sx, g->nx);
    r[1] = bucketgrid_index(b[1], g->y0, g->sy, g->ny);
    r[2] = bucketgrid_index(b[2], g->x0, g->sx, g->nx);
    r[3] = bucketgrid_index(b[3], g->y0, g->sy, g->ny);
}

/* A frame of nx * ny square cells of size 'cell' from (x0, y0). */
void bucketgrid_frame(bucketgrid *g, double x0, double y0, double cell, uint32_t nx, uint32_t ny);

/* Fills the lists of n items: boxes (4 doubles each, a box with
 * !(minx <= maxx) left out) or, with box NULL, points. The lists are
 * lasting memory of 'part' (start zero-filled by arena_calloc, item one
 * slot longer than needed) or, with part PLX_PART_SCRATCH, scratch. Both
 * aligned to 'align'. PLX_E_NOMEM when the arena is short or the lists
 * would pass 2^32 entries. */
plx_status bucketgrid_fill(bucketgrid *g, arena *a, plx_part part, size_t align, const double *box,
                           const vec2 *pts, uint32_t n);

/* The steps of a fill, for a grid whose items carry more than their id:
 * with start zeroed (nx * ny + 1 entries), bucketgrid_count for each
 * item's range; bucketgrid_offsets turns the counts into cursors (returns
 * the number of entries, SIZE_MAX past 2^32); the caller then places each
 * item in cell c at slot start[c]++ in item order; bucketgrid_rewind puts
 * start back to the offsets. */
void bucketgrid_count(bucketgrid *g, const uint32_t r[4]);
size_t bucketgrid_offsets(bucketgrid *g);
void bucketgrid_rewind(bucketgrid *g);

#endif
