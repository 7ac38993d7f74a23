/* polarlux route / dark-spots: how well lit are streets and routes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "geo_out.h"
#include "port.h"
#include "route_io.h"

static const char route_help[] =
    "usage: polarlux route SCENE --path FILE [--step M] [--dark-lux LX] [--geojson OUT] [options]\n"
    "\n"
    "Scores routes by their horizontal ground illuminance (direct + indirect when\n"
    "available). FILE is GeoJSON with LineString or MultiLineString features, in\n"
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
    "  --path FILE      the routes (required)\n"
    "  --step M         sampling step in metres (default 1)\n"
    "  --dark-lux LX    the dark threshold (default 1)\n"
    "  --height M       height of the Ev/Esc meters above the path (default 1.5)\n"
    "  --geojson OUT    also write the lines with these numbers as properties\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n"
    "\n"
    "With --network STREETS --from X,Y --to X,Y: the best-lit route over a street\n"
    "network ('polarlux route --network x --help').\n";

static const char spots_help[] =
    "usage: polarlux dark-spots SCENE [--res M] [--count N] [--spacing M] [--all] [-o OUT] [options]\n"
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
    "  -o OUT        write the GeoJSON to OUT instead of standard output\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

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

static void print_row(const char *line, const char *seg, const plx_route_stats *s, const double fac[4])
{
    char cls[4], fr[4];
    class_text(s->p_class, cls);
    class_text(facial_class(s, fac), fr);
    printf("%-8s %-5s %9.1f %9.3f %9.3f %9.3f %6.3f %6.3f %-5s %8.3f %8.3f %8.3f %8.3f %-3s", line, seg,
           s->length, s->mean, s->min, s->max, s->uniformity, s->dark_share, cls, fac[0], fac[1], fac[2], fac[3],
           fr);
    if (s->blocked_length > 0)
        printf("  (%.1f m inside buildings)", s->blocked_length);
    printf("\n");
}

static cJSON *stats_json(const plx_route_stats *s, const double fac[4])
{
    cJSON *o = cJSON_CreateObject();
    char cls[4], fr[4];
    class_text(s->p_class, cls);
    class_text(facial_class(s, fac), fr);
    cJSON_AddNumberToObject(o, "min_ev_fw_lx", fac[0] == fac[0] ? fac[0] : -1);
    cJSON_AddNumberToObject(o, "min_ev_bw_lx", fac[1] == fac[1] ? fac[1] : -1);
    cJSON_AddNumberToObject(o, "min_esc_fw_lx", fac[2] == fac[2] ? fac[2] : -1);
    cJSON_AddNumberToObject(o, "min_esc_bw_lx", fac[3] == fac[3] ? fac[3] : -1);
    cJSON_AddStringToObject(o, "p_class_facial", fr);
    cJSON_AddNumberToObject(o, "length_m", s->length);
    cJSON_AddNumberToObject(o, "mean_lx", s->mean);
    cJSON_AddNumberToObject(o, "min_lx", s->min);
    cJSON_AddNumberToObject(o, "max_lx", s->max);
    cJSON_AddNumberToObject(o, "uniformity", s->uniformity);
    cJSON_AddNumberToObject(o, "dark_share", s->dark_share);
    cJSON_AddStringToObject(o, "p_class", cls);
    cJSON_AddNumberToObject(o, "blocked_m", s->blocked_length);
    return o;
}

typedef struct route_opts {
    const char *scene, *path, *geojson;
    double step, dark, height;
    cli_common c;
} route_opts;

static int score_all(plx_engine *e, const route_opts *o, route_set *rs)
{
    geo_out g;
    size_t i;
    int rc = EXIT_OK;
    memset(&g, 0, sizeof g);
    if (o->geojson && geo_begin(&g, e) != 0)
        return EXIT_FAIL;
    printf("%-8s %-5s %9s %9s %9s %9s %6s %6s %-5s %8s %8s %8s %8s %s\n", "line", "seg", "length_m", "mean_lx",
           "min_lx", "max_lx", "U0", "dark", "class", "Ev_fw", "Ev_bw", "Esc_fw", "Esc_bw", "class_fr");
    for (i = 0; i < rs->n; i++) {
        const route_line *l = &rs->lines[i];
        plx_route_stats tot, *seg = malloc(sizeof *seg * l->n);
        double *fac = malloc(sizeof(double) * 4 * l->n), ftot[4];
        char name[32], sname[16];
        uint32_t k;
        plx_status st;
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
        if (tot.samples > 0 && !(tot.max > 0))
            cli_warn("route", &o->c, "%s: line %s is entirely dark (0 lx): %s", o->path, l->name,
                     cli_dark_reason(e));
        print_row(name, "all", &tot, ftot);
        for (k = 0; k + 1 < l->n; k++) {
            snprintf(sname, sizeof sname, "%u", k);
            print_row("", sname, &seg[k], fac + 4 * k);
        }
        if (g.root) {
            cJSON *props = stats_json(&tot, ftot), *segs = cJSON_AddArrayToObject(props, "segments"), *coords;
            cJSON_AddStringToObject(props, "name", l->name);
            for (k = 0; k + 1 < l->n; k++)
                cJSON_AddItemToArray(segs, stats_json(&seg[k], fac + 4 * k));
            coords = cJSON_CreateArray();
            for (k = 0; k < l->n; k++)
                cJSON_AddItemToArray(coords, geo_position(&g, l->xy[2 * k], l->xy[2 * k + 1], NULL));
            geo_add(&g, geo_geometry("LineString", coords), props);
        }
        free(seg);
        free(fac);
    }
    if (g.root && rc == EXIT_OK && geo_write(&g, "route", o->geojson) != 0)
        rc = EXIT_FAIL;
    geo_free(&g);
    return rc;
}

int cmd_route(int argc, char **argv)
{
    route_opts o;
    plx_engine *e;
    route_set rs;
    char err[512];
    int i, rc;
    for (i = 1; i < argc; i++) /* the best-lit route over a street network: cmd_network.c */
        if (strcmp(argv[i], "--network") == 0)
            return cmd_route_network(argc, argv);
    memset(&o, 0, sizeof o);
    o.step = 1.0;
    o.dark = 1.0;
    o.height = 1.5;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        int r = cli_common_option("route", argc, argv, &i, &o.c);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(route_help, stdout);
            return EXIT_OK;
        }
        if ((strcmp(a, "--path") == 0 || strcmp(a, "--step") == 0 || strcmp(a, "--dark-lux") == 0 ||
             strcmp(a, "--geojson") == 0 || strcmp(a, "--height") == 0) && i + 1 >= argc)
            return cli_usage_error("route", "%s needs a value", a);
        if (strcmp(a, "--path") == 0) {
            o.path = argv[++i];
        } else if (strcmp(a, "--geojson") == 0) {
            o.geojson = argv[++i];
        } else if (strcmp(a, "--step") == 0) {
            if (cli_parse_double(argv[++i], &o.step) != 0 || !(o.step >= 0.01))
                return cli_usage_error("route", "--step '%s' is not a number of metres >= 0.01", argv[i]);
        } else if (strcmp(a, "--height") == 0) {
            if (cli_parse_double(argv[++i], &o.height) != 0 || !(o.height >= 0) || !(o.height <= 1000))
                return cli_usage_error("route", "--height '%s' is not a number of metres from 0 to 1000", argv[i]);
        } else if (strcmp(a, "--dark-lux") == 0) {
            if (cli_parse_double(argv[++i], &o.dark) != 0 || !(o.dark >= 0))
                return cli_usage_error("route", "--dark-lux '%s' is not a number of lux >= 0", argv[i]);
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error("route", "unknown option '%s'", a);
        } else if (!o.scene) {
            o.scene = a;
        } else {
            return cli_usage_error("route", "unexpected argument '%s'", a);
        }
    }
    if (!o.scene)
        return cli_usage_error("route", "missing SCENE");
    if (!o.path)
        return cli_usage_error("route", "missing --path FILE");
    rc = cli_open_scene("route", o.scene, &o.c, &e);
    if (rc != EXIT_OK)
        return rc;
    if (route_read(o.path, e, &rs, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux route: %s\n", err);
        plx_engine_free(e);
        return EXIT_FAIL;
    }
    rc = score_all(e, &o, &rs);
    route_free(&rs);
    plx_engine_free(e);
    return rc;
}

