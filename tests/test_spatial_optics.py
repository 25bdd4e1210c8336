"""Spatial optics and geometry against closed forms: the MTF of a simulated slanted edge through
diffraction and the pixel aperture, the camera geometry, sub-pixel shifts, and the analytic targets."""
import doctest
import importlib

import numpy as np
import pytest

from spectracam.camera import CameraSpec, band_weights
from spectracam.scene.illuminant import IlluminantSpec
from spectracam.optics import OpticsSpec
from spectracam.sensor import SensorSpec
from spectracam.core.spectra import WavelengthGrid
from spectracam.evaluation.esfr import esfr
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.experiments.spatial.optics import (MARGIN_PX, OpticsSettings, channel_mtf_closed_form, diffraction_otf,
                                       margin_px, pixel_rates)
from spectracam.experiments.spatial.render import material_radiance, render_analytic
from spectracam.experiments.spatial.targets import SiemensStar, SlantedEdge, TiltedChart

GRID = WavelengthGrid(np.arange(405.0, 700.0, 10.0))
LIGHT = IlluminantSpec()


def edge_rates(pitch, N, w=96, h=128, fill_factor=1.0, settings=OpticsSettings(), ss=4, margin=None):
    g = CameraGeometry.framing(0.5 * w, 12.0, N, pitch, w, h)
    target = SlantedEdge()
    margin = margin_px(pitch, N, GRID.edges_nm[-1]) if margin is None else margin
    cube = render_analytic(target, g.with_margin(margin), LIGHT, GRID, ss)
    cam = CameraSpec(optics=OpticsSpec(f_number=N), sensor=SensorSpec(pixel_pitch_um=pitch, fill_factor=fill_factor))
    L = material_radiance(target, LIGHT, GRID)
    return pixel_rates(cube.radiance, cube.wavelengths_nm, ss, cam, GRID, g, settings, margin), cam, L[1] - L[0]


def test_margin_keeps_the_far_side_from_wrapping_round():
    """f/32 with a 2 µm pixel: the Airy line spread reaches 70 px.  The dark column at the image's
    border, next to the bright far side through the periodic wrap, must read what a much wider margin
    gives within the stated tolerance (measured 0.25 % of the step; an 8-px margin: 5.0 %)."""
    kw = dict(pitch=2.0, N=32.0, w=48, h=24, ss=2)
    wide, _, _ = edge_rates(**kw, margin=4 * margin_px(2.0, 32.0, GRID.edges_nm[-1]))
    ours, _, _ = edge_rates(**kw)
    step = wide[:, -1, 1].mean() - wide[:, 0, 1].mean()
    err = np.abs(ours[:, :2, 1] - wide[:, :2, 1]).max() / step
    assert err < 0.01, err
    narrow, _, _ = edge_rates(**kw, margin=MARGIN_PX)
    assert np.abs(narrow[:, :2, 1] - wide[:, :2, 1]).max() / step > 0.03


@pytest.mark.parametrize("pitch, N, w, fill, olpf", [(10.0, 1.4, 96, 1.0, 0.0), (10.0, 8.0, 96, 1.0, 0.0),
                                                     (2.0, 1.4, 96, 1.0, 0.0), (2.0, 8.0, 160, 1.0, 0.0),
                                                     (5.0, 4.0, 96, 0.5, 0.0), (10.0, 1.4, 96, 1.0, 1.0),
                                                     (5.0, 4.0, 96, 0.5, 0.75)])
