/* polarlux render: night images (SPEC §5). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "port.h"
#include "png/image_write.h"
#ifdef PLX_HAVE_OSMESA
#include "plx_osmesa.h"
#endif

#ifdef PLX_HAVE_OSMESA
#define OSMESA_STATE "built in"
#else
#define OSMESA_STATE "not built into this polarlux"
#endif

static const char help[] =
    "usage: polarlux render SCENE [--eye X,Y,Z --target X,Y,Z] [--fov DEG] [--size WxH]\n"
    "                       [--view street|aerial] [--backend soft|osmesa]\n"
    "                       [--exposure E [--tone-curve]] [--no-indirect] [--no-glow]\n"
    "                       [--aa N [--aa-full]] [--texel M] [--per-pixel] [--threads N]\n"
    "                       [--refine [--refine-height M]] [--photons N] [--frames K]\n"
    "                       [--lamps FILE] [--mem SIZE] [--strict] [--quiet]\n"
    "                       -o OUT.png [--pfm OUT.pfm]\n"
    "\n"
    "Renders the scene at night through a pinhole camera (SPEC §5: up is +z,\n"
    "vertical field of view, pixel centres): ground, facades and roofs lit by\n"
    "every lamp with exact 2.5D shadows (SPEC §2), Lambertian, each lamp in its\n"
    "colour, lamps drawn as small glows, black sky; exposure then sRGB into an\n"
    "8-bit PNG, and the linear radiance into a PFM with --pfm.\n"
    "\n"
    "With indirect light (the default) pixels are read from the radiance atlas:\n"
    "every surface's light at points --texel m apart, interpolated (a bake\n"
    "holds it; else a frame fills what it reads). --no-indirect, --per-pixel:\n"
    "the light computed at every pixel instead.\n"
    "\n"
    "  --eye X,Y,Z      camera position: X,Y in the scene's coordinates (lon/lat on a\n"
    "                   lon/lat scene), Z metres above the ground (z > 0)\n"
    "  --target X,Y,Z   the point looked at\n"
    "                   (default street view: 1.7 m up, 12 m from a lamp near the\n"
    "                   middle, looking past it at the least open space in view\n"
    "                   (at least 300 m^2): nearby facades;\n"
    "                   default aerial view: straight down over the whole scene)\n"
    "  --fov DEG        vertical field of view (default 60)\n"
    "  --size WxH       image size (default 640x480)\n"
    "  --view V         street (default) or aerial (without the atlas: the ground\n"
    "                   from a light map of exact illuminance, texels --texel m)\n"
    "  --texel M        the atlas's spacing (default 0.5 m, coarser to fit its\n"
    "                   budget; a bake's is kept), the light map's (default 1 m)\n"
    "  --exposure E     radiance multiplier before sRGB, no tone curve (SPEC §5;\n"
    "                   --exposure 1 is the reference image). Default: automatic:\n"
    "                   a high percentile of the lit pixels' luminance near white,\n"
    "                   a tone curve keeping highlights near lamps; printed\n"
    "  --tone-curve     with --exposure E: E with the tone curve (a walk frame\n"
    "                   again from its cameras.txt exposure)\n"
    "  --no-glow        no lamp glows: every pixel is exactly SPEC §5's radiance\n"
    "  --refine         near-viewer refinement (munoz2013 §3.3-3.4): the lamps near\n"
    "                   where the view meets the ground (up to 30 m ahead) get floor\n"
    "                   photon maps; 16 more photon frames refill the chart\n"
    "  --refine-height M  refine only with the eye at most M m above the ground\n"
    "                   (default 60)\n"
    "  --aa N           anti-aliasing: N x N samples per pixel, averaged in linear\n"
    "                   radiance (default 1: one sample at each pixel centre, SPEC §5);\n"
    "                   the later samples only where the first one's image has an edge\n"
    "                   (every sample when edges cover over half of an atlas frame)\n"
    "  --aa-full        every pixel takes all N x N samples\n"
    "  --no-indirect    direct light only, exact at every pixel\n"
    "  --per-pixel      with indirect light, each pixel's light computed there: slower\n"
    "  --photons N      photons per frame (default 16 a lamp, 65536..1048576)\n"
    "  --frames K       progressive photon frames for the still image (default 4)\n"
    "  --backend B      raster pass: soft (default, built in) or osmesa (OpenGL into\n"
    "                   an OSMesa buffer; " OSMESA_STATE "); the same image\n"
    "  -o FILE          output PNG (required)\n"
    "  --pfm FILE       also write the linear radiance as PFM\n"
    "  --threads N      threads for the frame (default: the number of processors);\n"
    "                   the same bytes for any N\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

typedef struct render_args {
    const char *scene, *out, *pfm;
    int have_eye, have_target, aerial, osmesa, refine;
    double refine_height;
    plx_camera cam;
    plx_render_opts opts;
    cli_common c;
    cli_indirect ind;
} render_args;

static int parse_vec3(const char *s, void *dst)
{
    double *v = dst;
    return cli_parse_coords(s, v, 3) == 0 && fabs(v[2]) <= 1e5 ? 0 : -1;
}

static int parse_backend(const char *s, void *dst)
{
    if (strcmp(s, "soft") && strcmp(s, "osmesa"))
        return -1;
    *(int *)dst = strcmp(s, "osmesa") == 0;
    return 0;
}

static int parse_texel(const char *s, void *dst)
{
    return cli_parse_real(s, 0.01, 1e4, dst);
}

static int parse_args(int argc, char **argv, render_args *a)
{
    cli_view v;
    int rc;
    const cli_opt opts[] = {
        { "--eye", NULL, a->cam.eye, parse_vec3,
          "--eye '%s' is not X,Y,Z (finite, x and y within 1e7 m, z within 1e5 m)", 0, NULL, &a->have_eye, NULL },
        { "--target", NULL, a->cam.target, parse_vec3,
          "--target '%s' is not X,Y,Z (finite, x and y within 1e7 m, z within 1e5 m)", 0, NULL, &a->have_target, NULL },
        CLI_OPT_VAL("--backend", &a->osmesa, parse_backend, "--backend '%s' is not soft or osmesa"),
        { "--exposure", NULL, &a->opts.exposure, cli_parse_exposure, "--exposure '%s' is not a number above 0, up to 1e9", 0,
          NULL, &v.exposure, NULL },
        CLI_OPT_VAL("--texel", &a->opts.aerial_m_per_texel, parse_texel,
                    "--texel '%s' is not a number of metres from 0.01 to 1e4"),
        CLI_OPT_STR("-o", &a->out),
        CLI_OPT_STR("--pfm", &a->pfm),
        CLI_OPT_MORE(v.frag),
        CLI_OPT_END
    };
    cli_args pa;
    memset(a, 0, sizeof *a);
    cli_view_init(&v, 640, 480, 60.0, &a->opts, &a->ind);
    rc = cli_options_n("render", help, argc, argv, opts, &a->c, &a->ind, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc;
    a->scene = pa.npos ? pa.pos[0] : NULL;
    a->cam.fov_deg = v.fov;
    a->cam.width = (int32_t)v.size[0];
    a->cam.height = (int32_t)v.size[1];
    if ((rc = cli_view_apply("render", &v, &a->ind, &a->opts)) != EXIT_OK)
        return rc;
    a->aerial = v.aerial;
    a->refine = v.refine;
    a->refine_height = v.refine_height;
    if (v.refine_height_set && !v.refine)
        cli_warn("render", &a->c, "--refine-height has no effect without --refine");
    if (v.refine && a->ind.off)
        cli_warn("render", &a->c, "--refine has no effect with --no-indirect (it refines the indirect light)");
    if (!a->scene)
        return cli_usage_error("render", "missing SCENE");
    if (!a->out)
        return cli_usage_error("render", "missing -o OUT.png");
    if (!cli_out_ext("render", "-o", a->out, "png", "PNG") || !cli_out_ext("render", "--pfm", a->pfm, "pfm", "PFM"))
        return EXIT_USAGE;
    if (a->have_eye != a->have_target)
        return cli_usage_error("render", "give both --eye and --target, or neither");
    if (a->have_eye && !(a->cam.eye[2] > 0.0))
        return cli_usage_error("render", "the eye must be above the ground (z > 0), not %g", a->cam.eye[2]);
    if (a->have_eye && a->cam.eye[0] == a->cam.target[0] && a->cam.eye[1] == a->cam.target[1] &&
        a->cam.eye[2] == a->cam.target[2])
        return cli_usage_error("render", "--eye and --target are the same point");
    return EXIT_OK;
}

/* Whether (x, y) is a free ground point, not inside any footprint
 * (visibility test): 1 free, 0 not, -1 out of memory for the query. */
