/* polarlux heatmap SCENE --res M -o map.png: top-down ground illuminance. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "canvas.h"
#include "cli.h"
#include "route_io.h"

static const char help[] =
    "usage: polarlux heatmap SCENE [--res M] -o MAP.png [options]\n"
    "\n"
    "Writes a top-down map of the direct ground illuminance over Bounds: one\n"
    "pixel per M x M metres, sampled at the pixel centre (exact 2.5D shadows,\n"
    "SPEC §2), coloured on a logarithmic scale with a legend in lux on the\n"
    "right. Building footprints are grey, lamps white dots.\n"
    "\n"
    "  --res M    metres per pixel (default: the longer side of Bounds / 1200)\n"
    "  -o FILE    output PNG (required)\n"
    "  --max LUX  top of the colour scale (default: the next power of ten above\n"
    "             the brightest pixel)\n"
    "  --box X0,Y0,X1,Y1  map only this box (local metres) instead of Bounds\n"
    "  --path FILE  draw these routes (GeoJSON LineStrings, as for 'polarlux\n"
    "             route') on the map, sampled every pixel and coloured by lux\n"
    "             on the same scale, outlined in cyan\n"
    "  --quantity Q  what to map (SPEC §6): h ground illuminance (default),\n"
    "             sc semi-cylindrical, v vertical, hs hemispherical illuminance;\n"
    "             v and sc face --facing, all but h are taken --height above\n"
    "             the ground (direct light)\n"
    "  --height M the meters' height for v, sc, hs (default 1.5)\n"
    "  --facing DEG  facing direction of v and sc, degrees counter-clockwise\n"
    "             from east (default 0)\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

/* A night palette on t in [0, 1]: black, deep blue, purple, orange, yellow, white. */
static void palette(double t, uint8_t rgb[3])
{
    static const double stops[6][3] = {
        { 0, 0, 0 }, { 20, 30, 110 }, { 120, 40, 140 }, { 230, 110, 40 }, { 250, 220, 80 }, { 255, 255, 255 },
    };
    double x;
    int i, k;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    x = t * 5.0;
    i = (int)x;
    if (i > 4)
        i = 4;
    x -= i;
    for (k = 0; k < 3; k++)
        rgb[k] = (uint8_t)(stops[i][k] + (stops[i + 1][k] - stops[i][k]) * x + 0.5);
}

#define LUX_MIN 0.1

static double scale_t(double lux, double top)
{
    if (!(lux > LUX_MIN))
        return 0.0;
    return log10(lux / LUX_MIN) / log10(top / LUX_MIN);
}

static void legend(canvas *c, int x0, double top)
{
    static const uint8_t white[3] = { 230, 230, 230 };
    int y, h = c->h - 40, ts = c->h > 600 ? 2 : 1;
    double v;
    for (y = 0; y < h; y++) {
        uint8_t rgb[3];
        palette(1.0 - (double)y / (h - 1), rgb);
        canvas_rect(c, x0 + 10, 20 + y, x0 + 30, 21 + y, rgb);
    }
    for (v = LUX_MIN; v <= top * 1.0001; v *= 10.0) {
        char label[32];
        int yy = 20 + (int)((1.0 - scale_t(v, top)) * (h - 1));
        snprintf(label, sizeof label, v < 1 ? "%.1f lx" : "%.0f lx", v);
        canvas_rect(c, x0 + 30, yy, x0 + 36, yy + 1, white);
        canvas_text(c, x0 + 40, yy - 3 * ts, ts, label, white);
    }
}

typedef struct heat_opts {
    double res, top, box[4];
    int have_box;
    int quantity;             /* PLX_METER_*; H maps the ground */
    double height, facing;
    const char *out, *path;
    const cli_common *c;
} heat_opts;

