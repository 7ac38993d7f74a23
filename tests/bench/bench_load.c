/* Loading benchmark: polarlux's full load (parse into the arena, validate,
 * clean rings, group blocks) against a baseline of cJSON parsing alone with
 * the C heap, in the same process, on the real district and on
 * `gen eixample 30 30`; and plx_load_file of that city from a file, read in
 * place through the port's mapping (plx_port.file_map) against the read
 * path (file_map NULL: the file copied into the block) as the baseline. */
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

/* Median time and the block's high-water mark of plx_load_file with port. */
static double file_loads(const plx_port *port, const char *path, int reps, size_t *peak)
{
    double t[32];
    plx_config cfg;
    plx_engine *e;
    plx_memory_report m;
    int i;
    plx_config_default(&cfg);
    cfg.port = port;
    if (plx_engine_new((size_t)1 << 30, &cfg, &e) != PLX_OK) {
        fprintf(stderr, "cannot create engine\n");
        exit(1);
    }
    for (i = 0; i < reps; i++) {
        unsigned long long t0 = port_now_ns();
        if (plx_load_file(e, path) != PLX_OK) {
            fprintf(stderr, "load failed: %s\n", plx_last_error(e));
            exit(1);
        }
        t[i] = (port_now_ns() - t0) / 1e6;
    }
    plx_memory_get(e, &m);
    *peak = m.peak_total;
    plx_engine_free(e);
    return median(t, reps);
}

static void bench_file(const char *name, const text *t)
{
    char path[] = "/tmp/plx_bench_load_XXXXXX";
    plx_port mapped = *plx_port_posix(), read = *plx_port_posix();
    size_t pm, pr;
    double tm, tr;
    FILE *f;
    int fd = mkstemp(path);
    if (fd < 0 || !(f = fdopen(fd, "wb")) || fwrite(t->buf, 1, t->len, f) != t->len || fclose(f) != 0) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
    read.file_map = NULL;
    read.file_unmap = NULL;
    tm = file_loads(&mapped, path, 7, &pm);
    tr = file_loads(&read, path, 7, &pr);
    remove(path);
    printf("plx_load_file %s, %.1f KB file\n", name, t->len / 1024.0);
    printf("  mapped (file_map)  median %8.2f ms   | read into the block (baseline) median %8.2f ms | ratio %.2fx\n",
           tm, tr, tm / tr);
    printf("  block high-water: mapped %.2f MB, read %.2f MB (the file's %.2f MB)\n", pm / 1e6, pr / 1e6,
           t->len / 1e6);
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
    bench_file("gen eixample 30 30", &t);
    free(t.buf);
    t.buf = NULL;
    t.len = t.cap = 0;
    if (plx_gen_city("oldtown", 110, 110, 1, append, &t) != PLX_OK)
        return 1;
    bench("gen oldtown 110 110", t.buf, t.len, 5);
    free(t.buf);
    return 0;
}
