"""Every registered option: refused by name from Python as from a file, and each checked against an
independent value (a closed form, a published number), so a bug on an optional branch fails."""
import numpy as np
import pytest

from conftest import small_scene
from spectracam import capture, score
from spectracam.architecture.base import ARCHITECTURES, MosaicLayout
from spectracam.camera import CameraSpec, CaptureSpec
from spectracam.camera.capture import RawCapture
from spectracam.processing.color import ADAPTATIONS, DEMOSAIC_METHODS, DISPLAYS, ProcessingSpec, adaptation_matrix, \
    display_rgb_to_xyz
from spectracam.core.errors import ConfigError
from spectracam.sensor.exposure import EXPOSURE_SCHEMES
from spectracam.architecture.filters import FILTER_KINDS, QE_MODELS, FilterSpec, quantum_efficiency, responsivities
from spectracam.scene.illuminant import ILLUMINANTS, IlluminantSpec
from spectracam.core.cielab import DELTA_E_METHODS, SNR_COMBINATIONS, combine_snr_db, delta_e
from spectracam.optics import IRRADIANCE_FORMS, OpticsSpec
from spectracam.render import RENDERERS, render
from spectracam.evaluation.score import channel_stats
from spectracam.sensor import FPN_READINGS, SHOT_NOISE_MODELS, SensorSpec, fixed_pattern
from spectracam.core.spectra import WavelengthGrid

W = np.array([0.95, 1.0, 1.09])


@pytest.mark.parametrize("call, field, value", [
    (lambda: delta_e([50, 0, 0], [50, 1, 1], "cie1994"), "processing.delta_e", "cie1994"),
    (lambda: OpticsSpec(irradiance_form="parxial"), "optics.irradiance_form", "parxial"),
    (lambda: display_rgb_to_xyz("sRGB"), "processing.display", "sRGB"),
    (lambda: SensorSpec(fpn_reading="rms"), "sensor.fpn_reading", "rms"),
    (lambda: adaptation_matrix(W, W, "von_kries"), "processing.adaptation", "von_kries"),
    (lambda: FilterSpec(kind="box"), "filters.kind", "box"),
    (lambda: FilterSpec(qe="si"), "filters.qe", "si"),
    (lambda: SensorSpec(shot_noise_model="poison"), "sensor.shot_noise_model", "poison"),
    (lambda: combine_snr_db([1.0] * 3, [1.0] * 3, "rms"), "processing.snr_combination", "rms"),
    (lambda: CaptureSpec(architecture="bayer"), "capture.architecture", "bayer"),
    (lambda: CaptureSpec(exposure="auto"), "capture.exposure", "auto"),
    (lambda: ProcessingSpec(demosaic="ahd"), "processing.demosaic", "ahd"),
    (lambda: IlluminantSpec(kind="led"), "illuminant.type", "led"),
    (lambda: render(small_scene(), "pbrt"), "renderer", "pbrt"),
])
def test_unknown_names_are_refused_from_python(call, field, value):
    with pytest.raises(ConfigError, match=rf"^{field} = '{value}': must be one of '"):
        call()


@pytest.mark.parametrize("registry", [RENDERERS, FILTER_KINDS, QE_MODELS, ARCHITECTURES, EXPOSURE_SCHEMES,
                                      DEMOSAIC_METHODS, DISPLAYS, ADAPTATIONS, DELTA_E_METHODS, SNR_COMBINATIONS,
                                      IRRADIANCE_FORMS, FPN_READINGS, SHOT_NOISE_MODELS, ILLUMINANTS])
def test_every_registered_name_is_listed_in_the_error(registry):
    with pytest.raises(ConfigError) as e:
        registry.check("no-such-name")
    assert all(repr(n) in str(e.value) for n in registry.names) and len(registry) >= 2


