/* abi_sizes: the layout of every C structure python/polarlux/_lib.py mirrors
 * with ctypes, for python/tests/test_abi.py (which compares it with
 * ctypes.sizeof and the Structure field offsets). A test tool: no part of
 * the library or its API.
 *
 * Output, one line each:
 *   struct NAME SIZE        (the C typedef name and its sizeof)
 *   field NAME FIELD OFFSET SIZE (offsetof and sizeof of every member)
 *
 * Every member of each structure is listed, not only the ones the Python
 * side declares, so a member the C structure gained shows up by name. When a
 * structure or member is added to include/polarlux.h (or a new structure is
 * mirrored in Python), add it here: test_abi.py fails naming what is missing.
 */
#include <stddef.h>
#include <stdio.h>
#include "polarlux.h"
#include "polarlux_port.h"

#define STRUCT(T) printf("struct %s %zu\n", #T, sizeof(T))
#define FIELD(T, f) printf("field %s %s %zu %zu\n", #T, #f, offsetof(T, f), sizeof(((T *)0)->f))

static void port(void)
{
    STRUCT(plx_port);
    FIELD(plx_port, ctx);
    FIELD(plx_port, clock_ns);
    FIELD(plx_port, log);
    FIELD(plx_port, file_size);
    FIELD(plx_port, file_read);
    FIELD(plx_port, lock);
    FIELD(plx_port, unlock);
    FIELD(plx_port, parallel_for);
    FIELD(plx_port, cores);
    FIELD(plx_port, file_map);
    FIELD(plx_port, file_unmap);
    FIELD(plx_port, progress);
}

static void config(void)
{
    STRUCT(plx_config);
    FIELD(plx_config, port);
    FIELD(plx_config, strict);
    FIELD(plx_config, part_budget);
    FIELD(plx_config, lit_cache_bytes);
    FIELD(plx_config, render_max_width);
    FIELD(plx_config, render_max_height);
    FIELD(plx_config, lightmap_bytes);
    FIELD(plx_config, photon_bytes);
    FIELD(plx_config, threads);
}

static void scene_info(void)
{
    STRUCT(plx_scene_info);
    FIELD(plx_scene_info, buildings);
    FIELD(plx_scene_info, raised);
    FIELD(plx_scene_info, blocks);
    FIELD(plx_scene_info, courtyards);
    FIELD(plx_scene_info, holes);
    FIELD(plx_scene_info, lamps);
    FIELD(plx_scene_info, vertices);
    FIELD(plx_scene_info, skipped_features);
    FIELD(plx_scene_info, skipped_lamps);
    FIELD(plx_scene_info, overlapping_pairs);
    FIELD(plx_scene_info, lonlat);
    FIELD(plx_scene_info, lon0);
    FIELD(plx_scene_info, lat0);
    FIELD(plx_scene_info, bounds);
    FIELD(plx_scene_info, height_min);
    FIELD(plx_scene_info, height_median);
    FIELD(plx_scene_info, height_max);
    FIELD(plx_scene_info, ground_albedo);
    FIELD(plx_scene_info, load_ns);
    FIELD(plx_scene_info, merged_lamps);
}

static void visibility(void)
{
    STRUCT(plx_visibility);
    FIELD(plx_visibility, area);
    FIELD(plx_visibility, nverts);
    FIELD(plx_visibility, xy);
    FIELD(plx_visibility, nvisible);
    FIELD(plx_visibility, visible);
}

static void route_stats(void)
{
    STRUCT(plx_route_stats);
    FIELD(plx_route_stats, length);
    FIELD(plx_route_stats, mean);
    FIELD(plx_route_stats, min);
    FIELD(plx_route_stats, max);
    FIELD(plx_route_stats, uniformity);
    FIELD(plx_route_stats, dark_share);
    FIELD(plx_route_stats, p_class);
    FIELD(plx_route_stats, samples);
    FIELD(plx_route_stats, blocked_length);
}

static void camera(void)
{
    STRUCT(plx_camera);
    FIELD(plx_camera, eye);
    FIELD(plx_camera, target);
    FIELD(plx_camera, fov_deg);
    FIELD(plx_camera, width);
    FIELD(plx_camera, height);
}

static void render_opts(void)
{
    STRUCT(plx_render_opts);
    FIELD(plx_render_opts, exposure);
    FIELD(plx_render_opts, no_glow);
    FIELD(plx_render_opts, aerial);
    FIELD(plx_render_opts, aerial_m_per_texel);
    FIELD(plx_render_opts, no_cull);
    FIELD(plx_render_opts, no_indirect);
    FIELD(plx_render_opts, backend);
    FIELD(plx_render_opts, auto_exposure);
    FIELD(plx_render_opts, aa);
    FIELD(plx_render_opts, aa_full);
    FIELD(plx_render_opts, per_pixel);
    FIELD(plx_render_opts, exposure_step);
}

static void render_info(void)
{
    STRUCT(plx_render_info);
    FIELD(plx_render_info, buildings);
    FIELD(plx_render_info, drawn);
    FIELD(plx_render_info, drawn_fraction);
    FIELD(plx_render_info, shaded_pixels);
    FIELD(plx_render_info, exposure);
    FIELD(plx_render_info, indirect_lookups);
    FIELD(plx_render_info, aa_later);
    FIELD(plx_render_info, aa_adaptive);
    FIELD(plx_render_info, eye_inside);
}

static void scene_size(void)
{
    STRUCT(plx_scene_size);
    FIELD(plx_scene_size, text_bytes);
    FIELD(plx_scene_size, json_values);
    FIELD(plx_scene_size, string_bytes);
    FIELD(plx_scene_size, features);
    FIELD(plx_scene_size, points);
    FIELD(plx_scene_size, positions);
    FIELD(plx_scene_size, rings);
}

static void memory_report(void)
{
    STRUCT(plx_memory_report);
    FIELD(plx_memory_report, capacity);
    FIELD(plx_memory_report, used);
    FIELD(plx_memory_report, peak);
    FIELD(plx_memory_report, used_total);
    FIELD(plx_memory_report, peak_total);
}

static void ground_image_info(void)
{
    STRUCT(plx_ground_image_info);
    FIELD(plx_ground_image_info, path);
    FIELD(plx_ground_image_info, bounds_given);
    FIELD(plx_ground_image_info, bounds);
    FIELD(plx_ground_image_info, width);
    FIELD(plx_ground_image_info, height);
    FIELD(plx_ground_image_info, mean_albedo);
    FIELD(plx_ground_image_info, mean_luminance);
}

int main(void)
{
    port();
    config();
    scene_info();
    visibility();
    route_stats();
    camera();
    render_opts();
    render_info();
    scene_size();
    memory_report();
    ground_image_info();
    return fflush(stdout) == 0 ? 0 : 1;
}
