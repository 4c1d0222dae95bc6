"""A saved FMU state is checked completely before it is restored (``check_state``, component.state_check).

In-process: the three components' states from real runs pass and survive JSON; tampered ones are
refused with a ``StateError`` naming the entry and its value, and leave a live component as it was.
"""

from __future__ import annotations

import copy
import functools
import json
import math
import re
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.component.model_exchange import PendulumStates
from double_pendulum.component.state_check import SHOWN_LENGTH, StateError
from double_pendulum.component.suspension import SuspensionCoSimulation
from double_pendulum.model.scene import ModelError
from double_pendulum.solvers import METHODS

STEP = 0.01


def pendulum(steps: int = 5, driven: bool = False, **values: Any) -> DoublePendulumCoSimulation:
    """A pendulum component after ``steps`` communication steps (``driven``: the pivot moving, new inputs each step)."""
    component = DoublePendulumCoSimulation()
    for name, value in values.items():
        component.set(name, value)
    component.initialise()
    for _ in range(steps):
        t = component.time
        if driven:
            component.set_input("pivot_x", 0.01 * math.sin(5.0 * t))
            component.set_input("pivot_vx", 0.05 * math.cos(5.0 * t))
            component.set_input("pivot_ax", -0.25 * math.sin(5.0 * t))
        component.do_step(t, STEP)
    return component


def suspension(steps: int = 5, **values: Any) -> SuspensionCoSimulation:
    """A suspension component after ``steps`` steps under a changing load."""
    component = SuspensionCoSimulation()
    for name, value in values.items():
        component.set(name, value)
    component.initialise()
    for k in range(steps):
        component.set_input("F_x", math.sin(k))
        component.do_step(component.time, STEP)
    return component


def model_exchange() -> PendulumStates:
    """Model Exchange states after a few derivative evaluations and an input jump."""
    states = PendulumStates(pendulum(steps=0, suspension=True))
    for k in range(3):
        states.set_time(0.001 * k)
        states.set_states([v + 1e-3 for v in states.x])
        states.derivatives()
    states.note_input("pivot_vx", 0.2)
    states.note_input("tau1", 0.01)
    return states


CHECK: dict[str, Callable[[Any], None]] = {
    "pendulum": DoublePendulumCoSimulation.check_state,
    "suspension": SuspensionCoSimulation.check_state,
    "model_exchange": PendulumStates.check_state,
}
REAL_RUNS: dict[str, tuple[str, Callable[[], Any]]] = {
    "pendulum, not initialised": ("pendulum", lambda: DoublePendulumCoSimulation()),
    "pendulum, initialised": ("pendulum", lambda: pendulum(steps=0)),
    "pendulum, defaults (dop853)": ("pendulum", lambda: pendulum()),
    **{f"pendulum, {solver}": ("pendulum", functools.partial(pendulum, solver=solver)) for solver in METHODS},
    "pendulum, rodas4, every mechanism": ("pendulum", lambda: pendulum(
        solver="rodas4", suspension=True, air_drag=True, bearing_friction=True, bearing_drag=True)),
    "pendulum, driven (dop853 landing steps)": ("pendulum", lambda: pendulum(steps=12, driven=True)),
    "pendulum, driven, pivot_input = position": ("pendulum", lambda: pendulum(
        steps=12, driven=True, pivot_input="position", solver="gauss4")),
    "suspension, not initialised": ("suspension", lambda: SuspensionCoSimulation()),
    "suspension, defaults (dop853)": ("suspension", lambda: suspension()),
    **{f"suspension, {solver}": ("suspension", functools.partial(suspension, solver=solver)) for solver in METHODS},
    "model exchange": ("model_exchange", model_exchange),
}


@functools.cache
def real_state(run: str) -> dict[str, Any]:
    """The state of real run ``run`` (as serialised: through JSON)."""
    return json.loads(json.dumps(REAL_RUNS[run][1]().get_state()))


