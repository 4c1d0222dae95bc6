"""Checking a saved FMU state before it is restored: the checks the components share (one copy).

A component's ``get_state()`` returns JSON data, which the FMU serialises to bytes a host may have
stored, copied or altered. Each component's ``check_state(state)``
(:class:`~double_pendulum.component.cosimulation.DoublePendulumCoSimulation`,
:class:`~double_pendulum.component.suspension.SuspensionCoSimulation`,
:class:`~double_pendulum.component.model_exchange.PendulumStates`) calls its function below
(:func:`cosimulation_state`, :func:`suspension_state`, :func:`model_exchange_state`), which raises
:class:`StateError` at the first entry ``get_state()`` cannot have produced; ``set_state`` calls it
before it changes anything. A check builds no model or integrator and changes nothing.

The helpers take the entry's place as ``(parent, key)``: the parent's path and the entry's key (a
dict key or list index; None for the parent itself), so a path is only put together for a message.
Their conventions:

* a path is the entry as Python indexes it from the root, e.g. ``state["integrator"]["y"][2]``;
* a *number* is an ``int`` or a ``float``, never a ``bool`` (JSON writers may drop a float's
  ``.0``), and an ``int`` must fit a float; it must be finite unless ``finite=False``;
* a *list* is a ``list`` or a ``tuple`` (JSON gives lists, a state kept in memory may hold tuples);
* a *dict* is a ``dict`` with exactly the given keys, none missing, none extra;
* a message is one line, ``<path> = <value> <what is wrong>``, the value's ``repr`` cut to
  :data:`SHOWN_LENGTH` characters.

``set_state`` runs often (a co-simulation master's coupling iterations roll back every step), so
the common case, lists and dicts of finite floats, is checked in a few passes at C speed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from collections.abc import Set as AbstractSet
from contextlib import contextmanager
from itertools import chain
from typing import Any, NoReturn

from ..model import suspension as _suspension
from ..model.inputs import INPUT_NAMES
from ..model.outputs import OUTPUT_NAMES
from ..model.parameters import ParameterError, check_value
from ..model.scene import every_state
from ..solvers.integrator import LANDING_REST, Integrator
from ..solvers.registry import METHODS
from .settings import PIVOT_INPUT_MODES

SHOWN_LENGTH = 60
"""Longest value shown in a message (its ``repr``, cut with ``...``)."""

PARAMETER_CHOICES: dict[str, tuple[str, ...]] = {"solver": tuple(sorted(METHODS)), "pivot_input": PIVOT_INPUT_MODES}
"""The string parameters and their valid values."""

EVERY_STATE: tuple[str, ...] = every_state()
"""Every state any scene of the pendulum can have (the Model Exchange states)."""

COSIMULATION_KEYS = frozenset((
    "version", "values", "time", "initialised", "initial_energy", "outputs", "integrator", "inputs", "driven", "hold",
    "y", "pivot_samples", "position_watch",
))
"""The keys of the pendulum's co-simulation state (``DoublePendulumCoSimulation.get_state``)."""
SUSPENSION_KEYS = frozenset(
    ("version", "values", "inputs", "held", "time", "initialised", "initial_energy", "y", "outputs", "integrator")
)
"""The keys of the suspension's state (``SuspensionCoSimulation.get_state``)."""
MODEL_EXCHANGE_KEYS = frozenset(("time", "x", "evaluations", "known", "instant", "left", "set_here"))
"""The keys of the Model Exchange states' state (``PendulumStates.get_state``)."""
INTEGRATOR_KEYS = frozenset((*Integrator.STATE_FIELDS, "landed"))
"""The keys of :meth:`~double_pendulum.solvers.Integrator.get_state`."""
INPUT_KEYS, OUTPUT_KEYS = frozenset(INPUT_NAMES), frozenset(OUTPUT_NAMES)
SUSPENSION_INPUT_KEYS = frozenset(q.name for q in _suspension.INPUTS)
SUSPENSION_OUTPUT_KEYS = frozenset(_suspension.OUTPUT_NAMES)
WATCH_KEYS = frozenset(("last", "warned"))

