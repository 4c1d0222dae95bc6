r"""The suspension on its own: a mass on springs and dampers to the ground, loaded by a force.

This is the ``Suspension`` FMU's model: the part of the pendulum-on-suspension system that carries
the pivot, split off so that the two can be coupled across an FMU boundary. Parameters ``M_s``,
``k_x``, ``k_y``, ``c_x``, ``c_y`` as in
:class:`~double_pendulum.model.parameters.SuspensionParameters`; input: the force
:math:`\vec F = (F_x, F_y)` [N] of the load on the mass.

Coordinates :math:`x, y` [m] are displacements from the static equilibrium under the static load
:math:`(0, F_{static,y})` (:class:`~double_pendulum.model.parameters.SuspensionLoad`; the spring
preload carries it and the mass's own weight). Newton:

.. math::

    M_s \ddot x = F_x - k_x x - c_x \dot x,\qquad
    M_s \ddot y = (F_y - F_{static,y}) - k_y y - c_y \dot y.

These are the suspension rows of the monolithic model (:mod:`double_pendulum.model.vector_field`)
with the pivot force left as an input: there, Newton on the suspension mass reads
:math:`F_{pivot} + (m_1+m_2) g \hat y = M_s \vec a_s + k \vec s + c \vec v_s`. So coupling
``DoublePendulum.F_pivot_x/y -> Suspension.F_x/F_y`` and ``Suspension.x, y, vx, vy, ax, ay ->
DoublePendulum.pivot_*`` (with the pendulum's ``suspension`` off and ``F_static_y = -(m1+m2) g``)
is the monolith's physics.

Energy: ``E_suspension`` (:func:`~double_pendulum.model.energy.suspension_energy`, about the
equilibrium), the power of the load about its static value
:math:`P_{in} = F_x \dot x + (F_y - F_{static,y}) \dot y`, the damper power
:math:`c_x \dot x^2 + c_y \dot y^2`; ``W_in`` and ``W_suspension`` integrate them, so
``energy_residual = E_suspension + W_suspension - W_in - E_suspension(0)`` is integration error.

State vector: ``[x, vx, y, vy, W_suspension, W_in]``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

from .energy import suspension_energy
from .parameters import SuspensionLoad, SuspensionParameters
from .quantities import Quantity

STATE_NAMES = ("x", "vx", "y", "vy", "W_suspension", "W_in")
PARAMETER_NAMES = ("M_s", "k_x", "k_y", "c_x", "c_y")  # taken from SuspensionParameters

INPUTS: tuple[Quantity, ...] = (
    Quantity("F_x", "N", "horizontal force of the load on the suspension mass"),
    Quantity("F_y", "N", "vertical force of the load on the suspension mass (F_static_y at rest)"),
)
OUTPUTS: tuple[Quantity, ...] = (
    Quantity("x", "m", "horizontal displacement of the mass from its static equilibrium"),
    Quantity("y", "m", "vertical displacement of the mass from its static equilibrium (up positive)"),
    Quantity("vx", "m/s", "horizontal velocity of the mass"),
    Quantity("vy", "m/s", "vertical velocity of the mass"),
    Quantity("ax", "m/s2", "horizontal acceleration of the mass"),
    Quantity("ay", "m/s2", "vertical acceleration of the mass"),
    Quantity("E_suspension", "J", "kinetic energy of the mass plus spring energy about the equilibrium"),
    Quantity("W_suspension", "J", "work dissipated in the dampers since the start"),
    Quantity("P_in", "W", "power of the load about its static value: F_x vx + (F_y - F_static_y) vy"),
    Quantity("W_in", "J", "work of the load about its static value since the start"),
    Quantity("energy_residual", "J", "E_suspension(t) + W_suspension - W_in - E_suspension(0)"),
)
OUTPUT_NAMES: tuple[str, ...] = tuple(q.name for q in OUTPUTS)
# The FMU's outputs (ports): the motion the pendulum's pivot inputs take; the energies, works and the
# power are local variables, recorded by name (as DoublePendulum's, double_pendulum.model.outputs).
PORT_NAMES: tuple[str, ...] = ("x", "y", "vx", "vy", "ax", "ay")
# Direct dependence on the inputs (FMI ModelStructure/Outputs): the acceleration and the power
# follow the force at once; positions, velocities, energies and works are states.
INPUT_DEPENDENCIES: dict[str, tuple[str, ...]] = {
    **{name: () for name in OUTPUT_NAMES},
    "ax": ("F_x",),
    "ay": ("F_y",),
    "P_in": ("F_x", "F_y"),
}


class SuspensionModel(NamedTuple):
    """The suspension's parameters and static load."""

    params: SuspensionParameters
    load: SuspensionLoad

    def accelerations(self, y: list[float], f_x: float, f_y: float) -> tuple[float, float]:
        """Return ``(ax, ay)`` [m/s2] of the mass in state ``y`` under the load ``(f_x, f_y)`` [N]."""
        p = self.params
        x, vx, yy, vy = y[0], y[1], y[2], y[3]
        ax = (f_x - p.k_x * x - p.c_x * vx) / p.M_s
        ay = (f_y - self.load.F_static_y - p.k_y * yy - p.c_y * vy) / p.M_s
        return ax, ay

    def powers(self, y: list[float], f_x: float, f_y: float) -> tuple[float, float]:
        """Return ``(P_damper, P_in)`` [W]: dissipated in the dampers, fed in by the load."""
        p, vx, vy = self.params, y[1], y[3]
        return p.c_x * vx * vx + p.c_y * vy * vy, f_x * vx + (f_y - self.load.F_static_y) * vy

    def vector_field(self, f_x: float, f_y: float) -> Callable[[float, list[float]], list[float]]:
        """Return ``f(t, y) -> dy/dt`` with the load held at ``(f_x, f_y)`` [N]."""
        accel, powers = self.accelerations, self.powers

        def vector_field(t: float, y: list[float]) -> list[float]:
            ax, ay = accel(y, f_x, f_y)
            p_damp, p_in = powers(y, f_x, f_y)
            return [y[1], ax, y[3], ay, p_damp, p_in]

        return vector_field

    def outputs(self, y: list[float], f_x: float, f_y: float, initial_energy: float | None = None) -> dict[str, float]:
        """All outputs at state ``y`` under the load ``(f_x, f_y)``; ``initial_energy`` None: this is the start."""
        p = self.params
        x, vx, yy, vy, w_susp, w_in = y
        ax, ay = self.accelerations(y, f_x, f_y)
        energy = suspension_energy(x, yy, vx, vy, p.M_s, p.k_x, p.k_y)
        e0 = energy if initial_energy is None else initial_energy
        return {
            "x": x, "y": yy, "vx": vx, "vy": vy, "ax": ax, "ay": ay,
            "E_suspension": energy, "W_suspension": w_susp,
            "P_in": self.powers(y, f_x, f_y)[1], "W_in": w_in,
            "energy_residual": energy + w_susp - w_in - e0,
        }  # fmt: skip
