/* ref_bake_sum: a bake file's checksum recomputed the way the README
 * ("Bake files") describes it, independently of src/api/bake.c: four
 * lanes over 64-bit words, each word w taken into its lane as
 * acc = rotl(acc + w K2, 31) K1, the header with its checksum field
 * (bytes 32..39) as 0, then the body; the lanes folded with the same step
 * and the result mixed by xor-shifts and multiplies. Header-only, shared
 * by tests/unit/test_bake.c and the fuzz target tests/fuzz/fuzz_bake.c
 * (built as one file). */
#ifndef REF_BAKE_SUM_H
#define REF_BAKE_SUM_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

static inline uint64_t ref_bake_step(uint64_t acc, uint64_t w)
{
    uint64_t x = acc + w * 0xd6e8feb86659fd93ull;
    x = (x << 31) | (x >> 33);
    return x * 0x9e3779b97f4a7c15ull;
}

static inline uint64_t ref_bake_sum(const uint8_t *f, size_t len)
{
    uint64_t h[4], w;
    uint8_t head[128];
    const uint8_t *parts[2];
    size_t lens[2], i, p;
    int k;
    for (k = 0; k < 4; k++)
        h[k] = 0xff51afd7ed558ccdull + (uint64_t)k;
    memcpy(head, f, 128);
    memset(head + 32, 0, 8);
    parts[0] = head; lens[0] = 128;
    parts[1] = f + 128; lens[1] = len - 128;
    for (p = 0; p < 2; p++) {
        for (i = 0; i + 32 <= lens[p]; i += 32)
            for (k = 0; k < 4; k++) {
                memcpy(&w, parts[p] + i + 8 * k, 8);
                h[k] = ref_bake_step(h[k], w);
            }
        for (; i < lens[p]; i++)
            h[0] = ref_bake_step(h[0], parts[p][i]);
    }
    w = h[0];
    for (k = 1; k < 4; k++)
        w = ref_bake_step(w, h[k]);
    w ^= w >> 33;
    w *= 0xff51afd7ed558ccdull;
    w ^= w >> 29;
    w *= 0xd6e8feb86659fd93ull;
    w ^= w >> 32;
    return w;
}

/* Makes a file of len >= 128 bytes self-consistent: its length field
 * (bytes 24..31) set to len, then its checksum field to the checksum. */
static inline void ref_bake_reseal(uint8_t *f, size_t len)
{
    uint64_t v = len;
    memcpy(f + 24, &v, 8);
    v = ref_bake_sum(f, len);
    memcpy(f + 32, &v, 8);
}

#endif
