/* irradiance_cache: the indirect light of an image (src/photon/irradiance_cache.h)
 * against the independent path tracer (tests/ref/ref_indirect.c).
 *
 * A street view of fixtures/eixample-4x4.geojson is rendered through the API
 * twice (linear floats, no glows), with and without indirect light; their
 * difference at a pixel is the indirect radiance a/pi E_indirect the image
 * shows there. Sample pixels are chosen on a grid, each kept when the ray
 * through its centre (the renderer's camera, written out here) meets the
 * ground or a wall within 60 m and the rays 2 pixels around it meet the same
 * surface (no pixel on an edge). At the point that ray meets, the path
 * tracer gives E_indirect; the image's E_indirect is pi / a times the
 * difference in the red channel (the fixture's lamps have the default
 * colour, whose red is 1: red E_indirect equals the colour-blind one the
 * path tracer gives, with grey albedos). Printed beside it: the photon buffers alone at the same
 * points, read as images read them before (the wide lookup).
 *
 * Also: the same camera gives the same bytes, whatever was rendered before
 * (records do not depend on the order pixels asked for them).
 * PLX_TEST_QUICK=1 (make check): fewer pixels and paths, a looser bound. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "base/engine.h"
#include "photon/trace.h"
#include "photon/indirect.h"
#include "photon/irradiance_cache.h"
#include "render/render.h"
#include "ref_indirect.h"
#include "fixture.h"
#include "slow.h"

#define PI 3.14159265358979323846
#define W 320
#define H 240

static int quick_mode(void)
{
    const char *v = getenv("PLX_TEST_QUICK");
    return v && v[0] && v[0] != '0';
}

static void camera(plx_camera *c)
{
    memset(c, 0, sizeof *c);
    c->eye[0] = 298.6;
    c->eye[1] = 265.5;
    c->eye[2] = 1.7;
    c->target[0] = 261.8;
    c->target[1] = 302.3;
    c->target[2] = 3.0;
    c->fov_deg = 60.0;
    c->width = W;
    c->height = H;
}

/* The ray through the centre of pixel (i, j), as camera.c projects. */
static void pixel_ray(const plx_camera *c, int i, int j, double d[3])
{
    double f[3], rt[3], up[3], l, x, y, th = tan(c->fov_deg * PI / 360.0);
    int k;
    for (k = 0; k < 3; k++)
        f[k] = c->target[k] - c->eye[k];
    l = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (k = 0; k < 3; k++)
        f[k] /= l;
    l = sqrt(f[0] * f[0] + f[1] * f[1]);
    rt[0] = f[1] / l;
    rt[1] = -f[0] / l;
    rt[2] = 0.0;
    up[0] = rt[1] * f[2] - rt[2] * f[1];
    up[1] = rt[2] * f[0] - rt[0] * f[2];
    up[2] = rt[0] * f[1] - rt[1] * f[0];
    x = ((i + 0.5) / c->width * 2.0 - 1.0) * th * c->width / c->height;
    y = (1.0 - (j + 0.5) / c->height * 2.0) * th;
    for (k = 0; k < 3; k++)
        d[k] = f[k] + x * rt[k] + y * up[k];
    l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (k = 0; k < 3; k++)
        d[k] /= l;
}

/* Kind and surface met through pixel (i, j): 0 for the sky or beyond 60 m. */
static uint64_t pixel_surface(tracer *T, const plx_camera *c, int i, int j, trace_hit *h)
{
    double d[3];
    pixel_ray(c, i, j, d);
    if (trace_ray(T, c->eye, d, 60.0, h) == TRACE_SKY)
        return 0;
    if (h->kind == TRACE_WALL)
        return ((uint64_t)1 << 40) | h->edge;
    if (h->kind == TRACE_GROUND)
        return (uint64_t)2 << 40;
    return 0;
}

static void render_pair(plx_engine *e, const plx_camera *c, float *with, float *without)
{
    plx_render_opts o;
    plx_render_opts_default(&o);
    o.per_pixel = 1; /* every pixel shaded: the irradiance cache, not the radiance atlas */
    o.no_glow = 1;
    o.no_indirect = 1;
    assert_int_equal(plx_render(e, c, &o, NULL, without, NULL), PLX_OK);
    o.no_indirect = 0;
    assert_int_equal(plx_render(e, c, &o, NULL, with, NULL), PLX_OK);
}

