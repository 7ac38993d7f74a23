/* plx_load_file through the port's read-only view of the file
 * (plx_port.file_map, port/posix: mmap), issue #16:
 *  - the engine's high-water mark for a file is that of the same text held
 *    by the caller (plx_load_geojson), the scene plus the loader's window;
 *    the process's anonymous memory (RssAnon) grows by that and not by the
 *    file, which the read path (a port without file_map) copies into the
 *    block;
 *  - the loader never reads past the text: every corpus file, the small
 *    fixtures and every prefix of two of them are loaded from a view that
 *    ends right before a page that cannot be read (any byte read past the
 *    end faults), with the same status and message as from the caller's
 *    NUL-terminated copy; and files of exactly one page mapped by the POSIX
 *    port, ending in a number;
 *  - the view is ended on every path (success, bad JSON, bad scene, out of
 *    memory, every failing allocation);
 *  - a missing file, a directory, a FIFO (not waited on), a device and an
 *    empty file give the same status and message with and without
 *    file_map; a port without file_map still loads, one with only file_map
 *    too. */
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS, madvise */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "port.h"
#include "fixture.h"
#include "slow.h"

static char tmpdir[512];

static int make_tmpdir(void **state)
{
    const char *base = getenv("TMPDIR");
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "%s/plx_test_loadfile.XXXXXX", base && base[0] ? base : "/tmp");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int remove_tmpdir(void **state)
{
    DIR *d = opendir(tmpdir);
    struct dirent *de;
    char p[1024];
    (void)state;
    while (d && (de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
            continue;
        snprintf(p, sizeof p, "%s/%s", tmpdir, de->d_name);
        if (unlink(p) != 0)
            rmdir(p);
    }
    if (d)
        closedir(d);
    return rmdir(tmpdir);
}

static const char *tmp_path(const char *name)
{
    static char p[1024];
    snprintf(p, sizeof p, "%s/%s", tmpdir, name);
    return p;
}

static void write_file(const char *path, const char *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_true(fwrite(data, 1, len, f) == len);
    assert_int_equal(fclose(f), 0);
}

/* ---- engines in fresh pages ---------------------------------------------------- */

typedef struct eng {
    void *block;
    size_t size;
    plx_engine *e;
} eng;

/* An engine in a block of its own pages (mmap: untouched until used, so
 * RssAnon grows by what the engine touches). */
static void eng_open(eng *x, size_t size, const plx_port *port)
{
    plx_config cfg;
    plx_config_default(&cfg);
    cfg.port = port;
    x->size = size;
    x->block = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    assert_true(x->block != MAP_FAILED);
#ifdef MADV_NOHUGEPAGE
    madvise(x->block, size, MADV_NOHUGEPAGE); /* pages of 4 KiB, even where huge pages are always on */
#endif
    assert_int_equal(plx_engine_create(x->block, size, &cfg, &x->e), PLX_OK);
}

static void eng_close(eng *x)
{
    plx_engine_destroy(x->e);
    munmap(x->block, x->size);
}

/* RssAnon of /proc/self/status in KiB (-1 when there is none). */
static long rss_anon_kib(void)
{
    char line[256];
    long kib = -1;
    FILE *f = fopen("/proc/self/status", "r");
    if (!f)
        return -1;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "RssAnon: %ld", &kib) == 1)
            break;
    fclose(f);
    return kib;
}

/* ---- ports ------------------------------------------------------------------------ */

/* The POSIX port without its log. */
static plx_port quiet_port(void)
{
    plx_port p = *plx_port_posix();
    p.log = NULL;
    return p;
}

/* The same without file_map: plx_load_file reads the file into the block. */
static plx_port read_port(void)
{
    plx_port p = quiet_port();
    p.file_map = NULL;
    p.file_unmap = NULL;
    return p;
}

/* The POSIX mapping, counted (ctx: a counts). */
typedef struct counts {
    int maps, unmaps;
} counts;

static int counted_map(void *ctx, const char *path, const void **data, size_t *size, void **handle, char *err,
                       size_t errlen)
{
    int r = plx_port_posix()->file_map(NULL, path, data, size, handle, err, errlen);
    if (r == 0)
        ((counts *)ctx)->maps++;
    return r;
}

