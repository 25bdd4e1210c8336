"""Design variables: what the optimiser moves, and how each choice becomes responsivities and a camera.

A :class:`Parametrisation` maps a vector ``x`` (with box bounds) to the three primary transmittances T_k(λ)
(R, G, B) — or, for stacked photodiodes, to the depths of the collection windows — evaluated at the same
sample points and trapezoid weights as :func:`spectracam.core.spectra.band_average` (400 a band), times QE × IR cut:
the band-averaged responsivities are then those the pipeline computes for the camera :meth:`camera` returns
(a test holds them together).  The architecture says what the design varies for it and how its channels are made
(:meth:`~spectracam.architecture.base.Architecture.design_variables`: ``"filters"`` or ``"depths"``; its
:attr:`~spectracam.architecture.base.Architecture.primaries`), and :func:`channels_from_primaries` makes them as the
pipeline does (W, Y, C, M capped at the unfiltered pixel); an architecture that computes its channels its own way is
refused by name (:func:`design_architecture`), never designed as another.  Optional extra variables: the IR-cut edge
(nm) and the exposure split of a field-sequential or prism camera.

=============  =====================================================  =================================
name           variables                                              pipeline camera
=============  =====================================================  =================================
``block``      the two cutoffs, nm (edges ``edge_width_nm`` wide)     ``kind = "block"``
``gaussian``   three centres and three FWHM, nm                       ``kind = "gaussian"``
``freeform``   transmittances at knots every ``knot_step_nm``, in     ``kind = "transmittance"``
               [``min_transmittance``, 1], linear between, smoothness
               penalised
``depths``     the stacked photodiodes' dead layer and window widths  ``stacked_depths_um``
=============  =====================================================  =================================
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.architecture import ARCHITECTURES, make_architecture
from spectracam.architecture.filters import CHANNELS, QE_MODELS, quantum_efficiency
from spectracam.core.registry import Registry
from spectracam.core.spectra import band_sample_points, logistic_scale_nm
from spectracam.experiments.design.ad import backend, fresh, tensor

if TYPE_CHECKING:
    from spectracam.architecture.base import Architecture
    from spectracam.architecture.filters import FilterSpec
    from spectracam.camera import CameraSpec
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.experiments.design.spec import DesignSpec

__all__ = ["DESIGN_VARIABLES", "PARAMETRISATIONS", "POINTS_PER_BAND", "Block", "Depths", "FreeForm", "Gaussian",
           "Parametrisation", "Samples", "band_average", "channels_from_primaries", "check_parametrisation",
           "design_architecture", "designable", "logistic"]

#: Points per band of the responsivities' trapezoid rule: those of the pipeline's smooth filters
#: (:func:`spectracam.architecture.filters._smooth`), so the two agree to rounding.
POINTS_PER_BAND = 400

PARAMETRISATIONS: Registry = Registry("design.filters", "filter parametrisation")


@dataclass(frozen=True, eq=False)
class Samples:
    """The wavelengths ``lam (B, P + 1)`` every transmittance is evaluated at, the trapezoid weights ``q (P + 1,)``
    of a band average, and QE there (with the camera's fixed IR cut, or without it when the edge is designed)."""

    lam: np.ndarray
    q: np.ndarray
    qe: np.ndarray

    @classmethod
    def of(cls, camera: CameraSpec, grid: WavelengthGrid, ir_cut_designed: bool) -> "Samples":
        """The samples of ``grid``'s bands, :data:`POINTS_PER_BAND` per band, with ``camera``'s QE there.

        Parameters
        ----------
        camera : CameraSpec
            Its filters' QE model and IR cut.
        grid : WavelengthGrid
            The bands, nm.
        ir_cut_designed : bool
            The IR-cut edge is a design variable: QE without the camera's IR cut.

        Returns
        -------
        Samples
            ``lam`` (nm), ``q`` and ``qe`` (e⁻/photon).
        """
        lam = band_sample_points(grid, POINTS_PER_BAND)
        q = np.full(POINTS_PER_BAND + 1, 1.0 / POINTS_PER_BAND)
        q[[0, -1]] *= 0.5
        f = camera.filters
        qe = (QE_MODELS[f.qe](f) if ir_cut_designed else quantum_efficiency(f))(lam)
        return cls(lam, q, np.asarray(qe, float))


def band_average(values: Any, samples: Samples) -> Any:
    """``(B,)`` trapezoid band averages of values at the sample points ``(B, P + 1)``.

    Parameters
    ----------
    values : TensorXf64
        ``(B, P + 1)`` at ``samples.lam``.
    samples : Samples
        Its trapezoid weights ``q``.

    Returns
    -------
    TensorXf64
        ``(B,)``.
    """
    dr, _ = backend()
    return dr.sum(values * tensor(samples.q)[None, :], axis=1)


def logistic(x: Any) -> Any:
    """The logistic function ``1 / (1 + e^(−x))``, elementwise on tensors (the soft filter edge).

    Parameters
    ----------
    x : TensorXf64

    Returns
    -------
    TensorXf64
        ``x``'s shape, in (0, 1).
    """
    dr, _ = backend()
    return 1.0 / (1.0 + dr.exp(-x))


#: What the parametrisations can vary (:meth:`~spectracam.architecture.base.Architecture.design_variables`).
DESIGN_VARIABLES = ("filters", "depths")


def designable() -> tuple[str, ...]:
    """The registered architectures the design can model, in registry order."""
    return tuple(n for n, cls in ARCHITECTURES.items() if cls.design_variables() in DESIGN_VARIABLES)


def design_architecture(architecture: Architecture | str) -> Architecture:
    """The architecture object the design models (``architecture``: one, or a registered name), or one line refusing
    an architecture the design cannot model (unknown, or computing its channels its own way).

    Parameters
    ----------
    architecture : Architecture or str

    Returns
    -------
    Architecture
        ``architecture``, or the registered one made from its name.

    Raises
    ------
    SpectracamError
        When the name is not registered, or its channels are made of neither filters nor depths.
    """
    if isinstance(architecture, str):
        if architecture not in ARCHITECTURES:
            raise SpectracamError(f"design: architecture {architecture!r} is not registered; the design models "
                                  + ", ".join(designable()))
        architecture = make_architecture(architecture)
    if architecture.design_variables() not in DESIGN_VARIABLES:
        raise SpectracamError(f"design: the {architecture.name!r} architecture makes its channels its own way "
                              "(not of the three filters of [filters], nor of stacked depths), so the design cannot "
                              "model it; it models " + ", ".join(designable()))
    return architecture


def channels_from_primaries(architecture: Architecture | str, R: list, clear: Any) -> list:
    """The architecture's channels (an architecture, or a registered name) from the primaries' responsivities R, G, B
    and the unfiltered pixel's ``clear``, as its :attr:`~spectracam.architecture.base.Architecture.primaries` say
    (:func:`spectracam.architecture.base.complementary`: a pair's sum capped at ``clear``; W: ``clear``).

    Parameters
    ----------
    architecture : Architecture or str
        One designed by filters.
    R : list
        The primaries' ``(B,)`` responsivities, R, G, B, e⁻/photon.
    clear : TensorXf64
        ``(B,)`` the unfiltered pixel's (QE × IR cut).

    Returns
    -------
    list
        One ``(B,)`` tensor per channel, in the architecture's order.

    Raises
    ------
    SpectracamError
        When the architecture is not designed by filters (:func:`design_architecture`).
    """
    dr, _ = backend()
    arch = design_architecture(architecture)
    if arch.design_variables() != "filters":
        raise SpectracamError(f"design: the {arch.name!r} architecture is designed by its "
                              f"{arch.design_variables()}, not by filters")

    def channel(p):
        if p == "W":
            return clear
        if len(p) == 1:
            return R[CHANNELS.index(p)]
        total = R[CHANNELS.index(p[0])]
        for c in p[1:]:
            total = total + R[CHANNELS.index(c)]
        return dr.minimum(total, clear)

    return [channel(p) for p in arch.primaries]


class Parametrisation:
    """One way of designing filters (see the module).  ``x`` is a numpy vector; :meth:`transmittances` takes it
    as a Dr.Jit tensor.

    Parameters
    ----------
    settings : DesignSpec
        The design file's settings (start values, edge width, knots, …).
    camera : CameraSpec
        The camera designed; its filters are replaced.
    grid : WavelengthGrid
        The scene's bands, nm.
    """

    name = ""
    #: What it varies, of :data:`DESIGN_VARIABLES`: an architecture is designed by the parametrisations that vary
    #: what its :meth:`~spectracam.architecture.base.Architecture.design_variables` says.
    varies = "filters"
    #: Does it design stacked photodiodes (by their depths) rather than filters?
    stacked = False

    def __init__(self, settings: DesignSpec, camera: CameraSpec, grid: WavelengthGrid):
        self.settings, self.camera, self.grid = settings, camera, grid

    def initial(self) -> np.ndarray:
        """The start of ``x``."""
        raise NotImplementedError

    def bounds(self) -> list:
        """``(low, high)`` per entry of ``x`` (L-BFGS-B's box)."""
        raise NotImplementedError

    def transmittances(self, x: Any, samples: Samples) -> list:
        """Three tensors ``(B, P + 1)``: T_R, T_G, T_B at the sample points.

        Parameters
        ----------
        x : TensorXf64
            The design vector; its first entries are this parametrisation's.
        samples : Samples
            Where, nm.

        Returns
        -------
        list
            T_R, T_G, T_B, each ``(B, P + 1)``, in [0, 1].
        """
        raise NotImplementedError

    def penalty(self, x: Any) -> Any:
        """The realisability term (0 unless a parametrisation has one).

        Parameters
        ----------
        x : TensorXf64
            The design vector.

        Returns
        -------
        TensorXf64 or float
            Added to the objective.
        """
        return 0.0

    def filters(self, x: np.ndarray) -> FilterSpec:
        """The :class:`~spectracam.architecture.filters.FilterSpec` of design ``x`` (for the pipeline).

        Parameters
        ----------
        x : ndarray
            This parametrisation's entries of the design vector.

        Returns
        -------
        FilterSpec
            The camera's filters with the designed ones in their place.
        """
        raise NotImplementedError

    def describe(self, x: np.ndarray) -> dict:
        """The design's numbers, named (results.json).

        Parameters
        ----------
        x : ndarray
            This parametrisation's entries of the design vector.

        Returns
        -------
        dict
            Name → value (nm, µm or the settings it was designed with).
        """
        raise NotImplementedError


def _t(x, i):
    """Element ``i`` of a tensor as a one-element tensor (a fresh view: see :func:`~spectracam.experiments.design.ad.fresh`)."""
    return fresh(x[i])


@PARAMETRISATIONS.register("block")
class Block(Parametrisation):
    """Block filters (paper 4.3) with the two cutoffs free; ideal steps (``edge_width_nm = 0``: a ramp one
    sample wide, so the band average is the exact overlap to 1/400 of a band) or logistic edges."""

    name = "block"

    def initial(self) -> np.ndarray:
        return np.asarray(self.settings.start_cutoffs_nm, float)

    def bounds(self) -> list:
        lo, hi = float(self.grid.edges_nm[0]), float(self.grid.edges_nm[-1])
        return [(lo + 5.0, hi - 5.0)] * 2

    def transmittances(self, x: Any, samples: Samples) -> list:
        dr, _ = backend()
        lam = tensor(samples.lam)
        w = self.settings.edge_width_nm
        if w > 0:
            s = float(logistic_scale_nm(w))

            def rise(c):
                return logistic((lam - c) / s)
        else:
            h = float(samples.lam[0, 1] - samples.lam[0, 0])

            def rise(c):
                return dr.clip((lam - c) / h + 0.5, 0.0, 1.0)
        r1, r2 = rise(_t(x, 0)), rise(_t(x, 1))
        return [r2, r1 * (1.0 - r2), 1.0 - r1]

    def penalty(self, x: Any) -> Any:
        dr, _ = backend()
        gap = _t(x, 1) - _t(x, 0) - 10.0   # the green band at least 10 nm wide
        return 1e3 * dr.square(dr.minimum(gap, 0.0))

    def filters(self, x: np.ndarray) -> FilterSpec:
        return self.camera.filters.replace(kind="block", cutoffs_nm=(float(x[0]), float(x[1])),
                                           edge_width_nm=float(self.settings.edge_width_nm))

    def describe(self, x: np.ndarray) -> dict:
        return {"cutoffs_nm": [round(float(v), 2) for v in x[:2]], "edge_width_nm": self.settings.edge_width_nm}


@PARAMETRISATIONS.register("gaussian")
class Gaussian(Parametrisation):
    """Three Gaussian transmittances of peak 1: centres and full widths at half maximum, nm."""

    name = "gaussian"

    def initial(self) -> np.ndarray:
        return np.array([*self.settings.start_centres_nm, *self.settings.start_fwhm_nm], float)

    def bounds(self) -> list:
        lo, hi = float(self.grid.edges_nm[0]), float(self.grid.edges_nm[-1])
        return [(lo, hi)] * 3 + [(10.0, 300.0)] * 3

    def transmittances(self, x: Any, samples: Samples) -> list:
        dr, _ = backend()
        lam = tensor(samples.lam)
        k = float(2 * np.sqrt(2 * np.log(2)))   # a numpy scalar would take the tensor apart
        return [dr.exp(-0.5 * dr.square((lam - _t(x, i)) * (k / _t(x, 3 + i)))) for i in range(3)]

    def filters(self, x: np.ndarray) -> FilterSpec:
        return self.camera.filters.replace(kind="gaussian", centres_nm=tuple(float(v) for v in x[:3]),
                                           fwhm_nm=tuple(float(v) for v in x[3:6]))

    def describe(self, x: np.ndarray) -> dict:
        return {"centres_nm": [round(float(v), 2) for v in x[:3]], "fwhm_nm": [round(float(v), 2) for v in x[3:6]]}


@PARAMETRISATIONS.register("freeform")
class FreeForm(Parametrisation):
    """Transmittances at knots every ``knot_step_nm`` over the scene's range, linear between, bounded to
    [``min_transmittance``, 1] (no real dye blocks completely), with a smoothness penalty:
    ``smoothness`` × the mean squared second difference of the knots per (10 nm)²."""

    name = "freeform"

    @property
    def knots_nm(self) -> np.ndarray:
        lo, hi = float(self.grid.edges_nm[0]), float(self.grid.edges_nm[-1])
        n = int(np.ceil((hi - lo) / self.settings.knot_step_nm - 1e-9))
        return np.linspace(lo, hi, n + 1)

    def initial(self) -> np.ndarray:
        """The paper's block filters sampled at the knots (or the start cutoffs), lifted to the floor."""
        c1, c2 = self.settings.start_cutoffs_nm
        k = self.knots_nm
        T = np.stack([(k > c2), (k > c1) & (k <= c2), (k <= c1)]).astype(float)
        return np.clip(T, self.settings.min_transmittance, 1.0).ravel()

    def bounds(self) -> list:
        return [(self.settings.min_transmittance, 1.0)] * (3 * self.knots_nm.size)

    def _hat(self, samples):
        """``(B·(P + 1), K)`` linear-interpolation weights from knots to sample points."""
        k = self.knots_nm
        lam = samples.lam.ravel()
        H = np.zeros((lam.size, k.size))
        j = np.clip(np.searchsorted(k, lam, side="right") - 1, 0, k.size - 2)
        f = np.clip((lam - k[j]) / (k[j + 1] - k[j]), 0.0, 1.0)
        H[np.arange(lam.size), j] = 1.0 - f
        H[np.arange(lam.size), j + 1] += f
        return H

    def _matrix(self, rows: np.ndarray, i: int, width: int) -> np.ndarray:
        """``rows`` acting on channel i's knots, as columns of the whole vector x (Dr.Jit 1.5 loses the gradient
        of a tensor slice that starts inside and ends inside a tensor — checked — so no slices: products)."""
        K = self.knots_nm.size
        out = np.zeros((rows.shape[0], width))
        out[:, i * K:(i + 1) * K] = rows
        return out

    def transmittances(self, x: Any, samples: Samples) -> list:
        dr, _ = backend()
        width = dr.width(x)
        key = (id(samples), width)
        if getattr(self, "_hat_key", None) != key:
            hat = self._hat(samples)
            self._hats, self._hat_key = [tensor(self._matrix(hat, i, width)) for i in range(3)], key
        out = []
        for H in self._hats:   # linear in the knots: a (samples × x) product
            T = dr.sum(H * x[None, :], axis=1)
            out.append(dr.reshape(type(T), T, samples.lam.shape))
        return out

    def penalty(self, x: Any) -> Any:
        dr, _ = backend()
        K = self.knots_nm.size
        width = dr.width(x)
        D = np.zeros((K - 2, K))
        for j in range(K - 2):
            D[j, j:j + 3] = (1.0, -2.0, 1.0)
        total = 0.0
        scale = (10.0 / self.settings.knot_step_nm) ** 2
        for i in range(3):
            d2 = dr.sum(tensor(self._matrix(D, i, width)) * x[None, :], axis=1)
            total = total + dr.mean(dr.square(d2)) * scale
        return self.settings.smoothness * total / 3.0

    def filters(self, x: np.ndarray) -> FilterSpec:
        K = self.knots_nm.size
        rows = np.clip(np.asarray(x, float)[:3 * K].reshape(3, K).T, 0.0, 1.0)
        return self.camera.filters.replace(kind="transmittance", transmittance_nm=tuple(self.knots_nm.tolist()),
                                           transmittance=tuple(tuple(r) for r in rows.tolist()))

    def describe(self, x: np.ndarray) -> dict:
        return {"knot_step_nm": self.settings.knot_step_nm, "knots": int(self.knots_nm.size),
                "min_transmittance": self.settings.min_transmittance, "smoothness": self.settings.smoothness}


@PARAMETRISATIONS.register("depths")
class Depths(Parametrisation):
    """Stacked photodiodes: the surface dead layer z₀ and each window's width, µm (so the boundaries stay
    ordered); QE_k = (1 − R)(exp(−α·z_k) − exp(−α·z_{k+1})) (:mod:`spectracam.architecture.stacked`)."""

    name = "depths"
    varies = "depths"
    stacked = True

    @property
    def depths_um(self) -> tuple:
        """The camera's window boundaries, as its stacked architecture reads them."""
        return self.camera.architecture().depths_um(self.camera.filters)

    def initial(self) -> np.ndarray:
        z = np.asarray(self.depths_um, float)
        return np.concatenate([[z[0]], np.diff(z)])

    def bounds(self) -> list:
        n = len(self.depths_um)
        return [(0.01, 2.0)] + [(0.05, 20.0)] * (n - 1)

    def layer_qe(self, x: Any, samples: Samples, ir_cut: Any | None = None) -> list:
        """Bottom-first layer responsivities at the sample points (the pipeline's ``layer_qe`` × IR cut).

        Parameters
        ----------
        x : TensorXf64
            The dead layer z₀ and the windows' widths, µm.
        samples : Samples
            Where, nm.
        ir_cut : TensorXf64 or None
            The designed IR cut's transmittance there (it replaces the camera's shared one); None: the camera's.

        Returns
        -------
        list
            One ``(B, P + 1)`` tensor per layer, deepest first, e⁻/photon.
        """
        dr, _ = backend()
        from spectracam.architecture.silicon import absorption_coefficient_per_um, reflectance

        alpha = tensor(absorption_coefficient_per_um(samples.lam))
        front = tensor(1.0 - reflectance(samples.lam))
        n = len(self.depths_um)
        z = [_t(x, 0)]
        for i in range(1, n):
            z.append(fresh(z[-1] + _t(x, i)))
        reach = [dr.exp(-alpha * fresh(zi)) for zi in z]
        # the filters in front of the layers: the stacked sensor's own IR cut (architectures.stacked.stacked_cut)
        # times the shared one, fixed — or, when the design varies the shared IR cut, the designed one instead
        from spectracam.architecture.layers import stacked_cut

        f = self.camera.filters if ir_cut is None else self.camera.filters.replace(ir_cut_nm=None)
        fixed = stacked_cut(f)
        cut = tensor(np.asarray(fixed(samples.lam), float)) if fixed is not None else 1.0
        if ir_cut is not None:
            cut = cut * ir_cut
        return [front * (reach[k] - reach[k + 1]) * cut for k in reversed(range(n - 1))]

    def filters(self, x: np.ndarray) -> FilterSpec:
        z = np.cumsum(np.asarray(x, float))
        return self.camera.architecture().with_depths(self.camera.filters, z)

    def describe(self, x: np.ndarray) -> dict:
        return {"stacked_depths_um": [round(float(v), 4) for v in np.cumsum(x)]}


def check_parametrisation(name: str, architecture: Architecture | str) -> None:
    """The parametrisation ``name`` varies what the architecture (an architecture, or a registered name) is designed
    by (:meth:`~spectracam.architecture.base.Architecture.design_variables`): stacked photodiodes their depths, every
    other architecture the design models its filters; one line otherwise, or for an architecture it cannot model.

    Parameters
    ----------
    name : str
        A name of :data:`PARAMETRISATIONS`.
    architecture : Architecture or str

    Raises
    ------
    SpectracamError
        When the two do not fit, or the design cannot model the architecture.
    """
    p = PARAMETRISATIONS[name]
    arch = design_architecture(architecture)
    varies = arch.design_variables()
    if p.varies != varies:
        fitting = [n for n, q in PARAMETRISATIONS.items() if q.varies == varies]
        fitting = ", ".join(fitting[:-1]) + " or " + fitting[-1] if len(fitting) > 1 else fitting[0]
        raise SpectracamError(f"design: filters = {name!r} cannot design a {arch.name} camera; "
                              + ("stacked photodiodes are designed by 'depths'" if varies == "depths"
                                 else f"'{p.name}' designs stacked photodiodes only; use {fitting}"))
