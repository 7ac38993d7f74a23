/* test_render: the renderer (src/render/render.h, src/render/mesh.h) against an
 * independent per-pixel reference written here.
 *
 * The reference follows SPEC §5 from scratch: one primary ray per pixel
 * through the pixel centre, the first hit found by brute force against
 * every wall, roof and underside of every prism and the ground plane,
 * shaded with tests/ref/ref_light (colour-weighted SPEC §2 illuminance),
 * radiance albedo / pi * E, exposure, the sRGB curve computed with pow and
 * rounded. The renderer is given the same brute-force shader, so the test
 * checks the camera, visibility, hit points, normals and tone mapping.
 *
 * Agreement rule: at least 99.5 % of pixels within 2/255 on every channel,
 * and every pixel beyond that has a neighbour (8-neighbourhood) whose
 * reference hit is another surface (a geometric edge).
 *
 * Golden images: fixtures/golden/NAME.png (glows on). On a mismatch the test
 * writes <name>.actual.png and <name>.diff.png into build/golden-out/ and
 * prints how to update: PLX_UPDATE_GOLDEN=1 build/tests/test_render.
 *
 * Backends: when built with OSMesa (PLX_HAVE_OSMESA), the fixture cameras
 * are also drawn through port/osmesa and must agree with the software
 * backend by the same rule (the soft image standing in for the reference,
 * its ids for the edges); without OSMesa that test says it is skipped and
 * passes.
 *
 * PLX_RENDER_OUT=dir writes every rendered image there, for looking at.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <cmocka.h>

#include "polarlux.h"
#include "polarlux_port.h"
#include "fixture.h"
#include "base/engine.h"
#include "render/render.h"
#include "render/mesh.h"
#include "render/exposure.h"
#include "base/bits.h"
#include "light/illuminance.h"
#include "light/litregion.h"
#include "base/geom.h"
#include "ref_light.h"
#include "ref_exposure.h"
#include "png/image_write.h"
#ifdef PLX_HAVE_OSMESA
#include "plx_osmesa.h"
#endif

#define MEM (512u << 20)
#define PI 3.14159265358979323846
#define TWO_PI_T (2.0 * PI)

static int quick(void)
{
    return getenv("PLX_TEST_QUICK") != NULL;
}

static plx_engine *open_scene(const char *path, void **mem)
{
    return fixture_file(path, MEM, mem);
}

/* The brute-force shader, fed per lamp only the buildings that can block
 * it: a blocking building meets the segment L->P, which lies within R of L
 * whenever the lamp contributes (d < R), so its box comes within R of L.
 * Each lamp gets a shallow copy of the scene holding that lamp alone and
 * those buildings (rings and points shared); the sum over lamps of
 * ref_illuminance_rgb on them is exactly ref_illuminance_rgb on the scene. */
typedef struct ref_sh {
    const scene *s;
    scene *sub;           /* one per lamp */
} ref_sh;

static ref_sh *ref_sh_new(const scene *s)
{
    ref_sh *r = calloc(1, sizeof *r);
    uint32_t l, b;
    r->s = s;
    r->sub = calloc(s->nlamps + 1, sizeof *r->sub);
    for (l = 0; l < s->nlamps; l++) {
        const scene_lamp *lp = &s->lamps[l];
        scene *q = &r->sub[l];
        *q = *s;
        q->lamps = (scene_lamp *)lp;
        q->nlamps = 1;
        q->bld = malloc((s->nbld + 1) * sizeof *q->bld);
        q->nbld = 0;
        for (b = 0; b < s->nbld; b++) {
            const double *bx = s->bld[b].box;
            double dx = fmax(0.0, fmax(bx[0] - lp->x, lp->x - bx[2]));
            double dy = fmax(0.0, fmax(bx[1] - lp->y, lp->y - bx[3]));
            if (dx * dx + dy * dy <= lp->radius * lp->radius * 1.0001 + 1e-6)
                q->bld[q->nbld++] = s->bld[b];
        }
    }
    return r;
}

static void ref_sh_free(ref_sh *r)
{
    uint32_t l;
    for (l = 0; l < r->s->nlamps; l++)
        free(r->sub[l].bld);
    free(r->sub);
    free(r);
}

static void ref_shade(void *user, const double P[3], const double n[3], double rgb[3])
{
    const ref_sh *r = user;
    uint32_t l;
    rgb[0] = rgb[1] = rgb[2] = 0;
    for (l = 0; l < r->s->nlamps; l++) {
        const scene_lamp *lp = &r->s->lamps[l];
        double dx = lp->x - P[0], dy = lp->y - P[1], dz = lp->z - P[2], e[3];
        if (dx * dx + dy * dy + dz * dz >= lp->radius * lp->radius)
            continue;
        ref_illuminance_rgb(&r->sub[l], P, n, e);
        rgb[0] += e[0];
        rgb[1] += e[1];
        rgb[2] += e[2];
    }
}

static void save_png(const char *name, const uint8_t *img, int w, int h)
{
    const char *dir = getenv("PLX_RENDER_OUT");
    char path[512], err[256];
    if (!dir)
        return;
    snprintf(path, sizeof path, "%s/%s.png", dir, name);
    if (image_write_png_rgb8(path, w, h, img, 0, err, sizeof err) != 0)
        print_message("%s\n", err);
}

/* ---- the independent reference ------------------------------------------ */

/* Crossing-number point in polygon (plain doubles; boundary either way). */
static int in_ring(const vec2 *p, uint32_t n, double x, double y)
{
    uint32_t i, j;
    int c = 0;
    for (i = 0, j = n - 1; i < n; j = i++) {
        if ((p[i].y > y) != (p[j].y > y)) {
            double xc = p[j].x + (y - p[j].y) * (p[i].x - p[j].x) / (p[i].y - p[j].y);
            if (x < xc)
                c = !c;
        }
    }
    return c;
}

static int in_footprint(const scene *s, const scene_building *b, double x, double y)
{
    uint32_t r;
    const scene_ring *o = &s->rings[b->ring_first];
    if (!in_ring(s->pts + o->first, o->count, x, y))
        return 0;
    for (r = 1; r < b->ring_count; r++) {
        const scene_ring *h = &s->rings[b->ring_first + r];
        if (in_ring(s->pts + h->first, h->count, x, y))
            return 0;
    }
    return 1;
}

typedef struct ref_hit {
    uint32_t surf;     /* the mesh.h id convention */
    double t;
    double n[3];
    double albedo;
} ref_hit;

static ref_hit ref_first_hit(const scene *s, const double e[3], const double d[3])
{
    ref_hit h;
    uint32_t b, r, i;
    h.surf = 0;
    h.t = HUGE_VAL;
    h.albedo = 0;
    h.n[0] = h.n[1] = 0;
    h.n[2] = 1;
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        double zs[2];
        int k;
        /* walls */
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            for (i = 0; i < rg->count; i++) {
                vec2 a = s->pts[rg->first + i], c = s->pts[rg->first + (i + 1) % rg->count];
                double ex = c.x - a.x, ey = c.y - a.y;
                /* solve e + t d = a + u (c - a) in xy */
                double den = d[0] * ey - d[1] * ex, t, u, z;
                if (den == 0.0)
                    continue;
                t = ((a.x - e[0]) * ey - (a.y - e[1]) * ex) / den;
                u = ((a.x - e[0]) * d[1] - (a.y - e[1]) * d[0]) / den;
                if (!(t > 0.0) || u < 0.0 || u > 1.0 || !(t < h.t))
                    continue;
                z = e[2] + t * d[2];
                if (z < bd->min_height || z > bd->height)
                    continue;
                h.t = t;
                h.surf = 2 + rg->first + i;
                {
                    double len = sqrt(ex * ex + ey * ey);
                    h.n[0] = ey / len;
                    h.n[1] = -ex / len;
                    h.n[2] = 0;
                }
                h.albedo = bd->albedo;
            }
        }
        /* roof and underside */
        zs[0] = bd->height;
        zs[1] = bd->min_height;
        for (k = 0; k < 2; k++) {
            double t, x, y;
            if (k == 1 && !(bd->min_height > 0))
                continue;
            if (d[2] == 0.0)
                continue;
            t = (zs[k] - e[2]) / d[2];
            if (!(t > 0.0) || !(t < h.t))
                continue;
            x = e[0] + t * d[0];
            y = e[1] + t * d[1];
            if (x < bd->box[0] || x > bd->box[2] || y < bd->box[1] || y > bd->box[3])
                continue;
            if (!in_footprint(s, bd, x, y))
                continue;
            h.t = t;
            h.surf = k == 0 ? 2 + s->npts + b : 2 + s->npts + s->nbld + b;
            h.n[0] = h.n[1] = 0;
            h.n[2] = k == 0 ? 1 : -1;
            h.albedo = bd->albedo;
        }
    }
    if (h.surf == 0 && d[2] < 0) {
        h.surf = 1;
        h.t = -e[2] / d[2];
        h.n[0] = h.n[1] = 0;
        h.n[2] = 1;
        h.albedo = s->ground_albedo;
    }
    return h;
}

static uint8_t ref_srgb8(double v)
{
    double e;
    if (!(v > 0))
        return 0;
    if (v >= 1)
        return 255;
    e = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (uint8_t)floor(e * 255.0 + 0.5);
}

typedef struct ref_cam {
    double eye[3], target[3], fov;
    int w, h;
} ref_cam;

/* The reference image (and the surface of each pixel). */
static void ref_render(const scene *s, const ref_sh *sh, const ref_cam *c, double exposure, uint8_t *img,
                       uint32_t *surf)
{
    double f[3], rt[3], up[3], l, th = tan(c->fov * PI / 360.0), asp = (double)c->w / c->h;
    int i, j, k;
    for (k = 0; k < 3; k++)
        f[k] = c->target[k] - c->eye[k];
    l = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (k = 0; k < 3; k++)
        f[k] /= l;
    /* right = f x (0, 0, 1) normalised; up = right x f */
    rt[0] = f[1];
    rt[1] = -f[0];
    rt[2] = 0;
    l = sqrt(rt[0] * rt[0] + rt[1] * rt[1]);
    rt[0] /= l;
    rt[1] /= l;
    up[0] = rt[1] * f[2] - rt[2] * f[1];
    up[1] = rt[2] * f[0] - rt[0] * f[2];
    up[2] = rt[0] * f[1] - rt[1] * f[0];
    for (j = 0; j < c->h; j++)
        for (i = 0; i < c->w; i++) {
            double x = (2.0 * (i + 0.5) / c->w - 1.0) * th * asp, y = (1.0 - 2.0 * (j + 0.5) / c->h) * th;
            double d[3], P[3], n[3], E[3] = { 0, 0, 0 };
            ref_hit h;
            uint8_t *px = &img[3 * ((size_t)j * c->w + i)];
            for (k = 0; k < 3; k++)
                d[k] = f[k] + x * rt[k] + y * up[k];
            h = ref_first_hit(s, c->eye, d);
            surf[(size_t)j * c->w + i] = h.surf;
            if (h.surf == 0) {
                px[0] = px[1] = px[2] = 0;
                continue;
            }
            for (k = 0; k < 3; k++)
                P[k] = c->eye[k] + h.t * d[k];
            if (h.surf == 1)
                P[2] = 0;
            /* the normal facing the eye */
            if (h.n[0] * d[0] + h.n[1] * d[1] + h.n[2] * d[2] > 0)
                for (k = 0; k < 3; k++)
                    h.n[k] = -h.n[k];
            for (k = 0; k < 3; k++)
                n[k] = h.n[k];
            ref_shade((void *)sh, P, n, E);
            for (k = 0; k < 3; k++)
                px[k] = ref_srgb8(h.albedo / PI * E[k] * exposure);
        }
}

/* ---- helpers ---------------------------------------------------------------- */

static render_camera to_cam(const ref_cam *c)
{
    render_camera k;
    memcpy(k.eye, c->eye, sizeof k.eye);
    memcpy(k.target, c->target, sizeof k.target);
    k.fov_deg = c->fov;
    k.width = c->w;
    k.height = c->h;
    return k;
}