static int free_point(plx_engine *e, double x, double y)
{
    plx_visibility v;
    plx_status st = plx_visibility_get(e, x, y, 0, 1, &v);
    return st == PLX_OK ? 1 : st == PLX_E_NOMEM ? -1 : 0;
}

/* A warning when the eye is inside a building's solid (over its footprint,
 * between min_height and height): the image then shows the inside of its
 * walls, which is seldom what was meant. */
static void warn_eye_inside(plx_engine *e, const double *eye, int quiet)
{
    plx_visibility v;
    plx_building b;
    const char *msg, *at;
    unsigned long k;
    if (quiet || plx_visibility_get(e, eye[0], eye[1], 0, 1, &v) != PLX_E_RANGE)
        return;
    msg = plx_last_error(e);
    at = strstr(msg, "is inside building ");
    if (!at || sscanf(at, "is inside building %lu", &k) != 1 || plx_building_get(e, (uint32_t)k, &b) != PLX_OK)
        return;
    if (eye[2] > b.min_height && eye[2] < b.height)
        fprintf(stderr, "polarlux render: warning: --eye (%g, %g, %g) is inside building %lu%s%s%s "
                "(%g to %g m high): the image shows the inside of its walls\n", eye[0], eye[1], eye[2], k,
                b.id ? " (" : "", b.id ? b.id : "", b.id ? ")" : "", b.min_height, b.height);
}

