"""Spatial targets rendered by Mitsuba (perspective and thin-lens cameras) against their closed forms."""
import dataclasses

import numpy as np
import pytest

from spectracam.camera import CameraSpec
from spectracam.scene.illuminant import IlluminantSpec
from spectracam.optics import OpticsSpec
from spectracam.core.spectra import WavelengthGrid
from spectracam.evaluation.esfr import esfr
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.experiments.spatial.optics import MARGIN_PX, OpticsSettings, pixel_rates
from spectracam.experiments.spatial.render import render_analytic, render_mitsuba
from spectracam.experiments.spatial.targets import SiemensStar, SlantedEdge, TiltedChart

GRID = WavelengthGrid(np.arange(410.0, 700.0, 20.0))   # 20-nm bands keep the renders short
LIGHT = IlluminantSpec()


@pytest.mark.parametrize("target, size, field", [(SlantedEdge(), (48, 48), 24.0),
                                                 (SiemensStar(cycles=12, radius_px=20), (48, 48), 24.0)])
def test_flat_targets_mitsuba_matches_closed_form(target, size, field):
    g = CameraGeometry.framing(field, 12.0, 4.0, 10.0, *size)
    a = render_analytic(target, g, LIGHT, GRID, 4).pixel_average()
    m = render_mitsuba(target, g, LIGHT, GRID, 4, 4).pixel_average()
    assert abs(m.mean() / a.mean() - 1) < 2e-3
    # away from edges every pixel agrees to the Monte Carlo noise; at edges the sub-pixel positions are random
    flat = np.abs(np.gradient(a[..., 7])[0]) + np.abs(np.gradient(a[..., 7])[1]) < 1e-6 * a[..., 7].max()
    assert np.abs(m[flat] / a[flat] - 1).max() < 0.02   # 64 samples per pixel and 20-nm band
    assert np.sqrt(np.mean((m - a) ** 2)) < 0.01 * a.max()   # edge pixels: random sub-pixel positions


def test_tilted_chart_perspective_matches_pinhole_projection():
    """Mitsuba's perspective camera and the closed-form ray–plane projection agree on every patch mask."""
    g = CameraGeometry.framing(300.0, 12.0, 4.0, 10.0, 96, 64)
    chart = TiltedChart(tilt_deg=40.0)
    a = render_analytic(chart, g, LIGHT, GRID, 2).pixel_average()
    m = render_mitsuba(chart, g, LIGHT, GRID, 2, 4, thinlens=False).pixel_average()
    for mask in chart.patch_masks(g):
        pa, pm = a[mask].mean(axis=0), m[mask].mean(axis=0)
        assert np.abs(pm / pa - 1).max() < 0.01


def test_thinlens_defocus_matches_blur_disc():
    """A flat edge out of focus: Mitsuba's thin lens (aperture f/2N, focus distance) blurs it as the
    geometric blur disc (diameter (f/N)·v·|1/z − 1/s|) applied by the optics stage to the sharp closed form."""
    g0 = CameraGeometry.framing(24.0, 12.0, 2.0, 10.0, 48, 48)
    g = dataclasses.replace(g0, focus_distance_mm=0.8 * g0.object_distance_mm)
    c = float(g.blur_diameter_um(g.object_distance_mm))
    assert 20 < c < 40   # 2–4 pixels across
    # the sensor sits at the image distance of the focus plane, so the pinhole framing changes with it
    big = g.with_margin(MARGIN_PX)
    cam = CameraSpec(optics=OpticsSpec(f_number=2.0))
    m = render_mitsuba(SlantedEdge(), big, LIGHT, GRID, 2, 16, thinlens=True)
    a = render_analytic(SlantedEdge(), big, LIGHT, GRID, 2)
    off = OpticsSettings(diffraction=False)
    rm = pixel_rates(m.radiance, m.wavelengths_nm, 2, cam, GRID, g, off)
    ra = pixel_rates(a.radiance, a.wavelengths_nm, 2, cam, GRID, g, dataclasses.replace(off, defocus_um=c))
    sharp = pixel_rates(a.radiance, a.wavelengths_nm, 2, cam, GRID, g, off)
    rms = np.sqrt(np.mean((rm - ra)[4:-4, 4:-4] ** 2)) / ra.max()
    assert rms < 0.006, rms   # Monte Carlo noise of the aperture sampling (0.3 % at 16 spp)
    mtf_m, mtf_a = (esfr(r[4:-4, 4:-4, 1], correct_binning=True).mtf50_cy_per_px for r in (rm, ra))
    assert mtf_m == pytest.approx(mtf_a, rel=0.02)
    assert np.abs(rm - sharp)[4:-4, 4:-4].max() / ra.max() > 0.1   # the defocus is there


