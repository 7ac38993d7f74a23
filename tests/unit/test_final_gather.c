/* final_gather: E_indirect by final gathering (src/photon/final_gather.h)
 * against independent answers:
 *  - a lamp over an infinite ground next to one infinite black wall: the
 *    one-bounce integral written out below, on the wall and (zero) on the
 *    ground;
 *  - energy in a closed room of uniform albedo a: the indirect light over
 *    all its surfaces is a / (1 - a) times the direct light (the later
 *    bounces come from the photon buffers);
 *  - accuracy against the path tracer (tests/ref/ref_indirect.c) on ground
 *    and facade points of fixtures/eixample-4x4.geojson and, in the full
 *    run, of `gen oldtown 40 40`, at the default settings (the engine's
 *    photon configuration, 16 x 65536 photons, 32 x 32 directions) over six
 *    seeds, next to the photon buffers alone with as many photons;
 *  - photons only from the lamps near the asked point
 *    (plx_indirect_select_lamps), still against the path tracer;
 *  - identical bytes for a seed through the API, whatever the order of the
 *    points.
 * PLX_TEST_QUICK=1 (make check) runs the accuracy on eixample only, with
 * fewer points, paths and seeds, and a looser bound (printed). */
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
#include "base/arena.h"
#include "scene/blocks.h"
#include "light/illuminance.h"
#include "photon/trace.h"
#include "photon/indirect.h"
#include "photon/final_gather.h"
#include "ref_scene.h"
#include "ref_indirect.h"
#include "fixture.h"
#include "slow.h"

#define PI 3.14159265358979323846

static int quick_mode(void)
{
    const char *v = getenv("PLX_TEST_QUICK");
    return v && v[0] && v[0] != '0';
}

typedef struct fixture {
    scene s;
    void *mem;
    arena a;
    light *lt;
    photon_sys *ps;
} fixture;

static void fx_open(fixture *f, size_t bytes)
{
    ref_scene_init(&f->s);
    f->mem = malloc(bytes);
    assert_non_null(f->mem);
    arena_init(&f->a, f->mem, bytes);
}

/* Blocks, the light object and the photon system (gather configuration). */
static void fx_finish(fixture *f)
{
    photon_config c;
    ref_scene_finish(&f->s);
    assert_int_equal(blocks_build(&f->a, &f->s, 0.05), PLX_OK);
    assert_int_equal(light_create(&f->a, &f->s, (size_t)8 << 20, &f->lt), PLX_OK);
    photon_config_gather(&c, &f->s);
    assert_int_equal(photon_create(&f->a, &f->s, &c, &f->ps), PLX_OK);
}

static void fx_close(fixture *f)
{
    ref_scene_free(&f->s);
    free(f->mem);
}

/* ---- one bounce: lamp over the ground beside one black wall ---------------- */

/*
 * The wall is the plane x = 0 (the solid x < 0, albedo 0), the ground z = 0
 * has albedo ag, the lamp (I cd, reach R) stands at (xl, 0, zl). A wall
 * point P = (0, yp, zp) facing +x sees only the ground, lit directly:
 *
 *   E_d(x, y) = I zl / d^3 W(d / R),   d^2 = (x - xl)^2 + y^2 + zl^2,
 *
 * and the ground is Lambertian (L = ag / pi E_d), so
 *
 *   E_ind(P) = integral over x > 0, y of ag / pi E_d(x, y) cos_P cos_Q / r^2
 *
 * with r the distance from P to (x, y, 0), cos_P = x / r (the wall's normal)
 * and cos_Q = zp / r (the ground's). Nothing else bounces: the wall is black
 * and the ground cannot see itself. Midpoint rule on 2 cm cells over the
 * lamp's reach (E_d is 0 beyond it).
 */
static double one_bounce_integral(double xl, double zl, double I, double R, double ag,
                                  double yp, double zp)
{
    double h = 0.02, sum = 0.0, x, y, rg = sqrt(R * R - zl * zl);
    for (x = 0.5 * h; x < xl + rg; x += h)
        for (y = -rg + 0.5 * h; y < rg; y += h) {
            double dx = x - xl, d2 = dx * dx + y * y + zl * zl, d = sqrt(d2), q, ed, r2;
            if (d >= R)
                continue;
            q = 1.0 - pow(d / R, 4.0);
            ed = I * zl / (d2 * d) * q * q;
            r2 = x * x + (y - yp) * (y - yp) + zp * zp;
            sum += ag / PI * ed * (x / sqrt(r2)) * (zp / sqrt(r2)) / r2;
        }
    return sum * h * h;
}