/* The sample pixels: candidates on a grid (no edge within 2 pixels), maxn
 * of them spread evenly over the list; their points, normals, albedos and
 * the reference there. Returns how many (those too dark are dropped). */
static int sample_pixels(plx_engine *e, const plx_camera *c, int step, int maxn, int paths,
                         int *px, trace_hit *hit, double *ref, double *noise)
{
    int i, j, k, n = 0, ncand = 0, *cand = malloc(sizeof *cand * W * H);
    assert_non_null(cand);
    for (j = step / 2; j < H; j += step)
        for (i = step / 2; i < W; i += step) {
            trace_hit h, h2;
            uint64_t id = pixel_surface(e->ph->T, c, i, j, &h);
            int di, dj, same = id != 0;
            for (dj = -2; dj <= 2 && same; dj += 2)
                for (di = -2; di <= 2 && same; di += 2)
                    same = pixel_surface(e->ph->T, c, i + di, j + dj, &h2) == id;
            if (same)
                cand[ncand++] = j * W + i;
        }
    *noise = 0.0;
    for (k = 0; k < maxn && k < ncand; k++) {
        int q = cand[(int)((k + 0.5) * ncand / maxn)];
        double se;
        pixel_surface(e->ph->T, c, q % W, q / W, &hit[n]);
        ref[n] = ref_indirect_paths(e->ph->T, e->sc, hit[n].p, hit[n].n, paths, 500u + (uint64_t)k,
                                    &se);
        if (!(ref[n] > 0.05))
            continue; /* too dark for a relative error (beyond the lamps' light) */
        *noise += se / ref[n];
        px[n++] = q;
    }
    free(cand);
    if (n > 0)
        *noise /= n;
    return n;
}

static void test_image_accuracy(void **state)
{
    plx_engine *e = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    float *with = malloc(sizeof *with * 3 * W * H), *without = malloc(sizeof *with * 3 * W * H);
    int step = quick_mode() ? 20 : 8, paths = quick_mode() ? 4000 : 40000;
    int maxn = quick_mode() ? 10 : 60, seeds = quick_mode() ? 1 : 6, px[60], n, k, sd, walls = 0;
    double bound = quick_mode() ? 0.12 : 0.08, err = 0.0, err_old = 0.0, noise, ref[60];
    trace_hit hit[60];
    plx_camera c;
    (void)state;
    assert_true(with && without);
    camera(&c);
    assert_int_equal(plx_indirect_step(e, 1, 1), PLX_OK); /* the tracer */
    n = sample_pixels(e, &c, step, maxn, paths, px, hit, ref, &noise);
    assert_true(n >= maxn / 2);
    for (sd = 0; sd < seeds; sd++) {
        assert_int_equal(plx_indirect_reset(e), PLX_OK);
        for (k = 0; k < 4; k++) /* the command's default: 4 x 65536 photons */
            assert_int_equal(plx_indirect_step(e, 65536, 100u * (uint64_t)sd + (uint64_t)k + 1),
                             PLX_OK);
        render_pair(e, &c, with, without);
        for (k = 0; k < n; k++) {
            /* red: the lamps' default colour has red 1 */
            const trace_hit *h = &hit[k];
            double a = h->kind == TRACE_WALL ? h->albedo : e->sc->ground_albedo, rgb_old[3];
            double img = (with[3 * px[k]] - without[3 * px[k]]) * PI / a;
            photon_indirect_rgb(e->ph, h->p, h->n, rgb_old);
            err += fabs(img - ref[k]) / ref[k];
            err_old += fabs(rgb_old[0] - ref[k]) / ref[k];
            walls += sd == 0 && h->kind == TRACE_WALL;
        }
    }
    err /= n * seeds;
    err_old /= n * seeds;
    printf("street view %dx%d of eixample-4x4, %d pixels (%d on walls), reference %d paths "
           "(its noise %.4f), %d seed%s of 4 x 65536 photons: mean relative error of the "
           "image's E_indirect %.4f (irradiance cache: %llu records), photon buffers alone "
           "%.4f; bound %.2f%s\n",
           W, H, n, walls, paths, noise, seeds, seeds > 1 ? "s" : "", err,
           (unsigned long long)e->ic->gathered, err_old, bound, quick_mode() ? " (quick mode)" : "");
    assert_true(noise < (quick_mode() ? 0.05 : 0.015));
    assert_true(err <= bound);
    assert_true(err < err_old);
    free(with);
    free(without);
    plx_engine_free(e);
}

