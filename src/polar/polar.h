/* polar: the four quadrant polar diagrams of the occluding footprints.
 *
 * Objects are the footprints of the buildings with min_height <= 0 (a raised
 * building is no occluder). Solid = the union of the closed footprints minus
 * the open courtyards; free space = the rest of the Bounds box s->bounds.
 *
 * Quadrant q scans directions in [q pi/2, (q+1) pi/2] counter-clockwise. The
 * diagram of quadrant q labels every free point p with the object met first
 * by that scan (ties: the nearest along the ray). Its polar axes are the
 * segments drawn from every footprint vertex parallel to the start direction
 * of the scan (backwards and forwards) until they meet a wall; where the ray
 * of direction q pi/2 leaves p and meets a wall, the owner is that wall's
 * building and is constant between two axes. The axes and the walls cut the
 * Bounds box into trapezoids ("regions"), each with at most two neighbours
 * across each of its two axis sides.
 *
 * Labels. The objects of the diagrams are the occluding footprints and the
 * Bounds frame: SPEC §3 closes every visibility polygon on the Bounds box, so
 * the scene is a world enclosed by that box, and the box's sides are walls
 * like any other (they are wall pieces here, bld[0] == -2). In an enclosed
 * world the start ray q pi/2 from any free point meets a wall, at angle 0 of
 * the scan, so the object angularly first from p is the owner of that wall
 * (ties at angle 0: the nearest along the ray). The owner is therefore
 * constant on every region, and every region is labelled: a building index,
 * or -1 for the Bounds frame. The diagrams are those of Grima, Marquez,
 * Ortega (2006) for the footprints plus the enclosing frame.
 * The first BUILDING of the scan (the frame left out) is not constant on
 * frame-labelled regions - it changes across the lines through pairs of
 * vertices - and is answered by vis_first() (visibility.h), which walks the
 * regions of the quadrant's cone.
 *
 * Quadrants 0 and 2 (scan starting east and west) share one set of
 * horizontal axes, quadrants 1 and 3 one set of vertical axes: two planar
 * subdivisions, four labellings. Each subdivision is the trapezoidal map
 * of the wall pieces, built by randomized incremental insertion (de Berg
 * et al., "Computational Geometry", ch. 6; Seidel 1991) in a seeded random
 * order (random rounds, spatial order within a round: deterministic),
 * which also gives its search DAG for point location: expected O(n) nodes,
 * O(n log n) time to build, O(log n) per query, for n wall pieces. A plane
 * sweep over the wall ends then checks that the pieces form a planar
 * subdivision and that the insertion's map is that subdivision, and makes
 * the free regions in a deterministic order with their adjacency: where
 * walls only start, it reads the piece below the event from the map (the
 * floor of the trapezoid below the lowest piece starting there), so each
 * event costs O(1) plus O(d log d) for d pieces starting at it: O(n log n)
 * in all, whatever the layout (no grid). Cutting the footprints at their
 * contacts costs O(n log n) plus, per pair of footprints whose bounding
 * boxes meet, O(log n) and a comparison of their edges near the other's
 * box (O(1) for footprints of bounded size; the pairs of edges compared
 * can number more than the contacts when many large boxes overlap). The
 * DAG's leaves are mapped to the sweep's free regions or marked solid.
 * A ray walks from region to region
 * through the stored adjacency until it leaves through a wall.
 *
 * Degenerate input: footprints that share walls exactly, touch at T-junctions
 * or overlap are first cut into pieces at every contact (exact predicates;
 * crossing points of overlapping walls are rounded to doubles, the only
 * inexact step). Pieces lying on top of each other are merged and keep up to
 * two owners; pieces of two footprints lying on top of each other in
 * opposite directions (a party wall: solid on both sides) are left out, as
 * no ray from free space meets them first. Every combinatorial decision
 * afterwards uses geom_orient.
 *
 * Memory: everything lives in the arena, part PLX_PART_POLAR; construction
 * temporaries come from arena_scratch and are released before return,
 * except the trapezoid slots of the map being built, taken from the low
 * end (PLX_PART_POLAR) as they are needed: the map's regions are kept in
 * their place and the rest is given back.
 */
