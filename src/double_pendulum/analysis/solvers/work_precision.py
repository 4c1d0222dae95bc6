"""Work-precision study: cases, solver settings, errors against a reference, the fastest method per band.

Error of a run (:func:`errors`): ``e(t) = max_i |x_i(t) - x_i^ref(t)|`` over the states
``x = (phi1, phi2, omega1, omega2)`` [rad, rad/s] against the cached reference
(:mod:`double_pendulum.analysis.solvers.reference`), on the output times the run and the reference share;
reported are the final error ``e(T)`` and the maximum over the horizon ``max_t e(t)``.
Energy drift (:func:`energy_drift`): ``max |E_total - E_0| / E_0`` frictionless, ``max |energy_residual| / E_0``
with dissipation. :func:`best_per_band` picks the fastest run (CPU time) whose max error is within
each band of :data:`BANDS`.
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunError, FmuRunner
from ...runs.results_io import report_opening
from ...solvers import make_method
from .reference import STATE_OUTPUTS, Reference, reference_solution

BANDS = (1e-3, 1e-6, 1e-9)  # report the fastest configuration reaching each max-error level
COMM_STEPS = (1e-2, 1e-1)  # the mid setting of every solver also runs at 100 ms (the cheapest: fewest doSteps)
THOROUGH_COMM_STEPS = (1e-3, 1e-2, 1e-1)  # --thorough adds 1 ms (ten times the doSteps: 30 s CPU)
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


def settings_for(solver: str, quick: bool, thorough: bool = False) -> list[dict[str, float]]:
    """The sweep of one solver: tolerances for adaptive methods, step sizes for fixed-step ones.

    Without ``thorough`` the sweeps leave out the settings that cost most and win no band (DOP853 reaches
    every band faster): Rodas4 stops at rtol 1e-8 (rtol 1e-10 and 1e-12 cost 3-16 s and 10-40 s a run),
    Dopri5 at rtol 1e-10 (1e-12: 2-6 s), Euler at h = 1e-4 s (2e-5 s: 8 s on the regular case).
    """
    method = make_method(solver)
    if method.adaptive:
        tols = (1e-5, 1e-8) if quick else (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
        if not quick and not thorough:
            tols = tols[:3] if solver == "rodas4" else tols[:4] if solver == "dopri5" else tols
        return [{"rtol": t, "atol": t * 1e-2} for t in tols]
    order = method.order
    if quick:
        steps: tuple[float, ...] = (1e-2, 5e-3)
    elif order == 1:
        steps = (1e-3, 1e-4, 2e-5) if thorough else (1e-3, 1e-4)
    else:
        steps = (2e-2, 1e-2, 5e-3, 2e-3, 1e-3)
    return [{"fixed_step": h} for h in steps]


def errors(result: np.ndarray, ref: Reference, comm_step: float) -> tuple[float, float]:
    """(final error, max error over the horizon) on the reference's output grid.

    The run's outputs every ``comm_step`` [s] are matched to the reference's samples at the same times
    (every k-th reference sample if ``comm_step`` is coarser, every k-th run sample if finer).
    """
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


def energy_drift(result: np.ndarray, dissipative: bool) -> float:
    """``max |E_total - E_0| / E_0`` (frictionless) or ``max |energy_residual| / E_0`` (with dissipation)."""
    e0 = float(result["E_total"][0])
    drift = result["energy_residual"] if dissipative else result["E_total"] - e0
    return float(np.max(np.abs(drift))) / e0


@dataclass(frozen=True)
class Timing:
    """How often a configuration runs: at least ``min_repeats`` times, then again while the CPU time
    of its runs so far [s] is below ``repeat_below_s``, at most ``max_repeats`` times. Cheap runs,
    whose timing is noisy and decides close races, get the median of several; expensive ones run once."""

    min_repeats: int = 1
    max_repeats: int = 5
    repeat_below_s: float = 0.5

    def more(self, cpu: list[float]) -> bool:
        """Whether to run once more after the runs timed in ``cpu`` [s]."""
        if len(cpu) < self.min_repeats:
            return True
        return len(cpu) < self.max_repeats and sum(cpu) < self.repeat_below_s

    def describe(self) -> str:
        if self.min_repeats == self.max_repeats:
            return f"median of {self.min_repeats} repeats"
        return (f"median of {self.min_repeats} to {self.max_repeats} repeats (repeated while the runs so far took "
                f"under {self.repeat_below_s:g} s CPU)")


TIMING = Timing(max_repeats=3, repeat_below_s=0.25)
THOROUGH_TIMING = Timing(min_repeats=3, max_repeats=5, repeat_below_s=1.0)


def timing_columns(cpu: list[float]) -> dict[str, float]:
    """``cpu_time_s``: the median CPU time [s] of the repeats; ``cpu_spread``: (max - min) / median;
    ``repeats``: how many runs were timed."""
    med = statistics.median(cpu)
    return {"cpu_time_s": med, "cpu_spread": (max(cpu) - min(cpu)) / med if med > 0 else 0.0, "repeats": len(cpu)}


STEP_FAILED = "the step was not completed: "  # what the FMU logs for a step it cannot do (fmu_src/slave_common.py)


def failure_columns(error: Exception) -> dict[str, str]:
    """``status`` (``unstable`` if the FMU reported an instability, else ``failed``) and its whole ``message``
    (without the ``fmi2DoStep: the step was not completed:`` prefix, which every failure shares)."""
    msg = str(error).split("FMU says: ")[-1].split(STEP_FAILED)[-1]
    return {"status": "unstable" if "instability" in msg else "failed", "message": msg}


def band_key(bound: float) -> str:
    """Summary key of a max-error band: ``1e-3`` -> ``"max_error_le_1e-3"`` (the bound on max_t e(t))."""
    return f"max_error_le_1e{round(math.log10(bound))}"


def setting_text(row: dict[str, Any]) -> str:
    """A run's solver setting in words: ``rtol 1e-08`` (adaptive) or ``h 0.005 s`` (fixed step)."""
    return f"rtol {row['rtol']:g}" if row.get("rtol") is not None else f"h {row['fixed_step']:g} s"


