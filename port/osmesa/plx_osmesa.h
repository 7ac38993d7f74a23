/* plx_osmesa: the OSMesa port of the renderer's visibility pass.
 *
 *     plx_osmesa *om = plx_osmesa_open(1024, 768, err, sizeof err);
 *     plx_render_opts o;  plx_render_opts_default(&o);
 *     o.backend = plx_osmesa_backend(om);     // then plx_render as usual
 *     ...
 *     plx_osmesa_close(om);                    // after the last frame
 *
 * The same frame as the built-in software rasteriser, drawn by OpenGL into
 * an off-screen OSMesa buffer: only the raster pass (surface id and depth
 * per pixel) moves to GL; culling, exact shading, glows and tone mapping
 * stay in the core, so the two backends differ only on triangle edges.
 *
 * Context and GL code are apart: glraster.c holds every GL call and makes
 * no context; this file only creates the OSMesa context and its buffer.
 * Mesa 25.1 removed OSMesa: a replacement file would create an EGL
 * surfaceless context (EGL_MESA_platform_surfaceless), bind a framebuffer
 * object with RGBA8 colour and a depth attachment of max_w x max_h, and
 * hand the same glraster to the core -- glraster.c is unchanged.
 *
 * Build: only when `pkg-config --exists osmesa` (port/osmesa/osmesa.mk);
 * programs built with it see PLX_HAVE_OSMESA. Not part of libpolarlux:
 * link build/libpolarlux_osmesa.a and -ldl as well; libOSMesa is opened at
 * run time by the first plx_osmesa_open (gl_api.h).
 *
 * Memory: the context and a max_w x max_h RGBA8 buffer from the C heap,
 * freed by plx_osmesa_close. One object per thread; the context is made
 * current at the start of each frame.
 */
#ifndef PLX_OSMESA_H
#define PLX_OSMESA_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"

typedef struct plx_osmesa plx_osmesa;

/* Opens a context for frames up to max_w x max_h (1..16384), this way
 * round only: an engine draws frames either way round
 * (plx_config.render_max_width), the context does not, so to draw both
 * open it at the frames' own size or at the longer side squared. Returns
 * NULL on failure with a one-line reason in err (errlen bytes, may be 0). */
plx_osmesa *plx_osmesa_open(int32_t max_w, int32_t max_h, char *err, size_t errlen);

/* The backend to put in plx_render_opts.backend (or render_opts.backend);
 * valid until plx_osmesa_close. */
const plx_backend *plx_osmesa_backend(plx_osmesa *om);

/* The last failure of a frame ("" when none). */
const char *plx_osmesa_error(const plx_osmesa *om);

/* Destroys the context and frees the buffer; NULL is allowed. */
void plx_osmesa_close(plx_osmesa *om);

#endif
