"""polarlux for Python: exact night lighting of 2.5D cities, over libpolarlux.so.

    import polarlux
    s = polarlux.Scene.from_file("fixtures/helsinki-centre.geojson")
    E_direct, E_indirect = s.illuminance(points_xy)          # (N,) lux
    m = s.meter(points_xyz, facing=(0, 1))                   # SPEC §6: E_h, E_v, E_sc, E_hs (N,) lux
    areas = s.visibility_areas(points_xy)                     # (N,) m^2, NaN where not free
    total, segments = s.route_score(line_xy, step=1.0)
    img = s.render(eye=(x, y, 1.7), target=(x2, y2, 1.0), size=(640, 480))   # (480, 640, 3) uint8

Coordinates are the scene's local metres (SPEC §1); lon/lat scenes convert
with Scene.lonlat_to_local / local_to_lonlat. Arrays go in and come out as
numpy arrays of float64 (images uint8 or float32). One Scene may be shared
by threads (its calls take turns). See README "Python".

Constants: USE_VISIBILITY, USE_LIGHT, USE_RENDER (memory_estimate's uses=,
or-ed: the polar diagrams; lamp light, lit regions and routes; frames at
the largest render size), EXPOSURE_FIXED, EXPOSURE_AUTO, EXPOSURE_ADAPT,
EXPOSURE_TONE (the header's plx_render_opts.auto_exposure, as
Scene.last_render reports them), BAKE_MAGIC (a bake file's first 8 bytes).
"""
import ctypes
import functools
import json
import mmap
import numbers
import os
import threading
import warnings as _warnings

import numpy as np

from . import _lib
from ._lib import lib

__version__ = lib.plx_version().decode()  # the loaded library's version (polarlux --version's)

__all__ = ["Scene", "PolarluxError", "MemoryBudgetError", "memory_estimate", "scene_size",
           "USE_VISIBILITY", "USE_LIGHT", "USE_RENDER"]

USE_VISIBILITY, USE_LIGHT, USE_RENDER = _lib.USE_VISIBILITY, _lib.USE_LIGHT, _lib.USE_RENDER
EXPOSURE_FIXED, EXPOSURE_AUTO, EXPOSURE_ADAPT, EXPOSURE_TONE = (_lib.EXPOSURE_FIXED, _lib.EXPOSURE_AUTO,
                                                                 _lib.EXPOSURE_ADAPT, _lib.EXPOSURE_TONE)


BAKE_MAGIC = b"PLXBAKE\0"  # a bake file's first 8 bytes (README "Bake files")


class PolarluxError(Exception):
    """A call failed: .status is the plx_status name, str() the engine's one-line message."""

    def __init__(self, status, message):
        self.status = _lib.STATUS_NAMES[status] if 0 <= status < len(_lib.STATUS_NAMES) else str(status)
        self.code = status
        super().__init__(f"{self.status}: {message}")


class MemoryBudgetError(PolarluxError):
    """PLX_E_NOMEM: the engine's block is too small (pass a larger mem=)."""


def _raise(status, message):
    cls = MemoryBudgetError if status == _lib.E_NOMEM else PolarluxError
    raise cls(status, message)


def _big_block(n):
    """n zeroed bytes of anonymous pages as a numpy array, asked to be huge
    pages where the system offers them (a bake's hundreds of megabytes then
    cost a few hundred page faults, not tens of thousands)."""
    m = mmap.mmap(-1, max(int(n), 1))
    if hasattr(m, "madvise") and hasattr(mmap, "MADV_HUGEPAGE"):
        m.madvise(mmap.MADV_HUGEPAGE)
    return np.frombuffer(m, dtype=np.uint8)


def _as_bytes(text):
    """GeoJSON as bytes: str (UTF-8), bytes-like, or a dict (json.load's)."""
    if isinstance(text, str):
        return text.encode("utf-8")
    if isinstance(text, (bytes, bytearray, memoryview)):
        return bytes(text)
    if isinstance(text, dict):
        return json.dumps(text).encode("utf-8")
    raise TypeError(f"a scene is GeoJSON text (str or bytes) or a dict, not {type(text).__name__}: "
                    "use Scene.from_file for a path")


def _engine_call(fn):
    """Runs a method with the Scene's lock held, once the Scene is known to
    be open: the engine's calls must not overlap (polarlux.h), and ctypes
    lets other threads run during each call, so threads sharing one Scene
    take turns (before 2026-12-03 four threads on one Scene crashed Python)."""
    @functools.wraps(fn)
    def call(self, *args, **kw):
        with self._lock:
            if not self._e:
                raise ValueError("the Scene is closed")
            return fn(self, *args, **kw)
    return call


