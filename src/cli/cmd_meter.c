/* polarlux meter: SPEC §6 pedestrian quantities (E_h, E_v, E_sc, E_hs) at
 * points. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "points.h"

static const char help[] =
    "usage: polarlux meter SCENE --points FILE [--quantity h,v,sc,hs] [--height M] [options]\n"
    "\n"
    "Light meters (SPEC §6, EN 13201): direct illuminance at points in free air\n"
    "or on surfaces. FILE has lines 'x y [z [ux uy]]' (x y in the scene's\n"
    "coordinates as for 'polarlux illum', or --points-crs; z in metres; '-'\n"
    "reads standard input, '#' starts a comment): z defaults to --height, the facing\n"
    "direction (ux, uy) of E_v and E_sc to east (+x). Prints one line per point:\n"
    "'x y z' then the asked quantities in the order given, in lux:\n"
    "  h   horizontal illuminance E_h (normal +z)\n"
    "  v   vertical illuminance E_v facing (ux, uy)\n"
    "  sc  semi-cylindrical illuminance E_sc facing (ux, uy)\n"
    "  hs  hemispherical illuminance E_hs\n"
    "A point strictly inside a building (or below the ground) prints nan, is\n"
    "reported on stderr with its line and makes the exit code 1.\n"
    "\n"
    "  --points FILE    the points (required)\n"
    "  --quantity LIST  comma-separated, any order (default h,v,sc,hs)\n"
    "  --height M       z of points that give none (default 1.5)\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

/* Parses "h,v,sc,hs" into PLX_METER_* indices; the count, or -1. */
static int parse_quantities(const char *s, int q[16])
{
    int n = 0;
    while (*s) {
        size_t len = strcspn(s, ",");
        int k = -1;
        if (len == 1 && s[0] == 'h') k = PLX_METER_H;
        else if (len == 1 && s[0] == 'v') k = PLX_METER_V;
        else if (len == 2 && strncmp(s, "sc", 2) == 0) k = PLX_METER_SC;
        else if (len == 2 && strncmp(s, "hs", 2) == 0) k = PLX_METER_HS;
        if (k < 0 || n == 16)
            return -1;
        q[n++] = k;
        s += len;
        if (*s == ',')
            s++;
    }
    return n;
}

static int run(plx_engine *e, const cli_common *c, const char *file, const points *pts, const double *given,
               const int *q, int nq)
{
    size_t k, got = 0, lit = 0;
    int failed = 0, i;
    for (k = 0; k < pts->n; k++) { /* every facing direction first: no rows printed before a bad one */
        const double *u = pts->v + 5 * k + 3;
        if (!(isfinite(u[0]) && isfinite(u[1])) || (u[0] == 0.0 && u[1] == 0.0)) {
            fprintf(stderr, "polarlux meter: %s:%zu: the facing direction (ux, uy) is zero or not finite\n", file,
                    pts->line[k]);
            return EXIT_FAIL;
        }
    }
    for (k = 0; k < pts->n; k++) {
        const double *p = pts->v + 5 * k;
        double m[PLX_METER_COUNT];
        plx_status st = plx_meter(e, 1, p, p + 3, m);
        if (st == PLX_E_RANGE) {
            cli_point_error("meter", file, pts->line[k], &given[2 * k], p, e);
            failed = 1;
        } else if (st == PLX_E_INVALID) {
            fprintf(stderr, "polarlux meter: %s:%zu: the facing direction (ux, uy) is zero or not finite\n", file,
                    pts->line[k]);
            return EXIT_FAIL;
        } else if (st != PLX_OK) {
            fprintf(stderr, "polarlux meter: %s\n", plx_last_error(e));
            return cli_exit_code(st);
        }
        { /* the point as given (24.944, not 24.943999999999999: the same double) */
            char gx[32], gy[32], gz[32];
            cli_shortest(given[2 * k], gx, sizeof gx);
            cli_shortest(given[2 * k + 1], gy, sizeof gy);
            cli_shortest(p[2], gz, sizeof gz);
            printf("%s %s %s", gx, gy, gz);
        }
        for (i = 0; i < nq; i++) {
            printf(" %.17g", m[q[i]]);
            lit += st == PLX_OK && m[q[i]] > 0.0;
        }
        printf("\n");
        got += st == PLX_OK;
    }
    if (got > 0 && lit == 0) /* as illum: every meter that read reads 0 lx */
        cli_warn("meter", c, "every point is dark (0 lx): %s", cli_dark_reason(e));
    return failed ? EXIT_FAIL : EXIT_OK;
}

typedef struct quantities {
    int q[16], n;
} quantities;

static int parse_list(const char *s, void *dst)
{
    quantities *l = dst;
    l->n = parse_quantities(s, l->q);
    return l->n <= 0 ? -1 : 0;
}

int cmd_meter(int argc, char **argv)
{
    cli_common c;
    const char *scene = NULL, *file = NULL;
    plx_engine *e;
    points pts;
    char err[512];
    double fill[5] = { 0, 0, 1.5, 1, 0 }, *given = NULL;
    quantities ql = { { PLX_METER_H, PLX_METER_V, PLX_METER_SC, PLX_METER_HS }, 4 };
    int *q = ql.q, rc;
    const cli_opt opts[] = {
        CLI_OPT_STR("--points", &file),
        CLI_OPT_VAL("--quantity", &ql, parse_list, "--quantity '%s' is not a list of h, v, sc, hs"),
        CLI_OPT_VAL("--height", &fill[2], cli_opt_height, "--height '%s' is not a number of metres from 0 to 1000"),
        CLI_OPT_END
    };
    cli_args pa;
    memset(&c, 0, sizeof c);
    rc = cli_options_n("meter", help, argc, argv, opts, &c, NULL, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    scene = pa.npos ? pa.pos[0] : NULL;
    if (!scene)
        return cli_usage_error("meter", "missing SCENE");
    if (!file)
        return cli_usage_error("meter", "missing --points FILE");
    if (points_read(file, 2, 5, fill, &pts, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux meter: %s\n", err);
        return EXIT_FAIL;
    }
    rc = cli_open_scene("meter", scene, &c, &e);
    if (rc != EXIT_OK) {
        points_free(&pts);
        return rc;
    }
    rc = cli_points_local("meter", e, &c, file, &pts, &given);
    if (rc == EXIT_OK)
        cli_points_far("meter", &c, e, file, &pts);
    if (rc == EXIT_OK)
        rc = run(e, &c, file, &pts, given, q, ql.n);
    free(given);
    if (rc == EXIT_OK && pts.n == 0)
        fprintf(stderr, "polarlux meter: %s holds no points\n", file);
    points_free(&pts);
    plx_engine_free(e);
    return rc;
}
