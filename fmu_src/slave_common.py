"""What every FMU's Python side shares, FMI 2 (pythonfmu) and FMI 3 (pythonfmu3): the bundled code
under private names, a Python host left as it was found, errors reported once.

The build bundles the package's runtime (model, solvers, component), the FMI library's Python part
and these adapters into the FMU's resources::

    resources/_dp_fmu_<id>_<Model>.py   the module the FMI library imports (slavemodule.txt names it)
    resources/_dp_fmu_<id>_adapters/    these adapters, a package
    resources/double_pendulum/          the runtime, imported as _dp_fmu_<id>
    resources/pythonfmu/ (pythonfmu3/)  the FMI library's Python part, imported as _dp_fmu_<id>_pythonfmu
    resources/bundle.json               {"id": a hash of the bundled code, "guard": the C guard is the binary}

In a built FMU (``bundle.json`` present) every module is imported under a private name, so the FMU
always runs its own code, whatever ``DoublePendulum``, ``slave_common``, ``double_pendulum``,
``pythonfmu`` or ``pythonfmu3`` the process holds (another author's FMU of the same name, an older
build of this one), and imports nothing under a public name. At build time (no ``bundle.json``)
the installed packages are used, as the FMI library's builder needs its own slave classes.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import sys
from pathlib import Path
from types import ModuleType

RESOURCES = Path(__file__).resolve().parent.parent  # in a built FMU: this package's folder is in resources/
BUNDLE_FILE = "bundle.json"  # written by the build (double_pendulum.fmu.build)
PRESET_FILE = "start_values.json"  # start values baked in by the build (double_pendulum.fmu.presets)
STDERR_SWITCH = "DOUBLE_PENDULUM_FMU_STDERR"  # "0": errors go to the FMI log only
PRIVATE_MARK = "_dp_fmu_"  # every private module name starts with it


def _bundle() -> dict:
    """``bundle.json`` in a built FMU, ``{}`` at build time."""
    try:
        return json.loads((RESOURCES / BUNDLE_FILE).read_text())
    except FileNotFoundError:
        return {}


BUNDLE = _bundle()
PRIVATE_PREFIX = PRIVATE_MARK + BUNDLE["id"] if "id" in BUNDLE else None  # _dp_fmu_<id>; None at build time
GUARDED = bool(BUNDLE.get("guard"))  # the FMU's binary is the C guard, which logs every error (fmu_src/loader/)


def _import_private(name: str, folder: Path, *, run_init: bool = True) -> ModuleType:
    """Import the package in ``folder`` as ``name`` (once per process); ``run_init=False`` registers it
    without running its ``__init__.py``, for its submodules alone."""
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, folder / "__init__.py", submodule_search_locations=[str(folder)]
        )
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
    would also import its builder (argparse, inspect, xml.dom): the slave side needs only submodules.
    """
    if PRIVATE_PREFIX:
        return _import_private(f"{PRIVATE_PREFIX}_{name}", RESOURCES / name, run_init=False).__name__
    return name


def runtime_package() -> ModuleType:
    """The ``double_pendulum`` package this FMU runs: the bundled copy (privately), or the installed one."""
    if PRIVATE_PREFIX:
        return _import_private(PRIVATE_PREFIX, RESOURCES / "double_pendulum")
    return importlib.import_module("double_pendulum")


def runtime_module(name: str) -> ModuleType:
    """Import ``double_pendulum.<name>`` from the package this FMU runs (bundled or installed)."""
    return importlib.import_module(f"{runtime_package().__name__}.{name}")


def leave_host_as_found(resources: str | None) -> None:
    """Undo what the FMI library's binary did to the host's interpreter to load this FMU.

    It puts the FMU's resources folder first on ``sys.path`` at every instantiation, where a later
    ``import pythonfmu`` or ``import double_pendulum`` in the host would find the FMU's copies. Once
    an instance exists, everything it needs is imported (under private names), so the folder goes.
    The FMU imports nothing under a public name, so ``sys.modules`` needs nothing undone. Does
    nothing at build time.
    """
    if not PRIVATE_PREFIX:
        return
    folder = os.path.normpath(resources or RESOURCES)  # the library inserts the string it was given
    if any(entry == folder or os.path.normpath(entry) == folder for entry in sys.path if entry):
        sys.path[:] = [entry for entry in sys.path if not entry or os.path.normpath(entry) != folder]


def baked_start_values(resources: str | None) -> dict:
    """The start values the build baked into this FMU (``resources/start_values.json``), ``{}`` for none.

    Read from the instance's own resources folder at every instantiation and reset: FMUs of one bundle
    share their modules, not their start values.
    """
    try:
        return json.loads((Path(resources or RESOURCES) / PRESET_FILE).read_text())
    except FileNotFoundError:
        return {}


class _StoredRepr(type):
    """A class whose repr is a stored string: ``repr()`` of it makes no new object."""

    def __repr__(cls) -> str:
        return cls.stored_repr


# What pythonfmu's findClass is shown in place of the FMU's class (entry_module_executed).
_FMI2_SLAVE_NAME = _StoredRepr("Fmi2Slave", (), {"stored_repr": "<class 'pythonfmu.Fmi2Slave'>"})
_FINDER_STAND_IN = _StoredRepr("StandIn", (_FMI2_SLAVE_NAME,), {"stored_repr": "_"})


