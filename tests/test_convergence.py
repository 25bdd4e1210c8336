"""Exact spectral integration: the paper's numbers converge with the wavelength step (issue 10)."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))
from spectral_convergence import compare, run  # noqa: E402


def test_analytic_numbers_converge_between_10_and_1_nm():
    rows = compare(run(10.0, "analytic", quick=True), run(1.0, "analytic", quick=True))
    # band edges on the stated limits, exact colorimetry: 0.12 % measured (0.116 %); a grid reaching 5 nm past
    # the limits (the old one) moved them by up to 1.1 %
    assert rows[0][3] < 0.003, rows[:3]


def test_mitsuba_numbers_converge_between_10_and_2_nm():
    # 96x72 px and 2-nm bands keep this to ~10 s.  Mitsuba renders each band from light-weighted
    # band-constant spectra (issue 17), so no Monte Carlo noise from sampling wavelengths is left in
    # a patch's pixels: every number, SNRs included, is held like the analytic renderer's, and
    # Figure 6's noise-free step is zero up to float32 rounding at both steps (it was 0.07 ΔE).
    small = ["image.width=96", "image.height=72"]
    coarse, fine = run(10.0, "mitsuba", False, small), run(2.0, "mitsuba", False, small)
    rows = compare(coarse, fine, skip=("fig6 perfect",))  # ~0: a relative change means nothing
    assert rows[0][3] < 0.003, rows[:3]
    assert fine["fig6 perfect"] < 1e-3 and coarse["fig6 perfect"] < 1e-3
