r"""The general evaluator of a scene's equations, assembled from named parts by the code generator.

:func:`build_evaluator` returns ``evaluate(y, u=None)``: the accelerations, the pivot force and the
powers of every enabled mechanism at state ``y`` (inputs ``u``), as an :class:`~.scene.Evaluation`.
The equations are those of :mod:`.vector_field`'s module docstring; each part below holds the source
of one group of them for the scene's switches, and :func:`double_pendulum.codegen.compile_function`
joins the parts into one straight-line function per combination of switches (compiled once),
bound to the scene's constants: no switch is tested and no part costs a call of its own per
evaluation (the force laws of :mod:`.forces` are still called).

Bearing friction torques depend on the joint reaction forces, which depend on the accelerations:
the coupled system is solved by fixed-point iteration (:func:`_joint_loads`).
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable

from ..codegen import compile_function
from .forces import bearing_drag_torque, bearing_torque, quadratic_drag, rod_drag_integrals
from .links import link_coefficients, plate_lengths
from .parameters import PendulumParameters
from .scene import Evaluation, ModelConfig, ModelError, StateLayout, state_layout

MAX_FRICTION_ITERATIONS = 50


def build_evaluator(config: ModelConfig) -> Callable[..., Evaluation]:
    """Return ``evaluate(y, u=None) -> Evaluation`` with only the enabled terms (general path).

    ``u`` (:class:`~double_pendulum.model.inputs.InputValues`) are the inputs at the evaluated
    instant; ``None`` (no inputs) skips every input term. Assembled from the named parts below, in
    order: :func:`_pivot_and_velocities`, :func:`_air_drag`, :func:`_joint_torques`,
    :func:`_angle_equations`, :func:`_joint_loads` and :func:`_powers_and_derivatives`, each the
    source text of its equations for the scene's switches; the code generator
    (:func:`double_pendulum.codegen.compile_function`) compiles them into one straight-line
    function per combination of switches, bound to the scene's constants
    (:func:`_evaluator_constants`), so no switch is tested per evaluation.
    """
    layout = state_layout(config)
    ix, iy = layout.index("xs"), layout.index("ys")
    has_bearing = config.bearing.bearing_friction
    parts = [
        _pivot_and_velocities(ix, iy),
        _air_drag(config.air.rod_drag) if config.air.air_drag else NO_AIR_DRAG,
        _joint_torques(config.bearing.bearing_drag),
        _angle_equations(ix is not None, iy is not None),
        _joint_loads(ix is not None, iy is not None, has_bearing),
        _powers_and_derivatives(layout, has_bearing),
    ]
    returns = "Evaluation(dydt, alpha1, alpha2, axs, ays, -fp_x, -fp_y, p_air, p_bearing, p_susp, p_drag, p_input)"
    return compile_function(
        "evaluate", "y, u", parts, returns, _evaluator_constants(config), defaults=(None,),
        doc="Evaluate the scene's equations at state ``y`` with inputs ``u`` (None: none): an Evaluation.",
    )  # fmt: skip


def _evaluator_constants(config: ModelConfig) -> dict[str, object]:
    """The names the parts of :func:`build_evaluator` read, for the scene ``config`` (SI units).

    Link coefficients ``j1, j2, k12`` [kg m^2], ``fm1, fm2`` (:math:`S_1, S_2`) [kg m] and
    ``gs1, gs2`` (:math:`g S_i`) [N m]; the weights ``weight`` = :math:`M g` and ``weight2`` (link 2)
    [N]; drag factors ``k_bob1, k_bob2`` = :math:`\\tfrac12\\rho c_W A_i` [kg/m] and
    ``kappa1, kappa2`` = :math:`\\tfrac12\\rho c_{W,rod} d_i` [kg/m^2] with the rods' plates from
    ``rod1_lo .. rod1_hi``, ``rod2_lo .. rod2_hi`` [m] below their upper joints; the suspension's
    ``m_t = M_s + M`` [kg], ``k_x, k_y`` [N/m], ``c_x, c_y`` [N s/m]; the bearings' constants and the
    torque scales ``c_R r_b M g`` [N m] of the friction iteration's convergence test; and the
    functions the parts call.
    """
    p, air, brg, sus = config.pendulum, config.air, config.bearing, config.suspension
    lc = link_coefficients(p)
    big_l1, big_l2 = plate_lengths(p)  # L_rod = 0: joint to joint
    return {
        "j1": lc.j1, "j2": lc.j2, "k12": lc.k, "fm1": lc.s1, "fm2": lc.s2, "gs1": lc.gs1, "gs2": lc.gs2,
        "weight": lc.mass * p.g, "weight2": lc.mass2 * p.g,
        "k_bob1": 0.5 * air.rho_air * air.cw * air.A1, "k_bob2": 0.5 * air.rho_air * air.cw * air.A2,
        "kappa1": 0.5 * air.rho_air * air.cw_rod * air.d_rod1, "kappa2": 0.5 * air.rho_air * air.cw_rod * air.d_rod2,
        "rod1_lo": 0.5 * p.l1 - 0.5 * big_l1, "rod1_hi": 0.5 * p.l1 + 0.5 * big_l1,
        "rod2_lo": 0.5 * p.l2 - 0.5 * big_l2, "rod2_hi": 0.5 * p.l2 + 0.5 * big_l2,
        "m_t": sus.M_s + lc.mass, "k_x": sus.k_x, "k_y": sus.k_y, "c_x": sus.c_x, "c_y": sus.c_y,
        "tau_b1": brg.tau_b1, "tau_b2": brg.tau_b2, "omega_reg": brg.omega_reg,
        "c_R1": brg.c_R1, "r_b1": brg.r_b1, "b_v1": brg.b_v1, "c_R2": brg.c_R2, "r_b2": brg.r_b2, "b_v2": brg.b_v2,
        "torque_scale_p": brg.c_R1 * brg.r_b1 * lc.mass * p.g + 1e-300,
        "torque_scale_e": brg.c_R2 * brg.r_b2 * lc.mass2 * p.g + 1e-300,
        "MAX_FRICTION_ITERATIONS": MAX_FRICTION_ITERATIONS, **momentum_constants(p),
        "sin": math.sin, "cos": math.cos, "hypot": math.hypot, "quadratic_drag": quadratic_drag,
        "rod_drag_integrals": rod_drag_integrals, "bearing_torque": bearing_torque,
        "bearing_drag_torque": bearing_drag_torque, "input_powers": _input_powers,
        "Evaluation": Evaluation, "ModelError": ModelError,
    }  # fmt: skip


def _pivot_and_velocities(ix: int | None, iy: int | None) -> str:
    r"""Part 1: the angles and rates from ``y``, the pivot's motion, and the absolute bob velocities.

    The pivot's displacement ``xs, ys`` [m] and velocity ``vxs, vys`` [m/s] are states in a
    suspended direction (slots ``ix``, ``iy``), else 0; with inputs ``u`` a suspended direction
    takes the base's motion ``xb, vxb`` (``yb, vyb``), a prescribed one the pivot's velocity and its
    acceleration ``apx`` (``apy``) [m/s^2]. Bob velocities [m/s]:

    .. math::

        \vec v_1 = \vec v_p + l_1\omega_1(\cos\varphi_1, \sin\varphi_1),\qquad
        \vec v_2 = \vec v_1 + l_2\omega_2(\cos\varphi_2, \sin\varphi_2).
    """
    x_state = f"xs, vxs = y[{ix}], y[{ix + 1}]" if ix is not None else "xs, vxs = 0.0, 0.0"
    y_state = f"ys, vys = y[{iy}], y[{iy + 1}]" if iy is not None else "ys, vys = 0.0, 0.0"
    x_input = "xb, vxb = u.pivot_x, u.pivot_vx" if ix is not None else "vxs, apx = u.pivot_vx, u.pivot_ax"
    y_input = "yb, vyb = u.pivot_y, u.pivot_vy" if iy is not None else "vys, apy = u.pivot_vy, u.pivot_ay"
    return f"""
