r"""Out-of-sample test of the loss models: fit one half of the record, predict the other half's energy.

The record's frames (:class:`.fitting.FitProblem`) are split at the middle frame into a first and a second
half (:func:`half_problem`: the same start state at t0 and the same simulation, only the fitted frames
differ). Each model is fitted to one half (:func:`.fitting.fit_loss_model`, started from its fit to the whole
record and from its nested models' fits to the same half, :func:`holdout_fits`), then run over the whole record
with those parameters and that half's calibration kappa, and its energy compared with the other half's frames,
which the fit never saw. Each direction is scored on the held-out frames by

* the plain :math:`\chi^2/n` of the normalised residuals :math:`r_i = (\kappa E^{sim}_i - E_i)/\sigma_i`;
* the AR(1) :math:`\chi^2/n`, :math:`Q(\rho)/n` (:func:`.noise.whitened_chi2`) with :math:`\rho` of the fit's
  residuals on its own half (the noise model is the training half's, not re-fitted to the test data);
* the predictive :math:`-2\ln L` of the AR(1) model with the training half's :math:`\rho` and :math:`s^2`
  (:func:`.noise.neg2_log_likelihood`): the ranking score; models within :data:`PREDICTIVE_TIE` of the lowest
  predict equally well;
* the mean residual :math:`\overline{\kappa E^{sim} - E}` [J], its error :math:`sd\,\sqrt{(1+\rho)/(1-\rho)/n}`.

The start state at t0 is fitted from the first frames after the release (:func:`.fitting.problem_from_track`)
in both directions: the prediction of the first half from the second is not free of the first half's data.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...runs.result_cache import cached
from .fitting import FitProblem, ModelFit, fit_loss_model, warm_starts
from .mechanisms import contains, model_rank, model_title, model_values
from .noise import ar1_criteria, ar1_factor, ar1_fit, neg2_log_likelihood, whitened_chi2

HALVES = ("first", "second")
"""The halves a model is fitted to; it predicts the other one."""
PREDICTIVE_TIE = 2.0
"""Models whose predictive -2 ln L lies within this of the lowest predict the held-out half equally well (the
scale of dAIC 2)."""


def other(half: str) -> str:
    """The half a fit to ``half`` predicts."""
    return HALVES[1 - HALVES.index(half)]


def half_slice(problem: FitProblem, half: str) -> slice:
    """The frames of ``half`` (``first``: before the middle frame, ``second``: from it on)."""
    h = len(problem.offsets) // 2
    return slice(0, h) if half == "first" else slice(h, None)


def half_problem(problem: FitProblem, half: str) -> FitProblem:
    """``problem`` restricted to the frames of ``half``: same t0, start state and settings."""
    s = half_slice(problem, half)
    return replace(problem, offsets=problem.offsets[s], t=problem.t[s], energy=problem.energy[s],
                   sigma=problem.sigma[s])  # fmt: skip


@dataclass(frozen=True)
class HoldoutItem:
    """A model to fit to one half, its candidate starts (the fit starts from the one with the lowest chi2), budget."""

    model: str
    half: str
    starts: tuple[tuple[float, ...], ...]
    max_nfev: int


@dataclass(frozen=True, eq=False)
class HoldoutFit:
    """A model fitted to one half (``fit``) and its energy E_sim [J] over the whole record's frames at that fit."""

    half: str
    fit: ModelFit
    e_sim: np.ndarray


def holdout_fit(item: HoldoutItem, problem: FitProblem) -> HoldoutFit:
    """Fit ``item.model`` to ``item.half`` of ``problem`` and run it over the whole record (a
    :func:`~double_pendulum.analysis.sweep.parallel_map` worker; the fit is cached by :func:`fit_loss_model`)."""
    part = half_problem(problem, item.half)
    chi2 = [float(np.sum(part.residuals(item.model, s) ** 2)) for s in item.starts] if len(item.starts) > 1 else [0.0]
    fit = fit_loss_model(item.model, part, start=item.starts[int(np.argmin(chi2))], max_nfev=item.max_nfev)
    key = {"model": item.model, "theta": [float(v) for v in fit.theta], "problem": problem.digest()}
    e_sim = cached("loss_holdout_runs", key, lambda: np.asarray(
        problem.simulate(model_values(item.model, fit.theta))["E_pendulum"])[problem.offsets])  # fmt: skip
    return HoldoutFit(item.half, fit, e_sim)