static void test_one_bounce_wall(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    fixture f;
    double xl = 4.0, zl = 5.0, I = 1000.0, R = 30.0, ag = 0.5, worst = 0.0, mean = 0.0;
    double pts[6][2] = {{0, 1}, {-3, 2}, {4, 1.5}, {0, 4}, {6, 3}, {-8, 2}};
    int i;
    (void)state;
    fx_open(&f, 256u << 20);
    assert_true(ref_scene_add_box(&f.s, -100, -100, 0, 100, 40.0, 0.0) >= 0);
    assert_true(ref_scene_add_lamp(&f.s, xl, 0, zl, I, R) >= 0);
    f.s.bld[0].albedo = 0.0;
    f.s.ground_albedo = ag;
    fx_finish(&f);
    photon_step(f.ps, 65536, 1); /* later bounces: none reflected (the wall is black) */
    printf("one bounce ground -> wall, final gathering 32 x 32:\n");
    for (i = 0; i < 6; i++) {
        double P[3] = {0.0, pts[i][0], pts[i][1]}, n[3] = {1, 0, 0}, up[3] = {0, 0, 1};
        double G[3] = {1.0 + i, pts[i][0], 0.0};
        double ref = one_bounce_integral(xl, zl, I, R, ag, P[1], P[2]);
        double est = final_gather_rgb(f.ps, f.ps->T, f.lt, P, n, FINAL_GATHER_SIDE, 7, NULL);
        double err = fabs(est - ref) / ref;
        printf("  y=%5.1f z=%4.1f: gathered %8.4f lx, integral %8.4f lx (%.4f)\n", P[1], P[2],
               est, ref, err);
        mean += err / 6;
        if (err > worst)
            worst = err;
        /* the ground sees only the black wall and the sky */
        assert_true(final_gather_rgb(f.ps, f.ps->T, f.lt, G, up, 8, 7, NULL) == 0.0);
    }
    printf("  mean relative error %.4f, worst %.4f (bounds 0.02, 0.05)\n", mean, worst);
    assert_true(mean < 0.02);
    assert_true(worst < 0.05);
    /* photons reach the wall second (and die there); the ground never is a
     * later hit, so the photons add nothing to the ground's radiance */
    assert_true(f.ps->st.stored_aerial == 0.0 && f.ps->st.stored_chart > 0.0);
    fx_close(&f);
}

/* ---- energy in a closed room ------------------------------------------------ */

/*
 * A courtyard closed by a slab: donut [0,20]^2 minus [5,15]^2, 10 m tall,
 * a slab over [4,16]^2 from 10 to 11 m; the room is [5,15]^2 x [0,10]
 * (floor, four walls, ceiling: 600 m^2), uniform albedo a, one lamp inside
 * with a reach beyond the room. Every lumen that lands is reflected with
 * probability a until absorbed, so the flux landing after one or more
 * bounces is a / (1 - a) times the flux landing directly: the area means of
 * E_indirect and E_direct over the room's surfaces have that ratio. Means
 * by the midpoint rule on 1 m cells of every surface.
 */
static void room_point(int face, int i, int j, double P[3], double n[3])
{
    double u = 5.5 + i, v = 0.5 + j;
    n[0] = n[1] = n[2] = 0.0;
    switch (face) {
    case 0: P[0] = u; P[1] = 5.5 + j; P[2] = 0.0; n[2] = 1; break;
    case 1: P[0] = u; P[1] = 5.5 + j; P[2] = 10.0; n[2] = -1; break;
    case 2: P[0] = 5; P[1] = u; P[2] = v; n[0] = 1; break;
    case 3: P[0] = 15; P[1] = u; P[2] = v; n[0] = -1; break;
    case 4: P[0] = u; P[1] = 5; P[2] = v; n[1] = 1; break;
    default: P[0] = u; P[1] = 15; P[2] = v; n[1] = -1; break;
    }
}

