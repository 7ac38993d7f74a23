"""Tests of the Python package over libpolarlux.so. Results are compared with
the polarlux command (a separate program over the static library:
$POLARLUX_BIN, default build/polarlux), with SPEC formulas written out here,
and with numpy sums over the package's own point queries."""
import os
import subprocess
import sys

import numpy as np
import pytest

import polarlux

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "web"))
from png_pixels import decode as decode_png  # noqa: E402

# Most tests draw random points over a scene without photon buffers: the
# package's warnings for points inside buildings and for E_indirect 0 are
# expected there and are checked where they are the subject
# (test_nan_points_say_why and the E_indirect tests, whose pytest.warns sees
# them whatever this filter says).
pytestmark = [pytest.mark.filterwarnings("ignore:point .* is inside a building:RuntimeWarning"),
              pytest.mark.filterwarnings("ignore:E_indirect is 0:RuntimeWarning")]

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BIN = os.environ.get("POLARLUX_BIN", os.path.join(ROOT, "build", "polarlux"))
TINY = os.path.join(ROOT, "fixtures", "tiny.geojson")
HELSINKI = os.path.join(ROOT, "fixtures", "helsinki-centre.geojson")
EIXAMPLE = os.path.join(ROOT, "fixtures", "eixample-4x4.geojson")


def run_cli(*args, stdin=None):
    r = subprocess.run([BIN, *args], input=stdin, capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def street_points(scene, n, seed):
    """n random ground points over the scene's box (some inside buildings)."""
    b = scene.info["bounds"]
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(b[0] + 40, b[2] - 40, n), rng.uniform(b[1] + 40, b[3] - 40, n)])


def test_version_is_the_library_and_the_command():
    import re
    rc, out, _ = run_cli("--version")
    assert rc == 0 and out == f"polarlux {polarlux.__version__}\n"
    with open(os.path.join(ROOT, "include", "polarlux.h")) as f:
        header = re.search(r'#define PLX_VERSION_STRING "([^"]+)"', f.read()).group(1)
    assert polarlux.__version__ == header


def test_load_file_and_string_agree():
    a = polarlux.Scene.from_file(TINY)
    with open(TINY) as f:
        b = polarlux.Scene(f.read())
    assert a.info["buildings"] == b.info["buildings"] == 4
    assert a.info["lamps"] == b.info["lamps"] == 3
    assert a.info["courtyards"] == 1
    assert any("lamp is inside building 0 (A); left out" in w for w in a.warnings)


@pytest.mark.parametrize("path", [TINY, EIXAMPLE, HELSINKI])
def test_illuminance_matches_the_command(path):
    s = polarlux.Scene.from_file(path)
    pts = street_points(s, 300, 1) if path != TINY else np.array([[30, 12], [50, 10], [35, 2], [5, 5]], float)
    ed, ei = s.illuminance(pts)
    text = "# crs: local\n" + "".join(f"{x!r} {y!r}\n" for x, y in pts)
    rc, out, _ = run_cli("illum", path, "--points", "-", "-q", "--no-indirect", stdin=text)
    rows = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    assert rows.shape == (len(pts), 5)
    assert rc == (1 if np.isnan(ed).any() else 0)
    assert np.array_equal(np.isnan(ed), np.isnan(rows[:, 3]))
    ok = ~np.isnan(ed)
    assert ok.sum() > 0
    np.testing.assert_allclose(ed[ok], rows[ok, 3], rtol=1e-12, atol=1e-12)
    assert (ei[ok] == 0).all()  # no photons traced through the package


def test_illuminance_under_a_lamp_is_spec_formula():
    # one lamp, nothing in its reach: E = I cos / d^2 W(d/R) (SPEC §2)
    text = ('{"type":"FeatureCollection","properties":{"units":"m"},"features":['
            '{"type":"Feature","properties":{"lamp":true,"z":5,"intensity":800,"radius":25},'
            '"geometry":{"type":"Point","coordinates":[0,0]}}]}')
    s = polarlux.Scene(text)
    pts = np.array([[0.0, 0.0], [3.0, 4.0], [10.0, -2.0], [30.0, 0.0]])
    ed, _ = s.illuminance(pts)
    d = np.sqrt((pts ** 2).sum(1) + 25.0)
    w = np.clip(1 - (d / 25.0) ** 4, 0, 1) ** 2
    np.testing.assert_allclose(ed, 800.0 * (5.0 / d) / d ** 2 * w, rtol=1e-12, atol=1e-15)
    # a wall point facing the lamp, (N, 3) points with normals
    ed3, _ = s.illuminance([[0.0, 0.0, 0.0]], normals=[[0.0, 0.0, 1.0]])
    assert ed3[0] == ed[0]


