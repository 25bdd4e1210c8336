"""Issue 19: textured targets of measured reflectances (library chart, Mondrian, dead leaves, photograph),
rendered by Mitsuba and in closed form, scored per pixel; every standard light and a measured SPD."""
import json
import subprocess
import sys

import numpy as np
import pytest

from spectracam.scene._paint import paint_shapes
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.scene.illuminant import IlluminantSpec, spectral_irradiance
from spectracam.pipeline import capture, score
from spectracam.scene.reference import ChartReference, TargetReference, library_colours
from spectracam.render import render
from spectracam.pipeline.scene_file import Scene, load_scene
from spectracam.core.spectra import cie_1931_cmfs
from spectracam.scene.target import TargetSpec, power_law, texel_labels

NOISE_OFF = {"shot_noise": False, "dark_current": False, "read_noise": False, "fpn": False, "quantization": False}


def small(kind, **target):
    return Scene.from_dict({"target": {"kind": kind, "size_max_px": 12, **target}, "image": {"width": 48, "height": 36},
                            "illuminant": {"type": "cie", "name": "D65"}})


# -- layouts --------------------------------------------------------------------------------------------

def test_a_library_chart_shows_every_sample_once_as_a_square_of_its_cell():
    spec = TargetSpec(kind="samples", columns=11, gap=0.2, supersampling=1)
    labels = texel_labels(spec, 440, 360, 99)        # cells of 40 px: squares of 32 px
    counts = np.bincount(labels.ravel(), minlength=100)
    assert np.all(counts[:99] == 32 * 32) and counts[99] == 440 * 360 - 99 * 32 * 32
    assert labels[4 + 20, 4 + 40 * 3] == 3 and labels[40 + 4 + 20, 4] == 11     # row by row, 11 across
    chosen = texel_labels(TargetSpec(kind="samples", samples=(5, 7), supersampling=1), 64, 32, 99)
    assert set(np.unique(chosen)) == {5, 7, 99}
    with pytest.raises(ConfigError, match="target.samples"):
        texel_labels(TargetSpec(kind="samples", samples=(99,)), 64, 32, 99)


def test_painted_shapes_cover_their_area_and_the_first_drawn_lies_on_top():
    labels = np.full((200, 200), -1, np.int32)
    f = np.array
    bare = paint_shapes(labels, f([100.0, 130.0]), f([100.0, 100.0]), f([40.0, 40.0]), f([40.0, 40.0]),
                        f([1, 2], np.int32), True, labels.size)
    n1, n2 = (labels == 1).sum(), (labels == 2).sum()
    assert n1 == pytest.approx(np.pi * 40**2, rel=0.01)        # a whole disc: π r² texels
    d = 30.0                                                    # the second shows only outside the first
    lens = 2 * 40**2 * np.arccos(d / 80) - d / 2 * np.sqrt(4 * 40**2 - d**2)
    assert n2 == pytest.approx(np.pi * 40**2 - lens, rel=0.02) and bare == labels.size - n1 - n2
    rect = np.full((100, 100), -1, np.int32)
    paint_shapes(rect, f([50.0]), f([40.0]), f([20.0]), f([10.0]), f([0], np.int32), False, rect.size)
    assert (rect == 0).sum() == 40 * 20                          # 2·half sides, by texel centres


def test_dead_leaf_radii_follow_the_power_law():
    """r^-3 on [2, 200]: the CDF is (r⁻² − lo⁻²)/(hi⁻² − lo⁻²); the maximum-likelihood exponent of the draws."""
    u = np.random.default_rng(1).uniform(size=200_000)
    r = power_law(u, 2.0, 200.0, 3.0)
    assert r.min() >= 2.0 and r.max() <= 200.0
    cdf = lambda x: (x**-2.0 - 2.0**-2) / (200.0**-2 - 2.0**-2)  # noqa: E731
    for x in (2.5, 4.0, 10.0, 50.0):
        assert np.mean(r <= x) == pytest.approx(cdf(x), abs=0.004)
    assert power_law(np.array([0.0, 0.5, 0.999999]), 1.0, 100.0, 1.0) == pytest.approx([1, 10, 100], rel=1e-4)


