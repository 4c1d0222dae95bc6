r"""Scenario ``measured_vs_sim``: how long does the FMU predict the measured track?

The seed started its simulation from the state estimated at t0 = 0.8 s and found its bob
coordinates agreeing with the camera track until about 2 s (its figs. 11-14). This scenario does
the same through the FMU and goes further:

- **seed start**: angles and rates of the frame nearest t0 from the measurement reconstruction
  (:func:`double_pendulum.analysis.measurement.reconstruct`: angles from the positions, rates from the
  Savitzky-Golay derivative), run frictionless as in the seed and with the identified losses;
- **least-squares start**: (phi1, phi2, omega1, omega2) at t0 fitted to the positions of the first
  :data:`FIT_FRAMES` frames (:func:`double_pendulum.analysis.start_state.fit_start_state`), run with the
  identified losses: air drag and bearing friction at the defaults, the suspension's c identified
  from the measured energy decay at the default k and M_s
  (:func:`double_pendulum.analysis.suspension_identification.identify_suspension`).

The FMU's positions are relative to the pivot's rest position; the track's are relative to its own
origin. Both are compared relative to the pivot fitted by the measurement (circle fit of the upper
bob): the plots show the FMU's positions shifted by that pivot, in the track's coordinates.

Prediction horizon: the time after t0 at which the position error |r_sim - r_track| [m] first
exceeds 1 cm and 5 cm, for the lower bob and for both bobs (the larger of the two errors). Two
floors limit it: the track itself (the distance between the bobs varies by about +-1 cm where a
rigid rod allows none, so 1 cm is at the data's own resolution) and chaos (the start state's
uncertainty, propagated by an ensemble of FMU runs drawn from the fit's covariance).

Outputs in ``results/measured_vs_sim/``: one CSV per run (FMU outputs from t0), ``errors.csv``
(track and position errors per frame), ``coordinates.png`` (x1, y1, x2, y2 measured and simulated,
the seed's figs. 11-14), ``prediction_error.png`` (errors over time with the 1 cm / 5 cm lines),
``summary.json`` and ``report.md``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from double_pendulum import plots
from double_pendulum.analysis.measurement import FRAME_INTERVAL, Reconstruction, load_track, reconstruct
from double_pendulum.analysis.prediction_report import report_text
from double_pendulum.analysis.start_state import STATE_NAMES
from double_pendulum.analysis.suspension_identification import START_FIT_FRAMES, identify_suspension
from double_pendulum.analysis.track_comparison import (
    THRESHOLDS_M,
    Prediction,
    chaos_horizons,
    chaos_spread,
    error_curves,
    errors_table,
    errors_units,
    least_squares_start,
    measured_coordinates,
    model_summary,
    model_values,
    nearest_frame,
    null_means,
    predict,
    reconstructed_state,
    rod_floor_summary,
    rod_length_floor,
    run_title,
    simulated_coordinates,
    start_fit_summary,
    window_sensitivity,
)
from double_pendulum.fmu.runner import FmuRunner
from double_pendulum.results_io import write_json, write_results_csv, write_text

DESCRIPTION = "FMU prediction of the measured track from t0 = 0.8 s: the seed's start and a least-squares start"

SEED_T0 = 0.8
"""The seed's start time [s]."""
FIT_FRAMES = START_FIT_FRAMES
"""Frames after t0 the least-squares start is fitted to (1/3 s)."""
PREDICTION_S = 6.0
"""Length [s] of each prediction (quick: :data:`QUICK_PREDICTION_S`)."""
QUICK_PREDICTION_S = 2.0
WINDOW_SENSITIVITY = (6, 15, 30)
"""Other fit windows [frames] tried for the least-squares start (full run only)."""
ENSEMBLE_SIZE = 16
"""FMU runs drawn from the least-squares start's covariance (quick: :data:`QUICK_ENSEMBLE_SIZE`)."""
QUICK_ENSEMBLE_SIZE = 4


