/* render_int.h: what the files of the renderer share (private to
 * src/render/; see render.h for the renderer itself).
 *
 *   render.c           the render object: creation, the frame driver, exposure
 *                      and tone mapping on the workers, the light map's builds
 *   camera.c           a frame's camera
 *   cull.c             culling: the grid of cells, the frustum, the occlusion
 *                      horizon and its front-to-back traversal
 *   soft_backend.c     the visibility pass: the built-in backend over raster.h,
 *                      bands of rows on the workers, the ground's ids
 *   pixel_hit.c        a pixel's surface, hit point and normal; the surface cache
 *   shade_tiles.c      the shading pass by tiles of pixels
 *   sparse_indirect.c  the indirect hook at the corners of blocks of pixels
 *   glow.c             the lamps' glow discs
 *   render_aa.c        adaptive anti-aliasing: the samples' sums, the marks, the
 *                      2 x 2 sums at the marked pixels (render_aa.h)
 *   render_atlas.c     frames from the radiance atlas (render_atlas.h)
 *
 * The small helpers are inline: they run in the hot loops of several files.
 */
#ifndef PLX_RENDER_INT_H
#define PLX_RENDER_INT_H

#include <stddef.h>
#include <stdint.h>
#include "render/render.h"
#include "render/raster.h"
#include "render/exposure.h"
#include "render/tonemap.h"
#include "render/lightmap.h"
#include "render/indmap.h"
#include "light/light.h"

#define PI 3.14159265358979323846

typedef struct cull_item { double key; uint32_t b; } cull_item;

#define RENDER_TILE 8           /* shading tiles, pixels a side */
#define CULL_CELL 64.0          /* m, the culling grid's cells, */
#define CULL_SIDE 128.0         /* at most this many a side (larger cells over larger scenes) */
#define CULL_GROUP 8u           /* cells a side of a group of cells, tested first (cull_buildings) */
#define RENDER_TILE_LAMPS 64    /* longest lamp list of a tile */
#define TILE_PX (RENDER_TILE * RENDER_TILE)
#define IND_STEP 4              /* sparse indirect: corners every IND_STEP pixels */

/* What one worker of the shading pass works in: a tile's hit points,
 * normals and E, its lamp list, and its counters. */
typedef struct shade_ws {
    uint32_t tl[RENDER_TILE_LAMPS];
    double tP[TILE_PX][3], tN[TILE_PX][3], tE[TILE_PX][3];
    uint8_t tcall[TILE_PX];     /* 0 sky, 1 no shader, 2 shader */
    double tI[TILE_PX][3];      /* indirect from the indirect ground map ... */
    uint8_t tind[TILE_PX];      /* ... when 1 (else the hook's) */
    render_stats st;            /* the shading pass's counters of this worker */
} shade_ws;

/* A grid corner's sample: whether its ray meets a surface, the point and
 * the normal (pixel_hit). */
typedef struct corner_hit {
    double P[3], n[3];
    int hit;
} corner_hit;

/* A glow disc seen in a frame (glow_disc): centre x, y and radius in
 * pixels, and its lamp. */
typedef struct glow_seen {
    double g[3];
    uint32_t lamp;
} glow_seen;