Key = str | int | None


class StateError(ValueError):
    """A saved FMU state is not one ``get_state()`` can have produced (a damaged or altered state).

    The message names the entry by its path from the state's root and shows its value.
    """


# ---------------------------------------------------------------------- messages
def shown(value: Any) -> str:
    """``repr(value)`` on one line, cut to :data:`SHOWN_LENGTH` characters."""
    text = repr(value).replace("\n", "\\n")
    return text if len(text) <= SHOWN_LENGTH else text[: SHOWN_LENGTH - 3] + "..."


def item(parent: str, key: Key) -> str:
    """The path of entry ``key`` (a dict key, a list index, or None: the parent itself) of ``parent``."""
    if key is None:
        return parent
    return f"{parent}[{key}]" if isinstance(key, int) else f'{parent}["{key}"]'


def fail(parent: str, key: Key, value: Any, problem: str) -> NoReturn:
    """Raise :class:`StateError`: ``<path> = <value> <problem>``."""
    raise StateError(f"{item(parent, key)} = {shown(value)} {problem}")


def _entries(n: int) -> str:
    return f"{n} entry" if n == 1 else f"{n} entries"


# ---------------------------------------------------------------------- values
def entries(parent: str, key: Key, value: Any, keys: AbstractSet[str]) -> Mapping[str, Any]:
    """``value``, checked to be a dict with exactly ``keys``."""
    if not isinstance(value, dict):
        fail(parent, key, value, "is not a dict")
    if value.keys() != keys:
        missing = sorted(k for k in keys if k not in value)
        extra = [k for k in value if k not in keys]
        more = f" (and {len(missing) + len(extra) - 1} more wrong keys)" if len(missing) + len(extra) > 1 else ""
        if missing:
            raise StateError(f'{item(parent, key)} has no key "{missing[0]}"{more}')
        raise StateError(f"{item(parent, key)} has an unexpected key {shown(extra[0])}{more}")
    return value


def sequence(parent: str, key: Key, value: Any, length: int | None = None) -> Sequence[Any]:
    """``value``, checked to be a list (of ``length`` entries, if given)."""
    if not isinstance(value, (list, tuple)):
        fail(parent, key, value, "is not a list")
    if length is not None and len(value) != length:
        fail(parent, key, value, f"has {_entries(len(value))}, expected {length}")
    return value


def number(parent: str, key: Key, value: Any, finite: bool = True) -> None:
    """Check that ``value`` is a number (int or float, not bool; finite if ``finite``)."""
    if type(value) is float:
        if finite and value - value != 0.0:  # inf or nan
            fail(parent, key, value, "is not finite")
    elif isinstance(value, bool):
        fail(parent, key, value, "is a bool, not a number")
    elif isinstance(value, int):
        try:
            float(value)
        except OverflowError:
            fail(parent, key, value, "is too large for a float")
    elif isinstance(value, float):
        number(parent, key, float(value), finite)
    else:
        fail(parent, key, value, "is not a number")


_FLOAT, _INT = frozenset((float,)), frozenset((int,))


def _floats(values: Collection[Any], finite: bool) -> bool:
    """True if ``values`` are all floats (finite if ``finite``): the common case, in two passes at C speed.

    False does not mean wrong: a sum of finite floats may overflow, and ints are numbers too.
    """
    return _FLOAT.issuperset(map(type, values)) and (not finite or math.isfinite(sum(values)))


def numbers(parent: str, key: Key, value: Any, length: int | None = None, finite: bool = True) -> Sequence[Any]:
    """``value``, checked to be a list of numbers (``length`` of them, if given; finite if ``finite``)."""
    value = sequence(parent, key, value, length)
    if not _floats(value, finite):
        path = item(parent, key)
        for k, v in enumerate(value):
            number(path, k, v, finite)
    return value


