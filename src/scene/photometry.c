/* photometry: IES LM-63 and EULUMDAT parsing, symmetry completion and the
 * bilinear candela lookup (contract in photometry.h). */
#include "scene/photometry.h"
#include "base/strbuf.h"

#include <math.h>
#include <string.h>

#define PM_PI 3.14159265358979323846
#define PM_DEG (PM_PI / 180.0)

/* ---- text reading ----------------------------------------------------------- */

typedef struct pm_text {
    const char *s;
    size_t len, pos;
    uint32_t line;            /* 1-based line of pos */
    uint32_t lline;           /* the line pm_line returned last (0: none yet) */
    const char *name;
    char *err;
    size_t errlen;
    int guessed_ldt;          /* read as EULUMDAT though not named *.ldt */
    char note[200];           /* a warning of the parse itself ("" none): TILT=INCLUDE not applied */
} pm_text;

static int pm_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

static plx_status pm_fail(pm_text *t, uint32_t line, const char *why, const char *what)
{
    strbuf b;
    size_t i;
    int blank = 1;
    sb_init(&b, t->err, t->errlen);
    sb_str(&b, t->name ? t->name : "photometry");
    for (i = 0; i < t->len && blank; i++)
        blank = pm_space(t->s[i]) || t->s[i] == '\n';
    if (blank) { /* nothing to read: not "line 0: table too short" */
        sb_str(&b, t->len ? ": the file holds only white space" : ": the file is empty");
        return PLX_E_PARSE;
    }
    sb_str(&b, ": line ");
    sb_uint(&b, line);
    sb_str(&b, ": ");
    sb_str(&b, why);
    if (what)
        sb_str(&b, what);
    if (t->guessed_ldt) /* a file not named .ldt, with no TILT= line: say how it was read */
        sb_str(&b, " (read as EULUMDAT: the file has no IES 'TILT=' line)");
    return PLX_E_PARSE;
}

/* The next line (without its end of line); 0 at the end of the text. */
static int pm_line(pm_text *t, const char **l, size_t *n)
{
    size_t e;
    if (t->pos >= t->len)
        return 0;
    e = t->pos;
    while (e < t->len && t->s[e] != '\n' && t->s[e] != '\r') /* LF, CRLF or a lone CR (old Mac exports) */
        e++;
    *l = t->s + t->pos;
    *n = e - t->pos;
    t->lline = t->line;
    if (e < t->len)
        e += t->s[e] == '\r' && e + 1 < t->len && t->s[e + 1] == '\n' ? 2 : 1;
    t->pos = e;
    t->line++;
    return 1;
}

/* A decimal number filling s[0..n) ("1", "-2.5", "3e-2"; comma as the
 * decimal point when 'comma'); 1 on success. */
static int pm_number(const char *s, size_t n, int comma, double *out)
{
    double mant = 0.0;
    size_t i = 0;
    int digits = 0, exp10 = 0, neg = 0, e = 0, eneg = 0, edig = 0;
    if (i < n && (s[i] == '+' || s[i] == '-'))
        neg = s[i++] == '-';
    for (; i < n && s[i] >= '0' && s[i] <= '9'; i++, digits = 1) {
        if (mant < 1e18)
            mant = mant * 10.0 + (s[i] - '0');
        else if (exp10 < 10000)
            exp10++;
    }
    if (i < n && (s[i] == '.' || (comma && s[i] == ','))) {
        for (i++; i < n && s[i] >= '0' && s[i] <= '9'; i++, digits = 1)
            if (mant < 1e18) {
                mant = mant * 10.0 + (s[i] - '0');
                exp10--;
            }
    }
    if (!digits)
        return 0;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        if (i < n && (s[i] == '+' || s[i] == '-'))
            eneg = s[i++] == '-';
        for (; i < n && s[i] >= '0' && s[i] <= '9'; i++, edig = 1)
            if (e < 10000)
                e = e * 10 + (s[i] - '0');
        if (!edig)
            return 0;
        exp10 += eneg ? -e : e;
    }
    if (i != n)
        return 0;
    if (mant == 0.0)
        exp10 = 0;
    if (exp10 < 0)
        mant /= pow(10.0, -exp10);
    else if (exp10 > 0)
        mant *= pow(10.0, exp10);
    if (!isfinite(mant))
        return 0;
    *out = neg ? -mant : mant;
    return 1;
}

/* The next number of a free-form run (blanks, commas and line ends
 * separate); 'what' names it for the messages. */
