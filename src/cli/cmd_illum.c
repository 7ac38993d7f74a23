/* polarlux illum: illuminance at points (SPEC §2). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "points.h"

static const char help[] =
    "usage: polarlux illum SCENE --points FILE [options]\n"
    "\n"
    "Illuminance at points (light meters anywhere, SPEC §2): on a surface or\n"
    "in free air, any unit normal. FILE has lines 'x y z nx ny nz': x y in\n"
    "the scene's coordinates (lon/lat on a lon/lat scene) unless a '# crs:'\n"
    "line (lonlat, local or the scene's CRS name) or --points-crs says\n"
    "otherwise, z in metres above the ground, and a unit normal; 'x y' alone\n"
    "means a ground point facing up, 'x y z' a point facing up; '-' reads\n"
    "standard input). Prints one line 'x y z E_direct E_indirect' per point,\n"
    "in lux. E_direct is exact (2.5D\n"
    "shadows, SPEC §2); E_indirect (SPEC §4) is gathered over 32 x 32\n"
    "directions: the light the surfaces around the point reflect, from their\n"
    "exact E_direct, plus their later bounces from the photon buffers, traced\n"
    "first (--frames progressive frames of --photons photons; progress on a\n"
    "terminal; only from the lamps whose reach comes within 100 m of the\n"
    "points); 0 with --no-indirect.\n"
    "Points may be on a surface or in free air (light meters anywhere, SPEC\n"
    "§2), any unit normal. A point strictly inside a building (or below the\n"
    "ground) prints 'x y z nan nan', is reported on stderr with its line, and\n"
    "makes the exit code 1.\n"
    "\n"
    "  --points FILE  the points (required)\n"
    "  --points-crs C  the points' coordinates: lonlat, local (the scene's metres)\n"
    "                 or the scene's CRS name, over the file's '# crs:' line\n"
    "  --photons N    photons per frame (default 65536)\n"
    "  --frames K     progressive photon frames (default 16: 1,048,576 photons)\n"
    "  --gather N     final gathering over N x N directions (default 32); 0: the\n"
    "                 photon buffers' own estimate at the point (the older\n"
    "                 method: give it --frames 256)\n"
    "  --no-indirect  direct light only (E_indirect 0)\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

int cmd_illum(int argc, char **argv)
{
    static const double fill[6] = { 0, 0, 0, 0, 0, 1 };
    cli_common c;
    cli_indirect ind;
    const char *scene = NULL, *file = NULL;
    plx_engine *e;
    points pts;
    char err[512];
    double *ed, *ei, *given = NULL;
    cli_progress pr;
    size_t k;
    const cli_opt opts[] = {
        { "--points", NULL, &file, NULL, NULL, 0, "--points needs a file", NULL, NULL },
        CLI_OPT_END
    };
    cli_args pa;
    int rc, failed = 0;
    memset(&c, 0, sizeof c);
    cli_indirect_default(&ind);
    ind.frames = CLI_GATHER_FRAMES;
    rc = cli_options("illum", help, argc, argv, opts, &c, &ind, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (pa.npos > 1)
        return cli_usage_error("illum", "unexpected argument '%s'", pa.pos[1]);
    scene = pa.npos ? pa.pos[0] : NULL;
    if (!scene)
        return cli_usage_error("illum", "missing SCENE");
    if (!file)
        return cli_usage_error("illum", "missing --points FILE");
    if (points_read(file, 2, 6, fill, &pts, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux illum: %s\n", err);
        return EXIT_FAIL;
    }
    rc = cli_open_scene("illum", scene, &c, &e);
    if (rc != EXIT_OK) {
        points_free(&pts);
        return rc;
    }
    rc = cli_points_local("illum", e, &c, file, &pts, &given);
    if (rc != EXIT_OK) {
        points_free(&pts);
        plx_engine_free(e);
        return rc;
    }
    cli_points_far("illum", &c, e, file, &pts);
    if (!ind.off && pts.n > 0) {
        double eye[3] = { 0, 0, 1.7 }, box[4];
        box[0] = box[2] = pts.v[0];
        box[1] = box[3] = pts.v[1];
        for (k = 0; k < pts.n; k++) {
            eye[0] += pts.v[6 * k] / pts.n;
            eye[1] += pts.v[6 * k + 1] / pts.n;
            box[0] = fmin(box[0], pts.v[6 * k]);
            box[1] = fmin(box[1], pts.v[6 * k + 1]);
            box[2] = fmax(box[2], pts.v[6 * k]);
            box[3] = fmax(box[3], pts.v[6 * k + 1]);
        }
        /* photons only from the lamps within 100 m of the points' box
         * (the gather setting first: it decides the photon configuration) */
        plx_status sst = ind.gather >= 0 ? plx_indirect_set_gather(e, (uint32_t)ind.gather) : PLX_OK;
        if (sst == PLX_OK)
            sst = plx_indirect_select_lamps(e, box, CLI_SELECT_MARGIN, NULL);
        if (sst != PLX_OK) {
            fprintf(stderr, "polarlux illum: %s\n", plx_last_error(e));
            free(given);
            points_free(&pts);
            plx_engine_free(e);
            return sst == PLX_E_NOMEM ? EXIT_NOMEM : EXIT_FAIL;
        }
        rc = cli_indirect_run("illum", &c, e, &ind, eye, NULL, 360.0);
        if (rc != EXIT_OK) {
            free(given);
            points_free(&pts);
            plx_engine_free(e);
            return rc;
        }
    }
    ed = malloc(sizeof *ed * (pts.n + 1));
    ei = malloc(sizeof *ei * (pts.n + 1));
    if (!ed || !ei) {
        fprintf(stderr, "polarlux illum: out of memory for %zu points\n", pts.n);
        rc = EXIT_FAIL;
        goto done;
    }
    cli_progress_start(&pr);
    for (k = 0; k < pts.n; k++) {
        const double *p = pts.v + 6 * k;
        plx_status st = plx_illuminance(e, 1, p, p + 3, &ed[k], &ei[k], NULL);
        cli_progress_step(&pr, "illum", k + 1, pts.n);
        if (st == PLX_E_RANGE) {
            cli_point_error("illum", file, pts.line[k], &given[2 * k], p, e);
            failed = 1;
        } else if (st != PLX_OK) {
            cli_progress_end(&pr);
            fprintf(stderr, "polarlux illum: %s\n", plx_last_error(e));
            rc = cli_exit_code(st);
            goto done;
        }
        { /* the point as given (24.944, not 24.943999999999999: the same double), then the lux */
            char gx[32], gy[32], gz[32];
            cli_shortest(given[2 * k], gx, sizeof gx);
            cli_shortest(given[2 * k + 1], gy, sizeof gy);
            cli_shortest(p[2], gz, sizeof gz);
            printf("%s %s %s %.17g %.17g\n", gx, gy, gz, ed[k], ei[k]);
        }
    }
    cli_progress_end(&pr);
    rc = failed ? EXIT_FAIL : EXIT_OK;
    {   /* dark: every point that got numbers (not those inside a building: nan) got 0 lx */
        size_t got = 0, lit = 0;
        for (k = 0; k < pts.n; k++) {
            got += ed[k] == ed[k];
            lit += ed[k] + ei[k] > 0;
        }
        if (got > 0 && lit == 0)
            cli_warn("illum", &c, "every point is dark (0 lx): %s", cli_dark_reason(e));
        if (pts.n == 0) /* as meter: an empty answer says why */
            fprintf(stderr, "polarlux illum: %s holds no points\n", file);
    }
done:
    free(given);
    free(ed);
    free(ei);
    points_free(&pts);
    plx_engine_free(e);
    return rc;
}