def entry_module_executed(namespace: dict, local_namespace: dict, model_class: type) -> type:
    """What the FMI 2 entry module (``resources/_dp_fmu_<id>_<Model>.py``) binds to the model's name.

    pythonfmu 0.7.0 (``PySlaveInstance.cpp``, ``findClass``) imports that module, then runs its
    source a second time, with the module's namespace as globals and fresh locals, and looks in the
    locals for a class whose MRO names ``Fmi2Slave``; it then takes the module's attribute of that
    name. On that second run (``locals() is not globals()``), at every instantiation, it

    * releases one reference to the module's namespace, which it only borrowed: given back here,
      or the namespace would be freed under the module after a few instantiations;
    * leaks the list of the MRO and the repr of each class in it, as a string and as bytes (about
      1.5 KiB for the model's class). It is shown a stand-in instead, whose MRO is two classes of
      ours, with reprs stored once ("_", and one naming Fmi2Slave) and ``object``: what still leaks
      is the list, the repr of ``object``, two bytes objects (about 0.3 KiB).

    At import (the first run) the model's class itself is bound, which findClass then takes.
    """
    if local_namespace is namespace:
        return model_class
    compensate_release(namespace)
    return _FINDER_STAND_IN


def compensate_release(*objects) -> None:
    """Add one reference count to each object, without keeping a reference.

    When a Python exception reaches the C++ layer of pythonfmu (<= 0.7.0) or pythonfmu3 (0.3.4), its
    ``handle_py_exception`` calls ``cleanPyObject``, which releases the slave's references (class,
    instance, log queue) once more while the C++ object still holds them and releases them again when
    it is freed. Unbalanced, a few dozen failed calls over fresh instances left the host to crash in
    the garbage collector (segfault, about 2 runs in 3), and the fourth failed call on one instance
    crashed it at once (FMI 2 and FMI 3 alike: the class was freed under the live instance). The slave
    adds one reference to each of the three per failed call, so the counts stay exact.
    """
    import ctypes

    for obj in objects:
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(obj))


def report(instance_name: str, model_identifier: str, error: BaseException) -> None:
    """Print an error to stderr where nothing else shows it.

    The C guard in front of the FMI library (every FMU built where a C compiler is) passes every
    error to the host's logger, debug logging on or off; there stderr would repeat it. Without the
    guard (pythonfmu's plain binary) the library logs only with debug logging on, and stderr makes
    the error visible to a user with logging off. A host that logs every message itself (the
    project's own ``FmuRunner``) sets ``DOUBLE_PENDULUM_FMU_STDERR=0``.
    """
    if not GUARDED and os.environ.get(STDERR_SWITCH, "1") != "0":
        print(f"[{instance_name}] {model_identifier}: {error}", file=sys.stderr, flush=True)


# The variable access of pythonfmu (FMI 2) and pythonfmu3 (FMI 3) that ComponentMapping guards.
ACCESSORS = tuple(f"{kind}_{type_}" for kind in ("get", "set") for type_ in (
    "real", "integer", "boolean", "string", "float64", "int32", "int64", "uint64"))


def _guarded_method(method):
    def guarded(self, *args):
        return self._guarded(method, self, *args)

    guarded.__name__, guarded.__doc__ = method.__name__, method.__doc__
    return guarded


class ComponentMapping:
    """The part of a slave that does not depend on the FMI version: one co-simulation component.

    Subclasses (with the FMI library's slave class) set ``interface`` (an ``FmuInterface``),
    ``error_status`` and ``warning_status`` (the library's statuses), keep the component in
    ``self._sim`` and implement :meth:`make_component`.
    """

    author = "double-pendulum-fmu contributors"
    license = "MIT"
    interface = None
    error_status = warning_status = None

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

    def __init_subclass__(cls, **kwargs) -> None:
        """Guard the FMI library's variable access too: an unknown value reference or a wrong type
        raises in the library's own code, and that exception releases the references as well. (An
        accessor a slave class of ours defines guards itself, with :meth:`_fail`.)"""
        super().__init_subclass__(**kwargs)
        for name in ACCESSORS:
            owner = next((k for k in cls.__mro__ if name in vars(k)), None)
            if owner is not None and not issubclass(owner, ComponentMapping):
                setattr(cls, name, _guarded_method(getattr(cls, name)))

    def _guarded(self, call, *args):
        """Run ``call``; on error report it and re-raise (:meth:`_fail`)."""
        try:
            return call(*args)
        except Exception as error:
            self._fail(error)

    def _fail(self, error: Exception):
        """Print ``error`` to stderr, balance the references the FMI library will release, re-raise it.

        pythonfmu turns the exception into fmi2Fatal (pythonfmu3: fmi3Fatal) and passes its message
        to the host's logger (pythonfmu: only when logging is on); stderr makes it visible to a user
        with logging off too. Both happen once per exception (:func:`compensate_release`), however
        many guarded calls it passes through.
        """
        if not getattr(error, "_dp_fmu_balanced", False):
            error._dp_fmu_balanced = True
            self._report(error)
            compensate_release(type(self), self, self.log_queue)
        raise error

    def _report(self, error) -> None:
        report(self.instance_name, self.interface.model_identifier, error)

    def _component_step(self, current_time: float, step_size: float) -> bool:
        """doStep of the component; any failure is a discarded step (False), never an exception into
        the FMI library: the message goes to the host's log and to stderr. The component's warnings
        (``notices``) go there too, once each."""
        sim = self._sim
        try:
            sim.do_step(current_time, step_size)
        except Exception as error:
            self.log(f"the step was not completed: {error}", self.error_status)
            self._report(error)
            return False
        if sim.notices:
            self._warn(sim.notices)
        return True

    def _warn(self, notices: list) -> None:
        """Pass the component's warnings to the host's log (warning status) and stderr, once each."""
        for notice in notices:
            self.log(notice, self.warning_status)
            self._report(notice)
        notices.clear()
