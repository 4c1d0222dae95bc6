"""What the FMI 2 and FMI 3 builds share: the bundled code staged for the builder, and the built zip rewritten.

The FMI 2 build (:mod:`double_pendulum.fmu.build.fmi2`) and the FMI 3 build (:mod:`double_pendulum.fmu.build.fmi3`)
hand their FMI library's builder the runtime (``__init__``, :mod:`~double_pendulum.model`,
:mod:`~double_pendulum.solvers`, :mod:`~double_pendulum.component`: :data:`RUNTIME_SUBPACKAGES`) and the
adapters, then :func:`rewrite_fmu` rewrites what the builder wrote:

* the bundled code's private layout (:mod:`double_pendulum.fmu.build.bundle`: every module under a private name)
  with hash-checked bytecode;
* the FMU's one binary: the loader of :mod:`double_pendulum.fmu.build.loader`, compiled from source with the FMU's
  GUID, which calls the Python side itself (the FMI library's binaries are left out), and
  ``resources/python.cfg``, the building CPython;
* ``resources/identity.cfg`` (model, GUID, entry module: the loader refuses another FMU's resources) and
  ``resources/bundle.json`` (a hash of the bundled code), which makes the FMU import its bundled code under
  private names (``fmu_src/slave_common.py``);
* the start values it is given (:mod:`double_pendulum.fmu.presets`);
* what a tool shows of the FMU: ``documentation/``, the icon and ``terminalsAndIcons/``
  (:mod:`double_pendulum.fmu.carries.presentation`).

Units in the modelDescription are SI (:data:`UNIT_EXPONENTS`: each unit's base-unit exponents).
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import shutil
import sys
import tempfile
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from .. import presets
from . import bundle, loader

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

BUNDLE_FILE = "resources/bundle.json"  # the bundle's id: the private name its code is imported under


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


def compiled_bytecode(source: bytes, arcname: str) -> tuple[str, bytes]:
    """Return the ``__pycache__`` path and hash-checked bytecode of one Python source in the FMU.

    Hosts extract FMUs without restoring file times, so the bytecode is checked against a hash
    of the source (PEP 552) rather than its time stamp; a Python of another minor version simply
    ignores it (other cache tag) and compiles the source as usual.
    """
    import importlib.util
    import py_compile

    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "module.py"
        src.write_bytes(source)
        cfile = Path(tmp) / "module.pyc"
        py_compile.compile(str(src), cfile=str(cfile), dfile=arcname, doraise=True,
                           invalidation_mode=py_compile.PycInvalidationMode.CHECKED_HASH)
        cached = importlib.util.cache_from_source(arcname)
        return cached, cfile.read_bytes()


def instantiation_token(model_description: bytes) -> str:
    """The FMU's GUID (FMI 2) or instantiation token (FMI 3), which the guard checks at instantiation."""
    root = ET.fromstring(model_description)
    return root.get("guid") or root.get("instantiationToken") or ""


def rewrite_fmu(fmu: Path, model_identifier: str, complete: Callable[[bytes], bytes], fmi_version: int = 2,
                defines: dict[str, str] | None = None, start_values: Mapping[str, Any] | None = None) -> None:
    """Rewrite the zip: the private layout of the bundled code, the completed modelDescription, bytecode,
    the loader (compiled with the FMU's GUID and ``defines``), ``bundle.json``, and what a tool shows of
    the FMU (documentation, icon, terminals: :mod:`double_pendulum.fmu.carries.presentation`).

    ``complete`` completes the modelDescription. Precompiled bytecode spares every fresh extraction
    (fmpy extracts the FMU anew for each ``simulate_fmu`` call) the compilation of the bundled
    sources at start-up. ``start_values`` (checked) become the FMU's defaults (:mod:`double_pendulum.fmu.presets`).
    """
    with zipfile.ZipFile(fmu) as src:
        files = {item.filename: src.read(item.filename) for item in src.infolist()}
    files, identity = bundle.bundled_entries(files, model_identifier, fmi_version)
    files["modelDescription.xml"] = presets.apply_start_values(complete(files["modelDescription.xml"]),
                                                               start_values or {})
    if start_values:
        files[presets.PRESET_FILE] = presets.preset_file(start_values)
    token = instantiation_token(files["modelDescription.xml"])
    # The FMI library's binaries (pythonfmu's C++ layer, for every platform it ships) are left out: the
    # FMU's one binary is the loader, built here from source, which calls the Python side itself.
    # pythonfmu3's sources/ build its own C++ library, not this binary: an FMU carries no sources that do not
    # build it
    files = {name: data for name, data in files.items() if not name.startswith(("binaries/", "sources/"))}
    binary = f"binaries/{loader.PLATFORMS[fmi_version]}/{model_identifier}.so"
    files[binary] = loader.compiled_loader(fmi_version, {"MODEL_IDENTIFIER": model_identifier, "FMU_GUID": token,
                                                         **(defines or {})})
    files[f"resources/{loader.CONFIG_NAME}"] = loader.python_record().encode()
    files[bundle.IDENTITY_FILE] = bundle.identity_record(model_identifier, token, identity)
    files[BUNDLE_FILE] = json.dumps({"id": identity}).encode()
    from ..carries.presentation import presentation_files  # here: matplotlib and numpy only when building

    files.update(presentation_files(model_identifier, fmi_version, files, start_values))
    tmp = fmu.with_suffix(".fmu.tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
        for name, data in files.items():
            dst.writestr(name, data)
            if name.startswith("resources/") and name.endswith(".py"):
                dst.writestr(*compiled_bytecode(data, name))
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
