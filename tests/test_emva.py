"""EMVA 1288 run on the simulated camera recovers the configured camera (issue 10)."""
import json
import math

import numpy as np

import pytest
from click.testing import CliRunner

from spectracam.camera import CameraSpec
from spectracam.cli import main
from spectracam.experiments.emva.experiment import KEYS, EmvaSetup, run_emva
from spectracam.sensor import SensorSpec


def quantiser_error_covariance(var_dn2):
    """Covariance of a floor quantiser's errors on two samples of one pixel, each with Gaussian noise of
    variance ``var_dn2`` (DN²), the code phase uniform over the pixels: with the sawtooth error
    e(x) = −Σ sin(2πmx)/(πm), E[e₁e₂] = Σₘ exp(−4π²m²σ²)/(2π²m²) — 1/12 at σ = 0 (both samples in one
    code), 0 when σ ≫ 1 DN.  The same sum is the spatial variance the quantiser adds to pixel means."""
    m = np.arange(1, 200)[:, None]
    return (np.exp(-4 * np.pi**2 * m**2 * np.atleast_1d(var_dn2)[None, :]) / (2 * np.pi**2 * m**2)).sum(axis=0)


def quantiser_bias(result, sensor, setup=EmvaSetup()):
    """What the analysis should measure on a noise-free average, as ratios to the configured values:
    (K, DSNU).  The temporal variance of a quantised signal is σ² + 1/12 − E[e₁e₂] (not σ² + 1/12):
    at 8 bits σ is below a code at the dark end of the photon transfer, so the slope K reads low
    (−1.3 %) and every quantity in electrons (÷ K) high; DSNU gains E[e₁e₂] at the dark stack's noise."""
    K = sensor.system_gain_dn_per_e
    cu = result["curves"]
    signal = np.asarray(cu["mu_y"]) - np.asarray(cu["mu_y_dark"])
    v_dark = K**2 * (sensor.read_noise_e**2 + sensor.dark_rate_e_per_s * np.asarray(cu["exposure_times_s"]))
    v = v_dark + K * signal
    excess = (v - quantiser_error_covariance(v)) - (v_dark - quantiser_error_covariance(v_dark))
    fit = np.asarray(cu["sensitivity_fit_mask"], bool)
    r_K = np.polyfit(signal[fit], excess[fit], 1)[0] / K
    v_stack = K**2 * (sensor.read_noise_e**2 + sensor.dark_rate_e_per_s * 0.5 * setup.saturation_time_s)
    s2 = (K * result["configured"]["dsnu_e"]) ** 2
    return r_K, math.sqrt(1 + quantiser_error_covariance(v_stack)[0] / s2) / r_K


@pytest.mark.parametrize("sensor", [SensorSpec(), SensorSpec(adc_bits=12, prnu_fraction=0.01, dsnu_fraction=0.2)],
                         ids=["default 8-bit", "12-bit with PRNU and DSNU"])
@pytest.mark.parametrize("seed", [0, 3, 6])
def test_measured_recovers_configured(sensor, seed):
    """Each measured value within 1.5 % of the configured one corrected for the quantiser's bias (closed
    form above: at 8 bits K −1.3 %, DSNU +1.6 %; at 12 bits none).  Residuals over seeds 0–9: at most
    0.73 % at 8 bits, 1.14 % at 12 (a variance over 65536 pixels: ±0.6 %).  Seeds 3 and 6 read DSNU
    +2.1 % and +2.4 % against the uncorrected value."""
    setup = EmvaSetup(seed=seed)
    r = run_emva(CameraSpec(sensor=sensor), setup)
    c, m = r["configured"], r["measured"]
    r_K, r_dsnu = quantiser_bias(r, sensor, setup)
    expect = {"system_gain_DN_per_e": r_K, "dsnu_e": r_dsnu, "prnu_percent": 1.0, "dynamic_range_db": 0.0,
              "snr_max_db": 10 * math.log10(1 / r_K)}
    for k in KEYS:
        if k == "linearity_error_percent":
            assert m[k] < 0.01  # a linear sensor: LE of the noise alone
        elif c[k] == 0:  # no PRNU configured: not measurable (the spatial variance is temporal noise)
            assert m[k] is None or m[k] < 0.1
        elif k.endswith("_db"):
            assert m[k] - c[k] == pytest.approx(expect[k], abs=0.13), k  # 1.5 % in amplitude
        else:   # in electrons: ÷ K
            assert m[k] / c[k] == pytest.approx(expect.get(k, 1 / r_K), abs=0.015), k
    # the 8-bit camera's dark noise is below the quantisation: the standard's upper limit, 0.40/K
    assert r["notes"]["dark_noise_is_upper_limit"] == (sensor.adc_bits == 8)


def test_emva_command_writes_the_datasheet(tmp_path):
    r = CliRunner().invoke(main, ["emva", "-o", str(tmp_path), "--quiet", "--set", "sensor.adc_bits=10", "--view"])
    assert r.exit_code == 0, r.output
    page = (tmp_path / "index.html").read_text()  # --view: the datasheet as HTML, the plots embedded
    assert "spectracam emva" in page and "system gain K" in page and page.count("data:image/png;base64,") >= 3
    data = json.loads((tmp_path / "emva.json").read_text())
    assert set(data["configured"]) == set(data["measured"]) == set(KEYS)
    assert data["camera"]["sensor"]["adc_bits"] == 10 and "--set sensor.adc_bits=10" in data["command"]
    for f in ("datasheet.md", "photon_transfer.png", "snr.svg", "linearity.png"):
        assert (tmp_path / f).exists()
    assert "| system gain K | DN/e⁻ |" in (tmp_path / "datasheet.md").read_text()


