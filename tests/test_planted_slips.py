"""Issue 35, "a test for every slip": one focused test per slip an earlier review planted and found that the
suite let through.  Each asserts a closed form, a published value or a physical property (never the
implementation's own expression), is fast, and fails with the slip planted.

Slips, in the issue's order: the held-out 95th percentile; the design model's dark shot noise and PRNU term;
the Quad Bayer and RGBW tiles; the stacked sensor's capture time; texel centres; the interior guard band (the
function and the margin its caller asks for); the motion still reference and crossing
speed; the rolling shutter's shift; the view's scene preview matrix and raw preview scale; the posed edge's
sign; the misregistration axis; a ``--set`` list index; a false CLI flag; the random generator's known answer.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from spectracam.pipeline.scene_file import parse_scene

SMALL = {"image": {"width": 160, "height": 120}}


# -- 1. the held-out 95th percentile ------------------------------------------------------------------------------

def test_held_out_p95_is_the_95th_percentile_of_the_errors():
    """0, 1, …, 100 ΔE: the 95th percentile is 95 (any definition: it is a sample value), the mean 50, the max 100.
    A percentile asked as ``np.percentile(e, 0.95)`` (the 0.95th) reads 0.95."""
    from spectracam.evaluation import heldout

    rng = np.random.default_rng(35)
    e = rng.permutation(np.arange(101.0))         # order must not matter
    s = heldout.summary(e, "test")
    assert s["samples"] == 101
    assert s["delta_e_mean"] == pytest.approx(50.0)
    assert s["delta_e_p95"] == pytest.approx(95.0), s
    assert s["delta_e_max"] == 100.0
    # and on a textured target's per-pixel statistics, the same 95th percentile
    from spectracam.evaluation.target_score import _stats

    assert _stats(e) == pytest.approx((50.0, 95.0, 100.0))


# -- 2, 3. the design model's pixel variance: shot noise of signal + dark, PRNU² × signal² ------------------------

def _design_sensor(off=(), **kw):
    """``(SensorSpec, the design model's SensorModel of it)``: the paper's sensor with PRNU, DSNU and column FPN on."""
    from spectracam.camera import CameraSpec
    from spectracam.experiments.design.model import SensorModel

    cam = CameraSpec()
    sensor = cam.sensor.replace(**{"prnu_fraction": 0.02, "dsnu_fraction": 0.1, "fpn_fraction": 0.005,
                                   "column_fpn_fraction": 0.001, **kw})
    if off:
        sensor = sensor.off(*off)
    return sensor, SensorModel.of(cam.replace(sensor=sensor))


def _closed_form_variance(sensor, p, t):
    """Per pixel after dark subtraction (paper 3.4; docs/metrics.md "Expected error"): Poisson shot noise of the
    signal and of the dark charge d = i_d·A·t, read noise², the offset FPN (pixel and column, fractions of the
    well), a uniform quantiser's step²/12, PRNU as a gain (σ = PRNU·p) and DSNU as a dark gain (σ = DSNU·d)."""
    d = sensor.dark_current_e_per_s_um2 * sensor.pixel_pitch_um**2 * sensor.fill_factor * t
    assert d == pytest.approx(sensor.dark_rate_e_per_s * t)   # the pixel area: pitch² × fill factor
    step = sensor.quantization_step_e
    fpn2 = sensor.fpn_rms_e**2 + (sensor.column_fpn_fraction * sensor.q_max_e) ** 2
    return (p + d) + sensor.read_noise_e**2 + fpn2 + step**2 / 12 + (sensor.prnu_fraction * p) ** 2 \
        + (sensor.dsnu_fraction * d) ** 2, d


def test_design_pixel_variance_is_the_closed_form():
    from spectracam.experiments.design.model import pixel_moments

    sensor, sm = _design_sensor()
    assert sm.dark_rate_e_per_s > 0 and sm.prnu > 0
    rates = [np.array([2.0e3, 4.0e4, 1.0e5]), np.array([5.0e2, 7.0e3, 9.0e4]), np.array([3.0e3, 1.0e3, 6.0e4])]
    times = [0.5, 1.0, 0.25]          # long enough that the dark charge (1000 e⁻/s here) is hundreds of electrons
    p, var, dark = pixel_moments(rates, times, SimpleNamespace(sensor=sm))
    for k in range(3):
        want, d = _closed_form_variance(sensor, rates[k] * times[k], times[k])
        np.testing.assert_allclose(np.asarray(p[k], float), rates[k] * times[k], rtol=1e-12)
        assert float(dark[k]) == pytest.approx(d, rel=1e-12)
        np.testing.assert_allclose(np.asarray(var[k], float), want, rtol=1e-10, err_msg=f"channel {k}")


def test_design_shot_noise_includes_the_dark_charge():
    """Only shot noise and dark current on: the variance is Poisson's, the mean charge p + d."""
    from spectracam.experiments.design.model import pixel_moments

    sensor, sm = _design_sensor(off=("read_noise", "fpn", "quantization"))
    r, t = np.array([0.0, 1.0e3, 1.0e4]), 2.0
    p, var, dark = pixel_moments([r, r, r], [t, t, t], SimpleNamespace(sensor=sm))
    d = sensor.dark_rate_e_per_s * t
    assert d == pytest.approx(2000.0)
    np.testing.assert_allclose(np.asarray(var[0], float), r * t + d, rtol=1e-12)   # a dark pixel: var = d, not 0


def test_design_prnu_is_a_gain_squared():
    """PRNU alone: σ = PRNU × signal, so the variance grows with the square of the signal (×4 at twice the signal),
    and in a one-sensor camera (field-sequential) the gain is the same in every frame: covariance PRNU²·p_k·p_j."""
    from spectracam.experiments.design.model import channel_covariances, pixel_moments

    _, sm = _design_sensor(off=("shot_noise", "dark_current", "read_noise", "quantization"), prnu_fraction=0.03,
                           dsnu_fraction=0.0, fpn_fraction=0.0, column_fpn_fraction=0.0)
    assert sm.read_var_e2 == sm.fpn_var_e2 == sm.quant_var_e2 == 0 and not sm.shot
    signal = np.array([1.0e3, 2.0e3, 5.0e4])
    p, var, dark = pixel_moments([signal, 0.5 * signal, 2 * signal], [1.0, 1.0, 1.0], SimpleNamespace(sensor=sm))
    for k, f in enumerate((1.0, 0.5, 2.0)):
        np.testing.assert_allclose(np.asarray(var[k], float), (0.03 * f * signal) ** 2, rtol=1e-12)
    cam = SimpleNamespace(sensor=sm, mosaic_factors=None, shared_pattern=True)
    (C,) = channel_covariances(p, var, dark, cam)
    np.testing.assert_allclose(np.asarray(C[0][2], float), 0.03**2 * signal * (2 * signal), rtol=1e-12)
    np.testing.assert_allclose(np.asarray(C[1][0], float), 0.03**2 * (0.5 * signal) * signal, rtol=1e-12)


# -- 4, 5. the mosaics' tiles, as published --------------------------------------------------------------------

def _pattern(architecture, cfa="RGGB"):
    from spectracam.camera import CaptureSpec

    return CaptureSpec(architecture=architecture, cfa_pattern=cfa).make_architecture().layout.pattern


def test_quad_bayer_is_bayer_of_two_by_two_same_colour_blocks():
    """Sony IMX586's Quad Bayer: each site of the Bayer tile becomes a 2×2 block, rows in the Bayer pattern's order.
    GRBG (not symmetric under transposition, unlike RGGB) tells a transposed tile apart."""
    assert _pattern("quad_bayer", "RGGB") == "RRGG" "RRGG" "GGBB" "GGBB"
    assert _pattern("quad_bayer", "GRBG") == "GGRR" "GGRR" "BBGG" "BBGG"
    assert _pattern("quad_bayer", "GBRG") == "GGBB" "GGBB" "RRGG" "RRGG"


def test_rgbw_tile_is_kodak_cfa_2_0():
    """Kodak's CFA 2.0 (Compton & Hamilton, US 2007/0024931), as the module's docstring draws it:
    W on a checkerboard, B top-left, R bottom-right."""
    import spectracam.architecture.rgbw as rgbw

    want = "WBWG" "BWGW" "WGWR" "GWRW"
    assert _pattern("rgbw") == want
    drawn = "".join("".join(line.split()) for line in rgbw.__doc__.splitlines()
                    if len(line.split()) == 4 and set(line.split()) <= set("RGBW"))
    assert drawn == want                                  # the tile the docstring cites


# -- 6. texel centres -------------------------------------------------------------------------------------------

def test_samples_layout_squares_are_centred_in_their_cells():
    """The library chart's squares, (1 − gap) of their cell, centred in it, rasterised by texel centre (i + ½):
    a cell of 10 texels with gap 0.25 (inset 1.25) keeps texels 1…8, one texel off each side — symmetric.  Centres
    off by half a texel keep 2…8."""
    from spectracam.scene.target import TargetSpec, texel_labels

    spec = TargetSpec(kind="samples", supersampling=2, gap=0.25, columns=4, samples=tuple(range(8)))
    labels = np.asarray(texel_labels(spec, 20, 10, 99))           # 40 × 20 texels: cells of 10 texels, 4 × 2
    assert labels.shape == (20, 40)
    square = labels != 99
    np.testing.assert_array_equal(square, square[::-1, ::-1])     # centred: the same turned half a turn
    cell = square[:10, :10]
    want = np.zeros((10, 10), bool)
    want[1:9, 1:9] = True
    np.testing.assert_array_equal(cell, want)
    assert labels[5, 5] == 0 and labels[5, 35] == 3 and labels[15, 5] == 4


def test_painted_shapes_cover_texels_by_their_centres():
    """A disc of radius 2 about texel coordinates (5, 5) (a texel's corner) covers the texels whose centre
    (x + ½, y + ½) lies within it: the 12 of a 4 × 4 block less its corners, symmetric about (5, 5); a rectangle of half
    sides 2 × 1 about (5, 5) covers columns 3…6 and rows 4…5."""
    from spectracam.scene._paint import paint_shapes

    def paint(disc, hw, hh):
        labels = np.full((10, 10), -1, np.int32)
        bare = paint_shapes(labels, np.array([5.0]), np.array([5.0]), np.array([hw]), np.array([hh]),
                            np.array([7], np.int32), disc, labels.size)
        return labels == 7, bare

    disc, bare = paint(True, 2.0, 2.0)
    y, x = np.mgrid[0:10, 0:10]
    want = (x + 0.5 - 5.0) ** 2 + (y + 0.5 - 5.0) ** 2 <= 4.0
    assert want.sum() == 12
    np.testing.assert_array_equal(disc, want)
    assert bare == 100 - 12
    rect, _ = paint(False, 2.0, 1.0)
    want = np.zeros((10, 10), bool)
    want[4:6, 3:7] = True
    np.testing.assert_array_equal(rect, want)


def test_stacked_layers_integrate_together_so_the_capture_takes_one_exposure():
    """Every layer of a stacked pixel integrates at once (one exposure for all): the capture lasts the exposure,
    not the sum of the layers' times — against the field-sequential camera, whose frames follow one another."""
    from spectracam.architecture import make_architecture

    times = [0.010, 0.010, 0.010]                      # the one exposure, as each layer records it
    assert make_architecture("stacked").capture_time_s(times) == pytest.approx(0.010)
    assert make_architecture("fsc").capture_time_s(times) == pytest.approx(0.030)


# -- 7. the interior guard band ---------------------------------------------------------------------------------

@pytest.mark.parametrize("margin", [1, 2, 3])
def test_interior_excludes_pixels_within_the_margin_of_another_label(margin):
    """Two labels meeting at column 10 of a 20 × 30 image, and one mixed pixel (−1) at (row 5, column 4): a pixel
    is interior when no other label, mixed pixel or image border lies within ``margin`` pixels (Chebyshev)."""
    from spectracam.evaluation.target_score import _interior

    labels = np.zeros((20, 30), np.int32)
    labels[:, 10:] = 1
    labels[5, 4] = -1
    got = _interior(labels, margin)
    y, x = np.mgrid[0:20, 0:30]
    inside = (y >= margin) & (y <= 19 - margin) & (x >= margin) & (x <= 29 - margin)
    away_from_boundary = (x <= 9 - margin) | (x >= 10 + margin)
    away_from_mixed = np.maximum(abs(y - 5), abs(x - 4)) > margin
    np.testing.assert_array_equal(got, inside & away_from_boundary & away_from_mixed)
    assert got[10, 9 - margin] and not got[10, 10 - margin]       # the guard band is margin pixels wide
    assert got[10, 10 + margin] and not got[10, 9 + margin]


def test_textured_score_asks_for_the_targets_own_margin(monkeypatch):
    """The guard band the score uses is ``target.interior_margin_px`` as stated, neither one less nor one more."""
    import spectracam.evaluation.target_score as ts
    from spectracam.pipeline import capture, render, score

    asked = []
    real = ts._interior
    monkeypatch.setattr(ts, "_interior", lambda labels, margin: asked.append(margin) or real(labels, margin))
    for margin in (1, 3):
        scene = parse_scene({"target": {"kind": "samples", "interior_margin_px": margin}, **SMALL})
        score(capture(render(scene, "analytic"), scene=scene), scene)
        assert asked[-1] == margin


# -- 8. the motion still reference is noise-free ---------------------------------------------------------------

MOTION_TINY = ("edge_size_px=[48, 32]", "speeds_px_per_ms=[0.0]", "samples_per_subpixel=4", "zone_half_width_px=12.0",
               "wavelengths={start_nm = 400, stop_nm = 700, step_nm = 30}", "rolling_shutter=[false]",
               "designs=['cfa/single']")


def test_motion_still_reference_is_the_noise_free_capture():
    """The still reference is the design's capture without noise: its false colour is the noise-free run's and
    does not change with the noise seed; at rest every noisy seed differs from it (by its noise: none is 0)."""
    from spectracam.experiments.motion.experiment import load_motion, run_motion

    def row(*sets):
        spec, scene = load_motion(MOTION_TINY + sets)
        (r,) = run_motion(spec, scene, renderer="analytic", keep_images=False)["rows"]
        return r

    noisy, other_seed, quiet = row("seeds=2"), row("seeds=2", "seed=5"), row("noise=false")
    assert quiet.scielab_delta_e_by_seed == (0.0,)
    assert noisy.false_colour_still == pytest.approx(quiet.false_colour_still, rel=1e-5)
    assert other_seed.false_colour_still == pytest.approx(noisy.false_colour_still, rel=1e-12)
    assert all(x > 0.05 for x in noisy.scielab_delta_e_by_seed + other_seed.scielab_delta_e_by_seed), \
        (noisy.scielab_delta_e_by_seed, other_seed.scielab_delta_e_by_seed)


# -- 9. the crossing speed --------------------------------------------------------------------------------------

def test_crossing_speed_is_the_linear_interpolation_of_the_difference():
    """a − b = −2, −1, +3 at 0, 0.1, 0.3 px/ms: zero between 0.1 and 0.3 at 0.1 + 0.2·1/4 = 0.15 px/ms."""
    from spectracam.experiments.motion.experiment import crossing

    speeds = np.array([0.0, 0.1, 0.3])
    b = np.array([5.0, 5.0, 5.0])
    got = crossing(speeds, b + np.array([-2.0, -1.0, 3.0]), b)
    assert got["status"] == "crosses" and got["between"] == [0.1, 0.3]
    assert got["speed_px_per_ms"] == pytest.approx(0.15)
    got = crossing(np.array([0.0, 1.0, 2.0]), np.array([1.0, 1.0, 4.0]), np.array([2.0, 3.0, 1.0]))
    assert got["speed_px_per_ms"] == pytest.approx(1.0 + 2.0 / 5.0)     # −1, −2, +3: 1 + 1·2/(2 + 3)


# -- 12. the rolling shutter's shift -----------------------------------------------------------------------------

def test_rolling_shutter_shifts_a_rightward_edge_right_in_lower_rows():
    """Rows are read top to bottom, row r a line time t_row later than row r − 1: a vertical edge moving right at v
    lies v·t_row·r further right in row r (a shear with the closed-form slope v·t_row)."""
    from spectracam.architecture.base import make_architecture
    from spectracam.experiments.motion.motion import Motion
    from spectracam.experiments.motion.render import MovingScene, integrate
    from spectracam.experiments.motion.timing import TimingSpec, capture_timing
    from spectracam.pipeline.scene_file import Scene
    from spectracam.experiments.spatial.geometry import CameraGeometry
    from spectracam.experiments.spatial.targets import SlantedEdge

    scene = Scene.from_dict({"wavelengths": {"start_nm": 400, "stop_nm": 700, "step_nm": 50}})
    width, height, margin, line_us, v = 32, 12, 4, 500.0, 0.4     # v in px/ms
    g = CameraGeometry.framing(width * 0.5, 12.0, 1.4, 10.0, width, height).with_margin(margin)
    ms = MovingScene(SlantedEdge(angle_deg=0.0, x0_px=0.3), g, scene.illuminant, scene.grid, 4, "analytic")
    motion = Motion(velocity_mm_per_s=(v * 1e3 * g.object_pixel_mm, 0.0))
    timing = capture_timing(make_architecture("cfa"), [0.002] * 3,
                            TimingSpec(rolling_shutter=True, line_time_us=line_us), g.height_px, -margin)
    (_, acc), = integrate(ms, motion, timing, max_step_px=0.05).groups
    px = acc.reshape(acc.shape[0], acc.shape[1] // 4, 4, acc.shape[2] // 4, 4).mean(axis=(2, 4))
    bright = px[1, margin:-margin, margin:-margin]
    edge = width / 2 - bright.sum(axis=1)                  # per image row, top to bottom: x of a sharp edge
    rows = np.arange(height)
    slope = np.polyfit(rows, edge, 1)[0]
    assert slope == pytest.approx(v * line_us * 1e-3, rel=0.02), edge
    np.testing.assert_allclose(np.diff(edge), v * line_us * 1e-3, atol=0.01)


# -- 10, 11. the view's previews --------------------------------------------------------------------------------

def _rgb8(image):
    h, w = image.shape
    return image.view(np.uint8).reshape(h, w, 4)[..., :3].astype(int)


def _srgb8(x):
    """IEC 61966-2-1 encoding to 8 bits."""
    x = np.clip(np.asarray(x, float), 0, 1)
    return np.round(255 * np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)).astype(int)


def test_view_scene_preview_is_srgb_of_the_scene():
    """Under CIE D65 (sRGB's white) a grey of reflectance 0.2 previews as linear sRGB (0.2, 0.2, 0.2) and the white
    diffuser as (1, 1, 1); an orange (a 600-nm band) as the published XYZ→sRGB matrix (IEC 61966-2-1) says."""
    from spectracam.scene.illuminant import white_diffuser_radiance
    from spectracam.render import RadianceCube
    from spectracam.core.spectra import K_M_LM_PER_W, cmf_band_weights
    from spectracam.view.cases import Case, _radiance

    scene = parse_scene({**SMALL, "illuminant": {"type": "cie", "name": "D65"}})
    grid = scene.grid
    white = white_diffuser_radiance(scene.illuminant, grid)
    orange = np.where(np.abs(np.asarray(grid.centres_nm) - 600) < 6, white, 0.02 * white)
    rad = np.stack([np.stack([white, 0.2 * white, orange])] * 2).astype(np.float32)    # 2 × 3 pixels
    cube = RadianceCube(rad, np.asarray(grid.centres_nm, float), {"scene": scene.to_dict()})
    case = Case(name="t", width=3, height=2, stride=1)
    _radiance(case, cube)
    got = _rgb8(case.images["scene"])
    assert got[0, 0].tolist() == [255, 255, 255]
    assert np.abs(got[0, 1] - _srgb8(0.2)).max() <= 1, got[0, 1]
    M = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])
    w = cmf_band_weights(grid) * K_M_LM_PER_W
    xyz = (orange @ w) / (white @ w)[1]
    want = _srgb8(M @ xyz)
    assert len(set(want.tolist())) == 3                  # a colour whose channels differ
    assert np.abs(got[0, 2] - want).max() <= 1, (got[0, 2], want)


