/* trapmap: the trapezoidal map of the wall pieces and its search DAG, by
 * randomized incremental insertion (see below). */
#include "polar/polar_int.h"

/* ---- the search DAG ---------------------------------------------------- */

/* The trapezoidal map of the wall pieces built by randomized incremental
 * insertion (de Berg et al., ch. 6): every piece is located by its
 * frame-left end in the DAG built so far (a left end shared with an
 * earlier piece goes right at that point's x node, and at a y node of a
 * piece sharing it the other ends decide, i.e. the slopes), followed
 * through the trapezoids it crosses, and those are replaced by the pieces
 * left, right, above and below it (runs of pieces above or below whose
 * separating axis the new piece cuts away are merged, so one leaf may have
 * several parents). The order is random from a fixed seed (see
 * insertion_order), so the build is deterministic while the expected bounds
 * hold: O(n) nodes, O(log n) nodes on a search path, O(n log n) time. A
 * piece with an end already in the map (about two thirds: polygon edges
 * share their ends) is not searched in the DAG: the trapezoid holding its
 * start is found among the few around that end (walk_at: the map's live
 * trapezoids are kept by role, per point and per piece end, updated by
 * every insertion; a walk longer than WALK_MAX falls back to the DAG from
 * that end's x node), the others are searched from the root.
 * Measured (bench_polar): 4.4 to 4.9 inner nodes per piece (8 or 12
 * bytes each, see polar_map), search paths of about 2 log2 n nodes on
 * average. It runs first, on pieces not yet checked: a walk only moves to
 * a live neighbour sharing the axis it crosses (so it moves strictly
 * along the frame order and ends), every index stays in range, and a
 * failure is PLX_E_SCENE; the sweep then checks the result. Point indices
 * are canonical (the first of the points sharing a position, as the
 * sweep's events are). In the end every leaf becomes a child word, set by
 * the sweep when it opens that trapezoid as a gap: its free region, or the
 * owner that polar_locate reports inside a solid one. */

static uint32_t bits_for(uint64_t n);

/* Build node n: its chunk, *off where it starts there: the bit of its
 * first field (packed), or of its first 32-bit word (three words). */
static inline uint64_t *nchunk_of(const dbuild *b, uint32_t n, uint64_t *off, int packed)
{
    *off = (uint64_t)(n & (NODE_CHUNK - 1)) * (packed ? b->stride : 3);
    return b->chunk[n >> NODE_BITS];
}

/* The test of a packed node (its first field) as kind << 30 | index. */
static inline uint32_t unpack_test(const dbuild *b, uint32_t v)
{
    return PACK(v >> (b->tb - 2), v & ((1u << (b->tb - 2)) - 1));
}

/* The test of the node at off in chunk w, as kind << 30 | index. */
static inline uint32_t ntest(const dbuild *b, const uint64_t *w, uint64_t off, int packed)
{
    uint32_t v;
    if (!packed)
        return ((const uint32_t *)(const void *)w)[off];
    v = (uint32_t)field_get(w, off, b->tb);
    return unpack_test(b, v);
}

/* Its child k (0, 1). */
static inline uint32_t nchild(const dbuild *b, const uint64_t *w, uint64_t off, int k,
                              int packed)
{
    if (!packed)
        return ((const uint32_t *)(const void *)w)[off + 1 + (k ? 1 : 0)];
    return (uint32_t)field_get(w, off + b->tb + (k ? b->cb : 0), b->cb);
}

/* Build node n: its test (kind << 30 | index) and children. */
static inline void nread(const dbuild *b, uint32_t n, uint32_t *t, uint32_t c[2])
{
    uint64_t off, v;
    const uint64_t *w = nchunk_of(b, n, &off, b->packed);
    if (!b->packed) {
        const uint32_t *nd = (const uint32_t *)(const void *)w + off;
        *t = nd[0];
        c[0] = nd[1];
        c[1] = nd[2];
        return;
    }
    v = field_get(w, off, b->tb + b->cb);
    *t = unpack_test(b, (uint32_t)v & ((1u << b->tb) - 1));
    c[0] = (uint32_t)(v >> b->tb);
    c[1] = (uint32_t)field_get(w, off + b->tb + b->cb, b->cb);
}

/* Packed build node n becomes test t, children c0, c1 (see nset). */
static void nset_packed(const dbuild *b, uint32_t n, uint32_t t, uint32_t c0, uint32_t c1)
{
    uint64_t off;
    uint64_t *w = nchunk_of(b, n, &off, 1);
    /* the test and the first child in one field (tb + cb < 64) */
    field_set(w, off, b->tb + b->cb, (uint64_t)(KIND(t) << (b->tb - 2) | IDX(t)) | (uint64_t)c0 << b->tb);
    field_set(w, off + b->tb + b->cb, b->cb, c1);
}

