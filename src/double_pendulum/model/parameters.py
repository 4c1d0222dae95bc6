"""Model parameters, initial state and solver settings: one frozen dataclass each.

Every field carries its unit, a description and a validity rule in its metadata. The FMU's
start values, its variable descriptions and unit definitions, the analysis defaults and the
error messages for bad input are all derived from these fields, so each number lives here once.

Defaults describe the pendulum built in the seed report (section 3): m1 = 301 g, m2 = 297 g;
the rod lengths are the ones measured from the report's camera track (Table 1,
``data/seed_table1.csv``): a least-squares circle fit of the upper mass gives
l1 = 0.2964 m (scatter 0.5 mm) and the mean distance between the two masses l2 = 0.1971 m
(scatter 3.9 mm); ``tests/test_parameters.py`` recomputes both from the data.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from types import MappingProxyType
from typing import Any


class ParameterError(ValueError):
    """A parameter, start value or setting is out of its valid range.

    The message names the variable, its value and unit, and the rule it breaks.
    """


def spec(
    default: Any,
    unit: str,
    description: str,
    *,
    rule: str = "finite",
) -> Any:
    """Declare a dataclass field with its unit, description and validity rule.

    ``rule`` is one of ``"finite"``, ``"positive"`` (finite and > 0), ``"nonnegative"``
    (finite and >= 0), ``"count"`` (a whole number >= 1: an FMI Integer), ``"angle"`` (a start angle:
    at most :data:`MAX_START_ANGLE` in size), ``"bool"`` or ``"str"``.
    """
    return field(default=default, metadata={"unit": unit, "description": description, "rule": rule})


COUNT_MAX = 2**31 - 1  # a count is an FMI Integer (fmi2Integer, fmi3Int32): 32 bits
MAX_START_ANGLE = 1e4
"""Largest start angle [rad] in size (about 1600 turns): the one rule for a start angle (:func:`check_start_angle`).
The solver's error control is relative to the state's size (atol + rtol |phi|), so an angle of 1e300 rad makes every
error look small and the run is garbage (its energy rose from 3 J to 2438 J without friction before the step size
underflowed). At 1e4 rad a double's spacing is 1.8e-12 rad and rtol = 1e-9 allows 1e-5 rad per step: still a
meaningful angle."""
START_ANGLES = ("phi1_0", "phi2_0")
"""The start angles: the parameters :func:`check_start_angle` checks."""


def check_value(name: str, value: Any, unit: str, rule: str) -> None:
    """Raise :class:`ParameterError` if ``value`` breaks ``rule``."""
    shown = f"{name} = {value!r}" + (f" {unit}" if unit and unit != "1" else "")
    if rule == "bool":
        if not isinstance(value, bool):
            raise ParameterError(f"invalid {shown}: must be a Boolean")
        return
    if rule == "str":
        if not isinstance(value, str):
            raise ParameterError(f"invalid {shown}: must be a string")
        return
    if rule == "count":
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= COUNT_MAX:
            raise ParameterError(f"invalid {shown}: must be a whole number from 1 to {COUNT_MAX}")
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"invalid {shown}: must be a real number")
    if not math.isfinite(value):
        raise ParameterError(f"invalid {shown}: must be finite")
    if rule == "positive" and not value > 0.0:
        raise ParameterError(f"invalid {shown}: must be > 0")
    if rule == "nonnegative" and not value >= 0.0:
        raise ParameterError(f"invalid {shown}: must be >= 0")
    if rule == "angle":
        check_start_angle(name, value)


def check_start_angle(name: str, value: Any) -> None:
    """The one rule for a start angle (``phi1_0``, ``phi2_0`` [rad]), the same in the FMU, the CLI and the app: any
    finite real number from -:data:`MAX_START_ANGLE` to +:data:`MAX_START_ANGLE` rad. Angles are 2 pi-periodic, so
    phi and phi + 2 pi k start the same motion; the start angle is used as given, not wrapped, so the outputs
    ``phi1``, ``phi2`` (unwrapped: they count the turns) start from it. That lets a run continue another's end state
    or start an inverted pendulum at pi + 0.05 rad. Raises :class:`ParameterError` naming ``name`` and ``value``."""
    shown = f"{name} = {value!r} rad"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"invalid {shown}: must be a real number")
    if not abs(value) <= MAX_START_ANGLE:  # NaN fails too
        raise ParameterError(f"invalid {shown}: a start angle must be a finite number from -{MAX_START_ANGLE:g} to "
                             f"{MAX_START_ANGLE:g} rad (the solver's error control is relative to it); angles are "
                             "2 pi-periodic, so give it within (-pi, pi] or near the state you continue")


class Validated:
    """Mixin: validate every field against its declared rule after construction."""

    def __post_init__(self) -> None:
        for f in fields(self):  # type: ignore[arg-type]
            check_value(f.name, getattr(self, f.name), f.metadata["unit"], f.metadata["rule"])


@dataclass(frozen=True)
class PendulumParameters(Validated):
    """Physical parameters of the planar double pendulum: a bob on each link, optionally a rod.

    Angles are measured from the downward vertical; y points up, the pivot is the origin. Each
    link may carry a uniform rod (plate) of mass ``m_rod`` and length ``L_rod`` centred between its
    two joints (:mod:`double_pendulum.model.links`); the default rod mass 0 is the point-mass
    pendulum on massless rods. ``L_rod`` also sets the length the rod drag acts on
    (:class:`AirDragParameters`), whatever the rod's mass; its default 0 means "the plate spans
    joint to joint" (``L = l``, :func:`~double_pendulum.model.links.plate_lengths`), so the default
    parameters are the point-mass model bit for bit, rod drag included. :data:`SEED_RIGID_LINKS`
    holds the seed pendulum's plates (35 cm and 25 cm, overhanging the joints).
    """

    m1: float = spec(0.301, "kg", "mass of the upper bob", rule="positive")
    m2: float = spec(0.297, "kg", "mass of the lower bob", rule="positive")
    l1: float = spec(0.2964, "m", "length of the upper rod (pivot to upper bob)", rule="positive")
    l2: float = spec(0.1971, "m", "length of the lower rod (upper bob to lower bob)", rule="positive")
    g: float = spec(9.81, "m/s2", "gravitational acceleration", rule="positive")
    m_rod1: float = spec(0.0, "kg", "mass of the upper rod (uniform plate; 0: massless)", rule="nonnegative")
    m_rod2: float = spec(0.0, "kg", "mass of the lower rod (uniform plate; 0: massless)", rule="nonnegative")
    L_rod1: float = spec(
        0.0,
        "m",
        "length of the upper rod's plate, centred between pivot and upper bob (0: pivot to bob, L = l1)",
        rule="nonnegative",
    )
    L_rod2: float = spec(
        0.0,
        "m",
        "length of the lower rod's plate, centred between the two bobs (0: bob to bob, L = l2)",
        rule="nonnegative",
    )


SEED_RIGID_LINKS: Mapping[str, float] = MappingProxyType(
    {"m_rod1": 0.070, "m_rod2": 0.070, "L_rod1": 0.35, "L_rod2": 0.25}
)
"""Rod parameters of the seed's pendulum (section 3.1 and 4.2.3 of the report), as start values.

