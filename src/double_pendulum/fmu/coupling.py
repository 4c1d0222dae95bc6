"""A small Jacobi master: DoublePendulum on Suspension, coupled across the FMU boundary.

Connections (no glue: the two FMUs' variables are meant for each other)::

    DoublePendulum.F_pivot_x, F_pivot_y            -> Suspension.F_x, F_y
    Suspension.x, y, vx, vy, ax, ay                -> DoublePendulum.pivot_x, ..., pivot_ay

(the pendulum with its own ``suspension`` off, the suspension's ``F_static_y`` the pendulum's
weight ``-(m1 + m2) g``). At each macro step both slaves read the other's outputs at the step's
start and then step side by side (Jacobi). ``F_pivot`` depends directly on ``pivot_a*`` and the
suspension's acceleration directly on the force: an algebraic loop, broken here by using the
outputs of the previous communication point (an explicit coupling, first order in the macro
step). The slaves are anything with ``set_input(name, value)``, ``get(name)`` and
``do_step(t, h)``: the in-process components, or FMUs through :class:`FmuSlave`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np

FORCE_CONNECTIONS: tuple[tuple[str, str], ...] = (("F_pivot_x", "F_x"), ("F_pivot_y", "F_y"))
MOTION_CONNECTIONS: tuple[tuple[str, str], ...] = (
    ("x", "pivot_x"), ("y", "pivot_y"), ("vx", "pivot_vx"), ("vy", "pivot_vy"), ("ax", "pivot_ax"), ("ay", "pivot_ay"),
)  # fmt: skip


class Slave(Protocol):
    """What the master needs of a co-simulation slave."""

    def set_input(self, name: str, value: float) -> None: ...

    def get(self, name: str) -> Any: ...

    def do_step(self, current_time: float, step_size: float) -> None: ...


def exchange(pendulum: Slave, suspension: Slave) -> None:
    """Pass each slave the other's current outputs (both read before either is written)."""
    forces = [(target, pendulum.get(source)) for source, target in FORCE_CONNECTIONS]
    motion = [(target, suspension.get(source)) for source, target in MOTION_CONNECTIONS]
    for target, value in forces:
        suspension.set_input(target, value)
    for target, value in motion:
        pendulum.set_input(target, value)


def run_jacobi(
    pendulum: Slave,
    suspension: Slave,
    *,
    stop_time: float,
    macro_step: float,
    start_time: float = 0.0,
    pendulum_outputs: Sequence[str] = ("phi1", "phi2", "E_pendulum", "W_input"),
    suspension_outputs: Sequence[str] = ("x", "y", "E_suspension", "W_suspension", "W_in"),
) -> np.ndarray:
    """Step two initialised slaves with a fixed macro step [s]; return the rows at each point.

    Columns: ``time``, the pendulum outputs, then the suspension outputs (prefixed ``s_`` when a
    name is on both sides).
    """
    names = list(pendulum_outputs) + [f"s_{n}" if n in pendulum_outputs else n for n in suspension_outputs]

    def row(t: float) -> tuple[float, ...]:
        return (t, *(pendulum.get(n) for n in pendulum_outputs), *(suspension.get(n) for n in suspension_outputs))

    rows = [row(start_time)]
    n_steps = int(round((stop_time - start_time) / macro_step))
    for n in range(n_steps):
        t = start_time + n * macro_step
        exchange(pendulum, suspension)
        pendulum.do_step(t, macro_step)
        suspension.do_step(t, macro_step)
        rows.append(row(start_time + (n + 1) * macro_step))
    return np.array(rows, dtype=[("time", np.float64)] + [(n, np.float64) for n in names])


class FmuSlave:
    """An extracted FMU as a :class:`Slave` (fmpy's ``FMU2Slave``), initialised with ``start_values``."""

    def __init__(
        self,
        unzipdir: str,
        model_description: Any,
        start_values: Mapping[str, Any] | None = None,
        instance_name: str | None = None,
        start_time: float = 0.0,
    ) -> None:
        from fmpy.fmi2 import FMU2Slave

        md = model_description
        self.refs = {v.name: v for v in md.modelVariables}
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=instance_name or md.coSimulation.modelIdentifier,
        )
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        for name, value in (start_values or {}).items():
            self._set(name, value)
        self.fmu.exitInitializationMode()

    def _set(self, name: str, value: Any) -> None:
        var = self.refs[name]
        setter = {"Real": self.fmu.setReal, "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}[var.type]
        setter([var.valueReference], [value])

    def set_input(self, name: str, value: float) -> None:
        self.fmu.setReal([self.refs[name].valueReference], [value])

    def get(self, name: str) -> float:
        return self.fmu.getReal([self.refs[name].valueReference])[0]

    def do_step(self, current_time: float, step_size: float) -> None:
        self.fmu.doStep(currentCommunicationPoint=current_time, communicationStepSize=step_size)

    def close(self) -> None:
        """Terminate and free the instance."""
        self.fmu.terminate()
        self.fmu.freeInstance()
