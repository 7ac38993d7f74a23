#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <cjson/cJSON.h>

#include "cli.h"
#include "posix/safe_out.h"
#include "base/jsonscan.h"
#include "lamp_layer.h"
#include "points.h"
#include <math.h>
#include "port.h"
#include "png/image_write.h"
#include <unistd.h>

int cli_usage_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "polarlux %s: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, " (see 'polarlux %s --help')\n", cmd);
    return EXIT_USAGE;
}

size_t cli_parse_size(const char *s)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (errno || end == s || !(v > 0))
        return 0;
    switch (*end) {
    case 'k': case 'K': v *= 1024.0; end++; break;
    case 'm': case 'M': v *= 1024.0 * 1024.0; end++; break;
    case 'g': case 'G': v *= 1024.0 * 1024.0 * 1024.0; end++; break;
    case 't': case 'T': v *= 1024.0 * 1024.0 * 1024.0 * 1024.0; end++; break;
    default: break;
    }
    if ((*end == 'i' || *end == 'I') && strchr("kKmMgGtT", end[-1])) /* 1GiB: binary, as 1G */
        end++;
    if (*end == 'B' || *end == 'b')
        end++;
    if (*end != '\0' || v > 1e15)
        return 0;
    return (size_t)v;
}

int cli_parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return (errno || end == s || *end != '\0' || !isfinite(*out)) ? -1 : 0;
}

int cli_parse_real(const char *s, double lo, double hi, double *out)
{
    return cli_parse_double(s, out) != 0 || !(*out >= lo && *out <= hi) ? -1 : 0;
}

const char *cli_render_nomem_hint(plx_status st, const plx_render_opts *o, plx_engine *e, char *buf, size_t len)
{
    plx_memory_report mr;
    if (st != PLX_E_NOMEM)
        return "";
    plx_memory_get(e, &mr);
    /* a bake's frame buffers are its --max-size's whatever --size asks */
    snprintf(buf, len, " (give a larger --mem: the block holds %zu bytes; or %s%s)", mr.capacity,
             cli_bake_last.loaded ? "bake with a smaller --max-size (a bake's frames take their buffers at it)"
                                  : "a smaller --size",
             o->aa > 1 ? "; anti-aliasing takes 20 bytes a pixel more of the largest frame, a bake's --max-size, "
                         "and --aa 1 none" : "");
    return buf;
}

int cli_parse_exposure(const char *s, void *out)
{
    double *v = out;
    return cli_parse_real(s, 0.0, 1e9, v) != 0 || !(*v > 0.0) ? -1 : 0;
}

int cli_parse_coords(const char *s, double *v, int n)
{
    const char *p = s;
    int k;
    for (k = 0; k < n; k++) {
        char buf[64];
        const char *comma = k + 1 < n ? strchr(p, ',') : p + strlen(p);
        size_t len = comma ? (size_t)(comma - p) : 0;
        if (!comma || len == 0 || len >= sizeof buf)
            return -1;
        memcpy(buf, p, len);
        buf[len] = '\0';
        if (cli_parse_real(buf, -CLI_MAX_COORD, CLI_MAX_COORD, &v[k]) != 0)
            return -1;
        p = comma + 1;
    }
    return 0;
}

int cli_parse_int(const char *s, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    *out = strtol(s, &end, 10);
    return (errno || end == s || *end != '\0' || *out < lo || *out > hi) ? -1 : 0;
}

int cli_common_option(const char *cmd, int argc, char **argv, int *i, cli_common *c)
{
    const char *a = argv[*i];
    if (strcmp(a, "--strict") == 0) {
        c->strict = 1;
        return 1;
    }
    if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
        c->quiet = 1;
        return 1;
    }
    if (strcmp(a, "--points-crs") == 0) {
        if (*i + 1 >= argc) {
            cli_usage_error(cmd, "--points-crs needs lonlat, local or the scene's CRS name");
            return -1;
        }
        c->points_crs = argv[++*i];
        return 1;
    }
    if (strcmp(a, "--lamps") == 0) {
        if (*i + 1 >= argc) {
            cli_usage_error(cmd, "--lamps needs a GeoJSON or CSV file of lamps");
            return -1;
        }
        if (argv[*i + 1][0] == '\0') {
            cli_usage_error(cmd, "--lamps needs a file name, not an empty string");
            return -1;
        }
        if (c->nlamp_files == CLI_MAX_LAMP_FILES) {
            cli_usage_error(cmd, "at most %d --lamps files", CLI_MAX_LAMP_FILES);
            return -1;
        }
        c->lamp_files[c->nlamp_files++] = argv[++*i];
        return 1;
    }
    if (strcmp(a, "--threads") == 0) {
        char *end = NULL;
        long n = *i + 1 < argc ? strtol(argv[*i + 1], &end, 10) : 0;
        if (*i + 1 >= argc || end == argv[*i + 1] || *end != '\0' || n < 1 || n > PLX_MAX_THREADS) {
            cli_usage_error(cmd, "--threads needs a number of threads from 1 to %d", PLX_MAX_THREADS);
            return -1;
        }
        ++*i;
        c->threads = (int)n;
        return 1;
    }
    if (strcmp(a, "--mem") == 0) {
        if (*i + 1 >= argc) {
            cli_usage_error(cmd, "--mem needs a size, e.g. --mem 512M");
            return -1;
        }
        c->mem = cli_parse_size(argv[++*i]);
        c->mem_given = 1;
        if (c->mem < PLX_ENGINE_MIN_BYTES) {
            cli_usage_error(cmd, "--mem '%s' is not a size from %d bytes to 1e15 (a number with K, M, G or T, "
                            "powers of 1024, e.g. 512M, 2G, 2GiB)", argv[*i], PLX_ENGINE_MIN_BYTES);
            return -1;
        }
        return 1;
    }
    return 0;
}

int cli_exit_code(plx_status s)
{
    if (s == PLX_OK)
        return EXIT_OK;
    if (s == PLX_E_NOMEM)
        return EXIT_NOMEM;
    if (s == PLX_E_INVALID)
        return EXIT_USAGE;
    return EXIT_FAIL;
}

static void quiet_log(void *ctx, plx_log_level level, const char *msg)
{
    (void)ctx;
    if (level == PLX_LOG_ERROR)
        fprintf(stderr, "polarlux: error: %s\n", msg);
}

/* The scene's ground image (properties.ground_image, a path relative to the
 * scene file's folder unless absolute) read and given to the engine.
 * Prints the error and returns an exit code on failure. */
