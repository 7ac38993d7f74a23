/* mesh: the loaded city as triangles, for the renderer (render.h).
 *
 * Surfaces. Every pixel of an image shows one surface, named by a 32-bit id:
 *   MESH_SURF_NONE (0)       sky
 *   MESH_SURF_GROUND (1)     the ground plane z = 0 (never meshed: see below)
 *   mesh_wall_id(s, k)       the wall over footprint edge k (scene.pts index
 *                            of its first vertex; the wall runs to the next
 *                            vertex of its ring, as lit_ring.wall in light.h)
 *   mesh_roof_id(s, b)       the roof of building b (z = height)
 *   mesh_under_id(s, b)      the underside of raised building b (z = min_height)
 * Each surface has a plane n.X = d with the outward unit normal n (out of
 * the solid: away from the footprint for walls, holes included; +z roofs;
 * -z undersides), its albedo, its building, and a flag 'lit' that is 0 when
 * no lamp's direct term can be non-zero on it (every lamp is behind or on
 * its plane, or at least its radius R away from the surface's box): SPEC §2
 * gives exactly 0 there (max(0, n.w) = 0 or W(d/R) = 0), so the renderer
 * skips the shader for such surfaces.
 *
 * Triangles. Per building, in one contiguous range of vertices and one of
 * triangles:
 *  - walls: a vertical quad per edge of every ring (outer ring and holes)
 *    from min_height to height, counter-clockwise seen from outside.
 *    T-junctions at shared corners are removed: the vertical edge at a
 *    footprint vertex position (x, y) gets a vertex at every height where
 *    any building with a vertex at exactly that position starts or ends, so
 *    two walls of different heights meeting at a shared corner have the
 *    same vertices along their common part of the edge and the rasteriser's
 *    fill rule leaves no crack there. The wall is then triangulated as a
 *    strip zipping its two columns (a horizontal edge wherever both columns
 *    have the same height, so a lower neighbour's roof edge along a fully
 *    shared wall meets an edge of the taller wall).
 *  - roof: the footprint with holes at z = height, counter-clockwise seen
 *    from above: holes are joined to the outer ring by bridges (for each
 *    hole, from its vertices by decreasing x, the nearest vertex of the
 *    polygon built so far that it can see: the bridge meets no edge except
 *    at its two ends and leaves that vertex into the polygon's angle, all
 *    exact geom_orient signs), then ear clipping: an ear is a strictly
 *    convex vertex whose triangle holds no other vertex inside or on its
 *    sides (vertices at the same position as a corner, from bridges, are
 *    ignored). Only ring vertices are used, so the roof's boundary edges
 *    are exactly the walls' top edges; collinear vertices are kept (they end
 *    up as corners of real triangles), so no roof edge passes through a
 *    wall's vertex. When no ear is found (degenerate input) the rules are
 *    relaxed in steps (vertices on the sides allowed, then any convex
 *    vertex, then a collinear vertex dropped) and the step is counted in
 *    mesh.fallbacks; a hole that cannot be bridged is counted in
 *    mesh.bad_holes and left out (the roof then covers it).
 *  - underside (min_height > 0 only): the roof triangles at z = min_height,
 *    reversed.
 * The ground is not meshed: every building lies in z >= 0, so from an eye
 * above the ground a ray that meets a building meets it before the ground;
 * the renderer takes the ground for the pixels no building covers.
 *
 * A building's mesh is closed (the bottom of a building standing on the
 * ground aside) and watertight: every edge is shared by two of its
 * triangles with the same two vertices (bit-identical coordinates).
 *
 * What is kept. The triangles are not stored: mesh_building writes one
 * building's vertices and triangles when it is drawn, the same doubles in
 * the same order every time, from the scene's footprints and a compact
 * record per building: the roof's triangles as indices local to the
 * building's ring vertices (16 bits when every building has fewer than
 * 65,536 ring vertices), and the column heights strictly between a
 * building's bottom and top at its ring vertices (the T-junction splits),
 * as (local vertex, height) pairs. A surface's plane, albedo, kind and
 * building (mesh_surface) are derived from the scene with the expressions
 * used when the mesh was built; only its 'lit' flag is kept, one bit a
 * surface (a wall's building is found by a search over the buildings'
 * first vertices when the scene's rings run in building order, as the
 * loader makes them, starting from a hint every 64 vertices; else it is
 * kept, 4 bytes a footprint vertex).
 *
 * Memory: everything in part PLX_PART_FRAME, construction scratch released
 * before return. No global state.
 */
#ifndef PLX_MESH_H
#define PLX_MESH_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/scene.h"
#include "base/arena.h"

#define MESH_SURF_NONE 0u
#define MESH_HINT_PTS 64u
#define MESH_SURF_GROUND 1u

enum { MESH_KIND_GROUND = 0, MESH_KIND_WALL, MESH_KIND_ROOF, MESH_KIND_UNDER };

typedef struct mesh_surf {
    double n[3];          /* outward unit normal */
    double d;             /* plane: n.X = d */
    double albedo;
    uint32_t bld;         /* building (UINT32_MAX for the ground) */
    uint8_t kind;         /* MESH_KIND_* */
    uint8_t lit;          /* 0: no lamp can light it directly */
} mesh_surf;

