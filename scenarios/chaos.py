"""Scenario ``chaos``: the seed's experiment 4.1 in silico, made quantitative.

The seed released its pendulum by hand from rest with the upper bob held against a threaded
rod (position known to about 5 mm) and the lower rod hanging; three long-exposure traces agreed
for a while and then parted completely. The report does not state the release angle: the default
start here is the upper rod at 2.0 rad (115 degrees, the upper bob 12 cm above the pivot, high
enough for the chaotic traces of its figs. 4-6) with the lower rod hanging (phi2 = 0), at rest.

Outputs in ``results/chaos/``:

* three releases drawn with the 5 mm uncertainty and the nominal one, through the FMU (run in
  parallel by :mod:`double_pendulum.analysis.sweep`): CSVs, the lower bob's traces with the point where
  they part, phase portraits at a regular and the chaotic energy;
* ensembles (:mod:`double_pendulum.analysis.ensemble`): the spread of the lower bob over time for start
  uncertainties from 0.01 to 10 mm, clouds of the 5 mm ensemble, the predictability horizon
  (spread above 1 cm and 10 cm) against the uncertainty;
* Lyapunov exponents (:mod:`double_pendulum.analysis.chaos`): the largest exponent of the default start
  with its convergence for DOP853 (rtol 1e-10, the high-accuracy estimate) and RK4 at h and h/2,
  the two-trajectory cross-check, the full spectrum (pairing lambda, 0, 0, -lambda), the exponent
  against the release angle phi1 = phi2 = theta0 from 0.5 to 3 rad;
* the flip-time map (200 x 200 release angles, 10 s) with the energetically impossible region;
* Poincare sections phi1 = 0 at a regular and the chaotic energy;
* ``summary.json`` with ``lyapunov_per_s`` for the default start.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis import chaos
from double_pendulum.analysis.ensemble import (
    batch_energy,
    batch_potential_energy,
    dop853_trajectory,
    initial_states,
    model_field,
    pendulum_field,
)
from double_pendulum.analysis.sweep import run_sweep
from double_pendulum.fmu.runner import FmuRunner
from double_pendulum.model.parameters import AirDragParameters, BearingParameters, PendulumParameters
from double_pendulum.model.vector_field import ModelConfig
from double_pendulum.results_io import write_json, write_results_csv

DESCRIPTION = "sensitivity to the start (seed 4.1): ensembles, predictability, Lyapunov exponents, flip map"

DEFAULT_START: dict[str, float] = {"phi1_0": 2.0, "phi2_0": 0.0, "omega1_0": 0.0, "omega2_0": 0.0}
START_UNCERTAINTY = 0.005  # m, the seed's estimate for the upper bob's position
SEED = 41  # random draws of the releases (seed section 4.1)
FMU_SETTINGS = {"solver": "dop853", "rtol": 1e-10, "atol": 1e-12}
THRESHOLDS = (0.01, 0.10)  # m, spread of the lower bob that ends predictability
RENORM = 0.5  # s, Benettin renormalisation interval
H = 1e-3  # s, RK4 step of the ensembles, maps and sections


@dataclass(frozen=True)
class Plan:
    """Sizes of the runs (full or quick)."""

    workers: int | None  # local processes for FMU sweeps and the flip map (None: all cores)
    fmu_stop: float
    sigmas: tuple[float, ...]
    members: int
    spread_t_end: float
    lyap_t_end: float
    lyap_members: int
    scan_thetas: tuple[float, ...]
    scan_t_end: float
    spectrum_t_end: float
    flip_n: int
    flip_t_max: float
    poincare_starts: int
    poincare_t_end: float
    friction_t_end: float
    friction_window: float


FULL = Plan(
    workers=None,
    fmu_stop=30.0,
    sigmas=(1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 5e-3, 1e-2),
    members=200,
    spread_t_end=15.0,
    lyap_t_end=100.0,
    lyap_members=63,
    scan_thetas=tuple(np.round(np.arange(0.5, 3.0001, 0.1), 2)),
    scan_t_end=100.0,
    spectrum_t_end=100.0,
    flip_n=200,
    flip_t_max=10.0,
    poincare_starts=12,
    poincare_t_end=100.0,
    friction_t_end=360.0,
    friction_window=20.0,
)
QUICK = Plan(
    workers=1,
    fmu_stop=4.0,
    sigmas=(1e-4, 1e-3, 5e-3),
    members=40,
    spread_t_end=3.0,
    lyap_t_end=2.0,
    lyap_members=7,
    scan_thetas=(0.5, 1.0, 1.5, 2.0, 2.5, 3.0),
    scan_t_end=2.0,
    spectrum_t_end=2.0,
    flip_n=24,
    flip_t_max=2.0,
    poincare_starts=4,
    poincare_t_end=3.0,
    friction_t_end=2.0,
    friction_window=1.0,
)


def _table(**columns: np.ndarray) -> np.ndarray:
    """Columns of equal length as a structured array (for :func:`write_results_csv`)."""
    arrays = [np.asarray(v, dtype=float).ravel() for v in columns.values()]
    return np.rec.fromarrays(arrays, names=list(columns)).view(np.ndarray)


def _mm(sigma: float) -> str:
    return f"{sigma * 1e3:g} mm"


# ---------------------------------------------------------------------------- FMU runs
def _releases(plan: Plan, params: PendulumParameters) -> dict[str, dict[str, float]]:
    """The nominal release and three drawn with the seed's 5 mm uncertainty (start values by name)."""
    starts = chaos.release_ensemble(
        DEFAULT_START["phi1_0"], DEFAULT_START["phi2_0"], START_UNCERTAINTY, 3, params, seed=SEED
    )
    out = {"nominal": dict(DEFAULT_START)}
    for k in range(3):
        out[f"release_{k + 1}"] = {**DEFAULT_START, "phi1_0": float(starts[0, k])}
    return out


