/*
 * polarlux — exact night lighting of 2.5D cities on small machines.
 *
 * This header is the whole public API. Conventions:
 *  - Every call takes the engine first; there is no global state.
 *  - The caller gives the engine one block of memory at creation. Nothing is
 *    allocated after that: running out of the block returns PLX_E_NOMEM and
 *    names the part that asked; the engine stays usable.
 *  - Functions returning plx_status return PLX_OK (0) on success. On failure
 *    plx_last_error() holds one line saying what failed, where and why.
 *  - Out parameters are marked OUT.
 *
 * Each call below states three things:
 *  - Errors: the plx_status values it returns. Besides those listed, every
 *    call taking an engine returns PLX_E_INVALID for a NULL or destroyed
 *    engine (then plx_last_error says "invalid engine handle"), and every
 *    call that may take memory returns PLX_E_NOMEM when the block (or a
 *    part's budget) is short: the message names the part and the bytes, and
 *    the engine stays usable with what it held before.
 *  - Lifetime: how long what it returns stays valid. Unless said otherwise,
 *    pointers into the engine (ids, rings, arrays) stay valid until the next
 *    plx_load_geojson / plx_load_file or plx_engine_destroy, whichever comes
 *    first. Nothing the engine returns is ever freed by the caller.
 *  - Threads: "engine" means the call may change the engine (caches built on
 *    first need, result buffers, the error message): calls on one engine
 *    must not overlap; different engines may be used from different threads
 *    at the same time. "engine (reads)" means the call only reads the
 *    engine: any number may run at once on one engine while no "engine" call
 *    runs on it. "any" means the call touches no engine and no shared state.
 *    Loading reads the JSON text in place with the engine's own reader
 *    (no cJSON, no process-wide state): engines may load in several threads
 *    at once without a lock, and an application's own cJSON hooks are left
 *    as they are.
 */
#ifndef POLARLUX_H
#define POLARLUX_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PLX_VERSION_MAJOR 0
#define PLX_VERSION_MINOR 1
#define PLX_VERSION_PATCH 0
#define PLX_VERSION_STRING "0.1.0"

/* The library's own PLX_VERSION_STRING, as it was built: an application
 * (or a binding such as the Python package, which cannot read the macros)
 * compares it with the header it was compiled against. Lifetime: static.
 * Threads: any. */
const char *plx_version(void);

/* One error enum for the whole library. */
typedef enum plx_status {
    PLX_OK = 0,
    PLX_E_INVALID,   /* bad argument or misuse of the API */
    PLX_E_NOMEM,     /* the engine's memory block (or a part's budget) is exhausted */
    PLX_E_IO,        /* a file could not be read or written */
    PLX_E_PARSE,     /* malformed JSON (message gives byte offset, line, column), or a damaged
                        or foreign bake file (the message says which) */
    PLX_E_SCENE,     /* the scene is not a valid polarlux GeoJSON profile */
    PLX_E_NOSCENE,   /* the call needs a loaded scene */
    PLX_E_RANGE,     /* a query point is outside Bounds, inside a building, ... */
    PLX_E_UNSUPPORTED, /* the port or build lacks the service asked for */
    PLX_STATUS_COUNT
} plx_status;

/* A short fixed description of a status code ("out of memory", ...);
 * "unknown status" outside the enum. Lifetime: static. Threads: any. */
const char *plx_strerror(plx_status s);

/* Parts of the engine's memory, for budgets and reports. */
typedef enum plx_part {
    PLX_PART_ENGINE = 0, /* the engine object itself */
    PLX_PART_SCENE,      /* buildings, rings, lamps, blocks */
    PLX_PART_POLAR,      /* polar diagrams */
    PLX_PART_LIT,        /* lamp lit regions */
    PLX_PART_PHOTON,     /* photon buffers */
    PLX_PART_FRAME,      /* frame buffers, query results */
    PLX_PART_SCRATCH,    /* temporary memory during a call (a loaded file's bytes, ...) */
    PLX_PART_COUNT
} plx_part;

/* "engine", "scene", ... ("unknown" outside the enum). Lifetime: static.
 * Threads: any. */
const char *plx_part_name(plx_part p);

/* Log levels passed to plx_port.log. */
typedef enum plx_log_level { PLX_LOG_ERROR = 0, PLX_LOG_WARN, PLX_LOG_INFO } plx_log_level;

/*
 * The platform services the core may ask for. Every member may be NULL:
 * the engine then has no clock (times read 0), is silent, or cannot read
 * files (plx_load_file returns PLX_E_UNSUPPORTED). plx_port_posix() gives
 * the POSIX implementation.
 */
typedef struct plx_port {
    void *ctx;
    /* Monotonic time in nanoseconds. */
    uint64_t (*clock_ns)(void *ctx);
    /* One message line, without a trailing newline. */
    void (*log)(void *ctx, plx_log_level level, const char *msg);
    /* Size of a file in bytes; 0 on success, else -1 with a reason in err. */
    int (*file_size)(void *ctx, const char *path, size_t *size, char *err, size_t errlen);
    /* Read exactly 'size' bytes of the file into buf; 0 on success. */
    int (*file_read)(void *ctx, const char *path, void *buf, size_t size, char *err, size_t errlen);
    /* A process-wide lock. No longer taken by the core (loads touch no
     * process-wide state since the streaming loader); kept so existing port
     * tables still compile. */
    void (*lock)(void *ctx);
    void (*unlock)(void *ctx);
    /* A parallel-for (NULL: everything runs on the calling thread): calls
     * job(arg, worker, k) once for each k = 0 .. njobs-1 on up to 'workers'
     * threads (worker in 0 .. workers-1 names the thread; the calls of one
     * worker come one after another; the calling thread may be one of
     * them) and returns when all are done, in any order. Returns 0, or -1
     * when it ran no job (the core then runs them itself). */
    int (*parallel_for)(void *ctx, int workers, uint32_t njobs,
                        void (*job)(void *arg, int worker, uint32_t k), void *arg);
    /* The number of processors: the default number of workers (NULL: 1). */
    int (*cores)(void *ctx);
    /* A read-only view of a whole file, for plx_load_file (NULL: the file
     * is read with file_size/file_read into the engine's block instead).
     * Gives *data (size bytes, no NUL after them: *data may be NULL when
     * size is 0) valid until file_unmap(ctx, *handle); 0 on success, else -1
     * with a reason in err and nothing to unmap. The bytes must not change
     * while mapped. POSIX: mmap of a regular file (a FIFO, a device or a
     * directory is refused at once, as file_size does; a file truncated by
     * another process during the load makes the process take SIGBUS). A
     * board maps the file where it lies, e.g. memory-mapped (XIP) flash.
     * Added after cores so port tables written before keep their layout. */
    int (*file_map)(void *ctx, const char *path, const void **data, size_t *size, void **handle,
                    char *err, size_t errlen);
    /* Ends a view file_map gave (called once for each successful map). */
    void (*file_unmap)(void *ctx, void *handle);
    /* Progress of long work, for a progress line (NULL: none). Before a
     * stage the calling thread calls progress(ctx, what, 0, total); while
     * it runs, any worker of parallel_for calls progress(ctx, what, n,
     * total) for n more units done (n >= 1: the port sums them, so it
     * must be thread-safe); after it, the calling thread calls
     * progress(ctx, what, 0, 0). 'what' names the stage (today "aerial
     * indirect layer", in rows of the light map: the bulk of a bake).
     * Added after file_unmap so port tables written before keep their
     * layout. */
    void (*progress)(void *ctx, const char *what, uint64_t n, uint64_t total);
} plx_port;

/* Most workers the core asks a parallel-for for. */
#define PLX_MAX_THREADS 16

/* The radiance atlas (plx_atlas_info_get): its spacing when none is asked
 * (aerial_m_per_texel 0), in m, and its most bytes when
 * plx_config.lightmap_bytes is 0 (a quarter of the block, at most this). */
#define PLX_ATLAS_SPACING_DEFAULT 0.5
#define PLX_ATLAS_MAX_BYTES ((size_t)64 << 20)

