/* Ground image benchmark (src/scene/ground.c): what the per-pixel ground albedo
 * costs. On fixtures/ground-image.geojson with fixtures/ground-day.png:
 *  - a 1280x960 street view and a 1280x960 aerial view (direct light, no
 *    glows: every ground pixel looks its albedo up), and
 *  - a photon frame of 200,000 photons (every ground bounce looks up the
 *    albedo's luminance),
 * each with the image set and, as the baseline in the same process, with
 * the image removed (the constant albedo), alternating, median of FRAMES.
 *
 * Usage: bench_ground [FRAMES]   (default 9)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "port.h"
#include "png/image_write.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int set_image(plx_engine *e, const uint8_t *px, int w, int h, int on)
{
    plx_status st = on ? plx_set_ground_image(e, (uint32_t)w, (uint32_t)h, px, NULL)
                       : plx_set_ground_image(e, 0, 0, NULL, NULL);
    if (st != PLX_OK)
        fprintf(stderr, "bench_ground: %s\n", plx_last_error(e));
    return st == PLX_OK ? 0 : -1;
}

int main(int argc, char **argv)
{
    int nf = argc > 1 ? atoi(argv[1]) : 9, w, h, k, on, v;
    plx_engine *e;
    plx_config cfg;
    uint8_t *px = NULL, *img;
    char err[300];
    double *t[2];
    const char *names[3] = { "street view 1280x960", "aerial view 1280x960", "photon frame 200000" };
    if (nf < 1)
        nf = 1;
    plx_config_default(&cfg);
    cfg.port = plx_port_posix();
    cfg.render_max_width = 1280;
    cfg.render_max_height = 960;
    if (plx_engine_new((size_t)512 << 20, &cfg, &e) != PLX_OK)
        return 1;
    if (plx_load_file(e, "fixtures/ground-image.geojson") != PLX_OK) {
        fprintf(stderr, "bench_ground: fixtures/ground-image.geojson: cannot load (run from the checkout)\n");
        return 1;
    }
    if (image_read_png_max("fixtures/ground-day.png", 16384, &px, &w, &h, err, sizeof err) != 0) {
        fprintf(stderr, "bench_ground: %s\n", err);
        return 1;
    }
    img = malloc((size_t)1280 * 960 * 3);
    t[0] = malloc((size_t)nf * sizeof(double));
    t[1] = malloc((size_t)nf * sizeof(double));
    printf("ground image %dx%d on fixtures/ground-image.geojson, median of %d runs each\n", w, h, nf);
    printf("%-24s %12s %12s %8s\n", "work", "image ms", "no image ms", "ratio");
    for (v = 0; v < 3; v++) {
        plx_camera cam;
        plx_render_opts o;
        memset(&cam, 0, sizeof cam);
        cam.width = 1280;
        cam.height = 960;
        cam.fov_deg = 60.0;
        if (v == 0) {
            cam.eye[0] = 12.0; cam.eye[1] = 5.0; cam.eye[2] = 1.7;
            cam.target[0] = -40.0; cam.target[1] = 5.0; cam.target[2] = 1.0;
        } else {
            cam.eye[2] = 80.0;
        }
        plx_render_opts_default(&o);
        o.no_glow = 1;
        o.no_indirect = 1;
        for (k = 0; k < nf; k++)
            for (on = 1; on >= 0; on--) {
                unsigned long long t0;
                plx_status st;
                if (set_image(e, px, w, h, on) != 0)
                    return 1;
                t0 = port_now_ns();
                st = v < 2 ? plx_render(e, &cam, &o, img, NULL, NULL) : plx_indirect_step(e, 200000, 1);
                if (st != PLX_OK) {
                    fprintf(stderr, "bench_ground: %s\n", plx_last_error(e));
                    return 1;
                }
                t[on][k] = (port_now_ns() - t0) / 1e6;
            }
        {
            double a = median(t[1], nf), b = median(t[0], nf);
            printf("%-24s %12.2f %12.2f %8.3f\n", names[v], a, b, a / b);
        }
    }
    free(t[0]);
    free(t[1]);
    free(img);
    free(px);
    plx_engine_free(e);
    return 0;
}
