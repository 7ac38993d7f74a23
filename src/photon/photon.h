/* photon: indirect light by urban photon buffers (SPEC §4; argudo2012 §3,
 * munoz2013 §3.1, §3.3-3.4), on the CPU, in memory fixed at creation.
 *
 * WHAT IS COMPUTED. E_indirect(P): the illuminance at surface point P carried
 * by light after one or more diffuse bounces; the outgoing radiance of the
 * indirect part is albedo / pi * E_indirect (SPEC §4), E_direct stays exact
 * (light.h). Photons are traced from the lamps through the 2.5D scene
 * (trace.h) and stored at the second and later surfaces they meet: the first
 * hit is direct light and is not stored.
 *
 * LAMPS AND THE REACH WINDOW. A lamp of intensity I cd is an isotropic point
 * emitting 4 pi I lm. SPEC §2 weights direct light by W(d/R); for the
 * indirect light to come from the same direct light, a photon's flux is
 * multiplied by W(d1/R), d1 = distance to its first hit. The expected flux
 * density at first hits is then exactly E_direct (with its falloff and its
 * cut at R), and every later bounce reflects that light. Photons whose
 * first hit is at d1 >= R carry nothing and are not traced further (the
 * first-hit ray is cast only to R).
 *
 * COLOUR. A photon carries PHOTON_CH = 4 weights: a colour-blind scalar
 * flux (channel 0; what illuminance in lux reports, SPEC §2: colour is
 * ignored) and an RGB flux (channels 1-3; what images use, each lamp's
 * light weighted by its colour). A photon of lamp i starts with
 * phi W (1, c_i). Charts, floor maps and ambient terms store all four, so
 * a lookup gives E_indirect and its RGB version in one pass.
 *
 * BOUNCES. Lambertian: cosine-weighted directions about the normal, Russian
 * roulette with one scalar survival probability p = the albedo's luminance
 * (building albedo on walls, roofs and undersides, grey; on the ground the
 * albedo at the hit, scene_ground_albedo: a ground image's pixel or the
 * scene's ground_albedo, src/ground.c), and the survivor's weights become
 * f_0 a_Y / p = f_0 and f_c a_c / p (photon_bounce): unbiased per channel,
 * and for grey albedos every weight is unchanged, so a stored photon
 * carries its emission flux times W. At most cfg.max_bounces surfaces
 * after the first.
 *
 * CHARTS (where photons are stored; argudo2012 §3.2).
 *  - Facades. Per block two cylindrical charts, outer walls and inner
 *    walls, centred on the block's box centre: u = angle / 2 pi (from -pi),
 *    v = z / (block's tallest height). A wall belongs to the inner chart
 *    when it is an edge of a hole of its building, or when the point 1 cm in
 *    front of its middle lies inside one of the block's courtyard rings
 *    (clockwise rings of the block outline, blocks.h; a raised building over
 *    a courtyard fills it in the outline, hence the first rule), or when
 *    another building touches its front (the exposed strip of a party wall
 *    above a lower neighbour, or below a raised one): such a strip faces a
 *    neighbour's roof (or its underside), not the street, and reading the
 *    street facade's light at its place around the block made it 1.7 to
 *    9.5 times too bright against the path tracer (test_photon's
 *    test_party_wall_strips).
 *    Only the exposed part of a wall is charted: the part not covered by
 *    another building touching its front (a shared wall is exposed only
 *    above the lower neighbour); this is decided at the wall's middle.
 *    Each texel keeps the world area of the exposed facade that maps to it
 *    (walls cut in pieces of <= 1/4 texel of angle), which is the Delta A
 *    of the lookup. Several walls mapping to one texel (a wall seen edge-on
 *    from the centre) share it: the method's known blur.
 *  - Ground and roofs ("aerial" chart). An orthogonal chart over Bounds
 *    with square texels, a surface channel (the key of the topmost
 *    horizontal surface at the texel centre, surface_key.h: a roof's
 *    height, 0 for open ground, -1 - c in courtyard c) and each texel's
 *    area = texel area times the fraction of k x k probes whose top
 *    surface has that key. Splats only reach texels of the photon's key
 *    (within 1 mm), so roof, street and courtyard photons do not mix, and
 *    a photon whose own texel holds another surface is not stored (lost):
 *    spread onto the nearest texels of its key it would add light from an
 *    area they do not count (on coarse charts roofs took the light of the
 *    roofs around them, courtyards the streets'). The price, on charts
 *    of a few texels across a whole city (a splat of 2 to 4 texels
 *    reaching the empty border): the streets read low (0.34 to 0.45 of the
 *    truth on eixample-4x4 at 8 texels a side, test_coarse_charts).
 *  - Covered ground (ground under raised buildings: canopies, bridges,
 *    min_height > 0). A second, sparse aerial layer on the same texel grid:
 *    gcov maps an aerial texel to its slot in compact arrays (cov_*), and
 *    only texels with covered ground get one; a slot's area is the texel
 *    area times the fraction of k x k probes that are open ground under a
 *    raised building (disjoint from the aerial chart's area there). Ground
 *    photons in such a texel whose point is covered (trace_top > 0) are
 *    splatted into this layer (same kernel, validity = a slot with area),
 *    and a lookup at z = 0 under a canopy reads it. Capacity is bounded
 *    from the scene alone (the aerial texels under the boxes of raised
 *    buildings), so photon_bytes needs no tracer; scenes without raised
 *    buildings allocate nothing for it.
 *    Other horizontal surfaces that are not topmost (roofs under a raised
 *    building, undersides) have no chart: photons there are counted as
 *    lost and the lookup answers with the block's ambient term (undersides)
 *    or the nearest texel of the right height (roofs).
 *
 * LEVELS (argudo2012 §3.6). Blocks get levels 0-4 from their distance d to
 * the viewer (nearest point of the block's box, 0..tallest height) and the
 * mean block diameter b: d < 3b level 0, < 6b level 1, < 12b level 2,
 * < 24b level 3, else 4; with a view direction, a block outside the view
 * cone is level 2 when d < 3b and level 4 otherwise (what is on screen is
 * charted; nearby blocks off screen keep a coarse chart). Blocks are taken
 * by increasing d and a full level passes the block to the next level with
 * room (budgets cfg.level_blocks, argudo's 10/40/160/640). Level L charts
 * are (chart_w >> L) x (chart_h >> L) texels, so every level's atlas has
 * about the same size. A block keeps its chart (and its accumulated
 * photons) while its level does not change; a block that changes level
 * starts a fresh chart. Level 4 blocks have no chart: their facades get a
 * constant ambient term, the mean facade irradiance of the block measured
 * by the same photons (flux on its exposed facades / their area / frames).
 *
 * PROGRESSIVE ACCUMULATION. photon_step adds one frame of photons; charts
 * count the frames they have received (M). Splat kernel: a cone of radius
 * r(M) = rmin + (rmax - rmin) k / (k + M - 1) texels (cfg.kernel_*), so the
 * first frames are blurry and later ones sharp; each splat's weights over
 * the texels it may reach (charted, right key) are normalised, so a
 * splat deposits exactly the photon's flux (else nearest valid texel; else
 * lost; lost too on a chart of surface keys when the texel under it holds
 * another surface). Lookup is O(1): E = (sum w Phi) / (sum w Delta A) / M over the
 * 2 x 2 texels around P (bilinear weights w, valid texels only).
 *
 * NIGHT LIGHTING (munoz2013 §3.3-3.4). Lamps near the viewer get their own
 * floor photon maps: a square of side 2R centred on the lamp, cfg.lamp_res^2
 * texels with a surface channel (keys as the aerial chart), filled by
 * cfg.lamp_photons photons of that lamp alone (deterministic: seeded by the lamp index), ground and roof
 * photons only. They live in an LRU cache of fixed slots (capacity from
 * cfg.lamp_slots or cfg.lamp_cache_bytes). The aerial chart and the floor
 * maps are combined without counting any lamp twice, as munoz's
 *   E(p) = sum_{i in L} + sum_{i in I, not in C} + sum_{i in C}:
 *  - A (the aerial chart, progressive) holds the lamps never refined (L);
 *  - I (improved aerial map, aerial resolution, one set of photons per
 *    lamp) holds every refined lamp's horizontal photons. "Push": the first
 *    time lamp i's floor map is computed, its photons are splatted into I
 *    at aerial resolution, lamp i is marked refined, the progressive pass
 *    stops splatting lamp i into A, and A restarts (M = 0) so that lamp i's
 *    older photons leave it.
 *  - C_i (cached floor map) replaces I's share of lamp i near the lamp: each
 *    slot also keeps D_i, its in-square photons splatted at aerial
 *    resolution, so E = A/M + I - sum_{i in C} D_i + sum_{i in C} C_i.
 *    Evicting a lamp needs no update (I already holds it); recomputing it
 *    gives the same photons, so D_i cancels its share of I again.
 *  Facade charts always take every lamp's photons from the progressive pass.
 *  Covered ground has no floor maps: A_cov (progressive) holds the unrefined
 *  lamps and I_cov every refined lamp's covered-ground photons, pushed with
 *  I; E = A_cov / M + I_cov (C_i and D_i leave covered photons out).
 *
 * COST OF A PASS (tests/bench/bench_photon.c, gen eixample 30 30, 64K
 * photons, 1.25 rays each). Most photons end at their first hit, so the
 * per-photon work is: the stratified lamp choice, a uniform direction,
 * the lamp ray (trace_lamp_ray: the lamp's table), W and the roulette; a
 * quarter of them bounce (cosine direction, a grid walk) and are stored.
 * What keeps it short, with the same random numbers and the same bytes
 * as the plain version (tests compare):
 *  - directions take cos and sin of 2 pi u from a polynomial, not libm
 *    (photon_sincos_turn; same random numbers in the same order);
 *  - lamps are taken in order, so the next lamps' tables and the walls
 *    they list are prefetched when the lamp changes (trace_lamp_prefetch);
 *  - the bounce reads the albedo the caster hands over with the hit;
 *  - a stored photon's chart, coordinates and radius are decided when it
 *    arrives and its texel rows prefetched; it is splatted STORE_QUEUE
 *    photons later, in arrival order (every sum in the same order);
 *  - the splat visits only the texels within r (squared distances first),
 *    without calls;
 *  - helpers are static: under -fPIC exported functions are not inlined.
 * Storing costs about a quarter of the pass, the caster about half.
 *
 * MEMORY. photon_create takes every buffer from the arena (part
 * PLX_PART_PHOTON): the tracer, per-edge and per-block tables, the four
 * level atlases, the aerial charts, the covered-ground layer, the lamp
 * cache. A texel keeps its flux as PHOTON_CH floats (16 bytes: scalar and
 * RGB) beside its area (and height) floats; cfg.lamp_cache_bytes is a byte
 * budget, so colour halves the slots it holds. photon_set_viewer and
 * photon_lamps_update use scratch memory (released before return); steps and
 * lookups allocate nothing. One photon_sys must not be used from two threads
 * at once. No global state: randomness comes from the seeds given.
 */
