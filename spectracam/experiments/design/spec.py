"""A design file (``scenes/design.toml``): which cameras to design, on which colours and lights, how.

Every key is checked here, before any work, and a bad one is refused in one line naming it, its value and what
is allowed.  The camera, processing and light level come from a paper experiment file (``experiment``), so a
design is made "at the paper's light and noise"; ``--set key=value`` changes any key.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from spectracam.core.errors import ConfigError
from spectracam.scene.reflectances import LIBRARIES, check_available
from spectracam.core.spec import Spec
from spectracam.experiments.design.variables import PARAMETRISATIONS

if TYPE_CHECKING:
    from collections.abc import Iterable

__all__ = ["DESIGN_KEYS", "DESIGN_OBJECTIVES", "DESIGN_WHITE_BALANCES", "QUICK", "DesignSpec", "load_design"]

#: Keys of a design file.
DESIGN_KEYS = ("experiment", "lights", "training", "held_out", "designs", "filters", "start_cutoffs_nm",
               "edge_width_nm", "start_centres_nm", "start_fwhm_nm", "knot_step_nm", "min_transmittance",
               "smoothness", "design_ir_cut", "start_ir_cut_nm", "snr_weight", "max_iterations", "tolerance",
               "seeds", "renderer", "image_px", "grid", "luther", "white_balance", "white_balance_p", "developed",
               "objective")


#: What the design minimises (:attr:`DesignSpec.objective`): the expected per-pixel ΔE*ab (the paper's score) or the
#: expected S-CIELAB ΔE*ab (the eye's spatial filters after the demosaicker; docs/metrics.md, "Expected S-CIELAB in
#: the design model").
DESIGN_OBJECTIVES = ("delta_e", "s_cielab")

#: The whites the design's model can balance by (:attr:`DesignSpec.white_balance`).
DESIGN_WHITE_BALANCES = ("oracle", "grey_world", "shades_of_grey")


@dataclass(frozen=True)
class DesignSpec(Spec):
    """What ``spectracam design`` designs (scenes/design.toml explains each key)."""

    TABLE = ""

    #: The paper experiment file whose camera, processing and calibrated light level the designs use.
    experiment: str = "paper.toml"
    #: Training lights: numbers are blackbody temperatures (K), strings CIE illuminants colour-science ships.
    lights: tuple = (3000, 5000, 6500, "D65")
    #: Reflectance library the designs are optimised on (mean expected ΔE over its samples × the lights).
    training: str = "rawtoaces190"
    #: Library every design is scored on and never optimised on.
    held_out: str = "cfi99"
    #: "architecture/exposure" of each design; "fsc/split" and "prism/split" design the exposure split too.
    designs: tuple = ("cfa/single", "prism/optimal", "fsc/optimal", "fsc/split", "stacked/single", "rgbw/single",
                      "ryyb/single", "cmy/single", "quad_bayer/single")
    #: How the filters are designed: block, gaussian or freeform (stacked photodiodes: always their depths).
    filters: str = "freeform"
    start_cutoffs_nm: tuple = (490.0, 610.0)
    edge_width_nm: float = 0.0
    start_centres_nm: tuple = (610.0, 540.0, 460.0)
    start_fwhm_nm: tuple = (100.0, 100.0, 100.0)
    knot_step_nm: float = 10.0
    #: No real dye blocks completely: the free-form transmittances' floor.
    min_transmittance: float = 0.02
    #: Weight of the free-form curves' smoothness penalty (mean squared second difference per (10 nm)²).
    smoothness: float = 1.0
    design_ir_cut: bool = False
    start_ir_cut_nm: float = 680.0
    #: ΔE per dB of mean combined SNR traded in the objective (0: ΔE alone).
    snr_weight: float = 0.0
    #: The expected error minimised: "delta_e" (per-pixel ΔE*ab on a flat patch, the paper's Figure 5b) or
    #: "s_cielab" (the same after the eye's S-CIELAB filters at the experiment's viewing geometry, so a demosaicker's
    #: averaging of neighbours counts only as far as the eye would not see the noise anyway).  Both are reported.
    objective: str = "delta_e"
    #: The white the objective's camera balances by (issue 33): "oracle" (told the light: the paper's) or an
    #: estimator the model differentiates through — "grey_world" or "shades_of_grey" (Minkowski p =
    #: white_balance_p) over training Mondrians of the training colours under each light: the expected ΔE then
    #: includes the estimator's error, so the filters are designed for a camera that must find its own white.
    white_balance: str = "oracle"
    white_balance_p: float = 6.0
    #: Also verify every design by Monte Carlo with the developed camera (its own metering, trained white balance,
    #: dual-illuminant calibration) beside the oracle.
    developed: bool = True
    max_iterations: int = 80
    #: L-BFGS-B stops when the objective changes by less than this (relative).
    tolerance: float = 1e-7
    #: Monte Carlo verification through the capture → score pipeline: seeds, renderer and image size.
    seeds: int = 3
    renderer: str = "mitsuba"
    image_px: tuple = (320, 240)
    #: Also evaluate the grid of block cutoffs (450–530 × 570–650 nm, 10 nm) with the model, and the Luther camera.
    grid: bool = True
    luther: bool = True

    def validate(self) -> None:
        from spectracam.render import RENDERERS

        self.string("experiment")
        self._check_lights()
        for k in ("training", "held_out"):
            v = getattr(self, k)
            if not isinstance(v, str) or not (v in LIBRARIES or (v.startswith("file:") and len(v) > 5)):
                raise self.error(k, "must be one of " + ", ".join(LIBRARIES) + " or 'file:PATH'")
        self._check_designs()
        self.choice("filters", PARAMETRISATIONS)
        if self.filters == "depths":
            raise self.error("filters", "must be block, gaussian or freeform (stacked photodiodes are always "
                                        "designed by their depths)")
        self.numbers("start_cutoffs_nm", 2, 300, increasing=True, unit="nm")
        self.number("edge_width_nm", 0, 200, unit="nm")
        self.numbers("start_centres_nm", 3, 300, unit="nm")
        self.numbers("start_fwhm_nm", 3, 10, unit="nm")
        self.number("knot_step_nm", 2, 100, unit="nm")
        self.number("min_transmittance", 0, 0.5)
        self.number("smoothness", 0, 1e6)
        self.boolean("design_ir_cut", "grid", "luther")
        self.number("start_ir_cut_nm", 550, 800, unit="nm")
        self.number("snr_weight", 0, 10)
        self.choice("objective", DESIGN_OBJECTIVES)
        self.choice("white_balance", DESIGN_WHITE_BALANCES)
        self.number("white_balance_p", 1, 16)
        self.boolean("developed")
        self.integer("max_iterations", 1, 10000)
        self.number("tolerance", 0, 1, lo_open=True)
        self.integer("seeds", 1, 100)
        self.choice("renderer", RENDERERS)
        px = self.image_px
        if not (isinstance(px, tuple) and len(px) == 2 and all(isinstance(v, int) and not isinstance(v, bool)
                                                                 and 64 <= v <= 4096 for v in px)):
            raise self.error("image_px", "must be [width, height], whole pixels 64–4096 each")

    def _check_lights(self) -> None:
        """Refuse lights that are not blackbody temperatures (1000–40000 K) or CIE illuminants colour-science ships."""
        lights = self.lights
        if not isinstance(lights, tuple) or not lights:
            raise self.error("lights", "must be a non-empty list of blackbody temperatures (K) and CIE illuminant "
                                       "names, e.g. [3000, 6500, 'D65']")
        from spectracam.core import colour_data

        names = colour_data.illuminant_names()
        for v in lights:
            ok = (isinstance(v, (int, float)) and not isinstance(v, bool) and 1000 <= v <= 40000) or \
                 (isinstance(v, str) and v in names)
            if not ok:
                raise self.error("lights", "each light must be a temperature 1000–40000 K or a CIE illuminant "
                                           "colour-science ships (e.g. 'D65', 'A', 'FL2')", v)

    def _check_designs(self) -> None:
        """Refuse designs that are not distinct 'architecture/exposure' pairs the architecture can expose."""
        from spectracam.architecture.base import ARCHITECTURES
        from spectracam.sensor.exposure import EXPOSURE_SCHEMES

        if not isinstance(self.designs, tuple) or not self.designs:
            raise self.error("designs", "must be a non-empty list like ['cfa/single', 'fsc/split']")
        for d in self.designs:
            arch, _, scheme = d.partition("/") if isinstance(d, str) else ("", "", "")
            if arch not in ARCHITECTURES or (scheme or "single") not in (*EXPOSURE_SCHEMES, "split"):
                raise self.error("designs", "each design is 'architecture/exposure' with an architecture of "
                                 + ", ".join(ARCHITECTURES) + " and an exposure of "
                                 + ", ".join(EXPOSURE_SCHEMES), d)
            if scheme in ("optimal", "balanced", "split") and not ARCHITECTURES[arch].independent_exposures:
                raise self.error("designs", f"the {arch} architecture has one exposure for all channels; use "
                                            f"'{arch}/single'", d)
        if len(set(self.designs)) != len(self.designs):
            raise self.error("designs", "lists a design twice")


#: ``--quick``: two lights, three designs, coarser free-form knots, fewer iterations and seeds, a small image.
QUICK = {"lights": (3000, 6500), "designs": ("cfa/single", "prism/optimal", "fsc/split"), "knot_step_nm": 20.0,
         "max_iterations": 25, "seeds": 2, "image_px": (160, 120), "training": "colorchecker24", "grid": False}


def load_design(path: str | Path, overrides: Iterable[str | tuple[str, object]] = (),
                quick: bool = False) -> tuple[DesignSpec, Path]:
    """A validated :class:`DesignSpec` from a design file (``overrides``: ``--set`` pairs, applied last; ``quick``:
    :data:`QUICK` before them); returns it and the directory its relative paths start from.

    Parameters
    ----------
    path : str or Path
        The design file.
    overrides : iterable of str or (str, object)
        ``KEY=VALUE`` strings or ``(key, value)`` pairs; each key must be one of :data:`DESIGN_KEYS`.
    quick : bool
        ``--quick``: :data:`QUICK`'s keys replace the file's (the file as written is validated first).

    Returns
    -------
    tuple of (DesignSpec, Path)
        The spec and the design file's directory.

    Raises
    ------
    ConfigError
        On an unknown key, an invalid value, or a colour library that is not available.
    """
    from spectracam.pipeline.overrides import apply_overrides, parse_assignment
    from spectracam.pipeline.scene_file import read_toml

    p = Path(path)
    t = read_toml(p, "design file")
    for k in t:
        if k not in DESIGN_KEYS:
            raise ConfigError(k, t[k], "unknown key; a design file has " + ", ".join(DESIGN_KEYS), str(p))
    DesignSpec.from_dict(t, str(p))   # the file as written is checked first, even when --quick replaces keys
    if quick:
        t = {**t, **{k: list(v) if isinstance(v, tuple) else v for k, v in QUICK.items()}}
    pairs = [parse_assignment(o) if isinstance(o, str) else o for o in overrides]
    for k, _ in pairs:
        if k.split("[")[0] not in DESIGN_KEYS:
            raise ConfigError(k, dict(pairs)[k], "unknown key; a design file has " + ", ".join(DESIGN_KEYS), str(p))
    t = apply_overrides(t, pairs)
    spec = DesignSpec.from_dict(t, str(p))
    for k in ("training", "held_out"):
        try:
            check_available(getattr(spec, k), k)
        except ConfigError as e:
            raise e.with_source(str(p)) from None
    return spec, p.parent
