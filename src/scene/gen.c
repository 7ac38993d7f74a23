/* gen: procedural cities for tests and benchmarks (plx_gen_city).
 *
 * The city is streamed as GeoJSON text through the caller's write callback
 * from a small buffer on the stack; nothing is allocated and there is no
 * global state. Every random choice comes from a splitmix64 generator seeded
 * from (seed, what, i, j) of the entity it decides, so a block, a cell or a
 * node is the same whichever pass or order asks for it.
 *
 * All geometry is computed in integer millimetres (or mapped once from
 * doubles and rounded to millimetres), and written with exactly three
 * decimals, so the text holds exactly the coordinates that were checked:
 * walls meant to be shared have bit-identical end vertices.
 *
 * Coordinates: metres, local frame, x east, y north; the street grid line 0
 * runs along x = 0 and y = 0. Rings are closed (first vertex repeated) and
 * counter-clockwise. Feature ids: buildings "b0", "b1", ... in output order,
 * then lamps "l0", "l1", ...
 *
 * Styles (nx * ny blocks):
 *  grid     pitch 100 m, streets 20 m (centred on x = i*100, y = j*100). One
 *           rectangle per block, set back 0-8 m from each kerb; height
 *           9-40 m (a quarter as 3-13 building:levels). Two lamps per street
 *           segment between crossings, at 30 m and 70 m along it, on
 *           opposite sides 3 m from the kerb line; z 7-9 m, 2000 cd, R 40 m.
 *  eixample pitch 133 m, chamfered blocks 113 m square with the corners cut
 *           14.142 m along each side (a 20 m chamfer face), streets 20 m.
 *           Each block is a ring of 16 buildings (4 hexagonal corner
 *           buildings 32 m along each street carrying the chamfer, 3
 *           rectangular plots per side between them, split points jittered
 *           +-3 m) of depth 22-26 m (per block) around an octagonal open
 *           courtyard; neighbours share walls with identical vertices.
 *           Heights 15-28 m, ~30 % as 5-9 levels. Lamps 2 m from the facade
 *           line into the street: 4 per block side (every 28.25 m), one
 *           facing each chamfer, and the same 4 on the far kerb of the
 *           streets bounding the city; z 6-9 m, 1500-2500 cd, R 35 m.
 *  oldtown  street-grid nodes at pitch 22 m jittered +-4 m; each grid edge is
 *           a street 3-7 m wide. A cell (convex quadrilateral) holds a lot
 *           set back a further 0-1.5 m; the lot is empty (14 %, a yard),
 *           one building, or two buildings sharing one exact wall (14 %).
 *           Shapes: rectangles, L (one corner cut), U (a notch in one side),
 *           Z (two opposite corners cut), built in the lot's (u, v)
 *           parameter square along iso-lines of the cell's bilinear map, so
 *           straight edges stay straight and disjoint shapes stay disjoint.
 *           Heights 4-30 m (~30 % as levels). Lamps: one per cell in the
 *           street margin of a random side, plus one at ~20 % of the street
 *           crossings; z 3-12 m, 600-1400 cd, R 25 m.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "polarlux.h"

/* ---- output ----------------------------------------------------------- */

#define GEN_BUF 4096

typedef struct gen_out {
    plx_write_fn write;
    void *ctx;
    size_t n;           /* bytes in buf */
    int failed;         /* sticky: the callback asked to stop */
    uint64_t features;  /* features written so far */
    uint64_t buildings; /* next building id */
    uint64_t lamps;     /* next lamp id */
    char buf[GEN_BUF];
} gen_out;

static void out_flush(gen_out *o)
{
    if (o->n > 0 && !o->failed && o->write(o->ctx, o->buf, o->n) != 0)
        o->failed = 1;
    o->n = 0;
}

static void out_bytes(gen_out *o, const char *s, size_t len)
{
    while (len > 0 && !o->failed) {
        size_t room = GEN_BUF - o->n;
        size_t k = len < room ? len : room;
        memcpy(o->buf + o->n, s, k);
        o->n += k;
        s += k;
        len -= k;
        if (o->n == GEN_BUF)
            out_flush(o);
    }
}

static void out_str(gen_out *o, const char *s)
{
    out_bytes(o, s, strlen(s));
}