#ifndef PLX_PHOTON_H
#define PLX_PHOTON_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"
#include "photon/trace.h"
#include "photon/surface_key.h"

#define PHOTON_LEVELS 4        /* charted levels 0..3; level 4 = ambient */
#define PHOTON_NONE 0xffffffffu
#define PHOTON_KERNEL_MAXI 6   /* largest splat radius, texels */
#define PHOTON_KERNEL_MAX ((double)PHOTON_KERNEL_MAXI)
#define PHOTON_LOOKUP_MAXI 16  /* largest lookup_radius, texels */
#define PHOTON_LOOKUP_MAX ((double)PHOTON_LOOKUP_MAXI)
#define PHOTON_CH 4            /* flux channels per texel: scalar, R, G, B */

typedef struct photon_config {
    uint32_t chart_w, chart_h;      /* level 0 facade chart, texels (u around, v up); 256 x 32 */
    uint32_t level_blocks[PHOTON_LEVELS]; /* blocks per level: 10, 40, 160, 640 */
    uint32_t aerial_res;            /* aerial chart texels along the longer side of Bounds; 512 */
    uint32_t coverage_probes;       /* k: k x k probes per horizontal texel for its area; 3 */
    double kernel_max, kernel_min;  /* splat radius in texels, first frame / limit; 2.5, 1.0 */
    double kernel_frames;           /* k of r(M); 8 */
    uint32_t max_bounces;           /* surfaces after the first; 16 */
    uint32_t lamp_res;              /* floor map side, texels; 64 */
    uint32_t lamp_photons;          /* photons per floor map; 32768 */
    double lamp_kernel;             /* floor map splat radius, texels; 1.5 */
    uint32_t lamp_slots;            /* LRU capacity; 0 = as many as lamp_cache_bytes hold */
    size_t lamp_cache_bytes;        /* used when lamp_slots is 0; 4 MiB */
    double near_radius;             /* photon_lamps_update: lamps within this horizontal
                                       distance of the viewer are refined; 60 m */
    double cell_size;               /* tracer grid cell, m; 0 = automatic */
    int no_lamp_tables;             /* 1: the tracer keeps no per-lamp ray tables (the same
                                       hits, first rays about 2x slower; trace_create_ex) */
    uint32_t coarsest_level;        /* photon_set_viewer gives no block a level above this
                                       (while its level has room); PHOTON_LEVELS (4) = the
                                       distance rule alone. Final gathering (final_gather.h)
                                       reads later bounces at surfaces all around its points,
                                       so it charts every block: 2 with level_blocks[2] =
                                       every block (photon_config_gather) */
    double lookup_radius;           /* lookups on facade charts and the aerial chart: 0 =
                                       bilinear over 2 x 2 texels; r > 0 = cone of r texels
                                       over the same surface (photon_gather_wide); 0, and 3
                                       in photon_config_gather */
} photon_config;

