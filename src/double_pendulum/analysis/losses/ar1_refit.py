r"""The loss models fitted again under the AR(1) noise model: the parameters that maximise its likelihood.

The fits of :mod:`.fitting` minimise :math:`\chi^2 = |r|^2`, as if the frames were independent; :mod:`.noise`
writes the AR(1) likelihood of the residuals. Evaluated at the least-squares optimum it is a lower bound on the
likelihood's maximum, and a model whose misfit is slow (what AR(1) forgives) gains least from being re-fitted.
Here every model is fitted under the likelihood itself. With the marginal variance profiled out,

.. math::

    -2\ln L(\theta, \kappa, \rho) = n \ln Q(\theta, \kappa, \rho) - \ln(1-\rho^2) + \mathrm{const},\qquad
    Q = \frac{|W_\rho\, r|^2}{1-\rho^2},\qquad r_i = \frac{\kappa E^{sim}_i(\theta) - E_i}{\sigma_i}

(:math:`W_\rho`: Prais-Winsten whitening, :func:`~double_pendulum.analysis.decay.noise.prewhiten`; :math:`\sigma_i`
[J] the frames' calibrated errors, :math:`E` [J] the energies). It is maximised by alternating (Cochrane-Orcutt):

1. at fixed :math:`\rho`, :math:`\theta` by damped Gauss-Newton (:func:`.fitting.gauss_newton`) on the whitened
   residuals :math:`w = W_\rho r/\sqrt{(1-\rho^2)\,s_0^2}` (:math:`s_0^2 = Q/n` at the start of the round, so a
   change of :math:`|w|^2` is the change of :math:`-2\ln L` to first order and the fit's tolerance keeps its meaning),
   with the calibration :math:`\kappa` profiled by generalised least squares,
   :math:`\kappa = \langle W a, W b\rangle / |W a|^2`, :math:`a = E^{sim}/\sigma`, :math:`b = E/\sigma`;
2. at fixed :math:`\theta`, :math:`\rho` by :func:`.noise.ar1_fit`;

until :math:`\rho` moves by less than :data:`RHO_TOLERANCE` (at most :data:`MAX_ROUNDS` rounds). Neither step can
raise :math:`-2\ln L`, so the re-fit ends at or below the least-squares optimum's value; it starts there, from that
fit's parameters, with the run budget of its fit item (:data:`REFIT_RUN_BUDGET`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...runs.result_cache import cached
from ..decay.noise import prewhiten
from .fitting import FitProblem, ModelFit, gauss_newton
from .mechanisms import mechanisms_of, model_values, parameters_of, shares
from .noise import ar1_fit

RHO_TOLERANCE = 0.005
"""A round of the alternation that moves rho by less than this ends the re-fit (rho's own standard error on the
seed's record is about sqrt((1 - rho^2)/n) = 0.04)."""
MAX_ROUNDS = 4
"""Rounds of the alternation at most (two sufficed on the seed's record)."""
REFIT_RUN_BUDGET = 12
"""Simulation runs of one model's Gauss-Newton at one rho (:data:`.fitting.SHORT_RUN_BUDGET`'s size): the re-fit
starts at the least-squares optimum, one Jacobian and a step or two away from the new one."""


@dataclass(frozen=True)
class RefitItem:
    """A least-squares fit to re-fit under AR(1): its model, optimum theta and normalised residuals there."""

    model: str
    theta: tuple[float, ...]
    residuals: np.ndarray = field(repr=False)
    max_runs: int = REFIT_RUN_BUDGET

    @classmethod
    def of(cls, fit: ModelFit, max_runs: int = REFIT_RUN_BUDGET) -> RefitItem:
        return cls(fit.model, tuple(float(v) for v in fit.theta), np.asarray(fit.residuals, dtype=float), max_runs)


@dataclass(frozen=True, eq=False)
class Ar1Refit:
    """One model fitted under the AR(1) likelihood: theta [units of its parameters], kappa [1], rho [1], the
    normalised residuals r at the optimum (GLS kappa), -2 ln L there and at the least-squares optimum (of the
    normalised residuals), the rounds, the runs, why the last Gauss-Newton stopped, and the mechanisms' shares of the
    dissipated work at the optimum."""

    model: str
    theta: np.ndarray
    kappa: float
    rho: float
    residuals: np.ndarray
    neg2_log_l: float
    neg2_log_l_least_squares: float
    rounds: int
    runs: int
    stop: str
    shares: dict[str, float]

    def as_dict(self) -> dict[str, Any]:
        """The summary's entry: parameters by name, the likelihood's gain over the least-squares optimum."""
        return {"theta": {p.name: float(v) for p, v in zip(parameters_of(self.model), self.theta)},
                "kappa": self.kappa, "rho": self.rho, "gain_neg2_log_likelihood":
                self.neg2_log_l_least_squares - self.neg2_log_l, "rounds": self.rounds, "runs": self.runs,
                "stop": self.stop, "shares": self.shares}  # fmt: skip


def gls_residuals(problem: FitProblem, e_sim: np.ndarray, rho: float) -> tuple[np.ndarray, float]:
    """Normalised residuals r [1] of the simulated energy ``e_sim`` [J] on the fitted frames with kappa profiled by
    generalised least squares at ``rho`` (module docstring), and that kappa."""
    a, b = e_sim / problem.sigma, problem.energy / problem.sigma
    wa, wb = prewhiten(a, rho), prewhiten(b, rho)
    kappa = float(wa @ wb / (wa @ wa))
    return kappa * a - b, kappa


def neg2_log_l(r: np.ndarray) -> tuple[float, float]:
    """(-2 ln L at its maximising rho, that rho) of normalised residuals ``r`` (:func:`.noise.ar1_fit`)."""
    f = ar1_fit(r)
    return f.neg2_log_l, f.rho


def refit_ar1(item: RefitItem, problem: FitProblem) -> Ar1Refit:
    """:func:`_refit` cached on disk (kind ``loss_fits_ar1``) under the model, its least-squares optimum, the budget
    and the problem's digest; a module-level function of (item, shared) for
    :func:`~double_pendulum.analysis.sweep.parallel_map`."""
    key = {"model": item.model, "theta": list(item.theta), "max_runs": item.max_runs, "problem": problem.digest(),
           "rounds": MAX_ROUNDS, "rho_tolerance": RHO_TOLERANCE}  # fmt: skip
    return cached("loss_fits_ar1", key, lambda: _refit(item, problem))


def _refit(item: RefitItem, problem: FitProblem) -> Ar1Refit:
    """:func:`refit_ar1` without the cache (module docstring)."""
    params = parameters_of(item.model)
    ref = np.array([p.ref for p in params])
    lo = np.array([p.bounds[0] for p in params])
    hi = np.array([p.bounds[1] for p in params])
    works = sorted({m.work for m in mechanisms_of(item.model)})
    results: dict[bytes, np.ndarray] = {}

    def theta_of(x: np.ndarray) -> np.ndarray:
        return np.clip(ref * np.abs(x), lo, hi)  # as the least-squares fit maps x: a loss coefficient is >= 0

    def run(theta: np.ndarray) -> np.ndarray:
        if theta.tobytes() not in results:
            results[theta.tobytes()] = problem.simulate(model_values(item.model, theta), outputs=("E_pendulum", *works))
        return results[theta.tobytes()]

    def energy(x: np.ndarray) -> np.ndarray:
        return np.asarray(run(theta_of(x))["E_pendulum"])[problem.offsets]

    start, rho = neg2_log_l(item.residuals)
    x = np.asarray(item.theta, dtype=float) / ref
    stop, rounds = "converged", 0
    while rounds < MAX_ROUNDS:
        rounds += 1
        r0, _ = gls_residuals(problem, energy(x), rho)
        scale = math.sqrt(float(prewhiten(r0, rho) @ prewhiten(r0, rho)) / len(r0))  # sqrt((1 - rho^2) s0^2)

        def whitened(x: np.ndarray, rho: float = rho, scale: float = scale) -> np.ndarray:
            return prewhiten(gls_residuals(problem, energy(x), rho)[0], rho) / scale

        x, _, stop = gauss_newton(whitened, x, max_runs=item.max_runs)
        _, new_rho = neg2_log_l(gls_residuals(problem, energy(x), rho)[0])
        moved, rho = abs(new_rho - rho), new_rho
        if moved < RHO_TOLERANCE:
            break
    theta = theta_of(x)
    r, kappa = gls_residuals(problem, energy(x), rho)
    value, rho = neg2_log_l(r)
    return Ar1Refit(item.model, theta, kappa, rho, r, value, start, rounds, len(results), stop,
                    shares(run(theta), item.model))


def refit_models(fits: Sequence[ModelFit], problem: FitProblem, pool: Any = None, max_workers: int | None = None,
                 max_runs: int = REFIT_RUN_BUDGET) -> dict[str, Ar1Refit]:
    """Every fit of ``fits`` re-fitted under AR(1) (:func:`refit_ar1`), in parallel on ``pool``'s workers, by
    model."""
    from ..sweep import parallel_map  # noqa: PLC0415 - process pools only when identifying

    items = [RefitItem.of(f, max_runs) for f in fits]
    out, _ = parallel_map(refit_ar1, items, shared=problem, max_workers=max_workers, label="AR(1) re-fits", pool=pool)
    return {r.model: r for r in out}