@pytest.mark.parametrize("kind", ["mondrian", "dead_leaves"])
def test_painted_targets_cover_every_texel_reproducibly(kind):
    a = texel_labels(TargetSpec(kind=kind, seed=3, size_max_px=16), 64, 48, 99)
    assert a.shape == (192, 256) and a.min() >= 0 and a.max() < 99
    assert np.array_equal(a, texel_labels(TargetSpec(kind=kind, seed=3, size_max_px=16), 64, 48, 99))
    assert not np.array_equal(a, texel_labels(TargetSpec(kind=kind, seed=4, size_max_px=16), 64, 48, 99))
    assert np.unique(a).size > 20


def test_a_photograph_of_library_colours_gets_their_spectra_back(tmp_path):
    """Texels whose sRGB is exactly a sample's colour under D65 are assigned that sample."""
    import colour

    d65 = library_colours("cfi99", IlluminantSpec("cie", None, "D65", 100.0), Scene().grid)
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    chosen = [3, 17, 42, 60, 88, 95]
    rgb = np.clip(d65.xyz[chosen] @ np.asarray(srgb.matrix_XYZ_to_RGB).T, 0, 1)
    ok = [i for i, c in zip(chosen, rgb) if 0.01 < c.min() and c.max() < 0.99]     # inside the sRGB gamut
    assert len(ok) >= 3
    encoded = np.asarray(colour.cctf_encoding(rgb, "sRGB"))
    img = np.repeat(np.repeat((encoded * 65535 + 0.5).astype(np.uint16)[None], 8, axis=0), 8, axis=1)   # 8 rows × 48
    import tifffile

    tifffile.imwrite(tmp_path / "p.tif", img)
    scene = Scene.from_dict({"target": {"kind": "photo", "photo": f"file:{tmp_path / 'p.tif'}", "supersampling": 1},
                             "image": {"width": 48, "height": 8}})
    labels = TargetReference.of(scene).pixel_labels()
    for j, i in enumerate(chosen):
        if i in ok:
            assert np.all(labels[:, 8 * j + 2: 8 * j + 6] == i)


def test_a_damaged_missing_or_changed_photograph_is_one_line(tmp_path):
    from spectracam.scene.target import resolve_target_files

    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\n not really")
    scene = Scene.from_dict({"target": {"kind": "photo", "photo": f"file:{tmp_path / 'bad.png'}"},
                             "image": {"width": 16, "height": 16}})
    with pytest.raises(SpectracamError, match="not an image file"):
        TargetReference.of(scene)
    with pytest.raises(ConfigError, match="cannot be read"):
        TargetSpec(kind="photo", photo=f"file:{tmp_path / 'missing.png'}")
    t = resolve_target_files({"kind": "photo", "photo": "file:bad.png"}, tmp_path)
    assert t["photo"] == f"file:{tmp_path / 'bad.png'}"
    recorded = scene.to_dict()["target"]
    assert len(recorded["photo_sha256"]) == 64                  # the scene records the file it was made from
    (tmp_path / "bad.png").write_bytes(b"changed")
    with pytest.raises(ConfigError, match="has changed since the scene was recorded"):
        Scene.from_dict({"target": recorded, "image": {"width": 16, "height": 16}})


