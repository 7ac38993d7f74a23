/* litregion: per-lamp sector index (bands), lit ground and facade polygons,
 * and the LRU cache of regions (contract in light.h). */
#include "light/light.h"
#include "scene/photometry.h"
#include "light/litregion.h"
#include "base/geom.h"
#include "base/plx_assert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LR_ALIGN 16

/* ---- output buffer: arrays growing up, rings growing down ------------------ */

typedef struct obuf {
    unsigned char *base;
    size_t cap, lo, hi;      /* hi: bytes used from the top */
} obuf;

static void *ob_up(obuf *b, size_t bytes)
{
    size_t start = (b->lo + 7) & ~(size_t)7;
    if (start > b->cap - b->hi || bytes > b->cap - b->hi - start)
        return NULL;
    b->lo = start + bytes;
    return b->base + start;
}

static lit_ring *ob_ring(obuf *b)
{
    if (sizeof(lit_ring) > b->cap - b->hi - b->lo)
        return NULL;
    b->hi += sizeof(lit_ring);
    return (lit_ring *)(void *)(b->base + b->cap - b->hi);
}

/* ---- working data of one region ---------------------------------------------- */

typedef struct lr_edge {
    uint32_t cand;           /* local candidate index */
    uint32_t va, vb;         /* scene point indices of the edge a -> b */
    int o;                   /* orient(O, a, b): > 0 exit (O on the interior side) */
    double a0, a1;           /* pseudo-angles of its span, counter-clockwise */
    uint32_t s0, s1;         /* its sectors [s0, s1) with wrap (set by incidences) */
} lr_edge;

typedef struct lr_key { uint32_t cand, edge; double t; } lr_key;

typedef struct lr_work {
    light *L;
    const scene *s;
    vec2 o;
    double zl, R, Rg;
    double zcap;             /* facades lit only below this height (a cut-off lamp's horizon) */
    uint32_t *cand, ncand;
    unsigned char *cstate;   /* 0 O outside, 1 strictly inside, 2 on the boundary */
    lr_edge *edge;
    uint32_t nedge;
    double *bang;            /* sector start angles (unique, ascending) */
    vec2 *bdir;              /* a direction vector for each */
    uint32_t nsec;
    uint32_t *inc_first, *inc, ninc;
    lr_key *key;
    obuf out;
    lit_region *reg;
    lit_band *band;
    lit_line *line;
    uint32_t *sec_first;
    size_t fpts_off;         /* offset of the facade points in the output */
} lr_work;

static double cross2(double ax, double ay, double bx, double by)
{
    return ax * by - ay * bx;
}

static vec2 vsub(vec2 a, vec2 b)
{
    vec2 r;
    r.x = a.x - b.x;
    r.y = a.y - b.y;
    return r;
}

/* A direction for pseudo-angle p (any real; reduced mod 4). */
static vec2 pseudo_dir(double p)
{
    vec2 d;
    double q;
    int k;
    p = fmod(p, 4.0);
    if (p < 0.0)
        p += 4.0;
    k = (int)p;
    q = p - k;
    switch (k & 3) {
    case 0: d.x = 1.0 - q; d.y = q; break;
    case 1: d.x = -q; d.y = 1.0 - q; break;
    case 2: d.x = q - 1.0; d.y = -q; break;
    default: d.x = q; d.y = q - 1.0; break;
    }
    return d;
}

/* ---- candidates ----------------------------------------------------------------- */

/* Squared distance from (x, y) to the box. */
static double box_dist2(const double b[4], double x, double y)
{
    double dx = x < b[0] ? b[0] - x : (x > b[2] ? x - b[2] : 0.0);
    double dy = y < b[1] ? b[1] - y : (y > b[3] ? y - b[3] : 0.0);
    return dx * dx + dy * dy;
}

/* Where O lies relative to building b's footprint: 0 out, 1 in, 2 on. */
static unsigned char o_state(const scene *s, uint32_t b, vec2 o)
{
    const scene_building *bd = &s->bld[b];
    uint32_t r;
    int w = geom_point_in_ring(o, s->pts + s->rings[bd->ring_first].first,
                               s->rings[bd->ring_first].count);
    if (w != GEOM_INSIDE)
        return w == GEOM_ON_BOUNDARY ? 2 : 0;
    for (r = 1; r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        w = geom_point_in_ring(o, s->pts + rg->first, rg->count);
        if (w == GEOM_INSIDE)
            return 0;
        if (w == GEOM_ON_BOUNDARY)
            return 2;
    }
    return 1;
}

static plx_status gather(lr_work *w)
{
    light *L = w->L;
    const bucketgrid *g = &L->bgrid;
    double box[4];
    uint32_t x, y, k, n = 0, stamp, r0, r1, c0, c1;
    if (w->s->nbld == 0) {
        w->ncand = 0;
        w->cand = NULL;
        w->cstate = NULL;
        return PLX_OK;
    }
    box[0] = w->o.x - w->R; box[1] = w->o.y - w->R;
    box[2] = w->o.x + w->R; box[3] = w->o.y + w->R;
    c0 = bucketgrid_cell(g, box[0], box[1]);
    c1 = bucketgrid_cell(g, box[2], box[3]);
    r0 = c0 / g->nx; r1 = c1 / g->nx;
    for (y = r0; y <= r1; y++)
        n += g->start[y * g->nx + c1 % g->nx + 1] - g->start[y * g->nx + c0 % g->nx];
    w->cand = arena_scratch(L->a, arena_mul(n + 1, sizeof *w->cand), LR_ALIGN);
    w->cstate = arena_scratch(L->a, n + 1, LR_ALIGN);
    if (!w->cand || !w->cstate)
        return PLX_E_NOMEM;
    stamp = ++L->stamp_now;
    if (stamp == 0) {
        memset(L->stamp, 0, sizeof *L->stamp * (w->s->nbld + 1));
        stamp = L->stamp_now = 1;
    }
    w->ncand = 0;
    for (y = r0; y <= r1; y++)
        for (x = c0 % g->nx; x <= c1 % g->nx; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                uint32_t b = g->item[k];
                if (L->stamp[b] == stamp)
                    continue;
                L->stamp[b] = stamp;
                if (box_dist2(w->s->bld[b].box, w->o.x, w->o.y) > w->R * w->R)
                    continue;
                w->cstate[w->ncand] = o_state(w->s, b, w->o);
                w->cand[w->ncand++] = b;
            }
    return PLX_OK;
}

/* ---- edges and sectors ------------------------------------------------------------ */

typedef struct ang_idx { double a; uint32_t v; } ang_idx;

static int cmp_ang(const void *p, const void *q)
{
    const ang_idx *a = p, *b = q;
    if (a->a != b->a)
        return a->a < b->a ? -1 : 1;
    return (a->v > b->v) - (a->v < b->v);
}

static uint32_t cand_vertices(const lr_work *w)
{
    uint32_t c, r, n = 0;
    for (c = 0; c < w->ncand; c++) {
        const scene_building *bd = &w->s->bld[w->cand[c]];
        for (r = 0; r < bd->ring_count; r++)
            n += w->s->rings[bd->ring_first + r].count;
    }
    return n;
}

/* Sector boundaries: the unique pseudo-angles of the candidate vertices. */
static plx_status sectors(lr_work *w, uint32_t nv)
{
    const scene *s = w->s;
    ang_idx *ai = arena_scratch(w->L->a, arena_mul(nv + 1, sizeof *ai), LR_ALIGN);
    uint32_t c, r, j, n = 0, k;
    w->bang = arena_scratch(w->L->a, arena_mul(nv + 1, sizeof *w->bang), LR_ALIGN);
    w->bdir = arena_scratch(w->L->a, arena_mul(nv + 1, sizeof *w->bdir), LR_ALIGN);
    if (!ai || !w->bang || !w->bdir)
        return PLX_E_NOMEM;
    for (c = 0; c < w->ncand; c++) {
        const scene_building *bd = &s->bld[w->cand[c]];
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            for (j = 0; j < rg->count; j++) {
                vec2 d = vsub(s->pts[rg->first + j], w->o);
                if (d.x == 0.0 && d.y == 0.0)
                    continue;
                ai[n].a = light_pseudo_angle(d.x, d.y);
                ai[n++].v = rg->first + j;
            }
        }
    }
    qsort(ai, n, sizeof *ai, cmp_ang);
    w->nsec = 0;
    for (k = 0; k < n; k++) {
        if (w->nsec && w->bang[w->nsec - 1] == ai[k].a)
            continue;
        w->bang[w->nsec] = ai[k].a;
        w->bdir[w->nsec++] = vsub(s->pts[ai[k].v], w->o);
    }
    if (w->nsec == 0) {
        w->bang[0] = 0.0;
        w->bdir[0].x = 1.0;
        w->bdir[0].y = 0.0;
        w->nsec = 1;
    }
    return PLX_OK;
}

