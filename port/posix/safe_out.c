/* realpath() is an XSI function of POSIX.1-2008; syncfs() (a batch's one
 * sync) is Linux's. */
#ifdef __linux__
#define _GNU_SOURCE
#else
#define _XOPEN_SOURCE 700
#endif
/* safe_out: outputs written through an exclusive temporary file and a
 * rename, or directly when the target is not a regular file. See
 * safe_out.h for the rules. */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

#include "port.h"
#include "safe_out.h"

#define SAFE_OUT_BUF 65536

struct safe_out {
    char *target;      /* the file finally written (a symlink resolved) */
    char *tmp;         /* the temporary file, NULL when written directly */
    int fd;
    int close_fd;      /* 0 for standard output */
    int err;           /* first write errno, sticky */
    mode_t mode;       /* permission bits of an existing target */
    int keep_mode;
    int batch;         /* committed without a sync (safe_out_open_batch) */
    size_t used;
    unsigned char buf[SAFE_OUT_BUF];
};

/* The descriptor "-" writes to (standard output unless claimed). */
static int stdout_fd = 1;

void safe_out_claim_stdout(void)
{
    int fd;
    if (stdout_fd != 1)
        return;
    fflush(stdout);
    fd = dup(1);
    if (fd < 0)
        return;
    stdout_fd = fd;
    dup2(2, 1);
}

static char *dup_str(const char *s)
{
    char *d = malloc(strlen(s) + 1);
    if (d)
        strcpy(d, s);
    return d;
}

/* Whether the folder that would hold target is missing or no folder: then
 * says so in err (what a user can act on, rather than the temporary
 * file's name and errno). */
static int folder_missing(const char *target, char *err, size_t errlen)
{
    const char *slash = strrchr(target, '/');
    char *dir;
    struct stat st;
    int missing;
    if (!slash || slash == target)
        return 0;
    dir = malloc((size_t)(slash - target) + 1);
    if (!dir)
        return 0;
    memcpy(dir, target, (size_t)(slash - target));
    dir[slash - target] = '\0';
    missing = stat(dir, &st) != 0;
    if (missing)
        port_set_err(err, errlen, "cannot write '%s': the folder '%s' does not exist", target, dir);
    else if (!S_ISDIR(st.st_mode))
        port_set_err(err, errlen, "cannot write '%s': '%s' is not a folder", target, dir);
    missing = missing || !S_ISDIR(st.st_mode);
    free(dir);
    return missing;
}

/* The regular-file case: an exclusive temporary file beside target. */
static int open_temp(safe_out *o, char *err, size_t errlen)
{
    size_t n = strlen(o->target) + 48;
    int k;
    o->tmp = malloc(n);
    if (!o->tmp) {
        port_set_err(err, errlen, "'%s': out of memory for the temporary file name", o->target);
        return -1;
    }
    for (k = 0; k < 1000; k++) {
        snprintf(o->tmp, n, "%s.tmp.%ld.%d", o->target, (long)getpid(), k);
        o->fd = open(o->tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW, 0666);
        if (o->fd >= 0 || errno != EEXIST)
            break;
    }
    if (o->fd < 0 && (errno == ENOENT || errno == ENOTDIR) && folder_missing(o->target, err, errlen))
        return -1;
    if (o->fd < 0) {
        port_set_err(err, errlen, "cannot create a temporary file for '%s' ('%s'): %s", o->target, o->tmp,
                strerror(errno));
        return -1;
    }
    o->close_fd = 1;
    return 0;
}

/* A device, FIFO or socket: written in place, never replaced. */
static int open_direct(safe_out *o, char *err, size_t errlen)
{
    o->fd = open(o->target, O_WRONLY | O_NOCTTY);
    if (o->fd < 0) {
        port_set_err(err, errlen, "cannot open '%s': %s", o->target, strerror(errno));
        return -1;
    }
    o->close_fd = 1;
    return 0;
}

static void free_out(safe_out *o)
{
    free(o->target);
    free(o->tmp);
    free(o);
}

safe_out *safe_out_open(const char *path, char *err, size_t errlen)
{
    safe_out *o;
    struct stat st;
    int rc;
    if (!path || !*path) {
        port_set_err(err, errlen, "empty output file name");
        return NULL;
    }
    o = calloc(1, sizeof *o);
    if (!o) {
        port_set_err(err, errlen, "'%s': out of memory", path);
        return NULL;
    }
    o->fd = -1;
    if (strcmp(path, "-") == 0) {
        o->target = dup_str("-");
        o->fd = stdout_fd;
        if (!o->target) {
            free_out(o);
            return NULL;
        }
        return o;
    }
    if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode)) {
        char *real = realpath(path, NULL);
        if (!real) {
            port_set_err(err, errlen, "'%s' is a symbolic link to nowhere: %s", path, strerror(errno));
            free_out(o);
            return NULL;
        }
        o->target = real;
    } else {
        o->target = dup_str(path);
    }
    if (!o->target) {
        port_set_err(err, errlen, "'%s': out of memory", path);
        free_out(o);
        return NULL;
    }
    if (stat(o->target, &st) == 0 && S_ISDIR(st.st_mode)) {
        port_set_err(err, errlen, "'%s' is a directory", path);
        free_out(o);
        return NULL;
    }
    if (stat(o->target, &st) == 0 && !S_ISREG(st.st_mode)) {
        rc = open_direct(o, err, errlen);
    } else {
        o->keep_mode = stat(o->target, &st) == 0;
        o->mode = st.st_mode & 07777;
        rc = open_temp(o, err, errlen);
    }
    if (rc != 0) {
        free_out(o);
        return NULL;
    }
    return o;
}

