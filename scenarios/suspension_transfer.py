r"""Scenario ``suspension_transfer``: can a damped suspension of the pivot explain the measured decay?

The seed measured the pendulum's energy falling as E = a exp(b t) with b = -0.024 1/s (the
project's own fit of Table 1, ``energy_decay``: b = -0.0252 1/s). Air drag on bobs and rods and
bearing friction at the seed's estimates (the parameter defaults) give only about a fifth of that.
This scenario asks how much a pivot on a damped suspension (mass M_s, springs k = k_x = k_y,
dampers c = c_x = c_y) adds, and which suspensions reproduce the measurement. Every run goes
through the FMU, from the state the pendulum was measured in after the hand release (fitted to the
first frames by :func:`double_pendulum.analysis.start_state.fit_start_state`), with air drag (bobs and rods)
and bearing friction on.

Decay rate. b is fitted to the **pendulum's** energy E_pendulum (the two bobs, output of the FMU)
on the measured frames with the measured fit's calibrated errors
(:func:`double_pendulum.analysis.decay_fit.fit_model`, ``exponential``), so a simulated b and the measured b
are the same statistic of the same frames. The camera sees the bobs only, so E_pendulum is the
measured quantity; E_total = E_pendulum + E_suspension differs by the energy stored in the
suspension (the map records b of both; the summary gives the largest difference).

Physics of the map. :mod:`double_pendulum.analysis.suspension_response` predicts the suspension's share of b
from the spectrum of the force the pendulum exerts on a fixed pivot (linear response, one FMU run):
a stiff suspension gives b - b0 ~ -c <|dF/dt|^2> / (k^2 E) (iso-b curves c ~ k^2), a lightly damped
one whose natural frequency sqrt(k/M) lies inside the force spectrum takes pi S_F(omega_n) / (2 M)
whatever c, an overdamped one <F^2>/c. The map is checked against all three.

Decay shape. Besides b, the power law dE/dt = -k E^p (``decay_fit`` model ``power``) is fitted to
the measured and the simulated energies: p tells how the loss depends on the amplitude (1/2 for
Coulomb friction, 1 for viscous losses, 3/2 for quadratic drag).

Outputs in ``results/suspension_transfer/``: ``decay_rate_map.csv`` (the sweep), ``frames.csv``
(measured and simulated energy per frame), ``identified.csv`` / ``resonant.csv`` (FMU trajectories
of the identified suspension and of a resonant one on the same iso-b curve),
``fixed_pivot_force.csv``; plots ``decay_rate_map.png``, ``decay_rate_cuts.png``,
``force_spectrum.png``, ``energy_flow.png``, ``energy_fit.png``; ``summary.json``; ``report.md``.

The analysis lives in the package: :mod:`double_pendulum.analysis.suspension_identification` (measured decay,
identification of c, its valley, decay shape) and :mod:`double_pendulum.analysis.decay_map` (the sweep over
(k, c, M_s) and its checks against the physics).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from double_pendulum.scenarios.energy_decay import SEED_FIT

from double_pendulum import plots
from double_pendulum.analysis.decay_map import (
    MAP_SETTINGS,
    MAP_UNITS,
    DecayMap,
    crossing,
    decay_map,
    linear_response_grid,
    map_summary,
    trace_valley,
)
from double_pendulum.analysis.measurement import FRAME_INTERVAL, load_track, reconstruct
from double_pendulum.analysis.suspension_identification import (
    DEFAULT_SUSPENSION,
    FIT_SETTINGS,
    LOSSES,
    QUICK_WINDOW_S,
    FitFrames,
    Identification,
    MeasuredDecay,
    decay_shape,
    identify_suspension,
    pendulum_values,
    point_summary,
    simulate_frames_from,
    simulated_decay_rate,
    suspension_values,
    valley_fisher,
    window_check,
)
from double_pendulum.analysis.suspension_response import ForceSpectrum
from double_pendulum.fmu.runner import FmuRunner
from double_pendulum.results_io import write_json, write_results_csv, write_text

DESCRIPTION = "decay rate b over suspension stiffness and damping; suspension identified from the measured decay"

SEED_B = SEED_FIT["b_per_s"]
"""The seed's measured decay rate [1/s]."""
ENERGY_FLOW_INTERVAL = 0.005
"""Output interval [s] of the energy-flow runs (P_to_suspension oscillates at omega_n)."""
ENERGY_FLOW_OUTPUTS: tuple[str, ...] = (
    "E_pendulum",
    "E_suspension",
    "E_total",
    "W_air",
    "W_bearing",
    "W_suspension",
    "P_to_suspension",
    "xs",
    "ys",
    "energy_residual",
)


@dataclass(frozen=True)
class Plan:
    """Sizes of one run: sweep grids, time window, extra fits."""

    k_grid: tuple[float, ...]
    c_grid: tuple[float, ...]
    m_s_main: float
    m_s_extra: tuple[float, ...]
    extra_stride: int
    window_s: float | None
    valley_k_factors: tuple[float, ...]
    window_checks_s: tuple[float, ...]
    max_workers: int | None


def _k_grid(exponents: Sequence[int]) -> tuple[float, ...]:
    """Stiffnesses 2e4 * 10^(n/5) N/m: the default k and steps of 1.585 around it."""
    return tuple(DEFAULT_SUSPENSION.k_x * 10.0 ** (n / 5.0) for n in exponents)


