r"""The prediction horizon with the losses' own uncertainty: an ensemble and the sensitivity to the damping level.

The horizons of :mod:`.loss_models` run each supported loss model at its fitted parameters as if they were
exact. They are not: each fit carries a covariance of its loss parameters :math:`\theta` (the curvature of
:math:`\chi^2` scaled by the residual-correlation factor F,
:meth:`~double_pendulum.analysis.losses.fitting.ModelFit.cov`), and the horizon is very sensitive to the level
of the damping: a model that dissipates a little less or a little more than fitted drifts in amplitude, and the
lower bob's error grows with it. Two measures of that, both on the main start (the least-squares start and
camera geometry of :mod:`.comparison`):

- **Damping level** (:func:`damping_sensitivity`): every fitted loss coefficient of a model multiplied by
  :math:`(1 + \delta)` (the energy lost per swing is nearly linear in each coefficient, so the dissipation
  changes by about :math:`\delta`), for :math:`\delta = \pm` :data:`DAMPING_STEP`; the lower bob's smoothed
  5 cm horizon [s] at each, and the change per 1 % of damping,

  .. math::

      \frac{\Delta h}{\Delta\delta} \approx \frac{h(+\delta) - h(-\delta)}{2\delta}\cdot 0.01
      \quad [\text{s per 1 \%}],

  with a censored horizon (never crossed within the record) counted as the record's length, so a slope
  that involves one is a lower bound on its size.
- **Ensemble** (:func:`horizon_ensemble`, ``thorough`` only): members whose loss parameters are drawn from
  their fit's covariance, :math:`\theta_i = \hat\theta + s\,L z_i` (:math:`L L^T` the covariance, :math:`z_i`
  standard normal, :math:`s` a width factor, 1 for the fit's own), together with the start state and geometry
  drawn from their least-squares covariance the same way; per model the median and the 16-84 % range of the
  horizons (smoothed 5 cm and frame by frame). Drawn values are clipped at zero (a loss coefficient cannot be
  negative). Censored members count as the record's length: a percentile equal to it says "beyond the record".

Everything is in-sample: the losses are fitted to the same record the horizons are measured on.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ...runs.result_cache import cached
from ..losses.fitting import ModelFit
from ..track.measurement import Reconstruction
from ..track.start_state import StartStateFit, split_geometry
from .comparison import headline_horizon, predict
from .loss_models import loss_values

DAMPING_STEP = 0.01
"""Relative change delta of every loss coefficient in :func:`damping_sensitivity` (1 %)."""
ENSEMBLE_SIZE = 12
"""Members per loss model of :func:`horizon_ensemble` (``thorough``; 5 models, about 1.3 s of CPU each)."""
ENSEMBLE_SEED = 20250611
"""Seed of the draws of :func:`horizon_ensemble` (common to every model and width, so wider draws of the same
members move each member outward along the same direction)."""
PERCENTILES = (16.0, 50.0, 84.0)
"""Percentiles reported of an ensemble's horizons: the 16-84 % range (about +-1 sigma) and the median."""


def correlated_draws(mean: np.ndarray, cov: np.ndarray, z: np.ndarray, width: float = 1.0) -> np.ndarray:
    """``mean + width * L z`` for each row of the standard-normal ``z`` (shape (n, d)), L a square root of ``cov``
    (eigen-decomposition: a singular or zero covariance is allowed; zero gives ``mean`` in every row)."""
    mean = np.asarray(mean, dtype=float)
    w, v = np.linalg.eigh(0.5 * (np.asarray(cov, dtype=float) + np.asarray(cov, dtype=float).T))
    root = v * np.sqrt(np.clip(w, 0.0, None))
    return mean + width * np.asarray(z, dtype=float) @ root.T


