/* mesh: the city as triangles (see mesh.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/mesh.h"
#include "render/party_walls.h"
#include "base/geom.h"
#include "base/bucketgrid.h"

#define MESH_ALIGN 16

/* ---- scratch helpers ----------------------------------------------------- */

static void release_scratch(arena *a, const arena_mark *m)
{
    arena_mark cur = arena_get_mark(a);
    cur.hi = m->hi;
    cur.used[PLX_PART_SCRATCH] = m->used[PLX_PART_SCRATCH];
    arena_release(a, &cur);
}

static int same_pt(vec2 a, vec2 b)
{
    return a.x == b.x && a.y == b.y;
}

/* ---- roof triangulation: hole bridges and ear clipping ------------------- */

typedef struct cand { double d2; uint32_t pos; } cand;

static int cmp_cand(const void *pa, const void *pb)
{
    const cand *a = pa, *b = pb;
    if (a->d2 != b->d2)
        return a->d2 < b->d2 ? -1 : 1;
    return (a->pos > b->pos) - (a->pos < b->pos);
}

typedef struct hole_ref { double maxx; uint32_t ring; } hole_ref;

static int cmp_hole(const void *pa, const void *pb)
{
    const hole_ref *a = pa, *b = pb;
    if (a->maxx != b->maxx)
        return a->maxx > b->maxx ? -1 : 1;
    return (a->ring > b->ring) - (a->ring < b->ring);
}

/* Does the edge (u, v) forbid the bridge P-M? */
static int edge_blocks(vec2 P, vec2 M, vec2 u, vec2 v)
{
    int r, shared;
    if (same_pt(u, v))
        return 0;
    r = geom_seg_meet(P, M, u, v);
    if (r == GEOM_SEG_DISJOINT)
        return 0;
    shared = same_pt(u, P) || same_pt(u, M) || same_pt(v, P) || same_pt(v, M);
    if (!shared || r != GEOM_SEG_TOUCH)
        return 1;
    /* Touching at a shared end is fine unless the edge's other end lies on
     * the bridge (then they run together). */
    {
        vec2 w[2];
        int k;
        w[0] = u;
        w[1] = v;
        for (k = 0; k < 2; k++) {
            double t;
            if (same_pt(w[k], P) || same_pt(w[k], M))
                continue;
            if (geom_orient(P, M, w[k]) != 0)
                continue;
            t = (w[k].x - P.x) * (M.x - P.x) + (w[k].y - P.y) * (M.y - P.y);
            if (t > 0 && t < (M.x - P.x) * (M.x - P.x) + (M.y - P.y) * (M.y - P.y))
                return 1;
        }
    }
    return 0;
}

/* Can position k of seq (len vertices) be joined to hole vertex M? */
static int bridge_ok(const vec2 *pts, const uint32_t *seq, uint32_t len, uint32_t k, vec2 M,
                     const scene *s, const uint32_t *hring, uint32_t nh)
{
    vec2 P = pts[seq[k]];
    vec2 prev = pts[seq[(k + len - 1) % len]], next = pts[seq[(k + 1) % len]];
    int conv, l1, l2, ok;
    uint32_t i, h;
    if (same_pt(P, M))
        return 1;
    conv = geom_orient(prev, P, next);
    l1 = geom_orient(prev, P, M) > 0;
    l2 = geom_orient(P, next, M) > 0;
    if (conv > 0)
        ok = l1 && l2;
    else if (conv < 0)
        ok = l1 || l2;
    else if ((next.x - P.x) * (P.x - prev.x) + (next.y - P.y) * (P.y - prev.y) > 0)
        ok = l1;
    else
        ok = 0;
    if (!ok)
        return 0;
    for (i = 0; i < len; i++)
        if (edge_blocks(P, M, pts[seq[i]], pts[seq[(i + 1) % len]]))
            return 0;
    for (h = 0; h < nh; h++) {
        const scene_ring *r = &s->rings[hring[h]];
        for (i = 0; i < r->count; i++) {
            uint32_t j = (i + 1) % r->count;
            if (edge_blocks(P, M, pts[r->first + i], pts[r->first + j]))
                return 0;
        }
    }
    return 1;
}

/* Ear test of node i at relaxation level lv (0 strict .. 2 any convex). */
static int is_ear(const vec2 *pts, const uint32_t *seq, const uint32_t *prv, const uint32_t *nxt,
                  uint32_t i, int lv)
{
    vec2 a = pts[seq[prv[i]]], b = pts[seq[i]], c = pts[seq[nxt[i]]];
    uint32_t j;
    if (geom_orient(a, b, c) <= 0)
        return 0;
    if (lv >= 2)
        return 1;
    for (j = nxt[nxt[i]]; j != prv[i]; j = nxt[j]) {
        vec2 x = pts[seq[j]];
        int o1, o2, o3;
        if (same_pt(x, a) || same_pt(x, b) || same_pt(x, c))
            continue;
        o1 = geom_orient(a, b, x);
        if (o1 < 0)
            continue;
        o2 = geom_orient(b, c, x);
        if (o2 < 0)
            continue;
        o3 = geom_orient(c, a, x);
        if (o3 < 0)
            continue;
        if (lv == 0)
            return 0;
        if (o1 > 0 && o2 > 0 && o3 > 0)
            return 0;
    }
    return 1;
}

