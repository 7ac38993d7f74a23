/* light: the light object (grids of buildings and lamps, the region cache
 * it holds), the exact segment test, point classification (contract in
 * light.h; lit regions and the cache are in litregion.c, illuminance in
 * illuminance.c). */
#include "light/light.h"
#include "base/geom.h"
#include "scene/photometry.h"

#include <math.h>
#include <string.h>

#define LIGHT_ALIGN 16

/* ---- small helpers ------------------------------------------------------ */

double light_pseudo_angle(double dx, double dy)
{
    if (dy >= 0.0) {
        if (dx > 0.0)
            return dy / (dx + dy);
        return 1.0 + (-dx) / (dy - dx);
    }
    if (dx < 0.0)
        return 2.0 + (-dy) / (-dx - dy);
    return 3.0 + dx / (dx - dy);
}

static const vec2 *ring_pts(const scene *s, uint32_t r, uint32_t *n)
{
    *n = s->rings[r].count;
    return s->pts + s->rings[r].first;
}

/* ---- uniform grids -------------------------------------------------------- */

/* Sets the grid frame over the union of the boxes (a box with min > max is
 * left out) with cells of about 'cell' metres, at most about 'maxcells' of
 * them; returns the cell size. */
static double grid_frame(bucketgrid *g, const double (*box)[4], uint32_t n, double cell,
                       double maxcells)
{
    double lo[2] = { 0.0, 0.0 }, hi[2] = { 1.0, 1.0 }, w, h;
    uint32_t i;
    int any = 0;
    for (i = 0; i < n; i++) {
        if (!(box[i][0] <= box[i][2]))
            continue;
        if (!any || box[i][0] < lo[0]) lo[0] = box[i][0];
        if (!any || box[i][1] < lo[1]) lo[1] = box[i][1];
        if (!any || box[i][2] > hi[0]) hi[0] = box[i][2];
        if (!any || box[i][3] > hi[1]) hi[1] = box[i][3];
        any = 1;
    }
    w = hi[0] - lo[0];
    h = hi[1] - lo[1];
    if (!(cell > 0.0) || !isfinite(cell))
        cell = 1.0;
    if ((w / cell + 1.0) * (h / cell + 1.0) > maxcells)
        cell = sqrt((w + cell) * (h + cell) / maxcells) + 1e-9;
    bucketgrid_frame(g, lo[0], lo[1], cell, (uint32_t)(w / cell) + 1, (uint32_t)(h / cell) + 1);
    return cell;
}

static plx_status build_grids(light *L, arena *a)
{
    const scene *s = L->s;
    uint32_t n = s->nbld > s->nlamps ? s->nbld : s->nlamps, i;
    double (*box)[4] = arena_scratch(a, arena_mul(n + 1, sizeof *box), LIGHT_ALIGN);
    double size = 0.0, reach = 0.0;
    plx_status st;
    if (!box)
        return PLX_E_NOMEM;
    for (i = 0; i < s->nbld; i++) {
        memcpy(box[i], s->bld[i].box, sizeof box[i]);
        size += sqrt((box[i][2] - box[i][0]) * (box[i][3] - box[i][1]));
    }
    L->bcell = grid_frame(&L->bgrid, (const double (*)[4])box, s->nbld,
                          s->nbld ? 1.5 * size / s->nbld : 1.0, 4.0 * s->nbld + 64.0);
    st = bucketgrid_fill(&L->bgrid, a, PLX_PART_LIT, LIGHT_ALIGN, box[0], NULL, s->nbld);
    for (i = 0, n = 0; st == PLX_OK && i < s->nlamps; i++) {
        const scene_lamp *lp = &s->lamps[i];
        double R = lp->radius;
        box[i][0] = 1.0;
        box[i][2] = 0.0;   /* left out unless the lamp can light anything */
        if (!(R > 0.0) || !isfinite(R) || !(lp->intensity != 0.0 || lp->photometry))
            continue;
        box[i][0] = lp->x - R;
        box[i][1] = lp->y - R;
        box[i][2] = lp->x + R;
        box[i][3] = lp->y + R;
        reach += R;
        n++;
    }
    if (st == PLX_OK) {
        grid_frame(&L->lgrid, (const double (*)[4])box, s->nlamps,
                   n ? 0.5 * reach / n : 1.0, 16.0 * n + 64.0);
        st = bucketgrid_fill(&L->lgrid, a, PLX_PART_LIT, LIGHT_ALIGN, box[0], NULL, s->nlamps);
    }
    return st;
}

