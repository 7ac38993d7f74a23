/* polarlux lit SCENE --lamp ID -o lit.geojson: a lamp's lit region. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "options.h"
#include "geo_out.h"
#include "lit_union.h"

static const char help[] =
    "usage: polarlux lit SCENE --lamp ID -o OUT.geojson [options]\n"
    "\n"
    "Writes the lit region of one lamp within its reach as GeoJSON: the lit\n"
    "ground as one polygon per connected region with holes where shadows are\n"
    "(z = 0, property kind = \"ground\"; the exact union of the engine's\n"
    "pieces, whose summed area is printed beside the union's) and lit facade\n"
    "polygons with\n"
    "3D coordinates (kind = \"facade\", with the building), plus the lamp as a\n"
    "point. Coordinates are lon/lat when the scene was lon/lat, else metres.\n"
    "\n"
    "  --lamp ID   the lamp's id (properties.id, e.g. node/314737872) or its\n"
    "              index among the loaded lamps (0, 1, ...)\n"
    "  -o FILE     output file (required)\n"
    "  --mem SIZE, --strict, --quiet, --lamps FILE   as for 'polarlux info'\n";

/* The lamp index for ID: an id string first, else a whole number index. */
static long find_lamp(plx_engine *e, const char *id)
{
    plx_scene_info si;
    uint32_t i;
    long v;
    plx_scene_info_get(e, &si);
    for (i = 0; i < si.lamps; i++) {
        plx_lamp l;
        plx_lamp_get(e, i, &l);
        if (l.id && strcmp(l.id, id) == 0)
            return (long)i;
    }
    if (cli_parse_int(id, 0, (long)si.lamps - 1, &v) == 0)
        return v;
    return -1;
}

/* The lit ground as one polygon per connected region, holes where shadows
 * are (the exact union of the region's pieces, lit_union.c); *area gets
 * its area and *pieces the pieces' summed area. */
static int add_ground(plx_engine *e, geo_out *g, const plx_lit_region *r, size_t *npoly, double *area,
                      double *pieces)
{
    const double **xy = malloc(sizeof *xy * (r->nground + 1));
    uint32_t *n = malloc(sizeof *n * (r->nground + 1)), k;
    lit_union u;
    size_t i, j;
    *npoly = 0;
    *area = *pieces = 0.0;
    if (!xy || !n) {
        free(xy), free(n);
        return -1;
    }
    for (k = 0; k < r->nground; k++) {
        uint32_t m;
        plx_lit_ground(e, k, &xy[k], &n[k]);
        for (m = 0; m < n[k]; m++) {
            uint32_t q = (m + 1) % n[k];
            *pieces += 0.5 * (xy[k][2 * m] * xy[k][2 * q + 1] - xy[k][2 * q] * xy[k][2 * m + 1]);
        }
    }
    if (lit_union_build(xy, n, r->nground, &u) != 0) {
        free(xy), free(n);
        return -1;
    }
    for (i = 0; i < u.nrings; i++) {
        cJSON *rings, *props;
        *area += u.rings[i].area;
        if (u.rings[i].area <= 0)
            continue;
        rings = cJSON_CreateArray();
        cJSON_AddItemToArray(rings, geo_ring(g, u.rings[i].xy, (uint32_t)u.rings[i].n, NULL));
        for (j = 0; j < u.nrings; j++)
            if (u.rings[j].outer == (long)i)
                cJSON_AddItemToArray(rings, geo_ring(g, u.rings[j].xy, (uint32_t)u.rings[j].n, NULL));
        props = cJSON_CreateObject();
        cJSON_AddStringToObject(props, "kind", "ground");
        geo_add(g, geo_geometry("Polygon", rings), props);
        (*npoly)++;
    }
    lit_union_free(&u);
    free(xy), free(n);
    return 0;
}

