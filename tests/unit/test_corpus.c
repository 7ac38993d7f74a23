/* The bad-input corpus (tests/corpus/): every file is loaded leniently and
 * strictly, asserting the exact error message, or the exact warnings and
 * what was kept when the lenient load succeeds. Every allocation of every
 * load of every corpus file is made to fail in turn (plx_load_geojson,
 * strict and lenient, and plx_load_file). The getters allocate nothing.
 * Rings of 10^6 vertices are generated here at run time. Fuzz crashes become
 * a corpus file plus a row of this table. */
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
#include "port.h"
#include "slow.h"

#define MEM (64u << 20)
#define CORPUS "tests/corpus/"

typedef struct logbook {
    size_t len;
    char all[16384];
} logbook;

static void log_to_book(void *ctx, plx_log_level level, const char *msg)
{
    logbook *b = ctx;
    int n;
    assert_int_equal(level, PLX_LOG_WARN);
    n = snprintf(b->all + b->len, sizeof b->all - b->len, "%s\n", msg);
    assert_true(n > 0 && (size_t)n < sizeof b->all - b->len);
    b->len += (size_t)n;
}

typedef struct engine {
    void *mem;
    size_t size;
    plx_engine *e;
    plx_port port;
    logbook book;
} engine;

static engine *open_engine(int strict, size_t size)
{
    engine *f = calloc(1, sizeof *f);
    plx_config cfg;
    assert_non_null(f);
    f->size = size;
    f->mem = malloc(size);
    assert_non_null(f->mem);
    f->port = *plx_port_posix();
    f->port.ctx = &f->book;
    f->port.log = log_to_book;
    plx_config_default(&cfg);
    cfg.port = &f->port;
    cfg.strict = strict;
    assert_int_equal(plx_engine_create(f->mem, size, &cfg, &f->e), PLX_OK);
    return f;
}

static void close_engine(engine *f)
{
    plx_engine_destroy(f->e);
    free(f->mem);
    free(f);
}

static void clear_log(engine *f)
{
    f->book.len = 0;
    f->book.all[0] = '\0';
}

static char *read_corpus(const char *file, size_t *len)
{
    char path[256], err[256];
    char *text;
    snprintf(path, sizeof path, CORPUS "%s", file);
    text = port_read_text(path, len, err, sizeof err);
    if (!text)
        fail_msg("%s: %s", path, err);
    return text;
}

/* "id id ...|id id ...": the buildings then the lamps kept, in order ("-" for no id). */
static void kept_ids(plx_engine *e, char *out, size_t cap)
{
    plx_scene_info si;
    size_t len = 0;
    uint32_t i;
    out[0] = '\0';
    assert_int_equal(plx_scene_info_get(e, &si), PLX_OK);
    for (i = 0; i < si.buildings; i++) {
        plx_building b;
        assert_int_equal(plx_building_get(e, i, &b), PLX_OK);
        len += (size_t)snprintf(out + len, cap - len, "%s%s", i ? " " : "", b.id ? b.id : "-");
    }
    len += (size_t)snprintf(out + len, cap - len, "|");
    for (i = 0; i < si.lamps; i++) {
        plx_lamp l;
        assert_int_equal(plx_lamp_get(e, i, &l), PLX_OK);
        len += (size_t)snprintf(out + len, cap - len, "%s%s", i ? " " : "", l.id ? l.id : "-");
    }
    assert_true(len < cap);
}

/* ---- the corpus table ------------------------------------------------------------ */

typedef struct corpus_case {
    const char *file;          /* in tests/corpus/ */
    plx_status status;         /* of the lenient load */
    const char *error;         /* its exact error, NULL when it succeeds */
    const char *strict_error;  /* exact error of the strict load, NULL when it succeeds */
    const char *warnings;      /* exact warnings of the lenient load, one per line */
    uint32_t buildings, lamps, skipped_features, skipped_lamps;
    const char *kept;          /* ids kept by the lenient load (see kept_ids) */
} corpus_case;