/* ---- creation ------------------------------------------------------------- */

static uint32_t max_vertices(const scene *s)
{
    uint32_t i, r, best = 0;
    for (i = 0; i < s->nbld; i++) {
        uint32_t n = 0;
        for (r = 0; r < s->bld[i].ring_count; r++)
            n += s->rings[s->bld[i].ring_first + r].count;
        if (n > best)
            best = n;
    }
    return best;
}

static void init_rays(light *L)
{
    int k;
    for (k = 0; k < 360; k++) {
        double th = (double)k * (3.14159265358979323846 / 180.0);
        L->ray_dir[k][0] = cos(th);
        L->ray_dir[k][1] = sin(th);
        L->ray_ang[k] = light_pseudo_angle(L->ray_dir[k][0], L->ray_dir[k][1]);
    }
    /* exact axis directions */
    L->ray_dir[0][1] = L->ray_dir[180][1] = 0.0;
    L->ray_dir[90][0] = L->ray_dir[270][0] = 0.0;
    L->ray_ang[0] = 0.0; L->ray_ang[90] = 1.0; L->ray_ang[180] = 2.0; L->ray_ang[270] = 3.0;
}

static plx_status create_parts(light *L, arena *a, size_t cache_bytes)
{
    const scene *s = L->s;
    uint32_t v = L->maxv + 1, i;
    L->stamp = arena_calloc(a, PLX_PART_LIT, s->nbld + 1, sizeof *L->stamp, LIGHT_ALIGN);
    L->cross_t = arena_alloc(a, PLX_PART_LIT, arena_mul(v, sizeof(double)), LIGHT_ALIGN);
    L->cross_d = arena_alloc(a, PLX_PART_LIT, arena_mul(v, sizeof(int)), LIGHT_ALIGN);
    L->col = arena_alloc(a, PLX_PART_LIT, arena_mul(2 * (size_t)v, sizeof(double)), LIGHT_ALIGN);
    L->ent = arena_alloc(a, PLX_PART_LIT, arena_mul(s->nlamps + 1, sizeof *L->ent), LIGHT_ALIGN);
    L->failed = arena_calloc(a, PLX_PART_LIT, (size_t)s->nlamps / 8 + 1, 1, LIGHT_ALIGN);
    L->fail_free = 0;
    if (!L->stamp || !L->cross_t || !L->cross_d || !L->col || !L->ent || !L->failed)
        return PLX_E_NOMEM;
    for (i = 0; i < s->nlamps; i++) {
        L->ent[i].reg = NULL;
        L->ent[i].prev = L->ent[i].next = LIT_NONE;
        L->ent[i].aprev = L->ent[i].anext = LIT_NONE;
    }
    L->lru_head = L->lru_tail = L->addr_head = L->addr_tail = LIT_NONE;
    L->pool_cap = cache_bytes & ~(size_t)(LIGHT_ALIGN - 1);
    L->pool = NULL;
    if (L->pool_cap) {
        L->pool = arena_alloc(a, PLX_PART_LIT, L->pool_cap, LIGHT_ALIGN);
        if (!L->pool)
            return PLX_E_NOMEM;
    }
    return PLX_OK;
}

