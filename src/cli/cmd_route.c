/* polarlux route / dark-spots: how well lit are streets and routes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "geo_out.h"
#include "port.h"
#include "route_io.h"
#include "twin_engines.h"

static const char route_help[] =
    "usage: polarlux route SCENE --path FILE [--step M] [--dark-lux LX] [--geojson OUT] [options]\n"
    "\n"
    "Scores routes by their horizontal ground illuminance: direct light, plus\n"
    "indirect light from a bake's photon buffers (a note on stderr says which).\n"
    "FILE is GeoJSON with LineString or MultiLineString features, in\n"
    "the scene's coordinate rules (properties.units = \"m\", else WGS84 lon/lat\n"
    "projected with the scene's own centre). Each line is sampled every --step\n"
    "metres; for each line and each segment between its vertices the table gives\n"
    "length, mean, minimum and maximum lux, uniformity (min / mean), the share of\n"
    "length below --dark-lux, and the EN 13201 P-class met (P1 15/3 lx ... P6\n"
    "2/0.4 lx, mean / minimum; '-' for none). Path inside building footprints is\n"
    "not scored and its length is reported.\n"
    "SPEC §6 (EN 13201-2): the last columns are the minimum vertical (Ev) and\n"
    "semi-cylindrical (Esc) illuminance at --height above the path (default\n"
    "1.5 m), facing along the segment ('fw', first vertex to last) and back\n"
    "('bw'), direct light, and the P-class with the facial-recognition\n"
    "criterion too ('class_fr': also min Ev and min Esc over both ways,\n"
    "P1 5/5 ... P6 0.6/0.2 lx).\n"
    "\n"
    "  --path FILE      the routes (required; '-': standard input)\n"
    "  --step M         sampling step in metres (default 1)\n"
    "  --dark-lux LX    the dark threshold (default 1)\n"
    "  --height M       height of the Ev/Esc meters above the path (default 1.5)\n"
    "  --geojson OUT    also write one LineString feature per segment with flat\n"
    "                   properties: name, line, segment, length_m, mean_lx, min_lx,\n"
    "                   max_lx, uniformity, dark_share, p_class, blocked_m, and the\n"
    "                   whole line's as line_length_m, line_mean_lx, ...\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n"
    "\n"
    "With --network STREETS --from X,Y --to X,Y: the best-lit route over a street\n"
    "network ('polarlux route --network x --help').\n";

static const char spots_help[] =
    "usage: polarlux dark-spots SCENE [--res M] [--count N] [--spacing M] [--all] [--exhaustive]\n"
    "                           [--threads N] [-o OUT] [options]\n"
    "\n"
    "Lists the darkest points of the street area (ground outside building\n"
    "footprints, inside Bounds) as GeoJSON points with their lux, worst first.\n"
    "The ground is sampled on a grid of --res metres; by default only points\n"
    "within the reach of some lamp count (the area meant to be lit; --all\n"
    "takes every point); reported spots are at least --spacing apart.\n"
    "\n"
    "  --res M       grid spacing in metres (default 2)\n"
    "  --count N     how many spots (default 50)\n"
    "  --spacing M   minimum distance between reported spots (default 10)\n"
    "  --all         also points out of every lamp's reach\n"
    "  --exhaustive  compute every point's indirect light (slow on a bake; the\n"
    "                same spots: by default only points whose direct lux can\n"
    "                still make them candidates get it)\n"
    "  -o OUT        write the GeoJSON to OUT instead of standard output\n"
    "  --threads N   threads gathering a bake's indirect light (default: the\n"
    "                processors, at most 8, while the copies fit in half the\n"
    "                machine's memory); each further thread loads the bake\n"
    "                again (its own --mem block: N times the memory); the same\n"
    "                spots for any N\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n"
    "\n"
    "A spot's lux is direct plus indirect light (a bake's photon buffers;\n"
    "a scene file alone has direct light only).\n";

static void class_text(int c, char out[4])
{
    if (c)
        snprintf(out, 4, "P%d", c);
    else
        strcpy(out, "-");
}

/* The P class with the facial-recognition criterion (SPEC §6): E_v and
 * E_sc at 1.5 m facing both ways; fac = min Ev fw, bw, min Esc fw, bw. */
static int facial_class(const plx_route_stats *s, const double fac[4])
{
    double ev = fmin(fac[0], fac[1]), esc = fmin(fac[2], fac[3]);
    if (s->samples == 0 || ev != ev || esc != esc)
        return 0;
    return plx_p_class_facial(s->mean, s->min, ev, esc);
}

/* The characters of UTF-8 text s (its bytes but the continuation bytes):
 * the columns a name takes (street names hold ä and ö). */
static int text_width(const char *s)
{
    int n = 0;
    for (; *s; s++)
        n += ((unsigned char)*s & 0xc0u) != 0x80u;
    return n;
}

/* s, then spaces to width characters. */
static void print_padded(const char *s, int width)
{
    int k;
    fputs(s, stdout);
    for (k = text_width(s); k < width; k++)
        putchar(' ');
}

static void print_row(int width, const char *line, const char *seg, const plx_route_stats *s, const double fac[4])
{
    char cls[4], fr[4];
    class_text(s->p_class, cls);
    class_text(facial_class(s, fac), fr);
    print_padded(line, width);
    printf(" %-5s %9.1f %9.3f %9.3f %9.3f %6.3f %6.3f %-5s %8.3f %8.3f %8.3f %8.3f %s", seg,
           s->length, s->mean, s->min, s->max, s->uniformity, s->dark_share, cls, fac[0], fac[1], fac[2], fac[3],
           fr);
    if (s->blocked_length > 0) /* in one column whatever the class's width (no trailing spaces without it) */
        printf("%*s  (%.1f m inside buildings)", 3 - (int)strlen(fr), "", s->blocked_length);
    printf("\n");
}