def vectors(parent: str, keys: Sequence[Key], values: Sequence[Any], length: int, finite: bool = True) -> None:
    """Check that each of ``values`` (entries ``keys`` of ``parent``) is a list of ``length`` numbers."""
    if not (all(type(v) is list and len(v) == length for v in values) and _floats(list(chain(*values)), finite)):
        for key, value in zip(keys, values):
            numbers(parent, key, value, length, finite)


def number_entries(parent: str, key: Key, value: Any, keys: AbstractSet[str], finite: bool = True) -> Mapping[str, Any]:
    """``value``, checked to be a dict with exactly ``keys`` whose values are numbers (finite if ``finite``)."""
    value = entries(parent, key, value, keys)
    if not _floats(value.values(), finite):
        path = item(parent, key)
        for k, v in value.items():
            number(path, k, v, finite)
    return value


def integer(parent: str, key: Key, value: Any, low: int = 0, high: int | None = None) -> None:
    """Check that ``value`` is an int (not bool) from ``low`` to ``high`` (if given)."""
    if isinstance(value, bool) or not isinstance(value, int):
        fail(parent, key, value, "is a bool, not an integer" if isinstance(value, bool) else "is not an integer")
    if value < low:
        fail(parent, key, value, f"is below {low}")
    if high is not None and value > high:
        fail(parent, key, value, f"is above {high}")


def boolean(parent: str, key: Key, value: Any) -> None:
    """Check that ``value`` is a bool."""
    if value is not True and value is not False:
        fail(parent, key, value, "is not a bool")


def choice(parent: str, key: Key, value: Any, choices: Collection[str]) -> None:
    """Check that ``value`` is one of the strings ``choices``."""
    if not isinstance(value, str):
        fail(parent, key, value, "is not a string")
    if value not in choices:
        fail(parent, key, value, f"is not one of {', '.join(choices)}")


def version(parent: str, key: Key, value: Any, supported: int) -> None:
    """Check that ``value`` is the state version ``supported`` (an int, not a bool)."""
    if type(value) is not int or value != supported:
        fail(parent, key, value, f"is not a supported FMU state version (this component's is {supported})")


_PASSED: set[tuple[int, tuple[Any, ...], tuple[type, ...]]] = set()
"""Parameter sets :func:`parameters` passed: (``id`` of the rules, the values and their types in the
rules' order). A rollback restores the same parameters again and again. Cleared at :data:`PASSED_KEPT`."""
PASSED_KEPT = 64


def parameters(parent: str, key: Key, value: Any, rules: Mapping[str, tuple[str, str]]) -> Mapping[str, Any]:
    """``value``, checked to hold exactly the parameters of ``rules`` (``name -> (unit, rule)``), each by its rule.

    A Boolean parameter must be a bool, a string one one of its :data:`PARAMETER_CHOICES`, any other a
    finite number that passes its rule (:func:`~double_pendulum.model.parameters.check_value`). A set
    equal to one passed before, value for value and type for type, passes at once.
    """
    value = entries(parent, key, value, rules.keys())
    ordered = tuple(map(value.__getitem__, rules))
    passed: tuple[int, tuple[Any, ...], tuple[type, ...]] | None = (id(rules), ordered, tuple(map(type, ordered)))
    try:
        if passed in _PASSED:
            return value
    except TypeError:  # an unhashable value: wrong, as the checks below say
        passed = None
    path = item(parent, key)
    for name, (unit, rule) in rules.items():
        v = value[name]
        if rule == "bool":
            boolean(path, name, v)
        elif name in PARAMETER_CHOICES:
            choice(path, name, v, PARAMETER_CHOICES[name])
        elif rule == "str":
            if not isinstance(v, str):
                fail(path, name, v, "is not a string")
        else:
            number(path, name, v)
            try:
                check_value(name, v, unit, rule)
            except ParameterError as error:
                fail(path, name, v, f"breaks its rule ({error})")
    if passed is not None:
        if len(_PASSED) >= PASSED_KEPT:
            _PASSED.clear()
        _PASSED.add(passed)
    return value