def horizon_stats(horizons: Sequence[float], span_s: float, censored: Sequence[bool]) -> dict[str, Any]:
    """Median and 16-84 % range [s] of ``horizons`` (censored ones given as ``span_s``), the censored fraction,
    and whether the top of the range is censored (then it only says "beyond the record")."""
    h = np.asarray(horizons, dtype=float)
    lo, med, hi = (float(x) for x in np.percentile(h, PERCENTILES))
    return {"median_s": med, "range_16_84_s": [lo, hi], "n": int(len(h)),
            "censored_fraction": float(np.mean(np.asarray(censored, dtype=bool))),
            "median_censored": bool(med >= span_s), "top_censored": bool(hi >= span_s)}  # fmt: skip


def _horizons(prediction: Any, span_s: float) -> tuple[float, bool, float, bool]:
    """Smoothed 5 cm horizon [s] and whether censored, per-frame 5 cm horizon [s] and whether censored."""
    h = headline_horizon(prediction, span_s)
    raw = h["raw_horizon_s"]
    return h["horizon_s"], h["censored"], span_s if raw is None else raw, raw is None


def ensemble_summary(members: Sequence[tuple[float, bool, float, bool]], span_s: float) -> dict[str, Any]:
    """:func:`horizon_stats` of the smoothed and the per-frame horizons of ``members`` (as :func:`_horizons`)."""
    m = list(zip(*members))
    return {"smoothed_5cm": horizon_stats(m[0], span_s, m[1]), "raw_5cm": horizon_stats(m[2], span_s, m[3])}


def damping_sensitivity(
    run: Callable[[Mapping[str, Any]], Any],
    model: str,
    theta: Sequence[float],
    span_s: float,
    central: Any,
    step: float = DAMPING_STEP,
) -> dict[str, Any]:
    """The smoothed and per-frame 5 cm horizons [s] of ``model`` with every coefficient ``theta`` times 1 - ``step``,
    1 and 1 + ``step`` (``run``: loss start values -> prediction; ``central``: the prediction at 1, already run),
    and the change of each per 1 % more damping [s] (central difference; see the module docstring)."""
    theta = np.asarray(theta, dtype=float)
    rows = {}
    for name, level in (("less_damping", -step), ("fitted", 0.0), ("more_damping", step)):
        p = central if level == 0.0 else run(loss_values(model, (1.0 + level) * theta))
        h, c, raw, raw_c = _horizons(p, span_s)
        rows[name] = {"damping_change": level, "horizon_s": h, "censored": c, "raw_horizon_s": raw,
                                 "raw_censored": raw_c}  # fmt: skip
    lo, hi = rows["less_damping"], rows["more_damping"]
    per_percent = 0.01 / (2.0 * step)
    return {
        "levels": rows,
        "smoothed_s_per_percent": (hi["horizon_s"] - lo["horizon_s"]) * per_percent,
        "raw_s_per_percent": (hi["raw_horizon_s"] - lo["raw_horizon_s"]) * per_percent,
        "slope_is_lower_bound": bool(lo["censored"] or hi["censored"]),
        "step": step,
    }


def horizon_ensemble(
    run: Callable[[Mapping[str, Any], np.ndarray, Mapping[str, float]], Any],
    model: str,
    fit: ModelFit,
    factor: float,
    start: StartStateFit,
    span_s: float,
    size: int = ENSEMBLE_SIZE,
    width: float = 1.0,
    seed: int = ENSEMBLE_SEED,
) -> dict[str, Any]:
    """Horizons of ``size`` members with the losses of ``fit`` (covariance ``fit.cov(factor)``) and the start state
    and geometry of ``start`` (its covariance) drawn ``width`` times as wide as fitted; ``run``: (loss start values,
    state, geometry) -> prediction. Returns :func:`ensemble_summary` and the members' horizons."""
    rng = np.random.default_rng(seed)
    z_loss = rng.standard_normal((size, len(fit.theta)))
    z_start = rng.standard_normal((size, len(start.values)))
    thetas = correlated_draws(fit.theta, fit.cov(factor), z_loss, width)
    starts = correlated_draws(start.values, start.covariance, z_start, width)
    members = []
    for theta, x in zip(thetas, starts):
        geometry = dict(zip(start.names[4:], x[4:]))
        split_geometry(geometry)  # the names must be known geometry (raises otherwise)
        members.append(_horizons(run(loss_values(model, theta), x[:4], geometry), span_s))
    return {**ensemble_summary(members, span_s), "width": width, "members_smoothed_5cm_s": [m[0] for m in members],
            "members_raw_5cm_s": [m[2] for m in members]}  # fmt: skip


