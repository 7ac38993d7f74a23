/* raster: the minimal software rasteriser (the default backend).
 *
 * Draws triangles given in clip space into frame buffers the caller owns.
 * Nothing is allocated and there is no global state: everything lives in a
 * raster_ctx the caller declares.
 *
 * Conventions (SPEC.md §5, OpenGL-style clip space):
 *  - A vertex is (x, y, z, w) in clip space plus up to RASTER_MAX_ATTRS
 *    float attributes. A point is visible when w >= RASTER_W_EPSILON and
 *    -w <= x, y, z <= w.
 *  - Pixel (i, j): i from the left, j from the top; its sample point is the
 *    centre (i + 0.5, j + 0.5) in pixel units. Window coordinates are
 *        X = (x/w + 1) * W / 2,   Y = (1 - y/w) * H / 2,
 *        depth = (z/w + 1) / 2   in [0, 1], smaller is nearer.
 *  - Depth test "less": a fragment passes when depth < stored depth.
 *
 * Fixed point and fill rule:
 *  - Window coordinates are snapped to RASTER_SUBPIXEL_BITS (8) fraction
 *    bits, i.e. to 1/256 pixel (round half up), and held in int64. Edge
 *    functions are evaluated exactly in int64 at every pixel centre: the
 *    guard band below keeps coordinates within +-2^23 fixed units (they are
 *    clamped to +-2^24 in any case), so edge functions stay below 2^52 in
 *    magnitude, far from overflow.
 *  - Top-left rule: a pixel is covered when its centre is strictly inside
 *    the triangle, or exactly on a top edge (horizontal, interior below) or
 *    a left edge (interior to the right). So two triangles sharing an edge
 *    (the same two snapped vertices) cover each pixel of that edge exactly
 *    once, and a mesh of triangles drawn with any mixture of windings has no
 *    cracks and no double hits.
 *  - Triangles whose snapped area is zero draw nothing.
 *
 * Clipping (guard band + scissor):
 *  - Triangles are clipped in homogeneous space against w >= RASTER_W_EPSILON,
 *    the near plane (z >= -w), the far plane (z <= w), and guard-band planes
 *    |x| <= gx*w, |y| <= gy*w lying RASTER_GUARD_PX pixels beyond each edge
 *    of the target. Pixels are then limited to the scissor rectangle (by
 *    default the whole target) before any pixel loop runs.
 *  - A triangle entirely inside all planes (the common case) is not touched.
 *    Otherwise all planes are applied in a fixed order (Sutherland-Hodgman)
 *    and every intersection point is computed from the inside endpoint of
 *    its edge towards the outside one, so the two triangles sharing an edge
 *    produce bit-identical clip points on it: clipped meshes stay
 *    watertight. The convex result (at most 10 vertices) is drawn as a fan
 *    with the winding of the whole polygon. A fan piece that snapping folds
 *    over (a sliver thinner than 1/256 pixel along a clip edge) is dropped.
 *  - Vertex positions that are NaN, infinite, or larger than RASTER_MAX_COORD
 *    in magnitude make the triangle draw nothing (counted as rejected).
 *
 * Attributes are interpolated perspective-correctly (attr/w and 1/w are
 * interpolated linearly in window space); depth is interpolated linearly
 * in window space, as z/w is affine there.
 */
#ifndef PLX_RASTER_H
#define PLX_RASTER_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"

#define RASTER_MAX_ATTRS 8
/* Fraction bits of snapped window coordinates: 1 pixel = 256 units. */
#define RASTER_SUBPIXEL_BITS 8
/* Largest target width or height accepted. */
#define RASTER_MAX_DIM PLX_RENDER_MAX_DIM
/* The guard band reaches this many pixels beyond each edge of the target. */
#define RASTER_GUARD_PX 8192
/* Clip-space w below which geometry is clipped away. */
#define RASTER_W_EPSILON 1e-6f
/* Clip-space coordinates beyond this magnitude are invalid input. */
#define RASTER_MAX_COORD 1e30f

/* Colour buffer formats. Each has its own write path. */
typedef enum raster_format {
    RASTER_RGBA8 = 0,  /* 4 bytes per pixel, R G B A; byte = round(clamp(c,0,1)*255) */
    RASTER_RGB_F32,    /* 3 floats per pixel, stored unchanged (no clamping) */
    RASTER_RGBA_F32    /* 4 floats per pixel, stored unchanged */
} raster_format;

/* Frame buffers owned by the caller. Either buffer may be NULL (depth-only
 * or colour-only drawing). Buffers must stay valid while the context is
 * used; the rasteriser only reads and writes pixels inside the target. */
typedef struct raster_target {
    raster_format format;
    int32_t width, height;   /* 1 .. RASTER_MAX_DIM */
    void *color;             /* row 0 is the top row; may be NULL */
    size_t color_stride;     /* bytes from one row to the next; 0 = packed */
    float *depth;            /* width*height floats, row 0 at the top; may be NULL */
    size_t depth_stride;     /* floats from one row to the next; 0 = width */
} raster_target;

/* One vertex: clip-space position and attributes (only the first nattr,
 * as set by raster_set_fragment, are read). */
typedef struct raster_vertex {
    float pos[4];
    float attr[RASTER_MAX_ATTRS];
} raster_vertex;

