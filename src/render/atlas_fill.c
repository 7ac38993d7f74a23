/* atlas_fill: the radiance atlas's values (atlas_fill.h). */
#include <math.h>
#include <string.h>

#include "render/atlas_fill.h"
#include "render/texel.h"
#include "light/illuminance.h"
#include "base/geom.h"

#define PI 3.14159265358979323846
#define GROUND_OUT 1e-3 /* m: a ground vertex under a footprint moves this far out of it */

/* ---- a vertex's point ------------------------------------------------------------ */

/* The nearest point to p on building b's rings, and the outward unit
 * normal of the edge it lies on. */
static void nearest_boundary(const scene *s, uint32_t b, vec2 p, vec2 *q, vec2 *out)
{
    const scene_building *bd = &s->bld[b];
    double best = INFINITY;
    uint32_t r, k;
    for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[r];
        for (k = 0; k < rg->count; k++) {
            vec2 a = s->pts[rg->first + k], c = s->pts[rg->first + (k + 1) % rg->count];
            double ex = c.x - a.x, ey = c.y - a.y, l2 = ex * ex + ey * ey, t, dx, dy, d2, l;
            t = l2 > 0.0 ? ((p.x - a.x) * ex + (p.y - a.y) * ey) / l2 : 0.0;
            t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
            dx = a.x + t * ex - p.x;
            dy = a.y + t * ey - p.y;
            d2 = dx * dx + dy * dy;
            if (!(d2 < best))
                continue;
            best = d2;
            q->x = a.x + t * ex;
            q->y = a.y + t * ey;
            l = sqrt(l2);
            /* outer rings counter-clockwise, holes clockwise: out of the solid is right */
            out->x = l > 0.0 ? ey / l : 0.0;
            out->y = l > 0.0 ? -ex / l : 0.0;
        }
    }
}

/* Whether p lies in building b's footprint: strictly inside (in > 0) or
 * also on its boundary (in == 0 counts the boundary in). */
static int in_footprint(const scene *s, uint32_t b, vec2 p, int strict)
{
    const scene_building *bd = &s->bld[b];
    const scene_ring *rg = &s->rings[bd->ring_first];
    uint32_t r;
    int w;
    if (p.x < bd->box[0] || p.x > bd->box[2] || p.y < bd->box[1] || p.y > bd->box[3])
        return 0;
    w = geom_point_in_ring(p, &s->pts[rg->first], rg->count);
    if (w == GEOM_OUTSIDE || (strict && w == GEOM_ON_BOUNDARY))
        return 0;
    for (r = bd->ring_first + 1; r < bd->ring_first + bd->ring_count; r++) {
        int h = geom_point_in_ring(p, &s->pts[s->rings[r].first], s->rings[r].count);
        if (h == GEOM_INSIDE || (strict && h == GEOM_ON_BOUNDARY))
            return 0;
    }
    return 1;
}

/* A building standing on the ground whose footprint holds p strictly
 * (the lowest index), UINT32_MAX for none; from the light's building grid. */
static uint32_t solid_at(const light *L, vec2 p)
{
    const bucketgrid *g = &L->bgrid;
    uint32_t cell, k;
    if (L->s->nbld == 0 || g->nx == 0)
        return UINT32_MAX;
    cell = bucketgrid_cell(g, p.x, p.y);
    for (k = g->start[cell]; k < g->start[cell + 1]; k++) {
        uint32_t b = g->item[k];
        if (L->s->bld[b].min_height == 0.0 && in_footprint(L->s, b, p, 1))
            return b;
    }
    return UINT32_MAX;
}

/* The nearest point to p on an edge of a building within radius rad of p
 * (the light's building grid), moved GROUND_OUT out of it along the
 * edge's outward normal, that lies strictly inside no solid standing on
 * the ground: visible ground. 1 with *q set, 0 when there is none. */
