/* shade_tiles: the shading pass, by tiles of RENDER_TILE x RENDER_TILE pixels
 * (each pixel's hit point, the tile's lamps, the illuminance). */
#include <math.h>
#include <string.h>

#include "base/plx_assert.h"
#include "base/bucketgrid.h"
#include "scene/photometry.h"
#include "light/illuminance.h"
#include "light/litregion.h"
#include "render/render_int.h"

/* Lamps whose reach sphere meets box bx (minx, miny, minz, maxx, maxy,
 * maxz), in lamp index order, into tl (at most RENDER_TILE_LAMPS);
 * returns their number, or -1 when there are more (the caller then takes
 * the light module's own lamp walk). A lamp in several grid cells is
 * taken once (looked up in the list so far). */
static int tile_lamps(const render *r, const double bx[6], uint32_t *tl)
{
    const bucketgrid *g = &r->lt->lgrid;
    const scene *s = r->s;
    uint32_t c0, c1, cx0, cx1, cy0, cy1, cx, cy, k;
    int n = 0, i, j;
    if (s->nlamps == 0 || g->nx == 0)
        return 0;
    c0 = bucketgrid_cell(g, bx[0], bx[1]);
    c1 = bucketgrid_cell(g, bx[3], bx[4]);
    cx0 = c0 % g->nx;
    cy0 = c0 / g->nx;
    cx1 = c1 % g->nx;
    cy1 = c1 / g->nx;
    if ((uint64_t)(cx1 - cx0 + 1) * (cy1 - cy0 + 1) > 16)
        return -1;
    for (cy = cy0; cy <= cy1; cy++)
        for (cx = cx0; cx <= cx1; cx++) {
            uint32_t cell = cy * g->nx + cx;
            PLX_ASSERT(cx < g->nx && cy < g->ny); /* a cell of the lamp grid */
            for (k = g->start[cell]; k < g->start[cell + 1]; k++) {
                uint32_t l = g->item[k];
                const scene_lamp *lp = &s->lamps[l];
                PLX_ASSERT(l < s->nlamps);
                double dx, dy, dz;
                if (!(lp->radius > 0.0) || !(lp->intensity > 0.0))
                    continue;
                dx = fmax(0.0, fmax(bx[0] - lp->x, lp->x - bx[3]));
                dy = fmax(0.0, fmax(bx[1] - lp->y, lp->y - bx[4]));
                dz = fmax(0.0, fmax(bx[2] - lp->z, lp->z - bx[5]));
                /* the term is 0 from d >= R on (light.h, SPEC §2): a margin keeps rounding out */
                if (!(dx * dx + dy * dy + dz * dz < lp->radius * lp->radius * (1.0 + 1e-9)))
                    continue;
                for (i = 0; i < n && tl[i] != l; i++)
                    ;
                if (i < n)
                    continue;
                if (n == RENDER_TILE_LAMPS)
                    return -1;
                tl[n++] = l;
            }
        }
    /* lamp index order (the order of the light module's walk) */
    for (i = 1; i < n; i++) {
        uint32_t v = tl[i];
        for (j = i - 1; j >= 0 && tl[j] > v; j--)
            tl[j + 1] = tl[j];
        tl[j + 1] = v;
    }
    return n;
}

/* The sector of pseudo-angle a (light.h: sector i starts at sec_ang[i];
 * angles before sec_ang[0] belong to the last, wrapping sector). */