@pytest.mark.parametrize("run", REAL_RUNS)
def test_a_real_state_passes_round_trips_through_json_and_restores(run):
    kind, make = REAL_RUNS[run]
    state = make().get_state()
    kept = copy.deepcopy(state)
    CHECK[kind](state)
    assert state == kept  # the check changes nothing
    restored = json.loads(json.dumps(state))
    assert restored == state
    CHECK[kind](restored)
    if kind != "model_exchange":
        fresh = type(make())()
        fresh.set_state(restored)
        assert fresh.get_state() == state


def test_the_integrator_state_variants_of_dop853_all_pass():
    """Driven, DOP853 lands on the communication points: deferred f(t, y), landing steps, restarts."""
    component, seen = pendulum(steps=0), set()
    for k in range(40):
        t = component.time
        component.set_input("pivot_x", 0.01 * math.sin(5.0 * t))
        component.set_input("pivot_ax", -0.25 * math.sin(5.0 * t) if k % 3 else 0.0)
        component.do_step(t, 0.002)
        state = component.get_state()
        DoublePendulumCoSimulation.check_state(state)
        integrator = state["integrator"]
        seen.add((len(integrator["stages"]), integrator["fy"] is None, integrator["landed"]))
    assert {(12, True, False), (7, False, True)} <= seen


# ---------------------------------------------------------------------- tampered states
# Each mutation takes a copy of a real state and returns the tampered state.
def _at(state: Any, path: tuple) -> Any:
    for key in path:
        state = state[key]
    return state


def _set(path: tuple, value: Any) -> Callable[[Any], Any]:
    def mutate(state: Any) -> Any:
        _at(state, path[:-1])[path[-1]] = value
        return state

    return mutate


def _delete(*path: Any) -> Callable[[Any], Any]:
    def mutate(state: Any) -> Any:
        del _at(state, path[:-1])[path[-1]]
        return state

    return mutate


def _append(*path: Any) -> Callable[[Any], Any]:
    def mutate(state: Any) -> Any:
        _at(state, path).append(0.0)
        return state

    return mutate


def _as_list(*path: Any) -> Callable[[Any], Any]:
    """The dict at ``path`` replaced by the list of its values."""
    def mutate(state: Any) -> Any:
        parent = _at(state, path[:-1])
        parent[path[-1]] = list(parent[path[-1]].values())
        return state

    return mutate


def _reversed(*path: Any) -> Callable[[Any], Any]:
    def mutate(state: Any) -> Any:
        _at(state, path).reverse()
        return state

    return mutate


