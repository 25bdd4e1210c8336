"""Exposure windows per architecture and the rolling shutter's row offsets."""
import numpy as np
import pytest

from spectracam.architecture.base import make_architecture
from spectracam.core.errors import ConfigError
from spectracam.sensor.exposure import exposure_times_s
from spectracam.experiments.motion.timing import TimingSpec, capture_timing
from spectracam.sensor import SensorSpec

T = np.array([0.02, 0.01, 0.04])


def test_cfa_and_prism_are_simultaneous():
    cfa = capture_timing(make_architecture("cfa"), [0.028] * 3, TimingSpec(), 4)
    assert np.allclose(cfa.start_s, -0.014) and cfa.groups() == [(0, 1, 2)]
    assert cfa.capture_time_s == pytest.approx(0.028)
    prism = capture_timing(make_architecture("prism"), T, TimingSpec(), 4)
    assert np.allclose(prism.start_s, prism.start_s[0])                 # open together
    assert prism.capture_time_s == pytest.approx(0.04)
    centre = capture_timing(make_architecture("prism"), T, TimingSpec(prism_alignment="centre"), 4)
    assert np.allclose(centre.start_s + T / 2, 0.0)                     # share their middle


def test_fsc_is_consecutive_in_order_with_gaps():
    t = capture_timing(make_architecture("fsc"), T, TimingSpec(readout_gap_ms=2.0), 1)
    end = t.start_s + t.duration_s
    assert t.start_s[1] == pytest.approx(end[0] + 0.002)                # G after R
    assert t.start_s[2] == pytest.approx(end[1] + 0.002)                # B after G
    assert t.capture_time_s == pytest.approx(T.sum() + 0.004)
    assert t.span_s[0] == pytest.approx(-t.span_s[1])                   # centred on t = 0
    g = capture_timing(make_architecture("fsc"), T, TimingSpec(order="BGR", readout_gap_ms=0.0), 1)
    assert g.start_s[2] < g.start_s[1] < g.start_s[0]
    assert g.start_s[1] == pytest.approx(g.start_s[2] + T[2])
    assert len(g.groups()) == 3


def test_balanced_fsc_takes_the_cfa_time():
    s = SensorSpec(q_max_e=100.0, dark_current=False)
    white = [100.0, 200.0, 50.0]
    fsc = make_architecture("fsc")
    bal = capture_timing(fsc, exposure_times_s("balanced", white, s, fsc), TimingSpec(readout_gap_ms=0.0), 1)
    single = exposure_times_s("single", white, s, make_architecture("cfa"))
    assert bal.capture_time_s == pytest.approx(single[0])


@pytest.mark.parametrize("arch", ["cfa", "prism", "fsc"])
def test_rolling_shutter_offsets_each_row_by_a_line_time(arch):
    rows = 10
    t = capture_timing(make_architecture(arch), T, TimingSpec(rolling_shutter=True, line_time_us=50.0), rows, -2)
    assert np.allclose(np.diff(t.row_delay_s), 50e-6)  # later rows later: the shift's sign
    # the first row passed is image row −2 (a margin above the image): image row 0 is read at delay 0,
    # the margin rows before it (a slip in the first row shifts every window by whole line times)
    assert t.row_delay_s[2] == 0.0 and t.row_delay_s[0] == pytest.approx(-100e-6)
    lo, hi = np.array([-1.0]), np.array([1.0])
    for k in range(3):   # every row's window has the channel's full length
        assert np.allclose(t.overlap_s(k, lo, hi)[:, 0], T[k])
    # an interval at row 0's opening: later rows see less of it, by one line time each
    k = 0
    a = t.start_s[k] + t.row_delay_s[0]
    ov = t.overlap_s(k, np.array([a]), np.array([a + 0.001]))[:, 0]
    assert np.allclose(ov, np.clip(0.001 - 50e-6 * np.arange(rows), 0, None))
    glob = capture_timing(make_architecture(arch), T, TimingSpec(), rows)
    assert np.all(glob.row_delay_s == 0)
    assert t.span_s[1] - t.span_s[0] == pytest.approx(glob.span_s[1] - glob.span_s[0] + 50e-6 * (rows - 1))


def test_bad_timing_is_one_clear_error():
    with pytest.raises(ConfigError, match="timing.order"):
        TimingSpec(order="RGX")
    with pytest.raises(ConfigError, match="timing.prism_alignment"):
        TimingSpec(prism_alignment="end")
