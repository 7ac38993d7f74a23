/* atlas: the radiance atlas's charts and its reads (atlas.h). */
#include <math.h>
#include <string.h>

#include "render/atlas.h"
#include "render/texel.h"
#include "render/party_walls.h"
#include "base/bucketgrid.h"
#include "base/geom.h"
#include "base/msort.h"

/* Vertices along a side of length len at most 'step' apart: at least 2. */
static uint32_t side_vertices(double len, double step)
{
    double n = ceil(len / step - 1e-9);
    if (!(n >= 1.0))
        return 2u;
    if (n > 65534.0)
        n = 65534.0;
    return (uint32_t)n + 1u;
}

/* Whether lamp l may light the ground: a photometric lamp counts even
 * before its table is given (its intensity is 0 until then, and the
 * atlas's layout does not change when it comes). */
static int lights_ground(const scene_lamp *l)
{
    return (l->intensity > 0.0 || l->photometry) && l->z < l->radius;
}

/* The box the ground tiles cover: Bounds and every lamp's ground reach. */
static void ground_box(const scene *s, double b[4])
{
    uint32_t i;
    memcpy(b, s->bounds, 4 * sizeof *b);
    for (i = 0; i < s->nlamps; i++) {
        const scene_lamp *l = &s->lamps[i];
        double rg;
        if (!lights_ground(l))
            continue;
        rg = sqrt(l->radius * l->radius - l->z * l->z);
        b[0] = fmin(b[0], l->x - rg);
        b[1] = fmin(b[1], l->y - rg);
        b[2] = fmax(b[2], l->x + rg);
        b[3] = fmax(b[3], l->y + rg);
    }
}

/* The ground tile grid for fine spacing 'fine'. */
static void tile_frame(const scene *s, double fine, double g0[2], double *tile, uint32_t *gx, uint32_t *gy)
{
    double b[4], nx, ny;
    ground_box(s, b);
    *tile = ATLAS_TILE * fine;
    g0[0] = b[0];
    g0[1] = b[1];
    nx = ceil((b[2] - b[0]) / *tile);
    ny = ceil((b[3] - b[1]) / *tile);
    *gx = nx >= 1.0 ? (nx < 65536.0 ? (uint32_t)nx : 65536u) : 1u;
    *gy = ny >= 1.0 ? (ny < 65536.0 ? (uint32_t)ny : 65536u) : 1u;
}

/* Marks (1) every ground tile some lamp's ground reach disk meets (its
 * box, conservatively), into fine[gx * gy]. */
static void mark_fine_tiles(const scene *s, const double g0[2], double tile, uint32_t gx, uint32_t gy,
                            uint8_t *fine)
{
    uint32_t i, x, y;
    memset(fine, 0, (size_t)gx * gy);
    for (i = 0; i < s->nlamps; i++) {
        const scene_lamp *l = &s->lamps[i];
        double rg, x0, x1, y0, y1;
        if (!lights_ground(l))
            continue;
        rg = sqrt(l->radius * l->radius - l->z * l->z);
        x0 = floor((l->x - rg - g0[0]) / tile);
        x1 = floor((l->x + rg - g0[0]) / tile);
        y0 = floor((l->y - rg - g0[1]) / tile);
        y1 = floor((l->y + rg - g0[1]) / tile);
        x0 = x0 < 0.0 ? 0.0 : x0;
        y0 = y0 < 0.0 ? 0.0 : y0;
        x1 = x1 > gx - 1.0 ? gx - 1.0 : x1;
        y1 = y1 > gy - 1.0 ? gy - 1.0 : y1;
        for (y = (uint32_t)y0; y1 >= 0.0 && y <= (uint32_t)y1; y++)
            for (x = (uint32_t)x0; x1 >= 0.0 && x <= (uint32_t)x1; x++)
                fine[(size_t)y * gx + x] = 1;
    }
}

/* ---- one chart of each kind ------------------------------------------------- */

static void chart_grid(atlas_chart *c, double lu, double lv, double step)
{
    c->nu = side_vertices(lu, step);
    c->nv = side_vertices(lv, step);
    c->tu = (float)(lu > 0.0 ? lu / (c->nu - 1) : step);
    c->tv = (float)(lv > 0.0 ? lv / (c->nv - 1) : step);
}

