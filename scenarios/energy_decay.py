"""Scenario ``energy_decay``: the energy loss of the real pendulum from the seed's camera track.

No simulation: the scenario analyses Table 1 (``data/seed_table1.csv``) like the seed's
section 4.2, with the package's own energy function. Outputs in ``results/energy_decay/``:

- ``track.csv``: per frame the positions relative to the fitted pivot, angles, angular
  velocities (central differences and Savitzky-Golay), energies and their uncertainties;
- ``energy_decay.png``: energy with error bars and the fitted decay models (the seed's fig. 7);
- ``circle_fit.png``: the pivot circle fit and the rod-length residuals;
- ``summary.json``: pivot, rod lengths, the exponential fit ``a_J``, ``b_per_s`` with errors, the
  model comparison (AIC/BIC), the same fit with other weights, and the seed's numbers;
- ``report.md``: the figures and why they differ from the seed's a = 0.813 J, b = -0.024 1/s.

The runner argument of :func:`run` is not used, nor is ``quick`` (the analysis takes about a second).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis.decay_fit import (
    AUTOCORRELATION_LAG_S,
    MODELS,
    FitResult,
    calibrate_error_model,
    comparison_table,
    effective_sample_factor,
    fit_all,
    fit_model,
)
from double_pendulum.analysis.measurement import (
    FPS,
    SEED_VELOCITY_ERROR,
    SG_POLYORDER,
    SG_WINDOW,
    Reconstruction,
    central_difference_coefficients,
    derivative_gain,
    load_track,
    reconstruct,
    savgol_derivative_coefficients,
)
from double_pendulum.results_io import write_json, write_results_csv, write_text

DESCRIPTION = (
    "energy decay of the real pendulum from the seed's camera track (Table 1), decay models compared"
)

SEED_FIT = {"a_J": 0.813, "a_rel_err": 0.0126, "b_per_s": -0.024, "b_rel_err": 0.0489}
"""The seed's exponential fit (section 4.2.5) and its relative errors, for comparison."""
SEED_TOTAL_MASS_KG = 0.7
"""The seed's total moving mass including the acrylic rods (section 4.2.3) [kg]."""
GAIN_CHECK_OMEGA = (10.0, 20.0, 25.0)
"""Angular frequencies [rad/s] at which the derivative filters' gains are reported."""

CSV_UNITS = {
    "frame": "1",
    "valid": "1",
    "in_fit": "1",
    "x1": "m",
    "y1": "m",
    "x2": "m",
    "y2": "m",
    "phi1": "rad",
    "phi2": "rad",
    "omega1_cd": "rad/s",
    "omega2_cd": "rad/s",
    "omega1": "rad/s",
    "omega2": "rad/s",
    "E_cd": "J",
    "E": "J",
    "E_kin": "J",
    "E_pot": "J",
    "sigma_E_seed": "J",
    "sigma_E_noise": "J",
    "sigma_E_fit": "J",
}


# --- analysis -----------------------------------------------------------------------------------


def _track_table(rec: Reconstruction, sigma_fit: np.ndarray) -> np.ndarray:
    """Per-frame results as a structured array (``time`` first), units in :data:`CSV_UNITS`."""
    columns = {
        "time": rec.t,
        "frame": rec.track.frame,
        "valid": rec.track.valid,
        "in_fit": rec.free_motion,
        "x1": rec.x1,
        "y1": rec.y1,
        "x2": rec.x2,
        "y2": rec.y2,
        "phi1": rec.phi1,
        "phi2": rec.phi2,
        "omega1_cd": rec.omega1_cd,
        "omega2_cd": rec.omega2_cd,
        "omega1": rec.omega1,
        "omega2": rec.omega2,
        "E_cd": rec.energy_cd,
        "E": rec.energy,
        "E_kin": rec.e_kin,
        "E_pot": rec.e_pot,
        "sigma_E_seed": rec.sigma_energy_seed,
        "sigma_E_noise": rec.sigma_energy,
        "sigma_E_fit": sigma_fit,
    }
    arrays = [np.asarray(v, dtype=float) for v in columns.values()]
    return np.rec.fromarrays(arrays, names=list(columns)).view(np.ndarray)


