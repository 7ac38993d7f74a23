/* cull: which buildings a frame draws: the grid of cells and groups of
 * cells, the frustum test, the occlusion horizon and its traversal. */
#include <math.h>
#include <string.h>

#include "base/bucketgrid.h"
#include "render/render_int.h"

#define TWO_PI (2.0 * PI)

/* The culling grid's side in cells (at most CULL_SIDE) over the buildings' boxes. */
uint32_t cull_side(const scene *s, double *x0, double *y0, double *cell)
{
    double w = s->bounds[2] - s->bounds[0], h = s->bounds[3] - s->bounds[1], side = fmax(w, h);
    uint32_t n = (uint32_t)fmin(CULL_SIDE, fmax(1.0, ceil(side / CULL_CELL)));
    *x0 = s->bounds[0];
    *y0 = s->bounds[1];
    *cell = side > 0.0 ? side / n : 1.0;
    return n;
}

static uint32_t cull_cell_of(const scene_building *bd, double x0, double y0, double cell, uint32_t n)
{
    double cx = 0.5 * (bd->box[0] + bd->box[2]), cy = 0.5 * (bd->box[1] + bd->box[3]);
    return bucketgrid_index(cy, y0, 1.0 / cell, n) * n + bucketgrid_index(cx, x0, 1.0 / cell, n);
}

/* Box bx (minx, miny, minz, maxx, maxy, maxz) grown to hold box bb. */
static void box_grow(double *bx, const double *bb)
{
    int q;
    for (q = 0; q < 3; q++) {
        bx[q] = fmin(bx[q], bb[q]);
        bx[3 + q] = fmax(bx[3 + q], bb[3 + q]);
    }
}

/* The group of cells cell c lies in. */
static uint32_t cell_group(const render *r, uint32_t c)
{
    return (c / r->cside / CULL_GROUP) * r->gside + (c % r->cside) / CULL_GROUP;
}

/* Fills the culling grid (its arrays taken already): counts, offsets,
 * the buildings in index order within each cell, the cells' boxes and
 * the groups'. */
void cull_grid_fill(render *r)
{
    const scene *s = r->s;
    double x0, y0, cell;
    uint32_t n = cull_side(s, &x0, &y0, &cell), b, c, k;
    memset(r->cell_start, 0, (r->ncell + 1) * sizeof *r->cell_start);
    for (b = 0; b < s->nbld; b++)
        r->cell_start[cull_cell_of(&s->bld[b], x0, y0, cell, n) + 1]++;
    for (c = 0; c < r->ncell; c++)
        r->cell_start[c + 1] += r->cell_start[c];
    for (b = 0; b < s->nbld; b++) { /* placed after the cell's earlier ones, then shifted back */
        c = cull_cell_of(&s->bld[b], x0, y0, cell, n);
        r->cell_bld[r->cell_start[c]++] = b;
    }
    for (c = r->ncell; c > 0; c--)
        r->cell_start[c] = r->cell_start[c - 1];
    r->cell_start[0] = 0;
    for (c = 0; c < r->ncell; c++) {
        double *bx = &r->cell_box[6 * (size_t)c];
        bx[0] = bx[1] = bx[2] = HUGE_VAL;
        bx[3] = bx[4] = bx[5] = -HUGE_VAL;
        for (k = r->cell_start[c]; k < r->cell_start[c + 1]; k++) {
            double bb[6];
            mesh_box(r->m, r->cell_bld[k], bb);
            box_grow(bx, bb);
        }
    }
    for (c = 0; c < (size_t)r->gside * r->gside; c++) {
        double *gb = &r->group_box[6 * (size_t)c];
        gb[0] = gb[1] = gb[2] = HUGE_VAL;
        gb[3] = gb[4] = gb[5] = -HUGE_VAL;
    }
    for (c = 0; c < r->ncell; c++)
        if (r->cell_start[c + 1] > r->cell_start[c])
            box_grow(&r->group_box[6 * (size_t)cell_group(r, c)], &r->cell_box[6 * (size_t)c]);
}