static int load_ground_image(const char *cmd, const char *scene_path, plx_engine *e, size_t mem)
{
    plx_ground_image_info gi;
    const char *slash;
    char *full;
    size_t dir;
    uint8_t *px = NULL;
    int w = 0, h = 0, rc;
    char err[600];
    plx_status st;
    if (plx_ground_image_get(e, &gi) != PLX_OK || !gi.path)
        return EXIT_OK;
    slash = strrchr(scene_path, '/');
    dir = gi.path[0] == '/' || !slash ? 0 : (size_t)(slash - scene_path) + 1;
    full = malloc(dir + strlen(gi.path) + 1);
    if (!full) {
        fprintf(stderr, "polarlux %s: %s: out of memory for the ground image path\n", cmd, scene_path);
        return EXIT_FAIL;
    }
    memcpy(full, scene_path, dir);
    strcpy(full + dir, gi.path);
    /* the decoded pixels count against --mem before they are decoded */
    rc = image_read_png_budget(full, 16384, mem, &px, &w, &h, err, sizeof err);
    if (rc != 0) {
        fprintf(stderr, "polarlux %s: %s: ground image '%s': %s%s\n", cmd, scene_path, gi.path, err,
                rc == -2 ? "; give it more with --mem" : "");
        free(full);
        return rc == -2 ? EXIT_NOMEM : EXIT_FAIL;
    }
    st = plx_set_ground_image(e, (uint32_t)w, (uint32_t)h, px, NULL);
    free(px);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: %s: ground image '%s' (%s): %s\n", cmd, scene_path, gi.path, full,
                plx_last_error(e));
        if (st == PLX_E_NOMEM)
            fprintf(stderr, "polarlux %s: give the engine more memory with --mem (now %zu bytes)\n", cmd, mem);
        free(full);
        return st == PLX_E_NOMEM ? EXIT_NOMEM : EXIT_FAIL;
    }
    free(full);
    return EXIT_OK;
}

/* A whole photometry file (port_read_text: opened as every other input,
 * a FIFO, device or folder refused at once), at most 64 MiB; NULL with
 * why. */
static char *read_photometry(const char *path, size_t *len, char *why, size_t whylen)
{
    struct stat sb;
    if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode) && (unsigned long long)sb.st_size > (64ull << 20)) {
        snprintf(why, whylen, "%llu bytes, more than a photometry file's 64 MiB", (unsigned long long)sb.st_size);
        return NULL;
    }
    return port_read_text(path, len, why, whylen);
}

/* The photometry files the scene's lamps name (properties.photometry,
 * relative to the scene file's folder unless absolute), read and given to
 * the engine (SPEC §2.1). Prints the error and returns an exit code. */
static int load_photometry(const char *cmd, const char *scene_path, plx_engine *e)
{
    uint32_t k, n = plx_photometry_count(e);
    const char *slash = strrchr(scene_path, '/');
    for (k = 0; k < n; k++) {
        const char *p;
        char *full, *data, why[160];
        size_t dir, len = 0;
        plx_status st;
        if (plx_photometry_path(e, k, &p) != PLX_OK)
            return EXIT_FAIL;
        dir = p[0] == '/' || !slash ? 0 : (size_t)(slash - scene_path) + 1;
        full = malloc(dir + strlen(p) + 1);
        if (!full)
            return EXIT_NOMEM;
        memcpy(full, scene_path, dir);
        strcpy(full + dir, p);
        data = read_photometry(full, &len, why, sizeof why);
        if (!data) {
            fprintf(stderr, "polarlux %s: %s: photometry file %s: %s\n", cmd, scene_path, full, why);
            free(full);
            return EXIT_FAIL;
        }
        st = plx_set_photometry(e, p, data, len, full);
        free(data);
        free(full);
        if (st != PLX_OK) {
            fprintf(stderr, "polarlux %s: %s: %s\n", cmd, scene_path, plx_last_error(e));
            return st == PLX_E_NOMEM ? EXIT_NOMEM : EXIT_FAIL;
        }
    }
    return EXIT_OK;
}

void cli_warn(const char *cmd, const cli_common *c, const char *fmt, ...)
{
    va_list ap;
    if (c && c->quiet)
        return;
    fprintf(stderr, "polarlux %s: warning: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n");
}

void cli_light_note(const char *cmd, const cli_common *c, plx_engine *e)
{
    uint64_t frames = plx_indirect_frames(e);
    if (c && c->quiet)
        return;
    if (frames > 0)
        fprintf(stderr, "polarlux %s: note: the ground's lux (E_h) are direct + indirect light (%llu photon "
                        "frames); Ev and Esc are direct light\n", cmd, (unsigned long long)frames);
    else if (cli_bake_last.loaded)
        fprintf(stderr, "polarlux %s: note: the lux are direct light only (the bake holds no photon buffers: %s)\n",
                cmd, cli_has_lamps(e) ? "baked with --no-indirect or --frames 0" : "its scene has no lamps");
    else
        fprintf(stderr, "polarlux %s: note: the lux are direct light only (no photon buffers: a bake of the scene "
                        "adds indirect light to E_h)\n", cmd);
}

void cli_shortest(double v, char *out, size_t len)
{
    int p;
    for (p = 1; p <= 17; p++) {
        snprintf(out, len, "%.*g", p, v);
        if (strtod(out, NULL) == v)
            break;
    }
    /* %g's exponent form of a whole number (100 as "1e+02": its digits fewer
     * than its exponent, so v is that whole number): plain digits instead,
     * the same double */
    if (strstr(out, "e+") && fabs(v) < 1e17)
        snprintf(out, len, "%.0f", v);
}

void cli_point_error(const char *cmd, const char *file, size_t line, const double *given, const double *local,
                     plx_engine *e)
{
    const char *msg = plx_last_error(e), *close = strstr(msg, ") ");
    char gx[32], gy[32];
    if ((given[0] == local[0] && given[1] == local[1]) || strncmp(msg, "point (", 7) != 0 || !close) {
        fprintf(stderr, "polarlux %s: %s:%zu: %s\n", cmd, file, line, msg);
        return;
    }
    /* the library's "point (x, y[, z]) why" in local metres: the point as
     * the file gave it first */
    cli_shortest(given[0], gx, sizeof gx);
    cli_shortest(given[1], gy, sizeof gy);
    fprintf(stderr, "polarlux %s: %s:%zu: point %s %s (local %.*s m) %s\n", cmd, file, line, gx, gy,
            (int)(close - (msg + 7)), msg + 7, close + 2);
}

/* Commands whose results are light: they say so when the scene has none. */
static int computes_light(const char *cmd)
{
    static const char *const names[] = { "illum", "lit", "heatmap", "render", "route", "dark-spots", "meter",
                                         "walk", "tiles", "annotate", "bake" };
    size_t i;
    for (i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strcmp(cmd, names[i]) == 0)
            return 1;
    return 0;
}

/* A bake (baked 1) takes no --lamps: its lamps come from 'polarlux bake'. */
static void note_no_lamps(const char *cmd, const char *path, const cli_common *c, plx_engine *e, int baked)
{
    plx_scene_info si;
    if (!computes_light(cmd) || plx_scene_info_get(e, &si) != PLX_OK || si.lamps > 0)
        return;
    if (baked)
        cli_warn(cmd, c, "%s has no lamps, so every result is dark (0 lx); bake a scene with lamps "
                 "(Point features with \"lamp\": true, or 'polarlux bake SCENE --lamps FILE')", path);
    else
        cli_warn(cmd, c, "%s has no lamps%s, so every result is dark (0 lx); add lamps as Point features "
                 "with \"lamp\": true, or from another file with --lamps FILE", path,
                 si.skipped_lamps ? " (all were left out, see the warnings above)" : "");
}

int cli_all_black(const uint8_t *px, size_t n)
{
    size_t k;
    for (k = 0; k < n && px[k] == 0; k++)
        ;
    return k == n;
}

int cli_other_ext(const char *path, const char *ext)
{
    const char *base = strrchr(path, '/'), *dot;
    size_t k;
    base = base ? base + 1 : path;
    dot = strrchr(base, '.');
    if (!dot || dot == base)
        return 0;
    for (k = 0; ext[k] && dot[1 + k]; k++)
        if (tolower((unsigned char)dot[1 + k]) != ext[k])
            return 1;
    return ext[k] != '\0' || dot[1 + k] != '\0';
}

