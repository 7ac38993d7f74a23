/* polarlux gen STYLE NX NY: a procedural city as GeoJSON. */
#include <stdlib.h>
#include <string.h>
#include "cli.h"
#include "options.h"
#include "posix/safe_out.h"

static const char help[] =
    "usage: polarlux gen STYLE NX NY [--seed S] [-o FILE]\n"
    "\n"
    "Writes a procedural city of NX x NY blocks as a GeoJSON FeatureCollection\n"
    "in metres (properties.units = \"m\"), on standard output or into FILE.\n"
    "The same seed gives the same bytes.\n"
    "\n"
    "styles:\n"
    "  grid      one rectangular building per block, lamps along the streets\n"
    "  eixample  chamfered square blocks of 16 wall-sharing buildings around an\n"
    "            open courtyard, lamps along both kerbs of every street\n"
    "  oldtown   irregular, some non-convex buildings of mixed heights; lamps\n"
    "            some lower and some higher than the roofs near them\n"
    "\n"
    "  --seed S   seed of the generator (default 1)\n"
    "  -o FILE    write FILE (a regular file through a temporary file renamed\n"
    "             into place; a device or FIFO directly; - for standard output)\n";

static int write_out(void *ctx, const char *data, size_t len)
{
    return safe_out_write(ctx, data, len);
}

static int parse_seed(const char *v, void *dst)
{
    char *end;
    *(unsigned long long *)dst = strtoull(v, &end, 10);
    return *end != '\0' || end == v ? -1 : 0;
}

int cmd_gen(int argc, char **argv)
{
    const char **pos, *out = NULL;
    char err[600];
    safe_out *o;
    long nx, ny;
    unsigned long long seed = 1;
    int npos, rc;
    plx_status st;
    const cli_opt opts[] = {
        { "--seed", NULL, &seed, parse_seed, "--seed '%s' is not a whole number", 0, "--seed needs a number", NULL,
          NULL },
        { "-o", NULL, &out, NULL, NULL, 0, "-o needs a file name", NULL, NULL },
        CLI_OPT_END
    };
    cli_args pa;
    rc = cli_options_n("gen", help, argc, argv, opts, NULL, NULL, 3, "too many arguments ('%s')", &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    pos = pa.pos;
    npos = pa.npos;
    if (npos < 3)
        return cli_usage_error("gen", "needs STYLE NX NY, e.g. 'polarlux gen eixample 30 30'");
    if (strcmp(pos[0], "grid") && strcmp(pos[0], "eixample") && strcmp(pos[0], "oldtown"))
        return cli_usage_error("gen", "unknown style '%s' (grid, eixample or oldtown)", pos[0]);
    if (cli_parse_int(pos[1], 1, 1000, &nx) || cli_parse_int(pos[2], 1, 1000, &ny))
        return cli_usage_error("gen", "NX and NY must be whole numbers from 1 to 1000");
    o = safe_out_open(out ? out : "-", err, sizeof err);
    if (!o) {
        fprintf(stderr, "polarlux gen: %s\n", err);
        return EXIT_FAIL;
    }
    st = plx_gen_city(pos[0], (int)nx, (int)ny, seed, write_out, o);
    if (st != PLX_OK) {
        int e = safe_out_errno(o);
        if (e)
            fprintf(stderr, "polarlux gen: cannot write '%s': %s\n", out ? out : "-", strerror(e));
        else
            fprintf(stderr, "polarlux gen: %s\n", plx_strerror(st));
        safe_out_abort(o);
        return e ? EXIT_FAIL : cli_exit_code(st);
    }
    if (safe_out_commit(&o, 1, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux gen: %s\n", err);
        return EXIT_FAIL;
    }
    return EXIT_OK;
}
