"""Scenario ``work_precision``: error against run time for every solver the FMU offers.

For each case (a regular start over 30 s, a chaotic start over 3 s -- before the reference itself
diverges --, and a stiff light suspension over 2 s) and each solver, a sweep of tolerances
(adaptive methods) or step sizes (fixed-step methods) runs **through fmpy** at a 10 ms
communication step, and one mid setting per solver also at 1 ms and 100 ms. Recorded per run:
final-horizon error and maximum error over the horizon (max over phi1, phi2, omega1, omega2
against the cached reference, :mod:`double_pendulum.analysis.reference`; the cases, errors and
the choice per band are in :mod:`double_pendulum.analysis.work_precision`), energy drift (frictionless: max
|E_total - E0| / E0; with dissipation: max |energy_residual| / E0), RHS evaluations and steps
(FMU outputs), CPU time (median of the repeats, with the spread). Failed or unstable
configurations are kept in the table with their status and message.

Outputs: ``work_precision.csv``, one log-log plot per case (max error against CPU time, one line
per method), ``report.md`` naming the fastest method per accuracy band and case.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from double_pendulum import plots
from double_pendulum.analysis.reference import Reference, reference_solution
from double_pendulum.analysis.work_precision import (
    BASE_COMM_STEP,
    CASES,
    COMM_STEPS,
    Case,
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


def run_config(runner: FmuRunner, case: Case, ref: Reference, solver: str, setting: dict, comm: float, horizon: float,
               repeats: int) -> dict[str, Any]:
    """Run one configuration ``repeats`` times; return its table row."""
    start = {**case.start, "solver": solver, **setting}
    row: dict[str, Any] = {"case": case.name, "solver": solver, **setting, "comm_step_s": comm, "horizon_s": horizon}
    cpu = []
    result = None
    try:
        for _ in range(repeats):
            t0 = time.process_time()
            result = runner.simulate(start, stop_time=horizon, output_interval=comm)
            cpu.append(time.process_time() - t0)
        row["status"] = "ok"
    except FmuRunError as error:
        return {**row, **failure_columns(error)}
    return {**row, **timing_columns(cpu), **accuracy_columns(result, case, ref, comm)}


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Sweep every solver on every case; write the table, plots and the report."""
    repeats = 1 if quick else 3
    solvers = ("dop853", "rk4") if quick else tuple(METHODS)
    cases = CASES[:1] if quick else CASES
    rows: list[dict[str, Any]] = []
    floors: dict[str, float] = {}
    for case in cases:
        horizon = case.quick_horizon if quick else case.horizon
        ref = reference_solution(case.start, horizon, BASE_COMM_STEP)
        floors[case.name] = ref.error_floor
        for solver in solvers:
            sweep = settings_for(solver, quick)
            for setting in sweep:
                rows.append(run_config(runner, case, ref, solver, setting, BASE_COMM_STEP, horizon, repeats))
            if not quick:  # communication-step sweep at the middle setting
                mid = sweep[len(sweep) // 2]
                for comm in COMM_STEPS:
                    if comm != BASE_COMM_STEP:
                        rows.append(run_config(runner, case, ref, solver, mid, comm, horizon, repeats))
        plots.plot_work_precision(
            [r for r in rows if r["case"] == case.name and r["comm_step_s"] == BASE_COMM_STEP],
            out_dir / f"work_precision_{case.name}.png", title=f"{case.name} (horizon {horizon:g} s)",
        )
    best = {case: best_per_band(rows, case, floor) for case, floor in floors.items()}
    write_table_csv(out_dir / "work_precision.csv", rows)
    write_text(out_dir / "report.md", report(rows, best, floors, quick))
    summary = {"scenario": "work_precision", "quick": quick, "reference_error_floor": floors,
               "best_per_band": best, "configurations": len(rows),
               "failed_or_unstable": sum(r["status"] != "ok" for r in rows)}
    write_json(out_dir / "summary.json", summary)
    return summary
