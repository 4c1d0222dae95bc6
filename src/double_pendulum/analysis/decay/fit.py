r"""Models of the energy decay E(t) [J] of the damped pendulum, weighted fits and their comparison.

Models (t in s, energies in J):

- ``exponential``: :math:`E = a\,e^{b t}` (losses proportional to E, the seed's 4.2.5 model);
- ``quadratic_drag``: :math:`E = E_0 / (1 + t/\tau)^2` (drag force ~ v^2, dE/dt ~ -E^{3/2});
- ``coulomb``: :math:`E = E_0 (1 - t/\tau)^2` for t < tau, 0 after (constant friction force,
  dE/dt ~ -E^{1/2}: the amplitude falls linearly);
- ``power``: the solution of :math:`dE/dt = -k E^p`,

  .. math::

      E(t) = \left(E_0^{1-p} - (1-p)\,k\,t\right)^{1/(1-p)} \quad (p \ne 1), \qquad
      E(t) = E_0 e^{-k t} \quad (p = 1),

  which contains the other three: p = 1 (k = -b), p = 3/2 (k = 2 / (tau sqrt(E0))) and
  p = 1/2 (k = 2 sqrt(E0) / tau). k has the unit J^(1-p)/s.

Fits use :func:`scipy.optimize.curve_fit` with per-point standard deviations ``sigma``.
With ``absolute_sigma=True`` the sigmas are taken as true errors: :math:`\chi^2` is meaningful,
the covariance is :math:`(J^T W J)^{-1}` and the information criteria are
:math:`AIC = \chi^2 + 2k`, :math:`BIC = \chi^2 + k \ln n` (k fitted parameters, n points; the
common constant of -2 ln L is dropped). With ``absolute_sigma=False`` the sigmas are relative
weights with an unknown common scale s, estimated by maximum likelihood: the covariance is
scaled by :math:`\chi^2/(n-k)` and :math:`AIC = n\ln(\chi^2/n) + 2(k+1)`,
:math:`BIC = n\ln(\chi^2/n) + (k+1)\ln n`. Only differences between models fitted to the same
points with the same weights mean something.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import curve_fit, minimize

P_ONE_TOLERANCE = 1e-9
"""|1 - p| below which the power model is evaluated as its exponential limit."""
AUTOCORRELATION_LAG_S = 1.5
"""Lag window [s] for the residual autocorrelation of the measured energy (the ``max_lag`` of
:func:`effective_sample_factor` times the frame rate): about one slow swing (period 1.31 s)."""
SEED_FIT = {"a_J": 0.813, "a_rel_err": 0.0126, "b_per_s": -0.024, "b_rel_err": 0.0489}
"""The seed's exponential fit E = a exp(b t) of the measured energy (section 4.2.5): a [J], b [1/s]
and their relative errors [1], for comparison."""


@dataclass(frozen=True)
class DecayModel:
    """A model E(t, *params) with parameter names, units and a start-value rule."""

    name: str
    func: Callable[..., np.ndarray]
    param_names: tuple[str, ...]
    param_units: tuple[str, ...]
    start: Callable[[np.ndarray, np.ndarray], tuple[float, ...]]
    equation: str


@dataclass(frozen=True, eq=False)
class FitResult:
    """Result of one weighted fit: parameters, standard errors, covariance and goodness of fit."""

    model: str
    param_names: tuple[str, ...]
    param_units: tuple[str, ...]
    params: np.ndarray
    stderr: np.ndarray
    cov: np.ndarray
    chi2: float
    n: int
    absolute_sigma: bool
    aic: float
    bic: float

    @property
    def k(self) -> int:
        """Number of fitted parameters."""
        return len(self.params)

    @property
    def dof(self) -> int:
        """Degrees of freedom n - k."""
        return self.n - self.k

    @property
    def chi2_red(self) -> float:
        """Reduced chi-square chi2 / (n - k)."""
        return self.chi2 / self.dof

    def value(self, name: str) -> float:
        """Fitted value of the parameter ``name``."""
        return float(self.params[self.param_names.index(name)])

    def error(self, name: str) -> float:
        """Standard error of the parameter ``name``."""
        return float(self.stderr[self.param_names.index(name)])

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON): values and errors by name, chi2, AIC, BIC."""
        return {
            "model": self.model,
            "params": {n: float(v) for n, v in zip(self.param_names, self.params)},
            "stderr": {n: float(e) for n, e in zip(self.param_names, self.stderr)},
            "units": dict(zip(self.param_names, self.param_units)),
            "n": self.n,
            "k": self.k,
            "chi2": self.chi2,
            "chi2_red": self.chi2_red,
            "absolute_sigma": self.absolute_sigma,
            "aic": self.aic,
            "bic": self.bic,
        }


# --- model functions ----------------------------------------------------------------------------