struct render {
    arena *a;
    const scene *s;
    mesh *m;
    render_shade_fn shade;
    void *user;
    int32_t max_w, max_h;
    float *depth;
    uint32_t *id;
    float *lin;
    raster_vertex *vbuf;        /* soft_draw: the vertices of the triangles it clips */
    raster_pvert *pv;           /* soft_draw's vertices prepared (raster_prepare) */
    float *clip;                /* 4 per vertex of one building */
    render_backend soft;        /* the built-in backend (user = this) */
    raster_ctx rc;              /* its rasteriser state during a frame */
    /* culling */
    cull_item *heap;            /* nbld, min-heap by w_max */
    double *gxyz;               /* one building's vertices (mesh_building) */
    mesh_tri *gtri;             /* and its triangles */
    uint32_t *sc_id;            /* sc_mask + 1 slots: surfaces seen (pixel_surf), by id */
    mesh_surf *sc;
    uint32_t sc_mask;           /* render_surf_slots - 1 */
    uint32_t nheap;
    double *wmin, *wmax;        /* nbld */
    uint8_t *draw;              /* nbld */
    /* the buildings by cells of a grid (each in the cell of its box's
     * centre), each cell with the box of its buildings' boxes: a cell
     * wholly outside the frustum culls its buildings at once */
    uint32_t ncell;
    uint32_t *cell_start;       /* ncell + 1 offsets into cell_bld */
    uint32_t *cell_bld;         /* nbld building indices, cell by cell, ascending */
    double *cell_box;           /* 6 a cell: minx, miny, minz, maxx, maxy, maxz */
    /* the cells by groups of CULL_GROUP x CULL_GROUP, each with the box of
     * its cells' boxes: a group wholly outside the frustum culls its cells
     * without testing them */
    uint32_t cside, gside;      /* cells and groups a side */
    double *group_box;          /* 6 a group, as cell_box */
    uint8_t *group_out;         /* gside^2: this frame's groups out of the frustum or wholly inside (cull_buildings) */
    cull_item *trav;            /* nbld + ncell: the occlusion pass's heap */
    uint32_t ntrav;
    double *bins;               /* RENDER_BINS */
    int32_t *yr;                /* nbld x 2: a drawn building's rows on screen (cull_buildings) */
    struct band *band;          /* RENDER_BANDS of them, or NULL: the rows drawn by bands */
    /* frame state */
    int32_t w, h;
    uint32_t cur_id;
    double eye[3], f[3], rt[3], up[3];
    double sx, sy, za, zb, tanh_, aspect, near_, far_;
    double far_eye[3], far_near; /* what far_ was found for (camera_setup) */
    double shift[2], shx, shy;  /* sample point offset in pixels, and in NDC */
    double cpad[3];             /* the frustum culling's widening: x and y in NDC a unit of w,
                                   and rows (render_opts.cull_samples) */
    /* the culling kept for the later sample points of a frame (cull_samples):
     * what it was made for, and its counts */
    int kept;
    double kept_key[16];
    int kept_inside;
    uint32_t kept_frustum, kept_occlusion;
    int bg_fill;                /* this frame's built-in rasteriser starts each row of ids at its
                                   background (row_background), for soft_ground_ids to skip */
    uint32_t *glamp;            /* nlamps + 1: with the kept culling, the lamps whose glow a
                                   sample point within the pixel may draw (glow_candidates) */
    uint32_t nglamp;
    int glamp_ok;               /* glamp holds them for this frame's camera */
    glow_seen *gseen;           /* nlamps + 1: the glow discs of the last frame drawn (glow_discs) */
    uint32_t ngseen;
    int gseen_ok;               /* gseen holds them */
    /* shading by tiles */
    light *lt;                  /* the light module when shade is render_shade_light */
    shade_ws ws[RENDER_MAX_WORKERS];  /* one per worker of the shading pass */
    uint8_t *defer;             /* per tile of the largest frame: left to the serial pass; in
                                   frames from the radiance atlas, per job of RENDER_TILE rows:
                                   read again (atlas_rows) */
    /* sparse indirect (render_opts.indirect_sparse): per block of IND_STEP
     * pixels a side, whether one surface covers it with its corners; the
     * hook's value at each corner of the grid (RGB) */
    uint8_t *blk;
    float *ind;
    corner_hit *crow;           /* two rows of corners' hit points (the longer side of the
                                   largest frame / IND_STEP + 2 each: frames either way round) */
    uint32_t hist[RENDER_MAX_WORKERS][EXPOSURE_BINS]; /* automatic exposure's counts, by part */
    int32_t *stop;              /* per row of corners, then per pixel row: where the workers'
                                   tries stopped (render_opts.indirect_try) */
    size_t corner_cap, crow_cap, stop_cap; /* entries of blk (ind: 3 floats each), crow, stop */
    int32_t nbx, nby;           /* blocks a row, rows of blocks */
    int sparse;                 /* this frame's indirect is sparse */
    lightmap lm;                /* the aerial light map (lightmap.c) */
    indmap im;                  /* its indirect twin (indmap.c) */
    double thr[TONEMAP_LEVELS];
    tonemap_table *tm;          /* the last exposure's table (tonemap.h) */
    uint32_t frames;            /* frames drawn: the atlas maps' stamp (atlas_frame.h) */
    exposure_table *et;         /* the exposure's bins without the logarithm (exposure.h) */
    const char *err;
};

/* A worker drawing a band of rows with the built-in rasteriser (render
 * frames on several workers): its own rasteriser state, scissored to the
 * band, and its own buffers for one building at a time. */
#define RENDER_BANDS 4                /* band workers at most */
typedef struct band {
    render *r;
    raster_ctx rc;
    uint32_t cur_id;
    double *gxyz;
    mesh_tri *gtri;
    float *clip;
    raster_vertex *vbuf;
    raster_pvert *pv;
} band;

