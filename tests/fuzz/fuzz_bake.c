/* libFuzzer target: the bake reader (plx_bake_block_size, plx_bake_load).
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

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CHECK(cond)                                                                      \
    do {                                                                                 \
        if (!(cond)) {                                                                   \
            fprintf(stderr, "FUZZ CHECK failed at %s:%d: %s\n", __FILE__, __LINE__, #cond); \
            abort();                                                                     \
        }                                                                                \
    } while (0)

#define BLOCK ((size_t)8 << 20)

/* The file checksum (README "Bake files"): FNV-1a over 64-bit words in
 * four lanes, the header with its checksum field as 0, then the body. */
static uint64_t file_sum(const uint8_t *f, size_t len)
{
    uint64_t h[4], w;
    uint8_t head[128];
    const uint8_t *parts[2];
    size_t lens[2], i, p;
    int k;
    for (k = 0; k < 4; k++)
        h[k] = 0xcbf29ce484222325ull ^ (uint64_t)k;
    memcpy(head, f, 128);
    memset(head + 32, 0, 8);
    parts[0] = head; lens[0] = 128;
    parts[1] = f + 128; lens[1] = len - 128;
    for (p = 0; p < 2; p++) {
        for (i = 0; i + 32 <= lens[p]; i += 32)
            for (k = 0; k < 4; k++) {
                memcpy(&w, parts[p] + i + 8 * k, 8);
                h[k] = (h[k] ^ w) * 0x00000100000001b3ull;
            }
        for (; i < lens[p]; i++)
            h[0] = (h[0] ^ parts[p][i]) * 0x00000100000001b3ull;
    }
    w = h[0];
    for (k = 1; k < 4; k++)
        w = (w ^ h[k]) * 0x00000100000001b3ull;
    return w;
}

static void one(const uint8_t *f, size_t len, void *mem)
{
    char err[512];
    size_t need = 0;
    plx_engine *e = NULL;
    plx_status st;
    err[0] = '\0';
    st = plx_bake_block_size(f, len, &need, err, sizeof err);
    CHECK(st == PLX_OK || st == PLX_E_PARSE || st == PLX_E_UNSUPPORTED);
    if (st != PLX_OK)
        CHECK(err[0] != '\0' && strchr(err, '\n') == NULL);
    err[0] = '\0';
    st = plx_bake_load(mem, BLOCK, NULL, f, len, &e, err, sizeof err);
    CHECK(st == PLX_OK || st == PLX_E_PARSE || st == PLX_E_UNSUPPORTED || st == PLX_E_NOMEM);
    if (st != PLX_OK) {
        CHECK(e == NULL);
        CHECK(err[0] != '\0' && strchr(err, '\n') == NULL);
    } else {
        CHECK(e != NULL && plx_engine_block(e) == mem);
        plx_engine_destroy(e);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static void *mem;
    uint8_t *fixed;
    uint64_t v;
    if (!mem && !(mem = malloc(BLOCK)))
        return 0;
    one(data, size, mem);
    if (size < 128 || memcmp(data, "PLXBAKE", 8) != 0)
        return 0;
    fixed = malloc(size);
    if (!fixed)
        return 0;
    memcpy(fixed, data, size);
    v = size;
    memcpy(fixed + 24, &v, 8);
    v = file_sum(fixed, size);
    memcpy(fixed + 32, &v, 8);
    one(fixed, size, mem);
    free(fixed);
    return 0;
}