def test_specs_are_validated_values():
    assert OpticsSpec(f_number=2) == OpticsSpec(f_number=2.0) and hash(OpticsSpec(2)) == hash(OpticsSpec(2.0))
    with pytest.raises(ConfigError, match=r"^optics.f_number = 0.1: must be a number between 0.5 and 64$"):
        OpticsSpec(f_number=0.1)
    with pytest.raises(ConfigError, match=r"^sensor.adc_bits = 8.5: must be an integer between 1 and 24$"):
        SensorSpec(adc_bits=8.5)
    s = small_scene()
    assert s == small_scene() and len({s, small_scene()}) == 1 and s.to_dict() == type(s).from_dict(s.to_dict()).to_dict()


# --- filters and QE: closed forms ------------------------------------------------------------------

FINE = WavelengthGrid(np.arange(400.0, 701.0, 1.0))


def test_gaussian_filters_have_the_stated_centre_and_fwhm():
    spec = FilterSpec(kind="gaussian", centres_nm=(610.0, 540.0, 460.0), fwhm_nm=(40.0, 60.0, 80.0), qe_peak=0.5)
    R = responsivities(spec, FINE)
    wl = np.asarray(FINE.centres_nm)
    for k, (c, fwhm) in enumerate(zip(spec.centres_nm, spec.fwhm_nm)):
        assert R[k, wl == c][0] == pytest.approx(0.5, rel=1e-3)  # peak transmittance 1 × QE
        for edge in (c - fwhm / 2, c + fwhm / 2):  # half maximum at ± FWHM/2
            assert R[k, wl == edge][0] == pytest.approx(0.25, rel=5e-3)


def test_camera_filters_peak_at_qe_peak_and_follow_the_measured_data():
    """A camera's relative curves are per unit energy: per photon they are S(λ)·λ⁻¹ up to one constant
    for all channels (the gains restored), scaled so the largest responsivity is qe_peak."""
    from spectracam.architecture.cameras import energy_sensitivities

    spec = FilterSpec(kind="camera", qe_peak=0.5)
    R = responsivities(spec, FINE)
    assert R.max() == pytest.approx(0.5, rel=5e-3)
    wl, S = energy_sensitivities(spec.camera)
    per_photon = S / wl[:, None]
    # between two measured samples the data are linear and so is 1/λ nearly: the band average over a
    # narrow band centred between them is the mean of the two samples' values
    i = list(wl).index(550.0)
    mid = (wl[i] + wl[i + 1]) / 2
    R_mid = responsivities(spec, WavelengthGrid([mid - 0.5, mid, mid + 0.5]))[:, 1]
    expected = 0.5 * (per_photon[i] + per_photon[i + 1]) * 0.5 / per_photon.max()
    np.testing.assert_allclose(R_mid, expected, rtol=1e-4)


def test_xyz_filters_are_quantal_colour_matching_functions():
    from spectracam.core.spectra import cie_1931_cmfs

    R = responsivities(FilterSpec(kind="xyz"), FINE)
    wl, xyz = cie_1931_cmfs()
    for lam in (450.0, 550.0, 600.0):
        j, i = int(np.flatnonzero(np.asarray(FINE.centres_nm) == lam)[0]), int(np.flatnonzero(wl == lam)[0])
        np.testing.assert_allclose(R[:, j] / R[1, j], xyz[i] / xyz[i, 1], rtol=2e-3)


@pytest.mark.parametrize("qe, at_400, at_600", [("flat", 0.5, 0.5), ("silicon", 0.35 * 0.5, 0.5)])
def test_qe_models(qe, at_400, at_600):
    f = quantum_efficiency(FilterSpec(qe=qe, qe_peak=0.5))
    np.testing.assert_allclose(f(np.array([400.0, 600.0])), [at_400, at_600])


# --- sensor options ------------------------------------------------------------------------------

def test_prnu_gain_has_mean_one_and_the_stated_rms():
    gain = fixed_pattern(SensorSpec(prnu_fraction=0.02), (500, 500), seed=3).gain
    assert gain.mean() == pytest.approx(1.0, abs=2e-4)  # 250k samples: σ of the mean 4e-5
    assert gain.std() == pytest.approx(0.02, rel=0.01)
    assert fixed_pattern(SensorSpec(prnu_fraction=0.0), (4, 4), seed=3)[1] is None