plx_status light_create(arena *a, const scene *s, size_t cache_bytes, light **out)
{
    arena_mark m;
    light *L;
    plx_status st;
    if (!a || !s || !out)
        return PLX_E_INVALID;
    *out = NULL;
    m = arena_get_mark(a);
    L = arena_calloc(a, PLX_PART_LIT, 1, sizeof *L, LIGHT_ALIGN);
    if (!L)
        return PLX_E_NOMEM;
    L->a = a;
    L->s = s;
    L->maxv = max_vertices(s);
    init_rays(L);
    st = create_parts(L, a, cache_bytes);
    if (st == PLX_OK) {
        arena_mark sm = arena_get_mark(a), now;
        st = build_grids(L, a);
        /* drop the scratch of the grids only (keep their persistent lists) */
        now = arena_get_mark(a);
        now.hi = sm.hi;
        now.used[PLX_PART_SCRATCH] = sm.used[PLX_PART_SCRATCH];
        arena_release(a, &now);
    }
    if (st != PLX_OK) {
        arena_release(a, &m);
        return st;
    }
    *out = L;
    return PLX_OK;
}

size_t light_base_bytes(const scene *s)
{
    size_t v = max_vertices(s) + 1;
    return sizeof(light) + 4 * (s->nbld + 1) + v * (8 + 4 + 16) +
           (s->nlamps + 1) * sizeof(light_entry) + s->nlamps / 8 + 1;
}

/* ---- the exact segment test ---------------------------------------------- */

static int footprint_strictly_inside(const scene *s, uint32_t b, vec2 p)
{
    const scene_building *bd = &s->bld[b];
    uint32_t r, n;
    const vec2 *q = ring_pts(s, bd->ring_first, &n);
    if (geom_point_in_ring(p, q, n) != GEOM_INSIDE)
        return 0;
    for (r = 1; r < bd->ring_count; r++) {
        q = ring_pts(s, bd->ring_first + r, &n);
        if (geom_point_in_ring(p, q, n) != GEOM_OUTSIDE)
            return 0;
    }
    return 1;
}

/* Parameter along a + t D of the meeting with edge u -> v, given the exact
 * sides su, sv of u and v (a zero side means the vertex is on the line). */
static double cross_param(vec2 a, vec2 D, double dd, vec2 u, vec2 v, int su, int sv)
{
    double ex, ey;
    if (su == 0)
        return ((u.x - a.x) * D.x + (u.y - a.y) * D.y) / dd;
    if (sv == 0)
        return ((v.x - a.x) * D.x + (v.y - a.y) * D.y) / dd;
    ex = v.x - u.x;
    ey = v.y - u.y;
    return ((u.x - a.x) * ey - (u.y - a.y) * ex) / (D.x * ey - D.y * ex);
}

typedef struct seg_work {
    double *t;  int *d;  uint32_t n;   /* crossings of the line */
    double *col; uint32_t ncol;        /* collinear edge ranges (pairs) */
} seg_work;

/* Crossings of the whole line through a, p (a != p) with the boundary of
 * building b, the line shifted infinitesimally to its right. */
static void line_crossings(const scene *s, uint32_t b, vec2 a, vec2 p, seg_work *w)
{
    const scene_building *bd = &s->bld[b];
    vec2 D;
    double dd;
    uint32_t r, j, n;
    D.x = p.x - a.x;
    D.y = p.y - a.y;
    dd = D.x * D.x + D.y * D.y;
    w->n = w->ncol = 0;
    for (r = 0; r < bd->ring_count; r++) {
        const vec2 *q = ring_pts(s, bd->ring_first + r, &n);
        vec2 u = q[n - 1];
        int su = geom_orient(a, p, u);
        for (j = 0; j < n; j++) {
            vec2 v = q[j];
            int sv = geom_orient(a, p, v);
            if ((su >= 0) != (sv >= 0)) {
                w->t[w->n] = cross_param(a, D, dd, u, v, su, sv);
                w->d[w->n++] = su >= 0 ? 1 : -1;
            } else if (su == 0 && sv == 0) {
                double tu = ((u.x - a.x) * D.x + (u.y - a.y) * D.y) / dd;
                double tv = ((v.x - a.x) * D.x + (v.y - a.y) * D.y) / dd;
                w->col[2 * w->ncol] = tu < tv ? tu : tv;
                w->col[2 * w->ncol + 1] = tu < tv ? tv : tu;
                w->ncol++;
            }
            u = v;
            su = sv;
        }
    }
}