/* Messages carry no file name: the corpus is loaded with name NULL. */
static const corpus_case corpus[] = {
    { "bom-only.geojson", PLX_E_PARSE,
      "malformed JSON at byte 3 (line 1, column 4): the text holds only a UTF-8 byte-order mark",
      "malformed JSON at byte 3 (line 1, column 4): the text holds only a UTF-8 byte-order mark",
      "",
      0, 0, 0, 0,
      NULL },
    { "bom-whitespace.geojson", PLX_E_PARSE,
      "malformed JSON at byte 8 (line 3, column 1): the text holds only a UTF-8 byte-order mark and white space",
      "malformed JSON at byte 8 (line 3, column 1): the text holds only a UTF-8 byte-order mark and white space",
      "",
      0, 0, 0, 0,
      NULL },
    { "bowtie-rings.geojson", PLX_OK,
      NULL,
      "feature 0 (bowtie, line 2, column 1): outer ring intersects itself (edges 0 and 2 meet)",
      "feature 0 (bowtie, line 2, column 1): outer ring intersects itself (edges 0 and 2 meet); left out\n"
      "feature 1 (bowtie-hole, line 3, column 1): inner ring 1 intersects itself (edges 0 and 2 meet); left out\n"
      "feature 2 (figure-eight, line 4, column 1): outer ring intersects itself (edges 2 and 5 meet); left out\n"
      "feature 3 (spike, line 5, column 1): outer ring intersects itself (edges 3 and 4 meet); left out\n"
      "feature 4 (twice-round, line 6, column 1): outer ring intersects itself (edges 0 and 4 meet); left out\n",
      0, 0, 5, 0,
      "|" },
    { "control-characters.geojson", PLX_OK,
      NULL,
      "feature 0 (pi?ch, line 2, column 1): outer ring intersects itself (edges 3 and 4 meet)",
      "feature 0 (pi?ch, line 2, column 1): outer ring intersects itself (edges 3 and 4 meet); left out\n"
      "feature 1 (tab?here, line 4, column 1): property \"height\" is not a number (\"3?4\"); ignored, the default applies\n",
      1, 0, 1, 0,
      "tab\there|" },
    { "deep-nesting-arrays.geojson", PLX_E_PARSE,
      "JSON nested deeper than 1000 levels at byte 1105 (line 2, column 1038)",
      "JSON nested deeper than 1000 levels at byte 1105 (line 2, column 1038)",
      "",
      0, 0, 0, 0,
      NULL },
    { "deep-nesting-objects.geojson", PLX_E_PARSE,
      "JSON nested deeper than 1000 levels at byte 5089 (line 2, column 5022)",
      "JSON nested deeper than 1000 levels at byte 5089 (line 2, column 5022)",
      "",
      0, 0, 0, 0,
      NULL },
    { "deep-nesting-within-limit.geojson", PLX_OK,
      NULL,
      NULL,
      "feature 0 (deep, line 2, column 1): property \"height\" is not a number; ignored, the default applies\n",
      1, 0, 0, 0,
      "deep|" },
    { "duplicate-keys.geojson", PLX_OK, /* the first of each read (cJSON's), the first such key said */
      NULL,
      "line 2, column 54: an object holds \"height\" twice; the first is read (as cJSON reads), where other "
      "readers may take the last",
      "line 2, column 54: an object holds \"height\" twice; the first is read (as cJSON reads), where other "
      "readers may take the last\n",
      2, 0, 0, 0,
      "A B|" },
    { "duplicate-points.geojson", PLX_OK,
      NULL,
      "feature 1 (all-same, line 3, column 1): outer ring has 1 distinct vertex (a ring needs at least 3)",
      "feature 1 (all-same, line 3, column 1): outer ring has 1 distinct vertex (a ring needs at least 3); left out\n"
      "feature 2 (pinch, line 4, column 1): outer ring intersects itself (edges 3 and 4 meet); left out\n",
      1, 0, 2, 0,
      "dups|" },
    { "empty-and-one-point-rings.geojson", PLX_OK,
      NULL,
      "feature 0 (no-rings, line 2, column 1): a polygon has no rings",
      "feature 0 (no-rings, line 2, column 1): a polygon has no rings; left out\n"
      "feature 1 (empty-ring, line 3, column 1): outer ring has 0 distinct vertices (a ring needs at least 3); left out\n"
      "feature 2 (one-point, line 4, column 1): outer ring has 1 distinct vertex (a ring needs at least 3); left out\n"
      "feature 3 (one-point-closed, line 5, column 1): outer ring has 1 distinct vertex (a ring needs at least 3); left out\n"
      "feature 4 (empty-hole, line 6, column 1): inner ring 1 has 0 distinct vertices (a ring needs at least 3); left out\n"
      "feature 5 (multi-empty, line 7, column 1): MultiPolygon has no polygons; left out\n"
      "feature 6 (multi-no-rings, line 8, column 1): polygon 0: a polygon has no rings; left out\n"
      "feature 7 (multi-one-point, line 9, column 1): polygon 1: outer ring has 1 distinct vertex (a ring needs at least 3); left out\n",
      0, 0, 8, 0,
      "|" },
    { "empty.geojson", PLX_E_PARSE,
      "malformed JSON at byte 0 (line 1, column 1): the file is empty",
      "malformed JSON at byte 0 (line 1, column 1): the file is empty",
      "",
      0, 0, 0, 0,
      NULL },
    { "holes-escaping.geojson", PLX_OK,
      NULL,
      "feature 0 (through-vertices, line 2, column 1): inner ring 1 is not inside the outer ring",
      "feature 0 (through-vertices, line 2, column 1): inner ring 1 is not inside the outer ring; left out\n"
      "feature 1 (across-mouth, line 3, column 1): inner ring 1 is not inside the outer ring; left out\n"
      "feature 2 (hole-in-hole, line 4, column 1): inner rings 1 and 2 overlap; left out\n",
      2, 0, 3, 0,
      "touching-corner holes-touching|" },
    { "huge-numbers.geojson", PLX_OK,
      NULL,
      "feature 0 (x1e308, line 2, column 1): position 1 of outer ring is out of range (|coordinate| > 1e7 m)",
      "feature 0 (x1e308, line 2, column 1): position 1 of outer ring is out of range (|coordinate| > 1e7 m); left out\n"
      "feature 1 (x1e309, line 3, column 1): position 1 of outer ring has a non-finite number; left out\n"
      "feature 2 (h1e308, line 4, column 1): height 1e308 m is out of range (must be > 0 and <= 1000 m); left out\n"
      "feature 3 (h1e999, line 5, column 1): height inf m is out of range (must be > 0 and <= 1000 m); left out\n"
      "feature 4 (h400digits, line 6, column 1): height inf m is out of range (must be > 0 and <= 1000 m); left out\n"
      "feature 5 (h0e99999, line 7, column 1): height 0 m is out of range (must be > 0 and <= 1000 m); left out\n"
      "feature 7 (htiny, line 9, column 1): height 0 m is out of range (must be > 0 and <= 1000 m); left out\n"
      "feature 8 (r1e400, line 10, column 1): lamp radius inf m is out of range (> 0 and <= 100000 m); left out\n"
      "feature 9 (i1e308, line 11, column 1): lamp intensity 1e308 cd is negative, not finite or above 1e12 cd; "
      "left out\n",
      1, 2, 9, 0,
      "hlongmantissa|id-huge 1e308" },
    { "infinity-bare.geojson", PLX_E_PARSE,
      "malformed JSON at byte 109 (line 2, column 42)"
      ": JSON has no NaN or Infinity (write null, or leave the value out)",
      "malformed JSON at byte 109 (line 2, column 42)"
      ": JSON has no NaN or Infinity (write null, or leave the value out)",
      "",
      0, 0, 0, 0,
      NULL },
    { "lamps-at-height-zero.geojson", PLX_OK,
      NULL,
      "feature 4 (ztiny, line 6, column 1): lamp z -1e-300 m is out of range (0 to 1000 m)",
      "feature 4 (ztiny, line 6, column 1): lamp z -1e-300 m is out of range (0 to 1000 m); left out\n",
      1, 3, 1, 0,
      "A|z0 z0m zneg0" },
    { "lamps-inside-buildings.geojson", PLX_OK,
      NULL,
      "feature 2 (inside, line 4, column 1): lamp is inside building 0 (A)", /* strict: the load fails, none left out */
      "feature 2 (inside, line 4, column 1): lamp is inside building 0 (A); left out\n"
      "feature 12 (in-canopy, line 14, column 1): lamp is inside building 1 (canopy); left out\n",
      2, 10, 0, 2,
      "A canopy|on-wall on-corner courtyard courtyard-wall roof above floor under-canopy canopy-bottom street" },
    { "lamps-negative-radius.geojson", PLX_OK,
      NULL,
      "feature 0 (neg, line 2, column 1): lamp radius -3 m is out of range (> 0 and <= 100000 m)",
      "feature 0 (neg, line 2, column 1): lamp radius -3 m is out of range (> 0 and <= 100000 m); left out\n"
      "feature 1 (zero, line 3, column 1): lamp radius 0 m is out of range (> 0 and <= 100000 m); left out\n"
      "feature 2 (negstr, line 4, column 1): lamp radius -5 m is out of range (> 0 and <= 100000 m); left out\n"
      "feature 3 (huge, line 5, column 1): lamp radius 100001 m is out of range (> 0 and <= 100000 m); left out\n",
      0, 1, 4, 0,
      "|ok" },
    /* since 2026-12-03 each lamp of 1e308 cd is left out on its own (above 1e12 cd), so the sum at one spot
     * that overflowed is no longer reached from a scene (lampmerge.c keeps its guard) */
    { "lamps-overflowing-sum.geojson", PLX_OK,
      NULL,
      "feature 0 (big-a, line 2, column 1): lamp intensity 1e308 cd is negative, not finite or above 1e12 cd",
      "feature 0 (big-a, line 2, column 1): lamp intensity 1e308 cd is negative, not finite or above 1e12 cd; "
      "left out\n"
      "feature 1 (big-b, line 3, column 1): lamp intensity 1e308 cd is negative, not finite or above 1e12 cd; "
      "left out\n"
      "feature 2 (big-c, line 4, column 1): lamp intensity 1e308 cd is negative, not finite or above 1e12 cd; "
      "left out\n"
      "feature 3 (ok, line 5, column 1): lamp intensity 1e308 cd is negative, not finite or above 1e12 cd; "
      "left out\n",
      0, 0, 4, 0,
      "|" },
    { "lamps-zero-intensity.geojson", PLX_OK,
      NULL,
      "feature 3 (neg, line 5, column 1): lamp intensity -1e-9 cd is negative, not finite or above 1e12 cd",
      "feature 0 (zero, line 2, column 1): lamp intensity is 0 cd: it gives no light\n"
      "feature 1 (zero-str, line 3, column 1): lamp intensity is 0 cd: it gives no light\n"
      "feature 2 (neg-zero, line 4, column 1): lamp intensity is 0 cd: it gives no light\n"
      "feature 3 (neg, line 5, column 1): lamp intensity -1e-9 cd is negative, not finite or above 1e12 cd; left out\n",
      0, 3, 1, 0,
      "|zero zero-str neg-zero" },
    { "minus-infinity-bare.geojson", PLX_E_PARSE,
      "malformed JSON at byte 116 (line 2, column 49)"
      ": JSON has no NaN or Infinity (write null, or leave the value out)",
      "malformed JSON at byte 116 (line 2, column 49)"
      ": JSON has no NaN or Infinity (write null, or leave the value out)",
      "",
      0, 0, 0, 0,
      NULL },
    { "nan-bare.geojson", PLX_E_PARSE,
      "malformed JSON at byte 154 (line 2, column 87)"
      ": JSON has no NaN or Infinity (write null, or leave the value out)",
      "malformed JSON at byte 154 (line 2, column 87)"
      ": JSON has no NaN or Infinity (write null, or leave the value out)",
      "",
      0, 0, 0, 0,
      NULL },
    { "nan-infinity-strings.geojson", PLX_OK,
      NULL,
      "feature 5 (f, line 7, column 1): position 0 of outer ring is not a position [x, y] of numbers",
      "feature 0 (a, line 2, column 1): property \"height\" is not a number (\"NaN\"); ignored, the default applies\n"
      "feature 1 (b, line 3, column 1): property \"height\" is not a number (\"nan\"); ignored, the default applies\n"
      "feature 2 (c, line 4, column 1): property \"height\" is not a number (\"Infinity\"); ignored, the default applies\n"
      "feature 3 (d, line 5, column 1): property \"height\" is not a number (\"-inf\"); ignored, the default applies\n"
      "feature 4 (e, line 6, column 1): property \"intensity\" is not a number (\"inf\"); ignored, the default applies\n"
      "feature 5 (f, line 7, column 1): position 0 of outer ring is not a position [x, y] of numbers; left out\n",
      4, 1, 1, 0,
      "a b c d|e" },
    { "rings-that-are-lines.geojson", PLX_OK,
      NULL,
      "feature 0 (line3, line 2, column 1): outer ring intersects itself (edges 0 and 2 meet)",
      "feature 0 (line3, line 2, column 1): outer ring intersects itself (edges 0 and 2 meet); left out\n"
      "feature 1 (back-and-forth, line 3, column 1): outer ring has 2 distinct vertices (a ring needs at least 3); left out\n"
      "feature 2 (folded, line 4, column 1): outer ring intersects itself (edges 0 and 2 meet); left out\n"
      "feature 3 (diagonal, line 5, column 1): outer ring intersects itself (edges 0 and 5 meet); left out\n",
      0, 0, 4, 0,
      "|" },
    { "truncated-after-key.geojson", PLX_E_PARSE,
      "malformed JSON at byte 38 (line 1, column 39): the text ends early",
      "malformed JSON at byte 38 (line 1, column 39): the text ends early",
      "",
      0, 0, 0, 0,
      NULL },
    { "truncated-in-coordinates.geojson", PLX_E_PARSE,
      "malformed JSON at byte 177 (line 2, column 110): the text ends early",
      "malformed JSON at byte 177 (line 2, column 110): the text ends early",
      "",
      0, 0, 0, 0,
      NULL },
    { "truncated-in-escape.geojson", PLX_E_PARSE,
      "malformed JSON at byte 50 (line 1, column 51)",
      "malformed JSON at byte 50 (line 1, column 51)",
      "",
      0, 0, 0, 0,
      NULL },
    { "truncated-in-number.geojson", PLX_E_PARSE,
      "malformed JSON at byte 264 (line 3, column 59): the text ends early",
      "malformed JSON at byte 264 (line 3, column 59): the text ends early",
      "",
      0, 0, 0, 0,
      NULL },
    { "truncated-in-string.geojson", PLX_E_PARSE,
      "malformed JSON at byte 142 (line 2, column 75)",
      "malformed JSON at byte 142 (line 2, column 75)",
      "",
      0, 0, 0, 0,
      NULL },
    { "whitespace-only.geojson", PLX_E_PARSE,
      "malformed JSON at byte 5 (line 3, column 1): the text holds only white space",
      "malformed JSON at byte 5 (line 3, column 1): the text holds only white space",
      "",
      0, 0, 0, 0,
      NULL },
    { "wrong-type-collection-type.geojson", PLX_E_SCENE,
      "the top-level object is not a FeatureCollection (\"type\" must be \"FeatureCollection\")",
      "the top-level object is not a FeatureCollection (\"type\" must be \"FeatureCollection\")",
      "",
      0, 0, 0, 0,
      NULL },
    { "wrong-type-features.geojson", PLX_E_SCENE,
      "the FeatureCollection has no \"features\" array",
      "the FeatureCollection has no \"features\" array",
      "",
      0, 0, 0, 0,
      NULL },
    { "wrong-type-ground-albedo.geojson", PLX_E_SCENE,
      "properties.ground_albedo must be a number from 0 to 1",
      "properties.ground_albedo must be a number from 0 to 1",
      "",
      0, 0, 0, 0,
      NULL },
    { "wrong-type-ground-image.geojson", PLX_OK,
      NULL,
      "properties.ground_image must be the path of a PNG file (a non-empty string of at most 4096 bytes)",
      "properties.ground_image must be the path of a PNG file (a non-empty string of at most 4096 bytes); ignored\n"
      "properties.ground_image_bounds must be [x0, y0, x1, y1]: 4 finite numbers with x0 < x1 and y0 < y1; ignored\n",
      0, 1, 0, 0,
      "|L" },
    { "wrong-type-top-level.geojson", PLX_E_SCENE,
      "the top-level value is not a JSON object (expected a GeoJSON FeatureCollection)",
      "the top-level value is not a JSON object (expected a GeoJSON FeatureCollection)",
      "",
      0, 0, 0, 0,
      NULL },
    { "wrong-type-units.geojson", PLX_E_SCENE,
      "properties.units must be \"m\" (metres) when given; leave it out for WGS84 lon/lat",
      "properties.units must be \"m\" (metres) when given; leave it out for WGS84 lon/lat",
      "",
      0, 0, 0, 0,
      NULL },
    { "wrong-types-building.geojson", PLX_OK,
      NULL,
      NULL,
      "feature 0 (h-bool, line 2, column 1): property \"height\" is not a number; ignored, the default applies\n"
      "feature 1 (h-array, line 3, column 1): property \"height\" is not a number; ignored, the default applies\n"
      "feature 2 (h-object, line 4, column 1): property \"height\" is not a number; ignored, the default applies\n"
      "feature 3 (h-list, line 5, column 1): property \"height\" is not a number (\"3;4\"); ignored, the default applies\n"
      "feature 4 (levels, line 6, column 1): property \"building:levels\" is not a number (\"many\"); ignored, the default applies\n"
      "feature 5 (min, line 7, column 1): property \"min_height\" is not a number; ignored, the default applies\n"
      "feature 6 (albedo, line 8, column 1): property \"albedo\" is not a number (\"white\"); ignored, the default applies\n",
      8, 0, 0, 0,
      "h-bool h-array h-object h-list levels min albedo nulls|" },
    { "wrong-types-lamp.geojson", PLX_OK,
      NULL,
      NULL,
      "feature 0 (z, line 2, column 1): property \"z\" is not a number (\"high\"); ignored, the default applies\n"
      "feature 1 (i, line 3, column 1): property \"intensity\" is not a number; ignored, the default applies\n"
      "feature 2 (r, line 4, column 1): property \"radius\" is not a number; ignored, the default applies\n"
      "feature 3 (c-name, line 5, column 1): property \"color\" is not [r, g, b] of numbers >= 0; ignored, the default applies\n"
      "feature 4 (c-two, line 6, column 1): property \"color\" is not [r, g, b] of numbers >= 0; ignored, the default applies\n"
      "feature 5 (c-str, line 7, column 1): property \"color\" is not [r, g, b] of numbers >= 0; ignored, the default applies\n"
      "feature 6 (c-neg, line 8, column 1): property \"color\" is not [r, g, b] of numbers >= 0; ignored, the default applies\n"
      "feature 7 (lamp-yes, line 9, column 1): property \"lamp\" is not true or false; ignored, the point is not a lamp\n"
      "feature 8 (lamp-one, line 10, column 1): property \"lamp\" is not true or false; ignored, the point is not a lamp\n",
      0, 7, 0, 0,
      "|z i r c-name c-two c-str c-neg" },
    { "wrong-types-structure.geojson", PLX_OK,
      NULL,
      "feature 0 (line 2, column 1): is not a JSON object",
      "feature 0 (line 2, column 1): is not a JSON object; left out\n"
      "feature 1 (line 3, column 1): \"properties\" is not an object; ignored\n"
      "feature 2 (g-str, line 4, column 1): has no geometry object; left out\n"
      "feature 3 (t-num, line 5, column 1): geometry has no \"type\" string; left out\n"
      "feature 4 (c-str, line 6, column 1): geometry has no \"coordinates\" array; left out\n"
      "feature 5 (pos-short, line 7, column 1): position 1 of outer ring is not a position [x, y] of numbers; left out\n"
      "feature 6 (pos-str, line 8, column 1): position 0 of outer ring is not a position [x, y] of numbers; left out\n"
      "feature 7 (ring-num, line 9, column 1): outer ring is not an array of positions; left out\n"
      "feature 8 (pt-str, line 10, column 1): the point is not a position [x, y] of numbers; left out\n"
      "feature 10 (line 12, column 1): outer ring has 2 distinct vertices (a ring needs at least 3); left out\n",
      2, 0, 9, 0,
      "- fid|" },
};

