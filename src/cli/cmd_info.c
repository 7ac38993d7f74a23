/* polarlux info SCENE: counts, bounds, heights, skipped features, load time
 * and memory per part. */
#include <stdlib.h>
#include <string.h>
#include "cli.h"
#include "options.h"
#include "port.h"

static const char help[] =
    "usage: polarlux info SCENE [--mem SIZE] [--strict] [--quiet] [--lamps FILE]... [--min-mem]\n"
    "                     [--photons]\n"
    "\n"
    "Loads SCENE (GeoJSON, see README 'Scene format') and prints counts of\n"
    "buildings, blocks, courtyards, lamps and vertices, the bounds, building\n"
    "heights (min/median/max), the ground albedo and ground image (path,\n"
    "size, bounds, mean albedo), skipped features, the load time, the polar\n"
    "diagrams (build time, memory by part) and the memory used per part with\n"
    "the high-water mark.\n"
    "\n"
    "  --mem SIZE   memory budget of the engine (default 1G; e.g. 256M)\n"
    "  --strict     the first bad feature is an error (default: skip and report)\n"
    "  --quiet      no warnings on stderr (skipped features, and every other\n"
    "               command's warnings too); errors are still printed\n"
    "  --lamps FILE add the lamps of another file to the scene (repeatable):\n"
    "               GeoJSON Points (each a lamp unless \"lamp\": false; when some\n"
    "               carry \"lamp\": true or highway=street_lamp, only those) with\n"
    "               the scene's lamp properties, or CSV with a header naming x,y\n"
    "               or lon,lat columns and optionally z, intensity, radius, id.\n"
    "               Positions in the scene's coordinates (lon/lat on a lon/lat\n"
    "               scene, metres on a metre scene; a '# crs: NAME' line or a\n"
    "               GeoJSON crs must match the scene's). Lamps inside buildings\n"
    "               are left out and lamps at an earlier lamp's position merged,\n"
    "               each with a warning.\n"
    "  --min-mem    also find the smallest --mem that loads SCENE (the file alone)\n"
    "               and builds its polar diagrams, by bisection over loads (to\n"
    "               4 KiB; about 18 loads), and print it; for a bake file, the\n"
    "               smallest block its image loads in (polar diagrams built\n"
    "               there if it has none, and then also the smallest for frames\n"
    "               without them), beside the block it takes without --mem\n"
    "               (room for queries), and the smallest that draws the whole\n"
    "               scene from above at its largest frame with walk's default\n"
    "               2 x 2 adaptive samples (a frame drawn at each step)\n"
    "  --photons    also create the photon buffers (no photons traced) and print\n"
    "               the sizes chosen at this --mem: bytes, the default quality's\n"
    "               bytes, the budget, the quality steps taken to fit it, chart\n"
    "               and aerial texels, lamp floor maps, lamp ray tables\n";

static void silent_log(void *ctx, plx_log_level level, const char *msg)
{
    (void)ctx, (void)level, (void)msg;
}

/* The bisection's engines: the default config through the POSIX port
 * without its log (port must outlive the engine). */
static void silent_config(plx_config *cfg, plx_port *port)
{
    plx_config_default(cfg);
    *port = *plx_port_posix();
    port->log = silent_log;
    cfg->port = port;
}

/* 1 when an engine of 'bytes' loads the scene and builds its polar diagrams. */
static int fits(const char *path, const cli_common *c, size_t bytes)
{
    static plx_port port;
    plx_config cfg;
    plx_engine *e;
    plx_polar_info pi;
    int ok;
    silent_config(&cfg, &port);
    cfg.strict = c->strict;
    if (plx_engine_new(bytes, &cfg, &e) != PLX_OK)
        return 0;
    ok = plx_load_file(e, path) == PLX_OK && plx_polar_info_get(e, &pi) == PLX_OK;
    plx_engine_free(e);
    return ok;
}

/* The smallest budget that fits, by bisection between the engine minimum
 * and 'hi' (known to fit), to 4 KiB; the load's memory use does not depend
 * on the budget, so fitting is monotonic. */