FULL = Plan(
    k_grid=_k_grid(range(-3, 6)),
    c_grid=tuple(float(c) for c in np.geomspace(1.0, 3000.0, 9)),
    m_s_main=DEFAULT_SUSPENSION.M_s,
    m_s_extra=(0.5, 8.0),
    extra_stride=2,
    window_s=None,
    valley_k_factors=(1.25, 1.5),
    window_checks_s=(7.0, 14.0),
    max_workers=None,
)
QUICK = Plan(
    k_grid=_k_grid((0, 3)),
    c_grid=(5.0, 200.0),
    m_s_main=DEFAULT_SUSPENSION.M_s,
    m_s_extra=(),
    extra_stride=1,
    window_s=QUICK_WINDOW_S,
    valley_k_factors=(),
    window_checks_s=(),
    max_workers=1,
)


# --- energy flow ---------------------------------------------------------------------------------


def energy_flow_run(runner: FmuRunner, values: Mapping[str, Any], frames: FitFrames) -> np.ndarray:
    """The run over the fit window at :data:`ENERGY_FLOW_INTERVAL` with the energy-flow outputs."""
    return simulate_frames_from(runner, values, frames, outputs=ENERGY_FLOW_OUTPUTS, interval=ENERGY_FLOW_INTERVAL)


def _peak_frequency(signal: np.ndarray, dt: float) -> float:
    """Angular frequency [rad/s] of the largest peak of the signal's amplitude spectrum (mean removed)."""
    spec = np.abs(np.fft.rfft(signal - np.mean(signal)))
    freq = np.fft.rfftfreq(len(signal), dt)
    return float(2.0 * math.pi * freq[1:][np.argmax(spec[1:])])


def energy_flow_summary(result: np.ndarray) -> dict[str, float]:
    r"""Where the pendulum's lost energy went, and the power balance of the suspension.

    Shares of the pendulum's loss E_p(t0) - E_p(end): W_suspension, W_air, W_bearing and what the
    suspension still holds. Balance: :math:`\int P_{to\ suspension}\,dt` (trapezoid) against
    E_suspension(end) - E_suspension(t0) + W_suspension(end); the difference is the trapezoid error of
    sampling a power that oscillates at the suspension frequency.
    """
    t = np.asarray(result["time"])
    e_p = np.asarray(result["E_pendulum"])
    lost = float(e_p[0] - e_p[-1])
    w_s = float(result["W_suspension"][-1])
    e_s = np.asarray(result["E_suspension"])
    p_int = float(np.trapezoid(result["P_to_suspension"], t))
    dt = float(t[1] - t[0])
    return {
        "pendulum_energy_lost_J": lost,
        "share_W_suspension": w_s / lost,
        "share_W_air": float(result["W_air"][-1]) / lost,
        "share_W_bearing": float(result["W_bearing"][-1]) / lost,
        "share_still_in_suspension": float(e_s[-1]) / lost,
        "max_E_suspension_J": float(np.max(e_s)),
        "mean_E_suspension_J": float(np.mean(e_s)),
        "mean_P_to_suspension_W": float(np.mean(result["P_to_suspension"])),
        "rms_P_to_suspension_W": float(np.sqrt(np.mean(np.asarray(result["P_to_suspension"]) ** 2))),
        "integral_P_dt_J": p_int,
        "E_suspension_gain_plus_W_suspension_J": float(e_s[-1] - e_s[0]) + w_s,
        "peak_frequency_xs_rad_s": _peak_frequency(np.asarray(result["xs"]), dt),
        "peak_frequency_ys_rad_s": _peak_frequency(np.asarray(result["ys"]), dt),
        "rms_xs_m": float(np.std(result["xs"])),
        "rms_ys_m": float(np.std(result["ys"])),
        "max_abs_energy_residual_J": float(np.max(np.abs(result["energy_residual"]))),
    }


def spectrum_summary(spectrum: ForceSpectrum, ident: Identification) -> dict[str, Any]:
    """Force statistics, the identified suspension's natural frequencies and the three limits there."""
    var_x, var_y = spectrum.force_variances()
    m_x, m_y = spectrum.masses(ident.m_s)
    return {
        "rms_F_x_N": math.sqrt(var_x),
        "rms_F_y_N": math.sqrt(var_y),
        "mean_dF_dt_squared_N2_per_s2": spectrum.fdot_squared,
        "rms_frequency_rad_s": math.sqrt(spectrum.fdot_squared / (var_x + var_y)),
        "mean_E_pendulum_J": spectrum.mean_energy,
        "identified_omega_n_x_rad_s": math.sqrt(ident.k / m_x),
        "identified_omega_n_y_rad_s": math.sqrt(ident.k / m_y),
        "linear_response_share_at_identified_per_s": spectrum.linear_response_rate(ident.k, ident.c, ident.m_s),
        "resonant_limit_share_at_identified_per_s": spectrum.resonant_rate(ident.k, ident.m_s),
        "quasi_static_share_at_identified_per_s": spectrum.quasi_static_rate(ident.k, ident.c),
    }


# --- files ---------------------------------------------------------------------------------------


def _table(rows: Sequence[Mapping[str, float]]) -> np.ndarray:
    """Rows of equal keys as a structured array (for :func:`write_results_csv`)."""
    names = list(rows[0])
    return np.rec.fromarrays([np.array([r[n] for r in rows], dtype=float) for n in names], names=names).view(np.ndarray)


FRAME_UNITS = {
    "frame": "1",
    "E_measured": "J",
    "sigma_E": "J",
    "E_pendulum_identified": "J",
    "E_total_identified": "J",
    "E_pendulum_no_suspension": "J",
    "E_pendulum_resonant": "J",
    "residual_identified": "1",
}