def accuracy_columns(result: np.ndarray, case: Case, ref: Reference, comm: float) -> dict[str, Any]:
    """Final and max error, energy drift, RHS evaluations and steps of a finished run."""
    final_error, max_error = errors(result, ref, comm)
    return {
        "final_error": final_error,
        "max_error": max_error,
        "energy_drift": energy_drift(result, case.dissipative),
        "rhs_evaluations": int(result["solver_rhs_evaluations"][-1]),
        "steps": int(result["solver_steps"][-1]),
    }


def best_per_band(rows: list[dict[str, Any]], case: str, floor: float) -> dict[str, Any]:
    """The fastest ok configuration of ``case`` (least CPU time) whose max error is within each band's bound.

    Keyed by :func:`band_key` (``"max_error_le_1e-3"``). A reached band gives ``reached: true``, the solver,
    its setting (``rtol`` for adaptive solvers, ``fixed_step_s`` for fixed-step ones), ``comm_step_s``,
    ``max_error`` and ``cpu_time_s``; otherwise ``reached: false`` and the ``reason``: no run reached it,
    or the bound lies below the reference's error floor ``floor`` (errors that small cannot be resolved).
    """
    out: dict[str, Any] = {}
    for bound in BANDS:
        if bound < floor:
            out[band_key(bound)] = {"reached": False, "reason": f"below the reference error floor {floor:.1e}"}
            continue
        ok = [r for r in rows if r["case"] == case and r["status"] == "ok" and r["max_error"] <= bound]
        best = min(ok, key=lambda r: r["cpu_time_s"], default=None)
        out[band_key(bound)] = {"reached": False, "reason": "no configuration reached it"} if best is None else {
            "reached": True, "solver": best["solver"],
            **({"rtol": best["rtol"]} if best.get("rtol") is not None else {"fixed_step_s": best["fixed_step"]}),
            **{k: best[k] for k in ("comm_step_s", "max_error", "cpu_time_s")}}
    return out


def report(
    rows: list[dict[str, Any]], best: dict[str, dict[str, Any]], floors: dict[str, float], quick: bool,
    timing: Timing = TIMING, thorough: bool = False,
) -> str:
    """The Markdown report: per case the reference floor, the fastest method per band, the failures."""
    median_spread = spread_value(rows)
    spread = (f"; the median spread (max - min) / median of repeated runs is {median_spread:.0%}"
              if median_spread is not None else "")
    option = " --quick" if quick else (" --thorough" if thorough else "")
    lines = [_opening(rows, best, spread_value(rows), quick).rstrip("\n"), "",
             f"Generated by `double-pendulum run work_precision{option}`.",
             "Error: max over phi1, phi2, omega1, omega2 against a DOP853 rtol 1e-13 reference "
             f"(cross-checked with SciPy's {'Radau rtol 1e-12' if thorough else 'DOP853 rtol 1e-13'}: their largest "
             "difference is the floor below; errors under it are not resolved and bands under it not ranked). "
             f"CPU: process time through fmpy, {timing.describe()}, configurations run on parallel worker "
             f"processes{spread}: CPU times closer than that do not rank the methods."
             + ("" if quick or thorough else " Left out here, as they cost most and win no band (DOP853 reaches "
                "every band faster): Rodas4 at rtol 1e-10 and 1e-12, Dopri5 at rtol 1e-12, Euler at h = 2e-5 s and "
                "the 1 ms communication step; `--thorough` adds them, cross-checks the references with Radau and "
                "times every run at least 3 times (about three times the CPU time)."), ""]
    for case, floor in floors.items():
        reached = [b["max_error"] for b in best[case].values() if b["reached"]]
        margin = (f" (the smallest error in the table below is {min(reached) / floor:.0f} times the floor)"
                  if reached and floor > 0 else "")
        lines += [f"## {case}", "", f"Reference error floor: {floor:.1e}{margin}", ""]
        lines += band_lines(best[case])
        lines += failure_lines([r for r in rows if r["case"] == case and r["status"] != "ok"])
        lines.append("")
    return "\n".join(lines)


