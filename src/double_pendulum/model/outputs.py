"""The model's output quantities: names, units, descriptions and how each is computed.

This table is the FMU's output interface (same names, same order) and the column set of every
result, in-process or through fmpy. Quantities of a mechanism that is switched off are zero.

Energy bookkeeping: ``E_total = E_pendulum + E_suspension`` is conserved without dissipation;
each mechanism's dissipated work ``W_*`` is integrated as a state, so
``energy_residual = E_total(t) + W_air + W_bearing + W_bearing_drag + W_suspension - W_input -
E_total(0)`` measures only the integration error, ``W_input`` being the work fed in through the
inputs (:mod:`double_pendulum.model.inputs`).

Every output group takes the inputs ``u`` at the output's instant (``None`` without inputs):
the pivot's motion and the pivot force depend on them directly (see :data:`INPUT_DEPENDENCIES`).
"""

from __future__ import annotations

from .inputs import InputValues
from .kinematics import positions
from .links import link_coefficients
from .quantities import Quantity
from .vector_field import Model, energies

OUTPUTS: tuple[Quantity, ...] = (
    Quantity("phi1", "rad", "angle of the upper rod from the downward vertical"),
    Quantity("phi2", "rad", "angle of the lower rod from the downward vertical"),
    Quantity("omega1", "rad/s", "angular velocity of the upper rod"),
    Quantity("omega2", "rad/s", "angular velocity of the lower rod"),
    Quantity("x1", "m", "horizontal position of the upper bob (pivot rest position at the origin)"),
    Quantity("y1", "m", "vertical position of the upper bob (up is positive)"),
    Quantity("x2", "m", "horizontal position of the lower bob"),
    Quantity("y2", "m", "vertical position of the lower bob"),
    Quantity("E_kin", "J", "kinetic energy of bobs and rods (absolute velocities)"),
    Quantity("E_pot", "J", "potential energy of bobs and rods relative to the pivot, zero hanging at rest"),
    Quantity("E_total", "J", "total mechanical energy E_pendulum + E_suspension"),
    Quantity("xs", "m", "horizontal displacement of the pivot from its rest position"),
    Quantity("ys", "m", "vertical displacement of the pivot from its rest position"),
    Quantity("vxs", "m/s", "horizontal velocity of the pivot"),
    Quantity("vys", "m/s", "vertical velocity of the pivot"),
    Quantity("E_pendulum", "J", "energy of the pendulum (bobs and rods): E_kin + E_pot"),
    Quantity("E_suspension", "J", "suspension mass kinetic energy plus spring energy about equilibrium"),
    Quantity("W_air", "J", "work dissipated by air drag since the start"),
    Quantity("W_bearing", "J", "work dissipated by bearing friction since the start"),
    Quantity("W_bearing_drag", "J", "work dissipated by the load-independent bearing drag torques since the start"),
    Quantity("W_suspension", "J", "work dissipated in the suspension dampers since the start"),
    Quantity(
        "P_to_suspension", "W", "power flowing from the pendulum through the pivot into the suspension (or the driver)"
    ),
    Quantity("F_pivot_x", "N", "horizontal force of the pendulum on its pivot"),
    Quantity("F_pivot_y", "N", "vertical force of the pendulum on its pivot (-(m1+m2+m_rod1+m_rod2) g at rest)"),
    Quantity(
        "energy_residual", "J", "E_total(t) + W_air + W_bearing + W_bearing_drag + W_suspension - W_input - E_total(0)"
    ),
    Quantity("W_input", "J", "work fed in through the inputs (pivot motion, joint torques) since the start"),
)

# Integrator statistics, for work-precision studies (counts since the start).
SOLVER_OUTPUTS: tuple[Quantity, ...] = (
    Quantity("solver_steps", "1", "accepted integrator steps since the start (count)"),
    Quantity("solver_rhs_evaluations", "1", "right-hand side evaluations since the start (count)"),
)

MODEL_OUTPUT_NAMES: tuple[str, ...] = tuple(q.name for q in OUTPUTS)
OUTPUTS = OUTPUTS + SOLVER_OUTPUTS
OUTPUT_NAMES: tuple[str, ...] = tuple(q.name for q in OUTPUTS)
WORK_NAMES: tuple[str, ...] = ("W_air", "W_bearing", "W_bearing_drag", "W_suspension")

# The FMU's outputs (its ports): what a master couples to, the pivot force, and what a user plots
# first, the angles, the rates and the total energy. Every other quantity is one of the FMU's local
# variables: read and recorded by name all the same (fmpy's ``output=[...]``), but neither a port
# nor in a tool's default plot (docs/fmu.md, "Outputs and diagnostics").
PORT_NAMES: tuple[str, ...] = ("phi1", "phi2", "omega1", "omega2", "E_total", "F_pivot_x", "F_pivot_y")


