"""Build the project's FMUs with pythonfmu and complete their modelDescription.

Each FMU of :data:`double_pendulum.component.variables.INTERFACES` (``DoublePendulum``,
``Suspension``) is built from its adapter ``fmu_src/<model identifier>.py``, which maps FMI calls
onto a component through the shared ``fmu_src/double_pendulum_slave.py``; the package's runtime
(``__init__``, :mod:`~double_pendulum.model`, :mod:`~double_pendulum.solvers`,
:mod:`~double_pendulum.component`) and the adapters are bundled into the FMU's ``resources/``
(:mod:`double_pendulum.fmu.build.bundle`: every module under a private name) so the FMU runs without the
project installed, and nothing else is (no analysis, plots or CLI). pythonfmu's
modelDescription lacks units and ``ModelStructure/InitialUnknowns``, so the build then

* adds ``UnitDefinitions`` (SI base-unit exponents) and a ``unit`` attribute on every physical
  Real variable, from the interface's variables (e.g.
  :func:`double_pendulum.component.variables.fmu_variables`);
* lists every output under ``ModelStructure/InitialUnknowns`` (they are computed at
  initialisation), so ``fmpy.validation.validate_fmu`` reports no problems;
* states each output's direct dependencies on the inputs under ``ModelStructure/Outputs``
  (the interface's ``output_dependencies``; ``dependencies=""`` for none),
  which pythonfmu leaves open (open means: depends on every input);
* then rewrites the zip as the FMI 3 build does (:func:`double_pendulum.fmu.build.staging.rewrite_fmu`): the
  bundled code's private layout, the FMU's one binary (the loader), the baked start values and what a tool
  shows of the FMU.

The FMU needs nothing installed where it runs: only a CPython >= 3.11 and its standard library.
Every FMU written is checked to hold a binary for this platform.
"""

from __future__ import annotations

import functools
import importlib.util
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from ...component.variables import INTERFACES, MODEL_IDENTIFIER, FmuInterface
from .. import presets
from . import bundle, loader
from .carried_python import PLATFORMS
from .staging import (
    adapter_sources,
    builder_imports_forgotten,
    check_platform_binary,
    copy_adapters,
    copy_runtime,
    rewrite_fmu,
    runtime_sources,
    unit_definitions,
)

DEFAULT_FMU_PATH = Path("build") / f"{MODEL_IDENTIFIER}.fmu"


def complete_model_description(xml_text: bytes, model_identifier: str = MODEL_IDENTIFIER) -> bytes:
    """Add units, output dependencies and InitialUnknowns to a pythonfmu modelDescription."""
    interface = INTERFACES[model_identifier]
    root = ET.fromstring(xml_text)
    units = {v.name: v.unit for v in interface.variables() if v.fmi_type == "Real" and v.unit not in ("", "1")}
    position = list(root).index(root.find("CoSimulation")) + 1
    root.insert(position, unit_definitions(units.values()))

    outputs_index = []
    index_of: dict[str, int] = {}
    for index, sv in enumerate(root.find("ModelVariables"), start=1):
        real = sv.find("Real")
        index_of[sv.get("name")] = index
        if real is not None and sv.get("name") in units:
            real.set("unit", units[sv.get("name")])
        if sv.get("causality") == "output":
            outputs_index.append(index)

    structure = root.find("ModelStructure")
    _set_output_dependencies(structure, index_of, interface)
    for old in structure.findall("InitialUnknowns"):
        structure.remove(old)
    initial = ET.SubElement(structure, "InitialUnknowns")
    for index in outputs_index:
        ET.SubElement(initial, "Unknown", index=str(index))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _set_output_dependencies(structure: ET.Element, index_of: dict[str, int], interface: FmuInterface) -> None:
    """Give every ``Outputs/Unknown`` its direct dependencies on the inputs (indices, ascending)."""
    name_of = {index: name for name, index in index_of.items()}
    outputs = structure.find("Outputs")
    for unknown in outputs if outputs is not None else ():
        name = name_of[int(unknown.get("index"))]
        deps = sorted(index_of[n] for n in interface.output_dependencies.get(name, ()))
        unknown.set("dependencies", " ".join(map(str, deps)))