def _frames_table(md: MeasuredDecay, runs: Mapping[str, np.ndarray], ident_resid: np.ndarray) -> np.ndarray:
    """Per fitted frame: measured energy and errors, simulated energies, normalised residuals."""
    off = md.frames.offsets
    columns: dict[str, np.ndarray] = {
        "time": md.frames.t,
        "frame": (md.i0 + off).astype(float),
        "E_measured": md.energy,
        "sigma_E": md.frames.sigma,
        "E_pendulum_identified": runs["identified"]["E_pendulum"][off],
        "E_total_identified": runs["identified"]["E_total"][off],
        "E_pendulum_no_suspension": runs["no suspension"]["E_pendulum"][off],
    }
    if "resonant" in runs:
        columns["E_pendulum_resonant"] = runs["resonant"]["E_pendulum"][off]
    columns["residual_identified"] = ident_resid
    return np.rec.fromarrays([np.asarray(v, dtype=float) for v in columns.values()], names=list(columns)).view(
        np.ndarray
    )


def _map_panels(maps: Sequence[DecayMap], spectrum: ForceSpectrum, n_fine: int) -> dict[str, dict[str, np.ndarray]]:
    panels = {}
    for dmap in maps:
        kf, cf, bf = linear_response_grid(
            spectrum, dmap.b_base, (dmap.k[0], dmap.k[-1]), (dmap.c[0], dmap.c[-1]), dmap.m_s, n_fine
        )
        panel = {"k": dmap.k, "c": dmap.c, "b": dmap.b, "k_fine": kf, "c_fine": cf, "b_fine": bf}
        panels[f"M_s = {dmap.m_s:g} kg"] = panel
    return panels


def _plots(
    out_dir: Path,
    maps: Sequence[DecayMap],
    spectrum: ForceSpectrum,
    md: MeasuredDecay,
    ident: Identification,
    points: Mapping[str, tuple[float, float]],
    runs: Mapping[str, np.ndarray],
    flows: Mapping[str, np.ndarray],
    n_fine: int,
) -> None:
    main = maps[0]
    levels = {"measured (this project)": md.b, "seed": SEED_B}
    plots.plot_decay_rate_map(
        _map_panels(maps, spectrum, n_fine),
        levels,
        out_dir / "decay_rate_map.png",
        points=points,
        slope_through=(ident.k, ident.c),
    )
    c_fine = np.geomspace(main.c[0], main.c[-1], 80)
    lr = np.array([[spectrum.linear_response_rate(k, c, main.m_s) for c in c_fine] for k in main.k])
    qs = np.array([[spectrum.quasi_static_rate(k, c) for c in c_fine] for k in main.k])
    plots.plot_decay_rate_cuts(
        main.k, main.c, main.b_suspension, c_fine, lr, qs, md.b - main.b_base, out_dir / "decay_rate_cuts.png"
    )
    w_x, w_y = math.sqrt(ident.k / ident.m_s), math.sqrt(ident.k / (ident.m_s + spectrum.m12))
    marks = {
        f"identified omega_n,x = sqrt(k/M_s) = {w_x:.0f} rad/s": w_x,
        f"identified omega_n,y = sqrt(k/(M_s+m1+m2)) = {w_y:.0f} rad/s": w_y,
    }
    shown = spectrum.omega >= 1.0  # below, the Welch window's leakage of the decaying mean
    plots.plot_force_spectrum(
        spectrum.omega[shown],
        {"F_x": spectrum.s_x[shown], "F_y": spectrum.s_y[shown]},
        marks,
        out_dir / "force_spectrum.png",
    )
    plots.plot_energy_flow(flows, out_dir / "energy_flow.png")
    t_curve = md.frames.t0 + np.arange(md.frames.n_frames) * FRAME_INTERVAL
    curves = {f"FMU, {label}": np.asarray(r["E_pendulum"]) for label, r in runs.items()}
    full_t = md.rec.t
    used = np.zeros(len(full_t), dtype=bool)
    used[md.i0 + md.frames.offsets] = True
    sigma = np.full(len(full_t), np.nan)
    sigma[used] = md.frames.sigma
    plots.plot_energy_decay(
        full_t,
        md.rec.energy,
        sigma,
        curves,
        t_curve,
        out_dir / "energy_fit.png",
        used=used,
        residual_curve="FMU, identified",
    )


# --- the scenario --------------------------------------------------------------------------------


def _resonant_point(main: DecayMap, level: float) -> tuple[float, float] | None:
    """(k, c) where the lightest-damped column of the map crosses ``level``: the resonant end of the curve."""
    k = crossing(main.k, main.b[:, 0], level)
    return None if k is None else (k, float(main.c[0]))


def _measured_summary(md: MeasuredDecay) -> dict[str, Any]:
    return {
        "t0_s": md.frames.t0,
        "release_frame": md.i0,
        "n_frames": int(len(md.frames.t)),
        "window_s": [float(md.frames.t[0]), float(md.frames.t[-1])],
        "a_J": md.fit.value("a"),
        "b_per_s": md.b,
        "b_per_s_stderr": md.fit.error("b"),
        "b_per_s_stderr_autocorr": md.b_err,
        "autocorrelation_factor": md.factor,
        "seed_b_per_s": SEED_B,
        "decay_shape": decay_shape(md.frames.t, md.energy, md.frames.sigma, md.factor),
    }