static void wall_chart(atlas_chart *c, const scene *s, uint32_t b, vec2 p, vec2 q, double step)
{
    const scene_building *bd = &s->bld[b];
    double dx = q.x - p.x, dy = q.y - p.y, len = sqrt(dx * dx + dy * dy);
    c->kind = ATLAS_WALL;
    c->bld = b;
    c->o[0] = p.x;
    c->o[1] = p.y;
    c->o[2] = bd->min_height;
    c->e[0] = (float)(len > 0.0 ? dx / len : 1.0);
    c->e[1] = (float)(len > 0.0 ? dy / len : 0.0);
    chart_grid(c, len, bd->height - bd->min_height, step);
}

static void flat_chart(atlas_chart *c, const scene_building *bd, uint32_t b, int kind, double step)
{
    c->kind = (uint8_t)kind;
    c->bld = b;
    c->o[0] = bd->box[0];
    c->o[1] = bd->box[1];
    c->o[2] = kind == ATLAS_ROOF ? bd->height : bd->min_height;
    c->e[0] = 1.0f;
    c->e[1] = 0.0f;
    chart_grid(c, bd->box[2] - bd->box[0], bd->box[3] - bd->box[1], step);
}

/* ---- ground blocks under buildings ----------------------------------------------- */

/* Twice the signed area of ring p (n vertices) clipped to the box q
 * (x0, y0, x1, y1): Sutherland-Hodgman against the four sides, buffers
 * buf0 and buf1 of n + 8 points each. */
static double clipped_area2(const vec2 *p, uint32_t n, const double q[4], vec2 *buf0, vec2 *buf1)
{
    const vec2 *in = p;
    vec2 *out = buf0;
    uint32_t m = n, side, i, k;
    double a = 0.0;
    for (side = 0; side < 4 && m > 0; side++) {
        uint32_t o = 0;
        for (i = 0; i < m; i++) {
            vec2 c = in[i], d = in[(i + 1) % m];
            double fc, fd;
            switch (side) {
            case 0: fc = c.x - q[0]; fd = d.x - q[0]; break;
            case 1: fc = q[2] - c.x; fd = q[2] - d.x; break;
            case 2: fc = c.y - q[1]; fd = d.y - q[1]; break;
            default: fc = q[3] - c.y; fd = q[3] - d.y; break;
            }
            if (fc >= 0.0)
                out[o++] = c;
            if ((fc >= 0.0) != (fd >= 0.0)) {
                double t = fc / (fc - fd);
                out[o].x = c.x + t * (d.x - c.x);
                out[o].y = c.y + t * (d.y - c.y);
                o++;
            }
        }
        m = o;
        in = out;
        out = out == buf0 ? buf1 : buf0;
    }
    for (k = 0; k < m; k++)
        a += in[k].x * in[(k + 1) % m].y - in[(k + 1) % m].x * in[k].y;
    return a;
}

/* What finding covered blocks needs: the buildings standing on the
 * ground by box (cells of 32 m, larger over a large Bounds: at most 1024
 * a side, so the grid's scratch follows the scene's extent no further),
 * and clip buffers. */
typedef struct cover_ctx {
    const scene *s;
    bucketgrid g;
    vec2 *buf0, *buf1;
} cover_ctx;

static int cover_init(cover_ctx *cc, arena *a, const scene *s)
{
    double *box = arena_scratch(a, arena_mul(s->nbld ? s->nbld : 1, 4 * sizeof(double)), 8);
    uint32_t b, most = 0, r;
    double cell = fmax(32.0, fmax(s->bounds[2] - s->bounds[0], s->bounds[3] - s->bounds[1]) / 1024.0);
    cc->s = s;
    if (!box)
        return -1;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        memcpy(&box[4 * b], bd->box, 4 * sizeof(double));
        if (bd->min_height != 0.0)
            box[4 * b + 2] = box[4 * b] - 1.0; /* left out: light and views pass under it */
        for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++)
            most = s->rings[r].count > most ? s->rings[r].count : most;
    }
    bucketgrid_frame(&cc->g, s->bounds[0], s->bounds[1], cell,
                     (uint32_t)ceil((s->bounds[2] - s->bounds[0]) / cell) + 1,
                     (uint32_t)ceil((s->bounds[3] - s->bounds[1]) / cell) + 1);
    cc->buf0 = arena_scratch(a, arena_mul(most + 8, sizeof(vec2)), 8);
    cc->buf1 = cc->buf0 ? arena_scratch(a, arena_mul(most + 8, sizeof(vec2)), 8) : NULL;
    if (!cc->buf1 || bucketgrid_fill(&cc->g, a, PLX_PART_SCRATCH, 8, box, NULL, s->nbld) != PLX_OK)
        return -1;
    return 0;
}

