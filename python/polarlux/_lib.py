"""ctypes declarations of include/polarlux.h (the calls this package uses).

Structures the engine fills are given buffers larger than the structures
declared here (see _padded), so a library whose structures grew at the end
cannot write past them. Each structure names the C structure it mirrors
(_c_name_); python/tests/test_abi.py compares sizes and field offsets with
the C compiler's (tests/abi_sizes.c), so keep both in step with the headers.
"""
import ctypes
import ctypes.util
import os

c_double_p = ctypes.POINTER(ctypes.c_double)
c_uint32_p = ctypes.POINTER(ctypes.c_uint32)
c_uint8_p = ctypes.POINTER(ctypes.c_uint8)

PART_COUNT = 7

# plx_status
OK, E_INVALID, E_NOMEM, E_IO, E_PARSE, E_SCENE, E_NOSCENE, E_RANGE, E_UNSUPPORTED = range(9)
STATUS_NAMES = ["PLX_OK", "PLX_E_INVALID", "PLX_E_NOMEM", "PLX_E_IO", "PLX_E_PARSE", "PLX_E_SCENE",
                "PLX_E_NOSCENE", "PLX_E_RANGE", "PLX_E_UNSUPPORTED"]

USE_VISIBILITY, USE_LIGHT, USE_RENDER = 1, 2, 4
# plx_render_opts.auto_exposure (PLX_EXPOSURE_* in polarlux.h; test_polarlux checks them)
EXPOSURE_FIXED, EXPOSURE_AUTO, EXPOSURE_ADAPT, EXPOSURE_TONE = 0, 1, 2, 3

LOG_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p)


class Port(ctypes.Structure):
    _c_name_ = "plx_port"
    _fields_ = [("ctx", ctypes.c_void_p), ("clock_ns", ctypes.c_void_p), ("log", LOG_FN),
                ("file_size", ctypes.c_void_p), ("file_read", ctypes.c_void_p),
                ("lock", ctypes.c_void_p), ("unlock", ctypes.c_void_p),
                ("parallel_for", ctypes.c_void_p), ("cores", ctypes.c_void_p),
                ("file_map", ctypes.c_void_p), ("file_unmap", ctypes.c_void_p),
                ("progress", ctypes.c_void_p)]


class Config(ctypes.Structure):
    _c_name_ = "plx_config"
    _fields_ = [("port", ctypes.POINTER(Port)), ("strict", ctypes.c_int),
                ("part_budget", ctypes.c_size_t * PART_COUNT), ("lit_cache_bytes", ctypes.c_size_t),
                ("render_max_width", ctypes.c_int32), ("render_max_height", ctypes.c_int32),
                ("lightmap_bytes", ctypes.c_size_t), ("photon_bytes", ctypes.c_size_t),
                ("threads", ctypes.c_int)]


class SceneInfo(ctypes.Structure):
    _c_name_ = "plx_scene_info"
    _fields_ = [(n, ctypes.c_uint32) for n in
                ("buildings", "raised", "blocks", "courtyards", "holes", "lamps", "vertices",
                 "skipped_features", "skipped_lamps", "overlapping_pairs")] + [
                ("lonlat", ctypes.c_int), ("lon0", ctypes.c_double), ("lat0", ctypes.c_double),
                ("bounds", ctypes.c_double * 4), ("height_min", ctypes.c_double),
                ("height_median", ctypes.c_double), ("height_max", ctypes.c_double),
                ("ground_albedo", ctypes.c_double), ("load_ns", ctypes.c_uint64),
                ("merged_lamps", ctypes.c_uint32)]


class Visibility(ctypes.Structure):
    _c_name_ = "plx_visibility"
    _fields_ = [("area", ctypes.c_double), ("nverts", ctypes.c_uint32), ("xy", c_double_p),
                ("nvisible", ctypes.c_uint32), ("visible", c_uint32_p)]


class RouteStats(ctypes.Structure):
    _c_name_ = "plx_route_stats"
    _fields_ = [("length", ctypes.c_double), ("mean", ctypes.c_double), ("min", ctypes.c_double),
                ("max", ctypes.c_double), ("uniformity", ctypes.c_double), ("dark_share", ctypes.c_double),
                ("p_class", ctypes.c_int), ("samples", ctypes.c_uint32), ("blocked_length", ctypes.c_double)]


class Camera(ctypes.Structure):
    _c_name_ = "plx_camera"
    _fields_ = [("eye", ctypes.c_double * 3), ("target", ctypes.c_double * 3), ("fov_deg", ctypes.c_double),
                ("width", ctypes.c_int32), ("height", ctypes.c_int32)]


class RenderOpts(ctypes.Structure):
    _c_name_ = "plx_render_opts"
    _fields_ = [("exposure", ctypes.c_double), ("no_glow", ctypes.c_int), ("aerial", ctypes.c_int),
                ("aerial_m_per_texel", ctypes.c_double), ("no_cull", ctypes.c_int),
                ("no_indirect", ctypes.c_int), ("backend", ctypes.c_void_p),
                ("auto_exposure", ctypes.c_int), ("aa", ctypes.c_int),
                ("aa_full", ctypes.c_int), ("per_pixel", ctypes.c_int), ("exposure_step", ctypes.c_int)]


class RenderInfo(ctypes.Structure):
    _c_name_ = "plx_render_info"
    _fields_ = [("buildings", ctypes.c_uint32), ("drawn", ctypes.c_uint32),
                ("drawn_fraction", ctypes.c_double), ("shaded_pixels", ctypes.c_uint64),
                ("exposure", ctypes.c_double), ("indirect_lookups", ctypes.c_uint64),
                ("aa_later", ctypes.c_uint64), ("aa_adaptive", ctypes.c_int), ("eye_inside", ctypes.c_int)]