#define NCORPUS (sizeof corpus / sizeof corpus[0])

static void test_corpus_files(void **state)
{
    if (slow_test_skipped()) /* not in plain make check: it stays within a minute */
        skip();
    size_t i;
    (void)state;
    for (i = 0; i < NCORPUS; i++) {
        const corpus_case *c = &corpus[i];
        engine *le = open_engine(0, MEM), *se = open_engine(1, MEM);
        size_t len;
        char *text = read_corpus(c->file, &len);
        plx_status st = plx_load_geojson(le->e, text, len, NULL);
        print_message("corpus %s\n", c->file);
        assert_int_equal(st, c->status);
        assert_string_equal(le->book.all, c->warnings);
        if (st != PLX_OK) {
            assert_string_equal(plx_last_error(le->e), c->error);
        } else {
            plx_scene_info si;
            char kept[4096];
            assert_string_equal(plx_last_error(le->e), "");
            assert_int_equal(plx_scene_info_get(le->e, &si), PLX_OK);
            assert_int_equal(si.buildings, c->buildings);
            assert_int_equal(si.lamps, c->lamps);
            assert_int_equal(si.skipped_features, c->skipped_features);
            assert_int_equal(si.skipped_lamps, c->skipped_lamps);
            kept_ids(le->e, kept, sizeof kept);
            assert_string_equal(kept, c->kept);
        }
        st = plx_load_geojson(se->e, text, len, NULL);
        if (c->strict_error) {
            assert_int_equal(st, c->status == PLX_OK ? PLX_E_SCENE : c->status);
            assert_string_equal(plx_last_error(se->e), c->strict_error);
        } else {
            assert_int_equal(st, PLX_OK);
        }
        free(text);
        close_engine(le);
        close_engine(se);
    }
}