@pytest.mark.parametrize("path", [TINY, HELSINKI])
def test_visibility_areas_match_the_command(path):
    s = polarlux.Scene.from_file(path)
    pts = street_points(s, 60, 2) if path != TINY else np.array([[50, 10], [30, 15], [5, 5]], float)
    areas = s.visibility_areas(pts)
    text = "# crs: local\n" + "".join(f"{x!r} {y!r}\n" for x, y in pts)
    _, out, _ = run_cli("vis", "-q", path, "--points", "-", stdin=text)
    cli = np.array([float(line.split()[2]) for line in out.splitlines()])
    assert np.array_equal(np.isnan(areas), np.isnan(cli))
    ok = ~np.isnan(areas)
    assert ok.sum() > 0
    np.testing.assert_allclose(areas[ok], cli[ok], rtol=1e-12)
    if path == TINY:
        assert areas[0] == 100.0 and np.isnan(areas[2])  # the courtyard; inside building A
        v = s.visibility(50, 10)
        assert v["area"] == 100.0 and v["polygon"].shape == (4, 2) and list(v["visible"]) == [2]
        with pytest.raises(polarlux.PolarluxError) as err:
            s.visibility(5, 5)
        assert err.value.status == "PLX_E_RANGE" and "inside building 0 (A)" in str(err.value)


def test_route_score_is_the_trapezoid_rule_over_illuminance():
    s = polarlux.Scene.from_file(EIXAMPLE)
    b = s.info["bounds"]
    y = 0.5 * (b[1] + b[3])
    line = np.array([[b[0] + 60, y], [b[2] - 60, y], [b[2] - 60, y + 37.5]])
    total, seg = s.route_score(line, step=1.0, dark_lux=2.0)
    ints, lengths = [], []
    for (x0, y0), (x1, y1) in zip(line[:-1], line[1:]):
        length = np.hypot(x1 - x0, y1 - y0)
        k = int(np.ceil(length / 1.0))
        t = np.arange(k + 1) / k
        ed, ei = s.illuminance(np.column_stack([x0 + t * (x1 - x0), y0 + t * (y1 - y0)]))
        e = ed + ei
        w = np.full(k + 1, length / k)
        w[0] = w[-1] = length / k / 2
        ok = ~np.isnan(e)
        ints.append((w[ok] * e[ok]).sum())
        lengths.append(w[ok].sum())
    np.testing.assert_allclose(seg["mean"], np.array(ints) / np.array(lengths), rtol=1e-12)
    np.testing.assert_allclose(total["mean"], sum(ints) / sum(lengths), rtol=1e-12)
    assert seg["length"].shape == (2,)
    # EN 13201 P-classes (SPEC §6 table): the best class whose mean and minimum are met
    table = [(15.0, 3.0), (10.0, 2.0), (7.5, 1.5), (5.0, 1.0), (3.0, 0.6), (2.0, 0.4)]
    want = next((k + 1 for k, (m, lo) in enumerate(table) if total["mean"] >= m and total["min"] >= lo), 0)
    assert total["p_class"] == want


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, 3)[::-1]


def test_render_matches_the_command(tmp_path):
    s = polarlux.Scene.from_file(EIXAMPLE)
    eye, target = (10.0, -30.0, 40.0), (60.0, 60.0, 0.0)
    img, lin = s.render(eye, target, fov_deg=50, size=(96, 64), linear=True)
    assert img.shape == (64, 96, 3) and img.dtype == np.uint8
    assert lin.shape == (64, 96, 3) and lin.dtype == np.float32
    assert 0 < (img.sum(axis=2) > 0).mean() < 1
    rc, _, err = run_cli("render", "-q", EIXAMPLE, "--eye", "10,-30,40", "--target", "60,60,0", "--fov", "50",
                         "--size", "96x64", "--no-indirect", "-o", str(tmp_path / "r.png"),
                         "--pfm", str(tmp_path / "r.pfm"))
    assert rc == 0, err
    assert np.array_equal(read_pfm(tmp_path / "r.pfm"), lin)