typedef struct agree { size_t n, close, edge_only, bad; int maxdiff; } agree;

/* Compares img with the reference ref (surfaces rs). */
static agree compare(const uint8_t *img, const uint8_t *ref, const uint32_t *rs, int w, int h)
{
    agree a;
    int i, j, k;
    memset(&a, 0, sizeof a);
    a.n = (size_t)w * h;
    for (j = 0; j < h; j++)
        for (i = 0; i < w; i++) {
            size_t p = (size_t)j * w + i;
            int dmax = 0, di, dj, edge = 0;
            for (k = 0; k < 3; k++) {
                int d = abs((int)img[3 * p + k] - (int)ref[3 * p + k]);
                if (d > dmax)
                    dmax = d;
            }
            if (dmax > a.maxdiff)
                a.maxdiff = dmax;
            if (dmax <= 2) {
                a.close++;
                continue;
            }
            for (dj = -1; dj <= 1; dj++)
                for (di = -1; di <= 1; di++) {
                    int x = i + di, y = j + dj;
                    if (x < 0 || y < 0 || x >= w || y >= h)
                        continue;
                    if (rs[(size_t)y * w + x] != rs[p])
                        edge = 1;
                }
            if (edge)
                a.edge_only++;
            else {
                if (a.bad < 5)
                    print_message("  non-edge mismatch at (%d, %d): %d %d %d vs %d %d %d, surface %u\n", i, j,
                                  img[3 * p], img[3 * p + 1], img[3 * p + 2], ref[3 * p], ref[3 * p + 1],
                                  ref[3 * p + 2], rs[p]);
                a.bad++;
            }
        }
    return a;
}

typedef struct fixture {
    void *mem;
    plx_engine *e;
    render *r;
    ref_sh *sh;
} fixture;

static void fx_open(fixture *f, const char *path, int w, int h)
{
    f->e = open_scene(path, &f->mem);
    f->sh = ref_sh_new(f->e->sc);
    assert_int_equal(render_create(&f->e->mem, f->e->sc, w, h, ref_shade, f->sh, &f->r), PLX_OK);
}

static void fx_close(fixture *f)
{
    ref_sh_free(f->sh);
    plx_engine_destroy(f->e);
    free(f->mem);
}

/* Renders c and the reference; checks the agreement rule. */
static void check_against_ref(fixture *f, const ref_cam *c, const char *name)
{
    render_camera cam = to_cam(c);
    render_opts o;
    render_stats st;
    size_t px = (size_t)c->w * c->h;
    uint8_t *img = malloc(3 * px), *ref = malloc(3 * px);
    uint32_t *rs = malloc(px * sizeof *rs);
    agree a;
    char nm[128];
    render_opts_default(&o);
    o.no_glow = 1;
    assert_int_equal(render_frame(f->r, &cam, &o, img, NULL, &st), PLX_OK);
    ref_render(f->e->sc, f->sh, c, 1.0, ref, rs);
    a = compare(img, ref, rs, c->w, c->h);
    print_message("%s: %zu px, %.3f %% within 2/255, %zu edge mismatches, %zu others, max diff %d; "
                  "%u/%u buildings drawn, %.1f %% of triangles\n", name, a.n, 100.0 * a.close / a.n,
                  a.edge_only, a.bad, a.maxdiff, st.drawn, st.buildings, 100.0 * st.drawn_fraction);
    snprintf(nm, sizeof nm, "%s", name);
    save_png(nm, img, c->w, c->h);
    snprintf(nm, sizeof nm, "%s.ref", name);
    save_png(nm, ref, c->w, c->h);
    assert_true(a.close >= (size_t)ceil(0.995 * a.n));
    assert_int_equal(a.bad, 0);
    /* something is lit: not a black image */
    {
        size_t p, lit = 0;
        for (p = 0; p < 3 * px; p++)
            lit += img[p] > 8;
        assert_true(lit > px / 50);
    }
    free(img);
    free(ref);
    free(rs);
}

static int W(void) { return quick() ? 96 : 160; }
static int H(void) { return quick() ? 72 : 120; }

/* ---- cameras ---------------------------------------------------------------- */

static ref_cam cam_tiny(void)
{
    ref_cam c = { { -18, -22, 9 }, { 32, 10, 2 }, 60, 0, 0 };
    c.w = W();
    c.h = H();
    return c;
}

static ref_cam cam_eixample(void)
{
    /* street level in the street x = 133, looking north, a little to the east */
    ref_cam c = { { 131, 40, 1.7 }, { 160, 300, 8 }, 60, 0, 0 };
    c.w = W();
    c.h = H();
    return c;
}

static ref_cam cam_helsinki(const scene *s)
{
    /* from above a lamp, at 25 m, looking at another lamp 150 m away */
    ref_cam c = { { 0, 0, 25 }, { 0, 0, 0 }, 55, 0, 0 };
    const scene_lamp *a = &s->lamps[0];
    uint32_t i;
    c.eye[0] = a->x;
    c.eye[1] = a->y;
    for (i = 1; i < s->nlamps; i++) {
        double dx = s->lamps[i].x - a->x, dy = s->lamps[i].y - a->y;
        if (dx * dx + dy * dy > 150.0 * 150.0) {
            c.target[0] = a->x + 0.4 * dx;
            c.target[1] = a->y + 0.4 * dy;
            break;
        }
    }
    c.w = W();
    c.h = H();
    return c;
}

/* ---- tests: images against the reference ----------------------------------- */

static void test_tiny_vs_ref(void **state)
{
    fixture f;
    ref_cam c = cam_tiny();
    (void)state;
    fx_open(&f, "fixtures/tiny.geojson", 320, 240);
    check_against_ref(&f, &c, "tiny");
    /* under the canopy D, looking at it from the side, low */
    {
        ref_cam c2 = { { 22, -6, 1.5 }, { 28, 3, 3.5 }, 70, 0, 0 };
        c2.w = W();
        c2.h = H();
        check_against_ref(&f, &c2, "tiny-canopy");
    }
    /* from high above the courtyard of C, nearly straight down */
    {
        ref_cam c3 = { { 50, 9, 60 }, { 50, 10, 0 }, 50, 0, 0 };
        c3.w = W();
        c3.h = H();
        check_against_ref(&f, &c3, "tiny-above");
    }
    fx_close(&f);
}

static void test_eixample_vs_ref(void **state)
{
    fixture f;
    ref_cam c = cam_eixample();
    (void)state;
    fx_open(&f, "fixtures/eixample-4x4.geojson", 320, 240);
    check_against_ref(&f, &c, "eixample");
    fx_close(&f);
}

static void test_helsinki_vs_ref(void **state)
{
    fixture f;
    ref_cam c;
    (void)state;
    fx_open(&f, "fixtures/helsinki-centre.geojson", 320, 240);
    c = cam_helsinki(f.e->sc);
    check_against_ref(&f, &c, "helsinki");
    fx_close(&f);
}

/* ---- backends: soft and osmesa draw the same frame ------------------------ */

#ifdef PLX_HAVE_OSMESA
/* Renders c with the soft backend and with be; checks the agreement rule. */
static void check_backend(fixture *f, const ref_cam *c, const render_backend *be, const char *name)
{
    render_camera cam = to_cam(c);
    render_opts o;
    render_stats sa, sb;
    size_t px = (size_t)c->w * c->h;
    uint8_t *a = malloc(3 * px), *b = malloc(3 * px);
    uint32_t *ids = malloc(px * sizeof *ids);
    size_t p, same_id = 0;
    agree g;
    char nm[128];
    render_opts_default(&o);
    o.no_glow = 1;
    o.exposure = 0.5;
    assert_int_equal(render_frame(f->r, &cam, &o, a, NULL, &sa), PLX_OK);
    memcpy(ids, render_ids(f->r), px * sizeof *ids);
    o.backend = be;
    assert_int_equal(render_frame(f->r, &cam, &o, b, NULL, &sb), PLX_OK);
    for (p = 0; p < px; p++)
        same_id += render_ids(f->r)[p] == ids[p];
    g = compare(b, a, ids, c->w, c->h);
    print_message("%s soft vs %s: %zu px, %.3f %% within 2/255, %.3f %% same surface, %zu edge mismatches, "
                  "%zu others, max diff %d\n", name, be->name, g.n, 100.0 * g.close / g.n,
                  100.0 * same_id / g.n, g.edge_only, g.bad, g.maxdiff);
    snprintf(nm, sizeof nm, "%s.%s", name, be->name);
    save_png(nm, b, c->w, c->h);
    assert_true(g.close >= (size_t)ceil(0.995 * g.n));
    assert_int_equal(g.bad, 0);
    assert_int_equal(sa.drawn, sb.drawn);
    free(a);
    free(b);
    free(ids);
}
#endif

static void test_backends_agree(void **state)
{
#ifdef PLX_HAVE_OSMESA
    static const char *const paths[] = { "fixtures/tiny.geojson", "fixtures/eixample-4x4.geojson",
                                         "fixtures/helsinki-centre.geojson" };
    char err[256];
    plx_osmesa *om = plx_osmesa_open(320, 240, err, sizeof err);
    int k;
    (void)state;
    if (!om) {
        print_message("osmesa built but no context (%s): skipped\n", err);
        return;
    }
    for (k = 0; k < 3; k++) {
        fixture f;
        ref_cam c;
        fx_open(&f, paths[k], 320, 240);
        c = k == 0 ? cam_tiny() : k == 1 ? cam_eixample() : cam_helsinki(f.e->sc);
        check_backend(&f, &c, plx_osmesa_backend(om), k == 0 ? "tiny" : k == 1 ? "eixample" : "helsinki");
        if (k == 0) {
            ref_cam c2 = { { 22, -6, 1.5 }, { 28, 3, 3.5 }, 70, 0, 0 };
            ref_cam c3 = { { 50, 9, 60 }, { 50, 10, 0 }, 50, 0, 0 };
            c2.w = c3.w = W();
            c2.h = c3.h = H();
            check_backend(&f, &c2, plx_osmesa_backend(om), "tiny-canopy");
            check_backend(&f, &c3, plx_osmesa_backend(om), "tiny-above");
        }
        fx_close(&f);
    }
    /* a frame larger than the backend's buffers is refused, not drawn */
    {
        fixture f;
        ref_cam c = cam_tiny();
        render_camera cam;
        render_opts o;
        c.w = 321;
        cam = to_cam(&c);
        fx_open(&f, paths[0], 400, 300);
        render_opts_default(&o);
        o.backend = plx_osmesa_backend(om);
        assert_int_equal(render_frame(f.r, &cam, &o, NULL, NULL, NULL), PLX_E_UNSUPPORTED);
        assert_string_equal(render_error(f.r), "render_frame: the backend could not start the frame");
        fx_close(&f);
    }
    plx_osmesa_close(om);
#else
    (void)state;
    print_message("osmesa: not built (no OSMesa at build time): soft vs osmesa skipped\n");
#endif
}

/* ---- the light shader's tiled lamp lists ---------------------------------- */

/* The light module through the generic shader path (no tiling). */
static void light_generic(void *user, const double P[3], const double n[3], double rgb[3])
{
    double E;
    if (light_illuminance((light *)user, P, n, &E, rgb) != PLX_OK)
        rgb[0] = rgb[1] = rgb[2] = 0.0;
}

/* render_shade_light takes the renderer's per-tile lamp lists; the image
 * must be the one of light_illuminance called per pixel. */