static plx_status pm_next(pm_text *t, const char *what, double *v)
{
    size_t b;
    char tok[48];
    strbuf m;
    while (t->pos < t->len && (pm_space(t->s[t->pos]) || t->s[t->pos] == ',' || t->s[t->pos] == '\n')) {
        if (t->s[t->pos] == '\n' || (t->s[t->pos] == '\r' && (t->pos + 1 >= t->len || t->s[t->pos + 1] != '\n')))
            t->line++;
        t->pos++;
    }
    if (t->pos >= t->len) {
        uint32_t last = t->line > 1 && t->len > 0 && t->s[t->len - 1] == '\n' ? t->line - 1 : t->line;
        sb_init(&m, tok, sizeof tok);
        sb_str(&m, what);
        return pm_fail(t, last, "table too short: the file ends before ", tok);
    }
    b = t->pos;
    while (t->pos < t->len && !pm_space(t->s[t->pos]) && t->s[t->pos] != ',' && t->s[t->pos] != '\n')
        t->pos++;
    if (!pm_number(t->s + b, t->pos - b, 0, v)) {
        char why[160];
        sb_init(&m, why, sizeof why);
        sb_str(&m, "bad number '");
        sb_strn(&m, t->s + b, t->pos - b > 24 ? 24 : t->pos - b);
        sb_str(&m, "' for ");
        sb_str(&m, what);
        return pm_fail(t, t->line, why, NULL);
    }
    return PLX_OK;
}

/* A whole number in [lo, hi]. */
static plx_status pm_count(pm_text *t, const char *what, double v, uint32_t line, long lo, long hi)
{
    char why[120];
    strbuf m;
    if (v == floor(v) && v >= (double)lo && v <= (double)hi)
        return PLX_OK;
    sb_init(&m, why, sizeof why);
    sb_str(&m, what);
    sb_str(&m, " ");
    sb_num(&m, v, 8);
    sb_str(&m, " is not a whole number from ");
    sb_int(&m, lo);
    sb_str(&m, " to ");
    sb_int(&m, hi);
    return pm_fail(t, line, why, NULL);
}

/* ---- the table ---------------------------------------------------------------- */

typedef struct pm_build {
    arena *a;
    plx_part part;
    photometry *p;
    double *g, *cd;           /* ng, nrows * ng */
    double *src_c;            /* nrows: the stored rows' C angles */
    uint32_t ng, nrows;
    double rated;             /* lm the header states (0: none): EULUMDAT the luminaire's, IES its lamps' */
    double multiplier;        /* IES: the candela multiplier (named when the flux check warns) */
} pm_build;

static plx_status pm_alloc(pm_build *B, uint32_t ng, uint32_t nrows)
{
    B->ng = ng;
    B->nrows = nrows;
    B->p = arena_calloc(B->a, B->part, 1, sizeof *B->p, 16);
    B->g = arena_alloc(B->a, B->part, arena_mul(ng, sizeof(double)), 16);
    B->cd = arena_alloc(B->a, B->part, arena_mul(arena_mul(ng, nrows), sizeof(double)), 16);
    B->src_c = arena_alloc(B->a, B->part, arena_mul(nrows, sizeof(double)), 16);
    return B->p && B->g && B->cd && B->src_c ? PLX_OK : PLX_E_NOMEM;
}

/* Symmetry: which mirror images of the stored rows complete the circle. */
enum { SYM_ROT = 1, SYM_NONE, SYM_C0, SYM_C90, SYM_QUAD };

static double wrap360(double c)
{
    c = fmod(c, 360.0);
    if (c < 0.0)
        c += 360.0;
    if (c >= 360.0)
        c = 0.0;
    return c;
}

/* Fills p->c and p->row from the stored rows and the symmetry. */
static plx_status pm_complete(pm_build *B, int sym)
{
    photometry *p = B->p;
    uint32_t n = 0, i, j, k, cap = 4 * B->nrows + 1;
    double *c = arena_alloc(B->a, B->part, arena_mul(cap, sizeof(double)), 16);
    uint32_t *row = arena_alloc(B->a, B->part, arena_mul(cap, sizeof(uint32_t)), 16);
    if (!c || !row)
        return PLX_E_NOMEM;
    if (sym == SYM_ROT) {
        c[0] = 0.0;
        row[0] = 0;
        n = 1;
    } else {
        for (k = 0; k < 4; k++)   /* the stored rows first: they win ties */
            for (i = 0; i < B->nrows; i++) {
                double s = B->src_c[i], m;
                if (k == 0) m = s;
                else if (sym == SYM_C0 && k == 1) m = 360.0 - s;
                else if (sym == SYM_C90 && k == 1) m = 180.0 - s;
                else if (sym == SYM_QUAD) m = k == 1 ? 180.0 - s : k == 2 ? 180.0 + s : 360.0 - s;
                else continue;
                m = wrap360(m);
                for (j = 0; j < n && fabs(c[j] - m) > 1e-9; j++)
                    ;
                if (j < n)
                    continue;
                for (j = n; j > 0 && c[j - 1] > m; j--) {
                    c[j] = c[j - 1];
                    row[j] = row[j - 1];
                }
                c[j] = m;
                row[j] = i;
                n++;
            }
    }
    p->c = c;
    p->row = row;
    p->nc = n;
    return PLX_OK;
}