typedef struct plx_config {
    const plx_port *port;             /* NULL: no platform services */
    int strict;                       /* 1: the first bad feature fails the load */
    size_t part_budget[PLX_PART_COUNT]; /* per-part byte limits, 0 = only the block limits */
    size_t lit_cache_bytes;           /* pool for lamp lit regions (0: from the budget, an eighth of
                                         the free bytes at first use, 256 KiB to 16 MiB) */
    int32_t render_max_width;         /* largest frame plx_render draws (0: 1920; at most
                                         PLX_RENDER_MAX_DIM, plx_engine_create refuses more),
                                         either way round: it draws height x width frames too
                                         (an OSMesa context, plx_osmesa_open, only its own way) */
    int32_t render_max_height;        /* (0: 1080) */
    size_t lightmap_bytes;            /* the light maps' budget: the radiance atlas's (4 bytes a
                                         sample point, its spacing grows from the one asked for until
                                         it fits; 0: a quarter of the block, at most 64 MiB) and the
                                         aerial light map's of frames without the atlas (12 bytes a
                                         texel, 28 with its indirect layer; 0: half the free bytes
                                         when the map is built, at most 48 MiB) */
    size_t photon_bytes;              /* the photon buffers' budget (0: from the budget, half the free
                                         bytes when they are first needed); their quality is lowered
                                         step by step until they fit (plx_indirect_info_get) */
    int threads;                      /* workers of a frame's shading (port.parallel_for): 0 = the
                                         port's cores, 1 = the calling thread only, at most
                                         PLX_MAX_THREADS; the results are the same bytes for any */
} plx_config;

/* Fills cfg with the defaults: no port, lenient loading, no part limits
 * (NULL: nothing). Threads: any. */
void plx_config_default(plx_config *cfg);

typedef struct plx_engine plx_engine;

/* Minimum size of the block given to plx_engine_create. */
#define PLX_ENGINE_MIN_BYTES 4096
/* The block is used from its first 16-byte aligned address. */
#define PLX_ENGINE_ALIGN 16

/*
 * Creates an engine inside the caller's block 'mem' of 'size' bytes. The
 * engine object itself lives in the block; the caller keeps ownership and
 * frees it after plx_engine_destroy. cfg (may be NULL: the defaults) and
 * its port table are copied; the port's ctx must outlive the engine.
 * plx_memory_estimate says what size a scene needs.
 * Errors: PLX_E_INVALID (mem or engine NULL, size < PLX_ENGINE_MIN_BYTES,
 * cfg's render_max_width or _height outside 0..PLX_RENDER_MAX_DIM, or
 * threads outside 0..PLX_MAX_THREADS),
 * PLX_E_NOMEM (the block cannot hold the engine object after alignment).
 * Lifetime: *engine is valid until plx_engine_destroy. Threads: any (it
 * touches only the block).
 */
plx_status plx_engine_create(void *mem, size_t size, const plx_config *cfg,
                             plx_engine **engine /* OUT */);
/* Ends the engine; the block may then be reused or freed by the caller.
 * Every pointer the engine gave out dies with it; a later call with the
 * handle returns PLX_E_INVALID (as long as the block is not reused). NULL
 * or a destroyed handle: no-op. Threads: engine. */
void plx_engine_destroy(plx_engine *e);
/* The block the engine was created in (the 'mem' given to plx_engine_create);
 * NULL for an invalid handle. Threads: engine (reads). */
void *plx_engine_block(const plx_engine *e);

/* The message of the last failing call of this engine. Loads, visibility,
 * illuminance, routes, renders and plx_set_ground_image clear it ("") when
 * they succeed; the getters leave it as it was. Never NULL ("invalid engine
 * handle" for a bad handle). Lifetime: the text lives in the engine and
 * changes with the next call that fails or clears it. Threads: engine (reads). */
const char *plx_last_error(const plx_engine *e);

/* Number of warnings (skipped features, ignored properties) of the last load
 * (0 for an invalid handle). Threads: engine (reads). */
uint32_t plx_warning_count(const plx_engine *e);

/*
 * Loads a scene from GeoJSON text (not necessarily NUL-terminated). 'name'
 * (may be NULL) prefixes messages. The previous scene and everything derived
 * from it are dropped first. On failure no scene is loaded and all memory the
 * load took is given back. Bad features are skipped with a warning through
 * the port's log (or fail the load with plx_config.strict).
 * Errors: PLX_E_INVALID (text NULL with len > 0), PLX_E_PARSE (malformed
 * JSON, or nested deeper than 1000 levels: byte offset, line and column in
 * the message), PLX_E_SCENE (not a FeatureCollection, unknown units, a bad
 * feature with strict), PLX_E_NOMEM (the scene does not fit: the text is
 * read in place, one feature at a time, with 8 bytes a feature of scratch).
 * Lifetime: text and name are not kept (ids are copied); everything
 * derived from the previous scene (polar diagrams, lamp light, renderer,
 * photons, ground image, pointers from every getter) is dropped at entry,
 * even when the load fails. Threads: engine (no process-wide state).
 */
plx_status plx_load_geojson(plx_engine *e, const char *text, size_t len, const char *name);
/* The same from a file, through the engine's port: read in place from the
 * port's file_map view when it has one (the file's bytes are not in the
 * block; the view is ended before returning, on success and failure), else
 * read with file_size/file_read into scratch memory (the file's bytes then
 * count against the block during the load).
 * Errors: those of plx_load_geojson, and PLX_E_INVALID (path NULL),
 * PLX_E_UNSUPPORTED (the port has neither file_map nor
 * file_size/file_read), PLX_E_IO (the port could not map or read it: the
 * message names the path and why). */
plx_status plx_load_file(plx_engine *e, const char *path);

typedef struct plx_scene_info {
    uint32_t buildings;       /* loaded buildings (raised ones included) */
    uint32_t raised;          /* buildings with min_height > 0 */
    uint32_t blocks;          /* connected groups of touching buildings */
    uint32_t courtyards;      /* courtyard rings of all blocks */
    uint32_t holes;           /* inner rings of the buildings themselves */
    uint32_t lamps;           /* loaded lamps */
    uint32_t vertices;        /* footprint vertices after cleaning */
    uint32_t skipped_features;/* bad features left out */
    uint32_t skipped_lamps;   /* lamps left out (inside a building, ...) */
    uint32_t overlapping_pairs; /* pairs of footprints whose interiors overlap */
    int lonlat;               /* 1 when coordinates were WGS84 and projected */
    double lon0, lat0;        /* projection centre when lonlat */
    double bounds[4];         /* minx, miny, maxx, maxy (building box + 50 m) */
    double height_min, height_median, height_max;
    double ground_albedo;
    uint64_t load_ns;         /* time the load took, by the port's clock */
    uint32_t merged_lamps;    /* lamps merged into another at the same spot (README "Duplicate lamps") */
} plx_scene_info;

/* Errors: PLX_E_NOSCENE, PLX_E_INVALID (out NULL). Allocates nothing.
 * Threads: engine (reads). */
plx_status plx_scene_info_get(plx_engine *e, plx_scene_info *out /* OUT */);

/* The scene's coordinate reference system as its file named it (a GeoJSON
 * 2008 top-level "crs": {"type": "name", "properties": {"name": ...}}, or
 * properties.crs as that object or a string), e.g.
 * "urn:ogc:def:crs:EPSG::2154"; NULL when it named none (or no scene). A
 * CRS other than WGS84 lon/lat (EPSG:4326, OGC CRS84) makes the load read
 * coordinates as metres, as properties.units = "m" does. Valid until the
 * next load. Threads: engine (reads). */
const char *plx_scene_crs(plx_engine *e);

/* ---- Ground albedo from a day image (README "Scene format") ------------- */

/*
 * The scene may name a day orthophoto (properties.ground_image, a PNG path
 * relative to the scene file) and where it lies (properties.ground_image_bounds
 * [x0, y0, x1, y1] in the scene's coordinates, else the Bounds box; top row
 * north). The core reads no files: the caller decodes the image and gives
 * its pixels here (the polarlux command does this for every scene it loads).
 *
 * Per pixel, each channel is decoded from sRGB to linear and scaled so the
 * image's mean linear luminance (0.2126 R + 0.7152 G + 0.0722 B) equals the
 * scene's ground albedo, then clamped to [0, 0.95]. The ground takes the
 * albedo of the nearest pixel inside the image's box and the constant
 * ground albedo outside it; images and photon bounces use it.
 *
 * rgb8: width*height pixels of 3 bytes (sRGB), top row first; copied into
 * the engine (part PLX_PART_SCENE, w*h*3 bytes + about 2.2 KB). bounds: the
 * box in local metres, or NULL for the scene's (see plx_ground_image_get).
 * Calling it again replaces the image (in the same memory when the new one
 * is not larger; otherwise the old memory stays held until the next load).
 * (0, 0, NULL, NULL) removes the image. Photons already traced used the old
 * ground: they are dropped (as plx_indirect_reset); renders need nothing
 * rebuilt. Loading a scene drops the image.
 * Errors: PLX_E_NOSCENE; PLX_E_INVALID (sizes outside 1..16384, rgb8 NULL,
 * bounds not finite and increasing, a black image); PLX_E_NOMEM (the old
 * image stays). Lifetime: rgb8 is not kept. Threads: engine.
 */