def spread_value(rows: list[dict[str, Any]]) -> float | None:
    """Median relative spread (max - min) / median of the CPU times of repeated runs (None: none repeated)."""
    spreads = [r["cpu_spread"] for r in rows if r["status"] == "ok" and r.get("repeats", 1) > 1]
    return statistics.median(spreads) if spreads else None


def _opening(rows: list[dict[str, Any]], best: dict[str, dict[str, Any]], spread: float | None, quick: bool) -> str:
    """Title, plain summary and the words used."""
    winners: dict[str, int] = {}
    for bands in best.values():
        for b in bands.values():
            if b["reached"]:
                winners[b["solver"]] = winners.get(b["solver"], 0) + 1
    reached = sum(winners.values())
    top = max(winners, key=winners.get) if winners else None
    solvers = sorted({r["solver"] for r in rows})
    cases = ", ".join(best)
    noise = (f"CPU times closer than about {spread:.0%} do not rank the solvers (repeated runs spread that much on "
             "this shared machine)" if spread is not None else "the runs were timed once each, so close CPU times do "
             "not rank the solvers")
    return report_opening("Work-precision report" + (" (quick run)" if quick else ""), [
        f"Each of the FMU's {len(solvers)} solvers ({', '.join(solvers)}) was run on the cases {cases} at several "
        "tolerances or step sizes, and each run's largest error against a far more accurate reference was set "
        "against the CPU time it took.",
        (f"The fastest run to reach an error band was {top}'s in {winners[top]} of the {reached} bands reached "
         "(the report's tables give, per case and band, the fastest solver and its setting)." if top else
         "No run reached an error band in this run."),
        f"How sure: {noise}, and errors below a reference's own error floor are not resolved.",
    ], {
        "rtol": "an adaptive solver's relative error tolerance per step (the solver picks its steps to meet it)",
        "fixed step h": "the step of a solver without step control (euler, rk4, gauss4)",
        "communication step": "the interval at which fmpy exchanges values with the FMU",
        "error floor": "the largest difference between two independent references: errors below it are not "
                       "resolved",
        "error band": "all runs whose largest error is at most the band's bound (1e-3, 1e-6, 1e-9)",
    })


def band_lines(best: dict[str, Any]) -> list[str]:
    """Markdown table: per band the fastest method, or why none is given."""
    lines = ["| max error <= | fastest method | setting | comm step [s] | max error | CPU [s] |",
             "|---|---|---|---|---|---|"]
    for key, b in best.items():
        bound = key.removeprefix("max_error_le_")
        if not b["reached"]:
            lines.append(f"| {bound} | none: {b['reason']} | - | - | - | - |")
            continue
        setting = f"rtol {b['rtol']:g}" if "rtol" in b else f"h {b['fixed_step_s']:g} s"
        lines.append(f"| {bound} | {b['solver']} | {setting} | {b['comm_step_s']:g} | "
                     f"{b['max_error']:.1e} | {b['cpu_time_s']:.3f} |")
    return lines


def failure_lines(bad: list[dict[str, Any]]) -> list[str]:
    """Markdown table of the failed or unstable configurations, each with its communication step and the
    FMU's whole message (expected: too-large steps and non-stiff methods on the stiff case)."""
    if not bad:
        return []
    lines = ["", "Failed or unstable configurations (expected where the step is too large for the motion):", "",
             "| solver | setting | comm step [s] | status | FMU message |", "|---|---|---|---|---|"]
    lines += [f"| {r['solver']} | {setting_text(r)} | {r['comm_step_s']:g} | {r['status']} | "
              f"{r.get('message', '').replace('|', '/')} |" for r in bad]
    return lines


# ---------------------------------------------------------------------------- the runs
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


def run_task(runner: FmuRunner, task: tuple[str, Any]) -> Any:
    """Worker: a reference (``("reference", (case, horizon, cross_check))``) or a configuration
    (``("config", Config)``); here, not in the scenario module, so worker processes do not import Matplotlib."""
    kind, item = task
    if kind == "reference":
        case, horizon, cross_check = item
        return reference_solution(case.start, horizon, BASE_COMM_STEP, cross_check=cross_check)
    return run_config(runner, item)