static void sort_crossings(seg_work *w)
{
    uint32_t i, j;
    for (i = 1; i < w->n; i++) {
        double t = w->t[i];
        int d = w->d[i];
        for (j = i; j > 0 && w->t[j - 1] > t; j--) {
            w->t[j] = w->t[j - 1];
            w->d[j] = w->d[j - 1];
        }
        w->t[j] = t;
        w->d[j] = d;
    }
    for (i = 1; i < w->ncol; i++) {
        double c0 = w->col[2 * i], c1 = w->col[2 * i + 1];
        for (j = i; j > 0 && w->col[2 * j - 2] > c0; j--) {
            w->col[2 * j] = w->col[2 * j - 2];
            w->col[2 * j + 1] = w->col[2 * j - 1];
        }
        w->col[2 * j] = c0;
        w->col[2 * j + 1] = c1;
    }
}

/* 1 if [x, y] minus the collinear ranges keeps a piece longer than the
 * minimum (lengths in t scaled by len3). */
static int piece_left(const seg_work *w, double x, double y, double len3)
{
    uint32_t i;
    double cur = x;
    if ((y - x) * len3 <= LIGHT_MIN_PIECE)
        return 0;
    for (i = 0; i < w->ncol; i++) {
        double c0 = w->col[2 * i], c1 = w->col[2 * i + 1];
        if (c1 <= cur)
            continue;
        if (c0 >= y)
            break;
        if ((c0 - cur) * len3 > LIGHT_MIN_PIECE)
            return 1;
        cur = c1;
    }
    return (y - cur) * len3 > LIGHT_MIN_PIECE;
}

/* 1 if an interior interval of the line overlaps (t1, t2) enough. */
static int interior_overlap(const seg_work *w, double t1, double t2, double len3)
{
    uint32_t i;
    int cnt = 0;
    double start = 0.0;
    for (i = 0; i < w->n; i++) {
        int before = cnt;
        cnt += w->d[i];
        if (before <= 0 && cnt > 0) {
            start = w->t[i];
        } else if (before > 0 && cnt <= 0) {
            double x = start > t1 ? start : t1, y = w->t[i] < t2 ? w->t[i] : t2;
            if (y > x && piece_left(w, x, y, len3))
                return 1;
        }
    }
    return 0;
}

/* The open t-interval (t1, t2) within [0, 1] where min_height < z < height
 * along A->B; returns 0 when it is too short to matter. */
static int slab_params(double za, double zb, double m, double h, double len3,
                       double *t1, double *t2)
{
    double dz = zb - za, a, b;
    if (dz == 0.0) {
        if (!(za > m && za < h))
            return 0;
        *t1 = 0.0;
        *t2 = 1.0;
        return len3 > LIGHT_MIN_PIECE;
    }
    a = (m - za) / dz;
    b = (h - za) / dz;
    if (a > b) {
        double c = a;
        a = b;
        b = c;
    }
    *t1 = a > 0.0 ? a : 0.0;
    *t2 = b < 1.0 ? b : 1.0;
    return (*t2 - *t1) * len3 > LIGHT_MIN_PIECE;
}