int cli_out_ext(const char *cmd, const char *opt, const char *path, const char *ext, const char *what)
{
    if (!path || !cli_other_ext(path, ext))
        return 1;
    cli_usage_error(cmd, "%s '%s': the file is written as %s (.%s); name it so", opt, path, what, ext);
    return 0;
}

int cli_out_writable(const char *cmd, const char *path)
{
    struct stat st;
    char err[512];
    safe_out *o;
    if (!path || strcmp(path, "-") == 0 || (stat(path, &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)))
        return 1;
    o = safe_out_open(path, err, sizeof err);
    if (!o) {
        fprintf(stderr, "polarlux %s: %s\n", cmd, err);
        return 0;
    }
    safe_out_abort(o);
    return 1;
}

double cli_black_share(const uint8_t *rgb, size_t npx)
{
    size_t k, black = 0;
    for (k = 0; k < npx; k++)
        black += (rgb[3 * k] | rgb[3 * k + 1] | rgb[3 * k + 2]) == 0;
    return npx ? (double)black / (double)npx : 1.0;
}

double cli_white_share(const uint8_t *rgb, size_t npx)
{
    size_t k, lit = 0, white = 0;
    for (k = 0; k < npx; k++) {
        lit += (rgb[3 * k] | rgb[3 * k + 1] | rgb[3 * k + 2]) != 0;
        white += (rgb[3 * k] & rgb[3 * k + 1] & rgb[3 * k + 2]) == 255;
    }
    return lit ? (double)white / (double)lit : 0.0;
}

int cli_atlas_made(plx_engine *e)
{
    plx_atlas_info ai;
    return plx_atlas_info_get(e, &ai) == PLX_OK && ai.made;
}

int cli_has_lamps(plx_engine *e)
{
    plx_scene_info si;
    return plx_scene_info_get(e, &si) == PLX_OK && si.lamps > 0;
}

/* Whether some lamp gives light: an intensity above 0 cd (a photometric
 * lamp's is its dimming times its table's peak). */
static int lamps_shine(plx_engine *e)
{
    plx_scene_info si;
    plx_lamp l;
    uint32_t i;
    if (plx_scene_info_get(e, &si) != PLX_OK)
        return 1;
    for (i = 0; i < si.lamps; i++)
        if (plx_lamp_get(e, i, &l) != PLX_OK || l.intensity > 0.0)
            return 1;
    return 0;
}

const char *cli_dark_reason(plx_engine *e)
{
    if (!cli_has_lamps(e))
        return "the scene has no lamps";
    if (!lamps_shine(e))
        return "every lamp gives no light (0 cd: an intensity or dimming of 0, or a photometry file whose "
               "candelas or multiplier are 0; 'polarlux info' lists their flux)";
    return "no lamp's light reaches it (each lamp lights only within its radius, and buildings cast shadows)";
}

/* Whether the camera looks up, level or less than about 11 degrees down. */
static int looks_up(const plx_camera *cam)
{
    double dz = cam->target[2] - cam->eye[2];
    return dz > -0.2 * hypot(cam->target[0] - cam->eye[0], cam->target[1] - cam->eye[1]);
}

const char *cli_black_reason(plx_engine *e, const plx_camera *cam, const plx_render_opts *o, double applied,
                             unsigned char *rgb8, char *buf, size_t len)
{
    plx_render_opts ao = *o;
    plx_render_info info;
    if (!rgb8)
        return cli_dark_reason(e);
    ao.auto_exposure = PLX_EXPOSURE_AUTO; /* the frame's own exposure: what is there to see */
    if (plx_render(e, cam, &ao, rgb8, NULL, &info) != PLX_OK)
        return cli_dark_reason(e);
    if (!cli_all_black(rgb8, (size_t)cam->width * cam->height * 3) && o->auto_exposure != PLX_EXPOSURE_AUTO) {
        if (o->auto_exposure == PLX_EXPOSURE_ADAPT)
            snprintf(buf, len, "its exposure %.4g, held from the frames before and following the view at a few "
                     "stops a second, is too low for it (its own: %.4g; --no-adapt takes each frame's own)",
                     applied, info.exposure);
        else
            snprintf(buf, len, "--exposure %g maps the light there to black (automatic exposure, without "
                     "--exposure, chooses %.4g)", o->exposure, info.exposure);
        return buf;
    }
    if (!cli_has_lamps(e))
        return cli_dark_reason(e);
    if (info.exposure == PLX_EXPOSURE_MAX) { /* only lit surfaces make the cap */
        snprintf(buf, len, "its light is under about 0.001 cd/m^2, where automatic exposure stops (at %g; "
                 "--exposure E brightens it)", PLX_EXPOSURE_MAX);
        return buf;
    }
    if (info.drawn == 0 && looks_up(cam)) {
        snprintf(buf, len, "the camera sees no building and no lit ground: it looks away from the city, or "
                 "level from high up (--target, or a walk path's properties.targets, aims it)");
        return buf;
    }
    if (info.drawn == 0) { /* looking down on ground no lamp reaches: past the city's edge (a kiosk pass's
                            * flight was told that no lamp's light reached it) */
        snprintf(buf, len, "the camera sees no building and no lit ground: it looks down past the city's edge "
                 "(--target, or a walk path's properties.targets, aims it)");
        return buf;
    }
    return cli_dark_reason(e);
}

/* The command's progress line for the core's long stages (plx_port.progress):
 * the workers' units summed under a lock, shown as cli_progress shows a
 * loop of the command's own (a terminal only, after a second). */
static struct {
    pthread_mutex_t lock;
    cli_progress pr;
    uint64_t done;
    int on;
} stage = { PTHREAD_MUTEX_INITIALIZER, { 0, 0, 0, 0 }, 0, 0 };

static void stage_progress(void *ctx, const char *what, uint64_t n, uint64_t total)
{
    (void)ctx;
    pthread_mutex_lock(&stage.lock);
    if (total == 0) {
        if (stage.on)
            cli_progress_end(&stage.pr);
        stage.on = 0;
    } else if (n == 0) {
        cli_progress_start(&stage.pr);
        stage.done = 0;
        stage.on = 1;
    } else if (stage.on) {
        stage.done += n;
        cli_progress_step(&stage.pr, what, (size_t)stage.done, (size_t)total);
    }
    pthread_mutex_unlock(&stage.lock);
}

void cli_config(const cli_common *c, plx_config *cfg)
{
    static plx_port port;
    plx_config_default(cfg);
    port = *plx_port_posix();
    if (c->quiet)
        port.log = quiet_log;
    else
        port.progress = stage_progress;
    cfg->port = &port;
    cfg->strict = c->strict;
    cfg->render_max_width = c->render_w;
    cfg->render_max_height = c->render_h;
    cfg->threads = c->threads;
}

cli_bake_state cli_bake_last;

int cli_is_bake(const char *path)
{
    char head[8];
    struct stat sb;
    FILE *f;
    int yes;
    /* only a regular file can be a bake: a FIFO or device is left to the
     * scene reader, which refuses it without waiting on it */
    if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode) || !(f = fopen(path, "rb")))
        return 0;
    yes = fread(head, 1, 8, f) == 8 && memcmp(head, "PLXBAKE", 8) == 0;
    fclose(f);
    return yes;
}

/* A regular file named *.plxb whose first byte cannot start a JSON text
 * (after a byte-order mark and white space, '{' or '['): a bake whose
 * magic is damaged, which
 * the bake reader refuses as such (the scene reader said "malformed JSON
 * at byte 0"). */