/* Integral of the bilinear table times sin(gamma) over the sphere: per
 * cell, the hat weights of the corners integrate in closed form. */
static double pm_flux(const photometry *p)
{
    double total = 0.0;
    uint32_t i, j;
    for (i = 0; i < p->nc; i++) {
        double wc;
        const double *r0 = p->cd + (size_t)p->row[i] * p->ng, *r1;
        if (p->nc == 1) {
            wc = 2.0 * PM_PI;
            r1 = r0;
        } else {
            double c1 = i + 1 < p->nc ? p->c[i + 1] : p->c[0] + 360.0;
            wc = 0.5 * (c1 - p->c[i]) * PM_DEG;
            r1 = p->cd + (size_t)p->row[i + 1 < p->nc ? i + 1 : 0] * p->ng;
            if (p->nc == 1)
                r1 = r0;
        }
        for (j = 0; j + 1 < p->ng; j++) {
            double a = p->g[j] * PM_DEG, b = p->g[j + 1] * PM_DEG, d = b - a, ds, wlo, whi;
            if (!(d > 0.0))
                continue;
            ds = (sin(b) - sin(a)) / d;
            wlo = cos(a) - ds;
            whi = -cos(b) + ds;
            if (p->nc == 1)
                total += wc * (r0[j] * wlo + r0[j + 1] * whi);
            else
                total += wc * ((r0[j] + r1[j]) * wlo + (r0[j + 1] + r1[j + 1]) * whi);
        }
    }
    return total;
}

static void pm_finish(pm_build *B, int format)
{
    photometry *p = B->p;
    uint32_t i, j, jmax = 0;
    int any = 0;
    p->ng = B->ng;
    p->nrows = B->nrows;
    p->g = B->g;
    p->cd = B->cd;
    p->format = format;
    p->peak = 0.0;
    for (i = 0; i < B->nrows; i++)
        for (j = 0; j < B->ng; j++) {
            double v = B->cd[(size_t)i * B->ng + j];
            if (v > p->peak)
                p->peak = v;
            if (v > 0.0 && (!any || j > jmax)) {
                jmax = j;
                any = 1;
            }
        }
    p->gamma_lit = !any ? 0.0 : jmax + 1 < B->ng ? B->g[jmax + 1] : B->g[B->ng - 1];
    if (any && jmax + 1 >= B->ng)
        p->gamma_lit = nextafter(p->gamma_lit, 1e300);
    p->flux = pm_flux(p);
}

/* Angles ascending within [lo, hi]. */
static plx_status pm_angles(pm_text *t, const char *what, double *v, uint32_t n, double lo, double hi)
{
    uint32_t i;
    plx_status st;
    for (i = 0; i < n; i++) {
        if ((st = pm_next(t, what, &v[i])) != PLX_OK)
            return st;
        if (!(v[i] >= lo && v[i] <= hi))
            return pm_fail(t, t->line, what, " out of range");
        if (i > 0 && !(v[i] > v[i - 1]))
            return pm_fail(t, t->line, what, " not in ascending order");
    }
    return PLX_OK;
}

/* An intensity as used (its multipliers applied) above PHOTOMETRY_MAX_CD,
 * or not finite, is refused: no luminaire gives it, and the table's flux
 * and every lux from it must stay finite. */
static plx_status pm_bounded(pm_text *t, uint32_t line, double cd, const char *by)
{
    strbuf m;
    char why[160];
    if (cd <= PHOTOMETRY_MAX_CD)
        return PLX_OK;
    sb_init(&m, why, sizeof why);
    sb_str(&m, "an intensity times ");
    sb_str(&m, by);
    sb_str(&m, " is above ");
    sb_num(&m, PHOTOMETRY_MAX_CD, 3);
    sb_str(&m, " cd: not a luminaire's");
    return pm_fail(t, line, why, NULL);
}

static plx_status pm_candela(pm_text *t, double *cd, size_t n, double mult)
{
    size_t i;
    plx_status st;
    for (i = 0; i < n; i++) {
        if ((st = pm_next(t, "the candela values", &cd[i])) != PLX_OK)
            return st;
        if (cd[i] < 0.0)
            return pm_fail(t, t->line, "negative candela value", NULL);
        cd[i] *= mult;
        if ((st = pm_bounded(t, t->line, cd[i], "the candela multiplier and ballast factors")) != PLX_OK)
            return st;
    }
    return PLX_OK;
}

