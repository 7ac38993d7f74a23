/* render: night images of the loaded city (SPEC §5), on the CPU.
 *
 * USE (the lead wires `polarlux render` and the public API onto this):
 *
 *     render *r;
 *     render_create(&e->mem, e->sc, 640, 480, render_shade_light, lightobj, &r);
 *     render_camera cam = { {x, y, 1.7}, {tx, ty, 1.7}, 60.0, 640, 480 };
 *     render_opts o;  render_opts_default(&o);
 *     render_frame(r, &cam, &o, rgb8, rgbf, &stats);   // either buffer may be NULL
 *     // aerial views: build the ground light map once, then o.lightmap = 1
 *     render_lightmap_build(r, 1.0, 64u << 20);
 *
 * Contract of a frame (SPEC §5). Pinhole camera at eye looking at target,
 * up = +z, vertical field of view fov_deg, width x height pixels; pixel
 * (i, j), i from the left and j from the top, is sampled through its
 * centre: the ray eye + t d with
 *     d = f + ((2 (i + 0.5) / W - 1) tan(fov/2) W/H) r + ((1 - 2 (j + 0.5) / H) tan(fov/2)) u
 * where f = (target - eye)/|target - eye|, r = f x z / |f x z| (for a camera
 * looking straight up or down r = +x), u = r x f. The pixel's linear value
 * is the radiance of the first surface hit, L = albedo / pi * E_rgb (on the
 * ground the albedo per channel of scene_ground_albedo: a day image's pixel
 * or the constant, src/ground.c), with
 * E_rgb the colour-weighted direct illuminance of SPEC §2 at the hit point
 * (from the shade function; each lamp's term times its color) plus the
 * optional indirect term (render_opts.indirect, the hook for the photon
 * module); 0 (black) for the sky. The normal given to the shader is the
 * surface's outward normal, turned to face the eye when the eye sees the
 * surface from inside a solid.
 *
 * What is drawn. Walls, roofs and undersides of every building (mesh.h),
 * and the ground: the whole plane z = 0 out to the horizon, not only the
 * Bounds box (SPEC §1 says the ground is the plane), computed per pixel:
 * a pixel that no building covers and whose ray goes down (d.z < 0) sees
 * the ground at t = -eye.z / d.z. This is exact because every building
 * lies in z >= 0, so a ray meets any building before it reaches the ground.
 * The eye must be above the ground (eye.z > 0).
 *
 * How. Two passes. (1) Visibility: the building triangles are rasterised
 * (raster.h: top-left fill rule, 1/256 px snapping, homogeneous clipping)
 * into a float depth buffer and a 32-bit surface-id buffer (mesh.h ids);
 * nothing is shaded there, so overdraw costs one store. (2) Shading: for
 * every pixel, once, the hit point is recomputed in double precision as
 * the intersection of the pixel-centre ray with the plane of the pixel's
 * surface (so P does not suffer from float interpolation), and the shader
 * is called there -- except on surfaces that no lamp can light (mesh.h
 * 'lit' flag: the direct term is exactly 0) when there is no indirect hook.
 * The shading pass runs by tiles of 8 x 8 pixels. With the light module's
 * shader (render_shade_light) the renderer does the lamp walk itself: the
 * lamps whose reach sphere meets the box of the tile's hit points are
 * gathered once per tile from the light module's lamp grid (in lamp index
 * order, the order of light_illuminance's walk; at most 64 lamps and 16
 * grid cells, else the tile takes light_illuminance per pixel), and every
 * pixel sums SPEC §2's term over that list with light_visible for the
 * visibility -- the same operations as light_illuminance, so the same
 * values (test_render checks them bit for bit); a lamp left out reaches no
 * hit point of the tile (its term is exactly 0 there). The visibility
 * query is skipped where its answer is known for the whole tile: for the
 * tile's ground pixels (hull: the box of their ground points) and for its
 * wall pixels when they all lie on one wall (hull: the segment between
 * the two extreme ones), a lamp whose sector index (light.h) has, in every
 * sector the hull's directions meet, only bands that start at or beyond
 * every point of the hull (t_lo >= 1 - 1e-9 / (4 R), checked at the hull's
 * corners since 1 / t_lo is linear in the point) lights all of them: such
 * a band cannot stop the segment by more than light.h's 1e-9 m rule. The
 * wall a pixel lies on starts exactly at it, so walls in the open take the
 * shortcut too; any band nearer than the hull (a shadow caster) or one
 * without a lo line (the lamp over a footprint) sends every pixel of the
 * group to light_visible. Other shaders are called per pixel.
 * Depth range: near plane render_opts.near (default 0.05 m), far plane
 * beyond the farthest corner of the scene (buildings and lamps' reach). Back
 * faces are dropped unless the eye is inside a solid.
 *
 * Lamp glows. Unless no_glow, each lamp in front of the camera whose centre
 * is not hidden (its depth is in front of the depth buffer at its pixel) is
 * added as a small disc: radius max(1.5 px, 0.3 m projected) up to 48 px,
 * radiance color * intensity / 250 * (1 - (r/R)^2)^2. With no_glow every
 * pixel is exactly SPEC §5's radiance. The linear output (rgbf, for PFM)
 * carries the same values as the 8-bit output before tone mapping (glows
 * included unless no_glow).
 *
 * Tone mapping. 8-bit output: v = radiance * exposure, clamped to [0, 1],
 * sRGB transfer curve, rounded to nearest (a table of the 255 exact
 * thresholds searched per channel, no pow per pixel).
 *
 * Street-view culling (render_opts.cull). Provably conservative: the image
 * is bit for bit the image of the unculled render (tests/unit/test_render.c
 * checks it, eye above low roofs included). Two steps:
 *  1. Frustum: a building whose box corners all lie beyond one side plane
 *     (or behind the near plane) covers no pixel centre.
 *  2. Occlusion horizon (2.5D, after Downs, Moeller and Sequin's occlusion
 *     horizons). Azimuths around the eye are cut into RENDER_BINS bins; bin
 *     k holds h[k], a slope (tan of elevation) below which every ray of the
 *     bin is known to be stopped. Buildings are taken by increasing w_min
 *     (the smallest view-space depth of their box corners). An occluder O is
 *     a building standing on the ground with no holes whose box does not
 *     contain the eye (so its footprint spans less than 180 degrees of
 *     azimuth). Claim: a ray whose azimuth lies strictly between O's
 *     extreme vertex azimuths (a_min, a_max) and whose slope s is below
 *     s_O = (h_O - z_eye) / rho_far(O)   (h_O >= z_eye; rho_far = largest
 *     horizontal distance to O's vertices), or (h_O - z_eye) / rho_near(O)
 *     (h_O < z_eye; rho_near = horizontal distance to O's box), meets O's
 *     solid or the ground no farther than O: the footprint's interior is
 *     connected and lies on both sides of such a ray within a half-plane,
 *     so the ray enters it, at horizontal distance rho_in <= rho_far, and
 *     at that point its height z_eye + s rho_in is below h_O (case analysis
 *     on the sign of h_O - z_eye) and, if not below 0, inside the wall.
 *     So lower buildings do occlude, but only rays going down steeply
 *     enough, and an eye above a roof sees over it (s_O < 0). O is inserted
 *     into the bins lying entirely within (a_min + m, a_max - m) with the
 *     slope s_O - m_s, once w_max(O) (1 + g) < w_min of the building being
 *     tested. A building B (its box does not contain the eye) is culled when
 *     every bin meeting [b_min - m, b_max + m] (azimuths of its box corners)
 *     has h[k] > s_B + m_s, s_B = the steepest slope from the eye to B's box
 *     top (the nearest box distance when h_B >= z_eye, the farthest
 *     otherwise). Then every ray that can reach B is stopped at O, which is
 *     nearer along the ray than B.
 *     From rays to pixels: the rasteriser snaps vertices to 1/256 px and
 *     interpolates depth as a convex combination of vertex depths, so
 *     - margins: m (azimuth) and m_s (slope) correspond to 2 pixel angles
 *       (mu = 2 tan(fov/2) / H per pixel), scaled by the worst factor
 *       between a direction change and an azimuth (sqrt(1 + s^2)) or slope
 *       ((1 + s^2)) change; a pixel centre that the snapped B can cover is
 *       then a ray stopped by O with room to spare, and O's closed,
 *       watertight mesh (mesh.h) covers it;
 *     - depth: O's fragments have depth <= depth(w_max(O)) and B's >=
 *       depth(w_min(B)); the gap g = 1e-3 + w mu / (8 z_eye) + 4e-6 w/near
 *       covers float depth rounding and keeps the ray's height where it
 *       enters O at least a few snapping errors above the ground.
 *     Culled buildings still act as occluders: by induction on the order,
 *     every fragment of a culled building is behind a fragment of an
 *     earlier building, so the nearest fragment of every pixel belongs to a
 *     drawn building; drawn buildings are always drawn in index order, so
 *     depth ties resolve as in the unculled render.
 *     Raised buildings, buildings with courtyards and buildings whose box
 *     contains the eye never occlude; the last are always drawn. The eye
 *     inside a solid, or at or below the ground, switches occlusion culling
 *     off, and so does an eye higher than twice the tallest top (from
 *     there the test hardly ever culls and costs more than it saves).
 *     Touching buildings are separate occluders, so a bin that holds the
 *     azimuth of a shared wall is not closed by either: the culling leaks
 *     there (conservative, costs drawn geometry).
 *     Why not the polar-diagram visible set (visibility.h): it treats every
 *     building as infinitely tall, which is only valid with occluders nothing
 *     behind can rise above; the horizon gives the same shadows for tall
 *     occluders and the finite ones of low occluders in one O(n log n) pass.
 *
 * Aerial view (render_lightmap_build, render_opts.lightmap): a zenithal
 * light map of the ground, nx x ny texels over the box of the lamps' ground
 * reach (beyond it no lamp reaches the ground and E = 0 exactly), each
 * texel the exact E_rgb (shadows included: the shader's) at its centre,
 * built once. Ground pixels then take the bilinear interpolation of the
 * four nearest texel centres (texels outside the map are 0); walls, roofs
 * and undersides are still shaded exactly per pixel. The map's pitch is the
 * one asked for, enlarged when needed to stay within the byte budget.
 * With an indirect layer (render_lightmap_build_ind) ground and roof
 * pixels of aerial frames take their indirect term from it too (no
 * per-pixel gathers: the frame costs what a direct-only one does). When
 * the map has no filled layer (images not gathering: plx_indirect_set_gather
 * 0), render_opts.indirect_map makes them read the indirect ground map
 * (indmap.h) instead, built from the indirect hook at its texel centres
 * for indirect_key.
 *
 * Threads (render_opts.par, workers). The shading pass and the map builds
 * may run on a parallel-for: rows of tiles (rows of texels) as jobs, each
 * worker with its own tile buffers. The light object's region cache is
 * filled on the calling thread first and only read by the workers; a tile
 * that needs more is shaded after them on the calling thread, as one
 * thread does. A pixel depends on its tile alone, so the bytes are the
 * same for any number of workers (tests/unit/test_threads.c).
 *
 * Backends (render_backend below). Only pass (1) is pluggable: a backend
 * takes the visible buildings' triangles, already in clip space (the core
 * computes them in double precision and rounds them to float, identically
 * for every backend), and returns per pixel the surface id of the nearest
 * triangle covering the pixel centre and its window depth. Culling, the
 * shading pass, glows and tone mapping stay in the core, so two backends
 * can differ only in which triangle owns a pixel on an edge (fill rule,
 * sub-pixel precision) and in depth quantisation. The built-in software
 * rasteriser (raster.h) is the default; port/osmesa/ draws through OpenGL.
 * Both cull back faces as raster.h's RASTER_CULL_BACK does unless the eye
 * is inside a solid.
 *
 * Memory: render_create takes the mesh (its compact records: the triangles
 * of a building are made by mesh_building when it is drawn, into buffers
 * for the largest building), the frame buffers for the largest
 * image (depth, ids, linear colour: 20 bytes per pixel), the culling
 * arrays, a cache of render_surf_slots (64..4096) surface records filled from
 * each frame's ids before the shading pass (its workers only read it) and
 * (light shader) 4 bytes per lamp from the arena (part
 * PLX_PART_FRAME); the light map is taken there when built. render_frame allocates nothing. No global state; one render
 * object must not be used by two threads at once.
 */