void photon_config_default(photon_config *c /* OUT */);
/* The configuration for final gathering at points: the default with every
 * block charted at level 2 or finer (coarsest_level 2, level_blocks[2] =
 * nblocks of s). */
void photon_config_gather(photon_config *c /* OUT */, const scene *s);

typedef struct photon_stats {
    uint64_t frames;                /* photon_step calls since the last reset */
    uint64_t photons;               /* photons emitted by photon_step */
    uint64_t traced;                /* rays cast (all bounces) */
    double emitted;                 /* lm emitted (sum of photon fluxes before W) */
    double first;                   /* lm arriving at first hits, W applied */
    double arrived;                 /* lm arriving at 2nd and later hits */
    double stored_chart;            /* lm splatted into facade charts (levels 0-3) */
    double stored_ambient;          /* lm counted in level-4 blocks' ambient terms */
    double stored_aerial;           /* lm splatted into the aerial chart A */
    double stored_covered;          /* lm splatted into the covered-ground layer A_cov */
    double skipped_refined;         /* lm of refined lamps' horizontal photons (kept in I) */
    double lost;                    /* lm arriving where there is no chart */
    double escaped;                 /* lm leaving to the sky after a bounce */
    double absorbed;                /* lm ended by Russian roulette */
    double cut;                     /* lm ended by max_bounces */
    double arrived_rgb[3];          /* RGB flux arriving at 2nd and later hits */
    double stored_rgb[3];           /* RGB flux stored by the progressive pass: facade
                                       charts, ambient terms, A and A_cov */
    uint64_t lamp_hits, lamp_misses, lamp_evictions, lamp_refined;
    uint64_t aerial_restarts;
} photon_stats;

