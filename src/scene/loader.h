/* loader: state shared by the GeoJSON reading steps (geojson.c, features.c)
 * and the helpers of loader.c. A JSON value is the byte offset of its first
 * character in the text (a jv, base/jsonscan.h): the text is checked once,
 * then read in place, one feature at a time. */
#ifndef PLX_LOADER_H
#define PLX_LOADER_H

#include "base/context.h"
#include "base/strbuf.h"
#include "base/jsonscan.h"

/* A JSON value: its offset in loader.text; JV_NONE when absent. */
typedef size_t jv;
#define JV_NONE JSONSCAN_NONE

/* Members of a few objects, found as far as lookups needed them (ld_get):
 * a lookup in a feature or its properties scans each member once. */
#define LD_MEMBERS 32
#define LD_OBJECTS 4
typedef struct ld_members {
    jv obj;                /* JV_NONE: unused */
    uint32_t n;            /* members found so far */
    int done;              /* 1: all found; -1: more than LD_MEMBERS */
    size_t next;           /* where the next member's key starts (JV_NONE: after val[n - 1]) */
    size_t key[LD_MEMBERS], val[LD_MEMBERS];
} ld_members;

typedef struct ld_cache {
    ld_members obj[LD_OBJECTS];
    uint32_t turn;         /* the entry replaced next */
    size_t dup;            /* the first key found again later in its object (a lookup's
                            * duplicate, which cJSON and we read the first of): the
                            * offset of the second; JV_NONE when none */
} ld_cache;

typedef struct loader {
    plx_engine *e;         /* for errors and warnings only (base/context.h) */
    arena *mem;
    scene *s;
    const char *name;      /* source name for messages, or NULL */
    const char *text;
    size_t len;
    jv root;               /* the top-level value */
    uint32_t *feat_line;   /* line of each feature (scratch) */
    uint32_t *feat_col;    /* its column */
    uint32_t nfeat;
    int metres;            /* properties.units == "m", or a projected crs */
    int crs_lonlat;        /* the file names a geographic (lon/lat) crs */
    double lon0, lat0, coslat;
    int gi_bounds_given;   /* properties.ground_image_bounds read (scene coordinates) */
    double gi_bounds[4];
    int oom;               /* a scratch allocation failed inside a reader (ld_number) */
    ld_cache *cache;       /* NULL: every lookup scans (geojson.c sets one up) */
} loader;

/* 1: a number (JSON number or numeric string with optional unit m),
 * 0: absent or null, -1: a value of another kind. */
int ld_number(loader *ld, jv item, double *out);
int ld_prop_number(loader *ld, uint32_t fi, const char *id, jv props, const char *key, double *out);

/* Reading values in place (loader.c; base/jsonscan.h for the rules). */
js_kind ld_kind(const loader *ld, jv v);
/* The member key of object obj (JV_NONE if none or obj is no object): the
 * first, as cJSON; a later member of the same key among the object's first
 * LD_MEMBERS members is noted in the cache's dup (a key found past them,
 * or a second one past them, is not compared). */
jv ld_get(const loader *ld, jv obj, const char *key);
/* Children of an array or object (an object's member values), as cJSON's
 * child list: the first (JV_NONE if none), the one after child. */
jv ld_first(const loader *ld, jv c);
jv ld_next(const loader *ld, jv c, jv child);
#define LD_EACH(ld, c, it) for ((it) = ld_first(ld, c); (it) != JV_NONE; (it) = ld_next(ld, c, it))
uint32_t ld_count(const loader *ld, jv c);
jv ld_item(const loader *ld, jv c, uint32_t i);
/* The value of a number (strtod over the text, as cJSON). */
double ld_double(const loader *ld, jv v);
/* v is a string equal to s (unescaped, up to a NUL). */
int ld_str_is(const loader *ld, jv v, const char *s);
/* v's string unescaped: at most cap - 1 bytes and a NUL into buf; returns
 * the full length (0 when v is no string). */
size_t ld_str(const loader *ld, jv v, char *buf, size_t cap);
/* Reports a bad feature; PLX_OK means skip it and go on (not strict). */
plx_status ld_bad_feature(loader *ld, uint32_t fi, const char *id, const char *why);
void ld_warn(loader *ld, uint32_t fi, const char *id, const char *why);
/* Fails the load (strict or not) with feature fi's place and why. */
plx_status ld_fail(loader *ld, uint32_t fi, const char *why);

#endif