@pytest.mark.parametrize("bits, black", [(8, 10.0), (12, 64.0), (10, 0.0)])
def test_configured_top_code_threshold_is_the_sensors_own_quantiser(bits, black):
    """The standard's model rounds (y = round(K·v + black)); the simulated ADC floors.  The configured
    values pass the black level less half a code, so that the charge at which the top code is first
    reached — which sets μ_e.sat — is the ADC's own, to a small fraction of an electron (a slip of
    the half code moves it by 0.5/K)."""
    import numpy as np

    from spectracam.experiments.emva.experiment import EmvaSetup, configured
    from spectracam.sensor import adc

    s = SensorSpec(adc_bits=bits, black_level_DN=black, q_max_e=10 * 2**bits)
    conf = configured(CameraSpec(sensor=s), EmvaSetup(), 1e6, 0.5)
    clip_e = conf["details"]["adc_clip_e"]
    K = s.system_gain_dn_per_e
    eps = 0.01 / K
    codes = adc(np.array([clip_e - eps, clip_e + eps], np.float32), s.replace(clipping=False))
    assert codes.tolist() == [2**bits - 2, 2**bits - 1]


def test_plots_mark_the_steps_the_analysis_left_out_of_its_fits():
    """Issue 23: each EMVA plot draws the steps its fit used, the steps below saturation outside its fit
    range and the steps beyond saturation as three kinds of marker, the two excluded kinds with a legend
    entry that cites the clause.  The markers' data, read back from the matplotlib figures, must be
    exactly the steps of the analysis's own masks (12-bit camera, 64 × 64 px: both kinds present)."""
    from spectracam.evaluation.emva1288 import analyse
    from spectracam.experiments.emva.experiment import figures, simulate_series

    camera = CameraSpec(sensor=SensorSpec(adc_bits=12, prnu_fraction=0.01, dsnu_fraction=0.2))
    setup = EmvaSetup(width=64, height=64)
    c = analyse(simulate_series(camera, setup)[0])["curves"]
    beyond = c["beyond_saturation_mask"]
    signal = c["mu_y"] - c["mu_y_dark"]
    plotted = {"photon_transfer": (signal, c["sensitivity_fit_mask"], "§6.6: above 70 % of saturation"),
               "snr": (c["mu_p"], c["sensitivity_fit_mask"], "§6.6: above 70 % of saturation"),
               "linearity": (c["mu_p"], c["linearity_fit_mask"], "§6.9: outside 5–95 % of saturation")}
    figs = figures(run_emva(camera, setup))
    assert set(figs) == set(plotted)
    for name, fig in figs.items():
        x, fit, clause = plotted[name]
        assert np.unique(x).size == x.size  # a marker's x names its step
        roles = {"fit": fit, "excluded": ~fit & ~beyond, "beyond_saturation": beyond}
        assert roles["excluded"].any() and beyond.any() and not (fit & beyond).any()
        for ax in fig.axes:
            drawn = {}
            for line in ax.lines:
                if line.get_gid() is None:
                    continue
                role = line.get_gid().removesuffix("_off_scale")
                steps = [int(np.flatnonzero(x == v)[0]) for v in np.asarray(line.get_xdata(), float)]
                assert len(steps) == len(line.get_xdata())
                drawn.setdefault(role, set()).update(steps)
            assert set(drawn) <= set(roles), (name, set(drawn))
            # every excluded step is drawn as excluded, and no other step is
            for role in ("excluded", "beyond_saturation"):
                assert drawn.get(role, set()) == set(np.flatnonzero(roles[role]).tolist()), (name, role)
            # the fit markers are fit steps (the SNR plot's log axes leave out the dark-most one)
            assert drawn["fit"] <= set(np.flatnonzero(fit).tolist())
            assert len(drawn["fit"]) >= fit.sum() - (name == "snr"), name
        legends = fig.legends + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
        labels = [t.get_text() for legend in legends for t in legend.get_texts()]
        assert f"excluded from the fit (EMVA 1288 {clause})" in labels, (name, labels)
        assert "excluded from the fit (EMVA 1288 §6.5: beyond saturation)" in labels, (name, labels)
        plt_close(fig)


def plt_close(fig):
    from spectracam.io.plots import pyplot

    pyplot().close(fig)


def test_a_noise_free_sensor_writes_its_datasheet(tmp_path):
    """Without read noise and fixed pattern the dark steps have no temporal noise, hence no SNR (NaN):
    emva.json writes it as null instead of refusing to write (it did: 'Out of range float values are
    not JSON compliant')."""
    from spectracam.experiments.emva.experiment import write_emva_outputs

    sensor = SensorSpec(read_noise=False, fpn=False)
    result = run_emva(CameraSpec(sensor=sensor), EmvaSetup(width=64, height=64))
    assert not np.all(np.isfinite(result["curves"]["snr"]))
    write_emva_outputs(tmp_path, result, "test")
    data = json.loads((tmp_path / "emva.json").read_text())
    assert None in data["curves"]["snr"] and (tmp_path / "linearity.png").exists()
