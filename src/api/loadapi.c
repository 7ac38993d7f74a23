/* loadapi: loading a scene (src/scene/geojson.c reads it): the engine's
 * previous scene and everything built on it dropped, the text read from
 * memory, from the port's read-only view of a file (file_map: never copied)
 * or through its file_size/file_read into scratch memory, scratch memory
 * given back. */
#include <string.h>

#include "base/engine.h"
#include "scene/geojson.h"

static void drop_scene(plx_engine *e)
{
    e->sc = NULL;
    e->pd = NULL;
    e->vis_poly = NULL;
    e->vis_ids = NULL;
    e->lt = NULL;
    e->lit_last = NULL;
    e->rd = NULL;
    e->ph = NULL;
    e->atlas = NULL;
    e->atlas_cache = NULL;
    e->atlas_list = NULL;
    e->atlas_rec = NULL;
    e->atlas_fine = 0.0;
    e->atlas_off = 0;
    e->lightmap_cell = 0.0;
    e->warnings = 0;
    eng_clear_error(e);
    e->mem.lo = e->base.lo;
    {
        size_t i;
        for (i = 0; i < PLX_PART_COUNT; i++)
            if (i != PLX_PART_SCRATCH)
                e->mem.used[i] = e->base.used[i];
    }
}

/* Loads text that may itself sit in scratch memory; gives back all scratch
 * memory taken after entry. */
static plx_status load_text(plx_engine *e, const char *text, size_t len, const char *name)
{
    arena_mark m = arena_get_mark(&e->mem);
    plx_status st;
    uint64_t t0 = eng_clock(e);
    if (len >= 8 && memcmp(text, "PLXBAKE", 8) == 0) { /* a bake's magic (bake_file.h), NUL included */
        strbuf b;
        sb_init(&b, e->err, sizeof e->err);
        sb_str(&b, name ? name : "scene");
        sb_str(&b, ": a bake file (polarlux bake), not GeoJSON: load it with plx_bake_load or plx_bake_load_read");
        return PLX_E_PARSE;
    }
    st = geojson_load(e, &e->mem, text, len, name, &e->sc);
    if (st != PLX_OK) {
        arena_release(&e->mem, &m);
        e->sc = NULL;
        return st;
    }
    e->mem.hi = m.hi;
    e->mem.used[PLX_PART_SCRATCH] = m.used[PLX_PART_SCRATCH];
    e->sc->load_ns = eng_clock(e) - t0;
    eng_check_scene(e->sc);
    return PLX_OK;
}

plx_status plx_load_geojson(plx_engine *e, const char *text, size_t len, const char *name)
{
    if (!eng_ok(e))
        return PLX_E_INVALID;
    drop_scene(e);
    if (!text && len)
        return eng_fail(e, PLX_E_INVALID, "plx_load_geojson: text is NULL");
    return load_text(e, text, len, name);
}

/* "path: why" as the engine's error. */
static plx_status io_fail(plx_engine *e, const char *path, const char *why)
{
    strbuf b;
    sb_init(&b, e->err, sizeof e->err);
    sb_str(&b, path);
    sb_str(&b, ": ");
    sb_str(&b, why);
    return PLX_E_IO;
}

/* Through the port's file_map: the text is read where the port maps it,
 * never copied into the block; unmapped on every path. */
static plx_status load_mapped(plx_engine *e, const char *path)
{
    char why[256];
    const void *data = NULL;
    void *handle = NULL;
    size_t size = 0;
    plx_status st;
    why[0] = '\0';
    if (e->port.file_map(e->port.ctx, path, &data, &size, &handle, why, sizeof why) != 0)
        return io_fail(e, path, why);
    if (!data && size)
        st = eng_fail(e, PLX_E_IO, "plx_load_file: the port mapped no bytes");
    else
        st = load_text(e, data ? (const char *)data : "", size, path);
    e->port.file_unmap(e->port.ctx, handle);
    return st;
}

/* Through file_size/file_read: the whole file into scratch memory. */
static plx_status load_read(plx_engine *e, const char *path)
{
    char why[256];
    size_t size = 0;
    char *buf;
    plx_status st;
    arena_mark m;
    why[0] = '\0';
    if (e->port.file_size(e->port.ctx, path, &size, why, sizeof why) != 0)
        return io_fail(e, path, why);
    m = arena_get_mark(&e->mem);
    buf = arena_scratch(&e->mem, size + 1, 16);
    if (!buf)
        return eng_nomem(e, "reading the scene file");
    if (e->port.file_read(e->port.ctx, path, buf, size, why, sizeof why) != 0) {
        arena_release(&e->mem, &m);
        return io_fail(e, path, why);
    }
    buf[size] = '\0';
    st = load_text(e, buf, size, path);
    e->mem.hi = m.hi;
    e->mem.used[PLX_PART_SCRATCH] = m.used[PLX_PART_SCRATCH];
    return st;
}

plx_status plx_load_file(plx_engine *e, const char *path)
{
    if (!eng_ok(e))
        return PLX_E_INVALID;
    drop_scene(e);
    if (!path)
        return eng_fail(e, PLX_E_INVALID, "plx_load_file: path is NULL");
    if (e->port.file_map && e->port.file_unmap)
        return load_mapped(e, path);
    if (!e->port.file_size || !e->port.file_read)
        return eng_fail(e, PLX_E_UNSUPPORTED, "plx_load_file: this engine's port has no file system; use plx_load_geojson");
    return load_read(e, path);
}
