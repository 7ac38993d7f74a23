/* Render benchmark (src/render/render.h): ms per frame of
 *  - a 640x480 street view (eye 1.7 m in a street, looking along it), and
 *  - a 1024x768 aerial view (once the ground light map is built)
 * of `gen eixample 30 30` (14,400 buildings, ~16,000 lamps) generated in
 * memory, shaded by the light module (light.h, lit-region cache), with the
 * fraction of the geometry drawn. Baselines in the same process: the same
 * street frame unculled, and the aerial frame with the ground shaded exactly
 * per pixel instead of from the light map. Median of several frames each;
 * the first frame (which fills the light module's cache) is reported apart.
 *
 * With OSMesa built (PLX_HAVE_OSMESA): the street frame through the osmesa
 * backend (port/osmesa) against the soft one, with the real and the zero
 * shader (the latter isolates the raster pass).
 *
 * Usage: bench_render [FRAMES]   (default 7)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "port.h"
#include "base/engine.h"
#include "light/illuminance.h"
#include "light/litregion.h"
#include "render/render.h"
#include "png/image_write.h"
#ifdef PLX_HAVE_OSMESA
#include "plx_osmesa.h"
#endif

#define BUDGET ((size_t)3 << 30)

#include "gen_text.h"

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

static void zero_shade(void *user, const double P[3], const double n[3], double rgb[3])
{
    (void)user;
    (void)P;
    (void)n;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
}

/* Renders cam nf times; returns the median ms, the first frame's ms in *first. */
static double time_frames(render *r, const render_camera *cam, const render_opts *o, int nf,
                          uint8_t *img, render_stats *st, double *first)
{
    double *t = malloc((size_t)nf * sizeof *t);
    int i;
    double m;
    for (i = 0; i < nf; i++) {
        unsigned long long t0 = port_now_ns();
        if (render_frame(r, cam, o, img, NULL, st) != PLX_OK) {
            fprintf(stderr, "bench_render: %s\n", render_error(r));
            exit(1);
        }
        t[i] = (port_now_ns() - t0) / 1e6;
    }
    *first = t[0];
    m = nf > 1 ? median(t + 1, nf - 1) : t[0];
    free(t);
    return m;
}

