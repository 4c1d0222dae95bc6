"""The FMUs' variables, derived from the parameter dataclasses and the input and output tables.

Both the pythonfmu adapters (which register them) and the build step (which adds FMI unit
definitions and output dependencies to the modelDescription) read these lists, so names, units,
descriptions and start values cannot drift apart. :data:`INTERFACES` holds one
:class:`FmuInterface` per model identifier: ``DoublePendulum`` and ``Suspension``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import Field, fields
from typing import Any, NamedTuple

from ..model import suspension
from ..model.inputs import INPUTS
from ..model.outputs import INPUT_DEPENDENCIES, OUTPUTS, PORT_NAMES
from ..model.quantities import Quantity
from .cosimulation import PARAMETER_GROUPS
from .suspension import INPUT_START, PARAMETER_FIELDS

MODEL_IDENTIFIER = "DoublePendulum"
MODEL_PHYSICS = (
    "Planar double pendulum (bobs on rods that may carry mass; fixed, moving or suspended pivot; air "
    "drag and bearing friction), equations of motion from the Lagrangian; inputs: pivot motion and "
    "joint torques"
)
MODEL_DESCRIPTION = MODEL_PHYSICS + "; FMI 2.0 co-simulation with an integrator that persists across doStep."
MODEL_DESCRIPTION_FMI3 = (
    MODEL_PHYSICS + "; FMI 3.0 Model Exchange (the host integrates the continuous states) and Co-Simulation "
    "(an integrator that persists across doStep)."
)
DEFAULT_EXPERIMENT = {"start_time": 0.0, "stop_time": 10.0, "step_size": 0.01}


class FmuVariable(NamedTuple):
    """One FMI scalar variable."""

    name: str
    fmi_type: str  # "Real", "Integer", "Boolean" or "String"
    causality: str  # "parameter", "input", "output" (a port) or "local" (a diagnostic, read by name)
    unit: str  # FMI unit string, "" for none
    description: str
    start: Any  # start value for parameters and inputs, None for outputs
    rule: str = ""  # a parameter's validity rule (double_pendulum.model.parameters.spec): "positive", ...


def _fmi_type(rule: str) -> str:
    return {"str": "String", "bool": "Boolean", "count": "Integer"}.get(rule, "Real")


def described(description: str, unit: str) -> str:
    """Append the unit to a description: pythonfmu has no unit attribute of its own."""
    return f"{description} [{unit}]" if unit else description


def _variables(
    parameters: Iterable[Field],
    inputs: Iterable[Quantity],
    input_start: Mapping[str, float],
    outputs: Iterable[Quantity],
    ports: Iterable[str],
) -> list[FmuVariable]:
    """Parameters (dataclass fields, in order), inputs, then the output quantities as FMU variables.

    The output quantities named in ``ports`` are the FMU's outputs, the others its local variables.
    """
    ports = frozenset(ports)
    variables = [
        FmuVariable(
            f.name,
            _fmi_type(f.metadata["rule"]),
            "parameter",
            f.metadata["unit"],
            described(f.metadata["description"], f.metadata["unit"]),
            f.default,
            f.metadata["rule"],
        )
        for f in parameters
    ]
    variables += [
        FmuVariable(q.name, "Real", "input", q.unit, described(q.description, q.unit), input_start.get(q.name, 0.0),
                    "finite")
        for q in inputs
    ]
    variables += [
        FmuVariable(q.name, "Real", "output" if q.name in ports else "local", q.unit,
                    described(q.description, q.unit), None)
        for q in outputs
    ]
    return variables


def fmu_variables() -> list[FmuVariable]:
    """Return all DoublePendulum variables: parameters (in dataclass order), inputs, then outputs and locals."""
    return _variables((f for group in PARAMETER_GROUPS for f in fields(group)), INPUTS, {}, OUTPUTS, PORT_NAMES)


def suspension_fmu_variables() -> list[FmuVariable]:
    """Return all Suspension variables (:mod:`double_pendulum.model.suspension`)."""
    return _variables(PARAMETER_FIELDS, suspension.INPUTS, INPUT_START, suspension.OUTPUTS, suspension.PORT_NAMES)


class FmuInterface(NamedTuple):
    """What the build and an adapter need to know about one FMU."""

    model_identifier: str
    description: str
    variables: Callable[[], list[FmuVariable]]
    output_dependencies: Mapping[str, tuple[str, ...]]  # output -> inputs it depends on directly
    default_experiment: Mapping[str, float]


INTERFACES: dict[str, FmuInterface] = {
    MODEL_IDENTIFIER: FmuInterface(
        MODEL_IDENTIFIER, MODEL_DESCRIPTION, fmu_variables, INPUT_DEPENDENCIES, DEFAULT_EXPERIMENT
    ),
    "Suspension": FmuInterface(
        "Suspension",
        "Suspension mass on springs and dampers to the ground, loaded by a force (inputs F_x, F_y); "
        "couples to DoublePendulum (F_pivot -> F, motion -> pivot_*) to give the pendulum on a suspension.",
        suspension_fmu_variables,
        suspension.INPUT_DEPENDENCIES,
        {"start_time": 0.0, "stop_time": 1.0, "step_size": 1e-3},
    ),
}
