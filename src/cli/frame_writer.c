/* frame_writer: PNG frames written beside the rendering (frame_writer.h). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "frame_writer.h"
#include "png/image_write.h"

int frame_log_line(FILE *log, const char *name, const char *line, char *err, size_t errlen)
{
    if (!log)
        return 0;
    errno = 0;
    if (fputs(line, log) >= 0 && fflush(log) == 0)
        return 0;
    snprintf(err, errlen, "%s: cannot write: %s", name, errno ? strerror(errno) : "a write failed");
    return -1;
}

static void *writer_loop(void *arg)
{
    frame_writer *fw = arg;
    pthread_mutex_lock(&fw->mu);
    for (;;) {
        int rc;
        while (!fw->busy && !fw->quit)
            pthread_cond_wait(&fw->cv, &fw->mu);
        if (!fw->busy)
            break;
        pthread_mutex_unlock(&fw->mu);
        rc = image_write_png_frame(fw->path, fw->w, fw->h, fw->rgb, 0, fw->err, sizeof fw->err);
        if (rc == 0)
            rc = frame_log_line(fw->log, fw->log_name, fw->line, fw->err, sizeof fw->err);
        pthread_mutex_lock(&fw->mu);
        if (rc != 0)
            fw->failed = 1;
        fw->busy = 0;
        pthread_cond_broadcast(&fw->cv);
    }
    pthread_mutex_unlock(&fw->mu);
    return NULL;
}

int frame_writer_start(frame_writer *fw, FILE *log, const char *name)
{
    memset(fw, 0, sizeof *fw);
    fw->log = log;
    fw->log_name = name;
    if (pthread_mutex_init(&fw->mu, NULL) != 0)
        return -1;
    if (pthread_cond_init(&fw->cv, NULL) != 0) {
        pthread_mutex_destroy(&fw->mu);
        return -1;
    }
    if (pthread_create(&fw->th, NULL, writer_loop, fw) != 0) {
        pthread_cond_destroy(&fw->cv);
        pthread_mutex_destroy(&fw->mu);
        return -1;
    }
    return 0;
}

/* Waits until no write is under way (mutex held on return). */
static void wait_idle(frame_writer *fw)
{
    pthread_mutex_lock(&fw->mu);
    while (fw->busy)
        pthread_cond_wait(&fw->cv, &fw->mu);
}

int frame_writer_put(frame_writer *fw, const char *path, const uint8_t *rgb, int w, int h, const char *line)
{
    wait_idle(fw);
    if (fw->failed) {
        pthread_mutex_unlock(&fw->mu);
        return -1;
    }
    snprintf(fw->path, sizeof fw->path, "%s", path);
    snprintf(fw->line, sizeof fw->line, "%s", line);
    fw->rgb = rgb;
    fw->w = w;
    fw->h = h;
    fw->busy = 1;
    pthread_cond_broadcast(&fw->cv);
    pthread_mutex_unlock(&fw->mu);
    return 0;
}

int frame_writer_stop(frame_writer *fw)
{
    int failed;
    wait_idle(fw);
    fw->quit = 1;
    failed = fw->failed;
    pthread_cond_broadcast(&fw->cv);
    pthread_mutex_unlock(&fw->mu);
    pthread_join(fw->th, NULL);
    pthread_cond_destroy(&fw->cv);
    pthread_mutex_destroy(&fw->mu);
    return failed ? -1 : 0;
}
