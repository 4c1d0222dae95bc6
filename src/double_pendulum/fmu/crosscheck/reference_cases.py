"""The reference cases: one per FMU the FMI Cross-Check tree holds, and the FMUs they run.

Each :class:`ReferenceCase` is a run of one FMU as the FMI Cross-Check rules (v4.1, section 9.1.4) ask
an exporting tool to document it: options (``_ref.opt``: start, stop, step, tolerance), the input
signals (``_in.csv``, every input of the FMU, piecewise linear) and at most ten outputs in the
reference result (``_ref.csv``). The Cross-Check's FMI Compliance Checker can set no start value (its
input file sets what it holds before every step, and the FMU refuses fixed parameters then), nor can
fmpy's cross-check runner, so a case whose scene is not the FMU's default runs an FMU with the scene
baked in as its defaults (:mod:`double_pendulum.fmu.presets`):

=====================  =================  ==================================================================
model                  variants           what it tests
=====================  =================  ==================================================================
DoublePendulum         2.0 cs, 3.0 cs     the FMU as built, driven through its inputs: the pivot oscillates
                                          horizontally (position, velocity, acceleration), a torque pulse
DoublePendulum         3.0 me             the FMU as built, free swing from its default start
DoublePendulumChaotic  2.0 cs, 3.0 cs/me  frictionless from the chaotic start 2 rad / 2 rad (short horizon)
DoublePendulumFriction 2.0 cs, 3.0 cs/me  every loss on: air drag on bobs and rods, bearing friction and drag,
                                          the seed's rods
Suspension             2.0 cs             the FMU as built, load pulses through its inputs
PendulumOnSuspension   2.0 cs             the container: the two FMUs coupled, from 1.5 rad / 1.5 rad
=====================  =================  ==================================================================

The reference of a case is its run in fmpy at tight tolerance (:data:`TIGHT`: the FMU's own
integrator, or CVode under Model Exchange), made by ``data/reference/fmu/make_fmu_references.py``
(:mod:`double_pendulum.fmu.crosscheck.reference_runs`) and committed; ``double-pendulum cross-check`` writes the
tree (:mod:`double_pendulum.fmu.crosscheck.tree`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...component.suspension import INPUT_START
from ...model.inputs import INPUT_NAMES

TIGHT = {"rtol": 1e-12, "atol": 1e-14}
"""The FMU's integrator settings of a reference run (for FMUs that do not have them baked in)."""
ME_REFERENCE_TOLERANCE = 1e-12  # CVode's relative tolerance of a Model Exchange reference run
CHAOTIC = {"phi1_0": 2.0, "phi2_0": 2.0, **TIGHT}
FRICTION = {"phi1_0": 1.5, "phi2_0": 0.5, "air_drag": True, "rod_drag": True, "bearing_friction": True,
            "bearing_drag": True, "tau_b1": 1e-3, "tau_b2": 1e-3, "m_rod1": 0.07, "m_rod2": 0.07,
            "L_rod1": 0.35, "L_rod2": 0.25, **TIGHT}
CONTAINER_VALUES = {"phi1_0": 1.5, "phi2_0": 1.5, **TIGHT}
"""The container's scene (monolith names, split by :func:`double_pendulum.fmu.masters.coupling.split_values`)."""
PIVOT_AMPLITUDE, PIVOT_FREQUENCY = 0.02, 1.5  # [m], [Hz] of the driven case's horizontal pivot motion


def pivot_drive(t: float) -> dict[str, float]:
    """The driven case's inputs at ``t`` [s]: the pivot on ``x = A sin(2 pi f t)`` with its velocity and
    acceleration, and a torque pulse of 0.05 N.m on the upper rod from 1 s to 2 s (0.1 s ramps)."""
    w = 2.0 * math.pi * PIVOT_FREQUENCY
    pulse = min(max((t - 0.9) / 0.1, 0.0), 1.0) * min(max((2.1 - t) / 0.1, 0.0), 1.0)
    return {"pivot_x": PIVOT_AMPLITUDE * math.sin(w * t), "pivot_vx": PIVOT_AMPLITUDE * w * math.cos(w * t),
            "pivot_ax": -PIVOT_AMPLITUDE * w * w * math.sin(w * t), "tau1": 0.05 * pulse}


def knots(points: Sequence[tuple[float, Mapping[str, float]]]) -> Callable[[float], dict[str, float]]:
    """The piecewise linear signal through ``points`` (time [s], values), held outside them."""
    def signal(t: float) -> dict[str, float]:
        for (t0, v0), (t1, v1) in zip(points, points[1:]):
            if t0 <= t <= t1:
                share = (t - t0) / (t1 - t0)
                return {name: v0[name] + share * (v1[name] - v0[name]) for name in v0}
        return dict(points[0][1] if t < points[0][0] else points[-1][1])
    return signal