def _dptr(a):
    return a.ctypes.data_as(_lib.c_double_p)


def _points(a, cols, what):
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.ndim == 1 and a.size == cols:
        a = a.reshape(1, cols)
    if a.ndim != 2 or a.shape[1] != cols:
        raise ValueError(f"{what} must have shape (N, {cols}), not {a.shape}")
    return a


def _config(lit_cache_bytes=0, render_max=(0, 0), strict=False, port=None):
    if int(lit_cache_bytes) < 0:
        raise ValueError(f"lit_cache_bytes must be 0 (the default) or more, not {lit_cache_bytes!r}")
    if len(render_max) != 2 or int(render_max[0]) < 0 or int(render_max[1]) < 0:
        raise ValueError(f"render_max must be (width, height), each 0 (the default, 1920x1080) or more, "
                         f"not {tuple(render_max)!r}")
    cfg = _lib.Config()
    lib.plx_config_default(ctypes.byref(cfg))
    cfg.strict = 1 if strict else 0
    cfg.lit_cache_bytes = int(lit_cache_bytes)
    cfg.render_max_width, cfg.render_max_height = int(render_max[0]), int(render_max[1])
    if port is not None:
        cfg.port = ctypes.pointer(port)
    return cfg


def scene_size(text):
    """plx_scene_size_scan: what a GeoJSON text holds, counted without parsing (a dict)."""
    data = _as_bytes(text)
    sz = _lib.padded(_lib.SceneSize)
    st = lib.plx_scene_size_scan(data, len(data), ctypes.byref(sz))
    if st != _lib.OK:
        _raise(st, "plx_scene_size_scan failed")
    return {name: getattr(sz, name) for name, _ in _lib.SceneSize._fields_}


def _estimate(data, uses, lit_cache_bytes, render_max, scan_checked=False):
    """plx_memory_estimate of GeoJSON bytes; the scan's failure raises only
    when scan_checked (Scene's sizing leaves it to the load, which says
    what is wrong with the text)."""
    sz = _lib.padded(_lib.SceneSize)
    st = lib.plx_scene_size_scan(data, len(data), ctypes.byref(sz))
    if scan_checked and st != _lib.OK:
        _raise(st, "plx_scene_size_scan failed")
    cfg = _config(lit_cache_bytes, render_max)
    return int(lib.plx_memory_estimate(ctypes.byref(sz), ctypes.byref(cfg), uses))


def memory_estimate(text, uses=USE_VISIBILITY | USE_LIGHT | USE_RENDER, lit_cache_bytes=0, render_max=(0, 0)):
    """plx_memory_estimate: the block (bytes) a scene needs for these uses:
    text is the scene's GeoJSON (str, bytes or dict), uses an or of
    USE_VISIBILITY, USE_LIGHT and USE_RENDER (default all three: what
    Scene sizes its block for), lit_cache_bytes and render_max as Scene's."""
    data = _as_bytes(text)
    if not data.lstrip().lstrip(b"\xef\xbb\xbf").lstrip()[:1] == b"{":  # a UTF-8 byte order mark allowed
        raise ValueError("memory_estimate takes the scene's GeoJSON text, which starts with '{', not "
                         f"{data[:40]!r}: read a file first")
    return _estimate(data, uses, lit_cache_bytes, render_max, scan_checked=True)


