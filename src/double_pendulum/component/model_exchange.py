r"""Model Exchange of the FMI 3 ``DoublePendulum`` FMU: its continuous states and their derivatives.

Runtime code (standard library only), bundled into the FMU; the adapter
``fmu_src/DoublePendulumFmi3.py`` maps pythonfmu3's calls onto it.

The host integrates :math:`\dot x = f(x, u)`; the FMU gives :math:`f` from the runtime's vector
field (:func:`double_pendulum.model.vector_field.build_vector_field`, the same function the
co-simulation integrates), nothing re-derived here.

**Continuous states** :data:`STATES`: every state any scene can have, in the order of
:func:`~double_pendulum.model.scene.state_layout`,

.. math::

    x = (\varphi_1, \varphi_2, \omega_1, \omega_2, x_s, \dot x_s, y_s, \dot y_s,
         W_{air}, W_{bearing}, W_{bearing\_drag}, W_{suspension}, W_{input})

[rad, rad, rad/s, rad/s, m, m/s, m, m/s, J, J, J, J, J]. Their number is fixed by the
modelDescription, while the scene (switches such as ``suspension`` or ``air_drag``) is a
parameter: a state the scene lacks keeps its start value 0 with derivative 0 (the suspension's
states when it is off, the work of a mechanism that is off, ``W_input`` while every input is 0).
The works are the integrated dissipated powers [W] the energy budget needs, so ``energy_residual``
measures the host's integration error.

**Smooth right-hand side, no event indicators.** The vector field is smooth in the states: the
sign of every friction torque is regularised, :math:`\tanh(\omega/\omega_{reg})` (bearing
friction and bearing drag, :mod:`double_pendulum.model.forces`), and quadratic air drag
:math:`|v|v` is continuously differentiable. So the FMU declares no event indicators and never
asks for an event; a host's error control sees the regularised torque like any other term (its
steepest slope, :math:`c_R r_b |F|/\omega_{reg}` [N m s/rad], is a viscous damper near rest).

**Inputs** are continuous inputs, used as set at the instant evaluated (no hold): the pivot's
acceleration and the torques drive the rates, its position and velocity enter kinematics, drag
and energies. A discontinuous input belongs in Event Mode (FMI 3.0): an input set twice at the
same time instant with different values has jumped there. The energy that a jump of the pivot's
(base's) position or velocity changes at once, :math:`E(x, u^+) - E(x, u^-)`, is booked into
``W_input`` at the next ``fmi3UpdateDiscreteStates``, which then reports
``valuesOfContinuousStatesChanged`` (as the co-simulation books it at a communication point).
"""

from __future__ import annotations

from typing import Any

from ..model import inputs as _inputs
from ..model import vector_field as _vector_field
from ..model.scene import every_state
from . import cosimulation as _cosimulation
from . import state_check as _state_check

InputHold, InputValues, INPUT_NAMES = _inputs.InputHold, _inputs.InputValues, _inputs.INPUT_NAMES
INPUT_ZEROS = _inputs.ZERO_INPUTS


STATES: tuple[str, ...] = every_state()
# The suspension's states are not the outputs xs, ys, vxs, vys: those report the prescribed pivot
# (an input) in a direction without a suspension state. These are the suspension mass's own.
LOCAL_STATES = {"xs": "suspension.x", "vxs": "suspension.vx", "ys": "suspension.y", "vys": "suspension.vy"}
DERIVATIVE_UNITS = {"rad": "rad/s", "rad/s": "rad/s2", "m": "m/s", "m/s": "m/s2", "J": "W"}  # unit / s


def state_variable(state: str) -> str:
    """The FMI variable that is continuous state ``state``: the output of that name, or a local."""
    return LOCAL_STATES.get(state, state)


