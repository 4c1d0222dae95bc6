r"""The decay models of :mod:`.fit` fitted under an AR(1) noise model, compared by AIC and BIC of that likelihood,
and the free exponent p of dE/dt = -k E^p with its profile-likelihood interval.

The normalised residuals :math:`z_i = (E_i - f(t_i;\theta))/\sigma_i` (E [J], sigma [J] the frames' errors) are
modelled as a stationary AR(1) process of marginal variance :math:`s^2` and lag-one correlation :math:`\rho`, the
likelihood of :mod:`~double_pendulum.analysis.losses.noise`:

.. math::

    -2\ln L = n\ln(2\pi s^2) + (n-1)\ln(1-\rho^2) + Q/s^2 + 2\sum_i\ln\sigma_i,\qquad
    Q = z_1^2 + \frac{\sum_{i\ge2}(z_i - \rho z_{i-1})^2}{1-\rho^2}

with :math:`s^2 = Q/n` profiled out. Unlike :mod:`~double_pendulum.analysis.losses.noise` (which evaluates it at
each loss model's least-squares optimum), every model here is **re-fitted under it**: :math:`\theta` and
:math:`\rho` maximise L jointly (:func:`ar1_ml_fit`: for each rho the Prais-Winsten least squares in theta, rho by
a bounded scalar search). AIC = -2 ln L + 2k, BIC = -2 ln L + k ln n_eff, k = the model's parameters + 2 (rho,
s^2), :math:`n_{eff} = n(1-\rho)/(1+\rho)` with the rho of the lowest AIC (one sample size for every model, as in
:mod:`~double_pendulum.analysis.losses.noise`).

**p** (:func:`exponent`): the power law's p with its error from the whitened problem's curvature, and its
profile-likelihood interval: the p at which :math:`\Delta(-2\ln L) = 1` and :math:`= 4` (about 68 % and 95 %), every
other parameter and rho re-fitted at each p. p = 1: losses proportional to E (viscous damping, the exponential);
p < 1: the decay speeds up relative to E as E falls (constant friction torques give p = 1/2); p > 1: it slows
(quadratic drag, p = 3/2).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.optimize import brentq, least_squares, minimize_scalar

from .fit import MODELS, DecayModel
from .noise import prewhiten

RHO_BOUND = 0.95
"""|rho| is searched below this."""
DEFAULT_MODELS: tuple[str, ...] = ("exponential", "power", "quadratic_drag", "coulomb")


def _inner(model: DecayModel, t: np.ndarray, e: np.ndarray, w: np.ndarray, rho: float, theta0: np.ndarray,
           fixed: dict[int, float]) -> tuple[np.ndarray, float]:  # fmt: skip
    """theta minimising the whitened sum of squares at ``rho`` (``fixed``: index -> held value); returns theta and
    -2 ln L (s^2 profiled, without the constant 2 sum ln sigma + n ln 2 pi)."""
    free = [i for i in range(len(theta0)) if i not in fixed]

    def full(x: np.ndarray) -> np.ndarray:
        th = np.array(theta0, dtype=float)
        th[free] = x
        for i, v in fixed.items():
            th[i] = v
        return th

    def white(x: np.ndarray) -> np.ndarray:
        return prewhiten((e - model.func(t, *full(x))) / w, rho)

    res = least_squares(white, np.asarray(theta0, dtype=float)[free], method="lm", x_scale="jac")
    th = full(res.x)
    n = len(t)
    q = float(res.fun @ res.fun) / (1.0 - rho * rho)
    return th, n * math.log(q / n) + (n - 1) * math.log(1.0 - rho * rho)


def ar1_ml_fit(model: DecayModel | str, t: np.ndarray, e: np.ndarray, sigma: np.ndarray | None = None,
               fixed: dict[int, float] | None = None,
               start: Sequence[float] | None = None) -> dict[str, Any]:  # fmt: skip
    """The maximum-likelihood fit of ``model`` with AR(1) residuals (module docstring): ``theta``, ``rho``,
    ``neg2_log_l`` (without the constant common to every model of the same frames and errors), ``k`` (the
    model's free parameters + 2) and ``stderr`` of theta (s^2 (Jw' Jw)^-1 of the whitened problem at the optimum;
    held parameters 0)."""
    model = MODELS[model] if isinstance(model, str) else model
    t = np.asarray(t, dtype=float)
    e = np.asarray(e, dtype=float)
    w = np.ones_like(e) if sigma is None else np.asarray(sigma, dtype=float)
    fixed = dict(fixed or {})
    theta = np.asarray(model.start(t, e) if start is None else start, dtype=float)
    for i, v in fixed.items():
        theta[i] = v
    best: dict[str, Any] = {"theta": theta}

    def objective(rho: float) -> float:
        th, m2ll = _inner(model, t, e, w, rho, best["theta"], fixed)
        best["theta"] = th
        return m2ll

    res = minimize_scalar(objective, bounds=(-RHO_BOUND, RHO_BOUND), method="bounded", options={"xatol": 1e-5})
    rho = float(res.x)
    theta, m2ll = _inner(model, t, e, w, rho, best["theta"], fixed)
    free = [i for i in range(len(theta)) if i not in fixed]
    z = lambda th: prewhiten((e - model.func(t, *th)) / w, rho)  # noqa: E731
    white = z(theta)
    jac = np.zeros((len(t), len(free)))
    for j, i in enumerate(free):
        h = 1e-6 * max(abs(theta[i]), 1e-8)
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        jac[:, j] = (z(up) - z(down)) / (2 * h)
    cov = float(white @ white) / (len(t) - len(free)) * np.linalg.pinv(jac.T @ jac)
    stderr = np.zeros(len(theta))
    stderr[free] = np.sqrt(np.diag(cov))
    return {"model": model.name, "theta": theta, "stderr": stderr, "rho": rho, "neg2_log_l": m2ll,
            "k": len(free) + 2, "n": len(t)}  # fmt: skip


def compare(t: np.ndarray, e: np.ndarray, sigma: np.ndarray | None = None,
            models: Sequence[str] = DEFAULT_MODELS) -> dict[str, Any]:  # fmt: skip
    """Every model re-fitted under AR(1) (:func:`ar1_ml_fit`) with its AIC, BIC, dAIC, dBIC (module docstring)."""
    fits = {m: ar1_ml_fit(m, t, e, sigma) for m in models}
    aic = {m: f["neg2_log_l"] + 2.0 * f["k"] for m, f in fits.items()}
    low = min(aic, key=aic.get)
    rho = fits[low]["rho"]
    n_eff = len(t) * (1.0 - rho) / (1.0 + rho)
    bic = {m: f["neg2_log_l"] + f["k"] * math.log(n_eff) for m, f in fits.items()}
    rows = {m: {"params": dict(zip(MODELS[m].param_names, map(float, f["theta"]))),
                "stderr": dict(zip(MODELS[m].param_names, map(float, f["stderr"]))),
                "rho": f["rho"], "k": f["k"], "neg2_log_l": f["neg2_log_l"], "aic": aic[m], "bic": bic[m],
                "delta_aic": aic[m] - aic[low], "delta_bic": bic[m] - min(bic.values())}
            for m, f in fits.items()}  # fmt: skip
    return {"models": rows, "lowest_aic": low, "n": len(t), "n_eff": n_eff,
            "ties_aic": sorted((m for m in rows if rows[m]["delta_aic"] < 2.0), key=lambda m: rows[m]["aic"]),
            "ties_bic": sorted((m for m in rows if rows[m]["delta_bic"] < 2.0),
                               key=lambda m: rows[m]["bic"])}  # fmt: skip


def exponent(t: np.ndarray, e: np.ndarray, sigma: np.ndarray | None = None, *, p_max: float = 3.0) -> dict[str, Any]:
    """The power law's p under AR(1) (module docstring): p, its curvature error, its profile-likelihood intervals at
    Delta(-2 ln L) = 1 and 4, and Delta(-2 ln L) of the exponential (p = 1) against the free p."""
    t = np.asarray(t, dtype=float)
    free = ar1_ml_fit("power", t, e, sigma)
    p_hat = float(free["theta"][2])
    ref = free["neg2_log_l"]

    def delta(p: float) -> float:
        return ar1_ml_fit("power", t, e, sigma, fixed={2: p}, start=free["theta"])["neg2_log_l"] - ref

    def bound(level: float, side: int) -> float | None:
        """The p beyond p_hat on ``side`` where delta reaches ``level``, searched in steps of the curvature error
        (None: not within 0 < p < p_max)."""
        step = max(float(free["stderr"][2]), 0.02)
        p = p_hat
        for _ in range(60):
            q = min(max(p + side * step, 1e-3), p_max)
            if delta(q) > level:
                return brentq(lambda x: delta(x) - level, min(p, q), max(p, q), xtol=1e-4)
            if q in (1e-3, p_max):
                return None
            p = q
        return None

    at_one = delta(1.0)
    e0, k = float(free["theta"][0]), float(free["theta"][1])
    stop = e0 ** (1.0 - p_hat) / ((1.0 - p_hat) * k) if p_hat < 1.0 else None
    return {"p": p_hat, "p_stderr": float(free["stderr"][2]), "rho": free["rho"], "E0_J": e0, "k": k,
            "stop_time_s": stop,
            "interval_68": [bound(1.0, -1), bound(1.0, 1)], "interval_95": [bound(4.0, -1), bound(4.0, 1)],
            "delta_neg2_log_l_at_p_1": at_one, "p_below_1_sigma": (1.0 - p_hat) / float(free["stderr"][2]),
            "definition": "p of dE/dt = -k E^p fitted with AR(1) residuals (joint maximum likelihood; E0 [J] at the "
                          "first fitted frame, k [J^(1-p)/s]; stop_time_s: where the law reaches E = 0 from it, "
                          "E0^(1-p) / ((1-p) k), None for p >= 1); intervals where "
                          "Delta(-2 ln L) <= 1 and <= 4 with every other parameter and rho re-fitted; None: beyond "
                          "0 < p < 3"}  # fmt: skip