def _geometry_summary(rec: Reconstruction) -> dict[str, Any]:
    g = rec.geometry
    p = g.pivot
    return {
        "pivot_origin_m": {"x": p.xc, "y": p.yc, "sigma_x": p.sigma_xc, "sigma_y": p.sigma_yc},
        "l1_m": g.l1,
        "l1_stderr_m": g.sigma_l1,
        "circle_rms_residual_m": p.rms_residual,
        "l2_m": g.l2,
        "l2_stderr_m": g.sigma_l2,
        "l2_std_m": g.l2_std,
        "position_noise_m": {"upper_bob": rec.sigma_pos1, "lower_bob": rec.sigma_pos2},
        "r1_drift_m_per_s": _r1_drift(rec),
    }


def _r1_drift(rec: Reconstruction) -> float:
    """Slope [m/s] of a straight line through the upper bob's distance from the pivot over time."""
    v = rec.track.valid
    slope, _ = np.polyfit(rec.t[v], np.hypot(rec.x1[v], rec.y1[v]), 1)
    return float(slope)


def _filter_summary() -> dict[str, Any]:
    """Noise gain sqrt(sum c_k^2) dt and harmonic gains of both derivative stencils."""
    out = {}
    stencils = {
        "central_difference": central_difference_coefficients(),
        "savgol": savgol_derivative_coefficients(),
    }
    for name, c in stencils.items():
        gains = derivative_gain(c, GAIN_CHECK_OMEGA)
        out[name] = {
            "frames": len(c),
            "noise_gain": math.sqrt(float(np.sum(c * c))) / FPS,
            "gain": {f"{w:g}_rad_s": float(g) for w, g in zip(GAIN_CHECK_OMEGA, gains)},
        }
    return out


def _exp_summary(fit: FitResult, factor: float) -> dict[str, Any]:
    """a, b with fit standard errors and the ones inflated for correlated residuals (x sqrt(factor))."""
    sa, sb = fit.error("a"), fit.error("b")
    return {
        "a_J": fit.value("a"),
        "a_J_stderr": sa,
        "b_per_s": fit.value("b"),
        "b_per_s_stderr": sb,
        "autocorrelation_factor": factor,
        "a_J_stderr_autocorr": sa * math.sqrt(factor),
        "b_per_s_stderr_autocorr": sb * math.sqrt(factor),
        "chi2_red": fit.chi2_red if fit.absolute_sigma else None,
        "n_points": fit.n,
    }


def _fit_exponential(
    t: np.ndarray, e: np.ndarray, sigma: np.ndarray | None, absolute: bool
) -> dict[str, Any]:
    fit = fit_model("exponential", t, e, sigma, absolute_sigma=absolute)
    resid = (e - MODELS["exponential"].func(t, *fit.params)) / (1.0 if sigma is None else sigma)
    return _exp_summary(fit, effective_sample_factor(resid, round(AUTOCORRELATION_LAG_S * FPS)))


def _weighting_variants(rec: Reconstruction, m: np.ndarray) -> dict[str, Any]:
    """The exponential fit with other energies and weights: how much the choice moves a and b."""
    t = rec.t[m]
    v = rec.energy_valid
    return {
        "equal_weights": _fit_exponential(t, rec.energy[m], None, False),
        "cd_equal_weights": _fit_exponential(t, rec.energy_cd[m], None, False),
        "position_noise_relative": _fit_exponential(t, rec.energy[m], rec.sigma_energy[m], False),
        "seed_eq25": _fit_exponential(t, rec.energy[m], rec.sigma_energy_seed[m], True),
        "seed_recipe_cd_eq25": _fit_exponential(t, rec.energy_cd[m], rec.sigma_energy_seed[m], True),
        "equal_weights_with_release": _fit_exponential(rec.t[v], rec.energy[v], None, False),
    }


def _scatter_summary(rec: Reconstruction, m: np.ndarray, fit: FitResult) -> dict[str, Any]:
    """Where the energy scatters: residuals of the exponential fit in the slowest and fastest quarter."""
    resid = rec.energy[m] - MODELS["exponential"].func(rec.t[m], *fit.params)
    p = rec.momentum[m]
    slow, fast = p <= np.quantile(p, 0.25), p >= np.quantile(p, 0.75)
    r2 = np.hypot(rec.x2 - rec.x1, rec.y2 - rec.y1)
    return {
        "max_abs_residual_J": float(np.max(np.abs(resid))),
        "rms_residual_slowest_quarter_J": float(np.sqrt(np.mean(resid[slow] ** 2))),
        "rms_residual_fastest_quarter_J": float(np.sqrt(np.mean(resid[fast] ** 2))),
        "seed_weight_share_of_slowest_tenth": _weight_share(
            rec.sigma_energy_seed[m], p <= np.quantile(p, 0.1)
        ),
        "max_bob_distance_change_in_two_frames_m": float(np.max(np.abs(r2[2:] - r2[:-2]))),
    }


