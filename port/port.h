/* port: what differs per platform. The core reaches the platform only
 * through the plx_port function table (include/polarlux.h) that the caller
 * puts in plx_config; port/posix provides the POSIX one. This header lists
 * the port-side helpers shared by the command and the tests. */
#ifndef PLX_PORT_H
#define PLX_PORT_H

#include <stddef.h>
#include "polarlux_port.h"

/* Reads a whole file into a malloc'd NUL-terminated buffer; NULL and a
 * reason in err on failure. The caller frees it. */
char *port_read_text(const char *path, size_t *len, char *err, size_t errlen);
/* Opens a file for reading without waiting on it (O_NONBLOCK, then
 * fstat): a FIFO, a device or a directory is refused with "not a regular
 * file (a FIFO)". Returns a blocking descriptor and the size, or -1. */
int port_open_input(const char *path, size_t *size, char *err, size_t errlen);
/* Writes data to path through a temporary file renamed into place, so a
 * crash never leaves a half-written file. 0 on success, else -1 and err. */
int port_write_atomic(const char *path, const void *data, size_t len, char *err, size_t errlen);
/* plx_port_posix's parallel-for (pthreads, port/posix/parallel.c) and
 * processor count (sysconf, 1 .. PLX_MAX_THREADS). */
int port_parallel_for(void *ctx, int workers, uint32_t njobs, void (*job)(void *arg, int worker, uint32_t k),
                      void *arg);
int port_cores(void *ctx);
/* The machine's physical memory in bytes (sysconf), 0 when unknown. */
unsigned long long port_memory_bytes(void);
/* Monotonic clock in nanoseconds. */
unsigned long long port_now_ns(void);
/* The message fmt, ... into err (errlen bytes, cut to fit); nothing when
 * err is NULL or errlen 0. */
void port_set_err(char *err, size_t errlen, const char *fmt, ...);

#endif