plx_status plx_set_ground_image(plx_engine *e, uint32_t width, uint32_t height, const uint8_t *rgb8,
                                const double bounds[4]);

typedef struct plx_ground_image_info {
    const char *path;         /* properties.ground_image as written, or NULL */
    int bounds_given;         /* properties.ground_image_bounds was given */
    double bounds[4];         /* x0, y0, x1, y1, local metres: the image's, else where the scene puts it */
    uint32_t width, height;   /* 0 until plx_set_ground_image */
    double mean_albedo[3];    /* mean albedo over the pixels (the constant without image) */
    double mean_luminance;    /* its luminance (the ground albedo unless pixels were clamped) */
} plx_ground_image_info;

/* Errors: PLX_E_NOSCENE, PLX_E_INVALID (out NULL). Lifetime: path points
 * into the scene (until the next load). Threads: engine (reads). */
plx_status plx_ground_image_get(plx_engine *e, plx_ground_image_info *out /* OUT */);

/* The ground's albedo per channel at (x, y) (local metres).
 * Errors: PLX_E_NOSCENE, PLX_E_INVALID (x or y not finite, rgb NULL).
 * Threads: engine (reads). */
plx_status plx_ground_albedo_at(plx_engine *e, double x, double y, double rgb[3] /* OUT */);

typedef struct plx_building {
    uint32_t nrings;           /* 1 outer ring + holes; see plx_building_ring */
    double height, min_height, albedo;
    double box[4];             /* minx, miny, maxx, maxy of the footprint */
    uint32_t feature;          /* index of the feature in the collection */
    uint32_t block;            /* index of its block */
    const char *id;            /* properties.id / @id / osm_id / feature id, or NULL */
} plx_building;

typedef struct plx_lamp {
    double x, y, z, intensity, radius;
    float color[3];
    uint32_t feature;
    const char *id;
} plx_lamp;

/*
 * Adds n lamps to the loaded scene: lamp layers from other files (the
 * polarlux command's --lamps). Positions are in the scene's own
 * coordinates: lon/lat degrees (x = lon, y = lat) on a lon/lat scene,
 * projected with the scene's centre as at load; metres on a metre scene.
 * z, intensity, radius and color as in the scene format (no defaults are
 * applied here); 'feature' is the lamp's record number in its source (for
 * messages) and 'id' is copied (may be NULL). 'source' (may be NULL) names
 * the file in messages. As at load: a lamp out of range, or inside a
 * building's solid, is left out with a warning (strict: the call fails and
 * no lamp is added); a lamp within 1 mm on the ground of an earlier lamp is
 * merged into it (the earlier kept) with a warning. A scene without
 * buildings takes its Bounds from all lamps. Must come before anything
 * computes light (illuminance, lit regions, photons, renders): PLX_E_INVALID
 * after. Memory: a new lamp array in PLX_PART_SCENE (the old one stays held
 * until the next load). Errors: PLX_E_NOSCENE, PLX_E_INVALID, PLX_E_SCENE
 * (strict), PLX_E_NOMEM (no lamp added). Threads: engine. plx_memory_estimate
 * counts only the scene's own lamps: add the layer's to sz.points and
 * sz.positions.
 */
plx_status plx_add_lamps(plx_engine *e, const plx_lamp *lamps, uint32_t n, const char *source);

typedef struct plx_block {
    uint32_t nbuildings;
    const uint32_t *buildings; /* building indices */
    uint32_t nrings;           /* outer boundary, courtyards, extra parts; see plx_block_ring */
    double box[4];
} plx_block;

/* Building, lamp and block i. Errors: PLX_E_NOSCENE, PLX_E_RANGE (i not
 * below the count of plx_scene_info), PLX_E_INVALID (out NULL). Lifetime:
 * id and buildings point into the scene (until the next load). Allocate
 * nothing. Threads: engine (reads) for valid arguments (an error writes the
 * message). */
plx_status plx_building_get(plx_engine *e, uint32_t i, plx_building *out /* OUT */);
plx_status plx_lamp_get(plx_engine *e, uint32_t i, plx_lamp *out /* OUT */);
plx_status plx_block_get(plx_engine *e, uint32_t i, plx_block *out /* OUT */);
/* Ring r of building i: n vertices as x,y pairs in local metres, no closing
 * vertex; ring 0 is the outer ring (counter-clockwise), the rest holes
 * (clockwise). Errors: PLX_E_NOSCENE, PLX_E_RANGE (i or r out of range),
 * PLX_E_INVALID (xy or n NULL). Lifetime: *xy points into the scene (until
 * the next load). Threads: as plx_building_get. */
plx_status plx_building_ring(plx_engine *e, uint32_t i, uint32_t r,
                             const double **xy /* OUT */, uint32_t *n /* OUT */);
/* Ring r of block i: ring 0 the outer boundary of the union of its
 * footprints (counter-clockwise, the largest), then its courtyards
 * (clockwise), then any further counter-clockwise rings (parts of the union
 * joined to the rest only at a point). See src/scene/blocks.h for the rules.
 * Errors, lifetime and threads as plx_building_ring. */
plx_status plx_block_ring(plx_engine *e, uint32_t i, uint32_t r,
                          const double **xy /* OUT */, uint32_t *n /* OUT */);

typedef struct plx_memory_report {
    size_t capacity;                 /* usable bytes of the block */
    size_t used[PLX_PART_COUNT];     /* bytes held now, by part */
    size_t peak[PLX_PART_COUNT];     /* high-water mark, by part */
    size_t used_total, peak_total;   /* all parts together */
} plx_memory_report;

/* All zero for an invalid handle; out NULL: nothing. Threads: engine (reads). */
void plx_memory_get(const plx_engine *e, plx_memory_report *out /* OUT */);

/*
 * Fault injection for tests: the k-th memory request from now on (k >= 1)
 * fails as if the block were exhausted; k = 0 switches it off. Returns the
 * number of memory requests served since the last call (0 for an invalid
 * handle). Threads: engine.
 */
uint64_t plx_debug_fail_alloc(plx_engine *e, uint64_t k);

/* ---- Polar diagrams and planar visibility (SPEC §3) -------------------- */

/*
 * Builds the four quadrant polar diagrams of the loaded scene (part
 * PLX_PART_POLAR) and the query result buffers (PLX_PART_FRAME). Queries
 * build them on first need; calling this first puts the cost up front.
 * Built once per scene: later calls return at once.
 * Errors: PLX_E_NOSCENE, PLX_E_NOMEM (nothing kept), PLX_E_INVALID
 * (non-finite Bounds), PLX_E_SCENE (the construction's own cross-checks of
 * its two maps disagree: a bug to report, not an input error).
 * Threads: engine.
 */
plx_status plx_polar_build(plx_engine *e);

typedef struct plx_polar_info {
    uint64_t build_ns;        /* construction time by the port's clock */
    size_t axes, regions, polygons, rest; /* bytes by part (robles2014 Table 3); rest:
                               * the point-location search DAGs, headers */
    size_t total;
    uint32_t nregions[4];     /* regions of quadrant diagrams 0..3 */
    uint32_t vertices;        /* footprint vertices of the occluders */
} plx_polar_info;

/* Builds the diagrams if needed, then describes them. Errors: those of
 * plx_polar_build, PLX_E_INVALID (out NULL). Threads: engine. */
plx_status plx_polar_info_get(plx_engine *e, plx_polar_info *out /* OUT */);

/*
 * Region i of quadrant diagram q (0: scan from east, 1: north, 2: west,
 * 3: south): up to 4 corners (x,y pairs, counter-clockwise) in xy, their count
 * in *n, the region's label in *owner (the object angularly first from the
 * region's points: a building, or -1 for the Bounds frame, which encloses
 * the scene and is met first where the start ray reaches the box) and
 * whether the region is inside a footprint in *solid.
 * Errors: those of plx_polar_build; PLX_E_INVALID (q outside 0..3, an
 * output NULL); PLX_E_RANGE (i not below the region count). Threads: engine
 * (they build the diagrams on first need; once built, engine (reads)).
 */
