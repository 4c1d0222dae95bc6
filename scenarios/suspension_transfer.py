r"""Scenario ``suspension_transfer``: can a damped suspension of the pivot explain the measured decay?

The seed measured the pendulum's energy falling as E = a exp(b t) with b = -0.024 1/s (the
project's own fit of Table 1, ``energy_decay``: b = -0.0252 1/s). Air drag on bobs and rods and
bearing friction at the seed's estimates (the parameter defaults) give only about a fifth of that.
This scenario asks how much a pivot on a damped suspension (mass M_s, springs k = k_x = k_y,
dampers c = c_x = c_y) adds, and which suspensions reproduce the measurement. Every run goes
through the FMU from the state measured after the hand release, with air drag and bearing friction
on; b is fitted to E_pendulum (the bobs, what the camera sees) on the measured frames.

Steps: identify c at the default k and M_s from the measured energy, with its valley in
(k, c, M_s) and the decay shape p of dE/dt = -k E^p
(:mod:`~double_pendulum.analysis.suspension.identification`); sweep b over (k, c) at a few M_s and
check the map against the linear response to the fixed-pivot force spectrum (the default run maps
M_s = 2 kg, the identified mass; ``--thorough`` adds coarser maps at 0.5 and 8 kg and the fits on the
first 7 and 14 s)
(:mod:`~double_pendulum.analysis.suspension.decay_map`, :mod:`~double_pendulum.analysis.suspension.response`);
run the identified suspension (and the resonant one on the same iso-b curve) again and follow the
energy into the suspension (:mod:`~double_pendulum.analysis.suspension.energy_flow`). Summary entries, tables
and figure inputs: :mod:`~double_pendulum.analysis.suspension.transfer`; the report:
:mod:`~double_pendulum.analysis.suspension.report`.

Outputs in ``results/suspension_transfer/``: ``decay_rate_map.csv`` (the sweep), ``frames.csv``
(measured and simulated energy per frame), ``identified.csv`` / ``resonant.csv`` (energy-flow runs),
``fixed_pivot_force.csv``; plots ``decay_rate_map.png``, ``decay_rate_cuts.png``,
``force_spectrum.png``, ``energy_flow.png``, ``energy_fit.png``; ``summary.json``; ``report.md``.

Cost: the identification is sequential (each Gauss-Newton step needs the last); the three maps
run in one parallel sweep; the refits along the valley, the window checks, the Fisher matrix and
the final runs, all independent once c is identified, run on parallel worker processes too.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from double_pendulum.scenarios.energy_decay import SEED_FIT

from double_pendulum import plots
from double_pendulum.analysis.decay.error_budget import error_budget
from double_pendulum.analysis.suspension import transfer as study
from double_pendulum.analysis.suspension.decay_map import (
    BASE_SETTINGS,
    MAP_SETTINGS,
    MAP_UNITS,
    decay_maps,
    map_summary,
    trace_valley,
)
from double_pendulum.analysis.suspension.energy_flow import energy_flow_run, energy_flow_summary
from double_pendulum.analysis.suspension.identification import (
    FIT_SETTINGS,
    LOSSES,
    identify_suspension,
    measured_decay,
    pendulum_values,
    point_summary,
    simulate_frames_from,
    suspension_values,
    valley_fisher,
    window_check,
)
from double_pendulum.analysis.suspension.plan import FULL, NULL_MEANS, QUICK, THOROUGH
from double_pendulum.analysis.suspension.report import report_text
from double_pendulum.analysis.sweep import runner_map
from double_pendulum.analysis.track.measurement import load_track, reconstruct
from double_pendulum.analysis.track.tilt import seed_record_geometry
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.runs.progress import step
from double_pendulum.runs.results_io import write_json, write_results_csv, write_text

DESCRIPTION = "decay rate b over suspension stiffness and damping; suspension identified from the measured decay"

SEED_B = SEED_FIT["b_per_s"]
"""The seed's measured decay rate [1/s]."""


def checks(runner: FmuRunner, task: tuple[str, Any, dict[str, Any]]) -> Any:
    """Worker: one of the independent runs after the identification (``kind``, argument, shared context)."""
    kind, arg, ctx = task
    md, base, ident = ctx["md"], ctx["base"], ctx["ident"]
    if kind == "trace":
        return trace_valley(runner, md, base, ident, ctx["map"], (arg,))[0]
    if kind == "window":
        return window_check(runner, ctx["rec"], base, ident, arg)
    if kind == "fisher":
        return valley_fisher(runner, md, base, ident)
    if kind == "frames":
        return simulate_frames_from(runner, arg, md.frames)
    if kind == "flow":
        return energy_flow_run(runner, arg, md.frames)
    raise ValueError(f"unknown task {kind!r}")


