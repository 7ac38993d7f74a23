/* estimate: how big a block a scene needs, before it is loaded (the caller
 * sizes its block, then creates the engine: the stb/SQLite habit).
 *
 * plx_scene_size_scan counts a GeoJSON text in one pass without parsing it
 * (no memory, no engine); plx_memory_estimate turns counts into bytes, one
 * term per part of the engine. The coefficients are the sizes of the
 * structures each part holds per item, rounded up; tests/unit/test_embed.c
 * checks that the result covers the measured high-water mark on every
 * fixture and generated cities, and stays within 4x of it. */
#include <string.h>
#include "polarlux.h"

#define SCAN_DEPTH 64
enum { FIRST_NONE = 0, FIRST_NUMBER, FIRST_POSITION, FIRST_OTHER };

typedef struct scan {
    plx_scene_size *out;
    unsigned char first[SCAN_DEPTH]; /* what the open array's first item was */
    unsigned char is_array[SCAN_DEPTH];
    unsigned char fresh[SCAN_DEPTH]; /* no item yet */
    int depth;
} scan;

/* A value starts in the current container: note what the enclosing array's
 * first item is. */
static void item(scan *c, int kind)
{
    int d = c->depth - 1;
    if (d >= 0 && d < SCAN_DEPTH && c->fresh[d]) {
        c->fresh[d] = 0;
        c->first[d] = (unsigned char)kind;
    }
}

static void open_container(scan *c, int array)
{
    item(c, FIRST_OTHER);
    c->out->json_values++;
    if (c->depth < SCAN_DEPTH) {
        c->is_array[c->depth] = (unsigned char)array;
        c->fresh[c->depth] = 1;
        c->first[c->depth] = FIRST_NONE;
    }
    c->depth++;
}

static void close_container(scan *c)
{
    int d;
    if (c->depth == 0)
        return;
    d = --c->depth;
    if (d >= SCAN_DEPTH || !c->is_array[d])
        return;
    if (c->first[d] == FIRST_NUMBER) {
        c->out->positions++;
        /* a position: its parent array's first item is a position */
        if (d > 0 && d - 1 < SCAN_DEPTH && c->first[d - 1] == FIRST_OTHER && c->is_array[d - 1])
            c->first[d - 1] = FIRST_POSITION;
    } else if (c->first[d] == FIRST_POSITION) {
        c->out->rings++;
    }
}

/* A string token from p (at the quote); returns the index after it. */
static size_t string_token(scan *c, const char *t, size_t len, size_t i)
{
    size_t start = ++i;
    while (i < len && t[i] != '"')
        i += t[i] == '\\' ? 2 : 1;
    c->out->string_bytes += (i - start) + 1;
    c->out->json_values++;
    item(c, FIRST_OTHER);
    if (i - start == 7 && memcmp(t + start, "Feature", 7) == 0)
        c->out->features++;
    if (i - start == 5 && memcmp(t + start, "Point", 5) == 0)
        c->out->points++;
    return i + 1;
}

static int number_char(char ch)
{
    return (ch >= '0' && ch <= '9') || ch == '-' || ch == '+' || ch == '.' || ch == 'e' || ch == 'E';
}

plx_status plx_scene_size_scan(const char *text, size_t len, plx_scene_size *out)
{
    scan c;
    size_t i = 0;
    if (!out || (!text && len))
        return PLX_E_INVALID;
    memset(out, 0, sizeof *out);
    memset(&c, 0, sizeof c);
    c.out = out;
    out->text_bytes = len;
    while (i < len) {
        char ch = text[i];
        if (ch == '"') {
            i = string_token(&c, text, len, i);
        } else if (ch == '{' || ch == '[') {
            open_container(&c, ch == '[');
            i++;
        } else if (ch == '}' || ch == ']') {
            close_container(&c);
            i++;
        } else if (ch == ':') {
            out->json_values--; /* the string before it was a key */
            i++;
        } else if (number_char(ch)) {
            out->json_values++;
            item(&c, FIRST_NUMBER);
            while (i < len && number_char(text[i]))
                i++;
        } else if (ch >= 'a' && ch <= 'z') {
            out->json_values++; /* true, false, null */
            item(&c, FIRST_OTHER);
            while (i < len && text[i] >= 'a' && text[i] <= 'z')
                i++;
        } else {
            i++;
        }
    }
    return PLX_OK;
}

/* ---- bytes from counts ------------------------------------------------- */

#define EST_LIT_CACHE (16u << 20)  /* plx_config.lit_cache_bytes 0 (lightapi.c) */
#define EST_MAX_W 1920             /* plx_config.render_max_width 0 (renderapi.c) */
#define EST_MAX_H 1080

typedef struct est {
    double values, strings, features, points, positions, rings;
} est;

/* Counts given by hand: the JSON they imply (each position an array of two
 * numbers, each feature about 30 values and 200 bytes of keys and ids). */