int mesh_triangulate(arena *a, const scene *s, uint32_t r0, uint32_t nr, uint32_t *tris,
                     uint32_t *fallbacks, uint32_t *bad_holes)
{
    arena_mark m = arena_get_mark(a);
    const vec2 *pts = s->pts;
    uint32_t ntot = 0, cap, len, i, h, nh = nr > 0 ? nr - 1 : 0;
    uint32_t *seq, *prv, *nxt, *hring, remaining, cur, stall;
    hole_ref *hr;
    cand *cd;
    int ntri = 0, lv;

    for (i = 0; i < nr; i++)
        ntot += s->rings[r0 + i].count;
    cap = ntot + 2 * nh + 2;
    seq = arena_scratch(a, arena_mul(cap, sizeof *seq), MESH_ALIGN);
    prv = arena_scratch(a, arena_mul(cap, sizeof *prv), MESH_ALIGN);
    nxt = arena_scratch(a, arena_mul(cap, sizeof *nxt), MESH_ALIGN);
    cd = arena_scratch(a, arena_mul(cap, sizeof *cd), MESH_ALIGN);
    hr = arena_scratch(a, arena_mul(nh + 1, sizeof *hr), MESH_ALIGN);
    hring = arena_scratch(a, arena_mul(nh + 1, sizeof *hring), MESH_ALIGN);
    if (!seq || !prv || !nxt || !cd || !hr || !hring) {
        release_scratch(a, &m);
        return -1;
    }
    len = s->rings[r0].count;
    for (i = 0; i < len; i++)
        seq[i] = s->rings[r0].first + i;

    /* Holes by decreasing largest x. */
    for (h = 0; h < nh; h++) {
        const scene_ring *r = &s->rings[r0 + 1 + h];
        double mx = pts[r->first].x;
        for (i = 1; i < r->count; i++)
            if (pts[r->first + i].x > mx)
                mx = pts[r->first + i].x;
        hr[h].maxx = mx;
        hr[h].ring = r0 + 1 + h;
    }
    qsort(hr, nh, sizeof *hr, cmp_hole);
    for (h = 0; h < nh; h++)
        hring[h] = hr[h].ring;

    for (h = 0; h < nh; h++) {
        const scene_ring *r = &s->rings[hring[h]];
        int found = 0;
        uint32_t tries;
        /* Hole vertices from the largest x down: the first usually works. */
        for (tries = 0; tries < r->count && !found; tries++) {
            uint32_t mi = 0, k, c;
            double best = -HUGE_VAL;
            /* the tries-th largest x (ties by index), found by a scan */
            for (k = 0; k < r->count; k++) {
                double x = pts[r->first + k].x;
                uint32_t rank = 0, q;
                for (q = 0; q < r->count; q++) {
                    double y = pts[r->first + q].x;
                    if (y > x || (y == x && q < k))
                        rank++;
                }
                if (rank == tries) {
                    mi = k;
                    best = x;
                    break;
                }
            }
            (void)best;
            {
                vec2 M = pts[r->first + mi];
                for (k = 0; k < len; k++) {
                    double dx = pts[seq[k]].x - M.x, dy = pts[seq[k]].y - M.y;
                    cd[k].d2 = dx * dx + dy * dy;
                    cd[k].pos = k;
                }
                qsort(cd, len, sizeof *cd, cmp_cand);
                for (c = 0; c < len; c++) {
                    uint32_t pos = cd[c].pos, q, ins;
                    if (!bridge_ok(pts, seq, len, pos, M, s, hring + h, nh - h))
                        continue;
                    /* seq: ..., P, M, hole after M ..., M, P, ... */
                    ins = r->count + 2;
                    memmove(seq + pos + 1 + ins, seq + pos + 1, (len - pos - 1) * sizeof *seq);
                    for (q = 0; q <= r->count; q++)
                        seq[pos + 1 + q] = r->first + (mi + q) % r->count;
                    seq[pos + 1 + r->count + 1] = seq[pos];
                    len += ins;
                    found = 1;
                    break;
                }
            }
        }
        if (!found && bad_holes)
            (*bad_holes)++;
    }

    /* Ear clipping over the linked list 0..len-1. */
    for (i = 0; i < len; i++) {
        prv[i] = (i + len - 1) % len;
        nxt[i] = (i + 1) % len;
    }
    remaining = len;
    cur = 0;
    stall = 0;
    lv = 0;
    while (remaining > 3) {
        int ear = lv <= 2 ? is_ear(pts, seq, prv, nxt, cur, lv) : 0;
        if (!ear && lv == 3) {
            vec2 pa = pts[seq[prv[cur]]], pb = pts[seq[cur]], pc = pts[seq[nxt[cur]]];
            if (geom_orient(pa, pb, pc) == 0)
                ear = -1; /* drop without a triangle */
        }
        if (!ear && lv >= 4)
            ear = -1;
        if (ear) {
            uint32_t p = prv[cur], q = nxt[cur];
            if (ear > 0) {
                tris[3 * ntri] = seq[p];
                tris[3 * ntri + 1] = seq[cur];
                tris[3 * ntri + 2] = seq[q];
                ntri++;
            }
            nxt[p] = q;
            prv[q] = p;
            remaining--;
            cur = q;
            stall = 0;
            if (lv > 0) {
                if (fallbacks)
                    (*fallbacks)++;
                lv = 0;
            }
            continue;
        }
        cur = nxt[cur];
        if (++stall >= remaining) {
            lv++;
            stall = 0;
        }
    }
    if (remaining == 3) {
        uint32_t p = prv[cur], q = nxt[cur];
        if (geom_orient(pts[seq[p]], pts[seq[cur]], pts[seq[q]]) > 0) {
            tris[3 * ntri] = seq[p];
            tris[3 * ntri + 1] = seq[cur];
            tris[3 * ntri + 2] = seq[q];
            ntri++;
        }
    }
    release_scratch(a, &m);
    return ntri;
}

