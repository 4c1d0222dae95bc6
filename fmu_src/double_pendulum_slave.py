"""pythonfmu slave shared by the project's FMUs: maps FMI 2.0 co-simulation calls onto a component.

A component (``double_pendulum.component``) has ``set``/``set_input``/``get``, ``set_start_time``,
``initialise``, ``do_step``, ``get_state``/``set_state`` and an ``outputs`` mapping; the variables
come from its :class:`~double_pendulum.component.variables.FmuInterface`. Each FMU's own adapter
(``DoublePendulum.py``, ``Suspension.py``) only names its interface and component.

All physics, numerics and validation live in the ``double_pendulum`` package, whose runtime part
(model, solvers, component) the build bundles into the FMU's resources next to this file, with
pythonfmu's Python part. In a built FMU (``resources/bundle.json`` present) both are imported
under private names (``_dp_fmu_<id>``, ``_dp_fmu_<id>_pythonfmu``, the id a hash of the bundled
code), so the FMU always runs its own code, whatever ``double_pendulum`` or ``pythonfmu`` the host
process has imported, and a Python host is left as it was found: once an instance exists, the
FMU's folder is taken off ``sys.path`` and its public modules out of ``sys.modules``
(:meth:`ComponentSlave._leave_host_as_found`). At build time (no ``bundle.json``) the installed
``pythonfmu`` and ``double_pendulum`` are used, as pythonfmu's builder needs its own ``Fmi2Slave``.
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


def _private_prefix() -> str | None:
    """``_dp_fmu_<id>`` in a built FMU, None at build time."""
    try:
        return "_dp_fmu_" + json.loads((RESOURCES / BUNDLE_FILE).read_text())["id"]
    except FileNotFoundError:
        return None


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


PRIVATE_PREFIX = _private_prefix()
if PRIVATE_PREFIX:
    # pythonfmu's __init__ would also import its builder (argparse, inspect, xml.dom): only the slave side
    _pythonfmu = _import_private(f"{PRIVATE_PREFIX}_pythonfmu", RESOURCES / "pythonfmu", run_init=False).__name__
    package = _import_private(PRIVATE_PREFIX, RESOURCES / "double_pendulum")
else:
    _pythonfmu = "pythonfmu"
    package = importlib.import_module("double_pendulum")

_slave = importlib.import_module(f"{_pythonfmu}.fmi2slave")
_variables = importlib.import_module(f"{_pythonfmu}.variables")
_enums = importlib.import_module(f"{_pythonfmu}.enums")
Fmi2Slave = _slave.Fmi2Slave
DefaultExperiment = importlib.import_module(f"{_pythonfmu}.default_experiment").DefaultExperiment
Fmi2Causality, Fmi2Variability, Fmi2Status = _enums.Fmi2Causality, _enums.Fmi2Variability, _enums.Fmi2Status
_FMI_TYPES = {name: getattr(_variables, name) for name in ("Real", "Boolean", "String")}
Real = _FMI_TYPES["Real"]


def _compensate_pythonfmu_release(*objects) -> None:
    """Add one reference count to each object, without keeping a reference.

    When a Python exception reaches pythonfmu's C++ layer (<= 0.7.0), its ``handle_py_exception``
    calls ``cleanPyObject``, which releases the slave's references (class, instance, log queue)
    while the C++ object still holds and later releases them again. In our test runs a few dozen
    failed calls then left the host to crash in the garbage collector (segfault, about 2 runs in 3).
    Balancing the release of the instance's log queue removed the crash in every repeated run
    (balancing the class or the instance alone did not). The cost is one small list kept alive per
    failed call.
    """
    import ctypes

    for obj in objects:
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(obj))


def runtime_module(name: str):
    """Import ``double_pendulum.<name>`` from the package this FMU runs (bundled or installed)."""
    return importlib.import_module(f"{package.__name__}.{name}")


class ComponentSlave(Fmi2Slave):
    """An FMU whose variables and behaviour are those of one co-simulation component.

    Subclasses set ``description``, ``default_experiment`` and ``interface`` (an ``FmuInterface``)
    and implement :meth:`make_component`.
    """

    author = "double-pendulum-fmu contributors"
    license = "MIT"
    version = package.__version__
    interface = None

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._sim = self.make_component()
        for var in self.interface.variables():
            self._register(var)
        # the hot paths of fmi2SetReal and fmi2GetReal (see set_real, get_real)
        self._real_names = {vr: var.name for vr, var in self.vars.items() if isinstance(var, Real)}
        input_names = getattr(runtime_module("model.inputs"), "INPUT_NAMES", ())
        self._input_index = (
            {vr: input_names.index(name) for vr, name in self._real_names.items() if name in input_names}
            if hasattr(self._sim, "set_inputs_at") else {}
        )
        if PRIVATE_PREFIX:
            self._leave_host_as_found()

    def _leave_host_as_found(self) -> None:
        """Undo what pythonfmu's binary did to the host's interpreter to load this FMU.

        It put the FMU's resources folder first on ``sys.path`` and imported the adapter (and through
        it this module) under public names; a later ``import pythonfmu`` or ``import double_pendulum``
        in the host would find the FMU's copies there. Everything the instance needs is loaded by now
        (the bundled code under private names), so both go: the folder from ``sys.path``, the modules
        loaded from it under public names from ``sys.modules``.
        """
        folder = os.path.realpath(self.resources or RESOURCES)
        sys.path[:] = [entry for entry in sys.path if not entry or os.path.realpath(entry) != folder]
        for name, module in list(sys.modules.items()):
            origin = getattr(module, "__file__", None)
            if origin and not name.startswith("_dp_fmu_") and os.path.dirname(os.path.realpath(origin)) == folder:
                del sys.modules[name]

    def make_component(self):
        raise NotImplementedError

    def set_real(self, vrs, values):
        """fmi2SetReal: inputs go straight to the component (one float check and a store each, as a
        master sets them before every step); anything else through pythonfmu and its setter."""
        index_of = self._input_index
        try:
            indices = [index_of[vr] for vr in vrs]
        except KeyError:  # not inputs only: one by one
            for vr, value in zip(vrs, values):
                if vr in index_of:
                    self._guarded(self._sim.set_inputs_at, (index_of[vr],), (value,))
                else:
                    super().set_real([vr], [value])
            return
        self._guarded(self._sim.set_inputs_at, indices, values)

    def get_real(self, vrs):
        """fmi2GetReal: after initialisation straight from the component (outputs computed when read)."""
        sim = self._sim
        if not sim.initialised:
            return super().get_real(vrs)  # the outputs of the values set so far (_output)
        try:
            return list(map(sim.get, map(self._real_names.__getitem__, vrs)))
        except KeyError:  # not a Real: pythonfmu's message
            return super().get_real(vrs)

    def _register(self, var) -> None:
        name = var.name
        if var.causality == "parameter":
            variable = _FMI_TYPES[var.fmi_type](
                name,
                causality=Fmi2Causality.parameter,
                variability=Fmi2Variability.fixed,
                description=var.description,
                getter=lambda: self._sim.get(name),
                setter=lambda value: self._guarded(self._sim.set, name, value),
            )
        elif var.causality == "input":
            variable = Real(
                name,
                causality=Fmi2Causality.input,
                variability=Fmi2Variability.continuous,
                description=var.description,
                getter=lambda: self._sim.get(name),
                setter=lambda value: self._guarded(self._sim.set_input, name, value),
            )
        else:
            variable = Real(
                name,
                causality=Fmi2Causality.output,
                variability=Fmi2Variability.continuous,
                description=var.description,
                getter=lambda: self._output(name),
            )
        self.register_variable(variable)

    def _output(self, name: str) -> float:
        """Output ``name``; before fmi2ExitInitializationMode from the parameters and inputs set so far.

        FMI 2.0 lets a master read outputs in Initialization Mode (libcosim and fmpy's container
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

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._guarded(self._sim.set_start_time, start_time)

    def _guarded(self, call, *args):
        """Run ``call``; on error also print the message to stderr, then re-raise.

        pythonfmu turns the exception into fmi2Fatal and passes its message to the host's logger
        only when logging is on; stderr makes it visible to a user with logging off too.
        """
        try:
            return call(*args)
        except Exception as error:
            self._fail(error)

    def _fail(self, error: Exception):
        """Report ``error`` (:meth:`_report`), balance pythonfmu's release, re-raise it."""
        self._report(error)
        _compensate_pythonfmu_release(self.log_queue)
        raise error

    def _report(self, error) -> None:
        """Print the error to stderr, unless the host collects the FMU's log itself.

        A host that logs every message and reports the failures it expects (the project's own
        ``FmuRunner``) sets ``DOUBLE_PENDULUM_FMU_STDERR=0`` while it runs the FMU.
        """
        if os.environ.get(STDERR_SWITCH, "1") != "0":
            print(f"[{self.instance_name}] {self.interface.model_identifier}: {error}", file=sys.stderr, flush=True)

    def exit_initialization_mode(self):
        self._guarded(self._sim.initialise)

    # FMU state (fmi2Get/SetFMUstate, fmi2(De)SerializeFMUstate): the component's complete
    # state, including the integrator's hidden state, as JSON-serialisable data.
    def _get_fmu_state(self):
        return self._sim.get_state()

    def _set_fmu_state(self, state):
        self._guarded(self._sim.set_state, state)

    def do_step(self, current_time, step_size):
        sim = self._sim
        try:
            sim.do_step(current_time, step_size)
        except Exception as error:  # any failure is a discarded step, never an exception into pythonfmu
            self.log(f"doStep failed: {error}", Fmi2Status.error)
            self._report(error)
            return False
        if sim.notices:
            self._warn(sim.notices)
        return True

    def _warn(self, notices: list) -> None:
        """Pass the component's warnings to the host's log (fmi2Warning) and stderr, once each."""
        for notice in notices:
            self.log(notice, Fmi2Status.warning)
            self._report(notice)
        notices.clear()
