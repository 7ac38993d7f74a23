/* blocks: group the buildings of a scene into blocks and outline each block.
 *
 * A block is a connected group of buildings whose footprints touch or
 * overlap. Its outline is the boundary of the union of its footprints. All
 * decisions use one tolerance 'tol' in metres (the loader passes 0.05) and
 * plain double arithmetic; the rules below are the contract.
 *
 * Footprint: the closed region of a building = inside its outer ring and
 * outside its holes (even-odd over the building's rings), boundary included.
 * Raised buildings (min_height > 0) are treated like all others.
 *
 * TOUCH (same block). Buildings A and B touch when the distance between their
 * closed footprints is <= tol: some edge of A and some edge of B are within
 * tol of each other (segment-to-segment distance), or a vertex of one lies
 * inside the other (containment). Blocks are the connected components of
 * this relation. Block i is numbered by its smallest building index, in
 * increasing order; block_bld lists each block's buildings in increasing
 * index order.
 *
 * OVERLAP (counted in overlapping_pairs; only touching pairs can overlap).
 * depth_B(p) is the distance from p to the boundary of B when p lies inside
 * B, else 0. The probe points of A against B are every vertex of A and the
 * midpoint of every piece of an edge of A between consecutive points where
 * it properly crosses an edge of B (an edge with no crossing is one piece, so
 * every edge midpoint is a probe). A and B overlap when
 *   (a) some probe of A has depth_B > tol, or some probe of B has
 *       depth_A > tol (penetration beyond tol: containment, a corner pushed
 *       in, a wall running through the other building, crossing bars); or
 *   (b) the footprints coincide: every vertex and edge midpoint of each lies
 *       within tol of the other's boundary, and the point 2*tol inside A
 *       from the middle of A's longest outer edge lies inside both A and B
 *       (identical or near-identical duplicates).
 * So walls that meet within tol, or overlap one another by up to tol, are
 * not counted; an overlap is counted once per pair of buildings.
 *
 * OUTLINE of a block (rings in block_pts, indices in block_rings):
 *  1. Snapping (distance tol). Vertices are taken in index order: a vertex
 *     not yet taken starts a cluster at its own position and takes every
 *     free vertex within tol of it (not transitively, so a finely drawn
 *     curve keeps its shape; each vertex moves by at most tol). Each edge
 *     is then bent through every cluster within tol of its interior
 *     (T-junctions become shared vertices, walls that meet within tol
 *     become one edge). Then edges are split where they properly cross;
 *     crossing points are not snapped (only points within 1e-9 m of each
 *     other or of an edge end are taken as one, for several edges through
 *     one point).
 *  2. Classification. Every resulting sub-edge carries the net count of
 *     footprint edges running along it (+1 per edge in one direction, -1 in
 *     the other). The coverage of a point is the sum of the winding numbers
 *     of all (snapped) footprint rings; a point is in the union when its
 *     coverage is > 0. A sub-edge is kept when exactly one of its sides is
 *     in the union; the coverage of one side is counted along an axis ray
 *     from the sub-edge's midpoint, the other side differs by the net
 *     count. Kept sub-edges are oriented with the union on their left.
 *  3. Loops. Kept edges are linked into closed loops: arriving at a vertex,
 *     the next edge is the first outgoing one clockwise from the way back.
 *     A loop that comes back to a vertex it has already visited is split
 *     there, so no ring passes through a point twice; rings may touch each
 *     other at a point (a courtyard touching the outer boundary or another
 *     courtyard, two parts joined at a corner) and never cross. Consecutive vertices closer than
 *     1e-7 m are merged and a vertex within 1e-7 m of the line through its
 *     neighbours is removed; loops of area < max(10*tol^2, 1e-12) m^2 are
 *     dropped.
 *  4. Order. Ring 0 is the counter-clockwise loop of largest area (the outer
 *     boundary); then the clockwise loops (courtyards: the holes of the
 *     union, whether one building's inner ring or enclosed by several
 *     buildings); then any further counter-clockwise loops ("extra outer
 *     rings": parts of the union joined to the rest only at a point, e.g.
 *     two squares touching at a corner, or across a gap of at most tol that
 *     snapping did not close). Orientation tells the kinds apart, so the
 *     courtyards of a block are its clockwise rings. ring_count is 0 when no
 *     counter-clockwise loop could be formed (then the block has no
 *     outline).
 *  If some kept edges cannot be linked into loops (snapping made the edges
 *  inconsistent; not seen in tests), the block is outlined again with no
 *  snapping, so it still gets the exact union of its footprints.
 * Limits: snapping is done once (edges bent by snapping are not snapped
 * again, crossings are not snapped), so near-misses between bent edges can
 * leave kinks or slivers smaller than about tol, and an outline vertex may
 * lie up to tol from the footprints; the union's area may differ from the
 * footprints' by about tol times the length of the walls that were snapped.
 *
 * Cost: candidate pairs come from a uniform grid over the building boxes.
 * Inside a block, the searches use grids whose cells follow the size of the
 * edges, and the ray counts of step 2 a sweep along the ray's line (the
 * edges crossing it well beyond the start are summed in a Fenwick tree, only
 * those near the start are tested one by one), so the work is about
 * n log n in the number of vertices for city-like input and also for one
 * ring of 10^6 vertices (a comb whose teeth share one band, a circle).
 * Many long edges near one point (a star, many buildings sharing a corner)
 * can still cost more, and long slanted edges among many short ones make
 * the cells of the crossing and ray searches coarser.
 */
#ifndef PLX_BLOCKS_H
#define PLX_BLOCKS_H

#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"

/*
 * Builds the blocks of scene 's' whose pts, rings, bld (with box) and nbld
 * are filled: outer rings counter-clockwise, holes clockwise, no closing
 * vertex. Fills bld[i].block, s->blocks/nblocks, s->block_bld,
 * s->block_pts/nblock_pts, s->block_rings/nblock_rings and
 * s->overlapping_pairs. The persistent arrays come from arena part
 * PLX_PART_SCENE; temporary memory is scratch and is given back before
 * returning, also on failure.
 * Returns PLX_OK; PLX_E_INVALID when a or s is NULL or tol is negative or not
 * finite; PLX_E_NOMEM when an arena request fails (the scene's block fields
 * are then unspecified and the persistent memory already taken in
 * PLX_PART_SCENE is left for the caller to release).
 */
plx_status blocks_build(arena *a, scene *s, double tol);

#endif
