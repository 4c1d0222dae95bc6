r"""Figures of the measured energy decay for the ``energy_decay`` scenario's summary and track table.

The exponential fit :math:`E = a\,e^{b t}` [J] of the reconstructed energy
(:func:`double_pendulum.analysis.track.measurement.reconstruct`) with its errors, the same fit with other
energies and weights, where the energy scatters, the geometry of the track and the derivative filters,
and the comparison with the seed's fit :data:`~double_pendulum.analysis.decay.fit.SEED_FIT`.

Fit errors are inflated for correlated residuals: :math:`\sigma_{corr} = \sigma \sqrt{F}` with the
record's variance inflation factor :math:`F = 1 + 2 \sum_k \rho_k` over :data:`AUTOCORRELATION_LAG_S` of lags
of the residuals about the free-exponent decay law
(:func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`, the same F for every fit of a record).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..track.measurement import (
    FPS,
    SEED_VELOCITY_ERROR,
    Reconstruction,
    central_difference_coefficients,
    derivative_gain,
    savgol_derivative_coefficients,
)
from .fit import (
    MODELS,
    SEED_FIT,
    ErrorModel,
    FitResult,
    fit_model,
    record_correlation_factor,
)

GAIN_CHECK_OMEGA = (10.0, 20.0, 25.0)
"""Angular frequencies [rad/s] at which the derivative filters' gains are reported."""
CURVE_POINTS = 400
"""Number of times at which the fitted decay curves are drawn."""

