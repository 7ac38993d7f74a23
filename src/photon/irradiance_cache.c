/* irradiance_cache: final gathers at sparse surface points, interpolated
 * for images (irradiance_cache.h). */
#include <math.h>
#include <string.h>

#include "base/bits.h"
#include "photon/irradiance_cache.h"
#include "photon/final_gather.h"
#include "photon/indirect.h"

#define ICACHE_SEED 0x1ca4e5eedull
#define HEIGHT_TOL 1e-3   /* m: one surface's height, as in photon.c */
#define PROBE_OFF 0.005   /* m: a wall probe starts this far in front */
#define PROBE_LEN 0.02    /* m: and looks this far back */
#define BLOCK_DZ 0.05     /* m: the segment tests run this far above the surface */
#define COORD_BIAS ((int64_t)1 << 28)
#define COORD_MASK (((uint64_t)1 << 29) - 1)

enum { REC_USED = 1, REC_VALID = 2 };

/* The surface a pixel's point lies on: its key and its grid frame. */
typedef struct plane {
    uint64_t code;        /* kind in the top bits, then what tells it apart */
    int wall;
    double o[3];          /* grid origin: (0, 0, z) or the edge's first vertex */
    double t[3], n[3];    /* grid u axis (x or along the wall), normal */
    double top;           /* horizontal: topmost height over P (trace_top) */
    uint32_t bld;         /* a roof's building (trace_top) */
    uint32_t edge;
} plane;

static uint64_t mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

uint32_t icache_records_for(size_t budget)
{
    uint32_t n = ICACHE_RECORDS;
    while (n > ICACHE_RECORDS_MIN && (size_t)n * sizeof(icache_rec) > budget / 16)
        n /= 2;
    return n;
}

size_t icache_bytes(uint32_t nrec)
{
    return sizeof(icache) + 64 + (size_t)nrec * sizeof(icache_rec) + 64;
}

plx_status icache_create(arena *a, uint32_t nrec, icache **out)
{
    arena_mark m = arena_get_mark(a);
    icache *c;
    if (nrec < ICACHE_RECORDS_MIN || nrec > ICACHE_RECORDS || (nrec & (nrec - 1)))
        return PLX_E_INVALID;
    c = arena_calloc(a, PLX_PART_PHOTON, 1, sizeof *c, 64);
    if (c)
        c->tab = arena_calloc(a, PLX_PART_PHOTON, nrec, sizeof(icache_rec), 64);
    if (!c || !c->tab) {
        arena_release(a, &m);
        return PLX_E_NOMEM;
    }
    c->nrec = nrec;
    c->side = ICACHE_SIDE;
    c->kappa = ICACHE_KAPPA;
    c->smin = ICACHE_SMIN;
    *out = c;
    return PLX_OK;
}

void icache_set_view(icache *c, const double eye[3])
{
    memcpy(c->eye, eye, sizeof c->eye);
}

void icache_set_spacing(icache *c, double s)
{
    uint32_t side = s > 0.0 ? ICACHE_AERIAL_SIDE : ICACHE_SIDE;
    c->fixed = s > 0.0 ? s : 0.0;
    if (side != c->side) /* the last cells hold the other kind's records */
        memset(c->last, 0, sizeof c->last);
    c->side = side;
}

static void flush(icache *c)
{
    memset(c->tab, 0, (size_t)c->nrec * sizeof(icache_rec));
    memset(c->last, 0, sizeof c->last);
    c->used = 0;
    c->flushes++;
}

void icache_clear(icache *c)
{
    flush(c);
    /* the peeks' cells too: a bake holds none of the workers' history */
    memset(c->peek_last, 0, sizeof c->peek_last);
    c->stamp = 0;
    c->gathered = c->direct = c->flushes = 0;
    /* and the last frame's viewer and spacing: every frame sets them */
    c->eye[0] = c->eye[1] = c->eye[2] = 0.0;
    c->fixed = 0.0;
}

/* What the records were gathered from: any new photon frame, reset,
 * refined lamp or floor map computed again (a miss: an evicted lamp's
 * map back in the cache) changes these sums and counts. */
