/* The public image-file calls of include/polarlux_port.h over image_write. */
#include "polarlux_port.h"
#include "png/image_write.h"

int plx_png_write(const char *path, int width, int height, const uint8_t *rgb8,
                  char *err, size_t errlen)
{
    return image_write_png_rgb8(path, width, height, rgb8, 0, err, errlen);
}

int plx_pfm_write(const char *path, int width, int height, const float *rgbf,
                  char *err, size_t errlen)
{
    return image_write_pfm(path, width, height, rgbf, err, errlen);
}

int plx_png_read(const char *path, int max_dim, uint8_t **rgb8, int *width, int *height,
                 char *err, size_t errlen)
{
    return image_read_png_max(path, max_dim, rgb8, width, height, err, errlen);
}