def _parting(results: list[np.ndarray], threshold: float) -> tuple[float, tuple[float, float]]:
    """First time [s] the lower bobs of the runs are more than ``threshold`` [m] apart, and where."""
    x = np.array([r["x2"] for r in results])
    y = np.array([r["y2"] for r in results])
    dist = np.max(np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :]), axis=(0, 1))
    i = int(np.argmax(dist > threshold)) if np.any(dist > threshold) else len(dist) - 1
    return float(results[0]["time"][i]), (float(x[:, i].mean()), float(y[:, i].mean()))


def fmu_runs(runner: FmuRunner, out_dir: Path, plan: Plan, params: PendulumParameters) -> dict:
    """Releases and a regular start through the FMU, run in parallel; CSVs, traces, phase portraits."""
    releases = _releases(plan, params)
    regular = {"phi1_0": 0.5, "phi2_0": 0.5}
    cases = [{**c, **FMU_SETTINGS} for c in [*releases.values(), regular]]
    start = time.perf_counter()
    results = run_sweep(runner.fmu_path, cases, stop_time=plan.fmu_stop, output_interval=0.01, max_workers=plan.workers)
    wall = time.perf_counter() - start
    for label, result in zip(releases, results):
        write_results_csv(out_dir / f"{label}.csv", result, runner.units)
    drawn = results[1:4]
    t_part, where = _parting(drawn, THRESHOLDS[0])
    t_show = min(t_part + 3.0, plan.fmu_stop)
    window = drawn[0]["time"] <= t_show
    traces = {
        f"{label} (phi1_0 = {releases[label]['phi1_0']:.4f} rad)": (r["x2"][window], r["y2"][window])
        for label, r in zip(list(releases)[1:], drawn)
    }
    plots.plot_lower_mass_traces(
        traces,
        out_dir / "release_traces.png",
        diverge=where,
        title=f"three releases drawn with sigma = 5 mm: traces until {t_show:.1f} s; arrow: 1 cm apart",
    )
    portraits = {"regular (phi1 = phi2 = 0.5 rad)": results[4], "chaotic (default start)": results[0]}
    plots.plot_phase_portraits(portraits, out_dir / "phase_portraits.png")
    return {
        "releases": releases,
        "settings": FMU_SETTINGS,
        "stop_time_s": plan.fmu_stop,
        "releases_part_by_1cm_at_s": t_part,
        "wall_time_s": wall,
        "nominal": results[0],
    }


def fmu_vs_batch(nominal: np.ndarray, params: PendulumParameters, t_check: float = 2.0) -> float:
    """Largest angle difference [rad] up to ``t_check`` between the FMU and the batch DOP853 run."""
    keep = nominal["time"] <= t_check + 1e-12
    times = nominal["time"][keep][1:]
    y0 = initial_states(DEFAULT_START["phi1_0"], DEFAULT_START["phi2_0"])
    batch = dop853_trajectory(pendulum_field(params), y0, times, rtol=FMU_SETTINGS["rtol"], atol=FMU_SETTINGS["atol"])
    return float(
        max(
            np.max(np.abs(batch.y[:, 0, 0] - nominal["phi1"][keep][1:])),
            np.max(np.abs(batch.y[:, 1, 0] - nominal["phi2"][keep][1:])),
        )
    )