class SceneSize(ctypes.Structure):
    _c_name_ = "plx_scene_size"
    _fields_ = [(n, ctypes.c_uint64) for n in
                ("text_bytes", "json_values", "string_bytes", "features", "points", "positions", "rings")]


class MemoryReport(ctypes.Structure):
    _c_name_ = "plx_memory_report"
    _fields_ = [("capacity", ctypes.c_size_t), ("used", ctypes.c_size_t * PART_COUNT),
                ("peak", ctypes.c_size_t * PART_COUNT), ("used_total", ctypes.c_size_t),
                ("peak_total", ctypes.c_size_t)]


class GroundImageInfo(ctypes.Structure):
    _c_name_ = "plx_ground_image_info"
    _fields_ = [("path", ctypes.c_char_p), ("bounds_given", ctypes.c_int), ("bounds", ctypes.c_double * 4),
                ("width", ctypes.c_uint32), ("height", ctypes.c_uint32), ("mean_albedo", ctypes.c_double * 3),
                ("mean_luminance", ctypes.c_double)]


def padded(struct_type):
    """An instance of struct_type inside a 1 KiB zeroed buffer."""
    buf = ctypes.create_string_buffer(max(1024, ctypes.sizeof(struct_type)))
    obj = struct_type.from_buffer(buf)
    obj._keep = buf
    return obj


def _find_library():
    env = os.environ.get("POLARLUX_LIB")
    if env:
        return env
    here = os.path.dirname(os.path.abspath(__file__))
    built = os.path.join(here, "..", "..", "build", "libpolarlux.so")
    if os.path.exists(built):
        return built
    found = ctypes.util.find_library("polarlux")
    if found:
        return found
    raise OSError("libpolarlux.so not found: build it (make) or set POLARLUX_LIB")


def _declare(lib):
    E = ctypes.c_void_p  # plx_engine *
    st = ctypes.c_int
    sig = {
        "plx_strerror": (ctypes.c_char_p, [st]),
        "plx_version": (ctypes.c_char_p, []),
        "plx_config_default": (None, [ctypes.POINTER(Config)]),
        "plx_engine_create": (st, [ctypes.c_void_p, ctypes.c_size_t, ctypes.POINTER(Config),
                                   ctypes.POINTER(ctypes.c_void_p)]),
        "plx_engine_destroy": (None, [E]),
        "plx_last_error": (ctypes.c_char_p, [E]),
        "plx_warning_count": (ctypes.c_uint32, [E]),
        "plx_load_geojson": (st, [E, ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p]),
        "plx_scene_info_get": (st, [E, ctypes.c_void_p]),
        "plx_photometry_count": (ctypes.c_uint32, [E]),
        "plx_photometry_path": (st, [E, ctypes.c_uint32, ctypes.POINTER(ctypes.c_char_p)]),
        "plx_set_photometry": (st, [E, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p]),
        "plx_memory_get": (None, [E, ctypes.c_void_p]),
        "plx_polar_build": (st, [E]),
        "plx_visibility_get": (st, [E, ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                                    ctypes.c_void_p]),
        "plx_illuminance": (st, [E, ctypes.c_size_t, c_double_p, c_double_p, c_double_p, c_double_p,
                                 c_double_p]),
        "plx_route_facial": (st, [E, c_double_p, ctypes.c_uint32, ctypes.c_double, ctypes.c_double, c_double_p,
                                  c_double_p]),
        "plx_p_class_facial": (ctypes.c_int, [ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_double]),
        "plx_indirect_frames": (ctypes.c_uint64, [E]),
        "plx_meter": (st, [E, ctypes.c_size_t, c_double_p, c_double_p, c_double_p]),
        "plx_ground_image_get": (st, [E, ctypes.c_void_p]),
        "plx_route_score": (st, [E, c_double_p, ctypes.c_uint32, ctypes.c_double, ctypes.c_double,
                                 ctypes.c_void_p, ctypes.c_void_p]),
        "plx_render_opts_default": (None, [ctypes.c_void_p]),
        "plx_render": (st, [E, ctypes.POINTER(Camera), ctypes.c_void_p, c_uint8_p,
                            ctypes.POINTER(ctypes.c_float), ctypes.c_void_p]),
        "plx_lonlat_to_local": (st, [E, ctypes.c_size_t, c_double_p, c_double_p]),
        "plx_local_to_lonlat": (st, [E, ctypes.c_size_t, c_double_p, c_double_p]),
        "plx_scene_size_scan": (st, [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_void_p]),
        "plx_memory_estimate": (ctypes.c_size_t, [ctypes.c_void_p, ctypes.POINTER(Config), ctypes.c_uint]),
        "plx_bake_block_size": (st, [ctypes.c_void_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_size_t),
                                     ctypes.c_char_p, ctypes.c_size_t]),
        "plx_bake_load": (st, [ctypes.c_void_p, ctypes.c_size_t, ctypes.POINTER(Config), ctypes.c_void_p,
                               ctypes.c_size_t, ctypes.POINTER(ctypes.c_void_p), ctypes.c_char_p,
                               ctypes.c_size_t]),
    }
    for name, (res, args) in sig.items():
        fn = getattr(lib, name)
        fn.restype = res
        fn.argtypes = args
    return lib


lib = _declare(ctypes.CDLL(_find_library()))
