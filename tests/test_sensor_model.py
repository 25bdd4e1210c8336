"""The fuller sensor (issue 10): black level and ADC range, DSNU, column FPN, the physical sensor's
identity, fixed patterns shared or not, and the QE models (silicon photodiode, data, IR cut)."""
import numpy as np
import pytest

from conftest import small_scene
from spectracam import capture
from spectracam.camera import CameraSpec, CaptureSpec
from spectracam.camera.capture import capture as capture_stage
from spectracam.core.errors import ConfigError
from spectracam.architecture.filters import FilterSpec, quantum_efficiency, responsivities
from spectracam.optics import OpticsSpec, radiance_to_photon_irradiance
from spectracam.render import RadianceCube, render
from spectracam.pipeline.scene_file import load_scene
from spectracam.sensor import SensorSpec, adc_inverse, expose, fixed_pattern, noise_stream
from spectracam.core.spectra import WavelengthGrid

GRID = WavelengthGrid(np.arange(405.0, 700.0, 10.0))


def dark_frame(sensor, t=0.028, shape=(500, 500), seed=1):
    return expose(np.zeros(shape, np.float32), t, sensor, noise_stream(seed, 2), fixed_pattern(sensor, shape, seed))


def test_black_level_keeps_dark_pixels_off_code_zero():
    dn, _ = dark_frame(SensorSpec())
    assert (dn == 0).mean() < 0.005  # EMVA 1288's limit
    assert abs(np.mean(adc_inverse(dn, SensorSpec())) - 28) < 30  # dark charge 28 e⁻, unbiased to ~0.1 DN
    paper_adc, _ = dark_frame(SensorSpec(black_level_DN=0.0))
    assert (paper_adc == 0).mean() > 0.3  # the paper's ADC clips the negative half of the noise


def test_dsnu_and_column_fpn_statistics():
    s = SensorSpec(dsnu_fraction=0.2, fpn_fraction=0.0, column_fpn_fraction=0.005)
    p = fixed_pattern(s, (400, 600), seed=3)
    assert p.dark_gain.mean() == pytest.approx(1.0, abs=2e-3) and p.dark_gain.std() == pytest.approx(0.2, rel=0.02)
    assert np.all(p.offset_e == p.offset_e[0])  # one offset per column
    assert p.offset_e[0].std() == pytest.approx(0.005 * 131072, rel=0.1)  # 600 columns: ±3 % (1σ)
    # the DSNU multiplies the dark charge: expected electrons of a dark frame vary as 0.2 × 1000 e⁻
    _, expected = expose(np.zeros((400, 600), np.float32), 1.0, s, noise_stream(0), p)
    assert expected.std() / expected.mean() == pytest.approx(0.2, rel=0.02)


def test_one_physical_sensor_many_frames():
    s = SensorSpec(pattern_seed=7)
    a, b = fixed_pattern(s, (50, 50), seed=1), fixed_pattern(s, (50, 50), seed=2)
    np.testing.assert_array_equal(a.offset_e, b.offset_e)
    da, _ = expose(np.full((50, 50), 1e6, np.float32), 0.01, s, noise_stream(1, 2), a)
    db, _ = expose(np.full((50, 50), 1e6, np.float32), 0.01, s, noise_stream(2, 2), b)
    assert not np.array_equal(da, db)  # each frame its own temporal noise
    assert not np.array_equal(fixed_pattern(SensorSpec(), (50, 50), 1).offset_e,
                              fixed_pattern(SensorSpec(), (50, 50), 2).offset_e)


@pytest.mark.parametrize("arch, choice, shared", [("fsc", "physical", True), ("prism", "physical", False),
                                                  ("fsc", "independent", False), ("prism", "shared", True)])