def exponential(t: np.ndarray, a: float, b: float) -> np.ndarray:
    """E = a exp(b t) [J]; a in J, b in 1/s."""
    return a * np.exp(b * np.asarray(t, dtype=float))


def quadratic_drag(t: np.ndarray, e0: float, tau: float) -> np.ndarray:
    """E = E0 / (1 + t/tau)^2 [J]; E0 in J, tau in s."""
    return e0 / (1.0 + np.asarray(t, dtype=float) / tau) ** 2


def coulomb(t: np.ndarray, e0: float, tau: float) -> np.ndarray:
    """E = E0 (1 - t/tau)^2 for t < tau, else 0 [J]; E0 in J, tau in s (time to stop)."""
    return e0 * np.clip(1.0 - np.asarray(t, dtype=float) / tau, 0.0, None) ** 2


def power_decay(t: np.ndarray, e0: float, k: float, p: float) -> np.ndarray:
    """Solution of dE/dt = -k E^p with E(0) = E0 [J]; k in J^(1-p)/s, p dimensionless.

    Written as ``E0 * exp(log1p(-u x) / u)`` with ``u = 1 - p`` and ``x = k E0^(-u) t``, which
    tends to ``E0 exp(-x)`` smoothly as p -> 1 (used for ``|u| < P_ONE_TOLERANCE``). For p < 1
    the energy reaches 0 at finite time (``u x >= 1``) and stays 0.
    """
    t = np.asarray(t, dtype=float)
    u = 1.0 - p
    x = k * e0 ** (-u) * t
    if abs(u) < P_ONE_TOLERANCE:
        return e0 * np.exp(-x)
    arg = 1.0 - u * x
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        e = e0 * np.exp(np.log(np.clip(arg, 0.0, None)) / u)
    return np.where(arg > 0.0, e, 0.0 if u > 0 else np.inf)


# --- start values -------------------------------------------------------------------------------


def _log_linear_start(t: np.ndarray, e: np.ndarray) -> tuple[float, float]:
    """Straight line through (t, ln E) of the positive energies: start values (a, b)."""
    pos = e > 0
    b, ln_a = np.polyfit(t[pos], np.log(e[pos]), 1)
    return float(math.exp(ln_a)), float(min(b, -1e-6))


def _start_exponential(t: np.ndarray, e: np.ndarray) -> tuple[float, ...]:
    return _log_linear_start(t, e)


def _start_quadratic_drag(t: np.ndarray, e: np.ndarray) -> tuple[float, ...]:
    a, b = _log_linear_start(t, e)
    return a, 2.0 / -b  # same initial slope: dE/dt(0) = -2 E0 / tau = a b


def _start_coulomb(t: np.ndarray, e: np.ndarray) -> tuple[float, ...]:
    a, b = _log_linear_start(t, e)
    return a, max(2.0 / -b, 1.01 * float(np.max(t)))


def _start_power(t: np.ndarray, e: np.ndarray) -> tuple[float, ...]:
    a, b = _log_linear_start(t, e)
    return a, -b, 1.0


MODELS: dict[str, DecayModel] = {
    m.name: m
    for m in (
        DecayModel("exponential", exponential, ("a", "b"), ("J", "1/s"), _start_exponential, "E = a e^(b t)"),
        DecayModel(
            "quadratic_drag",
            quadratic_drag,
            ("E0", "tau"),
            ("J", "s"),
            _start_quadratic_drag,
            "E = E0 / (1 + t/tau)^2",
        ),
        DecayModel("coulomb", coulomb, ("E0", "tau"), ("J", "s"), _start_coulomb, "E = E0 (1 - t/tau)^2"),
        DecayModel(
            "power", power_decay, ("E0", "k", "p"), ("J", "J^(1-p)/s", "1"), _start_power, "dE/dt = -k E^p"
        ),
    )
}
"""The decay models by name."""


# --- fitting ------------------------------------------------------------------------------------


def information_criteria(
    chi2: float, n: int, k: int, absolute_sigma: bool, factor: float = 1.0
) -> tuple[float, float]:
    """Return (AIC, BIC) of a least-squares fit (see the module docstring for the two cases).

    ``factor`` is the residual-correlation factor F (:func:`record_correlation_factor`): the points count as
    n / F independent ones, so -2 ln L is divided by F and ln n becomes ln(n / F)."""
    n_eff = n / factor
    if absolute_sigma:
        return chi2 / factor + 2.0 * k, chi2 / factor + k * math.log(n_eff)
    m2ll = n * math.log(chi2 / n) / factor
    return m2ll + 2.0 * (k + 1), m2ll + (k + 1) * math.log(n_eff)


