"""Hard cases for the FMU (stiff, near-singular, long, extreme) and their pass criteria.

Each :class:`Case` is judged (:func:`judge`) on its table row (:func:`evaluate_result`):

* the run finished -- or, for a case marked ``expect_failure``, it failed *loudly*: the failure was
  detected and reported with a message;
* all outputs finite;
* ``|energy_residual| <= tol * E_scale`` with ``E_scale = max(E_total(0), (m1+m2) g (l1+l2))`` [J]
  (:func:`energy_scale`; the residual closes the energy budget, so it measures only integration error);
* CPU time within the case's budget [s].
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunError, FmuRunner
from ...model.parameters import PendulumParameters
from ...runs.results_io import report_opening

STIFF = "rodas4"
SYMPLECTIC = "gauss4"
BASE = {"phi1_0": 1.0, "phi2_0": 1.0}
STIFF_SUSPENSION = {"suspension": True, "M_s": 0.01, "k_x": 1e8, "k_y": 1e8, "c_x": 200.0, "c_y": 200.0}
STUCK = {"phi1_0": 5e-4, "phi2_0": 0.0, "bearing_friction": True, "c_R1": 0.05, "c_R2": 0.05, "omega_reg": 1e-6}
STICK = {"phi1_0": 0.05, "phi2_0": 0.03, "bearing_friction": True, "c_R1": 0.05, "c_R2": 0.05, "omega_reg": 1e-6}
STIFF_STOP = 0.5  # s, stiff-suspension cases: the first half swing, ~1000 suspension periods at k = 1e8 N/m
QUICK_STIFF_STOP = 0.02  # s, the same in a quick run (a smoke test: ~40 suspension periods at k = 1e8 N/m)


@dataclass(frozen=True)
class Case:
    """One hard case: FMU start values, run length, communication step and its pass criterion."""

    name: str
    start: dict[str, Any]
    stop_time: float = 2.0
    output_interval: float = 0.01
    tol: float = 1e-6  # allowed |energy_residual| / E_scale
    cpu_budget_s: float = 60.0
    expect_failure: bool = False
    note: str = ""
    quick_stop_time: float | None = None
    tags: tuple[str, ...] = field(default_factory=tuple)


def critical_damping(k: float, m: float) -> float:
    """c = 2 sqrt(k m) [N s/m]: critical damping of a mass m [kg] on a spring k [N/m]."""
    return 2.0 * math.sqrt(k * m)


def cases() -> list[Case]:
    """The table of hard cases (see the module docstring for the criteria)."""
    p = PendulumParameters()
    m_t = 0.05 + p.m1 + p.m2
    k = 1e6
    c_crit = critical_damping(k, m_t)
    stiff: dict[str, Any] = {"stop_time": STIFF_STOP, "quick_stop_time": QUICK_STIFF_STOP}
    return [
        Case("stiff suspension k=1e8, M_s=0.01, stiff solver", {**BASE, **STIFF_SUSPENSION, "solver": STIFF,
             "rtol": 1e-8, "atol": 1e-12}, **stiff, note="omega_s ~ 1.3e4 rad/s"),
        Case("stiff suspension k=1e8, M_s=0.01, rk4 h=1e-3", {**BASE, **STIFF_SUSPENSION, "solver": "rk4",
             "fixed_step": 1e-3}, **stiff, expect_failure=True, note="explicit: unstable, blow-up must be detected"),
        Case("stiff suspension k=1e8, M_s=0.01, dop853 (step budget)", {**BASE, **STIFF_SUSPENSION,
             "solver": "dop853", "rtol": 1e-8, "max_steps": 200}, **stiff, expect_failure=True,
             note="explicit adaptive: stability-limited steps exhaust the per-doStep budget"),
        Case("stiff suspension k=1e7, M_s=0.05, dop853", {**BASE, **STIFF_SUSPENSION, "M_s": 0.05, "k_x": 1e7,
             "k_y": 1e7, "solver": "dop853", "rtol": 1e-8}, **stiff, note="explicit but affordable"),
        Case("critically damped suspension", {**BASE, "suspension": True, "M_s": 0.05, "k_x": k, "k_y": k,
             "c_x": c_crit, "c_y": c_crit, "solver": STIFF, "rtol": 1e-8}, **stiff,
             note=f"c = 2 sqrt(k M_t) = {c_crit:.0f}"),
        Case("strongly over-damped suspension", {**BASE, "suspension": True, "M_s": 0.05, "k_x": k, "k_y": k,
             "c_x": 100 * c_crit, "c_y": 100 * c_crit, "solver": STIFF, "rtol": 1e-8}, **stiff, note="c = 100 c_crit"),
        Case("sharp bearing regularisation 1e-6 rad/s, stick-slip swings", {**STICK, "solver": "dop853",
             "rtol": 1e-8}, stop_time=10.0, quick_stop_time=2.0,
             note="the first 10 s of ~27 s of swings decaying by Coulomb friction; dop853 steps over the "
             "reversals (at rest the friction is a stiff damper: dop853 then needs ~27 000 steps/s, see the "
             "stuck cases)"),
        Case("sharp bearing regularisation 1e-6 rad/s, stuck, stiff solver", {**STUCK, "solver": STIFF,
             "rtol": 1e-8}, stop_time=5.0, note="at rest: friction acts as a damper c_R r_b |F| / omega_reg"),
        Case("sharp bearing regularisation 1e-6 rad/s, stuck, dop853 (step budget)", {**STUCK,
             "solver": "dop853", "rtol": 1e-8, "max_steps": 20}, stop_time=5.0, expect_failure=True,
             note="explicit: stability limits h to ~1e-4 s; budget 20 steps per 10 ms"),
        Case("m2 = 1e-4 m1", {**BASE, "m2": 1e-4 * p.m1, "solver": "dop853", "rtol": 1e-10}, tol=1e-7,
             note="near-singular mass matrix"),
        Case("m1 = 1e-4 m2", {**BASE, "m1": 1e-4 * p.m2, "solver": "dop853", "rtol": 1e-10}, tol=1e-7),
        Case("l2 = 1 mm", {**BASE, "l2": 1e-3, "solver": "dop853", "rtol": 1e-10}, tol=1e-7,
             note="fast lower pendulum, omega ~ 100 rad/s"),
        Case("high energy, many flips (omega2 = 50 rad/s)", {"phi1_0": 0.0, "phi2_0": 0.0, "omega1_0": 20.0,
             "omega2_0": 50.0, "solver": "dop853", "rtol": 1e-10}, stop_time=10.0, quick_stop_time=2.0, tol=1e-7),
        Case("1000 s frictionless, gauss4", {"phi1_0": 0.3, "phi2_0": 0.3, "solver": SYMPLECTIC,
             "fixed_step": 0.02}, stop_time=1000.0, quick_stop_time=20.0, output_interval=0.5, tol=1e-6,
             cpu_budget_s=300.0, note="symplectic: bounded energy error"),
        Case("1000 s frictionless, dop853 rtol 1e-10", {"phi1_0": 0.3, "phi2_0": 0.3, "solver": "dop853",
             "rtol": 1e-10}, stop_time=1000.0, quick_stop_time=20.0, output_interval=0.5, tol=1e-7,
             cpu_budget_s=300.0),
        Case("large communication step 0.5 s", {**BASE, "solver": "dop853", "rtol": 1e-10}, stop_time=20.0,
             output_interval=0.5, tol=1e-8),
        Case("tiny communication step 1e-5 s", {**BASE, "solver": "dop853", "rtol": 1e-10}, stop_time=0.1,
             quick_stop_time=0.01, output_interval=1e-5, tol=1e-8, note="10 000 doSteps"),
        Case("unstable upright equilibrium", {"phi1_0": math.pi, "phi2_0": math.pi, "solver": "dop853",
             "rtol": 1e-12, "atol": 1e-14}, stop_time=10.0, tol=1e-9, note="stays up for a while, then falls"),
        Case("all mechanisms, stiff suspension, stiff solver", {**BASE, **STIFF_SUSPENSION, "k_x": 1e7, "k_y": 1e7,
             "air_drag": True, "rod_drag": True, "bearing_friction": True, "solver": STIFF, "rtol": 1e-8},
             **{**stiff, "stop_time": STIFF_STOP / 2}, note="0.25 s, ~160 suspension periods: ~0.9 ms a Rodas4 step "
             "with every loss mechanism"),
    ]


def _energy_scale(start: dict[str, Any]) -> float:
    p = PendulumParameters(**{k: start[k] for k in ("m1", "m2", "l1", "l2", "g") if k in start})
    return (p.m1 + p.m2) * p.g * (p.l1 + p.l2)


def energy_scale(start: dict[str, Any]) -> float:
    """``(m1 + m2) g (l1 + l2)`` [J] of the pendulum in ``start`` (defaults for the values not given).

    The potential energy from hanging to both rods upright is twice this; residuals are judged relative to it.
    """
    p = PendulumParameters(**{k: start[k] for k in ("m1", "m2", "l1", "l2", "g") if k in start})
    return (p.m1 + p.m2) * p.g * (p.l1 + p.l2)


def run_length(case: Case, quick: bool) -> float:
    """Run length [s]: the case's own, or in a quick run its ``quick_stop_time`` (if any), at most 5 s."""
    stop = case.quick_stop_time if (quick and case.quick_stop_time) else case.stop_time
    if quick:
        stop = min(stop, 5.0)
    return stop