static inline void to_clip(const render *r, const double *X, double out[4])
{
    double v0 = X[0] - r->eye[0], v1 = X[1] - r->eye[1], v2 = X[2] - r->eye[2];
    double w = v0 * r->f[0] + v1 * r->f[1] + v2 * r->f[2];
    out[0] = (v0 * r->rt[0] + v1 * r->rt[1] + v2 * r->rt[2]) * r->sx - r->shx * w;
    out[1] = (v0 * r->up[0] + v1 * r->up[1] + v2 * r->up[2]) * r->sy + r->shy * w;
    out[2] = r->za * w + r->zb;
    out[3] = w;
}

/* Surface sid's albedo (cached, or mesh_albedo). */
static inline double surf_albedo(const render *r, uint32_t sid)
{
    uint32_t k = sid & r->sc_mask;
    return r->sc_id[k] == sid ? r->sc[k].albedo : mesh_albedo(r->m, sid);
}

/* The workers a parallel-for of this frame may use: 1 without one, at
 * most RENDER_MAX_WORKERS. */
static inline int par_workers(const render_opts *o)
{
    if (!o || !o->par || o->workers < 2)
        return 1;
    return o->workers > RENDER_MAX_WORKERS ? RENDER_MAX_WORKERS : o->workers;
}

/* fn(arg, worker, k) for k = 0 .. jobs - 1 on the workers, or on this
 * thread without them (or when the port could not run them). */
static inline void run_jobs(const render_opts *o, uint32_t jobs, render_job_fn fn, void *arg)
{
    uint32_t k;
    if (par_workers(o) < 2 || jobs < 2 || o->par(o->par_ctx, par_workers(o), jobs, fn, arg) != 0)
        for (k = 0; k < jobs; k++)
            fn(arg, 0, k);
}

/* Surface sid's record: from the cache when it holds it, else made in
 * tmp (the same values: mesh_surface). */
static inline const mesh_surf *pixel_surf(const render *r, uint32_t sid, mesh_surf *tmp)
{
    uint32_t k = sid & r->sc_mask;
    if (r->sc_id[k] == sid)
        return &r->sc[k];
    mesh_surface(r->m, sid, tmp);
    return tmp;
}

/* camera.c: a frame's camera from render_camera and render_opts (0 and
 * r->err on a bad one); a pixel's sample ray direction. */
int camera_setup(render *r, const render_camera *c, const render_opts *o);
void camera_pixel_dir(const render *r, int32_t i, int32_t j, double d[3]);

/* cull.c: the culling grid's side and its fill (render_create); the
 * frame's culling (r->draw, by frustum and occlusion). */
uint32_t cull_side(const scene *s, double *x0, double *y0, double *cell);
void cull_grid_fill(render *r);
void cull_buildings(render *r, const render_opts *o, int inside, int rows, render_stats *st);

/* soft_backend.c: the built-in backend "soft" over raster.h; its band
 * workers' buffers (render_create); the visibility pass by bands of rows
 * or through a backend; the ground's ids where nothing was drawn. */
int soft_begin(void *user, int32_t w, int32_t h, int cull_back);
void soft_draw(void *user, const float *clip, uint32_t nv, const mesh_tri *tri, uint32_t ntri,
               uint32_t v_base);
int soft_finish(void *user, uint32_t *id, float *depth);
void soft_bands_create(render *r, arena *a);
void soft_draw_bands(render *r, const render_opts *o, int cull_back, render_stats *st);
void soft_draw_buildings(render *r, const render_backend *be, render_stats *st);
void soft_ground_ids(render *r, const render_opts *o);

/* glow.c: the lamps whose glow a frame's sample points may draw; the
 * glows added to the linear image; their pixels marked in a mask. */
void glow_candidates(render *r);
void glow_draw(render *r, const render_opts *o, render_stats *st);
size_t glow_mark(render *r, uint8_t *mask, uint8_t nw);

/* render_aa.c: a later anti-aliasing sample's mask updated (render_opts.mask). */
void render_aa_mask_update(render *r, const render_opts *o);

/* render_atlas.c: every pixel of a frame from the radiance atlas (-1 when
 * what it shows could not be filled). */
int render_atlas_pass(render *r, const render_opts *o, render_stats *st);

/* pixel_hit.c: the surface cache filled before the shading pass; a
 * pixel's surface, hit point and normal. */
void pixel_surf_cache_fill(render *r);
int pixel_hit(render *r, int32_t i, int32_t j, uint32_t *sid_out, double P[3], double n[3]);

/* shade_tiles.c: the shading pass by tiles. */
void shade_pass(render *r, const render_opts *o, render_stats *st);

/* sparse_indirect.c: the hook at the corners of one-surface blocks before
 * the shading pass, a pixel's term from them, the other pixels after it. */
void sparse_corners(render *r, const render_opts *o, render_stats *st);
void sparse_at(const render *r, int32_t i, int32_t j, double E[3]);
void sparse_rest(render *r, const render_opts *o, render_stats *st);

#endif