static void heap_push(render *r, double key, uint32_t b)
{
    uint32_t i = r->nheap++;
    while (i > 0) {
        uint32_t p = (i - 1) / 2;
        if (r->heap[p].key <= key)
            break;
        r->heap[i] = r->heap[p];
        i = p;
    }
    r->heap[i].key = key;
    r->heap[i].b = b;
}

static cull_item heap_pop(render *r)
{
    cull_item top = r->heap[0], last = r->heap[--r->nheap];
    uint32_t i = 0, n = r->nheap;
    for (;;) {
        uint32_t c = 2 * i + 1;
        if (c >= n)
            break;
        if (c + 1 < n && r->heap[c + 1].key < r->heap[c].key)
            c++;
        if (last.key <= r->heap[c].key)
            break;
        r->heap[i] = r->heap[c];
        i = c;
    }
    if (n > 0)
        r->heap[i] = last;
    return top;
}

static int eye_in_box(const render *r, const double *box)
{
    return r->eye[0] >= box[0] && r->eye[0] <= box[3] && r->eye[1] >= box[1] && r->eye[1] <= box[4];
}

static double box_dist(const render *r, const double *box)
{
    double dx = fmax(0.0, fmax(box[0] - r->eye[0], r->eye[0] - box[3]));
    double dy = fmax(0.0, fmax(box[1] - r->eye[1], r->eye[1] - box[4]));
    return sqrt(dx * dx + dy * dy);
}

/* Bin index of azimuth a (any real), in 0..RENDER_BINS-1. */
static int64_t bin_floor(double a)
{
    return (int64_t)floor((a + PI) * (RENDER_BINS / TWO_PI));
}

static uint32_t bin_wrap(int64_t k)
{
    int64_t m = k % RENDER_BINS;
    return (uint32_t)(m < 0 ? m + RENDER_BINS : m);
}

/* Angle of (x, y) relative to the direction c (unit), in (-pi, pi]. */
static double rel_angle(double cx, double cy, double x, double y)
{
    return atan2(cx * y - cy * x, cx * x + cy * y);
}

/* Inserts occluder b into the horizon. */
static void occluder_insert(render *r, uint32_t b, double mu)
{
    const scene *s = r->s;
    const scene_building *bd = &s->bld[b];
    double box[6];
    const scene_ring *rg = &s->rings[bd->ring_first];
    double cx, cy, cl, c0, lo = HUGE_VAL, hi = -HUGE_VAL, rfar = 0, rnear;
    double dz, sO, ma, ms, slope;
    int64_t k0, k1, k;
    uint32_t i;
    mesh_box(r->m, b, box);
    cx = 0.5 * (box[0] + box[3]) - r->eye[0];
    cy = 0.5 * (box[1] + box[4]) - r->eye[1];
    cl = sqrt(cx * cx + cy * cy);
    if (!(cl > 0))
        return;
    cx /= cl;
    cy /= cl;
    c0 = atan2(cy, cx);
    for (i = 0; i < rg->count; i++) {
        double x = s->pts[rg->first + i].x - r->eye[0], y = s->pts[rg->first + i].y - r->eye[1];
        double a = rel_angle(cx, cy, x, y), d = sqrt(x * x + y * y);
        lo = fmin(lo, a);
        hi = fmax(hi, a);
        rfar = fmax(rfar, d);
    }
    rnear = box_dist(r, box);
    if (!(rnear > 0))
        return;
    dz = bd->height - r->eye[2];
    sO = dz >= 0 ? dz / (rfar * (1.0 + 1e-12)) : dz / (rnear * (1.0 - 1e-12));
    /* margins: direction error 2 pixel angles */
    slope = fmax(fabs(dz), fabs(r->eye[2])) / rnear;
    ma = 2.0 * mu * sqrt(1.0 + slope * slope) + 1e-9;
    ms = 2.0 * 2.0 * mu * (1.0 + sO * sO) + 1e-12;
    sO -= ms;
    lo += c0 + ma;
    hi += c0 - ma;
    if (!(hi > lo))
        return;
    k0 = bin_floor(lo) + 1;       /* first bin starting after lo */
    k1 = bin_floor(hi) - 1;       /* last bin ending before hi */
    /* bin k spans [k w - pi, (k + 1) w - pi]: check ends exactly */
    for (k = k0; k <= k1 && k - k0 < RENDER_BINS; k++) {
        uint32_t q = bin_wrap(k);
        if (sO > r->bins[q])
            r->bins[q] = sO;
    }
}