int light_seg_blocked_by(light *L, uint32_t b, const double A[3], const double B[3],
                         double len3)
{
    const scene *s = L->s;
    const scene_building *bd = &s->bld[b];
    double t1, t2;
    vec2 a, p;
    seg_work w;
    if (!slab_params(A[2], B[2], bd->min_height, bd->height, len3, &t1, &t2))
        return 0;
    a.x = A[0]; a.y = A[1];
    p.x = B[0]; p.y = B[1];
    if ((a.x < bd->box[0] && p.x < bd->box[0]) || (a.x > bd->box[2] && p.x > bd->box[2]) ||
        (a.y < bd->box[1] && p.y < bd->box[1]) || (a.y > bd->box[3] && p.y > bd->box[3]))
        return 0;
    if (a.x == p.x && a.y == p.y)
        return footprint_strictly_inside(s, b, a);
    w.t = L->cross_t;
    w.d = L->cross_d;
    w.col = L->col;
    line_crossings(s, b, a, p, &w);
    sort_crossings(&w);
    return interior_overlap(&w, t1, t2, len3);
}

static uint32_t next_stamp(light *L)
{
    if (++L->stamp_now == 0) {
        memset(L->stamp, 0, sizeof *L->stamp * (L->s->nbld + 1));
        L->stamp_now = 1;
    }
    return L->stamp_now;
}

/* Tests the buildings listed in one grid cell; 1 when one blocks. */
static int cell_blocks(light *L, uint32_t cell, uint32_t stamp, const double A[3],
                       const double B[3], double len3)
{
    const bucketgrid *g = &L->bgrid;
    uint32_t k;
    for (k = g->start[cell]; k < g->start[cell + 1]; k++) {
        uint32_t b = g->item[k];
        if (L->stamp[b] == stamp)
            continue;
        L->stamp[b] = stamp;
        if (light_seg_blocked_by(L, b, A, B, len3))
            return 1;
    }
    return 0;
}

/* The x-range of segment A'B' within the rows' y-slab [y0, y1]. */
static void row_span(const double A[3], const double B[3], double y0, double y1,
                     double *x0, double *x1)
{
    double dy = B[1] - A[1], lo, hi;
    if (dy == 0.0) {
        lo = A[0] < B[0] ? A[0] : B[0];
        hi = A[0] < B[0] ? B[0] : A[0];
    } else {
        double ya = (A[1] < B[1] ? A[1] : B[1]), yb = (A[1] < B[1] ? B[1] : A[1]);
        double xa, xb;
        if (y0 < ya) y0 = ya;
        if (y1 > yb) y1 = yb;
        xa = A[0] + (y0 - A[1]) * (B[0] - A[0]) / dy;
        xb = A[0] + (y1 - A[1]) * (B[0] - A[0]) / dy;
        lo = xa < xb ? xa : xb;
        hi = xa < xb ? xb : xa;
    }
    *x0 = lo;
    *x1 = hi;
}

int light_segment_blocked(light *L, const double A[3], const double B[3])
{
    const bucketgrid *g = &L->bgrid;
    double v[3], len3, pad, ylo, yhi;
    uint32_t stamp, iy0, iy1, iy, ix0, ix1, ix;
    if (L->s->nbld == 0)
        return 0;
    v[0] = B[0] - A[0]; v[1] = B[1] - A[1]; v[2] = B[2] - A[2];
    len3 = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (len3 == 0.0)
        return 0;
    stamp = next_stamp(L);
    pad = 1e-9 * L->bcell;
    ylo = (A[1] < B[1] ? A[1] : B[1]);
    yhi = (A[1] < B[1] ? B[1] : A[1]);
    iy0 = bucketgrid_index(ylo - pad, g->y0, g->sy, g->ny);
    iy1 = bucketgrid_index(yhi + pad, g->y0, g->sy, g->ny);
    for (iy = iy0; iy <= iy1; iy++) {
        double x0, x1;
        row_span(A, B, g->y0 + iy * L->bcell - pad, g->y0 + (iy + 1) * L->bcell + pad, &x0, &x1);
        if (iy == 0 || iy == g->ny - 1) {   /* clamped rows: whole span */
            x0 = A[0] < B[0] ? A[0] : B[0];
            x1 = A[0] < B[0] ? B[0] : A[0];
        }
        ix0 = bucketgrid_index(x0 - pad, g->x0, g->sx, g->nx);
        ix1 = bucketgrid_index(x1 + pad, g->x0, g->sx, g->nx);
        for (ix = ix0; ix <= ix1; ix++)
            if (cell_blocks(L, iy * g->nx + ix, stamp, A, B, len3))
                return 1;
    }
    return 0;
}