typedef struct photon_level {
    uint32_t w, h;                  /* chart texels */
    uint32_t nslots;
    float *flux;                    /* nslots * 2 charts * w * h * PHOTON_CH: accumulated lm */
    float *area;                    /* nslots * 2 charts * w * h: world area of each texel, m^2 */
    uint32_t *slot_block;           /* block in each slot or PHOTON_NONE */
    uint32_t *slot_frames;          /* frames the slot has received */
    uint32_t *free_slots;           /* stack of free slot indices */
    uint32_t nfree;
} photon_level;

typedef struct photon_lamp_slot {
    uint32_t lamp;                  /* PHOTON_NONE when empty */
    uint32_t prev, next;            /* LRU list, most recent first */
    double x0, y0, texel;           /* floor map origin (min corner) and texel size */
    int32_t dx0, dy0;               /* D window origin in aerial texels */
    float *flux;                    /* lamp_res^2 * PHOTON_CH */
    float *area, *height;           /* lamp_res^2 each */
    float *dwin;                    /* D_i: dwin_n^2 aerial texels * PHOTON_CH */
} photon_lamp_slot;

typedef struct photon_sys {
    arena *a;
    const scene *s;
    photon_config cfg;
    tracer *T;
    /* walls (per scene point = edge start) */
    uint8_t *eclass;                /* PHOTON_EDGE_* */
    float *ez0, *ez1;               /* exposed height range */
    /* blocks */
    uint8_t *blevel;                /* 0..4 */
    uint32_t *bslot;                /* slot in its level or PHOTON_NONE */
    double *bcx, *bcy, *bhmax;      /* chart centre and height */
    double *bfacade;                /* exposed facade area, m^2 */
    double *bamb;                   /* facade flux accumulated, lm, PHOTON_CH per block
                                       (ambient term) */
    double mean_diam;               /* b */
    uint32_t amb_frames;
    photon_level lev[PHOTON_LEVELS];
    uint32_t level_count[PHOTON_LEVELS + 1];
    /* aerial chart */
    uint32_t gw, gh;
    double gx0, gy0, gtex;
    float *gheight, *garea;         /* a texel's surface key (surface_key.h) and area */
    surface_keys keys;              /* the courtyards (surface_key.h) */
    float *gflux;                   /* A: progressive, unrefined lamps; PHOTON_CH per texel */
    float *gimp;                    /* I: refined lamps, one computation each; same */
    uint32_t gframes;
    /* covered ground (under raised buildings): sparse layer on the aerial grid */
    uint32_t *gcov;                 /* per aerial texel: slot or PHOTON_NONE; NULL when
                                       the scene has no raised building */
    uint32_t ncov, cov_cap;         /* slots used, slots allocated */
    float *cov_area;                /* per slot: covered ground area, m^2 */
    float *cov_flux;                /* A_cov: PHOTON_CH per slot */
    float *cov_imp;                 /* I_cov: PHOTON_CH per slot */
    /* lamps */
    double *lamp_cdf;               /* cumulative flux, nlamps */
    double flux_total;
    uint8_t *refined;
    uint32_t *lamp_slot;            /* per lamp: cache slot or PHOTON_NONE */
    photon_lamp_slot *slots;
    uint32_t nslots, lru_head, lru_tail;
    uint32_t dwin_n;                /* D window side, aerial texels */
    double eye[3];
    photon_stats st;
} photon_sys;

