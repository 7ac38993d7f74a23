#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "canvas.h"
#include "png/image_write.h"

int canvas_init(canvas *c, const double box[4], int size)
{
    double w = box[2] - box[0], h = box[3] - box[1];
    memset(c, 0, sizeof *c);
    if (!(w > 0 && h > 0) || size < 16)
        return -1;
    c->scale = size / (w > h ? w : h);
    c->w = (int)ceil(w * c->scale);
    c->h = (int)ceil(h * c->scale);
    c->x0 = box[0];
    c->y0 = box[3];
    c->rgb = calloc((size_t)c->w * c->h, 3);
    return c->rgb ? 0 : -1;
}

void canvas_fill(canvas *c, uint8_t r, uint8_t g, uint8_t b)
{
    size_t i, n = (size_t)c->w * c->h;
    for (i = 0; i < n; i++) {
        c->rgb[3 * i] = r;
        c->rgb[3 * i + 1] = g;
        c->rgb[3 * i + 2] = b;
    }
}

static void put(canvas *c, int x, int y, const uint8_t rgb[3])
{
    uint8_t *p;
    if (x < 0 || y < 0 || x >= c->w || y >= c->h)
        return;
    p = c->rgb + 3 * ((size_t)y * c->w + x);
    p[0] = rgb[0];
    p[1] = rgb[1];
    p[2] = rgb[2];
}

/* Scanline fill: for each pixel row, the x span where the row's centre line
 * is inside the convex polygon. */
void canvas_poly(canvas *c, const double *xy, int n, const uint8_t rgb[3])
{
    double px[16], py[16], ymin = 1e300, ymax = -1e300;
    int i, y;
    if (n < 3 || n > 16)
        return;
    for (i = 0; i < n; i++) {
        px[i] = (xy[2 * i] - c->x0) * c->scale;
        py[i] = (c->y0 - xy[2 * i + 1]) * c->scale;
        ymin = fmin(ymin, py[i]);
        ymax = fmax(ymax, py[i]);
    }
    for (y = (int)floor(ymin); y <= (int)ceil(ymax); y++) {
        double yc = y + 0.5, lo = 1e300, hi = -1e300;
        int x;
        for (i = 0; i < n; i++) {
            int j = (i + 1) % n;
            if ((py[i] <= yc && py[j] > yc) || (py[j] <= yc && py[i] > yc)) {
                double xc = px[i] + (yc - py[i]) * (px[j] - px[i]) / (py[j] - py[i]);
                lo = fmin(lo, xc);
                hi = fmax(hi, xc);
            }
        }
        if (lo > hi)
            continue;
        for (x = (int)ceil(lo - 0.5); x + 0.5 < hi; x++)
            put(c, x, y, rgb);
    }
}

void canvas_line(canvas *c, double ax, double ay, double bx, double by, const uint8_t rgb[3])
{
    double x0 = (ax - c->x0) * c->scale, y0 = (c->y0 - ay) * c->scale;
    double x1 = (bx - c->x0) * c->scale, y1 = (c->y0 - by) * c->scale;
    double len = fmax(fabs(x1 - x0), fabs(y1 - y0));
    int k, n = (int)ceil(len) + 1;
    if (n > 100000)
        n = 100000;
    for (k = 0; k <= n; k++) {
        double t = (double)k / n;
        put(c, (int)floor(x0 + t * (x1 - x0)), (int)floor(y0 + t * (y1 - y0)), rgb);
    }
}

/* 5x7 glyphs: 7 rows of 5 bits, the high bit on the left. */
typedef struct glyph {
    char c;
    uint8_t rows[7];
} glyph;

static const glyph font[] = {
    { '0', { 14, 17, 19, 21, 25, 17, 14 } }, { '1', { 4, 12, 4, 4, 4, 4, 14 } },
    { '2', { 14, 17, 1, 2, 4, 8, 31 } },     { '3', { 31, 2, 4, 2, 1, 17, 14 } },
    { '4', { 2, 6, 10, 18, 31, 2, 2 } },     { '5', { 31, 16, 30, 1, 1, 17, 14 } },
    { '6', { 6, 8, 16, 30, 17, 17, 14 } },   { '7', { 31, 1, 2, 4, 8, 8, 8 } },
    { '8', { 14, 17, 17, 14, 17, 17, 14 } }, { '9', { 14, 17, 17, 15, 1, 2, 12 } },
    { '.', { 0, 0, 0, 0, 0, 12, 12 } },      { '-', { 0, 0, 0, 31, 0, 0, 0 } },
    { '+', { 0, 4, 4, 31, 4, 4, 0 } },       { 'e', { 0, 0, 14, 17, 31, 16, 14 } },
    { 'l', { 12, 4, 4, 4, 4, 4, 14 } },      { 'u', { 0, 0, 17, 17, 17, 19, 13 } },
    { 'x', { 0, 0, 17, 10, 4, 10, 17 } },      { 'm', { 0, 0, 26, 21, 21, 17, 17 } },
    { 'k', { 16, 16, 18, 20, 24, 20, 18 } },   { 'N', { 17, 25, 21, 19, 17, 17, 17 } },
};

void canvas_rect(canvas *c, int x0, int y0, int x1, int y1, const uint8_t rgb[3])
{
    int x, y;
    for (y = y0; y < y1; y++)
        for (x = x0; x < x1; x++)
            put(c, x, y, rgb);
}

void canvas_text(canvas *c, int x, int y, int scale, const char *text, const uint8_t rgb[3])
{
    for (; *text; text++, x += 6 * scale) {
        size_t g;
        int r, b;
        for (g = 0; g < sizeof font / sizeof font[0] && font[g].c != *text; g++)
            ;
        if (g == sizeof font / sizeof font[0])
            continue;
        for (r = 0; r < 7; r++)
            for (b = 0; b < 5; b++)
                if (font[g].rows[r] & (16 >> b))
                    canvas_rect(c, x + b * scale, y + r * scale, x + (b + 1) * scale, y + (r + 1) * scale, rgb);
    }
}

int canvas_write(const canvas *c, const char *path, char *err, size_t errlen)
{
    return image_write_png_rgb8(path, c->w, c->h, c->rgb, 0, err, errlen);
}

void canvas_free(canvas *c)
{
    free(c->rgb);
    c->rgb = NULL;
}
