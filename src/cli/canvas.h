/* A small RGB canvas for the command's diagnostic drawings (polar diagrams):
 * a world-to-pixel mapping, filled convex polygons, lines, PNG output. */
#ifndef PLX_CLI_CANVAS_H
#define PLX_CLI_CANVAS_H

#include <stdint.h>

typedef struct canvas {
    int w, h;
    uint8_t *rgb;
    double x0, y0, scale;   /* pixel = (x - x0) * scale, (y0 - y) * scale */
} canvas;

/* A canvas of about 'size' pixels on its longer side showing the box. */
int canvas_init(canvas *c, const double box[4], int size);
void canvas_fill(canvas *c, uint8_t r, uint8_t g, uint8_t b);
/* Fills a convex polygon (n x,y pairs in world coordinates). */
void canvas_poly(canvas *c, const double *xy, int n, const uint8_t rgb[3]);
void canvas_line(canvas *c, double ax, double ay, double bx, double by, const uint8_t rgb[3]);
/* Text in a 5x7 pixel font scaled by 'scale' (digits, . - + e l u x and
 * space; other characters draw nothing), top-left corner at pixel (x, y). */
void canvas_text(canvas *c, int x, int y, int scale, const char *text, const uint8_t rgb[3]);
/* Fills the pixel rectangle [x0, x1) x [y0, y1). */
void canvas_rect(canvas *c, int x0, int y0, int x1, int y1, const uint8_t rgb[3]);
int canvas_write(const canvas *c, const char *path, char *err, size_t errlen);
void canvas_free(canvas *c);

#endif
