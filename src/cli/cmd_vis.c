/* polarlux vis: exact planar visibility (SPEC §3) from points. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "geo_out.h"
#include "points.h"

static const char help[] =
    "usage: polarlux vis SCENE --points FILE [--geojson OUT] [options]\n"
    "       polarlux vis SCENE --at X,Y [--dir DEG --fov DEG] [--geojson OUT] [options]\n"
    "\n"
    "Exact visibility from free points, buildings treated as infinitely tall\n"
    "(SPEC §3), through the polar diagrams.\n"
    "\n"
    "  --points FILE  lines 'x y [...]' in the scene's coordinates (a '# crs:' line\n"
    "                 or --points-crs says otherwise; '-' reads standard input);\n"
    "                 prints one line 'x y area nverts' per point: the area (m^2)\n"
    "                 of the visibility polygon within Bounds and its vertex count.\n"
    "                 A point that is not free (inside a building, on a wall,\n"
    "                 outside Bounds) prints 'x y nan 0' and a message on stderr,\n"
    "                 and the exit code is 1.\n"
    "  --at X,Y       one viewer: prints the visible buildings (index and id), the\n"
    "                 area, and the fraction of the scene's buildings and vertices\n"
    "                 they hold\n"
    "  --dir DEG      view direction, degrees counter-clockwise from east (default 0)\n"
    "  --fov DEG      horizontal field of view (default 360: the full turn)\n"
    "  --geojson OUT  also write the visibility polygons (lon/lat when the scene\n"
    "                 was lon/lat), with area and the visible building count\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

typedef struct vis_opts {
    const char *scene, *points, *geojson;
    int have_at;
    double at[2], dir, fov;
    cli_common c;
} vis_opts;

static int parse_at(const char *v, void *dst)
{
    return cli_parse_coords(v, dst, 2);
}

static int parse_dir(const char *v, void *dst)
{
    return cli_parse_real(v, -1e6, 1e6, dst);
}

static int parse_fov(const char *v, void *dst)
{
    double *f = dst;
    return cli_parse_real(v, 0, 1e6, f) != 0 || !(*f > 0) ? -1 : 0;
}

static int parse_args(int argc, char **argv, vis_opts *o)
{
    int rc;
    const cli_opt opts[] = {
        CLI_OPT_STR("--points", &o->points),
        CLI_OPT_STR("--geojson", &o->geojson),
        { "--at", NULL, o->at, parse_at, "--at '%s' is not X,Y (finite, within 1e7 m)", 0, NULL, &o->have_at, NULL },
        CLI_OPT_VAL("--dir", &o->dir, parse_dir, "--dir '%s' is not a number of degrees"),
        CLI_OPT_VAL("--fov", &o->fov, parse_fov, "--fov '%s' is not a positive number of degrees"),
        CLI_OPT_END
    };
    cli_args pa;
    memset(o, 0, sizeof *o);
    o->fov = 360.0;
    rc = cli_options_n("vis", help, argc, argv, opts, &o->c, NULL, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc;
    o->scene = pa.npos ? pa.pos[0] : NULL;
    if (!o->scene)
        return cli_usage_error("vis", "missing SCENE");
    if (!o->points == !o->have_at)
        return cli_usage_error("vis", "give exactly one of --points FILE and --at X,Y");
    return EXIT_OK;
}

static void add_polygon(geo_out *g, const plx_visibility *v, double x, double y)
{
    cJSON *props = cJSON_CreateObject(), *rings = cJSON_CreateArray();
    cJSON_AddNumberToObject(props, "x", x);
    cJSON_AddNumberToObject(props, "y", y);
    cJSON_AddNumberToObject(props, "area", v->area);
    cJSON_AddNumberToObject(props, "nverts", v->nverts);
    cJSON_AddNumberToObject(props, "visible_buildings", v->nvisible);
    if (v->nverts >= 3)
        cJSON_AddItemToArray(rings, geo_ring(g, v->xy, v->nverts, NULL));
    geo_add(g, geo_geometry("Polygon", rings), props);
}

static int run_points(plx_engine *e, const vis_opts *o, geo_out *g)
{
    points pts;
    char err[512];
    size_t k;
    int failed = 0, rc;
    double *given = NULL;
    if (points_read(o->points, 2, 2, NULL, &pts, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux vis: %s\n", err);
        return EXIT_FAIL;
    }
    rc = cli_points_local("vis", e, &o->c, o->points, &pts, &given);
    if (rc != EXIT_OK) {
        points_free(&pts);
        return rc;
    }
    for (k = 0; k < pts.n; k++) {
        double x = pts.v[2 * k], y = pts.v[2 * k + 1], gx = given[2 * k], gy = given[2 * k + 1];
        plx_visibility v;
        plx_status st = plx_visibility_get(e, x, y, o->dir, o->fov, &v);
        if (st != PLX_OK) {
            cli_point_error("vis", o->points, pts.line[k], &given[2 * k], &pts.v[2 * k], e);
            if (st != PLX_E_RANGE) {
                points_free(&pts);
                free(given);
                return cli_exit_code(st);
            }
            printf("%.17g %.17g nan 0\n", gx, gy);
            failed = 1;
            continue;
        }
        printf("%.17g %.17g %.17g %u\n", gx, gy, v.area, v.nverts);
        if (g->root)
            add_polygon(g, &v, gx, gy);
    }
    points_free(&pts);
    free(given);
    return failed ? EXIT_FAIL : EXIT_OK;
}

static int run_at(plx_engine *e, const vis_opts *o, geo_out *g)
{
    plx_visibility v;
    plx_scene_info si;
    uint32_t i, vis_verts = 0, all_verts = 0, occluders = 0;
    double at[2];
    plx_status st;
    at[0] = o->at[0];
    at[1] = o->at[1];
    if (cli_option_local("vis", "--at", e, &at[0], &at[1]) != 0)
        return EXIT_USAGE;
    st = plx_visibility_get(e, at[0], at[1], o->dir, o->fov, &v);
    if (st != PLX_OK) {
        if (at[0] != o->at[0] || at[1] != o->at[1])
            fprintf(stderr, "polarlux vis: --at %.7f,%.7f (local %.3f, %.3f m): %s\n", o->at[0], o->at[1], at[0],
                    at[1], plx_last_error(e));
        else
            fprintf(stderr, "polarlux vis: %s\n", plx_last_error(e));
        return cli_exit_code(st);
    }
    plx_scene_info_get(e, &si);
    for (i = 0; i < si.buildings; i++) {
        plx_building b;
        uint32_t r, n = 0;
        plx_building_get(e, i, &b);
        if (b.min_height > 0)
            continue;
        for (r = 0; r < b.nrings; r++) {
            const double *xy;
            uint32_t m;
            plx_building_ring(e, i, r, &xy, &m);
            n += m;
        }
        all_verts += n;
        occluders++;
    }
    printf("# visible buildings from (%.7f, %.7f), dir %.3f, fov %.3f\n", o->at[0], o->at[1], o->dir, o->fov);
    for (i = 0; i < v.nvisible; i++) {
        plx_building b;
        uint32_t r;
        plx_building_get(e, v.visible[i], &b);
        printf("%u %s\n", v.visible[i], b.id ? b.id : "-");
        for (r = 0; r < b.nrings; r++) {
            const double *xy;
            uint32_t m;
            plx_building_ring(e, v.visible[i], r, &xy, &m);
            vis_verts += m;
        }
    }
    printf("# area %.6f m^2, %u polygon vertices\n", v.area, v.nverts);
    printf("# visible: %u of %u buildings (%.3f%%), %u of %u vertices (%.3f%% of the geometry)\n",
           v.nvisible, occluders, occluders ? 100.0 * v.nvisible / occluders : 0.0, vis_verts, all_verts,
           all_verts ? 100.0 * vis_verts / all_verts : 0.0);
    if (g->root)
        add_polygon(g, &v, o->at[0], o->at[1]);
    return EXIT_OK;
}

int cmd_vis(int argc, char **argv)
{
    vis_opts o;
    plx_engine *e;
    geo_out g;
    int rc = parse_args(argc, argv, &o);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (!cli_out_writable("vis", o.geojson))
        return EXIT_FAIL;
    rc = cli_open_scene("vis", o.scene, &o.c, &e);
    if (rc != EXIT_OK)
        return rc;
    memset(&g, 0, sizeof g);
    if (o.geojson && geo_begin(&g, e) != 0) {
        fprintf(stderr, "polarlux vis: out of memory\n");
        plx_engine_free(e);
        return EXIT_FAIL;
    }
    rc = o.points ? run_points(e, &o, &g) : run_at(e, &o, &g);
    if (o.geojson && rc != EXIT_USAGE && rc != EXIT_NOMEM && geo_write(&g, "vis", o.geojson) != 0)
        rc = EXIT_FAIL;
    geo_free(&g);
    plx_engine_free(e);
    return rc;
}
