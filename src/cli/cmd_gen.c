/* polarlux gen STYLE NX NY: a procedural city as GeoJSON. */
#include <stdlib.h>
#include <string.h>
#include "cli.h"
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

int cmd_gen(int argc, char **argv)
{
    const char *pos[3], *out = NULL;
    char err[600];
    safe_out *o;
    long nx, ny;
    unsigned long long seed = 1;
    int npos = 0, i;
    plx_status st;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(help, stdout);
            return EXIT_OK;
        } else if (strcmp(argv[i], "--seed") == 0) {
            char *end;
            if (i + 1 >= argc)
                return cli_usage_error("gen", "--seed needs a number");
            seed = strtoull(argv[++i], &end, 10);
            if (*end != '\0' || end == argv[i])
                return cli_usage_error("gen", "--seed '%s' is not a whole number", argv[i]);
        } else if (strcmp(argv[i], "-o") == 0) {
            if (i + 1 >= argc)
                return cli_usage_error("gen", "-o needs a file name");
            out = argv[++i];
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            return cli_usage_error("gen", "unknown option '%s'", argv[i]);
        } else if (npos < 3) {
            pos[npos++] = argv[i];
        } else {
            return cli_usage_error("gen", "too many arguments ('%s')", argv[i]);
        }
    }
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
