"""When a capture is no usable image: the rule that keeps a comparison from naming a winner among pictures nobody
could use (docs/metrics.md, "Usable image").

A case is **usable** when both hold (each a stated threshold, an option with its default):

* the white patch's rendered luminance SNR (:attr:`~spectracam.evaluation.score.ChartSummary.snr_white_rendered_db`, the noise a
  viewer sees after the colour conversion) is at least ``min_white_snr_db`` — 20 dB, ISO 12232's lowest
  "acceptable" noise criterion (a luminance SNR of 10); asked of the white, the brightest patch, so a capture that
  fails it has no part that meets the standard's minimum (``None``: noise-free, or no defined SNR: the ΔE rule
  decides);
* the chart's mean S-CIELAB ΔE*ab (:attr:`~spectracam.evaluation.score.ChartSummary.s_cielab_mean`) is at most
  ``max_s_cielab_mean`` — 40, the error of an image that shows every patch as one flat grey of the chart's mean
  lightness (ΔE*ab 40.8 under D65, 42.1 under a 3000 K blackbody, 40.8 at 7000 K; S-CIELAB equals CIELAB on such
  uniform patches): a capture further from the scene than that carries less colour than no picture at all.  S-CIELAB,
  not the per-pixel ΔE*ab, because the per-pixel score counts noise the eye does not see: the stacked sensor at the
  paper's light, developed under 3000 K, scores a per-pixel ΔE*ab of 40.0 and an S-CIELAB of 4.9 — a noisy-looking
  number for a picture a viewer would accept.

Unusable cases stay in the results (``usable``: false and ``unusable_reason``) and in the figures (greyed), but
are never named as a winner: where no case of a group is usable, the winner is "no usable image".
"""
from __future__ import annotations

from dataclasses import dataclass

from spectracam.core.spec import Spec

__all__ = ["MAX_S_CIELAB_MEAN", "MIN_WHITE_SNR_DB", "NO_USABLE_IMAGE", "UsabilitySpec"]

#: ISO 12232's "acceptable" noise-based criterion: luminance SNR 10, in dB.
MIN_WHITE_SNR_DB = 20.0
#: The chart's ΔE*ab when every patch is shown as a flat grey of the chart's mean lightness (≈ 41).
MAX_S_CIELAB_MEAN = 40.0
#: What a winners table says where no case is usable.
NO_USABLE_IMAGE = "no usable image"


@dataclass(frozen=True)
class UsabilitySpec(Spec):
    """The thresholds below which a case is no usable image (module docstring)."""

    TABLE = "usability"

    min_white_snr_db: float = MIN_WHITE_SNR_DB
    max_s_cielab_mean: float = MAX_S_CIELAB_MEAN

    def validate(self) -> None:
        # -20 dB (noise 10× the white) admits anything; 60 dB is beyond a 1e6-e⁻ well's shot noise
        self.number("min_white_snr_db", -20.0, 60.0, unit="dB")
        # a ΔE*ab of 0.5 is below the just-noticeable difference (~1–2.3): no capture with noise would pass
        self.number("max_s_cielab_mean", 0.5, 1000.0)

    def judge(self, s_cielab_mean: float | None, snr_white_db: float | None) -> tuple[bool, str]:
        """``(usable, reason)``: the reason names each failed threshold ("" when usable).

        Parameters
        ----------
        s_cielab_mean : float or None
            The capture's mean S-CIELAB ΔE; None (undefined) fails.
        snr_white_db : float or None
            The white patch's SNR, dB; None (noise-free) passes.

        Returns
        -------
        usable : bool
            Whether every threshold is met.
        reason : str
            Each failed threshold, ``"; "``-separated.
        """
        reasons = []
        if snr_white_db is not None and snr_white_db < self.min_white_snr_db:
            reasons.append(f"white-patch SNR {snr_white_db:.1f} dB < {self.min_white_snr_db:g} dB")
        if s_cielab_mean is None or not s_cielab_mean <= self.max_s_cielab_mean:
            reasons.append("mean S-CIELAB " + ("undefined" if s_cielab_mean is None else f"{s_cielab_mean:.1f}")
                           + f" > {self.max_s_cielab_mean:g}")
        return not reasons, "; ".join(reasons)
