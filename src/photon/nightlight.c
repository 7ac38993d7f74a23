/* nightlight: munoz2013's night lighting of the ground: per-lamp floor
 * photon maps in an LRU cache and their exchange with the aerial chart
 * (munoz2013 §3.3-3.4; see nightlight.h and photon.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "photon/photon.h"
#include "scene/photometry.h"
#include "photon/nightlight.h"

#define PI 3.14159265358979323846
#define HEIGHT_TOL 1e-3

typedef struct lamp_ctx {
    photon_lamp_slot *sl;
    int push;             /* first computation: also into I */
    photon_stats st;
} lamp_ctx;

static void store_lamp(photon_sys *ps, void *vctx, uint32_t lamp, const trace_hit *h,
                       const double f[PHOTON_CH])
{
    lamp_ctx *c = vctx;
    photon_lamp_slot *sl = c->sl;
    uint32_t F = ps->cfg.lamp_res;
    double fx, fy, gx, gy, key;
    (void)lamp;
    if (h->kind != TRACE_GROUND && h->kind != TRACE_ROOF)
        return;
    photon_aerial_xy(ps, h->p[0], h->p[1], &gx, &gy);
    if (h->kind == TRACE_GROUND && photon_covered_at(ps, h->p[0], h->p[1])) {
        /* covered ground: only I_cov (no floor map, so neither C nor D) */
        if (c->push)
            photon_splat_sparse(ps->cov_imp, ps->cov_area, ps->gcov, ps->gw, ps->gh, gx, gy,
                                ps->cfg.kernel_min, f);
        return;
    }
    key = surface_key(&ps->keys, ps->s, h->p[0], h->p[1], h->p[2]);
    fx = (h->p[0] - sl->x0) / sl->texel;
    fy = (h->p[1] - sl->y0) / sl->texel;
    if (fx >= 0.0 && fy >= 0.0 && fx < (double)F && fy < (double)F &&
        photon_splat(sl->flux, sl->area, sl->height, key, F, F, 0, fx, fy,
                     ps->cfg.lamp_kernel, f)) {
        /* in C: also its aerial-resolution copy D (same kernel as I) */
        photon_splat_win(sl->dwin, ps->dwin_n, ps->dwin_n, sl->dx0, sl->dy0, ps->garea,
                         ps->gheight, key, ps->gw, ps->gh, gx, gy, ps->cfg.kernel_min, f);
    }
    if (c->push)
        photon_splat(ps->gimp, ps->garea, ps->gheight, key, ps->gw, ps->gh, 0, gx, gy,
                     ps->cfg.kernel_min, f);
}

