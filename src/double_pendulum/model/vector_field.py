r"""The assembled model: which states exist, the vector field, and every output quantity.

A scene switches mechanisms on or off (:class:`ModelConfig`); :func:`build_model` then builds a
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
from dataclasses import dataclass, field
from typing import NamedTuple

from ..codegen import compile_function
from .dynamics import LINK_ACCELERATIONS, fixed_pivot_vector_field
from .energy import kinetic_energy_moving_pivot, potential_energy, suspension_energy
from .forces import bearing_drag_torque, bearing_torque, quadratic_drag, rod_drag_integrals
from .inputs import InputHold, InputValues
from .links import link_coefficients, plate_lengths
from .parameters import AirDragParameters, BearingParameters, PendulumParameters, SuspensionParameters

MAX_FRICTION_ITERATIONS = 50


class ModelError(RuntimeError):
    """The model equations cannot be evaluated (e.g. the friction iteration does not converge)."""


@dataclass(frozen=True)
class ModelConfig:
    """All parameters of a scene: the pendulum and each (switchable) mechanism."""

    pendulum: PendulumParameters = field(default_factory=PendulumParameters)
    air: AirDragParameters = field(default_factory=AirDragParameters)
    bearing: BearingParameters = field(default_factory=BearingParameters)
    suspension: SuspensionParameters = field(default_factory=SuspensionParameters)
    inputs: bool = False  # pivot motion and joint torques enter as inputs (adds the W_input state)


@dataclass(frozen=True)
class StateLayout:
    """Which states exist and where they sit in the state vector."""

    names: tuple[str, ...]

    def index(self, name: str) -> int | None:
        """Position of state ``name``, or ``None`` if the scene does not have it."""
        return self.names.index(name) if name in self.names else None

    @property
    def size(self) -> int:
        return len(self.names)


def state_layout(config: ModelConfig) -> StateLayout:
    """Return the states needed by ``config`` (see the module docstring for the order)."""
    s = config.suspension
    names = ["phi1", "phi2", "omega1", "omega2"]
    if s.suspension and s.suspension_x:
        names += ["xs", "vxs"]
    if s.suspension and s.suspension_y:
        names += ["ys", "vys"]
    if config.air.air_drag:
        names.append("W_air")
    if config.bearing.bearing_friction:
        names.append("W_bearing")
    if config.bearing.bearing_drag:
        names.append("W_bearing_drag")
    if s.suspension:
        names.append("W_suspension")
    if config.inputs:
        names.append("W_input")
    return StateLayout(tuple(names))


def every_state() -> tuple[str, ...]:
    """Every state any scene can have: those of the scene with every mechanism and the inputs on, in order."""
    scene = ModelConfig(
        air=AirDragParameters(air_drag=True),
        bearing=BearingParameters(bearing_friction=True, bearing_drag=True),
        suspension=SuspensionParameters(suspension=True),
        inputs=True,
    )
    return state_layout(scene).names


class Evaluation(NamedTuple):
    """Everything the equations produce at one state (units: SI)."""

    dydt: list[float]
    alpha1: float  # rad/s^2
    alpha2: float  # rad/s^2
    axs: float  # m/s^2
    ays: float  # m/s^2
    f_pivot_x: float  # N, force the pendulum exerts on its pivot (with the static weight)
    f_pivot_y: float  # N
    p_air: float  # W
    p_bearing: float  # W
    p_suspension: float  # W, dissipated in the suspension dampers
    p_bearing_drag: float = 0.0  # W, dissipated by the load-independent bearing drag torques
    p_input: float = 0.0  # W, power fed in through the inputs


def has_mechanism(config: ModelConfig) -> bool:
    """True if air drag, a bearing term or the suspension is on."""
    return (
        config.air.air_drag
        or config.bearing.bearing_friction
        or config.bearing.bearing_drag
        or config.suspension.suspension
    )


def is_core(config: ModelConfig) -> bool:
    """True if every mechanism is off: the scene is the frictionless fixed-pivot pendulum."""
    return not (has_mechanism(config) or config.inputs)


def is_driven_core(config: ModelConfig) -> bool:
    """True if the scene has inputs and no mechanism: the frictionless pendulum on a driven pivot."""
    return config.inputs and not has_mechanism(config)


def build_evaluator(config: ModelConfig) -> Callable[..., Evaluation]:
    """Return ``evaluate(y, u=None) -> Evaluation`` with only the enabled terms (general path).

    ``u`` (:class:`~double_pendulum.model.inputs.InputValues`) are the inputs at the evaluated
    instant; ``None`` (no inputs) skips every input term.
    """
    p, air, brg, sus = config.pendulum, config.air, config.bearing, config.suspension
    layout = state_layout(config)
    m2, l1, l2, g = p.m2, p.l1, p.l2, p.g
    lc = link_coefficients(p)
    j1, j2, k12, fm1, fm2, gs1, gs2 = lc.j1, lc.j2, lc.k, lc.s1, lc.s2, lc.gs1, lc.gs2
    hr2 = 0.5 * p.m_rod2  # half the mass of rod 2 (its centre: the mean of its joints)
    big_l1, big_l2 = plate_lengths(p)  # L_rod = 0: joint to joint
    rod1_lo, rod1_hi = 0.5 * l1 - 0.5 * big_l1, 0.5 * l1 + 0.5 * big_l1  # plates, from upper joints
    rod2_lo, rod2_hi = 0.5 * l2 - 0.5 * big_l2, 0.5 * l2 + 0.5 * big_l2
    ix, iy = layout.index("xs"), layout.index("ys")
    has_x, has_y = ix is not None, iy is not None
    has_air = air.air_drag
    has_rods = air.air_drag and air.rod_drag
    has_bearing = brg.bearing_friction
    has_drag = brg.bearing_drag
    k_bob1 = 0.5 * air.rho_air * air.cw * air.A1
    k_bob2 = 0.5 * air.rho_air * air.cw * air.A2
    kappa1 = 0.5 * air.rho_air * air.cw_rod * air.d_rod1
    kappa2 = 0.5 * air.rho_air * air.cw_rod * air.d_rod2
    m_t = sus.M_s + lc.mass
    k_x, k_y, c_x, c_y = sus.k_x, sus.k_y, sus.c_x, sus.c_y
    n = layout.size
    work_slots = [layout.index(name) for name in ("W_air", "W_bearing", "W_suspension", "W_bearing_drag")]
    sin, cos, torque = math.sin, math.cos, bearing_torque
    torque_scale_p = brg.c_R1 * brg.r_b1 * lc.mass * g + 1e-300
    torque_scale_e = brg.c_R2 * brg.r_b2 * lc.mass2 * g + 1e-300
    input_slot = layout.index("W_input")
    momentum_rate = _momentum_rate_function(p)

    def evaluate(y: list[float], u: InputValues | None = None) -> Evaluation:
        phi1, phi2, w1, w2 = y[0], y[1], y[2], y[3]
        xs, vxs = (y[ix], y[ix + 1]) if has_x else (0.0, 0.0)
        ys, vys = (y[iy], y[iy + 1]) if has_y else (0.0, 0.0)
        apx = apy = 0.0  # prescribed pivot acceleration (directions without a suspension state)
        xb = vxb = yb = vyb = 0.0  # motion of the suspension's base
        if u is not None:
            if has_x:
                xb, vxb = u.pivot_x, u.pivot_vx
            else:
                vxs, apx = u.pivot_vx, u.pivot_ax
            if has_y:
                yb, vyb = u.pivot_y, u.pivot_vy
            else:
                vys, apy = u.pivot_vy, u.pivot_ay
        s1, c1, s2, c2 = sin(phi1), cos(phi1), sin(phi2), cos(phi2)
        sd, cd = sin(phi1 - phi2), cos(phi1 - phi2)
        # absolute bob velocities
        v1x = vxs + l1 * c1 * w1
        v1y = vys + l1 * s1 * w1
        v2x = v1x + l2 * c2 * w2
        v2y = v1y + l2 * s2 * w2

        # external (air) forces: generalised forces q1, q2, qx, qy and the total force on the pendulum
        q1 = q2 = qx = qy = 0.0
        fext_x = fext_y = f2x = f2y = 0.0
        p_air = 0.0
        if has_air:
            f1x, f1y, p1 = quadratic_drag(v1x, v1y, k_bob1)
            f2x, f2y, p2 = quadratic_drag(v2x, v2y, k_bob2)
            fext_x, fext_y, p_air = f1x + f2x, f1y + f2y, p1 + p2
            q1 = l1 * (c1 * fext_x + s1 * fext_y)
            q2 = l2 * (c2 * f2x + s2 * f2y)
            qx, qy = fext_x, fext_y
            if has_rods:
                # rod 1: normal n1 = (c1, s1), v_n = vs.n1 + s w1
                i0, i1, i3 = rod_drag_integrals(vxs * c1 + vys * s1, w1, rod1_lo, rod1_hi)
                q1 -= kappa1 * i1
                qx -= kappa1 * i0 * c1
                qy -= kappa1 * i0 * s1
                fext_x -= kappa1 * i0 * c1
                fext_y -= kappa1 * i0 * s1
                p_air += kappa1 * i3
                # rod 2: normal n2 = (c2, s2), v_n = v1.n2 + s w2; dr/dphi1 . n2 = l1 cos(phi1 - phi2)
                i0, i1, i3 = rod_drag_integrals(v1x * c2 + v1y * s2, w2, rod2_lo, rod2_hi)
                q1 -= kappa2 * i0 * l1 * cd
                q2 -= kappa2 * i1
                qx -= kappa2 * i0 * c2
                qy -= kappa2 * i0 * s2
                fext_x -= kappa2 * i0 * c2
                fext_y -= kappa2 * i0 * s2
                p_air += kappa2 * i3

        # load-independent bearing drag: torques along omega1 (pivot) and omega2 - omega1 (elbow)
        p_drag = 0.0
        if has_drag:
            drag_p = bearing_drag_torque(w1, brg.tau_b1, brg.omega_reg)
            drag_e = bearing_drag_torque(w2 - w1, brg.tau_b2, brg.omega_reg)
            q1 += drag_e - drag_p
            q2 -= drag_e
            p_drag = drag_p * w1 + drag_e * (w2 - w1)
        if u is not None:  # joint torques
            q1 += u.tau1 - u.tau2
            q2 += u.tau2

        # mass matrix and right-hand side of the angle equations
        a11 = j1
        a12 = k12 * cd
        a22 = j2
        b1 = -k12 * w2 * w2 * sd - gs1 * s1 + q1
        b2 = k12 * w1 * w1 * sd - gs2 * s2 + q2
        if u is not None:  # fictitious forces of the prescribed pivot acceleration
            b1 -= fm1 * (c1 * apx + s1 * apy)
            b2 -= fm2 * (c2 * apx + s2 * apy)
        # eliminate the pivot coordinates (Schur complement)
        bx = by = 0.0
        ax1 = ax2 = ay1 = ay2 = 0.0
        if has_x:
            ax1, ax2 = fm1 * c1, fm2 * c2
            bx = fm1 * s1 * w1 * w1 + fm2 * s2 * w2 * w2 - k_x * xs - c_x * vxs + qx
            if u is not None:  # the spring and damper act relative to the moving base
                bx += k_x * xb + c_x * vxb
            a11 -= ax1 * ax1 / m_t
            a12 -= ax1 * ax2 / m_t
            a22 -= ax2 * ax2 / m_t
            b1 -= ax1 * bx / m_t
            b2 -= ax2 * bx / m_t
        if has_y:
            ay1, ay2 = fm1 * s1, fm2 * s2
            by = -fm1 * c1 * w1 * w1 - fm2 * c2 * w2 * w2 - k_y * ys - c_y * vys + qy
            if u is not None:
                by += k_y * yb + c_y * vyb
            a11 -= ay1 * ay1 / m_t
            a12 -= ay1 * ay2 / m_t
            a22 -= ay2 * ay2 / m_t
            b1 -= ay1 * by / m_t
            b2 -= ay2 * by / m_t
        det = a11 * a22 - a12 * a12

        tau_p = tau_e = 0.0  # bearing torques, positive along omega1 and omega2 - omega1
        for _ in range(MAX_FRICTION_ITERATIONS):
            e1 = b1 - tau_p + tau_e
            e2 = b2 - tau_e
            alpha1 = (e1 * a22 - a12 * e2) / det
            alpha2 = (a11 * e2 - a12 * e1) / det
            axs = (bx - ax1 * alpha1 - ax2 * alpha2) / m_t if has_x else apx
            ays = (by - ay1 * alpha1 - ay2 * alpha2) / m_t if has_y else apy
            # bob accelerations and the reaction forces the joints carry
            acc1x, acc1y, acc2x, acc2y, ma_x, ma_y = momentum_rate(axs, ays, c1, s1, c2, s2, w1, w2, alpha1, alpha2)
            # force of the pivot on the pendulum: sum m a (bobs, rods) - gravity - external forces
            fp_x = ma_x - fext_x
            fp_y = ma_y + lc.mass * g - fext_y
            if not has_bearing:
                break
            # force of the elbow on link 2, bob and rod (the small drag share of rod 2 is neglected)
            fe_x = m2 * acc2x + hr2 * (acc1x + acc2x) - f2x
            fe_y = m2 * acc2y + hr2 * (acc1y + acc2y) + lc.mass2 * g - f2y
            new_p = torque(math.hypot(fp_x, fp_y), w1, brg.c_R1, brg.r_b1, brg.omega_reg, brg.b_v1)
            new_e = torque(math.hypot(fe_x, fe_y), w2 - w1, brg.c_R2, brg.r_b2, brg.omega_reg, brg.b_v2)
            # Converged to rounding level of the torque scale c_R r_b (m1 + m2) g: near-zero loads carry
            # cancellation noise, so a purely relative test could cycle between neighbouring floats.
            converged = abs(new_p - tau_p) <= 1e-12 * (abs(new_p) + torque_scale_p) and abs(
                new_e - tau_e
            ) <= (1e-12 * (abs(new_e) + torque_scale_e))
            tau_p, tau_e = new_p, new_e
            if converged:
                break
        else:
            raise ModelError(
                "bearing friction: the joint-load iteration did not converge; c_R * r_b is too large "
                f"for rods of l1 = {l1} m, l2 = {l2} m"
            )

        p_bearing = tau_p * w1 + tau_e * (w2 - w1) if has_bearing else 0.0
        p_susp = c_x * vxs * vxs + c_y * vys * vys
        p_input = 0.0
        if u is not None:
            p_susp, p_input = _input_powers(
                (has_x, xs - xb, vxs, vxb, k_x, c_x, fp_x),
                (has_y, ys - yb, vys, vyb, k_y, c_y, fp_y - lc.mass * g),
                u.tau1 * w1 + u.tau2 * (w2 - w1),
            )
        dydt = [0.0] * n
        dydt[0], dydt[1], dydt[2], dydt[3] = w1, w2, alpha1, alpha2
        if has_x:
            dydt[ix], dydt[ix + 1] = vxs, axs
        if has_y:
            dydt[iy], dydt[iy + 1] = vys, ays
        for slot, power in zip(work_slots, (p_air, p_bearing, p_susp, p_drag)):
            if slot is not None:
                dydt[slot] = power
        if input_slot is not None:
            dydt[input_slot] = p_input
        return Evaluation(dydt, alpha1, alpha2, axs, ays, -fp_x, -fp_y, p_air, p_bearing, p_susp, p_drag, p_input)

    return evaluate


MomentumRate = Callable[..., tuple[float, float, float, float, float, float]]

MOMENTUM_RATE = """
acc1x = axs + l1 * (c1 * alpha1 - s1 * omega1 * omega1)
acc1y = ays + l1 * (s1 * alpha1 + c1 * omega1 * omega1)
acc2x = acc1x + l2 * (c2 * alpha2 - s2 * omega2 * omega2)
acc2y = acc1y + l2 * (s2 * alpha2 + c2 * omega2 * omega2)
ma_x = m1 * acc1x + m2 * acc2x + hr1 * (axs + acc1x) + hr2 * (acc1x + acc2x)
ma_y = m1 * acc1y + m2 * acc2y + hr1 * (ays + acc1y) + hr2 * (acc1y + acc2y)
"""
"""Bob accelerations and the rate of change of the pendulum's momentum, as a snippet
(:mod:`~double_pendulum.codegen`; see :func:`_momentum_rate_function`)."""


def _momentum_constants(p: PendulumParameters) -> dict[str, float]:
    return {"m1": p.m1, "m2": p.m2, "l1": p.l1, "l2": p.l2, "hr1": 0.5 * p.m_rod1, "hr2": 0.5 * p.m_rod2}


def _momentum_rate_function(p: PendulumParameters) -> MomentumRate:
    r"""Return ``rate(a_x, a_y, c1, s1, c2, s2, w1, w2, alpha1, alpha2)`` for the pendulum ``p``.

    From the pivot acceleration :math:`(a_x, a_y)` [m/s^2], :math:`c_i = \cos\varphi_i`,
    :math:`s_i = \sin\varphi_i`, the rates :math:`\omega_i` [rad/s] and the angular accelerations
    :math:`\alpha_i` [rad/s^2] it returns the bob accelerations [m/s^2]

    .. math::

        \vec a_1 = \vec a_p + l_1(\alpha_1 \vec n_1 - \omega_1^2 \vec e_1),\qquad
        \vec a_2 = \vec a_1 + l_2(\alpha_2 \vec n_2 - \omega_2^2 \vec e_2)

    and the rate of change of the pendulum's momentum [N],
    :math:`m_1\vec a_1 + m_2\vec a_2 + \tfrac12 m_{r1}(\vec a_p + \vec a_1)
    + \tfrac12 m_{r2}(\vec a_1 + \vec a_2)` (each rod's centre moves as the mean of its joints):
    ``(a1x, a1y, a2x, a2y, ma_x, ma_y)``. The pivot force on the pendulum is this minus gravity and
    the external forces. Compiled from :data:`MOMENTUM_RATE`, which the fast driven core inlines.
    """
    return compile_function(
        "rate", "axs, ays, c1, s1, c2, s2, omega1, omega2, alpha1, alpha2", [MOMENTUM_RATE],
        "acc1x, acc1y, acc2x, acc2y, ma_x, ma_y", _momentum_constants(p),
    )  # fmt: skip


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
the input power (:func:`_input_powers` with both directions prescribed)."""


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
    and :math:`\dot W_{input}` [W] as in :func:`_input_powers`: the torques' power
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
        **_momentum_constants(params),
    }  # fmt: skip
    forcing, power = DRIVEN_CORE
    return compile_function(
        "driven_core_vector_field", "t, y", [forcing, LINK_ACCELERATIONS, MOMENTUM_RATE, power],
        "[omega1, omega2, alpha1, alpha2, p_input]", constants,
    )  # fmt: skip