/* ---- wall columns -------------------------------------------------------- */

typedef struct colpt { double x, y, z; } colpt;

static int cmp_colpt(const void *pa, const void *pb)
{
    const colpt *a = pa, *b = pb;
    if (a->x != b->x)
        return a->x < b->x ? -1 : 1;
    if (a->y != b->y)
        return a->y < b->y ? -1 : 1;
    return (a->z > b->z) - (a->z < b->z);
}

/* The heights of column (x, y) within [lo, hi]: first index and count. */
static uint32_t column(const colpt *c, uint32_t n, vec2 p, double lo, double hi, uint32_t *first)
{
    uint32_t a = 0, b = n, k;
    while (a < b) {
        uint32_t mid = a + (b - a) / 2;
        const colpt *q = &c[mid];
        if (q->x < p.x || (q->x == p.x && (q->y < p.y || (q->y == p.y && q->z < lo))))
            a = mid + 1;
        else
            b = mid;
    }
    *first = a;
    for (k = a; k < n && c[k].x == p.x && c[k].y == p.y && c[k].z <= hi; k++)
        ;
    return k - a;
}

/* ---- lamps near surfaces -------------------------------------------------- */

typedef struct lgrid {
    bucketgrid b;     /* lamps by position */
    double rmax;
} lgrid;

static int lgrid_build(arena *a, const scene *s, lgrid *g)
{
    uint32_t i, nc;
    double minx = HUGE_VAL, miny = HUGE_VAL, maxx = -HUGE_VAL, maxy = -HUGE_VAL, cell;
    memset(g, 0, sizeof *g);
    if (s->nlamps == 0)
        return 0;
    g->rmax = 0;
    for (i = 0; i < s->nlamps; i++) {
        const scene_lamp *l = &s->lamps[i];
        minx = fmin(minx, l->x);
        miny = fmin(miny, l->y);
        maxx = fmax(maxx, l->x);
        maxy = fmax(maxy, l->y);
        g->rmax = fmax(g->rmax, l->radius);
    }
    cell = fmax(g->rmax, 1.0);
    g->b.nx = (uint32_t)fmin((maxx - minx) / cell + 1.0, 4096.0);
    g->b.ny = (uint32_t)fmin((maxy - miny) / cell + 1.0, 4096.0);
    cell = fmax(cell, fmax((maxx - minx) / g->b.nx, (maxy - miny) / g->b.ny) * (1.0 + 1e-9));
    bucketgrid_frame(&g->b, minx, miny, cell, g->b.nx, g->b.ny);
    nc = g->b.nx * g->b.ny;
    g->b.start = arena_scratch(a, arena_mul(nc + 1, sizeof(uint32_t)), MESH_ALIGN);
    g->b.item = arena_scratch(a, arena_mul(s->nlamps, sizeof(uint32_t)), MESH_ALIGN);
    if (!g->b.start || !g->b.item)
        return -1;
    memset(g->b.start, 0, (nc + 1) * sizeof(uint32_t));
    for (i = 0; i < s->nlamps; i++)
        g->b.start[bucketgrid_cell(&g->b, s->lamps[i].x, s->lamps[i].y) + 1]++;
    bucketgrid_offsets(&g->b);
    for (i = 0; i < s->nlamps; i++)
        g->b.item[g->b.start[bucketgrid_cell(&g->b, s->lamps[i].x, s->lamps[i].y)]++] = i;
    bucketgrid_rewind(&g->b);
    return 0;
}

/* Squared distance from (px, py) to the segment ab. */
static double seg_d2(double px, double py, vec2 a, vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t = 0;
    if (l2 > 0) {
        t = ((px - a.x) * dx + (py - a.y) * dy) / l2;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
    }
    dx = a.x + t * dx - px;
    dy = a.y + t * dy - py;
    return dx * dx + dy * dy;
}

static double box_d2(double px, double py, const double *box)
{
    double dx = fmax(0.0, fmax(box[0] - px, px - box[2]));
    double dy = fmax(0.0, fmax(box[1] - py, py - box[3]));
    return dx * dx + dy * dy;
}

/* Is some lamp able to light the surface? kind: wall (a, b, n), roof or
 * underside (box, z). Conservative: distances are enlarged by a relative
 * 1e-9 and 1e-9 m before comparing with R. */