/* Computes lamp i's floor map into slot sl. */
static void lamp_compute(photon_sys *ps, uint32_t i, photon_lamp_slot *sl)
{
    const scene_lamp *L = &ps->s->lamps[i];
    uint32_t F = ps->cfg.lamp_res, k = ps->cfg.coverage_probes, a, b, x, y, n;
    size_t f2 = (size_t)F * F;
    double R = L->radius > 0.0 ? L->radius : 1.0, t;
    uint32_t margin = (uint32_t)ceil(ps->cfg.kernel_min) + 2u;
    lamp_ctx c;
    uint64_t rng;
    double phi;
    sl->texel = t = 2.0 * R / F;
    sl->x0 = L->x - R;
    sl->y0 = L->y - R;
    sl->dx0 = (int32_t)floor((sl->x0 - ps->gx0) / ps->gtex) - (int32_t)margin;
    sl->dy0 = (int32_t)floor((sl->y0 - ps->gy0) / ps->gtex) - (int32_t)margin;
    memset(sl->flux, 0, f2 * PHOTON_CH * sizeof(float));
    memset(sl->dwin, 0, (size_t)ps->dwin_n * ps->dwin_n * PHOTON_CH * sizeof(float));
    for (y = 0; y < F; y++)
        for (x = 0; x < F; x++) {
            double cx = sl->x0 + (x + 0.5) * t, cy = sl->y0 + (y + 0.5) * t;
            double hc = surface_key(&ps->keys, ps->s, cx, cy, trace_top(ps->T, cx, cy, NULL));
            uint32_t match = 0;
            for (b = 0; b < k; b++)
                for (a = 0; a < k; a++) {
                    double px = sl->x0 + (x + (a + 0.5) / k) * t;
                    double py = sl->y0 + (y + (b + 0.5) / k) * t;
                    if (fabs(surface_key(&ps->keys, ps->s, px, py, trace_top(ps->T, px, py, NULL)) - hc) <= HEIGHT_TOL)
                        match++;
                }
            if (match == 0)
                match = 1;
            sl->height[(size_t)y * F + x] = (float)hc;
            sl->area[(size_t)y * F + x] = (float)(t * t * match / (double)(k * k));
        }
    memset(&c, 0, sizeof c);
    c.sl = sl;
    c.push = !ps->refined[i];
    n = ps->cfg.lamp_photons;
    if (n > 0 && L->intensity > 0.0 && L->radius > 0.0 && lamp_flux(L) > 0.0) {
        phi = lamp_flux(L) / n;
        /* deterministic per lamp: a recomputation gives the same photons */
        rng = 0x6a09e667f3bcc909ull ^ ((uint64_t)i * 0x9e3779b97f4a7c15ull);
        rng = photon_rand(&rng);
        rng = photon_rand(&rng);
        for (a = 0; a < n; a++)
            photon_trace_lamp(ps, i, phi, &rng, &c.st, store_lamp, &c);
    }
    if (c.push) {
        ps->refined[i] = 1;
        ps->st.lamp_refined++;
        /* A restarts without lamp i (its older photons leave A) */
        memset(ps->gflux, 0, (size_t)ps->gw * ps->gh * PHOTON_CH * sizeof(float));
        if (ps->cov_cap > 0)
            memset(ps->cov_flux, 0, (size_t)ps->cov_cap * PHOTON_CH * sizeof(float));
        ps->gframes = 0;
        ps->st.aerial_restarts++;
    }
}

static void lru_unlink(photon_sys *ps, uint32_t s)
{
    photon_lamp_slot *sl = &ps->slots[s];
    if (sl->prev != PHOTON_NONE)
        ps->slots[sl->prev].next = sl->next;
    else
        ps->lru_head = sl->next;
    if (sl->next != PHOTON_NONE)
        ps->slots[sl->next].prev = sl->prev;
    else
        ps->lru_tail = sl->prev;
    sl->prev = sl->next = PHOTON_NONE;
}

static void lru_front(photon_sys *ps, uint32_t s)
{
    photon_lamp_slot *sl = &ps->slots[s];
    sl->prev = PHOTON_NONE;
    sl->next = ps->lru_head;
    if (ps->lru_head != PHOTON_NONE)
        ps->slots[ps->lru_head].prev = s;
    ps->lru_head = s;
    if (ps->lru_tail == PHOTON_NONE)
        ps->lru_tail = s;
}

int photon_lamp_request(photon_sys *ps, uint32_t lamp)
{
    uint32_t s;
    if (!ps || lamp >= ps->s->nlamps || ps->nslots == 0)
        return -1;
    s = ps->lamp_slot[lamp];
    if (s != PHOTON_NONE) {
        ps->st.lamp_hits++;
        if (ps->lru_head != s) {
            lru_unlink(ps, s);
            lru_front(ps, s);
        }
        return 1;
    }
    ps->st.lamp_misses++;
    s = ps->lru_tail;
    if (ps->slots[s].lamp != PHOTON_NONE) {
        ps->lamp_slot[ps->slots[s].lamp] = PHOTON_NONE;
        ps->st.lamp_evictions++;
    }
    ps->slots[s].lamp = PHOTON_NONE;
    lamp_compute(ps, lamp, &ps->slots[s]);
    ps->slots[s].lamp = lamp;
    ps->lamp_slot[lamp] = s;
    lru_unlink(ps, s);
    lru_front(ps, s);
    return 0;
}

int photon_lamp_cached(const photon_sys *ps, uint32_t lamp)
{
    if (!ps || lamp >= ps->s->nlamps)
        return 0;
    return ps->lamp_slot[lamp] != PHOTON_NONE;
}