static uint32_t find_sector(const double *bang, uint32_t nsec, double a)
{
    uint32_t lo = 0, n = nsec;
    if (a < bang[0])
        return nsec - 1;
    /* the last sector starting at or before a, halving [lo, lo + n) with
     * a select rather than a branch (the comparison is unpredictable) */
    while (n > 1) {
        uint32_t half = n / 2;
        lo = bang[lo + half] <= a ? lo + half : lo;
        n -= half;
    }
    return lo;
}

/* Edges seen with positive angular width from O. */
static plx_status edges(lr_work *w, uint32_t nv)
{
    const scene *s = w->s;
    uint32_t c, r, j;
    w->edge = arena_scratch(w->L->a, arena_mul(nv + 1, sizeof *w->edge), LR_ALIGN);
    if (!w->edge)
        return PLX_E_NOMEM;
    w->nedge = 0;
    for (c = 0; c < w->ncand; c++) {
        const scene_building *bd = &s->bld[w->cand[c]];
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            for (j = 0; j < rg->count; j++) {
                uint32_t va = rg->first + j, vb = rg->first + (j + 1) % rg->count;
                vec2 a = vsub(s->pts[va], w->o), b = vsub(s->pts[vb], w->o);
                int o = geom_orient(w->o, s->pts[va], s->pts[vb]);
                lr_edge *e = &w->edge[w->nedge];
                double pa, pb;
                if (o == 0)
                    continue;
                pa = light_pseudo_angle(a.x, a.y);
                pb = light_pseudo_angle(b.x, b.y);
                if (pa == pb)
                    continue;       /* thinner than the pseudo-angle resolution */
                e->cand = c;
                e->va = va;
                e->vb = vb;
                e->o = o;
                e->a0 = o > 0 ? pa : pb;
                e->a1 = o > 0 ? pb : pa;
                w->nedge++;
            }
        }
    }
    return PLX_OK;
}

/* The sector range of edge e: sectors [i0, i1) with wrap. */
static void edge_range(const lr_work *w, const lr_edge *e, uint32_t *i0, uint32_t *i1)
{
    *i0 = find_sector(w->bang, w->nsec, e->a0);
    *i1 = find_sector(w->bang, w->nsec, e->a1);
}

/* Lists the active edges of every sector (CSR). */
static plx_status incidences(lr_work *w)
{
    uint32_t k, i, total = 0;
    w->inc_first = arena_scratch(w->L->a, arena_mul(w->nsec + 2, sizeof(uint32_t)), LR_ALIGN);
    if (!w->inc_first)
        return PLX_E_NOMEM;
    memset(w->inc_first, 0, (w->nsec + 2) * sizeof(uint32_t));
    for (k = 0; k < w->nedge; k++) {
        lr_edge *e = &w->edge[k];
        edge_range(w, e, &e->s0, &e->s1);
        for (i = e->s0; i != e->s1; i = (i + 1 == w->nsec ? 0 : i + 1)) {
            w->inc_first[i + 1]++;
            total++;
        }
    }
    for (i = 0; i < w->nsec; i++)
        w->inc_first[i + 1] += w->inc_first[i];
    w->ninc = total;
    w->inc = arena_scratch(w->L->a, arena_mul(total + 1, sizeof(uint32_t)), LR_ALIGN);
    w->key = arena_scratch(w->L->a, arena_mul(total + 1, sizeof(lr_key)), LR_ALIGN);
    if (!w->inc || !w->key)
        return PLX_E_NOMEM;
    for (k = 0; k < w->nedge; k++)
        for (i = w->edge[k].s0; i != w->edge[k].s1; i = (i + 1 == w->nsec ? 0 : i + 1))
            w->inc[w->inc_first[i]++] = k;
    for (i = w->nsec; i > 0; i--)
        w->inc_first[i] = w->inc_first[i - 1];
    w->inc_first[0] = 0;
    return PLX_OK;
}

/* ---- bands ---------------------------------------------------------------------------- */

static void make_lines(lr_work *w)
{
    uint32_t k;
    for (k = 0; k < w->nedge; k++) {
        vec2 a = vsub(w->s->pts[w->edge[k].va], w->o);
        vec2 b = vsub(w->s->pts[w->edge[k].vb], w->o);
        lit_line *l = &w->line[k];
        l->ex = b.x - a.x;
        l->ey = b.y - a.y;
        l->c = cross2(a.x, a.y, l->ex, l->ey);
    }
}

/* Direction in the middle of sector i. */
static vec2 sector_mid(const lr_work *w, uint32_t i)
{
    double a0 = w->bang[i], a1 = i + 1 < w->nsec ? w->bang[i + 1] : w->bang[0] + 4.0;
    return pseudo_dir(0.5 * (a0 + a1));
}

/* Whether the ray u leaves O into the interior of building cand (O on its
 * boundary), from the walls through O. */
static int start_inside_on(const lr_work *w, uint32_t cand, vec2 u)
{
    const scene *s = w->s;
    const scene_building *bd = &s->bld[w->cand[cand]];
    uint32_t r, j;
    for (r = 0; r < bd->ring_count; r++) {
        const scene_ring *rg = &s->rings[bd->ring_first + r];
        for (j = 0; j < rg->count; j++) {
            vec2 p = s->pts[rg->first + (j + rg->count - 1) % rg->count];
            vec2 v = s->pts[rg->first + j], q = s->pts[rg->first + (j + 1) % rg->count];
            if (v.x == w->o.x && v.y == w->o.y) {
                int l1 = cross2(v.x - p.x, v.y - p.y, u.x, u.y) > 0.0;
                int l2 = cross2(q.x - v.x, q.y - v.y, u.x, u.y) > 0.0;
                return geom_orient(p, v, q) > 0 ? (l1 && l2) : (l1 || l2);
            }
            if (geom_orient(v, q, w->o) == 0 &&
                (w->o.x - v.x) * (q.x - w->o.x) + (w->o.y - v.y) * (q.y - w->o.y) > 0.0)
                return cross2(q.x - v.x, q.y - v.y, u.x, u.y) > 0.0;
        }
    }
    return 0;
}

static void sort_keys(lr_key *k, uint32_t n)
{
    uint32_t i, j;
    for (i = 1; i < n; i++) {
        lr_key x = k[i];
        for (j = i; j > 0 && (k[j - 1].cand > x.cand ||
                              (k[j - 1].cand == x.cand && k[j - 1].t > x.t)); j--)
            k[j] = k[j - 1];
        k[j] = x;
    }
}

/* Bands of one building along the sorted keys k[0..n). */
static uint32_t building_bands(lr_work *w, const lr_key *k, uint32_t n, int inside,
                               lit_band *out)
{
    uint32_t i, nb = 0, lo = LIT_NONE, b = w->cand[k[0].cand];
    for (i = 0; i < n; i++) {
        int enter = w->edge[k[i].edge].o < 0;
        if (enter && !inside) {
            lo = k[i].edge;
            inside = 1;
        } else if (!enter && inside) {
            out[nb].bld = b;
            out[nb].lo = lo;
            out[nb++].hi = k[i].edge;
            inside = 0;
        }
    }
    if (inside) {            /* rounding left the ray inside: to infinity */
        out[nb].bld = b;
        out[nb].lo = lo;
        out[nb++].hi = LIT_NONE;
    }
    return nb;
}

/* Candidates with O inside get a band even where no edge is active. */
static uint32_t sector_bands(lr_work *w, uint32_t i, lit_band *out)
{
    uint32_t a = w->inc_first[i], n = w->inc_first[i + 1] - a, j, g, nb = 0, c;
    vec2 u = sector_mid(w, i);
    lr_key *k = w->key;
    for (j = 0; j < n; j++) {
        uint32_t e = w->inc[a + j];
        const lit_line *l = &w->line[e];
        k[j].cand = w->edge[e].cand;
        k[j].edge = e;
        k[j].t = l->c / cross2(u.x, u.y, l->ex, l->ey);
    }
    sort_keys(k, n);
    for (j = 0; j < n; j = g) {
        int inside;
        c = k[j].cand;
        for (g = j; g < n && k[g].cand == c; g++)
            ;
        inside = w->cstate[c] == 1 || (w->cstate[c] == 2 && start_inside_on(w, c, u));
        nb += building_bands(w, k + j, g - j, inside, out + nb);
    }
    return nb;
}