def test_edge_mtf_matches_diffraction_times_aperture(pitch, N, w, fill, olpf):
    """The e-SFR of each channel of a simulated 5° edge matches the circular-aperture OTF weighted over
    the channel's signal spectrum × the pixel aperture's sinc (× the optical low-pass filter's
    cos·cos) within 2 % (of the zero-frequency response) up to Nyquist. (2 µm at f/8 needs a wider
    region: the e-SFR's Hamming window truncates the diffraction LSF's long tails, +0.02 at low
    frequency over 96 px, +0.015 over 160 px.)"""
    rates, cam, step = edge_rates(pitch, N, w=w, fill_factor=fill, settings=OpticsSettings(olpf_separation_px=olpf))
    W = band_weights(cam, GRID)
    for k in range(3):
        r = esfr(rates[:, :, k], correct_binning=True)
        f = r.frequencies_cy_per_px
        m = f <= 0.5
        cf = channel_mtf_closed_form(f, r.edge_angle_deg, pitch, N, GRID.centres_nm, W[:, k] * step, fill, olpf)
        assert np.abs(r.sfr[m] - cf[m]).max() < 0.02, (k, np.abs(r.sfr[m] - cf[m]).max())
    if olpf:   # the filter's own first zero, cos(π·f·d) = 0 at f = 1/(2d), shows in the closed form
        f0 = 1 / (2 * olpf * np.cos(np.radians(r.edge_angle_deg)))
        assert channel_mtf_closed_form([f0], r.edge_angle_deg, pitch, N, GRID.centres_nm, W[:, 1], fill,
                                       olpf)[0] == pytest.approx(0.0, abs=1e-9)


def test_olpf_is_four_spots():
    """The filter's OTF sampled on a grid is the Fourier transform of four equal spots at (±d/2, ±d/2):
    a point through it, in space, is those four spots (d = 2 px on a 32-px periodic grid)."""
    from spectracam.experiments.spatial.optics import olpf_otf

    n, d = 32, 2.0
    f = np.fft.fftfreq(n)
    psf = np.fft.ifft2(olpf_otf(f[None, :], f[:, None], d)).real
    want = np.zeros((n, n))
    for y in (-1, 1):
        for x in (-1, 1):
            want[y % n, x % n] = 0.25
    assert np.abs(psf - want).max() < 1e-12


def test_diffraction_otf_closed_form_values():
    # half the cut-off: (2/π)(acos ½ − ½·√¾) = 0.391002
    assert diffraction_otf(0.5 / (0.5 * 4.0), 500.0, 4.0) == pytest.approx(0.391002, abs=1e-6)
    assert diffraction_otf(10.0, 500.0, 4.0) == 0.0


def test_misregistration_is_a_subpixel_shift():
    """Sampling the red plane 0.5 px further right equals imaging the edge moved 0.5 px left."""
    g = CameraGeometry.framing(48.0, 12.0, 4.0, 10.0, 96, 64)
    cam = CameraSpec(optics=OpticsSpec(f_number=4.0))
    out = []
    for x0, shift in ((0.3, 0.5), (-0.2, 0.0)):
        cube = render_analytic(SlantedEdge(x0_px=x0), g.with_margin(MARGIN_PX), LIGHT, GRID, 4)
        out.append(pixel_rates(cube.radiance, cube.wavelengths_nm, 4, cam, GRID, g,
                               OpticsSettings(shifts_px=((shift, 0.0), (0.0, 0.0), (0.0, 0.0)))))
    shifted, moved = out
    assert np.abs(shifted[:, :, 0] - moved[:, :, 0]).max() < 1e-4 * moved[:, :, 0].max()
    assert np.abs(shifted[:, :, 1] - moved[:, :, 1]).max() > 0.05 * moved[:, :, 1].max()  # green not shifted


def test_full_aperture_without_diffraction_is_the_pixel_area_average():
    """No diffraction and a full fill factor: each pixel is exactly the mean of its sub-pixels."""
    g = CameraGeometry.framing(40.0, 12.0, 2.0, 10.0, 40, 32)
    cube = render_analytic(SiemensStar(cycles=8, radius_px=14), g.with_margin(MARGIN_PX), LIGHT, GRID, 4)
    cam = CameraSpec(optics=OpticsSpec(f_number=2.0))
    rates = pixel_rates(cube.radiance, cube.wavelengths_nm, 4, cam, GRID, g, OpticsSettings(diffraction=False))
    expect = cube.pixel_average()[MARGIN_PX:-MARGIN_PX, MARGIN_PX:-MARGIN_PX] @ band_weights(cam, GRID)
    assert np.abs(rates - expect).max() < 1e-4 * expect.max()