static int open_ground_near(const light *L, vec2 p, double rad, vec2 *q)
{
    const scene *s = L->s;
    const bucketgrid *g = &L->bgrid;
    double box[4], best = INFINITY;
    uint32_t r0[4], x, y, k, r, e;
    int found = 0;
    box[0] = p.x - rad;
    box[1] = p.y - rad;
    box[2] = p.x + rad;
    box[3] = p.y + rad;
    bucketgrid_range(g, box, r0);
    for (y = r0[1]; y <= r0[3]; y++)
        for (x = r0[0]; x <= r0[2]; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                const scene_building *bd = &s->bld[g->item[k]];
                if (bd->box[0] > box[2] || bd->box[2] < box[0] || bd->box[1] > box[3] || bd->box[3] < box[1])
                    continue;
                for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++)
                    for (e = 0; e < s->rings[r].count; e++) {
                        vec2 a = s->pts[s->rings[r].first + e];
                        vec2 b = s->pts[s->rings[r].first + (e + 1) % s->rings[r].count];
                        double ex = b.x - a.x, ey = b.y - a.y, l2 = ex * ex + ey * ey, t, l, d2;
                        vec2 c;
                        if (!(l2 > 0.0))
                            continue;
                        t = ((p.x - a.x) * ex + (p.y - a.y) * ey) / l2;
                        t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
                        l = sqrt(l2);
                        c.x = a.x + t * ex + GROUND_OUT * ey / l;
                        c.y = a.y + t * ey - GROUND_OUT * ex / l;
                        d2 = (c.x - p.x) * (c.x - p.x) + (c.y - p.y) * (c.y - p.y);
                        if (d2 < best && d2 <= rad * rad && solid_at(L, c) == UINT32_MAX) {
                            best = d2;
                            *q = c;
                            found = 1;
                        }
                    }
            }
    return found; /* within rad: no building outside the box has a point nearer */
}

/* The footprint edge of wall chart c (its first point and the next of
 * its ring): wall chart k of the atlas is the wall over footprint point
 * k (mesh_wall_id), found through its building's rings; a copy of a
 * chart (the tests') is matched instead by the edge of its building that
 * starts at the chart's origin and runs along its direction (atlas.c's
 * wall_chart: o is the edge's first point, e its unit direction rounded
 * to float). 0 when there is none. */
static int wall_line(const atlas *A, const atlas_chart *c, vec2 ends[2])
{
    const scene *s = A->s;
    const scene_building *bd = &s->bld[c->bld];
    uintptr_t base = (uintptr_t)A->chart, at = (uintptr_t)c;
    uint32_t r, k;
    int own = at >= base && at - base < (uintptr_t)A->nsurf * sizeof *A->chart &&
              (at - base) % sizeof *A->chart == 0;
    uint32_t pt = own ? (uint32_t)((at - base) / sizeof *A->chart) : 0u;
    for (r = bd->ring_first; r < bd->ring_first + bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[r];
        if (own) {
            if (pt < rg->first || pt - rg->first >= rg->count)
                continue;
            ends[0] = s->pts[pt];
            ends[1] = s->pts[rg->first + (pt - rg->first + 1) % rg->count];
            return ends[0].x == c->o[0] && ends[0].y == c->o[1] &&
                   (ends[1].x != ends[0].x || ends[1].y != ends[0].y);
        }
        for (k = 0; k < rg->count; k++) {
            vec2 a = s->pts[rg->first + k], q = s->pts[rg->first + (k + 1) % rg->count];
            double dx = q.x - a.x, dy = q.y - a.y, len = sqrt(dx * dx + dy * dy);
            if (a.x == c->o[0] && a.y == c->o[1] && len > 0.0 && fabs(dx / len - c->e[0]) <= 1e-6 &&
                fabs(dy / len - c->e[1]) <= 1e-6) {
                ends[0] = a;
                ends[1] = q;
                return 1;
            }
        }
    }
    return 0;
}

/* A wall vertex's point P moved onto its footprint edge's line (ends),
 * and the edge's outward normal, both in double: the chart's direction
 * is a float (atlas.h), so o + u e drifts off the wall by up to its length
 * times 2^-24 (2.4 um on a 40 m wall at 10 degrees), and a point that far
 * inside the building is in its own wall's shadow (the visibility's
 * tolerance is 1e-9 m): most vertices of such a wall were dark. Only the
 * distance along the edge is kept from P, within the edge. */
static void wall_site(const vec2 ends[2], double P[3], double n[3])
{
    double dx = ends[1].x - ends[0].x, dy = ends[1].y - ends[0].y, l2 = dx * dx + dy * dy, t, len;
    t = ((P[0] - ends[0].x) * dx + (P[1] - ends[0].y) * dy) / l2;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t; /* the last vertex, (nu - 1) tu with a float tu, can pass the corner:
                                              inside the building at a reflex corner */
    P[0] = ends[0].x + t * dx;
    P[1] = ends[0].y + t * dy;
    len = sqrt(l2);
    n[0] = dy / len; /* outer rings counter-clockwise, holes clockwise: out is right */
    n[1] = -dx / len;
    n[2] = 0.0;
    /* out by geom_round_margin: a + t d rounds to about 1e-9 m far from
     * the origin, the visibility's tolerance (pixel_hit.c moves a frame's
     * wall points alike) */
    t = geom_round_margin(P[0], P[1]);
    P[0] += t * n[0];
    P[1] += t * n[1];
}