#ifndef PLX_POLAR_H
#define PLX_POLAR_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/scene.h"
#include "base/arena.h"

#define POLAR_NONE 0xffffffffu

/* One footprint wall piece (or a side of the Bounds box, bld[0] == -2). */
typedef struct polar_seg {
    uint32_t a, b;       /* point indices; the building lies on the left of a->b */
    int32_t bld[2];      /* owning buildings (bld[1] = -1 unless two coincide) */
    int32_t cover;       /* footprints entered when crossing from right to left */
} polar_seg;

/* A free region of a subdivision: a trapezoid in the frame of its map,
 * bounded by two walls (or Bounds sides) and by the polar axes of two
 * points. 32 bytes. */
typedef struct polar_trap {
    uint32_t lp, rp;         /* points whose axes bound it (frame left / right) */
    uint32_t top, bot;       /* wall pieces bounding it (frame above / below) */
    uint32_t nb[4];          /* regions across its axis sides: upper-left,
                              * lower-left, upper-right, lower-right (or
                              * POLAR_NONE: the side ends on that wall) */
} polar_trap;

/* One of the two subdivisions. Trapezoids in its frame: frame 0 maps world
 * (x, y) to (y, -x) (axes horizontal in the world), frame 1 is the identity
 * (axes vertical). Within a frame points are ordered by (u, v) lexicographic
 * order, so equal u needs no special case.
 *
 * Only the free trapezoids are kept as regions: a region next to a free one
 * across an axis side is free too (solid and free are only ever separated
 * by walls), so walks never need the solid ones.
 *
 * Point location: node[] holds the inner nodes of the search DAG of the
 * trapezoidal map, in the order they were made (the top levels first). A
 * node is a test, kind << 30 | index (kind POLAR_NODE_X: is the point
 * before point 'index' in the frame's lexicographic order; POLAR_NODE_Y /
 * POLAR_NODE_YB: is it below wall piece 'index', whose frame-left end is
 * seg.a / seg.b), and the child words for "before / below" and "after /
 * above". A child word is an inner node (tag POLAR_CHILD_NODE), a free
 * region (POLAR_CHILD_FREE, its index) or a solid trapezoid
 * (POLAR_CHILD_SOLID, the owner reported by polar_locate plus one).
 * Stored in 8 bytes a node ("narrow") when all indices fit: the 64 bits
 * w0 | w1 << 32 hold the test as kind << 20 | index in bits 0-21 and the
 * children as tag << 19 | index in bits 22-42 and 43-63 (up to 2^19 nodes,
 * regions and buildings, 2^20 points and pieces); otherwise packed in
 * tbits + 2 cbits bits a node (pack = tbits | cbits << 8; node j at bit j
 * (tbits + 2 cbits) of node[] read as 64-bit words, a field running on
 * into the next word where it does not fit): the test as kind <<
 * (tbits - 2) | index; each child as one number, an inner node below
 * nnode, nnode + a free region below nnode + ntrap, else nnode + ntrap +
 * the solid trapezoid's owner plus one, in cbits bits (8.5 bytes a node on
 * a 10^6-vertex ring, where the three words took 12). polar_node()
 * unpacks either. */
#define POLAR_TAG(w) ((w) >> 30)
#define POLAR_IDX(w) ((w) & 0x3fffffffu)
enum { POLAR_CHILD_NODE = 0, POLAR_CHILD_FREE = 1, POLAR_CHILD_SOLID = 2 };
enum { POLAR_NODE_X = 1, POLAR_NODE_Y = 2, POLAR_NODE_YB = 3 };

typedef struct polar_map {
    int frame;
    uint32_t ntrap;          /* free regions */
    polar_trap *trap;
    uint32_t *node;          /* inner search nodes (see above): 2 words each
                              * when narrow, else packed 64-bit words */
    uint32_t nnode;
    uint32_t root;           /* child word of the root */
    int narrow;
    uint32_t box_top, box_bot; /* segment indices of the Bounds sides on top/bottom */
    uint32_t box_lo, box_hi;   /* point indices of the extreme Bounds corners */
    uint32_t pack;           /* packed nodes: tbits | cbits << 8 (see above) */
} polar_map;

