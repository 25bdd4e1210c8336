"""Time-resolved rendering: a uniformly moving edge gives the closed-form blur profile."""
import numpy as np
import pytest

from spectracam.architecture.base import make_architecture
from spectracam.experiments.motion.motion import Motion
from spectracam.experiments.motion.render import MovingScene, channel_rates, integrate, posed_edge, slice_times
from spectracam.experiments.motion.timing import TimingSpec, capture_timing
from spectracam.pipeline.scene_file import Scene
from spectracam.experiments.spatial import optics as sopt
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.experiments.spatial.render import render_analytic
from spectracam.experiments.spatial.targets import SlantedEdge

SCENE = Scene.from_dict({"wavelengths": {"start_nm": 400, "stop_nm": 700, "step_nm": 20}})
MARGIN = 8


def _G(z):  # antiderivative of clip(z, 0, 1)
    z = np.asarray(z, float)
    return np.where(z <= 0, 0.0, np.where(z <= 1, 0.5 * z * z, z - 0.5))


def closed_form_profile(width_px, x0_px, speed_px_per_ms, exposure_ms):
    """Bright fraction of each pixel column, time-averaged over an edge moving from x0 − vT/2 to
    x0 + vT/2: a ramp of width v·T convolved with the pixel (exact)."""
    u = np.arange(width_px) + 0.5 - width_px / 2
    e0 = x0_px - speed_px_per_ms * exposure_ms / 2
    e1 = x0_px + speed_px_per_ms * exposure_ms / 2
    return (_G(u + 0.5 - e0) - _G(u + 0.5 - e1)) / (e1 - e0)


