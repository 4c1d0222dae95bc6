r"""A result against its reference inside a tube, as the FMI Cross-Check and the Modelica Standard Library's
regression tests compare them, by fmpy's :func:`fmpy.util.validate_signal`.

The tube around a reference signal :math:`y_r(t)` is, at each time :math:`t`,

.. math::

    \min_{|s-t|\le\tau} y_r(s) - w \;\le\; y(t) \;\le\; \max_{|s-t|\le\tau} y_r(s) + w,

:math:`\tau` [s] the time tolerance (a result may run early or late by up to :math:`\tau`) and :math:`w` the value
tolerance in the variable's unit, :math:`w = \max(\mathrm{atol}, \mathrm{rtol}\cdot\mathrm{nominal})`, the nominal
by default the larger of the reference's range :math:`\max y_r - \min y_r` and its size :math:`\max |y_r|` (1 where
it is zero throughout), so that a signal that hardly moves is not held to a fraction of its wobble.
fmpy resamples the reference onto an even grid of ``num`` points and widens it by a filter of ``dx`` points and by
``dy`` times its range; :func:`band_arguments` chooses them so that the tube is the one above, with a grid fine enough
for :math:`\tau` (at least four points a tolerance). Only the result's points within the reference's time span
count, as fmpy counts them; a result that ends before the reference fails on that alone.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .results import Result

MOST_BAND_POINTS = 200_000
"""The finest grid the tube is resampled on; a time tolerance below a few of its steps is widened to them."""


@dataclasses.dataclass(frozen=True)
class Tolerance:
    """The tube of one variable: ``time`` [s] either side, ``atol`` in the variable's unit, ``rtol`` of
    ``nominal`` (``None``: the larger of the reference's range and its size); the value half-width is
    ``max(atol, rtol * nominal)``."""

    time: float = 0.0
    atol: float = 0.0
    rtol: float = 0.01
    nominal: float | None = None

    def __post_init__(self) -> None:
        for name in ("time", "atol", "rtol"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ValueError(f"tolerance {name} = {value!r}: must be a finite number >= 0")
        if self.nominal is not None and not (math.isfinite(self.nominal) and self.nominal > 0):
            raise ValueError(f"tolerance nominal = {self.nominal!r}: must be a finite number > 0")

    def width(self, reference: np.ndarray) -> tuple[float, float]:
        """The value half-width :math:`w` and the nominal it is taken of, for the reference values
        ``reference``."""
        nominal = self.nominal
        if nominal is None:
            span = float(np.ptp(reference)) if len(reference) else 0.0
            nominal = max(span, float(np.max(np.abs(reference), initial=0.0))) or 1.0
        return max(self.atol, self.rtol * nominal), nominal


@dataclasses.dataclass(frozen=True)
class VariableCheck:
    """How one variable fared: ``first_out`` [s] the first time it was outside the tube (``None``: never),
    ``points_out`` of ``points`` compared, the largest ``deviation`` from the reference (interpolated at the
    result's times) at ``deviation_time`` [s], the largest ``excess`` beyond the tube at ``excess_time``, the
    ``tolerance`` and the tube's value half-width ``width`` and time half-width ``time_width`` as applied."""

    name: str
    unit: str
    first_out: float | None
    points_out: int
    points: int
    deviation: float
    deviation_time: float
    excess: float
    excess_time: float
    tolerance: Tolerance
    width: float
    nominal: float
    time_width: float
    band: tuple[np.ndarray, np.ndarray, np.ndarray] = dataclasses.field(repr=False)
    outside: np.ndarray = dataclasses.field(repr=False, default_factory=lambda: np.zeros(0, bool))

    @property
    def passed(self) -> bool:
        return self.points_out == 0

    def describe(self) -> str:
        """One line: where it left the tube, how far, and the tube."""
        unit = f" {self.unit}" if self.unit else ""
        tube = (f"tube +-{self.width:.4g}{unit} (max(atol {self.tolerance.atol:g}, rtol {self.tolerance.rtol:g} x "
                f"nominal {self.nominal:.4g})), +-{self.time_width:.4g} s in time")
        if self.passed:
            return f"{self.name}: inside, largest deviation {self.deviation:.4g}{unit}; {tube}"
        return (f"{self.name}: left the tube first at t = {self.first_out:.6g} s ({self.points_out} of "
                f"{self.points} points outside); largest deviation {self.deviation:.4g}{unit} at t = "
                f"{self.deviation_time:.6g} s, {self.excess:.4g}{unit} beyond the tube at t = {self.excess_time:.6g}"
                f" s; {tube}")


def band_arguments(t_ref: np.ndarray, y_ref: np.ndarray, width: float,
                   time: float) -> tuple[dict[str, Any], float, float]:
    """fmpy's ``num``, ``dx`` and ``dy`` for a tube of value half-width ``width`` and time half-width ``time``
    [s] around ``y_ref(t_ref)``, the time half-width they give (``time`` or the grid's step where that is coarser)
    and the offset both signals get: fmpy gives a constant zero reference a fixed width of 0.5, so such a
    reference and its result are compared shifted by 1 (their difference unchanged)."""
    span = float(t_ref[-1] - t_ref[0])
    num = max(len(t_ref), 1000)
    if time > 0 and span > 0:
        num = max(num, min(MOST_BAND_POINTS, math.ceil(4 * span / time) + 1))
    step = span / (num - 1) if span > 0 else 0.0
    half = math.ceil(time / step - 1e-9) if step > 0 and time > 0 else 0
    y_band = np.interp(np.linspace(t_ref[0], t_ref[-1], num), t_ref, y_ref)
    low, high = float(np.min(y_band)), float(np.max(y_band))
    offset = 0.0
    if low == high:
        if low == 0.0:
            offset = low = 1.0
        dy = width / abs(low)
    else:
        dy = width / (high - low)
    return {"num": num, "dx": 2 * half + 1, "dy": dy}, half * step, offset


def check_variable(result: Result, reference: Result, name: str, tolerance: Tolerance) -> VariableCheck:
    """``result[name]`` against ``reference[name]`` in the tube of ``tolerance`` (:func:`fmpy.util.validate_signal`)."""
    from fmpy.util import validate_signal

    t = np.asarray(result.time, dtype=float)
    y = np.asarray(result[name], dtype=float)
    t_ref = np.array(reference.time, dtype=float)  # a copy: fmpy nudges repeated times in place
    y_ref = np.asarray(reference[name], dtype=float)
    width, nominal = tolerance.width(y_ref)
    arguments, time_width, offset = band_arguments(t_ref, y_ref, width, tolerance.time)
    t_band, y_min, y_max, out = validate_signal(t, y + offset, t_ref, y_ref + offset, **arguments)
    y_min, y_max = y_min - offset, y_max - offset
    inside = (t > t_band[0]) & (t < t_band[-1])
    deviation = np.where(inside, np.abs(y - np.interp(t, t_ref, y_ref)), 0.0)
    excess = np.where(out, np.maximum(np.interp(t, t_band, y_min) - y, y - np.interp(t, t_band, y_max)), 0.0)
    k, j = int(np.argmax(deviation)), int(np.argmax(excess))
    first = float(t[out][0]) if out.any() else None
    return VariableCheck(name, result.unit(name) or reference.unit(name), first, int(out.sum()), int(inside.sum()),
                         float(deviation[k]), float(t[k]), float(excess[j]), float(t[j]), tolerance, width, nominal,
                         time_width, (t_band, y_min, y_max), out)


def tolerances_for(names: Sequence[str], base: Tolerance,
                   per_variable: Mapping[str, Tolerance | Mapping[str, float]] | None) -> dict[str, Tolerance]:
    """Each variable's tolerance: ``base``, with what ``per_variable[name]`` sets (a :class:`Tolerance` or a
    mapping of its fields) in its place."""
    per_variable = dict(per_variable or {})
    unknown = sorted(set(per_variable) - set(names))
    if unknown:
        raise KeyError(f"tolerances given for {', '.join(unknown)}, which are not compared ({', '.join(names)})")
    out = {}
    for name in names:
        given = per_variable.get(name, {})
        if isinstance(given, Tolerance):
            out[name] = given
            continue
        fields = {f.name for f in dataclasses.fields(Tolerance)}
        wrong = sorted(set(given) - fields)
        if wrong:
            raise KeyError(f"tolerance of {name}: unknown {', '.join(wrong)} (known: {', '.join(sorted(fields))})")
        out[name] = dataclasses.replace(base, **given)
    return out


def assert_matches_reference(result: Result, reference: Result, variables: Sequence[str] | None = None, *,
                             time: float = 0.0, atol: float = 0.0, rtol: float = 0.01, nominal: float | None = None,
                             tolerances: Mapping[str, Tolerance | Mapping[str, float]] | None = None,
                             plot_dir: str | Path | None = None) -> dict[str, VariableCheck]:
    """Assert that every variable of ``variables`` (default: every column the two share) stays in the tube around
    the reference: ``time`` [s], ``atol``, ``rtol`` and ``nominal`` for all (:class:`Tolerance`), ``tolerances``
    by variable where one differs. On failure the message names each variable that left the tube, when it first
    did and its largest deviation, and where the plot of result, reference and tube is (in ``plot_dir``, else the
    test's artefact folder the plugin's fixtures know). Returns each variable's :class:`VariableCheck`."""
    __tracebackhide__ = True  # pytest shows the test's line, not this one
    shared = [name for name in result.names if name in reference]
    names = list(variables) if variables is not None else shared
    missing = [f"{name!r} (not in the {what})" for name in names
               for what, columns in (("result", result), ("reference", reference)) if name not in columns]
    if missing:
        raise AssertionError(f"cannot compare {', '.join(missing)}")
    if not names:
        raise AssertionError(f"{result.label} and {reference.label} share no column to compare")
    base = Tolerance(time, atol, rtol, nominal)
    checks = {name: check_variable(result, reference, name, tol)
              for name, tol in tolerances_for(names, base, tolerances).items()}
    failed = [check for check in checks.values() if not check.passed]
    ends, reference_ends = float(result.time[-1]), float(reference.time[-1])
    short = ends < reference_ends - max(base.time, 1e-9 * max(1.0, abs(reference_ends)))
    if not failed and not short:
        return checks
    lines = [f"{result.label} does not match {reference.label}:"]
    if short:
        lines.append(f"  the result ends at t = {ends:.6g} s, the reference runs to {reference_ends:.6g} s")
    if failed:
        lines.append(f"  {len(failed)} of {len(checks)} variables left the tube:")
        lines += [f"    {check.describe()}" for check in failed]
    folder = Path(plot_dir) if plot_dir is not None else next(
        (source.artefacts() for source in (result, reference) if source.artefacts is not None), None)
    if failed and folder is not None:
        lines.append(f"  plot: {plot_tube(result, reference, failed, folder)}")
    elif failed:
        lines.append("  (no plot: pass plot_dir=, or take the result from the plugin's simulate fixture)")
    raise AssertionError("\n".join(lines))


def plot_tube(result: Result, reference: Result, checks: Sequence[VariableCheck], folder: Path) -> Path:
    """Draw each variable of ``checks``: the reference, its tube, the result and the points outside, one panel
    each, into ``folder/tube-<names>.png`` (Matplotlib's Agg canvas, no window); returns the path."""
    from matplotlib.figure import Figure

    shown = list(checks)[:6]
    figure = Figure(figsize=(8, 2.4 * len(shown) + 0.6), layout="constrained")
    axes = figure.subplots(len(shown), 1, sharex=True, squeeze=False)[:, 0]
    for ax, check in zip(axes, shown):
        t_band, y_min, y_max = check.band
        ax.fill_between(t_band, y_min, y_max, color="0.85", label="tube")
        ax.plot(reference.time, reference[check.name], color="0.3", lw=1, label=reference.label)
        ax.plot(result.time, result[check.name], color="C0", lw=1, label=result.label)
        out = check.outside
        ax.plot(result.time[out], result[check.name][out], ".", color="C3", ms=2.5, alpha=0.7,
                label="outside the tube")
        if check.first_out is not None:
            ax.axvline(check.first_out, color="C3", lw=0.8, ls="--")
        ax.set_ylabel(f"{check.name} [{check.unit}]" if check.unit else check.name)
    axes[-1].set_xlabel("time [s]")
    figure.legend(*axes[0].get_legend_handles_labels(), loc="outside upper center", ncols=4, fontsize="small")
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"tube-{re.sub(r'[^A-Za-z0-9_.-]+', '_', '-'.join(c.name for c in shown))[:80]}.png"
    figure.savefig(path, dpi=100)
    return path

