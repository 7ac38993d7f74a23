/* polarlux bake SCENE -o city.plxb: everything built once, saved in one file
 * that every command taking a SCENE loads without rebuilding. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "options.h"
#include "port.h"
#include "posix/safe_out.h"

static const char help[] =
    "usage: polarlux bake SCENE -o CITY.plxb [--photons N] [--frames K] [--no-indirect]\n"
    "                     [--no-aerial] [--no-polar] [--texel M] [--max-size WxH]\n"
    "                     [--threads N] [--mem SIZE] [--strict] [--quiet]\n"
    "\n"
    "Loads SCENE (a GeoJSON file; a bake file cannot be baked again) and builds\n"
    "everything queries and frames need: polar diagrams, lamp light, photon\n"
    "buffers with K frames of N photons (levels for a viewer at the centre, all\n"
    "around), the renderer for frames up to --max-size and the radiance atlas:\n"
    "every surface's light (exact direct light, indirect light from the photons)\n"
    "at sample points --texel metres apart, which street and aerial frames read\n"
    "(filled after the photons on --threads workers, with a progress line on a\n"
    "terminal; with --no-indirect the aerial light map of direct light instead);\n"
    "then writes it all to one file. Every other command that takes a SCENE also\n"
    "takes the bake file and starts at once (README 'Bake files'). Prints the\n"
    "file size, the engine memory in use and the times.\n"
    "\n"
    "  -o FILE         the bake file (required)\n"
    "  --photons N     photons per frame (default 16 a lamp, from 65536 to\n"
    "                  1048576: a large city's facades need more)\n"
    "  --frames K      photon frames (default 16: the points' final gathering\n"
    "                  reads them too; 0 bakes as --no-indirect)\n"
    "  --no-indirect   no photon buffers\n"
    "  --no-aerial     no radiance atlas: frames lay it out in the loaded block and\n"
    "                  fill it as they need it (coarser than a full bake's when it\n"
    "                  would take over a quarter of that block: other images)\n"
    "  --no-polar      no polar diagrams: frames do not need them (a bake for a\n"
    "                  walk in a small --mem); queries build them when asked\n"
    "  --texel M       the atlas's spacing between sample points (default 0.5 m,\n"
    "                  coarser until it fits its budget: a quarter of --mem, at\n"
    "                  most 64 MiB; printed); with --no-indirect the aerial light\n"
    "                  map's resolution (default 1 m)\n"
    "  --max-size WxH  the largest frame the loaded engine renders, either way\n"
    "                  round (default 1024x768: 768x1024 frames too)\n"
    "  --threads N     threads for filling the atlas (default: the number of\n"
    "                  processors); the same file for any N\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n"
    "\n"
    "Exit codes: 0 written, 1 the scene or the file failed, 2 usage, 3 --mem too small.\n";

typedef struct bake_args {
    const char *scene, *out;
    cli_common c;
    cli_indirect ind;
    plx_bake_opts o;
    int frames0;    /* --frames 0: baked as with --no-indirect */
} bake_args;

static int parse_texel(const char *v, void *dst)
{
    return cli_parse_real(v, 0.01, 1e4, dst); /* render's and walk's range */
}

