r"""The contract every integration method of this package keeps: what the integrator may rely on.

Modelled on diffrax's ``AbstractSolver``: abstract methods, and class-level attributes every concrete
method must define (checked when it is instantiated, :meth:`Method.__new__`).

A method advances ``dy/dt = f(t, y)`` by one step and offers a continuous extension of it:

* ``step(f, t, y, fy, h) -> (y_new, f_new, stages)``: one step of size ``h`` [s] from ``(t, y)``
  with ``fy = f(t, y)`` given; ``f_new = f(t + h, y_new)`` is reused as the next step's ``fy``;
  ``stages`` are the vectors the error estimate and the dense output need (``n_stages`` of them).
  A method with ``deferrable_f_new`` also takes ``with_f_new=False`` and then returns
  ``f_new = None`` and one stage fewer (the integrator evaluates it when needed);
* ``interpolant(f, t, y, y_new, fy, f_new, h, stages) -> g``: the dense output
  :math:`g(\theta) \approx y(t + \theta h)`, :math:`0 \le \theta \le 1`, of order ``dense_order``
  (local error :math:`O(h^{dense\_order + 1})`), costing ``dense_evals`` evaluations of ``f``;
* adaptive methods (:class:`AdaptiveMethod`) also give
  ``error_norm(y, y_new, stages, h, rtol, atol)``: the scaled RMS norm of the local error estimate
  of order ``error_order``; a step is accepted when it is <= 1.

Attributes: ``name`` (the registry's name), ``adaptive`` (a bool: step-size control with an error
estimate, or a fixed step), ``order`` (of ``y_new``), ``error_order`` (of the error estimate; ``None``
for a fixed-step method), ``dense_order``, ``evals_per_step`` (evaluations of ``f`` in one ``step``
call; the integrator reads it after each call, so a method whose cost varies, e.g. with a Jacobian or
an iteration, sets it on the instance in ``step``), ``dense_evals``, ``n_stages``; optional, with
defaults: ``landing_method`` (an adaptive method for short steps onto a stop time, see
:mod:`.integrator`; ``None``) and ``deferrable_f_new`` (``False``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import ClassVar

VectorField = Callable[[float, list[float]], list[float]]
Interpolant = Callable[[float], list[float]]
StepResult = tuple[list[float], list[float], list[list[float]]]

# The class-level attributes every concrete method defines (Method's "abstract class variables").
ABSTRACT_ATTRIBUTES: tuple[str, ...] = (
    "name",
    "adaptive",
    "order",
    "error_order",
    "dense_order",
    "evals_per_step",
    "dense_evals",
    "n_stages",
)


def contract_violations(cls: type) -> list[str]:
    """What ``cls`` lacks of the :class:`Method` contract, one phrase each (empty if it keeps it).

    Checked: it is a :class:`Method` with no abstract method left; every attribute of
    :data:`ABSTRACT_ATTRIBUTES` is defined; ``name`` a non-empty str; ``adaptive`` a bool; ``order``,
    ``dense_order``, ``evals_per_step`` and ``n_stages`` ints >= 1, ``dense_evals`` an int >= 0;
    ``error_order`` an int >= 1 exactly for adaptive methods, which are :class:`AdaptiveMethod`\\ s,
    and ``None`` for fixed-step ones; ``landing_method`` ``None`` or an adaptive method.
    """
    if not (isinstance(cls, type) and issubclass(cls, Method)):
        return [f"{getattr(cls, '__name__', cls)!s} is not a Method"]
    problems = [f"abstract method {name} not implemented" for name in sorted(cls.__abstractmethods__)]
    missing = [name for name in ABSTRACT_ATTRIBUTES if not hasattr(cls, name)]
    problems += [f"class attribute {name} not defined" for name in missing]
    if missing:
        return problems

    def is_int(value: object, low: int) -> bool:
        return type(value) is int and value >= low

    if not (isinstance(cls.name, str) and cls.name):
        problems.append(f"name = {cls.name!r} is not a non-empty str")
    if type(cls.adaptive) is not bool:
        problems.append(f"adaptive = {cls.adaptive!r} is not a bool")
    for name in ("order", "dense_order", "evals_per_step", "n_stages"):
        if not is_int(getattr(cls, name), 1):
            problems.append(f"{name} = {getattr(cls, name)!r} is not an int >= 1")
    if not is_int(cls.dense_evals, 0):
        problems.append(f"dense_evals = {cls.dense_evals!r} is not an int >= 0")
    if cls.adaptive is True:
        if not is_int(cls.error_order, 1):
            problems.append(f"adaptive, but error_order = {cls.error_order!r} is not an int >= 1")
        if not issubclass(cls, AdaptiveMethod):
            problems.append("adaptive, but not an AdaptiveMethod (no error_norm)")
    elif cls.error_order is not None:
        problems.append(f"fixed-step, but error_order = {cls.error_order!r} is not None")
    landing = cls.landing_method
    if landing is not None and not (isinstance(landing, AdaptiveMethod) and landing.adaptive is True):
        problems.append(f"landing_method = {landing!r} is not an adaptive method")
    return problems


class Method(ABC):
    """An integration method: one step and its dense output (module docstring).

    Concrete subclasses define every attribute of :data:`ABSTRACT_ATTRIBUTES` at class level;
    instantiating one that does not, or whose values break the contract, raises ``TypeError``
    (:func:`contract_violations`).
    """

    name: ClassVar[str]
    adaptive: ClassVar[bool]
    order: ClassVar[int]
    error_order: ClassVar[int | None]
    dense_order: ClassVar[int]
    evals_per_step: int
    dense_evals: ClassVar[int]
    n_stages: ClassVar[int]
    landing_method: ClassVar[AdaptiveMethod | None] = None
    deferrable_f_new: ClassVar[bool] = False

    def __new__(cls, *args: object, **kwargs: object) -> Method:
        problems = contract_violations(cls)
        if problems:
            raise TypeError(f"Can't instantiate method {cls.__name__}: {'; '.join(problems)}")
        return super().__new__(cls)

    @abstractmethod
    def step(self, f: VectorField, t: float, y: list[float], fy: list[float], h: float) -> StepResult:
        """One step of size ``h`` [s]: ``(y_new, f(t + h, y_new), stages)``."""

    @abstractmethod
    def interpolant(
        self,
        f: VectorField,
        t: float,
        y: list[float],
        y_new: list[float],
        fy: list[float],
        f_new: list[float],
        h: float,
        stages: list[list[float]],
    ) -> Interpolant:
        """The dense output ``g(theta) ~ y(t + theta h)`` on the step just taken."""


class AdaptiveMethod(Method):
    """A method with an embedded error estimate, for step-size control (``adaptive = True``)."""

    error_order: ClassVar[int]

    @abstractmethod
    def error_norm(
        self, y: list[float], y_new: list[float], stages: list[list[float]], h: float, rtol: float, atol: float
    ) -> float:
        """Scaled RMS norm of the local error estimate of the step ``y -> y_new`` (accepted if <= 1)."""