def test_view_raw_preview_maps_the_top_code_to_full_scale(tmp_path):
    """Each raw pixel in its channel's colour at brightness DN / top code (2ⁿ − 1): a G pixel at the top code is the
    G colour at full scale, at half the top code at half of it."""
    from spectracam.architecture.base import MosaicLayout
    from spectracam.camera import CameraSpec
    from spectracam.camera.capture import RawCapture
    from spectracam.io.exr import write_raw_exr
    from spectracam.view.cases import CHANNEL_COLOURS, load_case

    cam = CameraSpec()
    top = 2**cam.sensor.adc_bits - 1
    dn = np.full((4, 4), float(top), np.float32)          # RGGB: (0, 1) and (1, 0) are G
    dn[1, 0] = round(top / 2)
    dn[1, 1] = 0.0
    raw = RawCapture(dn, None, np.array([0.01, 0.01, 0.01]), 0.01, MosaicLayout.bayer("RGGB"), cam, 0)
    case = load_case("t", None, write_raw_exr(tmp_path / "raw.exr", raw), None)
    got = _rgb8(case.images["raw"])
    g = np.array(CHANNEL_COLOURS["G"])
    assert got[0, 1].tolist() == _srgb8(g).tolist()
    assert np.abs(got[1, 0] - _srgb8(g * round(top / 2) / top)).max() <= 1
    assert got[0, 0].tolist() == _srgb8(CHANNEL_COLOURS["R"]).tolist()
    assert got[1, 1].tolist() == [0, 0, 0]


