r"""Equations of motion of the planar double pendulum with a fixed pivot.

Generalised coordinates: the rod angles :math:`\varphi_1, \varphi_2` from the downward vertical.
With :math:`\Delta = \varphi_1 - \varphi_2`, the Lagrangian
:math:`L = T - V` (see :mod:`double_pendulum.model.energy`) gives (seed eqs. 14/15, re-derived; the
seed's eqs. 12 and 13 have their left-hand sides swapped and its eq. 21 is
:math:`\ddot\varphi_2`, not :math:`\ddot\varphi_1`):

.. math::

    (m_1+m_2) l_1^2 \ddot\varphi_1 + m_2 l_1 l_2 \cos\Delta\,\ddot\varphi_2
        = -m_2 l_1 l_2 \dot\varphi_2^2 \sin\Delta - (m_1+m_2) g l_1 \sin\varphi_1 + Q_1

    m_2 l_1 l_2 \cos\Delta\,\ddot\varphi_1 + m_2 l_2^2 \ddot\varphi_2
        = m_2 l_1 l_2 \dot\varphi_1^2 \sin\Delta - m_2 g l_2 \sin\varphi_2 + Q_2

:math:`Q_1, Q_2` [N m] are generalised non-conservative forces (zero for the frictionless core).
The mass matrix has determinant :math:`m_2 l_1^2 l_2^2 (m_1 + m_2 \sin^2\Delta) > 0`, so the
2x2 system is solved in closed form (Cramer's rule).

The functions take ``sin``/``cos`` as arguments so the same formula serves Python floats
(``math``, fastest for one trajectory) and NumPy arrays (``numpy``, a whole ensemble at once).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from .parameters import PendulumParameters


def angular_accelerations(
    phi1: Any,
    phi2: Any,
    omega1: Any,
    omega2: Any,
    m1: float,
    m2: float,
    l1: float,
    l2: float,
    g: float,
    q1: Any = 0.0,
    q2: Any = 0.0,
    sin: Callable[[Any], Any] = math.sin,
    cos: Callable[[Any], Any] = math.cos,
) -> tuple[Any, Any]:
    r"""Return :math:`(\ddot\varphi_1, \ddot\varphi_2)` [rad/s^2] from the equations above.

    Arguments are angles [rad], angular velocities [rad/s], masses [kg], lengths [m],
    gravity [m/s^2] and the generalised forces ``q1, q2`` [N m].
    """
    delta = phi1 - phi2
    s_d = sin(delta)
    c_d = cos(delta)
    m12 = m1 + m2
    # Mass matrix [[a11, a12], [a12, a22]] and right-hand side (b1, b2).
    a11 = m12 * l1 * l1
    a12 = m2 * l1 * l2 * c_d
    a22 = m2 * l2 * l2
    b1 = -m2 * l1 * l2 * omega2 * omega2 * s_d - m12 * g * l1 * sin(phi1) + q1
    b2 = m2 * l1 * l2 * omega1 * omega1 * s_d - m2 * g * l2 * sin(phi2) + q2
    det = a11 * a22 - a12 * a12
    return (b1 * a22 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det


def fixed_pivot_vector_field(params: PendulumParameters) -> Callable[[float, list[float]], list[float]]:
    """Return ``f(t, y) -> dy/dt`` for ``y = [phi1, phi2, omega1, omega2]`` (frictionless).

    Units: y in (rad, rad, rad/s, rad/s), dy/dt in (rad/s, rad/s, rad/s^2, rad/s^2).
    The parameters are bound once so each call does no attribute look-ups.
    """
    m1, m2, l1, l2, g = params.m1, params.m2, params.l1, params.l2, params.g
    accel = angular_accelerations

    def vector_field(t: float, y: list[float]) -> list[float]:
        phi1, phi2, omega1, omega2 = y
        alpha1, alpha2 = accel(phi1, phi2, omega1, omega2, m1, m2, l1, l2, g)
        return [omega1, omega2, alpha1, alpha2]

    return vector_field


def linearised_normal_modes(
    params: PendulumParameters,
) -> tuple[tuple[float, float], tuple[tuple[float, float], tuple[float, float]]]:
    r"""Angular frequencies [rad/s] and mode shapes of the small-angle motion.

    Linearising about the hanging rest state gives :math:`M_0\ddot q + K q = 0` with
    :math:`M_0 = [[(m_1+m_2) l_1^2, m_2 l_1 l_2], [m_2 l_1 l_2, m_2 l_2^2]]` and
    :math:`K = \mathrm{diag}((m_1+m_2) g l_1, m_2 g l_2)`. The squared frequencies solve
    :math:`\det(K - \omega^2 M_0) = 0`, a quadratic in :math:`\omega^2`. Returns
    ``((omega_slow, omega_fast), (shape_slow, shape_fast))`` with each shape
    ``(1, phi2/phi1)``.
    """
    m1, m2, l1, l2, g = params.m1, params.m2, params.l1, params.l2, params.g
    m12 = m1 + m2
    a, b, c = m12 * l1 * l1, m2 * l1 * l2, m2 * l2 * l2
    k1, k2 = m12 * g * l1, m2 * g * l2
    # det([[k1 - w a, -w b], [-w b, k2 - w c]]) = (a c - b^2) w^2 - (k1 c + k2 a) w + k1 k2
    qa = a * c - b * b
    qb = -(k1 * c + k2 * a)
    qc = k1 * k2
    root = math.sqrt(qb * qb - 4.0 * qa * qc)
    # Numerically stable quadratic roots.
    w_big = (-qb + root) / (2.0 * qa)
    w_small = qc / (qa * w_big)
    omegas = (math.sqrt(w_small), math.sqrt(w_big))
    shapes = tuple((1.0, (k1 - w * a) / (w * b)) for w in (w_small, w_big))
    return omegas, shapes  # type: ignore[return-value]