# ---------------------------------------------------------------------------- ensembles
def ensembles(out_dir: Path, plan: Plan, params: PendulumParameters, lyapunov: float) -> dict:
    """Spread of release ensembles over time and the predictability horizon against the uncertainty."""
    groups = [
        chaos.release_ensemble(DEFAULT_START["phi1_0"], DEFAULT_START["phi2_0"], s, plan.members, params, seed=SEED + i)
        for i, s in enumerate(plan.sigmas)
    ]
    seed_group = plan.sigmas.index(START_UNCERTAINTY)
    snapshots = [t for t in (0.0, 1.0, 2.0, 3.0, 5.0, 8.0) if t <= plan.spread_t_end]
    start = time.perf_counter()
    spread = chaos.ensemble_spread(
        pendulum_field(params),
        groups,
        params,
        plan.spread_t_end,
        h=H,
        snapshot_times=snapshots,
        snapshot_group=seed_group,
    )
    wall = time.perf_counter() - start
    sigmas = np.array(plan.sigmas)
    horizons = {d: chaos.predictability_horizon(spread.times, spread.spread, d) for d in THRESHOLDS}
    labels = [f"spread_sigma_{s * 1e3:g}mm" for s in sigmas]
    write_results_csv(
        out_dir / "ensemble_spread.csv",
        _table(time=spread.times, **{k: spread.spread[:, j] for j, k in enumerate(labels)}),
        {k: "m" for k in labels},
    )
    write_results_csv(
        out_dir / "predictability.csv",
        _table(sigma=sigmas, horizon_1cm=horizons[0.01], horizon_10cm=horizons[0.10]),
        {"sigma": "m", "horizon_1cm": "s", "horizon_10cm": "s"},
    )
    plots.plot_ensemble_spread(
        spread.times,
        {f"sigma = {_mm(s)}": spread.spread[:, j] for j, s in enumerate(sigmas)},
        THRESHOLDS,
        out_dir / "ensemble_spread.png",
    )
    plots.plot_ensemble_clouds(
        spread.snapshots,
        out_dir / "ensemble_clouds.png",
        title=f"{plan.members} releases, upper bob uncertain by sigma = {_mm(START_UNCERTAINTY)}: lower bob",
    )
    plots.plot_predictability(
        sigmas,
        {f"spread > {d * 100:g} cm": horizons[d] for d in THRESHOLDS},
        lyapunov,
        out_dir / "predictability.png",
    )
    slopes = {}
    for d in THRESHOLDS:
        ok = np.isfinite(horizons[d])
        if np.count_nonzero(ok) >= 2:
            slopes[f"{d * 100:g}cm"] = float(-np.polyfit(np.log(sigmas[ok]), horizons[d][ok], 1)[0])
    return {
        "members_per_ensemble": plan.members,
        "sigmas_m": sigmas,
        "horizon_1cm_s": horizons[0.01],
        "horizon_10cm_s": horizons[0.10],
        "horizon_1cm_at_5mm_s": float(horizons[0.01][seed_group]),
        "horizon_10cm_at_5mm_s": float(horizons[0.10][seed_group]),
        "horizon_slope_per_ln_sigma_s": slopes,
        "one_over_lyapunov_s": 1.0 / lyapunov if lyapunov > 0 else None,
        "wall_time_s": wall,
    }


# ---------------------------------------------------------------------------- Lyapunov exponents
def _checkpoints(times: np.ndarray, running: np.ndarray) -> dict[str, float]:
    return {f"{t:g}": float(running[np.argmin(np.abs(times - t))]) for t in (5, 10, 20, 50, 100, 200) if t <= times[-1]}