uint32_t photon_lamp_lru(const photon_sys *ps, uint32_t *lamps, uint32_t cap)
{
    uint32_t s, n = 0;
    if (!ps)
        return 0;
    for (s = ps->lru_head; s != PHOTON_NONE; s = ps->slots[s].next)
        if (ps->slots[s].lamp != PHOTON_NONE) {
            if (n < cap && lamps)
                lamps[n] = ps->slots[s].lamp;
            n++;
        }
    return n;
}

typedef struct near_lamp {
    double d2;
    uint32_t id;
} near_lamp;

static int cmp_near(const void *a, const void *b)
{
    const near_lamp *x = a, *y = b;
    if (x->d2 != y->d2)
        return x->d2 < y->d2 ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

int photon_lamps_update(photon_sys *ps, const double eye[3])
{
    const scene *s;
    arena_mark m;
    near_lamp *cand;
    uint32_t i, n = 0, use;
    double r2;
    int misses = 0;
    if (!ps || !eye)
        return -1;
    s = ps->s;
    if (ps->nslots == 0 || s->nlamps == 0)
        return 0;
    m = arena_get_mark(ps->a);
    cand = arena_scratch(ps->a, (size_t)s->nlamps * sizeof *cand, 16);
    if (!cand)
        return -1;
    r2 = ps->cfg.near_radius * ps->cfg.near_radius;
    for (i = 0; i < s->nlamps; i++) {
        double dx = s->lamps[i].x - eye[0], dy = s->lamps[i].y - eye[1];
        double d2 = dx * dx + dy * dy;
        if (d2 <= r2) {
            cand[n].d2 = d2;
            cand[n].id = i;
            n++;
        }
    }
    qsort(cand, n, sizeof *cand, cmp_near);
    use = n < ps->nslots ? n : ps->nslots;
    /* farthest first, so the nearest ends most recently used */
    for (i = use; i > 0; i--)
        if (photon_lamp_request(ps, cand[i - 1].id) == 0)
            misses++;
    arena_release(ps->a, &m);
    return misses;
}

void photon_night_horizontal(const photon_sys *ps, double x, double y, double z, int covered,
                             double e[PHOTON_CH])
{
    double gx, gy, t[PHOTON_CH];
    uint32_t s, F;
    int c;
    for (c = 0; c < PHOTON_CH; c++)
        e[c] = 0.0;
    if (!ps || ps->st.lamp_refined == 0)
        return;
    photon_aerial_xy(ps, x, y, &gx, &gy);
    if (covered) {
        photon_gather_sparse(ps->cov_imp, ps->cov_area, ps->gcov, ps->gw, ps->gh, gx, gy, e);
        return;
    }
    photon_gather(ps->gimp, ps->garea, ps->gheight, z, ps->gw, ps->gh, 0, gx, gy, e);
    F = ps->cfg.lamp_res;
    /* in slot order, not LRU order: a hit reorders the LRU list but moves
     * no slot, so the sum keeps its bits until a miss changes the cached
     * lamps (plx_indirect_refine keys the frames' caches on that) */
    for (s = 0; s < ps->nslots; s++) {
        const photon_lamp_slot *sl = &ps->slots[s];
        double fx, fy;
        if (sl->lamp == PHOTON_NONE)
            continue;
        fx = (x - sl->x0) / sl->texel;
        fy = (y - sl->y0) / sl->texel;
        if (!(fx >= 0.0 && fy >= 0.0 && fx < (double)F && fy < (double)F))
            continue;
        photon_gather(sl->flux, sl->area, sl->height, z, F, F, 0, fx, fy, t);
        for (c = 0; c < PHOTON_CH; c++)
            e[c] += t[c];
        photon_gather_win(sl->dwin, ps->dwin_n, ps->dwin_n, sl->dx0, sl->dy0, ps->garea,
                          ps->gheight, z, ps->gw, ps->gh, gx, gy, t);
        for (c = 0; c < PHOTON_CH; c++)
            e[c] -= t[c];
    }
}
