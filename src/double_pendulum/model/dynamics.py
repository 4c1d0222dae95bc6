r"""Equations of motion of the planar double pendulum with a fixed pivot.

Generalised coordinates: the rod angles :math:`\varphi_1, \varphi_2` from the downward vertical.
With :math:`\Delta = \varphi_1 - \varphi_2`, the Lagrangian
:math:`L = T - V` (see :mod:`double_pendulum.model.energy` and, for the coefficients
:math:`J_1, J_2, K, S_1, S_2` of bobs and rods, :mod:`double_pendulum.model.links`) gives

.. math::

    J_1 \ddot\varphi_1 + K \cos\Delta\,\ddot\varphi_2
        = -K \dot\varphi_2^2 \sin\Delta - g S_1 \sin\varphi_1 + Q_1

    K \cos\Delta\,\ddot\varphi_1 + J_2 \ddot\varphi_2
        = K \dot\varphi_1^2 \sin\Delta - g S_2 \sin\varphi_2 + Q_2

For point masses on massless rods (:math:`J_1 = (m_1+m_2) l_1^2`, :math:`J_2 = m_2 l_2^2`,
:math:`K = m_2 l_1 l_2`, :math:`S_1 = (m_1+m_2) l_1`, :math:`S_2 = m_2 l_2`) these are the seed's
eqs. 14/15, re-derived; the seed's eqs. 12 and 13 have their left-hand sides swapped and its
eq. 21 is :math:`\ddot\varphi_2`, not :math:`\ddot\varphi_1`.

:math:`Q_1, Q_2` [N m] are generalised non-conservative forces (zero for the frictionless core).
The mass matrix has determinant :math:`J_1 J_2 - K^2\cos^2\Delta \ge J_1 J_2 - K^2 > 0` (for point
masses :math:`m_2 l_1^2 l_2^2 (m_1 + m_2 \sin^2\Delta)`; with rods :math:`J_1 J_2 > K^2` by the
Cauchy-Schwarz inequality and :math:`m_1 > 0`), so the 2x2 system is solved in closed form
(Cramer's rule).

The functions take ``sin``/``cos`` as arguments so the same formula serves Python floats
(``math``, fastest for one trajectory) and NumPy arrays (``numpy``, a whole ensemble at once).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from ..codegen import compile_function
from .links import link_coefficients
from .parameters import PendulumParameters

LINK_ACCELERATIONS = """
delta = phi1 - phi2
s_d = sin(delta)
c_d = cos(delta)
a12 = k * c_d
b1 = -k * omega2 * omega2 * s_d - gs1 * sin(phi1) + q1
b2 = k * omega1 * omega1 * s_d - gs2 * sin(phi2) + q2
det = j1 * j2 - a12 * a12
alpha1 = (b1 * j2 - a12 * b2) / det
alpha2 = (j1 * b2 - a12 * b1) / det
"""
"""The equations above solved for :math:`(\\ddot\\varphi_1, \\ddot\\varphi_2)` = ``(alpha1, alpha2)``
[rad/s^2] by Cramer's rule, as a snippet (:mod:`double_pendulum.codegen`): from ``phi1, phi2``
[rad], ``omega1, omega2`` [rad/s], ``q1, q2`` [N m] and the coefficients ``j1, j2, k`` [kg m^2],
``gs1, gs2`` [N m]. The one copy of these equations: :func:`link_accelerations` and the fast
vector fields are compiled from it."""

link_accelerations: Callable[..., tuple[Any, Any]] = compile_function(
    "link_accelerations",
    "phi1, phi2, omega1, omega2, j1, j2, k, gs1, gs2, q1, q2, sin, cos",
    [LINK_ACCELERATIONS],
    "alpha1, alpha2",
    {},
    defaults=(0.0, 0.0, math.sin, math.cos),
    doc=r"""Return :math:`(\ddot\varphi_1, \ddot\varphi_2)` [rad/s^2] from the equations above.

    Arguments are angles [rad], angular velocities [rad/s], the coefficients :math:`J_1, J_2, K`
    [kg m^2] and :math:`g S_1, g S_2` [N m] (:class:`~double_pendulum.model.links.LinkCoefficients`),
    the generalised forces ``q1, q2`` [N m] (default 0) and ``sin``/``cos`` (default ``math``'s)
    (:data:`LINK_ACCELERATIONS`).
    """,
)


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
    r"""Return :math:`(\ddot\varphi_1, \ddot\varphi_2)` [rad/s^2] for point masses on massless rods.

    Arguments are angles [rad], angular velocities [rad/s], masses [kg], lengths [m],
    gravity [m/s^2] and the generalised forces ``q1, q2`` [N m]; :func:`link_accelerations` with
    the point-mass coefficients.
    """
    m12 = m1 + m2
    return link_accelerations(
        phi1, phi2, omega1, omega2, m12 * l1 * l1, m2 * l2 * l2, m2 * l1 * l2, m12 * g * l1, m2 * g * l2,
        q1, q2, sin, cos,
    )  # fmt: skip


def fixed_pivot_vector_field(params: PendulumParameters) -> Callable[[float, list[float]], list[float]]:
    """Return ``f(t, y) -> dy/dt`` for ``y = [phi1, phi2, omega1, omega2]`` (frictionless).

    Units: y in (rad, rad, rad/s, rad/s), dy/dt in (rad/s, rad/s, rad/s^2, rad/s^2).
    Straight-line code from :data:`LINK_ACCELERATIONS` with the coefficients (bobs and rods) bound
    once, so each call is one frame of float arithmetic.
    """
    c = link_coefficients(params)
    constants = {"j1": c.j1, "j2": c.j2, "k": c.k, "gs1": c.gs1, "gs2": c.gs2, "q1": 0.0, "q2": 0.0,
                 "sin": math.sin, "cos": math.cos}  # fmt: skip
    return compile_function(
        "fixed_pivot_vector_field", "t, y", ["phi1, phi2, omega1, omega2 = y", LINK_ACCELERATIONS],
        "[omega1, omega2, alpha1, alpha2]", constants,
    )  # fmt: skip


def linearised_normal_modes(
    params: PendulumParameters,
) -> tuple[tuple[float, float], tuple[tuple[float, float], tuple[float, float]]]:
    r"""Angular frequencies [rad/s] and mode shapes of the small-angle motion.

    Linearising about the hanging rest state gives :math:`M_0\ddot q + K q = 0` with
    :math:`M_0 = [[J_1, K_{12}], [K_{12}, J_2]]` and :math:`K = \mathrm{diag}(g S_1, g S_2)`
    (:math:`K_{12}` the coupling coefficient of :mod:`double_pendulum.model.links`; for point masses
    :math:`M_0 = [[(m_1+m_2) l_1^2, m_2 l_1 l_2], [m_2 l_1 l_2, m_2 l_2^2]]`,
    :math:`K = \mathrm{diag}((m_1+m_2) g l_1, m_2 g l_2)`). The squared frequencies solve
    :math:`\det(K - \omega^2 M_0) = 0`, a quadratic in :math:`\omega^2`. Returns
    ``((omega_slow, omega_fast), (shape_slow, shape_fast))`` with each shape
    ``(1, phi2/phi1)``.
    """
    co = link_coefficients(params)
    a, b, c = co.j1, co.k, co.j2
    k1, k2 = co.gs1, co.gs2
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
