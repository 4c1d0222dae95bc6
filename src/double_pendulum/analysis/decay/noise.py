r"""Statistical error of the exponential fit E = a exp(b t) [J] with correlated residuals: an AR(1) noise
model and a moving-block bootstrap.

The fit (:func:`~double_pendulum.analysis.decay.fit.fit_model`) minimises
:math:`\sum_i z_i^2` with the normalised residuals :math:`z_i = (E_i - a e^{b t_i}) / \sigma_i`
(sigma_i [J] the per-frame errors, 1 for equal weights). Its standard errors assume independent z_i;
the measured residuals are correlated over about a swing. Two descriptions of that noise:

- **AR(1).** :math:`z_i = \rho z_{i-1} + s\,\varepsilon_i` with independent standard normal
  :math:`\varepsilon_i`, so :math:`\mathrm{var}\,z = s^2/(1-\rho^2)` and
  :math:`\mathrm{corr}(z_i, z_j) = \rho^{|i-j|}`. rho is the lag-one autocorrelation of the fit's
  residuals (:func:`~double_pendulum.analysis.ar1.ar1_coefficient`, Yule-Walker). Two uses:

  * the error of the weighted least-squares (WLS) estimate itself under that noise, the sandwich
    :math:`C_\theta = (J^T J)^{-1} J^T \Sigma J (J^T J)^{-1}` with the normalised Jacobian
    :math:`J_{ij} = \partial f_i/\partial\theta_j / \sigma_i` and
    :math:`\Sigma_{ij} = \hat v\,\rho^{|i-j|}`, :math:`\hat v = \sum z_i^2/(n-2)`
    (:func:`ar1_sandwich_errors`, through :func:`~double_pendulum.analysis.ar1.ar1_sandwich`);
  * the generalised least-squares fit with that likelihood (:func:`ar1_gls_fit`, Prais-Winsten):
    minimise :math:`\sum_i w_i^2` with the prewhitened residuals :math:`w_1 = \sqrt{1-\rho^2}\,z_1`,
    :math:`w_i = z_i - \rho z_{i-1}`, which is -2 ln L up to terms free of (a, b) at fixed rho
    (:math:`-2\ln L = \sum w_i^2/s^2 + n \ln s^2 - \ln(1-\rho^2) + n\ln 2\pi`); rho is re-estimated
    from the new residuals until it settles (Cochrane-Orcutt iteration); covariance
    :math:`\hat s^2 (J_w^T J_w)^{-1}`, :math:`\hat s^2 = \sum w_i^2/(n-2)`, J_w the whitened Jacobian.

- **Moving-block bootstrap** (:func:`block_bootstrap`): no model of the correlation within a block.
  Blocks of L consecutive normalised residuals of the WLS fit, starting at uniformly drawn frames, are
  laid end to end into a new residual series z*; the record E* = f(t; a, b) + sigma z* is refitted (WLS,
  Gauss-Newton from the fitted values); the standard deviation of the refitted b over the resamples is
  b's statistical error. L must exceed the residuals' correlation time; the default
  :data:`~double_pendulum.analysis.decay.fit.AUTOCORRELATION_LAG_S` (1.5 s, one slow swing of 1.31 s
  and the lag window of the record's correlation factor F) keeps a whole swing's pattern inside a block.

Units: t [s], E and sigma [J], a [J], b [1/s], rho and z dimensionless.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..ar1 import ar1_coefficient, ar1_sandwich
from .fit import AUTOCORRELATION_LAG_S, exponential, fit_model, residual_autocorrelation

BOOTSTRAP_RESAMPLES = 1000
"""Resamples of the moving-block bootstrap of a record (b's error to about 2 % of itself)."""
BOOTSTRAP_SEED = 20240935
"""Seed of the bootstrap's random generator (the summary is reproducible)."""
GAUSS_NEWTON_STEPS = 6
"""Gauss-Newton steps of each bootstrap refit from the fitted values (converged to < 1e-10 relative)."""


def exponential_jacobian(t: np.ndarray, a: float, b: float) -> np.ndarray:
    """d(a exp(b t))/d(a, b) at times ``t`` [s]: columns exp(b t) [1] and a t exp(b t) [J s], shape (n, 2)."""
    t = np.asarray(t, dtype=float)
    g = np.exp(b * t)
    return np.column_stack([g, a * t * g])


def _weights(sigma: np.ndarray | None, n: int) -> np.ndarray:
    return np.ones(n) if sigma is None else np.asarray(sigma, dtype=float)


def ar1_sandwich_errors(
    t: np.ndarray, energy: np.ndarray, sigma: np.ndarray | None, a: float, b: float, rho: float
) -> tuple[float, float]:
    """Standard errors (sigma_a [J], sigma_b [1/s]) of the WLS fit (a, b) under AR(1) residuals of
    coefficient ``rho`` (the sandwich of the module docstring); ``sigma`` [J] the fit's errors (None: equal)."""
    t = np.asarray(t, dtype=float)
    w = _weights(sigma, len(t))
    z = (np.asarray(energy, dtype=float) - exponential(t, a, b)) / w
    cov = ar1_sandwich(exponential_jacobian(t, a, b) / w[:, None], z, rho)
    return float(math.sqrt(cov[0, 0])), float(math.sqrt(cov[1, 1]))


def prewhiten(z: np.ndarray, rho: float) -> np.ndarray:
    """Prais-Winsten prewhitening along the last axis: sqrt(1 - rho^2) z_1, z_i - rho z_(i-1)."""
    out = np.empty_like(z)
    out[..., 0] = math.sqrt(1.0 - rho**2) * z[..., 0]
    out[..., 1:] = z[..., 1:] - rho * z[..., :-1]
    return out


@dataclass(frozen=True)
class Ar1Fit:
    """GLS fit of E = a exp(b t) with AR(1) residuals: a [J], b [1/s], their errors, rho, iterations."""

    a: float
    b: float
    sigma_a: float
    sigma_b: float
    rho: float
    iterations: int


def ar1_gls_fit(
    t: np.ndarray, energy: np.ndarray, sigma: np.ndarray | None, *, rtol: float = 1e-6, max_iterations: int = 20
) -> Ar1Fit:
    """Prais-Winsten GLS fit of E = a exp(b t) (module docstring), rho iterated from the residuals."""
    t = np.asarray(t, dtype=float)
    e = np.asarray(energy, dtype=float)
    w = _weights(sigma, len(t))
    wls = fit_model("exponential", t, e, sigma)
    theta = wls.params.copy()
    rho = ar1_coefficient((e - exponential(t, *theta)) / w)
    iterations = 0
    for iterations in range(1, max_iterations + 1):  # noqa: B007 (the count is returned)
        r = rho
        res = least_squares(lambda p, r=r: prewhiten((e - exponential(t, *p)) / w, r), theta,
                            jac=lambda p, r=r: -prewhiten((exponential_jacobian(t, *p) / w[:, None]).T, r).T)
        theta = res.x
        rho = ar1_coefficient((e - exponential(t, *theta)) / w)
        if abs(rho - r) < rtol:
            break
    white = prewhiten((e - exponential(t, *theta)) / w, rho)
    jw = prewhiten((exponential_jacobian(t, *theta) / w[:, None]).T, rho).T
    cov = float(white @ white) / (len(t) - 2) * np.linalg.inv(jw.T @ jw)
    return Ar1Fit(float(theta[0]), float(theta[1]), math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1]), rho, iterations)