static int damaged_bake(const char *path)
{
    size_t n = strlen(path);
    struct stat sb;
    FILE *f;
    int ch;
    if (n < 5 || strcmp(path + n - 5, ".plxb") != 0 || stat(path, &sb) != 0 || !S_ISREG(sb.st_mode) ||
        !(f = fopen(path, "rb")))
        return 0;
    ch = fgetc(f);
    if (ch == 0xEF && fgetc(f) == 0xBB && fgetc(f) == 0xBF) /* a UTF-8 byte-order mark, as the reader skips */
        ch = fgetc(f);
    while (ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r')
        ch = fgetc(f);
    fclose(f);
    return ch != EOF && ch != '{' && ch != '[';
}

/* A bake file read through plx_bake_load_read (the command's memory
 * stays the block: the file is not held beside it): its descriptor, and
 * why the last read failed. */
typedef struct bake_in {
    int fd;
    char why[160];
} bake_in;

static int bake_read(void *user, uint64_t off, void *buf, size_t n)
{
    bake_in *b = user;
    unsigned char *p = buf;
    while (n > 0) {
        ssize_t r = pread(b->fd, p, n, (off_t)off);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0) {
            snprintf(b->why, sizeof b->why, "%s", r < 0 ? strerror(errno) : "the file shrank");
            return -1;
        }
        p += r;
        off += (uint64_t)r;
        n -= (size_t)r;
    }
    return 0;
}

/* A bake's error line: the library's, with the read's reason after a
 * failed read. */
static void bake_say(const char *cmd, const char *path, plx_status st, const char *err, const bake_in *in)
{
    fprintf(stderr, "polarlux %s: %s: %s%s%s\n", cmd, path, err, st == PLX_E_IO && in->why[0] ? ": " : "",
            st == PLX_E_IO ? in->why : "");
}

/* The bake read into the block mem of need bytes (freed when the load
 * fails), the reason said on stderr when it cannot be. */
static plx_status load_bake_in(const char *cmd, const char *path, void *mem, size_t need, const plx_config *cfg,
                               bake_in *in, uint64_t len, plx_engine **e)
{
    char err[512];
    plx_status st;
    in->why[0] = '\0';
    st = plx_bake_load_read(mem, need, cfg, bake_read, in, len, e, err, sizeof err);
    if (st != PLX_OK) {
        bake_say(cmd, path, st, err, in);
        free(mem);
    }
    return st;
}

/* The block a bake without its atlas is loaded in again (no --mem): a
 * quarter of it for the atlas at its most, and that much free beside the
 * image of need bytes. */
static size_t atlas_block(size_t need)
{
    return need + PLX_ATLAS_MAX_BYTES > CLI_ATLAS_BLOCK ? need + PLX_ATLAS_MAX_BYTES : CLI_ATLAS_BLOCK;
}

/* Whether a loaded bake holds its radiance atlas, or holds no indirect
 * light (its frames shade every pixel anyway). */
static int bake_has_atlas(plx_engine *e)
{
    return plx_indirect_frames(e) == 0 || cli_atlas_made(e);
}

/* The block size of the bake read through in, after the whole file is
 * checked (through a buffer of the command's own, freed before any block
 * is taken): a damaged file's verdict. */
static plx_status block_size_checked(bake_in *in, uint64_t len, size_t *need, char *err, size_t errlen)
{
    void *scratch = malloc(CLI_BAKE_SCRATCH);
    plx_status st = plx_bake_block_size_read(bake_read, in, len, scratch, scratch ? CLI_BAKE_SCRATCH : 0, need, err,
                                             errlen);
    free(scratch);
    return st;
}

/* The bake read through in (len bytes) into a block of its own: mem
 * bytes (--mem), else the size the header asks for, the whole file
 * checked first when that block is far beyond the file (more than 64
 * times it and a GiB: a damaged size field asked for 4.6e18 bytes, which
 * a sanitizer build does not even try to take) or cannot be had; the load
 * checks the file as it reads it. *need: the block's size. On failure a
 * status and its reason in msg (the library's line, with a failed read's
 * cause after it). */
static plx_status load_into_block(bake_in *in, size_t len, size_t mem, const plx_config *cfg, plx_engine **e,
                                  size_t *need, char *msg, size_t msglen)
{
    char err[512];
    void *block = NULL;
    plx_status st = PLX_OK;
    *need = mem;
    if (!mem) {
        st = plx_bake_block_size_read(bake_read, in, len, NULL, 0, need, err, sizeof err);
        if (st == PLX_OK && *need / 64 <= len + ((size_t)1 << 24))
            block = cli_big_alloc(*need);
        if (st == PLX_OK && !block)
            st = block_size_checked(in, len, need, err, sizeof err);
        if (st != PLX_OK) {
            snprintf(msg, msglen, "%s", err);
            return st;
        }
    }
    if (!block && !(block = cli_big_alloc(*need))) {
        snprintf(msg, msglen, "cannot take a block of %zu bytes for the bake", *need);
        return PLX_E_NOMEM;
    }
    in->why[0] = '\0';
    st = plx_bake_load_read(block, *need, cfg, bake_read, in, len, e, err, sizeof err);
    if (st != PLX_OK) {
        snprintf(msg, msglen, "%s%s%s", err, st == PLX_E_IO && in->why[0] ? ": " : "", st == PLX_E_IO ? in->why : "");
        free(block);
    }
    return st;
}

/* An engine from a bake file: the file read through the library's
 * reads into the block sized by the bake (or --mem), its pointers
 * relocated. */
static int open_bake(const char *cmd, const char *path, const cli_common *c, plx_engine **e)
{
    char msg[1024];
    size_t len, need;
    void *big = NULL;
    bake_in in;
    plx_config cfg;
    plx_status st;
    unsigned char head[16];
    unsigned long long t0 = port_now_ns();
    in.why[0] = '\0';
    in.fd = port_open_input(path, &len, msg, sizeof msg);
    if (in.fd < 0) {
        fprintf(stderr, "polarlux %s: %s: %s\n", cmd, path, msg);
        return EXIT_FAIL;
    }
    if (bake_read(&in, 24, head, sizeof head) != 0)
        memset(head, 0, sizeof head); /* too short: the load says so */
    cli_config(c, &cfg);
    st = load_into_block(&in, len, c->mem, &cfg, e, &need, msg, sizeof msg);
    if (st != PLX_OK)
        fprintf(stderr, "polarlux %s: %s: %s\n", cmd, path, msg);
    if (st == PLX_OK && c->atlas_room && !c->mem && !bake_has_atlas(*e) && (big = cli_big_alloc(atlas_block(need)))) {
        /* no --mem, and the bake holds no radiance atlas (--no-aerial):
         * again in a block whose quarter holds the atlas at its finest,
         * as a scene's default block does, not at the 4 m the bake's own
         * size left (its pages are taken as the atlas fills them); kept
         * as loaded when that block cannot be had */
        plx_engine_free(*e);
        *e = NULL;
        st = load_bake_in(cmd, path, big, atlas_block(need), &cfg, &in, len, e);
    }
    close(in.fd);
    if (st != PLX_OK)
        return st == PLX_E_NOMEM ? EXIT_NOMEM : EXIT_FAIL;
    cli_bake_last.loaded = 1;
    cli_bake_last.bytes = len;
    cli_bake_last.load_ns = port_now_ns() - t0;
    memcpy(cli_bake_last.head, head, sizeof head);
    note_no_lamps(cmd, path, c, *e, 1);
    return EXIT_OK;
}

