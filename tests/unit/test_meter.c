/* Light meters anywhere (SPEC §2): free-air points and points 0.1 mm off a
 * wall, any unit normal, through the public API, exact against the
 * brute-force reference tests/ref/ref_light (which knows nothing of the
 * engine's visibility structures). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "fixture.h"
#include "base/engine.h"
#include "ref_light.h"
#include "ref_scene.h"

#define MEM (256u << 20)

static uint64_t rng_state = 0x1234567887654321ull;

static double uni(double a, double b)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return a + (b - a) * (double)(rng_state >> 11) / 9007199254740992.0;
}

static plx_engine *open_scene(const char *path, void **mem)
{
    return fixture_file(path, MEM, mem);
}

static void random_unit(double n[3])
{
    double l;
    do {
        n[0] = uni(-1, 1);
        n[1] = uni(-1, 1);
        n[2] = uni(-1, 1);
        l = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    } while (l < 0.01 || l > 1.0);
    l = sqrt(l);
    n[0] /= l;
    n[1] /= l;
    n[2] /= l;
}

/* Strictly inside some building's solid, by the reference's own test. */
static int ref_inside(const scene *s, const double P[3])
{
    uint32_t b;
    for (b = 0; b < s->nbld; b++)
        if (P[2] > s->bld[b].min_height && P[2] < s->bld[b].height &&
            ref_footprint_where(s, b, P[0], P[1]) == REF_IN)
            return 1;
    return 0;
}

static int quick(void)
{
    return getenv("PLX_TEST_QUICK") != NULL;
}

/* A point near a lamp: in the air within its reach, or 0.1 mm off one of
 * the walls of a building near it. */
static void meter_point(const scene *s, double P[3], int off_wall)
{
    const scene_lamp *lp = &s->lamps[(uint32_t)uni(0, s->nlamps) % s->nlamps];
    if (off_wall && s->nbld) {
        uint32_t b = (uint32_t)uni(0, s->nbld) % s->nbld, k, j;
        const scene_ring *r = &s->rings[s->bld[b].ring_first];
        double t = uni(0.05, 0.95), ex, ey, len;
        vec2 u, v;
        k = (uint32_t)uni(0, r->count) % r->count;
        j = (k + 1) % r->count;
        u = s->pts[r->first + k];
        v = s->pts[r->first + j];
        ex = v.x - u.x;
        ey = v.y - u.y;
        len = sqrt(ex * ex + ey * ey);
        /* outer rings are counter-clockwise: outside is on the right */
        P[0] = u.x + t * ex + 1e-4 * ey / len;
        P[1] = u.y + t * ey - 1e-4 * ex / len;
        P[2] = uni(s->bld[b].min_height, s->bld[b].height);
        return;
    }
    P[0] = lp->x + uni(-lp->radius, lp->radius);
    P[1] = lp->y + uni(-lp->radius, lp->radius);
    P[2] = uni(0.01, 1.0) < 0.5 ? 1.5 : uni(0.001, 25.0);
}

static void compare_free(const char *path, int npts)
{
    void *mem;
    plx_engine *e = open_scene(path, &mem);
    const scene *s = e->sc;
    int k, inside = 0, lit = 0, walls = 0;
    for (k = 0; k < npts; k++) {
        double P[3], n[3], E = -1, Ei = -1, ref;
        plx_status st;
        meter_point(s, P, k % 3 == 2);
        random_unit(n);
        st = plx_illuminance(e, 1, P, n, &E, &Ei, NULL);
        if (ref_inside(s, P)) {
            /* only a point strictly inside a solid is an error */
            assert_int_equal(st, PLX_E_RANGE);
            assert_true(isnan(E));
            inside++;
            continue;
        }
        if (st != PLX_OK) {
            printf("%s: P=(%.17g, %.17g, %.17g): %s\n", path, P[0], P[1], P[2], plx_last_error(e));
            fail();
        }
        ref = ref_illuminance(s, P, n);
        if (!(fabs(E - ref) <= 1e-9 * fmax(1.0, fabs(ref)))) {
            printf("%s: P=(%.17g, %.17g, %.17g) n=(%g, %g, %g): engine %.17g reference %.17g\n", path, P[0],
                   P[1], P[2], n[0], n[1], n[2], E, ref);
            fail();
        }
        assert_true(Ei == 0.0);
        lit += E > 0.0;
        walls += k % 3 == 2;
    }
    printf("  %s: %d points (%d 0.1 mm off a wall, %d inside a solid), %d lit, all equal to the reference\n", path,
           npts, walls, inside, lit);
    assert_true(lit > npts / 10);
    plx_engine_destroy(e);
    free(mem);
}

static void test_free_air_eixample(void **state)
{
    (void)state;
    compare_free("fixtures/eixample-4x4.geojson", quick() ? 600 : 6000);
}

static void test_free_air_helsinki(void **state)
{
    (void)state;
    compare_free("fixtures/helsinki-centre.geojson", quick() ? 300 : 3000);
}

/* The cases of the issue by hand: 0.1 mm off a wall facing it, 1.5 m above
 * the pavement facing east, and a point strictly inside. */
static void test_free_air_cases(void **state)
{
    static const char text[] =
        "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
        "{\"type\":\"Feature\",\"properties\":{\"height\":10},\"geometry\":{\"type\":\"Polygon\","
        "\"coordinates\":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}},"
        "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":5,\"intensity\":800,\"radius\":40},"
        "\"geometry\":{\"type\":\"Point\",\"coordinates\":[15,5]}}]}";
    void *mem;
    plx_engine *e = fixture_text(text, MEM, 0, &mem);
    double P[9] = { 10.0001, 5, 3, 15, 2, 1.5, 5, 5, 5 }, N[9] = { 1, 0, 0, 1, 0, 0, 0, 0, 1 }, E[3];
    double d2a = 4.9999 * 4.9999 + 4, x;
    double wa;
    (void)state;
    assert_int_equal(plx_illuminance(e, 3, P, N, E, NULL, NULL), PLX_E_RANGE);
    assert_non_null(strstr(plx_last_error(e), "inside"));
    x = sqrt(d2a) / 40;
    wa = (1 - x * x * x * x) * (1 - x * x * x * x);
    assert_true(fabs(E[0] - 800 * (4.9999 / sqrt(d2a)) / d2a * wa) < 1e-12);
    /* (15, 2, 1.5) facing east: the lamp is due north-ish, n.w = 0 */
    assert_true(E[1] == 0.0);
    assert_true(isnan(E[2]));
    fixture_done(e, mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_free_air_cases),
        cmocka_unit_test(test_free_air_eixample),
        cmocka_unit_test(test_free_air_helsinki),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
