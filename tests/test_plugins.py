"""A new architecture defined in this file alone — a stripe colour filter array (columns R, G, B in a
1×3 tile) — goes through capture, scoring, the raw EXR, the DNG and ``--arch`` on the command line
without any edit to spectracam: everything downstream dispatches on its layout."""
import numpy as np
import pytest
from click.testing import CliRunner

from spectracam import ChartReference, capture, score
from spectracam.architecture.base import ARCHITECTURES, Architecture, MosaicLayout
from spectracam.cli import main
from spectracam.processing.color import ProcessingSpec
from spectracam.io.dng import write_dng
from spectracam.io.exr import read_raw_exr, write_radiance_exr, write_raw_exr

QUAD = MosaicLayout(((0, 1, 2),))


class Stripes(Architecture):
    name = "quad"
    independent_exposures = False
    layout = QUAD

    def capture_time_s(self, times_s):
        return float(times_s[0])

    def record(self, rates, times_s, sensor, seed):
        return self.record_mosaic(rates, times_s, sensor, seed)


@pytest.fixture(autouse=True)
def quad_registered():
    ARCHITECTURES.register("quad", Stripes)
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
    # the same photons and filters: the same conversion error; a 1x3 tile's estimate holds one site of
    # each colour, the Bayer tile's two greens: a little more noise
    assert quad_score.delta_e_conversion == pytest.approx(cfa_score.delta_e_conversion, rel=1e-9)
    assert cfa_score.delta_e_conversion < cfa_score.delta_e_mean < quad_score.delta_e_mean
    # the periodic bilinear and, through a remosaic to Bayer, Menon 2007 take any mosaic of three channels
    for method in ("bilinear", "menon2007"):
        s = score(raw, scene_5000, ProcessingSpec(demosaic=method)).summary
        assert cfa_score.delta_e_conversion < s.delta_e_mean < 2 * cfa_score.delta_e_mean


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
        # LibRaw decodes tiles two columns wide only: the DNG holds the mosaic remosaicked to RGGB, and says so
        assert tags[33421].value == (2, 2) and list(tags[33422].value) == [0, 1, 1, 2]
        assert "remosaicked to RGGB" in t.pages[0].description
        sites = QUAD.channel_index(raw.digital.shape) == MosaicLayout.bayer("RGGB").channel_index(raw.digital.shape)
        np.testing.assert_array_equal(t.pages[0].asarray()[sites], raw.digital.astype(np.uint16)[sites])


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
    assert r.exit_code == 2 and "--arch = 'quad': must be one of 'cfa', 'prism', 'fsc', 'cmy'" in r.output
