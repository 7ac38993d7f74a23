/* options: the one option loop of the commands. A command lists its
 * options in a table; cli_options walks argv once: the common options
 * (--mem, --strict, --quiet, ... : cli_common_option), the indirect-light
 * options when the command takes them (cli_indirect_option), --help/-h,
 * then the table (and the tables it links with CLI_OPT_MORE, such as the
 * view options of render and walk); anything else not starting with '-' is
 * a positional argument. Messages are the commands' usual ones ("polarlux
 * CMD: --x needs a value", "unknown option '--y'", "unexpected argument
 * 'z'"). */
#ifndef PLX_CLI_OPTIONS_H
#define PLX_CLI_OPTIONS_H

#include "cli.h"

/* Parses value into dst; 0 on success, -1 for the entry's 'bad' message,
 * -2 when it printed a message of its own. */
typedef int (*cli_parse_fn)(const char *value, void *dst);

typedef struct cli_opt {
    const char *name;       /* "--points" */
    const char *alt;        /* a second spelling ("-o"), or NULL */
    void *dst;              /* int * for a flag; const char ** when parse is NULL */
    cli_parse_fn parse;     /* NULL: keep the value as it is */
    const char *bad;        /* usage message when parse fails ("%s": the value) */
    int flag;               /* 1: takes no value, sets *(int *)dst = 1 */
    const char *need;       /* message when the value is missing (NULL:
                             * "--x needs a value") */
    int *given;             /* set to 1 when the option is met, or NULL */
    const struct cli_opt *more; /* with name NULL: also the options of this table */
} cli_opt;

/* Table entries: a value kept as given (const char **dst), a value parsed
 * into dst (message 'bad' when it does not parse), a flag (int *dst). */
#define CLI_OPT_STR(name, dst) { name, NULL, dst, NULL, NULL, 0, NULL, NULL, NULL }
#define CLI_OPT_VAL(name, dst, parse, bad) { name, NULL, dst, parse, bad, 0, NULL, NULL, NULL }
#define CLI_OPT_FLAG(name, dst) { name, NULL, dst, NULL, NULL, 1, NULL, NULL, NULL }
#define CLI_OPT_MORE(table) { NULL, NULL, NULL, NULL, NULL, 0, NULL, NULL, table }
#define CLI_OPT_END { NULL, NULL, NULL, NULL, NULL, 0, NULL, NULL, NULL }
#define CLI_MAX_POS 8

typedef struct cli_args {
    const char *pos[CLI_MAX_POS]; /* positional arguments in order */
    int npos;
} cli_args;

/* Walks argv[1..argc-1]. c and ind may be NULL (the command has none of
 * those options). Returns EXIT_OK; EXIT_USAGE after a message on stderr;
 * or -1 after printing help on standard output (the command then exits
 * EXIT_OK). More than CLI_MAX_POS positionals is a usage error. */
int cli_options(const char *cmd, const char *help, int argc, char **argv, const cli_opt *opts,
                cli_common *c, cli_indirect *ind, cli_args *out);

/* The same with at most maxpos (0..CLI_MAX_POS) positionals: the one after
 * is a usage error where it stands, before the options after it, with
 * message toomany (given the argument, then the positional before it: "%s"
 * or "%2$s ... %1$s"; NULL: "unexpected argument '%s'"). */
int cli_options_n(const char *cmd, const char *help, int argc, char **argv, const cli_opt *opts,
                  cli_common *c, cli_indirect *ind, int maxpos, const char *toomany, cli_args *out);

/* Parsers for the table (dst: double *, long *). */
int cli_opt_double(const char *value, void *dst);
/* A height in metres from 0 to 1000 (dst: double *). */
int cli_opt_height(const char *value, void *dst);
/* A facing direction in degrees, or min (dst: heat_quantity *: its facing
 * and facing_min). */
int cli_opt_facing(const char *value, void *dst);

/* WxH with 1..8192 each (dst: long[2]). */
int cli_opt_size(const char *value, void *dst);

/* ---- the view options of render and walk ---------------------------------- */

#define CLI_VIEW_NOPTS 11
/* --refine-height's default, m: munoz2013 §3.3 refines only when the
 * camera is below a height; the near radius of the refinement. */
#define CLI_REFINE_HEIGHT 60.0

typedef struct cli_view {
    long size[2];           /* --size WxH (1..8192 each) */
    double fov;             /* --fov (0..180 degrees) */
    long aa;                /* --aa (1..PLX_RENDER_MAX_AA) */
    int aerial;             /* --view street|aerial */
    int no_glow, refine;    /* --no-glow, --refine */
    double refine_height;   /* --refine-height: refine only with the eye at most this high, m */
    int refine_height_set;  /* --refine-height was given */
    int aa_full;            /* --aa-full */
    int per_pixel;          /* --per-pixel: light computed at every pixel, not read from the atlas */
    int exposure;           /* --exposure was given (the command's own table
                             * entry sets it): no automatic exposure */
    int tone_curve;         /* --tone-curve: the fixed exposure with the tone curve */
    cli_opt frag[CLI_VIEW_NOPTS]; /* the options above (the last entry
                             * CLI_OPT_END), for CLI_OPT_MORE(v.frag) */
} cli_view;

/* The defaults of render and walk: o the default render options with
 * automatic exposure (until --exposure), ind the default indirect light;
 * v w x h pixels, fov degrees, o's anti-aliasing and glow, the street view,
 * no refinement, and its options in v->frag. */
void cli_view_init(cli_view *v, long w, long h, double fov, plx_render_opts *o, cli_indirect *ind);

/* After parsing: the anti-aliasing, glow, view, exposure, --per-pixel and
 * --no-indirect into o; EXIT_USAGE, said, for --tone-curve without
 * --exposure. */
int cli_view_apply(const char *cmd, const cli_view *v, const cli_indirect *ind, plx_render_opts *o);

#endif
