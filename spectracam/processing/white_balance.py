"""White balance as a camera finds it: the light's neutral estimated from the image (``processing.white_balance``).

An estimator sees the demosaicked, exposure-normalised camera image ``ρ(x) (H, W, N)`` (photo-electrons per second
per channel; :func:`spectracam.evaluation.score.camera_rates`) and the mask of pixels it may use (finite and not clipped), and
returns the **neutral** ``ê (N,)``: its estimate of the camera's response to a perfect white diffuser under the
scene's light, up to scale.  The truth ``e`` is that response computed from the light (the ``oracle``).

``oracle``          ``e`` itself (the paper's reading: the camera knows the light).
``grey_world``      ``ê_k = mean_x ρ_k(x)`` (Buchsbaum 1980: the scene averages to grey).
``white_patch``     ``ê_k`` = the :data:`WHITE_PATCH_PERCENTILE` th percentile of ``ρ_k`` (max-RGB, Land 1977; a
                    percentile instead of the maximum so that a few hot pixels do not decide it).
``shades_of_grey``  ``ê_k = (mean_x ρ_k^p)^(1/p)``, ``p = processing.white_balance_p`` (Finlayson & Trezzi, CIC
                    2004; p = 1 is grey world, p → ∞ max-RGB).
``grey_edge``       ``ê_k = (mean_x |∇(G_σ * ρ_k)|^p)^(1/p)``: first-order grey edge (van de Weijer, Gevers &
                    Gijsenij, IEEE TIP 16(9) 2007) with a Gaussian of σ = ``processing.white_balance_sigma_px``.
``corrected_moments`` a trained estimator (Finlayson, "Corrected-moment illuminant estimation", ICCV 2013): the
                    moments ``f = [SoG_1, SoG_2, SoG_4, SoG_8, max, GE_1, GE_2, GE_6]`` of the pixels and of their
                    edges (each ``(N,)`` and scaled to unit norm) map to the neutral by one linear correction
                    ``ê = f·C`` fitted by least squares on training Mondrians made of a reflectance library
                    (``processing.white_balance_training``) under :data:`TRAINING_LIGHTS`; a training sample that
                    matches any colour of the scored scene (spectral rms < :data:`EXCLUDE_RMS`) is removed, so the
                    estimator is never trained on what it is scored on.  A training scene's radiance is its band
                    reflectance times the light's band radiance (the product of band averages: for rawtoaces' 190
                    at 10-nm bands within 1.2 % of the average of the product in every band under the smooth
                    training lights — 2500 K: 1.2 %, CIE A: 0.9 % — though 12 % under FL11's lines; a prior, not a
                    rendering).

Errors (degrees), both against the true neutral ``e``:

* **recovery** ``arccos(ê·e / |ê||e|)`` (Hordley & Finlayson, JOSA A 23(5) 2006);
* **reproduction** the angle between ``e/ê`` (the white as the estimate leaves it) and the achromatic ``(1, …, 1)``
  (Finlayson & Zakizadeh, BMVC 2014): what the picture shows.
"""
from __future__ import annotations

from dataclasses import dataclass
from collections.abc import Iterable
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.processing.registries import WHITE_BALANCE_METHODS  # noqa: F401  (the estimators register into it)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from spectracam.camera import CameraSpec
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.scene.illuminant import IlluminantSpec
    from spectracam.scene.reflectances import ReflectanceSet
    from spectracam.sensor import SensorSpec

__all__ = ["CLIP_SHARE", "EDGE_ORDERS", "EXCLUDE_RMS", "MOMENT_ORDERS", "TRAINING_EDGES_PER_SURFACE",
           "TRAINING_LIGHTS", "TRAINING_RIDGE", "TRAINING_SCENES_PER_LIGHT", "TRAINING_SEED", "TRAINING_SURFACES",
           "WHITE_BALANCE_METHODS", "WHITE_PATCH_PERCENTILE", "Estimation", "TrainedCorrection", "band_reflectance",
           "edge_magnitudes", "estimate_neutral", "exclusion_key", "minkowski_mean", "moment_features",
           "recovery_error_deg", "reproduction_error_deg", "trained_correction", "training_camera", "training_lights",
           "usable_pixels"]