static void stats_props(cJSON *o, const char *prefix, const plx_route_stats *s)
{
    static const char *const keys[] = { "length_m", "mean_lx", "min_lx", "max_lx", "uniformity", "dark_share",
                                         "blocked_m" };
    double v[7];
    char key[48], cls[4];
    int k;
    v[0] = s->length, v[1] = s->mean, v[2] = s->min, v[3] = s->max, v[4] = s->uniformity, v[5] = s->dark_share;
    v[6] = s->blocked_length;
    for (k = 0; k < 7; k++) {
        snprintf(key, sizeof key, "%s%s", prefix, keys[k]);
        cJSON_AddNumberToObject(o, key, v[k]);
    }
    class_text(s->p_class, cls);
    snprintf(key, sizeof key, "%sp_class", prefix);
    cJSON_AddStringToObject(o, key, cls);
}

/* One feature per segment, flat properties: the segment's numbers, and its
 * line's name, index and totals (line_...), as GIS tools style them. */
/* The SPEC §6 facial-recognition numbers of a segment or line (fac: min
 * E_v forward, backward, min E_sc forward, backward; -1 where not had). */
static void facial_props(cJSON *o, const char *prefix, const plx_route_stats *s, const double fac[4])
{
    static const char *const keys[] = { "min_ev_fw_lx", "min_ev_bw_lx", "min_esc_fw_lx", "min_esc_bw_lx" };
    char key[48], fr[4];
    int k;
    for (k = 0; k < 4; k++) {
        snprintf(key, sizeof key, "%s%s", prefix, keys[k]);
        cJSON_AddNumberToObject(o, key, fac[k] == fac[k] ? fac[k] : -1);
    }
    class_text(facial_class(s, fac), fr);
    snprintf(key, sizeof key, "%sp_class_facial", prefix);
    cJSON_AddStringToObject(o, key, fr);
}

static void add_segments(geo_out *g, const route_line *l, size_t li, const plx_route_stats *tot,
                         const plx_route_stats *seg, const double *ftot, const double *fac)
{
    uint32_t k;
    for (k = 0; k + 1 < l->n; k++) {
        cJSON *props = cJSON_CreateObject(), *coords = cJSON_CreateArray();
        cJSON_AddStringToObject(props, "name", l->name);
        cJSON_AddNumberToObject(props, "line", (double)li);
        cJSON_AddNumberToObject(props, "segment", k);
        stats_props(props, "", &seg[k]);
        stats_props(props, "line_", tot);
        facial_props(props, "", &seg[k], fac + 4 * k);
        facial_props(props, "line_", tot, ftot);
        cJSON_AddItemToArray(coords, geo_position(g, l->xy[2 * k], l->xy[2 * k + 1], NULL));
        cJSON_AddItemToArray(coords, geo_position(g, l->xy[2 * k + 2], l->xy[2 * k + 3], NULL));
        geo_add(g, geo_geometry("LineString", coords), props);
    }
}

typedef struct route_opts {
    const char *scene, *path, *geojson;
    double step, dark, height;
    cli_common c;
} route_opts;

/* The path's samples at --step, counted before any work: at most
 * ROUTE_MAX_SAMPLES in all (and 1e7 a segment, the engine's limit). */
#define ROUTE_MAX_SAMPLES 1e8
/* The line's length in metres (the scene's frame). */
static double line_length(const route_line *l)
{
    double len = 0.0;
    uint32_t k;
    for (k = 0; k + 1 < l->n; k++)
        len += hypot(l->xy[2 * k + 2] - l->xy[2 * k], l->xy[2 * k + 3] - l->xy[2 * k + 1]);
    return len;
}

static int check_samples(const route_opts *o, const route_set *rs)
{
    double total = 0, longest = 0, len = 0;
    size_t i;
    uint32_t k;
    for (i = 0; i < rs->n; i++)
        for (k = 0; k + 1 < rs->lines[i].n; k++) {
            const double *a = rs->lines[i].xy + 2 * k;
            double d = hypot(a[2] - a[0], a[3] - a[1]);
            len += d;
            total += ceil(d / o->step) + 1;
            longest = fmax(longest, ceil(d / o->step));
        }
    for (i = 0; i < rs->n; i++)
        if (!(line_length(&rs->lines[i]) > 0.0)) { /* a mean over no length: 0 lx would read as dark */
            fprintf(stderr, "polarlux route: %s: line %s (feature %u) has no length (its %u positions are one "
                            "point): give it two distinct positions\n", o->path, rs->lines[i].name,
                    rs->lines[i].feature, rs->lines[i].n);
            return EXIT_FAIL;
        }
    if (total > ROUTE_MAX_SAMPLES || longest > 1e7)
        return cli_usage_error("route", "--step %g gives %.0f samples over the path's %.0f m (at most 1e8, "
                               "1e7 a segment)", o->step, total, len);
    return EXIT_OK;
}

/* The box of the scene's bounds and every lamp's reach: outside it nothing
 * lights a route and nothing is known of the ground. */
static void scene_reach(plx_engine *e, double b[4])
{
    plx_scene_info si;
    plx_lamp l;
    uint32_t i;
    plx_scene_info_get(e, &si);
    memcpy(b, si.bounds, 4 * sizeof b[0]);
    for (i = 0; i < si.lamps; i++)
        if (plx_lamp_get(e, i, &l) == PLX_OK) {
            b[0] = fmin(b[0], l.x - l.radius);
            b[1] = fmin(b[1], l.y - l.radius);
            b[2] = fmax(b[2], l.x + l.radius);
            b[3] = fmax(b[3], l.y + l.radius);
        }
}

/* The metres of the polyline xy (n vertices) outside box b: each segment
 * clipped to the box (Liang-Barsky), the rest summed. */
