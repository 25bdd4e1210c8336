"""A new architecture defined in this file alone — a Quad-Bayer colour filter array (2×2 blocks of one
colour in a 4×4 tile) — goes through capture, scoring, the raw EXR, the DNG and ``--arch`` on the
command line without any edit to spectracam: everything downstream dispatches on its layout."""
import numpy as np
import pytest
from click.testing import CliRunner

from spectracam import ChartReference, capture, score
from spectracam.architecture import ARCHITECTURES, Architecture, MosaicLayout
from spectracam.cli import main
from spectracam.color import ProcessingSpec
from spectracam.errors import ConfigError
from spectracam.io.dng import write_dng
from spectracam.io.exr import read_raw_exr, write_radiance_exr, write_raw_exr

QUAD = MosaicLayout(((0, 0, 1, 1), (0, 0, 1, 1), (1, 1, 2, 2), (1, 1, 2, 2)))


class QuadBayer(Architecture):
    name = "quad"
    independent_exposures = False
    layout = QUAD

    def capture_time_s(self, times_s):
        return float(times_s[0])

    def record(self, rates, times_s, sensor, seed):
        return self.record_mosaic(rates, times_s, sensor, seed)


@pytest.fixture(autouse=True)
def quad_registered():
    ARCHITECTURES.register("quad", QuadBayer)
    yield
    ARCHITECTURES.unregister("quad")


def test_quad_bayer_captures_and_scores(scene_5000, analytic_5000):
    raw = capture(analytic_5000, design="quad/single", seed=2, scene=scene_5000)
    assert raw.layout == QUAD and raw.digital.shape == (120, 160) and raw.design == "quad/single"
    # each pixel holds the expected charge of its own channel in the 4x4 tile
    from spectracam.camera import photo_electron_rates

    rates = photo_electron_rates(analytic_5000.radiance, analytic_5000.grid, raw.camera)
    idx = QUAD.channel_index((120, 160))
    t = raw.exposure_times_s[0]
    expected = np.take_along_axis(rates, idx[..., None], axis=2)[..., 0] * t + raw.camera.sensor.dark_rate_e_per_s * t
    np.testing.assert_allclose(raw.expected_e, expected, rtol=1e-5)
    cfa = capture(analytic_5000, seed=2, scene=scene_5000)
    patch = ProcessingSpec(demosaic="patch")
    quad_score = score(raw, scene_5000, patch).summary
    cfa_score = score(cfa, scene_5000, patch).summary
    # the same photons and filters: the same conversion error; per-tile estimates average 4 sites of
    # each colour instead of 1-2, so less noise than the Bayer tile
    assert quad_score.delta_e_conversion == pytest.approx(cfa_score.delta_e_conversion, rel=1e-9)
    assert cfa_score.delta_e_conversion < quad_score.delta_e_mean < cfa_score.delta_e_mean
    with pytest.raises(ConfigError, match="needs a 2x2 Bayer mosaic; this capture's tile is RRGGRRGGGGBBGGBB"):
        score(raw, scene_5000, ProcessingSpec(demosaic="bilinear"))


def test_quad_bayer_files(tmp_path, scene_5000, analytic_5000):
    raw = capture(analytic_5000, design="quad/single", seed=2, scene=scene_5000)
    write_raw_exr(tmp_path / "raw.exr", raw)
    back = read_raw_exr(tmp_path / "raw.exr")
    assert back.layout == QUAD and back.camera == raw.camera
    np.testing.assert_array_equal(back.digital, raw.digital)
    write_dng(tmp_path / "raw.dng", raw, ChartReference.of(scene_5000))
    import tifffile

    with tifffile.TiffFile(tmp_path / "raw.dng") as t:
        tags = t.pages[0].tags
        assert tags[33421].value == (4, 4) and list(tags[33422].value) == [0, 0, 1, 1] * 2 + [1, 1, 2, 2] * 2
        np.testing.assert_array_equal(t.pages[0].asarray(), raw.digital.astype(np.uint16))


def test_quad_bayer_on_the_command_line(tmp_path, scene_5000, analytic_5000):
    write_radiance_exr(tmp_path / "radiance.exr", analytic_5000)
    runner = CliRunner()
    r = runner.invoke(main, ["capture", str(tmp_path / "radiance.exr"), "-o", str(tmp_path / "q"), "--arch", "quad",
                             "--quiet"])
    assert r.exit_code == 0, r.output
    assert read_raw_exr(tmp_path / "q" / "raw.exr").layout == QUAD and (tmp_path / "q" / "raw.dng").exists()
    r = runner.invoke(main, ["score", str(tmp_path / "q" / "raw.exr"), "-o", str(tmp_path / "s"), "--demosaic", "patch",
                             "--quiet"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "s" / "report.json").exists()
    ARCHITECTURES.unregister("quad")
    r = runner.invoke(main, ["capture", str(tmp_path / "radiance.exr"), "-o", str(tmp_path / "x"), "--arch", "quad"])
    assert r.exit_code == 2 and "--arch = 'quad': must be one of 'cfa', 'prism', 'fsc'" in r.output