def test_geometry_thin_lens():
    g = CameraGeometry(object_distance_mm=1000.0, focal_length_mm=50.0, f_number=2.0, pixel_pitch_um=10.0,
                       width_px=400, height_px=300)
    assert 1 / g.image_distance_mm + 1 / 1000.0 == pytest.approx(1 / 50.0)
    assert g.object_pixel_mm * g.magnification == pytest.approx(0.01)
    assert g.aperture_radius_mm == 12.5
    assert float(g.blur_diameter_um(1000.0)) == 0.0
    f = CameraGeometry.framing(300.0, 12.0, 1.4, 10.0, 384, 256)
    assert f.field_of_view_mm[0] == pytest.approx(300.0)
    assert f.off_axis_cos4().max() <= 1.0


def test_edge_coverage_is_exact_area():
    g = CameraGeometry.framing(32.0, 12.0, 4.0, 10.0, 32, 32)
    cov = SlantedEdge(angle_deg=5.0).coverage(g, 1)
    assert np.allclose(cov.sum(axis=0), 1.0)
    # the bright area of each row = the part of the row right of the line, averaged along the row height
    k = g.object_distance_mm / g.image_distance_mm
    s = g.pixel_pitch_mm * k
    t = np.tan(np.radians(5.0))
    u, w = g.pixel_centres_mm()
    x0 = 0.3 * g.object_pixel_mm
    for row in (3, 16, 28):
        xe = x0 - t * w[row] * k    # edge position at the row's centre (the mean over the row, the line is straight)
        total = cov[1, row].sum() * s
        assert total == pytest.approx(u[-1] * k + s / 2 - xe, rel=1e-9)


def test_tilted_chart_masks_and_materials():
    g = CameraGeometry.framing(300.0, 12.0, 1.4, 10.0, 192, 128)
    chart = TiltedChart(tilt_deg=40.0)
    masks = chart.patch_masks(g)
    assert masks.shape == (24, 128, 192) and all(m.any() for m in masks)
    assert not np.any(masks.sum(axis=0) > 1)
    # perspective: the far (right) patches are smaller than the near (left) ones
    assert masks[0].sum() > masks[5].sum()
    lo, hi = chart.depth_range_mm(g)
    assert hi - lo == pytest.approx(chart.chart.board_size_mm[0] * np.sin(np.radians(40.0)))


def test_doctests():
    for name in ("geometry", "optics"):
        mod = importlib.import_module(f"spectracam.experiments.spatial.{name}")
        assert doctest.testmod(mod).failed == 0



@pytest.mark.parametrize("ss, fill_factor, inner", [(4, 0.25, slice(1, 3)), (6, 1 / 9, slice(2, 4)),
                                                    (6, 4 / 9, slice(1, 5))])
def test_the_pixel_aperture_is_a_centred_square_of_side_pitch_times_root_fill_factor(ss, fill_factor, inner):
    """No diffraction: with ss × ss sub-pixels per pixel, a fill factor whose aperture side √(ff)·pitch
    spans whole sub-pixels about the centre gives exactly the mean of those sub-pixels (a side of
    ff·pitch — a slip — does not)."""
    g = CameraGeometry.framing(40.0, 12.0, 2.0, 10.0, 40, 32)
    cube = render_analytic(SiemensStar(cycles=8, radius_px=14), g.with_margin(MARGIN_PX), LIGHT, GRID, ss)
    cam = CameraSpec(optics=OpticsSpec(f_number=2.0), sensor=SensorSpec(pixel_pitch_um=10.0, fill_factor=fill_factor))
    rates = pixel_rates(cube.radiance, cube.wavelengths_nm, ss, cam, GRID, g, OpticsSettings(diffraction=False))
    H, W, B = cube.radiance.shape
    aperture = cube.radiance.reshape(H // ss, ss, W // ss, ss, B)[:, inner, :, inner].mean(axis=(1, 3))
    expect = aperture[MARGIN_PX:-MARGIN_PX, MARGIN_PX:-MARGIN_PX] @ band_weights(cam, GRID)
    assert np.abs(rates - expect).max() < 1e-5 * expect.max()          # measured: 1.6e-7
