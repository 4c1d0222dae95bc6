"""What the FMI 2 and FMI 3 builds share: the bundled code staged for the builder, and the built zip rewritten.

The FMI 2 build (:mod:`double_pendulum.fmu.build.fmi2`) and the FMI 3 build (:mod:`double_pendulum.fmu.build.fmi3`)
hand their FMI library's builder the runtime (``__init__``, :mod:`~double_pendulum.model`,
:mod:`~double_pendulum.solvers`, :mod:`~double_pendulum.component`: :data:`RUNTIME_SUBPACKAGES`) and the
adapters, then :func:`rewrite_fmu` rewrites what the builder wrote:

* the bundled code in one archive, ``resources/python_code.zip``, every module under a private name
  (:mod:`double_pendulum.fmu.build.bundle`), with hash-checked bytecode;
* the FMU's binaries: the loader of :mod:`double_pendulum.fmu.build.loader`, compiled from source with the FMU's
  GUID for each platform it ships, which calls the Python side itself (the FMI library's binaries are left out),
  and beside it the CPython it carries there (:mod:`double_pendulum.fmu.build.carried_python`: x86_64 Linux and
  Windows); a lean FMU (``--lean``) ships the Linux loader alone and ``resources/python.cfg``, the building
  CPython, which it looks for where it runs;
* ``resources/identity.cfg`` (model, GUID, the code's archive, its package and entry module: the loader refuses
  another FMU's resources and imports the bundled code under private names, ``fmu_src/slave_common.py``);
* the start values it is given (:mod:`double_pendulum.fmu.presets`);
* what a tool shows of the FMU: ``documentation/``, the icon and ``terminalsAndIcons/``
  (:mod:`double_pendulum.fmu.carries.presentation`).

Units in the modelDescription are SI (:data:`UNIT_EXPONENTS`: each unit's base-unit exponents).
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import shutil
import sys
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from .. import presets
from . import bundle, carried_python, loader

PACKAGE_DIR = Path(__file__).resolve().parents[2]
# The runtime the FMU runs: the package's __init__ and these subpackages, nothing else.
RUNTIME_SUBPACKAGES = ("model", "solvers", "component", "codegen")

# SI base-unit exponents of every unit the interfaces use (FMI 2.0 section 2.2.2, FMI 3.0 2.4.3).
UNIT_EXPONENTS: dict[str, dict[str, int]] = {
    "s": {"s": 1},
    "m": {"m": 1},
    "kg": {"kg": 1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "m2": {"m": 2},
    "kg/m3": {"kg": 1, "m": -3},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
    "J": {"kg": 1, "m": 2, "s": -2},
    "W": {"kg": 1, "m": 2, "s": -3},
}



def _adapters_dir() -> Path:
    spec = importlib.util.find_spec("double_pendulum.adapters")
    if spec is None or not spec.submodule_search_locations:
        raise FileNotFoundError("cannot find double_pendulum.adapters: is double-pendulum-fmu installed?")
    return Path(next(iter(spec.submodule_search_locations)))


def adapter_sources(fmi_version: int = 2) -> list[Path]:
    """fmu_src's modules that the FMI ``fmi_version`` FMUs bundle (:data:`double_pendulum.fmu.build.bundle.ADAPTERS`).

    They live in the repository's ``fmu_src/``, installed as ``double_pendulum.adapters``.
    """
    folder = _adapters_dir()
    return [folder / name for name in bundle.ADAPTERS[fmi_version]]


def copy_adapters(dest: Path, fmi_version: int = 2) -> Path:
    """Copy the adapters the FMU bundles into ``dest/adapters`` (the builder's name for their folder)."""
    target = dest / bundle.BUILDER_ADAPTERS
    target.mkdir(parents=True)
    for source in adapter_sources(fmi_version):
        shutil.copy2(source, target / source.name)
    return target


@contextlib.contextmanager
def builder_imports_forgotten() -> Iterator[None]:
    """Forget the modules an FMI library's builder imports from its temporary copy of the adapter.

    pythonfmu's and pythonfmu3's builders import the builder's stub from a temporary folder to write the
    modelDescription and leave that folder on ``sys.path``; the stub would stay in ``sys.modules``.
    """
    before, path = set(sys.modules), list(sys.path)
    try:
        yield
    finally:
        sys.path[:] = path
        for name in set(sys.modules) - before:
            origin = getattr(sys.modules[name], "__file__", None)
            if origin and not os.path.exists(origin):
                del sys.modules[name]


def runtime_sources() -> list[Path]:
    """The package's runtime sources, which the FMU bundles: ``__init__.py`` and the runtime subpackages."""
    files = [PACKAGE_DIR / "__init__.py"]
    for sub in RUNTIME_SUBPACKAGES:
        files += sorted((PACKAGE_DIR / sub).rglob("*.py"))
    return files


def copy_runtime(dest: Path) -> Path:
    """Copy the runtime sources (no caches) into ``dest/double_pendulum``."""
    target = dest / PACKAGE_DIR.name
    for source in runtime_sources():
        copy = target / source.relative_to(PACKAGE_DIR)
        copy.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, copy)
    return target