static int write_region(plx_engine *e, uint32_t lamp, const char *out, const cli_common *c)
{
    size_t npoly;
    double area, pieces;
    plx_lit_region r;
    plx_lamp l;
    geo_out g;
    uint32_t k;
    cJSON *props;
    plx_status st = plx_lit_region_get(e, lamp, &r);
    if (st != PLX_OK) {
        fprintf(stderr, "polarlux lit: %s\n", plx_last_error(e));
        return cli_exit_code(st);
    }
    if (geo_begin(&g, e) != 0) {
        fprintf(stderr, "polarlux lit: out of memory\n");
        return EXIT_FAIL;
    }
    plx_lamp_get(e, lamp, &l);
    if (r.nground == 0 && r.nfacade == 0)
        cli_warn("lit", c, "lamp %u lights nothing: %s", lamp,
                 l.intensity > 0 ? "its radius does not reach the ground or a facade" : "its intensity is 0 cd");
    props = cJSON_CreateObject();
    cJSON_AddStringToObject(props, "kind", "lamp");
    cJSON_AddStringToObject(props, "id", l.id ? l.id : "");
    cJSON_AddNumberToObject(props, "z", l.z);
    cJSON_AddNumberToObject(props, "intensity", l.intensity);
    cJSON_AddNumberToObject(props, "radius", l.radius);
    geo_add(&g, geo_geometry("Point", geo_position(&g, l.x, l.y, NULL)), props);
    if (add_ground(e, &g, &r, &npoly, &area, &pieces) != 0) {
        geo_free(&g);
        fprintf(stderr, "polarlux lit: out of memory\n");
        return EXIT_FAIL;
    }
    for (k = 0; k < r.nfacade; k++) {
        const double *xyz;
        uint32_t n, bld, i;
        plx_building b;
        double *xy, *z;
        cJSON *rings = cJSON_CreateArray();
        plx_lit_facade(e, k, &xyz, &n, &bld);
        xy = malloc(sizeof *xy * 2 * n);
        z = malloc(sizeof *z * n);
        if (!xy || !z) {
            free(xy);
            free(z);
            geo_free(&g);
            fprintf(stderr, "polarlux lit: out of memory\n");
            return EXIT_FAIL;
        }
        for (i = 0; i < n; i++) {
            xy[2 * i] = xyz[3 * i];
            xy[2 * i + 1] = xyz[3 * i + 1];
            z[i] = xyz[3 * i + 2];
        }
        cJSON_AddItemToArray(rings, geo_ring(&g, xy, n, z));
        free(xy);
        free(z);
        plx_building_get(e, bld, &b);
        props = cJSON_CreateObject();
        cJSON_AddStringToObject(props, "kind", "facade");
        cJSON_AddNumberToObject(props, "building", bld);
        if (b.id)
            cJSON_AddStringToObject(props, "building_id", b.id);
        geo_add(&g, geo_geometry("Polygon", rings), props);
    }
    if (geo_write(&g, "lit", out) != 0) {
        geo_free(&g);
        return EXIT_FAIL;
    }
    geo_free(&g);
    printf("lamp %u (%s): %zu lit ground polygons, %u lit facade polygons, written to %s; the ground is the union "
           "of %u pieces: area %.6f m^2 (pieces %.6f m^2)\n", lamp, l.id ? l.id : "-", npoly, r.nfacade, out,
           r.nground, area, pieces);
    return EXIT_OK;
}

int cmd_lit(int argc, char **argv)
{
    cli_common c;
    const char *scene, *id = NULL, *out = NULL;
    const cli_opt opts[] = {
        { "--lamp", NULL, &id, NULL, NULL, 0, NULL, NULL, NULL },
        { "-o", NULL, &out, NULL, NULL, 0, NULL, NULL, NULL },
        CLI_OPT_END
    };
    cli_args pa;
    plx_engine *e;
    long lamp;
    int rc;
    memset(&c, 0, sizeof c);
    rc = cli_options("lit", help, argc, argv, opts, &c, NULL, &pa);
    if (rc != EXIT_OK)
        return rc < 0 ? EXIT_OK : rc;
    if (pa.npos > 1)
        return cli_usage_error("lit", "unexpected argument '%s'", pa.pos[1]);
    scene = pa.npos ? pa.pos[0] : NULL;
    if (!scene)
        return cli_usage_error("lit", "missing SCENE");
    if (!id)
        return cli_usage_error("lit", "missing --lamp ID");
    if (!out)
        return cli_usage_error("lit", "missing -o OUT.geojson");
    if (!cli_out_writable("lit", out))
        return EXIT_FAIL;
    rc = cli_open_scene("lit", scene, &c, &e);
    if (rc != EXIT_OK)
        return rc;
    lamp = find_lamp(e, id);
    if (lamp < 0) {
        fprintf(stderr, "polarlux lit: no lamp with id or index '%s' in %s\n", id, scene);
        rc = EXIT_FAIL;
    } else {
        rc = write_region(e, (uint32_t)lamp, out, &c);
    }
    plx_engine_free(e);
    return rc;
}
