r"""The model's inputs: motion of the pivot (or of the suspension's base) and two joint torques.

Inputs (all start at 0; with every input 0 the model is exactly the one without inputs):

* ``pivot_x, pivot_y`` [m], ``pivot_vx, pivot_vy`` [m/s], ``pivot_ax, pivot_ay`` [m/s2]: the motion
  of the point the pendulum hangs from. In a direction without a suspension state (``suspension``
  off, or that direction of the suspension switched off) it *is* the pivot's motion: the angles are
  driven by the acceleration (a fictitious force :math:`-m_i \vec a_p` on each bob), positions and
  velocities (bob positions ``x1..y2``, air drag, kinetic energy) use the position and velocity. In
  a direction with a suspension state it is the motion of the suspension's base (ground excitation):
  the spring and damper act on :math:`x_s - x_b` and :math:`\dot x_s - v_b`; the base acceleration
  does not enter (the base's inertia is the host's business).
* ``tau1`` [N.m]: torque on the upper rod at the pivot (a motor between support and rod 1), acting
  on :math:`\omega_1`; ``tau2`` [N.m]: torque of the upper rod on the lower rod at the elbow, acting
  on :math:`\omega_2 - \omega_1` (its reaction acts on rod 1). Generalised forces:
  :math:`Q_1 \mathrel{+}= \tau_1 - \tau_2`, :math:`Q_2 \mathrel{+}= \tau_2`.

**Second-order hold.** FMI 2.0 co-simulation holds inputs between communication points. This
model holds the pivot motion as the quadratic through the values set for the step starting at
:math:`t_0` (:class:`InputHold`):

.. math::

    x(t_0+\tau) = x + v\tau + \tfrac12 a\tau^2,\qquad v(t_0+\tau) = v + a\tau,\qquad
    a(t_0+\tau) = a,\qquad \tau_{1,2}(t_0+\tau) = \tau_{1,2}.

A host that sends consistent values (``v`` the derivative of ``x``, ``a`` of ``v``) gets a motion
continuous in position and velocity. **Inconsistent values are used as given**, each for what it
drives: the angles see ``a``, drag, energies and bob positions see ``x`` and ``v``; at each
communication point the hold restarts from the values then set (so a host that sets only
``pivot_ay`` gets the right angles for that acceleration, with the pivot position held at
``pivot_y`` + the quadratic from each step's start).

**Work.** ``W_input`` [J] integrates the power of the inputs into the system: the torques'
:math:`\tau_1\omega_1 + \tau_2(\omega_2-\omega_1)`, plus, per direction, the pivot force on the
pendulum about its static value (the weight share :math:`(m_1+m_2) g` lifts the whole pendulum,
which :math:`E_{pot}`, measured relative to the pivot, does not count either), or for a suspended
direction the dynamic spring-damper force :math:`-k(x_s-x_b)-c(\dot x_s-v_b)` times the base
velocity. Then ``energy_residual = E_total(t) + W_air + W_bearing + W_suspension - W_input - E_total(0)``
still measures only the integration error.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

from .quantities import Quantity

INPUTS: tuple[Quantity, ...] = (
    Quantity(
        "pivot_x",
        "m",
        "horizontal position of the pivot (suspension on: of its base)"
        "; without suspension it moves the angles only with pivot_input = position",
    ),
    Quantity(
        "pivot_y",
        "m",
        "vertical position of the pivot (suspension on: of its base), up positive"
        "; without suspension it moves the angles only with pivot_input = position",
    ),
    Quantity(
        "pivot_vx",
        "m/s",
        "horizontal velocity of the pivot (suspension on: of its base)"
        "; ignored with pivot_input = position",
    ),
    Quantity(
        "pivot_vy",
        "m/s",
        "vertical velocity of the pivot (suspension on: of its base)"
        "; ignored with pivot_input = position",
    ),
    Quantity(
        "pivot_ax",
        "m/s2",
        "horizontal acceleration of the pivot (drives the angles)"
        "; ignored with pivot_input = position",
    ),
    Quantity(
        "pivot_ay",
        "m/s2",
        "vertical acceleration of the pivot (drives the angles)"
        "; ignored with pivot_input = position",
    ),
    Quantity("tau1", "N.m", "torque on the upper rod at the pivot (motor), along omega1"),
    Quantity("tau2", "N.m", "torque of the upper rod on the lower rod at the elbow, along omega2 - omega1"),
)
INPUT_NAMES: tuple[str, ...] = tuple(q.name for q in INPUTS)
INPUT_UNITS: dict[str, str] = {q.name: q.unit for q in INPUTS}


class InputValues(NamedTuple):
    """The inputs at one instant (SI units, see :data:`INPUTS`)."""

    pivot_x: float = 0.0
    pivot_y: float = 0.0
    pivot_vx: float = 0.0
    pivot_vy: float = 0.0
    pivot_ax: float = 0.0
    pivot_ay: float = 0.0
    tau1: float = 0.0
    tau2: float = 0.0

    def is_zero(self) -> bool:
        """True if every input is exactly 0."""
        return not any(self)


ZERO_INPUTS = InputValues()
# Values that agree to this relative tolerance are the same hold (rounding of the host's own
# extrapolation), so a consistent quadratic keeps the integrator running across the step.
HOLD_MATCH_RTOL = 1e-13


def _same(a: float, b: float) -> bool:
    return a == b or abs(a - b) <= HOLD_MATCH_RTOL * max(abs(a), abs(b))


class InputHold:
    """The second-order hold of the current communication step: the input values set at ``t0`` [s].

    One object per driven component, **reset in place** at each communication point where the
    inputs jump (:meth:`reset`): the vector fields built on it read its values on every call, so
    an input change gives them a new right-hand side without building anything.
    ``u`` holds the eight values in :data:`INPUT_NAMES` order.
    """

    __slots__ = ("t0", "u")

    def __init__(self, t0: float, values: Sequence[float]) -> None:
        self.t0 = float(t0)
        self.u = [float(v) for v in values]

    @property
    def values(self) -> InputValues:
        """The values set at ``t0``."""
        return InputValues(*self.u)

    def reset(self, t0: float, values: Sequence[float]) -> None:
        """Start a new hold at ``t0`` [s] with ``values`` (eight floats in :data:`INPUT_NAMES` order)."""
        self.t0 = t0
        self.u[:] = values

    def held(self, t: float) -> Sequence[float]:
        """The eight held values at time ``t`` [s] (quadratic position, linear velocity)."""
        u = self.u
        x, y, vx, vy, ax, ay, tau1, tau2 = u
        tau = t - self.t0
        if tau == 0.0 or not (vx or vy or ax or ay):
            return u
        return (
            x + tau * (vx + 0.5 * tau * ax),
            y + tau * (vy + 0.5 * tau * ay),
            vx + tau * ax,
            vy + tau * ay,
            ax,
            ay,
            tau1,
            tau2,
        )

    def at(self, t: float) -> InputValues:
        """Return the held inputs at time ``t`` [s] (quadratic position, linear velocity)."""
        return InputValues(*self.held(t))

    def velocity_at(self, t: float) -> tuple[float, float]:
        """Return the held pivot velocity ``(vx, vy)`` [m/s] at time ``t`` [s], as in :meth:`at`."""
        u = self.u
        tau = t - self.t0
        if tau == 0.0:
            return u[2], u[3]
        return u[2] + tau * u[4], u[3] + tau * u[5]

    def continued_by(self, t0: float, values: Sequence[float]) -> bool:
        """True if ``values`` set at ``t0`` describe this same hold (no discontinuity at ``t0``).

        Then the integrator may go on with this hold; otherwise the right-hand side jumps at
        ``t0`` and the integration must restart there.
        """
        return all(map(_same, self.held(t0), values))