def _weight_share(sigma: np.ndarray, subset: np.ndarray) -> float:
    """Fraction of the total weight sum(1/sigma^2) that the frames in ``subset`` carry."""
    w = 1.0 / sigma**2
    return float(np.sum(w[subset]) / np.sum(w))


def _seed_comparison(main: dict[str, Any]) -> dict[str, Any]:
    s_b_seed = abs(SEED_FIT["b_per_s"]) * SEED_FIT["b_rel_err"]
    s_a_seed = SEED_FIT["a_J"] * SEED_FIT["a_rel_err"]
    db = main["b_per_s"] - SEED_FIT["b_per_s"]
    da = main["a_J"] - SEED_FIT["a_J"]
    return {
        **SEED_FIT,
        "b_difference_per_s": db,
        "b_difference_in_seed_sigma": db / s_b_seed,
        "b_difference_in_combined_sigma": db / math.hypot(s_b_seed, main["b_per_s_stderr_autocorr"]),
        "a_difference_J": da,
        "a_difference_in_combined_sigma": da / math.hypot(s_a_seed, main["a_J_stderr_autocorr"]),
    }


def _plots(
    rec: Reconstruction, m: np.ndarray, sigma: np.ndarray, fits: list[FitResult], out_dir: Path
) -> None:
    t_curve = np.linspace(0.0, float(rec.t[-1]), 400)
    curves = {}
    for f in fits:
        curves[f"{f.model} (dAIC {f.aic - fits[0].aic:.1f})"] = MODELS[f.model].func(t_curve, *f.params)
    exp_label = next(k for k in curves if k.startswith("exponential"))
    curves["seed: 0.813 J exp(-0.024 t)"] = SEED_FIT["a_J"] * np.exp(SEED_FIT["b_per_s"] * t_curve)
    full_sigma = np.full(len(rec.t), np.nan)
    full_sigma[m] = sigma
    path = out_dir / "energy_decay.png"
    plots.plot_energy_decay(
        rec.t, rec.energy, full_sigma, curves, t_curve, path, used=m, residual_curve=exp_label
    )
    g = rec.geometry
    plots.plot_circle_fit(
        rec.x1, rec.y1, rec.x2, rec.y2, rec.t, g.l1, g.l2, out_dir / "circle_fit.png", valid=rec.track.valid
    )


def run(runner: Any, out_dir: Path, *, quick: bool = False) -> dict:
    """Analyse the seed's track and write CSV, plots, summary and report (``runner``, ``quick`` unused)."""
    out_dir = Path(out_dir)
    rec = reconstruct(load_track())
    m = rec.free_motion
    t, e = rec.t[m], rec.energy[m]
    errors = calibrate_error_model(t, e, rec.sigma_energy[m], rec.momentum[m])
    fits = fit_all(t, e, errors.sigma, absolute_sigma=True)
    main = _fit_exponential(t, e, errors.sigma, True)
    sigma_fit = np.full(len(rec.t), np.nan)
    sigma_fit[m] = errors.sigma
    exp_fit = next(f for f in fits if f.model == "exponential")
    summary: dict[str, Any] = {
        "scenario": "energy_decay",
        "source": "seed Table 1 (data/seed_table1.csv)",
        "n_frames": len(rec.t),
        "n_flagged": int(np.count_nonzero(~rec.track.valid)),
        "release_frame": rec.release_frame,
        "release_time_s": float(rec.t[rec.release_frame]),
        "n_fit": int(np.count_nonzero(m)),
        "masses_kg": {"m1": rec.params.m1, "m2": rec.params.m2},
        **_geometry_summary(rec),
        "derivative_filters": _filter_summary(),
        "error_model": {
            "floor_J": errors.floor,
            "dv_m_per_s": errors.dv,
            "seed_dv_m_per_s": SEED_VELOCITY_ERROR,
            "median_sigma_noise_J": float(np.median(rec.sigma_energy[m])),
            "median_sigma_fit_J": float(np.median(errors.sigma)),
            "chi2_red_with_noise_only": fit_model("exponential", t, e, rec.sigma_energy[m]).chi2_red,
        },
        "scatter": _scatter_summary(rec, m, exp_fit),
        **main,
        "model_comparison": comparison_table(fits),
        "weighting_variants": _weighting_variants(rec, m),
        "seed": _seed_comparison(main),
    }
    write_results_csv(out_dir / "track.csv", _track_table(rec, sigma_fit), CSV_UNITS)
    _plots(rec, m, errors.sigma, fits, out_dir)
    write_json(out_dir / "summary.json", summary)
    write_text(out_dir / "report.md", report_text(summary))
    return summary


