"""The expected-error model: a camera's mean ΔE*ab and SNR under noise, in closed form, differentiable.

For responsivities R_k(λ) (filter × QE × IR cut, electrons per photon), one light and one sensor, with every
colour's band radiance L_s(λ) (docs/metrics.md, "Expected error"):

* rates ``ρ_sk = Σ_b L_sb·g_b·R_kb`` (paper 3.2-3.3; ``g_b`` the optics' photon factor × band width × pixel area);
* exposure ``t_k`` metered on the chart's white patch by the camera's scheme (paper 4.5; :mod:`spectracam.sensor.exposure`);
* per pixel of channel k, after the dark-frame subtraction: mean ``p = ρ·t`` electrons and variance
  ``σ² = (p + d)·[shot] + σ_r² + σ_FPN² + Δ²/12 + (PRNU·p)² + (DSNU·d)²`` (paper 3.4; ``d = i_d·A·t`` the dark
  charge, Δ the ADC step in electrons: the floor-and-mid-step quantiser is unbiased with variance Δ²/12 while the
  other noise spans a step or more);
* demosaicking (a linear interpolator, the paper's bilinear by default) mixes neighbours: the covariance of the
  interpolated channels at each site of the tile is ``Σ_c σ_c²·F[u, c]``, with ``F`` the sum of squared (and
  crossed) interpolation weights read from the project's own demosaicker by impulses (:func:`demosaic_factors`);
  full planes share one fixed pattern across channels when the architecture has one sensor (FSC);
* the conversion ``M`` least squares on the chart's noise-free rates (paper 3.5), solved in the model, so its
  gradient flows; display RGB mean ``ρ·M`` and covariance ``Mᵀ·diag(1/t)·C·diag(1/t)·M``;
* the expected ΔE*ab = E‖Lab(M_disp·x) − Lab_scene‖ over x ~ N(mean, covariance), by a fixed scrambled-Sobol
  quadrature of :data:`QUADRATURE_POINTS` normal points (the full CIELAB non-linearity, no linearisation):
  deterministic, so the objective is smooth and its gradient exact for the quadrature.

Clipping is excluded: the white patch is metered to ``white_fill`` (0.95) of the well, so no chart colour clips;
colours whose mean + 3σ passes the well are counted (``clipped``), never silently scored.  The black level keeps
the ADC's zero code below 3σ of the dark noise (:mod:`spectracam.sensor`), so that clip is excluded too.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from spectracam.architecture.base import MosaicLayout
from spectracam.core.errors import SpectracamError
from spectracam.experiments.design.ad import backend, cholesky3, fresh, solve_spd, tensor, xyz_to_lab
from spectracam.sensor import dark_gain_moments

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from spectracam.architecture.base import Architecture
    from spectracam.camera import CameraSpec
    from spectracam.processing.color import ProcessingSpec

__all__ = ["DEFAULT_DISPLAY_PIXEL_PITCH_MM", "DEFAULT_VIEWING_DISTANCE_M", "QUADRATURE_POINTS",
           "QUADRATURE_SEED", "SCORES", "CameraModel", "ColourSet", "LightModel", "LightResult",
           "SensorModel", "WhiteModel", "capture_rule", "channel_covariances", "conversion",
           "demosaic_factors", "evaluate", "expected_delta_e", "exposure_times", "normal_points",
           "pixel_moments", "scielab_covariances", "scielab_mosaic_factors", "scielab_white_factors",
           "viewing_samples_per_degree", "white_balance_penalty"]

#: Normal points of the expected-ΔE quadrature (a power of two: Sobol's balance).  256 agree with 4096 within
#: 0.3 % of the mean ΔE on the paper's designs (tests/test_design_model.py).
QUADRATURE_POINTS = 256
#: The quadrature's scramble: fixed, so the objective is one deterministic function.
QUADRATURE_SEED = 1999


def normal_points(n: int = QUADRATURE_POINTS) -> np.ndarray:
    """``(n, 3)`` standard normal points of a scrambled Sobol sequence (fixed seed).

    Parameters
    ----------
    n : int
        How many points (a power of two keeps Sobol's balance).

    Returns
    -------
    ndarray
        ``(n, 3)`` float64, the same for every call (:data:`QUADRATURE_SEED`).
    """
    from scipy.stats import norm, qmc

    u = qmc.Sobol(3, scramble=True, seed=QUADRATURE_SEED).random(n)
    return norm.ppf(np.clip(u, 1e-12, 1 - 1e-12))


@dataclass(frozen=True)
class SensorModel:
    """The sensor's numbers the moments need (:class:`~spectracam.sensor.SensorSpec`)."""

    q_max_e: float
    white_fill: float
    dark_rate_e_per_s: float
    shot: bool
    read_var_e2: float
    fpn_var_e2: float
    quant_var_e2: float
    prnu: float
    dsnu: float

    @classmethod
    def of(cls, camera: CameraSpec) -> "SensorModel":
        """The sensor numbers of ``camera`` (its sensor, and its capture's ``white_fill``), as plain floats.

        Parameters
        ----------
        camera : CameraSpec
            The camera; a noise source switched off contributes 0.

        Returns
        -------
        SensorModel
            Variances in e⁻², the dark rate in e⁻/s, the well in e⁻.

        Raises
        ------
        SpectracamError
            When the sensor's read-out is not ``"single"`` (the model knows one read at the end of the exposure).
        """
        s = camera.sensor
        if s.readout != "single":
            raise SpectracamError(f"sensor.readout = {s.readout!r}: the design's expected-error model knows one read at "
                                  "the end of the exposure (the paper's); design with 'single', then compare read-outs "
                                  "with spectracam dynamic-range or spectracam datasheet")
        fpn = s.fpn and s.fpn_fraction > 0
        # plain floats: a numpy scalar times a Dr.Jit tensor would let numpy try to broadcast the tensor
        return cls(q_max_e=float(s.q_max_e), white_fill=float(camera.capture.white_fill),
                   dark_rate_e_per_s=float(s.dark_rate_e_per_s), shot=bool(s.shot_noise),
                   read_var_e2=float(s.read_noise_rms_e**2),
                   fpn_var_e2=float(s.fpn_rms_e**2 + (s.column_fpn_fraction * s.q_max_e) ** 2 if fpn else 0.0),
                   quant_var_e2=float(s.quantization_step_e**2 / 12.0 if s.quantization else 0.0),
                   prnu=float(s.prnu_fraction if s.fpn else 0.0),
                   dsnu=float(np.sqrt(dark_gain_moments(s)[1])))


def demosaic_factors(layout: MosaicLayout, method: str) -> np.ndarray:
    """``F[u, c, k, j]``: for output site ``u`` of the tile (row-major), the covariance of demosaicked channels k
    and j per unit variance of input channel c's pixels, all pixels independent: Σ over c's pixels of the product
    of their weights in k and j.  Read from the demosaicker by one impulse per tile site (exact for a linear,
    tile-periodic interpolator); a non-linear one is refused.

    Parameters
    ----------
    layout : MosaicLayout
        The mosaic.
    method : str
        The demosaicker (``processing.demosaic``).

    Returns
    -------
    ndarray
        ``(tile sites, N, N, N)``.

    Raises
    ------
    SpectracamError
        When the demosaicker is not linear.
    """
    from spectracam.processing.color import demosaic

    th, tw = layout.tile_shape
    n = len(layout.channels)
    reps = max(8, -(-24 // min(th, tw)))
    H, W = th * reps, tw * reps
    cy, cx = (reps // 2) * th, (reps // 2) * tw
    rng = np.random.default_rng(0)
    a, b = rng.random((H, W)), rng.random((H, W))
    if not np.allclose(demosaic(2 * a - 3 * b, layout, method), 2 * demosaic(a, layout, method)
                       - 3 * demosaic(b, layout, method), atol=1e-9):
        raise SpectracamError(f"design: processing.demosaic = {method!r} is not linear; the expected-error model "
                              "needs a linear demosaicker (bilinear, patch or malvar2004)")
    F = np.zeros((th * tw, n, n, n))
    for dy, dx, c in layout.sites():
        img = np.zeros((H, W))
        img[cy + dy, cx + dx] = 1.0
        out = demosaic(img, layout, method)
        for uy in range(th):
            for ux in range(tw):
                sel = out[uy::th, ux::tw].reshape(-1, n)
                F[uy * tw + ux, c] += sel.T @ sel
    return F


#: The viewing geometry S-CIELAB assumes when the processing names none: 0.5 m from a 120-dpi display, the
#: reference code's (ISETCam's scParams) and ProcessingSpec's defaults (41.2 samples per degree).
DEFAULT_VIEWING_DISTANCE_M = 0.5
DEFAULT_DISPLAY_PIXEL_PITCH_MM = 25.4 / 120


def viewing_samples_per_degree(processing: ProcessingSpec | object) -> float:
    """Image samples per degree of visual angle of ``processing``'s viewing geometry (``viewing_distance_m``,
    ``display_pixel_pitch_mm``; one image pixel per display pixel): ``1 / (2·atan(p/2d))`` in degrees
    (:func:`spectracam.evaluation.scielab.samples_per_degree`), the chart score's own.

    Parameters
    ----------
    processing : ProcessingSpec or object
        Its ``viewing_distance_m`` (m) and ``display_pixel_pitch_mm`` (mm); a missing one is
        :data:`DEFAULT_VIEWING_DISTANCE_M` or :data:`DEFAULT_DISPLAY_PIXEL_PITCH_MM`.

    Returns
    -------
    float
        Samples per degree.
    """
    from spectracam.evaluation.scielab import samples_per_degree

    d = getattr(processing, "viewing_distance_m", DEFAULT_VIEWING_DISTANCE_M)
    p = getattr(processing, "display_pixel_pitch_mm", DEFAULT_DISPLAY_PIXEL_PITCH_MM)
    return samples_per_degree(d, p * 1e-3)


def _scielab_kernels(samples_per_degree: float) -> np.ndarray:
    """``(3, n, n)`` the S-CIELAB point spreads (luminance, red-green, blue-yellow; each sums to 1) of
    :func:`spectracam.evaluation.scielab.scielab_kernels`, the pipeline's own."""
    from spectracam.evaluation.scielab import scielab_kernels

    return np.stack(scielab_kernels(samples_per_degree))


def scielab_white_factors(samples_per_degree: float) -> np.ndarray:
    """``ρ[i, j] = Σ_x h_i(x)·h_j(x)``: the covariance of opponent channels i and j after the S-CIELAB kernels
    ``h_i``, ``h_j`` per unit covariance of spatially white noise (full planes: one independent draw per pixel).

    Parameters
    ----------
    samples_per_degree : float
        The viewing geometry (:func:`viewing_samples_per_degree`).

    Returns
    -------
    ndarray
        ``(3, 3)`` ρ, over luminance, red-green and blue-yellow.
    """
    h = _scielab_kernels(samples_per_degree)
    return np.einsum("iab,jab->ij", h, h)


_SCIELAB_MOSAIC_CACHE: dict = {}


def scielab_mosaic_factors(layout: MosaicLayout, method: str, samples_per_degree: float) -> np.ndarray:
    """``S[u, c, i, j, k, l]``: at an output pixel of tile site ``u`` (row-major), the covariance of the demosaicked
    channels k and l after the S-CIELAB kernels h_i and h_j, per unit variance of input channel c's pixels, all
    pixels independent:

        S[u, c, i, j, k, l] = Σ_{y ∈ c's pixels} g_ik(x_u; y)·g_jl(x_u; y),   g_ik(x; y) = Σ_x' h_i(x − x')·w_k(x', y)

    with ``w_k(x', y)`` the demosaicker's weight of pixel y in channel k at x' (its impulse response).  By the
    tile's periodicity the sum over c's pixels for one output pixel equals, for one impulse per site of c in the
    tile, the sum over every output pixel of site u — how it is computed: one impulse per tile site through
    :func:`spectracam.processing.color.demosaic`, each output plane convolved with each kernel.  With one-pixel kernels
    (``h = δ``) it is :func:`demosaic_factors` (``S[u, c, i, j, k, l] = F[u, c, k, l]``).  Cached per layout, method
    and samples per degree (the factors depend on nothing else).

    Parameters
    ----------
    layout : MosaicLayout
    method : str
        The demosaicker; it must be linear.
    samples_per_degree : float
        The viewing geometry (:func:`viewing_samples_per_degree`).

    Returns
    -------
    ndarray
        ``(tile sites, N, 3, 3, N, N)`` S; the cached array itself (not a copy).
    """
    from scipy.signal import fftconvolve

    from spectracam.processing.color import DEMOSAIC_MARGIN, demosaic

    key = (layout, method, float(samples_per_degree))
    if key in _SCIELAB_MOSAIC_CACHE:
        return _SCIELAB_MOSAIC_CACHE[key]
    _require_linear(layout, method)
    h = _scielab_kernels(samples_per_degree)
    half = (h.shape[-1] - 1) // 2
    th, tw = layout.tile_shape
    n = len(layout.channels)
    reach = half + DEMOSAIC_MARGIN + max(th, tw)      # the impulse's response lies well inside the image
    ry, rx = -(-(2 * reach + 1) // th), -(-(2 * reach + 1) // tw)
    H, W = th * ry, tw * rx
    cy, cx = (ry // 2) * th, (rx // 2) * tw
    S = np.zeros((th * tw, n, 3, 3, n, n))
    for dy, dx, c in layout.sites():
        img = np.zeros((H, W))
        img[cy + dy, cx + dx] = 1.0
        out = demosaic(img, layout, method)                                   # (H, W, n): w_k(·, y)
        g = np.stack([[fftconvolve(out[..., k], h[i], mode="same") for k in range(n)] for i in range(3)])
        for uy in range(th):
            for ux in range(tw):
                sel = g[:, :, uy::th, ux::tw].reshape(3 * n, -1)
                S[uy * tw + ux, c] += (sel @ sel.T).reshape(3, n, 3, n).transpose(0, 2, 1, 3)
    S[np.abs(S) < 1e-15 * np.abs(S).max()] = 0.0    # the FFT's rounding where no channel mixes another
    _SCIELAB_MOSAIC_CACHE[key] = S
    return S


def _require_linear(layout: MosaicLayout, method: str) -> None:
    """Refuse a demosaicker that is not linear (the factors are read by impulses)."""
    from spectracam.processing.color import demosaic

    th, tw = layout.tile_shape
    reps = max(8, -(-24 // min(th, tw)))
    rng = np.random.default_rng(0)
    a, b = rng.random((th * reps, tw * reps)), rng.random((th * reps, tw * reps))
    if not np.allclose(demosaic(2 * a - 3 * b, layout, method), 2 * demosaic(a, layout, method)
                       - 3 * demosaic(b, layout, method), atol=1e-9):
        raise SpectracamError(f"design: processing.demosaic = {method!r} is not linear; the expected-error model "
                              "needs a linear demosaicker (bilinear, patch or malvar2004)")


def capture_rule(architecture: Architecture) -> str:
    """``first`` (one exposure), ``max`` (sensors exposed together) or ``sum`` (frames in sequence).

    Parameters
    ----------
    architecture : Architecture
        Probed with distinct exposure times through its ``capture_time_s``.

    Returns
    -------
    str
        ``"first"``, ``"max"`` or ``"sum"``.

    Raises
    ------
    SpectracamError
        When its capture time is none of these.
    """
    probe = np.array([1.0, 2.0, 4.0, 8.0][:len(architecture.channels)])
    got = architecture.capture_time_s(probe)
    for name, want in (("first", probe[0]), ("max", probe.max()), ("sum", probe.sum())):
        if abs(got - want) < 1e-12:
            return name
    raise SpectracamError(f"design: architecture {architecture.name!r} has a capture time the model does not know")


@dataclass(frozen=True, eq=False)
class CameraModel:
    """Everything about the camera except its responsivities: sensor, layout, exposure scheme, processing."""

    sensor: SensorModel
    channels: tuple
    exposure: str               # single | optimal | balanced | split
    capture: str                # first | max | sum
    mosaic_factors: np.ndarray | None   # demosaic_factors, or None for full planes
    shared_pattern: bool        # planes sharing one fixed pattern (one sensor)
    display_matrix: np.ndarray  # display RGB → XYZ
    snr_combination: str
    points: np.ndarray = field(default_factory=normal_points)
    #: S-CIELAB's viewing geometry, image samples per degree of visual angle (:func:`viewing_samples_per_degree`).
    samples_per_degree: float | None = None
    #: The filtered-noise factors: ``S[u, c, i, j, k, l]`` (:func:`scielab_mosaic_factors`) for a mosaic, ``ρ[i, j]``
    #: (:func:`scielab_white_factors`) for full planes; ``None``: the expected S-CIELAB is not modelled.
    scielab_factors: np.ndarray | None = None

    @classmethod
    def of(cls, camera: CameraSpec, processing: ProcessingSpec, exposure: str | None = None,
           samples_per_degree: float | None = None) -> "CameraModel":
        """The model of ``camera`` developed by ``processing``; ``samples_per_degree`` (S-CIELAB's viewing geometry)
        defaults to the processing's viewing distance and display pixel pitch.

        Parameters
        ----------
        camera : CameraSpec
        processing : ProcessingSpec
            Must score ΔE*ab (``cie1976``) without the gamut clip; a mosaic needs a linear demosaicker.
        exposure : str or None
            The exposure scheme; None: the camera's.
        samples_per_degree : float or None
            S-CIELAB's viewing geometry; None: the processing's.

        Returns
        -------
        CameraModel
            With the demosaicking and S-CIELAB factors computed.

        Raises
        ------
        SpectracamError
            On another ΔE formula, the gamut clip, a non-linear demosaicker, or an unmodelled capture or read-out.
        """
        from spectracam.processing.color import display_rgb_to_xyz

        if processing.delta_e != "cie1976":
            raise SpectracamError(f"design: processing.delta_e = {processing.delta_e!r}: the expected-error model "
                                  "scores ΔE*ab ('cie1976'), the paper's")
        if processing.gamut_clip:
            raise SpectracamError("design: processing.gamut_clip = true: the expected-error model scores the linear "
                                  "conversion (the paper's); switch the clip off")
        arch = camera.architecture()
        layout = arch.layout
        spd = viewing_samples_per_degree(processing) if samples_per_degree is None else float(samples_per_degree)
        if isinstance(layout, MosaicLayout):
            factors, shared = demosaic_factors(layout, processing.demosaic), False
            scielab = scielab_mosaic_factors(layout, processing.demosaic, spd)
        else:
            factors = None
            shared = arch.fixed_pattern == "shared" or (arch.fixed_pattern == "physical" and arch.sensors == 1)
            scielab = scielab_white_factors(spd)
        return cls(SensorModel.of(camera), tuple(arch.channels), exposure or camera.capture.exposure,
                   capture_rule(arch), factors, shared, display_rgb_to_xyz(processing.display),
                   processing.snr_combination, samples_per_degree=spd, scielab_factors=scielab)

    @property
    def sites(self) -> int:
        return 1 if self.mosaic_factors is None else self.mosaic_factors.shape[0]


@dataclass(frozen=True, eq=False)
class ColourSet:
    """Colours under one light: ``weights[s, b]`` = band radiance × the optics' photon factor × band width ×
    pixel area (rates are ``weights @ R``), and their true CIELAB against the light's white."""

    name: str
    weights: np.ndarray   # (S, B)
    lab: np.ndarray       # (S, 3)


@dataclass(frozen=True, eq=False)
class LightModel:
    """One light: the chart the conversion is fitted on and metered with, and the sets scored."""

    label: str
    chart_weights: np.ndarray   # (24, B)
    target_rgb: np.ndarray      # (24, 3)
    white_weights: np.ndarray   # (B,) the metering patch
    sets: dict                  # name → ColourSet


def _rates(weights: np.ndarray, R) -> list:
    """Per channel ``(S,)`` tensors Σ_b w_sb·R_kb."""
    dr, _ = backend()
    W = tensor(weights)
    return [dr.sum(W * r[None, :], axis=1) for r in R]


def _fold(op, values):
    """``op`` (``dr.minimum``, ``dr.maximum``) over a list of tensors."""
    out = values[0]
    for v in values[1:]:
        out = op(out, v)
    return out


def exposure_times(white_rates: list, cam: CameraModel, split: Sequence[Any] | None = None) -> list:
    """Per-channel exposure times, s (:func:`spectracam.sensor.exposure.exposure_times_s` in tensors); ``split``
    (scheme ``split``): each channel's share of the single exposure's time budget, capped at its saturation.

    Parameters
    ----------
    white_rates : list
        Per channel, the white patch's rate, e⁻/s (tensors).
    cam : CameraModel
        Its exposure scheme (paper 4.5), capture rule and sensor (well, white fill, dark rate).
    split : sequence or None
        The shares, one per channel (scheme ``split`` only).

    Returns
    -------
    list
        Per channel, the exposure time, s (tensors).

    Raises
    ------
    SpectracamError
        For a scheme the model does not know.
    """
    dr, _ = backend()
    s = cam.sensor
    sat = [s.white_fill * s.q_max_e / (w + s.dark_rate_e_per_s) for w in white_rates]
    if cam.exposure == "single":
        t = _fold(dr.minimum, sat)
        return [t] * len(sat)
    if cam.exposure == "optimal":
        return sat
    if cam.exposure == "balanced":
        total = {"first": sat[0], "max": _fold(dr.maximum, sat), "sum": sum(sat[1:], sat[0])}[cam.capture]
        return [x * (_fold(dr.minimum, sat) / total) for x in sat]
    if cam.exposure == "split":
        budget = _fold(dr.minimum, sat)
        return [dr.minimum(budget * f, x) for f, x in zip(split, sat)]
    raise SpectracamError(f"design: exposure {cam.exposure!r} is not modelled")


def conversion(chart_rates: list, target_rgb: np.ndarray) -> list:
    """The N×3 least-squares conversion (paper 3.5) from the chart's noise-free rates, as ``M[k][c]`` tensors.
    Three channels: the normal equations (the same solution as :func:`spectracam.processing.color.fit_conversion`); more
    channels: scaled to unit norm with a ridge of (10⁻⁴·largest singular value)² standing in for that fit's
    singular-value cut-off.

    Parameters
    ----------
    chart_rates : list
        Per channel, the 24 patches' noise-free rates, e⁻/s (``(24,)`` tensors).
    target_rgb : ndarray
        ``(24, 3)`` the patches' display RGB to reach.

    Returns
    -------
    list of list
        ``M[k][c]``, N×3 scalar tensors: channel k's rate to display channel c.
    """
    dr, _ = backend()
    n = len(chart_rates)
    scale = [dr.sqrt(dr.sum(r * r)) for r in chart_rates] if n > 3 else [1.0] * n
    A = [r / fresh(sc) for r, sc in zip(chart_rates, scale)]
    G = [[dr.sum(A[i] * A[j]) for j in range(n)] for i in range(n)]
    if n > 3:
        from spectracam.processing.color import CONVERSION_RCOND

        ridge = (CONVERSION_RCOND**2) * sum(G[i][i] for i in range(n))
        G = [[G[i][j] + (ridge if i == j else 0.0) for j in range(n)] for i in range(n)]
    Y = [tensor(target_rgb[:, c]) for c in range(3)]
    cols = solve_spd(G, [[dr.sum(A[i] * Y[c]) for i in range(n)] for c in range(3)])
    return [[cols[c][k] / scale[k] for c in range(3)] for k in range(n)]


def pixel_moments(rates: list, times: list, cam: CameraModel) -> tuple[list, list, list]:
    """``(p, var, dark)``: per channel, the mean photo-electrons, the variance of one pixel after the dark-frame
    subtraction and the dark charge (see the module).

    Parameters
    ----------
    rates : list
        Per channel, the colours' rates, e⁻/s (``(S,)`` tensors).
    times : list
        Per channel, the exposure time, s.
    cam : CameraModel
        Its sensor's noise sources (paper 3.4).

    Returns
    -------
    tuple of (list, list, list)
        Per channel: ``p`` (e⁻), ``var`` (e⁻²) and ``dark`` (e⁻).
    """
    s = cam.sensor
    p, var, dark = [], [], []
    for r, t in zip(rates, times):
        pk = r * fresh(t)
        dk = s.dark_rate_e_per_s * t
        v = s.read_var_e2 + s.fpn_var_e2 + s.quant_var_e2 + pk * 0.0
        if s.shot:
            v = v + pk + fresh(dk)
        if s.prnu:
            v = v + (s.prnu * pk) ** 2
        if s.dsnu:
            v = v + fresh((s.dsnu * dk) ** 2)
        p.append(pk)
        var.append(v)
        dark.append(dk)
    return p, var, dark


def channel_covariances(p: list, var: list, dark: list, cam: CameraModel) -> list:
    """Per site of the tile, the N×N covariance (electrons²) of the channels one output pixel holds.

    Parameters
    ----------
    p, var, dark : list
        :func:`pixel_moments`' per-channel mean (e⁻), variance (e⁻²) and dark charge (e⁻).
    cam : CameraModel
        Its demosaicking factors (a mosaic), or whether full planes share one fixed pattern.

    Returns
    -------
    list
        One N×N nested list per tile site (one for full planes); an entry is a tensor or ``0.0``.
    """
    n = len(var)
    s = cam.sensor
    if cam.mosaic_factors is None:
        C = [[var[k] if k == j else 0.0 for j in range(n)] for k in range(n)]
        if cam.shared_pattern:   # one sensor: the same offset, gain and dark factor in every frame
            for k in range(n):
                for j in range(n):
                    if k != j:
                        C[k][j] = (s.prnu**2) * p[k] * p[j] + fresh(s.fpn_var_e2 + (s.dsnu**2) * dark[k] * dark[j])
        return [C]
    out = []
    for F in cam.mosaic_factors:
        C = [[0.0] * n for _ in range(n)]
        for c in range(n):
            for k in range(n):
                for j in range(n):
                    if F[c, k, j] != 0.0:
                        C[k][j] = C[k][j] + var[c] * float(F[c, k, j])
        out.append(C)
    return out


def expected_delta_e(mean_rgb: list, cov_rgb: list, lab_true: np.ndarray, cam: CameraModel) -> Any:
    """``(S,)`` E‖Lab(x) − Lab_true‖ for x ~ N(mean, cov) in display RGB, by the fixed quadrature.

    Parameters
    ----------
    mean_rgb : list
        Per display channel, the ``(S,)`` mean.
    cov_rgb : list
        3×3 nested lists of ``(S,)`` tensors, symmetric positive definite.
    lab_true : ndarray
        ``(S, 3)`` the colours' true CIELAB.
    cam : CameraModel
        Its quadrature points and display matrix (display RGB → XYZ; its white is the display's).

    Returns
    -------
    TensorXf64
        ``(S,)`` expected ΔE*ab.
    """
    dr, _ = backend()
    L = cholesky3(cov_rgb)
    z = [tensor(cam.points[:, d])[None, :] for d in range(3)]
    x = []
    for c in range(3):
        v = mean_rgb[c][:, None] + L[c][0][:, None] * z[0]
        for d in range(1, c + 1):
            v = v + L[c][d][:, None] * z[d]
        x.append(v)
    Md = [[float(v) for v in row] for row in cam.display_matrix]
    X, Y, Z = (Md[i][0] * x[0] + Md[i][1] * x[1] + Md[i][2] * x[2] for i in range(3))
    lab = xyz_to_lab(X, Y, Z, cam.display_matrix.sum(axis=1))
    d2 = sum((lab[i] - tensor(lab_true[:, i])[:, None]) ** 2 for i in range(3))
    return dr.mean(dr.sqrt(d2 + 1e-12), axis=1)


@dataclass(frozen=True, eq=False)
class WhiteModel:
    """A camera that must find its own white (issue 33), for the design: training Mondrians of the training colours
    under the light, each a weighted set of its colours (``weights (K, S)``), the estimator's Minkowski order ``p``
    (1: grey world; 6: shades of grey), and the light's perfect white diffuser (``white_weights (B,)``)."""

    weights: np.ndarray
    p: float
    white_weights: np.ndarray


def white_balance_penalty(R: list, rates: list, M: list, lab_true: np.ndarray, wm: WhiteModel,
                          cam: CameraModel) -> Any:
    """``(K,)`` the extra noise-free ΔE*ab of the colours (``rates`` per channel, ``(S,)``) when the camera balances
    by the neutral its estimator finds in each training Mondrian instead of the true one: the estimate
    ``ê_jk = (Σ_s W_js ρ_sk^p / Σ_s W_js)^(1/p)``, the gains ``e/ê_j`` scaled so the white keeps its luminance, the
    colours through ``diag(g_j)·M`` against their truth, minus the same through ``M``.  Differentiable in ``R``.

    Parameters
    ----------
    R : list
        Per channel, the ``(B,)`` responsivity, e⁻/photon.
    rates : list
        Per channel, the colours' ``(S,)`` rates, e⁻/s.
    M : list
        The conversion, ``M[k][c]`` (:func:`conversion`).
    lab_true : ndarray
        ``(S, 3)`` the colours' true CIELAB.
    wm : WhiteModel
    cam : CameraModel
        Its display matrix.

    Returns
    -------
    TensorXf64
        ``(K,)`` per training Mondrian, the mean ΔE*ab with the estimated white minus that with the true one.
    """
    dr, _ = backend()
    n = len(R)
    e = [dr.sum(tensor(wm.white_weights) * r) for r in R]                    # the true neutral, e⁻/s
    W = tensor(wm.weights)                                                   # (K, S)
    wsum = tensor(wm.weights.sum(axis=1))
    est = []
    for k in range(n):
        x = rates[k] / fresh(e[k])                                            # ≈ reflectance scale: no overflow
        est.append(dr.power(dr.sum(W * dr.power(x, wm.p)[None, :], axis=1) / wsum, 1.0 / wm.p) * fresh(e[k]))
    Md = [[float(v) for v in row] for row in cam.display_matrix]
    white = cam.display_matrix.sum(axis=1)
    y_disp = [sum(fresh(M[k][c]) * Md[1][c] for c in range(3)) for k in range(n)]   # luminance per unit of channel k
    y_true = sum(e[k] * y_disp[k] for k in range(n))
    g = [fresh(e[k]) / est[k] for k in range(n)]                              # (K,) per channel
    y_est = sum(g[k] * fresh(e[k] * y_disp[k]) for k in range(n))
    g = [gk * fresh(y_true) / y_est for gk in g]

    def lab_of(gains):
        rgb = [sum(rates[k][None, :] * (gains[k][:, None] if gains else 1.0) * fresh(M[k][c]) for k in range(n))
               for c in range(3)]
        X, Y, Z = (Md[i][0] * rgb[0] + Md[i][1] * rgb[1] + Md[i][2] * rgb[2] for i in range(3))
        return xyz_to_lab(X, Y, Z, white)

    def delta_e(lab):
        return dr.sqrt(sum((lab[i] - tensor(lab_true[:, i])[None, :]) ** 2 for i in range(3)) + 1e-12)

    return dr.mean(delta_e(lab_of(g)), axis=1) - dr.mean(delta_e(lab_of(None)), axis=1)


def scielab_covariances(M: list, times: list, var: list, C_planes: list, cam: CameraModel) -> list:
    """Per output site of the tile, the 3×3 display-RGB covariance (as lists of ``(S,)`` tensors) of the noise after
    the demosaicker and S-CIELAB's filters (docs/metrics.md, "Expected S-CIELAB in the design model").

    With ``P = O·M_disp`` (display RGB → opponent: :data:`~spectracam.evaluation.scielab.XYZ_TO_OPPONENT` after the
    display's RGB → XYZ) and ``A_ik = Σ_d P_id·M_kd / t_k`` (camera channel k's electrons → opponent i), opponent
    channel i filtered by ``h_i``:

    * mosaic: ``Cov_f[i, j] = Σ_c σ_c² Σ_kl A_ik·A_jl·S[u, c, i, j, k, l]`` (:func:`scielab_mosaic_factors`; for a
      demosaicker that keeps channels apart, k = l = c: ``Σ_c A_ic·A_jc·σ_c²·ρ_c(i, j)``);
    * full planes (spatially white): ``Cov_f[i, j] = ρ[i, j]·Σ_kl A_ik·A_jl·C[k, l]`` with ``ρ = Σ_x h_i·h_j``
      (:func:`scielab_white_factors`) and ``C`` the planes' channel covariance (the shared fixed pattern included);

    then back to display RGB: ``P⁻¹·Cov_f·P⁻ᵀ``.  ``var``: per channel the ``(S,)`` pixel variance (e⁻²);
    ``C_planes``: :func:`channel_covariances` of full planes (ignored for a mosaic).

    Parameters
    ----------
    M : list
        The conversion, ``M[k][c]``.
    times : list
        Per channel, the exposure time, s.
    var : list
        Per channel, the ``(S,)`` pixel variance, e⁻².
    C_planes : list
        :func:`channel_covariances` of full planes.
    cam : CameraModel
        Its display matrix and S-CIELAB factors.

    Returns
    -------
    list
        One 3×3 nested list of ``(S,)`` tensors per tile site (one for full planes).
    """
    from spectracam.evaluation.scielab import XYZ_TO_OPPONENT

    P = XYZ_TO_OPPONENT @ cam.display_matrix
    Pi = np.linalg.inv(P)
    A = _camera_to_opponent(M, times, P)
    if cam.mosaic_factors is None:
        return [_opponent_to_rgb(_planes_opponent_covariance(A, cam.scielab_factors, C_planes[0]), Pi)]
    return [_opponent_to_rgb(_mosaic_opponent_covariance(A, S, var), Pi) for S in cam.scielab_factors]


#: The (i, j) of the lower triangle (j ≤ i) of a 3×3 opponent covariance, the entries computed.
_LOWER_3X3 = tuple((i, j) for i in range(3) for j in range(i + 1))


def _camera_to_opponent(M: list, times: list, P: np.ndarray) -> list:
    """``A[i][k] = Σ_d P_id·M_kd / t_k``: camera channel k's electrons to opponent channel i (docs/metrics.md)."""
    return [[fresh(sum((float(P[i, d]) * M[k][d] for d in range(1, 3)), float(P[i, 0]) * M[k][0]) / times[k])
             for k in range(len(M))] for i in range(3)]


def _planes_opponent_covariance(A: list, rho: np.ndarray, C: list) -> list:
    """Full planes (spatially white): ``Cov_f[i, j] = ρ[i, j]·Σ_kl A_ik·A_jl·C[k, l]``, lower triangle."""
    n = len(A[0])
    Cf = [[None] * 3 for _ in range(3)]
    for i, j in _LOWER_3X3:
        acc = 0.0
        for k in range(n):
            for l in range(n):
                if isinstance(C[k][l], float) and C[k][l] == 0.0:
                    continue
                acc = acc + fresh(A[i][k] * A[j][l] * float(rho[i, j])) * C[k][l]
        Cf[i][j] = acc
    return Cf


def _mosaic_opponent_covariance(A: list, S: np.ndarray, var: list) -> list:
    """A mosaic's output site: ``Cov_f[i, j] = Σ_c σ_c² Σ_kl A_ik·A_jl·S[c, i, j, k, l]``, lower triangle."""
    n = len(A[0])
    Cf = [[None] * 3 for _ in range(3)]
    for i, j in _LOWER_3X3:
        acc = 0.0
        for c in range(n):
            coef = 0.0
            for k in range(n):
                for l in range(n):
                    if S[c, i, j, k, l] != 0.0:
                        coef = coef + A[i][k] * A[j][l] * float(S[c, i, j, k, l])
            if not isinstance(coef, float):
                acc = acc + fresh(coef) * var[c]
        Cf[i][j] = acc
    return Cf


def _opponent_to_rgb(Cf: list, Pi: np.ndarray) -> list:
    """Back to display RGB: ``P⁻¹·Cov_f·P⁻ᵀ`` from the lower triangle of ``Cov_f`` (1e-14 added on the diagonal)."""
    cov = [[0.0] * 3 for _ in range(3)]
    for a in range(3):
        for b in range(a + 1):
            acc = 0.0
            for i in range(3):
                for j in range(3):
                    w = float(Pi[a, i] * Pi[b, j])
                    if w != 0.0:
                        acc = acc + w * Cf[max(i, j)][min(i, j)]
            cov[a][b] = cov[b][a] = acc + (1e-14 if a == b else 0.0)
    return cov


@dataclass
class LightResult:
    """The model's answer for one light: tensors (differentiable) per colour set."""

    times_s: list
    conversion: list
    delta_e: dict       # set → (S,) expected ΔE*ab
    snr_db: dict        # set → (S,) combined SNR
    channel_snr_db: dict
    clipped: dict       # set → number of colours whose mean + 3σ passes the well
    #: set → (K,) the extra ΔE*ab of an estimated white per training Mondrian (:func:`white_balance_penalty`)
    white_penalty: dict = field(default_factory=dict)
    #: set → (S,) expected S-CIELAB ΔE*ab on a flat patch of each colour (:func:`scielab_covariances`)
    s_cielab: dict = field(default_factory=dict)


#: The expectations :func:`evaluate` can compute: the per-pixel ΔE*ab and the S-CIELAB ΔE*ab.
SCORES = ("delta_e", "s_cielab")


def evaluate(R: list, light: LightModel, cam: CameraModel, split: Sequence[Any] | None = None,
             sets: Sequence[str] | None = None, estimated: Mapping[str, WhiteModel] | None = None,
             scores: Sequence[str] = ("delta_e",)) -> LightResult:
    """The expected-error model for responsivities ``R`` (N tensors of shape (B,), electrons per photon); with
    ``estimated`` (set name → :class:`WhiteModel`), the estimated white's penalty for those sets too; ``scores``:
    which of :data:`SCORES` to compute (each is a quadrature per tile site).

    Parameters
    ----------
    R : list
        Per channel, the responsivity over the bands, e⁻ per photon (tensors of shape (B,)).
    light : LightModel
        The chart the conversion is fitted on and metered with, and the colour sets scored.
    cam : CameraModel
        Sensor, layout, exposure scheme and processing.
    split : sequence or None
        Each channel's share of the exposure budget (scheme ``split`` only; :func:`exposure_times`).
    sets : sequence of str or None
        The colour sets scored (None: every set of ``light``).
    estimated : mapping of str to WhiteModel, or None
        Set name → the estimated white whose penalty is computed for that set.
    scores : sequence of str
        Which of :data:`SCORES`.

    Returns
    -------
    LightResult
        Exposure times, s, the conversion and, per set, the expected ΔE*ab (and S-CIELAB), the SNR, dB, the
        colours that clip and the white's penalty (tensors: differentiable).

    Raises
    ------
    SpectracamError
        On unknown or no scores, or S-CIELAB without the camera model's S-CIELAB factors.
    """
    _check_scores(scores, cam)
    dr, _ = backend()
    chart = _rates(light.chart_weights, R)
    M = conversion(chart, light.target_rgb)
    white = [dr.sum(tensor(light.white_weights) * r) for r in R]
    times = exposure_times(white, cam, split)
    n = len(R)
    res = LightResult(times, M, {}, {}, {}, {})
    for name in sets or light.sets:
        cs = light.sets[name]
        rates = _rates(cs.weights, R)
        p, var, dark = pixel_moments(rates, times, cam)
        mean_rgb = [sum((rates[k] * fresh(M[k][c]) for k in range(1, n)), rates[0] * fresh(M[0][c])) for c in range(3)]
        covs = channel_covariances(p, var, dark, cam)
        if "s_cielab" in scores:
            sc = [expected_delta_e(mean_rgb, cov, cs.lab, cam) for cov in scielab_covariances(M, times, var, covs, cam)]
            res.s_cielab[name] = sum(sc[1:], sc[0]) / len(sc)
        des = [_expected_delta_e(C, M, times, n, mean_rgb, cs.lab, cam) for C in (covs if "delta_e" in scores else ())]
        if des:
            res.delta_e[name] = sum(des[1:], des[0]) / len(des)
        if estimated and name in estimated:
            res.white_penalty[name] = white_balance_penalty(R, rates, M, cs.lab, estimated[name], cam)
        _snr_and_clipping(res, name, p, var, dark, cam)
    return res


def _check_scores(scores: Sequence[str], cam: CameraModel) -> None:
    """Refuse :func:`evaluate`'s ``scores`` unless a non-empty subset of :data:`SCORES` the camera model can give."""
    if not set(scores) <= set(SCORES) or not scores:
        raise SpectracamError(f"design: scores = {scores!r}: a non-empty subset of {', '.join(SCORES)}")
    if "s_cielab" in scores and cam.scielab_factors is None:
        raise SpectracamError("design: this camera model has no S-CIELAB factors (CameraModel.of computes them)")


def _expected_delta_e(C: list, M: list, times: list, n: int, mean_rgb: list, lab: np.ndarray,
                      cam: CameraModel) -> Any:
    """:func:`evaluate`'s expected ΔE*ab of one channel covariance ``C`` (N × N), through the conversion ``M`` and
    the exposure times to display RGB."""
    cov = [[0.0] * 3 for _ in range(3)]
    for c in range(3):
        for d in range(c + 1):
            acc = 0.0
            for k in range(n):
                for j in range(n):
                    if isinstance(C[k][j], float) and C[k][j] == 0.0:
                        continue
                    acc = acc + fresh(M[k][c] * M[j][d] / (times[k] * times[j])) * C[k][j]
            cov[c][d] = cov[d][c] = acc + (1e-14 if c == d else 0.0)
    return expected_delta_e(mean_rgb, cov, lab, cam)


def _snr_and_clipping(res: LightResult, name: str, p: list, var: list, dark: list, cam: CameraModel) -> None:
    """:func:`evaluate`'s per-channel and combined SNR, dB, and the colours whose mean + 3σ passes the well, of
    set ``name`` into ``res``."""
    dr, _ = backend()
    n = len(p)
    ln10 = float(np.log(10.0))
    ch = [10.0 * dr.log(pk * pk / v) / ln10 for pk, v in zip(p, var)]
    res.channel_snr_db[name] = ch
    if cam.snr_combination == "power":
        res.snr_db[name] = 10.0 * dr.log(sum(pk * pk for pk in p) / sum(var)) / ln10
    else:
        res.snr_db[name] = sum(ch) / n
    over = None
    for pk, v, dk in zip(p, var, dark):
        hit = (pk + fresh(dk) + 3.0 * dr.sqrt(v)) > cam.sensor.q_max_e
        over = hit if over is None else (over | hit)
    res.clipped[name] = int(np.count_nonzero(over.numpy()))