TASK_COST = {"trace": 12.0, "window": 6.0, "fisher": 3.0, "frames": 1.5, "flow": 2.0}
"""Rough CPU seconds per task (to start the long ones first)."""


CONDITIONAL_ON = {
    "k": "assumed (the parameter default), not measured",
    "M_s": "assumed (the parameter default), not measured",
    "losses": "the default air drag, rod drag and rolling friction (settings.losses), not fitted",
    "model": "this suspension model at these k and M_s: refitted it reproduces neither b nor the loss exponent p "
             "(refit), so at these k and M_s the data do not support it; another k, M_s or suspension law, or "
             "another part of the record, could change that (not fitted here)",
    "valley": "equally good fits lie along valley.linearised: c is not an identified property of the stand",
}
"""What the identified c is conditional on (``summary["identified"]["conditional_on"]``)."""
VALLEY_K_FACTORS = (0.8, 0.9, 1.0, 1.1, 1.25)
"""k over the identified k at which :func:`valley_points` states c along the linearised valley."""


def valley_points(k: float, c: float, slope: float) -> list[dict[str, float]]:
    """c [N s/m] along the linearised valley through (``k`` [N/m], ``c``): ln c = ln c0 + ``slope`` ln(k/k0),
    at :data:`VALLEY_K_FACTORS` times k (the Fisher matrix's valley, not refitted: equally good fits)."""
    return [{"k_N_per_m": f * k, "c_N_s_per_m": c * f**slope} for f in VALLEY_K_FACTORS]


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False, thorough: bool = False) -> dict:
    """Identify, sweep, check, write CSVs, plots, summary and report (see the module docstring);
    ``thorough``: the maps at the other suspension masses too (:data:`THOROUGH`)."""
    wall0 = time.perf_counter()
    out_dir = Path(out_dir)
    plan = QUICK if quick else THOROUGH if thorough else FULL

    # identification of c at the default k, M_s; the map b(k, c); c refitted along its valley
    step("fitting the release state and the damping c to the measured energy (sequential FMU runs)")
    rec = reconstruct(load_track(), seed_record_geometry().geometry)
    model = identify_suspension(runner, rec, quick=quick, m_s=plan.m_s_main)
    md, ident, spectrum = model.measured, model.identification, model.spectrum
    base = {**pendulum_values(rec), **LOSSES, **model.start.start_values()}
    step(f"decay-rate maps over (k, c) at M_s = {', '.join(f'{m:g}' for m in (plan.m_s_main, *plan.m_s_extra))} kg")
    t_map = time.perf_counter()
    maps = decay_maps(
        runner.fmu_path, base, md.frames, spectrum, plan.k_grid, plan.c_grid, plan.m_s_main,
        m_s_extra=plan.m_s_extra, extra_stride=plan.extra_stride, max_workers=plan.max_workers,
    )
    map_wall = time.perf_counter() - t_map

    # independent now: refits along the valley, window checks, Fisher matrix, runs on the measured frames
    resonant = study.resonant_point(maps[0], md.b) if plan.resonant_end else None
    ctx = {"md": md, "base": base, "ident": ident, "map": maps[0], "rec": rec}
    tasks: list[tuple[str, Any, dict[str, Any]]] = [("trace", f, ctx) for f in plan.valley_k_factors]
    tasks += [("window", w, ctx) for w in plan.window_checks_s]
    tasks += [("fisher", None, ctx), ("frames", model.values, ctx), ("frames", base, ctx), ("flow", model.values, ctx)]
    if resonant is not None:
        values = {**base, **suspension_values(resonant[0], resonant[1], plan.m_s_main)}
        tasks += [("frames", values, ctx), ("flow", values, ctx)]
    extra = [f"{n} {what}" for n, what in ((len(plan.valley_k_factors), "refits along the valley"),
                                           (len(plan.window_checks_s), "window checks")) if n]  # fmt: skip
    step(", ".join([*extra, "the Fisher matrix and the energy-flow runs"]))
    done = runner_map(checks, tasks, runner, max_workers=plan.max_workers, costs=[TASK_COST[t[0]] for t in tasks],
                      label="suspension checks", unit="task")
    n_trace, n_window = len(plan.valley_k_factors), len(plan.window_checks_s)
    trace = done[:n_trace]
    windows = done[n_trace:n_trace + n_window]
    fisher, ident_run, base_run, ident_flow, *resonant_runs = done[n_trace + n_window:]

    # runs on the measured frames: identified, no suspension, the resonant end of the iso-b curve
    runs = {"identified": ident_run, "no suspension": base_run}
    flows = {"identified": ident_flow}
    points = {f"c fitted at the assumed k = {ident.k:g} N/m (conditional, not identified)": (ident.k, ident.c)}
    points.update({f"c refitted at k = {f.k:.3g} N/m": (f.k, f.c) for f in trace})
    if resonant is not None:
        runs["resonant"], flows["resonant"] = resonant_runs
        points["resonant end of the curve"] = resonant
    step("summary, tables, plots and the report")
    # energy_decay's total error of the whole record's b (the quick run fits only its first seconds: the same error)
    total_b_err = error_budget(rec, measured_decay(rec).frames.sigma)["total_b_per_s"]

    summary: dict[str, Any] = {
        "scenario": "suspension_transfer",
        "quick": quick,
        "thorough": thorough,
        "energy_fitted": "E_pendulum (the bobs' energy, what the camera measures)",
        "settings": {"map": MAP_SETTINGS, "map_without_suspension": BASE_SETTINGS, "fits": FIT_SETTINGS,
                     "losses": LOSSES},
        "measured": study.measured_summary(md, SEED_B, total_b_err),
        "start_state": model.start.as_dict(),
        "identified": {**point_summary(md, ident, ident.chi2), "fixed": {"k": ident.k, "M_s": ident.m_s},
                       "conditional_on": CONDITIONAL_ON},
        "refit": {label: study.run_summary(md, r, ident.chi2, total_b_err) for label, r in runs.items()},
        "valley": {
            "fisher": fisher,
            "trace": [point_summary(md, f, ident.chi2) for f in trace],
            "resonant_end": None if resonant is None else study.resonant_summary(resonant, plan.m_s_main, spectrum),
            "linearised": valley_points(ident.k, ident.c, fisher["valley_slope_dlnc_dlnk"]),
        },
        "window_checks": windows,
        "spectrum": study.spectrum_summary(spectrum, ident),
        "maps": [map_summary(d, spectrum, md, SEED_B) for d in maps],
        "energy_flow": {label: energy_flow_summary(f) for label, f in flows.items()},
        "map_runs": int(sum(d.b.size for d in maps) + 1),  # one run without suspension serves every map
        "map_wall_time_s": map_wall,
        "null_means": NULL_MEANS,
    }

    write_results_csv(out_dir / "decay_rate_map.csv", study.map_table(maps, spectrum.m12), MAP_UNITS)
    write_results_csv(out_dir / "frames.csv", study.frames_table(md, runs, ident.residuals), study.FRAME_UNITS)
    for label, flow in flows.items():
        write_results_csv(out_dir / f"{label}.csv", flow, runner.units)
    write_results_csv(out_dir / "fixed_pivot_force.csv", spectrum.result, runner.units)

    main = maps[0]
    levels = {"measured (this project)": md.b, "seed": SEED_B}
    panels = study.map_panels(maps, spectrum, 24 if quick else 60)
    map_path = out_dir / "decay_rate_map.png"
    plots.plot_decay_rate_map(panels, levels, map_path, points=points, slope_through=(ident.k, ident.c))
    c_fine, lr, qs = study.predicted_cuts(main, spectrum)
    cuts_path = out_dir / "decay_rate_cuts.png"
    plots.plot_decay_rate_cuts(main.k, main.c, main.b_suspension, c_fine, lr, qs, md.b - main.b_base, cuts_path)
    omega, force_spectra = study.shown_force_spectra(spectrum)
    marks = study.natural_frequency_marks(spectrum, ident)
    plots.plot_force_spectrum(omega, force_spectra, marks, out_dir / "force_spectrum.png")
    plots.plot_energy_flow(flows, out_dir / "energy_flow.png")
    energy_fit = study.energy_fit_inputs(md, runs)
    plots.plot_energy_decay(**energy_fit, path=out_dir / "energy_fit.png", residual_curve="FMU, identified")

    summary["wall_time_s"] = time.perf_counter() - wall0
    write_json(out_dir / "summary.json", summary)
    write_text(out_dir / "report.md", report_text(summary))
    return summary
