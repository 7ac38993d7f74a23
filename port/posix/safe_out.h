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
/* Gives up: closes, removes the temporary file, frees. NULL is ignored. */
void safe_out_abort(safe_out *o);
/* "-" as an output: the data goes to the original standard output and
 * what the command prints on stdout from now on goes to stderr, so the
 * two never mix. Called by the command before any output. */
void safe_out_claim_stdout(void);

#endif
