r"""An explicit noise model for the loss fits: AR(1) residuals, their likelihood, AIC and BIC from it.

The residuals of a loss model against the measured energy, normalised by the frames' calibrated errors,
:math:`r_i = (\kappa E^{sim}_i - E_i)/\sigma_i` (:meth:`.fitting.FitProblem.scaled_residuals`), are correlated
over about a swing. Instead of one variance factor F taken from a lag window (:mod:`.fitting`), they are modelled
as a stationary first-order autoregressive process with marginal variance :math:`s^2` [1] and lag-1 correlation
:math:`\rho` [1]:

.. math::

    r_i = \rho\, r_{i-1} + e_i,\qquad e_i \sim N\big(0, s^2 (1-\rho^2)\big),\qquad r_1 \sim N(0, s^2).

Its exact Gaussian log-likelihood of the energies [J] is

.. math::

    -2\ln L = n\ln(2\pi s^2) + (n-1)\ln(1-\rho^2) + Q(\rho)/s^2 + 2\sum_i \ln\sigma_i,\qquad
    Q(\rho) = r_1^2 + \frac{\sum_{i\ge 2} (r_i - \rho r_{i-1})^2}{1-\rho^2}

(Q: the "whitened chi2"; at :math:`\rho = 0` it is chi2). :math:`s^2` is profiled out, :math:`\hat s^2 = Q/n`,
and :math:`\rho` is the value that maximises the profile (:func:`ar1_fit`), so every model's noise is estimated
from its own residuals; the noise adds two parameters to each model (:data:`NOISE_PARAMETERS`), the same for all.
With k the fitted numbers of the model (its loss parameters and kappa) plus the two:

.. math::

    AIC = -2\ln L + 2k,\qquad BIC = -2\ln L + k\ln n_{eff},\qquad n_{eff} = n\,\frac{1-\rho}{1+\rho}

(:math:`n_{eff}`: the number of independent frames with the same variance of a mean as n AR(1) frames; one
:math:`n_{eff}` for every model, from the :math:`\rho` of the model with the lowest AIC, as BIC needs one sample
size). For a slow misfit, whitening at one rho divides a chi2 difference by about :math:`(1+\rho)/(1-\rho)`, the AR(1)
counterpart of F (:func:`ar1_factor`).

Evaluated at the least-squares optimum of each fit (the fits minimise chi2, not :math:`Q`), the likelihood is a
lower bound on its maximum; :mod:`.ar1_refit` fits every model again under it, and :func:`noise_model_summary`
takes the criteria from those re-fits where it is given them (the default and thorough identifications), with the
least-squares optimum's beside them. Whether AR(1) describes the residuals is checked by the autocorrelation of the
innovations :math:`e_i` (:func:`innovation_autocorrelation`: near 0 at every lag if it does).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from ..decay.noise import prewhiten

NOISE_PARAMETERS = 2
"""Parameters of the noise model fitted with each loss model: rho and s^2."""
RHO_BOUND = 0.99
"""|rho| is searched below this (a random walk, rho = 1, has no stationary variance)."""


def whitened_chi2(r: np.ndarray, rho: float) -> float:
    """Q(rho) of the module docstring [1]: the AR(1)-whitened sum of squares of the normalised residuals ``r``."""
    white = prewhiten(np.asarray(r, dtype=float), rho)  # Prais-Winsten: |white|^2 = (1 - rho^2) Q
    return float(white @ white) / (1.0 - rho * rho)


def neg2_log_likelihood(r: np.ndarray, rho: float, s2: float | None = None, sigma: np.ndarray | None = None) -> float:
    """-2 ln L of the AR(1) model (module docstring) for the normalised residuals ``r`` at ``rho``; ``s2`` [1]:
    the marginal variance (None: profiled, Q/n); ``sigma`` [J]: the frames' errors (adds 2 sum ln sigma, the
    likelihood of the energies; None: of the normalised residuals)."""
    n = len(r)
    q = whitened_chi2(r, rho)
    s2 = q / n if s2 is None else s2
    out = n * math.log(2.0 * math.pi * s2) + (n - 1) * math.log(1.0 - rho * rho) + q / s2
    return out + (2.0 * float(np.sum(np.log(sigma))) if sigma is not None else 0.0)


@dataclass(frozen=True)
class Ar1Fit:
    """The AR(1) noise model fitted to one set of normalised residuals: rho, s^2, Q, -2 ln L, n."""

    rho: float
    s2: float
    q: float
    neg2_log_l: float
    n: int


def ar1_fit(r: np.ndarray, sigma: np.ndarray | None = None) -> Ar1Fit:
    """The maximum-likelihood rho (|rho| < :data:`RHO_BOUND`) and s^2 = Q/n of the normalised residuals ``r``."""
    r = np.asarray(r, dtype=float)
    res = minimize_scalar(lambda rho: neg2_log_likelihood(r, rho), bounds=(-RHO_BOUND, RHO_BOUND), method="bounded",
                          options={"xatol": 1e-6})  # fmt: skip
    rho = float(res.x)
    q = whitened_chi2(r, rho)
    return Ar1Fit(rho, q / len(r), q, neg2_log_likelihood(r, rho, sigma=sigma), len(r))


def ar1_factor(rho: float) -> float:
    """(1 + rho)/(1 - rho) [1]: the variance factor of a mean of AR(1) residuals (n_eff = n / factor)."""
    return (1.0 + rho) / (1.0 - rho)


def innovation_autocorrelation(r: np.ndarray, rho: float, max_lag: int = 3) -> list[float]:
    """Autocorrelation of the innovations e_i = r_i - rho r_(i-1) at lags 1..``max_lag`` (near 0 if AR(1) holds;
    its standard error under independence is 1/sqrt(n))."""
    e = np.asarray(r[1:], dtype=float) - rho * np.asarray(r[:-1], dtype=float)
    e = e - e.mean()
    c0 = float(e @ e)
    return [float(e[: len(e) - k] @ e[k:]) / c0 for k in range(1, max_lag + 1)]


def ar1_criteria(residuals: Mapping[str, np.ndarray], ks: Mapping[str, int],
                 sigma: np.ndarray | None = None) -> dict[str, dict[str, Any]]:
    """Per model: the AR(1) fit of its normalised residuals, -2 ln L, AIC, BIC (module docstring; ``ks``: each
    model's fitted numbers without the noise, which adds :data:`NOISE_PARAMETERS`), dAIC, dBIC against the lowest
    of each; n_eff from the rho of the model with the lowest AIC."""
    fits = {m: ar1_fit(r, sigma) for m, r in residuals.items()}
    k = {m: ks[m] + NOISE_PARAMETERS for m in fits}
    aic = {m: f.neg2_log_l + 2.0 * k[m] for m, f in fits.items()}
    best = min(aic, key=aic.get)
    n = fits[best].n
    n_eff = n / ar1_factor(fits[best].rho)
    bic = {m: f.neg2_log_l + k[m] * math.log(n_eff) for m, f in fits.items()}
    return {m: {"rho": f.rho, "s2": f.s2, "whitened_chi2": f.q, "neg2_log_likelihood": f.neg2_log_l, "k": k[m],
                "aic": aic[m], "bic": bic[m], "delta_aic": aic[m] - aic[best], "delta_bic": bic[m] - min(bic.values()),
                "n_eff": n_eff, "innovation_autocorrelation": innovation_autocorrelation(residuals[m], f.rho)}
            for m, f in fits.items()}  # fmt: skip


def ties(criteria: Mapping[str, Mapping[str, Any]], key: str, within: float = 2.0,
         eligible: Sequence[str] | None = None) -> list[str]:
    """The models (of ``eligible``, default all) whose ``key`` (``delta_aic``, ``delta_bic``) lies below ``within``
    of the lowest among them, lowest first."""
    names = [m for m in criteria if eligible is None or m in eligible]
    if not names:
        return []
    low = min(criteria[m][key] for m in names)
    return sorted((m for m in names if criteria[m][key] - low < within), key=lambda m: criteria[m][key])


AIR_LABEL = "air drag"
"""The air-drag entry of a comparison row's ``shares``."""


def air_range(rows: Sequence[Mapping[str, Any]], models: Sequence[str],
              shares_by_model: Mapping[str, Mapping[str, float]] | None = None) -> list[float] | None:
    """The smallest and largest air-drag share [1] among ``models`` (0 for one without air drag); None if none
    of them has air drag. The shares are the rows' (the least-squares fits'), or ``shares_by_model``'s where given
    (the AR(1) re-fits')."""
    shares = [shares_by_model[m] if shares_by_model and m in shares_by_model
              else next(r["shares"] for r in rows if r["model"] == m) for m in models]
    air = [s.get(AIR_LABEL, 0.0) for s in shares]
    return [min(air), max(air)] if any(AIR_LABEL in s for s in shares) else None


def noise_model_summary(rows: Sequence[Mapping[str, Any]], residuals: Mapping[str, np.ndarray],
                        sigma: np.ndarray, factor: float, refits: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The AR(1) criteria (:func:`ar1_criteria`) of every converged model of the comparison ``rows`` (their
    normalised residuals ``residuals`` by model, the frames' errors ``sigma`` [J]) and which models tie (within 2)
    under each of the four criteria, AIC and BIC with the common factor F = ``factor`` and with the AR(1)
    likelihood, each with its range of the air-drag share; models that reduce to a nested one are no candidates
    (:func:`.comparison.reduces_to`). ``refits`` (:class:`.ar1_refit.Ar1Refit` by model): the AR(1) criteria and
    their air shares are the re-fits' (``refitted``), each model's ``least_squares`` entry the criteria at its
    least-squares optimum, ``refit`` its re-fit; without them the criteria are the least-squares optimum's."""
    ranked = [r for r in rows if r["converged"]]
    ks = {r["model"]: r["k"] for r in ranked}
    refitted = refits is not None and all(r["model"] in refits for r in ranked)
    at_lsq = ar1_criteria({r["model"]: residuals[r["model"]] for r in ranked}, ks, sigma)
    crit = (ar1_criteria({m: refits[m].residuals for m in ks}, ks, sigma) if refitted else at_lsq)  # fmt: skip
    if refitted:
        for m, c in crit.items():
            c["least_squares"] = {k: at_lsq[m][k] for k in ("rho", "neg2_log_likelihood", "delta_aic", "delta_bic")}
            c["refit"] = refits[m].as_dict()
    refit_shares = {m: refits[m].shares for m in ks} if refitted else None
    eligible = [r["model"] for r in ranked if not r.get("reduces_to")]
    by_f = {r["model"]: r for r in ranked}
    tied = {"aic_F": ties(by_f, "delta_aic", eligible=eligible), "bic_F": ties(by_f, "delta_bic", eligible=eligible),
            "aic_ar1": ties(crit, "delta_aic", eligible=eligible),
            "bic_ar1": ties(crit, "delta_bic", eligible=eligible)}  # fmt: skip
    best = min(crit, key=lambda m: crit[m]["aic"])
    rhos = [c["rho"] for c in crit.values()]
    out = {"model": "AR(1) residuals, rho and s^2 fitted to each model's normalised residuals",
           "refitted": refitted, "criteria": crit, "rho_range": [min(rhos), max(rhos)],
           "rho_of_lowest_aic": crit[best]["rho"], "equivalent_factor": ar1_factor(crit[best]["rho"]),
           "common_factor_F": factor, "ties": tied,
           "air_share_range": {k: air_range(rows, v, refit_shares if k.endswith("ar1") else None)
                               for k, v in tied.items()}}  # fmt: skip
    if refitted:
        out["ties_at_least_squares"] = {k: ties(at_lsq, f"delta_{k[:3]}", eligible=eligible)
                                        for k in ("aic_ar1", "bic_ar1")}  # fmt: skip
    out["text"] = noise_text(out)
    return out


CRITERIA_WORDS = {"aic_F": "AIC with F", "bic_F": "BIC with F", "aic_ar1": "AIC with the AR(1) likelihood",
                  "bic_ar1": "BIC with the AR(1) likelihood"}  # fmt: skip
"""The four criteria of :func:`noise_model_summary` in words."""


def noise_text(s: Mapping[str, Any]) -> str:
    """Which models tie under each criterion, and the air share each tie leaves open."""
    def one(key: str) -> str:
        models = s["ties"][key]
        air = s["air_share_range"][key]
        share = ("no air drag" if air is None else f"air drag's share {air[0]:.0%}"
                 if f"{air[0]:.0%}" == f"{air[1]:.0%}" else f"air drag's share {air[0]:.0%} to {air[1]:.0%}")
        return f"{CRITERIA_WORDS[key]}: {len(models)} ({', '.join(models)}; {share})"

    lo, hi = s["rho_range"]
    agree = len({tuple(sorted(v)) for v in s["ties"].values()}) == 1
    return (refit_text(s) + f"Fitted as AR(1), the residuals of the models have lag-1 correlation rho {lo:.2f} to "
            f"{hi:.2f} (the lowest "
            f"AIC's: {s['rho_of_lowest_aic']:.2f}, a variance factor (1+rho)/(1-rho) = {s['equivalent_factor']:.2f} "
            f"against F = {s['common_factor_F']:.2f} from the lag window). Models within 2 of the lowest: "
            + "; ".join(one(k) for k in CRITERIA_WORDS) + ". "
            + ("All four criteria give the same tie." if agree else
               "The criteria disagree, so which models tie, and the air share, depend on the criterion: the "
               "range over all of them is what the record supports."))


def refit_text(s: Mapping[str, Any]) -> str:
    """What re-fitting every model under the AR(1) likelihood changed: its gain in -2 ln L and the ties."""
    if not s.get("refitted"):
        return ("The AR(1) likelihood is evaluated at each model's least-squares optimum (a lower bound on its "
                "maximum; no model was re-fitted under it). ")
    gains = [c["refit"]["gain_neg2_log_likelihood"] for c in s["criteria"].values()]
    changed = [k for k in ("aic_ar1", "bic_ar1") if sorted(s["ties"][k]) != sorted(s["ties_at_least_squares"][k])]
    return (f"Every model is re-fitted under the AR(1) likelihood, which raises it over the least-squares optimum's "
            f"(-2 ln L lower by {min(gains):.2f} to {max(gains):.2f}); "
            + ("the models within 2 are the same as at the least-squares optimum under both AR(1) criteria. "
               if not changed else "the re-fit changes which models tie under "
               + " and ".join(f"{CRITERIA_WORDS[k]} (at the least-squares optimum: "
                              f"{', '.join(s['ties_at_least_squares'][k])})" for k in changed) + ". "))