static int surf_lit(const scene *s, const lgrid *g, int kind, vec2 a, vec2 b, const double *n,
                    const double *box, double zlo, double zhi)
{
    uint32_t r[4], cx, cy;
    double q[4];
    q[0] = box[0] - g->rmax;
    q[1] = box[1] - g->rmax;
    q[2] = box[2] + g->rmax;
    q[3] = box[3] + g->rmax;
    if (!g->b.start)
        return 0;
    bucketgrid_range(&g->b, q, r);
    for (cy = r[1]; cy <= r[3]; cy++)
        for (cx = r[0]; cx <= r[2]; cx++) {
            uint32_t k, c = cy * g->b.nx + cx;
            for (k = g->b.start[c]; k < g->b.start[c + 1]; k++) {
                const scene_lamp *l = &s->lamps[g->b.item[k]];
                double h2, dz, d;
                if (!(l->radius > 0) || !(l->intensity > 0))
                    continue;
                if (kind == MESH_KIND_WALL) {
                    if (!((l->x - a.x) * n[0] + (l->y - a.y) * n[1] > 0))
                        continue;
                    h2 = seg_d2(l->x, l->y, a, b);
                } else {
                    if (kind == MESH_KIND_ROOF && !(l->z > zhi))
                        continue;
                    if (kind == MESH_KIND_UNDER && !(l->z < zlo))
                        continue;
                    h2 = box_d2(l->x, l->y, box);
                }
                dz = fmax(0.0, fmax(zlo - l->z, l->z - zhi));
                d = sqrt(h2 + dz * dz);
                if (d * (1.0 - 1e-9) - 1e-9 < l->radius)
                    return 1;
            }
        }
    return 0;
}

/* ---- the mesh ------------------------------------------------------------ */

/* A wall's plane from its footprint edge a -> b (n[2] = 0). */
static void wall_plane(vec2 pa, vec2 pb, double *n, double *d)
{
    double dx = pb.x - pa.x, dy = pb.y - pa.y, len = sqrt(dx * dx + dy * dy);
    n[0] = n[1] = n[2] = 0.0;
    if (len > 0) {
        n[0] = dy / len;
        n[1] = -dx / len;
    }
    *d = n[0] * pa.x + n[1] * pa.y;
}

/* The vertex after pt on its ring (pt is in building bd). */
static uint32_t ring_next(const scene *s, const scene_building *bd, uint32_t pt)
{
    uint32_t r;
    for (r = 0; r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        if (pt >= rg->first && pt < rg->first + rg->count)
            return pt + 1 < rg->first + rg->count ? pt + 1 : rg->first;
    }
    return pt;
}

/* First and one past the last footprint vertex of building b. */
static void bld_span(const scene *s, uint32_t b, uint32_t *first, uint32_t *end)
{
    const scene_building *bd = &s->bld[b];
    const scene_ring *last = &s->rings[bd->ring_first + bd->ring_count - 1];
    *first = s->rings[bd->ring_first].first;
    *end = last->first + last->count;
}

/* The building of footprint vertex pt (UINT32_MAX: none). */
static uint32_t pt_building(const mesh *m, uint32_t pt)
{
    const scene *s = m->s;
    uint32_t lo, hi, f, e, k = pt / MESH_HINT_PTS;
    if (m->pt_bld)
        return m->pt_bld[pt];
    /* between the hints around pt */
    lo = m->pt_hint[k];
    hi = m->pt_hint[k + 1] + 1 < s->nbld ? m->pt_hint[k + 1] + 1 : s->nbld;
    /* the last building whose first vertex is <= pt */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        bld_span(s, mid, &f, &e);
        if (f <= pt)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo == 0)
        return UINT32_MAX;
    bld_span(s, lo - 1, &f, &e);
    return pt < e ? lo - 1 : UINT32_MAX;
}

/* pt_hint[k]: the last building whose first vertex is <= k MESH_HINT_PTS
 * (0 when none), for k up to npts / MESH_HINT_PTS + 1. */
static void make_hints(mesh *m)
{
    const scene *s = m->s;
    uint32_t k, b = 0, nk = s->npts / MESH_HINT_PTS + 2, f, e;
    for (k = 0; k < nk; k++) {
        uint64_t at = (uint64_t)k * MESH_HINT_PTS;
        while (b + 1 < s->nbld) {
            bld_span(s, b + 1, &f, &e);
            if (f > at)
                break;
            b++;
        }
        m->pt_hint[k] = b;
    }
}

/* Do the buildings' rings, and their vertices, run in order without
 * overlaps (then pt_building searches)? */
static int rings_in_order(const scene *s)
{
    uint32_t b, r, prev_end = 0;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        if (bd->ring_count == 0 || (uint64_t)bd->ring_first + bd->ring_count > s->nrings)
            return 0;
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            if (rg->first < prev_end || (uint64_t)rg->first + rg->count > s->npts)
                return 0;
            if (r > 0 && rg->first != prev_end)
                return 0;
            prev_end = rg->first + rg->count;
        }
    }
    return 1;
}

static void set_lit(mesh *m, uint32_t id, int on)
{
    if (on)
        m->lit[id >> 3] |= (uint8_t)(1u << (id & 7u));
}

