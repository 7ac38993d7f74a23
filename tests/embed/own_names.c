/* An application with functions of the names the core uses inside
 * (arena_alloc, camera_setup, geom_orient, port_now_ns): it links with the
 * public libpolarlux.a and libpolarlux-port.a, or libpolarlux.so, and the
 * library still uses its own (check-lib-split). Before 2026-12-03 the
 * archives exported 340 such names: the static link failed with "multiple
 * definition", and with the .so the application's arena_alloc replaced the
 * library's (the engine then failed to create). */
#include <stdio.h>
#include <stdlib.h>
#include "polarlux.h"
#include "polarlux_port.h"

static int calls;

void *arena_alloc(void *a, int part, size_t n, size_t align);
int camera_setup(void *r, const void *c, const void *o);
double geom_orient(const double *a, const double *b, const double *c);
unsigned long long port_now_ns(void);

void *arena_alloc(void *a, int part, size_t n, size_t align)
{
    (void)a, (void)part, (void)n, (void)align;
    calls++;
    return NULL;
}
int camera_setup(void *r, const void *c, const void *o)
{
    (void)r, (void)c, (void)o;
    calls++;
    return 0;
}
double geom_orient(const double *a, const double *b, const double *c)
{
    (void)a, (void)b, (void)c;
    calls++;
    return 0.0;
}
unsigned long long port_now_ns(void)
{
    calls++;
    return 0;
}

int main(void)
{
    static const char scene[] = "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
                                "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"intensity\":1000,\"height\":6},"
                                "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,0]}}]}";
    static unsigned char block[4u << 20];
    double P[3] = { 0, 0, 0 }, N[3] = { 0, 0, 1 }, E, Ei;
    plx_engine *e = NULL;
    plx_config cfg;
    plx_status st;
    plx_config_default(&cfg);
    cfg.port = plx_port_posix(); /* the port's object too, with its own port_now_ns inside */
    st = plx_engine_create(block, sizeof block, &cfg, &e);
    if (st != PLX_OK || plx_load_geojson(e, scene, sizeof scene - 1, "own") != PLX_OK ||
        plx_illuminance(e, 1, P, N, &E, &Ei, NULL) != PLX_OK) {
        printf("own_names: the library failed: %s\n", e ? plx_last_error(e) : plx_strerror(st));
        return 1;
    }
    if (calls != 0 || E < 27.68 || E > 27.70) { /* 1000 cd at 6 m: 27.78 lx times W(0.2) = 0.9968 */
        printf("own_names: the application's functions were called %d times, E %.6f\n", calls, E);
        return 1;
    }
    printf("own_names: the library kept its own functions (E %.4f lx under the lamp)\n", E);
    return 0;
}