Use ``PendulumParameters(**SEED_RIGID_LINKS)`` or pass them to the FMU with the other start
values. Assumptions, from the report's words:

* "70 g pro Stab": 70 g per *member*. The upper member is two thin plates, one on each side of
  the pendulum (35 g each), the lower member one thicker plate: ``m_rod1 = m_rod2 = 0.070`` kg.
  The report's total "0.7 kg including the acrylic plates" supports this reading: with the bobs'
  0.598 kg it gives 0.738 kg, where 70 g per plate (three plates) would give 0.808 kg. The
  rounded 0.7 kg alone would mean about 0.10 kg of acrylic: the rod mass is uncertain by about
  +-0.03 kg a member.
* Plate lengths 35 cm (upper) and 25 cm (lower), section 4.2.3; each plate centred between its
  joints, so with the track's l1 = 0.2964 m and l2 = 0.1971 m it overhangs both joints by
  2.7 cm and 2.6 cm.
* Uniform plates, widths neglected (a plate of width w in the swing plane would add
  m w^2 / 12 to its moment of inertia: 1.5e-5 kg m^2 for w = 5 cm, 0.03 % of J1 and 0.1 % of J2);
  the bobs' masses m1, m2 are taken as the bobs alone, bearings and screws included.
"""


@dataclass(frozen=True)
class AirDragParameters(Validated):
    """Quadratic air drag (seed eq. 23), F = -1/2 rho c_W A |v| v, on the bobs and optionally the rods.

    Defaults: rho = 1.2 kg/m^3 is the seed's number (section 4.2.3). The rods are the acrylic plates
    of section 3.1; they swing in their own plane, so the air meets them edge-on: the frontal width
    is the plates' thickness (upper member two plates 4 mm thick, 8 mm; lower one plate 6 mm) and
    the flow runs across the plate's width. The seed's c_W = 2 is the face-on value of a flat
    plate (flow normal to its face); a thin rectangular section met edge-on, its chord several
    times its thickness, has c_W of about 1 to 1.3 on the thickness, so ``cw_rod`` defaults to 1.2.
    ``loss_identification`` fits a common factor on all drag coefficients to the measured energy. The
    report gives no bob geometry: each bob's frontal area defaults to the seed's example area
    1.5e-3 m^2 (a 300 g steel cylinder of about 3 cm x 5 cm seen from the side) with c_W = 1
    (a short cylinder in cross flow at Reynolds numbers of 1e3..1e4). The rod drag acts over each
    plate's whole length ``L_rod1``, ``L_rod2`` (:class:`PendulumParameters`; 0: joint to joint),
    centred between its joints, overhangs included.
    """

    air_drag: bool = spec(False, "", "switch: quadratic air drag on the bobs", rule="bool")
    rho_air: float = spec(1.2, "kg/m3", "density of air", rule="nonnegative")
    cw: float = spec(1.0, "1", "drag coefficient of the bobs", rule="nonnegative")
    A1: float = spec(1.5e-3, "m2", "frontal area of the upper bob", rule="nonnegative")
    A2: float = spec(1.5e-3, "m2", "frontal area of the lower bob", rule="nonnegative")
    rod_drag: bool = spec(False, "", "switch: also drag on the rods (needs air_drag)", rule="bool")
    cw_rod: float = spec(
        1.2, "1", "drag coefficient of the rods (plates met edge-on, on their thickness; face-on would be 2)",
        rule="nonnegative",
    )
    d_rod1: float = spec(8e-3, "m", "frontal width of the upper rod (two 4 mm plates)", rule="nonnegative")
    d_rod2: float = spec(6e-3, "m", "frontal width of the lower rod (one 6 mm plate)", rule="nonnegative")


@dataclass(frozen=True)
class BearingParameters(Validated):
    """Rolling friction in the ball bearings (seed eq. 24, F_R = c_R F_N) as a joint torque.

    Torque magnitude c_R r_b |F_joint| with F_joint the reaction force the joint carries, opposing
    the joint's relative angular velocity (pivot: omega1, elbow: omega2 - omega1); the sign
    function is regularised as tanh(omega / omega_reg). Defaults: c_R = 1e-3 (the seed's range
    0.5e-3 to 1e-3 for ball bearings), r_b = 4 mm (the bore radius of a 608 bearing).
    An optional viscous torque b_v * omega per joint adds to it.

    Bearing drag (``bearing_drag``, its own switch): a load-independent friction torque
    tau_b tanh(omega / omega_reg) per joint, the drag of the bearing's seals and grease (of the
    order of 1 N mm for sealed ball bearings), with the same regularisation speed. It dissipates
    tau_b |omega| tanh(|omega| / omega_reg), booked separately as ``W_bearing_drag``.
    """

    bearing_friction: bool = spec(False, "", "switch: rolling friction in both bearings", rule="bool")
    c_R1: float = spec(1e-3, "1", "rolling friction coefficient of the pivot bearing", rule="nonnegative")
    c_R2: float = spec(1e-3, "1", "rolling friction coefficient of the elbow bearing", rule="nonnegative")
    r_b1: float = spec(4e-3, "m", "friction radius of the pivot bearing", rule="nonnegative")
    r_b2: float = spec(4e-3, "m", "friction radius of the elbow bearing", rule="nonnegative")
    omega_reg: float = spec(
        1e-3, "rad/s", "regularisation speed of the friction sign function", rule="positive"
    )
    b_v1: float = spec(0.0, "N.m.s/rad", "viscous friction of the pivot bearing", rule="nonnegative")
    b_v2: float = spec(0.0, "N.m.s/rad", "viscous friction of the elbow bearing", rule="nonnegative")
    bearing_drag: bool = spec(
        False, "", "switch: load-independent drag torque in both bearings (seals, grease)", rule="bool"
    )
    tau_b1: float = spec(0.0, "N.m", "load-independent drag torque of the pivot bearing", rule="nonnegative")
    tau_b2: float = spec(0.0, "N.m", "load-independent drag torque of the elbow bearing", rule="nonnegative")


@dataclass(frozen=True)
class SuspensionParameters(Validated):
    """Damped suspension carrying the pivot (seed 2.4.3): mass M_s on springs and dampers.

    The pivot coordinates xs, ys are displacements from the static equilibrium (the spring
    preload carries the weight of everything). The seed gives no numbers: the defaults are an
    illustrative stiff table mount; ``suspension_transfer`` identifies values from the measured
    energy decay.
    """

    suspension: bool = spec(False, "", "switch: the pivot sits on a damped suspension", rule="bool")
    suspension_x: bool = spec(True, "", "suspension moves horizontally (with suspension on)", rule="bool")
    suspension_y: bool = spec(True, "", "suspension moves vertically (with suspension on)", rule="bool")
    M_s: float = spec(2.0, "kg", "mass of the suspension (moving with the pivot)", rule="positive")
    k_x: float = spec(2e4, "N/m", "horizontal spring stiffness of the suspension", rule="nonnegative")
    k_y: float = spec(2e4, "N/m", "vertical spring stiffness of the suspension", rule="nonnegative")
    c_x: float = spec(20.0, "N.s/m", "horizontal damping of the suspension", rule="nonnegative")
    c_y: float = spec(20.0, "N.s/m", "vertical damping of the suspension", rule="nonnegative")


@dataclass(frozen=True)
class InitialState(Validated):
    """Start values of the rod angles and their rates (the suspension starts at rest)."""

    phi1_0: float = spec(1.0, "rad", "initial angle of the upper rod from the downward vertical", rule="angle")
    phi2_0: float = spec(1.0, "rad", "initial angle of the lower rod from the downward vertical", rule="angle")
    omega1_0: float = spec(0.0, "rad/s", "initial angular velocity of the upper rod")
    omega2_0: float = spec(0.0, "rad/s", "initial angular velocity of the lower rod")

    def as_list(self) -> list[float]:
        """Return ``[phi1, phi2, omega1, omega2]`` (rad, rad, rad/s, rad/s)."""
        return [self.phi1_0, self.phi2_0, self.omega1_0, self.omega2_0]


@dataclass(frozen=True)
class SuspensionLoad(Validated):
    """The static load of the stand-alone ``Suspension`` FMU (see :mod:`double_pendulum.model.suspension`).

    Its coordinates are displacements from the static equilibrium under this load, so a load
    equal to it leaves the mass at rest. The default is the weight of the default pendulum
    hanging at rest, the force it exerts on its pivot: -(m1 + m2) g.
    """

    F_static_y: float = spec(
        -(PendulumParameters.m1 + PendulumParameters.m2) * PendulumParameters.g,
        "N",
        "static vertical load on the suspension mass (default: -(m1 + m2) g of the default pendulum)",
    )
