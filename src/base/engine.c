#include "base/engine.h"
#include "base/plx_assert.h"
#include <math.h>
#include <string.h>

static const char *const status_text[PLX_STATUS_COUNT] = {
    "success",
    "invalid argument",
    "out of memory",
    "input/output error",
    "malformed input (JSON, or a damaged bake file)",
    "invalid scene",
    "no scene loaded",
    "out of range",
    "not supported by this build or port",
};

static const char *const part_text[PLX_PART_COUNT] = {
    "engine", "scene", "polar", "lit", "photon", "frame", "scratch",
};

const char *plx_version(void)
{
    return PLX_VERSION_STRING;
}

const char *plx_strerror(plx_status s)
{
    if ((unsigned)s >= PLX_STATUS_COUNT)
        return "unknown status";
    return status_text[s];
}

const char *plx_part_name(plx_part p)
{
    if ((unsigned)p >= PLX_PART_COUNT)
        return "unknown";
    return part_text[p];
}

void plx_config_default(plx_config *cfg)
{
    if (cfg)
        memset(cfg, 0, sizeof *cfg);
}

int eng_ok(const plx_engine *e)
{
    return e != NULL && e->magic == ENGINE_MAGIC;
}

/* Messages are one line: control characters that came in with the input
 * (a raw newline inside an id, say) are shown as '?'. */
static void one_line(char *s)
{
    for (; *s; s++)
        if ((unsigned char)*s < 0x20 || *s == 0x7f)
            *s = '?';
}

plx_status eng_fail(plx_engine *e, plx_status s, const char *msg)
{
    strbuf b;
    if (e->err != msg) {
        sb_init(&b, e->err, sizeof e->err);
        sb_str(&b, msg);
    }
    one_line(e->err);
    return s;
}

plx_status eng_need_scene(plx_engine *e, const char *fn)
{
    char msg[128];
    strbuf b;
    if (!eng_ok(e))
        return PLX_E_INVALID;
    if (e->sc)
        return PLX_OK;
    sb_init(&b, msg, sizeof msg);
    sb_str(&b, fn);
    sb_str(&b, ": no scene is loaded");
    return eng_fail(e, PLX_E_NOSCENE, msg);
}

void eng_clear_error(plx_engine *e)
{
    e->err[0] = '\0';
}

plx_status eng_nomem(plx_engine *e, const char *during)
{
    strbuf b;
    sb_init(&b, e->err, sizeof e->err);
    sb_str(&b, "out of memory");
    if (during) {
        sb_str(&b, " while ");
        sb_str(&b, during);
    }
    sb_str(&b, ": part '");
    sb_str(&b, plx_part_name(e->mem.failed_part));
    sb_str(&b, "' asked for ");
    sb_uint(&b, e->mem.failed_size);
    sb_str(&b, " bytes");
    if (e->mem.budget[e->mem.failed_part]) {
        sb_str(&b, " (its budget is ");
        sb_uint(&b, e->mem.budget[e->mem.failed_part]);
        sb_str(&b, " bytes)");
    }
    sb_str(&b, "; ");
    sb_uint(&b, e->mem.failed_free); /* at the refusal: the step has released its memory since */
    sb_str(&b, " of ");
    sb_uint(&b, e->mem.cap);
    sb_str(&b, " bytes free");
    return PLX_E_NOMEM;
}

void eng_log(plx_engine *e, plx_log_level level, const char *msg)
{
    char line[ENGINE_ERR_BYTES];
    strbuf b;
    if (!e->port.log)
        return;
    sb_init(&b, line, sizeof line);
    sb_str(&b, msg);
    one_line(line);
    e->port.log(e->port.ctx, level, line);
}

uint64_t eng_clock(plx_engine *e)
{
    return e->port.clock_ns ? e->port.clock_ns(e->port.ctx) : 0;
}

