"""The optimiser: L-BFGS-B (SciPy) on the model's objective with Dr.Jit's exact gradient, inside the variables'
bounds; every evaluation (objective + gradient over all training colours × lights) is counted and recorded."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Callable

    from spectracam.experiments.design.problem import DesignProblem

__all__ = ["Optimisation", "optimise"]


@dataclass
class Optimisation:
    """The result: the best design found, its objective, and the history of every evaluation."""

    x: np.ndarray
    objective: float
    training_delta_e: float
    evaluations: int
    iterations: int
    message: str
    history: list = field(default_factory=list)   # per evaluation: (objective, training ΔE)


def optimise(problem: DesignProblem, x0: np.ndarray | None = None, max_iterations: int = 80, tolerance: float = 1e-7,
             log: Callable[[str], object] = lambda m: None, progress: bool = False) -> Optimisation:
    """Minimise ``problem``'s objective from ``x0`` (default: its start) with L-BFGS-B; ``progress``: a bar
    over the iterations on a terminal (it only counts: the optimiser's steps are the same).

    Parameters
    ----------
    problem : DesignProblem
        Its ``value_and_gradient``, ``initial`` and ``bounds``.
    x0 : ndarray or None
        The start; None: ``problem.initial()``.
    max_iterations : int
        L-BFGS-B's ``maxiter``; reaching it is reported as the budget, not a failure.
    tolerance : float
        L-BFGS-B's ``ftol``.
    log : callable
        ``log(line)``: one line at the end (evaluations, iterations, training error, why it stopped).
    progress : bool
        A bar over the iterations on a terminal.

    Returns
    -------
    Optimisation
        The best design evaluated (not necessarily the last), its objective and training error, and the history.
    """
    from scipy.optimize import minimize

    from spectracam.core.progress import bar

    history = []
    best = {"v": np.inf, "x": None, "de": None}

    def f(x):
        v, g, de = problem.value_and_gradient(x)
        history.append((v, de))
        if v < best["v"]:
            best.update(v=v, x=np.array(x, float), de=de)
        return v, g

    x0 = problem.initial() if x0 is None else np.asarray(x0, float)
    with bar(total=int(max_iterations), desc=f"{problem.design} iterations", unit="it", progress=progress) as b:
        res = minimize(f, x0, jac=True, method="L-BFGS-B", bounds=problem.bounds(),
                       options={"maxiter": int(max_iterations), "ftol": float(tolerance), "gtol": 1e-9},
                       callback=(lambda xk: b.update(1)) if progress else None)
    msg = res.message if isinstance(res.message, str) else res.message.decode()
    # L-BFGS-B's status 1 ("STOP: TOTAL NO. OF ITERATIONS REACHED LIMIT", or its evaluations' limit) is the budget
    # asked for, not a failure
    why = f"stopped at the budget of {int(max_iterations)} iterations" if res.status == 1 else msg
    log(f"{problem.design}: {len(history)} evaluations, {res.nit} iterations, training "
        f"{'S-CIELAB' if getattr(problem, 'score', 'delta_e') == 's_cielab' else 'ΔE'} {best['de']:.4f} ({why})")
    return Optimisation(best["x"], float(best["v"]), float(best["de"]), len(history), int(res.nit), msg, history)
