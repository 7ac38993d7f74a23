/* glraster: the renderer's visibility pass through OpenGL 1.1 (see glraster.h).
 * No context creation here: only GL calls on the current context. */
#include <string.h>
#include <GL/gl.h>

#include "glraster.h"

static int gl_begin(void *user, int32_t w, int32_t h, int cull_back)
{
    glraster *g = user;
    if (w < 1 || h < 1 || w > g->max_w || h > g->max_h) {
        g->err = "the frame is larger than the GL buffers";
        return -1;
    }
    if (g->make_current && g->make_current(g->ctx) != 0) {
        g->err = "cannot make the GL context current";
        return -1;
    }
    g->w = w;
    g->h = h;
    while (glGetError() != GL_NO_ERROR)
        ;
    glViewport(0, 0, w, h);
    glScissor(0, 0, w, h);
    glEnable(GL_SCISSOR_TEST);
    glDisable(GL_DITHER);
    glDisable(GL_BLEND);
    glDisable(GL_LIGHTING);
    glDisable(GL_TEXTURE_2D);
    glDisable(GL_ALPHA_TEST);
    glDisable(GL_STENCIL_TEST);
    glDisable(GL_POLYGON_SMOOTH);
    glDisable(GL_FOG);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glShadeModel(GL_FLAT);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glDepthRange(0.0, 1.0);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glFrontFace(GL_CCW);
    glCullFace(GL_BACK);
    if (cull_back)
        glEnable(GL_CULL_FACE);
    else
        glDisable(GL_CULL_FACE);
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    return 0;
}

static void gl_draw(void *user, const float *clip, uint32_t nv, const mesh_tri *tri, uint32_t ntri,
                    uint32_t v_base)
{
    uint32_t k;
    int i;
    (void)user;
    glBegin(GL_TRIANGLES);
    for (k = 0; k < ntri; k++) {
        uint32_t id = tri[k].surf;
        glColor4ub((GLubyte)(id & 255u), (GLubyte)((id >> 8) & 255u), (GLubyte)((id >> 16) & 255u),
                   (GLubyte)(id >> 24));
        for (i = 0; i < 3; i++) {
            uint32_t v = tri[k].v[i] - v_base;
            if (v < nv)
                glVertex4fv(clip + 4 * (size_t)v);
            else
                glVertex4f(0.0f, 0.0f, 0.0f, 1.0f);  /* never: keeps the triple aligned */
        }
    }
    glEnd();
}

/* Swaps rows j and h-1-j of a w x h array of 4-byte elements. */
static void flip_rows(void *buf, int32_t w, int32_t h)
{
    uint32_t *p = buf;
    int32_t j, i;
    for (j = 0; j < h / 2; j++) {
        uint32_t *a = p + (size_t)j * (size_t)w, *b = p + (size_t)(h - 1 - j) * (size_t)w;
        for (i = 0; i < w; i++) {
            uint32_t t = a[i];
            a[i] = b[i];
            b[i] = t;
        }
    }
}

static int gl_finish(void *user, uint32_t *id, float *depth)
{
    glraster *g = user;
    size_t p, px = (size_t)g->w * (size_t)g->h;
    unsigned char *bytes = (unsigned char *)id;
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    glReadPixels(0, 0, g->w, g->h, GL_RGBA, GL_UNSIGNED_BYTE, id);
    glReadPixels(0, 0, g->w, g->h, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    if (glGetError() != GL_NO_ERROR) {
        g->err = "glReadPixels failed";
        return -1;
    }
    /* bytes R G B A of pixel p -> id, in place (each pixel read before it is written) */
    for (p = 0; p < px; p++) {
        const unsigned char *c = bytes + 4 * p;
        id[p] = (uint32_t)c[0] | (uint32_t)c[1] << 8 | (uint32_t)c[2] << 16 | (uint32_t)c[3] << 24;
    }
    flip_rows(id, g->w, g->h);
    flip_rows(depth, g->w, g->h);
    return 0;
}

void glraster_init(glraster *g, int32_t max_w, int32_t max_h, int (*make_current)(void *ctx), void *ctx)
{
    memset(g, 0, sizeof *g);
    g->max_w = max_w;
    g->max_h = max_h;
    g->make_current = make_current;
    g->ctx = ctx;
    g->err = "";
    g->be.name = "gl";
    g->be.user = g;
    g->be.begin = gl_begin;
    g->be.draw = gl_draw;
    g->be.finish = gl_finish;
}
