/* Photon buffers sized from the budget (plx_config.photon_bytes, 0: half
 * the free bytes when they are first needed; photon_config_fit): every
 * budget is kept, the quality steps grow as it shrinks, the first step
 * (no lamp ray tables) gives the same light, a budget below the lowest
 * quality is refused with a message, and the indirect light at reduced
 * sizes stays close to the default's (the difference is printed).
 * PLX_TEST_QUICK=1: 2 frames of 10,000 photons (else 4 of 40,000), fewer
 * budgets. */
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
#include "photon/irradiance_cache.h"
#include "slow.h"

#define MEM ((size_t)256 << 20)
#define SCENE "fixtures/eixample-4x4.geojson"
#define NPTS 16
#define PHOTONS 40000
#define FRAMES 4

static int quick_mode(void)
{
    const char *v = getenv("PLX_TEST_QUICK");
    return v && v[0] && v[0] != '0';
}

typedef struct run {
    void *mem;
    plx_engine *e;
    plx_status st;
    plx_indirect_info info;
    double Ei[NPTS];
} run;

/* Ground points 2 m beside the first lamps, facing up. */
static void points(plx_engine *e, double *P, double *N)
{
    uint32_t i;
    for (i = 0; i < NPTS; i++) {
        plx_lamp L;
        assert_int_equal(plx_lamp_get(e, i, &L), PLX_OK);
        P[3 * i] = L.x + 2.0;
        P[3 * i + 1] = L.y;
        P[3 * i + 2] = 0.0;
        N[3 * i] = N[3 * i + 1] = 0.0;
        N[3 * i + 2] = 1.0;
    }
}

/* Loads the scene with the photon budget given (0: the default rule),
 * traces FRAMES frames and reads E_indirect from the photon buffers. */
static void do_run(run *r, size_t budget)
{
    plx_config cfg;
    plx_port port = *plx_port_posix();
    double P[3 * NPTS], N[3 * NPTS], Ed[NPTS];
    int k;
    port.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &port;
    cfg.photon_bytes = budget;
    memset(r, 0, sizeof *r);
    r->mem = malloc(MEM);
    assert_non_null(r->mem);
    assert_int_equal(plx_engine_create(r->mem, MEM, &cfg, &r->e), PLX_OK);
    assert_int_equal(plx_load_file(r->e, SCENE), PLX_OK);
    assert_int_equal(plx_indirect_set_gather(r->e, 0), PLX_OK); /* the buffers' own estimate */
    for (k = 0; k < (quick_mode() ? 2 : FRAMES); k++) {
        r->st = plx_indirect_step(r->e, quick_mode() ? PHOTONS / 4 : PHOTONS, (uint64_t)k + 1);
        if (r->st != PLX_OK)
            return;
    }
    assert_int_equal(plx_indirect_info_get(r->e, &r->info), PLX_OK);
    points(r->e, P, N);
    assert_int_equal(plx_illuminance(r->e, NPTS, P, N, Ed, r->Ei, NULL), PLX_OK);
}

static void done(run *r)
{
    plx_engine_destroy(r->e);
    free(r->mem);
}

static void test_budgets_kept(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    run full, r;
    size_t budget;
    uint32_t last = 0;
    (void)state;
    do_run(&full, 0);
    assert_int_equal(full.st, PLX_OK);
    /* the default rule: half the free bytes, far more than they need here */
    assert_int_equal(full.info.reductions, 0);
    assert_true(full.info.lamp_tables);
    assert_true(full.info.bytes <= full.info.full_bytes);
    assert_true(full.info.budget > full.info.full_bytes);
    printf("default quality: %zu bytes (photon_bytes %zu), charts %ux%u, aerial %ux%u, %u lamp slots\n",
           full.info.bytes, full.info.full_bytes, full.info.chart_w, full.info.chart_h, full.info.aerial_w,
           full.info.aerial_h, full.info.lamp_slots);
    for (budget = full.info.full_bytes; budget > 0; budget = quick_mode() ? budget / 2 : budget * 3 / 4) {
        do_run(&r, budget);
        if (r.st != PLX_OK) {
            /* below the lowest quality: refused, saying so */
            assert_int_equal(r.st, PLX_E_NOMEM);
            assert_non_null(strstr(plx_last_error(r.e), "at their lowest quality"));
            printf("budget %zu: refused: %s\n", budget, plx_last_error(r.e));
            done(&r);
            break;
        }
        printf("budget %zu: %zu bytes, %u steps, charts %ux%u, aerial %ux%u (%.2f m), %u slots, tables %d\n",
               budget, r.info.bytes, r.info.reductions, r.info.chart_w, r.info.chart_h, r.info.aerial_w,
               r.info.aerial_h, r.info.aerial_texel, r.info.lamp_slots, r.info.lamp_tables);
        assert_true(r.info.bytes <= budget);
        assert_int_equal(r.info.budget, budget);
        assert_true(r.info.reductions >= last);
        last = r.info.reductions;
        done(&r);
    }
    assert_true(last >= 3); /* the loop went through several steps before refusing */
    assert_true(budget > 0);
    done(&full);
}

