/* annotate's scores kept with a street network: annotate writes every
 * edge's light into its GeoJSON with the settings and the scene it was
 * scored for (the collection's "polarlux_scores" member), and route
 * --network reads them back instead of scoring the edges again.
 *
 * What a route needs of an edge is written so that it reads back as the
 * same doubles (cJSON prints numbers that read back exactly): scored_m,
 * blocked_m, below_m (scored metres below --dark-lux: dark_m less
 * blocked_m, which no subtraction gives back exactly), mean_lux,
 * min_lux, max_lux, uniformity, the four E_v and E_sc minima (-1: no
 * meter) and class_h; annotate writes the coordinates so too
 * (geo_position_exact). The header's edges_hash (every edge's vertices
 * and light) is computed again over what was read: read back, the edges
 * hold what net_score gave them, so the routes are those of the scored
 * network, or the file is refused (edited, or numbers that did not read
 * back to the same bits). */
#ifndef PLX_CLI_NET_SCORES_H
#define PLX_CLI_NET_SCORES_H

#include <stddef.h>
#include <cjson/cJSON.h>
#include "network.h"

/* A P class as text (P1 .. P6, '-' for none). */
void net_class_text(int c, char out[4]);
/* The SPEC §6 class with every criterion (0: none, also without a meter). */
int net_full_class(double scored, double mean, double min, double min_ev, double min_esc);
/* v, or -1 for NaN (no meter). */
double net_or_none(double v);

#define NET_SCORES_MEMBER "polarlux_scores"
#define NET_SCORES_VERSION 3 /* 3: light_hash (2026-12-03) */

/* Edge i's properties as annotate writes them (weight W for cost and
 * factor); NULL when out of memory. */
cJSON *net_scores_edge_props(const network *net, uint32_t i, const char *osm_id, const char *name, double weight);

/* The collection's member naming how the edges were scored: the settings,
 * the network's counts, and the scene (its buildings and lamps, the photon
 * frames of its indirect light) as e holds it. NULL when out of memory. */
cJSON *net_scores_header(const network *net, plx_engine *e);

/* The scores of doc (the network file's GeoJSON, net built from its lines)
 * put into net's edges, every edge marked scored, when doc holds
 * annotate's scores: 0. 1 when it holds none (a plain network: nothing
 * done). -1 when they cannot be used, with why in err: the settings
 * (net_set_scoring's, set before) or the scene e differ from those the
 * scores were made for (*usage 1: the options differ), or the file is not
 * as annotate wrote it (*usage 0). */
int net_scores_read(network *net, const cJSON *doc, plx_engine *e, int *usage /* OUT */, char *err, size_t errlen);

#endif
