/* The polarlux command: shared helpers of the subcommands. */
#ifndef PLX_CLI_H
#define PLX_CLI_H

#include <stdio.h>
#include "polarlux.h"
#include "polarlux_port.h"
#include <cjson/cJSON.h>

/* Exit codes (README, "Exit codes"). */
enum {
    EXIT_OK = 0,
    EXIT_FAIL = 1,   /* the work failed: bad scene, I/O, query out of range */
    EXIT_USAGE = 2,  /* unknown option, missing or malformed argument */
    EXIT_NOMEM = 3   /* the memory budget (--mem) is too small */
};

#define CLI_MAX_LAMP_FILES 16

typedef struct cli_common {
    size_t mem;      /* engine budget in bytes (--mem) */
    int mem_given;   /* --mem was given */
    int strict;      /* --strict */
    int quiet;       /* --quiet: no warnings on stderr */
    int render_w, render_h; /* largest frame the engine will render (0: default) */
    const char *lamp_files[CLI_MAX_LAMP_FILES]; /* --lamps FILE, in order */
    int nlamp_files;
    const char *points_crs; /* --points-crs: lonlat, local, or a CRS name (NULL: the file says, or the scene's) */
    int threads;     /* --threads N: workers of a frame (0: the number of processors) */
    int atlas_room;  /* frames will read the radiance atlas: a bake without one, loaded without
                        --mem, gets a block with room for it (CLI_ATLAS_BLOCK) */
} cli_common;

#define CLI_DEFAULT_MEM ((size_t)1 << 30)
/* The block a bake without its atlas is loaded in when no --mem is given: room for the atlas at its most. */
#define CLI_ATLAS_BLOCK (4 * PLX_ATLAS_MAX_BYTES + ((size_t)1 << 20))
/* The buffer a bake file is checked through before its block is taken. */
#define CLI_BAKE_SCRATCH ((size_t)1 << 20)

/* Prints "polarlux CMD: msg" on stderr and returns EXIT_USAGE. */
int cli_usage_error(const char *cmd, const char *fmt, ...);
/* Parses sizes like 512M, 2G, 65536; 0 on failure. */
size_t cli_parse_size(const char *s);
/* Parses a decimal number / integer strictly; 0 on success. */
int cli_parse_double(const char *s, double *out);
int cli_parse_int(const char *s, long lo, long hi, long *out);
/* Bounds of hostile option values (README, "Limits"): every number is
 * finite (cli_parse_double refuses inf and nan); a coordinate is within
 * CLI_MAX_COORD metres of the origin, as scene coordinates are. */
#define CLI_MAX_COORD 1e7
/* A finite number in [lo, hi]; 0 on success. */
int cli_parse_real(const char *s, double lo, double hi, double *out);
/* --exposure of render and walk: a number above 0, at most 1e9 (0 drew
 * a black image, called dark for want of lamps); 0 on success. */
int cli_parse_exposure(const char *s, void *out);
/* n comma-separated coordinates "X,Y[,Z...]", each finite and within
 * +-CLI_MAX_COORD; 0 on success. */
int cli_parse_coords(const char *s, double *v, int n);
/* Most photons one run traces (--photons x --frames): about 18 minutes. */
#define CLI_MAX_PHOTONS 4294967296.0
/* Handles --mem, --strict, --quiet at argv[*i]; 1 if consumed, -1 on error. */
int cli_common_option(const char *cmd, int argc, char **argv, int *i, cli_common *c);
/* Creates an engine and loads the scene; prints the error and returns an
 * exit code on failure (engine freed), EXIT_OK on success. */
int cli_open_scene(const char *cmd, const char *path, const cli_common *c, plx_engine **e);
/* Whether path is a regular file starting with the bake magic (README
 * "Bake files"); 0 for anything else, unreadable files included. */
int cli_is_bake(const char *path);
/* A large block (2 MiB aligned, huge pages where offered); free() it. */
void *cli_big_alloc(size_t size);

/* The engine configuration of the common options (port, --strict, --quiet). */
void cli_config(const cli_common *c, plx_config *cfg /* OUT */);
/* Loads the scene file into the existing engine *e (and its ground image);
 * on failure prints, frees the engine and returns an exit code. */
