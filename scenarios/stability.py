"""Scenario ``stability``: stiff and extreme cases through the FMU, each with a pass criterion.

Every case (:mod:`double_pendulum.analysis.solvers.stability_cases`) runs through fmpy and is judged on:

* the run finished (the solver did not give up) -- or, for a case marked ``expect_failure``,
  the failure was detected and reported with a message (status and text in the table);
* all outputs finite;
* ``|energy_residual| <= tol * E_scale`` with ``E_scale = max(E_total(0), (m1+m2) g (l1+l2))``
  (the residual closes the energy budget, so it measures only integration error);
* CPU time within the case's budget.

Explicit methods on the stiff cases are expected to fail (fixed step: blow-up detected from the
energy; adaptive: the step budget per doStep is exhausted), and the table shows the stiff solver
passing the same case. Outputs: ``stability.csv`` (one row per case), ``report.md``, plots of the
residual of the worst passing cases and CSVs of their trajectories.

Cost: the cases run on parallel worker processes (one per core, the longest first), about 25 s CPU
in all (a quick run: one process, about 4 s beyond the imports); each case's CPU time is the process
time of its own run. What made the cases expensive before (the cuts keep every case's point): the
stiff suspension cases run 0.5 s, the first half swing and ~1000 periods of the k = 1e8 N/m
suspension (Rodas4 resolves the lightly damped suspension mode, ~25 000 steps per simulated second;
with every loss mechanism ~0.9 ms a step, so that case runs 0.25 s); the stick-slip case runs its
first 10 s (at rest, from ~27 s, the sharp friction is a stiff damper and DOP853 needed ~27 000 steps
per second: the stuck cases cover that); Gauss4 takes 1000 s at h = 0.02 s; the tiny communication
step runs 0.1 s (10 000 doSteps).
"""

from __future__ import annotations

from pathlib import Path

from double_pendulum import plots
from double_pendulum.analysis.solvers.stability_cases import (
    case_cost,
    cases,
    report,
    run_case,
    run_case_item,
    summary_rows,
    worst_passing,
)
from double_pendulum.analysis.sweep import runner_map, where_runs
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.runs.progress import step
from double_pendulum.runs.results_io import write_json, write_results_csv, write_table_csv, write_text

__all__ = ["DESCRIPTION", "run", "run_case"]

DESCRIPTION = "stiff and extreme cases through the FMU with pass criteria (table, report, worst-case plots)"


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Run every case; write the table, the report, and plots/CSVs of the worst passing cases."""
    table = cases()
    step(f"{len(table)} cases through fmpy {where_runs(len(table), 1 if quick else None)}")
    outcomes = runner_map(run_case_item, [(case, quick) for case in table], runner, max_workers=1 if quick else None,
                          costs=[case_cost(case, quick) for case in table], label="stability cases", unit="case")
    rows, results = [], {}
    for case, (row, result) in zip(table, outcomes):
        rows.append(row)
        if result is not None:
            results[case.name] = result
    step("table, report and the worst passing cases")
    write_table_csv(out_dir / "stability.csv", rows)
    write_text(out_dir / "report.md", report(rows, quick))
    worst = worst_passing(rows, 3)
    for i, r in enumerate(worst):
        write_results_csv(out_dir / f"worst_{i + 1}.csv", results[r["case"]], runner.units)
    plots.plot_residuals({r["case"]: results[r["case"]] for r in worst}, out_dir / "worst_residuals.png")
    summary = {
        "scenario": "stability",
        "quick": quick,
        "cases": len(rows),
        "passed": sum(r["passed"] for r in rows),
        "rows": summary_rows(rows),
    }
    write_json(out_dir / "summary.json", summary)
    return summary
