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