/* ---- IES LM-63 ---------------------------------------------------------------- */

static int pm_starts(const char *l, size_t n, const char *w)
{
    size_t k = strlen(w);
    return n >= k && memcmp(l, w, k) == 0;
}

/* Whether s[0..n) holds w. */
static int pm_has(const char *s, size_t n, const char *w)
{
    size_t k = strlen(w), i;
    for (i = 0; i + k <= n; i++)
        if (memcmp(s + i, w, k) == 0)
            return 1;
    return 0;
}

/* Whether s[0..n) is w, any case (w upper case). */
static int pm_is_ci(const char *s, size_t n, const char *w)
{
    size_t i;
    if (n != strlen(w))
        return 0;
    for (i = 0; i < n; i++)
        if ((s[i] >= 'a' && s[i] <= 'z' ? s[i] - 'a' + 'A' : s[i]) != w[i])
            return 0;
    return 1;
}

/* TILT=INCLUDE's block after the TILT line: the lamp-to-luminaire
 * geometry, the number of tilt angles, the angles and their multiplying
 * factors, read and checked; the factors are not applied (a lamp's tilt
 * is the scene's), which t->note says with their range. */
static plx_status ies_tilt_block(pm_text *t)
{
    double geom, count, v, lo = 0.0, hi = 0.0;
    uint32_t k, n;
    plx_status st;
    strbuf b;
    if ((st = pm_next(t, "the tilt's lamp-to-luminaire geometry", &geom)) != PLX_OK ||
        (st = pm_next(t, "the number of tilt angles", &count)) != PLX_OK ||
        (st = pm_count(t, "the number of tilt angles", count, t->line, 1, PHOTOMETRY_MAX_ANGLES)) != PLX_OK)
        return st;
    n = (uint32_t)count;
    for (k = 0; k < n; k++)
        if ((st = pm_next(t, "the tilt angles", &v)) != PLX_OK)
            return st;
    for (k = 0; k < n; k++) {
        if ((st = pm_next(t, "the tilt factors", &v)) != PLX_OK)
            return st;
        if (!(v >= 0.0) || !isfinite(v))
            return pm_fail(t, t->line, "a tilt factor is negative or not finite", NULL);
        lo = k == 0 || v < lo ? v : lo;
        hi = k == 0 || v > hi ? v : hi;
    }
    sb_init(&b, t->note, sizeof t->note);
    sb_str(&b, "TILT=INCLUDE: its ");
    sb_uint(&b, n);
    sb_str(&b, " lamp-tilt factors (");
    sb_num(&b, lo, 4);
    sb_str(&b, " .. ");
    sb_num(&b, hi, 4);
    sb_str(&b, ") are not applied: the table is used as photometered");
    return PLX_OK;
}