def holdout_fits(problem: FitProblem, fits: Sequence[ModelFit], max_runs: int, pool: Any = None,
                 max_workers: int | None = None) -> list[HoldoutFit]:
    """Every model of ``fits`` (the whole-record fits) fitted to each half, in rounds by :func:`model_rank` like
    the identification: each from its whole-record optimum and, for a model with nested ones, from their fits to
    the same half (:func:`warm_starts`), so a pair can reach a corner (one loss near zero) the whole-record
    optimum lies far from; ``max_runs`` runs a fit."""
    from ..sweep import parallel_map  # noqa: PLC0415 - process pools only when identifying

    done: list[HoldoutFit] = []
    for rank in sorted({model_rank(f.model) for f in fits}):
        items = []
        for f in (f for f in fits if model_rank(f.model) == rank):
            for half in HALVES:
                nested = [h.fit for h in done if h.half == half and contains(f.model, h.fit.model)]
                starts = [tuple(map(float, f.theta))] + [s for p in nested for s in warm_starts(f.model, p)]
                items.append(HoldoutItem(f.model, half, tuple(dict.fromkeys(starts)), max_runs))
        more, _ = parallel_map(holdout_fit, items, shared=problem, max_workers=max_workers, label="out of sample",
                               pool=pool)  # fmt: skip
        done += more
    return done


def prediction_score(problem: FitProblem, h: HoldoutFit) -> dict[str, Any]:
    """The scores of the module docstring of one fit's prediction of the other half, with its parameters."""
    test = half_slice(problem, other(h.half))
    d = h.fit.kappa * h.e_sim[test] - problem.energy[test]
    r = d / problem.sigma[test]
    noise = ar1_fit(h.fit.residuals)
    n = len(r)
    return {"fitted_on": h.half, "predicts": other(h.half), "n_frames": n,
            "theta": dict(zip(h.fit.names, map(float, h.fit.theta))), "kappa": h.fit.kappa,
            "chi2_per_frame": float(r @ r) / n, "ar1_chi2_per_frame": whitened_chi2(r, noise.rho) / n,
            "rho_training": noise.rho, "s2_training": noise.s2,
            "predictive_neg2_log_likelihood": neg2_log_likelihood(r, noise.rho, noise.s2),
            "mean_residual_J": float(np.mean(d)),
            "mean_residual_stderr_J": float(np.std(d, ddof=1) * math.sqrt(ar1_factor(noise.rho) / n)),
            "fit_stopped": h.fit.extra.get("stop", "converged"), "n_runs": h.fit.n_runs}  # fmt: skip


def ranking(scores: Mapping[str, Mapping[str, Any]], key: str) -> dict[str, Any]:
    """Models by ``key`` (lowest first) with its difference to the lowest and those within :data:`PREDICTIVE_TIE`."""
    order = sorted(scores, key=lambda m: scores[m][key])
    low = scores[order[0]][key]
    return {"order": order, "delta": {m: scores[m][key] - low for m in order},
            "tie": [m for m in order if scores[m][key] - low < PREDICTIVE_TIE]}