static void drain(safe_out *o)
{
    size_t off = 0;
    while (off < o->used && o->err == 0) {
        ssize_t w = write(o->fd, o->buf + off, o->used - off);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            o->err = w < 0 ? errno : ENOSPC;
        else
            off += (size_t)w;
    }
    o->used = 0;
}

int safe_out_write(safe_out *o, const void *data, size_t len)
{
    const unsigned char *p = data;
    while (len > 0 && o->err == 0) {
        size_t k = SAFE_OUT_BUF - o->used;
        if (k > len)
            k = len;
        memcpy(o->buf + o->used, p, k);
        o->used += k;
        p += k;
        len -= k;
        if (o->used == SAFE_OUT_BUF)
            drain(o);
    }
    return o->err ? -1 : 0;
}

int safe_out_errno(const safe_out *o)
{
    return o->err;
}

void safe_out_abort(safe_out *o)
{
    if (!o)
        return;
    if (o->close_fd)
        close(o->fd);
    if (o->tmp)
        unlink(o->tmp);
    free_out(o);
}

/* Flush, sync and close one output; 0 or an errno. */
static int finish_one(safe_out *o)
{
    drain(o);
    if (o->err)
        return o->err;
    if (o->tmp) {
        if (o->keep_mode && fchmod(o->fd, o->mode) != 0)
            return errno;
        if (!o->batch && fsync(o->fd) != 0)
            return errno;
    }
    if (o->close_fd) {
        o->close_fd = 0;
        if (close(o->fd) != 0)
            return errno;
    }
    return 0;
}

/* Makes the renames durable: syncs the folder of target (best effort). */
static void sync_folder(const char *target)
{
    const char *slash = strrchr(target, '/');
    char dir[PATH_MAX];
    int fd;
    if (!slash)
        strcpy(dir, ".");
    else if ((size_t)(slash - target) + 2 > sizeof dir)
        return;
    else {
        memcpy(dir, target, (size_t)(slash - target) + 1);
        dir[slash - target + 1] = '\0';
    }
    fd = open(dir, O_RDONLY);
    if (fd >= 0) {
        fsync(fd);
        close(fd);
    }
}

int safe_out_commit(safe_out **outs, size_t n, char *err, size_t errlen)
{
    size_t i;
    int rc = 0;
    for (i = 0; i < n && rc == 0; i++) {
        int e = finish_one(outs[i]);
        if (e) {
            port_set_err(err, errlen, "cannot write '%s': %s", outs[i]->target, strerror(e));
            rc = -1;
        }
    }
    for (i = 0; i < n && rc == 0; i++) {
        if (outs[i]->tmp && rename(outs[i]->tmp, outs[i]->target) != 0) {
            port_set_err(err, errlen, "cannot rename '%s' to '%s': %s", outs[i]->tmp, outs[i]->target,
                    strerror(errno));
            rc = -1;
            break;
        }
        if (outs[i]->tmp) {
            if (!outs[i]->batch)
                sync_folder(outs[i]->target);
            free(outs[i]->tmp);
            outs[i]->tmp = NULL;
        }
    }
    for (i = 0; i < n; i++)
        safe_out_abort(outs[i]);
    return rc;
}

safe_out *safe_out_open_batch(const char *path, char *err, size_t errlen)
{
    safe_out *o = safe_out_open(path, err, errlen);
    if (o)
        o->batch = 1;
    return o;
}

int safe_out_batch_begin(const char *dir, char *err, size_t errlen)
{
    char tmp[PATH_MAX];
    int fd = open(dir, O_RDONLY), e = errno, k;
    if (fd >= 0)
        return fd;
    /* a folder one may write but not read (mode 0300): a file of its
     * own there, removed at once, names the file system to sync */
    for (k = 0; k < 1000 && fd < 0; k++) {
        if (snprintf(tmp, sizeof tmp, "%s/.sync.%ld.%d", dir, (long)getpid(), k) >= (int)sizeof tmp)
            break;
        fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW, 0600);
        if (fd < 0 && errno != EEXIST)
            break;
    }
    if (fd >= 0) {
        unlink(tmp);
        return fd;
    }
    port_set_err(err, errlen, "cannot open the folder '%s': %s", dir, strerror(e));
    return -1;
}

/* The file system's data written back: Linux's syncfs, which reports a
 * write-back error met since fd was opened; elsewhere sync(), which
 * reports none (the outputs' own write and close errors still are). */
static int sync_all(int fd)
{
#ifdef __linux__
    return syncfs(fd);
#else
    (void)fd;
    sync();
    return 0;
#endif
}

int safe_out_batch_end(int fd, const char *dir, int commit, char *err, size_t errlen)
{
    int rc = 0;
    if (fd < 0)
        return 0;
    if (commit && sync_all(fd) != 0) {
        port_set_err(err, errlen, "cannot write the files in '%s' to disk: %s", dir, strerror(errno));
        rc = -1;
    }
    if (commit && rc == 0)
        (void)fsync(fd); /* the renames (best effort, as one output's commit: not every file system syncs
                            folders; on the stand-in file of an unreadable folder, nothing) */
    close(fd);
    return rc;
}