static void counted_unmap(void *ctx, void *handle)
{
    ((counts *)ctx)->unmaps++;
    plx_port_posix()->file_unmap(NULL, handle);
}

static plx_port counted_port(counts *c)
{
    plx_port p = quiet_port();
    p.ctx = c;
    p.file_map = counted_map;
    p.file_unmap = counted_unmap;
    return p;
}

/* A view that ends right before a page that cannot be read: the file's
 * bytes copied to the end of readable pages followed by a PROT_NONE page. */
typedef struct guarded {
    char *base;
    size_t len;
} guarded;

static size_t page_size(void)
{
    return (size_t)sysconf(_SC_PAGESIZE);
}

static int guards_lost;        /* mprotect calls refused (an emulator) */

static guarded *guard_text(const char *text, size_t len)
{
    size_t pg = page_size(), pages = (len + pg - 1) / pg + 1;
    guarded *g = malloc(sizeof *g);
    assert_non_null(g);
    g->len = pages * pg;
    g->base = mmap(NULL, g->len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    assert_true(g->base != MAP_FAILED);
    /* under qemu-user mprotect may fail on such a mapping: then the view
     * is compared unguarded (guards_lost counts it; the tests say so) */
    if (mprotect(g->base + g->len - pg, pg, PROT_NONE) != 0)
        guards_lost++;
    memcpy(g->base + g->len - pg - len, text, len);
    if (mprotect(g->base, g->len - pg, PROT_READ) != 0)
        guards_lost++;
    return g;
}

static void guard_end(guarded *g)
{
    munmap(g->base, g->len);
    free(g);
}

static int guarded_map(void *ctx, const char *path, const void **data, size_t *size, void **handle, char *err,
                       size_t errlen)
{
    size_t len;
    char *text = port_read_text(path, &len, err, errlen);
    guarded *g;
    (void)ctx;
    if (!text)
        return -1;
    g = guard_text(text, len);
    free(text);
    *data = g->base + g->len - page_size() - len;
    *size = len;
    *handle = g;
    return 0;
}

static void guarded_unmap(void *ctx, void *handle)
{
    (void)ctx;
    guard_end(handle);
}

static plx_port guarded_port(void)
{
    plx_port p = quiet_port();
    p.file_map = guarded_map;
    p.file_unmap = guarded_unmap;
    return p;
}

/* ---- the load peak ------------------------------------------------------------- */

/* Loads path (or text when path is NULL) into a fresh engine; the engine's
 * report and the growth of RssAnon in bytes. */
static void measured_load(const plx_port *port, const char *path, const fixture_city *text, size_t block,
                          plx_memory_report *m, long *anon)
{
    eng x;
    long a0, a1;
    plx_status st;
    eng_open(&x, block, port);
    a0 = rss_anon_kib();
    st = path ? plx_load_file(x.e, path) : plx_load_geojson(x.e, text->buf, text->len, "gen");
    a1 = rss_anon_kib();
    assert_int_equal(st, PLX_OK);
    plx_memory_get(x.e, m);
    *anon = (a1 - a0) * 1024;
    eng_close(&x);
}

static void test_map_peak(void **state)
{
    int quick = getenv("PLX_TEST_QUICK") != NULL, n = quick ? 12 : 86;
    size_t block = quick ? (size_t)8 << 20 : (size_t)64 << 20;
    const char *path = tmp_path("city.geojson");
    fixture_city g;
    plx_port mp = quiet_port(), rp = read_port();
    plx_memory_report mm, mt, mr;
    plx_scene_size sz;
    long am, at, ar;
    size_t window;
    (void)state;
    fixture_gen("eixample", n, n, 1, &g);
    assert_int_equal(plx_scene_size_scan(g.buf, g.len, &sz), PLX_OK);
    write_file(path, g.buf, g.len);
    measured_load(&mp, NULL, &g, block, &mt, &at); /* first: the loader's first run warms up */
    measured_load(&mp, path, NULL, block, &mm, &am);
    measured_load(&rp, path, NULL, block + g.len, &mr, &ar);
    window = 8 * (size_t)sz.features + 32 * (size_t)sz.positions + ((size_t)1 << 20);
    print_message("gen eixample %d %d, %zu bytes: load peak with file_map %zu, text in memory %zu, read into "
                  "the block %zu (scene %zu, window allowed %zu); RssAnon +%ld, +%ld, +%ld KiB\n",
                  n, n, g.len, mm.peak_total, mt.peak_total, mr.peak_total, mm.used[PLX_PART_SCENE], window,
                  am / 1024, at / 1024, ar / 1024);
    /* the mapped file is not in the block: the same peak as text in memory */
    assert_true(mm.peak_total <= mt.peak_total + 4096 && mt.peak_total <= mm.peak_total + 4096);
    assert_true(mm.used_total == mt.used_total);
    assert_true(mm.peak_total <= mm.used_total + window);
    /* the read path holds the whole file besides */
    assert_true(mr.peak_total >= mm.peak_total + g.len);
    /* the process: anonymous memory grows by the block's pages, not the file
     * (its pages are the page cache's, counted in RssFile while mapped) */
    if (am >= 0 && ar >= 0) {
        assert_true((size_t)am <= mm.peak_total + ((size_t)512 << 10));
        assert_true((size_t)ar >= (size_t)am + g.len - g.len / 4);
    }
    free(g.buf);
    unlink(path);
}

/* ---- never past the end ------------------------------------------------------- */

/* Loads text from the caller's NUL-terminated copy and from a guarded view
 * of the file holding it: the same status, message and counts. */
static void same_from_guarded(const char *text, size_t len, const char *path)
{
    plx_port gp = guarded_port();
    plx_scene_info a, b;
    eng x, y;
    plx_status sa, sb;
    eng_open(&x, (size_t)16 << 20, &gp);
    eng_open(&y, (size_t)16 << 20, &gp);
    write_file(path, text, len);
    sa = plx_load_geojson(x.e, text, len, path);
    sb = plx_load_file(y.e, path);
    if (sa != sb || strcmp(plx_last_error(x.e), plx_last_error(y.e)) != 0)
        fail_msg("%s (%zu bytes): from memory %d '%s', from a guarded view %d '%s'", path, len, sa,
                 plx_last_error(x.e), sb, plx_last_error(y.e));
    if (sa == PLX_OK) {
        assert_int_equal(plx_scene_info_get(x.e, &a), PLX_OK);
        assert_int_equal(plx_scene_info_get(y.e, &b), PLX_OK);
        assert_int_equal(a.buildings, b.buildings);
        assert_int_equal(a.lamps, b.lamps);
        assert_int_equal(a.vertices, b.vertices);
        assert_memory_equal(a.bounds, b.bounds, sizeof a.bounds);
    }
    eng_close(&x);
    eng_close(&y);
}

static void guarded_file(const char *src, int prefixes)
{
    char err[256];
    size_t len, n;
    char *text = port_read_text(src, &len, err, sizeof err);
    const char *path = tmp_path("guarded.geojson");
    if (!text)
        fail_msg("%s: %s", src, err);
    same_from_guarded(text, len, path);
    for (n = 0; prefixes && n < len; n++)
        same_from_guarded(text, n, path);
    free(text);
    unlink(path);
}

static void test_guarded_views(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    static const char *const fixtures[] = {
        "fixtures/tiny.geojson", "fixtures/grid-4x4.geojson", "fixtures/ground-image.geojson",
        "fixtures/net-detour.geojson", "fixtures/oldtown-8x8.geojson", "fixtures/helsinki-centre.geojson",
    };
    DIR *d = opendir("tests/corpus");
    struct dirent *de;
    char p[512];
    size_t i;
    int files = 0;
    (void)state;
    assert_non_null(d);

    while ((de = readdir(d)) != NULL) {
        size_t k = strlen(de->d_name);
        if (k < 8 || strcmp(de->d_name + k - 8, ".geojson") != 0)
            continue;
        snprintf(p, sizeof p, "tests/corpus/%s", de->d_name);
        guarded_file(p, 0);
        files++;
    }
    closedir(d);
    assert_true(files >= 30);
    for (i = 0; i < sizeof fixtures / sizeof fixtures[0]; i++)
        guarded_file(fixtures[i], 0);
    /* every prefix: texts cut in a number, a string, an escape, a key, ... */
    guarded_file("fixtures/tiny.geojson", 1);
    guarded_file("tests/corpus/wrong-types-lamp.geojson", 1);
    if (guards_lost)
        print_message("note: mprotect refused %d times here (an emulator?): those views were compared "
                      "without the unreadable page after them\n", guards_lost);
}

/* A text of exactly 'len' bytes: head, spaces, tail. */
static char *padded(const char *head, const char *tail, size_t len)
{
    char *t = malloc(len);
    size_t h = strlen(head), k = strlen(tail);
    assert_non_null(t);
    assert_true(h + k <= len);
    memcpy(t, head, h);
    memset(t + h, ' ', len - h - k);
    memcpy(t + len - k, tail, k);
    return t;
}

/* Files of exactly one page, ending in a number, through the POSIX port's
 * own mapping (the byte after the last is past the mapping) and a guarded
 * view (a fault for certain). */
static void test_page_sized_files(void **state)
{
    static const char *const heads[] = {
        "", /* a lone number: valid JSON, not a FeatureCollection */
        "{\"type\":\"FeatureCollection\",\"features\":[{\"type\":\"Feature\",\"properties\":{},"
        "\"geometry\":{\"type\":\"Point\",\"coordinates\":[1,",
        "[1e",
    };
    size_t pg = page_size(), i;
    const char *path = tmp_path("page.geojson");
    plx_port mp = quiet_port();
    (void)state;
    for (i = 0; i < sizeof heads / sizeof heads[0]; i++) {
        char *t = padded(heads[i], "12345.678e-1", pg);
        eng x, y;
        plx_status sa, sb;
        same_from_guarded(t, pg, path);
        eng_open(&x, (size_t)1 << 20, &mp);
        eng_open(&y, (size_t)1 << 20, &mp);
        sa = plx_load_geojson(x.e, t, pg, path);
        sb = plx_load_file(y.e, path);
        assert_true(sa == PLX_E_PARSE || sa == PLX_E_SCENE);
        assert_int_equal(sa, sb);
        assert_string_equal(plx_last_error(x.e), plx_last_error(y.e));
        eng_close(&x);
        eng_close(&y);
        free(t);
    }
    unlink(path);
}

/* ---- the view is ended on every path ------------------------------------------- */

static void test_unmapped_on_every_path(void **state)
{
    static const char *const texts[] = {
        "{\"type\":\"FeatureCollection\",\"features\":[]}", /* loads */
        "{\"type\":\"FeatureCollection\",\"features\":[", /* bad JSON */
        "{\"type\":\"Feature\"}",                          /* not a collection */
    };
    static const plx_status want[] = { PLX_OK, PLX_E_PARSE, PLX_E_SCENE };
    const char *path = tmp_path("paths.geojson");
    counts c = { 0, 0 };
    plx_port cp = counted_port(&c);
    plx_config cfg;
    plx_engine *e;
    void *small;
    eng x;
    uint64_t k;
    size_t i;
    (void)state;
    eng_open(&x, (size_t)4 << 20, &cp);
    for (i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        write_file(path, texts[i], strlen(texts[i]));
        assert_int_equal(plx_load_file(x.e, path), want[i]);
        assert_int_equal(c.maps, (int)i + 1);
        assert_int_equal(c.unmaps, c.maps);
    }
    /* refused before anything is mapped */
    assert_int_equal(plx_load_file(x.e, tmp_path("missing.geojson")), PLX_E_IO);
    assert_int_equal(c.maps, 3);
    assert_int_equal(c.unmaps, 3);
    /* every allocation of a load failing in turn */
    for (k = 1;; k++) {
        plx_status st;
        plx_debug_fail_alloc(x.e, k);
        st = plx_load_file(x.e, "fixtures/tiny.geojson");
        plx_debug_fail_alloc(x.e, 0);
        assert_int_equal(c.unmaps, c.maps);
        if (st == PLX_OK)
            break;
        assert_int_equal(st, PLX_E_NOMEM);
    }
    assert_true(k > 3);
    eng_close(&x);
    /* a block too small for the scene */
    plx_config_default(&cfg);
    cfg.port = &cp;
    small = malloc(64 << 10);
    assert_non_null(small);
    assert_int_equal(plx_engine_create(small, 64 << 10, &cfg, &e), PLX_OK);
    assert_int_equal(plx_load_file(e, "fixtures/helsinki-centre.geojson"), PLX_E_NOMEM);
    assert_int_equal(c.unmaps, c.maps);
    plx_engine_destroy(e);
    free(small);
    unlink(path);
}

/* ---- errors and ports without the mapping ---------------------------------------- */

static void same_error(const char *path, plx_status want, const char *why)
{
    plx_port mp = quiet_port(), rp = read_port();
    eng x, y;
    char msg[600];
    eng_open(&x, (size_t)1 << 20, &mp);
    eng_open(&y, (size_t)1 << 20, &rp);
    assert_int_equal(plx_load_file(x.e, path), want);
    assert_int_equal(plx_load_file(y.e, path), want);
    assert_string_equal(plx_last_error(x.e), plx_last_error(y.e));
    snprintf(msg, sizeof msg, "%s: %s", path, why);
    if (why[0] && strcmp(plx_last_error(x.e), msg) != 0)
        fail_msg("'%s', want '%s'", plx_last_error(x.e), msg);
    eng_close(&x);
    eng_close(&y);
}

static void test_errors_as_before(void **state)
{
    const char *fifo = tmp_path("in.fifo");
    char fifo_path[1024];
    (void)state;
    snprintf(fifo_path, sizeof fifo_path, "%s", fifo);
    assert_int_equal(mkfifo(fifo_path, 0600), 0);
    same_error(fifo_path, PLX_E_IO, "not a regular file (a FIFO)"); /* returns at once: no writer needed */
    same_error(tmpdir, PLX_E_IO, "not a regular file (a directory)");
    same_error("/dev/zero", PLX_E_IO, "not a regular file (a device)");
    same_error(tmp_path("missing.geojson"), PLX_E_IO, "cannot open: No such file or directory");
    write_file(tmp_path("empty.geojson"), "", 0);
    same_error(tmp_path("empty.geojson"), PLX_E_PARSE, "");
    unlink(fifo_path);
}

static void test_ports_without_the_mapping(void **state)
{
    plx_port rp = read_port(), mp = quiet_port(), only_map = quiet_port(), none = quiet_port();
    plx_scene_info a, b, c;
    plx_memory_report mr, mm;
    eng x, y, z, w;
    struct stat st;
    (void)state;
    only_map.file_size = NULL;
    only_map.file_read = NULL;
    none.file_map = NULL;
    none.file_unmap = NULL;
    none.file_size = NULL;
    eng_open(&x, (size_t)16 << 20, &rp);
    eng_open(&y, (size_t)16 << 20, &mp);
    eng_open(&z, (size_t)16 << 20, &only_map);
    eng_open(&w, (size_t)16 << 20, &none);
    assert_int_equal(stat("fixtures/helsinki-centre.geojson", &st), 0);
    assert_int_equal(plx_load_file(x.e, "fixtures/helsinki-centre.geojson"), PLX_OK);
    assert_int_equal(plx_load_file(y.e, "fixtures/helsinki-centre.geojson"), PLX_OK);
    assert_int_equal(plx_load_file(z.e, "fixtures/helsinki-centre.geojson"), PLX_OK);
    assert_int_equal(plx_load_file(w.e, "fixtures/helsinki-centre.geojson"), PLX_E_UNSUPPORTED);
    assert_int_equal(plx_scene_info_get(x.e, &a), PLX_OK);
    assert_int_equal(plx_scene_info_get(y.e, &b), PLX_OK);
    assert_int_equal(plx_scene_info_get(z.e, &c), PLX_OK);
    assert_int_equal(a.buildings, b.buildings);
    assert_int_equal(a.vertices, b.vertices);
    assert_int_equal(a.lamps, c.lamps);
    assert_int_equal(a.vertices, c.vertices);
    plx_memory_get(x.e, &mr);
    plx_memory_get(y.e, &mm);
    /* the read path holds the file in the block during the load */
    assert_true(mr.peak_total >= mm.peak_total + (size_t)st.st_size);
    assert_int_equal(mr.used_total, mm.used_total);
    eng_close(&x);
    eng_close(&y);
    eng_close(&z);
    eng_close(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_map_peak), /* first: the process's anonymous memory is measured */
        cmocka_unit_test(test_guarded_views),
        cmocka_unit_test(test_page_sized_files),
        cmocka_unit_test(test_unmapped_on_every_path),
        cmocka_unit_test(test_errors_as_before),
        cmocka_unit_test(test_ports_without_the_mapping),
    };
    return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}
