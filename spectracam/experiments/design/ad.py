"""Automatic differentiation for the design: Dr.Jit's LLVM backend (installed with Mitsuba), double precision.

The expected-error model is written on :data:`Tensor` (``drjit.llvm.ad.TensorXf64``): numpy-like tensors with
broadcasting whose gradients :func:`value_and_gradient` returns.  Small matrices (the N×3 conversion, a 3×3
covariance) are Python lists of tensors, one per entry, each holding every colour at once.  Dr.Jit's LLVM backend
(drjit 1.5) needs libLLVM 19 — with libLLVM 15 the first kernel it runs aborts the process; where it is missing
the design refuses with one line instead of aborting.
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from spectracam.core.errors import SpectracamError

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from types import ModuleType

    from numpy.typing import ArrayLike

__all__ = ["LAB_EPSILON", "backend", "cholesky3", "fresh", "lab_f", "numpy", "solve_spd", "tensor",
           "value_and_gradient", "xyz_to_lab"]

#: CIE 1976 L*a*b*: the linear segment below (6/29)³ (CIE 015:2018, 8.2.1; colour-science's
#: ``intermediate_lightness_function_CIE1976``).
LAB_EPSILON = (6.0 / 29.0) ** 3

_DR = None


def backend() -> tuple[ModuleType, type]:
    """``(drjit, Tensor)``: Dr.Jit with its LLVM AD backend, libLLVM 19 found first (or one clear error).

    Returns
    -------
    tuple of (module, type)
        ``drjit`` and ``drjit.llvm.ad.TensorXf64``, imported once.

    Raises
    ------
    SpectracamError
        When libLLVM 19 is not found (and ``DRJIT_LIBLLVM_PATH`` is not set) or Dr.Jit cannot start.
    """
    global _DR
    if _DR is None:
        from spectracam.render.mitsuba import find_libllvm19

        if "DRJIT_LIBLLVM_PATH" not in os.environ:
            lib = find_libllvm19()
            if lib is None:
                raise SpectracamError("design: Dr.Jit's LLVM backend needs libLLVM 19 (Debian: apt-get install "
                                      "libllvm19, as tools/setup.sh does) or DRJIT_LIBLLVM_PATH naming it; none found")
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
        try:
            import drjit as dr
            from drjit.llvm.ad import TensorXf64
        except (ImportError, RuntimeError) as e:
            raise SpectracamError(f"design: Dr.Jit's LLVM backend cannot start here ({e})") from None
        _DR = (dr, TensorXf64)
    return _DR


def tensor(values: ArrayLike) -> Any:
    """A constant Dr.Jit tensor (float64) of a numpy array or number.

    Parameters
    ----------
    values : array_like
        The values, any shape.

    Returns
    -------
    TensorXf64
        The same shape, float64, without gradient tracking.
    """
    _, T = backend()
    return T(np.ascontiguousarray(np.asarray(values, np.float64)))


def numpy(x: Any) -> np.ndarray:
    """The value of a tensor (or number) as a float64 numpy array.

    Parameters
    ----------
    x : TensorXf64 or array_like
        A Dr.Jit tensor or anything numpy reads.

    Returns
    -------
    ndarray
        float64, the tensor's shape.
    """
    return np.asarray(x.numpy() if hasattr(x, "numpy") else x, np.float64)


def fresh(x: Any) -> Any:
    """A new view of a one-element tensor, to combine with a larger one.  Dr.Jit 1.5 widens a one-element
    tensor's array in place when it is broadcast against a larger tensor, which breaks its next use (checked
    on this machine); a fresh view absorbs that.  Anything else is returned as is.

    Parameters
    ----------
    x : TensorXf64 or object
        A tensor or anything else.

    Returns
    -------
    TensorXf64 or object
        A new tensor on the same array for a tensor of shape ``()`` or ``(1,)``; ``x`` otherwise.
    """
    _, T = backend()
    if isinstance(x, T) and x.shape in ((), (1,)):
        return T(x.array, x.shape)
    return x


def value_and_gradient(f: Callable[[Any], tuple[Any, Any]], x: np.ndarray) -> tuple[float, np.ndarray, Any]:
    """``(f(x), ∂f/∂x, aux)`` for ``f(tensor) → (scalar tensor, aux)``, the gradient by Dr.Jit's reverse mode.

    Parameters
    ----------
    f : callable
        ``f(tensor) → (scalar tensor, aux)``, written on Dr.Jit operations.
    x : ndarray
        The point, any shape.

    Returns
    -------
    value : float
        ``f(x)``.
    gradient : ndarray
        ``∂f/∂x``, float64, ``x``'s shape.
    aux : object
        What ``f`` returned beside its value.
    """
    dr, _ = backend()
    xt = tensor(x)
    dr.enable_grad(xt)
    value, aux = f(xt)
    dr.backward(value)
    g = numpy(dr.grad(xt))
    return float(numpy(value).reshape(-1)[0]), g.reshape(np.shape(x)), aux


def lab_f(t: Any) -> Any:
    """CIE 1976's f(t): ∛t above :data:`LAB_EPSILON`, linear below (also for t < 0, as colour-science).

    Parameters
    ----------
    t : TensorXf64
        A tristimulus value over its white's.

    Returns
    -------
    TensorXf64
        f(t), ``t``'s shape.
    """
    dr, _ = backend()
    return dr.select(t > LAB_EPSILON, dr.cbrt(dr.maximum(t, LAB_EPSILON)), t * (841.0 / 108.0) + 4.0 / 29.0)


def xyz_to_lab(X: Any, Y: Any, Z: Any, white: np.ndarray) -> tuple[Any, Any, Any]:
    """L*, a*, b* of tensors X, Y, Z relative to ``white`` (any scale; as :func:`spectracam.core.cielab.xyz_to_lab`).

    Parameters
    ----------
    X, Y, Z : TensorXf64
        Tristimulus values, on the white's scale.
    white : ndarray
        ``(3,)`` the white's XYZ.

    Returns
    -------
    tuple of TensorXf64
        ``(L*, a*, b*)``, each ``X``'s shape.
    """
    w = [float(v) for v in white]
    fx, fy, fz = lab_f(X / w[0]), lab_f(Y / w[1]), lab_f(Z / w[2])
    return 116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)


def cholesky3(C: Sequence[Sequence[Any]]) -> tuple[tuple[Any, Any, Any], ...]:
    """Lower-triangular L with L·Lᵀ = C for a 3×3 symmetric positive-definite C given as nested lists of tensors
    (every colour's matrix at once).

    Parameters
    ----------
    C : sequence of sequence of TensorXf64
        ``C[i][j]``, 3×3; only the lower triangle is read.

    Returns
    -------
    tuple of tuple
        ``L[i][j]`` as tensors, None above the diagonal.
    """
    dr, _ = backend()
    l00 = dr.sqrt(C[0][0])
    l10, l20 = C[1][0] / l00, C[2][0] / l00
    l11 = dr.sqrt(dr.maximum(C[1][1] - l10 * l10, 0.0) + 1e-300)
    l21 = (C[2][1] - l20 * l10) / l11
    l22 = dr.sqrt(dr.maximum(C[2][2] - l20 * l20 - l21 * l21, 0.0) + 1e-300)
    return ((l00, None, None), (l10, l11, None), (l20, l21, l22))


def solve_spd(A: Sequence[Sequence[Any]], b: Sequence[Sequence[Any]]) -> list[list[Any]]:
    """x with A·x = b for a small symmetric positive-definite A (nested lists of scalar tensors) and b (a list of
    columns, each a list of scalar tensors): Cholesky, forward and back substitution.

    Parameters
    ----------
    A : sequence of sequence of TensorXf64
        ``A[i][j]``, n×n; only the lower triangle is read.
    b : sequence of sequence of TensorXf64
        The right-hand sides, column by column, each of n entries.

    Returns
    -------
    list of list of TensorXf64
        ``x`` column by column, as ``b``.
    """
    dr, _ = backend()
    n = len(A)
    L = [[None] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = A[i][j]
            for k in range(j):
                s = s - L[i][k] * L[j][k]
            L[i][j] = dr.sqrt(s) if i == j else s / L[j][j]
    out = []
    for col in b:
        y = []
        for i in range(n):
            s = col[i]
            for k in range(i):
                s = s - L[i][k] * y[k]
            y.append(s / L[i][i])
        x = [None] * n
        for i in reversed(range(n)):
            s = y[i]
            for k in range(i + 1, n):
                s = s - L[k][i] * x[k]
            x[i] = s / L[i][i]
        out.append(x)
    return out
