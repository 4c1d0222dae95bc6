"""What every FMU's Python side shares, FMI 2 (pythonfmu) and FMI 3 (pythonfmu3): the bundled code
under private names, and the mapping of a slave onto one co-simulation component.

The build bundles the package's runtime (model, solvers, component, codegen), the FMI library's slave
modules and these adapters into one zip in the FMU's resources (``double_pendulum.fmu.build.bundle``)::

    resources/python_code.zip
        _dp_fmu_<id>_<Model>.py       the module the loader imports (slavemodule.txt names it)
        _dp_fmu_<id>_adapters/        these adapters, a package
        _dp_fmu_<id>/                 the runtime
        _dp_fmu_<id>_pythonfmu/       the FMI library's slave modules (pythonfmu3 for FMI 3)
    resources/identity.cfg            the model, its GUID, the archive and the entry module, for the C loader
    resources/start_values.json       start values baked in by the build (if any)

In a built FMU (these adapters imported from that zip under a private name) every module is imported
under a private name, so the FMU always runs its own code, whatever ``DoublePendulum``,
``slave_common``, ``double_pendulum``, ``pythonfmu`` or ``pythonfmu3`` the process holds (another author's
FMU of the same name, an older build of this one), and imports nothing under a public name; nothing is
put on ``sys.path`` (the loader imports the entry module from the archive: ``loader/bridge.c``). At build
time (imported as ``double_pendulum.adapters``) the installed packages are used, as the FMI library's
builder needs its own slave classes.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import sys
import zipimport
from pathlib import Path
from types import ModuleType

from .fmi_bridge import host_exception

PRESET_FILE = "start_values.json"  # start values baked in by the build (double_pendulum.fmu.presets)
PRIVATE_MARK = "_dp_fmu_"  # every private module name starts with it
ADAPTERS_SUFFIX = "_adapters"

# In a built FMU: the archive these adapters were imported from, and the private prefix _dp_fmu_<id> of the
# bundle (this package is _dp_fmu_<id>_adapters); at build time both None.
ARCHIVE = getattr(globals().get("__loader__"), "archive", None) if __package__.startswith(PRIVATE_MARK) else None
PRIVATE_PREFIX = __package__.removesuffix(ADAPTERS_SUFFIX) if ARCHIVE else None
RESOURCES = Path(ARCHIVE).parent if ARCHIVE else Path(__file__).resolve().parent


def _import_private(name: str, *, run_init: bool = True) -> ModuleType:
    """Import the package ``name`` from the bundle's archive (once per process; through the finder the loader's
    bootstrap registered for it, archive_import, else zipimport); ``run_init=False`` registers it without running
    its ``__init__``, for its submodules alone."""
    if name not in sys.modules:
        finder = sys.path_importer_cache.get(ARCHIVE)
        spec = (finder if hasattr(finder, "find_spec") else zipimport.zipimporter(ARCHIVE)).find_spec(name)
        if spec is None:
            raise ImportError(f"{name} is not in {ARCHIVE}", name=name)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            if run_init:
                spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    return sys.modules[name]


def fmi_library(name: str) -> str:
    """The name to import the FMI library ``name`` (``pythonfmu`` or ``pythonfmu3``) under.

    In a built FMU its bundled copy is registered privately without running its ``__init__``, which
    would also import its builder (argparse, inspect, xml.dom; not bundled): the slave side needs only
    submodules.
    """
    if PRIVATE_PREFIX:
        return _import_private(f"{PRIVATE_PREFIX}_{name}", run_init=False).__name__
    return name


def runtime_package() -> ModuleType:
    """The ``double_pendulum`` package this FMU runs: the bundled copy (privately), or the installed one."""
    if PRIVATE_PREFIX:
        return _import_private(PRIVATE_PREFIX)
    return importlib.import_module("double_pendulum")


def runtime_module(name: str) -> ModuleType:
    """Import ``double_pendulum.<name>`` from the package this FMU runs (bundled or installed)."""
    return importlib.import_module(f"{runtime_package().__name__}.{name}")


def baked_start_values(resources: str | None) -> dict:
    """The start values the build baked into this FMU (``resources/start_values.json``), ``{}`` for none.

    Read from the instance's own resources folder at every instantiation and reset: FMUs of one bundle
    share their modules, not their start values.
    """
    try:
        return json.loads((Path(resources or RESOURCES) / PRESET_FILE).read_text())
    except FileNotFoundError:
        return {}


class ComponentMapping:
    """The part of a slave that does not depend on the FMI version: one co-simulation component.

    Subclasses (with the FMI library's slave class) set ``interface`` (an ``FmuInterface``),
    ``discard_status`` and ``warning_status`` (the library's statuses), keep the component in
    ``self._sim`` and implement :meth:`make_component`. Exceptions go to the loader, which logs them
    (``fmi_bridge.py``).
    """

    author = "double-pendulum-fmu contributors"
    license = "MIT"
    interface = None
    discard_status = warning_status = None

    def make_component(self):
        raise NotImplementedError

    def new_component(self):
        """A fresh component with the start values baked into this FMU (:func:`baked_start_values`)."""
        component = self.make_component()
        for name, value in baked_start_values(self.resources).items():
            component.set(name, value)
        return component

    def _output(self, name: str) -> float:
        """Output ``name``; before initialisation from the parameters and inputs set so far.

        FMI lets a master read outputs in Initialization Mode (libcosim and fmpy's container
        FMU pass them on to other FMUs there); they must then follow the start values already
        set, not the defaults. A throwaway component initialised with those values gives them.
        """
        if self._sim.initialised:
            return self._sim.outputs[name]
        return self._preview().outputs[name]

    def _preview(self):
        key = repr((sorted(self._sim.values.items()), sorted(self._sim.inputs.items()), self._sim.time))
        if getattr(self, "_preview_key", None) != key:
            preview = self.make_component()
            for parameter, value in self._sim.values.items():
                preview.set(parameter, value)
            preview.set_start_time(self._sim.time)
            preview.initialise()
            for input_name, value in self._sim.inputs.items():
                preview.set_input(input_name, value)
            self._preview_key, self._preview_sim = key, preview
        return self._preview_sim

    def check_fmu_state(self, state) -> None:
        """Raise (naming what is wrong) unless ``state`` is one :meth:`_get_fmu_state` of this FMU gives."""
        type(self._sim).check_state(state)

    def fmu_state_time(self, state) -> float:
        """The component's time [s] in a checked ``state`` (the time the loader's state header must hold)."""
        return state["time"]

    def _component_step(self, current_time: float, step_size: float) -> bool:
        """doStep of the component; a failure of the solver is a discarded step (False), logged with the
        Discard status. The component's warnings (``notices``) go to the host's log, once each."""
        sim = self._sim
        try:
            sim.do_step(current_time, step_size)
        except Exception as error:
            if host_exception(error):  # the host's signal handler, not the solver: no Discard
                raise
            self.log(f"the step was not completed: {error}", self.discard_status)
            return False
        if sim.notices:
            self._warn(sim.notices)
        return True

    def _warn(self, notices: list) -> None:
        """Pass the component's warnings to the host's log (warning status), once each."""
        for notice in notices:
            self.log(notice, self.warning_status)
        notices.clear()
