"""The model's output quantities: names, units, descriptions and how each is computed.

This table is the FMU's output interface (same names, same order) and the column set of every
result, in-process or through fmpy. Quantities of a mechanism that is switched off are zero.

Energy bookkeeping: ``E_total = E_pendulum + E_suspension`` is conserved without dissipation;
each mechanism's dissipated work ``W_*`` is integrated as a state, so
``energy_residual = E_total(t) + W_air + W_bearing + W_suspension - E_total(0)`` measures only
the integration error.
"""

from __future__ import annotations

from typing import NamedTuple

from .kinematics import positions
from .model import Model


class Quantity(NamedTuple):
    """An output variable: name, unit (FMI unit string) and description."""

    name: str
    unit: str
    description: str


OUTPUTS: tuple[Quantity, ...] = (
    Quantity("phi1", "rad", "angle of the upper rod from the downward vertical"),
    Quantity("phi2", "rad", "angle of the lower rod from the downward vertical"),
    Quantity("omega1", "rad/s", "angular velocity of the upper rod"),
    Quantity("omega2", "rad/s", "angular velocity of the lower rod"),
    Quantity("x1", "m", "horizontal position of the upper bob (pivot rest position at the origin)"),
    Quantity("y1", "m", "vertical position of the upper bob (up is positive)"),
    Quantity("x2", "m", "horizontal position of the lower bob"),
    Quantity("y2", "m", "vertical position of the lower bob"),
    Quantity("E_kin", "J", "kinetic energy of both bobs (absolute velocities)"),
    Quantity("E_pot", "J", "potential energy of the bobs relative to the pivot, zero hanging at rest"),
    Quantity("E_total", "J", "total mechanical energy E_pendulum + E_suspension"),
    Quantity("xs", "m", "horizontal displacement of the pivot from its rest position"),
    Quantity("ys", "m", "vertical displacement of the pivot from its rest position"),
    Quantity("vxs", "m/s", "horizontal velocity of the pivot"),
    Quantity("vys", "m/s", "vertical velocity of the pivot"),
    Quantity("E_pendulum", "J", "energy of the two bobs: E_kin + E_pot"),
    Quantity("E_suspension", "J", "suspension mass kinetic energy plus spring energy about equilibrium"),
    Quantity("W_air", "J", "work dissipated by air drag since the start"),
    Quantity("W_bearing", "J", "work dissipated by bearing friction since the start"),
    Quantity("W_suspension", "J", "work dissipated in the suspension dampers since the start"),
    Quantity("P_to_suspension", "W", "power flowing from the pendulum into the suspension through the pivot"),
    Quantity("F_pivot_x", "N", "horizontal force of the pendulum on its pivot"),
    Quantity("F_pivot_y", "N", "vertical force of the pendulum on its pivot (-(m1+m2) g at rest)"),
    Quantity("energy_residual", "J", "E_total(t) + W_air + W_bearing + W_suspension - E_total(0)"),
)

# Integrator statistics, for work-precision studies (counts since the start).
SOLVER_OUTPUTS: tuple[Quantity, ...] = (
    Quantity("solver_steps", "1", "accepted integrator steps since the start (count)"),
    Quantity("solver_rhs_evaluations", "1", "right-hand side evaluations since the start (count)"),
)

MODEL_OUTPUT_NAMES: tuple[str, ...] = tuple(q.name for q in OUTPUTS)
OUTPUTS = OUTPUTS + SOLVER_OUTPUTS
OUTPUT_NAMES: tuple[str, ...] = tuple(q.name for q in OUTPUTS)
WORK_NAMES: tuple[str, ...] = ("W_air", "W_bearing", "W_suspension")


def output_values(model: Model, y: list[float], initial_energy: float | None = None) -> tuple[float, ...]:
    """Return the model outputs, in :data:`MODEL_OUTPUT_NAMES` order, at state ``y``.

    ``initial_energy`` [J] is E_total at the start (for the residual); ``None`` means this state
    is the start.
    """
    from .model import energies

    layout, p = model.layout, model.config.pendulum
    phi1, phi2, omega1, omega2 = y[0], y[1], y[2], y[3]
    ix, iy = layout.index("xs"), layout.index("ys")
    xs, vxs = (y[ix], y[ix + 1]) if ix is not None else (0.0, 0.0)
    ys, vys = (y[iy], y[iy + 1]) if iy is not None else (0.0, 0.0)
    x1, y1, x2, y2 = positions(phi1, phi2, p.l1, p.l2)
    e_kin, e_pot, e_sus = energies(model.config, y)
    e_pend = e_kin + e_pot
    e_total = e_pend + e_sus
    work = [y[i] if i is not None else 0.0 for i in (layout.index(n) for n in WORK_NAMES)]
    ev = model.evaluate(y)
    # power into the suspension: the pivot force about its static value (the preload carries the weight)
    p_susp = ev.f_pivot_x * vxs + (ev.f_pivot_y + (p.m1 + p.m2) * p.g) * vys
    e0 = e_total if initial_energy is None else initial_energy
    return (
        phi1,
        phi2,
        omega1,
        omega2,
        x1 + xs,
        y1 + ys,
        x2 + xs,
        y2 + ys,
        e_kin,
        e_pot,
        e_total,
        xs,
        ys,
        vxs,
        vys,
        e_pend,
        e_sus,
        *work,
        p_susp,
        ev.f_pivot_x,
        ev.f_pivot_y,
        e_total + sum(work) - e0,
    )
