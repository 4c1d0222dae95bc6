"""The app's inputs: each field's unit, description and default from the parameter dataclasses
(:mod:`double_pendulum.model.parameters`, :mod:`double_pendulum.component.settings`), a range the app offers, and
the check of a whole form into FMU start values or messages per field.

A value is refused when it is not a number, when the component itself refuses it
(:func:`~double_pendulum.model.parameters.check_value`, the rule of the parameter's field, in the FMU's words), or
when it lies outside the field's :class:`Field` range (the app's ranges: what a lab pendulum sensibly has; the FMU
accepts more): the message says which.
Only the fields that apply are checked and used (:func:`applying`): the masses and lengths with one's own
pendulum, a loss's coefficients with its switch on, the suspension's with it on, none of them against the
measured track (:data:`MODES`), which runs the fitted start of ``measured_vs_sim``; the page disables the others.
No Dash here: the callbacks (:mod:`.callbacks`) pass the form's values in and show the messages beside the fields.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from ..component.settings import SolverSettings
from ..model.parameters import (
    MAX_START_ANGLE,
    SEED_RIGID_LINKS,
    AirDragParameters,
    BearingParameters,
    InitialState,
    ParameterError,
    PendulumParameters,
    SuspensionParameters,
    check_value,
)
from ..solvers.registry import METHODS

OUTPUT_INTERVAL_S = 0.01
"""The runs' output interval [s] (also the communication step): 100 rows a second, as ``double-pendulum simulate``."""
_FIELDS = {f.name: f for cls in (PendulumParameters, InitialState, AirDragParameters, BearingParameters,
                                 SuspensionParameters, SolverSettings) for f in fields(cls)}
_RUN = {"stop_time": {"unit": "s", "description": "how long the run lasts (fmpy's stop_time)", "default": 20.0}}
"""The form's one field that is no FMU variable."""


def _meta(name: str) -> dict[str, Any]:
    if name in _RUN:
        return _RUN[name]
    return {**_FIELDS[name].metadata, "default": _FIELDS[name].default}