/* Whether ground point p lies strictly inside a solid standing on the
 * ground. */
static int under_solid(const cover_ctx *cc, vec2 p)
{
    uint32_t cell = bucketgrid_cell(&cc->g, p.x, p.y), k;
    for (k = cc->g.start[cell]; k < cc->g.start[cell + 1]; k++) {
        const scene *s = cc->s;
        const scene_building *bd = &s->bld[cc->g.item[k]];
        uint32_t r;
        int in;
        if (bd->min_height != 0.0 || p.x <= bd->box[0] || p.x >= bd->box[2] || p.y <= bd->box[1] ||
            p.y >= bd->box[3])
            continue;
        in = geom_point_in_ring(p, &s->pts[s->rings[bd->ring_first].first], s->rings[bd->ring_first].count) ==
             GEOM_INSIDE;
        for (r = bd->ring_first + 1; in && r < bd->ring_first + bd->ring_count; r++)
            in = geom_point_in_ring(p, &s->pts[s->rings[r].first], s->rings[r].count) == GEOM_OUTSIDE;
        if (in)
            return 1;
    }
    return 0;
}

/* Whether point p lies strictly inside building b's footprint (outer
 * ring in, holes out, boundaries out). */
static int strictly_in(const scene *s, uint32_t b, vec2 p)
{
    const scene_building *bd = &s->bld[b];
    uint32_t r;
    if (geom_point_in_ring(p, &s->pts[s->rings[bd->ring_first].first], s->rings[bd->ring_first].count) != GEOM_INSIDE)
        return 0;
    for (r = bd->ring_first + 1; r < bd->ring_first + bd->ring_count; r++)
        if (geom_point_in_ring(p, &s->pts[s->rings[r].first], s->rings[r].count) != GEOM_OUTSIDE)
            return 0;
    return 1;
}

/* Whether footprint a's edges enter footprint b's interior: an edge of a
 * crosses one of b, or a vertex of a, or a point just inside a next to an
 * edge's middle (a copy of b, or a lying within b), lies strictly inside
 * b. Footprints that only share walls do not. */
static int enters(const scene *s, uint32_t a, uint32_t b)
{
    const scene_building *ba = &s->bld[a], *bb = &s->bld[b];
    uint32_t ra, rb, i, j;
    if (ba->box[2] < bb->box[0] || ba->box[0] > bb->box[2] || ba->box[3] < bb->box[1] || ba->box[1] > bb->box[3])
        return 0;
    for (ra = ba->ring_first; ra < ba->ring_first + ba->ring_count; ra++) {
        const scene_ring *g = &s->rings[ra];
        for (i = 0; i < g->count; i++) {
            vec2 u = s->pts[g->first + i], v = s->pts[g->first + (i + 1) % g->count], m;
            double ex = v.x - u.x, ey = v.y - u.y, l = sqrt(ex * ex + ey * ey);
            if (strictly_in(s, b, u))
                return 1;
            /* inward is left of the edge (outer rings counter-clockwise, holes clockwise) */
            m.x = 0.5 * (u.x + v.x) - 1e-6 * ey / (l > 0.0 ? l : 1.0);
            m.y = 0.5 * (u.y + v.y) + 1e-6 * ex / (l > 0.0 ? l : 1.0);
            if (strictly_in(s, b, m))
                return 1;
            for (rb = bb->ring_first; rb < bb->ring_first + bb->ring_count; rb++)
                for (j = 0; j < s->rings[rb].count; j++) {
                    const scene_ring *h = &s->rings[rb];
                    if (geom_seg_meet(u, v, s->pts[h->first + j], s->pts[h->first + (j + 1) % h->count]) ==
                        GEOM_SEG_CROSS)
                        return 1;
                }
        }
    }
    return 0;
}

/* Whether the ground block q (x0, y0, x1, y1, its vertices 'step' apart)
 * is wholly under footprints: one footprint's area within it is its
 * area, or the footprints' areas add up to it and no two of them overlap
 * (else overlaps could make up for a gap); and every vertex lies strictly
 * inside one. */
