"""Start-state estimation from bob positions and the measured-vs-simulated scenario."""

from __future__ import annotations

import json

import numpy as np
import pytest
from double_pendulum.scenarios import measured_vs_sim as mv

from double_pendulum.analysis.measurement import load_track, reconstruct
from double_pendulum.analysis.start_state import (
    ANGLE_OUTPUTS,
    FIT_SETTINGS,
    fit_start_state,
    output_matrix,
    simulate_frames,
    state_start_values,
)
from double_pendulum.results_io import read_results_csv

MODEL = {"air_drag": True, "rod_drag": True, "bearing_friction": True, "suspension": True}
TRUE_STATE = np.array([-0.2, 0.7, 2.0, -4.0])  # rad, rad, rad/s, rad/s


def _synthetic_frames(runner, outputs, noise, n_frames=12, t0=0.5, seed=1):
    """FMU-generated frames from TRUE_STATE with white noise of standard deviation ``noise``."""
    run = simulate_frames(runner, {**FIT_SETTINGS, **MODEL, **state_start_values(TRUE_STATE)}, t0, n_frames,
                          outputs=outputs)
    clean = output_matrix(run, outputs)
    return clean + np.random.default_rng(seed).normal(0.0, noise, clean.shape)


@pytest.mark.parametrize("outputs, noise", [(("x1", "y1", "x2", "y2"), 5e-4), (ANGLE_OUTPUTS, 3e-3)])
def test_least_squares_recovers_a_known_start_state_from_noisy_frames(runner, outputs, noise):
    data = _synthetic_frames(runner, outputs, noise)
    guess = TRUE_STATE + np.array([0.03, -0.03, 0.4, -0.6])  # a poor reconstruction
    fit = fit_start_state(runner, 0.5, np.arange(len(data)), data, noise, guess, MODEL, outputs=outputs,
                          absolute_sigma=True)
    error = fit.state - TRUE_STATE
    assert np.all(np.abs(error) < 4.0 * fit.stderr)  # consistent with its own error bars
    assert np.all(np.abs(error[:2]) < 5e-3) and np.all(np.abs(error[2:]) < 0.1)
    assert np.all(np.abs(error) < np.abs(guess - TRUE_STATE) / 5)  # far better than the start of the fit
    assert 0.3 < fit.chi2_red < 2.5  # the residuals are the noise that was put in


def test_horizon_is_the_first_crossing():
    t = np.arange(6) * 0.1
    assert mv.horizon(t, np.array([0.0, 0.005, 0.02, 0.001, 0.06, 0.07]), 0.01) == pytest.approx(0.2)
    assert mv.horizon(t, np.zeros(6), 0.01) is None
    assert mv.horizon(t, np.full(6, 0.5), 0.01) == 0.0


def test_quick_run_compares_both_starts_with_the_track(runner, tmp_path):
    summary = mv.run(runner, tmp_path, quick=True)
    assert json.loads((tmp_path / "summary.json").read_text())["t0_s"] == pytest.approx(0.8, abs=0.5 / 29.97)
    # the least-squares start follows the first second of the track better than the reconstruction's
    rms = summary["rms_error_first_second_m"]
    assert rms["lsq_start_identified"]["lower_bob"] < rms["seed_start_identified"]["lower_bob"]
    # the FMU's positions (pivot rest position at the origin) plus the fitted pivot land on the track at t0
    rec = reconstruct(load_track())
    i0 = summary["start_frame"]
    run = read_results_csv(tmp_path / "lsq_start_identified.csv")
    pivot = summary["pivot_origin_m"]
    assert run["time"][0] == pytest.approx(rec.t[i0])
    assert np.hypot(run["x2"][0] + pivot["x"] - rec.track.x2[i0], run["y2"][0] + pivot["y"] - rec.track.y2[i0]) < 0.01
    errors = read_results_csv(tmp_path / "errors.csv")
    horizon = summary["horizons_s"]["lsq_start_identified"]["lower_bob_5cm_s"]
    assert horizon == mv.horizon(errors["t_since_t0"], errors["e2_lsq_start_identified"], 0.05)
    for name in ("coordinates", "prediction_error"):
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000
    assert "Prediction horizons" in (tmp_path / "report.md").read_text()
