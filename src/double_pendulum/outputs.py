"""The model's output quantities: names, units, descriptions and how each is computed.

This table is the FMU's output interface (same names, same order) and the column set of every
result, in-process or through fmpy.
"""

from __future__ import annotations

from typing import NamedTuple

from .energy import kinetic_energy, potential_energy
from .kinematics import positions
from .parameters import PendulumParameters


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
    Quantity("x1", "m", "horizontal position of the upper bob (pivot at the origin)"),
    Quantity("y1", "m", "vertical position of the upper bob (up is positive)"),
    Quantity("x2", "m", "horizontal position of the lower bob"),
    Quantity("y2", "m", "vertical position of the lower bob"),
    Quantity("E_kin", "J", "kinetic energy of both bobs"),
    Quantity("E_pot", "J", "potential energy, zero with both bobs hanging at rest"),
    Quantity("E_total", "J", "total mechanical energy E_kin + E_pot"),
)

OUTPUT_NAMES: tuple[str, ...] = tuple(q.name for q in OUTPUTS)


def output_values(y: list[float], params: PendulumParameters) -> tuple[float, ...]:
    """Return the outputs, in :data:`OUTPUTS` order, for state ``y = [phi1, phi2, omega1, omega2]``."""
    phi1, phi2, omega1, omega2 = y[0], y[1], y[2], y[3]
    x1, y1, x2, y2 = positions(phi1, phi2, params.l1, params.l2)
    e_kin = kinetic_energy(phi1, phi2, omega1, omega2, params)
    e_pot = potential_energy(phi1, phi2, params)
    return (phi1, phi2, omega1, omega2, x1, y1, x2, y2, e_kin, e_pot, e_kin + e_pot)
