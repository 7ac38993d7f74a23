/* atlas: the radiance atlas, every surface of the city's light baked into
 * textures, so that a frame reads its pixels instead of computing them
 * (issue "Kiosk mode"; munoz2013 §3.2: light maps for views of many lamps).
 *
 * WHAT IT HOLDS. For every surface a chart: a grid of sample points
 * ("vertices") laid on the surface, each holding the outgoing radiance
 * there, RGB, albedo / pi (E_direct + E_indirect) (SPEC §4, §5; packed,
 * texel.h). A frame's pixel takes the bilinear mix of the four vertices
 * around its hit point on its own surface's chart, so light never crosses
 * a wall foot, a roof edge or a building corner.
 *  - Walls (one per footprint edge, mesh_wall_id): u along the edge from
 *    its first vertex, v up from the building's bottom; the grid's corner
 *    vertices are the wall's corners.
 *  - Roofs and undersides of raised buildings: the footprint's box at the
 *    roof's (the underside's) height, x and y; vertices outside the
 *    footprint hold the light at the nearest point of its boundary.
 *  - The ground: square tiles of ATLAS_TILE fine steps over the box of
 *    the scene's Bounds and every lamp's ground reach, each cut into
 *    blocks of ATLAS_BLOCK steps (ATLAS_BLOCK + 1 vertices a side; blocks
 *    side by side share their border vertices, with the same values: no
 *    seam, but for rounding: one step of the packed values at most). A
 *    block wholly under the footprints of buildings standing on the
 *    ground (none of it can be seen) holds nothing. A ground vertex inside
 *    such a footprint holds the light of the nearest open ground
 *    (atlas_fill.h). Beyond the tiles the ground is black
 *    (no lamp reaches it; the light bounced there is left out).
 *  - A wall shared with another building (the same edge, the other way
 *    round) is hidden where the other building's solid stands against it:
 *    its chart covers only the part above (or below) that, and a wall
 *    hidden whole has no chart.
 * Spacing: 'fine' (the texel size asked for) on surfaces some lamp may
 * light directly (mesh.h's lit flag; a ground tile some lamp's ground
 * reach meets), 'coarse' (ATLAS_COARSE times it) on the others, which
 * only indirect light reaches and which change slowly: a coarse ground
 * tile is one block. A surface narrower than a step has two vertices
 * across it.
 *
 * WHAT A PIXEL GETS. The linear radiance the frame shows at a pixel whose
 * sample ray meets surface S at P is the bilinear interpolation of S's
 * chart at P: at a vertex exactly the vertex's value (texel.h's rounding
 * aside), between vertices a mix. This is not SPEC §5's exact pixel (its
 * shadow edges are as sharp as the spacing); frames that must be exact
 * (no indirect light, render.h) do not read the atlas.
 *
 * MEMORY. The charts (ATLAS_CHART_BYTES + 1 each: one per footprint edge,
 * two per building), the ground tiles (81 bytes each) and the packed
 * values (4 bytes a vertex), from the arena (part PLX_PART_FRAME), sized before anything is
 * taken (atlas_plan): the fine spacing grows from the one asked for until
 * the whole fits the budget. A bake saves it with the engine's other
 * structures (no pointer but into the arena).
 *
 * FILLING (atlas_fill.c). The direct light at every vertex, exact (the
 * light module), then the indirect light from a hook at a coarser grid of
 * each chart, interpolated. A chart's values depend on the chart alone,
 * so the atlas is the same bytes for any number of threads.
 */
#ifndef PLX_ATLAS_H
#define PLX_ATLAS_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"
#include "render/mesh.h"

#define ATLAS_TILE 32         /* ground tile: this many fine steps a side */
#define ATLAS_BLOCK 8         /* ground block: this many steps a side (fine or coarse) */
#define ATLAS_TB (ATLAS_TILE / ATLAS_BLOCK) /* fine blocks a tile side */
#define ATLAS_COARSE 4        /* coarse spacing: this many fine steps (a coarse tile is one block) */
#define ATLAS_NOVERT 0xffffffffu /* a block with no vertices */
#define ATLAS_FINE_DEFAULT PLX_ATLAS_SPACING_DEFAULT /* m, the spacing asked for when none is */
#define ATLAS_COARSEST 64.0  /* m: atlas_spacing_for grows the spacing no further (unless asked for more) */

enum { ATLAS_NONE = 0, ATLAS_WALL, ATLAS_ROOF, ATLAS_UNDER, ATLAS_GROUND };

/* A chart's or block's state (atlas.cdone, atlas.gdone): not filled;
 * filled; listed by atlas_frame_missing this round; filled and every
 * value 0 (a frame writes its pixels black without reading them). */
enum { ATLAS_UNFILLED = 0, ATLAS_FILLED = 1, ATLAS_LISTED = 2, ATLAS_DARK = 3 };

static inline int atlas_filled(uint8_t state)
{
    return state == ATLAS_FILLED || state == ATLAS_DARK;
}

typedef struct atlas_chart {
    double o[3];          /* the world point of vertex (0, 0) */
    float e[2];           /* walls: the edge's unit direction (x, y); else (1, 0) */
    float tu, tv;         /* vertex steps along u and v, m (> 0) */
    uint32_t nu, nv;      /* vertices along u and v (>= 2 each) */
    uint32_t first;       /* vertex (0, 0) in atlas.tex; vertex (i, j) at first + j nu + i */
    uint32_t bld;         /* the building (UINT32_MAX for the ground) */
    uint8_t kind;         /* ATLAS_* */
    uint8_t fine;         /* 1: the fine spacing */
    uint8_t pad[6];
} atlas_chart;

#define ATLAS_CHART_BYTES sizeof(atlas_chart)