/* Values behind some rows of the table. */
static void test_corpus_values(void **state)
{
    engine *f = open_engine(0, MEM);
    size_t len;
    char *text;
    plx_building b;
    plx_lamp l;
    const double *xy;
    uint32_t n;
    (void)state;
    /* "1" + 400 zeros + "e-399" is 10, not nan */
    text = read_corpus("huge-numbers.geojson", &len);
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_OK);
    assert_int_equal(plx_building_get(f->e, 0, &b), PLX_OK);
    assert_true(b.height == 10.0);
    /* an intensity of 1e308 cd is left out (above 1e12 cd: its lux overflowed) */
    assert_int_equal(plx_lamp_get(f->e, 0, &l), PLX_OK);
    assert_true(l.z == 0.0); /* "1e-400" */
    assert_int_equal(plx_lamp_get(f->e, 1, &l), PLX_OK);
    assert_string_equal(l.id, "1e308");
    free(text);
    /* duplicates dropped: the square's 4 corners, counter-clockwise from (0,0) */
    text = read_corpus("duplicate-points.geojson", &len);
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_OK);
    assert_int_equal(plx_building_ring(f->e, 0, 0, &xy, &n), PLX_OK);
    assert_int_equal(n, 4);
    assert_true(xy[0] == 0 && xy[1] == 0 && xy[2] == 10 && xy[3] == 0 && xy[4] == 10 && xy[5] == 10 &&
                xy[6] == 0 && xy[7] == 10);
    free(text);
    /* lamps at height 0 are kept at 0 */
    text = read_corpus("lamps-at-height-zero.geojson", &len);
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_OK);
    for (n = 0; n < 3; n++) {
        assert_int_equal(plx_lamp_get(f->e, n, &l), PLX_OK);
        assert_true(l.z == 0.0 && l.intensity == 1000.0);
    }
    free(text);
    /* zero intensity: kept, at 0 */
    text = read_corpus("lamps-zero-intensity.geojson", &len);
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_OK);
    assert_int_equal(plx_lamp_get(f->e, 1, &l), PLX_OK);
    assert_true(l.intensity == 0.0 && l.radius == 30.0);
    free(text);
    /* the holes that do lie inside (touching the outer ring or each other at a point) */
    text = read_corpus("holes-escaping.geojson", &len);
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_OK);
    assert_int_equal(plx_building_get(f->e, 1, &b), PLX_OK);
    assert_int_equal(b.nrings, 3);
    assert_int_equal(plx_building_ring(f->e, 1, 2, &xy, &n), PLX_OK);
    assert_int_equal(n, 4);
    free(text);
    close_engine(f);
}