def test_walk_frames_from_python(tmp_path):
    """A walk's frames drawn again: each frame's automatic exposure held at
    the last one's (held=, what walk does), and a frame at its cameras.txt
    exposure with the tone curve (tone_curve=True), byte for byte; the
    constants are the header's."""
    header = open(os.path.join(ROOT, "include", "polarlux.h")).read()
    for name in ("FIXED", "AUTO", "ADAPT", "TONE"):
        value = int(header.split(f"#define PLX_EXPOSURE_{name} ")[1].split()[0])
        assert getattr(polarlux._lib, f"EXPOSURE_{name}") == value
    bake = bake_fixture(tmp_path)
    path = tmp_path / "p.geojson"
    path.write_text('{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString",'
                    '"coordinates":[[298.6,265.5,1.7],[270,294,1.7],[262,330]]}}')
    rc, _, err = run_cli("walk", "-q", str(bake), "--path", str(path), "--size", "96x64", "--fps", "0.1",
                         "-o", str(tmp_path / "w"))
    assert rc == 0, err
    cams = [ln.split() for ln in open(tmp_path / "w" / "cameras.txt") if not ln.startswith("#")]
    assert len(cams) >= 3
    s = polarlux.Scene.from_bake(bake)
    held = None
    for k, c in enumerate(cams):
        eye, target, ex = [float(v) for v in c[1:4]], [float(v) for v in c[4:7]], float(c[7])
        img = s.render(eye, target, size=(96, 64), exposure="auto", aa=2, held=held,
                       exposure_step=320)  # walk's 8 x 4 stops a second / --fps 0.1
        assert s.last_render["exposure"] == ex
        w8, h8, bpp, rows = decode_png(tmp_path / "w" / f"frame-{k + 1:04d}.png")
        assert b"".join(bytes(r) for r in rows) == img.tobytes()
        again = s.render(eye, target, size=(96, 64), exposure=ex, tone_curve=True, aa=2)
        assert np.array_equal(again, img)
        held = ex
    with pytest.raises(polarlux.PolarluxError) as err:  # the step reaches the library
        s.render(cams[0][1:4], cams[0][4:7], size=(96, 64), exposure="auto", held=0.5, exposure_step=-1)
    assert "exposure_step must be 0 .. 4096" in str(err.value)
    with pytest.raises(ValueError):
        s.render(cams[0][1:4], cams[0][4:7], exposure=0.5, held=0.5)
    with pytest.raises(ValueError):
        s.render(cams[0][1:4], cams[0][4:7], exposure="auto", tone_curve=True)


def bake_fixture(tmp_path, *extra):
    out = tmp_path / "e.plxb"
    rc, _, err = run_cli("bake", "-q", EIXAMPLE, "--frames", "2", "--photons", "4000", "--texel", "2",
                         "--max-size", "160x120", *extra, "-o", str(out))
    assert rc == 0, err
    return out