/* The test camera, and another one 30 m away that fills the cache first. */
static void two_views(plx_camera *c, plx_camera *other)
{
    camera(c);
    *other = *c;
    other->eye[0] -= 30.0;
    other->target[1] += 20.0;
}

/* The same camera, the same bytes: after another view filled the cache, in
 * a fresh engine, and whatever the caches' sizes (they come from the
 * budget): the second engine has the smallest irradiance-cache table
 * (ICACHE_RECORDS_MIN slots: it is emptied and refilled during the frames,
 * asserted), and a renderer made for 64x48 frames (64 surface slots,
 * render_surf_slots) gives the 64x48 frame of the default one. */
static void test_image_same_bytes(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    plx_engine *e1 = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    plx_engine *e2 = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    plx_engine *e3;
    plx_config cfg;
    uint8_t *a = malloc(3 * W * H), *b = malloc(3 * W * H);
    plx_render_opts o;
    plx_camera c, other;
    (void)state;
    assert_true(a && b);
    two_views(&c, &other);
    plx_render_opts_default(&o);
    o.per_pixel = 1; /* every pixel shaded: the irradiance cache, not the radiance atlas */
    assert_int_equal(plx_indirect_step(e1, 16384, 3), PLX_OK);
    assert_int_equal(plx_indirect_step(e2, 16384, 3), PLX_OK);
    assert_int_equal(e1->ic->nrec, ICACHE_RECORDS);
    assert_int_equal(icache_create(&e2->mem, ICACHE_RECORDS_MIN, &e2->ic), PLX_OK);
    assert_int_equal(icache_create(&e2->mem, 3000, &e2->ic), PLX_E_INVALID);
    assert_int_equal(plx_render(e1, &c, &o, a, NULL, NULL), PLX_OK);
    assert_int_equal(plx_render(e2, &other, &o, b, NULL, NULL), PLX_OK);
    assert_int_equal(plx_render(e2, &c, &o, b, NULL, NULL), PLX_OK);
    printf("table of %u slots: emptied %llu times, %llu records gathered (default table: %llu)\n",
           (unsigned)e2->ic->nrec, (unsigned long long)e2->ic->flushes, (unsigned long long)e2->ic->gathered,
           (unsigned long long)e1->ic->gathered);
    assert_true(e2->ic->flushes > 0);
    assert_memory_equal(a, b, 3 * W * H);

    plx_config_default(&cfg);
    cfg.port = fixture_quiet_port();
    cfg.render_max_width = 64;
    cfg.render_max_height = 48;
    assert_int_equal(plx_engine_new((size_t)1 << 30, &cfg, &e3), PLX_OK);
    assert_int_equal(plx_load_file(e3, "fixtures/eixample-4x4.geojson"), PLX_OK);
    assert_int_equal(plx_indirect_step(e3, 16384, 3), PLX_OK);
    assert_int_equal(render_surf_slots(e3->sc, 64, 48), 64);
    assert_int_equal(render_surf_slots(e3->sc, W, H), 2048);
    c.width = other.width = 64;
    c.height = other.height = 48;
    assert_int_equal(plx_render(e1, &c, &o, a, NULL, NULL), PLX_OK);
    assert_int_equal(plx_render(e3, &other, &o, b, NULL, NULL), PLX_OK);
    assert_int_equal(plx_render(e3, &c, &o, b, NULL, NULL), PLX_OK);
    assert_memory_equal(a, b, 3 * 64 * 48);
    free(a);
    free(b);
    plx_engine_free(e1);
    plx_engine_free(e2);
    plx_engine_free(e3);
}

/* An aerial frame without indirect light gathers nothing (it does not
 * read the light map's indirect layer, so the map is built without it: a
 * 1024x768 frame from a gen eixample 30 30 bake waited 16 s for it), and
 * changes no byte of the aerial frame with indirect light that follows
 * (which gathers the layer then), nor does a gathered layer change a
 * frame without indirect light. */
