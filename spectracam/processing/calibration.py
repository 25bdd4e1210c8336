"""Colour calibration as a camera does it (``processing.calibration``): how the white-balanced camera image becomes
XYZ, given the neutral the camera estimated.

``scene_light``      the paper's conversion (section 3.5) fitted on the chart under the scene's own light
                     (:func:`conversion_matrix`), applied after carrying the estimated neutral to the
                     true one: ``M = diag(e/ê)·M_scene``.  With the oracle's neutral it is the paper's reading.
``dual_illuminant``  the DNG model (Adobe DNG Specification 1.6, chapter 6, "Mapping Camera Color Space to CIE
                     XYZ Space"): for each calibration light i ∈ {CIE A, D65} (:data:`CALIBRATION_LIGHTS`)

                     * a **ColorMatrix** ``CM_i`` (3 × N; XYZ → camera), least squares on the chart under light i,
                       scaled so that the light's white gives a largest channel of 1;
                     * a **ForwardMatrix** ``FM_i`` (N × 3; white-balanced camera → XYZ under D50), least squares on the
                       chart under light i with the constraint that the balanced neutral ``(1, …, 1)`` maps to D50's
                       white exactly (as the specification requires of a ForwardMatrix); the chart's XYZ are carried
                       from light i's white to D50's by ``processing.adaptation``.

                     The camera then finds the white's chromaticity from its *estimated* neutral ê as the DNG SDK
                     does (``dng_color_spec::NeutralToXY``): starting at D50, repeatedly interpolate ``CM`` at the
                     correlated colour temperature of the current xy (Robertson 1968, colour-science), solve
                     ``XYZ·CM ∥ ê`` and take its xy, until xy moves less than 1e-7.  The interpolation weight is linear
                     in 1/CCT between the two calibration lights and clamped outside them:
                     ``w = (1/T − 1/T_D65)/(1/T_A − 1/T_D65)``, ``FM = w·FM_A + (1 − w)·FM_D65``.
                     Camera → display: ``ρ·diag(1/ê)·FM`` (XYZ under D50) carried to the display white by
                     ``processing.adaptation`` and through the display's inverse.

The brightness: a camera that is not told the light does not know its level either.  Every calibration but the
oracle chain shows the metered white (``raw.metered_rate_e_per_s``: the level the metering took for a perfect white
diffuser) at display luminance Y = 1.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.processing.color import CONVERSION_RCOND, adaptation_matrix, display_rgb_to_xyz, fit_conversion
from spectracam.processing.registries import CALIBRATIONS  # noqa: F401  (the calibrations register into it)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from spectracam.camera import CameraSpec
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.processing.color import ProcessingSpec
    from spectracam.scene.illuminant import IlluminantSpec
    from spectracam.scene.reference import ChartReference

__all__ = ["CALIBRATIONS", "CALIBRATION_LIGHTS", "CCT_RANGE_K", "D50_XYZ", "NEUTRAL_XY_ITERATIONS",
           "NEUTRAL_XY_TOLERANCE", "Calibration", "DualIlluminant", "constrained_lstsq", "conversion_matrix",
           "conversion_target_rgb", "dual_illuminant_matrices", "light_cct_K", "white_neutral", "xy_to_cct", "xyz_to_display_rgb",
           "xyz_to_xy"]

#: The DNG's two calibration lights (EXIF LightSource 17 = Standard light A, 21 = D65), as spectracam names them.
CALIBRATION_LIGHTS = ("A", "D65")
#: The DNG profile connection space's white, D50 at xy (0.3457, 0.3585) (the DNG SDK's), Y = 1: ForwardMatrices map
#: the balanced neutral onto it, and the SDK normalises every ColorMatrix on it (``NormalizeColorMatrix``).
D50_XYZ = np.array([0.3457 / 0.3585, 1.0, (1 - 0.3457 - 0.3585) / 0.3585])
#: Iterations of the neutral → xy search, and its tolerance in xy.
NEUTRAL_XY_ITERATIONS = 30
NEUTRAL_XY_TOLERANCE = 1e-7


@dataclass(frozen=True, eq=False)
class Calibration:
    """What a calibration is given: the chart reference of the scene (its chart, grid, image), the camera and the
    processing (display, adaptation)."""

    reference: object     # ChartReference of the scored scene
    camera: object        # CameraSpec
    processing: object    # ProcessingSpec
    true_neutral: np.ndarray


def white_neutral(illuminant: IlluminantSpec, grid: WavelengthGrid, camera: CameraSpec) -> np.ndarray:
    """``(N,)`` the camera's noise-free rates (e⁻/s) for a perfect white diffuser under ``illuminant``.

    Parameters
    ----------
    illuminant : IlluminantSpec
        The light, at its absolute level.
    grid : WavelengthGrid
        The bands.
    camera : CameraSpec
        The camera.

    Returns
    -------
    ndarray
        ``(N,)`` float64, e⁻/s.
    """
    from spectracam.camera import photo_electron_rates
    from spectracam.scene.illuminant import white_diffuser_radiance

    white = white_diffuser_radiance(illuminant, grid)
    return photo_electron_rates(white[None].astype(np.float32), grid, camera)[0].astype(np.float64)


def constrained_lstsq(A: np.ndarray, B: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``X`` minimising ‖A·X − B‖² subject to ``c·X = d`` (one row constraint on every column), by eliminating the
    constraint: ``X = X₀ + N·Z`` with ``X₀ = cᵀd/|c|²`` and ``N`` an orthonormal basis of ``c``'s null space.  With
    more than three channels the reduced problem is solved as :func:`spectracam.processing.color.fit_conversion` solves the
    conversion (columns at unit norm, singular values below ``CONVERSION_RCOND`` dropped: a W channel that is the
    sum of R, G and B leaves the plain solution undetermined).

    Parameters
    ----------
    A : ndarray
        ``(m, n)`` the inputs (one sample a row).
    B : ndarray
        ``(m, k)`` the targets.
    c : ndarray
        ``(n,)`` the constraint's row (e.g. the camera's white).
    d : ndarray
        ``(k,)`` what ``c·X`` must equal (e.g. the white's XYZ).

    Returns
    -------
    ndarray
        ``(n, k)`` X.

    Examples
    --------
    >>> A = np.eye(3); X = constrained_lstsq(A, np.eye(3), np.ones(3), np.array([1.0, 1.0, 1.0]))
    >>> np.allclose(np.ones(3) @ X, 1.0)
    True
    """
    c = np.asarray(c, float)
    X0 = np.outer(c, np.asarray(d, float)) / (c @ c)
    _, _, vt = np.linalg.svd(c[None, :])
    N = vt[1:].T                                            # (n, n − 1), orthonormal, c·N = 0
    R = B - A @ X0
    AN = A @ N
    if A.shape[1] <= 3:
        Z, *_ = np.linalg.lstsq(AN, R, rcond=None)
    else:
        scale = np.linalg.norm(AN, axis=0)
        Z, *_ = np.linalg.lstsq(AN / scale, R, rcond=CONVERSION_RCOND)
        Z = Z / scale[:, None]
    return X0 + N @ Z