# ---------------------------------------------------------------------- states
def integrator_state(parent: str, key: Key, value: Any, solver: str, size: int) -> None:
    """Check an :meth:`Integrator.get_state() <double_pendulum.solvers.Integrator.get_state>` of method ``solver``.

    ``size`` is the number of states. Checked: exactly its keys; the times ``t0 <= t_prev <= t``
    and the step ``h > 0`` finite; ``y``, ``y_prev``, ``fy_prev`` ``size`` finite numbers; ``fy``
    ``size`` numbers, finite for an adaptive method (it accepts no step with a non-finite ``f(t, y)``;
    a fixed-step one may have taken a step to the brink of overflow, which the next step reports),
    or None where the method defers it (``deferrable_f_new``); the counters ints, ``nfev >= 1``,
    ``grid_start <= n_steps``, ``landing_rest`` up to ``LANDING_REST`` (0 without a landing method);
    ``landed`` a bool, True only for a method with a landing method; ``stages`` lists of ``size``
    finite numbers, as many as the last step leaves: none after a (re)start, the method's
    ``n_stages``, one fewer while ``fy`` is deferred, the landing method's after a landing step.
    """
    s = entries(parent, key, value, INTEGRATOR_KEYS)
    path = item(parent, key)
    method = METHODS[solver]
    landing = method.landing_method
    times = (s["t0"], s["t_prev"], s["t"], s["h"])
    if not _floats(times, True):
        for name in ("t0", "t_prev", "t", "h"):
            number(path, name, s[name])
    if not s["t0"] <= s["t_prev"] <= s["t"]:
        raise StateError(f"{path}: t0 = {s['t0']!r}, t_prev = {s['t_prev']!r}, t = {s['t']!r} are not in order")
    if not s["h"] > 0.0:
        fail(path, "h", s["h"], "is not > 0")
    stages = sequence(path, "stages", s["stages"])
    vectors(path, ("y", "y_prev", "fy_prev"), (s["y"], s["y_prev"], s["fy_prev"]), size)
    fy = s["fy"]
    if fy is not None:
        numbers(path, "fy", fy, size, finite=method.adaptive)
    elif not method.deferrable_f_new:
        fail(path, "fy", fy, f"but {solver} never defers f(t, y)")
    rest_limit = LANDING_REST if landing is not None else 0
    nfev, n_steps, n_rejected, grid_start, rest = (
        s["nfev"], s["n_steps"], s["n_rejected"], s["grid_start"], s["landing_rest"]
    )
    if not (_INT.issuperset(map(type, (nfev, n_steps, n_rejected, grid_start, rest))) and nfev >= 1
            and n_rejected >= 0 and 0 <= grid_start <= n_steps and 0 <= rest <= rest_limit):  # else say which
        integer(path, "nfev", nfev, low=1)
        integer(path, "n_steps", n_steps)
        integer(path, "n_rejected", n_rejected)
        integer(path, "grid_start", grid_start, high=n_steps)
        integer(path, "landing_rest", rest, high=rest_limit)
    boolean(path, "landed", s["landed"])
    if s["landed"]:
        if landing is None:
            fail(path, "landed", True, f"but {solver} has no landing method")
        if fy is None:
            fail(path, "fy", fy, "but the last step was a landing step")
        counts: tuple[int, ...] = (landing.n_stages,)
    elif fy is None:
        counts = (method.n_stages - 1,)
    else:
        counts = (0, method.n_stages)
    if len(stages) not in counts:
        expected = " or ".join(str(n) for n in counts)
        fail(path, "stages", stages, f"has {_entries(len(stages))}, expected {expected} ({solver})")
    vectors(item(path, "stages"), range(len(stages)), stages, size)


