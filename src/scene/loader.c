/* loader: the helpers every GeoJSON reading step shares (geojson.c,
 * features.c): where a feature is in messages, bad features and warnings
 * (strict or lenient, SPEC §1), numbers in properties. */
#include <math.h>
#include <string.h>

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
    eng_warn(ld->e, msg);
    return PLX_OK;
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

/* 1: a number (JSON number or numeric string), 0: absent/null, -1: other. */
int ld_number(const cJSON *item, double *out)
{
    if (!item || cJSON_IsNull(item))
        return 0;
    if (cJSON_IsNumber(item)) {
        *out = item->valuedouble;
        return 1;
    }
    if (cJSON_IsString(item) && parse_number_text(item->valuestring, out))
        return 1;
    return -1;
}

/* A numeric property: 1 found, 0 absent; a value of the wrong kind is
 * ignored with a warning (SPEC §1) and reads as absent. */
int ld_prop_number(loader *ld, uint32_t fi, const char *id, const cJSON *props,
                   const char *key, double *out)
{
    const cJSON *item = props ? cJSON_GetObjectItemCaseSensitive(props, key) : NULL;
    int r = ld_number(item, out);
    if (r == -1) {
        char why[200];
        strbuf b;
        sb_init(&b, why, sizeof why);
        sb_str(&b, "property \"");
        sb_str(&b, key);
        sb_str(&b, "\" is not a number");
        if (cJSON_IsString(item)) {
            sb_str(&b, " (\"");
            sb_strn(&b, item->valuestring, 40);
            sb_str(&b, "\")");
        }
        sb_str(&b, "; ignored, the default applies");
        ld_warn(ld, fi, id, why);
        return 0;
    }
    return r;
}