static void test_energy_closed_room(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    fixture f;
    double xy[16] = {0, 0, 20, 0, 20, 20, 0, 20, 5, 5, 5, 15, 15, 15, 15, 5};
    uint32_t rn[2] = {4, 4}, b;
    double a = 0.5, sd = 0.0, si = 0.0, sfirst = 0.0, ratio, s24 = 0.0, s24l = 0.0, sd24 = 0.0;
    int n24 = 0;
    int face, i, j, k;
    (void)state;
    fx_open(&f, 256u << 20);
    assert_true(ref_scene_add_building(&f.s, xy, rn, 2, 10.0, 0.0) >= 0);
    assert_true(ref_scene_add_box(&f.s, 4, 4, 16, 16, 11.0, 10.0) >= 0);
    assert_true(ref_scene_add_lamp(&f.s, 10, 9, 5, 1000, 1e6) >= 0);
    f.s.ground_albedo = a;
    for (b = 0; b < f.s.nbld; b++)
        f.s.bld[b].albedo = a;
    fx_finish(&f);
    for (k = 0; k < 8; k++)
        photon_step(f.ps, 65536, 1 + k);
    for (face = 0; face < 6; face++)
        for (j = 0; j < 10; j++)
            for (i = 0; i < 10; i++) {
                double P[3], n[3], ed, e1;
                room_point(face, i, j, P, n);
                assert_int_equal(light_illuminance(f.lt, P, n, &ed, NULL), PLX_OK);
                sd += ed;
                if ((i + j) % 7 == 0)
                    sd24 += ed;
                si += final_gather_rgb(f.ps, f.ps->T, f.lt, P, n, 16, 3, NULL);
                e1 = final_gather_rgb(NULL, f.ps->T, f.lt, P, n, 16, 3, NULL);
                sfirst += e1;
                /* E_later at one direction of each 3 x 3 strata (the aerial
                 * layer's records): the directions and E_direct are the same */
                s24l += final_gather_rgb_later(f.ps, f.ps->T, f.lt, P, n, 24, 3, 5, NULL);
                if ((i + j) % 7 == 0) {
                    s24 += final_gather_rgb(f.ps, f.ps->T, f.lt, P, n, 24, 5, NULL);
                    n24++;
                    assert_true(final_gather_rgb_later(NULL, f.ps->T, f.lt, P, n, 24, 3, 5, NULL) ==
                                final_gather_rgb(NULL, f.ps->T, f.lt, P, n, 24, 5, NULL));
                }
                if (getenv("SHOWFACE"))
                    printf("face %d: direct %.3f gathered %.3f first %.3f\n", face, ed,
                           final_gather_rgb(f.ps, f.ps->T, f.lt, P, n, 16, 3, NULL), e1);
            }
    ratio = si / sd;
    printf("closed room, albedo %.2f: mean E_direct %.3f lx, E_indirect %.3f lx (first bounce "
           "%.3f); ratio %.4f, expected a / (1 - a) = %.4f (bound 5%%)\n",
           a, sd / 600, si / 600, sfirst / 600, ratio, a / (1 - a));
    assert_true(fabs(ratio - a / (1 - a)) < 0.05 * a / (1 - a));
    printf("24 x 24 directions: ratio %.4f with E_later at one direction in each 3 x 3 strata (all "
           "600 points), %.4f at every direction (%d of them; bound 5%% of the expected)\n",
           s24l / sd, s24 / sd24, n24);
    assert_true(fabs(s24l / sd - a / (1 - a)) < 0.05 * a / (1 - a));
    assert_true(fabs(s24 / sd24 - a / (1 - a)) < 0.05 * a / (1 - a));
    /* the first bounce alone carries a of it: the photons' share matters */
    assert_true(fabs(sfirst / sd - a) < 0.03 * a);
    fx_close(&f);
}

/* ---- accuracy against the path tracer ----------------------------------------- */

static plx_engine *engine_on(const char *path, const char *text, size_t len)
{
    plx_engine *e = fixture_new((size_t)1 << 30, path, text, len);
    assert_int_equal(eng_need(e, ENG_LIGHT, "test"), PLX_OK);
    return e;
}