@pytest.mark.parametrize("f_cy_per_px", [4 / 32, 10 / 32, 15 / 32, 17 / 32, 26 / 32, 33 / 32])
@pytest.mark.parametrize("axis", [0, 1])
def test_band_limited_reference_keeps_below_nyquist_and_removes_above(f_cy_per_px, axis):
    """A cosine box-averaged over 4×4 sub-pixels: the ideal low-pass returns the cosine itself at the pixel
    centres below 0.5 cy/px (the sub-pixel box divided out, the half-pixel phase right) and its mean above."""
    from spectracam.experiments.spatial.render import SubpixelCube

    ss, n = 4, 32
    edges = np.arange(n * ss + 1) / ss
    sub = (np.sin(2 * np.pi * f_cy_per_px * edges[1:]) - np.sin(2 * np.pi * f_cy_per_px * edges[:-1])) \
        / (2 * np.pi * f_cy_per_px / ss)
    line = 1.0 + 0.5 * sub
    img = np.broadcast_to(line[None, :] if axis == 1 else line[:, None], (n * ss, n * ss))
    cube = SubpixelCube(np.ascontiguousarray(np.stack([img, 2 * img], -1), np.float32), np.array([500.0, 510.0]), ss,
                        None)
    out = cube.band_limited()
    x = np.arange(n) + 0.5
    expect = 1 + 0.5 * np.cos(2 * np.pi * f_cy_per_px * x) if f_cy_per_px < 0.5 else np.ones(n)
    got = out[0, :, 0] if axis == 1 else out[:, 0, 0]
    np.testing.assert_allclose(got, expect, atol=1e-6)
    np.testing.assert_allclose(out[..., 1], 2 * out[..., 0], atol=1e-6)


@pytest.mark.parametrize("patches", [("neutral 3.5 (1.05 D)", "neutral 6.5 (.44 D)"), ("magenta", "cyan")])
def test_zone_plate_mitsuba_blend_matches_closed_form(patches):
    """Mitsuba's blendbsdf weighted by the zone plate's bitmap against the closed-form coverage: the same
    mean, and per-pixel differences at the Monte Carlo noise of 16 samples per sub-pixel (0.54 % rms at 16,
    1.08 % at 4: it halves as the samples quadruple, so it is noise, not a bias)."""
    from spectracam.experiments.spatial.targets import ZonePlate

    t = ZonePlate(patches=patches, radius_px=24)
    g = CameraGeometry.framing(24.0, 12.0, 4.0, 10.0, 48, 48)
    a = render_analytic(t, g, LIGHT, GRID, 4).pixel_average()
    m = render_mitsuba(t, g, LIGHT, GRID, 4, 16).pixel_average()
    assert abs(m.mean() / a.mean() - 1) < 1e-3
    assert np.sqrt(np.mean((m - a) ** 2)) < 0.008 * a.max()
    # the two materials are where the closed form puts them: the centre is material 1, the first dark ring material 0
    w = t.coverage(g, 1)[1]
    assert w[24, 24] > 0.95 and w[24, 28] < 0.1   # pixel centre (0.5, 4.5) px: r² = 20.5, πkr² = 0.85π
