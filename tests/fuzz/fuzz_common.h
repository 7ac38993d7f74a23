/* Shared by the fuzz targets: engines kept across inputs, and the checks
 * every load must pass whatever the input (through the public API only).
 * A failed check prints "FUZZ CHECK" and aborts, which libFuzzer reports as
 * a crash with the input saved. */
#ifndef FUZZ_COMMON_H
#define FUZZ_COMMON_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "fuzz_check.h"

#define FUZZ_MEM (256u << 20)

typedef struct fuzz_log {
    uint32_t lines;
} fuzz_log;

/* Every message is one non-empty line of bounded length. */
static void fuzz_log_line(void *ctx, plx_log_level level, const char *msg)
{
    fuzz_log *l = ctx;
    size_t n = strlen(msg);
    CHECK(level <= PLX_LOG_INFO);
    CHECK(n > 0 && n < 512);
    CHECK(strchr(msg, '\n') == NULL);
    l->lines++;
}

typedef struct fuzz_engine {
    void *mem;
    plx_engine *e;
    plx_port port;
    fuzz_log log;
    size_t base_used;   /* arena bytes in use with no scene loaded */
} fuzz_engine;

static void fuzz_engine_open(fuzz_engine *f, int strict)
{
    plx_config cfg;
    plx_memory_report m;
    memset(f, 0, sizeof *f);
    f->mem = malloc(FUZZ_MEM);
    CHECK(f->mem != NULL);
    f->port.ctx = &f->log;
    f->port.log = fuzz_log_line;
    plx_config_default(&cfg);
    cfg.port = &f->port;
    cfg.strict = strict;
    CHECK(plx_engine_create(f->mem, FUZZ_MEM, &cfg, &f->e) == PLX_OK);
    plx_memory_get(f->e, &m);
    f->base_used = m.used_total;
}

static uint64_t fuzz_hash(const uint8_t *d, size_t n)
{
    uint64_t h = 1469598103934665603ull;
    size_t i;
    for (i = 0; i < n; i++)
        h = (h ^ d[i]) * 1099511628211ull;
    return h;
}

static int fuzz_finite_in(double v, double lo, double hi)
{
    return isfinite(v) && v >= lo && v <= hi;
}

/* After a failed load: one line of error, no scene, all memory given back. */
static void fuzz_check_failed(fuzz_engine *f, plx_status st)
{
    const char *err = plx_last_error(f->e);
    plx_scene_info si;
    plx_building b;
    plx_memory_report m;
    CHECK(st > PLX_OK && st < PLX_STATUS_COUNT);
    CHECK(err[0] != '\0' && strlen(err) < 512 && strchr(err, '\n') == NULL);
    if (st == PLX_E_NOMEM)
        CHECK(strncmp(err, "out of memory", 13) == 0);
    CHECK(plx_scene_info_get(f->e, &si) == PLX_E_NOSCENE);
    CHECK(plx_building_get(f->e, 0, &b) == PLX_E_NOSCENE);
    plx_memory_get(f->e, &m);
    CHECK(m.used_total == f->base_used);
}

/* After a successful load: every getter agrees with the counts and every
 * value is within the ranges the loader promises. */
static void fuzz_check_loaded(fuzz_engine *f)
{
    plx_scene_info si;
    plx_memory_report m;
    uint32_t i, r, k, verts = 0, holes = 0, in_blocks = 0;
    CHECK(plx_scene_info_get(f->e, &si) == PLX_OK);
    CHECK(si.bounds[0] < si.bounds[2] && si.bounds[1] < si.bounds[3]);
    CHECK(fuzz_finite_in(si.ground_albedo, 0, 1));
    if (si.buildings)
        CHECK(si.height_min <= si.height_median && si.height_median <= si.height_max);
    for (i = 0; i < si.buildings; i++) {
        plx_building b;
        CHECK(plx_building_get(f->e, i, &b) == PLX_OK);
        CHECK(b.nrings >= 1);
        CHECK(fuzz_finite_in(b.height, 1e-300, 1000) && b.height > 0);
        CHECK(fuzz_finite_in(b.min_height, 0, 1000) && b.min_height < b.height);
        CHECK(fuzz_finite_in(b.albedo, 0, 1));
        CHECK(b.block < si.blocks);
        CHECK(b.id == NULL || strlen(b.id) <= 200);
        CHECK(b.height >= si.height_min && b.height <= si.height_max);
        holes += b.nrings - 1;
        for (r = 0; r < b.nrings; r++) {
            const double *xy;
            uint32_t n;
            double box[4];
            CHECK(plx_building_ring(f->e, i, r, &xy, &n) == PLX_OK);
            CHECK(n >= 3);
            verts += n;
            box[0] = box[2] = xy[0];
            box[1] = box[3] = xy[1];
            for (k = 0; k < n; k++) {
                CHECK(fuzz_finite_in(xy[2 * k], -1e7, 1e7) && fuzz_finite_in(xy[2 * k + 1], -1e7, 1e7));
                /* cleaned: no duplicate consecutive vertices, no closing vertex */
                CHECK(xy[2 * k] != xy[2 * ((k + 1) % n)] || xy[2 * k + 1] != xy[2 * ((k + 1) % n) + 1]);
                box[0] = fmin(box[0], xy[2 * k]);
                box[1] = fmin(box[1], xy[2 * k + 1]);
                box[2] = fmax(box[2], xy[2 * k]);
                box[3] = fmax(box[3], xy[2 * k + 1]);
            }
            if (r == 0)
                CHECK(memcmp(box, b.box, sizeof box) == 0);
            CHECK(box[0] >= si.bounds[0] && box[2] <= si.bounds[2]);
            CHECK(box[1] >= si.bounds[1] && box[3] <= si.bounds[3]);
        }
        {
            const double *xy;
            uint32_t n;
            CHECK(plx_building_ring(f->e, i, b.nrings, &xy, &n) == PLX_E_RANGE);
        }
    }
    CHECK(verts == si.vertices);
    CHECK(holes == si.holes);
    for (i = 0; i < si.lamps; i++) {
        plx_lamp l;
        CHECK(plx_lamp_get(f->e, i, &l) == PLX_OK);
        CHECK(fuzz_finite_in(l.x, -1e7, 1e7) && fuzz_finite_in(l.y, -1e7, 1e7));
        CHECK(fuzz_finite_in(l.z, 0, 1000));
        CHECK(fuzz_finite_in(l.intensity, 0, INFINITY));
        CHECK(fuzz_finite_in(l.radius, 1e-300, 1e5) && l.radius > 0);
        for (k = 0; k < 3; k++)
            CHECK(isfinite(l.color[k]) && l.color[k] >= 0);
    }
    for (i = 0; i < si.blocks; i++) {
        plx_block bk;
        CHECK(plx_block_get(f->e, i, &bk) == PLX_OK);
        CHECK(bk.nbuildings >= 1);
        in_blocks += bk.nbuildings;
        for (k = 0; k < bk.nbuildings; k++) {
            plx_building b;
            CHECK(bk.buildings[k] < si.buildings);
            CHECK(plx_building_get(f->e, bk.buildings[k], &b) == PLX_OK);
            CHECK(b.block == i);
        }
        for (r = 0; r < bk.nrings; r++) {
            const double *xy;
            uint32_t n;
            CHECK(plx_block_ring(f->e, i, r, &xy, &n) == PLX_OK);
            for (k = 0; k < 2 * n; k++)
                CHECK(isfinite(xy[k]));
        }
    }
    CHECK(in_blocks == si.buildings);
    {
        plx_building b;
        plx_lamp l;
        plx_block bk;
        CHECK(plx_building_get(f->e, si.buildings, &b) == PLX_E_RANGE);
        CHECK(plx_lamp_get(f->e, si.lamps, &l) == PLX_E_RANGE);
        CHECK(plx_block_get(f->e, si.blocks, &bk) == PLX_E_RANGE);
    }
    plx_memory_get(f->e, &m);
    CHECK(m.used[PLX_PART_SCRATCH] == 0);
    CHECK(m.used_total > f->base_used);
}

