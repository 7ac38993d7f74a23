/* atlas_frame: a frame's pixels read from the radiance atlas (atlas.h).
 *
 * For a pixel whose sample ray meets surface S (the id buffer of the
 * visibility pass), the radiance is the bilinear interpolation of S's
 * chart at the ray's hit point (atlas_sample_uv), the hit point taken in
 * single precision from a projective map of the pixel's coordinates made
 * once per surface and frame: with the ray d(i, j) = D0 + i Dx + j Dy and
 * S's plane n.X = c, the chart coordinates are
 *     u = (Au + Bu i + Cu j) / (Aw + Bw i + Cw j),  v likewise,
 * a ratio of two affine functions of (i, j) (the denominator is n.d).
 * Ground pixels take the ground's own map (z = 0) to (x, y), then the
 * block under it. Sky pixels (and ground off the tiles, surfaces without
 * a chart) are 0.
 *
 * Each worker keeps the maps of the surfaces it met in this frame in its
 * own cache (atlas_cache, ATLAS_CACHE_SLOTS by surface id), so no worker
 * writes what another reads; a map depends on the surface and the camera
 * alone, so the pixels are the same for any number of workers.
 */
#ifndef PLX_ATLAS_FRAME_H
#define PLX_ATLAS_FRAME_H

#include <stdint.h>
#include "render/atlas.h"

#define ATLAS_CACHE_SLOTS 256

/* A frame's camera: pixel (i, j)'s ray is eye + t (D0 + i Dx + j Dy). */
typedef struct atlas_view {
    double eye[3], D0[3], Dx[3], Dy[3];
    int32_t w, h;
    uint32_t stamp;           /* this frame's number: the caches' maps of other frames are stale */
} atlas_view;

typedef struct atlas_map {
    uint32_t sid, stamp;
    float a[9];               /* Au Bu Cu Av Bv Cv Aw Bw Cw */
    const atlas_chart *c;
} atlas_map;

typedef struct atlas_cache {
    atlas_map slot[ATLAS_CACHE_SLOTS];
} atlas_cache;

/* Row j of the frame: lin (3 floats a pixel) from ids (mesh.h's ids, the
 * ground's set), through worker cache k; only the pixels whose mask byte
 * is set when mask is not NULL (the others keep what lin held);
 * count[0..2] += the sky, ground and building pixels written. Returns
 * nonzero when a pixel read a chart or block not filled (atlas_filled
 * false): the row's values are then not the atlas's light, and it must be
 * read again once atlas_frame_missing's items are filled (the same row
 * and mask list every item the row read). */
int atlas_frame_row(const atlas *A, const atlas_view *v, atlas_cache *k, const uint32_t *ids, const uint8_t *mask,
                    int32_t j, float *lin /* OUT */, uint64_t count[3]);

/* The charts and blocks (atlas.h's items) the pixels of rows j0 .. j1 - 1
 * of the frame read that are not filled yet, listed into list (at most
 * cap), each once: their done bytes are set to 2 (listed) until
 * atlas_fill_items fills them. With a mask (not NULL), only the pixels
 * whose byte is set, the ones atlas_frame_row reads with that mask:
 * anti-aliasing's later samples. Returns how many were listed; 0 at once
 * when the atlas is complete. */
uint32_t atlas_frame_missing(atlas *A, const atlas_view *v, const uint32_t *ids, const uint8_t *mask, int32_t j0,
                             int32_t j1, uint32_t *list, uint32_t cap);

#endif
