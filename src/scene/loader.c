/* loader: the helpers every GeoJSON reading step shares (geojson.c,
 * features.c): where a feature is in messages, bad features and warnings
 * (strict or lenient, SPEC §1), numbers in properties. */
#include <math.h>
#include <string.h>
#include <stdlib.h> /* strtod */

#include "base/plx_assert.h"
#include "scene/loader.h"

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/* ---- messages ----------------------------------------------------------- */

static void msg_where(loader *ld, strbuf *b, uint32_t fi, const char *id)
{
    if (ld->name) {
        sb_str(b, ld->name);
        sb_str(b, ": ");
    }
    sb_str(b, "feature ");
    sb_uint(b, fi);
    if (id || (ld->feat_line && fi < ld->nfeat && ld->feat_line[fi])) {
        sb_str(b, " (");
        if (id) {
            sb_str(b, id);
            if (ld->feat_line && ld->feat_line[fi])
                sb_str(b, ", ");
        }
        if (ld->feat_line && fi < ld->nfeat && ld->feat_line[fi]) {
            sb_str(b, "line ");
            sb_uint(b, ld->feat_line[fi]);
            sb_str(b, ", column ");
            sb_uint(b, ld->feat_col[fi]);
        }
        sb_char(b, ')');
    }
    sb_str(b, ": ");
}

/* A feature-level problem: in strict mode the load fails, otherwise the
 * feature is skipped and reported. Returns PLX_OK to go on. */
plx_status ld_bad_feature(loader *ld, uint32_t fi, const char *id, const char *why)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    msg_where(ld, &b, fi, id);
    sb_str(&b, why);
    if (eng_strict(ld->e))
        return eng_fail(ld->e, PLX_E_SCENE, msg);
    ld->s->skipped_features++;
    if (!strstr(why, "left out") && !strstr(why, "dropped")) /* a dropped lamp among hundreds went unnoticed */
        sb_str(&b, "; left out");
    eng_warn(ld->e, msg);
    return PLX_OK;
}

plx_status ld_fail(loader *ld, uint32_t fi, const char *why)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    msg_where(ld, &b, fi, NULL);
    sb_str(&b, why);
    return eng_fail(ld->e, PLX_E_SCENE, msg);
}

void ld_warn(loader *ld, uint32_t fi, const char *id, const char *why)
{
    char msg[ENGINE_ERR_BYTES];
    strbuf b;
    sb_init(&b, msg, sizeof msg);
    msg_where(ld, &b, fi, id);
    sb_str(&b, why);
    eng_warn(ld->e, msg);
}

/* ---- numbers in properties ------------------------------------------------ */

/* Parses "12", "12.5", "-3e2", "12.5 m", "12m" (surrounding spaces allowed).
 * Returns 1 and the value, or 0 when the text is anything else. */
static int parse_number_text(const char *s, double *out)
{
    double mant = 0.0;
    int digits = 0, exp10 = 0, neg = 0, eneg = 0, e = 0, edigits = 0;
    while (is_space(*s))
        s++;
    if (*s == '+' || *s == '-')
        neg = (*s++ == '-');
    /* digits past the 18th only scale the value (they are below its
     * precision), so a long mantissa cannot overflow to inf */
    for (; *s >= '0' && *s <= '9'; s++, digits = 1) {
        if (mant < 1e18)
            mant = mant * 10.0 + (*s - '0');
        else if (exp10 < 10000)
            exp10++;
    }
    if (*s == '.') {
        for (s++; *s >= '0' && *s <= '9'; s++, digits = 1) {
            if (mant < 1e18 && exp10 > -10000) {
                mant = mant * 10.0 + (*s - '0');
                exp10--;
            }
        }
    }
    if (digits == 0)
        return 0;
    if (*s == 'e' || *s == 'E') {
        s++;
        if (*s == '+' || *s == '-')
            eneg = (*s++ == '-');
        for (; *s >= '0' && *s <= '9'; s++, edigits = 1)
            if (e < 10000)
                e = e * 10 + (*s - '0');
        if (edigits == 0)
            return 0;
        exp10 += eneg ? -e : e;
    }
    while (is_space(*s))
        s++;
    if (*s == 'm') {
        s++;
        while (is_space(*s))
            s++;
    }
    if (*s != '\0')
        return 0;
    if (mant == 0.0)
        exp10 = 0; /* "0e99999" is 0, not 0 * inf */
    if (exp10 < 0)
        mant /= pow(10.0, -exp10);
    else if (exp10 > 0)
        mant *= pow(10.0, exp10);
    *out = neg ? -mant : mant;
    return 1;
}