#ifndef PLX_RENDER_H
#define PLX_RENDER_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/scene.h"
#include "base/arena.h"
#include "render/mesh.h"
#include "render/lightmap.h"

#define RENDER_BINS 4096

struct atlas;
struct atlas_cache;
struct atlas_view;

/* The shader: colour-weighted illuminance E_rgb (lux, per channel) at
 * surface point P with unit normal n. Must not fail; must be deterministic
 * (the culling guarantee compares images). */
typedef void (*render_shade_fn)(void *user, const double P[3], const double n[3],
                                double rgb[3] /* OUT */);

/* The light module (light.h) as a shader: user is a light *. */
void render_shade_light(void *user, const double P[3], const double n[3], double rgb[3]);

typedef struct render_camera {
    double eye[3], target[3];
    double fov_deg;            /* vertical, 0 < fov < 180 */
    int32_t width, height;     /* 1 .. the render object's maximum */
} render_camera;

enum { RENDER_CULL_NONE = 0, RENDER_CULL_FRUSTUM = 1, RENDER_CULL_OCCLUSION = 2,
       RENDER_CULL_ALL = 3 };

/* A raster backend (pass 1 above). Public as the opaque plx_backend of
 * polarlux.h; a port fills the functions and its own state in user. Per
 * frame the core calls begin once, draw once per visible building (in
 * building index order), then finish once. A backend must draw each
 * call's triangles in order with the depth test "less" (a later triangle
 * at equal depth does not replace an earlier one), so ties resolve as in
 * the software rasteriser. */
