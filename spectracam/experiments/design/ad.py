"""Automatic differentiation for the design: Dr.Jit's LLVM backend (installed with Mitsuba), double precision.

The expected-error model is written on :data:`Tensor` (``drjit.llvm.ad.TensorXf64``): numpy-like tensors with
broadcasting whose gradients :func:`value_and_gradient` returns.  Small matrices (the N×3 conversion, a 3×3
covariance) are Python lists of tensors, one per entry, each holding every colour at once.  Dr.Jit's LLVM backend
(drjit 1.5) needs libLLVM 19 — with libLLVM 15 the first kernel it runs aborts the process; where it is missing
the design refuses with one line instead of aborting.
"""
from __future__ import annotations

import os

import numpy as np

from spectracam.core.errors import SpectracamError

__all__ = ["LAB_EPSILON", "backend", "cholesky3", "fresh", "lab_f", "numpy", "solve_spd", "tensor",
           "value_and_gradient", "xyz_to_lab"]

#: CIE 1976 L*a*b*: the linear segment below (6/29)³ (CIE 015:2018, 8.2.1; colour-science's
#: ``intermediate_lightness_function_CIE1976``).
LAB_EPSILON = (6.0 / 29.0) ** 3

_DR = None


def backend():
    """``(drjit, Tensor)``: Dr.Jit with its LLVM AD backend, libLLVM 19 found first (or one clear error)."""
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


def tensor(values) -> object:
    """A constant Dr.Jit tensor (float64) of a numpy array or number."""
    _, T = backend()
    return T(np.ascontiguousarray(np.asarray(values, np.float64)))


def numpy(x) -> np.ndarray:
    """The value of a tensor (or number) as a float64 numpy array."""
    return np.asarray(x.numpy() if hasattr(x, "numpy") else x, np.float64)


def fresh(x):
    """A new view of a one-element tensor, to combine with a larger one.  Dr.Jit 1.5 widens a one-element
    tensor's array in place when it is broadcast against a larger tensor, which breaks its next use (checked
    on this machine); a fresh view absorbs that.  Anything else is returned as is."""
    _, T = backend()
    if isinstance(x, T) and x.shape in ((), (1,)):
        return T(x.array, x.shape)
    return x


def value_and_gradient(f, x: np.ndarray):
    """``(f(x), ∂f/∂x, aux)`` for ``f(tensor) → (scalar tensor, aux)``, the gradient by Dr.Jit's reverse mode."""
    dr, _ = backend()
    xt = tensor(x)
    dr.enable_grad(xt)
    value, aux = f(xt)
    dr.backward(value)
    g = numpy(dr.grad(xt))
    return float(numpy(value).reshape(-1)[0]), g.reshape(np.shape(x)), aux


def lab_f(t):
    """CIE 1976's f(t): ∛t above :data:`LAB_EPSILON`, linear below (also for t < 0, as colour-science)."""
    dr, _ = backend()
    return dr.select(t > LAB_EPSILON, dr.cbrt(dr.maximum(t, LAB_EPSILON)), t * (841.0 / 108.0) + 4.0 / 29.0)


def xyz_to_lab(X, Y, Z, white: np.ndarray):
    """L*, a*, b* of tensors X, Y, Z relative to ``white`` (any scale; as :func:`spectracam.core.cielab.xyz_to_lab`)."""
    w = [float(v) for v in white]
    fx, fy, fz = lab_f(X / w[0]), lab_f(Y / w[1]), lab_f(Z / w[2])
    return 116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)


def cholesky3(C):
    """Lower-triangular L with L·Lᵀ = C for a 3×3 symmetric positive-definite C given as nested lists of tensors
    (every colour's matrix at once)."""
    dr, _ = backend()
    l00 = dr.sqrt(C[0][0])
    l10, l20 = C[1][0] / l00, C[2][0] / l00
    l11 = dr.sqrt(dr.maximum(C[1][1] - l10 * l10, 0.0) + 1e-300)
    l21 = (C[2][1] - l20 * l10) / l11
    l22 = dr.sqrt(dr.maximum(C[2][2] - l20 * l20 - l21 * l21, 0.0) + 1e-300)
    return ((l00, None, None), (l10, l11, None), (l20, l21, l22))


def solve_spd(A, b):
    """x with A·x = b for a small symmetric positive-definite A (nested lists of scalar tensors) and b (a list of
    columns, each a list of scalar tensors): Cholesky, forward and back substitution."""
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