int cli_load_scene(const char *cmd, const char *path, const cli_common *c, plx_engine **e);
/* The bake file cli_open_scene loaded, if any (README "Bake files"). */
typedef struct cli_bake_state {
    int loaded;
    size_t bytes;
    unsigned long long load_ns;
    unsigned char head[16];  /* the header's file length and checksum (bytes 24-39), as loaded */
} cli_bake_state;
extern cli_bake_state cli_bake_last;
/* A twin of the bake cli_open_scene loaded last from path: the same file
 * read again into a block of its own (sized as that load sized it: the
 * header's, or --mem), quietly (no warning of the engine's, no line on
 * stderr: why says why it cannot be) and leaving cli_bake_last as it is.
 * The file must still hold the bytes first loaded: its length and
 * checksum are compared with the first load's, before and after. EXIT_OK
 * or an exit code. */
int cli_open_twin(const char *path, const cli_common *c, plx_engine **e, char *why, size_t whylen);
/* "NAME: malformed JSON at byte B (line L, column C)" into err, where
 * cJSON stopped in text (len bytes; cJSON_GetErrorPtr, read right after
 * the failed parse), with ": the text ends early" for a text cut short:
 * the scene loader's words (src/scene/geojson.c's parse_error). */
void cli_json_error(const char *name, const char *text, size_t len, char *err, size_t errlen);
/* text (len bytes) parsed, or NULL with cli_json_error's words in err;
 * anything but white space after the JSON value is refused at its byte,
 * as the scene loader does (walk and route paths took it). */
cJSON *cli_json_parse(const char *name, const char *text, size_t len, char *err, size_t errlen);
/* Photon frames for indirect light (--photons, --frames, --no-indirect). */
typedef struct cli_indirect {
    long photons;    /* per frame with --photons (else 65536, or cli_photons's with per_lamp) */
    long frames;     /* progressive frames (default 4; illum and bake 16) */
    int frames_given; /* --frames was given */
    int photons_given; /* --photons was given */
    int per_lamp;    /* without --photons, cli_photons's count a lamp (bake, render, walk) */
    int off;         /* --no-indirect */
    long gather;     /* --gather N: final gathering side at points (0 = photon
                        buffers only); -1 = the engine's default */
} cli_indirect;
/* Photon frames by default when points are answered by final gathering
 * (illum): the photons carry only the later bounces (16 x 65536). */
#define CLI_GATHER_FRAMES 16
/* illum: photons from the lamps whose reach comes within this many metres
 * of the points' box (plx_indirect_select_lamps). */
#define CLI_SELECT_MARGIN 100.0
void cli_indirect_default(cli_indirect *ind);
/* Photons per frame without --photons, with per_lamp: 16 a lamp, from
 * 65,536 to 1,048,576. The fixed 65,536 leaves each street-facade point of
 * gen eixample 30 30 (18,480 lamps) 27% off the path tracer on average
 * after a bake's 16 frames and 50% after render's 4; 16 a lamp (295,680)
 * about 15% and 28%, for 0.8 s more of a 6 s bake and 0.17 s more of a
 * 1 s render (README "Bake files", "Indirect light"). */
#define CLI_PHOTONS_PER_LAMP 16
#define CLI_PHOTONS_MIN 65536L
#define CLI_PHOTONS_MAX 1048576L
/* The photons a frame cli_indirect_run traces: --photons when given (or
 * without per_lamp, 65,536), else CLI_PHOTONS_PER_LAMP times the scene's
 * lamps, clamped to CLI_PHOTONS_MIN .. CLI_PHOTONS_MAX. */
long cli_photons(plx_engine *e, const cli_indirect *ind);
/* Handles --photons N, --frames K, --no-indirect, --gather N at argv[*i]; 1 if consumed, -1 on error. */
int cli_indirect_option(const char *cmd, int argc, char **argv, int *i, cli_indirect *ind);
/* Traces the frames (progress on a terminal), viewer at eye looking along
 * dir (either may be NULL). Returns an exit code. */
