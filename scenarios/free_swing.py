"""Scenario ``free_swing``: the frictionless pendulum from a regular and a chaotic start, and the chaotic one
again from a start a hair's breadth away.

Every run goes through the FMU with fmpy. Outputs in ``results/free_swing/``: one CSV per run, plots of the
angles, the bob traces, the energies and the phase portraits (the seed's figs. 15/16) of the regular and the
chaotic run, ``twin_starts.gif`` (the two chaotic starts in real time, drawn from their CSV files: they stay
together, then part), and ``summary.json`` with the energy drift, run time and motion statistics and when the
two chaotic starts part.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from double_pendulum import plots
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.runs.results_io import read_results_csv, write_json, write_results_csv

DESCRIPTION = "frictionless swing from a regular (small-angle) and a chaotic (2 rad) start"

NUDGE_RAD = 1e-5
"""How much larger [rad] phi1_0 is in the run ``chaotic_nudged`` than in ``chaotic``: the upper bob starts 3
micrometres further along its circle, a twentieth of a hair's width."""
STARTS: dict[str, dict[str, float]] = {
    "regular": {"phi1_0": 0.3, "phi2_0": 0.3, "omega1_0": 0.0, "omega2_0": 0.0},
    "chaotic": {"phi1_0": 2.0, "phi2_0": 2.0, "omega1_0": 0.0, "omega2_0": 0.0},
    "chaotic_nudged": {"phi1_0": 2.0 + NUDGE_RAD, "phi2_0": 2.0, "omega1_0": 0.0, "omega2_0": 0.0},
}
PLOTTED = ("regular", "chaotic")
"""The runs the figures show (the nudged one only differs from ``chaotic`` once the two have parted)."""
SETTINGS = {"solver": "dop853", "rtol": 1e-10, "atol": 1e-12}
STOP_TIME = 30.0
OUTPUT_INTERVAL = 0.005
APART_M = 0.01
"""The two chaotic starts count as parted once their lower bobs are this far apart [m]."""
ANIMATION_S = 10.0
"""The animation shows the first 10 s (the default run's starts part after about 4 s); a quick run all of its 3 s."""


def _count_flips(phi: np.ndarray) -> int:
    """Number of times a rod passes the upright position (phi = pi mod 2 pi)."""
    turns = np.floor((np.asarray(phi) + np.pi) / (2 * np.pi))
    return int(np.count_nonzero(np.diff(turns)))


def _parting(a: np.ndarray, b: np.ndarray) -> dict:
    """When the lower bobs of two runs on the same time grid are first :data:`APART_M` apart (None: not within the
    runs), and how far apart they are at the end [m]."""
    distance = np.hypot(a["x2"] - b["x2"], a["y2"] - b["y2"])
    apart = np.flatnonzero(distance > APART_M)
    return {
        "phi1_0_difference_rad": NUDGE_RAD,
        "lower_bobs_1cm_apart_at_s": float(a["time"][apart[0]]) if len(apart) else None,
        "lower_bob_distance_at_end_m": float(distance[-1]),
        "null_means": {"lower_bobs_1cm_apart_at_s": "the lower bobs stayed within 1 cm of each other all the run"},
    }


def _animate(out_dir: Path, parting: dict) -> None:
    """``twin_starts.gif``: the two chaotic runs as their CSV files hold them, over the first :data:`ANIMATION_S`."""
    a, b = (read_results_csv(out_dir / f"{label}.csv") for label in ("chaotic", "chaotic_nudged"))
    rows = a["time"] <= ANIMATION_S + 1e-9
    parted = parting["lower_bobs_1cm_apart_at_s"]
    note = f"1 cm apart after {parted:.2f} s" if parted is not None else "within 1 cm of each other throughout"
    swings = [plots.swing(a[rows], "first start", "C0"), plots.swing(b[rows], "second start", "C3")]
    phi = STARTS["chaotic"]["phi1_0"]
    plots.animate_swings(a["time"][rows], swings, out_dir / "twin_starts.gif",
                         title=f"frictionless, from phi1_0 = {phi:g} and {phi:g} + {NUDGE_RAD:g} rad:\n"
                               f"the lower bobs are {note}")


def _in_short(summary: dict, quick: bool) -> str:
    """The plain summary (``in_short``): what was run, what was found, how sure; every number from ``summary``."""
    runs, twins, stop = summary["runs"], summary["twin_starts"], summary["stop_time_s"]
    drift = max(entry["max_relative_energy_drift"] for entry in runs.values())
    parted = twins["lower_bobs_1cm_apart_at_s"]
    part = (f"kept its lower bob within 1 cm of the first one's for {parted:.1f} s, then went its own way"
            if parted is not None else f"kept its lower bob within 1 cm of the first one's for the whole {stop:g} s")
    return " ".join([
        f"The pendulum without friction was run through the FMU for {stop:g} s from a small start (both rods at "
        f"{STARTS['regular']['phi1_0']:g} rad) and a large one (both at {STARTS['chaotic']['phi1_0']:g} rad).",
        f"Its energy stayed what it was at the start to {drift:.0e} (relative): nothing is lost without friction, "
        "and the integrator adds nothing that matters.",
        f"From the small start the rods swing to and fro; from the large one the lower rod turned over "
        f"{runs['chaotic']['flips_rod2']} times.",
        f"A second large start, {NUDGE_RAD:g} rad from the first (a few micrometres at the upper bob), {part}: "
        "the motion from the large start is chaotic." + (" A quick run: a smoke test." if quick else ""),
    ])


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
    summary["twin_starts"] = _parting(runs["chaotic"], runs["chaotic_nudged"])
    shown = {label: runs[label] for label in PLOTTED}
    plots.plot_angles(shown, out_dir / "angles.png")
    plots.plot_traces(shown, out_dir / "traces.png")
    plots.plot_energy(shown, out_dir / "energy.png")
    plots.plot_phase_portraits(shown, out_dir / "phase_portraits.png")
    _animate(out_dir, summary["twin_starts"])
    summary["in_short"] = _in_short(summary, quick)
    write_json(out_dir / "summary.json", summary)
    return summary