PENDULUM = "pendulum, rodas4, every mechanism"
TAMPERED: list[tuple[str, str, Callable[[Any], Any], str]] = [
    # (real run, what, mutation, expected fragment of the message)
    (PENDULUM, "a string in the state vector", _set(("y", 2), "abc"), """state["y"][2] = 'abc' is not a number"""),
    (PENDULUM, "a string in the integrator's", _set(("integrator", "y", 2), "abc"),
     """state["integrator"]["y"][2] = 'abc' is not a number"""),
    (PENDULUM, "a string in a stage", _set(("integrator", "stages", 5, 0), "abc"),
     """state["integrator"]["stages"][5][0] = 'abc' is not a number"""),
    (PENDULUM, "a missing key", _delete("time"), 'state has no key "time"'),
    (PENDULUM, "a missing nested key", _delete("integrator", "h"), 'state["integrator"] has no key "h"'),
    (PENDULUM, "a missing parameter", _delete("values", "m1"), 'state["values"] has no key "m1"'),
    (PENDULUM, "an extra key", _set(("extra",), 1), "state has an unexpected key 'extra'"),
    (PENDULUM, "an extra parameter", _set(("values", "m3"), 0.1), """state["values"] has an unexpected key 'm3'"""),
    (PENDULUM, "an extra input", _set(("inputs", "tau3"), 0.0), """state["inputs"] has an unexpected key 'tau3'"""),
    (PENDULUM, "a state too many", _append("y"), 'state["y"] = ['),
    (PENDULUM, "a state too many (message)", _append("y"), "has 13 entries, expected 12 (the scene's states)"),
    (PENDULUM, "a short integrator state", _delete("integrator", "y_prev", 0),
     'state["integrator"]["y_prev"] = ['),
    (PENDULUM, "a stage too long", _append("integrator", "stages", 1), "has 13 entries, expected 12"),
    (PENDULUM, "a stage too many", _append("integrator", "stages"), "has 7 entries, expected 0 or 6 (rodas4)"),
    (PENDULUM, "no hold", _delete("hold"), 'state has no key "hold"'),
    (PENDULUM, "NaN for the time", _set(("time",), math.nan), 'state["time"] = nan is not finite'),
    (PENDULUM, "NaN in the state vector", _set(("y", 0), math.nan), 'state["y"][0] = nan is not finite'),
    (PENDULUM, "inf in the step size", _set(("integrator", "h"), math.inf),
     'state["integrator"]["h"] = inf is not finite'),
    (PENDULUM, "inf in an input", _set(("inputs", "tau1"), -math.inf), 'state["inputs"]["tau1"] = -inf is not finite'),
    (PENDULUM, "NaN in a parameter", _set(("values", "k_x"), math.nan), 'state["values"]["k_x"] = nan is not finite'),
    (PENDULUM, "a bool for the time", _set(("time",), True), 'state["time"] = True is a bool, not a number'),
    (PENDULUM, "a bool for a parameter", _set(("values", "m1"), False), 'state["values"]["m1"] = False is a bool'),
    (PENDULUM, "a bool for a count", _set(("integrator", "nfev"), True),
     'state["integrator"]["nfev"] = True is a bool, not an integer'),
    (PENDULUM, "a float for a count", _set(("integrator", "n_steps"), 5.0),
     'state["integrator"]["n_steps"] = 5.0 is not an integer'),
    (PENDULUM, "a number for a switch", _set(("values", "air_drag"), 1),
     'state["values"]["air_drag"] = 1 is not a bool'),
    (PENDULUM, "the integrator as a list", _as_list("integrator"), 'state["integrator"] = ['),
    (PENDULUM, "the integrator as a list (message)", _as_list("integrator"), "is not a dict"),
    (PENDULUM, "the parameters as a list", _as_list("values"), 'state["values"] = [0.301, 0.297'),
    (PENDULUM, "the outputs as a list", _as_list("outputs"), 'state["outputs"] = ['),
    (PENDULUM, "no integrator, initialised", _set(("integrator",), None),
     'state["integrator"] = None is not a dict'),
    (PENDULUM, "an unknown solver", _set(("values", "solver"), "rk5"),
     """state["values"]["solver"] = 'rk5' is not one of dop853, dopri5"""),
    (PENDULUM, "another solver", _set(("values", "solver"), "dop853"), "has 6 entries, expected 0 or 13 (dop853)"),
    (PENDULUM, "an unknown pivot_input", _set(("values", "pivot_input"), "force"),
     """state["values"]["pivot_input"] = 'force' is not one of acceleration, position"""),
    (PENDULUM, "a parameter out of its rule", _set(("values", "m1"), -0.3),
     'state["values"]["m1"] = -0.3 breaks its rule (invalid m1 = -0.3 kg: must be > 0)'),
    (PENDULUM, "a huge int", _set(("time",), 10**400), "is too large for a float"),
    (PENDULUM, "another version", _set(("version",), 2), 'state["version"] = 2 is not a supported FMU state version'),
    (PENDULUM, "a landing step of rodas4", _set(("integrator", "landed"), True),
     'state["integrator"]["landed"] = True but rodas4 has no landing method'),
    (PENDULUM, "deferred f(t, y) of rodas4", _set(("integrator", "fy"), None), "but rodas4 never defers f(t, y)"),
    (PENDULUM, "times out of order", _set(("integrator", "t_prev"), 1e3), "are not in order"),
    (PENDULUM, "a hold without inputs", _set(("hold",), [0.0, [0.0] * 8]), 'does not go with driven = False'),
    (PENDULUM, "the wrong pivot reader", _set(("pivot_samples",), []), "does not go with pivot_input = 'acceleration'"),
    (PENDULUM, "None at the top", lambda state: None, "state = None is not a dict"),
    (PENDULUM, "a list at the top", lambda state: list(state), "state = ['version', 'values'"),
    ("pendulum, driven, pivot_input = position", "pivot samples out of order", _reversed("pivot_samples"),
     'state["pivot_samples"] = [[0.1'),
    ("pendulum, driven, pivot_input = position", "pivot samples out of order (message)", _reversed("pivot_samples"),
     "has times that do not increase"),
    ("pendulum, driven, pivot_input = position", "a pivot sample too short", _delete("pivot_samples", 0, 2),
     'state["pivot_samples"][0] = [0.'),
    ("pendulum, driven, pivot_input = position", "a pivot sample too short (message)",
     _delete("pivot_samples", 0, 2), "has 2 entries, expected 3"),
    ("pendulum, not initialised", "an integrator, not initialised", _set(("integrator",), {}),
     'state["integrator"] = {} is not None, but the state is not initialised'),
    ("suspension, rodas4", "a string in the state vector", _set(("y", 1), "abc"),
     """state["y"][1] = 'abc' is not a number"""),
    ("suspension, rodas4", "a missing key", _delete("held"), 'state has no key "held"'),
    ("suspension, rodas4", "an extra key", _set(("outputs", "E_total"), 0.0),
     """state["outputs"] has an unexpected key 'E_total'"""),
    ("suspension, rodas4", "a wrong list length", _append("held"), "has 3 entries, expected 2"),
    ("suspension, rodas4", "NaN in the integrator", _set(("integrator", "y_prev", 3), math.nan),
     'state["integrator"]["y_prev"][3] = nan is not finite'),
    ("suspension, rodas4", "a bool for a float", _set(("inputs", "F_y"), True),
     'state["inputs"]["F_y"] = True is a bool'),
    ("suspension, rodas4", "the integrator as a list", _as_list("integrator"), "is not a dict"),
    ("suspension, rodas4", "None at the top", lambda state: None, "state = None is not a dict"),
    ("suspension, rodas4", "the pendulum's version", _set(("version",), 3), "this component's is 1"),
    ("model exchange", "a string in the state vector", _set(("x", 4), "abc"),
     """state["x"][4] = 'abc' is not a number"""),
    ("model exchange", "a missing key", _delete("instant"), 'state has no key "instant"'),
    ("model exchange", "an extra key", _set(("known", "F_x"), 0.0), """state["known"] has an unexpected key 'F_x'"""),
    ("model exchange", "a wrong list length", _delete("x", 0), "has 12 entries, expected 13"),
    ("model exchange", "NaN in an input", _set(("left", "tau1"), math.nan),
     'state["left"]["tau1"] = nan is not finite'),
    ("model exchange", "a bool for a float", _set(("time",), False), 'state["time"] = False is a bool, not a number'),
    ("model exchange", "the inputs as a list", _as_list("known"), 'state["known"] = [0.0'),
    ("model exchange", "None at the top", lambda state: None, "state = None is not a dict"),
    ("model exchange", "an unknown input", _set(("set_here", 0), "tau3"),
     """state["set_here"][0] = 'tau3' is not one of"""),
    ("model exchange", "an input twice", lambda state: {**state, "set_here": state["set_here"] * 2},
     'state["set_here"][2] = '),
    ("model exchange", "an input twice (message)", lambda state: {**state, "set_here": state["set_here"] * 2},
     "is there twice"),
]