/* Build node n becomes test t (kind << 30 | index), children c0, c1. */
static inline void nset(const dbuild *b, uint32_t n, uint32_t t, uint32_t c0, uint32_t c1)
{
    uint64_t off;
    uint32_t *nd;
    if (b->packed) {
        nset_packed(b, n, t, c0, c1);
        return;
    }
    nd = (uint32_t *)(void *)nchunk_of(b, n, &off, 0) + off;
    nd[0] = t;
    nd[1] = c0;
    nd[2] = c1;
}

static vec2 bpt(const dbuild *b, uint32_t i)
{
    return fpt(b->pd, b->frame, i);
}

/* Slots are allocated TRAP_STEP at a time from the low end of the arena,
 * where nothing else is allocated while the map is built, so they stay one
 * array; b->cap bounds them (see polar_dag_build). */
#define TRAP_STEP 2048u

static int grow_packed_traps(dbuild *b, uint32_t step)
{
    /* 2,048 slots are whole words; the first step has a word more */
    size_t words = ((size_t)step * b->sw + 63) / 64 + (b->TW ? 0 : 1);
    uint64_t *p = arena_alloc(b->a, PLX_PART_POLAR, words * 8, 8);
    if (!p)
        return 0;
    memset(p, 0, words * 8);
    if (!b->TW)
        b->TW = p;
    else if (p != b->TW + (size_t)b->tcap * b->sw / 64 + 1)
        return 0;             /* not contiguous: cannot happen */
    b->tcap += step;
    return 1;
}

static int grow_traps(dbuild *b)
{
    uint32_t step = b->cap - b->tcap < TRAP_STEP ? b->cap - b->tcap : TRAP_STEP;
    btrap *p;
    if (step == 0)
        return 0;
    if (b->tpk)
        return grow_packed_traps(b, step);
    p = arena_alloc(b->a, PLX_PART_POLAR, (size_t)step * sizeof(btrap), 16);
    if (!p)
        return 0;
    if (!b->T)
        b->T = p;
    else if (p != b->T + b->tcap)
        return 0;             /* not contiguous: cannot happen (see above) */
    b->tcap += step;
    return 1;
}

static uint32_t new_node(dbuild *b, uint32_t kind, uint32_t idx, uint32_t c0, uint32_t c1)
{
    uint32_t n = b->nnode;
    if (n == b->nchunk * NODE_CHUNK) {
        if (b->nchunk == b->maxchunk ||
            !(b->chunk[b->nchunk] = arena_scratch(b->a, b->cwords * 8, 16))) {
            b->fail = 1;
            return 0;
        }
        if (b->packed)
            memset(b->chunk[b->nchunk], 0, b->cwords * 8);
        b->nchunk++;
    }
    b->nnode++;
    nset(b, n, PACK(kind, idx), c0, c1);
    return n;
}

/* The y test of piece s: its kind by which end is frame-left. */
static inline uint32_t ykind(const dbuild *b, uint32_t s)
{
    const polar_seg *g = &b->pd->seg[s];
    return lex_cmp(bpt(b, g->a), bpt(b, g->b)) < 0 ? N_Y : N_YB;
}

/* One insertion, its data gathered beforehand (in insertion order). */
typedef struct irec {
    vec2 P, Q;               /* frame ends, left first */
    uint32_t s, l, r;        /* the piece, its canonical end points */
} irec;

/* Descends the DAG with end A of a new piece AD from node n to a leaf's
 * trapezoid: x tests send A left when before the point (or at it, with
 * ties_left), y tests by A's side of the piece or, when A is on its line
 * (a shared end), by D's (the slopes). packed: b->packed, a constant in
 * each of the two copies the compiler makes (the hot loop of the
 * insertion). */
static inline uint32_t descend(dbuild *b, uint32_t n, vec2 A, vec2 D, int ties_left, int packed)
{
    for (;; b->steps++) {
        uint64_t off, v = 0;
        const uint64_t *cw = nchunk_of(b, n, &off, packed);
        uint32_t w;
        int right;
        if (packed) {
            v = field_get(cw, off, b->tb + b->cb);   /* the test and child 0 */
            w = unpack_test(b, (uint32_t)v & ((1u << b->tb) - 1));
        } else {
            w = ntest(b, cw, off, 0);
        }
        if (KIND(w) == N_LEAF)
            return IDX(w);
        if (KIND(w) == N_X) {
            int c = lex_cmp(A, bpt(b, IDX(w)));
            right = !(c < 0 || (ties_left && c == 0));
        } else {
            vec2 g0 = pend(b->pd, b->frame, b->SR, IDX(w), 0);
            vec2 g1 = pend(b->pd, b->frame, b->SR, IDX(w), 1);
            int o = geom_orient(g0, g1, A);
            if (o == 0)
                o = geom_orient(g0, g1, D);
            if (o == 0) {
                b->fail = 2;
                return POLAR_NONE;
            }
            right = o > 0;
        }
        n = packed && !right ? (uint32_t)(v >> b->tb) : nchild(b, cw, off, right, packed);
    }
}

