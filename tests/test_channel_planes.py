"""Rendering into one camera's channel planes (issue 38): each band integrated into the camera's photo-electron rates
as it is rendered, the (H, W, B) cube never held, and the same capture as from the cube.

Held here: the planes are the cube through the camera's band weights (both renderers, float32 rounding); a capture of
the planes is the cube's (same exposure, digital numbers apart only where float32 rounding crosses a quantisation
step, the same scores); no array of the cube's size is allocated on the way; and every refusal is one line before any
file is written (another camera, an off-axis field, light groups, a textured target, another white, planes that
contradict their scene).
"""
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import small_scene
from spectracam.camera import band_weights
from spectracam.core.errors import SpectracamError
from spectracam.pipeline import capture, check_memory, render, render_planes, score


def through_weights(cube, camera):
    """The cube's photo-electron rates in float64: what the planes stand for."""
    w = band_weights(camera, cube.grid).astype(np.float64)
    r = cube.radiance
    return (r.reshape(-1, r.shape[-1]).astype(np.float64) @ w).reshape(*r.shape[:2], w.shape[1])


@pytest.mark.parametrize("renderer", ["analytic", "mitsuba"])
def test_the_planes_are_the_cube_through_the_cameras_weights(renderer):
    scene = small_scene()
    cube, planes = render(scene, renderer), render_planes(scene, renderer)
    want = through_weights(cube, scene.camera)
    assert planes.planes.shape == want.shape == (120, 160, 3) and planes.planes.dtype == np.float32
    # float32 accumulation over the bands: a few ulp of the largest rate
    np.testing.assert_allclose(planes.planes, want, rtol=0, atol=1e-6 * want.max())
    np.testing.assert_allclose(planes.weights, band_weights(scene.camera, scene.grid), rtol=1e-7)
    assert planes.metadata["scene"] == scene.to_dict() and planes.metadata["renderer"] == renderer
    assert planes.metadata["channel_planes"]["channels"] == ["R", "G", "B"]


@pytest.mark.parametrize("design", [None, "stacked/single", "fsc/single", "rgbw/single"])
def test_a_capture_of_the_planes_is_the_capture_of_the_cube(design):
    """Same metering, same noise draws: the digital numbers differ only where the rates' float32 rounding (the sensor
    pass sums the bands itself) crosses a quantisation step, by one DN; the scores agree to 1e-3 ΔE."""
    scene = small_scene(image={"width": 240, "height": 180})
    if design is not None:
        scene = scene.replace(camera=scene.camera.with_design(design))
    a = capture(render(scene, "analytic"), scene=scene)
    b = capture(render_planes(scene, "analytic"), scene=scene)
    np.testing.assert_allclose(b.exposure_times_s, a.exposure_times_s, rtol=1e-6)
    np.testing.assert_allclose(b.metered_rate_e_per_s, a.metered_rate_e_per_s, rtol=1e-6)
    differ = a.digital != b.digital
    assert differ.mean() < 1e-3 and (np.abs(a.digital - b.digital).max() <= 1)
    sa, sb = score(a, scene).summary, score(b, scene).summary
    assert sb.delta_e_mean == pytest.approx(sa.delta_e_mean, abs=1e-3)
    assert sb.s_cielab_mean == pytest.approx(sa.s_cielab_mean, abs=1e-3)
    assert sb.capture_time_ms == pytest.approx(sa.capture_time_ms, rel=1e-6)


def test_the_planes_never_hold_an_array_of_the_cubes_size():
    """The point of the option: render + capture of the planes allocate under a third of one cube (the planes are
    3/30 of it, the capture's planes as many again); a path that rendered the cube and integrated it afterwards
    would allocate it all."""
    import tracemalloc

    scene = small_scene(image={"width": 400, "height": 300})
    capture(render_planes(scene, "analytic"), scene=scene)      # tables, kernels
    cube_bytes = 400 * 300 * len(scene.grid) * 4
    tracemalloc.start()
    try:
        capture(render_planes(scene, "analytic"), scene=scene)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < cube_bytes / 3, peak / cube_bytes


def test_planes_for_another_camera_are_refused():
    scene = small_scene()
    planes = render_planes(scene, "analytic")
    with pytest.raises(SpectracamError, match="another camera"):
        capture(planes, scene=scene, design="stacked/single")      # other responsivities: other weights
    other = scene.replace(camera=scene.camera.with_design("stacked/single"))
    assert capture(render_planes(scene, "analytic", camera=other.camera), scene=other).digital.ndim == 3