# -- 13. the posed edge's sign -----------------------------------------------------------------------------------

def test_posed_edge_moves_with_the_object():
    """The slanted edge runs ``angle`` from the vertical, its column growing down the image (documented).  Moving
    the object up by 3 pixels (y up) moves the image up 3 rows: the posed edge's coverage at row r is the resting
    edge's at row r + 3; moved right by 2 pixels, it is the resting edge's 2 columns to the left."""
    from spectracam.experiments.motion.render import posed_edge
    from spectracam.experiments.spatial.geometry import CameraGeometry
    from spectracam.experiments.spatial.targets import SlantedEdge

    ss, W, H = 2, 40, 40
    g = CameraGeometry.framing(W * 0.5, 12.0, 1.4, 10.0, W, H)
    edge = SlantedEdge(angle_deg=10.0, x0_px=0.3)
    rest = edge.coverage(g, ss)[1]                                    # bright fraction (Hs, Ws)
    cols = W - rest.reshape(H, ss, W, ss).mean(axis=(1, 3)).sum(axis=1)
    assert cols[-1] > cols[0]                                         # the documented sign: column grows with row
    assert (cols[-1] - cols[0]) / (H - 1) == pytest.approx(math.tan(math.radians(10.0)), rel=1e-3)
    up = posed_edge(edge, g, (0.0, 3 * g.object_pixel_mm, 0.0)).coverage(g, ss)[1]
    np.testing.assert_allclose(up[:-3 * ss], rest[3 * ss:], atol=1e-9)
    right = posed_edge(edge, g, (2 * g.object_pixel_mm, 0.0, 0.0)).coverage(g, ss)[1]
    np.testing.assert_allclose(right[:, 2 * ss:], rest[:, :-2 * ss], atol=1e-9)
    assert posed_edge(edge, g, (0.0, 3 * g.object_pixel_mm, 0.0)).x0_px == pytest.approx(
        0.3 + 3 * math.tan(math.radians(10.0)))


