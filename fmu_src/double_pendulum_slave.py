"""pythonfmu slave shared by the project's FMI 2 FMUs: maps FMI 2.0 co-simulation calls onto a component.

A component (``double_pendulum.component``) has ``set``/``set_input``/``get``, ``set_start_time``,
``initialise``, ``do_step``, ``get_state``/``set_state`` and an ``outputs`` mapping; the variables
come from its :class:`~double_pendulum.component.variables.FmuInterface`. Each FMU's own adapter
(``DoublePendulum.py``, ``Suspension.py``) only names its interface and component.

All physics, numerics and validation live in the ``double_pendulum`` package, whose runtime part
(model, solvers, component) the build bundles into the FMU's resources, with pythonfmu's Python part
and these adapters, all imported under private names (``slave_common.py``, shared with the FMI 3
FMU). The FMU's binary calls the slave through ``fmi_bridge.py``.
"""

from __future__ import annotations

import importlib

from .slave_common import (
    ComponentMapping,
    fmi_library,
    runtime_module,
    runtime_package,
)

package = runtime_package()
_pythonfmu = fmi_library("pythonfmu")
_slave = importlib.import_module(f"{_pythonfmu}.fmi2slave")
_variables = importlib.import_module(f"{_pythonfmu}.variables")
_enums = importlib.import_module(f"{_pythonfmu}.enums")
Fmi2Slave = _slave.Fmi2Slave
DefaultExperiment = importlib.import_module(f"{_pythonfmu}.default_experiment").DefaultExperiment
Fmi2Causality, Fmi2Variability, Fmi2Status = _enums.Fmi2Causality, _enums.Fmi2Variability, _enums.Fmi2Status
_FMI_TYPES = {name: getattr(_variables, name) for name in ("Real", "Integer", "Boolean", "String")}
Real = _FMI_TYPES["Real"]


class ComponentSlave(ComponentMapping, Fmi2Slave):
    """An FMU whose variables and behaviour are those of one co-simulation component.

    Subclasses set ``description``, ``default_experiment`` and ``interface`` (an ``FmuInterface``)
    and implement :meth:`make_component`.
    """

    version = package.__version__
    discard_status, warning_status = Fmi2Status.discard, Fmi2Status.warning

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._sim = self.new_component()
        for var in self.interface.variables():
            self._register(var)
        # the hot paths of fmi2SetReal and fmi2GetReal (see set_real, get_real)
        self._real_names = {vr: var.name for vr, var in self.vars.items() if isinstance(var, Real)}
        input_names = getattr(runtime_module("model.inputs"), "INPUT_NAMES", ())
        self._input_index = (
            {vr: input_names.index(name) for vr, name in self._real_names.items() if name in input_names}
            if hasattr(self._sim, "set_inputs_at") else {}
        )

    def set_real(self, vrs, values):
        """fmi2SetReal: inputs go straight to the component (one float check and a store each, as a
        master sets them before every step); anything else through pythonfmu and its setter."""
        index_of = self._input_index
        try:
            indices = [index_of[vr] for vr in vrs]
        except KeyError:  # not inputs only: one by one
            for vr, value in zip(vrs, values):
                if vr in index_of:
                    self._sim.set_inputs_at((index_of[vr],), (value,))
                else:
                    super().set_real([vr], [value])
            return
        self._sim.set_inputs_at(indices, values)

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
                setter=lambda value: self._sim.set(name, value),
            )
        elif var.causality == "input":
            variable = Real(
                name,
                causality=Fmi2Causality.input,
                variability=Fmi2Variability.continuous,
                description=var.description,
                getter=lambda: self._sim.get(name),
                setter=lambda value: self._sim.set_input(name, value),
            )
        else:  # an output (a port) or a local diagnostic, read by name
            variable = Real(
                name,
                causality=Fmi2Causality[var.causality],
                variability=Fmi2Variability.continuous,
                description=var.description,
                getter=lambda: self._output(name),
            )
        self.register_variable(variable)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._sim.set_start_time(start_time)

    def exit_initialization_mode(self):
        self._sim.initialise()

    # FMU state (fmi2Get/SetFMUstate, fmi2(De)SerializeFMUstate): the component's complete
    # state, including the integrator's hidden state, as JSON-serialisable data.
    def _get_fmu_state(self):
        return self._sim.get_state()

    def _set_fmu_state(self, state):
        """The loader hands back only states this FMU made, or deserialised after check_fmu_state."""
        self._sim.set_state(state, validate=False)

    def do_step(self, current_time, step_size):
        return self._component_step(current_time, step_size)
