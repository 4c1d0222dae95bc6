"""Start-state estimation from bob positions and the measured-vs-simulated scenario."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis.losses.fitting import ComponentRunner
from double_pendulum.analysis.prediction import comparison as tc
from double_pendulum.analysis.prediction.report import cause_text, fmt_horizon, regime_text
from double_pendulum.analysis.track.measurement import FRAME_INTERVAL, load_track, reconstruct
from double_pendulum.analysis.track.start_state import (
    ANGLE_OUTPUTS,
    FIT_SETTINGS,
    POSITION_OUTPUTS,
    fit_start_state,
    output_matrix,
    shift_outputs,
    simulate_frames,
    state_start_values,
)
from double_pendulum.analysis.track.tilt import seed_record_geometry
from double_pendulum.model.parameters import PendulumParameters
from double_pendulum.runs.results_io import read_results_csv

MODEL = {"air_drag": True, "rod_drag": True, "bearing_friction": True, "suspension": True}
TRUE_STATE = np.array([-0.2, 0.7, 2.0, -4.0])  # rad, rad, rad/s, rad/s


def _synthetic_frames(runner, outputs, noise, n_frames=12, t0=0.5, seed=1):
    """FMU-generated frames from TRUE_STATE with white noise of standard deviation ``noise``."""
    run = simulate_frames(
        runner, {**FIT_SETTINGS, **MODEL, **state_start_values(TRUE_STATE)}, t0, n_frames, outputs=outputs
    )
    clean = output_matrix(run, outputs)
    return clean + np.random.default_rng(seed).normal(0.0, noise, clean.shape)


@pytest.mark.parametrize("outputs, noise", [(("x1", "y1", "x2", "y2"), 5e-4), (ANGLE_OUTPUTS, 3e-3)])
def test_least_squares_recovers_a_known_start_state_from_noisy_frames(runner, outputs, noise):
    data = _synthetic_frames(runner, outputs, noise)
    guess = TRUE_STATE + np.array([0.03, -0.03, 0.4, -0.6])  # a poor reconstruction
    fit = fit_start_state(
        runner, 0.5, np.arange(len(data)), data, noise, guess, MODEL, outputs=outputs, absolute_sigma=True
    )
    error = fit.state - TRUE_STATE
    assert np.all(np.abs(error) < 4.0 * fit.stderr)  # consistent with its own error bars
    assert np.all(np.abs(error[:2]) < 5e-3) and np.all(np.abs(error[2:]) < 0.1)
    assert np.all(np.abs(error) < np.abs(guess - TRUE_STATE) / 5)  # far better than the start of the fit
    assert 0.3 < fit.chi2_red < 2.5  # the residuals are the noise that was put in


def test_least_squares_recovers_a_known_pivot_offset_and_l2_with_the_state():
    """A synthetic track made by the FMU's own component seen by a turned camera, with a shifted pivot, a
    longer lower rod and the seed's position noise (about 3 mm): the state and geometry fit finds them back."""
    runner = ComponentRunner()
    truth = {"view_rotation": 0.03, "pivot_offset_x": 0.004, "pivot_offset_y": -0.004, "l2": 0.203}  # rad, m
    model = {"l1": 0.2964, "l2": 0.1971}  # the fit starts from the track's l2 and pivot offset 0
    n, noise = 60, 3e-3
    run = simulate_frames(runner, {**FIT_SETTINGS, **model, "l2": truth["l2"], **state_start_values(TRUE_STATE)},
                          0.5, n)
    shifts = {k: truth[k] for k in ("view_rotation", "pivot_offset_x", "pivot_offset_y")}
    clean = shift_outputs(output_matrix(run), POSITION_OUTPUTS, shifts)
    data = clean + np.random.default_rng(3).normal(0.0, noise, clean.shape)
    guess = TRUE_STATE + np.array([0.02, -0.02, 0.3, -0.4])
    fit = fit_start_state(runner, 0.5, np.arange(n), data, noise, guess, model, absolute_sigma=True,
                          geometry=tc.FREE_GEOMETRY)
    assert fit.names == ("phi1_0", "phi2_0", "omega1_0", "omega2_0", *tc.FREE_GEOMETRY)
    err = {k: fit.geometry[k] - v for k, v in truth.items()}
    assert all(abs(err[k]) < 4.0 * fit.geometry_stderr[k] for k in truth)  # consistent with its error bars
    assert all(abs(err[k]) < 3e-3 for k in ("pivot_offset_x", "pivot_offset_y", "l2"))  # m, from 4-6 mm off
    assert abs(err["view_rotation"]) < 0.01  # rad, from 0.03 rad (1.7 deg) off
    assert np.all(np.abs(fit.state - TRUE_STATE) < 4.0 * fit.stderr)
    assert 0.5 < fit.chi2_red < 2.0 and fit.full_cov.shape == (8, 8)
    assert fit.as_dict()["geometry"]["l2"] == pytest.approx(fit.geometry["l2"])