typedef struct plx_backend render_backend;
struct plx_backend {
    const char *name;          /* "soft", "osmesa", ... for messages */
    void *user;                /* the backend's state */
    /* Starts a frame of w x h pixels: depth cleared to the far plane, ids
     * to MESH_SURF_NONE. cull_back: drop triangles clockwise in normalised
     * device coordinates (x right, y up). Returns 0, or -1 when the backend
     * cannot draw this frame (e.g. larger than its buffers). */
    int (*begin)(void *user, int32_t w, int32_t h, int cull_back);
    /* Draws ntri triangles over nv vertices: triangle k has the clip-space
     * vertices clip[4 (tri[k].v[i] - v_base) ..] (x, y, z, w floats, OpenGL
     * clip space as in raster.h; tri[k].v[i] - v_base < nv) and the surface
     * id tri[k].surf. The renderer passes one building at a time, its
     * triangles made for this call (v_base 0). */
    void (*draw)(void *user, const float *clip, uint32_t nv, const mesh_tri *tri, uint32_t ntri,
                 uint32_t v_base);
    /* Ends the frame: writes the id of every pixel to id[w*h] and its window
     * depth in [0, 1] (1 where nothing was drawn) to depth[w*h], row 0 at
     * the top. Returns 0, or -1 on failure. */
    int (*finish)(void *user, uint32_t *id /* OUT */, float *depth /* OUT */);
};

