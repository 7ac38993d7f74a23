/* failwrite: an LD_PRELOAD stand-in for a full or failing disk, for the
 * safe-output tests (tests/cli/hostile.sh) where a small tmpfs cannot be
 * mounted. write(2) and fsync(2) on a file whose path contains
 * $PLX_FAILWRITE_MATCH fail once $PLX_FAILWRITE_AFTER bytes (default 0)
 * have gone to such files: with ENOSPC, or the errno named by
 * $PLX_FAILWRITE_ERRNO (EIO, EFBIG), or, with "SHORT", by writing 0 bytes
 * (a short write). fsync and syncfs fail with EIO when $PLX_FAILWRITE_FSYNC
 * is set.
 * Everything else goes to the C library. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static size_t written;

static int matches(int fd)
{
    const char *m = getenv("PLX_FAILWRITE_MATCH");
    char link[64], path[4096];
    ssize_t n;
    if (!m || !*m)
        return 0;
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    n = readlink(link, path, sizeof path - 1);
    if (n < 0)
        return 0;
    path[n] = '\0';
    return strstr(path, m) != NULL;
}

ssize_t write(int fd, const void *buf, size_t len)
{
    ssize_t (*real)(int, const void *, size_t);
    *(void **)&real = dlsym(RTLD_NEXT, "write");
    if (matches(fd)) {
        const char *after = getenv("PLX_FAILWRITE_AFTER"), *e = getenv("PLX_FAILWRITE_ERRNO");
        size_t limit = after ? (size_t)strtoull(after, NULL, 10) : 0;
        if (written + len > limit) {
            if (e && strcmp(e, "SHORT") == 0)
                return 0;
            errno = e && strcmp(e, "EIO") == 0 ? EIO : e && strcmp(e, "EFBIG") == 0 ? EFBIG : ENOSPC;
            return -1;
        }
        written += len;
    }
    return real(fd, buf, len);
}

int fsync(int fd)
{
    int (*real)(int);
    *(void **)&real = dlsym(RTLD_NEXT, "fsync");
    if (getenv("PLX_FAILWRITE_FSYNC") && matches(fd)) {
        errno = EIO;
        return -1;
    }
    return real(fd);
}

int syncfs(int fd)
{
    int (*real)(int);
    *(void **)&real = dlsym(RTLD_NEXT, "syncfs");
    if (getenv("PLX_FAILWRITE_FSYNC") && matches(fd)) {
        errno = EIO;
        return -1;
    }
    return real(fd);
}