def unit_definitions(units: Iterable[str]) -> ET.Element:
    """``UnitDefinitions`` for ``units`` (FMI 2 and 3 alike): each one's SI base-unit exponents."""
    used = sorted(set(units))
    unknown = [u for u in used if u not in UNIT_EXPONENTS]
    if unknown:
        raise ValueError(f"no SI definition for unit(s) {unknown}: add them to UNIT_EXPONENTS")
    definitions = ET.Element("UnitDefinitions")
    for unit in used:
        element = ET.SubElement(definitions, "Unit", name=unit)
        ET.SubElement(element, "BaseUnit", {k: str(v) for k, v in UNIT_EXPONENTS[unit].items()})
    return definitions


def variable_count(model_description: bytes) -> int:
    """The number of variables in a modelDescription (FMI 2's ScalarVariables, FMI 3's typed elements): the loader
    refuses a get or set call that names more value references (``N_VARIABLES``)."""
    variables = ET.fromstring(model_description).find("ModelVariables")
    return 0 if variables is None else len(variables)


def instantiation_token(model_description: bytes) -> str:
    """The FMU's GUID (FMI 2) or instantiation token (FMI 3), which the guard checks at instantiation."""
    root = ET.fromstring(model_description)
    return root.get("guid") or root.get("instantiationToken") or ""


# What a host's tool reads of a self-contained FMU: nothing outside it is needed (FMI 2.0 and 3.0,
# needsExecutionTool); a lean FMU needs a CPython installed where it runs.
INTERFACE_ELEMENTS = ("CoSimulation", "ModelExchange")
# Stored, not deflated: fmpy extracts an FMU anew for each simulate_fmu call, and inflating the carried Pythons'
# libraries (about 12 MB) would cost every call more than copying them (docs/performance.md); and a zip whose
# members are deflated already (the Windows standard library).
STORED_SUFFIXES = (".dll", ".so.1.0", ".pyd")


def _stored(name: str, data: bytes) -> bool:
    """Whether the FMU's zip stores ``name`` as it is (see :data:`STORED_SUFFIXES`)."""
    if not name.startswith("binaries/"):
        return False
    if name.endswith(".zip"):
        with zipfile.ZipFile(io.BytesIO(data)) as inner:
            return any(info.compress_type != zipfile.ZIP_STORED for info in inner.infolist())
    return name.endswith(STORED_SUFFIXES)


def mark_execution_tool(model_description: bytes, needed: bool) -> bytes:
    """The modelDescription with ``needsExecutionTool`` set on each interface to ``needed``."""
    root = ET.fromstring(model_description)
    for element in root:
        if element.tag in INTERFACE_ELEMENTS:
            element.set("needsExecutionTool", "true" if needed else "false")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _binaries(model_identifier: str, fmi_version: int, token: str, defines: Mapping[str, str],
              code: Mapping[str, bytes], lean: bool, platforms: tuple[str, ...]) -> dict[str, bytes]:
    """``binaries/``: the loader for each of ``platforms`` and, unless ``lean``, the CPython it carries there
    (:mod:`double_pendulum.fmu.build.carried_python`) with its licences; a lean FMU ships the Linux loader and
    ``resources/python.cfg`` (the building CPython, which it looks for where it runs)."""
    identity = {"MODEL_IDENTIFIER": model_identifier, "FMU_GUID": token, **defines}
    if lean:
        return {f"binaries/{loader.LINUX.folder(fmi_version)}/{model_identifier}{loader.LINUX.suffix}":
                loader.compiled_loader(fmi_version, identity), f"resources/{loader.CONFIG_NAME}":
                loader.python_record().encode()}
    files = {}
    for python in carried_python.carried_pythons(code, platforms):
        target = loader.TARGETS[python.platform]
        folder = f"binaries/{target.folder(fmi_version)}/"
        names = {"BUNDLED_PYTHON_LIBRARY": python.library, "BUNDLED_PYTHON_STDLIB": python.stdlib,
                 "BUNDLED_PYTHON_MINOR": str(python.minor), "BUNDLED_PYTHON_PRELOAD": ":".join(python.preload)}
        files[f"{folder}{model_identifier}{target.suffix}"] = loader.compiled_loader(fmi_version,
                                                                                     {**identity, **names}, target)
        files.update({folder + name: data for name, data in python.files.items()})
        files.update({f"documentation/licenses/{name}": text for name, text in carried_python.licenses(python).items()})
    return files


