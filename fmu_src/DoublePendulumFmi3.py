"""pythonfmu3 adapter of the FMI 3.0 ``DoublePendulum.fmu``: Model Exchange and Co-Simulation from one class.

Parameters, inputs and outputs are those of the FMI 2 FMU (same names, descriptions and start
values, from :data:`double_pendulum.component.variables.INTERFACES`), with ``time`` (the
independent variable) and, for Model Exchange, the continuous states and their derivatives
``der(<state>)`` (:mod:`double_pendulum.component.model_exchange`).

* **Co-Simulation**: the component
  :class:`double_pendulum.component.cosimulation.DoublePendulumCoSimulation` does every doStep,
  exactly as in the FMI 2 FMU (same integrator, same numbers).
* **Model Exchange**: the host integrates the states; the FMU gives their derivatives from the
  runtime's vector field, no event indicators (:mod:`double_pendulum.component.model_exchange`).

The same class serves either interface; the Model Exchange functions (``fmi3SetTime`` after
initialisation, ``fmi3SetContinuousStates``, ``fmi3UpdateDiscreteStates``) switch the outputs over
to the host's states. In Initialization Mode the continuous states and their derivatives are those
of the start values set so far, as FMI 3.0 lets a host read them there. The FMU's binary
(``fmu_src/loader/fmi3_guard.c``) calls it through ``fmi_bridge.py``.
"""

from __future__ import annotations

import importlib
from types import SimpleNamespace

from .slave_common import ComponentMapping, fmi_library, runtime_module, runtime_package

_exchange = runtime_module("component.model_exchange")
DERIVATIVE_UNITS, LOCAL_STATES, STATES = _exchange.DERIVATIVE_UNITS, _exchange.LOCAL_STATES, _exchange.STATES
PendulumStates, state_variable = _exchange.PendulumStates, _exchange.state_variable

_library = fmi_library("pythonfmu3")
_variables = importlib.import_module(f"{_library}.variables")
_enums = importlib.import_module(f"{_library}.enums")
Fmi3SlaveBase = importlib.import_module(f"{_library}.fmi3slave").Fmi3SlaveBase
ModelExchange = importlib.import_module(f"{_library}.modelexchange").ModelExchange
CoSimulation = importlib.import_module(f"{_library}.cosimulation").CoSimulation
DefaultExperiment = importlib.import_module(f"{_library}.default_experiment").DefaultExperiment
Causality, Variability = _enums.Fmi3Causality, _enums.Fmi3Variability
Initial, Status = _enums.Fmi3Initial, _enums.Fmi3Status
Float64 = _variables.Float64
_TYPES = {"Real": Float64, "Integer": _variables.Int32, "Boolean": _variables.Boolean, "String": _variables.String}

_cosimulation = runtime_module("component.cosimulation")
_names = runtime_module("component.variables")
_interface = _names.INTERFACES[_names.MODEL_IDENTIFIER]
_UNITS = {v.name: v.unit for v in _interface.variables() if v.fmi_type == "Real" and v.unit not in ("", "1")}


