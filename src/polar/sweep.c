/* sweep: the trapezoidal map of one frame checked and labelled by a plane
 * sweep over the wall ends (see below), which makes the free regions with
 * their adjacency; build_map of one frame (search DAG, then sweep). */
#include "polar/polar_int.h"

/* ---- trapezoidal map construction: a plane sweep ---------------------- */

/* The sweep runs over the wall ends in frame order (lexicographic (u, v),
 * i.e. a sweep line turned by an infinitesimal angle, so equal u needs no
 * special case). The status is the list of wall pieces crossing the sweep
 * line, bottom to top, headed by the Bounds side at the bottom; between two
 * consecutive pieces lies one open trapezoid, which the next event between
 * them closes with the axis of that event's point. An event where pieces
 * end finds its place in the list through them; an event where pieces only
 * start reads the piece below it from the DAG's map, already built: the
 * floor of the trapezoid below the lowest piece starting there, at its
 * left end, which is the status piece below the point (no piece ends
 * there); it is checked to be in the status and strictly below the point,
 * and the piece above to be strictly above it. Pieces starting together
 * are sorted by merge sort (O(d log d) at a point of degree d), so the
 * sweep is O(n log n) worst case. Every gap it opens is looked up in the
 * DAG's map the same way and must be a trapezoid there with the same left
 * axis, floor and ceiling (and right axis, for free regions), each once,
 * all of them. Only free trapezoids are made: whether the gap above a
 * piece is solid is known when the piece enters the status (footprints
 * counted from the bottom, as the piece below plus the piece's own change).
 * Every decision is a geom_orient sign or a lexicographic comparison. */

typedef struct fpoint {
    vec2 f;             /* frame coordinates */
    uint32_t i;         /* point index */
} fpoint;

typedef struct sweep {
    const polar *pd;
    polar_map *m;
    snode *N;           /* per segment (walls and Bounds sides) */
    uint32_t ntrap, cap; /* regions made, the most there can be */
    uint32_t nclosed;   /* regions closed */
    const uint32_t *inc_first, *inc; /* walls incident to each point */
    uint32_t *start, *tmp; /* scratch: pieces starting at the event */
    /* the final map of the search DAG: per piece the trapezoid below /
     * above it at its left end, per point one trapezoid with that left
     * axis; each gap the sweep opens is one of them, whose child word it
     * sets in its leaf field; a free one is a region, kept in the slot
     * (its adjacency in nb: the slot's own is not read again), the
     * status naming it by its slot (snode.open) */
    const dbuild *DT;        /* the map's slots (tget, tset) */
    btrap *T;                /* the same when not packed, else NULL */
    const sroles *SR;
    const proles *PR;
    uint32_t ngap;      /* gaps opened, free or solid */
    uint64_t steps;     /* status pieces walked and start pieces sorted */
} sweep;

/* A sorted event: its point index, EV_SAME when at the position of the one
 * before. */
#define EV_SAME 0x80000000u
#define EV_POINT 0x7fffffffu

/* The frame ends of piece s. */
#define EL(w, s) pend((w)->pd, (w)->m->frame, (w)->SR, (s), 0)
#define ER(w, s) pend((w)->pd, (w)->m->frame, (w)->SR, (s), 1)

static int fp_before(const fpoint *a, const fpoint *b, const void *ctx)
{
    (void)ctx;
    int c = lex_cmp(a->f, b->f);
    return c < 0 || (c == 0 && a->i < b->i);
}

MSORT_DEFINE(sort_fpoints, fpoint, const void *, fp_before)

/* The region index of the free trapezoid in slot d (or POLAR_NONE). */
static inline uint32_t regno(const sweep *w, uint32_t d)
{
    if (d == POLAR_NONE)
        return POLAR_NONE;
    return POLAR_IDX(w->T ? w->T[d].leaf : tget_packed(w->DT, d, F_LEAF));
}

