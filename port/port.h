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
/* Writes data to path through a temporary file renamed into place, so a
 * crash never leaves a half-written file. 0 on success, else -1 and err. */
int port_write_atomic(const char *path, const void *data, size_t len, char *err, size_t errlen);
/* Monotonic clock in nanoseconds. */
unsigned long long port_now_ns(void);

#endif
