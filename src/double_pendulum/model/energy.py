r"""Kinetic, potential and total energy of the double pendulum.

.. math::

    T = \tfrac12 (m_1+m_2) l_1^2 \dot\varphi_1^2 + \tfrac12 m_2 l_2^2 \dot\varphi_2^2
        + m_2 l_1 l_2 \dot\varphi_1 \dot\varphi_2 \cos(\varphi_1-\varphi_2)

    V = (m_1+m_2) g l_1 (1-\cos\varphi_1) + m_2 g l_2 (1-\cos\varphi_2)

(seed eqs. 8/9, with the potential shifted so that V = 0 with both bobs hanging at rest).
Energies in J. ``sin``/``cos`` may be NumPy's for arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from .parameters import PendulumParameters


def kinetic_energy(
    phi1: Any,
    phi2: Any,
    omega1: Any,
    omega2: Any,
    params: PendulumParameters,
    cos: Callable[[Any], Any] = math.cos,
) -> Any:
    """Return T [J] of both bobs."""
    m1, m2, l1, l2 = params.m1, params.m2, params.l1, params.l2
    return (
        0.5 * (m1 + m2) * l1 * l1 * omega1 * omega1
        + 0.5 * m2 * l2 * l2 * omega2 * omega2
        + m2 * l1 * l2 * omega1 * omega2 * cos(phi1 - phi2)
    )


def potential_energy(
    phi1: Any, phi2: Any, params: PendulumParameters, cos: Callable[[Any], Any] = math.cos
) -> Any:
    """Return V [J], zero with both bobs hanging at rest below the pivot."""
    m1, m2, l1, l2, g = params.m1, params.m2, params.l1, params.l2, params.g
    return (m1 + m2) * g * l1 * (1.0 - cos(phi1)) + m2 * g * l2 * (1.0 - cos(phi2))


def total_energy(
    phi1: Any,
    phi2: Any,
    omega1: Any,
    omega2: Any,
    params: PendulumParameters,
    cos: Callable[[Any], Any] = math.cos,
) -> Any:
    """Return T + V [J]."""
    return kinetic_energy(phi1, phi2, omega1, omega2, params, cos) + potential_energy(phi1, phi2, params, cos)


def kinetic_energy_moving_pivot(
    phi1: float,
    phi2: float,
    omega1: float,
    omega2: float,
    vxs: float,
    vys: float,
    params: PendulumParameters,
) -> float:
    r"""Return the bobs' kinetic energy [J] with absolute velocities when the pivot moves at (vxs, vys) [m/s].

    :math:`T = T_{rel} + \tfrac12 (m_1+m_2)|\vec v_s|^2
    + \vec v_s\cdot(m_1 \vec v_{1,rel} + m_2 \vec v_{2,rel})`,
    which is exactly :func:`kinetic_energy` for a pivot at rest.
    """
    m1, m2, l1, l2 = params.m1, params.m2, params.l1, params.l2
    if vxs == 0.0 and vys == 0.0:
        return kinetic_energy(phi1, phi2, omega1, omega2, params)
    # momentum of the bobs relative to the pivot
    px = (m1 + m2) * l1 * omega1 * math.cos(phi1) + m2 * l2 * omega2 * math.cos(phi2)
    py = (m1 + m2) * l1 * omega1 * math.sin(phi1) + m2 * l2 * omega2 * math.sin(phi2)
    return (
        kinetic_energy(phi1, phi2, omega1, omega2, params)
        + 0.5 * (m1 + m2) * (vxs * vxs + vys * vys)
        + vxs * px
        + vys * py
    )


def suspension_energy(
    xs: float, ys: float, vxs: float, vys: float, m_s: float, k_x: float, k_y: float
) -> float:
    r"""Return :math:`\tfrac12 M_s |\vec v_s|^2 + \tfrac12 k_x x_s^2 + \tfrac12 k_y y_s^2` [J].

    Kinetic energy of the suspension mass plus spring energy about the static equilibrium
    (the spring preload that carries all weights does no net work there).
    """
    return 0.5 * m_s * (vxs * vxs + vys * vys) + 0.5 * k_x * xs * xs + 0.5 * k_y * ys * ys
