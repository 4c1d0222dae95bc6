"""Scenario ``friction_budget``: where does the seed pendulum's energy go?

The seed pendulum released like the start of the measured track (Table 1, frame 0: the rods at
about -0.64 rad and 1.08 rad, at rest), run through the FMU for 60 s with each loss mechanism
alone (air drag on bobs and rods, bearing friction, the damped suspension) and all together.
Outputs: one CSV per run; ``energy_per_mechanism.png`` (E_total over time, log scale);
``energy_budget_stacked.png`` (all mechanisms: pendulum and suspension energy plus each
mechanism's dissipated work, stacked, adding up to the start energy); ``summary.json`` with each
mechanism's share of the loss and the exponential decay rate b fitted to E_total of each run.
These are the default coefficients' shares, illustrative, not the real pendulum's: the suspension's defaults
are assumed (the seed gives none), and ``loss_identification`` finds that the measured decay supports no
dominant suspension loss at them; ``suspension_transfer`` maps which suspensions would give the measured rate.

Cost: about 15 s CPU on two worker processes (a quick run, 5 s per run in this process: about 2 s beyond
the imports). DOP853 at rtol 1e-8 keeps the energy residual below 1e-6 J of the 0.65 J start energy (the
works and shares agree with rtol 1e-10 to 1e-6 relative); the outputs every 50 ms leave the decay rates b
within a tenth of their standard error of those fitted to outputs every 10 ms (the summary's ``precision``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis.decay.fit import fit_model
from double_pendulum.analysis.sweep import runner_map, timed_simulate, where_runs
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.runs.progress import step
from double_pendulum.runs.results_io import write_json, write_results_csv

DESCRIPTION = "energy budget of air drag, bearing friction and suspension, each alone and all together"

SEED_RELEASE = {"phi1_0": -0.64, "phi2_0": 1.08, "omega1_0": 0.0, "omega2_0": 0.0}
SETTINGS = {"solver": "dop853", "rtol": 1e-8, "atol": 1e-10}
RUNS: dict[str, dict[str, bool]] = {
    "frictionless": {},
    "air_drag": {"air_drag": True, "rod_drag": True},
    "bearing_friction": {"bearing_friction": True},
    "suspension": {"suspension": True},
    "all": {"air_drag": True, "rod_drag": True, "bearing_friction": True, "suspension": True},
}
WORK = {"air_drag": "W_air", "bearing_friction": "W_bearing", "suspension": "W_suspension"}
COEFFICIENTS_NOTE = "default, illustrative coefficients (the suspension's assumed): not fitted to the seed's pendulum"
"""Said on both figures: the budget is the defaults', which loss_identification finds the measured decay does not
support (its suspension fits worse than a rigid pivot); the shares are no finding about the real pendulum."""
STOP_TIME = 60.0
OUTPUT_INTERVAL = 0.05  # s; the energies are smooth on this grid (b moved by 0.02 % against 10 ms)
PRECISION = {
    "share_of_loss_all_on": "the works and shares to 1e-6 relative (rtol 1e-8 against 1e-10), |energy_residual| "
    "< 1e-6 J",
    "decay_rate_b_per_s": "fit to E_total every 50 ms; b_per_s_stderr is the fit's standard error (0.5 % for the "
    "suspension runs, taking the residuals as independent), the 50 ms sampling moves b by 0.02 % against 10 ms",
}


def _decay_rate(result: np.ndarray) -> dict[str, float]:
    """Fit E_total(t) = a exp(b t) (equal weights) and return a, b with standard errors."""
    fit = fit_model("exponential", result["time"], result["E_total"])
    return {
        "a_J": fit.value("a"),
        "a_J_stderr": fit.error("a"),
        "b_per_s": fit.value("b"),
        "b_per_s_stderr": fit.error("b"),
    }


def _in_short(summary: dict, quick: bool) -> str:
    """The plain summary (``in_short``): what was run, what was found, how sure; every number from ``summary``."""
    shares, every = summary["share_of_loss_all_on"], summary["runs"]["all"]
    return " ".join([
        f"The pendulum was released from the seed's start and run for {summary['stop_time_s']:g} s through the FMU: "
        "without friction, with each loss alone (air drag, bearing friction, a damped springy pivot) and with all "
        "three, each at its parameters' default values, not fitted to the measurement.",
        f"With all three on it lost {every['lost_fraction']:.0%} of its energy; of what the pendulum lost the "
        f"suspension took {shares['suspension']:.0%}, air drag {shares['air_drag']:.0%} and bearing friction "
        f"{shares['bearing_friction']:.0%} ({shares['still_in_suspension']:.0%} was still in the suspension).",
        f"All on, the energy decays at b = {summary['decay_rate_b_per_s']['all']:.4f} 1/s, against the "
        f"{summary['seed_measured_b_per_s']:g} 1/s the seed measured.",
        "How sure: the shares are exact for these parameter values; which values the real pendulum has, the "
        "loss_identification scenario asks." + (" A quick run: a smoke test." if quick else ""),
    ])


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Run every mechanism alone and all together; write CSVs, plots and the summary."""
    stop_time = 5.0 if quick else STOP_TIME
    results: dict[str, np.ndarray] = {}
    summary: dict = {
        "scenario": "friction_budget",
        "start_values": SEED_RELEASE,
        "settings": SETTINGS,
        "stop_time_s": stop_time,
        "output_interval_s": OUTPUT_INTERVAL,
        "runs": {},
    }
    step(f"{len(RUNS)} runs of {stop_time:g} s through fmpy {where_runs(len(RUNS), 1 if quick else None)}")
    options = {"stop_time": stop_time, "output_interval": OUTPUT_INTERVAL}
    items = [({**SEED_RELEASE, **SETTINGS, **switches}, options) for switches in RUNS.values()]
    timed = runner_map(timed_simulate, items, runner, max_workers=1 if quick else None, label="friction_budget runs",
                       costs=[len(s) + 1.0 for s in RUNS.values()])
    for (label, switches), (r, cpu) in zip(RUNS.items(), timed):
        write_results_csv(out_dir / f"{label}.csv", r, runner.units)
        results[label] = r
        e0, e_end = float(r["E_total"][0]), float(r["E_total"][-1])
        entry = {
            "switches": switches,
            "E_total_0_J": e0,
            "E_total_end_J": e_end,
            "lost_fraction": (e0 - e_end) / e0,
            "W_air_J": float(r["W_air"][-1]),
            "W_bearing_J": float(r["W_bearing"][-1]),
            "W_suspension_J": float(r["W_suspension"][-1]),
            "max_abs_energy_residual_J": float(np.max(np.abs(r["energy_residual"]))),
            "cpu_time_s": cpu,
        }
        if label != "frictionless":
            entry["exponential_fit"] = _decay_rate(r)
        summary["runs"][label] = entry

    # Shares of the energy the pendulum (the two bobs) lost, all mechanisms on: each mechanism's
    # dissipated work, plus what is still stored in the suspension at the end. They add up to 1.
    e_pend = results["all"]["E_pendulum"]
    lost = float(e_pend[0] - e_pend[-1])
    shares = {mech: float(results["all"][w][-1]) / lost for mech, w in WORK.items()}
    shares["still_in_suspension"] = float(results["all"]["E_suspension"][-1]) / lost
    summary["pendulum_energy_lost_all_on_J"] = lost
    summary["share_of_loss_all_on"] = shares
    summary["decay_rate_b_per_s"] = {
        label: summary["runs"][label]["exponential_fit"]["b_per_s"]
        for label in RUNS
        if label != "frictionless"
    }
    summary["seed_measured_b_per_s"] = -0.024
    summary["precision"] = PRECISION if not quick else {"quick": f"{stop_time:g} s runs: a smoke test, not the budget"}

    plots.plot_energy_per_mechanism(results, out_dir / "energy_per_mechanism.png", note=COEFFICIENTS_NOTE)
    plots.plot_energy_budget_stacked(results["all"], out_dir / "energy_budget_stacked.png", note=COEFFICIENTS_NOTE)
    summary["in_short"] = _in_short(summary, quick)
    write_json(out_dir / "summary.json", summary)
    return summary