/* The region's header, sector index, bands and lines into the output. */
static plx_status index_emit(lr_work *w, uint32_t lamp)
{
    uint32_t i, nb = 0, cap;
    lit_region *r = ob_up(&w->out, sizeof *r);
    double *ang;
    if (!r)
        return PLX_E_NOMEM;
    memset(r, 0, sizeof *r);
    w->reg = r;
    r->lamp = lamp;
    r->o[0] = w->o.x; r->o[1] = w->o.y; r->o[2] = w->zl;
    r->reach = w->R;
    r->ground_reach = w->Rg;
    r->ncand = w->ncand;
    ang = ob_up(&w->out, sizeof(double) * w->nsec);
    w->sec_first = ob_up(&w->out, sizeof(uint32_t) * (w->nsec + 1));
    w->line = ob_up(&w->out, sizeof(lit_line) * (w->nedge + 1));
    /* a building's bands in a sector are at most its active edges there */
    cap = w->ninc + 1;
    w->band = ob_up(&w->out, arena_mul(cap, sizeof(lit_band)));
    if (!ang || !w->sec_first || !w->line || !w->band)
        return PLX_E_NOMEM;
    memcpy(ang, w->bang, sizeof(double) * w->nsec);
    make_lines(w);
    for (i = 0; i < w->nsec; i++) {
        w->sec_first[i] = nb;
        nb += sector_bands(w, i, w->band + nb);
    }
    w->sec_first[w->nsec] = nb;
    w->out.lo = (size_t)((unsigned char *)(w->band + nb) - w->out.base);
    r->nsec = w->nsec;
    r->sec_ang = ang;
    r->sec_first = w->sec_first;
    r->band = w->band;
    r->nband = nb;
    r->line = w->line;
    r->nline = w->nedge;
    return PLX_OK;
}

/* ---- lit ground polygons ---------------------------------------------------------- */

/* The ground is built sector by sector. Within a sector the lines bounding
 * the shadows (scaled edge lines) are straight, and the outer bound is the
 * reach polygon (the 360-gon inscribed in the circle of radius Rg, vertices
 * on the 1-degree rays). The order of all bounds along a ray changes only
 * where two lines cross or where a line crosses the reach polygon; those
 * directions cut the sector into sub-sectors, and each lit interval of a
 * sub-sector becomes one polygon: a quad (a triangle from O) between two
 * lines, or a ring whose outer side follows the reach polygon through the
 * vertices of the rays inside the sub-sector. */

/* A boundary line: the points O + t u of the line have t = c / cross(u, e)
 * (a scaled edge line, or a chord of the reach polygon). */
typedef struct gline { double ex, ey, c; int near; } gline;
/* near: the line comes within the reach circle (else it cannot meet the
 * reach polygon) */

/* Bounds of one shadow interval along a ray: indices into the lines; G_O is
 * O for lo and infinity for hi. */
typedef struct gspan { int lo, hi; double tlo, thi; } gspan;

/* A cut direction of a sector and its pseudo-angle (unwrapped from the
 * sector's start). */
typedef struct gcut { vec2 v; double a; } gcut;

#define G_MAXB 64            /* shadow intervals kept per sector */
#define G_O (-1)             /* O (lower bound), infinity (upper bound) */
#define G_RING_MAX 64        /* points of a ring following the reach polygon */

typedef struct gpiece {
    gline line[2 * G_MAXB];
    int nline;
    gspan span[G_MAXB];
    int nspan;
    gcut *cut;               /* scratch, cutcap entries */
    uint32_t ncut, cutcap;
    unsigned char before[2 * G_MAXB]; /* per line: inside the reach polygon */
    double rg;               /* the ground reach */
    lit_ring *fan;           /* the last ring, when it is a fan O, reach... */
    double fan_a;            /* pseudo-angle where the open fan ends */
} gpiece;

/* Cut directions a sector may need, for a sector of at most 'edges' active
 * edges (each ground line is one of them, scaled): crossings of its lines
 * in pairs and of each line with the reach polygon (at most twice, as it is
 * convex; ground_add_cut drops any beyond the room, which only rounding at
 * a grazing line could ask for). */
static uint32_t ground_cut_cap(uint32_t edges)
{
    uint32_t nl = edges < 2 * G_MAXB ? edges : 2 * G_MAXB;
    return nl * (nl > 0 ? nl - 1 : 0) / 2 + 2 * nl + 4;
}

static double gl_t(const gline *l, vec2 u)
{
    return l->c / cross2(u.x, u.y, l->ex, l->ey);
}

static vec2 gl_point(const lr_work *w, const gline *l, vec2 u)
{
    double t = gl_t(l, u);
    vec2 p;
    p.x = w->o.x + t * u.x;
    p.y = w->o.y + t * u.y;
    return p;
}

static int add_gline(gpiece *g, const lit_line *l, double scale)
{
    gline *d = &g->line[g->nline];
    d->ex = l->ex;
    d->ey = l->ey;
    d->c = l->c * scale;
    d->near = fabs(d->c) < g->rg * sqrt(d->ex * d->ex + d->ey * d->ey);
    return g->nline++;
}

/* The shadow intervals of sector i's bands on the ground. A band whose
 * scaled near line stays outside the reach circle shadows nothing within
 * reach. */
static void sector_spans(const lr_work *w, uint32_t i, gpiece *g)
{
    uint32_t k;
    g->nspan = 0;
    g->nline = 0;
    for (k = w->sec_first[i]; k < w->sec_first[i + 1] && g->nspan < G_MAXB; k++) {
        const lit_band *b = &w->band[k];
        const scene_building *bd = &w->s->bld[b->bld];
        gspan *sp = &g->span[g->nspan];
        if (!(bd->min_height < w->zl))
            continue;                       /* no ground shadow */
        sp->lo = G_O;
        if (b->lo != LIT_NONE) {
            const lit_line *l = &w->line[b->lo];
            double cm = w->zl / (w->zl - bd->min_height);
            if (fabs(l->c * cm) >= w->Rg * sqrt(l->ex * l->ex + l->ey * l->ey))
                continue;                   /* beyond the reach */
            sp->lo = add_gline(g, l, cm);
        }
        sp->hi = G_O;
        if (b->hi != LIT_NONE && bd->height < w->zl)
            sp->hi = add_gline(g, &w->line[b->hi], w->zl / (w->zl - bd->height));
        g->nspan++;
    }
}

/* Direction (t > 0 side) where lines a and b cross; 0 if parallel. */
static int line_cross_dir(const gline *a, const gline *b, vec2 *v)
{
    double den;
    v->x = a->c * b->ex - b->c * a->ex;
    v->y = a->c * b->ey - b->c * a->ey;
    den = cross2(v->x, v->y, a->ex, a->ey);
    if (den == 0.0 || a->c == 0.0)
        return 0;
    if ((a->c > 0.0) != (den > 0.0)) {       /* t = c / den < 0 */
        v->x = -v->x;
        v->y = -v->y;
    }
    return 1;
}

/* ---- the 1-degree rays and the reach polygon ---- */

/* Ray kk in [0, 720): direction and pseudo-angle (unwrapped: + 4 from 360). */
static double ray_ang_at(const light *L, int kk)
{
    return kk < 360 ? L->ray_ang[kk] : L->ray_ang[kk - 360] + 4.0;
}

/* First ray whose pseudo-angle is above a (strict) or at least a, for a in
 * [0, 8). */
static int ray_search(const light *L, double a, int strict)
{
    int lo = 0, hi = 360, off = 0;
    if (a >= 4.0) {
        a -= 4.0;
        off = 360;
    }
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (strict ? L->ray_ang[mid] > a : L->ray_ang[mid] >= a)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo + off;
}

/* The chord of the reach polygon from ray kk to ray kk + 1. */
static void reach_chord(const lr_work *w, int kk, gline *c)
{
    const double *r0 = w->L->ray_dir[kk % 360], *r1 = w->L->ray_dir[(kk + 1) % 360];
    c->ex = w->Rg * (r1[0] - r0[0]);
    c->ey = w->Rg * (r1[1] - r0[1]);
    c->c = cross2(w->Rg * r0[0], w->Rg * r0[1], c->ex, c->ey);
    c->near = 1;
}

