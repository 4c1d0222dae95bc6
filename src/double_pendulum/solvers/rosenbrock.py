r"""RODAS4: a stiffly accurate, L-stable Rosenbrock method of order 4(3) with dense output.

For the stiff scenes: a light, stiff suspension (``k`` = 1e6..1e8 N/m, ``M_s`` = 0.01..0.05 kg,
eigenvalues up to ~1e4..1e5 1/s) and bearing friction with a sharp regularisation ``omega_reg``
(viscous time scale ``I omega_reg / (c_R r_b |F|)``). Explicit methods are limited there by
stability, not accuracy: DOP853 needs ``h |lambda| <~ 6``, i.e. thousands of steps per second.

**Method** (E. Hairer, G. Wanner, Solving Ordinary Differential Equations II, 2nd ed.,
Springer 1996, section IV.7, eq. (7.4'), transformed form without matrix-vector products, and
section VI.4, the code RODAS). With ``J = df/dy(t, y)`` and ``f_t = df/dt(t, y)`` each stage
``u_i`` (i = 1..6) solves the linear system

.. math::

    \Big(\frac{1}{h\gamma} I - J\Big) u_i = f\Big(t + \alpha_i h,\ y + \sum_{j<i} a_{ij} u_j\Big)
        + \sum_{j<i} \frac{c_{ij}}{h} u_j + \gamma_i h f_t,

then ``y_new = y + sum_j a_6j u_j + u_6`` with ``a_6j = a_5j`` (j <= 4), ``a_65 = 1``: the
last two stages are evaluated at the end point (``alpha_5 = alpha_6 = 1``), so the method is
*stiffly accurate* (``y_new`` is the argument of a stage plus a correction) and L-stable
(``R(infinity) = 0``: unresolved stiff modes are damped out, not carried along). The embedded
3rd-order solution is ``y + sum_j a_5j u_j + u_5``, so the local error estimate is ``u_6``
itself. Dense output of order 3 (continuous extension of RODAS):

.. math::

    y(t + \theta h) \approx (1 - \theta) y + \theta\big(y_{new} + (1 - \theta)(q_1 + \theta q_2)\big),
    \quad q_1 = \sum_{j=1}^{5} d_{2j} u_j,\ q_2 = \sum_{j=1}^{5} d_{3j} u_j.

``gamma = 0.25``; the coefficients ``alpha, gamma_i, a_ij, c_ij, d_ij`` are those of Hairer's
RODAS (``rodas.f``, subroutine ``ROCOE``, ``METH = 1``).

**Jacobian.** ``J`` and ``f_t`` are forward differences, column ``j`` with the increment
``sqrt(eps * max(1e-5, |y_j|))`` as in RODAS/RADAU5 (``n + 1`` extra evaluations). A
Rosenbrock method's order conditions use the exact Jacobian at ``(t_n, y_n)`` (it is not a
W-method), so ``J`` is not carried across accepted steps; it *is* reused when a rejected step is
retried from the same ``(t_n, y_n)`` (only the LU decomposition of the new matrix is redone). The
forward-difference error (~1e-8 relative) perturbs the order conditions far below any useful
tolerance. A singular iteration matrix (``1/(h gamma)`` an eigenvalue of ``J``) yields a
non-finite step, which the integrator rejects and retries with a smaller ``h``, as RODAS does.

**Why RODAS4 rather than RADAU5.** Both are L-stable and stiffly accurate. A Rosenbrock step
needs no Newton iteration: exactly one Jacobian, one LU of an ``n x n`` matrix (``n`` = 4..11
here), six triangular solves and six evaluations, with nothing that can fail to converge and no
iteration state to carry between steps. RADAU5 (order 5) solves a ``3n``-dimensional stage
system by simplified Newton (one real and one complex ``n x n`` decomposition plus iteration
control); it pays off at very tight tolerances, while the stiff scenes here run at moderate ones,
where order 4 with a robust embedded estimate is the cheaper choice in pure Python. Measured
(``benchmarks/implicit_solvers.py``; suspension ``k`` = 1e7 N/m, ``c`` = 200 N s/m,
``M_s`` = 0.05 kg, 2 s at rtol 1e-6): 416 steps against DOP853's 4754 and SciPy Radau's 443.

**Limits.** A Rosenbrock method has stage order 1. When a stiff mode is driven hard by a slow
forcing (Prothero-Robinson type, e.g. ``y'' = -1e8 (y - sin t) - sin t``) its local error does
not vanish for ``|h lambda|`` ~ 1..100 and the step size locks there (15477 steps over 2 s,
SciPy's Radau with stage order 3: 76). The suspension is forced only weakly (pivot
displacements ~``F / k`` = 1e-7 m), so this does not bite there. Where the solution is slaved to
its stiff equilibrium the steps may grow far beyond the output interval; the dense output's
error is not part of the step-size control (the integrator's ``max_step`` bounds it). RODAS4
pays at moderate tolerances: at rtol 1e-8 the accuracy of the pendulum itself sets the steps
and DOP853 is about as fast.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from .linalg import LUDecomposition, SingularMatrixError, lu_factor
from .method import AdaptiveMethod, VectorField
from .runge_kutta import _stage_input, scaled_rms

GAMMA = 0.25
ALPHA = (0.0, 0.386, 0.21, 0.63, 1.0, 1.0)
GAMMA_T = (0.25, -0.1043, 0.1035, -0.3620000000000023e-01, 0.0, 0.0)  # gamma_i, coefficients of h f_t

_A51, _A52, _A53, _A54 = (
    0.1221224509226641e01,
    0.6019134481288629e01,
    0.1253708332932087e02,
    -0.6878860361058950e00,
)
# Sparse rows: A[i] lists (j, a_ij) of the stage argument y + sum_j a_ij u_j, C[i] lists (j, c_ij).
A: tuple[tuple[tuple[int, float], ...], ...] = (
    (),
    ((0, 0.1544000000000000e01),),
    ((0, 0.9466785280815826e00), (1, 0.2557011698983284e00)),
    ((0, 0.3314825187068521e01), (1, 0.2896124015972201e01), (2, 0.9986419139977817e00)),
    ((0, _A51), (1, _A52), (2, _A53), (3, _A54)),
    ((0, _A51), (1, _A52), (2, _A53), (3, _A54), (4, 1.0)),
)
C: tuple[tuple[tuple[int, float], ...], ...] = (
    (),
    ((0, -0.5668800000000000e01),),
    ((0, -0.2430093356833875e01), (1, -0.2063599157091915e00)),
    ((0, -0.1073529058151375e00), (1, -0.9594562251023355e01), (2, -0.2047028614809616e02)),
    (
        (0, 0.7496443313967647e01),
        (1, -0.1024680431464352e02),
        (2, -0.3399990352819905e02),
        (3, 0.1170890893206160e02),
    ),
    (
        (0, 0.8083246795921522e01),
        (1, -0.7981132988064893e01),
        (2, -0.3152159432874371e02),
        (3, 0.1631930543123136e02),
        (4, -0.6058818238834054e01),
    ),
)
B_ROW = A[5] + ((5, 1.0),)  # y_new = y + sum_j a_5j u_j + u_5 + u_6
DENSE_D2 = (
    0.1012623508344586e02,
    -0.7487995877610167e01,
    -0.3480091861555747e02,
    -0.7992771707568823e01,
    0.1025137723295662e01,
)
DENSE_D3 = (
    -0.6762803392801253e00,
    0.6087714651680015e01,
    0.1643084320892478e02,
    0.2476722511418386e02,
    -0.6594389125716872e01,
)
_DENSE_ROWS = (tuple(enumerate(DENSE_D2)), tuple(enumerate(DENSE_D3)))

_EPS = 2.0**-52


def fd_jacobian(
    f: VectorField, t: float, y: list[float], fy: list[float]
) -> tuple[list[list[float]], list[float]]:
    """Return ``(J, f_t)`` by forward differences: ``J[i][j] ~ df_i/dy_j``, ``f_t ~ df/dt`` (``n + 1`` calls).

    Increment of component ``j``: ``sqrt(eps * max(1e-5, |y_j|))`` (Hairer-Wanner, RODAS), of ``t``
    likewise with ``|t|``.
    """
    n = len(y)
    jac = [[0.0] * n for _ in range(n)]
    for j in range(n):
        delta = math.sqrt(_EPS * max(1e-5, abs(y[j])))
        shifted = list(y)
        shifted[j] = y[j] + delta
        delta = shifted[j] - y[j]  # the increment actually represented
        column = f(t, shifted)
        for i in range(n):
            jac[i][j] = (column[i] - fy[i]) / delta
    dt = math.sqrt(_EPS * max(1e-5, abs(t)))
    dt = (t + dt) - t
    f_t = [(a - b) / dt for a, b in zip(f(t + dt, y), fy)]
    return jac, f_t


def iteration_matrix(jac: Sequence[Sequence[float]], diagonal: float) -> list[list[float]]:
    """Return ``diagonal * I - J``."""
    out = [[-v for v in row] for row in jac]
    for i, row in enumerate(out):
        row[i] += diagonal
    return out


class Rodas4(AdaptiveMethod):
    """Hairer-Wanner's RODAS: Rosenbrock 4(3), stiffly accurate, L-stable, 3rd-order dense output.

    ``evals_per_step`` is set by every :meth:`step` to the evaluations of that call: 6 (five
    stages and ``f(t + h, y_new)``) plus ``n + 1`` when a new Jacobian is needed.
    """

    name = "rodas4"
    adaptive = True
    order = 4
    error_order = 3
    dense_order = 3
    evals_per_step = 6
    dense_evals = 0
    n_stages = 6  # u_1..u_6

    def __init__(self) -> None:
        # (t, y, J, f_t) at the start of the last step. Keyed on the identity of y: the integrator
        # retries a rejected step with the very same list, while a step after an accepted one or
        # after set_state gets a new list, so a restored run recomputes J exactly where the
        # original did (bit-identical steps and nfev).
        self._jacobian_cache: tuple[float, list[float], list[list[float]], list[float]] | None = None

    def _jacobian(
        self, f: VectorField, t: float, y: list[float], fy: list[float]
    ) -> tuple[list[list[float]], list[float], int]:
        """Return ``(J, f_t, evaluations spent)``, reusing the Jacobian of a retried step."""
        cache = self._jacobian_cache
        if cache is not None and cache[1] is y and cache[0] == t:
            return cache[2], cache[3], 0
        jac, f_t = fd_jacobian(f, t, y, fy)
        self._jacobian_cache = (t, y, jac, f_t)
        return jac, f_t, len(y) + 1

    def _stages(
        self,
        f: VectorField,
        t: float,
        y: list[float],
        fy: list[float],
        h: float,
        lu: LUDecomposition,
        f_t: list[float],
    ) -> list[list[float]]:
        """Solve the six linear stage equations of the module docstring for ``u_1..u_6``."""
        us: list[list[float]] = []
        inv_h = 1.0 / h
        for i in range(6):
            rhs = fy if i == 0 else f(t + ALPHA[i] * h, _stage_input(y, 1.0, A[i], us))
            rhs = _stage_input(rhs, inv_h, C[i], us)
            if GAMMA_T[i] != 0.0:
                hg = h * GAMMA_T[i]
                rhs = [r + hg * d for r, d in zip(rhs, f_t)]
            us.append(lu.solve(rhs))
        return us

    def step(
        self, f: VectorField, t: float, y: list[float], fy: list[float], h: float
    ) -> tuple[list[float], list[float], list[list[float]]]:
        """One step of size ``h``: ``(y_new, f(t + h, y_new), [u_1, ..., u_6])``."""
        jac, f_t, evals = self._jacobian(f, t, y, fy)
        try:
            lu = lu_factor(iteration_matrix(jac, 1.0 / (h * GAMMA)))
        except SingularMatrixError:
            self.evals_per_step = evals
            nan = [math.nan] * len(y)
            return nan, nan, [nan] * 6
        us = self._stages(f, t, y, fy, h, lu, f_t)
        y_new = _stage_input(y, 1.0, B_ROW, us)
        f_new = f(t + h, y_new)
        self.evals_per_step = evals + 6
        return y_new, f_new, us

    def error_norm(
        self, y: list[float], y_new: list[float], us: list[list[float]], h: float, rtol: float, atol: float
    ) -> float:
        """Scaled RMS norm of ``u_6``, the difference of the 4th- and 3rd-order solutions."""
        return scaled_rms(us[5], y, y_new, rtol, atol)

    def interpolant(
        self,
        f: VectorField,
        t: float,
        y: list[float],
        y_new: list[float],
        fy: list[float],
        f_new: list[float],
        h: float,
        us: list[list[float]],
    ) -> Callable[[float], list[float]]:
        """RODAS's 3rd-order continuous extension (module docstring) on ``t + theta h``."""
        q1, q2 = (_stage_input([0.0] * len(y), 1.0, row, us) for row in _DENSE_ROWS)

        def evaluate(theta: float) -> list[float]:
            s1 = 1.0 - theta
            return [s1 * u + theta * (v + s1 * (a + theta * b)) for u, v, a, b in zip(y, y_new, q1, q2)]

        return evaluate
