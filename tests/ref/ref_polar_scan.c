/* ref_polar_scan: the former point location of the polar diagrams, kept as
 * a reference for tests and benchmarks (the construction uses no grid):
 * a grid of the wall pieces, the nearest wall below a point found by
 * scanning its column, then the regions above that wall walked to the
 * point's abscissa. */
#include "ref_polar_scan.h"
#include "polar/polar_int.h"

/* ---- the grid of wall pieces ------------------------------------------ */

/* Cell (x, y) lists the pieces whose bounding boxes meet it,
 * wall[cell[y nx + x] .. cell[.. + 1]). Only for the reference locator
 * polar_scan (the construction uses none). */
typedef struct wgrid {
    uint32_t nx, ny;
    double sx, sy;           /* cells per metre */
    uint32_t *cell, *wall;
} wgrid;

/* n items of size bytes, scratch or kept (PLX_PART_POLAR, uncounted). */
static void *grid_n(arena *a, size_t n, size_t size, int keep)
{
    size_t bytes = arena_mul(n ? n : 1, size);
    if (bytes == SIZE_MAX)
        return NULL;
    return keep ? arena_alloc(a, PLX_PART_POLAR, bytes, 16) : arena_scratch(a, bytes, 16);
}

static uint32_t grid_cell(double v, double v0, double scale, uint32_t n)
{
    double c = floor((v - v0) * scale);
    if (!(c >= 0.0))
        return 0;
    if (c >= (double)n)
        return n - 1;
    return (uint32_t)c;
}

static uint32_t grid_x(const polar *pd, const wgrid *g, double x)
{
    return grid_cell(x, pd->box[0], g->sx, g->nx);
}

static uint32_t grid_y(const polar *pd, const wgrid *g, double y)
{
    return grid_cell(y, pd->box[1], g->sy, g->ny);
}

/* Every wall piece listed in the cells its bounding box meets (about two
 * pieces per cell). Cell functions are monotone, which is all wall_below
 * needs to stop its scan exactly. */
static plx_status build_grid(arena *a, const polar *pd, wgrid *g, int keep)
{
    double W = pd->box[2] - pd->box[0], H = pd->box[3] - pd->box[1];
    double side = sqrt(W * H / ((double)pd->nwall / 2.0 + 1.0));
    uint32_t nx = (uint32_t)fmin(fmax(ceil(W / side), 1.0), 2048.0);
    uint32_t ny = (uint32_t)fmin(fmax(ceil(H / side), 1.0), 2048.0);
    uint32_t ncell = nx * ny, s, i, x, y;
    uint32_t *cell;
    size_t total = 0;
    g->nx = nx;
    g->ny = ny;
    g->sx = (double)nx / W;
    g->sy = (double)ny / H;
    cell = grid_n(a, (size_t)ncell + 1, 4, keep);
    if (!cell)
        return PLX_E_NOMEM;
    memset(cell, 0, ((size_t)ncell + 1) * 4);
    for (s = 0; s < pd->nwall; s++) {
        vec2 p = pd->pts[pd->seg[s].a], q = pd->pts[pd->seg[s].b];
        uint32_t x0 = grid_x(pd, g, fmin(p.x, q.x)), x1 = grid_x(pd, g, fmax(p.x, q.x));
        uint32_t y0 = grid_y(pd, g, fmin(p.y, q.y)), y1 = grid_y(pd, g, fmax(p.y, q.y));
        for (y = y0; y <= y1; y++)
            for (x = x0; x <= x1; x++)
                cell[y * nx + x + 1]++;
        total += (size_t)(x1 - x0 + 1) * (y1 - y0 + 1);
    }
    if (total >= 0xffffffffu)
        return PLX_E_NOMEM;
    for (i = 0; i < ncell; i++)
        cell[i + 1] += cell[i];
    g->wall = grid_n(a, total, 4, keep);
    if (!g->wall)
        return PLX_E_NOMEM;
    for (s = 0; s < pd->nwall; s++) {
        vec2 p = pd->pts[pd->seg[s].a], q = pd->pts[pd->seg[s].b];
        uint32_t x0 = grid_x(pd, g, fmin(p.x, q.x)), x1 = grid_x(pd, g, fmax(p.x, q.x));
        uint32_t y0 = grid_y(pd, g, fmin(p.y, q.y)), y1 = grid_y(pd, g, fmax(p.y, q.y));
        for (y = y0; y <= y1; y++)
            for (x = x0; x <= x1; x++)
                g->wall[cell[y * nx + x]++] = s;
    }
    for (i = ncell; i > 0; i--)
        cell[i] = cell[i - 1];
    cell[0] = 0;
    g->cell = cell;
    return PLX_OK;
}