static void test_aerial_without_indirect_gathers_nothing(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    plx_engine *e1 = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    plx_engine *e2 = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    uint8_t *a = malloc(3 * W * H), *b = malloc(3 * W * H);
    plx_render_opts oa, od;
    plx_camera top;
    (void)state;
    assert_true(a && b);
    camera(&top);
    top.eye[2] = 150.0;
    top.target[0] = top.eye[0];
    top.target[1] = top.eye[1] + 1.0;
    top.target[2] = 0.0;
    plx_render_opts_default(&oa);
    oa.per_pixel = 1; /* the light map, not the radiance atlas */
    oa.aerial = 1;
    od = oa;
    od.no_indirect = 1;
    assert_int_equal(plx_indirect_step(e1, 16384, 3), PLX_OK);
    assert_int_equal(plx_indirect_step(e2, 16384, 3), PLX_OK);
    assert_int_equal(plx_render(e2, &top, &od, b, NULL, NULL), PLX_OK);
    assert_int_equal(e2->ic->gathered, 0);
    assert_int_equal(plx_render(e1, &top, &oa, a, NULL, NULL), PLX_OK);
    assert_true(e1->ic->gathered > 0);
    assert_int_equal(plx_render(e2, &top, &oa, b, NULL, NULL), PLX_OK);
    assert_memory_equal(a, b, 3 * W * H);
    assert_int_equal(plx_render(e1, &top, &od, a, NULL, NULL), PLX_OK);
    assert_int_equal(plx_render(e2, &top, &od, b, NULL, NULL), PLX_OK);
    assert_memory_equal(a, b, 3 * W * H);
    free(a);
    free(b);
    plx_engine_free(e1);
    plx_engine_free(e2);
}

/* An aerial frame first (its light map's layer gathers 8 m records of
 * 24 x 24 directions into the engine's cache) changes no byte of a street
 * frame: the two kinds of records never share a slot, though the street
 * frame's far pixels use the same 8 m level. */
static void test_image_after_aerial_same_bytes(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    plx_engine *e1 = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    plx_engine *e2 = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    uint8_t *a = malloc(3 * W * H), *b = malloc(3 * W * H);
    plx_render_opts o, oa;
    plx_camera c, top;
    (void)state;
    assert_true(a && b);
    camera(&c);
    c.eye[2] = 60.0; /* the ground 60-110 m away: the 8 m level */
    c.target[2] = 0.0;
    top = c;
    top.eye[2] = 150.0;
    top.target[0] = top.eye[0];
    top.target[1] = top.eye[1] + 1.0;
    top.target[2] = 0.0;
    plx_render_opts_default(&o);
    o.per_pixel = 1; /* every pixel shaded: the irradiance cache, not the radiance atlas */
    oa = o;
    oa.aerial = 1;
    assert_int_equal(plx_indirect_step(e1, 16384, 3), PLX_OK);
    assert_int_equal(plx_indirect_step(e2, 16384, 3), PLX_OK);
    assert_int_equal(plx_render(e1, &c, &o, a, NULL, NULL), PLX_OK);
    assert_int_equal(plx_render(e2, &top, &oa, b, NULL, NULL), PLX_OK);
    assert_true(e2->ic->gathered > 0);
    assert_int_equal(plx_render(e2, &c, &o, b, NULL, NULL), PLX_OK);
    assert_memory_equal(a, b, 3 * W * H);
    free(a);
    free(b);
    plx_engine_free(e1);
    plx_engine_free(e2);
}

/* icache_peek (what the frame's workers ask first): at points of a view
 * and of a second view 30 m away, every 3rd pixel out to 60 m, after a
 * frame of the first view filled the table; then the same again after
 * new photons emptied the table and the second view's frame filled it. A peek changes
 * no byte of the cache but its worker's own cells (3 workers in turn);
 * where it answers, it gives icache_lookup's bits; where it does not
 * (records not yet gathered: asserted to happen), the lookup gathers and
 * the peek answers after it with the lookup's bits (unless no record of
 * the point's cell is valid: the lookup gathers at the point itself, every
 * time). */