/* Region h's link on side f becomes r (nothing when h is POLAR_NONE). */
static inline void set_link(sweep *w, uint32_t h, int f, uint32_t r)
{
    if (h == POLAR_NONE)
        return;
    if (w->T)
        w->T[h].nb[f] = r;
    else
        tset_packed(w->DT, h, F_NB + f, r);
}

/* The child word of a solid trapezoid above piece s: the owner
 * polar_locate reports inside it, the footprint entered across s, if any
 * (see locate in polar_scan), plus one. */
static inline uint32_t solid_word(const polar *pd, int frame, uint32_t s)
{
    const polar_seg *gs = &pd->seg[s];
    uint32_t l, r;
    int32_t own;
    seg_ends(pd, frame, s, &l, &r);
    own = (l == gs->a ? gs->cover : -gs->cover) > 0 && gs->bld[0] >= 0 ? gs->bld[0] : -1;
    return PACK(POLAR_CHILD_SOLID, (uint32_t)(own + 1));
}

/* The gap above bot opened at point pi (below top) is trapezoid d of the
 * DAG's map: checked, and its child word set: a new region when it is
 * free, *h = d (its slot), else solid, *h = POLAR_NONE. Returns 0, or -1
 * when the two maps differ. */
static int open_gap_packed(sweep *w, uint32_t d, uint32_t pi, uint32_t top, uint32_t bot,
                           int free, uint32_t *h)
{
    const dbuild *b = w->DT;
    int k;
    if (tget_packed(b, d, F_LP) != pi || tget_packed(b, d, F_TOP) != top ||
        tget_packed(b, d, F_BOT) != bot || POLAR_TAG(tget_packed(b, d, F_LEAF)) != 0)
        return -1;
    if (free) {
        if (w->ntrap >= w->cap)
            return -1;
        *h = d;
        for (k = 0; k < 4; k++)
            tset_packed(b, d, F_NB + k, POLAR_NONE);
        tset_packed(b, d, F_LEAF, PACK(POLAR_CHILD_FREE, w->ntrap++));
    } else {
        tset_packed(b, d, F_LEAF, solid_word(w->pd, w->m->frame, bot));
    }
    w->ngap++;
    return 0;
}

static int open_gap(sweep *w, uint32_t d, uint32_t pi, uint32_t top, uint32_t bot, int free,
                    uint32_t *h)
{
    btrap *t;
    *h = POLAR_NONE;
    if (d == POLAR_NONE)
        return -1;
    if (!w->T)
        return open_gap_packed(w, d, pi, top, bot, free, h);
    t = &w->T[d];
    if (t->lp != pi || t->top != top || t->bot != bot || POLAR_TAG(t->leaf) != 0)
        return -1;
    if (free) {
        if (w->ntrap >= w->cap)
            return -1;
        *h = d;
        t->nb[0] = t->nb[1] = t->nb[2] = t->nb[3] = POLAR_NONE;
        t->leaf = PACK(POLAR_CHILD_FREE, w->ntrap++);
    } else {
        t->leaf = solid_word(w->pd, w->m->frame, bot);
    }
    w->ngap++;
    return 0;
}

/* The region in slot h closed by the axis of point pi, which must be its
 * right axis in the DAG's map. Returns 0, or -1 when the two maps
 * differ. */
static inline int close_region(sweep *w, uint32_t h, uint32_t pi)
{
    if (h == POLAR_NONE)
        return 0;
    if ((w->T ? w->T[h].rp : tget_packed(w->DT, h, F_RP)) != pi)
        return -1;
    w->nclosed++;
    return 0;
}

/* Does piece y start below piece x (both starting at the same point)?
 * Sets *flat when they are collinear. */
static int start_below(const sweep *w, uint32_t y, uint32_t x, int *flat)
{
    int o = geom_orient(EL(w, y), ER(w, y), ER(w, x));
    if (o == 0)
        *flat = 1;
    return o > 0;
}

/* Sorts the n pieces w->start[] starting at one point bottom to top
 * (insertion sort for a few, else bottom-up merge sort: O(n log n) at a
 * point of any degree). Returns 0, or -1 when two are collinear (two
 * neighbours in the order are always compared, so it is seen). */
