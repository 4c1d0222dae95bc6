r"""Which loss mechanisms drain the real pendulum? The loss identification of the ``loss_identification``
scenario (:func:`identify_losses`): every model (:mod:`.mechanisms`) fitted to the measured energy
(:mod:`.fitting`), compared (:mod:`.comparison`), the best one re-run through the FMU, and what the fits
support (:mod:`.claims`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.parameters import SEED_RIGID_LINKS
from ..suspension.identification import MeasuredDecay, measured_decay
from ..track.measurement import Reconstruction, load_track, reconstruct
from ..track.tilt import seed_record_geometry
from . import claims as loss_claims
from .air_profile import AIR_MODELS, EXTEND_STEPS, LEVEL, air_point, air_points, air_share_intervals
from .ar1_refit import refit_models
from .comparison import (
    air_share_at_defaults,
    common_factor,
    comparison_rows,
    decay_numbers,
    half_residuals,
    identifiability,
    parameter_table,
    profile_item,
    profile_items,
    profile_summary,
    regularisation_effect,
    share_errors,
)
from .fitting import SHORT_RUN_BUDGET, FitProblem, ModelFit, fit_models, problem_from_track, run_budget
from .holdout import HoldoutFit, holdout_fits, out_of_sample
from .mechanisms import (
    FULL_MODELS,
    MECHANISMS,
    OMEGA_REG,
    QUICK_MODELS,
    SUSPENSION_K,
    SUSPENSION_M,
    THOROUGH_MODELS,
    mechanisms_of,
    model_title,
    model_values,
    shares,
)
from .noise import noise_model_summary

REGULARISED_MODEL = "air+drag"
"""The model whose sensitivity to the friction regularisation the summary reports (``regularisation``): its drag
torque is the regularised law measured_vs_sim uses (viscous damping has no sign function to regularise)."""


def half_fits(problem: FitProblem, fits: Sequence[ModelFit], rows: Sequence[Mapping[str, Any]], quick: bool,
              pool: Any = None, max_workers: int | None = None) -> list[HoldoutFit]:
    """The out-of-sample test's fits (:func:`.holdout.holdout_fits`): every converged model of ``fits`` (``rows``:
    their :func:`.comparison.comparison_rows`) fitted to each half, with the mode's run budget (quick: the quick
    one, else :data:`.fitting.SHORT_RUN_BUDGET`)."""
    return holdout_fits(problem, converged(fits, rows), run_budget(quick) or SHORT_RUN_BUDGET, pool, max_workers)


def thorough_half_fits(rec: Reconstruction) -> tuple[FitProblem, list[HoldoutFit]]:
    """The fit problem of ``rec`` and its half fits exactly as :func:`identify_losses` obtains them with
    ``thorough`` (the same models, starts and budgets, in this process), so after that run they are read from the
    cache (``measured_vs_sim --thorough`` predicts the motion with them)."""
    problem = problem_from_track(rec, measured(rec))
    fits, _ = fit_models(THOROUGH_MODELS, problem, max_workers=1, short=False, max_runs=run_budget(False))
    return problem, half_fits(problem, fits, comparison_rows(fits, common_factor(problem)), False, max_workers=1)


def converged(fits: Sequence[ModelFit], rows: Sequence[Mapping[str, Any]]) -> list[ModelFit]:
    """The fits of the comparison ``rows``' converged models (those the criteria rank)."""
    ok = {r["model"] for r in rows if r["converged"]}
    return [f for f in fits if f.model in ok]


def measured_loss(md: MeasuredDecay) -> float:
    """Energy lost [J] over the fitted frames according to the measured exponential fit."""
    a, b = md.fit.value("a"), md.fit.value("b")
    return a * (math.exp(b * md.frames.t[0]) - math.exp(b * md.frames.t[-1]))


def seed_reconstruction(*, tilt: bool = True) -> Reconstruction:
    """The seed's track reconstructed with the rigid links :data:`SEED_RIGID_LINKS`, in the record's one geometry
    (:func:`~..track.tilt.seed_record_geometry`): turned back by the camera's tilt against gravity; ``tilt=False``:
    the untilted track as the camera saw it (the named variant, same pivot and lengths)."""
    rg = seed_record_geometry()
    return reconstruct(load_track(), rg.geometry if tilt else rg.untilted, rods=SEED_RIGID_LINKS)


def measured(rec: Reconstruction | None = None, window_s: float | None = None) -> MeasuredDecay:
    """The measured decay after the release of a reconstruction (default: :func:`seed_reconstruction`),
    optionally only the first ``window_s`` seconds [s]."""
    return measured_decay(seed_reconstruction() if rec is None else rec, window_s)


