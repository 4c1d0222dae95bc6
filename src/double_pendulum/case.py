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

The files are made in a folder of their own inside the output folder and moved into it once all are written,
so an interrupted run changes nothing there and leaves nothing behind. When the FMU stops the run (a bad value
it refuses at the start, a step it cannot complete), the rows it returned are written all the same, with the
FMU's message in the summary and the figure.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
import time
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
from .runs.results_io import read_results_csv, write_json, write_results_csv

MAX_ANIMATION_S = 30.0
"""The animation shows at most this much of a run [s] (600 frames at 20 a second: about 3 MB)."""
FILES = ("simulation.csv", "simulation.png", "simulation.gif", "summary.json")
"""What :func:`run_case` writes, in that order."""
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


def _summary(case: Case, runner: FmuRunner, state: list[StartValue], result: np.ndarray | None,
             message: str | None, wall_s: float) -> dict[str, Any]:  # fmt: skip
    """``summary.json``: the call, the case, the start state used (each quantity's value, unit and ``set`` or
    ``default``) and how the run ended, with the energies of the rows returned."""
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
        "status": "finished" if message is None else "stopped by the FMU",
        "fmu_message": message,
        "rows": 0 if result is None else len(result),
        "wall_time_s": wall_s,
        "null_means": {},  # why a value is null, for the values that are (runs.page.null_reason)
    }
    if message is None:
        summary["null_means"]["fmu_message"] = "the run reached its stop time"
    if case.fmi_type == "ModelExchange":  # fmpy's CVode: the default experiment's tolerance, else its own 1e-5
        summary["relative_tolerance"] = float(experiment.tolerance) if experiment and experiment.tolerance else 1e-5
    else:
        summary["relative_tolerance"] = None
        summary["null_means"]["relative_tolerance"] = "not used: the FMU integrates with its own solver (its rtol)"
    if result is not None and len(result):
        e = np.asarray(result["E_total"])
        summary.update(end_time_s=float(result["time"][-1]), E_total_start_J=float(e[0]),
                       E_total_end_J=float(e[-1]),
                       max_abs_energy_residual_J=float(np.max(np.abs(result["energy_residual"]))))
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
    """The figure and the animation, drawn from ``simulation.csv`` as written."""
    result = read_results_csv(folder / "simulation.csv")
    plot_case(result, folder / "simulation.png", title=_title(case, state, summary))
    rows = result["time"] <= MAX_ANIMATION_S + 1e-9
    if animate and rows.sum() > 1:
        shown = float(result["time"][rows][-1])
        note = "" if shown >= float(result["time"][-1]) else f" (the first {shown:g} s)"
        animate_swings(result["time"][rows], [swing(result[rows], "your case", "C0")], folder / "simulation.gif",
                       title=f"{case.words()}{note}")
        summary["animation_s"] = shown
    else:
        summary["animation_s"] = None
        summary["null_means"]["animation_s"] = "no animation: fewer than two rows, or switched off"


def run_case(case: Case, out: Path, *, animate: bool = True) -> Outcome:
    """Run ``case`` and write :data:`FILES` into ``out`` (the GIF only if ``animate``); see the module docstring.
    KeyboardInterrupt (also when the FMU turned Ctrl-C into a failed run) leaves ``out`` as it was."""
    out = Path(out)
    staging = Path(tempfile.mkdtemp(prefix=".simulate-", dir=out))
    try:
        with FmuRunner(case.fmu, reuse_instance=False) as runner:
            start, message = time.perf_counter(), None
            try:
                result = runner.simulate(case.start_values, stop_time=case.stop_time,
                                         output_interval=case.output_interval, fmi_type=case.fmi_type,
                                         outputs=case.outputs)
            except FmuRunError as error:
                if interrupted():
                    raise KeyboardInterrupt from None
                result, message = error.partial_result, str(error).split(" -- FMU says: ")[-1]
            wall_s = time.perf_counter() - start
            state = start_state(case.start_values, runner.model_description)
            summary = _summary(case, runner, state, result, message, wall_s)
            if result is not None and len(result):
                write_results_csv(staging / "simulation.csv", result, runner.units)
                _draw(staging, case, state, summary, animate)
        write_json(staging / "summary.json", summary)
        written = []
        for name in FILES:  # this run's set replaces an earlier run's whole: no file of that one stays beside it
            if (staging / name).is_file():
                os.replace(staging / name, out / name)
                written.append(out / name)
            else:
                (out / name).unlink(missing_ok=True)
        return Outcome(written, summary, message, state)
    except KeyboardInterrupt:
        acknowledge()  # the run stops here: a repeated interrupt must not cut the clean-up below short
        raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