static int sort_starts(sweep *w, uint32_t n)
{
    uint32_t *src = w->start, *dst = w->tmp, i, j, wd;
    int flat = 0;
    for (i = 0; i < n; i += 8) {
        uint32_t e = i + 8 < n ? i + 8 : n;
        for (j = i + 1; j < e; j++) {
            uint32_t t = src[j], k = j;
            while (k > i && start_below(w, t, src[k - 1], &flat)) {
                src[k] = src[k - 1];
                k--;
            }
            src[k] = t;
        }
    }
    for (wd = 8; wd < n; wd *= 2) {
        for (i = 0; i < n; i += 2 * wd) {
            uint32_t a = i, am = i + wd < n ? i + wd : n, b = am, bm = i + 2 * wd < n ? i + 2 * wd : n;
            uint32_t o = i;
            while (a < am && b < bm)
                dst[o++] = start_below(w, src[b], src[a], &flat) ? src[b++] : src[a++];
            while (a < am)
                dst[o++] = src[a++];
            while (b < bm)
                dst[o++] = src[b++];
        }
        {
            uint32_t *t = src;
            src = dst;
            dst = t;
        }
    }
    if (src != w->start)
        memcpy(w->start, src, (size_t)n * 4);
    w->steps += n;
    return flat ? -1 : 0;
}

/* One event: the walls ending and starting at frame point P (point index
 * pi, the points pts[0..npts-1] all at P). Returns 0, or -1 when the walls
 * are not a planar subdivision (pieces crossing after rounding). */
static int sweep_event(sweep *w, vec2 P, uint32_t pi, const uint32_t *pts, uint32_t npts)
{
    snode *N = w->N;
    const polar_map *m = w->m;
    uint32_t x, y, B, A, last = POLAR_NONE, some_end = POLAR_NONE, k = 0, nend = 0, ns = 0;
    uint32_t G0, Gk, H0 = POLAR_NONE, Hm = POLAR_NONE, i, j;
    /* the walls starting here, bottom to top; those ending here counted */
    for (i = 0; i < npts; i++) {
        uint32_t p = pts[i] & EV_POINT;
        for (j = w->inc_first[p]; j < w->inc_first[p + 1]; j++) {
            uint32_t s = w->inc[j];
            if (lex_cmp(EL(w, s), P) == 0) {
                w->start[ns++] = s;
            } else {
                nend++;
                some_end = s;
            }
        }
    }
    if (ns > 1 && sort_starts(w, ns) != 0)
        return -1;
    /* B: the status piece below P */
    if (nend > 0) {
        x = some_end;
        if (N[x].prev == POLAR_NONE)
            return -1;
        while ((y = N[x].prev) != m->box_bot && lex_cmp(ER(w, y), P) == 0)
            x = y;
        B = N[x].prev;
    } else {
        /* only starts: the floor of the trapezoid below the lowest piece
         * starting here, at its left end, in the DAG's map (the map has
         * every piece: that floor is the piece below P just right of P,
         * and no piece ends at P, so it is the status piece below P);
         * checked to be in the status and strictly below P */
        uint32_t d = ns ? w->SR[w->start[0]].down[0] : POLAR_NONE;
        if (d == POLAR_NONE)
            return -1;
        B = w->T ? w->T[d].bot : tget_packed(w->DT, d, F_BOT);
        if (B != m->box_bot &&
            (B >= w->pd->nseg || N[B].prev == POLAR_NONE || geom_orient(EL(w, B), ER(w, B), P) <= 0))
            return -1;
    }
    /* the pieces ending at P follow B */
    for (y = N[B].next; y != POLAR_NONE && lex_cmp(ER(w, y), P) == 0; y = N[y].next) {
        last = y;
        k++;
    }
    w->steps += k + ns;
    if (k != nend)
        return -1;
    A = y;
    if (A != POLAR_NONE && geom_orient(EL(w, A), ER(w, A), P) >= 0)
        return -1;
    /* close the gaps B..e1, e1..e2, ..., ek..A */
    G0 = N[B].open;
    Gk = k ? N[last].open : G0;
    if (close_region(w, G0, pi) != 0)
        return -1;
    for (y = N[B].next, i = 0; i < k; i++) {
        x = N[y].next;
        if (close_region(w, N[y].open, pi) != 0)
            return -1;
        N[y].prev = N[y].next = POLAR_NONE;
        y = x;
    }
    /* open the gaps B..s1, s1..s2, ..., sm..A and link s1..sm in */
    for (j = 0; j <= ns; j++) {
        uint32_t bot = j ? w->start[j - 1] : B;
        uint32_t top = j < ns ? w->start[j] : (A == POLAR_NONE ? m->box_top : A);
        uint32_t h;
        if (j > 0) {
            const polar_seg *g = &w->pd->seg[bot];
            int32_t d = lex_cmp(fpt(w->pd, m->frame, g->a), P) == 0 ? g->cover : -g->cover;
            uint32_t below = j > 1 ? w->start[j - 2] : B;
            N[bot].cov = N[below].cov + d;
            N[bot].prev = below;
            N[below].next = bot;
        }
        if (open_gap(w, j ? w->SR[bot].up[0] : ns ? w->SR[w->start[0]].down[0] : w->PR[pi].side[0],
                     pi, top, bot, N[bot].cov == 0, &h) != 0)
            return -1;
        N[bot].open = h;
        if (j == 0)
            H0 = h;
        if (j == ns) {
            Hm = h;
            N[bot].next = A;
            if (A != POLAR_NONE)
                N[A].prev = bot;
        }
    }
    set_link(w, G0, LR, regno(w, H0));
    set_link(w, Gk, UR, regno(w, Hm));
    set_link(w, H0, LL, regno(w, G0));
    set_link(w, Hm, UL, regno(w, Gk));
    return 0;
}