/* A bake without photon frames (bake --no-indirect or --frames 0) gives
 * images of the direct light, as it was made (README "Bake files"):
 * render and walk do not trace photons into its block, which has no room
 * for them beside a frame. Sets ind->off with a warning and returns 1
 * then; 0 otherwise (not a bake, photons traced, or indirect light off). */
int cli_bake_direct(const char *cmd, const char *path, const cli_common *c, plx_engine *e, cli_indirect *ind);
/* A word on stderr for options a loaded bake makes moot: --photons and
 * --frames (its photon buffers are used), --texel (texel > 0) when it
 * holds the radiance atlas. Nothing for a scene. */
void cli_bake_kept(const char *cmd, const char *path, const cli_common *c, plx_engine *e, const cli_indirect *ind,
                   double texel);
/* A line on stderr when the photon buffers were fitted below the default
 * quality: to fit --mem, or (a loaded bake's, photons traced again for
 * illum's lamps) when the bake was made. Not a warning: --quiet keeps it. */
/* The EPSG code at the end of a CRS name ("EPSG:2154",
 * "urn:ogc:def:crs:EPSG::2154"), or 0; two names of one CRS (the same
 * string, or the same EPSG code written either way). */
int cli_crs_epsg(const char *name);
int cli_same_crs(const char *a, const char *b);
void cli_indirect_note(const char *cmd, const cli_common *c, plx_engine *e);
/* A line on stderr when this run's first frame laid out the radiance
 * atlas (had: whether it was made before the frame, a bake's) with its
 * points farther apart than asked (texel, or the default 0.5 m when 0)
 * because the block is small (its quarter under PLX_ATLAS_MAX_BYTES: a
 * larger --mem gives finer points). Not a warning: --quiet keeps it. */
void cli_atlas_note(const char *cmd, const cli_common *c, plx_engine *e, int had, double texel);
int cli_indirect_run(const char *cmd, const cli_common *c, plx_engine *e, const cli_indirect *ind, const double *eye,
                     const double *dir, double fov_deg);
/* A command's near-viewer refinement (cli_refine): its settings and
 * what its calls did. */
typedef struct cli_refiner {
    double height;          /* refine only with the eye at most this high above the ground, m */
    long frames, photons;   /* refill photon frames after a newly refined lamp, and their photons */
    plx_refine_stats rs;    /* the last refinement's counters */
    long refills;           /* refill photon frames traced, all calls */
    long high;              /* calls with the eye above height: nothing refined */
} cli_refiner;

/* The settings, and no call yet. */
void cli_refiner_init(cli_refiner *r, double height, long frames, long photons);

/* Near-viewer refinement for camera cam (plx_indirect_refine_view: around
 * the ground point the view looks at) when the eye is at most r->height
 * above the ground (munoz2013 §3.3: only low views are
 * refined; above it nothing changes and r->high counts the call); when
 * lamps were refined for the first time (r->rs.refined grew), r->frames
 * photon frames refill the aerial chart. Prints the error and returns an
 * exit code. */
int cli_refine(const char *cmd, plx_engine *e, const plx_camera *cam, cli_refiner *r);
/* The end of a frame's out-of-memory line (in buf): a larger --mem or a
 * smaller --size, and when it was anti-aliased, that its buffers take 20
 * bytes a pixel of the largest frame (a bake's --max-size) and --aa 1
 * none; "" for another error. */
const char *cli_render_nomem_hint(plx_status st, const plx_render_opts *o, plx_engine *e, char *buf, size_t len);
/* "polarlux CMD: warning: ..." on stderr unless --quiet (c may be NULL). */
void cli_warn(const char *cmd, const cli_common *c, const char *fmt, ...);
/* Whether the file name's extension (a dot in its last part) is another
 * than ext (lower case; any case matches). Names without one (a device,
 * a FIFO, "-") are not. */
int cli_other_ext(const char *path, const char *ext);
/* 1 when path (NULL: none) may take the format what (.ext), else 0 after
 * a usage message: render -o x.jpg wrote a PNG under that name. */
int cli_out_ext(const char *cmd, const char *opt, const char *path, const char *ext, const char *what);
/* A note on stderr (unless --quiet): whether the horizontal illuminance
 * printed is direct light only or direct + indirect (the photon buffers,
 * a bake's). route and annotate gave different numbers for a scene and
 * its bake, the table saying nothing. */