/* Just below the default size the irradiance cache's table shrinks first
 * (its share of the budget, icache_records_for), the buffers whole; with
 * the buffers one byte short the lamp ray tables go, nothing else, and the
 * light is the same (lamp rays walk the grid instead). */
static void test_no_tables_same_light(void **state)
{
    run full, r;
    int i, lit = 0;
    uint32_t n = ICACHE_RECORDS;
    size_t P, b;
    (void)state;
    do_run(&full, 0);
    P = full.info.full_bytes - icache_bytes(ICACHE_RECORDS);
    do_run(&r, full.info.full_bytes - 1);
    assert_int_equal(r.st, PLX_OK);
    assert_int_equal(r.info.reductions, 0);
    assert_true(r.info.lamp_tables);
    assert_true(r.info.bytes < full.info.bytes);
    printf("one byte below the default size: the table shrinks, %zu bytes instead of %zu\n", r.info.bytes,
           full.info.bytes);
    for (i = 0; i < NPTS; i++)
        assert_true(r.Ei[i] == full.Ei[i]);
    done(&r);
    b = P - 1 + icache_bytes(n);
    while (n > ICACHE_RECORDS_MIN && icache_records_for(b) < n) {
        n /= 2;
        b = P - 1 + icache_bytes(n);
    }
    do_run(&r, b);
    assert_int_equal(r.st, PLX_OK);
    assert_int_equal(r.info.reductions, 1);
    assert_false(r.info.lamp_tables);
    assert_int_equal(r.info.chart_w, full.info.chart_w);
    assert_int_equal(r.info.aerial_w, full.info.aerial_w);
    for (i = 0; i < NPTS; i++) {
        assert_true(fabs(r.Ei[i] - full.Ei[i]) <= 1e-9 * (1.0 + fabs(full.Ei[i])));
        lit += full.Ei[i] > 0.0;
    }
    assert_true(lit >= NPTS / 2);
    printf("without lamp tables: %zu bytes instead of %zu, the same E_indirect at %d points\n", r.info.bytes,
           full.info.bytes, NPTS);
    done(&r);
    done(&full);
}

/* Coarser charts blur the light, they do not lose it: the mean relative
 * difference from the default quality at points near lamps, printed per
 * budget, and bounded at a quarter of the default size. */
static void test_reduced_quality(void **state)
{
    run full, r;
    int q, i;
    (void)state;
    if (quick_mode()) {   /* with 20,000 photons the noise hides the blur */
        printf("reduced quality: make check-full compares it (PLX_TEST_QUICK is set)\n");
        return;
    }
    do_run(&full, 0);
    for (q = 2; q <= 16; q *= 2) {
        double sum = 0.0, n = 0.0;
        do_run(&r, full.info.full_bytes / (size_t)q);
        if (q > 4 && r.st == PLX_E_NOMEM) {   /* below the lowest quality */
            printf("budget 1/%d of the default: below the lowest quality\n", q);
            done(&r);
            break;
        }
        assert_int_equal(r.st, PLX_OK);
        for (i = 0; i < NPTS; i++)
            if (full.Ei[i] > 0.0) {
                sum += fabs(r.Ei[i] - full.Ei[i]) / full.Ei[i];
                n += 1.0;
            }
        assert_true(n > 0.0);
        printf("budget 1/%d of the default (%zu bytes, %u steps, charts %ux%u, aerial %ux%u): mean relative "
               "difference of E_indirect %.3f over %.0f points\n",
               q, r.info.bytes, r.info.reductions, r.info.chart_w, r.info.chart_h, r.info.aerial_w,
               r.info.aerial_h, sum / n, n);
        if (q <= 4)
            assert_true(sum / n < 0.5);
        done(&r);
    }
    done(&full);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_budgets_kept),
        cmocka_unit_test(test_no_tables_same_light),
        cmocka_unit_test(test_reduced_quality),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
