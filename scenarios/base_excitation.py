"""Scenario ``base_excitation``: the pivot driven through the FMU's inputs by fmpy (``simulate_fmu(input=...)``).

1. **Kapitza**: in the single-pendulum limit (m2 = 1e-4 m1) the upright threshold amplitude of a
   vertical vibration y = a sin(omega t) at omega = 50 rad/s, bisected on the Floquet multipliers of
   the system as simulated (the monodromy matrix of one period through the FMU, the acceleration held
   over each communication step), against the exact bound of that held input, the exact Mathieu bound
   of the continuous sinusoid and a^2 omega^2 = 2 g l.
2. **Acheson**: a map over amplitude and frequency of the inverted double pendulum's upright position,
   stable or not by its simulated Floquet multipliers, against the linear theory (each normal mode an
   inverted simple pendulum of length g / omega_i^2: Mathieu's equation, and its held-input version),
   with example runs.
3. **Resonance**: pivot torque tau1 = T0 sin(omega t) with a viscous pivot bearing; steady-state
   amplitudes against omega near the two normal modes, peaks against the damped linear response.

Analysis: ``double_pendulum.analysis`` excitation, excitation_theory, excitation_study,
excitation_report; figures: ``double_pendulum.plots.excitation``. Map and resonance runs go through
the FMU in parallel worker processes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from double_pendulum.analysis.excitation import report as rep
from double_pendulum.analysis.excitation import study
from double_pendulum.analysis.excitation.drive import TORQUE_OUTPUTS, run_cases, run_torque
from double_pendulum.analysis.excitation.theory import held_floquet_exponent
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.plots import excitation as fig
from double_pendulum.runs.results_io import write_json, write_results_csv, write_table_csv, write_text

DESCRIPTION = "pivot vibration and torque through the inputs: Kapitza threshold, Acheson's upright map, resonance"


@dataclass(frozen=True)
class Plan:
    """Sizes of the three studies and the number of worker processes (None: all cores)."""

    kapitza: study.KapitzaSetup
    acheson: study.AchesonSetup
    resonance: study.ResonanceSetup
    workers: int | None


FULL = Plan(
    study.KapitzaSetup(),
    study.AchesonSetup(omegas=tuple(np.linspace(60.0, 300.0, 11)), amplitudes=tuple(np.linspace(0.0035, 0.042, 12))),
    study.ResonanceSetup(n_broad=14),
    None,
)
QUICK = Plan(
    study.KapitzaSetup(stop_time=2.5, steps_per_period=20, iterations=8),
    study.AchesonSetup(omegas=(100.0, 200.0), amplitudes=(0.005, 0.02, 0.04),
                       example_amplitudes=(0.022,), example_stop_time=1.0),
    study.ResonanceSetup(settle_time=6.0, window=4.0, step=0.025, n_broad=3, offsets=(-0.025, 0.0, 0.025)),
    1,
)


def write_tables(out: Path, kap: study.KapitzaResult, map_rows: list, bands: list, res_rows: list,
                 peaks: list) -> None:
    """The tables: bisection probes, map points, measured against theoretical bands, resonance curve and peaks."""
    write_table_csv(out / "kapitza_bisection.csv", rep.unit_headers(kap.bisection.probes))
    write_table_csv(out / "acheson_map.csv", rep.unit_headers(map_rows))
    omegas = np.array([b["omega_rad_per_s"] for b in bands])
    theory = study.theory_boundaries(omegas)
    write_table_csv(out / "acheson_bands.csv", rep.unit_headers([
        {**b, "theory_kapitza_m": k, "theory_lower_m": lo, "theory_upper_m": up}
        for b, k, lo, up in zip(bands, theory["kapitza_m"], theory["lower_m"], theory["upper_m"])]))
    write_table_csv(out / "resonance_curve.csv", rep.unit_headers(sorted(res_rows, key=lambda r: r["omega_rad_per_s"])))
    write_table_csv(out / "resonance_peaks.csv", rep.unit_headers(peaks))


def draw(out: Path, kap: study.KapitzaResult, map_rows: list, examples: dict, res_rows: list, peaks: list,
         plan: Plan) -> None:
    """The figures: Kapitza threshold, Acheson map and example runs, resonance curve."""
    lines = {"averaged a^2 omega^2 = 2 g l1": kap.theory_point_mass,
             "exact, continuous sinusoid (Mathieu)": kap.mathieu_exact,
             "exact, input held over each step": kap.held_exact, "simulated threshold": kap.bisection.threshold}
    amplitudes = np.linspace(*(f * kap.theory_point_mass for f in (0.97, 1.03)), 241)
    exponents = np.array([held_floquet_exponent(a, kap.setup.omega, kap.effective_length, kap.params.g,
                                                kap.setup.steps_per_period) for a in amplitudes])
    fig.plot_kapitza_threshold(kap.bisection.probes, (amplitudes, exponents), lines, kap.examples, kap.setup.theta0,
                               out / "kapitza_threshold.png")
    curve = np.linspace(min(plan.acheson.omegas) - 10.0, max(plan.acheson.omegas) + 10.0, 200)
    theory = study.theory_boundaries(curve)
    fig.plot_stability_map(map_rows, curve, {
        "theory, lower bound (slow mode, exact Mathieu)": theory["lower_m"],
        "theory, averaged a^2 omega^2 = 2 g L_slow (on the solid line)": theory["kapitza_m"],
        "theory, flutter bound (fast mode, exact Mathieu)": theory["upper_m"]}, out / "acheson_map.png")
    fig.plot_upright_runs({study.example_label(a, plan.acheson): r for a, r in examples.items()},
                          out / "acheson_examples.png")
    fig.plot_resonance_curve(res_rows, study.normal_modes(), peaks, plan.resonance.torque, out / "resonance_curve.png")


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Run the three studies through the FMU; write CSVs, figures, ``summary.json`` and ``report.md``."""
    plan = QUICK if quick else FULL
    out = Path(out_dir)
    # 1. Kapitza: bisection through fmpy in this process
    kap = study.kapitza_study(runner, plan.kapitza)
    # 2./3. Acheson map and resonance curve: through fmpy in worker processes
    map_cases, res_cases = study.acheson_cases(plan.acheson), study.resonance_cases(plan.resonance)
    outcomes = run_cases(map_cases + res_cases, str(runner.fmu_path), max_workers=plan.workers)
    map_rows = study.acheson_rows(outcomes[:len(map_cases)], plan.acheson.steps_per_period)
    res_rows = outcomes[len(map_cases):]
    bands, peaks = study.measured_bands(map_rows), study.resonance_peaks(res_rows, plan.resonance)
    examples = study.acheson_examples(runner, plan.acheson)
    slow_case = min(res_cases, key=lambda c: abs(c.omega - study.normal_modes()[0]))
    # files
    below, above = kap.examples.values()
    for name, result in (("kapitza_below_threshold", below), ("kapitza_above_threshold", above),
                         ("resonance_slow_mode", run_torque(slow_case, runner, TORQUE_OUTPUTS))):
        write_results_csv(out / f"{name}.csv", result, runner.units)
    for a, result in examples.items():
        write_results_csv(out / f"acheson_a{a * 1e3:g}mm.csv", result, runner.units)
    write_tables(out, kap, map_rows, bands, res_rows, peaks)
    draw(out, kap, map_rows, examples, res_rows, peaks, plan)
    summary = {"scenario": "base_excitation", "quick": quick, **rep.kapitza_summary(kap),
               **rep.acheson_summary(map_rows, bands), **rep.resonance_summary(res_rows, peaks)}
    write_json(out / "summary.json", summary)
    write_text(out / "report.md", rep.report(summary, peaks, quick))
    return summary