def lyapunov(out_dir: Path, plan: Plan, params: PendulumParameters) -> dict:
    """Largest exponent of the default start (three integrations), cross-check, spectrum, energy scan.

    A single trajectory's finite-time estimate still scatters by 10-20 % after 100 s; the start and
    its neighbours within the 5 mm uncertainty lie in the same chaotic sea, where the exponent is
    one number, so ``lyapunov_per_s`` is their mean (DOP853), with its standard error.
    """
    field = pendulum_field(params)
    starts = chaos.release_ensemble(
        DEFAULT_START["phi1_0"],
        DEFAULT_START["phi2_0"],
        START_UNCERTAINTY,
        plan.lyap_members + 1,
        params,
        seed=SEED,
        include_nominal=True,
    )
    methods = {
        "dop853": chaos.Integration("dop853", rtol=1e-10, atol=1e-12),
        "rk4_h": chaos.Integration("rk4", h=H),
        "rk4_h_half": chaos.Integration("rk4", h=H / 2),
    }
    runs, walls = {}, {}
    for name, integration in methods.items():
        start = time.perf_counter()
        runs[name] = chaos.lyapunov_benettin(
            field, starts, plan.lyap_t_end, renorm_interval=RENORM, integration=integration
        )
        walls[name] = time.perf_counter() - start
    times = runs["dop853"].times
    nominal = {name: r.running[:, 0, 0] for name, r in runs.items()}
    cloud = {name: r.exponents[0] for name, r in runs.items()}
    cloud_running = {name: r.running[:, 0, :].mean(axis=1) for name, r in runs.items()}
    best = float(cloud["dop853"].mean())
    _, two = chaos.lyapunov_two_trajectory(field, starts, plan.lyap_t_end, renorm_interval=RENORM)
    columns = {f"lambda_{n}_nominal": v for n, v in nominal.items()}
    columns.update({f"lambda_{n}_cloud_mean": v for n, v in cloud_running.items()})
    units = {k: "1/s" for k in columns}
    write_results_csv(out_dir / "lyapunov_convergence.csv", _table(time=times, **columns), units)
    curves = {f"{methods[n].label()}, default start": (times, v) for n, v in nominal.items()}
    curves.update(
        {
            f"{methods[n].label()}, mean of {starts.shape[1]} starts within 5 mm": (times, v)
            for n, v in cloud_running.items()
        }
    )
    plots.plot_lyapunov_convergence(
        curves, out_dir / "lyapunov_convergence.png", title="largest exponent, default start"
    )
    n = starts.shape[1]
    summary = {
        "lyapunov_per_s": best,
        "lyapunov_sem_per_s": float(cloud["dop853"].std(ddof=1) / math.sqrt(starts.shape[1])),
        "method": (
            f"Benettin, complex-step tangent, renormalised every {RENORM} s, {methods['dop853'].label()}, "
            f"{plan.lyap_t_end:g} s, mean over the default start and {plan.lyap_members} starts within 5 mm"
        ),
        "default_start_alone_per_s": float(nominal["dop853"][-1]),
        "convergence_default_start": {n_: _checkpoints(times, v) for n_, v in nominal.items()},
        "convergence_cloud_mean": {n_: _checkpoints(times, v) for n_, v in cloud_running.items()},
        "step_halving": {
            methods[name].label(): {
                "default_start": float(nominal[name][-1]),
                "cloud_mean": float(cloud[name].mean()),
                "cloud_sem": float(cloud[name].std(ddof=1) / math.sqrt(n)),
                "relative_to_dop853_cloud_mean": float(cloud[name].mean() / cloud["dop853"].mean() - 1.0),
                "wall_time_s": walls[name],
            }
            for name in methods
        },
        "cloud_members": n,
        "two_trajectory_rk4_default_start": float(two[-1, 0]),
        "two_trajectory_rk4_cloud_mean": float(two[-1].mean()),
    }
    summary["spectrum"] = spectrum(out_dir, plan, params, field)
    summary["energy_scan"] = energy_scan(out_dir, plan, params, field)
    summary["with_friction"] = with_friction(out_dir, plan, params)
    return summary


def spectrum(out_dir: Path, plan: Plan, params: PendulumParameters, field) -> dict:
    """All four exponents of the default start (QR), their pairing and the bound on their sum."""
    y0 = initial_states(DEFAULT_START["phi1_0"], DEFAULT_START["phi2_0"])
    res = chaos.lyapunov_benettin(
        field,
        y0,
        plan.spectrum_t_end,
        renorm_interval=RENORM,
        n_vectors=4,
        integration=chaos.Integration("rk4", h=H),
    )
    run = res.running[:, :, 0]
    bound = chaos.spectrum_sum_bound(params, res.times)
    write_results_csv(
        out_dir / "lyapunov_spectrum.csv",
        _table(
            time=res.times,
            **{f"lambda{i + 1}": run[:, i] for i in range(4)},
            sum=run.sum(axis=1),
            sum_bound=bound,
        ),
        {**{f"lambda{i + 1}": "1/s" for i in range(4)}, "sum": "1/s", "sum_bound": "1/s"},
    )
    plots.plot_lyapunov_spectrum(res.times, run, bound, out_dir / "lyapunov_spectrum.png")
    lam = run[-1]
    return {
        "exponents_per_s": lam,
        "lambda1_plus_lambda4_per_s": float(lam[0] + lam[3]),
        "sum_per_s": float(lam.sum()),
        "sum_bound_per_s": float(bound[-1]),
        "t_end_s": plan.spectrum_t_end,
        "method": "QR (Gram-Schmidt) of 4 complex-step tangent vectors, rk4 h = 1 ms",
    }


