/* frame_writer: PNG frames written on a thread of their own while the
 * caller renders the next one (polarlux walk). One write at a time: a new
 * frame waits for the last write to finish, so a caller with two frame
 * buffers may render into the one not being written. Each frame's line
 * of a log (walk's cameras.txt) is appended and flushed once its PNG is
 * written, so the log lists the frames on disk, whenever the walk stops. */
#ifndef PLX_CLI_FRAME_WRITER_H
#define PLX_CLI_FRAME_WRITER_H

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>

typedef struct frame_writer {
    pthread_t th;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int busy, quit, failed;
    const uint8_t *rgb;
    int w, h;
    char path[4096], err[512];
    FILE *log;                  /* the log (NULL: none), named log_name */
    const char *log_name;
    char line[320];             /* the frame's line of it */
} frame_writer;

/* line appended to log (named name) and flushed: 0, or -1 with the
 * reason in err. */
int frame_log_line(FILE *log, const char *name, const char *line, char *err, size_t errlen);

/* Starts the thread, with the log log (named name; NULL: none); 0, or -1
 * when it could not be started. */
int frame_writer_start(frame_writer *fw, FILE *log, const char *name);

/* Waits for the write under way, then hands over rgb (w x h, kept by the
 * caller until the next put or stop) to be written to path, then line to
 * the log. Returns 0, or -1 when an earlier write failed (err says which
 * and why; nothing handed over). */
int frame_writer_put(frame_writer *fw, const char *path, const uint8_t *rgb, int w, int h, const char *line);

/* Waits for the last write and ends the thread: 0, or -1 when a write
 * failed (err). */
int frame_writer_stop(frame_writer *fw);

#endif