#: ``white_patch``: the percentile of each channel taken as the white.  Max-RGB would take 100; 99.9 ignores up to
#: 1 pixel in 1000 (hot pixels, a specular glint) while the chart's white patch covers ≈ 3 % of its image.
WHITE_PATCH_PERCENTILE = 99.9
#: A pixel whose recorded charge reaches this share of the full well in any channel is clipped: no estimator uses
#: it (its ratio of channels is the well's, not the light's).
CLIP_SHARE = 0.98
#: Moments of the trained estimator: of the pixels (Finlayson 2013 uses moments up to order 8 and the maximum) and of
#: the edges (his edge-based corrected moments; the grey-edge family of van de Weijer et al. 2007).
MOMENT_ORDERS = (1.0, 2.0, 4.0, 8.0)
EDGE_ORDERS = (1.0, 2.0, 6.0)
#: Borders per surface in a training Mondrian (a surface of a tiling meets about four others).
TRAINING_EDGES_PER_SURFACE = 2

#: The trained estimator's lights: the Planckian locus 2500–9000 K every 500 K and CIE daylights D50–D75, the prior a
#: camera maker trains on.  No fluorescent or LED light is in it, so those are held-out lights for the estimator.
TRAINING_LIGHTS = (tuple(("blackbody", float(t)) for t in range(2500, 9001, 500))
                   + tuple(("cie", n) for n in ("D50", "D55", "D65", "D75")))
#: Training scenes per light, and the surfaces in each (a uniform number in this range, areas Dirichlet(1)): a natural
#: image holds many surfaces (20–60 was chosen over 8–32 after seeing the chart: 4.2° against 5.3° recovery error).
TRAINING_SCENES_PER_LIGHT = 60
TRAINING_SURFACES = (20, 60)
#: The trained estimator's draws are its own, fixed: it is the camera's firmware, not part of the experiment's
#: random draws (the report records it).
TRAINING_SEED = 1999
#: A training reflectance within this rms (reflectance units, over the scene's bands) of a scored colour is dropped.
EXCLUDE_RMS = 0.01
#: Ridge regularisation of the correction (relative to the mean diagonal of FᵀF).
TRAINING_RIDGE = 1e-6


@dataclass(frozen=True, eq=False)
class Estimation:
    """What an estimator is given: the image and its usable pixels, and what the trained one needs."""

    image: np.ndarray            # (H, W, N) camera rates, e⁻/s
    valid: np.ndarray            # (H, W) bool
    processing: object           # ProcessingSpec
    camera: object = None        # CameraSpec (the trained estimator is trained for this sensor)
    grid: object = None          # WavelengthGrid
    true_neutral: np.ndarray | None = None   # the oracle's (no other estimator reads it)
    scored_reflectances: tuple = ()          # (n, B) arrays of the scored scene's colours, band-averaged

    def pixels(self) -> np.ndarray:
        """``(n, N)`` the usable pixels, negatives (read noise below the dark level) set to 0."""
        px = self.image[self.valid]
        if px.shape[0] == 0:
            raise SpectracamError("white balance: no usable pixel (every pixel is clipped or not finite); lower the "
                                  "exposure (capture.metering) or the light level")
        return np.maximum(px, 0.0)


def usable_pixels(image: np.ndarray, exposure_times_s: ArrayLike, sensor: SensorSpec) -> np.ndarray:
    """``(H, W)`` bool: finite in every channel and below :data:`CLIP_SHARE` of the full well in every channel.

    Parameters
    ----------
    image : ndarray
        ``(H, W, N)`` camera rates, e⁻/s.
    exposure_times_s : array_like
        ``(N,)`` the channels' exposure times, s.
    sensor : SensorSpec
        The sensor (dark rate, e⁻/s, and full well q_max, e⁻).

    Returns
    -------
    ndarray
        ``(H, W)`` bool.
    """
    t = np.asarray(exposure_times_s, float)
    charge = image * t + sensor.dark_rate_e_per_s * t
    return np.all(np.isfinite(image), axis=-1) & np.all(charge < CLIP_SHARE * sensor.q_max_e, axis=-1)


