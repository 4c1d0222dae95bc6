"""The out-of-sample test of the motion: held-out frames, scores, ranking and ties, and the split it shares with
the energy test."""

from __future__ import annotations

import numpy as np
import pytest

from double_pendulum.analysis.losses import holdout
from double_pendulum.analysis.prediction import comparison as tc
from double_pendulum.analysis.prediction import out_of_sample as oos
from double_pendulum.analysis.prediction.report import motion_out_of_sample_text
from double_pendulum.analysis.track.measurement import FRAME_INTERVAL

T = np.arange(301) * FRAME_INTERVAL  # 10 s after t0
SPLIT = T[150]


def _prediction(e2: np.ndarray, label: str = "run") -> tc.Prediction:
    return tc.Prediction(label, np.zeros(4), None, T, np.zeros_like(e2), np.asarray(e2, float))


def _error(before: float, after: float) -> np.ndarray:
    """A lower-bob error [m] of ``before`` before the split and ``after`` from it on."""
    return np.where(T < SPLIT, before, after)


def test_held_out_frames_are_the_other_half():
    p = _prediction(_error(0.01, 0.02))
    first_fit, second_fit = oos.held_out(p, SPLIT, "first"), oos.held_out(p, SPLIT, "second")
    assert np.all(p.t[first_fit] >= SPLIT) and np.all(p.t[second_fit] < SPLIT)
    assert first_fit.sum() + second_fit.sum() == len(T) and not np.any(first_fit & second_fit)


def test_scores_are_taken_on_the_held_out_half_only():
    p = _prediction(_error(0.001, 0.03))
    fitted_first = oos.motion_scores(p, SPLIT, "first", float(T[-1]))
    fitted_second = oos.motion_scores(p, SPLIT, "second", float(T[-1]))
    assert fitted_first["rms_error_m"] == pytest.approx(0.03) and fitted_first["predicts"] == "second"
    assert fitted_second["rms_error_m"] == pytest.approx(0.001)
    assert fitted_first["horizon_5cm_censored"] and fitted_first["horizon_5cm_s"] == pytest.approx(T[-1])
    crossing = oos.motion_scores(_prediction(_error(0.001, 0.08)), SPLIT, "first", float(T[-1]))
    assert not crossing["horizon_5cm_censored"] and crossing["horizon_5cm_s"] == pytest.approx(SPLIT, abs=0.2)


def test_ranking_orders_by_held_out_error_and_ties_within_the_floor():
    halves = {"viscous": {"first": _prediction(_error(0.05, 0.010)), "second": _prediction(_error(0.020, 0.05))},
              "bearing": {"first": _prediction(_error(0.001, 0.012)), "second": _prediction(_error(0.021, 0.0))},
              "air": {"first": _prediction(_error(0.0, 0.040)), "second": _prediction(_error(0.030, 0.0))}}  # fmt: skip
    whole = {"viscous": _prediction(_error(0.01, 0.02)), "bearing": _prediction(_error(0.01, 0.01)),
             "air": _prediction(_error(0.01, 0.01))}  # fmt: skip
    out = oos.motion_out_of_sample(halves, whole, SPLIT, tie_m=0.004)
    first = out["directions"]["first_predicts_second"]
    assert first["order"] == ["viscous", "bearing", "air"] and first["tie"] == ["viscous", "bearing"]
    assert first["whole_record_scores"]["air"]["rms_error_m"] == pytest.approx(0.01)
    second = out["directions"]["second_predicts_first"]
    assert second["order"] == ["viscous", "bearing", "air"] and second["tie"] == ["viscous", "bearing"]
    assert "2 of 3 models predict it worse than their whole-record fit" in out["text"]
    text = motion_out_of_sample_text({"prediction_s": float(T[-1]), "out_of_sample_motion": out})
    assert "| viscous joint damping alone (tie) | 1.0 (2.0) |" in text and "out_of_sample_motion.png" in text


def test_the_motion_split_is_the_energy_tests_split():
    """The record's middle frame (the energy test's split, :func:`holdout.half_slice`) in seconds after t0."""
    t0_record = 0.2
    problem_t = t0_record + np.arange(11) * FRAME_INTERVAL
    problem = holdout.FitProblem(t0_record, np.arange(11), problem_t, np.ones(11), np.ones(11), {})
    second = holdout.half_problem(problem, "second")
    t0 = t0_record + 2 * FRAME_INTERVAL
    assert oos.split_after_t0(problem_t, t0) == pytest.approx(second.t[0] - t0)


def test_a_half_fit_at_the_whole_records_losses_is_said_to_be_the_in_sample_prediction():
    whole = {"viscous": _prediction(_error(0.01, 0.02)), "air": _prediction(_error(0.01, 0.02))}
    halves = {"viscous": {"first": _prediction(_error(0.01, 0.02)), "second": _prediction(_error(0.01, 0.03))},
              "air": {"first": _prediction(_error(0.01, 0.025)), "second": _prediction(_error(0.02, 0.02))}}
    out = oos.motion_out_of_sample(halves, whole, SPLIT, tie_m=0.004)
    first = out["directions"]["first_predicts_second"]["scores"]
    assert first["viscous"]["same_as_whole_record"] and not first["air"]["same_as_whole_record"]
    assert not any(s["same_as_whole_record"] for s in out["directions"]["second_predicts_first"]["scores"].values())
    assert out["text"].count("prediction is the in-sample one") == 1
    assert "Fitted to that half, viscous joint damping alone lands at the whole record's losses" in out["text"]


def test_the_motion_test_says_whether_the_energy_test_ranks_the_same_models_best():
    halves = {"viscous": {"first": _prediction(_error(0.05, 0.010)), "second": _prediction(_error(0.020, 0.05))},
              "air": {"first": _prediction(_error(0.0, 0.040)), "second": _prediction(_error(0.030, 0.0))}}
    whole = {m: _prediction(_error(0.01, 0.01)) for m in halves}
    energy = {"first_predicts_second": ["air", "bearing"], "second_predicts_first": ["viscous"]}
    out = oos.motion_out_of_sample(halves, whole, SPLIT, tie_m=0.004, energy_best=energy)
    d = out["directions"]
    assert d["first_predicts_second"]["energy_test_best"] == ["air"]  # only the models the motion test ran
    assert d["first_predicts_second"]["tie"] == ["viscous"]
    assert "ranks air drag alone best in this direction: the motion and the energy rank the models differently" \
        in out["text"]
    assert "ranks viscous joint damping alone best in this direction: the two tests agree" in out["text"]
