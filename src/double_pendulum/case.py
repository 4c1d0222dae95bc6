"""A case of one's own (``double-pendulum simulate``): the FMU run once, the way fmpy runs it, to a CSV file, a
figure, an animation and a summary.

:func:`run_case` calls :func:`fmpy.simulate_fmu` on the FMU with the user's start values (through
:class:`~double_pendulum.fmu.running.runner.FmuRunner`, a new instance, as a plain ``simulate_fmu`` call makes: the
numbers are fmpy's, bit for bit, ``summary.json`` says which call gives them) and writes into the output folder:

* ``simulation.csv``: time and every output, units in the column names;
* ``simulation.png``: angles, energies, the energy budget and the bobs' paths, drawn from the CSV file;
* ``simulation.gif``: the pendulum in real time, drawn from the CSV file (at most the first
  :data:`MAX_ANIMATION_S` seconds);
* ``summary.json``: the call, the start values, the start state used, how the run ended and its energies.

The start state it used, all four of :data:`START_STATE` with units, each given or the FMU's default
(:func:`start_state`), is said in the summary, the figure's title and the command's line: ``--set phi1_0=2``
alone starts the lower rod at the FMU's ``phi2_0``, which the user did not choose.

The rows go to ``simulation.csv`` as the FMU computes them (:class:`~double_pendulum.runs.row_stream.RowStream`),
so memory stays flat however long the run; the figure is drawn from at most :data:`FIGURE_ROWS` rows spread over
the file. Once the first :data:`PROBE_S` seconds of simulated time and :data:`PROBE_WALL_S` of wall time are done,
a run still going is estimated from their pace (:class:`Estimate`, told to ``on_estimate``); a run estimated to
take longer than ``max_wall_s`` stops there and writes nothing (:class:`TooLong`). A run over sooner is not
estimated.

The files are made in a folder of their own inside the output folder and moved into it once all are written.
When the FMU stops the run (a bad value it refuses at the start, a step it cannot complete), the rows it returned
are written all the same, with the FMU's message in the summary and the figure. An interrupted run (Ctrl-C) moves
the rows so far into the output folder, ``simulation.csv`` with every line whole and ``summary.json`` saying where
it stopped, no figure or animation (:class:`Interrupted`), and leaves no temporary file.
"""

from __future__ import annotations

import dataclasses
import math
import os
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .fmu.running.runner import FmuRunError, FmuRunner
from .fmu.running.start_values import value_text
from .model.outputs import OUTPUT_NAMES
from .model.parameters import InitialState
from .plots import animate_swings, swing
from .plots.case import plot_case
from .runs.interrupts import acknowledge, interrupted
from .runs.results_io import write_json
from .runs.row_stream import RowStream, read_spread

MAX_ANIMATION_S = 30.0
"""The animation shows at most this much of a run [s] (600 frames at 20 a second: about 3 MB)."""
FILES = ("simulation.csv", "simulation.png", "simulation.gif", "summary.json")
"""What :func:`run_case` writes, in that order."""
FIGURE_ROWS = 20_000
"""The figure is drawn from at most this many rows, spread evenly over the run (a 10 s run at 10 ms has 1001)."""
PROBE_S = 0.5
"""Simulated time [s] whose pace estimates the whole run's wall time: at least this, and :data:`PROBE_WALL_S`."""
PROBE_WALL_S = 1.0
"""Wall time [s] the probe takes at least (a fast case's first 0.5 s take a few ms: too short a sample)."""
FMI_TYPES = {"CoSimulation": "co-simulation", "ModelExchange": "model exchange"}
START_STATE = tuple(spec.name for spec in dataclasses.fields(InitialState))
"""The pendulum's start state as the FMU names its parameters: the angles phi1_0, phi2_0 [rad] of the rods from
the downward vertical and their rates omega1_0, omega2_0 [rad/s] (the model's
:class:`~double_pendulum.model.parameters.InitialState`)."""


