"""Scenario ``work_precision``: error against run time for every solver the FMU offers.

For each case (a regular start over 30 s, a chaotic start over 3 s -- before the reference itself
diverges --, and a stiff light suspension over 2 s) and each solver, a sweep of tolerances
(adaptive methods) or step sizes (fixed-step methods) runs **through fmpy** at a 10 ms
communication step, and one mid setting per solver also at 1 ms and 100 ms. Recorded per run:
final-horizon error and maximum error over the horizon (max over phi1, phi2, omega1, omega2
against the cached reference, :mod:`double_pendulum.analysis.reference`), energy drift (frictionless: max
|E_total - E0| / E0; with dissipation: max |energy_residual| / E0), RHS evaluations and steps
(FMU outputs), CPU time (median of the repeats, with the spread). Failed or unstable
configurations are kept in the table with their status and message.

Outputs: ``work_precision.csv``, one log-log plot per case (max error against CPU time, one line
per method), ``report.md`` naming the fastest method per accuracy band and case.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis.reference import STATE_OUTPUTS, reference_solution
from double_pendulum.fmu.runner import FmuRunError, FmuRunner
from double_pendulum.results_io import write_json, write_table_csv, write_text
from double_pendulum.solvers import METHODS, make_method

DESCRIPTION = "error against CPU time for every solver, tolerance and communication step (through fmpy)"

BANDS = (1e-3, 1e-6, 1e-9)  # report the fastest configuration reaching each max-error level
COMM_STEPS = (1e-3, 1e-2, 1e-1)
BASE_COMM_STEP = 1e-2


@dataclass(frozen=True)
class Case:
    """A start state and horizon over which the reference is trustworthy."""

    name: str
    start: dict[str, Any]
    horizon: float
    quick_horizon: float
    dissipative: bool = False


CASES = (
    Case("regular", {"phi1_0": 0.3, "phi2_0": 0.3}, 30.0, 1.0),
    Case("chaotic", {"phi1_0": 2.0, "phi2_0": 2.0}, 3.0, 0.5),
    Case(
        "stiff_suspension",
        {"phi1_0": 1.0, "phi2_0": 1.0, "suspension": True, "M_s": 0.05, "k_x": 1e7, "k_y": 1e7, "c_x": 20.0,
         "c_y": 20.0},
        2.0,
        0.2,
        dissipative=True,
    ),
)


def settings_for(solver: str, quick: bool) -> list[dict[str, float]]:
    """The sweep of one solver: tolerances for adaptive methods, step sizes for fixed-step ones."""
    method = make_method(solver)
    if method.adaptive:
        tols = (1e-5, 1e-8) if quick else (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
        return [{"rtol": t, "atol": t * 1e-2} for t in tols]
    order = method.order
    if quick:
        steps = (1e-2, 5e-3)
    elif order == 1:
        steps = (1e-3, 1e-4, 2e-5)
    else:
        steps = (2e-2, 1e-2, 5e-3, 2e-3, 1e-3)
    return [{"fixed_step": h} for h in steps]


def _errors(result: np.ndarray, ref, comm_step: float) -> tuple[float, float]:
    """(final error, max error over the horizon) on the reference's output grid."""
    stride = comm_step / (ref.time[1] - ref.time[0])
    if stride >= 1:
        idx_ref = np.arange(0, len(ref.time), int(round(stride)))
        idx_res = np.arange(len(idx_ref))
    else:
        idx_res = np.arange(0, len(result), int(round(1 / stride)))
        idx_ref = np.arange(len(idx_res))
    n = min(len(idx_ref), len(idx_res))
    diff = np.max([np.abs(result[name][idx_res[:n]] - ref.states[name][idx_ref[:n]]) for name in STATE_OUTPUTS], axis=0)
    return float(diff[-1]), float(np.max(diff))


def run_config(runner: FmuRunner, case: Case, ref, solver: str, setting: dict, comm: float, horizon: float,
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
        msg = str(error).split("FMU says: ")[-1]
        row["status"] = "unstable" if "instability" in msg else "failed"
        row["message"] = msg[:200]
        return row
    med = statistics.median(cpu)
    row["cpu_time_s"] = med
    row["cpu_spread"] = (max(cpu) - min(cpu)) / med if med > 0 else 0.0
    row["final_error"], row["max_error"] = _errors(result, ref, comm)
    e0 = float(result["E_total"][0])
    drift = result["energy_residual"] if case.dissipative else result["E_total"] - e0
    row["energy_drift"] = float(np.max(np.abs(drift))) / e0
    row["rhs_evaluations"] = int(result["solver_rhs_evaluations"][-1])
    row["steps"] = int(result["solver_steps"][-1])
    return row


def best_per_band(rows: list[dict[str, Any]], case: str, floor: float) -> dict[str, Any]:
    """The fastest ok configuration of ``case`` whose max error is within each band's bound."""
    out = {}
    for bound in BANDS:
        if bound < floor:
            out[f"{bound:g}"] = None
            continue
        ok = [r for r in rows if r["case"] == case and r["status"] == "ok" and r["max_error"] <= bound]
        best = min(ok, key=lambda r: r["cpu_time_s"], default=None)
        out[f"{bound:g}"] = None if best is None else {k: best.get(k) for k in (
            "solver", "rtol", "fixed_step", "comm_step_s", "max_error", "cpu_time_s")}
    return out


def _report(rows, best, floors, quick) -> str:
    lines = ["# Work-precision report", "",
             "Generated by `double-pendulum run work_precision`" + (" --quick" if quick else "") + ".",
             "Error: max over phi1, phi2, omega1, omega2 against a DOP853 rtol 1e-13 reference "
             "(cross-checked with SciPy Radau: the floor below). CPU: median over repeats, through fmpy.", ""]
    for case, floor in floors.items():
        lines += [f"## {case}", "", f"Reference error floor: {floor:.1e}", "",
                  "| max error <= | fastest method | setting | comm step [s] | max error | CPU [s] |",
                  "|---|---|---|---|---|---|"]
        for bound, b in best[case].items():
            if b is None:
                lines.append(f"| {bound} | (none reached it, or below the reference floor) | | | | |")
            else:
                setting = f"rtol {b['rtol']:g}" if b.get("rtol") is not None else f"h {b['fixed_step']:g} s"
                lines.append(f"| {bound} | {b['solver']} | {setting} | {b['comm_step_s']:g} | "
                             f"{b['max_error']:.1e} | {b['cpu_time_s']:.3f} |")
        bad = [r for r in rows if r["case"] == case and r["status"] != "ok"]
        if bad:
            lines += ["", "Failed or unstable configurations:", ""]
            lines += [f"- {r['solver']} {r.get('rtol') or r.get('fixed_step')}: {r['status']}: {r.get('message', '')}"
                      for r in bad]
        lines.append("")
    return "\n".join(lines)


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
    write_text(out_dir / "report.md", _report(rows, best, floors, quick))
    summary = {"scenario": "work_precision", "quick": quick, "reference_error_floor": floors,
               "best_per_band": best, "configurations": len(rows),
               "failed_or_unstable": sum(r["status"] != "ok" for r in rows)}
    write_json(out_dir / "summary.json", summary)
    return summary
