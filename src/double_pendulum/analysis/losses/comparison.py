"""The fitted loss models compared: the common residual-correlation factor, AIC/BIC rows, parameter tables,
identifiability, profile likelihoods, each mechanism's share of the loss and the fit's residuals by half
of the record (see :mod:`.fitting` for the fit itself)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.parameters import AirDragParameters
from ..decay.fit import MODELS, effective_sample_factor, fit_model
from ..suspension.identification import decay_shape
from .fitting import FitProblem, ModelFit, fit_loss_model
from .mechanisms import LAG_FRAMES, MECHANISMS, contains, mechanisms_of, parameters_of


def common_factor(fits: Sequence[ModelFit]) -> float:
    """Residual-correlation factor F of the best-fitting model (lowest chi2), used for all."""
    best = min(fits, key=lambda f: f.chi2)
    return effective_sample_factor(best.residuals, LAG_FRAMES)


CONVERGENCE_TOLERANCE = 0.5
"""chi2 a model may end above the best model nested in it before its fit counts as not converged."""


def converged(fit: ModelFit, fits: Sequence[ModelFit]) -> bool:
    """False if a model nested in ``fit``'s (a subset of its mechanisms) reached a lower chi2 by more
    than :data:`CONVERGENCE_TOLERANCE`: the larger model contains that optimum, so its own fit stalled."""
    nested = [f.chi2 for f in fits if f is not fit and contains(fit.model, f.model)]
    return not nested or fit.chi2 <= min(nested) + CONVERGENCE_TOLERANCE


def not_ranked_because(model: str) -> str:
    """Why a model whose chi2 ended above a nested model's (:func:`converged`) is not ranked: a mechanism
    with a ``warm_scan`` (the suspension) reaches its nested limit only outside the scanned values;
    any other fit stalled."""
    scanned = [p for p in parameters_of(model) if p.warm_scan]
    if not scanned:
        return "the fit stalled: chi2 above a model nested in it"
    p = scanned[0]
    return (f"chi2 above the model nested in it for every {p.name} tried ({p.warm_scan[0]:g} to "
            f"{p.warm_scan[-1]:g} {p.unit}, then Gauss-Newton): the nested model is its limit {p.name} -> infinity")


def comparison_rows(fits: Sequence[ModelFit], factor: float) -> list[dict[str, Any]]:
    """One row per model, sorted by the corrected AIC: parameters with errors, chi2, AIC, BIC, Akaike weight.

    Fits that did not converge (:func:`converged`) come last with Akaike weight 0: their chi2 is not
    the model's minimum, so the comparison says nothing about them."""
    crit = {f.model: f.criteria(factor) for f in fits}
    ok = {f.model: converged(f, fits) for f in fits}
    ordered = sorted(fits, key=lambda f: (not ok[f.model], crit[f.model][0]))
    best_aic = crit[ordered[0].model][0]
    best_bic = min(crit[m][1] for m in crit if ok[m])
    weights = np.array([math.exp(-0.5 * (crit[f.model][0] - best_aic)) if ok[f.model] else 0.0 for f in ordered])
    weights /= weights.sum()
    return [
        {
            "model": f.model,
            "parameters": parameter_table(f, factor),
            "chi2": f.chi2,
            "chi2_red": f.chi2 / (f.n - f.k),
            "n_frames": f.n,
            "k": f.k,
            "aic": crit[f.model][0],
            "bic": crit[f.model][1],
            "delta_aic": crit[f.model][0] - best_aic,
            "delta_bic": crit[f.model][1] - best_bic,
            "akaike_weight": float(w),
            "converged": ok[f.model],
            **({} if ok[f.model] else {"not_ranked_because": not_ranked_because(f.model)}),
            "energy_scale_kappa": f.kappa,
            "shares": f.extra.get("shares", {}),
            **f.extra.get("decay", {}),
            "n_runs": f.n_runs,
            "fit_stopped": f.extra.get("stop", "converged"),
        }
        for f, w in zip(ordered, weights)
    ]