static uint32_t tile_find_sector(const double *ang, uint32_t nsec, double a)
{
    uint32_t lo = 0, hi = nsec;
    if (a < ang[0])
        return nsec - 1;
    while (hi - lo > 1) {
        uint32_t mid = (lo + hi) / 2;
        if (ang[mid] <= a)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* SPEC §2's term of lamp lp at P facing n, without visibility: the light
 * module's formula (light.c), operation for operation. */
static double lamp_term(const scene_lamp *lp, const double P[3], const double n[3])
{
    double v[3], d2, d, x, x2, c, w, cw;
    v[0] = lp->x - P[0];
    v[1] = lp->y - P[1];
    v[2] = lp->z - P[2];
    d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if (d2 == 0.0 || !(lp->radius > 0.0) || !(d2 < lp->radius * lp->radius))
        return 0.0;
    d = sqrt(d2);
    x = d / lp->radius;
    x2 = x * x;
    c = 1.0 - x2 * x2;
    if (c <= 0.0)
        return 0.0;
    w = c * c;
    cw = (n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / d;
    if (!(cw > 0.0))
        return 0.0;
    if (lp->photometry) {
        double u[3];
        u[0] = -v[0] / d;
        u[1] = -v[1] / d;
        u[2] = -v[2] / d;
        return lamp_intensity(lp, u) * cw / d2 * w;
    }
    return lp->intensity * cw / d2 * w;
}

/* Is every point whose ground projection lies in the convex hull of the nc
 * points c (2 or 4: a segment or a box, none of them at the lamp's ground
 * point O) visible from lamp l for sure? Through the lamp's sector index
 * (light.h, litregion.c's light_region_visible): along w = P' - O a band
 * covers t from t_lo = c / cross(w, e) (its lo line) on, and stops the
 * segment O->P only if (min(t_hi, t2) - max(t_lo, t1)) |P - L| > 1e-9 with
 * t2 <= 1; the term of lamp l is 0 unless |P - L| < R. So a band with
 * t_lo >= 1 - eta/2, eta = 1e-9 / R, stops nothing at P -- neither a
 * building beyond P nor the wall P lies on (t_lo = 1 there). With
 * q(w) = cross(w, e) / c = 1 / t_lo, linear in w: if 0 < q <= 1 + eta/4 at
 * every corner of the hull, the same holds over the hull, so t_lo >=
 * 1 - eta/4 at every point of it (rounding of t_lo, ~1e-15 relative, is
 * far inside the remaining eta/4). The bands looked at are those of every
 * sector meeting the pseudo-angle range of the corners (the hull subtends
 * less than 180 degrees from O: checked). Returns 0 when unsure: no
 * region, a hull around O, a band from O itself (no lo line). */
static int hull_visible(render *r, uint32_t l, const double (*c)[2], int nc, int ro)
{
    light *L = r->lt;
    const lit_region *rg = NULL;
    double wx[4], wy[4], base = 0.0, lo = 0.0, hi = 0.0, qmax, span;
    uint32_t i0, i1, i, k, seen;
    int j, all = 0;
    if (L->pool_cap == 0 || !(r->s->lamps[l].radius > 0.0))
        return 0;
    if (ro)
        rg = L->ent[l].reg;   /* read-only: the cache as it is (no LRU move) */
    else if (light_region_index(L, l, &rg) != PLX_OK)
        rg = NULL;
    if (!rg || rg->nsec == 0)
        return 0;
    qmax = 1.0 + 0.25e-9 / r->s->lamps[l].radius;
    for (j = 0; j < nc; j++) {
        double d;
        wx[j] = c[j][0] - rg->o[0];
        wy[j] = c[j][1] - rg->o[1];
        if (wx[j] == 0.0 && wy[j] == 0.0)
            return 0;
        if (j == 0) {
            base = light_pseudo_angle(wx[0], wy[0]);
            continue;
        }
        d = light_pseudo_angle(wx[j], wy[j]) - base;
        if (d > 2.0) d -= 4.0;
        if (d <= -2.0) d += 4.0;
        lo = d < lo ? d : lo;
        hi = d > hi ? d : hi;
    }
    /* O outside the hull: for a box, not inside it; for a segment, not on
     * its line (checked by the spans below: a hull around O spans 2 or more) */
    if (nc == 4 && rg->o[0] >= c[0][0] && rg->o[0] <= c[3][0] && rg->o[1] >= c[0][1] && rg->o[1] <= c[3][1])
        return 0;
    if (nc == 2 && !(wx[0] * wy[1] - wy[0] * wx[1] != 0.0))
        return 0;
    if (!(hi - lo < 1.999))
        return 0;
    lo += base - 1e-9;
    hi += base + 1e-9;
    span = hi - lo;
    lo = lo < 0.0 ? lo + 4.0 : lo >= 4.0 ? lo - 4.0 : lo;
    hi = hi < 0.0 ? hi + 4.0 : hi >= 4.0 ? hi - 4.0 : hi;
    i0 = tile_find_sector(rg->sec_ang, rg->nsec, lo);
    i1 = tile_find_sector(rg->sec_ang, rg->nsec, hi);
    /* both ends in one sector: the range lies in it, or it runs from that
     * sector all the way round back into it (the last sector wraps past 4
     * to sec_ang[0]: a range from before sec_ang[0] to after
     * sec_ang[nsec - 1] meets every sector), and then every sector is looked at */
    if (i0 == i1) {
        double s0 = rg->sec_ang[i0], e0 = i0 + 1 < rg->nsec ? rg->sec_ang[i0 + 1] : rg->sec_ang[0] + 4.0;
        double d = lo - s0;
        d = d < 0.0 ? d + 4.0 : d;
        all = !(d + span <= e0 - s0);
    }
    for (i = i0, seen = 1;; i = (i + 1) % rg->nsec, seen++) {
        for (k = rg->sec_first[i]; k < rg->sec_first[i + 1]; k++) {
            const lit_band *b = &rg->band[k];
            const lit_line *ln;
            if (b->lo == LIT_NONE)
                return 0;
            ln = &rg->line[b->lo];
            if (!(ln->c != 0.0) || !isfinite(ln->c))
                return 0;
            for (j = 0; j < nc; j++) {
                double q = (wx[j] * ln->ey - wy[j] * ln->ex) / ln->c;
                if (!(q > 0.0 && q <= qmax))
                    return 0;
            }
        }
        if ((i == i1 && !all) || seen == rg->nsec)
            break;
    }
    return 1;
}

/* One tile of the shading pass: its pixels, box, wall and lamp list, and
 * its counters (added to the worker's when the tile is done). */
typedef struct tile_state {
    int32_t ti, tj, i1, j1;
    double bx[6];               /* box of the hit points the shader is called for */
    double gb[4];               /* box of those on the ground */
    double wa[2], wb[2], wmin, wmax;
    uint32_t wall;              /* the one wall of the tile's wall pixels, if one */
    int ncall, nground, nl;
    uint64_t sure_g, sure_w;
    uint64_t sky, ground, building, calls, tiled, skipped, icalls;
} tile_state;

/* E_rgb at P from the tile's lamp list (the light shader's value); lamps
 * whose bit is set in sure are visible without asking. ro: the regions
 * are read from the cache as they are (tile_light checked that each is
 * there); returns -1 when a point needs the segment path (P straight
 * under a lamp, which uses the light object's buffers), else 0. */
static int shade_tile_lamps(render *r, const uint32_t *tl, int nl, uint64_t sure, int ro, const double P[3],
                            const double n[3], double rgb[3], tile_state *t)
{
    const scene *s = r->s;
    int k;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (k = 0; k < nl; k++) {
        uint32_t l = tl[k];
        const scene_lamp *lp = &s->lamps[l];
        double term = lamp_term(lp, P, n);
        if (term == 0.0)
            continue;
        if ((sure >> k) & 1u)
            t->skipped++;
        else if (ro) {
            const lit_region *rg = r->lt->ent[l].reg;
            if (P[0] == rg->o[0] && P[1] == rg->o[1])
                return -1;
            if (!light_region_visible(r->lt, rg, P))
                continue;
        } else if (!light_visible(r->lt, l, P))
            continue;
        rgb[0] += term * lp->color[0];
        rgb[1] += term * lp->color[1];
        rgb[2] += term * lp->color[2];
    }
    return 0;
}

/* Grows the tile's boxes (and its one wall) by hit point P on surface sid. */
static void tile_grow(tile_state *t, const mesh_surf *sf, uint32_t sid, const double P[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        t->bx[k] = P[k] < t->bx[k] ? P[k] : t->bx[k];
        t->bx[3 + k] = P[k] > t->bx[3 + k] ? P[k] : t->bx[3 + k];
    }
    if (sid == MESH_SURF_GROUND) {
        t->nground++;
        t->gb[0] = P[0] < t->gb[0] ? P[0] : t->gb[0];
        t->gb[1] = P[1] < t->gb[1] ? P[1] : t->gb[1];
        t->gb[2] = P[0] > t->gb[2] ? P[0] : t->gb[2];
        t->gb[3] = P[1] > t->gb[3] ? P[1] : t->gb[3];
    } else if (sf->kind == MESH_KIND_WALL && t->wall != UINT32_MAX) {
        /* the ends of the wall pixels along the wall */
        double u = P[0] * -sf->n[1] + P[1] * sf->n[0];
        if (t->wall != MESH_SURF_NONE && t->wall != sid)
            t->wall = UINT32_MAX;
        else {
            t->wall = sid;
            if (u < t->wmin) {
                t->wmin = u;
                t->wa[0] = P[0];
                t->wa[1] = P[1];
            }
            if (u > t->wmax) {
                t->wmax = u;
                t->wb[0] = P[0];
                t->wb[1] = P[1];
            }
        }
    }
}

/* Whether this frame's ground pixels take the indirect term from the
 * indirect ground map (render_opts.indirect_map; built for its key). */
static int indmap_usable(const render *r, const render_opts *o)
{
    return o->indirect && o->indirect_map && r->im.built && r->im.key == o->indirect_key;
}

/* Step 1 of a tile: every pixel's hit point and normal; E = 0 (or the
 * light map's, when sample) for now; sky pixels written. */
static void tile_points(render *r, shade_ws *w, const render_opts *o, tile_state *t, int sample)
{
    int use_lm = o->lightmap && r->lm.built;
    int use_im = use_lm && sample && indmap_usable(r, o);
    int32_t i, j;
    int q = 0, k;
    for (k = 0; k < 3; k++) {
        t->bx[k] = HUGE_VAL;
        t->bx[3 + k] = -HUGE_VAL;
    }
    t->gb[0] = t->gb[1] = HUGE_VAL;
    t->gb[2] = t->gb[3] = -HUGE_VAL;
    t->wmin = HUGE_VAL;
    t->wmax = -HUGE_VAL;
    t->wa[0] = t->wa[1] = t->wb[0] = t->wb[1] = 0.0;
    t->wall = MESH_SURF_NONE;
    t->ncall = t->nground = 0;
    t->nl = -1;
    t->sure_g = t->sure_w = 0;
    t->sky = t->ground = t->building = t->calls = t->tiled = t->skipped = t->icalls = 0;
    for (j = t->tj; j < t->j1; j++) {
        for (i = t->ti; i < t->i1; i++, q++) {
            size_t p = (size_t)j * (size_t)r->w + (size_t)i;
            double E[3] = { 0, 0, 0 };
            double *P = w->tP[q], *n = w->tN[q];
            uint32_t sid;
            mesh_surf sfv;
            const mesh_surf *sf;
            float *out = &r->lin[3 * p];
            w->tcall[q] = 0;
            if (o->mask && !o->mask[p])
                continue;
            if (!pixel_hit(r, i, j, &sid, P, n)) {
                t->sky++;
                out[0] = out[1] = out[2] = 0.0f;
                continue;
            }
            sf = pixel_surf(r, sid, &sfv);
            if (sid == MESH_SURF_GROUND)
                t->ground++;
            else
                t->building++;
            w->tcall[q] = 1;
            /* facing up: the map's indirect layer (the indirect ground map without one) */
            w->tind[q] = use_lm && sample && o->indirect && n[2] > 0.5 &&
                         (r->lm.has_ind ? lightmap_sample_ind(&r->lm, P, w->tI[q])
                                        : use_im && indmap_sample(&r->im, P, w->tI[q]));
            if (sf->lit && sid == MESH_SURF_GROUND && use_lm) {
                if (sample)
                    lightmap_sample(&r->lm, P, E);
            } else if (sf->lit) {
                w->tcall[q] = 2;
                t->ncall++;
                if (r->lt) /* hit points are finite: plain comparisons */
                    tile_grow(t, sf, sid, P);
            }
            for (k = 0; k < 3; k++)
                w->tE[q][k] = E[k];
        }
    }
}

/* Step 2: the tile's lamps and which of them light its ground (or its one
 * wall) for sure. ro: nothing in the light object is changed; returns -1
 * when the tile needs it (more lamps than a list holds, a lamp's region
 * not in the cache), else 0. */
static int tile_light(render *r, shade_ws *w, tile_state *t, int ro)
{
    int k;
    if (t->ncall > 0 && r->lt)
        t->nl = tile_lamps(r, t->bx, w->tl);
    if (ro && t->ncall > 0) {
        if (t->nl < 0)
            return -1;
        for (k = 0; k < t->nl; k++)
            if (!r->lt->ent[w->tl[k]].reg)
                return -1;
    }
    if (t->nl > 0 && t->nground > 0) {
        double hb[4][2];
        hb[0][0] = hb[2][0] = t->gb[0];
        hb[1][0] = hb[3][0] = t->gb[2];
        hb[0][1] = hb[1][1] = t->gb[1];
        hb[2][1] = hb[3][1] = t->gb[3];
        for (k = 0; k < t->nl; k++)
            if (hull_visible(r, w->tl[k], (const double (*)[2])hb, 4, ro))
                t->sure_g |= (uint64_t)1 << k;
    }
    if (t->nl > 0 && t->wall != MESH_SURF_NONE && t->wall != UINT32_MAX) {
        double hs[2][2];
        hs[0][0] = t->wa[0];
        hs[0][1] = t->wa[1];
        hs[1][0] = t->wb[0];
        hs[1][1] = t->wb[1];
        /* a single pixel: a point is a segment of length 0 (O not on it) */
        for (k = 0; k < t->nl; k++)
            if (hull_visible(r, w->tl[k], (const double (*)[2])hs, 2, ro))
                t->sure_w |= (uint64_t)1 << k;
    }
    return 0;
}

/* Step 3: shade every pixel of the tile. Returns -1 (ro only) when a pixel
 * needs the light object's buffers, else 0. */
static int tile_shade(render *r, shade_ws *w, const render_opts *o, tile_state *t, int ro)
{
    int32_t i, j;
    int q = 0;
    for (j = t->tj; j < t->j1; j++)
        for (i = t->ti; i < t->i1; i++, q++) {
            size_t p = (size_t)j * (size_t)r->w + (size_t)i;
            double *E = w->tE[q];
            float *out = &r->lin[3 * p];
            int k;
            if (!w->tcall[q])
                continue;
            if (w->tcall[q] == 2) {
                if (t->nl >= 0) {
                    uint64_t sure = r->id[p] == MESH_SURF_GROUND ? t->sure_g : r->id[p] == t->wall ? t->sure_w : 0;
                    if (shade_tile_lamps(r, w->tl, t->nl, sure, ro, w->tP[q], w->tN[q], E, t) != 0)
                        return -1;
                    t->tiled++;
                } else
                    r->shade(r->user, w->tP[q], w->tN[q], E);
                t->calls++;
            }
            if (w->tind[q]) {
                for (k = 0; k < 3; k++)
                    E[k] += w->tI[q][k];
            } else if (o->indirect && r->sparse) {
                sparse_at(r, i, j, E); /* the pixels it leaves: sparse_rest */
            } else if (o->indirect) {
                double Ei[3] = { 0, 0, 0 };
                if (o->indirect_surf) {
                    mesh_surf sfv;
                    const mesh_surf *sf = pixel_surf(r, r->id[p], &sfv);
                    o->indirect_surf(o->indirect_user, r->id[p], sf->bld, w->tP[q], w->tN[q], Ei);
                } else
                    o->indirect(o->indirect_user, w->tP[q], w->tN[q], Ei);
                t->icalls++;
                for (k = 0; k < 3; k++)
                    E[k] += Ei[k];
            }
            if (r->id[p] == MESH_SURF_GROUND) {
                double alb[3]; /* per channel: the ground image (ground.c) */
                scene_ground_albedo(r->s, w->tP[q][0], w->tP[q][1], alb);
                for (k = 0; k < 3; k++)
                    out[k] = (float)(alb[k] / PI * E[k]);
            } else {
                double albedo = surf_albedo(r, r->id[p]);
                for (k = 0; k < 3; k++)
                    out[k] = (float)(albedo / PI * E[k]);
            }
        }
    return 0;
}

static void tile_init(const render *r, tile_state *t, int32_t ti, int32_t tj)
{
    t->ti = ti;
    t->tj = tj;
    t->i1 = ti + RENDER_TILE < r->w ? ti + RENDER_TILE : r->w;
    t->j1 = tj + RENDER_TILE < r->h ? tj + RENDER_TILE : r->h;
}

static void tile_count(render_stats *st, const tile_state *t)
{
    st->sky_pixels += t->sky;
    st->ground_pixels += t->ground;
    st->building_pixels += t->building;
    st->shader_calls += t->calls;
    st->shader_tiled += t->tiled;
    st->visibility_skipped += t->skipped;
    st->indirect_calls += t->icalls;
}

/* A whole tile on the calling thread, as one thread does it. */
static void tile_serial(render *r, const render_opts *o, int32_t ti, int32_t tj)
{
    tile_state t;
    tile_init(r, &t, ti, tj);
    tile_points(r, &r->ws[0], o, &t, 1);
    (void)tile_light(r, &r->ws[0], &t, 0);
    (void)tile_shade(r, &r->ws[0], o, &t, 0);
    tile_count(&r->ws[0].st, &t);
}

/* Before the workers start: the lamp regions every tile will ask for are
 * put in the light object's cache (hit points and lamp lists only). */
static void tile_warm(render *r, const render_opts *o, int32_t ti, int32_t tj)
{
    tile_state t;
    shade_ws *w = &r->ws[0];
    int k;
    tile_init(r, &t, ti, tj);
    tile_points(r, w, o, &t, 0);
    if (t.ncall == 0)
        return;
    t.nl = tile_lamps(r, t.bx, w->tl);
    for (k = 0; k < t.nl; k++) {
        const lit_region *rg;
        if (!r->lt->ent[w->tl[k]].reg)
            (void)light_region_index(r->lt, w->tl[k], &rg);
    }
}

/* fn on each tile, row after row; with defer (tw tiles a row), only on the
 * tiles marked in it. */
typedef void (*tile_fn)(render *r, const render_opts *o, int32_t ti, int32_t tj);

static void each_tile(render *r, const render_opts *o, tile_fn fn, const uint8_t *defer, int32_t tw)
{
    int32_t ti, tj;
    for (tj = 0; tj < r->h; tj += RENDER_TILE)
        for (ti = 0; ti < r->w; ti += RENDER_TILE)
            if (!defer || defer[(size_t)(tj / RENDER_TILE) * (size_t)tw + (size_t)(ti / RENDER_TILE)])
                fn(r, o, ti, tj);
}

typedef struct shade_job {
    render *r;
    const render_opts *o;
    uint8_t *defer;             /* per tile: 1 when a worker left it to the serial pass */
    int32_t tw;                 /* tiles in a row */
    int again;                  /* only the tiles defer marks */
} shade_job;

/* One row of tiles on worker 'worker' (render_job_fn). */
static void shade_row(void *arg, int worker, uint32_t row)
{
    shade_job *jb = arg;
    render *r = jb->r;
    shade_ws *w = &r->ws[worker];
    int32_t ti, tj = (int32_t)row * RENDER_TILE;
    for (ti = 0; ti < r->w; ti += RENDER_TILE) {
        tile_state t;
        size_t k = (size_t)row * (size_t)jb->tw + (size_t)(ti / RENDER_TILE);
        if (jb->again && !jb->defer[k])
            continue;
        tile_init(r, &t, ti, tj);
        tile_points(r, w, jb->o, &t, 1);
        if (tile_light(r, w, &t, 1) != 0 || tile_shade(r, w, jb->o, &t, 1) != 0) {
            jb->defer[k] = 1;
            continue;
        }
        jb->defer[k] = 0;
        tile_count(&w->st, &t);
    }
}

static int any_deferred(const uint8_t *defer, size_t n)
{
    size_t k;
    for (k = 0; k < n; k++)
        if (defer[k])
            return 1;
    return 0;
}

/* How many workers the shading pass of this frame may use: several only
 * with a parallel-for, the light module's shader and a thread-safe
 * indirect hook (or none). */
static int shade_workers(const render *r, const render_opts *o)
{
    if (!r->lt || (o->indirect && !o->indirect_mt && !r->sparse))
        return 1;
    return par_workers(o);
}

/* The shading pass, by tiles of RENDER_TILE x RENDER_TILE pixels: first
 * every pixel's hit point, then (light shader) the lamps whose reach meets
 * the box of the tile's hit points, then the illuminance from that list.
 * With several workers: the workers shade rows of tiles reading the light
 * object only; the tiles they could not finish that way (a lamp region not
 * in the cache: most tiles of a first frame, few along a walk) get their
 * regions cached on this thread, then the workers try them again, and
 * what is still left is shaded here, as one thread does. (Caching every
 * tile's regions first cost every frame a serial pass over all hit
 * points.) A tile's pixels depend on the tile alone, so the image is the
 * same bytes for any number of workers. */
void shade_pass(render *r, const render_opts *o, render_stats *st)
{
    int nw = shade_workers(r, o), k;
    for (k = 0; k < nw; k++)
        memset(&r->ws[k].st, 0, sizeof r->ws[k].st);
    if (nw == 1) {
        each_tile(r, o, tile_serial, NULL, 0);
    } else {
        shade_job jb;
        uint32_t rows = (uint32_t)((r->h + RENDER_TILE - 1) / RENDER_TILE), row;
        jb.r = r;
        jb.o = o;
        jb.defer = r->defer;
        jb.tw = (r->w + RENDER_TILE - 1) / RENDER_TILE;
        jb.again = 0;
        if (o->par(o->par_ctx, nw, rows, shade_row, &jb) != 0)
            for (row = 0; row < rows; row++)
                shade_row(&jb, 0, row);
        if (any_deferred(jb.defer, (size_t)rows * (size_t)jb.tw)) {
            each_tile(r, o, tile_warm, r->defer, jb.tw);
            jb.again = 1;
            if (o->par(o->par_ctx, nw, rows, shade_row, &jb) != 0)
                for (row = 0; row < rows; row++)
                    shade_row(&jb, 0, row);
            each_tile(r, o, tile_serial, r->defer, jb.tw);
        }
    }
    for (k = 0; k < nw; k++) {
        const render_stats *ws = &r->ws[k].st;
        st->sky_pixels += ws->sky_pixels;
        st->ground_pixels += ws->ground_pixels;
        st->building_pixels += ws->building_pixels;
        st->shader_calls += ws->shader_calls;
        st->shader_tiled += ws->shader_tiled;
        st->visibility_skipped += ws->visibility_skipped;
        st->indirect_calls += ws->indirect_calls;
    }
}
