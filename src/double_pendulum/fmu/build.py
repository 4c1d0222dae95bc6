"""Build the project's FMUs with pythonfmu and complete their modelDescription.

Each FMU of :data:`double_pendulum.component.variables.INTERFACES` (``DoublePendulum``,
``Suspension``) is built from its adapter ``fmu_src/<model identifier>.py``, which maps FMI calls
onto a component through the shared ``fmu_src/double_pendulum_slave.py``; the package's runtime
(``__init__``, :mod:`~double_pendulum.model`, :mod:`~double_pendulum.solvers`,
:mod:`~double_pendulum.component`) and the adapters are bundled into the FMU's ``resources/``
(:mod:`double_pendulum.fmu.bundle`: every module under a private name) so the FMU runs without the
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
* makes the FMU's one binary the loader of :mod:`double_pendulum.fmu.loader` (compiled from source
  with the FMU's GUID), which calls the Python side itself (pythonfmu's binaries are left out), so
  the FMU runs in hosts that are not Python and answers every FMI call as the standard says, and
  records the building CPython in ``resources/python.cfg``;
* writes ``resources/identity.cfg`` (model, GUID, entry module: the loader refuses another FMU's
  resources) and ``resources/bundle.json`` (a hash of the bundled code), which makes the FMU import
  its bundled code under private names (``fmu_src/slave_common.py``);
* bakes in the start values it is given (:mod:`double_pendulum.fmu.presets`);
* adds what a tool shows of the FMU: ``documentation/``, the icon and ``terminalsAndIcons/``
  (:mod:`double_pendulum.fmu.presentation`).

The FMU needs nothing installed where it runs: only a CPython >= 3.11 and its standard library.
Every FMU written is checked to hold a binary for this platform.
"""

from __future__ import annotations

import contextlib
import functools
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

from ..component.variables import INTERFACES, MODEL_IDENTIFIER, FmuInterface
from . import bundle, loader, presets

PACKAGE_DIR = Path(__file__).resolve().parents[1]
# The runtime the FMU runs: the package's __init__ and these subpackages, nothing else.
RUNTIME_SUBPACKAGES = ("model", "solvers", "component", "codegen")
DEFAULT_FMU_PATH = Path("build") / f"{MODEL_IDENTIFIER}.fmu"

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
    """fmu_src's modules that the FMI ``fmi_version`` FMUs bundle (:data:`double_pendulum.fmu.bundle.ADAPTERS`).

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


def _copy_runtime(dest: Path) -> Path:
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
    the FMU (documentation, icon, terminals: :mod:`.presentation`).

    ``complete`` completes the modelDescription. Precompiled bytecode spares every fresh extraction
    (fmpy extracts the FMU anew for each ``simulate_fmu`` call) the compilation of the bundled
    sources at start-up. ``start_values`` (checked) become the FMU's defaults (:mod:`.presets`).
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
    from .presentation import presentation_files  # here: matplotlib and numpy only when building

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


def build_fmu(dest: str | Path = DEFAULT_FMU_PATH, model_identifier: str = MODEL_IDENTIFIER,
              start_values: Mapping[str, Any] | None = None) -> Path:
    """Build the FMU ``model_identifier`` at ``dest`` (a ``.fmu`` path or a folder) and return its path.

    ``start_values`` (parameters by name) are baked in as the FMU's defaults (:mod:`.presets`). The FMU
    is first written to a temporary folder and moved into place at the end, so a failed build never
    leaves a broken FMU behind.
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
                project_files=[_copy_runtime(tmp_dir), copy_adapters(tmp_dir, 2)],
                canGetAndSetFMUstate=True,
                canSerializeFMUstate=True,
            )
        rewrite_fmu(Path(built), model_identifier, functools.partial(complete_model_description,
                                                                     model_identifier=model_identifier),
                    start_values=start_values)
        check_platform_binary(Path(built), model_identifier)
        shutil.move(str(built), fmu_path)
    return fmu_path


def build_all(dest: str | Path = DEFAULT_FMU_PATH) -> list[Path]:
    """Build every FMU: ``DoublePendulum`` at ``dest`` (a ``.fmu`` path or a folder), the others next to it,
    then the coupled system (:func:`build_systems`), then the FMI 3.0 ``DoublePendulum`` in the
    subfolder ``fmi3/`` (:func:`double_pendulum.fmu.build_fmi3.build_fmu3`)."""
    from .build_fmi3 import build_fmu3

    dest = Path(dest)
    first = build_fmu(dest, MODEL_IDENTIFIER)
    others = [build_fmu(first.parent / f"{name}.fmu", name) for name in INTERFACES if name != MODEL_IDENTIFIER]
    fmi3 = build_fmu3(first.parent / "fmi3" / f"{MODEL_IDENTIFIER}.fmu")
    return [first, *others, *build_systems(first), fmi3]


def build_systems(
    pendulum_fmu: str | Path, values: dict | None = None, macro_step: float = 1e-3
) -> list[Path]:
    """Write the coupled system next to the built FMUs: ``PendulumOnSuspension.ssp`` (SSP, for libcosim)
    and ``PendulumOnSuspension.fmu`` (fmpy's container FMU, FMI 2.0), macro step ``macro_step`` [s].

    ``pendulum_fmu``: the DoublePendulum FMU; ``Suspension.fmu`` is expected next to it.
    """
    from .container import write_container
    from .ssp import write_ssp

    folder = Path(pendulum_fmu).parent
    fmus = (Path(pendulum_fmu), folder / "Suspension.fmu")
    return [
        write_ssp(folder / "PendulumOnSuspension.ssp", *fmus, values, macro_step=macro_step, reference=True),
        write_container(folder / "PendulumOnSuspension.fmu", *fmus, values, macro_step=macro_step, documented=True),
    ]


# The modules that write what the FMU holds besides the bundled code (its layout, documentation, icon,
# terminals, baked start values): a change to one of them makes the built FMUs stale too.
BUILD_MODULES = ("build", "build_fmi3", "bundle", "presets", "presentation", "documentation", "doc_plot",
                 "docstring_html", "icons", "terminals", "tex_html", "elf_needs", "loader")


def build_sources() -> list[Path]:
    """The build's own modules (:data:`BUILD_MODULES`)."""
    folder = Path(__file__).resolve().parent
    return [folder / f"{name}.py" for name in BUILD_MODULES]


def fmu_is_current(fmu_path: str | Path, model_identifier: str = MODEL_IDENTIFIER) -> bool:
    """True if ``fmu_path`` exists and is newer than every source file it is built from."""
    fmu_path = Path(fmu_path)
    if not fmu_path.is_file():
        return False
    built = fmu_path.stat().st_mtime
    sources = [*adapter_sources(2), *runtime_sources(), *loader.loader_sources(2), *build_sources()]
    return all(src.stat().st_mtime <= built for src in sources)