class PendulumStates:
    """The continuous states of one initialised component, for a Model Exchange host.

    ``component`` is an initialised :class:`~double_pendulum.component.cosimulation.DoublePendulumCoSimulation`:
    its parameters, inputs (``component.inputs``, checked when set) and start state are used; its
    integrator is not.
    """

    def __init__(self, component: Any) -> None:
        self._component = component
        self.time = component.time
        self.initial_energy = component.initial_energy
        start = component.state_values()
        self.x = [float(start.get(name, 0.0)) for name in STATES]
        self.evaluations = 0  # derivative evaluations the host asked for
        self._scenes: dict[bool, tuple[Any, list[int]]] = {}
        self._hold = InputHold(0.0, INPUT_ZEROS)  # the inputs as set, read by the driven vector field
        self._field: Any = None  # the driven vector field (built once, on the hold)
        self._outputs = None
        self._derivatives: list[float] | None = None
        # Input jumps: the values set first at the current instant are its left limit.
        self._known = dict(component.inputs)
        self._instant, self._left, self._set_here = self.time, dict(self._known), set(INPUT_NAMES)

    # ------------------------------------------------------------------ the scene
    def _scene(self, driven: bool) -> tuple[Any, list[int]]:
        """The model without (with) inputs and where its states sit in :data:`STATES`."""
        if driven not in self._scenes:
            model = _vector_field.build_model(self._component.model_config(inputs=driven))
            self._scenes[driven] = (model, [STATES.index(name) for name in model.layout.names])
        return self._scenes[driven]

    def _inputs(self) -> Any:
        return InputValues(**self._component.inputs)

    def _y(self, slots: list[int]) -> list[float]:
        return [self.x[i] for i in slots]

    # ------------------------------------------------------------------ states and derivatives
    def set_states(self, values: list[float]) -> None:
        """Set the continuous states (``fmi3SetContinuousStates``), in the order of :data:`STATES`."""
        if len(values) != len(STATES):
            raise ValueError(f"expected {len(STATES)} continuous states ({', '.join(STATES)}), got {len(values)}")
        self.x = [float(v) for v in values]
        self._outputs = self._derivatives = None

    def set_time(self, time: float) -> None:
        """Set the time [s] (``fmi3SetTime``); the vector field does not depend on it."""
        self.time = float(time)

    def derivatives(self) -> list[float]:
        """:math:`\\dot x` [unit of the state / s] at the current states and inputs (13 values)."""
        if self._derivatives is None:
            driven = self._component.driven
            model, slots = self._scene(driven)
            y = self._y(slots)
            if driven:
                self._hold.reset(0.0, self._inputs())  # the inputs as set, at this instant: no hold
                if self._field is None:
                    self._field = _vector_field.build_vector_field(model.config, model.evaluate, self._hold)
                dy = self._field(0.0, y)
            else:
                dy = model.vector_field(self.time, y)
            dx = [0.0] * len(STATES)
            for slot, value in zip(slots, dy):
                dx[slot] = value
            self._derivatives = dx
            self.evaluations += 1
        return self._derivatives

    # ------------------------------------------------------------------ outputs
    def output(self, name: str) -> float:
        """Output ``name`` at the current states and inputs (as the co-simulation computes it)."""
        if name == "solver_rhs_evaluations":
            return float(self.evaluations)
        if name == "solver_steps":
            return 0.0  # the host's integrator takes the steps
        if self._outputs is None:
            driven = self._component.driven
            model, slots = self._scene(driven)
            self._outputs = _cosimulation.LazyOutputs(
                model, self._y(slots), self.initial_energy, {}, inputs=self._inputs() if driven else None
            )
        return self._outputs[name]

    # ------------------------------------------------------------------ inputs and events
    def note_input(self, name: str, value: float) -> None:
        """Record that input ``name`` was set to ``value`` (already checked) at the current time."""
        if self.time != self._instant:  # a new instant: what is set first here is the left limit
            self._instant, self._left, self._set_here = self.time, dict(self._known), set()
        if name not in self._set_here:
            self._left[name] = value
            self._set_here.add(name)
        self._known[name] = value
        self._outputs = self._derivatives = None

    def book_jump(self) -> bool:
        """Book the energy of the input jump at this instant into ``W_input``; True if a state changed.

        Called at ``fmi3UpdateDiscreteStates``: the inputs set first at this instant (left limit)
        against those set now (right limit), as the co-simulation books a jump
        (:meth:`~double_pendulum.component.cosimulation.DoublePendulumCoSimulation.with_jump_work`;
        an input that changed made the component driven, with this scene).
        """
        old, new = InputValues(**self._left), InputValues(**self._known)
        self._left = dict(self._known)
        if old == new:
            return False
        model, slots = self._scene(True)
        y = self._y(slots)
        booked = self._component.with_jump_work(y, old, new)
        if booked == y:
            return False
        for slot, value in zip(slots, booked):
            self.x[slot] = value
        self._outputs = self._derivatives = None
        return True

    # ------------------------------------------------------------------ FMU state
    def get_state(self) -> dict[str, Any]:
        """Everything above as JSON-serialisable data (the component's state is saved with it)."""
        return {"time": self.time, "x": list(self.x), "evaluations": self.evaluations, "known": dict(self._known),
                "instant": self._instant, "left": dict(self._left), "set_here": sorted(self._set_here)}

    @classmethod
    def check_state(cls, state: Any, *, path: str = "state") -> None:
        """Raise :class:`~double_pendulum.component.state_check.StateError` unless ``state`` is one
        :meth:`get_state` can return; build and change nothing.

        Checks the keys (none missing, none extra), the types and lengths of every entry, the inputs
        finite and the input names; the time and the continuous states, which the host sets, may be
        any float. Details: :func:`~double_pendulum.component.state_check.model_exchange_state`.
        The message names the entry by its path from ``path`` and shows its value.
        """
        _state_check.model_exchange_state(path, state)

    def set_state(self, state: dict[str, Any], *, validate: bool = True) -> None:
        """Restore :meth:`get_state`; :meth:`check_state` first (unless ``validate`` is False, for a state this
        process made and kept), so a state it refuses changes nothing."""
        if validate:
            self.check_state(state)
        self.time, self.x, self.evaluations = float(state["time"]), [float(v) for v in state["x"]], state["evaluations"]
        self._known, self._instant = dict(state["known"]), float(state["instant"])
        self._left, self._set_here = dict(state["left"]), set(state["set_here"])
        self._outputs = self._derivatives = None