/* Is wall LR above wall BL-BR where both span a common frame abscissa
 * (lexicographically) and do not cross? */
static int seg_over(vec2 L, vec2 R, vec2 BL, vec2 BR)
{
    int c = lex_cmp(L, BL), o;
    if (c > 0) {
        o = geom_orient(BL, BR, L);
        return (o ? o : geom_orient(BL, BR, R)) > 0;
    }
    if (c < 0) {
        o = geom_orient(L, R, BL);
        return (o ? o : geom_orient(L, R, BR)) < 0;
    }
    return geom_orient(BL, BR, R) > 0;
}

/* The nearest wall piece below frame point f (frame "below": smaller v)
 * among those whose span holds f strictly (lexicographically), found by
 * scanning the grid column of f downwards and stopping as soon as no unseen
 * piece can be higher; POLAR_NONE when there is none (the Bounds side).
 * Sets *on and returns POLAR_NONE when f is on a piece or is the end of
 * one. O(1) expected for evenly spread walls, O(n) worst case. */
static uint32_t wall_below(const polar *pd, const wgrid *g, int frame, vec2 f, int *on)
{
    vec2 wp = polar_from_frame(frame, f), BL = f, BR = f;
    uint32_t best = POLAR_NONE, fixed, nx = g->nx;
    int32_t k, end, step;
    *on = 0;
    if (frame) {
        fixed = grid_x(pd, g, wp.x);
        k = (int32_t)grid_y(pd, g, wp.y);
        step = -1;
        end = -1;
    } else {
        fixed = grid_y(pd, g, wp.y);
        k = (int32_t)grid_x(pd, g, wp.x);
        step = 1;
        end = (int32_t)nx;
    }
    for (; k != end; k += step) {
        uint32_t cell = frame ? (uint32_t)k * nx + fixed : fixed * nx + (uint32_t)k, e;
        for (e = g->cell[cell]; e < g->cell[cell + 1]; e++) {
            uint32_t s = g->wall[e];
            vec2 L, R, wa = pd->pts[pd->seg[s].a], wb = pd->pts[pd->seg[s].b];
            int cl, cr, o;
            if (frame ? (wa.x < wp.x && wb.x < wp.x) || (wa.x > wp.x && wb.x > wp.x)
                      : (wa.y < wp.y && wb.y < wp.y) || (wa.y > wp.y && wb.y > wp.y))
                continue;      /* its frame abscissae miss f's */
            L = to_frame(frame, wa);
            R = to_frame(frame, wb);
            if (lex_cmp(L, R) > 0) {
                vec2 x = L;
                L = R;
                R = x;
            }
            cl = lex_cmp(f, L);
            cr = lex_cmp(f, R);
            if (cl == 0 || cr == 0) {
                *on = 1;
                return POLAR_NONE;
            }
            if (cl < 0 || cr > 0 || s == best)
                continue;
            o = geom_orient(L, R, f);
            if (o == 0) {
                *on = 1;
                return POLAR_NONE;
            }
            if (o > 0 && (best == POLAR_NONE || seg_over(L, R, BL, BR))) {
                best = s;
                BL = L;
                BR = R;
            }
        }
        if (best != POLAR_NONE) {
            double low = fmin(BL.y, BR.y);
            int32_t lim = frame ? (int32_t)grid_y(pd, g, low) : (int32_t)grid_x(pd, g, -low);
            if (frame ? k <= lim : k >= lim)
                break;
        }
    }
    return best;
}


