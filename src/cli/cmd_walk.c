/* polarlux walk: frames along a camera path (README "Walking through a city"). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "options.h"
#include "port.h"
#include "frame_writer.h"
#include "png/image_write.h"
#include "walk_path.h"

static const char help[] =
    "usage: polarlux walk SCENE|BAKE --path CAMERA.geojson -o DIR [--size WxH] [--fps F]\n"
    "                     [--speed M/S] [--fov DEG] [--pitch DEG] [--aa N [--aa-full]]\n"
    "                     [--exposure E [--tone-curve]] [--no-adapt] [--no-glow]\n"
    "                     [--no-indirect] [--per-pixel] [--view street|aerial]\n"
    "                     [--max-frames N] [--texel M] [--threads N] [--photons N] [--frames K]\n"
    "                     [--refine [--refine-height M] [--refine-frames K]]\n"
    "                     [--mem SIZE] [--strict] [--quiet]\n"
    "\n"
    "Renders frames along a camera path, --speed / --fps metres apart and the last\n"
    "at the path's end, and writes DIR/frame-0001.png ..., DIR/cameras.txt (frame,\n"
    "eye, target in the scene's coordinates, exposure), DIR/walk.png\n"
    "(the frames as an animated PNG, 1/F s each, looping) and DIR/contact.png (a\n"
    "contact sheet of up to 16 frames), synced to disk together at the end.\n"
    "Everything is built once (or loaded from a bake) and\n"
    "reused by every frame: with indirect light each frame reads the radiance\n"
    "atlas (see render), filled as the frames need it or held by the bake.\n"
    "Prints the render time per frame (median, p95) and frames per second, and on\n"
    "stderr how many frames are entirely black and whether the frames\n"
    "render slower than --fps; on a terminal, a walk of more than a second shows\n"
    "the share of its frames done as it goes.\n"
    "\n"
    "  --path FILE      a GeoJSON LineString of eye positions [x, y] or [x, y, z]\n"
    "                   (z default 1.7 m); the eye looks 10 m ahead along the path,\n"
    "                   or at properties.targets (one [x, y] or [x, y, z] per\n"
    "                   position, z default 1.7 m, in the positions' coordinates);\n"
    "                   '-': standard input\n"
    "  --pitch DEG      no targets: look DEG (0-89) degrees down the path (default 0)\n"
    "  --size WxH       frame size (default 640x480)\n"
    "  --fps F          frames per second of the walk (default 25)\n"
    "  --speed M/S      walking speed along the path (default 1.4)\n"
    "  --fov DEG        vertical field of view (default 60)\n"
    "  --aa N           N x N samples per pixel (default 2; 1: pixel centres, SPEC §5),\n"
    "                   the later ones only at edges, as for render (--aa-full: all)\n"
    "  --exposure E     fixed exposure, no tone curve (--tone-curve: with it). Default:\n"
    "                   automatic, held while a frame's own choice stays within half\n"
    "                   a stop, else following it at about 4 stops a second (16 as\n"
    "                   it falls: no flicker);\n"
    "                   in cameras.txt, for render --tone-curve\n"
    "  --no-adapt       each frame's automatic exposure from its own image alone\n"
    "  --no-glow, --no-indirect, --per-pixel, --view V, --texel M, --photons N,\n"
    "  --frames K       as for render; the camera comes from the path, so --view\n"
    "                   aerial changes only the ground of frames shaded pixel by\n"
    "                   pixel (--per-pixel, --no-indirect), not those of the atlas\n"
    "  --max-frames N   at most N frames (default 1000)\n"
    "  --refine         near-viewer refinement (munoz2013 §3.3-3.4): before each frame\n"
    "                   the lamps near the ground point the view looks at (at most\n"
    "                   half the refinement radius ahead of the eye) get floor\n"
    "                   photon maps in an LRU cache.\n"
    "                   A miss changes the indirect light: the atlas is filled again\n"
    "                   as frames show it (a slower frame); hits keep it. A lamp\n"
    "                   refined for the first time restarts the aerial chart, and\n"
    "                   --refine-frames K photon frames (default 2) refill it.\n"
    "                   Prints the cache's hits, misses and evictions\n"
    "  --refine-height M  refine only the frames whose eye is at most M m above\n"
    "                   the ground (default 60; munoz2013 §3.3 refines low views\n"
    "                   only: from higher up a miss costs a slow frame for lamps\n"
    "                   the view hardly shows)\n"
    "  --threads N      threads for each frame (default: the processors);\n"
    "                   the same bytes for any N\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

typedef struct walk_args {
    const char *scene, *path, *dir;
    int w, h, aerial, refine;
    int no_adapt;              /* --no-adapt: each frame's exposure from its own image alone */
    double refine_height;
    long refine_frames;
    long max_frames;
    int max_frames_given;
    double fps, speed, fov;
    double pitch;              /* --pitch, degrees below level (no targets) */
    int pitch_set;
    plx_render_opts opts;
    cli_common c;
    cli_indirect ind;
} walk_args;

static int parse_rate(const char *val, void *dst)
{
    double *v = dst;
    return cli_parse_double(val, v) != 0 || !(*v > 0) || *v > 1e4 ? -1 : 0;
}

static int parse_pitch(const char *val, void *dst)
{
    return cli_parse_real(val, 0.0, 89.0, dst);
}

static int parse_texel(const char *val, void *dst)
{
    return cli_parse_real(val, 0.01, 1e4, dst);
}

static int parse_refine_frames(const char *val, void *dst)
{
    return cli_parse_int(val, 0, 100000, dst);
}

static int parse_max_frames(const char *val, void *dst)
{
    return cli_parse_int(val, 1, 1000000, dst);
}

