"""The component's settings, as FMU parameters: its integrator and accuracy, and how it reads its inputs.

They live with the component, not the model: the model is the physics, the component decides
how to integrate it (see :mod:`double_pendulum.solvers`) and how the host's input samples become
the model's inputs.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..model.parameters import ParameterError, Validated, spec
from ..solvers.registry import check_solver_name


@dataclass(frozen=True)
class SolverSettings(Validated):
    """Choice of integrator and its accuracy settings (see :mod:`double_pendulum.solvers`)."""

    solver: str = spec(
        "dop853", "", "integration method: dop853, dopri5, rodas4 (stiff), gauss4, gauss2, rk4 or euler", rule="str"
    )
    rtol: float = spec(1e-9, "1", "relative tolerance of the adaptive solvers", rule="positive")
    atol: float = spec(1e-12, "1", "absolute tolerance of the adaptive solvers (rad, rad/s)", rule="positive")
    fixed_step: float = spec(
        1e-3, "s", "step size of the fixed-step solvers (gauss4, gauss2, rk4, euler)", rule="positive"
    )
    max_steps: int = spec(
        1_000_000, "1", "most integrator steps within one doStep before it fails (bounds the CPU time)", rule="count"
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        check_solver_name(self.solver)


PIVOT_INPUT_MODES: tuple[str, ...] = ("acceleration", "position")


@dataclass(frozen=True)
class InputSettings(Validated):
    """How the pivot inputs drive the pendulum (see :mod:`double_pendulum.component.pivot_motion`)."""

    pivot_input: str = spec(
        "acceleration",
        "",
        "how the pivot inputs drive the pendulum: acceleration (pivot_ax, pivot_ay drive the angles; send "
        "position, velocity and acceleration) or position (velocity and acceleration derived from the "
        "pivot_x, pivot_y samples: a parabola through the last three, one step of lag in the acceleration)",
        rule="str",
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.pivot_input not in PIVOT_INPUT_MODES:
            raise ParameterError(
                f"invalid pivot_input = {self.pivot_input!r}: must be one of {', '.join(PIVOT_INPUT_MODES)}"
            )
