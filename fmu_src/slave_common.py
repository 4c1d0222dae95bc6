"""What every FMU's Python side shares, FMI 2 (pythonfmu) and FMI 3 (pythonfmu3): the bundled code
under private names, a Python host left as it was found, errors on stderr.

The build bundles the package's runtime (model, solvers, component) and the FMI library's Python
part into the FMU's resources next to this file. In a built FMU (``resources/bundle.json`` present)
both are imported under private names (``_dp_fmu_<id>``, ``_dp_fmu_<id>_<library>``, the id a hash
of the bundled code), so the FMU always runs its own code, whatever ``double_pendulum``,
``pythonfmu`` or ``pythonfmu3`` the host process has imported. At build time (no ``bundle.json``)
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

RESOURCES = Path(__file__).resolve().parent
BUNDLE_FILE = "bundle.json"  # written by the build (double_pendulum.fmu.build): {"id": hash of the bundled code}
STDERR_SWITCH = "DOUBLE_PENDULUM_FMU_STDERR"  # "0": errors go to the FMI log only
PRIVATE_MARK = "_dp_fmu_"  # every private module name starts with it


def _private_prefix() -> str | None:
    """``_dp_fmu_<id>`` in a built FMU, None at build time."""
    try:
        return PRIVATE_MARK + json.loads((RESOURCES / BUNDLE_FILE).read_text())["id"]
    except FileNotFoundError:
        return None


PRIVATE_PREFIX = _private_prefix()


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

    It put the FMU's resources folder first on ``sys.path`` and imported the adapter (and through it
    the shared modules) under public names; a later ``import pythonfmu`` or ``import double_pendulum``
    in the host would find the FMU's copies there. Once an instance exists, everything it needs is
    loaded (the bundled code under private names), so both go: the folder from ``sys.path``, the
    modules loaded from it under public names from ``sys.modules``. Does nothing at build time.
    """
    if not PRIVATE_PREFIX:
        return
    folder = os.path.realpath(resources or RESOURCES)
    sys.path[:] = [entry for entry in sys.path if not entry or os.path.realpath(entry) != folder]
    for name, module in list(sys.modules.items()):
        origin = getattr(module, "__file__", None)
        if origin and not name.startswith(PRIVATE_MARK) and os.path.dirname(os.path.realpath(origin)) == folder:
            del sys.modules[name]


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
    """Print an error to stderr, unless the host collects the FMU's log itself.

    pythonfmu passes an exception's message to the host's logger only when logging is on; stderr
    makes it visible to a user with logging off too. A host that logs every message and reports the
    failures it expects (the project's own ``FmuRunner``) sets ``DOUBLE_PENDULUM_FMU_STDERR=0``
    while it runs the FMU.
    """
    if os.environ.get(STDERR_SWITCH, "1") != "0":
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
            self.log(f"doStep failed: {error}", self.error_status)
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
