/* libFuzzer target: the bake reader (plx_bake_block_size, plx_bake_load,
 * and through reads plx_bake_block_size_read, plx_bake_load_read, which
 * must give the load's status).
 * Every input is read as it comes (nearly all fail at the header or the
 * checksum, with one line and no engine). Inputs starting with the magic
 * are also read with their length field and checksum made right, so the
 * fuzzer reaches the layout checks, the page copy and the relocations.
 * Whatever the bytes: no crash, a status from the documented set, a
 * one-line message on failure, an engine only on success. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "../ref/ref_bake_sum.h"
#include "fuzz_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define BLOCK ((size_t)8 << 20)

typedef struct bytes_in {
    const uint8_t *f;
    size_t len;
} bytes_in;

static int bytes_read(void *user, uint64_t off, void *buf, size_t n)
{
    const bytes_in *b = user;
    if (off > b->len || n > b->len - off)
        return -1;
    memcpy(buf, b->f + off, n);
    return 0;
}

/* A load's result: on failure no engine and a line; on success an
 * engine in mem, destroyed. */
static void loaded(plx_status st, plx_engine *e, const char *err, void *mem)
{
    if (st != PLX_OK) {
        CHECK(e == NULL);
        CHECK(err[0] != '\0' && strchr(err, '\n') == NULL);
    } else {
        CHECK(e != NULL && plx_engine_block(e) == mem);
        plx_engine_destroy(e);
    }
}

/* The same file through reads: the size-first call gives
 * plx_bake_block_size's status (size_st; without scratch the header's
 * checks only, so PLX_OK where the body is damaged), the load
 * plx_bake_load's (load_st). */
static void one_read(const uint8_t *f, size_t len, void *mem, plx_status size_st, plx_status load_st)
{
    char err[512];
    size_t need = 0;
    plx_engine *e = NULL;
    unsigned char scratch[1024];
    bytes_in in;
    plx_status st;
    in.f = f;
    in.len = len;
    st = plx_bake_block_size_read(bytes_read, &in, len, NULL, 0, &need, err, sizeof err);
    CHECK(st == PLX_OK || st == size_st);
    st = plx_bake_block_size_read(bytes_read, &in, len, scratch, sizeof scratch, &need, err, sizeof err);
    CHECK(st == size_st);
    err[0] = '\0';
    st = plx_bake_load_read(mem, BLOCK, NULL, bytes_read, &in, len, &e, err, sizeof err);
    CHECK(st == load_st);
    loaded(st, e, err, mem);
}

static void one(const uint8_t *f, size_t len, void *mem)
{
    char err[512];
    size_t need = 0;
    plx_engine *e = NULL;
    plx_status st, size_st;
    err[0] = '\0';
    st = size_st = plx_bake_block_size(f, len, &need, err, sizeof err);
    CHECK(st == PLX_OK || st == PLX_E_PARSE || st == PLX_E_UNSUPPORTED);
    if (st != PLX_OK)
        CHECK(err[0] != '\0' && strchr(err, '\n') == NULL);
    err[0] = '\0';
    st = plx_bake_load(mem, BLOCK, NULL, f, len, &e, err, sizeof err);
    CHECK(st == PLX_OK || st == PLX_E_PARSE || st == PLX_E_UNSUPPORTED || st == PLX_E_NOMEM);
    loaded(st, e, err, mem);
    one_read(f, len, mem, size_st, st);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static void *mem;
    uint8_t *fixed;
    if (!mem && !(mem = malloc(BLOCK)))
        return 0;
    one(data, size, mem);
    if (size < 128 || memcmp(data, "PLXBAKE", 8) != 0)
        return 0;
    fixed = malloc(size);
    if (!fixed)
        return 0;
    memcpy(fixed, data, size);
    ref_bake_reseal(fixed, size);
    one(fixed, size, mem);
    free(fixed);
    return 0;
}