def live(kind: str) -> Any:
    """A live component of ``kind``, somewhere else than the real runs (a partial restore would show)."""
    if kind == "pendulum":
        return pendulum(steps=3, air_drag=True, solver="dopri5")
    if kind == "suspension":
        return suspension(steps=3, k_x=1234.0)
    return model_exchange()


@pytest.mark.parametrize(("run", "what", "mutate", "fragment"), TAMPERED, ids=[f"{r} - {w}" for r, w, _, _ in TAMPERED])
def test_a_tampered_state_is_refused_naming_the_entry_and_changes_nothing(run, what, mutate, fragment):
    kind = REAL_RUNS[run][0]
    bad = mutate(copy.deepcopy(real_state(run)))
    with pytest.raises(StateError, match=re.escape(fragment)) as error:
        CHECK[kind](bad)
    message = str(error.value)
    assert "\n" not in message and len(message) < 400
    component = live(kind)
    before = component.get_state()
    with pytest.raises(StateError, match=re.escape(fragment)):
        component.set_state(bad)
    assert component.get_state() == before


def test_a_state_error_is_a_value_error_with_a_cut_value():
    state = copy.deepcopy(real_state(PENDULUM))
    state["integrator"] = "x" * 1000
    with pytest.raises(ValueError, match=r'^state\["integrator"\] = \'x+\.\.\. is not a dict$') as error:
        DoublePendulumCoSimulation.check_state(state)
    assert isinstance(error.value, StateError)
    assert len(str(error.value)) < len('state["integrator"] = ') + SHOWN_LENGTH + len(" is not a dict") + 1


