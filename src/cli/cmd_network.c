/* polarlux route --network (the best-lit walking route) and polarlux
 * annotate (every street edge with its light, for routing engines). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "geo_out.h"
#include "network.h"
#include "net_scores.h"
#include "points.h"
#include "port.h"

static const char route_help[] =
    "usage: polarlux route SCENE --network STREETS --from X,Y --to X,Y [--dark-lux LX]\n"
    "                      [--dark-weight W] [--max-detour F] [--geojson OUT] [--threads N]\n"
    "                      [options]\n"
    "\n"
    "Finds the best-lit walking route and the shortest route between two points\n"
    "of a street network and prints them side by side: metres, dark metres, min\n"
    "and mean lux, min vertical (Ev) and semi-cylindrical (Esc) illuminance at\n"
    "--height facing both ways along the route, the EN 13201 P-class of E_h\n"
    "alone (class_h) and with every SPEC §6 criterion (class: mean and min E_h,\n"
    "min Ev, min Esc) and the detour the light costs.\n"
    "STREETS is GeoJSON LineStrings (e.g. OpenStreetMap highway=* ways), joined\n"
    "where they share a vertex (the exact same coordinates), in the scene's\n"
    "coordinate rules (lon/lat projected with the scene's projection, or metres\n"
    "with properties.units = \"m\"). X,Y are in the scene's coordinates (lon,lat\n"
    "for a lon/lat scene) and are snapped to the nearest point of a street.\n"
    "Each edge is scored once as 'polarlux route --path' scores a line. The\n"
    "search (Dijkstra) minimises\n"
    "    cost = length + W x dark metres\n"
    "where dark metres are the metres below --dark-lux plus the metres inside\n"
    "building footprints (passages, whose light is unknown). W = 0 gives the\n"
    "shortest route.\n"
    "STREETS may be 'polarlux annotate' output: its edges' light is then read,\n"
    "not scored again (only the ends' pieces are), when it was made on this\n"
    "scene (the same buildings, lamps and photon frames) with the same --step,\n"
    "--dark-lux and --height; otherwise the command says what differs.\n"
    "\n"
    "  --network FILE   the street network (required; '-': standard input)\n"
    "  --from X,Y       start (required)\n"
    "  --to X,Y         end (required)\n"
    "  --dark-lux LX    the dark threshold (default 1)\n"
    "  --dark-weight W  extra cost of a dark metre in metres, 0 to 1e6 (default 3)\n"
    "  --max-detour F   the best-lit route may be at most (1 + F) times as long\n"
    "                   as the shortest: W is lowered to the largest weight whose\n"
    "                   route keeps within it (halving W until a route keeps\n"
    "                   within, then bisection to a thousandth of the weight)\n"
    "  --snap M         the ends may lie at most M metres from a street (default 50)\n"
    "  --step M         sampling step in metres (default 1)\n"
    "  --height M       height of the Ev/Esc meters above the street (default 1.5)\n"
    "  --geojson OUT    write both routes as LineStrings (properties route,\n"
    "                   length_m, dark_m, min_lux, mean_lux, min_ev_lux,\n"
    "                   min_sc_lux, class, class_h, ...)\n"
    "  --threads N      threads scoring the edges on a bake with indirect light\n"
    "                   (default: the processors, at most 8, while the copies fit\n"
    "                   in half the machine's memory); each further thread loads\n"
    "                   the bake again (its own --mem block: N times the memory);\n"
    "                   the same scores for any N\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

static const char annotate_help[] =
    "usage: polarlux annotate SCENE --network STREETS -o OUT.geojson [--csv OUT.csv]\n"
    "                         [--dark-lux LX] [--dark-weight W] [--step M] [--threads N]\n"
    "                         [options]\n"
    "\n"
    "Scores every edge of a street network (as 'polarlux route --network' does)\n"
    "and writes it as a GeoJSON LineString with its light: osm_id, name, from and\n"
    "to node, length_m, scored_m, blocked_m, dark_m, dark_share, mean_lux,\n"
    "min_lux, max_lux, uniformity, the SPEC §6 minima at --height facing along\n"
    "the edge's coordinates (fw) and back (bw): min_ev_fw_lux, min_ev_bw_lux,\n"
    "min_sc_fw_lux, min_sc_bw_lux, and over both ways min_ev_lux, min_sc_lux\n"
    "(-1: no meter outside a solid), class (every SPEC §6 criterion), class_h\n"
    "(E_h alone), cost (length + W x dark metres) and factor (cost / length,\n"
    ">= 1). With --csv, one row per way id (properties osm_id, @id or id, else\n"
    "the feature's id, else #FEATURE) summed over its edges:\n"
    "osm_id,length_m,dark_m,blocked_m,dark_share,mean_lux,min_lux,class,factor,\n"
    "min_ev_lux,min_sc_lux,class_h, for routing engines that take per-way\n"
    "weights. The GeoJSON also holds below_m (dark_m less blocked_m) and, as\n"
    "its member polarlux_scores, the settings and the scene it was scored for,\n"
    "so that 'polarlux route --network OUT.geojson' reads the edges' light\n"
    "instead of scoring them again.\n"
    "\n"
    "  --network FILE   the street network (required; '-': standard input)\n"
    "  -o OUT           the annotated GeoJSON (required)\n"
    "  --csv OUT        the per-way CSV\n"
    "  --dark-lux LX, --dark-weight W, --step M, --height M   as for 'polarlux\n"
    "                   route --network'\n"
    "  --threads N      as for 'polarlux route --network'\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

typedef struct net_opts {
    const char *cmd, *scene, *network, *geojson, *out, *csv, *from_s, *to_s;
    double dark, weight, detour, snap, step, height;
    int have_detour;
    cli_common c;
} net_opts;

static int parse_number(const char *v, void *dst)
{
    double *d = dst;
    return cli_parse_double(v, d) != 0 || !(*d >= 0) || !isfinite(*d) ? -1 : 0;
}

static int parse_step(const char *v, void *dst)
{
    double *d = dst;
    return cli_parse_double(v, d) != 0 || !(*d >= 0.01) || !isfinite(*d) ? -1 : 0;
}

/* A number >= 0 into *d, then at most max: -1 (the option's own "not a
 * number" message), or -2 with too_big (its '%s': the value) printed. */
