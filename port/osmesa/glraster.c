/* glraster: the renderer's visibility pass through OpenGL 1.1 (see glraster.h).
 * No context creation here: only GL calls on the current context. */
#include <string.h>

#include "glraster.h"

static int gl_begin(void *user, int32_t w, int32_t h, int cull_back)
{
    glraster *g = user;
    const gl_api *api = g->api;
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
    while (api->GetError() != GL_NO_ERROR)
        ;
    api->Viewport(0, 0, w, h);
    api->Scissor(0, 0, w, h);
    api->Enable(GL_SCISSOR_TEST);
    api->Disable(GL_DITHER);
    api->Disable(GL_BLEND);
    api->Disable(GL_LIGHTING);
    api->Disable(GL_TEXTURE_2D);
    api->Disable(GL_ALPHA_TEST);
    api->Disable(GL_STENCIL_TEST);
    api->Disable(GL_POLYGON_SMOOTH);
    api->Disable(GL_FOG);
    api->PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    api->ShadeModel(GL_FLAT);
    api->ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    api->MatrixMode(GL_PROJECTION);
    api->LoadIdentity();
    api->MatrixMode(GL_MODELVIEW);
    api->LoadIdentity();
    api->DepthRange(0.0, 1.0);
    api->Enable(GL_DEPTH_TEST);
    api->DepthFunc(GL_LESS);
    api->DepthMask(GL_TRUE);
    api->FrontFace(GL_CCW);
    api->CullFace(GL_BACK);
    if (cull_back)
        api->Enable(GL_CULL_FACE);
    else
        api->Disable(GL_CULL_FACE);
    api->ClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    api->ClearDepth(1.0);
    api->Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    return 0;
}

static void gl_draw(void *user, const float *clip, uint32_t nv, const mesh_tri *tri, uint32_t ntri,
                    uint32_t v_base)
{
    const gl_api *api = ((glraster *)user)->api;
    uint32_t k;
    int i;
    api->Begin(GL_TRIANGLES);
    for (k = 0; k < ntri; k++) {
        uint32_t id = tri[k].surf;
        api->Color4ub((GLubyte)(id & 255u), (GLubyte)((id >> 8) & 255u), (GLubyte)((id >> 16) & 255u),
                   (GLubyte)(id >> 24));
        for (i = 0; i < 3; i++) {
            uint32_t v = tri[k].v[i] - v_base;
            if (v < nv)
                api->Vertex4fv(clip + 4 * (size_t)v);
            else
                api->Vertex4f(0.0f, 0.0f, 0.0f, 1.0f);  /* never: keeps the triple aligned */
        }
    }
    api->End();
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
    const gl_api *api = g->api;
    size_t p, px = (size_t)g->w * (size_t)g->h;
    unsigned char *bytes = (unsigned char *)id;
    api->PixelStorei(GL_PACK_ALIGNMENT, 4);
    api->PixelStorei(GL_PACK_ROW_LENGTH, 0);
    api->ReadPixels(0, 0, g->w, g->h, GL_RGBA, GL_UNSIGNED_BYTE, id);
    api->ReadPixels(0, 0, g->w, g->h, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    if (api->GetError() != GL_NO_ERROR) {
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

void glraster_init(glraster *g, const gl_api *api, int32_t max_w, int32_t max_h,
                   int (*make_current)(void *ctx), void *ctx)
{
    memset(g, 0, sizeof *g);
    g->api = api;
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