/* Descends the DAG with the left end P of a new piece PQ, from node n:
 * the root, or the x node of P if P is already in the map (its cell, the
 * trapezoid that held P when it came in, holds everything just right of P). */
static uint32_t find_first(dbuild *b, uint32_t n, vec2 P, vec2 Q)
{
    return b->packed ? descend(b, n, P, Q, 0, 1) : descend(b, n, P, Q, 0, 0);
}

/* The same from the right end Q of the new piece, known to the map: from
 * its x node, with Q pushed towards P (ties at Q go left). */
static uint32_t find_last(dbuild *b, uint32_t n, vec2 Q, vec2 P)
{
    return b->packed ? descend(b, n, Q, P, 1, 1) : descend(b, n, Q, P, 1, 0);
}

/* Asks the cache for what insertion i + 8 will read first (its ends'
 * roles and hints; the piece's own data was asked for 8 insertions
 * before). A hint only; nothing where the compiler offers no prefetch. */
static inline void prefetch_ahead(const dbuild *b, uint32_t i, uint32_t nw)
{
#if defined(__GNUC__)
    if (i + 16 < nw) {
        uint32_t s = b->order[i + 16];
        __builtin_prefetch(&b->SR[s]);
    }
    if (i + 8 < nw) {
        const sroles *r = &b->SR[b->order[i + 8]];
        __builtin_prefetch(&b->PR[r->end[0]]);
        __builtin_prefetch(&b->PR[r->end[1]]);
        __builtin_prefetch(&b->hint[r->end[0]]);
        __builtin_prefetch(&b->pd->pts[r->end[0]]);
        __builtin_prefetch(&b->pd->pts[r->end[1]]);
    }
#else
    (void)b;
    (void)i;
    (void)nw;
#endif
}

/* The insertion's slot work (trapins.h), once for each slot layout. */
#define WALK_MAX 12
enum { F_lp = F_LP, F_rp = F_RP, F_top = F_TOP, F_bot = F_BOT, F_leaf = F_LEAF };
#define SLOTFN(name) name##_w
#define TG(b, t, f) ((b)->T[t].f)
#define TS(b, t, f, v) ((b)->T[t].f = (v))
#define TGN(b, t, k) ((b)->T[t].nb[k])
#define TSN(b, t, k, v) ((b)->T[t].nb[k] = (v))
#include "polar/trapins.h"
#undef SLOTFN
#undef TG
#undef TS
#undef TGN
#undef TSN
#define SLOTFN(name) name##_p
#define TG(b, t, f) tget_packed(b, t, F_##f)
#define TS(b, t, f, v) tset_packed(b, t, F_##f, v)
#define TGN(b, t, k) tget_packed(b, t, F_NB + (k))
#define TSN(b, t, k, v) tset_packed(b, t, F_NB + (k), v)
#include "polar/trapins.h"
#undef SLOTFN
#undef TG
#undef TS
#undef TGN
#undef TSN

static uint64_t rng_step(uint64_t *st)
{
    uint64_t x = *st;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *st = x;
    return x;
}

/* Child word c (tag << 30 | index) in the narrow form, tag << 19 | index. */
static uint64_t narrow_child(uint32_t c)
{
    return (uint64_t)(POLAR_TAG(c) << 19 | POLAR_IDX(c));
}

/* Stores inner node j of m: test t, children c0, c1 (32-bit forms). */
static inline void put_node(polar_map *m, uint32_t j, uint32_t t, uint32_t c0, uint32_t c1)
{
    if (m->narrow) {
        uint64_t x = (uint64_t)(KIND(t) << 20 | IDX(t)) | narrow_child(c0) << 22 |
                     narrow_child(c1) << 43;
        m->node[2 * (size_t)j] = (uint32_t)x;
        m->node[2 * (size_t)j + 1] = (uint32_t)(x >> 32);
    } else {
        uint64_t *pw = (uint64_t *)(void *)m->node;
        uint32_t tb = m->pack & 0xffu, cb = m->pack >> 8, c[2], i;
        uint64_t off = (uint64_t)j * (tb + 2 * cb);
        c[0] = c0;
        c[1] = c1;
        bits_put(pw, off, tb, KIND(t) << (tb - 2) | IDX(t));
        off += tb;
        for (i = 0; i < 2; i++, off += cb) {
            uint32_t tag = POLAR_TAG(c[i]);
            bits_put(pw, off, cb,
                     POLAR_IDX(c[i]) + (tag == POLAR_CHILD_NODE ? 0
                                        : tag == POLAR_CHILD_FREE ? m->nnode
                                                                  : m->nnode + m->ntrap));
        }
    }
}

/* Bits needed for the numbers below n. */
static uint32_t bits_for(uint64_t n)
{
    uint32_t b = 1;
    while (b < 32 && ((uint64_t)1 << b) < n)
        b++;
    return b;
}