# --- report -------------------------------------------------------------------------------------


def _fmt(value: float, err: float, scale: float = 1.0, digits: int = 4) -> str:
    return f"{value * scale:.{digits}f} +- {err * scale:.{digits}f}"


def _comparison_rows(summary: dict[str, Any]) -> str:
    lines = ["| model | parameters | chi2_red | dAIC | dBIC | Akaike weight |", "|---|---|---|---|---|---|"]
    for row in summary["model_comparison"]:
        units = row["units"]
        params = ", ".join(
            f"{n} = {v:.4g} +- {row['stderr'][n]:.2g} {units[n] if units[n] != '1' else ''}".rstrip()
            for n, v in row["params"].items()
        )
        lines.append(
            f"| {row['model']} | {params} | {row['chi2_red']:.3f} | {row['delta_aic']:.1f} | "
            f"{row['delta_bic']:.1f} | {row['akaike_weight']:.3f} |"
        )
    return "\n".join(lines)


def _variant_rows(summary: dict[str, Any]) -> str:
    labels = {
        "equal_weights": "Savitzky-Golay energy, equal weights",
        "cd_equal_weights": "central-difference energy, equal weights",
        "position_noise_relative": "Savitzky-Golay energy, propagated noise as relative weights",
        "seed_eq25": "Savitzky-Golay energy, seed's eq. 25",
        "seed_recipe_cd_eq25": "central-difference energy, seed's eq. 25 (the seed's recipe)",
        "equal_weights_with_release": "Savitzky-Golay energy, equal weights, hand release included",
    }
    lines = ["| energy, weights | a [J] | b [1/s] | chi2_red | n |", "|---|---|---|---|---|"]
    rows = {"Savitzky-Golay energy, calibrated errors (main result)": summary}
    rows.update({labels[k]: v for k, v in summary["weighting_variants"].items()})
    for label, v in rows.items():
        chi2 = "-" if v["chi2_red"] is None else f"{v['chi2_red']:.2f}"
        a = _fmt(v["a_J"], v["a_J_stderr_autocorr"])
        b = _fmt(v["b_per_s"], v["b_per_s_stderr_autocorr"], digits=5)
        lines.append(f"| {label} | {a} | {b} | {chi2} | {v['n_points']} |")
    return "\n".join(lines)


def _geometry_section(s: dict[str, Any]) -> str:
    pivot = s["pivot_origin_m"]
    noise = s["position_noise_m"]
    return f"""## Geometry

- Frames: {s["n_frames"]} at {FPS} fps; flagged as tracker jumps: {s["n_flagged"]}; hand release over at
  frame {s["release_frame"]} (t = {s["release_time_s"]:.3f} s); frames in the fits: {s["n_fit"]}.
- Pivot (circle fit of the upper bob, in the table's coordinates):
  x = {_fmt(pivot["x"], pivot["sigma_x"], 1e3, 2)} mm, y = {_fmt(pivot["y"], pivot["sigma_y"], 1e3, 2)} mm;
  rms distance of the upper bob from the circle {1e3 * s["circle_rms_residual_m"]:.2f} mm.
- l1 = {_fmt(s["l1_m"], s["l1_stderr_m"], 1e3, 2)} mm (circle radius);
  l2 = {_fmt(s["l2_m"], s["l2_stderr_m"], 1e3, 2)} mm (mean bob distance, std {1e3 * s["l2_std_m"]:.1f} mm).
  Both errors treat the frames as independent; the radii wander slowly, so they are lower bounds: the
  upper bob's distance from the pivot drifts by {1e3 * s["r1_drift_m_per_s"] * s["n_frames"] / FPS:+.1f} mm
  over the run (camera or mount moving). The energy uses the angles, which a radial shift leaves unchanged.
- Position noise (frame-to-frame jitter of the rod lengths): upper bob {1e3 * noise["upper_bob"]:.2f} mm,
  lower bob {1e3 * noise["lower_bob"]:.2f} mm.
"""


