/* bucketgrid: uniform grid of buckets, counting-sort lists (contract in
 * bucketgrid.h). */
#include "base/bucketgrid.h"

#include <string.h>

void bucketgrid_frame(bucketgrid *g, double x0, double y0, double cell, uint32_t nx, uint32_t ny)
{
    g->x0 = x0;
    g->y0 = y0;
    g->sx = g->sy = 1.0 / cell;
    g->nx = nx;
    g->ny = ny;
}

void bucketgrid_count(bucketgrid *g, const uint32_t r[4])
{
    uint32_t x, y;
    for (y = r[1]; y <= r[3]; y++)
        for (x = r[0]; x <= r[2]; x++)
            g->start[(size_t)y * g->nx + x + 1]++;
}

size_t bucketgrid_offsets(bucketgrid *g)
{
    size_t ncell = (size_t)g->nx * g->ny, total = 0, c;
    for (c = 0; c < ncell; c++) {
        total += g->start[c + 1];
        if (total > UINT32_MAX)
            return SIZE_MAX;
        g->start[c + 1] = (uint32_t)total;
    }
    return total;
}

void bucketgrid_rewind(bucketgrid *g)
{
    size_t c;
    for (c = (size_t)g->nx * g->ny; c > 0; c--)
        g->start[c] = g->start[c - 1];
    g->start[0] = 0;
}

/* Box of item i (a point's box is the point). */
static const double *item_box(const double *box, const vec2 *pts, uint32_t i, double b[4])
{
    if (box)
        return box + 4 * (size_t)i;
    b[0] = b[2] = pts[i].x;
    b[1] = b[3] = pts[i].y;
    return b;
}

/* One pass over the items: counts them into start (place 0) or places
 * their ids at the cursors (place 1). */
static void fill_pass(bucketgrid *g, const double *box, const vec2 *pts, uint32_t n, int place)
{
    uint32_t i, x, y, r[4];
    double b[4];
    for (i = 0; i < n; i++) {
        const double *bi = item_box(box, pts, i, b);
        if (box && !(bi[0] <= bi[2]))
            continue;
        bucketgrid_range(g, bi, r);
        if (!place) {
            bucketgrid_count(g, r);
            continue;
        }
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                g->item[g->start[(size_t)y * g->nx + x]++] = i;
    }
}

static void *grid_mem(arena *a, plx_part part, size_t n, size_t align, int zero)
{
    void *p;
    if (part != PLX_PART_SCRATCH)
        return zero ? arena_calloc(a, part, n, sizeof(uint32_t), align)
                    : arena_alloc(a, part, arena_mul(n, sizeof(uint32_t)), align);
    p = arena_scratch(a, arena_mul(n, sizeof(uint32_t)), align);
    if (p && zero)
        memset(p, 0, n * sizeof(uint32_t));
    return p;
}

plx_status bucketgrid_fill(bucketgrid *g, arena *a, plx_part part, size_t align, const double *box,
                           const vec2 *pts, uint32_t n)
{
    size_t total;
    g->start = grid_mem(a, part, (size_t)g->nx * g->ny + 1, align, 1);
    if (!g->start)
        return PLX_E_NOMEM;
    fill_pass(g, box, pts, n, 0);
    total = bucketgrid_offsets(g);
    if (total == SIZE_MAX)
        return PLX_E_NOMEM;
    g->item = grid_mem(a, part, total + (part != PLX_PART_SCRATCH), align, 0);
    if (!g->item)
        return PLX_E_NOMEM;
    fill_pass(g, box, pts, n, 1);
    bucketgrid_rewind(g);
    return PLX_OK;
}
