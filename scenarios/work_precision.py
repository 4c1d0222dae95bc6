"""Scenario ``work_precision``: error against run time for every solver the FMU offers.

For each case (a regular start over 30 s, a chaotic start over 3 s -- before the reference itself
diverges --, and a stiff light suspension over 2 s) and each solver, a sweep of tolerances
(adaptive methods) or step sizes (fixed-step methods) runs **through fmpy** at a 10 ms
communication step, and one mid setting per solver also at 100 ms. Recorded per run:
final-horizon error and maximum error over the horizon (max over phi1, phi2, omega1, omega2
against the cached reference, :mod:`double_pendulum.analysis.solvers.reference`; the cases, errors and
the choice per band are in :mod:`double_pendulum.analysis.solvers.work_precision`), energy drift (frictionless: max
|E_total - E0| / E0; with dissipation: max |energy_residual| / E0), RHS evaluations and steps
(FMU outputs), CPU time (process time of the run; the median of 1-3 repeats: runs are repeated while
they took under 0.25 s CPU in all, so cheap runs, whose timing decides close races, are timed several
times and expensive ones once). Failed or unstable configurations are kept in the table with their
status and message.

Cost: the configurations and the three references (cached, see
:mod:`double_pendulum.analysis.solvers.reference`; their error floor from SciPy's DOP853 at rtol 1e-13, about
15 s CPU for all three) run on parallel worker processes, one per core, about 70 s CPU in all on a first
run. ``thorough=True`` (``--thorough``, about three times the CPU time) adds the settings that cost most
and win no band -- Rodas4 at rtol 1e-10 and 1e-12 (40 s CPU on the stiff case alone), Dopri5 at rtol
1e-12, Euler at h = 2e-5 s, the 1 ms communication step --, cross-checks the references with SciPy's
Radau at rtol 1e-12 (80 s CPU) and times every configuration at least 3 times.

Outputs: ``work_precision.csv``, one log-log plot per case (max error against CPU time, one line
per method), ``report.md`` naming the fastest method per accuracy band and case.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from double_pendulum import plots
from double_pendulum.analysis.solvers.reference import CROSS_CHECK, THOROUGH_CROSS_CHECK, Reference, cached_reference
from double_pendulum.analysis.solvers.work_precision import (
    BASE_COMM_STEP,
    CASES,
    COMM_STEPS,
    OUTPUTS,
    THOROUGH_COMM_STEPS,
    THOROUGH_TIMING,
    TIMING,
    Config,
    accuracy_columns,
    best_per_band,
    report,
    run_config,
    run_task,
    settings_for,
)
from double_pendulum.analysis.sweep import runner_map
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.runs.progress import step
from double_pendulum.runs.results_io import write_json, write_table_csv, write_text
from double_pendulum.solvers import METHODS

__all__ = ["DESCRIPTION", "OUTPUTS", "Config", "configurations", "run", "run_config"]

DESCRIPTION = "error against CPU time for every solver, tolerance and communication step (through fmpy)"

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
                        for comm in (THOROUGH_COMM_STEPS if thorough else COMM_STEPS) if comm != BASE_COMM_STEP]
    return out


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False, thorough: bool = False) -> dict:
    """Sweep every solver on every case; write the table, plots and the report."""
    configs = configurations(quick, thorough)
    horizons = {c.case.name: (c.case, c.horizon) for c in configs}
    refs: dict[str, Reference] = {}
    tasks: list[tuple[str, Any]] = []
    costs: list[float] = []
    cross_check = THOROUGH_CROSS_CHECK if thorough else CROSS_CHECK
    for name, (case, horizon) in horizons.items():
        cached = cached_reference(case.start, horizon, BASE_COMM_STEP, cross_check=cross_check)
        if cached is not None:
            refs[name] = cached
        else:
            tasks.append(("reference", (case, horizon, cross_check)))
            costs.append(1e9)  # the references are the longest tasks: start them first
    missing = [t[1][0].name for t in tasks]
    step(f"{len(configs)} configurations through fmpy" + (
        f", and the references of {', '.join(missing)} (computed once, then cached)" if missing else
        " (references cached)"))
    tasks += [("config", c) for c in configs]
    costs += [c.cost() for c in configs]
    results = runner_map(run_task, tasks, runner, max_workers=1 if quick else None, costs=costs,
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
               "cpu_timing": timing.describe(),
               "reference_cross_check": f"SciPy {cross_check['method']} rtol {cross_check['rtol']:g}"}
    write_json(out_dir / "summary.json", summary)
    return summary