static double outside_length(const double *xy, uint32_t n, const double b[4])
{
    double out = 0.0;
    uint32_t k;
    for (k = 0; k + 1 < n; k++) {
        const double *p = xy + 2 * k, *q = p + 2;
        double d[2] = { q[0] - p[0], q[1] - p[1] }, t0 = 0.0, t1 = 1.0, len = hypot(d[0], d[1]);
        int c, ok = 1;
        for (c = 0; c < 2 && ok; c++) {
            double lo = b[c] - p[c], hi = b[c + 2] - p[c];
            if (d[c] == 0.0) {
                ok = lo <= 0.0 && hi >= 0.0;
            } else {
                double a = lo / d[c], z = hi / d[c];
                if (a > z) {
                    double t = a;
                    a = z;
                    z = t;
                }
                t0 = fmax(t0, a);
                t1 = fmin(t1, z);
                ok = t0 <= t1;
            }
        }
        out += ok ? len * (1.0 - (t1 - t0)) : len;
    }
    return out;
}

static int score_all(plx_engine *e, const route_opts *o, route_set *rs)
{
    geo_out g;
    size_t i;
    cli_progress pr;
    int rc = EXIT_OK, width = 8;
    memset(&g, 0, sizeof g);
    if (o->geojson && geo_begin(&g, e) != 0)
        return EXIT_FAIL;
    for (i = 0; i < rs->n; i++) /* the names' column as wide as the longest */
        width = text_width(rs->lines[i].name) > width ? text_width(rs->lines[i].name) : width;
    print_padded("line", width);
    printf(" %-5s %9s %9s %9s %9s %6s %6s %-5s %8s %8s %8s %8s %s\n", "seg", "length_m", "mean_lx",
           "min_lx", "max_lx", "U0", "dark", "class", "Ev_fw", "Ev_bw", "Esc_fw", "Esc_bw", "class_fr");
    cli_progress_start(&pr);
    for (i = 0; i < rs->n; i++) {
        const route_line *l = &rs->lines[i];
        plx_route_stats tot, *seg;
        double *fac = malloc(sizeof(double) * 4 * l->n), ftot[4];
        char name[32], sname[16];
        uint32_t k;
        plx_status st;
        seg = malloc(sizeof *seg * l->n);
        if (!seg || !fac) {
            free(seg);
            free(fac);
            rc = EXIT_FAIL;
            break;
        }
        st = plx_route_score(e, l->xy, l->n, o->step, o->dark, &tot, seg);
        if (st == PLX_OK)
            st = plx_route_facial(e, l->xy, l->n, o->step, o->height, fac, ftot);
        if (st != PLX_OK) {
            fprintf(stderr, "polarlux route: %s: line %zu: %s\n", o->path, i, plx_last_error(e));
            free(seg);
            free(fac);
            rc = cli_exit_code(st);
            break;
        }
        snprintf(name, sizeof name, "%s", l->name);
        {
            double b[4], far;
            scene_reach(e, b);
            far = outside_length(l->xy, l->n, b);
            if (far > 1.0) /* helper-64: 2 km east of the district counted as measured dark metres */
                cli_warn("route", &o->c, "%s: line %s runs %.1f m outside the scene (its buildings' box and 50 m, "
                         "and every lamp's reach): no lamp and no building there, so those metres count as dark",
                         o->path, l->name, far);
        }
        if (tot.samples > 0 && !(tot.max > 0))
            cli_warn("route", &o->c, "%s: line %s is entirely dark (0 lx): %s", o->path, l->name,
                     cli_dark_reason(e));
        print_row(width, name, "all", &tot, ftot);
        for (k = 0; k + 1 < l->n; k++) {
            snprintf(sname, sizeof sname, "%u", k);
            print_row(width, "", sname, &seg[k], fac + 4 * k);
        }
        if (g.root)
            add_segments(&g, l, i, &tot, seg, ftot, fac);
        cli_progress_step(&pr, "route", i + 1, rs->n);
        free(seg);
        free(fac);
    }
    cli_progress_end(&pr);
    if (rc == EXIT_OK)
        cli_light_note("route", &o->c, e);
    if (g.root && rc == EXIT_OK && geo_write(&g, "route", o->geojson) != 0)
        rc = EXIT_FAIL;
    geo_free(&g);
    return rc;
}

static int parse_step(const char *v, void *dst)
{
    return cli_parse_real(v, 0.01, CLI_MAX_COORD, dst);
}

static int parse_dark_lux(const char *v, void *dst)
{
    return cli_parse_real(v, 0, 1e9, dst);
}

