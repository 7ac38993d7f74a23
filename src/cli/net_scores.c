/* net_scores: annotate's scores written with a network and read back
 * (net_scores.h). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "net_scores.h"

/* v as a JSON number that reads back as the same double (cJSON's own
 * printing keeps 15 digits when they come within a rounding of v, which
 * may read back one bit away), null when not finite. */
static void add_exact(cJSON *o, const char *k, double v)
{
    char buf[40];
    if (!isfinite(v)) {
        cJSON_AddNullToObject(o, k);
        return;
    }
    cli_shortest(v, buf, sizeof buf);
    cJSON_AddRawToObject(o, k, buf);
}

void net_class_text(int c, char out[4])
{
    if (c)
        snprintf(out, 4, "P%d", c);
    else
        strcpy(out, "-");
}

int net_full_class(double scored, double mean, double min, double min_ev, double min_esc)
{
    if (!(scored > 0) || min_ev != min_ev || min_esc != min_esc)
        return 0;
    return plx_p_class_facial(mean, min, min_ev, min_esc);
}

double net_or_none(double v)
{
    return v == v ? v : -1.0;
}

cJSON *net_scores_edge_props(const network *net, uint32_t i, const char *osm_id, const char *name, double weight)
{
    const net_edge *ed = &net->edges[i];
    cJSON *p = cJSON_CreateObject();
    double dark = ed->dark + ed->s.blocked_length, cost = ed->length + weight * dark;
    double ev = fmin(ed->fac[0], ed->fac[1]), esc = fmin(ed->fac[2], ed->fac[3]);
    char cls[4];
    if (!p)
        return NULL;
    net_class_text(net_full_class(ed->s.length, ed->s.mean, ed->s.min, ev, esc), cls);
    cJSON_AddStringToObject(p, "osm_id", osm_id);
    cJSON_AddStringToObject(p, "name", name);
    cJSON_AddNumberToObject(p, "edge", i);
    cJSON_AddNumberToObject(p, "from", ed->a);
    cJSON_AddNumberToObject(p, "to", ed->b);
    add_exact(p, "length_m", ed->length);
    add_exact(p, "scored_m", ed->s.length);
    add_exact(p, "blocked_m", ed->s.blocked_length);
    add_exact(p, "below_m", ed->dark);
    add_exact(p, "dark_m", dark);
    add_exact(p, "dark_share", ed->length > 0 ? fmin(dark / ed->length, 1.0) : 0.0); /* not 1 + 2^-52 */
    add_exact(p, "mean_lux", ed->s.mean);
    add_exact(p, "min_lux", ed->s.min);
    add_exact(p, "max_lux", ed->s.max);
    add_exact(p, "uniformity", ed->s.uniformity);
    add_exact(p, "min_ev_fw_lux", net_or_none(ed->fac[0]));
    add_exact(p, "min_ev_bw_lux", net_or_none(ed->fac[1]));
    add_exact(p, "min_sc_fw_lux", net_or_none(ed->fac[2]));
    add_exact(p, "min_sc_bw_lux", net_or_none(ed->fac[3]));
    add_exact(p, "min_ev_lux", net_or_none(ev));
    add_exact(p, "min_sc_lux", net_or_none(esc));
    cJSON_AddStringToObject(p, "class", cls);
    net_class_text(ed->s.p_class, cls);
    cJSON_AddStringToObject(p, "class_h", cls);
    add_exact(p, "cost", cost);
    add_exact(p, "factor", ed->length > 0 ? cost / ed->length : 1.0);
    return p;
}

/* The scene as e holds it: buildings, lamps, photon frames. */
static void scene_counts(plx_engine *e, double out[3])
{
    plx_scene_info si;
    memset(&si, 0, sizeof si);
    (void)plx_scene_info_get(e, &si);
    out[0] = si.buildings;
    out[1] = si.lamps;
    out[2] = (double)plx_indirect_frames(e);
}

/* n bytes into FNV-1a hash h. */
static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    size_t i;
    for (i = 0; i < n; i++)
        h = (h ^ b[i]) * 1099511628211u;
    return h;
}

/* Lamp i's photometry into h: its file's format, azimuth, tilt, dimming,
 * peak, flux and dark angle, and (a photometric lamp) its intensity in
 * the scene's frame toward PHOT_GAMMAS x PHOT_CS fixed directions, so that
 * a turned, tilted or rescaled table changes the hash where the lamp's
 * position, intensity and reach do not. */
