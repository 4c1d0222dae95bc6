"""Scenario ``work_precision``: error against run time for every solver the FMU offers.

For each case (a regular start over 30 s, a chaotic start over 3 s -- before the reference itself
diverges --, and a stiff light suspension over 2 s) and each solver, a sweep of tolerances
(adaptive methods) or step sizes (fixed-step methods) runs **through fmpy** at a 10 ms
communication step, and one mid setting per solver also at 1 ms and 100 ms. Recorded per run:
final-horizon error and maximum error over the horizon (max over phi1, phi2, omega1, omega2
against the cached reference, :mod:`double_pendulum.analysis.reference`; the cases, errors and
the choice per band are in :mod:`double_pendulum.analysis.work_precision`), energy drift (frictionless: max
|E_total - E0| / E0; with dissipation: max |energy_residual| / E0), RHS evaluations and steps
(FMU outputs), CPU time (process time of the run; the median of 1-5 repeats: runs are repeated while
they took under 0.5 s CPU in all, so cheap runs, whose timing decides close races, are timed several
times and expensive ones once). Failed or unstable configurations are kept in the table with their
status and message.

Cost: the configurations and the three references (cached, see
:mod:`double_pendulum.analysis.reference`) run on parallel worker processes, one per core, about
2 minutes CPU in all without cached references. ``thorough=True`` (``--thorough``) adds Rodas4 at
rtol 1e-12 (40 s CPU on the stiff case alone; it wins no band) and times every configuration at
least 3 times.

Outputs: ``work_precision.csv``, one log-log plot per case (max error against CPU time, one line
per method), ``report.md`` naming the fastest method per accuracy band and case.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis.progress import step
from double_pendulum.analysis.reference import STATE_OUTPUTS, Reference, cached_reference, reference_solution
from double_pendulum.analysis.sweep import runner_map
from double_pendulum.analysis.work_precision import (
    BASE_COMM_STEP,
    CASES,
    COMM_STEPS,
    THOROUGH_TIMING,
    TIMING,
    Case,
    Timing,
    accuracy_columns,
    best_per_band,
    failure_columns,
    report,
    settings_for,
    timing_columns,
)
from double_pendulum.fmu.runner import FmuRunError, FmuRunner
from double_pendulum.results_io import write_json, write_table_csv, write_text
from double_pendulum.solvers import METHODS

DESCRIPTION = "error against CPU time for every solver, tolerance and communication step (through fmpy)"

OUTPUTS = (*STATE_OUTPUTS, "E_total", "energy_residual", "solver_rhs_evaluations", "solver_steps")
"""The outputs a configuration needs for its errors, drift and counts."""


@dataclass(frozen=True)
class Config:
    """One run of the table: a case, a solver with its setting, a communication step, a horizon."""

    case: Case
    solver: str
    setting: dict[str, float]
    comm: float
    horizon: float
    timing: Timing

    def cost(self) -> float:
        """A rough estimate of the run's CPU time (to start the expensive runs first)."""
        per_step = self.setting.get("fixed_step") or self.setting.get("rtol", 1e-8) ** (1 / 5) * 0.05
        implicit = 8.0 if self.solver in ("rodas4", "gauss4", "gauss2") else 1.0
        stiff = 20.0 if self.case.dissipative else 1.0
        return self.horizon * (implicit * stiff / per_step + 1.0 / self.comm)


def run_config(runner: FmuRunner, config: Config) -> tuple[dict[str, Any], np.ndarray | None]:
    """Run one configuration (repeated as its :class:`Timing` says); its row (no errors yet) and result."""
    case = config.case
    start = {**case.start, "solver": config.solver, **config.setting}
    row: dict[str, Any] = {"case": case.name, "solver": config.solver, **config.setting,
                           "comm_step_s": config.comm, "horizon_s": config.horizon}
    cpu: list[float] = []
    result = None
    try:
        while config.timing.more(cpu):
            t0 = time.process_time()
            result = runner.simulate(start, stop_time=config.horizon, output_interval=config.comm, outputs=OUTPUTS)
            cpu.append(time.process_time() - t0)
        row["status"] = "ok"
    except FmuRunError as error:
        return {**row, **failure_columns(error)}, None
    return {**row, **timing_columns(cpu)}, result