plx_status plx_polar_region_count(plx_engine *e, int q, uint32_t *count /* OUT */);
plx_status plx_polar_region(plx_engine *e, int q, uint32_t i, double xy[8] /* OUT */,
                            uint32_t *n /* OUT */, int32_t *owner /* OUT */, int *solid /* OUT */);

typedef struct plx_visibility {
    double area;              /* m^2, within Bounds (SPEC §3) */
    uint32_t nverts;          /* vertices of the visibility polygon */
    const double *xy;         /* its vertices, x,y pairs, counter-clockwise */
    uint32_t nvisible;        /* visible buildings */
    const uint32_t *visible;  /* their indices, ascending */
} plx_visibility;

/*
 * The exact visibility polygon and visible set of the free point (x, y),
 * buildings infinitely tall, over the directions dir_deg ± fov_deg/2
 * (degrees counter-clockwise from +x, east); fov_deg >= 360 is the full turn.
 * Builds the polar diagrams on first need.
 * Errors: PLX_E_RANGE when the point is outside Bounds, on a wall or inside a
 * footprint (the message says which building); PLX_E_INVALID for non-finite
 * input, fov_deg <= 0 or out NULL; PLX_E_NOSCENE; PLX_E_NOMEM.
 * Lifetime: out->xy and out->visible point into engine buffers that the
 * next plx_visibility_get overwrites; a load drops them.
 * Threads: engine (the result buffers are the engine's).
 */
plx_status plx_visibility_get(plx_engine *e, double x, double y, double dir_deg, double fov_deg,
                              plx_visibility *out /* OUT */);

/* ---- Lamp light (SPEC §2) -------------------------------------------------- */

/*
 * Direct illuminance E (lux) at n points P[3k..3k+2] with unit normals
 * N[3k..3k+2] (SPEC §2, exact 2.5D visibility): light meters anywhere, on a
 * surface or in free air, any unit normal. E_indirect gets the photon-buffer
 * estimate (0 until indirect light is computed; may be NULL): at a surface
 * point facing out the buffers' value there, at any other point the value
 * on the horizontal surface straight below it (the topmost roof under the
 * point, else the ground). rgb (may be NULL) gets 3 values per point: each
 * lamp's term weighted by its colour. A point strictly inside a building's
 * solid (or below the ground) gets NaN, and the call returns PLX_E_RANGE
 * naming the first such point; the others are filled.
 * Lamp lit regions are computed on first need and cached (part
 * PLX_PART_LIT, pool size from plx_config.lit_cache_bytes).
 * Errors: PLX_E_NOSCENE; PLX_E_INVALID (P, N or E_direct NULL with n > 0);
 * PLX_E_RANGE (some point strictly inside a solid or below the ground,
 * non-finite, or a normal not of unit length within 1e-6: the others are
 * still filled); PLX_E_NOMEM
 * (setting up lamp light). Lifetime: nothing kept from the arrays. Threads:
 * engine (the lit-region cache changes; may evict the polygons of
 * plx_lit_ground / plx_lit_facade).
 */
plx_status plx_illuminance(plx_engine *e, size_t n, const double *P, const double *N,
                           double *E_direct /* OUT */, double *E_indirect /* OUT */,
                           double *rgb /* OUT */);

/*
 * Indirect light at n surface points, as images use it (SPEC §4, §5): rgb
 * gets 3 values per point, the photon-buffer E_indirect with each lamp's
 * light weighted by its colour (equal to E_indirect for white lamps); the
 * colour-blind E_indirect (lux, as plx_illuminance reports it) goes to
 * E_indirect (may be NULL). 0 until indirect light is computed. Same
 * checks as plx_illuminance (NaN and PLX_E_RANGE for points strictly
 * inside a solid; free points get the estimate from the surface below);
 * PLX_E_INVALID when P, N or rgb is NULL with n > 0;
 * PLX_E_NOSCENE; PLX_E_NOMEM (setting up lamp light). Threads: engine.
 */
plx_status plx_indirect_rgb(plx_engine *e, size_t n, const double *P, const double *N,
                            double *E_indirect /* OUT */, double *rgb /* OUT */);

/* Is P (normal n) lit, and by which lamps: up to cap lamp indices and their
 * terms in lux, in lamp order; *count gets the number of lamps lighting P
 * (which may exceed cap). Same checks as plx_illuminance (PLX_E_RANGE for a
 * point strictly inside a solid); PLX_E_INVALID (P, n or count NULL, or ids/lux
 * NULL with cap > 0); PLX_E_NOSCENE; PLX_E_NOMEM. Threads: engine. */
plx_status plx_lamps_at(plx_engine *e, const double P[3], const double n[3], uint32_t *ids /* OUT */,
                        double *lux /* OUT */, uint32_t cap, uint32_t *count /* OUT */);

/* For n points P[3k..3k+2]: count[k] gets the number of lamps whose light
 * can reach the point (intensity > 0 and distance below the lamp's radius),
 * shadows aside. Uses the lamps' spatial index: the cost per point grows
 * with the lamps in reach, not with all lamps. Errors: PLX_E_NOSCENE,
 * PLX_E_INVALID (NULL arrays), PLX_E_NOMEM (setting up lamp light). */
plx_status plx_lamps_in_reach(plx_engine *e, size_t n, const double *P, uint32_t *count /* OUT */);

typedef struct plx_lit_region {
    uint32_t lamp;
    uint32_t nground;             /* lit ground polygons (z = 0) */
    uint32_t nfacade;             /* lit facade polygons (on wall planes) */
} plx_lit_region;

/*
 * The lit region of a lamp within its reach. The polygons are read with
 * plx_lit_ground / plx_lit_facade and stay valid until the next call that
 * computes light (plx_illuminance, plx_indirect_rgb, plx_lamps_at,
 * plx_route_score, plx_render, another plx_lit_region_get: any may evict it
 * from the cache) or a load.
 * Errors: PLX_E_NOSCENE; PLX_E_INVALID (out NULL); PLX_E_RANGE (no such
 * lamp); PLX_E_NOMEM (the region does not fit the lit cache: raise
 * plx_config.lit_cache_bytes); PLX_E_UNSUPPORTED (the lamp's reach crosses
 * more than 64 building intervals along some direction: no polygons, light
 * unaffected). Threads: engine.
 */
plx_status plx_lit_region_get(plx_engine *e, uint32_t lamp, plx_lit_region *out /* OUT */);
/* Ground polygon k of the last plx_lit_region_get: n vertices, x,y pairs.
 * Errors: PLX_E_RANGE (no region got yet, k out of range, an output NULL).
 * Lifetime: as the region (see above). Threads: engine (reads). */
plx_status plx_lit_ground(plx_engine *e, uint32_t k, const double **xy /* OUT */, uint32_t *n /* OUT */);
/* Facade polygon k: n vertices, x,y,z triples, on the wall of building
 * *bld. Errors, lifetime and threads as plx_lit_ground. */
plx_status plx_lit_facade(plx_engine *e, uint32_t k, const double **xyz /* OUT */, uint32_t *n /* OUT */,
                          uint32_t *bld /* OUT */);

/* ---- Indirect light (SPEC §4, photon buffers) ------------------------------ */

/*
 * One progressive frame of the photon pass: 'photons' photons shared among
 * the lamps by flux, traced with diffuse bounces and splatted into the
 * photon buffers (part PLX_PART_PHOTON, created on first need). After one or
 * more frames plx_illuminance fills E_indirect and plx_render adds indirect
 * light. Deterministic for (frames so far, photons, seed).
 * Errors: PLX_E_NOSCENE, PLX_E_INVALID (photons == 0), PLX_E_NOMEM (the
 * buffers are about 40 MiB with the defaults; plx_memory_estimate leaves
 * them out). Threads: engine.
 */
plx_status plx_indirect_step(plx_engine *e, uint32_t photons, uint64_t seed);
/* Frames accumulated so far (0 before the first step or after a reset, or
 * for an invalid handle). Threads: engine (reads). */
uint64_t plx_indirect_frames(const plx_engine *e);
/* Photons emitted by those frames, all frames together (0 as above).
 * Threads: engine (reads). */