static void test_peek_same_bits(void **state)
{
    if (quick_mode()) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    plx_engine *e = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    size_t tab = (size_t)ICACHE_RECORDS * 32;
    unsigned char *before = malloc(tab + sizeof(icache));
    plx_render_opts o;
    plx_camera c, other;
    uint32_t answered = 0, missed = 0, v, i, j, round;
    size_t shared = offsetof(icache, peek_last); /* what no peek may change */
    int full, worker = 0;
    (void)state;
    assert_non_null(before);
    two_views(&c, &other);
    plx_render_opts_default(&o);
    o.per_pixel = 1; /* every pixel shaded: the irradiance cache, not the radiance atlas */
    assert_int_equal(plx_indirect_step(e, 16384, 3), PLX_OK);
    assert_int_equal(plx_render(e, &c, &o, NULL, NULL, NULL), PLX_OK);
    assert_int_equal(e->ic->nrec, ICACHE_RECORDS);
    for (round = 0; round < 2; round++) {
    if (round == 1) { /* new photons: the next lookup empties the table (the workers'
                       * cells now name records gone), the frame refills it */
        assert_int_equal(plx_indirect_step(e, 16384, 3), PLX_OK);
        assert_int_equal(plx_render(e, &other, &o, NULL, NULL, NULL), PLX_OK);
    }
    for (v = 0; v < 2; v++)
        for (j = 1; j < H; j += 3)
            for (i = 1; i < W; i += 3) {
                trace_hit h;
                double peek[3], look[3];
                if (!pixel_surface(e->ph->T, v ? &other : &c, (int)i, (int)j, &h))
                    continue;
                icache_set_view(e->ic, (v ? &other : &c)->eye);
                memcpy(before, e->ic, sizeof(icache));
                full = (answered + missed) % 64 == 0; /* the whole table now and then */
                if (full)
                    memcpy(before + sizeof(icache), e->ic->tab, tab);
                worker = (worker + 1) % 3;
                if (icache_peek(e->ic, e->ph, worker, h.p, h.n, peek)) {
                    answered++;
                    assert_memory_equal(before, e->ic, shared);
                    if (full)
                        assert_memory_equal(before + sizeof(icache), e->ic->tab, tab);
                    icache_lookup(e->ic, e->ph, e->lt, h.p, h.n, look);
                    assert_memory_equal(peek, look, sizeof peek);
                } else {
                    uint64_t direct = e->ic->direct;
                    missed++;
                    assert_memory_equal(before, e->ic, shared);
                    if (full)
                        assert_memory_equal(before + sizeof(icache), e->ic->tab, tab);
                    icache_lookup(e->ic, e->ph, e->lt, h.p, h.n, look);
                    if (e->ic->direct != direct)
                        continue; /* no vertex of its cell is valid: gathered at the point */
                    assert_true(icache_peek(e->ic, e->ph, worker, h.p, h.n, peek));
                    assert_memory_equal(peek, look, sizeof peek);
                }
            }
    }
    printf("peeks: %u answered, %u would gather\n", (unsigned)answered, (unsigned)missed);
    assert_true(answered > 1000);
    assert_true(missed > 10);
    assert_int_equal(e->ic->flushes, 1);
    free(before);
    plx_engine_free(e);
}

/* A worker's last cells name table slots: a slot that no longer holds
 * the vertex's record is not read through them. Peek at points of a view
 * with worker 0; then change the second key of every record its cells
 * name (as if the table had been emptied and those slots refilled with
 * other vertices): the next peek at the point must not answer from them
 * (it misses: the records are not found by their keys); with the keys put
 * back it answers the same bits again. */
static void test_peek_cells_follow_table(void **state)
{
    plx_engine *e = fixture_new((size_t)1 << 30, "fixtures/eixample-4x4.geojson", NULL, 0);
    plx_render_opts o;
    plx_camera c, other;
    uint32_t tried = 0, i, j;
    (void)state;
    two_views(&c, &other);
    plx_render_opts_default(&o);
    o.per_pixel = 1; /* every pixel shaded: the irradiance cache, not the radiance atlas */
    assert_int_equal(plx_indirect_step(e, 16384, 3), PLX_OK);
    assert_int_equal(plx_render(e, &c, &o, NULL, NULL, NULL), PLX_OK);
    icache_set_view(e->ic, c.eye);
    for (j = 5; j < H && tried < 40; j += 17)
        for (i = 5; i < W && tried < 40; i += 23) {
            trace_hit h;
            double first[3], again[3];
            uint32_t idx[(ICACHE_LEVEL_MAX + 1) * 4];
            int n = 0, l, v, k;
            if (!pixel_surface(e->ph->T, &c, (int)i, (int)j, &h) || h.n[2] < -0.5 ||
                !icache_peek(e->ic, e->ph, 0, h.p, h.n, first))
                continue;
            for (l = 0; l <= ICACHE_LEVEL_MAX; l++)
                for (v = 0; v < 4; v++)
                    if (e->ic->peek_last[0][l].r[v])
                        idx[n++] = e->ic->peek_last[0][l].r[v] - 1;
            if (n == 0)
                continue; /* answered from the photon buffers (far) */
            tried++;
            for (k = 0; k < n; k++)
                e->ic->tab[idx[k]].k2 ^= 1;
            assert_false(icache_peek(e->ic, e->ph, 0, h.p, h.n, again));
            for (k = 0; k < n; k++)
                e->ic->tab[idx[k]].k2 ^= 1;
            assert_true(icache_peek(e->ic, e->ph, 0, h.p, h.n, again));
            assert_memory_equal(first, again, sizeof first);
        }
    assert_true(tried >= 20);
    plx_engine_free(e);
}

