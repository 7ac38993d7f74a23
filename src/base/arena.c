#include "base/arena.h"
#include "base/plx_assert.h"

/* Invariants (PLX_ASSERT in debug builds): lo + hi <= cap; the base is
 * PLX_ENGINE_ALIGN-aligned; every block handed out lies inside the free
 * middle and is aligned to its request (up to the base's alignment); marks
 * are released in stack order within the block. */

static size_t align_up(size_t v, size_t align)
{
    PLX_ASSERT(align != 0 && (align & (align - 1)) == 0 && align <= 64);
    return (v + align - 1) & ~(align - 1);
}

void arena_init(arena *a, void *mem, size_t size)
{
    size_t off = (size_t)(-(uintptr_t)mem) & (PLX_ENGINE_ALIGN - 1);
    size_t i;
    a->base = (unsigned char *)mem + off;
    a->cap = size > off ? size - off : 0;
    a->lo = a->hi = 0;
    a->peak_total = 0;
    for (i = 0; i < PLX_PART_COUNT; i++) {
        a->used[i] = a->peak[i] = a->budget[i] = 0;
    }
    a->requests = 0;
    a->fail_at = 0;
    a->failed_part = PLX_PART_ENGINE;
    a->failed_size = 0;
    a->failed_free = 0;
    PLX_ASSERT(((uintptr_t)a->base & (PLX_ENGINE_ALIGN - 1)) == 0 || a->cap == 0);
}

size_t arena_mul(size_t n, size_t size)
{
    if (size != 0 && n > SIZE_MAX / size)
        return SIZE_MAX;
    return n * size;
}

/* Records a refused request with the free bytes at this moment (read
 * later, the figure would count what the failed step released since). */
static int refuse(arena *a, plx_part part, size_t size, size_t align)
{
    size_t start = align_up(a->lo, align), top = a->cap - a->hi;
    a->failed_part = part;
    a->failed_size = size;
    a->failed_free = start < a->lo || start > top ? 0 : top - start;
    return 0;
}

/* Counts the request and checks fault injection and the part budget. */
static int admit(arena *a, plx_part part, size_t size, size_t align)
{
    a->requests++;
    if (a->fail_at != 0 && a->requests == a->fail_at)
        return refuse(a, part, size, align);
    if (a->budget[part] != 0 &&
        (size > a->budget[part] || a->used[part] > a->budget[part] - size))
        return refuse(a, part, size, align);
    return 1;
}

static void account(arena *a, plx_part part, size_t bytes)
{
    size_t total = a->lo + a->hi;
    PLX_ASSERT((unsigned)part < PLX_PART_COUNT);
    PLX_ASSERT(a->lo <= a->cap && a->hi <= a->cap - a->lo);
    a->used[part] += bytes;
    if (a->used[part] > a->peak[part])
        a->peak[part] = a->used[part];
    if (total > a->peak_total)
        a->peak_total = total;
}

void *arena_alloc(arena *a, plx_part part, size_t size, size_t align)
{
    size_t start, end;
    if (!admit(a, part, size, align))
        return NULL;
    if (size == 0)
        size = 1;
    start = align_up(a->lo, align);
    if (start < a->lo || start > a->cap - a->hi || size > a->cap - a->hi - start)
        return refuse(a, part, size, align), NULL;
    end = start + size;
    PLX_ASSERT(part != PLX_PART_SCRATCH && start % align == 0);
    {
        size_t grown = end - a->lo;
        a->lo = end;
        account(a, part, grown);
    }
    return a->base + start;
}

void *arena_calloc(arena *a, plx_part part, size_t n, size_t size, size_t align)
{
    size_t bytes = arena_mul(n, size);
    unsigned char *p;
    size_t i;
    if (bytes == SIZE_MAX)
        return (void)admit(a, part, bytes, align), refuse(a, part, bytes, align), NULL;
    p = arena_alloc(a, part, bytes, align);
    if (p)
        for (i = 0; i < bytes; i++)
            p[i] = 0;
    return p;
}

void *arena_scratch(arena *a, size_t size, size_t align)
{
    size_t top, start, avail;
    if (!admit(a, PLX_PART_SCRATCH, size, align))
        return NULL;
    if (size == 0)
        size = 1;
    avail = a->cap - a->hi - a->lo;
    if (size > avail)
        return refuse(a, PLX_PART_SCRATCH, size, align), NULL;
    top = a->cap - a->hi;
    start = (top - size) & ~(align - 1);
    if (start < a->lo)
        return refuse(a, PLX_PART_SCRATCH, size, align), NULL;
    PLX_ASSERT((align & (align - 1)) == 0 && start % align == 0 && start >= a->lo);
    a->hi = a->cap - start;
    account(a, PLX_PART_SCRATCH, top - start);
    return a->base + start;
}

arena_mark arena_get_mark(const arena *a)
{
    arena_mark m;
    size_t i;
    m.lo = a->lo;
    m.hi = a->hi;
    for (i = 0; i < PLX_PART_COUNT; i++)
        m.used[i] = a->used[i];
    return m;
}

void arena_release(arena *a, const arena_mark *m)
{
    size_t i;
    PLX_ASSERT(m->lo <= a->cap && m->hi <= a->cap - m->lo);
    a->lo = m->lo;
    a->hi = m->hi;
    for (i = 0; i < PLX_PART_COUNT; i++)
        a->used[i] = m->used[i];
}

size_t arena_free_bytes(const arena *a)
{
    return a->cap - a->lo - a->hi;
}
