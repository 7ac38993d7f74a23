/* atlas_fill: the radiance atlas's values (atlas.h), direct light exact at
 * every vertex plus indirect light from a hook on a coarser grid.
 *
 * A VERTEX'S POINT. Walls: the vertex moved onto its footprint edge's
 * line (computed in double from the edge's two points, with the edge's
 * normal: the chart's float direction leaves o + u e up to the wall's
 * length times 2^-24 off the wall, in its own shadow when inside),
 * between its corners. Roofs and undersides: the vertex when it lies in
 * the footprint (outer ring in, holes out, boundaries in), else the
 * nearest point of the footprint's boundary. The ground: the vertex,
 * unless it lies strictly inside the footprint of a building standing on
 * the ground (its solid): then the nearest point of that footprint's
 * boundary, moved 1 mm out along the edge's outward normal, or, when
 * that point lies strictly inside a solid too (a wall two buildings
 * share, a narrow reflex corner), the nearest such point (an edge's
 * nearest point 1 mm out) of any building around that lies in none: open
 * ground, searched within a radius doubled until one is found (256 m at
 * most). The light at a vertex is SPEC §2's at that point with the
 * surface's outward normal.
 * So every vertex holds the light of a point on (or 1 mm off) its own
 * surface, and a pixel near a wall foot or a roof edge mixes only values
 * of its surface.
 *
 * WHAT IS STORED. albedo / pi (E_direct_rgb + E_indirect_rgb), E_direct
 * from light_illuminance (colour-weighted, exact 2.5D visibility) at
 * every vertex of every chart, E_indirect from the hook at the "records"
 * of each chart: every ATLAS_IND_EVERY-th vertex along each side (the
 * last vertex too), interpolated bilinearly between them. The albedo is
 * the building's on walls, roofs and undersides, the ground's
 * (scene_ground_albedo) at the vertex's point on the ground.
 *
 * THREADS. Charts are the jobs (in runs of ATLAS_JOB_CHARTS); worker w
 * computes with its own light object and hook state (atlas_worker[w]);
 * a chart's values depend only on the chart, so the atlas is the same
 * bytes for any number of workers.
 */
#ifndef PLX_ATLAS_FILL_H
#define PLX_ATLAS_FILL_H

#include "render/atlas.h"
#include "render/lightmap.h"

struct light;

#define ATLAS_IND_EVERY 8     /* fine vertices between indirect records (4 m at 0.5 m) */
#define ATLAS_JOB_CHARTS 64   /* charts a job */

/* E_indirect RGB (lux) at surface point P with unit normal n on the
 * surface of chart c (sid: mesh.h's surface id, MESH_SURF_GROUND for the
 * ground). Must give a point the same value whatever was asked before. */
typedef void (*atlas_ind_fn)(void *user, const atlas_chart *c, uint32_t sid, const double P[3], const double n[3],
                             double rgb[3] /* OUT */);

typedef struct atlas_worker {
    struct light *lt;         /* the worker's own (its region cache fills as it reads) */
    atlas_ind_fn ind;         /* NULL: no indirect light */
    void *ind_user;
    double *rec;              /* records of one chart: atlas_fill_records() doubles */
} atlas_worker;

/* Doubles a worker's records need: 3 per record of the largest chart. */
size_t atlas_fill_records(const atlas *A);

/* The parallel-for (render.h's render_par_fn) and progress. */
typedef struct atlas_par {
    int (*par)(void *ctx, int workers, uint32_t njobs, void (*job)(void *arg, int worker, uint32_t k), void *arg);
    void *ctx;
    lightmap_progress progress;
} atlas_par;

#define ATLAS_STAGE "radiance atlas"

/* Fills every chart and block not filled yet with workers w[0 .. nw-1]
 * (w[0] on this thread when there is no parallel-for), and marks them
 * filled. Every worker must have ind set alike (all or none). Returns
 * PLX_OK or PLX_E_INVALID. */
plx_status atlas_fill(atlas *A, atlas_worker *w, int nw, const atlas_par *par /* may be NULL */);

/* The same for the n items listed (atlas.h's numbering; those filled
 * already, or without vertices, are left; an item may be listed twice). */
plx_status atlas_fill_items(atlas *A, atlas_worker *w, int nw, const atlas_par *par /* may be NULL */,
                            const uint32_t *items, uint32_t n);

/* One vertex's point and normal (as above): for tests and the frame. */
void atlas_vertex_site(const atlas *A, const struct light *L, const atlas_chart *c, uint32_t i, uint32_t j,
                       double P[3] /* OUT */, double n[3] /* OUT */);

#endif