# -- renderers --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["samples", "mondrian", "dead_leaves", "photo"])
def test_mitsuba_renders_every_target_as_its_closed_form_within_the_render_noise(kind):
    """Pixels inside one sample are exact; where samples meet, the box-filtered Monte Carlo's squared
    error is the variance of the pixel's texels over the samples per pixel (an offset or a flipped
    texture would show in both).  Random positions (``sampler="independent"``; the default, one ray per texel
    centre, is exact: tests/test_textured_render.py), the same in every band (issue 34)."""
    from spectracam.render.target import render_target_mitsuba

    scene = small(kind)
    a, m = render(scene, "analytic"), render_target_mitsuba(scene, sampler="independent")
    ref = TargetReference.of(scene)
    pure = ref.pixel_labels() >= 0
    scale = float(a.radiance.mean())
    assert np.abs(m.radiance - a.radiance)[pure].max() <= 1e-5 * scale
    sq_mean = ref.pixel_mean(ref.radiance.astype(np.float64) ** 2)
    expected = (sq_mean - a.radiance.astype(np.float64) ** 2) / scene.render.samples_per_pixel   # (H, W, B)
    got = (m.radiance.astype(np.float64) - a.radiance) ** 2
    assert got[~pure].sum() / expected[~pure].sum() == pytest.approx(1.0, abs=0.15)
    assert abs((m.radiance - a.radiance)[~pure].mean()) < 4 * np.sqrt(expected[~pure].mean() / (~pure).sum())


def test_a_target_renders_at_the_stated_light_level():
    """The surround of a library chart is a flat reflectance: its radiance is ρ·E/π of the light."""
    from spectracam.scene.illuminant import white_diffuser_radiance

    scene = Scene.from_dict({"target": {"kind": "samples"}, "image": {"width": 64, "height": 48}})
    cube = render(scene, "analytic")
    ref = TargetReference.of(scene)
    surround = ref.pixel_labels() == ref.surround
    want = scene.chart.surround_reflectance * white_diffuser_radiance(scene.illuminant, scene.grid)
    np.testing.assert_allclose(cube.radiance[surround].mean(axis=0), want, rtol=1e-5)


# -- scores -----------------------------------------------------------------------------------------------

def _noise_free(scene, design="prism/optimal"):
    scene = scene.replace(camera=scene.camera.with_design(design).replace(
        sensor=scene.camera.sensor.replace(**NOISE_OFF)))
    return scene, score(capture(render(scene, "analytic"), scene=scene), scene)


def test_noise_free_sample_scores_are_the_conversion_error_and_s_cielab_is_cielab_on_flat_areas():
    scene, s = _noise_free(Scene.from_dict({"target": {"kind": "samples"}, "image": {"width": 220, "height": 180}}))
    h = s.held_out
    assert h["samples"] == 99 and h["samples_scored"] == 99 and not h["fitted_on_these"]
    for smp in s.samples:
        assert smp.delta_e_of_mean == pytest.approx(smp.delta_e_conversion, abs=2e-3)
        assert smp.delta_e_mean == pytest.approx(smp.delta_e_conversion, abs=2e-3)
    ref = TargetReference.of(scene)
    assert h["pixels"] == int((ref.pixel_labels() != ref.surround).sum())
    # squares of 128 px: at their centres the 1° (41 px) S-CIELAB kernels see a flat field, and with the
    # default XYZ-scaling adaptation S-CIELAB is the per-pixel CIELAB ΔE there
    scene, s = _noise_free(Scene.from_dict({"target": {"kind": "samples", "samples": [0, 30, 60, 90], "columns": 2},
                                            "image": {"width": 320, "height": 320}}))
    centres = s.scielab_map[64 - 4:64 + 4, 64 - 4:64 + 4], s.delta_e_map[64 - 4:64 + 4, 64 - 4:64 + 4]
    assert centres[1].mean() == pytest.approx(s.samples[0].delta_e_conversion, abs=2e-3)
    np.testing.assert_allclose(centres[0], centres[1], atol=2e-3)
    assert np.nanmax(np.abs(s.scielab_map - s.delta_e_map)) > 0.5    # but not near the edges