#define COVER_MAX 16 /* footprints meeting a block that the overlap check takes */
static int block_covered(const cover_ctx *cc, const double q[4], double step)
{
    const scene *s = cc->s;
    uint32_t r0[4], x, y, k, i, j, got[COVER_MAX], ngot = 0;
    double area = 0.0, full = (q[2] - q[0]) * (q[3] - q[1]);
    int one = 0;
    bucketgrid_range(&cc->g, q, r0);
    for (y = r0[1]; y <= r0[3]; y++)
        for (x = r0[0]; x <= r0[2]; x++)
            for (k = cc->g.start[y * cc->g.nx + x]; k < cc->g.start[y * cc->g.nx + x + 1]; k++) {
                uint32_t b = cc->g.item[k], r;
                const scene_building *bd = &s->bld[b];
                double a = 0.0;
                /* count each building once: in the first cell of the range its box meets */
                if (bd->min_height != 0.0 || bd->box[2] <= q[0] || bd->box[0] >= q[2] || bd->box[3] <= q[1] ||
                    bd->box[1] >= q[3] || bucketgrid_index(fmax(bd->box[0], q[0]), cc->g.x0, cc->g.sx, cc->g.nx) != x ||
                    bucketgrid_index(fmax(bd->box[1], q[1]), cc->g.y0, cc->g.sy, cc->g.ny) != y)
                    continue;
                for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++)
                    a += 0.5 * clipped_area2(&s->pts[s->rings[r].first], s->rings[r].count, q, cc->buf0, cc->buf1);
                if (!(a > 0.0))
                    continue;
                if (a >= full * (1.0 - 1e-9))
                    one = 1; /* one footprint covers it: no overlap can matter */
                if (ngot < COVER_MAX)
                    got[ngot] = b;
                ngot++;
                area += a;
            }
    if (area < full * (1.0 - 1e-9))
        return 0;
    if (!one && ngot > COVER_MAX)
        return 0; /* too many to check for overlaps: kept */
    for (i = 0; !one && i < ngot; i++)
        for (j = 0; j < ngot; j++)
            if (i != j && enters(s, got[i], got[j]))
                return 0;
    for (j = 0; j <= ATLAS_BLOCK; j++)
        for (i = 0; i <= ATLAS_BLOCK; i++) {
            vec2 p;
            p.x = q[0] + i * step;
            p.y = q[1] + j * step;
            if (!under_solid(cc, p))
                return 0;
        }
    return 1;
}

/* ---- layout ------------------------------------------------------------------ */

/* Places chart c (kind set) at the next free vertex: stores it as chart
 * k when A has charts; counts its vertices. 0, or -1 past 2^32 vertices. */
static int place(atlas *A, uint32_t k, atlas_chart *c, uint64_t *n)
{
    uint64_t cnt = (uint64_t)c->nu * c->nv;
    if (c->kind == ATLAS_NONE)
        return 0;
    if (*n + cnt > UINT32_MAX)
        return -1;
    c->first = (uint32_t)*n;
    *n += cnt;
    if (c->fine)
        A->ntex_fine += cnt;
    if (A->chart)
        A->chart[k] = *c;
    return 0;
}

/* The chart of building b's surface sid of the given kind (a wall: its
 * visible heights zlo .. zhi). */
static void surface_chart(const atlas *A, atlas_chart *c, uint32_t b, uint32_t sid, int kind, vec2 p, vec2 q,
                          double zlo, double zhi)
{
    int lit = mesh_lit(A->m, sid);
    double step = lit ? A->fine : A->coarse;
    memset(c, 0, sizeof *c);
    if (kind == ATLAS_WALL) {
        if (!(zhi > zlo))
            return; /* hidden whole: ATLAS_NONE */
        wall_chart(c, A->s, b, p, q, step);
        c->o[2] = zlo;
        c->nv = side_vertices(zhi - zlo, step);
        c->tv = (float)((zhi - zlo) / (c->nv - 1));
    } else {
        flat_chart(c, &A->s->bld[b], b, kind, step);
    }
    c->fine = (uint8_t)lit;
}

/* Building b's charts: its walls ring by ring, its roof, its underside
 * (raised buildings only). */
static int lay_building(atlas *A, uint32_t b, const double *zlo, const double *zhi, uint64_t *n)
{
    const scene *s = A->s;
    const scene_building *bd = &s->bld[b];
    atlas_chart c;
    vec2 o = { 0.0, 0.0 };
    uint32_t r, k;
    for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[r];
        for (k = 0; k < rg->count; k++) {
            uint32_t pt = rg->first + k, sid = mesh_wall_id(s, pt);
            surface_chart(A, &c, b, sid, ATLAS_WALL, s->pts[pt], s->pts[rg->first + (k + 1) % rg->count], zlo[pt],
                          zhi[pt]);
            if (place(A, sid - 2u, &c, n) != 0)
                return -1;
        }
    }
    surface_chart(A, &c, b, mesh_roof_id(s, b), ATLAS_ROOF, o, o, 0.0, 0.0);
    if (place(A, mesh_roof_id(s, b) - 2u, &c, n) != 0)
        return -1;
    if (!(bd->min_height > 0.0))
        return 0;
    surface_chart(A, &c, b, mesh_under_id(s, b), ATLAS_UNDER, o, o, 0.0, 0.0);
    return place(A, mesh_under_id(s, b) - 2u, &c, n);
}