/* ---- aerial views: the light map's indirect layer ---------------------------- */

#define AW 200
#define AH 150

/* Kind and surface met through pixel (i, j) of a straight-down camera:
 * the ground, or a roof (its building); 0 for anything else. */
static uint64_t aerial_surface(tracer *T, const plx_camera *c, int i, int j, trace_hit *h)
{
    double th = tan(c->fov_deg * PI / 360.0), d[3], l;
    d[0] = ((i + 0.5) / c->width * 2.0 - 1.0) * th * c->width / c->height;
    d[1] = (1.0 - (j + 0.5) / c->height * 2.0) * th;
    d[2] = -1.0;
    l = sqrt(d[0] * d[0] + d[1] * d[1] + 1.0);
    d[0] /= l;
    d[1] /= l;
    d[2] /= l;
    if (trace_ray(T, c->eye, d, 2.0 * c->eye[2], h) == TRACE_SKY)
        return 0;
    if (h->kind == TRACE_ROOF)
        return ((uint64_t)1 << 40) | h->bld;
    if (h->kind == TRACE_GROUND)
        return (uint64_t)2 << 40;
    return 0;
}


/* An aerial view of a generated Eixample of 2 x 2 blocks (courtyards closed
 * on every side), straight down, through the API with and without indirect
 * light. Candidate pixels on a grid, on open ground or a roof, 2 pixels
 * from any edge; a short path-traced estimate sorts them: lit ones
 * (E_indirect > 0.3 lx), of which maxn spread over the list are compared
 * against a long reference (mean relative error), and dark ones (under
 * 0.01 lx by 4 sigma: closed courtyards, roofs no wall looks down on),
 * where the image must add almost nothing. Printed beside: the photon
 * buffers' lookup at the same points (what aerial views read before). */
