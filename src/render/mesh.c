/* mesh: the city as triangles (see mesh.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/mesh.h"
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

static void put_v(mesh *m, uint32_t *nv, double x, double y, double z)
{
    m->xyz[3 * *nv] = x;
    m->xyz[3 * *nv + 1] = y;
    m->xyz[3 * *nv + 2] = z;
    (*nv)++;
}

static void put_t(mesh *m, uint32_t a, uint32_t b, uint32_t c, uint32_t surf)
{
    mesh_tri *t = &m->tri[m->ntri++];
    t->v[0] = a;
    t->v[1] = b;
    t->v[2] = c;
    t->surf = surf;
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

plx_status mesh_build(arena *a, const scene *s, mesh **out)
{
    arena_mark m0;
    mesh *m;
    colpt *col;
    uint32_t ncol = 0, i, b, nv_cap = 0, nt_cap = 0, maxv = 0, *tris = NULL, maxring = 0;
    lgrid lg;
    size_t lo0;

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

    /* Column heights: every ring vertex at its building's bottom and top. */
    col = arena_scratch(a, arena_mul(2 * (size_t)s->npts + 1, sizeof *col), MESH_ALIGN);
    if (!col)
        goto nomem;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        uint32_t r, ntot = 0;
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            ntot += rg->count;
            for (i = 0; i < rg->count; i++) {
                vec2 p = s->pts[rg->first + i];
                col[ncol].x = p.x; col[ncol].y = p.y; col[ncol].z = bd->min_height; ncol++;
                col[ncol].x = p.x; col[ncol].y = p.y; col[ncol].z = bd->height; ncol++;
            }
        }
        if (ntot + 2 * bd->ring_count > maxring)
            maxring = ntot + 2 * bd->ring_count;
    }
    qsort(col, ncol, sizeof *col, cmp_colpt);
    {
        uint32_t k = 0;
        for (i = 0; i < ncol; i++)
            if (k == 0 || cmp_colpt(&col[k - 1], &col[i]) != 0)
                col[k++] = col[i];
        ncol = k;
    }

    /* Count. */
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        uint32_t r, ntot = 0, nvb = 0, ntb = 0, f;
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            ntot += rg->count;
            for (i = 0; i < rg->count; i++) {
                uint32_t j = (i + 1) % rg->count;
                uint32_t ca = column(col, ncol, s->pts[rg->first + i], bd->min_height, bd->height, &f);
                uint32_t cb = column(col, ncol, s->pts[rg->first + j], bd->min_height, bd->height, &f);
                nvb += ca + cb;
                ntb += ca + cb - 2;
                m->split_verts += ca - 2;
            }
        }
        nvb += ntot * (bd->min_height > 0 ? 2 : 1);
        ntb += (ntot + 2 * (bd->ring_count - 1)) * (bd->min_height > 0 ? 2 : 1);
        nv_cap += nvb;
        nt_cap += ntb;
        if (nvb > maxv)
            maxv = nvb;
    }
    m->max_bld_verts = maxv;
    m->xyz = arena_alloc(a, PLX_PART_FRAME, arena_mul(3 * (size_t)nv_cap, sizeof(double)), MESH_ALIGN);
    m->tri = arena_alloc(a, PLX_PART_FRAME, arena_mul(nt_cap, sizeof *m->tri), MESH_ALIGN);
    m->surf = arena_calloc(a, PLX_PART_FRAME, m->nsurf, sizeof *m->surf, MESH_ALIGN);
    m->bld = arena_calloc(a, PLX_PART_FRAME, s->nbld + 1, sizeof *m->bld, MESH_ALIGN);
    tris = arena_scratch(a, arena_mul(3 * (size_t)maxring, sizeof *tris), MESH_ALIGN);
    if (!m->xyz || !m->tri || !m->surf || !m->bld || !tris)
        goto nomem;
    if (lgrid_build(a, s, &lg) != 0)
        goto nomem;

    m->surf[MESH_SURF_GROUND].n[2] = 1.0;
    /* the constant; render.c shades ground pixels with scene_ground_albedo */
    m->surf[MESH_SURF_GROUND].albedo = s->ground_albedo;
    m->surf[MESH_SURF_GROUND].bld = UINT32_MAX;
    m->surf[MESH_SURF_GROUND].kind = MESH_KIND_GROUND;
    m->surf[MESH_SURF_GROUND].lit = s->nlamps > 0;

    /* Fill. */
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        mesh_bld *mb = &m->bld[b];
        uint32_t r, nv = m->nv, f, rid = mesh_roof_id(s, b), uid = mesh_under_id(s, b);
        double lo = bd->min_height, hi = bd->height;
        int nt;
        mb->v_first = m->nv;
        mb->t_first = m->ntri;
        mb->box[0] = bd->box[0]; mb->box[1] = bd->box[1]; mb->box[2] = lo;
        mb->box[3] = bd->box[2]; mb->box[4] = bd->box[3]; mb->box[5] = hi;
        mb->occluder = lo == 0.0 && bd->ring_count == 1;
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            for (i = 0; i < rg->count; i++) {
                uint32_t j = (i + 1) % rg->count, fa, fb, ca, cb, k, L0, R0, li = 0, ri = 0;
                uint32_t wid = mesh_wall_id(s, rg->first + i);
                vec2 pa = s->pts[rg->first + i], pb = s->pts[rg->first + j];
                mesh_surf *sf = &m->surf[wid];
                double dx = pb.x - pa.x, dy = pb.y - pa.y, len = sqrt(dx * dx + dy * dy);
                ca = column(col, ncol, pa, lo, hi, &fa);
                cb = column(col, ncol, pb, lo, hi, &fb);
                L0 = nv;
                for (k = 0; k < ca; k++)
                    put_v(m, &nv, pa.x, pa.y, col[fa + k].z);
                R0 = nv;
                for (k = 0; k < cb; k++)
                    put_v(m, &nv, pb.x, pb.y, col[fb + k].z);
                /* zip the columns; (L_i, R_j, R_j+1) and (L_i, R_j, L_i+1)
                 * are counter-clockwise seen from outside (right of a->b) */
                while (li + 1 < ca || ri + 1 < cb) {
                    if (ri + 1 < cb && (li + 1 >= ca || col[fb + ri + 1].z <= col[fa + li + 1].z)) {
                        put_t(m, L0 + li, R0 + ri, R0 + ri + 1, wid);
                        ri++;
                    } else {
                        put_t(m, L0 + li, R0 + ri, L0 + li + 1, wid);
                        li++;
                    }
                }
                sf->kind = MESH_KIND_WALL;
                sf->bld = b;
                sf->albedo = bd->albedo;
                if (len > 0) {
                    sf->n[0] = dy / len;
                    sf->n[1] = -dx / len;
                }
                sf->d = sf->n[0] * pa.x + sf->n[1] * pa.y;
                sf->lit = (uint8_t)surf_lit(s, &lg, MESH_KIND_WALL, pa, pb, sf->n, bd->box, lo, hi);
            }
        }
        m->nv = nv;
        /* roof (and underside) */
        nt = mesh_triangulate(a, s, bd->ring_first, bd->ring_count, tris, &m->fallbacks, &m->bad_holes);
        if (nt < 0)
            goto nomem;
        {
            uint32_t base = m->nv, k, q;
            for (r = 0; r < bd->ring_count; r++) {
                const scene_ring *rg = &s->rings[bd->ring_first + r];
                for (k = 0; k < rg->count; k++)
                    put_v(m, &nv, s->pts[rg->first + k].x, s->pts[rg->first + k].y, hi);
            }
            /* tris hold scene.pts indices: make them local to the roof */
            for (q = 0; q < 3 * (uint32_t)nt; q++)
                tris[q] = local_index(s, bd, tris[q]);
            for (q = 0; q < (uint32_t)nt; q++)
                put_t(m, base + tris[3 * q], base + tris[3 * q + 1], base + tris[3 * q + 2], rid);
            if (lo > 0) {
                uint32_t ubase = nv;
                for (r = 0; r < bd->ring_count; r++) {
                    const scene_ring *rg = &s->rings[bd->ring_first + r];
                    for (k = 0; k < rg->count; k++)
                        put_v(m, &nv, s->pts[rg->first + k].x, s->pts[rg->first + k].y, lo);
                }
                for (q = 0; q < (uint32_t)nt; q++)
                    put_t(m, ubase + tris[3 * q], ubase + tris[3 * q + 2], ubase + tris[3 * q + 1], uid);
            }
            m->nv = nv;
        }
        {
            mesh_surf *sf = &m->surf[rid];
            sf->n[2] = 1.0;
            sf->d = hi;
            sf->albedo = bd->albedo;
            sf->bld = b;
            sf->kind = MESH_KIND_ROOF;
            sf->lit = (uint8_t)surf_lit(s, &lg, MESH_KIND_ROOF, s->pts[0], s->pts[0], sf->n, bd->box, hi, hi);
            sf = &m->surf[uid];
            sf->n[2] = -1.0;
            sf->d = -lo;
            sf->albedo = bd->albedo;
            sf->bld = b;
            sf->kind = MESH_KIND_UNDER;
            sf->lit = lo > 0 && surf_lit(s, &lg, MESH_KIND_UNDER, s->pts[0], s->pts[0], sf->n, bd->box, lo, lo);
        }
        mb->v_count = m->nv - mb->v_first;
        mb->t_count = m->ntri - mb->t_first;
        (void)f;
    }
    release_scratch(a, &m0);
    m->bytes = a->lo - lo0;
    *out = m;
    return PLX_OK;

nomem:
    arena_release(a, &m0);
    return PLX_E_NOMEM;
}
