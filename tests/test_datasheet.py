"""``spectracam datasheet`` (issue 36): each figure against its definition in closed form or by a hand calculation
that shares nothing with spectracam's code but the inputs, and the command's files and refusals."""
import json
import math
import subprocess
import sys
from statistics import NormalDist

import colour
import numpy as np
import pytest

from spectracam.architecture.filters import FilterSpec, responsivities
from spectracam.camera import CameraSpec
from spectracam.core.spectra import WavelengthGrid
from spectracam.evaluation import datasheet as ds
from spectracam.experiments.datasheet.experiment import (GRID_NM, DatasheetSpec, measure_readout, photometry,
                                                         smi_figures, speeds)
from spectracam.sensor import READOUT_NAMES, SensorSpec

#: An ideal sensor: shot and read noise only (no dark current, FPN or quantiser), 12 bits, a 10000 e⁻ well.
IDEAL = SensorSpec(q_max_e=10000.0, read_noise_e=5.0, dark_current=False, fpn=False, quantization=False,
                   adc_bits=12, black_level_DN=64.0)


@pytest.fixture(scope="module")
def ideal():
    return measure_readout(IDEAL, DatasheetSpec(), eta=1.0)


def _snr_level(level, read_e):
    """μ with μ/√(μ + σ_r²) = level: μ² − L²μ − L²σ_r² = 0."""
    L2 = level * level
    return (L2 + math.sqrt(L2 * L2 + 4 * L2 * read_e**2)) / 2


def test_snr10_and_the_threshold_against_their_closed_forms(ideal):
    assert ideal["snr10_e"] == pytest.approx(_snr_level(10, 5.0), rel=0.03)   # 120.7 e⁻
    assert ideal["threshold_e"] == pytest.approx(_snr_level(1, 5.0), rel=0.05)   # 5.52 e⁻
    assert ideal["snr40_e"] == pytest.approx(_snr_level(40, 5.0), rel=0.03)


def test_saturation_and_dynamic_range_against_their_definitions(ideal):
    # 0.15 % of the pixels at the top value: μ + z·√(μ + σ_r²) = q_max (the well clips; the read noise after it
    # puts half the clipped pixels at the top code)
    z = NormalDist().inv_cdf(1 - 0.0015)
    mu = 10000.0
    for _ in range(50):
        mu = 10000.0 - z * math.sqrt(mu + 25.0)
    assert ideal["saturation_method"] == "pixel_fraction"
    assert ideal["saturation_e"] == pytest.approx(mu, rel=0.01)
    expected = ideal["saturation_e"] / _snr_level(1, 5.0)
    assert ideal["dynamic_range"] == pytest.approx(expected, rel=0.05)
    assert ideal["dynamic_range_db"] == pytest.approx(20 * math.log10(ideal["dynamic_range"]))


def test_the_closed_form_curve_is_the_linear_model(ideal):
    mu = np.asarray(ideal["curve"]["signal_e"])
    assert np.allclose(ideal["curve"]["snr_model"], mu / np.sqrt(mu + 25.0))


def test_snr_crossing_interpolates_in_log_log():
    x = np.array([1.0, 10.0, 100.0])
    assert ds.snr_crossing(x, x**0.5, 3.0) == pytest.approx(9.0)
    assert ds.snr_crossing(x, x * 0.01, 5.0) is None


def _hand_e_per_lux_s(camera, k):
    """Electrons per lux·s at the sensor plane of channel k under D65, by a 1 nm sum: A·ΣS·λ/(hc)·R / (683·ΣS·ȳ)
    (the lens's factor multiplies both and cancels)."""
    lam = np.arange(380.0, 781.0, 1.0)
    d65 = colour.SDS_ILLUMINANTS["D65"]
    S = np.interp(lam, d65.wavelengths, d65.values)
    R = responsivities(camera.filters, WavelengthGrid(lam))[k]
    ybar = np.interp(lam, colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].wavelengths,
                     colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values[:, 1])
    area = camera.sensor.pixel_pitch_um**2 * camera.sensor.fill_factor * 1e-12
    return area * np.sum(S * lam * 1e-9 / (6.62607015e-34 * 299792458.0) * R) / (683.0 * np.sum(S * ybar))


def test_iso12232_speeds_and_lux_against_a_hand_calculation(ideal):
    camera = CameraSpec(sensor=IDEAL)
    spec = DatasheetSpec()
    phot = photometry(camera, spec)
    c = {k: _hand_e_per_lux_s(camera, i) for i, k in enumerate("RGB")}
    for k in "RGB":
        assert phot["e_per_lux_s"][k] == pytest.approx(c[k], rel=0.01)
    iso = speeds(ideal, phot, spec, "G", 78.0)
    h_sat = ideal["saturation_e"] / max(c.values())                   # the first channel to clip
    assert iso["S_sat"] == pytest.approx(78.0 / h_sat, rel=0.01)
    assert iso["S_noise10"] == pytest.approx(10.0 / (_snr_level(10, 5.0) / c["G"]), rel=0.04)
    assert iso["snr10_sensor_lux"] == pytest.approx(_snr_level(10, 5.0) / c["G"] / spec.exposure_time_s, rel=0.04)
    # at the scene: an 18 % grey through f/1.4, T = 1, paraxial: E_sensor = π/(4N²)·0.18·E_scene/π
    k = 0.18 / (4 * 1.4**2)
    assert iso["snr10_scene_lux"] == pytest.approx(iso["snr10_sensor_lux"] / k, rel=0.01)