def _moving_profile(renderer, speed, exposure_ms=28.0, samples=64, width=48, height=12):
    g = CameraGeometry.framing(width * 0.5, 12.0, 1.4, 10.0, width, height).with_margin(MARGIN)
    ms = MovingScene(SlantedEdge(angle_deg=0.0, x0_px=0.3), g, SCENE.illuminant, SCENE.grid, 4, renderer)
    motion = Motion(velocity_mm_per_s=(speed * 1e3 * g.object_pixel_mm, 0.0))
    timing = capture_timing(make_architecture("cfa"), [exposure_ms * 1e-3] * 3, TimingSpec(), g.height_px, -MARGIN)
    integ = integrate(ms, motion, timing, max_step_px=0.1, samples_per_subpixel=samples)
    acc = integ.groups[0][1]
    ss = 4
    px = acc.reshape(acc.shape[0], acc.shape[1] // ss, ss, acc.shape[2] // ss, ss).mean(axis=(2, 4))
    return px[1, MARGIN:-MARGIN].mean(axis=0), g, integ


@pytest.mark.parametrize("speed", [0.2, 0.5])
def test_moving_edge_is_the_closed_form_ramp_analytic(speed):
    prof, g, integ = _moving_profile("analytic", speed)
    cf = closed_form_profile(g.width_px, 0.3, speed, 28.0)
    assert np.abs(prof - cf).max() < 0.01          # within 1 % of the step (measured: < 1e-6)
    assert integ.info["slices"] >= speed * 28.0 / 0.1


def test_moving_edge_is_the_closed_form_ramp_mitsuba():
    prof, g, integ = _moving_profile("mitsuba", 0.5, samples=64)
    cf = closed_form_profile(g.width_px, 0.3, 0.5, 28.0)
    assert np.abs(prof - cf).max() < 0.01          # measured: 6e-4
    # the ramp is v·T wide: 14 px between 1 % and 99 % (less the pixel)
    assert np.count_nonzero((cf > 0.01) & (cf < 0.99)) >= 13


def test_static_capture_equals_the_spatial_optics():
    W, H = 48, 32
    g = CameraGeometry.framing(W * 0.5, 12.0, 1.4, 10.0, W, H)
    big = g.with_margin(MARGIN)
    edge = SlantedEdge()
    cube = render_analytic(edge, big, SCENE.illuminant, SCENE.grid, 4)
    ref = sopt.pixel_rates(cube.radiance, cube.wavelengths_nm, 4, SCENE.camera, SCENE.grid, g)
    ms = MovingScene(edge, big, SCENE.illuminant, SCENE.grid, 4, "analytic")
    timing = capture_timing(make_architecture("fsc"), [0.02, 0.01, 0.03], TimingSpec(), big.height_px, -MARGIN)
    rates = channel_rates(ms, integrate(ms, Motion(), timing), SCENE.camera, sopt.OpticsSettings(), MARGIN)
    assert np.abs(rates - ref).max() <= 1e-5 * ref.max()


def test_slices_keep_the_step_and_share_positions():
    g = CameraGeometry.framing(32.0, 12.0, 1.4, 10.0, 64, 16)
    timing = capture_timing(make_architecture("fsc"), [0.03, 0.03, 0.06], TimingSpec(), 16)
    for v in (0.05, 0.2):
        m = Motion(velocity_mm_per_s=(v * 1e3 * g.object_pixel_mm, 0.0))
        t, dt = slice_times(m, timing, g, 0.25)
        step_px = np.diff(m.poses(t)[:, 0]) / g.object_pixel_mm
        assert np.allclose(step_px, 0.25)                         # at most a quarter pixel between slices
        pos = m.poses(t)[:, 0] / g.object_pixel_mm / 0.25
        assert np.allclose(pos, np.round(pos))                     # on one grid for every speed: renders shared
    t, _ = slice_times(m, timing, g, 0.25, slices=16)
    assert t.size == 16


def test_posed_edge_moves_and_turns():
    g = CameraGeometry.framing(32.0, 12.0, 1.4, 10.0, 64, 16)
    e = SlantedEdge(angle_deg=5.0, x0_px=0.3)
    moved = posed_edge(e, g, (2.0 * g.object_pixel_mm, 0.0, 0.0))
    assert moved.x0_px == pytest.approx(2.3) and moved.angle_deg == 5.0
    turned = posed_edge(e, g, (0.0, 0.0, 3.0))
    assert turned.angle_deg == 8.0


def test_shake_has_the_stated_rms():
    m = Motion(shake_rms_px=1.5, seed=3)
    t = -0.05 + 1e-3 * np.arange(101)           # the walk's own steps (1 ms)
    p = m.poses(t, (-0.05, 0.05), object_pixel_mm=0.5)[:, :2] / 0.5
    rms = np.sqrt(((p - p.mean(axis=0)) ** 2).sum(axis=1).mean())
    assert rms == pytest.approx(1.5, rel=0.02)
    assert np.array_equal(p, Motion(shake_rms_px=1.5, seed=3).poses(t, (-0.05, 0.05), 0.5)[:, :2] / 0.5)


@pytest.mark.parametrize("vx", [0.4, -0.4])
def test_a_moving_edge_moves_the_way_it_is_told(vx):
    """Field-sequential capture (R, then G, then B) of an edge moving at vx px/ms: each channel sees the
    edge where it is at the middle of that channel's window, x0 + vx·t_k (x right, t = 0 the middle of
    the capture) — the sign of the motion and of the time axis both show here, not in a time average."""
    width, height = 48, 8
    g = CameraGeometry.framing(width * 0.5, 12.0, 1.4, 10.0, width, height).with_margin(MARGIN)
    ms = MovingScene(SlantedEdge(angle_deg=0.0, x0_px=0.3), g, SCENE.illuminant, SCENE.grid, 4, "analytic")
    motion = Motion(velocity_mm_per_s=(vx * 1e3 * g.object_pixel_mm, 0.0))
    timing = capture_timing(make_architecture("fsc"), [0.004] * 3, TimingSpec(), g.height_px, -MARGIN)
    integ = integrate(ms, motion, timing, max_step_px=0.05)
    t0, t1 = timing.span_s
    for chans, acc in integ.groups:
        k = chans[0]
        px = acc.reshape(acc.shape[0], acc.shape[1] // 4, 4, acc.shape[2] // 4, 4).mean(axis=(2, 4))
        bright = px[1, MARGIN:-MARGIN, MARGIN:-MARGIN].mean(axis=0)  # the bright material, columns left → right
        edge = width / 2 - bright.sum()                             # where a sharp edge with this much dark lies
        middle_ms = 1e3 * (timing.start_s[k] + timing.duration_s[k] / 2 + timing.row_delay_s[MARGIN + height // 2]
                           - (t0 + t1) / 2)
        assert edge == pytest.approx(0.3 + vx * middle_ms, abs=0.02), (k, middle_ms)


def test_a_rolling_shutter_shears_a_moving_edge_the_right_way():
    """A CFA with a rolling shutter (400 µs per line) and an edge moving right at 0.4 px/ms: row r is
    exposed r line times later, so its edge lies 0.4·0.4·r px further right — a shear whose sign and
    size both come from the row timing reaching the right rows through the integration."""
    width, height, line_us, vx = 48, 16, 400.0, 0.4
    g = CameraGeometry.framing(width * 0.5, 12.0, 1.4, 10.0, width, height).with_margin(MARGIN)
    ms = MovingScene(SlantedEdge(angle_deg=0.0, x0_px=0.3), g, SCENE.illuminant, SCENE.grid, 4, "analytic")
    motion = Motion(velocity_mm_per_s=(vx * 1e3 * g.object_pixel_mm, 0.0))
    timing = capture_timing(make_architecture("cfa"), [0.002] * 3, TimingSpec(rolling_shutter=True, line_time_us=line_us),
                            g.height_px, -MARGIN)
    integ = integrate(ms, motion, timing, max_step_px=0.05)
    (chans, acc), = integ.groups
    px = acc.reshape(acc.shape[0], acc.shape[1] // 4, 4, acc.shape[2] // 4, 4).mean(axis=(2, 4))
    edge = width / 2 - px[1, MARGIN:-MARGIN, MARGIN:-MARGIN].sum(axis=1)        # per image row
    t0, t1 = timing.span_s
    middle_ms = 1e3 * (timing.start_s[0] + timing.duration_s[0] / 2 + timing.row_delay_s[MARGIN:-MARGIN] - (t0 + t1) / 2)
    assert np.abs(edge - (0.3 + vx * middle_ms)).max() < 0.02
    assert edge[-1] - edge[0] == pytest.approx(vx * line_us * 1e-3 * (height - 1), abs=0.02)