static vec2 ray_vertex(const lr_work *w, int kk)
{
    vec2 p;
    p.x = w->o.x + w->Rg * w->L->ray_dir[kk % 360][0];
    p.y = w->o.y + w->Rg * w->L->ray_dir[kk % 360][1];
    return p;
}

/* Where the ray of direction u (pseudo-angle a) meets the reach polygon. */
static vec2 reach_point(const lr_work *w, vec2 u, double a)
{
    int kk = ray_search(w->L, a, 1) - 1;
    gline c;
    if (ray_ang_at(w->L, kk) == a)
        return ray_vertex(w, kk);
    reach_chord(w, kk, &c);
    return gl_point(w, &c, u);
}

/* ---- cuts ---- */

static void ground_add_cut(gpiece *g, vec2 v, double a0, double a1)
{
    double a = light_pseudo_angle(v.x, v.y);
    if (a < a0)
        a += 4.0;
    if (!(a > a0 && a < a1) || g->ncut >= g->cutcap)
        return;
    g->cut[g->ncut].v = v;
    g->cut[g->ncut++].a = a;
}

/* Crossings of two lines within the reach circle, inside (a0, a1). */
static void line_cuts(gpiece *g, double a0, double a1)
{
    int p, q;
    double r2 = g->rg * g->rg;
    vec2 v;
    for (p = 0; p < g->nline; p++) {
        const gline *lp = &g->line[p];
        if (!lp->near)
            continue;                        /* meets every other line beyond reach */
        for (q = p + 1; q < g->nline; q++) {
            double t;
            if (!g->line[q].near || !line_cross_dir(lp, &g->line[q], &v))
                continue;
            t = gl_t(lp, v);
            if (t * t * (v.x * v.x + v.y * v.y) >= r2)
                continue;                    /* beyond the reach polygon: no matter */
            ground_add_cut(g, v, a0, a1);
        }
    }
}

/* 1 when line l is met by the ray u at 0 < t < tb. */
static unsigned char gl_before(const gline *l, vec2 u, double tb)
{
    double t = gl_t(l, u);
    return t > 0.0 && t < tb;
}

/* Crossings of the near lines with the reach polygon inside (a0, a1): the
 * side a line is on (inside the reach polygon or not) is taken at the
 * sector's ends and at every ray between; inside one chord's span a line
 * crosses the chord at most once, and exactly when its side changes. */
static void reach_cuts(const lr_work *w, gpiece *g, vec2 d0, double a0, vec2 d1, double a1)
{
    const light *L = w->L;
    int idx[2 * G_MAXB], nn = 0, j, kk;
    gline c;
    vec2 u;
    double tb;
    for (j = 0; j < g->nline; j++)
        if (g->line[j].near)
            idx[nn++] = j;
    if (nn == 0)
        return;
    kk = ray_search(L, a0, 1);
    reach_chord(w, kk - 1, &c);
    tb = gl_t(&c, d0);
    for (j = 0; j < nn; j++)
        g->before[idx[j]] = gl_before(&g->line[idx[j]], d0, tb);
    for (;; kk++) {
        int end = kk >= 720 || !(ray_ang_at(L, kk) < a1);
        if (end) {
            u = d1;
            tb = gl_t(&c, d1);
        } else {
            u.x = L->ray_dir[kk % 360][0];
            u.y = L->ray_dir[kk % 360][1];
            tb = w->Rg;
        }
        for (j = 0; j < nn; j++) {
            gline *l = &g->line[idx[j]];
            unsigned char b = gl_before(l, u, tb);
            vec2 v;
            if (b != g->before[idx[j]] && line_cross_dir(&c, l, &v))
                ground_add_cut(g, v, a0, a1);
            g->before[idx[j]] = b;
        }
        if (end)
            break;
        reach_chord(w, kk, &c);
    }
}

static int cmp_cut(const void *p, const void *q)
{
    const gcut *a = p, *b = q;
    return (a->a > b->a) - (a->a < b->a);
}

static void sort_cuts(gcut *c, uint32_t n)
{
    uint32_t i, j;
    if (n > 24) {
        qsort(c, n, sizeof *c, cmp_cut);
        return;
    }
    for (i = 1; i < n; i++) {
        gcut x = c[i];
        for (j = i; j > 0 && c[j - 1].a > x.a; j--)
            c[j] = c[j - 1];
        c[j] = x;
    }
}

/* ---- emitting ---- */

/* Appends one ring of n points; returns its first point slot or NULL. */
static vec2 *ground_ring(lr_work *w, uint32_t n)
{
    vec2 *p = ob_up(&w->out, n * sizeof *p);
    lit_ring *r;
    if (!p)
        return NULL;
    r = ob_ring(&w->out);
    if (!r)
        return NULL;
    r->first = w->reg->ngpts;
    r->count = n;
    r->wall = LIT_NONE;
    w->reg->ngpts += n;
    w->reg->nground++;
    return p;
}

/* The lit piece between line x (G_O: O) and line y along [u0, u1]. */
static plx_status ground_quad(lr_work *w, gpiece *g, int x, int y, vec2 u0, vec2 u1)
{
    vec2 *p = ground_ring(w, x < 0 ? 3 : 4);
    g->fan = NULL;
    if (!p)
        return PLX_E_NOMEM;
    if (x < 0) {
        p[0] = w->o;
        p[1] = gl_point(w, &g->line[y], u0);
        p[2] = gl_point(w, &g->line[y], u1);
    } else {
        p[0] = gl_point(w, &g->line[x], u0);
        p[1] = gl_point(w, &g->line[y], u0);
        p[2] = gl_point(w, &g->line[y], u1);
        p[3] = gl_point(w, &g->line[x], u1);
    }
    return PLX_OK;
}

/* Extends the open fan (ending at pseudo-angle pa) by the rays [kb, ke)
 * and the reach point of ub; 0 when it has no room. */
static int fan_extend(lr_work *w, gpiece *g, double pa, int kb, int ke, vec2 ub, double pb,
                      plx_status *st)
{
    int at_ray = ray_ang_at(w->L, kb > 0 ? kb - 1 : 0) == pa;
    uint32_t add = (uint32_t)(ke - kb) + (at_ray ? 1u : 0u);
    vec2 *p;
    int kk;
    if (g->fan->count + add > G_RING_MAX)
        return 0;
    *st = PLX_OK;
    if (add > 0 && !(p = ob_up(&w->out, add * sizeof *p))) {
        *st = PLX_E_NOMEM;
        return 1;
    }
    /* the fan's last point lies on the chord the next points start on,
     * unless it is a vertex: then it stays */
    p = (vec2 *)(void *)(w->out.base + w->out.lo) - ((ke - kb) + 1);
    for (kk = kb; kk < ke; kk++)
        *p++ = ray_vertex(w, kk);
    *p = reach_point(w, ub, pb);
    g->fan->count += add;
    w->reg->ngpts += add;
    g->fan_a = pb;
    return 1;
}

/* The lit piece between line x (G_O: O) and the reach polygon along
 * [ua, ub] (pseudo-angles pa < pb), rings of at most G_RING_MAX points
 * through the reach vertices in between. */
static plx_status ground_reach(lr_work *w, gpiece *g, int x, vec2 ua, double pa, vec2 ub,
                               double pb)
{
    int kb = ray_search(w->L, pa, 1), ke = ray_search(w->L, pb, 0);
    int room = G_RING_MAX - 2 - (x < 0 ? 1 : 2);
    plx_status st = PLX_OK;
    if (x < 0 && g->fan && g->fan_a == pa && fan_extend(w, g, pa, kb, ke, ub, pb, &st))
        return st;
    for (;;) {
        int last = ke - kb <= room, kend = last ? ke : kb + room, n, kk, j = 0;
        vec2 ue = ub, *p;
        double pe = pb;
        if (!last) {
            ue.x = w->L->ray_dir[kend % 360][0];
            ue.y = w->L->ray_dir[kend % 360][1];
            pe = ray_ang_at(w->L, kend);
        }
        n = (kend - kb) + 2 + (x < 0 ? 1 : 2);
        p = ground_ring(w, (uint32_t)n);
        if (!p)
            return PLX_E_NOMEM;
        p[j++] = x < 0 ? w->o : gl_point(w, &g->line[x], ua);
        p[j++] = reach_point(w, ua, pa);
        for (kk = kb; kk < kend; kk++)
            p[j++] = ray_vertex(w, kk);
        p[j++] = reach_point(w, ue, pe);
        if (x >= 0)
            p[j++] = gl_point(w, &g->line[x], ue);
        if (x < 0) {
            g->fan = (lit_ring *)(void *)(w->out.base + w->out.cap - w->out.hi);
            g->fan_a = pe;
        } else {
            g->fan = NULL;
        }
        if (last)
            return st;
        ua = ue;
        pa = pe;
        kb = kend + 1;
    }
}

