/* scene: the loaded city, in local metres.
 *
 * Footprint rings are cleaned at load: no closing vertex, no duplicate
 * consecutive vertices, outer rings counter-clockwise, holes (courtyards of
 * the building itself) clockwise. All arrays live in the engine's arena
 * (part PLX_PART_SCENE) and do not change until the next load.
 */
#ifndef PLX_SCENE_H
#define PLX_SCENE_H

#include <stdint.h>

typedef struct vec2 { double x, y; } vec2;

typedef struct scene_ring {
    uint32_t first;   /* index of the first vertex in scene.pts */
    uint32_t count;   /* number of vertices (>= 3) */
} scene_ring;

typedef struct scene_building {
    uint32_t ring_first;  /* index of the outer ring in scene.rings */
    uint32_t ring_count;  /* 1 + number of holes */
    double height;        /* top of the prism, m */
    double min_height;    /* bottom of the prism, m (0 for most) */
    double albedo;
    double box[4];        /* minx, miny, maxx, maxy of the outer ring */
    uint32_t feature;     /* index of the feature in the collection */
    uint32_t block;       /* index into scene.blocks */
    const char *id;       /* source id string, or NULL */
} scene_building;

typedef struct scene_lamp {
    double x, y, z;
    double intensity;     /* cd */
    double radius;        /* influence radius R, m */
    float color[3];       /* linear RGB */
    uint32_t feature;
    const char *id;
} scene_lamp;

/* A block: a connected group of buildings that touch or overlap. */
typedef struct scene_block {
    uint32_t bld_first;   /* index into scene.block_bld */
    uint32_t bld_count;
    uint32_t ring_first;  /* index into scene.block_rings: outer boundary then courtyards */
    uint32_t ring_count;  /* 1 + courtyards (0 if the outline could not be formed) */
    double box[4];
} scene_block;

typedef struct scene {
    vec2 *pts;            uint32_t npts;
    scene_ring *rings;    uint32_t nrings;
    scene_building *bld;  uint32_t nbld;
    scene_lamp *lamps;    uint32_t nlamps;

    scene_block *blocks;  uint32_t nblocks;
    uint32_t *block_bld;  /* building indices grouped by block */
    vec2 *block_pts;      uint32_t nblock_pts;
    scene_ring *block_rings; uint32_t nblock_rings; /* rings into block_pts */

    double bounds[4];     /* building box grown by 50 m */
    double ground_albedo;
    int lonlat;
    double lon0, lat0;
    double height_min, height_median, height_max;
    uint32_t skipped_features, skipped_lamps, overlapping_pairs;
    uint64_t load_ns;
} scene;

#endif
