/* safe_out: every output file of the command and the image writers.
 *
 * The rules (README, "Safe outputs"):
 *  - A regular file (or a name that does not exist yet) is written through a
 *    temporary file in the same folder, "<target>.tmp.<pid>.<n>", created
 *    exclusively (O_CREAT|O_EXCL), then flushed to disk (fsync), closed,
 *    checked and renamed over the target. An existing target keeps its
 *    permission bits. On any error the temporary file is removed and the
 *    target is left as it was.
 *  - A symbolic link is followed: the file it points to is the target (the
 *    link stays a link).
 *  - A target that is not a regular file (a character or block device, a
 *    FIFO, a socket) is opened and written directly, never renamed over;
 *    "-" is standard output. A directory is refused.
 *  - Outputs that belong together (an image and its PFM) are committed with
 *    one safe_out_commit call: nothing is renamed unless every one of them
 *    was written and synced.
 * Writes go through write(2) with a buffer of its own; a short write, EIO,
 * ENOSPC or EFBIG is sticky and reported by safe_out_commit. Messages are
 * one line: "cannot write 'out.png': No space left on device". */
#ifndef PLX_SAFE_OUT_H
#define PLX_SAFE_OUT_H

#include <stddef.h>

typedef struct safe_out safe_out;

/* Opens path for writing; NULL with a message in err on failure. */
safe_out *safe_out_open(const char *path, char *err, size_t errlen);
/* Appends len bytes; 0, or -1 once any write has failed (sticky). */
int safe_out_write(safe_out *o, const void *data, size_t len);
/* The errno of the first failed write (0 if none). */
int safe_out_errno(const safe_out *o);
/* Flushes, syncs and closes every one of outs[0..n-1], then renames the
 * temporary files into place, only if all of them succeeded. Frees them
 * all. 0, or -1 with a message naming the first failure. */
int safe_out_commit(safe_out **outs, size_t n, char *err, size_t errlen);
/* A batch: many outputs in one folder (walk's frames), each opened with
 * safe_out_open_batch, written and committed as any other (checked,
 * renamed into place, its temporary file removed on an error) but
 * without a sync, then all made durable together by safe_out_batch_end:
 * one sync of the folder's file system instead of two a file (a file's
 * fsync and its folder's cost milliseconds on an SD card). Until then a
 * crash may leave a committed file of the batch empty or cut short, also
 * one that replaced an earlier file (the rename may reach the disk before
 * the data).
 * safe_out_batch_begin opens dir before the batch's first output (so a
 * write-back error met during the batch is reported at its end; a folder
 * that cannot be read, a stand-in file made and removed in it): a handle,
 * or -1 with a message. safe_out_batch_end syncs (when commit is
 * non-zero) and closes it: 0, or -1 with a message when the file system
 * reports a failed write-back. On Linux that is syncfs(), which reports
 * write-back errors since kernel 5.8 (before, it returns 0), for the
 * whole file system: a failure of another program's file there is
 * reported too, and an output that is a symbolic link to another file
 * system is neither synced nor checked. Elsewhere it is sync(), which
 * reports nothing and may return before the data is written. A handle of
 * -1 is ignored. */
safe_out *safe_out_open_batch(const char *path, char *err, size_t errlen);
int safe_out_batch_begin(const char *dir, char *err, size_t errlen);
int safe_out_batch_end(int fd, const char *dir, int commit, char *err, size_t errlen);
/* Gives up: closes, removes the temporary file, frees. NULL is ignored. */
void safe_out_abort(safe_out *o);
/* "-" as an output: the data goes to the original standard output and
 * what the command prints on stdout from now on goes to stderr, so the
 * two never mix. Called by the command before any output. */
void safe_out_claim_stdout(void);

#endif
