"""The pendulum on its suspension as an SSP system: ``PendulumOnSuspension.ssp`` for libcosim.

An SSP file (System Structure and Parameterization, the FMI family's standard for systems of
FMUs) is a zip holding ``SystemStructure.ssd`` and the FMUs it references, here
``resources/DoublePendulum.fmu`` and ``resources/Suspension.fmu``. The SSD lists the two
components with their connectors, the eight connections of
:mod:`double_pendulum.fmu.masters.coupling` and, per component, an inline parameter set
(``ssd:ParameterBindings/ssd:ParameterValues/ssv:ParameterSet``) with the values of
:func:`~double_pendulum.fmu.masters.coupling.split_values`: the pendulum's start values with its own
suspension off, the suspension's ``M_s, k, c`` and ``F_static_y = -(m1 + m2) g``.

libcosim (libcosimpy ``CosimExecution.from_ssp_file``) reads exactly this subset of SSP 1.0:
components with ``source``, ``ssd:Connectors`` typed ``ssc:Real``, inline or ``.ssv`` parameter
sets (the first set is applied), plain connections (optionally ``ssc:LinearTransformation``), and
``ssd:DefaultExperiment`` with the OSP annotation ``osp:FixedStepAlgorithm baseStepSize`` [s],
the macro step (a step size passed to ``from_ssp_file`` replaces it). It unzips a ``.ssp`` to a
temporary folder itself. No units conversion, no signal dictionaries.
"""

from __future__ import annotations

import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from ..masters.coupling import FORCE_CONNECTIONS, MOTION_CONNECTIONS, split_values

SYSTEM_NAME = "PendulumOnSuspension"
PENDULUM, SUSPENSION = "DoublePendulum", "Suspension"
NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
}
DEFAULT_MACRO_STEP = 1e-3


def _q(tag: str) -> str:
    prefix, name = tag.split(":")
    return f"{{{NS[prefix]}}}{name}"


def _literal(value: Any) -> tuple[str, str]:
    """The SSV element type and XML literal of a parameter value."""
    if isinstance(value, bool):
        return "Boolean", "true" if value else "false"
    if isinstance(value, str):
        return "String", value
    if isinstance(value, int):
        return "Integer", str(value)
    return "Real", repr(float(value))


def _connectors(component: ET.Element, outputs: list[str], inputs: list[str], units: Mapping[str, str]) -> None:
    connectors = ET.SubElement(component, _q("ssd:Connectors"))
    for kind, names in (("output", outputs), ("input", inputs)):
        for name in names:
            connector = ET.SubElement(connectors, _q("ssd:Connector"), name=name, kind=kind)
            ET.SubElement(connector, _q("ssc:Real"), {"unit": units[name]} if units.get(name) else {})


def _parameter_set(component: ET.Element, values: Mapping[str, Any]) -> None:
    bindings = ET.SubElement(component, _q("ssd:ParameterBindings"))
    binding = ET.SubElement(bindings, _q("ssd:ParameterBinding"))
    holder = ET.SubElement(binding, _q("ssd:ParameterValues"))
    pset = ET.SubElement(holder, _q("ssv:ParameterSet"), version="1.0", name="system")
    parameters = ET.SubElement(pset, _q("ssv:Parameters"))
    for name, value in values.items():
        kind, text = _literal(value)
        parameter = ET.SubElement(parameters, _q("ssv:Parameter"), name=name)
        ET.SubElement(parameter, _q(f"ssv:{kind}"), value=text)


def system_structure(
    values: Mapping[str, Any], macro_step: float = DEFAULT_MACRO_STEP, stop_time: float = 10.0,
    units: Mapping[str, str] | None = None,
) -> bytes:
    """The ``SystemStructure.ssd`` of the coupled system for the monolith's start ``values``."""
    for prefix, uri in NS.items():
        ET.register_namespace(prefix, uri)
    units = units or {}
    pendulum_values, suspension_values = split_values(values)
    root = ET.Element(_q("ssd:SystemStructureDescription"), name=SYSTEM_NAME, version="1.0")
    system = ET.SubElement(root, _q("ssd:System"), name=SYSTEM_NAME,
                           description="DoublePendulum hanging from the Suspension mass, coupled by force and motion")
    elements = ET.SubElement(system, _q("ssd:Elements"))
    sides = (
        (PENDULUM, [s for s, _ in FORCE_CONNECTIONS], [t for _, t in MOTION_CONNECTIONS], pendulum_values),
        (SUSPENSION, [s for s, _ in MOTION_CONNECTIONS], [t for _, t in FORCE_CONNECTIONS], suspension_values),
    )
    for name, outputs, inputs, start in sides:
        component = ET.SubElement(elements, _q("ssd:Component"), name=name, source=f"resources/{name}.fmu",
                                  type="application/x-fmu-sharedlibrary")
        _connectors(component, outputs, inputs, units)
        _parameter_set(component, start)
    connections = ET.SubElement(system, _q("ssd:Connections"))
    for start_element, end_element, pairs in ((PENDULUM, SUSPENSION, FORCE_CONNECTIONS),
                                              (SUSPENSION, PENDULUM, MOTION_CONNECTIONS)):
        for source, target in pairs:
            ET.SubElement(connections, _q("ssd:Connection"), startElement=start_element, startConnector=source,
                          endElement=end_element, endConnector=target)
    experiment = ET.SubElement(root, _q("ssd:DefaultExperiment"), startTime="0.0", stopTime=repr(float(stop_time)))
    annotations = ET.SubElement(experiment, _q("ssd:Annotations"))
    annotation = ET.SubElement(annotations, _q("ssc:Annotation"), type="com.opensimulationplatform")
    algorithm = ET.SubElement(annotation, _q("osp:Algorithm"))
    ET.SubElement(algorithm, _q("osp:FixedStepAlgorithm"), baseStepSize=repr(float(macro_step)))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _units(fmu: Path) -> dict[str, str]:
    from fmpy import read_model_description

    return {v.name: v.unit for v in read_model_description(str(fmu)).modelVariables if v.unit}


def write_ssp(
    dest: str | Path, pendulum_fmu: str | Path, suspension_fmu: str | Path, values: Mapping[str, Any] | None = None,
    *, macro_step: float = DEFAULT_MACRO_STEP, stop_time: float = 10.0, reference: bool = False,
) -> Path:
    """Write the ``.ssp`` at ``dest`` holding both FMUs; ``values``: the monolith's start values (defaults if None).

    ``reference=True`` (the build's SSP) adds the reference result of its default experiment,
    ``extra/org.fmi-standard.fmi-ls-ref/`` as in the FMUs (:func:`~double_pendulum.fmu.carries.reference_result.
    ssp_reference_files`: the states as libcosim steps them; about 1.5 s of CPU for the 10 s).
    """
    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    units = {**_units(Path(pendulum_fmu)), **_units(Path(suspension_fmu))}
    ssd = system_structure(values or {}, macro_step, stop_time, units)
    tmp = dest.with_suffix(".ssp.tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        archive.write(pendulum_fmu, f"resources/{PENDULUM}.fmu")
        archive.write(suspension_fmu, f"resources/{SUSPENSION}.fmu")
        if reference:
            from ..carries.reference_result import ssp_reference_files

            for name, data in ssp_reference_files(values or {}, stop_time, macro_step).items():
                archive.writestr(name, data)
    tmp.replace(dest)
    return dest