/* 1: a number (JSON number or numeric string), 0: absent/null, -1: other.
 * A numeric string longer than a line is unescaped into scratch memory;
 * when that fails, ld->oom is set and the value reads as absent. */
int ld_number(loader *ld, jv item, double *out)
{
    char small[256], *text = small;
    size_t n;
    int r;
    arena_mark m;
    js_kind k = ld_kind(ld, item);
    if (k == JS_NONE || k == JS_NULL)
        return 0;
    if (k == JS_NUMBER) {
        *out = ld_double(ld, item);
        return 1;
    }
    if (k != JS_STRING)
        return -1;
    n = ld_str(ld, item, small, sizeof small);
    m = arena_get_mark(ld->mem);
    if (n >= sizeof small) {
        text = arena_scratch(ld->mem, n + 1, 1);
        if (!text) {
            ld->oom = 1;
            return 0;
        }
        ld_str(ld, item, text, n + 1);
    }
    r = parse_number_text(text, out) ? 1 : -1;
    arena_release(ld->mem, &m);
    return r;
}

/* A numeric property: 1 found, 0 absent; a value of the wrong kind is
 * ignored with a warning (SPEC §1) and reads as absent. */
int ld_prop_number(loader *ld, uint32_t fi, const char *id, jv props, const char *key, double *out)
{
    jv item = ld_get(ld, props, key);
    int r = ld_number(ld, item, out);
    if (r == -1) {
        char why[200], head[41];
        strbuf b;
        sb_init(&b, why, sizeof why);
        sb_str(&b, "property \"");
        sb_str(&b, key);
        sb_str(&b, "\" is not a number");
        if (ld_kind(ld, item) == JS_STRING) {
            ld_str(ld, item, head, sizeof head);
            sb_str(&b, " (\"");
            sb_str(&b, head);
            sb_str(&b, "\")");
        }
        sb_str(&b, "; ignored, the default applies");
        ld_warn(ld, fi, id, why);
        return 0;
    }
    return r;
}

/* ---- JSON values in place ------------------------------------------------------ */

js_kind ld_kind(const loader *ld, jv v)
{
    return jsonscan_kind(ld->text, v);
}

static ld_members *members_of(const loader *ld, jv obj)
{
    ld_cache *c = ld->cache;
    ld_members *m;
    uint32_t i;
    for (i = 0; i < LD_OBJECTS; i++)
        if (c->obj[i].obj == obj)
            return &c->obj[i];
    m = &c->obj[c->turn];
    c->turn = (c->turn + 1) % LD_OBJECTS;
    m->obj = obj;
    m->n = 0;
    m->done = 0;
    m->next = jsonscan_ws(ld->text, ld->len, obj + 1);
    if (m->next >= ld->len || ld->text[m->next] != '"')
        m->done = 1;
    return m;
}

/* Finds one more member of m's object; 0 when there is none. The value of
 * the last member found is skipped only when a member after it is asked
 * for; the duplicate-key check (note_duplicate) asks for every member
 * after a key found, so each value, coordinates too, is skipped once per
 * pass (about a tenth of a large scene's load). */
