/* polarlux: the command-line program. */
#include <string.h>
#include "cli.h"
#include "posix/safe_out.h"

typedef struct command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    { "info", cmd_info, "load a scene and print what it holds, its timing and memory" },
    { "gen", cmd_gen, "write a procedural city (grid, eixample, oldtown) as GeoJSON" },
    { "vis", cmd_vis, "exact visibility (area, polygon, visible buildings) from points" },
    { "draw", cmd_draw, "draw a quadrant polar diagram as a PNG" },
    { "illum", cmd_illum, "illuminance in lux at surface points" },
    { "lit", cmd_lit, "a lamp's lit ground and facade polygons as GeoJSON" },
    { "heatmap", cmd_heatmap, "a top-down ground illuminance map with a lux legend (PNG)" },
    { "render", cmd_render, "a night image (street or aerial view) as PNG, and PFM" },
    { "nightify", cmd_nightify, "turn a day orthophoto into night colours (histogram matching)" },
    { "route", cmd_route, "how well lit is a route: lux statistics and EN 13201 P-class" },
    { "dark-spots", cmd_dark_spots, "the darkest points of the street area as GeoJSON" },
    { "bake", cmd_bake, "build everything once and save it in one file that loads at once" },
    { "walk", cmd_walk, "frames along a camera path (PNG frames, contact sheet, frame times)" },
    { "meter", cmd_meter, "pedestrian light meters: E_h, E_v, E_sc, E_hs at points (EN 13201)" },
    { "tiles", cmd_tiles, "web-map raster tiles of the ground light (folder z/x/y.png or MBTiles)" },
    { "annotate", cmd_annotate, "every street of a network with its light (GeoJSON, CSV by way id)" },
};

static void usage(FILE *f)
{
    size_t i;
    fprintf(f, "usage: polarlux COMMAND [options]\n\n"
               "Exact night lighting of 2.5D cities (version " PLX_VERSION_STRING ").\n\n"
               "commands:\n");
    for (i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\n'polarlux COMMAND --help' describes a command.\n"
               "exit codes: 0 success, 1 the work failed (bad scene, I/O, query out of range),\n"
               "            2 usage error, 3 memory budget too small (--mem)\n");
}

/* An output option given "-" (standard output): the data gets the real
 * standard output and the command's own report lines go to stderr. */
static void claim_stdout_for_data(int argc, char **argv)
{
    int i;
    for (i = 2; i + 1 < argc; i++)
        if ((strcmp(argv[i], "-o") == 0 || strcmp(argv[i], "--pfm") == 0 || strcmp(argv[i], "--geojson") == 0) &&
            strcmp(argv[i + 1], "-") == 0)
            safe_out_claim_stdout();
}

int main(int argc, char **argv)
{
    size_t i;
    if (argc < 2) {
        usage(stderr);
        return EXIT_USAGE;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
        usage(stdout);
        return EXIT_OK;
    }
    if (strcmp(argv[1], "--version") == 0) {
        printf("polarlux %s\n", PLX_VERSION_STRING);
        return EXIT_OK;
    }
    claim_stdout_for_data(argc, argv);
    for (i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (strcmp(argv[1], commands[i].name) == 0)
            return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "polarlux: unknown command '%s' (see 'polarlux --help')\n", argv[1]);
    return EXIT_USAGE;
}