def loss_uncertainty(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
    pendulum: Mapping[str, Any],
    start: StartStateFit,
    fits: Mapping[str, tuple[ModelFit, float]],
    central: Mapping[str, Any],
    models: Sequence[str],
    ensemble_size: int = 0,
) -> dict[str, Any]:
    """The damping-level sensitivity of ``models`` and, with ``ensemble_size`` > 0, the ensemble of every model in
    ``fits`` (model -> (fit, correlation factor F)); ``central``: each model's prediction at its fitted losses
    (:func:`~.loss_models.loss_model_predictions`)."""
    span = (n_frames - 1) * rec.track.dt

    def run_losses(values: Mapping[str, Any]) -> Any:
        return predict(runner, "damping", {**pendulum, **values}, start.state, rec, i0, n_frames, start.geometry)

    def run_member(values: Mapping[str, Any], state: np.ndarray, geometry: Mapping[str, float]) -> Any:
        return predict(runner, "member", {**pendulum, **values}, state, rec, i0, n_frames, geometry)

    key = {"pendulum": dict(pendulum), "t0": float(rec.t[i0]), "n_frames": n_frames, "state": start.state.tolist(),
           "geometry": dict(start.geometry), "covariance": np.asarray(start.covariance).tolist()}  # fmt: skip

    def model_key(model: str) -> dict[str, Any]:
        fit, factor = fits[model]
        return {**key, "model": model, "theta": fit.theta.tolist(), "cov": fit.cov(factor).tolist()}

    out: dict[str, Any] = {
        "damping_sensitivity": {
            m: cached("horizon_damping", {**model_key(m), "step": DAMPING_STEP},
                      lambda m=m: damping_sensitivity(run_losses, m, fits[m][0].theta, span, central[m]))
            for m in models
        },
        "damping_definition": "every fitted loss coefficient times (1 + delta), delta = +-1 %: the energy lost per "
                              "swing changes by about delta; slope = change of the lower bob's 5 cm horizon per 1 % "
                              "more damping (censored horizons count as the record's length: then a lower bound)",
    }
    out["damping_slope_range_s_per_percent"] = slope_range(out["damping_sensitivity"])
    if ensemble_size > 0:
        out["ensemble"] = {
            m: cached("horizon_ensemble", {**model_key(m), "size": ensemble_size, "seed": ENSEMBLE_SEED},
                      lambda m=m, f=f, factor=factor: horizon_ensemble(run_member, m, f, factor, start, span,
                                                                       ensemble_size))
            for m, (f, factor) in fits.items()
        }
        out["ensemble_definition"] = (
            f"{ensemble_size} members per model: loss parameters drawn from their fit's covariance (with the "
            "correlation factor F) and the start state and geometry from theirs; lower bob's 5 cm horizon, "
            "median and 16-84 % range; censored members count as the record's length. In-sample.")
    return out


def slope_range(sensitivity: Mapping[str, Mapping[str, Any]]) -> dict[str, Any] | None:
    """The smallest and largest size [s per 1 %] of the smoothed horizon's change with the damping level over the
    models of ``sensitivity`` (:func:`damping_sensitivity` by model), and which of them are lower bounds; None if
    empty."""
    if not sensitivity:
        return None
    sizes = {m: abs(d["smoothed_s_per_percent"]) for m, d in sensitivity.items()}
    return {"smoothed_abs_min": min(sizes.values()), "smoothed_abs_max": max(sizes.values()),
            "lower_bound_models": [m for m, d in sensitivity.items() if d["slope_is_lower_bound"]]}  # fmt: skip