def parameter_table(fit: ModelFit, factor: float) -> dict[str, dict[str, Any]]:
    """Value, standard error (with the correlation factor), unit and description of each parameter."""
    err = fit.stderr(factor)
    return {
        p.name: {"value": float(v), "stderr": float(e), "relative_error": float(e / v), "unit": p.unit,
                 "description": p.description, "at_bound": bool(v <= p.bounds[0] * 1.001 or v >= p.bounds[1] / 1.001)}
        for p, v, e in zip(parameters_of(fit.model), fit.theta, err)
    }  # fmt: skip


def identifiability(fit: ModelFit, factor: float, max_rel_error: float = 0.5, max_corr: float = 0.95) -> dict[str, Any]:
    """Correlation matrix and a verdict per parameter: ``identified`` if its relative error (the
    other parameters free) is below ``max_rel_error``; ``strongly_correlated`` names the parameters
    it trades off against (|r| > ``max_corr``): the energy fixes their combination far better than
    each alone, and the split of the loss between them is uncertain by their errors."""
    corr = fit.correlation(factor)
    rel = fit.stderr(factor) / fit.theta
    names = fit.names
    verdict = {name: bool(rel[i] < max_rel_error) for i, name in enumerate(names)}
    strong = {name: [names[j] for j in range(len(names)) if j != i and abs(corr[i, j]) > max_corr]
              for i, name in enumerate(names)}  # fmt: skip
    return {"parameters": names, "correlation": corr.tolist(), "identified": verdict, "strongly_correlated": strong}


# --- profile likelihood --------------------------------------------------------------------------

PROFILE_STEPS: tuple[float, ...] = (-2.0, -1.0, 1.0, 2.0)
"""Profile points in standard errors from the optimum."""


@dataclass(frozen=True)
class ProfileItem:
    """One profile point: parameter index, its value, warm start of the others."""

    model: str
    index: int
    value: float
    start: tuple[float, ...]


def profile_item(item: ProfileItem, problem: FitProblem) -> float:
    """chi2 at a profile point (other parameters re-fitted; :func:`parallel_map` worker)."""
    fit = fit_loss_model(item.model, problem, fixed={item.index: item.value}, start=item.start, max_nfev=20)
    return fit.chi2


def profile_items(fit: ModelFit, factor: float, steps: Sequence[float] = PROFILE_STEPS) -> list[ProfileItem]:
    """Profile points of every parameter (kept inside its bounds); warm starts of the others shifted
    along the covariance (the linear prediction of the profile)."""
    cov = fit.cov(factor)
    params = parameters_of(fit.model)
    items = []
    for i, p in enumerate(params):
        s = math.sqrt(cov[i, i])
        for step in steps:
            value = min(max(fit.theta[i] + step * s, p.bounds[0] * 1.01), p.bounds[1] / 1.01)
            shift = cov[:, i] / cov[i, i] * (value - fit.theta[i])
            start = [min(max(v, q.bounds[0] * 1.01), q.bounds[1] / 1.01) for v, q in zip(fit.theta + shift, params)]
            items.append(ProfileItem(fit.model, i, float(value), tuple(map(float, start))))
    return items


def profile_summary(fit: ModelFit, factor: float, items: Sequence[ProfileItem], chi2s: Sequence[float]) -> dict:
    """Per parameter: values, delta chi2 / F, and the interval where it stays below 1 (interpolated)."""
    out: dict[str, Any] = {}
    for i, name in enumerate(fit.names):
        pts = [(it.value, c) for it, c in zip(items, chi2s) if it.index == i]
        pts = sorted([*pts, (float(fit.theta[i]), fit.chi2)])
        values = [v for v, _ in pts]
        delta = [(c - fit.chi2) / factor for _, c in pts]
        out[name] = {
            "values": values,
            "delta_chi2_over_F": delta,
            "interval_1sigma": _profile_interval(values, delta),
            "curvature_stderr": float(fit.stderr(factor)[i]),
        }
    return out