@dataclass(frozen=True)
class Case:
    """A run of the FMU file ``fmu`` as :func:`fmpy.simulate_fmu` makes it: ``fmi_type``, the ``start_values``,
    ``stop_time`` [s], ``output_interval`` [s] (also the communication step of a co-simulation), the quantities
    recorded, ``outputs`` (the FMU's outputs and its local diagnostics: every quantity), and ``start_time`` [s]."""

    fmu: Path
    start_values: dict[str, Any] = field(default_factory=dict)
    stop_time: float = 10.0
    output_interval: float = 0.01
    fmi_type: str = "CoSimulation"
    outputs: tuple[str, ...] = OUTPUT_NAMES
    start_time: float = 0.0

    def fmpy_call(self) -> str:
        """The Python call that gives the same numbers, from any folder (the FMU's absolute path); it names
        what it records, as fmpy records only the FMU's outputs by default."""
        return (f"fmpy.simulate_fmu({str(Path(self.fmu).resolve())!r}, fmi_type={self.fmi_type!r}, "
                f"start_values={self.start_values!r}, "
                + (f"start_time={self.start_time!r}, " if self.start_time else "")
                + f"stop_time={self.stop_time!r}, "
                f"output_interval={self.output_interval!r}, output={list(self.outputs)!r})")

    def words(self) -> str:
        """The case in a line: its start values and length."""
        values = ", ".join(f"{k} = {value_text(v)}" for k, v in self.start_values.items()) or "the FMU's defaults"
        return f"{values}; {self.stop_time:g} s"


@dataclass(frozen=True)
class StartValue:
    """One quantity of the start state a run used: its FMU ``name``, ``value`` in ``unit``, and whether the user
    ``given`` it (``--set``) or it is the FMU's default (the start value of its modelDescription)."""

    name: str
    value: float
    unit: str
    given: bool

    def words(self) -> str:
        """``phi2_0 = 1 rad (default)``."""
        return f"{self.name} = {value_text(self.value)} {self.unit} ({'set' if self.given else 'default'})"


def start_state(start_values: dict[str, Any], model_description: Any) -> list[StartValue]:
    """The start state (:data:`START_STATE`) a run of an FMU of ``model_description`` (fmpy's) with
    ``start_values`` begins from: each value given, else the variable's start value in the modelDescription,
    with the variable's unit."""
    variables = {v.name: v for v in model_description.modelVariables}
    state = []
    for name in START_STATE:
        variable = variables[name]
        unit = variable.unit or (variable.declaredType.unit if variable.declaredType else None) or ""
        given = name in start_values
        state.append(StartValue(name, float(start_values[name] if given else variable.start), unit, given))
    return state


def start_state_words(state: list[StartValue]) -> str:
    """The start state in a line: ``phi1_0 = 2 rad (set), phi2_0 = 1 rad (default), ...``."""
    return ", ".join(value.words() for value in state)


@dataclass(frozen=True)
class Outcome:
    """What :func:`run_case` wrote (``files`` in the output folder) and the run's ``summary``; ``message``: why the
    FMU stopped the run (None if it ran to the stop time); ``start_state``: the start state it used."""

    files: list[Path]
    summary: dict[str, Any]
    message: str | None
    start_state: list[StartValue]


def _summary(case: Case, runner: FmuRunner, state: list[StartValue], stream: RowStream, message: str | None,
             wall_s: float, status: str | None = None) -> dict[str, Any]:  # fmt: skip
    """``summary.json``: the call, the case, the start state used (each quantity's value, unit and ``set`` or
    ``default``) and how the run ended (``status``: by default finished, or stopped by the FMU with ``message``),
    with the energies of the rows written."""
    md = runner.model_description
    experiment = md.defaultExperiment
    summary: dict[str, Any] = {
        "command": "double-pendulum simulate",
        "fmpy_call": case.fmpy_call(),
        "fmu": str(case.fmu),
        "fmi_version": md.fmiVersion,
        "fmi_type": case.fmi_type,
        "start_values": case.start_values,
        "start_state": {value.name: {"value": value.value, "unit": value.unit,
                                     "source": "set" if value.given else "default"} for value in state},
        "stop_time_s": case.stop_time,
        "output_interval_s": case.output_interval,
        "status": status or ("finished" if message is None else "stopped by the FMU"),
        "fmu_message": message,
        "rows": stream.rows,
        "wall_time_s": wall_s,
        "null_means": {},  # why a value is null, for the values that are (runs.page.null_reason)
    }
    if message is None:
        summary["null_means"]["fmu_message"] = ("the run reached its stop time" if status is None
                                                else "the FMU did not stop the run")
    if case.fmi_type == "ModelExchange":  # fmpy's CVode: the default experiment's tolerance, else its own 1e-5
        summary["relative_tolerance"] = float(experiment.tolerance) if experiment and experiment.tolerance else 1e-5
    else:
        summary["relative_tolerance"] = None
        summary["null_means"]["relative_tolerance"] = "not used: the FMU integrates with its own solver (its rtol)"
    if stream.rows:
        summary.update(end_time_s=stream.last["time"], E_total_start_J=stream.first["E_total"],
                       E_total_end_J=stream.last["E_total"], max_abs_energy_residual_J=stream.max_abs_residual)
    return summary


