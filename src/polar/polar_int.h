/* polar_int.h: what the parts of the polar diagram construction share
 * (private to src/polar/; see polar.h for the diagrams themselves).
 *
 *   walls.c    the footprints cut at their contacts into wall pieces
 *   trapmap.c  the trapezoidal map and its search DAG (randomized insertion)
 *   sweep.c    the plane sweep that checks the map and makes the labelled
 *              free regions with their adjacency (build_map of one frame)
 *   locate.c   point location in the search DAG and ray shooting
 *   polar.c    the build of the four diagrams, frames, regions for drawing
 *
 * The small helpers are inline: they run in the hot loops of all of them.
 */
#ifndef PLX_POLAR_INT_H
#define PLX_POLAR_INT_H

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "polar/polar.h"
#include "base/msort.h"
#include "base/geom.h"
#include "base/plx_assert.h"

enum { UL = 0, LL = 1, UR = 2, LR = 3 };
/* search nodes: a leaf, a point (x) test, a segment (y) test whose frame-left
 * end is seg.a (N_Y) or seg.b (N_YB); the same kinds as POLAR_NODE_* */
enum { N_LEAF = 0, N_X = POLAR_NODE_X, N_Y = POLAR_NODE_Y, N_YB = POLAR_NODE_YB };
#define KIND(w) ((w) >> 30)
#define IDX(w) ((w) & 0x3fffffffu)
#define PACK(k, i) (((uint32_t)(k) << 30) | (uint32_t)(i))

/* ---- frames and small helpers ----------------------------------------- */

static inline vec2 to_frame(int frame, vec2 w)
{
    vec2 f;
    if (frame == 0) {
        f.x = w.y;
        f.y = -w.x;
    } else {
        f = w;
    }
    return f;
}

/* Point i in a frame (the inline twin of polar_fpt, for the hot loops). */
static inline vec2 fpt(const polar *pd, int frame, uint32_t i)
{
    vec2 w = pd->pts[i], f;
    if (frame == 0) {
        f.x = w.y;
        f.y = -w.x;
    } else {
        f = w;
    }
    return f;
}

static inline int lex_cmp(vec2 a, vec2 b)
{
    if (a.x < b.x)
        return -1;
    if (a.x > b.x)
        return 1;
    if (a.y < b.y)
        return -1;
    if (a.y > b.y)
        return 1;
    return 0;
}

/* Left and right end (frame order) of segment s. */
static inline void seg_ends(const polar *pd, int frame, uint32_t s, uint32_t *l, uint32_t *r)
{
    const polar_seg *g = &pd->seg[s];
    if (lex_cmp(fpt(pd, frame, g->a), fpt(pd, frame, g->b)) < 0) {
        *l = g->a;
        *r = g->b;
    } else {
        *l = g->b;
        *r = g->a;
    }
}

/* Footprints entered when crossing segment s upwards in the frame. */
static inline int32_t seg_delta(const polar *pd, int frame, uint32_t s)
{
    const polar_seg *g = &pd->seg[s];
    int fwd = lex_cmp(fpt(pd, frame, g->a), fpt(pd, frame, g->b)) < 0;
    return fwd ? g->cover : -g->cover;
}

/* n items of size bytes of arena scratch. */
static inline void *scratch_n(arena *a, size_t n, size_t size)
{
    size_t bytes = arena_mul(n ? n : 1, size);
    if (bytes == SIZE_MAX)
        return NULL;
    return arena_scratch(a, bytes, 16);
}

static inline void *keep_n(arena *a, size_t n, size_t size, size_t *acc)
{
    size_t bytes = arena_mul(n ? n : 1, size);
    void *p;
    if (bytes == SIZE_MAX)
        return NULL;
    p = arena_alloc(a, PLX_PART_POLAR, bytes, 16);
    if (p)
        *acc += bytes;
    return p;
}
/* The packed search nodes (polar_map): a field of 'width' bits (1 to 32)
 * at bit 'off' of w[], which may run on into the next word. */
static inline uint32_t bits_get(const uint64_t *w, uint64_t off, uint32_t width)
{
    size_t i = (size_t)(off >> 6);
    uint32_t sh = (uint32_t)(off & 63);
    uint64_t x = w[i] >> sh;
    if (sh + width > 64)
        x |= w[i + 1] << (64 - sh);
    return (uint32_t)(x & (((uint64_t)1 << width) - 1));
}

/* Sets such a field, all zero before. */
static inline void bits_put(uint64_t *w, uint64_t off, uint32_t width, uint32_t v)
{
    size_t i = (size_t)(off >> 6);
    uint32_t sh = (uint32_t)(off & 63);
    w[i] |= (uint64_t)v << sh;
    if (sh + width > 64)
        w[i + 1] |= (uint64_t)v >> (64 - sh);
}

static inline int32_t seg_owner(const polar *pd, uint32_t s)
{
    return pd->seg[s].bld[0] < 0 ? -1 : pd->seg[s].bld[0];
}


/* Which map and which side (1 = top, 0 = bottom) hold quadrant q's start wall. */
static inline void quadrant_side(int q, int *map, int *top)
{
    *map = q & 1;
    *top = (q == 1 || q == 2);
}


