/* Route scoring benchmark: metres of route scored per second on
 * `gen eixample 30 30` (street centre lines sampled every metre), against
 * the brute-force SPEC §2 reference (tests/ref/ref_light) on a few of the
 * same sample points, in the same process. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "port.h"
#include "base/engine.h"
#include "ref_light.h"

#include "gen_text.h"

int main(void)
{
    text t = { NULL, 0, 0 };
    plx_engine *e;
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    double metres = 0, secs, ref_secs, per_ref;
    unsigned long long t0;
    int i, nref = 300, k;
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    if (plx_gen_city("eixample", 30, 30, 1, append, &t) != PLX_OK || plx_engine_new((size_t)1 << 30, &cfg, &e) != PLX_OK ||
        plx_load_geojson(e, t.buf, t.len, "eixample") != PLX_OK) {
        fprintf(stderr, "setup failed\n");
        return 1;
    }
    free(t.buf);
    /* warm the lit-region cache once, as a navigation app would */
    {
        double xy[4] = { 133.0 * 5, 0, 133.0 * 5, 133.0 * 30 };
        plx_route_stats s;
        plx_route_score(e, xy, 2, 1.0, 1.0, &s, NULL);
    }
    t0 = port_now_ns();
    for (i = 1; i < 30; i += 2) { /* 15 north-south streets, the whole city long */
        double xy[4] = { 133.0 * i, 0, 133.0 * i, 133.0 * 30 };
        plx_route_stats s;
        if (plx_route_score(e, xy, 2, 1.0, 1.0, &s, NULL) != PLX_OK) {
            fprintf(stderr, "%s\n", plx_last_error(e));
            return 1;
        }
        metres += s.length + s.blocked_length;
    }
    secs = (port_now_ns() - t0) / 1e9;
    /* the brute force on nref sample points of the same streets */
    t0 = port_now_ns();
    for (k = 0; k < nref; k++) {
        double P[3] = { 133.0 * (1 + 2 * (k % 15)), 133.0 * 30 * (k + 0.5) / nref, 0 }, n[3] = { 0, 0, 1 };
        volatile double E = ref_illuminance(e->sc, P, n);
        (void)E;
    }
    ref_secs = (port_now_ns() - t0) / 1e9;
    per_ref = nref / ref_secs;
    printf("route scoring on gen eixample 30 30 (14,400 buildings, 18,480 lamps), 1 m steps\n");
    printf("  polarlux      %10.0f m of route in %.3f s = %10.0f m/s\n", metres, secs, metres / secs);
    printf("  brute force   %10d samples in %.3f s   = %10.0f m/s (tests/ref/ref_light, every lamp and building)\n",
           nref, ref_secs, per_ref);
    printf("  ratio         %.0fx\n", (metres / secs) / per_ref);
    plx_engine_free(e);
    return 0;
}
