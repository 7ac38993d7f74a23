/* lamplayer: lamps added to a loaded scene from another source (lamp layers,
 * plx_add_lamps). The new lamps are checked as at load (position in range,
 * z, intensity and radius in range, not inside a building's solid), put in
 * the scene's frame (lon/lat projected with the scene's own centre) and
 * merged with lamps at the same ground position (within LAYER_SAME_M): the
 * first lamp there is kept, the later ones are left out with a warning
 * (neither they nor lamps out of range count in skipped_lamps, which
 * counts lamps inside buildings). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/engine.h"
#include "base/strbuf.h"
#include "base/lonlat.h"
#include "scene/features.h"
#include "scene/photometry.h"

#define LAYER_MAX_COORD 1.0e7
#define LAYER_MAX_HEIGHT 1000.0
#define LAYER_MAX_RADIUS 1.0e5
#define LAYER_SAME_M 1.0e-3   /* lamps closer than this on the ground are one */
#define LAYER_MARGIN 50.0     /* Bounds margin, as at load */

static void layer_where(strbuf *b, const char *source, const plx_lamp *l, uint32_t k)
{
    if (source) {
        sb_str(b, source);
        sb_str(b, ": ");
    }
    sb_str(b, "feature ");
    sb_uint(b, l ? l->feature : k);
    if (l && l->id) {
        sb_str(b, " (");
        sb_strn(b, l->id, 80);
        sb_char(b, ')');
    }
    sb_str(b, ": ");
}

/* Warns, or fails in strict mode; PLX_OK means leave the lamp out and go on. */
static plx_status layer_skip(plx_engine *e, const char *source, const plx_lamp *l, const char *why, int count)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    layer_where(&b, source, l, 0);
    sb_str(&b, why);
    if (e->cfg.strict)
        return eng_fail(e, PLX_E_SCENE, msg);
    if (!strstr(why, "left out")) /* as the scene's skipped features say */
        sb_str(&b, "; left out");
    if (count)
        e->sc->skipped_lamps++;
    e->warnings++;
    eng_log(e, PLX_LOG_WARN, msg);
    return PLX_OK;
}

/* The lamp in scene metres; NULL when fine, else why it is left out. */
static const char *layer_lamp(const scene *s, const plx_lamp *in, scene_lamp *out)
{
    double x = in->x, y = in->y;
    int k;
    if (!isfinite(x) || !isfinite(y))
        return "position is not finite";
    if (s->lonlat) {
        if (fabs(x) > 180.0 || fabs(y) > 90.0)
            return "position is not lon/lat (the scene is in lon/lat)";
        lonlat_to_local(s->lon0, s->lat0, lonlat_cos(s->lat0), &x, &y);
    }
    if (fabs(x) > LAYER_MAX_COORD || fabs(y) > LAYER_MAX_COORD)
        return "position is out of range (|coordinate| > 1e7 m)";
    if (!isfinite(in->z) || in->z < 0.0 || in->z > LAYER_MAX_HEIGHT)
        return "z is out of range (0 to 1000 m)";
    if (!(in->intensity >= 0.0 && in->intensity <= PHOTOMETRY_MAX_CD))
        return "intensity is negative, not finite or above 1e12 cd";
    if (!isfinite(in->radius) || !(in->radius > 0.0) || in->radius > LAYER_MAX_RADIUS)
        return "radius is out of range (> 0 and <= 100000 m)";
    for (k = 0; k < 3; k++)
        if (!isfinite(in->color[k]) || in->color[k] < 0.0f)
            return "color is negative or not finite";
    memset(out, 0, sizeof *out);
    out->x = x;
    out->y = y;
    out->z = in->z;
    out->intensity = in->intensity;
    out->radius = in->radius;
    memcpy(out->color, in->color, sizeof out->color);
    out->feature = in->feature;
    return NULL;
}

static const char *copy_text(plx_engine *e, const char *t)
{
    size_t n = strlen(t) + 1;
    char *c = arena_alloc(&e->mem, PLX_PART_SCENE, n, 1);
    if (c)
        memcpy(c, t, n);
    return c;
}

/* ---- same position -------------------------------------------------------- */

typedef struct lamp_key {
    double x, y;
    uint32_t i;
} lamp_key;

static int cmp_key(const void *a, const void *b)
{
    const lamp_key *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    return (p->i > q->i) - (p->i < q->i);
}

/* Marks in 'drop' every lamp from 'first' on that lies within LAYER_SAME_M
 * of a lamp of lower index (which is kept); 'keep_of' gets that lamp. */
static plx_status find_same(plx_engine *e, uint32_t first, uint8_t *drop, uint32_t *keep_of)
{
    const scene *s = e->sc;
    uint32_t n = s->nlamps, i, j;
    lamp_key *k = arena_scratch(&e->mem, arena_mul(n, sizeof *k), 8);
    if (!k)
        return eng_nomem(e, "merging lamps at the same position");
    for (i = 0; i < n; i++) {
        k[i].x = s->lamps[i].x;
        k[i].y = s->lamps[i].y;
        k[i].i = i;
    }
    qsort(k, n, sizeof *k, cmp_key);
    for (i = 0; i < n; i++) {
        for (j = i + 1; j < n && k[j].x - k[i].x <= LAYER_SAME_M; j++) {
            uint32_t lo = k[i].i < k[j].i ? k[i].i : k[j].i, hi = k[i].i ^ k[j].i ^ lo;
            if (hi < first || drop[hi] || drop[lo] || fabs(k[j].y - k[i].y) > LAYER_SAME_M)
                continue;
            drop[hi] = 1;
            keep_of[hi] = lo;
        }
    }
    return PLX_OK;
}

