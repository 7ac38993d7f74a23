/* options: the one option loop of the commands (see options.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "options.h"

#define STR_(x) #x
#define STR(x) STR_(x)

int cli_opt_double(const char *value, void *dst)
{
    return cli_parse_double(value, dst);
}

int cli_opt_height(const char *value, void *dst)
{
    double *h = dst;
    return cli_parse_double(value, h) != 0 || !(*h >= 0) || !(*h <= 1000) ? -1 : 0;
}

int cli_opt_facing(const char *value, void *dst)
{
    heat_quantity *q = dst;
    q->facing_min = strcmp(value, "min") == 0;
    return !q->facing_min && (cli_parse_double(value, &q->facing) != 0 || !isfinite(q->facing)) ? -1 : 0;
}

static const cli_opt *find_opt(const cli_opt *opts, const char *a)
{
    for (; opts && (opts->name || opts->more); opts++) {
        if (!opts->name) {
            const cli_opt *o = find_opt(opts->more, a);
            if (o)
                return o;
        } else if (strcmp(a, opts->name) == 0 || (opts->alt && strcmp(a, opts->alt) == 0)) {
            return opts;
        }
    }
    return NULL;
}

/* One table option at argv[*i]; EXIT_OK or EXIT_USAGE. */
static int take_opt(const char *cmd, int argc, char **argv, int *i, const cli_opt *o)
{
    const char *a = argv[*i];
    int r;
    if (o->given)
        *o->given = 1;
    if (o->flag) {
        *(int *)o->dst = 1;
        return EXIT_OK;
    }
    if (*i + 1 >= argc)
        return o->need ? cli_usage_error(cmd, "%s", o->need) : cli_usage_error(cmd, "%s needs a value", a);
    ++*i;
    if (!o->parse) {
        *(const char **)o->dst = argv[*i];
        return EXIT_OK;
    }
    r = o->parse(argv[*i], o->dst);
    if (r == -2)
        return EXIT_USAGE;
    if (r != 0)
        return cli_usage_error(cmd, o->bad, argv[*i]);
    return EXIT_OK;
}

/* ---- outputs that would replace an input -------------------------------- */

/* Whether option name n names an output file. */
static int output_opt(const char *n)
{
    return strcmp(n, "-o") == 0 || strcmp(n, "--pfm") == 0 || strcmp(n, "--geojson") == 0 || strcmp(n, "--csv") == 0;
}

/* Whether option name n names an input file (the other string options
 * keep points or ids: network's --from and --to, lit's --lamp). */
static int input_opt(const char *n)
{
    return strcmp(n, "--path") == 0 || strcmp(n, "--points") == 0 || strcmp(n, "--network") == 0 ||
           strcmp(n, "--lamps") == 0 || strcmp(n, "the input") == 0;
}

/* Whether paths a and b are one existing regular file (the same device
 * and inode: also through a link or another spelling of the path). */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && S_ISREG(sa.st_mode) && S_ISREG(sb.st_mode) &&
           sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* Path p's folder, as stat takes it, in buf (n bytes), and its last
 * part; 0 when the path is too long for buf. */
static int split_path(const char *p, char *buf, size_t n, const char **base)
{
    const char *slash = strrchr(p, '/');
    size_t d;
    if (!slash) {
        *base = p;
        return snprintf(buf, n, ".") > 0;
    }
    *base = slash + 1;
    d = slash == p ? 1 : (size_t)(slash - p);
    if (d + 1 > n)
        return 0;
    memcpy(buf, p, d);
    buf[d] = '\0';
    return 1;
}

/* Whether outputs a and b are one file: the same existing file, or, not
 * there yet, the same name in the same folder (another spelling of the
 * folder too: './a.png' and 'a.png'). */