/* Walls incident to each point (both frames), and the number of points
 * that are wall ends: the events of the sweeps. */
plx_status polar_incidence(arena *a, const polar *pd, uint32_t **inc_first, uint32_t **inc,
                           uint32_t *nev)
{
    uint32_t i, s, n = 0, *f, *v;
    f = scratch_n(a, (size_t)pd->npts + 1, 4);
    v = scratch_n(a, (size_t)pd->nwall * 2, 4);
    if (!f || !v)
        return PLX_E_NOMEM;
    memset(f, 0, ((size_t)pd->npts + 1) * 4);
    for (s = 0; s < pd->nwall; s++) {
        f[pd->seg[s].a + 1]++;
        f[pd->seg[s].b + 1]++;
    }
    for (i = 0; i < pd->npts; i++) {
        if (f[i + 1] > 0)
            n++;
        f[i + 1] += f[i];
    }
    for (s = 0; s < pd->nwall; s++) {
        v[f[pd->seg[s].a]++] = s;
        v[f[pd->seg[s].b]++] = s;
    }
    for (i = pd->npts; i > 0; i--)
        f[i] = f[i - 1];
    f[0] = 0;
    *inc_first = f;
    *inc = v;
    *nev = n;
    return PLX_OK;
}


/* Box sides and corners as seen in a frame: top, bottom, lowest, highest. */
static void frame_box(const polar *pd, polar_map *m)
{
    uint32_t i, s0 = pd->nwall, p0 = pd->npts - 4;
    double vmax = -DBL_MAX, vmin = DBL_MAX;
    for (i = 0; i < 4; i++) {
        const polar_seg *g = &pd->seg[s0 + i];
        vec2 a = fpt(pd, m->frame, g->a), b = fpt(pd, m->frame, g->b);
        if (a.y == b.y && a.y > vmax) {
            vmax = a.y;
            m->box_top = s0 + i;
        }
        if (a.y == b.y && a.y < vmin) {
            vmin = a.y;
            m->box_bot = s0 + i;
        }
    }
    m->box_lo = m->box_hi = p0;
    for (i = 1; i < 4; i++) {
        vec2 f = fpt(pd, m->frame, p0 + i);
        if (lex_cmp(f, fpt(pd, m->frame, m->box_lo)) < 0)
            m->box_lo = p0 + i;
        if (lex_cmp(f, fpt(pd, m->frame, m->box_hi)) > 0)
            m->box_hi = p0 + i;
    }
}