typedef struct polar {
    const scene *s;
    vec2 *pts;               /* footprint vertices, crossing points, 4 box corners */
    uint32_t npts;
    polar_seg *seg;          /* wall pieces, then the 4 Bounds sides */
    uint32_t nseg;
    uint32_t nwall;          /* wall pieces come first: seg[0 .. nwall-1] */
    uint32_t nbld;           /* s->nbld */
    uint32_t wall_rounds;    /* contact searches after the first cut, the last finding
                              * none (0: no crossing point was rounded) */
    double box[4];           /* s->bounds */
    polar_map map[2];        /* [0]: quadrants 0, 2   [1]: quadrants 1, 3 */
    size_t bytes[4];         /* axes, regions, polygons, rest (search DAGs, header) */
    uint64_t steps;          /* construction work, for tests: DAG nodes and
                              * trapezoids visited by the insertions, status
                              * pieces walked and sorted by the sweeps */
} polar;

/* The build's scratch: the arena's high-water mark during polar_build
 * beyond what was in use before and what the diagrams keep (the scratch
 * and the trapezoid slots) is at most POLAR_SCRATCH_PER_VERTEX bytes a
 * footprint vertex plus POLAR_SCRATCH_FIXED: a block must hold the
 * diagrams and that (tests/unit/test_polar_scratch.c measures it on
 * growing rings and generated cities: 157 bytes a vertex on a
 * 100,000-vertex ring, 96 on gen eixample 24 24; README "Polar build
 * scratch"). */
#define POLAR_SCRATCH_PER_VERTEX 200
#define POLAR_SCRATCH_FIXED ((size_t)1 << 20)

/* Builds the four diagrams of scene s. On success *out points into arena
 * memory (PLX_PART_POLAR) valid until that memory is released; the scene must
 * stay unchanged meanwhile. Fails with PLX_E_NOMEM (nothing kept, scratch
 * released), PLX_E_INVALID (NULL argument, empty or non-finite bounds) or
 * PLX_E_SCENE (wall pieces that still touch elsewhere than at their ends:
 * after many rounds of cuts at the contacts rounded crossing points make,
 * which no scene is known to need, or where edges of one building touch,
 * which the loader rejects as a self-intersecting ring; nothing kept).
 * A scene with no occluder gives diagrams of one free region each. */
plx_status polar_build(arena *a, const scene *s, polar **out /* OUT */);

/* Bytes of arena memory held, like robles2014 Table 3:
 * [0] polar axes, [1] polar regions, [2] polygons (wall pieces and points),
 * [3] the rest (the search DAGs of point location, headers). Both
 * subdivisions together. */
void polar_memory(const polar *pd, size_t bytes[4] /* OUT */);

/* For drawing. Number of (free) regions of the diagram of quadrant q, and
 * region i as a polygon of 3 or 4 corners (world coordinates,
 * counter-clockwise; a degenerate region may repeat a corner): returns the
 * number of corners written to c[0..3] and stores the owner (as
 * polar_locate) and whether the region is solid (always 0: solid trapezoids
 * are not kept). Returns 0 for an index out of range. */
uint32_t polar_region_count(const polar *pd, int q);
int polar_region(const polar *pd, int q, uint32_t i, vec2 c[4] /* OUT */,
                 int32_t *owner /* OUT */, int *solid /* OUT */);

/* Internal helpers shared with visibility.c: frames. */
vec2 polar_fpt(const polar *pd, int frame, uint32_t i);      /* point in a frame */
vec2 polar_to_frame(int frame, vec2 w);
vec2 polar_from_frame(int frame, vec2 f);

/* ---- for tests and benchmarks only ---- */

/* polar_build with flags: POLAR_BUILD_NO_DAG does not keep the search DAGs
 * (the trapezoidal maps are still built by insertion, the sweep needs them:
 * this times keeping the nodes; point location and everything using it are
 * then unusable); POLAR_BUILD_WIDE_DAG stores every node packed (to
 * test that layout on small scenes). */
enum { POLAR_BUILD_NO_DAG = 1, POLAR_BUILD_WIDE_DAG = 2 };
plx_status polar_build_flags(arena *a, const scene *s, int flags, polar **out /* OUT */);

#endif