static plx_status parse_ies(pm_text *t, pm_build *B)
{
    const char *l = NULL;
    size_t n = 0;
    int blpf = 0, first = 1, sym;
    double h[13], mult;
    double *hc;
    uint32_t nv, nh, k, hline;
    plx_status st;
    static const char *names[13] = { "the number of lamps", "lumens per lamp", "the candela multiplier",
                                     "the number of vertical angles", "the number of horizontal angles",
                                     "the photometric type", "the units type", "the width", "the length",
                                     "the height", "the ballast factor", "the ballast-lamp factor",
                                     "the input watts" };
    for (;;) {
        if (!pm_line(t, &l, &n))
            return pm_fail(t, t->lline, "no TILT= line: not an IES LM-63 file", NULL);
        if (first && n >= 3 && memcmp(l, "\xEF\xBB\xBF", 3) == 0) { /* a UTF-8 byte order mark */
            l += 3;
            n -= 3;
        }
        while (n > 0 && pm_space(*l)) {
            l++;
            n--;
        }
        /* the ballast-lamp photometric factor: LM-63-1986 (no version
         * line), -1991 and -1995; 2002 and 2019 use the field otherwise */
        if (first)
            blpf = !(pm_has(l, n, "LM-63-2002") || pm_has(l, n, "LM-63-2019"));
        first = 0;
        if (pm_starts(l, n, "TILT="))
            break;
    }
    l += 5;
    n -= 5;
    while (n > 0 && pm_space(l[n - 1]))
        n--;
    while (n > 0 && pm_space(*l)) {
        l++;
        n--;
    }
    if (pm_is_ci(l, n, "INCLUDE")) {
        if ((st = ies_tilt_block(t)) != PLX_OK)
            return st;
    } else if (!pm_is_ci(l, n, "NONE")) {
        return pm_fail(t, t->lline, "unsupported tilt: TILT=<file> names a separate tilt file, which is not read "
                       "(TILT=NONE and TILT=INCLUDE are)", NULL);
    }
    for (k = 0; k < 13; k++) {
        if ((st = pm_next(t, names[k], &h[k])) != PLX_OK)
            return st;
        if (k == 3 && (st = pm_count(t, "the number of vertical angles", h[3], t->line, 1,
                                     PHOTOMETRY_MAX_ANGLES)) != PLX_OK)
            return st;
        if (k == 4 && (st = pm_count(t, "the number of horizontal angles", h[4], t->line, 1,
                                     PHOTOMETRY_MAX_ANGLES)) != PLX_OK)
            return st;
        if (k == 5 && h[5] != 1.0)
            return pm_fail(t, t->line, "photometric type is not C (1): types A and B are not read", NULL);
    }
    mult = h[2] * h[10] * (blpf ? h[11] : 1.0);
    if (!(mult >= 0.0) || !isfinite(mult))
        return pm_fail(t, t->line, "the multipliers give a negative or infinite factor", NULL);
    B->multiplier = h[2];
    if (h[0] > 0.0 && h[1] > 0.0) /* lumens -1: absolute photometry, no lamp flux stated */
        B->rated = h[0] * h[1] * h[10] * (blpf ? h[11] : 1.0);
    nv = (uint32_t)h[3];
    nh = (uint32_t)h[4];
    if ((st = pm_alloc(B, nv, nh)) != PLX_OK)
        return st;
    if ((st = pm_angles(t, "the vertical angles", B->g, nv, 0.0, 180.0)) != PLX_OK)
        return st;
    hc = B->src_c;
    if ((st = pm_angles(t, "the horizontal angles", hc, nh, 0.0, 360.0)) != PLX_OK)
        return st;
    hline = t->line;
    if ((st = pm_candela(t, B->cd, (size_t)nv * nh, mult)) != PLX_OK)
        return st;
    if (nh == 1)
        sym = SYM_ROT;
    else if (hc[0] == 0.0 && hc[nh - 1] == 90.0)
        sym = SYM_QUAD;
    else if ((hc[0] == 0.0 && hc[nh - 1] == 180.0) || (hc[0] == 180.0 && hc[nh - 1] == 360.0))
        sym = SYM_C0;
    else if (hc[0] == 90.0 && hc[nh - 1] == 270.0)
        sym = SYM_C90;
    else if (hc[0] == 0.0)
        sym = SYM_NONE;
    else
        return pm_fail(t, hline, "the horizontal angles follow no LM-63 symmetry rule "
                                 "(first angle not 0, 90 or 180)", NULL);
    return pm_complete(B, sym);
}

/* ---- EULUMDAT ------------------------------------------------------------------ */

/* Line k (1-based, k > the last line read) of the header. */
static plx_status ldt_line(pm_text *t, uint32_t k, const char *what, const char **l, size_t *n)
{
    while (t->lline < k)
        if (!pm_line(t, l, n))
            return pm_fail(t, t->lline, "table too short: the file ends before ", what);
    return PLX_OK;
}

static int pm_trim_number(const char *l, size_t n, int comma, double *v)
{
    while (n > 0 && pm_space(*l)) {
        l++;
        n--;
    }
    while (n > 0 && pm_space(l[n - 1]))
        n--;
    return pm_number(l, n, comma, v);
}

/* Line k of the header as a number. */
static plx_status ldt_number(pm_text *t, uint32_t k, const char *what, double *v)
{
    const char *l = NULL;
    size_t n = 0;
    plx_status st = ldt_line(t, k, what, &l, &n);
    if (st != PLX_OK)
        return st;
    if (!pm_trim_number(l, n, 1, v)) { /* the line is in the message: not again from what's "(line k)" */
        const char *paren = strstr(what, " (line ");
        char bare[96];
        size_t m = paren ? (size_t)(paren - what) : strlen(what);
        if (m >= sizeof bare)
            m = sizeof bare - 1;
        memcpy(bare, what, m);
        bare[m] = '\0';
        return pm_fail(t, k, "bad number for ", bare);
    }
    return PLX_OK;
}

/* The light output ratio (line 23, %), read only to check the table's
 * flux by: 0 when it is not a number. */