phi1, phi2, omega1, omega2 = y[0], y[1], y[2], y[3]
{x_state}
{y_state}
apx = apy = 0.0
xb = vxb = yb = vyb = 0.0
if u is not None:
    {x_input}
    {y_input}
s1, c1, s2, c2 = sin(phi1), cos(phi1), sin(phi2), cos(phi2)
sd, cd = sin(phi1 - phi2), cos(phi1 - phi2)
v1x = vxs + l1 * c1 * omega1
v1y = vys + l1 * s1 * omega1
v2x = v1x + l2 * c2 * omega2
v2y = v1y + l2 * s2 * omega2
"""


NO_AIR_DRAG = """
q1 = q2 = qx = qy = 0.0
fext_x = fext_y = f2x = f2y = 0.0
p_air = 0.0
"""
"""Part 2 without air drag: no generalised force [N m, N], external force [N] or drag power [W]."""


def _air_drag(rods: bool) -> str:
    r"""Part 2 with air drag: generalised forces ``q1, q2`` [N m], ``qx, qy`` [N], the external force
    ``fext`` on the pendulum and ``f2`` on bob 2 [N], and the drag power ``p_air`` [W].

    Bobs: :math:`\vec F_i = -k_i |\vec v_i| \vec v_i` (:func:`~double_pendulum.model.forces.quadratic_drag`),
    :math:`Q_1 = l_1 (\vec F_1 + \vec F_2)\cdot\vec n_1`, :math:`Q_2 = l_2 \vec F_2\cdot\vec n_2`
    with :math:`\vec n_i = (\cos\varphi_i, \sin\varphi_i)`, :math:`(Q_x, Q_y) = \vec F_1 + \vec F_2`.
    With ``rods``, each rod's plate adds :math:`-\kappa_i \int |v_n| v_n\,(1, s)\,ds` over its length
    (:func:`~double_pendulum.model.forces.rod_drag_integrals`, normal velocity
    :math:`v_n = \vec v_{joint}\cdot\vec n_i + s\,\omega_i`); rod 2's force acts on :math:`\varphi_1`
    through :math:`\partial\vec r/\partial\varphi_1\cdot\vec n_2 = l_1\cos(\varphi_1 - \varphi_2)`.
    """
    bobs = """
