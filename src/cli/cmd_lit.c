/* polarlux lit SCENE --lamp ID -o lit.geojson: a lamp's lit region. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "geo_out.h"

static const char help[] =
    "usage: polarlux lit SCENE --lamp ID -o OUT.geojson [options]\n"
    "\n"
    "Writes the lit region of one lamp within its reach as GeoJSON: lit ground\n"
    "polygons (z = 0, property kind = \"ground\") and lit facade polygons with\n"
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

static int write_region(plx_engine *e, uint32_t lamp, const char *out, const cli_common *c)
{
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
    for (k = 0; k < r.nground; k++) {
        const double *xy;
        uint32_t n;
        cJSON *rings = cJSON_CreateArray();
        plx_lit_ground(e, k, &xy, &n);
        cJSON_AddItemToArray(rings, geo_ring(&g, xy, n, NULL));
        props = cJSON_CreateObject();
        cJSON_AddStringToObject(props, "kind", "ground");
        geo_add(&g, geo_geometry("Polygon", rings), props);
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
    printf("lamp %u (%s): %u lit ground polygons, %u lit facade polygons, written to %s\n", lamp,
           l.id ? l.id : "-", r.nground, r.nfacade, out);
    return EXIT_OK;
}

int cmd_lit(int argc, char **argv)
{
    cli_common c;
    const char *scene = NULL, *id = NULL, *out = NULL;
    plx_engine *e;
    long lamp;
    int i, rc;
    memset(&c, 0, sizeof c);
    for (i = 1; i < argc; i++) {
        int r = cli_common_option("lit", argc, argv, &i, &c);
        if (r < 0)
            return EXIT_USAGE;
        if (r)
            continue;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(help, stdout);
            return EXIT_OK;
        }
        if ((strcmp(argv[i], "--lamp") == 0 || strcmp(argv[i], "-o") == 0) && i + 1 >= argc)
            return cli_usage_error("lit", "%s needs a value", argv[i]);
        if (strcmp(argv[i], "--lamp") == 0)
            id = argv[++i];
        else if (strcmp(argv[i], "-o") == 0)
            out = argv[++i];
        else if (argv[i][0] == '-' && argv[i][1] != '\0')
            return cli_usage_error("lit", "unknown option '%s'", argv[i]);
        else if (!scene)
            scene = argv[i];
        else
            return cli_usage_error("lit", "unexpected argument '%s'", argv[i]);
    }
    if (!scene)
        return cli_usage_error("lit", "missing SCENE");
    if (!id)
        return cli_usage_error("lit", "missing --lamp ID");
    if (!out)
        return cli_usage_error("lit", "missing -o OUT.geojson");
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