@dataclass(frozen=True, eq=False)
class DualIlluminant:
    """The two calibrations of a camera on a chart (:func:`dual_illuminant_matrices`)."""

    cct_K: tuple             # (T_A, T_D65)
    color_matrices: tuple    # (3×N, 3×N): XYZ → camera (row vectors: camera = XYZ·CM)
    forward_matrices: tuple  # (N×3, N×3): balanced camera → XYZ under D50
    neutrals: tuple          # (N,), (N,) each light's white through the camera, e⁻/s

    def weight(self, cct_K: float) -> float:
        """The weight of calibration 1 (CIE A) at ``cct_K``: linear in 1/CCT, clamped to [0, 1].

        Parameters
        ----------
        cct_K : float
            The light's correlated colour temperature, K.

        Returns
        -------
        float
            In [0, 1]; 1 at CIE A's CCT and below, 0 at D65's and above.
        """
        t1, t2 = self.cct_K
        w = (1.0 / cct_K - 1.0 / t2) / (1.0 / t1 - 1.0 / t2)
        return float(np.clip(w, 0.0, 1.0))

    def color_matrix(self, cct_K: float) -> np.ndarray:
        """The ColorMatrix at ``cct_K``: the two interpolated element by element with :meth:`weight` (DNG 1.4).

        Parameters
        ----------
        cct_K : float
            The light's correlated colour temperature, K.

        Returns
        -------
        ndarray
            ``(3, N)`` XYZ → camera (row vectors: camera = XYZ·CM).
        """
        w = self.weight(cct_K)
        return w * self.color_matrices[0] + (1 - w) * self.color_matrices[1]

    def forward_matrix(self, cct_K: float) -> np.ndarray:
        """The ForwardMatrix at ``cct_K``, interpolated as :meth:`color_matrix`.

        Parameters
        ----------
        cct_K : float
            The light's correlated colour temperature, K.

        Returns
        -------
        ndarray
            ``(N, 3)`` white-balanced camera → XYZ under D50 (row vectors).
        """
        w = self.weight(cct_K)
        return w * self.forward_matrices[0] + (1 - w) * self.forward_matrices[1]

    def neutral_to_xy(self, neutral: np.ndarray) -> tuple[np.ndarray, float, int]:
        """``(xy, CCT K, iterations)`` of the white whose interpolated ColorMatrix response is parallel to
        ``neutral`` (the DNG SDK's search; module docstring).

        Parameters
        ----------
        neutral : ndarray
            ``(N,)`` the camera's neutral, any scale.

        Returns
        -------
        xy : ndarray
            ``(2,)`` CIE 1931 chromaticity.
        cct_K : float
            Its correlated colour temperature, K.
        iterations : int
            The search's iterations.

        Raises
        ------
        SpectracamError
            A neutral that maps to no chromaticity.
        """
        xy = xyz_to_xy(D50_XYZ)
        n = np.asarray(neutral, float)
        for it in range(1, NEUTRAL_XY_ITERATIONS + 1):
            cct = xy_to_cct(xy)
            xyz, *_ = np.linalg.lstsq(self.color_matrix(cct).T, n, rcond=None)
            new = xyz_to_xy(xyz)
            if not np.all(np.isfinite(new)):
                raise SpectracamError(f"calibration 'dual_illuminant': the neutral {np.round(n, 6).tolist()} maps to "
                                      "no chromaticity (its XYZ sum is 0 or negative)")
            done = np.max(np.abs(new - xy)) < NEUTRAL_XY_TOLERANCE
            xy = new
            if done:
                break
        return xy, xy_to_cct(xy), it