/* Whether every ray that can reach box (minx, miny, minz, maxx, maxy,
 * maxz) is stopped by the horizon's bins (render.h); *slope_out gets the
 * steepest slope from the eye to its top (sB) when it is computed. */
static int hidden_box(render *r, const double *box, double mu, double *slope_out)
{
    double cx, cy, cl, c0, lo = HUGE_VAL, hi = -HUGE_VAL, rnear, rfar = 0;
    double dz, sB, slope, ma, ms;
    int64_t k0, k1, k;
    int i;
    *slope_out = HUGE_VAL;
    cx = 0.5 * (box[0] + box[3]) - r->eye[0];
    cy = 0.5 * (box[1] + box[4]) - r->eye[1];
    cl = sqrt(cx * cx + cy * cy);
    if (!(cl > 0))
        return 0;
    cx /= cl;
    cy /= cl;
    c0 = atan2(cy, cx);
    for (i = 0; i < 4; i++) {
        double x = box[(i & 1) ? 3 : 0] - r->eye[0], y = box[(i & 2) ? 4 : 1] - r->eye[1];
        double a = rel_angle(cx, cy, x, y);
        lo = fmin(lo, a);
        hi = fmax(hi, a);
        rfar = fmax(rfar, sqrt(x * x + y * y));
    }
    rnear = box_dist(r, box);
    if (!(rnear > 0))
        return 0;
    dz = box[5] - r->eye[2];
    sB = dz >= 0 ? dz / (rnear * (1.0 - 1e-12)) : dz / (rfar * (1.0 + 1e-12));
    *slope_out = sB;
    slope = fmax(fabs(dz), fabs(box[2] - r->eye[2])) / rnear;
    ma = 2.0 * mu * sqrt(1.0 + slope * slope) + 1e-9;
    ms = 2.0 * 2.0 * mu * (1.0 + sB * sB) + 1e-12;
    sB += ms;
    lo += c0 - ma;
    hi += c0 + ma;
    k0 = bin_floor(lo);
    k1 = bin_floor(hi);
    if (k1 - k0 >= RENDER_BINS / 2)
        return 0;
    for (k = k0; k <= k1; k++)
        if (!(r->bins[bin_wrap(k)] > sB))
            return 0;
    return 1;
}

/* Is building b hidden by the horizon? */
static int hidden(render *r, uint32_t b, double mu)
{
    double box[6], sB;
    mesh_box(r->m, b, box);
    return hidden_box(r, box, mu, &sB);
}

/* The traversal of the occlusion pass: a min-heap of cells and buildings
 * by (key, index), a cell's index nbld + its number. */
static int trav_before(const cull_item *a, const cull_item *b)
{
    return a->key < b->key || (a->key == b->key && a->b < b->b);
}

static void trav_push(render *r, double key, uint32_t b)
{
    uint32_t i = r->ntrav++;
    cull_item it;
    it.key = key;
    it.b = b;
    while (i > 0) {
        uint32_t p = (i - 1) / 2;
        if (trav_before(&r->trav[p], &it))
            break;
        r->trav[i] = r->trav[p];
        i = p;
    }
    r->trav[i] = it;
}

static cull_item trav_pop(render *r)
{
    cull_item top = r->trav[0], last = r->trav[--r->ntrav];
    uint32_t i = 0, n = r->ntrav;
    for (;;) {
        uint32_t c = 2 * i + 1;
        if (c >= n)
            break;
        if (c + 1 < n && trav_before(&r->trav[c + 1], &r->trav[c]))
            c++;
        if (!trav_before(&r->trav[c], &last))
            break;
        r->trav[i] = r->trav[c];
        i = c;
    }
    if (n > 0)
        r->trav[i] = last;
    return top;
}