static plx_status merge_same(plx_engine *e, const char *source, uint32_t first)
{
    scene *s = e->sc;
    arena_mark m = arena_get_mark(&e->mem);
    uint8_t *drop = arena_scratch(&e->mem, s->nlamps + 1u, 1);
    uint32_t *keep_of = arena_scratch(&e->mem, arena_mul(s->nlamps + 1u, sizeof *keep_of), 4);
    uint32_t i, kept = first;
    plx_status st;
    if (!drop || !keep_of) {
        arena_release(&e->mem, &m);
        return eng_nomem(e, "merging lamps at the same position");
    }
    memset(drop, 0, s->nlamps + 1u);
    st = find_same(e, first, drop, keep_of);
    for (i = first; st == PLX_OK && i < s->nlamps; i++) {
        char msg[ENGINE_ERR_BYTES];
        strbuf b;
        plx_lamp l;
        if (!drop[i]) {
            s->lamps[kept++] = s->lamps[i];
            continue;
        }
        memset(&l, 0, sizeof l);
        l.feature = s->lamps[i].feature;
        l.id = s->lamps[i].id;
        sb_init(&b, msg, sizeof msg);
        if (keep_of[i] < first) {
            sb_str(&b, "at the same position as lamp ");
            sb_uint(&b, keep_of[i]);
        } else {
            sb_str(&b, "at the same position as the added lamp ");
            sb_uint(&b, s->lamps[keep_of[i]].feature);
        }
        if (s->lamps[keep_of[i]].id) {
            sb_str(&b, " (");
            sb_strn(&b, s->lamps[keep_of[i]].id, 80);
            sb_char(&b, ')');
        }
        sb_str(&b, "; merged into it (the first is kept, this one left out)");
        st = layer_skip(e, source, &l, msg, 0);
    }
    if (st == PLX_OK)
        s->nlamps = kept;
    arena_release(&e->mem, &m);
    return st;
}

/* ---- the call -------------------------------------------------------------- */

static void lamps_bounds(scene *s)
{
    double b[4] = { 1e300, 1e300, -1e300, -1e300 };
    uint32_t i;
    if (s->nbld > 0 || s->nlamps == 0)
        return;
    for (i = 0; i < s->nlamps; i++) {
        b[0] = fmin(b[0], s->lamps[i].x);
        b[1] = fmin(b[1], s->lamps[i].y);
        b[2] = fmax(b[2], s->lamps[i].x);
        b[3] = fmax(b[3], s->lamps[i].y);
    }
    s->bounds[0] = b[0] - LAYER_MARGIN;
    s->bounds[1] = b[1] - LAYER_MARGIN;
    s->bounds[2] = b[2] + LAYER_MARGIN;
    s->bounds[3] = b[3] + LAYER_MARGIN;
}

/* Appends the valid lamps of 'in' to a new lamp array of the scene. */
static plx_status append(plx_engine *e, const char *source, const plx_lamp *in, uint32_t n)
{
    scene *s = e->sc;
    scene_lamp *all;
    uint32_t k, old = s->nlamps;
    if ((uint64_t)old + n > 0xfffffff0u)
        return eng_fail(e, PLX_E_INVALID, "plx_add_lamps: more than 4e9 lamps");
    all = arena_alloc(&e->mem, PLX_PART_SCENE, arena_mul((size_t)old + n + 1u, sizeof *all), 16);
    if (!all)
        return eng_nomem(e, "adding lamps");
    memcpy(all, s->lamps, sizeof *all * old);
    s->lamps = all;
    for (k = 0; k < n; k++) {
        scene_lamp *l = &all[s->nlamps];
        const char *why = layer_lamp(s, &in[k], l);
        if (why) {
            plx_status st = layer_skip(e, source, &in[k], why, 0);
            if (st != PLX_OK)
                return st;
            continue;
        }
        if (in[k].id && !(l->id = copy_text(e, in[k].id)))
            return eng_nomem(e, "copying lamp ids");
        s->nlamps++;
    }
    return PLX_OK;
}

plx_status plx_add_lamps(plx_engine *e, const plx_lamp *lamps, uint32_t n, const char *source)
{
    scene *s;
    loader ld;
    uint32_t old;
    plx_status st = eng_need(e, ENG_SCENE, "plx_add_lamps");
    if (st != PLX_OK)
        return st;
    if (n > 0 && !lamps)
        return eng_fail(e, PLX_E_INVALID, "plx_add_lamps: lamps is NULL");
    if (e->lt || e->ph || e->rd)
        return eng_fail(e, PLX_E_INVALID, "plx_add_lamps: light was already computed for this scene; "
                                          "add lamps right after loading it");
    s = e->sc;
    old = s->nlamps;
    eng_clear_error(e);
    st = append(e, source, lamps, n);
    if (st == PLX_OK) {
        memset(&ld, 0, sizeof ld);
        ld.e = e;
        ld.mem = &e->mem;
        ld.s = s;
        ld.name = source;
        st = ld_drop_buried_lamps_from(&ld, old);
    }
    if (st == PLX_OK)
        st = merge_same(e, source, old);
    if (st != PLX_OK) {
        s->nlamps = old;
        return st;
    }
    lamps_bounds(s);
    return PLX_OK;
}
