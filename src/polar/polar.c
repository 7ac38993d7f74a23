/* polar: quadrant polar diagrams as trapezoidal subdivisions (see polar.h):
 * the build of both subdivisions from its parts (polar_int.h lists the
 * files), the frames, and the regions for drawing.
 *
 * Construction, per subdivision, in a frame where the axes are "vertical"
 * and points are ordered lexicographically by (u, v) (the trapezoidal map
 * of de Berg et al., "Computational Geometry", ch. 6):
 * 1. the map and its search DAG by randomized incremental insertion of the
 *    wall pieces (trapmap.c; expected O(n log n));
 * 2. a plane sweep over the wall ends (sweep.c), which reads
 *    from that map the piece below every event where pieces only start
 *    (O(1); the piece below is the floor of the map's trapezoid below the
 *    lowest piece starting there), checks that the pieces form a planar
 *    subdivision and that every gap it opens is a trapezoid of the map with
 *    the same sides, and makes the free regions (whether a gap is solid is
 *    known when its floor enters the sweep) in a deterministic order with
 *    their adjacency, setting the DAG leaf of each: O(n log n) worst case;
 * 3. the DAG kept, its leaves as child words (a free region or the owner
 *    of a solid trapezoid).
 * Before that, the footprints are cut at their contacts (walls.c). Queries
 * (point location, ray shooting) are in locate.c. No grid is used;
 * tests/ref/ref_polar_scan.c keeps one, with the former grid-scan point
 * location, as a reference for tests and benchmarks. pd->steps counts the
 * searching work (DAG nodes and trapezoids visited by the insertions,
 * status pieces walked and sorted by the sweeps) for the tests.
 */
#include "polar/polar_int.h"

vec2 polar_to_frame(int frame, vec2 w)
{
    return to_frame(frame, w);
}

vec2 polar_from_frame(int frame, vec2 f)
{
    vec2 w;
    if (frame == 0) {
        w.x = -f.y;
        w.y = f.x;
    } else {
        w = f;
    }
    return w;
}

vec2 polar_fpt(const polar *pd, int frame, uint32_t i)
{
    return fpt(pd, frame, i);
}

/* ---- build ------------------------------------------------------------- */

static int finite_box(const double *bx)
{
    int i;
    for (i = 0; i < 4; i++)
        if (!isfinite(bx[i]))
            return 0;
    return bx[0] < bx[2] && bx[1] < bx[3];
}

/* The first map's regions held in bits while the second map is built (the
 * packed build, where the block is tight): lp, rp, top, bot in pb bits,
 * the links in lb (all ones: none), record i at bit i rw of the regions'
 * own place (written from the first up: record i ends at or before byte
 * 32 (i + 1), where region i + 1 starts); what follows them in the low end
 * (the first map's DAG) is moved down by delta, a multiple of 16, and the
 * low end given back by as much. unhold_regions moves everything after
 * them back up by delta (the second map's regions and DAG too) and widens
 * the records from the last down. */
typedef struct held {
    polar_map *m;
    uint64_t *w;             /* the records (at m->trap) */
    unsigned char *tail;     /* where what followed them starts now */
    size_t delta;            /* 0: nothing held */
    uint32_t pb, lb, rw;
} held;