f1x, f1y, p1 = quadratic_drag(v1x, v1y, k_bob1)
f2x, f2y, p2 = quadratic_drag(v2x, v2y, k_bob2)
fext_x, fext_y, p_air = f1x + f2x, f1y + f2y, p1 + p2
q1 = l1 * (c1 * fext_x + s1 * fext_y)
q2 = l2 * (c2 * f2x + s2 * f2y)
qx, qy = fext_x, fext_y
"""
    if not rods:
        return bobs
    return bobs + """
i0, i1, i3 = rod_drag_integrals(vxs * c1 + vys * s1, omega1, rod1_lo, rod1_hi)
q1 -= kappa1 * i1
qx -= kappa1 * i0 * c1
qy -= kappa1 * i0 * s1
fext_x -= kappa1 * i0 * c1
fext_y -= kappa1 * i0 * s1
p_air += kappa1 * i3
i0, i1, i3 = rod_drag_integrals(v1x * c2 + v1y * s2, omega2, rod2_lo, rod2_hi)
q1 -= kappa2 * i0 * l1 * cd
q2 -= kappa2 * i1
qx -= kappa2 * i0 * c2
qy -= kappa2 * i0 * s2
fext_x -= kappa2 * i0 * c2
fext_y -= kappa2 * i0 * s2
p_air += kappa2 * i3
"""


def _joint_torques(bearing_drag: bool) -> str:
    r"""Part 3: the load-independent joint torques in the generalised forces, and their power.

    With ``bearing_drag``: :math:`\tau_p = \tau_{b,1}\tanh(\omega_1/\omega_{reg})` at the pivot along
    :math:`\omega_1`, :math:`\tau_e = \tau_{b,2}\tanh((\omega_2 - \omega_1)/\omega_{reg})` at the elbow
    along :math:`\omega_2 - \omega_1` [N m]: :math:`Q_1 \mathrel{+}= \tau_e - \tau_p`,
    :math:`Q_2 \mathrel{-}= \tau_e`, dissipating ``p_drag`` = :math:`\tau_p\omega_1 + \tau_e(\omega_2 - \omega_1)` [W].
    With inputs, the joint torques: :math:`Q_1 \mathrel{+}= \tau_1 - \tau_2`, :math:`Q_2 \mathrel{+}= \tau_2`.
    """
    drag = """