static int same_output(const char *a, const char *b)
{
    char da[4096], db[4096];
    const char *ba, *bb;
    struct stat sa, sb;
    if (strcmp(a, b) == 0 || same_file(a, b))
        return 1;
    if (stat(a, &sa) == 0 || stat(b, &sb) == 0) /* one is there: same_file said no */
        return 0;
    return split_path(a, da, sizeof da, &ba) && split_path(b, db, sizeof db, &bb) && strcmp(ba, bb) == 0 &&
           ba[0] != '\0' && stat(da, &sa) == 0 && stat(db, &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

#define CLI_MAX_FILES 32

/* The file names of a command line: its outputs and its inputs, each
 * with the option (or word) that gave it. */
typedef struct cli_files {
    const char *on[CLI_MAX_FILES], *ov[CLI_MAX_FILES], *in[CLI_MAX_FILES], *iv[CLI_MAX_FILES];
    const char *out_std;        /* the first output given as '-' (standard output) */
    int no, ni, nstd;
} cli_files;

/* A string option's value (o: its table entry, as typed: name) kept
 * among the outputs or the inputs ("-": standard output or input, no
 * file; outputs there counted); options of points or ids left out. */
static void file_opt(cli_files *f, const char *name, const char *v)
{
    if (strcmp(v, "-") == 0) {
        if (output_opt(name) && f->nstd++ == 0)
            f->out_std = name;
        return;
    }
    if (output_opt(name) && f->no < CLI_MAX_FILES) {
        f->on[f->no] = name;
        f->ov[f->no++] = v;
    } else if (input_opt(name) && f->ni < CLI_MAX_FILES) {
        f->in[f->ni] = name;
        f->iv[f->ni++] = v;
    }
}

/* Refuses (usage error) an output file that is one of the command's
 * inputs (its positional arguments but for gen's, the string options
 * that are not outputs, the --lamps files): writing it would replace the
 * input; and two outputs that name one file (the second would replace
 * the first). A name not there yet can be no input. */
static int outputs_clash(const char *cmd, cli_files *f, const cli_common *c, const cli_args *a)
{
    int i, k;
    if (strcmp(cmd, "gen") != 0) /* gen's positionals are a kind and numbers, not files */
        for (i = 0; i < a->npos; i++)
            file_opt(f, "the input", a->pos[i]);
    for (i = 0; c && i < c->nlamp_files; i++)
        file_opt(f, "--lamps", c->lamp_files[i]);
    for (k = 0; k < f->no; k++) {
        for (i = 0; i < f->ni; i++)
            if (same_file(f->ov[k], f->iv[i]))
                return cli_usage_error(cmd, "%s '%s' is %s '%s': writing it would replace it; choose another name",
                                       f->on[k], f->ov[k], f->in[i], f->iv[i]);
        for (i = 0; i < k; i++)
            if (same_output(f->ov[k], f->ov[i]))
                return cli_usage_error(cmd, "%s '%s' and %s '%s' name the same file; give each its own", f->on[i],
                                       f->ov[i], f->on[k], f->ov[k]);
    }
    if (f->nstd > 1)
        return cli_usage_error(cmd, "%s and another output are both '-': only one can go to standard output",
                               f->out_std);
    return EXIT_OK;
}

int cli_options_n(const char *cmd, const char *help, int argc, char **argv, const cli_opt *opts,
                  cli_common *c, cli_indirect *ind, int maxpos, const char *toomany, cli_args *out)
{
    int i;
    cli_files files;
    memset(&files, 0, sizeof files);
    memset(out, 0, sizeof *out);
    if (maxpos > CLI_MAX_POS)
        maxpos = CLI_MAX_POS;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        const cli_opt *o;
        int r = c ? cli_common_option(cmd, argc, argv, &i, c) : 0;
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        r = ind ? cli_indirect_option(cmd, argc, argv, &i, ind) : 0;
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(help, stdout);
            return -1;
        }
        o = find_opt(opts, a);
        if (o) {
            if (take_opt(cmd, argc, argv, &i, o) != EXIT_OK)
                return EXIT_USAGE;
            if (!o->flag && !o->parse && argv[i][0] == '\0' && (output_opt(o->name) || input_opt(o->name)))
                return cli_usage_error(cmd, "%s needs a file name, not an empty string", o->name);
            if (!o->flag && !o->parse)
                file_opt(&files, o->name, argv[i]);
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else if (out->npos < maxpos) {
            out->pos[out->npos++] = a;
        } else {
            return cli_usage_error(cmd, toomany ? toomany : "unexpected argument '%s'", a,
                                   out->npos ? out->pos[out->npos - 1] : "");
        }
    }
    return outputs_clash(cmd, &files, c, out);
}

int cli_options(const char *cmd, const char *help, int argc, char **argv, const cli_opt *opts,
                cli_common *c, cli_indirect *ind, cli_args *out)
{
    return cli_options_n(cmd, help, argc, argv, opts, c, ind, CLI_MAX_POS, NULL, out);
}

/* ---- the view options of render and walk ---------------------------------- */

int cli_opt_size(const char *v, void *dst)
{
    long *wh = dst, w, h;
    char extra;
    if (sscanf(v, "%ldx%ld%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > 8192 || h > 8192)
        return -1;
    wh[0] = w;
    wh[1] = h;
    return 0;
}

static int parse_fov(const char *v, void *dst)
{
    double *fov = dst;
    return cli_parse_double(v, fov) != 0 || !(*fov > 0 && *fov < 180) ? -1 : 0;
}

static int parse_aa(const char *v, void *dst)
{
    return cli_parse_int(v, 1, PLX_RENDER_MAX_AA, dst);
}

static int parse_view(const char *v, void *dst)
{
    if (strcmp(v, "street") && strcmp(v, "aerial"))
        return -1;
    *(int *)dst = strcmp(v, "aerial") == 0;
    return 0;
}

static int parse_refine_height(const char *v, void *dst)
{
    cli_view *cv = dst;
    if (cli_parse_real(v, 0.0, 1e6, &cv->refine_height) != 0)
        return -1;
    cv->refine_height_set = 1;
    return 0;
}

static void view_opts(cli_view *v)
{
    const cli_opt f[CLI_VIEW_NOPTS] = {
        CLI_OPT_VAL("--size", v->size, cli_opt_size, "--size '%s' is not WxH (1..8192 each)"),
        CLI_OPT_VAL("--fov", &v->fov, parse_fov, "--fov '%s' is not between 0 and 180 degrees"),
        CLI_OPT_VAL("--aa", &v->aa, parse_aa,
                    "--aa '%s' is not a whole number from 1 to " STR(PLX_RENDER_MAX_AA)),
        CLI_OPT_VAL("--view", &v->aerial, parse_view, "--view '%s' is not street or aerial"),
        CLI_OPT_FLAG("--aa-full", &v->aa_full),
        CLI_OPT_FLAG("--no-glow", &v->no_glow),
        CLI_OPT_FLAG("--refine", &v->refine),
        CLI_OPT_VAL("--refine-height", v, parse_refine_height,
                    "--refine-height '%s' is not a number of metres from 0 to 1e6"),
        CLI_OPT_FLAG("--per-pixel", &v->per_pixel),
        CLI_OPT_FLAG("--tone-curve", &v->tone_curve),
        CLI_OPT_END
    };
    memcpy(v->frag, f, sizeof f);
}

void cli_view_init(cli_view *v, long w, long h, double fov, plx_render_opts *o, cli_indirect *ind)
{
    plx_render_opts_default(o);
    o->auto_exposure = 1; /* until --exposure */
    cli_indirect_default(ind);
    ind->per_lamp = 1; /* render and walk: 16 photons a lamp without --photons (cli_photons) */
    memset(v, 0, sizeof *v);
    v->size[0] = w;
    v->size[1] = h;
    v->fov = fov;
    v->aa = o->aa;
    v->no_glow = o->no_glow;
    v->refine_height = CLI_REFINE_HEIGHT;
    view_opts(v);
}

int cli_view_apply(const char *cmd, const cli_view *v, const cli_indirect *ind, plx_render_opts *o)
{
    o->aa = (int)v->aa;
    o->aa_full = v->aa_full;
    o->no_glow = v->no_glow;
    o->aerial = v->aerial;
    o->per_pixel = v->per_pixel;
    if (v->exposure)
        o->auto_exposure = v->tone_curve ? PLX_EXPOSURE_TONE : PLX_EXPOSURE_FIXED;
    o->no_indirect = ind->off;
    if (v->tone_curve && !v->exposure)
        return cli_usage_error(cmd, "--tone-curve needs --exposure E (automatic exposure has the curve already)");
    return EXIT_OK;
}