static void out_u64(gen_out *o, uint64_t v)
{
    char tmp[20];
    int i = (int)sizeof tmp;
    do {
        tmp[--i] = (char)('0' + (int)(v % 10u));
        v /= 10u;
    } while (v != 0);
    out_bytes(o, tmp + i, sizeof tmp - (size_t)i);
}

/* Writes v / 1000 with exactly three decimals: -1234 gives "-1.234". */
static void out_milli(gen_out *o, int64_t v)
{
    char tmp[24];
    int i = (int)sizeof tmp, k;
    uint64_t m = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    for (k = 0; k < 3; k++) {
        tmp[--i] = (char)('0' + (int)(m % 10u));
        m /= 10u;
    }
    tmp[--i] = '.';
    do {
        tmp[--i] = (char)('0' + (int)(m % 10u));
        m /= 10u;
    } while (m != 0);
    if (v < 0)
        tmp[--i] = '-';
    out_bytes(o, tmp + i, sizeof tmp - (size_t)i);
}

static void out_feature_sep(gen_out *o)
{
    out_str(o, o->features ? ",\n" : "\n");
    o->features++;
}

/* A building of n vertices xy[2n] (mm, CCW, ring not closed). Writes
 * "building:levels" when levels > 0, else "height" (mm). */
static void out_building(gen_out *o, const int64_t *xy, int n, int64_t height_mm, int levels)
{
    int i;
    out_feature_sep(o);
    out_str(o, "{\"type\":\"Feature\",\"properties\":{\"id\":\"b");
    out_u64(o, o->buildings++);
    if (levels > 0) {
        out_str(o, "\",\"building:levels\":");
        out_u64(o, (uint64_t)levels);
    } else {
        out_str(o, "\",\"height\":");
        out_milli(o, height_mm);
    }
    out_str(o, "},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[");
    for (i = 0; i <= n; i++) {
        int k = i < n ? i : 0;
        out_str(o, i ? ",[" : "[");
        out_milli(o, xy[2 * k]);
        out_str(o, ",");
        out_milli(o, xy[2 * k + 1]);
        out_str(o, "]");
    }
    out_str(o, "]]}}");
}

static void out_lamp(gen_out *o, int64_t x, int64_t y, int64_t z_mm, int64_t cd_milli,
                     int64_t radius_mm)
{
    out_feature_sep(o);
    out_str(o, "{\"type\":\"Feature\",\"properties\":{\"id\":\"l");
    out_u64(o, o->lamps++);
    out_str(o, "\",\"lamp\":true,\"z\":");
    out_milli(o, z_mm);
    out_str(o, ",\"intensity\":");
    out_milli(o, cd_milli);
    out_str(o, ",\"radius\":");
    out_milli(o, radius_mm);
    out_str(o, "},\"geometry\":{\"type\":\"Point\",\"coordinates\":[");
    out_milli(o, x);
    out_str(o, ",");
    out_milli(o, y);
    out_str(o, "]}}");
}

/* ---- randomness --------------------------------------------------------- */

typedef struct gen_rng {
    uint64_t s;
} gen_rng;

static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

/* What a generator decides; part of its seed. */
enum {
    TAG_GRID_BLOCK = 1,
    TAG_GRID_LAMP,
    TAG_EIX_BLOCK,
    TAG_EIX_LAMP,
    TAG_OLD_NODE,
    TAG_OLD_VEDGE,
    TAG_OLD_HEDGE,
    TAG_OLD_LOT,
    TAG_OLD_BUILD,
    TAG_OLD_LAMP,
    TAG_OLD_NODE_LAMP
};

static void rng_seed(gen_rng *r, uint64_t seed, unsigned tag, int64_t a, int64_t b)
{
    uint64_t z = mix64(seed + UINT64_C(0x9e3779b97f4a7c15) * (uint64_t)tag);
    z = mix64(z ^ (uint64_t)a);
    z = mix64((z + UINT64_C(0x632be59bd9b4e019)) ^ (uint64_t)b);
    r->s = z;
}

static uint64_t rng_next(gen_rng *r)
{
    r->s += UINT64_C(0x9e3779b97f4a7c15);
    return mix64(r->s);
}

/* Uniform integer in [lo, hi]. */
static int64_t rng_int(gen_rng *r, int64_t lo, int64_t hi)
{
    return lo + (int64_t)(rng_next(r) % (uint64_t)(hi - lo + 1));
}