def _energy_section(s: dict[str, Any]) -> str:
    em, sc = s["error_model"], s["scatter"]
    sg = s["derivative_filters"]["savgol"]["gain"]
    cd = s["derivative_filters"]["central_difference"]["gain"]
    return f"""## Energy and its errors

The energy is `double_pendulum.model.energy.total_energy` for point masses m1 = {s["masses_kg"]["m1"]} kg,
m2 = {s["masses_kg"]["m2"]} kg on the measured rods (potential zero with both bobs at rest below the
fitted pivot). The angular velocities come from a Savitzky-Golay derivative ({SG_WINDOW} frames, order
{SG_POLYORDER}): on a harmonic motion at 10 / 20 / 25 rad/s it returns {sg["10_rad_s"]:.3f} /
{sg["20_rad_s"]:.3f} / {sg["25_rad_s"]:.3f} of the true rate, the seed's central differences
{cd["10_rad_s"]:.3f} / {cd["20_rad_s"]:.3f} / {cd["25_rad_s"]:.3f} (kinetic energy: the square).

The propagated position noise gives energy errors of only {1e3 * em["median_sigma_noise_J"]:.1f} mJ
(median); the exponential fit with them has chi2_red = {em["chi2_red_with_noise_only"]:.0f}, so the
scatter of the energy is not white position noise. It grows with speed: the rms residual is
{1e3 * sc["rms_residual_slowest_quarter_J"]:.0f} mJ in the slowest quarter of the frames and
{1e3 * sc["rms_residual_fastest_quarter_J"]:.0f} mJ in the fastest, single frames are off by up to
{sc["max_abs_residual_J"]:.2f} J, and the distance between the bobs changes by up to
{1e3 * sc["max_bob_distance_change_in_two_frames_m"]:.0f} mm within two frames (a rigid rod would not).
The fits therefore use errors calibrated on the data by maximum likelihood, alternating with the
exponential fit: sigma^2 = sigma_noise^2 + s0^2 + dv^2 (m1^2 v1^2 + m2^2 v2^2) with
s0 = {1e3 * em["floor_J"]:.1f} mJ and dv = {em["dv_m_per_s"]:.3f} m/s (the seed's eq. 25 has
dv = {em["seed_dv_m_per_s"]} m/s and no floor).
"""


def _fit_section(s: dict[str, Any]) -> str:
    seed = s["seed"]
    return f"""## Exponential fit E = a exp(b t)

a = {_fmt(s["a_J"], s["a_J_stderr"])} J, b = {_fmt(s["b_per_s"], s["b_per_s_stderr"], digits=5)} 1/s
(standard errors of the fit). The residuals are correlated over a swing: the variance inflation
factor 1 + 2 sum(rho_k) over {AUTOCORRELATION_LAG_S} s of lags is {s["autocorrelation_factor"]:.2f},
which makes the errors a +- {s["a_J_stderr_autocorr"]:.4f} J, b +- {s["b_per_s_stderr_autocorr"]:.5f} 1/s.

The seed: a = {seed["a_J"]} J +- {100 * seed["a_rel_err"]:.2f} %, b = {seed["b_per_s"]} 1/s
+- {100 * seed["b_rel_err"]:.2f} %. Difference in b: {seed["b_difference_per_s"]:+.5f} 1/s, that is
{seed["b_difference_in_seed_sigma"]:+.2f} times the seed's error and
{seed["b_difference_in_combined_sigma"]:+.2f} times the combined error; in a: {seed["a_difference_J"]:+.4f} J,
{seed["a_difference_in_combined_sigma"]:+.2f} times the combined error.

The same fit with other energies and weights (errors inflated for the correlation):

{_variant_rows(s)}
"""