/* atlas_vertex_site with the wall's edge found already (NULL: not a wall,
 * or none found). */
static void vertex_site(const atlas *A, const light *L, const atlas_chart *c, const vec2 *ends, uint32_t i,
                        uint32_t j, double P[3], double n[3])
{
    vec2 p, q, o;
    atlas_vertex_point(c, i, j, P);
    atlas_chart_normal(c, n);
    if (ends)
        wall_site(ends, P, n);
    p.x = P[0];
    p.y = P[1];
    if ((c->kind == ATLAS_ROOF || c->kind == ATLAS_UNDER) && !in_footprint(A->s, c->bld, p, 0)) {
        nearest_boundary(A->s, c->bld, p, &q, &o);
        P[0] = q.x;
        P[1] = q.y;
    } else if (c->kind == ATLAS_GROUND) {
        uint32_t b = solid_at(L, p);
        if (b != UINT32_MAX) {
            double rad;
            nearest_boundary(A->s, b, p, &q, &o);
            q.x += GROUND_OUT * o.x;
            q.y += GROUND_OUT * o.y;
            /* that point may lie in another solid (a wall shared by two
             * buildings, a narrow reflex corner): then the nearest open
             * ground around, searched ever farther */
            rad = 2.0 * sqrt((q.x - p.x) * (q.x - p.x) + (q.y - p.y) * (q.y - p.y)) + 1.0;
            while (solid_at(L, q) != UINT32_MAX && rad <= 256.0) {
                if (open_ground_near(L, p, rad, &q))
                    break;
                rad *= 2.0;
            }
            P[0] = q.x;
            P[1] = q.y;
        }
    }
}

void atlas_vertex_site(const atlas *A, const light *L, const atlas_chart *c, uint32_t i, uint32_t j, double P[3],
                       double n[3])
{
    vec2 ends[2];
    int wall = c->kind == ATLAS_WALL && wall_line(A, c, ends);
    vertex_site(A, L, c, wall ? ends : NULL, i, j, P, n);
}

/* ---- values ------------------------------------------------------------------------ */

/* The surface id of a chart (mesh.h; MESH_SURF_GROUND for a tile). */
static uint32_t chart_sid(const atlas *A, const atlas_chart *c)
{
    if (c->kind == ATLAS_GROUND)
        return MESH_SURF_GROUND;
    return (uint32_t)(c - A->chart) + 2u;
}

/* Vertices between records along a chart's sides. */
static uint32_t rec_every(const atlas_chart *c)
{
    uint32_t k = c->fine ? ATLAS_IND_EVERY : ATLAS_IND_EVERY / ATLAS_COARSE;
    return k < 1 ? 1 : k;
}

/* Records along a side of n vertices: every k-th vertex and the last. */
static uint32_t rec_count(uint32_t n, uint32_t k)
{
    return (n - 1 + k - 1) / k + 1;
}

static uint32_t rec_vertex(uint32_t r, uint32_t n, uint32_t k)
{
    uint32_t v = r * k;
    return v < n - 1 ? v : n - 1;
}

size_t atlas_fill_records(const atlas *A)
{
    atlas_chart g;
    size_t most = 0, n;
    uint32_t k;
    for (k = 0; k < A->nsurf; k++) {
        const atlas_chart *c = &A->chart[k];
        if (c->kind == ATLAS_NONE)
            continue;
        n = (size_t)rec_count(c->nu, rec_every(c)) * rec_count(c->nv, rec_every(c));
        most = n > most ? n : most;
    }
    memset(&g, 0, sizeof g);
    g.nu = g.nv = ATLAS_BLOCK + 1;
    for (k = 0; k < 2; k++) { /* a coarse block and a fine one */
        g.fine = (uint8_t)k;
        n = (size_t)rec_count(g.nu, rec_every(&g)) * rec_count(g.nv, rec_every(&g));
        most = n > most ? n : most;
    }
    return 3 * most;
}

/* The chart's indirect records (rec: 3 doubles each, row by row). */
static void chart_records(const atlas *A, atlas_worker *w, const atlas_chart *c)
{
    uint32_t k = rec_every(c), nru = rec_count(c->nu, k), nrv = rec_count(c->nv, k), a, b;
    uint32_t sid = chart_sid(A, c);
    vec2 ends[2];
    int wall = c->kind == ATLAS_WALL && wall_line(A, c, ends);
    for (b = 0; b < nrv; b++)
        for (a = 0; a < nru; a++) {
            double P[3], n[3], *e = &w->rec[3 * ((size_t)b * nru + a)];
            vertex_site(A, w->lt, c, wall ? ends : NULL, rec_vertex(a, c->nu, k), rec_vertex(b, c->nv, k), P, n);
            w->ind(w->ind_user, c, sid, P, n, e);
        }
}