/* ---- fault injection: every allocation of every load fails in turn ----------------- */

typedef plx_status (*load_fn)(engine *f, const char *file, const char *text, size_t len);

static plx_status by_text(engine *f, const char *file, const char *text, size_t len)
{
    (void)file;
    return plx_load_geojson(f->e, text, len, NULL);
}

static plx_status by_file(engine *f, const char *file, const char *text, size_t len)
{
    char path[256];
    (void)text;
    (void)len;
    snprintf(path, sizeof path, CORPUS "%s", file);
    return plx_load_file(f->e, path);
}

/* Loads with the k-th allocation failing for k = 1, 2, ... until the load
 * gets through; each failure is PLX_E_NOMEM with all memory given back and no
 * scene. Then the result must be the one of a load without faults. */
static void fault_inject(const char *file, int strict, load_fn load)
{
    engine *f = open_engine(strict, MEM);
    plx_memory_report before, after;
    size_t len;
    char *text = read_corpus(file, &len);
    char want_err[512], want_log[16384];
    plx_status want, st = PLX_E_NOMEM;
    uint64_t k, requests;
    clear_log(f);
    want = load(f, file, text, len);
    snprintf(want_err, sizeof want_err, "%s", plx_last_error(f->e));
    snprintf(want_log, sizeof want_log, "%s", f->book.all);
    plx_engine_destroy(f->e);
    {
        plx_config cfg;
        plx_config_default(&cfg);
        cfg.port = &f->port;
        cfg.strict = strict;
        assert_int_equal(plx_engine_create(f->mem, f->size, &cfg, &f->e), PLX_OK);
    }
    plx_memory_get(f->e, &before);
    for (k = 1; st == PLX_E_NOMEM; k++) {
        plx_scene_info si;
        clear_log(f);
        plx_debug_fail_alloc(f->e, k);
        st = load(f, file, text, len);
        requests = plx_debug_fail_alloc(f->e, 0);
        if (st != PLX_E_NOMEM)
            break;
        if (strncmp(plx_last_error(f->e), "out of memory while ", 20) != 0)
            fail_msg("%s k=%llu: %s", file, (unsigned long long)k, plx_last_error(f->e));
        assert_true(requests >= k);
        plx_memory_get(f->e, &after);
        assert_int_equal(after.used_total, before.used_total);
        assert_int_equal(after.used[PLX_PART_SCRATCH], 0);
        assert_int_equal(plx_scene_info_get(f->e, &si), PLX_E_NOSCENE);
        assert_true(k < 1000000);
    }
    if (st != want || strcmp(plx_last_error(f->e), want_err) != 0 || strcmp(f->book.all, want_log) != 0)
        fail_msg("%s (strict %d) after %llu faults: status %d '%s', want %d '%s'", file, strict,
                 (unsigned long long)k - 1, st, plx_last_error(f->e), want, want_err);
    /* the fault was never reached: the load asked for fewer than k */
    assert_true(requests < k);
    free(text);
    close_engine(f);
}