/* Per piece: the sweep's data (N, unless NULL: made later) and its
 * canonical ends (SR, all else unset: POLAR_NONE); canon: per point the first event point at its
 * position. */
static void frame_pieces(polar *pd, polar_map *m, snode *N, sroles *SR,
                         const uint32_t *canon)
{
    uint32_t s;
    memset(SR, 0xff, (size_t)pd->nseg * sizeof(sroles));
    for (s = 0; s < pd->nseg; s++) {
        uint32_t l, r;
        seg_ends(pd, m->frame, s, &l, &r);
        SR[s].end[0] = canon[l];
        SR[s].end[1] = canon[r];
        if (!N)
            continue;
        N[s].cov = 0;
        N[s].open = POLAR_NONE;
        N[s].prev = N[s].next = POLAR_NONE;
    }
}

/* The sweep's data per piece, made after the insertion (the late order). */
static snode *new_snodes(arena *a, const polar *pd)
{
    snode *N = scratch_n(a, pd->nseg, sizeof(snode));
    uint32_t s;
    if (!N)
        return NULL;
    for (s = 0; s < pd->nseg; s++) {
        N[s].cov = 0;
        N[s].open = POLAR_NONE;
        N[s].prev = N[s].next = POLAR_NONE;
    }
    return N;
}

/* The events in sweep order (evs, EV_SAME marking a position already
 * seen), the canonical point of every point, the longest run of event
 * positions from a wall piece's left end to its right end (a piece
 * crosses at most one trapezoid per position strictly between its ends,
 * plus one: the insertion's lists are sized by it) and the most walls at
 * one position (the sweep's lists of pieces starting at an event). canon
 * and the sort's buffers are scratch given back by the caller. */
static plx_status sort_events(arena *a, const polar *pd, int frame, uint32_t nev,
                              const uint32_t *inc_first, uint32_t *evs,
                              uint32_t *canon, uint32_t *span, uint32_t *maxdeg)
{
    fpoint *ev = scratch_n(a, nev, sizeof(fpoint)), *tmp = scratch_n(a, nev, sizeof(fpoint));
    uint32_t *rank = scratch_n(a, pd->npts, 4), i, j, nd = 0, s;
    if (!ev || !tmp || !rank)
        return PLX_E_NOMEM;
    for (i = 0, j = 0; i < pd->npts && j < nev; i++) {
        if (inc_first[i + 1] == inc_first[i])
            continue;
        ev[j].f = fpt(pd, frame, i);
        ev[j++].i = i;
    }
    sort_fpoints(ev, tmp, nev, NULL);
    for (i = 0; i < pd->npts; i++) {
        canon[i] = i;
        rank[i] = 0;
    }
    *maxdeg = 0;
    for (i = 0; i < nev; i = j, nd++) {
        uint32_t deg = inc_first[ev[i].i + 1] - inc_first[ev[i].i];
        evs[i] = ev[i].i;
        rank[ev[i].i] = nd;
        for (j = i + 1; j < nev && lex_cmp(ev[j].f, ev[i].f) == 0; j++) {
            canon[ev[j].i] = ev[i].i;
            rank[ev[j].i] = nd;
            evs[j] = ev[j].i | EV_SAME;
            deg += inc_first[ev[j].i + 1] - inc_first[ev[j].i];
        }
        if (deg > *maxdeg)
            *maxdeg = deg;
    }
    *span = 0;
    for (s = 0; s < pd->nwall; s++) {
        uint32_t ra = rank[pd->seg[s].a], rb = rank[pd->seg[s].b];
        uint32_t d = ra > rb ? ra - rb : rb - ra;
        if (d > *span)
            *span = d;
    }
    return PLX_OK;
}