def _run_summary(md: MeasuredDecay, result: np.ndarray, reference_chi2: float) -> dict[str, Any]:
    """b (E_pendulum and E_total), p and chi2 of one FMU run on the fitted frames."""
    energy = np.asarray(result["E_pendulum"])[md.frames.offsets]
    r = (energy - md.energy) / md.frames.sigma
    b = simulated_decay_rate(result, md.frames)
    return {
        "b_E_pendulum_per_s": b,
        "b_E_total_per_s": simulated_decay_rate(result, md.frames, "E_total"),
        "relative_difference_to_measured": (b - md.b) / md.b,
        "difference_in_measured_sigma": (b - md.b) / md.b_err,
        "p": decay_shape(md.frames.t, energy, md.frames.sigma)["p"],
        "chi2": float(r @ r),
        "delta_chi2": float(r @ r) - reference_chi2,
    }


def _resonant_summary(point: tuple[float, float], m_s: float, spectrum: ForceSpectrum) -> dict[str, float]:
    """The resonant end of the iso-b curve with its natural frequencies [rad/s]."""
    m_x, m_y = spectrum.masses(m_s)
    k, c = point
    return {
        "k_N_per_m": k,
        "c_N_s_per_m": c,
        "M_s_kg": m_s,
        "omega_n_x_rad_s": math.sqrt(k / m_x),
        "omega_n_y_rad_s": math.sqrt(k / m_y),
        "linear_response_share_per_s": spectrum.linear_response_rate(k, c, m_s),
        "resonant_limit_share_per_s": spectrum.resonant_rate(k, m_s),
    }


def _sweep_maps(
    runner: FmuRunner, base: Mapping[str, Any], md: MeasuredDecay, spectrum: ForceSpectrum, plan: Plan
) -> list[DecayMap]:
    """The main (k, c) map at plan.m_s_main and coarser ones (every extra_stride-th value) at the other masses."""
    maps = [
        decay_map(runner.fmu_path, base, md.frames, spectrum, plan.k_grid, plan.c_grid, plan.m_s_main, plan.max_workers)
    ]
    k_grid, c_grid = plan.k_grid[:: plan.extra_stride], plan.c_grid[:: plan.extra_stride]
    for m_s in plan.m_s_extra:
        maps.append(decay_map(runner.fmu_path, base, md.frames, spectrum, k_grid, c_grid, m_s, plan.max_workers))
    return maps


def _write_files(
    out_dir: Path,
    runner: FmuRunner,
    maps: Sequence[DecayMap],
    md: MeasuredDecay,
    ident: Identification,
    runs: Mapping[str, np.ndarray],
    flows: Mapping[str, np.ndarray],
    spectrum: ForceSpectrum,
) -> None:
    rows = [row for d in maps for row in d.rows(spectrum.m12)]
    write_results_csv(out_dir / "decay_rate_map.csv", _table(rows), MAP_UNITS)
    write_results_csv(out_dir / "frames.csv", _frames_table(md, runs, ident.residuals), FRAME_UNITS)
    for label, flow in flows.items():
        write_results_csv(out_dir / f"{label}.csv", flow, runner.units)
    write_results_csv(out_dir / "fixed_pivot_force.csv", spectrum.result, runner.units)


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Identify, sweep, check, write CSVs, plots, summary and report (see the module docstring)."""
    wall0 = time.perf_counter()
    out_dir = Path(out_dir)
    plan = QUICK if quick else FULL
    rec = reconstruct(load_track())
    model = identify_suspension(runner, rec, quick=quick, m_s=plan.m_s_main)
    md, ident, spectrum = model.measured, model.identification, model.spectrum
    base = {**pendulum_values(rec), **LOSSES, **model.start.start_values()}
    t_map = time.perf_counter()
    maps = _sweep_maps(runner, base, md, spectrum, plan)
    map_wall = time.perf_counter() - t_map
    trace = trace_valley(runner, md, base, ident, maps[0], plan.valley_k_factors)
    runs = {
        "identified": simulate_frames_from(runner, model.values, md.frames),
        "no suspension": simulate_frames_from(runner, base, md.frames),
    }
    flows = {"identified": energy_flow_run(runner, model.values, md.frames)}
    points = {f"identified (k fixed at {ident.k:g} N/m)": (ident.k, ident.c)}
    points.update({f"c refitted at k = {f.k:.3g} N/m": (f.k, f.c) for f in trace})
    resonant = _resonant_point(maps[0], md.b) if plan.valley_k_factors else None
    if resonant is not None:
        values = {**base, **suspension_values(resonant[0], resonant[1], plan.m_s_main)}
        runs["resonant"] = simulate_frames_from(runner, values, md.frames)
        flows["resonant"] = energy_flow_run(runner, values, md.frames)
        points["resonant end of the curve"] = resonant
    summary: dict[str, Any] = {
        "scenario": "suspension_transfer",
        "quick": quick,
        "energy_fitted": "E_pendulum (the bobs' energy, what the camera measures)",
        "settings": {"map": MAP_SETTINGS, "fits": FIT_SETTINGS, "losses": LOSSES},
        "measured": _measured_summary(md),
        "start_state": model.start.as_dict(),
        "identified": {**point_summary(md, ident, ident.chi2), "fixed": {"k": ident.k, "M_s": ident.m_s}},
        "refit": {label: _run_summary(md, r, ident.chi2) for label, r in runs.items()},
        "valley": {
            "fisher": valley_fisher(runner, md, base, ident),
            "trace": [point_summary(md, f, ident.chi2) for f in trace],
            "resonant_end": None if resonant is None else _resonant_summary(resonant, plan.m_s_main, spectrum),
        },
        "window_checks": [window_check(runner, rec, base, ident, w) for w in plan.window_checks_s],
        "spectrum": spectrum_summary(spectrum, ident),
        "maps": [map_summary(d, spectrum, md, SEED_B) for d in maps],
        "energy_flow": {label: energy_flow_summary(f) for label, f in flows.items()},
        "map_runs": int(sum(d.b.size + 1 for d in maps)),
        "map_wall_time_s": map_wall,
    }
    _write_files(out_dir, runner, maps, md, ident, runs, flows, spectrum)
    _plots(out_dir, maps, spectrum, md, ident, points, runs, flows, 24 if quick else 60)
    summary["wall_time_s"] = time.perf_counter() - wall0
    write_json(out_dir / "summary.json", summary)
    write_text(out_dir / "report.md", report_text(summary))
    return summary


# --- report ------------------------------------------------------------------------------------


def _g(value: float | None, fmt: str = ".4g") -> str:
    return "-" if value is None else format(value, fmt)


def _measured_section(s: Mapping[str, Any]) -> str:
    m, st = s["measured"], s["start_state"]
    shape = m["decay_shape"]
    return f"""## Measured decay and start