def _cmfs(lam):
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    return np.stack([np.interp(lam, cmfs.wavelengths, cmfs.values[:, k]) for k in range(3)], axis=-1)


def _d65(lam):
    d65 = colour.SDS_ILLUMINANTS["D65"]
    return np.interp(lam, d65.wavelengths, d65.values)


def _iso17321_18(lam):
    sds = list(colour.SDS_COLOURCHECKERS["ISO 17321-1"].values())[:18]
    return np.array([np.interp(lam, sd.wavelengths, sd.values) for sd in sds])


@pytest.mark.parametrize("fit", ["delta_e", "least_squares"])
def test_a_luther_camera_scores_100(fit):
    lam = GRID_NM
    A = np.array([[0.9, 0.3, 0.0], [0.1, 1.0, 0.05], [0.0, 0.1, 1.2]])
    R = (A @ _cmfs(lam).T) / lam          # photon responsivities whose energy form R·λ is a mix of x̄ȳz̄
    r = ds.sensitivity_metamerism_index(R, lam, _d65(lam), _iso17321_18(lam), _cmfs(lam), fit)
    assert r.smi == pytest.approx(100.0, abs=1e-6)


def test_the_paper_blocks_smi_against_a_hand_calculation():
    lam = GRID_NM
    R = responsivities(FilterSpec(), WavelengthGrid(lam))
    S, rho, cmf = _d65(lam), _iso17321_18(lam), _cmfs(lam)
    cam, xyz = (rho * S * lam) @ R.T, (rho * S) @ cmf
    cw, xw = R @ (S * lam), cmf.T @ S
    cam, cw, xyz, xw = cam / cw.max(), cw / cw.max(), xyz / xw[1], xw / xw[1]
    # the white-preserving least squares as one KKT system per column: [[2CᵀC, w], [wᵀ, 0]]·[m, λ] = [2Cᵀx, x_w]
    K = np.block([[2 * cam.T @ cam, cw[:, None]], [cw[None, :], np.zeros((1, 1))]])
    M = np.stack([np.linalg.solve(K, np.r_[2 * cam.T @ xyz[:, j], xw[j]])[:3] for j in range(3)], axis=1)
    white = colour.XYZ_to_xy(xw)
    de = colour.delta_E(colour.XYZ_to_Lab(cam @ M, white), colour.XYZ_to_Lab(xyz, white), method="CIE 1976")
    hand = 100 - 5.5 * de.mean()
    got = smi_figures(CameraSpec())
    assert got["smi_least_squares"] == pytest.approx(hand, abs=1e-6)
    assert got["smi"] >= got["smi_least_squares"] - 1e-9    # the ΔE-optimal matrix is at least as good
    assert 0 < got["smi"] < 100


def test_visual_noise_is_zero_without_noise_and_rises_with_it():
    white = np.array([0.95, 1.0, 1.09])
    flat = np.broadcast_to(0.2 * white, (64, 64, 3)).copy()
    assert ds.visual_noise(flat, white, 40.0)["visual_noise"] == pytest.approx(0.0, abs=1e-9)   # round-off only
    rng = np.random.default_rng(0)
    noise = rng.standard_normal((64, 64, 3))
    values = [ds.visual_noise(flat * (1 + s * noise), white, 40.0)["visual_noise"] for s in (0.005, 0.02, 0.08)]
    assert 0 < values[0] < values[1] < values[2]


def _run(*args):
    return subprocess.run([sys.executable, "-m", "spectracam", "datasheet", *args], capture_output=True, text=True)


def _working_readouts():
    """The read-outs this installation reads (all five once spectracam.sensor.readout is in place)."""
    from spectracam.experiments.datasheet.experiment import available_readouts

    return available_readouts(None)[0]


def test_the_command_writes_its_files_and_records_its_parameters(tmp_path):
    readout = [n for n in _working_readouts() if n != "single"][:1] or ["single"]
    out = tmp_path / "ds"
    r = _run("-o", str(out), "--quick", "--set", f"sensor.readout={readout[0]}", "--seed", "3")
    assert r.returncode == 0, r.stderr
    assert {p.name for p in out.iterdir()} == {"datasheet.md", "results.json", "snr.png", "snr.svg"}
    res = json.loads((out / "results.json").read_text())
    assert res["command"].endswith(f"--seed 3 --set sensor.readout={readout[0]}")
    assert res["parameters"]["scene"]["sensor"]["readout"] == readout[0]
    assert res["parameters"]["quick"] is True and res["parameters"]["seed"] == 3
    assert list(res["readouts"]) == readout
    assert res["iso12232"]["S_sat"] > 0 and "SMI" in (out / "datasheet.md").read_text()


@pytest.mark.parametrize("readout", [n for n in READOUT_NAMES if n != "single"])
def test_every_readout_is_measured_through_read_frame(readout):
    if readout not in _working_readouts():
        pytest.skip("spectracam.sensor.readout is not in this installation")
    r = measure_readout(SensorSpec(readout=readout), DatasheetSpec(quick=True), eta=0.5)
    assert r["dynamic_range_db"] is not None and r["saturation_e"] > 0 and r["threshold_e"] > 0


@pytest.mark.parametrize("args", [["--set", "sensor.readout=bogus"], ["--set", "sensor.temperature_C=400"],
                                  ["--seed", "-1"]])
def test_a_bad_value_is_one_line(tmp_path, args):
    r = _run("-o", str(tmp_path / "x"), "--quick", *args)
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and r.stderr.startswith("spectracam: error:")
    assert not (tmp_path / "x").exists()