static void sort_spans(gspan *s, int n)
{
    int i, j;
    for (i = 1; i < n; i++) {
        gspan x = s[i];
        for (j = i; j > 0 && s[j - 1].tlo > x.tlo; j--)
            s[j] = s[j - 1];
        s[j] = x;
    }
}

static int lit_width(double x, double y)
{
    return y - x > 1e-12 * (y > 0.0 ? y : -y) + 1e-300;
}

/* Lit pieces along the rays between u0 and u1 (pseudo-angles p0 < p1; the
 * order of the bounds is fixed there). */
static plx_status ground_sub(lr_work *w, gpiece *g, vec2 u0, double p0, vec2 u1, double p1)
{
    double pm = 0.5 * (p0 + p1), tr, cur = 0.0;
    vec2 m = pseudo_dir(pm);
    gline c;
    int k, cur_id = G_O;
    plx_status st = PLX_OK;
    reach_chord(w, ray_search(w->L, pm, 1) - 1, &c);
    tr = gl_t(&c, m);
    for (k = 0; k < g->nspan; k++) {
        gspan *sp = &g->span[k];
        sp->tlo = sp->lo < 0 ? 0.0 : gl_t(&g->line[sp->lo], m);
        sp->thi = sp->hi < 0 ? INFINITY : gl_t(&g->line[sp->hi], m);
    }
    sort_spans(g->span, g->nspan);
    for (k = 0; k < g->nspan && cur < tr && st == PLX_OK; k++) {
        const gspan *sp = &g->span[k];
        if (sp->tlo > cur) {
            double y = sp->tlo < tr ? sp->tlo : tr;
            if (lit_width(cur, y))
                st = sp->tlo < tr ? ground_quad(w, g, cur_id, sp->lo, u0, u1)
                                  : ground_reach(w, g, cur_id, u0, p0, u1, p1);
        }
        if (sp->thi > cur) {
            cur = sp->thi;
            cur_id = sp->hi;
        }
    }
    if (st == PLX_OK && cur < tr && lit_width(cur, tr))
        st = ground_reach(w, g, cur_id, u0, p0, u1, p1);
    return st;
}

/* The lit ground of sector i. */
static plx_status ground_sector(lr_work *w, gpiece *g, uint32_t i)
{
    uint32_t nx = i + 1 < w->nsec ? i + 1 : 0, k;
    double a0 = w->bang[i], a1 = nx ? w->bang[nx] : w->bang[0] + 4.0, p0 = a0;
    vec2 d0 = w->bdir[i], d1 = w->bdir[nx], u0 = d0;
    plx_status st = PLX_OK;
    if (w->sec_first[i + 1] - w->sec_first[i] > G_MAXB)
        return PLX_E_UNSUPPORTED; /* more bands than the polygon builder keeps: never drop one */
    sector_spans(w, i, g);
    if (g->nspan == 0)
        return a1 - a0 >= 1.0 || cross2(d0.x, d0.y, d1.x, d1.y) > 0.0
               ? ground_reach(w, g, G_O, d0, a0, d1, a1) : PLX_OK;
    g->ncut = 0;
    line_cuts(g, a0, a1);
    reach_cuts(w, g, d0, a0, d1, a1);
    sort_cuts(g->cut, g->ncut);
    for (k = 0; k <= g->ncut && st == PLX_OK; k++) {
        vec2 u1 = k < g->ncut ? g->cut[k].v : d1;
        double p1 = k < g->ncut ? g->cut[k].a : a1;
        if (p1 > p0 && (p1 - p0 >= 1.0 || cross2(u0.x, u0.y, u1.x, u1.y) > 0.0))
            st = ground_sub(w, g, u0, p0, u1, p1);
        u0 = u1;
        p0 = p1;
    }
    return st;
}

static plx_status ground_emit(lr_work *w, gpiece *g)
{
    uint32_t i;
    plx_status st = PLX_OK;
    w->reg->gpts = (const vec2 *)(const void *)(w->out.base + ((w->out.lo + 7) & ~(size_t)7));
    g->fan = NULL;
    g->rg = w->Rg;
    for (i = 0; i < w->nsec && st == PLX_OK; i++)
        st = ground_sector(w, g, i);
    return st;
}

/* ---- lit facade polygons ------------------------------------------------------------ */

/* z-bound functions of a band on a wall: variants of the blocked interval's
 * ends (see light.h); all affine in the wall parameter u. */
enum {
    FZ_LO_A = 0,   /* zL - (zL - m) fa */
    FZ_LO_B,       /* zL + (m - zL) fb */
    FZ_M,          /* m */
    FZ_LO_ZL,      /* zL */
    FZ_HI_A,       /* zL + (h - zL) fa */
    FZ_HI_B,       /* zL - (zL - h) fb */
    FZ_H,          /* h */
    FZ_HI_ZL,      /* zL */
    FZ_N
};
#define FZ_BOTTOM (-1)   /* the wall's foot */
#define FZ_TOP (-2)      /* the wall's top */
#define FZ_NEGINF (-3)
#define FZ_POSINF (-4)

/* One band as seen from a wall: fa(u) = 1/ta = alpha_a + beta_a u (or
 * infinite), fb(u) = 1/tb (0 when the band has no end). */
typedef struct fband {
    double aa, ba, ab, bb;
    int inf_a;
    double m, h;
} fband;

typedef struct fwall {
    vec2 a, e;               /* wall start relative to O, direction */
    vec2 a3;                 /* wall start, world */
    double mw, hw;
    uint32_t wall;
    fband fb[G_MAXB];
    int nfb;
    lit_ring *open;          /* an open fully lit quad, for merging */
    double open_lo;
} fwall;

static double fb_fa(const fband *b, double u) { return b->aa + b->ba * u; }
static double fb_fb(const fband *b, double u) { return b->ab + b->bb * u; }

static double fz_eval(const lr_work *w, const fwall *f, int id, double u)
{
    const fband *b;
    double zl = w->zl;
    switch (id) {
    case FZ_BOTTOM: return f->mw;
    case FZ_TOP: return f->hw;
    case FZ_NEGINF: return -1e300;
    case FZ_POSINF: return 1e300;
    default: break;
    }
    b = &f->fb[id / FZ_N];
    switch (id % FZ_N) {
    case FZ_LO_A: return zl - (zl - b->m) * fb_fa(b, u);
    case FZ_LO_B: return zl + (b->m - zl) * fb_fb(b, u);
    case FZ_M: return b->m;
    case FZ_HI_A: return zl + (b->h - zl) * fb_fa(b, u);
    case FZ_HI_B: return zl - (zl - b->h) * fb_fb(b, u);
    case FZ_H: return b->h;
    default: return zl;
    }
}

/* The blocked z-interval of band j at u (ends as function ids); 0 when the
 * band does not block there. */
static int fb_interval(const lr_work *w, const fwall *f, int j, double u, int *lo, int *hi)
{
    const fband *b = &f->fb[j];
    double zl = w->zl, fa = b->inf_a ? INFINITY : fb_fa(b, u), fb = fb_fb(b, u);
    int base = j * FZ_N, bmax = fb > 1.0;
    if (!(fa > 1.0))
        return 0;
    if (b->m < zl)
        *lo = b->inf_a ? FZ_NEGINF : base + FZ_LO_A;
    else if (b->m > zl)
        *lo = base + (bmax ? FZ_LO_B : FZ_M);
    else
        *lo = base + FZ_LO_ZL;
    if (b->h > zl)
        *hi = b->inf_a ? FZ_POSINF : base + FZ_HI_A;
    else if (b->h < zl)
        *hi = base + (bmax ? FZ_HI_B : FZ_H);
    else
        *hi = base + FZ_HI_ZL;
    return 1;
}