static uint64_t photon_stamp(const photon_sys *ps)
{
    const photon_stats *st = &ps->st;
    uint64_t h = mix64(st->frames ^ 0x5eedull);
    h = mix64(h ^ st->photons);
    h = mix64(h ^ bits_of_double(st->emitted));
    h = mix64(h ^ bits_of_double(st->arrived));
    h = mix64(h ^ bits_of_double(st->stored_chart));
    h = mix64(h ^ bits_of_double(st->stored_aerial));
    h = mix64(h ^ st->lamp_refined);
    h = mix64(h ^ st->lamp_misses);
    h = mix64(h ^ st->aerial_restarts);
    return mix64(h ^ bits_of_double(ps->flux_total));
}

/* A wall probe: the edge whose wall is within 2 cm behind P along -n. */
static int probe_wall(tracer *T, const double P[3], const double n[3], trace_hit *h)
{
    double o[3], d[3];
    int k;
    for (k = 0; k < 3; k++) {
        o[k] = P[k] + PROBE_OFF * n[k];
        d[k] = -n[k];
    }
    if (!(o[2] >= 0.0))
        return 0;
    return trace_ray(T, o, d, PROBE_LEN, h) == TRACE_WALL;
}

static uint64_t mm(double z)
{
    return (uint64_t)(int64_t)llround(z * 1000.0) & 0x3fffffffull;
}

/* The surface of a point P facing up whose topmost surface (trace_top)
 * is top, of building bld: the ground or a roof. */
static void plane_up(const double P[3], double top, uint32_t bld, plane *pl)
{
    memset(pl, 0, sizeof *pl);
    pl->top = top;
    pl->bld = top > HEIGHT_TOL ? bld : 0;
    /* a roof is its building's own surface: roofs of one height
     * elsewhere (across a street or a courtyard) are others */
    pl->code = ((uint64_t)1 << 62) | (mix64(pl->bld ^ mix64((mm(P[2]) << 30) | mm(pl->top))) >> 2);
    pl->o[2] = P[2];
    pl->t[0] = 1.0;
    pl->n[2] = 1.0;
}

/* P's surface: 1 with pl filled, 0 when it has no grid (undersides,
 * points no probe ties to a wall). */
static int plane_of(tracer *T, const scene *s, const double P[3], const double n[3], plane *pl)
{
    trace_hit h;
    memset(pl, 0, sizeof *pl);
    if (n[2] > 0.5) {
        uint32_t bld;
        double top = trace_top(T, P[0], P[1], &bld);
        plane_up(P, top, bld, pl);
        return 1;
    }
    if (n[2] < -0.5 || !probe_wall(T, P, n, &h))
        return 0;
    pl->wall = 1;
    pl->edge = h.edge;
    pl->code = ((uint64_t)2 << 62) | h.edge;
    pl->o[0] = s->pts[h.edge].x;
    pl->o[1] = s->pts[h.edge].y;
    pl->n[0] = h.n[0];
    pl->n[1] = h.n[1];
    pl->t[0] = -h.n[1];
    pl->t[1] = h.n[0];
    return 1;
}

/* The point of vertex (i, j) of spacing sp. */
static void vertex_point(const plane *pl, double sp, int64_t i, int64_t j, double Q[3])
{
    double u = (double)i * sp, v = (double)j * sp;
    if (pl->wall) {
        Q[0] = pl->o[0] + u * pl->t[0];
        Q[1] = pl->o[1] + u * pl->t[1];
        Q[2] = v;
    } else {
        Q[0] = u;
        Q[1] = v;
        Q[2] = pl->o[2];
    }
}

/* Whether Q lies on pl's surface (irradiance_cache.h, VALID VERTICES). */
static int vertex_valid(tracer *T, const plane *pl, const double Q[3])
{
    trace_hit h;
    if (!pl->wall) {
        uint32_t b = 0;
        double top = trace_top(T, Q[0], Q[1], &b);
        return fabs(top - pl->top) <= HEIGHT_TOL && (!(top > HEIGHT_TOL) || b == pl->bld);
    }
    if (!(Q[2] > 0.0) || !probe_wall(T, Q, pl->n, &h) || h.edge != pl->edge)
        return 0;
    /* not behind a building standing against the wall */
    return trace_top(T, Q[0] + 0.01 * pl->n[0], Q[1] + 0.01 * pl->n[1], NULL) < Q[2];
}

/* The records' E_later step (final_gather_rgb_later): views from above
 * read it at one direction in ICACHE_AERIAL_LATER^2. */
static uint32_t later_of(const icache *c)
{
    return c->fixed > 0.0 ? ICACHE_AERIAL_LATER : 1;
}