static int parse_args(int argc, char **argv, bake_args *a)
{
    long size[2] = { 1024, 768 };
    int no_aerial = 0, rc;
    const cli_opt opts[] = {
        CLI_OPT_FLAG("--no-aerial", &no_aerial),
        CLI_OPT_FLAG("--no-polar", &a->o.no_polar),
        CLI_OPT_STR("-o", &a->out),
        CLI_OPT_VAL("--texel", &a->o.aerial_m_per_texel, parse_texel, "--texel '%s' is not a number of metres from 0.01 to 1e4"),
        CLI_OPT_VAL("--max-size", size, cli_opt_size, "--max-size '%s' is not WxH (1..8192 each)"),
        CLI_OPT_END
    };
    cli_args pa;
    memset(a, 0, sizeof *a);
    cli_indirect_default(&a->ind);
    a->ind.per_lamp = 1;
    a->ind.frames = CLI_GATHER_FRAMES; /* illum on the bake gathers over them */
    rc = cli_options_n("bake", help, argc, argv, opts, &a->c, &a->ind, 1, NULL, &pa);
    if (rc != EXIT_OK)
        return rc;
    a->scene = pa.npos ? pa.pos[0] : NULL;
    a->o.aerial = !no_aerial;
    a->c.render_w = (int)size[0];
    a->c.render_h = (int)size[1];
    if (!a->scene)
        return cli_usage_error("bake", "missing SCENE");
    if (!a->out)
        return cli_usage_error("bake", "missing -o CITY.plxb");
    if (cli_is_bake(a->scene)) { /* its scene is the loader's result, not the file it came from */
        fprintf(stderr,
                "polarlux bake: %s is a bake file, not a GeoJSON scene: bake the scene it was made from "
                "again with the options you want\n",
                a->scene);
        return EXIT_USAGE;
    }
    /* no photon frames: a bake as with --no-indirect (the photon buffers
     * and a radiance atlas of direct light were built and saved, and
     * frames, having no indirect light, shaded every pixel instead) */
    a->frames0 = !a->ind.off && a->ind.frames == 0;
    a->ind.off |= a->frames0;
    a->o.no_indirect = a->ind.off;
    return EXIT_OK;
}

/* An engine in a zeroed block (calloc: the twin's sits alike modulo 64),
 * with the scene loaded. */
static int load_engine(const bake_args *a, int twin, plx_engine **e)
{
    size_t mem = a->c.mem ? a->c.mem : CLI_DEFAULT_MEM;
    plx_config cfg;
    void *block;
    plx_status st;
    *e = NULL;
    /* zeros (calloc of a large block takes fresh pages, nothing written):
     * the bake saves every byte of the arena's used end, padding and
     * never-written bytes included, which must be defined */
    if (!(block = calloc(1, mem))) {
        fprintf(stderr, "polarlux bake: cannot take a block of %zu bytes\n", mem);
        return EXIT_NOMEM;
    }
    cli_config(&a->c, &cfg);
    if (twin) {
        static plx_port silent;
        silent = *cfg.port;
        silent.log = NULL; /* the twin's warnings were printed once already */
        silent.progress = NULL;
        cfg.port = &silent;
    }
    st = plx_engine_create(block, mem, &cfg, e);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux bake: cannot create an engine of %zu bytes: %s\n", mem, plx_strerror(st));
        free(block);
        return cli_exit_code(st);
    }
    if (twin) { /* the command's own notes too (no lamps, ...) */
        cli_common quiet = a->c;
        quiet.quiet = 1;
        return cli_load_scene("bake", a->scene, &quiet, e);
    }
    return cli_load_scene("bake", a->scene, &a->c, e);
}

/* Whether the renderer's frame buffers (20 bytes a pixel of --max-size)
 * take an eighth of the block or more: only then does a smaller
 * --max-size free much (at 16x16 it was still offered). */
static int frame_share(const bake_args *a)
{
    size_t mem = a->c.mem ? a->c.mem : CLI_DEFAULT_MEM;
    return 20.0 * a->c.render_w * a->c.render_h >= mem / 8.0;
}

/* The options not given yet that need less memory at the stage that ran
 * out (why: the engine's message), into buf as "--a, --b or --c"; returns
 * how many (0: buf empty). The stages in order: polar diagrams, lamp light, photon
 * buffers, renderer, radiance atlas; an option helps at its own stage and
 * the later ones: --no-polar after the polar diagrams' own, --no-indirect
 * (no photon buffers) from theirs on, a smaller --max-size where the
 * renderer's frame buffers count (the photon buffers' budget is what the
 * renderer leaves; not the renderer's scratch, which the city sizes;
 * only when the frame buffers are a large share, frame_share), and
 * --no-aerial or a coarser --texel at the atlas. */