# -- 14. the spatial misregistration axis -----------------------------------------------------------------------

def test_misregistration_along_x_shifts_columns():
    """The prism's red sensor is misregistered by +m along x, the blue by +m along y; a sensor sampling 1 px to the
    right (x) sees the next column, 1 px down (y) the next row, of the same image."""
    from scipy import fft as sfft

    from spectracam.experiments.spatial.capture import misregistration_shifts
    from spectracam.experiments.spatial.optics import sample_channels

    assert misregistration_shifts(0.5) == ((0.5, 0.0), (0.0, 0.0), (0.0, 0.5))
    ss, H, W = 2, 8, 12
    img = np.random.default_rng(14).random((H * ss, W * ss))
    spectra = sfft.rfft2(img)[None]
    fy, fx = sfft.fftfreq(H * ss)[:, None], sfft.rfftfreq(W * ss)[None, :]

    def sample(shift):
        return sample_channels(spectra, fy, fx, img.shape, ss, 1.0, (shift,), 0)[..., 0]

    still = sample((0.0, 0.0))
    np.testing.assert_allclose(sample((1.0, 0.0)), np.roll(still, -1, axis=1), atol=1e-5)
    np.testing.assert_allclose(sample((0.0, 1.0)), np.roll(still, -1, axis=0), atol=1e-5)