/* The second key of vertex (i, j) at level l (the first: the surface). */
static uint64_t key2(const icache *c, int l, int64_t i, int64_t j)
{
    return ((uint64_t)(c->side != ICACHE_SIDE) << 62) | ((uint64_t)l << 58) |
           (((uint64_t)(i + COORD_BIAS) & COORD_MASK) << 29) | ((uint64_t)(j + COORD_BIAS) & COORD_MASK);
}

/* Vertex (i, j) at level l's slot: the one holding its record, or the
 * free slot where it goes. */
static icache_rec *slot(const icache *c, const plane *pl, int l, int64_t i, int64_t j, uint64_t *k2_out)
{
    uint64_t k2 = key2(c, l, i, j);
    uint32_t mask = c->nrec - 1, at;
    icache_rec *r;
    at = (uint32_t)mix64(pl->code ^ mix64(k2)) & mask;
    for (;;) {
        r = &c->tab[at];
        if (!(r->flags & REC_USED) || (r->k1 == pl->code && r->k2 == k2))
            break;
        at = (at + 1) & mask;
    }
    *k2_out = k2;
    return r;
}

/* The record of vertex (i, j) at level l, gathered on first need. */
static const icache_rec *record(icache *c, photon_sys *ps, light *L, const plane *pl, int l,
                                int64_t i, int64_t j)
{
    uint64_t k2;
    icache_rec *r = slot(c, pl, l, i, j, &k2);
    double Q[3], rgb[3];
    if (r->flags & REC_USED)
        return r;
    if (c->used >= c->nrec / 4 * 3) {
        flush(c);
        return record(c, ps, L, pl, l, i, j);
    }
    c->used++;
    r->k1 = pl->code;
    r->k2 = k2;
    r->flags = REC_USED;
    vertex_point(pl, ICACHE_S0 * ldexp(1.0, l), i, j, Q);
    if (vertex_valid(ps->T, pl, Q)) {
        final_gather_rgb_later(ps, ps->T, L, Q, pl->n, c->side, later_of(c), ICACHE_SEED, rgb);
        r->e[0] = (float)rgb[0];
        r->e[1] = (float)rgb[1];
        r->e[2] = (float)rgb[2];
        r->flags |= REC_VALID;
        c->gathered++;
    }
    return r;
}

/* Vertex v (0..3: +a, +2b) of cell (i, j) at level l: from the level's
 * last cell when it is this one, else from the table (record). */
/* lc made cell (i, j) of pl's surface, emptied when it was another
 * (or none: the table was emptied). */
static void cell_at(icache_cell *lc, const plane *pl, int64_t i, int64_t j)
{
    if (lc->set && lc->code == pl->code && lc->i == i && lc->j == j)
        return;
    memset(lc, 0, sizeof *lc);
    lc->set = ICACHE_CELL_SET;
    lc->code = pl->code;
    lc->i = i;
    lc->j = j;
}

static const icache_rec *cell_record(icache *c, photon_sys *ps, light *L, const plane *pl, int l,
                                     int64_t i, int64_t j, int v)
{
    icache_cell *lc = &c->last[l];
    const icache_rec *r;
    cell_at(lc, pl, i, j);
    if (lc->r[v])
        return &c->tab[lc->r[v] - 1];
    r = record(c, ps, L, pl, l, i + (v & 1), j + (v >> 1));
    cell_at(lc, pl, i, j); /* the table was emptied to make room: this cell again */
    lc->r[v] = (uint32_t)(r - c->tab) + 1;
    return r;
}

/* A peek's vertex v of cell (i, j) at level l (as cell_record): from
 * the worker's last cell at the level while its slot holds the vertex,
 * else the table; NULL when the record is not there (nothing remembered
 * then). */
static const icache_rec *peek_record(const icache *c, icache_cell *last, const plane *pl, int l, int64_t i,
                                     int64_t j, int v)
{
    icache_cell *lc = &last[l];
    int64_t vi = i + (v & 1), vj = j + (v >> 1);
    icache_rec *r;
    uint64_t k2;
    cell_at(lc, pl, i, j);
    if (lc->r[v]) {
        r = &c->tab[lc->r[v] - 1];
        if ((r->flags & REC_USED) && r->k1 == pl->code && r->k2 == key2(c, l, vi, vj))
            return r;
    }
    r = slot(c, pl, l, vi, vj, &k2);
    if (!(r->flags & REC_USED)) {
        lc->r[v] = 0;
        return NULL;
    }
    lc->r[v] = (uint32_t)(r - c->tab) + 1;
    return r;
}