/* The packed form's field widths (see polar_map) and its words, zeroed. */
static plx_status packed_nodes(arena *a, polar *pd, polar_map *m)
{
    size_t nw;
    uint32_t tb = 2 + bits_for(pd->npts > pd->nseg ? pd->npts : pd->nseg);
    uint32_t cb = bits_for((uint64_t)m->nnode + m->ntrap + pd->nbld + 1);
    m->pack = tb | cb << 8;
    /* one word more: a field may be read from two words */
    nw = (size_t)(((uint64_t)m->nnode * (tb + 2 * cb) + 63) / 64) + 1;
    m->node = keep_n(a, nw, 8, &pd->bytes[3]);
    if (!m->node)
        return PLX_E_NOMEM;
    memset(m->node, 0, nw * 8);
    return PLX_OK;
}

/* Leaves to child words (set by the sweep in the trapezoids' leaf field,
 * copied here into the leaf nodes' second word; the slots are read here
 * for the last time), and the inner nodes' ranks: a bit per build node
 * (inner) and the inner nodes before every 64 (rk: 12 bytes per 64
 * nodes of scratch). */
plx_status polar_dag_words(arena *a, dbuild *b, dag_rank *rk)
{
    uint32_t i, nw64 = (b->nnode + 63) / 64, nq = 0;
    rk->bits = scratch_n(a, nw64, 8);
    rk->before = scratch_n(a, nw64, 4);
    if (!rk->bits || !rk->before)
        return PLX_E_NOMEM;
    memset(rk->bits, 0, (size_t)nw64 * 8);
    for (i = 0; i < b->nnode; i++) {
        uint64_t off;
        uint64_t *cw = nchunk_of(b, i, &off, b->packed);
        uint32_t t = ntest(b, cw, off, b->packed), c;
        if ((i & 63) == 0)
            rk->before[i >> 6] = nq;
        if (KIND(t) != N_LEAF) {
            rk->bits[i >> 6] |= (uint64_t)1 << (i & 63);
            nq++;
            continue;
        }
        /* a leaf: its child word's tag and index as its children */
        c = tget(b, IDX(t), F_LEAF);
        if (POLAR_TAG(c) == POLAR_CHILD_NODE || (uint64_t)POLAR_IDX(c) >> b->cb)
            return PLX_E_SCENE;
        if (b->packed)
            field_set(cw, off + b->tb, 2 * b->cb,
                      POLAR_TAG(c) | (uint64_t)POLAR_IDX(c) << b->cb);
        else
            nset(b, i, t, POLAR_TAG(c), POLAR_IDX(c));
    }
    rk->nq = nq;
    return PLX_OK;
}

static uint32_t popcount64(uint64_t x)
{
    x = x - ((x >> 1) & 0x5555555555555555ull);
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return (uint32_t)((x * 0x0101010101010101ull) >> 56);
}

/* The child word of build node c: the inner node's index among the kept
 * ones (from the bitmap alone), or its leaf's word. */
static uint32_t child_word(const dbuild *b, const dag_rank *rk, uint32_t c)
{
    uint64_t w = rk->bits[c >> 6], below = ((uint64_t)1 << (c & 63)) - 1;
    if (w >> (c & 63) & 1)
        return PACK(POLAR_CHILD_NODE, rk->before[c >> 6] + popcount64(w & below));
    {
        uint32_t t, k[2];
        nread(b, c, &t, k);
        return PACK(k[0], k[1]);
    }
}

/* The packed build's DAG before the sweep (the late order of
 * polar_map_build): the leaves dropped and the inner nodes moved down to
 * their ranks in place, their children renamed first (an inner node by
 * its rank, a leaf by nq + its slot, nq the inner nodes; the leaves are
 * read, not written); then the chunks past the last inner node and the
 * rank bitmap are given back, and b->nnode is nq (b->compact). Nothing is
 * done when the nodes are not packed, the root is a leaf or a child field
 * could not hold nq + a slot + a solid word. */
