r"""The prediction under every loss model the measured energy supports equally.

``loss_identification`` fits several loss models to the measured energy and finds more than one within
delta AIC 2 of the lowest (:func:`~double_pendulum.analysis.losses.claims.supported_models`): the record does
not rank them. A prediction of the track needs one set of losses, so ``measured_vs_sim`` runs its main start
(the least-squares start and camera geometry) with :data:`~.comparison.LOSS_MODEL`; this module runs the same
start with each supported model in turn and reports the spread of the horizons. The start and geometry stay
the ones fitted with :data:`~.comparison.LOSS_MODEL` over the first 1.5 s, in which every supported model
dissipates the same energy to within its fit (they all follow the measured decay), so what changes from run
to run is the loss model alone.

The fits are obtained exactly as ``loss_identification`` obtains them in the same mode
(:func:`~double_pendulum.analysis.losses.fitting.fit_models` with the same models, starts and run budgets), so
after that scenario they are read from the cache; on a cold cache they cost its fitting time (about a minute of
CPU by default, a few seconds in a quick run, which fits :data:`~..losses.mechanisms.QUICK_MODELS` alone).

A horizon here is the first time the lower bob's error exceeds 5 cm, smoothed (:func:`~.comparison.smoothed`)
and per frame, as :func:`~.comparison.headline_horizon` defines it; the spread over the supported models is
the part of a horizon the energy record cannot pin down.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ..losses import claims, comparison, fitting, identification, mechanisms
from ..track.measurement import FRAME_INTERVAL, Reconstruction
from ..track.start_state import StartStateFit
from .comparison import Prediction, headline_horizon, predict, smoothed

THRESHOLD_M = 0.05
"""The error [m] whose first crossing is compared across the loss models."""


def supported_loss_fits(rec: Reconstruction, *, quick: bool = False,
                        bic_too: bool = False) -> dict[str, tuple[fitting.ModelFit, float]]:  # fmt: skip
    """The fit of every model within delta AIC 2 of the lowest (``bic_too``: or within delta BIC 2 of the lowest
    BIC, the models some criterion keeps) and the record's correlation factor F (its covariance is
    ``fit.cov(F)``), by model name, fitted to the whole record of ``rec`` as ``loss_identification`` fits them in
    that mode (quick: its one model)."""
    problem = fitting.problem_from_track(rec, identification.measured(rec), quick=quick)
    models = mechanisms.QUICK_MODELS if quick else mechanisms.FULL_MODELS
    fits, _ = fitting.fit_models(models, problem, max_workers=1, max_runs=fitting.run_budget(quick))
    factor = comparison.common_factor(problem)
    rows = comparison.comparison_rows(fits, factor)
    supported = set(claims.supported_models(rows)["models"])
    if bic_too:
        supported |= {r["model"] for r in rows if r["converged"] and not r.get("reduces_to")
                      and r["delta_bic"] < claims.SUPPORTED_DAIC}  # fmt: skip
    return {f.model: (f, factor) for f in fits if f.model in supported}


def loss_values(model: str, theta: Sequence[float]) -> dict[str, Any]:
    """FMU start values of the losses of ``model`` at parameters ``theta`` (negative values clipped to 0: a drawn
    loss, :mod:`.loss_uncertainty`) with the friction regularisation of the fits."""
    theta = np.clip(np.asarray(theta, dtype=float), 0.0, None)
    return {**mechanisms.model_values(model, theta), "omega_reg": mechanisms.OMEGA_REG}


def supported_loss_values(fits: Mapping[str, tuple[fitting.ModelFit, float]]) -> dict[str, dict[str, Any]]:
    """FMU start values of the losses of each of ``fits`` (:func:`supported_loss_fits`) at its fitted parameters
    (within their bounds, all > 0)."""
    return {model: loss_values(model, f.theta) for model, (f, _) in fits.items()}


def loss_model_predictions(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
    pendulum: Mapping[str, Any],
    start: StartStateFit,
    losses: Mapping[str, Mapping[str, Any]],
    done: tuple[Mapping[str, Any], Prediction] | None = None,
) -> dict[str, Prediction]:
    """The prediction from ``start`` (state and geometry) over ``n_frames`` frames with each model's ``losses``
    (:func:`supported_loss_values`) on the ``pendulum`` (lengths, masses, rods), by model name. ``done``: the
    start values of a prediction already run from ``start`` and that prediction; a model whose start values are
    those takes it instead of running again (the main run's model is one of the supported ones)."""
    out = {}
    for model, values in losses.items():
        start_values = {**pendulum, **values}
        out[model] = (done[1] if done is not None and start_values == dict(done[0]) else
                      predict(runner, f"loss_model_{model}", start_values, start.state, rec, i0, n_frames,
                              start.geometry))  # fmt: skip
    return out


def loss_model_sensitivity(predictions: Mapping[str, Prediction], n_frames: int,
                           dt: float = FRAME_INTERVAL) -> dict[str, Any]:  # fmt: skip
    """The lower bob's 5 cm horizons [s] of each loss model's prediction (:func:`~.comparison.headline_horizon`:
    smoothed, censored or not, and per frame) and their ranges over the models; a per-frame horizon of None
    (never crossed) counts as the record's length in the range, with ``raw_censored_models`` naming those; ``dt``
    [s]: the record's frame interval."""
    span = (n_frames - 1) * dt
    per_model = {model: headline_horizon(p, span, THRESHOLD_M) for model, p in predictions.items()}
    smoothed = [h["horizon_s"] for h in per_model.values()]
    raw = [span if h["raw_horizon_s"] is None else h["raw_horizon_s"] for h in per_model.values()]
    margins = [h["margin_below_threshold_m"] for h in per_model.values()]
    smoothed_censored = [m for m, h in per_model.items() if h["censored"]]
    raw_censored = [m for m, h in per_model.items() if h["raw_horizon_s"] is None]
    return {
        "models": per_model,
        "n_models": len(per_model),
        "smoothed_5cm_range_s": [float(np.min(smoothed)), float(np.max(smoothed))],
        "smoothed_censored_models": smoothed_censored,
        "smoothed_5cm_claim": range_claim(smoothed, len(smoothed_censored), span),
        "raw_5cm_range_s": [float(np.min(raw)), float(np.max(raw))],
        "raw_censored_models": raw_censored,
        "raw_5cm_claim": range_claim(raw, len(raw_censored), span),
        "margin_range_m": [float(np.min(margins)), float(np.max(margins))],
        "statement": "the start and camera geometry fitted to the first 1.5 s, run with each loss model the measured "
                     "energy supports equally (loss_identification): the range is what the record cannot pin down. "
                     "A horizon that reaches the end of the record is censored (only known to exceed it). In-sample: "
                     "the losses are fitted to the same record.",
    }


def range_claim(horizons: Sequence[float], n_censored: int, span: float) -> str:
    """The horizons [s] over the models as they may be claimed, in words: censored ones (``n_censored`` of them,
    given as the record's length ``span`` [s]) are only known to exceed the record."""
    lo, hi = float(np.min(horizons)), float(np.max(horizons))
    if n_censored == len(horizons):
        return f"the whole {span:.1f} s compared (censored: never exceeded within the record)"
    if n_censored:
        return f"{lo:.1f} s to the whole {span:.1f} s compared (censored)"
    return f"{lo:.1f} s" if hi - lo < 0.05 else f"{lo:.1f} to {hi:.1f} s"


def smoothed_error_band(predictions: Mapping[str, Prediction]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time since t0 [s] and the lowest and highest smoothed lower-bob error [m] over the loss models' predictions
    at each frame (they share the frames: one start, one track)."""
    runs = list(predictions.values())
    errors = np.array([smoothed(p.t, p.e2) for p in runs])
    return runs[0].t, errors.min(axis=0), errors.max(axis=0)