typedef struct fuzz_result {
    plx_status st;
    plx_scene_info si;      /* load_ns zeroed */
    uint32_t warnings;
    char err[512];
} fuzz_result;

static void fuzz_load(fuzz_engine *f, const char *text, size_t len, fuzz_result *res)
{
    memset(res, 0, sizeof *res);
    res->st = plx_load_geojson(f->e, text, len, "fuzz");
    /* the load's own message (the checks below may set others) */
    snprintf(res->err, sizeof res->err, "%s", plx_last_error(f->e));
    if (res->st == PLX_OK) {
        fuzz_check_loaded(f);
        CHECK(plx_scene_info_get(f->e, &res->si) == PLX_OK);
        res->si.load_ns = 0;
    } else {
        fuzz_check_failed(f, res->st);
    }
    res->warnings = plx_warning_count(f->e);
}

static int fuzz_same(const fuzz_result *a, const fuzz_result *b)
{
    return a->st == b->st && a->warnings == b->warnings && strcmp(a->err, b->err) == 0 &&
           memcmp(&a->si, &b->si, sizeof a->si) == 0;
}

/* The checks every input gets, whatever the target made of its bytes:
 *  - lenient and strict loads pass the invariants above;
 *  - strict succeeds exactly when lenient skipped nothing, with the same scene
 *    (or lenient ignored a bad properties.ground_image(_bounds), or read the
 *    first of a key given twice in an object, with a warning, which strict
 *    refuses);
 *  - a failure injected at one allocation of the load (chosen from the
 *    input's hash) gives PLX_E_NOMEM with all memory back;
 *  - loading again gives the same result (the engine is still usable and
 *    the load is deterministic). */
static void fuzz_check_text(fuzz_engine *lenient, fuzz_engine *strict, const char *text, size_t len,
                            uint64_t hash)
{
    fuzz_result a, s, again;
    uint64_t served;
    plx_debug_fail_alloc(lenient->e, 0);
    fuzz_load(lenient, text, len, &a);
    served = plx_debug_fail_alloc(lenient->e, 0);
    fuzz_load(strict, text, len, &s);
    if (a.st != PLX_OK) {
        CHECK(s.st != PLX_OK);
        CHECK(a.st != PLX_E_NOMEM);
    } else if (a.si.skipped_features == 0 && a.si.skipped_lamps == 0) {
        /* a bad properties.ground_image(_bounds), or a key given twice, is
         * a warning when lenient and fatal when strict: nothing is skipped */
        if (!(s.st == PLX_E_SCENE && (strstr(s.err, "properties.ground_image") || strstr(s.err, "\" twice; ")) &&
              a.warnings > 0)) {
            CHECK(s.st == PLX_OK);
            CHECK(memcmp(&a.si, &s.si, sizeof a.si) == 0);
        }
    } else {
        CHECK(s.st == PLX_E_SCENE);
    }
    if (served > 0) {
        fuzz_result nm;
        plx_debug_fail_alloc(lenient->e, 1 + hash % served);
        fuzz_load(lenient, text, len, &nm);
        CHECK(nm.st == PLX_E_NOMEM);
        plx_debug_fail_alloc(lenient->e, 0);
    }
    fuzz_load(lenient, text, len, &again);
    CHECK(fuzz_same(&a, &again));
}

#endif