static void print_min_mem(const char *path, const cli_common *c, size_t hi)
{
    size_t lo = PLX_ENGINE_MIN_BYTES; /* does not fit (or is the minimum) */
    int loads = 0;
    while (hi - lo > 4096) {
        size_t mid = lo + (hi - lo) / 2;
        loads++;
        if (fits(path, c, mid))
            hi = mid;
        else
            lo = mid;
    }
    printf("smallest --mem: %zu bytes (%.2f MiB) loads the scene and builds its polar diagrams "
           "(bisection, %d loads; a ground image needs its pixels on top)\n", hi, hi / 1048576.0, loads);
}

/* What a bisection over bake loads asks of each block: the load alone,
 * the polar diagrams too (built for a --no-polar bake, as info does), or
 * a frame as walk draws it by default. */
enum { BAKE_LOADS = 0, BAKE_POLAR, BAKE_FRAME };

/* One frame as walk draws them by default (2 x 2 samples, adaptive, its
 * buffers in the block; automatic exposure; fov 60) at the engine's largest size, the whole
 * scene from above (render --view aerial's camera: every chart or the
 * most of them read), into rgb8 (3 bytes a pixel of that size). */
static int frame_fits(plx_engine *e, uint8_t *rgb8)
{
    plx_camera cam;
    plx_render_opts o;
    plx_render_info ri;
    memset(&cam, 0, sizeof cam);
    if (!rgb8 || plx_render_max_get(e, &cam.width, &cam.height) != PLX_OK)
        return 0;
    cam.fov_deg = 60.0;
    cli_default_aerial(e, &cam);
    plx_render_opts_default(&o);
    o.auto_exposure = PLX_EXPOSURE_AUTO;
    o.aa = 2;
    /* with room for the adaptive buffers (without, every sample is
     * taken: PLX_AA_EVERY, slower) */
    return plx_render(e, &cam, &o, rgb8, NULL, &ri) == PLX_OK && ri.aa_adaptive != PLX_AA_EVERY;
}

/* 1 when the block 'mem', given as 'bytes' long, loads the bake and does
 * 'what' (BAKE_*; a frame into rgb8). The block is aligned as the
 * command's (cli_big_alloc), which the bake's offset in it depends on. */
static int bake_fits(void *mem, size_t bytes, const void *data, size_t len, int what, uint8_t *rgb8)
{
    static plx_port port;
    plx_config cfg;
    plx_engine *e;
    plx_polar_info pi;
    int ok = 1;
    silent_config(&cfg, &port);
    if (plx_bake_load(mem, bytes, &cfg, data, len, &e, NULL, 0) != PLX_OK)
        return 0;
    if (what == BAKE_POLAR)
        ok = plx_polar_info_get(e, &pi) == PLX_OK;
    else if (what == BAKE_FRAME)
        ok = frame_fits(e, rgb8);
    plx_engine_destroy(e);
    return ok;
}

/* A bake's --min-mem search: its loads counted against the most it can
 * take, on a progress line (a terminal's, after a second: a city's search
 * takes 7 to 11 s). */
typedef struct min_search {
    int loads, most;
    cli_progress pg;
} min_search;

static void search_load(min_search *ms)
{
    ms->loads++;
    cli_progress_step(&ms->pg, "info --min-mem: bisection over loads", (size_t)ms->loads, (size_t)ms->most);
}

/* Bisection steps over hi - lo bytes to 4 KiB. */
static int steps_over(size_t lo, size_t hi)
{
    int n = 0;
    for (; hi - lo > 4096; hi = lo + (hi - lo) / 2)
        n++;
    return n;
}

/* The smallest block from lo to hi, to 4 KiB, that bake_fits 'what', by
 * bisection; loads counted. */
