/* glraster: the visibility pass of the renderer (render.h, render_backend)
 * through OpenGL 1.1 calls only, independent of how the context was made.
 *
 * The core gives each visible building's triangles in clip space; they are
 * drawn with identity matrices (so GL's clipping, perspective division and
 * viewport transform are the ones raster.h documents), flat-shaded with the
 * 32-bit surface id as the colour (R = bits 0-7, G = 8-15, B = 16-23,
 * A = 24-31; no blending, dithering, lighting or texturing, so the bytes
 * arrive unchanged), depth test GL_LESS, back faces culled as raster.h's
 * RASTER_CULL_BACK (counter-clockwise front faces) when asked. finish reads
 * the colour and depth buffers back with glReadPixels, turns the colour
 * into ids and flips the rows (GL's row 0 is the bottom).
 *
 * What the context must provide (the context file's job: plx_osmesa.c for
 * OSMesa; an EGL surfaceless context would bind a framebuffer object with
 * an RGBA8 colour and a depth attachment instead): a current context whose
 * bound framebuffer has 8 bits in each of R, G, B and A, a depth buffer,
 * and at least max_w x max_h pixels; frames use its lower-left w x h
 * corner. make_current (may be NULL) is called at the start of every frame.
 *
 * Memory: none of its own; the id buffer given to finish is used as the
 * read-back area for the colour bytes (4 bytes per pixel, like an id).
 */
#ifndef PLX_GLRASTER_H
#define PLX_GLRASTER_H

#include <stdint.h>
#include "render/render.h"
#include "gl_api.h"

typedef struct glraster {
    render_backend be;              /* be.user = this */
    const gl_api *api;              /* the GL functions (gl_api.h) */
    int32_t max_w, max_h, w, h;
    int (*make_current)(void *ctx);  /* returns 0 on success */
    void *ctx;
    const char *err;                /* last failure, "" when none */
} glraster;

/* Fills g (and g->be) for frames up to max_w x max_h, drawing through api
 * (which must outlive g). */
void glraster_init(glraster *g, const gl_api *api, int32_t max_w, int32_t max_h,
                   int (*make_current)(void *ctx), void *ctx);

#endif