/* Tile t's blocks: their first vertices (A->gfirst when set), counted. */
static int lay_tile(atlas *A, const cover_ctx *cc, uint32_t tx, uint32_t ty, int fine, uint64_t *n)
{
    uint32_t nb = fine ? ATLAS_TB : 1, bx, by, t = ty * A->gx + tx;
    double step = fine ? A->fine : A->coarse, side = ATLAS_BLOCK * step;
    uint32_t per = (ATLAS_BLOCK + 1) * (ATLAS_BLOCK + 1);
    if (A->gfine)
        A->gfine[t] = (uint8_t)fine;
    for (by = 0; by < ATLAS_TB; by++)
        for (bx = 0; bx < ATLAS_TB; bx++) {
            double q[4];
            uint32_t first = ATLAS_NOVERT;
            q[0] = A->g0[0] + tx * A->tile + bx * side;
            q[1] = A->g0[1] + ty * A->tile + by * side;
            q[2] = q[0] + side;
            q[3] = q[1] + side;
            if (bx < nb && by < nb && !block_covered(cc, q, step)) {
                if (*n + per > UINT32_MAX)
                    return -1;
                first = (uint32_t)*n;
                *n += per;
                if (fine)
                    A->ntex_fine += per;
            }
            if (A->gfirst)
                A->gfirst[(size_t)t * ATLAS_TB * ATLAS_TB + by * ATLAS_TB + bx] = first;
        }
    return 0;
}

/* Every chart and block (stored when A->chart is set); returns the
 * vertex count, UINT64_MAX past 2^32. */
static uint64_t lay(atlas *A, const uint8_t *fine_tile, const double *zlo, const double *zhi, const cover_ctx *cc)
{
    uint64_t n = 0;
    uint32_t b, x, y;
    A->ntex_fine = 0;
    for (b = 0; b < A->s->nbld; b++)
        if (lay_building(A, b, zlo, zhi, &n) != 0)
            return UINT64_MAX;
    for (y = 0; y < A->gy; y++)
        for (x = 0; x < A->gx; x++)
            if (lay_tile(A, cc, x, y, fine_tile[(size_t)y * A->gx + x], &n) != 0)
                return UINT64_MAX;
    return n;
}

/* The frame of an atlas at fine spacing 'fine' (no memory yet); -1 when
 * its tiles would be too many. */
static int frame(atlas *A, const scene *s, const mesh *m, double fine)
{
    memset(A, 0, sizeof *A);
    A->s = s;
    A->m = m;
    A->fine = fine;
    A->coarse = fine * ATLAS_COARSE;
    tile_frame(s, fine, A->g0, &A->tile, &A->gx, &A->gy);
    A->inv_tile = 1.0 / A->tile;
    A->inv_fine = 1.0 / A->fine;
    A->inv_coarse = 1.0 / A->coarse;
    A->nsurf = s->npts + 2u * s->nbld;
    if ((uint64_t)A->gx * A->gy > (uint64_t)(UINT32_MAX / 64))
        return -1;
    return 0;
}

static size_t bytes_for(const atlas *A, uint64_t ntex)
{
    size_t c = arena_mul(A->nsurf, sizeof(atlas_chart) + 1), g = arena_mul((size_t)A->gx * A->gy, 5 * ATLAS_TB * ATLAS_TB + 1), t;
    if (ntex == UINT64_MAX || c == SIZE_MAX || g == SIZE_MAX)
        return SIZE_MAX;
    t = arena_mul((size_t)ntex, sizeof(uint32_t));
    return t == SIZE_MAX ? SIZE_MAX : sizeof(atlas) + c + g + t + 6 * 64;
}

/* What laying out needs, in scratch from a: the fine tiles' marks, the
 * walls' visible heights, the footprints' grid. */
typedef struct lay_scratch {
    uint8_t *marks;
    double *zlo, *zhi;
    cover_ctx cc;
} lay_scratch;