/* Default street camera: among the 40 lamps nearest the middle of Bounds and
 * 8 directions each, an eye 1.7 m high 12 m before the lamp with 40 m of free
 * ground past it, choosing the most enclosed view (the smallest visible area
 * in a 60-degree field of view, at least 300 m^2): a street rather than a
 * square. 0 found, -1 none, -2 no memory for the polar diagrams, -3 no
 * memory for the search's visibility queries. */
typedef struct lamp_rank {
    double dist;
    uint32_t i;
} lamp_rank;

static int cmp_rank(const void *a, const void *b)
{
    const lamp_rank *p = a, *q = b;
    return (p->dist > q->dist) - (p->dist < q->dist);
}

static int default_street(plx_engine *e, plx_camera *cam)
{
    plx_scene_info si;
    lamp_rank *r;
    double cx, cy, best = INFINITY;
    uint32_t i, n;
    plx_status st = plx_polar_build(e); /* the search below asks for visibility */
    if (st != PLX_OK)
        return st == PLX_E_NOMEM ? -2 : -1;
    plx_scene_info_get(e, &si);
    cx = 0.5 * (si.bounds[0] + si.bounds[2]);
    cy = 0.5 * (si.bounds[1] + si.bounds[3]);
    r = malloc(sizeof *r * (si.lamps + 1));
    if (!r)
        return -1;
    for (i = 0; i < si.lamps; i++) {
        plx_lamp l;
        plx_lamp_get(e, i, &l);
        r[i].dist = hypot(l.x - cx, l.y - cy);
        r[i].i = i;
    }
    qsort(r, si.lamps, sizeof *r, cmp_rank);
    n = si.lamps < 40 ? si.lamps : 40;
    for (i = 0; i < n; i++) {
        plx_lamp l;
        int d;
        plx_lamp_get(e, r[i].i, &l);
        for (d = 0; d < 8; d++) {
            double a = d * 0.7853981633974483, ux = cos(a), uy = sin(a);
            double ex = l.x - 12 * ux, ey = l.y - 12 * uy, tx = l.x + 40 * ux, ty = l.y + 40 * uy;
            plx_visibility v;
            plx_status vs = PLX_OK;
            int k, ok = free_point(e, ex, ey);
            for (k = 1; ok == 1 && k <= 10; k++)
                ok = free_point(e, ex + (tx - ex) * k / 10, ey + (ty - ey) * k / 10);
            if (ok == 1)
                vs = plx_visibility_get(e, ex, ey, a * 57.29577951308232, 60, &v);
            if (ok < 0 || vs == PLX_E_NOMEM) {
                free(r);
                return -3;
            }
            if (ok == 0 || vs != PLX_OK || v.area < 300 || v.area >= best)
                continue;
            best = v.area;
            cam->eye[0] = ex;
            cam->eye[1] = ey;
            cam->eye[2] = 1.7;
            cam->target[0] = tx;
            cam->target[1] = ty;
            cam->target[2] = 3.0;
        }
    }
    free(r);
    return best < INFINITY ? 0 : -1;
}