# -- 15, 16. --set list elements and false flags -----------------------------------------------------------------

def test_set_list_index_sets_that_element():
    """``a.b[1]=v`` sets the second element (indices from 0), in a table, at the top level and in a list the file
    leaves at its default."""
    from spectracam.pipeline.overrides import apply_overrides

    assert apply_overrides({"a": {"b": [1, 2, 3]}}, ["a.b[1]=9"]) == {"a": {"b": [1, 9, 3]}}
    assert apply_overrides({"a": {"b": [1, 2, 3]}}, ["a.b[0]=9"]) == {"a": {"b": [9, 2, 3]}}
    assert apply_overrides({"k": [1, 2, 3]}, ["k[2]=9"]) == {"k": [1, 2, 9]}
    assert apply_overrides({}, ["a.b[1]=9"], defaults=lambda: {"a": {"b": [1, 2, 3]}}) == {"a": {"b": [1, 9, 3]}}
    from spectracam.experiments.motion.experiment import load_motion

    spec, _ = load_motion(("designs[1]='rgbw/single'",))      # an experiment's list left at its default
    default, _ = load_motion(())
    assert spec.designs == (default.designs[0], "rgbw/single", *default.designs[2:])


def test_a_false_flag_reaches_the_spec_as_false():
    """``--no-gamut-clip`` over a scene that clips, and ``--set processing.gamut_clip=false``: both turn it off."""
    import click
    from click.testing import CliRunner

    from spectracam.experiments.options import scene_from as _scene
    from spectracam.experiments.options import flag_overrides, processing_options

    data = {**SMALL, "processing": {"gamut_clip": True}}
    seen = {}

    @click.command()
    @processing_options
    def cmd(**kw):
        seen.update(kw)

    for argv, want in ((["--no-gamut-clip"], False), (["--gamut-clip"], True), ([], True)):
        seen.clear()
        r = CliRunner().invoke(cmd, argv)
        assert r.exit_code == 0, r.output
        flags = flag_overrides(**seen)
        assert (("processing.gamut_clip", want) in flags) == bool(argv), flags
        assert _scene(data, "scene.toml", flags=flags).processing.gamut_clip is want, argv
    assert _scene(data, "scene.toml", sets=["processing.gamut_clip=false"]).processing.gamut_clip is False
    assert _scene({**SMALL}, "scene.toml", sets=["processing.gamut_clip=true"]).processing.gamut_clip is True


