"""``terminalsAndIcons/terminalsAndIcons.xml``: the ports a tool wires, grouped, and where they sit on the icon.

FMI 3.0 (section 2.4.9, schema ``fmi3TerminalsAndIcons.xsd``) and, back-ported, FMI 2.0.4 (section
2.3, "Terminals and Icons": the same file, its ``fmiVersion`` naming the FMI 3.0 definition it follows)
let an FMU group variables into terminals for a graphical tool. Every FMU of the project carries one
(the same ``fmiVersion="3.0"`` file for FMI 2 and FMI 3), made from the variables it has:

``pivot`` (DoublePendulum) and ``mount`` (Suspension), ``plug``, kind :data:`MOUNT_KIND`
    the coupling of :mod:`double_pendulum.fmu.masters.coupling`: the pivot's motion in and the pivot force out
    (DoublePendulum), the mass's motion out and the load in (Suspension). Member names are the
    Suspension's variable names (``x, y, vx, vy, ax, ay, F_x, F_y``), so a tool that matches members by
    name connects ``DoublePendulum.pivot`` to ``Suspension.mount`` as the container does.
``joint_torques`` (DoublePendulum), ``bus``
    the motor torques ``tau1`` at the pivot, ``tau2`` at the elbow.
``angles`` (DoublePendulum, the container), ``bus``
    the rod angles and rates a controller reads.

Each terminal has a picture (:func:`double_pendulum.fmu.carries.icons.terminal_icon`) on the icon's edge:
pivot and mount at the top, torques on the left, angles on the right. Terminals naming variables the
FMU lacks are left out (the container has no inputs and only the angles).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import NamedTuple
from xml.etree import ElementTree as ET

from ..masters.coupling import FORCE_CONNECTIONS, MOTION_CONNECTIONS

FILE = "terminalsAndIcons/terminalsAndIcons.xml"
FMI_VERSION = "3.0"  # the FMI version whose definition the file follows, also in an FMI 2.0 FMU
MOUNT_KIND = "_double-pendulum-fmu_PlanarMount"
EXTENT = (-100.0, -100.0, 100.0, 100.0)  # the icon's coordinate system (FMI's default)
SCALE_TO_MM = 0.1
SIZE = 20.0  # a terminal's picture, in the icon's coordinates
PLACES = {"top": (0.0, 100.0), "left": (-100.0, 0.0), "right": (100.0, 0.0)}
COLOURS = {"mount": "31 59 87", "torque": "192 57 43", "sensor": "31 59 87"}


class Terminal(NamedTuple):
    """One terminal: its name, matching rule, kind, picture, place and members ``(variable, member name)``."""

    name: str
    matching_rule: str
    kind: str | None
    icon: str  # a kind of icons.terminal_icon
    place: str  # a key of PLACES
    description: str
    members: tuple[tuple[str, str], ...]


def _mount(pendulum_side: bool) -> tuple[tuple[str, str], ...]:
    """The coupling's members, named by the Suspension's variables: (variable of this FMU, member name)."""
    pairs = [*((b, a) for a, b in MOTION_CONNECTIONS), *FORCE_CONNECTIONS]  # (pendulum variable, suspension variable)
    return tuple((mine if pendulum_side else theirs, theirs) for mine, theirs in pairs)


TERMINALS: tuple[Terminal, ...] = (
    Terminal("pivot", "plug", MOUNT_KIND, "mount", "top",
             "where the pendulum hangs: the pivot's motion in (position, velocity, acceleration), the force of the "
             "pendulum on its pivot out; connects to Suspension.mount", _mount(True)),
    Terminal("mount", "plug", MOUNT_KIND, "mount", "top",
             "the suspension mass as a mount: its motion out, the force of the load in; connects to "
             "DoublePendulum.pivot", _mount(False)),
    Terminal("joint_torques", "bus", None, "torque", "left",
             "motor torques: tau1 on the upper rod at the pivot, tau2 of the upper on the lower rod at the elbow",
             (("tau1", "tau1"), ("tau2", "tau2"))),
    Terminal("angles", "bus", None, "sensor", "right", "rod angles and angular velocities, for a controller",
             (("phi1", "phi1"), ("phi2", "phi2"), ("omega1", "omega1"), ("omega2", "omega2"))),
)


def terminals_for(variables: Iterable[str], prefix: str = "") -> list[Terminal]:
    """The terminals of an FMU with ``variables``: each with the members it has (``prefix`` + variable: the
    container's ``DoublePendulum.``), a ``plug`` only if it has them all, a ``bus`` if it has any (its
    description then names the members it has)."""
    names = set(variables)
    found = []
    for terminal in TERMINALS:
        members = tuple((prefix + variable, member) for variable, member in terminal.members
                        if prefix + variable in names)
        if members and (terminal.matching_rule != "plug" or len(members) == len(terminal.members)):
            description = terminal.description
            if len(members) < len(terminal.members):  # a bus with some of its members: say which it has
                description += f" (this FMU has {', '.join(member for _, member in members)} only)"
            found.append(terminal._replace(members=members, description=description))
    return found


def terminals_xml(terminals: Sequence[Terminal]) -> bytes:
    """The ``terminalsAndIcons.xml`` of an FMU with ``terminals`` and an icon over the whole extent."""
    root = ET.Element("fmiTerminalsAndIcons", fmiVersion=FMI_VERSION)
    graphics = ET.SubElement(root, "GraphicalRepresentation")
    x1, y1, x2, y2 = (repr(v) for v in EXTENT)
    ET.SubElement(graphics, "CoordinateSystem", x1=x1, y1=y1, x2=x2, y2=y2,
                  suggestedScalingFactorTo_mm=repr(SCALE_TO_MM))
    ET.SubElement(graphics, "Icon", x1=x1, y1=y1, x2=x2, y2=y2)
    if terminals:
        group = ET.SubElement(root, "Terminals")
        for terminal in terminals:
            attributes = {"name": terminal.name, "matchingRule": terminal.matching_rule}
            if terminal.kind:
                attributes["terminalKind"] = terminal.kind
            element = ET.SubElement(group, "Terminal", attributes, description=terminal.description)
            for variable, member in terminal.members:
                ET.SubElement(element, "TerminalMemberVariable", variableName=variable, memberName=member,
                              variableKind="signal")
            cx, cy = PLACES[terminal.place]
            ET.SubElement(element, "TerminalGraphicalRepresentation", defaultConnectionColor=COLOURS[terminal.icon],
                          defaultConnectionStrokeSize="1.0", x1=repr(cx - SIZE / 2), y1=repr(cy - SIZE / 2),
                          x2=repr(cx + SIZE / 2), y2=repr(cy + SIZE / 2), iconBaseName=terminal.icon)
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def icon_files(terminals: Sequence[Terminal]) -> set[str]:
    """The pictures ``terminals`` reference: ``terminalsAndIcons/<icon>.png``."""
    return {f"terminalsAndIcons/{terminal.icon}.png" for terminal in terminals}