/* One segment a..b sampled every pixel: pass 0 the outline, pass 1 the fill. */
static void draw_segment(plx_engine *e, canvas *c, const heat_opts *o, double top, const double *a, int pass)
{
    static const uint8_t outline[3] = { 0, 200, 255 };
    const double *b = a + 2;
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    int m = (int)ceil(len / o->res) + 1, j;
    for (j = 0; j <= m; j++) {
        double P[3], N[3] = { 0, 0, 1 }, E, Ei;
        uint8_t rgb[3];
        int px, py;
        P[0] = a[0] + (b[0] - a[0]) * j / m;
        P[1] = a[1] + (b[1] - a[1]) * j / m;
        P[2] = 0;
        px = (int)((P[0] - c->x0) * c->scale);
        py = (int)((c->y0 - P[1]) * c->scale);
        if (pass == 0) {
            canvas_rect(c, px - 4, py - 4, px + 5, py + 5, outline);
            continue;
        }
        if (plx_illuminance(e, 1, P, N, &E, &Ei, NULL) != PLX_OK)
            continue;
        palette(scale_t(E + Ei, top), rgb);
        canvas_rect(c, px - 2, py - 2, px + 3, py + 3, rgb);
    }
}

/* Draws the routes of 'path' sampled every pixel, coloured by lux. */
static int draw_routes(plx_engine *e, canvas *c, const heat_opts *o, double top)
{
    route_set rs;
    char err[512];
    size_t i;
    int pass;
    if (route_read(o->path, e, &rs, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux heatmap: %s\n", err);
        return EXIT_FAIL;
    }
    for (pass = 0; pass < 2; pass++) {
        for (i = 0; i < rs.n; i++) {
            uint32_t k;
            for (k = 0; k + 1 < rs.lines[i].n; k++)
                draw_segment(e, c, o, top, rs.lines[i].xy + 2 * k, pass);
        }
    }
    route_free(&rs);
    return EXIT_OK;
}

static int run(plx_engine *e, const heat_opts *o)
{
    static const uint8_t grey[3] = { 60, 60, 66 }, white[3] = { 255, 255, 255 }, black[3] = { 0, 0, 0 };
    plx_scene_info si;
    canvas c;
    double box[4], *P, *N, *E, top = 0.0;
    size_t w, h, n, k;
    int legend_w, map_w;
    char err[512];
    plx_status st;
    double res = o->res;
    plx_scene_info_get(e, &si);
    memcpy(box, o->have_box ? o->box : si.bounds, sizeof box);
    w = (size_t)ceil((box[2] - box[0]) / res);
    h = (size_t)ceil((box[3] - box[1]) / res);
    if (w < 1 || h < 1 || w * h > 50000000u) {
        fprintf(stderr, "polarlux heatmap: --res %g gives %zux%zu pixels (at most 5e7)\n", res, w, h);
        return EXIT_USAGE;
    }
    n = w * h;
    P = malloc(sizeof *P * 3 * n);
    N = malloc(sizeof *N * 3 * n);
    E = malloc(sizeof *E * n);
    if (!P || !N || !E) {
        free(P), free(N), free(E);
        fprintf(stderr, "polarlux heatmap: out of memory for %zu pixels\n", n);
        return EXIT_FAIL;
    }
    for (k = 0; k < n; k++) {
        P[3 * k] = box[0] + (k % w + 0.5) * res;
        P[3 * k + 1] = box[3] - (k / w + 0.5) * res;
        P[3 * k + 2] = 0.0;
        N[3 * k] = N[3 * k + 1] = 0.0;
        N[3 * k + 2] = 1.0;
    }
    if (o->quantity == PLX_METER_H) {
        st = plx_illuminance(e, n, P, N, E, NULL, NULL);
    } else {
        double u[2], m[PLX_METER_COUNT];
        u[0] = cos(o->facing * 3.14159265358979323846 / 180.0);
        u[1] = sin(o->facing * 3.14159265358979323846 / 180.0);
        st = PLX_OK;
        for (k = 0; k < n && (st == PLX_OK || st == PLX_E_RANGE); k++) {
            P[3 * k + 2] = o->height;
            st = plx_meter(e, 1, P + 3 * k, u, m);
            E[k] = m[o->quantity];
        }
    }
    if (st != PLX_OK && st != PLX_E_RANGE) { /* RANGE: pixels under buildings */
        fprintf(stderr, "polarlux heatmap: %s\n", plx_last_error(e));
        free(P), free(N), free(E);
        return cli_exit_code(st);
    }
    for (k = 0; k < n; k++)
        if (E[k] == E[k] && E[k] > top)
            top = E[k];
    if (!(top > 0))
        cli_warn("heatmap", o->c, "every pixel of the map is dark (0 lx): %s", cli_dark_reason(e));
    top = o->top > 0 ? o->top : pow(10.0, ceil(log10(fmax(top, 1.0))));
    map_w = (int)w;
    legend_w = h > 600 ? 150 : 90;
    c.w = map_w + legend_w;
    c.h = (int)h < 200 ? 200 : (int)h;
    c.rgb = calloc((size_t)c.w * c.h, 3);
    c.x0 = box[0];
    c.y0 = box[3];
    c.scale = 1.0 / res;
    if (!c.rgb) {
        free(P), free(N), free(E);
        return EXIT_FAIL;
    }
    for (k = 0; k < n; k++) {
        uint8_t rgb[3];
        if (E[k] != E[k])
            memcpy(rgb, grey, 3);
        else
            palette(scale_t(E[k], top), rgb);
        canvas_rect(&c, (int)(k % w), (int)(k / w), (int)(k % w) + 1, (int)(k / w) + 1, rgb);
    }
    for (k = 0; k < si.lamps; k++) {
        plx_lamp l;
        int px, py;
        plx_lamp_get(e, (uint32_t)k, &l);
        px = (int)((l.x - box[0]) / res);
        py = (int)((box[3] - l.y) / res);
        canvas_rect(&c, px - 1, py - 1, px + 2, py + 2, white);
    }
    free(P), free(N), free(E);
    if (o->path && draw_routes(e, &c, o, top) != EXIT_OK) {
        canvas_free(&c);
        return EXIT_FAIL;
    }
    canvas_rect(&c, map_w, 0, c.w, c.h, black);
    legend(&c, map_w, top);
    if (canvas_write(&c, o->out, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux heatmap: %s\n", err);
        canvas_free(&c);
        return EXIT_FAIL;
    }
    if (o->quantity != PLX_METER_H)
        printf("heatmap: %s illuminance at %g m facing %g deg\n",
               o->quantity == PLX_METER_SC ? "semi-cylindrical" : o->quantity == PLX_METER_V ? "vertical"
                                                                : "hemispherical", o->height, o->facing);
    printf("heatmap: %zux%zu pixels at %g m, scale %g..%g lx, written to %s\n", w, h, res, LUX_MIN, top, o->out);
    canvas_free(&c);
    return EXIT_OK;
}

int cmd_heatmap(int argc, char **argv)
{
    cli_common c;
    const char *scene = NULL;
    heat_opts o;
    plx_engine *e;
    int i, rc;
    memset(&c, 0, sizeof c);
    memset(&o, 0, sizeof o);
    o.quantity = PLX_METER_H;
    o.height = 1.5;
    for (i = 1; i < argc; i++) {
        int r = cli_common_option("heatmap", argc, argv, &i, &c);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(help, stdout);
            return EXIT_OK;
        }
        if ((strcmp(argv[i], "--res") == 0 || strcmp(argv[i], "-o") == 0 || strcmp(argv[i], "--max") == 0 ||
             strcmp(argv[i], "--box") == 0 || strcmp(argv[i], "--path") == 0 || strcmp(argv[i], "--quantity") == 0 ||
             strcmp(argv[i], "--height") == 0 || strcmp(argv[i], "--facing") == 0) && i + 1 >= argc)
            return cli_usage_error("heatmap", "%s needs a value", argv[i]);
        if (strcmp(argv[i], "--res") == 0) {
            if (cli_parse_double(argv[++i], &o.res) != 0 || !(o.res > 0))
                return cli_usage_error("heatmap", "--res '%s' is not a positive number of metres", argv[i]);
        } else if (strcmp(argv[i], "--max") == 0) {
            if (cli_parse_double(argv[++i], &o.top) != 0 || !(o.top > 0.1))
                return cli_usage_error("heatmap", "--max '%s' is not a number of lux above 0.1", argv[i]);
        } else if (strcmp(argv[i], "--quantity") == 0) {
            const char *q = argv[++i];
            o.quantity = strcmp(q, "h") == 0 ? PLX_METER_H : strcmp(q, "v") == 0 ? PLX_METER_V
                       : strcmp(q, "sc") == 0 ? PLX_METER_SC : strcmp(q, "hs") == 0 ? PLX_METER_HS : -1;
            if (o.quantity < 0)
                return cli_usage_error("heatmap", "--quantity '%s' is not h, v, sc or hs", q);
        } else if (strcmp(argv[i], "--height") == 0) {
            if (cli_parse_double(argv[++i], &o.height) != 0 || !(o.height >= 0) || !(o.height <= 1000))
                return cli_usage_error("heatmap", "--height '%s' is not a number of metres from 0 to 1000", argv[i]);
        } else if (strcmp(argv[i], "--facing") == 0) {
            if (cli_parse_double(argv[++i], &o.facing) != 0 || !isfinite(o.facing))
                return cli_usage_error("heatmap", "--facing '%s' is not a number of degrees", argv[i]);
        } else if (strcmp(argv[i], "-o") == 0) {
            o.out = argv[++i];
        } else if (strcmp(argv[i], "--path") == 0) {
            o.path = argv[++i];
        } else if (strcmp(argv[i], "--box") == 0) {
            char extra;
            if (sscanf(argv[++i], "%lf,%lf,%lf,%lf%c", &o.box[0], &o.box[1], &o.box[2], &o.box[3], &extra) != 4 ||
                !(o.box[2] > o.box[0]) || !(o.box[3] > o.box[1]))
                return cli_usage_error("heatmap", "--box '%s' is not X0,Y0,X1,Y1 with X1 > X0 and Y1 > Y0", argv[i]);
            o.have_box = 1;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            return cli_usage_error("heatmap", "unknown option '%s'", argv[i]);
        } else if (!scene) {
            scene = argv[i];
        } else {
            return cli_usage_error("heatmap", "unexpected argument '%s'", argv[i]);
        }
    }
    if (!scene)
        return cli_usage_error("heatmap", "missing SCENE");
    if (!o.out)
        return cli_usage_error("heatmap", "missing -o MAP.png");
    rc = cli_open_scene("heatmap", scene, &c, &e);
    if (rc != EXIT_OK)
        return rc;
    if (o.have_box && (cli_option_local("heatmap", "--box", e, &o.box[0], &o.box[1]) != 0 ||
                       cli_option_local("heatmap", "--box", e, &o.box[2], &o.box[3]) != 0)) {
        plx_engine_free(e);
        return EXIT_USAGE;
    }
    if (o.res == 0) {
        plx_scene_info si;
        const double *b;
        plx_scene_info_get(e, &si);
        b = o.have_box ? o.box : si.bounds;
        o.res = fmax(b[2] - b[0], b[3] - b[1]) / 1200.0;
    }
    o.c = &c;
    rc = run(e, &o);
    plx_engine_free(e);
    return rc;
}

/* The heat map's colour of 'lux' on its scale topped at 'top', for other
 * maps drawn in the same colours (polarlux tiles). Returns 0 when the lux
 * is at or below the bottom of the scale (no light: black), else 1. */
int heatmap_colour(double lux, double top, uint8_t rgb[3])
{
    palette(scale_t(lux, top), rgb);
    return lux > LUX_MIN;
}