/* The PNG and the PFM belong together: both are written, then both are
 * renamed into place (safe_out_commit), or neither. */
static int write_outputs(const render_args *a, const uint8_t *rgb8, const float *rgbf)
{
    char err[512];
    safe_out *o[2] = { NULL, NULL };
    size_t n = a->pfm ? 2 : 1;
    o[0] = safe_out_open(a->out, err, sizeof err);
    if (o[0] && a->pfm)
        o[1] = safe_out_open(a->pfm, err, sizeof err);
    if (!o[0] || (a->pfm && !o[1])) {
        safe_out_abort(o[0]);
        fprintf(stderr, "polarlux render: %s\n", err);
        return EXIT_FAIL;
    }
    if (image_encode_png(o[0], a->out, a->cam.width, a->cam.height, rgb8, 0, err, sizeof err) != 0 ||
        (a->pfm && image_encode_pfm(o[1], a->pfm, a->cam.width, a->cam.height, rgbf, err, sizeof err) != 0)) {
        safe_out_abort(o[0]);
        safe_out_abort(o[1]);
        fprintf(stderr, "polarlux render: %s\n", err);
        return EXIT_FAIL;
    }
    if (safe_out_commit(o, n, err, sizeof err) != 0) {
        fprintf(stderr, "polarlux render: %s\n", err);
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

/* Digits after the point for the scene's coordinates: lon/lat or metres. */
static int coord_digits(plx_engine *e)
{
    plx_scene_info si;
    plx_scene_info_get(e, &si);
    return si.lonlat ? 7 : 1;
}

/* The refinement's centre, in the scene's coordinates as the view line,
 * and what it cached. */
static void print_refinement(plx_engine *e, const plx_camera *cam, const plx_refine_stats *rs)
{
    double cx = rs->centre[0], cy = rs->centre[1], ahead = hypot(cx - cam->eye[0], cy - cam->eye[1]);
    int d = coord_digits(e);
    cli_from_local(e, &cx, &cy);
    printf("refinement: %u lamps near (%.*f, %.*f), %.1f m ahead of the eye, got floor maps (%u cached of %u "
           "slots)\n", rs->misses_now, d, cx, d, cy, ahead, rs->cached, rs->slots);
}

int cmd_render(int argc, char **argv)
{
    render_args a;
    plx_engine *e;
    plx_render_info info;
    uint8_t *rgb8 = NULL;
    float *rgbf = NULL;
    unsigned long long t0;
    plx_status st;
    int prec, had_atlas;
#ifdef PLX_HAVE_OSMESA
    plx_osmesa *om = NULL;
#endif
    int rc = parse_args(argc, argv, &a);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    a.c.render_w = a.cam.width;
    a.c.render_h = a.cam.height;
    a.c.atlas_room = !a.opts.no_indirect && !a.opts.per_pixel;
#ifndef PLX_HAVE_OSMESA
    if (a.osmesa) {
        fprintf(stderr, "polarlux render: this polarlux was built without OSMesa (libosmesa6-dev); "
                        "use --backend soft\n");
        return EXIT_FAIL;
    }
#endif
    /* the outputs tried before the work (a frame of a large city takes
     * seconds; a missing folder was said after them) */
    if (!cli_out_writable("render", a.out) || !cli_out_writable("render", a.pfm))
        return EXIT_FAIL;
    rc = cli_open_scene("render", a.scene, &a.c, &e);
    if (rc != EXIT_OK)
        return rc;
    if (cli_bake_direct("render", a.scene, &a.c, e, &a.ind))
        a.opts.no_indirect = 1;
    cli_bake_kept("render", a.scene, &a.c, e, &a.ind, a.opts.aerial_m_per_texel);
    if (a.have_eye && (cli_option_local("render", "--eye", e, &a.cam.eye[0], &a.cam.eye[1]) != 0 ||
                       cli_option_local("render", "--target", e, &a.cam.target[0], &a.cam.target[1]) != 0)) {
        plx_engine_free(e);
        return EXIT_USAGE;
    }
    if (a.have_eye)
        warn_eye_inside(e, a.cam.eye, a.c.quiet);
    if (!a.have_eye) {
        if (a.aerial) {
            cli_default_aerial(e, &a.cam);
        } else if ((rc = default_street(e, &a.cam)) == -2) {
            fprintf(stderr, "polarlux render: %s: the default street view needs the polar diagrams to find a "
                            "street%s; give --eye and --target, --view aerial, or a larger --mem\n",
                    plx_last_error(e), cli_bake_last.loaded ? ", and this bake was made without them (--no-polar)" : "");
            plx_engine_free(e);
            return EXIT_NOMEM;
        } else if (rc == -3) {
            fprintf(stderr, "polarlux render: %s: the default street view's search for a street ran out of "
                            "memory; give --eye and --target, --view aerial, or a larger --mem\n", plx_last_error(e));
            plx_engine_free(e);
            return EXIT_NOMEM;
        } else if (rc != 0) {
            plx_scene_info si;
            plx_scene_info_get(e, &si);
            if (si.lamps == 0)
                fprintf(stderr, "polarlux render: the scene has no lamps, so the default street view (beside a "
                                "lamp) has nowhere to stand; give --eye and --target, or --view aerial\n");
            else
                fprintf(stderr, "polarlux render: found no free street spot beside a lamp; give --eye and --target\n");
            plx_engine_free(e);
            return EXIT_FAIL;
        }
    }
    {
        /* the photon buffers' levels for a viewer at the scene's centre, as
         * walk and bake lay them out: a walk frame and render at its camera
         * are the same image from a scene too (levels for this camera made
         * them differ by up to 30 of 255 on the Helsinki district) */
        rc = cli_indirect_run("render", &a.c, e, &a.ind, NULL, NULL, a.cam.fov_deg);
        if (rc == EXIT_OK && a.refine && !a.ind.off) {
            cli_refiner rf;
            cli_refiner_init(&rf, a.refine_height, 16, a.ind.photons);
            rc = cli_refine("render", e, &a.cam, &rf);
            if (rc == EXIT_OK && !rf.high)
                print_refinement(e, &a.cam, &rf.rs);
            else if (rc == EXIT_OK)
                cli_warn("render", &a.c, "--refine: the eye is %g m high, above --refine-height %g m, so no lamp "
                         "was refined (munoz2013 refines only low views; a larger --refine-height refines from "
                         "higher up)", a.cam.eye[2], a.refine_height);
        }
        if (rc != EXIT_OK) {
            plx_engine_free(e);
            return rc;
        }
    }
    rgb8 = malloc((size_t)a.cam.width * a.cam.height * 3);
    rgbf = a.pfm ? malloc(sizeof *rgbf * (size_t)a.cam.width * a.cam.height * 3) : NULL;
    if (!rgb8 || (a.pfm && !rgbf)) {
        fprintf(stderr, "polarlux render: out of memory for a %dx%d image\n", a.cam.width, a.cam.height);
        rc = EXIT_FAIL;
        goto done;
    }
#ifdef PLX_HAVE_OSMESA
    if (a.osmesa) {
        char err[256];
        om = plx_osmesa_open(a.cam.width, a.cam.height, err, sizeof err);
        if (!om) {
            fprintf(stderr, "polarlux render: %s\n", err);
            rc = EXIT_FAIL;
            goto done;
        }
        a.opts.backend = plx_osmesa_backend(om);
    }
#endif
    had_atlas = cli_atlas_made(e);
    t0 = port_now_ns();
    st = plx_render(e, &a.cam, &a.opts, rgb8, rgbf, &info);
    t0 = port_now_ns() - t0; /* the frame alone, not the PNG written after it */
    if (st == PLX_OK)
        cli_atlas_note("render", &a.c, e, had_atlas, a.opts.aerial_m_per_texel);
    if (st != PLX_OK) {
        char hint[400];
        fprintf(stderr, "polarlux render: %s%s\n", plx_last_error(e),
                cli_render_nomem_hint(st, &a.opts, e, hint, sizeof hint));
#ifdef PLX_HAVE_OSMESA
        if (om && *plx_osmesa_error(om))
            fprintf(stderr, "polarlux render: osmesa: %s\n", plx_osmesa_error(om));
#endif
        rc = cli_exit_code(st);
        goto done;
    }
    rc = write_outputs(&a, rgb8, rgbf);
    if (rc == EXIT_OK && cli_all_black(rgb8, (size_t)a.cam.width * a.cam.height * 3)) {
        char why[200]; /* rgb8 is written out: cli_black_reason may draw into it */
        cli_warn("render", &a.c, "the image is entirely black: %s",
                 cli_black_reason(e, &a.cam, &a.opts, info.exposure, rgb8, why, sizeof why));
    } else if (rc == EXIT_OK) {
        size_t npx = (size_t)a.cam.width * a.cam.height;
        double share = cli_black_share(rgb8, npx);
        /* the share rounded down: 100.00% would say all */
        if (share >= CLI_NEARLY_BLACK)
            cli_warn("render", &a.c, "the image is nearly black: %.2f%% of its pixels are black (%.0f lit): %s",
                     floor(share * 10000.0) / 100.0, (1.0 - share) * (double)npx, CLI_NEARLY_BLACK_WHY);
        share = cli_white_share(rgb8, npx);
        if (share >= CLI_BLOWN_OUT && (a.opts.auto_exposure == PLX_EXPOSURE_FIXED || a.opts.auto_exposure == PLX_EXPOSURE_TONE)) /* as a black image is said */
            cli_warn("render", &a.c, "the image is blown out: %.0f%% of its lit pixels are full white: --exposure "
                     "%g maps the light above white (without --exposure, automatic exposure chooses one from the "
                     "image)", floor(share * 100.0), a.opts.exposure);
    }
    prec = coord_digits(e);
    cli_from_local(e, &a.cam.eye[0], &a.cam.eye[1]);
    cli_from_local(e, &a.cam.target[0], &a.cam.target[1]);
    if (rc == EXIT_OK)
        printf("%s view %dx%d from (%.*f, %.*f, %.1f) to (%.*f, %.*f, %.1f): drew %u of %u buildings "
               "(%.2f%% of the geometry) in %.1f ms, written to %s\n",
               a.aerial ? "aerial" : "street", a.cam.width, a.cam.height, prec, a.cam.eye[0], prec, a.cam.eye[1],
               a.cam.eye[2], prec, a.cam.target[0], prec, a.cam.target[1], a.cam.target[2], info.drawn, info.buildings,
               100.0 * info.drawn_fraction, t0 / 1e6, a.out);
    /* read from the radiance atlas: no pixel shaded, indirect light not off
     * or per pixel (aerial frames shaded pixel by pixel shade none either:
     * their ground is the aerial light map's), an atlas made */
    if (rc == EXIT_OK && a.aerial && a.have_eye && info.shaded_pixels == 0 && !info.eye_inside && !a.ind.off &&
        !a.opts.no_indirect && !a.opts.per_pixel && cli_atlas_made(e) &&
        !cli_all_black(rgb8, (size_t)a.cam.width * a.cam.height * 3))
        cli_warn("render", &a.c, "--view aerial changed nothing: --eye and --target place the camera, and the "
                 "frame was read from the radiance atlas, the same for any view (--view aerial picks the aerial "
                 "light map for the ground of frames shaded pixel by pixel: --per-pixel, --no-indirect)");
    if (rc == EXIT_OK) {
        cli_aa_warn("render", &a.c, &a.opts, &info);
        cli_aa_print(&a.opts, info.aa_later, (double)a.cam.width * a.cam.height, 1,
                     info.aa_adaptive == PLX_AA_ADAPTIVE, info.aa_adaptive == PLX_AA_DENSE);
    }
    if (rc == EXIT_OK && a.opts.auto_exposure == PLX_EXPOSURE_AUTO && info.exposure == PLX_EXPOSURE_MAX &&
        !cli_all_black(rgb8, (size_t)a.cam.width * a.cam.height * 3))
        cli_warn("render", &a.c, "the view is dark: its lit surfaces are under about 0.001 cd/m^2, where automatic "
                 "exposure stops (at %g; --exposure E brightens it)", PLX_EXPOSURE_MAX);
    if (rc == EXIT_OK && a.opts.auto_exposure == PLX_EXPOSURE_AUTO)
        printf("exposure: %.4g (automatic: a high percentile of the lit surfaces' luminance near white, "
               "tone curve; --exposure 1 for SPEC §5's linear image)\n", info.exposure);
done:
#ifdef PLX_HAVE_OSMESA
    plx_osmesa_close(om);
#endif
    free(rgb8);
    free(rgbf);
    plx_engine_free(e);
    return rc;
}