void mesh_surface(const mesh *m, uint32_t id, mesh_surf *out)
{
    const scene *s = m->s;
    const scene_building *bd;
    uint32_t b;
    memset(out, 0, sizeof *out);
    if (id == MESH_SURF_NONE || id >= m->nsurf)
        return;
    out->lit = (uint8_t)mesh_lit(m, id);
    if (id == MESH_SURF_GROUND) {
        out->n[2] = 1.0;
        out->albedo = s->ground_albedo;
        out->bld = UINT32_MAX;
        out->kind = MESH_KIND_GROUND;
        return;
    }
    if (id < 2u + s->npts) {
        uint32_t pt = id - 2u;
        b = pt_building(m, pt);
        if (b >= s->nbld)
            return;
        bd = &s->bld[b];
        wall_plane(s->pts[pt], s->pts[ring_next(s, bd, pt)], out->n, &out->d);
        out->kind = MESH_KIND_WALL;
    } else if (id < 2u + s->npts + s->nbld) {
        b = id - 2u - s->npts;
        bd = &s->bld[b];
        out->n[2] = 1.0;
        out->d = bd->height;
        out->kind = MESH_KIND_ROOF;
    } else {
        b = id - 2u - s->npts - s->nbld;
        bd = &s->bld[b];
        out->n[2] = -1.0;
        out->d = -bd->min_height;
        out->kind = MESH_KIND_UNDER;
    }
    out->albedo = bd->albedo;
    out->bld = b;
}

double mesh_albedo(const mesh *m, uint32_t id)
{
    const scene *s = m->s;
    uint32_t b;
    if (id == MESH_SURF_GROUND)
        return s->ground_albedo;
    if (id < 2u || id >= m->nsurf)
        return 0.0;
    if (id < 2u + s->npts)
        b = pt_building(m, id - 2u);
    else {
        b = id - 2u - s->npts;
        b = b < s->nbld ? b : b - s->nbld;
    }
    return b < s->nbld ? s->bld[b].albedo : 0.0;
}

/* Roof index q of the mesh. */
static uint32_t roof_at(const mesh *m, uint32_t q)
{
    return m->roof16 ? m->roof16[q] : m->roof32[q];
}

/* Local vertex of split k. */
static uint32_t split_v(const mesh *m, uint32_t k)
{
    return m->split16 ? m->split16[k] : m->split32[k];
}

/* Footprint vertex pt's wall is hidden whole (mesh.hidden). */
static int wall_hidden(const mesh *m, uint32_t pt)
{
    return (m->hidden[pt >> 3] >> (pt & 7)) & 1;
}

static void put_t(mesh_tri *tri, uint32_t *nt, uint32_t a, uint32_t b, uint32_t c, uint32_t surf)
{
    mesh_tri *t = &tri[(*nt)++];
    t->v[0] = a;
    t->v[1] = b;
    t->v[2] = c;
    t->surf = surf;
}

/* The vertices of local vertex v's wall column (mesh_building's order:
 * the ring vertices at the top, then at the bottom, then the splits):
 * bottom, len - 2 splits from 'split' on, top. */
typedef struct wall_col {
    uint32_t bot, top, split, len;
} wall_col;

/* The column of local vertex v, vertices taken in increasing order: *k,
 * the first split at or after the last vertex's (from the building's
 * first), moved on to v's first (the splits are in order of vertex). */
static void col_next(const mesh *m, uint32_t b, uint32_t v, uint32_t ntot, uint32_t *k, wall_col *c)
{
    uint32_t f = m->bld[b].split_first, e = m->bld[b + 1].split_first, n = 0;
    while (*k < e && split_v(m, *k) < v)
        (*k)++;
    while (*k + n < e && split_v(m, *k + n) == v)
        n++;
    c->bot = ntot + v;
    c->top = v;
    c->split = 2 * ntot + (*k - f);
    c->len = n + 2;
}

/* Two triangles zipping columns L and R of two vertices each (no
 * splits), in put_walls' order. */
static void put_plain_wall(const wall_col *L, const wall_col *R, const double *xyz, mesh_tri *tri, uint32_t *nt,
                           uint32_t wid)
{
    if (xyz[3 * (size_t)R->top + 2] <= xyz[3 * (size_t)L->top + 2]) {
        put_t(tri, nt, L->bot, R->bot, R->top, wid);
        put_t(tri, nt, L->bot, R->top, L->top, wid);
    } else {
        put_t(tri, nt, L->bot, R->bot, L->top, wid);
        put_t(tri, nt, L->top, R->bot, R->top, wid);
    }
}

/* Vertex t (0: the bottom) of column c. */
static uint32_t col_at(const wall_col *c, uint32_t t)
{
    return t == 0 ? c->bot : t + 1 == c->len ? c->top : c->split + t - 1;
}

/* Columns L and R zipped: (L_i, R_j, R_j+1) and (L_i, R_j, L_i+1) are
 * counter-clockwise seen from outside (right of a->b); the lower next
 * vertex first, R's on a tie. Each column's vertex at hand (la, ra) and
 * next one (ln, rn; read only while there is one) carried. */