static int lay_scratch_get(arena *a, const atlas *A, lay_scratch *ls)
{
    const scene *s = A->s;
    size_t np = s->npts ? s->npts : 1;
    ls->marks = arena_scratch(a, (size_t)A->gx * A->gy, 8);
    ls->zlo = ls->marks ? arena_scratch(a, arena_mul(np, sizeof(double)), 8) : NULL;
    ls->zhi = ls->zlo ? arena_scratch(a, arena_mul(np, sizeof(double)), 8) : NULL;
    if (!ls->zhi || party_wall_heights(a, s, ls->zlo, ls->zhi) != 0 || cover_init(&ls->cc, a, s) != 0)
        return -1;
    mark_fine_tiles(s, A->g0, A->tile, A->gx, A->gy, ls->marks);
    return 0;
}

/* Releases the scratch taken since mark m, keeping what was allocated. */
static void drop_scratch(arena *a, const arena_mark *m)
{
    arena_mark cur = arena_get_mark(a);
    cur.hi = m->hi;
    cur.used[PLX_PART_SCRATCH] = m->used[PLX_PART_SCRATCH];
    arena_release(a, &cur);
}

size_t atlas_plan(arena *a, const scene *s, const mesh *m, double fine, uint64_t *ntex)
{
    atlas F;
    arena_mark mk = arena_get_mark(a);
    lay_scratch ls;
    uint64_t n;
    if (!(fine > 0.0) || !isfinite(fine) || frame(&F, s, m, fine) != 0)
        return SIZE_MAX;
    if (lay_scratch_get(a, &F, &ls) != 0) {
        arena_release(a, &mk);
        return SIZE_MAX;
    }
    n = lay(&F, ls.marks, ls.zlo, ls.zhi, &ls.cc);
    arena_release(a, &mk);
    if (ntex)
        *ntex = n;
    return bytes_for(&F, n);
}

/* m: the finest first plan atlas_spacing_for makes. Coarser than 4 cm,
 * whose plan took seconds; fine enough that every spacing asked from
 * ATLAS_GUESS / 4 up gets the first plan, and so the answer, it got
 * before: atlas_plan's bytes do not always fall as the spacing grows
 * (tiny.geojson: 0.67 m 110,960 bytes, 0.80 m 117,587), so a guess from
 * elsewhere can stop at another step. */
#define ATLAS_GUESS 0.25

/* Whether the plan at spacing f fits max_bytes (its vertex count in *n,
 * UINT64_MAX when the plan was not made); *known: 1 when it was made (0: no scratch for it, or past 2^32 vertices,
 * which a later plan at this spacing may not meet again). */
static int plan_fits(arena *a, const scene *s, const mesh *m, double f, size_t max_bytes, uint64_t *n, int *known)
{
    size_t b = atlas_plan(a, s, m, f, n);
    *known = b != SIZE_MAX;
    if (!*known)
        *n = UINT64_MAX; /* not counted (it "fits" a budget of SIZE_MAX) */
    return b <= max_bytes;
}

double atlas_spacing_for(arena *a, const scene *s, const mesh *m, double fine, size_t max_bytes, uint64_t *ntex)
{
    const double step = 1.189207115002721; /* 2^(1/4) */
    double f0 = fine > 0.0 && isfinite(fine) ? fine : ATLAS_FINE_DEFAULT, c, g;
    size_t bc;
    uint64_t n_at, n_below;
    int k = 0, n, known, bad = -1; /* bad: a step whose plan was made and did not fit */
    /* a first guess k steps up from a plan at four times the spacing, or
     * at ATLAS_GUESS when that is coarser (a plan's time grows with its
     * points), its bytes growing about as 1 / spacing^2; then the finest
     * step that fits: down while the next finer one fits, else up until
     * one does (the step below one that fits is not planned again when
     * it was the one that did not) */
    g = fmax(4.0 * f0, ATLAS_GUESS);
    bc = atlas_plan(a, s, m, g, NULL);
    if (bc != SIZE_MAX && bc > 0 && max_bytes > 0) {
        c = g * sqrt((double)bc / (double)max_bytes);
        while (f0 * pow(step, k + 1) <= c && k < 64)
            k++;
    }
    for (n = 0; n < 64 && f0 * pow(step, k) <= fmax(ATLAS_COARSEST, f0); n++) {
        if (plan_fits(a, s, m, f0 * pow(step, k), max_bytes, &n_at, &known)) {
            while (k > 0 && k - 1 != bad && plan_fits(a, s, m, f0 * pow(step, k - 1), max_bytes, &n_below, &known)) {
                k--;
                n_at = n_below;
            }
            if (ntex)
                *ntex = n_at;
            return f0 * pow(step, k);
        }
        bad = known ? k : -1;
        k++;
    }
    return 0.0;
}