plx_status polar_dag_compact(arena *a, dbuild *b)
{
    arena_mark mk = arena_get_mark(a), r;
    uint32_t i, j, k, nq = 0, nw64 = (b->nnode + 63) / 64, keep, *before;
    uint64_t *bits, off;
    if (!b->packed || b->nnode == 0)
        return PLX_OK;
    bits = scratch_n(a, nw64, 8);
    before = scratch_n(a, nw64, 4);
    if (!bits || !before)
        return PLX_E_NOMEM;
    memset(bits, 0, (size_t)nw64 * 8);
    for (i = 0; i < b->nnode; i++) {
        const uint64_t *cw = nchunk_of(b, i, &off, 1);
        if ((i & 63) == 0)
            before[i >> 6] = nq;
        if (KIND(ntest(b, cw, off, 1)) != N_LEAF) {
            bits[i >> 6] |= (uint64_t)1 << (i & 63);
            nq++;
        }
    }
    if (!(bits[0] & 1) || (uint64_t)nq + b->cap + b->pd->nbld + 1 > ((uint64_t)1 << b->cb)) {
        arena_release(a, &mk);
        return PLX_OK;
    }
    for (i = 0; i < b->nnode; i++) {
        uint64_t *cw;
        if (!(bits[i >> 6] >> (i & 63) & 1))
            continue;
        cw = nchunk_of(b, i, &off, 1);
        for (k = 0; k < 2; k++) {
            uint64_t at = off + b->tb + (k ? b->cb : 0), w, coff;
            uint32_t c = (uint32_t)field_get(cw, at, b->cb), v;
            w = bits[c >> 6];
            if (w >> (c & 63) & 1) {
                v = before[c >> 6] + popcount64(w & (((uint64_t)1 << (c & 63)) - 1));
            } else {
                const uint64_t *lw = nchunk_of(b, c, &coff, 1);
                v = nq + IDX(ntest(b, lw, coff, 1));
            }
            field_set(cw, at, b->cb, v);
        }
    }
    for (i = 0, j = 0; i < b->nnode; i++) {
        if (!(bits[i >> 6] >> (i & 63) & 1))
            continue;
        if (j != i) {
            uint64_t ioff, joff, x, y;
            const uint64_t *src = nchunk_of(b, i, &ioff, 1);
            uint64_t *dst;
            x = field_get(src, ioff, b->tb + b->cb);
            y = field_get(src, ioff + b->tb + b->cb, b->cb);
            dst = nchunk_of(b, j, &joff, 1);
            field_set(dst, joff, b->tb + b->cb, x);
            field_set(dst, joff + b->tb + b->cb, b->cb, y);
        }
        j++;
    }
    /* the chunks are the last scratch before the bitmap: everything past
     * chunk keep - 1 goes */
    keep = (nq + NODE_CHUNK - 1) >> NODE_BITS;
    r = arena_get_mark(a);
    r.hi = a->cap - (size_t)((unsigned char *)(void *)b->chunk[keep - 1] - a->base);
    r.used[PLX_PART_SCRATCH] -= a->hi - r.hi;
    arena_release(a, &r);
    b->nchunk = keep;
    b->nnode = nq;
    b->compact = 1;
    return PLX_OK;
}

/* The compacted DAG's leaf children (nq + a slot) made the child words the
 * sweep set in the slots: nq + a free region, or nq + nreg + a solid
 * trapezoid's owner plus one (read before the slots become the regions). */
plx_status polar_dag_resolve(dbuild *b, uint32_t nreg)
{
    uint32_t j, k, nq = b->nnode;
    for (j = 0; j < nq; j++) {
        uint64_t off;
        uint64_t *cw = nchunk_of(b, j, &off, 1);
        for (k = 0; k < 2; k++) {
            uint64_t at = off + b->tb + (k ? b->cb : 0);
            uint32_t v = (uint32_t)field_get(cw, at, b->cb), c;
            if (v < nq)
                continue;
            if (v - nq >= b->ntrap)
                return PLX_E_SCENE;
            c = tget(b, v - nq, F_LEAF);
            if (POLAR_TAG(c) == POLAR_CHILD_NODE ||
                (POLAR_TAG(c) == POLAR_CHILD_FREE && POLAR_IDX(c) >= nreg))
                return PLX_E_SCENE;
            field_set(cw, at, b->cb,
                      nq + POLAR_IDX(c) + (POLAR_TAG(c) == POLAR_CHILD_FREE ? 0 : nreg));
        }
    }
    return PLX_OK;
}

/* Record i of the regions being kept: a packed slot (b->tpk: read as a
 * region, its leaf field left alone), else a polar_trap of R. */
static inline void rec_get(const dbuild *b, const polar_trap *R, uint32_t i, polar_trap *r)
{
    int k;
    if (!b->TW) {
        *r = R[i];
        return;
    }
    r->lp = tget(b, i, F_LP);
    r->rp = tget(b, i, F_RP);
    r->top = tget(b, i, F_TOP);
    r->bot = tget(b, i, F_BOT);
    for (k = 0; k < 4; k++)
        r->nb[k] = tget(b, i, F_NB + k);
}

static inline void rec_put(const dbuild *b, polar_trap *R, uint32_t i, const polar_trap *r)
{
    int k;
    if (!b->TW) {
        R[i] = *r;
        return;
    }
    tset(b, i, F_LP, r->lp);
    tset(b, i, F_RP, r->rp);
    tset(b, i, F_TOP, r->top);
    tset(b, i, F_BOT, r->bot);
    for (k = 0; k < 4; k++)
        tset(b, i, F_NB + k, r->nb[k]);
}