def test_predictions_at_their_looser_tolerance_follow_the_fits_integration(runner):
    """The predictions run at PREDICTION_SETTINGS (rtol 1e-8), the fits at FIT_SETTINGS (1e-10): over 8 s of
    lively motion the positions agree to micrometres, far below the 2 cm and 5 cm of the horizons."""
    start = {**MODEL, **state_start_values(TRUE_STATE)}
    tight, loose = (output_matrix(simulate_frames(runner, {**settings, **start}, 0.5, 241))
                    for settings in (FIT_SETTINGS, tc.PREDICTION_SETTINGS))  # fmt: skip
    assert tc.PREDICTION_SETTINGS["rtol"] > FIT_SETTINGS["rtol"]
    assert np.max(np.abs(loose - tight)) < 2e-5  # m


def test_smoothed_horizon_ignores_single_frame_jitter_but_not_a_sustained_rise():
    t = np.arange(60) * FRAME_INTERVAL
    error = 0.01 + 0.02 * (t > 1.0)  # 1 cm, then 3 cm from t > 1 s
    error[[5, 6, 20]] = 0.08  # the track's jitter: one or two frames far off
    assert tc.horizon(t, error, 0.05) == pytest.approx(t[5])  # raw: the first spike
    smooth = tc.smoothed(t, error, 0.25)  # median over +-0.125 s: about 7 frames
    assert np.max(smooth[:25]) == pytest.approx(0.01)  # spikes gone
    assert tc.horizon(t, smooth, 0.05) is None
    assert tc.horizon(t, smooth, 0.02) == pytest.approx(t[np.flatnonzero(t > 1.0)[0]], abs=4 * FRAME_INTERVAL)
    gappy = np.delete(np.arange(60), [30, 31, 32])  # missing frames: the window is in time, not in samples
    np.testing.assert_allclose(tc.smoothed(t[gappy], error[gappy], 0.25)[:25], 0.01)
    p = tc.Prediction("run", np.zeros(4), None, t, error, error)
    h = p.smoothed_horizons()
    assert list(h) == tc.horizon_keys() == ["lower_bob_2cm_s", "both_bobs_2cm_s", "lower_bob_5cm_s", "both_bobs_5cm_s"]
    assert h["lower_bob_5cm_s"] is None and h["lower_bob_2cm_s"] == tc.horizon(t, smooth, 0.02)


def test_regime_is_regular_below_and_chaotic_far_above_the_flip_energy():
    """Over 10 s, as the quick run (0.7 s of CPU each; 20 s took twice that): the regular start's exponent falls
    from 0.45 to 0.12 1/s between T/4 and T (regular below half), the chaotic one's stays at 2.2 (2.3 at T/4)."""
    params = PendulumParameters()
    regular = tc.regime(params, [0.1, 0.2, 0.0, 0.0], 10.0)
    assert regular["verdict"] == "regular" and regular["energy_over_flip_energy"] < 0.1
    assert "model and measurement limit" in regime_text({"regime": regular})
    wild = tc.regime(params, [2.0, 2.5, 0.0, 0.0], 10.0)
    assert wild["verdict"] == "chaotic" and wild["largest_lyapunov_exponent_per_s"] > 0.5
    assert "chaotic" in regime_text({"regime": wild})


