"""Scenario ``energy_decay``: the energy loss of the real pendulum from the seed's camera track.

No simulation: the scenario analyses Table 1 (``data/seed_table1.csv``) like the seed's
section 4.2, with the package's own energy function. Outputs in ``results/energy_decay/``:

- ``track.csv``: per frame the positions relative to the fitted pivot, angles, angular
  velocities (central differences and Savitzky-Golay), energies and their uncertainties;
- ``energy_decay.png``: energy with error bars and the fitted decay models (the seed's fig. 7);
- ``circle_fit.png``: the pivot circle fit and the rod-length residuals;
- ``summary.json``: pivot, rod lengths, the exponential fit ``a_J``, ``b_per_s`` with errors, the
  model comparison (AIC/BIC), the same fit with other weights, the seed's numbers, and the error
  budget of a and b (``error_budget``: statistical and systematic rows, quadrature totals ``total_a_J``,
  ``total_b_per_s``; :mod:`double_pendulum.analysis.decay.error_budget`), b as it is
  (``error_budget/b_statement``: the statistical error from an AR(1) noise model and a block bootstrap,
  ``error_budget/noise_model``; the range over named variants apart; the halves in sigma) and the
  non-stationarity study (``error_budget/stationarity``: calibration drift, the energy's biases, b in windows
  against the energy; :mod:`double_pendulum.analysis.decay.stationarity`);
- ``summary.json``'s ``tilt``: the record's one geometry (the camera's tilt against gravity fitted to the energy,
  pivot, l1, l2 and their covariance, :mod:`double_pendulum.analysis.track.tilt`; every figure above is on the track
  turned back by it) and, for the tilted and the untilted track side by side, b, the halves, the decay models
  re-fitted under AR(1) noise and the free exponent p (:mod:`double_pendulum.analysis.decay.shape`);
- ``report.md``: the figures and why they differ from the seed's a = 0.813 J, b = -0.024 1/s.

With a user's own record (``double-pendulum run energy_decay --track FILE.csv --pendulum FILE.toml``,
:mod:`double_pendulum.analysis.track.user_track`) the same analysis runs on it: its summary names the record
(``record``), holds no seed numbers, and its report is
:func:`~double_pendulum.analysis.decay.own_report.own_report_text`.

The runner argument of :func:`run` is not used, nor is ``quick`` (the analysis takes about a second).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis.decay.error_budget import error_budget
from double_pendulum.analysis.decay.fit import (
    SEED_FIT,
    FitResult,
    calibrate_error_model,
    comparison_table,
    fit_all,
    record_correlation_factor,
)
from double_pendulum.analysis.decay.own_report import own_report_text
from double_pendulum.analysis.decay.report import report_text
from double_pendulum.analysis.decay.shape import tilt_effect
from double_pendulum.analysis.decay.summary import (
    TRACK_CSV_UNITS,
    decay_curves,
    error_model_summary,
    filter_summary,
    fit_exponential,
    geometry_summary,
    on_all_frames,
    scatter_summary,
    seed_comparison,
    track_table,
    weighting_variants,
)
from double_pendulum.analysis.track.measurement import SEED_TOTAL_MASS_KG, Reconstruction, load_track, reconstruct
from double_pendulum.analysis.track.rods import seed_rods_summary
from double_pendulum.analysis.track.tilt import seed_record_geometry
from double_pendulum.analysis.track.user_track import UserRecord
from double_pendulum.runs.results_io import write_json, write_results_csv, write_text

__all__ = ["DESCRIPTION", "SEED_FIT", "SEED_TOTAL_MASS_KG", "report_text", "run"]
# SEED_FIT and SEED_TOTAL_MASS_KG live in the analysis package; re-exported for older imports.

DESCRIPTION = "energy decay of the real pendulum from the seed's camera track (Table 1), decay models compared"


def _plots(rec: Reconstruction, m: np.ndarray, sigma: np.ndarray, fits: list[FitResult], out_dir: Path,
           seed: bool = True) -> None:  # fmt: skip
    """``energy_decay.png`` (energy with errors ``sigma`` on the fitted frames ``m``, fitted curves; the seed's
    curve on the seed's record) and ``circle_fit.png``."""
    t_curve, curves, best_label = decay_curves(fits, float(rec.t[-1]), seed)
    plots.plot_energy_decay(
        rec.t,
        rec.energy,
        on_all_frames(sigma, m),
        curves,
        t_curve,
        out_dir / "energy_decay.png",
        used=m,
        residual_curve=best_label,
    )
    g = rec.geometry
    plots.plot_circle_fit(
        rec.x1, rec.y1, rec.x2, rec.y2, rec.t, g.l1, g.l2, out_dir / "circle_fit.png", valid=rec.track.valid
    )


def run(runner: Any, out_dir: Path, *, quick: bool = False, record: UserRecord | None = None) -> dict:
    """Analyse the seed's track, or a user's ``record`` (:mod:`double_pendulum.analysis.track.user_track`: no
    comparison with the seed), and write CSV, plots, summary and report (``runner``, ``quick`` unused)."""
    out_dir = Path(out_dir)
    seed = record is None
    geometry = seed_record_geometry() if seed else record.record_geometry
    rec = reconstruct(load_track(), geometry.geometry) if seed else record.reconstruction()
    untilted = reconstruct(load_track(), geometry.untilted) if seed else record.reconstruction(tilt=False)
    m = rec.free_motion
    t, e = rec.t[m], rec.energy[m]
    errors = calibrate_error_model(t, e, rec.sigma_energy[m], rec.momentum[m])
    factor = record_correlation_factor(t, e, errors.sigma)  # the one F of this record, for errors and AIC alike
    fits = fit_all(t, e, errors.sigma, absolute_sigma=True, factor=factor)
    main = fit_exponential(t, e, errors.sigma, True)
    exp_fit = next(f for f in fits if f.model == "exponential")
    summary: dict[str, Any] = {
        "scenario": "energy_decay",
        "source": "seed Table 1 (data/seed_table1.csv)" if seed else f"{record.name}: a user's own record",
        **({} if seed else {"record": record.describe()}),
        "n_frames": len(rec.t),
        "n_flagged": int(np.count_nonzero(~rec.track.valid)),
        "release_frame": rec.release_frame,
        "release_time_s": float(rec.t[rec.release_frame]),
        "n_fit": int(np.count_nonzero(m)),
        "masses_kg": {"m1": rec.params.m1, "m2": rec.params.m2},
        **geometry_summary(rec),
        **({} if seed else {"lengths_fitted_m": record.fitted_lengths()}),
        "derivative_filters": filter_summary(dt=rec.track.dt),
        "error_model": {k: v for k, v in error_model_summary(rec, m, errors).items() if seed or "seed" not in k},
        "scatter": scatter_summary(rec, m, exp_fit),
        **main,
        "model_comparison": comparison_table(fits),
        "weighting_variants": weighting_variants(rec, m),
        **({"seed": seed_comparison(main)} if seed else {}),
        "null_means": {"chi2_red": "not defined for this fit: its errors are relative weights (scaled to the "
                                   "scatter), not absolute errors",
                       "interval_68": "tilt/*/exponent: that end of p's profile interval lies beyond 0 < p < 3",
                       "interval_95": "tilt/*/exponent: that end of p's profile interval lies beyond 0 < p < 3",
                       "stop_time_s": "tilt/*/exponent: p >= 1, the decay law never reaches E = 0"},
        "error_budget": error_budget(rec, errors.sigma, seed=seed),
        "tilt": {**tilt_effect(geometry, rec, untilted),
                 **({"rods_from_energy": seed_rods_summary()} if seed else {})},
    }
    write_results_csv(out_dir / "track.csv", track_table(rec, on_all_frames(errors.sigma, m)), TRACK_CSV_UNITS)
    _plots(rec, m, errors.sigma, fits, out_dir, seed)
    write_json(out_dir / "summary.json", summary)
    write_text(out_dir / "report.md", report_text(summary) if seed else own_report_text(summary))
    return summary
