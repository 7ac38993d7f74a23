/* lampmerge: lamps at one spot merged into one (README, "Duplicate lamps").
 *
 * Lamps with the same x, y, z (exactly, after projection) and the same
 * radius R light every point identically up to their intensity and colour:
 * SPEC §2's term is I·cos/d²·W(d/R) with the same V, d and W, and an image
 * weights it by colour per channel. So they become one lamp with
 *   I = Σ I_k,   colour = Σ I_k·colour_k / I   (per channel),
 * which gives the same scalar illuminance, the same per-channel image
 * radiance and the same photon flux per channel. The merged lamp is the
 * group's first lamp in file order (its feature and id). Lamps at one spot
 * with different radii are kept apart: their falloff differs, and each costs
 * a lamp. A group whose intensities are all 0 keeps the first colour.
 * Sorting the lamps makes this O(n log n); a warning names each of the first
 * LAMPMERGE_WARN groups, then one line counts the rest. */
#include <float.h>
#include <string.h>

#include "base/msort.h"
#include "base/strbuf.h"
#include "scene/lampmerge.h"

#define LAMPMERGE_WARN 10

static int lamp_before(const uint32_t *a, const uint32_t *b, const scene_lamp *l)
{
    const scene_lamp *p = &l[*a], *q = &l[*b];
    if (p->x != q->x)
        return p->x < q->x;
    if (p->y != q->y)
        return p->y < q->y;
    if (p->z != q->z)
        return p->z < q->z;
    if (p->radius != q->radius)
        return p->radius < q->radius;
    return *a < *b;
}

MSORT_DEFINE(lamp_sort, uint32_t, const scene_lamp *, lamp_before)

static int same_spot(const scene_lamp *p, const scene_lamp *q)
{
    return p->x == q->x && p->y == q->y && p->z == q->z && p->radius == q->radius;
}

/* Merges lamps order[i0 .. i1-1] into the first of them; marks the others.
 * Returns -1 (nothing changed) when their intensities add up beyond the
 * largest double. */
static int merge_group(scene_lamp *l, const uint32_t *order, uint32_t i0, uint32_t i1, uint8_t *gone)
{
    scene_lamp *m = &l[order[i0]];
    double sum = 0, c[3] = { 0, 0, 0 };
    uint32_t i;
    int k;
    for (i = i0; i < i1; i++)
        sum += l[order[i]].intensity;
    if (!(sum <= DBL_MAX))
        return -1;
    for (i = i0; i < i1; i++) {
        const scene_lamp *p = &l[order[i]];
        for (k = 0; k < 3; k++)
            c[k] += sum > 0 ? p->intensity / sum * (double)p->color[k] : 0.0;
        if (i > i0)
            gone[order[i]] = 1;
    }
    if (sum > 0)
        for (k = 0; k < 3; k++)
            m->color[k] = (float)c[k];
    m->intensity = sum;
    return 0;
}

/* "N lamps at one spot (x, y, z)" */
static void spot_words(strbuf *b, const scene_lamp *m, uint32_t n)
{
    sb_uint(b, n);
    sb_str(b, " lamps at one spot (");
    sb_num(b, m->x, 10);
    sb_str(b, ", ");
    sb_num(b, m->y, 10);
    sb_str(b, ", ");
    sb_num(b, m->z, 10);
    sb_str(b, ")");
}

/* A group whose intensities overflow: a bad feature (the first lamp's);
 * without --strict every lamp of the group is dropped. */
static plx_status drop_group(loader *ld, scene *s, const uint32_t *order, uint32_t i0, uint32_t i1, uint8_t *gone)
{
    const scene_lamp *m = &s->lamps[order[i0]];
    char why[200];
    strbuf b;
    uint32_t i;
    plx_status st;
    sb_init(&b, why, sizeof why);
    spot_words(&b, m, i1 - i0);
    sb_str(&b, ": their intensities add up beyond the largest number; the lamps are dropped");
    st = ld_bad_feature(ld, m->feature, m->id, why);
    if (st != PLX_OK)
        return st;
    s->skipped_features += i1 - i0 - 1;
    for (i = i0; i < i1; i++)
        gone[order[i]] = 1;
    return PLX_OK;
}

static void warn_group(loader *ld, const scene_lamp *m, uint32_t n)
{
    char why[200];
    strbuf b;
    sb_init(&b, why, sizeof why);
    spot_words(&b, m, n);
    sb_str(&b, " merged into this one: ");
    sb_num(&b, m->intensity, 10);
    sb_str(&b, " cd");
    ld_warn(ld, m->feature, m->id, why);
}

static void warn_rest(loader *ld, uint32_t groups, uint32_t lamps)
{
    char why[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, why, sizeof why);
    if (ld->name) {
        sb_str(&b, ld->name);
        sb_str(&b, ": ");
    }
    sb_str(&b, "and ");
    sb_uint(&b, groups);
    sb_str(&b, " more spots with duplicate lamps (");
    sb_uint(&b, lamps);
    sb_str(&b, " lamps) merged the same way");
    eng_warn(ld->e, why);
}

plx_status ld_merge_duplicate_lamps(loader *ld)
{
    scene *s = ld->s;
    arena_mark mark = arena_get_mark(ld->mem);
    uint32_t n = s->nlamps, i, j, kept = 0, groups = 0, rest_groups = 0, rest_lamps = 0;
    uint32_t *order, *tmp;
    uint8_t *gone;
    if (n < 2)
        return PLX_OK;
    order = arena_scratch(ld->mem, arena_mul(n, 2 * sizeof *order), 8);
    gone = arena_scratch(ld->mem, n, 1);
    if (!order || !gone) {
        arena_release(ld->mem, &mark);
        return eng_nomem(ld->e, "merging duplicate lamps");
    }
    tmp = order + n;
    for (i = 0; i < n; i++)
        order[i] = i;
    memset(gone, 0, n);
    lamp_sort(order, tmp, n, s->lamps);
    for (i = 0; i < n; i = j) {
        for (j = i + 1; j < n && same_spot(&s->lamps[order[i]], &s->lamps[order[j]]); j++)
            ;
        if (j - i < 2)
            continue;
        if (merge_group(s->lamps, order, i, j, gone) != 0) {
            plx_status st = drop_group(ld, s, order, i, j, gone);
            if (st != PLX_OK) {
                arena_release(ld->mem, &mark);
                return st;
            }
            continue;
        }
        s->merged_lamps += j - i - 1;
        if (groups++ < LAMPMERGE_WARN) {
            warn_group(ld, &s->lamps[order[i]], j - i);
        } else {
            rest_groups++;
            rest_lamps += j - i;
        }
    }
    if (rest_groups)
        warn_rest(ld, rest_groups, rest_lamps);
    for (i = 0; i < n; i++)
        if (!gone[i])
            s->lamps[kept++] = s->lamps[i];
    s->nlamps = kept;
    arena_release(ld->mem, &mark);
    return PLX_OK;
}