/* A parallel-for (plx_port.parallel_for): job(arg, worker, k) for k = 0 ..
 * njobs-1 on up to 'workers' threads, worker in 0 .. workers-1, the calls
 * of one worker one after another; returns 0 when all ran, -1 when none
 * did. */
typedef void (*render_job_fn)(void *arg, int worker, uint32_t k);
typedef int (*render_par_fn)(void *ctx, int workers, uint32_t njobs, render_job_fn job, void *arg);
#define RENDER_MAX_WORKERS 16

#define RENDER_EXPOSURE_FIXED 0   /* render_opts.auto_exposure (PLX_EXPOSURE_*) */
#define RENDER_EXPOSURE_AUTO 1
#define RENDER_EXPOSURE_ADAPT 2
#define RENDER_EXPOSURE_TONE 3
#define RENDER_SAMPLE_FIRST 1     /* render_opts.cull_samples */
#define RENDER_SAMPLE_LATER 2

typedef struct render_opts {
    double exposure;           /* radiance multiplier before sRGB, default 1 */
    int no_glow;               /* 1: no lamp discs (exact SPEC §5 pixels) */
    int cull;                  /* RENDER_CULL_*, default RENDER_CULL_ALL */
    int lightmap;              /* 1: ground from the light map if built */
    double near;               /* near plane distance, default 0.05 m */
    render_shade_fn indirect;  /* added to E_rgb when not NULL (photon hook) */
    void *indirect_user;
    const render_backend *backend;  /* pass 1; NULL: the built-in software rasteriser */
    int auto_exposure;         /* RENDER_EXPOSURE_*: 0 exposure, linear; 1 from the image, 2 from the
                                  image held near exposure (exposure_hold), 3 exposure; 1 to 3
                                  with the tone curve (exposure.h) */
    int exposure_step;         /* RENDER_EXPOSURE_ADAPT: at most this many eighths of a stop a
                                  frame (0: no limit; exposure_hold) */
    double shift[2];           /* the sample point of each pixel: its centre + shift (pixels,
                                  x right, y down; |shift| < 0.5); 0 0 is SPEC §5's centre */
    int cull_samples;          /* a frame of several sample points (anti-aliasing): RENDER_SAMPLE_FIRST
                                  culls for any sample point within the pixel (the frustum
                                  widened by a pixel each way, its rows by one more) and keeps
                                  the culling; RENDER_SAMPLE_LATER reuses it when the camera,
                                  the near plane, the culling mode and the drawing path are the
                                  same (else culls as FIRST does); 0: culls for this sample point */
    uint8_t mask_new;          /* with mask: the byte a pixel newly marked by this sample
                                  gets (0 taken as 1); render_aa's 2 x 2 sums take 2, to
                                  find the pixels they catch up (render_aa_add_marked) */
    render_par_fn par;         /* the shading pass's parallel-for (NULL: one thread) */
    void *par_ctx;
    int workers;               /* workers it may use (1 .. RENDER_MAX_WORKERS; more are cut) */
    int indirect_mt;           /* 1: indirect may be called from several threads at once */
    int indirect_map;          /* 1: with lightmap, ground pixels read indirect from the indirect
                                  ground map (indmap.h), built from indirect when indirect_key
                                  differs from the last build's */
    uint64_t indirect_key;     /* changes whenever what indirect_far returns changes */
    render_shade_fn indirect_far; /* the hook the indirect ground map is built from (NULL:
                                  indirect): one that does not depend on the eye and is safe
                                  on several threads (its user is indirect_user) */
    double (*top)(void *user, double x, double y);  /* the map's surface height at (x, y): the
                                  topmost roof or 0 (NULL: the ground); user is indirect_user */
    int indirect_sparse;       /* 1 (not with lightmap): indirect is asked at the corners of
                                  blocks of 4 x 4 pixels, on this thread before the shading
                                  pass; a block on one surface (its pixels and corners),
                                  whose corners lie within indirect_span times the distance
                                  of the nearest of them from the eye, is interpolated
                                  bilinearly; the other pixels ask indirect after the pass.
                                  The shading pass may then use workers whatever
                                  indirect_mt says */
    double indirect_span;      /* see indirect_sparse (> 0, else no sparse indirect) */
    int (*indirect_try)(void *user, int worker, const double P[3], const double n[3], double rgb[3]);
                               /* sparse, with workers: indirect's value (the same bits) when
                                  it can be had without changing anything but the state of
                                  this worker (0 .. workers - 1 of the parallel-for), so on
                                  several workers at once, else 0 (NULL: indirect alone, on
                                  this thread); user is indirect_user */
    void (*indirect_surf)(void *user, uint32_t sid, uint32_t bld, const double P[3], const double n[3],
                          double rgb[3]);
                               /* not sparse: called instead of indirect for each pixel, with
                                  the pixel's surface id and its building (mesh.h); the same
                                  rules (indirect_mt) and user */
    uint8_t *mask;             /* adaptive anti-aliasing's later samples (render_aa_mask): only
                                  the pixels whose byte is not 0 are shaded, lit by indirect
                                  light and glows, and written; the others keep what the linear
                                  image held. First, an unmarked pixel whose surface is not
                                  mask_id's (a building's surface id; the ground and the sky
                                  count as one), or that a glow of this sample covers, gets its
                                  byte set to mask_new. NULL: every pixel */
    const uint32_t *mask_id;   /* with mask: the first sample's surface ids */
    const struct atlas *atlas; /* not NULL: every pixel read from this radiance atlas (atlas.h,
                                  atlas_frame.h) instead of shaded (the mask's pixels only,
                                  when there is one); the indirect hooks and the light map
                                  are then not used */
    struct atlas_cache *atlas_cache; /* with atlas: one per worker (workers of them, at least 1) */
    int (*atlas_need)(void *user, const struct atlas_view *v, const uint32_t *ids, const uint8_t *mask,
                      int32_t j0, int32_t j1);
                               /* with atlas (may be NULL: the atlas is complete): called for
                                  each run of rows j0 .. j1 - 1 (whole jobs of the frame's rows,
                                  j1 may pass its height) of which a row read a chart or block
                                  not filled yet (atlas_frame_row), with the frame's surface ids
                                  (the ground's set): fills what those rows read of the atlas
                                  (atlas_frame_missing; with mask, the marked pixels' reads
                                  only), after which they are read again. The caller
                                  makes the atlas current for the light before the frame (its
                                  filled items are read as they are);
                                  returns 0, or -1 when it could not (the frame then fails with
                                  PLX_E_NOMEM) */
    void *atlas_user;
} render_opts;

