/* The POSIX port: clock_gettime, stderr logging, stdio files, a pthread
 * mutex for JSON parsing, and engines in a malloc'd block. */
#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/stat.h>

#include "polarlux_port.h"
#include "port.h"

static pthread_mutex_t json_mutex = PTHREAD_MUTEX_INITIALIZER;

unsigned long long port_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (unsigned long long)ts.tv_sec * 1000000000ull + (unsigned long long)ts.tv_nsec;
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

static int posix_file_size(void *ctx, const char *path, size_t *size, char *err, size_t errlen)
{
    struct stat st;
    (void)ctx;
    if (stat(path, &st) != 0) {
        snprintf(err, errlen, "cannot open: %s", strerror(errno));
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "not a regular file");
        return -1;
    }
    *size = (size_t)st.st_size;
    return 0;
}

static int posix_file_read(void *ctx, const char *path, void *buf, size_t size, char *err, size_t errlen)
{
    FILE *f = fopen(path, "rb");
    size_t got;
    (void)ctx;
    if (!f) {
        snprintf(err, errlen, "cannot open: %s", strerror(errno));
        return -1;
    }
    got = fread(buf, 1, size, f);
    if (got != size || ferror(f)) {
        snprintf(err, errlen, "read %zu of %zu bytes: %s", got, size,
                 ferror(f) ? strerror(errno) : "file changed while reading");
        fclose(f);
        return -1;
    }
    fclose(f);
    return 0;
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
    if (posix_file_size(NULL, path, &size, err, errlen) != 0)
        return NULL;
    buf = malloc(size + 1);
    if (!buf) {
        snprintf(err, errlen, "out of memory reading %zu bytes", size);
        return NULL;
    }
    if (posix_file_read(NULL, path, buf, size, err, errlen) != 0) {
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
    char tmp[4096];
    int fd;
    FILE *f;
    if (snprintf(tmp, sizeof tmp, "%s.tmp.XXXXXX", path) >= (int)sizeof tmp) {
        snprintf(err, errlen, "%s: path too long", path);
        return -1;
    }
    fd = mkstemp(tmp);
    if (fd < 0) {
        snprintf(err, errlen, "%s: cannot create a temporary file beside it: %s", path, strerror(errno));
        return -1;
    }
    f = fdopen(fd, "wb");
    if (!f) {
        snprintf(err, errlen, "%s: %s", path, strerror(errno));
        close(fd);
        unlink(tmp);
        return -1;
    }
    if (fwrite(data, 1, len, f) != len || fflush(f) != 0) {
        snprintf(err, errlen, "%s: write failed: %s", path, strerror(errno));
        fclose(f);
        unlink(tmp);
        return -1;
    }
    if (fclose(f) != 0) {
        snprintf(err, errlen, "%s: write failed: %s", path, strerror(errno));
        unlink(tmp);
        return -1;
    }
    chmod(tmp, 0644);
    if (rename(tmp, path) != 0) {
        snprintf(err, errlen, "%s: cannot rename the temporary file into place: %s", path, strerror(errno));
        unlink(tmp);
        return -1;
    }
    return 0;
}