The camera energy (``double_pendulum.analysis.measurement``, calibrated errors, {m["n_frames"]} frames from the end of
the hand release at t = {m["window_s"][0]:.2f} s to t = {m["window_s"][1]:.2f} s): E = a exp(b t) with
a = {m["a_J"]:.4f} J, **b = {m["b_per_s"]:.5f} +- {m["b_per_s_stderr_autocorr"]:.5f} 1/s** (error inflated by the
residual correlation, factor {m["autocorrelation_factor"]:.2f}); the seed printed b = {m["seed_b_per_s"]} 1/s.
The free exponent of dE/dt = -k E^p is p = {shape["p"]:.2f} +- {shape["p_stderr"]:.2f}.

Every run starts at t0 = {m["t0_s"]:.3f} s from the state fitted to the positions of the first
{st["n_frames"]} frames (rms residual {1e3 * st["rms_residual"]:.1f} mm, chi2_red {st["chi2_red"]:.0f}: the track's
own systematic errors, see ``measured_vs_sim``): phi1 = {st["state"]["phi1_0"]:.4f} rad,
phi2 = {st["state"]["phi2_0"]:.4f} rad, omega1 = {st["state"]["omega1_0"]:.3f} rad/s,
omega2 = {st["state"]["omega2_0"]:.3f} rad/s. Air drag (bobs and rods) and bearing friction are on at the
defaults. b is fitted to E_pendulum, the bobs' energy: the camera sees the bobs, not the suspension.
"""


def _contour_text(points: Sequence[Mapping[str, Any]]) -> str:
    if not points:
        return "none on this grid"
    return "; ".join(f"k = {p['k']:.3g} N/m, c = {p['c']:.3g} N s/m ({p['branch']})" for p in points)


def _map_section(s: Mapping[str, Any]) -> str:
    main = s["maps"][0]
    lines = []
    for m in s["maps"]:
        lines.append(
            f"| {m['M_s_kg']:g} | {len(m['k_N_per_m'])} x {len(m['c_N_s_per_m'])} "
            f"| {m['b_base_no_suspension_per_s']:.5f} "
            f"| {_g(m['reach_measured_b']['stiffest_k_reaching_N_per_m'], '.3g')} "
            f"| {_contour_text(m['iso_b_measured'])} |"
        )
    lr, qs, stiff = main["linear_response"], main["quasi_static_c_over_k2"], main["stiff_region"]
    needed = s["measured"]["b_per_s"] - main["b_base_no_suspension_per_s"]
    mono = main["monotonic_in_c"]
    mono_rows = ", ".join(
        f"{k} ({'yes' if v['monotonic_below_it'] else 'no'}, peak at c = {v['c_at_largest_loss']:.3g})"
        for k, v in mono.items()
    )
    qs_share = _g(qs["largest_share_within_per_s"], ".2g")
    largest = qs["largest_share_within_per_s"]
    verdict = (
        ": a suspension stiff enough for the law cannot explain the measurement"
        if largest is not None and largest < -needed
        else ""
    )
    fisher = s["valley"]["fisher"]
    return f"""## The map b(k, c)

{s["map_runs"]} FMU runs (``decay_rate_map.csv``, ``decay_rate_map.png``), k = k_x = k_y from
{main["k_N_per_m"][0]:.3g} to {main["k_N_per_m"][-1]:.3g} N/m, c = c_x = c_y from {main["c_N_s_per_m"][0]:.3g} to
{main["c_N_s_per_m"][-1]:.3g} N s/m, swept in {s["map_wall_time_s"]:.0f} s by ``analysis.sweep.run_sweep``.
b of E_pendulum and of E_total differ by at most {main["max_abs_b_E_pendulum_minus_b_E_total"]:.1e} 1/s.

| M_s [kg] | grid | b without suspension [1/s] | stiffest k reaching the measured b [N/m] | iso-b points (measured b) |
|---|---|---|---|---|
{chr(10).join(lines)}

**The suspensions that explain the measured b form a curve, not a point.** The suspension has to add
{needed:.4f} 1/s. {_branches_text(s)}

