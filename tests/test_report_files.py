"""Scoring outputs as people look at them: rendered.png on an sRGB screen, rendered.exr's primaries
in an EXR viewer, the ΔE map's layout and the SVG's text."""
import numpy as np
import pytest

from spectracam import ChartReference, capture, score
from spectracam.camera import CameraSpec, CaptureSpec
from spectracam.processing.color import ProcessingSpec, display_rgb_to_xyz
from spectracam.architecture.filters import FilterSpec
from spectracam.io.report import (REC709_CHROMATICITIES, delta_e_figure, display_chromaticities, srgb_preview,
                                  write_score_outputs)
from spectracam.core.cielab import xyz_to_lab
from spectracam.sensor import SensorSpec

colour = pytest.importorskip("colour")
SRGB = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ)


@pytest.fixture(scope="module")
def luther(scene_5000, analytic_5000):
    """A noise-free camera whose channels are the CIE 1931 CMFs: its rendering is the scene's colour."""
    cam = CameraSpec(filters=FilterSpec(kind="xyz"), capture=CaptureSpec("prism", "optimal"),
                     sensor=SensorSpec().off("shot_noise", "dark_current", "read_noise", "fpn", "quantization"))
    return capture(analytic_5000, camera=cam, scene=scene_5000)


def png_lab(path, reference):
    """CIELAB (against D65) of each patch's mean, the PNG decoded as sRGB."""
    import matplotlib.image as mpimg

    rgb = colour.cctf_decoding(mpimg.imread(str(path))[..., :3].astype(np.float64), "sRGB")
    xyz = np.stack([rgb[r, c].reshape(-1, 3).mean(axis=0) for r, c in reference.boxes]) @ SRGB.T
    return xyz_to_lab(xyz, SRGB.sum(axis=1))


@pytest.mark.parametrize("display", ["crt", "srgb"])
def test_rendered_png_neutrals_look_neutral_on_an_srgb_screen(tmp_path, display, luther, scene_5000):
    # measured: greys 19-23 |a*| ≤ 0.8, |b*| ≤ 0.63 (8-bit PNG; the chart's own greys reach 0.65);
    # the white patch keeps its slight yellow (b* 2.5, scene 2.6)
    ref = ChartReference.of(scene_5000)
    write_score_outputs(tmp_path, score(luther, scene_5000, ProcessingSpec(display=display)))
    lab = png_lab(tmp_path / "rendered.png", ref)
    scene = xyz_to_lab(ref.patch_xyz, ref.white_xyz)
    assert np.all(np.abs(lab[19:24, 1:]) < 1.0), lab[19:24]
    np.testing.assert_allclose(lab[18:24], scene[18:24], atol=1.0)


def test_unadapted_crt_preview_stays_bluish(luther, scene_5000):
    # the option keeps the display's own colours: the CRT's ~8300 K white looks blue-green on sRGB
    ref = ChartReference.of(scene_5000)
    res = score(luther, scene_5000, ProcessingSpec(display="crt"))
    rgb8 = {a: srgb_preview(res.rendered_rgb, "crt", adapt_white=a) for a in (True, False)}
    lin = colour.cctf_decoding(rgb8[False] / 255.0, "sRGB")
    xyz = np.stack([lin[r, c].reshape(-1, 3).mean(axis=0) for r, c in ref.boxes]) @ SRGB.T
    lab = xyz_to_lab(xyz, SRGB.sum(axis=1))
    assert np.all(lab[19:23, 2] < -4) and np.all(lab[19:23, 1] < -2), lab[19:23]
    # on an sRGB display both previews are the same image
    sres = score(luther, scene_5000, ProcessingSpec(display="srgb")).rendered_rgb
    np.testing.assert_array_equal(srgb_preview(sres, "srgb", True), srgb_preview(sres, "srgb", False))


