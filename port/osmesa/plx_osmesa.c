/* plx_osmesa: an OSMesa context for glraster (see plx_osmesa.h). */
#include <stdio.h>
#include <stdlib.h>

#include "plx_osmesa.h"
#include "glraster.h"

struct plx_osmesa {
    gl_api api;
    osmesa_api osm;
    glraster gl;
    OSMesaContext ctx;
    unsigned char *buf;
    int32_t w, h;
};

/* Mesa keeps a few small blocks for the life of the process (its loader and
 * per-thread state, not freed by OSMesaDestroyContext); LeakSanitizer would
 * report them in every program that opened a context. This hook (read by
 * LeakSanitizer when present, unused otherwise) leaves out leaks whose
 * stack holds libOSMesa; leaks of polarlux's own code are still reported. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
    return "leak:libOSMesa.so\n";
}

static int make_current(void *user)
{
    plx_osmesa *om = user;
    return om->osm.MakeCurrent(om->ctx, om->buf, GL_UNSIGNED_BYTE, om->w, om->h) ? 0 : -1;
}

plx_osmesa *plx_osmesa_open(int32_t max_w, int32_t max_h, char *err, size_t errlen)
{
    static const GLint depths[] = { 32, 24 };
    plx_osmesa *om;
    size_t k;
    if (max_w < 1 || max_h < 1 || max_w > 16384 || max_h > 16384) {
        if (errlen)
            snprintf(err, errlen, "osmesa: frame size %dx%d outside 1..16384", (int)max_w, (int)max_h);
        return NULL;
    }
    om = calloc(1, sizeof *om);
    if (!om || !(om->buf = malloc((size_t)max_w * (size_t)max_h * 4))) {
        if (errlen)
            snprintf(err, errlen, "osmesa: out of memory for a %dx%d buffer", (int)max_w, (int)max_h);
        free(om);
        return NULL;
    }
    om->w = max_w;
    om->h = max_h;
    if (gl_api_load(&om->api, &om->osm, err, errlen) != 0) {
        plx_osmesa_close(om);
        return NULL;
    }
    /* the deepest depth buffer the driver gives */
    for (k = 0; k < sizeof depths / sizeof depths[0] && !om->ctx; k++)
        om->ctx = om->osm.CreateContextExt(OSMESA_RGBA, depths[k], 0, 0, NULL);
    if (!om->ctx || make_current(om) != 0) {
        if (errlen)
            snprintf(err, errlen, "osmesa: cannot create an RGBA context with a depth buffer");
        plx_osmesa_close(om);
        return NULL;
    }
    om->osm.PixelStore(OSMESA_Y_UP, 1);
    glraster_init(&om->gl, &om->api, max_w, max_h, make_current, om);
    om->gl.be.name = "osmesa";
    return om;
}

const plx_backend *plx_osmesa_backend(plx_osmesa *om)
{
    return om ? &om->gl.be : NULL;
}

const char *plx_osmesa_error(const plx_osmesa *om)
{
    return om ? om->gl.err : "";
}

void plx_osmesa_close(plx_osmesa *om)
{
    if (!om)
        return;
    if (om->ctx)
        om->osm.DestroyContext(om->ctx);
    free(om->buf);
    free(om);
}