@pytest.mark.parametrize("tables, message", [
    ({"optics": {"relative_illumination": "cos4"}}, r"optics.relative_illumination = 'cos4'"),
    ({"optics": {"cra_corner_deg": 20.0}}, r"optics.cra_corner_deg = 20"),
    ({"pixel": {"microlens": True}}, r"pixel.microlens = True"),
    ({"target": {"kind": "photo"}}, r"target = 'photo'"),
])
def test_a_scene_the_planes_cannot_stand_for_is_refused_before_rendering(tables, message):
    with pytest.raises(SpectracamError, match=message):
        render_planes(small_scene(**tables), "analytic")


def test_light_groups_and_another_white_are_refused():
    from spectracam.pipeline.scene_file import parse_scene

    light = {"type": "cie", "name": "D65", "white_luminance_cd_m2": 100.0}
    lights = parse_scene({"image": {"width": 256, "height": 96},
                          "lights": [{"name": "a", "illuminant": light}, {"name": "b", "illuminant": light}]})
    with pytest.raises(SpectracamError, match="light groups"):
        render_planes(lights, "analytic")
    scene = small_scene()
    planes = render_planes(scene, "analytic")
    with pytest.raises(SpectracamError, match="white = 'brightest'"):
        capture(planes, scene=scene, white="brightest")
    assert capture(planes, scene=scene, white="patch").digital.shape == (120, 160)


def test_planes_that_contradict_their_scene_are_refused():
    scene = small_scene()
    planes = render_planes(scene, "analytic")
    planes.planes[..., 1] *= 1.05                                   # the green channel 5 % brighter everywhere
    with pytest.raises(SpectracamError, match=r"patch \d+ .* differs by .* % rms"):
        capture(planes, scene=scene)
    other = small_scene(image={"width": 168, "height": 120})
    with pytest.raises(SpectracamError, match="160x120 pixels, but its scene says 168x120"):
        capture(render_planes(scene, "analytic"), scene=other)


def test_the_memory_check_counts_the_planes_not_the_cube(monkeypatch):
    import spectracam.pipeline as pipeline
    from spectracam.pipeline import MEMORY_PER_CUBE, MEMORY_PER_PIXEL_PLANES

    scene = small_scene(image={"width": 4000, "height": 3000})
    px = 4000 * 3000
    cube_need = px * len(scene.grid) * 4 * MEMORY_PER_CUBE
    monkeypatch.setattr(pipeline, "memory_available", lambda: ((cube_need + px * MEMORY_PER_PIXEL_PLANES) / 2, "test"))
    with pytest.raises(SpectracamError, match=f"image = 4000x3000 with {len(scene.grid)} bands: needs about"):
        check_memory(scene)
    check_memory(scene, channel_planes=True)   # a tenth of the memory: it fits
    assert MEMORY_PER_PIXEL_PLANES <= 0.75 * len(scene.grid) * 4 * MEMORY_PER_CUBE


def test_simulate_channel_planes_writes_the_capture_and_no_spectral_cube(tmp_path):
    run = [sys.executable, "-m", "spectracam", "simulate", "d65", "--renderer", "analytic", "--quiet",
           "--set", "image.width=160", "--set", "image.height=120"]
    a = subprocess.run(run + ["-o", str(tmp_path / "cube")], capture_output=True, text=True)
    b = subprocess.run(run + ["-o", str(tmp_path / "planes"), "--channel-planes"], capture_output=True, text=True)
    assert a.returncode == 0 and b.returncode == 0, b.stderr
    assert (tmp_path / "cube" / "radiance.exr").exists() and not (tmp_path / "planes" / "radiance.exr").exists()
    assert {"raw.exr", "raw.dng", "report.json", "rendered.exr"} <= {p.name for p in (tmp_path / "planes").iterdir()}
    ra, rb = (json.loads((tmp_path / d / "report.json").read_text()) for d in ("cube", "planes"))
    assert rb["chart"]["delta_e_mean"] == pytest.approx(ra["chart"]["delta_e_mean"], abs=1e-3)
    assert rb["both_ways"]["developed"]["delta_e_mean"] == pytest.approx(ra["both_ways"]["developed"]["delta_e_mean"],
                                                                         abs=1e-3)
    from spectracam.io.exr import read_raw_exr

    raw = read_raw_exr(tmp_path / "planes" / "raw.exr")
    assert raw.digital.shape == (120, 160) and raw.scene is not None
    assert raw.rates == "channel planes" and read_raw_exr(tmp_path / "cube" / "raw.exr").rates == "cube"
    bad = subprocess.run(run + ["-o", str(tmp_path / "bad"), "--channel-planes", "--set",
                                "optics.relative_illumination='cos4'"], capture_output=True, text=True)
    assert bad.returncode != 0 and len(bad.stderr.strip().splitlines()) == 1 and "channel planes" in bad.stderr
    assert not (tmp_path / "bad").exists() or not any((tmp_path / "bad").iterdir())


