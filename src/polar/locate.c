/* locate: point location in the search DAG of a diagram, and ray shooting
 * (the regions walked from the point's region to the first wall). */
#include "polar/polar_int.h"
#include "polar/locate.h"

/* ---- queries ----------------------------------------------------------- */

/* Node n of m unpacked (see polar_map). */
static void node_get(const polar_map *m, uint32_t n, uint32_t w[3])
{
    if (m->narrow) {
        uint64_t x = (uint64_t)m->node[2 * (size_t)n] | (uint64_t)m->node[2 * (size_t)n + 1] << 32;
        uint32_t t = (uint32_t)(x & 0x3fffffu), c0 = (uint32_t)(x >> 22) & 0x1fffffu,
                 c1 = (uint32_t)(x >> 43) & 0x1fffffu;
        w[0] = PACK(t >> 20, t & 0xfffffu);
        w[1] = PACK(c0 >> 19, c0 & 0x7ffffu);
        w[2] = PACK(c1 >> 19, c1 & 0x7ffffu);
    } else {
        const uint64_t *pw = (const uint64_t *)(const void *)m->node;
        uint32_t tb = m->pack & 0xffu, cb = m->pack >> 8, i;
        uint64_t off = (uint64_t)n * (tb + 2 * cb);
        uint32_t t = bits_get(pw, off, tb);
        w[0] = PACK(t >> (tb - 2), t & ((1u << (tb - 2)) - 1));
        off += tb;
        for (i = 1; i < 3; i++, off += cb) {
            uint32_t c = bits_get(pw, off, cb);
            w[i] = c < m->nnode ? PACK(POLAR_CHILD_NODE, c)
                   : c - m->nnode < m->ntrap ? PACK(POLAR_CHILD_FREE, c - m->nnode)
                                             : PACK(POLAR_CHILD_SOLID, c - m->nnode - m->ntrap);
        }
    }
}

void polar_node(const polar_map *m, uint32_t n, uint32_t w[3])
{
    node_get(m, n, w);
}

/* The free region holding frame point f: the search DAG descended from
 * its root. -2 as soon as a test is a tie: f at a vertex (x test) or on a
 * wall piece (y test: the nodes met are those whose regions hold f, so f
 * lies within the piece's span). -3 at a solid leaf, whose child word
 * carries the owner. */
static int32_t dag_locate(const polar *pd, const polar_map *m, vec2 f, int32_t *owner,
                          uint32_t *depth)
{
    uint32_t c = m->root, d = 0;
    int32_t r;
    while (POLAR_TAG(c) == POLAR_CHILD_NODE) {
        uint32_t nd[3], w;
        int k;
        node_get(m, c, nd);
        w = nd[0];
        d++;
        if (KIND(w) == N_X) {
            k = lex_cmp(f, fpt(pd, m->frame, IDX(w)));
        } else {
            const polar_seg *g = &pd->seg[IDX(w)];
            vec2 a = fpt(pd, m->frame, g->a), b = fpt(pd, m->frame, g->b);
            k = KIND(w) == N_Y ? geom_orient(a, b, f) : geom_orient(b, a, f);
        }
        if (k == 0) {
            c = POLAR_NONE;
            break;
        }
        c = nd[k > 0 ? 2 : 1];
    }
    if (depth)
        *depth = d;
    if (c == POLAR_NONE)
        r = -2;
    else if (POLAR_TAG(c) == POLAR_CHILD_FREE)
        r = (int32_t)POLAR_IDX(c);
    else
        r = -3;
    if (owner)
        *owner = r == -3 ? (int32_t)POLAR_IDX(c) - 1 : -1;
    return r;
}

int32_t polar_locate_frame(const polar *pd, const polar_map *m, vec2 f)
{
    return dag_locate(pd, m, f, NULL, NULL);
}

int32_t polar_locate_frame_ex(const polar *pd, const polar_map *m, vec2 f, int32_t *owner,
                               uint32_t *depth)
{
    return dag_locate(pd, m, f, owner, depth);
}


static int inside_box(const polar *pd, vec2 p)
{
    return p.x > pd->box[0] && p.x < pd->box[2] && p.y > pd->box[1] && p.y < pd->box[3];
}

int32_t polar_locate(const polar *pd, int q, vec2 p, int32_t *owner)
{
    int mi, top;
    const polar_map *m;
    int32_t t;
    if (owner)
        *owner = -1;
    if (!pd || q < 0 || q > 3 || !inside_box(pd, p))
        return -1;
    quadrant_side(q, &mi, &top);
    m = &pd->map[mi];
    t = dag_locate(pd, m, to_frame(m->frame, p), owner, NULL);
    PLX_ASSERT(t >= -3 && (t < 0 || (uint32_t)t < m->ntrap)); /* a region of this map */
    if (t >= 0 && owner)
        *owner = seg_owner(pd, top ? m->trap[t].top : m->trap[t].bot);
    return t;
}


/* Intersection parameter of line p->q with the line of segment s. */
static double line_param(vec2 p, vec2 q, vec2 a, vec2 b)
{
    double rx = q.x - p.x, ry = q.y - p.y, sx = b.x - a.x, sy = b.y - a.y;
    double den = rx * sy - ry * sx;
    if (den == 0.0)
        return 0.0;
    return ((a.x - p.x) * sy - (a.y - p.y) * sx) / den;
}

/* Parameter where the ray p->q leaves the box. */
static double box_exit(const polar *pd, vec2 p, vec2 q)
{
    double dx = q.x - p.x, dy = q.y - p.y, t = DBL_MAX;
    if (dx > 0)
        t = fmin(t, (pd->box[2] - p.x) / dx);
    if (dx < 0)
        t = fmin(t, (pd->box[0] - p.x) / dx);
    if (dy > 0)
        t = fmin(t, (pd->box[3] - p.y) / dy);
    if (dy < 0)
        t = fmin(t, (pd->box[1] - p.y) / dy);
    return t;
}