/* Whether the bake at in still has the header bytes 24-39 of the first load. */
static int twin_same_file(bake_in *in)
{
    unsigned char head[16];
    return bake_read(in, 24, head, sizeof head) == 0 && memcmp(head, cli_bake_last.head, sizeof head) == 0;
}

int cli_open_twin(const char *path, const cli_common *c, plx_engine **e, char *why, size_t whylen)
{
    char err[512];
    size_t len, need;
    bake_in in;
    plx_config cfg;
    plx_status st;
    cli_common quiet = *c;
    int changed;
    *e = NULL;
    if (!cli_bake_last.loaded) {
        snprintf(why, whylen, "the scene was not loaded from a bake");
        return EXIT_FAIL;
    }
    in.why[0] = '\0';
    if ((in.fd = port_open_input(path, &len, err, sizeof err)) < 0) {
        snprintf(why, whylen, "%s", err);
        return EXIT_FAIL;
    }
    quiet.quiet = 1;
    cli_config(&quiet, &cfg);
    changed = !twin_same_file(&in);
    st = changed ? PLX_E_INVALID : load_into_block(&in, len, c->mem, &cfg, e, &need, why, whylen);
    if (st == PLX_OK && !twin_same_file(&in)) { /* changed as it was read: its checksum held, but another file's */
        plx_engine_free(*e);
        *e = NULL;
        changed = 1;
        st = PLX_E_INVALID;
    }
    if (changed)
        snprintf(why, whylen, "the file changed since it was loaded");
    close(in.fd);
    return st == PLX_OK ? EXIT_OK : cli_exit_code(st);
}

int cli_open_scene(const char *cmd, const char *path, const cli_common *c, plx_engine **e)
{
    plx_config cfg;
    plx_status st;
    memset(&cli_bake_last, 0, sizeof cli_bake_last); /* this scene's (commands run in one process: test_tiles) */
    if (cli_is_bake(path) || damaged_bake(path)) {
        if (c->nlamp_files > 0) {
            fprintf(stderr, "polarlux %s: %s: --lamps cannot be added to a bake file; give them to 'polarlux bake'\n",
                    cmd, path);
            return EXIT_USAGE;
        }
        return open_bake(cmd, path, c, e);
    }
    cli_config(c, &cfg);
    st = plx_engine_new(c->mem ? c->mem : CLI_DEFAULT_MEM, &cfg, e);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: cannot create an engine of %zu bytes: %s\n", cmd,
                c->mem ? c->mem : CLI_DEFAULT_MEM, plx_strerror(st));
        return cli_exit_code(st);
    }
    return cli_load_scene(cmd, path, c, e);
}

int cli_load_scene(const char *cmd, const char *path, const cli_common *c, plx_engine **e)
{
    int rc, k;
    plx_status st;
    struct stat sb;
    if (strcmp(path, "-") == 0 && stat(path, &sb) != 0) { /* '-' reads standard input for paths and points */
        fprintf(stderr, "polarlux %s: SCENE '-': a scene is not read from standard input; give its file "
                "(./- for a file named '-')\n", cmd);
        plx_engine_free(*e);
        *e = NULL;
        return EXIT_USAGE;
    }
    st = plx_load_file(*e, path);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: %s\n", cmd, plx_last_error(*e));
        if (st == PLX_E_NOMEM)
            fprintf(stderr, "polarlux %s: give the engine more memory with --mem (now %zu bytes)\n",
                    cmd, c->mem ? c->mem : CLI_DEFAULT_MEM);
        plx_engine_free(*e);
        *e = NULL;
        return st == PLX_E_INVALID ? EXIT_FAIL : cli_exit_code(st);
    }
    rc = load_ground_image(cmd, path, *e, c->mem ? c->mem : CLI_DEFAULT_MEM);
    if (rc == EXIT_OK)
        rc = load_photometry(cmd, path, *e);
    if (rc != EXIT_OK) {
        plx_engine_free(*e);
        *e = NULL;
        return rc;
    }
    for (k = 0; k < c->nlamp_files; k++) {
        rc = lamp_layer_add(cmd, c->lamp_files[k], *e, c->quiet);
        if (rc != EXIT_OK) {
            plx_engine_free(*e);
            *e = NULL;
            return rc;
        }
    }
    note_no_lamps(cmd, path, c, *e, 0);
    return rc;
}

void cli_indirect_default(cli_indirect *ind)
{
    ind->photons = 65536;
    ind->frames = 4; /* 262,144 photons for images: they carry only the later bounces,
                        the irradiance cache gathers the first from the exact direct light
                        (README, "Indirect light"); illum sets CLI_GATHER_FRAMES */
    ind->frames_given = 0;
    ind->photons_given = 0;
    ind->per_lamp = 0;
    ind->off = 0;
    ind->gather = -1;
}

int cli_indirect_option(const char *cmd, int argc, char **argv, int *i, cli_indirect *ind)
{
    const char *a = argv[*i];
    if (strcmp(a, "--no-indirect") == 0) {
        ind->off = 1;
        return 1;
    }
    if (strcmp(a, "--gather") == 0) {
        if (*i + 1 >= argc || cli_parse_int(argv[++*i], 0, 1024, &ind->gather)) {
            cli_usage_error(cmd, "--gather needs a whole number from 0 to 1024");
            return -1;
        }
        return 1;
    }
    if (strcmp(a, "--photons") != 0 && strcmp(a, "--frames") != 0)
        return 0;
    if (*i + 1 >= argc) {
        cli_usage_error(cmd, "%s needs a number", a);
        return -1;
    }
    if (strcmp(a, "--photons") == 0 ? cli_parse_int(argv[++*i], 1, 100000000, &ind->photons)
                                    : cli_parse_int(argv[++*i], 0, 100000, &ind->frames)) {
        cli_usage_error(cmd, "%s '%s' is not a whole number from %s", a, argv[*i],
                        strcmp(a, "--photons") == 0 ? "1 to 100000000" : "0 to 100000");
        return -1;
    }
    ind->frames_given |= strcmp(a, "--frames") == 0;
    ind->photons_given |= strcmp(a, "--photons") == 0;
    return 1;
}

int cli_bake_direct(const char *cmd, const char *path, const cli_common *c, plx_engine *e, cli_indirect *ind)
{
    /* cli_open_scene says whether it loaded a bake: the file is not read again */
    if (ind->off || plx_indirect_frames(e) > 0 || !cli_bake_last.loaded)
        return 0;
    ind->off = 1;
    if (!cli_has_lamps(e)) /* nothing to trace: the dark scene's own warnings say so */
        return 1;
    cli_warn(cmd, c, "%s holds no indirect light (baked with --no-indirect or --frames 0): its images show the "
             "direct light; bake the scene without those options for indirect light", path);
    return 1;
}

void cli_bake_kept(const char *cmd, const char *path, const cli_common *c, plx_engine *e, const cli_indirect *ind,
                   double texel)
{
    plx_atlas_info ai;
    if (!cli_bake_last.loaded)
        return;
    if (!ind->off && plx_indirect_frames(e) > 0 && (ind->photons_given || ind->frames_given))
        cli_warn(cmd, c, "%s%s%s%s not used: %s holds its photon buffers (bake again to change them)",
                 ind->photons_given ? "--photons" : "", ind->photons_given && ind->frames_given ? " and " : "",
                 ind->frames_given ? "--frames" : "", ind->photons_given && ind->frames_given ? " are" : " is",
                 path);
    if (texel > 0.0 && plx_atlas_info_get(e, &ai) == PLX_OK && ai.made)
        cli_warn(cmd, c, "--texel is not used: %s holds its radiance atlas, %.2f m between its points (bake again "
                 "with --texel to change it)", path, ai.spacing);
}