/* Whether the horizontal segment from P (5 cm above its surface) to the
 * vertex Q meets a wall: on coarse grids a ground cell may span a small
 * building, and the street beyond it is the same height of ground. */
static int blocked(tracer *T, const double P[3], const double Q[3])
{
    double o[3], d[3], l;
    trace_hit h;
    d[0] = Q[0] - P[0];
    d[1] = Q[1] - P[1];
    d[2] = 0.0;
    l = sqrt(d[0] * d[0] + d[1] * d[1]);
    if (!(l > 1e-9))
        return 0;
    d[0] /= l;
    d[1] /= l;
    o[0] = P[0];
    o[1] = P[1];
    o[2] = P[2] + BLOCK_DZ;
    return trace_ray(T, o, d, l, &h) != TRACE_SKY;
}

/* Whether P's cell (i, j) at level l, spacing sp, of a horizontal
 * surface has no wall at the height of the segment tests (blocked): then
 * none of them can meet one. Kept with the level's last cell (cell_record
 * set it to this cell). The surface's points lie within 1 mm of one
 * height (its code holds it in mm), so walls within 1 mm of the segments'
 * height z count. */
static int cell_clear(icache_cell *last, tracer *T, const plane *pl, int l, int64_t i, int64_t j, double sp,
                      double z)
{
    icache_cell *lc = &last[l];
    if (!lc->set || lc->code != pl->code || lc->i != i || lc->j != j)
        return 0;
    if (lc->set == ICACHE_CELL_SET)
        lc->set = trace_box_clear(T, (double)i * sp, (double)j * sp, (double)(i + 1) * sp,
                                  (double)(j + 1) * sp, z - HEIGHT_TOL, z + HEIGHT_TOL)
                      ? ICACHE_CELL_CLEAR : ICACHE_CELL_WALLS;
    return lc->set == ICACHE_CELL_CLEAR;
}

/* A peek's state: set when a record is not there, and the worker's
 * last cells. */
typedef struct peek_state {
    int miss;
    icache_cell *last;
} peek_state;

/* Bilinear over the valid vertices of P's cell at level l; 0 when none
 * of them is valid (with weight). With pk (a peek): the records are only
 * looked for, and pk->miss set (0 returned) when one is not there. */
static int level_value(icache *c, photon_sys *ps, light *L, const plane *pl, const double P[3],
                       int l, double rgb[3], peek_state *pk)
{
    double sp = ICACHE_S0 * ldexp(1.0, l), d[3], fu, fv, wu, wv, ws = 0.0, acc[3] = {0, 0, 0};
    int64_t i, j;
    int a, b, k;
    for (k = 0; k < 3; k++)
        d[k] = P[k] - pl->o[k];
    fu = (d[0] * pl->t[0] + d[1] * pl->t[1]) / sp;
    fv = (pl->wall ? P[2] : P[1]) / sp;
    i = (int64_t)floor(fu);
    j = (int64_t)floor(fv);
    wu = fu - (double)i;
    wv = fv - (double)j;
    for (b = 0; b < 2; b++)
        for (a = 0; a < 2; a++) {
            double w = (a ? wu : 1.0 - wu) * (b ? wv : 1.0 - wv);
            const icache_rec *r;
            if (!(w > 0.0))
                continue;
            if (pk) {
                r = peek_record(c, pk->last, pl, l, i, j, 2 * b + a);
                if (!r) {
                    pk->miss = 1;
                    return 0;
                }
            } else
                r = cell_record(c, ps, L, pl, l, i, j, 2 * b + a);
            if (!(r->flags & REC_VALID))
                continue;
            if (!pl->wall && l >= ICACHE_LEVEL_SEG &&
                !cell_clear(pk ? pk->last : c->last, ps->T, pl, l, i, j, sp, P[2] + BLOCK_DZ)) {
                double Q[3];
                vertex_point(pl, sp, i + a, j + b, Q);
                if (blocked(ps->T, P, Q))
                    continue;
            }
            ws += w;
            for (k = 0; k < 3; k++)
                acc[k] += w * r->e[k];
        }
    if (!(ws > 1e-6))
        return 0;
    for (k = 0; k < 3; k++)
        rgb[k] = acc[k] / ws;
    return 1;
}

