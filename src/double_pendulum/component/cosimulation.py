"""The co-simulation component: parameters by name, initialisation, doStep, outputs.

This is what the FMU runs (``fmu_src/DoublePendulum.py`` only maps FMI calls onto it) and what
:func:`double_pendulum.fmu.masters.simulate.simulate` runs in-process, so both give identical numbers.

Life cycle (FMI 2.0 co-simulation):

1. ``set(name, value)`` any parameter, before :meth:`initialise` only; each value is checked at
   once against its declared rule, so a bad value fails at the call that sets it;
2. :meth:`initialise` builds the parameter dataclasses (cross-checks), the vector field and the
   integrator, and computes the outputs at the start time;
3. :meth:`do_step` advances from ``current_time`` by ``step_size``; the integrator persists
   between calls, so results do not depend on the communication step.

Inputs (:mod:`double_pendulum.model.inputs`) may be set at any time with :meth:`set_input`; a
non-finite value is refused. While every input is 0 the component runs the model without
inputs (bit-identical to a build without them). The first non-zero input switches it, at the
current communication point, to the model with inputs (one more state, ``W_input``). Each
``do_step`` then holds the inputs set for it (second-order hold,
:class:`~double_pendulum.model.inputs.InputHold`); when they do not continue the previous step's
hold, the right-hand side jumps at ``current_time`` and the integrator is restarted there
(:meth:`~double_pendulum.solvers.Integrator.restart`), so no step or dense output computed with
the old inputs is used beyond the communication point. If the new values make the pivot's (or
base's) position or velocity jump, the energy changes at once (kinetic energy with the pivot
velocity, spring energy with the base position); that change is booked into ``W_input`` at the
jump, so ``energy_residual`` keeps measuring only the integration error.
"""

from __future__ import annotations

import functools
import math
import numbers
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import fields
from typing import Any

from ..model.energy import pivot_motion_energy, relative_momentum
from ..model.inputs import INPUT_NAMES, INPUT_UNITS, ZERO_INPUTS, InputHold, InputValues
from ..model.links import LinkCoefficients, link_coefficients
from ..model.outputs import GROUP_OF, OUTPUT_GROUPS, OUTPUT_NAMES
from ..model.parameters import (
    AirDragParameters,
    BearingParameters,
    InitialState,
    ParameterError,
    PendulumParameters,
    SuspensionParameters,
    check_value,
)
from ..model.scene import ModelError
from ..model.vector_field import (
    Model,
    ModelConfig,
    build_model,
    build_vector_field,
    energies,
    state_layout,
)
from ..solvers import Integrator, SolverError, make_integrator
from . import state_check as check
from .pivot_motion import PositionOnlyWatch, PositionSamples
from .settings import InputSettings, SolverSettings
from .state_check import StateError

PARAMETER_GROUPS: tuple[type, ...] = (
    PendulumParameters,
    InitialState,
    AirDragParameters,
    BearingParameters,
    SuspensionParameters,
    SolverSettings,
    InputSettings,
)
STRING_PARAMETER_GROUPS: dict[str, type] = {"solver": SolverSettings, "pivot_input": InputSettings}
"""String parameters, by name, and the group whose checks a value must pass (names, not just strings)."""
ENERGY_BLOWUP_FACTOR = 1e3


class CoSimulationError(RuntimeError):
    """A co-simulation call was made out of order or with an invalid argument."""


def check_step_call(initialised: bool, time: float, current_time: float, step_size: float) -> None:
    """Raise :class:`CoSimulationError` for a doStep out of order or with a non-positive step [s]."""
    if not initialised:
        raise CoSimulationError("doStep called before initialisation")
    if not (math.isfinite(step_size) and step_size > 0.0):
        raise CoSimulationError(f"invalid communication step size {step_size!r} s: must be > 0")
    if abs(current_time - time) > 1e-9 * max(1.0, abs(time)):
        raise CoSimulationError(
            f"doStep at t = {current_time!r} s does not continue from the last communication "
            f"point t = {time!r} s"
        )


