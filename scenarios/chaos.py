"""Scenario ``chaos``: the seed's experiment 4.1 in silico, made quantitative.

The seed released its pendulum by hand from rest, the upper bob held against a threaded rod (position
known to about 5 mm), the lower rod hanging; three long-exposure traces agreed for a while, then parted.
The release angle is not stated: here the upper rod starts at 2.0 rad (the upper bob 12 cm above the
pivot, high enough for the chaotic traces of its figs. 4-6), the lower rod hanging, at rest.

Outputs in ``results/chaos/`` (CSVs, plots, ``summary.json`` with ``lyapunov_per_s`` and ``in_short``): FMU runs
of the nominal and three drawn releases; ensembles and predictability horizons; Lyapunov exponents (convergence,
two-trajectory check, step halving with ``--thorough``, spectrum, against the energy, with friction); the flip-time
map and Poincare sections. The analysis: :mod:`double_pendulum.analysis.chaos`; costs and sizes in its ``plan``.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis.chaos import flips, lyapunov_study, phase_space, predictability, releases
from double_pendulum.analysis.chaos.ensemble import initial_states, pendulum_field, rod_field
from double_pendulum.analysis.chaos.in_short import in_short
from double_pendulum.analysis.chaos.lyapunov import LyapunovResult, lyapunov_benettin, lyapunov_two_trajectory
from double_pendulum.analysis.chaos.plan import FULL, QUICK, THOROUGH, H, Plan, precision
from double_pendulum.analysis.sweep import default_workers, parallel_map, run_sweep, where_runs
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.model.parameters import AirDragParameters, BearingParameters, PendulumParameters
from double_pendulum.model.vector_field import ModelConfig
from double_pendulum.runs.progress import step
from double_pendulum.runs.results_io import write_json, write_results_csv

DESCRIPTION = "sensitivity to the start (seed 4.1): ensembles, predictability, Lyapunov exponents, flip map"

DEFAULT_START: dict[str, float] = {"phi1_0": 2.0, "phi2_0": 0.0, "omega1_0": 0.0, "omega2_0": 0.0}
PHI0 = (DEFAULT_START["phi1_0"], DEFAULT_START["phi2_0"])  # rad, released from rest
REGULAR_START: dict[str, float] = {"phi1_0": 0.5, "phi2_0": 0.5}
START_UNCERTAINTY = 0.005  # m, the seed's estimate for the upper bob's position
SEED = 41  # random draws of the releases (seed section 4.1)
FMU_SETTINGS = {"solver": "dop853", "rtol": 1e-10, "atol": 1e-12}
THRESHOLDS = (0.01, 0.10)  # m, spread of the lower bob that ends predictability
SNAPSHOTS = (0.0, 1.0, 2.0, 3.0, 5.0, 8.0)  # s, clouds of the 5 mm ensemble
RENORM = 0.5  # s, Benettin renormalisation interval


def fmu_runs(runner: FmuRunner, out: Path, plan: Plan, params: PendulumParameters) -> tuple[dict, float]:
    """Nominal release, three drawn within 5 mm and a regular start via the FMU; summary, FMU-batch difference."""
    releases = predictability.drawn_releases(DEFAULT_START, START_UNCERTAINTY, 3, params, seed=SEED)
    cases = [{**c, **FMU_SETTINGS} for c in [*releases.values(), REGULAR_START]]
    start = time.perf_counter()
    results = run_sweep(runner.fmu_path, cases, stop_time=plan.fmu_stop, output_interval=0.01, max_workers=plan.workers)
    wall = time.perf_counter() - start
    for label, result in zip(releases, results):
        write_results_csv(out / f"{label}.csv", result, runner.units)
    drawn = {f"{k.replace('_', ' ')} (phi1_0 = {releases[k]['phi1_0']:.4f} rad)": r
             for k, r in zip(list(releases)[1:], results[1:4])}
    t_part, where = predictability.lower_bob_parting(list(drawn.values()), THRESHOLDS[0])
    t_show = min(t_part + 3.0, plan.fmu_stop)
    plots.plot_lower_mass_traces(
        predictability.lower_bob_traces(drawn, t_show), out / "release_traces.png", diverge=where,
        title=f"three releases drawn with sigma = 5 mm, until {t_show:.1f} s; red arrow: where they part by 1 cm",
    )
    portraits = {"regular (phi1 = phi2 = 0.5 rad)": results[4], "chaotic (default start)": results[0]}
    plots.plot_phase_portraits(portraits, out / "phase_portraits.png")
    fmu_vs_batch = predictability.batch_angle_difference(results[0], *PHI0, params, t_check=2.0,
                                                         rtol=FMU_SETTINGS["rtol"], atol=FMU_SETTINGS["atol"])
    return {"releases": releases, "settings": FMU_SETTINGS, "stop_time_s": plan.fmu_stop,
            "releases_part_by_1cm_at_s": t_part, "wall_time_s": wall}, fmu_vs_batch


def ensemble_part(plan: Plan, params: PendulumParameters) -> predictability.Predictability:
    """The release ensembles of every uncertainty, integrated (RK4 step :data:`H`)."""
    return predictability.release_predictability(pendulum_field(params), params, *PHI0, plan.sigmas, plan.members,
                                                 plan.spread_t_end, thresholds=THRESHOLDS, h=H, seed=SEED,
                                                 snapshot_sigma=START_UNCERTAINTY, snapshot_times=SNAPSHOTS)


def ensembles(out: Path, plan: Plan, params: PendulumParameters, lyapunov: float,
              res: predictability.Predictability | None = None) -> dict:
    """Spread of release ensembles over time and the predictability horizon against the uncertainty."""
    res = ensemble_part(plan, params) if res is None else res
    write_results_csv(out / "ensemble_spread.csv", *predictability.spread_table(res))
    write_results_csv(out / "predictability.csv", *predictability.horizon_table(res))
    spreads = {f"sigma = {s * 1e3:g} mm": res.spread.spread[:, j] for j, s in enumerate(res.sigmas)}
    plots.plot_ensemble_spread(res.spread.times, spreads, THRESHOLDS, out / "ensemble_spread.png")
    plots.plot_ensemble_clouds(res.spread.snapshots, out / "ensemble_clouds.png", title=f"{plan.members} releases, "
                               f"upper bob's start uncertain by sigma = {START_UNCERTAINTY * 1e3:g} mm")
    horizons = {f"spread > {d * 100:g} cm": res.horizons[d] for d in THRESHOLDS}
    plots.plot_predictability(res.sigmas, horizons, lyapunov, out / "predictability.png")
    return predictability.predictability_summary(res, lyapunov)


def lyapunov_starts(plan: Plan, params: PendulumParameters) -> np.ndarray:
    """The default start and its ``lyap_members`` neighbours drawn within 5 mm."""
    return releases.release_ensemble(*PHI0, START_UNCERTAINTY, plan.lyap_members + 1, params, seed=SEED,
                                  include_nominal=True)


def benettin_part(plan: Plan, params: PendulumParameters, name: str) -> tuple[LyapunovResult, float]:
    """Largest exponent of the Lyapunov starts by the integration ``METHODS[name]``, and its wall time [s]."""
    start = time.perf_counter()
    res = lyapunov_benettin(pendulum_field(params), lyapunov_starts(plan, params), plan.lyap_t_end,
                                  renorm_interval=RENORM, integration=plan.methods()[name])
    return res, time.perf_counter() - start


def two_trajectory_part(plan: Plan, params: PendulumParameters) -> np.ndarray:
    """The two-trajectory estimate (RK4) of the Lyapunov starts: running estimates ``(n_t, N)``."""
    _, two = lyapunov_two_trajectory(pendulum_field(params), lyapunov_starts(plan, params), plan.lyap_t_end,
                                           renorm_interval=RENORM)
    return two


def lyapunov(out: Path, plan: Plan, params: PendulumParameters, parts: dict[str, Any] | None = None) -> dict:
    """Largest exponent of the default start and its neighbours within 5 mm (their DOP853 mean), three integrations.

    ``parts`` holds the integrations computed elsewhere (``benettin:NAME``, ``two_trajectory``); missing ones
    are computed here.
    """
    parts = dict(parts or {})
    methods = plan.methods()
    for name in methods:
        if f"benettin:{name}" not in parts:
            parts[f"benettin:{name}"] = benettin_part(plan, params, name)
    if "two_trajectory" not in parts:
        parts["two_trajectory"] = two_trajectory_part(plan, params)
    cmp = lyapunov_study.IntegrationComparison(
        methods, {n: parts[f"benettin:{n}"][0] for n in methods}, {n: parts[f"benettin:{n}"][1] for n in methods},
        parts["two_trajectory"], RENORM, plan.lyap_t_end,
    )
    write_results_csv(out / "lyapunov_convergence.csv", *lyapunov_study.convergence_table(cmp))
    curves = lyapunov_study.convergence_curves(cmp, "starts within 5 mm")
    plots.plot_lyapunov_convergence(curves, out / "lyapunov_convergence.png", title="default start")
    return lyapunov_study.largest_exponent_summary(cmp, "dop853", "starts within 5 mm")


def spectrum(out: Path, plan: Plan, params: PendulumParameters) -> dict:
    """All four exponents of the default start, their pairing and the bound on their sum."""
    spec = lyapunov_study.lyapunov_spectrum(pendulum_field(params), initial_states(*PHI0), plan.spectrum_t_end,
                                            params, renorm=RENORM, h=H)
    write_results_csv(out / "lyapunov_spectrum.csv", *lyapunov_study.spectrum_table(spec))
    plots.plot_lyapunov_spectrum(spec.times, spec.running, spec.sum_bound, out / "lyapunov_spectrum.png")
    return lyapunov_study.spectrum_summary(spec, plan.spectrum_t_end)


def energy_scan(out: Path, plan: Plan, params: PendulumParameters) -> dict:
    """Largest exponent against the release angle phi1 = phi2 = theta0 (from rest)."""
    scan = lyapunov_study.energy_scan(pendulum_field(params), plan.scan_thetas, params, plan.scan_t_end,
                                      renorm=RENORM, h=H)
    write_results_csv(out / "lyapunov_energy.csv", *lyapunov_study.energy_scan_table(scan))
    plots.plot_lyapunov_vs_energy(scan.theta0, scan.energy_ratio, scan.exponent, out / "lyapunov_energy.png")
    return lyapunov_study.energy_scan_summary(scan, plan.scan_t_end)


def with_friction(out: Path, plan: Plan, params: PendulumParameters) -> dict:
    """The largest exponent in time windows while the seed's air drag and bearing friction drain the energy."""
    field = rod_field(ModelConfig(params, AirDragParameters(air_drag=True), BearingParameters(bearing_friction=True)))
    win = lyapunov_study.exponent_with_friction(field, [*PHI0, 0.0, 0.0], plan.friction_t_end, params,
                                                renorm=RENORM, window=plan.friction_window, rtol=plan.friction_rtol)
    write_results_csv(out / "lyapunov_friction.csv", *lyapunov_study.friction_table(win))
    plots.plot_lyapunov_with_friction(
        win.centres, win.exponent, win.times, win.energy_ratio, out / "lyapunov_friction.png",
        title=f"default start, seed's air drag and bearing friction: exponent per {plan.friction_window:g} s",
    )
    return lyapunov_study.friction_summary(win, plan.friction_window, ["air_drag (bobs)", "bearing_friction"])