static plx_status ldt_ratio(pm_text *t, double *lor)
{
    const char *l = NULL;
    size_t n = 0;
    plx_status st = ldt_line(t, 23, "the light output ratio (line 23)", &l, &n);
    if (st == PLX_OK && !pm_trim_number(l, n, 1, lor))
        *lor = 0.0;
    return st;
}

/* A number on a line of its own (the C and gamma angles, the values):
 * EULUMDAT writes one per line, decimal commas allowed; blank lines skipped. */
static plx_status ldt_value(pm_text *t, const char *what, double *v)
{
    const char *l;
    size_t n, i;
    do {
        if (!pm_line(t, &l, &n))
            return pm_fail(t, t->lline, "table too short: the file ends before ", what);
        for (i = 0; i < n && pm_space(l[i]); i++)
            ;
    } while (i == n);
    if (!pm_trim_number(l, n, 1, v))
        return pm_fail(t, t->lline, "bad number for ", what);
    return PLX_OK;
}

static plx_status parse_ldt(pm_text *t, pm_build *B)
{
    double isym, mc, ng, lor, cf, nsets, flux, v;
    uint32_t Mc, Ng, first, count, i, k, lsets;
    double *call;
    plx_status st;
    int sym;
    if ((st = ldt_number(t, 3, "the symmetry indicator (line 3)", &isym)) != PLX_OK ||
        (st = pm_count(t, "the symmetry indicator Isym", isym, 3, 0, 4)) != PLX_OK ||
        (st = ldt_number(t, 4, "the number of C planes (line 4)", &mc)) != PLX_OK ||
        (st = pm_count(t, "the number of C planes Mc", mc, 4, 1, PHOTOMETRY_MAX_ANGLES)) != PLX_OK ||
        (st = ldt_number(t, 6, "the number of intensities per plane (line 6)", &ng)) != PLX_OK ||
        (st = pm_count(t, "the number of intensities Ng", ng, 6, 1, PHOTOMETRY_MAX_ANGLES)) != PLX_OK ||
        (st = ldt_ratio(t, &lor)) != PLX_OK ||
        (st = ldt_number(t, 24, "the conversion factor (line 24)", &cf)) != PLX_OK ||
        (st = ldt_number(t, 26, "the number of lamp sets (line 26)", &nsets)) != PLX_OK ||
        (st = pm_count(t, "the number of lamp sets", nsets, 26, 1, 20)) != PLX_OK ||
        (st = ldt_number(t, 29, "the lamps' luminous flux (line 26c)", &flux)) != PLX_OK)
        return st;
    Mc = (uint32_t)mc;
    Ng = (uint32_t)ng;
    lsets = 26 + 6 * (uint32_t)nsets + 10;  /* last line of the direct ratios */
    if ((isym == 2.0 || isym == 3.0) && Mc % 2 != 0)
        return pm_fail(t, 4, "Mc must be even for symmetry 2 or 3", NULL);
    if (isym == 4.0 && Mc % 4 != 0)
        return pm_fail(t, 4, "Mc must be a multiple of 4 for symmetry 4", NULL);
    if (!(cf >= 0.0))
        return pm_fail(t, 24, "the conversion factor is negative", NULL);
    if (cf == 0.0)
        return pm_fail(t, 24, "the conversion factor is 0: every intensity would be 0", NULL);
    if (!(fabs(flux) > 0.0))
        return pm_fail(t, 29, "the lamps' luminous flux is 0", NULL);
    if (lor > 0.0) /* 0: not stated; the conversion factor scales the table only (a wrong one is caught) */
        B->rated = lor / 100.0 * fabs(flux);
    sym = isym == 0.0 ? SYM_NONE : isym == 1.0 ? SYM_ROT : isym == 2.0 ? SYM_C0 : isym == 3.0 ? SYM_C90 : SYM_QUAD;
    first = sym == SYM_C90 ? Mc / 4 : 0;
    count = sym == SYM_NONE ? Mc : sym == SYM_ROT ? 1 : sym == SYM_QUAD ? Mc / 4 + 1 : Mc / 2 + 1;
    if ((st = pm_alloc(B, Ng, count)) != PLX_OK)
        return st;
    {
        const char *l;
        size_t n;
        if ((st = ldt_line(t, lsets, "the direct ratios (line 27)", &l, &n)) != PLX_OK)
            return st;
    }
    call = arena_scratch(B->a, arena_mul(Mc + 1, sizeof(double)), 16);
    if (!call)
        return PLX_E_NOMEM;
    for (i = 0; i < Mc; i++) {
        if ((st = ldt_value(t, "the C angles", &call[i])) != PLX_OK)
            return st;
        if (!(call[i] >= 0.0 && call[i] < 360.0) || (i > 0 && !(call[i] > call[i - 1])))
            return pm_fail(t, t->lline, "the C angles are not ascending within 0..360", NULL);
    }
    for (i = 0; i < count; i++)
        B->src_c[i] = call[(first + i) % Mc];
    for (i = 0; i < Ng; i++) {
        if ((st = ldt_value(t, "the gamma angles", &B->g[i])) != PLX_OK)
            return st;
        if (!(B->g[i] >= 0.0 && B->g[i] <= 180.0) || (i > 0 && !(B->g[i] > B->g[i - 1])))
            return pm_fail(t, t->lline, "the gamma angles are not ascending within 0..180", NULL);
    }
    for (k = 0; k < (size_t)count * Ng; k++) {
        if ((st = ldt_value(t, "the intensities", &v)) != PLX_OK)
            return st;
        if (v < 0.0)
            return pm_fail(t, t->lline, "negative intensity", NULL);
        B->cd[k] = v * cf * fabs(flux) / 1000.0;
        if ((st = pm_bounded(t, t->lline, B->cd[k], "the conversion factor x the lamps' flux / 1000")) != PLX_OK)
            return st;
    }
    return pm_complete(B, sym);
}