/* The regions kept where the trapezoid slots were (no copy: the slots
 * are the last thing in the low end of the arena): every slot cut to its
 * first 32 bytes, which are a polar_trap (packed slots: left as they
 * are), then region h moved from slot regd[h] to place h, following
 * chains of moves (a place is written only once the slot there has been
 * moved; regd is one-to-one); packed slots are then widened to
 * polar_traps from the last down (record h ends at or before byte 32 h:
 * a slot has at most 256 bits), the low end grown first where the
 * regions need more than the slots had. The rest is given back. The low
 * end is then as if the regions had been allocated after the slots were
 * given back, as keep_n would. Marks on regd: bit 31. */
#define MOVED 0x80000000u
plx_status polar_keep_regions(arena *a, polar *pd, polar_map *m, dbuild *b, uint32_t *regd,
                              uint32_t nreg)
{
    polar_trap *R = b->tpk ? (polar_trap *)(void *)b->TW : (polar_trap *)(void *)b->T;
    uint32_t i, h, nw64 = (b->ntrap + 63) / 64;
    uint64_t *needed = scratch_n(a, nw64, 8);
    arena_mark mk;
    size_t end;
    if (!needed)
        return PLX_E_NOMEM;
    PLX_ASSERT(sizeof(polar_trap) == 32 && sizeof(btrap) == 36 && nreg <= b->ntrap);
    PLX_ASSERT(!b->tpk || b->sw <= 256);
    if (b->tpk) {
        size_t have = ((size_t)b->tcap * b->sw + 63) / 64 * 8 + 8, want = (size_t)nreg * 32;
        if (want > have) {
            unsigned char *p = arena_alloc(a, PLX_PART_POLAR, want - have, 8);
            if (!p || p != (unsigned char *)(void *)R + have)
                return PLX_E_NOMEM;
        }
    } else {
        for (i = 0; i < b->ntrap; i++)
            memmove(&R[i], &b->T[i], sizeof(polar_trap));
    }
    memset(needed, 0, (size_t)nw64 * 8);
    for (h = 0; h < nreg; h++)
        needed[regd[h] >> 6] |= (uint64_t)1 << (regd[h] & 63);
    /* chains that start at a place whose slot no region needs */
    for (h = 0; h < nreg; h++) {
        uint32_t cur = h;
        if (needed[h >> 6] >> (h & 63) & 1)
            continue;
        while (cur < nreg && !(regd[cur] & MOVED)) {
            uint32_t src = regd[cur];
            polar_trap r;
            rec_get(b, R, src, &r);
            rec_put(b, R, cur, &r);
            regd[cur] |= MOVED;
            cur = src;
        }
    }
    /* the rest are cycles */
    for (h = 0; h < nreg; h++) {
        polar_trap first, r;
        uint32_t cur = h;
        if (regd[h] & MOVED)
            continue;
        rec_get(b, R, h, &first);
        for (;;) {
            uint32_t src = regd[cur];
            regd[cur] |= MOVED;
            if (src == h) {
                rec_put(b, R, cur, &first);
                break;
            }
            rec_get(b, R, src, &r);
            rec_put(b, R, cur, &r);
            cur = src;
        }
    }
    if (b->tpk) {
        for (h = nreg; h-- > 0;) {
            polar_trap r;
            rec_get(b, R, h, &r);
            R[h] = r;
        }
    }
    /* the low end: the slots' mark plus the regions, as arena_alloc counts */
    end = (size_t)((unsigned char *)(R + nreg) - a->base);
    mk = arena_get_mark(a);
    mk.lo = end;
    mk.used[PLX_PART_POLAR] = b->tmark.used[PLX_PART_POLAR] + (end - b->tmark.lo);
    arena_release(a, &mk);
    pd->bytes[0] += (size_t)nreg * sizeof(polar_trap);
    m->trap = R;
    m->ntrap = nreg;
    b->T = NULL;
    b->TW = NULL;
    return PLX_OK;
}

/* The inner nodes kept in the order they were made (the top levels first;
 * with the insertion order, nodes made together lie together), their
 * children as child words (fw, polar_dag_words), narrow when every index
 * fits, and counted in polar_memory (rest). */