def new_row(case: Case, stop: float) -> dict[str, Any]:
    """The table row of a case before it runs: name, solver, run length and step, expectation, note."""
    return {"case": case.name, "solver": case.start.get("solver", "dop853"), "stop_time_s": stop,
            "output_interval_s": case.output_interval, "expect_failure": case.expect_failure, "note": case.note}


def failure_message(error: Exception) -> str:
    """The FMU's own words from an FMU run error (after ``FMU says: ``), at most 300 characters."""
    return str(error).split("FMU says: ")[-1][:300]


def measured_columns(case: Case, result: np.ndarray | None) -> dict[str, Any]:
    """The columns measured on a (possibly partial) result; none if the run produced no output.

    ``finite``, ``max_rel_energy_residual = max |energy_residual| / E_scale`` with
    ``E_scale = max(E_total(0), energy_scale(start))`` [J], ``solver_steps``, ``rhs_evaluations``,
    ``reached_time_s``.
    """
    if result is None or not len(result):
        return {}
    scale = max(float(result["E_total"][0]), energy_scale(case.start))
    return {
        "finite": all(bool(np.all(np.isfinite(result[n]))) for n in result.dtype.names),
        "max_rel_energy_residual": float(np.max(np.abs(result["energy_residual"]))) / scale,
        "solver_steps": int(result["solver_steps"][-1]),
        "rhs_evaluations": int(result["solver_rhs_evaluations"][-1]),
        "reached_time_s": float(result["time"][-1]),
    }