static int number_at_most(const net_opts *o, const char *v, double *d, double max, const char *too_big)
{
    if (parse_number(v, d) != 0)
        return -1;
    if (*d > max) {
        cli_usage_error(o->cmd, too_big, v);
        return -2;
    }
    return 0;
}

/* dst: the net_opts. */
static int parse_height(const char *v, void *dst)
{
    net_opts *o = dst;
    return number_at_most(o, v, &o->height, 1000, "--height '%s' is not a number of metres from 0 to 1000");
}

/* Far larger weights only overflow the route's costs to infinity, which
 * the search would take for unconnected ends. dst: the net_opts. */
static int parse_weight(const char *v, void *dst)
{
    net_opts *o = dst;
    return number_at_most(o, v, &o->weight, 1e6,
                          "--dark-weight '%s' is more than 1000000 (a dark metre's cost in lit metres)");
}

/* Parses the options shared by route --network and annotate; -1 for --help
 * (printed), else an exit code. */
static int parse(net_opts *o, int argc, char **argv, const char *help)
{
    int rc;
    const cli_opt opts[] = {
        CLI_OPT_STR("--network", &o->network),
        CLI_OPT_STR("--from", &o->from_s),
        CLI_OPT_STR("--to", &o->to_s),
        CLI_OPT_STR("--geojson", &o->geojson),
        CLI_OPT_STR("-o", &o->out),
        CLI_OPT_STR("--csv", &o->csv),
        CLI_OPT_VAL("--dark-lux", &o->dark, parse_number, "--dark-lux '%s' is not a number >= 0"),
        CLI_OPT_VAL("--dark-weight", o, parse_weight, "--dark-weight '%s' is not a number >= 0"),
        CLI_OPT_VAL("--snap", &o->snap, parse_number, "--snap '%s' is not a number >= 0"),
        { "--max-detour", NULL, &o->detour, parse_number, "--max-detour '%s' is not a number >= 0", 0, NULL,
          &o->have_detour, NULL },
        CLI_OPT_VAL("--step", &o->step, parse_step, "--step '%s' is not a number >= 0.01"),
        CLI_OPT_VAL("--height", o, parse_height, "--height '%s' is not a number >= 0"),
        CLI_OPT_END
    };
    cli_args pa;
    o->dark = 1.0;
    o->weight = 3.0;
    o->snap = 50.0;
    o->step = 1.0;
    o->height = 1.5;
    rc = cli_options_n(o->cmd, help, argc, argv, opts, &o->c, NULL, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc;
    o->scene = pa.npos ? pa.pos[0] : NULL;
    if (!o->scene)
        return cli_usage_error(o->cmd, "missing SCENE");
    if (!o->network)
        return cli_usage_error(o->cmd, "missing --network STREETS");
    return EXIT_OK;
}

/* "X,Y" in the scene's coordinates to local metres. */
static int parse_point(plx_engine *e, const char *s, double *x, double *y)
{
    char extra;
    if (sscanf(s, "%lf,%lf%c", x, y, &extra) != 2 || !isfinite(*x) || !isfinite(*y))
        return -1;
    return cli_to_local(e, x, y);
}

/* Loads the network and scores its edges (all: every edge; else none yet,
 * for net_score_route); prints the error and returns an exit code on
 * failure. */
static int load_network(const net_opts *o, plx_engine *e, network *net, int all, int *read_scores)
{
    route_set rs;
    char err[512];
    plx_status st;
    plx_engine *failed;
    twin_set tg;
    cJSON *doc = NULL;
    int usage;
    *read_scores = 0;
    if (route_read_doc(o->network, e, &rs, all ? NULL : &doc, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux %s: %s\n", o->cmd, err);
        return EXIT_FAIL;
    }
    if (rs.note[0])
        cli_warn(o->cmd, &o->c, "%s: %s", o->network, rs.note);
    if (net_build(net, &rs, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux %s: %s: %s\n", o->cmd, o->network, err);
        cJSON_Delete(doc);
        return EXIT_FAIL;
    }
    if (!all) { /* route: annotate's scores when the file holds them, else none yet (net_score_route) */
        net_set_scoring(net, o->step, o->dark, o->height);
        *read_scores = net_scores_read(net, doc, e, &usage, err, sizeof err);
        cJSON_Delete(doc);
        if (*read_scores < 0) {
            fprintf(stderr, "polarlux %s: %s: annotate's scores: %s\n", o->cmd, o->network, err);
            net_free(net);
            return usage ? EXIT_USAGE : EXIT_FAIL;
        }
        *read_scores = *read_scores == 0;
        return EXIT_OK;
    }
    twin_set_init(&tg, o->cmd, o->scene, &o->c, e);
    st = net_score(net, e, &tg, o->step, o->dark, o->height, 1, &failed);
    if (twin_threads(&tg) > 1 && !o->c.quiet)
        fprintf(stderr, "polarlux %s: note: the %u edges scored on %d threads, each with its own copy of the bake\n",
                o->cmd, net->nedges, twin_threads(&tg));
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: %s: scoring the edges: %s\n", o->cmd, o->network, plx_last_error(failed));
        twin_set_free(&tg);
        net_free(net);
        return cli_exit_code(st);
    }
    twin_set_free(&tg);
    return EXIT_OK;
}

static double route_mean(const net_route *r)
{
    return r->scored > 0 ? r->integral / r->scored : 0.0;
}

/* A SPEC §6 minimum for output: -1 when there was no meter (NaN). */
static void print_route(const char *name, const net_route *r, double shortest)
{
    char cls[4], clh[4];
    net_class_text(r->p_class, cls);
    net_class_text(r->p_class_h, clh);
    printf("%-9s %9.1f %9.1f %9.3f %9.3f %9.3f %9.3f  %-7s %-5s %+7.1f%%\n", name, r->length, r->dark + r->blocked,
           r->min, route_mean(r), net_or_none(r->min_ev), net_or_none(r->min_esc), clh, cls,
           shortest > 0 ? 100.0 * (r->length / shortest - 1.0) : 0.0);
}

static cJSON *route_props(const char *name, const net_route *r, double shortest, double weight)
{
    cJSON *p = cJSON_CreateObject();
    char cls[4];
    net_class_text(r->p_class, cls);
    cJSON_AddStringToObject(p, "route", name);
    cJSON_AddNumberToObject(p, "length_m", r->length);
    cJSON_AddNumberToObject(p, "dark_m", r->dark + r->blocked);
    cJSON_AddNumberToObject(p, "min_lux", r->min);
    cJSON_AddNumberToObject(p, "mean_lux", route_mean(r));
    cJSON_AddNumberToObject(p, "min_ev_lux", net_or_none(r->min_ev));
    cJSON_AddNumberToObject(p, "min_sc_lux", net_or_none(r->min_esc));
    cJSON_AddStringToObject(p, "class", cls);
    net_class_text(r->p_class_h, cls);
    cJSON_AddStringToObject(p, "class_h", cls);
    cJSON_AddNumberToObject(p, "blocked_m", r->blocked);
    cJSON_AddNumberToObject(p, "detour_pct", shortest > 0 ? 100.0 * (r->length / shortest - 1.0) : 0.0);
    cJSON_AddNumberToObject(p, "dark_weight", weight);
    cJSON_AddNumberToObject(p, "cost", r->cost);
    return p;
}

static int write_routes(const net_opts *o, plx_engine *e, const net_route *best, const net_route *shortest,
                        double weight)
{
    geo_out g;
    const net_route *r[2] = { best, shortest };
    static const char *const names[2] = { "best-lit", "shortest" };
    int k, rc = EXIT_OK;
    if (geo_begin(&g, e) != 0)
        return EXIT_FAIL;
    for (k = 0; k < 2; k++) {
        cJSON *coords = cJSON_CreateArray();
        uint32_t i;
        for (i = 0; i < r[k]->n; i++)
            cJSON_AddItemToArray(coords, geo_position(&g, r[k]->xy[2 * i], r[k]->xy[2 * i + 1], NULL));
        geo_add(&g, geo_geometry("LineString", coords),
                route_props(names[k], r[k], shortest->length, k == 0 ? weight : 0.0));
    }
    if (geo_write(&g, o->cmd, o->geojson) != 0)
        rc = EXIT_FAIL;
    geo_free(&g);
    return rc;
}

/* The best-lit route within --max-detour (net_route_capped), in place of
 * the route at W in *best. */
static int cap_detour(network *net, plx_engine *e, const net_snap *a, const net_snap *b, const net_opts *o,
                      const net_route *shortest, net_route *best, double *weight, char *err, size_t errlen)
{
    net_route capped;
    if (net_route_capped(net, e, a, b, o->weight, (1.0 + o->detour) * shortest->length, shortest, &capped, weight,
                         err, errlen) != 0)
        return -1;
    net_route_free(best);
    *best = capped;
    return 0;
}

static int snap_end(const net_opts *o, plx_engine *e, const network *net, const char *opt, const char *val,
                    net_snap *s)
{
    double x, y;
    if (parse_point(e, val, &x, &y) != 0) {
        cli_usage_error(o->cmd, "%s '%s' is not X,Y in the scene's coordinates (lon,lat for a lon/lat scene)",
                        opt, val);
        return EXIT_USAGE;
    }
    net_snap_point(net, x, y, s);
    if (s->dist > o->snap) {
        double a, b;
        net_snap sw;
        char swapped[64];
        /* the two numbers the other way round near a street: likely lat,lon given for lon,lat */
        int hint = sscanf(val, "%lf,%lf", &a, &b) == 2 && (snprintf(swapped, sizeof swapped, "%.10g,%.10g", b, a),
                                                            parse_point(e, swapped, &x, &y) == 0) &&
                   net_snap_point(net, x, y, &sw) == 0 && sw.dist <= o->snap;
        fprintf(stderr, "polarlux %s: %s %s is %.1f m from the nearest street of %s (more than --snap %g m)%s%s%s\n",
                o->cmd, opt, val, s->dist, o->network, o->snap, hint ? "; " : "", hint ? swapped : "",
                hint ? " is on a street: lon and lat swapped?" : "");
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

/* The edges the routes from a to b can take scored (net_score_route), on
 * twins of a bake as annotate's; an exit code. */
static int score_route_edges(const net_opts *o, plx_engine *e, network *net, const net_snap *a, const net_snap *b)
{
    twin_set tg;
    plx_engine *failed;
    size_t n;
    plx_status st;
    twin_set_init(&tg, o->cmd, o->scene, &o->c, e);
    st = net_score_route(net, e, &tg, a, b, o->weight, 1, &n, &failed);
    if (st == PLX_OK && !o->c.quiet && n > 0) {
        fprintf(stderr, "polarlux %s: note: %zu of the %u edges scored (those a walk from --from to --to no longer "
                        "than the shortest route's cost can take)", o->cmd, n, net->nedges);
        if (twin_threads(&tg) > 1)
            fprintf(stderr, ", on %d threads, each with its own copy of the bake", twin_threads(&tg));
        fputc('\n', stderr);
    }
    if (st != PLX_OK)
        fprintf(stderr, "polarlux %s: %s: scoring the edges: %s\n", o->cmd, o->network,
                failed ? plx_last_error(failed) : "out of memory");
    twin_set_free(&tg);
    return st == PLX_OK ? EXIT_OK : cli_exit_code(st);
}

/* The routes; the edges scored first unless read from annotate's scores
 * (read_scores). */
static int find_routes(const net_opts *o, plx_engine *e, network *net, int read_scores)
{
    net_snap a, b;
    net_route shortest, best;
    double weight = o->weight;
    char err[256];
    int rc = snap_end(o, e, net, "--from", o->from_s, &a), r1, r2;
    if (rc == EXIT_OK)
        rc = snap_end(o, e, net, "--to", o->to_s, &b);
    if (rc == EXIT_OK && !read_scores)
        rc = score_route_edges(o, e, net, &a, &b);
    if (rc != EXIT_OK)
        return rc;
    if (read_scores && !o->c.quiet)
        fprintf(stderr, "polarlux %s: note: the %u edges' light read from annotate's scores in %s (the ends' "
                        "pieces scored here)\n", o->cmd, net->nedges, cli_input_name(o->network));
    r1 = net_route_find(net, e, &a, &b, 0.0, &shortest, err, sizeof err);
    r2 = r1 == 0 ? net_route_find(net, e, &a, &b, o->weight, &best, err, sizeof err) : r1;
    if (r1 == 1 || r2 == 1) {
        double la = net_part_length(net, net->edges[a.edge].a), lb = net_part_length(net, net->edges[b.edge].a);
        fprintf(stderr, "polarlux %s: %s: no path from --from %s to --to %s: they lie on unconnected parts of the "
                        "network (it has %u parts): --from snapped %.1f m to a part of %.0f m of streets, --to "
                        "%.1f m to one of %.0f m%s\n", o->cmd, o->network, o->from_s, o->to_s, net_components(net),
                a.dist, la, b.dist, lb, fmin(la, lb) < 0.1 * fmax(la, lb) ? " (the smaller is likely an isolated "
                "piece of the street data: move that end nearer a street of the larger)" : "");
        rc = EXIT_FAIL;
    } else if (r1 < 0 || r2 < 0) {
        fprintf(stderr, "polarlux %s: %s\n", o->cmd, err);
        rc = EXIT_FAIL;
    }
    if (rc == EXIT_OK && !(shortest.length > 0.0)) {
        fprintf(stderr, "polarlux %s: --from %s and --to %s meet the streets of %s at the same point: the route has "
                        "no length, so there is nothing to score\n", o->cmd, o->from_s, o->to_s, o->network);
        rc = EXIT_FAIL;
    }
    if (rc == EXIT_OK && o->have_detour && best.length > (1.0 + o->detour) * shortest.length &&
        cap_detour(net, e, &a, &b, o, &shortest, &best, &weight, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux %s: %s\n", o->cmd, err);
        rc = EXIT_FAIL;
    }
    if (rc == EXIT_OK) {
        printf("%-9s %9s %9s %9s %9s %9s %9s  %-7s %-5s %8s\n", "route", "length_m", "dark_m", "min_lx", "mean_lx",
               "min_Ev", "min_Esc", "class_h", "class", "detour");
        print_route("best-lit", &best, shortest.length);
        print_route("shortest", &shortest, shortest.length);
        cli_light_note(o->cmd, &o->c, e);
        printf("cost = length + %g x dark metres (below %g lx or inside footprints)", weight, o->dark);
        if (weight != o->weight)
            printf("; weight lowered from %g by --max-detour %g", o->weight, o->detour);
        printf("; Ev, Esc at %g m facing both ways; network %u node%s, %u edge%s; ends %.1f m and %.1f m from the "
               "streets\n", o->height, net->nnodes, net->nnodes == 1 ? "" : "s", net->nedges,
               net->nedges == 1 ? "" : "s", a.dist, b.dist);
        if (best.dark + best.blocked > 0 && !o->c.quiet)
            fprintf(stderr, "polarlux %s: note: the best-lit route still has %.1f dark metres\n", o->cmd,
                    best.dark + best.blocked);
        if (o->geojson)
            rc = write_routes(o, e, &best, &shortest, weight);
    }
    if (r1 == 0)
        net_route_free(&shortest);
    if (r2 == 0)
        net_route_free(&best);
    return rc;
}

int cmd_route_network(int argc, char **argv)
{
    net_opts o;
    plx_engine *e;
    network net;
    int rc, read_scores;
    int i;
    memset(&o, 0, sizeof o);
    o.cmd = "route";
    for (i = 1; i < argc; i++) /* route's other way: said as such, not as an unknown option */
        if (strcmp(argv[i], "--path") == 0)
            return cli_usage_error("route", "--path and --network do not combine: --path scores a given line; "
                                   "--network finds the best-lit route from --from to --to");
    rc = parse(&o, argc, argv, route_help);
    read_scores = 0;
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (!o.from_s || !o.to_s)
        return cli_usage_error("route", "--network needs --from X,Y and --to X,Y");
    if (o.out || o.csv)
        return cli_usage_error("route", "-o and --csv belong to 'polarlux annotate'");
    if (!cli_out_writable("route", o.geojson))
        return EXIT_FAIL;
    rc = cli_open_scene("route", o.scene, &o.c, &e);
    if (rc != EXIT_OK)
        return rc;
    rc = load_network(&o, e, &net, 0, &read_scores);
    if (rc == EXIT_OK) {
        rc = find_routes(&o, e, &net, read_scores);
        net_free(&net);
    }
    plx_engine_free(e);
    return rc;
}

/* ---- annotate ------------------------------------------------------------- */

/* The SPEC §6 class of mean and min E_h and min E_v, E_sc over both ways
 * (0 with no E_h sample or no meter). */
static const char *edge_id(const network *net, const net_edge *ed, char buf[48])
{
    const route_line *l = &net->lines.lines[ed->line];
    if (l->id[0])
        return l->id;
    snprintf(buf, 48, "#%u", l->feature);
    return buf;
}

static int write_edges(const net_opts *o, plx_engine *e, const network *net)
{
    geo_out g;
    uint32_t i, k;
    int rc = EXIT_OK;
    cJSON *h;
    if (geo_begin(&g, e) != 0)
        return EXIT_FAIL;
    h = net_scores_header(net, e);
    if (!h || !cJSON_AddItemToObject(g.root, NET_SCORES_MEMBER, h)) {
        cJSON_Delete(h);
        geo_free(&g);
        fprintf(stderr, "polarlux annotate: out of memory\n");
        return EXIT_FAIL;
    }
    for (i = 0; i < net->nedges; i++) {
        const net_edge *ed = &net->edges[i];
        const route_line *l = &net->lines.lines[ed->line];
        char buf[48];
        cJSON *p = net_scores_edge_props(net, i, edge_id(net, ed, buf), l->name, o->weight);
        cJSON *coords = cJSON_CreateArray();
        for (k = ed->v0; k <= ed->v1; k++)
            cJSON_AddItemToArray(coords, geo_position_exact(&g, l->xy[2 * k], l->xy[2 * k + 1]));
        geo_add(&g, geo_geometry("LineString", coords), p);
    }
    if (geo_write(&g, "annotate", o->out) != 0)
        rc = EXIT_FAIL;
    geo_free(&g);
    return rc;
}

/* Sums of the edges of one way id. */
typedef struct way_sum {
    char id[48];
    uint32_t first;
    double length, dark, blocked, scored, integral, min, min_ev, min_esc; /* min_ev, min_esc NaN: none */
} way_sum;

static int cmp_id(const void *pa, const void *pb)
{
    const way_sum *a = pa, *b = pb;
    int c = strcmp(a->id, b->id);
    return c ? c : (a->first > b->first) - (a->first < b->first);
}

static int cmp_first(const void *pa, const void *pb)
{
    const way_sum *a = pa, *b = pb;
    return (a->first > b->first) - (a->first < b->first);
}

static void csv_row(FILE *f, const way_sum *w, double weight)
{
    double mean = w->scored > 0 ? w->integral / w->scored : 0.0, min = w->scored > 0 ? w->min : 0.0;
    double dark = w->dark + w->blocked;
    char cls[4], clh[4];
    const char *c;
    net_class_text(net_full_class(w->scored, mean, min, w->min_ev, w->min_esc), cls);
    net_class_text(w->scored > 0 ? plx_p_class(mean, min) : 0, clh);
    if (strpbrk(w->id, ",\"\n")) {
        fputc('"', f);
        for (c = w->id; *c; c++) {
            if (*c == '"')
                fputc('"', f);
            fputc(*c, f);
        }
        fputc('"', f);
    } else {
        fputs(w->id, f);
    }
    fprintf(f, ",%.3f,%.3f,%.3f,%.4f,%.4f,%.4f,%s,%.4f,%.4f,%.4f,%s\n", w->length, dark, w->blocked,
            w->length > 0 ? dark / w->length : 0.0, mean, min, cls,
            w->length > 0 ? (w->length + weight * dark) / w->length : 1.0, net_or_none(w->min_ev), net_or_none(w->min_esc),
            clh);
}

/* One row per way id, in the order the ways first appear. */
static int write_csv(const net_opts *o, const network *net)
{
    way_sum *w = calloc((size_t)net->nedges + 1, sizeof *w);
    uint32_t i, n = 0;
    FILE *f;
    if (!w)
        return EXIT_FAIL;
    for (i = 0; i < net->nedges; i++) {
        const net_edge *ed = &net->edges[i];
        char buf[48];
        snprintf(w[i].id, sizeof w[i].id, "%s", edge_id(net, ed, buf));
        w[i].first = i;
        w[i].length = ed->length;
        w[i].dark = ed->dark;
        w[i].blocked = ed->s.blocked_length;
        w[i].scored = ed->s.length;
        w[i].integral = ed->s.mean * ed->s.length;
        w[i].min = ed->s.length > 0 ? ed->s.min : INFINITY;
        w[i].min_ev = fmin(ed->fac[0], ed->fac[1]);
        w[i].min_esc = fmin(ed->fac[2], ed->fac[3]);
    }
    qsort(w, net->nedges, sizeof *w, cmp_id);
    for (i = 0; i < net->nedges; i++) {
        if (n > 0 && strcmp(w[n - 1].id, w[i].id) == 0) {
            way_sum *t = &w[n - 1];
            t->length += w[i].length;
            t->dark += w[i].dark;
            t->blocked += w[i].blocked;
            t->scored += w[i].scored;
            t->integral += w[i].integral;
            t->min = fmin(t->min, w[i].min);
            t->min_ev = fmin(t->min_ev, w[i].min_ev); /* fmin skips a NaN */
            t->min_esc = fmin(t->min_esc, w[i].min_esc);
        } else {
            w[n++] = w[i];
        }
    }
    qsort(w, n, sizeof *w, cmp_first);
    f = fopen(o->csv, "w");
    if (!f) {
        fprintf(stderr, "polarlux annotate: %s: cannot write\n", o->csv);
        free(w);
        return EXIT_FAIL;
    }
    fprintf(f, "osm_id,length_m,dark_m,blocked_m,dark_share,mean_lux,min_lux,class,factor,min_ev_lux,min_sc_lux,"
               "class_h\n");
    for (i = 0; i < n; i++)
        csv_row(f, &w[i], o->weight);
    free(w);
    if (fclose(f) != 0) {
        fprintf(stderr, "polarlux annotate: %s: write failed\n", o->csv);
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

int cmd_annotate(int argc, char **argv)
{
    net_opts o;
    plx_engine *e;
    network net;
    int rc, read_scores;
    memset(&o, 0, sizeof o);
    o.cmd = "annotate";
    rc = parse(&o, argc, argv, annotate_help);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (!o.out)
        return cli_usage_error("annotate", "missing -o OUT.geojson");
    if (o.from_s || o.to_s || o.geojson || o.have_detour)
        return cli_usage_error("annotate", "--from, --to, --geojson and --max-detour belong to 'polarlux route'");
    if (!cli_out_writable("annotate", o.out) || !cli_out_writable("annotate", o.csv))
        return EXIT_FAIL;
    rc = cli_open_scene("annotate", o.scene, &o.c, &e);
    if (rc != EXIT_OK)
        return rc;
    rc = load_network(&o, e, &net, 1, &read_scores);
    if (rc == EXIT_OK) {
        double dark = 0, len = 0;
        uint32_t i;
        rc = write_edges(&o, e, &net);
        if (rc == EXIT_OK && o.csv)
            rc = write_csv(&o, &net);
        for (i = 0; i < net.nedges; i++) {
            dark += net.edges[i].dark + net.edges[i].s.blocked_length;
            len += net.edges[i].length;
        }
        if (rc == EXIT_OK) {
            printf("annotate: %u edge%s, %u node%s, %.0f m of street, %.0f m dark (below %g lx), written to "
                   "%s%s%s\n", net.nedges, net.nedges == 1 ? "" : "s", net.nnodes, net.nnodes == 1 ? "" : "s", len, dark, o.dark, o.out, o.csv ? " and " : "", o.csv ? o.csv : "");
            cli_light_note("annotate", &o.c, e);
        }
        net_free(&net);
    }
    plx_engine_free(e);
    return rc;
}