def test_the_chart_as_a_target_scores_the_training_error():
    """The ColorChecker's own samples as a library chart: what the conversion was fitted on, flagged so;
    each sample's error is the chart's training error of that patch (two paths to the same numbers)."""
    _, s = _noise_free(Scene.from_dict({"target": {"kind": "samples", "library": "colorchecker24"},
                                        "image": {"width": 240, "height": 160}}))
    assert s.held_out["fitted_on_these"] and s.held_out["samples_scored"] == 24
    assert np.mean([x.delta_e_of_mean for x in s.samples]) == pytest.approx(s.training["delta_e_mean"], abs=2e-3)


def test_noise_and_demosaicking_show_per_pixel_and_s_cielab_forgives_edges():
    scene = Scene.from_dict({"target": {"kind": "dead_leaves", "size_max_px": 30}, "image": {"width": 160,
                                                                                             "height": 120}})
    s = score(capture(render(scene, "analytic"), scene=scene), scene)
    h = s.held_out
    assert h["delta_e_mean"] > h["sample_delta_e_of_mean_mean"] > 0       # pixels carry noise and edges
    assert h["s_cielab_mean"] < h["delta_e_mean"]                          # the eye's blur forgives both
    assert h["delta_e_p95"] >= h["delta_e_mean"] and h["delta_e_max"] >= h["delta_e_p95"]
    assert h["samples"] <= 99 and s.delta_e_map.shape == (120, 160)


