"""Start values from the command line (``--set NAME=VALUE``), checked against an FMU's modelDescription.

:func:`parse_start_values` turns ``NAME=VALUE`` texts into the ``start_values`` mapping
:func:`fmpy.simulate_fmu` takes, each value of its variable's type (FMI 2 or FMI 3), and refuses in one line
what the FMU would refuse or ignore: a name that is no variable (naming the closest parameter), a variable that
is no parameter one may set (an input, an output, a constant or a calculated parameter), a value that is not of
the variable's type, not finite or outside its ``min`` .. ``max``, and a name given twice. What the modelDescription
cannot say (a length must be positive, a solver must be one of seven) the FMU itself checks when it starts, with
its own message.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from difflib import SequenceMatcher
from typing import Any

SETTABLE_VARIABILITY = ("fixed", "tunable")
"""The variabilities of the parameters a master may set before the run (FMI 2 and FMI 3)."""
REAL_TYPES = ("Real", "Float64", "Float32")
INTEGER_TYPES = ("Integer", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64", "Enumeration")
TRUE_WORDS = ("true", "1", "yes", "on")
FALSE_WORDS = ("false", "0", "no", "off")


class StartValueError(ValueError):
    """A ``--set`` the FMU cannot take; its message is the one line that says why."""


_ARTICLE = {"independent": "the", "local": "a"}  # "x2 is a local variable", "phi1 is an output variable"


def parameters(model_description: Any) -> list[Any]:
    """The variables of ``model_description`` (fmpy's) that ``--set`` may set: parameters, fixed or tunable."""
    return [v for v in model_description.modelVariables
            if v.causality == "parameter" and v.variability in SETTABLE_VARIABILITY]  # fmt: skip


def closest_name(name: str, names: Iterable[str]) -> str | None:
    """The name of ``names`` most like ``name`` (letters compared without case), None if there are none."""
    candidates = list(names)
    if not candidates:
        return None
    return max(candidates, key=lambda other: SequenceMatcher(None, name.lower(), other.lower()).ratio())


def _typed(variable: Any, text: str) -> Any:
    """``text`` as a value of ``variable``'s type, or a StartValueError that says what the type takes."""
    kind, name = variable.type, variable.name
    if kind in REAL_TYPES:
        try:
            value = float(text)
        except ValueError:
            raise StartValueError(f"--set {name}={text}: {name} is a real number{_unit(variable)}, "
                                  f"e.g. --set {name}=0.5") from None
        if not math.isfinite(value):
            raise StartValueError(f"--set {name}={text}: {name} must be a finite number{_unit(variable)}")
        return value
    if kind in INTEGER_TYPES:
        try:
            return int(text)
        except ValueError:
            raise StartValueError(f"--set {name}={text}: {name} is a whole number ({kind})") from None
    if kind == "Boolean":
        word = text.strip().lower()
        if word in TRUE_WORDS or word in FALSE_WORDS:
            return word in TRUE_WORDS
        raise StartValueError(f"--set {name}={text}: {name} is a switch: true or false")
    if kind == "String":
        return text
    raise StartValueError(f"--set {name}={text}: {name} is of type {kind}, which --set does not take")


def _unit(variable: Any) -> str:
    unit = getattr(variable, "unit", None) or getattr(getattr(variable, "declaredType", None), "unit", None)
    return f" [{unit}]" if unit else ""


def _check_range(variable: Any, value: Any, text: str) -> None:
    """Refuse ``value`` outside ``variable``'s ``min`` .. ``max`` (where the modelDescription gives them)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return
    low, high = (None if bound in (None, "") else float(bound) for bound in (variable.min, variable.max))
    if low is not None and value < low or high is not None and value > high:
        span = f"{'-inf' if low is None else f'{low:g}'} .. {'inf' if high is None else f'{high:g}'}"
        raise StartValueError(f"--set {variable.name}={text}: outside the range {span}{_unit(variable)} "
                              "the modelDescription gives")


def _refuse_unsettable(variable: Any, text: str) -> None:
    """Refuse a variable that is not a parameter a master may set before the run, saying what it is."""
    name, causality = variable.name, variable.causality
    if causality == "input":
        raise StartValueError(f"--set {name}={text}: {name} is an input, driven by a signal over time, not a "
                              "parameter (an fmpy input signal drives it: examples/drive_inputs.py)")
    if causality in ("output", "local", "independent"):
        raise StartValueError(f"--set {name}={text}: {name} is {_ARTICLE.get(causality, 'an')} "
                              f"{causality} variable, which the FMU computes; --set takes parameters")
    raise StartValueError(f"--set {name}={text}: {name} is a {variable.variability} {causality}, "
                          "which a master cannot set")


def parse_start_values(settings: Sequence[str], model_description: Any) -> dict[str, Any]:
    """The start values ``NAME=VALUE`` of ``settings`` for an FMU of ``model_description`` (fmpy's), in their
    order, each of its variable's type; a StartValueError for the first one the FMU cannot take."""
    variables: Mapping[str, Any] = {v.name: v for v in model_description.modelVariables}
    settable = [v.name for v in parameters(model_description)]
    values: dict[str, Any] = {}
    for setting in settings:
        name, sep, text = setting.partition("=")
        name, text = name.strip(), text.strip()
        if not sep or not name or not text:
            raise StartValueError(f"--set {setting!r}: write NAME=VALUE, e.g. --set phi1_0=2")
        variable = variables.get(name)
        if variable is None:
            closest = closest_name(name, settable)
            hint = f"; the closest parameter is {closest}" if closest else ""
            raise StartValueError(f"--set {setting}: the FMU has no parameter {name}{hint} "
                                  "(double-pendulum variables lists them)")
        if name not in settable:
            _refuse_unsettable(variable, text)
        if name in values:
            raise StartValueError(f"--set {setting}: {name} is set twice")
        value = _typed(variable, text)
        _check_range(variable, value, text)
        values[name] = value
    return values


def value_text(value: Any) -> str:
    """A start value as the command line writes it (``true``/``false`` for a switch)."""
    return str(value).lower() if isinstance(value, bool) else f"{value:g}" if isinstance(value, float) else str(value)