def test_fixed_pattern_across_channels_is_a_choice(arch, choice, shared):
    cube = RadianceCube(np.full((200, 200, len(GRID)), 1e-3, np.float32), np.asarray(GRID.centres_nm), {})
    sensor = SensorSpec(quantization=False, shot_noise=False, read_noise=False, dark_current=False)
    cam = CameraSpec(sensor=sensor, capture=CaptureSpec(arch, "optimal", fixed_pattern=choice))
    raw = capture_stage(cube, cam, 2, (slice(None), slice(None)))
    resid = adc_inverse(raw.digital, sensor) - raw.expected_e
    corr = np.corrcoef(resid[0].ravel(), resid[2].ravel())[0, 1]
    assert (corr > 0.999) if shared else (abs(corr) < 0.02)


def test_photodiode_qe_follows_the_collection_depth():
    lam = np.array([450.0, 550.0, 650.0, 700.0])
    shallow = quantum_efficiency(FilterSpec(qe="photodiode", collection_depth_um=2.0))(lam)
    deep = quantum_efficiency(FilterSpec(qe="photodiode", collection_depth_um=20.0))(lam)
    assert shallow[3] / shallow[1] < 0.5 and deep[3] / deep[1] > 0.95  # red lost below 2 µm
    assert max(shallow.max(), deep.max()) <= 0.5 + 1e-9  # scaled to qe_peak over 380-780 nm


def test_ir_cut_edge():
    q = quantum_efficiency(FilterSpec(ir_cut_nm=650.0, ir_cut_width_nm=20.0))
    np.testing.assert_allclose(q(np.array([640.0, 650.0, 660.0])), [0.45, 0.25, 0.05], rtol=1e-9)


def test_qe_and_transmittance_from_files(tmp_path):
    (tmp_path / "qe.csv").write_text("# a measured QE\nwavelength_nm,qe\n380,0.2\n550,0.6\n780,0.1\n")
    (tmp_path / "lens.toml").write_text("wavelength_nm = [380, 780]\nvalues = [0.8, 0.9]\n")
    (tmp_path / "s.toml").write_text('[image]\nwidth = 96\nheight = 72\n[filters]\nqe_file = "qe.csv"\n'
                                     '[optics]\ntransmittance_file = "lens.toml"\n')
    scene = load_scene(tmp_path / "s.toml")
    f = scene.camera.filters
    assert f.qe == "data" and f.qe_curve == (0.2, 0.6, 0.1)
    assert "qe_file" not in scene.to_dict()["filters"]  # the data are recorded, not the path
    assert quantum_efficiency(f)(np.array([465.0]))[0] == pytest.approx(0.4)
    k = radiance_to_photon_irradiance(GRID, scene.camera.optics) / radiance_to_photon_irradiance(GRID, OpticsSpec())
    np.testing.assert_allclose(k, 0.8 + 0.1 * (np.asarray(GRID.centres_nm) - 380) / 400, rtol=1e-6)
    (tmp_path / "bad.csv").write_text("wavelength,qe\n500,abc\n")
    (tmp_path / "b.toml").write_text('[filters]\nqe_file = "bad.csv"\n')
    with pytest.raises(ConfigError, match="filters.qe_file = .*bad.csv.*is not a curve"):
        load_scene(tmp_path / "b.toml")
    with pytest.raises(ConfigError, match="filters.qe_curve = .*values must lie in"):
        FilterSpec(qe="data", qe_curve_nm=(400.0, 700.0), qe_curve=(0.5, 1.5))


def test_the_default_camera_recovers_its_electrons():
    # metering ignores the black level: the white patch's mean charge still reaches white_fill of the well
    scene = small_scene()
    raw = capture(render(scene, "analytic"), design="prism/optimal", scene=scene)
    from spectracam import ChartReference

    r, c = ChartReference.of(scene).white_box
    assert scene.camera.capture.white_fill == 0.95
    np.testing.assert_allclose(raw.expected_e[:, r, c].mean(axis=(1, 2)), 0.95 * 131072.0, rtol=1e-5)
    assert responsivities(FilterSpec(), GRID).shape == (3, len(GRID))