#define PHOT_GAMMAS 19 /* 0, 10, .. 180 degrees from the nadir */
#define PHOT_CS 24     /* 0, 15, .. 345 degrees from east */
#define PHOT_PI 3.14159265358979323846
static uint64_t photometry_hash(plx_engine *e, uint32_t i, uint64_t h)
{
    plx_lamp_photometry ph;
    double v[7];
    int g, c;
    if (plx_lamp_photometry_get(e, i, &ph) != PLX_OK)
        return h;
    v[0] = ph.format;
    v[1] = ph.azimuth;
    v[2] = ph.tilt;
    v[3] = ph.dimming;
    v[4] = ph.peak_cd;
    v[5] = ph.flux_lm;
    v[6] = ph.gamma_lit;
    h = fnv(h, v, sizeof v);
    if (ph.format == 0)
        return h;
    for (g = 0; g < PHOT_GAMMAS; g++)
        for (c = 0; c < PHOT_CS; c++) {
            double gr = g * (PHOT_PI / (PHOT_GAMMAS - 1)), cr = c * (2.0 * PHOT_PI / PHOT_CS), cd = 0.0;
            double dir[3];
            dir[0] = sin(gr) * cos(cr);
            dir[1] = sin(gr) * sin(cr);
            dir[2] = -cos(gr);
            if (plx_lamp_intensity(e, i, dir, &cd, NULL, NULL) != PLX_OK)
                cd = -1.0;
            h = fnv(h, &cd, sizeof cd);
        }
    return h;
}

/* A hash of what the light depends on in the scene: every building's
 * rings, heights and albedo, every lamp's position, intensity, reach,
 * colour and photometry, the ground's albedo (as 16 hex digits). */
