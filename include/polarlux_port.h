/*
 * polarlux_port — the POSIX port and the PNG/PFM image files, outside the
 * portable core (library libpolarlux-port: port/posix, port/png).
 *
 * libpolarlux (include/polarlux.h) is the portable core alone: it needs
 * libc's string/math functions and libm (no cJSON: it reads JSON itself),
 * and reaches the platform only through the plx_port table the caller puts
 * in plx_config. A board or an application with its own platform layer
 * links libpolarlux alone. This library adds what a POSIX program wants: a
 * plx_port over clock_gettime, stderr and stdio, engines in a malloc'd
 * block, and image files. It needs libpng and pthreads:
 *
 *   cc app.c -lpolarlux-port -lpolarlux -lpng -lpthread -lm
 *
 * Thread-safety: every call here may be made from any thread. The port's
 * lock/unlock are one process-wide pthread mutex, which the core no longer
 * takes (loading touches no process-wide state).
 */
#ifndef POLARLUX_PORT_H
#define POLARLUX_PORT_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The POSIX services: clock_gettime (CLOCK_MONOTONIC), one line a message on
 * stderr, files read whole or mapped read-only (mmap), a parallel_for on a
 * pthread pool, the processor count, and a process-wide pthread mutex as
 * lock/unlock (not taken by the core). The table is static: valid for the
 * life of the process. Never fails. */
const plx_port *plx_port_posix(void);

/* Creates an engine in a block of 'budget' bytes taken from the C heap
 * (malloc). Errors: PLX_E_INVALID (engine NULL, budget below
 * PLX_ENGINE_MIN_BYTES), PLX_E_NOMEM (malloc failed), else those of
 * plx_engine_create. On failure *engine is NULL and nothing is held. */
plx_status plx_engine_new(size_t budget, const plx_config *cfg, plx_engine **engine /* OUT */);
/* Destroys an engine made by plx_engine_new and frees its block; NULL is a
 * no-op. Every pointer the engine gave out dies with it. */
void plx_engine_free(plx_engine *e);

/*
 * Image files (libpng). Rows top first, 3 bytes (R G B) a pixel. Each
 * writer writes a temporary file beside the output and renames it into
 * place, so the path holds either the whole new file or what was there
 * before. All return 0 on success, else -1 with one line in err (what, which
 * file, why; err may be NULL). They keep no state.
 */
/* An 8-bit sRGB PNG of width x height (1..1000000 each). */
int plx_png_write(const char *path, int width, int height, const uint8_t *rgb8,
                  char *err, size_t errlen);
/* Linear float RGB as a little-endian colour PFM (what plx_render's rgbf holds). */
int plx_pfm_write(const char *path, int width, int height, const float *rgbf,
                  char *err, size_t errlen);
/* Reads any PNG as packed 8-bit RGB into a new malloc'd buffer (*rgb8, freed
 * by the caller with free()), refusing images wider or taller than max_dim
 * (1..1000000) before taking pixel memory. On failure *rgb8 is NULL. */
int plx_png_read(const char *path, int max_dim, uint8_t **rgb8 /* OUT */, int *width /* OUT */,
                 int *height /* OUT */, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