def cosimulation_state(
    path: str, state: Any, supported: int, rules: Mapping[str, tuple[str, str]],
    scene_size: Callable[[Mapping[str, Any], bool], int],
) -> None:
    """Check a :class:`~double_pendulum.component.cosimulation.DoublePendulumCoSimulation` state at ``path``.

    ``supported`` is its version, ``rules`` its parameters' ``(unit, rule)`` by name and
    ``scene_size(values, inputs)`` the number of states of the scene of the parameter ``values``
    (with the inputs' state if ``inputs``). Checked:

    * a dict with exactly the keys of ``get_state`` (:data:`COSIMULATION_KEYS`); ``version`` the supported one;
    * ``values``: every parameter, no other, each by its rule; ``solver`` and ``pivot_input`` by name;
    * ``time`` finite; ``initialised``, ``driven`` bools; ``inputs``: every input, finite;
    * ``outputs``: every output, numbers; ``initial_energy`` None or a number. Not necessarily
      finite: energies and forces derived from a finite state may overflow at extreme valid
      parameters or inputs, and a restored state only reports them;
    * ``y`` finite; ``hold`` None or ``[t0, the eight inputs]``, finite; ``pivot_samples`` None
      or up to three ``[t, x, y]``, finite, times increasing; ``position_watch`` None or
      ``{"last": None or [x, y] finite, "warned": bool}``.

    Initialised: ``y`` has the states of the scene (parameters, and the inputs' state if driven or
    an input is non-zero), ``integrator`` is an :func:`integrator_state` of ``solver`` for them,
    ``initial_energy`` a number, ``hold`` there exactly when ``driven`` and the pivot readers those
    of ``pivot_input`` (samples for ``position``, the watch otherwise). Not initialised:
    ``integrator`` None; the rest is as it was and unused, so ``y`` has 4 to 13 states (any scene's).
    """
    s = entries(path, None, state, COSIMULATION_KEYS)
    version(path, "version", s["version"], supported)
    values = parameters(path, "values", s["values"], rules)
    number(path, "time", s["time"])
    boolean(path, "initialised", s["initialised"])
    boolean(path, "driven", s["driven"])
    initialised, driven = s["initialised"], s["driven"]
    inputs = number_entries(path, "inputs", s["inputs"], INPUT_KEYS)
    number_entries(path, "outputs", s["outputs"], OUTPUT_KEYS, finite=False)
    if initialised or s["initial_energy"] is not None:
        number(path, "initial_energy", s["initial_energy"], finite=False)
    hold, samples, watch = s["hold"], s["pivot_samples"], s["position_watch"]
    if hold is not None:
        sequence(path, "hold", hold, 2)
        number(item(path, "hold"), 0, hold[0])
        numbers(item(path, "hold"), 1, hold[1], len(INPUT_NAMES))
    y = numbers(path, "y", s["y"])
    if samples is not None:
        if len(sequence(path, "pivot_samples", samples)) > 3:
            fail(path, "pivot_samples", samples, f"has {len(samples)} entries, expected at most 3")
        vectors(item(path, "pivot_samples"), range(len(samples)), samples, 3)
        if any(a[0] >= b[0] for a, b in zip(samples, samples[1:])):
            fail(path, "pivot_samples", samples, "has times that do not increase")
    if watch is not None:
        entries(path, "position_watch", watch, WATCH_KEYS)
        if watch["last"] is not None:
            numbers(item(path, "position_watch"), "last", watch["last"], 2)
        boolean(item(path, "position_watch"), "warned", watch["warned"])
    if not initialised:
        if s["integrator"] is not None:
            fail(path, "integrator", s["integrator"], "is not None, but the state is not initialised")
        if not 4 <= len(y) <= len(EVERY_STATE):
            fail(path, "y", y, f"has {len(y)} entries, expected 4 to {len(EVERY_STATE)}")
        return
    size = scene_size(values, driven or any(inputs.values()))
    if len(y) != size:
        fail(path, "y", y, f"has {len(y)} entries, expected {size} (the scene's states)")
    integrator_state(path, "integrator", s["integrator"], values["solver"], size)
    if (hold is None) == driven:
        fail(path, "hold", hold, f"does not go with driven = {driven}")
    position = values["pivot_input"] == "position"
    if (samples is None) == position or (watch is None) != position:
        reader = "pivot_samples" if (samples is None) == position else "position_watch"
        fail(path, reader, s[reader], f"does not go with pivot_input = {values['pivot_input']!r}")