static void test_fault_injection_corpus(void **state)
{
    size_t i;
    (void)state;
    for (i = 0; i < NCORPUS; i++) {
        fault_inject(corpus[i].file, 0, by_text);
        fault_inject(corpus[i].file, 1, by_text);
        fault_inject(corpus[i].file, 0, by_file);
    }
}

/* The getters and reports allocate nothing: with the very next allocation
 * set to fail they all succeed, and no request was made. */
static void test_getters_allocate_nothing(void **state)
{
    engine *f = open_engine(0, MEM);
    plx_scene_info si;
    plx_building b;
    plx_lamp l;
    plx_block k;
    plx_memory_report m;
    const double *xy;
    uint32_t n;
    (void)state;
    assert_int_equal(plx_load_file(f->e, CORPUS "lamps-inside-buildings.geojson"), PLX_OK);
    plx_debug_fail_alloc(f->e, 1);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(plx_building_get(f->e, 0, &b), PLX_OK);
    assert_int_equal(plx_lamp_get(f->e, 0, &l), PLX_OK);
    assert_int_equal(plx_block_get(f->e, 0, &k), PLX_OK);
    assert_int_equal(plx_building_ring(f->e, 0, 1, &xy, &n), PLX_OK);
    assert_int_equal(plx_block_ring(f->e, 0, 0, &xy, &n), PLX_OK);
    assert_int_equal(plx_building_get(f->e, 99, &b), PLX_E_RANGE);
    assert_string_equal(plx_last_error(f->e), "plx_building_get: index 99 is out of range (there are 2)");
    plx_memory_get(f->e, &m);
    assert_true(m.used[PLX_PART_SCENE] > 0);
    assert_int_equal(plx_warning_count(f->e), 2);
    assert_ptr_equal(plx_engine_block(f->e), f->mem);
    assert_int_equal(plx_debug_fail_alloc(f->e, 0), 0);
    /* and still usable */
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.lamps, 10);
    close_engine(f);
}