/* Uniform double in [0, 1). */
static double rng_unit(gen_rng *r)
{
    return (double)(rng_next(r) >> 11) * (1.0 / 9007199254740992.0);
}

static double rng_range(gen_rng *r, double lo, double hi)
{
    return lo + (hi - lo) * rng_unit(r);
}

/* ---- grid ----------------------------------------------------------------- */

#define GRID_PITCH 100000   /* mm */
#define GRID_HALF_STREET 10000

static void gen_grid(gen_out *o, int nx, int ny, uint64_t seed)
{
    int i, j, s;
    gen_rng r;
    for (j = 0; j < ny && !o->failed; j++) {
        for (i = 0; i < nx; i++) {
            int64_t x0 = (int64_t)i * GRID_PITCH + GRID_HALF_STREET;
            int64_t y0 = (int64_t)j * GRID_PITCH + GRID_HALF_STREET;
            int64_t x1 = (int64_t)(i + 1) * GRID_PITCH - GRID_HALF_STREET;
            int64_t y1 = (int64_t)(j + 1) * GRID_PITCH - GRID_HALF_STREET;
            int64_t xy[8], h;
            int levels = 0;
            rng_seed(&r, seed, TAG_GRID_BLOCK, i, j);
            x0 += 100 * rng_int(&r, 0, 80);
            y0 += 100 * rng_int(&r, 0, 80);
            x1 -= 100 * rng_int(&r, 0, 80);
            y1 -= 100 * rng_int(&r, 0, 80);
            h = 9000 + 100 * rng_int(&r, 0, 310);
            if (rng_unit(&r) < 0.25)
                levels = (int)rng_int(&r, 3, 13);
            xy[0] = x0; xy[1] = y0;
            xy[2] = x1; xy[3] = y0;
            xy[4] = x1; xy[5] = y1;
            xy[6] = x0; xy[7] = y1;
            out_building(o, xy, 4, h, levels);
        }
    }
    /* Streets along x = i*pitch (s = 0) and y = j*pitch (s = 1). */
    for (s = 0; s < 2; s++) {
        int nl = s == 0 ? nx + 1 : ny + 1; /* street lines */
        int ns = s == 0 ? ny : nx;         /* segments along one line */
        for (i = 0; i < nl && !o->failed; i++) {
            for (j = 0; j < ns; j++) {
                int64_t across = (int64_t)i * GRID_PITCH;
                int64_t along = (int64_t)j * GRID_PITCH + GRID_HALF_STREET;
                int k;
                rng_seed(&r, seed, TAG_GRID_LAMP, 2 * (int64_t)i + s, j);
                for (k = 0; k < 2; k++) {
                    int64_t a = along + (k == 0 ? 20000 : 60000);
                    int64_t c = across + (k == 0 ? -7000 : 7000);
                    int64_t z = 7000 + 100 * rng_int(&r, 0, 20);
                    if (s == 0)
                        out_lamp(o, c, a, z, 2000000, 40000);
                    else
                        out_lamp(o, a, c, z, 2000000, 40000);
                }
            }
        }
    }
}

/* ---- eixample ------------------------------------------------------------- */

#define EIX_PITCH 133000
#define EIX_SIDE 113000    /* block side; streets are pitch - side = 20 m */
#define EIX_CHAMFER 14142  /* corner cut along each side: a 20 m face */
#define EIX_CORNER 32000   /* corner building's length along each street */
#define EIX_LAMP_SET 2000  /* lamps stand this far from the facade line */

/* Rotates a block-local point k quarter turns counter-clockwise about the
 * block centre; exact in integers. */
static void eix_rot(int64_t *x, int64_t *y, int k)
{
    while (k-- > 0) {
        int64_t t = *x;
        *x = EIX_SIDE - *y;
        *y = t;
    }
}