/* A word on stderr when the photon buffers were made smaller than the
 * default quality to fit --mem (README "Memory budgets"). */
void cli_indirect_note(const char *cmd, const cli_common *c, plx_engine *e)
{
    plx_indirect_info pi;
    if ((c && c->quiet) || plx_indirect_info_get(e, &pi) != PLX_OK || pi.reductions == 0)
        return;
    fprintf(stderr,
            "polarlux %s: indirect light at reduced quality %s: photon buffers %.1f MiB "
            "instead of %.1f (%u steps: facade charts %ux%u, aerial chart %ux%u texels of %.1f m, "
            "%u lamp floor maps, lamp ray tables %s)\n",
            cmd, cli_bake_last.loaded ? "as the bake was made (to fit its --mem when baked)" : "to fit --mem",
            pi.bytes / 1048576.0, pi.full_bytes / 1048576.0, pi.reductions, pi.chart_w, pi.chart_h,
            pi.aerial_w, pi.aerial_h, pi.aerial_texel, pi.lamp_slots, pi.lamp_tables ? "on" : "off");
}

void cli_atlas_note(const char *cmd, const cli_common *c, plx_engine *e, int had, double texel)
{
    plx_atlas_info ai;
    plx_memory_report mr;
    double asked = texel > 0.0 ? texel : PLX_ATLAS_SPACING_DEFAULT;
    if ((c && c->quiet) || had || plx_atlas_info_get(e, &ai) != PLX_OK || !ai.made || !(ai.spacing > asked * 1.001))
        return;
    plx_memory_get(e, &mr);
    if (mr.capacity / 4 >= PLX_ATLAS_MAX_BYTES / 100 * 99) /* the atlas's own ceiling set it (the block's
                                                              usable bytes are a little under --mem) */
        return;
    fprintf(stderr,
            "polarlux %s: radiance atlas at reduced quality to fit %s: points %.2f m apart instead of %.2f "
            "(%.2f m where only indirect light reaches), in a quarter of the block (%.1f MiB); lamp pools and "
            "shadow edges are blurred at that scale: a larger --mem for finer points (the atlas takes at most "
            "%d MiB, from a block of %d MiB)\n",
            cmd, cli_bake_last.loaded ? "the block beside the bake" : "the block", ai.spacing, asked, ai.coarse,
            mr.capacity / 4 / 1048576.0, (int)(PLX_ATLAS_MAX_BYTES >> 20), (int)(4 * (PLX_ATLAS_MAX_BYTES >> 20)));
}

void cli_json_error(const char *name, const char *text, size_t len, char *err, size_t errlen)
{
    const char *at = cJSON_GetErrorPtr(), *tail;
    size_t off = jsonscan_error_at(text, len, at && at >= text ? (size_t)(at - text) : len, &tail);
    uint32_t line, col;
    jsonscan_line_col(text, len, off, &line, &col);
    if (off < len && (text[off] == '[' || text[off] == '{') && jsonscan_depth_at(text, len, off) >= JSONSCAN_DEPTH)
        snprintf(err, errlen, "%s: JSON nested deeper than %d levels at byte %zu (line %lu, column %lu)", name,
                 JSONSCAN_DEPTH, off, (unsigned long)line, (unsigned long)col); /* the scene loader's words */
    else
        snprintf(err, errlen, "%s: malformed JSON at byte %zu (line %lu, column %lu)%s", name, off,
                 (unsigned long)line, (unsigned long)col, tail);
}

cJSON *cli_json_parse(const char *name, const char *text, size_t len, char *err, size_t errlen)
{
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    size_t off;
    uint32_t line, col;
    if (!root) {
        cli_json_error(name, text, len, err, errlen);
        return NULL;
    }
    off = jsonscan_trailing(text, len, end && end >= text ? (size_t)(end - text) : len);
    if (off == len)
        return root;
    cJSON_Delete(root); /* more after the value: the scene loader's rule */
    jsonscan_line_col(text, len, off, &line, &col);
    snprintf(err, errlen, "%s: malformed JSON at byte %zu (line %lu, column %lu)", name, off, (unsigned long)line,
             (unsigned long)col);
    return NULL;
}

long cli_photons(plx_engine *e, const cli_indirect *ind)
{
    plx_scene_info si;
    long n;
    if (ind->photons_given || !ind->per_lamp || plx_scene_info_get(e, &si) != PLX_OK)
        return ind->photons;
    if (si.lamps > CLI_PHOTONS_MAX / CLI_PHOTONS_PER_LAMP) /* clamped before the product: no overflow */
        return CLI_PHOTONS_MAX;
    n = (long)si.lamps * CLI_PHOTONS_PER_LAMP;
    return n < CLI_PHOTONS_MIN ? CLI_PHOTONS_MIN : n;
}

/* What takes less when the photon buffers ran out of memory (a walk in
 * --mem 1M said only that they did). */
static const char *photons_hint(plx_status st)
{
    return st == PLX_E_NOMEM ? " (--no-indirect needs no photon buffers: direct light alone; or give a larger --mem)"
                             : "";
}

int cli_indirect_run(const char *cmd, const cli_common *c, plx_engine *e, const cli_indirect *ind,
                     const double *eye, const double *dir, double fov_deg)
{
    long k, photons = cli_photons(e, ind);
    int tty = isatty(2);
    unsigned long long t0 = port_now_ns();
    if (!ind->off && ind->frames == 0 && plx_indirect_frames(e) == 0 && strcmp(cmd, "bake") != 0)
        cli_warn(cmd, c, "--frames 0 traces no photons: no indirect light, as with --no-indirect"); /* bake says */
    if (ind->off || ind->frames == 0 || plx_indirect_frames(e) > 0)
        return EXIT_OK; /* off, or traced already (a bake) */
    if ((double)photons * (double)ind->frames > CLI_MAX_PHOTONS)
        return ind->photons_given
                   ? cli_usage_error(cmd, "--photons %ld x --frames %ld is more than %.0f photons", photons,
                                     ind->frames, CLI_MAX_PHOTONS)
                   : cli_usage_error(cmd, "%ld photons a frame (16 a lamp; --photons sets it) x --frames %ld is "
                                     "more than %.0f photons", photons, ind->frames, CLI_MAX_PHOTONS);
    if (ind->gather >= 0 && plx_indirect_set_gather(e, (uint32_t)ind->gather) != PLX_OK) {
        fprintf(stderr, "polarlux %s: %s\n", cmd, plx_last_error(e));
        return EXIT_USAGE;
    }
    if (eye) {
        plx_status st = plx_indirect_set_viewer(e, eye, dir, fov_deg);
        if (st != PLX_OK) {
            fprintf(stderr, "polarlux %s: %s%s\n", cmd, plx_last_error(e), photons_hint(st));
            return cli_exit_code(st);
        }
    }
    for (k = 0; k < ind->frames; k++) {
        plx_status st = plx_indirect_step(e, (uint32_t)photons, (uint64_t)k + 1);
        if (st != PLX_OK) {
            fprintf(stderr, "%spolarlux %s: %s%s\n", tty ? "\n" : "", cmd, plx_last_error(e), photons_hint(st));
            return cli_exit_code(st);
        }
        if (k == 0)
            cli_indirect_note(cmd, c, e);
        if (tty)
            fprintf(stderr, "\rindirect light: frame %ld/%ld (%ld photons each), %.1f s", k + 1, ind->frames,
                    photons, (port_now_ns() - t0) / 1e9);
    }
    if (tty)
        fprintf(stderr, "\n");
    return EXIT_OK;
}