def _title(case: Case, state: list[StartValue], summary: dict[str, Any]) -> str:
    """The figure's title: the case, the start state it used (given or default), how the run ended."""
    kind = FMI_TYPES.get(case.fmi_type, case.fmi_type)
    line = f"your case: {case.words()}, FMI {summary['fmi_version']} {kind} through fmpy"
    line += f"\nstart state: {start_state_words(state)}"
    if summary["fmu_message"] is not None:
        line += f"\nstopped by the FMU at t = {summary.get('end_time_s', 0.0):g} s: {summary['fmu_message']}"
    return line


def _draw(folder: Path, case: Case, state: list[StartValue], summary: dict[str, Any], animate: bool) -> None:
    """The figure and the animation, drawn from ``simulation.csv`` as written: the figure from at most
    :data:`FIGURE_ROWS` rows spread over it, the animation from its first :data:`MAX_ANIMATION_S` seconds."""
    csv = folder / "simulation.csv"
    spread, every = read_spread(csv, summary["rows"], FIGURE_ROWS)
    title = _title(case, state, summary)
    if every > 1:
        title += f"\ndrawn from every {every}th of its {summary['rows']} rows (all of them in simulation.csv)"
    plot_case(spread, folder / "simulation.png", title=title)
    head = read_spread(csv, summary["rows"], summary["rows"])[0] if every == 1 else _head(csv, case)
    rows = head["time"] <= MAX_ANIMATION_S + 1e-9
    if animate and rows.sum() > 1:
        shown = float(head["time"][rows][-1])
        note = "" if shown >= summary["end_time_s"] else f" (the first {shown:g} s)"
        animate_swings(head["time"][rows], [swing(head[rows], "your case", "C0")], folder / "simulation.gif",
                       title=f"{case.words()}{note}")
        summary["animation_s"] = shown
    else:
        summary["animation_s"] = None
        summary["null_means"]["animation_s"] = "no animation: fewer than two rows, or switched off"


def _head(csv: Path, case: Case) -> np.ndarray:
    """The rows of ``csv`` up to :data:`MAX_ANIMATION_S` (and a few more), every one."""
    with open(csv) as fh:
        names = [h.strip('"').split(" [")[0] for h in fh.readline().rstrip("\n").split(",")]
    data = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2,
                      max_rows=int(MAX_ANIMATION_S / case.output_interval) + 3)
    return np.rec.fromarrays(data.T, names=names).view(np.ndarray)


@dataclass(frozen=True)
class Estimate:
    """The wall time a run will take, from the pace of its first ``probe_s`` seconds of simulated time (they took
    ``probe_wall_s`` [s] of wall time): ``total_wall_s`` [s] in all (the start of the FMU included) and about
    ``csv_bytes`` of CSV for its ``rows``."""

    probe_s: float
    probe_wall_s: float
    total_wall_s: float
    rows: int
    csv_bytes: float

    def words(self) -> str:
        """``about 15 s (the first 65 s of simulated time took 1 s; 100,001 rows, about 36 MB of CSV)``."""
        return (f"about {duration_words(self.total_wall_s)} (the first {_two_digits(self.probe_s)} s of simulated "
                f"time took {_two_digits(self.probe_wall_s)} s; {self.rows:,} rows, about {size_words(self.csv_bytes)} "
                "of CSV)")