def test_bake_loads_and_renders_as_the_command(tmp_path):
    bake = bake_fixture(tmp_path)
    s = polarlux.Scene.from_bake(bake)
    geo = polarlux.Scene.from_file(EIXAMPLE)
    for k in ("buildings", "lamps", "blocks", "courtyards", "vertices"):
        assert s.info[k] == geo.info[k]
    assert s.info["bounds"] == geo.info["bounds"]
    b = polarlux.Scene.from_file(bake)  # the magic is recognised
    assert b.info == s.info
    # a frame from the bake's radiance atlas (indirect light included) is
    # the command's frame from the same bake, float for float
    eye, target = (10.0, -30.0, 40.0), (60.0, 60.0, 0.0)
    img, lin = s.render(eye, target, fov_deg=50, size=(96, 64), linear=True)
    assert 0 < (img.sum(axis=2) > 0).mean() < 1
    rc, _, err = run_cli("render", "-q", str(bake), "--eye", "10,-30,40", "--target", "60,60,0", "--fov", "50",
                         "--size", "96x64", "--exposure", "1", "-o", str(tmp_path / "r.png"),
                         "--pfm", str(tmp_path / "r.pfm"))
    assert rc == 0, err
    assert np.array_equal(read_pfm(tmp_path / "r.pfm"), lin)
    # and differs from the GeoJSON scene's direct light alone (the bake's photons are read)
    assert not np.array_equal(geo.render(eye, target, fov_deg=50, size=(96, 64), linear=True)[1], lin)
    # the command's defaults for a frame: automatic exposure, 2 x 2 samples
    img2, lin2 = s.render(eye, target, fov_deg=50, size=(96, 64), linear=True, exposure="auto", aa=2)
    rc, out, err = run_cli("render", str(bake), "--eye", "10,-30,40", "--target", "60,60,0", "--fov", "50",
                           "--size", "96x64", "--aa", "2", "-o", str(tmp_path / "a.png"), "--pfm",
                           str(tmp_path / "a.pfm"))
    assert rc == 0, err
    assert np.array_equal(read_pfm(tmp_path / "a.pfm"), lin2)
    w8, h8, bpp, rows = decode_png(tmp_path / "a.png")  # tests/web/png_pixels.py: zlib alone
    assert (w8, h8, bpp) == (96, 64, 3) and b"".join(bytes(r) for r in rows) == img2.tobytes()
    chosen = float(out.split("exposure: ")[1].split()[0])
    assert s.last_render["exposure"] == pytest.approx(chosen, rel=1e-3) and chosen != 1.0
    assert s.last_render["aa_later"] > 0 and not np.array_equal(lin2, lin)
    with pytest.raises(ValueError):
        s.render(eye, target, aa=0)
    with pytest.raises(ValueError):
        s.render(eye, target, exposure="bright")
    # a frame beyond the bake's --max-size: the engine's message
    with pytest.raises(polarlux.PolarluxError) as e:
        s.render(eye, target, size=(320, 240))
    assert "160x120" in str(e.value)