/* Record index and weight of vertex i along a side of n vertices. */
static void rec_pos(uint32_t i, uint32_t n, uint32_t k, uint32_t nr, uint32_t *r, double *f)
{
    uint32_t lo, hi;
    *r = i / k;
    if (*r >= nr - 1)
        *r = nr - 2;
    lo = rec_vertex(*r, n, k);
    hi = rec_vertex(*r + 1, n, k);
    *f = hi > lo ? (double)(i - lo) / (double)(hi - lo) : 0.0;
}

/* E_indirect at vertex (i, j) from the chart's records. */
static void rec_at(const atlas_worker *w, const atlas_chart *c, uint32_t i, uint32_t j, double e[3])
{
    uint32_t k = rec_every(c), nru = rec_count(c->nu, k), nrv = rec_count(c->nv, k), a, b, q;
    double fu, fv;
    const double *r00, *r10, *r01, *r11;
    rec_pos(i, c->nu, k, nru, &a, &fu);
    rec_pos(j, c->nv, k, nrv, &b, &fv);
    r00 = &w->rec[3 * ((size_t)b * nru + a)];
    r10 = r00 + 3;
    r01 = r00 + 3 * (size_t)nru;
    r11 = r01 + 3;
    for (q = 0; q < 3; q++)
        e[q] = (1.0 - fv) * ((1.0 - fu) * r00[q] + fu * r10[q]) + fv * ((1.0 - fu) * r01[q] + fu * r11[q]);
}

/* The albedo per channel at a vertex's point. */
static void site_albedo(const atlas *A, const atlas_chart *c, const double P[3], double a[3])
{
    if (c->kind == ATLAS_GROUND) {
        scene_ground_albedo(A->s, P[0], P[1], a);
        return;
    }
    a[0] = a[1] = a[2] = A->s->bld[c->bld].albedo;
}

/* One chart, row by row: direct light at every vertex (none on coarse
 * ground tiles: no lamp reaches them), indirect from the records. */
static void fill_chart(const atlas *A, atlas_worker *w, const atlas_chart *c)
{
    uint32_t i, j, q;
    int direct = !(c->kind == ATLAS_GROUND && !c->fine);
    vec2 ends[2];
    int wall = c->kind == ATLAS_WALL && wall_line(A, c, ends);
    if (w->ind)
        chart_records(A, w, c);
    for (j = 0; j < c->nv; j++) {
        uint32_t *t = &A->tex[c->first + (size_t)j * c->nu];
        for (i = 0; i < c->nu; i++) {
            double P[3], n[3], E = 0.0, rgb[3] = { 0.0, 0.0, 0.0 }, ind[3] = { 0.0, 0.0, 0.0 }, a[3];
            vertex_site(A, w->lt, c, wall ? ends : NULL, i, j, P, n);
            if (direct && light_illuminance(w->lt, P, n, &E, rgb) != PLX_OK)
                rgb[0] = rgb[1] = rgb[2] = 0.0;
            if (w->ind)
                rec_at(w, c, i, j, ind);
            site_albedo(A, c, P, a);
            for (q = 0; q < 3; q++)
                rgb[q] = a[q] / PI * (rgb[q] + ind[q]);
            t[i] = texel_pack(rgb[0], rgb[1], rgb[2]);
        }
    }
}

typedef struct fill_job {
    atlas *A;
    atlas_worker *w;
    const atlas_par *par;
    const uint32_t *items;  /* the items to fill (atlas.h), or NULL: every one not done */
    uint32_t nitems;
    uint32_t nsj;           /* NULL items: jobs of surface charts (ATLAS_JOB_CHARTS each); a row of tiles each after */
    uint32_t njobs;
} fill_job;

/* Item it (atlas.h's numbering) unless already filled. */
static void fill_item(const atlas *A, atlas_worker *w, uint32_t it)
{
    atlas_chart c;
    uint32_t b, tile;
    if (it < A->nsurf) {
        if (!atlas_filled(A->cdone[it]) && A->chart[it].kind != ATLAS_NONE)
            fill_chart(A, w, &A->chart[it]);
        return;
    }
    b = it - A->nsurf;
    tile = b / (ATLAS_TB * ATLAS_TB);
    if (atlas_filled(A->gdone[b]) || A->gfirst[b] == ATLAS_NOVERT)
        return;
    b %= ATLAS_TB * ATLAS_TB;
    atlas_ground_block(A, tile % A->gx, tile / A->gx, b % ATLAS_TB, b / ATLAS_TB, &c);
    fill_chart(A, w, &c);
}