drag_p = bearing_drag_torque(omega1, tau_b1, omega_reg)
drag_e = bearing_drag_torque(omega2 - omega1, tau_b2, omega_reg)
q1 += drag_e - drag_p
q2 -= drag_e
p_drag = drag_p * omega1 + drag_e * (omega2 - omega1)
"""
    return (drag if bearing_drag else "p_drag = 0.0\n") + """
if u is not None:
    q1 += u.tau1 - u.tau2
    q2 += u.tau2
"""


_PIVOT_ROW = """
a{d}1, a{d}2 = fm1 * {a1}, fm2 * {a2}
b{d} = {centripetal} - k_{d} * {d}s - c_{d} * v{d}s + q{d}
if u is not None:
    b{d} += k_{d} * {d}b + c_{d} * v{d}b
a11 -= a{d}1 * a{d}1 / m_t
a12 -= a{d}1 * a{d}2 / m_t
a22 -= a{d}2 * a{d}2 / m_t
b1 -= a{d}1 * b{d} / m_t
b2 -= a{d}2 * b{d} / m_t
"""
"""The row of a suspended direction ``d`` (x or y) and its elimination, for :func:`_angle_equations`."""


def _angle_equations(has_x: bool, has_y: bool) -> str:
    r"""Part 4: the angle equations :math:`A\,(\alpha_1, \alpha_2) = (b_1, b_2)` with the pivot rows eliminated.

    :math:`A = ((J_1, K\cos\Delta), (K\cos\Delta, J_2))` [kg m^2],
    :math:`b_1 = -K\omega_2^2\sin\Delta - gS_1\sin\varphi_1 + Q_1`,
    :math:`b_2 = K\omega_1^2\sin\Delta - gS_2\sin\varphi_2 + Q_2` [N m], with inputs less the fictitious
    forces :math:`S_i(\cos\varphi_i a_x + \sin\varphi_i a_y)` of a prescribed pivot acceleration. A
    suspended direction (module docstring) adds its row, :math:`A_{1x}\alpha_1 + A_{2x}\alpha_2 + M_t\ddot x_s
    = b_x` with :math:`A_{ix} = S_i\cos\varphi_i`,
    :math:`b_x = S_1\sin\varphi_1\omega_1^2 + S_2\sin\varphi_2\omega_2^2 - k_x(x_s - x_b) - c_x(\dot x_s - v_b) + Q_x`
    [N] (y alike, :math:`A_{iy} = S_i\sin\varphi_i`), eliminated by its Schur complement:
    :math:`A_{ij} \mathrel{-}= A_{ix}A_{jx}/M_t`, :math:`b_i \mathrel{-}= A_{ix}b_x/M_t`. ``det`` is
    :math:`\det A`.
    """
    source = """
a11 = j1
a12 = k12 * cd
a22 = j2
b1 = -k12 * omega2 * omega2 * sd - gs1 * s1 + q1
b2 = k12 * omega1 * omega1 * sd - gs2 * s2 + q2
if u is not None:
    b1 -= fm1 * (c1 * apx + s1 * apy)
    b2 -= fm2 * (c2 * apx + s2 * apy)