def out_of_sample(problem: FitProblem, hfits: Sequence[HoldoutFit]) -> dict[str, Any]:
    """The summary of the test: per direction the scores of every model and their ranking, the in-sample AR(1)
    AIC ranking of the same half fits (what a fit to that half alone would conclude), the sum of both directions'
    predictive -2 ln L, and a sentence on what it says."""
    out: dict[str, Any] = {"split_after_frame": len(problem.offsets) // 2,
                           "split_at_t_s": float(problem.t[len(problem.offsets) // 2]),
                           "tie_within": PREDICTIVE_TIE, "directions": {}}  # fmt: skip
    for half in HALVES:
        mine = [h for h in hfits if h.half == half]
        scores = {h.fit.model: prediction_score(problem, h) for h in mine}
        crit = ar1_criteria({h.fit.model: h.fit.residuals for h in mine}, {h.fit.model: h.fit.k for h in mine})
        in_sample = sorted(crit, key=lambda m: crit[m]["aic"])
        out["directions"][f"{half}_predicts_{other(half)}"] = {
            "scores": scores, "ranking": ranking(scores, "predictive_neg2_log_likelihood"),
            "in_sample_ar1_aic_order": in_sample,
            "in_sample_ar1_delta_aic": {m: crit[m]["delta_aic"] for m in in_sample}}  # fmt: skip
    dirs = list(out["directions"].values())
    total = {m: {"predictive_neg2_log_likelihood": sum(d["scores"][m]["predictive_neg2_log_likelihood"]
                                                        for d in dirs)} for m in dirs[0]["scores"]}  # fmt: skip
    out["both_directions"] = ranking(total, "predictive_neg2_log_likelihood")
    out["text"] = holdout_text(out)
    return out


def holdout_text(out: Mapping[str, Any]) -> str:
    """What the test says, in words: the best predictors each way and in both, and whether a half's in-sample
    ranking agrees with the out-of-sample one (a decay shape that does not hold across the record)."""
    parts = []
    for name, d in out["directions"].items():
        tie = d["ranking"]["tie"]
        s = d["scores"]
        best = ", ".join(f"{model_title(m)} (chi2/n {s[m]['chi2_per_frame']:.2f}, "
                         f"AR(1) {s[m]['ar1_chi2_per_frame']:.2f})" for m in tie)  # fmt: skip
        worst = d["ranking"]["order"][-1]
        same = d["in_sample_ar1_aic_order"][0] in tie
        parts.append(f"Fitted to the {name.replace('_predicts_', ' half, predicting the ')} half: best {best}; worst "
                     f"{model_title(worst)} (chi2/n {s[worst]['chi2_per_frame']:.2f}). In sample on that half the "
                     f"lowest AR(1) AIC is {model_title(d['in_sample_ar1_aic_order'][0])}, which "
                     + ("also predicts best." if same else "does not predict best: the half's own fit ranks "
                        "the models otherwise than their predictions do."))
    both = out["both_directions"]["tie"]
    parts.append(f"Summed over both directions the best predictors are {', '.join(model_title(m) for m in both)} "
                 f"(predictive -2 ln L within {out['tie_within']:g}). All of this is one record split in two: the "
                 "halves differ in amplitude, so a law that fits one half and predicts the other is one whose "
                 "amplitude dependence holds across the record.")
    return " ".join(parts)


def holdout_section(s: Mapping[str, Any]) -> str:
    """The out-of-sample test: a table of every model's scores in both directions and what it says."""
    o = s.get("out_of_sample")
    if not o:
        return ("## Out of sample\n\nNot run here: the test that fits each model to one half of the record and "
                "predicts the other runs with --thorough (it would almost double this run's time).")
    dirs = list(o["directions"].items())
    head = " | ".join(f"{n.split('_')[0]} -> {n.split('_')[-1]}: chi2/n, AR(1) chi2/n, mean residual [mJ]"
                      for n, _ in dirs)  # fmt: skip
    lines = [f"| model | {head} | rank both ways |", "|---|" + "---|" * len(dirs) + "---|"]
    order = o["both_directions"]["order"]
    for i, m in enumerate(order):
        cells = []
        for _, d in dirs:
            x = d["scores"][m]
            cells.append(f"{x['chi2_per_frame']:.2f}, {x['ar1_chi2_per_frame']:.2f}, "
                         f"{1e3 * x['mean_residual_J']:+.2f} +- {1e3 * x['mean_residual_stderr_J']:.2f}")
        tie = " (tie)" if m in o["both_directions"]["tie"] else ""
        lines.append(f"| {model_title(m)} | {' | '.join(cells)} | {i + 1}{tie} |")
    params = "; ".join(f"{model_title(m)}: " + ", ".join(
        f"{n.split('_')[0]} half {', '.join(f'{k} = {v:.3g}' for k, v in d['scores'][m]['theta'].items())}"
        for n, d in dirs) for m in order if any(k == "air_factor" for k in dirs[0][1]["scores"][m]["theta"]))
    return f"""## Out of sample: each model fitted to one half of the record, predicting the other

The record is split at frame {o['split_after_frame']} (t = {o['split_at_t_s']:.1f} s). Each model is fitted to
one half alone and run over the whole record from the same start state; its energy (with that half's kappa) is
compared with the other half, which the fit never saw. Scores on the held-out half: chi2 per frame, the
AR(1) chi2 per frame (rho of the fit's own residuals), the mean residual simulated - measured with its AR(1)
error; the ranking is by the predictive -2 ln L of the AR(1) model (ties: within {o['tie_within']:g}).

{chr(10).join(lines)}

{o['text']}

Fitted air factors of the models with air drag, by half: {params}.

![out of sample](out_of_sample.png)"""