static void fill_run(void *arg, int worker, uint32_t k)
{
    fill_job *jb = arg;
    const atlas *A = jb->A;
    uint32_t i, i0, i1;
    if (jb->items) {
        i0 = k * ATLAS_JOB_CHARTS;
        i1 = i0 + ATLAS_JOB_CHARTS < jb->nitems ? i0 + ATLAS_JOB_CHARTS : jb->nitems;
        for (i = i0; i < i1; i++)
            fill_item(A, &jb->w[worker], jb->items[i]);
    } else if (k < jb->nsj) {
        i1 = (k + 1) * ATLAS_JOB_CHARTS < A->nsurf ? (k + 1) * ATLAS_JOB_CHARTS : A->nsurf;
        for (i = k * ATLAS_JOB_CHARTS; i < i1; i++)
            fill_item(A, &jb->w[worker], i);
    } else {
        uint32_t ty = k - jb->nsj, per = ATLAS_TB * ATLAS_TB;
        for (i = 0; i < A->gx * per; i++)
            fill_item(A, &jb->w[worker], atlas_block_item(A, ty * A->gx, 0) + i);
    }
    if (jb->par && jb->par->progress.fn)
        jb->par->progress.fn(jb->par->progress.ctx, ATLAS_STAGE, 1, jb->njobs);
}

/* Whether the n values from first are all 0. */
static int all_zero(const atlas *A, uint32_t first, size_t n)
{
    uint32_t any = 0;
    size_t k;
    for (k = 0; k < n; k++)
        any |= A->tex[first + k];
    return any == 0;
}

/* Marks item it filled, ATLAS_DARK when its values are all 0 (this
 * thread, after the workers). */
static void mark_done(atlas *A, uint32_t it)
{
    uint8_t *d;
    int dark;
    if (it < A->nsurf) {
        const atlas_chart *c = &A->chart[it];
        if (c->kind == ATLAS_NONE)
            return;
        d = &A->cdone[it];
        dark = all_zero(A, c->first, (size_t)c->nu * c->nv);
    } else {
        uint32_t first = A->gfirst[it - A->nsurf];
        if (first == ATLAS_NOVERT)
            return;
        d = &A->gdone[it - A->nsurf];
        dark = all_zero(A, first, (ATLAS_BLOCK + 1) * (ATLAS_BLOCK + 1));
    }
    if (!atlas_filled(*d) && A->todo > 0)
        A->todo--;
    *d = dark ? ATLAS_DARK : ATLAS_FILLED;
}

static plx_status run_fill(atlas *A, atlas_worker *w, int nw, const atlas_par *par, const uint32_t *items, uint32_t n)
{
    fill_job jb;
    uint32_t k;
    int told = par && par->progress.fn;
    if (!A || !w || nw < 1 || !w[0].lt)
        return PLX_E_INVALID;
    jb.A = A;
    jb.w = w;
    jb.par = par;
    jb.items = items;
    jb.nitems = n;
    jb.nsj = (A->nsurf + ATLAS_JOB_CHARTS - 1) / ATLAS_JOB_CHARTS;
    jb.njobs = items ? (n + ATLAS_JOB_CHARTS - 1) / ATLAS_JOB_CHARTS : jb.nsj + A->gy;
    if (told)
        par->progress.fn(par->progress.ctx, ATLAS_STAGE, 0, jb.njobs);
    if (nw < 2 || jb.njobs < 2 || !par || !par->par || par->par(par->ctx, nw, jb.njobs, fill_run, &jb) != 0)
        for (k = 0; k < jb.njobs; k++)
            fill_run(&jb, 0, k);
    if (told)
        par->progress.fn(par->progress.ctx, ATLAS_STAGE, 0, 0);
    if (items) {
        for (k = 0; k < n; k++)
            mark_done(A, items[k]);
    } else {
        uint32_t nb = A->gx * A->gy * ATLAS_TB * ATLAS_TB;
        for (k = 0; k < A->nsurf + nb; k++)
            mark_done(A, k);
    }
    A->with_ind = w[0].ind != NULL;
    return PLX_OK;
}

plx_status atlas_fill(atlas *A, atlas_worker *w, int nw, const atlas_par *par)
{
    return run_fill(A, w, nw, par, NULL, 0);
}

plx_status atlas_fill_items(atlas *A, atlas_worker *w, int nw, const atlas_par *par, const uint32_t *items, uint32_t n)
{
    return run_fill(A, w, nw, par, items, n);
}