def xyz_to_xy(xyz: ArrayLike) -> np.ndarray:
    """CIE 1931 chromaticity ``x, y`` of a tristimulus value; NaN when its sum is not > 0.

    Parameters
    ----------
    xyz : array_like
        ``(3,)`` XYZ.

    Returns
    -------
    ndarray
        ``(2,)``.
    """
    xyz = np.asarray(xyz, float)
    s = xyz.sum()
    return xyz[:2] / s if s > 0 else np.array([np.nan, np.nan])


#: The CCT range the Robertson search is asked about (its tables span 1667 K to ∞); xy outside are clamped here.
CCT_RANGE_K = (1667.0, 25000.0)


def xy_to_cct(xy: ArrayLike) -> float:
    """Correlated colour temperature (K) of CIE 1931 xy by Robertson's method (1968), colour-science's, clamped to
    :data:`CCT_RANGE_K` (a neutral far off the locus still gets a temperature, as in the DNG SDK).

    Parameters
    ----------
    xy : array_like
        ``(2,)`` CIE 1931 chromaticity.

    Returns
    -------
    float
        The CCT, K.
    """
    from spectracam.core import colour_data

    uv = colour_data.xy_to_uv(np.asarray(xy, float))
    cct = float(np.asarray(colour_data.uv_to_cct_robertson(uv))[0])
    if not np.isfinite(cct):
        return CCT_RANGE_K[1]
    return float(np.clip(cct, *CCT_RANGE_K))


def light_cct_K(illuminant: IlluminantSpec) -> float:
    """The correlated colour temperature of a light (Robertson's method on its chromaticity,
    :func:`spectracam.processing.calibration.xy_to_cct`), K: the temperature the lens-shading ``"cct"`` correction (:mod:`spectracam.processing.shading`) picks its table by.
    A camera estimates it from its white balance; here it is the light's own (the correction's best case).

    Parameters
    ----------
    illuminant : IlluminantSpec
        The light (a blackbody's temperature is its own CCT).

    Returns
    -------
    float
        The CCT, K.
    """
    if illuminant.kind == "blackbody":
        return float(illuminant.temperature_K)
    from spectracam.core import colour_data
    from spectracam.scene.illuminant import relative_spd

    lam = np.arange(380.0, 781.0, 5.0)
    spd = relative_spd(illuminant)(lam)
    cmfs = colour_data.cmfs_1931_380_780_5()
    return xy_to_cct(xyz_to_xy(spd @ cmfs))


def _illuminant_cct(name: str) -> float:
    from spectracam.core import colour_data

    return xy_to_cct(colour_data.illuminant_xy(name))