/* ---- the scene's coordinates ---------------------------------------------- */

/* One point through the engine's projection (plx_lonlat_to_local or
 * plx_local_to_lonlat), in place. */
static int cli_project(plx_engine *e, plx_status (*fn)(plx_engine *, size_t, const double *, double *),
                       double *x, double *y)
{
    double in[2], out[2];
    in[0] = *x;
    in[1] = *y;
    if (fn(e, 1, in, out) != PLX_OK)
        return -1;
    *x = out[0];
    *y = out[1];
    return 0;
}

int cli_to_local(plx_engine *e, double *x, double *y)
{
    plx_scene_info si;
    plx_scene_info_get(e, &si);
    if (!si.lonlat)
        return 0;
    if (!(fabs(*x) <= 180.0 && fabs(*y) <= 90.0))
        return -1;
    return cli_project(e, plx_lonlat_to_local, x, y);
}

void cli_from_local(plx_engine *e, double *x, double *y)
{
    plx_scene_info si;
    plx_scene_info_get(e, &si);
    if (!si.lonlat)
        return;
    cli_project(e, plx_local_to_lonlat, x, y);
}

int cli_option_local(const char *cmd, const char *opt, plx_engine *e, double *x, double *y)
{
    if (cli_to_local(e, x, y) == 0)
        return 0;
    fprintf(stderr, "polarlux %s: %s %g,%g is not lon/lat, and the scene is in lon/lat: coordinate options take "
                    "the scene's own coordinates\n", cmd, opt, *x, *y);
    return -1;
}

int cli_crs_epsg(const char *name)
{
    const char *p = strstr(name, "EPSG"), *d = name + strlen(name);
    long v;
    if (!p)
        return 0;
    while (d > p && isdigit((unsigned char)d[-1]))
        d--;
    if (!*d || d[-1] != ':')
        return 0;
    v = strtol(d, NULL, 10);
    return v > 0 && v < 1000000 ? (int)v : 0;
}

int cli_same_crs(const char *a, const char *b)
{
    int ca = cli_crs_epsg(a);
    return strcmp(a, b) == 0 || (ca != 0 && ca == cli_crs_epsg(b));
}

/* a and b equal but for the case of ASCII letters */
static int same_ci(const char *a, const char *b)
{
    for (; *a && tolower((unsigned char)*a) == tolower((unsigned char)*b); a++, b++)
        ;
    return *a == '\0' && *b == '\0';
}

/* 1: lon/lat, 0: local metres, -1: unknown name ("LonLat", "LOCAL" as well). */
static int frame_of(plx_engine *e, const char *name)
{
    plx_scene_info si;
    const char *crs = plx_scene_crs(e);
    plx_scene_info_get(e, &si);
    if (same_ci(name, "lonlat") || same_ci(name, "EPSG:4326") || same_ci(name, "WGS84"))
        return 1;
    if (same_ci(name, "local"))
        return 0;
    if (crs && cli_same_crs(name, crs)) /* "EPSG:3067" names "urn:ogc:def:crs:EPSG::3067" too */
        return si.lonlat;
    return -1;
}

/* A word when points (local metres) lie more than CLI_FAR_POINT m outside
 * the box of the scene's bounds and every lamp's reach: no lamp reaches
 * them, and a point 30 km away said only that no lamp's light reached it. */
#define CLI_FAR_POINT 1000.0
void cli_points_far(const char *cmd, const cli_common *c, plx_engine *e, const char *path, const struct points *p)
{
    plx_scene_info si;
    plx_lamp l;
    size_t k, n = 0, worst = 0;
    double far = 0.0, b[4];
    uint32_t i;
    if (p->n == 0 || plx_scene_info_get(e, &si) != PLX_OK)
        return;
    memcpy(b, si.bounds, sizeof b);
    for (i = 0; i < si.lamps; i++) /* lamps outside the buildings' box, a --lamps layer's */
        if (plx_lamp_get(e, i, &l) == PLX_OK) {
            b[0] = fmin(b[0], l.x - l.radius);
            b[1] = fmin(b[1], l.y - l.radius);
            b[2] = fmax(b[2], l.x + l.radius);
            b[3] = fmax(b[3], l.y + l.radius);
        }
    for (k = 0; k < p->n; k++) {
        const double *row = p->v + k * (size_t)p->cols;
        double dx = fmax(fmax(b[0] - row[0], row[0] - b[2]), 0.0), dy = fmax(fmax(b[1] - row[1], row[1] - b[3]), 0.0);
        double d = hypot(dx, dy);
        if (!(d > CLI_FAR_POINT))
            continue;
        if (d > far) {
            far = d;
            worst = k;
        }
        n++;
    }
    if (n > 0) {
        char km[32]; /* not 300 digits for a point at 1e300 */
        snprintf(km, sizeof km, far / 1000.0 < 1e7 ? "%.1f" : "%.3g", far / 1000.0);
        cli_warn(cmd, c, "%s: %zu of %zu points lie more than %.0f km outside the scene's bounds and every lamp's "
                 "reach (the farthest %s km, line %zu): are they in the scene's coordinates?",
                 strcmp(path, "-") == 0 ? "<stdin>" : path, n, p->n, CLI_FAR_POINT / 1000.0, km, p->line[worst]);
    }
}

int cli_points_local(const char *cmd, plx_engine *e, const cli_common *c, const char *path, struct points *p,
                     double **orig)
{
    plx_scene_info si;
    const char *name = c->points_crs ? c->points_crs : p->crs[0] ? p->crs : NULL;
    int lonlat;
    size_t k;
    plx_scene_info_get(e, &si);
    if (strcmp(path, "-") == 0) /* named as the points' own messages name it */
        path = "<stdin>";
    lonlat = name ? frame_of(e, name) : si.lonlat;
    if (lonlat < 0) {
        fprintf(stderr, "polarlux %s: %s: points crs '%s' is not lonlat, local or the scene's CRS (%s)\n", cmd,
                path, name, plx_scene_crs(e) ? plx_scene_crs(e) : "none named");
        return c->points_crs ? EXIT_USAGE : EXIT_FAIL;
    }
    if (lonlat && !si.lonlat) {
        fprintf(stderr, "polarlux %s: %s: the points are in lon/lat but the scene is in metres\n", cmd, path);
        return EXIT_FAIL;
    }
    if (orig) {
        *orig = malloc(sizeof **orig * 2 * (p->n + 1));
        if (!*orig) {
            fprintf(stderr, "polarlux %s: %s: out of memory\n", cmd, path);
            return EXIT_FAIL;
        }
        for (k = 0; k < p->n; k++) {
            (*orig)[2 * k] = p->v[k * (size_t)p->cols];
            (*orig)[2 * k + 1] = p->v[k * (size_t)p->cols + 1];
        }
    }
    for (k = 0; lonlat && k < p->n; k++) {
        double *row = p->v + k * (size_t)p->cols;
        if (cli_to_local(e, &row[0], &row[1]) != 0) {
            fprintf(stderr, "polarlux %s: %s:%zu: %g %g is not lon/lat (the points are in lon/lat: %s)\n", cmd,
                    path, p->line[k], row[0], row[1],
                    name ? "their crs says so" : "the scene's coordinates; '# crs: local' for metres");
            if (orig) {
                free(*orig);
                *orig = NULL;
            }
            return EXIT_FAIL;
        }
    }
    return EXIT_OK;
}