plx_status polar_dag_keep(arena *a, polar *pd, polar_map *m, dbuild *b, const dag_rank *rk,
                          int flags)
{
    uint32_t i, j, nq = b->compact ? b->nnode : rk->nq;
    m->nnode = nq;
    m->narrow = !(flags & POLAR_BUILD_WIDE_DAG) && nq < (1u << 19) && m->ntrap < (1u << 19) &&
                pd->nbld < (1u << 19) - 1 && pd->npts < (1u << 20) && pd->nseg < (1u << 20);
    if (m->narrow) {
        m->node = keep_n(a, nq, 8, &pd->bytes[3]);
        if (!m->node)
            return PLX_E_NOMEM;
    } else if (packed_nodes(a, pd, m) != PLX_OK) {
        return PLX_E_NOMEM;
    }
    if (b->compact) {
        /* children: an inner node, nq + a region, nq + ntrap + a solid word */
        for (j = 0; j < nq; j++) {
            uint32_t t, c[2], k;
            nread(b, j, &t, c);
            for (k = 0; k < 2; k++)
                c[k] = c[k] < nq               ? PACK(POLAR_CHILD_NODE, c[k])
                       : c[k] - nq < m->ntrap ? PACK(POLAR_CHILD_FREE, c[k] - nq)
                                              : PACK(POLAR_CHILD_SOLID, c[k] - nq - m->ntrap);
            put_node(m, j, t, c[0], c[1]);
        }
        m->root = PACK(POLAR_CHILD_NODE, 0);
        return PLX_OK;
    }
    for (i = 0, j = 0; i < b->nnode; i++) {
        uint32_t t, c[2];
        if (!(rk->bits[i >> 6] >> (i & 63) & 1))
            continue;             /* a leaf */
        nread(b, i, &t, c);
        put_node(m, j++, t, child_word(b, rk, c[0]), child_word(b, rk, c[1]));
    }
    m->root = child_word(b, rk, 0);
    return PLX_OK;
}

static uint32_t spread16(uint32_t x)
{
    x &= 0xffffu;
    x = (x | (x << 8)) & 0x00ff00ffu;
    x = (x | (x << 4)) & 0x0f0f0f0fu;
    x = (x | (x << 2)) & 0x33333333u;
    x = (x | (x << 1)) & 0x55555555u;
    return x;
}

/* The insertion order of the wall pieces, shared by both maps: a biased
 * randomized insertion order (Amenta, Choi, Rote 2003). Every piece draws
 * a round from a seeded generator (the last round holds about half of
 * them, the one before a quarter, ...); rounds go in order and, within a
 * round, pieces follow a Z-order curve of their midpoints. The rounds are
 * random samples, which keeps the expected bounds of randomized
 * incremental construction (size, search path length); the spatial order
 * within a round makes consecutive insertions walk the same nodes (cache
 * hits). Sorted by a stable radix sort on 64-bit keys (ties: piece
 * order). Deterministic: no global state. */
#define RADIX_BITS 11
#define RADIX (1u << RADIX_BITS)
plx_status polar_insertion_order(arena *a, const polar *pd, uint32_t **out)
{
    uint32_t i, n = pd->nwall, d, *out0 = scratch_n(a, n, 4), *order, *o2;
    arena_mark mk = arena_get_mark(a);  /* the sort's own scratch is given back */
    uint64_t *key, *k2;
    uint32_t *cnt;
    uint64_t seed = 0x9e3779b97f4a7c15ull;
    double sx = 65535.0 / (pd->box[2] - pd->box[0]), sy = 65535.0 / (pd->box[3] - pd->box[1]);
    order = scratch_n(a, n, 4);
    o2 = scratch_n(a, n, 4);
    key = scratch_n(a, n, 8);
    k2 = scratch_n(a, n, 8);
    cnt = scratch_n(a, RADIX, 4);
    if (!out0 || !order || !o2 || !key || !k2 || !cnt)
        return PLX_E_NOMEM;
    for (i = 0; i < n; i++) {
        const polar_seg *g = &pd->seg[i];
        vec2 pa = pd->pts[g->a], pb = pd->pts[g->b];
        uint64_t r = rng_step(&seed) >> 20;
        uint32_t round = 0, ux, uy;
        double mx = 0.5 * (pa.x + pb.x) - pd->box[0], my = 0.5 * (pa.y + pb.y) - pd->box[1];
        while (round < 40 && (r & 1u)) {   /* round 40 - t with probability 2^-(t+1) */
            round++;
            r >>= 1;
        }
        ux = (uint32_t)fmin(fmax(mx * sx, 0.0), 65535.0);
        uy = (uint32_t)fmin(fmax(my * sy, 0.0), 65535.0);
        /* round (6 bits), then the Z-order of the midpoint (32) */
        key[i] = (uint64_t)(40 - round) << 32 | (uint64_t)(spread16(ux) | (spread16(uy) << 1));
        order[i] = i;
    }
    for (d = 0; d < 44; d += RADIX_BITS) {  /* LSD radix sort: 4 passes of 11 bits */
        memset(cnt, 0, RADIX * 4);
        for (i = 0; i < n; i++)
            cnt[(key[i] >> d) & (RADIX - 1)]++;
        {
            uint32_t sum = 0, c;
            for (i = 0; i < RADIX; i++) {
                c = cnt[i];
                cnt[i] = sum;
                sum += c;
            }
        }
        for (i = 0; i < n; i++) {
            uint32_t at = cnt[(key[i] >> d) & (RADIX - 1)]++;
            k2[at] = key[i];
            o2[at] = order[i];
        }
        {
            uint64_t *tk = key;
            uint32_t *to = order;
            key = k2;
            k2 = tk;
            order = o2;
            o2 = to;
        }
    }
    memcpy(out0, order, (size_t)n * 4);
    arena_release(a, &mk);
    *out = out0;
    return PLX_OK;
}