int main(int argc, char **argv)
{
    int nf = argc > 1 ? atoi(argv[1]) : 7;
    text city = { NULL, 0, 0 };
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    plx_engine *e;
    light *L;
    render *r;
    render_opts o;
    render_stats st;
    render_lightmap_info li;
    uint8_t *img = malloc(1024 * 768 * 3);
    double first, culled, unculled, aerial, aerial_exact, lm_ms;
    unsigned long long t0;
    const char *out = getenv("PLX_BENCH_OUT");
    render_camera street = { { 133.0, 1000.0, 1.7 }, { 133.0, 1400.0, 6.0 }, 60.0, 640, 480 };
    render_camera air = { { 1900.0, 1100.0, 700.0 }, { 1950.0, 1900.0, 0.0 }, 50.0, 1024, 768 };

    if (nf < 2)
        nf = 2;
    if (plx_gen_city("eixample", 30, 30, 1, append, &city) != PLX_OK) {
        fprintf(stderr, "bench_render: gen failed\n");
        return 1;
    }
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    if (plx_engine_new(BUDGET, &cfg, &e) != PLX_OK ||
        plx_load_geojson(e, city.buf, city.len, "eixample-30x30") != PLX_OK) {
        fprintf(stderr, "bench_render: cannot load the city\n");
        return 1;
    }
    printf("city: gen eixample 30 30: %u buildings, %u lamps\n", e->sc->nbld, e->sc->nlamps);
    if (light_create(&e->mem, e->sc, (size_t)512 << 20, &L) != PLX_OK) {
        fprintf(stderr, "bench_render: light_create failed\n");
        return 1;
    }
    t0 = port_now_ns();
    if (render_create(&e->mem, e->sc, 1024, 768, render_shade_light, L, &r) != PLX_OK) {
        fprintf(stderr, "bench_render: render_create failed\n");
        return 1;
    }
    printf("mesh: %u triangles, %u vertices, %.1f MB, built in %.1f ms\n", render_mesh(r)->ntri,
           render_mesh(r)->nv, render_mesh(r)->bytes / 1e6, (port_now_ns() - t0) / 1e6);

    render_opts_default(&o);
    o.exposure = 0.3;
    culled = time_frames(r, &street, &o, nf, img, &st, &first);
    printf("street 640x480 culled:   median %.2f ms (first frame %.1f ms), drawn %u of %u buildings "
           "(%.2f %% of triangles; %u frustum-culled, %u occlusion-culled), %llu shader calls\n",
           culled, first, st.drawn, st.buildings, 100.0 * st.drawn_fraction, st.frustum_culled,
           st.occlusion_culled, (unsigned long long)st.shader_calls);
    printf("  of which %llu from tile lamp lists, %llu lamp visibilities known from the tile\n",
           (unsigned long long)st.shader_tiled, (unsigned long long)st.visibility_skipped);
    if (out) {
        char p[512], err[256];
        snprintf(p, sizeof p, "%s/bench-street.png", out);
        if (image_write_png_rgb8(p, 640, 480, img, 0, err, sizeof err) != 0)
            fprintf(stderr, "%s\n", err);
    }
    o.cull = RENDER_CULL_NONE;
    unculled = time_frames(r, &street, &o, nf, img, &st, &first);
    printf("street 640x480 unculled: median %.2f ms (baseline), ratio culled/unculled %.3f\n", unculled,
           culled / unculled);
    o.cull = RENDER_CULL_ALL;
    o.no_glow = 1;
    o.lightmap = 0;
    {
        /* where the time goes: the same frame with a shader returning 0 */
        render *r0;
        double g, gu;
        if (render_create(&e->mem, e->sc, 640, 480, zero_shade, NULL, &r0) != PLX_OK) {
            fprintf(stderr, "bench_render: render_create failed\n");
            return 1;
        }
        g = time_frames(r0, &street, &o, nf, img, &st, &first);
        o.cull = RENDER_CULL_NONE;
        gu = time_frames(r0, &street, &o, nf, img, &st, &first);
        o.cull = RENDER_CULL_ALL;
        printf("street 640x480 with a zero shader (culling, raster, shading pass, tone map): culled %.2f ms, "
               "unculled %.2f ms, ratio %.3f\n", g, gu, g / gu);
#ifdef PLX_HAVE_OSMESA
        {
            char err[256];
            plx_osmesa *om = plx_osmesa_open(640, 480, err, sizeof err);
            if (!om) {
                printf("osmesa: no context (%s)\n", err);
            } else {
                double go, so, ss;
                o.backend = plx_osmesa_backend(om);
                go = time_frames(r0, &street, &o, nf, img, &st, &first);
                so = time_frames(r, &street, &o, nf, img, &st, &first);
                o.backend = NULL;
                ss = time_frames(r, &street, &o, nf, img, &st, &first);
                printf("street 640x480 culled, soft vs osmesa: zero shader %.2f vs %.2f ms, light shader "
                       "%.2f vs %.2f ms, ratio osmesa/soft %.3f\n", g, go, ss, so, so / ss);
                plx_osmesa_close(om);
            }
        }
#else
        printf("osmesa: not built (no OSMesa at build time)\n");
#endif
    }

    t0 = port_now_ns();
    if (render_lightmap_build(r, 1.0, (size_t)256 << 20) != PLX_OK) {
        fprintf(stderr, "bench_render: %s\n", render_error(r));
        return 1;
    }
    lm_ms = (port_now_ns() - t0) / 1e6;
    render_lightmap_get(r, &li);
    printf("light map: %u x %u texels at %.2f m, %.1f MB, %llu shaded, built in %.0f ms\n", li.nx, li.ny,
           li.cell, li.bytes / 1e6, (unsigned long long)li.shaded, lm_ms);
    o.no_glow = 0;
    o.lightmap = 1;
    o.exposure = 0.5;
    aerial = time_frames(r, &air, &o, nf, img, &st, &first);
    printf("aerial 1024x768 light map: median %.2f ms (first frame %.1f ms), drawn %u of %u buildings "
           "(%.2f %% of triangles), %llu shader calls, %llu ground px\n", aerial, first, st.drawn, st.buildings,
           100.0 * st.drawn_fraction, (unsigned long long)st.shader_calls, (unsigned long long)st.ground_pixels);
    if (out) {
        char p[512], err[256];
        snprintf(p, sizeof p, "%s/bench-aerial.png", out);
        if (image_write_png_rgb8(p, 1024, 768, img, 0, err, sizeof err) != 0)
            fprintf(stderr, "%s\n", err);
    }
    o.lightmap = 0;
    aerial_exact = time_frames(r, &air, &o, 3, img, &st, &first);
    printf("aerial 1024x768 exact ground: median %.2f ms (baseline), ratio light map/exact %.3f\n", aerial_exact,
           aerial / aerial_exact);
    printf("targets: street <= 10 ms: %s; aerial <= 5 ms: %s\n", culled <= 10 ? "met" : "NOT met",
           aerial <= 5 ? "met" : "NOT met");
    plx_engine_free(e);
    free(city.buf);
    free(img);
    return 0;
}