int cmd_route(int argc, char **argv)
{
    route_opts o;
    plx_engine *e;
    route_set rs;
    char err[512];
    int i, rc;
    const cli_opt opts[] = {
        CLI_OPT_STR("--path", &o.path),
        CLI_OPT_STR("--geojson", &o.geojson),
        CLI_OPT_VAL("--step", &o.step, parse_step, "--step '%s' is not a number of metres from 0.01 to 1e7"),
        CLI_OPT_VAL("--height", &o.height, cli_opt_height, "--height '%s' is not a number of metres from 0 to 1000"),
        CLI_OPT_VAL("--dark-lux", &o.dark, parse_dark_lux, "--dark-lux '%s' is not a number of lux from 0 to 1e9"),
        CLI_OPT_END
    };
    cli_args pa;
    static const char *const network_only[] = { "--from", "--to", "--dark-weight", "--max-detour", "--snap" };
    size_t k;
    for (i = 1; i < argc; i++) /* the best-lit route over a street network: cmd_network.c */
        if (strcmp(argv[i], "--network") == 0)
            return cmd_route_network(argc, argv);
    for (i = 1; i < argc; i++) /* its options, said as such rather than unknown */
        for (k = 0; k < sizeof network_only / sizeof *network_only; k++)
            if (strcmp(argv[i], network_only[k]) == 0)
                return cli_usage_error("route", "%s needs --network STREETS.geojson (the best-lit route between "
                                       "two points over a street network); without it route scores --path",
                                       argv[i]);
    memset(&o, 0, sizeof o);
    o.step = 1.0;
    o.dark = 1.0;
    o.height = 1.5;
    rc = cli_options_n("route", route_help, argc, argv, opts, &o.c, NULL, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    o.scene = pa.npos ? pa.pos[0] : NULL;
    if (!o.scene)
        return cli_usage_error("route", "missing SCENE");
    if (!o.path)
        return cli_usage_error("route", "missing --path FILE");
    if (!cli_out_writable("route", o.geojson))
        return EXIT_FAIL;
    rc = cli_open_scene("route", o.scene, &o.c, &e);
    if (rc != EXIT_OK)
        return rc;
    if (route_read(o.path, e, &rs, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux route: %s\n", err);
        plx_engine_free(e);
        return EXIT_FAIL;
    }
    if (rs.note[0])
        cli_warn("route", &o.c, "%s: %s", o.path, rs.note);
    rc = check_samples(&o, &rs);
    if (rc == EXIT_OK)
        rc = score_all(e, &o, &rs);
    route_free(&rs);
    plx_engine_free(e);
    return rc;
}

/* ---- dark spots ------------------------------------------------------------ */

/* A street point of the grid: its index j * w + i and its lux (exact:
 * direct + indirect; else direct only, a bound below the exact lux). */
typedef struct spot {
    uint32_t k;
    uint32_t exact;
    double lux;
} spot;

/* The order spots are taken in: darkest first, then by y, then x (the grid
 * order). */
static int spot_before(const spot *p, const spot *q)
{
    if (p->lux != q->lux)
        return p->lux < q->lux;
    return p->k < q->k;
}

static int cmp_spot(const void *a, const void *b)
{
    return spot_before(a, b) ? -1 : spot_before(b, a) ? 1 : 0;
}

#define SPOT_STRIP 65536 /* grid points per illuminance call, at most */
#define SPOT_POINT_BYTES (3 * sizeof(double) * 2 + 2 * sizeof(double) + 2 * sizeof(uint32_t))
#define SPOT_MIN_CANDIDATES 1024
#define SPOT_PER_COUNT 256 /* candidates the first pass keeps per spot asked (at least SPOT_MIN_CANDIDATES) */

/* The street points are not all kept: a pass over the grid keeps the `cap`
 * darkest of those after `after` (in spot_before's order) in a max-heap,
 * so the command's buffers stay within --mem however fine --res is. The
 * spacing rule then takes them in order; when it runs out of candidates
 * before --count spots, the next pass continues after the last one. The
 * spots are those of one sort of every street point, pass or no pass.
 *
 * Indirect light (a final gather a point, on a bake: a thousand times the
 * direct light's cost) is computed only where it can change the answer:
 * a point's direct lux is a bound below its lux, so a point whose bound
 * is already after the cap-th darkest lux found cannot be a candidate
 * (spot_pass). That first pass keeps SPOT_PER_COUNT candidates a spot
 * asked; a pass after it (the spacing rule left too few) computes it at
 * every point, as --exhaustive does from the start (the reference): a
 * later pass's points darker than its start would each be gathered twice
 * by the bounds, which made it slower than gathering once everywhere. */
typedef struct spot_grid {
    double x0, y0, res;
    size_t w, h, strip;
    spot *heap;          /* max-heap of the darkest candidates of this pass */
    size_t n, cap;
    size_t cap_mem;      /* the most candidates --mem leaves room for (at most the grid points) */
    int mem_limited;     /* cap_mem is below the grid points: --mem sets the passes */
    spot after;          /* this pass takes spots after this one ... */
    int has_after;       /* ... when set */
    int exhaustive;      /* every point's lux exact at once (--exhaustive, or no indirect light) */
    int no_indirect;     /* the engine has no photon buffers: the direct lux is exact */
    size_t offered;      /* street points after `after` seen this pass */
    size_t unbounded;    /* of them, those step 1 gathered or bounded by 0 (no direct light) */
    size_t street;       /* street points of the grid (first pass) */
    double max_lux;      /* the brightest street point's lux, direct only unless exhaustive (first pass) */
    size_t gathered;     /* points whose indirect light was computed */
    twin_set tg;         /* the gathers shared with the bake's twins (--threads) */
} spot_grid;

/* One pass's buffers: a strip of grid points. */
typedef struct spot_bufs {
    double *P, *N, *E, *Ei;
    uint32_t *reach, *mark;
} spot_bufs;

static void spot_xy(const spot_grid *g, uint32_t k, double *x, double *y)
{
    *x = g->x0 + (k % g->w + 0.5) * g->res;
    *y = g->y0 + (k / g->w + 0.5) * g->res;
}

static void heap_swap(spot *h, size_t a, size_t b)
{
    spot t = h[a];
    h[a] = h[b];
    h[b] = t;
}

static void heap_down(spot *h, size_t n, size_t i)
{
    for (;;) {
        size_t l = 2 * i + 1, r = l + 1, m = i;
        if (l < n && spot_before(&h[m], &h[l]))
            m = l;
        if (r < n && spot_before(&h[m], &h[r]))
            m = r;
        if (m == i)
            break;
        heap_swap(h, i, m);
        i = m;
    }
}

/* Whether spot s (its lux exact or a bound below) can still be one of
 * this pass's candidates: the heap has room, or s is before its last. */
static int spot_may_enter(const spot_grid *g, const spot *s)
{
    return g->n < g->cap || spot_before(s, &g->heap[0]);
}

/* Offers one street point (after `after`) to this pass's candidates. */
static void spot_offer(spot_grid *g, spot s)
{
    spot *h = g->heap;
    size_t i;
    if (g->n < g->cap) {
        for (i = g->n++, h[i] = s; i > 0 && spot_before(&h[(i - 1) / 2], &h[i]); i = (i - 1) / 2)
            heap_swap(h, i, (i - 1) / 2);
        return;
    }
    if (!spot_before(&s, &h[0]))
        return;
    h[0] = s;
    heap_down(h, g->n, 0);
}

/* Whether s is after this pass's start (`after`). */
static int spot_after(const spot_grid *g, const spot *s)
{
    return !g->has_after || spot_before(&g->after, s);
}

static int spot_fail(plx_engine *e, plx_status st)
{
    fprintf(stderr, "polarlux dark-spots: %s\n", plx_last_error(e));
    return cli_exit_code(st);
}

/* Grid points [k0, k1) in reach of some lamp (every one with --all): their
 * positions and grid indices in b (P, reach), their direct lux (E, NaN
 * under a building); *m: how many. */
static int spot_direct(plx_engine *e, const spot_grid *g, size_t k0, size_t k1, int all, spot_bufs *b, size_t *m)
{
    size_t k, n = k1 - k0;
    plx_status st;
    *m = 0;
    for (k = 0; k < n; k++) {
        spot_xy(g, (uint32_t)(k0 + k), &b->P[3 * k], &b->P[3 * k + 1]);
        b->P[3 * k + 2] = 0.0;
    }
    if (!all && (st = plx_lamps_in_reach(e, n, b->P, b->reach)) != PLX_OK)
        return spot_fail(e, st);
    for (k = 0; k < n; k++) {
        if (!all && b->reach[k] == 0)
            continue;
        memmove(&b->P[3 * *m], &b->P[3 * k], 3 * sizeof *b->P);
        b->N[3 * *m] = b->N[3 * *m + 1] = 0.0;
        b->N[3 * *m + 2] = 1.0;
        b->reach[(*m)++] = (uint32_t)(k0 + k);
    }
    st = plx_illuminance(e, *m, b->P, b->N, b->E, NULL, NULL);
    return st != PLX_OK && st != PLX_E_RANGE ? spot_fail(e, st) : EXIT_OK;
}

/* The exact lux (direct + indirect) of the points b->mark[0 .. nm) of the
 * strip, into b->E; their positions and grid indices moved to the front
 * of b->P and b->reach (marks rise: nothing is read after it is moved
 * over). */
static int spot_exact(plx_engine *e, spot_grid *g, spot_bufs *b, size_t nm)
{
    size_t j;
    plx_status st;
    plx_engine *failed;
    for (j = 0; j < nm; j++) {
        memmove(&b->P[3 * j], &b->P[3 * b->mark[j]], 3 * sizeof *b->P);
        b->reach[j] = b->reach[b->mark[j]];
    }
    st = twin_illuminance(&g->tg, e, nm, b->P, b->N, b->E, b->Ei, &failed);
    if (st != PLX_OK && st != PLX_E_RANGE)
        return spot_fail(failed, st);
    for (j = 0; j < nm; j++)
        b->E[j] += b->Ei[j];
    g->gathered += nm;
    return EXIT_OK;
}

/* Step 1 of a pass on grid points [k0, k1): every street point after
 * `after` offered with its direct lux as a bound (counted), or, where
 * that bound is not after `after` (or --exhaustive), its exact lux. */
static int spot_bound_strip(plx_engine *e, spot_grid *g, size_t k0, size_t k1, int all, spot_bufs *b)
{
    size_t k, m, nm = 0;
    int rc = spot_direct(e, g, k0, k1, all, b, &m);
    if (rc != EXIT_OK)
        return rc;
    for (k = 0; k < m; k++) {
        spot s;
        if (b->E[k] != b->E[k])
            continue; /* under a building */
        s.k = b->reach[k];
        s.exact = 0;
        s.lux = b->E[k];
        if (!g->has_after) {
            g->street++;
            g->max_lux = g->street == 1 || s.lux > g->max_lux ? s.lux : g->max_lux;
        }
        if (g->no_indirect)
            s.exact = 1;
        else if (g->exhaustive || !spot_after(g, &s)) {
            b->mark[nm++] = (uint32_t)k; /* the exact lux decides */
            continue;
        }
        if (!spot_after(g, &s))
            continue;
        g->offered++;
        g->unbounded += !s.exact && !(s.lux > 0.0);
        spot_offer(g, s);
    }
    if (nm == 0 || (rc = spot_exact(e, g, b, nm)) != EXIT_OK)
        return rc;
    for (k = 0; k < nm; k++) {
        spot s;
        s.k = b->reach[k];
        s.exact = 1;
        s.lux = b->E[k];
        if (g->exhaustive && !g->has_after)
            g->max_lux = s.lux > g->max_lux ? s.lux : g->max_lux;
        if (!spot_after(g, &s))
            continue;
        g->offered++;
        g->unbounded++;
        spot_offer(g, s);
    }
    return EXIT_OK;
}

/* Step 2: the candidates whose lux is a bound get their exact lux (in
 * strips of b's size), and the heap is made again. */
static int spot_exact_heap(plx_engine *e, spot_grid *g, spot_bufs *b)
{
    size_t i = 0, k;
    while (i < g->n) {
        size_t nm = 0, first = i;
        int rc;
        for (; i < g->n && nm < g->strip; i++)
            if (!g->heap[i].exact) {
                spot_xy(g, g->heap[i].k, &b->P[3 * nm], &b->P[3 * nm + 1]);
                b->P[3 * nm + 2] = 0.0;
                b->N[3 * nm] = b->N[3 * nm + 1] = 0.0;
                b->N[3 * nm + 2] = 1.0;
                b->mark[nm] = (uint32_t)nm;
                b->reach[nm] = g->heap[i].k;
                nm++;
            }
        if (nm == 0)
            continue;
        if ((rc = spot_exact(e, g, b, nm)) != EXIT_OK)
            return rc;
        for (k = first, nm = 0; k < i; k++)
            if (!g->heap[k].exact) {
                g->heap[k].lux = b->E[nm++];
                g->heap[k].exact = 1;
            }
    }
    for (k = g->n / 2; k-- > 0;)
        heap_down(g->heap, g->n, k);
    return EXIT_OK;
}

/* Step 3 on grid points [k0, k1), when step 1 filled the heap: the points
 * step 1 left out (bound after `last`, its last candidate then) whose
 * bound is still before the heap's last get their exact lux and are
 * offered. A point whose exact lux step 1 took is taken again. */
static int spot_refine_strip(plx_engine *e, spot_grid *g, size_t k0, size_t k1, int all, const spot *last,
                             spot_bufs *b)
{
    size_t k, m, nm = 0;
    int rc = spot_direct(e, g, k0, k1, all, b, &m);
    if (rc != EXIT_OK)
        return rc;
    for (k = 0; k < m; k++) {
        spot s;
        if (b->E[k] != b->E[k])
            continue;
        s.k = b->reach[k];
        s.exact = 0;
        s.lux = b->E[k];
        if (spot_after(g, &s) && (!spot_before(last, &s) || !spot_may_enter(g, &s)))
            continue; /* in the heap since step 1, or never a candidate */
        b->mark[nm++] = (uint32_t)k;
    }
    if (nm == 0 || (rc = spot_exact(e, g, b, nm)) != EXIT_OK)
        return rc;
    for (k = 0; k < nm; k++) {
        spot s;
        s.k = b->reach[k];
        s.exact = 1;
        s.lux = b->E[k];
        if (spot_after(g, &s) && spot_before(last, &s)) /* else not after `after`, or in the heap since step 1 */
            spot_offer(g, s);
    }
    return EXIT_OK;
}

/* One sweep of a pass over every grid point, strip by strip (progress
 * on a terminal): step 1 (spot_bound_strip, from an empty heap) or step
 * 3 (spot_refine_strip, last: step 1's last candidate). */
static int spot_sweep(plx_engine *e, spot_grid *g, int all, int pass, int step, const spot *last, spot_bufs *b)
{
    size_t total = g->w * g->h, k0;
    char what[64];
    cli_progress pr;
    int rc = EXIT_OK;
    if (step == 1) {
        g->n = g->offered = g->unbounded = 0;
        if (!g->has_after) {
            g->street = 0;
            g->max_lux = 0.0;
        }
    }
    snprintf(what, sizeof what, "dark-spots%s%s", step == 3 ? " (exact lux)" : "", pass > 1 ? " (again)" : "");
    cli_progress_start(&pr);
    for (k0 = 0; rc == EXIT_OK && k0 < total; k0 += g->strip) {
        size_t k1 = k0 + g->strip < total ? k0 + g->strip : total;
        rc = step == 1 ? spot_bound_strip(e, g, k0, k1, all, b) : spot_refine_strip(e, g, k0, k1, all, last, b);
        cli_progress_step(&pr, what, k1, total);
    }
    cli_progress_end(&pr);
    return rc;
}

/* From here on every point's lux is exact at once, as --exhaustive: the
 * heap as large as --mem leaves room for. */
static int spot_all_exact(spot_grid *g)
{
    spot *h = realloc(g->heap, sizeof *h * (g->cap_mem ? g->cap_mem : 1));
    if (!h) {
        fprintf(stderr, "polarlux dark-spots: out of memory for %zu candidate points\n", g->cap_mem);
        return EXIT_FAIL;
    }
    g->heap = h;
    g->cap = g->cap_mem;
    g->exhaustive = 1;
    return EXIT_OK;
}

/* One pass over every grid point, strip by strip (progress on a terminal);
 * leaves this pass's candidates, the `cap` darkest street points after
 * `after` by their exact lux, sorted in g->heap[0 .. n). Step 1 keeps
 * the darkest by bound, step 2 makes them exact, step 3 (when step 1's
 * heap was full) brings in the points whose bound is before the last of
 * them: a point left out has a bound, and so a lux, at or after it.
 * When at least half the points step 1 saw were gathered or had a bound
 * of 0 (no direct light: out of reach with --all, or in shadow), bounds
 * would rule out too few: the pass starts again gathering everywhere. */
static int spot_pass(plx_engine *e, spot_grid *g, int all, int pass)
{
    spot_bufs b;
    spot last = { 0, 0, 0.0 };
    int rc = EXIT_OK;
    b.P = malloc(sizeof *b.P * 3 * g->strip);
    b.N = malloc(sizeof *b.N * 3 * g->strip);
    b.E = malloc(sizeof *b.E * g->strip);
    b.Ei = malloc(sizeof *b.Ei * g->strip);
    b.reach = malloc(sizeof *b.reach * g->strip);
    b.mark = malloc(sizeof *b.mark * g->strip);
    if (!b.P || !b.N || !b.E || !b.Ei || !b.reach || !b.mark) {
        fprintf(stderr, "polarlux dark-spots: out of memory\n");
        rc = EXIT_FAIL;
    }
    if (rc == EXIT_OK)
        rc = spot_sweep(e, g, all, pass, 1, NULL, &b);
    if (rc == EXIT_OK && !g->exhaustive && 2 * (g->unbounded + g->cap) >= g->offered) {
        /* most points have no direct light (a bound of 0) or are gathered
         * anyway: the bounds would rule out too few; gather everywhere */
        if ((rc = spot_all_exact(g)) == EXIT_OK)
            rc = spot_sweep(e, g, all, pass, 1, NULL, &b);
    }
    if (rc == EXIT_OK && !g->exhaustive && g->n == g->cap) { /* full: steps 2 and 3 */
        last = g->heap[0]; /* step 1's last candidate, by bound */
        if ((rc = spot_exact_heap(e, g, &b)) == EXIT_OK)
            rc = spot_sweep(e, g, all, pass, 3, &last, &b);
    } else if (rc == EXIT_OK && !g->exhaustive) { /* every point after `after` a candidate: step 2 */
        rc = spot_exact_heap(e, g, &b);
    }
    free(b.P), free(b.N), free(b.E), free(b.Ei), free(b.reach), free(b.mark);
    if (g->n > 1) /* the heap is empty (maybe NULL) when there are no spots */
        qsort(g->heap, g->n, sizeof *g->heap, cmp_spot);
    return rc;
}

/* Sizes the strip and the candidate heap from what --mem leaves the
 * command (at most SPOT_PER_COUNT a spot asked, when not --exhaustive);
 * 0, or the exit code after a message. */
static int spot_buffers(plx_engine *e, const cli_common *c, spot_grid *g, long count)
{
    size_t budget = cli_buffer_budget(e, c), total = g->w * g->h;
    size_t pick = sizeof(spot) * (size_t)count, fixed, need, want;
    g->strip = budget / 4 / SPOT_POINT_BYTES;
    g->strip = g->strip > SPOT_STRIP ? SPOT_STRIP : g->strip < 64 ? 64 : g->strip;
    fixed = g->strip * SPOT_POINT_BYTES + pick;
    need = fixed + sizeof(spot) * SPOT_MIN_CANDIDATES;
    if (budget < need) {
        fprintf(stderr, "polarlux dark-spots: --mem leaves %zu bytes for the command's own buffers; "
                "it needs %zu (grid strips, %ld spots, %d candidates): raise --mem\n", budget, need, count,
                SPOT_MIN_CANDIDATES);
        return EXIT_NOMEM;
    }
    g->cap_mem = (budget - fixed) / sizeof(spot);
    g->mem_limited = g->cap_mem < total;
    g->cap_mem = g->cap_mem > total ? total : g->cap_mem;
    want = (size_t)count * SPOT_PER_COUNT;
    want = want < SPOT_MIN_CANDIDATES ? SPOT_MIN_CANDIDATES : want;
    g->cap = g->exhaustive || g->cap_mem <= want ? g->cap_mem : want;
    g->heap = malloc(sizeof *g->heap * (g->cap ? g->cap : 1));
    if (!g->heap) {
        fprintf(stderr, "polarlux dark-spots: out of memory for %zu candidate points\n", g->cap);
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

/* Whether (x, y) lies between two footprints: on a wall two buildings
 * share, where the grid of a city drawn on whole metres falls (the
 * ground there is no street: nothing lights it). Both neighbours a hair
 * away along x, or both along y, are inside a building (nan). */
static int spot_between(plx_engine *e, double x, double y, double res)
{
    double d = 1e-4 * res, P[12], N[12], E[4], Ei[4];
    int k;
    for (k = 0; k < 4; k++) {
        P[3 * k] = x + (k == 0 ? d : k == 1 ? -d : 0.0);
        P[3 * k + 1] = y + (k == 2 ? d : k == 3 ? -d : 0.0);
        P[3 * k + 2] = 0.0;
        N[3 * k] = N[3 * k + 1] = 0.0;
        N[3 * k + 2] = 1.0;
    }
    if (plx_illuminance(e, 4, P, N, E, Ei, NULL) == PLX_E_RANGE)
        return (E[0] != E[0] && E[1] != E[1]) || (E[2] != E[2] && E[3] != E[3]);
    return 0;
}

/* Takes this pass's candidates in order, each at least `spacing` from every
 * spot taken before, and none between two footprints (spot_between). */
static void spot_take(plx_engine *e, const spot_grid *g, double spacing, long count, spot *pick, long *npick)
{
    size_t k;
    for (k = 0; k < g->n && *npick < count; k++) {
        double x, y;
        long j;
        spot_xy(g, g->heap[k].k, &x, &y);
        for (j = 0; j < *npick; j++) {
            double px, py;
            spot_xy(g, pick[j].k, &px, &py);
            if (hypot(px - x, py - y) < spacing)
                break;
        }
        if (j == *npick && !spot_between(e, x, y, g->res))
            pick[(*npick)++] = g->heap[k];
    }
}

/* The spots, as many passes as the candidates' room asks for. */
static int spot_search(plx_engine *e, spot_grid *g, int all, double spacing, long count, spot *pick,
                       long *npick)
{
    size_t first = g->cap;
    int pass, rc;
    for (pass = 1;; pass++) {
        rc = spot_pass(e, g, all, pass);
        if (rc != EXIT_OK)
            return rc;
        spot_take(e, g, spacing, count, pick, npick);
        if (*npick == count || g->offered <= g->n)
            break;
        g->after = g->heap[g->n - 1];
        g->has_after = 1;
        if (pass == 1)
            first = g->cap;
        if (!g->exhaustive && (rc = spot_all_exact(g)) != EXIT_OK) /* the next passes gather everywhere */
            return rc;
    }
    if (pass > 1 && g->mem_limited)
        fprintf(stderr, "dark-spots: %d passes over the grid: --mem leaves room for %zu of the %zu street "
                "points at a time\n", pass, g->cap, g->street);
    else if (pass > 1)
        fprintf(stderr, "dark-spots: %d passes over the grid: --spacing left too few of the %zu darkest points "
                "the first kept; the second gathered indirect light at every point after them\n", pass, first);
    return EXIT_OK;
}

static int find_spots(plx_engine *e, const char *scene, double res, long count, double spacing, int all,
                      int exhaustive, const char *out, const cli_common *c)
{
    plx_scene_info si;
    spot_grid g;
    spot *pick = NULL;
    long npick = 0, k;
    geo_out geo;
    int rc;
    plx_scene_info_get(e, &si);
    memset(&g, 0, sizeof g);
    g.x0 = si.bounds[0];
    g.y0 = si.bounds[1];
    g.res = res;
    g.no_indirect = plx_indirect_frames(e) == 0;
    g.exhaustive = exhaustive || g.no_indirect;
    twin_set_init(&g.tg, "dark-spots", scene, c, e);
    {   /* counted in doubles: no integer overflow for any finite --res */
        double wd = floor((si.bounds[2] - si.bounds[0]) / res), hd = floor((si.bounds[3] - si.bounds[1]) / res);
        if (!(wd * hd >= 1 && wd * hd <= 2e9)) {
            fprintf(stderr, "polarlux dark-spots: --res %g gives %.3g grid points (1 to 2e9)\n", res, wd * hd);
            return EXIT_USAGE;
        }
        g.w = (size_t)wd;
        g.h = (size_t)hd;
    }
    rc = spot_buffers(e, c, &g, count);
    if (rc != EXIT_OK)
        goto done;
    pick = malloc(sizeof *pick * (size_t)count);
    if (!pick) {
        fprintf(stderr, "polarlux dark-spots: out of memory\n");
        rc = EXIT_FAIL;
        goto done;
    }
    rc = spot_search(e, &g, all, spacing, count, pick, &npick);
    if (rc != EXIT_OK)
        goto done;
    if (g.street == 0)
        cli_warn("dark-spots", c, "no street point is within a lamp's reach (%s), so there are no spots; "
                 "--all takes every street point", si.lamps ? "the lamps are outside Bounds or their radius "
                 "does not reach the ground" : "the scene has no lamps");
    if (g.street > 0 && !(g.max_lux > 0) && (exhaustive || g.no_indirect))
        cli_warn("dark-spots", c, "all %zu street points are dark (0 lx): %s", g.street, cli_dark_reason(e));
    else if (g.street > 0 && !(g.max_lux > 0)) /* the direct lux's maximum; indirect light only where needed */
        cli_warn("dark-spots", c, "no direct light reaches any of the %zu street points (0 lx direct): %s",
                 g.street, cli_dark_reason(e));
    cli_light_note("dark-spots", c, e);
    if (g.gathered > 0 && !exhaustive && !g.no_indirect && !c->quiet)
        fprintf(stderr, "dark-spots: indirect light gathered %zu times for the %zu street points (not where the "
                "direct lux alone rules a point out; --exhaustive gathers at every one), on %d thread%s\n",
                g.gathered, g.street, twin_threads(&g.tg), twin_threads(&g.tg) > 1 ? "s" : "");
    if (geo_begin(&geo, e) != 0) {
        rc = EXIT_FAIL;
        goto done;
    }
    for (k = 0; k < npick; k++) {
        cJSON *props = cJSON_CreateObject();
        double x, y, sx, sy;
        spot_xy(&g, pick[k].k, &x, &y);
        sx = x;
        sy = y;
        cli_from_local(e, &sx, &sy);
        cJSON_AddNumberToObject(props, "rank", (double)k + 1);
        cJSON_AddNumberToObject(props, "lux", pick[k].lux);
        cJSON_AddNumberToObject(props, "x", sx);
        cJSON_AddNumberToObject(props, "y", sy);
        geo_add(&geo, geo_geometry("Point", geo_position(&geo, x, y, NULL)), props);
    }
    if (out) {
        if (geo_write(&geo, "dark-spots", out) != 0)
            rc = EXIT_FAIL;
        else
            fprintf(stderr, "dark-spots: %ld spots from %zu street points, darkest %.3f lx, written to %s\n",
                    npick, g.street, npick ? pick[0].lux : 0.0, out);
    } else {
        char *text = cJSON_PrintUnformatted(geo.root);
        if (text)
            puts(text);
        free(text);
    }
    geo_free(&geo);
done:
    twin_set_free(&g.tg);
    free(g.heap);
    free(pick);
    return rc;
}

static int parse_res(const char *v, void *dst)
{
    double *r = dst;
    return cli_parse_real(v, 0, CLI_MAX_COORD, r) != 0 || !(*r > 0) ? -1 : 0;
}

static int parse_spacing(const char *v, void *dst)
{
    return cli_parse_real(v, 0, CLI_MAX_COORD, dst);
}

static int parse_count(const char *v, void *dst)
{
    return cli_parse_int(v, 1, 1000000, dst);
}

int cmd_dark_spots(int argc, char **argv)
{
    cli_common c;
    const char *scene = NULL, *out = NULL;
    double res = 2.0, spacing = 10.0;
    long count = 50;
    int all = 0, exhaustive = 0, rc;
    plx_engine *e;
    const cli_opt opts[] = {
        CLI_OPT_VAL("--res", &res, parse_res, "--res '%s' is not a positive number of metres"),
        CLI_OPT_VAL("--spacing", &spacing, parse_spacing, "--spacing '%s' is not a number of metres >= 0"),
        CLI_OPT_VAL("--count", &count, parse_count, "--count '%s' is not 1..1000000"),
        CLI_OPT_FLAG("--all", &all),
        CLI_OPT_FLAG("--exhaustive", &exhaustive),
        CLI_OPT_STR("-o", &out),
        CLI_OPT_END
    };
    cli_args pa;
    memset(&c, 0, sizeof c);
    rc = cli_options_n("dark-spots", spots_help, argc, argv, opts, &c, NULL, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    scene = pa.npos ? pa.pos[0] : NULL;
    if (!scene)
        return cli_usage_error("dark-spots", "missing SCENE");
    if (!cli_out_writable("dark-spots", out)) /* before the search, not after it */
        return EXIT_FAIL;
    rc = cli_open_scene("dark-spots", scene, &c, &e);
    if (rc != EXIT_OK)
        return rc;
    rc = find_spots(e, scene, res, count, spacing, all, exhaustive, out, &c);
    plx_engine_free(e);
    return rc;
}
