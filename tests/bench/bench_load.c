/* Loading benchmark: polarlux's full load (parse into the arena, validate,
 * clean rings, group blocks) against a baseline of cJSON parsing alone with
 * the C heap, in the same process, on the real district and on
 * `gen eixample 30 30`. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cjson/cJSON.h>

#include "polarlux.h"
#include "port.h"

#include "gen_text.h"

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp);
    return v[n / 2];
}

static void bench(const char *name, const char *buf, size_t len, int reps)
{
    static const size_t mem = (size_t)2 << 30;
    double tl[32], tp[32];
    plx_config cfg;
    plx_engine *e;
    plx_scene_info si;
    plx_memory_report m;
    int i;
    plx_port quiet = *plx_port_posix();
    quiet.log = NULL; /* the warnings of the real district are shown by polarlux info */
    plx_config_default(&cfg);
    cfg.port = &quiet;
    if (plx_engine_new(mem, &cfg, &e) != PLX_OK) {
        fprintf(stderr, "cannot create engine\n");
        exit(1);
    }
    for (i = 0; i < reps; i++) {
        unsigned long long t0 = port_now_ns();
        cJSON *root = cJSON_ParseWithLength(buf, len);
        unsigned long long t1 = port_now_ns();
        plx_status st;
        if (!root) {
            fprintf(stderr, "baseline parse failed\n");
            exit(1);
        }
        cJSON_Delete(root);
        tp[i] = (t1 - t0) / 1e6;
        t0 = port_now_ns();
        st = plx_load_geojson(e, buf, len, name);
        tl[i] = (port_now_ns() - t0) / 1e6;
        if (st != PLX_OK) {
            fprintf(stderr, "load failed: %s\n", plx_last_error(e));
            exit(1);
        }
    }
    plx_scene_info_get(e, &si);
    plx_memory_get(e, &m);
    printf("load %-22s %7.1f KB text, %6u buildings, %6u lamps, %6u blocks, %7u vertices\n", name,
           len / 1024.0, si.buildings, si.lamps, si.blocks, si.vertices);
    printf("  polarlux load  median %8.2f ms   | cJSON parse alone (baseline) median %8.2f ms | ratio %.2fx\n",
           median(tl, reps), median(tp, reps), median(tl, reps) / median(tp, reps));
    printf("  memory: scene %.2f MB kept, peak %.2f MB during the load (%.1f bytes of peak per byte of text)\n",
           m.used[PLX_PART_SCENE] / 1048576.0, m.peak_total / 1048576.0, (double)m.peak_total / len);
    plx_engine_free(e);
}

int main(void)
{
    char err[256];
    size_t len;
    char *h = port_read_text("fixtures/helsinki-centre.geojson", &len, err, sizeof err);
    text t = { NULL, 0, 0 };
    if (!h) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    bench("helsinki-centre", h, len, 15);
    free(h);
    if (plx_gen_city("eixample", 30, 30, 1, append, &t) != PLX_OK)
        return 1;
    bench("gen eixample 30 30", t.buf, t.len, 5);
    free(t.buf);
    t.buf = NULL;
    t.len = t.cap = 0;
    if (plx_gen_city("oldtown", 110, 110, 1, append, &t) != PLX_OK)
        return 1;
    bench("gen oldtown 110 110", t.buf, t.len, 5);
    free(t.buf);
    return 0;
}