static est est_counts(const plx_scene_size *sz)
{
    est c;
    c.features = (double)sz->features;
    c.points = (double)sz->points;
    c.positions = (double)sz->positions;
    c.rings = (double)sz->rings;
    c.values = sz->json_values ? (double)sz->json_values : 3.0 * c.positions + 8.0 * c.rings + 30.0 * c.features;
    c.strings = sz->string_bytes ? (double)sz->string_bytes : 200.0 * c.features;
    return c;
}

/* Each use holds some memory for good ('kept') and needs some for the
 * length of a call ('scratch'); the block must hold, at every moment, all
 * that earlier uses kept plus the current call's scratch. */
typedef struct phase {
    double kept, scratch;
} phase;

/* Loading: the scene kept (points, rings, buildings, lamps, blocks, ids);
 * the loader streams the text (src/scene/geojson.c: no parse tree), so its
 * scratch is the line index (8 bytes a feature), one ring's checks and the
 * block outlines (measured about 25 bytes a vertex). Kept: 16 bytes a
 * vertex and the block outlines, a building (80) and its blocks a ring, a
 * lamp (136) a point, and every string at most (ids, paths). The text itself is the caller's (plx_load_geojson);
 * plx_load_file reads it into the block: add text_bytes for that. */
static phase est_load(const est *c)
{
    phase p;
    p.kept = 4096.0 + 40.0 * c->positions + 160.0 * c->rings + 144.0 * c->points + c->strings;
    p.scratch = 8192.0 + 16.0 * c->features + 32.0 * c->positions + 64.0 * c->rings;
    return p;
}

/* Polar diagrams: four maps, their search DAGs and the visibility buffers
 * (measured 170-250 bytes a vertex); the construction's scratch and
 * trapezoid slots beyond them (measured up to about 250 bytes a vertex
 * over a fixed part of about 50 KB; POLAR_SCRATCH_PER_VERTEX). */
static phase est_polar(const est *c)
{
    phase p;
    p.kept = 8192.0 + 320.0 * c->positions;
    p.scratch = 64.0 * 1024.0 + 300.0 * c->positions;
    return p;
}

/* Lamp light: the lit-region pool, per-building and per-vertex tables, the
 * lamp grid; one region's output takes up to the pool's size in scratch. */
static phase est_light(const est *c, const plx_config *cfg)
{
    phase p;
    double cache = cfg && cfg->lit_cache_bytes ? (double)cfg->lit_cache_bytes : (double)EST_LIT_CACHE;
    p.kept = 65536.0 + cache + 128.0 * c->positions + 128.0 * c->rings + 64.0 * c->points;
    p.scratch = 65536.0 + cache + 128.0 * c->positions;
    return p;
}

/* Images: 40 bytes a pixel of the largest frame (depth, id, linear RGB;
 * anti-aliasing's sums, the first sample's ids and bytes, the marks),
 * the mesh's compact records (mesh.h: about 12 bytes a footprint vertex
 * and 20 a building) and culling tables, a 64 KB tone-mapping table and the
 * surface cache; the mesh's construction in scratch (its roof
 * triangulations and wall splits: 320 bytes a position, was 768 when
 * the mesh kept every triangle). */
static phase est_render(const est *c, const plx_config *cfg)
{
    phase p;
    double w = cfg && cfg->render_max_width ? cfg->render_max_width : EST_MAX_W;
    double h = cfg && cfg->render_max_height ? cfg->render_max_height : EST_MAX_H;
    p.kept = 262144.0 + 40.5 * w * h + 64.0 * c->positions + 128.0 * c->rings;
    p.scratch = 65536.0 + 320.0 * c->positions;
    return p;
}

/* The block's high-water mark after phase p: what was kept before, what p
 * keeps, and p's scratch. */
static double step(double *kept, double high, phase p)
{
    double top = *kept + p.kept + p.scratch;
    *kept += p.kept;
    return top > high ? top : high;
}

size_t plx_memory_estimate(const plx_scene_size *sz, const plx_config *cfg, unsigned uses)
{
    est c;
    double kept = 0.0, high = 0.0;
    if (!sz)
        return 0;
    c = est_counts(sz);
    if (uses & PLX_USE_RENDER)
        uses |= PLX_USE_LIGHT; /* images shade with the lamp light */
    high = step(&kept, high, est_load(&c));
    if (uses & PLX_USE_VISIBILITY)
        high = step(&kept, high, est_polar(&c));
    if (uses & PLX_USE_LIGHT)
        high = step(&kept, high, est_light(&c, cfg));
    if (uses & PLX_USE_RENDER) {
        /* a frame computes the lit regions it shades with on demand: one
         * region's output scratch on top of the frame's buffers */
        phase r = est_render(&c, cfg), l = est_light(&c, cfg);
        if (l.scratch > r.scratch)
            r.scratch = l.scratch;
        high = step(&kept, high, r);
    }
    high += PLX_ENGINE_ALIGN + PLX_ENGINE_MIN_BYTES;
    if (!(high < (double)((size_t)-1 / 2)))
        return 0;
    return ((size_t)high + 4095u) & ~(size_t)4095u;
}