uint64_t plx_indirect_photons(const plx_engine *e);
/* Chart resolution levels for a viewer at eye looking along dir (any
 * length, made unit here, or NULL for all around) with a full cone of fov_deg (argudo2012 §3.6; a
 * fov_deg <= 0 or >= 360 is all around too); blocks whose level changes
 * start again. Errors: PLX_E_NOSCENE, PLX_E_INVALID (eye NULL or not
 * finite, dir not finite or zero, fov_deg not finite), PLX_E_NOMEM. Creates the photon buffers on first need.
 * Threads: engine. */
plx_status plx_indirect_set_viewer(plx_engine *e, const double eye[3], const double dir[3], double fov_deg);
/* The sizes the photon buffers were given (README "Memory budgets"). */
typedef struct plx_indirect_info {
    size_t bytes;               /* held by the photon buffers (part PLX_PART_PHOTON) */
    size_t full_bytes;          /* what the default quality would take */
    size_t budget;              /* the budget they were fitted to */
    uint32_t reductions;        /* quality steps taken to fit (0: the default quality) */
    int lamp_tables;            /* 1: the ray caster keeps per-lamp tables (0: same light, slower) */
    uint32_t chart_w, chart_h;  /* facade chart texels at the finest level (default 256 x 32) */
    uint32_t aerial_w, aerial_h; /* ground and roof chart texels */
    double aerial_texel;        /* its texel side, m */
    uint32_t lamp_slots;        /* floor maps the near-viewer cache holds */
} plx_indirect_info;

/* Fills out once the photon buffers exist. Errors: PLX_E_INVALID (out
 * NULL), PLX_E_NOSCENE (no photon buffers yet). Threads: engine (reads). */
plx_status plx_indirect_info_get(plx_engine *e, plx_indirect_info *out /* OUT */);

/* Drops every accumulated photon (none yet: nothing to do). Errors: only
 * the invalid handle. Threads: engine. */
plx_status plx_indirect_reset(plx_engine *e);
/*
 * How plx_illuminance and plx_indirect_rgb (and so routes) estimate
 * E_indirect at points: final gathering over side x side stratified
 * cosine-weighted directions (default 32: 1024 directions), each gathering
 * a (E_direct + E_photons) from the first surface it meets, E_direct exact,
 * the photon buffers only for light that bounced before (README,
 * "Indirect light"); side 0: the photon buffers' own estimate at the point
 * (the older method). Images always read the photon buffers. Errors:
 * PLX_E_INVALID (side > 1024). Threads: engine.
 */
plx_status plx_indirect_set_gather(plx_engine *e, uint32_t side);
/*
 * Photons only from the lamps that can matter for a region: the lamps
 * whose reach comes within margin metres of box (x0, y0, x1, y1, local
 * metres); box NULL: every lamp. Drops the accumulated photons; count (may
 * be NULL) gets the number of lamps chosen. `illum` chooses by the box of
 * its points with a margin of 100 m. Errors: PLX_E_NOSCENE, PLX_E_INVALID
 * (an empty box, a negative or non-finite margin), PLX_E_NOMEM.
 */
plx_status plx_indirect_select_lamps(plx_engine *e, const double box[4], double margin,
                                     uint32_t *count /* OUT */);

#define PLX_REFINE_LRU_MAX 64

typedef struct plx_refine_stats {
    uint32_t misses_now;        /* floor maps computed by this call */
    uint64_t hits, misses, evictions, refined; /* lamp cache totals since creation or reset */
    uint32_t slots;             /* cache capacity (lamps) */
    double near_radius;         /* lamps within this horizontal distance are refined, m */
    uint32_t cached;            /* lamps in the cache now ... */
    uint32_t lru[PLX_REFINE_LRU_MAX]; /* ... the first of them, most recently used first */
    double centre[3];           /* the point the lamps were chosen around: local metres (x, y; z 0) */
} plx_refine_stats;

/*
 * Near-viewer refinement (munoz2013 §3.3-3.4, README "Walking through a
 * city"): the lamps within near_radius of eye (horizontally), nearest
 * first, up to the cache capacity, get their own floor photon maps, kept
 * in an LRU cache; a lamp's map is pushed into the improved aerial map the
 * first time, and the progressive aerial chart then restarts without that
 * lamp: it holds nothing (every lamp's share of it is gone) until further
 * plx_indirect_step frames fill it again, so trace some before the next
 * frame (polarlux walk traces --refine-frames, 2 by default; a frame drawn
 * straight after a miss lacked about a third of its indirect light on the
 * 4x4 Eixample). Only a miss
 * changes the indirect light (the cached maps are summed in slot order,
 * which hits do not change): after a call of hits alone the frames'
 * radiance atlas and indirect map stay filled. out (may be NULL)
 * gets the cache's counters. Errors: PLX_E_NOSCENE (no photon buffers yet),
 * PLX_E_INVALID, PLX_E_NOMEM (scratch).
 */
plx_status plx_indirect_refine(plx_engine *e, const double eye[3], plx_refine_stats *out /* OUT */);

/*
 * Histogram matching of a day orthophoto to a night palette (munoz2013
 * §3.1): each channel of day (npx RGB8 pixels) is mapped so its histogram
 * follows night's (nnight pixels), leaving out night pixels darker than
 * dark_threshold (luminance 0..255). out may be day. Needs no engine and
 * allocates nothing (when every night pixel is darker than the threshold,
 * all are used). Errors: PLX_E_INVALID (a NULL array, npx or nnight 0).
 * Threads: any.
 */
plx_status plx_nightify(const uint8_t *day, size_t npx, const uint8_t *night, size_t nnight,
                        double dark_threshold, uint8_t *out /* OUT */);

/* ---- Night images (SPEC §5) ----------------------------------------------- */

typedef struct plx_camera {
    double eye[3], target[3];   /* up is +z */
    double fov_deg;             /* vertical field of view, 0 < fov < 180 */
    int32_t width, height;      /* pixels, at most the config's render maximum */
} plx_camera;

/*
 * plx_indirect_refine around the ground point a camera looks at rather
 * than its eye (README "Walking through a city"): the eye's ground point
 * moved along the view's horizontal direction to where the view's centre
 * ray meets the ground (z = 0), but at most near_radius / 2 ahead. A view
 * from 30 to 60 m looking ahead refines the lamps it shows instead of
 * those under the eye, below the frame; a level view (no ground met) is
 * centred near_radius / 2 ahead, so the lamps beside the viewer stay
 * within reach. A view straight down, and an eye at or below the ground,
 * keep the eye's ground point.
 * out->centre gets the centre. Errors: those of plx_indirect_refine;
 * PLX_E_INVALID for a NULL or non-finite camera.
 */
plx_status plx_indirect_refine_view(plx_engine *e, const plx_camera *cam, plx_refine_stats *out /* OUT */);

/* A raster backend for the visibility pass (depth and surface id per
 * pixel); opaque here, made by a port (see plx_render_opts.backend). */
typedef struct plx_backend plx_backend;

typedef struct plx_render_opts {
    double exposure;            /* radiance multiplier before sRGB (SPEC default 1) */
    int no_glow;                /* 1: no lamp glows: every pixel is SPEC §5's radiance */
    int aerial;                 /* 1: a view from above. Frames that read the radiance atlas
                                   (indirect light traced, not per_pixel) draw it as any other;
                                   the others take the ground from the aerial light map (built
                                   once; with photons traced, its indirect layer lights ground
                                   and roofs; a reset of the photons rebuilds it) */
    double aerial_m_per_texel;  /* the radiance atlas's spacing when the frame makes it (0: 0.5 m),
                                   and the light map's resolution (0: 1 m); both coarser if the
                                   budget needs; 0 or PLX_TEXEL_MIN .. _MAX. Not read once the
                                   atlas is made (a bake's, or an earlier frame's) */
    int no_cull;                /* 1: draw every building (the culled image is identical) */
    int no_indirect;            /* 1: direct light only even when photons were traced */
    const plx_backend *backend; /* visibility pass: NULL = the built-in software rasteriser;
                                   or a port's, e.g. port/osmesa/plx_osmesa.h */
    int auto_exposure;          /* PLX_EXPOSURE_AUTO (1): the exposure is chosen from the image (a
                                   high percentile of the lit pixels' luminance near white) and a
                                   tone curve keeps the highlights near lamps; exposure is then
                                   ignored. PLX_EXPOSURE_ADAPT: chosen so, but held at exposure
                                   (the last frame's) while the image's own choice stays within
                                   half a stop of it, else moved towards half a stop from that
                                   choice, at most exposure_step eighths of a stop a frame
                                   (frames of a walk without flicker; kept when no lit surface
                                   is counted; at most PLX_EXPOSURE_MAX): a walk's first frame
                                   takes PLX_EXPOSURE_AUTO, each later one _ADAPT with exposure
                                   the last frame's plx_render_info.exposure. PLX_EXPOSURE_TONE: exposure
                                   with the tone curve. PLX_EXPOSURE_FIXED (0): exposure, linear
                                   (SPEC §5). rgbf stays linear radiance. README "Automatic
                                   exposure" */
    int aa;                     /* anti-aliasing: aa x aa samples per pixel on a regular grid,
                                   averaged in linear radiance (0 or 1: one sample at the pixel
                                   centre, SPEC §5); at most PLX_RENDER_MAX_AA. Adaptive unless
                                   aa_full: the later samples only where the first sample's
                                   image has an edge (README "Anti-aliasing") */
    int aa_full;                /* 1: every pixel takes all aa x aa samples */
    int per_pixel;              /* 1: with indirect light, every pixel's light computed at the
                                   pixel (exact direct light, the irradiance cache's indirect
                                   light), not read from the radiance atlas (README "The
                                   radiance atlas"): slower, shadow edges exact */
    int exposure_step;          /* PLX_EXPOSURE_ADAPT: the most the exposure rises in a frame,
                                   in eighths of a stop; it falls up to 4 times that (0: to the
                                   band around the image's own choice at once; 0 .. 4096 in
                                   every mode, else PLX_E_INVALID); walk gives round(32 / fps),
                                   at least 1: about 4 stops a second rising */
} plx_render_opts;

