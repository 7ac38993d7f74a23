#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

int cli_usage_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "polarlux %s: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, " (see 'polarlux %s --help')\n", cmd);
    return EXIT_USAGE;
}

size_t cli_parse_size(const char *s)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (errno || end == s || !(v > 0))
        return 0;
    switch (*end) {
    case 'k': case 'K': v *= 1024.0; end++; break;
    case 'm': case 'M': v *= 1024.0 * 1024.0; end++; break;
    case 'g': case 'G': v *= 1024.0 * 1024.0 * 1024.0; end++; break;
    default: break;
    }
    if (*end == 'B' || *end == 'b')
        end++;
    if (*end != '\0' || v > 1e15)
        return 0;
    return (size_t)v;
}

int cli_parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return (errno || end == s || *end != '\0' || *out != *out) ? -1 : 0;
}

int cli_parse_int(const char *s, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    *out = strtol(s, &end, 10);
    return (errno || end == s || *end != '\0' || *out < lo || *out > hi) ? -1 : 0;
}

int cli_common_option(const char *cmd, int argc, char **argv, int *i, cli_common *c)
{
    const char *a = argv[*i];
    if (strcmp(a, "--strict") == 0) {
        c->strict = 1;
        return 1;
    }
    if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
        c->quiet = 1;
        return 1;
    }
    if (strcmp(a, "--mem") == 0) {
        if (*i + 1 >= argc) {
            cli_usage_error(cmd, "--mem needs a size, e.g. --mem 512M");
            return -1;
        }
        c->mem = cli_parse_size(argv[++*i]);
        if (c->mem < PLX_ENGINE_MIN_BYTES) {
            cli_usage_error(cmd, "--mem '%s' is not a size of at least %d bytes (e.g. 512M, 2G)",
                            argv[*i], PLX_ENGINE_MIN_BYTES);
            return -1;
        }
        return 1;
    }
    return 0;
}

int cli_exit_code(plx_status s)
{
    if (s == PLX_OK)
        return EXIT_OK;
    if (s == PLX_E_NOMEM)
        return EXIT_NOMEM;
    if (s == PLX_E_INVALID)
        return EXIT_USAGE;
    return EXIT_FAIL;
}

static void quiet_log(void *ctx, plx_log_level level, const char *msg)
{
    (void)ctx;
    if (level == PLX_LOG_ERROR)
        fprintf(stderr, "polarlux: error: %s\n", msg);
}

int cli_open_scene(const char *cmd, const char *path, const cli_common *c, plx_engine **e)
{
    static plx_port quiet_port;
    plx_config cfg;
    plx_status st;
    plx_config_default(&cfg);
    cfg.port = plx_port_posix();
    if (c->quiet) {
        quiet_port = *cfg.port;
        quiet_port.log = quiet_log;
        cfg.port = &quiet_port;
    }
    cfg.strict = c->strict;
    cfg.render_max_width = c->render_w;
    cfg.render_max_height = c->render_h;
    st = plx_engine_new(c->mem ? c->mem : CLI_DEFAULT_MEM, &cfg, e);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: cannot create an engine of %zu bytes: %s\n", cmd,
                c->mem ? c->mem : CLI_DEFAULT_MEM, plx_strerror(st));
        return cli_exit_code(st);
    }
    st = plx_load_file(*e, path);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux %s: %s\n", cmd, plx_last_error(*e));
        if (st == PLX_E_NOMEM)
            fprintf(stderr, "polarlux %s: give the engine more memory with --mem (now %zu bytes)\n",
                    cmd, c->mem ? c->mem : CLI_DEFAULT_MEM);
        plx_engine_free(*e);
        *e = NULL;
        return st == PLX_E_INVALID ? EXIT_FAIL : cli_exit_code(st);
    }
    return EXIT_OK;
}