@dataclass(frozen=True)
class Field:
    """A number field of the form: the FMU variable ``name`` (its unit, description and default from its parameter
    dataclass), the range offered [``low``, ``high``] in that unit, and a slider-free ``step``."""

    name: str
    low: float
    high: float
    step: float | str = "any"

    @property
    def unit(self) -> str:
        unit = _meta(self.name)["unit"]
        return "" if unit == "1" else unit

    @property
    def description(self) -> str:
        return _meta(self.name)["description"]

    @property
    def default(self) -> float:
        return _meta(self.name)["default"]

    @property
    def label(self) -> str:
        unit = f" [{self.unit}]" if self.unit else ""
        return f"{self.name}{unit}"

    def range_text(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        return f"{self.low:g} to {self.high:g}{unit}"


STOP_TIME = Field("stop_time", 0.1, 120.0)
"""The run's length [s] (not an FMU variable: fmpy's stop_time)."""
# the start angles: the one rule of the FMU and the CLI (model.parameters.check_start_angle), no narrower range
START = (Field("phi1_0", -MAX_START_ANGLE, MAX_START_ANGLE), Field("phi2_0", -MAX_START_ANGLE, MAX_START_ANGLE),
         Field("omega1_0", -30.0, 30.0), Field("omega2_0", -30.0, 30.0))
OWN_PENDULUM = (Field("m1", 0.01, 10.0), Field("m2", 0.01, 10.0), Field("l1", 0.02, 2.0), Field("l2", 0.02, 2.0))
LOSSES: dict[str, tuple[Field, ...]] = {
    "air_drag": (Field("cw", 0.0, 5.0), Field("A1", 0.0, 0.05), Field("A2", 0.0, 0.05)),
    "bearing_friction": (Field("c_R1", 0.0, 0.05), Field("c_R2", 0.0, 0.05)),
    "bearing_drag": (Field("tau_b1", 0.0, 0.05), Field("tau_b2", 0.0, 0.05)),
}
"""Each loss mechanism's switch (a Boolean FMU parameter) and the coefficients the form offers with it."""
SUSPENSION = (Field("M_s", 0.1, 100.0), Field("k_x", 0.0, 1e6), Field("k_y", 0.0, 1e6), Field("c_x", 0.0, 1e4),
              Field("c_y", 0.0, 1e4))
TOLERANCE = Field("rtol", 1e-12, 1e-3)
SOLVERS = tuple(METHODS)
PENDULUMS = {
    "seed": "the seed's pendulum (bobs and acrylic rods)",
    "frictionless": "frictionless point masses (no loss, whatever is switched on)",
    "own": "one's own masses and lengths (point masses)",
}
"""The pendulums offered: the seed's (the defaults with its rods, :data:`SEED_RIGID_LINKS`), the frictionless
point-mass pendulum, or the masses and lengths typed in."""
MODES = {
    "case": "your case",
    "twins": "your case and a start a hair apart",
    "measured": "against the measured track",
}
"""What a run runs: the form's case, the case and its twin (``phi1_0`` nudged), or ``measured_vs_sim``'s main
prediction of the camera's track, whose start, pendulum and losses are fitted, not the form's."""
NUMBER_FIELDS: tuple[Field, ...] = (STOP_TIME, *START, *OWN_PENDULUM, *(f for fs in LOSSES.values() for f in fs),
                                    *SUSPENSION, TOLERANCE)


def default_values() -> dict[str, Any]:
    """The form as it opens: every number field at its default (stop time 20 s), the seed's pendulum, no loss."""
    values: dict[str, Any] = {f.name: f.default for f in NUMBER_FIELDS}
    return {**values, "mode": "case", "pendulum": "seed", "switches": [], "suspension": False,
            "solver": SolverSettings.solver}


def applying(form: Mapping[str, Any]) -> tuple[list[Field], list[str]]:
    """The number fields that apply to ``form`` (its ``mode``, ``pendulum``, ``switches`` and ``suspension``) and
    the loss switches that do: nothing against the measured track, no loss with the frictionless pendulum."""
    if form.get("mode") == "measured":
        return [], []
    pendulum = form.get("pendulum", "seed")
    switches = [s for s in form.get("switches") or () if s in LOSSES] if pendulum != "frictionless" else []
    needed = [STOP_TIME, *START, TOLERANCE]
    if pendulum == "own":
        needed += OWN_PENDULUM
    for name in switches:
        needed += LOSSES[name]
    if form.get("suspension"):
        needed += SUSPENSION
    return needed, switches


def notes(form: Mapping[str, Any]) -> tuple[str, str]:
    """Why the pendulum's fields (m1..l2) and the losses' are disabled in ``form``, each "" when nothing needs
    saying (against the measured track the page says why the whole form does not apply)."""
    if form.get("mode") == "measured":
        return "", ""
    names = ", ".join(f.name for f in OWN_PENDULUM)
    pendulum = form.get("pendulum", "seed")
    if pendulum == "seed":
        return (f"{names} do not apply: the seed's pendulum has its own (the FMU's defaults, with its acrylic rods); "
                f"choose \"{PENDULUMS['own']}\" to set them."), "a loss's coefficients apply when it is switched on"
    if pendulum == "frictionless":
        return (f"{names} do not apply: the frictionless pendulum has the FMU's default masses and lengths, no rods.",
                "no loss applies to the frictionless pendulum")
    return "", "a loss's coefficients apply when it is switched on"


@dataclass(frozen=True)
class Checked:
    """A checked form: the FMU ``start_values`` and ``stop_time`` [s] of the run, or ``errors`` (field name ->
    message) when a value is refused."""

    start_values: dict[str, Any]
    stop_time: float
    errors: dict[str, str]


def _number(field: Field, raw: Any) -> tuple[float | None, str | None]:
    """The field's value, or why it is refused."""
    if raw is None or (isinstance(raw, str) and not raw.strip()):
        return None, f"{field.name}: a number is needed ({field.range_text()})"
    try:
        value = float(raw)
    except (TypeError, ValueError):
        return None, f"{field.name} = {raw!r} is not a number ({field.range_text()})"
    if field.name in _FIELDS:  # the FMU's own rule first: its words for what it would refuse
        meta = _FIELDS[field.name].metadata
        try:
            check_value(field.name, value, meta["unit"], meta["rule"])
        except ParameterError as error:
            return None, str(error)
    if not field.low <= value <= field.high:
        return None, f"{field.name} = {value:g} is out of range: {field.range_text()}"
    return value, None


def check_form(form: Mapping[str, Any]) -> Checked:
    """The FMU start values of ``form`` (field name -> raw value; ``mode``, ``pendulum``, ``switches``: the
    switched-on loss mechanisms, ``suspension``, ``solver``), only those that differ from the FMU's defaults' meaning;
    the fields that do not apply (:func:`applying`) are neither checked nor used. Against the measured track no
    field applies: no start values, no errors."""
    errors: dict[str, str] = {}
    pendulum = form.get("pendulum", "seed")
    needed, switches = applying(form)
    if form.get("mode") == "measured":
        return Checked({}, 0.0, {})
    values: dict[str, float] = {}
    for field in needed:
        value, message = _number(field, form.get(field.name))
        if message:
            errors[field.name] = message
        else:
            values[field.name] = value
    solver = form.get("solver") or SolverSettings.solver
    if solver not in SOLVERS:
        errors["solver"] = f"solver = {solver!r}: must be one of {', '.join(SOLVERS)}"
    if errors:
        return Checked({}, 0.0, errors)
    start: dict[str, Any] = {f.name: values[f.name] for f in START}
    if pendulum == "seed":
        start.update(SEED_RIGID_LINKS)
    elif pendulum == "own":
        start.update({f.name: values[f.name] for f in OWN_PENDULUM})
    for name in switches:
        start[name] = True
        start.update({f.name: values[f.name] for f in LOSSES[name]})
    if form.get("suspension"):
        start["suspension"] = True
        start.update({f.name: values[f.name] for f in SUSPENSION})
    start.update(solver=solver, rtol=values["rtol"])
    return Checked(start, values["stop_time"], {})