/* The default aerial view: straight down over the scene's box (its
 * buildings plus 50 m), the box's limiting side 1 / AERIAL_MARGIN of the
 * frame's (a margin of 5% of the frame each side: with none, glow discs
 * and lit ground at the box's edge touched the frame's). */
#define AERIAL_MARGIN (1.0 / 0.9)

void cli_default_aerial(plx_engine *e, plx_camera *cam)
{
    plx_scene_info si;
    double w, h, half;
    plx_scene_info_get(e, &si);
    w = si.bounds[2] - si.bounds[0];
    h = si.bounds[3] - si.bounds[1];
    half = 0.5 * fmax(h, w * cam->height / cam->width) * AERIAL_MARGIN;
    cam->target[0] = cam->eye[0] = 0.5 * (si.bounds[0] + si.bounds[2]);
    cam->target[1] = cam->eye[1] = 0.5 * (si.bounds[1] + si.bounds[3]);
    cam->target[2] = 0.0;
    cam->eye[2] = half / tan(cam->fov_deg * 0.008726646259971648);
}

/* ---- progress and the command's buffers ------------------------------------ */

void cli_progress_start(cli_progress *p)
{
    p->tty = isatty(2);
    p->shown = 0;
    p->t0 = p->last = port_now_ns();
}

void cli_progress_step(cli_progress *p, const char *what, size_t done, size_t total)
{
    unsigned long long now;
    if (!p->tty)
        return;
    now = port_now_ns();
    if (now - p->t0 < 1000000000ull || (now - p->last < 100000000ull && done < total))
        return;
    p->last = now;
    p->shown = 1;
    fprintf(stderr, "\r%s: %3.0f%% (%.1f s)", what, total ? 100.0 * done / total : 100.0, (now - p->t0) / 1e9);
}

void cli_progress_end(cli_progress *p)
{
    if (p->shown)
        fprintf(stderr, "\n");
    p->shown = 0;
}

size_t cli_buffer_budget(const plx_engine *e, const cli_common *c)
{
    plx_memory_report m;
    size_t mem = c->mem ? c->mem : CLI_DEFAULT_MEM;
    plx_memory_get(e, &m);
    return m.peak_total < mem ? mem - m.peak_total : 0;
}

void cli_refiner_init(cli_refiner *r, double height, long frames, long photons)
{
    memset(r, 0, sizeof *r);
    r->height = height;
    r->frames = frames;
    r->photons = photons;
}

int cli_refine(const char *cmd, plx_engine *e, const plx_camera *cam, cli_refiner *r)
{
    uint64_t before = r->rs.refined;
    plx_status st;
    long k;
    if (cam->eye[2] > r->height) {
        r->high++;
        return EXIT_OK;
    }
    st = plx_indirect_refine_view(e, cam, &r->rs);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: %s\n", cmd, plx_last_error(e));
        return cli_exit_code(st);
    }
    /* a newly refined lamp restarts the progressive aerial chart: refill it
     * (an evicted lamp's map computed again restarts nothing) */
    for (k = 0; r->rs.refined > before && k < r->frames; k++) {
        st = plx_indirect_step(e, (uint32_t)r->photons, plx_indirect_frames(e) + 1);
        if (st != PLX_OK) {
            fprintf(stderr, "polarlux %s: %s\n", cmd, plx_last_error(e));
            return cli_exit_code(st);
        }
        r->refills++;
    }
    return EXIT_OK;
}

void cli_aa_warn(const char *cmd, const cli_common *c, const plx_render_opts *o, const plx_render_info *info)
{
    if (o->aa_full && o->aa <= 1)
        cli_warn(cmd, c, "--aa-full has no effect without --aa 2 or more (one sample a pixel)");
    if (o->aa > 1 && !o->aa_full && info->aa_adaptive == PLX_AA_EVERY)
        cli_warn(cmd, c, "the engine's memory block (--mem; for a bake without --mem, the bake's own room) "
                 "leaves no room for adaptive anti-aliasing (8 bytes a pixel of the largest frame): every "
                 "pixel takes all %dx%d samples (slower; the image differs from the adaptive one by about 1 "
                 "in 255)", o->aa, o->aa);
}

void cli_aa_print(const plx_render_opts *o, uint64_t later, double px, long frames, long adaptive, long dense)
{
    double all = ((double)o->aa * o->aa - 1.0) * px;
    char how[160];
    if (o->aa <= 1)
        return;
    if (adaptive == 0 && dense == 0)
        snprintf(how, sizeof how, "every sample");
    else if (dense > 0 && dense == frames)
        snprintf(how, sizeof how, "every sample: edges at more than half the pixels%s; --aa 1 is faster",
                 frames > 1 ? " of every frame" : "");
    else if (dense > 0)
        snprintf(how, sizeof how, "adaptive: edges and glows; every sample in %ld of %ld frames, with edges at "
                 "more than half the pixels", dense, frames);
    else
        snprintf(how, sizeof how, "adaptive: edges and glows; --aa-full for all");
    printf("anti-aliasing %dx%d: the later samples shaded %.1f%% of the pixels (%s)\n", o->aa, o->aa,
           all > 0.0 ? 100.0 * (double)later / all : 0.0, how);
}

void cli_atlas_print(plx_engine *e)
{
    plx_atlas_info ai;
    if (plx_atlas_info_get(e, &ai) != PLX_OK || !ai.made)
        return;
    printf("radiance atlas: %llu sample points %.2f m apart (%.2f m where only indirect light reaches), "
           "%zu bytes (%.1f MiB), %s%s\n",
           (unsigned long long)ai.points, ai.spacing, ai.coarse, ai.bytes, ai.bytes / 1048576.0,
           ai.unfilled ? "filled as frames need it" : "filled",
           ai.indirect ? ", indirect light included" : ", direct light only");
}

int cli_scene_attribution(const char *path, char *buf, size_t cap)
{
    const plx_port *pt = plx_port_posix();
    const void *data = NULL;
    void *handle = NULL;
    const char *text;
    size_t len = 0, at, root, v;
    char why[128];
    int got = 0;
    if (cap > 0)
        buf[0] = '\0';
    if (!pt->file_map || pt->file_map(pt->ctx, path, &data, &len, &handle, why, sizeof why) != 0)
        return 0;
    text = data;
    root = len >= 3 && memcmp(text, "\xef\xbb\xbf", 3) == 0 ? 3 : 0; /* a UTF-8 byte order mark */
    root = jsonscan_ws(text, len, root);
    if (root < len && jsonscan_check(text + root, len - root, &at) && jsonscan_kind(text + root, 0) == JS_OBJECT &&
        (v = jsonscan_get(text + root, len - root, 0, "attribution")) != JSONSCAN_NONE &&
        jsonscan_kind(text + root, v) == JS_STRING) {
        jsonscan_string(text + root, len - root, v, buf, cap);
        got = buf[0] != '\0';
    }
    pt->file_unmap(pt->ctx, handle);
    return got;
}
