"""Scenario ``free_swing``: the frictionless pendulum from a regular and a chaotic start.

Both runs go through the FMU with fmpy. Outputs in ``results/free_swing/``: one CSV per run,
plots of the angles, the bob traces, the energies and the phase portraits (the seed's
figs. 15/16), and ``summary.json`` with the energy drift, run time and motion statistics.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from double_pendulum import plots
from double_pendulum.fmu.runner import FmuRunner
from double_pendulum.runs.results_io import write_json, write_results_csv

DESCRIPTION = "frictionless swing from a regular (small-angle) and a chaotic (2 rad) start"

STARTS: dict[str, dict[str, float]] = {
    "regular": {"phi1_0": 0.3, "phi2_0": 0.3, "omega1_0": 0.0, "omega2_0": 0.0},
    "chaotic": {"phi1_0": 2.0, "phi2_0": 2.0, "omega1_0": 0.0, "omega2_0": 0.0},
}
SETTINGS = {"solver": "dop853", "rtol": 1e-10, "atol": 1e-12}
STOP_TIME = 30.0
OUTPUT_INTERVAL = 0.005


def _count_flips(phi: np.ndarray) -> int:
    """Number of times a rod passes the upright position (phi = pi mod 2 pi)."""
    turns = np.floor((np.asarray(phi) + np.pi) / (2 * np.pi))
    return int(np.count_nonzero(np.diff(turns)))


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Run both starts through the FMU and write CSV, plots and the summary."""
    stop_time = 3.0 if quick else STOP_TIME
    runs: dict[str, np.ndarray] = {}
    summary: dict = {
        "scenario": "free_swing",
        "settings": SETTINGS,
        "stop_time_s": stop_time,
        "output_interval_s": OUTPUT_INTERVAL,
        "runs": {},
    }
    for label, start in STARTS.items():
        t0 = time.process_time()
        result = runner.simulate({**start, **SETTINGS}, stop_time=stop_time, output_interval=OUTPUT_INTERVAL)
        cpu = time.process_time() - t0
        write_results_csv(out_dir / f"{label}.csv", result, runner.units)
        runs[label] = result
        e = result["E_total"]
        summary["runs"][label] = {
            "start_values": start,
            "E_total_0_J": float(e[0]),
            "max_relative_energy_drift": float(np.max(np.abs(e - e[0])) / abs(e[0])),
            "cpu_time_s": cpu,
            "flips_rod1": _count_flips(result["phi1"]),
            "flips_rod2": _count_flips(result["phi2"]),
            "max_abs_omega2_rad_s": float(np.max(np.abs(result["omega2"]))),
        }
    plots.plot_angles(runs, out_dir / "angles.png")
    plots.plot_traces(runs, out_dir / "traces.png")
    plots.plot_energy(runs, out_dir / "energy.png")
    plots.plot_phase_portraits(runs, out_dir / "phase_portraits.png")
    write_json(out_dir / "summary.json", summary)
    return summary
