/* polarlux heatmap SCENE --res M -o map.png: top-down ground illuminance. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "canvas.h"
#include "cli.h"
#include "options.h"
#include "geotiff.h"
#include "png/image_write.h"
#include "route_io.h"

static const char help[] =
    "usage: polarlux heatmap SCENE [--res M] -o MAP.png|MAP.tif [options]\n"
    "\n"
    "Writes a top-down map of the direct ground illuminance over Bounds: one\n"
    "pixel per M x M metres, sampled at the pixel centre (exact 2.5D shadows,\n"
    "SPEC §2).\n"
    "MAP.png: coloured on a logarithmic scale from the 2nd to the 98th\n"
    "percentile of the lit pixels (rounded out to 1, 2, 5 x 10^k lx), with a\n"
    "legend in lux, a scale bar and a north arrow; footprints grey, lamps white\n"
    "dots (single pixels from 1 m per pixel). A world file MAP.pgw beside it\n"
    "places the map in the scene's coordinates (lon/lat degrees or metres).\n"
    "MAP.tif (or .tiff): a float32 GeoTIFF, band 1 the lux at pixel centres,\n"
    "NaN under buildings, georeferenced in the scene's CRS: WGS84 (EPSG:4326)\n"
    "for a lon/lat scene, the EPSG code of the scene's crs, else local metres.\n"
    "The map's lux (4 bytes a pixel) and the PNG's image are held whole, the\n"
    "lux computed in strips, so that the command's buffers and the engine\n"
    "together stay within --mem (exit 3 when the map and one row do not fit).\n"
    "\n"
    "  --res M    metres per pixel (default: the longer side of Bounds / 1200)\n"
    "  -o FILE    output .png or .tif (required)\n"
    "  --max LUX  a fixed scale from 0.1 lx to LUX (as 'polarlux tiles') instead\n"
    "             of the percentiles\n"
    "  --box X0,Y0,X1,Y1  map only this box (the scene's coordinates: lon/lat on\n"
    "             a lon/lat scene) instead of Bounds\n"
    "  --path FILE  draw these routes (GeoJSON LineStrings, as for 'polarlux\n"
    "             route') on the map, sampled every pixel and coloured by lux\n"
    "             on the same scale, outlined in cyan ('-': standard input)\n"
    "  --quantity Q  what to map (SPEC §6): h ground illuminance (default),\n"
    "             sc semi-cylindrical, v vertical, hs hemispherical illuminance;\n"
    "             v and sc face --facing, all but h are taken --height above\n"
    "             the ground (direct light)\n"
    "  --height M the meters' height for v, sc, hs (default 1.5)\n"
    "  --facing DEG  facing direction of v and sc, degrees counter-clockwise\n"
    "             from east (default 0); for sc also 'min': the least E_sc over\n"
    "             every horizontal facing direction (as 'polarlux tiles')\n"
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

/* Position of lux on the log colour scale from lo (0) to top (1). */
static double scale_t(double lux, double lo, double top)
{
    if (!(lux > lo))
        return 0.0;
    return log10(lux / lo) / log10(top / lo);
}

static void legend(canvas *c, int x0, double lo, double top)
{
    static const uint8_t white[3] = { 230, 230, 230 };
    int y, h = c->h - 40, ts = c->h > 600 ? 2 : 1;
    double v, marks[16];
    int n = 0, k;
    for (y = 0; y < h; y++) {
        uint8_t rgb[3];
        palette(1.0 - (double)y / (h - 1), rgb);
        canvas_rect(c, x0 + 10, 20 + y, x0 + 30, 21 + y, rgb);
    }
    marks[n++] = lo;
    for (v = pow(10.0, ceil(log10(lo) + 1e-9)); v < top * 0.9999 && n < 14; v *= 10.0)
        if (v > lo * 1.5 && v < top / 1.5)
            marks[n++] = v;
    marks[n++] = top;
    for (k = 0; k < n; k++) {
        char label[32];
        int yy = 20 + (int)((1.0 - scale_t(marks[k], lo, top)) * (h - 1));
        snprintf(label, sizeof label, marks[k] < 1 ? "%.2g lx" : "%.0f lx", marks[k]);
        canvas_rect(c, x0 + 30, yy, x0 + 36, yy + 1, white);
        canvas_text(c, x0 + 40, yy - 3 * ts, ts, label, white);
    }
}