def _task(runner: FmuRunner, task: tuple[str, Any]) -> Any:
    """Worker: a reference (``("reference", (case, horizon))``) or a configuration (``("config", Config)``)."""
    kind, item = task
    if kind == "reference":
        case, horizon = item
        return reference_solution(case.start, horizon, BASE_COMM_STEP)
    return run_config(runner, item)


def configurations(quick: bool, thorough: bool) -> list[Config]:
    """Every configuration of the sweep, case by case, solver by solver."""
    solvers = ("dop853", "rk4") if quick else tuple(METHODS)
    timing = THOROUGH_TIMING if thorough else TIMING
    out = []
    for case in CASES[:1] if quick else CASES:
        horizon = case.quick_horizon if quick else case.horizon
        for solver in solvers:
            sweep = settings_for(solver, quick, thorough)
            out += [Config(case, solver, setting, BASE_COMM_STEP, horizon, timing) for setting in sweep]
            if not quick:  # communication-step sweep at the middle setting
                mid = sweep[len(sweep) // 2]
                out += [Config(case, solver, mid, comm, horizon, timing)
                        for comm in COMM_STEPS if comm != BASE_COMM_STEP]
    return out


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False, thorough: bool = False) -> dict:
    """Sweep every solver on every case; write the table, plots and the report."""
    configs = configurations(quick, thorough)
    horizons = {c.case.name: (c.case, c.horizon) for c in configs}
    refs: dict[str, Reference] = {}
    tasks: list[tuple[str, Any]] = []
    costs: list[float] = []
    for name, (case, horizon) in horizons.items():
        cached = cached_reference(case.start, horizon, BASE_COMM_STEP)
        if cached is not None:
            refs[name] = cached
        else:
            tasks.append(("reference", (case, horizon)))
            costs.append(1e9)  # the references are the longest tasks: start them first
    missing = [t[1][0].name for t in tasks]
    step(f"{len(configs)} configurations through fmpy" + (
        f", and the references of {', '.join(missing)} (computed once, then cached)" if missing else
        " (references cached)"))
    tasks += [("config", c) for c in configs]
    costs += [c.cost() for c in configs]
    results = runner_map(_task, tasks, runner, max_workers=1 if quick else None, costs=costs,
                         label="work_precision", unit="run")
    for (kind, item), value in zip(tasks, results):
        if kind == "reference":
            refs[item[0].name] = value
    rows: list[dict[str, Any]] = []
    for config, (row, result) in zip(configs, results[len(missing):]):
        if result is not None:
            row.update(accuracy_columns(result, config.case, refs[config.case.name], config.comm))
        rows.append(row)
    step("tables, plots and the report")
    floors = {name: refs[name].error_floor for name in horizons}
    for name, (_case, horizon) in horizons.items():
        plots.plot_work_precision(
            [r for r in rows if r["case"] == name and r["comm_step_s"] == BASE_COMM_STEP],
            out_dir / f"work_precision_{name}.png", title=f"{name} (horizon {horizon:g} s)",
        )
    best = {case: best_per_band(rows, case, floor) for case, floor in floors.items()}
    timing = THOROUGH_TIMING if thorough else TIMING
    write_table_csv(out_dir / "work_precision.csv", rows)
    write_text(out_dir / "report.md", report(rows, best, floors, quick, timing, thorough))
    summary = {"scenario": "work_precision", "quick": quick, "thorough": thorough,
               "reference_error_floor": floors, "best_per_band": best, "configurations": len(rows),
               "failed_or_unstable": sum(r["status"] != "ok" for r in rows),
               "cpu_timing": timing.describe()}
    write_json(out_dir / "summary.json", summary)
    return summary