static plx_status facade_quad(lr_work *w, fwall *f, double u0, double u1, int x, int y)
{
    lit_pt3 *p = ob_up(&w->out, 4 * sizeof *p);
    lit_ring *r;
    double uu[4], zz[4];
    int k;
    if (!p || !(r = ob_ring(&w->out)))
        return PLX_E_NOMEM;
    r->first = w->reg->nfpts;
    r->count = 4;
    r->wall = f->wall;
    w->reg->nfpts += 4;
    w->reg->nfacade++;
    uu[0] = u0; zz[0] = fz_eval(w, f, x, u0);
    uu[1] = u1; zz[1] = fz_eval(w, f, x, u1);
    uu[2] = u1; zz[2] = fz_eval(w, f, y, u1);
    uu[3] = u0; zz[3] = fz_eval(w, f, y, u0);
    for (k = 0; k < 4; k++) {
        p[k].x = f->a3.x + uu[k] * f->e.x;
        p[k].y = f->a3.y + uu[k] * f->e.y;
        p[k].z = zz[k];
    }
    f->open = (x == FZ_BOTTOM && y == FZ_TOP) ? r : NULL;
    f->open_lo = u0;
    return PLX_OK;
}

/* Widens the open fully lit quad of the wall down to u0. */
static plx_status facade_extend(lr_work *w, fwall *f, double u0)
{
    lit_pt3 *p = (lit_pt3 *)(void *)(w->out.base + w->fpts_off) + f->open->first;
    p[0].x = p[3].x = f->a3.x + u0 * f->e.x;
    p[0].y = p[3].y = f->a3.y + u0 * f->e.y;
    f->open_lo = u0;
    return PLX_OK;
}

typedef struct zspan { int lo, hi; double zlo, zhi; } zspan;

static plx_status facade_sub(lr_work *w, fwall *f, double u0, double u1)
{
    zspan sp[G_MAXB];
    int n = 0, j, cur_id = FZ_BOTTOM;
    double um = 0.5 * (u0 + u1), cur = f->mw;
    plx_status st = PLX_OK;
    for (j = 0; j < f->nfb; j++) {
        int lo, hi, k;
        zspan x;
        if (!fb_interval(w, f, j, um, &lo, &hi))
            continue;
        x.lo = lo; x.hi = hi;
        x.zlo = fz_eval(w, f, lo, um);
        x.zhi = fz_eval(w, f, hi, um);
        for (k = n; k > 0 && sp[k - 1].zlo > x.zlo; k--)
            sp[k] = sp[k - 1];
        sp[k] = x;
        n++;
    }
    for (j = 0; j < n && cur < f->hw && st == PLX_OK; j++) {
        if (sp[j].zlo > cur) {
            int yid = sp[j].zlo < f->hw ? sp[j].lo : FZ_TOP;
            double y = sp[j].zlo < f->hw ? sp[j].zlo : f->hw;
            if (lit_width(cur, y))
                st = facade_quad(w, f, u0, u1, cur_id, yid);
        }
        if (sp[j].zhi > cur) {
            cur = sp[j].zhi;
            cur_id = sp[j].hi;
        }
    }
    if (st == PLX_OK && cur < f->hw && lit_width(cur, f->hw)) {
        if (f->open && cur_id == FZ_BOTTOM && f->open_lo == u1)
            return facade_extend(w, f, u0);
        st = facade_quad(w, f, u0, u1, cur_id, FZ_TOP);
    }
    return st;
}

#define F_MAXCUT 256

/* Affine forms alpha + beta u of every bound a band may take. */
static int fb_forms(const lr_work *w, const fwall *f, double *al, double *be)
{
    int j, n = 0;
    double zl = w->zl;
    for (j = 0; j < f->nfb && n + 6 <= F_MAXCUT / 4; j++) {
        const fband *b = &f->fb[j];
        if (!b->inf_a) {
            al[n] = zl - (zl - b->m) * b->aa; be[n++] = -(zl - b->m) * b->ba;
            al[n] = zl + (b->h - zl) * b->aa; be[n++] = (b->h - zl) * b->ba;
        }
        al[n] = zl + (b->m - zl) * b->ab; be[n++] = (b->m - zl) * b->bb;
        al[n] = zl - (zl - b->h) * b->ab; be[n++] = -(zl - b->h) * b->bb;
        al[n] = b->m; be[n++] = 0.0;
        al[n] = b->h; be[n++] = 0.0;
    }
    al[n] = zl; be[n++] = 0.0;
    al[n] = f->mw; be[n++] = 0.0;
    al[n] = f->hw; be[n++] = 0.0;
    return n;
}

static int add_cut(double *cut, int n, double u, double p0, double p1)
{
    int i;
    if (!(u > p0 && u < p1) || n >= F_MAXCUT)
        return n;
    for (i = n; i > 0 && cut[i - 1] > u; i--)
        cut[i] = cut[i - 1];
    cut[i] = u;
    return n + 1;
}

/* Wall parameters in (p0, p1) where the order of the bounds may change. */
static int facade_cuts(const lr_work *w, const fwall *f, double p0, double p1, double *cut)
{
    double al[F_MAXCUT / 4], be[F_MAXCUT / 4];
    int n = 0, j, k, nf = fb_forms(w, f, al, be);
    for (j = 0; j < f->nfb; j++) {
        const fband *b = &f->fb[j];
        if (!b->inf_a && b->ba != 0.0)
            n = add_cut(cut, n, (1.0 - b->aa) / b->ba, p0, p1);
        if (b->bb != 0.0)
            n = add_cut(cut, n, (1.0 - b->ab) / b->bb, p0, p1);
    }
    for (j = 0; j < nf; j++)
        for (k = j + 1; k < nf; k++)
            if (be[j] != be[k])
                n = add_cut(cut, n, (al[k] - al[j]) / (be[j] - be[k]), p0, p1);
    return n;
}

/* The bands of sector i that may block wall edge e, as fbands. */
static void facade_bands(const lr_work *w, fwall *f, uint32_t e, uint32_t i, double p0,
                         double p1)
{
    uint32_t k;
    f->nfb = 0;
    for (k = w->sec_first[i]; k < w->sec_first[i + 1] && f->nfb < G_MAXB; k++) {
        const lit_band *b = &w->band[k];
        const scene_building *bd = &w->s->bld[b->bld];
        fband *x = &f->fb[f->nfb];
        if (b->lo == e)
            continue;                       /* the wall's own building */
        x->inf_a = b->lo == LIT_NONE;
        x->aa = x->ba = x->ab = x->bb = 0.0;
        if (!x->inf_a) {
            const lit_line *l = &w->line[b->lo];
            x->aa = cross2(f->a.x, f->a.y, l->ex, l->ey) / l->c;
            x->ba = cross2(f->e.x, f->e.y, l->ex, l->ey) / l->c;
            if (fb_fa(x, p0) <= 1.0 + 1e-12 && fb_fa(x, p1) <= 1.0 + 1e-12)
                continue;                   /* starts at or beyond the wall */
        }
        if (b->hi != LIT_NONE) {
            const lit_line *l = &w->line[b->hi];
            x->ab = cross2(f->a.x, f->a.y, l->ex, l->ey) / l->c;
            x->bb = cross2(f->e.x, f->e.y, l->ex, l->ey) / l->c;
        }
        x->m = bd->min_height;
        x->h = bd->height;
        f->nfb++;
    }
}

static plx_status facade_piece(lr_work *w, fwall *f, uint32_t e, uint32_t i, double p0,
                               double p1)
{
    double cut[F_MAXCUT], u0 = p0;
    int n, k;
    plx_status st = PLX_OK;
    if (w->sec_first[i + 1] - w->sec_first[i] > G_MAXB)
        return PLX_E_UNSUPPORTED; /* more bands than the polygon builder keeps: never drop one */
    facade_bands(w, f, e, i, p0, p1);
    n = f->nfb ? facade_cuts(w, f, p0, p1, cut) : 0;
    for (k = 0; k <= n && st == PLX_OK; k++) {
        double u1 = k < n ? cut[k] : p1;
        if (u1 > u0)
            st = facade_sub(w, f, u0, u1);
        u0 = u1;
    }
    return st;
}

/* u on the wall where the ray of direction d from O meets it. */
static double wall_u(const fwall *f, vec2 d)
{
    return -cross2(d.x, d.y, f->a.x, f->a.y) / cross2(d.x, d.y, f->e.x, f->e.y);
}