# -- 17. the random generator: known answers ------------------------------------------------------------------------

#: Philox4x32-10 of the zero counter under the zero key: Random123's published known-answer vector
#: (Salmon et al., SC'11; Random123 ``kat_vectors``: "philox4x32 10 0 0 0 0 0 0 → 6627e8d5 e169c58d bc57ac4c 9b00dbd8").
PHILOX_ZERO = (0x6627E8D5, 0xE169C58D, 0xBC57AC4C, 0x9B00DBD8)
#: Recorded at commit b2d6aa4: the Philox key of seed 0's temporal-noise stream (``noise_stream(0, TEMPORAL_STREAM)``)
#: and its first draws.  A change to the key derivation (the seed sequence, the stream numbers, the words taken)
#: changes every noisy result; if it is meant, record the new values here and say so.
RECORDED_KEY = (3141116543, 4003597245)
RECORDED_NORMALS = (0.20630094408988953, 1.5000828504562378, -1.113478183746338, -1.2905722856521606,
                    1.4449615478515625, 0.19389772415161133)
RECORDED_UNIFORMS = (0.8014543652534485, 0.20666712522506714, 0.47262847423553467, 0.37641477584838867)


def test_philox_matches_the_published_known_answer():
    from spectracam.sensor import kernels

    got = kernels.philox_np(np.array([0], np.uint64), (0, 0), 0)
    assert tuple(int(w[0]) for w in got) == PHILOX_ZERO
    if kernels.available():          # the compiled kernel: the same first word, as a uniform (top 24 bits · 2⁻²⁴)
        from spectracam.sensor import _numba_kernels as nk

        out = np.empty(4, np.float32)
        nk.fill_kernel(out, np.int64(0), np.uint64(0), np.uint64(0), False)
        assert float(out[0]) == (PHILOX_ZERO[0] >> 8) * 2.0**-24


@pytest.mark.parametrize("fused", ["1", "0"])
def test_noise_stream_known_answer(fused, monkeypatch):
    """The project's generator from seed 0 (recorded at b2d6aa4), on the compiled kernels and on the NumPy path."""
    from spectracam.sensor import kernels
    from spectracam.sensor import TEMPORAL_STREAM, noise_stream

    monkeypatch.setenv("SPECTRACAM_FUSED", fused)
    if fused == "1" and not kernels.available():
        pytest.skip("numba kernels unavailable here")
    seq = noise_stream(0, TEMPORAL_STREAM)
    assert kernels.stream_key(seq) == RECORDED_KEY
    rng = kernels.CounterRNG(seq)
    np.testing.assert_array_equal(rng.standard_normal(6, dtype=np.float32), np.float32(RECORDED_NORMALS))
    np.testing.assert_array_equal(rng.random(4, dtype=np.float32), np.float32(RECORDED_UNIFORMS))