def _unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, float)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(~np.isfinite(n)) or np.any(n <= 0):
        raise SpectracamError(f"white balance: the estimated neutral {np.round(v, 6).tolist()} has no direction "
                              "(every channel is 0): the image holds no light the estimator can use")
    return v / n


def minkowski_mean(pixels: np.ndarray, p: float) -> np.ndarray:
    """``(mean x^p)^(1/p)`` over the first axis (the shades-of-grey moment), stably for large p.

    Parameters
    ----------
    pixels : ndarray
        ``(n, N)`` values ≥ 0.
    p : float
        The order (1: the mean; large: towards the maximum).

    Returns
    -------
    ndarray
        ``(N,)``.
    """
    x = np.asarray(pixels, float)
    top = x.max(axis=0)
    top = np.where(top > 0, top, 1.0)
    y = x / top  # ≤ 1: no overflow at p = 8 on e⁻/s values of 1e6
    return top * np.mean(y ** p, axis=0) ** (1.0 / p)


@WHITE_BALANCE_METHODS.register("oracle")
def _oracle(ctx: Estimation) -> np.ndarray:
    """The true neutral (the camera is told the light)."""
    return np.asarray(ctx.true_neutral, float)


@WHITE_BALANCE_METHODS.register("grey_world")
def _grey_world(ctx: Estimation) -> np.ndarray:
    """Mean of each channel over the usable pixels."""
    return ctx.pixels().mean(axis=0)


@WHITE_BALANCE_METHODS.register("white_patch")
def _white_patch(ctx: Estimation) -> np.ndarray:
    """Each channel's :data:`WHITE_PATCH_PERCENTILE` th percentile over the usable pixels."""
    return np.percentile(ctx.pixels(), WHITE_PATCH_PERCENTILE, axis=0)


@WHITE_BALANCE_METHODS.register("shades_of_grey")
def _shades_of_grey(ctx: Estimation) -> np.ndarray:
    """Minkowski p-mean of each channel, p = ``processing.white_balance_p``."""
    return minkowski_mean(ctx.pixels(), ctx.processing.white_balance_p)


@WHITE_BALANCE_METHODS.register("grey_edge")
def _grey_edge(ctx: Estimation) -> np.ndarray:
    """Minkowski p-mean of each channel's edge magnitudes (:func:`edge_magnitudes`)."""
    return minkowski_mean(edge_magnitudes(ctx), ctx.processing.white_balance_p)


