r"""Out-of-sample prediction of the motion: each loss model fitted to one half of the energy record predicts the
lower bob's path through the FMU.

:mod:`..losses.holdout` fits every loss model to one half of the measured energy and predicts the other half's
energy. This module takes the same half fits (:func:`~..losses.identification.thorough_half_fits`, read from the
cache after ``loss_identification --thorough``) and runs the main start of ``measured_vs_sim`` (the least-squares
start and camera geometry at t0) through the FMU with the losses, fitted to one half, of each model that AIC or
BIC keeps within 2 of its lowest (AIC alone may keep one). The split is the energy record's (its middle frame),
:math:`t_s` after t0. Per model and half fitted to, on the frames of the other half (the held-out frames, which
the loss fit never saw):

* the RMS of the lower bob's per-frame position error :math:`e_2 = |r_2^{sim} - r_2^{track}|` [m];
* the median of the smoothed error (:func:`~.comparison.smoothed`) [m];
* the lower bob's smoothed 5 cm horizon over the whole run [s] (:func:`~.comparison.headline_horizon`,
  censored at the record's end),

beside the same scores of the model's whole-record fit (in-sample). Models whose held-out RMS error lies within
the track's own floor (the RMS of the rod-length deviation :math:`||r_2 - r_1| - l_2|`,
:func:`~.comparison.rod_floor_summary`: what no rigid-rod model can match) of the lowest predict equally well.

Not free of the held-out data: the start state and geometry are fitted to the first 1.5 s after t0 (inside the
first half) with the main model's whole-record losses, since a prediction of the motion needs a start; so the
second-half fit's prediction of the first half starts from the first half's own frames.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ..losses.holdout import HALVES, HoldoutFit, other, out_of_sample
from ..losses.identification import thorough_half_fits
from ..losses.mechanisms import model_title
from ..track.measurement import FRAME_INTERVAL, Reconstruction
from ..track.start_state import StartStateFit
from .comparison import Prediction, headline_horizon, predict, smoothed
from .loss_models import loss_values


def held_out(prediction: Prediction, split_s: float, half: str) -> np.ndarray:
    """Mask of the frames of ``prediction`` in the half ``other(half)`` (the one a fit to ``half`` never saw):
    t >= ``split_s`` [s after t0] for the second half, before it for the first."""
    return prediction.t >= split_s if other(half) == "second" else prediction.t < split_s


def motion_scores(prediction: Prediction, split_s: float, half: str, span_s: float) -> dict[str, Any]:
    """The scores of the module docstring of ``prediction`` (losses fitted to ``half``) on the held-out frames."""
    mask = held_out(prediction, split_s, half)
    e2 = prediction.e2[mask]
    h = headline_horizon(prediction, span_s)
    return {"fitted_on": half, "predicts": other(half), "n_frames": int(mask.sum()),
            "rms_error_m": float(np.sqrt(np.mean(e2**2))),
            "median_smoothed_error_m": float(np.median(smoothed(prediction.t, prediction.e2)[mask])),
            "horizon_5cm_s": h["horizon_s"], "horizon_5cm_censored": h["censored"]}  # fmt: skip


def half_predictions(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
    pendulum: Mapping[str, Any],
    start: StartStateFit,
    hfits: Sequence[HoldoutFit],
    models: Sequence[str],
) -> dict[str, dict[str, Prediction]]:
    """The prediction from ``start`` (state and geometry) over ``n_frames`` frames through ``runner`` with the
    losses of each of ``models`` fitted to each half (``hfits``), by model and half fitted to."""
    out: dict[str, dict[str, Prediction]] = {}
    for h in hfits:
        if h.fit.model in models:
            values = {**pendulum, **loss_values(h.fit.model, h.fit.theta)}
            out.setdefault(h.fit.model, {})[h.half] = predict(
                runner, f"half_{h.half}_{h.fit.model}", values, start.state, rec, i0, n_frames, start.geometry)
    return out


def motion_out_of_sample(
    halves: Mapping[str, Mapping[str, Prediction]],
    whole: Mapping[str, Prediction],
    split_s: float,
    tie_m: float,
    energy_best: Mapping[str, Sequence[str]] | None = None,
) -> dict[str, Any]:
    """Per direction the scores of every model's half-fitted prediction (``halves``, :func:`half_predictions`) and
    of its whole-record one (``whole``, in-sample), the ranking by held-out RMS error with the models within
    ``tie_m`` [m] (the track's floor) of the lowest, and a sentence on what it says; ``energy_best``: per direction
    the models the energy test (:func:`..losses.holdout.out_of_sample`) finds predicting best, for the contrast."""
    first = next(iter(halves.values()))[HALVES[0]]
    span = float(first.t[-1])
    out: dict[str, Any] = {"split_after_t0_s": split_s, "tie_within_m": tie_m, "directions": {}}
    for half in HALVES:
        scores = {m: {**motion_scores(p[half], split_s, half, span),
                      "same_as_whole_record": bool(np.allclose(p[half].e2, whole[m].e2, rtol=0.0, atol=1e-6))}
                  for m, p in halves.items()}  # fmt: skip
        in_sample = {m: motion_scores(whole[m], split_s, half, span) for m in halves}
        order = sorted(scores, key=lambda m: scores[m]["rms_error_m"])
        low = scores[order[0]]["rms_error_m"]
        out["directions"][f"{half}_predicts_{other(half)}"] = {
            "scores": scores, "whole_record_scores": in_sample, "order": order,
            "tie": [m for m in order if scores[m]["rms_error_m"] - low < tie_m]}  # fmt: skip
        if energy_best is not None:
            name = f"{half}_predicts_{other(half)}"
            out["directions"][name]["energy_test_best"] = [m for m in energy_best[name] if m in halves]
    out["text"] = motion_text(out)
    return out


def motion_test(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
    pendulum: Mapping[str, Any],
    start: StartStateFit,
    whole: Mapping[str, Prediction],
    tie_m: float,
) -> tuple[dict[str, Any], dict[str, dict[str, tuple[np.ndarray, np.ndarray]]]]:
    """The whole test: the half fits of ``loss_identification --thorough`` (:func:`..losses.identification.
    thorough_half_fits`, read from its cache), the main start (``start``) run with each of the models of ``whole``
    (their whole-record predictions) fitted to each half, scored (:func:`motion_out_of_sample`) beside the energy
    test's best predictors; returns the summary and the error curves to draw (:func:`error_curves`)."""
    problem, hfits = thorough_half_fits(rec)
    halves = half_predictions(runner, rec, i0, n_frames, pendulum, start, hfits, list(whole))
    energy = out_of_sample(problem, hfits)["directions"]
    best = {name: d["ranking"]["tie"] for name, d in energy.items()}
    out = motion_out_of_sample(halves, whole, split_after_t0(problem.t, float(rec.t[i0]), rec.track.dt), tie_m, best)
    return out, error_curves(halves)


def motion_text(out: Mapping[str, Any]) -> str:
    """What the motion test says: per direction the best predictors and how the half fits compare with the
    whole-record fits on the same frames."""
    parts = []
    for name, d in out["directions"].items():
        s, w = d["scores"], d["whole_record_scores"]
        best = ", ".join(f"{model_title(m)} ({100 * s[m]['rms_error_m']:.1f} cm)" for m in d["tie"])
        worse = [m for m in s if s[m]["rms_error_m"] > w[m]["rms_error_m"]]
        same = [model_title(m) for m in s if s[m]["same_as_whole_record"]]
        energy = d.get("energy_test_best")
        contrast = "" if energy is None else (
            " The energy test of the same half fits ranks "
            + (", ".join(model_title(m) for m in energy) if energy else "none of these models")
            + " best in this direction"
            + (": the two tests agree on the best." if set(energy) & set(d["tie"]) else
               ": the motion and the energy rank the models differently (the energy test scores the energy's level, "
               "the motion test the bob's position, which a loss moves mostly through the swing's phase)."))
        parts.append(f"Losses fitted to the {name.replace('_predicts_', ' half, predicting the ')} half's motion: "
                     f"lowest RMS error of the lower bob {best}; {len(worse)} of {len(s)} models predict it worse "
                     "than their whole-record fit does." + contrast
                     + (f" Fitted to that half, {' and '.join(same)} land{'s' if len(same) == 1 else ''} at the "
                        "whole record's losses (the half's optimum lies within the fit's step tolerance of it), so "
                        f"{'its' if len(same) == 1 else 'their'} prediction is the in-sample one." if same else ""))
    return " ".join(parts) + (f" Ties: within {100 * out['tie_within_m']:.2f} cm, the track's own rod-length RMS; the "
                              "start is fitted to the first 1.5 s in both directions.")


def error_curves(halves: Mapping[str, Mapping[str, Prediction]]) -> dict[str, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """Time since t0 [s] and the smoothed lower-bob error [m] of every half-fitted prediction, by half fitted to
    and model (what :func:`~double_pendulum.plots.prediction.plot_out_of_sample_motion` draws)."""
    return {half: {m: (p[half].t, smoothed(p[half].t, p[half].e2)) for m, p in halves.items()} for half in HALVES}


def split_after_t0(problem_t: np.ndarray, t0: float, dt: float = FRAME_INTERVAL) -> float:
    """The energy record's split (its middle frame, as :func:`..losses.holdout.half_slice`) in seconds after the
    prediction's t0 [s], on the frame grid of ``dt`` [s]."""
    t_split = float(problem_t[len(problem_t) // 2])
    return round((t_split - t0) / dt) * dt