static void test_tiled_light_same(void **state)
{
    static const char *const paths[] = { "fixtures/tiny.geojson", "fixtures/eixample-4x4.geojson",
                                         "fixtures/helsinki-centre.geojson" };
    int k;
    (void)state;
    for (k = 0; k < 3; k++) {
        void *mem;
        plx_engine *e = open_scene(paths[k], &mem);
        light *L;
        render *ra, *rb;
        render_camera cams[3];
        ref_cam c = k == 0 ? cam_tiny() : k == 1 ? cam_eixample() : cam_helsinki(e->sc);
        int ci, w = c.w, h = c.h;
        size_t px = (size_t)w * h, p, same = 0;
        float *fa = malloc(3 * px * sizeof *fa), *fb = malloc(3 * px * sizeof *fb);
        double maxrel = 0.0;
        uint64_t tiled = 0, skipped = 0;
        render_opts o;
        render_stats st;
        assert_int_equal(light_create(&e->mem, e->sc, (size_t)32 << 20, &L), PLX_OK);
        assert_int_equal(render_create(&e->mem, e->sc, w, h, render_shade_light, L, &ra), PLX_OK);
        assert_int_equal(render_create(&e->mem, e->sc, w, h, light_generic, L, &rb), PLX_OK);
        cams[0] = to_cam(&c);
        cams[1] = cams[0];
        cams[1].eye[2] += 40.0;   /* higher: bigger tiles in metres */
        cams[2] = cams[0];
        cams[2].target[0] = cams[2].eye[0] + 1e-3;   /* nearly straight down */
        cams[2].target[1] = cams[2].eye[1];
        cams[2].target[2] = 0.0;
        cams[2].eye[2] = 120.0;
        render_opts_default(&o);
        o.no_glow = 1;
        for (ci = 0; ci < 3; ci++) {
            assert_int_equal(render_frame(ra, &cams[ci], &o, NULL, fa, &st), PLX_OK);
            tiled += st.shader_tiled;
            skipped += st.visibility_skipped;
            assert_int_equal(render_frame(rb, &cams[ci], &o, NULL, fb, NULL), PLX_OK);
            for (p = 0; p < 3 * px; p++) {
                double a = fa[p], b = fb[p], rel = fabs(a - b) / fmax(1e-30, fmax(fabs(a), fabs(b)));
                same += fa[p] == fb[p];
                if (rel > maxrel)
                    maxrel = rel;
            }
        }
        print_message("%s: tiled vs per-pixel light shader: %.4f %% of values identical, max relative "
                      "difference %.2g\n", paths[k], 100.0 * same / (9.0 * px), maxrel);
        print_message("  %llu of the shaded pixels took a tile's lamp list; %llu lamp visibilities known "
                      "from the tile\n", (unsigned long long)tiled, (unsigned long long)skipped);
        assert_true(maxrel <= 1e-12);
        assert_true(tiled > 0);
        assert_true(skipped > 0);
        free(fa);
        free(fb);
        plx_engine_destroy(e);
        free(mem);
    }
}

/* A tile whose corners, seen from the lamp, span a range of angles that
 * starts before the lamp's first sector and ends after its last: both ends
 * fall in the last sector, which wraps past 4 (shade_tiles.c's
 * hull_visible). The range meets every sector; only the last was looked
 * at, so the tile was "surely lit" and its pixels behind the L's far arm
 * took the lamp's light (8 x 8 tiles lit in shadow, a random sweep's
 * scene, minimised: one L, one lamp). The tiled image must be the
 * per-pixel one. */
static void test_tiled_light_wrapping_sector(void **state)
{
    static const char *text =
        "{\"type\": \"FeatureCollection\", \"properties\": {\"units\": \"m\"}, \"features\": ["
        "{\"type\": \"Feature\", \"properties\": {\"height\": 14.17}, \"geometry\": {\"type\": \"Polygon\", "
        "\"coordinates\": [[[-21.82289277228733, 5.336292667928892], [-16.406078437873774, 8.894474622181901], "
        "[-18.035904743373212, 11.37564804381684], [-20.971545656151825, 9.447292395063268], "
        "[-23.321351165505426, 13.024529402557082], [-25.80252458714037, 11.394703097057645], "
        "[-21.82289277228733, 5.336292667928892]]]}}, "
        "{\"type\": \"Feature\", \"properties\": {\"lamp\": true, \"z\": 3.01, \"intensity\": 1771.5, "
        "\"radius\": 25.7}, \"geometry\": {\"type\": \"Point\", \"coordinates\": [-31.102, -0.088]}}]}";
    ref_cam c = { { 16.532226, 16.238432, 1.7 }, { -21.104302, 9.180411, 2.4 }, 60, 160, 120 };
    void *mem;
    plx_engine *e = fixture_text(text, (size_t)64 << 20, 1, &mem);
    light *L;
    render *ra, *rb;
    render_camera cam = to_cam(&c);
    size_t px = (size_t)c.w * c.h, p, differ = 0;
    float *fa = malloc(3 * px * sizeof *fa), *fb = malloc(3 * px * sizeof *fb);
    render_opts o;
    render_stats st;
    (void)state;
    assert_non_null(e);
    assert_int_equal(light_create(&e->mem, e->sc, (size_t)32 << 20, &L), PLX_OK);
    assert_int_equal(render_create(&e->mem, e->sc, c.w, c.h, render_shade_light, L, &ra), PLX_OK);
    assert_int_equal(render_create(&e->mem, e->sc, c.w, c.h, light_generic, L, &rb), PLX_OK);
    render_opts_default(&o);
    o.no_glow = 1;
    assert_int_equal(render_frame(ra, &cam, &o, NULL, fa, &st), PLX_OK);
    assert_int_equal(render_frame(rb, &cam, &o, NULL, fb, NULL), PLX_OK);
    for (p = 0; p < 3 * px; p++)
        differ += fabs((double)fa[p] - fb[p]) > 1e-12 * fmax(1e-30, fmax(fabs((double)fa[p]), fabs((double)fb[p])));
    print_message("wrapping sector: %zu of %zu values differ between the tiled and the per-pixel light; %llu "
                  "lamp visibilities known from the tile\n", differ, 3 * px, (unsigned long long)st.visibility_skipped);
    assert_int_equal(differ, 0); /* 117 before the fix */
    free(fa);
    free(fb);
    fixture_done(e, mem);
}

/* ---- sparse indirect (render_opts.indirect_sparse) ------------------------- */

typedef struct ind_count {
    uint64_t calls;
    int smooth;                /* 0: constant on each plane; 1: smooth in space */
} ind_count;

static void zero_shade(void *user, const double P[3], const double n[3], double rgb[3])
{
    (void)user;
    (void)P;
    (void)n;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
}

/* An indirect term constant on each plane (from its normal and offset),
 * or smooth over the whole scene (tens of metres). */
static void ind_hook(void *user, const double P[3], const double n[3], double rgb[3])
{
    ind_count *c = user;
    c->calls++;
    if (c->smooth) {
        rgb[0] = 10.0 + 5.0 * sin(0.05 * P[0] + 0.03 * P[1]) + 0.2 * P[2];
        rgb[1] = 8.0 + 4.0 * cos(0.04 * P[1]) + 0.1 * P[2];
        rgb[2] = 6.0 + 2.0 * sin(0.02 * (P[0] - P[1]));
    } else {
        double d = fabs(n[0] * P[0] + n[1] * P[1] + n[2] * P[2]);
        rgb[0] = 10.0 + 3.0 * n[0] + 2.0 * n[1] + n[2] + 0.01 * fmod(d, 100.0);
        rgb[1] = 7.0 + 0.5 * n[0] - n[1];
        rgb[2] = 5.0 + 0.02 * fmod(d, 50.0);
    }
}

/* Sparse against per pixel, on street and raised views of two fixtures:
 * with a term constant on each plane every pixel must agree (float
 * rounding: 1e-6) - no pixel forgotten, no light carried across an edge
 * into another surface -; with a smooth term the mean relative difference
 * stays small; the hook is asked far less often. */
static void test_sparse_indirect(void **state)
{
    static const char *const paths[] = { "fixtures/eixample-4x4.geojson", "fixtures/helsinki-centre.geojson" };
    int k;
    (void)state;
    for (k = 0; k < 2; k++) {
        void *mem;
        plx_engine *e = open_scene(paths[k], &mem);
        render *r;
        render_camera cams[2];
        ref_cam c = k == 0 ? cam_eixample() : cam_helsinki(e->sc);
        int ci, sm, w = c.w, h = c.h;
        size_t px = (size_t)w * h, p;
        float *fa = malloc(3 * px * sizeof *fa), *fb = malloc(3 * px * sizeof *fb);
        assert_non_null(fa);
        assert_non_null(fb);
        assert_int_equal(render_create(&e->mem, e->sc, w, h, zero_shade, NULL, &r), PLX_OK);
        cams[0] = to_cam(&c);
        cams[1] = cams[0];
        cams[1].eye[2] += 40.0;
        for (sm = 0; sm < 2; sm++)
            for (ci = 0; ci < 2; ci++) {
                ind_count ca = { 0, sm }, cb = { 0, sm };
                render_opts o;
                double maxrel = 0.0, sumrel = 0.0;
                size_t n = 0;
                render_opts_default(&o);
                o.no_glow = 1;
                o.indirect = ind_hook;
                o.indirect_user = &ca;
                assert_int_equal(render_frame(r, &cams[ci], &o, NULL, fa, NULL), PLX_OK);
                o.indirect_user = &cb;
                o.indirect_sparse = 1;
                o.indirect_span = 0.15; /* what the engine takes (ICACHE_KAPPA) */
                assert_int_equal(render_frame(r, &cams[ci], &o, NULL, fb, NULL), PLX_OK);
                for (p = 0; p < 3 * px; p++) {
                    double a = fa[p], b = fb[p], rel;
                    assert_true((a == 0.0) == (b == 0.0)); /* sky in both or neither */
                    if (a == 0.0)
                        continue;
                    rel = fabs(a - b) / fabs(a);
                    maxrel = rel > maxrel ? rel : maxrel;
                    sumrel += rel;
                    n++;
                }
                print_message("%s, %s view, %s term: hook asked %llu times sparse, %llu per pixel; "
                              "relative difference mean %.2g, max %.2g over %zu values\n",
                              paths[k], ci ? "raised" : "street", sm ? "smooth" : "plane-constant",
                              (unsigned long long)cb.calls, (unsigned long long)ca.calls,
                              n ? sumrel / (double)n : 0.0, maxrel, n);
                assert_true(n > px);              /* most of the frame is surface */
                /* fewer calls; in the full street view (large surfaces,
                 * 160 x 120) under half */
                assert_true(cb.calls < ca.calls && (ci || quick() || cb.calls * 2 < ca.calls));
                if (!sm)
                    assert_true(maxrel <= 1e-6);
                else
                    assert_true(sumrel / (double)n <= 2e-3);
            }
        free(fa);
        free(fb);
        plx_engine_destroy(e);
        free(mem);
    }
}

/* ---- culling: the culled image is the unculled image ---------------------- */

/* A cheap shader that gives every surface point its own colour. */
static void pos_shade(void *user, const double P[3], const double n[3], double rgb[3])
{
    (void)user;
    rgb[0] = 20.0 * (1.5 + sin(0.7 * P[0] + 0.3 * n[0]));
    rgb[1] = 20.0 * (1.5 + sin(0.9 * P[1] + 0.5 * n[1]));
    rgb[2] = 20.0 * (1.5 + sin(1.3 * P[2] + 0.7 * n[2]));
}

static uint64_t rng_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double rng_unit(uint64_t *s)
{
    return (rng_next(s) >> 11) * (1.0 / 9007199254740992.0);
}

/* The culling an anti-aliased frame's first sample point keeps for the
 * later ones (render_opts.cull_samples): camera c's frame with n x n
 * sample points (n = 2 or 3 by turns), one later sample point drawn at
 * random, is the same (ids, bytes and floats) with the first one's
 * culling kept as unculled, on one worker or (every other pair of
 * cameras) by bands of rows on two. a, fa, b, fb, ids: scratch of the
 * frame's size. */
