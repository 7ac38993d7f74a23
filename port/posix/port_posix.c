/* The POSIX port: clock_gettime, stderr logging, files read whole or
 * mapped read-only (mmap), a pthread mutex (no longer taken by the core),
 * and engines in a malloc'd block. */
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/mman.h>
#include <sys/stat.h>

#include "polarlux_port.h"
#include "port.h"
#include "posix/safe_out.h"

static pthread_mutex_t json_mutex = PTHREAD_MUTEX_INITIALIZER;

unsigned long long port_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (unsigned long long)ts.tv_sec * 1000000000ull + (unsigned long long)ts.tv_nsec;
}

void port_set_err(char *err, size_t errlen, const char *fmt, ...)
{
    va_list ap;
    if (err == NULL || errlen == 0)
        return;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

static uint64_t posix_clock(void *ctx)
{
    (void)ctx;
    return port_now_ns();
}

static void posix_log(void *ctx, plx_log_level level, const char *msg)
{
    static const char *const tag[] = { "error", "warning", "info" };
    (void)ctx;
    fprintf(stderr, "polarlux: %s: %s\n", tag[level <= PLX_LOG_INFO ? level : PLX_LOG_INFO], msg);
}

/* Opens an input without ever waiting on it: O_NONBLOCK (a FIFO with no
 * writer, a device) then fstat, so a FIFO, a device or a directory is
 * refused at once; the descriptor is then made blocking again. -1 and a
 * message on failure. */
int port_open_input(const char *path, size_t *size, char *err, size_t errlen)
{
    struct stat st;
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY);
    if (fd < 0) {
        snprintf(err, errlen, "cannot open: %s", strerror(errno));
        return -1;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "not a regular file (%s)", S_ISDIR(st.st_mode) ? "a directory"
                 : S_ISFIFO(st.st_mode) ? "a FIFO" : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                 : "a special file");
        close(fd);
        return -1;
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    if (size)
        *size = (size_t)st.st_size;
    return fd;
}

/* Reads exactly size bytes from fd and closes it. */
static int read_all(int fd, void *buf, size_t size, char *err, size_t errlen)
{
    size_t got = 0;
    while (got < size) {
        ssize_t r = read(fd, (char *)buf + got, size - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0) {
            snprintf(err, errlen, "read %zu of %zu bytes: %s", got, size,
                     r < 0 ? strerror(errno) : "file changed while reading");
            close(fd);
            return -1;
        }
        got += (size_t)r;
    }
    close(fd);
    return 0;
}

static int posix_file_size(void *ctx, const char *path, size_t *size, char *err, size_t errlen)
{
    int fd = port_open_input(path, size, err, errlen);
    (void)ctx;
    if (fd < 0)
        return -1;
    close(fd);
    return 0;
}

static int posix_file_read(void *ctx, const char *path, void *buf, size_t size, char *err, size_t errlen)
{
    size_t now;
    int fd = port_open_input(path, &now, err, errlen);
    (void)ctx;
    if (fd < 0)
        return -1;
    if (now != size) {
        snprintf(err, errlen, "file changed while reading (%zu bytes, was %zu)", now, size);
        close(fd);
        return -1;
    }
    return read_all(fd, buf, size, err, errlen);
}

/* What file_unmap needs: the mapping and its length. */
typedef struct posix_map {
    void *addr;
    size_t len;
} posix_map;

/* A private read-only mapping of the whole file (plx_port.file_map): the
 * same refusals as file_size (port_open_input: never waits on a FIFO or a
 * device). An empty file maps nothing (mmap refuses length 0). The kernel
 * is told the file will be read in order (POSIX_MADV_SEQUENTIAL: more read-ahead,
 * and pages already read are the first dropped under memory pressure). */
static int posix_file_map(void *ctx, const char *path, const void **data, size_t *size, void **handle,
                          char *err, size_t errlen)
{
    posix_map *m;
    size_t n;
    int fd = port_open_input(path, &n, err, errlen);
    (void)ctx;
    *data = NULL;
    *size = 0;
    *handle = NULL;
    if (fd < 0)
        return -1;
    if (n == 0) {
        close(fd);
        return 0;
    }
    m = malloc(sizeof *m);
    if (!m) {
        snprintf(err, errlen, "out of memory");
        close(fd);
        return -1;
    }
    m->addr = mmap(NULL, n, PROT_READ, MAP_PRIVATE, fd, 0);
    close(fd); /* the mapping keeps the file */
    if (m->addr == MAP_FAILED) {
        snprintf(err, errlen, "cannot map %zu bytes: %s", n, strerror(errno));
        free(m);
        return -1;
    }
    m->len = n;
    posix_madvise(m->addr, n, POSIX_MADV_SEQUENTIAL);
    *data = m->addr;
    *size = n;
    *handle = m;
    return 0;
}

static void posix_file_unmap(void *ctx, void *handle)
{
    posix_map *m = handle;
    (void)ctx;
    if (!m)
        return;
    munmap(m->addr, m->len);
    free(m);
}

static void posix_lock(void *ctx)
{
    (void)ctx;
    pthread_mutex_lock(&json_mutex);
}

static void posix_unlock(void *ctx)
{
    (void)ctx;
    pthread_mutex_unlock(&json_mutex);
}

static const plx_port posix_port = {
    NULL, posix_clock, posix_log, posix_file_size, posix_file_read, posix_lock, posix_unlock,
    port_parallel_for, port_cores, posix_file_map, posix_file_unmap,
    NULL, /* progress: the command sets its own (src/cli/common.c, cli_config) */
};

const plx_port *plx_port_posix(void)
{
    return &posix_port;
}


plx_status plx_engine_new(size_t budget, const plx_config *cfg, plx_engine **engine)
{
    void *mem;
    plx_status st;
    if (!engine)
        return PLX_E_INVALID;
    *engine = NULL;
    if (budget < PLX_ENGINE_MIN_BYTES)
        return PLX_E_INVALID;
    mem = malloc(budget);
    if (!mem)
        return PLX_E_NOMEM;
    st = plx_engine_create(mem, budget, cfg, engine);
    if (st != PLX_OK)
        free(mem);
    return st;
}

void plx_engine_free(plx_engine *e)
{
    void *mem;
    if (!e)
        return;
    mem = plx_engine_block(e);
    plx_engine_destroy(e);
    free(mem);
}

char *port_read_text(const char *path, size_t *len, char *err, size_t errlen)
{
    size_t size;
    char *buf;
    int fd = port_open_input(path, &size, err, errlen);
    if (fd < 0)
        return NULL;
    buf = size < (size_t)-1 ? malloc(size + 1) : NULL;
    if (!buf) {
        snprintf(err, errlen, "out of memory reading %zu bytes", size);
        close(fd);
        return NULL;
    }
    if (read_all(fd, buf, size, err, errlen) != 0) {
        free(buf);
        return NULL;
    }
    buf[size] = '\0';
    if (len)
        *len = size;
    return buf;
}

int port_write_atomic(const char *path, const void *data, size_t len, char *err, size_t errlen)
{
    safe_out *o = safe_out_open(path, err, errlen);
    if (!o)
        return -1;
    safe_out_write(o, data, len);
    return safe_out_commit(&o, 1, err, errlen);
}
