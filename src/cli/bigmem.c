/* Large blocks for engines and bake files: 2 MiB aligned and, where the
 * system offers it, backed by huge pages, so that touching a few hundred
 * megabytes costs a few hundred page faults instead of tens of thousands
 * (on virtual machines a page fault costs tens of microseconds). */
#define _DEFAULT_SOURCE 1
#include <stdlib.h>
#include <sys/mman.h>

#include "cli.h"

void *cli_big_alloc(size_t size)
{
    void *p = NULL;
    size_t align = (size_t)2 << 20;
    if (posix_memalign(&p, align, size) != 0)
        return NULL;
#ifdef MADV_HUGEPAGE
    if (size >= align)
        madvise(p, size & ~(align - 1), MADV_HUGEPAGE);
#endif
    return p;
}

