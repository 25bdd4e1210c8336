"""Issue 34: colour breakup measured to a fraction of a pixel — the spread of the channels' edge positions —
with the blur kept apart; field-sequential frames spread by v·(t_last − t_first), one exposure by nothing."""
import math

import numpy as np
import pytest

from spectracam.core.errors import SpectracamError
from spectracam.experiments.motion import metrics as mm
from spectracam.experiments.motion.experiment import check_motion_memory, load_motion, motion_estimate, run_motion

H, W = 64, 96


def _edge_image(shifts, ramp_px, lo=(10.0, 20.0, 5.0), hi=(90.0, 60.0, 45.0)):
    """A 5° slanted edge whose channel k is a linear ramp ``ramp_px`` long centred ``shifts[k]`` px right of the
    edge (sampled at pixel centres), from ``lo[k]`` on the left to ``hi[k]`` on the right."""
    dist = mm.edge_distance((H, W), mm.edge_columns(W, H, 0.0, 5.0))
    img = np.stack([a + (b - a) * np.clip((dist - s) / ramp_px + 0.5, 0, 1)
                    for s, a, b in zip(shifts, lo, hi)], axis=-1)
    return dist, img


def test_the_metric_reads_known_sub_pixel_shifts_and_ramps():
    """Channels shifted by known sub-pixel amounts: the shifts read within 0.01 px, the breakup is their spread
    (max − min), and the blur each ramp's 10–90 % rise, 0.8 × its length (closed forms of a linear ramp); the
    levels differ per channel and do not matter."""
    dist, still = _edge_image((0.0, 0.0, 0.0), 1.0)
    shifts = (-0.37, 0.12, 0.81)
    _, moving = _edge_image(shifts, 5.0)
    d, ref = mm.channel_profiles(still, dist)
    _, mov = mm.channel_profiles(moving, dist)
    e = mm.edge_channels(d, mov, ref)
    np.testing.assert_allclose(e.shift_px, shifts, atol=0.01)
    assert e.separation_px == pytest.approx(0.81 + 0.37, abs=0.01)
    np.testing.assert_allclose(e.rise_px, 0.8 * 5.0, atol=0.02)
    assert e.blur_px == pytest.approx(4.0, abs=0.02)
    assert mm.breakup_width_px(d, mov, ref) == e.separation_px
    # against the scene's edge (d = 0) rather than the still capture's: the still's own offsets count
    _, offset_still = _edge_image((0.05, 0.0, -0.05), 1.0)
    _, off = mm.channel_profiles(offset_still, dist)
    assert mm.edge_channels(d, off, ref, relative=False).separation_px == pytest.approx(0.10, abs=0.01)
    # a ramp that blurs every channel alike is no breakup, however wide; the old threshold width would count it
    _, blurred = _edge_image((0.2, 0.2, 0.2), 9.0)
    e = mm.edge_channels(d, mm.channel_profiles(blurred, dist)[1], ref)
    assert e.separation_px < 0.01 and e.blur_px == pytest.approx(7.2, abs=0.05)


def test_an_edge_that_leaves_the_image_reads_none_not_a_guess():
    dist, still = _edge_image((0.0, 0.0, 0.0), 1.0)
    _, gone = _edge_image((0.0, 0.0, 80.0), 1.0)          # the blue edge moved out of the image
    d, ref = mm.channel_profiles(still, dist)
    e = mm.edge_channels(d, mm.channel_profiles(gone, dist)[1], ref)
    assert math.isnan(e.separation_px) and math.isnan(e.shift_px[2])


SPEEDS = (0.0025, 0.005, 0.02, 0.08)


@pytest.fixture(scope="module")
def noise_free_run():
    spec, scene = load_motion(("edge_size_px=[64, 48]", "samples_per_subpixel=4", "noise=false",
                               "wavelengths={start_nm = 400, stop_nm = 700, step_nm = 30}",
                               "designs=['cfa/single', 'fsc/optimal']", "rolling_shutter=[false, true]",
                               "speeds_px_per_ms=[0.0, " + ", ".join(map(str, SPEEDS)) + "]"))
    return run_motion(spec, scene, renderer="analytic", keep_images=False)


