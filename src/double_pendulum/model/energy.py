r"""Kinetic, potential and total energy of the double pendulum (bobs and rods).

.. math::

    T = \tfrac12 J_1 \dot\varphi_1^2 + \tfrac12 J_2 \dot\varphi_2^2
        + K \dot\varphi_1 \dot\varphi_2 \cos(\varphi_1-\varphi_2)

    V = g S_1 (1-\cos\varphi_1) + g S_2 (1-\cos\varphi_2)

with the coefficients of :mod:`double_pendulum.model.links`; for point masses on massless rods
:math:`J_1 = (m_1+m_2) l_1^2`, :math:`J_2 = m_2 l_2^2`, :math:`K = m_2 l_1 l_2`,
:math:`g S_1 = (m_1+m_2) g l_1`, :math:`g S_2 = m_2 g l_2` (seed eqs. 8/9, with the potential
shifted so that V = 0 with everything hanging at rest). Energies in J. ``sin``/``cos`` may be
NumPy's for arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from .links import LinkCoefficients, link_coefficients
from .parameters import PendulumParameters


def kinetic_energy(
    phi1: Any,
    phi2: Any,
    omega1: Any,
    omega2: Any,
    params: PendulumParameters,
    cos: Callable[[Any], Any] = math.cos,
) -> Any:
    """Return T [J] of both links (bobs and rods) about a pivot at rest."""
    c = link_coefficients(params)
    return 0.5 * c.j1 * omega1 * omega1 + 0.5 * c.j2 * omega2 * omega2 + c.k * omega1 * omega2 * cos(phi1 - phi2)


def potential_energy(
    phi1: Any, phi2: Any, params: PendulumParameters, cos: Callable[[Any], Any] = math.cos
) -> Any:
    """Return V [J] of bobs and rods, zero with everything hanging at rest below the pivot."""
    c = link_coefficients(params)
    return c.gs1 * (1.0 - cos(phi1)) + c.gs2 * (1.0 - cos(phi2))


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


def relative_momentum(
    phi1: float, phi2: float, omega1: float, omega2: float, c: LinkCoefficients
) -> tuple[float, float]:
    r"""Return the momentum [kg m/s] of bobs and rods relative to the pivot,
    :math:`\vec P = S_1 \dot\varphi_1 \vec n_1 + S_2 \dot\varphi_2 \vec n_2`,
    :math:`\vec n_i = (\cos\varphi_i, \sin\varphi_i)` (``c``: the link coefficients)."""
    px = c.s1 * omega1 * math.cos(phi1) + c.s2 * omega2 * math.cos(phi2)
    py = c.s1 * omega1 * math.sin(phi1) + c.s2 * omega2 * math.sin(phi2)
    return px, py


def pivot_motion_energy(px: float, py: float, vxs: float, vys: float, mass: float, plus: float = 0.0) -> float:
    r"""Return ``plus`` + the part of the kinetic energy [J] that the pivot's velocity :math:`\vec v_s` [m/s]
    adds, :math:`\tfrac12 M|\vec v_s|^2 + \vec v_s\cdot\vec P` (``(px, py)``: :func:`relative_momentum`,
    ``mass``: M, bobs and rods [kg]), added term by term to ``plus`` [J]."""
    return plus + 0.5 * mass * (vxs * vxs + vys * vys) + vxs * px + vys * py


def kinetic_energy_moving_pivot(
    phi1: float,
    phi2: float,
    omega1: float,
    omega2: float,
    vxs: float,
    vys: float,
    params: PendulumParameters,
) -> float:
    r"""Return the pendulum's kinetic energy [J] with absolute velocities when the pivot moves at (vxs, vys) [m/s].

    :math:`T = T_{rel} + \tfrac12 M|\vec v_s|^2
    + \vec v_s\cdot(S_1 \dot\varphi_1 \vec n_1 + S_2 \dot\varphi_2 \vec n_2)`,
    :math:`\vec n_i = (\cos\varphi_i, \sin\varphi_i)`, M the total mass (bobs and rods), the last
    two terms :func:`pivot_motion_energy`; exactly :func:`kinetic_energy` for a pivot at rest.
    """
    if vxs == 0.0 and vys == 0.0:
        return kinetic_energy(phi1, phi2, omega1, omega2, params)
    c = link_coefficients(params)
    px, py = relative_momentum(phi1, phi2, omega1, omega2, c)
    return pivot_motion_energy(px, py, vxs, vys, c.mass, plus=kinetic_energy(phi1, phi2, omega1, omega2, params))


def suspension_energy(
    xs: float, ys: float, vxs: float, vys: float, m_s: float, k_x: float, k_y: float
) -> float:
    r"""Return :math:`\tfrac12 M_s |\vec v_s|^2 + \tfrac12 k_x x_s^2 + \tfrac12 k_y y_s^2` [J].

    Kinetic energy of the suspension mass plus spring energy about the static equilibrium
    (the spring preload that carries all weights does no net work there).
    """
    return 0.5 * m_s * (vxs * vxs + vys * vys) + 0.5 * k_x * xs * xs + 0.5 * k_y * ys * ys