static int nomem_options(const bake_args *a, const char *why, char *buf, size_t len)
{
    const char *o[5];
    int n = 0, k, atlas = strstr(why, "radiance atlas") != NULL;
    int photons = strstr(why, "photon buffers") != NULL, renderer = strstr(why, "renderer") != NULL;
    if (atlas && a->o.aerial)
        o[n++] = "--no-aerial";
    if (!a->o.no_polar)
        o[n++] = "--no-polar";
    if ((photons || renderer || atlas) && !a->o.no_indirect)
        o[n++] = "--no-indirect";
    if ((photons || atlas || (renderer && !strstr(why, "part 'scratch'"))) && frame_share(a))
        o[n++] = "a smaller --max-size";
    if (atlas && a->o.aerial)
        o[n++] = "a coarser --texel";
    buf[0] = '\0';
    for (k = 0; k < n; k++) {
        size_t u = strlen(buf);
        snprintf(buf + u, len - u, "%s%s", k == 0 ? "" : k == n - 1 ? " or " : ", ", o[k]);
    }
    return n;
}

/* Everything prepared (plx_bake_prepare); a failure's line goes to err
 * (the twin's is printed only when the engine itself did not fail). */
static int prepare_engine(const bake_args *a, int twin, plx_engine **e, char *err, size_t errlen)
{
    plx_bake_opts o = a->o;
    plx_status st;
    o.twin = twin;
    st = plx_bake_prepare(*e, &o);
    if (st == PLX_OK)
        return EXIT_OK;
    if (st == PLX_E_NOMEM) { /* what would need less, of the options not given yet, at the stage that failed */
        const char *why = plx_last_error(*e);
        char opts[160];
        int n = nomem_options(a, why, opts, sizeof opts);
        if (n == 0)
            snprintf(err, errlen, "polarlux bake: %s (give a larger --mem)\n", why);
        else
            snprintf(err, errlen, "polarlux bake: %s (%s need%s less; or give a larger --mem)\n", why, opts,
                     n > 1 ? "" : "s");
    } else
        snprintf(err, errlen, "polarlux bake: %s\n", plx_last_error(*e));
    plx_engine_free(*e);
    *e = NULL;
    return st == PLX_E_NOMEM ? EXIT_NOMEM : EXIT_FAIL;
}

/* The twin, prepared on a thread of its own while the engine builds and
 * traces its photons (with more than one thread: they do not depend on
 * each other, and the twin's work is the engine's again). */
typedef struct twin_job {
    const bake_args *a;
    plx_engine *t;
    int rc;
    char err[512];
} twin_job;

static void *twin_prepare(void *p)
{
    twin_job *j = p;
    j->rc = prepare_engine(j->a, 1, &j->t, j->err, sizeof j->err);
    return NULL;
}

static int save(const bake_args *a, plx_engine *e, plx_engine *t, size_t *bytes)
{
    char err[512];
    void *buf;
    plx_status st = plx_bake_size(e, t, bytes);
    if (st == PLX_OK) {
        buf = malloc(*bytes);
        if (!buf) {
            fprintf(stderr, "polarlux bake: out of memory for a %zu-byte file\n", *bytes);
            return EXIT_FAIL;
        }
        st = plx_bake_save(e, t, buf, *bytes, bytes);
        if (st == PLX_OK && port_write_atomic(a->out, buf, *bytes, err, sizeof err) != 0) {
            fprintf(stderr, "polarlux bake: %s\n", err);
            free(buf);
            return EXIT_FAIL;
        }
        free(buf);
    }
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux bake: %s\n", plx_last_error(e));
        return EXIT_FAIL;
    }
    return EXIT_OK;
}