**Shape check.** The stiff-suspension law (dissipated power c <|dF/dt|^2> / k^2, so b - b0 ~ c/k^2 and
iso-b curves c ~ k^2) is checked where the suspension is much stiffer than the pendulum (natural
frequencies and k/c at least {stiff["natural_frequency_over_force_frequency"]:g} times the force's rms
frequency, {stiff["n_cells"]} cells): it holds within {100 * qs["tolerance"]:.0f} % in {qs["n_cells_within"]} of them,
per k at c = {_rows(qs["rows_within"])}; elsewhere in that region the c-independent resonant loss
still adds (small c). The largest suspension share where the law holds is {qs_share} 1/s, against the
{-needed:.4f} 1/s needed{verdict}. Along the measured curve the local slope of the valley is
d ln c / d ln k = {fisher["valley_slope_dlnc_dlnk"]:.1f} (c ~ k^2 would be 2). The full linear response
(``double_pendulum.analysis.suspension_response``, from one fixed-pivot run's force spectrum; dotted in the map)
agrees with the FMU within
{100 * lr["tolerance"]:.0f} % in {lr["n_cells_within"]} of {lr["n_cells"]} cells, per k at c =
{_rows(lr["rows_within"])}: it
fails where the suspension drains the pendulum so fast that its motion (and force spectrum) changes,
i.e. at soft, lightly damped suspensions, and in the chaotic resonance floor. See ``decay_rate_cuts.png``.

**Monotonic in c?** Per k [N/m]: whether |b| grows monotonically with c up to its largest loss:
{mono_rows}. Where it does not, the lightly damped end wiggles: the resonant loss depends on the chaotic
trajectory's spectrum near omega_n, which changes from run to run.
"""


def _branches_text(s: Mapping[str, Any]) -> str:
    """The three branches of the measured iso-b curve on the main map, in numbers."""
    main = s["maps"][0]
    pts = main["iso_b_measured"]
    rising = [p for p in pts if p["branch"] == "rising"]
    falling = [p for p in pts if p["branch"] == "falling"]
    res = s["valley"]["resonant_end"]
    reach = main["reach_measured_b"]
    out = [f"On the map at M_s = {main['M_s_kg']:g} kg the measured b is crossed at: {_contour_text(pts)}."]
    if res is not None:
        out.append(
            f"Lightly damped branch: at c = {res['c_N_s_per_m']:g} N s/m the crossing lies at "
            f"k = {res['k_N_per_m']:.3g} N/m, "
            f"where the suspension's natural frequencies ({res['omega_n_x_rad_s']:.0f} rad/s horizontally, "
            f"{res['omega_n_y_rad_s']:.0f} rad/s vertically) lie in the pendulum's force spectrum and the loss hardly "
            f"depends on c (resonant limit pi S(omega_n)/(2M): {res['resonant_limit_share_per_s']:.4f} 1/s; the "
            f"linear response overestimates here, the FMU run at that point gives "
            f"b = {s['refit']['resonant']['b_E_pendulum_per_s']:.4f} 1/s: along c = {res['c_N_s_per_m']:g} the map "
            "is rough, the resonant loss follows the chaotic trajectory)."
        )
    if rising:
        out.append(f"Rising branch ({len(rising)} crossings): c grows steeply with k.")
    if falling:
        out.append(f"Overdamped branch ({len(falling)} crossings): the damper clamps the pivot, b ~ 1/c.")
    stiffest = reach["stiffest_k_reaching_N_per_m"]
    c_best = ", ".join(f"{k}: {c:.3g}" for k, c in reach["c_of_most_negative_b"].items())
    out.append(
        f"No c on the grid reaches the measured b above k = {_g(stiffest, '.3g')} N/m: at fixed k the loss peaks at "
        f"c ~ k/omega (c of the largest loss per k: {c_best}) and that peak falls with k. The stiffest k that still "
        f"reaches it per suspension mass: "
        + ", ".join(
            f"{m['M_s_kg']:g} kg: {_g(m['reach_measured_b']['stiffest_k_reaching_N_per_m'], '.3g')} N/m"
            for m in s["maps"]
        )
        + " (a heavier suspension has lower natural frequencies at the same k)."
    )
    return " ".join(out)


def _rows(rows: Mapping[str, Sequence[float]]) -> str:
    parts = [f"{k}: {', '.join(f'{c:.3g}' for c in cs)}" for k, cs in rows.items() if cs]
    return "; ".join(parts) if parts else "none"


def _identification_section(s: Mapping[str, Any]) -> str:
    i, v = s["identified"], s["valley"]
    f = v["fisher"]
    trace = [i, *v["trace"]]
    rows = "\n".join(
        f"| {t['k_N_per_m']:.3g} | {t['c_N_s_per_m']:.4g} +- {t['c_stderr']:.2g} | {t['chi2']:.1f} "
        f"| {t['delta_chi2']:+.1f} "
        f"| {t['delta_chi2_over_factor']:+.1f} | {t['b_per_s']:.5f} | {t['p']:.2f} |"
        for t in trace
    )
    res = v["resonant_end"]
    res_text = (
        ""
        if res is None
        else (
            f"The resonant end of the curve (k = {res['k_N_per_m']:.3g} N/m, c = {res['c_N_s_per_m']:g} N s/m) fits "
            f"worse: chi2 = {s['refit']['resonant']['chi2']:.0f} "
            f"({s['refit']['resonant']['delta_chi2']:+.0f}); its loss depends even more steeply on the amplitude "
            f"(p = {s['refit']['resonant']['p']:.2f})."
        )
    )
    return f"""## Identification

Least squares of the simulated E_pendulum against the measured energy per frame (calibrated errors),
k = {i["fixed"]["k"]:g} N/m and M_s = {i["fixed"]["M_s"]:g} kg fixed (the parameter defaults), c free:
**c = {i["c_N_s_per_m"]:.1f} +- {i["c_stderr"]:.1f} N s/m** (+- {i["c_stderr_uncorrelated"]:.1f} from the Jacobian,
inflated by sqrt({i["autocorrelation_factor"]:.1f}) for the correlated residuals), chi2 = {i["chi2"]:.1f} for
{i["n_frames"]} frames (chi2_red {i["chi2_red"]:.2f}), {i["n_fmu_runs"]} FMU runs.

**The degenerate direction.** The energy fixes one combination of (k, c, M_s). The Jacobian in
(ln k, ln c, ln M_s) at the identified point has Fisher eigenvalues {", ".join(f"{e:.3g}" for e in f["eigenvalues"])};
the weakest direction is {", ".join(f"{n} {x:+.2f}" for n, x in f["weakest_direction"].items())}. Fitting k too would
give sigma(ln k) = {f["stderr_ln_k_with_k_free"]:.3f}, sigma(ln c) = {f["stderr_ln_c_with_k_free"]:.2f} with correlation
{f["correlation_ln_k_ln_c"]:.3f}: a long narrow valley along d ln c / d ln k = {f["valley_slope_dlnc_dlnk"]:.1f}.
M_s moves the residuals {f["sensitivity_ratio_M_s_to_c"]:.1f} times as much as ln c does per unit of its logarithm,
nearly as the opposite of k does (the residual changes of ln M_s and ln k have a cosine of
{f["cos_angle_ln_k_ln_M_s"]:+.2f}): M_s enters mainly through the natural frequencies sqrt(k/M).

Following the valley (c refitted at fixed k):

| k [N/m] | c [N s/m] | chi2 | delta chi2 | delta chi2 / factor | b [1/s] | p |
|---|---|---|---|---|---|---|
{rows}

{res_text} {_valley_text(trace)}
"""


def _valley_text(trace: Sequence[Mapping[str, Any]]) -> str:
    """Which way chi2 runs along the valley, and what that means."""
    if len(trace) < 2:
        return "(The valley is followed in the full run only.)"
    last = trace[-1]
    direction = "falls" if last["delta_chi2"] < 0 else "rises"
    return (
        f"Along the valley chi2 {direction} by {abs(last['delta_chi2']):.0f} "
        f"({abs(last['delta_chi2_over_factor']):.1f} after dividing by the correlation factor) from "
        f"k = {trace[0]['k_N_per_m']:.3g} to {last['k_N_per_m']:.3g} N/m, while p goes from {trace[0]['p']:.2f} "
        f"to {last['p']:.2f}: the valley is not flat, chi2 follows how closely the "
        "shape of the simulated decay (its amplitude dependence p) matches the measured one. No suspension reproduces "
        "that shape (next section), so this preference does not identify k: the result is the iso-b curve of the map "
        "and this valley, with c quoted at the default k."
    )


def _refit_section(s: Mapping[str, Any]) -> str:
    m = s["measured"]
    rows = "\n".join(
        f"| {label} | {r['b_E_pendulum_per_s']:.5f} | {r['b_E_total_per_s']:.5f} "
        f"| {100 * r['relative_difference_to_measured']:+.1f} % "
        f"| {r['difference_in_measured_sigma']:+.1f} | {r['p']:.2f} | {r['chi2']:.0f} |"
        for label, r in s["refit"].items()
    )
    windows = "\n".join(
        f"| first {w['window_s']:g} s | {w['measured_b_per_s']:.5f} +- {w['measured_b_stderr']:.5f} "
        f"| {w['c_N_s_per_m']:.1f} +- "
        f"{w['c_stderr']:.1f} | {w['b_per_s']:.5f} | {100 * w['b_relative_to_measured']:+.1f} % |"
        for w in s["window_checks"]
    )
    i = s["identified"]
    whole = (
        f"| whole record | {m['b_per_s']:.5f} +- {m['b_per_s_stderr_autocorr']:.5f} | {i['c_N_s_per_m']:.1f} +- "
        f"{i['c_stderr']:.1f} | {i['b_per_s']:.5f} | {100 * i['b_relative_to_measured']:+.1f} % |"
    )
    return f"""## Refit: does the identified suspension reproduce b?

The identified parameters run again through the FMU and b fitted on the same frames with the same
errors (measured: b = {m["b_per_s"]:.5f} +- {m["b_per_s_stderr_autocorr"]:.5f} 1/s, p = {m["decay_shape"]["p"]:.2f}):

| run | b of E_pendulum [1/s] | b of E_total [1/s] | vs measured | in measured sigma | p | chi2 |
|---|---|---|---|---|---|---|
{rows}

The same fit on the first seconds only (same start, same k, M_s; full run only):

| frames | measured b [1/s] | c [N s/m] | refit b [1/s] | vs measured |
|---|---|---|---|---|
{windows}{chr(10) if windows else ""}{whole}

**Rate yes, shape no.** Least squares of the energy matches the energy level, not the exponential rate,
so where the simulated decay has another shape the two rates differ. The exponent of dE/dt = -k E^p is
{i["p"]:.2f} for the identified suspension against the measured {m["decay_shape"]["p"]:.2f} +-
{m["decay_shape"]["p_stderr"]:.2f} (1/2: Coulomb friction, 1: viscous losses, 3/2: quadratic drag): the
suspension's loss grows steeply with the amplitude, because the force rate |dF/dt|^2 comes from the lower
bob's whips, which fade as the energy falls. One c fitted to a longer record has to make up for the fading
loss late in the record{_window_trend(s["window_checks"], i)}. The suspension can supply the measured rate,
but the measured shape points to a loss that depends weakly on the amplitude (Coulomb-like friction).
"""


def _window_trend(windows: Sequence[Mapping[str, Any]], whole: Mapping[str, Any]) -> str:
    if not windows:
        return ""
    cs = ", ".join(f"{w['c_N_s_per_m']:.1f}" for w in windows)
    spans = ", ".join(f"{w['window_s']:g}" for w in windows)
    return f": c = {cs} and {whole['c_N_s_per_m']:.1f} N s/m for the first {spans} s and the whole record"


FLOW_HEADER = (
    "| run | pendulum lost [J] | to the dampers | to air | to the bearings | max E_suspension [mJ] "
    "| P mean / rms [mW] | spectral peak of xs / ys [rad/s] | integral of P / E_s gain + W_s [J] |\n"
    "|---|---|---|---|---|---|---|---|---|"
)


def _flow_section(s: Mapping[str, Any]) -> str:
    sp = s["spectrum"]
    fmu_share = s["refit"]["identified"]["b_E_pendulum_per_s"] - s["refit"]["no suspension"]["b_E_pendulum_per_s"]
    parts = []
    for label, f in s["energy_flow"].items():
        parts.append(
            f"| {label} | {f['pendulum_energy_lost_J']:.3f} | {100 * f['share_W_suspension']:.0f} % | "
            f"{100 * f['share_W_air']:.0f} % | {100 * f['share_W_bearing']:.1f} % "
            f"| {1e3 * f['max_E_suspension_J']:.2f} | "
            f"{1e3 * f['mean_P_to_suspension_W']:.2f} / {1e3 * f['rms_P_to_suspension_W']:.0f} | "
            f"{f['peak_frequency_xs_rad_s']:.1f} / {f['peak_frequency_ys_rad_s']:.1f} | "
            f"{f['integral_P_dt_J']:.5f} / {f['E_suspension_gain_plus_W_suspension_J']:.5f} |"
        )
    return f"""## How the energy flows into the suspension

``energy_flow.png``, ``identified.csv`` (and ``resonant.csv``): P_to_suspension, E_suspension and the works
at 5 ms resolution.

{FLOW_HEADER}
{chr(10).join(parts)}

{_flow_text(s)}

Pivot force of the fixed-pivot pendulum (``force_spectrum.png``): rms {sp["rms_F_x_N"]:.2f} N horizontally,
{sp["rms_F_y_N"]:.2f} N vertically, rms frequency sqrt(<|dF/dt|^2>/<F^2>) = {sp["rms_frequency_rad_s"]:.1f} rad/s.
The identified suspension's natural frequencies, {sp["identified_omega_n_x_rad_s"]:.0f} rad/s (x) and
{sp["identified_omega_n_y_rad_s"]:.0f} rad/s (y), are only a few times that. Its share of b is
{fmu_share:.4f} 1/s in the FMU; linear response predicts {sp["linear_response_share_at_identified_per_s"]:.4f} 1/s,
the stiff limit {sp["quasi_static_share_at_identified_per_s"]:.4f} 1/s, the resonant limit alone
{sp["resonant_limit_share_at_identified_per_s"]:.4f} 1/s: neither limit applies, the suspension sits between them.
"""


def _flow_text(s: Mapping[str, Any]) -> str:
    f = s["energy_flow"]["identified"]
    text = (
        f"P_to_suspension swings both ways, its rms {f['rms_P_to_suspension_W'] / f['mean_P_to_suspension_W']:.0f} "
        "times its mean: the pivot force pumps energy into the springs and takes most of it back within each "
        "swing; what the dampers keep is the loss. The suspension holds on average "
        f"{1e3 * f['mean_E_suspension_J']:.2f} mJ, at most {1e3 * f['max_E_suspension_J']:.1f} mJ: it passes the "
        "energy on about as fast as it arrives. The power balance closes (last column). At the identified "
        f"point the pivot moves at {f['peak_frequency_xs_rad_s']:.1f} rad/s (x) and {f['peak_frequency_ys_rad_s']:.1f} "
        "rad/s (y): it follows the pendulum's own force"
    )
    r = s["energy_flow"].get("resonant")
    if r is not None:
        text += (
            f"; at the resonant end at {r['peak_frequency_xs_rad_s']:.0f} and "
            f"{r['peak_frequency_ys_rad_s']:.0f} rad/s, "
            f"its natural frequencies, holding {1e3 * r['mean_E_suspension_J']:.1f} mJ on average"
        )
    return text + "."


def report_text(summary: Mapping[str, Any]) -> str:
    """The Markdown report: every figure from ``summary``."""
    quick = " (quick run: small grid, first seconds only)" if summary["quick"] else ""
    b0 = summary["refit"]["no suspension"]["b_E_pendulum_per_s"]
    head = f"""# Can the pivot's suspension explain the measured energy decay?{quick}

Air drag and bearing friction at the seed's estimates take b = {b0:.4f} 1/s
of the measured {summary["measured"]["b_per_s"]:.4f} 1/s. How much can a damped suspension of the pivot add, which
suspensions reproduce the measurement, and is that the explanation? Run time {summary["wall_time_s"]:.0f} s.

"""
    sections = (_measured_section, _map_section, _identification_section, _refit_section, _flow_section)
    return head + "\n".join(section(summary) for section in sections)