/* ---- 10^6-vertex rings, made here ------------------------------------------------------- */

#define BIG_N 1000000u

/* A comb of BIG_N vertices with integer coordinates: the bottom edge from
 * (0,0) to (W,0), then back along a zigzag top y = 10 or 15. With 'cross'
 * the top vertex at x = 500000 dips to y = -5, through the bottom edge. */
static char *comb_ring(int cross, size_t *len)
{
    uint32_t w = BIG_N - 3, x;
    size_t cap = (size_t)BIG_N * 20 + 400, n = 0;
    char *s = malloc(cap);
    assert_non_null(s);
    n += (size_t)snprintf(s + n, cap - n,
                          "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[\n"
                          "{\"type\":\"Feature\",\"properties\":{\"id\":\"comb\"},\"geometry\":{\"type\":\"Polygon\","
                          "\"coordinates\":[[[0,0],[%u,0]", w);
    for (x = w + 1; x-- > 0;) {
        int y = x % 2 ? 15 : 10;
        if (cross && x == 500000)
            y = -5;
        n += (size_t)snprintf(s + n, cap - n, ",[%u,%d]", x, y);
    }
    n += (size_t)snprintf(s + n, cap - n, ",[0,0]]]}}]}\n");
    assert_true(n < cap);
    *len = n;
    return s;
}