def test_horizon_is_the_first_crossing():
    t = np.arange(6) * 0.1
    assert tc.horizon(t, np.array([0.0, 0.005, 0.02, 0.001, 0.06, 0.07]), 0.01) == pytest.approx(0.2)
    assert tc.horizon(t, np.zeros(6), 0.01) is None
    assert tc.horizon(t, np.full(6, 0.5), 0.01) == 0.0


def _prediction(e1, e2, label="run", result=None):
    t = np.arange(len(e1)) * 0.5
    return tc.Prediction(label, np.zeros(4), result, t, np.asarray(e1, float), np.asarray(e2, float))


def test_prediction_horizons_take_the_worse_bob_for_both():
    p = _prediction([0.0, 0.02, 0.02, 0.06], [0.0, 0.005, 0.03, 0.03])
    np.testing.assert_array_equal(p.e_both, [0.0, 0.02, 0.03, 0.06])
    assert p.horizons() == {
        "lower_bob_2cm_s": 1.0,  # e2 first above 2 cm at t = 1.0 s
        "both_bobs_2cm_s": 1.0,  # the upper bob reaches 2 cm but does not exceed it
        "lower_bob_5cm_s": None,
        "both_bobs_5cm_s": 1.5,
    }
    assert p.rms_lower_bob_error(0.5) == pytest.approx(np.sqrt((0.0 + 0.005**2) / 2))


def test_chaos_horizons_and_error_curves():
    t = np.arange(5) * FRAME_INTERVAL
    spread = (t, np.array([1e-4, 1e-3, 0.02, 0.04, 0.2]))
    assert tc.chaos_horizons(spread) == {
        "lower_bob_2cm_s": pytest.approx(3 * FRAME_INTERVAL),
        "lower_bob_5cm_s": pytest.approx(4 * FRAME_INTERVAL),
    }
    runs = [_prediction([0.0], [0.0], "a"), _prediction([0.0], [0.0], "b")]
    curves = tc.error_curves(runs, spread)
    assert list(curves.smoothed) == ["a", "b"] and curves.per_frame[0] == "b"  # the main run: the last
    assert curves.spread is spread
    assert tc.errors_units(runs)["e2_b"] == "m"


@pytest.fixture(scope="module")
def rec():
    return reconstruct(load_track())


def test_start_frame_is_valid_and_nearest_to_t0(rec):
    i0 = tc.nearest_frame(rec, 0.8)
    assert abs(rec.t[i0] - 0.8) <= FRAME_INTERVAL
    assert rec.track.valid[i0] and np.isfinite(rec.omega1[i0]) and np.isfinite(rec.omega2[i0])
    state = tc.reconstructed_state(rec, i0)
    np.testing.assert_array_equal(state, [rec.phi1[i0], rec.phi2[i0], rec.omega1[i0], rec.omega2[i0]])


def test_rod_length_floor_is_the_tracks_deviation_from_a_rigid_lower_rod(rec):
    i0, n = 24, 60
    t, dev = tc.rod_length_floor(rec, i0, n)
    idx = i0 + np.round(t / FRAME_INTERVAL).astype(int)
    assert t[0] == 0.0 and np.all(rec.track.valid[idx])
    r2 = np.hypot(rec.x2[idx] - rec.x1[idx], rec.y2[idx] - rec.y1[idx])
    np.testing.assert_allclose(dev, np.abs(r2 - rec.params.l2), rtol=1e-12)
    floor = tc.rod_floor_summary(rec, i0, n)
    assert floor["rms_m"] == pytest.approx(np.sqrt(np.mean(dev**2)))
    assert floor["max_m"] == pytest.approx(dev.max())
    assert floor["fraction_above_1cm"] == pytest.approx(np.mean(dev > 0.01))
    assert 0.001 < floor["rms_m"] < 0.03  # millimetres to centimetres: the track's own resolution
    table = tc.errors_table(rec, i0, n, [])
    np.testing.assert_array_equal(table["rod2_deviation"], dev)
    np.testing.assert_array_equal(table["x2"], rec.track.x2[idx])  # the track's own coordinates