void render_opts_default(render_opts *o /* OUT */);


typedef struct render_stats {
    uint32_t buildings;        /* in the scene */
    uint32_t frustum_culled, occlusion_culled, drawn;
    uint64_t triangles, triangles_drawn;
    double drawn_fraction;     /* triangles drawn / triangles of the scene */
    uint64_t shader_calls;     /* calls of the shade function */
    uint64_t shader_tiled;     /* of which answered from a tile's lamp list */
    uint64_t visibility_skipped; /* lamp visibility known from the tile (no query) */
    uint64_t ground_pixels, building_pixels, sky_pixels;
    uint64_t indirect_calls;   /* calls of the indirect hook (sparse: corners and the pixels left) */
    uint64_t indirect_blocks;  /* sparse: blocks interpolated, of */
    uint64_t indirect_nblocks; /* the frame's blocks */
    uint32_t glows;            /* lamp discs drawn */
    int eye_inside;            /* the eye is inside a solid */
    int cull_kept;             /* the culling kept by the frame's first sample point was reused
                                  (render_opts.cull_samples) */
    double exposure;           /* the exposure applied (chosen when auto_exposure) */
} render_stats;

typedef struct render render;

/* Builds the mesh and takes the frame memory for images up to max_w x
 * max_h, or max_h x max_w (render_frame_fits). shade (required) and user are kept. Returns PLX_OK, PLX_E_INVALID
 * (NULL argument, sizes outside 1..16384), PLX_E_NOMEM (arena back where it
 * was). */