def test_simulate_a_target_writes_its_files_and_capture_score_read_them_back(tmp_path):
    (tmp_path / "t.toml").write_text('[target]\nkind = "mondrian"\nsize_max_px = 20\n'
                                     '[image]\nwidth = 64\nheight = 48\n')
    r = subprocess.run([sys.executable, "-m", "spectracam", "simulate", str(tmp_path / "t.toml"), "-o",
                        str(tmp_path / "s")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "mondrian of cfi99 (colours it was not fitted on)" in r.stderr
    rep = json.loads((tmp_path / "s" / "report.json").read_text())
    assert {"delta_e_mean", "delta_e_p95", "pixels", "samples", "s_cielab_mean"} <= set(rep["held_out"])
    assert rep["parameters"]["scene"]["target"]["kind"] == "mondrian"
    for f in ("radiance.exr", "raw.exr", "raw.dng", "rendered.exr", "rendered.png", "delta_e.png", "s_cielab.png",
              "report.csv"):
        assert (tmp_path / "s" / f).stat().st_size > 0
    r = subprocess.run([sys.executable, "-m", "spectracam", "capture", str(tmp_path / "s" / "radiance.exr"), "-o",
                        str(tmp_path / "c")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([sys.executable, "-m", "spectracam", "score", str(tmp_path / "c" / "raw.exr"), "-o",
                        str(tmp_path / "d")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    again = json.loads((tmp_path / "d" / "report.json").read_text())
    assert again["held_out"] == rep["held_out"]                 # the same seed, the same numbers
    r = subprocess.run([sys.executable, "-m", "spectracam", "score", str(tmp_path / "c" / "raw.exr"), "-o",
                        str(tmp_path / "e"), "--set", "target.seed=1"], capture_output=True, text=True)
    assert r.returncode == 2 and "another target" in r.stderr


@pytest.mark.parametrize("bad, what", [("target.kind=\"leaves\"", "target.kind"),
                                       ("target.library=\"nope\"", "target.library"),
                                       ("target.supersampling=0", "target.supersampling"),
                                       ("target.size_max_px=1", "target.size_max_px"),
                                       ("target.photo=\"nowhere\"", "target.photo")])
def test_bad_target_values_are_one_line(tmp_path, bad, what):
    r = subprocess.run([sys.executable, "-m", "spectracam", "render", "scenes/dead_leaves.toml", "-o",
                        str(tmp_path), "--set", bad], capture_output=True, text=True)
    assert r.returncode == 2 and what in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_the_sweep_and_the_paper_refuse_a_textured_target_in_one_line(tmp_path):
    sweep = tmp_path / "sw.toml"
    sweep.write_text(f'base_scene = "{__import__("pathlib").Path("scenes/dead_leaves.toml").resolve()}"\n'
                     'metrics = ["delta_e_mean"]\n[axes]\n"sensor.read_noise_e" = [10, 20]\n')
    r = subprocess.run([sys.executable, "-m", "spectracam", "sweep", str(sweep), "-o", str(tmp_path / "o"), "--serial"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "a sweep scores the ColorChecker" in r.stderr, r.stderr
    r = subprocess.run([sys.executable, "-m", "spectracam", "paper", "--quick", "-o", str(tmp_path / "p"), "--set",
                        'target.kind="mondrian"'], capture_output=True, text=True)
    assert r.returncode == 2 and "the paper's experiment scores the ColorChecker" in r.stderr, r.stderr


# -- lights ----------------------------------------------------------------------------------------------

def _every_illuminant():
    import colour

    return sorted(colour.SDS_ILLUMINANTS)


@pytest.mark.parametrize("name", _every_illuminant())
def test_every_illuminant_colour_science_ships_lights_a_scene_at_the_stated_level(name):
    spec = IlluminantSpec.from_dict({"type": "cie", "name": name, "white_luminance_cd_m2": 250.0})
    wl, cmfs = cie_1931_cmfs()
    assert 683 * np.trapezoid(spectral_irradiance(spec)(wl) / np.pi * cmfs[:, 1], wl) == pytest.approx(250.0, rel=1e-9)
    ref = ChartReference.of(Scene(illuminant=spec, image=Scene().image.replace(width=96, height=72)))
    assert ref.white_xyz[1] == pytest.approx(1.0) and np.all(ref.patch_xyz[:, 1] > 0)


def test_a_measured_spd_from_a_file_is_the_light_it_measures(tmp_path):
    import colour

    sd = colour.SDS_ILLUMINANTS["FL2"]
    rows = "\n".join(f"{w:g},{v:.9g}" for w, v in zip(sd.wavelengths, sd.values))
    (tmp_path / "fl2.csv").write_text("wavelength_nm,relative power\n" + rows + "\n")
    (tmp_path / "s.toml").write_text('[illuminant]\nfile = "fl2.csv"\nwhite_luminance_cd_m2 = 80\n')
    scene = load_scene(tmp_path / "s.toml")
    assert scene.illuminant.kind == "measured" and scene.illuminant.name == "fl2.csv"
    assert scene.to_dict()["illuminant"]["values"][0] == pytest.approx(sd.values[0])    # the data, not a path
    cie = scene.replace(illuminant=IlluminantSpec.from_dict({"type": "cie", "name": "FL2",
                                                            "white_luminance_cd_m2": 80}))
    a, b = ChartReference.of(scene), ChartReference.of(cie)
    np.testing.assert_allclose(a.patch_radiance, b.patch_radiance, rtol=1e-9)
    np.testing.assert_allclose(a.patch_xyz, b.patch_xyz, rtol=1e-9)


@pytest.mark.parametrize("csv, what", [("400,1\n500,2\n", "wavelengths_nm"),
                                       ("400,1\n550,-1\n700,1\n", "values"),
                                       ("400,0\n550,0\n700,0\n", "values"),
                                       ("450,1\n550,1\n650,1\n", "must cover the scene's bands"),
                                       ("0.4,1\n0.55,1\n0.7,1\n", "wavelengths_nm"),
                                       ("400,1\n400,1\n700,1\n", "wavelengths_nm"),
                                       ("400;1\n", "is not a curve")])
def test_a_bad_spd_file_is_one_line(tmp_path, csv, what):
    (tmp_path / "l.csv").write_text(csv)
    (tmp_path / "s.toml").write_text('[illuminant]\nfile = "l.csv"\n')
    r = subprocess.run([sys.executable, "-m", "spectracam", "render", str(tmp_path / "s.toml"), "-o",
                        str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode == 2 and what in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "o").exists()
