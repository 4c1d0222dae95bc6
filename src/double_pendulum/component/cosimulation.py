"""The co-simulation component: parameters by name, initialisation, doStep, outputs.

This is what the FMU runs (``fmu_src/DoublePendulum.py`` only maps FMI calls onto it) and what
:func:`double_pendulum.fmu.simulate.simulate` runs in-process, so both give identical numbers.

Life cycle (FMI 2.0 co-simulation):

1. ``set(name, value)`` any parameter, before :meth:`initialise` only; each value is checked at
   once against its declared rule, so a bad value fails at the call that sets it;
2. :meth:`initialise` builds the parameter dataclasses (cross-checks), the vector field and the
   integrator, and computes the outputs at the start time;
3. :meth:`do_step` advances from ``current_time`` by ``step_size``; the integrator persists
   between calls, so results do not depend on the communication step.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import fields
from typing import Any

from ..model.links import link_coefficients
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
from ..model.vector_field import Model, ModelConfig, ModelError, build_model
from ..solvers import Integrator, SolverError, make_integrator
from .settings import SolverSettings

PARAMETER_GROUPS: tuple[type, ...] = (
    PendulumParameters,
    InitialState,
    AirDragParameters,
    BearingParameters,
    SuspensionParameters,
    SolverSettings,
)
ENERGY_BLOWUP_FACTOR = 1e3


class CoSimulationError(RuntimeError):
    """A co-simulation call was made out of order or with an invalid argument."""


def _parameter_rules() -> dict[str, tuple[str, str]]:
    """Map each parameter name to ``(unit, rule)``."""
    return {
        f.name: (f.metadata["unit"], f.metadata["rule"]) for group in PARAMETER_GROUPS for f in fields(group)
    }


def default_parameter_values() -> dict[str, Any]:
    """Return every parameter's default, by name."""
    return {f.name: f.default for group in PARAMETER_GROUPS for f in fields(group)}


class LazyOutputs(Mapping[str, float]):
    """The outputs at one communication point, computed group by group on first access.

    A host that reads only the angles never pays for the energies or the pivot force
    (see :data:`double_pendulum.model.outputs.OUTPUT_GROUPS`).
    """

    def __init__(self, model: Model | None, y: list[float] | None, initial_energy: float | None,
                 solver_stats: dict[str, float], values: Mapping[str, float] | None = None) -> None:
        self._model, self._y, self._e0 = model, y, initial_energy
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
                self._values.update(OUTPUT_GROUPS[group](self._model, self._y, self._e0))
                self._done.add(group)
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(OUTPUT_NAMES)

    def __len__(self) -> int:
        return len(OUTPUT_NAMES)