/* ---- shared by the search DAG (trapmap.c) and the sweep (sweep.c) ---- */

/* A trapezoid of the search DAG's map (see "the search DAG" below). 36
 * bytes: the frame coordinates of rp are read from the points. */
typedef struct btrap {
    uint32_t lp, rp, top, bot;
    uint32_t nb[4];          /* neighbours; in a free slot nb[0] links the
                              * next free slot */
    uint32_t leaf;           /* its leaf node (below 2^30); POLAR_NONE: slot
                              * free; once the map is built, the sweep
                              * replaces it by the trapezoid's child word
                              * (tag 1 or 2: set) */
} btrap;

/* The live trapezoids of the DAG's map by role (see walk_at), packed so
 * that one record serves a whole update. Per piece: its canonical ends
 * and the trapezoids above / below it at them; index 0: left end, 1:
 * right end. Per point: a trapezoid whose left (0) / right (1) axis is the
 * point's. POLAR_NONE: none yet. */
typedef struct sroles {
    uint32_t end[2], up[2], down[2];
} sroles;

typedef struct proles {
    uint32_t side[2];
} proles;

/* The frame end k (0: left, 1: right) of piece s: its canonical end point
 * SR[s].end[k], at the same position as the piece's own. */
static inline vec2 pend(const polar *pd, int frame, const sroles *SR, uint32_t s, int k)
{
    return fpt(pd, frame, SR[s].end[k]);
}

/* The sweep's data per piece (its frame ends are read through its
 * canonical ends, pend). */
typedef struct snode {
    int32_t cov;        /* footprints covering the gap above it */
    uint32_t open;      /* the slot of the free region open above it, or POLAR_NONE */
    uint32_t prev, next; /* status list; prev == POLAR_NONE: not in it */
} snode;

#define NODE_BITS 12
#define NODE_CHUNK (1u << NODE_BITS)
/* Search nodes are packed in bits while built (a quarter smaller, 15%
 * slower to build: README "Polar build scratch") in both maps beyond this
 * many pieces when the block has less than PACKED_NODES_ROOM bytes a
 * piece left for the maps (what they take with three-word nodes: the
 * first map kept, about 70 bytes a piece, and the second's build, about
 * 205: 8 nodes of 12 bytes, 2 slots of 36, the pieces' and points' roles
 * and sweep data; 275 on the 10^6-vertex ring); POLAR_BUILD_PACKED
 * (polar_map_build's flags) says so. That packed build also packs the
 * trapezoid slots, makes each map's incidence and the sweep's piece data
 * after the insertion, drops the DAG's leaves before the sweep and holds
 * the first map's regions in bits while the second is built (the ring in
 * 256 MiB). */
#define PACKED_NODES_FROM (1u << 17)
#define PACKED_NODES_ROOM 288u
enum { POLAR_BUILD_PACKED = 1 << 8 };

typedef struct dbuild {
    const polar *pd;
    arena *a;
    int frame;
    btrap *T;                /* slots, in the low end of the arena (grown
                              * TRAP_STEP at a time while the map is built,
                              * given back by polar_dag_free_traps) */
    uint32_t ntrap, tcap, cap; /* slots used, slots allocated, the bound */
    uint32_t freel, nfree;   /* the last freed slot (its nb[0] links the
                              * one freed before), free slots */
    arena_mark tmark;        /* the arena before the slots */
    uint64_t **chunk;        /* nodes in chunks of NODE_CHUNK (scratch):
                              * three 32-bit words (the test kind << 30 |
                              * index, two children), or (PACKED_NODES_FROM)
                              * packed in bits: the
                              * test as kind << (tb - 2) | index and the
                              * children in cb bits each */
    uint32_t nchunk, maxchunk, nnode;
    int packed;
    uint32_t tb, cb, stride; /* field widths; a node's bits (packed) or
                              * 32-bit words */
    size_t cwords;           /* 64-bit words of one chunk */
    uint32_t *list, *up, *lo; /* per crossed trapezoid: it, its new upper / lower part */
    uint32_t lcap;           /* their length: a piece crosses one trapezoid more than the
                              * axes it cuts, each at a distinct event position
                              * between its ends (the longest such run + 8) */
    const uint32_t *order;   /* the insertion order */
    /* the live trapezoids by role, kept up to date by every insertion */
    sroles *SR;
    proles *PR;
    vec2 P, Q;               /* the piece being inserted: its frame ends */
    uint32_t *hint;          /* per canonical point: its x node, POLAR_NONE */
    uint64_t *TW;            /* the slots packed in bits (tpk), TRAP_STEP
                              * at a time from the low end, as T */
    int tpk;                 /* 1: slots packed (the packed build): slot t
                              * at bit t sw, field f at soff[f], swid[f]
                              * bits, all ones for POLAR_NONE (a link or
                              * a leaf), a leaf word as tag << (swid - 2) |
                              * index */
    uint32_t sw, soff[9], swid[9];
    int fail;                /* 1: out of memory, 2: pieces not planar */
    int compact;             /* 1: the leaves dropped (polar_dag_compact):
                              * nnode inner nodes in rank order, a child
                              * below nnode an inner node, else nnode + a
                              * slot, then (polar_dag_resolve) nnode + a
                              * region or nnode + regions + solid word */
    uint64_t steps;          /* search nodes and trapezoids visited */
} dbuild;