static void eix_block_buildings(gen_out *o, int bi, int bj, uint64_t seed)
{
    const int64_t a = EIX_CORNER, c = EIX_CHAMFER, len = EIX_SIDE - 2 * EIX_CORNER;
    const int64_t ox = (int64_t)bi * EIX_PITCH + (EIX_PITCH - EIX_SIDE) / 2;
    const int64_t oy = (int64_t)bj * EIX_PITCH + (EIX_PITCH - EIX_SIDE) / 2;
    int64_t d, split[4][4];
    int k, m, v;
    gen_rng r;
    rng_seed(&r, seed, TAG_EIX_BLOCK, bi, bj);
    d = 22000 + 100 * rng_int(&r, 0, 40);
    for (k = 0; k < 4; k++) {
        split[k][0] = a;
        split[k][1] = a + len / 3 + 100 * rng_int(&r, -30, 30);
        split[k][2] = a + 2 * len / 3 + 100 * rng_int(&r, -30, 30);
        split[k][3] = EIX_SIDE - a;
    }
    /* Ring order: corner k, then the 3 plots of side k, for k = 0..3
     * (bottom-left corner and bottom side in frame 0). */
    for (k = 0; k < 4 && !o->failed; k++) {
        for (m = -1; m < 3; m++) {
            int64_t xy[12], h;
            int n, levels = 0;
            if (m < 0) {
                const int64_t corner[12] = { c, 0, a, 0, a, d, d, a, 0, a, 0, c };
                memcpy(xy, corner, sizeof corner);
                n = 6;
            } else {
                xy[0] = split[k][m];     xy[1] = 0;
                xy[2] = split[k][m + 1]; xy[3] = 0;
                xy[4] = split[k][m + 1]; xy[5] = d;
                xy[6] = split[k][m];     xy[7] = d;
                n = 4;
            }
            for (v = 0; v < n; v++) {
                eix_rot(&xy[2 * v], &xy[2 * v + 1], k);
                xy[2 * v] += ox;
                xy[2 * v + 1] += oy;
            }
            h = 15000 + 100 * rng_int(&r, 0, 130);
            if (rng_unit(&r) < 0.3)
                levels = (int)rng_int(&r, 5, 9);
            out_building(o, xy, n, h, levels);
        }
    }
}

static void eix_block_lamps(gen_out *o, int bi, int bj, int nx, int ny, uint64_t seed)
{
    const int64_t ox = (int64_t)bi * EIX_PITCH + (EIX_PITCH - EIX_SIDE) / 2;
    const int64_t oy = (int64_t)bj * EIX_PITCH + (EIX_PITCH - EIX_SIDE) / 2;
    /* The chamfer face is x + y = c; its lamp stands 2 m off its middle. */
    const int64_t cl = EIX_CHAMFER / 2 - 1414;
    int k, m;
    gen_rng r;
    rng_seed(&r, seed, TAG_EIX_LAMP, bi, bj);
    for (k = 0; k < 4; k++) {
        /* Side k of the block faces the city's edge? (bottom, right, top, left) */
        int edge = (k == 0 && bj == 0) || (k == 1 && bi == nx - 1) ||
                   (k == 2 && bj == ny - 1) || (k == 3 && bi == 0);
        int count = edge ? 9 : 5;
        for (m = 0; m < count; m++) {
            int64_t x, y, z, cd;
            if (m == 0) {
                x = cl;
                y = cl;
            } else if (m <= 4) {
                x = 14125 + 28250 * (int64_t)(m - 1);
                y = -EIX_LAMP_SET;
            } else { /* far kerb of a street at the city's edge */
                x = 14125 + 28250 * (int64_t)(m - 5);
                y = -(EIX_PITCH - EIX_SIDE) + EIX_LAMP_SET;
            }
            eix_rot(&x, &y, k);
            z = 6000 + 100 * rng_int(&r, 0, 30);
            cd = 1000 * (1500 + 10 * rng_int(&r, 0, 100));
            out_lamp(o, x + ox, y + oy, z, cd, 35000);
        }
    }
}

static void gen_eixample(gen_out *o, int nx, int ny, uint64_t seed)
{
    int i, j;
    for (j = 0; j < ny && !o->failed; j++)
        for (i = 0; i < nx; i++)
            eix_block_buildings(o, i, j, seed);
    for (j = 0; j < ny && !o->failed; j++)
        for (i = 0; i < nx; i++)
            eix_block_lamps(o, i, j, nx, ny, seed);
}

/* ---- oldtown -------------------------------------------------------------- */

#define OLD_PITCH 22000
#define OLD_JITTER 4000

/* One cell of the jittered street grid and the lot inside it. */
typedef struct old_cell {
    double q[8];          /* corners Q00 Q10 Q11 Q01 (mm), counter-clockwise */
    double u0, u1, v0, v1; /* the lot in the cell's (u, v) parameter square */
} old_cell;

