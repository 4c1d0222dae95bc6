"""Solver names and their construction: the one place that maps a name to a method."""

from __future__ import annotations

from typing import Any

from .gauss import Gauss2, Gauss4
from .integrator import Integrator
from .method import Method, VectorField
from .rosenbrock import Rodas4
from .runge_kutta import ClassicRK4, Dop853, Dopri5, ExplicitEuler

METHODS: dict[str, type[Method]] = {
    "dop853": Dop853,
    "dopri5": Dopri5,
    "rk4": ClassicRK4,
    "euler": ExplicitEuler,
    "rodas4": Rodas4,
    "gauss4": Gauss4,
    "gauss2": Gauss2,
}


class UnknownSolverError(ValueError):
    """The solver name is not one of :data:`METHODS`."""


def check_solver_name(name: str) -> None:
    """Raise :class:`UnknownSolverError` naming the valid choices if ``name`` is unknown."""
    if name not in METHODS:
        raise UnknownSolverError(f"invalid solver = {name!r}: must be one of {', '.join(sorted(METHODS))}")


def make_method(name: str) -> Method:
    """Return a fresh method object for ``name`` (it keeps the :class:`~.method.Method` contract)."""
    check_solver_name(name)
    return METHODS[name]()


def make_integrator(
    name: str,
    f: VectorField,
    t0: float,
    y0: list[float],
    *,
    rtol: float,
    atol: float,
    fixed_step: float,
    **options: Any,
) -> Integrator:
    """Build an :class:`Integrator` for ``f`` with the method called ``name``."""
    return Integrator(f, t0, y0, make_method(name), rtol=rtol, atol=atol, fixed_step=fixed_step, **options)