def flip_map(out: Path, plan: Plan, params: PendulumParameters) -> dict:
    """Time to the first flip on a grid of release angles; check the energetic bound on every start."""
    fmap = flips.flip_time_map(plan.flip_n, plan.flip_n, params, t_max=plan.flip_t_max, h=H, max_workers=plan.workers)
    write_results_csv(out / "flip_map.csv", *phase_space.flip_map_table(fmap))
    plots.plot_flip_map(fmap.phi1, fmap.phi2, fmap.time, fmap.energy, fmap.threshold, out / "flip_map.png",
                        t_max=fmap.t_max)
    return phase_space.flip_map_summary(fmap, params)


def poincare(out: Path, plan: Plan, params: PendulumParameters) -> dict:
    """Sections phi1 = 0, omega1 > 0 at a regular energy and at the default start's energy."""
    releases = {"regular, energy of a rest start at phi1 = phi2 = 0.5 rad": (0.5, 0.5),
                "chaotic, energy of the default start": PHI0}
    energies = [phase_space.rest_energy(*phi, params) for phi in releases.values()]
    sections = dict(zip(releases, phase_space.poincare_at_energies(
        pendulum_field(params), energies, plan.poincare_starts, params, t_end=plan.poincare_t_end, h=H)))
    plots.plot_poincare_sections(phase_space.section_points(sections), out / "poincare_sections.png")
    return {label: phase_space.section_summary(s, params) for label, s in sections.items()}


