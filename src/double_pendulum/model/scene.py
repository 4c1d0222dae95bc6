"""A scene: which mechanisms are on, which states exist, and what the equations produce at a state.

:class:`ModelConfig` holds every parameter of a scene; :func:`state_layout` lists the states it
needs (``[phi1, phi2, omega1, omega2]``, then ``[xs, vxs]``, ``[ys, vys]`` for a suspended
direction, the dissipated works ``W_air``, ``W_bearing``, ``W_bearing_drag``, ``W_suspension`` [J]
of the enabled mechanisms and ``W_input`` [J] with inputs); :class:`Evaluation` is what the
evaluator (:mod:`.evaluator`) returns. The equations are in :mod:`.vector_field` and :mod:`.evaluator`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from .parameters import AirDragParameters, BearingParameters, PendulumParameters, SuspensionParameters


class ModelError(RuntimeError):
    """The model equations cannot be evaluated (e.g. the friction iteration does not converge)."""


@dataclass(frozen=True)
class ModelConfig:
    """All parameters of a scene: the pendulum and each (switchable) mechanism."""

    pendulum: PendulumParameters = field(default_factory=PendulumParameters)
    air: AirDragParameters = field(default_factory=AirDragParameters)
    bearing: BearingParameters = field(default_factory=BearingParameters)
    suspension: SuspensionParameters = field(default_factory=SuspensionParameters)
    inputs: bool = False  # pivot motion and joint torques enter as inputs (adds the W_input state)


@dataclass(frozen=True)
class StateLayout:
    """Which states exist and where they sit in the state vector."""

    names: tuple[str, ...]

    def index(self, name: str) -> int | None:
        """Position of state ``name``, or ``None`` if the scene does not have it."""
        return self.names.index(name) if name in self.names else None

    @property
    def size(self) -> int:
        return len(self.names)


def state_layout(config: ModelConfig) -> StateLayout:
    """Return the states needed by ``config`` (see the module docstring for the order)."""
    s = config.suspension
    names = ["phi1", "phi2", "omega1", "omega2"]
    if s.suspension and s.suspension_x:
        names += ["xs", "vxs"]
    if s.suspension and s.suspension_y:
        names += ["ys", "vys"]
    if config.air.air_drag:
        names.append("W_air")
    if config.bearing.bearing_friction:
        names.append("W_bearing")
    if config.bearing.bearing_drag:
        names.append("W_bearing_drag")
    if s.suspension:
        names.append("W_suspension")
    if config.inputs:
        names.append("W_input")
    return StateLayout(tuple(names))


def every_state() -> tuple[str, ...]:
    """Every state any scene can have: those of the scene with every mechanism and the inputs on, in order."""
    scene = ModelConfig(
        air=AirDragParameters(air_drag=True),
        bearing=BearingParameters(bearing_friction=True, bearing_drag=True),
        suspension=SuspensionParameters(suspension=True),
        inputs=True,
    )
    return state_layout(scene).names


class Evaluation(NamedTuple):
    """Everything the equations produce at one state (units: SI)."""

    dydt: list[float]
    alpha1: float  # rad/s^2
    alpha2: float  # rad/s^2
    axs: float  # m/s^2
    ays: float  # m/s^2
    f_pivot_x: float  # N, force the pendulum exerts on its pivot (with the static weight)
    f_pivot_y: float  # N
    p_air: float  # W
    p_bearing: float  # W
    p_suspension: float  # W, dissipated in the suspension dampers
    p_bearing_drag: float = 0.0  # W, dissipated by the load-independent bearing drag torques
    p_input: float = 0.0  # W, power fed in through the inputs


def has_mechanism(config: ModelConfig) -> bool:
    """True if air drag, a bearing term or the suspension is on."""
    return (
        config.air.air_drag
        or config.bearing.bearing_friction
        or config.bearing.bearing_drag
        or config.suspension.suspension
    )


def is_core(config: ModelConfig) -> bool:
    """True if every mechanism is off: the scene is the frictionless fixed-pivot pendulum."""
    return not (has_mechanism(config) or config.inputs)


def is_driven_core(config: ModelConfig) -> bool:
    """True if the scene has inputs and no mechanism: the frictionless pendulum on a driven pivot."""
    return config.inputs and not has_mechanism(config)