static void old_node(uint64_t seed, int i, int j, double *x, double *y)
{
    gen_rng r;
    rng_seed(&r, seed, TAG_OLD_NODE, i, j);
    *x = (double)((int64_t)i * OLD_PITCH + rng_int(&r, -OLD_JITTER, OLD_JITTER));
    *y = (double)((int64_t)j * OLD_PITCH + rng_int(&r, -OLD_JITTER, OLD_JITTER));
}

/* Street width (mm) of the grid edge of line 'line', segment 'seg'. */
static double old_street(uint64_t seed, unsigned tag, int line, int seg)
{
    gen_rng r;
    rng_seed(&r, seed, tag, line, seg);
    return (double)(3000 + 100 * rng_int(&r, 0, 40));
}

static double old_dist(const double *p, const double *q)
{
    return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]));
}

static void old_cell_get(uint64_t seed, int i, int j, old_cell *cell)
{
    double lu, lv;
    gen_rng r;
    old_node(seed, i, j, &cell->q[0], &cell->q[1]);
    old_node(seed, i + 1, j, &cell->q[2], &cell->q[3]);
    old_node(seed, i + 1, j + 1, &cell->q[4], &cell->q[5]);
    old_node(seed, i, j + 1, &cell->q[6], &cell->q[7]);
    lu = 0.5 * (old_dist(&cell->q[0], &cell->q[2]) + old_dist(&cell->q[6], &cell->q[4]));
    lv = 0.5 * (old_dist(&cell->q[0], &cell->q[6]) + old_dist(&cell->q[2], &cell->q[4]));
    rng_seed(&r, seed, TAG_OLD_LOT, i, j);
    cell->u0 = (0.5 * old_street(seed, TAG_OLD_VEDGE, i, j) + 100.0 * (double)rng_int(&r, 0, 15)) / lu;
    cell->u1 = 1.0 - (0.5 * old_street(seed, TAG_OLD_VEDGE, i + 1, j) +
                      100.0 * (double)rng_int(&r, 0, 15)) / lu;
    cell->v0 = (0.5 * old_street(seed, TAG_OLD_HEDGE, j, i) + 100.0 * (double)rng_int(&r, 0, 15)) / lv;
    cell->v1 = 1.0 - (0.5 * old_street(seed, TAG_OLD_HEDGE, j + 1, i) +
                      100.0 * (double)rng_int(&r, 0, 15)) / lv;
}

/* The cell's bilinear map at (u, v), rounded to mm. Lines of constant u or
 * v are straight, so a polygon whose edges follow them maps exactly. */
static void old_map(const old_cell *cell, double u, double v, int64_t *out)
{
    const double *q = cell->q;
    double w0 = (1.0 - u) * (1.0 - v), w1 = u * (1.0 - v), w2 = u * v, w3 = (1.0 - u) * v;
    double x = w0 * q[0] + w1 * q[2] + w2 * q[4] + w3 * q[6];
    double y = w0 * q[1] + w1 * q[3] + w2 * q[5] + w3 * q[7];
    out[0] = (int64_t)floor(x + 0.5);
    out[1] = (int64_t)floor(y + 0.5);
}

/* lerp exact at both ends: t = 0 gives lo, t = 1 gives hi. */
static double lerp(double lo, double hi, double t)
{
    return (1.0 - t) * lo + t * hi;
}

/* A footprint in the unit square, counter-clockwise; 'shared' is the side
 * (0 bottom, 1 right, 2 top, 3 left, -1 none) that is a party wall and so
 * must stay whole. Returns the vertex count (at most 8). */