static int members_more(const loader *ld, ld_members *m)
{
    const char *t = ld->text;
    size_t p = m->next, v;
    if (m->done)
        return 0;
    if (p == JV_NONE) {
        p = jsonscan_ws(t, ld->len, jsonscan_skip(t, ld->len, m->val[m->n - 1]));
        if (p >= ld->len || t[p] != ',') {
            m->done = 1;
            return 0;
        }
        p = jsonscan_ws(t, ld->len, p + 1);
    }
    if (m->n == LD_MEMBERS) {
        m->done = -1;
        return 0;
    }
    v = jsonscan_ws(t, ld->len, jsonscan_skip(t, ld->len, p)); /* the ':' after the key */
    v = jsonscan_ws(t, ld->len, v + 1);
    m->key[m->n] = p;
    m->val[m->n++] = v;
    m->next = JV_NONE;
    return 1;
}

/* A second member of the key found at m->key[i], looked for among the rest
 * (each value skipped once; the members stay cached for later lookups):
 * the first such in the text is kept in the cache's dup. */
static void note_duplicate(const loader *ld, ld_members *m, uint32_t i, const char *key)
{
    uint32_t j;
    for (j = i + 1;; j++) {
        if (j == m->n && !members_more(ld, m))
            return;
        if (jsonscan_key_is(ld->text, ld->len, m->key[j], key)) {
            if (ld->cache->dup == JV_NONE || m->key[j] < ld->cache->dup)
                ld->cache->dup = m->key[j];
            return;
        }
    }
}

jv ld_get(const loader *ld, jv obj, const char *key)
{
    ld_members *m;
    uint32_t i;
    if (!ld->cache || ld_kind(ld, obj) != JS_OBJECT)
        return jsonscan_get(ld->text, ld->len, obj, key);
    m = members_of(ld, obj);
    for (i = 0;; i++) {
        if (i == m->n && !members_more(ld, m))
            break;
        if (jsonscan_key_is(ld->text, ld->len, m->key[i], key)) {
            note_duplicate(ld, m, i, key);
            return m->val[i];
        }
    }
    return m->done < 0 ? jsonscan_get(ld->text, ld->len, obj, key) : JV_NONE;
}

jv ld_first(const loader *ld, jv c)
{
    return jsonscan_first(ld->text, ld->len, c);
}

jv ld_next(const loader *ld, jv c, jv child)
{
    return jsonscan_next(ld->text, ld->len, child, ld->text[c] == '{');
}

uint32_t ld_count(const loader *ld, jv c)
{
    uint32_t n = 0;
    jv it;
    LD_EACH(ld, c, it)
        n++;
    return n;
}

jv ld_item(const loader *ld, jv c, uint32_t i)
{
    jv it;
    LD_EACH(ld, c, it)
        if (i-- == 0)
            return it;
    return JV_NONE;
}

/* The number at v, by strtod on a NUL-terminated copy of the bytes it
 * reads (jsonscan_number_len, bounded by the text's end): the text may be a
 * mapped file with nothing after its last byte. A number longer than the
 * copy (64 characters or more, rare) is read in place: the checked text
 * holds numbers inside containers only, so a byte strtod stops at (',',
 * ']', '}' or white space) follows it before the end. */
double ld_double(const loader *ld, jv v)
{
    char buf[64];
    size_t n = jsonscan_number_len(ld->text, ld->len, v);
    if (n < sizeof buf) {
        memcpy(buf, ld->text + v, n);
        buf[n] = '\0';
        return strtod(buf, NULL);
    }
    PLX_ASSERT(v + n < ld->len);
    return strtod(ld->text + v, NULL);
}

int ld_str_is(const loader *ld, jv v, const char *s)
{
    return jsonscan_string_is(ld->text, ld->len, v, s);
}

size_t ld_str(const loader *ld, jv v, char *buf, size_t cap)
{
    if (ld_kind(ld, v) != JS_STRING) {
        if (cap)
            buf[0] = '\0';
        return 0;
    }
    return jsonscan_string(ld->text, ld->len, v, buf, cap);
}