def energy_scan(out_dir: Path, plan: Plan, params: PendulumParameters, field) -> dict:
    """Largest exponent against the release angle phi1 = phi2 = theta0 (from rest)."""
    theta = np.array(plan.scan_thetas)
    y0 = initial_states(theta, theta)
    start = time.perf_counter()
    res = chaos.lyapunov_benettin(
        field, y0, plan.scan_t_end, renorm_interval=RENORM, integration=chaos.Integration("rk4", h=H)
    )
    wall = time.perf_counter() - start
    energy = batch_energy(y0, params)
    ratio = energy / chaos.flip_energy_threshold(params)
    lam = res.exponents[0]
    write_results_csv(
        out_dir / "lyapunov_energy.csv",
        _table(theta0=theta, E_0=energy, E_over_E_flip=ratio, lambda_max=lam),
        {"theta0": "rad", "E_0": "J", "lambda_max": "1/s"},
    )
    plots.plot_lyapunov_vs_energy(theta, ratio, lam, out_dir / "lyapunov_energy.png")
    return {
        "theta0_rad": theta,
        "lambda_per_s": lam,
        "E_over_E_flip": ratio,
        "t_end_s": plan.scan_t_end,
        "wall_time_s": wall,
    }


def with_friction(out_dir: Path, plan: Plan, params: PendulumParameters) -> dict:
    """The largest exponent in time windows while the seed's air drag and bearing friction drain the energy.

    The model with friction (:mod:`double_pendulum.model.vector_field`, the seed's drag and bearing numbers) runs
    column by column (:func:`double_pendulum.analysis.ensemble.model_field`); its tangent uses central
    differences (the friction terms are evaluated with ``math``), DOP853 rtol 1e-8.
    """
    config = ModelConfig(
        pendulum=params,
        air=AirDragParameters(air_drag=True),
        bearing=BearingParameters(bearing_friction=True),
    )
    y0 = initial_states(DEFAULT_START["phi1_0"], DEFAULT_START["phi2_0"])
    start = time.perf_counter()
    res = chaos.lyapunov_benettin(
        model_field(config),
        y0,
        plan.friction_t_end,
        renorm_interval=RENORM,
        integration=chaos.Integration("dop853", rtol=1e-8, atol=1e-10),
        jvp="central",
    )
    wall = time.perf_counter() - start
    centres, local = chaos.local_exponents(res, plan.friction_window)
    ratio = batch_energy(res.states[:, :, 0].T, params) / chaos.flip_energy_threshold(params)
    at_centres = np.interp(centres, res.times, ratio)
    write_results_csv(
        out_dir / "lyapunov_friction.csv",
        _table(time=centres, lambda_window=local[:, 0], E_over_E_flip=at_centres),
        {"lambda_window": "1/s"},
    )
    plots.plot_lyapunov_with_friction(
        centres,
        local[:, 0],
        res.times,
        ratio,
        out_dir / "lyapunov_friction.png",
        title=f"default start, seed's air drag and bearing friction: exponent per {plan.friction_window:g} s",
    )
    return {
        "mechanisms": ["air_drag (bobs)", "bearing_friction"],
        "window_s": plan.friction_window,
        "window_centres_s": centres,
        "lambda_per_window_per_s": local[:, 0],
        "E_over_E_flip_at_centres": at_centres,
        "wall_time_s": wall,
    }