/* ---- dark spots ------------------------------------------------------------ */

typedef struct spot {
    double x, y, lux;
} spot;

static int cmp_spot(const void *a, const void *b)
{
    const spot *p = a, *q = b;
    if (p->lux != q->lux)
        return p->lux < q->lux ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return (p->x > q->x) - (p->x < q->x);
}

static int in_reach(plx_engine *e, uint32_t nlamps, double x, double y)
{
    uint32_t k;
    for (k = 0; k < nlamps; k++) {
        plx_lamp l;
        plx_lamp_get(e, k, &l);
        if ((l.x - x) * (l.x - x) + (l.y - y) * (l.y - y) + l.z * l.z < l.radius * l.radius)
            return 1;
    }
    return 0;
}

static int find_spots(plx_engine *e, double res, long count, double spacing, int all, const char *out,
                      const cli_common *c)
{
    plx_scene_info si;
    size_t w, h, n = 0, k, cap;
    double *P, *N, *E;
    spot *s, *pick;
    long npick = 0;
    geo_out g;
    int rc = EXIT_OK;
    plx_scene_info_get(e, &si);
    w = (size_t)floor((si.bounds[2] - si.bounds[0]) / res);
    h = (size_t)floor((si.bounds[3] - si.bounds[1]) / res);
    cap = w * h;
    if (cap == 0 || cap > 20000000u) {
        fprintf(stderr, "polarlux dark-spots: --res %g gives %zu grid points (1 to 2e7)\n", res, cap);
        return EXIT_USAGE;
    }
    P = malloc(sizeof *P * 3 * cap);
    N = malloc(sizeof *N * 3 * cap);
    E = malloc(sizeof *E * cap);
    s = malloc(sizeof *s * cap);
    pick = malloc(sizeof *pick * (size_t)count);
    if (!P || !N || !E || !s || !pick) {
        fprintf(stderr, "polarlux dark-spots: out of memory\n");
        rc = EXIT_FAIL;
        goto done;
    }
    for (k = 0; k < cap; k++) {
        double x = si.bounds[0] + (k % w + 0.5) * res, y = si.bounds[1] + (k / w + 0.5) * res;
        if (!all && !in_reach(e, si.lamps, x, y))
            continue;
        P[3 * n] = x;
        P[3 * n + 1] = y;
        P[3 * n + 2] = 0;
        N[3 * n] = N[3 * n + 1] = 0;
        N[3 * n + 2] = 1;
        n++;
    }
    {
        double *Ei = malloc(sizeof *Ei * (n + 1));
        plx_status st = Ei ? plx_illuminance(e, n, P, N, E, Ei, NULL) : PLX_E_NOMEM;
        if (st != PLX_OK && st != PLX_E_RANGE) {
            fprintf(stderr, "polarlux dark-spots: %s\n", plx_last_error(e));
            free(Ei);
            rc = cli_exit_code(st);
            goto done;
        }
        for (k = 0; k < n; k++)
            E[k] += Ei[k];
        free(Ei);
    }
    if (n == 0)
        cli_warn("dark-spots", c, "no street point is within a lamp's reach (%s), so there are no spots; "
                 "--all takes every street point", si.lamps ? "the lamps are outside Bounds or their radius "
                 "does not reach the ground" : "the scene has no lamps");
    for (k = 0, cap = 0; k < n; k++)
        if (E[k] == E[k]) {
            s[cap].x = P[3 * k];
            s[cap].y = P[3 * k + 1];
            s[cap++].lux = E[k];
        }
    qsort(s, cap, sizeof *s, cmp_spot);
    if (cap > 0 && !(s[cap - 1].lux > 0))
        cli_warn("dark-spots", c, "all %zu street points are dark (0 lx): %s", cap, cli_dark_reason(e));
    for (k = 0; k < cap && npick < count; k++) {
        long j;
        for (j = 0; j < npick; j++)
            if (hypot(pick[j].x - s[k].x, pick[j].y - s[k].y) < spacing)
                break;
        if (j == npick)
            pick[npick++] = s[k];
    }
    if (geo_begin(&g, e) != 0) {
        rc = EXIT_FAIL;
        goto done;
    }
    for (k = 0; k < (size_t)npick; k++) {
        cJSON *props = cJSON_CreateObject();
        cJSON_AddNumberToObject(props, "rank", (double)k + 1);
        cJSON_AddNumberToObject(props, "lux", pick[k].lux);
        cJSON_AddNumberToObject(props, "x", pick[k].x);
        cJSON_AddNumberToObject(props, "y", pick[k].y);
        geo_add(&g, geo_geometry("Point", geo_position(&g, pick[k].x, pick[k].y, NULL)), props);
    }
    if (out) {
        if (geo_write(&g, "dark-spots", out) != 0)
            rc = EXIT_FAIL;
        else
            fprintf(stderr, "dark-spots: %ld spots from %zu street points, darkest %.3f lx, written to %s\n",
                    npick, cap, npick ? pick[0].lux : 0.0, out);
    } else {
        char *text = cJSON_PrintUnformatted(g.root);
        if (text)
            puts(text);
        free(text);
    }
    geo_free(&g);
done:
    free(P), free(N), free(E), free(s), free(pick);
    return rc;
}

