/* polarlux tiles SCENE --zoom Z0-Z1 -o OUT: web-map raster tiles of the
 * ground illuminance (a folder OUT/z/x/y.png or an MBTiles file). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cjson/cJSON.h>

#include "cli.h"
#include "options.h"
#include "port.h"
#include "tiles.h"

static const char help[] =
    "usage: polarlux tiles SCENE --zoom Z0[-Z1] [--quantity h|sc] [--max LUX] -o OUT [options]\n"
    "\n"
    "Writes web-map raster tiles (Web Mercator, XYZ numbering, 256 x 256 pixels)\n"
    "of the direct ground illuminance E_h (with --quantity sc: the direct\n"
    "semi-cylindrical illuminance E_sc above the ground) over the scene's Bounds,\n"
    "in the colours of 'polarlux heatmap' (logarithmic scale from 0.1 lx to\n"
    "--max); pixels with no light (0.1 lx or less, or inside a footprint or\n"
    "solid) are transparent. Each pixel is the ground point under its centre.\n"
    "The scene must be in lon/lat.\n"
    "OUT ending in .mbtiles is an MBTiles 1.3 file (SQLite; metadata name,\n"
    "format, type, version, bounds, center, minzoom, maxzoom, description, and\n"
    "attribution when there is one); otherwise OUT is a folder receiving\n"
    "OUT/z/x/y.png and OUT/metadata.json (TileJSON 3.0.0: name, description,\n"
    "attribution, bounds, center, minzoom, maxzoom; and polarlux_scale: min_lux,\n"
    "max_lux, for a legend).\n"
    "\n"
    "  --zoom Z0-Z1   zoom levels (0..22; one level: --zoom Z)\n"
    "  --quantity Q   h: the horizontal illuminance E_h on the ground (default);\n"
    "                 sc: the semi-cylindrical illuminance E_sc (SPEC §6) --height\n"
    "                 above it, facing --facing\n"
    "  --height M     height of the sc meters (default 1.5)\n"
    "  --facing F     sc's facing direction: 'min' (default), the least E_sc over\n"
    "                 every horizontal direction (the face worst lit), or degrees\n"
    "                 counter-clockwise from east (as 'polarlux heatmap --facing')\n"
    "  --max LUX      top of the colour scale (default: the next power of ten\n"
    "                 above the brightest pixel of the quantity on the grid of\n"
    "                 'polarlux heatmap''s default resolution; heatmap's own\n"
    "                 default scale spans its pixels' percentiles: give both\n"
    "                 --max for one scale)\n"
    "  -o OUT         folder or .mbtiles file (required)\n"
    "  --attribution TEXT  the MBTiles attribution (the data's credit line;\n"
    "                 default: the scene file's own top-level \"attribution\"\n"
    "                 member, as OpenStreetMap extracts carry; '' for none)\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

typedef struct tiles_opts {
    const char *scene, *out, *attribution;
    long z0, z1;
    double top;
    heat_quantity q;
    cli_common c;
} tiles_opts;

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

static int make_dir(const char *path)
{
    return mkdir(path, 0777) == 0 || errno == EEXIST ? 0 : -1;
}

/* Writes OUT/z/x/y.png, making the folders. */
static int write_file(const tiles_opts *o, int z, long x, long y, const uint8_t *png, size_t len)
{
    char path[4096], err[512];
    snprintf(path, sizeof path, "%s/%d", o->out, z);
    if (make_dir(o->out) != 0 || make_dir(path) != 0) {
        fprintf(stderr, "polarlux tiles: %s: cannot make the folder: %s\n", path, strerror(errno));
        return -1;
    }
    snprintf(path, sizeof path, "%s/%d/%ld", o->out, z, x);
    if (make_dir(path) != 0) {
        fprintf(stderr, "polarlux tiles: %s: cannot make the folder: %s\n", path, strerror(errno));
        return -1;
    }
    snprintf(path, sizeof path, "%s/%d/%ld/%ld.png", o->out, z, x, y);
    if (port_write_atomic(path, png, len, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux tiles: %s\n", err);
        return -1;
    }
    return 0;
}

static void lonlat_bounds(plx_engine *e, double b[4])
{
    plx_scene_info si;
    double c;
    plx_scene_info_get(e, &si);
    c = 111320.0 * cos(si.lat0 * 3.14159265358979323846 / 180.0);
    b[0] = si.lon0 + si.bounds[0] / c;
    b[1] = si.lat0 + si.bounds[1] / 110540.0;
    b[2] = si.lon0 + si.bounds[2] / c;
    b[3] = si.lat0 + si.bounds[3] / 110540.0;
}

/* The scene file's name without folder and extension (MBTiles "name"). */
static const char *scene_name(const char *path, char *buf, size_t len)
{
    const char *base = strrchr(path, '/');
    char *dot;
    snprintf(buf, len, "%s", base ? base + 1 : path);
    dot = strrchr(buf, '.');
    if (dot && dot != buf)
        *dot = '\0';
    return buf;
}

static long count_tiles(plx_engine *e, const tiles_opts *o)
{
    long total = 0, x0, y0, x1, y1;
    int z;
    for (z = (int)o->z0; z <= o->z1; z++) {
        tile_range(e, z, &x0, &y0, &x1, &y1);
        total += (x1 - x0 + 1) * (y1 - y0 + 1);
    }
    return total;
}

/* What the tiles map, for the summary line and the MBTiles description. */
static void quantity_text(const heat_quantity *q, char *buf, size_t len)
{
    if (q->quantity == PLX_METER_H)
        snprintf(buf, len, "direct ground illuminance E_h");
    else if (q->facing_min)
        snprintf(buf, len, "direct semi-cylindrical illuminance E_sc at %g m, the least over every facing direction",
                 q->height);
    else
        snprintf(buf, len, "direct semi-cylindrical illuminance E_sc at %g m facing %g deg", q->height, q->facing);
}

/* The MBTiles attribution: --attribution, else the scene file's own (none
 * from a bake, which does not keep it: said on stderr). */
static const char *tiles_attribution(const tiles_opts *o, char *buf, size_t cap)
{
    if (o->attribution)
        return o->attribution;
    if (cli_bake_last.loaded) {
        cli_warn("tiles", &o->c, "%s: a bake keeps no attribution: the %s has none (give --attribution TEXT, the "
                 "data's credit line)", o->scene, ends_with(o->out, ".mbtiles") ? "MBTiles file" : "metadata.json");
        return NULL;
    }
    return cli_scene_attribution(o->scene, buf, cap) ? buf : NULL;
}

/* A folder's OUT/metadata.json: TileJSON 3.0.0 (the MBTiles metadata's
 * fields) and the colour scale, so a page can label its legend in lux. */
static int write_tilejson(const tiles_opts *o, const char *name, const double b[4], const char *what, double top,
                          const char *attribution)
{
    cJSON *j = cJSON_CreateObject(), *scale;
    const char *tiles[1] = { "{z}/{x}/{y}.png" };
    double centre[3];
    char path[4096], err[512], *text, *line;
    size_t n;
    int rc;
    centre[0] = 0.5 * (b[0] + b[2]);
    centre[1] = 0.5 * (b[1] + b[3]);
    centre[2] = (double)o->z1;
    cJSON_AddStringToObject(j, "tilejson", "3.0.0");
    cJSON_AddStringToObject(j, "name", name);
    cJSON_AddStringToObject(j, "description", what);
    if (attribution && attribution[0])
        cJSON_AddStringToObject(j, "attribution", attribution);
    cJSON_AddItemToObject(j, "tiles", cJSON_CreateStringArray(tiles, 1));
    cJSON_AddItemToObject(j, "bounds", cJSON_CreateDoubleArray(b, 4));
    cJSON_AddItemToObject(j, "center", cJSON_CreateDoubleArray(centre, 3));
    cJSON_AddNumberToObject(j, "minzoom", (double)o->z0);
    cJSON_AddNumberToObject(j, "maxzoom", (double)o->z1);
    scale = cJSON_AddObjectToObject(j, "polarlux_scale");
    cJSON_AddStringToObject(scale, "kind", "logarithmic, the heat map's colours; transparent at or below min_lux");
    cJSON_AddNumberToObject(scale, "min_lux", 0.1);
    cJSON_AddNumberToObject(scale, "max_lux", top);
    text = cJSON_Print(j);
    cJSON_Delete(j);
    if (!text || !(line = realloc(text, (n = strlen(text)) + 2))) {
        free(text);
        fprintf(stderr, "polarlux tiles: out of memory for metadata.json\n");
        return -1;
    }
    text = line;
    memcpy(text + n, "\n", 2); /* the last line ends */
    snprintf(path, sizeof path, "%s/metadata.json", o->out);
    rc = port_write_atomic(path, text, n + 1, err, sizeof err);
    if (rc != 0)
        fprintf(stderr, "polarlux tiles: %s\n", err);
    free(text);
    return rc;
}

/* Renders and stores every tile; returns an exit code. */
static int run(plx_engine *e, const tiles_opts *o, double top)
{
    uint8_t *rgba = malloc(TILE_SIZE * TILE_SIZE * 4);
    long total = count_tiles(e, o), done = 0, lit_tiles = 0, x0, y0, x1, y1, x, y;
    int z, rc = EXIT_OK, tty = isatty(2);
    tile_work w;
    mbtiles *mb = NULL;
    char err[512], name[256], what[160], credit[512];
    double b[4];
    memset(&w, 0, sizeof w);
    lonlat_bounds(e, b);
    if (!rgba || tile_work_init(&w) != 0) {
        fprintf(stderr, "polarlux tiles: out of memory\n");
        free(rgba);
        return EXIT_FAIL;
    }
    w.q = o->q;
    quantity_text(&o->q, what, sizeof what);
    if (ends_with(o->out, ".mbtiles") &&
        !(mb = mbtiles_open(o->out, scene_name(o->scene, name, sizeof name), b, (int)o->z0, (int)o->z1, what, top,
                             tiles_attribution(o, credit, sizeof credit), err, sizeof err))) {
        fprintf(stderr, "polarlux tiles: %s\n", err);
        rc = EXIT_FAIL;
    }
    for (z = (int)o->z0; z <= o->z1 && rc == EXIT_OK; z++) {
        tile_range(e, z, &x0, &y0, &x1, &y1);
        for (y = y0; y <= y1 && rc == EXIT_OK; y++)
            for (x = x0; x <= x1 && rc == EXIT_OK; x++) {
                uint8_t *png;
                size_t len;
                long lit = tile_render(e, &w, z, x, y, top, rgba);
                if (lit < 0) {
                    fprintf(stderr, "polarlux tiles: tile %d/%ld/%ld: %s\n", z, x, y, plx_last_error(e));
                    rc = EXIT_FAIL;
                    break;
                }
                lit_tiles += lit > 0;
                if (tile_png(rgba, &png, &len) != 0) {
                    fprintf(stderr, "polarlux tiles: tile %d/%ld/%ld: PNG encoding failed\n", z, x, y);
                    rc = EXIT_FAIL;
                    break;
                }
                if (mb ? mbtiles_put(mb, z, x, y, png, len, err, sizeof err) != 0 : write_file(o, z, x, y, png, len) != 0) {
                    if (mb)
                        fprintf(stderr, "polarlux tiles: %s\n", err);
                    rc = EXIT_FAIL;
                }
                free(png);
                if (tty && (++done % 16 == 0 || done == total))
                    fprintf(stderr, "\rtiles: %ld / %ld", done, total);
            }
    }
    if (tty && done >= 16)
        fprintf(stderr, "\n");
    if (mb && mbtiles_close(mb, rc == EXIT_OK, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux tiles: %s\n", err);
        rc = EXIT_FAIL;
    }
    if (!mb && rc == EXIT_OK && (make_dir(o->out) != 0 ||
                                 write_tilejson(o, scene_name(o->scene, name, sizeof name), b, what, top,
                                                tiles_attribution(o, credit, sizeof credit)) != 0))
        rc = EXIT_FAIL;
    if (rc == EXIT_OK) {
        printf("tiles: %ld tiles at zoom %ld-%ld (%ld with light) of %s, scale 0.1..%g lx, written to %s\n", total,
               o->z0, o->z1, lit_tiles, what, top, o->out);
        if (lit_tiles == 0)
            fprintf(stderr, "polarlux tiles: note: no tile has light (every pixel at or below 0.1 lx)\n");
    }
    tile_work_free(&w);
    free(rgba);
    return rc;
}

/* Z or Z0-Z1 into o->z0, o->z1 (dst: the tiles_opts). */
static int parse_zoom(const char *s, void *dst)
{
    tiles_opts *o = dst;
    char a[32], *dash;
    snprintf(a, sizeof a, "%s", s);
    dash = strchr(a, '-');
    if (dash)
        *dash = '\0';
    if (cli_parse_int(a, 0, 22, &o->z0) != 0)
        return -1;
    o->z1 = o->z0;
    if (dash && cli_parse_int(dash + 1, 0, 22, &o->z1) != 0)
        return -1;
    return o->z1 >= o->z0 ? 0 : -1;
}

static int parse_quantity(const char *q, void *dst)
{
    int *k = dst;
    *k = strcmp(q, "h") == 0 ? PLX_METER_H : strcmp(q, "sc") == 0 ? PLX_METER_SC : -1;
    return *k < 0 ? -1 : 0;
}

static int parse_max(const char *s, void *dst)
{
    double *t = dst;
    return cli_parse_double(s, t) != 0 || !(*t > 0.1) ? -1 : 0;
}

static int parse(int argc, char **argv, tiles_opts *o)
{
    int have_zoom = 0, sc_option = 0, rc;
    struct stat st;
    const cli_opt opts[] = {
        { "--zoom", NULL, o, parse_zoom, "--zoom '%s' is not Z or Z0-Z1 with 0 <= Z0 <= Z1 <= 22", 0, NULL, &have_zoom,
          NULL },
        CLI_OPT_VAL("--quantity", &o->q.quantity, parse_quantity, "--quantity '%s' is not h (ground E_h) or sc (E_sc)"),
        { "--height", NULL, &o->q.height, cli_opt_height, "--height '%s' is not a number of metres from 0 to 1000", 0,
          NULL, &sc_option, NULL },
        { "--facing", NULL, &o->q, cli_opt_facing, "--facing '%s' is not a number of degrees or min", 0, NULL,
          &sc_option, NULL },
        CLI_OPT_VAL("--max", &o->top, parse_max, "--max '%s' is not a number of lux above 0.1"),
        CLI_OPT_STR("-o", &o->out),
        CLI_OPT_STR("--attribution", &o->attribution),
        CLI_OPT_END
    };
    cli_args pa;
    o->q.quantity = PLX_METER_H;
    o->q.height = 1.5;
    o->q.facing_min = 1;
    rc = cli_options_n("tiles", help, argc, argv, opts, &o->c, NULL, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc;
    o->scene = pa.npos ? pa.pos[0] : NULL;
    if (!o->scene)
        return cli_usage_error("tiles", "missing SCENE");
    if (!have_zoom)
        return cli_usage_error("tiles", "missing --zoom Z0-Z1");
    if (!o->out)
        return cli_usage_error("tiles", "missing -o OUT (a folder or a .mbtiles file)");
    if (strcmp(o->out, "-") == 0) /* elsewhere '-' is standard input or output: never a folder named '-' */
        return cli_usage_error("tiles", "-o names a folder or a .mbtiles file: '-' (standard output) cannot hold "
                               "tiles; name a folder, e.g. -o ./-");
    if (ends_with(o->out, ".mbtiles") && stat(o->out, &st) == 0 && S_ISDIR(st.st_mode))
        return cli_usage_error("tiles", "-o '%s' is a folder: an .mbtiles file cannot replace it (remove it, or name "
                               "another file)", o->out);
    if (!ends_with(o->out, ".mbtiles") && stat(o->out, &st) == 0 && !S_ISDIR(st.st_mode))
        return cli_usage_error("tiles", "-o '%s' is a file, not a folder: name a folder for z/x/y.png tiles, or a "
                               ".mbtiles file", o->out);
    if (sc_option && o->q.quantity != PLX_METER_SC)
        return cli_usage_error("tiles", "--height and --facing need --quantity sc (E_h is on the ground)");
    return EXIT_OK;
}

#define MAX_TILES 20000L

int cmd_tiles(int argc, char **argv)
{
    tiles_opts o;
    plx_engine *e;
    plx_scene_info si;
    long n;
    int rc;
    memset(&o, 0, sizeof o);
    rc = parse(argc, argv, &o);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    rc = cli_open_scene("tiles", o.scene, &o.c, &e);
    if (rc != EXIT_OK)
        return rc;
    plx_scene_info_get(e, &si);
    if (!si.lonlat) {
        const char *crs = plx_scene_crs(e);
        if (crs) /* a projected CRS: polarlux does not reproject (no projection library) */
            fprintf(stderr, "polarlux tiles: %s: the scene is in %s metres, which polarlux does not turn into "
                            "lon/lat: web-map tiles need a scene in WGS84 lon/lat (reproject it first, e.g. ogr2ogr "
                            "-t_srs EPSG:4326)\n", o.scene, crs);
        else
            fprintf(stderr, "polarlux tiles: %s: the scene is in local metres, with no lon/lat to place tiles on "
                            "the map (web-map tiles need a scene in WGS84 lon/lat)\n", o.scene);
        plx_engine_free(e);
        return EXIT_FAIL;
    }
    n = count_tiles(e, &o);
    if (n > MAX_TILES) {
        fprintf(stderr, "polarlux tiles: --zoom %ld-%ld covers the scene with %ld tiles (at most %ld)\n", o.z0, o.z1,
                n, MAX_TILES);
        plx_engine_free(e);
        return EXIT_USAGE;
    }
    rc = run(e, &o, o.top > 0 ? o.top : tile_default_top(e, &o.q));
    plx_engine_free(e);
    return rc;
}