/* Mean relative errors (gathered, photons alone) over the points and seeds;
 * the photons alone are read as images read them (the wide lookup, photon.h
 * lookup_radius) and with the 2 x 2 lookup (printed). */
static void accuracy(const char *name, plx_engine *e, int npts, int paths, int seeds,
                     double *err_gather, double *err_photons)
{
    double e2 = 0.0, r0;
    double *P = malloc(sizeof *P * 3 * (size_t)npts), *N = malloc(sizeof *N * 3 * (size_t)npts);
    double *ref = malloc(sizeof *ref * (size_t)npts), noise = 0.0, eg = 0.0, ep = 0.0;
    int np, i, sd, k;
    assert_true(P && N && ref);
    assert_int_equal(plx_indirect_step(e, 1, 1), PLX_OK); /* creates the photon system */
    np = ref_indirect_points(e->ph->T, e->sc, npts / 2, npts - npts / 2, 4242, P, N);
    assert_int_equal(np, npts);
    for (i = 0; i < np; i++) {
        double se;
        ref[i] = ref_indirect_paths(e->ph->T, e->sc, P + 3 * i, N + 3 * i, paths, 9000 + i, &se);
        assert_true(ref[i] > 0.0);
        noise += se / ref[i] / np;
    }
    for (sd = 0; sd < seeds; sd++) {
        assert_int_equal(plx_indirect_reset(e), PLX_OK);
        for (k = 0; k < 16; k++)
            assert_int_equal(plx_indirect_step(e, 65536, 1000u * (uint64_t)sd + k + 1), PLX_OK);
        for (i = 0; i < np; i++) {
            double g = final_gather_rgb(e->ph, e->ph->T, e->lt, P + 3 * i, N + 3 * i,
                                        FINAL_GATHER_SIDE, (uint64_t)sd + 1, NULL);
            double p = photon_indirect(e->ph, P + 3 * i, N + 3 * i), p2;
            r0 = e->ph->cfg.lookup_radius;
            e->ph->cfg.lookup_radius = 0.0;
            p2 = photon_indirect(e->ph, P + 3 * i, N + 3 * i);
            e->ph->cfg.lookup_radius = r0;
            e2 += fabs(p2 - ref[i]) / ref[i];
            eg += fabs(g - ref[i]) / ref[i];
            ep += fabs(p - ref[i]) / ref[i];
        }
    }
    *err_gather = eg / (np * seeds);
    *err_photons = ep / (np * seeds);
    printf("%s: %d points, reference %d paths (its noise %.4f), %d seeds of 16 x 65536 photons: "
           "mean relative error gathered %.4f, photon buffers alone %.4f (2 x 2 lookup %.4f)\n",
           name, np, paths, noise, seeds, *err_gather, *err_photons, e2 / (np * seeds));
    assert_true(noise < (quick_mode() ? 0.04 : 0.01));
    free(P);
    free(N);
    free(ref);
}

#include "../bench/gen_text.h"

static void test_accuracy(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    plx_engine *e;
    double eg, ep, bound = quick_mode() ? 0.08 : 0.05;
    (void)state;
    e = engine_on("fixtures/eixample-4x4.geojson", NULL, 0);
    if (quick_mode())
        accuracy("eixample-4x4", e, 8, 6000, 2, &eg, &ep);
    else
        accuracy("eixample-4x4", e, 32, 60000, 6, &eg, &ep);
    printf("  bound %.2f%s\n", bound, quick_mode() ? " (quick mode)" : "");
    assert_true(eg <= bound);
    assert_true(eg < 0.5 * ep);
    plx_engine_free(e);
    if (!quick_mode()) {
        text t = {NULL, 0, 0};
        assert_int_equal(plx_gen_city("oldtown", 40, 40, 1, append, &t), PLX_OK);
        e = engine_on(NULL, t.buf, t.len);
        accuracy("gen oldtown 40 40", e, 32, 60000, 6, &eg, &ep);
        printf("  bound %.2f\n", bound);
        assert_true(eg <= bound);
        assert_true(eg < 0.5 * ep);
        plx_engine_free(e);
        free(t.buf);
    }
}

/* ---- photons from the lamps near the asked point ---------------------------- */