def test_snr_combinations_closed_forms():
    mu, sd = np.array([10.0, 20.0, 40.0]), np.array([1.0, 2.0, 2.0])
    assert combine_snr_db(mu, sd, "power") == pytest.approx(10 * np.log10(2100 / 9))
    assert combine_snr_db(mu, sd, "mean_db") == pytest.approx((20 + 20 + 20 * np.log10(20)) / 3)


def test_cfa_statistics_use_both_green_sites():
    # RGGB mosaic with the two greens at different levels: the G statistics must see both
    dn = np.tile(np.array([[50.0, 100.0], [300.0, 20.0]], np.float32), (8, 8))
    sensor = SensorSpec(dark_current=False, black_level_DN=0.0)
    raw = RawCapture(dn, None, np.ones(3), 1.0, MosaicLayout.bayer("RGGB"), CameraSpec(sensor=sensor), 0)
    means, stds = channel_stats(raw, [(slice(1, 15), slice(3, 13))])
    step = sensor.quantization_step_e
    np.testing.assert_allclose(means[0], np.array([50.5, 200.5, 20.5]) * step)
    assert stds[0, 1] == pytest.approx(100 * step) and stds[0, 0] == 0


# --- processing options --------------------------------------------------------------------------

def test_displays():
    import colour

    np.testing.assert_allclose(display_rgb_to_xyz("srgb"), colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ)
    M = display_rgb_to_xyz("crt")
    assert M.sum(axis=1)[1] == pytest.approx(1.0)
    # P22 phosphor chromaticities of a typical colour CRT: R (0.625, 0.340), G (0.280, 0.595), B (0.155, 0.070)
    xy = (M / M.sum(axis=0)).T[:, :2]
    np.testing.assert_allclose(xy, [[0.625, 0.340], [0.280, 0.595], [0.155, 0.070]], atol=0.012)


def test_gamut_clip_keeps_display_rgb_in_zero_one(scene_5000, analytic_5000):
    raw = capture(analytic_5000, seed=1, scene=scene_5000)
    free = score(raw, scene_5000, ProcessingSpec()).rendered_rgb
    clipped = score(raw, scene_5000, ProcessingSpec(gamut_clip=True)).rendered_rgb
    assert free.min() < 0 or free.max() > 1  # the CRT cannot show every patch
    assert clipped.min() == 0.0 and clipped.max() <= 1.0
    inside = (free >= 0) & (free <= 1)
    np.testing.assert_array_equal(clipped[inside], free[inside])
    np.testing.assert_array_equal(clipped[free > 1], 1.0)


@pytest.mark.parametrize("method", DEMOSAIC_METHODS.names)
def test_every_demosaicking_method_reproduces_a_flat_field(method):
    # a uniform field of each colour is reproduced exactly away from the border
    layout = MosaicLayout.bayer("GRBG")
    rgb = np.broadcast_to(np.array([3.0, 5.0, 7.0]), (16, 16, 3))
    out = DEMOSAIC_METHODS[method](layout.sample(np.ascontiguousarray(rgb, np.float32)).astype(float), layout)
    np.testing.assert_allclose(out[4:-4, 4:-4], rgb[4:-4, 4:-4], rtol=1e-6)


@pytest.mark.parametrize("name", ["D65", "A", None])
def test_dng_calibration_illuminants_are_a_and_d65_whatever_the_light(tmp_path, name):
    import tifffile

    from spectracam import ChartReference
    from spectracam.io.dng import write_dng

    ill = {"type": "cie", "name": name} if name else {"type": "blackbody", "temperature_K": 4000}
    scene = small_scene(image={"width": 96, "height": 72}, illuminant=ill)
    raw = capture(render(scene, "analytic"), scene=scene)
    write_dng(tmp_path / "r.dng", raw, ChartReference.of(scene))
    with tifffile.TiffFile(tmp_path / "r.dng") as t:
        tags = t.pages[0].tags  # CalibrationIlluminant1, 2 (EXIF LightSource): A and D65, never 255 ("other")
        assert tags[50778].value == 17 and tags[50779].value == 21 and 50721 in tags and 50722 in tags