#define PLX_EXPOSURE_FIXED 0
#define PLX_EXPOSURE_AUTO 1
#define PLX_EXPOSURE_ADAPT 2
#define PLX_EXPOSURE_TONE 3
#define PLX_EXPOSURE_STEP_MAX 4096 /* plx_render_opts.exposure_step at most */
/* The largest exposure automatic exposure chooses: a frame whose lit
 * surfaces are all darker than about 0.001 cd/m^2 stays dark */
#define PLX_EXPOSURE_MAX 1024.0

/* plx_render_opts.aerial_m_per_texel and plx_bake_opts': 0 (the default)
 * or within these, m (a finer atlas laid out for minutes) */
#define PLX_TEXEL_MIN 0.01
#define PLX_TEXEL_MAX 1e4

#define PLX_RENDER_MAX_AA 16
#define PLX_RENDER_MAX_DIM 16384   /* the largest frame width or height */

/* The radiance atlas frames with indirect light read (README "The radiance
 * atlas"): made at the first such frame (or by plx_bake_prepare), filled
 * as frames need it (or whole by plx_bake_size or plx_bake_save). */
typedef struct plx_atlas_info {
    int made;                   /* 0: no atlas yet (the rest is 0) */
    double spacing;             /* m between sample points on surfaces a lamp may light */
    double coarse;              /* and on the others (indirect light only) */
    uint64_t points;            /* sample points, 4 bytes each */
    uint64_t points_fine;       /* of which at the fine spacing */
    size_t bytes;               /* the atlas's memory (part PLX_PART_FRAME) */
    uint64_t unfilled;          /* charts and ground blocks not filled yet (0: complete) */
    int indirect;               /* its values hold indirect light */
} plx_atlas_info;

/* Fills out. Errors: PLX_E_INVALID (out NULL). Threads: engine (reads). */
plx_status plx_atlas_info_get(plx_engine *e, plx_atlas_info *out /* OUT */);

/* The largest frame plx_render draws: plx_config.render_max_width and
 * _height, or their defaults (1920 x 1080), or a bake's (its --max-size);
 * frames of either orientation fit. Errors: PLX_E_INVALID (e, w or h
 * NULL). Threads: engine (reads). */
plx_status plx_render_max_get(plx_engine *e, int32_t *w /* OUT */, int32_t *h /* OUT */);

/* Exposure 1, everything else off (NULL: nothing). Threads: any. */
void plx_render_opts_default(plx_render_opts *o /* OUT */);

typedef struct plx_render_info {
    uint32_t buildings, drawn;  /* buildings in the scene, drawn after culling */
    double drawn_fraction;      /* triangles drawn / triangles of the scene */
    uint64_t shaded_pixels;     /* the direct-light shader's calls, all --aa passes together (0 for
                                   frames read from the radiance atlas) */
    double exposure;            /* the exposure applied (the chosen one with auto_exposure) */
    uint64_t indirect_lookups;  /* points whose indirect light was looked up (the irradiance
                                   cache or the photon buffers), all --aa passes together;
                                   street frames that gather ask only the corners of 4x4
                                   blocks on one surface and the pixels the blocks leave */
    uint64_t aa_later;          /* aa > 1: pixels the later samples shaded, all passes together
                                   ((aa * aa - 1) * width * height when every sample is taken) */
    int aa_adaptive;            /* aa > 1: PLX_AA_ADAPTIVE when the later samples were adaptive;
                                   PLX_AA_DENSE when a frame read from the radiance atlas had
                                   edges at more than half its pixels, so every sample was
                                   taken (faster there: the image is aa_full's); PLX_AA_EVERY
                                   (0) with aa_full, or when the block had no room for the
                                   adaptive buffers (8 bytes a pixel of the largest frame) */
    int eye_inside;             /* 1: the eye was inside a building's solid: the frame shows the
                                   inside of its walls, every pixel computed (not read from the
                                   radiance atlas: slower) */
} plx_render_info;

#define PLX_AA_EVERY 0
#define PLX_AA_ADAPTIVE 1
#define PLX_AA_DENSE 2

/*
 * Renders one frame into caller-owned buffers: rgb8 (width*height*3 bytes,
 * sRGB after exposure, row 0 at the top) and/or rgbf (width*height*3 floats,
 * linear radiance); either may be NULL. Indirect light is added when photon
 * frames were traced (plx_indirect_step) unless o->no_indirect; such frames
 * read the radiance atlas (plx_atlas_info_get; made on first need, the
 * charts a frame shows filled as it draws them) unless o->per_pixel, the
 * eye is inside a building, or the atlas does not fit the block (said once
 * in a warning): then every pixel's light is computed there. The
 * renderer's own buffers come from the engine (PLX_PART_FRAME) on first use.
 * Lamp light, the renderer's frame buffers and mesh (sized for the
 * config's largest frame) and, with o->aerial and no atlas, the aerial light
 * map are built on first need and kept until the next load.
 * Errors: PLX_E_INVALID (cam NULL; eye or target not finite; eye not above
 * the ground, z <= 0; eye == target; fov_deg outside (0, 180); width or
 * height outside 1 .. the engine's largest frame, render_max_width/height
 * or the bake's, either way round; o->auto_exposure not one of PLX_EXPOSURE_FIXED, _AUTO,
 * _ADAPT, _TONE (before 2026-11-30 any nonzero value meant _AUTO; 2 and 3
 * now hold or fix the exposure); o->exposure not a finite number above 0
 * unless auto_exposure is PLX_EXPOSURE_AUTO; o->aa outside 0 ..
 * PLX_RENDER_MAX_AA),
 * PLX_E_NOSCENE, PLX_E_NOMEM, PLX_E_UNSUPPORTED (o->backend could not draw
 * the frame); after an error the buffers' contents are unspecified (an
 * anti-aliased frame may have written its first sample). Lifetime: the
 * caller's buffers are written, not kept. Threads: engine.
 */
plx_status plx_render(plx_engine *e, const plx_camera *cam, const plx_render_opts *o, uint8_t *rgb8 /* OUT */,
                      float *rgbf /* OUT */, plx_render_info *info /* OUT */);

/* ---- How well lit is a route? ------------------------------------------- */

typedef struct plx_route_stats {
    double length;          /* m of path scored (on the ground outside buildings) */
    double mean, min, max;  /* horizontal illuminance in lux (direct + indirect) */
    double uniformity;      /* min / mean (0 when mean is 0) */
    double dark_share;      /* share of the scored length with E below dark_lux */
    int p_class;            /* EN 13201 P-class met: 1..6 for P1..P6, 0 for none */
    uint32_t samples;       /* points computed */
    double blocked_length;  /* m of path inside building footprints, not scored */
} plx_route_stats;