int cmd_dark_spots(int argc, char **argv)
{
    cli_common c;
    const char *scene = NULL, *out = NULL;
    double res = 2.0, spacing = 10.0;
    long count = 50;
    int all = 0, i, rc;
    plx_engine *e;
    memset(&c, 0, sizeof c);
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        int r = cli_common_option("dark-spots", argc, argv, &i, &c);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(spots_help, stdout);
            return EXIT_OK;
        }
        if ((strcmp(a, "--res") == 0 || strcmp(a, "--count") == 0 || strcmp(a, "--spacing") == 0 ||
             strcmp(a, "-o") == 0) && i + 1 >= argc)
            return cli_usage_error("dark-spots", "%s needs a value", a);
        if (strcmp(a, "--res") == 0) {
            if (cli_parse_double(argv[++i], &res) != 0 || !(res > 0))
                return cli_usage_error("dark-spots", "--res '%s' is not a positive number of metres", argv[i]);
        } else if (strcmp(a, "--spacing") == 0) {
            if (cli_parse_double(argv[++i], &spacing) != 0 || !(spacing >= 0))
                return cli_usage_error("dark-spots", "--spacing '%s' is not a number of metres >= 0", argv[i]);
        } else if (strcmp(a, "--count") == 0) {
            if (cli_parse_int(argv[++i], 1, 1000000, &count) != 0)
                return cli_usage_error("dark-spots", "--count '%s' is not 1..1000000", argv[i]);
        } else if (strcmp(a, "--all") == 0) {
            all = 1;
        } else if (strcmp(a, "-o") == 0) {
            out = argv[++i];
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error("dark-spots", "unknown option '%s'", a);
        } else if (!scene) {
            scene = a;
        } else {
            return cli_usage_error("dark-spots", "unexpected argument '%s'", a);
        }
    }
    if (!scene)
        return cli_usage_error("dark-spots", "missing SCENE");
    rc = cli_open_scene("dark-spots", scene, &c, &e);
    if (rc != EXIT_OK)
        return rc;
    rc = find_spots(e, res, count, spacing, all, out, &c);
    plx_engine_free(e);
    return rc;
}