def fmu_part(fmu_path: str, units: dict[str, str], out: Path, plan: Plan, params: PendulumParameters) -> tuple:
    """:func:`fmu_runs` in a worker process (the FMU runs one after another there)."""
    return fmu_runs(SimpleNamespace(fmu_path=fmu_path, units=units), out, dataclasses.replace(plan, workers=1), params)


PART_COST = {"fmu": 10, "benettin:dop853": 31, "benettin:rk4_h": 18, "benettin:rk4_h_half": 45, "two_trajectory": 17,
             "spectrum": 9, "energy_scan": 9, "with_friction": 22, "ensembles": 10, "poincare": 8}
"""CPU seconds of each part in a default run, measured (to start the long ones first)."""


def run_part(part: tuple[str, tuple]) -> Any:
    """Worker: run one part ``(name, arguments)``: a module-level function of this scenario by name."""
    name, args = part
    function = {"fmu": fmu_part, "two_trajectory": two_trajectory_part, "ensembles": ensemble_part}.get(name)
    if name.startswith("benettin:"):
        return benettin_part(*args, name.split(":", 1)[1])
    return (function or globals()[name])(*args)


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False, thorough: bool = False) -> dict:
    """Run every part and write CSVs, plots and ``summary.json``."""
    plan = QUICK if quick else (THOROUGH if thorough else FULL)
    params, out = PendulumParameters(), Path(out_dir)
    start = time.perf_counter()
    parts: list[tuple[str, tuple]] = [
        ("fmu", (str(runner.fmu_path), dict(runner.units), out, plan, params)),
        *[(f"benettin:{name}", (plan, params)) for name in plan.methods()],
        ("two_trajectory", (plan, params)),
        ("spectrum", (out, plan, params)),
        ("energy_scan", (out, plan, params)),
        ("with_friction", (out, plan, params)),
        ("ensembles", (plan, params)),
        ("poincare", (out, plan, params)),
    ]
    parts.sort(key=lambda part: -PART_COST.get(part[0], 0))
    workers = default_workers() if plan.workers is None else plan.workers
    step(f"{len(parts)} parts (FMU runs, Lyapunov exponents by {len(plan.methods()) + 1} integrations, spectrum, "
         f"energy scan, with friction, ensembles, Poincare sections) {where_runs(len(parts), workers)}")
    values, _ = parallel_map(run_part, parts, max_workers=workers, label="chaos parts", unit="part")
    done = {name: value for (name, _), value in zip(parts, values)}
    fmu, fmu_vs_batch = done["fmu"]
    step("Lyapunov convergence and ensembles: tables and plots")
    lyap = {**lyapunov(out, plan, params, done), "spectrum": done["spectrum"],
            "energy_scan": done["energy_scan"], "with_friction": done["with_friction"]}
    summary: dict = {
        "scenario": "chaos", "quick": quick, "thorough": thorough, "default_start": DEFAULT_START,
        "start_uncertainty_m": START_UNCERTAINTY,
        "lyapunov_per_s": lyap["lyapunov_per_s"], "lyapunov": lyap, "fmu_runs": fmu,
        "fmu_vs_batch_dop853_max_angle_difference_rad_first_2s": fmu_vs_batch,
        "predictability": ensembles(out, plan, params, lyap["lyapunov_per_s"], done["ensembles"]),
    }
    step(f"flip map: {plan.flip_n} x {plan.flip_n} releases")
    summary["flip_map"] = flip_map(out, plan, params)
    summary["poincare"] = done["poincare"]
    summary["precision"], summary["in_short"] = precision(plan, summary), in_short(summary)
    summary["wall_time_s"] = time.perf_counter() - start
    write_json(out / "summary.json", summary)
    return summary