def build_fmu(dest: str | Path = DEFAULT_FMU_PATH, model_identifier: str = MODEL_IDENTIFIER,
              start_values: Mapping[str, Any] | None = None, lean: bool = False,
              platforms: tuple[str, ...] = PLATFORMS) -> Path:
    """Build the FMU ``model_identifier`` at ``dest`` (a ``.fmu`` path or a folder) and return its path.

    ``start_values`` (parameters by name) are baked in as the FMU's defaults
    (:mod:`double_pendulum.fmu.presets`). A self-contained FMU carries a CPython for each of ``platforms`` (Linux
    and Windows); a ``lean`` one ships the Linux binary alone and needs a CPython where it runs
    (:func:`~.staging.rewrite_fmu`). The FMU is first written to a temporary folder and moved into
    place at the end, so a failed build never leaves a broken FMU behind.
    """
    from pythonfmu.builder import FmuBuilder

    if model_identifier not in INTERFACES:
        raise ValueError(f"unknown model identifier {model_identifier!r}; known: {', '.join(INTERFACES)}")
    start_values = presets.checked_start_values(model_identifier, start_values)
    dest = Path(dest)
    fmu_path = dest if dest.suffix == ".fmu" else dest / f"{model_identifier}.fmu"
    fmu_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="dp_fmu_build_") as tmp:
        tmp_dir = Path(tmp)
        (tmp_dir / "script").mkdir()
        with builder_imports_forgotten():
            built = FmuBuilder.build_FMU(
                bundle.builder_script(tmp_dir / "script", model_identifier, 2),
                dest=tmp_dir / f"{model_identifier}.fmu",
                project_files=[copy_runtime(tmp_dir), copy_adapters(tmp_dir, 2)],
                canGetAndSetFMUstate=True,
                canSerializeFMUstate=True,
            )
        rewrite_fmu(Path(built), model_identifier, functools.partial(complete_model_description,
                                                                     model_identifier=model_identifier),
                    start_values=start_values, lean=lean, platforms=platforms)
        check_platform_binary(Path(built), model_identifier)
        shutil.move(str(built), fmu_path)
    return fmu_path


# The modules that write what the FMU holds besides the bundled code (its layout, documentation, icon,
# terminals, baked start values): a change to one of them makes the built FMUs stale too.
BUILD_MODULES = (
    "double_pendulum.fmu.build.fmi2",
    "double_pendulum.fmu.build.fmi3",
    "double_pendulum.fmu.build.staging",
    "double_pendulum.fmu.build.bundle",
    "double_pendulum.fmu.presets",
    "double_pendulum.fmu.carries.presentation",
    "double_pendulum.fmu.carries.documentation",
    "double_pendulum.fmu.carries.doc_plot",
    "double_pendulum.fmu.carries.docstring_html",
    "double_pendulum.fmu.carries.icons",
    "double_pendulum.fmu.carries.terminals",
    "double_pendulum.fmu.carries.tex_html",
    "double_pendulum.fmu.carries.elf_needs",
    "double_pendulum.fmu.build.loader",
)


def build_sources() -> list[Path]:
    """The build's own modules (:data:`BUILD_MODULES`), found by their names."""
    return [Path(importlib.util.find_spec(name).origin) for name in BUILD_MODULES]


def fmu_is_current(fmu_path: str | Path, model_identifier: str = MODEL_IDENTIFIER) -> bool:
    """True if ``fmu_path`` exists and is newer than every source file it is built from."""
    fmu_path = Path(fmu_path)
    if not fmu_path.is_file():
        return False
    built = fmu_path.stat().st_mtime
    sources = [*adapter_sources(2), *runtime_sources(), *loader.loader_sources(2), *build_sources()]
    return all(src.stat().st_mtime <= built for src in sources)