/* The sweep over the sorted events evs[0..nev-1], with the DAG's map b. */
static plx_status run_sweep(sweep *w, const dbuild *b, const uint32_t *evs, uint32_t nev)
{
    polar_map *m = w->m;
    uint32_t i, j;
    if (open_gap(w, b->SR[m->box_bot].up[0], m->box_lo, m->box_top, m->box_bot, 1,
                 &w->N[m->box_bot].open) != 0)
        return PLX_E_SCENE;
    for (i = 0; i < nev; i = j) {
        for (j = i + 1; j < nev && (evs[j] & EV_SAME); j++)
            ;
        if (sweep_event(w, fpt(w->pd, m->frame, evs[i]), evs[i], evs + i, j - i) != 0)
            return PLX_E_SCENE;
    }
    if (w->N[m->box_bot].next != POLAR_NONE || w->N[m->box_bot].open == POLAR_NONE)
        return PLX_E_SCENE;
    /* both maps the same: every live trapezoid of the DAG's map is one gap
     * of the sweep, with the same sides (every region closed, where the
     * map's right axis is) */
    if (close_region(w, w->N[m->box_bot].open, m->box_hi) != 0 || w->nclosed != w->ntrap)
        return PLX_E_SCENE;
    if (w->ngap != b->ntrap - b->nfree)
        return PLX_E_SCENE;
    return PLX_OK;
}

/* Per region its slot, named by the region's child word in the slot's leaf
 * field: written over the insertion's point roles (b->PR, not read after
 * the sweep) when they are long enough, else new scratch. */
static uint32_t *region_slots(arena *a, const polar *pd, const dbuild *b, uint32_t nreg)
{
    uint32_t t, *regd = nreg <= 2 * (uint64_t)pd->npts ? (uint32_t *)(void *)b->PR
                                                        : scratch_n(a, nreg, 4);
    if (!regd)
        return NULL;
    for (t = 0; t < b->ntrap; t++) {
        uint32_t c = tget(b, t, F_LEAF);
        if (POLAR_TAG(c) == POLAR_CHILD_FREE)
            regd[POLAR_IDX(c)] = t;
    }
    return regd;
}

/* Builds the trapezoidal map of one frame: the search DAG's map by
 * randomized insertion, then the sweep, which uses it to place the events
 * where pieces only start, checks that the pieces form a planar
 * subdivision and that both maps agree, and makes the free regions (kept,
 * in sweep order, with their adjacency); then the DAG is kept with its
 * leaves mapped to those regions (unless flags say otherwise).
 * Memory, in stack order: per piece N (24 bytes) and SR (24), the
 * sorted events (4 a point); the sort's buffers and canonical indices
 * (given back before the insertion); the insertion's hints and roles (4 +
 * 8 a point), lists (by the longest piece) and search nodes (12 bytes
 * each, or packed in bits for a large scene in a tight block, about 6 a
 * piece, chunks); its trapezoid slots (36 bytes, about 2 a
 * piece) in the low end of the arena. The sweep's regions live in those
 * slots (regd: 4 bytes per live trapezoid names them), and are kept in
 * place (polar_keep_regions) before the search nodes are (scratch).
 * With no incidence given (the packed build, see polar_build), N and the
 * incidence are made after the insertion instead, once the DAG's leaves
 * are dropped (polar_dag_compact), and given back before the DAG is kept.
 * README "Polar build scratch". */