def rewrite_fmu(fmu: Path, model_identifier: str, complete: Callable[[bytes], bytes], fmi_version: int = 2,
                defines: dict[str, str] | None = None, start_values: Mapping[str, Any] | None = None,
                lean: bool = False, platforms: tuple[str, ...] = carried_python.PLATFORMS) -> None:
    """Rewrite the zip: the bundled code in one archive under private names, the completed modelDescription,
    the loaders (compiled with the FMU's GUID and ``defines``) for ``platforms`` with the CPython each carries (a
    ``lean`` FMU: the Linux loader alone), ``identity.cfg``, and what a tool shows of the FMU (documentation, icon,
    terminals: :mod:`double_pendulum.fmu.carries.presentation`).

    ``complete`` completes the modelDescription. Precompiled bytecode spares every fresh extraction
    (fmpy extracts the FMU anew for each ``simulate_fmu`` call) the compilation of the bundled
    sources at start-up. ``start_values`` (checked) become the FMU's defaults (:mod:`double_pendulum.fmu.presets`).
    """
    with zipfile.ZipFile(fmu) as src:
        files = {item.filename: src.read(item.filename) for item in src.infolist()}
    files, code, identity = bundle.bundled_entries(files, model_identifier, fmi_version)
    description = mark_execution_tool(complete(files["modelDescription.xml"]), needed=lean)
    files["modelDescription.xml"] = presets.apply_start_values(description, start_values or {})
    if start_values:
        files[presets.PRESET_FILE] = presets.preset_file(start_values)
    token = instantiation_token(files["modelDescription.xml"])
    # The FMI library's binaries (pythonfmu's C++ layer, for every platform it ships) are left out: the
    # FMU's binaries are the loader, built here from source, which calls the Python side itself.
    # pythonfmu3's sources/ build its own C++ library, not this binary: an FMU carries no sources that do not
    # build it
    files = {name: data for name, data in files.items() if not name.startswith(("binaries/", "sources/"))}
    defines = {**(defines or {}), "N_VARIABLES": str(variable_count(files["modelDescription.xml"]))}
    files.update(_binaries(model_identifier, fmi_version, token, defines, code, lean, platforms))
    files[bundle.IDENTITY_FILE] = bundle.identity_record(model_identifier, token, identity)
    from ..carries.presentation import presentation_files  # here: matplotlib and numpy only when building

    files.update(presentation_files(model_identifier, fmi_version, files, start_values))
    tmp = fmu.with_suffix(".fmu.tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
        for name, data in files.items():
            dst.writestr(name, data, compress_type=zipfile.ZIP_STORED if _stored(name, data) else zipfile.ZIP_DEFLATED)
    tmp.replace(fmu)


def check_platform_binary(fmu: Path, model_identifier: str, fmi_version: int = 2) -> None:
    """Raise if ``fmu`` holds no binary for this platform (it could not run here)."""
    from fmpy import platform, platform_tuple, sharedLibraryExtension

    binary = f"binaries/{platform if fmi_version == 2 else platform_tuple}/{model_identifier}{sharedLibraryExtension}"
    with zipfile.ZipFile(fmu) as z:
        if binary not in z.namelist():
            library = "pythonfmu" if fmi_version == 2 else "pythonfmu3"
            raise RuntimeError(f"{fmu} holds no binary for this platform ({binary} missing): is {library}'s "
                               f"binary for this platform installed ({library}.builder.FmuBuilder.has_binary())?")
