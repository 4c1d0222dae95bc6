"""The fitted loss models compared: the common residual-correlation factor, AIC/BIC rows, parameter tables,
identifiability, profile likelihoods, each mechanism's share of the loss and the fit's residuals by half
of the record (see :mod:`.fitting` for the fit itself)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.parameters import AirDragParameters, BearingParameters
from ..decay.fit import fit_model, record_correlation_factor
from ..suspension.identification import decay_shape
from .fitting import FitProblem, ModelFit, fit_loss_model
from .mechanisms import MECHANISMS, OMEGA_REG, contains, mechanisms_of, model_title, model_values, parameters_of


def common_factor(problem: FitProblem) -> float:
    """Residual-correlation factor F of the measured record
    (:func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`: the residuals about the free-exponent
    decay law), used for every model fitted to it, as ``energy_decay`` uses it for its decay laws."""
    return record_correlation_factor(problem.t, problem.energy, problem.sigma)


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


def limit_model(model: str) -> str | None:
    """The model a model reaches in the limit of its scanned parameter going to infinity (``air+suspension``:
    ``air``, the pivot held rigid by an infinitely stiff damper), or None if it has no such parameter."""
    names = [m.name for m in mechanisms_of(model) if not any(p.warm_scan for p in m.parameters)]
    return "+".join(names) if names and len(names) < len(mechanisms_of(model)) else None


def bound_entry(fit: ModelFit, fits: Sequence[ModelFit], crit: Mapping[str, tuple[float, float]],
                best_aic: float) -> dict[str, Any]:
    """What a model that did not converge because its optimum is its nested limit (:func:`limit_model`) supports:
    a bound, not a fit. Its best chi2 is the limit model's (no finite value of the scanned parameter did better),
    so its AIC at best is the limit model's plus 2 per extra parameter: ``delta_aic_at_best``. Empty if the model
    has no limit model among ``fits`` (a fit that merely stalled)."""
    limit = limit_model(fit.model)
    nested = next((f for f in fits if f.model == limit), None)
    if nested is None:
        return {}
    scanned = next(p for p in parameters_of(fit.model) if p.warm_scan)
    return {"best_is_limit_model": limit, "best_is_limit_model_in_words": model_title(limit),
            "delta_aic_at_best": crit[limit][0] + 2.0 * (fit.k - nested.k) - best_aic,
            "bound": f"no {scanned.name} tried ({scanned.warm_scan[0]:g} to {scanned.warm_scan[-1]:g} {scanned.unit},"
                     f" then Gauss-Newton) fits better than its limit {scanned.name} -> infinity, "
                     f"{model_title(limit)}: "
                     f"its best is that limit, {scanned.name} has no finite estimate, and its delta AIC is at best "
                     f"that model's plus 2 per extra parameter"}  # fmt: skip


REDUCES_TOLERANCE = 0.05
"""chi2 a converged model must gain over a model nested in it to be more than that model (:func:`reduces_to`): the
fit's own resolution (:data:`.fitting.CHI2_TOLERANCE`)."""


def reduces_to(fit: ModelFit, fits: Sequence[ModelFit], ok: Mapping[str, bool]) -> str | None:
    """The smallest converged model nested in ``fit``'s that fits as well (chi2 within :data:`REDUCES_TOLERANCE`),
    or None: a model that gains nothing over it has fitted its extra mechanism to nothing (air+viscous with its air
    drag at the lower bound is viscous damping alone) and is no candidate of its own."""
    same = [f for f in fits if f is not fit and ok[f.model] and contains(fit.model, f.model)
            and f.chi2 <= fit.chi2 + REDUCES_TOLERANCE]  # fmt: skip
    return min(same, key=lambda f: f.k).model if same else None


def comparison_rows(fits: Sequence[ModelFit], factor: float) -> list[dict[str, Any]]:
    """One row per model, sorted by the corrected AIC: parameters with errors, chi2, AIC, BIC, Akaike weight.

    Fits that did not converge (:func:`converged`) come last with Akaike weight 0: their chi2 is not
    the model's minimum, so the comparison says nothing about them; their parameters are where the fit stopped,
    without standard errors (``null_means``), and a model whose optimum is its nested limit gets the bound of
    :func:`bound_entry`."""
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
            "model_in_words": model_title(f.model),
            "parameters": parameter_table(f, factor, ok[f.model]),
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
            **({} if ok[f.model] else {"not_ranked_because": not_ranked_because(f.model),
                                       **bound_entry(f, fits, crit, best_aic)}),
            "reduces_to": reduces_to(f, fits, ok) if ok[f.model] else None,
            "parameter_correlation": f.correlation(factor).tolist() if ok[f.model] else None,
            "energy_scale_kappa": f.kappa,
            "shares": f.extra.get("shares", {}),
            **f.extra.get("decay", {}),
            "n_runs": f.n_runs,
            "fit_stopped": f.extra.get("stop", "converged"),
        }
        for f, w in zip(ordered, weights)
    ]


def parameter_table(fit: ModelFit, factor: float, converged: bool = True) -> dict[str, dict[str, Any]]:
    """Value, standard error (with the correlation factor), unit and description of each parameter; a fit that
    did not converge (``converged`` False) has its values where it stopped and no errors (None): the curvature
    there is not that of an optimum."""
    err = fit.stderr(factor)
    return {
        p.name: {"value": float(v), "stderr": float(e) if converged else None,
                 "relative_error": float(e / v) if converged else None, "unit": p.unit,
                 "description": p.description, "at_bound": bool(v <= p.bounds[0] * 1.001 or v >= p.bounds[1] / 1.001)}
        for p, v, e in zip(parameters_of(fit.model), fit.theta, err)
    }  # fmt: skip


def identifiability(fit: ModelFit, factor: float, max_rel_error: float = 0.5, max_corr: float = 0.95) -> dict[str, Any]:
    """Correlation matrix and a verdict per parameter: ``identified`` if its relative error (the
    other parameters free) is below ``max_rel_error`` and it trades off against no other parameter;
    ``strongly_correlated`` names the parameters it trades off against (|r| > ``max_corr``): the energy fixes
    their combination far better than each alone, so none of them is identified on its own, and the split of
    the loss between them is uncertain by their errors."""
    corr = fit.correlation(factor)
    rel = fit.stderr(factor) / fit.theta
    names = fit.names
    strong = {name: [names[j] for j in range(len(names)) if j != i and abs(corr[i, j]) > max_corr]
              for i, name in enumerate(names)}  # fmt: skip
    verdict = {name: bool(rel[i] < max_rel_error and not strong[name]) for i, name in enumerate(names)}
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


def inside_bounds(value: float, parameter: Any) -> float:
    """``value`` kept 1 % inside ``parameter``'s bounds (where a fit may start)."""
    return min(max(value, parameter.bounds[0] * 1.01), parameter.bounds[1] / 1.01)


def profile_point(fit: ModelFit, cov: np.ndarray, i: int, value: float) -> ProfileItem:
    """The profile point of ``fit``'s parameter ``i`` held at ``value``: the warm start of the others shifted along
    the covariance ``cov`` (the linear prediction of the profile), kept inside their bounds."""
    params = parameters_of(fit.model)
    shift = cov[:, i] / cov[i, i] * (value - fit.theta[i])
    start = [inside_bounds(v, q) for v, q in zip(fit.theta + shift, params)]
    return ProfileItem(fit.model, i, float(value), tuple(map(float, start)))


def profile_items(fit: ModelFit, factor: float, steps: Sequence[float] = PROFILE_STEPS) -> list[ProfileItem]:
    """Profile points of every parameter (kept inside its bounds) at ``steps`` standard errors from the optimum
    (:func:`profile_point`)."""
    cov = fit.cov(factor)
    return [profile_point(fit, cov, i, inside_bounds(fit.theta[i] + step * math.sqrt(cov[i, i]), p))
            for i, p in enumerate(parameters_of(fit.model)) for step in steps]


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


def decay_numbers(problem: FitProblem, e_meas: np.ndarray, e_sim: np.ndarray, factor: float) -> dict[str, float]:
    """b [1/s] of E = a exp(b t) and p of dE/dt = -k E^p fitted to the measured and simulated energies
    on the same frames with the same errors; the errors of the measured b and p with the record's
    residual-correlation factor ``factor`` (:func:`common_factor`)."""
    t, s = problem.t, problem.sigma
    exp_m = fit_model("exponential", t, e_meas, s)
    shape_m = decay_shape(t, e_meas, s, factor)
    shape_s = decay_shape(t, e_sim, s)
    return {
        "b_measured_per_s": exp_m.value("b"),
        "b_measured_stderr": exp_m.error("b") * math.sqrt(factor),
        "b_sim_per_s": fit_model("exponential", t, e_sim, s).value("b"),
        "p_measured": shape_m["p"],
        "p_measured_stderr": shape_m["p_stderr"],
        "p_sim": shape_s["p"],
    }


OMEGA_REG_DEFAULT = BearingParameters().omega_reg
"""The FMU's default omega_reg [rad/s] (parameter ``omega_reg``)."""
REGULARISATION_WIDTHS = (1e-1, OMEGA_REG, OMEGA_REG_DEFAULT)
"""omega_reg [rad/s] compared by :func:`regularisation_effect`: 10 times the fits', the fits', the FMU's default."""
REGULARISATION_REFERENCE = 1e-5
"""omega_reg [rad/s] of the reference run of :func:`regularisation_effect` (a near-sign function)."""
REGULARISATION_SETTINGS = {"rtol": 1e-10, "atol": 1e-12}
"""Tolerances of those runs: integration errors far below the differences measured."""


def regularisation_effect(problem: FitProblem, model: str, theta: Sequence[float]) -> dict[str, Any]:
    """What the width omega_reg [rad/s] of the friction sign functions tanh(omega / omega_reg) changes: ``model`` at
    ``theta`` run over the record at each width of :data:`REGULARISATION_WIDTHS` against
    :data:`REGULARISATION_REFERENCE`; per width the largest angle difference [rad], the relative change of the joint
    losses' work, the change of chi2 against the measured energy. Below |omega| ~ omega_reg the torque is
    viscous instead of constant, so the loss missing is about tau omega_reg per unit time near each reversal."""
    works = sorted({m.work for m in mechanisms_of(model)} - {"W_air"})
    outputs = ("phi1", "phi2", "E_pendulum", *works)
    values = model_values(model, theta)
    runs = {w: problem.simulate({**values, **REGULARISATION_SETTINGS, "omega_reg": w}, outputs=outputs)
            for w in (*REGULARISATION_WIDTHS, REGULARISATION_REFERENCE)}  # fmt: skip

    def chi2(run: np.ndarray) -> float:
        r, _ = problem.scaled_residuals(np.asarray(run["E_pendulum"])[problem.offsets])
        return float(r @ r)

    ref = runs[REGULARISATION_REFERENCE]
    joint_work = sum(float(ref[w][-1]) for w in works)
    def angle_difference(run: np.ndarray) -> float:
        return float(max(np.max(np.abs(run[k] - ref[k])) for k in ("phi1", "phi2")))

    rows = {f"{w:g}": {"max_angle_difference_rad": angle_difference(runs[w]),
                       "joint_work_relative_change": sum(float(runs[w][x][-1]) for x in works) / joint_work - 1.0,
                       "delta_chi2": chi2(runs[w]) - chi2(ref)}
            for w in REGULARISATION_WIDTHS}  # fmt: skip
    return {"model": model, "reference_omega_reg_rad_per_s": REGULARISATION_REFERENCE,
            "fits_omega_reg_rad_per_s": OMEGA_REG, "fmu_default_omega_reg_rad_per_s": OMEGA_REG_DEFAULT,
            "record_s": problem.duration, "by_omega_reg_rad_per_s": rows}  # fmt: skip


def air_share_at_defaults(
    problem: FitProblem, measured_loss: float, decaying: ModelFit | None = None
) -> dict[str, Any]:
    """Air drag at the default coefficients (factor 1) on the seed's pendulum, by two definitions, each with its work
    over the record [J] and its share of the measured loss (the seed gives no share: it calls air drag negligible,
    section 4.2.3):

    - ``W_air_J``, ``share_of_measured_loss``: air drag *alone* at factor 1 (no other loss), the pendulum then
      losing only that work, so it keeps a larger amplitude than the real one and air drag (force ~ v^2) works
      more;
    - ``W_air_on_measured_decay_J``, ``share_on_measured_decay``: air drag at factor 1 along a motion that decays
      as measured: the air work of ``decaying`` (a fitted model with air drag, which follows the measured energy)
      divided by its fitted air factor (on a given motion the drag force, hence its work, is proportional to the
      factor). None without such a model.
    """
    r = problem.simulate(MECHANISMS["air"].values([1.0]), outputs=("W_air",))
    w = float(r["W_air"][-1])
    out: dict[str, Any] = {"W_air_J": w, "share_of_measured_loss": w / measured_loss,
                           "cw_rod": AirDragParameters().cw_rod, "W_air_on_measured_decay_J": None,
                           "share_on_measured_decay": None, "measured_decay_model": None}  # fmt: skip
    if decaying is not None:
        factor = float(decaying.theta[decaying.names.index("air_factor")])
        run = problem.simulate(model_values(decaying.model, decaying.theta), outputs=("W_air",))
        w_decay = float(run["W_air"][-1]) / factor
        out.update(W_air_on_measured_decay_J=w_decay, share_on_measured_decay=w_decay / measured_loss,
                   measured_decay_model=decaying.model)  # fmt: skip
    out["definitions"] = ("share_of_measured_loss: air drag alone at the default coefficients (no other loss: the "
                          "pendulum keeps more amplitude, so air works more); share_on_measured_decay: air drag at the "
                          "default coefficients along the motion of measured_decay_model, which decays as measured")
    return out
