r"""Fits of the simulated to the measured energy: the fit problem, damped Gauss-Newton, the cached fits.

The camera energy of the seed's pendulum (Table 1, rigid links :data:`SEED_RIGID_LINKS`, energies
by :func:`~double_pendulum.analysis.track.measurement.reconstruct` with the package's energy function)
falls from about 0.93 J to 0.55 J in the 21 s after the hand release. Each *model* here is a set of
loss *mechanisms* (:data:`.mechanisms.MECHANISMS`) with free parameters; the pendulum is simulated from the
measured start state (:func:`~double_pendulum.analysis.suspension.identification.fit_release_state`)
and its energy ``E_pendulum`` compared with the measured one frame by frame:

.. math::

    r_i(\theta) = \frac{\kappa\,E^{sim}_i(\theta) - E_i}{\sigma_i},\qquad
    \kappa(\theta) = \frac{\sum_i E^{sim}_i E_i/\sigma_i^2}{\sum_i (E^{sim}_i)^2/\sigma_i^2}

with the calibrated errors :math:`\sigma_i` of the exponential fit
(:func:`~double_pendulum.analysis.decay.fit.calibrate_error_model`). :math:`\kappa` (profiled out
analytically) absorbs the energy calibration of the camera (rod masses, lengths, start state,
about 1 %); it changes neither the decay rate b nor the loss exponent p. :math:`\chi^2 = |r|^2` is
minimised by damped Gauss-Newton (:func:`gauss_newton`) in :math:`x_j = \theta_j/\theta_{j,ref}`,
:math:`\theta_j = \theta_{j,ref}|x_j|` clipped to its bounds (the energy lost is nearly linear in
each loss coefficient, so it converges in two or three steps; scipy's ``least_squares`` needed
15 to 30 runs for the same optimum).

Correlated residuals. The residuals of a smooth model against the measured energy are correlated
over about a swing; :func:`~double_pendulum.analysis.decay.fit.effective_sample_factor` gives the
variance factor F (n_eff = n/F). It is taken from the model that fits best (lowest chi2) and used
for every model, so the comparison stays a likelihood ratio:

.. math::

    AIC = \chi^2/F + 2k,\qquad BIC = \chi^2/F + k\ln(n/F)

(k: free loss parameters + 1 for :math:`\kappa`). Covariance of x: :math:`F (J^T J)^{-1}` (J the
Jacobian of r in x at the optimum); :math:`\sigma_\theta = \theta_{ref}\,\sigma_x`; the correlation
matrix tells which parameters the energy separates. The profile likelihood (:func:`.comparison.profile_items`)
re-fits the other parameters at fixed values of one and gives :math:`\Delta\chi^2/F` (1 at one standard error if the
problem is linear in u).

Simulations run in-process (:func:`double_pendulum.fmu.masters.simulate.simulate`, the FMU's own component;
:class:`ComponentRunner`); the scenario re-runs the best model through the FMU for its headline
numbers. All regularised friction laws use :data:`.mechanisms.OMEGA_REG` = 0.01 rad/s (the loss of the
regularisation below it is < 1e-4 of the drag torque's work over a swing of ~5 rad/s peak rate).

Units: energies J, times s, c_R 1, tau_b N m, b_v N m s/rad, c N s/m, the air factor 1 (multiplies
rho_air, i.e. all drag coefficients).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ...fmu.masters.simulate import simulate
from ...model.parameters import SEED_RIGID_LINKS
from ...runs.result_cache import cached
from ..decay.fit import fit_model
from ..suspension.identification import MeasuredDecay, decay_shape, fit_release_state
from ..track.measurement import FRAME_INTERVAL, Reconstruction
from .mechanisms import (
    DIFF_STEP,
    FULL_MODELS,
    QUICK_MODELS,
    QUICK_RUN_BUDGET,
    QUICK_SIM_SETTINGS,
    SIM_SETTINGS,
    contains,
    mechanisms_of,
    model_rank,
    model_values,
    parameters_of,
    shares,
)


class ComponentRunner:
    """The FMU's co-simulation component in-process, with :class:`~double_pendulum.fmu.running.runner.FmuRunner`'s
    ``simulate`` signature (same numbers, no FMI layer)."""

    def simulate(self, start_values: Mapping[str, Any] | None = None, **kwargs: Any) -> np.ndarray:
        return simulate(start_values, **kwargs)


# --- the fit problem -----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FitProblem:
    """Measured energy on the fitted frames and the pendulum the models start from.

    ``t0`` [s]: start frame; ``offsets``: fitted frames after it; ``t`` [s], ``energy`` [J],
    ``sigma`` [J]: the measurement; ``base``: FMU start values of the pendulum (lengths, rods,
    start state, solver settings) to which a model's loss values are added; ``dt`` [s]: the frame interval.
    """

    t0: float
    offsets: np.ndarray
    t: np.ndarray
    energy: np.ndarray
    sigma: np.ndarray
    base: dict[str, Any]
    dt: float = FRAME_INTERVAL

    @property
    def duration(self) -> float:
        """Simulated time [s] from t0 to the last fitted frame."""
        return int(self.offsets[-1]) * self.dt

    def simulate(self, values: Mapping[str, Any], outputs: Sequence[str] = ("E_pendulum",), runner: Any = None):
        """Run the pendulum with the loss ``values`` from t0 over the record (rows on the frame grid)."""
        runner = ComponentRunner() if runner is None else runner
        return runner.simulate(
            {**self.base, **values},
            start_time=self.t0,
            stop_time=self.t0 + self.duration,
            output_interval=self.dt,
            outputs=tuple(outputs),
        )

    def digest(self) -> str:
        """Hash of the measurement and the pendulum: what a fit of this problem depends on."""
        h = hashlib.sha256(json.dumps({"t0": self.t0, "dt": self.dt, "base": self.base}, sort_keys=True).encode())
        for a in (self.offsets, self.t, self.energy, self.sigma):
            h.update(np.ascontiguousarray(a, dtype=float).tobytes())
        return h.hexdigest()[:16]

    def scaled_residuals(self, e_sim: np.ndarray) -> tuple[np.ndarray, float]:
        """Normalised residuals r and the calibration kappa (module docstring) of a simulated energy."""
        w = 1.0 / self.sigma**2
        kappa = float(np.sum(w * e_sim * self.energy) / np.sum(w * e_sim * e_sim))
        return (kappa * e_sim - self.energy) / self.sigma, kappa

    def residuals(self, model: str, theta: Sequence[float]) -> np.ndarray:
        """Normalised residuals of ``model`` at ``theta``."""
        e_sim = np.asarray(self.simulate(model_values(model, theta))["E_pendulum"])[self.offsets]
        return self.scaled_residuals(e_sim)[0]


def problem_from_track(
    rec: Reconstruction, md: MeasuredDecay, runner: Any = None, *, quick: bool = False
) -> FitProblem:
    """The fit problem of a reconstruction with rods: measured decay ``md``, start state fitted after the release;
    runs at :data:`SIM_SETTINGS` (``quick``: :data:`QUICK_SIM_SETTINGS`, the start state fitted as
    :func:`~double_pendulum.analysis.suspension.identification.fit_release_state` does in a quick run)."""
    runner = ComponentRunner() if runner is None else runner
    rods = {k: getattr(rec.params, k) for k in SEED_RIGID_LINKS}
    pendulum = {"l1": rec.params.l1, "l2": rec.params.l2, "m1": rec.params.m1, "m2": rec.params.m2, **rods}
    start = fit_release_state(runner, rec, {**pendulum, "air_drag": True, "rod_drag": True}, quick=quick)
    base = {**(QUICK_SIM_SETTINGS if quick else SIM_SETTINGS), **pendulum, **start.start_values()}
    f = md.frames
    return FitProblem(f.t0, np.asarray(f.offsets), np.asarray(f.t), np.asarray(md.energy), np.asarray(f.sigma), base,
                      f.dt)


# --- fitting one model ---------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ModelFit:
    """Least-squares fit of one model: parameters, chi2, Jacobian in x = theta/ref, kappa, runs."""

    model: str
    theta: np.ndarray
    chi2: float
    n: int
    jac: np.ndarray
    residuals: np.ndarray
    kappa: float
    n_runs: int
    factor: float = 1.0
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        return [p.name for p in parameters_of(self.model)]

    @property
    def k(self) -> int:
        """Fitted parameters: the loss parameters and kappa."""
        return len(self.theta) + 1

    @property
    def ref(self) -> np.ndarray:
        return np.array([p.ref for p in parameters_of(self.model)])

    def cov(self, factor: float) -> np.ndarray:
        """Covariance of theta [units^2]: ``factor ref ref^T (J^T J)^-1`` (J in x = theta/ref)."""
        return factor * np.linalg.pinv(self.jac.T @ self.jac) * np.outer(self.ref, self.ref)

    def stderr(self, factor: float) -> np.ndarray:
        """Standard errors of theta (in its units)."""
        return np.sqrt(np.diag(self.cov(factor)))

    def correlation(self, factor: float) -> np.ndarray:
        """Correlation matrix of the parameters."""
        c = self.cov(factor)
        d = np.sqrt(np.diag(c))
        return c / np.outer(d, d)

    def criteria(self, factor: float) -> tuple[float, float]:
        """(AIC, BIC) with the residual-correlation factor (module docstring)."""
        n_eff = self.n / factor
        return self.chi2 / factor + 2.0 * self.k, self.chi2 / factor + self.k * math.log(n_eff)


CHI2_TOLERANCE = 0.05
"""A Gauss-Newton step that promises less than this decrease of chi2 ends the fit: one standard error
of a parameter is a chi2 change of about F (1.3), so 0.05 moves no result by more than 0.2 of its error."""


def gauss_newton(
    residuals: Callable[[np.ndarray], np.ndarray], x0: np.ndarray, *, max_runs: int = 30, xtol: float = 1e-2
) -> tuple[np.ndarray, np.ndarray, str]:
    r"""Minimise :math:`|r(x)|^2` by damped Gauss-Newton with a forward-difference Jacobian.

    Each iteration: :math:`J_{:j} = (r(x + h e_j) - r(x))/h` (h = :data:`DIFF_STEP`, one run per
    parameter), step :math:`\Delta x = -(J^T J + \lambda\,\mathrm{diag} J^T J)^{-1} J^T r`, halved
    while :math:`|r|^2` grows (:math:`\lambda` = 1e-6 guards near-degenerate directions). Stops when
    :math:`\max|\Delta x_j| <` ``xtol`` (1 % of a reference value, far below the parameters' errors),
    or when the step's predicted decrease of :math:`|r|^2` (linear model) is below
    :data:`CHI2_TOLERANCE` (along a valley of strongly correlated parameters the step can stay large
    while chi2 is flat to within the integration noise), or after ``max_runs`` runs.
    The problem is nearly linear in x, so two or three iterations suffice. Returns x, J at x and why it
    stopped: ``"converged"`` (step below ``xtol``), ``"run limit"`` or ``"no descent"`` (six halvings of
    the step did not lower chi2).
    """
    x = np.asarray(x0, dtype=float).copy()
    r0 = residuals(x)
    if not len(x):  # every parameter held (a one-parameter model's profile point): nothing to fit
        return x, np.zeros((len(r0), 0)), "converged"
    runs = 1
    while True:
        jac = np.column_stack([(residuals(x + DIFF_STEP * e) - r0) / DIFF_STEP for e in np.eye(len(x))])
        runs += len(x)
        a = jac.T @ jac
        dx = -np.linalg.pinv(a + 1e-6 * np.diag(np.diag(a))) @ (jac.T @ r0)  # pinv: a column may vanish at a bound
        predicted = float(r0 @ r0 - np.sum((r0 + jac @ dx) ** 2))
        if np.max(np.abs(dx)) < xtol or predicted < CHI2_TOLERANCE:
            return x, jac, "converged"
        if runs >= max_runs:
            return x, jac, "run limit"
        for _ in range(6):
            r_new = residuals(x + dx)
            runs += 1
            if r_new @ r_new <= r0 @ r0:
                break
            dx *= 0.5
        else:
            return x, jac, "no descent"
        x, r0 = x + dx, r_new


def fit_loss_model(
    model: str,
    problem: FitProblem,
    fixed: Mapping[int, float] | None = None,
    start: Sequence[float] | None = None,
    max_nfev: int = 30,
) -> ModelFit:
    """Fit ``model`` to ``problem`` (least squares in x = theta/ref); ``fixed``: index -> value held.

    ``start``: start values of theta (default the references). Returns the fit at the optimum. Fits
    are cached on disk (:func:`~double_pendulum.runs.result_cache.cached`, kind ``loss_fits``)
    under the model, the start, the held values, the run budget and the problem's digest: a repeated
    run, or another scenario fitting the same model from the same start, reads the same fit.
    """
    key = {"model": model, "fixed": sorted((int(i), float(v)) for i, v in (fixed or {}).items()),
           "start": None if start is None else [float(v) for v in start], "max_nfev": max_nfev,
           "problem": problem.digest()}  # fmt: skip
    return cached("loss_fits", key, lambda: _fit_loss_model(model, problem, fixed, start, max_nfev))


def _fit_loss_model(
    model: str,
    problem: FitProblem,
    fixed: Mapping[int, float] | None,
    start: Sequence[float] | None,
    max_nfev: int,
) -> ModelFit:
    """:func:`fit_loss_model` without the cache. Every run books the model's works too, so the run at the
    optimum (the last accepted one) gives its shares and no run is repeated."""
    params = parameters_of(model)
    fixed = dict(fixed or {})
    ref = np.array([p.ref for p in params])
    theta0 = ref.copy() if start is None else np.asarray(start, dtype=float).copy()
    free = [i for i in range(len(params)) if i not in fixed]
    runs = [0]
    works = sorted({m.work for m in mechanisms_of(model)})
    results: dict[bytes, np.ndarray] = {}  # run result by theta, to reuse the one at the optimum

    lo = np.array([params[i].bounds[0] for i in free])
    hi = np.array([params[i].bounds[1] for i in free])

    def theta_of(x: np.ndarray) -> np.ndarray:
        theta = theta0.copy()
        theta[free] = np.clip(ref[free] * np.abs(x), lo, hi)  # |x|: a loss coefficient is >= 0
        for i, v in fixed.items():
            theta[i] = v
        return theta

    def run(theta: np.ndarray) -> np.ndarray:
        key = theta.tobytes()
        if key not in results:
            runs[0] += 1
            results[key] = problem.simulate(model_values(model, theta), outputs=("E_pendulum", *works))
        return results[key]

    def resid(x: np.ndarray) -> np.ndarray:
        return problem.scaled_residuals(np.asarray(run(theta_of(x))["E_pendulum"])[problem.offsets])[0]

    x, jac, stop = gauss_newton(resid, theta0[free] / ref[free], max_runs=max_nfev)
    theta = theta_of(x)
    result = run(theta)
    r, kappa = problem.scaled_residuals(np.asarray(result["E_pendulum"])[problem.offsets])
    e_fit = problem.energy + r * problem.sigma  # kappa E_sim on the frames
    extra = {"shares": shares(result, model), "stop": stop, "decay": {
        "b_sim_per_s": fit_model("exponential", problem.t, e_fit, problem.sigma).value("b"),
        "p_sim": decay_shape(problem.t, e_fit, problem.sigma)["p"]}}  # fmt: skip
    return ModelFit(model, theta, float(r @ r), len(r), jac, r, kappa, runs[0], extra=extra)


@dataclass(frozen=True)
class FitItem:
    """A model to fit and its candidate start values (none: the parameters' references); with several,
    the fit starts from the one with the lowest chi2."""

    model: str
    starts: tuple[tuple[float, ...], ...] = ()
    max_nfev: int = 30


def fit_item(item: FitItem, problem: FitProblem) -> ModelFit:
    """:func:`fit_loss_model` for :func:`~double_pendulum.analysis.sweep.parallel_map`, from the best of
    ``item.starts`` (one run each when there are several)."""
    start = None
    if len(item.starts) == 1:
        start = item.starts[0]
    elif item.starts:
        chi2 = [float(np.sum(problem.residuals(item.model, s) ** 2)) for s in item.starts]
        start = item.starts[int(np.argmin(chi2))]
    return fit_loss_model(item.model, problem, start=start, max_nfev=item.max_nfev)


WARM_START_FRACTION = 1e-3
"""An added mechanism starts at this fraction of its reference value: a loss far below the others, so
the nested model starts at its parent's chi2 (up to ~1e-3 of the parent's loss)."""


def warm_starts(model: str, parent: ModelFit) -> tuple[tuple[float, ...], ...]:
    """Candidate start values of ``model`` from a nested ``parent`` fit: shared parameters at the parent's
    optimum, an added one at :data:`WARM_START_FRACTION` of its reference, or at each value of its
    ``warm_scan`` (the suspension: its loss vanishes only as c goes to 0, where the undamped suspension
    trades energy with the pendulum, or to infinity, where it is rigid; in between it peaks). A nested
    model then starts no worse than its parent where a negligible loss exists, so its chi2 cannot end
    above the parent's through a poor start."""
    known = dict(zip(parent.names, parent.theta))
    choices = [(float(known[p.name]),) if p.name in known else (float(known[p.start_from]),)
               if p.start_from in known else (p.warm_scan or (WARM_START_FRACTION * p.ref,))
               for p in parameters_of(model)]  # fmt: skip
    return tuple(itertools.product(*choices))


SHORT_RUN_BUDGET = 12
"""Gauss-Newton runs (after any warm scan) of a model whose fit cannot change the comparison's figures by
more than they state: one that generalises its parent's mechanism (``air+drag2`` from ``air+drag``: the
same optimum plus a flat valley along one extra parameter, its chi2 within ~0.05 of the parent's, so its
delta AIC is 2.0 to the stated 0.1 however long it runs) and one with a scanned parameter (the suspension:
in every run so far its chi2 stayed above the nested model's for every scanned c, so it is not ranked).
Thirty runs of each bought the default run nothing but about 20 s of CPU."""


def fit_items_of(model: str, fits: Sequence[ModelFit], *, short: bool = True) -> list[FitItem]:
    """The fit items of ``model``, best first: one warm-started from each of ``fits`` nested in it and in no other
    of them (:func:`contains`, :func:`warm_starts`; air+viscous from air drag alone and from viscous damping
    alone), or one from the references if none; :func:`fit_models` keeps the item that ends lowest. From one
    parent only, a valley of two correlated losses can end the fit short of the optimum the other parent's start
    reaches (air+viscous from viscous damping alone stopped 0.18 in chi2 above it). Each with
    :data:`SHORT_RUN_BUDGET` runs if it generalises its parent's mechanism or scans a parameter (``short``; the
    thorough run: 30)."""
    nested = [f for f in fits if contains(model, f.model)]
    parents = sorted((f for f in nested if not any(contains(g.model, f.model) for g in nested)), key=lambda f: f.chi2)
    if not parents:
        return [FitItem(model)]
    params = parameters_of(model)
    items = []
    for parent in parents:
        brief = short and (any(p.warm_scan for p in params) or any(p.start_from in parent.names for p in params))
        items.append(FitItem(model, warm_starts(model, parent), SHORT_RUN_BUDGET if brief else 30))
    return items


def run_budget(quick: bool) -> int | None:
    """The run budget :func:`fit_models` imposes on every fit of a mode: :data:`QUICK_RUN_BUDGET` in a quick run,
    none otherwise (each fit item's own, :func:`fit_items_of`)."""
    return QUICK_RUN_BUDGET if quick else None


def fit_models(
    models: Sequence[str], problem: FitProblem, max_workers: int | None = None, pool: Any = None,
    *, short: bool = True, max_runs: int | None = None,
) -> tuple[list[ModelFit], int]:
    """Fit every model, in rounds by :func:`model_rank`: one-mechanism models from the references, each
    larger one warm-started from the models of earlier rounds nested in it, keeping the fit that ends lowest
    (:func:`fit_items_of`); the items of a round are fitted in parallel (on ``pool``'s workers if given,
    a :func:`~double_pendulum.analysis.sweep.worker_pool`); ``short``: see :func:`fit_items_of`;
    ``max_runs``: every fit's run budget instead of its item's (the quick run's, :func:`run_budget`)."""
    from ..sweep import parallel_map  # noqa: PLC0415 - process pools only when identifying

    fits: list[ModelFit] = []
    workers = 1
    for rank in sorted({model_rank(m) for m in models}):
        items = [item for m in models if model_rank(m) == rank for item in fit_items_of(m, fits, short=short)]
        if max_runs is not None:
            items = [replace(item, max_nfev=max_runs) for item in items]
        more, used = parallel_map(fit_item, items, shared=problem, max_workers=max_workers, label="loss models",
                                  pool=pool)  # fmt: skip
        best: dict[str, ModelFit] = {}
        for fit in more:  # several starts of one model: the fit that ends lowest
            if fit.model not in best or fit.chi2 < best[fit.model].chi2:
                best[fit.model] = fit
        fits += [best[m] for m in models if m in best]
        workers = max(workers, used)
    return fits, workers


def identified_fit(model: str, problem: FitProblem, *, quick: bool = False) -> ModelFit:
    """The fit of ``model`` (one of :data:`FULL_MODELS`; quick: :data:`QUICK_MODELS`) exactly as
    :func:`identify_losses` obtains it in that mode, in this process: the same rounds (:func:`fit_models`)
    restricted to ``model`` and the default models nested in it, so its item (start, run budget) is the
    identification's and :func:`fit_loss_model`'s cache serves either run with the other's fits."""
    models = QUICK_MODELS if quick else FULL_MODELS
    if model not in models:
        raise ValueError(f"{model!r} is not fitted by the {'quick' if quick else 'default'} identification {models}")
    needed = [m for m in models if m == model or contains(model, m)]
    fits, _ = fit_models(needed, problem, max_workers=1, max_runs=run_budget(quick))
    return next(f for f in fits if f.model == model)
