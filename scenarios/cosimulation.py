"""Scenario ``cosimulation``: the pendulum on its suspension, monolithic against split into two FMUs.

Runs the monolith (reference) and the split system (in-process Jacobi, linear extrapolation,
iterative coupling with rollback; libcosim on the SSP file; fmpy's container FMU) over macro steps
from 1e-4 s to 2e-2 s for a regular and a chaotic start and two suspensions, and maps where Jacobi
coupling stays bounded over mass ratio and h omega against the derived added-mass limit
(analysis: :mod:`~double_pendulum.analysis.coupling.cosimulation`,
:mod:`~double_pendulum.analysis.coupling.stability`; figures: :mod:`~double_pendulum.plots.coupling`).

Outputs in ``results/cosimulation/``: ``runs.csv``, ``stability_map.csv``, ``error_vs_macro_step.png``,
``error_vs_cpu_time.png``, ``coupling_energy.png``, ``stability_map.png``, ``summary.json``, ``report.md``.

Cost: about 35 s CPU; the split runs and the map points share one pool of worker processes, the longest
runs first. Plain Jacobi runs down to h = 0.1 ms, the container FMU
(about 0.5 s a run to write, extract and load, whatever h) at 1-10 ms, the others at 1-20 ms. A quick run
(0.05 s, the regular start on the default suspension, h = 1, 2 and 5 ms: the orders still come out at 1 and
2 within 5 %) runs in this process.
"""

from __future__ import annotations

import itertools
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from double_pendulum.analysis.coupling import cosimulation as study
from double_pendulum.analysis.coupling.report import report_text
from double_pendulum.analysis.coupling.stability import critical_mass_ratio, limit_table
from double_pendulum.analysis.sweep import parallel_map
from double_pendulum.fmu.build.fmi2 import build_fmu, fmu_is_current
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.plots import coupling as plots
from double_pendulum.runs.results_io import write_json, write_table_csv, write_text

MAP_SCHEMES = ("jacobi", "jacobi_sequential")
DESCRIPTION = "pendulum on suspension split into two FMUs: coupling error, energy and added-mass stability"

FULL = {
    "stop": 0.3, "starts": tuple(study.STARTS), "suspensions": tuple(study.SUSPENSIONS),
    "steps": (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2),
    "min_step": {"jacobi": 0.0, "jacobi_sequential": 1e-3, "extrapolation": 2e-4, "iterative": 1e-3,
                 "libcosim": 1e-3, "container": 1e-3},
    "max_step": {"container": 1e-2},
    "mass_ratios": (0.25, 0.4, 0.6, 0.8, 0.9, 1.1, 1.25, 2.0), "h_omegas": (0.1, 0.5, 1.0, 1.5, 2.0),
    "map_steps": 120, "zeta": 0.05,
}
QUICK = {
    "stop": 0.05, "starts": ("regular",), "suspensions": ("default",), "steps": (1e-3, 2e-3, 5e-3),
    "min_step": {m: 0.0 for m in study.METHODS}, "max_step": {},
    "mass_ratios": (0.7, 1.4), "h_omegas": (0.3,), "map_steps": 60, "zeta": 0.05,
}