enum { PHOTON_EDGE_INTERNAL = 0, PHOTON_EDGE_OUTER = 1, PHOTON_EDGE_INNER = 2 };

/*
 * Creates the photon system for scene s, which must have its blocks
 * (scene.nblocks > 0 when it has buildings; blocks_build) and must not
 * change while the system lives. cfg NULL = defaults. Levels are first set
 * for a viewer at the centre of Bounds, 1.7 m above the ground.
 * Returns PLX_OK; PLX_E_INVALID (NULL argument, a config value out of
 * range: zero sizes, chart_w or chart_h below 8, kernel radii not in
 * (0, PHOTON_KERNEL_MAX], kernel_min > kernel_max, buildings without
 * blocks); PLX_E_NOMEM (the arena is back where it was).
 */
plx_status photon_create(arena *a, const scene *s, const photon_config *cfg,
                         photon_sys **out /* OUT */);

/* Bytes photon_create would take from part PLX_PART_PHOTON. */
size_t photon_bytes(const scene *s, const photon_config *cfg);

/*
 * Lowers the quality of c until photon_bytes(s, c) <= budget, step by step:
 * first the tracer's lamp tables go (the same light, slower), then in turn
 * the lamp cache is halved (down to two floor maps; it serves only
 * near-viewer refinement), the facade charts are halved each way (down to
 * PHOTON_FIT_CHART_H texels high at level 0) and the aerial chart is
 * halved each way (down to PHOTON_FIT_AERIAL texels along the longer
 * side). Returns the number of steps taken (0:
 * c already fits), or -1 when even the smallest sizes do not fit (c is
 * then at those sizes). The photon count is not touched: coarser charts
 * blur the indirect light, they do not make it noisier.
 */