static void zip_columns(const wall_col *L, const wall_col *R, const double *xyz, mesh_tri *tri, uint32_t *nt,
                        uint32_t wid)
{
    uint32_t li = 0, ri = 0, la = L->bot, ra = R->bot, ln = col_at(L, 1), rn = col_at(R, 1);
    while (li + 1 < L->len || ri + 1 < R->len) {
        if (ri + 1 < R->len && (li + 1 >= L->len || xyz[3 * (size_t)rn + 2] <= xyz[3 * (size_t)ln + 2])) {
            put_t(tri, nt, la, ra, rn, wid);
            ra = rn;
            rn = col_at(R, ++ri + 1);
        } else {
            put_t(tri, nt, la, ra, ln, wid);
            la = ln;
            ln = col_at(L, ++li + 1);
        }
    }
}

/* Building b's splits (its columns' vertices between bottom and top), in
 * the order of the building's split list (by local vertex, then height),
 * from xyz vertex nv on. */
static uint32_t put_splits(const mesh *m, uint32_t b, double *xyz, uint32_t nv)
{
    const scene *s = m->s;
    const scene_building *bd = &s->bld[b];
    uint32_t r, i, off = 0, k = m->bld[b].split_first, e = m->bld[b + 1].split_first;
    for (r = 0; r < bd->ring_count && k < e; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        for (i = 0; i < rg->count; i++)
            for (; k < e && split_v(m, k) == off + i; k++, nv++) {
                xyz[3 * (size_t)nv] = s->pts[rg->first + i].x;
                xyz[3 * (size_t)nv + 1] = s->pts[rg->first + i].y;
                xyz[3 * (size_t)nv + 2] = m->split_z[k];
            }
        off += rg->count;
    }
    return nv;
}

/* Building b's walls (ntot ring vertices; its vertices written): each
 * footprint edge's two columns zipped (*nt triangles). */
static void put_walls(const mesh *m, uint32_t b, uint32_t ntot, const double *xyz, mesh_tri *tri, uint32_t *nt)
{
    const scene *s = m->s;
    const scene_building *bd = &s->bld[b];
    uint32_t r, i, off = 0, k = m->bld[b].split_first;
    for (r = 0; r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        wall_col first, L, R;
        if (rg->count == 0)
            continue;
        col_next(m, b, off, ntot, &k, &first);
        R = first;
        for (i = 0; i < rg->count; i++) {
            uint32_t wid = mesh_wall_id(s, rg->first + i);
            L = R; /* the last wall's right column */
            if (i + 1 < rg->count)
                col_next(m, b, off + i + 1, ntot, &k, &R);
            else
                R = first;
            if (wall_hidden(m, rg->first + i))
                continue;
            if (L.len == 2 && R.len == 2)
                put_plain_wall(&L, &R, xyz, tri, nt, wid);
            else
                zip_columns(&L, &R, xyz, tri, nt, wid);
        }
        off += rg->count;
    }
}

/* The ring vertices of building bd (ntot of them) at its height from xyz
 * vertex 0 on, and at its min_height from vertex ntot on. */
static void put_ring_verts(const scene *s, const scene_building *bd, uint32_t ntot, double *xyz)
{
    double *top = xyz, *bot = xyz + 3 * (size_t)ntot;
    uint32_t r, k;
    for (r = 0; r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        for (k = 0; k < rg->count; k++, top += 3, bot += 3) {
            top[0] = bot[0] = s->pts[rg->first + k].x;
            top[1] = bot[1] = s->pts[rg->first + k].y;
            top[2] = bd->height;
            bot[2] = bd->min_height;
        }
    }
}

/* Building bd's ring vertices. */
static uint32_t ring_total(const scene *s, const scene_building *bd)
{
    uint32_t r, n = 0;
    for (r = 0; r < bd->ring_count; r++)
        n += s->rings[bd->ring_first + r].count;
    return n;
}

void mesh_building(const mesh *m, uint32_t b, double *xyz, mesh_tri *tri)
{
    const scene *s = m->s;
    const scene_building *bd = &s->bld[b];
    uint32_t nt = 0, ntot, q, q0 = m->bld[b].roof_first, q1 = m->bld[b + 1].roof_first;
    uint32_t rid = mesh_roof_id(s, b), uid = mesh_under_id(s, b);
    ntot = ring_total(s, bd);
    put_ring_verts(s, bd, ntot, xyz);
    (void)put_splits(m, b, xyz, 2 * ntot);
    put_walls(m, b, ntot, xyz, tri, &nt);
    for (q = q0; q < q1; q += 3)
        put_t(tri, &nt, roof_at(m, q), roof_at(m, q + 1), roof_at(m, q + 2), rid);
    if (bd->min_height > 0)
        for (q = q0; q < q1; q += 3)
            put_t(tri, &nt, ntot + roof_at(m, q), ntot + roof_at(m, q + 2), ntot + roof_at(m, q + 1), uid);
}

/* Position of scene point t among the building's ring vertices, rings in order. */
static uint32_t local_index(const scene *s, const scene_building *bd, uint32_t t)
{
    uint32_t r, off = 0;
    for (r = 0; r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        if (t >= rg->first && t < rg->first + rg->count)
            return off + (t - rg->first);
        off += rg->count;
    }
    return 0;
}

/* The sorted, distinct column points: every ring vertex at its building's
 * bottom and top (scratch). */