class Scene:
    """One engine with one loaded scene.

    mem: the engine's block in bytes; None sizes it with plx_memory_estimate
    for visibility, light and rendering at render_max (default 1920x1080).
    Warnings of the load (skipped features, ignored properties) are in
    .warnings; strict=True makes the first one an error.

    Lamps naming an IES or EULUMDAT file (properties.photometry, SPEC §2.1)
    get it read here, relative to base_dir unless absolute: from_file's
    default is the scene file's folder, as the polarlux command's; Scene's
    is the current directory. A file that cannot be read or parsed raises
    PolarluxError naming it (such a lamp would give no light).

    text: GeoJSON as str or bytes, or a dict as json.load gives it.
    .info: plx_scene_info as a dict: buildings, raised, blocks, courtyards,
    holes, lamps, vertices, skipped_features, skipped_lamps,
    overlapping_pairs, lonlat (1 when the scene is WGS84 lon/lat), lon0 and
    lat0 (the projection's centre), bounds [x0, y0, x1, y1] (local metres),
    height_min, height_median, height_max, ground_albedo, load_ns,
    merged_lamps. .last_render (after render): plx_render_info: buildings,
    drawn, drawn_fraction, shaded_pixels (0: read from a bake's radiance
    atlas), exposure (applied), indirect_lookups, aa_later, aa_adaptive,
    eye_inside (1: the eye is inside a building, the frame shows its walls).
    Threads: one Scene may be shared; its calls take turns (a lock), since
    one engine runs one call at a time. Separate Scenes run in parallel.
    A Scene cannot be pickled or copied (it owns an engine in its own
    block): load the text again.
    """

    def __init__(self, text, name="scene", mem=None, strict=False, lit_cache_bytes=0, render_max=(0, 0),
                 base_dir=None):
        data = _as_bytes(text)
        if data[:len(BAKE_MAGIC)] == BAKE_MAGIC:
            raise ValueError(f"{name}: a bake file (polarlux bake), not GeoJSON: load it with Scene.from_bake "
                             "or Scene.from_file")
        self._start(strict, lit_cache_bytes, render_max)
        if mem is None:
            mem = _estimate(data, USE_VISIBILITY | USE_LIGHT | USE_RENDER, lit_cache_bytes, render_max)
        # np.empty: the pages are taken by the OS only when the engine touches them
        self._block = np.empty(int(mem), dtype=np.uint8)
        self._e = ctypes.c_void_p()
        st = lib.plx_engine_create(self._block.ctypes.data_as(ctypes.c_void_p), self._block.size,
                                   ctypes.byref(self._cfg), ctypes.byref(self._e))
        if st != _lib.OK:
            _raise(st, "plx_engine_create failed (mem too small?)")
        self._check(lib.plx_load_geojson(self._e, data, len(data), name.encode("utf-8")))
        self._load_photometry(name, base_dir)
        self._read_info()
        self._note_ground_image(name)

    def _note_ground_image(self, name):
        """A ground image the scene names is not read here (the package
        decodes no PNG): said in .warnings, as renders differ from the
        command's."""
        g = _lib.padded(_lib.GroundImageInfo)
        if lib.plx_ground_image_get(self._e, ctypes.byref(g)) == _lib.OK and g.path:
            self.warnings.append(f"{name}: ground image {os.fsdecode(g.path)} is not loaded (the Python package "
                                 "decodes no PNG): the ground keeps the scene's constant albedo in renders; "
                                 "polarlux render reads it")

    def _load_photometry(self, name, base_dir):
        """Every photometry file the lamps name, read and given to the
        engine (the core reads no files)."""
        for k in range(lib.plx_photometry_count(self._e)):
            p = ctypes.c_char_p()
            self._check(lib.plx_photometry_path(self._e, k, ctypes.byref(p)))
            rel = os.fsdecode(p.value)  # the bytes the scene names, as the file system reads them
            full = rel if os.path.isabs(rel) else os.path.join(base_dir or os.getcwd(), rel)
            if not os.path.isfile(full):
                why = "not a regular file" if os.path.exists(full) else "no such file"
                _raise(_lib.E_IO, f"{name}: photometry file {full}: {why}")
            try:
                with open(full, "rb") as f:
                    blob = f.read()
            except OSError as ex:
                _raise(_lib.E_IO, f"{name}: photometry file {full}: {ex.strerror}")
            self._check(lib.plx_set_photometry(self._e, p.value, blob, len(blob), full.encode("utf-8")))

    def _start(self, strict, lit_cache_bytes=0, render_max=(0, 0)):
        self._lock = threading.RLock()
        self._baked = False
        self._said_indirect = False
        self.warnings = log = []
        self._e = ctypes.c_void_p()
        # the callback holds the list, not the Scene: no reference cycle, so
        # the engine's block goes with the Scene's last reference (with a
        # bound method it waited for the cycle collector: 30 Scenes in a
        # loop held 359 MB)
        self._log = _lib.LOG_FN(lambda ctx, level, msg: log.append(msg.decode("utf-8", "replace")))
        self._port = _lib.Port()
        self._port.log = self._log
        self._cfg = _config(lit_cache_bytes, render_max, strict, self._port)

    def _read_info(self):
        info = _lib.padded(_lib.SceneInfo)
        self._check(lib.plx_scene_info_get(self._e, ctypes.byref(info)))
        self.info = {name: (list(getattr(info, name)) if name == "bounds" else getattr(info, name))
                     for name, _ in _lib.SceneInfo._fields_}

    @classmethod
    def from_file(cls, path, **kw):
        """Loads a GeoJSON file, or a bake file (polarlux bake: see
        from_bake, which takes mem= and strict= only); read here, the core
        reads no files."""
        with open(path, "rb") as f:
            if f.read(len(BAKE_MAGIC)) == BAKE_MAGIC:
                return cls._from_bake_file(f, str(path), **kw)
            f.seek(0)
            data = f.read()
        kw.setdefault("name", str(path))
        kw.setdefault("base_dir", os.path.dirname(os.path.abspath(path)))
        return cls(data, **kw)

    @classmethod
    def from_bake(cls, path, mem=None, strict=False, **rest):
        """An engine from a bake file (polarlux bake SCENE -o CITY.plxb):
        one copy of its image into a block of its own, no parsing and no
        rebuilding; frames read the bake's radiance atlas. mem: the block
        in bytes (None: the size the bake asks, plx_bake_block_size). A
        bake keeps its render maximum and lit cache (polarlux bake
        --max-size)."""
        with open(path, "rb") as f:
            return cls._from_bake_file(f, str(path), mem=mem, strict=strict, **rest)

    @classmethod
    def _from_bake_file(cls, f, name, mem=None, strict=False, **rest):
        """The bake read through a mapping of the file (no copy of it in
        Python's memory) into a block of anonymous pages, huge pages where
        the system offers them: the load copies the image once, as the
        command's does."""
        unknown = set(rest) - {"name", "render_max", "lit_cache_bytes", "base_dir"}
        if unknown:
            raise TypeError(f"unexpected keyword argument {sorted(unknown)[0]!r}")
        if set(rest) - {"name", "base_dir"}:  # a bake holds its photometry tables: base_dir has nothing to read
            raise ValueError(f"{name}: a bake file takes mem= and strict= only (it keeps its own "
                             f"{', '.join(sorted(set(rest) - {'name', 'base_dir'}))}: set them with polarlux bake)")
        size = os.fstat(f.fileno()).st_size
        fmap = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) if size else None
        data = np.frombuffer(fmap, dtype=np.uint8) if fmap is not None else np.zeros(1, dtype=np.uint8)
        self = cls.__new__(cls)
        self._start(strict)
        err = ctypes.create_string_buffer(512)
        need = ctypes.c_size_t()
        st = lib.plx_bake_block_size(data.ctypes.data, size, ctypes.byref(need), err, len(err))
        if st != _lib.OK:
            _raise(st, f"{name}: {err.value.decode('utf-8', 'replace')}")
        self._block = _big_block(int(need.value) if mem is None else int(mem))
        st = lib.plx_bake_load(self._block.ctypes.data, self._block.size, ctypes.byref(self._cfg), data.ctypes.data,
                               size, ctypes.byref(self._e), err, len(err))
        if st != _lib.OK:
            self._e = ctypes.c_void_p()
            self._block = None
            _raise(st, f"{name}: {err.value.decode('utf-8', 'replace')}")
        self._baked = True
        self._read_info()
        return self

    def _check(self, st):
        if st != _lib.OK:
            _raise(st, lib.plx_last_error(self._e).decode("utf-8", "replace"))

    def close(self):
        """Ends the engine and gives its block back; later calls raise
        ValueError("the Scene is closed")."""
        with self._lock:
            if self._e:
                lib.plx_engine_destroy(self._e)
                self._e = ctypes.c_void_p()
                self._block = None

    def __repr__(self):
        if not getattr(self, "_e", None):
            return "<polarlux.Scene (closed)>"
        i = self.info
        return (f"<polarlux.Scene: {i['buildings']} buildings, {i['lamps']} lamps"
                f"{', lon/lat' if i['lonlat'] else ''}{', baked' if self._baked else ''}>")

    def __reduce__(self):
        raise TypeError("a Scene owns an engine in its own memory block and cannot be pickled: "
                        "pickle the scene's text (or keep a bake file) and load it again")

    def __copy__(self):
        raise TypeError("a Scene cannot be copied (two copies would share one engine): load the scene again")

    def __deepcopy__(self, memo):
        self.__copy__()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    # ---- memory ----------------------------------------------------------------
    @_engine_call
    def memory(self):
        """plx_memory_get: capacity, used_total, peak_total (bytes)."""
        r = _lib.padded(_lib.MemoryReport)
        lib.plx_memory_get(self._e, ctypes.byref(r))
        return {"capacity": r.capacity, "used_total": r.used_total, "peak_total": r.peak_total}

    # ---- coordinates -------------------------------------------------------------
    def _local(self, xy, what):
        """Raises ValueError when the (N, >=2) local points of a lon/lat scene
        all lie where the scene's own bounds would be in lon/lat degrees
        (grown by their own size on every side): they
        are lon/lat given where the API takes metres (such a point as metres
        lies in a box of centimetres next to the scene's centre; before
        2026-12-02 a route of them scored 0 m, a render showed black)."""
        if not self.info.get("lonlat"):
            return
        a = np.atleast_2d(np.asarray(xy, dtype=np.float64))
        if a.ndim != 2 or a.shape[0] == 0 or a.shape[1] < 2:
            return
        b = self.info["bounds"]
        corners = self.local_to_lonlat(np.array([[b[0], b[1]], [b[2], b[3]]]))
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        pad = np.maximum(hi - lo, 0.001)  # a route may leave the scene a little (300 m past its edge: 2026-12-03)
        lo, hi = lo - pad, hi + pad
        x, y = a[:, 0], a[:, 1]
        if np.all((x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1])):
            raise ValueError(f"{what} look like lon/lat degrees within the scene ({lo[0]:.5f}..{hi[0]:.5f}, "
                             f"{lo[1]:.5f}..{hi[1]:.5f}); this API takes the scene's local metres: convert "
                             f"with Scene.lonlat_to_local")

    @_engine_call
    def lonlat_to_local(self, lonlat):
        """(N, 2) lon/lat degrees -> (N, 2) local metres (SPEC §1); lon/lat scenes only.
        Longitudes beyond +-180 or latitudes beyond +-90 raise ValueError."""
        a = _points(lonlat, 2, "lonlat")
        bad = (np.abs(a[:, 0]) > 180.0) | (np.abs(a[:, 1]) > 90.0)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"lonlat[{k}] = ({a[k, 0]!r}, {a[k, 1]!r}) is not lon/lat degrees "
                             "(longitude -180..180, latitude -90..90)")
        out = np.empty_like(a)
        self._check(lib.plx_lonlat_to_local(self._e, a.shape[0], _dptr(a), _dptr(out)))
        return out

    @_engine_call
    def local_to_lonlat(self, xy):
        """(N, 2) local metres -> (N, 2) lon/lat degrees."""
        a = _points(xy, 2, "xy")
        out = np.empty_like(a)
        self._check(lib.plx_local_to_lonlat(self._e, a.shape[0], _dptr(a), _dptr(out)))
        return out

    # ---- light -------------------------------------------------------------------
    @_engine_call
    def illuminance(self, points, normals=None):
        """Illuminance (lux, SPEC §2) at points: (N, 2) ground points facing
        up, or (N, 3) points with (N, 3) unit normals (any point in free air,
        on the ground or on a surface). Returns (E_direct, E_indirect), two
        (N,) arrays. E_indirect comes from the scene's photon buffers: a
        bake's (Scene.from_bake; polarlux bake traces them); a GeoJSON scene
        has none here, so it is 0 (said once with a RuntimeWarning).
        NaN, with a RuntimeWarning giving the engine's reason for the first
        such point, where a point is strictly inside a building or below the
        ground, not finite, or its normal is not of unit length within 1e-6
        (the others are computed)."""
        pts = np.ascontiguousarray(points, dtype=np.float64)
        if pts.ndim == 1 and pts.size in (2, 3):
            pts = pts.reshape(1, pts.size)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3):
            raise ValueError(f"points must have shape (N, 2) or (N, 3), not {pts.shape}")
        if pts.shape[1] == 2:
            pts = np.column_stack([pts, np.zeros(pts.shape[0])])
        pts = _points(pts, 3, "points")
        self._local(pts, "points")
        if normals is None:
            nrm = np.zeros_like(pts)
            nrm[:, 2] = 1.0
        else:
            nrm = _points(normals, 3, "normals")
            if nrm.shape != pts.shape:
                raise ValueError("normals must have the shape of points")
        n = pts.shape[0]
        self._far(pts)
        ed, ei = np.empty(n), np.empty(n)
        st = lib.plx_illuminance(self._e, n, _dptr(pts), _dptr(nrm), _dptr(ed), _dptr(ei), None)
        if st not in (_lib.OK, _lib.E_RANGE):
            self._check(st)
        if st == _lib.E_RANGE:
            _warnings.warn(f"{lib.plx_last_error(self._e).decode('utf-8', 'replace')}: "
                           f"{int(np.isnan(ed).sum())} of {n} points are NaN", RuntimeWarning, stacklevel=3)
        if not self._said_indirect and n and self.info["lamps"] and lib.plx_indirect_frames(self._e) == 0:
            self._said_indirect = True
            _warnings.warn("E_indirect is 0: " + ("the bake holds no photon buffers (baked with --no-indirect or "
                                                  "--frames 0)" if self._baked else
                                                  "a GeoJSON scene has no photon buffers in the Python package; "
                                                  "load a bake (polarlux bake SCENE -o CITY.plxb; Scene.from_bake)"
                                                  " for indirect light"),
                           RuntimeWarning, stacklevel=3)
        return ed, ei

    def _far(self, pts):
        """A RuntimeWarning when points lie more than 1 km outside the scene's
        bounds (the command's warning: no lamp reaches them, and they read 0
        lx without a word)."""
        b = self.info["bounds"]
        with np.errstate(invalid="ignore"):
            d = np.hypot(np.maximum(np.maximum(b[0] - pts[:, 0], pts[:, 0] - b[2]), 0.0),
                         np.maximum(np.maximum(b[1] - pts[:, 1], pts[:, 1] - b[3]), 0.0))
        far = d > 1000.0
        if far.any():
            k = int(np.argmax(np.where(far, d, -1.0)))
            _warnings.warn(f"{int(far.sum())} of {len(pts)} points lie more than 1 km outside the scene's bounds "
                           f"(the farthest, point {k}, {d[k] / 1000.0:.4g} km): are they in the scene's local "
                           f"metres?", RuntimeWarning, stacklevel=4)

    @_engine_call
    def meter(self, points, facing=None):
        """Light meter readings in free air (SPEC §6, EN 13201's pedestrian
        criteria), direct light, lux: (N, 3) points (a meter 1.5 m above the
        ground is z = 1.5) and the horizontal facing direction u, (N, 2) or
        one (2,) for every point (normalised here; None: east, +x).
        Returns a dict of (N,) arrays: E_h (horizontal, facing up), E_v
        (vertical, facing u), E_sc (semi-cylindrical, facing u), E_hs
        (hemispherical). NaN, with a RuntimeWarning, for a point strictly
        inside a building or below the ground; a zero or non-finite u raises
        PolarluxError (PLX_E_INVALID)."""
        pts = _points(points, 3, "points")
        self._local(pts, "points")
        self._far(pts)
        n = pts.shape[0]
        u = None
        if facing is not None:
            u = np.ascontiguousarray(facing, dtype=np.float64)
            if u.shape == (2,):
                u = np.tile(u, (n, 1))
            if u.shape != (n, 2):
                raise ValueError(f"facing must have shape (2,) or ({n}, 2), not {u.shape}")
        out = np.empty((n, 4))
        st = lib.plx_meter(self._e, n, _dptr(pts), _dptr(u) if u is not None else None, _dptr(out))
        if st not in (_lib.OK, _lib.E_RANGE):
            self._check(st)
        if st == _lib.E_RANGE:
            _warnings.warn(f"{lib.plx_last_error(self._e).decode('utf-8', 'replace')}: "
                           f"{int(np.isnan(out[:, 0]).sum())} of {n} points are NaN", RuntimeWarning, stacklevel=3)
        return {"E_h": out[:, 0].copy(), "E_v": out[:, 1].copy(), "E_sc": out[:, 2].copy(), "E_hs": out[:, 3].copy()}

    # ---- visibility -----------------------------------------------------------------
    @_engine_call
    def visibility(self, x, y, dir_deg=0.0, fov_deg=360.0):
        """The exact visibility polygon from (x, y): {"area", "polygon" (M, 2),
        "visible" (K,) building indices}. Raises PolarluxError (PLX_E_RANGE)
        for a point that is not free."""
        self._local([[float(x), float(y)]], "x, y")
        v = _lib.padded(_lib.Visibility)
        self._check(lib.plx_visibility_get(self._e, float(x), float(y), float(dir_deg), float(fov_deg),
                                           ctypes.byref(v)))
        poly = np.ctypeslib.as_array(v.xy, shape=(v.nverts * 2,)).reshape(-1, 2).copy() if v.nverts else \
            np.empty((0, 2))
        vis = np.ctypeslib.as_array(v.visible, shape=(v.nvisible,)).astype(np.int64) if v.nvisible else \
            np.empty(0, dtype=np.int64)
        return {"area": v.area, "polygon": poly, "visible": vis}

    @_engine_call
    def visibility_areas(self, points, dir_deg=0.0, fov_deg=360.0):
        """(N, 2) viewpoints -> (N,) visible areas in m^2 (SPEC §3); NaN where the
        point is not free (inside a building, on a wall, outside Bounds) or
        not finite."""
        pts = _points(points, 2, "points")
        self._local(pts, "points")
        out = np.empty(pts.shape[0])
        v = _lib.padded(_lib.Visibility)
        for i, (x, y) in enumerate(pts):
            if not (np.isfinite(x) and np.isfinite(y)):
                out[i] = np.nan
                continue
            st = lib.plx_visibility_get(self._e, x, y, float(dir_deg), float(fov_deg), ctypes.byref(v))
            if st == _lib.E_RANGE:
                out[i] = np.nan
                continue
            self._check(st)
            out[i] = v.area
        return out

    # ---- routes --------------------------------------------------------------------
    @_engine_call
    def route_score(self, xy, step=1.0, dark_lux=1.0, facial_height=None):
        """How well lit is the polyline xy (N, 2): returns (total, segments):
        total a dict (length, mean, min, max, uniformity, dark_share, p_class,
        samples, blocked_length), segments a dict of (N-1,) arrays of the same.
        Lux are direct light on the ground, sampled every step metres (the
        trapezoid rule; README "Routes"); dark_share is the length below
        dark_lux. p_class is EN 13201's P class the mean and minimum meet:
        1 .. 6 for P1 .. P6, 0 for none. Length inside buildings is
        blocked_length and is not sampled (a route wholly inside scores
        mean = min = 0 with samples 0).
        facial_height=H (1.5 for EN 13201's pedestrians): also min_ev_fw,
        min_ev_bw, min_esc_fw, min_esc_bw (the least vertical and
        semi-cylindrical lux H m above the line, facing along it and back;
        NaN where a segment has no sample) and class_fr (the P class meeting
        the facial-recognition criterion too: min E_v and min E_sc over both
        ways; 0 for none), as polarlux route's Ev_fw .. class_fr columns."""
        a = _points(xy, 2, "xy")
        n = a.shape[0]
        if n < 2:
            raise ValueError("a route needs 2 or more vertices")
        if not (isinstance(step, numbers.Real) and np.isfinite(step) and step > 0):
            raise ValueError(f"step must be a number of metres above 0, not {step!r}")
        if not (isinstance(dark_lux, numbers.Real) and np.isfinite(dark_lux) and dark_lux >= 0):
            raise ValueError(f"dark_lux must be a number of lux from 0, not {dark_lux!r}")
        if facial_height is not None and not (isinstance(facial_height, numbers.Real) and
                                              np.isfinite(facial_height) and facial_height > 0):
            raise ValueError(f"facial_height must be a height in metres above 0, not {facial_height!r}")
        self._local(a, "xy")
        total = _lib.padded(_lib.RouteStats)
        segs = (_lib.RouteStats * (n - 1))()
        self._check(lib.plx_route_score(self._e, _dptr(a), n, float(step), float(dark_lux),
                                        ctypes.byref(total), segs))
        names = [f for f, _ in _lib.RouteStats._fields_]
        tot = {f: getattr(total, f) for f in names}
        seg = {f: np.array([getattr(s, f) for s in segs]) for f in names}
        if facial_height is not None:
            self._facial(a, float(step), float(facial_height), tot, seg)
        return tot, seg

    def _facial(self, a, step, height, tot, seg):
        """route_score's facial_height: plx_route_facial's minima and the
        class with the facial-recognition criterion (polarlux route's rule)."""
        n = a.shape[0]
        fs = np.empty((n - 1, 4))
        ft = np.empty(4)
        self._check(lib.plx_route_facial(self._e, _dptr(a), n, step, height, _dptr(fs), _dptr(ft)))
        keys = ("min_ev_fw", "min_ev_bw", "min_esc_fw", "min_esc_bw")

        def cls(mean, mn, samples, f):
            ev, esc = min(f[0], f[1]), min(f[2], f[3])
            if samples == 0 or np.isnan(ev) or np.isnan(esc):
                return 0
            return int(lib.plx_p_class_facial(mean, mn, ev, esc))
        for k, key in enumerate(keys):
            tot[key] = float(ft[k])
            seg[key] = fs[:, k].copy()
        tot["class_fr"] = cls(tot["mean"], tot["min"], tot["samples"], ft)
        seg["class_fr"] = np.array([cls(seg["mean"][i], seg["min"][i], seg["samples"][i], fs[i])
                                    for i in range(n - 1)], dtype=np.int64)

    # ---- images ---------------------------------------------------------------------
    @_engine_call
    def render(self, eye, target, fov_deg=60.0, size=(640, 480), exposure=1.0, aerial=False, glow=True,
               linear=False, aa=1, held=None, tone_curve=False, exposure_step=0):
        """A night image (SPEC §5) as an (H, W, 3) uint8 sRGB array; with
        linear=True also the (H, W, 3) float32 linear radiance: (rgb8, rgbf).
        exposure="auto": chosen from the image, with the tone curve (the
        command's default; README "Automatic exposure"), and with held=E (the
        last frame's exposure) held at E while the image's own choice stays
        within half a stop, as walk's frames are (exposure_step=N: moving at
        most N eighths of a stop a frame, walk's 32 / fps); a number with
        tone_curve=True: that exposure with the tone curve (a walk frame
        again); aa=N: N x N samples a pixel, adaptive (1: the pixel centre,
        SPEC §5). What plx_render reported (the exposure applied, ...) is in
        .last_render."""
        if not hasattr(size, "__len__") or len(size) != 2 or any(not isinstance(k, numbers.Integral) or k < 1
                                                                 for k in size):
            raise ValueError(f"size must be (width, height) in whole pixels, not {size!r}")
        w, h = int(size[0]), int(size[1])
        if not (isinstance(aa, numbers.Integral) and 1 <= aa <= 16):
            raise ValueError(f"aa must be a whole number from 1 to 16, not {aa!r}")
        if isinstance(exposure, str) and exposure != "auto":
            raise ValueError(f"exposure must be a number or 'auto', not {exposure!r}")
        if held is not None and exposure != "auto":
            raise ValueError("held needs exposure='auto' (it holds the automatic exposure)")
        if held is not None and not (isinstance(held, numbers.Real) and np.isfinite(held) and held > 0):
            raise ValueError(f"held must be the last frame's exposure, a positive number, not {held!r}")
        if tone_curve and exposure == "auto":
            raise ValueError("tone_curve needs a number for exposure (automatic exposure has the curve)")
        for name, v in (("eye", eye), ("target", target)):
            if len(v) != 3:
                raise ValueError(f"{name} must be (x, y, z) in the scene's local metres, not {tuple(v)!r}")
        self._local([list(eye)[:2], list(target)[:2]], "eye and target")
        cam = _lib.Camera()
        cam.eye[:] = [float(v) for v in eye]
        cam.target[:] = [float(v) for v in target]
        cam.fov_deg, cam.width, cam.height = float(fov_deg), w, h
        opts = _lib.padded(_lib.RenderOpts)
        lib.plx_render_opts_default(ctypes.byref(opts))
        if exposure == "auto" and held is not None:
            opts.auto_exposure, opts.exposure = EXPOSURE_ADAPT, float(held)
            opts.exposure_step = int(exposure_step)
        elif exposure == "auto":
            opts.auto_exposure = EXPOSURE_AUTO
        else:
            opts.exposure = float(exposure)
            opts.auto_exposure = EXPOSURE_TONE if tone_curve else EXPOSURE_FIXED
        opts.aerial, opts.no_glow, opts.aa = int(bool(aerial)), int(not glow), int(aa)
        rgb8 = np.zeros((h, w, 3), dtype=np.uint8)
        rgbf = np.zeros((h, w, 3), dtype=np.float32) if linear else None
        info = _lib.padded(_lib.RenderInfo)
        self._check(lib.plx_render(self._e, ctypes.byref(cam), ctypes.byref(opts),
                                   rgb8.ctypes.data_as(_lib.c_uint8_p),
                                   rgbf.ctypes.data_as(ctypes.POINTER(ctypes.c_float)) if linear else None,
                                   ctypes.byref(info)))
        self.last_render = {name: getattr(info, name) for name, _ in _lib.RenderInfo._fields_}
        return (rgb8, rgbf) if linear else rgb8