plx_status render_create(arena *a, const scene *s, int32_t max_w, int32_t max_h,
                         render_shade_fn shade, void *user, render **out /* OUT */);

/* Bytes render_create takes besides the mesh (frame buffers, culling
 * arrays, tables) for scene s and that maximum image, give or take a few
 * kilobytes of alignment; the mesh's bytes are render_mesh(r)->bytes. */
size_t render_bytes(const scene *s, int32_t max_w, int32_t max_h);

/* Whether a w x h frame is one a render object for max_w x max_h draws:
 * at most max_w x max_h, or max_h x max_w (turned a quarter: a portrait
 * screen's frames from a bake for a landscape one). */
int render_frame_fits(int32_t w, int32_t h, int32_t max_w, int32_t max_h);

/* The mesh (read-only). */
const mesh *render_mesh(const render *r);

/* Renders one frame. rgb8 (width*height*3 bytes, top row first) and rgbf
 * (width*height*3 floats, linear) are caller-owned and either may be NULL;
 * stats may be NULL. Returns PLX_OK or PLX_E_INVALID (bad camera: non-finite,
 * eye == target, fov outside (0, 180), size outside 1..max, eye.z <= 0;
 * render_error says which) or PLX_E_UNSUPPORTED (the backend could not
 * draw the frame). */