def suspension_state(path: str, state: Any, supported: int, rules: Mapping[str, tuple[str, str]]) -> None:
    """Check a :class:`~double_pendulum.component.suspension.SuspensionCoSimulation` state at ``path``.

    ``supported`` is its version, ``rules`` its parameters' ``(unit, rule)`` by name. Checked: a
    dict with exactly the keys of ``get_state`` (:data:`SUSPENSION_KEYS`); ``version`` the
    supported one; ``values``: every parameter, no other, each by its rule, ``solver`` by name;
    ``inputs``: ``F_x`` and ``F_y``, finite; ``held``: the two load components, finite; ``time``
    finite; ``initialised`` a bool; ``initial_energy`` None or finite (the energy at rest, 0);
    ``y``: the six states, finite; ``outputs``: every output, numbers (not necessarily finite:
    the energy of a finite state may overflow at extreme valid parameters); ``integrator`` an
    :func:`integrator_state` of ``solver`` for the six states if initialised, else None.
    """
    s = entries(path, None, state, SUSPENSION_KEYS)
    version(path, "version", s["version"], supported)
    values = parameters(path, "values", s["values"], rules)
    number_entries(path, "inputs", s["inputs"], SUSPENSION_INPUT_KEYS)
    numbers(path, "held", s["held"], len(SUSPENSION_INPUT_KEYS))
    number(path, "time", s["time"])
    boolean(path, "initialised", s["initialised"])
    if s["initialised"] or s["initial_energy"] is not None:
        number(path, "initial_energy", s["initial_energy"])
    numbers(path, "y", s["y"], len(_suspension.STATE_NAMES))
    number_entries(path, "outputs", s["outputs"], SUSPENSION_OUTPUT_KEYS, finite=False)
    if s["initialised"]:
        integrator_state(path, "integrator", s["integrator"], values["solver"], len(_suspension.STATE_NAMES))
    elif s["integrator"] is not None:
        fail(path, "integrator", s["integrator"], "is not None, but the state is not initialised")


def model_exchange_state(path: str, state: Any) -> None:
    """Check a :class:`~double_pendulum.component.model_exchange.PendulumStates` state at ``path``.

    Checked: a dict with exactly the keys of ``get_state`` (:data:`MODEL_EXCHANGE_KEYS`);
    ``time`` and ``instant`` numbers and ``x`` the 13 continuous states (:data:`EVERY_STATE`),
    numbers, none necessarily finite (the host sets them unchecked, ``fmi3SetTime``,
    ``fmi3SetContinuousStates``); ``evaluations`` an int >= 0; ``known`` and ``left``: every
    input, finite (checked when set); ``set_here``: input names, each once.
    """
    s = entries(path, None, state, MODEL_EXCHANGE_KEYS)
    number(path, "time", s["time"], finite=False)
    number(path, "instant", s["instant"], finite=False)
    numbers(path, "x", s["x"], len(EVERY_STATE), finite=False)
    integer(path, "evaluations", s["evaluations"])
    number_entries(path, "known", s["known"], INPUT_KEYS)
    number_entries(path, "left", s["left"], INPUT_KEYS)
    names = sequence(path, "set_here", s["set_here"])
    for k, name in enumerate(names):
        choice(item(path, "set_here"), k, name, INPUT_NAMES)
        if name in names[:k]:
            fail(item(path, "set_here"), k, name, "is there twice")


@contextmanager
def restored_on_failure(component: Any) -> Iterator[None]:
    """Put ``component``'s attributes back (a shallow copy) if the block raises.

    For a ``set_state`` that rebuilds (``initialise``) after its state passed ``check_state``: the
    rebuild makes new objects, so the old ones, put back, are as they were.
    """
    saved = dict(vars(component))
    try:
        yield
    except BaseException:
        vars(component).clear()
        vars(component).update(saved)
        raise
