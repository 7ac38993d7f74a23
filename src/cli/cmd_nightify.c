/* polarlux nightify DAY.png NIGHT.png -o OUT.png: day orthophoto to night
 * colours by histogram matching (munoz2013 §3.1). */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "png/image_write.h"

static const char help[] =
    "usage: polarlux nightify DAY.png NIGHT.png -o OUT.png [--dark-threshold T]\n"
    "\n"
    "Turns a day orthophoto into night colours: each channel of DAY is mapped so\n"
    "that its histogram follows NIGHT's (a night photo or render of a similar\n"
    "place), leaving out NIGHT's pixels darker than the threshold (luminance\n"
    "0..255) so that unlit areas do not dominate the palette.\n"
    "\n"
    "  -o FILE              output PNG (- for standard output)\n"
    "  --mem SIZE           memory for the decoded images (default 1G): an image\n"
    "                       whose header claims more pixels is refused (exit 3)\n"
    "                       before it is decoded\n"
    "  --dark-threshold T   luminance below which night pixels are left out of\n"
    "                       the reference histograms (default 10)\n";

static int parse_dark(const char *v, void *dst)
{
    double *d = dst;
    return cli_parse_double(v, d) != 0 || *d < 0 || *d > 255 ? -1 : 0;
}

int cmd_nightify(int argc, char **argv)
{
    const char **pos, *out = NULL;
    double dark = 10.0;
    int npos, dw = 0, dh = 0, nw, nh, rc = EXIT_OK, r;
    uint8_t *day = NULL, *night = NULL;
    char err[512];
    cli_common c;
    size_t mem;
    const cli_opt opts[] = {
        CLI_OPT_STR("-o", &out),
        CLI_OPT_VAL("--dark-threshold", &dark, parse_dark, "--dark-threshold '%s' is not 0..255"),
        CLI_OPT_END
    };
    cli_args pa;
    memset(&c, 0, sizeof c);
    rc = cli_options_n("nightify", help, argc, argv, opts, &c, NULL, 2, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    pos = pa.pos;
    npos = pa.npos;
    if (npos < 2)
        return cli_usage_error("nightify", "needs DAY.png and NIGHT.png");
    if (!out)
        return cli_usage_error("nightify", "missing -o OUT.png");
    if (!cli_out_ext("nightify", "-o", out, "png", "PNG"))
        return EXIT_USAGE;
    mem = c.mem ? c.mem : CLI_DEFAULT_MEM;
    if ((r = image_read_png_budget(pos[0], 1000000, mem, &day, &dw, &dh, err, sizeof err)) != 0 ||
        (r = image_read_png_budget(pos[1], 1000000, mem - (size_t)dw * dh * 3, &night, &nw, &nh, err,
                                   sizeof err)) != 0) {
        fprintf(stderr, "polarlux nightify: %s%s\n", err, r == -2 ? "; give it more with --mem" : "");
        rc = r == -2 ? EXIT_NOMEM : EXIT_FAIL;
    } else if (plx_nightify(day, (size_t)dw * dh, night, (size_t)nw * nh, dark, day) != PLX_OK) {
        fprintf(stderr, "polarlux nightify: empty image\n");
        rc = EXIT_FAIL;
    } else if (image_write_png_rgb8(out, dw, dh, day, 0, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux nightify: %s\n", err);
        rc = EXIT_FAIL;
    } else {
        printf("nightify: %dx%d day image matched to %dx%d night reference, written to %s\n", dw, dh, nw, nh, out);
    }
    free(day);
    free(night);
    return rc;
}