/*
 * Scores the polyline of n vertices xy (local metres) sampled every 'step'
 * metres (each segment into ceil(length/step) equal parts, both ends
 * included) on the ground facing up. Means are length-weighted (trapezoid
 * rule); min and max are over the samples. total (may be NULL) gets the
 * whole line, segments (may be NULL) n-1 entries, one per segment. The
 * P-class is the best class whose mean and minimum the line meets (P1 15/3,
 * P2 10/2, P3 7.5/1.5, P4 5/1, P5 3/0.6, P6 2/0.4 lx).
 * Samples inside a footprint are not scored (blocked_length). A segment
 * of no length (a repeated vertex) is its one point: mean = min = max =
 * that point's lux, dark_share 1 or 0, length 0 (inside a footprint it is
 * scored as nothing, all 0, as a segment wholly inside one).
 * Errors: PLX_E_INVALID (xy NULL, n < 2, step <= 0, dark_lux < 0,
 * non-finite input), PLX_E_NOSCENE, PLX_E_NOMEM (the samples of one segment
 * are held in scratch: 64 bytes a sample). Threads: engine.
 */
plx_status plx_route_score(plx_engine *e, const double *xy, uint32_t n, double step, double dark_lux,
                           plx_route_stats *total /* OUT */, plx_route_stats *segments /* OUT */);

/* The EN 13201 P-class (1..6, 0 for none) met by mean and minimum lux.
 * Threads: any. */
int plx_p_class(double mean, double min);

/* ---- Photometric lamps and pedestrian metrics (SPEC §2.1, §6) ---------- */

/*
 * A lamp may name an IES LM-63 or EULUMDAT file (properties.photometry, a
 * path relative to the scene file's folder). The core reads no files: the
 * caller reads each path the scene names and hands the bytes over (the
 * polarlux command does this for every scene it loads). Until then such a
 * lamp gives no light (its intensity reads 0).
 *
 * plx_photometry_count / plx_photometry_path: the distinct paths named by
 * the scene's lamps, as written, k = 0 .. count-1 (PLX_E_RANGE past it).
 * plx_set_photometry parses data[0..len) (IES when a line starts with
 * "TILT=", else EULUMDAT; 'name' prefixes messages) into part
 * PLX_PART_SCENE and gives it to every lamp naming 'path'; those lamps'
 * intensity becomes dimming x the table's peak. Cached light (lit regions,
 * photons) is dropped. Errors: PLX_E_PARSE "NAME: line L: why" (bad number,
 * table too short, unsupported tilt or photometric type, ...);
 * PLX_E_INVALID when no lamp names path; PLX_E_NOSCENE; PLX_E_NOMEM.
 * A table whose own flux (the integral of its intensities) is more than
 * 10% off what its header states (EULUMDAT: light output ratio x the
 * lamps' flux; IES: only above lamps x lumens per lamp x ballast factor)
 * is taken as given with a warning through the port's log.
 * Lifetime: *path lives until the next load; data is not kept (the table
 * is, until the next load). Threads: engine.
 */
uint32_t plx_photometry_count(plx_engine *e);
plx_status plx_photometry_path(plx_engine *e, uint32_t k, const char **path /* OUT */);
plx_status plx_set_photometry(plx_engine *e, const char *path, const char *data, size_t len,
                              const char *name);

typedef struct plx_lamp_photometry {
    const char *path;         /* properties.photometry, or NULL (isotropic) */
    int loaded;               /* the file was given */
    int format;               /* 1 IES, 2 EULUMDAT, 0 none */
    double azimuth, tilt;     /* degrees: C = 0 counter-clockwise from east; tilt raises C = 0 */
    double dimming;           /* 0..1 */
    double peak_cd;           /* dimming x the table's largest value (the intensity when isotropic) */
    double flux_lm;           /* total flux: the integral of I over the sphere */
    double gamma_lit;         /* degrees from nadir beyond which I = 0 (180 when isotropic) */
} plx_lamp_photometry;

plx_status plx_lamp_photometry_get(plx_engine *e, uint32_t lamp, plx_lamp_photometry *out /* OUT */);
/* I(omega) of lamp 'lamp' toward the direction dir (need not be unit) from
 * the lamp, in cd; *c_deg and *gamma_deg (may be NULL) get the direction's
 * C and gamma in the lamp's frame. Errors: PLX_E_NOSCENE, PLX_E_RANGE (lamp
 * out of range), PLX_E_INVALID (dir zero or not finite, NULL arguments).
 * Threads: engine (reads). */
plx_status plx_lamp_intensity(plx_engine *e, uint32_t lamp, const double dir[3], double *cd /* OUT */,
                              double *c_deg /* OUT */, double *gamma_deg /* OUT */);

/* SPEC §6 quantities, direct light: out[4k..4k+3] = E_h, E_v(u), E_sc(u),
 * E_hs (lux) at P[3k..3k+2]; U[2k..2k+1] the horizontal facing direction u
 * (normalised here; NULL: east, +x). A point strictly inside a solid or
 * below the ground gets NaN and the call returns PLX_E_RANGE naming the
 * first; PLX_E_INVALID for a zero or non-finite u; PLX_E_NOSCENE;
 * PLX_E_NOMEM (setting up lamp light). Threads: engine (the lit-region
 * cache changes, as plx_illuminance). */
enum { PLX_METER_H = 0, PLX_METER_V, PLX_METER_SC, PLX_METER_HS, PLX_METER_COUNT };
plx_status plx_meter(plx_engine *e, size_t n, const double *P, const double *U, double *out /* OUT */);

/* EN 13201-2 P class (1..6, 0 none) with the facial-recognition criterion:
 * mean and min E_h and also min E_v and min E_sc (SPEC §6 table). */
int plx_p_class_facial(double mean, double min, double min_ev, double min_esc);

/*
 * min E_v and min E_sc at 'height' m above the polyline (xy, n vertices),
 * sampled like plx_route_score (each segment into ceil(length/step) equal
 * parts, ends included; samples inside a building's solid left out), facing
 * along the segment (dir 0: from vertex i to i+1) and back (dir 1); a
 * segment of no length faces along the next segment with a length (else
 * the previous one; east when none has).
 * seg (may be NULL): 4 values per segment, min_ev[0], min_ev[1], min_esc[0],
 * min_esc[1]; total (may be NULL) the same over the line (each direction's
 * minimum over all segments). A segment with no sample gets NaN.
 * Errors: PLX_E_INVALID (n < 2, step <= 0, height < 0, non-finite input),
 * PLX_E_NOSCENE, PLX_E_NOMEM. Threads: engine.
 */
plx_status plx_route_facial(plx_engine *e, const double *xy, uint32_t n, double step, double height,
                            double *seg /* OUT */, double total[4] /* OUT */);

/* ---- Procedural cities (plx gen) ------------------------------------- */

/* Receives generated text; returns 0 to go on, non-zero to stop. */
typedef int (*plx_write_fn)(void *ctx, const char *data, size_t len);

/*
 * Writes a procedural city as a GeoJSON FeatureCollection in metres.
 * style: "grid", "eixample" or "oldtown"; nx, ny: blocks along x and y.
 * Deterministic for a seed. Needs no engine and allocates nothing.
 * Errors: PLX_E_INVALID (unknown style, nx or ny outside 1..1000, style or
 * write NULL), PLX_E_IO (write returned non-zero: stopped there).
 * Threads: any (write is called from the calling thread only).
 */
plx_status plx_gen_city(const char *style, int nx, int ny, uint64_t seed,
                        plx_write_fn write, void *ctx);

/* ---- Bake files: build once, load without rebuilding (README "Bake files") */

typedef struct plx_bake_opts {
    int aerial;                 /* 1: make the radiance atlas (filled by plx_bake_size or
                                   plx_bake_save, after the photons); with no_indirect the
                                   aerial light map of direct light instead */
    double aerial_m_per_texel;  /* the atlas's spacing (0: 0.5 m), or the light map's
                                   resolution (0: 1 m); coarser if the budget needs; 0 or
                                   PLX_TEXEL_MIN .. _MAX */
    int no_indirect;            /* 1: no photon buffers */
    int twin;                   /* 1: the twin engine (see plx_bake_save): the same memory
                                   layout without the atlas's or light map's values */
    int no_polar;               /* 1: no polar diagrams (frames do not read them; a
                                   query on the loaded bake builds them on need) */
} plx_bake_opts;

/*
 * Builds everything queries and frames need for the loaded scene: polar
 * diagrams (unless o->no_polar), lamp light, photon buffers (levels for a viewer at the centre
 * of Bounds, all around), the renderer and, with o->aerial, the radiance
 * atlas laid out (or, with o->no_indirect, the aerial light map). Photon
 * frames are then added with plx_indirect_step.
 */