def suspension_fmu(pendulum_fmu: Path, folder: Path) -> Path:
    """The Suspension FMU the split runs couple to ``pendulum_fmu``: the one ``build`` (and ``run``, which builds
    what is missing or stale) keeps next to it, if it is there and newer than its sources, else one built into
    ``folder``. Both are built by the same call from the same sources (about 2 s of CPU to build one)."""
    neighbour = pendulum_fmu.parent / "Suspension.fmu"
    if fmu_is_current(neighbour, "Suspension"):
        return neighbour
    return build_fmu(folder / "Suspension.fmu", "Suspension")


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict[str, Any]:
    """Run the plan, write CSVs, figures, summary and report (see the module docstring)."""
    wall = time.perf_counter()
    out_dir = Path(out_dir)
    plan = QUICK if quick else FULL
    fmu_dir = tempfile.TemporaryDirectory(prefix="dp_cosimulation_")
    fmus = (str(runner.fmu_path), str(suspension_fmu(Path(runner.fmu_path), Path(fmu_dir.name))))

    # split runs and the points of the stability map, in one pool (the longest first); the monolith per case
    methods, missing = study.available_methods()
    items = [(s, u, m, h, plan["stop"], fmus)
             for s, u, m, h in itertools.product(plan["starts"], plan["suspensions"], methods, plan["steps"])
             if plan["min_step"][m] <= h <= plan["max_step"].get(m, np.inf)]
    order = sorted(range(len(items)), key=lambda i: -study.run_cost(items[i][2], items[i][3], items[i][4]))
    map_items = [(mu, hw, plan["zeta"], plan["map_steps"], scheme) for scheme, mu, hw in
                 itertools.product(MAP_SCHEMES, plan["mass_ratios"], plan["h_omegas"])]
    done, workers = parallel_map(study.run_item, [("split", items[i]) for i in order] + [("map", i) for i in map_items],
                                 label="cosimulation runs and stability map", max_workers=None if not quick else 1)
    rows: list[dict[str, Any]] = [{} for _ in items]
    for i, row in zip(order, done):
        rows[i] = row
    points = done[len(items):]
    rows = study.drop_failed_engines(rows, missing)
    references = {(s, u): study.monolith(study.case_values(s, u), plan["stop"])
                  for s, u in itertools.product(plan["starts"], plan["suspensions"])}
    study.add_errors(rows, references)

    # stability map against the derived limit
    h_omega = np.geomspace(0.03, 3.0, 40)
    curves = {scheme: (h_omega, np.array([critical_mass_ratio(hw, plan["zeta"], scheme) for hw in h_omega]))
              for scheme in MAP_SCHEMES}

    summary = {
        "scenario": "cosimulation", "quick": quick, "stop_time_s": plan["stop"], "workers": workers,
        "skipped_methods": missing,
        "order_angles": study.orders(rows, "angle_error_rad"),
        "order_pivot": study.orders(rows, "pivot_error_m"),
        "order_energy": study.orders(rows, "energy_error_J"),
        "order_coupling_energy": study.orders(rows, "coupling_energy_J"),
        "orders_unresolved": {q: study.unresolved_orders(rows, f"{q}_{unit}") for q, unit in
                              (("angle", "error_rad"), ("pivot", "error_m"), ("energy", "error_J"))},
        "orders_unresolved_means": f"log|error| is not linear in log h (R^2 < {study.ORDER_MIN_R2:g}): the fitted "
                                   "slope is no order of convergence",
        "cheapest_to_1e-4_rad": study.cheapest(rows, 1e-4),
        "unstable_runs": [r["message"] for r in rows if not r["stable"]],
        "stability": {scheme: {"zeta": plan["zeta"],
                               "measured_limit": {f"h_omega_{hw:g}": bracket
                                                  for hw, bracket in study.measured_limit(points, scheme).items()},
                               "derived_limit": {f"h_omega_{hw:g}": critical_mass_ratio(hw, plan["zeta"], scheme)
                                                 for hw in plan["h_omegas"]},
                               "criterion": "spectral radius of the step map fitted to the run <= 1 + "
                                            f"{study.STABILITY_TOLERANCE:g}",
                               "max_abs_fitted_minus_derived_spectral_radius": max(
                                   (abs(p["spectral_radius_fitted"] - p["spectral_radius_derived"]) for p in points
                                    if p["scheme"] == scheme and math.isfinite(p["spectral_radius_fitted"])),
                                   default=math.nan),
                               "points_too_short_to_fit": sum(not math.isfinite(p["spectral_radius_fitted"])
                                                              for p in points if p["scheme"] == scheme),
                               "brackets_hold_derived_limit": all(
                                   lo <= critical_mass_ratio(hw, plan["zeta"], scheme) <= hi
                                   for hw, (lo, hi) in study.measured_limit(points, scheme).items()),
                               "derived_limit_small_step": 1.0,
                               "derived_limit_by_damping": limit_table(tuple(plan["h_omegas"]), scheme)}
                      for scheme in MAP_SCHEMES},
        "cpu_s_by_method": {m: sum(r["cpu_s"] for r in rows if r["method"] == m) for m in methods},
    }
    write_table_csv(out_dir / "runs.csv", rows)
    write_table_csv(out_dir / "stability_map.csv", points)
    plots.plot_against(rows, "macro_step_s", "angle_error_rad", out_dir / "error_vs_macro_step.png",
                       xlabel="macro step h [s]", ylabel="angle error at the stop time [rad]",
                       title="Coupling error against macro step (reference: monolithic FMU)")
    plots.plot_against(rows, "cpu_s", "angle_error_rad", out_dir / "error_vs_cpu_time.png",
                       xlabel="CPU time of the run [s]", ylabel="angle error at the stop time [rad]",
                       title="Coupling error against CPU time")
    plots.plot_against(rows, "macro_step_s", "coupling_energy_J", out_dir / "coupling_energy.png",
                       xlabel="macro step h [s]", ylabel="energy made by the coupling [J]",
                       title="Energy the coupling creates or destroys: |W_input + W_in|, the work the pendulum "
                             "receives minus the work the suspension gives")
    plots.plot_stability_map(points, curves, out_dir / "stability_map.png")
    summary["wall_s"] = time.perf_counter() - wall
    write_json(out_dir / "summary.json", summary)
    write_text(out_dir / "report.md", report_text(summary, rows))
    fmu_dir.cleanup()
    return summary
