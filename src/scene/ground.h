/* ground: the ground's albedo from a day image (src/ground.c). The lookup,
 * scene_ground_albedo, is declared in scene.h; this is the setter. */
#ifndef PLX_GROUND_H
#define PLX_GROUND_H

#include "base/arena.h"
#include "base/scene.h"

/* Largest width or height of a ground image. */
#define GROUND_MAX_DIM 16384u

/* Gives s the ground image of w x h pixels rgb (8-bit sRGB, 3 bytes a
 * pixel, top row first) over box (x0 < x1, y0 < y1, local metres). The
 * pixels are copied: into the current image's memory when they fit, else
 * into w*h*3 new bytes of part PLX_PART_SCENE (the old ones stay held
 * until the next load). Returns PLX_OK; PLX_E_INVALID when w or h is 0 or
 * above GROUND_MAX_DIM or the image is black (its albedo cannot be scaled
 * to the ground albedo); PLX_E_NOMEM (s keeps its old image). */
plx_status ground_image_set(arena *a, scene *s, uint32_t w, uint32_t h, const uint8_t *rgb,
                            const double box[4]);

/* The luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of a linear colour. */
double ground_luminance(const double rgb[3]);

#endif
