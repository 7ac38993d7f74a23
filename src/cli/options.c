/* options: the one option loop of the commands (see options.h). */
#include <stdio.h>
#include <string.h>

#include "options.h"

int cli_opt_double(const char *value, void *dst)
{
    return cli_parse_double(value, dst);
}

static const cli_opt *find_opt(const cli_opt *opts, const char *a)
{
    for (; opts && opts->name; opts++)
        if (strcmp(a, opts->name) == 0 || (opts->alt && strcmp(a, opts->alt) == 0))
            return opts;
    return NULL;
}

/* One table option at argv[*i]; EXIT_OK or EXIT_USAGE. */
static int take_opt(const char *cmd, int argc, char **argv, int *i, const cli_opt *o)
{
    const char *a = argv[*i];
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
    if (o->parse(argv[*i], o->dst) != 0)
        return cli_usage_error(cmd, o->bad, argv[*i]);
    return EXIT_OK;
}

int cli_options(const char *cmd, const char *help, int argc, char **argv, const cli_opt *opts,
                cli_common *c, cli_indirect *ind, cli_args *out)
{
    int i;
    memset(out, 0, sizeof *out);
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
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else if (out->npos < CLI_MAX_POS) {
            out->pos[out->npos++] = a;
        } else {
            return cli_usage_error(cmd, "unexpected argument '%s'", a);
        }
    }
    return EXIT_OK;
}