@pytest.mark.parametrize("display", ["crt", "srgb"])
def test_rendered_exr_carries_the_display_chromaticities(tmp_path, display, luther, scene_5000):
    from spectracam.io.exr import read_exr

    write_score_outputs(tmp_path, score(luther, scene_5000, ProcessingSpec(display=display)))
    _, attrs = read_exr(tmp_path / "rendered.exr")
    c = np.array(attrs["chromaticities"])
    # the RGB → XYZ matrix a viewer builds from them is the display's (white Y = 1; IEC 61966-2-1
    # rounds sRGB's matrix to 4 decimals, hence 5e-5 there)
    npm = colour.normalised_primary_matrix(c[:6].reshape(3, 2), c[6:])
    np.testing.assert_allclose(npm, display_rgb_to_xyz(display), atol=5e-5 if display == "srgb" else 2e-6)
    if display == "srgb":
        np.testing.assert_allclose(c, REC709_CHROMATICITIES, atol=1e-7)
    else:  # the CRT's phosphors, not sRGB's
        assert np.abs(c - REC709_CHROMATICITIES).max() > 0.01
    oiio = pytest.importorskip("OpenImageIO")
    spec = oiio.ImageInput.open(str(tmp_path / "rendered.exr")).spec()
    attr = {a.name: a for a in spec.extra_attribs}
    assert str(attr["chromaticities"].type) == "float[8]"  # OpenImageIO's name for EXR chromaticities
    np.testing.assert_allclose(attr["chromaticities"].value, display_chromaticities(display), atol=1e-7)
    assert str(attr["spectracamSeed"].type) == "int"


def _boxes(fig):
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    image, bar = fig.axes
    return image.get_window_extent(r), bar.get_window_extent(r), image.title.get_window_extent(r)


def test_delta_e_map_layout_and_fixed_scale(tmp_path):
    from spectracam.io.plots import pyplot, save_figure

    de = np.full((120, 160), np.nan)
    de[20:40, 20:60] = np.linspace(0, 35, 800).reshape(20, 40)  # goes beyond the fixed scale
    fig = delta_e_figure(de, "cfa/single, a long title: mean ΔE*ab 7.87, SNR 27.0 dB")
    image, bar, title = _boxes(fig)
    # the colour bar is as tall as the image and stays below the title
    assert bar.height <= image.height + 1 and abs(bar.y0 - image.y0) <= 1 and bar.y1 < title.y0
    assert bar.x0 >= image.x1  # beside it, covering nothing
    cbar = fig.axes[1]
    assert cbar.get_ylim() == (0.0, 20.0) and "fixed scale 0–20" in cbar.get_ylabel()
    save_figure(fig, tmp_path / "d.png", tmp_path / "d.svg")
    svg = (tmp_path / "d.svg").read_text()
    # text as text: selectable and searchable, not glyph outlines
    assert pyplot().rcParams["svg.fonttype"] == "none"
    assert "<text" in svg and "a long title" in svg and "fixed scale 0–20" in svg
    # vmax=None: the map's own scale
    fig = delta_e_figure(de, "t", vmax=None)
    assert fig.axes[1].get_ylim()[1] == pytest.approx(np.nanpercentile(de, 99))
    assert "this map" in fig.axes[1].get_ylabel()
    pyplot().close(fig)


def test_score_outputs_of_a_real_capture(tmp_path, scene_5000, analytic_5000):
    # the files a person opens after `spectracam score` (looked at while writing these tests)
    raw = capture(analytic_5000, seed=3, scene=scene_5000)
    paths = write_score_outputs(tmp_path, score(raw, scene_5000))
    assert {p.name for p in paths} == {"rendered.exr", "rendered.png", "delta_e.png", "report.json", "report.csv"}
    import matplotlib.image as mpimg

    png = mpimg.imread(str(tmp_path / "rendered.png"))
    assert png.shape[:2] == (120, 160)
    assert mpimg.imread(str(tmp_path / "delta_e.png")).shape[1] > 600
