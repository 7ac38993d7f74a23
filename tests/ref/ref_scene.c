/* ref_scene: plain-array scene builder for tests (see ref_scene.h). */
#include "ref_scene.h"

#include <stdlib.h>
#include <string.h>

void ref_scene_init(scene *s)
{
    memset(s, 0, sizeof *s);
    s->ground_albedo = 0.15;
}

/* Copies ring k (n pairs at xy) into out as vec2, dropping consecutive
 * duplicates and the closing vertex. Returns the number of vertices kept. */
static uint32_t clean_ring(const double *xy, uint32_t n, vec2 *out)
{
    uint32_t i, m = 0;
    for (i = 0; i < n; i++) {
        vec2 v;
        v.x = xy[2 * i];
        v.y = xy[2 * i + 1];
        if (m > 0 && out[m - 1].x == v.x && out[m - 1].y == v.y)
            continue;
        out[m++] = v;
    }
    while (m > 1 && out[m - 1].x == out[0].x && out[m - 1].y == out[0].y)
        m--;
    return m;
}

/* Twice the signed area of a ring (positive when counter-clockwise). */
static long double ring_area2(const vec2 *p, uint32_t n)
{
    long double a = 0.0L;
    uint32_t i;
    for (i = 0; i < n; i++) {
        const vec2 *u = &p[i], *v = &p[(i + 1) % n];
        a += (long double)u->x * v->y - (long double)v->x * u->y;
    }
    return a;
}

static void reverse_ring(vec2 *p, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n / 2; i++) {
        vec2 t = p[i];
        p[i] = p[n - 1 - i];
        p[n - 1 - i] = t;
    }
}

/* Grows the pts and rings arrays so that they can take 'addpts' more points
 * and 'addrings' more rings. Returns 0 or -1. */
static int grow_geometry(scene *s, uint32_t addpts, uint32_t addrings)
{
    vec2 *p = realloc(s->pts, (s->npts + addpts + 1) * sizeof *p);
    scene_ring *r;
    if (!p)
        return -1;
    s->pts = p;
    r = realloc(s->rings, (s->nrings + addrings + 1) * sizeof *r);
    if (!r)
        return -1;
    s->rings = r;
    return 0;
}

static void outer_box(const vec2 *p, uint32_t n, double box[4])
{
    uint32_t i;
    box[0] = box[2] = p[0].x;
    box[1] = box[3] = p[0].y;
    for (i = 1; i < n; i++) {
        if (p[i].x < box[0]) box[0] = p[i].x;
        if (p[i].y < box[1]) box[1] = p[i].y;
        if (p[i].x > box[2]) box[2] = p[i].x;
        if (p[i].y > box[3]) box[3] = p[i].y;
    }
}

int ref_scene_add_building(scene *s, const double *xy, const uint32_t *ring_n,
                           uint32_t nrings, double height, double min_height)
{
    uint32_t k, total = 0, np0 = s->npts, nr0 = s->nrings, off = 0;
    scene_building *nb, *b;

    if (nrings == 0)
        return -1;
    for (k = 0; k < nrings; k++)
        total += ring_n[k];
    if (grow_geometry(s, total, nrings) != 0)
        return -1;
    for (k = 0; k < nrings; k++) {
        vec2 *dst = s->pts + s->npts;
        uint32_t m = clean_ring(xy + 2 * off, ring_n[k], dst);
        long double a2 = m >= 3 ? ring_area2(dst, m) : 0.0L;
        off += ring_n[k];
        if (m < 3 || a2 == 0.0L) {
            s->npts = np0;
            s->nrings = nr0;
            return -1;
        }
        if ((k == 0) != (a2 > 0.0L))
            reverse_ring(dst, m);
        s->rings[s->nrings].first = s->npts;
        s->rings[s->nrings].count = m;
        s->nrings++;
        s->npts += m;
    }
    nb = realloc(s->bld, (s->nbld + 1) * sizeof *nb);
    if (!nb) {
        s->npts = np0;
        s->nrings = nr0;
        return -1;
    }
    s->bld = nb;
    b = &s->bld[s->nbld];
    memset(b, 0, sizeof *b);
    b->ring_first = nr0;
    b->ring_count = nrings;
    b->height = height;
    b->min_height = min_height;
    b->albedo = 0.35;
    outer_box(s->pts + s->rings[nr0].first, s->rings[nr0].count, b->box);
    b->feature = s->nbld + s->nlamps;
    b->block = UINT32_MAX;
    b->id = NULL;
    return (int)s->nbld++;
}

