"""What the model is shown: for one scene's light, the chart (conversion fit and metering) and the colour sets
scored, as the constant arrays of :class:`~spectracam.experiments.design.model.LightModel`.

The conversion is fitted on the scene's ColorChecker, as the capture → score pipeline fits it
(:func:`spectracam.processing.calibration.conversion_matrix`), and the exposure metered on its white patch; the colour sets are
the chart itself (``chart``) or measured reflectance libraries (:mod:`spectracam.scene.reflectances`) under the same
light, their truth the CIE 1931 colorimetry of :func:`spectracam.scene.reference.library_colours`.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from spectracam.scene.chart import WHITE_PATCH
from spectracam.core.spectra import logistic_scale_nm
from spectracam.core.cielab import xyz_to_lab
from spectracam.optics import radiance_to_photon_irradiance
from spectracam.scene.reference import ChartReference, library_colours
from spectracam.processing.calibration import conversion_target_rgb
from spectracam.experiments.design.ad import tensor
from spectracam.experiments.design.model import ColourSet, LightModel

if TYPE_CHECKING:
    from collections.abc import Sequence

    from spectracam.camera import CameraSpec
    from spectracam.experiments.design.model import LightResult, WhiteModel
    from spectracam.experiments.design.spec import DesignSpec
    from spectracam.pipeline.scene_file import Scene
    from spectracam.processing.color import ProcessingSpec

__all__ = ["CHART", "DESIGN_MONDRIANS", "DesignProblem", "light_model", "photon_weights", "white_models"]

#: The colour-set name that means the scene's own chart.
CHART = "chart"


def photon_weights(scene: Scene, camera: CameraSpec) -> np.ndarray:
    """``(B,)`` factor from band radiance to photo-electrons per second per unit responsivity: the optics'
    photon irradiance × band width × pixel area (paper 3.2-3.3; :func:`spectracam.camera.band_weights`).

    Parameters
    ----------
    scene : Scene
        Its wavelength grid, nm.
    camera : CameraSpec
        Its optics and pixel area, µm².

    Returns
    -------
    ndarray
        ``(B,)``: e⁻/s per unit responsivity (e⁻/photon) per W·m⁻²·sr⁻¹·nm⁻¹ of band radiance.
    """
    grid = scene.grid
    return radiance_to_photon_irradiance(grid, camera.optics) * grid.widths_nm * camera.sensor.pixel_area_um2 * 1e-12


def light_model(scene: Scene, camera: CameraSpec, processing: ProcessingSpec, sets: Sequence[str] = (CHART,),
                label: str | None = None) -> LightModel:
    """The :class:`LightModel` of a chart scene for ``camera`` with the colour ``sets`` (``chart`` or library
    names).

    Parameters
    ----------
    scene : Scene
        A chart scene: its chart, light and grid.
    camera : CameraSpec
        Its optics and pixel (:func:`photon_weights`).
    processing : ProcessingSpec
        Sets the conversion's target display RGB.
    sets : sequence of str
        :data:`CHART` or reflectance-library names.
    label : str or None
        The light's label; None: the illuminant's.

    Returns
    -------
    LightModel
        The chart's weights and target RGB, the white patch's weights and each set's weights and true CIELAB.
    """
    ref = ChartReference.of(scene)
    g = photon_weights(scene, camera)
    chart_w = ref.patch_radiance * g[None, :]
    out = {}
    for name in sets:
        if name == CHART:
            out[name] = ColourSet(name, chart_w, xyz_to_lab(ref.patch_xyz, ref.white_xyz))
        else:
            c = library_colours(name, scene.illuminant, scene.grid)
            out[name] = ColourSet(name, c.radiance * g[None, :], xyz_to_lab(c.xyz, c.white_xyz))
    return LightModel(label or scene.illuminant.label, chart_w, conversion_target_rgb(ref, processing),
                      chart_w[WHITE_PATCH], out)


#: Training Mondrians per light for a design whose camera estimates its white, and the surfaces in each (as the
#: trained estimator's: spectracam.processing.white_balance).
DESIGN_MONDRIANS = 24


def white_models(scene: Scene, camera: CameraSpec, light: LightModel, sets: Sequence[str],
                 settings: DesignSpec) -> dict[str, WhiteModel]:
    """Set name → :class:`~spectracam.experiments.design.model.WhiteModel`: Mondrians of that set's colours under the light
    (fixed draws), the estimator's order, and the light's perfect white diffuser through the optics.

    Parameters
    ----------
    scene : Scene
        The light's scene.
    camera : CameraSpec
    light : LightModel
        :func:`light_model`'s, holding the sets.
    sets : sequence of str
        The sets to model (repeats once).
    settings : DesignSpec
        ``white_balance`` (``"grey_world"``: order 1) and ``white_balance_p``.

    Returns
    -------
    dict of str to WhiteModel
        :data:`DESIGN_MONDRIANS` Mondrians per set, drawn with the trained estimator's seed.
    """
    from spectracam.scene.illuminant import white_diffuser_radiance
    from spectracam.processing.white_balance import TRAINING_SEED, TRAINING_SURFACES
    from spectracam.experiments.design.model import WhiteModel

    p = 1.0 if settings.white_balance == "grey_world" else float(settings.white_balance_p)
    white = white_diffuser_radiance(scene.illuminant, scene.grid) * photon_weights(scene, camera)
    out = {}
    for name in dict.fromkeys(sets):
        n = light.sets[name].weights.shape[0]
        rng = np.random.default_rng(TRAINING_SEED)
        W = np.zeros((DESIGN_MONDRIANS, n))
        for j in range(DESIGN_MONDRIANS):
            k = int(rng.integers(min(TRAINING_SURFACES[0], n), min(TRAINING_SURFACES[1], n) + 1))
            W[j, rng.choice(n, k, replace=False)] = rng.dirichlet(np.ones(k))
        out[name] = WhiteModel(W, p, white)
    return out


class DesignProblem:
    """One architecture's design: its parametrisation, the optional IR-cut edge and exposure split, the lights,
    and the objective — the mean expected ΔE*ab (``settings.objective = "delta_e"``) or expected S-CIELAB
    (``"s_cielab"``) over the training colours × lights, plus the realisability penalty, minus ``snr_weight`` × the
    mean combined SNR (dB) when asked.

    ``x`` = [the parametrisation's variables | IR-cut edge, nm (if designed) | exposure shares (if designed)].

    Parameters
    ----------
    design : str
        ``architecture/exposure``; ``…/split`` designs the exposure shares too.
    parametrisation : str
        A name of :data:`~spectracam.experiments.design.variables.PARAMETRISATIONS`.
    settings : DesignSpec
    camera : CameraSpec
        The base camera.
    processing : ProcessingSpec
    scenes : list of Scene
        One chart scene per light, on one wavelength grid.
    training, held_out : str
        The colour sets optimised on and held out (:data:`CHART` or library names).
    """

    def __init__(self, design: str, parametrisation: str, settings: DesignSpec, camera: CameraSpec,
                 processing: ProcessingSpec, scenes: list, training: str, held_out: str):
        from spectracam.experiments.design.model import CameraModel
        from spectracam.experiments.design.variables import PARAMETRISATIONS, Samples, check_parametrisation

        self.camera = camera.with_design(design.replace("/split", "/single") if design.endswith("/split") else design)
        self.design, self.settings, self.processing = design, settings, processing
        self.architecture = self.camera.architecture()
        check_parametrisation(parametrisation, self.architecture)
        self.grid = scenes[0].grid
        self.param = PARAMETRISATIONS[parametrisation](settings, self.camera, self.grid)
        self.ir_cut = bool(settings.design_ir_cut)
        self.split = design.endswith("/split")
        self.samples = Samples.of(self.camera, self.grid, self.ir_cut)
        self.model = CameraModel.of(self.camera, processing, exposure="split" if self.split else None)
        self.training, self.held_out = training, held_out
        self.lights = [light_model(s, self.camera, processing, sets=tuple(dict.fromkeys((CHART, training, held_out))))
                       for s in scenes]
        self.white = [white_models(s, self.camera, light, (training, held_out), settings) for s, light in
                      zip(scenes, self.lights)] if getattr(settings, "white_balance", "oracle") != "oracle" else None
        self.n_param = self.param.initial().size
        self.evaluations = 0

    # -- the vector x -------------------------------------------------------------------------------------------
    def initial(self) -> np.ndarray:
        parts = [self.param.initial()]
        if self.ir_cut:
            parts.append([self.camera.filters.ir_cut_nm or self.settings.start_ir_cut_nm])
        if self.split:
            parts.append(np.full(len(self.model.channels), 1.0 / len(self.model.channels)
                                 if self.model.capture == "sum" else 1.0))
        return np.concatenate([np.asarray(p, float) for p in parts])

    def bounds(self) -> list:
        b = list(self.param.bounds())
        if self.ir_cut:
            b.append((550.0, float(self.grid.edges_nm[-1]) + 50.0))
        if self.split:
            b += [(0.01, 1.0)] * len(self.model.channels)
        return b

    # -- from x to the model --------------------------------------------------------------------------------------
    def responsivities(self, x: Any) -> list:
        """The channels' band-averaged responsivities ``(B,)`` as tensors.

        Parameters
        ----------
        x : TensorXf64
            The design vector (see the class).

        Returns
        -------
        list
            Per channel, the ``(B,)`` responsivity, e⁻/photon (filter × QE × IR cut).
        """
        from spectracam.experiments.design.ad import backend, fresh, tensor
        from spectracam.experiments.design.variables import band_average, channels_from_primaries, logistic

        dr, _ = backend()
        cut = None
        if self.ir_cut:
            c = fresh(x[self.n_param])
            s = float(logistic_scale_nm(self.camera.filters.ir_cut_width_nm))
            cut = logistic((c - tensor(self.samples.lam)) / s)
        qe = tensor(self.samples.qe) if cut is None else tensor(self.samples.qe) * cut
        xp = x   # the parametrisation reads its own first n_param entries (no slices: see FreeForm._matrix)
        if self.param.varies == "depths":
            return [band_average(v, self.samples) for v in self.param.layer_qe(xp, self.samples, cut)]
        R = [band_average(T * qe, self.samples) for T in self.param.transmittances(xp, self.samples)]
        return channels_from_primaries(self.architecture, R, band_average(qe, self.samples))

    def shares(self, x: Any) -> list | None:
        """The exposure shares (tensors), normalised to sum 1 for frames in sequence.

        Parameters
        ----------
        x : TensorXf64
            The design vector.

        Returns
        -------
        list or None
            One share per channel; None unless the design is ``…/split``.
        """
        if not self.split:
            return None
        from spectracam.experiments.design.ad import fresh

        n = len(self.model.channels)
        i0 = self.n_param + (1 if self.ir_cut else 0)
        f = [fresh(x[i0 + k]) for k in range(n)]
        if self.model.capture == "sum":
            total = f[0]
            for v in f[1:]:
                total = total + v
            f = [v / total for v in f]
        return f

    @property
    def score(self) -> str:
        """The expectation the objective minimises: ``delta_e`` or ``s_cielab`` (:attr:`DesignSpec.objective`)."""
        return getattr(self.settings, "objective", "delta_e")

    def evaluate(self, x: Any, sets: Sequence[str] | None = None,
                 scores: Sequence[str] = ("delta_e",)) -> list[LightResult]:
        """The model's :class:`~spectracam.experiments.design.model.LightResult` for each light (``scores``: see
        :func:`~spectracam.experiments.design.model.evaluate`).

        Parameters
        ----------
        x : TensorXf64
            The design vector.
        sets : sequence of str or None
            The colour sets scored; None: every set of each light.
        scores : sequence of str
            ``"delta_e"`` and/or ``"s_cielab"``.

        Returns
        -------
        list of LightResult
            One per light, in order.
        """
        from spectracam.experiments.design.model import evaluate

        R = self.responsivities(x)
        split = self.shares(x)
        white = self.white or [None] * len(self.lights)
        return [evaluate(R, light, self.model, split, sets, w, scores) for light, w in zip(self.lights, white)]

    def objective(self, x: Any) -> tuple[Any, Any]:
        """``(value, aux)``: the scalar the optimiser minimises (see the class), and the training ΔE*ab (or
        S-CIELAB, as the objective) it holds.

        Parameters
        ----------
        x : TensorXf64
            The design vector.

        Returns
        -------
        tuple of TensorXf64
            The objective, and the mean expected error over the training colours and lights (with the estimated
            white's penalty when the camera finds its own white).
        """
        from spectracam.experiments.design.ad import backend

        dr, _ = backend()
        score = self.score
        results = self.evaluate(x, sets=(self.training,), scores=(score,))
        de = sum(dr.mean(getattr(r, score)[self.training]) for r in results) / len(results)
        if self.white:   # the camera finds its own white: the estimator's extra error on the training colours
            de = de + sum(dr.mean(r.white_penalty[self.training]) for r in results) / len(results)
        value = de + self.param.penalty(x)
        if self.settings.snr_weight:
            snr = sum(dr.mean(r.snr_db[self.training]) for r in results) / len(results)
            value = value - self.settings.snr_weight * snr
        return value, de

    def value_and_gradient(self, x: np.ndarray) -> tuple[float, np.ndarray, float]:
        """The objective, its gradient and the training error at ``x`` (counted in ``evaluations``).

        Parameters
        ----------
        x : ndarray
            The design vector.

        Returns
        -------
        tuple of (float, ndarray, float)
            :meth:`objective`'s value, ``∂value/∂x`` (``x``'s shape), and the training ΔE*ab (or S-CIELAB).
        """
        from spectracam.experiments.design.ad import numpy, value_and_gradient

        self.evaluations += 1
        v, g, de = value_and_gradient(self.objective, x)
        return v, g, float(numpy(de).reshape(-1)[0])

    # -- from x to the pipeline ------------------------------------------------------------------------------------
    def camera_of(self, x: np.ndarray) -> CameraSpec:
        """The :class:`~spectracam.camera.CameraSpec` of design ``x``: what the capture → score pipeline runs.

        Parameters
        ----------
        x : ndarray
            The design vector.

        Returns
        -------
        CameraSpec
            The base camera with the designed filters (and IR-cut edge, nm), and the ``split`` exposure's shares
            clipped to [1e-6, 1].
        """
        x = np.asarray(x, float)
        filters = self.param.filters(x[:self.n_param])
        if self.ir_cut:
            filters = filters.replace(ir_cut_nm=float(x[self.n_param]))
        cam = self.camera.replace(filters=filters)
        if self.split:
            shares = np.array([float(v.numpy().reshape(-1)[0]) for v in self.shares(tensor(x))])
            cam = cam.replace(capture=cam.capture.replace(exposure="split",
                                                          exposure_split=tuple(np.clip(shares, 1e-6, 1.0).tolist())))
        return cam

    def describe(self, x: np.ndarray) -> dict:
        """The design ``x`` in words and numbers, for results.json.

        Parameters
        ----------
        x : ndarray
            The design vector.

        Returns
        -------
        dict
            The parametrisation's description, with ``ir_cut_nm`` and ``exposure_split`` when designed.
        """
        x = np.asarray(x, float)
        out = dict(self.param.describe(x[:self.n_param]))
        if self.ir_cut:
            out["ir_cut_nm"] = round(float(x[self.n_param]), 2)
        if self.split:
            out["exposure_split"] = list(self.camera_of(x).capture.exposure_split)
        return out

