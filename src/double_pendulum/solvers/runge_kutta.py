"""Explicit Runge-Kutta methods over Python lists of floats.

Each method keeps the contract of :mod:`double_pendulum.solvers.method` (:class:`~.method.Method`,
adaptive ones :class:`~.method.AdaptiveMethod`), which the integrator in
:mod:`double_pendulum.solvers.integrator` drives: ``step``, ``interpolant`` (dense output),
``error_norm`` (adaptive methods), and the attributes ``name``, ``adaptive``, ``order``,
``error_order`` (``None`` for a fixed step), ``dense_order``, ``evals_per_step``, ``dense_evals``,
``n_stages``.
The implicit methods are in :mod:`.rosenbrock` (stiff) and :mod:`.gauss` (symplectic).

Lists of floats are used instead of NumPy arrays: for a state of 4 to 11 components a Python
float loop is several times cheaper per step than NumPy's per-call overhead.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import partial

from . import tableaus as tb
from .combinations import (
    alternating_horner,
    dense_columns,
    explicit_stages,
    scaled_error_norm,
    sparse,
    step_combination,
    two_estimate_error_norm,
    weighted_sum,
)
from .method import AdaptiveMethod, Method, VectorField

SparseRows = Sequence[Sequence[tuple[int, float]]]


_KERNELS: dict[tuple[int, int, str], Callable] = {}


def _tableau_kernel(key: object, n: int, kind: str, build: Callable[[], Callable]) -> Callable:
    """The compiled ``kind`` of kernel of a *module-level constant* tableau part ``key`` for state size
    ``n``, built once.

    Cached by the constant's identity (a tableau lives as long as the module, so an identity is never
    reused for other coefficients): finding it costs one small dict look-up, not the hash of a whole
    tableau.
    """
    kernel = _KERNELS.get((id(key), n, kind))
    if kernel is None:
        kernel = _KERNELS[(id(key), n, kind)] = build()
    return kernel


def _constant_kernel(row: Sequence, n: int, *, dense_weights: bool = False) -> Callable:
    """Compiled combination for a module-level constant ``row`` (:func:`_tableau_kernel`).

    Sparse rows ``((j, a_j), ...)`` give ``g(y, h, ks) = y + h sum_j a_j k_j``; dense weights
    (``dense_weights=True``) give ``g(ks) = sum_j w_j k_j``.
    """
    if dense_weights:
        return _tableau_kernel(row, n, "weights", lambda: weighted_sum(sparse(row), n))
    return _tableau_kernel(row, n, "step", lambda: step_combination(tuple(row), n))


def _stage_input(y: list[float], h: float, row: Sequence[tuple[int, float]], ks: list[list[float]]) -> list[float]:
    """Return ``y + h * sum_j a_ij k_j`` for one sparse tableau row (any row; cached by content)."""
    return step_combination(row if isinstance(row, tuple) else tuple(row), len(y))(y, h, ks)


def _stages(a: SparseRows, c: Sequence[float], n_stages: int, b: SparseRows, n: int) -> Callable:
    """:func:`~double_pendulum.solvers.combinations.explicit_stages` of a module-level tableau."""
    return _tableau_kernel(a, n, "stages", lambda: explicit_stages(a, tuple(c), n_stages, b, n))


_DOPRI5_B_ROW = sparse(tb.DOPRI5_B)
_DOPRI5_E_ROW = sparse(tb.DOPRI5_E)
_DOP853_B_ROW = sparse(tb.DOP853_B)
_DOP853_E5_ROW = sparse(tb.DOP853_E5)
_DOP853_E3_ROW = sparse(tb.DOP853_E3)
_DOP853_EXTRA_STAGES = tuple((i, tuple(tb.DOP853_A[i]), tb.DOP853_C[i]) for i in (13, 14, 15))
_DOP853_D_ROWS = tuple(sparse(row) for row in tb.DOP853_D)
_RK4_B_ROW = sparse(tb.RK4_B)
_DOPRI5_P_COLUMNS = tuple(tuple(row[k] for row in tb.DOPRI5_P) for k in range(len(tb.DOPRI5_P[0])))


def scaled_rms(err: list[float], y: list[float], y_new: list[float], rtol: float, atol: float) -> float:
    """Return ``sqrt(mean((err_i / (atol + rtol * max(|y_i|, |y_new_i|)))^2))``."""
    total = 0.0
    for e, u, v in zip(err, y, y_new):
        s = atol + rtol * max(abs(u), abs(v))
        total += (e / s) ** 2
    return math.sqrt(total / len(err))


class Dopri5(AdaptiveMethod):
    """Dormand-Prince 5(4) pair, FSAL, with Shampine's 4th-order dense output."""

    name = "dopri5"
    adaptive = True
    order = 5
    error_order = 4
    dense_order = 4
    evals_per_step = 6  # the 7th stage is f_new, reused as the next step's first stage
    n_stages = 7  # the six stages and f_new
    dense_evals = 0

    def step(self, f: VectorField, t: float, y: list[float], fy: list[float], h: float):
        y_new, ks = _stages(tb.DOPRI5_A, tb.DOPRI5_C, 6, _DOPRI5_B_ROW, len(y))(f, t, y, fy, h)
        f_new = f(t + h, y_new)
        ks.append(f_new)
        return y_new, f_new, ks

    def error_norm(self, y, y_new, ks, h, rtol, atol) -> float:
        norm = _tableau_kernel(_DOPRI5_E_ROW, len(y), "norm", lambda: scaled_error_norm(_DOPRI5_E_ROW, len(y)))
        return norm(y, y_new, ks, h, rtol, atol)

    def interpolant(self, f, t, y, y_new, fy, f_new, h, ks):
        # y(t + theta h) = y + h * sum_k Q[:, k] theta^(k+1), Q = K^T P
        q = [_constant_kernel(column, len(y), dense_weights=True)(ks) for column in _DOPRI5_P_COLUMNS]

        def evaluate(theta: float) -> list[float]:
            p1, p2, p3, p4 = theta, theta**2, theta**3, theta**4
            return [yc + h * (q0 * p1 + q1 * p2 + q2 * p3 + q3 * p4) for yc, q0, q1, q2, q3 in zip(y, *q)]

        return evaluate


