/* polarlux gen STYLE NX NY: a procedural city as GeoJSON. */
#include <stdlib.h>
#include <string.h>
#include "cli.h"
#include "options.h"

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
    "  -o FILE    write FILE (through a temporary file renamed into place)\n";

typedef struct sink {
    FILE *f;
} sink;

static int write_out(void *ctx, const char *data, size_t len)
{
    sink *s = ctx;
    return fwrite(data, 1, len, s->f) == len ? 0 : -1;
}

static int finish_file(sink *s, const char *tmp, const char *out)
{
    if (fclose(s->f) != 0 || rename(tmp, out) != 0) {
        perror(out);
        remove(tmp);
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

static int parse_seed(const char *v, void *dst)
{
    char *end;
    *(unsigned long long *)dst = strtoull(v, &end, 10);
    return *end != '\0' || end == v;
}

int cmd_gen(int argc, char **argv)
{
    const char *out = NULL;
    char tmp[4096];
    long nx, ny;
    unsigned long long seed = 1;
    const cli_opt opts[] = {
        { "--seed", NULL, &seed, parse_seed, "--seed '%s' is not a whole number", 0, "--seed needs a number" },
        { "-o", NULL, &out, NULL, NULL, 0, "-o needs a file name" },
        CLI_OPT_END
    };
    cli_args pa;
    const char **pos = pa.pos;
    int rc;
    plx_status st;
    sink s;
    rc = cli_options("gen", help, argc, argv, opts, NULL, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (pa.npos > 3)
        return cli_usage_error("gen", "too many arguments ('%s')", pa.pos[3]);
    if (pa.npos < 3)
        return cli_usage_error("gen", "needs STYLE NX NY, e.g. 'polarlux gen eixample 30 30'");
    if (strcmp(pos[0], "grid") && strcmp(pos[0], "eixample") && strcmp(pos[0], "oldtown"))
        return cli_usage_error("gen", "unknown style '%s' (grid, eixample or oldtown)", pos[0]);
    if (cli_parse_int(pos[1], 1, 1000, &nx) || cli_parse_int(pos[2], 1, 1000, &ny))
        return cli_usage_error("gen", "NX and NY must be whole numbers from 1 to 1000");
    s.f = stdout;
    if (out) {
        if (snprintf(tmp, sizeof tmp, "%s.tmp", out) >= (int)sizeof tmp)
            return cli_usage_error("gen", "output path too long");
        s.f = fopen(tmp, "wb");
        if (!s.f) {
            perror(out);
            return EXIT_FAIL;
        }
    }
    st = plx_gen_city(pos[0], (int)nx, (int)ny, seed, write_out, &s);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux gen: %s\n", plx_strerror(st));
        if (out) {
            fclose(s.f);
            remove(tmp);
        }
        return cli_exit_code(st);
    }
    if (out)
        return finish_file(&s, tmp, out);
    return fflush(stdout) == 0 ? EXIT_OK : EXIT_FAIL;
}