static int old_shape(gen_rng *r, int shared, double *st)
{
    double p = rng_unit(r);
    int n, k, v, kind;
    kind = p < 0.45 ? 0 : p < 0.75 ? 1 : p < 0.92 ? 2 : 3;
    if (kind == 3 && shared >= 0)
        kind = 1;
    if (kind == 0) {
        const double rect[8] = { 0, 0, 1, 0, 1, 1, 0, 1 };
        memcpy(st, rect, sizeof rect);
        return 4;
    }
    if (kind == 1) { /* L: top-right corner cut; touches sides 1 and 2 */
        double fs = rng_range(r, 0.3, 0.6), ft = rng_range(r, 0.3, 0.6);
        double l[12];
        l[0] = 0;        l[1] = 0;
        l[2] = 1;        l[3] = 0;
        l[4] = 1;        l[5] = 1 - ft;
        l[6] = 1 - fs;   l[7] = 1 - ft;
        l[8] = 1 - fs;   l[9] = 1;
        l[10] = 0;       l[11] = 1;
        memcpy(st, l, sizeof l);
        n = 6;
    } else if (kind == 2) { /* U: a notch in the top side */
        double n0 = rng_range(r, 0.2, 0.4), n1 = 1.0 - rng_range(r, 0.2, 0.4);
        double dd = rng_range(r, 0.3, 0.55);
        double u[16];
        u[0] = 0;   u[1] = 0;
        u[2] = 1;   u[3] = 0;
        u[4] = 1;   u[5] = 1;
        u[6] = n1;  u[7] = 1;
        u[8] = n1;  u[9] = 1 - dd;
        u[10] = n0; u[11] = 1 - dd;
        u[12] = n0; u[13] = 1;
        u[14] = 0;  u[15] = 1;
        memcpy(st, u, sizeof u);
        n = 8;
    } else { /* Z: bottom-left and top-right corners cut */
        double a0 = rng_range(r, 0.2, 0.4), b0 = rng_range(r, 0.2, 0.4);
        double a1 = rng_range(r, 0.2, 0.4), b1 = rng_range(r, 0.2, 0.4);
        double z[16];
        z[0] = a0;      z[1] = 0;
        z[2] = 1;       z[3] = 0;
        z[4] = 1;       z[5] = 1 - b1;
        z[6] = 1 - a1;  z[7] = 1 - b1;
        z[8] = 1 - a1;  z[9] = 1;
        z[10] = 0;      z[11] = 1;
        z[12] = 0;      z[13] = b0;
        z[14] = a0;     z[15] = b0;
        memcpy(st, z, sizeof z);
        n = 8;
    }
    /* Quarter turns of the square move side q to q + 1; pick one that keeps
     * the party wall whole. */
    do {
        k = (int)rng_int(r, 0, 3);
    } while (shared >= 0 && (kind == 2 ? (2 + k) % 4 == shared
                                       : ((1 + k) % 4 == shared || (2 + k) % 4 == shared)));
    for (v = 0; v < n; v++) {
        int t;
        for (t = 0; t < k; t++) {
            double s = st[2 * v];
            st[2 * v] = 1.0 - st[2 * v + 1];
            st[2 * v + 1] = s;
        }
    }
    return n;
}

static void old_building(gen_out *o, gen_rng *r, const old_cell *cell, double ua, double ub,
                         double va, double vb, int shared)
{
    double st[16], p;
    int64_t xy[16], h;
    int n, v, levels = 0;
    n = old_shape(r, shared, st);
    for (v = 0; v < n; v++)
        old_map(cell, lerp(ua, ub, st[2 * v]), lerp(va, vb, st[2 * v + 1]), &xy[2 * v]);
    p = rng_unit(r);
    if (p < 0.2)
        h = 4000 + 100 * rng_int(r, 0, 40);
    else if (p < 0.85)
        h = 8000 + 100 * rng_int(r, 0, 100);
    else
        h = 18000 + 100 * rng_int(r, 0, 120);
    if (rng_unit(r) < 0.3) {
        levels = (int)((h + 1500) / 3000);
        levels = levels < 2 ? 2 : levels > 10 ? 10 : levels;
    }
    out_building(o, xy, n, h, levels);
}

/* An old-town lamp. The intensity is drawn before the height: two draws
 * inside one call's arguments would be made in an order C leaves open (and
 * gcc takes them one way on x86-64, the other on aarch64). */
static void old_lamp(gen_out *o, gen_rng *r, int64_t x, int64_t y)
{
    int64_t cd = 1000 * (600 + 10 * rng_int(r, 0, 80));
    int64_t z = 3000 + 100 * rng_int(r, 0, 90);
    out_lamp(o, x, y, z, cd, 25000);
}