def checked_parameter(rules: Mapping[str, tuple[str, str]], name: str, value: Any, initialised: bool) -> Any:
    """Return ``value`` for parameter ``name`` after checking it against ``rules``; a real-valued parameter's
    number becomes a Python float (ints, and numpy's scalars, which a fit's parameter vector holds: in the scalar
    right-hand side they made every run about 2.6 times slower for the same numbers).

    Raises :class:`ParameterError` for an unknown name or a value that breaks its rule and
    :class:`CoSimulationError` after initialisation (FMI: fixed parameters).
    """
    if name not in rules:
        raise ParameterError(f"unknown parameter {name!r}")
    if initialised:
        raise CoSimulationError(
            f"cannot set parameter {name} = {value!r} after initialisation (FMI: a fixed parameter "
            "is set before the FMU leaves Initialization Mode)"
        )
    unit, rule = rules[name]
    if rule not in ("str", "bool", "count") and isinstance(value, numbers.Real) and not isinstance(value, bool):
        value = float(value)
    if rule == "count" and isinstance(value, float) and value.is_integer() and abs(value) < 2.0**53:
        value = int(value)  # 1e6 from Python is the count 1000000; 1.5 is refused by check_value
    check_value(name, value, unit, rule)
    if name in STRING_PARAMETER_GROUPS:
        STRING_PARAMETER_GROUPS[name](**{name: value})  # checks the name
    return value


def _parameter_rules() -> dict[str, tuple[str, str]]:
    """Map each parameter name to ``(unit, rule)``."""
    return {
        f.name: (f.metadata["unit"], f.metadata["rule"]) for group in PARAMETER_GROUPS for f in fields(group)
    }


def default_parameter_values() -> dict[str, Any]:
    """Return every parameter's default, by name."""
    return {f.name: f.default for group in PARAMETER_GROUPS for f in fields(group)}


def parameter_group(cls: type, values: Mapping[str, Any]) -> Any:
    """The parameter dataclass ``cls`` of the parameter ``values`` (by name)."""
    return cls(**{f.name: values[f.name] for f in fields(cls)})


def scene_config(values: Mapping[str, Any], inputs: bool) -> ModelConfig:
    """The scene of the parameter ``values`` (by name), with inputs if ``inputs``."""
    return ModelConfig(
        pendulum=parameter_group(PendulumParameters, values),
        air=parameter_group(AirDragParameters, values),
        bearing=parameter_group(BearingParameters, values),
        suspension=parameter_group(SuspensionParameters, values),
        inputs=inputs,
    )


def _scene_size(values: Mapping[str, Any], inputs: bool) -> int:
    """The number of states of :func:`scene_config` for checked ``values`` (builds parameter records, no model)."""
    return _scene_size_of(tuple(values.items()), inputs)


@functools.lru_cache(maxsize=64)
def _scene_size_of(items: tuple[tuple[str, Any], ...], inputs: bool) -> int:
    return state_layout(scene_config(dict(items), inputs)).size


class LazyOutputs(Mapping[str, float]):
    """The outputs at one communication point, computed group by group on first access.

    A host that reads only the angles never pays for the energies or the pivot force
    (see :data:`double_pendulum.model.outputs.OUTPUT_GROUPS`).
    """

    def __init__(self, model: Model | None, y: list[float] | None, initial_energy: float | None,
                 solver_stats: dict[str, float], values: Mapping[str, float] | None = None,
                 inputs: InputValues | None = None) -> None:
        self._model, self._y, self._e0, self._u = model, y, initial_energy, inputs
        self._values: dict[str, float] = {**solver_stats, **(values or {})}
        self._done: set[int] = set() if values is None else set(range(len(OUTPUT_GROUPS)))

    _STATE_INDEX = {"phi1": 0, "phi2": 1, "omega1": 2, "omega2": 3}

    def __getitem__(self, name: str) -> float:
        index = self._STATE_INDEX.get(name)
        if index is not None and self._y is not None:
            return self._y[index]
        if name not in self._values:
            group = GROUP_OF[name]  # KeyError for unknown names, as a dict would
            if group not in self._done:
                self._values.update(OUTPUT_GROUPS[group](self._model, self._y, self._e0, self._u))
                self._done.add(group)
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(OUTPUT_NAMES)

    def __len__(self) -> int:
        return len(OUTPUT_NAMES)


INPUT_INDEX: dict[str, int] = {name: k for k, name in enumerate(INPUT_NAMES)}
STATE_OUTPUT_INDEX: dict[str, int] = {"phi1": 0, "phi2": 1, "omega1": 2, "omega2": 3}