/* The occluders whose w_max, with the depth gap, lies before w: into the
 * horizon's bins (valid for whatever is tested at w or beyond). */
static void occluders_before(render *r, double w, double mu, double gap_a, double gap_b)
{
    while (r->nheap > 0) {
        double wo = r->heap[0].key;
        if (!(wo * (1.0 + gap_a + gap_b * wo) < w))
            break;
        occluder_insert(r, heap_pop(r).b, mu);
    }
}

/* The occlusion pass (render.h's occlusion horizon) over the cells cull_buildings
 * pushed: cells and buildings taken by increasing key (the smallest w of
 * a box's corners, at least near; a cell's is at most its buildings',
 * its box holding theirs) from one heap. A cell whose box the horizon
 * hides hides every building in it (their boxes lie in its box: their
 * azimuths within its azimuths, their top slopes at most its own, for
 * slopes above -64 where the margins grow too little with the slope to
 * matter), and they are culled at once, untested; otherwise each of its
 * buildings gets its frustum test and, when drawn, joins the heap. A
 * building is tested as before, after the occluders due before its key,
 * so with the horizon the one-by-one pass would give it (buildings of
 * equal key cannot occlude one another: an occluder waits for its w_max,
 * at least its own key). The buildings a hidden cell takes away are
 * hidden too; they no longer occlude for others, which only culls less. */
static int cull_building(render *r, int mode, uint32_t b, render_stats *st, double *key);

static void occlusion_start(render *r)
{
    uint32_t k;
    for (k = 0; k < RENDER_BINS; k++)
        r->bins[k] = -HUGE_VAL;
    r->nheap = 0;
    r->ntrav = 0;
}

static void occlusion(render *r, int mode, render_stats *st)
{
    const mesh *m = r->m;
    double mu = 2.0 * r->tanh_ / r->h;
    double gap_a = 1e-3, gap_b = mu / (8.0 * r->eye[2]) + 4e-6 / r->near_;
    while (r->ntrav > 0) {
        cull_item it = trav_pop(r);
        occluders_before(r, it.key, mu, gap_a, gap_b);
        if (it.b >= m->nbld) {
            uint32_t c = it.b - m->nbld, q;
            const double *cb = &r->cell_box[6 * (size_t)c];
            double sB, key;
            int h = !eye_in_box(r, cb) && hidden_box(r, cb, mu, &sB) && sB > -64.0;
            for (q = r->cell_start[c]; q < r->cell_start[c + 1]; q++) {
                uint32_t b = r->cell_bld[q];
                if (h) {
                    r->draw[b] = 0;
                    st->occlusion_culled++;
                } else if (cull_building(r, mode, b, st, &key) == 2) {
                    trav_push(r, key, b);
                }
            }
        } else {
            double box[6];
            mesh_box(m, it.b, box);
            if (!eye_in_box(r, box)) {
                if (hidden(r, it.b, mu)) {
                    r->draw[it.b] = 0;
                    st->occlusion_culled++;
                }
                if (mesh_occluder(m, it.b))
                    heap_push(r, r->wmax[it.b], it.b);
            }
        }
    }
}

/* The clip coordinates of box bx's 8 corners (minx, miny, minz, maxx,
 * maxy, maxz; corner k takes max x when k & 1, max y when k & 2, max z
 * when k & 4): clip coordinates are affine in the point, so the corner
 * (min, min, min) and the box's three edges make all eight. */
