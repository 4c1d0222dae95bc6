r"""Non-conservative forces: air drag on bobs and rods, bearing friction torques.

Air drag on a bob (seed eq. 23): :math:`\vec F = -\tfrac12 \rho c_W A\,|\vec v|\,\vec v` with the
absolute velocity :math:`\vec v`; it dissipates the power :math:`\tfrac12 \rho c_W A |\vec v|^3`.

Air drag on a rod: each element ``ds`` of a rod of frontal width ``d`` feels
:math:`-\kappa |v_n| v_n \hat n\,ds` with :math:`\kappa = \tfrac12 \rho c_W d` and :math:`v_n` the
velocity normal to the rod, linear along it: :math:`v_n(s) = a + b s`, ``s`` the distance from the
link's upper joint. The plate covers ``s_lo <= s <= s_hi``: ``l/2 -+ L/2`` for a plate of length
``L`` centred between joints ``l`` apart (it overhangs both joints when ``L > l``). The
generalised forces need :math:`I_0 = \int |v_n| v_n\,ds` and :math:`I_1 = \int |v_n| v_n s\,ds`,
the power :math:`\kappa\int |v_n|^3 ds`, all over the plate. On each piece where :math:`v_n` keeps its sign the
integrands are polynomials of degree <= 3, so two-point Gauss-Legendre quadrature per piece is exact.

Bearing friction (seed eq. 24, :math:`F_R = c_R F_N`): the rolling friction force acts at the
bearing's friction radius, a torque of magnitude :math:`c_R r_b |\vec F_{joint}|` opposing the joint's
relative rotation. The sign function is regularised as :math:`\tanh(\omega/\omega_{reg})`: the torque
is smooth, but near rest it acts like a viscous damper of coefficient
:math:`c_R r_b |F|/\omega_{reg}`, which makes the equations stiff for small :math:`\omega_{reg}`
(time scale :math:`I\,\omega_{reg}/(c_R r_b |F|)` with ``I`` the rod's moment of inertia).

Bearing drag: a load-independent torque :math:`\tau_b \tanh(\omega/\omega_{reg})` (seals and
grease), opposing the joint's relative rotation like the friction above; it dissipates
:math:`\tau_b\,\omega \tanh(\omega/\omega_{reg}) \ge 0`.
"""

from __future__ import annotations

import math

_GAUSS = (0.5 - 0.5 / math.sqrt(3.0), 0.5 + 0.5 / math.sqrt(3.0))  # nodes on [0, 1], weights 1/2


def quadratic_drag(vx: float, vy: float, k: float) -> tuple[float, float, float]:
    """Return the drag force ``(Fx, Fy)`` [N] and dissipated power [W] for ``k = rho c_W A / 2`` [kg/m]."""
    speed = math.hypot(vx, vy)
    return -k * speed * vx, -k * speed * vy, k * speed * speed * speed


def rod_drag_integrals(a: float, b: float, s_lo: float, s_hi: float) -> tuple[float, float, float]:
    """Return ``(I0, I1, I3)`` for ``v_n(s) = a + b s`` on ``[s_lo, s_hi]`` [m].

    ``I0 = int |v_n| v_n ds`` [m^3/s^2], ``I1 = int |v_n| v_n s ds`` [m^4/s^2],
    ``I3 = int |v_n|^3 ds`` [m^4/s^3]; exact (piecewise two-point Gauss-Legendre).
    """
    pieces = [(s_lo, s_hi)]
    if b != 0.0:
        root = -a / b
        if s_lo < root < s_hi:
            pieces = [(s_lo, root), (root, s_hi)]
    i0 = i1 = i3 = 0.0
    for lo, hi in pieces:
        half = 0.5 * (hi - lo)
        for node in _GAUSS:
            s = lo + 2.0 * half * node
            v = a + b * s
            g = abs(v) * v
            i0 += half * g
            i1 += half * g * s
            i3 += half * abs(v) * v * v
    return i0, i1, i3


def bearing_torque(load: float, omega: float, c_r: float, r_b: float, omega_reg: float, b_v: float) -> float:
    """Return the friction torque [N m] of a joint, positive along ``omega`` (it opposes the motion).

    ``load`` [N] is the magnitude of the joint's reaction force, ``omega`` [rad/s] the joint's
    relative angular velocity: ``c_R r_b load tanh(omega / omega_reg) + b_v omega``.
    """
    return c_r * r_b * load * math.tanh(omega / omega_reg) + b_v * omega


def bearing_drag_torque(omega: float, tau_b: float, omega_reg: float) -> float:
    """Return the load-independent drag torque [N m] of a joint, positive along ``omega`` [rad/s].

    ``tau_b tanh(omega / omega_reg)``: the regularised sign function of :func:`bearing_torque`.
    """
    return tau_b * math.tanh(omega / omega_reg)