#define PHOTON_FIT_CHART_H 8
#define PHOTON_FIT_AERIAL 64
int photon_config_fit(photon_config *c, const scene *s, size_t budget);

/* Bytes of one lamp cache slot (the unit of cfg.lamp_cache_bytes). */
size_t photon_lamp_slot_bytes(const scene *s, const photon_config *cfg);

/*
 * One progressive frame: n photons shared among the lamps in proportion to
 * their flux (stratified), each carrying (total flux) / n lm, traced and
 * splatted. Deterministic for (state, n, seed). Needs no memory.
 */
void photon_step(photon_sys *ps, uint32_t n, uint64_t seed);

/*
 * Levels for a viewer at eye looking along dir (unit; NULL = all around)
 * with a full cone angle fov_deg. Blocks whose level changes get a new
 * empty chart. Returns PLX_OK or PLX_E_NOMEM (scratch for sorting; levels
 * unchanged).
 */
plx_status photon_set_viewer(photon_sys *ps, const double eye[3], const double dir[3],
                             double fov_deg);

/* Level of block b (0..4). */
int photon_block_level(const photon_sys *ps, uint32_t b);

/* Drops every accumulated photon (charts, ambient, A, I, the lamp cache and
 * the refined marks); levels stay. For changed lamps. */
/* The lamps' photometry changed (plx_set_photometry): fluxes recomputed,
 * every photon dropped. */
/* A photon's first direction from lamp Lp: uniform on the sphere when
 * isotropic, else distributed as its I(omega) (rejection sampling against
 * the peak; Lp must have flux > 0). */
void photon_lamp_dir(const scene_lamp *Lp, uint64_t *rng, double d[3] /* OUT */);
void photon_lamps_changed(photon_sys *ps);
void photon_reset(photon_sys *ps);

/* ---- internal, shared by photon*.c ------------------------------------ */

/* Facade chart coordinates of (x, y, z) for block k at level lv. */
void photon_chart_xy(const photon_sys *ps, uint32_t k, const photon_level *lv, double x, double y,
                     double z, double *fx /* OUT */, double *fy /* OUT */);

/* The reach window W(x) = (clamp(1 - x^4, 0, 1))^2. */
double photon_window(double x);
/* Splats the PHOTON_CH weights phi at continuous texel coordinates
 * (fx, fy) of a w x h grid: cone of radius r (texels), texels valid when
 * area > 0 and, with height (surface keys) given, |height - z| <= 1 mm;
 * wrap: u periodic. flux holds PHOTON_CH floats per texel. Returns 1 when
 * deposited, 0 when no valid texel was near or, with height given, the
 * texel under (fx, fy) on the grid is not valid (another surface's):
 * nothing deposited. */
int photon_splat(float *flux, const float *area, const float *height, double z,
                 uint32_t w, uint32_t h, int wrap, double fx, double fy, double r,
                 const double phi[PHOTON_CH]);
/* Ratio lookup over the 2 x 2 texels around (fx, fy): e = sum w F / sum w A
 * per channel (0 when no valid texel). Returns e[0]. */
double photon_gather(const float *flux, const float *area, const float *height, double z,
                     uint32_t w, uint32_t h, int wrap, double fx, double fy,
                     double e[PHOTON_CH] /* OUT */);