typedef struct mesh_tri {
    uint32_t v[3];        /* vertex indices, counter-clockwise from outside */
    uint32_t surf;        /* surface id */
} mesh_tri;

typedef struct mesh_bld {
    uint32_t roof_first;  /* first roof index (3 a triangle; the next building's ends them) */
    uint32_t split_first; /* first split (mesh.split16/32, split_z; the next building's ends them) */
    uint32_t v_count, t_count;  /* what mesh_building writes */
} mesh_bld;

typedef struct mesh {
    const scene *s;
    uint32_t nv, ntri, nsurf, nbld;  /* nv, ntri: over all buildings */
    mesh_bld *bld;        /* nbld + 1 */
    uint16_t *roof16;     /* roof indices, local to the building's ring vertices */
    uint32_t *roof32;     /* (one of the two; roof32 when a building has 65,536+) */
    uint16_t *split16;    /* local ring vertex of each split, by vertex then height */
    uint32_t *split32;    /* (16 bits as the roofs') */
    double *split_z;      /* its height */
    uint32_t *pt_bld;     /* npts: building of each footprint vertex; NULL when the
                           * buildings' rings and vertices run in order (searched) */
    uint32_t *pt_hint;    /* then per MESH_HINT_PTS vertices from 0: the last building
                           * starting at or before it (npts / MESH_HINT_PTS + 2) */
    uint8_t *lit;         /* a bit per surface id: mesh_surf.lit */
    uint8_t *hidden;      /* a bit per footprint vertex: its wall is hidden whole by the
                           * solids against it (party_walls.h) and not drawn */
    uint32_t max_bld_verts;  /* most vertices of one building */
    uint32_t max_bld_tris;   /* most triangles of one building */
    uint32_t split_verts;    /* vertices added on wall columns (T-junctions) */
    uint32_t fallbacks;      /* relaxed ear-clipping steps */
    uint32_t bad_holes;      /* holes left out of roofs */
    size_t bytes;            /* persistent bytes taken */
} mesh;

/* Builds the mesh of scene s (which must not change while the mesh lives).
 * Returns PLX_OK, PLX_E_INVALID (NULL argument), or PLX_E_NOMEM (the arena
 * is then back where it was). */
plx_status mesh_build(arena *a, const scene *s, mesh **out /* OUT */);

static inline uint32_t mesh_wall_id(const scene *s, uint32_t pt) { (void)s; return 2u + pt; }
static inline uint32_t mesh_roof_id(const scene *s, uint32_t b) { return 2u + s->npts + b; }
static inline uint32_t mesh_under_id(const scene *s, uint32_t b) { return 2u + s->npts + s->nbld + b; }

/* Building b's vertices (3 doubles each, bld[b].v_count of them, at most
 * max_bld_verts) into xyz and its triangles (bld[b].t_count, at most
 * max_bld_tris; vertex indices 0..v_count-1, local to the building) into
 * tri: walls ring by ring and edge by edge, then the roof, then the
 * underside. Each point is written once: the ring vertices at the top
 * (the roof's), then at the bottom (the underside's), then the columns'
 * splits (by ring vertex, then height); the two walls meeting at a ring
 * vertex share its column (a renderer transforms about 2.4 times fewer
 * vertices than with a column per wall side and a ring per flat face). */
void mesh_building(const mesh *m, uint32_t b, double *xyz, mesh_tri *tri);

/* Surface id's record (MESH_SURF_NONE: all zero). */
void mesh_surface(const mesh *m, uint32_t id, mesh_surf *out /* OUT */);

/* Its albedo alone (mesh_surface(m, id).albedo). */
double mesh_albedo(const mesh *m, uint32_t id);

static inline int mesh_lit(const mesh *m, uint32_t id)
{
    return (m->lit[id >> 3] >> (id & 7u)) & 1u;
}

/* Building b's box: minx, miny, minz, maxx, maxy, maxz. */
static inline void mesh_box(const mesh *m, uint32_t b, double box[6])
{
    const scene_building *bd = &m->s->bld[b];
    box[0] = bd->box[0];
    box[1] = bd->box[1];
    box[2] = bd->min_height;
    box[3] = bd->box[2];
    box[4] = bd->box[3];
    box[5] = bd->height;
}

/* Does building b stand on the ground with no holes (render.h)? */
static inline int mesh_occluder(const mesh *m, uint32_t b)
{
    const scene_building *bd = &m->s->bld[b];
    return bd->min_height == 0.0 && bd->ring_count == 1;
}

/* Triangulates one footprint (ring r0 with nr rings: outer then holes) of
 * scene s into tris (counter-clockwise in xy; each triangle three indices
 * into s->pts). tris must hold 3 (n + 2 (nr - 1)) indices for n vertices in
 * all the rings. Scratch from a, released before return. Returns the
 * number of triangles, or -1 when scratch runs out. fallbacks and
 * bad_holes (may be NULL) are increased as described above. */
int mesh_triangulate(arena *a, const scene *s, uint32_t r0, uint32_t nr, uint32_t *tris,
                     uint32_t *fallbacks, uint32_t *bad_holes);

#endif
