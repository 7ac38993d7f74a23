/* fixture: the one way the unit tests get an engine holding a scene, from
 * a GeoJSON string or a file, in a block of 'bytes' from the C heap. Every
 * step is asserted (cmocka). Files load through a quiet POSIX port (no log
 * lines in the test output). Free with fixture_done. Include after
 * cmocka.h.
 *
 * A test that needs its own configuration (a port with a log book, render
 * sizes, budgets) fills a plx_config and calls fixture_engine_cfg, then
 * fixture_load_text / fixture_load_file. */
#ifndef PLX_TEST_FIXTURE_H
#define PLX_TEST_FIXTURE_H

#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include "polarlux.h"
#include "polarlux_port.h"

/* The POSIX port without its log (one static copy, so it outlives the
 * engines that use it). */
static inline const plx_port *fixture_quiet_port(void)
{
    static plx_port quiet;
    quiet = *plx_port_posix();
    quiet.log = NULL;
    return &quiet;
}

/* An engine with configuration cfg (NULL: the defaults) in a new block of
 * 'bytes' (*mem, for fixture_done). */
static inline plx_engine *fixture_engine_cfg(size_t bytes, const plx_config *cfg, void **mem)
{
    plx_engine *e = NULL;
    *mem = malloc(bytes);
    assert_non_null(*mem);
    assert_int_equal(plx_engine_create(*mem, bytes, cfg, &e), PLX_OK);
    return e;
}

static inline plx_engine *fixture_engine(size_t bytes, int strict, const plx_port *port, void **mem)
{
    plx_config cfg;
    plx_config_default(&cfg);
    cfg.strict = strict;
    cfg.port = port;
    return fixture_engine_cfg(bytes, &cfg, mem);
}

/* Loads a scene from a string ('name' is its name in messages). */
static inline plx_engine *fixture_load_text(plx_engine *e, const char *json, const char *name)
{
    assert_int_equal(plx_load_geojson(e, json, strlen(json), name), PLX_OK);
    return e;
}

static inline plx_engine *fixture_load_file(plx_engine *e, const char *path)
{
    assert_int_equal(plx_load_file(e, path), PLX_OK);
    return e;
}

/* A scene from a string (no port: the engine is silent). */
static inline plx_engine *fixture_text(const char *json, size_t bytes, int strict, void **mem)
{
    return fixture_load_text(fixture_engine(bytes, strict, NULL, mem), json, "t");
}

/* A scene from a file through the POSIX port without its log. */
static inline plx_engine *fixture_file(const char *path, size_t bytes, void **mem)
{
    return fixture_load_file(fixture_engine(bytes, 0, fixture_quiet_port(), mem), path);
}

static inline void fixture_done(plx_engine *e, void *mem)
{
    plx_engine_destroy(e);
    free(mem);
}

/* An engine from plx_engine_new (a block of 'bytes'; free it with
 * plx_engine_free) through the POSIX port without its log, holding the
 * scene of the file path, or when path is NULL of text (len bytes, named
 * "gen" in messages). */
static inline plx_engine *fixture_new(size_t bytes, const char *path, const char *text, size_t len)
{
    plx_engine *e;
    plx_config cfg;
    plx_config_default(&cfg);
    cfg.port = fixture_quiet_port();
    assert_int_equal(plx_engine_new(bytes, &cfg, &e), PLX_OK);
    assert_int_equal(path ? plx_load_file(e, path) : plx_load_geojson(e, text, len, "gen"), PLX_OK);
    return e;
}

/* ---- an engine with a log book ------------------------------------------ */

/* The engine's messages: how many, the warnings among them, the last
 * message, the last warning, and all of them one a line (cut at the size). */
typedef struct fixture_book {
    int n, warnings;
    char last[512], last_warn[512];
    char all[8192];
} fixture_book;

static inline void fixture_book_log(void *ctx, plx_log_level level, const char *msg)
{
    fixture_book *b = ctx;
    size_t len = strlen(b->all);
    b->n++;
    snprintf(b->last, sizeof b->last, "%s", msg);
    snprintf(b->all + len, sizeof b->all - len, "%s\n", msg);
    if (level == PLX_LOG_WARN) {
        b->warnings++;
        snprintf(b->last_warn, sizeof b->last_warn, "%s", msg);
    }
}

/* An engine (strict or not) in a block of 'bytes' whose POSIX port logs
 * into book. Free with fixture_close. */
typedef struct fixture_log {
    void *mem;
    plx_engine *e;
    plx_port port;
    fixture_book book;
} fixture_log;

static inline fixture_log *fixture_open(int strict, size_t bytes)
{
    fixture_log *f = calloc(1, sizeof *f);
    assert_non_null(f);
    f->port = *plx_port_posix();
    f->port.ctx = &f->book;
    f->port.log = fixture_book_log;
    f->e = fixture_engine(bytes, strict, &f->port, &f->mem);
    return f;
}

static inline void fixture_close(fixture_log *f)
{
    fixture_done(f->e, f->mem);
    free(f);
}

/* ---- a generated city as text ------------------------------------------- */

/* Text grown by plx_gen_city's writer (always NUL-terminated; free buf). */
typedef struct fixture_city {
    char *buf;
    size_t len, cap;
} fixture_city;

static inline int fixture_city_put(void *ctx, const char *data, size_t len)
{
    fixture_city *t = ctx;
    if (t->len + len + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : (size_t)1 << 20;
        while (cap < t->len + len + 1)
            cap *= 2;
        t->buf = realloc(t->buf, cap);
        assert_non_null(t->buf);
        t->cap = cap;
    }
    memcpy(t->buf + t->len, data, len);
    t->len += len;
    t->buf[t->len] = '\0';
    return 0;
}

/* plx_gen_city(style, nx, ny, seed) into *t (asserted). */
static inline void fixture_gen(const char *style, int nx, int ny, uint64_t seed, fixture_city *t)
{
    memset(t, 0, sizeof *t);
    assert_int_equal(plx_gen_city(style, nx, ny, seed, fixture_city_put, t), PLX_OK);
}

#endif
