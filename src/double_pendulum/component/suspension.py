"""The ``Suspension`` co-simulation component: the mass-spring-damper that can carry the pendulum.

What ``fmu_src/Suspension.py`` runs (model: :mod:`double_pendulum.model.suspension`), with the
same life cycle as :class:`~double_pendulum.component.cosimulation.DoublePendulumCoSimulation`:
``set`` parameters before :meth:`initialise`, :meth:`set_input` at any time, :meth:`do_step`,
:meth:`get_state`/:meth:`set_state`. The mass starts at rest in its static equilibrium.

The load ``F_x, F_y`` [N] is held constant over a communication step (zero-order hold: a force
has no derivative to extrapolate with). The integrator persists across steps; when the load
changes, its right-hand side jumps at the communication point and it is restarted there
(:meth:`~double_pendulum.solvers.Integrator.restart`).
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

from ..model.parameters import SuspensionLoad, SuspensionParameters, check_value
from ..model.suspension import PARAMETER_NAMES, STATE_NAMES, SuspensionModel
from ..solvers import Integrator, SolverError, make_integrator
from . import state_check as check
from .cosimulation import CoSimulationError, check_step_call, checked_parameter
from .settings import SolverSettings

PARAMETER_FIELDS = (
    *(f for f in fields(SuspensionParameters) if f.name in PARAMETER_NAMES),
    *fields(SuspensionLoad),
    *fields(SolverSettings),
)
INPUT_START = {"F_x": 0.0, "F_y": SuspensionLoad().F_static_y}  # the static load: at rest unconnected


class SuspensionCoSimulation:
    """One instance of the suspension as a co-simulation slave."""

    RULES = {f.name: (f.metadata["unit"], f.metadata["rule"]) for f in PARAMETER_FIELDS}
    STATE_VERSION = 1

    def __init__(self, start_time: float = 0.0) -> None:
        self.values: dict[str, Any] = {f.name: f.default for f in PARAMETER_FIELDS}
        self.inputs: dict[str, float] = dict(INPUT_START)
        self.time = float(start_time)
        self.initialised = False
        self.integrator: Integrator | None = None
        self.model = self._model()
        self._y = [0.0] * len(STATE_NAMES)
        self._held = self._load()  # the load the integrator integrates with
        self.initial_energy: float | None = None
        self.notices: list[str] = []  # warnings for the host's log (none so far), as the pendulum's component
        self.outputs: dict[str, float] = self.model.outputs(self._y, *self._held)

    # ------------------------------------------------------------------ variables
    def set(self, name: str, value: Any) -> None:
        """Set parameter ``name`` (before :meth:`initialise`); raises ``ParameterError`` if invalid."""
        self.values[name] = checked_parameter(self.RULES, name, value, self.initialised)

    def set_input(self, name: str, value: float) -> None:
        """Set the load component ``name`` [N]; a non-finite value is refused, naming it."""
        if name not in self.inputs:
            raise CoSimulationError(f"unknown input {name!r}")
        if isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        check_value(f"input {name}", value, "N", "finite")
        self.inputs[name] = value
        if self.initialised:
            self.outputs = self.model.outputs(self._y, *self._load(), self.initial_energy)

    def get(self, name: str) -> Any:
        """Return a parameter, input or output value by name."""
        for table in (self.values, self.inputs):
            if name in table:
                return table[name]
        return self.outputs[name]

    def _load(self) -> tuple[float, float]:
        return self.inputs["F_x"], self.inputs["F_y"]

    def _model(self) -> SuspensionModel:
        params = SuspensionParameters(**{n: self.values[n] for n in PARAMETER_NAMES})
        return SuspensionModel(params, SuspensionLoad(F_static_y=self.values["F_static_y"]))

    # ------------------------------------------------------------------ life cycle
    def set_start_time(self, start_time: float) -> None:
        """Set the simulation start time [s] (fmi2SetupExperiment)."""
        if not math.isfinite(start_time):
            raise CoSimulationError(f"invalid start time {start_time!r} s: must be finite")
        self.time = float(start_time)

    def initialise(self) -> None:
        """Check the parameters together and start at rest in the static equilibrium."""
        settings = SolverSettings(**{f.name: self.values[f.name] for f in fields(SolverSettings)})
        self.model = self._model()
        self._y = [0.0] * len(STATE_NAMES)
        self._held = self._load()
        self.integrator = make_integrator(
            settings.solver,
            self.model.vector_field(*self._held),
            self.time,
            self._y,
            rtol=settings.rtol,
            atol=settings.atol,
            fixed_step=settings.fixed_step,
            max_steps_per_call=max(1, int(settings.max_steps)),
        )
        self.outputs = self.model.outputs(self._y, *self._held)
        self.initial_energy = self.outputs["E_suspension"]
        self.initialised = True

    def do_step(self, current_time: float, step_size: float) -> None:
        """Advance from ``current_time`` [s] by ``step_size`` [s] with the load held as set now."""
        check_step_call(self.initialised and self.integrator is not None, self.time, current_time, step_size)
        if self._load() != self._held:  # the load jumps here: restart, integrate nothing across it
            self._held = self._load()
            self.integrator.restart(self.time, self._y, self.model.vector_field(*self._held))
        t_end = current_time + step_size
        y = self.integrator.advance_to(t_end)
        if not all(math.isfinite(v) for v in y):
            raise SolverError(f"numerical instability at t = {t_end:.6g} s: non-finite suspension state")
        self.time, self._y = t_end, list(y)
        self.outputs = self.model.outputs(self._y, *self._held, self.initial_energy)

    # ------------------------------------------------------------------ FMU state
    def get_state(self) -> dict[str, Any]:
        """Return the complete state (parameters, inputs, time, integrator) as JSON-serialisable data."""
        return {
            "version": self.STATE_VERSION,
            "values": dict(self.values),
            "inputs": dict(self.inputs),
            "held": list(self._held),
            "time": self.time,
            "initialised": self.initialised,
            "initial_energy": self.initial_energy,
            "y": list(self._y),
            "outputs": dict(self.outputs),
            "integrator": self.integrator.get_state() if self.integrator is not None else None,
        }

    @classmethod
    def check_state(cls, state: Any, *, path: str = "state") -> None:
        """Raise :class:`~.state_check.StateError` unless ``state`` is one :meth:`get_state` can return; change nothing.

        Checks the keys (none missing, none extra), the types, lengths and finiteness of every entry,
        the parameters by their rules, the solver by name and the integrator's state (its hidden
        state included) for the six states. Details:
        :func:`~double_pendulum.component.state_check.suspension_state`. The message names the entry
        by its path from ``path`` and shows its value.
        """
        check.suspension_state(path, state, cls.STATE_VERSION, cls.RULES)

    def set_state(self, state: dict[str, Any], *, validate: bool = True) -> None:
        """Restore a state from :meth:`get_state`; the run continues bit-identically.

        :meth:`check_state` first (unless ``validate`` is False, for a state this process made and kept): a
        state it refuses (:class:`~.state_check.StateError`) changes nothing.
        """
        if validate:
            self.check_state(state)
        with check.restored_on_failure(self):
            self._restore(state)

    def _restore(self, state: dict[str, Any]) -> None:
        self.values = dict(state["values"])
        self.inputs = {name: float(value) for name, value in state["inputs"].items()}
        self.time = float(state["time"])
        self.initialised = False
        self.integrator = None
        if state["initialised"]:
            self.initialise()
            self._held = (float(state["held"][0]), float(state["held"][1]))
            self.integrator.f = self.model.vector_field(*self._held)
            self.integrator.set_state(state["integrator"])
            self.time = float(state["time"])
        self._y = list(state["y"])
        self.initial_energy = state["initial_energy"]
        self.outputs = dict(state["outputs"])
