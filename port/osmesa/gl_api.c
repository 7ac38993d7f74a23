/* gl_api: libOSMesa opened at run time (see gl_api.h). */
#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

#include "gl_api.h"

/* The names dlopen tries: the library's SONAME, then the development link. */
static const char *const libnames[] = { "libOSMesa.so.8", "libOSMesa.so" };

/* dlsym returns an object pointer; C99 has no cast from it to a function
 * pointer, so its bytes are copied (POSIX guarantees they are the same). */
static int find(void *lib, const char *name, void *fn, size_t fn_size, char *err, size_t errlen)
{
    void *p = dlsym(lib, name);
    if (!p) {
        if (errlen)
            snprintf(err, errlen, "osmesa: libOSMesa has no %s", name);
        return -1;
    }
    memcpy(fn, &p, fn_size);
    return 0;
}

#define GL_API_FIND_GL(ret, name, args)                                              \
    if (find(lib, "gl" #name, &gl->name, sizeof gl->name, err, errlen) != 0)         \
        return -1;
#define GL_API_FIND_OSMESA(ret, name, args)                                          \
    if (find(lib, "OSMesa" #name, &om->name, sizeof om->name, err, errlen) != 0)     \
        return -1;

int gl_api_load(gl_api *gl, osmesa_api *om, char *err, size_t errlen)
{
    void *lib = NULL;
    size_t k;
    for (k = 0; k < sizeof libnames / sizeof libnames[0] && !lib; k++)
        lib = dlopen(libnames[k], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        if (errlen)
            snprintf(err, errlen, "osmesa: cannot load %s (%s); install libosmesa6", libnames[0], dlerror());
        return -1;
    }
    GL_API_GL(GL_API_FIND_GL)
    GL_API_OSMESA(GL_API_FIND_OSMESA)
    return 0;
}