def _pivot(model: Model, y: list[float], u: InputValues | None = None) -> tuple[float, float, float, float]:
    """``(xs, ys, vxs, vys)`` of the pivot: state ``y``, or the inputs ``u`` where it is prescribed."""
    layout = model.layout
    ix, iy = layout.index("xs"), layout.index("ys")
    xs, vxs = (y[ix], y[ix + 1]) if ix is not None else (0.0, 0.0)
    ys, vys = (y[iy], y[iy + 1]) if iy is not None else (0.0, 0.0)
    if u is not None:
        if ix is None:
            xs, vxs = u.pivot_x, u.pivot_vx
        if iy is None:
            ys, vys = u.pivot_y, u.pivot_vy
    return xs, ys, vxs, vys


def kinematic_outputs(
    model: Model, y: list[float], initial_energy: float | None = None, u: InputValues | None = None
) -> dict[str, float]:
    """Angles, rates, bob positions and the pivot's motion (cheap: no energies, no forces)."""
    p = model.config.pendulum
    phi1, phi2 = y[0], y[1]
    xs, ys, vxs, vys = _pivot(model, y, u)
    x1, y1, x2, y2 = positions(phi1, phi2, p.l1, p.l2)
    return {
        "phi1": phi1, "phi2": phi2, "omega1": y[2], "omega2": y[3],
        "x1": x1 + xs, "y1": y1 + ys, "x2": x2 + xs, "y2": y2 + ys,
        "xs": xs, "ys": ys, "vxs": vxs, "vys": vys,
    }  # fmt: skip


def energy_outputs(
    model: Model, y: list[float], initial_energy: float | None = None, u: InputValues | None = None
) -> dict[str, float]:
    """Energies, dissipated works, the work of the inputs and the energy residual [J].

    ``initial_energy`` is E_total at the start; ``None`` means this state is the start.
    """
    e_kin, e_pot, e_sus = energies(model.config, y, model.layout, u)
    e_pend = e_kin + e_pot
    e_total = e_pend + e_sus
    layout = model.layout
    work = {n: (y[i] if (i := layout.index(n)) is not None else 0.0) for n in WORK_NAMES}
    e0 = e_total if initial_energy is None else initial_energy
    w_input = y[i] if (i := layout.index("W_input")) is not None else 0.0
    return {
        "E_kin": e_kin, "E_pot": e_pot, "E_total": e_total, "E_pendulum": e_pend, "E_suspension": e_sus,
        **work, "energy_residual": e_total + sum(work.values()) - w_input - e0, "W_input": w_input,
    }  # fmt: skip


def force_outputs(
    model: Model, y: list[float], initial_energy: float | None = None, u: InputValues | None = None
) -> dict[str, float]:
    """Pivot force [N] and the power into the suspension [W] (needs the accelerations)."""
    p = model.config.pendulum
    _, _, vxs, vys = _pivot(model, y, u)
    ev = model.evaluate(y) if u is None else model.evaluate(y, u)
    # power into the suspension: the pivot force about its static value (the preload carries the weight)
    p_susp = ev.f_pivot_x * vxs + (ev.f_pivot_y + link_coefficients(p).mass * p.g) * vys
    return {"P_to_suspension": p_susp, "F_pivot_x": ev.f_pivot_x, "F_pivot_y": ev.f_pivot_y}


OUTPUT_GROUPS = (kinematic_outputs, energy_outputs, force_outputs)
GROUP_OF: dict[str, int] = {
    name: k
    for k, names in enumerate(
        (
            ("phi1", "phi2", "omega1", "omega2", "x1", "y1", "x2", "y2", "xs", "ys", "vxs", "vys"),
            ("E_kin", "E_pot", "E_total", "E_pendulum", "E_suspension", *WORK_NAMES, "energy_residual", "W_input"),
            ("P_to_suspension", "F_pivot_x", "F_pivot_y"),
        )
    )
    for name in names
}

# Direct dependence of each output on the inputs at the same instant (FMI ModelStructure/Outputs):
# the pivot's motion and the bob positions on the pivot position or velocity, the energies too
# (kinetic energy with the pivot velocity, spring stretch relative to the base), the pivot force on
# every input (the acceleration and torques drive the angular accelerations it contains, drag and
# spring forces use the position and velocity): direct feedthrough. Angles, rates, E_pot and the
# integrated works are states or functions of the states only: no direct dependence.
_MOTION = ("pivot_x", "pivot_y", "pivot_vx", "pivot_vy")
INPUT_DEPENDENCIES: dict[str, tuple[str, ...]] = {
    **{name: () for name in OUTPUT_NAMES},
    **{name: ("pivot_x",) for name in ("x1", "x2", "xs")},
    **{name: ("pivot_y",) for name in ("y1", "y2", "ys")},
    "vxs": ("pivot_vx",),
    "vys": ("pivot_vy",),
    "E_kin": ("pivot_vx", "pivot_vy"),
    "E_suspension": ("pivot_x", "pivot_y"),
    **{name: _MOTION for name in ("E_total", "E_pendulum", "energy_residual")},
    **{name: (*_MOTION, "pivot_ax", "pivot_ay", "tau1", "tau2") for name in ("F_pivot_x", "F_pivot_y")},
    "P_to_suspension": (*_MOTION, "pivot_ax", "pivot_ay", "tau1", "tau2"),
}