static void box_clip(const render *r, const double *bx, double c[8][4])
{
    double o[3], e[3][4], X[3];
    int k, q, a;
    o[0] = bx[0];
    o[1] = bx[1];
    o[2] = bx[2];
    to_clip(r, o, c[0]);
    for (a = 0; a < 3; a++) {
        double t[4];
        memcpy(X, o, sizeof X);
        X[a] = bx[3 + a];
        to_clip(r, X, t);
        for (q = 0; q < 4; q++)
            e[a][q] = t[q] - c[0][q];
    }
    /* corner k is corner k & ~4 (or k & ~2) plus one edge: the sums
     * c[0] + e[0] + e[1] + e[2] in that order, the absent edges left out
     * (adding +0.0 would change only a -0.0; corners are compared, and
     * divided by a w of at least near, where -0.0 acts as +0.0) */
    for (q = 0; q < 4; q++) {
        c[1][q] = c[0][q] + e[0][q];
        c[2][q] = c[0][q] + e[1][q];
        c[3][q] = c[1][q] + e[1][q];
    }
    for (k = 0; k < 4; k++)
        for (q = 0; q < 4; q++)
            c[4 + k][q] = c[k][q] + e[2][q];
}

/* Whether every corner c of a box (box_clip) lies beyond one side plane of the
 * frustum (by a tolerance of 1e-6 |w| + 1e-9, far above the corners'
 * rounding) or before the near plane: no pixel centre sees it; its
 * corners' smallest and largest w. whole: the tolerance from the largest
 * |w| of the corners for every corner, so that what holds for the box
 * holds for every box inside it (clip coordinates are affine in the
 * point: inside, x - w is at least its least value at a corner, and |w|
 * at most its largest). rows (may be NULL): the rows its projection may
 * cover (its corners' rows, two pixels more each way for snapping), every
 * row when a corner is not in front of the near plane: what a band of
 * rows needs to draw (soft_draw_bands). box_out: the same from the box. */
static int corners_out(const render *r, double c[8][4], double *wmn, double *wmx, int whole, int32_t *rows)
{
    int out_l = 1, out_r = 1, out_b = 1, out_t = 1, out_n = 1, k, all_front = 1;
    double big = 0.0, lo = HUGE_VAL, hi = -HUGE_VAL;
    *wmn = HUGE_VAL;
    *wmx = -HUGE_VAL;
    for (k = 0; k < 8; k++) {
        double w = c[k][3], aw = w < 0.0 ? -w : w;
        *wmn = w < *wmn ? w : *wmn;
        *wmx = w > *wmx ? w : *wmx;
        big = aw > big ? aw : big;
    }
    for (k = 0; k < 8; k++) {
        double w = c[k][3], aw = whole ? big : (w < 0.0 ? -w : w), tol = 1e-6 * aw + 1e-9;
        double tx = tol + r->cpad[0] * aw, ty = tol + r->cpad[1] * aw; /* tol when not widened */
        if (!(c[k][0] > w + tx)) out_r = 0;
        if (!(c[k][0] < -w - tx)) out_l = 0;
        if (!(c[k][1] > w + ty)) out_t = 0;
        if (!(c[k][1] < -w - ty)) out_b = 0;
        if (!(w < r->near_ * (1.0 - 1e-6))) out_n = 0;
        if (!(w >= r->near_)) {
            all_front = 0;
        } else if (rows) {
            double y = (1.0 - c[k][1] / w) * 0.5 * r->h;
            lo = y < lo ? y : lo;
            hi = y > hi ? y : hi;
        }
    }
    if (rows) {
        rows[0] = 0;
        rows[1] = r->h - 1;
        if (all_front) { /* clamped before the conversion: far-off boxes give huge rows */
            double a = fmin(fmax(lo - 2.0 - r->cpad[2], 0.0), r->h - 1.0);
            double b = fmin(fmax(hi + 2.0 + r->cpad[2], 0.0), r->h - 1.0);
            rows[0] = (int32_t)a;
            rows[1] = (int32_t)b;
        }
    }
    return out_l || out_r || out_t || out_b || out_n;
}

static int box_out(const render *r, const double *bx, double *wmn, double *wmx, int whole, int32_t *rows)
{
    double c[8][4];
    box_clip(r, bx, c);
    return corners_out(r, c, wmn, wmx, whole, rows);
}