def fit_model(
    model: DecayModel | str,
    t: np.ndarray,
    energy: np.ndarray,
    sigma: np.ndarray | None = None,
    *,
    absolute_sigma: bool = True,
    factor: float = 1.0,
) -> FitResult:
    """Weighted least-squares fit of ``model`` to E(t) [J] with per-point errors ``sigma`` [J].

    ``sigma=None`` means equal weights (then ``absolute_sigma`` is treated as False). Standard
    errors are the square roots of the diagonal of curve_fit's covariance (not inflated by ``factor``);
    ``factor``, the residual-correlation factor F, enters the information criteria
    (:func:`information_criteria`).
    """
    model = MODELS[model] if isinstance(model, str) else model
    t = np.asarray(t, dtype=float)
    energy = np.asarray(energy, dtype=float)
    absolute_sigma = absolute_sigma and sigma is not None
    w_sigma = np.ones_like(energy) if sigma is None else np.asarray(sigma, dtype=float)
    params, cov = curve_fit(
        model.func,
        t,
        energy,
        p0=model.start(t, energy),
        sigma=w_sigma,
        absolute_sigma=absolute_sigma,
        maxfev=20000,
    )
    resid = (energy - model.func(t, *params)) / w_sigma
    chi2 = float(resid @ resid)
    aic, bic = information_criteria(chi2, len(t), len(params), absolute_sigma, factor)
    return FitResult(
        model=model.name,
        param_names=model.param_names,
        param_units=model.param_units,
        params=params,
        stderr=np.sqrt(np.diag(cov)),
        cov=cov,
        chi2=chi2,
        n=len(t),
        absolute_sigma=absolute_sigma,
        aic=aic,
        bic=bic,
    )


def fit_all(
    t: np.ndarray,
    energy: np.ndarray,
    sigma: np.ndarray | None = None,
    *,
    absolute_sigma: bool = True,
    models: Sequence[str] = tuple(MODELS),
    factor: float = 1.0,
) -> list[FitResult]:
    """Fit every model in ``models`` to the same points; return the results sorted by AIC (with the
    residual-correlation factor ``factor``, :func:`information_criteria`)."""
    results = [fit_model(name, t, energy, sigma, absolute_sigma=absolute_sigma, factor=factor) for name in models]
    return sorted(results, key=lambda r: r.aic)


def comparison_table(results: Sequence[FitResult]) -> list[dict]:
    """Rows sorted by AIC: parameters, chi2, chi2_red, AIC, BIC, deltas to the best model, Akaike weight.

    The Akaike weight exp(-dAIC/2) / sum exp(-dAIC/2) is the relative support of each model.
    """
    ordered = sorted(results, key=lambda r: r.aic)
    best_aic = ordered[0].aic
    best_bic = min(r.bic for r in ordered)
    likelihoods = [math.exp(-0.5 * (r.aic - best_aic)) for r in ordered]
    total = sum(likelihoods)
    return [
        {
            **r.as_dict(),
            "delta_aic": r.aic - best_aic,
            "delta_bic": r.bic - best_bic,
            "akaike_weight": w / total,
        }
        for r, w in zip(ordered, likelihoods)
    ]


def residual_autocorrelation(residuals: np.ndarray, max_lag: int) -> np.ndarray:
    """Autocorrelation of normalised residuals at lags 0..max_lag (1 at lag 0)."""
    r = np.asarray(residuals, dtype=float) - np.mean(residuals)
    c0 = float(r @ r)
    return np.array([float(r[: len(r) - k] @ r[k:]) / c0 for k in range(max_lag + 1)])


def effective_sample_factor(residuals: np.ndarray, max_lag: int) -> float:
    r"""Variance inflation :math:`1 + 2\sum_{k=1}^{K}\rho_k` of a mean of correlated residuals (>= 1).

    The standard errors of a least-squares fit assume independent residuals; with
    autocorrelation rho_k they are too small by about the square root of this factor
    (n_eff = n / factor). K = ``max_lag`` should cover the correlation time (here one swing).
    """
    rho = residual_autocorrelation(residuals, max_lag)
    return max(1.0, 1.0 + 2.0 * float(np.sum(rho[1:])))


CORRELATION_REFERENCE_MODEL = "power"
"""The decay law whose residuals give a record's correlation factor (:func:`record_correlation_factor`)."""