def _plots(
    out_dir: Path,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
    predictions: list[Prediction],
    spread: tuple[np.ndarray, np.ndarray],
) -> None:
    """``coordinates.png`` (track and runs in the track's coordinates) and ``prediction_error.png``."""
    t, measured = measured_coordinates(rec, i0, n_frames)
    runs = {run_title(p.label): simulated_coordinates(rec, p) for p in predictions}
    starts = {"start time t0 of the predictions": float(rec.t[i0])}
    plots.plot_track_comparison(t, measured, runs, out_dir / "coordinates.png", starts=starts)
    plots.plot_prediction_errors(
        error_curves(predictions, spread),
        list(THRESHOLDS_M),
        out_dir / "prediction_error.png",
        floor=rod_length_floor(rec, i0, n_frames),
    )


def run(runner: FmuRunner, out_dir: Path, *, quick: bool = False) -> dict:
    """Predict the track from t0 = 0.8 s from both starts; write CSVs, plots, summary and report."""
    wall0 = time.perf_counter()
    out_dir = Path(out_dir)
    rec = reconstruct(load_track())
    identified = identify_suspension(runner, rec, quick=quick)
    values = model_values(identified)
    frictionless = {"l1": values["l1"], "l2": values["l2"]}
    i0 = nearest_frame(rec, SEED_T0)
    n_frames = round((QUICK_PREDICTION_S if quick else PREDICTION_S) / FRAME_INTERVAL) + 1
    ensemble_size = QUICK_ENSEMBLE_SIZE if quick else ENSEMBLE_SIZE
    seed_state = reconstructed_state(rec, i0)
    fit = least_squares_start(runner, rec, i0, values, FIT_FRAMES)
    predictions = [
        predict(runner, "seed_start_frictionless", frictionless, seed_state, rec, i0, n_frames),
        predict(runner, "seed_start_identified", values, seed_state, rec, i0, n_frames),
        predict(runner, "lsq_start_identified", values, fit.state, rec, i0, n_frames),
    ]
    spread = chaos_spread(runner, values, fit, predictions[-1], n_frames, ensemble_size)
    summary: dict[str, Any] = {
        "scenario": "measured_vs_sim",
        "quick": quick,
        "t0_s": float(rec.t[i0]),
        "start_frame": i0,
        "prediction_s": (n_frames - 1) * FRAME_INTERVAL,
        "pivot_origin_m": {"x": rec.geometry.pivot.xc, "y": rec.geometry.pivot.yc},
        "model": model_summary(rec, identified.identification, frictionless),
        "starts": {
            "seed_reconstruction": dict(zip(STATE_NAMES, seed_state.tolist())),
            "least_squares": start_fit_summary(fit, seed_state),
        },
        "horizons_s": {p.label: p.horizons() for p in predictions},
        "chaos_horizons_s": chaos_horizons(spread),
        "ensemble_size": ensemble_size,
        "track_rod_length_floor": rod_floor_summary(rec, i0, n_frames),
        "rms_error_first_second_m": {p.label: {"lower_bob": p.rms_lower_bob_error(1.0)} for p in predictions},
        "null_means": null_means((n_frames - 1) * FRAME_INTERVAL),
    }
    if not quick:
        summary["fit_window_sensitivity"] = window_sensitivity(runner, rec, i0, values, n_frames, WINDOW_SENSITIVITY)
    for p in predictions:
        write_results_csv(out_dir / f"{p.label}.csv", p.result, runner.units)
    write_results_csv(out_dir / "errors.csv", errors_table(rec, i0, n_frames, predictions), errors_units(predictions))
    _plots(out_dir, rec, i0, n_frames, predictions, spread)
    summary["wall_time_s"] = time.perf_counter() - wall0
    write_json(out_dir / "summary.json", summary)
    write_text(out_dir / "report.md", report_text(summary))
    return summary