/* ---- entry points --------------------------------------------------------------- */

/* The header's stated flux against the table's own (the integral of its
 * intensities): a warning in t's err when an EULUMDAT table gives more
 * than 10% above or below its light output ratio x lamp flux, or an IES
 * table more than 10% above its lamps' lumens (no luminaire gives more
 * light than its lamps), or when every intensity is 0; then the parse's
 * own note (t->note), "; " between. The table is used as given. */
static void pm_check_flux(pm_text *t, const pm_build *B, int ies)
{
    double f = B->p->flux, r = B->rated;
    int off = r > 0.0 && !(f <= 1.1 * r && (ies || f >= 0.9 * r));
    strbuf b;
    if (!t->errlen || (!off && B->p->peak > 0.0 && !t->note[0]))
        return;
    sb_init(&b, t->err, t->errlen);
    sb_str(&b, t->name ? t->name : "photometry");
    sb_str(&b, ": ");
    if (!(B->p->peak > 0.0)) {
        sb_str(&b, "every intensity of the table is 0: its lamps give no light");
    } else if (off) {
        sb_str(&b, "the table's intensities give ");
        sb_fixed(&b, f, 0);
        sb_str(&b, " lm, ");
        sb_fixed(&b, 100.0 * f / r, 0);
        sb_str(&b, ies ? "% of the lumens of its lamps (" : "% of the flux its header states (");
        sb_fixed(&b, r, 0);
        sb_str(&b, ies ? " lm: lamps x lumens per lamp x ballast factor" : " lm: light output ratio x the lamps' flux");
        if (ies && B->multiplier != 1.0) {
            sb_str(&b, "; the candela multiplier ");
            sb_num(&b, B->multiplier, 6);
            sb_str(&b, " scales the table");
        }
        sb_str(&b, "); the table is used as given");
    }
    if (t->note[0]) {
        if (off || !(B->p->peak > 0.0))
            sb_str(&b, "; ");
        sb_str(&b, t->note);
    }
}


/* Whether the name ends in .ldt (any case). */
static int named_ldt(const char *name)
{
    size_t n = name ? strlen(name) : 0;
    return n >= 4 && name[n - 4] == '.' && (name[n - 3] | 32) == 'l' && (name[n - 2] | 32) == 'd' &&
           (name[n - 1] | 32) == 't';
}

static int looks_ies(const char *s, size_t len)
{
    size_t i = 0;
    while (i < len) {
        while (i < len && (s[i] == ' ' || s[i] == '\t'))
            i++;
        if (len - i >= 5 && memcmp(s + i, "TILT=", 5) == 0)
            return 1;
        while (i < len && s[i] != '\n' && s[i] != '\r')
            i++;
        i++;
    }
    return 0;
}