plx_status polar_map_build(arena *a, polar *pd, polar_map *m, const uint32_t *inc_first,
                           const uint32_t *inc, uint32_t nev,
                           const uint32_t *order, int flags, uint64_t *steps)
{
    sweep w;
    dbuild b;
    uint32_t *evs, *canon, *regd, nlive, span, maxdeg, *tf, *ti, tn;
    sroles *SR;
    dag_rank rk;
    arena_mark mk, ms;
    plx_status st;
    int late = inc_first == NULL;
    if (pd->npts >= (1u << 26) || pd->nwall >= (1u << 26))
        return PLX_E_NOMEM;   /* indices must fit in 30 bits (26 here) */
    memset(&w, 0, sizeof w);
    memset(&b, 0, sizeof b);
    memset(&rk, 0, sizeof rk);
    w.pd = pd;
    w.m = m;
    if (!late && !(w.N = scratch_n(a, pd->nseg, sizeof(snode))))
        return PLX_E_NOMEM;
    w.SR = SR = scratch_n(a, pd->nseg, sizeof(sroles));
    evs = scratch_n(a, nev, 4);
    if (!SR || !evs)
        return PLX_E_NOMEM;
    frame_box(pd, m);
    mk = arena_get_mark(a);
    canon = scratch_n(a, pd->npts, 4);
    if (!canon)
        return PLX_E_NOMEM;
    if (late) {
        /* the incidence for the sort alone, given back with it */
        st = polar_incidence(a, pd, &tf, &ti, &tn);
        if (st != PLX_OK)
            return st;
        PLX_ASSERT(tn == nev);
        inc_first = tf;
    }
    st = sort_events(a, pd, m->frame, nev, inc_first, evs, canon, &span, &maxdeg);
    if (st != PLX_OK)
        return st;
    frame_pieces(pd, m, w.N, SR, canon);
    arena_release(a, &mk);
    st = polar_dag_build(a, pd, m, &b, SR, order, span, flags);
    if (st != PLX_OK)
        return st;
    ms = arena_get_mark(a);
    if (late) {
        st = polar_dag_compact(a, &b);
        if (st != PLX_OK)
            return st;
        ms = arena_get_mark(a);
        w.N = new_snodes(a, pd);
        if (!w.N)
            return PLX_E_NOMEM;
        st = polar_incidence(a, pd, &tf, &ti, &tn);
        if (st != PLX_OK)
            return st;
        inc_first = tf;
        inc = ti;
    }
    w.inc_first = inc_first;
    w.inc = inc;
    w.DT = &b;
    w.T = b.tpk ? NULL : b.T;
    w.SR = b.SR;
    w.PR = b.PR;
    /* every region is a live trapezoid of the map, each once (open_gap) */
    nlive = b.ntrap - b.nfree;
    w.cap = nlive;
    w.start = scratch_n(a, (size_t)maxdeg + 1, 4);
    w.tmp = scratch_n(a, (size_t)maxdeg + 1, 4);
    if (!w.start || !w.tmp)
        return PLX_E_NOMEM;
    st = run_sweep(&w, &b, evs, nev);
    if (st != PLX_OK)
        return st;
    regd = region_slots(a, pd, &b, w.ntrap);
    if (!regd)
        return PLX_E_NOMEM;
    *steps += w.steps + b.steps;
    if (!(flags & POLAR_BUILD_NO_DAG)) {
        st = b.compact ? polar_dag_resolve(&b, w.ntrap) : polar_dag_words(a, &b, &rk);
        if (st != PLX_OK)
            return st;
    }
    st = polar_keep_regions(a, pd, m, &b, regd, w.ntrap);
    if (st != PLX_OK)
        return st;
    /* polar_memory: the axes (lp, rp, nb) and the regions (top, bot) */
    pd->bytes[0] -= (size_t)w.ntrap * 8;
    pd->bytes[1] += (size_t)w.ntrap * 8;
    if (b.compact) {
        /* the sweep's data, the incidence and lists given back (the
         * compacted nodes lie below them) */
        arena_mark r = arena_get_mark(a);
        r.hi = ms.hi;
        r.used[PLX_PART_SCRATCH] = ms.used[PLX_PART_SCRATCH];
        arena_release(a, &r);
    }
    if (flags & POLAR_BUILD_NO_DAG)
        return PLX_OK;
    return polar_dag_keep(a, pd, m, &b, &rk, flags);
}