static void hold_regions(arena *a, polar *pd, polar_map *m, held *h)
{
    uint32_t i, k, n = m->ntrap;
    uint64_t most = pd->npts > pd->nseg ? pd->npts : pd->nseg, bits;
    unsigned char *end = (unsigned char *)(void *)(m->trap + n), *lo = a->base + a->lo;
    arena_mark mk;
    h->delta = 0;
    h->m = m;
    h->w = (uint64_t *)(void *)m->trap;
    h->pb = 1;
    while (h->pb < 32 && ((uint64_t)1 << h->pb) < most)
        h->pb++;
    h->lb = 1;
    while (h->lb < 32 && ((uint64_t)1 << h->lb) < (uint64_t)n + 1)
        h->lb++;
    h->rw = 4 * h->pb + 4 * h->lb;
    bits = (uint64_t)n * h->rw + 64;   /* a word more: fields are read in two */
    if (((uintptr_t)h->w & 7) != 0 || bits / 8 + 16 >= (uint64_t)n * 32)
        return;
    for (i = 0; i < n; i++) {
        polar_trap r = m->trap[i];
        uint64_t off = (uint64_t)i * h->rw;
        uint32_t f[8];
        f[0] = r.lp;
        f[1] = r.rp;
        f[2] = r.top;
        f[3] = r.bot;
        for (k = 0; k < 4; k++)
            f[4 + k] = r.nb[k] == POLAR_NONE ? (uint32_t)(((uint64_t)1 << h->lb) - 1) : r.nb[k];
        for (k = 0; k < 8; k++)
            field_set(h->w, off + (k < 4 ? k * h->pb : 4 * h->pb + (k - 4) * h->lb),
                      k < 4 ? h->pb : h->lb, f[k]);
    }
    h->delta = (size_t)((end - (unsigned char *)(void *)h->w) - (size_t)((bits + 63) / 64) * 8) & ~(size_t)15;
    h->tail = end - h->delta;
    memmove(h->tail, end, (size_t)(lo - end));
    if (m->node)
        m->node = (uint32_t *)(void *)((unsigned char *)(void *)m->node - h->delta);
    mk = arena_get_mark(a);
    mk.lo -= h->delta;
    mk.used[PLX_PART_POLAR] -= h->delta;
    arena_release(a, &mk);
}

static unsigned char *moved_up(void *p, size_t delta)
{
    return (unsigned char *)p + delta;
}

static plx_status unhold_regions(arena *a, polar *pd, held *h)
{
    polar_map *m = h->m;
    unsigned char *lo = a->base + a->lo;
    uint32_t i, k;
    if (h->delta == 0)
        return PLX_OK;
    if (arena_alloc(a, PLX_PART_POLAR, h->delta, 1) != lo)
        return PLX_E_NOMEM;
    memmove(h->tail + h->delta, h->tail, (size_t)(lo - h->tail));
    if (m->node)
        m->node = (uint32_t *)(void *)moved_up(m->node, h->delta);
    for (i = 0; i < 2; i++) {
        if (&pd->map[i] == m)
            continue;
        pd->map[i].trap = (polar_trap *)(void *)moved_up(pd->map[i].trap, h->delta);
        if (pd->map[i].node)
            pd->map[i].node = (uint32_t *)(void *)moved_up(pd->map[i].node, h->delta);
    }
    for (i = m->ntrap; i-- > 0;) {
        polar_trap r;
        uint64_t off = (uint64_t)i * h->rw, none = ((uint64_t)1 << h->lb) - 1, v;
        r.lp = (uint32_t)field_get(h->w, off, h->pb);
        r.rp = (uint32_t)field_get(h->w, off + h->pb, h->pb);
        r.top = (uint32_t)field_get(h->w, off + 2 * h->pb, h->pb);
        r.bot = (uint32_t)field_get(h->w, off + 3 * h->pb, h->pb);
        for (k = 0; k < 4; k++) {
            v = field_get(h->w, off + 4 * h->pb + k * h->lb, h->lb);
            r.nb[k] = v == none ? POLAR_NONE : (uint32_t)v;
        }
        m->trap[i] = r;
    }
    return PLX_OK;
}

plx_status polar_build(arena *a, const scene *s, polar **out)
{
    return polar_build_flags(a, s, 0, out);
}