def test_the_path_of_a_state_inside_another_is_named():
    state = copy.deepcopy(real_state("model exchange"))
    state["x"][0] = "abc"
    with pytest.raises(StateError, match=re.escape("""state["states"]["x"][0] = 'abc' is not a number""")):
        PendulumStates.check_state(state, path='state["states"]')


def test_a_restore_whose_rebuild_fails_changes_nothing():
    """Parameters within their rules that the model refuses when rebuilt: the component is put back."""
    state = json.loads(json.dumps(pendulum(bearing_friction=True).get_state()))
    state["values"].update(c_R1=1e4, r_b1=0.1)  # the joint-load iteration does not converge
    DoublePendulumCoSimulation.check_state(state)
    component = live("pendulum")
    before = component.get_state()
    with pytest.raises(ModelError):
        component.set_state(state)
    assert component.get_state() == before
    component.do_step(component.time, STEP)  # and it runs on


# ---------------------------------------------------------------------- any single leaf of a wrong type
def leaves(value: Any, path: tuple = ()) -> Iterator[tuple[tuple, Any]]:
    """Every leaf (not a dict or list) of a JSON value with its path of keys."""
    if isinstance(value, dict):
        for key, v in value.items():
            yield from leaves(v, (*path, key))
    elif isinstance(value, list):
        for k, v in enumerate(value):
            yield from leaves(v, (*path, k))
    else:
        yield path, value


def path_text(path: tuple) -> str:
    return "state" + "".join(f"[{k}]" if isinstance(k, int) else f'["{k}"]' for k in path)


CONTAINERS = st.sampled_from([[], {}, [0.0], {"a": 0.0}])


def wrong_type(value: Any) -> st.SearchStrategy[Any]:
    """Values of another type than ``value``'s (an int stands for a float: JSON writers may drop the .0)."""
    text = st.text(max_size=4)
    if isinstance(value, bool):
        return st.one_of(text, st.none(), st.integers(), st.floats(), CONTAINERS)
    if isinstance(value, int):
        return st.one_of(text, st.none(), st.booleans(), st.floats(), CONTAINERS)
    if isinstance(value, float):
        return st.one_of(text, st.none(), st.booleans(), CONTAINERS)
    if isinstance(value, str):
        return st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), CONTAINERS)
    assert value is None
    return st.one_of(text, st.booleans())


HYPOTHESIS_RUNS = ("pendulum, driven (dop853 landing steps)", "pendulum, driven, pivot_input = position", PENDULUM,
                   "pendulum, not initialised", "suspension, rodas4", "suspension, not initialised", "model exchange")


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_any_single_leaf_of_a_wrong_type_is_refused(data):
    run = data.draw(st.sampled_from(HYPOTHESIS_RUNS), label="run")
    state = copy.deepcopy(real_state(run))
    path, value = data.draw(st.sampled_from(list(leaves(state))), label="leaf")
    new = data.draw(wrong_type(value), label="new value")
    target = state
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = new
    kind = REAL_RUNS[run][0]
    with pytest.raises(StateError) as error:
        CHECK[kind](state)
    assert str(error.value).startswith(path_text(path)), str(error.value)
    component = _live_component(kind)
    before = component.get_state()
    with pytest.raises(StateError):
        component.set_state(state)
    assert component.get_state() == before


@functools.cache
def _live_component(kind: str) -> Any:
    return live(kind)