static colpt *columns(arena *a, const scene *s, uint32_t *ncol)
{
    colpt *col = arena_scratch(a, arena_mul(2 * (size_t)s->npts + 1, sizeof *col), MESH_ALIGN);
    uint32_t b, r, i, n = 0, k = 0;
    if (!col)
        return NULL;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            for (i = 0; i < rg->count; i++) {
                vec2 p = s->pts[rg->first + i];
                col[n].x = p.x; col[n].y = p.y; col[n].z = bd->min_height; n++;
                col[n].x = p.x; col[n].y = p.y; col[n].z = bd->height; n++;
            }
        }
    }
    qsort(col, n, sizeof *col, cmp_colpt);
    for (i = 0; i < n; i++)
        if (k == 0 || cmp_colpt(&col[k - 1], &col[i]) != 0)
            col[k++] = col[i];
    *ncol = k;
    return col;
}

/* mesh.hidden from the walls' open heights (scratch released). */
static int mark_hidden(arena *a, mesh *m)
{
    const scene *s = m->s;
    arena_mark mk = arena_get_mark(a);
    double *zlo = arena_scratch(a, arena_mul((size_t)s->npts + 1, sizeof *zlo), 8);
    double *zhi = zlo ? arena_scratch(a, arena_mul((size_t)s->npts + 1, sizeof *zhi), 8) : NULL;
    uint32_t p;
    if (!zhi || party_wall_heights(a, s, zlo, zhi) != 0)
        return -1;
    for (p = 0; p < s->npts; p++)
        if (!(zhi[p] > zlo[p]))
            m->hidden[p >> 3] |= (uint8_t)(1u << (p & 7));
    release_scratch(a, &mk);
    return 0;
}

/* Count pass: each building's vertices and wall triangles, the splits,
 * the footprint vertices' buildings; *roof_cap: roof indices at most;
 * *maxring: most ring vertices (+ 2 a hole) of one building. */
static void count(mesh *m, const colpt *col, uint32_t ncol, uint32_t *nsplit, uint32_t *roof_cap,
                  uint32_t *maxring)
{
    const scene *s = m->s;
    uint32_t b, r, i, f;
    for (i = 0; m->pt_bld && i < s->npts; i++)
        m->pt_bld[i] = UINT32_MAX;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        mesh_bld *mb = &m->bld[b];
        uint32_t ntot = 0, nvb = 0, ntb = 0;
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            ntot += rg->count;
            for (i = 0; i < rg->count; i++) {
                uint32_t j = (i + 1) % rg->count;
                uint32_t ca = column(col, ncol, s->pts[rg->first + i], bd->min_height, bd->height, &f);
                uint32_t cb = column(col, ncol, s->pts[rg->first + j], bd->min_height, bd->height, &f);
                nvb += ca; /* its column once: bottom, splits, top (mesh_building) */
                if (!wall_hidden(m, rg->first + i))
                    ntb += ca + cb - 2;
                *nsplit += ca - 2;
                if (m->pt_bld)
                    m->pt_bld[rg->first + i] = b;
            }
        }
        mb->v_count = nvb;
        mb->t_count = ntb;  /* the roof's added in the fill pass */
        *roof_cap += 3 * (ntot + 2 * (bd->ring_count - 1));
        if (ntot + 2 * bd->ring_count > *maxring)
            *maxring = ntot + 2 * bd->ring_count;
        if (nvb > m->max_bld_verts)
            m->max_bld_verts = nvb;
    }
    m->split_verts = *nsplit;
}

/* Fill pass for building b: its splits, its roof (into roof, local
 * indices; returns how many, or -1 out of scratch) and its lit bits. */
static int fill(arena *a, mesh *m, uint32_t b, const colpt *col, uint32_t ncol, const lgrid *lg,
                uint32_t *tris, uint32_t *roof, uint32_t *nsplit)
{
    const scene *s = m->s;
    const scene_building *bd = &s->bld[b];
    double lo = bd->min_height, hi = bd->height, n[3], d;
    uint32_t r, i, k, off = 0, q;
    int nt;
    m->bld[b].split_first = *nsplit;
    for (r = 0; r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        for (i = 0; i < rg->count; i++) {
            vec2 pa = s->pts[rg->first + i], pb = s->pts[rg->first + (i + 1) % rg->count];
            uint32_t fa, ca = column(col, ncol, pa, lo, hi, &fa);
            for (k = 1; k + 1 < ca; k++) {
                if (m->split16)
                    m->split16[*nsplit] = (uint16_t)(off + i);
                else
                    m->split32[*nsplit] = off + i;
                m->split_z[*nsplit] = col[fa + k].z;
                (*nsplit)++;
            }
            wall_plane(pa, pb, n, &d);
            set_lit(m, mesh_wall_id(s, rg->first + i), surf_lit(s, lg, MESH_KIND_WALL, pa, pb, n, bd->box, lo, hi));
        }
        off += rg->count;
    }
    nt = mesh_triangulate(a, s, bd->ring_first, bd->ring_count, tris, &m->fallbacks, &m->bad_holes);
    if (nt < 0)
        return -1;
    for (q = 0; q < 3 * (uint32_t)nt; q++)
        roof[q] = local_index(s, bd, tris[q]);
    m->bld[b].t_count += (uint32_t)nt * (lo > 0 ? 2 : 1);
    n[0] = n[1] = 0.0;
    n[2] = 1.0;
    set_lit(m, mesh_roof_id(s, b), surf_lit(s, lg, MESH_KIND_ROOF, s->pts[0], s->pts[0], n, bd->box, hi, hi));
    n[2] = -1.0;
    set_lit(m, mesh_under_id(s, b),
            lo > 0 && surf_lit(s, lg, MESH_KIND_UNDER, s->pts[0], s->pts[0], n, bd->box, lo, lo));
    return nt;
}

