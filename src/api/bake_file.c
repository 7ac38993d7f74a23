/* bake_file: the bake file's checksum and layout (bake_file.h). */
#include <string.h>

#include "api/bake_file.h"
#include "light/light.h"
#include "light/litregion.h"
#include "photon/photon.h"
#include "photon/irradiance_cache.h"
#include "polar/polar.h"
#include "render/render.h"
#include "render/atlas.h"
#include "render/atlas_frame.h"

/* ---- checksum: a multiply-rotate round over 64-bit words, four lanes ------ */

/* Each word enters its lane as acc = rotl(acc + w K2, 31) K1: for a fixed
 * word a bijection of acc, for a fixed acc a bijection of w (K1 and K2
 * odd), and the rotation carries every bit of the product into the low
 * bits of the next one. Format 2's FNV-1a step, (acc ^ w) P, carried a
 * word's bit 63 only into the sum's bit 63: two flipped top bits in one
 * lane cancelled, and one in a field nothing reads went unseen, so a
 * damaged file passed and crashed the frames (a hostile-input pass). */
#define SUM_K1 0x9e3779b97f4a7c15ull /* 2^64 / the golden ratio, odd */
#define SUM_K2 0xd6e8feb86659fd93ull
#define SUM_K3 0xff51afd7ed558ccdull

static uint64_t rotl64(uint64_t x, unsigned r)
{
    return (x << r) | (x >> (64u - r));
}

static uint64_t bake_round(uint64_t acc, uint64_t w)
{
    return rotl64(acc + w * SUM_K2, 31) * SUM_K1;
}

void bake_sum_init(bake_sum *s)
{
    int k;
    for (k = 0; k < 4; k++)
        s->h[k] = SUM_K3 + (uint64_t)k;
}

void bake_sum_add(bake_sum *s, const unsigned char *p, size_t n)
{
    size_t i = 0;
    uint64_t h0 = s->h[0], h1 = s->h[1], h2 = s->h[2], h3 = s->h[3], w[4];
    for (; i + 32 <= n; i += 32) {
        memcpy(w, p + i, 32);
        h0 = bake_round(h0, w[0]);
        h1 = bake_round(h1, w[1]);
        h2 = bake_round(h2, w[2]);
        h3 = bake_round(h3, w[3]);
    }
    for (; i < n; i++)
        h0 = bake_round(h0, p[i]);
    s->h[0] = h0;
    s->h[1] = h1;
    s->h[2] = h2;
    s->h[3] = h3;
}

/* The lanes folded in order through the same round, then mixed so that
 * every bit of the result depends on every bit of each lane. */
uint64_t bake_sum_end(const bake_sum *s)
{
    uint64_t h = s->h[0];
    int k;
    for (k = 1; k < 4; k++)
        h = bake_round(h, s->h[k]);
    h ^= h >> 33;
    h *= SUM_K3;
    h ^= h >> 29;
    h *= SUM_K2;
    h ^= h >> 32;
    return h;
}

void bake_sum_header(bake_sum *s, const unsigned char *h)
{
    unsigned char c[BAKE_HEADER];
    memcpy(c, h, BAKE_HEADER);
    memset(c + H_SUM, 0, 8);
    bake_sum_add(s, c, BAKE_HEADER);
}

uint64_t bake_file_sum(const unsigned char *f, size_t len)
{
    bake_sum s;
    bake_sum_init(&s);
    bake_sum_header(&s, f);
    bake_sum_add(&s, f + BAKE_HEADER, len - BAKE_HEADER);
    return bake_sum_end(&s);
}

uint32_t bake_layout_print(void)
{
    const size_t sz[] = { sizeof(struct plx_engine), sizeof(scene), sizeof(scene_building),
                          sizeof(scene_lamp), sizeof(light), sizeof(lit_region), sizeof(photon_sys),
                          sizeof(photon_config), sizeof(photon_lamp_slot), sizeof(arena),
                          sizeof(plx_config), sizeof(render_opts), render_struct_bytes(),
                          sizeof(render_stats), sizeof(icache), sizeof(polar), sizeof(polar_trap),
                          PLX_PART_COUNT, sizeof(mesh), sizeof(mesh_bld),
                          sizeof(mesh_surf), RENDER_SURF_CACHE, sizeof(atlas), sizeof(atlas_chart),
                          sizeof(atlas_cache), sizeof(light_entry),
                          7 /* format changes that keep the sizes (bump on such changes): 2 the polar
                               DAG's wide nodes bit-packed, 3 aerial records keyed apart, 8 m, 4 the
                               radiance atlas, 5 a wall column's vertices shared by its two walls, the
                               roof and the underside (mesh_bld.v_count), 6 the renderer's buffers of
                               a row or a column for the longer side (it draws frames either way
                               round: an older bake's are too short for a turned frame), 7 the photon
                               charts' surface keys (courtyards apart) and own-texel rule. The atlas's dark state
                               (ATLAS_DARK, 2026-11-29) needs none: an older bake's charts read as
                               filled (no shortcut, the same
                               image), an older reader takes the state as done (a saved bake has
                               nothing left to fill) */ };
    uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a's basis and prime: the sizes are small */
    size_t i;
    for (i = 0; i < sizeof sz / sizeof sz[0]; i++)
        h = (h ^ (uint64_t)sz[i]) * 0x00000100000001b3ull;
    return (uint32_t)(h ^ (h >> 32));
}

uint32_t bake_arch_sizes(void)
{
    return (uint32_t)sizeof(void *) | (uint32_t)sizeof(size_t) << 8 | (uint32_t)sizeof(double) << 16 |
           (uint32_t)sizeof(long) << 24;
}

size_t bake_pad8(size_t n)
{
    return (n + 7) & ~(size_t)7;
}

void bake_layout_fill(bake_layout *L)
{
    L->npages = (L->image + BAKE_PAGE - 1) / BAKE_PAGE;
    L->bitmap_at = BAKE_HEADER;
    L->pages_at = L->bitmap_at + bake_pad8((L->npages + 7) / 8);
    L->rel_at = L->pages_at + L->pages_present * BAKE_PAGE;
    L->total = L->rel_at + 4 * L->nrel;
}

void bake_bind_code(plx_engine *e)
{
    if (e->rd)
        render_code_bind(e->rd, render_shade_light);
}
