/* options: the one option loop of the commands. A command lists its
 * options in a table; cli_options walks argv once: the common options
 * (--mem, --strict, --quiet, ... : cli_common_option), the indirect-light
 * options when the command takes them (cli_indirect_option), --help/-h,
 * then the table; anything else not starting with '-' is a positional
 * argument. Messages are the commands' usual ones ("polarlux CMD: --x
 * needs a value", "unknown option '--y'"). */
#ifndef PLX_CLI_OPTIONS_H
#define PLX_CLI_OPTIONS_H

#include "cli.h"

/* Parses value into dst; 0 on success. */
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
} cli_opt;

#define CLI_OPT_END { NULL, NULL, NULL, NULL, NULL, 0, NULL }
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

/* Parsers for the table (dst: double *, long *). */
int cli_opt_double(const char *value, void *dst);

#endif