static void scene_hash(plx_engine *e, char out[17])
{
    plx_scene_info si;
    uint64_t h = 14695981039346656037u;
    uint32_t i, r, n;
    memset(&si, 0, sizeof si);
    (void)plx_scene_info_get(e, &si);
    h = fnv(h, &si.ground_albedo, sizeof si.ground_albedo);
    for (i = 0; i < si.buildings; i++) {
        plx_building b;
        const double *xy;
        if (plx_building_get(e, i, &b) != PLX_OK)
            continue;
        h = fnv(h, &b.height, sizeof b.height);
        h = fnv(h, &b.min_height, sizeof b.min_height);
        h = fnv(h, &b.albedo, sizeof b.albedo);
        for (r = 0; r < b.nrings; r++)
            if (plx_building_ring(e, i, r, &xy, &n) == PLX_OK)
                h = fnv(h, xy, sizeof *xy * 2 * (size_t)n);
    }
    for (i = 0; i < si.lamps; i++) {
        plx_lamp l;
        if (plx_lamp_get(e, i, &l) != PLX_OK)
            continue;
        h = fnv(h, &l.x, sizeof l.x);
        h = fnv(h, &l.y, sizeof l.y);
        h = fnv(h, &l.z, sizeof l.z);
        h = fnv(h, &l.intensity, sizeof l.intensity);
        h = fnv(h, &l.radius, sizeof l.radius);
        h = fnv(h, l.color, sizeof l.color);
        h = photometry_hash(e, i, h);
    }
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

/* A hash of the indirect light the edges were scored with, beyond its
 * photon frames (scene_counts): the photons those frames emitted (two
 * bakes differing only in --photons), the photon buffers' sizes and chart
 * texels, and the direct and indirect lux on the ground at up to
 * LIGHT_EDGES points where the scores are (the first vertex of edges
 * spread over the network), up to LIGHT_LAMPS points 1 m east of lamps
 * spread over the scene, and 4 x 4 points over its box: a gather each
 * (0.2 ms), with the default directions annotate and route use. "0"
 * without photon frames. */
#define LIGHT_SIDE 4
#define LIGHT_EDGES 16
#define LIGHT_LAMPS 16
#define LIGHT_POINTS (LIGHT_SIDE * LIGHT_SIDE + LIGHT_EDGES + LIGHT_LAMPS)
static void light_hash(const network *net, plx_engine *e, char out[17])
{
    plx_scene_info si;
    plx_indirect_info ii;
    double P[3 * LIGHT_POINTS], N[3 * LIGHT_POINTS], E[2][LIGHT_POINTS], v[7];
    uint64_t h = 14695981039346656037u;
    uint32_t i, j, k, n = 0;
    if (plx_indirect_frames(e) == 0 || plx_scene_info_get(e, &si) != PLX_OK) {
        snprintf(out, 17, "0");
        return;
    }
    memset(&ii, 0, sizeof ii);
    (void)plx_indirect_info_get(e, &ii);
    v[0] = (double)ii.bytes;
    v[1] = ii.chart_w;
    v[2] = ii.chart_h;
    v[3] = ii.aerial_w;
    v[4] = ii.aerial_h;
    v[5] = ii.aerial_texel;
    v[6] = (double)plx_indirect_photons(e);
    h = fnv(h, v, sizeof v);
    for (j = 0; j < LIGHT_SIDE; j++)
        for (i = 0; i < LIGHT_SIDE; i++, n++) {
            P[3 * n] = si.bounds[0] + (si.bounds[2] - si.bounds[0]) * (i + 0.5) / LIGHT_SIDE;
            P[3 * n + 1] = si.bounds[1] + (si.bounds[3] - si.bounds[1]) * (j + 0.5) / LIGHT_SIDE;
        }
    for (k = 0; k < LIGHT_EDGES && k < net->nedges; k++, n++) {
        uint32_t m = LIGHT_EDGES < net->nedges ? LIGHT_EDGES : net->nedges;
        const net_edge *ed = &net->edges[(uint64_t)k * net->nedges / m];
        const double *xy = net->lines.lines[ed->line].xy + 2 * ed->v0;
        P[3 * n] = xy[0];
        P[3 * n + 1] = xy[1];
    }
    for (k = 0; k < LIGHT_LAMPS && k < si.lamps; k++) {
        plx_lamp l;
        uint32_t m = LIGHT_LAMPS < si.lamps ? LIGHT_LAMPS : si.lamps;
        if (plx_lamp_get(e, (uint32_t)((uint64_t)k * si.lamps / m), &l) != PLX_OK)
            continue;
        P[3 * n] = l.x + 1.0;
        P[3 * n + 1] = l.y;
        n++;
    }
    for (k = 0; k < n; k++) {
        P[3 * k + 2] = 0.0;
        N[3 * k] = N[3 * k + 1] = 0.0;
        N[3 * k + 2] = 1.0;
    }
    if (plx_illuminance(e, n, P, N, E[0], E[1], NULL) == PLX_E_NOMEM) {
        snprintf(out, 17, "nomem");
        return;
    }
    for (k = 0; k < n; k++) { /* inside a building: NaN, as the same bits every time */
        E[0][k] = isnan(E[0][k]) ? -1.0 : E[0][k];
        E[1][k] = isnan(E[1][k]) ? -1.0 : E[1][k];
    }
    h = fnv(h, E[0], sizeof E[0][0] * n);
    h = fnv(h, E[1], sizeof E[1][0] * n);
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

/* A hash of the network as routes read it: every edge in order, its
 * vertices (local metres, as projected) and its light (the -1 of no
 * meter for NaN), as 16 hex digits. annotate writes it; route compares it
 * with the network it read back, so a file whose coordinates or scores
 * changed (edited, or numbers that did not read back to the same bits) is
 * refused rather than routed over. */
static void edges_hash(const network *net, char out[17])
{
    uint64_t h = 14695981039346656037u;
    uint32_t i;
    int k;
    for (i = 0; i < net->nedges; i++) {
        const net_edge *ed = &net->edges[i];
        const double *xy = net->lines.lines[ed->line].xy + 2 * ed->v0;
        double v[11];
        h = fnv(h, xy, sizeof *xy * 2 * ((size_t)ed->v1 - ed->v0 + 1));
        v[0] = ed->s.length;
        v[1] = ed->s.blocked_length;
        v[2] = ed->dark;
        v[3] = ed->s.mean;
        v[4] = ed->s.min;
        v[5] = ed->s.max;
        v[6] = ed->s.uniformity;
        for (k = 0; k < 4; k++)
            v[7 + k] = net_or_none(ed->fac[k]);
        h = fnv(h, v, sizeof v);
        h = fnv(h, &ed->s.p_class, sizeof ed->s.p_class);
    }
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

cJSON *net_scores_header(const network *net, plx_engine *e)
{
    cJSON *h = cJSON_CreateObject();
    double sc[3];
    char hash[17];
    if (!h)
        return NULL;
    scene_counts(e, sc);
    scene_hash(e, hash);
    add_exact(h, "version", NET_SCORES_VERSION);
    add_exact(h, "step", net->step);
    add_exact(h, "dark_lux", net->dark_lux);
    add_exact(h, "height", net->height);
    add_exact(h, "edges", net->nedges);
    add_exact(h, "nodes", net->nnodes);
    add_exact(h, "buildings", sc[0]);
    add_exact(h, "lamps", sc[1]);
    add_exact(h, "photon_frames", sc[2]);
    cJSON_AddStringToObject(h, "scene_hash", hash);
    light_hash(net, e, hash);
    cJSON_AddStringToObject(h, "light_hash", hash);
    edges_hash(net, hash);
    cJSON_AddStringToObject(h, "edges_hash", hash);
    return h;
}

/* Member k of object o as a number into *v; 0, or -1 when it is not one. */
static int number(const cJSON *o, const char *k, double *v)
{
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(o, k);
    if (!cJSON_IsNumber(n)) /* also null: add_exact's value that was not finite, which a route cannot use */
        return -1;
    *v = n->valuedouble;
    return 0;
}

/* The hash the header holds under key when it differs from 'have'
 * ("none" when it holds none), NULL when they agree. */
static const char *hash_differs(const cJSON *h, const char *key, const char *have)
{
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(h, key);
    if (!cJSON_IsString(s))
        return "none";
    return strcmp(s->valuestring, have) != 0 ? s->valuestring : NULL;
}

/* The settings and the scene against the header; 0, or -1 with why. */
static int check_header(const network *net, const cJSON *h, plx_engine *e, int *usage, char *err, size_t errlen)
{
    static const char *const opt[3] = { "--step", "--dark-lux", "--height" };
    static const char *const key[3] = { "step", "dark_lux", "height" };
    double have[3], sc[3], want[3], v;
    const char *there;
    char hash[17];
    int k;
    have[0] = net->step;
    have[1] = net->dark_lux;
    have[2] = net->height;
    if (number(h, "version", &v) != 0 || v != NET_SCORES_VERSION) {
        snprintf(err, errlen, "%s member is not version %d (written by another polarlux)", NET_SCORES_MEMBER,
                 NET_SCORES_VERSION);
        return -1;
    }
    for (k = 0; k < 3; k++) {
        if (number(h, key[k], &v) != 0) {
            snprintf(err, errlen, "%s member has no number '%s'", NET_SCORES_MEMBER, key[k]);
            return -1;
        }
        if (v != have[k]) {
            *usage = 1;
            snprintf(err, errlen, "its edges were scored with %s %g, not %g: pass %s %g, or run annotate again", opt[k],
                     v, have[k], opt[k], v);
            return -1;
        }
    }
    scene_counts(e, sc);
    if (number(h, "buildings", &want[0]) != 0 || number(h, "lamps", &want[1]) != 0 ||
        number(h, "photon_frames", &want[2]) != 0) {
        snprintf(err, errlen, "%s member has no scene counts (buildings, lamps, photon_frames)", NET_SCORES_MEMBER);
        return -1;
    }
    if (want[0] != sc[0] || want[1] != sc[1] || want[2] != sc[2]) {
        snprintf(err, errlen, "its edges were scored on another scene or light (buildings, lamps, photon frames: "
                 "%.0f, %.0f, %.0f there; %.0f, %.0f, %.0f here): run annotate again on this scene, or route over "
                 "the plain street network", want[0], want[1], want[2], sc[0], sc[1], sc[2]);
        return -1;
    }
    scene_hash(e, hash);
    if ((there = hash_differs(h, "scene_hash", hash)) != NULL) {
        snprintf(err, errlen, "its edges were scored on another scene (the same counts, but the buildings' or "
                 "lamps' positions, heights, intensities, colours or photometry differ: scene_hash %s there, %s here): run "
                 "annotate again on this scene, or route over the plain street network", there, hash);
        return -1;
    }
    if (number(h, "edges", &v) != 0 || v != net->nedges || number(h, "nodes", &want[0]) != 0 ||
        want[0] != net->nnodes) {
        snprintf(err, errlen, "its lines join into %u edges and %u nodes, not the ones annotate wrote (an edited "
                 "file?): run annotate again", net->nedges, net->nnodes);
        return -1;
    }
    light_hash(net, e, hash); /* on the same edges as annotate's (checked just above) */
    if ((there = hash_differs(h, "light_hash", hash)) != NULL) {
        snprintf(err, errlen, "its edges were scored with other indirect light (the same scene and photon frames, "
                 "but other photons a frame: light_hash %s there, %s here): run annotate again on this bake, or "
                 "route over the plain street network", there, hash);
        return -1;
    }
    return 0;
}

/* Edge i's scores from its feature's properties p; 0, or -1 with why. */
static int read_edge(net_edge *ed, const cJSON *p, uint32_t feature, char *err, size_t errlen)
{
    static const char *const key[11] = { "scored_m", "blocked_m", "below_m", "mean_lux", "min_lux", "max_lux",
                                          "uniformity", "min_ev_fw_lux", "min_ev_bw_lux", "min_sc_fw_lux",
                                          "min_sc_bw_lux" };
    double v[11];
    const cJSON *ch = cJSON_GetObjectItemCaseSensitive(p, "class_h");
    int k;
    for (k = 0; k < 11; k++)
        if (number(p, key[k], &v[k]) != 0) {
            snprintf(err, errlen, "feature %u: no number '%s' (not as annotate wrote it)", feature, key[k]);
            return -1;
        }
    if (!cJSON_IsString(ch) || !(strcmp(ch->valuestring, "-") == 0 ||
                                 (ch->valuestring[0] == 'P' && ch->valuestring[1] >= '1' &&
                                  ch->valuestring[1] <= '6' && ch->valuestring[2] == '\0'))) {
        snprintf(err, errlen, "feature %u: class_h is not P1 .. P6 or '-'", feature);
        return -1;
    }
    memset(&ed->s, 0, sizeof ed->s);
    ed->s.length = v[0];
    ed->s.blocked_length = v[1];
    ed->dark = v[2];
    ed->s.mean = v[3];
    ed->s.min = v[4];
    ed->s.max = v[5];
    ed->s.uniformity = v[6];
    ed->s.dark_share = v[0] > 0 ? v[2] / v[0] : 0.0;
    ed->s.p_class = ch->valuestring[0] == 'P' ? ch->valuestring[1] - '0' : 0;
    for (k = 0; k < 4; k++)
        ed->fac[k] = v[7 + k] < 0 ? NAN : v[7 + k]; /* -1: no meter */
    return 0;
}

int net_scores_read(network *net, const cJSON *doc, plx_engine *e, int *usage, char *err, size_t errlen)
{
    const cJSON *h = cJSON_GetObjectItemCaseSensitive(doc, NET_SCORES_MEMBER), *features, *ft;
    const cJSON **byf;
    const char *there;
    char hash[17];
    size_t nf = 0;
    uint32_t i;
    int rc = 0;
    *usage = 0;
    if (!h)
        return 1;
    if (check_header(net, h, e, usage, err, errlen) != 0)
        return -1;
    features = cJSON_GetObjectItemCaseSensitive(doc, "features");
    byf = malloc(sizeof *byf * ((size_t)cJSON_GetArraySize(features) + 1));
    if (!byf) {
        snprintf(err, errlen, "out of memory reading the scores");
        return -1;
    }
    cJSON_ArrayForEach(ft, features) byf[nf++] = ft;
    for (i = 0; i < net->nedges && rc == 0; i++) {
        net_edge *ed = &net->edges[i];
        const route_line *l = &net->lines.lines[ed->line];
        if (ed->v0 != 0 || ed->v1 + 1 != l->n || l->feature >= nf || (ed->line > 0 && l[-1].feature == l->feature)) {
            snprintf(err, errlen, "feature %u is not one edge of the network (not as annotate wrote it)", l->feature);
            rc = -1;
            break;
        }
        rc = read_edge(ed, cJSON_GetObjectItemCaseSensitive(byf[l->feature], "properties"), l->feature, err,
                       errlen);
    }
    free(byf);
    if (rc != 0)
        return -1;
    edges_hash(net, hash);
    if ((there = hash_differs(h, "edges_hash", hash)) != NULL) {
        snprintf(err, errlen, "its edges' coordinates or light are not those annotate wrote (edges_hash %s there, "
                 "%s here: an edited file, or coordinates that did not read back to the same bits): run annotate "
                 "again, or route over the plain street network", there, hash);
        return -1;
    }
    for (i = 0; i < net->nedges; i++)
        net->scored[i] = 1;
    net->partial = 0;
    return 0;
}