static void kept_equal(render *r, const render_camera *cam, int c, uint8_t *a, float *fa, uint8_t *b, float *fb,
                       uint32_t *ids)
{
    size_t px = (size_t)cam->width * cam->height;
    uint64_t seed = 0x5eed0000u + (uint64_t)c; /* the cameras' own sequence untouched */
    int n = 2 + c % 2, k = 1 + (int)(rng_next(&seed) % (uint64_t)(n * n - 1));
    render_opts o;
    render_stats st;
    render_opts_default(&o);
    o.par = plx_port_posix()->parallel_for; /* every other camera by bands of rows on two workers */
    o.par_ctx = plx_port_posix()->ctx;
    o.workers = 1 + (c / 2) % 2;
    o.cull = RENDER_CULL_NONE;
    o.shift[0] = (k % n + 0.5) / n - 0.5;
    o.shift[1] = (k / n + 0.5) / n - 0.5;
    assert_int_equal(render_frame(r, cam, &o, a, fa, &st), PLX_OK);
    memcpy(ids, render_ids(r), px * sizeof *ids);
    o.cull = RENDER_CULL_ALL;
    o.cull_samples = RENDER_SAMPLE_FIRST;
    o.shift[0] = o.shift[1] = 0.5 / n - 0.5;
    assert_int_equal(render_frame(r, cam, &o, b, fb, &st), PLX_OK);
    o.cull_samples = RENDER_SAMPLE_LATER;
    o.shift[0] = (k % n + 0.5) / n - 0.5;
    o.shift[1] = (k / n + 0.5) / n - 0.5;
    assert_int_equal(render_frame(r, cam, &o, b, fb, &st), PLX_OK);
    assert_int_equal(st.cull_kept, 1);
    if (memcmp(ids, render_ids(r), px * sizeof *ids) != 0 || memcmp(a, b, 3 * px) != 0 ||
        memcmp(fa, fb, 3 * px * sizeof(float)) != 0)
        fail_msg("camera %d: eye (%.3f, %.3f, %.3f) target (%.3f, %.3f, %.3f) fov %.2f, sample %d of %dx%d: "
                 "the first sample's culling kept gives another frame than no culling", c, cam->eye[0],
                 cam->eye[1], cam->eye[2], cam->target[0], cam->target[1], cam->target[2], cam->fov_deg, k, n, n);
}

/* Renders ncam cameras culled and unculled; returns buildings culled by
 * occlusion in all. Eyes: near lamps (streets), at height z (z < 0: the
 * eye height drawn from 1.5 .. -z). */
/* zmin 0: street-level eyes from 1.5 m to zmax looking about level;
 * else eyes from zmin to zmax looking down at the ground 50 to 300 m
 * away. */
static uint64_t cull_equal_from(const char *path, int ncam, double zmin, double zmax, uint64_t seed)
{
    void *mem;
    plx_engine *e = open_scene(path, &mem);
    const scene *s = e->sc;
    render *r;
    int w = quick() ? 80 : 160, h = quick() ? 60 : 120, c;
    size_t px = (size_t)w * h;
    uint8_t *a = malloc(3 * px), *b = malloc(3 * px);
    float *fa = malloc(3 * px * sizeof(float)), *fb = malloc(3 * px * sizeof(float));
    uint32_t *ids = malloc(px * sizeof *ids);
    uint64_t culled = 0, drawn = 0, total = 0;
    assert_int_equal(render_create(&e->mem, s, w, h, pos_shade, NULL, &r), PLX_OK);
    for (c = 0; c < ncam; c++) {
        const scene_lamp *l = &s->lamps[rng_next(&seed) % s->nlamps];
        double ang = TWO_PI_T * rng_unit(&seed);
        render_camera cam;
        render_opts o;
        render_stats sa, sb;
        cam.eye[0] = l->x + 1.3 * cos(ang);
        cam.eye[1] = l->y + 1.3 * sin(ang);
        cam.eye[2] = zmin > 0.0 ? zmin + (zmax - zmin) * rng_unit(&seed) : 1.5 + (zmax - 1.5) * rng_unit(&seed);
        ang = TWO_PI_T * rng_unit(&seed);
        if (zmin > 0.0) {
            double d = 50 + 250 * rng_unit(&seed);
            cam.target[0] = cam.eye[0] + d * cos(ang);
            cam.target[1] = cam.eye[1] + d * sin(ang);
            cam.target[2] = 0.0;
        } else {
            cam.target[0] = cam.eye[0] + 100 * cos(ang);
            cam.target[1] = cam.eye[1] + 100 * sin(ang);
            cam.target[2] = cam.eye[2] + 30 * (rng_unit(&seed) - 0.6);
        }
        cam.fov_deg = 30 + 60 * rng_unit(&seed);
        cam.width = w;
        cam.height = h;
        render_opts_default(&o);
        o.cull = RENDER_CULL_NONE;
        assert_int_equal(render_frame(r, &cam, &o, a, fa, &sa), PLX_OK);
        memcpy(ids, render_ids(r), px * sizeof *ids);
        o.cull = RENDER_CULL_ALL;
        assert_int_equal(render_frame(r, &cam, &o, b, fb, &sb), PLX_OK);
        if (memcmp(ids, render_ids(r), px * sizeof *ids) != 0 || memcmp(a, b, 3 * px) != 0 ||
            memcmp(fa, fb, 3 * px * sizeof(float)) != 0) {
            size_t p, nd = 0;
            for (p = 0; p < px; p++)
                nd += ids[p] != render_ids(r)[p];
            save_png("cull-unculled", a, w, h);
            save_png("cull-culled", b, w, h);
            fail_msg("%s camera %d: eye (%.3f, %.3f, %.3f) target (%.3f, %.3f, %.3f) fov %.2f: culled image "
                     "differs (%zu pixels of other surfaces)", path, c, cam.eye[0], cam.eye[1], cam.eye[2],
                     cam.target[0], cam.target[1], cam.target[2], cam.fov_deg, nd);
        }
        assert_int_equal(sa.occlusion_culled, 0);
        kept_equal(r, &cam, c, a, fa, b, fb, ids);
        culled += sb.occlusion_culled;
        drawn += sb.triangles_drawn;
        total += sb.triangles;
    }
    print_message("%s: %d cameras, eye z 1.5 .. %.0f m: %.1f %% of triangles drawn, %llu buildings culled by "
                  "occlusion\n", path, ncam, zmax, 100.0 * drawn / total, (unsigned long long)culled);
    free(a);
    free(b);
    free(fa);
    free(fb);
    free(ids);
    plx_engine_destroy(e);
    free(mem);
    return culled;
}

static uint64_t cull_equal(const char *path, int ncam, double zmax, uint64_t seed)
{
    return cull_equal_from(path, ncam, 0.0, zmax, seed);
}

static void test_cull_equal_street(void **state)
{
    (void)state;
    assert_true(cull_equal("fixtures/eixample-4x4.geojson", quick() ? 6 : 24, 1.8, 11) > 0);
    assert_true(cull_equal("fixtures/helsinki-centre.geojson", quick() ? 6 : 24, 1.8, 12) > 0);
    cull_equal("fixtures/tiny.geojson", 10, 1.8, 13);
}

static void test_cull_equal_above_roofs(void **state)
{
    (void)state;
    /* eyes up to 35 m: above many roofs (eixample 15-28 m, Helsinki median 12 m).
     * The images must be equal in every mode; that culling did take place is
     * asserted on the full set of cameras (the few quick-mode cameras, used
     * under valgrind, may all look over every roof). */
    uint64_t a = cull_equal("fixtures/eixample-4x4.geojson", quick() ? 6 : 24, 35, 21);
    uint64_t b = cull_equal("fixtures/helsinki-centre.geojson", quick() ? 6 : 24, 35, 22);
    if (!quick()) {
        assert_true(a > 0);
        assert_true(b > 0);
    }
    cull_equal("fixtures/tiny.geojson", 10, 14, 23);
    cull_equal("fixtures/oldtown-8x8.geojson", quick() ? 6 : 16, 25, 24);
}

/* The groups of culling cells (cull.c groups_out: a group out of the
 * frustum culls its cells untested), over scenes of several groups a
 * side: eyes anywhere over the scene, at street level looking level to
 * up (the frame's lower edge cuts walls: a group's tops decide) or above
 * the roofs looking down, any way round, small frames; the culled ids
 * must equal the unculled ones. Returns the buildings the frustum culled in all. */
static uint64_t cull_groups_equal(plx_engine *e, int ncam, uint64_t seed)
{
    const scene *s = e->sc;
    const double *bd = s->bounds;
    render *r;
    int w = 40, h = 30, c;
    size_t px = (size_t)w * h;
    uint32_t *ids = malloc(px * sizeof *ids);
    uint64_t culled = 0;
    assert_int_equal(render_create(&e->mem, s, w, h, pos_shade, NULL, &r), PLX_OK);
    for (c = 0; c < ncam; c++) {
        double ang = TWO_PI_T * rng_unit(&seed), pitch = c % 2 ? -0.6 * rng_unit(&seed) : 0.6 * rng_unit(&seed) - 0.1;
        render_camera cam;
        render_opts o;
        render_stats st;
        cam.eye[0] = bd[0] + (bd[2] - bd[0]) * rng_unit(&seed);
        cam.eye[1] = bd[1] + (bd[3] - bd[1]) * rng_unit(&seed);
        cam.eye[2] = c % 2 ? 20.0 + 200.0 * rng_unit(&seed) : 1.5 + 0.5 * rng_unit(&seed);
        cam.target[0] = cam.eye[0] + 100 * cos(ang);
        cam.target[1] = cam.eye[1] + 100 * sin(ang);
        cam.target[2] = cam.eye[2] + 100 * pitch;
        cam.fov_deg = 10 + 100 * rng_unit(&seed);
        cam.width = w;
        cam.height = h;
        render_opts_default(&o);
        o.cull = RENDER_CULL_NONE;
        assert_int_equal(render_frame(r, &cam, &o, NULL, NULL, NULL), PLX_OK);
        memcpy(ids, render_ids(r), px * sizeof *ids);
        o.cull = RENDER_CULL_ALL;
        assert_int_equal(render_frame(r, &cam, &o, NULL, NULL, &st), PLX_OK);
        if (memcmp(ids, render_ids(r), px * sizeof *ids) != 0)
            fail_msg("camera %d: eye (%.3f, %.3f, %.3f) target (%.3f, %.3f, %.3f) fov %.2f: culled ids differ",
                     c, cam.eye[0], cam.eye[1], cam.eye[2], cam.target[0], cam.target[1], cam.target[2],
                     cam.fov_deg);
        culled += st.frustum_culled;
    }
    free(ids);
    return culled;
}

static void test_cull_groups(void **state)
{
    fixture_city t;
    void *mem;
    plx_engine *e;
    int n = quick() ? 60 : 400;
    (void)state;
    fixture_gen("eixample", 12, 12, 7, &t); /* about 1.6 km a side: 4 groups a side */
    e = fixture_text(t.buf, MEM, 0, &mem);
    assert_true(cull_groups_equal(e, n, 31) > 0);
    plx_engine_destroy(e);
    free(mem);
    free(t.buf);
    e = open_scene("fixtures/helsinki-centre.geojson", &mem); /* 28 cells, 4 groups a side */
    assert_true(cull_groups_equal(e, n, 32) > 0);
    plx_engine_destroy(e);
    free(mem);
}

/* Eyes above twice the tallest top, where the occlusion test is skipped
 * (cull.c occlusion_pays): the image is still the unculled one. */
static void test_cull_equal_high(void **state)
{
    (void)state;
    cull_equal_from("fixtures/eixample-4x4.geojson", quick() ? 4 : 16, 57, 400, 25);
    cull_equal_from("fixtures/helsinki-centre.geojson", quick() ? 4 : 16, 141, 500, 26);
    cull_equal_from("fixtures/oldtown-8x8.geojson", quick() ? 4 : 12, 60, 300, 27);
}

/* The kept culling at the frame's edge (render_opts.cull_samples): a box
 * building seen from a level eye, the camera turned so that the box's
 * leftmost vertical edge falls at 81 places across the last two pixels
 * of the right-hand edge. With 3 x 3 sample points the first (a third of
 * a pixel left and up of the centre) and a later one lie 2/3 of a pixel
 * apart, more than the half pixel by which the frame's edge lies beyond
 * its outermost sample points: a culling made for the first sample alone
 * would cull the building where a later sample sees it. Every later
 * sample with the first one's culling kept equals no culling (ids and
 * floats), and some of them see the building where the first does not. */