plx_status plx_bake_prepare(plx_engine *e, const plx_bake_opts *o);

/*
 * Bytes of the bake file of e, and the file itself written into the
 * caller's buffer (the core does no I/O). twin: a second engine in another
 * block, with the same scene loaded (and the same ground image) and
 * plx_bake_prepare called with the same options and twin = 1, but no photon
 * frames; the words that differ between the two by exactly the distance of
 * their blocks are the pointers, saved as offsets. Both blocks must have
 * the same address modulo 64, and be zero-filled when the engines were
 * created (padding and never-written bytes are saved too). With the
 * radiance atlas, the first of these calls fills it (on
 * plx_config.threads workers, the bulk of a large city's bake; progress
 * through plx_port.progress), so the loaded engine's frames fill nothing;
 * what frames drawn before left in the engine is not saved.
 * Errors: PLX_E_INVALID (no twin of the same layout, buffer too small),
 * PLX_E_NOSCENE, PLX_E_NOMEM (no room to fill the atlas).
 */
plx_status plx_bake_size(plx_engine *e, plx_engine *twin, size_t *bytes /* OUT */);
plx_status plx_bake_save(plx_engine *e, plx_engine *twin, void *buf, size_t cap,
                         size_t *written /* OUT */);

/*
 * Size first: checks the bake's header and checksum and gives the block
 * size to pass to plx_bake_load: the image, plus 32 MiB for queries, plus
 * 20 bytes a pixel of the largest frame with a renderer. Frames need less
 * than that: the image and the 20 bytes a pixel (anti-aliasing's buffers;
 * with less, plx_render takes every sample, PLX_AA_EVERY, or, below 8
 * bytes a pixel, a frame of aa > 1 fails with PLX_E_NOMEM).
 * Errors (one line in err, emptied on success): PLX_E_PARSE (not a bake,
 * truncated, corrupt; bake NULL), PLX_E_UNSUPPORTED (another format
 * version, architecture or build). Threads: any (reads only bake).
 */
plx_status plx_bake_block_size(const void *bake, size_t len, size_t *block_bytes /* OUT */, char *err,
                               size_t errlen);

/*
 * Creates an engine in the caller's block from a bake: one copy of the
 * image and the relocation of its pointers, no parsing, no rebuilding.
 * cfg gives the port, strictness and part budgets (the lit cache and the
 * render maximum stay the bake's). The bake buffer may be freed after; it
 * must not overlap the block (PLX_E_INVALID: the image is written over the
 * block from its start).
 * cfg->threads is taken as for plx_engine_create.
 * Errors as plx_bake_block_size, plus PLX_E_NOMEM (block too small) and
 * PLX_E_INVALID; err gets one line, emptied on success. Lifetime: the
 * engine lives in mem until plx_engine_destroy. Threads: any (it touches only mem and the bake).
 */
plx_status plx_bake_load(void *mem, size_t size, const plx_config *cfg, const void *bake, size_t len,
                         plx_engine **engine /* OUT */, char *err, size_t errlen);

/*
 * The bake read through the caller's reads, not held in memory: what a
 * program that keeps to a fixed memory uses (a bake held beside the
 * block doubles the memory a load takes). read(user, off, buf, n) puts
 * the n bytes at offset off of the file (len bytes long) into buf and
 * returns 0, or -1 when it cannot (an error, or the file ended).
 * plx_bake_block_size_read gives plx_bake_block_size's size, with its
 * checks when given scratch (scratch_len >= 512 bytes of the caller's to
 * read the file through; the more, the fewer reads), else the header's
 * only (its size field unchecked: a damaged one can ask for a block far
 * too big); plx_bake_load_read reads the file once, straight into the
 * block, checking it as it reads as plx_bake_load does (only a reading
 * that fails is followed by a second, checking the whole file through
 * the block for the damaged file's own message): the same engine as
 * plx_bake_load's, the same errors and messages, plus PLX_E_IO (a read
 * failed: which bytes) and PLX_E_PARSE "corrupt bake file: it changed
 * while it was read" (the first reading failed its checks, the second
 * passed them). The file is checked first, through the block, when the
 * image is over four times the file (the pages it leaves out are zeroed
 * as the reading passes them) and, through 512 bytes of the stack, when
 * the image does not fit the block, so that a damaged file gets its own
 * error before the block's. No read reaches past the stored pages the
 * bitmap counts. After an error the block's contents are unspecified.
 * Threads: any (it touches only mem and what read gives).
 */
typedef int (*plx_bake_read_fn)(void *user, uint64_t off, void *buf, size_t n);
plx_status plx_bake_block_size_read(plx_bake_read_fn read, void *user, uint64_t len, void *scratch, size_t scratch_len,
                                    size_t *block_bytes /* OUT */, char *err, size_t errlen);
plx_status plx_bake_load_read(void *mem, size_t size, const plx_config *cfg, plx_bake_read_fn read, void *user,
                              uint64_t len, plx_engine **engine /* OUT */, char *err, size_t errlen);

/* ---- Embedding: coordinates and memory sizing -------------------------- */

/*
 * The SPEC §1 projection of the loaded lon/lat scene, for n points given as
 * pairs (lon, lat degrees / x, y metres), in may equal out:
 *   x = (lon - lon0) * 111320 * cos(lat0),  y = (lat - lat0) * 110540
 * about the centre (lon0, lat0) of plx_scene_info; the forward direction is
 * bit for bit what the loader did to the scene's coordinates. Non-finite
 * input gives non-finite output (no check).
 * Errors: PLX_E_NOSCENE; PLX_E_INVALID (the scene is in local metres, or an
 * array NULL with n > 0). Reads the scene only: may run in several threads
 * at once on one engine as long as no thread loads a scene meanwhile.
 */
plx_status plx_lonlat_to_local(plx_engine *e, size_t n, const double *lonlat, double *xy /* OUT */);
plx_status plx_local_to_lonlat(plx_engine *e, size_t n, const double *xy, double *lonlat /* OUT */);

/* What a GeoJSON text holds, counted without parsing it. */
typedef struct plx_scene_size {
    uint64_t text_bytes;   /* the text's length */
    uint64_t json_values;  /* JSON values (objects, arrays, strings, numbers, literals; keys not) */
    uint64_t string_bytes; /* bytes of every string, keys included, plus 1 each */
    uint64_t features;     /* "Feature" strings */
    uint64_t points;       /* "Point" strings: at least the lamps */
    uint64_t positions;    /* arrays of numbers: vertices and points */
    uint64_t rings;        /* arrays of positions: rings (at least the buildings) */
} plx_scene_size;

/*
 * Counts text (len bytes, not necessarily NUL-terminated) in one pass, with
 * no engine and no memory. Malformed text gives counts anyway (the load
 * will say what is wrong). Errors: PLX_E_INVALID (out NULL, text NULL with
 * len > 0). Thread-safe (touches only *out).
 */
plx_status plx_scene_size_scan(const char *text, size_t len, plx_scene_size *out /* OUT */);

/* What the caller will do with the scene (OR them); loading is always counted. */
#define PLX_USE_LOAD       0u
#define PLX_USE_VISIBILITY 1u  /* polar diagrams: plx_visibility_get, plx_polar_* */
#define PLX_USE_LIGHT      2u  /* plx_illuminance, plx_lamps_at, lit regions, routes */
#define PLX_USE_RENDER     4u  /* plx_render at the config's largest frame (direct light,
                                  anti-aliased or not; aerial light map not included) */

/*
 * The block size (bytes, for plx_engine_create) that a scene of these
 * counts needs for the uses asked, with the config's sizes (lit cache,
 * largest frame; cfg NULL: the defaults). Counts the caller knows by other
 * means may be given by hand: set positions (vertices + lamps), rings
 * (buildings), points (lamps), features; text_bytes, json_values and
 * string_bytes left 0 are then derived from them. Photon buffers
 * (plx_indirect_step) are not included. Returns 0 when sz is NULL or the
 * size does not fit in size_t. Pure function: thread-safe.
 */
size_t plx_memory_estimate(const plx_scene_size *sz, const plx_config *cfg, unsigned uses);

/* ---- Ports -------------------------------------------------------------- */

/* The POSIX port (plx_port_posix, plx_engine_new, plx_engine_free) and the
 * PNG/PFM files are not part of this library: see polarlux_port.h and
 * libpolarlux-port. */

#ifdef __cplusplus
}
#endif
#endif
