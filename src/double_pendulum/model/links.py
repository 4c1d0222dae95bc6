r"""Mass distribution of the two links: bobs and uniform rods, reduced to a few coefficients.

Each link is a point mass (bob) at its lower joint plus, optionally, a uniform rod (the acrylic
plate) of mass :math:`m_{r,i}` and length :math:`L_i`, centred between the link's two joints:
centre of mass at :math:`l_i/2` from the upper joint, moment of inertia :math:`m_{r,i} L_i^2/12`
about its centre (the plate's width is neglected; it would add :math:`m_{r,i} w^2/12`). A plate
longer than :math:`l_i` overhangs both joints by :math:`(L_i - l_i)/2`. ``L_rod = 0`` (the
default) stands for :math:`L_i = l_i`, a plate from joint to joint (:func:`plate_lengths`).

With :math:`\vec e_i = (\sin\varphi_i, -\cos\varphi_i)` along link ``i`` and the pivot at
:math:`\vec s`, the bodies sit at

* bob 1: :math:`\vec s + l_1 \vec e_1`; bob 2: :math:`\vec s + l_1 \vec e_1 + l_2 \vec e_2`;
* rod 1: :math:`\vec s + r \vec e_1`; rod 2: :math:`\vec s + l_1 \vec e_1 + r \vec e_2`,
  :math:`r \in [l_i/2 - L_i/2,\ l_i/2 + L_i/2]`, with :math:`\langle r\rangle = l_i/2`,
  :math:`\langle r^2\rangle = l_i^2/4 + L_i^2/12`.

Summing :math:`\tfrac12 \int |\dot{\vec r}|^2 dm` and :math:`g \int y\,dm` over the bodies gives
(:math:`\Delta = \varphi_1 - \varphi_2`, :math:`\vec n_i = \partial\vec e_i/\partial\varphi_i
= (\cos\varphi_i, \sin\varphi_i)`):

.. math::

    T = \tfrac12 J_1 \dot\varphi_1^2 + \tfrac12 J_2 \dot\varphi_2^2
        + K \dot\varphi_1 \dot\varphi_2 \cos\Delta
        + \tfrac12 M |\dot{\vec s}|^2
        + \dot{\vec s}\cdot(S_1 \dot\varphi_1 \vec n_1 + S_2 \dot\varphi_2 \vec n_2)

    V = g S_1 (1 - \cos\varphi_1) + g S_2 (1 - \cos\varphi_2)
        \quad\text{(relative to the pivot, zero hanging at rest)}

    J_1 = (m_1 + m_2 + m_{r2}) l_1^2 + m_{r1} (L_1^2/12 + l_1^2/4),\qquad
    J_2 = m_2 l_2^2 + m_{r2} (L_2^2/12 + l_2^2/4)

    K = (m_2 + m_{r2}/2)\, l_1 l_2,\quad
    S_1 = (m_1 + m_2 + m_{r2} + m_{r1}/2)\, l_1,\quad
    S_2 = (m_2 + m_{r2}/2)\, l_2,\quad
    M = m_1 + m_2 + m_{r1} + m_{r2}

Units: :math:`J_i, K` in kg m^2, :math:`S_i` in kg m, :math:`M` in kg. With massless rods they are
the point-mass coefficients :math:`J_1 = (m_1+m_2) l_1^2`, :math:`J_2 = m_2 l_2^2`,
:math:`K = m_2 l_1 l_2`, :math:`S_1 = (m_1+m_2) l_1`, :math:`S_2 = m_2 l_2` (seed eqs. 8/9).

Bit-identity with the point-mass model: every coefficient is evaluated in the same order of
floating-point operations as the point-mass expressions it replaces, with the rod terms added
last. A zero rod mass adds exactly ``0.0``, so ``m_rod1 = m_rod2 = 0`` reproduces the point-mass
arithmetic bit for bit (``tests/test_rigid_links.py`` checks it against results recorded before
the rods existed).
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

from .parameters import PendulumParameters


class LinkCoefficients(NamedTuple):
    """Inertia and first moments of the two links (see the module docstring for the formulas)."""

    j1: float  # kg m^2, J1: moment of inertia of everything on link 1 about the pivot (link 2 as a point)
    j2: float  # kg m^2, J2: moment of inertia of link 2 about the elbow
    k: float  # kg m^2, K: coupling coefficient of the two links
    s1: float  # kg m, S1: first moment of everything hanging from the pivot, along link 1
    s2: float  # kg m, S2: first moment of link 2 about the elbow
    gs1: float  # N m, g S1 (evaluated as (M1 g) l1, the point-mass order of operations)
    gs2: float  # N m, g S2
    mass: float  # kg, M: total mass of the pendulum
    mass2: float  # kg, mass of link 2 (bob 2 and rod 2): what the elbow carries


def plate_lengths(p: PendulumParameters) -> tuple[float, float]:
    """Return the plate lengths ``(L1, L2)`` [m] of the two links.

    ``L_rod = 0`` (the default) means a plate spanning joint to joint, ``L = l``: the rod of the
    point-mass model, whose drag acts between the joints only. Used alike for the rods' inertia
    (:func:`link_coefficients`) and their air drag (:mod:`double_pendulum.model.vector_field`).
    """
    return (p.L_rod1 if p.L_rod1 > 0.0 else p.l1, p.L_rod2 if p.L_rod2 > 0.0 else p.l2)


@lru_cache(maxsize=128)
def link_coefficients(p: PendulumParameters) -> LinkCoefficients:
    """Return the :class:`LinkCoefficients` of ``p`` (bobs, and rods of mass ``m_rod1, m_rod2``).

    Cached by the (frozen, hashable) parameters: the energy functions call it at every output.
    """
    m1, m2, l1, l2, g = p.m1, p.m2, p.l1, p.l2, p.g
    mr1, mr2 = p.m_rod1, p.m_rod2
    big_l1, big_l2 = plate_lengths(p)
    # second moments <r^2> of the rods about their upper joints
    r2_1 = big_l1 * big_l1 / 12.0 + l1 * l1 / 4.0
    r2_2 = big_l2 * big_l2 / 12.0 + l2 * l2 / 4.0
    m_j1 = m1 + m2 + mr2  # masses at distance l1 from the pivot
    m_s1 = m_j1 + 0.5 * mr1  # first-moment mass of link 1
    m_2 = m2 + 0.5 * mr2  # first-moment mass of link 2
    return LinkCoefficients(
        j1=m_j1 * l1 * l1 + mr1 * r2_1,
        j2=m2 * l2 * l2 + mr2 * r2_2,
        k=m_2 * l1 * l2,
        s1=m_s1 * l1,
        s2=m_2 * l2,
        gs1=m_s1 * g * l1,
        gs2=m_2 * g * l2,
        mass=m1 + m2 + mr1 + mr2,
        mass2=m2 + mr2,
    )
