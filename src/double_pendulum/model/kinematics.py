r"""Positions and velocities of the two bobs from the generalised coordinates.

With the pivot at the origin, x to the right and y up (seed eqs. 4-7):

.. math::

    x_1 = l_1 \sin\varphi_1,\quad y_1 = -l_1 \cos\varphi_1,\qquad
    x_2 = x_1 + l_2 \sin\varphi_2,\quad y_2 = y_1 - l_2 \cos\varphi_2

    \dot x_1 = l_1 \dot\varphi_1 \cos\varphi_1,\quad \dot y_1 = l_1 \dot\varphi_1 \sin\varphi_1,
    \qquad \dot x_2 = \dot x_1 + l_2 \dot\varphi_2 \cos\varphi_2,\quad
    \dot y_2 = \dot y_1 + l_2 \dot\varphi_2 \sin\varphi_2

Positions in m, velocities in m/s. ``sin``/``cos`` may be NumPy's for arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any


def positions(
    phi1: Any,
    phi2: Any,
    l1: float,
    l2: float,
    sin: Callable[[Any], Any] = math.sin,
    cos: Callable[[Any], Any] = math.cos,
) -> tuple[Any, Any, Any, Any]:
    """Return ``(x1, y1, x2, y2)`` [m] of the bobs relative to the pivot."""
    x1 = l1 * sin(phi1)
    y1 = -l1 * cos(phi1)
    return x1, y1, x1 + l2 * sin(phi2), y1 - l2 * cos(phi2)


def velocities(
    phi1: Any,
    phi2: Any,
    omega1: Any,
    omega2: Any,
    l1: float,
    l2: float,
    sin: Callable[[Any], Any] = math.sin,
    cos: Callable[[Any], Any] = math.cos,
) -> tuple[Any, Any, Any, Any]:
    """Return ``(vx1, vy1, vx2, vy2)`` [m/s] of the bobs relative to the pivot."""
    vx1 = l1 * omega1 * cos(phi1)
    vy1 = l1 * omega1 * sin(phi1)
    return vx1, vy1, vx1 + l2 * omega2 * cos(phi2), vy1 + l2 * omega2 * sin(phi2)