plx_status render_frame(render *r, const render_camera *cam, const render_opts *o,
                        uint8_t *rgb8 /* OUT */, float *rgbf /* OUT */,
                        render_stats *stats /* OUT */);

/* Tone mapping of px pixels of linear RGB: times ex, through the tone
 * curve when curve (exposure.h), into sRGB bytes (SPEC §5's exact
 * thresholds), on o's parallel-for; what render_frame does to its own
 * image. From a table of the exposure's float thresholds (tonemap.h:
 * tonemap_value's bytes, each value on its own). Returns whether a value
 * is beyond +-FLT_MAX / 4 or NaN (tonemap_apply). */
int render_tonemap_par(render *r, const float *lin, size_t px, double ex, int curve,
                       uint8_t *rgb8 /* OUT */, const render_opts *o);

/* The linear image of the last frame (width*height*3). Valid until the next frame.
 * After plx_render's anti-aliased frames it is not the frame's image:
 * after a 2 x 2 adaptive frame into bytes it holds the frame's sums
 * (scaled), after the others the last sample point's image; plx_render
 * returns the frame's own floats. */
const float *render_linear(const render *r);

/* Gives the renderer lin (room for its largest frame's 3 floats a pixel:
 * not checked, the caller sizes it as render_create does) as its linear
 * image from now on, and returns the one it had. 2 x 2
 * adaptive frames lend it the sums' buffer after the first sample, and
 * keep the first sample where it was drawn as the start of the sums. */
float *render_swap_linear(render *r, float *lin);

/* The surface id buffer of the last frame (width*height, row 0 on top;
 * MESH_SURF_NONE for sky, MESH_SURF_GROUND for ground) -- for tests and
 * picking. Valid until the next frame. */
const uint32_t *render_ids(const render *r);

/* Builds the ground light map (see above) at m_per_texel metres per texel,
 * coarser if needed to fit max_bytes (12 bytes per texel). Calls the shader
 * once per texel whose centre some lamp reaches. A second call rebuilds in
 * place when the new map fits the first one's memory. Returns PLX_OK,
 * PLX_E_INVALID (m_per_texel <= 0, max_bytes < 12), PLX_E_NOMEM. */