def test_simulated_positions_move_into_the_tracks_coordinates_by_the_pivot(rec):
    """The FMU's origin is the pivot at rest: a bob at the FMU's origin sits at the fitted pivot of the track."""
    names = ("time", "x1", "y1", "x2", "y2")
    result = np.zeros(3, dtype=[(n, float) for n in names])
    result["y2"] = -0.5
    t, coords = tc.simulated_coordinates(rec, _prediction([0.0] * 3, [0.0] * 3, result=result))
    pivot = rec.geometry.pivot
    np.testing.assert_array_equal(coords["x1"], pivot.xc)
    np.testing.assert_array_equal(coords["y2"], pivot.yc - 0.5)
    t_meas, measured = tc.measured_coordinates(rec, 30, 20, lead=10)
    assert t_meas[0] >= rec.t[20] and t_meas[-1] <= rec.t[49] and len(measured["x1"]) == len(t_meas)


def _cause_summary(observed, chaos):
    return {
        "prediction_s": 2.0,
        "horizons_smoothed_s": {"lsq_geometry_identified": {"lower_bob_5cm_s": observed}},
        "chaos_horizons_s": {"lower_bob_5cm_s": chaos},
    }


def test_cause_is_model_error_when_the_fit_allows_more_than_twice_the_observed_horizon():
    assert "model error" in cause_text(_cause_summary(0.4, None))  # the ensemble: beyond the 2 s prediction
    assert "start's uncertainty limits it" in cause_text(_cause_summary(0.6, 1.0))
    assert "whole 2.0 s prediction" in cause_text(_cause_summary(None, None))
    assert fmt_horizon(None, 2.0) == "none in 2.00" and fmt_horizon(0.123, 2.0) == "0.12"  # censored: no "> 2"