bx = by = 0.0
ax1 = ax2 = ay1 = ay2 = 0.0
"""
    if has_x:
        centripetal = "fm1 * s1 * omega1 * omega1 + fm2 * s2 * omega2 * omega2"
        source += _PIVOT_ROW.format(d="x", a1="c1", a2="c2", centripetal=centripetal)
    if has_y:
        centripetal = "-fm1 * c1 * omega1 * omega1 - fm2 * c2 * omega2 * omega2"
        source += _PIVOT_ROW.format(d="y", a1="s1", a2="s2", centripetal=centripetal)
    return source + "det = a11 * a22 - a12 * a12\n"


def _joint_loads(has_x: bool, has_y: bool, bearing_friction: bool) -> str:
    r"""Part 5: the accelerations and the pivot force, with bearing friction by fixed-point iteration.

    For the bearing torques :math:`\tau_p, \tau_e` [N m] (0 without friction):
    :math:`\alpha = A^{-1}(b_1 - \tau_p + \tau_e,\ b_2 - \tau_e)` [rad/s^2] by Cramer's rule, the
    pivot's acceleration [m/s^2] from its eliminated row,
    :math:`\ddot x_s = (b_x - A_{1x}\alpha_1 - A_{2x}\alpha_2)/M_t` (prescribed: :math:`a_x`), the bob
    accelerations and momentum rate of :data:`MOMENTUM_RATE`, and the force of the pivot on the pendulum
    :math:`\vec F_p = \sum m\vec a + M g\,\hat y - \vec F_{ext}` [N]. With ``bearing_friction`` the
    elbow's force on link 2, :math:`\vec F_e = m_2\vec a_2 + \tfrac12 m_{r2}(\vec a_1 + \vec a_2) +
    (m_2 + m_{r2}) g\,\hat y - \vec F_2` [N], gives the torques
    :math:`\tau = ` :func:`~double_pendulum.model.forces.bearing_torque` of :math:`|\vec F_p|`,
    :math:`|\vec F_e|`; iterated until both change by at most :math:`10^{-12}` of their scale
    :math:`c_R r_b M g` (the map contracts by about :math:`c_R r_b / l`, ~1e-5); no convergence in
    :data:`MAX_FRICTION_ITERATIONS` raises :class:`ModelError`.
    """
    axs = "axs = (bx - ax1 * alpha1 - ax2 * alpha2) / m_t" if has_x else "axs = apx"
    ays = "ays = (by - ay1 * alpha1 - ay2 * alpha2) / m_t" if has_y else "ays = apy"
    accelerations = f"""
e1 = b1 - tau_p + tau_e
e2 = b2 - tau_e
alpha1 = (e1 * a22 - a12 * e2) / det
alpha2 = (a11 * e2 - a12 * e1) / det
{axs}
{ays}
{textwrap.dedent(MOMENTUM_RATE).strip()}
fp_x = ma_x - fext_x
fp_y = ma_y + weight - fext_y
"""
    if not bearing_friction:
        return "tau_p = tau_e = 0.0\n" + accelerations
    friction = """
fe_x = m2 * acc2x + hr2 * (acc1x + acc2x) - f2x
fe_y = m2 * acc2y + hr2 * (acc1y + acc2y) + weight2 - f2y
new_p = bearing_torque(hypot(fp_x, fp_y), omega1, c_R1, r_b1, omega_reg, b_v1)
new_e = bearing_torque(hypot(fe_x, fe_y), omega2 - omega1, c_R2, r_b2, omega_reg, b_v2)
converged = abs(new_p - tau_p) <= 1e-12 * (abs(new_p) + torque_scale_p) and abs(
    new_e - tau_e
) <= (1e-12 * (abs(new_e) + torque_scale_e))
tau_p, tau_e = new_p, new_e
if converged:
    break
"""
    loop = textwrap.indent(accelerations.strip("\n") + friction, "    ")
    return f"""
tau_p = tau_e = 0.0
for _ in range(MAX_FRICTION_ITERATIONS):
{loop}else:
    raise ModelError(
        "bearing friction: the joint-load iteration did not converge; c_R * r_b is too large "
        f"for rods of l1 = {{l1}} m, l2 = {{l2}} m"
    )
"""


_DERIVATIVES = {
    "phi1": "omega1", "phi2": "omega2", "omega1": "alpha1", "omega2": "alpha2", "xs": "vxs", "vxs": "axs",
    "ys": "vys", "vys": "ays", "W_air": "p_air", "W_bearing": "p_bearing", "W_bearing_drag": "p_drag",
    "W_suspension": "p_susp", "W_input": "p_input",
}  # fmt: skip
"""The time derivative of each state, by the name the parts of :func:`build_evaluator` give it."""


def _powers_and_derivatives(layout: StateLayout, bearing_friction: bool) -> str:
    r"""Part 6: the dissipated and fed-in powers [W] and ``dydt`` in the order of ``layout``.

    Bearing friction dissipates :math:`\tau_p\omega_1 + \tau_e(\omega_2 - \omega_1)`, the suspension
    dampers :math:`c_x\dot x_s^2 + c_y\dot y_s^2`; with inputs :func:`_input_powers` gives the dampers'
    power relative to the base and the power ``p_input`` the inputs feed in. Each state's derivative
    is :data:`_DERIVATIVES`' entry (the works' rates are these powers).
    """
    suspended = (layout.index("xs") is not None, layout.index("ys") is not None)
    p_bearing = "tau_p * omega1 + tau_e * (omega2 - omega1)" if bearing_friction else "0.0"
    return f"""
p_bearing = {p_bearing}
p_susp = c_x * vxs * vxs + c_y * vys * vys
p_input = 0.0
if u is not None:
    p_susp, p_input = input_powers(
        ({suspended[0]}, xs - xb, vxs, vxb, k_x, c_x, fp_x),
        ({suspended[1]}, ys - yb, vys, vyb, k_y, c_y, fp_y - weight),
        u.tau1 * omega1 + u.tau2 * (omega2 - omega1),
    )
dydt = [{", ".join(_DERIVATIVES[name] for name in layout.names)}]
"""


MOMENTUM_RATE = """
acc1x = axs + l1 * (c1 * alpha1 - s1 * omega1 * omega1)
acc1y = ays + l1 * (s1 * alpha1 + c1 * omega1 * omega1)
acc2x = acc1x + l2 * (c2 * alpha2 - s2 * omega2 * omega2)
acc2y = acc1y + l2 * (s2 * alpha2 + c2 * omega2 * omega2)
ma_x = m1 * acc1x + m2 * acc2x + hr1 * (axs + acc1x) + hr2 * (acc1x + acc2x)
ma_y = m1 * acc1y + m2 * acc2y + hr1 * (ays + acc1y) + hr2 * (acc1y + acc2y)
"""
r"""Bob accelerations and the rate of change of the pendulum's momentum, as a snippet
(:mod:`double_pendulum.codegen`), inlined by :func:`_joint_loads` and the fast driven core.

From the pivot acceleration ``(axs, ays)`` [m/s^2], ``c_i, s_i`` = :math:`\cos\varphi_i, \sin\varphi_i`,
the rates ``omega_i`` [rad/s] and the angular accelerations ``alpha_i`` [rad/s^2]: the bob
accelerations [m/s^2]

.. math::

    \vec a_1 = \vec a_p + l_1(\alpha_1 \vec n_1 - \omega_1^2 \vec e_1),\qquad
    \vec a_2 = \vec a_1 + l_2(\alpha_2 \vec n_2 - \omega_2^2 \vec e_2)

and the rate of change of the pendulum's momentum ``(ma_x, ma_y)`` [N],
:math:`m_1\vec a_1 + m_2\vec a_2 + \tfrac12 m_{r1}(\vec a_p + \vec a_1) + \tfrac12 m_{r2}(\vec a_1 + \vec a_2)`
(each rod's centre moves as the mean of its joints), with the constants of :func:`momentum_constants`.
The pivot force on the pendulum is this minus gravity and the external forces."""


def momentum_constants(p: PendulumParameters) -> dict[str, float]:
    """The constants :data:`MOMENTUM_RATE` reads: masses ``m1, m2`` [kg], lengths ``l1, l2`` [m] and
    half the rod masses ``hr1, hr2`` [kg] of the pendulum ``p``."""
    return {"m1": p.m1, "m2": p.m2, "l1": p.l1, "l2": p.l2, "hr1": 0.5 * p.m_rod1, "hr2": 0.5 * p.m_rod2}


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