/* Level l, or the finest level below it with a valid vertex, or P itself
 * (a peek: pk->miss set instead of gathering). */
static void level_or_finer(icache *c, photon_sys *ps, light *L, const plane *pl,
                           const double P[3], int l, double rgb[3], peek_state *pk)
{
    for (; l >= 0; l--)
        if (level_value(c, ps, L, pl, P, l, rgb, pk) || (pk && pk->miss))
            return;
    if (pk) {
        pk->miss = 1;
        return;
    }
    c->direct++;
    final_gather_rgb_later(ps, ps->T, L, P, pl->n, c->side, later_of(c), ICACHE_SEED, rgb);
}

/* The table's records belong to the photon buffers as they are. */
static void check_stamp(icache *c, const photon_sys *ps)
{
    uint64_t stamp = photon_stamp(ps);
    if (stamp != c->stamp) {
        if (c->used)
            flush(c);
        c->stamp = stamp;
    }
}

/* A fixed spacing's level (icache_set_spacing). */
static int fixed_level(const icache *c)
{
    return (int)fmin(floor(log2(fmax(c->fixed, ICACHE_S0) / ICACHE_S0)), ICACHE_LEVEL_MAX);
}

double icache_lookup_top(icache *c, photon_sys *ps, light *L, double x, double y, double rgb[3])
{
    double P[3];
    uint32_t bld;
    plane pl;
    P[0] = x;
    P[1] = y;
    P[2] = trace_top(ps->T, x, y, &bld);
    if (!(c->fixed > 0.0)) {
        static const double up[3] = { 0.0, 0.0, 1.0 };
        icache_lookup(c, ps, L, P, up, rgb);
        return P[2];
    }
    check_stamp(c, ps);
    plane_up(P, P[2], bld, &pl);
    level_or_finer(c, ps, L, &pl, P, fixed_level(c), rgb, NULL);
    return P[2];
}

/* icache_lookup, or with pk its peek (nothing changed but the worker's
 * last cells). */
static void lookup(icache *c, photon_sys *ps, light *L, const double P[3], const double n[3], double rgb[3],
                   peek_state *pk)
{
    double dx = P[0] - c->eye[0], dy = P[1] - c->eye[1], dz = P[2] - c->eye[2], lf, t, r1[3];
    plane pl;
    int l0, k;
    if (pk) {
        if (photon_stamp(ps) != c->stamp) {
            pk->miss = 1;
            return;
        }
    } else
        check_stamp(c, ps);
    if (!plane_of(ps->T, ps->s, P, n, &pl)) {
        photon_indirect_rgb(ps, P, n, rgb);
        return;
    }
    if (c->fixed > 0.0) {
        level_or_finer(c, ps, L, &pl, P, fixed_level(c), rgb, pk);
        return;
    }
    lf = log2(fmax(c->kappa * sqrt(dx * dx + dy * dy + dz * dz), fmax(c->smin, ICACHE_S0)) / ICACHE_S0);
    if (!(lf < ICACHE_LEVEL_MAX + 1.0)) {
        photon_indirect_rgb(ps, P, n, rgb); /* far: the photon buffers */
        return;
    }
    l0 = (int)floor(lf);
    t = lf - l0;
    level_or_finer(c, ps, L, &pl, P, l0, rgb, pk);
    if (t > 0.0 && !(pk && pk->miss)) {
        if (l0 < ICACHE_LEVEL_MAX)
            level_or_finer(c, ps, L, &pl, P, l0 + 1, r1, pk);
        else
            photon_indirect_rgb(ps, P, n, r1);
        for (k = 0; k < 3; k++)
            rgb[k] = (1.0 - t) * rgb[k] + t * r1[k];
    }
}

void icache_lookup(icache *c, photon_sys *ps, light *L, const double P[3], const double n[3],
                   double rgb[3])
{
    lookup(c, ps, L, P, n, rgb, NULL);
}

int icache_peek(icache *c, photon_sys *ps, int worker, const double P[3], const double n[3], double rgb[3])
{
    peek_state pk;
    if (worker < 0 || worker >= ICACHE_PEEK_WORKERS)
        return 0;
    pk.miss = 0;
    pk.last = c->peek_last[worker];
    lookup(c, ps, NULL, P, n, rgb, &pk);
    return !pk.miss;
}