def moment_features(pixels: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """``((len(MOMENT_ORDERS) + 1 + len(EDGE_ORDERS))·N,)`` the corrected-moments features of an image: the Minkowski
    moments of its pixels ``(n, N)``, their :data:`WHITE_PATCH_PERCENTILE` th percentile (the maximum) and the
    Minkowski moments of its edge magnitudes ``(m, N)``, each moment scaled to unit norm (so an image's pixel and edge
    moments, whose scales differ from a training scene's, enter by their directions; the training computes the same
    for all its scenes at once, :func:`trained_correction`).

    Parameters
    ----------
    pixels : ndarray
        ``(n, N)`` the usable pixels, e⁻/s.
    edges : ndarray
        ``(m, N)`` their edge magnitudes (:func:`edge_magnitudes`).

    Returns
    -------
    ndarray
        The features, one unit-norm group of N after another.
    """
    x = np.maximum(np.asarray(pixels, float), 0.0)
    groups = [minkowski_mean(x, p) for p in MOMENT_ORDERS] + [np.percentile(x, WHITE_PATCH_PERCENTILE, axis=0)]
    groups += [minkowski_mean(edges, p) for p in EDGE_ORDERS]
    return np.concatenate([_unit(g) for g in groups])


def edge_magnitudes(ctx: Estimation) -> np.ndarray:
    """``(m, N)`` each channel's Gaussian-derivative gradient magnitude (σ = ``processing.white_balance_sigma_px``)
    at the pixels whose 3×3 neighbourhood is usable (an edge into a clipped pixel is the well's, not the scene's).

    Parameters
    ----------
    ctx : Estimation
        The image, its usable pixels and the processing.

    Returns
    -------
    ndarray
        ``(m, N)``, e⁻/s per pixel.

    Raises
    ------
    SpectracamError
        No usable pixel with usable neighbours.
    """
    from scipy.ndimage import binary_erosion, gaussian_gradient_magnitude

    sigma = ctx.processing.white_balance_sigma_px
    image = np.where(ctx.valid[..., None], np.maximum(ctx.image, 0.0), 0.0)
    keep = binary_erosion(ctx.valid, np.ones((3, 3), bool), border_value=1)
    grads = np.stack([gaussian_gradient_magnitude(image[..., k], sigma, mode="nearest")[keep]
                      for k in range(image.shape[-1])], axis=-1)
    if grads.shape[0] == 0:
        raise SpectracamError("white balance: no usable pixel with usable neighbours to find edges on")
    return grads


@WHITE_BALANCE_METHODS.register("corrected_moments")
def _corrected_moments(ctx: Estimation) -> np.ndarray:
    """The moments of the usable pixels through the correction trained for this camera (module docstring)."""
    model = trained_correction(training_camera(ctx.camera), ctx.grid, ctx.processing.white_balance_training,
                               exclusion_key(ctx.scored_reflectances))
    return moment_features(ctx.pixels(), edge_magnitudes(ctx)) @ model.correction


def training_camera(camera: CameraSpec) -> CameraSpec:
    """The part of a camera its responses depend on (its exposure and metering do not change a neutral's
    direction): one trained estimator serves every exposure scheme and metering of a sensor.

    Parameters
    ----------
    camera : CameraSpec
        The camera.

    Returns
    -------
    CameraSpec
        A copy whose ``capture`` keeps only the architecture, CFA pattern and fixed-pattern choice.
    """
    cap = camera.capture
    return camera.replace(capture=type(cap)(architecture=cap.architecture, cfa_pattern=cap.cfa_pattern,
                                            fixed_pattern=cap.fixed_pattern))


@dataclass(frozen=True, eq=False)
class TrainedCorrection:
    correction: np.ndarray       # (5N, N)
    library: str
    samples: int                 # training reflectances after the exclusion
    excluded: int                # dropped because they match a scored colour
    scenes: int
    training_recovery_deg: dict  # mean / median / p95 on its own training scenes (a training score)

    def to_dict(self) -> dict:
        return {"library": self.library, "samples": self.samples, "excluded_as_scored_colours": self.excluded,
                "scenes": self.scenes, "lights": [f"{k}:{v:g}" if k == "blackbody" else f"{k}:{v}"
                                                  for k, v in TRAINING_LIGHTS],
                "seed": TRAINING_SEED, "training_recovery_deg": self.training_recovery_deg}


def exclusion_key(arrays: Iterable[np.ndarray]) -> tuple:
    """A hashable key for the scored reflectances (arrays by content).

    Parameters
    ----------
    arrays : iterable of ndarray
        ``(n, B)`` band reflectances (:func:`spectracam.processing.develop.scored_reflectances`).

    Returns
    -------
    tuple
        ``(shape, float64 bytes)`` per array.
    """
    return tuple((a.shape, np.ascontiguousarray(a, np.float64).tobytes()) for a in arrays)


def training_lights() -> list[IlluminantSpec]:
    from spectracam.scene.illuminant import IlluminantSpec

    return [IlluminantSpec("blackbody", v, None, 100.0) if k == "blackbody" else IlluminantSpec("cie", None, v, 100.0)
            for k, v in TRAINING_LIGHTS]


@lru_cache(maxsize=32)
def trained_correction(camera: CameraSpec, grid: WavelengthGrid, library: str,
                       exclusion: tuple = ()) -> TrainedCorrection:
    """The corrected-moments correction for ``camera`` on ``grid``, trained on ``library`` under
    :data:`TRAINING_LIGHTS` minus the scored colours ``exclusion`` (memoised).

    Parameters
    ----------
    camera : CameraSpec
        The camera (:func:`training_camera`'s part of it).
    grid : WavelengthGrid
        The bands.
    library : str
        The reflectance library trained on (``processing.white_balance_training``).
    exclusion : tuple
        :func:`exclusion_key` of the scored scene's colours.

    Returns
    -------
    TrainedCorrection
        The ``(F, N)`` correction (F features, :func:`moment_features`) and what it was trained on.

    Raises
    ------
    SpectracamError
        Fewer than the smallest Mondrian's surfaces remain after the exclusion.
    """
    from spectracam.scene.reflectances import load

    rset = load(library, "processing.white_balance_training")
    lo, hi = float(grid.edges_nm[0]), float(grid.edges_nm[-1])
    rset.check_covers(lo, hi, "processing.white_balance_training")
    # band-averaged reflectance of every training sample (n, B)
    refl = band_reflectance(rset, grid)
    keep = np.ones(len(refl), bool)
    for shape, data in exclusion:
        scored = np.frombuffer(data, np.float64).reshape(shape)
        if scored.shape[-1] != refl.shape[1]:
            continue
        d = np.sqrt(((refl[:, None, :] - scored[None, :, :]) ** 2).mean(axis=-1))   # (n, m)
        keep &= d.min(axis=1) >= EXCLUDE_RMS
    if keep.sum() < TRAINING_SURFACES[0]:
        raise SpectracamError(f"processing.white_balance_training = {library!r}: {int(keep.sum())} of its {len(refl)} "
                              f"reflectances remain once those matching the scored scene's colours are removed; the "
                              f"trained estimator needs at least {TRAINING_SURFACES[0]}: train on another library")
    return _trained(camera, grid, library, keep.tobytes())


@lru_cache(maxsize=32)
def _trained(camera, grid, library: str, kept: bytes) -> TrainedCorrection:
    """The training itself, memoised on the samples kept (scored sets that remove the same samples share it)."""
    from spectracam.camera import photo_electron_rates
    from spectracam.scene.illuminant import white_diffuser_radiance
    from spectracam.scene.reflectances import load

    refl_all = band_reflectance(load(library, "processing.white_balance_training"), grid)
    keep = np.frombuffer(kept, bool)
    refl = refl_all[keep]
    rng = np.random.default_rng(TRAINING_SEED)
    n, S = len(refl), TRAINING_SCENES_PER_LIGHT
    feats, truth = [], []
    for light in training_lights():
        white = white_diffuser_radiance(light, grid)                                 # (B,)
        rates = photo_electron_rates((refl * white[None]).astype(np.float32), grid, camera).astype(np.float64)
        e = photo_electron_rates(white[None].astype(np.float32), grid, camera)[0].astype(np.float64)
        # the draws, scene by scene; the moments of all S scenes at once.  A scene is a Mondrian of k surfaces with
        # areas W[j] and TRAINING_EDGES_PER_SURFACE·k borders between random pairs, each as long as the two surfaces
        # are large; a border's magnitude is the difference of the two (a step seen through the image's Gaussian
        # derivative keeps its direction in camera space)
        W = np.zeros((S, n))
        scene_of, a_all, b_all, w_edge = [], [], [], []
        for j in range(S):
            k = int(rng.integers(TRAINING_SURFACES[0], min(TRAINING_SURFACES[1], n) + 1))
            pick = rng.choice(n, k, replace=False)
            w = rng.dirichlet(np.ones(k))
            W[j, pick] = w
            a, b = rng.integers(0, k, (2, TRAINING_EDGES_PER_SURFACE * k))
            a, b = a[a != b], b[a != b]
            scene_of.append(np.full(a.size, j))
            a_all.append(pick[a])
            b_all.append(pick[b])
            w_edge.append(np.sqrt(w[a] * w[b]))
        scene_of, a_all, b_all, w_edge = (np.concatenate(v) for v in (scene_of, a_all, b_all, w_edge))
        y = np.maximum(rates, 0.0) / e                     # ≤ ~1 (reflectance scale): no overflow at p = 8
        edges = np.abs(y[a_all] - y[b_all])
        edge_sum = np.bincount(scene_of, w_edge, minlength=S)
        groups = [(W @ y ** p / W.sum(axis=1)[:, None]) ** (1.0 / p) for p in MOMENT_ORDERS]
        groups.append(np.where(W[:, :, None] > 0, y[None], -np.inf).max(axis=1))
        groups += [(np.stack([np.bincount(scene_of, w_edge * edges[:, c] ** p, minlength=S)
                              for c in range(y.shape[1])], axis=-1) / edge_sum[:, None]) ** (1.0 / p)
                   for p in EDGE_ORDERS]
        feats.append(np.concatenate([_unit(g * e) for g in groups], axis=-1))   # as moment_features does
        truth.append(np.repeat(_unit(e)[None], S, axis=0))
    F, E = np.concatenate(feats), np.concatenate(truth)
    A = F.T @ F
    C = np.linalg.solve(A + TRAINING_RIDGE * np.trace(A) / len(A) * np.eye(len(A)), F.T @ E)
    errs = recovery_error_deg(F @ C, E)
    return TrainedCorrection(C, library, int(keep.sum()), int((~keep).sum()), len(F),
                             {"mean": float(errs.mean()), "median": float(np.median(errs)),
                              "p95": float(np.percentile(errs, 95))})


def band_reflectance(rset: ReflectanceSet, grid: WavelengthGrid) -> np.ndarray:
    """``(n, B)`` band-averaged reflectances of a set, vectorised over samples (20 points per band).

    Parameters
    ----------
    rset : ReflectanceSet
        The reflectances (its samples cover the grid).
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    ndarray
        ``(n, B)`` reflectance, 0–1.
    """
    from spectracam.core.spectra import band_sample_points

    lam = band_sample_points(grid, 20)                                  # (B, P + 1)
    y = rset.at(lam.ravel()).reshape(-1, *lam.shape)                     # (n, B, P + 1)
    return 0.5 * (y[..., 1:] + y[..., :-1]).mean(axis=-1)


def recovery_error_deg(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Angle in degrees between estimated and true neutrals (last axis; Hordley & Finlayson 2006).

    Parameters
    ----------
    estimate : ndarray
        ``(..., N)`` estimated neutrals, any scale.
    truth : ndarray
        ``(..., N)`` true neutrals, any scale.

    Returns
    -------
    ndarray
        ``(...)`` degrees.

    Examples
    --------
    >>> round(float(recovery_error_deg(np.array([1.0, 0.0, 0.0]), np.array([1.0, 1.0, 0.0]))), 6)
    45.0
    """
    a, b = np.asarray(estimate, float), np.asarray(truth, float)
    c = (a * b).sum(-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def reproduction_error_deg(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Angle in degrees between ``truth/estimate`` and the achromatic ``(1, …, 1)`` (Finlayson & Zakizadeh 2014).

    Parameters
    ----------
    estimate : ndarray
        ``(..., N)`` estimated neutrals, any scale.
    truth : ndarray
        ``(..., N)`` true neutrals, any scale.

    Returns
    -------
    ndarray
        ``(...)`` degrees.

    Examples
    --------
    >>> round(float(reproduction_error_deg(np.array([1.0, 1.0, 2.0]), np.array([1.0, 1.0, 1.0]))), 4)
    15.7932
    """
    r = np.asarray(truth, float) / np.asarray(estimate, float)
    return recovery_error_deg(r, np.ones_like(r))


def estimate_neutral(ctx: Estimation) -> np.ndarray:
    """The registered estimator ``ctx.processing.white_balance``'s neutral, unit norm.

    Parameters
    ----------
    ctx : Estimation
        The image, its usable pixels and the processing.

    Returns
    -------
    ndarray
        ``(N,)``, unit norm.

    Raises
    ------
    SpectracamError
        An estimate with no direction (every channel 0), or no usable pixel.
    """
    return _unit(WHITE_BALANCE_METHODS[ctx.processing.white_balance_method](ctx))
