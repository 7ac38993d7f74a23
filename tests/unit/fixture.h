/* fixture: the one way the unit tests get an engine holding a scene, from
 * a GeoJSON string or a file, in a block of 'bytes' from the C heap. Every
 * step is asserted (cmocka). Files load through a quiet POSIX port (no log
 * lines in the test output). Free with fixture_done. Include after
 * cmocka.h, polarlux.h and polarlux_port.h. */
#ifndef PLX_TEST_FIXTURE_H
#define PLX_TEST_FIXTURE_H

#include <stdlib.h>
#include <string.h>

static inline plx_engine *fixture_engine(size_t bytes, int strict, const plx_port *port, void **mem)
{
    plx_engine *e;
    plx_config cfg;
    plx_config_default(&cfg);
    cfg.strict = strict;
    cfg.port = port;
    *mem = malloc(bytes);
    assert_non_null(*mem);
    assert_int_equal(plx_engine_create(*mem, bytes, &cfg, &e), PLX_OK);
    return e;
}

/* A scene from a string (no port: the engine is silent). */
static inline plx_engine *fixture_text(const char *json, size_t bytes, int strict, void **mem)
{
    plx_engine *e = fixture_engine(bytes, strict, NULL, mem);
    assert_int_equal(plx_load_geojson(e, json, strlen(json), "t"), PLX_OK);
    return e;
}

/* A scene from a file through the POSIX port without its log. */
static inline plx_engine *fixture_file(const char *path, size_t bytes, void **mem)
{
    static plx_port quiet;
    plx_engine *e;
    quiet = *plx_port_posix();
    quiet.log = NULL;
    e = fixture_engine(bytes, 0, &quiet, mem);
    assert_int_equal(plx_load_file(e, path), PLX_OK);
    return e;
}

static inline void fixture_done(plx_engine *e, void *mem)
{
    plx_engine_destroy(e);
    free(mem);
}

#endif