def _comparison_section(s: dict[str, Any]) -> str:
    rows = {r["model"]: r for r in s["model_comparison"]}
    power = rows["power"]
    p, sp = power["params"]["p"], power["stderr"]["p"]
    sp_corr = sp * math.sqrt(s["autocorrelation_factor"])
    return f"""## Model comparison (same frames, calibrated errors)

{_comparison_rows(s)}

Best by AIC: {s["model_comparison"][0]["model"]}. The criteria count every frame as independent; with
the correlation factor the differences are worth about 1/{s["autocorrelation_factor"]:.1f} of the
printed values. The free exponent of dE/dt = -k E^p is p = {p:.2f} +- {sp:.2f} (+- {sp_corr:.2f} with
the correlation): Coulomb friction has p = 1/2 ({(p - 0.5) / sp_corr:+.1f} sigma), losses proportional
to the energy p = 1 ({(p - 1.0) / sp_corr:+.1f} sigma), quadratic drag (E ~ 1/(1 + t/tau)^2, the seed's
alternative "inverse square of time") p = 3/2 ({(p - 1.5) / sp_corr:+.1f} sigma, dAIC =
{rows["quadratic_drag"]["delta_aic"]:.0f}).
"""


def _discussion_section(s: dict[str, Any]) -> str:
    m1, m2 = s["masses_kg"]["m1"], s["masses_kg"]["m2"]
    cd20 = s["derivative_filters"]["central_difference"]["gain"]["20_rad_s"]
    sg20 = s["derivative_filters"]["savgol"]["gain"]["20_rad_s"]
    var = s["weighting_variants"]
    return f"""## Why a and b differ from the seed's

- **Origin and rod lengths.** The seed put the pivot at the grid point of least variance of the
  distance; here it is a geometric circle fit. The potential energy is measured from the pivot, and
  1 mm of height is (m1 + m2) g * 1 mm = {1e3 * (m1 + m2) * 9.81e-3:.1f} mJ; the seed does not say where
  its potential is zero.
- **Velocity smoothing at 30 fps.** As the seed explains (4.2.2, fig. 8), the frames before and after
  the lowest point cut the corner and flatten the speed peaks: central differences return
  {100 * cd20:.1f} % of the rate of a 20 rad/s motion ({100 * cd20**2:.0f} % of its kinetic energy), the
  Savitzky-Golay derivative {100 * sg20:.1f} %. Larger kinetic energies mean a larger a: with equal
  weights a = {var["cd_equal_weights"]["a_J"]:.4f} J from central differences,
  {var["equal_weights"]["a_J"]:.4f} J from the Savitzky-Golay derivative.
- **Energy model.** Point masses on massless rods: the seed's pendulum moves
  {SEED_TOTAL_MASS_KG} kg in total (4.2.3) against m1 + m2 = {m1 + m2:.3f} kg, so about
  {SEED_TOTAL_MASS_KG - m1 - m2:.1f} kg of acrylic rods are missing from the energy and make the
  computed energy depend on the configuration: one source of the floor s0.
- **Weights.** The seed weighted with eq. 25, whose errors nearly vanish at the turning points although
  the energy scatters there too: the slowest tenth of the frames carries
  {100 * s["scatter"]["seed_weight_share_of_slowest_tenth"]:.0f} % of the total weight. With eq. 25 weights
  b = {var["seed_eq25"]["b_per_s"]:.4f} 1/s, with equal weights {var["equal_weights"]["b_per_s"]:.4f} 1/s:
  the weights move b by more than its statistical error, a sign that the exponential is only an
  approximation to the decay.
- **Frames.** The energy rises during the first frames while the hand lets go; those frames are left
  out. Table 1 covers {s["n_frames"] / FPS:.1f} s (the seed speaks of a 30 s measurement).
- **Rounding.** The seed prints b = -0.024 with two digits: every value from -0.0245 to -0.0235 is
  printed so, a range as wide as the seed's own error of b.
"""


def report_text(summary: dict[str, Any]) -> str:
    """The Markdown report: figures from ``summary`` and the discussion of the differences to the seed."""
    sections = (_geometry_section, _energy_section, _fit_section, _comparison_section, _discussion_section)
    body = "\n".join(section(summary) for section in sections)
    return "# Energy decay of the seed pendulum (Table 1)\n\n" + body