plx_status render_lightmap_build(render *r, double m_per_texel, size_t max_bytes);
/* The same with its rows on a parallel-for (lightmap.h: with the light
 * module's shader; the same map for any number of workers). */
plx_status render_lightmap_build_par(render *r, double m_per_texel, size_t max_bytes, render_par_fn par,
                                     void *ctx, int workers);

/* The same with the map's indirect layer (lightmap.h, lightmap_build_ind;
 * 28 bytes per texel): ind(user, x, y, ...) gives E_indirect at the topmost
 * surface over each reached texel centre. Aerial frames with an indirect
 * hook then read their ground and roof pixels' indirect term from it (the
 * hook only where the layer has no texel of the pixel's surface around it:
 * walls, slivers narrower than a texel, beyond the lamps' reach nothing).
 * ind is called on this thread; the direct part's rows as
 * render_lightmap_build_par. */
plx_status render_lightmap_build_ind(render *r, double m_per_texel, size_t max_bytes, lightmap_ind_fn ind,
                                     void *user, render_par_fn par, void *ctx, int workers);

/* The built map's indirect layer filled again by ind (lightmap_fill_ind:
 * users[w] for worker w of par), its direct part kept: PLX_E_INVALID
 * without a layer. Its rows are reported to pg (may be NULL). */
plx_status render_lightmap_fill_ind(render *r, lightmap_ind_fn ind, void *const *users, render_par_fn par,
                                    void *ctx, int workers, const lightmap_progress *pg);

typedef struct render_lightmap_info {
    int built;
    uint32_t nx, ny;
    double x0, y0, cell;       /* texel (i, j) centre: x0 + (i + .5) cell, y0 + (j + .5) cell */
    size_t bytes;
    uint64_t shaded;           /* texels the shader was called for */
    const float *rgb;          /* nx*ny*3, row j = y0 + j cell */
    int has_ind;               /* the indirect layer is filled (render_lightmap_build_ind) */
    const float *ind;          /* nx*ny*4: E_indirect RGB, topmost height (ind[0] < 0: none) */
} render_lightmap_info;

void render_lightmap_get(const render *r, render_lightmap_info *out /* OUT */);

/* Code addresses held by the render object (the shader, the built-in
 * backend's functions, the rasteriser's fragment function, the error text)
 * differ between processes: render_code_unbind clears them (before the
 * object's memory is saved in a bake), render_code_bind sets them again
 * with shade as the shader (after a bake is loaded). The shader's user
 * pointer is kept. */
void render_code_unbind(render *r);
/* Surface records the renderer keeps, by id modulo their number (a power
 * of 2; render_int.h's pixel_surf): at most this many. */
#define RENDER_SURF_CACHE 16384
/* Their number for a scene and the largest frame: one per surface of the
 * scene (every one cached), at most one per 64 pixels and
 * RENDER_SURF_CACHE, at least 64. A record not cached is made again when
 * read (the same values), so the number changes no byte of a frame. */
uint32_t render_surf_slots(const scene *s, int32_t max_w, int32_t max_h);

/* Every buffer and value a frame leaves behind set to zero, so that what
 * the object holds does not depend on the frames drawn (a bake saves it):
 * the next frame starts as the first one did. */
void render_frame_clear(render *r);

/* Whether the point eye lies in some building's solid (its footprint,
 * holes out, boundaries in, between its heights): frames from there see
 * the inner faces of walls, which the radiance atlas does not hold. */
int render_eye_inside(const render *r, const double eye[3]);

/* sizeof the render object (opaque elsewhere). */
size_t render_struct_bytes(void);
void render_code_bind(render *r, render_shade_fn shade);

/* One fixed sentence about the last failure ("" after success). */
const char *render_error(const render *r);

/* sRGB byte of a linear value (exact thresholds; for tests and tools). */
uint8_t render_srgb8(const render *r, double v);

#endif