/* Whether a box whose corners are c (box_clip) lies inside the frustum's
 * four sides and in front of the near plane, every corner by a margin
 * (1e-6 |w| + 1e-9, far above the corners' rounding): no box inside it is
 * out (box_out). */
static int corners_inside(const render *r, double c[8][4])
{
    int k;
    for (k = 0; k < 8; k++) {
        double w = c[k][3], tol = 1e-6 * (w < 0.0 ? -w : w) + 1e-9;
        if (!(w >= r->near_ * (1.0 + 1e-6) && c[k][0] <= w - tol && c[k][0] >= -w + tol && c[k][1] <= w - tol &&
              c[k][1] >= -w + tol))
            return 0;
    }
    return 1;
}

/* Building b's frustum test: culled (counted, 0), or drawn (1; 2 when
 * it has triangles: a candidate for the occlusion pass, its key the
 * smallest w of its box's corners, at least near). */
static int cull_building(render *r, int mode, uint32_t b, render_stats *st, double *key)
{
    double bx[6], wmn, wmx;
    int out;
    mesh_box(r->m, b, bx);
    out = box_out(r, bx, &wmn, &wmx, 0, &r->yr[2 * (size_t)b]);
    r->wmin[b] = wmn;
    r->wmax[b] = wmx;
    r->draw[b] = 1;
    if ((mode & RENDER_CULL_FRUSTUM) && out) {
        r->draw[b] = 0;
        st->frustum_culled++;
        return 0;
    }
    *key = fmax(wmn, r->near_);
    return r->m->bld[b].t_count == 0 ? 1 : 2;
}

/* Whether the occlusion test may pay: not when the eye is higher than
 * twice the tallest top. From there a building hides a whole other one
 * only just behind a taller one, and the front-to-back traversal cost
 * more than it saved (the aerial bench's frames: 11 million instructions
 * a frame, nothing culled). Either way the image is the same: culling
 * only skips what the depth test would hide. */
static int occlusion_pays(const render *r)
{
    double top = -HUGE_VAL;
    uint32_t c;
    for (c = 0; c < r->ncell; c++)
        if (r->cell_start[c + 1] > r->cell_start[c])
            top = fmax(top, r->cell_box[6 * (size_t)c + 5]);
    return !(r->eye[2] > 2.0 * fmax(top, 0.0));
}

/* Cell c's buildings all drawn (1) or all culled by the frustum (0, counted). */
static void cell_draw(render *r, uint32_t c, uint8_t draw, render_stats *st)
{
    uint32_t k;
    for (k = r->cell_start[c]; k < r->cell_start[c + 1]; k++)
        r->draw[r->cell_bld[k]] = draw;
    if (!draw)
        st->frustum_culled += r->cell_start[c + 1] - r->cell_start[c];
}

/* group_out's values: a group of cells wholly out of the frustum, or
 * wholly inside it (groups_out). */
#define GROUP_OUT 1u
#define GROUP_IN 2u

/* Cells c0 .. c1 - 1 without the occlusion pass: a cell out of the frustum
 * culls its buildings, the others' buildings are tested one by one, but
 * for a cell wholly inside, or in a group wholly inside, when no band
 * needs its buildings' rows (their boxes lie in it: none is out). */
static void cull_cells(render *r, int mode, int rows, uint32_t c0, uint32_t c1, render_stats *st)
{
    uint32_t c, k;
    for (c = c0; c < c1; c++) {
        double corner[8][4], wmn, wmx, key;
        uint8_t g;
        if (r->cell_start[c + 1] == r->cell_start[c])
            continue;
        g = r->group_out[cell_group(r, c)];
        if (g == GROUP_OUT || (g == GROUP_IN && !rows)) {
            cell_draw(r, c, g == GROUP_IN, st);
            continue;
        }
        box_clip(r, &r->cell_box[6 * (size_t)c], corner);
        if ((mode & RENDER_CULL_FRUSTUM) && corners_out(r, corner, &wmn, &wmx, 1, NULL))
            cell_draw(r, c, 0, st);
        else if (!rows && corners_inside(r, corner))
            cell_draw(r, c, 1, st);
        else
            for (k = r->cell_start[c]; k < r->cell_start[c + 1]; k++)
                (void)cull_building(r, mode, r->cell_bld[k], st, &key);
    }
}