/* ---- the former point location (tests and benchmarks) ----------------- */

struct polar_scan {
    const polar *pd;
    wgrid g;
    uint32_t *above[2];      /* per wall piece: the first (frame-leftmost)
                              * region above it, POLAR_NONE when solid */
    uint32_t *col_start[2];  /* per grid column of frame abscissae: the first
                              * region above the Bounds side at the bottom
                              * reaching that column */
    uint32_t ncol[2];
};

static plx_status scan_tables(arena *a, polar_scan *g, int mi)
{
    const polar *pd = g->pd;
    const polar_map *m = &pd->map[mi];
    uint32_t *above, *col, ncol = m->frame ? g->g.nx : g->g.ny, t, c, s;
    above = grid_n(a, pd->nwall, 4, 1);
    col = grid_n(a, ncol, 4, 1);
    if (!above || !col)
        return PLX_E_NOMEM;
    for (s = 0; s < pd->nwall; s++)
        above[s] = POLAR_NONE;
    for (t = 0; t < m->ntrap; t++) {
        uint32_t b = m->trap[t].bot;
        if (b < pd->nwall && (above[b] == POLAR_NONE ||
                              lex_cmp(fpt(pd, m->frame, m->trap[t].lp),
                                      fpt(pd, m->frame, m->trap[above[b]].lp)) < 0))
            above[b] = t;
    }
    /* the regions above the bottom side, left to right (region 0 first):
     * per column the first one reaching into it */
    for (t = 0, c = 0; t != POLAR_NONE && c < ncol; t = m->trap[t].nb[LR]) {
        double u = fpt(pd, m->frame, m->trap[t].rp).x;
        uint32_t last = m->frame ? grid_x(pd, &g->g, u) : grid_y(pd, &g->g, u);
        if (m->trap[t].rp == m->box_hi)
            last = ncol - 1;
        while (c <= last && c < ncol)
            col[c++] = t;
    }
    if (c < ncol)
        return PLX_E_SCENE;
    g->above[mi] = above;
    g->col_start[mi] = col;
    g->ncol[mi] = ncol;
    return PLX_OK;
}

plx_status polar_scan_new(arena *a, const polar *pd, polar_scan **out)
{
    polar_scan *g;
    plx_status st;
    if (!a || !pd || !out)
        return PLX_E_INVALID;
    g = arena_calloc(a, PLX_PART_POLAR, 1, sizeof *g, 16);
    if (!g)
        return PLX_E_NOMEM;
    g->pd = pd;
    st = build_grid(a, pd, &g->g, 1);
    if (st == PLX_OK)
        st = scan_tables(a, g, 0);
    if (st == PLX_OK)
        st = scan_tables(a, g, 1);
    *out = st == PLX_OK ? g : NULL;
    return st;
}

/* The nearest wall below f (frame) by scanning the grid column of f
 * downwards, stopping as soon as no unseen wall can be higher; then the
 * regions above that wall walked to f's abscissa. */
int32_t polar_scan_locate_frame(const polar_scan *g, int mi, vec2 f, int32_t *owner)
{
    const polar *pd = g->pd;
    const polar_map *m = &pd->map[mi];
    int on;
    uint32_t t, best = wall_below(pd, &g->g, m->frame, f, &on);
    if (owner)
        *owner = -1;
    if (on)
        return -2;
    if (best == POLAR_NONE) {
        vec2 wp = polar_from_frame(m->frame, f);
        t = g->col_start[mi][m->frame ? grid_x(pd, &g->g, wp.x) : grid_y(pd, &g->g, wp.y)];
    } else {
        t = g->above[mi][best];
        if (t == POLAR_NONE) {
            if (owner)
                *owner = seg_delta(pd, m->frame, best) > 0 ? seg_owner(pd, best) : -1;
            return -3;
        }
    }
    for (;;) {
        int c = lex_cmp(f, fpt(pd, m->frame, m->trap[t].rp));
        if (c < 0)
            return (int32_t)t;
        if (c == 0)
            return -2;
        t = m->trap[t].nb[LR];
        if (t == POLAR_NONE)
            return -2;
    }
}
