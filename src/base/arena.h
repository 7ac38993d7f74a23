/* arena: the caller's one block of memory, split into parts.
 *
 * Persistent memory grows from the low end, scratch memory (live only during
 * one call) from the high end. Both are released by marks, never one by one.
 * Every request is counted per part with a high-water mark, and any request
 * can be made to fail (fault injection).
 */
#ifndef PLX_ARENA_H
#define PLX_ARENA_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"

typedef struct arena {
    unsigned char *base;
    size_t cap;
    size_t lo;                      /* bytes used from the low end */
    size_t hi;                      /* bytes used from the high end */
    size_t peak_total;
    size_t used[PLX_PART_COUNT];
    size_t peak[PLX_PART_COUNT];
    size_t budget[PLX_PART_COUNT];  /* 0 = no per-part limit */
    uint64_t requests;              /* requests served or refused */
    uint64_t fail_at;               /* 0 = off, else the request number that fails */
    plx_part failed_part;           /* part of the last refused request */
    size_t failed_size;             /* bytes it asked for */
    size_t failed_free;             /* bytes it could have had when refused: the free
                                     * middle less its alignment padding (for a request
                                     * the block refused, less than failed_size) */
} arena;

/* A position to roll back to; taken and released in stack order. */
typedef struct arena_mark {
    size_t lo, hi;
    size_t used[PLX_PART_COUNT];
} arena_mark;

void arena_init(arena *a, void *mem, size_t size);
/* Persistent memory for 'part', aligned to 'align' (a power of two <= 64).
 * NULL when the block or the part's budget is exhausted. */
void *arena_alloc(arena *a, plx_part part, size_t size, size_t align);
/* The same, zero-filled. */
void *arena_calloc(arena *a, plx_part part, size_t n, size_t size, size_t align);
/* Scratch memory from the high end, counted as PLX_PART_SCRATCH. */
void *arena_scratch(arena *a, size_t size, size_t align);
arena_mark arena_get_mark(const arena *a);
void arena_release(arena *a, const arena_mark *m);
size_t arena_free_bytes(const arena *a);
/* Bytes a multiplication would need, or SIZE_MAX on overflow. */
size_t arena_mul(size_t n, size_t size);

#endif