/* The wide lookup: cone weights w = 1 - dist / r over the valid texels
 * (area > 0, height within 1 mm) within r texels of (fx, fy), e = sum w F /
 * sum w A; photon_gather when r <= 0 or no texel is valid. */
double photon_gather_wide(const float *flux, const float *area, const float *height, double z,
                          uint32_t w, uint32_t h, int wrap, double fx, double fy, double r,
                          double e[PHOTON_CH] /* OUT */);
/* The same on a sparse grid: grid texel k is stored in slot idx[k]
 * (PHOTON_NONE: not charted); flux and area are per slot; no height, no
 * wrap. */
int photon_splat_sparse(float *flux, const float *area, const uint32_t *idx, uint32_t w,
                        uint32_t h, double fx, double fy, double r, const double phi[PHOTON_CH]);
double photon_gather_sparse(const float *flux, const float *area, const uint32_t *idx,
                            uint32_t w, uint32_t h, double fx, double fy,
                            double e[PHOTON_CH] /* OUT */);
/* The same into a window of the grid: out holds ow x oh texels whose first
 * is texel (ox, oy) of the w x h grid (no wrap); validity comes from the
 * full grid's area and height. Parts falling outside the window are
 * dropped. */
int photon_splat_win(float *out, uint32_t ow, uint32_t oh, int32_t ox, int32_t oy,
                     const float *area, const float *height, double z, uint32_t w, uint32_t h,
                     double fx, double fy, double r, const double phi[PHOTON_CH]);
/* photon_gather with the flux taken from such a window (0 outside it). */
double photon_gather_win(const float *out, uint32_t ow, uint32_t oh, int32_t ox, int32_t oy,
                         const float *area, const float *height, double z, uint32_t w,
                         uint32_t h, double fx, double fy, double e[PHOTON_CH] /* OUT */);
/* Receives a photon arriving at h (second or later hit) with weights f. */
typedef void (*photon_store_fn)(photon_sys *ps, void *ctx, uint32_t lamp, const trace_hit *h,
                                const double f[PHOTON_CH]);
/* Traces one photon of flux phi (before W) from lamp: first hit, W, then
 * bounces, calling store at every later hit; counts into st. */
void photon_trace_lamp(photon_sys *ps, uint32_t lamp, double phi, uint64_t *rng,
                       photon_stats *st, photon_store_fn store, void *ctx);
/* The colour-blind albedo of an RGB albedo: its luminance (Rec. 709
 * weights), exactly the common value when the three are equal. */
double photon_albedo_scalar(const double rgb[3]);
/* One diffuse bounce's Russian roulette with uniform u in [0, 1): returns 0
 * (absorbed) when u >= p = photon_albedo_scalar(alb), else scales the RGB
 * weights f[1..3] by alb_c / p (f[0] is kept) and returns 1. */
int photon_bounce(double f[PHOTON_CH], const double alb[3], double u);
/* Whether (x, y) is ground under a raised building that the covered-ground
 * layer charts (its aerial texel has a slot and the point is covered). */
int photon_covered_at(const photon_sys *ps, double x, double y);
/* Random numbers (splitmix64 state). */
uint64_t photon_rand(uint64_t *st);
double photon_rand01(uint64_t *st);
/* cos and sin of 2 pi u, u in [0, 1), by a polynomial (no libm call;
 * within 2 ulps of libm). */
void photon_sincos_turn(double u, double *c /* OUT */, double *s /* OUT */);
/* Uniform direction on the unit sphere from two random numbers
 * (z = 1 - 2 u1, azimuth 2 pi u2). */
void photon_sphere_dir(uint64_t *st, double d[3] /* OUT */);
/* Cosine-weighted direction about unit n (radius sqrt u1, azimuth 2 pi u2). */
void photon_cosine_dir(uint64_t *st, const double n[3], double d[3] /* OUT */);
/* Aerial texel coordinates of (x, y). */
void photon_aerial_xy(const photon_sys *ps, double x, double y, double *fx, double *fy);


#endif