def record_correlation_factor(t: np.ndarray, energy: np.ndarray, sigma: np.ndarray | None) -> float:
    r"""The residual-correlation factor F of a measured energy record: :func:`effective_sample_factor` of the
    normalised residuals about the free-exponent decay law (:data:`CORRELATION_REFERENCE_MODEL`, dE/dt = -k E^p)
    fitted with the same errors ``sigma`` [J] (None: equal weights), over :data:`AUTOCORRELATION_LAG_S` of lags.

    The one treatment of correlated residuals in every study of the measured energy: each standard error from a
    record is multiplied by sqrt(F) and each information criterion uses chi2 / F and n / F, whatever model is
    fitted. The free-exponent law is the most flexible smooth decay law here, so what is left of its residuals
    is the track's own scatter, not a model's misfit of the decay's shape; the residuals of a model that misfits
    carry that misfit as a slow trend, which inflates its own factor (the exponential's on the seed's record:
    about 3.3 against 1.3). A misfit of the shape is a systematic error (the error budget's first-against-second
    half row), not a statistical one.
    """
    t = np.asarray(t, dtype=float)
    energy = np.asarray(energy, dtype=float)
    model = MODELS[CORRELATION_REFERENCE_MODEL]
    fit = fit_model(model, t, energy, sigma)
    resid = (energy - model.func(t, *fit.params)) / (1.0 if sigma is None else np.asarray(sigma, dtype=float))
    return effective_sample_factor(resid, correlation_lag_frames(t))


def correlation_lag_frames(t: np.ndarray) -> int:
    """:data:`AUTOCORRELATION_LAG_S` in samples of the (evenly spaced) times ``t`` [s]."""
    dt = float(np.median(np.diff(t)))
    return max(1, round(AUTOCORRELATION_LAG_S / dt))


# --- empirical error model ----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ErrorModel:
    r"""Per-point energy errors calibrated on the scatter of the data.

    :math:`\sigma_i^2 = \sigma_{known,i}^2 + s_0^2 + \Delta v^2\,u_i^2` with the known part (e.g.
    propagated position noise), a floor ``floor`` = s0 [J] and a speed-dependent part of the
    seed's eq. 25 form, :math:`u_i = \sqrt{m_1^2 v_1^2 + m_2^2 v_2^2}` [kg m/s], with the
    effective speed error ``dv`` [m/s] (the seed assumed 0.1 m/s).
    """

    floor: float
    dv: float
    sigma: np.ndarray
    iterations: int


def _error_model_sigma(sigma_known: np.ndarray, momentum: np.ndarray, floor: float, dv: float) -> np.ndarray:
    return np.sqrt(sigma_known**2 + floor**2 + (dv * momentum) ** 2)


def _ml_variance_terms(
    resid: np.ndarray, sigma_known: np.ndarray, momentum: np.ndarray
) -> tuple[float, float]:
    r"""Maximum-likelihood (floor, dv) for fixed residuals.

    Minimises :math:`\sum_i r_i^2/\sigma_i^2 + \ln\sigma_i^2` over the two variance terms
    (in logarithms, scaled by the rms residual and rms momentum so both start near 1).
    """
    scale = float(np.sqrt(np.mean(resid**2)))
    u2 = (momentum / max(float(np.sqrt(np.mean(momentum**2))), 1e-300)) ** 2

    def nll(q: np.ndarray) -> float:
        var = sigma_known**2 + scale**2 * (np.exp(q[0]) + np.exp(q[1]) * u2)
        return float(np.sum(resid**2 / var + np.log(var)))

    q = minimize(nll, x0=[math.log(0.5), math.log(0.5)], method="L-BFGS-B", bounds=[(-30.0, 5.0)] * 2).x
    floor = scale * math.exp(0.5 * q[0])
    dv = scale * math.exp(0.5 * q[1]) / max(float(np.sqrt(np.mean(momentum**2))), 1e-300)
    return floor, dv


def calibrate_error_model(
    t: np.ndarray,
    energy: np.ndarray,
    sigma_known: np.ndarray,
    momentum: np.ndarray,
    *,
    model: str = "exponential",
    rtol: float = 1e-6,
    max_iterations: int = 50,
) -> ErrorModel:
    """Fit ``model`` and the error model (:class:`ErrorModel`) to E(t) alternately until the sigmas settle.

    Each round fits the model with the current sigmas (``absolute_sigma=True``), then sets
    floor and dv to their maximum-likelihood values for the residuals (Gaussian errors), which
    makes the weights follow the scatter actually present: 1/sigma^2 weights are efficient only
    if sigma is the real error. Starts from ``sigma_known`` combined with the seed's dv = 0.1 m/s.
    """
    sigma = _error_model_sigma(sigma_known, momentum, 0.0, 0.1)
    floor = dv = 0.0
    for iteration in range(1, max_iterations + 1):
        fit = fit_model(model, t, energy, sigma, absolute_sigma=True)
        resid = energy - MODELS[model].func(t, *fit.params)
        floor, dv = _ml_variance_terms(resid, sigma_known, momentum)
        new = _error_model_sigma(sigma_known, momentum, floor, dv)
        if np.max(np.abs(new / sigma - 1.0)) < rtol:
            return ErrorModel(floor, dv, new, iteration)
        sigma = new
    return ErrorModel(floor, dv, sigma, max_iterations)