static void test_aerial_accuracy(void **state)
{
    plx_engine *e;
    plx_config cfg;
    static plx_port port;
    plx_render_opts o;
    plx_camera c;
    plx_scene_info si;
    fixture_city g;
    float *with = malloc(sizeof *with * 3 * AW * AH), *without = malloc(sizeof *with * 3 * AW * AH);
    int step = quick_mode() ? 6 : 3, paths = quick_mode() ? 5000 : 40000;
    int maxn = quick_mode() ? 10 : 50, i, j, n = 0, roofs = 0, dark = 0, nlit = 0, k;
    int *lit = malloc(sizeof *lit * AW * AH);
    double bound = quick_mode() ? 0.35 : 0.25, err = 0.0, err_old = 0.0, noise = 0.0, dark_max = 0.0;
    double dark_old = 0.0;
    (void)state;
    assert_true(with && without && lit);
    fixture_gen("eixample", 2, 2, 1, &g);
    port = *plx_port_posix();
    port.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &port;
    assert_int_equal(plx_engine_new((size_t)1 << 29, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_geojson(e, g.buf, g.len, "eixample-2x2"), PLX_OK);
    free(g.buf);
    plx_scene_info_get(e, &si);
    memset(&c, 0, sizeof c);
    c.fov_deg = 40.0;
    c.width = AW;
    c.height = AH;
    c.eye[0] = c.target[0] = 0.5 * (si.bounds[0] + si.bounds[2]);
    c.eye[1] = c.target[1] = 0.5 * (si.bounds[1] + si.bounds[3]);
    c.eye[2] = 0.5 * fmax(si.bounds[3] - si.bounds[1], (si.bounds[2] - si.bounds[0]) * AH / AW) /
               tan(c.fov_deg * PI / 360.0);
    for (k = 0; k < 4; k++) /* the command's default: 4 x 65536 photons */
        assert_int_equal(plx_indirect_step(e, 65536, (uint64_t)k + 1), PLX_OK);
    plx_render_opts_default(&o);
    o.per_pixel = 1; /* every pixel shaded: the irradiance cache, not the radiance atlas */
    o.no_glow = 1;
    o.aerial = 1;
    o.no_indirect = 1;
    assert_int_equal(plx_render(e, &c, &o, NULL, without, NULL), PLX_OK);
    o.no_indirect = 0;
    assert_int_equal(plx_render(e, &c, &o, NULL, with, NULL), PLX_OK);
    for (j = step / 2; j < AH; j += step)
        for (i = step / 2; i < AW; i += step) {
            double nrm[3] = { 0, 0, 1 }, se, ref, img, rgb_old[3];
            int di, dj, same;
            trace_hit h, h2;
            uint64_t id = aerial_surface(e->ph->T, &c, i, j, &h);
            same = id != 0;
            for (dj = -2; dj <= 2 && same; dj += 2)
                for (di = -2; di <= 2 && same; di += 2)
                    same = aerial_surface(e->ph->T, &c, i + di, j + dj, &h2) == id;
            if (!same)
                continue;
            ref = ref_indirect_paths(e->ph->T, e->sc, h.p, nrm, 300, 7u + (uint64_t)(j * AW + i), &se);
            if (ref > 0.3) {
                lit[nlit++] = j * AW + i;
            } else if (ref + 4.0 * se < 0.01) {
                /* dark (closed courtyards, roofs no wall sees): no light added */
                double a = h.kind == TRACE_ROOF ? e->sc->bld[h.bld].albedo : e->sc->ground_albedo;
                img = (with[3 * (j * AW + i)] - without[3 * (j * AW + i)]) * PI / a;
                photon_indirect_rgb(e->ph, h.p, nrm, rgb_old);
                dark_max = fmax(dark_max, img);
                dark_old = fmax(dark_old, rgb_old[0]);
                dark++;
            }
        }
    for (k = 0; k < maxn && k < nlit; k++) {
        int q = lit[(int)((k + 0.5) * nlit / maxn)];
        double nrm[3] = { 0, 0, 1 }, se, ref, img, rgb_old[3], a;
        trace_hit h;
        aerial_surface(e->ph->T, &c, q % AW, q / AW, &h);
        ref = ref_indirect_paths(e->ph->T, e->sc, h.p, nrm, paths, 900u + (uint64_t)k, &se);
        a = h.kind == TRACE_ROOF ? e->sc->bld[h.bld].albedo : e->sc->ground_albedo;
        img = (with[3 * q] - without[3 * q]) * PI / a;
        photon_indirect_rgb(e->ph, h.p, nrm, rgb_old);
        err += fabs(img - ref) / ref;
        err_old += fabs(rgb_old[0] - ref) / ref;
        noise += se / ref;
        roofs += h.kind == TRACE_ROOF;
        n++;
    }
    assert_true(n >= maxn / 2);
    err /= n;
    err_old /= n;
    noise /= n;
    printf("aerial view %dx%d of a generated eixample 2x2, %d lit pixels (%d on roofs), reference %d paths "
           "(its noise %.4f), 4 x 65536 photons: mean relative error of the image's E_indirect %.4f "
           "(irradiance cache: %llu records), photon buffers alone %.4f; bound %.2f%s; %d dark pixels, "
           "most indirect light added there %.4f lx (photon buffers %.4f lx)\n",
           AW, AH, n, roofs, paths, noise, err, (unsigned long long)e->ic->gathered, err_old, bound,
           quick_mode() ? " (quick mode)" : "", dark, dark_max, dark_old);
    assert_true(noise < (quick_mode() ? 0.15 : 0.05)); /* ground in streets: few paths find light */
    assert_true(err <= bound);
    assert_true(err < err_old);
    assert_true(dark >= 4);
    assert_true(dark_max <= 0.15);
    free(lit);
    free(with);
    free(without);
    plx_engine_free(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_image_accuracy),
        cmocka_unit_test(test_image_same_bytes),
        cmocka_unit_test(test_image_after_aerial_same_bytes),
        cmocka_unit_test(test_aerial_without_indirect_gathers_nothing),
        cmocka_unit_test(test_peek_same_bits),
        cmocka_unit_test(test_peek_cells_follow_table),
        cmocka_unit_test(test_aerial_accuracy),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