/* A word on stderr when --texel asked for finer points than the atlas
 * has (its budget, a quarter of --mem at most 64 MiB, took coarser ones;
 * said on stdout only, among the bake's figures). */
static void coarser_note(const bake_args *a, plx_engine *e)
{
    plx_atlas_info ai;
    double asked = a->o.aerial_m_per_texel;
    if (asked <= 0.0 || plx_atlas_info_get(e, &ai) != PLX_OK || !ai.made || !(ai.spacing > asked * 1.0001))
        return;
    cli_warn("bake", &a->c, "--texel %g: the radiance atlas's points are %.2f m apart, the finest that fits its "
             "budget (a quarter of --mem, at most 64 MiB)%s", asked, ai.spacing,
             a->c.mem && a->c.mem / 4 < PLX_ATLAS_MAX_BYTES ? "; a larger --mem fits finer ones" : "");
}

int cmd_bake(int argc, char **argv)
{
    bake_args a;
    plx_engine *e = NULL, *t = NULL;
    plx_memory_report m;
    unsigned long long t0 = port_now_ns(), t1, t2;
    char err[512];
    twin_job tj;
    pthread_t th;
    int alongside;
    size_t bytes = 0;
    int rc = parse_args(argc, argv, &a);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (!cli_out_writable("bake", a.out))
        return EXIT_FAIL;
    tj.a = &a;
    tj.t = NULL;
    tj.rc = EXIT_FAIL;
    tj.err[0] = '\0';
    rc = load_engine(&a, 0, &e);
    if (rc == EXIT_OK)
        rc = load_engine(&a, 1, &tj.t);
    alongside = rc == EXIT_OK && a.c.threads != 1 && pthread_create(&th, NULL, twin_prepare, &tj) == 0;
    if (rc == EXIT_OK && (rc = prepare_engine(&a, 0, &e, err, sizeof err)) != EXIT_OK)
        fputs(err, stderr);
    t1 = port_now_ns();
    if (rc == EXIT_OK) {
        rc = cli_indirect_run("bake", &a.c, e, &a.ind, NULL, NULL, 60.0);
    }
    t2 = port_now_ns();
    if (alongside)
        pthread_join(th, NULL);
    else if (rc == EXIT_OK)
        twin_prepare(&tj);
    t = tj.t;
    if (rc == EXIT_OK && tj.rc != EXIT_OK) {
        fputs(tj.err, stderr);
        rc = tj.rc;
    }
    if (rc == EXIT_OK)
        rc = save(&a, e, t, &bytes);
    if (rc == EXIT_OK) {
        plx_memory_get(e, &m);
        printf("baked %s into %s: %zu bytes (%.1f MiB); engine memory in use %zu bytes (%.1f MiB)\n", a.scene,
               a.out, bytes, bytes / 1048576.0, m.used_total, m.used_total / 1048576.0);
        cli_atlas_print(e);
        coarser_note(&a, e);
        char ph[96];
        if (a.ind.off)
            snprintf(ph, sizeof ph, "no photons (%s)", a.frames0 ? "--frames 0: as --no-indirect" : "--no-indirect");
        else if (plx_indirect_frames(e) == 0 && !cli_has_lamps(e))
            snprintf(ph, sizeof ph, "no photons (no lamps to trace from)");
        else
            snprintf(ph, sizeof ph, "photons %.0f ms (%ld x %ld)", (t2 - t1) / 1e6, a.ind.frames,
                     cli_photons(e, &a.ind));
        printf("times: load and build %.0f ms, %s, %s %.0f ms, total %.2f s\n", (t1 - t0) / 1e6, ph,
               cli_atlas_made(e) ? "radiance atlas, twin and save" /* not with --no-aerial or --no-indirect */ : "twin and save", (port_now_ns() - t2) / 1e6,
               (port_now_ns() - t0) / 1e9);
    }
    plx_engine_free(t);
    plx_engine_free(e);
    return rc;
}