def test_quick_run_compares_both_starts_with_the_track(quick_results):
    tmp_path, summary = quick_scenario(quick_results, "measured_vs_sim")
    assert summary["t0_s"] == pytest.approx(0.8, abs=0.5 / 29.97)
    # the least-squares start follows the first second of the track better than the reconstruction's
    rms = summary["rms_error_first_second_m"]
    assert rms["lsq_start_identified"]["lower_bob"] < rms["seed_start_identified"]["lower_bob"]
    # the track is turned back by the camera's tilt fitted to the energy (analysis/track/tilt.py): the rotation the
    # motion fits on top of it is zero within its errors (the motion agrees with the energy's tilt)
    geo = summary["starts"]["least_squares_geometry"]
    assert abs(geo["geometry"]["view_rotation"]) < 3.0 * geo["geometry_stderr"]["view_rotation"]
    labels = ["seed_start_frictionless", "seed_start_identified", "lsq_start_identified",
              "lsq_fixed_geometry_identified", "lsq_pivot_shift_identified", "lsq_geometry_identified"]
    for key in ("horizons_smoothed_s", "horizons_raw_s"):
        assert list(summary[key]) == labels and key in summary["null_means"]
        assert all(list(h) == tc.horizon_keys() for h in summary[key].values())
    assert summary["smoothing"]["window_s"] == tc.SMOOTHING_S
    goal = summary["goal"]
    assert goal["required_s"] == 3.0 and isinstance(goal["met"], bool)
    assert goal["met"] == (goal["reached_s"] >= 3.0)
    assert set(summary["starts"]["least_squares_geometry"]["geometry"]) == set(tc.FREE_GEOMETRY)
    assert summary["regime"]["verdict"] in ("regular", "chaotic")
    assert summary["model"]["loss_model"] == "air+drag"
    # the FMU's positions (pivot rest position at the origin) plus the fitted pivot land on the track at t0
    # (the positions about the pivot, turned back by the camera's tilt: the reconstruction measured_vs_sim reads)
    rec = reconstruct(load_track(), seed_record_geometry().geometry)
    i0 = summary["start_frame"]
    run = read_results_csv(tmp_path / "lsq_start_identified.csv")  # no pivot offset fitted
    pivot = summary["pivot_origin_m"]
    assert (pivot["x"], pivot["y"]) == pytest.approx((rec.geometry.pivot.xc, rec.geometry.pivot.yc))
    assert run["time"][0] == pytest.approx(rec.t[i0])
    assert np.hypot(run["x2"][0] - rec.x2[i0], run["y2"][0] - rec.y2[i0]) < 0.01
    errors = read_results_csv(tmp_path / "errors.csv")
    t, e2 = errors["t_since_t0"], errors["e2_lsq_start_identified"]
    assert summary["horizons_raw_s"]["lsq_start_identified"]["lower_bob_5cm_s"] == tc.horizon(t, e2, 0.05)
    smooth = tc.smoothed(t, errors["e2_lsq_geometry_identified"])
    assert summary["horizons_smoothed_s"]["lsq_geometry_identified"]["lower_bob_2cm_s"] == tc.horizon(t, smooth, 0.02)
    for name in ("coordinates", "prediction_error"):
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000
    report = (tmp_path / "report.md").read_text()
    assert "Prediction horizons" in report
    # a horizon that reaches the end of the prediction is censored and claimed as "not reached in the span compared"
    for suffix, label in (("", "lsq_geometry_identified"), ("_fixed_geometry", "lsq_fixed_geometry_identified"),
                          ("_pivot_shift", "lsq_pivot_shift_identified")):
        crossing = tc.horizon(t, tc.smoothed(t, errors[f"e2_{label}"]), 0.05)
        assert summary[f"horizon_5cm_censored{suffix}"] == (crossing is None)
        assert summary[f"horizon_5cm_s{suffix}"] == (summary["prediction_s"] if crossing is None else crossing)
        if crossing is None:
            assert f"not reached in the {summary['prediction_s']:.2f} s compared (censored)" in report
    assert set(summary["starts"]["least_squares_pivot_shift"]["geometry"]) == set(tc.PIVOT_SHIFT_GEOMETRY)
    assert "geometry" not in summary["starts"]["least_squares_fixed_geometry"] or not summary["starts"][
        "least_squares_fixed_geometry"]["geometry"]
    assert "in-sample" in report
    # the fit-window check belongs to --thorough; the report says so instead of leaving it out silently
    assert not summary["thorough"] and "fit_window_sensitivity" not in summary
    assert "are fitted with ``--thorough``" in report
    assert summary["starts"]["least_squares_geometry"]["n_frames"] <= 15  # the quick run's shorter geometry fit
    assert summary["regime"]["averaging_time_s"] == pytest.approx(10.0)
    # the damping-level runs: their fitted level is the loss model's own prediction; the ensemble is --thorough only
    unc = summary["loss_uncertainty"]
    for model, d in unc["damping_sensitivity"].items():
        assert d["levels"]["fitted"]["horizon_s"] == summary["loss_model_sensitivity"]["models"][model]["horizon_s"]
        h = [d["levels"][k]["horizon_s"] for k in ("less_damping", "more_damping")]
        assert d["smoothed_s_per_percent"] == pytest.approx((h[1] - h[0]) / 2.0)
    assert "ensemble" not in unc and "The losses' uncertainty" in report


def test_the_loss_models_reuse_the_main_run_and_run_each_other_model_once(monkeypatch):
    """loss_model_predictions runs the start once per supported model, except the model whose start values are
    those of the run already done (the main run's), which it takes as it is."""
    from types import SimpleNamespace

    from double_pendulum.analysis.prediction import loss_models

    ran = []
    monkeypatch.setattr(loss_models, "predict",
                        lambda runner, label, values, *args: ran.append((label, values)) or label)
    start = SimpleNamespace(state=None, geometry={})
    pendulum = {"l1": 0.3}
    losses = {"air+drag": {"air_factor": 2.2}, "viscous": {"b_v1": 1e-4}}
    main = object()
    out = loss_models.loss_model_predictions(None, None, 0, 10, pendulum, start, losses,
                                             done=({"l1": 0.3, "air_factor": 2.2}, main))
    assert out == {"air+drag": main, "viscous": "loss_model_viscous"}
    assert ran == [("loss_model_viscous", {"l1": 0.3, "b_v1": 1e-4})]
    ran.clear()
    loss_models.loss_model_predictions(None, None, 0, 10, pendulum, start, losses, done=({"l1": 0.3}, main))
    assert [label for label, _ in ran] == ["loss_model_air+drag", "loss_model_viscous"]