class DoublePendulumCoSimulation:
    """One instance of the double pendulum as a co-simulation slave."""

    RULES = _parameter_rules()

    def __init__(self, start_time: float = 0.0) -> None:
        self.values: dict[str, Any] = default_parameter_values()
        self.time = float(start_time)
        self.initialised = False
        self.integrator: Integrator | None = None
        self.model: Model = build_model(ModelConfig())
        self.outputs: Mapping[str, float] = {}
        self.initial_energy: float | None = None
        self._update_outputs(self.model.initial_state(*InitialState().as_list()))

    # ------------------------------------------------------------------ parameters
    def set(self, name: str, value: Any) -> None:
        """Set parameter ``name``; raises :class:`ParameterError` for an invalid value."""
        if name not in self.RULES:
            raise ParameterError(f"unknown parameter {name!r}")
        if self.initialised:
            raise CoSimulationError(
                f"cannot set parameter {name} = {value!r} after initialisation (FMI: fixed parameters "
                "may only be set before fmi2ExitInitializationMode)"
            )
        unit, rule = self.RULES[name]
        if rule != "str" and rule != "bool" and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        check_value(name, value, unit, rule)
        if name == "solver":
            SolverSettings(solver=value)  # checks the name
        self.values[name] = value

    def get(self, name: str) -> Any:
        """Return a parameter or output value by name."""
        if name in self.values:
            return self.values[name]
        return self.outputs[name]

    def _group(self, cls: type) -> Any:
        return cls(**{f.name: self.values[f.name] for f in fields(cls)})

    # ------------------------------------------------------------------ life cycle
    def set_start_time(self, start_time: float) -> None:
        """Set the simulation start time [s] (fmi2SetupExperiment)."""
        if not math.isfinite(start_time):
            raise CoSimulationError(f"invalid start time {start_time!r} s: must be finite")
        self.time = float(start_time)

    def initialise(self) -> None:
        """Validate all parameters together and start the integrator at the start time."""
        config = ModelConfig(
            pendulum=self._group(PendulumParameters),
            air=self._group(AirDragParameters),
            bearing=self._group(BearingParameters),
            suspension=self._group(SuspensionParameters),
        )
        initial = self._group(InitialState)
        settings = self._group(SolverSettings)
        self.model = build_model(config)
        y0 = self.model.initial_state(*initial.as_list())
        self.integrator = make_integrator(
            settings.solver,
            self.model.vector_field,
            self.time,
            y0,
            rtol=settings.rtol,
            atol=settings.atol,
            fixed_step=settings.fixed_step,
            max_steps_per_call=max(1, int(settings.max_steps)),
        )
        self.initial_energy = None
        self._update_outputs(y0)
        self.initial_energy = self.outputs["E_total"]
        self.initialised = True

    def do_step(self, current_time: float, step_size: float) -> None:
        """Advance from ``current_time`` [s] to ``current_time + step_size`` [s].

        Raises :class:`CoSimulationError` for a call out of order or a non-positive step and
        :class:`SolverError` when the integrator gives up; the state is then left at the last
        successful communication point.
        """
        if not self.initialised or self.integrator is None:
            raise CoSimulationError("doStep called before initialisation")
        if not (math.isfinite(step_size) and step_size > 0.0):
            raise CoSimulationError(f"invalid communication step size {step_size!r} s: must be > 0")
        if abs(current_time - self.time) > 1e-9 * max(1.0, abs(self.time)):
            raise CoSimulationError(
                f"doStep at t = {current_time!r} s does not continue from the last communication "
                f"point t = {self.time!r} s"
            )
        t_end = current_time + step_size
        try:
            y = self.integrator.advance_to(t_end)
        except ModelError as error:
            raise SolverError(str(error)) from error
        outputs = self._outputs_at(y)
        if not self.integrator.method.adaptive:  # adaptive methods reject non-finite or inaccurate steps
            self._check_bounded(y, outputs, t_end)
        self.time = t_end
        self.outputs = outputs

    # ------------------------------------------------------------------ FMU state
    STATE_VERSION = 1

    def get_state(self) -> dict[str, Any]:
        """Return the complete state (parameters, time, integrator) as JSON-serialisable data.

        Restoring it with :meth:`set_state`, in this or a fresh instance, continues bit-identically:
        the integrator's hidden state (step size, last step, stage derivatives) is included.
        """
        return {
            "version": self.STATE_VERSION,
            "values": dict(self.values),
            "time": self.time,
            "initialised": self.initialised,
            "initial_energy": self.initial_energy,
            "outputs": dict(self.outputs),
            "integrator": self.integrator.get_state() if self.integrator is not None else None,
        }

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore a state from :meth:`get_state` (FMI fmi2SetFMUstate)."""
        if state.get("version") != self.STATE_VERSION:
            raise CoSimulationError(f"unsupported FMU state version {state.get('version')!r}")
        values = dict(state["values"])
        if set(values) != set(self.values):
            raise CoSimulationError("FMU state does not match this model's parameters")
        self.values = values
        self.initialised = False
        self.integrator = None
        self.time = float(state["time"])
        if state["initialised"]:
            self.initialise()  # rebuilds model and integrator from the restored parameters
            self.integrator.set_state(state["integrator"])
            self.time = float(state["time"])
        self.initial_energy = state["initial_energy"]
        self.outputs = LazyOutputs(None, None, None, {}, values=state["outputs"])

    def _check_bounded(self, y: list[float], outputs: Mapping[str, float], t_end: float) -> None:
        """Raise :class:`SolverError` if the motion has blown up numerically.

        The model has no inputs, so its energy can never rise above the start energy. An energy
        beyond ``ENERGY_BLOWUP_FACTOR`` times the start energy plus the energy scale
        ``M g (l1 + l2)`` (M the pendulum's mass, bobs and rods), or a non-finite state, can only come from an unstable
        integration (e.g. explicit Euler with too large a step); it is reported instead of
        returning meaningless numbers.
        """
        energy = outputs["E_total"]
        p = self.model.config.pendulum
        e0 = self.initial_energy or 0.0
        limit = ENERGY_BLOWUP_FACTOR * (abs(e0) + link_coefficients(p).mass * p.g * (p.l1 + p.l2))
        if not all(math.isfinite(v) for v in y) or not abs(energy) <= limit:
            raise SolverError(
                f"numerical instability at t = {t_end:.6g} s: E_total = {energy:.6g} J, started at "
                f"{e0:.6g} J (solver {self.values['solver']}; reduce fixed_step or "
                "use an adaptive solver)"
            )

    def _outputs_at(self, y: list[float]) -> LazyOutputs:
        it = self.integrator
        stats = {
            "solver_steps": float(it.n_steps) if it is not None else 0.0,
            "solver_rhs_evaluations": float(it.nfev) if it is not None else 0.0,
        }
        return LazyOutputs(self.model, list(y), self.initial_energy, stats)

    def _update_outputs(self, y: list[float]) -> None:
        self.outputs = self._outputs_at(y)


__all__ = [
    "CoSimulationError",
    "DoublePendulumCoSimulation",
    "PARAMETER_GROUPS",
    "ParameterError",
    "SolverError",
    "default_parameter_values",
]