class DoublePendulum(ComponentMapping, Fmi3SlaveBase, ModelExchange, CoSimulation):
    """The double pendulum behind FMI 3.0 Model Exchange and Co-Simulation."""

    interface = _interface
    discard_status, warning_status = Status.discard, Status.warning

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        # pythonfmu3 reads these from the instance (its __init__ has just set them to None)
        self.author, self.license = ComponentMapping.author, ComponentMapping.license
        self.version = runtime_package().__version__
        self.description = _names.MODEL_DESCRIPTION_FMI3
        # the tolerance of a Model Exchange host: the co-simulation's own default rtol
        rtol = _cosimulation.default_parameter_values()["rtol"]
        self.default_experiment = DefaultExperiment(**_interface.default_experiment, tolerance=rtol)
        self._sim = self.new_component()
        self._states: PendulumStates | None = None  # from fmi3ExitInitializationMode on
        self._model_exchange_used = False
        self.register_variable(Float64("time", causality=Causality.independent, variability=Variability.continuous,
                                       description="simulation time [s]", unit="s", getter=lambda: self.time))
        for variable in _interface.variables():
            self._register(variable)
        self._register_states()

    def make_component(self):
        return _cosimulation.DoublePendulumCoSimulation()

    def _register(self, var) -> None:
        name = var.name
        unit = {"unit": _UNITS[name]} if name in _UNITS else {}
        if var.causality == "parameter":
            variable = _TYPES[var.fmi_type](
                name, causality=Causality.parameter, variability=Variability.fixed, description=var.description,
                getter=lambda: self._sim.get(name), setter=lambda value: self._sim.set(name, value),
                **unit)
        elif var.causality == "input":
            variable = Float64(
                name, causality=Causality.input, variability=Variability.continuous, description=var.description,
                getter=lambda: self._sim.get(name), setter=lambda value: self._set_input(name, value), **unit)
        else:  # an output (a port) or a local diagnostic, read by name
            variable = Float64(
                name, causality=Causality[var.causality], variability=Variability.continuous,
                initial=Initial.calculated, description=var.description, getter=lambda: self._output(name), **unit)
        self.register_variable(variable)

    def _register_states(self) -> None:
        """The continuous states (outputs, or the suspension's locals) and their derivatives ``der(<state>)``."""
        references = {}
        for k, state in enumerate(STATES):
            if state in LOCAL_STATES:
                self.register_variable(Float64(
                    LOCAL_STATES[state], causality=Causality.local, variability=Variability.continuous,
                    initial=Initial.calculated, unit=_UNITS[state], getter=lambda k=k: self._view().x[k],
                    description=f"continuous state {state} of the suspension mass (stays 0 where it does not move) "
                    f"[{_UNITS[state]}]"))
            references[state] = next(v.value_reference for v in self.vars.values() if v.name == state_variable(state))
        for k, state in enumerate(STATES):
            unit = DERIVATIVE_UNITS[_UNITS[state]]
            self.register_variable(Float64(
                f"der({state_variable(state)})", causality=Causality.local, variability=Variability.continuous,
                initial=Initial.calculated, derivative=references[state], unit=unit,
                description=f"time derivative of {state_variable(state)} [{unit}]",
                getter=lambda k=k: self._view().derivatives()[k]))

    # ------------------------------------------------------------------ both interfaces
    @property
    def time(self) -> float:
        """The current time [s]: the host's under Model Exchange, the last communication point otherwise."""
        return self._states.time if self._model_exchange_used else self._sim.time

    def setup_experiment(self, start_time: float) -> None:
        """The start time of fmi3EnterInitializationMode."""
        self._sim.set_start_time(start_time)

    def set_time(self, time: float) -> None:
        """fmi3SetTime (Model Exchange, after initialisation)."""
        self._model_exchange().set_time(time)

    def _set_input(self, name: str, value: float) -> None:
        self._sim.set_input(name, value)
        if self._states is not None:
            self._states.note_input(name, float(value))

    def _output(self, name: str) -> float:
        if self._model_exchange_used:
            return self._states.output(name)
        return super()._output(name)

    def exit_initialization_mode(self):
        self._sim.initialise()
        self._states = PendulumStates(self._sim)

    def _view(self) -> PendulumStates:
        """The states of the instance (Model Exchange), or a view of the component (before, or under CS)."""
        if self._model_exchange_used:
            return self._states
        return PendulumStates(self._sim if self._sim.initialised else self._preview())

    # ------------------------------------------------------------------ Co-Simulation
    def do_step(self, current_time: float, step_size: float) -> bool:
        return self._component_step(current_time, step_size)

    # ------------------------------------------------------------------ Model Exchange
    def _model_exchange(self) -> PendulumStates:
        if self._states is None:
            raise RuntimeError("a Model Exchange function was called before fmi3ExitInitializationMode")
        self._model_exchange_used = True
        return self._states

    def get_number_of_continuous_states(self) -> int:
        return len(STATES)

    def _states_to_read(self) -> PendulumStates:
        """The states a host reads: its own under Model Exchange; in Initialization Mode those of the start
        values set so far (FMI 3.0 lets a host read states and derivatives there)."""
        return self._model_exchange() if self._states is not None else self._view()

    def get_continuous_states(self) -> list[float]:
        return list(self._states_to_read().x)

    def set_continuous_states(self, values: list[float]) -> None:
        self._model_exchange().set_states(values)

    def get_continuous_state_derivatives(self) -> list[float]:
        return list(self._states_to_read().derivatives())

    def get_event_indicators(self) -> list[float]:
        return []  # a smooth right-hand side (double_pendulum.component.model_exchange)

    def update_discrete_states(self) -> SimpleNamespace:
        """Event Mode: book an input jump's energy into W_input; there are no discrete states.

        The attribute names are those pythonfmu3's C++ layer reads (its own result class spells two
        of them otherwise, so they were never written; the loader also initialises them).
        """
        changed = self._model_exchange().book_jump()
        return SimpleNamespace(discreteStatesNeedUpdate=False, terminateSimulation=False,
                               nominalContinuousStatesChanged=False, valuesOfContinuousStatesChanged=changed,
                               nextEventTimeDefined=False, nextEventTime=0.0)

    # ------------------------------------------------------------------ FMU state
    def _get_fmu_state(self):
        """The component's complete state, and under Model Exchange the host's states, as JSON data."""
        return {"component": self._sim.get_state(), "model_exchange_used": self._model_exchange_used,
                "states": self._states.get_state() if self._states is not None else None}

    def _set_fmu_state(self, state):
        """The loader hands back only states this FMU made, or deserialised after :meth:`check_fmu_state`."""
        self._sim.set_state(state["component"], validate=False)
        self._states = PendulumStates(self._sim) if state["states"] is not None else None
        if self._states is not None:
            self._states.set_state(state["states"], validate=False)
        self._model_exchange_used = bool(state["model_exchange_used"])

    def fmu_state_time(self, state) -> float:
        """The component's time [s] in a checked ``state`` (the time the loader's state header must hold)."""
        return state["component"]["time"]

    def check_fmu_state(self, state) -> None:
        """Raise (naming what is wrong) unless ``state`` is one :meth:`_get_fmu_state` gives."""
        if not isinstance(state, dict) or set(state) != {"component", "model_exchange_used", "states"}:
            raise ValueError("an FMU state of the FMI 3 FMU is a dict of component, model_exchange_used and states, "
                             f"not {_cut(state)}")
        if not isinstance(state["model_exchange_used"], bool):
            raise ValueError(f'state["model_exchange_used"] = {_cut(state["model_exchange_used"])} is not a bool')
        type(self._sim).check_state(state["component"], path='state["component"]')
        if state["states"] is not None:
            PendulumStates.check_state(state["states"], path='state["states"]')


def _cut(value, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."