@lru_cache(maxsize=64)
def dual_illuminant_matrices(reference: ChartReference, camera: CameraSpec, adaptation: str) -> DualIlluminant:
    """The ColorMatrix and ForwardMatrix of ``camera`` under each of :data:`CALIBRATION_LIGHTS`, fitted on the chart
    of ``reference`` (memoised).

    Parameters
    ----------
    reference : ChartReference
        The chart (its grid and white luminance).
    camera : CameraSpec
        The camera.
    adaptation : str
        The chromatic adaptation from each light's white to D50 (``"bradford"``, …).

    Returns
    -------
    DualIlluminant
        The CCTs, ColorMatrices, ForwardMatrices and neutrals (e⁻/s) under CIE A and D65.
    """
    from spectracam.scene.illuminant import IlluminantSpec

    cms, fms, ns, ccts = [], [], [], []
    for name in CALIBRATION_LIGHTS:
        light = IlluminantSpec("cie", None, name, reference.illuminant.white_luminance_cd_m2)
        ref = reference.lit_by(light)
        rates = ref.patch_rates(camera)                              # (24, N)
        n = white_neutral(light, reference.grid, camera)             # (N,)
        CM, *_ = np.linalg.lstsq(ref.patch_xyz, rates, rcond=None)   # (3, N): rates ≈ XYZ·CM
        CM = CM / np.max(ref.white_xyz @ CM)
        to_d50 = adaptation_matrix(ref.white_xyz, D50_XYZ, adaptation)
        FM = constrained_lstsq(rates / n, ref.patch_xyz @ to_d50.T, np.ones(len(n)), D50_XYZ)
        cms.append(CM)
        fms.append(FM)
        ns.append(n)
        ccts.append(_illuminant_cct(name))
    return DualIlluminant(tuple(ccts), tuple(cms), tuple(fms), tuple(ns))


def xyz_to_display_rgb(processing: ProcessingSpec) -> tuple[np.ndarray, np.ndarray]:
    """``(3×3 inverse display matrix, display white XYZ)``.

    Parameters
    ----------
    processing : ProcessingSpec
        Its display.

    Returns
    -------
    to_rgb : ndarray
        ``(3, 3)`` XYZ → linear display RGB.
    white_xyz : ndarray
        ``(3,)`` the display white's XYZ (Y = 1).
    """
    M_disp = display_rgb_to_xyz(processing.display)
    return np.linalg.inv(M_disp), M_disp.sum(axis=1)


def conversion_target_rgb(reference: ChartReference, processing: ProcessingSpec) -> np.ndarray:
    """``(24, 3)`` what the conversion aims at (paper 3.5): the display RGB that shows each patch's XYZ carried
    from the light's white to the display's.

    Parameters
    ----------
    reference : ChartReference
        The chart under the scene's light (its patches' XYZ, the light's white Y = 1).
    processing : ProcessingSpec
        Its display and chromatic adaptation.

    Returns
    -------
    ndarray
        ``(24, 3)`` linear display RGB.
    """
    M_disp = display_rgb_to_xyz(processing.display)
    to_display_xyz = adaptation_matrix(reference.white_xyz, M_disp.sum(axis=1), processing.adaptation)
    return reference.patch_xyz @ to_display_xyz.T @ np.linalg.inv(M_disp).T


def conversion_matrix(reference: ChartReference, camera: CameraSpec, processing: ProcessingSpec) -> np.ndarray:
    """The N×3 colour conversion (paper 3.5; 3×3 for three channels): least squares from the chart's noise-free
    camera rates to :func:`conversion_target_rgb` — the paper's camera's, fitted under the scene's own light.

    Parameters
    ----------
    reference : ChartReference
        The chart under the scene's light.
    camera : CameraSpec
        The camera (its noise-free patch rates, e⁻/s).
    processing : ProcessingSpec
        Its display and chromatic adaptation.

    Returns
    -------
    ndarray
        ``(N, 3)``, e⁻/s → linear display RGB.
    """
    return fit_conversion(reference.patch_rates(camera), conversion_target_rgb(reference, processing))


@CALIBRATIONS.register("scene_light")
def _scene_light(ctx: Calibration, neutral: np.ndarray):
    """The conversion fitted under the scene's light, applied after carrying ê to the true neutral (in display RGB)."""
    M = conversion_matrix(ctx.reference, ctx.camera, ctx.processing)         # rates → display RGB
    e = ctx.true_neutral / np.linalg.norm(ctx.true_neutral)
    return (e / neutral)[:, None] * M, {"fitted_under": ctx.reference.illuminant.label}


@CALIBRATIONS.register("dual_illuminant")
def _dual_illuminant(ctx: Calibration, neutral: np.ndarray):
    """The DNG's two calibrations interpolated at the CCT the camera finds from ê (module docstring)."""

    dual = dual_illuminant_matrices(ctx.reference, ctx.camera, ctx.processing.adaptation)
    xy, cct, iterations = dual.neutral_to_xy(neutral)
    inv_disp, display_white = xyz_to_display_rgb(ctx.processing)
    to_display = adaptation_matrix(D50_XYZ, display_white, ctx.processing.adaptation)
    M = (1.0 / neutral)[:, None] * (dual.forward_matrix(cct) @ to_display.T @ inv_disp.T)
    return M, {"estimated_white_xy": xy.tolist(), "estimated_cct_K": cct, "weight_A": dual.weight(cct),
               "calibration_cct_K": list(dual.cct_K), "iterations": iterations}
