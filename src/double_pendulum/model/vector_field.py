r"""The assembled model: its equations, the vector field of a scene, its energies.

A scene switches mechanisms on or off (:class:`~.scene.ModelConfig`, with its states in
:mod:`.scene`); the general evaluator of the equations below is :mod:`.evaluator`'s, built from
named parts; :func:`build_model` then builds a
state vector with only the states the scene needs and a vector field with only the enabled terms.
With every mechanism off the vector field *is* the frictionless core
(:func:`double_pendulum.model.dynamics.fixed_pivot_vector_field`), so results are bit-identical.

State vector: ``[phi1, phi2, omega1, omega2]``, then ``[xs, vxs]`` if the suspension moves
horizontally, ``[ys, vys]`` if it moves vertically, then the dissipated work ``W_air``,
``W_bearing``, ``W_bearing_drag``, ``W_suspension`` [J] of each enabled mechanism (integrated
powers, so the energy budget closes to the integration tolerance).

The links carry bobs and, optionally, uniform rods; their mass distribution enters only through
the coefficients :math:`J_1, J_2, K, S_1, S_2` and the total mass :math:`M = m_1 + m_2 + m_{r1} +
m_{r2}` of :mod:`double_pendulum.model.links`. Equations with the suspension (pivot displaced by
``(xs, ys)`` from its static equilibrium, :math:`M_t = M_s + M`), from the Lagrangian with the
pivot coordinates added (:math:`T = \tfrac12 M_s |\dot{\vec s}|^2 + T_{pendulum}` with the
pendulum's kinetic energy at absolute velocities, see
:func:`double_pendulum.model.energy.kinetic_energy_moving_pivot`; :math:`V` = pendulum potential
relative to the pivot + :math:`\tfrac12 k_x x_s^2 + \tfrac12 k_y y_s^2`):

.. math::

    \begin{pmatrix} M_{11} & M_{12} & A_{1x} & A_{1y}\\ M_{12} & M_{22} & A_{2x} & A_{2y}\\
    A_{1x} & A_{2x} & M_t & 0\\ A_{1y} & A_{2y} & 0 & M_t \end{pmatrix}
    \begin{pmatrix}\ddot\varphi_1\\ \ddot\varphi_2\\ \ddot x_s\\ \ddot y_s\end{pmatrix} =
    \begin{pmatrix} b_1\\ b_2\\
    S_1 s_1\omega_1^2 + S_2 s_2 \omega_2^2 - k_x x_s - c_x \dot x_s + Q_x\\
    -S_1 c_1\omega_1^2 - S_2 c_2 \omega_2^2 - k_y y_s - c_y \dot y_s + Q_y \end{pmatrix}

with :math:`A_{1x} = S_1 \cos\varphi_1`, :math:`A_{1y} = S_1 \sin\varphi_1`,
:math:`A_{2x} = S_2 \cos\varphi_2`, :math:`A_{2y} = S_2 \sin\varphi_2`, :math:`M_{11} = J_1`,
:math:`M_{12} = K\cos\Delta`, :math:`M_{22} = J_2` and :math:`b_i` as in
:mod:`double_pendulum.model.dynamics` (including the generalised forces :math:`Q_1, Q_2`). The pivot rows
are eliminated (Schur complement) and the remaining 2x2 system solved in closed form.

Forces on the bodies: the pivot force is the rate of change of the total momentum of bobs and
rods minus gravity and air drag (each rod's centre accelerates as the mean of its two joints);
the elbow carries bob 2 and rod 2. Air drag on a rod acts over its whole plate,
``l/2 - L/2 .. l/2 + L/2`` from its upper joint (L = L_rod, or l for L_rod = 0), overhangs included (whatever the rod's
mass). The bearing drag torques :math:`\tau_{b,i}\tanh(\omega_{rel}/\omega_{reg})` are
generalised forces like the friction torques: :math:`Q_1 = -\tau_p + \tau_e`,
:math:`Q_2 = -\tau_e` (pivot torque :math:`\tau_p` along :math:`\omega_1`, elbow torque
:math:`\tau_e` along :math:`\omega_2 - \omega_1`).

Bearing friction torques depend on the joint reaction forces, which depend on the accelerations:
the coupled system is solved by fixed-point iteration (the map contracts by about
:math:`c_R r_b / l`, ~1e-5 here, so two or three iterations reach rounding level).

Inputs (:mod:`double_pendulum.model.inputs`, only with ``ModelConfig.inputs``; the evaluator then
takes the inputs ``u`` at the evaluated instant): in a direction without a suspension state the
pivot moves as prescribed, which adds the fictitious forces of its acceleration
:math:`(a_x, a_y)` to the angle equations,

.. math::

    b_1 \mathrel{-}= A_{1x} a_x + A_{1y} a_y,\qquad b_2 \mathrel{-}= A_{2x} a_x + A_{2y} a_y

(a constant upward :math:`a_y` acts as gravity :math:`g + a_y`), and uses its velocity in the bob
velocities; in a suspended direction the input is the base, and the pivot row reads
:math:`\dots - k_x (x_s - x_b) - c_x (\dot x_s - v_{b,x}) + Q_x`. The joint torques add
:math:`Q_1 \mathrel{+}= \tau_1 - \tau_2`, :math:`Q_2 \mathrel{+}= \tau_2`. The state ``W_input`` [J]
integrates the power the inputs feed in (see :mod:`double_pendulum.model.inputs`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from ..codegen import compile_function
from .dynamics import LINK_ACCELERATIONS, fixed_pivot_vector_field
from .energy import kinetic_energy_moving_pivot, potential_energy, suspension_energy
from .evaluator import MOMENTUM_RATE, build_evaluator, momentum_constants
from .inputs import InputHold, InputValues
from .links import link_coefficients
from .parameters import PendulumParameters
from .scene import Evaluation, ModelConfig, StateLayout, is_core, is_driven_core, state_layout

DRIVEN_CORE = """
phi1, phi2, omega1, omega2 = y[0], y[1], y[2], y[3]
axs, ays, tau1, tau2 = u[4], u[5], u[6], u[7]
s1 = sin(phi1)
c1 = cos(phi1)
s2 = sin(phi2)
c2 = cos(phi2)
q1 = tau1 - tau2 - fm1 * (c1 * axs + s1 * ays)
q2 = tau2 - fm2 * (c2 * axs + s2 * ays)
""", """
fp_y = ma_y + weight
tau = t - hold.t0
p_input = tau1 * omega1 + tau2 * (omega2 - omega1) + ma_x * (u[2] + tau * axs) + (fp_y - weight) * (u[3] + tau * ays)
"""
"""The driven core around :data:`~double_pendulum.model.dynamics.LINK_ACCELERATIONS` and
:data:`MOMENTUM_RATE`: the forcing (joint torques, fictitious forces of the pivot acceleration) and
the input power (:func:`~.evaluator._input_powers` with both directions prescribed)."""


def driven_core_vector_field(
    params: PendulumParameters, hold: InputHold
) -> Callable[[float, list[float]], list[float]]:
    r"""Return ``f(t, y) -> dy/dt`` for ``y = [phi1, phi2, omega1, omega2, W_input]`` (fast path).

    The frictionless pendulum on a prescribed pivot, inputs ``hold.at(t)``: the angle equations of
    :data:`~double_pendulum.model.dynamics.LINK_ACCELERATIONS` with the generalised forces [N m]

    .. math::

        Q_1 = \tau_1 - \tau_2 - S_1(\cos\varphi_1 a_x + \sin\varphi_1 a_y),\qquad
        Q_2 = \tau_2 - S_2(\cos\varphi_2 a_x + \sin\varphi_2 a_y)

    (joint torques and the fictitious forces of the pivot acceleration :math:`(a_x, a_y)` [m/s^2]),
    and :math:`\dot W_{input}` [W] as in :func:`~.evaluator._input_powers`: the torques' power
    :math:`\tau_1\omega_1 + \tau_2(\omega_2 - \omega_1)` plus the pivot force on the pendulum about
    its static value (:data:`MOMENTUM_RATE`) times the pivot velocity :math:`(v_x, v_y)(t)` [m/s]
    (:meth:`InputHold.velocity_at`). The same equations as :func:`build_evaluator` without
    mechanisms, to rounding, as one frame of straight-line code (:data:`DRIVEN_CORE`). Built once
    per scene: it reads the hold's values on every call, so :meth:`InputHold.reset` changes it.
    """
    lc = link_coefficients(params)
    constants = {
        "j1": lc.j1, "j2": lc.j2, "k": lc.k, "gs1": lc.gs1, "gs2": lc.gs2, "fm1": lc.s1, "fm2": lc.s2,
        "weight": lc.mass * params.g, "hold": hold, "u": hold.u, "sin": math.sin, "cos": math.cos,
        **momentum_constants(params),
    }  # fmt: skip
    forcing, power = DRIVEN_CORE
    return compile_function(
        "driven_core_vector_field", "t, y", [forcing, LINK_ACCELERATIONS, MOMENTUM_RATE, power],
        "[omega1, omega2, alpha1, alpha2, p_input]", constants,
    )  # fmt: skip


def build_vector_field(
    config: ModelConfig,
    evaluate: Callable[..., Evaluation] | None = None,
    hold: InputHold | None = None,
) -> Callable[[float, list[float]], list[float]]:
    """Return ``f(t, y) -> dy/dt`` for the states of :func:`state_layout` (only enabled terms).

    ``evaluate`` is the scene's evaluator if already built (see :func:`build_model`); ``hold``
    (with ``config.inputs``) gives the inputs as functions of time over a communication step.
    """
    if is_core(config):
        return fixed_pivot_vector_field(config.pendulum)
    if hold is not None and is_driven_core(config):
        return driven_core_vector_field(config.pendulum, hold)
    evaluate = evaluate or build_evaluator(config)
    if hold is not None:
        at = hold.at

        def driven_vector_field(t: float, y: list[float]) -> list[float]:
            return evaluate(y, at(t)).dydt

        return driven_vector_field

    def vector_field(t: float, y: list[float]) -> list[float]:
        return evaluate(y).dydt

    return vector_field


def initial_state(config: ModelConfig, phi1: float, phi2: float, omega1: float, omega2: float) -> list[float]:
    """Return the start vector: given angles and rates, suspension at rest at equilibrium, no work done."""
    y = [phi1, phi2, omega1, omega2]
    return y + [0.0] * (state_layout(config).size - 4)


def energies(
    config: ModelConfig, y: list[float], layout: StateLayout | None = None, u: InputValues | None = None
) -> tuple[float, float, float]:
    """Return ``(E_kin, E_pot, E_suspension)`` [J] of state ``y`` (inputs ``u`` at that instant).

    ``E_kin``: bobs and rods, absolute velocities; ``E_pot``: pendulum potential relative to the pivot,
    zero hanging at rest; ``E_suspension``: see :func:`double_pendulum.model.energy.suspension_energy`,
    with the springs stretched by the displacement relative to the base.
    """
    layout = layout or state_layout(config)
    ix, iy = layout.index("xs"), layout.index("ys")
    xs, vxs = (y[ix], y[ix + 1]) if ix is not None else (0.0, 0.0)
    ys, vys = (y[iy], y[iy + 1]) if iy is not None else (0.0, 0.0)
    p, s = config.pendulum, config.suspension
    vpx, vpy = vxs, vys  # pivot velocity
    if u is not None:
        vpx = vxs if ix is not None else u.pivot_vx
        vpy = vys if iy is not None else u.pivot_vy
        xs = xs - u.pivot_x if ix is not None else 0.0
        ys = ys - u.pivot_y if iy is not None else 0.0
    e_kin = kinetic_energy_moving_pivot(y[0], y[1], y[2], y[3], vpx, vpy, p)
    e_pot = potential_energy(y[0], y[1], p)
    e_sus = suspension_energy(xs, ys, vxs, vys, s.M_s, s.k_x, s.k_y) if s.suspension else 0.0
    return e_kin, e_pot, e_sus


@dataclass(frozen=True)
class Model:
    """A built scene: its configuration, state layout, vector field and full evaluator."""

    config: ModelConfig
    layout: StateLayout
    vector_field: Callable[[float, list[float]], list[float]]
    evaluate: Callable[..., Evaluation]

    def initial_state(self, phi1: float, phi2: float, omega1: float, omega2: float) -> list[float]:
        """Start vector for the given angles [rad] and rates [rad/s]."""
        return initial_state(self.config, phi1, phi2, omega1, omega2)


def build_model(config: ModelConfig) -> Model:
    """Build the scene ``config``: only the enabled mechanisms are integrated and evaluated."""
    evaluate = build_evaluator(config)
    return Model(config, state_layout(config), build_vector_field(config, evaluate), evaluate)