void cli_light_note(const char *cmd, const cli_common *c, plx_engine *e);

/* The scene file's own top-level "attribution" string (a member some
 * GeoJSON extracts carry: OpenStreetMap's licence line) into buf, read in
 * place through the POSIX port's mapping; 1 when there is a non-empty
 * one, else 0 and buf empty (a bake, no such member, a file that cannot
 * be mapped). */
int cli_scene_attribution(const char *path, char *buf, size_t cap);
/* v (finite) in the fewest significant digits that read back as v
 * (24.937911661 as it was written, not 24.93791166 or
 * 24.937911661000001); len at least 32. */
void cli_shortest(double v, char *out, size_t len);
/* A point query's failure (plx_last_error) at FILE:LINE, the point as the
 * file gave it (given: x y) when that differs from the local metres the
 * library names (lon/lat points): "point 24.9379 60.1740 (local -353.5,
 * 266.0 m) is inside building 368". */
void cli_point_error(const char *cmd, const char *file, size_t line, const double *given, const double *local,
                     plx_engine *e);
/* Why a result is dark: "the scene has no lamps", or that no light reaches it. */
const char *cli_dark_reason(plx_engine *e);
/* Whether the loaded scene has lamps. */
int cli_has_lamps(plx_engine *e);
/* Whether the engine holds a radiance atlas (frames may be read from it). */
int cli_atlas_made(plx_engine *e);
/* Why a frame at cam came out entirely black (applied: its exposure): the
 * frame is drawn again into rgb8 (its buffer, written out already) at its
 * own automatic exposure; when that shows light, the fixed or held
 * exposure is named (a tiny --exposure was blamed on the lamps); when it
 * is black at automatic exposure's cap, the light is too faint; with no
 * building drawn, the camera looks away; else cli_dark_reason. */
const char *cli_black_reason(plx_engine *e, const plx_camera *cam, const plx_render_opts *o, double applied,
                             unsigned char *rgb8, char *buf, size_t len);
/* Whether an 8-bit image of n bytes is entirely black (every byte 0). */
int cli_all_black(const uint8_t *px, size_t n);
/* Whether output path can be written, tried before any work (a bake or
 * a frame of a large city takes seconds): a temporary file is made beside
 * it and removed (safe_out, as the write at the end does), so a folder
 * given as the file, a missing folder or one without write permission is
 * said at once (on stderr, as "polarlux CMD: ..."). "-", NULL and a
 * target that exists and is not a regular file (a device) are left to
 * the write. */
int cli_out_writable(const char *cmd, const char *path);
/* The share of an RGB image's npx pixels that are black (all three bytes
 * 0). */
double cli_black_share(const uint8_t *rgb, size_t npx);
/* The share of the image's lit (not black) pixels that are full white
 * (255, 255, 255 ); 0 when none is lit. At CLI_BLOWN_OUT or more, render
 * calls a fixed --exposure's image blown out. */
double cli_white_share(const uint8_t *rgb, size_t npx);
#define CLI_BLOWN_OUT 0.5
/* At or above this share of black pixels (and not all), render and walk
 * call a frame nearly black: a normal night view from above is 70 to 90%
 * black (its roofs), a street view 10 to 15%. */
#define CLI_NEARLY_BLACK 0.99
/* Why a nearly black frame is so, for its warning. */
#define CLI_NEARLY_BLACK_WHY "little that is lit is in view (each lamp lights only within its radius, and " \
                             "buildings cast shadows): move the camera toward the lamps, or aim it at them"

/* After a frame: a warning when the anti-aliasing (o->aa > 1) was to be
 * adaptive but the block had no room for it (every sample taken), or when
 * --aa-full comes without --aa 2 or more. */
void cli_aa_warn(const char *cmd, const cli_common *c, const plx_render_opts *o, const plx_render_info *info);

/* With o->aa > 1, the line saying which share of px pixels (all frames
 * together) the later anti-aliasing samples shaded, later of them, and
 * how: of the frames, adaptive were adaptive and dense took every sample
 * for their edges (plx_render_info.aa_adaptive PLX_AA_DENSE); the others
 * took every sample (aa_full, or no room). */
