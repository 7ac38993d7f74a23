/* mbtiles: MBTiles 1.3 output (an SQLite file: metadata and tiles tables,
 * tile rows in TMS order), written to a temporary file renamed into place. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sqlite3.h>

#include "tiles.h"

struct mbtiles {
    sqlite3 *db;
    sqlite3_stmt *put;
    char *path, *tmp;
};

static int sql_fail(mbtiles *m, const char *what, char *err, size_t errlen)
{
    snprintf(err, errlen, "%s: %s: %s", m->path, what, m->db ? sqlite3_errmsg(m->db) : "out of memory");
    return -1;
}

static int add_meta(mbtiles *m, const char *name, const char *value)
{
    sqlite3_stmt *s;
    int rc;
    if (sqlite3_prepare_v2(m->db, "INSERT INTO metadata (name, value) VALUES (?, ?)", -1, &s, NULL) != SQLITE_OK)
        return -1;
    sqlite3_bind_text(s, 1, name, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s, 2, value, -1, SQLITE_TRANSIENT);
    rc = sqlite3_step(s) == SQLITE_DONE ? 0 : -1;
    sqlite3_finalize(s);
    return rc;
}

static int write_metadata(mbtiles *m, const char *name, const double b[4], int z0, int z1, const char *what,
                          double top, const char *attribution)
{
    char v[512];
    int rc = 0;
    rc |= add_meta(m, "name", name);
    rc |= add_meta(m, "format", "png");
    rc |= add_meta(m, "type", "overlay");
    rc |= add_meta(m, "version", "1");
    snprintf(v, sizeof v, "%.7f,%.7f,%.7f,%.7f", b[0], b[1], b[2], b[3]);
    rc |= add_meta(m, "bounds", v);
    snprintf(v, sizeof v, "%.7f,%.7f,%d", 0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3]), z1);
    rc |= add_meta(m, "center", v);
    snprintf(v, sizeof v, "%d", z0);
    rc |= add_meta(m, "minzoom", v);
    snprintf(v, sizeof v, "%d", z1);
    rc |= add_meta(m, "maxzoom", v);
    snprintf(v, sizeof v,
             "%s by polarlux, logarithmic colour scale 0.1..%g lx "
             "(the heat map's); transparent where there is no light",
             what, top);
    rc |= add_meta(m, "description", v);
    if (attribution && attribution[0])
        rc |= add_meta(m, "attribution", attribution);
    return rc;
}

mbtiles *mbtiles_open(const char *path, const char *name, const double bounds[4], int z0, int z1,
                      const char *what, double top, const char *attribution, char *err, size_t errlen)
{
    static const char schema[] =
        "PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF; BEGIN;"
        "CREATE TABLE metadata (name TEXT, value TEXT);"
        "CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER, tile_data BLOB);"
        "CREATE UNIQUE INDEX tile_index ON tiles (zoom_level, tile_column, tile_row);";
    mbtiles *m = calloc(1, sizeof *m);
    size_t n = strlen(path) + 32;
    if (!m || !(m->path = malloc(n)) || !(m->tmp = malloc(n))) {
        snprintf(err, errlen, "%s: out of memory", path);
        if (m)
            free(m->path);
        free(m);
        return NULL;
    }
    snprintf(m->path, n, "%s", path);
    snprintf(m->tmp, n, "%s.tmp.%ld", path, (long)getpid());
    unlink(m->tmp);
    if (sqlite3_open(m->tmp, &m->db) != SQLITE_OK || sqlite3_exec(m->db, schema, NULL, NULL, NULL) != SQLITE_OK ||
        write_metadata(m, name, bounds, z0, z1, what, top, attribution) != 0 ||
        sqlite3_prepare_v2(m->db, "INSERT INTO tiles VALUES (?, ?, ?, ?)", -1, &m->put, NULL) != SQLITE_OK) {
        sql_fail(m, "cannot create the MBTiles file", err, errlen);
        mbtiles_close(m, 0, NULL, 0);
        return NULL;
    }
    return m;
}

int mbtiles_put(mbtiles *m, int z, long x, long y, const uint8_t *png, size_t len, char *err, size_t errlen)
{
    int rc;
    sqlite3_bind_int(m->put, 1, z);
    sqlite3_bind_int64(m->put, 2, x);
    sqlite3_bind_int64(m->put, 3, (1L << z) - 1 - y);
    sqlite3_bind_blob(m->put, 4, png, (int)len, SQLITE_TRANSIENT);
    rc = sqlite3_step(m->put);
    sqlite3_reset(m->put);
    return rc == SQLITE_DONE ? 0 : sql_fail(m, "cannot add a tile", err, errlen);
}

int mbtiles_close(mbtiles *m, int commit, char *err, size_t errlen)
{
    int rc = 0;
    sqlite3_finalize(m->put);
    if (commit && sqlite3_exec(m->db, "COMMIT;", NULL, NULL, NULL) != SQLITE_OK)
        rc = sql_fail(m, "cannot commit", err, errlen);
    if (sqlite3_close(m->db) != SQLITE_OK && rc == 0 && commit)
        rc = sql_fail(m, "cannot close", err, errlen);
    m->db = NULL;
    if (commit && rc == 0 && rename(m->tmp, m->path) != 0) {
        snprintf(err, errlen, "%s: cannot rename %s into place: %s", m->path, m->tmp, strerror(errno));
        rc = -1;
    }
    if (!commit || rc != 0)
        unlink(m->tmp);
    free(m->path);
    free(m->tmp);
    free(m);
    return rc;
}
