/* gl_api: the OpenGL 1.1 and OSMesa calls the port uses, found at run time.
 *
 * libOSMesa pulls in Mesa's llvmpipe (libLLVM and its dependencies, about
 * 50 MB mapped and 0.1 s of relocation at every start). Linking it would
 * charge that to every polarlux command, though only `render --backend
 * osmesa` draws with it. So the library is opened with dlopen the first time
 * a context is asked for, and its functions are called through this table.
 *
 * GL_API_FUNCS lists every function as X(return type, name without the "gl"
 * or "OSMesa" prefix, parameter list); the table has one member per entry.
 * The library stays open for the life of the process (Mesa keeps per-thread
 * state that an unload would leave dangling).
 */
#ifndef PLX_GL_API_H
#define PLX_GL_API_H

#include <stddef.h>
#include <GL/osmesa.h>

#define GL_API_GL(X)                                                                  \
    X(GLenum, GetError, (void))                                                       \
    X(void, Viewport, (GLint, GLint, GLsizei, GLsizei))                               \
    X(void, Scissor, (GLint, GLint, GLsizei, GLsizei))                                \
    X(void, Enable, (GLenum))                                                         \
    X(void, Disable, (GLenum))                                                        \
    X(void, PolygonMode, (GLenum, GLenum))                                            \
    X(void, ShadeModel, (GLenum))                                                     \
    X(void, ColorMask, (GLboolean, GLboolean, GLboolean, GLboolean))                  \
    X(void, MatrixMode, (GLenum))                                                     \
    X(void, LoadIdentity, (void))                                                     \
    X(void, DepthRange, (GLclampd, GLclampd))                                         \
    X(void, DepthFunc, (GLenum))                                                      \
    X(void, DepthMask, (GLboolean))                                                   \
    X(void, FrontFace, (GLenum))                                                      \
    X(void, CullFace, (GLenum))                                                       \
    X(void, ClearColor, (GLclampf, GLclampf, GLclampf, GLclampf))                     \
    X(void, ClearDepth, (GLclampd))                                                   \
    X(void, Clear, (GLbitfield))                                                      \
    X(void, Begin, (GLenum))                                                          \
    X(void, End, (void))                                                              \
    X(void, Color4ub, (GLubyte, GLubyte, GLubyte, GLubyte))                           \
    X(void, Vertex4fv, (const GLfloat *))                                             \
    X(void, Vertex4f, (GLfloat, GLfloat, GLfloat, GLfloat))                           \
    X(void, PixelStorei, (GLenum, GLint))                                             \
    X(void, ReadPixels, (GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, GLvoid *))

#define GL_API_OSMESA(X)                                                              \
    X(OSMesaContext, CreateContextExt, (GLenum, GLint, GLint, GLint, OSMesaContext))  \
    X(GLboolean, MakeCurrent, (OSMesaContext, void *, GLenum, GLsizei, GLsizei))      \
    X(void, PixelStore, (GLint, GLint))                                               \
    X(void, DestroyContext, (OSMesaContext))

#define GL_API_MEMBER(ret, name, args) ret (*name) args;

typedef struct gl_api {
    GL_API_GL(GL_API_MEMBER)
} gl_api;

typedef struct osmesa_api {
    GL_API_OSMESA(GL_API_MEMBER)
} osmesa_api;

/* Opens libOSMesa (once per call; dlopen counts the references) and fills
 * both tables. Returns 0, or -1 with a one-line reason in err (errlen bytes,
 * may be 0): the library or one of its functions is missing. */
int gl_api_load(gl_api *gl, osmesa_api *om, char *err, size_t errlen);

#endif