def judged_row(row: dict[str, Any], case: Case, result: np.ndarray | None) -> dict[str, Any]:
    """``row`` with the measured columns of ``result`` and the verdict of :func:`judge` (``passed``, ``verdict``)."""
    out = {**row, **measured_columns(case, result)}
    out["passed"], out["verdict"] = judge(case, out)
    return out


def judge(case: Case, row: dict[str, Any]) -> tuple[bool, str]:
    """Apply the case's pass criterion to its table row."""
    if case.expect_failure:
        if row["status"] == "failed" and row["message"]:
            return True, "failure detected and reported, as expected"
        return False, "expected the explicit solver to fail loudly, but it finished"
    if row["status"] != "finished":
        return False, f"solver gave up: {row['message']}"
    if not row.get("finite", False):
        return False, "non-finite outputs"
    if row["max_rel_energy_residual"] > case.tol:
        return False, f"energy residual {row['max_rel_energy_residual']:.2e} > {case.tol:.0e}"
    if row["cpu_time_s"] > case.cpu_budget_s:
        return False, f"CPU time {row['cpu_time_s']:.1f} s > budget {case.cpu_budget_s:.0f} s"
    return True, "ok"


def report(rows: list[dict[str, Any]], quick: bool) -> str:
    """The Markdown report: criteria, one table line per case, the failure messages and the tally."""
    n_pass = sum(r["passed"] for r in rows)
    loud = sum(1 for r in rows if r["status"] == "failed" and r["passed"])
    worst = max((r["max_rel_energy_residual"] for r in rows if r["status"] == "finished"), default=0.0)
    lines = [
        report_opening("Stability report" + (" (quick run: shortened runs)" if quick else ""), [
            f"The FMU was run through {len(rows)} hard cases (stiff or heavily damped suspensions, near-sharp "
            "friction, extreme masses and lengths, many flips, 1000 s runs, very large and very small communication "
            "steps), each with a pass criterion.",
            (f"All {len(rows)} passed: every run that finished kept the energy balance within its tolerance "
             f"(the worst relative energy residual was {worst:.1e}), and {loud} explicit-solver runs on stiff cases "
             "stopped with an error message, as they should, instead of returning wrong numbers."
             if n_pass == len(rows) else
             f"{n_pass} of {len(rows)} passed; the table below says why the others failed (the worst relative "
             f"energy residual of a finished run was {worst:.1e})."),
            "How sure: each case is one run on this machine; the CPU budgets are generous limits, not timings.",
        ], {
            "energy residual": "E_total(t) plus the dissipated work minus the work fed in minus E_total(0): zero "
                               "for an exact solution, so its size measures the integration error; relative: "
                               "divided by the case's energy scale",
            "explicit solver": "a solver whose step uses only known values (rk4, dop853); on a stiff case it needs "
                               "tiny steps or fails, where an implicit one (rodas4, gauss4) copes",
            "communication step": "the interval at which the host exchanges values with the FMU",
            "rtol": "an adaptive solver's relative error tolerance per step",
        }).rstrip("\n"),
        "",
        "Generated by `double-pendulum run stability`" + (" --quick (shortened runs)" if quick else "") + ".",
        "Criteria: run finished (or, for explicit solvers on stiff cases, failed *loudly*), finite outputs,",
        "|energy_residual| / E_scale within the case tolerance, CPU time within budget.",
        "The residual is given for finished runs only (-: the run stopped early); the solver steps and the status",
        "are in `stability.csv`.",
        "",
        "| case | solver | passed | verdict | max rel. residual | CPU [s] |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        res = r.get("max_rel_energy_residual") if r["status"] == "finished" else None
        lines.append(
            f"| {r['case']} | {r['solver']} | {'yes' if r['passed'] else '**NO**'} | {r['verdict']} | "
            f"{'-' if res is None else f'{res:.1e}'} | {r['cpu_time_s']:.2f} |"
        )
    failed = [r for r in rows if r["status"] == "failed"]
    if failed:
        lines += ["", "## Failure messages (as reported by the FMU)", ""]
        lines += [f"- **{r['case']}**: {r['message']}" for r in failed]
    lines += ["", f"{n_pass} of {len(rows)} cases passed their criterion."]
    return "\n".join(lines) + "\n"


def summary_rows(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The table rows for ``summary.json``: empty texts (no note, no message) left out rather than written empty."""
    return [{k: v for k, v in r.items() if v != ""} for r in rows]


def worst_passing(rows: list[dict[str, Any]], n: int = 3) -> list[dict[str, Any]]:
    """The ``n`` finished rows with the largest relative energy residual, worst first."""
    passing = [r for r in rows if r["status"] == "finished" and "max_rel_energy_residual" in r]
    return sorted(passing, key=lambda r: r["max_rel_energy_residual"], reverse=True)[:n]


# ---------------------------------------------------------------------------- running a case
def run_case(runner: FmuRunner, case: Case, quick: bool) -> tuple[dict[str, Any], np.ndarray | None]:
    """Run one case through the FMU and judge it; return the table row and the result (if any)."""
    stop = run_length(case, quick)
    row = new_row(case, stop)
    t0 = time.process_time()
    result = None
    try:
        result = runner.simulate(case.start, stop_time=stop, output_interval=case.output_interval)
        row["status"] = "finished"
        row["message"] = ""
    except FmuRunError as error:
        row["status"] = "failed"
        row["message"] = failure_message(error)
        result = error.partial_result
    row["cpu_time_s"] = time.process_time() - t0
    return judged_row(row, case, result), result


def run_case_item(runner: FmuRunner, item: tuple[Case, bool]) -> tuple[dict[str, Any], np.ndarray | None]:
    """Worker (:func:`double_pendulum.analysis.sweep.runner_map`): :func:`run_case` of ``(case, quick)``; it lives
    here, not in the scenario module, so worker processes do not import Matplotlib."""
    return run_case(runner, *item)


def case_cost(case: Case, quick: bool) -> float:
    """A rough CPU estimate [s] of a case (to start the long ones first), from the CPU seconds per
    simulated second of a full run: Rodas4 ~4 (~15 with drag), DOP853 over sharp bearing friction ~1,
    Gauss4 at 10 ms ~0.01, DOP853 otherwise ~0.003; tiny communication steps add ~5 s."""
    solver = case.start.get("solver", "dop853")
    per_s = {"rodas4": 4.0, "gauss4": 0.01}.get(solver, 0.003)
    if solver == "dop853" and case.start.get("omega_reg") is not None:
        per_s = 1.0
    if solver == "rodas4" and case.start.get("air_drag"):
        per_s *= 4.0
    return run_length(case, quick) * per_s + (5.0 if case.output_interval < 1e-3 else 0.0)