def block_length_frames(t: np.ndarray, seconds: float = AUTOCORRELATION_LAG_S) -> int:
    """``seconds`` [s] in samples of the evenly spaced times ``t`` [s] (at least 1)."""
    return max(1, round(seconds / float(np.median(np.diff(t)))))


def _block_resample(z: np.ndarray, block: int, n_boot: int, rng: np.random.Generator) -> np.ndarray:
    """``n_boot`` moving-block resamples of the series ``z`` (blocks of ``block`` frames end to end), (n_boot, n)."""
    n = len(z)
    n_blocks = -(-n // block)
    starts = rng.integers(0, n - block + 1, size=(n_boot, n_blocks))
    idx = (starts[:, :, None] + np.arange(block)).reshape(n_boot, -1)[:, :n]
    return z[idx]


def gauss_newton_exponential(t: np.ndarray, energy: np.ndarray, w: np.ndarray, a0: float, b0: float,
                             steps: int = GAUSS_NEWTON_STEPS) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """WLS fits of E = a exp(b t) to each row of ``energy`` (shape (m, n), errors ``w`` [J]), vectorised
    Gauss-Newton from (a0, b0); returns the arrays a [J] and b [1/s]."""
    e = np.atleast_2d(energy)
    a = np.full(len(e), a0, dtype=float)
    b = np.full(len(e), b0, dtype=float)
    for _ in range(steps):
        g = np.exp(b[:, None] * t) / w
        ja, jb = g, a[:, None] * t * g
        r = e / w - a[:, None] * g
        saa, sab, sbb = (ja * ja).sum(1), (ja * jb).sum(1), (jb * jb).sum(1)
        ra, rb = (ja * r).sum(1), (jb * r).sum(1)
        det = saa * sbb - sab**2
        a = a + (sbb * ra - sab * rb) / det
        b = b + (saa * rb - sab * ra) / det
    return a, b


def block_bootstrap(
    t: np.ndarray,
    energy: np.ndarray,
    sigma: np.ndarray | None,
    a: float,
    b: float,
    *,
    block: int,
    n_boot: int = BOOTSTRAP_RESAMPLES,
    rng: np.random.Generator | None = None,
) -> tuple[float, float]:
    """Moving-block bootstrap errors (sigma_a [J], sigma_b [1/s]) of the WLS fit (a, b) of E(t) with errors
    ``sigma`` [J] (None: equal weights), blocks of ``block`` frames (module docstring)."""
    rng = np.random.default_rng(BOOTSTRAP_SEED) if rng is None else rng
    t = np.asarray(t, dtype=float)
    w = _weights(sigma, len(t))
    fitted = exponential(t, a, b)
    z = (np.asarray(energy, dtype=float) - fitted) / w
    z_star = _block_resample(z - z.mean(), block, n_boot, rng)
    a_star, b_star = gauss_newton_exponential(t, fitted + w * z_star, w, a, b)
    return float(np.std(a_star, ddof=1)), float(np.std(b_star, ddof=1))


def noise_model(t: np.ndarray, energy: np.ndarray, sigma: np.ndarray | None, *,
                block_s: float = AUTOCORRELATION_LAG_S, n_boot: int = BOOTSTRAP_RESAMPLES) -> dict:  # fmt: skip
    """The WLS fit of E = a exp(b t) with its statistical errors from both noise descriptions (JSON-ready).

    Keys: ``a_J``, ``b_per_s`` (the WLS fit), ``rho`` (lag-one autocorrelation of its normalised residuals),
    ``ar1`` (sandwich errors of the WLS fit under AR(1)), ``gls`` (the AR(1) GLS fit with its errors and rho),
    ``bootstrap`` (moving-block errors, block length in frames and seconds, resamples), ``definitions``.
    """
    t = np.asarray(t, dtype=float)
    e = np.asarray(energy, dtype=float)
    wls = fit_model("exponential", t, e, sigma, absolute_sigma=sigma is not None)
    a, b = wls.value("a"), wls.value("b")
    z = (e - exponential(t, a, b)) / _weights(sigma, len(t))
    rho = ar1_coefficient(z)
    sa, sb = ar1_sandwich_errors(t, e, sigma, a, b, rho)
    gls = ar1_gls_fit(t, e, sigma)
    block = block_length_frames(t, block_s)
    acf = residual_autocorrelation(z, block)
    dt = float(np.median(np.diff(t)))
    ba, bb = block_bootstrap(t, e, sigma, a, b, block=block, n_boot=n_boot)
    return {
        "a_J": a,
        "b_per_s": b,
        "rho": rho,
        "autocorrelation_lags_1_to_3": [float(x) for x in acf[1:4]],
        "first_negative_lag_s": float(np.argmax(acf < 0.0) * dt) if np.any(acf < 0.0) else None,
        "ar1": {"a_J_stderr": sa, "b_per_s_stderr": sb},
        "gls": {"a_J": gls.a, "b_per_s": gls.b, "a_J_stderr": gls.sigma_a, "b_per_s_stderr": gls.sigma_b,
                "rho": gls.rho, "iterations": gls.iterations},  # fmt: skip
        "bootstrap": {"a_J_stderr": ba, "b_per_s_stderr": bb, "block_frames": block,
                      "block_s": block * dt, "resamples": n_boot},  # fmt: skip
        "definitions": {
            "first_negative_lag_s": "smallest lag [s] at which the residuals' autocorrelation is negative "
                                    "(None: not within the block length)",
            "rho": "lag-one autocorrelation of the normalised residuals (E - a exp(b t)) / sigma of the fit",
            "ar1": "errors of this fit if the normalised residuals are AR(1) with coefficient rho: "
                   "(J'J)^-1 J' S J (J'J)^-1, S_ij = v rho^|i-j|, v = sum z^2 / (n - 2)",
            "gls": "the Prais-Winsten (generalised least-squares) fit with AR(1) residuals: the likelihood's "
                   "optimum, rho iterated, errors s^2 (Jw'Jw)^-1 of the prewhitened problem",
            "bootstrap": "standard deviation of b over refits of E* = a exp(b t) + sigma z*, z* blocks of "
                         "consecutive normalised residuals drawn with replacement (moving-block bootstrap); "
                         "blocks of 1.5 s hold one slow swing (1.31 s), longer than the residuals' correlation",
        },
    }
