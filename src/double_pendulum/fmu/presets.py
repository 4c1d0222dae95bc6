"""Start values baked into a build: an FMU whose defaults are a chosen scene.

Some hosts cannot set start values at all: the FMI Compliance Checker sets every variable of its input
file before every step, which the FMU refuses for fixed parameters after initialisation, and fmpy's
cross-check runner sets none. An FMU built with ``start_values`` (``build_fmu(...,
start_values={"phi1_0": 2.0})``) runs that scene with no start value set. The build

* checks each value as the component would (a parameter of the FMU, its rule: ``ParameterError``);
* writes them as the ``start`` attributes of the modelDescription (FMI 2 and FMI 3 layouts) and adds
  them to its ``description``;
* writes ``resources/start_values.json`` (:data:`PRESET_FILE`), which the FMU's Python side applies
  to every new component, at instantiation and at reset (``fmu_src/slave_common.py``), so the
  modelDescription and the instance agree.

An FMU built without start values is the plain one, byte for byte in its modelDescription.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any
from xml.etree import ElementTree as ET

from ..component.cosimulation import DoublePendulumCoSimulation
from ..component.suspension import SuspensionCoSimulation
from ..component.variables import INTERFACES

PRESET_FILE = "resources/start_values.json"
"""Where a build keeps its start values in the FMU (read by ``fmu_src/slave_common.py``)."""
COMPONENTS = {"DoublePendulum": DoublePendulumCoSimulation, "Suspension": SuspensionCoSimulation}


def checked_start_values(model_identifier: str, values: Mapping[str, Any] | None) -> dict[str, Any]:
    """``values`` as the FMU will hold them; raises ``ValueError`` for a name that is not a parameter of the
    FMU and ``ParameterError`` (a ``ValueError``) for a value the component refuses."""
    values = dict(values or {})
    parameters = {v.name for v in INTERFACES[model_identifier].variables() if v.causality == "parameter"}
    unknown = sorted(set(values) - parameters)
    if unknown:
        raise ValueError(f"{model_identifier} has no parameter {', '.join(unknown)}: start values can be baked "
                         "in for parameters only")
    component = COMPONENTS[model_identifier]()
    for name, value in values.items():
        component.set(name, value)
    return values


def literal(value: Any) -> str:
    """A start value as the modelDescription writes it (``true``/``false``, ``repr`` of a float)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    if isinstance(value, int):  # an Integer
        return str(value)
    return repr(float(value))


def describe(values: Mapping[str, Any]) -> str:
    """``name = value, ...`` of the baked start values, for descriptions and documentation."""
    return ", ".join(f"{name} = {literal(value)}" for name, value in values.items())


def apply_start_values(xml_text: bytes, values: Mapping[str, Any]) -> bytes:
    """The modelDescription ``xml_text`` (FMI 2 or FMI 3) with ``values`` as start values; unchanged if empty."""
    if not values:
        return xml_text
    root = ET.fromstring(xml_text)
    fmi3 = root.get("fmiVersion", "").startswith("3")
    found = set()
    for variable in root.find("ModelVariables"):
        name = variable.get("name")
        if name not in values:
            continue
        found.add(name)
        text = literal(values[name])
        if not fmi3:  # <ScalarVariable><Real start=.../></ScalarVariable>
            next(iter(variable)).set("start", text)
        elif variable.tag == "String":  # <String><Start value=.../></String>
            variable.find("Start").set("value", text)
        else:
            variable.set("start", text)
    missing = sorted(set(values) - found)
    if missing:
        raise ValueError(f"the modelDescription has no variable {', '.join(missing)}")
    root.set("description", f"{root.get('description', '')} Start values of this build: {describe(values)}.")
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def preset_file(values: Mapping[str, Any]) -> bytes:
    """The content of :data:`PRESET_FILE`: the values as JSON, in the order given."""
    return (json.dumps(dict(values), indent=2) + "\n").encode()