STATIC = INPUT_START["F_y"]  # [N] the Suspension's static load (its default F_y)
LOAD_PULSES = ((0.0, 0.1, 0.11, 0.35, 0.36, 0.45, 0.46, 0.65, 0.66, 0.8),
               {"F_x": (0.0, 0.0, 2.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
                "F_y": (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -3.0, -3.0, 0.0, 0.0)})


def load_pulses() -> list[tuple[float, dict[str, float]]]:
    """The Suspension case's load: 2 N sideways from 0.1 s to 0.35 s, 3 N more down from 0.45 s to 0.65 s."""
    times, values = LOAD_PULSES
    return [(t, {"F_x": values["F_x"][k], "F_y": STATIC + values["F_y"][k]}) for k, t in enumerate(times)]


@dataclass(frozen=True)
class ReferenceCase:
    """One model of the cross-check tree: its FMU, the run and what it shows."""

    model: str  # Model_Name: the FMU's file name (without .fmu) and its folder
    fmi_version: str  # "2.0" or "3.0"
    fmi_type: str  # "cs" or "me"
    source: str  # the FMU it is built as: "DoublePendulum", "Suspension" or "PendulumOnSuspension"
    baked: Mapping[str, Any]  # start values baked into the FMU ({}: the FMU as `build` writes it)
    stop_time: float  # [s]
    step_size: float  # [s] communication step (CS) or output interval (ME), also the reference's rows
    outputs: tuple[str, ...]  # the reference result's columns after time (at most 10)
    description: str
    input_signal: Callable[[float], dict[str, float]] | None = None  # inputs not at their start values
    input_times: tuple[float, ...] = ()  # the rows of _in.csv (with the start and stop time)
    reference_start: Mapping[str, Any] = field(default_factory=dict)  # set only in the reference run

    @property
    def folder(self) -> Path:
        """``<fmi_version>/<fmi_type>/<model>``, below ``fmus/.../<tool>/<version>`` in the tree."""
        return Path(self.fmi_version, self.fmi_type, self.model)

    @property
    def rel_tol(self) -> float:
        """The ``RelTol`` of ``_ref.opt``: the tolerance that made the reference, CVode's under Model Exchange
        (:data:`ME_REFERENCE_TOLERANCE`), the FMU's own integrator's under Co-Simulation."""
        if self.fmi_type == "me":
            return ME_REFERENCE_TOLERANCE
        return float({**self.baked, **self.reference_start}.get("rtol", 1e-9))


# Every output of the FMU first (fmpy's cross-check marks a reference that leaves one out), then signals among
# the locals. Not diagnostics: energy_residual (integration error) and a conserved E_total depend on the importer's
# tolerance by design, and the cross-check's band is 10 % of a signal's range: the frictionless cases leave E_total
# out (the one output they do).
PENDULUM_OUTPUTS = ("phi1", "phi2", "omega1", "omega2", "F_pivot_x", "F_pivot_y", "x1", "y1", "x2", "y2")
DRIVEN_OUTPUTS = ("phi1", "phi2", "omega1", "omega2", "x2", "y2", "F_pivot_x", "F_pivot_y", "W_input", "E_total")
FRICTION_OUTPUTS = ("phi1", "phi2", "omega1", "omega2", "E_total", "F_pivot_x", "F_pivot_y", "W_air", "W_bearing",
                    "W_bearing_drag")
SUSPENSION_OUTPUTS = ("x", "y", "vx", "vy", "ax", "ay", "E_suspension", "W_suspension", "W_in", "P_in")
CONTAINER_OUTPUTS = ("DoublePendulum.phi1", "DoublePendulum.phi2", "DoublePendulum.F_pivot_x",
                     "DoublePendulum.F_pivot_y", "Suspension.x", "Suspension.y", "Suspension.vx", "Suspension.vy",
                     "Suspension.ax", "Suspension.ay")

DRIVEN = ("the FMU as `double-pendulum build` writes it, driven through its inputs (_in.csv): the pivot moves "
          f"horizontally on x = {PIVOT_AMPLITUDE} m sin(2 pi {PIVOT_FREQUENCY} Hz t) (position, velocity and "
          "acceleration given, sampled every 10 ms, linear in between), and a torque pulse of 0.05 N.m on the upper "
          "rod from 1 s to 2 s; from the FMU's default start (1 rad, 1 rad, frictionless)")
CHAOTIC_TEXT = ("the frictionless pendulum from the chaotic start phi1 = phi2 = 2 rad (baked in as the FMU's "
                "defaults, with its integrator at rtol 1e-12); a short horizon, as the trajectory is chaotic")
FRICTION_TEXT = ("every loss on (air drag on bobs and rods, rolling friction and drag torques in both bearings) "
                 "with the seed's rods, from 1.5 rad / 0.5 rad (baked in as the FMU's defaults, rtol 1e-12): "
                 "the works W_air, W_bearing, W_bearing_drag and the closed energy budget")


def _cases() -> tuple[ReferenceCase, ...]:
    driven_times = tuple(round(0.01 * k, 2) for k in range(501))
    cases = [
        ReferenceCase("DoublePendulum", "2.0", "cs", "DoublePendulum", {}, 5.0, 0.01, DRIVEN_OUTPUTS, DRIVEN,
                      pivot_drive, driven_times, TIGHT),
        ReferenceCase("DoublePendulumChaotic", "2.0", "cs", "DoublePendulum", CHAOTIC, 3.0, 0.01,
                      PENDULUM_OUTPUTS, CHAOTIC_TEXT),
        ReferenceCase("DoublePendulumFriction", "2.0", "cs", "DoublePendulum", FRICTION, 5.0, 0.01,
                      FRICTION_OUTPUTS, FRICTION_TEXT),
        ReferenceCase("Suspension", "2.0", "cs", "Suspension", {}, 0.8, 0.001, SUSPENSION_OUTPUTS,
                      "the FMU as `double-pendulum build` writes it, loaded through its inputs (_in.csv): 2 N "
                      "sideways from 0.1 s to 0.35 s, 3 N more down from 0.45 s to 0.65 s (10 ms ramps), on top of "
                      "the static load; the load is held over each 1 ms step (its default experiment's step, which "
                      "fmpy's cross-check runner uses), so the result depends on that step",
                      knots(load_pulses()), LOAD_PULSES[0], TIGHT),
        ReferenceCase("PendulumOnSuspension", "2.0", "cs", "PendulumOnSuspension", CONTAINER_VALUES, 2.0, 0.01,
                      CONTAINER_OUTPUTS, "the container FMU: DoublePendulum on the Suspension, coupled every 1 ms "
                      "(the force passed first, inputs held over the macro step), from phi1 = phi2 = 1.5 rad "
                      "(its start values, the pendulum's integrator at rtol 1e-12)"),
        ReferenceCase("DoublePendulum", "3.0", "cs", "DoublePendulum", {}, 5.0, 0.01, DRIVEN_OUTPUTS,
                      DRIVEN + "; Co-Simulation runs the FMI 2 FMU's component: the same numbers",
                      pivot_drive, driven_times, TIGHT),
        ReferenceCase("DoublePendulumChaotic", "3.0", "cs", "DoublePendulum", CHAOTIC, 3.0, 0.01,
                      PENDULUM_OUTPUTS, CHAOTIC_TEXT),
        ReferenceCase("DoublePendulumFriction", "3.0", "cs", "DoublePendulum", FRICTION, 5.0, 0.01,
                      FRICTION_OUTPUTS, FRICTION_TEXT),
        ReferenceCase("DoublePendulum", "3.0", "me", "DoublePendulum", {}, 5.0, 0.01, PENDULUM_OUTPUTS,
                      "Model Exchange of the FMU as `double-pendulum build` writes it: the free swing from its "
                      "default start (1 rad, 1 rad, frictionless), inputs at 0 (_in.csv); the host integrates"),
        ReferenceCase("DoublePendulumChaotic", "3.0", "me", "DoublePendulum", CHAOTIC, 3.0, 0.01,
                      PENDULUM_OUTPUTS, "Model Exchange: " + CHAOTIC_TEXT.replace(", with its integrator at rtol "
                                                                                  "1e-12", "")),
        ReferenceCase("DoublePendulumFriction", "3.0", "me", "DoublePendulum", FRICTION, 5.0, 0.01,
                      FRICTION_OUTPUTS, "Model Exchange: " + FRICTION_TEXT.replace(", rtol 1e-12", "")
                      + " (regularised, smooth friction: no events)"),
    ]
    return tuple(cases)


CASES = _cases()


def input_names(case: ReferenceCase) -> tuple[str, ...]:
    """Every input of the case's FMU (the container has none)."""
    if case.source == "DoublePendulum":
        return INPUT_NAMES
    if case.source == "Suspension":
        return tuple(INPUT_START)
    return ()


def input_table(case: ReferenceCase) -> list[tuple[float, ...]] | None:
    """The rows of ``_in.csv`` (time, then :func:`input_names`), or None for an FMU without inputs.

    Inputs the signal does not drive stay at their start values (the Suspension's ``F_y``: its static
    load); an undriven case holds them over two rows, its start and stop time."""
    names = input_names(case)
    if not names:
        return None
    start = {name: INPUT_START.get(name, 0.0) for name in names}
    times = case.input_times or (0.0, case.stop_time)
    rows = []
    for t in times:
        values = {**start, **(case.input_signal(t) if case.input_signal else {})}
        rows.append((t, *(values[name] for name in names)))
    return rows


def fmu_file(case: ReferenceCase) -> str:
    """The case's FMU in a folder of built case FMUs
    (:func:`double_pendulum.fmu.crosscheck.reference_runs.build_case_fmus`): ``<fmi_version>/<model>.fmu``
    (an FMI 3 FMU serves both its interfaces)."""
    return f"{case.fmi_version}/{case.model}.fmu"
