/* surface_key: the surfaces of the horizontal photon charts (surface_key.h). */
#include <math.h>
#include <string.h>

#include "base/geom.h"
#include "photon/surface_key.h"

#define HEIGHT_TOL 1e-3     /* m: as in photon.c */

#define CY_CELL_MIN 64.0    /* m: the courtyard grid's cells at least */
#define CY_CELLS_MAX 128u   /* and at most this many a side */
#define CY_MAX (1u << 24)   /* courtyards kept apart (their keys exact in a float) */

/* Calls fn for every courtyard ring (the rings after the first of each
 * block, clockwise), at most CY_MAX. */
static uint32_t each_courtyard(const scene *s, void (*fn)(void *, const scene *, uint32_t, uint32_t), void *arg)
{
    uint32_t k, r, n = 0;
    for (k = 0; k < s->nblocks; k++)
        for (r = 1; r < s->blocks[k].ring_count && n < CY_MAX; r++) {
            uint32_t ri = s->blocks[k].ring_first + r;
            if (!(geom_ring_area2(&s->block_pts[s->block_rings[ri].first], s->block_rings[ri].count) < 0.0))
                continue;
            if (fn)
                fn(arg, s, ri, n);
            n++;
        }
    return n;
}

static void ring_box(const scene *s, uint32_t ri, double b[4])
{
    const scene_ring *R = &s->block_rings[ri];
    const vec2 *p = &s->block_pts[R->first];
    uint32_t i;
    b[0] = b[2] = p[0].x;
    b[1] = b[3] = p[0].y;
    for (i = 1; i < R->count; i++) {
        b[0] = p[i].x < b[0] ? p[i].x : b[0];
        b[1] = p[i].y < b[1] ? p[i].y : b[1];
        b[2] = p[i].x > b[2] ? p[i].x : b[2];
        b[3] = p[i].y > b[3] ? p[i].y : b[3];
    }
}

void surface_keys_dims(const scene *s, surface_keys *K)
{
    double w = s->bounds[2] - s->bounds[0], h = s->bounds[3] - s->bounds[1], side = w > h ? w : h;
    K->ncy = each_courtyard(s, NULL, NULL);
    K->x0 = s->bounds[0];
    K->y0 = s->bounds[1];
    K->cell = side / CY_CELLS_MAX > CY_CELL_MIN ? side / CY_CELLS_MAX : CY_CELL_MIN;
    K->cyw = K->ncy ? (uint32_t)ceil(w / K->cell) + 1u : 0u;
    K->cyh = K->ncy ? (uint32_t)ceil(h / K->cell) + 1u : 0u;
}

/* The cells a box meets, clamped to the grid: 0 when none. */
static int box_cells(const surface_keys *K, const double b[4], uint32_t c[4])
{
    double i0 = floor((b[0] - K->x0) / K->cell), j0 = floor((b[1] - K->y0) / K->cell);
    double i1 = floor((b[2] - K->x0) / K->cell), j1 = floor((b[3] - K->y0) / K->cell);
    if (!(i1 >= 0.0 && j1 >= 0.0 && i0 < (double)K->cyw && j0 < (double)K->cyh))
        return 0;
    c[0] = i0 > 0.0 ? (uint32_t)i0 : 0u;
    c[1] = j0 > 0.0 ? (uint32_t)j0 : 0u;
    c[2] = i1 < (double)K->cyw - 1.0 ? (uint32_t)i1 : K->cyw - 1u;
    c[3] = j1 < (double)K->cyh - 1.0 ? (uint32_t)j1 : K->cyh - 1u;
    return 1;
}

typedef struct cy_walk {
    surface_keys *K;
    size_t pairs;   /* counted */
    int fill;       /* 0 count the items, 1 count each cell's, 2 place them */
} cy_walk;

static void cy_visit(void *arg, const scene *s, uint32_t ri, uint32_t n)
{
    cy_walk *w = arg;
    surface_keys *K = w->K;
    double b[4];
    uint32_t c[4], i, j;
    ring_box(s, ri, b);
    if (w->fill == 1) {
        K->ring[n] = ri;
        memcpy(&K->box[4 * (size_t)n], b, sizeof b);
    }
    if (!box_cells(K, b, c))
        return;
    for (j = c[1]; j <= c[3]; j++)
        for (i = c[0]; i <= c[2]; i++) {
            uint32_t k = j * K->cyw + i;
            if (w->fill == 0)
                w->pairs++;
            else if (w->fill == 1)
                K->first[k + 1]++;
            else
                K->item[K->first[k]++] = n;
        }
}

size_t surface_keys_pairs(const scene *s, const surface_keys *K)
{
    cy_walk w;
    w.K = (surface_keys *)K; /* counting only: nothing written */
    w.pairs = 0;
    w.fill = 0;
    if (K->ncy)
        (void)each_courtyard(s, cy_visit, &w);
    return w.pairs;
}

/* Counts, offsets, then the items, in courtyard order within each cell. */
void surface_keys_build(const scene *s, surface_keys *K)
{
    cy_walk w;
    uint32_t k, ncell = K->cyw * K->cyh;
    if (!K->ncy)
        return;
    w.K = K;
    memset(K->first, 0, ((size_t)ncell + 1) * sizeof(uint32_t));
    w.fill = 1;
    (void)each_courtyard(s, cy_visit, &w);
    for (k = 0; k < ncell; k++)
        K->first[k + 1] += K->first[k];
    w.fill = 2; /* first[k] runs to cell k's end: then shifted back */
    (void)each_courtyard(s, cy_visit, &w);
    for (k = ncell; k > 0; k--)
        K->first[k] = K->first[k - 1];
    K->first[0] = 0;
}

double surface_key(const surface_keys *K, const scene *s, double x, double y, double z)
{
    double fi, fj;
    uint32_t k, q;
    vec2 p;
    if (z > HEIGHT_TOL || K->ncy == 0)
        return z;
    fi = floor((x - K->x0) / K->cell);
    fj = floor((y - K->y0) / K->cell);
    if (!(fi >= 0.0 && fj >= 0.0 && fi < (double)K->cyw && fj < (double)K->cyh))
        return z;
    k = (uint32_t)fj * K->cyw + (uint32_t)fi;
    for (q = K->first[k]; q < K->first[k + 1]; q++) {
        uint32_t c = K->item[q];
        const double *b = &K->box[4 * (size_t)c];
        const scene_ring *R = &s->block_rings[K->ring[c]];
        p.x = x;
        p.y = y;
        if (x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3] &&
            geom_point_in_ring(p, &s->block_pts[R->first], R->count) == GEOM_INSIDE)
            return -1.0 - (double)c;
    }
    return z;
}
