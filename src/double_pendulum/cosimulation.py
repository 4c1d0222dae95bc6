"""The co-simulation component: parameters by name, initialisation, doStep, outputs.

This is what the FMU runs (``fmu_src/DoublePendulum.py`` only maps FMI calls onto it) and what
:func:`double_pendulum.simulate.simulate` runs in-process, so both give identical numbers.

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
from dataclasses import fields
from typing import Any

from .dynamics import fixed_pivot_vector_field
from .outputs import OUTPUT_NAMES, output_values
from .parameters import (
    InitialState,
    ParameterError,
    PendulumParameters,
    SolverSettings,
    check_value,
)
from .solvers import Integrator, SolverError, make_integrator

PARAMETER_GROUPS: tuple[type, ...] = (PendulumParameters, InitialState, SolverSettings)
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


class DoublePendulumCoSimulation:
    """One instance of the double pendulum as a co-simulation slave."""

    RULES = _parameter_rules()

    def __init__(self, start_time: float = 0.0) -> None:
        self.values: dict[str, Any] = default_parameter_values()
        self.time = float(start_time)
        self.initialised = False
        self.integrator: Integrator | None = None
        self.params = PendulumParameters()
        self.outputs: dict[str, float] = {}
        self.initial_energy = 0.0
        self._update_outputs(InitialState().as_list())

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
        self.params = self._group(PendulumParameters)
        initial = self._group(InitialState)
        settings = self._group(SolverSettings)
        f = fixed_pivot_vector_field(self.params)
        y0 = initial.as_list()
        self.integrator = make_integrator(
            settings.solver,
            f,
            self.time,
            y0,
            rtol=settings.rtol,
            atol=settings.atol,
            fixed_step=settings.fixed_step,
        )
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
        y = self.integrator.advance_to(t_end)
        outputs = dict(zip(OUTPUT_NAMES, output_values(y, self.params)))
        self._check_bounded(outputs, t_end)
        self.time = t_end
        self.outputs = outputs

    def _check_bounded(self, outputs: dict[str, float], t_end: float) -> None:
        """Raise :class:`SolverError` if the motion has blown up numerically.

        The model has no inputs, so its energy can never rise above the start energy. An energy
        beyond ``ENERGY_BLOWUP_FACTOR`` times the start energy plus the energy scale
        ``(m1 + m2) g (l1 + l2)`` can only come from an unstable integration (e.g. explicit Euler
        with too large a step); it is reported instead of returning meaningless numbers.
        """
        energy = outputs["E_total"]
        p = self.params
        limit = ENERGY_BLOWUP_FACTOR * (abs(self.initial_energy) + (p.m1 + p.m2) * p.g * (p.l1 + p.l2))
        if not all(math.isfinite(v) for v in outputs.values()) or abs(energy) > limit:
            raise SolverError(
                f"numerical instability at t = {t_end:.6g} s: E_total = {energy:.6g} J, started at "
                f"{self.initial_energy:.6g} J (solver {self.values['solver']}; reduce fixed_step or "
                "use an adaptive solver)"
            )

    def _update_outputs(self, y: list[float]) -> None:
        self.outputs = dict(zip(OUTPUT_NAMES, output_values(y, self.params)))


__all__ = [
    "CoSimulationError",
    "DoublePendulumCoSimulation",
    "PARAMETER_GROUPS",
    "ParameterError",
    "SolverError",
    "default_parameter_values",
]