/* One sweep of test_cull_kept_edge: the camera turned (vertical: pitched)
 * so that the box's leftmost vertical edge (vertical: its top edge) falls
 * at 81 places across the last two pixels of the frame's right (bottom)
 * edge, drawn on the given workers (2: by bands of rows). Returns the
 * later samples that see the box where the first does not. */
static int kept_edge_sweep(render *r, int w, int h, int vertical, int workers)
{
    const int n = 3;
    size_t px = (size_t)w * h, p;
    render_camera cam = { { 0, 0, 6 }, { 0, 0, 6 }, 60, 0, 0 };
    render_opts o;
    render_stats st;
    uint32_t *ids = malloc(px * sizeof *ids);
    float *fa = malloc(3 * px * sizeof *fa);
    int step, k, first_sees, only_later = 0;
    /* the footprint's most anticlockwise corner from the eye, (-5, 40), and
     * the elevation of the box's front top edge (20 m high, 40 m away) */
    double phi = atan2(40.0, -5.0), sx = 1.0 / (tan(PI / 6.0) * (double)w / h), alpha = atan2(14.0, 40.0);
    cam.width = w;
    cam.height = h;
    for (step = 0; step <= 80; step++) {
        double xb = 1.0 - 4.0 / w + step * (4.0 / w) / 80.0, yb = -1.0 + step * (4.0 / h) / 80.0;
        if (vertical) {
            double th = alpha - atan(yb * tan(PI / 6.0));
            cam.target[0] = 0.0;
            cam.target[1] = 100.0 * cos(th);
            cam.target[2] = 6.0 + 100.0 * sin(th);
        } else {
            double th = phi + atan(xb / sx);
            cam.target[0] = 100.0 * cos(th);
            cam.target[1] = 100.0 * sin(th);
            cam.target[2] = 6.0;
        }
        for (k = 1; k < n * n; k++) {
            int later_sees = 0;
            render_camera moved = cam;
            /* the later sample unculled; then the first sample's culling,
             * kept for the later one (a frame between would drop it) */
            render_opts_default(&o);
            o.par = plx_port_posix()->parallel_for;
            o.par_ctx = plx_port_posix()->ctx;
            o.workers = workers;
            o.shift[0] = (k % n + 0.5) / n - 0.5;
            o.shift[1] = (k / n + 0.5) / n - 0.5;
            o.cull = RENDER_CULL_NONE;
            assert_int_equal(render_frame(r, &cam, &o, NULL, fa, &st), PLX_OK);
            memcpy(ids, render_ids(r), px * sizeof *ids);
            o.cull = RENDER_CULL_ALL;
            o.cull_samples = RENDER_SAMPLE_FIRST;
            o.shift[0] = o.shift[1] = 0.5 / n - 0.5;
            assert_int_equal(render_frame(r, &cam, &o, NULL, NULL, &st), PLX_OK);
            assert_int_equal(st.cull_kept, 0);
            for (p = 0, first_sees = 0; p < px; p++)
                first_sees |= render_ids(r)[p] >= 2;
            o.cull_samples = RENDER_SAMPLE_LATER;
            o.shift[0] = (k % n + 0.5) / n - 0.5;
            o.shift[1] = (k / n + 0.5) / n - 0.5;
            assert_int_equal(render_frame(r, &cam, &o, NULL, NULL, &st), PLX_OK);
            assert_int_equal(st.cull_kept, 1);
            assert_memory_equal(ids, render_ids(r), px * sizeof *ids);
            assert_memory_equal(fa, render_linear(r), 3 * px * sizeof *fa);
            for (p = 0; p < px; p++)
                later_sees |= ids[p] >= 2;
            only_later += later_sees && !first_sees;
            /* a later sample of another camera culls for itself */
            moved.eye[0] += 0.5;
            assert_int_equal(render_frame(r, &moved, &o, NULL, NULL, &st), PLX_OK);
            assert_int_equal(st.cull_kept, 0);
        }
    }
    free(ids);
    free(fa);
    return only_later;
}

/* The kept culling at the frame's edge (render_opts.cull_samples): a box
 * building seen from an eye 6 m up, the camera turned so that the box's
 * edge falls at 81 places across the last two pixels of the frame's
 * right-hand edge, then pitched so that its top edge falls across the
 * bottom edge, on one worker and by bands of rows on two. With 3 x 3
 * sample points the first (a third of a pixel left and up of the centre)
 * and a later one lie 2/3 of a pixel apart, more than the half pixel by
 * which the frame's edge lies beyond its outermost sample points: a
 * culling made for the first sample alone would cull the box where a
 * later sample sees it. Every later sample with the first one's culling
 * kept equals no culling (ids and floats), some of them see the box where
 * the first does not, and a later sample of another camera does not take
 * the kept culling. */
static void test_cull_kept_edge(void **state)
{
    if (getenv("PLX_TEST_QUICK")) /* seconds: check-full (CI) runs it, make check keeps its minute */
        skip();
    static const char *text =
        "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
        "{\"type\":\"Feature\",\"properties\":{\"height\":20},\"geometry\":{\"type\":\"Polygon\","
        "\"coordinates\":[[[-5,40],[5,40],[5,50],[-5,50],[-5,40]]]}},"
        "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":8,\"radius\":80},"
        "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,20]}}]}";
    void *mem;
    plx_engine *e = fixture_load_text(fixture_engine(MEM, 0, NULL, &mem), text, "edge");
    render *r;
    int vertical, workers, only;
    (void)state;
    assert_int_equal(render_create(&e->mem, e->sc, 96, 72, pos_shade, NULL, &r), PLX_OK);
    for (vertical = 0; vertical < 2; vertical++)
        for (workers = 1; workers <= 2; workers++) {
            only = kept_edge_sweep(r, 96, 72, vertical, workers);
            print_message("kept culling at the frame's %s edge, %d worker%s: 648 later samples equal to no "
                          "culling, %d of them see the building where the first sample does not\n",
                          vertical ? "bottom" : "right", workers, workers > 1 ? "s" : "", only);
            assert_true(only > 0);
        }
    plx_engine_destroy(e);
    free(mem);
}

/* The far plane kept between frames of one eye (camera_setup): a frame
 * from an eye far outside the scene after one from inside it needs a far
 * plane of its own; its ids equal those of a new render object's first
 * frame from there (with the first eye's far plane the farther buildings
 * would be cut off). */
static void test_far_plane_follows_eye(void **state)
{
    void *mem;
    plx_engine *e = fixture_file("fixtures/eixample-4x4.geojson", MEM, &mem);
    const scene *s = e->sc;
    render *r, *fresh;
    double cx = 0.5 * (s->bounds[0] + s->bounds[2]), cy = 0.5 * (s->bounds[1] + s->bounds[3]);
    render_camera near_cam = { { 0, 0, 1.7 }, { 0, 0, 3 }, 60, 96, 72 };
    render_camera far_cam = { { 0, 0, 40 }, { 0, 0, 0 }, 20, 96, 72 };
    render_opts o;
    render_stats st;
    uint32_t *ids = malloc(96 * 72 * sizeof *ids);
    size_t p, seen = 0;
    (void)state;
    near_cam.eye[0] = cx;
    near_cam.eye[1] = cy;
    near_cam.target[0] = cx + 50.0;
    near_cam.target[1] = cy;
    far_cam.eye[0] = cx - 3000.0;
    far_cam.eye[1] = cy;
    far_cam.target[0] = cx;
    far_cam.target[1] = cy;
    assert_int_equal(render_create(&e->mem, s, 96, 72, pos_shade, NULL, &r), PLX_OK);
    assert_int_equal(render_create(&e->mem, s, 96, 72, pos_shade, NULL, &fresh), PLX_OK);
    render_opts_default(&o);
    assert_int_equal(render_frame(fresh, &far_cam, &o, NULL, NULL, &st), PLX_OK);
    memcpy(ids, render_ids(fresh), 96 * 72 * sizeof *ids);
    assert_int_equal(render_frame(r, &near_cam, &o, NULL, NULL, &st), PLX_OK);
    assert_int_equal(render_frame(r, &far_cam, &o, NULL, NULL, &st), PLX_OK);
    assert_memory_equal(ids, render_ids(r), 96 * 72 * sizeof *ids);
    for (p = 0; p < 96 * 72; p++)
        seen += ids[p] >= 2;
    print_message("far plane from 3 km after a frame from inside the scene: %zu building pixels, as a new "
                  "render object's\n", seen);
    assert_true(seen > 0);
    free(ids);
    plx_engine_destroy(e);
    free(mem);
}

/* An eye just above a low roof, looking over it at taller buildings behind:
 * the low building must not hide them. */
static void test_cull_over_low_roof(void **state)
{
    static const char *text =
        "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
        "{\"type\":\"Feature\",\"properties\":{\"height\":6},\"geometry\":{\"type\":\"Polygon\","
        "\"coordinates\":[[[-20,10],[20,10],[20,20],[-20,20],[-20,10]]]}},"
        "{\"type\":\"Feature\",\"properties\":{\"height\":30},\"geometry\":{\"type\":\"Polygon\","
        "\"coordinates\":[[[-10,40],[10,40],[10,50],[-10,50],[-10,40]]]}},"
        "{\"type\":\"Feature\",\"properties\":{\"height\":5},\"geometry\":{\"type\":\"Polygon\","
        "\"coordinates\":[[[-5,60],[5,60],[5,70],[-5,70],[-5,60]]]}},"
        "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":8,\"radius\":60},"
        "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,30]}},"
        "{\"type\":\"Feature\",\"properties\":{\"lamp\":true,\"z\":8,\"radius\":60},"
        "\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,0]}}]}";
    void *mem;
    plx_engine *e = fixture_load_text(fixture_engine(MEM, 0, NULL, &mem), text, "low");
    render *r;
    render_camera cam = { { 0, 0, 7 }, { 0, 45, 8 }, 60, 96, 72 };
    render_opts o;
    render_stats st;
    uint32_t *ids = malloc(96 * 72 * sizeof *ids);
    size_t p, tall = 0;
    double z;
    (void)state;
    assert_int_equal(render_create(&e->mem, e->sc, 96, 72, pos_shade, NULL, &r), PLX_OK);
    render_opts_default(&o);
    for (z = 1.5; z < 40; z += 2.5) {
        cam.eye[2] = z;
        cam.target[2] = z;
        o.cull = RENDER_CULL_NONE;
        assert_int_equal(render_frame(r, &cam, &o, NULL, NULL, &st), PLX_OK);
        memcpy(ids, render_ids(r), 96 * 72 * sizeof *ids);
        o.cull = RENDER_CULL_ALL;
        assert_int_equal(render_frame(r, &cam, &o, NULL, NULL, &st), PLX_OK);
        assert_memory_equal(ids, render_ids(r), 96 * 72 * sizeof *ids);
        for (p = 0, tall = 0; p < 96 * 72; p++)
            tall += ids[p] == mesh_roof_id(e->sc, 1) || (ids[p] >= 2 + 4 && ids[p] < 2 + 8);
        /* below 6 m the low building hides the tall one's lower part only;
         * the tall one always shows (it rises above) */
        assert_true(tall > 0);
        /* the 5 m building right behind the tower is in its shadow from
         * every height here (from above, rays reaching it are too steep) */
        assert_true(st.occlusion_culled >= 1);
    }
    free(ids);
    plx_engine_destroy(e);
    free(mem);
}

/* ---- the mesh ---------------------------------------------------------------- */

typedef struct dedge { double a[3], b[3]; int ground; } dedge; /* ground: a bottom edge at z = 0 */