@pytest.fixture(scope="module")
def radiance_file(tmp_path_factory):
    """A spectracam radiance.exr (analytic, 160×120) and a copy of it that records no scene (another tool's)."""
    from spectracam.io.exr import read_exr, write_exr, write_radiance_exr

    d = tmp_path_factory.mktemp("planes-capture")
    write_radiance_exr(d / "radiance.exr", render(small_scene(), "analytic"))
    channels, attrs = read_exr(d / "radiance.exr")    # the same pixels without the spectracam* attributes
    write_exr(d / "foreign.exr", channels, {k: v for k, v in attrs.items()
                                            if k in ("spectralLayoutVersion", "emissiveUnits")})
    return d


def test_the_files_bands_unstacked_are_the_cubes(radiance_file):
    from spectracam.io.exr import read_radiance_bands, read_radiance_exr

    cube, _ = read_radiance_exr(radiance_file / "radiance.exr")
    wl, bands, meta, _ = read_radiance_bands(radiance_file / "radiance.exr")
    assert np.array_equal(np.stack(bands, axis=-1), cube.radiance) and np.array_equal(wl, cube.wavelengths_nm)
    assert meta["scene"] == cube.metadata["scene"]


def test_capture_channel_planes_is_the_capture_of_the_cube(radiance_file, tmp_path):
    from spectracam.io.exr import read_raw_exr

    run = [sys.executable, "-m", "spectracam", "capture", str(radiance_file / "radiance.exr"), "--quiet"]
    a = subprocess.run(run + ["-o", str(tmp_path / "cube")], capture_output=True, text=True)
    b = subprocess.run(run + ["-o", str(tmp_path / "planes"), "--channel-planes"], capture_output=True, text=True)
    assert a.returncode == 0 and b.returncode == 0, b.stderr
    ra, rb = read_raw_exr(tmp_path / "cube" / "raw.exr"), read_raw_exr(tmp_path / "planes" / "raw.exr")
    np.testing.assert_allclose(rb.exposure_times_s, ra.exposure_times_s, rtol=1e-6)
    assert (ra.digital != rb.digital).mean() < 1e-3 and np.abs(ra.digital - rb.digital).max() <= 1
    assert (tmp_path / "planes" / "raw.dng").exists()


@pytest.mark.parametrize("extra, message", [
    (["--white", "brightest"], "white = 'brightest'"),
    (["--set", "optics.relative_illumination='cos4'"], "optics.relative_illumination = 'cos4'"),
])
def test_capture_channel_planes_refuses_in_one_line(radiance_file, tmp_path, extra, message):
    run = [sys.executable, "-m", "spectracam", "capture", "--channel-planes", "--quiet", "-o", str(tmp_path / "o")]
    r = subprocess.run(run + [str(radiance_file / "radiance.exr"), *extra], capture_output=True, text=True)
    assert r.returncode != 0 and len(r.stderr.strip().splitlines()) == 1 and message in r.stderr, r.stderr
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())
    r = subprocess.run(run + [str(radiance_file / "foreign.exr")], capture_output=True, text=True)
    assert r.returncode != 0 and "records no spectracam scene" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_a_capture_records_what_its_rates_came_from(tmp_path):
    """raw.exr says a capture of channel planes is one (its recorded parameters reproduce it through the same path);
    a cube's file carries no new attribute; a damaged value is refused in one line."""
    from spectracam.core.errors import SpectracamError
    from spectracam.io.exr import read_exr, read_raw_exr, write_exr, write_raw_exr

    scene = small_scene()
    a, b = capture(render(scene, "analytic"), scene=scene), capture(render_planes(scene, "analytic"), scene=scene)
    assert (a.rates, b.rates) == ("cube", "channel planes")
    write_raw_exr(tmp_path / "a.exr", a)
    write_raw_exr(tmp_path / "b.exr", b)
    assert "spectracamRates" not in read_exr(tmp_path / "a.exr")[1]
    assert read_raw_exr(tmp_path / "b.exr").rates == "channel planes"
    channels, attrs = read_exr(tmp_path / "b.exr")
    write_exr(tmp_path / "c.exr", channels, {**attrs, "spectracamRates": "guessed"})
    with pytest.raises(SpectracamError, match="spectracamRates = 'guessed'"):
        read_raw_exr(tmp_path / "c.exr")