class Dop853(AdaptiveMethod):
    """Hairer's DOP853: 8th-order propagation, 5th/3rd-order error estimates, 7th-order dense output."""

    name = "dop853"
    adaptive = True
    order = 8
    error_order = 7
    dense_order = 7
    evals_per_step = 12
    n_stages = 13  # twelve and f_new (twelve while f_new is deferred)
    dense_evals = 3
    deferrable_f_new = True  # the error estimate does not use f(t + h, y_new)
    landing_method = Dopri5()  # short landing steps (see double_pendulum.solvers.integrator)

    def step(self, f: VectorField, t: float, y: list[float], fy: list[float], h: float, *, with_f_new: bool = True):
        """One step; ``with_f_new=False`` skips ``f(t + h, y_new)`` (returned as ``None``, not in the stages).

        The caller then evaluates it when needed (next step, dense output) and appends it to the
        stages, or never, if the right-hand side changes at ``t + h`` (a restart).
        """
        y_new, ks = _stages(tb.DOP853_A, tb.DOP853_C, 12, _DOP853_B_ROW, len(y))(f, t, y, fy, h)
        if not with_f_new:
            return y_new, None, ks
        f_new = f(t + h, y_new)
        ks.append(f_new)
        return y_new, f_new, ks

    def error_norm(self, y, y_new, ks, h, rtol, atol) -> float:
        n = len(y)
        build = partial(two_estimate_error_norm, _DOP853_E5_ROW, _DOP853_E3_ROW, n)
        return _tableau_kernel(tb.DOP853_E5, n, "norm", build)(y, y_new, ks, h, rtol, atol)

    def interpolant(self, f, t, y, y_new, fy, f_new, h, ks):
        n = len(y)
        dense = _tableau_kernel(tb.DOP853_D, n, "dense", lambda: dense_columns(_DOP853_EXTRA_STAGES, _DOP853_D_ROWS, n))
        columns = dense(f, t, y, y_new, fy, f_new, h, ks)  # per component: its 7 coefficients, highest first
        # y + F0 x + F1 x(1-x) + F2 x^2(1-x) + ..., Horner-like with factors alternating x and 1-x
        return partial(alternating_horner(n, 7), columns, y)


class ClassicRK4(Method):
    """The classic 4th-order Runge-Kutta method (fixed step), cubic Hermite dense output."""

    name = "rk4"
    adaptive = False
    order = 4
    error_order = None
    dense_order = 3
    evals_per_step = 4  # f_new is the next step's first stage
    n_stages = 4
    dense_evals = 0

    def step(self, f: VectorField, t: float, y: list[float], fy: list[float], h: float):
        y_new, ks = _stages(tb.RK4_A, tb.RK4_C, 4, _RK4_B_ROW, len(y))(f, t, y, fy, h)
        return y_new, f(t + h, y_new), ks

    def interpolant(self, f, t, y, y_new, fy, f_new, h, ks):
        return hermite_interpolant(y, y_new, fy, f_new, h)


class ExplicitEuler(Method):
    """Explicit Euler (first order, fixed step): the seed report's scheme, for comparison only."""

    name = "euler"
    adaptive = False
    order = 1
    error_order = None
    dense_order = 1
    evals_per_step = 1
    n_stages = 1  # fy
    dense_evals = 0

    def step(self, f: VectorField, t: float, y: list[float], fy: list[float], h: float):
        y_new = [u + h * d for u, d in zip(y, fy)]
        return y_new, f(t + h, y_new), [fy]

    def interpolant(self, f, t, y, y_new, fy, f_new, h, ks):
        def evaluate(theta: float) -> list[float]:
            return [u + theta * (v - u) for u, v in zip(y, y_new)]

        return evaluate


def hermite_interpolant(y, y_new, fy, f_new, h):
    """Cubic Hermite interpolation on a step from the end values and derivatives (3rd order)."""

    def evaluate(theta: float) -> list[float]:
        t2 = theta * theta
        t3 = t2 * theta
        h00 = 2.0 * t3 - 3.0 * t2 + 1.0
        h10 = t3 - 2.0 * t2 + theta
        h01 = -2.0 * t3 + 3.0 * t2
        h11 = t3 - t2
        return [h00 * u + h * h10 * du + h01 * v + h * h11 * dv for u, v, du, dv in zip(y, y_new, fy, f_new)]

    return evaluate