static void gen_oldtown(gen_out *o, int nx, int ny, uint64_t seed)
{
    int i, j;
    gen_rng r;
    old_cell cell;
    for (j = 0; j < ny && !o->failed; j++) {
        for (i = 0; i < nx; i++) {
            double p;
            old_cell_get(seed, i, j, &cell);
            rng_seed(&r, seed, TAG_OLD_BUILD, i, j);
            p = rng_unit(&r);
            if (p < 0.14)
                continue; /* a yard or a small square */
            if (p < 0.28) { /* two houses sharing a wall across the longer side */
                double lu = old_dist(&cell.q[0], &cell.q[2]) * (cell.u1 - cell.u0);
                double lv = old_dist(&cell.q[0], &cell.q[6]) * (cell.v1 - cell.v0);
                double f = rng_range(&r, 0.35, 0.65);
                if (lu >= lv) {
                    double us = lerp(cell.u0, cell.u1, f);
                    old_building(o, &r, &cell, cell.u0, us, cell.v0, cell.v1, 1);
                    old_building(o, &r, &cell, us, cell.u1, cell.v0, cell.v1, 3);
                } else {
                    double vs = lerp(cell.v0, cell.v1, f);
                    old_building(o, &r, &cell, cell.u0, cell.u1, cell.v0, vs, 2);
                    old_building(o, &r, &cell, cell.u0, cell.u1, vs, cell.v1, 0);
                }
            } else {
                old_building(o, &r, &cell, cell.u0, cell.u1, cell.v0, cell.v1, -1);
            }
        }
    }
    for (j = 0; j < ny && !o->failed; j++) {
        for (i = 0; i < nx; i++) {
            int64_t xy[2];
            double t, u, v;
            int side;
            old_cell_get(seed, i, j, &cell);
            rng_seed(&r, seed, TAG_OLD_LAMP, i, j);
            side = (int)rng_int(&r, 0, 3);
            t = rng_range(&r, 0.2, 0.8);
            /* In the street margin of the chosen side, outside the lot. */
            switch (side) {
            case 0: u = t; v = 0.4 * cell.v0; break;
            case 1: u = 1.0 - 0.4 * (1.0 - cell.u1); v = t; break;
            case 2: u = t; v = 1.0 - 0.4 * (1.0 - cell.v1); break;
            default: u = 0.4 * cell.u0; v = t; break;
            }
            old_map(&cell, u, v, xy);
            old_lamp(o, &r, xy[0], xy[1]);
        }
    }
    for (j = 0; j <= ny && !o->failed; j++) {
        for (i = 0; i <= nx; i++) {
            double x, y;
            rng_seed(&r, seed, TAG_OLD_NODE_LAMP, i, j);
            if (rng_unit(&r) >= 0.2)
                continue;
            old_node(seed, i, j, &x, &y);
            old_lamp(o, &r, (int64_t)x, (int64_t)y);
        }
    }
}

/* ---- entry ---------------------------------------------------------------- */

plx_status plx_gen_city(const char *style, int nx, int ny, uint64_t seed,
                        plx_write_fn write, void *ctx)
{
    gen_out o;
    int which;
    if (style == NULL || write == NULL || nx < 1 || ny < 1 || nx > 1000 || ny > 1000)
        return PLX_E_INVALID;
    if (strcmp(style, "grid") == 0)
        which = 0;
    else if (strcmp(style, "eixample") == 0)
        which = 1;
    else if (strcmp(style, "oldtown") == 0)
        which = 2;
    else
        return PLX_E_INVALID;

    o.write = write;
    o.ctx = ctx;
    o.n = 0;
    o.failed = 0;
    o.features = o.buildings = o.lamps = 0;

    out_str(&o, "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\","
                "\"generator\":\"polarlux gen\",\"style\":\"");
    out_str(&o, style);
    out_str(&o, "\",\"nx\":");
    out_u64(&o, (uint64_t)nx);
    out_str(&o, ",\"ny\":");
    out_u64(&o, (uint64_t)ny);
    out_str(&o, ",\"seed\":");
    out_u64(&o, seed);
    out_str(&o, "},\"features\":[");
    if (which == 0)
        gen_grid(&o, nx, ny, seed);
    else if (which == 1)
        gen_eixample(&o, nx, ny, seed);
    else
        gen_oldtown(&o, nx, ny, seed);
    out_str(&o, "\n]}\n");
    out_flush(&o);
    return o.failed ? PLX_E_IO : PLX_OK;
}