plx_status photometry_parse(arena *a, plx_part part, const char *data, size_t len, const char *name,
                            const photometry **out, char *err, size_t errlen)
{
    arena_mark m;
    pm_text t;
    pm_build B;
    plx_status st;
    int ies;
    if (!a || !out || (!data && len > 0))
        return PLX_E_INVALID;
    *out = NULL;
    if (err && errlen)
        err[0] = '\0';
    memset(&t, 0, sizeof t);
    t.s = data;
    t.len = len;
    t.line = 1;
    t.name = name;
    t.err = err;
    t.errlen = err ? errlen : 0;
    memset(&B, 0, sizeof B);
    B.a = a;
    B.part = part;
    m = arena_get_mark(a);
    ies = looks_ies(data, len);
    t.guessed_ldt = !ies && !named_ldt(name);
    st = ies ? parse_ies(&t, &B) : parse_ldt(&t, &B);
    if (st == PLX_OK) {
        arena_mark now = arena_get_mark(a);
        pm_finish(&B, ies ? 1 : 2);
        pm_check_flux(&t, &B, ies); /* a warning in err, or err stays empty */
        now.hi = m.hi;   /* drop the scratch, keep the table */
        now.used[PLX_PART_SCRATCH] = m.used[PLX_PART_SCRATCH];
        arena_release(a, &now);
        *out = B.p;
        return PLX_OK;
    }
    if (st == PLX_E_NOMEM && t.errlen) {
        strbuf b;
        sb_init(&b, err, errlen);
        sb_str(&b, name ? name : "photometry");
        sb_str(&b, ": out of memory for the table");
    }
    arena_release(a, &m);
    return st;
}

/* ---- lookup ---------------------------------------------------------------------- */

/* The index j with v[j] <= x <= v[j+1] (n >= 2, v[0] <= x <= v[n-1]). */
static uint32_t pm_find(const double *v, uint32_t n, double x)
{
    uint32_t lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (v[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

static double pm_row_at(const photometry *p, uint32_t r, uint32_t j, double tg)
{
    const double *v = p->cd + (size_t)p->row[r] * p->ng;
    if (tg == 0.0)
        return v[j];
    return (1.0 - tg) * v[j] + tg * v[j + 1];
}

double photometry_at(const photometry *p, double c_deg, double gamma_deg)
{
    uint32_t j = 0, i0, i1;
    double tg = 0.0, tc, c0, c1;
    if (!(gamma_deg >= p->g[0] && gamma_deg <= p->g[p->ng - 1]))
        return 0.0;
    if (p->ng > 1) {
        j = pm_find(p->g, p->ng, gamma_deg);
        tg = (gamma_deg - p->g[j]) / (p->g[j + 1] - p->g[j]);
    }
    if (p->nc == 1)
        return pm_row_at(p, 0, j, tg);
    c_deg = wrap360(c_deg);
    if (c_deg < p->c[0]) {
        i0 = p->nc - 1;
        i1 = 0;
        c0 = p->c[i0] - 360.0;
        c1 = p->c[0];
    } else if (c_deg >= p->c[p->nc - 1]) {
        i0 = p->nc - 1;
        i1 = 0;
        c0 = p->c[i0];
        c1 = p->c[0] + 360.0;
    } else {
        i0 = pm_find(p->c, p->nc, c_deg);
        i1 = i0 + 1;
        c0 = p->c[i0];
        c1 = p->c[i1];
    }
    tc = (c_deg - c0) / (c1 - c0);
    if (tc == 0.0)
        return pm_row_at(p, i0, j, tg);
    return (1.0 - tc) * pm_row_at(p, i0, j, tg) + tc * pm_row_at(p, i1, j, tg);
}

/* ---- lamps ---------------------------------------------------------------------- */

void photometry_lamp_frame(scene_lamp *lp)
{
    lp->frame[0] = cos(lp->azimuth * PM_DEG);
    lp->frame[1] = sin(lp->azimuth * PM_DEG);
    lp->frame[2] = cos(lp->tilt * PM_DEG);
    lp->frame[3] = sin(lp->tilt * PM_DEG);
}

void lamp_direction_angles(const scene_lamp *lp, const double d[3], double *c_deg, double *gamma_deg)
{
    /* turn by -azimuth about z, then by -tilt about the new y axis */
    double xp = lp->frame[0] * d[0] + lp->frame[1] * d[1];
    double yp = -lp->frame[1] * d[0] + lp->frame[0] * d[1];
    double lx = lp->frame[2] * xp + lp->frame[3] * d[2];
    double lz = -lp->frame[3] * xp + lp->frame[2] * d[2];
    double h = sqrt(lx * lx + yp * yp);
    *gamma_deg = atan2(h, -lz) / PM_DEG;
    *c_deg = h > 0.0 ? atan2(yp, lx) / PM_DEG : 0.0;
}

double lamp_intensity(const scene_lamp *lp, const double d[3])
{
    double c, g;
    if (!lp->photometry)
        return lp->intensity;
    if (!lp->phot)
        return 0.0;
    lamp_direction_angles(lp, d, &c, &g);
    return lp->dimming * photometry_at(lp->phot, c, g);
}

double lamp_flux(const scene_lamp *lp)
{
    if (!lp->photometry)
        return 4.0 * PM_PI * lp->intensity;
    if (!lp->phot)
        return 0.0;
    return lp->dimming * lp->phot->flux;
}
