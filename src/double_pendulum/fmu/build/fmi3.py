"""Build the FMI 3.0 ``DoublePendulum.fmu`` (Model Exchange and Co-Simulation) with pythonfmu3.

The adapter ``fmu_src/DoublePendulumFmi3.py`` maps the FMI 3 calls onto the same component as the
FMI 2 FMU (Co-Simulation) and onto the runtime's vector field (Model Exchange,
``double_pendulum.component.model_exchange``); the runtime is bundled as for FMI 2
(:mod:`double_pendulum.fmu.build.staging`), with pythonfmu3's Python part imported under a private name.
The build then

* adds ``UnitDefinitions`` for the units the adapter gives its Float64 variables;
* writes ``ModelStructure`` anew: every output (its direct dependencies on the inputs and, for
  Model Exchange, on the continuous states), every state derivative, and as initial unknowns the
  outputs, the derivatives and the states computed at initialisation, so that
  ``fmpy.validation.validate_fmu`` reports no problems;
* on Linux makes the FMU's binary the FMI 3 loader (``fmu_src/loader/fmi3_loader.c``), with
  pythonfmu3's library beside it, records the building CPython, and writes ``resources/bundle.json``.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from ...component.model_exchange import STATES
from ...component.variables import INTERFACES, MODEL_IDENTIFIER
from .. import presets
from . import bundle
from .carried_python import PLATFORMS
from .staging import adapter_sources as _adapter_sources
from .staging import (
    builder_imports_forgotten,
    check_platform_binary,
    copy_adapters,
    copy_runtime,
    rewrite_fmu,
    unit_definitions,
)

DEFAULT_FMU3_PATH = Path("build") / "fmi3" / f"{MODEL_IDENTIFIER}.fmu"


def adapter_sources() -> list[Path]:
    """The FMI 3 adapter and the modules it shares (in the installed ``double_pendulum.adapters``)."""
    return _adapter_sources(3)


def complete_model_description_fmi3(xml_text: bytes) -> bytes:
    """Add unit definitions and write the ModelStructure of a pythonfmu3 modelDescription."""
    interface = INTERFACES[MODEL_IDENTIFIER]
    root = ET.fromstring(xml_text)
    variables = list(root.find("ModelVariables"))
    units = [v.get("unit") for v in variables if v.get("unit")]
    last_interface = max(i for i, e in enumerate(root) if e.tag in ("ModelExchange", "CoSimulation"))
    for old in root.findall("UnitDefinitions"):
        root.remove(old)
    root.insert(last_interface + 1, unit_definitions(units))

    reference = {v.get("name"): v.get("valueReference") for v in variables}
    states = [v.get("derivative") for v in variables if v.get("derivative") is not None]
    structure = root.find("ModelStructure")
    for old in list(structure):
        structure.remove(old)
    for v in variables:
        if v.get("causality") != "output":
            continue
        own = reference[v.get("name")]
        inputs = [reference[name] for name in interface.output_dependencies.get(v.get("name"), ())]
        knowns = [own] if own in states else states  # a state output is its state
        ET.SubElement(structure, "Output", valueReference=own,
                      dependencies=" ".join(sorted(set(inputs + knowns), key=int)))
    for v in variables:
        if v.get("derivative") is not None:
            ET.SubElement(structure, "ContinuousStateDerivative", valueReference=v.get("valueReference"))
    # FMI 3.0, 2.4.8: the outputs, the continuous states and their derivatives that are calculated or
    # approx; a local diagnostic that is neither is no initial unknown
    derivatives = {v.get("valueReference") for v in variables if v.get("derivative") is not None}
    for v in variables:
        vr = v.get("valueReference")
        exposed = v.get("causality") == "output" or vr in states or vr in derivatives
        if v.get("initial") in ("approx", "calculated") and exposed:
            ET.SubElement(structure, "InitialUnknown", valueReference=vr)
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def build_fmu3(dest: str | Path = DEFAULT_FMU3_PATH, start_values: Mapping[str, Any] | None = None,
               lean: bool = False, platforms: tuple[str, ...] = PLATFORMS) -> Path:
    """Build the FMI 3.0 ``DoublePendulum`` FMU at ``dest`` (a ``.fmu`` path or a folder); return its path.

    ``start_values`` (parameters by name) are baked in as the FMU's defaults
    (:mod:`double_pendulum.fmu.presets`); ``lean`` and ``platforms``: as for FMI 2 (:func:`~.fmi2.build_fmu`).
    Written to a temporary folder first and moved into place at the end,
    so a failed build never leaves a broken FMU behind.
    """
    from pythonfmu3.builder import FmuBuilder

    start_values = presets.checked_start_values(MODEL_IDENTIFIER, start_values)
    dest = Path(dest)
    fmu_path = dest if dest.suffix == ".fmu" else dest / f"{MODEL_IDENTIFIER}.fmu"
    fmu_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="dp_fmu3_build_") as tmp:
        tmp_dir = Path(tmp)
        (tmp_dir / "script").mkdir()
        with builder_imports_forgotten():
            built = Path(FmuBuilder.build_FMU(
                bundle.builder_script(tmp_dir / "script", MODEL_IDENTIFIER, 3),
                dest=tmp_dir / "out",
                project_files=[copy_runtime(tmp_dir), copy_adapters(tmp_dir, 3)],
                canGetAndSetFMUState=True,
                canSerializeFMUState=True,
                canHandleVariableCommunicationStepSize=True,
                needsCompletedIntegratorStep=False,
            ))
        rewrite_fmu(built, MODEL_IDENTIFIER, complete_model_description_fmi3, fmi_version=3,
                    defines={"N_CONTINUOUS_STATES": str(len(STATES))}, start_values=start_values, lean=lean,
                    platforms=platforms)
        check_platform_binary(built, MODEL_IDENTIFIER, fmi_version=3)
        shutil.move(str(built), fmu_path)
    return fmu_path