plx_status plx_engine_create(void *mem, size_t size, const plx_config *cfg,
                             plx_engine **out)
{
    arena a;
    plx_engine *e;
    size_t i;
    if (out)
        *out = NULL;
    if (!mem || !out || size < PLX_ENGINE_MIN_BYTES)
        return PLX_E_INVALID;
    /* a frame larger than any the renderer draws (it failed at the first
     * frame, "creating the renderer failed", and the estimate took it) */
    if (cfg && (cfg->render_max_width < 0 || cfg->render_max_width > PLX_RENDER_MAX_DIM ||
                cfg->render_max_height < 0 || cfg->render_max_height > PLX_RENDER_MAX_DIM ||
                cfg->threads < 0 || cfg->threads > PLX_MAX_THREADS))
        return PLX_E_INVALID;
    memset(&a, 0, sizeof a); /* padding too: a bake saves the engine's bytes */
    arena_init(&a, mem, size);
    e = arena_alloc(&a, PLX_PART_ENGINE, sizeof *e, 16);
    if (!e)
        return PLX_E_NOMEM;
    memset(e, 0, sizeof *e);
    e->magic = ENGINE_MAGIC;
    e->block = mem;
    if (cfg)
        e->cfg = *cfg;
    else
        plx_config_default(&e->cfg);
    if (e->cfg.port)
        e->port = *e->cfg.port;
    e->cfg.port = &e->port;
    e->mem = a;
    for (i = 0; i < PLX_PART_COUNT; i++)
        e->mem.budget[i] = e->cfg.part_budget[i];
    e->base = arena_get_mark(&e->mem);
    *out = e;
    return PLX_OK;
}

void plx_engine_destroy(plx_engine *e)
{
    if (eng_ok(e))
        e->magic = 0;
}

void *plx_engine_block(const plx_engine *e)
{
    return eng_ok(e) ? e->block : NULL;
}

const char *plx_last_error(const plx_engine *e)
{
    if (!eng_ok(e))
        return "invalid engine handle";
    return e->err;
}

uint32_t plx_warning_count(const plx_engine *e)
{
    return eng_ok(e) ? e->warnings : 0;
}

void plx_memory_get(const plx_engine *e, plx_memory_report *out)
{
    size_t i;
    if (!out)
        return;
    memset(out, 0, sizeof *out);
    if (!eng_ok(e))
        return;
    out->capacity = e->mem.cap;
    for (i = 0; i < PLX_PART_COUNT; i++) {
        out->used[i] = e->mem.used[i];
        out->peak[i] = e->mem.peak[i];
    }
    out->used_total = e->mem.lo + e->mem.hi;
    out->peak_total = e->mem.peak_total;
}

uint64_t plx_debug_fail_alloc(plx_engine *e, uint64_t k)
{
    uint64_t served;
    if (!eng_ok(e))
        return 0;
    served = e->mem.requests;
    e->mem.requests = 0;
    e->mem.fail_at = k;
    return served;
}

void eng_warn(plx_engine *e, const char *msg)
{
    e->warnings++;
    eng_log(e, PLX_LOG_WARN, msg);
}

int eng_strict(const plx_engine *e)
{
    return e->cfg.strict;
}

const plx_port *eng_port(const plx_engine *e)
{
    return &e->port;
}

#ifdef PLX_DEBUG
static void check_rings(const scene_ring *rings, uint32_t first, uint32_t count, uint32_t nrings, uint32_t npts)
{
    uint32_t r;
    PLX_ASSERT(first <= nrings && count <= nrings - first);
    for (r = first; r < first + count; r++)
        PLX_ASSERT(rings[r].count >= 3 && rings[r].first <= npts && rings[r].count <= npts - rings[r].first);
}
#endif

void eng_check_scene(const scene *s)
{
#ifdef PLX_DEBUG
    uint32_t i, k;
    for (i = 0; i < s->nbld; i++) {
        const scene_building *b = &s->bld[i];
        PLX_ASSERT(b->ring_count >= 1 && b->block < s->nblocks);
        PLX_ASSERT(b->min_height >= 0.0 && b->min_height < b->height);
        check_rings(s->rings, b->ring_first, b->ring_count, s->nrings, s->npts);
    }
    for (k = 0; k < s->nblocks; k++) {
        const scene_block *g = &s->blocks[k];
        PLX_ASSERT(g->bld_count >= 1 && g->bld_first <= s->nbld && g->bld_count <= s->nbld - g->bld_first);
        for (i = g->bld_first; i < g->bld_first + g->bld_count; i++)
            PLX_ASSERT(s->block_bld[i] < s->nbld && s->bld[s->block_bld[i]].block == k);
        check_rings(s->block_rings, g->ring_first, g->ring_count, s->nblock_rings, s->nblock_pts);
    }
    for (i = 0; i < s->nlamps; i++)
        PLX_ASSERT(isfinite(s->lamps[i].x) && isfinite(s->lamps[i].y) && s->lamps[i].z >= 0.0);
#else
    (void)s;
#endif
}