int ref_scene_add_box(scene *s, double x0, double y0, double x1, double y1,
                      double height, double min_height)
{
    double xy[8];
    uint32_t n = 4;
    xy[0] = x0; xy[1] = y0;
    xy[2] = x1; xy[3] = y0;
    xy[4] = x1; xy[5] = y1;
    xy[6] = x0; xy[7] = y1;
    return ref_scene_add_building(s, xy, &n, 1, height, min_height);
}

int ref_scene_add_lamp_rgb(scene *s, double x, double y, double z,
                           double intensity, double radius,
                           double r, double g, double b)
{
    scene_lamp *nl = realloc(s->lamps, (s->nlamps + 1) * sizeof *nl);
    scene_lamp *l;
    if (!nl)
        return -1;
    s->lamps = nl;
    l = &s->lamps[s->nlamps];
    memset(l, 0, sizeof *l);
    l->x = x;
    l->y = y;
    l->z = z;
    l->intensity = intensity;
    l->radius = radius;
    l->color[0] = (float)r;
    l->color[1] = (float)g;
    l->color[2] = (float)b;
    l->feature = s->nbld + s->nlamps;
    l->id = NULL;
    return (int)s->nlamps++;
}

int ref_scene_add_lamp(scene *s, double x, double y, double z,
                       double intensity, double radius)
{
    return ref_scene_add_lamp_rgb(s, x, y, z, intensity, radius, 1.0, 0.62, 0.28);
}

static void box_add(double box[4], int *empty, double x, double y)
{
    if (*empty || x < box[0]) box[0] = x;
    if (*empty || y < box[1]) box[1] = y;
    if (*empty || x > box[2]) box[2] = x;
    if (*empty || y > box[3]) box[3] = y;
    *empty = 0;
}

void ref_scene_finish(scene *s)
{
    double box[4] = { 0.0, 0.0, 0.0, 0.0 };
    int empty = 1;
    uint32_t i;
    for (i = 0; i < s->nbld; i++) {
        box_add(box, &empty, s->bld[i].box[0], s->bld[i].box[1]);
        box_add(box, &empty, s->bld[i].box[2], s->bld[i].box[3]);
    }
    for (i = 0; s->nbld == 0 && i < s->nlamps; i++)
        box_add(box, &empty, s->lamps[i].x, s->lamps[i].y);
    s->bounds[0] = box[0] - 50.0;
    s->bounds[1] = box[1] - 50.0;
    s->bounds[2] = box[2] + 50.0;
    s->bounds[3] = box[3] + 50.0;
}

void ref_scene_free(scene *s)
{
    free(s->pts);
    free(s->rings);
    free(s->bld);
    free(s->lamps);
    ref_scene_init(s);
}

/* Where q lies relative to one ring: REF_IN, REF_ON or REF_OUT (even-odd
 * crossing count, after an explicit on-edge test). */
static int ring_where(const vec2 *p, uint32_t n, long double x, long double y)
{
    uint32_t i;
    int inside = 0;
    for (i = 0; i < n; i++) {
        long double ax = p[i].x, ay = p[i].y;
        long double bx = p[(i + 1) % n].x, by = p[(i + 1) % n].y;
        long double cr = (bx - ax) * (y - ay) - (by - ay) * (x - ax);
        if (cr == 0.0L &&
            x >= (ax < bx ? ax : bx) && x <= (ax < bx ? bx : ax) &&
            y >= (ay < by ? ay : by) && y <= (ay < by ? by : ay))
            return REF_ON;
        if ((ay > y) != (by > y)) {
            long double xc = ax + (y - ay) * (bx - ax) / (by - ay);
            if (x < xc)
                inside = !inside;
        }
    }
    return inside ? REF_IN : REF_OUT;
}

int ref_footprint_where(const scene *s, uint32_t b, long double x, long double y)
{
    const scene_building *bd = &s->bld[b];
    uint32_t k;
    const scene_ring *r = &s->rings[bd->ring_first];
    int w = ring_where(s->pts + r->first, r->count, x, y);
    if (w != REF_IN)
        return w;
    for (k = 1; k < bd->ring_count; k++) {
        r = &s->rings[bd->ring_first + k];
        w = ring_where(s->pts + r->first, r->count, x, y);
        if (w == REF_IN)
            return REF_OUT;
        if (w == REF_ON)
            return REF_ON;
    }
    return REF_IN;
}