class DoublePendulumCoSimulation:
    """One instance of the double pendulum as a co-simulation slave."""

    RULES = _parameter_rules()

    def __init__(self, start_time: float = 0.0) -> None:
        self.values: dict[str, Any] = default_parameter_values()
        self.time = float(start_time)
        self.initialised = False
        self.integrator: Integrator | None = None
        self.model: Model = build_model(ModelConfig())
        self._coefficients: LinkCoefficients = link_coefficients(self.model.config.pendulum)
        self._outputs: Mapping[str, float] | None = None  # None: computed when read
        self._inputs_set = False  # inputs set since the last communication point
        self.initial_energy: float | None = None
        self._u: list[float] = [0.0] * len(INPUT_NAMES)  # the inputs as set, in INPUT_NAMES order
        self.driven = False  # the model with inputs is running (from the first non-zero input on)
        self._hold: InputHold | None = None  # the hold the integrator is integrating (reset in place)
        self._fixed_step = False  # the solver is a fixed-step one (its blow-up is checked per step)
        self._pivot_samples: PositionSamples | None = None  # pivot_input = position: the last positions
        self._position_watch: PositionOnlyWatch | None = None  # pivot_input = acceleration: position-only wiring
        self.notices: list[str] = []  # warnings for the host's log, taken by the FMU adapter
        self._y: list[float] = self.model.initial_state(*InitialState().as_list())  # state at self.time
        self._update_outputs(self._y)

    # ------------------------------------------------------------------ parameters
    def set(self, name: str, value: Any) -> None:
        """Set parameter ``name``; raises :class:`ParameterError` for an invalid value."""
        self.values[name] = checked_parameter(self.RULES, name, value, self.initialised)

    def get(self, name: str) -> Any:
        """Return a parameter, input or output value by name."""
        index = STATE_OUTPUT_INDEX.get(name)
        if index is not None:
            return self._y[index]
        if name in self.values:
            return self.values[name]
        index = INPUT_INDEX.get(name)
        if index is not None:
            return self._u[index]
        return self.outputs[name]

    # ------------------------------------------------------------------ inputs
    @property
    def inputs(self) -> dict[str, float]:
        """The inputs as set now, by name (a copy)."""
        return dict(zip(INPUT_NAMES, self._u))

    def set_input(self, name: str, value: float) -> None:
        """Set input ``name`` [its unit] for the next ``do_step``; any time, any number of times.

        Raises :class:`ParameterError` naming the input and value if it is not a finite number
        (the input keeps its previous value). Outputs read afterwards see the new inputs (the
        pivot force depends on them directly).
        """
        index = INPUT_INDEX.get(name)
        if index is None:
            raise ParameterError(f"unknown input {name!r}")
        self.set_input_at(index, value)

    def set_input_at(self, index: int, value: float) -> None:
        """:meth:`set_input` by position in :data:`~double_pendulum.model.inputs.INPUT_NAMES`."""
        self.set_inputs_at((index,), (value,))

    def set_inputs_at(self, indices: Sequence[int], values: Sequence[float]) -> None:
        """Set several inputs by position (the hot path of a co-simulation master's fmi2SetReal).

        A finite float costs one check and a store; the right-hand side learns of the new values
        at the next ``do_step``. A bad value raises :class:`ParameterError` naming the input; the
        values before it are set, it and those after it are not.
        """
        u = self._u
        changed = False
        for index, value in zip(indices, values):
            if type(value) is not float or value - value != 0.0:  # not a float, or inf or nan
                value = self._checked_input(index, value)
            if value != u[index]:
                u[index] = value
                changed = True
        if changed:
            self._outputs = None  # recomputed when read: a host sets several inputs per step
            self._inputs_set = True
            if self.initialised and not self.driven:
                self._start_driving()

    def _checked_input(self, index: int, value: Any) -> float:
        """``value`` as a float, or :class:`ParameterError` naming the input and value."""
        name = INPUT_NAMES[index]
        if isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        check_value(f"input {name}", value, INPUT_UNITS[name], "finite")
        return value

    @property
    def outputs(self) -> Mapping[str, float]:
        """The outputs at the current communication point, with the inputs as now set."""
        if self._outputs is None:
            if self.driven and self._inputs_set:
                new = self._input_values()
                y = self.with_jump_work(self._y, self._hold.held(self.time), new)  # as it will be booked
                self._outputs = self._outputs_at(y, new)
            else:
                self._outputs = self._outputs_at(self._y, self._hold.at(self.time) if self.driven else None)
        return self._outputs

    @outputs.setter
    def outputs(self, values: Mapping[str, float]) -> None:
        self._outputs = values

    def state_values(self) -> dict[str, float]:
        """The model's state at the current communication point, by state name (``model.layout``)."""
        return dict(zip(self.model.layout.names, self._y))

    def _input_values(self) -> InputValues:
        return InputValues(*self._u)

    def with_jump_work(self, y: list[float], old: Sequence[float], new: Sequence[float]) -> list[float]:
        """Return ``y`` with the energy jump [J] of switching the inputs ``old -> new`` added to ``W_input``.

        ``old`` and ``new`` are the eight input values in :data:`INPUT_NAMES` order. Only the pivot
        (base) position and velocity change the energy at once; a consistent hold makes the jump
        vanish with the communication step. Without a suspension only the pivot's velocity counts
        (:func:`~double_pendulum.model.energy.pivot_motion_energy`: the potential energy is relative
        to the pivot).
        """
        config, layout = self.model.config, self.model.layout
        if config.suspension.suspension:
            jump = sum(energies(config, y, layout, InputValues(*new))) - sum(
                energies(config, y, layout, InputValues(*old))
            )
        elif old[2] == new[2] and old[3] == new[3]:
            return y
        else:
            c = self._coefficients
            px, py = relative_momentum(y[0], y[1], y[2], y[3], c)
            before = pivot_motion_energy(px, py, old[2], old[3], c.mass)
            jump = pivot_motion_energy(px, py, new[2], new[3], c.mass) - before
        if jump == 0.0:
            return y
        booked = list(y)
        booked[layout.index("W_input")] += jump
        return booked

    def _start_driving(self) -> None:
        """Switch to the model with inputs at the current point: add ``W_input = 0``, restart."""
        self.driven = True
        self.model = build_model(self.model_config())
        self._y = self._y + [0.0]  # W_input is the last state
        self._hold = InputHold(self.time, ZERO_INPUTS)
        self.integrator.f = build_vector_field(self.model.config, self.model.evaluate, self._hold)
        self._restart(self.time)

    def _restart(self, t: float) -> None:
        """Restart the integrator at ``t`` with the inputs set now: the hold and the right-hand side
        (which reads the hold) change in place; the step size carries over."""
        self._y = self.with_jump_work(self._y, self._hold.held(t), self._u)
        self._hold.reset(t, self._u)
        self.integrator.restart(t, self._y)

    def _group(self, cls: type) -> Any:
        return parameter_group(cls, self.values)

    # ------------------------------------------------------------------ life cycle
    def set_start_time(self, start_time: float) -> None:
        """Set the simulation start time [s] (fmi2SetupExperiment)."""
        if not math.isfinite(start_time):
            raise CoSimulationError(f"invalid start time {start_time!r} s: must be finite")
        self.time = float(start_time)

    def model_config(self, inputs: bool | None = None) -> ModelConfig:
        """The scene of the parameters set so far, with inputs if ``inputs`` (default: if driven)."""
        return scene_config(self.values, self.driven if inputs is None else inputs)

    def initialise(self) -> None:
        """Validate all parameters together and start the integrator at the start time."""
        self.driven = self.driven or any(self._u)
        initial = self._group(InitialState)
        settings = self._group(SolverSettings)
        self.model = build_model(self.model_config())
        self._coefficients = link_coefficients(self.model.config.pendulum)
        y0 = self.model.initial_state(*initial.as_list())
        self._hold = InputHold(self.time, self._u) if self.driven else None
        self.integrator = make_integrator(
            settings.solver,
            build_vector_field(self.model.config, self.model.evaluate, self._hold),
            self.time,
            y0,
            rtol=settings.rtol,
            atol=settings.atol,
            fixed_step=settings.fixed_step,
            max_steps_per_call=max(1, int(settings.max_steps)),
        )
        self._fixed_step = not self.integrator.method.adaptive
        self._start_pivot_input()
        self.initial_energy = None
        self._y = y0
        self._inputs_set = False
        self._update_outputs(y0)
        self.initial_energy = self.outputs["E_total"]
        self.initialised = True

    def _start_pivot_input(self, samples: list | None = None, watch: dict | None = None) -> None:
        """Set up the reading of the pivot inputs (:mod:`~double_pendulum.component.pivot_motion`)."""
        layout = self.model.layout
        if self._group(InputSettings).pivot_input == "position":
            self._pivot_samples, self._position_watch = PositionSamples(samples or ()), None
        else:
            self._pivot_samples = None
            self._position_watch = PositionOnlyWatch(layout.index("xs") is None, layout.index("ys") is None)
            if watch:
                self._position_watch.last = tuple(watch["last"]) if watch["last"] is not None else None
                self._position_watch.warned = watch["warned"]

    def _read_pivot_input(self) -> None:
        """At a communication point: derive the pivot's velocity and acceleration from its positions
        (``pivot_input = position``), or look out for position-only wiring (``acceleration``)."""
        u = self._u
        if self._pivot_samples is not None:
            u[2], u[3], u[4], u[5] = self._pivot_samples.rates_at(self.time, u[0], u[1])
        elif not self._position_watch.warned and self.driven:
            notice = self._position_watch.check(u)
            if notice:
                self.notices.append(notice)

    def do_step(self, current_time: float, step_size: float) -> None:
        """Advance from ``current_time`` [s] to ``current_time + step_size`` [s].

        Raises :class:`CoSimulationError` for a call out of order or a non-positive step and
        :class:`SolverError` when the integrator gives up; the state is then left at the last
        successful communication point. The outputs are computed when read.
        """
        if not (current_time == self.time and 0.0 < step_size < math.inf and self.initialised):
            check_step_call(self.initialised and self.integrator is not None, self.time, current_time, step_size)
        t_end = current_time + step_size
        land = False
        if self.driven or self._pivot_samples is not None:
            self._read_pivot_input()
        try:
            if self.driven:
                if not self._hold.continued_by(self.time, self._u):
                    self._restart(self.time)  # the inputs jump here: integrate nothing across it
                    # Land on t_end: the next step likely restarts too, so a step past it and its
                    # dense output would be wasted.
                    land = True
                self._inputs_set = False
            y = self.integrator.advance_to(t_end, land=land)
        except ModelError as error:
            raise SolverError(str(error)) from error
        if self._fixed_step:  # adaptive methods reject non-finite or inaccurate steps
            self._check_bounded(y, self._outputs_at(y, self._hold.at(t_end) if self.driven else None), t_end)
        self.time = t_end
        self._y = y
        self._outputs = None

    # ------------------------------------------------------------------ FMU state
    STATE_VERSION = 3

    def get_state(self) -> dict[str, Any]:
        """Return the complete state (parameters, time, integrator) as JSON-serialisable data.

        Restoring it with :meth:`set_state`, in this or a fresh instance, continues bit-identically:
        the integrator's hidden state (step size, last step, stage derivatives) is included.
        """
        watch = self._position_watch
        return {
            "version": self.STATE_VERSION,
            "values": dict(self.values),
            "time": self.time,
            "initialised": self.initialised,
            "initial_energy": self.initial_energy,
            "outputs": dict(self.outputs),
            "integrator": self.integrator.get_state() if self.integrator is not None else None,
            "inputs": self.inputs,
            "driven": self.driven,
            "hold": [self._hold.t0, list(self._hold.u)] if self._hold is not None else None,
            "y": list(self._y),
            "pivot_samples": [list(s) for s in self._pivot_samples.samples] if self._pivot_samples else None,
            "position_watch": (
                {"last": list(watch.last) if watch.last is not None else None, "warned": watch.warned}
                if watch is not None else None
            ),
        }

    @classmethod
    def check_state(cls, state: Any, *, path: str = "state") -> None:
        """Raise :class:`StateError` unless ``state`` is one :meth:`get_state` can return; build and change nothing.

        Checks the keys (none missing, none extra), the types, lengths and finiteness of every entry,
        the parameters by their rules and names, and, initialised, the state's fit to its scene: ``y``
        and the integrator's state (its hidden state included) sized for the scene's states, the
        input hold and pivot readers as driven and ``pivot_input`` have them. Details:
        :func:`~double_pendulum.component.state_check.cosimulation_state`. The message names the entry
        by its path from ``path`` and shows its value.
        """
        check.cosimulation_state(path, state, cls.STATE_VERSION, cls.RULES, _scene_size)

    def set_state(self, state: dict[str, Any], *, validate: bool = True) -> None:
        """Restore a state from :meth:`get_state` (FMI fmi2SetFMUstate).

        :meth:`check_state` first (unless ``validate`` is False: a state this process made and kept, as a
        master's rollback or the FMU's own fmi2SetFMUstate, needs no second look, and the check costs
        20 to 40 us): a state it refuses (:class:`StateError`) changes nothing, nor does one whose
        parameters the rebuild refuses (the attributes are put back).
        """
        if validate:
            self.check_state(state)
        with check.restored_on_failure(self):
            self._restore(state)

    def _restore(self, state: dict[str, Any]) -> None:
        values = dict(state["values"])
        # A rollback to a state of this same model (coupling iterations) keeps the model and the integrator
        # object: the integrator's complete state is restored below, so only the rebuild is saved.
        model, integrator = self.model, self.integrator
        same_model = self.initialised and model is not None and integrator is not None and values == self.values
        self.values = values
        self.initialised = False
        self.integrator = None
        self.time = float(state["time"])
        self._u = [float(state["inputs"][name]) for name in INPUT_NAMES]
        self.driven = bool(state["driven"])
        if state["initialised"]:
            driven = self.driven or any(self._u)
            if same_model and model.config.inputs == driven:
                # the integrator's vector field reads self._hold: reset it in place (below), nothing rebuilt
                self.driven, self.model, self.integrator, self.initialised = driven, model, integrator, True
                if driven:
                    self._hold.reset(self.time, self._u)
                else:
                    self._hold = None
            else:
                self.initialise()  # rebuilds model, integrator and hold from the restored parameters
            hold = state["hold"]
            if hold is not None:
                self._hold.reset(float(hold[0]), [float(v) for v in hold[1]])
            self.integrator.set_state(state["integrator"])
            self.time = float(state["time"])
            self._y = list(state["y"])
            self._start_pivot_input(state["pivot_samples"], state["position_watch"])
        self.initial_energy = state["initial_energy"]
        self.outputs = LazyOutputs(None, None, None, {}, values=state["outputs"])
        self._inputs_set = False

    def _check_bounded(self, y: list[float], outputs: Mapping[str, float], t_end: float) -> None:
        """Raise :class:`SolverError` if the motion has blown up numerically.

        Without inputs the energy can never rise above the start energy, and with inputs
        ``E_total - W_input`` cannot. A value beyond ``ENERGY_BLOWUP_FACTOR`` times the start
        energy plus the energy scale ``M g (l1 + l2)`` (M the pendulum's mass, bobs and rods), or a
        non-finite state, can only come from an unstable integration (e.g. explicit Euler with too
        large a step); it is reported instead of returning meaningless numbers.
        """
        energy = outputs["E_total"] - outputs["W_input"]
        p = self.model.config.pendulum
        e0 = self.initial_energy or 0.0
        limit = ENERGY_BLOWUP_FACTOR * (abs(e0) + link_coefficients(p).mass * p.g * (p.l1 + p.l2))
        if not all(math.isfinite(v) for v in y) or not abs(energy) <= limit:
            raise SolverError(
                f"numerical instability at t = {t_end:.6g} s: E_total = {energy:.6g} J, started at "
                f"{e0:.6g} J (solver {self.values['solver']}; reduce fixed_step or "
                "use an adaptive solver)"
            )

    def _outputs_at(self, y: list[float], inputs: InputValues | None = None) -> LazyOutputs:
        it = self.integrator
        stats = {
            "solver_steps": float(it.n_steps) if it is not None else 0.0,
            "solver_rhs_evaluations": float(it.nfev) if it is not None else 0.0,
        }
        return LazyOutputs(self.model, list(y), self.initial_energy, stats, inputs=inputs)

    def _update_outputs(self, y: list[float]) -> None:
        """Outputs at the current point with the inputs as set now."""
        self.outputs = self._outputs_at(y, self._input_values() if self.driven else None)


__all__ = [
    "CoSimulationError",
    "DoublePendulumCoSimulation",
    "PARAMETER_GROUPS",
    "ParameterError",
    "SolverError",
    "StateError",
    "default_parameter_values",
]
