/* scene: the loaded city, in local metres.
 *
 * Footprint rings are cleaned at load: no closing vertex, no duplicate
 * consecutive vertices, outer rings counter-clockwise, holes (courtyards of
 * the building itself) clockwise. All arrays live in the engine's arena
 * (part PLX_PART_SCENE) and do not change until the next load.
 */
#ifndef PLX_SCENE_H
#define PLX_SCENE_H

#include <stddef.h>
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

struct photometry;

typedef struct scene_lamp {
    double x, y, z;
    double intensity;     /* cd; a photometric lamp: dimming x the table's peak
                             (0 until its file is given) */
    double radius;        /* influence radius R, m */
    float color[3];       /* linear RGB */
    uint32_t feature;
    const char *id;
    /* SPEC §2.1 (src/light/photometry.h): properties.photometry as written
     * (NULL: isotropic), its table once given (plx_set_photometry), the
     * frame (azimuth, tilt in degrees; cos/sin of both) and dimming. */
    const char *photometry;
    const struct photometry *phot;
    double azimuth, tilt, dimming;
    double frame[4];
} scene_lamp;

/* The ground's albedo from a day image (src/ground.c; README "Scene
 * format"). The pixels are the caller's 8-bit sRGB, kept as bytes: the
 * albedo of channel value v is lut[v] (sRGB decoded to linear, times
 * ground_albedo / mean_y so that the image's mean linear luminance is the
 * scene's ground albedo, clamped to [0, 0.95]). */
typedef struct scene_ground_image {
    uint32_t w, h;
    uint8_t *rgb;         /* w*h*3, top row (y = box[3]) first */
    size_t cap;           /* bytes available at rgb (a smaller image reuses them) */
    double box[4];        /* x0, y0, x1, y1 in local metres */
    double fx, fy;        /* pixels per metre along x and y */
    double mean_y;        /* mean linear luminance of the pixels (> 0) */
    double mean_albedo[3]; /* mean albedo per channel over the pixels */
    double lut[256];
} scene_ground_image;

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
    double ground_albedo;   /* the constant ground albedo (outside a ground image) */
    const char *ground_image;   /* properties.ground_image as written, or NULL */
    int ground_image_bounds_given;
    double ground_image_bounds[4]; /* x0, y0, x1, y1, local metres (the Bounds box when not given) */
    scene_ground_image *gimg;   /* pixels given by plx_set_ground_image, or NULL */
    int lonlat;
    double lon0, lat0;
    const char *crs;      /* the scene's CRS name (top-level "crs" or properties.crs), or NULL */
    double height_min, height_median, height_max;
    uint32_t skipped_features, skipped_lamps, overlapping_pairs;
    uint64_t load_ns;
} scene;

/* The ground's albedo per channel at (x, y) (src/ground.c): the ground
 * image's nearest pixel inside its box, else the constant ground_albedo.
 * Every read of the ground's albedo goes through here. O(1). */
void scene_ground_albedo(const scene *s, double x, double y, double rgb[3] /* OUT */);
/* Its luminance 0.2126 R + 0.7152 G + 0.0722 B (the ground_albedo itself
 * where there is no image): the photon tracer's survival probability. */
double scene_ground_albedo_y(const scene *s, double x, double y);

#endif