/* Walks the ray from frame point P through Q from region *t of map m, until
 * it leaves through a wall (*hit) or reaches the Bounds box (*hit =
 * POLAR_NONE); returns 1. side = +1 / -1: the one-sided ray, a corner on the
 * ray counted as passed on the other side. side = 0: the exact ray, which
 * stops at the first corner lying exactly on it and returns 0 with *t the
 * region whose corner that is (the two one-sided rays part there, and walk
 * on from *t). *steps counts the regions left behind. */
static int walk(const polar *pd, const polar_map *m, uint32_t *t, vec2 P, vec2 Q, int side,
                uint32_t *hit, uint32_t *steps)
{
    const polar_trap *trap = m->trap;
    int right = lex_cmp(Q, P) > 0;
    uint32_t end = right ? m->box_hi : m->box_lo, k = *t, n = 0;
    double qx = Q.x - P.x, qy = Q.y - P.y;
    for (;;) {
        uint32_t r = right ? trap[k].rp : trap[k].lp, nx;
        vec2 R;
        int o;
        n++;
        if (r == end) {
            *hit = POLAR_NONE;
            break;
        }
        R = fpt(pd, m->frame, r);
        /* geom_orient(P, Q, R), filtered on the differences from P */
        o = geom_orient_filter(qx * (R.y - P.y), qy * (R.x - P.x));
        if (o == 0)
            o = geom_orient(P, Q, R);
        if (o == 0) {
            if (side == 0) {
                *t = k;
                *steps += n - 1;
                return 0;
            }
            o = side > 0 ? -1 : 1;
        }
        if (!right)
            o = -o;
        /* o > 0: the ray passes below r (in the frame) */
        nx = trap[k].nb[o > 0 ? (right ? LR : LL) : (right ? UR : UL)];
        if (nx == POLAR_NONE) {
            *hit = o > 0 ? trap[k].bot : trap[k].top;
            break;
        }
        k = nx;
    }
    *t = k;
    *steps += n;
    return 1;
}

/* Fills the hit record of the ray p->q that left through wall piece hit
 * (POLAR_NONE: through the Bounds box). */
static void hit_record(const polar *pd, vec2 p, vec2 q, uint32_t hit, uint32_t steps,
                       polar_hit *h)
{
    h->steps = steps;
    if (hit == POLAR_NONE || pd->seg[hit].bld[0] == -2) {
        h->bld = h->bld2 = -1;
        h->seg = hit;
        h->t = box_exit(pd, p, q);
    } else {
        const polar_seg *g = &pd->seg[hit];
        h->bld = g->bld[0];
        h->bld2 = g->bld[1];
        h->seg = hit;
        h->t = line_param(p, q, pd->pts[g->a], pd->pts[g->b]);
    }
    h->pt.x = p.x + h->t * (q.x - p.x);
    h->pt.y = p.y + h->t * (q.y - p.y);
}

/* The exact ray (side 0) is walked once; only where it passes exactly
 * through a corner does it part into the two one-sided rays, each walked on
 * from there, and the one blocked farther wins (the exact ray enters the
 * solid only where both sides of it are solid). */
plx_status polar_shoot_to(const polar *pd, vec2 p, vec2 q, int side, polar_hit *out)
{
    const polar_map *m;
    int32_t t;
    uint32_t k, hit, steps = 0;
    vec2 P, Q;
    if (!pd || !out)
        return PLX_E_INVALID;
    if (p.x == q.x && p.y == q.y)
        return PLX_E_INVALID;
    if (!inside_box(pd, p))
        return PLX_E_RANGE;
    /* the diagram of the quadrant holding the direction */
    {
        double dx = q.x - p.x, dy = q.y - p.y;
        int qd = (dx > 0 && dy >= 0) ? 0 : (dx <= 0 && dy > 0) ? 1 : (dx < 0) ? 2 : 3;
        m = &pd->map[qd & 1];
    }
    P = to_frame(m->frame, p);
    Q = to_frame(m->frame, q);
    t = polar_locate_frame(pd, m, P);
    if (t < 0)
        return PLX_E_RANGE;
    k = (uint32_t)t;
    if (walk(pd, m, &k, P, Q, side, &hit, &steps)) {
        hit_record(pd, p, q, hit, steps, out);
    } else {
        polar_hit h2;
        uint32_t k2 = k, hit2, steps2 = 0;
        walk(pd, m, &k, P, Q, 1, &hit, &steps);
        walk(pd, m, &k2, P, Q, -1, &hit2, &steps2);
        hit_record(pd, p, q, hit, steps + steps2, out);
        hit_record(pd, p, q, hit2, steps + steps2, &h2);
        if (h2.t > out->t)
            *out = h2;
    }
    return PLX_OK;
}

plx_status polar_shoot(const polar *pd, vec2 p, double dx, double dy, polar_hit *out)
{
    vec2 q;
    double L, n;
    if (!pd || !out || !(dx != 0.0 || dy != 0.0) || !isfinite(dx) || !isfinite(dy))
        return PLX_E_INVALID;
    L = 2.0 * ((pd->box[2] - pd->box[0]) + (pd->box[3] - pd->box[1]));
    n = sqrt(dx * dx + dy * dy);
    q.x = p.x + dx / n * L;
    q.y = p.y + dy / n * L;
    return polar_shoot_to(pd, p, q, 0, out);
}