/* ---- point classification ------------------------------------------------- */

typedef struct where_acc {
    int inside;
    int ground_covered;
    uint32_t fac_b, roof_b, under_b;
    double fac_out[2];       /* outward unit normal of the nearest wall */
    double fac_d;
    int fac_buried;
} where_acc;

/* Distance from p to segment uv. */
static double seg_dist(vec2 p, vec2 u, vec2 v, double out[2])
{
    double ex = v.x - u.x, ey = v.y - u.y, l2 = ex * ex + ey * ey, t, dx, dy, len;
    t = l2 > 0.0 ? ((p.x - u.x) * ex + (p.y - u.y) * ey) / l2 : 0.0;
    if (t < 0.0) t = 0.0;
    if (t > 1.0) t = 1.0;
    dx = p.x - (u.x + t * ex);
    dy = p.y - (u.y + t * ey);
    len = sqrt(l2);
    out[0] = len > 0.0 ? ey / len : 0.0;    /* interior on the left: outward right */
    out[1] = len > 0.0 ? -ex / len : 0.0;
    return sqrt(dx * dx + dy * dy);
}

/* Nearest boundary distance of p to building b's rings, with the outward
 * normal of that edge. */
static double boundary_dist(const scene *s, uint32_t b, vec2 p, double out[2])
{
    const scene_building *bd = &s->bld[b];
    double best = INFINITY, o[2];
    uint32_t r, j, n;
    for (r = 0; r < bd->ring_count; r++) {
        const vec2 *q = ring_pts(s, bd->ring_first + r, &n);
        for (j = 0; j < n; j++) {
            double d = seg_dist(p, q[j], q[(j + 1) % n], o);
            if (d < best) {
                best = d;
                out[0] = o[0];
                out[1] = o[1];
            }
        }
    }
    return best;
}

static void classify_one(const scene *s, uint32_t b, const double P[3], where_acc *w)
{
    const scene_building *bd = &s->bld[b];
    const double tol = LIGHT_CLASSIFY_TOL;
    vec2 p;
    double out[2] = { 0.0, 0.0 }, d;
    int in;
    p.x = P[0];
    p.y = P[1];
    d = boundary_dist(s, b, p, out);
    in = footprint_strictly_inside(s, b, p);
    if (in && d > tol && P[2] > bd->min_height + tol && P[2] < bd->height - tol)
        w->inside = 1;
    if (in && d > tol && bd->min_height <= tol)
        w->ground_covered = 1;
    if ((in || d <= tol) && fabs(P[2] - bd->height) <= tol && w->roof_b == UINT32_MAX)
        w->roof_b = b;
    if ((in || d <= tol) && bd->min_height > 0.0 && fabs(P[2] - bd->min_height) <= tol &&
        w->under_b == UINT32_MAX)
        w->under_b = b;
    if (d <= tol && P[2] >= bd->min_height - tol && P[2] <= bd->height + tol) {
        int strict = P[2] > bd->min_height + tol && P[2] < bd->height - tol;
        if (w->fac_b != UINT32_MAX && strict &&
            out[0] * w->fac_out[0] + out[1] * w->fac_out[1] < -0.99)
            w->fac_buried = 1;     /* a wall between two solids */
        if (w->fac_b == UINT32_MAX || d < w->fac_d) {
            w->fac_b = b;
            w->fac_d = d;
            w->fac_out[0] = out[0];
            w->fac_out[1] = out[1];
        }
    }
}

