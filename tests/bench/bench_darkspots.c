/* dark-spots benchmark: which grid points lie in some lamp's reach, on a
 * city of 30,600 lamps (a 6 x 6 km street grid, streets every 120 m, a lamp
 * every 20 m, Montpellier's count) and 2,500 buildings, at dark-spots'
 * default 2 m grid. Side by side in the same process: the lamps' spatial
 * index (plx_lamps_in_reach, what 'polarlux dark-spots' uses) and the
 * all-lamps scan the command used before (every lamp at every point), on
 * the same points; the counts must be identical. The scan runs on every
 * 1000th point only (hours on all of them); its time on the
 * whole grid is extrapolated from that. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "polarlux.h"
#include "port.h"

#define SIDE 6000.0
#define STREET 120.0
#define LAMP_STEP 20.0
#define RES 2.0
#define SUBSET 1000

typedef struct text {
    char *buf;
    size_t len, cap;
} text;

static void put(text *t, const char *s)
{
    size_t n = strlen(s);
    if (t->len + n + 1 > t->cap) {
        t->cap = (t->len + n + 1) * 2;
        t->buf = realloc(t->buf, t->cap);
        if (!t->buf) {
            fprintf(stderr, "bench_darkspots: out of memory\n");
            exit(1);
        }
    }
    memcpy(t->buf + t->len, s, n + 1);
    t->len += n;
}

static void city(text *t, unsigned *nlamps, unsigned *nbld)
{
    char f[512];
    double a, b;
    int first = 1;
    put(t, "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[");
    for (a = 0; a + STREET <= SIDE; a += STREET)
        for (b = 0; b + STREET <= SIDE; b += STREET, (*nbld)++) {
            snprintf(f, sizeof f, "%s{\"type\":\"Feature\",\"properties\":{\"height\":15},\"geometry\":"
                     "{\"type\":\"Polygon\",\"coordinates\":[[[%g,%g],[%g,%g],[%g,%g],[%g,%g],[%g,%g]]]}}",
                     first ? "" : ",", a + 12, b + 12, a + 108, b + 12, a + 108, b + 108, a + 12, b + 108, a + 12,
                     b + 12);
            put(t, f);
            first = 0;
        }
    for (a = 0; a <= SIDE; a += STREET)
        for (b = 0; b < SIDE; b += LAMP_STEP) {
            int k;
            for (k = 0; k < 2; k++, (*nlamps)++) {
                snprintf(f, sizeof f, ",{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":8,"
                         "\"intensity\":1500,\"radius\":35},\"geometry\":{\"type\":\"Point\",\"coordinates\":"
                         "[%g,%g]}}", k ? b + 10 : a, k ? a : b + 10);
                put(t, f);
            }
        }
    put(t, "]}");
}

/* The all-lamps scan: the command's former in_reach, with the index's rule. */
static unsigned scan_count(plx_engine *e, unsigned nlamps, const double P[3])
{
    unsigned k, c = 0;
    for (k = 0; k < nlamps; k++) {
        plx_lamp l;
        double dx, dy, dz;
        plx_lamp_get(e, k, &l);
        dx = l.x - P[0];
        dy = l.y - P[1];
        dz = l.z - P[2];
        if (l.intensity > 0 && dx * dx + dy * dy + dz * dz < l.radius * l.radius)
            c++;
    }
    return c;
}

int main(void)
{
    text t = { NULL, 0, 0 };
    plx_engine *e;
    plx_config cfg;
    plx_port quiet = *plx_port_posix();
    plx_scene_info si;
    unsigned nlamps = 0, nbld = 0;
    size_t w, h, n, k, ns = 0, in = 0, mismatch = 0, strip = 65536;
    double *P;
    uint32_t *cnt;
    unsigned long long t0, t_index, t_scan;
    quiet.log = NULL;
    plx_config_default(&cfg);
    cfg.port = &quiet;
    city(&t, &nlamps, &nbld);
    if (plx_engine_new((size_t)1 << 30, &cfg, &e) != PLX_OK || plx_load_geojson(e, t.buf, t.len, "city") != PLX_OK) {
        fprintf(stderr, "bench_darkspots: setup failed\n");
        return 1;
    }
    free(t.buf);
    plx_scene_info_get(e, &si);
    w = (size_t)floor((si.bounds[2] - si.bounds[0]) / RES);
    h = (size_t)floor((si.bounds[3] - si.bounds[1]) / RES);
    n = w * h;
    P = malloc(sizeof *P * 3 * strip);
    cnt = malloc(sizeof *cnt * strip);
    if (!P || !cnt)
        return 1;
    plx_lamps_in_reach(e, 0, P, cnt); /* sets up the lamp index */
    /* the index on the whole grid */
    t0 = port_now_ns();
    for (k = 0; k < n; k += strip) {
        size_t m = k + strip < n ? strip : n - k, j;
        for (j = 0; j < m; j++) {
            P[3 * j] = si.bounds[0] + ((k + j) % w + 0.5) * RES;
            P[3 * j + 1] = si.bounds[1] + ((k + j) / w + 0.5) * RES;
            P[3 * j + 2] = 0;
        }
        plx_lamps_in_reach(e, m, P, cnt);
        for (j = 0; j < m; j++)
            in += cnt[j] > 0;
    }
    t_index = port_now_ns() - t0;
    /* both on every SUBSET-th point: same counts? the scan's time */
    t_scan = 0;
    for (k = 0; k < n; k += SUBSET, ns++) {
        double Q[3];
        uint32_t c;
        Q[0] = si.bounds[0] + (k % w + 0.5) * RES;
        Q[1] = si.bounds[1] + (k / w + 0.5) * RES;
        Q[2] = 0;
        plx_lamps_in_reach(e, 1, Q, &c);
        t0 = port_now_ns();
        if (scan_count(e, si.lamps, Q) != c)
            mismatch++;
        t_scan += port_now_ns() - t0;
    }
    printf("bench_darkspots: %u lamps, %u buildings, %.0f x %.0f m, %g m grid: %zu points (%zu in reach)\n",
           si.lamps, si.buildings, si.bounds[2] - si.bounds[0], si.bounds[3] - si.bounds[1], RES, n, in);
    printf("  lamp index:     %8.1f ns/point, whole grid %.2f s\n", (double)t_index / n, t_index / 1e9);
    printf("  all-lamps scan: %8.1f ns/point (on %zu points), whole grid ~%.0f s (extrapolated)\n",
           (double)t_scan / ns, ns, (double)t_scan / ns * n / 1e9);
    printf("  ratio scan / index: %.0fx; counts identical on %zu of %zu points\n",
           ((double)t_scan / ns) / ((double)t_index / n), ns - mismatch, ns);
    free(P);
    free(cnt);
    plx_engine_free(e);
    return mismatch ? 1 : 0;
}