/* The lit part of the wall along active edge e (facing O). */
static plx_status facade_wall(lr_work *w, uint32_t e, fwall *f)
{
    const lr_edge *ed = &w->edge[e];
    const scene_building *bd = &w->s->bld[w->cand[ed->cand]];
    vec2 A = w->s->pts[ed->va], B = w->s->pts[ed->vb];
    double qa, qb, qc, disc, ulo, uhi;
    uint32_t i, i0, i1;
    plx_status st = PLX_OK;
    f->a = vsub(A, w->o);
    f->e = vsub(B, A);
    f->a3 = A;
    f->mw = bd->min_height;
    f->hw = bd->height < w->zcap ? bd->height : w->zcap;
    f->wall = ed->va;
    f->open = NULL;
    if (!(f->hw > f->mw))
        return PLX_OK;
    qa = f->e.x * f->e.x + f->e.y * f->e.y;
    qb = f->a.x * f->e.x + f->a.y * f->e.y;
    qc = f->a.x * f->a.x + f->a.y * f->a.y - w->R * w->R;
    disc = qb * qb - qa * qc;
    if (!(disc > 0.0))
        return PLX_OK;
    ulo = (-qb - sqrt(disc)) / qa;
    uhi = (-qb + sqrt(disc)) / qa;
    if (ulo < 0.0) ulo = 0.0;
    if (uhi > 1.0) uhi = 1.0;
    if (!(ulo < uhi))
        return PLX_OK;
    i0 = ed->s0;
    i1 = ed->s1;
    for (i = i0; i != i1 && st == PLX_OK; i = (i + 1 == w->nsec ? 0 : i + 1)) {
        uint32_t nx = i + 1 == w->nsec ? 0 : i + 1;
        double us = i == i0 ? 1.0 : wall_u(f, w->bdir[i]);
        double ue = nx == i1 ? 0.0 : wall_u(f, w->bdir[nx]);
        double p0 = ue > ulo ? ue : ulo, p1 = us < uhi ? us : uhi;
        if (p0 < p1)
            st = facade_piece(w, f, e, i, p0, p1);
    }
    return st;
}

static plx_status facade_emit(lr_work *w, fwall *f)
{
    uint32_t k;
    plx_status st = PLX_OK;
    w->fpts_off = (w->out.lo + 7) & ~(size_t)7;
    w->reg->fpts = (const lit_pt3 *)(const void *)(w->out.base + w->fpts_off);
    for (k = 0; k < w->nedge && st == PLX_OK; k++)
        if (w->edge[k].o < 0)
            st = facade_wall(w, k, f);
    return st;
}

/* Moves the rings stacked at the top of the output after the points. */
static const lit_ring *rings_down(obuf *b, uint32_t n)
{
    lit_ring *top = (lit_ring *)(void *)(b->base + b->cap), *dst;
    uint32_t k;
    dst = ob_up(b, (size_t)n * sizeof *dst + 1);
    if (!dst)
        return NULL;
    b->lo -= 1;
    for (k = 0; k < n; k++)
        dst[k] = top[-(ptrdiff_t)k - 1];
    b->hi = 0;
    return dst;
}

/* ---- computing one region ------------------------------------------------------------ */

static plx_status region_work(lr_work *w, uint32_t lamp)
{
    uint32_t nv;
    plx_status st = gather(w);
    if (st != PLX_OK)
        return st;
    nv = cand_vertices(w);
    st = sectors(w, nv);
    if (st == PLX_OK)
        st = edges(w, nv);
    if (st == PLX_OK)
        st = incidences(w);
    (void)lamp;
    return st;
}

/* Everything after the working arrays: index, ground, facades. */
static plx_status region_output(lr_work *w, uint32_t lamp, int polygons)
{
    gpiece *g = arena_scratch(w->L->a, sizeof *g, LR_ALIGN);
    fwall *f = arena_scratch(w->L->a, sizeof *f, LR_ALIGN);
    uint32_t i, maxinc = 0;
    size_t room;
    plx_status st;
    if (!g || !f)
        return PLX_E_NOMEM;
    if (polygons && w->Rg > 0.0) {
        /* a sector's ground lines are some of its active edges, scaled */
        for (i = 0; i < w->nsec; i++)
            if (w->inc_first[i + 1] - w->inc_first[i] > maxinc)
                maxinc = w->inc_first[i + 1] - w->inc_first[i];
        g->cutcap = ground_cut_cap(maxinc);
        g->cut = arena_scratch(w->L->a, arena_mul(g->cutcap, sizeof *g->cut), LR_ALIGN);
        if (!g->cut)
            return PLX_E_NOMEM;
    }
    room = arena_free_bytes(w->L->a);
    room = room > 256 ? room - 256 : 0;
    if (room > w->L->pool_cap)
        room = w->L->pool_cap;
    w->out.base = arena_scratch(w->L->a, room, LR_ALIGN);
    w->out.cap = room;
    w->out.lo = w->out.hi = 0;
    if (!w->out.base)
        return PLX_E_NOMEM;
    st = index_emit(w, lamp);
    if (st == PLX_OK)
        w->reg->polygons = polygons;
    if (st == PLX_OK && w->Rg > 0.0 && polygons)
        st = ground_emit(w, g);
    if (st == PLX_OK)
        st = (w->reg->ground = rings_down(&w->out, w->reg->nground)) ? PLX_OK : PLX_E_NOMEM;
    if (st == PLX_OK && polygons)
        st = facade_emit(w, f);
    if (st == PLX_OK)
        st = (w->reg->facade = rings_down(&w->out, w->reg->nfacade)) ? PLX_OK : PLX_E_NOMEM;
    if (st == PLX_OK)
        w->reg->bytes = (w->out.lo + LR_ALIGN - 1) & ~(size_t)(LR_ALIGN - 1);
    return st;
}

/* ---- the cache ------------------------------------------------------------------------ */

static void lru_unlink(light *L, uint32_t i)
{
    light_entry *e = &L->ent[i];
    if (e->prev != LIT_NONE) L->ent[e->prev].next = e->next; else L->lru_head = e->next;
    if (e->next != LIT_NONE) L->ent[e->next].prev = e->prev; else L->lru_tail = e->prev;
    e->prev = e->next = LIT_NONE;
}

static void lru_front(light *L, uint32_t i)
{
    light_entry *e = &L->ent[i];
    e->prev = LIT_NONE;
    e->next = L->lru_head;
    if (L->lru_head != LIT_NONE) L->ent[L->lru_head].prev = i; else L->lru_tail = i;
    L->lru_head = i;
}

static void addr_unlink(light *L, uint32_t i)
{
    light_entry *e = &L->ent[i];
    if (e->aprev != LIT_NONE) L->ent[e->aprev].anext = e->anext; else L->addr_head = e->anext;
    if (e->anext != LIT_NONE) L->ent[e->anext].aprev = e->aprev; else L->addr_tail = e->aprev;
    e->aprev = e->anext = LIT_NONE;
}

static void addr_append(light *L, uint32_t i)
{
    light_entry *e = &L->ent[i];
    e->anext = LIT_NONE;
    e->aprev = L->addr_tail;
    if (L->addr_tail != LIT_NONE) L->ent[L->addr_tail].anext = i; else L->addr_head = i;
    L->addr_tail = i;
}

static void evict(light *L, uint32_t i)
{
    L->pool_live -= L->ent[i].reg->bytes;
    lru_unlink(L, i);
    addr_unlink(L, i);
    L->ent[i].reg = NULL;
    L->ncached--;
    L->st.evictions++;
}

/* Fixes the pointers of a region copied from 'from' to 'to' (arrays an
 * index-only region lacks stay NULL). */
#define REBASE(p, T) \
    ((p) = (p) ? (T)(void *)(to + ((const unsigned char *)(const void *)(p) - from)) : NULL)
static void rebase(lit_region *r, const unsigned char *from, unsigned char *to)
{
    REBASE(r->sec_ang, const double *);
    REBASE(r->sec_first, const uint32_t *);
    REBASE(r->band, const lit_band *);
    REBASE(r->line, const lit_line *);
    REBASE(r->ground, const lit_ring *);
    REBASE(r->gpts, const vec2 *);
    REBASE(r->facade, const lit_ring *);
    REBASE(r->fpts, const lit_pt3 *);
}
#undef REBASE

static void compact(light *L)
{
    uint32_t i;
    size_t dst = 0;
    for (i = L->addr_head; i != LIT_NONE; i = L->ent[i].anext) {
        unsigned char *src = (unsigned char *)L->ent[i].reg;
        size_t n = L->ent[i].reg->bytes;
        if (src != L->pool + dst) {
            memmove(L->pool + dst, src, n);
            L->ent[i].reg = (lit_region *)(void *)(L->pool + dst);
            rebase(L->ent[i].reg, src, L->pool + dst);
        }
        dst += n;
    }
    L->pool_end = dst;
    L->st.compactions++;
}

