"""Integrators, kept apart from the right-hand sides they integrate.

* :mod:`.method` — the contract every method keeps (:class:`~.method.Method`);
* :mod:`.runge_kutta` — explicit methods (one step, error estimate, dense output);
* :mod:`.rosenbrock` — Rodas4, linearly implicit and L-stable, for stiff scenes;
* :mod:`.gauss` — Gauss-Legendre collocation (symmetric, energy error bounded over long runs);
* :mod:`.linalg` — the small dense LU they need;
* :mod:`.integrator` — step-size control, dense output and persistent state;
* :mod:`.registry` — the names users pass as ``solver``.
"""

from .integrator import Integrator, SolverError
from .registry import METHODS, UnknownSolverError, check_solver_name, make_integrator, make_method

__all__ = [
    "Integrator",
    "METHODS",
    "SolverError",
    "UnknownSolverError",
    "check_solver_name",
    "make_integrator",
    "make_method",
]
