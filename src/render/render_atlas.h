/* render_atlas: frames read from the radiance atlas (render_atlas.c). */
#ifndef PLX_RENDER_ATLAS_H
#define PLX_RENDER_ATLAS_H

#include "render/render.h"

/* The atlas's view (atlas_frame.h) of the camera and sample shift of the
 * last frame set up, with the stamp of the last frame read from the atlas:
 * right after a frame read from the atlas, that frame's view. */
void render_atlas_view(const render *r, struct atlas_view *v /* OUT */);

#endif