/* atlas_create with the vertex count n when known (else n_known 0). */
static plx_status create(arena *a, const scene *s, const mesh *m, double fine, int n_known, uint64_t n, atlas **out)
{
    atlas F, *A;
    arena_mark mk;
    lay_scratch ls;
    size_t nt;
    if (!a || !s || !m || !out || !(fine > 0.0) || !isfinite(fine))
        return PLX_E_INVALID;
    mk = arena_get_mark(a);
    if (frame(&F, s, m, fine) != 0)
        return PLX_E_NOMEM;
    if (lay_scratch_get(a, &F, &ls) != 0) {
        arena_release(a, &mk);
        return PLX_E_NOMEM;
    }
    if (!n_known) /* the count first: nothing lasting taken if it does not fit */
        n = lay(&F, ls.marks, ls.zlo, ls.zhi, &ls.cc);
    F.ntex = n;
    F.bytes = bytes_for(&F, n);
    nt = (size_t)F.gx * F.gy;
    A = F.bytes != SIZE_MAX ? arena_alloc(a, PLX_PART_FRAME, sizeof *A, 64) : NULL;
    F.chart = A ? arena_calloc(a, PLX_PART_FRAME, F.nsurf ? F.nsurf : 1, sizeof(atlas_chart), 64) : NULL;
    F.gfirst = F.chart ? arena_alloc(a, PLX_PART_FRAME, arena_mul(nt, 4 * ATLAS_TB * ATLAS_TB), 64) : NULL;
    F.gfine = F.gfirst ? arena_alloc(a, PLX_PART_FRAME, nt, 64) : NULL;
    F.cdone = F.gfine ? arena_calloc(a, PLX_PART_FRAME, F.nsurf ? F.nsurf : 1, 1, 64) : NULL;
    F.gdone = F.cdone ? arena_calloc(a, PLX_PART_FRAME, nt * ATLAS_TB * ATLAS_TB, 1, 64) : NULL;
    F.tex = F.gdone ? arena_calloc(a, PLX_PART_FRAME, n ? (size_t)n : 1, sizeof(uint32_t), 64) : NULL;
    if (!F.tex || lay(&F, ls.marks, ls.zlo, ls.zhi, &ls.cc) != n) { /* a count not this layout's: refused */
        arena_release(a, &mk);
        return F.tex ? PLX_E_INVALID : PLX_E_NOMEM;
    }
    drop_scratch(a, &mk);
    *A = F;
    atlas_clear(A, 0);
    *out = A;
    return PLX_OK;
}

plx_status atlas_create(arena *a, const scene *s, const mesh *m, double fine, atlas **out)
{
    return create(a, s, m, fine, 0, 0, out);
}

plx_status atlas_create_counted(arena *a, const scene *s, const mesh *m, double fine, uint64_t ntex, atlas **out)
{
    return create(a, s, m, fine, 1, ntex, out);
}

void atlas_clear(atlas *A, uint64_t key)
{
    size_t k, nb = (size_t)A->gx * A->gy * ATLAS_TB * ATLAS_TB;
    A->todo = 0;
    for (k = 0; k < A->nsurf; k++) {
        A->cdone[k] = 0;
        A->todo += A->chart[k].kind != ATLAS_NONE;
    }
    for (k = 0; k < nb; k++) {
        A->gdone[k] = 0;
        A->todo += A->gfirst[k] != ATLAS_NOVERT;
    }
    A->key = key;
    A->with_ind = 0;
}

/* ---- reads ---------------------------------------------------------------------- */

void atlas_ground_block(const atlas *A, uint32_t tx, uint32_t ty, uint32_t bx, uint32_t by, atlas_chart *c)
{
    uint32_t t = ty * A->gx + tx, first = A->gfirst[(size_t)t * ATLAS_TB * ATLAS_TB + by * ATLAS_TB + bx];
    double step = A->gfine[t] ? A->fine : A->coarse;
    memset(c, 0, sizeof *c);
    if (first == ATLAS_NOVERT)
        return;
    c->kind = ATLAS_GROUND;
    c->bld = UINT32_MAX;
    c->fine = A->gfine[t];
    c->o[0] = A->g0[0] + tx * A->tile + bx * ATLAS_BLOCK * step;
    c->o[1] = A->g0[1] + ty * A->tile + by * ATLAS_BLOCK * step;
    c->o[2] = 0.0;
    c->e[0] = 1.0f;
    c->e[1] = 0.0f;
    c->tu = c->tv = (float)step;
    c->nu = c->nv = ATLAS_BLOCK + 1;
    c->first = first;
}