/*
 * Fragment function, called once per pixel that is covered and passes the
 * depth test, with the pixel (x, y), its depth, and the nattr interpolated
 * attributes. It stores the colour in rgba (pre-set to 0, 0, 0, 1; alpha is
 * ignored by RASTER_RGB_F32) and returns nonzero to write the pixel (colour
 * and depth), 0 to discard it. Any exposure or sRGB encoding wanted in an
 * RGBA8 target is the fragment function's job.
 */
typedef int (*raster_fragment_fn)(void *user, int32_t x, int32_t y, float depth,
                                  const float *attr, float rgba[4]);

typedef enum raster_cull {
    RASTER_CULL_NONE = 0,
    RASTER_CULL_BACK,   /* drop triangles clockwise in normalised device coords (x right, y up) */
    RASTER_CULL_FRONT   /* drop triangles counter-clockwise there */
} raster_cull;

typedef struct raster_stats {
    uint64_t triangles_in;       /* calls to raster_triangle */
    uint64_t triangles_rejected; /* invalid, outside, degenerate or fully clipped */
    uint64_t triangles_culled;
    uint64_t triangles_clipped;  /* needed the clipper */
    uint64_t fragments_shaded;   /* fragment function calls */
    uint64_t pixels_written;
} raster_stats;

/* The rasteriser state. Fill it with raster_init; the fields are public so
 * that it can live on the stack, but change them only through the setters. */
typedef struct raster_ctx {
    raster_target t;
    int32_t sx0, sy0, sx1, sy1;    /* scissor, half-open [sx0,sx1) x [sy0,sy1) */
    int nattr;
    raster_cull cull;
    int depth_test, depth_write;
    raster_fragment_fn frag;
    void *user;
    float gx, gy;                  /* guard band, in x/w and y/w units */
    raster_stats stats;
} raster_ctx;

/*
 * Sets up r for drawing into t: scissor = whole target, no attributes, no
 * fragment function, no culling, depth test and write on, stats zero.
 * Fails with PLX_E_INVALID (r untouched, *why set to a fixed message when
 * why is not NULL) if t is NULL, a size is outside 1..RASTER_MAX_DIM, the
 * format is unknown, or a stride is smaller than one row.
 */
plx_status raster_init(raster_ctx *r, const raster_target *t, const char **why);

/*
 * Sets the fragment function and the number of attributes interpolated
 * (clamped to 0..RASTER_MAX_ATTRS). With fn NULL, the colour is the first
 * attributes taken as r, g, b, a (missing ones 0, alpha 1).
 */
void raster_set_fragment(raster_ctx *r, raster_fragment_fn fn, void *user, int nattr);

/* Limits drawing to [x0,x1) x [y0,y1), clamped to the target (may be empty). */
void raster_set_scissor(raster_ctx *r, int32_t x0, int32_t y0, int32_t x1, int32_t y1);

void raster_set_cull(raster_ctx *r, raster_cull cull);

/* Depth test (less) and depth write switches; both need a depth buffer. */
void raster_set_depth(raster_ctx *r, int test, int write);

/* Fills the whole colour buffer (ignoring the scissor) with rgba, converted
 * as a fragment's colour would be. Does nothing without a colour buffer. */
void raster_clear_color(raster_ctx *r, const float rgba[4]);

/* Fills the whole depth buffer with depth (usually 1.0f). */
void raster_clear_depth(raster_ctx *r, float depth);

/*
 * Draws one triangle. Never fails: invalid or degenerate input draws
 * nothing. Returns the number of pixels written.
 */
size_t raster_triangle(raster_ctx *r, const raster_vertex *v0,
                       const raster_vertex *v1, const raster_vertex *v2);

/*
 * Draws ntri triangles from a vertex array: triangle k uses vertices
 * idx[3k], idx[3k+1], idx[3k+2], or 3k, 3k+1, 3k+2 when idx is NULL.
 * Triangles with an index >= nvert are skipped (counted as rejected).
 * Returns the number of pixels written.
 */
size_t raster_triangles(raster_ctx *r, const raster_vertex *verts, size_t nvert,
                        const uint32_t *idx, size_t ntri);

/*
 * Surface ids without fragment calls: the same coverage, depths and
 * depth test (less, written) as raster_triangle with no attributes, the
 * id written instead of a colour. For a mesh whose triangles share
 * vertices: raster_prepare projects each vertex once (clip-space x, y, z,
 * w); raster_triangle_id then draws a triangle whose three prepared
 * vertices lie inside every clip plane straight from them, and returns -1
 * for any other triangle (the caller draws it with raster_triangle, whose
 * fragment function writes the id: the same pixels either way).
 */
typedef struct raster_pvert {
    int64_t x, y;          /* snapped window position */
    double z;              /* window depth */
    unsigned code;         /* outcode (clip planes outside); ~0u: invalid input */
} raster_pvert;

void raster_prepare(const raster_ctx *r, const float *pos, raster_pvert *out /* OUT */);
/* raster_prepare for n vertices, x, y, z, w each, one after another. */
void raster_prepare_n(const raster_ctx *r, const float *pos, size_t n, raster_pvert *out /* OUT: n */);
long raster_triangle_id(raster_ctx *r, const raster_pvert *v0, const raster_pvert *v1, const raster_pvert *v2,
                        uint32_t id, uint32_t *ids /* width x height, row 0 at the top */);

#endif