/* Each point asked alone with photons only from the lamps whose reach
 * comes within 100 m of it (plx_indirect_select_lamps): a fraction of the
 * scene's lamps, and the answer still matches the path tracer (the lamps
 * left out reach the point only over more than 100 m). */
static void test_select_lamps(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    plx_engine *e = engine_on("fixtures/eixample-4x4.geojson", NULL, 0);
    int npts = quick_mode() ? 2 : 8, paths = quick_mode() ? 6000 : 40000, np, i, k;
    double P[3 * 8], N[3 * 8], err = 0.0, bound = quick_mode() ? 0.10 : 0.05;
    double bad[4] = {10, 0, 0, 10};
    uint32_t chosen, total = 0;
    (void)state;
    assert_int_equal(plx_indirect_step(e, 1, 1), PLX_OK);
    assert_int_equal(plx_indirect_select_lamps(e, bad, 100.0, NULL), PLX_E_INVALID);
    np = ref_indirect_points(e->ph->T, e->sc, npts / 2, npts - npts / 2, 515, P, N);
    assert_int_equal(np, npts);
    for (i = 0; i < np; i++) {
        double box[4] = {P[3 * i], P[3 * i + 1], P[3 * i], P[3 * i + 1]};
        double ref = ref_indirect_paths(e->ph->T, e->sc, P + 3 * i, N + 3 * i, paths, 70 + i,
                                        NULL);
        double g;
        assert_int_equal(plx_indirect_select_lamps(e, box, 100.0, &chosen), PLX_OK);
        assert_true(chosen > 0 && chosen < e->sc->nlamps);
        assert_int_equal(plx_indirect_frames(e), 0);
        total += chosen;
        for (k = 0; k < 16; k++)
            assert_int_equal(plx_indirect_step(e, 65536, 31 + k), PLX_OK);
        g = final_gather_rgb(e->ph, e->ph->T, e->lt, P + 3 * i, N + 3 * i, FINAL_GATHER_SIDE, 1,
                             NULL);
        err += fabs(g - ref) / ref / np;
    }
    printf("lamps chosen per point: %.1f of %u; mean relative error %.4f (bound %.2f)\n",
           (double)total / np, e->sc->nlamps, err, bound);
    assert_true(err <= bound);
    assert_int_equal(plx_indirect_select_lamps(e, NULL, 0.0, &chosen), PLX_OK);
    assert_int_equal(chosen, e->sc->nlamps);
    plx_engine_free(e);
}

/* ---- same bytes ------------------------------------------------------------------ */

static void answers(double *E, const double *P, const double *N, int n, int reverse)
{
    plx_engine *e = engine_on("fixtures/eixample-4x4.geojson", NULL, 0);
    double ed[64], ei[64];
    int k, i;
    for (k = 0; k < 2; k++)
        assert_int_equal(plx_indirect_step(e, 16384, 5 + k), PLX_OK);
    for (i = 0; i < n; i++) {
        int j = reverse ? n - 1 - i : i;
        assert_int_equal(plx_illuminance(e, 1, P + 3 * j, N + 3 * j, &ed[j], &ei[j], NULL),
                         PLX_OK);
    }
    for (i = 0; i < n; i++)
        E[i] = ei[i];
    plx_engine_free(e);
}

static void test_same_bytes(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    plx_engine *e = engine_on("fixtures/eixample-4x4.geojson", NULL, 0);
    double P[3 * 16], N[3 * 16], a[16], b[16], c[16];
    int i;
    (void)state;
    assert_int_equal(plx_indirect_set_gather(e, 1025), PLX_E_INVALID);
    assert_int_equal(plx_indirect_step(e, 1, 1), PLX_OK);
    assert_int_equal(ref_indirect_points(e->ph->T, e->sc, 8, 8, 99, P, N), 16);
    plx_engine_free(e);
    answers(a, P, N, 16, 0);
    answers(b, P, N, 16, 0);
    answers(c, P, N, 16, 1);
    assert_memory_equal(a, b, sizeof a);
    assert_memory_equal(a, c, sizeof a);
    for (i = 0; i < 16; i++)
        assert_true(a[i] > 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_bounce_wall),
        cmocka_unit_test(test_energy_closed_room),
        cmocka_unit_test(test_accuracy),
        cmocka_unit_test(test_select_lamps),
        cmocka_unit_test(test_same_bytes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