# ---------------------------------------------------------------------------- flip map
def flip_map(out_dir: Path, plan: Plan, params: PendulumParameters) -> dict:
    """Time to the first flip on a grid of release angles; check the energetic bound on every start."""
    fmap = chaos.flip_time_map(plan.flip_n, plan.flip_n, params, t_max=plan.flip_t_max, h=H, max_workers=plan.workers)
    g1, g2 = np.meshgrid(fmap.phi1, fmap.phi2)
    write_results_csv(
        out_dir / "flip_map.csv",
        _table(phi1_0=g1, phi2_0=g2, E_0=fmap.energy, flip_time=fmap.time, flipped_rod=fmap.rod),
        {"phi1_0": "rad", "phi2_0": "rad", "E_0": "J", "flip_time": "s"},
    )
    plots.plot_flip_map(
        fmap.phi1,
        fmap.phi2,
        fmap.time,
        fmap.energy,
        fmap.threshold,
        out_dir / "flip_map.png",
        t_max=fmap.t_max,
    )
    bound1, bound2 = chaos.flip_energy_bounds(params)
    return {
        "grid": [plan.flip_n, plan.flip_n],
        "t_max_s": plan.flip_t_max,
        "rk4_step_s": H,
        "wall_time_s": fmap.wall_time,
        "workers": fmap.workers,
        "fraction_flipped": float(np.mean(fmap.rod > 0)),
        "energy_bound": (
            "a rod can flip only if E >= V at its upright position; V is smallest there with the other "
            "rod hanging: rod 1 needs E >= V(pi, 0) = 2 (m1+m2) g l1, rod 2 E >= V(0, pi) = 2 m2 g l2"
        ),
        "E_flip_rod1_J": bound1,
        "E_flip_rod2_J": bound2,
        "starts_below_bound": int(np.count_nonzero(fmap.energy < fmap.threshold)),
        "bound_violations": int(
            np.count_nonzero(((fmap.rod == 1) & (fmap.energy < bound1)) | ((fmap.rod == 2) & (fmap.energy < bound2)))
        ),
    }


# ---------------------------------------------------------------------------- Poincare sections
def poincare(out_dir: Path, plan: Plan, params: PendulumParameters) -> dict:
    """Sections phi1 = 0, omega1 > 0 at a regular energy and at the default start's energy."""
    field = pendulum_field(params)
    energies = {
        "regular: E of phi1 = phi2 = 0.5 rad": float(batch_energy(initial_states(0.5, 0.5), params)[0]),
        "chaotic: E of the default start": float(
            batch_energy(initial_states(DEFAULT_START["phi1_0"], DEFAULT_START["phi2_0"]), params)[0]
        ),
    }
    sections, out = {}, {}
    for label, energy in energies.items():
        phi2 = np.linspace(-1.0, 1.0, plan.poincare_starts) * _phi2_reach(energy, params)
        starts = chaos.section_starts(energy, phi2, 0.0, params)
        pts, owner = chaos.poincare_section(field, starts, plan.poincare_t_end, h=H)
        sections[f"{label} = {energy:.3f} J"] = (pts[:, 1], pts[:, 3], owner)
        out[label] = {
            "energy_J": energy,
            "starts": int(starts.shape[1]),
            "points": int(pts.shape[0]),
            "start_energy_relative_error": float(np.max(np.abs(batch_energy(starts, params) - energy)) / energy),
        }
    plots.plot_poincare_sections(sections, out_dir / "poincare_sections.png")
    return out


def _phi2_reach(energy: float, params: PendulumParameters) -> float:
    """Largest |phi2| [rad] on the section phi1 = 0 at rest with energy ``energy`` (95 % of it)."""
    grid = np.linspace(0.0, math.pi, 2001)
    allowed = grid[batch_potential_energy(0.0, grid, params) < energy]
    return 0.95 * float(allowed.max())


# ---------------------------------------------------------------------------- the scenario
def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Run every part and write CSVs, plots and ``summary.json``."""
    plan = QUICK if quick else FULL
    params = PendulumParameters()
    out_dir = Path(out_dir)
    start = time.perf_counter()
    fmu = fmu_runs(runner, out_dir, plan, params)
    lyap = lyapunov(out_dir, plan, params)
    summary: dict = {
        "scenario": "chaos",
        "quick": quick,
        "default_start": DEFAULT_START,
        "start_uncertainty_m": START_UNCERTAINTY,
        "lyapunov_per_s": lyap["lyapunov_per_s"],
        "lyapunov": lyap,
        "fmu_runs": {k: v for k, v in fmu.items() if k != "nominal"},
        "fmu_vs_batch_dop853_max_angle_difference_rad_first_2s": fmu_vs_batch(fmu["nominal"], params),
    }
    summary["predictability"] = ensembles(out_dir, plan, params, lyap["lyapunov_per_s"])
    summary["flip_map"] = flip_map(out_dir, plan, params)
    summary["poincare"] = poincare(out_dir, plan, params)
    summary["wall_time_s"] = time.perf_counter() - start
    write_json(out_dir / "summary.json", summary)
    return summary
