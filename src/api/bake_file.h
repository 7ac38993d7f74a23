/* bake_file: the bake file's format (README "Bake files"), shared by the
 * saving (bake.c) and the loading (bake_load.c): its constants and header
 * fields, the checksum, the layout of its parts, and the engine's code
 * addresses bound again after a load. */
#ifndef PLX_BAKE_FILE_H
#define PLX_BAKE_FILE_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "base/engine.h"

#define BAKE_MAGIC "PLXBAKE\0"
#define BAKE_VERSION 3u
#define BAKE_HEADER 128u
#define BAKE_ENDIAN 0x01020304u
#define BAKE_ALIGN 64u
#define BAKE_PAGE 4096u
#define BAKE_SLACK ((uint64_t)32 << 20) /* room for queries' scratch */

enum {
    H_MAGIC = 0, H_VERSION = 8, H_ENDIAN = 12, H_SIZES = 16, H_LAYOUT = 20, H_LENGTH = 24,
    H_SUM = 32, H_IMAGE = 40, H_NREL = 48, H_BASEMOD = 56, H_SLACK = 64, H_RESERVED = 72, H_PAGES = 80
};

/* The checksum's running state (bake_file.c). */
typedef struct bake_sum {
    uint64_t h[4];
} bake_sum;

void bake_sum_init(bake_sum *s);
/* Adds n bytes (n a multiple of 32 except for the last call). */
void bake_sum_add(bake_sum *s, const unsigned char *p, size_t n);
uint64_t bake_sum_end(const bake_sum *s);
/* The header's bytes as the checksum takes them: its checksum field as 0. */
void bake_sum_header(bake_sum *s, const unsigned char *h);
/* The checksum of a whole file: the header with its checksum field as 0,
 * then everything after the header. */
uint64_t bake_file_sum(const unsigned char *f, size_t len);

static inline void bake_put32(unsigned char *p, uint32_t v) { memcpy(p, &v, 4); }
static inline void bake_put64(unsigned char *p, uint64_t v) { memcpy(p, &v, 8); }
static inline uint32_t bake_get32(const unsigned char *p) { uint32_t v; memcpy(&v, p, 4); return v; }
static inline uint64_t bake_get64(const unsigned char *p) { uint64_t v; memcpy(&v, p, 8); return v; }

/* Sizes of the saved structures: a bake from a build whose structures
 * differ is refused (a cheap guard; BAKE_VERSION is the real contract). */
uint32_t bake_layout_print(void);
uint32_t bake_arch_sizes(void);
size_t bake_pad8(size_t n);

/* Where a file's parts are: the page bitmap, the stored pages, the
 * relocations. */
typedef struct bake_layout {
    size_t image, npages, pages_present, nrel;
    size_t bitmap_at, pages_at, rel_at, total;
} bake_layout;

/* The parts' places from image, pages_present and nrel. */
void bake_layout_fill(bake_layout *L);

/* The code addresses a bake clears (the renderer's shader), bound again. */
void bake_bind_code(plx_engine *e);

#endif