static int parse_args(int argc, char **argv, walk_args *a)
{
    cli_view v;
    int rc, refine_frames_set = 0;
    const cli_opt opts[] = {
        CLI_OPT_STR("--path", &a->path),
        CLI_OPT_STR("-o", &a->dir),
        CLI_OPT_VAL("--fps", &a->fps, parse_rate, "--fps '%s' is not a number above 0, up to 1e4"),
        CLI_OPT_VAL("--speed", &a->speed, parse_rate, "--speed '%s' is not a number above 0, up to 1e4 (m/s)"),
        { "--exposure", NULL, &a->opts.exposure, cli_parse_exposure, "--exposure '%s' is not a number above 0, up to 1e9", 0, NULL,
          &v.exposure, NULL },
        { "--refine-frames", NULL, &a->refine_frames, parse_refine_frames,
          "--refine-frames '%s' is not a whole number from 0 to 100000", 0, NULL, &refine_frames_set, NULL },
        { "--max-frames", NULL, &a->max_frames, parse_max_frames,
          "--max-frames '%s' is not a whole number from 1 to 1000000", 0, NULL, &a->max_frames_given, NULL },
        CLI_OPT_FLAG("--no-adapt", &a->no_adapt),
        { "--pitch", NULL, &a->pitch, parse_pitch, "--pitch '%s' is not a number of degrees from 0 to 89", 0, NULL,
          &a->pitch_set, NULL },
        CLI_OPT_VAL("--texel", &a->opts.aerial_m_per_texel, parse_texel,
                    "--texel '%s' is not a number of metres from 0.01 to 1e4"),
        CLI_OPT_MORE(v.frag),
        CLI_OPT_END
    };
    cli_args pa;
    memset(a, 0, sizeof *a);
    cli_view_init(&v, 640, 480, 60, &a->opts, &a->ind);
    v.aa = 2;
    a->fps = 25;
    a->speed = 1.4;
    a->max_frames = 1000;
    a->refine_frames = 2;
    rc = cli_options_n("walk", help, argc, argv, opts, &a->c, &a->ind, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc;
    a->scene = pa.npos ? pa.pos[0] : NULL;
    a->w = (int)v.size[0];
    a->h = (int)v.size[1];
    a->fov = v.fov;
    if ((rc = cli_view_apply("walk", &v, &a->ind, &a->opts)) != EXIT_OK)
        return rc;
    if (a->no_adapt && v.exposure)
        cli_warn("walk", &a->c, "--no-adapt has no effect with --exposure (a fixed exposure does not adapt)");
    a->aerial = v.aerial;
    a->refine = v.refine;
    a->refine_height = v.refine_height;
    if (v.refine_height_set && !v.refine)
        cli_warn("walk", &a->c, "--refine-height has no effect without --refine");
    if (refine_frames_set && !v.refine)
        cli_warn("walk", &a->c, "--refine-frames has no effect without --refine");
    if (v.refine && a->ind.off)
        cli_warn("walk", &a->c, "--refine has no effect with --no-indirect (it refines the indirect light)");
    if (!a->scene)
        return cli_usage_error("walk", "missing SCENE");
    if (!a->path)
        return cli_usage_error("walk", "missing --path CAMERA.geojson");
    if (!a->dir)
        return cli_usage_error("walk", "missing -o DIR");
    if (strcmp(a->dir, "-") == 0) /* elsewhere '-' is standard input or output: never a folder named '-' */
        return cli_usage_error("walk", "-o names the folder for the frames: '-' (standard output) cannot hold "
                               "them; name a folder, e.g. -o ./-");
    return EXIT_OK;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* The contact sheet: up to 16 frames spread over the walk, 4 to a row,
 * each shrunk by an integer factor f (box filter) to at most 400 pixels
 * on its longer side (a portrait frame's height: a sheet of 768x1024
 * frames was 2.25 times the bytes of one of 1024x768 frames), drawn into
 * the sheet as each is rendered (the frames themselves are not kept). */
typedef struct sheet {
    uint8_t *px;               /* W x H x 3, NULL: none */
    int f, tw, th, W, H, n;    /* n: cells filled */
    int skipped;               /* 1: no sheet (the budget) */
} sheet;

/* The sheet's size with frames shrunk by f. */
static void sheet_size(sheet *sh, const walk_args *a, long frames, int f)
{
    int cells = frames < 16 ? (int)frames : 16, cols = cells < 4 ? cells : 4;
    sh->f = f;
    sh->tw = a->w / sh->f;
    sh->th = a->h / sh->f;
    sh->W = cols * sh->tw;
    sh->H = (cells + 3) / 4 * sh->th;
}

/* The frame's longer and shorter sides. */
static int long_side(const walk_args *a)
{
    return a->w > a->h ? a->w : a->h;
}

static int short_side(const walk_args *a)
{
    return a->w < a->h ? a->w : a->h;
}

/* The factor f shrinks the longer side to 400 pixels or less, and keeps
 * the shorter one at least a pixel (a 3x1600 frame: 3 pixels wide). */
static void sheet_plan(sheet *sh, const walk_args *a, long frames)
{
    int f;
    memset(sh, 0, sizeof *sh);
    for (f = 1; long_side(a) / f > 400 && f < short_side(a); f++)
        ;
    sheet_size(sh, a, frames, f);
}

/* A smaller sheet when the budget leaves too little room for the planned
 * one: frames shrunk further, down to 80 pixels on the longer side; 0
 * when even that does not fit. */
static int sheet_fit(sheet *sh, const walk_args *a, long frames, size_t room)
{
    int f = sh->f;
    while ((size_t)sh->W * sh->H * 3 > room) {
        if (long_side(a) / (f + 1) < 80 || f + 1 > short_side(a))
            return 0;
        sheet_size(sh, a, frames, ++f);
    }
    return 1;
}

/* Frame rgb shrunk into cell k. */
static void sheet_put(sheet *sh, const walk_args *a, const uint8_t *rgb, int k)
{
    int x, y, c, f = sh->f;
    for (y = 0; y < sh->th; y++)
        for (x = 0; x < sh->tw; x++)
            for (c = 0; c < 3; c++) {
                unsigned sum = 0;
                int i, j;
                for (j = 0; j < f; j++)
                    for (i = 0; i < f; i++)
                        sum += rgb[((size_t)(y * f + j) * a->w + (size_t)(x * f + i)) * 3 + c];
                sh->px[((size_t)((k / 4) * sh->th + y) * sh->W + (size_t)((k % 4) * sh->tw + x)) * 3 + c] =
                    (uint8_t)((sum + (unsigned)(f * f) / 2) / (unsigned)(f * f));
            }
}

static int contact_sheet(const walk_args *a, const sheet *sh, char *err, size_t errlen)
{
    char path[4096];
    if (!sh->px)
        return 0;
    snprintf(path, sizeof path, "%s/contact.png", a->dir);
    return image_write_png_frame(path, sh->W, sh->H, sh->px, 0, err, errlen);
}

/* APNG's frame delay num / den s (each 1 .. 65535) nearest x s: the last
 * convergent of x's continued fraction whose terms fit (1/30 for 30 fps,
 * 100/2997 for 29.97; it was rounded to whole ms, 33/1000), clamped to
 * 1/65535 .. 65535/1 s. */
static void delay_fraction(double x, unsigned *num, unsigned *den)
{
    double h1 = 1.0, h2 = 0.0, k1 = 0.0, k2 = 1.0, r = x;
    int i;
    *num = 1;
    *den = 65535;
    if (!(x > 1.0 / 65535.0)) /* also NaN */
        return;
    if (x >= 65535.0) {
        *num = 65535;
        *den = 1;
        return;
    }
    for (i = 0; i < 64; i++) {
        double a = floor(r), h = a * h1 + h2, k = a * k1 + k2;
        if (h > 65535.0 || k > 65535.0)
            break;
        if (h >= 1.0) {
            *num = (unsigned)h;
            *den = (unsigned)k;
        }
        h2 = h1;
        h1 = h;
        k2 = k1;
        k1 = k;
        if (!(r - a > 1e-12))
            break;
        r = 1.0 / (r - a);
    }
}

/* The animated PNG DIR/walk.png from the n frame files, 1/fps s each. */
static int animation(const walk_args *a, long n, char *err, size_t errlen)
{
    char path[4096], **names = calloc((size_t)n, sizeof *names);
    unsigned num, den;
    long k;
    int rc = -1;
    if (!names)
        return snprintf(err, errlen, "out of memory for the animation"), -1;
    delay_fraction(1.0 / a->fps, &num, &den);
    for (k = 0; k < n; k++) {
        names[k] = malloc(strlen(a->dir) + 32);
        if (!names[k])
            break;
        sprintf(names[k], "%s/frame-%04ld.png", a->dir, k + 1);
    }
    snprintf(path, sizeof path, "%s/walk.png", a->dir);
    if (k == n)
        rc = image_write_apng(path, (const char *const *)names, (int)n, num, den, err, errlen);
    else
        snprintf(err, errlen, "out of memory for the animation");
    for (k = 0; k < n; k++)
        free(names[k]);
    free(names);
    return rc;
}

typedef struct walk_run {
    long n;
    double *ms;
    uint8_t *rgb8;
    sheet sh;
    FILE *cams;
    char cams_name[4096];       /* its path, for messages */
    cli_refiner ref;           /* --refine */
    double refine_ms;
    uint64_t lookups;          /* indirect lookups, all frames */
    uint64_t aa_later;         /* pixels the later anti-aliasing samples shaded, all frames */
    long aa_adaptive, aa_dense; /* frames whose anti-aliasing was adaptive, took every sample for its edges */
    uint8_t *buf[2];           /* with the writer: frame k is rendered into buf[k & 1] */
    frame_writer fw;
    int writer;                /* 1: frames written on the writer's thread */
    long black, first_black;   /* frames entirely black, the eye outside buildings: how many,
                                  the first (1-based) */
    plx_camera black_cam;      /* the first one's camera, options and exposure */
    plx_render_opts black_opts;
    double black_exposure;
    long inside, first_inside; /* frames with the eye inside a building: how many, the first */
    long from_atlas;           /* frames that shaded no pixel: read from the radiance atlas, or of sky alone */
    long atlas_lit;            /* of which not black: some pixel read from the atlas */
    long nearly, first_nearly; /* frames nearly black (CLI_NEARLY_BLACK), not all: how many, the first */
    double inside_eye[3];      /* the first one's eye */
    double inside_ms;          /* their render times summed, ms */
    double bounds[4];          /* the scene's (plx_scene_info), taken once */
    int lonlat;                /* a lon/lat scene: cameras.txt in degrees */
    double held;               /* the last frame's exposure (automatic exposure, held near it) */
    double near_scene;         /* the least distance of an eye or target from bounds, m (0: inside) */
} walk_run;

/* An eye position as the user gave it: "(x, y, z)" in the scene's own
 * coordinates (lon/lat degrees to 7 places on a lon/lat scene, else
 * metres to 2), z in metres. */
static const char *eye_text(plx_engine *e, const double P[3], char *buf, size_t len)
{
    plx_scene_info si;
    double x = P[0], y = P[1];
    int ll = plx_scene_info_get(e, &si) == PLX_OK && si.lonlat;
    cli_from_local(e, &x, &y);
    snprintf(buf, len, ll ? "(%.7f, %.7f, %.2f)" : "(%.2f, %.2f, %.2f)", x, y, P[2]);
    return buf;
}

/* A black walk whose eyes and targets all stay farther than this from
 * the scene's bounds (the buildings' box and 50 m) is said to be outside
 * the scene, m. */
#define WALK_FAR_OUTSIDE 100.0

/* How far (x, y) lies from the box b (minx, miny, maxx, maxy), m; 0 inside. */
static double box_distance(const double b[4], double x, double y)
{
    double dx = x < b[0] ? b[0] - x : x > b[2] ? x - b[2] : 0.0;
    double dy = y < b[1] ? b[1] - y : y > b[3] ? y - b[3] : 0.0;
    return sqrt(dx * dx + dy * dy);
}

/* After the first frame (the engine at its peak): the frames are written
 * on a thread of their own, beside the next frame's rendering, when --mem
 * leaves room for a second frame buffer beside the first and the planned
 * contact sheet; else each frame is written before the next is rendered. */
static void writer_plan(const walk_args *a, plx_engine *e, walk_run *wr)
{
    size_t frame_bytes = (size_t)a->w * a->h * 3, sheet_bytes = (size_t)wr->sh.W * wr->sh.H * 3;
    if (wr->n < 2 || cli_buffer_budget(e, &a->c) < 2 * frame_bytes + sheet_bytes)
        return;
    wr->buf[0] = wr->rgb8;
    wr->buf[1] = malloc(frame_bytes);
    if (!wr->buf[1])
        return;
    if (frame_writer_start(&wr->fw, wr->cams, wr->cams_name) != 0) {
        free(wr->buf[1]);
        wr->buf[1] = NULL;
        return;
    }
    wr->writer = 1;
}

/* Frame k's PNG, then its line of cameras.txt: handed to the writer, or
 * written now. */
static int write_frame(const walk_args *a, walk_run *wr, long k, const char *line)
{
    char path[4096], err[512];
    snprintf(path, sizeof path, "%s/frame-%04ld.png", a->dir, k + 1);
    if (wr->writer) {
        if (frame_writer_put(&wr->fw, path, wr->rgb8, a->w, a->h, line) == 0)
            return EXIT_OK;
        fprintf(stderr, "polarlux walk: %s\n", wr->fw.err);
        return EXIT_FAIL;
    }
    if (image_write_png_frame(path, a->w, a->h, wr->rgb8, 0, err, sizeof err) != 0 ||
        frame_log_line(wr->cams, wr->cams_name, line, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux walk: %s\n", err);
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

/* The writer's last frame written and its thread ended (rc kept unless
 * that write failed). */
static int writer_end(walk_run *wr, int rc)
{
    int failed;
    if (!wr->writer)
        return rc;
    failed = frame_writer_stop(&wr->fw) != 0; /* first: it may still read buf[1] */
    wr->writer = 0;
    wr->rgb8 = wr->buf[0];
    free(wr->buf[1]);
    wr->buf[1] = NULL;
    if (failed && rc == EXIT_OK) {
        fprintf(stderr, "polarlux walk: %s\n", wr->fw.err);
        return EXIT_FAIL;
    }
    return rc;
}

/* DIR/cameras.txt opened and its header written, once the first frame
 * rendered: a walk whose first frame fails leaves an earlier walk's file
 * as it was. */
static int cams_open(const walk_args *a, walk_run *wr)
{
    snprintf(wr->cams_name, sizeof wr->cams_name, "%s/cameras.txt", a->dir);
    if (!(wr->cams = fopen(wr->cams_name, "w"))) {
        fprintf(stderr, "polarlux walk: %s: cannot write: %s\n", wr->cams_name, strerror(errno));
        return -1;
    }
    if (wr->lonlat)
        fprintf(wr->cams, "# frame eye_lon eye_lat eye_z target_lon target_lat target_z exposure (degrees; z in m)\n");
    else
        fprintf(wr->cams, "# frame eye_x eye_y eye_z target_x target_y target_z exposure\n");
    return 0;
}

/* DIR/cameras.txt closed, its writes checked (rc kept unless they
 * failed). */
static int cams_close(const walk_args *a, walk_run *wr, int rc)
{
    int e = 0, earlier;
    if (!wr->cams)
        return rc;
    if (fflush(wr->cams) != 0)
        e = errno;
    earlier = ferror(wr->cams); /* a write before: its errno is gone */
    if (fclose(wr->cams) != 0 && !e)
        e = errno;
    wr->cams = NULL;
    if ((e || earlier) && rc == EXIT_OK) {
        fprintf(stderr, "polarlux walk: %s/cameras.txt: cannot write: %s\n", a->dir,
                e ? strerror(e) : "a write failed");
        return EXIT_FAIL;
    }
    return rc;
}

/* How fast a walk's held exposure follows the view, stops a second (of
 * the walk's time, --fps frames a second): a few dozen bright pixels at a
 * frame's edge moved it 3.5 stops for one frame and back at 25 fps. */
#define WALK_ADAPT_STOPS 4.0 /* rising; falling 4 times as fast (EXPOSURE_FALL) */

/* Frame k's place along the path: k steps, the last frame at the path's
 * end when the steps do not reach it (a flight's landing ended a step
 * short, in the air). */
static double frame_at(long k, double step, double L)
{
    return fmin((double)k * step, L);
}

static int frame(const walk_args *a, plx_engine *e, const walk_path *wp, walk_run *wr, long k, double s)
{
    plx_camera cam;
    plx_render_info info;
    plx_render_opts o;
    unsigned long long t0;
    plx_status st;
    int had_atlas = 0, black;
    char line[320];
    memset(&cam, 0, sizeof cam);
    walk_path_camera(wp, s, cam.eye, cam.target);
    {
        double d = fmin(box_distance(wr->bounds, cam.eye[0], cam.eye[1]),
                        box_distance(wr->bounds, cam.target[0], cam.target[1]));
        wr->near_scene = k == 0 || d < wr->near_scene ? d : wr->near_scene;
    }
    cam.fov_deg = a->fov;
    cam.width = a->w;
    cam.height = a->h;
    if (a->refine && !a->ind.off) {
        int rc;
        t0 = port_now_ns();
        rc = cli_refine("walk", e, &cam, &wr->ref);
        wr->refine_ms += (port_now_ns() - t0) / 1e6;
        if (rc != EXIT_OK)
            return rc;
    }
    if (wr->writer) /* the other buffer: the writer may still read the last frame */
        wr->rgb8 = wr->buf[k & 1];
    o = a->opts;
    if (o.auto_exposure == PLX_EXPOSURE_AUTO && !a->no_adapt && k > 0) { /* held from the last frame */
        double eighths = floor(8.0 * WALK_ADAPT_STOPS / a->fps + 0.5); /* the most a frame */
        o.auto_exposure = PLX_EXPOSURE_ADAPT;
        o.exposure = wr->held;
        o.exposure_step = eighths < 1.0 ? 1 : eighths > PLX_EXPOSURE_STEP_MAX ? PLX_EXPOSURE_STEP_MAX : (int)eighths;
    }
    if (k == 0)
        had_atlas = cli_atlas_made(e);
    t0 = port_now_ns();
    st = plx_render(e, &cam, &o, wr->rgb8, NULL, &info);
    wr->ms[k] = (port_now_ns() - t0) / 1e6;
    if (st == PLX_OK && k == 0)
        cli_atlas_note("walk", &a->c, e, had_atlas, a->opts.aerial_m_per_texel);
    wr->lookups += info.indirect_lookups;
    wr->aa_later += info.aa_later;
    if (st == PLX_OK) {
        wr->aa_adaptive += info.aa_adaptive == PLX_AA_ADAPTIVE;
        wr->aa_dense += info.aa_adaptive == PLX_AA_DENSE;
    }
    wr->held = info.exposure;
    if (st == PLX_OK && k == 0) {
        cli_aa_warn("walk", &a->c, &a->opts, &info);
        if (cams_open(a, wr) != 0)
            return EXIT_FAIL;
    }
    if (st != PLX_OK) {
        char at[96], why[512], hint[400];
        /* the error first: eye_text asks the engine again, which clears it */
        snprintf(why, sizeof why, "%s", plx_last_error(e));
        fprintf(stderr, "polarlux walk: frame %ld at %s: %s%s\n", k + 1, eye_text(e, cam.eye, at, sizeof at), why,
                cli_render_nomem_hint(st, &a->opts, e, hint, sizeof hint));
        return cli_exit_code(st);
    }
    /* black with the eye inside a building: its own warning says why */
    black = !info.eye_inside && cli_all_black(wr->rgb8, (size_t)a->w * a->h * 3);
    if (black && wr->black++ == 0) {
        wr->first_black = k + 1;
        wr->black_cam = cam;
        wr->black_opts = o; /* the frame's own: held (_ADAPT) after the first */
        wr->black_exposure = info.exposure;
    }
    if (!info.eye_inside && !black && cli_black_share(wr->rgb8, (size_t)a->w * a->h) >= CLI_NEARLY_BLACK &&
        wr->nearly++ == 0)
        wr->first_nearly = k + 1;
    /* no pixel shaded: read from the radiance atlas, or sky alone (a
     * black frame: it shades nothing either) */
    if (info.shaded_pixels == 0 && !info.eye_inside) {
        wr->from_atlas++;
        wr->atlas_lit += !black;
    }
    if (info.eye_inside && wr->inside++ == 0) {
        wr->first_inside = k + 1;
        memcpy(wr->inside_eye, cam.eye, sizeof wr->inside_eye);
    }
    {
        /* in the scene's own coordinates (lon/lat on a lon/lat scene), as
         * render --eye and --target take them; written once the frame is */
        double ex = cam.eye[0], ey = cam.eye[1], tx = cam.target[0], ty = cam.target[1];
        cli_from_local(e, &ex, &ey);
        cli_from_local(e, &tx, &ty);
        snprintf(line, sizeof line, "%ld %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", k + 1, ex, ey, cam.eye[2], tx,
                 ty, cam.target[2], info.exposure);
    }
    if (k == 0)
        writer_plan(a, e, wr);
    if (wr->sh.n < 16 && k == (wr->n >= 16 ? (wr->sh.n * (wr->n - 1)) / 15 : wr->sh.n)) {
        if (!wr->sh.px && !wr->sh.skipped) {
            /* the command's own buffers count in --mem: the frame and the sheet */
            size_t need = (size_t)wr->sh.W * wr->sh.H * 3, frame_bytes = (size_t)a->w * a->h * 3 * (wr->writer ? 2 : 1);
            size_t budget = cli_buffer_budget(e, &a->c), room = budget > frame_bytes ? budget - frame_bytes : 0;
            int f = wr->sh.f;
            if (!sheet_fit(&wr->sh, a, wr->n, room) || !(wr->sh.px = calloc((size_t)wr->sh.W * wr->sh.H * 3, 1))) {
                char old[4096];
                struct stat sb;
                int left;
                snprintf(old, sizeof old, "%s/contact.png", a->dir);
                left = stat(old, &sb) == 0; /* an earlier walk's */
                if (!a->c.quiet)
                    fprintf(stderr, "polarlux walk: no contact sheet: it needs %.2f MB beside the engine and the "
                            "frame (%.2f MB with frames %d pixels wide), and --mem leaves %.2f MB%s%s%s\n",
                            need / 1e6, (double)wr->sh.W * wr->sh.H * 3 / 1e6, wr->sh.tw, room / 1e6,
                            left ? "; " : "", left ? old : "", left ? " is an earlier walk's, left as it was" : "");
                wr->sh.skipped = 1;
            } else if (wr->sh.f != f && !a->c.quiet) {
                fprintf(stderr, "polarlux walk: contact sheet with frames %d pixels wide (not %d) to fit --mem: "
                        "%.1f MB left beside the engine and the frame\n", wr->sh.tw, a->w / f, room / 1e6);
            }
        }
        if (wr->sh.px)
            sheet_put(&wr->sh, a, wr->rgb8, wr->sh.n);
        wr->sh.n++;
    }
    return write_frame(a, wr, k, line);
}

/* A path whose eye stays this high, drawn as street views without the
 * radiance atlas: a word on stderr (metres above the ground). Frames that
 * read the atlas (indirect light, no --per-pixel) take as long either way
 * (the bench's 700 m flight: 21.8 ms as street views, 22.4 ms with
 * --view aerial), so they get no word. Without it, the street view's
 * ground takes the per-pixel path (93 ms a 1024x768 frame of that flight)
 * and --view aerial reads the aerial light map (73 ms), which the first
 * frame builds unless the bake holds it (0.32 to 0.34 s for that city,
 * measured with walk --max-frames 1). */
#define WALK_HIGH 100.0

static void view_hint(const walk_args *a, const walk_path *wp)
{
    double zmin = HUGE_VAL, zmax = 0.0;
    uint32_t k;
    for (k = 0; k < wp->n; k++)
        zmax = fmax(zmax, wp->eye[3 * k + 2]);
    if (!wp->target && !(a->pitch > 0.0) && zmax >= WALK_HIGH) /* a flight's frames of sky: said whatever the view */
        cli_warn("walk", &a->c, "the eye rises to %.0f m and looks level, 10 m ahead along the path at its own "
                 "height: the city is below those frames; --pitch DEG looks down along the path, "
                 "properties.targets (one [x, y, z] a position) aim the camera", zmax);
    if (a->aerial || (!a->ind.off && !a->opts.per_pixel))
        return;
    for (k = 0; k < wp->n; k++)
        zmin = fmin(zmin, wp->eye[3 * k + 2]);
    if (zmin >= WALK_HIGH)
        cli_warn("walk", &a->c, "the eye stays %.0f m or more above the ground: --view aerial draws views "
                 "from above faster (the ground and roofs from the aerial light map)", zmin);
}

/* The refinement's line, and a word when the eye was too high for it. */
static void walk_refine_print(const walk_args *a, const walk_run *wr)
{
    const plx_refine_stats *rs = &wr->ref.rs;
    if (wr->ref.high == wr->n) {
        cli_warn("walk", &a->c, "--refine: the eye was above --refine-height %g m at every frame, so no lamp was "
                 "refined (munoz2013 refines only low views; a larger --refine-height refines from higher up)",
                 a->refine_height);
        return;
    }
    printf("refinement: %llu hits, %llu misses, %llu evictions, %llu lamps refined (%u slots, %.0f m); "
           "%ld refill photon frames; %.1f ms in all (floor maps and refill frames)", (unsigned long long)rs->hits,
           (unsigned long long)rs->misses, (unsigned long long)rs->evictions, (unsigned long long)rs->refined,
           rs->slots, rs->near_radius, wr->ref.refills, wr->refine_ms);
    if (wr->ref.high)
        printf("; %ld of %ld frames above --refine-height %g m not refined", wr->ref.high, wr->n,
               a->refine_height);
    printf("\n");
}

/* A word when DIR already holds the frame after this walk's last (an
 * earlier, longer walk's): the folder would mix the two walks' frames. */
static void stale_hint(const walk_args *a, long n)
{
    char path[4096];
    FILE *f;
    snprintf(path, sizeof path, "%s/frame-%04ld.png", a->dir, n + 1);
    if (!(f = fopen(path, "rb")))
        return;
    fclose(f);
    cli_warn("walk", &a->c, "%s holds %s and maybe later frames from an earlier walk: this walk writes frames 1 "
             "to %ld and leaves them", a->dir, path + strlen(a->dir) + 1, n);
}

/* Whether the frames with the eye inside a building are why a walk falls
 * behind: most frames are such, or the others alone keep up at fps (their
 * mean within a frame's time; 10 of 21 inside at 3.7 s each fell behind
 * while the others took 25 ms, and the advice named --aa and --size). */
static int behind_inside(const walk_run *wr, double fps)
{
    long out = wr->n - wr->inside, k;
    double sum = 0.0;
    if (wr->inside == 0)
        return 0;
    if (2 * wr->inside >= wr->n)
        return 1;
    for (k = 0; k < wr->n; k++)
        sum += wr->ms[k];
    sum -= wr->inside_ms;
    if (wr->first_inside != 1 && out > 1) { /* as the warning: not the first, which fills a scene's atlas */
        sum -= wr->ms[0];
        out--;
    }
    return sum / (double)out <= 1000.0 / fps;
}

/* A word at the first frame with the eye inside a building, as it comes
 * (the walk's end counts them all): such frames are computed pixel by
 * pixel, seconds each on a large city, and a walk of hundreds of them
 * ran for minutes without a word. Below the progress line, if shown. */
static void inside_now(const walk_args *a, plx_engine *e, const walk_run *wr, cli_progress *pr)
{
    char at[96];
    if (a->c.quiet)
        return;
    cli_progress_end(pr);
    cli_warn("walk", &a->c, "frame %ld at %s: the eye is inside a building: such frames show the inside of its "
             "walls, every pixel computed (%.0f ms this one); move the path out of the footprints or raise it above "
             "the roofs", wr->first_inside, eye_text(e, wr->inside_eye, at, sizeof at), wr->ms[wr->first_inside - 1]);
}

/* The walk's frames; *done: how many were written. */
static int run(const walk_args *a, plx_engine *e, const walk_path *wp, long *done)
{
    walk_run wr;
    cli_progress pr;
    double L = walk_path_length(wp), step = a->speed / a->fps, steps, *sorted;
    char err[512];
    int rc = EXIT_OK, batch;
    long k;
    memset(&wr, 0, sizeof wr);
    /* the frames, sheet and cameras.txt synced together at the end */
    if ((batch = safe_out_batch_begin(a->dir, err, sizeof err)) < 0) {
        fprintf(stderr, "polarlux walk: %s\n", err);
        *done = 0;
        return EXIT_FAIL;
    }
    cli_refiner_init(&wr.ref, a->refine_height, a->refine_frames, a->ind.photons);
    view_hint(a, wp);
    if (!walk_path_moves(wp))
        cli_warn("walk", &a->c, "the path never moves horizontally and has no properties.targets: the camera "
                 "looks east (+x); give targets to aim it");
    /* compared as a double: a long path at a slow pace has more steps
     * than a long holds, and converting such a double is undefined */
    steps = floor(L / step) + 1.0;
    if (L - (steps - 1.0) * step > 1e-9 * fmax(L, 1.0)) /* and one at the end */
        steps += 1.0;
    wr.n = steps < (double)a->max_frames ? (long)steps : a->max_frames;
    if (steps > (double)a->max_frames) {
        char all[40];
        if (steps < 1e15) /* whole digits, not 1.786e+04 */
            snprintf(all, sizeof all, "%.0f", steps);
        else
            snprintf(all, sizeof all, "more than 10^15");
        cli_warn("walk", &a->c, "--max-frames %ld%s stops the walk at %.1f m of the path's %.1f m (%s frames "
                 "would walk it all)", a->max_frames, a->max_frames_given ? "" : " (the default)",
                 frame_at(wr.n - 1, step, L), L, all);
    }
    stale_hint(a, wr.n);
    sheet_plan(&wr.sh, a, wr.n);
    wr.ms = malloc(sizeof *wr.ms * (size_t)wr.n);
    sorted = malloc(sizeof *sorted * (size_t)wr.n);
    wr.rgb8 = malloc((size_t)a->w * a->h * 3);
    if (!wr.ms || !sorted || !wr.rgb8) {
        fprintf(stderr, "polarlux walk: out of memory for %ld frames of %dx%d\n", wr.n, a->w, a->h);
        rc = EXIT_FAIL;
    } else {
        plx_scene_info si;
        int ok = plx_scene_info_get(e, &si) == PLX_OK;
        wr.bounds[0] = wr.bounds[1] = -HUGE_VAL; /* unknown: every eye inside, no outside warning */
        wr.bounds[2] = wr.bounds[3] = HUGE_VAL;
        if (ok)
            memcpy(wr.bounds, si.bounds, sizeof wr.bounds);
        wr.lonlat = ok && si.lonlat;
    }
    cli_progress_start(&pr); /* a line on a terminal, after a second */
    for (k = 0; rc == EXIT_OK && k < wr.n; k++) {
        long inside = wr.inside;
        rc = frame(a, e, wp, &wr, k, frame_at(k, step, L));
        if (wr.inside > inside && rc == EXIT_OK)
            wr.inside_ms += wr.ms[k];
        if (wr.inside == 1 && inside == 0)
            inside_now(a, e, &wr, &pr);
        cli_progress_step(&pr, "walk", (size_t)k + 1, (size_t)wr.n);
    }
    *done = rc == EXIT_OK ? k : k - 1;
    cli_progress_end(&pr);
    rc = writer_end(&wr, rc);
    if (rc == EXIT_OK && contact_sheet(a, &wr.sh, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux walk: %s\n", err);
        rc = EXIT_FAIL;
    }
    if (rc == EXIT_OK && animation(a, wr.n, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux walk: %s\n", err);
        rc = EXIT_FAIL;
    }
    rc = cams_close(a, &wr, rc);
    if (safe_out_batch_end(batch, a->dir, *done > 0, err, sizeof err) != 0 && rc == EXIT_OK) {
        fprintf(stderr, "polarlux walk: %s\n", err);
        rc = EXIT_FAIL;
    }
    if (rc == EXIT_OK) {
        double med, p95, sum = 0;
        char why[200]; /* the frames are written (writer_end): cli_black_reason may draw into wr.rgb8 */
        memcpy(sorted, wr.ms, sizeof *sorted * (size_t)wr.n);
        qsort(sorted, (size_t)wr.n, sizeof *sorted, cmp_double);
        for (k = 0; k < wr.n; k++)
            sum += sorted[k];
        /* the middle frame, or the mean of the two middle ones */
        med = wr.n % 2 ? sorted[wr.n / 2] : 0.5 * (sorted[wr.n / 2 - 1] + sorted[wr.n / 2]);
        p95 = sorted[(size_t)ceil(0.95 * wr.n) - 1];
        printf("walk: %ld frame%s %dx%d (%.1f m of %.1f m at %g m/s, %g fps, aa %d), written to %s%s\n", wr.n,
               wr.n == 1 ? "" : "s", a->w, a->h, frame_at(wr.n - 1, step, L), L, a->speed, a->fps,
               a->opts.aa > 1 ? a->opts.aa : 1, a->dir,
               a->dir[0] && a->dir[strlen(a->dir) - 1] == '/' ? "" : "/"); /* "DIR/" as given, one slash */
        printf("frame time: median %.2f ms, p95 %.2f ms, mean %.2f ms: %.1f frames per second (rendering only",
               med, p95, sum / wr.n, 1000.0 * wr.n / sum);
        if (wr.n >= 3 && wr.ms[0] > 2.0 * med && wr.ms[0] > med + 20.0) /* the atlas filled in the first frame */
            printf("; the first frame %.1f ms, the %ld after it %.1f frames per second", wr.ms[0], wr.n - 1,
                   1000.0 * (wr.n - 1) / (sum - wr.ms[0]));
        printf(")\n");
        if (wr.lookups)
            printf("indirect light: %.0f lookups a frame on average, for %.0f samples (the pixels' first and "
                   "the later ones taken)\n", (double)wr.lookups / wr.n,
                   (double)a->w * a->h + (double)wr.aa_later / wr.n);
        cli_aa_print(&a->opts, wr.aa_later, (double)a->w * a->h * wr.n, wr.n, wr.aa_adaptive, wr.aa_dense);
        if (a->refine && !a->ind.off)
            walk_refine_print(a, &wr);
        /* shown as they are made, the frames would fall behind: by the
         * median or by the mean after the first (3 frames at least: a walk
         * from a scene fills the atlas in its first; the median alone let a
         * few slow frames pass while the rate printed was under --fps) */
        if (wr.n >= 3 && (med > 1000.0 / a->fps || (sum - wr.ms[0]) / (wr.n - 1) > 1000.0 / a->fps))
            cli_warn("walk", &a->c, "the frames took %.1f ms (median; mean after the first %.1f ms) to render, "
                     "longer than a frame lasts at %g fps (%.1f ms): shown as they are made, they fall behind on "
                     "this machine; %s%s",
                     med, (sum - wr.ms[0]) / (wr.n - 1), a->fps, 1000.0 / a->fps,
                     behind_inside(&wr, a->fps) ? "the frames with the eye inside a building (below), computed "
                                                  "pixel by pixel, take the time"
                     : a->opts.aa > 1      ? "--aa 1 (one sample a pixel), a smaller --size or a lower --fps keep up"
                                           : "a smaller --size or a lower --fps keep up",
                     a->c.mem_given ? "; a larger --mem may too (near the smallest block, the lamps' lit "
                                      "regions and the radiance atlas find no room)"
                                    : "");
        if (wr.inside) {
            char at[96];
            cli_warn("walk", &a->c, "%ld of %ld frames have the eye inside a building (the first: frame %ld at "
                     "%s): they show the inside of its walls, every pixel computed (slower); "
                     "move the path out of the footprints or raise it above the roofs", wr.inside, wr.n,
                     wr.first_inside, eye_text(e, wr.inside_eye, at, sizeof at));
        }
        if (a->aerial && wr.from_atlas == wr.n && wr.atlas_lit > 0 && !a->ind.off && !a->opts.no_indirect &&
            !a->opts.per_pixel && cli_atlas_made(e))
            cli_warn("walk", &a->c, "--view aerial changed nothing: the camera comes from the path, and every frame "
                     "was read from the radiance atlas, the same for any view (--view aerial picks the aerial light "
                     "map for the ground of frames shaded pixel by pixel: --per-pixel, --no-indirect)");
        if (wr.black == wr.n && wr.near_scene > WALK_FAR_OUTSIDE && cli_has_lamps(e))
            cli_warn("walk", &a->c, "every frame is entirely black: the camera path stays outside the scene, its "
                     "eyes and targets %.0f m or more from the scene's bounds (its buildings' box and 50 m); is the "
                     "path in the scene's coordinates?", wr.near_scene);
        else if (wr.black == wr.n)
            cli_warn("walk", &a->c, "every frame is entirely black: %s",
                     cli_black_reason(e, &wr.black_cam, &wr.black_opts, wr.black_exposure, wr.rgb8, why, sizeof why));
        else if (wr.black)
            cli_warn("walk", &a->c, "%ld of %ld frames are entirely black (the first: frame %ld): %s", wr.black,
                     wr.n, wr.first_black,
                     cli_black_reason(e, &wr.black_cam, &wr.black_opts, wr.black_exposure, wr.rgb8, why, sizeof why));
        if (wr.nearly)
            cli_warn("walk", &a->c, "%ld of %ld frames are nearly black, %.0f%% of their pixels or more (the first: "
                     "frame %ld): %s", wr.nearly, wr.n, 100.0 * CLI_NEARLY_BLACK, wr.first_nearly,
                     CLI_NEARLY_BLACK_WHY);
    }
    free(wr.sh.px);
    free(wr.ms);
    free(sorted);
    free(wr.rgb8);
    return rc;
}

static int is_folder(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

int cmd_walk(int argc, char **argv)
{
    walk_args a;
    walk_path wp;
    plx_engine *e;
    char err[600];
    int made = 0;
    long done = 0;
    int rc = parse_args(argc, argv, &a);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (strlen(a.dir) > 4000) /* its files' names are made in 4096 bytes */
        return cli_usage_error("walk", "-o: the folder's path is longer than 4000 bytes");
    if (mkdir(a.dir, 0755) == 0) {
        made = 1; /* removed again if the walk fails before its first frame (rmdir: only when empty) */
    } else if (errno != EEXIST) {
        fprintf(stderr, "polarlux walk: %s: cannot create the folder: %s\n", a.dir, strerror(errno));
        return EXIT_FAIL;
    }
    if (!is_folder(a.dir)) {
        fprintf(stderr, "polarlux walk: %s: not a folder (-o names the folder the frames go to)\n", a.dir);
        return EXIT_FAIL;
    }
    a.c.render_w = a.w;
    a.c.render_h = a.h;
    a.c.atlas_room = !a.opts.no_indirect && !a.opts.per_pixel;
    rc = cli_open_scene("walk", a.scene, &a.c, &e);
    if (rc != EXIT_OK) {
        if (made)
            (void)rmdir(a.dir);
        return rc;
    }
    if (walk_path_read(a.path, e, &wp, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux walk: %s\n", err);
        plx_engine_free(e);
        if (made)
            (void)rmdir(a.dir);
        return EXIT_FAIL;
    }
    if (wp.lines > 1)
        cli_warn("walk", &a.c, "%s holds %u line features: the walk follows the first LineString (%.1f m), the "
                 "others are left out", a.path, wp.lines, walk_path_length(&wp));
    if (a.pitch_set && wp.target)
        cli_warn("walk", &a.c, "--pitch has no effect: %s has properties.targets, which aim the camera", a.path);
    else
        wp.pitch_tan = tan(a.pitch * (3.14159265358979323846 / 180.0));
    if (cli_bake_direct("walk", a.scene, &a.c, e, &a.ind))
        a.opts.no_indirect = 1;
    cli_bake_kept("walk", a.scene, &a.c, e, &a.ind, a.opts.aerial_m_per_texel);
    rc = cli_indirect_run("walk", &a.c, e, &a.ind, NULL, NULL, a.fov);
    if (rc == EXIT_OK)
        rc = run(&a, e, &wp, &done);
    walk_path_free(&wp);
    plx_engine_free(e);
    if (rc != EXIT_OK && done <= 0 && made) { /* no frame written in the folder it made: removed */
        char path[4096];
        snprintf(path, sizeof path, "%s/cameras.txt", a.dir);
        (void)remove(path);
        (void)rmdir(a.dir);
    }
    return rc;
}