typedef struct atlas {
    const scene *s;
    const mesh *m;
    double fine, coarse;  /* vertex spacing, m */
    double tile;          /* ground tile side, m (ATLAS_TILE fine steps) */
    double inv_tile, inv_fine, inv_coarse; /* their reciprocals */
    double g0[2];         /* ground tiles' low corner */
    uint32_t gx, gy;      /* ground tiles along x and y */
    uint32_t nsurf;       /* charts by surface: chart[sid - 2], sid a wall, roof or underside */
    atlas_chart *chart;
    uint32_t *gfirst;     /* per tile ATLAS_TB^2 blocks, row by row: block (bx, by)'s vertex
                             (0, 0) at gfirst[tile * ATLAS_TB^2 + by * ATLAS_TB + bx], its
                             vertex (i, j) j (ATLAS_BLOCK + 1) + i after; ATLAS_NOVERT: none.
                             A coarse tile has its one block at bx = by = 0 */
    uint8_t *gfine;       /* per tile: 1 fine, 0 coarse */
    uint8_t *cdone;       /* per surface chart: its state (ATLAS_FILLED ...) */
    uint8_t *gdone;       /* per ground block (as gfirst): its state */
    uint64_t todo;        /* charts and blocks with vertices not filled yet */
    uint64_t key;         /* the light the values belong to (the engine's; atlas_clear) */
    uint32_t *tex;        /* packed radiance (texel.h), ntex */
    uint64_t ntex;
    uint64_t ntex_fine;   /* vertices on fine charts */
    int with_ind;         /* the values filled hold indirect light */
    size_t bytes;         /* charts and values */
} atlas;

/* Bytes the atlas of scene s takes at fine spacing 'fine' (m > 0), and
 * its vertex count (may be NULL); SIZE_MAX when it cannot be laid out
 * (past 2^32 vertices, or no scratch in a for the ground tiles' marks,
 * a byte a tile, released before return). */
size_t atlas_plan(arena *a, const scene *s, const mesh *m, double fine, uint64_t *ntex /* OUT */);

/* The fine spacing to use: 'fine' (ATLAS_FINE_DEFAULT when <= 0) grown by
 * steps of 2^(1/4) until atlas_plan fits max_bytes (the finest such step);
 * 0 when even ATLAS_COARSEST (or 'fine', if coarser) does not. ntex (may
 * be NULL): the vertex count of the plan at the spacing returned, or
 * UINT64_MAX when that plan could not be made (no scratch) and max_bytes
 * is SIZE_MAX: then atlas_create counts it. */
double atlas_spacing_for(arena *a, const scene *s, const mesh *m, double fine, size_t max_bytes,
                         uint64_t *ntex /* OUT */);

/* Lays out the charts at fine spacing 'fine' and takes their memory (the
 * values zero: black). Returns PLX_OK, PLX_E_INVALID, PLX_E_NOMEM (arena
 * back where it was). */
plx_status atlas_create(arena *a, const scene *s, const mesh *m, double fine, atlas **out /* OUT */);

/* atlas_create when the vertex count at 'fine' is known (atlas_plan's or
 * atlas_spacing_for's ntex): the same atlas, without laying it out twice
 * (once to count, once to store). */
plx_status atlas_create_counted(arena *a, const scene *s, const mesh *m, double fine, uint64_t ntex,
                                atlas **out /* OUT */);

/* Marks every chart and block not filled (the light changed: the values
 * are stale), under a new key. */
void atlas_clear(atlas *A, uint64_t key);

/* Items: a surface chart is its index (sid - 2), ground block b of tile t
 * is nsurf + t ATLAS_TB^2 + b. */
static inline uint32_t atlas_block_item(const atlas *A, uint32_t tile, uint32_t b)
{
    return A->nsurf + tile * ATLAS_TB * ATLAS_TB + b;
}

/* The chart of surface sid (a wall, roof or underside: mesh.h), NULL for
 * others. */
static inline const atlas_chart *atlas_surface_chart(const atlas *A, uint32_t sid)
{
    return sid >= 2u && sid - 2u < A->nsurf && A->chart[sid - 2u].kind != ATLAS_NONE ? &A->chart[sid - 2u]
                                                                                     : NULL;
}

/* The ground block holding (x, y) as a chart (*c written), 0 off the
 * tiles or where the block holds nothing. */
int atlas_ground_chart(const atlas *A, double x, double y, atlas_chart *c /* OUT */);

/* The chart of ground block (bx, by) of tile (tx, ty) (c->kind ATLAS_NONE
 * when it holds nothing). */
void atlas_ground_block(const atlas *A, uint32_t tx, uint32_t ty, uint32_t bx, uint32_t by, atlas_chart *c /* OUT */);

/* Vertex (i, j)'s world point. */
void atlas_vertex_point(const atlas_chart *c, uint32_t i, uint32_t j, double P[3] /* OUT */);

/* The chart coordinates (in steps) of world point P on the chart's plane. */
void atlas_chart_uv(const atlas_chart *c, const double P[3], double *u /* OUT */, double *v /* OUT */);

/* The outward unit normal of a chart's surface. */
void atlas_chart_normal(const atlas_chart *c, double n[3] /* OUT */);

/* The radiance (RGB, linear) at chart coordinates (u, v): bilinear over
 * the four vertices around, clamped to the chart. */
void atlas_sample_uv(const atlas *A, const atlas_chart *c, double u, double v, float rgb[3] /* OUT */);

/* The radiance at point P on surface sid (MESH_SURF_GROUND: the ground
 * tile under P; 0 off the tiles). */
void atlas_sample(const atlas *A, uint32_t sid, const double P[3], float rgb[3] /* OUT */);

#endif