plx_status polar_build_flags(arena *a, const scene *s, int flags, polar **out)
{
    arena_mark m0, m1, mi;
    held hd;
    polar *pd;
    plx_status st;
    uint32_t *inc_first = NULL, *inc = NULL, *order = NULL, nev = 0, i;
    if (!a || !s || !out)
        return PLX_E_INVALID;
    *out = NULL;
    hd.delta = 0;
    if (!finite_box(s->bounds))
        return PLX_E_INVALID;
    m0 = arena_get_mark(a);
    pd = arena_calloc(a, PLX_PART_POLAR, 1, sizeof(polar), 16);
    if (!pd)
        return PLX_E_NOMEM;
    pd->s = s;
    pd->nbld = s->nbld;
    memcpy(pd->box, s->bounds, sizeof pd->box);
    pd->bytes[3] = sizeof(polar);
    st = polar_make_walls(a, pd);
    mi = arena_get_mark(a);
    if (st == PLX_OK)
        st = polar_incidence(a, pd, &inc_first, &inc, &nev);
    if (st == PLX_OK)
        st = polar_insertion_order(a, pd, &order);
    if (pd->nwall > PACKED_NODES_FROM && arena_free_bytes(a) / PACKED_NODES_ROOM < pd->nwall)
        flags |= POLAR_BUILD_PACKED;
    if (st == PLX_OK && (flags & (POLAR_BUILD_PACKED | POLAR_BUILD_WIDE_DAG))) {
        /* the packed build makes each map's incidence after its insertion
         * (polar_map_build): the shared one is given back, the insertion
         * order moved down in its place */
        uint32_t *o2;
        arena_release(a, &mi);
        o2 = scratch_n(a, pd->nwall, 4);
        if (!o2)
            st = PLX_E_NOMEM;
        else
            memmove(o2, order, (size_t)pd->nwall * 4);
        order = o2;
        inc_first = inc = NULL;
    }
    for (i = 0; st == PLX_OK && i < 2; i++) {
        arena_mark mm = arena_get_mark(a);
        pd->map[i].frame = (int)i;
        st = polar_map_build(a, pd, &pd->map[i], inc_first, inc, nev, order, flags, &pd->steps);
        /* give back this map's scratch (kept memory grows from the other end) */
        mm.lo = a->lo;
        mm.used[PLX_PART_POLAR] = a->used[PLX_PART_POLAR];
        if (st == PLX_OK)
            arena_release(a, &mm);
        if (st == PLX_OK && i == 0 && !inc_first)
            hold_regions(a, pd, &pd->map[0], &hd);
    }
    /* release the scratch only, keep what was allocated for the diagrams */
    m1 = arena_get_mark(a);
    m1.hi = m0.hi;
    m1.used[PLX_PART_SCRATCH] = m0.used[PLX_PART_SCRATCH];
    if (st == PLX_OK) {
        arena_release(a, &m1);
        st = unhold_regions(a, pd, &hd);
    }
    if (st != PLX_OK) {
        arena_release(a, &m0);
        return st;
    }
    *out = pd;
    return PLX_OK;
}

void polar_memory(const polar *pd, size_t bytes[4])
{
    int i;
    for (i = 0; i < 4; i++)
        bytes[i] = pd ? pd->bytes[i] : 0;
}

uint32_t polar_region_count(const polar *pd, int q)
{
    if (!pd || q < 0 || q > 3)
        return 0;
    return pd->map[q & 1].ntrap;
}

/* Point of segment s at frame abscissa u (its end if s is vertical). */
static vec2 seg_at(const polar *pd, int frame, uint32_t s, double u)
{
    uint32_t l, r;
    vec2 A, B, c;
    seg_ends(pd, frame, s, &l, &r);
    A = fpt(pd, frame, l);
    B = fpt(pd, frame, r);
    c.x = u;
    if (B.x == A.x)
        c.y = A.y;
    else
        c.y = A.y + (B.y - A.y) * ((u - A.x) / (B.x - A.x));
    return c;
}

int polar_region(const polar *pd, int q, uint32_t i, vec2 c[4], int32_t *owner, int *solid)
{
    const polar_map *m;
    int mi, top;
    double ul, ur;
    if (!pd || q < 0 || q > 3 || i >= pd->map[q & 1].ntrap)
        return 0;
    quadrant_side(q, &mi, &top);
    m = &pd->map[mi];
    ul = fpt(pd, m->frame, m->trap[i].lp).x;
    ur = fpt(pd, m->frame, m->trap[i].rp).x;
    c[0] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].bot, ul));
    c[1] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].bot, ur));
    c[2] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].top, ur));
    c[3] = polar_from_frame(m->frame, seg_at(pd, m->frame, m->trap[i].top, ul));
    if (owner)
        *owner = seg_owner(pd, top ? m->trap[i].top : m->trap[i].bot);
    PLX_ASSERT(!owner || (*owner >= -1 && *owner < (int32_t)pd->nbld)); /* a building or the frame */
    if (solid)
        *solid = 0;
    return 4;
}