/* Builds the trapezoidal map of the wall pieces of m and its search DAG by
 * randomized incremental insertion, into b (scratch, the trapezoid slots
 * in the low end of the arena). SR: the pieces' canonical ends (pend),
 * the rest of it unset. The nodes are packed in bits with
 * POLAR_BUILD_PACKED (a large scene in a tight block, PACKED_NODES_FROM)
 * or POLAR_BUILD_WIDE_DAG in flags. */
plx_status polar_dag_build(arena *a, polar *pd, polar_map *m, dbuild *b,
                           sroles *SR, const uint32_t *order, uint32_t span, int flags)
{
    uint32_t nw = pd->nwall;
    if (nw >= (1u << 26) || pd->npts >= (1u << 26))
        return PLX_E_NOMEM;   /* indices must fit in 30 bits */
    memset(b, 0, sizeof *b);
    b->pd = pd;
    b->a = a;
    b->frame = m->frame;
    b->SR = SR;
    b->order = order;
    /* trapezoid slots: at most 3 i + 1 live after i pieces; a new piece
     * crosses one trapezoid more than the axes it cuts (at most span - 1,
     * one per event position strictly between its ends) and makes two per
     * crossed one plus two: 3 n + 2 span + 64 (the bound; slots are
     * allocated as they are used, about 2 a piece) */
    b->cap = 3 * nw + 2 * span + 64;
    /* expected about 8 nodes per piece; beyond 64 the shuffle has failed
     * beyond any reasonable chance (reported as out of memory) */
    b->maxchunk = (uint32_t)(((uint64_t)64 * nw + 1024) >> NODE_BITS) + 1;
    if (b->maxchunk > (1u << (30 - NODE_BITS)))
        b->maxchunk = 1u << (30 - NODE_BITS);
    /* node fields: a test's index (a point, a piece or, in a leaf, a slot)
     * and the children (a node, or in a leaf its child word's tag and
     * index: a region, below the slots, or an owner plus one) */
    {
        uint64_t most = pd->npts > pd->nseg ? pd->npts : pd->nseg;
        uint64_t kids = (uint64_t)b->maxchunk * NODE_CHUNK;
        if (most < b->cap)
            most = b->cap;
        if (kids < b->cap)
            kids = b->cap;
        if (kids < (uint64_t)pd->nbld + 1)
            kids = (uint64_t)pd->nbld + 1;
        b->tb = 2 + bits_for(most);
        b->cb = bits_for(kids);
        if (b->tb + b->cb > 63 || 2 * b->cb > 63)
            return PLX_E_NOMEM;   /* cannot happen: indices fit in 26 bits */
        b->packed = (flags & (POLAR_BUILD_PACKED | POLAR_BUILD_WIDE_DAG)) != 0;
        b->stride = b->packed ? b->tb + 2 * b->cb : 3;
        b->cwords = b->packed ? ((size_t)NODE_CHUNK * b->stride + 63) / 64 + 1
                              : (size_t)NODE_CHUNK * 3 / 2;
    }
    if (b->packed) {
        /* the slots packed too: points and pieces, links (all ones: none),
         * the leaf word (a node, or a child word's tag and index) */
        uint32_t f, off = 0, pb = bits_for(pd->npts > pd->nseg ? pd->npts : pd->nseg);
        uint32_t sb = bits_for((uint64_t)b->cap + 1);
        for (f = 0; f < 9; f++) {
            b->swid[f] = f < F_NB ? pb : f < F_LEAF ? sb : 2 + b->cb;
            b->soff[f] = off;
            off += b->swid[f];
        }
        b->sw = off;
        b->tpk = 1;
    }
    b->lcap = span + 8;
    b->list = scratch_n(a, b->lcap, 4);
    b->up = scratch_n(a, b->lcap, 4);
    b->lo = scratch_n(a, b->lcap, 4);
    b->chunk = scratch_n(a, b->maxchunk, sizeof *b->chunk);
    b->hint = scratch_n(a, pd->npts, 4);
    b->PR = scratch_n(a, pd->npts, sizeof(proles));
    if (!b->list || !b->up || !b->lo || !b->chunk || !b->hint || !b->PR)
        return PLX_E_NOMEM;
    memset(b->PR, 0xff, (size_t)pd->npts * sizeof(proles));
    memset(b->hint, 0xff, (size_t)pd->npts * 4);
    b->tmark = arena_get_mark(a);
    if (b->tpk)
        insert_all_p(b, m, nw);
    else
        insert_all_w(b, m, nw);
    if (b->fail)
        return b->fail == 1 ? PLX_E_NOMEM : PLX_E_SCENE;
    return PLX_OK;
}
