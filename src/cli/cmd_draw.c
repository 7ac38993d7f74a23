/* polarlux draw SCENE --polar Q -o pd.png: a picture of a polar diagram. */
#include <string.h>

#include "canvas.h"
#include "cli.h"
#include "options.h"

static const char help[] =
    "usage: polarlux draw SCENE --polar Q -o OUT.png [--size PX] [options]\n"
    "\n"
    "Draws quadrant polar diagram Q (0: the scan starts east, 1: north, 2: west,\n"
    "3: south) over the Bounds box: each region filled with a colour of its owner\n"
    "(the object met first by the counter-clockwise scan from its points: a\n"
    "building, or in grey the Bounds frame enclosing the scene), footprints in\n"
    "black, region boundaries (polar axes and walls) in dark lines.\n"
    "\n"
    "  --polar Q     quadrant 0..3 (required)\n"
    "  -o OUT.png    output image (required)\n"
    "  --size PX     pixels on the longer side (default 1600)\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

/* A stable colour for a building index. */
static void owner_colour(int32_t owner, uint8_t rgb[3])
{
    uint32_t h = (uint32_t)owner * 2654435761u;
    if (owner < 0) {
        rgb[0] = rgb[1] = rgb[2] = 70;
        return;
    }
    rgb[0] = (uint8_t)(60 + (h >> 8) % 170);
    rgb[1] = (uint8_t)(60 + (h >> 16) % 170);
    rgb[2] = (uint8_t)(60 + (h >> 24) % 170);
}

static int draw(plx_engine *e, int q, const char *out, int size)
{
    static const uint8_t white[3] = { 255, 255, 255 }, edge[3] = { 20, 20, 20 };
    plx_scene_info si;
    canvas c;
    uint32_t i, count;
    char err[512];
    plx_status st = plx_polar_region_count(e, q, &count);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux draw: %s\n", plx_last_error(e));
        return cli_exit_code(st);
    }
    plx_scene_info_get(e, &si);
    if (canvas_init(&c, si.bounds, size) != 0) {
        fprintf(stderr, "polarlux draw: cannot make a %d-pixel canvas\n", size);
        return EXIT_FAIL;
    }
    canvas_fill(&c, 0, 0, 0);
    for (i = 0; i < count; i++) {
        double xy[8];
        uint32_t n;
        int32_t owner;
        int solid;
        uint8_t rgb[3];
        if (plx_polar_region(e, q, i, xy, &n, &owner, &solid) != PLX_OK || n < 3)
            continue;
        owner_colour(owner, rgb);
        canvas_poly(&c, xy, (int)n, solid ? white : rgb);
    }
    for (i = 0; i < count; i++) {
        double xy[8];
        uint32_t n, k;
        int32_t owner;
        int solid;
        if (plx_polar_region(e, q, i, xy, &n, &owner, &solid) != PLX_OK || n < 3 || solid)
            continue;
        for (k = 0; k < n; k++)
            canvas_line(&c, xy[2 * k], xy[2 * k + 1], xy[2 * ((k + 1) % n)], xy[2 * ((k + 1) % n) + 1], edge);
    }
    if (canvas_write(&c, out, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux draw: %s\n", err);
        canvas_free(&c);
        return EXIT_FAIL;
    }
    printf("polar diagram %d: %u regions, %dx%d pixels, written to %s\n", q, count, c.w, c.h, out);
    canvas_free(&c);
    return EXIT_OK;
}

static int parse_quadrant(const char *v, void *dst)
{
    return cli_parse_int(v, 0, 3, dst);
}

static int parse_size(const char *v, void *dst)
{
    return cli_parse_int(v, 16, 16384, dst);
}

int cmd_draw(int argc, char **argv)
{
    cli_common c;
    const char *scene, *out = NULL;
    long q = -1, size = 1600;
    const cli_opt opts[] = {
        { "--polar", NULL, &q, parse_quadrant, "--polar '%s' is not a quadrant 0..3", 0, NULL, NULL, NULL },
        { "-o", NULL, &out, NULL, NULL, 0, NULL, NULL, NULL },
        { "--size", NULL, &size, parse_size, "--size '%s' is not 16..16384 pixels", 0, NULL, NULL, NULL },
        CLI_OPT_END
    };
    cli_args pa;
    plx_engine *e;
    int rc;
    memset(&c, 0, sizeof c);
    rc = cli_options("draw", help, argc, argv, opts, &c, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (pa.npos > 1)
        return cli_usage_error("draw", "unexpected argument '%s'", pa.pos[1]);
    scene = pa.npos ? pa.pos[0] : NULL;
    if (!scene)
        return cli_usage_error("draw", "missing SCENE");
    if (q < 0)
        return cli_usage_error("draw", "missing --polar Q (0..3)");
    if (!out)
        return cli_usage_error("draw", "missing -o OUT.png");
    if (!cli_out_ext("draw", "-o", out, "png", "PNG"))
        return EXIT_USAGE;
    if (!cli_out_writable("draw", out))
        return EXIT_FAIL;
    rc = cli_open_scene("draw", scene, &c, &e);
    if (rc != EXIT_OK)
        return rc;
    rc = draw(e, (int)q, out, (int)size);
    plx_engine_free(e);
    return rc;
}