def _profile_interval(values: Sequence[float], delta: Sequence[float]) -> list[float | None]:
    """Values where delta chi2 / F crosses 1 on either side of the minimum (linear interpolation)."""
    k = int(np.argmin(delta))
    bounds: list[float | None] = []
    for rng in (range(k, 0, -1), range(k, len(values) - 1)):
        found = None
        for j in rng:
            a, b = (j, j - 1) if rng.step == -1 else (j, j + 1)
            if delta[a] < 1.0 <= delta[b]:
                f = (1.0 - delta[a]) / (delta[b] - delta[a])
                found = float(values[a] + f * (values[b] - values[a]))
                break
        bounds.append(found)
    return bounds


# --- the best model's loss budget and decay shape ------------------------------------------------


def share_errors(fit: ModelFit, model_shares: Mapping[str, float], factor: float) -> dict[str, float]:
    """First-order standard errors of the shares [1]: a mechanism's work at fixed motion is proportional
    to its (single) coefficient and the data fix the total, so sigma_share = share x relative error of
    that coefficient (mechanisms with two coefficients: the larger relative error)."""
    rel = dict(zip(fit.names, fit.stderr(factor) / fit.theta))
    out = {}
    for mech in mechanisms_of(fit.model):
        r = max(rel[p.name] for p in mech.parameters)
        out[mech.label] = float(model_shares[mech.label] * r)
    return out


def half_residuals(problem: FitProblem, e_sim: np.ndarray, kappa: float, factor: float) -> dict[str, Any]:
    """Mean residual E_sim - E_meas [J] over the first and second half of the frames, errors sqrt(F) s/sqrt(n)."""
    d = kappa * e_sim - problem.energy
    half = len(d) // 2
    out = {}
    for name, part in (("first_half", d[:half]), ("second_half", d[half:])):
        out[name] = {"mean_J": float(np.mean(part)),
                     "stderr_J": float(np.std(part, ddof=1) * math.sqrt(factor / len(part)))}  # fmt: skip
    diff = out["second_half"]["mean_J"] - out["first_half"]["mean_J"]
    err = math.hypot(out["first_half"]["stderr_J"], out["second_half"]["stderr_J"])
    out["difference_J"] = diff
    out["difference_stderr_J"] = err
    out["trend"] = bool(abs(diff) > 2.0 * err)
    return out


def decay_numbers(problem: FitProblem, e_meas: np.ndarray, e_sim: np.ndarray) -> dict[str, float]:
    """b [1/s] of E = a exp(b t) and p of dE/dt = -k E^p fitted to the measured and simulated energies
    on the same frames with the same errors; p's error with the residual-correlation factor."""
    t, s = problem.t, problem.sigma
    power = fit_model("power", t, e_meas, s)
    r_pow = (e_meas - MODELS["power"].func(t, *power.params)) / s
    f_pow = effective_sample_factor(r_pow, LAG_FRAMES)
    exp_m = fit_model("exponential", t, e_meas, s)
    r_exp = (e_meas - MODELS["exponential"].func(t, *exp_m.params)) / s
    f_exp = effective_sample_factor(r_exp, LAG_FRAMES)
    shape_m = decay_shape(t, e_meas, s, f_pow)
    shape_s = decay_shape(t, e_sim, s)
    return {
        "b_measured_per_s": exp_m.value("b"),
        "b_measured_stderr": exp_m.error("b") * math.sqrt(f_exp),
        "b_sim_per_s": fit_model("exponential", t, e_sim, s).value("b"),
        "p_measured": shape_m["p"],
        "p_measured_stderr": shape_m["p_stderr"],
        "p_sim": shape_s["p"],
    }


def air_share_at_defaults(problem: FitProblem, measured_loss: float) -> dict[str, float]:
    """Air drag at the default coefficients (factor 1) on the seed's pendulum: its work over the record [J]
    and its share of the measured loss (the seed gives no share: it calls air drag negligible, section 4.2.3)."""
    r = problem.simulate(MECHANISMS["air"].values([1.0]), outputs=("W_air",))
    w = float(r["W_air"][-1])
    return {"W_air_J": w, "share_of_measured_loss": w / measured_loss, "cw_rod": AirDragParameters().cw_rod}