typedef struct heat_opts {
    double res, top, box[4];
    int have_box, have_height, have_facing;
    heat_quantity q;          /* q.quantity PLX_METER_*; H maps the ground */
    const char *out, *path;
    const cli_common *c;
} heat_opts;

/* One segment a..b sampled every pixel: pass 0 the outline, pass 1 the fill. */
static void draw_segment(plx_engine *e, canvas *c, const heat_opts *o, double lo, double top, const double *a,
                         int pass)
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
        palette(scale_t(E + Ei, lo, top), rgb);
        canvas_rect(c, px - 2, py - 2, px + 3, py + 3, rgb);
    }
}

/* Draws the routes of 'path' sampled every pixel, coloured by lux. */
static int draw_routes(plx_engine *e, canvas *c, const heat_opts *o, double lo, double top)
{
    route_set rs;
    char err[512];
    size_t i;
    int pass;
    if (route_read(o->path, e, &rs, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux heatmap: %s\n", err);
        return EXIT_FAIL;
    }
    if (rs.note[0])
        cli_warn("heatmap", o->c, "%s: %s", o->path, rs.note);
    for (pass = 0; pass < 2; pass++) {
        for (i = 0; i < rs.n; i++) {
            uint32_t k;
            for (k = 0; k + 1 < rs.lines[i].n; k++)
                draw_segment(e, c, o, lo, top, rs.lines[i].xy + 2 * k, pass);
        }
    }
    route_free(&rs);
    return EXIT_OK;
}

/* ---- the map: illuminance in strips under the --mem budget ---------------- */

#define STRIP_BYTES_PER_PX (7 * sizeof(double)) /* P, N and E of a strip */

typedef struct heat_map {
    size_t w, h;
    double box[4], res;
    float *E;        /* w*h lux, NaN under buildings; top row first */
    size_t strip;    /* rows per strip */
} heat_map;

/* Rows per strip so the command's buffers (fixed + strips) stay within the
 * budget; 0 when not even one row fits. */
static size_t strip_rows(size_t w, size_t h, size_t fixed, size_t budget)
{
    size_t per_row = w * STRIP_BYTES_PER_PX, r;
    if (fixed + per_row > budget)
        return 0;
    r = (budget - fixed) / per_row;
    if (r > h)
        r = h;
    return r > 4096 ? 4096 : r;
}

/* One strip of rows [y0, y1) into m->E. */
static plx_status heat_strip(plx_engine *e, const heat_opts *o, heat_map *m, size_t y0, size_t y1, double *P,
                             double *N, double *E)
{
    size_t n = (y1 - y0) * m->w, k;
    plx_status st;
    for (k = 0; k < n; k++) {
        P[3 * k] = m->box[0] + (k % m->w + 0.5) * m->res;
        P[3 * k + 1] = m->box[3] - (y0 + k / m->w + 0.5) * m->res;
        P[3 * k + 2] = 0.0;
        N[3 * k] = N[3 * k + 1] = 0.0;
        N[3 * k + 2] = 1.0;
    }
    if (o->q.quantity == PLX_METER_H) {
        st = plx_illuminance(e, n, P, N, E, NULL, NULL);
    } else {
        st = PLX_OK;
        for (k = 0; k < n && (st == PLX_OK || st == PLX_E_RANGE); k++)
            st = heatmap_value(e, &o->q, P[3 * k], P[3 * k + 1], &E[k]);
    }
    for (k = 0; k < n; k++)
        m->E[y0 * m->w + k] = (float)E[k];
    return st == PLX_E_RANGE ? PLX_OK : st; /* RANGE: pixels under buildings (NaN) */
}

static int heat_compute(plx_engine *e, const heat_opts *o, heat_map *m, size_t fixed, const cli_common *c)
{
    double probe[3] = { 0, 0, 0 }, up[3] = { 0, 0, 1 }, E0;
    size_t y, budget;
    double *P, *N, *E;
    cli_progress pr;
    plx_illuminance(e, 1, probe, up, &E0, NULL, NULL); /* builds the light first: its memory counts */
    budget = cli_buffer_budget(e, c);
    m->strip = strip_rows(m->w, m->h, fixed, budget);
    if (m->strip == 0) {
        fprintf(stderr, "polarlux heatmap: a %zux%zu map needs %zu bytes of buffers, and --mem leaves %zu after the "
                        "engine; give more --mem or a coarser --res\n", m->w, m->h, fixed + m->w * STRIP_BYTES_PER_PX,
                budget);
        return EXIT_NOMEM;
    }
    P = malloc(sizeof *P * 3 * m->w * m->strip);
    N = malloc(sizeof *N * 3 * m->w * m->strip);
    E = malloc(sizeof *E * m->w * m->strip);
    if (!P || !N || !E) {
        free(P), free(N), free(E);
        fprintf(stderr, "polarlux heatmap: out of memory for a strip of %zu rows\n", m->strip);
        return EXIT_FAIL;
    }
    cli_progress_start(&pr);
    for (y = 0; y < m->h; y += m->strip) {
        size_t y1 = y + m->strip < m->h ? y + m->strip : m->h;
        plx_status st = heat_strip(e, o, m, y, y1, P, N, E);
        if (st != PLX_OK) {
            cli_progress_end(&pr);
            fprintf(stderr, "polarlux heatmap: %s\n", plx_last_error(e));
            free(P), free(N), free(E);
            return cli_exit_code(st);
        }
        cli_progress_step(&pr, "heatmap", y1, m->h);
    }
    cli_progress_end(&pr);
    free(P), free(N), free(E);
    return EXIT_OK;
}

/* ---- the colour scale: robust percentiles ----------------------------------- */

#define HIST_LO -3.0   /* log10 lux of the first bin */
#define HIST_BINS 1000 /* 0.01 decade each: 1e-3 .. 1e7 lx */

/* The p-th quantile (0..1) of the lit pixels (E > 0) from a log histogram;
 * 0 when none is lit. */
static double lit_quantile(const float *E, size_t n, double p)
{
    size_t hist[HIST_BINS];
    size_t k, lit = 0, acc = 0, want;
    memset(hist, 0, sizeof hist);
    for (k = 0; k < n; k++) {
        if (E[k] > 0) {
            int b = (int)floor((log10(E[k]) - HIST_LO) * 100.0);
            hist[b < 0 ? 0 : b >= HIST_BINS ? HIST_BINS - 1 : b]++;
            lit++;
        }
    }
    if (lit == 0)
        return 0.0;
    want = (size_t)ceil(p * lit);
    for (k = 0; k < HIST_BINS; k++) {
        acc += hist[k];
        if (acc >= want && acc > 0)
            return pow(10.0, HIST_LO + (k + 1) / 100.0); /* the bin's upper edge */
    }
    return pow(10.0, HIST_LO + HIST_BINS / 100.0);
}

/* The next value of 1, 2, 5 x 10^k at or above v (below v when down). */
static double nice(double v, int down)
{
    double p = pow(10.0, floor(log10(v))), m = v / p;
    if (down)
        return (m >= 5 ? 5 : m >= 2 ? 2 : 1) * p;
    return (m <= 1.0000001 ? 1 : m <= 2.0000001 ? 2 : m <= 5.0000001 ? 5 : 10) * p;
}

/* The scale: 2nd to 98th percentile of the lit pixels, widened to nice
 * values, at least one decade; --max gives the fixed scale 0.1 lx..max. */
static void heat_scale(const heat_map *m, double user_top, double *lo, double *top)
{
    size_t n = m->w * m->h;
    double p2 = lit_quantile(m->E, n, 0.02), p98 = lit_quantile(m->E, n, 0.98);
    if (user_top > 0) { /* a fixed scale, the same as 'polarlux tiles' */
        *lo = LUX_MIN;
        *top = user_top;
        return;
    }
    *lo = p2 > 0 ? fmax(LUX_MIN, nice(p2, 1)) : LUX_MIN;
    *top = p98 > 0 ? nice(p98, 0) : 1.0;
    if (*lo > *top / 10.0)
        *lo = *top / 10.0;
}

/* ---- the PNG ------------------------------------------------------------------ */

/* A bar of a nice length near a fifth of the map, bottom left, labelled in
 * metres (km from 1000 m). */
static void scale_bar(canvas *c, int map_w, int map_h, double res)
{
    static const uint8_t white[3] = { 240, 240, 240 }, black[3] = { 0, 0, 0 };
    double len = nice(map_w * res / 5.0, 1);
    int px = (int)(len / res + 0.5), x0 = 12, y0 = map_h - 16, ts = map_h > 600 ? 2 : 1;
    char label[32];
    if (px < 8 || map_h < 60)
        return;
    if (len >= 1000)
        snprintf(label, sizeof label, "%g km", len / 1000.0);
    else
        snprintf(label, sizeof label, "%g m", len);
    canvas_rect(c, x0 - 2, y0 - 2 - 10 * ts, x0 + px + 2, y0 + 6, black);
    canvas_rect(c, x0, y0, x0 + px, y0 + 4, white);
    canvas_rect(c, x0, y0 - 4, x0 + 1, y0, white);
    canvas_rect(c, x0 + px - 1, y0 - 4, x0 + px, y0, white);
    canvas_text(c, x0, y0 - 2 - 9 * ts, ts, label, white);
}

/* An arrow pointing up (north: the map's top row is north) with an N,
 * top right of the map. */
static void north_arrow(canvas *c, int map_w, int map_h)
{
    static const uint8_t white[3] = { 240, 240, 240 }, black[3] = { 0, 0, 0 };
    int ts = map_h > 600 ? 2 : 1, s = 10 * ts, cx = map_w - 14 - s / 2, y0 = 8, k;
    if (map_w < 60 || map_h < 60)
        return;
    canvas_rect(c, cx - s / 2 - 3, y0 - 3, cx + s / 2 + 4, y0 + 2 * s + 10 * ts + 3, black);
    for (k = 0; k < s; k++) /* the head: a triangle, one row per pixel */
        canvas_rect(c, cx - k / 2, y0 + k, cx + k / 2 + 1, y0 + k + 1, white);
    canvas_rect(c, cx - ts / 2, y0 + s, cx + ts / 2 + 1, y0 + 2 * s, white);
    canvas_text(c, cx - 2 * ts, y0 + 2 * s + 2, ts, "N", white);
}

/* Lamps: 3x3 white dots at street scale, single dim pixels at city scale
 * (res >= 1 m) so they do not hide the colours. */
static void draw_lamps(plx_engine *e, canvas *c, const heat_map *m)
{
    static const uint8_t white[3] = { 255, 255, 255 }, dim[3] = { 200, 230, 255 };
    plx_scene_info si;
    uint32_t k;
    int big = m->res < 1.0;
    plx_scene_info_get(e, &si);
    for (k = 0; k < si.lamps; k++) {
        plx_lamp l;
        int px, py;
        plx_lamp_get(e, k, &l);
        px = (int)floor((l.x - m->box[0]) / m->res);
        py = (int)floor((m->box[3] - l.y) / m->res);
        if (px < 0 || py < 0 || (size_t)px >= m->w || (size_t)py >= m->h)
            continue;
        if (big)
            canvas_rect(c, px - 1, py - 1, px + 2, py + 2, white);
        else
            canvas_rect(c, px, py, px + 1, py + 1, dim);
    }
}

/* The map and its world file belong together: both are written, then both
 * renamed into place (safe_out_commit), or neither. "-", a device or a
 * FIFO gets no world file (a line on stderr says so). */
static int write_map(const canvas *c, const char *out, const raster_frame *f)
{
    char err[512], *wpath = world_file_wanted(out) ? world_file_path(out) : NULL;
    safe_out *o[2] = { NULL, NULL };
    size_t n = wpath ? 2 : 1;
    int rc = EXIT_FAIL;
    if (!wpath && world_file_wanted(out))
        snprintf(err, sizeof err, "%s: out of memory", out);
    else if ((o[0] = safe_out_open(out, err, sizeof err)) && (!wpath || (o[1] = safe_out_open(wpath, err, sizeof err)))) {
        if (image_encode_png(o[0], out, c->w, c->h, c->rgb, 0, err, sizeof err) != 0) {
            safe_out_abort(o[0]);
            safe_out_abort(o[1]);
        } else {
            if (wpath)
                (void)world_file_encode(o[1], f);
            rc = safe_out_commit(o, n, err, sizeof err) == 0 ? EXIT_OK : EXIT_FAIL;
        }
    } else {
        safe_out_abort(o[0]);
    }
    if (rc != EXIT_OK)
        fprintf(stderr, "polarlux heatmap: %s\n", err);
    else if (!wpath)
        fprintf(stderr, "polarlux heatmap: no world file (.pgw) for '%s': it is not a regular file\n", out);
    free(wpath);
    return rc;
}

static int write_png(plx_engine *e, const heat_opts *o, const heat_map *m, double lo, double top)
{
    static const uint8_t grey[3] = { 60, 60, 66 }, black[3] = { 0, 0, 0 };
    canvas c;
    raster_frame f;
    size_t k, n = m->w * m->h;
    int map_w = (int)m->w, legend_w = m->h > 600 ? 150 : 90, rc;
    c.w = map_w + legend_w;
    c.h = (int)m->h < 200 ? 200 : (int)m->h;
    c.rgb = calloc((size_t)c.w * c.h, 3);
    c.x0 = m->box[0];
    c.y0 = m->box[3];
    c.scale = 1.0 / m->res;
    if (!c.rgb) {
        fprintf(stderr, "polarlux heatmap: out of memory for the %dx%d image\n", c.w, c.h);
        return EXIT_FAIL;
    }
    for (k = 0; k < n; k++) {
        uint8_t rgb[3];
        if (m->E[k] != m->E[k])
            memcpy(rgb, grey, 3);
        else
            palette(scale_t(m->E[k], lo, top), rgb);
        canvas_rect(&c, (int)(k % m->w), (int)(k / m->w), (int)(k % m->w) + 1, (int)(k / m->w) + 1, rgb);
    }
    draw_lamps(e, &c, m);
    if (o->path && draw_routes(e, &c, o, lo, top) != EXIT_OK) {
        canvas_free(&c);
        return EXIT_FAIL;
    }
    scale_bar(&c, map_w, (int)m->h, m->res);
    north_arrow(&c, map_w, (int)m->h);
    canvas_rect(&c, map_w, 0, c.w, c.h, black);
    legend(&c, map_w, lo, top);
    raster_frame_of(e, m->box, m->res, &f);
    rc = write_map(&c, o->out, &f);
    canvas_free(&c);
    return rc;
}

/* The GeoTIFF's description of its band: the quantity mapped (it named E_h
 * for every --quantity). */
static void band_description(const heat_quantity *q, char *buf, size_t cap)
{
    const char *name = q->quantity == PLX_METER_SC ? "semi-cylindrical illuminance E_sc"
                       : q->quantity == PLX_METER_V ? "vertical illuminance E_v"
                                                    : "hemispherical illuminance E_hs";
    if (q->quantity == PLX_METER_H)
        snprintf(buf, cap, "polarlux heatmap: band 1 = direct horizontal ground illuminance E_h in lux at pixel "
                 "centres; NaN under buildings");
    else if (q->facing_min)
        snprintf(buf, cap, "polarlux heatmap: band 1 = direct %s in lux at %g m above pixel centres, the least over "
                 "every facing direction; NaN under buildings", name, q->height);
    else if (q->quantity == PLX_METER_HS)
        snprintf(buf, cap, "polarlux heatmap: band 1 = direct %s in lux at %g m above pixel centres; NaN under "
                 "buildings", name, q->height);
    else
        snprintf(buf, cap, "polarlux heatmap: band 1 = direct %s in lux at %g m above pixel centres, facing %g deg; "
                 "NaN under buildings", name, q->height, q->facing);
}

static int write_tiff(plx_engine *e, const heat_opts *o, const heat_map *m)
{
    raster_frame f;
    char err[512], what[256];
    raster_frame_of(e, m->box, m->res, &f);
    band_description(&o->q, what, sizeof what);
    if (geotiff_write(o->out, m->E, (int)m->w, (int)m->h, 1, &f, what, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux heatmap: %s\n", err);
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

static int run(plx_engine *e, const heat_opts *o)
{
    plx_scene_info si;
    heat_map m;
    double lo, top;
    int rc, tiff = is_tiff_path(o->out);
    size_t fixed, k, lit = 0;
    memset(&m, 0, sizeof m);
    plx_scene_info_get(e, &si);
    memcpy(m.box, o->have_box ? o->box : si.bounds, sizeof m.box);
    m.res = o->res;
    {   /* counted in doubles: no integer overflow for any finite box */
        double wd = ceil((m.box[2] - m.box[0]) / m.res), hd = ceil((m.box[3] - m.box[1]) / m.res);
        if (!(wd >= 1 && hd >= 1 && wd * hd <= 5e7 && wd <= 1e6 && hd <= 1e6)) {
            fprintf(stderr, "polarlux heatmap: --res %g over a box of %.0f x %.0f m gives %.0fx%.0f pixels "
                    "(at most 5e7, 1e6 a side)\n", m.res, m.box[2] - m.box[0], m.box[3] - m.box[1], wd, hd);
            return EXIT_USAGE;
        }
        m.w = (size_t)wd;
        m.h = (size_t)hd;
    }
    /* the map's floats, and the PNG's canvas (map + legend, >= 200 rows) */
    fixed = sizeof *m.E * m.w * m.h + (tiff ? 0 : 3 * (m.w + 150) * (m.h < 200 ? 200 : m.h));
    m.E = malloc(sizeof *m.E * m.w * m.h);
    if (!m.E) {
        fprintf(stderr, "polarlux heatmap: out of memory for %zu pixels\n", m.w * m.h);
        return EXIT_FAIL;
    }
    rc = heat_compute(e, o, &m, fixed, o->c);
    if (rc != EXIT_OK) {
        free(m.E);
        return rc;
    }
    for (k = 0; k < m.w * m.h; k++)
        lit += m.E[k] > 0;
    if (lit == 0)
        cli_warn("heatmap", o->c, "every pixel of the map is dark (0 lx): %s",
                 o->have_box && (m.box[2] < si.bounds[0] || m.box[0] > si.bounds[2] || m.box[3] < si.bounds[1] ||
                                 m.box[1] > si.bounds[3])
                     ? "--box lies wholly outside the scene's bounds (see 'polarlux info')"
                     : cli_dark_reason(e));
    heat_scale(&m, o->top, &lo, &top);
    rc = tiff ? write_tiff(e, o, &m) : write_png(e, o, &m, lo, top);
    if (rc == EXIT_OK && tiff)
        printf("heatmap: %zux%zu pixels at %g m, float32 GeoTIFF of lux (%zu lit), written to %s\n", m.w, m.h,
               m.res, lit, o->out);
    else if (rc == EXIT_OK)
        printf(o->top > 0 ? "heatmap: %zux%zu pixels at %g m, scale %g..%g lx (fixed by --max; %zu lit pixels), "
                            "written to %s%s\n"
                 : lit == 0 ? "heatmap: %zux%zu pixels at %g m, scale %g..%g lx (%zu lit pixels: the default scale), "
                              "written to %s%s\n"
                            : "heatmap: %zux%zu pixels at %g m, scale %g..%g lx (2nd-98th percentile of the %zu lit "
                              "pixels), written to %s%s\n",
               m.w, m.h, m.res, lo, top, lit, o->out, world_file_wanted(o->out) ? " (world file .pgw beside it)" : "");
    if (rc == EXIT_OK && o->q.quantity != PLX_METER_H && o->q.facing_min)
        printf("heatmap: semi-cylindrical illuminance at %g m, the least over every facing direction\n",
               o->q.height);
    else if (rc == EXIT_OK && o->q.quantity != PLX_METER_H)
        printf("heatmap: %s illuminance at %g m facing %g deg\n",
               o->q.quantity == PLX_METER_SC ? "semi-cylindrical" : o->q.quantity == PLX_METER_V ? "vertical"
                                                                    : "hemispherical", o->q.height, o->q.facing);
    if (rc == EXIT_OK && m.strip < m.h)
        printf("heatmap: computed in strips of %zu rows to stay within --mem\n", m.strip);
    free(m.E);
    return rc;
}

static int parse_res(const char *v, void *dst)
{
    double *r = dst;
    return cli_parse_real(v, 0, CLI_MAX_COORD, r) != 0 || !(*r > 0) ? -1 : 0;
}

static int parse_max(const char *v, void *dst)
{
    double *t = dst;
    return cli_parse_real(v, 0.1, 1e9, t) != 0 || !(*t > 0.1) ? -1 : 0;
}

static int parse_quantity(const char *q, void *dst)
{
    int *k = dst;
    *k = strcmp(q, "h") == 0 ? PLX_METER_H : strcmp(q, "v") == 0 ? PLX_METER_V
       : strcmp(q, "sc") == 0 ? PLX_METER_SC : strcmp(q, "hs") == 0 ? PLX_METER_HS : -1;
    return *k < 0 ? -1 : 0;
}

static int parse_box(const char *v, void *dst)
{
    double *b = dst;
    return cli_parse_coords(v, b, 4) != 0 || !(b[2] > b[0]) || !(b[3] > b[1]) ? -1 : 0;
}

int cmd_heatmap(int argc, char **argv)
{
    cli_common c;
    const char *scene = NULL;
    heat_opts o;
    plx_engine *e;
    int rc;
    const cli_opt opts[] = {
        CLI_OPT_VAL("--res", &o.res, parse_res, "--res '%s' is not a positive number of metres (at most 1e7)"),
        CLI_OPT_VAL("--max", &o.top, parse_max, "--max '%s' is not a number of lux above 0.1 (at most 1e9)"),
        CLI_OPT_VAL("--quantity", &o.q.quantity, parse_quantity, "--quantity '%s' is not h, v, sc or hs"),
        { "--height", NULL, &o.q.height, cli_opt_height, "--height '%s' is not a number of metres from 0 to 1000", 0,
          NULL, &o.have_height, NULL },
        { "--facing", NULL, &o.q, cli_opt_facing, "--facing '%s' is not a number of degrees or min", 0, NULL,
          &o.have_facing, NULL },
        CLI_OPT_STR("-o", &o.out),
        CLI_OPT_STR("--path", &o.path),
        { "--box", NULL, o.box, parse_box,
          "--box '%s' is not X0,Y0,X1,Y1 with X1 > X0 and Y1 > Y0 (finite, within 1e7 m)", 0, NULL, &o.have_box, NULL },
        CLI_OPT_END
    };
    cli_args pa;
    memset(&c, 0, sizeof c);
    memset(&o, 0, sizeof o);
    o.q.quantity = PLX_METER_H;
    o.q.height = 1.5;
    rc = cli_options_n("heatmap", help, argc, argv, opts, &c, NULL, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    scene = pa.npos ? pa.pos[0] : NULL;
    if (!scene)
        return cli_usage_error("heatmap", "missing SCENE");
    if (!o.out)
        return cli_usage_error("heatmap", "missing -o MAP.png");
    if (o.q.facing_min && o.q.quantity != PLX_METER_SC)
        return cli_usage_error("heatmap", "--facing min needs --quantity sc (the least E_sc over every direction)");
    if (!is_tiff_path(o.out) && cli_other_ext(o.out, "png"))
        return cli_usage_error("heatmap", "-o '%s': the map is written as PNG (.png) or GeoTIFF (.tif, .tiff); "
                               "name the file so", o.out);
    if (o.have_height && o.q.quantity == PLX_METER_H)
        cli_warn("heatmap", &c, "--height is for --quantity v, sc and hs: the ground illuminance (h) is mapped on "
                 "the ground");
    if (o.have_facing && !o.q.facing_min && o.q.quantity != PLX_METER_V && o.q.quantity != PLX_METER_SC)
        cli_warn("heatmap", &c, "--facing is for --quantity v and sc: %s illuminance faces no direction",
                 o.q.quantity == PLX_METER_H ? "ground" : "hemispherical");
    if (!cli_out_writable("heatmap", o.out))
        return EXIT_FAIL;
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

/* E_sc(u) = sum of I W (|w_h| + u.w_h) / (pi d^2) (SPEC §6, as light_meter
 * computes it) is affine in the unit vector u: S + u.V. Facing east, west
 * and north give S = (E_e + E_w) / 2, V = ((E_e - E_w) / 2, E_n - S), and
 * the least over every direction is S - |V| (u = -V / |V|). */
static plx_status sc_least(plx_engine *e, const double P[3], double *out)
{
    static const double U[6] = { 1, 0, -1, 0, 0, 1 };
    double Pr[9], m[3 * PLX_METER_COUNT], S, vx, vy;
    plx_status st;
    int k;
    for (k = 0; k < 9; k++)
        Pr[k] = P[k % 3];
    st = plx_meter(e, 3, Pr, U, m);
    if (st != PLX_OK) {
        *out = NAN;
        return st;
    }
    S = 0.5 * (m[PLX_METER_SC] + m[PLX_METER_COUNT + PLX_METER_SC]);
    vx = 0.5 * (m[PLX_METER_SC] - m[PLX_METER_COUNT + PLX_METER_SC]);
    vy = m[2 * PLX_METER_COUNT + PLX_METER_SC] - S;
    *out = fmax(0.0, S - hypot(vx, vy)); /* >= 0 but for rounding */
    return PLX_OK;
}

plx_status heatmap_value(plx_engine *e, const heat_quantity *q, double x, double y, double *out)
{
    double P[3], N[3] = { 0, 0, 1 }, u[2], m[PLX_METER_COUNT];
    plx_status st;
    P[0] = x;
    P[1] = y;
    P[2] = 0.0;
    if (q->quantity == PLX_METER_H)
        return plx_illuminance(e, 1, P, N, out, NULL, NULL);
    P[2] = q->height;
    if (q->quantity == PLX_METER_SC && q->facing_min)
        return sc_least(e, P, out);
    u[0] = cos(q->facing * 3.14159265358979323846 / 180.0);
    u[1] = sin(q->facing * 3.14159265358979323846 / 180.0);
    st = plx_meter(e, 1, P, u, m);
    *out = st == PLX_OK || st == PLX_E_RANGE ? m[q->quantity] : NAN;
    return st;
}

/* The heat map's colour of 'lux' on its scale topped at 'top', for other
 * maps drawn in the same colours (polarlux tiles). Returns 0 when the lux
 * is at or below the bottom of the scale (no light: black), else 1. */
int heatmap_colour(double lux, double top, uint8_t rgb[3])
{
    palette(scale_t(lux, LUX_MIN, top), rgb);
    return lux > LUX_MIN;
}