def _input_powers(
    x: tuple[bool, float, float, float, float, float, float],
    y: tuple[bool, float, float, float, float, float, float],
    torque_power: float,
) -> tuple[float, float]:
    r"""Return ``(p_suspension, p_input)`` [W] with inputs.

    Per direction ``(suspended, stretch [m], v_pivot [m/s], v_base [m/s], k, c, f_dyn [N])``:
    suspended, the damper dissipates :math:`c(\dot x_s - v_b)^2` and the base feeds in
    :math:`(-k\,\mathrm{stretch} - c(\dot x_s - v_b))\,v_b`; prescribed, the pivot feeds in the
    dynamic part ``f_dyn`` of its force on the pendulum times its velocity.
    """
    p_susp, p_input = 0.0, torque_power
    for suspended, stretch, v_pivot, v_base, k, c, f_dyn in (x, y):
        if suspended:
            dv = v_pivot - v_base
            p_susp += c * dv * dv
            p_input += (-k * stretch - c * dv) * v_base
        else:
            p_input = _pivot_power(p_input, f_dyn, v_pivot)
    return p_susp, p_input


def _pivot_power(p_input: float, f_dyn: float, v_pivot: float) -> float:
    """Return ``p_input + f_dyn * v_pivot`` [W]: add the power a prescribed pivot direction feeds in.

    ``f_dyn`` [N] is the dynamic part of the pivot's force on the pendulum in that direction,
    ``v_pivot`` [m/s] the pivot's velocity.
    """
    return p_input + f_dyn * v_pivot


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