void cli_aa_print(const plx_render_opts *o, uint64_t later, double px, long frames, long adaptive, long dense);
/* One line on the engine's radiance atlas (nothing when it has none). */
void cli_atlas_print(plx_engine *e);
/* Coordinates of options (--at, --eye, --box, ...) are the scene's own:
 * lon/lat degrees on a lon/lat scene, metres on a metre scene. These turn
 * them into the engine's local metres and back; to_local returns -1 when a
 * lon/lat position is out of range. */
int cli_to_local(plx_engine *e, double *x, double *y);
void cli_from_local(plx_engine *e, double *x, double *y);
/* A "--opt X,Y" value in the scene's coordinates turned to local metres
 * (prints the error and returns -1 when out of range). */
int cli_option_local(const char *cmd, const char *opt, plx_engine *e, double *x, double *y);
/* Turns the first two columns of each row of p to local metres. The frame
 * is --points-crs (c->points_crs), else the file's '# crs: NAME' line, else
 * the scene's own coordinates; NAME is lonlat, local (the engine's metres)
 * or the scene's CRS name. *orig (may be NULL) gets a malloc'd copy of the
 * given x,y pairs. Prints the error and returns an exit code. */
struct points;
/* A warning when points (local metres) lie more than 1 km outside the box
 * of the scene's bounds and every lamp's reach (illum, meter). */
void cli_points_far(const char *cmd, const cli_common *c, plx_engine *e, const char *path, const struct points *p);
int cli_points_local(const char *cmd, plx_engine *e, const cli_common *c, const char *path, struct points *p,
                     double **orig);
/* render's default aerial view into cam (its size and fov kept): straight
 * down over the scene's box, with a margin of 5% of the frame each side. */
void cli_default_aerial(plx_engine *e, plx_camera *cam);
/* Progress of long work on a terminal: a line "WHAT: N% (T s)" on stderr,
 * only when stderr is a terminal and the work has run over a second. */
typedef struct cli_progress {
    int tty, shown;
    unsigned long long t0, last;
} cli_progress;
void cli_progress_start(cli_progress *p);
void cli_progress_step(cli_progress *p, const char *what, size_t done, size_t total);
void cli_progress_end(cli_progress *p);
/* The bytes the command may still allocate for its own buffers under the
 * --mem budget: the budget less what the engine has touched (its peak). */
size_t cli_buffer_budget(const plx_engine *e, const cli_common *c);
/* Maps a status to an exit code. */
int cli_exit_code(plx_status s);

int cmd_info(int argc, char **argv);
int cmd_gen(int argc, char **argv);
int cmd_vis(int argc, char **argv);
int cmd_draw(int argc, char **argv);
int cmd_illum(int argc, char **argv);
int cmd_lit(int argc, char **argv);
int cmd_heatmap(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_route(int argc, char **argv);
int cmd_nightify(int argc, char **argv);
int cmd_dark_spots(int argc, char **argv);
int cmd_bake(int argc, char **argv);
int cmd_walk(int argc, char **argv);
int cmd_meter(int argc, char **argv);
/* route --network and annotate (cmd_network.c) */
int cmd_route_network(int argc, char **argv);
int cmd_annotate(int argc, char **argv);
int cmd_tiles(int argc, char **argv);
/* The heat map's colour scale (cmd_heatmap.c): 0 when lux is at or below its
 * bottom (no light), else 1. */
int heatmap_colour(double lux, double top, uint8_t rgb[3]);
/* What a heat map or a tile maps (cmd_heatmap.c): quantity PLX_METER_H is
 * the direct E_h on the ground; V, SC and HS are plx_meter's at 'height'
 * metres, v and sc facing 'facing' degrees counter-clockwise from east or,
 * for sc with facing_min, the least E_sc over every horizontal facing
 * direction. */
typedef struct heat_quantity {
    int quantity;
    double height, facing;
    int facing_min;
} heat_quantity;
/* The quantity at the ground point (x, y): PLX_OK, or PLX_E_RANGE and NaN
 * when the point (or its meter) is inside a solid; other errors as
 * plx_meter. */
plx_status heatmap_value(plx_engine *e, const heat_quantity *q, double x, double y, double *out);

#endif