/* This frame's groups of cells wholly out of the frustum (group_out
 * GROUP_OUT), by box_out with the tolerance of the whole box: each cell's
 * box lies in its group's, so its own test would cull it too (in real
 * numbers; the cell's corners, rounded on their own, could fall the other
 * way only at the margin, where the image is the same and only the counts
 * of culled buildings could differ). The others wholly inside (GROUP_IN)
 * by corners_inside: then so is each cell's box in it (the margin's test
 * is convex in the point: what holds at the group's corners holds in its
 * box; and a cell's buildings tested one by one would all be drawn too).
 * An empty group (no box) is neither: its cells are empty and skipped. */
static void groups_out(render *r, int mode)
{
    uint32_t g, n = r->gside * r->gside;
    for (g = 0; g < n; g++) {
        const double *gb = &r->group_box[6 * (size_t)g];
        double c[8][4], wmn, wmx;
        r->group_out[g] = 0;
        if (!(gb[0] <= gb[3]))
            continue;
        box_clip(r, gb, c);
        if ((mode & RENDER_CULL_FRUSTUM) && corners_out(r, c, &wmn, &wmx, 1, NULL))
            r->group_out[g] = GROUP_OUT;
        else if (corners_inside(r, c))
            r->group_out[g] = GROUP_IN;
    }
}

#define CULL_JOB_CELLS 256
typedef struct cull_job {
    render *r;
    int mode, rows;
    uint64_t culled[RENDER_MAX_WORKERS];
} cull_job;

static void cull_part(void *arg, int worker, uint32_t k)
{
    cull_job *jb = arg;
    render_stats st;
    uint32_t c1 = (k + 1) * CULL_JOB_CELLS < jb->r->ncell ? (k + 1) * CULL_JOB_CELLS : jb->r->ncell;
    memset(&st, 0, sizeof st);
    cull_cells(jb->r, jb->mode, jb->rows, k * CULL_JOB_CELLS, c1, &st);
    jb->culled[worker] += st.frustum_culled;
}

/* Culling (render.h): cells of buildings first. A cell whose box lies
 * out of the frustum culls its buildings (their boxes lie in it); with
 * occlusion culling the others go to the occlusion pass as a whole (their
 * buildings are tested when the cell is reached and not hidden), without
 * it their buildings are tested at once, cells on the workers (each
 * building's results its own: the same for any split). */
void cull_buildings(render *r, const render_opts *o, int inside, int rows, render_stats *st)
{
    uint32_t c;
    int mode = o->cull, occl = (mode & RENDER_CULL_OCCLUSION) && !inside && occlusion_pays(r);
    occlusion_start(r);
    groups_out(r, mode);
    if (!occl) {
        cull_job jb;
        int k;
        memset(&jb, 0, sizeof jb);
        jb.r = r;
        jb.mode = mode;
        jb.rows = rows;
        run_jobs(o, (r->ncell + CULL_JOB_CELLS - 1) / CULL_JOB_CELLS, cull_part, &jb);
        for (k = 0; k < RENDER_MAX_WORKERS; k++)
            st->frustum_culled += jb.culled[k];
        return;
    }
    for (c = 0; c < r->ncell; c++) {
        double wmn, wmx;
        if (r->cell_start[c + 1] == r->cell_start[c])
            continue;
        if (r->group_out[cell_group(r, c)] == GROUP_OUT ||
            (box_out(r, &r->cell_box[6 * (size_t)c], &wmn, &wmx, 1, NULL) && (mode & RENDER_CULL_FRUSTUM)))
            cell_draw(r, c, 0, st);
        else
            trav_push(r, fmax(wmn, r->near_), r->m->nbld + c);
    }
    occlusion(r, mode, st);
}