static int cmp_dedge(const void *pa, const void *pb)
{
    const double *a = pa, *b = pb;
    int k;
    for (k = 0; k < 6; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

static void check_mesh_scene(plx_engine *e, const scene *s, const char *path, int want_search)
{
    mesh *m;
    uint32_t b, k, open_edges = 0, nv = 0, ntri = 0, hidden = 0, *wall_tris;
    size_t ne = 0, i;
    dedge *ed;
    double *xyz;
    mesh_tri *tri;
    assert_int_equal(mesh_build(&e->mem, s, &m), PLX_OK);
    assert_int_equal(m->bad_holes, 0);
    /* walls find their building by a search, or by the kept table */
    assert_int_equal(m->pt_bld == NULL, want_search);
    ed = malloc((3 * (size_t)m->ntri + 1) * sizeof *ed);
    wall_tris = calloc((size_t)s->npts + 1, sizeof *wall_tris);
    xyz = malloc((3 * (size_t)m->max_bld_verts + 1) * sizeof *xyz);
    tri = malloc(((size_t)m->max_bld_tris + 1) * sizeof *tri);
    for (b = 0; b < s->nbld; b++) {
        const scene_building *bd = &s->bld[b];
        const mesh_bld *mb = &m->bld[b];
        double want = 0, got = 0;
        uint32_t r;
        assert_true(mb->v_count <= m->max_bld_verts && mb->t_count <= m->max_bld_tris);
        mesh_building(m, b, xyz, tri);
        nv += mb->v_count;
        ntri += mb->t_count;
        for (r = 0; r < bd->ring_count; r++) {
            const scene_ring *rg = &s->rings[bd->ring_first + r];
            want += geom_ring_area2(s->pts + rg->first, rg->count) * 0.5;
        }
        for (k = 0; k < mb->t_count; k++) {
            const mesh_tri *t = &tri[k];
            const double *p0 = &xyz[3 * t->v[0]], *p1 = &xyz[3 * t->v[1]], *p2 = &xyz[3 * t->v[2]];
            double nx = (p1[1] - p0[1]) * (p2[2] - p0[2]) - (p1[2] - p0[2]) * (p2[1] - p0[1]);
            double ny = (p1[2] - p0[2]) * (p2[0] - p0[0]) - (p1[0] - p0[0]) * (p2[2] - p0[2]);
            double nz = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
            mesh_surf sf;
            int j;
            mesh_surface(m, t->surf, &sf);
            for (j = 0; j < 3; j++)
                assert_true(t->v[j] < mb->v_count);
            /* every triangle faces out of the solid, and lies on its surface's plane */
            assert_true(nx * sf.n[0] + ny * sf.n[1] + nz * sf.n[2] > 0);
            for (j = 0; j < 3; j++) {
                const double *pj = &xyz[3 * t->v[j]];
                double off = sf.n[0] * pj[0] + sf.n[1] * pj[1] + sf.n[2] * pj[2] - sf.d;
                assert_true(fabs(off) <= 1e-9 * (fabs(sf.d) + fabs(pj[0]) + fabs(pj[1]) + fabs(pj[2]) + 1.0));
            }
            assert_int_equal(sf.bld, b);
            assert_true(sf.albedo == bd->albedo && mesh_albedo(m, t->surf) == sf.albedo);
            assert_int_equal(sf.kind, t->surf == mesh_roof_id(s, b) ? MESH_KIND_ROOF
                                      : t->surf == mesh_under_id(s, b) ? MESH_KIND_UNDER : MESH_KIND_WALL);
            if (t->surf == mesh_roof_id(s, b))
                got += 0.5 * nz;
            if (t->surf >= 2 && t->surf < 2 + s->npts)
                wall_tris[t->surf - 2]++;
            for (j = 0; j < 3; j++) {
                memcpy(ed[ne].a, &xyz[3 * t->v[j]], 3 * sizeof(double));
                memcpy(ed[ne].b, &xyz[3 * t->v[(j + 1) % 3]], 3 * sizeof(double));
                ed[ne].ground = bd->min_height == 0 && ed[ne].a[2] == 0 && ed[ne].b[2] == 0;
                ne++;
            }
        }
        if (fabs(got - want) > 1e-9 * fabs(want) + 1e-9)
            fail_msg("%s building %u: roof area %.17g, footprint area %.17g", path, b, got, want);
    }
    /* watertight as a whole: every directed edge has its reverse in some
     * building (the bottoms of buildings on the ground aside): a wall
     * hidden whole is left out, and the solids against it close the mesh
     * there with the same points */
    qsort(ed, ne, sizeof *ed, cmp_dedge);
    for (i = 0; i < ne; i++) {
        dedge rev;
        memcpy(rev.a, ed[i].b, sizeof rev.a);
        memcpy(rev.b, ed[i].a, sizeof rev.b);
        if (!ed[i].ground && !bsearch(&rev, ed, ne, sizeof *ed, cmp_dedge))
            open_edges++;
    }
    /* exactly the walls hidden whole have no triangles */
    for (k = 0; k < s->npts; k++) {
        int hid = (m->hidden[k >> 3] >> (k & 7)) & 1;
        hidden += (uint32_t)hid;
        if (hid) {
            assert_int_equal(wall_tris[k], 0);
        } else {
            mesh_surf sf;
            mesh_surface(m, mesh_wall_id(s, k), &sf);
            if (s->bld[sf.bld].height > s->bld[sf.bld].min_height && wall_tris[k] == 0)
                fail_msg("%s: wall %u has no triangles and is not hidden", path, k);
        }
    }
    assert_int_equal(nv, m->nv);
    assert_int_equal(ntri, m->ntri);
    print_message("%s: %u vertices, %u triangles, %u column split vertices, %u walls hidden whole, %u ear "
                  "fallbacks, %zu bytes\n",
                  path, m->nv, m->ntri, m->split_verts, hidden, m->fallbacks, m->bytes);
    assert_int_equal(open_edges, 0);
    free(wall_tris);
    free(ed);
    free(xyz);
    free(tri);
}

static void check_mesh_of(plx_engine *e, const char *path)
{
    check_mesh_scene(e, e->sc, path, 1);
}

/* The same buildings listed backwards: their rings no longer run in
 * building order, so the mesh keeps each footprint vertex's building. */
static void check_mesh_reversed(plx_engine *e, const char *path)
{
    scene s = *e->sc;
    uint32_t b;
    s.bld = malloc((s.nbld + 1) * sizeof *s.bld);
    for (b = 0; b < s.nbld; b++)
        s.bld[b] = e->sc->bld[s.nbld - 1 - b];
    check_mesh_scene(e, &s, path, s.nbld < 2);
    free(s.bld);
}

static void check_mesh(const char *path)
{
    void *mem;
    plx_engine *e = open_scene(path, &mem);
    check_mesh_of(e, path);
    check_mesh_reversed(e, path);
    plx_engine_destroy(e);
    free(mem);
}

static void test_mesh_fixtures(void **state)
{
    (void)state;
    check_mesh("fixtures/tiny.geojson");
    check_mesh("fixtures/eixample-4x4.geojson");
    check_mesh("fixtures/oldtown-8x8.geojson");
    check_mesh("fixtures/helsinki-centre.geojson");
}

/* Awkward footprints: collinear vertices, a comb, holes near each other and
 * near the outer ring, a hole touching the outer ring's vertex line. */
static void test_mesh_awkward(void **state)
{
    static const char *text =
        "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":["
        /* square with collinear vertices on every side and two holes */
        "{\"type\":\"Feature\",\"properties\":{\"height\":10},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":["
        "[[0,0],[5,0],[10,0],[10,5],[10,10],[5,10],[0,10],[0,5],[0,0]],"
        "[[2,2],[2,4],[4,4],[4,2],[2,2]],[[6,6],[6,8],[8,8],[8,6],[6,6]]]}},"
        /* a comb */
        "{\"type\":\"Feature\",\"properties\":{\"height\":7},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":["
        "[[20,0],[30,0],[30,10],[29,10],[29,2],[28,2],[28,10],[27,10],[27,2],[26,2],[26,10],[25,10],"
        "[25,2],[24,2],[24,10],[23,10],[23,2],[22,2],[22,10],[20,10],[20,0]]]}},"
        /* holes side by side with aligned vertices (bridges must not cross) */
        "{\"type\":\"Feature\",\"properties\":{\"height\":9,\"min_height\":3},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":["
        "[[40,0],[60,0],[60,10],[40,10],[40,0]],"
        "[[42,4],[42,6],[44,6],[44,4],[42,4]],[[46,4],[46,6],[48,6],[48,4],[46,4]],"
        "[[50,4],[50,6],[52,6],[52,4],[50,4]],[[54,4],[54,6],[56,6],[56,4],[54,4]]]}},"
        /* a spiral-ish concave polygon */
        "{\"type\":\"Feature\",\"properties\":{\"height\":12},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":["
        "[[0,20],[12,20],[12,32],[2,32],[2,24],[8,24],[8,28],[6,28],[6,26],[4,26],[4,30],[10,30],[10,22],"
        "[0,22],[0,20]]]}}]}";
    void *mem;
    plx_engine *e = fixture_load_text(fixture_engine(MEM, 0, NULL, &mem), text, "awkward");
    (void)state;
    assert_int_equal(e->sc->nbld, 4);
    check_mesh_of(e, "awkward");
    plx_engine_destroy(e);
    free(mem);
}

/* ---- golden images ------------------------------------------------------------ */

/* Compares img with fixtures/golden/<name>.png: every channel within 3/255
 * on 99.8 % of pixels (and the image size equal). On failure writes
 * build/golden-out/<name>.actual.png and <name>.diff.png (|difference| x 16)
 * and says how to update. PLX_UPDATE_GOLDEN=1 writes the golden instead. */
static void golden(const char *name, const uint8_t *img, int w, int h)
{
    char path[256], err[256], out[256];
    uint8_t *g = NULL;
    int gw = 0, gh = 0;
    size_t p, bad = 0, px = (size_t)w * h;
    snprintf(path, sizeof path, "fixtures/golden/%s.png", name);
    if (getenv("PLX_UPDATE_GOLDEN")) {
        mkdir("fixtures/golden", 0777);
        assert_int_equal(image_write_png_rgb8(path, w, h, img, 0, err, sizeof err), 0);
        print_message("golden: wrote %s\n", path);
        return;
    }
    if (image_read_png_rgb8(path, NULL, 0, &g, &gw, &gh, err, sizeof err) == 0 && gw == w && gh == h) {
        for (p = 0; p < 3 * px; p += 3) {
            int k, d = 0;
            for (k = 0; k < 3; k++)
                d = abs((int)img[p + k] - (int)g[p + k]) > d ? abs((int)img[p + k] - (int)g[p + k]) : d;
            bad += d > 3;
        }
        if (bad * 1000 <= px * 2) {
            free(g);
            return;
        }
    }
    mkdir("build", 0777);
    mkdir("build/golden-out", 0777);
    snprintf(out, sizeof out, "build/golden-out/%s.actual.png", name);
    image_write_png_rgb8(out, w, h, img, 0, err, sizeof err);
    if (g && gw == w && gh == h) {
        uint8_t *d = malloc(3 * px);
        for (p = 0; p < 3 * px; p++) {
            int v = abs((int)img[p] - (int)g[p]) * 16;
            d[p] = (uint8_t)(v > 255 ? 255 : v);
        }
        snprintf(out, sizeof out, "build/golden-out/%s.diff.png", name);
        image_write_png_rgb8(out, w, h, d, 0, err, sizeof err);
        free(d);
    }
    free(g);
    fail_msg("golden image %s: %s (%zu pixels beyond 3/255); actual and diff images are in build/golden-out/; "
             "if the change is intended, update with: PLX_UPDATE_GOLDEN=1 build/tests/test_render (from the "
             "repository root), then look at fixtures/golden/%s.png", path,
             gw ? "differs" : "missing or unreadable", bad, name);
}

static void test_golden(void **state)
{
    fixture f;
    render_opts o;
    render_camera cam;
    uint8_t *img = malloc(160 * 120 * 3);
    ref_cam c;
    (void)state;
    render_opts_default(&o);
    /* tiny: glows on */
    fx_open(&f, "fixtures/tiny.geojson", 160, 120);
    c = cam_tiny();
    c.w = 160;
    c.h = 120;
    cam = to_cam(&c);
    assert_int_equal(render_frame(f.r, &cam, &o, img, NULL, NULL), PLX_OK);
    save_png("golden-tiny", img, 160, 120);
    golden("tiny-street", img, 160, 120);
    fx_close(&f);
    /* eixample street, exposure 0.25 */
    fx_open(&f, "fixtures/eixample-4x4.geojson", 160, 120);
    c = cam_eixample();
    c.w = 160;
    c.h = 120;
    cam = to_cam(&c);
    o.exposure = 0.25;
    assert_int_equal(render_frame(f.r, &cam, &o, img, NULL, NULL), PLX_OK);
    save_png("golden-eixample", img, 160, 120);
    golden("eixample-street", img, 160, 120);
    /* eixample aerial with the light map */
    assert_int_equal(render_lightmap_build(f.r, 2.0, 64u << 20), PLX_OK);
    {
        render_camera air = { { 266, -150, 320 }, { 266, 300, 0 }, 55, 160, 120 };
        o.exposure = 0.5;
        o.lightmap = 1;
        assert_int_equal(render_frame(f.r, &air, &o, img, NULL, NULL), PLX_OK);
        save_png("golden-eixample-aerial", img, 160, 120);
        golden("eixample-aerial", img, 160, 120);
    }
    fx_close(&f);
    free(img);
}

/* ---- aerial view: the light map ------------------------------------------------ */

static void test_aerial_lightmap(void **state)
{
    fixture f;
    render_opts o;
    render_stats st;
    render_lightmap_info li;
    render_camera air = { { 200, -120, 260 }, { 260, 260, 0 }, 50, 0, 0 };
    int w = quick() ? 96 : 160, h = quick() ? 72 : 120;
    size_t px = (size_t)w * h, p, ground = 0, close = 0, same = 0, bld = 0;
    float *exact = malloc(3 * px * sizeof(float)), *map = malloc(3 * px * sizeof(float));
    uint8_t *a8 = malloc(3 * px), *b8 = malloc(3 * px);
    uint32_t *ids = malloc(px * sizeof *ids);
    uint64_t seed = 5;
    int i;
    double sum = 0;
    (void)state;
    air.width = w;
    air.height = h;
    fx_open(&f, "fixtures/eixample-4x4.geojson", w, h);
    render_lightmap_get(f.r, &li);
    assert_int_equal(li.built, 0);
    /* a budget too small for 1 m texels: the pitch grows to fit */
    assert_int_equal(render_lightmap_build(f.r, 1.0, (size_t)12 * 200 * 200), PLX_OK);
    render_lightmap_get(f.r, &li);
    assert_true(li.built && li.cell > 1.0 && li.bytes <= (size_t)12 * 200 * 200);
    assert_int_equal(render_lightmap_build(f.r, 0.0, 1000), PLX_E_INVALID);
    /* texels hold the exact illuminance at their centres */
    render_lightmap_get(f.r, &li);
    for (i = 0; i < 300; i++) {
        uint32_t x = (uint32_t)(rng_next(&seed) % li.nx), y = (uint32_t)(rng_next(&seed) % li.ny);
        double P[3], n[3] = { 0, 0, 1 }, E[3];
        const float *t = &li.rgb[3 * ((size_t)y * li.nx + x)];
        int k;
        P[0] = li.x0 + (x + 0.5) * li.cell;
        P[1] = li.y0 + (y + 0.5) * li.cell;
        P[2] = 0;
        ref_illuminance_rgb(f.e->sc, P, n, E);
        for (k = 0; k < 3; k++)
            assert_true(fabs(t[k] - E[k]) <= 1e-6 * fabs(E[k]) + 1e-9);
    }
    render_opts_default(&o);
    o.no_glow = 1;
    o.exposure = 0.5;
    assert_int_equal(render_frame(f.r, &air, &o, a8, exact, &st), PLX_OK);
    memcpy(ids, render_ids(f.r), px * sizeof *ids);
    o.lightmap = 1;
    assert_int_equal(render_frame(f.r, &air, &o, b8, map, &st), PLX_OK);
    save_png("aerial-exact", a8, w, h);
    save_png("aerial-map", b8, w, h);
    assert_memory_equal(ids, render_ids(f.r), px * sizeof *ids);
    for (p = 0; p < px; p++) {
        int k, d = 0;
        for (k = 0; k < 3; k++)
            d = abs((int)a8[3 * p + k] - (int)b8[3 * p + k]) > d ? abs((int)a8[3 * p + k] - (int)b8[3 * p + k]) : d;
        if (ids[p] == MESH_SURF_GROUND) {
            ground++;
            close += d <= 6;
            sum += d;
        } else {
            /* facades and roofs are shaded exactly either way */
            bld++;
            same += memcmp(&exact[3 * p], &map[3 * p], 3 * sizeof(float)) == 0;
        }
    }
    print_message("aerial: light map %u x %u at %.2f m; %zu ground px, %.2f %% within 6/255, mean diff %.2f/255; "
                  "%zu building px identical of %zu\n", li.nx, li.ny, li.cell, ground, 100.0 * close / ground,
                  sum / ground, same, bld);
    assert_true(ground > px / 4);
    assert_int_equal(same, bld);
    assert_true(close >= (size_t)(0.9 * ground));
    assert_true(sum / ground < 2.0);
    fx_close(&f);
    free(exact);
    free(map);
    free(a8);
    free(b8);
    free(ids);
}

/* ---- errors, glows, memory --------------------------------------------------- */

static void test_errors_and_glow(void **state)
{
    fixture f;
    render_camera c = { { -18, -22, 9 }, { 32, 10, 2 }, 60, 64, 48 };
    render_camera bad;
    render_opts o;
    render_stats st;
    uint8_t a[64 * 48 * 3], b[64 * 48 * 3];
    float fa[64 * 48 * 3];
    size_t p, diff = 0;
    (void)state;
    fx_open(&f, "fixtures/tiny.geojson", 64, 48);
    render_opts_default(&o);
    bad = c;
    bad.eye[2] = 0;
    assert_int_equal(render_frame(f.r, &bad, &o, a, NULL, NULL), PLX_E_INVALID);
    assert_string_equal(render_error(f.r), "render_frame: the eye must be above the ground (z > 0)");
    bad = c;
    memcpy(bad.target, bad.eye, sizeof bad.eye);
    assert_int_equal(render_frame(f.r, &bad, &o, a, NULL, NULL), PLX_E_INVALID);
    assert_string_equal(render_error(f.r), "render_frame: eye and target are the same point");
    bad = c;
    bad.fov_deg = 180;
    assert_int_equal(render_frame(f.r, &bad, &o, a, NULL, NULL), PLX_E_INVALID);
    bad = c;
    bad.width = 65;
    assert_int_equal(render_frame(f.r, &bad, &o, a, NULL, NULL), PLX_E_INVALID);
    bad = c;
    bad.eye[0] = NAN;
    assert_int_equal(render_frame(f.r, &bad, &o, a, NULL, NULL), PLX_E_INVALID);
    assert_int_equal(render_frame(f.r, NULL, &o, a, NULL, NULL), PLX_E_INVALID);
    /* straight down works (right = +x) */
    bad = c;
    bad.eye[0] = bad.target[0] = 30;
    bad.eye[1] = bad.target[1] = 10;
    bad.eye[2] = 80;
    bad.target[2] = 0;
    assert_int_equal(render_frame(f.r, &bad, &o, a, NULL, &st), PLX_OK);
    assert_string_equal(render_error(f.r), "");
    assert_true(st.building_pixels > 0 && st.ground_pixels > 0);
    /* glows: only near lamps, only adding light; none with no_glow */
    assert_int_equal(render_frame(f.r, &c, &o, a, fa, &st), PLX_OK);
    assert_true(st.glows >= 1);
    o.no_glow = 1;
    assert_int_equal(render_frame(f.r, &c, &o, b, NULL, &st), PLX_OK);
    assert_int_equal(st.glows, 0);
    for (p = 0; p < sizeof a; p++) {
        assert_true(a[p] >= b[p]);
        diff += a[p] != b[p];
    }
    assert_true(diff > 0 && diff < sizeof a / 10);
    /* the float output is the radiance before tone mapping */
    for (p = 0; p < sizeof a; p++)
        assert_int_equal(a[p], render_srgb8(f.r, fa[p]));
    /* sRGB table: exact at the ends and monotonic */
    assert_int_equal(render_srgb8(f.r, 0.0), 0);
    assert_int_equal(render_srgb8(f.r, -1.0), 0);
    assert_int_equal(render_srgb8(f.r, NAN), 0);
    assert_int_equal(render_srgb8(f.r, 1.0), 255);
    assert_int_equal(render_srgb8(f.r, 0.5), ref_srgb8(0.5));
    assert_int_equal(render_srgb8(f.r, 0.001), ref_srgb8(0.001));
    fx_close(&f);
}

static void test_eye_inside_solid(void **state)
{
    fixture f;
    render_camera c = { { 5, 5, 5 }, { 15, 6, 5 }, 70, 64, 48 };
    render_stats st;
    uint8_t a[64 * 48 * 3];
    (void)state;
    fx_open(&f, "fixtures/tiny.geojson", 64, 48);
    assert_int_equal(render_frame(f.r, &c, NULL, a, NULL, &st), PLX_OK);
    assert_int_equal(st.eye_inside, 1);
    assert_int_equal(st.occlusion_culled, 0);
    assert_int_equal(st.sky_pixels + st.ground_pixels, 0); /* walls all round */
    fx_close(&f);
}

static void test_fault_injection(void **state)
{
    void *mem;
    plx_engine *e = open_scene("fixtures/eixample-4x4.geojson", &mem);
    plx_memory_report before, after;
    render *r = NULL;
    plx_status st = PLX_E_NOMEM;
    uint64_t k;
    (void)state;
    plx_memory_get(e, &before);
    for (k = 1; st == PLX_E_NOMEM; k++) {
        plx_debug_fail_alloc(e, k);
        st = render_create(&e->mem, e->sc, 64, 48, pos_shade, NULL, &r);
        if (st == PLX_E_NOMEM) {
            plx_memory_get(e, &after);
            assert_int_equal(after.used_total, before.used_total);
            assert_null(r);
        }
    }
    plx_debug_fail_alloc(e, 0);
    assert_int_equal(st, PLX_OK);
    assert_true(k > 10);
    plx_memory_get(e, &after);
    print_message("render_create on eixample-4x4, 64x48: %zu bytes in part frame, %llu requests tried\n",
                  after.used[PLX_PART_FRAME] - before.used[PLX_PART_FRAME], (unsigned long long)k - 1);
    /* the frame itself allocates nothing */
    {
        render_camera c = { { 131, 40, 1.7 }, { 160, 300, 8 }, 60, 64, 48 };
        plx_debug_fail_alloc(e, 1);
        assert_int_equal(render_frame(r, &c, NULL, NULL, NULL, NULL), PLX_OK);
        assert_int_equal(plx_debug_fail_alloc(e, 0), 0);
    }
    plx_engine_destroy(e);
    free(mem);
}

/* Automatic exposure against brute force: on random images (sky pixels,
 * black, NaN and infinite pixels among them, luminances over 40 stops)
 * the lit pixel at the rule's percentile of the sorted luminances
 * (ref_exposure.h, the independent answer) is mapped
 * to within an eighth of a stop below the key; counting the pixels in
 * random parts and summing gives the same exposure (what the frame's
 * workers do). */
static void test_exposure_parts(void **state)
{
    enum { N = 20000 };
    float *lin = malloc(sizeof *lin * 3 * N);
    uint32_t *id = malloc(sizeof *id * N), hist[EXPOSURE_BINS], hist2[EXPOSURE_BINS];
    double *y = malloc(sizeof *y * N);
    exposure_table *et = malloc(sizeof *et);
    uint64_t seed = 7;
    int round;
    (void)state;
    assert_true(lin && id && y && et);
    exposure_table_init(et);
    for (round = 0; round < 40; round++) {
        size_t p, n = 0, cut[8];
        double e, yp;
        int k;
        for (p = 0; p < N; p++) {
            int c;
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            id[p] = (seed >> 60) == 0 ? EXPOSURE_SKY : 1u + (uint32_t)(seed >> 40) % 50u;
            for (c = 0; c < 3; c++) {
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                lin[3 * p + c] = (seed >> 59) == 0 ? 0.0f : (float)exp2(((double)(seed >> 11) / 9007199254740992.0) * 40.0 - 20.0 + round % 5);
            }
            if (p % 997 == 0)
                lin[3 * p] = (p / 997) % 2 ? NAN : INFINITY;
            {
                double Y = 0.2126 * lin[3 * p] + 0.7152 * lin[3 * p + 1] + 0.0722 * lin[3 * p + 2];
                if (id[p] != EXPOSURE_SKY && Y > 0.0 && isfinite(Y))
                    y[n++] = Y;
            }
        }
        e = exposure_auto(lin, id, N);
        yp = ref_exposure_luminance(y, n);
        assert_true(yp * e <= EXPOSURE_KEY * (1.0 + 1e-12));
        assert_true(yp * e > EXPOSURE_KEY * exp2(-0.125) * (1.0 - 1e-12));
        cut[0] = 0;
        cut[7] = N;
        for (k = 1; k < 7; k++) {
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            cut[k] = cut[k - 1] + (size_t)(seed >> 33) % (N - cut[k - 1] + 1) / 2;
        }
        memset(hist, 0, sizeof hist);
        for (k = 0; k < 7; k++)
            exposure_count(lin, id, cut[k], cut[k + 1], hist);
        assert_true(exposure_from(hist) == e);
        /* the table's counts (what frames use) are the same */
        memset(hist2, 0, sizeof hist2);
        for (k = 0; k < 7; k++)
            exposure_count_table(et, lin, id, cut[k], cut[k + 1], hist2);
        assert_memory_equal(hist, hist2, sizeof hist);
    }
    free(lin);
    free(id);
    free(y);
    free(et);
}


/* The dim pixels left out: a view's lit pixels (1,000 at 1 to 8 cd/m^2)
 * with any number of pixels 13 stops or more below them (what a
 * per-pixel gather gives where the atlas's photon charts give 0: the
 * whole-city aerial view of gen eixample 30 30 had 212,631 at a median of
 * 3.5e-4 beside 214,806 lit, and its exposure moved from 0.081 to 0.177)
 * choose the exposure of the lit pixels alone; pixels within 12 stops
 * count. */
static void test_exposure_dim_pixels(void **state)
{
    enum { LIT = 1000, DIM = 40000 };
    uint32_t hist[EXPOSURE_BINS];
    double alone, with, *y = malloc(sizeof *y * (LIT + DIM));
    size_t k;
    (void)state;
    assert_non_null(y);
    memset(hist, 0, sizeof hist);
    for (k = 0; k < LIT; k++)
        hist[exposure_bin(exp2(3.0 * (double)k / LIT))]++;
    alone = exposure_from(hist);
    for (k = 0; k < DIM; k++)
        hist[exposure_bin(exp2(-13.0 - 10.0 * (double)k / DIM))]++;
    with = exposure_from(hist);
    assert_true(with == alone);
    for (k = 0; k < LIT; k++)
        y[k] = exp2(3.0 * (double)k / LIT);
    assert_true(ref_exposure_luminance(y, LIT) * alone <= EXPOSURE_KEY * (1.0 + 1e-12));
    /* 40,000 pixels 11 stops below count: the percentile's rank moves
     * (0.5% of 41,000 is 205 from the top, not 5), and the exposure
     * rises */
    memset(hist, 0, sizeof hist);
    for (k = 0; k < LIT; k++)
        hist[exposure_bin(exp2(3.0 * (double)k / LIT))]++;
    for (k = 0; k < DIM; k++)
        hist[exposure_bin(exp2(-8.0 - 0.5 * (double)k / DIM))]++;
    for (k = 0; k < LIT + DIM; k++)
        y[k] = k < LIT ? exp2(3.0 * (double)k / LIT) : exp2(-8.0 - 0.5 * (double)(k - LIT) / DIM);
    with = exposure_from(hist);
    {
        double yp = ref_exposure_luminance(y, LIT + DIM);
        assert_true(yp * with <= EXPOSURE_KEY * (1.0 + 1e-12));
        assert_true(yp * with > EXPOSURE_KEY * exp2(-0.125) * (1.0 - 1e-12));
        assert_true(with > alone * exp2(0.375)); /* 4 eighths: 2^2.99 to 2^2.39 */
    }
    free(y);
}

/* A walk's held exposure (exposure_hold), on every pair of exposure_from's
 * exposures 2^(32 - (b + 1) / 8), b in 0 .. 511, written here from the
 * formula: within half a stop (4 eighths) of the image's own choice the
 * held one stays, bit for bit; farther, it moves to the band's edge, or
 * by the step when one is given and the edge is farther (EXPOSURE_FALL
 * steps when the exposure falls), on the held one's side; and a frame
 * that reached the band, drawn again with its own exposure as the held
 * one, keeps it.
 * A held exposure off the steps counts as its nearest step. */
static void test_exposure_hold(void **state)
{
    int bh, bc, step;
    (void)state;
    for (step = 0; step <= 4; step += step ? 3 : 1) /* no limit, an eighth and half a stop a frame */
        for (bh = 0; bh < EXPOSURE_BINS; bh += 3)
            for (bc = 0; bc < EXPOSURE_BINS; bc++) {
                double h = exp2(32.0 - (bh + 1) / 8.0), c = exp2(32.0 - (bc + 1) / 8.0);
                double a = exposure_hold(h, c, step);
                int most = bc > bh ? EXPOSURE_FALL * step : step; /* falls faster than it rises */
                int out = abs(bc - bh) - EXPOSURE_HOLD, moved = step > 0 && out > most ? most : out;
                if (out <= 0) {
                    assert_true(a == h);
                } else {
                    double eighths = log2(h / a) * 8.0; /* + when the bin grew */
                    assert_true(fabs(eighths - (bc > bh ? moved : -moved)) < 1e-9);
                    assert_true((a - c) * (h - c) > 0.0);                     /* on the held one's side */
                    assert_true(fabs(log2(a / c)) * 8.0 > EXPOSURE_HOLD - 1e-9); /* not past the band */
                }
                if (moved == out) /* reached the band: drawn again, kept */
                    assert_true(exposure_hold(a, c, step) == a);
                assert_true(exposure_hold(h * 1.01, c, step) == (out <= 0 ? h * 1.01 : a));
            }
    {
        /* the cap: a frame darker than 2^-10 (about 0.001 cd/m^2) at its
         * percentile is exposed at most EXPOSURE_MAX; just above, less */
        uint32_t hist[EXPOSURE_BINS];
        memset(hist, 0, sizeof hist);
        hist[0] = 10;
        assert_true(exposure_from(hist) == EXPOSURE_MAX && EXPOSURE_MAX == PLX_EXPOSURE_MAX);
        hist[0] = 0;
        hist[EXPOSURE_MAX_BIN] = 10;
        assert_true(exposure_from(hist) == EXPOSURE_MAX);
        hist[EXPOSURE_MAX_BIN] = 0;
        hist[EXPOSURE_MAX_BIN + 1] = 10;
        assert_true(exposure_from(hist) == EXPOSURE_MAX * exp2(-0.125));
        assert_true(exposure_bin(1.0 / EXPOSURE_MAX) == EXPOSURE_MAX_BIN + 1);
    }
    assert_true(exposure_hold(0.0, 0.25, 0) == 0.25); /* nothing held: the choice */
    assert_true(exposure_hold(NAN, 0.25, 4) == 0.25);
}

/* The exposure's table of bin thresholds gives exposure_bin's bin for
 * every luminance tried (exposure_table_bin): 2,000 doubles each side of
 * every threshold, a million spread log-uniformly over 2^-45 .. 2^45
 * through exposure_count_table, and the extremes; and no hint's cell
 * holds more thresholds than exposure_table_bin's one step can pass. */
static void test_exposure_table(void **state)
{
    exposure_table *et = malloc(sizeof *et);
    static const double extreme[] = { 4.9406564584124654e-324, 2.2250738585072014e-308, 1e-300, 1e-20,
                                      0x1p-32, 0x1p32, 1e20, 1e300, 1.7976931348623157e308 };
    uint64_t seed = 77;
    uint32_t h1[EXPOSURE_BINS], h2[EXPOSURE_BINS];
    float lin[3];
    uint32_t id = 1;
    size_t i;
    int k, d;
    (void)state;
    assert_non_null(et);
    exposure_table_init(et);
    for (k = 1; k < EXPOSURE_BINS; k++) {
        uint64_t t;
        memcpy(&t, &et->t[k], sizeof t);
        assert_true(exposure_bin(et->t[k]) >= k);
        assert_true(exposure_bin(double_of_bits(t - 1)) < k);
        for (d = -2000; d <= 2000; d++) {
            double y = double_of_bits(t + (uint64_t)(int64_t)d);
            int b = exposure_table_bin(et, y);
            if (b != exposure_bin(y))
                fail_msg("y %.17g: table bin %d, exposure_bin %d", y, b, exposure_bin(y));
        }
    }
    /* the counting's one step from the hint reaches every bin: a hint's
     * cell of doubles holds at most EXPOSURE_HINT_STEPS thresholds past
     * its first double */
    {
        int most = 0, in_cell = 0;
        uint64_t cell = UINT64_MAX;
        for (k = 1; k < EXPOSURE_BINS; k++) {
            uint64_t t;
            memcpy(&t, &et->t[k], sizeof t);
            if (t >> 49 != cell) {
                cell = t >> 49;
                in_cell = 0;
            }
            in_cell += (t & ((1ull << 49) - 1)) != 0;
            most = in_cell > most ? in_cell : most;
        }
        printf("exposure table: at most %d threshold(s) in a hint's cell (the counting takes %d step(s))\n", most,
               EXPOSURE_HINT_STEPS);
        assert_true(most <= EXPOSURE_HINT_STEPS);
    }
    /* through exposure_count_table itself: luminances of grey pixels */
    for (i = 0; i < 1000000 + sizeof extreme / sizeof extreme[0]; i++) {
        double y;
        if (i < 1000000) {
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            lin[0] = lin[1] = lin[2] = (float)exp2(((double)(seed >> 11) / 9007199254740992.0) * 90.0 - 45.0);
        } else
            lin[0] = lin[1] = lin[2] = (float)extreme[i - 1000000];
        y = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2];
        memset(h1, 0, sizeof h1);
        memset(h2, 0, sizeof h2);
        exposure_count(lin, &id, 0, 1, h1);
        exposure_count_table(et, lin, &id, 0, 1, h2);
        if (memcmp(h1, h2, sizeof h1) != 0)
            fail_msg("luminance %.17g: the table counts another bin", y);
    }
    free(et);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tiny_vs_ref),
        cmocka_unit_test(test_eixample_vs_ref),
        cmocka_unit_test(test_helsinki_vs_ref),
        cmocka_unit_test(test_backends_agree),
        cmocka_unit_test(test_tiled_light_same), cmocka_unit_test(test_tiled_light_wrapping_sector),
        cmocka_unit_test(test_sparse_indirect),
        cmocka_unit_test(test_exposure_table),
        cmocka_unit_test(test_cull_equal_street),
        cmocka_unit_test(test_cull_equal_above_roofs),
        cmocka_unit_test(test_cull_equal_high),
        cmocka_unit_test(test_cull_groups),
        cmocka_unit_test(test_cull_over_low_roof),
        cmocka_unit_test(test_cull_kept_edge),
        cmocka_unit_test(test_far_plane_follows_eye),
        cmocka_unit_test(test_mesh_fixtures),
        cmocka_unit_test(test_mesh_awkward),
        cmocka_unit_test(test_golden),
        cmocka_unit_test(test_aerial_lightmap),
        cmocka_unit_test(test_errors_and_glow),
        cmocka_unit_test(test_eye_inside_solid),
        cmocka_unit_test(test_fault_injection),
        cmocka_unit_test(test_exposure_parts),
        cmocka_unit_test(test_exposure_dim_pixels),
        cmocka_unit_test(test_exposure_hold),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