# --- the whole identification --------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class LossIdentification:
    """Everything the scenario writes: the summary and the arrays of its table and figures."""

    summary: dict[str, Any]
    t: np.ndarray
    e_measured: np.ndarray
    sigma: np.ndarray
    e_sim: np.ndarray
    works: dict[str, np.ndarray]


SUSPENSION_WOULD_CHANGE = (
    "another stiffness k or suspension mass M_s (assumed, not measured: suspension_transfer maps the decay rate "
    "over k and the damping c)",
    "another suspension law: a stiff suspension loses about c <|dF/dt|^2> / k^2, so only the combination c / k^2 "
    "is tested here, at one k",
    "another part of the record (only the whole record is fitted here; a fit to a shorter window weighs the early, "
    "larger swings more)",
)
"""What the suspension verdict of :func:`suspension_answer` is conditional on: what could change it."""


def suspension_verdict(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """The suspension's verdict as a conditional statement, not a bare yes/no: ``verdict`` ("main loss" if the model
    with the lowest AIC loses more than half its energy in the suspension, else "not the main loss"), ``holds_at``
    (the fixed k [N/m] and M_s [kg], the record fitted, the criterion), the suspension's share in the top model and
    where it is fitted, the bound of air drag + suspension (``loss_claims.suspension_bound``) and
    ``would_change_it`` (:data:`SUSPENSION_WOULD_CHANGE`). None when no fitted model has a suspension (quick)."""
    label = MECHANISMS["suspension"].label
    if not any("suspension" in r["model"].split("+") for r in rows):
        return None
    best = rows[0]
    share = best["shares"].get(label, 0.0)
    bound = loss_claims.suspension_bound(rows)
    return {
        "verdict": "main loss" if share > 0.5 else "not the main loss",
        "holds_at": {"k_N_per_m": SUSPENSION_K, "M_s_kg": SUSPENSION_M, "record": "the whole measured record",
                     "criterion": "the suspension's share of the loss in the model with the lowest AIC > 50 %"},
        "top_model": best["model"],
        "suspension_share_in_top_model": share,
        "delta_aic_at_best_of_air_and_suspension": None if bound is None else bound["delta_aic_at_best"],
        "would_change_it": list(SUSPENSION_WOULD_CHANGE),
    }


def suspension_answer(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Does the suspension dominate the loss? A conditional verdict (:func:`suspension_verdict`: at the assumed k and
    M_s, on the whole record), the suspension's share in every model that has it and a plain sentence that says the
    conditions; not asked (verdict ``None``) when no fitted model has a suspension (the quick run)."""
    label = MECHANISMS["suspension"].label
    verdict = suspension_verdict(rows)
    if verdict is None:
        return {"suspension_verdict": None, "suspension_share_by_model": {},
                "answer": "Not tested: no model with a suspension was fitted in this run (quick mode fits "
                          "air+drag alone); the default run fits air+suspension."}  # fmt: skip
    with_susp = {r["model"]: r["shares"].get(label) for r in rows if label in r["shares"] and r["converged"]}
    best = rows[0]
    at = f"at the assumed k = {SUSPENSION_K:g} N/m and M_s = {SUSPENSION_M:g} kg, on the whole record"
    if verdict["verdict"] == "main loss":
        text = (f"At these conditions, yes ({at}): the model with the lowest AIC ({model_title(best['model'])}) loses "
                f"{verdict['suspension_share_in_top_model']:.0%} of its energy in the suspension.")
    else:
        parts = ", ".join(f"{m}: {s:.0%} (delta AIC {next(r['delta_aic'] for r in rows if r['model'] == m):.1f})"
                          for m, s in with_susp.items())  # fmt: skip
        if label in best["shares"]:
            text = (f"Not the main loss {at}: the suspension carries {best['shares'][label]:.0%} of the loss in the "
                    "model with the lowest AIC")
        else:
            text = (f"Not the main loss {at}: the model with the lowest AIC ({model_title(best['model'])}) has no "
                    "suspension")
        text += f"; suspension share where it is fitted: {parts}." if parts else "."
    bound = loss_claims.suspension_bound(rows)
    if bound is not None:
        text += (f" As the main loss ({bound['model_in_words']}) the suspension has no finite optimum at these k and "
                 f"M_s: {bound['statement']}; so it fits worse than the lowest AIC by at least delta AIC "
                 f"{bound['delta_aic_at_best']:.0f}, at these k and M_s only.")
    text += " What would change it: " + "; ".join(SUSPENSION_WOULD_CHANGE) + "."
    return {"suspension_verdict": verdict, "answer": text, "suspension_share_by_model": with_susp}


def _air_model_on_measured_decay(fits: Sequence[Any], rows: Sequence[Mapping[str, Any]]) -> Any:
    """The converged model with air drag and the lowest AIC among those within delta AIC 2 (it follows the measured
    energy), for :func:`~.comparison.air_share_at_defaults`; None if there is none."""
    supported = loss_claims.supported_models(rows)["models"]
    for r in rows:  # rows are in AIC order
        if r["model"] in supported and r["converged"] and "air" in r["model"].split("+"):
            return next(f for f in fits if f.model == r["model"])
    return None


def air_share_profile(problem: FitProblem, fits: Sequence[ModelFit], rows: Sequence[Mapping[str, Any]],
                      factor: float, pool: Any = None, max_workers: int | None = None) -> dict[str, Any]:
    """Air drag's share as a profile-likelihood interval (:mod:`.air_profile`) over the converged models of ``rows``
    with air drag beside a bearing loss; the points fitted on ``pool``."""
    from ..sweep import parallel_map  # noqa: PLC0415 - process pools only when identifying

    best = min(r["chi2"] for r in rows if r["converged"])  # a model whose own optimum lies beyond the level: no share
    converged_models = [r["model"] for r in rows if r["converged"] and r["model"] in AIR_MODELS
                        and (r["chi2"] - best) / factor <= LEVEL]  # fmt: skip
    items = air_points(fits, factor, converged_models)
    results, _ = parallel_map(air_point, items, shared=problem, max_workers=max_workers, label="air share profile",
                              pool=pool)  # fmt: skip
    first = air_share_intervals(fits, rows, factor, items, results)
    open_top = [m for m, d in first["models"].items() if d["share_interval"] and d["share_interval"][1] is None]
    if open_top:  # a flat profile: further points above the optimum
        more = air_points(fits, factor, open_top, EXTEND_STEPS)
        extra, _ = parallel_map(air_point, more, shared=problem, max_workers=max_workers, label="air share profile",
                                pool=pool)  # fmt: skip
        items, results = [*items, *more], [*results, *extra]
    return air_share_intervals(fits, rows, factor, items, results)


def untilted_identification(rec: Reconstruction, pool: Any = None, max_workers: int | None = None) -> dict[str, Any]:
    """The default identification's comparison on another reconstruction (the untilted track): the models within
    delta AIC 2 under F and under AR(1), each model's delta AIC, delta BIC and air share, and the air share's
    profile interval (the thorough run's named variant)."""
    problem = problem_from_track(rec, measured(rec))
    fits, _ = fit_models(FULL_MODELS, problem, max_workers, pool, max_runs=run_budget(False))
    factor = common_factor(problem)
    rows = comparison_rows(fits, factor)
    noise = noise_model_summary(rows, {f.model: f.residuals for f in fits}, problem.sigma, factor,
                                refit_models(converged(fits, rows), problem, pool, max_workers))
    return {"tilt_deg": math.degrees(rec.geometry.tilt), "correlation_factor_F": factor,
            "supported_models": loss_claims.supported_models(rows), "ties": noise["ties"],
            "air_share_range": noise["air_share_range"], "noise_model": noise,
            "models": {r["model"]: {"delta_aic": r["delta_aic"], "delta_bic": r["delta_bic"], "shares": r["shares"],
                                    "converged": r["converged"]} for r in rows},
            "air_share_profile": air_share_profile(problem, fits, rows, factor, pool, max_workers)}  # fmt: skip


def goal_checks(numbers: Mapping[str, float], halves: Mapping[str, Any]) -> dict[str, Any]:
    """The issue's goal: b_sim within 2 % of b_measured, p_sim within 2 p_measured_stderr, no trend."""
    b_dev = numbers["b_sim_per_s"] / numbers["b_measured_per_s"] - 1.0
    p_dev = (numbers["p_sim"] - numbers["p_measured"]) / numbers["p_measured_stderr"]
    checks = {
        "b_relative_deviation": b_dev,
        "b_within_2_percent": bool(abs(b_dev) <= 0.02),
        "p_deviation_in_stderr": p_dev,
        "p_within_2_stderr": bool(abs(p_dev) <= 2.0),
        "no_trend_between_halves": not halves["trend"],
    }
    checks["met"] = all(checks[k] for k in ("b_within_2_percent", "p_within_2_stderr", "no_trend_between_halves"))
    return checks


def identify_losses(
    runner: Any, *, quick: bool = False, thorough: bool = False, max_workers: int | None = None,
    record: Any = None,
) -> LossIdentification:
    """Fit every model (:data:`FULL_MODELS`; thorough: :data:`THOROUGH_MODELS`; quick: :data:`QUICK_MODELS`,
    in this process, at :data:`QUICK_SIM_SETTINGS` with :data:`QUICK_RUN_BUDGET` runs: one Gauss-Newton
    step) in parallel with the in-process component, compare them, profile the best one (thorough mode only:
    in the runs so far its intervals matched the curvature errors, for 8 more fits, about 18 s of CPU) and
    re-run it through ``runner`` (the FMU) for the headline numbers. One pool of worker processes serves
    every round and the profile. All modes fit the whole record (the first 8 s alone leave the losses
    unidentified); the fits are cached (:func:`fit_loss_model`), and ``measured_vs_sim`` obtains its
    ``air+drag`` by :func:`identified_fit` from the same problem (:func:`problem_from_track` in the same
    mode: the same start, budget and settings), so it reads this mode's fit. The AR(1) criteria
    (:func:`.noise.noise_model_summary`) come from every converged model re-fitted under the AR(1) likelihood
    (:func:`.ar1_refit.refit_models`, default and thorough mode; quick: at the least-squares optimum); the
    out-of-sample test (:mod:`.holdout`: every converged model fitted to each half, 12 runs a fit, quick: the
    quick budget) runs in the thorough and the quick mode only."""
    from ..sweep import parallel_map, worker_pool  # noqa: PLC0415 - process pools only when identifying

    seed = record is None
    rec = seed_reconstruction() if seed else record.reconstruction()
    md = measured(rec)
    problem = problem_from_track(rec, md, quick=quick)
    models = QUICK_MODELS if quick else THOROUGH_MODELS if thorough else FULL_MODELS
    profile: dict[str, Any] = {}
    max_workers = 1 if quick else max_workers  # one model: no worker processes to start
    with worker_pool(max_workers) as pool:
        fits, workers = fit_models(models, problem, max_workers, pool, short=not thorough, max_runs=run_budget(quick))
        factor = common_factor(problem)
        rows = comparison_rows(fits, factor)
        best = next(f for f in fits if f.model == rows[0]["model"])
        refits = None if quick else refit_models(converged(fits, rows), problem, pool, max_workers)
        noise = noise_model_summary(rows, {f.model: f.residuals for f in fits}, problem.sigma, factor, refits)
        for r in rows:
            r["ar1"] = {k: noise["criteria"][r["model"]][k] for k in ("rho", "aic", "bic", "delta_aic", "delta_bic")
                        } if r["model"] in noise["criteria"] else None  # fmt: skip
        air = None if quick else air_share_profile(problem, fits, rows, factor, pool, max_workers)
        untilted = None
        if thorough:  # the same identification on the untilted track: what the tilt changes (about 50 s of CPU)
            untilted = untilted_identification(seed_reconstruction(tilt=False) if seed
                                               else record.reconstruction(tilt=False), pool, max_workers)
        holdout = None
        if quick or thorough:  # the default run: +86 % wall time (109 s to 203 s), so thorough (and quick) only
            holdout = out_of_sample(problem, half_fits(problem, fits, rows, quick, pool, max_workers))
        if thorough:
            items = profile_items(best, factor)
            chi2s, _ = parallel_map(profile_item, items, shared=problem, max_workers=max_workers, label="profile",
                                    pool=pool)  # fmt: skip
            profile = profile_summary(best, factor, items, chi2s)
    works = sorted({m.work for m in mechanisms_of(best.model)})
    result = problem.simulate(model_values(best.model, best.theta), outputs=("E_pendulum", *works), runner=runner)
    e_sim = np.asarray(result["E_pendulum"])[problem.offsets]
    _, kappa = problem.scaled_residuals(e_sim)
    numbers = decay_numbers(problem, problem.energy, e_sim, factor)
    halves = half_residuals(problem, e_sim, kappa, factor)
    loss = measured_loss(md)
    drag_fit = next((f for f in fits if f.model == REGULARISED_MODEL), None)
    regularisation = (None if quick or drag_fit is None
                      else regularisation_effect(problem, drag_fit.model, drag_fit.theta))
    summary = {
        "scenario": "loss_identification",
        "source": ("seed Table 1 (data/seed_table1.csv), rigid links SEED_RIGID_LINKS" if seed
                   else f"{record.name}: a user's own record"),
        **({} if seed else {"record": record.describe()}),
        "pendulum": {k: getattr(rec.params, k) for k in ("m1", "m2", "l1", "l2", *SEED_RIGID_LINKS)},
        "t0_s": problem.t0,
        "record_s": float(problem.t[-1] - problem.t[0]),
        "n_frames": len(problem.t),
        "quick": quick,
        "thorough": thorough,
        "models_fitted": list(models),
        "workers": workers,
        "top_model": best.model,
        "top_model_means": "the lowest AIC; models within delta AIC 2 (supported_models) fit about as well, so "
                           "b_sim_per_s, p_sim, parameters and top_model_shares are the top model's, not a verdict",
        **numbers,
        "top_model_shares": shares(result, best.model),
        "top_model_shares_stderr": share_errors(best, shares(result, best.model), factor),
        "parameters": parameter_table(best, factor),
        "identifiability": identifiability(best, factor),
        "profile_likelihood": profile,
        "energy_scale_kappa": kappa,
        "correlation_factor_F": factor,
        "correlation_factor_from": "the record's residuals about the free-exponent decay law dE/dt = -k E^p "
                                   "(decay.fit.record_correlation_factor), the same F for every model",
        "supported_from_factor": loss_claims.supported_from_factor(rows, factor),
        "noise_model": noise,
        "out_of_sample": holdout,
        "air_share_profile": air,
        "untilted_track": untilted,
        "residual_halves": halves,
        "goal": goal_checks(numbers, halves),
        "measured_loss_J": loss,
        "simulated_loss_J": float(sum(float(result[w][-1]) for w in works)),
        **suspension_answer(rows),
        "suspension_as_main_loss": loss_claims.suspension_bound(rows),
        "supported_models": loss_claims.supported_models(rows),
        "b_sim_range_all_models_per_s": loss_claims.b_sim_range(rows),
        "load_proportional_friction_against_seed": loss_claims.seed_friction_coefficient(rows) if seed else None,
        "drag_torque_against_seed_rolling_friction": next(
            (loss_claims.seed_rolling_friction(rec.params, r["parameters"]["tau_b"]["value"]) for r in rows
             if r["model"] == "air+drag"), None) if seed else None,
        "air_drag_at_defaults": air_share_at_defaults(problem, loss, _air_model_on_measured_decay(fits, rows)),
        "models": rows,
        "suspension_fixed": {"k_N_per_m": SUSPENSION_K, "M_s_kg": SUSPENSION_M},
        "omega_reg_rad_per_s": OMEGA_REG,
        "regularisation": regularisation,
        "null_means": {"suspension_verdict": "not tested: no model with a suspension was fitted (quick mode)",
                       "suspension_as_main_loss": "not fitted (quick mode), or air+suspension converged to a "
                                                  "finite damping",
                       "stderr": "models[...].parameters of a model that did not converge: values where its fit "
                                 "stopped, no standard errors",
                       "relative_error": "as stderr: a model that did not converge has no standard errors",
                       "reduces_to": "the model fits better than every converged model nested in it (or it did not "
                                     "converge)",
                       "parameter_correlation": "a model that did not converge: no curvature of an optimum",
                       "supported_from_factor": "a model that joins the supported set at no F up to 10",
                       "regularisation": "not measured in the quick run",
                       "ar1": "models[...].ar1 of a model that did not converge: no likelihood of an optimum",
                       "out_of_sample": "not run: the half-record test runs with --thorough (and --quick, one model "
                                        "as a smoke run); it would add about 85 % to the default run's time",
                       "air_share_profile": "not profiled in the quick run",
                       "share_interval": "air_share_profile: no share of that model comes within Delta(-2 ln L) <= 4 "
                                         "of the best fit, or (an end) the profile stays below it beyond the "
                                         "profiled points",
                       "untilted_track": "the identification on the untilted track runs with --thorough only (about "
                                         "50 s more CPU)",
                       "profile_likelihood": "empty: profiled with --thorough only (its intervals matched the "
                                             "curvature errors in the runs so far)",
                       **({} if seed else {
                           "load_proportional_friction_against_seed": "a user's record: the seed's bearing values "
                                                                      "are not this pendulum's",
                           "drag_torque_against_seed_rolling_friction": "a user's record: the seed's bearing values "
                                                                        "are not this pendulum's"})},
        "start_state": {k: problem.base[k] for k in ("phi1_0", "phi2_0", "omega1_0", "omega2_0")},
    }
    t = problem.t
    return LossIdentification(summary, t, problem.energy, problem.sigma, kappa * e_sim,
                              {w: np.asarray(result[w])[problem.offsets] for w in works})  # fmt: skip