/* The roof indices from scratch into the mesh, 16 bits when they fit. */
static int keep_roofs(arena *a, mesh *m, const uint32_t *roof, uint32_t n, uint32_t maxring)
{
    uint32_t q;
    if (maxring <= 65535u) {
        m->roof16 = arena_alloc(a, PLX_PART_FRAME, arena_mul(n + 1, sizeof *m->roof16), MESH_ALIGN);
        if (!m->roof16)
            return -1;
        for (q = 0; q < n; q++)
            m->roof16[q] = (uint16_t)roof[q];
    } else {
        m->roof32 = arena_alloc(a, PLX_PART_FRAME, arena_mul(n + 1, sizeof *m->roof32), MESH_ALIGN);
        if (!m->roof32)
            return -1;
        memcpy(m->roof32, roof, n * sizeof *roof);
    }
    return 0;
}

plx_status mesh_build(arena *a, const scene *s, mesh **out)
{
    arena_mark m0;
    mesh *m;
    colpt *col;
    uint32_t ncol = 0, b, nsplit = 0, roof_cap = 0, maxring = 0, nroof = 0, *tris, *roof;
    lgrid lg;
    size_t lo0;
    int ordered;

    if (!a || !s || !out)
        return PLX_E_INVALID;
    *out = NULL;
    m0 = arena_get_mark(a);
    lo0 = a->lo;
    m = arena_calloc(a, PLX_PART_FRAME, 1, sizeof *m, MESH_ALIGN);
    if (!m)
        return PLX_E_NOMEM;
    m->s = s;
    m->nbld = s->nbld;
    m->nsurf = 2 + s->npts + 2 * s->nbld;
    m->bld = arena_calloc(a, PLX_PART_FRAME, s->nbld + 1, sizeof *m->bld, MESH_ALIGN);
    ordered = rings_in_order(s);
    if (!ordered)
        m->pt_bld = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)s->npts + 1, sizeof *m->pt_bld), MESH_ALIGN);
    else if ((m->pt_hint = arena_alloc(a, PLX_PART_FRAME,
                                       arena_mul((size_t)s->npts / MESH_HINT_PTS + 2, sizeof *m->pt_hint),
                                       MESH_ALIGN)) != NULL)
        make_hints(m);
    m->lit = arena_calloc(a, PLX_PART_FRAME, m->nsurf / 8 + 1, 1, MESH_ALIGN);
    m->hidden = arena_calloc(a, PLX_PART_FRAME, s->npts / 8 + 1, 1, MESH_ALIGN);
    if (!m->bld || (!m->pt_bld && !m->pt_hint) || !m->lit || !m->hidden || mark_hidden(a, m) != 0)
        goto nomem;
    col = columns(a, s, &ncol);
    if (!col)
        goto nomem;
    count(m, col, ncol, &nsplit, &roof_cap, &maxring);
    if (maxring <= 65535u)
        m->split16 = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)nsplit + 1, sizeof *m->split16), MESH_ALIGN);
    else
        m->split32 = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)nsplit + 1, sizeof *m->split32), MESH_ALIGN);
    m->split_z = arena_alloc(a, PLX_PART_FRAME, arena_mul((size_t)nsplit + 1, sizeof *m->split_z), MESH_ALIGN);
    tris = arena_scratch(a, arena_mul(3 * (size_t)maxring, sizeof *tris), MESH_ALIGN);
    roof = arena_scratch(a, arena_mul((size_t)roof_cap + 1, sizeof *roof), MESH_ALIGN);
    if ((!m->split16 && !m->split32) || !m->split_z || !tris || !roof || lgrid_build(a, s, &lg) != 0)
        goto nomem;
    set_lit(m, MESH_SURF_GROUND, s->nlamps > 0);
    nsplit = 0;
    for (b = 0; b < s->nbld; b++) {
        int nt;
        m->bld[b].roof_first = nroof;
        nt = fill(a, m, b, col, ncol, &lg, tris, roof + nroof, &nsplit);
        if (nt < 0)
            goto nomem;
        nroof += 3 * (uint32_t)nt;
        m->nv += m->bld[b].v_count;
        m->ntri += m->bld[b].t_count;
        if (m->bld[b].t_count > m->max_bld_tris)
            m->max_bld_tris = m->bld[b].t_count;
    }
    m->bld[s->nbld].roof_first = nroof;
    m->bld[s->nbld].split_first = nsplit;
    if (keep_roofs(a, m, roof, nroof, maxring) != 0)
        goto nomem;
    release_scratch(a, &m0);
    m->bytes = a->lo - lo0;
    *out = m;
    return PLX_OK;

nomem:
    arena_release(a, &m0);
    return PLX_E_NOMEM;
}