static light_where pick_surface(const where_acc *w, const double P[3], const double n[3],
                                uint32_t *bld, int *ok)
{
    light_where kind[4];
    uint32_t who[4];
    double dot[4];
    int k = 0, i;
    if (fabs(P[2]) <= LIGHT_CLASSIFY_TOL && !w->ground_covered) {
        kind[k] = LIGHT_GROUND; who[k] = UINT32_MAX; dot[k++] = n[2];
    }
    if (w->roof_b != UINT32_MAX) {
        kind[k] = LIGHT_ROOF; who[k] = w->roof_b; dot[k++] = n[2];
    }
    if (w->under_b != UINT32_MAX) {
        kind[k] = LIGHT_UNDERSIDE; who[k] = w->under_b; dot[k++] = -n[2];
    }
    if (w->fac_b != UINT32_MAX) {
        kind[k] = LIGHT_FACADE; who[k] = w->fac_b;
        dot[k++] = n[0] * w->fac_out[0] + n[1] * w->fac_out[1];
    }
    if (k == 0)
        return LIGHT_AIR;
    for (i = 0; i < k && !(dot[i] > 0.0); i++)
        ;
    if (i == k)
        i = 0;
    *bld = who[i];
    *ok = dot[i] > 0.0;
    return kind[i];
}

light_where light_classify_point(light *L, const double P[3], const double n[3],
                                 uint32_t *bld, int *normal_ok)
{
    const bucketgrid *g = &L->bgrid;
    const double tol = LIGHT_CLASSIFY_TOL;
    double box[4];
    uint32_t r[4], x, y, k, stamp, b0 = UINT32_MAX;
    int ok0 = 0;
    where_acc w;
    light_where res;
    memset(&w, 0, sizeof w);
    w.fac_b = w.roof_b = w.under_b = UINT32_MAX;
    if (L->s->nbld) {
        box[0] = P[0] - tol; box[1] = P[1] - tol;
        box[2] = P[0] + tol; box[3] = P[1] + tol;
        bucketgrid_range(g, box, r);
        stamp = next_stamp(L);
        for (y = r[1]; y <= r[3]; y++)
            for (x = r[0]; x <= r[2]; x++)
                for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                    uint32_t b = g->item[k];
                    const double *bb = L->s->bld[b].box;
                    if (L->stamp[b] == stamp || P[0] < bb[0] - tol || P[0] > bb[2] + tol ||
                        P[1] < bb[1] - tol || P[1] > bb[3] + tol)
                        continue;
                    L->stamp[b] = stamp;
                    classify_one(L->s, b, P, &w);
                }
    }
    if (w.inside || w.fac_buried ||
        (w.ground_covered && fabs(P[2]) <= tol && w.fac_b == UINT32_MAX))
        res = LIGHT_INSIDE;     /* in a solid, a buried wall, under a footprint */
    else
        res = pick_surface(&w, P, n, &b0, &ok0);
    if (bld)
        *bld = b0;
    if (normal_ok)
        *normal_ok = ok0;
    return res;
}

uint32_t light_lamps_reaching(const light *L, const double P[3])
{
    const scene *s = L->s;
    const bucketgrid *g = &L->lgrid;
    uint32_t cell, k, count = 0;
    if (s->nlamps == 0 || g->nx == 0)
        return 0;
    cell = bucketgrid_cell(g, P[0], P[1]);
    for (k = cell == UINT32_MAX ? 0 : g->start[cell]; cell != UINT32_MAX && k < g->start[cell + 1]; k++) {
        const scene_lamp *lp = &s->lamps[g->item[k]];
        double dx = lp->x - P[0], dy = lp->y - P[1], dz = lp->z - P[2];
        if (lp->intensity > 0.0 && dx * dx + dy * dy + dz * dz < lp->radius * lp->radius)
            count++;
    }
    return count;
}