int atlas_ground_chart(const atlas *A, double x, double y, atlas_chart *c)
{
    double fx = floor((x - A->g0[0]) / A->tile), fy = floor((y - A->g0[1]) / A->tile), bs, bx, by;
    uint32_t tx, ty;
    if (!(fx >= 0.0 && fx < A->gx && fy >= 0.0 && fy < A->gy))
        return 0;
    tx = (uint32_t)fx;
    ty = (uint32_t)fy;
    bs = ATLAS_BLOCK * (A->gfine[ty * A->gx + tx] ? A->fine : A->coarse);
    bx = floor((x - A->g0[0] - tx * A->tile) / bs);
    by = floor((y - A->g0[1] - ty * A->tile) / bs);
    bx = bx < 0.0 ? 0.0 : bx > ATLAS_TB - 1 ? ATLAS_TB - 1 : bx;
    by = by < 0.0 ? 0.0 : by > ATLAS_TB - 1 ? ATLAS_TB - 1 : by;
    atlas_ground_block(A, tx, ty, (uint32_t)bx, (uint32_t)by, c);
    return c->kind == ATLAS_GROUND;
}

void atlas_vertex_point(const atlas_chart *c, uint32_t i, uint32_t j, double P[3])
{
    double u = (double)i * c->tu, v = (double)j * c->tv;
    if (c->kind == ATLAS_WALL) {
        P[0] = c->o[0] + u * c->e[0];
        P[1] = c->o[1] + u * c->e[1];
        P[2] = c->o[2] + v;
    } else {
        P[0] = c->o[0] + u;
        P[1] = c->o[1] + v;
        P[2] = c->o[2];
    }
}

void atlas_chart_uv(const atlas_chart *c, const double P[3], double *u, double *v)
{
    double dx = P[0] - c->o[0], dy = P[1] - c->o[1];
    if (c->kind == ATLAS_WALL) {
        *u = (dx * c->e[0] + dy * c->e[1]) / c->tu;
        *v = (P[2] - c->o[2]) / c->tv;
    } else {
        *u = dx / c->tu;
        *v = dy / c->tv;
    }
}

void atlas_chart_normal(const atlas_chart *c, double n[3])
{
    n[0] = n[1] = n[2] = 0.0;
    if (c->kind == ATLAS_WALL) { /* outer rings run counter-clockwise, holes clockwise: out is right */
        n[0] = c->e[1];
        n[1] = -c->e[0];
    } else {
        n[2] = c->kind == ATLAS_UNDER ? -1.0 : 1.0;
    }
}

/* Cell index and weight along one axis of n vertices: i in 0 .. n - 2. */
static void axis(double u, uint32_t n, uint32_t *i, float *f)
{
    double fl;
    if (!(u > 0.0)) {
        *i = 0;
        *f = 0.0f;
        return;
    }
    if (u >= (double)(n - 1)) {
        *i = n - 2;
        *f = 1.0f;
        return;
    }
    fl = floor(u);
    *i = (uint32_t)fl;
    *f = (float)(u - fl);
}

void atlas_sample_uv(const atlas *A, const atlas_chart *c, double u, double v, float rgb[3])
{
    const uint32_t *t;
    float a[3], b[3], d[3], e[3], fu, fv;
    uint32_t i, j;
    int k;
    axis(u, c->nu, &i, &fu);
    axis(v, c->nv, &j, &fv);
    t = &A->tex[c->first + (size_t)j * c->nu + i];
    texel_unpack(t[0], a);
    texel_unpack(t[1], b);
    texel_unpack(t[c->nu], d);
    texel_unpack(t[c->nu + 1], e);
    for (k = 0; k < 3; k++) {
        float lo = a[k] + fu * (b[k] - a[k]), hi = d[k] + fu * (e[k] - d[k]);
        rgb[k] = lo + fv * (hi - lo);
    }
}

void atlas_sample(const atlas *A, uint32_t sid, const double P[3], float rgb[3])
{
    atlas_chart g;
    const atlas_chart *c = sid == MESH_SURF_GROUND ? (atlas_ground_chart(A, P[0], P[1], &g) ? &g : NULL)
                                                   : atlas_surface_chart(A, sid);
    double u, v;
    if (!c) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    atlas_chart_uv(c, P, &u, &v);
    atlas_sample_uv(A, c, u, v, rgb);
}
