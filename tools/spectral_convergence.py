"""How the paper's numbers depend on the wavelength step: run the experiment (no sensitivity
section) at several steps and print the largest relative differences against the finest.

    python3 tools/spectral_convergence.py [--renderer analytic|mitsuba] [--steps 10 5 1] [--full]

Quick (160x120) by default.  The "perfect system" step of Figure 6 is the Monte Carlo noise of the
render (0 for the analytic renderer); it is reported apart, in absolute terms.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def flatten(r: dict) -> dict[str, float]:
    """Every number of Figures 4-6 and the exposures, by a readable key."""
    v = {}
    for k in ("exposure_ms", "fig5a_snr_db", "fig5b_delta_e"):
        for d, per in r[k].items():
            for T, x in per.items():
                v[f"{k} {d} {T} K"] = x
    for s in r["fig6_budget_delta_e"]:
        v[f"fig6 {s['step']}"] = s["delta_e"]
    for d, per in r["fig4_white_response"].items():
        for T, x in per.items():
            for c, y in zip("RGB", x):
                v[f"fig4 {d} {T} K {c}"] = y
    return v


def run(step_nm: float, renderer: str, quick: bool, overrides=()) -> dict[str, float]:
    from spectracam.experiments.paper.experiment import load_experiment, run_paper

    exp = load_experiment(ROOT / "scenes" / "paper.toml", [f"wavelengths.step_nm={step_nm}", *overrides])
    r, _, _ = run_paper(dataclasses.replace(exp, alternatives=()), renderer=renderer, quick=quick, use_cache=False)
    return flatten(r)


def compare(coarse: dict, fine: dict, skip=("fig6 perfect",)) -> list[tuple[str, float, float, float]]:
    """``(key, coarse, fine, |relative difference|)``, largest first, ``skip`` left out."""
    rows = [(k, coarse[k], fine[k], abs(coarse[k] - fine[k]) / abs(fine[k])) for k in fine
            if k not in skip and fine[k]]
    return sorted(rows, key=lambda r: -r[3])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--renderer", default="analytic")
    ap.add_argument("--steps", type=float, nargs="+", default=[10.0, 5.0, 1.0])
    ap.add_argument("--full", action="store_true", help="640x480 instead of the quick 160x120")
    a = ap.parse_args()
    results = {}
    for st in a.steps:
        t = time.perf_counter()
        results[st] = run(st, a.renderer, not a.full)
        print(f"{st:g} nm: {time.perf_counter() - t:.1f} s", file=sys.stderr)
    fine = results[a.steps[-1]]
    for st in a.steps[:-1]:
        rows = compare(results[st], fine)
        print(f"{st:g} nm vs {a.steps[-1]:g} nm ({a.renderer}): largest relative difference "
              f"{100 * rows[0][3]:.3f} % ({rows[0][0]}: {rows[0][1]:.4f} vs {rows[0][2]:.4f}); "
              f"perfect-system residual {results[st]['fig6 perfect']:.4f} vs {fine['fig6 perfect']:.4f} ΔE")
        for k, c, f, d in rows[1:6]:
            print(f"    {k}: {c:.4f} vs {f:.4f} ({100 * d:.3f} %)")


if __name__ == "__main__":
    main()
