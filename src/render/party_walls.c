/* party_walls: the heights of each wall that no other building's solid
 * stands against (party_walls.h). */
#include "render/party_walls.h"
#include "base/msort.h"

/* A wall edge for finding shared walls: its end points in a fixed order
 * (the smaller first), which way it runs, its first vertex's index. */
typedef struct wall_key {
    vec2 a, b;
    uint32_t pt, bld;
    int flip;
} wall_key;

static int key_before(const wall_key *p, const wall_key *q, void *ctx)
{
    (void)ctx;
    if (p->a.x != q->a.x)
        return p->a.x < q->a.x;
    if (p->a.y != q->a.y)
        return p->a.y < q->a.y;
    if (p->b.x != q->b.x)
        return p->b.x < q->b.x;
    if (p->b.y != q->b.y)
        return p->b.y < q->b.y;
    return p->pt < q->pt;
}

MSORT_DEFINE(sort_keys, wall_key, void *, key_before)

static int pt_before(vec2 p, vec2 q)
{
    return p.x < q.x || (p.x == q.x && p.y < q.y);
}

/* Takes from wall [zlo, zhi] of pt the part building o's solid (its
 * heights) stands against, when that part reaches an end of it. */
static void cut_wall(const scene *s, uint32_t o, double *zlo, double *zhi)
{
    double lo = s->bld[o].min_height, hi = s->bld[o].height;
    if (lo <= *zlo && hi >= *zhi)
        *zlo = *zhi; /* hidden whole */
    else if (lo <= *zlo && hi > *zlo)
        *zlo = hi;
    else if (hi >= *zhi && lo < *zhi)
        *zhi = lo;
}

/* Wall x of keys i .. j-1 (one edge) cut by every building on the other
 * side of the edge, again until no cut changes it: solids stacked against
 * it (one over another) reach its end one after the other, in any order. */
static void cut_by_all(const scene *s, const wall_key *k, uint32_t i, uint32_t j, uint32_t x, double *zlo,
                       double *zhi)
{
    int changed = 1;
    while (changed && *zhi > *zlo) {
        double lo = *zlo, hi = *zhi;
        uint32_t y;
        for (y = i; y < j; y++)
            if (k[x].flip != k[y].flip && k[x].bld != k[y].bld)
                cut_wall(s, k[y].bld, zlo, zhi);
        changed = *zlo != lo || *zhi != hi;
    }
}

int party_wall_heights(arena *a, const scene *s, double *zlo, double *zhi)
{
    wall_key *k = arena_scratch(a, arena_mul(s->npts, sizeof *k), 8);
    wall_key *tmp = k ? arena_scratch(a, arena_mul(s->npts, sizeof *k), 8) : NULL;
    uint32_t b, r, i, n = 0, j;
    if (!tmp)
        return -1;
    for (b = 0; b < s->nbld; b++)
        for (r = s->bld[b].ring_first; r < s->bld[b].ring_first + s->bld[b].ring_count; r++)
            for (i = 0; i < s->rings[r].count; i++) {
                uint32_t p = s->rings[r].first + i;
                vec2 u = s->pts[p], v = s->pts[s->rings[r].first + (i + 1) % s->rings[r].count];
                k[n].flip = pt_before(v, u);
                k[n].a = k[n].flip ? v : u;
                k[n].b = k[n].flip ? u : v;
                k[n].pt = p;
                k[n].bld = b;
                zlo[p] = s->bld[b].min_height;
                zhi[p] = s->bld[b].height;
                n++;
            }
    sort_keys(k, tmp, n, NULL);
    for (i = 0; i < n; i = j) {
        uint32_t x;
        for (j = i + 1; j < n && k[j].a.x == k[i].a.x && k[j].a.y == k[i].a.y && k[j].b.x == k[i].b.x &&
                        k[j].b.y == k[i].b.y;
             j++)
            ;
        for (x = i; x < j; x++)
            cut_by_all(s, k, i, j, x, &zlo[k[x].pt], &zhi[k[x].pt]);
    }
    return 0;
}