@pytest.mark.parametrize("rolling", [False, True])
def test_field_sequential_breakup_is_the_speed_times_the_frames_spread_in_time(noise_free_run, rolling):
    """fsc/optimal: the channels' edges spread by v·T, T the time between the first and the last frame's middle
    (RGB frames of 52, 28 and 48 ms here with 1 ms gaps: T = 80 ms, not the 130 ms capture), within 10 % at every
    speed — 0.0025 px/ms included (0.20 px: the 0.5 px-binned threshold width read 1–2 px there) — whichever
    shutter (a rolling shutter delays every channel of a row alike)."""
    r = noise_free_run
    timing = r["exposure_timing"]["fsc/optimal" + (" rolling" if rolling else "")]
    centres = np.array(timing["start_ms"]) + np.array(timing["duration_ms"]) / 2
    T_ms = centres.max() - centres.min()
    assert 70 < T_ms < 100
    rows = [x for x in r["rows"] if x.design == "fsc/optimal" and x.rolling_shutter == rolling]
    for row in rows:
        v = row.speed_px_per_ms
        if v == 0:
            assert row.breakup_width_px == 0 and row.channel_edge_shift_px == (0.0, 0.0, 0.0)
            continue
        assert row.breakup_width_px == pytest.approx(v * T_ms, rel=0.10), v
        # each frame's edge moved by v × its middle (R first, B last)
        np.testing.assert_allclose(row.channel_edge_shift_px, v * centres, atol=0.1 * v * T_ms)
    assert rows[-1].edge_blur_px > 2 * rows[0].edge_blur_px       # blur grows with speed, apart from breakup


@pytest.mark.parametrize("rolling", [False, True])
def test_one_exposure_does_not_break_up(noise_free_run, rolling):
    """cfa/single: one window for every colour, so the channels' edges move together: ≤ 0.2 px at every speed,
    while the threshold width reads the demosaicked blur of the fastest edge as breakup."""
    rows = [x for x in noise_free_run["rows"] if x.design == "cfa/single" and x.rolling_shutter == rolling]
    assert all(x.breakup_width_px is not None and x.breakup_width_px <= 0.2 for x in rows)
    fast = rows[-1]
    assert fast.speed_px_per_ms == 0.08 and fast.edge_blur_px > 2.0
    assert fast.breakup_threshold_width_px > 10 * fast.breakup_width_px


def test_slow_speeds_put_several_slices_in_every_window():
    """At 0.0025 px/ms the 0.25 px step is 100 ms, longer than a frame: the step is halved until the shortest
    window holds 4 slices, on the shared lattice of positions (max_step / 2^k)."""
    from spectracam.architecture.base import make_architecture
    from spectracam.experiments.motion.motion import Motion
    from spectracam.experiments.motion.render import MIN_SLICES_PER_WINDOW, slice_times
    from spectracam.experiments.motion.timing import TimingSpec, capture_timing
    from spectracam.experiments.spatial.geometry import CameraGeometry

    g = CameraGeometry.framing(32.0, 12.0, 1.4, 10.0, 64, 16)
    timing = capture_timing(make_architecture("fsc"), [0.039, 0.038, 0.051], TimingSpec(), 16)
    m = Motion(velocity_mm_per_s=(0.0025 * 1e3 * g.object_pixel_mm, 0.0))
    t, dt = slice_times(m, timing, g, 0.25)
    assert dt <= 0.038 / MIN_SLICES_PER_WINDOW
    step = np.diff(m.poses(t)[:, 0])[0] / g.object_pixel_mm
    assert math.log2(0.25 / step) == pytest.approx(round(math.log2(0.25 / step)))


def test_a_run_is_estimated_and_refused_up_front_when_it_cannot_fit(monkeypatch):
    """slices = 100000: about 8 million slice renders and a full pose cache, said before any work; under a
    memory limit one line naming the fields."""
    import spectracam.pipeline as pipeline

    spec, scene = load_motion(("slices=100000",))
    est, default = motion_estimate(spec, scene), motion_estimate(*load_motion(()))
    assert est.slice_renders == 100000 * (len(spec.speeds_px_per_ms) - 1) * 4 * 2 + 4 * 2
    assert est.bytes > default.bytes + 0.9 * 2**30 and "slice renders" in est.line()
    monkeypatch.setattr(pipeline, "memory_available", lambda: (1.2 * 2**30, "available"))
    with pytest.raises(SpectracamError, match=r"^edge_size_px = \[128, 128\].*slices = 100000.*needs about 1\.\d GiB, "
                                              r"1\.2 GiB available; .*fewer slices$"):
        check_motion_memory(spec, scene)
    assert check_motion_memory(*load_motion(())).bytes == default.bytes     # the default run fits
