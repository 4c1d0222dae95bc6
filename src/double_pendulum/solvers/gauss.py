r"""Gauss-Legendre collocation: symplectic, symmetric implicit Runge-Kutta methods (fixed step).

For long runs of the frictionless pendulum. Its Hamiltonian
:math:`H = \tfrac12 p^T M(\varphi)^{-1} p + V(\varphi)` is not separable (the kinetic energy depends
on :math:`\varphi_1 - \varphi_2`), so explicit symplectic splitting methods do not apply; the
Gauss-Legendre methods are symplectic for *every* Hamiltonian system in canonical coordinates and
symmetric (E. Hairer, C. Lubich, G. Wanner, Geometric Numerical Integration, 2nd ed., Springer
2006, theorems VI.4.2 and V.2.3). A symplectic method with a fixed step conserves a modified
Hamiltonian :math:`\tilde H = H + O(h^{2s})` over exponentially long times (ibid. theorem
IX.8.1): the energy error stays bounded, :math:`O(h^{2s})`, instead of drifting as with an
explicit method.

The integrator works on the model's state ``(phi1, phi2, omega1, omega2)``, the velocity form of
the same system. Runge-Kutta methods commute only with affine changes of variables, and
``p = M(phi) omega`` is not affine, so there the method is not exactly symplectic; it stays
symmetric, and since ``omega -> -omega`` reverses time, reversible, which on (near-)integrable
motion also keeps the energy error bounded (ibid. chapter XI). Measured with ``gauss4``: from the
regular 0.3 rad start at ``h`` = 0.02 s the largest energy error is 1.84e-9 J in both the first
and the last 100 s of 1000 s (4.0e-9 J integrating canonical ``(phi, p)``); from the chaotic
2 rad start at ``h`` = 0.005 s, 2.7e-5 J over the first and 1.4e-5 J over the last 30 s of
300 s, the same as in canonical coordinates.

**Method.** ``s`` stages at the Gauss-Legendre nodes ``c_i`` (zeros of the shifted Legendre
polynomial of degree ``s``), order ``2s``:

.. math::

    Z_i = h \sum_{j=1}^{s} a_{ij} f(t + c_j h, y + Z_j), \qquad
    y_{new} = y + h \sum_{j=1}^{s} b_j f(t + c_j h, y + Z_j).

* ``gauss2`` (``s = 1``, the implicit midpoint rule): ``c = 1/2``, ``a = 1/2``, ``b = 1``;
* ``gauss4`` (``s = 2``): ``c = 1/2 -+ sqrt(3)/6``,
  ``A = [[1/4, 1/4 - sqrt(3)/6], [1/4 + sqrt(3)/6, 1/4]]``, ``b = (1/2, 1/2)``
  (Hairer, Norsett, Wanner, Solving ODEs I, table II.7.3; Hairer, Wanner II, section IV.5).

**Stage equations.** Solved by fixed-point iteration ``Z^{k+1} = h A F(Z^k)`` (the recommended
solver for non-stiff problems, Geometric Numerical Integration section VIII.6.1), started from
``Z_i^0 = c_i h f(t, y)`` (the first iterate from ``Z = 0``, free since ``f(t, y)`` is known). It
contracts by about ``h rho(A) |lambda|`` per iteration, ``|lambda|`` the fastest frequency (a few
percent for the pendulum at ``h`` = 0.01..0.02 s). Convergence criterion (ibid.): with
``delta_k = max_i |Z^k_i - Z^{k-1}_i| / (|y_i| + |Z^k_i|)`` (component-wise relative change),
iterate until ``delta_k = 0`` or ``delta_k >= delta_{k-1}`` with ``delta_k <= 1e-13``: the
increments have stopped shrinking at rounding level, where further iterations only exchange
rounding errors. Rounding-level convergence matters: a truncated iteration is no longer
symplectic and its error drifts. If that is not reached within ``MAX_ITERATIONS`` (the
iteration diverges or stalls, e.g. a stiff suspension or too large a step) the step raises
:class:`~double_pendulum.solvers.integrator.SolverError`; use ``rodas4`` for stiff scenes.

**Dense output:** cubic Hermite interpolation from ``y, y_new`` and their derivatives ``f``
(local error ``O(h^4)``, order 3; order 2 for ``gauss2``, whose ``y_new`` is only ``O(h^3)``
accurate). For ``gauss4`` this matches the method's global error ``O(h^4)``; the degree-``s``
collocation polynomial would only give ``O(h^{s+1})``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import ClassVar

from .combinations import sparse
from .integrator import SolverError
from .method import Method, VectorField
from .runge_kutta import _stage_input, hermite_interpolant

MAX_ITERATIONS = 100
ROUNDING_LEVEL = 1e-13  # largest relative increment still taken as rounding noise
_EPS = 2.0**-52  # a relative change below the unit roundoff: the stages are final to one ulp


def _relative_change(old: list[list[float]], new: list[list[float]], y: list[float]) -> float:
    """Return ``max |new - old| / (|y| + |new|)`` over all stages and components.

    Components that did not change count as 0, a change to ``new = y = 0`` as 1; a non-finite
    ``new`` gives ``inf``.
    """
    worst = 0.0
    for z_old, z_new in zip(old, new):
        for a, b, u in zip(z_old, z_new, y):
            diff = b - a
            if diff:
                ratio = abs(diff) / ((abs(u) + abs(b)) or abs(diff))
                if not ratio <= worst:
                    if ratio != ratio:  # NaN: b is not finite
                        return math.inf
                    worst = ratio
    return worst


class GaussLegendre(Method):
    """Base class of the ``s``-stage Gauss-Legendre methods; subclasses give the tableau, ``name``,
    ``order``, ``dense_order``, ``n_stages`` and ``evals_per_step``.

    ``evals_per_step`` is set by every :meth:`step` to the evaluations of that call:
    ``s`` per fixed-point iteration plus ``f(t + h, y_new)``; the class value is the fewest (one
    iteration).
    """

    adaptive = False
    error_order = None
    dense_evals = 0
    C: ClassVar[tuple[float, ...]]
    A: ClassVar[tuple[tuple[float, ...], ...]]
    B: ClassVar[tuple[float, ...]]

    def __init__(self) -> None:
        self._a_rows = tuple(sparse(row) for row in self.A)
        self._b_row = sparse(self.B)

    def _solve_stages(
        self, f: VectorField, t: float, y: list[float], fy: list[float], h: float
    ) -> tuple[list[list[float]], int]:
        """Iterate the stage equations to rounding level; return the stage derivatives and evaluations."""
        zero = [0.0] * len(y)
        zs = [[c * h * v for v in fy] for c in self.C]
        previous = math.inf
        for iteration in range(1, MAX_ITERATIONS + 1):
            ks = [f(t + c * h, [u + z for u, z in zip(y, zi)]) for c, zi in zip(self.C, zs)]
            new_zs = [_stage_input(zero, h, row, ks) for row in self._a_rows]
            delta = _relative_change(zs, new_zs, y)
            zs = new_zs
            if delta <= _EPS or previous <= delta <= ROUNDING_LEVEL:
                return ks, iteration * len(self.C)
            if not math.isfinite(delta):
                break
            previous = delta
        raise SolverError(
            f"{self.name}: the stage iteration did not converge at t = {t:.6g} s within {MAX_ITERATIONS} "
            f"iterations (last relative change {delta:.3g}); fixed_step = {h:g} s is too large for this "
            "motion, or the problem is stiff (use rodas4)"
        )

    def step(
        self, f: VectorField, t: float, y: list[float], fy: list[float], h: float
    ) -> tuple[list[float], list[float], list[list[float]]]:
        """One step of size ``h``: ``(y_new, f(t + h, y_new), stage derivatives)``."""
        ks, evals = self._solve_stages(f, t, y, fy, h)
        y_new = _stage_input(y, h, self._b_row, ks)
        self.evals_per_step = evals + 1
        return y_new, f(t + h, y_new), ks

    def interpolant(
        self,
        f: VectorField,
        t: float,
        y: list[float],
        y_new: list[float],
        fy: list[float],
        f_new: list[float],
        h: float,
        ks: list[list[float]],
    ) -> Callable[[float], list[float]]:
        """Cubic Hermite interpolation on ``t + theta h`` (module docstring)."""
        return hermite_interpolant(y, y_new, fy, f_new, h)


_R3 = math.sqrt(3.0)


class Gauss2(GaussLegendre):
    """Implicit midpoint rule: the 1-stage Gauss-Legendre method, order 2."""

    name = "gauss2"
    n_stages = 1
    evals_per_step = 2
    order = 2
    dense_order = 2  # the Hermite interpolant inherits the O(h^3) local error of y_new
    C = (0.5,)
    A = ((0.5,),)
    B = (1.0,)


class Gauss4(GaussLegendre):
    """The 2-stage Gauss-Legendre method, order 4."""

    name = "gauss4"
    n_stages = 2
    evals_per_step = 3
    order = 4
    dense_order = 3
    C = (0.5 - _R3 / 6.0, 0.5 + _R3 / 6.0)
    A = ((0.25, 0.25 - _R3 / 6.0), (0.25 + _R3 / 6.0, 0.25))
    B = (0.5, 0.5)