static plx_status cache_insert(light *L, uint32_t lamp, const lit_region *r)
{
    size_t n = r->bytes;
    unsigned char *dst;
    if (n > L->pool_cap)
        return PLX_E_NOMEM;
    while (L->pool_cap - L->pool_live < n && L->lru_tail != LIT_NONE)
        evict(L, L->lru_tail);
    if (L->pool_cap - L->pool_end < n) {
        /* Compaction moves every live region: free a quarter of the pool
         * beyond what this region needs first, so a full cache compacts once
         * per cap/4 bytes inserted, not on every miss (amortised O(1) per
         * byte instead of O(pool)). */
        size_t keep = L->pool_cap - L->pool_cap / 4;
        while (L->pool_live + n > keep && L->lru_tail != LIT_NONE)
            evict(L, L->lru_tail);
        compact(L);
    }
    PLX_ASSERT(L->pool_cap - L->pool_end >= n); /* eviction and compaction made room */
    dst = L->pool + L->pool_end;
    memcpy(dst, r, n);
    L->ent[lamp].reg = (lit_region *)(void *)dst;
    rebase(L->ent[lamp].reg, (const unsigned char *)r, dst);
    L->pool_end += n;
    L->pool_live += n;
    L->ncached++;
    lru_front(L, lamp);
    addr_append(L, lamp);
    return PLX_OK;
}

static plx_status region_compute(light *L, uint32_t lamp, int polygons)
{
    const scene_lamp *lp = &L->s->lamps[lamp];
    arena_mark m = arena_get_mark(L->a);
    lr_work w;
    plx_status st;
    memset(&w, 0, sizeof w);
    w.L = L;
    w.s = L->s;
    w.o.x = lp->x;
    w.o.y = lp->y;
    w.zl = lp->z;
    w.R = lp->radius > 0.0 ? lp->radius : 0.0;
    w.Rg = w.R > w.zl ? sqrt(w.R * w.R - w.zl * w.zl) : 0.0;
    /* SPEC §2.1: a lamp whose I is 0 from gamma_lit <= 90 deg on (untilted)
     * lights nothing above its horizon, and no ground beyond zL tan(gamma_lit) */
    w.zcap = INFINITY;
    if (lp->photometry && lp->tilt == 0.0) {
        double gl = lp->phot ? lp->phot->gamma_lit : 0.0;
        if (gl <= 90.0)
            w.zcap = w.zl;
        if (gl < 90.0 && w.zl * tan(gl * 3.14159265358979323846 / 180.0) < w.Rg)
            w.Rg = w.zl * tan(gl * 3.14159265358979323846 / 180.0);
    }
    st = region_work(&w, lamp);
    if (st == PLX_OK)
        st = region_output(&w, lamp, polygons);
    if (st == PLX_OK)
        st = cache_insert(L, lamp, w.reg);
    if (st == PLX_OK)
        L->st.computed++;
    arena_release(L->a, &m);
    return st;
}

/* Forgets which lamps' regions ran out of memory. */
static void fail_clear(light *L)
{
    memset(L->failed, 0, (size_t)L->s->nlamps / 8 + 1);
    L->fail_free = 0;
}

static plx_status region_get(light *L, uint32_t lamp, int polygons, const lit_region **out)
{
    plx_status st;
    if (!L || !out || lamp >= L->s->nlamps)
        return PLX_E_INVALID;
    *out = NULL;
    if (L->ent[lamp].reg && (L->ent[lamp].reg->polygons || !polygons)) {
        L->st.hits++;
        if (L->lru_head != lamp) {
            lru_unlink(L, lamp);
            lru_front(L, lamp);
        }
        *out = L->ent[lamp].reg;
        return PLX_OK;
    }
    L->st.misses++;
    if (L->pool_cap == 0)
        return PLX_E_NOMEM;
    /* it ran out of memory with this much free or more: the same again
     * (a frame near the block's smallest --mem asked every lamp in view
     * at every pixel, each failing late: 100 times slower than with 30
     * KB more) */
    if (L->failed[lamp >> 3] & (1u << (lamp & 7))) {
        if (arena_free_bytes(L->a) <= L->fail_free)
            return PLX_E_NOMEM;
        fail_clear(L); /* more memory now: every lamp may be tried again */
    }
    if (L->ent[lamp].reg)
        evict(L, lamp);             /* index only: replaced by the full region */
    st = region_compute(L, lamp, polygons);
    if (st == PLX_E_NOMEM) {
        size_t f = arena_free_bytes(L->a);
        L->failed[lamp >> 3] |= (unsigned char)(1u << (lamp & 7));
        L->fail_free = f > L->fail_free ? f : L->fail_free;
        L->st.failed++;
    }
    if (st == PLX_OK)
        *out = L->ent[lamp].reg;
    /* the cache stays inside its pool; a region got is at the LRU head */
    PLX_ASSERT(L->pool_end <= L->pool_cap && L->pool_live <= L->pool_end);
    PLX_ASSERT(st != PLX_OK || (*out && L->lru_head == lamp));
    return st;
}

plx_status light_region(light *L, uint32_t lamp, const lit_region **out)
{
    return region_get(L, lamp, 1, out);
}

plx_status light_region_index(light *L, uint32_t lamp, const lit_region **out)
{
    return region_get(L, lamp, 0, out);
}

void light_cache_clear(light *L)
{
    while (L->lru_tail != LIT_NONE)
        evict(L, L->lru_tail);
    L->pool_end = 0;
    fail_clear(L);
}

void light_cache_reset(light *L)
{
    light_cache_clear(L);
    memset(&L->st, 0, sizeof L->st);
    memset(L->stamp, 0, sizeof *L->stamp * (L->s->nbld + 1));
    L->stamp_now = 0; /* the next visit is 1: no building is marked */
}

/* ---- visibility through a region --------------------------------------------------- */

/* The part of the segment from the lamp to P (as a fraction of it) that
 * band b's building covers; <= 0 when none. */
static double band_overlap(const lit_region *r, const lit_band *b, const scene_building *bd,
                           vec2 w, double zp)
{
    double t1, t2, ta = 0.0, tb = INFINITY, dz = zp - r->o[2], x, y;
    if (dz == 0.0) {
        if (!(r->o[2] > bd->min_height && r->o[2] < bd->height))
            return 0.0;
        t1 = 0.0;
        t2 = 1.0;
    } else {
        t1 = (bd->min_height - r->o[2]) / dz;
        t2 = (bd->height - r->o[2]) / dz;
        if (t1 > t2) {
            double c = t1;
            t1 = t2;
            t2 = c;
        }
        if (t1 < 0.0) t1 = 0.0;
        if (t2 > 1.0) t2 = 1.0;
    }
    if (b->lo != LIT_NONE) {
        const lit_line *l = &r->line[b->lo];
        ta = l->c / cross2(w.x, w.y, l->ex, l->ey);
    }
    if (b->hi != LIT_NONE) {
        const lit_line *l = &r->line[b->hi];
        tb = l->c / cross2(w.x, w.y, l->ex, l->ey);
    }
    x = ta > t1 ? ta : t1;
    y = tb < t2 ? tb : t2;
    return y - x;
}

static inline int region_visible(light *L, const lit_region *r, const double P[3])
{
    vec2 w;
    double len3 = -1.0;
    uint32_t i, k;
    w.x = P[0] - r->o[0];
    w.y = P[1] - r->o[1];
    if (w.x == 0.0 && w.y == 0.0)
        return !light_segment_blocked(L, r->o, P);
    i = find_sector(r->sec_ang, r->nsec, light_pseudo_angle(w.x, w.y));
    for (k = r->sec_first[i]; k < r->sec_first[i + 1]; k++) {
        const lit_band *b = &r->band[k];
        double ov = band_overlap(r, b, &L->s->bld[b->bld], w, P[2]);
        /* blocked by more than LIGHT_MIN_PIECE of 3D length (the length
         * taken only when a band covers some of the segment: most do not) */
        if (ov > 0.0) {
            if (len3 < 0.0) {
                double dz = P[2] - r->o[2];
                len3 = sqrt(w.x * w.x + w.y * w.y + dz * dz);
            }
            if (ov * len3 > LIGHT_MIN_PIECE)
                return 0;
        }
    }
    return 1;
}

int light_region_visible(light *L, const lit_region *r, const double P[3])
{
    return region_visible(L, r, P);
}

int light_lamp_visible_cached(light *L, uint32_t lamp, const double P[3])
{
    const lit_region *r = L->ent[lamp].reg;
    if (!r)
        return -1;
    L->st.hits++;
    if (L->lru_head != lamp) {
        lru_unlink(L, lamp);
        lru_front(L, lamp);
    }
    return region_visible(L, r, P);
}
