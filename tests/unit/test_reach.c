/* plx_lamps_in_reach (the lamp index dark-spots uses) against the plain
 * count over all lamps, on random lamps (some of intensity 0, various radii
 * and heights) and random points, many near reach boundaries. */
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
#include "fixture.h"

#define MEM (64u << 20)

static uint64_t rng = 12345;
static double rnd(void)
{
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static void test_reach_equals_all_lamps(void **state)
{
    char *json = malloc(1 << 20), *p;
    void *mem;
    plx_engine *e;
    plx_scene_info si;
    int i, k, nl = 600, np = getenv("PLX_TEST_QUICK") ? 4000 : 40000, inside = 0;
    (void)state;
    p = json + sprintf(json, "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                             "{\"type\":\"Feature\",\"properties\":{\"height\":10},\"geometry\":{\"type\":\"Polygon\","
                             "\"coordinates\":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}}");
    for (i = 0; i < nl; i++)
        p += sprintf(p, ",{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":%.3f,\"intensity\":%g,"
                        "\"radius\":%.3f},\"geometry\":{\"type\":\"Point\",\"coordinates\":[%.3f,%.3f]}}",
                     12 + 10 * rnd(), i % 7 == 0 ? 0.0 : 1000.0, 15 + 60 * rnd(), -400 + 800 * rnd(), -400 + 800 * rnd());
    strcpy(p, "]}");
    e = fixture_text(json, MEM, 0, &mem);
    plx_scene_info_get(e, &si);
    assert_int_equal(si.lamps, (uint32_t)nl);
    for (k = 0; k < np; k++) {
        double P[3];
        uint32_t c, want = 0;
        plx_lamp l;
        plx_lamp_get(e, (uint32_t)(k % nl), &l);
        if (k % 2) { /* near lamp k's reach boundary */
            double a = 6.283185307179586 * rnd(), r = sqrt(l.radius * l.radius - l.z * l.z) * (0.999 + 0.002 * rnd());
            P[0] = l.x + r * cos(a);
            P[1] = l.y + r * sin(a);
        } else {
            P[0] = -500 + 1000 * rnd();
            P[1] = -500 + 1000 * rnd();
        }
        P[2] = k % 5 == 0 ? 3.0 * rnd() : 0.0;
        for (i = 0; i < nl; i++) {
            double dx, dy, dz;
            plx_lamp_get(e, (uint32_t)i, &l);
            dx = l.x - P[0];
            dy = l.y - P[1];
            dz = l.z - P[2];
            want += l.intensity > 0 && dx * dx + dy * dy + dz * dz < l.radius * l.radius;
        }
        assert_int_equal(plx_lamps_in_reach(e, 1, P, &c), PLX_OK);
        assert_int_equal(c, want);
        inside += want > 0;
    }
    assert_true(inside > np / 4 && inside < np);
    assert_int_equal(plx_lamps_in_reach(e, 1, NULL, NULL), PLX_E_INVALID);
    fixture_done(e, mem);
    free(json);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reach_equals_all_lamps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