def test_bake_errors(tmp_path):
    bake = bake_fixture(tmp_path)
    data = bake.read_bytes()
    cut = tmp_path / "cut.plxb"
    cut.write_bytes(data[:len(data) // 2])
    with pytest.raises(polarlux.PolarluxError) as e:
        polarlux.Scene.from_bake(cut)
    assert e.value.status == "PLX_E_PARSE" and "truncated bake file" in str(e.value) and "cut.plxb" in str(e.value)
    bad = tmp_path / "bad.plxb"
    bad.write_bytes(data[:200] + bytes([data[200] ^ 1]) + data[201:])
    with pytest.raises(polarlux.PolarluxError):
        polarlux.Scene.from_file(bad)
    with pytest.raises(polarlux.MemoryBudgetError):
        polarlux.Scene.from_bake(bake, mem=1 << 20)
    with pytest.raises(ValueError) as v:
        polarlux.Scene.from_file(bake, render_max=(640, 480))
    assert "render_max" in str(v.value)


def test_projection_round_trip_and_formula():
    s = polarlux.Scene.from_file(HELSINKI)
    assert s.info["lonlat"] == 1
    lon0, lat0 = s.info["lon0"], s.info["lat0"]
    ll = np.array([[24.94, 60.17], [24.95, 60.168], [lon0, lat0]])
    xy = s.lonlat_to_local(ll)
    np.testing.assert_allclose(xy[:, 0], (ll[:, 0] - lon0) * 111320.0 * np.cos(np.radians(lat0)), atol=1e-9)
    np.testing.assert_allclose(xy[:, 1], (ll[:, 1] - lat0) * 110540.0, atol=1e-9)
    np.testing.assert_allclose(s.local_to_lonlat(xy), ll, atol=1e-12)
    metres = polarlux.Scene.from_file(TINY)
    with pytest.raises(polarlux.PolarluxError) as err:
        metres.lonlat_to_local([[24.9, 60.1]])
    assert err.value.status == "PLX_E_INVALID" and "local metres" in str(err.value)


def test_memory_estimate_sizes_the_block():
    with open(HELSINKI, "rb") as f:
        text = f.read()
    size = polarlux.scene_size(text)
    assert size["text_bytes"] == len(text) and size["features"] > 1000
    need = polarlux.memory_estimate(text, polarlux.USE_VISIBILITY | polarlux.USE_LIGHT | polarlux.USE_RENDER,
                                    render_max=(320, 240))
    s = polarlux.Scene(text, mem=need, render_max=(320, 240))
    assert s.memory()["capacity"] <= need
    s.visibility_areas(street_points(s, 5, 3))
    s.illuminance(street_points(s, 100, 4))
    s.render((0, -300, 200), (0, 0, 0), size=(320, 240))
    s.render((0, -300, 200), (0, 0, 0), size=(320, 240), exposure="auto", aa=2)  # its own buffers
    assert s.memory()["peak_total"] <= need
    with pytest.raises(polarlux.MemoryBudgetError):
        polarlux.Scene(text, mem=64 * 1024)


def test_estimate_holds_anti_aliased_frames():
    # a small scene in its estimated block (frames up to the default
    # 1920x1080): anti-aliasing's buffers, sized by the largest frame, fit
    # (they were left out of plx_memory_estimate: PLX_E_NOMEM here)
    s = polarlux.Scene.from_file(EIXAMPLE)
    s.render((10.0, -30.0, 40.0), (60.0, 60.0, 0.0), size=(32, 24), aa=2)
    assert s.last_render["aa_later"] > 0
    assert s.memory()["peak_total"] <= s.memory()["capacity"]


def test_errors_name_the_place():
    with pytest.raises(polarlux.PolarluxError) as err:
        polarlux.Scene('{"type": "FeatureCollection",\n "features": [,]}', name="bad.json")
    assert err.value.status == "PLX_E_PARSE"
    assert "bad.json: malformed JSON at byte 44 (line 2, column 15)" in str(err.value)
    with pytest.raises(ValueError):
        polarlux.Scene.from_file(TINY).illuminance(np.zeros((3, 4)))


def test_far_points_are_said():
    s = polarlux.Scene.from_file(TINY)
    with pytest.warns(RuntimeWarning, match=r"1 of 2 points lie more than 1 km outside the scene's bounds "
                                            r"\(the farthest, point 1, 1e\+04 km\)"):
        ed, _ = s.illuminance([[30, 12], [1e7, 0]])
    assert ed[1] == 0.0 and ed[0] > 0.0
    with pytest.warns(RuntimeWarning, match="more than 1 km outside"):
        s.meter([[1e5, 0, 1.5]])
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.filterwarnings("ignore", "E_indirect is 0")
        s.illuminance([[30, 12], [60, 40]])  # near points: no word


def test_lonlat_given_for_metres_is_refused(tmp_path):
    """A lon/lat scene's API takes local metres: lon/lat degrees within the
    scene are refused (a route of them scored 0 m, a render was black), and
    the same points converted work."""
    s = polarlux.Scene.from_file(HELSINKI)
    ll = np.array([[24.9432847, 60.1676957], [24.9452847, 60.1676957]])
    for call in (lambda: s.route_score(ll), lambda: s.illuminance(ll), lambda: s.visibility_areas(ll),
                 lambda: s.visibility(*ll[0]),
                 lambda: s.render(eye=(*ll[0], 1.7), target=(*ll[1], 1.0), size=(32, 24))):
        with pytest.raises(ValueError) as v:
            call()
        assert "look like lon/lat" in str(v.value) and "lonlat_to_local" in str(v.value)
    xy = s.lonlat_to_local(ll)
    total, _ = s.route_score(xy, step=2.0)
    assert 100.0 < total["length"] < 120.0 and total["mean"] > 0.0
    with pytest.raises(ValueError) as v:
        s.render(eye=(xy[0][0], xy[0][1]), target=(xy[1][0], xy[1][1], 1.0), size=(32, 24))
    assert "eye must be (x, y, z)" in str(v.value)
    ed, _ = s.illuminance([xy[0][0], xy[0][1]])
    assert ed.shape == (1,)
    with pytest.raises(ValueError) as v:
        s.illuminance(np.zeros((2, 4)))
    assert "(N, 2) or (N, 3)" in str(v.value)
    bake = bake_fixture(tmp_path)
    with pytest.raises(ValueError) as v:
        polarlux.Scene.from_bake(bake, render_max=(640, 480))
    assert "render_max" in str(v.value)
    with pytest.raises(TypeError):
        polarlux.Scene.from_bake(bake, bogus=1)


LUMINAIRES = os.path.join(ROOT, "fixtures", "helsinki-street-luminaires.geojson")
ONE_IES = ("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n100 0\n")


def ies_scene(phot):
    """One lamp 8 m up naming the photometry file phot, a metre scene."""
    return ('{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":'
            '{"lamp":true,"z":8,"radius":40,"photometry":"%s"},"geometry":{"type":"Point","coordinates":[0,0]}}]}'
            % phot)


def test_photometry_read_relative_to_the_scene_file(tmp_path):
    # 100 cd toward the nadir from 8 m, reach 40 m: E_h = 100 / 64 W(8 / 40) lx under the lamp (SPEC §2,
    # §2.1); the package once left such lamps dark (0 lx) with no word
    (tmp_path / "l.ies").write_text(ONE_IES)
    (tmp_path / "s.geojson").write_text(ies_scene("l.ies"))
    s = polarlux.Scene.from_file(str(tmp_path / "s.geojson"))
    ed, _ = s.illuminance(np.array([[0.0, 0.0]]))
    assert ed[0] == pytest.approx(100.0 / 64.0 * (1.0 - 0.2 ** 4) ** 2, rel=1e-12)
    t = polarlux.Scene(ies_scene("l.ies"), base_dir=str(tmp_path))
    assert np.array_equal(t.illuminance(np.array([[0.0, 0.0]]))[0], ed)


def test_photometry_matches_the_command():
    s = polarlux.Scene.from_file(LUMINAIRES)
    pts = street_points(s, 200, 5)
    ed, _ = s.illuminance(pts)
    text = "# crs: local\n" + "".join(f"{x!r} {y!r}\n" for x, y in pts)
    rc, out, _ = run_cli("illum", LUMINAIRES, "--points", "-", "-q", "--no-indirect", stdin=text)
    rows = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    ok = ~np.isnan(ed)
    assert (ed[ok] > 0).sum() > 20
    np.testing.assert_allclose(ed[ok], rows[ok, 3], rtol=1e-12, atol=1e-12)


def test_photometry_file_errors(tmp_path):
    (tmp_path / "s.geojson").write_text(ies_scene("l.ies"))
    with pytest.raises(polarlux.PolarluxError, match=r"photometry file .*l\.ies: no such file"):
        polarlux.Scene.from_file(str(tmp_path / "s.geojson"))
    os.mkfifo(tmp_path / "l.ies")  # refused, never waited on
    with pytest.raises(polarlux.PolarluxError, match=r"photometry file .*l\.ies: not a regular file"):
        polarlux.Scene.from_file(str(tmp_path / "s.geojson"))
    os.remove(tmp_path / "l.ies")
    (tmp_path / "l.ies").write_text("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n100 abc\n")
    with pytest.raises(polarlux.PolarluxError, match=r"line 7: bad number 'abc'"):
        polarlux.Scene.from_file(str(tmp_path / "s.geojson"))


def test_photometry_flux_warning(tmp_path):
    """A table giving more light than its lamps (4 pi 100 = 1257 lm from one
    1000 lm lamp) is used as given, with the loader's warning in warnings."""
    (tmp_path / "s.geojson").write_text(ies_scene("l.ies"))
    (tmp_path / "l.ies").write_text("IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 2 1 1 2 0 0 0\n1 1 0\n0 180\n0\n100 100\n")
    s = polarlux.Scene.from_file(str(tmp_path / "s.geojson"))
    assert any("1257 lm, 126% of the lumens of its lamps" in w for w in s.warnings)
    (tmp_path / "l.ies").write_text("IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 2 1 1 2 0 0 0\n1 1 0\n0 180\n0\n70 70\n")
    s = polarlux.Scene.from_file(str(tmp_path / "s.geojson"))
    assert not any("lumens of its lamps" in w for w in s.warnings)


# ---- a user's pass of 2026-12-03 (threads, lifetime, warnings, meters) ----------------------------------

def test_one_scene_shared_by_threads():
    """Four threads on one Scene take turns (the engine runs one call at a
    time): the same numbers as one thread, where it crashed Python before."""
    import threading
    s = polarlux.Scene.from_file(HELSINKI)
    pts = [street_points(s, 400, k) for k in range(4)]
    out = [None] * 4

    def work(k):
        out[k] = (s.illuminance(pts[k])[0], s.visibility_areas(pts[k][:20]),
                  s.route_score(pts[k][:5], step=4.0)[0]["mean"])
    with pytest.warns(RuntimeWarning):
        threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    fresh = polarlux.Scene.from_file(HELSINKI)
    for k in range(4):
        np.testing.assert_array_equal(out[k][0], fresh.illuminance(pts[k])[0])
        np.testing.assert_array_equal(out[k][1], fresh.visibility_areas(pts[k][:20]))
        assert out[k][2] == fresh.route_score(pts[k][:5], step=4.0)[0]["mean"]


def test_scene_goes_with_its_last_reference():
    """No reference cycle: the engine's block is freed at del, not when the
    cycle collector runs."""
    import gc
    import weakref
    gc.disable()
    try:
        s = polarlux.Scene.from_file(TINY)
        r = weakref.ref(s)
        del s
        assert r() is None
    finally:
        gc.enable()


def test_nan_points_say_why():
    s = polarlux.Scene.from_file(TINY)
    with pytest.warns(RuntimeWarning, match=r"not a unit vector.*: 2 of 3 points are NaN"):
        ed, _ = s.illuminance([[30, 12, 1.5]] * 3, normals=[[.707, .707, 0], [.7071068, .7071068, 0], [1, 1, 0]])
    assert np.isnan(ed[0]) and ed[1] > 0 and np.isnan(ed[2])
    areas = s.visibility_areas([[30, 12], [np.nan, 12]])
    assert areas[0] > 0 and np.isnan(areas[1])


def test_indirect_zero_is_said_once():
    s = polarlux.Scene.from_file(TINY)
    with pytest.warns(RuntimeWarning, match="E_indirect is 0"):
        s.illuminance([[30, 12]])
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s.illuminance([[30, 12]])  # said once a Scene


def test_lonlat_route_leaving_the_scene_is_refused():
    """One vertex 300 m past the district's east edge: still lon/lat, still
    refused (it scored length 0 with no word)."""
    s = polarlux.Scene.from_file(HELSINKI)
    b = s.info["bounds"]
    east = s.local_to_lonlat([[b[2] + 300.0, 0.0]])[0]
    ll = np.array([[24.9432847, 60.1676957], [24.9452847, 60.1676957], east])
    with pytest.raises(ValueError, match="look like lon/lat"):
        s.route_score(ll)
    with pytest.raises(ValueError, match=r"lonlat\[1\] = \(200.0, 95.0\) is not lon/lat degrees"):
        s.lonlat_to_local([[24.9, 60.1], [200, 95]])


def test_meter_matches_the_command():
    s = polarlux.Scene.from_file(HELSINKI)
    xy = street_points(s, 60, 5)
    pts = np.column_stack([xy, np.full(len(xy), 1.5)])
    u = np.column_stack([np.cos(np.arange(len(xy))), np.sin(np.arange(len(xy)))])
    with pytest.warns(RuntimeWarning, match="inside a building"):
        m = s.meter(pts, facing=u)
    text = "# crs: local\n" + "".join(f"{p[0]!r} {p[1]!r} 1.5 {a!r} {b!r}\n" for p, (a, b) in zip(pts, u))
    rc, out, _ = run_cli("meter", HELSINKI, "--points", "-", "-q", stdin=text)
    rows = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    assert rows.shape == (len(pts), 7)
    got = np.column_stack([m["E_h"], m["E_v"], m["E_sc"], m["E_hs"]])
    assert np.array_equal(np.isnan(got), np.isnan(rows[:, 3:]))
    ok = ~np.isnan(got)
    assert ok.sum() > 100
    np.testing.assert_allclose(got[ok], rows[:, 3:][ok], rtol=1e-12, atol=1e-12)
    one = s.meter(pts[~np.isnan(got[:, 0])][:1], facing=(0.0, 2.0))  # one direction for all, normalised
    assert one["E_v"].shape == (1,)
    with pytest.raises(polarlux.PolarluxError):
        s.meter(pts[:1], facing=(0.0, 0.0))
    with pytest.raises(ValueError, match="facing must have shape"):
        s.meter(pts[:2], facing=np.zeros((3, 2)))


def test_meter_under_a_lamp_is_spec_formula():
    """One isotropic lamp, no buildings (SPEC §2, §6): E_h = I h / d^3 W(d/R),
    E_v = I (u.r) / d^3 W(d/R), W(x) = (1 - x^4)^2, R = 30 m."""
    s = polarlux.Scene('{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature",'
                       '"properties":{"lamp":true,"intensity":1000,"height":6},'
                       '"geometry":{"type":"Point","coordinates":[0,0]}}]}')
    m = s.meter([[3.0, 4.0, 1.5]], facing=(-1.0, 0.0))
    d = np.sqrt(9 + 16 + 4.5 ** 2)
    w = (1 - (d / 30) ** 4) ** 2
    assert abs(m["E_h"][0] - 1000 * 4.5 / d ** 3 * w) < 1e-12
    assert abs(m["E_v"][0] - 1000 * 3 / d ** 3 * w) < 1e-12


def test_scene_inputs_and_lifetime_errors(tmp_path):
    import copy
    import json
    import pickle
    with open(TINY) as f:
        as_dict = json.load(f)
    assert polarlux.Scene(as_dict).info["buildings"] == 4
    with pytest.raises(TypeError, match="GeoJSON text"):
        polarlux.Scene(5)
    with pytest.raises(ValueError, match="render_max"):
        polarlux.Scene(as_dict, render_max=(-1, -1))
    with pytest.raises(ValueError, match="lit_cache_bytes"):
        polarlux.Scene(as_dict, lit_cache_bytes=-1)
    with pytest.raises(ValueError, match="GeoJSON text"):
        polarlux.memory_estimate(TINY)
    with pytest.raises(polarlux.PolarluxError, match="malformed JSON"):
        polarlux.Scene("not json")  # the load's own message, not memory_estimate's
    with pytest.raises(ValueError, match="a bake file .* Scene.from_bake"):
        polarlux.Scene(polarlux.BAKE_MAGIC + b"rest")
    s = polarlux.Scene.from_file(TINY)
    assert repr(s) == "<polarlux.Scene: 4 buildings, 3 lamps>"
    with pytest.raises(TypeError, match="cannot be pickled"):
        pickle.dumps(s)
    with pytest.raises(TypeError, match="cannot be copied"):
        copy.copy(s)
    with pytest.raises(ValueError, match="held must be"):
        s.render(eye=(30, 12, 1.7), target=(50, 10, 1), size=(8, 6), exposure="auto", held=-1)
    with pytest.raises(ValueError, match="size must be"):
        s.render(eye=(30, 12, 1.7), target=(50, 10, 1), size=(8.5, 6))
    with pytest.raises(ValueError, match="size must be"):  # a bare int was a TypeError from inside (helper-64)
        s.render(eye=(30, 12, 1.7), target=(50, 10, 1), size=32)
    with pytest.raises(ValueError, match="step must be a number of metres above 0, not 0"):  # each named
        s.route_score([[30, 12], [50, 12]], step=0)
    with pytest.raises(ValueError, match="dark_lux must be"):
        s.route_score([[30, 12], [50, 12]], dark_lux=-1)
    s.close()
    assert repr(s) == "<polarlux.Scene (closed)>"
    for call in (lambda: s.illuminance([[30, 12]]), lambda: s.memory(), lambda: s.meter([[30, 12, 1.5]])):
        with pytest.raises(ValueError, match="the Scene is closed"):
            call()


def test_ground_image_not_loaded_is_said():
    s = polarlux.Scene.from_file(os.path.join(ROOT, "fixtures", "ground-image.geojson"))
    assert any("ground image" in w and "is not loaded" in w for w in s.warnings)


def test_route_facial_matches_the_command():
    """facial_height=1.5: the Ev/Esc minima and class_fr of polarlux route's table."""
    import json
    s = polarlux.Scene.from_file(HELSINKI)
    path = os.path.join(ROOT, "fixtures", "helsinki-route.geojson")
    with open(path) as f:
        feats = json.load(f)["features"]
    rc, out, _ = run_cli("route", "-q", HELSINKI, "--path", path)
    assert rc == 0
    rows = {}
    name = None
    for line in out.splitlines()[1:]:
        w = line.split()
        if not w or not (w[0] == "all" or w[0].isdigit() or w[1] == "all"):
            continue
        if w[1] == "all":
            name = w[0]
            w = w[1:]
        rows[(name, w[0])] = w
    checked = 0
    for ft in feats:
        nm = ft["properties"].get("name")
        xy = s.lonlat_to_local(ft["geometry"]["coordinates"])
        tot, seg = s.route_score(xy, facial_height=1.5)
        for key, vals in [("all", tot)] + [(str(i), {k: v[i] for k, v in seg.items()}) for i in range(len(xy) - 1)]:
            w = rows[(nm, key)]
            assert abs(vals["mean"] - float(w[2])) < 6e-4
            for col, k in zip(w[8:12], ("min_ev_fw", "min_ev_bw", "min_esc_fw", "min_esc_bw")):
                assert abs(vals[k] - float(col)) < 6e-4, (nm, key, k)
            assert (f"P{vals['class_fr']}" if vals["class_fr"] else "-") == w[12]
            checked += 1
    assert checked >= 4