TRACK_CSV_UNITS = {
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
"""Units of the columns of :func:`track_table` (``time`` [s] is added by the CSV writer)."""


def on_all_frames(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``values`` given on the frames of ``mask`` spread over all frames, NaN elsewhere."""
    full = np.full(len(mask), np.nan)
    full[mask] = values
    return full


def track_table(rec: Reconstruction, sigma_fit: np.ndarray) -> np.ndarray:
    """Per-frame results as a structured array (``time`` first), units in :data:`TRACK_CSV_UNITS`.

    ``sigma_fit``: the calibrated energy error [J] per frame (NaN outside the fit).
    """
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


# --- geometry and filters -----------------------------------------------------------------------


def r1_drift(rec: Reconstruction) -> float:
    """Slope [m/s] of a straight line through the upper bob's distance from the pivot over time."""
    v = rec.track.valid
    slope, _ = np.polyfit(rec.t[v], np.hypot(rec.x1[v], rec.y1[v]), 1)
    return float(slope)


def geometry_summary(rec: Reconstruction) -> dict[str, Any]:
    """Pivot [m], rod lengths l1, l2 [m] with errors, circle residual, position noise [m], r1 drift [m/s]."""
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
        "r1_drift_m_per_s": r1_drift(rec),
    }


def filter_summary(omegas: Sequence[float] = GAIN_CHECK_OMEGA, dt: float = 1.0 / FPS) -> dict[str, Any]:
    """Both derivative stencils c_k [1/s] at the frame interval ``dt`` [s] (default the seed's camera): length,
    noise gain sqrt(sum c_k^2) dt [1] and harmonic gains.

    The noise gain is the standard deviation of the derivative of white noise of unit standard
    deviation, times the frame interval dt; the gain at omega [rad/s] is the stencil's derivative of
    sin(omega t) divided by the true one (1 for a perfect derivative).
    """
    out = {}
    stencils = {
        "central_difference": central_difference_coefficients(dt),
        "savgol": savgol_derivative_coefficients(dt=dt),
    }
    for name, c in stencils.items():
        gains = derivative_gain(c, omegas, dt)
        out[name] = {
            "frames": len(c),
            "noise_gain": math.sqrt(float(np.sum(c * c))) * dt,
            "gain": {f"{w:g}_rad_s": float(g) for w, g in zip(omegas, gains)},
        }
    return out


# --- the exponential fit ------------------------------------------------------------------------


def exponential_summary(fit: FitResult, factor: float) -> dict[str, Any]:
    """a [J], b [1/s] with fit standard errors and the ones inflated for correlated residuals (x sqrt(factor))."""
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


def fit_exponential(t: np.ndarray, e: np.ndarray, sigma: np.ndarray | None, absolute: bool) -> dict[str, Any]:
    """Fit E = a exp(b t) to energies ``e`` [J] at times ``t`` [s]: :func:`exponential_summary`.

    ``sigma`` [J]: errors (None: equal weights), ``absolute``: take them as true errors. The
    autocorrelation factor is the record's (:func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`,
    with the same errors).
    """
    fit = fit_model("exponential", t, e, sigma, absolute_sigma=absolute)
    return exponential_summary(fit, record_correlation_factor(t, e, sigma))


def weighting_variants(rec: Reconstruction, m: np.ndarray) -> dict[str, Any]:
    """The exponential fit on the frames ``m`` with other energies and weights: how much the choice moves a, b."""
    t = rec.t[m]
    v = rec.energy_valid
    return {
        "equal_weights": fit_exponential(t, rec.energy[m], None, False),
        "cd_equal_weights": fit_exponential(t, rec.energy_cd[m], None, False),
        "position_noise_relative": fit_exponential(t, rec.energy[m], rec.sigma_energy[m], False),
        "seed_eq25": fit_exponential(t, rec.energy[m], rec.sigma_energy_seed[m], True),
        "seed_recipe_cd_eq25": fit_exponential(t, rec.energy_cd[m], rec.sigma_energy_seed[m], True),
        "equal_weights_with_release": fit_exponential(rec.t[v], rec.energy[v], None, False),
    }


def error_model_summary(rec: Reconstruction, m: np.ndarray, errors: ErrorModel) -> dict[str, Any]:
    """The calibrated errors sigma^2 = sigma_noise^2 + s0^2 + dv^2 p^2 against the noise alone.

    s0 [J], dv [m/s] (the seed's dv for comparison), median errors [J] on the frames ``m``, and the
    reduced chi-square of the exponential fit weighted with the propagated position noise only.
    """
    t, e = rec.t[m], rec.energy[m]
    return {
        "floor_J": errors.floor,
        "dv_m_per_s": errors.dv,
        "seed_dv_m_per_s": SEED_VELOCITY_ERROR,
        "median_sigma_noise_J": float(np.median(rec.sigma_energy[m])),
        "median_sigma_fit_J": float(np.median(errors.sigma)),
        "chi2_red_with_noise_only": fit_model("exponential", t, e, rec.sigma_energy[m]).chi2_red,
    }


# --- scatter and the seed -----------------------------------------------------------------------


def weight_share(sigma: np.ndarray, subset: np.ndarray) -> float:
    """Fraction of the total weight sum(1/sigma^2) that the frames in ``subset`` carry."""
    w = 1.0 / sigma**2
    return float(np.sum(w[subset]) / np.sum(w))


def scatter_summary(rec: Reconstruction, m: np.ndarray, fit: FitResult) -> dict[str, Any]:
    """Where the energy scatters: residuals [J] of the exponential ``fit`` in the slowest and fastest quarter.

    Speed is the momentum sqrt(m1^2 v1^2 + m2^2 v2^2) [kg m/s]; also the weight share of the slowest
    tenth under the seed's eq. 25 and the largest change [m] of the bob distance within two frames.
    """
    resid = rec.energy[m] - MODELS["exponential"].func(rec.t[m], *fit.params)
    p = rec.momentum[m]
    slow, fast = p <= np.quantile(p, 0.25), p >= np.quantile(p, 0.75)
    r2 = np.hypot(rec.x2 - rec.x1, rec.y2 - rec.y1)
    return {
        "max_abs_residual_J": float(np.max(np.abs(resid))),
        "rms_residual_slowest_quarter_J": float(np.sqrt(np.mean(resid[slow] ** 2))),
        "rms_residual_fastest_quarter_J": float(np.sqrt(np.mean(resid[fast] ** 2))),
        "seed_weight_share_of_slowest_tenth": weight_share(rec.sigma_energy_seed[m], p <= np.quantile(p, 0.1)),
        "max_bob_distance_change_in_two_frames_m": float(np.max(np.abs(r2[2:] - r2[:-2]))),
    }


def seed_comparison(main: dict[str, Any]) -> dict[str, Any]:
    """The seed's fit and the differences of ``main`` (:func:`exponential_summary`) from it.

    Differences in a [J], b [1/s] and in units of the seed's error and of the combined error
    hypot(sigma_seed, sigma_corr) (the seed's errors are its relative errors times |a|, |b|).
    """
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


def decay_curves(fits: Sequence[FitResult], t_end: float,
                 seed: bool = True) -> tuple[np.ndarray, dict[str, np.ndarray], str]:  # fmt: skip
    """Fitted decay curves E(t) [J] on 0..``t_end`` [s] for the plot, labelled with their dAIC, and the seed's
    (``seed``: the seed's record; not on a user's).

    ``fits`` best first (as :func:`~double_pendulum.analysis.decay.fit.fit_all`). Returns the times,
    the curves by label and the label of the best model by AIC (the curve the plot's residuals refer to).
    """
    t_curve = np.linspace(0.0, t_end, CURVE_POINTS)
    curves = {}
    for f in fits:
        curves[f"{f.model} (dAIC {f.aic - fits[0].aic:.1f})"] = MODELS[f.model].func(t_curve, *f.params)
    best_label = next(iter(curves))
    if seed:
        curves["seed: 0.813 J exp(-0.024 t)"] = SEED_FIT["a_J"] * np.exp(SEED_FIT["b_per_s"] * t_curve)
    return t_curve, curves, best_label
