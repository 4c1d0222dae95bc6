"""The FMU's variables, derived from the parameter dataclasses and the output table.

Both the pythonfmu adapter (which registers them) and the build step (which adds FMI unit
definitions to the modelDescription) read this one list, so names, units, descriptions and
start values cannot drift apart.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any, NamedTuple

from ..model.outputs import OUTPUTS
from .cosimulation import PARAMETER_GROUPS

MODEL_IDENTIFIER = "DoublePendulum"
MODEL_DESCRIPTION = (
    "Planar double pendulum (bobs on rods that may carry mass; fixed pivot or damped suspension; air "
    "drag and bearing friction), equations of motion from the Lagrangian; FMI 2.0 co-simulation with "
    "an integrator that persists across doStep."
)
DEFAULT_EXPERIMENT = {"start_time": 0.0, "stop_time": 10.0, "step_size": 0.01}


class FmuVariable(NamedTuple):
    """One FMI scalar variable."""

    name: str
    fmi_type: str  # "Real", "Boolean" or "String"
    causality: str  # "parameter" or "output"
    unit: str  # FMI unit string, "" for none
    description: str
    start: Any  # start value for parameters, None for outputs


def _fmi_type(rule: str) -> str:
    return {"str": "String", "bool": "Boolean"}.get(rule, "Real")


def described(description: str, unit: str) -> str:
    """Append the unit to a description: pythonfmu has no unit attribute of its own."""
    return f"{description} [{unit}]" if unit else description


def fmu_variables() -> list[FmuVariable]:
    """Return all FMU variables: parameters (in dataclass order), then outputs."""
    variables = [
        FmuVariable(
            f.name,
            _fmi_type(f.metadata["rule"]),
            "parameter",
            f.metadata["unit"],
            described(f.metadata["description"], f.metadata["unit"]),
            f.default,
        )
        for group in PARAMETER_GROUPS
        for f in fields(group)
    ]
    variables += [
        FmuVariable(q.name, "Real", "output", q.unit, described(q.description, q.unit), None) for q in OUTPUTS
    ]
    return variables