static size_t bisect_bake(void *mem, size_t lo, size_t hi, const void *data, size_t len, int what, uint8_t *rgb8,
                          min_search *ms)
{
    while (hi - lo > 4096) {
        size_t mid = lo + (hi - lo) / 2;
        search_load(ms);
        if (bake_fits(mem, mid, data, len, what, rgb8))
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

/* The smallest block for walk's frames (frame_fits) from lo (the load's
 * smallest) up to hi, and the frame's size (*w, *h, the bake's largest);
 * 0 when hi holds none. */
static size_t frames_min(void *mem, size_t lo, size_t hi, const void *data, size_t len, min_search *ms, int32_t *w,
                         int32_t *h)
{
    static plx_port port;
    plx_config cfg;
    plx_engine *e;
    uint8_t *rgb8 = NULL;
    size_t f = 0;
    silent_config(&cfg, &port);
    if (plx_bake_load(mem, hi, &cfg, data, len, &e, NULL, 0) != PLX_OK)
        return 0;
    if (plx_render_max_get(e, w, h) == PLX_OK)
        rgb8 = malloc((size_t)*w * (size_t)*h * 3);
    plx_engine_destroy(e);
    search_load(ms);
    if (rgb8 && bake_fits(mem, hi, data, len, BAKE_FRAME, rgb8))
        f = bisect_bake(mem, lo, hi, data, len, BAKE_FRAME, rgb8, ms);
    free(rgb8);
    return f;
}

/* For a bake, the smallest --mem is the block its image loads in (the
 * bake's block size adds room for queries and frames): the same bisection,
 * over bake loads into one block of 'hi' bytes (0: the bake's own size);
 * for a bake without polar diagrams (has_polar 0) also the smallest
 * without building them. */
static int print_min_mem_bake(const char *path, size_t hi, int has_polar)
{
    char err[512];
    size_t len, own, lo = PLX_ENGINE_MIN_BYTES;
    char *data = port_read_text(path, &len, err, sizeof err);
    void *mem = NULL;
    int rc = EXIT_FAIL, polar = has_polar;
    min_search ms;
    int32_t fw = 0, fh = 0;
    size_t alone = 0, top, frames;
    if (data && plx_bake_block_size(data, len, &own, err, sizeof err) == PLX_OK) {
        if (!hi)
            hi = own;
        if (!(mem = cli_big_alloc(hi))) {
            snprintf(err, sizeof err, "cannot take a block of %zu bytes", hi);
            rc = EXIT_NOMEM;
        }
    }
    if (!mem) {
        fprintf(stderr, "polarlux info: %s: --min-mem: %s\n", path, err);
        free(data);
        return rc;
    }
    top = hi;
    ms.loads = 0;
    ms.most = steps_over(lo, top) * (polar ? 2 : 3) + 1;
    cli_progress_start(&ms.pg);
    hi = bisect_bake(mem, lo, hi, data, len, BAKE_POLAR, NULL, &ms);
    if (!polar)
        alone = bisect_bake(mem, lo, hi, data, len, BAKE_LOADS, NULL, &ms);
    frames = frames_min(mem, polar ? hi : alone, top, data, len, &ms, &fw, &fh);
    cli_progress_step(&ms.pg, "info --min-mem: bisection over loads", 1, 1);
    cli_progress_end(&ms.pg);
    free(mem);
    free(data);
    printf("smallest --mem: %zu bytes (%.2f MiB) loads the bake and has its polar diagrams%s (bisection, %d loads; "
           "without --mem a bake takes %zu bytes (%.2f MiB), room for queries and frames)\n", hi, hi / 1048576.0,
           polar ? "" : " (built, as info does)", ms.loads, own, own / 1048576.0);
    if (!polar)
        printf("smallest --mem for frames: %zu bytes (%.2f MiB) loads the bake, made with --no-polar, without them "
               "(walk and render with --eye, --aa 1; anti-aliasing adds 20 bytes a pixel; at the smallest, frames "
               "can be several times slower: the lamps' lit regions, the irradiance cache and the radiance atlas "
               "take what is free beyond it)\n", alone, alone / 1048576.0);
    if (frames)
        printf("smallest --mem for frames from above: %zu bytes (%.2f MiB) loads the bake and draws the whole "
               "scene from above in a %dx%d frame (its largest) with walk's default 2 x 2 samples, adaptive "
               "(bisection, as above; street views and --aa 1 may need less; walk's own frame buffers, 3 bytes a "
               "pixel of its --size, and its contact sheet take what --mem leaves beside)\n",
               frames, frames / 1048576.0, fw, fh);
    else if (fw > 0 && fh > 0)
        printf("smallest --mem for frames from above: not found: a %dx%d frame of the whole scene with 2 x 2 "
               "samples does not fit in %zu bytes\n", fw, fh, top);
    else
        printf("smallest --mem for frames from above: not found: the bake did not load in %zu bytes to ask its "
               "largest frame\n", top);
    return EXIT_OK;
}

/* The photon buffers at this budget (created when missing). */
static int print_photons(plx_engine *e, const char *path, const plx_scene_info *si)
{
    double eye[3];
    plx_indirect_info pi;
    plx_status st;
    eye[0] = 0.5 * (si->bounds[0] + si->bounds[2]);
    eye[1] = 0.5 * (si->bounds[1] + si->bounds[3]);
    eye[2] = 1.7;
    st = plx_indirect_info_get(e, &pi);
    if (st == PLX_E_NOSCENE) {
        st = plx_indirect_set_viewer(e, eye, NULL, 360.0);
        if (st == PLX_OK)
            st = plx_indirect_info_get(e, &pi);
    }
    if (st != PLX_OK) {
        printf("photon buffers: not created: %s\n", plx_last_error(e));
        fprintf(stderr, "polarlux info: %s: photon buffers not created: %s\n", path, plx_last_error(e));
        return cli_exit_code(st);
    }
    /* a bake's buffers were sized in the block it was baked in, not this one */
    printf("photon buffers: %zu bytes (default quality %zu, budget %zu%s): %u quality steps; facade charts %ux%u, "
           "aerial chart %ux%u texels of %.2f m, %u lamp floor maps, lamp ray tables %s\n",
           pi.bytes, pi.full_bytes, pi.budget, cli_bake_last.loaded ? " when baked" : "", pi.reductions, pi.chart_w,
           pi.chart_h, pi.aerial_w, pi.aerial_h, pi.aerial_texel, pi.lamp_slots, pi.lamp_tables ? "on" : "off");
    return EXIT_OK;
}

static void print_memory(const plx_engine *e)
{
    plx_memory_report m;
    int p;
    plx_memory_get(e, &m);
    printf("memory: %zu bytes in use, peak %zu, of the block's %zu usable bytes\n", m.used_total, m.peak_total,
           m.capacity);
    for (p = 0; p < PLX_PART_COUNT; p++)
        printf("  %-8s %12zu bytes  (peak %zu)\n", plx_part_name((plx_part)p), m.used[p], m.peak[p]);
}

/* One line per photometry file the lamps name (SPEC §2.1). */
static void print_photometry(plx_engine *e, uint32_t nlamps)
{
    uint32_t k, n = plx_photometry_count(e), l;
    for (k = 0; k < n; k++) {
        const char *p;
        plx_lamp_photometry ph;
        uint32_t used = 0, first = 0;
        if (plx_photometry_path(e, k, &p) != PLX_OK)
            return;
        for (l = 0; l < nlamps; l++)
            if (plx_lamp_photometry_get(e, l, &ph) == PLX_OK && ph.path && strcmp(ph.path, p) == 0 && !used++)
                first = l;
        plx_lamp_photometry_get(e, first, &ph);
        printf("photometry: %s (%s) for %u lamp%s; lamp %u: peak %.1f cd, flux %.1f lm, dark from gamma %.1f deg\n",
               p, ph.format == 1 ? "IES" : "EULUMDAT", used, used == 1 ? "" : "s", first, ph.peak_cd, ph.flux_lm, ph.gamma_lit);
    }
}

int cmd_info(int argc, char **argv)
{
    cli_common c;
    const char *path = NULL;
    plx_engine *e;
    plx_scene_info si;
    plx_polar_info pi;
    plx_ground_image_info gi;
    int rc, min_mem = 0, photons = 0, polar_baked = 0;
    const cli_opt opts[] = { CLI_OPT_FLAG("--min-mem", &min_mem), CLI_OPT_FLAG("--photons", &photons), CLI_OPT_END };
    cli_args pa;
    memset(&c, 0, sizeof c);
    rc = cli_options_n("info", help, argc, argv, opts, &c, NULL, 1, "one scene at a time ('%2$s' and '%1$s')", &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    path = pa.npos ? pa.pos[0] : NULL;
    if (!path)
        return cli_usage_error("info", "missing SCENE");
    rc = cli_open_scene("info", path, &c, &e);
    if (rc != EXIT_OK)
        return rc;
    plx_scene_info_get(e, &si);
    printf("scene: %s\n", path);
    printf("buildings: %u (%u raised above the ground; %u inner rings of their own)\n", si.buildings,
           si.raised, si.holes);
    printf("blocks: %u with %u courtyards\n", si.blocks, si.courtyards);
    printf("lamps: %u\n", si.lamps);
    if (plx_scene_crs(e))
        printf("crs: %s\n", plx_scene_crs(e));
    printf("vertices: %u\n", si.vertices);
    printf("skipped: %u features, %u lamps inside buildings\n", si.skipped_features, si.skipped_lamps);
    if (si.merged_lamps)
        printf("duplicate lamps: %u merged into lamps at the same spot\n", si.merged_lamps);
    printf("overlapping pairs: %u\n", si.overlapping_pairs);
    if (si.lonlat && plx_scene_crs(e)) /* a geographic crs of its own (ETRS89, NAD83, ...) */
        printf("coordinates: lon/lat (%s), projected about lon0 %.7f lat0 %.7f\n", plx_scene_crs(e), si.lon0,
               si.lat0);
    else if (si.lonlat)
        printf("coordinates: WGS84 lon/lat, projected about lon0 %.7f lat0 %.7f\n", si.lon0, si.lat0);
    else
        printf("coordinates: local metres\n");
    printf("bounds: %.3f %.3f %.3f %.3f (%.1f x %.1f m)\n", si.bounds[0], si.bounds[1],
           si.bounds[2], si.bounds[3], si.bounds[2] - si.bounds[0], si.bounds[3] - si.bounds[1]);
    printf("heights: min %.2f median %.2f max %.2f m\n", si.height_min, si.height_median, si.height_max);
    printf("ground albedo: %.3f\n", si.ground_albedo);
    if (plx_ground_image_get(e, &gi) == PLX_OK && gi.width > 0)
        printf("ground image: %s (%ux%u pixels) over %.3f %.3f %.3f %.3f%s; mean albedo %.4f %.4f %.4f"
               " (luminance %.4f)\n", gi.path ? gi.path : "(set by the caller)", gi.width, gi.height,
               gi.bounds[0], gi.bounds[1], gi.bounds[2], gi.bounds[3],
               gi.bounds_given ? "" : " (the bounds)", gi.mean_albedo[0], gi.mean_albedo[1],
               gi.mean_albedo[2], gi.mean_luminance);
    print_photometry(e, si.lamps);
    if (!cli_bake_last.loaded) /* a bake's line below says how long it took */
        printf("load time: %.2f ms\n", si.load_ns / 1e6);
    if (cli_bake_last.loaded)
        printf("bake: %zu bytes (%.1f MiB) loaded in %.2f ms (read, check, copy, relocate)\n", cli_bake_last.bytes,
               cli_bake_last.bytes / 1048576.0, cli_bake_last.load_ns / 1e6);
    if (cli_bake_last.loaded) {
        int32_t w = 0, h = 0;
        plx_render_max_get(e, &w, &h);
        printf("largest frame: %dx%d (either way round; bake --max-size), render and walk draw up to it\n", w, h);
    }
    cli_atlas_print(e);
    if (plx_polar_info_get(e, &pi) == PLX_OK) {
        polar_baked = pi.build_ns == 0 && cli_bake_last.loaded;
        if (polar_baked)
            printf("polar diagrams: from the bake; ");
        else
            printf("polar diagrams: built in %.2f ms; ", pi.build_ns / 1e6);
        printf("%zu bytes = axes %zu + regions %zu + polygons %zu + rest (search DAGs) %zu"
               " (%.1f bytes per footprint vertex); regions per quadrant %u %u %u %u\n",
               pi.total, pi.axes, pi.regions, pi.polygons, pi.rest,
               pi.vertices ? (double)pi.total / pi.vertices : 0.0, pi.nregions[0], pi.nregions[1],
               pi.nregions[2], pi.nregions[3]);
    } else {
        printf("polar diagrams: not built: %s\n", plx_last_error(e));
        fprintf(stderr, "polarlux info: %s: polar diagrams not built: %s\n", path, plx_last_error(e));
        rc = plx_last_error(e)[0] && strstr(plx_last_error(e), "out of memory") ? EXIT_NOMEM : EXIT_FAIL;
    }
    /* a bake's photon buffers are its own (no budget to try): said always */
    if ((photons || (cli_bake_last.loaded && plx_indirect_frames(e) > 0)) && rc == EXIT_OK && si.lamps > 0)
        rc = print_photons(e, path, &si);
    print_memory(e);
    plx_engine_free(e);
    if (min_mem && rc == EXIT_OK && cli_bake_last.loaded)
        rc = print_min_mem_bake(path, c.mem, polar_baked);
    else if (min_mem && rc == EXIT_OK)
        print_min_mem(path, &c, c.mem ? c.mem : CLI_DEFAULT_MEM);
    return rc;
}