/* A ring of n vertices on a circle of radius 2e6 m (within the 1e7 m range):
 * 12.6 m apart for n = 10^6, so rounding to whole metres leaves n distinct
 * vertices and a simple ring. */
static char *circle_ring(uint32_t n, size_t *len)
{
    size_t cap = (size_t)n * 24 + 400, k = 0;
    char *s = malloc(cap);
    uint32_t i;
    assert_non_null(s);
    k += (size_t)snprintf(s + k, cap - k,
                          "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[\n"
                          "{\"type\":\"Feature\",\"properties\":{\"id\":\"circle\"},\"geometry\":{\"type\":\"Polygon\","
                          "\"coordinates\":[[");
    for (i = 0; i < n; i++) {
        double a = 2.0 * 3.14159265358979323846 * i / n;
        k += (size_t)snprintf(s + k, cap - k, "%s[%.0f,%.0f]", i ? "," : "", 2e6 * cos(a), 2e6 * sin(a));
    }
    k += (size_t)snprintf(s + k, cap - k, "]]}}]}\n");
    assert_true(k < cap);
    *len = k;
    return s;
}

/* 10^6 vertices (10^5 under valgrind, PLX_TEST_QUICK) load as one building. */
static void test_million_vertex_ring(void **state)
{
    uint32_t big = getenv("PLX_TEST_QUICK") ? BIG_N / 10 : BIG_N;
    engine *f = open_engine(0, 512u << 20);
    size_t len;
    char *text = circle_ring(big, &len);
    plx_scene_info si;
    const double *xy;
    uint32_t n;
    (void)state;
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_OK);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.buildings, 1);
    assert_int_equal(si.vertices, big);
    assert_int_equal(si.skipped_features, 0);
    assert_int_equal(si.blocks, 1);
    assert_int_equal(plx_building_ring(f->e, 0, 0, &xy, &n), PLX_OK);
    assert_int_equal(n, big);
    assert_true(xy[0] == 2e6 && xy[1] == 0 && xy[2] == 2e6 && xy[3] > 0); /* counter-clockwise as given */
    assert_string_equal(f->book.all, "");
    free(text);
    close_engine(f);
}

/* The valid comb: all its teeth share one band of y, the hostile case for
 * the block outline (it used to take over an hour; now about 4 s for the
 * whole load). Skipped in the quick mode used under valgrind. */
static void test_million_vertex_comb(void **state)
{
    engine *f;
    size_t len;
    char *text;
    plx_scene_info si;
    (void)state;
    if (getenv("PLX_TEST_QUICK"))
        skip();
    f = open_engine(0, 512u << 20);
    text = comb_ring(0, &len);
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_OK);
    assert_int_equal(plx_scene_info_get(f->e, &si), PLX_OK);
    assert_int_equal(si.vertices, BIG_N);
    free(text);
    close_engine(f);
}

static void test_million_vertex_crossing(void **state)
{
    engine *f = open_engine(1, 512u << 20);
    size_t len;
    char *text = comb_ring(1, &len);
    (void)state;
    /* the dipping vertex is number 2 + (W - 500000) = 499999: its edges
     * 499998 and 499999 both cross the bottom edge 0; the second is named */
    assert_int_equal(plx_load_geojson(f->e, text, len, NULL), PLX_E_SCENE);
    assert_string_equal(plx_last_error(f->e),
                        "feature 0 (comb, line 2, column 1): outer ring intersects itself (edges 0 and 499999 meet)");
    free(text);
    close_engine(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_corpus_files),
        cmocka_unit_test(test_corpus_values),
        cmocka_unit_test(test_fault_injection_corpus),
        cmocka_unit_test(test_getters_allocate_nothing),
        cmocka_unit_test(test_million_vertex_ring),
        cmocka_unit_test(test_million_vertex_crossing),
        cmocka_unit_test(test_million_vertex_comb),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