/* A field of 1 to 63 bits at bit off of w[], read and written without a
 * branch (w has a word more after the last field; the offsets are the
 * data's, so a branch on them would be mispredicted often). */
static inline uint64_t field_get(const uint64_t *w, uint64_t off, uint32_t width)
{
    size_t i = (size_t)(off >> 6);
    uint32_t sh = (uint32_t)(off & 63);
    uint64_t x = (w[i] >> sh) | ((w[i + 1] << 1) << (63 - sh));
    return x & (((uint64_t)1 << width) - 1);
}

static inline void field_set(uint64_t *w, uint64_t off, uint32_t width, uint64_t v)
{
    size_t i = (size_t)(off >> 6);
    uint32_t sh = (uint32_t)(off & 63);
    uint64_t mask = ((uint64_t)1 << width) - 1;
    w[i] = (w[i] & ~(mask << sh)) | v << sh;
    w[i + 1] = (w[i + 1] & ~((mask >> 1) >> (63 - sh))) | ((v >> 1) >> (63 - sh));
}

/* The fields of a trapezoid slot, in btrap's order (nb[k] is F_NB + k). */
enum { F_LP = 0, F_RP = 1, F_TOP = 2, F_BOT = 3, F_NB = 4, F_LEAF = 8 };

/* Field f of packed slot t. */
static inline uint32_t tget_packed(const dbuild *b, uint32_t t, int f)
{
    uint32_t w = b->swid[f];
    uint64_t v = field_get(b->TW, (uint64_t)t * b->sw + b->soff[f], w);
    uint64_t ones = ((uint64_t)1 << w) - 1;
    if (f >= F_NB && v == ones)
        return POLAR_NONE;
    if (f == F_LEAF)
        return PACK(v >> (w - 2), v & (ones >> 2));
    return (uint32_t)v;
}

/* Packed slot t's field f becomes x. */
static inline void tset_packed(const dbuild *b, uint32_t t, int f, uint32_t x)
{
    uint32_t w = b->swid[f];
    uint64_t v = x;
    if (f >= F_NB && x == POLAR_NONE)
        v = ((uint64_t)1 << w) - 1;
    else if (f == F_LEAF)
        v = (uint64_t)KIND(x) << (w - 2) | IDX(x);
    field_set(b->TW, (uint64_t)t * b->sw + b->soff[f], w, v);
}

/* Field f of slot t, either layout (outside the insertion's hot loops,
 * which are compiled once for each: trapins.h). */
static inline uint32_t tget(const dbuild *b, uint32_t t, int f)
{
    if (b->tpk)
        return tget_packed(b, t, f);
    return ((const uint32_t *)(const void *)&b->T[t])[f];
}

/* Slot t's field f becomes x. */
static inline void tset(const dbuild *b, uint32_t t, int f, uint32_t x)
{
    if (b->tpk)
        tset_packed(b, t, f, x);
    else
        ((uint32_t *)(void *)&b->T[t])[f] = x;
}

/* walls.c: cuts the occluders' edges into wall pieces (pd->pts, pd->seg
 * filled, the Bounds box added). */
plx_status polar_make_walls(arena *a, polar *pd);

/* sweep.c: walls incident to each point and the sweep events; the map of
 * one frame (search DAG, sweep, regions kept). */
plx_status polar_incidence(arena *a, const polar *pd, uint32_t **inc_first, uint32_t **inc,
                           uint32_t *nev);
plx_status polar_map_build(arena *a, polar *pd, polar_map *m, const uint32_t *inc_first,
                           const uint32_t *inc, uint32_t nev,
                           const uint32_t *order, int flags, uint64_t *steps);

/* trapmap.c: the random insertion order; the map and DAG of one frame by
 * randomized insertion; the DAG kept with its leaves as child words. */
plx_status polar_insertion_order(arena *a, const polar *pd, uint32_t **out);
plx_status polar_dag_build(arena *a, polar *pd, polar_map *m, dbuild *b,
                           sroles *SR, const uint32_t *order, uint32_t span, int flags);
/* The inner nodes' ranks among the build nodes (see polar_dag_words). */
typedef struct dag_rank {
    uint64_t *bits;          /* bit i: build node i is inner */
    uint32_t *before;        /* inner nodes before node 64 k */
    uint32_t nq;             /* inner nodes */
} dag_rank;
plx_status polar_dag_words(arena *a, dbuild *b, dag_rank *rk);
plx_status polar_dag_compact(arena *a, dbuild *b);
plx_status polar_dag_resolve(dbuild *b, uint32_t nreg);
plx_status polar_keep_regions(arena *a, polar *pd, polar_map *m, dbuild *b, uint32_t *regd,
                              uint32_t nreg);
plx_status polar_dag_keep(arena *a, polar *pd, polar_map *m, dbuild *b, const dag_rank *rk,
                          int flags);

#endif
