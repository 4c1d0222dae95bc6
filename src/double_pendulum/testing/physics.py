r"""Physics a double pendulum's result must keep, as assertions that say what went wrong with numbers.

The physics is the project's one copy (:mod:`double_pendulum.model`): the energy budget is the one the FMU reports
as ``energy_residual`` (:mod:`double_pendulum.model.outputs`),

.. math::

    E_\mathrm{total}(t) + W_\mathrm{air} + W_\mathrm{bearing} + W_\mathrm{bearing\_drag} + W_\mathrm{suspension}
    - W_\mathrm{input} - E_\mathrm{total}(0) = 0 \quad [\mathrm{J}],

recomputed here from the result's columns, and the small oscillations are the normal modes of the pendulum
linearised about its hanging rest (:func:`double_pendulum.model.dynamics.linearised_normal_modes`), their periods
:math:`T_i = 2\pi/\omega_i` [s].
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..model.dynamics import linearised_normal_modes
from ..model.outputs import WORK_NAMES
from ..model.parameters import PendulumParameters
from .results import Result

ENERGY_COLUMNS: tuple[str, ...] = ("E_total", *WORK_NAMES, "W_input")
"""The columns the energy budget needs: ask ``simulate(outputs=[..., *ENERGY_COLUMNS])`` for them."""

MODES = ("slow", "fast")
"""The normal modes by name, the slower (both rods swing together) first."""


def _needs(result: Result, names: tuple[str, ...] | list[str], what: str) -> None:
    __tracebackhide__ = True  # pytest shows the test's line, not this one
    missing = [name for name in names if name not in result]
    if missing:
        raise AssertionError(f"{what} needs the columns {', '.join(missing)}, which {result.label} lacks (ask "
                             f"simulate for outputs=[..., {', '.join(map(repr, missing))}])")


def assert_energy_budget_closes(result: Result, rtol: float = 1e-6, atol: float = 0.0) -> float:
    """Assert that the energy budget closes (module docstring) at every row of ``result`` within
    ``max(atol, rtol * E)`` [J], E the largest of :math:`|E_\\mathrm{total}|` and the works; returns the largest
    :math:`|\\mathrm{residual}|` [J]."""
    __tracebackhide__ = True  # pytest shows the test's line, not this one
    _needs(result, ENERGY_COLUMNS, "the energy budget")
    energy = np.asarray(result["E_total"], dtype=float)
    works = sum(np.asarray(result[name], dtype=float) for name in WORK_NAMES)
    residual = energy + works - np.asarray(result["W_input"], dtype=float) - energy[0]
    scale = max(float(np.max(np.abs(energy))), *(float(np.max(np.abs(result[n]))) for n in (*WORK_NAMES, "W_input")))
    bound = max(atol, rtol * scale)
    k = int(np.argmax(np.abs(residual)))
    worst = float(abs(residual[k]))
    if worst > bound:
        first = float(result.time[np.argmax(np.abs(residual) > bound)])
        raise AssertionError(
            f"the energy budget of {result.label} does not close: E_total + {' + '.join(WORK_NAMES)} - W_input - "
            f"E_total(0) reaches {residual[k]:.4g} J at t = {result.time[k]:.6g} s (first beyond the bound at t = "
            f"{first:.6g} s); bound max(atol {atol:g} J, rtol {rtol:g} x {scale:.4g} J) = {bound:.4g} J")
    return worst


def assert_energy_never_rises(result: Result, rtol: float = 1e-9, atol: float = 0.0, name: str = "E_total") -> None:
    """Assert that ``result[name]`` [J] never rises from one row to the next by more than
    ``max(atol, rtol * max|E|)``: what friction without a drive must give. A result whose inputs fed work in
    (``W_input`` not zero) is refused, naming how much."""
    __tracebackhide__ = True  # pytest shows the test's line, not this one
    _needs(result, [name], "the energy's fall")
    energy = np.asarray(result[name], dtype=float)
    time = result.time
    if "W_input" in result and float(np.max(np.abs(result["W_input"]))) > 0:
        k = int(np.argmax(np.abs(result["W_input"])))
        raise AssertionError(f"{result.label} is driven: its inputs fed in W_input = {result['W_input'][k]:.4g} J "
                             f"by t = {time[k]:.6g} s, so its energy may rise")
    rises = np.diff(energy)
    bound = max(atol, rtol * float(np.max(np.abs(energy))))
    up = np.flatnonzero(rises > bound)
    if len(up):
        k, first = int(up[np.argmax(rises[up])]), int(up[0])
        raise AssertionError(
            f"{name} of {result.label} rises {len(up)} times of {len(rises)} steps: first by {rises[first]:.4g} J "
            f"between t = {time[first]:.6g} and {time[first + 1]:.6g} s, most by {rises[k]:.4g} J between "
            f"t = {time[k]:.6g} and {time[k + 1]:.6g} s (from {energy[k]:.6g} J); bound max(atol {atol:g} J, "
            f"rtol {rtol:g} x {float(np.max(np.abs(energy))):.4g} J) = {bound:.4g} J")


def assert_conserved(result: Result, name: str = "E_total", rtol: float = 1e-6, scale: float | None = None) -> float:
    """Assert that ``result[name]`` stays within ``rtol`` of its start, relative to ``scale`` (default: the size
    of its start value, else of its largest value); returns the largest relative drift."""
    __tracebackhide__ = True  # pytest shows the test's line, not this one
    _needs(result, [name], f"the conservation of {name}")
    values = np.asarray(result[name], dtype=float)
    if scale is None:
        scale = abs(float(values[0])) or float(np.max(np.abs(values)))
    if not scale > 0:
        raise AssertionError(f"{name} of {result.label} is zero throughout: pass a scale to compare its drift with")
    drift = np.abs(values - values[0]) / scale
    k = int(np.argmax(drift))
    unit = f" {result.unit(name)}" if result.unit(name) else ""
    if drift[k] > rtol:
        first = float(result.time[np.argmax(drift > rtol)])
        raise AssertionError(
            f"{name} of {result.label} is not conserved: it drifts from {values[0]:.8g}{unit} to {values[k]:.8g}"
            f"{unit} at t = {result.time[k]:.6g} s, {drift[k]:.3g} of {scale:.4g}{unit} (first beyond {rtol:g} at "
            f"t = {first:.6g} s)")
    return float(drift[k])


def pendulum_parameters(variables: Mapping[str, Any], start_values: Mapping[str, Any] | None = None
                        ) -> PendulumParameters:
    """The pendulum's parameters (masses, lengths, g, rods) of an FMU: ``variables`` its start values by name (or
    the ``fmu`` fixture's ``variables``, fmpy's variables), ``start_values`` what a run set in their place."""
    values = {}
    for field in dataclasses.fields(PendulumParameters):
        given = (start_values or {}).get(field.name)
        if given is None:
            if field.name not in variables:
                raise KeyError(f"the FMU has no parameter {field.name!r}: not the double pendulum's")
            given = variables[field.name]
            given = getattr(given, "start", given)
        values[field.name] = float(given)
    return PendulumParameters(**values)


def normal_mode_start(parameters: PendulumParameters, mode: str, amplitude: float = 0.01) -> dict[str, float]:
    """Start values of a pure normal mode ``mode`` (``"slow"`` or ``"fast"``): the upper rod at ``amplitude``
    [rad], the lower one in the mode's shape, both at rest."""
    if mode not in MODES:
        raise ValueError(f"mode = {mode!r}: must be one of {', '.join(MODES)}")
    _, shapes = linearised_normal_modes(parameters)
    ratio = shapes[MODES.index(mode)][1]
    return {"phi1_0": amplitude, "phi2_0": amplitude * ratio, "omega1_0": 0.0, "omega2_0": 0.0}