def duration_words(seconds: float) -> str:
    """``4.2 s``, ``3.5 min``, ``2.1 h``, ``4.5 days``, ``13 years``."""
    for unit, size in (("years", 365.25 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= 2 * size if unit != "min" else seconds >= 90:
            return f"{_two_digits(seconds / size)} {unit}"
    return f"{_two_digits(seconds)} s"


def _two_digits(x: float) -> str:
    """``x`` to two significant digits, without an exponent: ``270``, ``4.2``, ``0.27``."""
    return f"{float(f'{x:.2g}'):g}" if x < 1e6 else f"{x:.2g}"


def size_words(n: float) -> str:
    """``3 MB``, ``4.1 GB`` (decimal units)."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{_two_digits(n / size)} {unit}"
    return f"{n:.0f} bytes"


class TooLong(Exception):
    """A run estimated to take longer than it may (``max_wall_s``); it stopped after its probe, nothing written."""

    def __init__(self, estimate: Estimate, max_wall_s: float) -> None:
        super().__init__(estimate.words())
        self.estimate, self.max_wall_s = estimate, max_wall_s


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a run: its message says what was kept (the rows so far, or nothing)."""


def run_case(case: Case, out: Path, *, animate: bool = True, max_wall_s: float = math.inf,
             on_estimate: Callable[[Estimate], None] | None = None) -> Outcome:
    """Run ``case`` and write :data:`FILES` into ``out`` (the GIF only if ``animate``), streaming the rows; see the
    module docstring. After its probe (:data:`PROBE_S`, :data:`PROBE_WALL_S`) ``on_estimate`` is told the run's
    :class:`Estimate`; above ``max_wall_s`` the run stops and :class:`TooLong` is raised, nothing written.
    KeyboardInterrupt (also when the FMU turned Ctrl-C into a failed run) writes the rows so far and raises
    :class:`Interrupted`."""
    out = Path(out)
    staging = Path(tempfile.mkdtemp(prefix=".simulate-", dir=out))
    stream: RowStream | None = None
    recorders: list[Any] = []
    probe: dict[str, Any] = {}

    def step_finished(t: float, recorder: Any) -> bool:
        if not recorders:
            recorders.append(recorder)
            probe.update(t0=t, wall0=time.perf_counter())
        stream.take(recorder)
        probed = t - probe["t0"] >= PROBE_S and time.perf_counter() - probe["wall0"] >= PROBE_WALL_S
        if "estimate" not in probe and probed and t < case.stop_time:
            probe["estimate"] = _estimate(case, probe, t, time.perf_counter() - start, stream)
            if on_estimate is not None:
                on_estimate(probe["estimate"])
            if probe["estimate"].total_wall_s > max_wall_s:
                probe["too_long"] = True
                return False
        return True

    try:
        with FmuRunner(case.fmu, reuse_instance=False) as runner:
            stream = RowStream(staging / "simulation.csv", runner.units)
            start, message, result = time.perf_counter(), None, None
            try:
                result = runner.simulate(case.start_values, stop_time=case.stop_time,
                                         output_interval=case.output_interval, fmi_type=case.fmi_type,
                                         outputs=case.outputs, step_finished=step_finished)
            except FmuRunError as error:
                if interrupted():
                    raise KeyboardInterrupt from None
                if probe.get("too_long"):
                    stream.finish(None)
                    raise TooLong(probe["estimate"], max_wall_s) from None
                result, message = error.partial_result, str(error).split(" -- FMU says: ")[-1]
            wall_s = time.perf_counter() - start
            stream.finish(recorders[0] if recorders else None, result)
            state = start_state(case.start_values, runner.model_description)
            summary = _summary(case, runner, state, stream, message, wall_s)
            if stream.rows:
                _draw(staging, case, state, summary, animate)
        write_json(staging / "summary.json", summary)
        return Outcome(_move(staging, out), summary, message, state)
    except KeyboardInterrupt:
        acknowledge()  # the run stops here: a repeated interrupt must not cut the clean-up below short
        if stream is None or "wall0" not in probe:
            raise Interrupted("nothing was written") from None
        stream.finish(recorders[0])
        summary = _summary(case, runner, start_state(case.start_values, runner.model_description), stream,
                                None, time.perf_counter() - start, status="interrupted by the user")
        summary["animation_s"] = None
        summary["null_means"]["animation_s"] = "no animation or figure: the run was interrupted"
        write_json(staging / "summary.json", summary)
        written = _move(staging, out)
        raise Interrupted(f"wrote the {stream.rows} rows so far, to t = {stream.last.get('time', 0.0):g} s "
                          f"({', '.join(path.name for path in written)} in {out}; no figure)") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _estimate(case: Case, probe: dict[str, Any], t: float, wall_s: float, stream: RowStream) -> Estimate:
    """The run's :class:`Estimate` at simulated time ``t``, ``wall_s`` after the run began (the FMU's start
    included): the pace since the first step, for the rest of the run; the CSV's size from the rows so far."""
    probe_s, probe_wall = t - probe["t0"], time.perf_counter() - probe["wall0"]
    pace = probe_wall / probe_s if probe_s > 0 else 0.0
    rows = int(round(case.stop_time / case.output_interval)) + 1  # from t = 0, as fmpy records
    size = stream.path.stat().st_size
    per_row = size / stream.rows if stream.rows else 25.0 * (len(case.outputs) + 1)
    return Estimate(probe_s, probe_wall, wall_s + pace * (case.stop_time - t), rows, per_row * rows)


def _move(staging: Path, out: Path) -> list[Path]:
    """Move the files of :data:`FILES` made in ``staging`` into ``out``; this run's set replaces an earlier run's
    whole: no file of that one stays beside it. The files moved."""
    written = []
    for name in FILES:
        if (staging / name).is_file():
            os.replace(staging / name, out / name)
            written.append(out / name)
        else:
            (out / name).unlink(missing_ok=True)
    return written
