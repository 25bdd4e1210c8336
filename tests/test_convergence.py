"""Exact spectral integration: the paper's numbers converge with the wavelength step (issue 10)."""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))
from spectral_convergence import compare, run  # noqa: E402


def test_analytic_numbers_converge_between_10_and_1_nm():
    rows = compare(run(10.0, "analytic", quick=True), run(1.0, "analytic", quick=True))
    # band edges on the stated limits, exact colorimetry: 0.07 % measured; a grid reaching 5 nm past
    # the limits (the old one) moved them by up to 1.1 %
    assert rows[0][3] < 0.003, rows[:3]


def test_mitsuba_numbers_converge_between_10_and_2_nm():
    # 96x72 px and 2-nm bands keep this to ~10 s; the noise-free steps of Figure 6 measure the
    # render's Monte Carlo noise, which falls as the bands (each with its own samples) multiply
    small = ["image.width=96", "image.height=72"]
    coarse, fine = run(10.0, "mitsuba", False, small), run(2.0, "mitsuba", False, small)
    rows = compare(coarse, fine, skip=("fig6 perfect", "fig6 shot_noise"))
    assert rows[0][3] < 0.003, rows[:3]
    assert fine["fig6 perfect"] < coarse["fig6 perfect"] < 0.15