def measured_period(time: np.ndarray, values: np.ndarray) -> tuple[float, int]:
    """The mean period [s] between the first and the last upward zero crossing of ``values(time)`` (each
    interpolated linearly) and the number of periods it spans (0 where there are fewer than two crossings)."""
    values = np.asarray(values, dtype=float)
    k = np.flatnonzero((values[:-1] < 0) & (values[1:] >= 0))
    if len(k) < 2:
        return math.nan, 0
    crossings = time[k] - values[k] * (time[k + 1] - time[k]) / (values[k + 1] - values[k])
    return float((crossings[-1] - crossings[0]) / (len(crossings) - 1)), len(crossings) - 1


def assert_normal_mode_periods(result: Result, parameters: PendulumParameters, mode: str,
                               rtol: float = 0.01) -> dict[str, float]:
    """Assert that both angles of ``result``, a small oscillation started in normal mode ``mode``
    (:func:`normal_mode_start`), swing with the mode's period :math:`2\\pi/\\omega` within ``rtol``; returns the
    measured period [s] of each angle."""
    __tracebackhide__ = True  # pytest shows the test's line, not this one
    if mode not in MODES:
        raise ValueError(f"mode = {mode!r}: must be one of {', '.join(MODES)}")
    _needs(result, ["phi1", "phi2"], "the normal modes' periods")
    omegas, _ = linearised_normal_modes(parameters)
    expected = 2 * math.pi / omegas[MODES.index(mode)]
    periods, problems = {}, []
    for name in ("phi1", "phi2"):
        period, count = measured_period(result.time, result[name])
        periods[name] = period
        if count == 0:
            problems.append(f"{name} crosses zero upwards fewer than twice by t = {result.time[-1]:.6g} s: run it "
                            f"for at least two periods ({2 * expected:.4g} s)")
        elif abs(period - expected) > rtol * expected:
            problems.append(f"{name} swings with a period of {period:.6g} s (mean of {count}), the {mode} normal "
                            f"mode's is {expected:.6g} s: {abs(period / expected - 1):.3%} apart, more than "
                            f"{rtol:.3%}")
    if problems:
        amplitude = max(float(np.max(np.abs(result[name]))) for name in ("phi1", "phi2"))
        note = (f"; the angles reach {amplitude:.3g} rad, not a small oscillation" if amplitude > 0.1 else "")
        raise AssertionError(f"{result.label}, the {mode} normal mode: " + "; ".join(problems) + note)
    return periods
