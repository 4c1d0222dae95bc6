r"""Which loss mechanisms drain the real pendulum? Fits of the simulated to the measured energy.

The camera energy of the seed's pendulum (Table 1, rigid links :data:`SEED_RIGID_LINKS`, energies
by :func:`~double_pendulum.analysis.track.measurement.reconstruct` with the package's energy function)
falls from about 0.93 J to 0.55 J in the 21 s after the hand release. Each *model* here is a set of
loss *mechanisms* (:data:`MECHANISMS`) with free parameters; the pendulum is simulated from the
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
matrix tells which parameters the energy separates. :func:`profile_likelihood` re-fits the other
parameters at fixed values of one and gives :math:`\Delta\chi^2/F` (1 at one standard error if the
problem is linear in u).

Simulations run in-process (:func:`double_pendulum.fmu.simulate.simulate`, the FMU's own component;
:class:`ComponentRunner`); the scenario re-runs the best model through the FMU for its headline
numbers. All regularised friction laws use :data:`OMEGA_REG` = 0.01 rad/s (the loss of the
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

from ...fmu.simulate import simulate
from ...model.parameters import SEED_RIGID_LINKS, AirDragParameters
from ..decay.fit import AUTOCORRELATION_LAG_S, MODELS, effective_sample_factor, fit_model
from ..result_cache import cached
from ..suspension.identification import MeasuredDecay, decay_shape, fit_release_state, measured_decay
from ..track.measurement import FPS, FRAME_INTERVAL, Reconstruction, load_track, reconstruct
from . import claims as loss_claims

OMEGA_REG = 0.01
"""Regularisation speed [rad/s] of the friction sign functions in every loss model."""
SIM_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-6, "atol": 1e-8, "omega_reg": OMEGA_REG}
"""Integration tolerances: energy errors ~1e-6 J (chi2 changes by < 0.01 against 1e-8), far below
the effect of a 2 % parameter step (~1e-3 J)."""
QUICK_SIM_SETTINGS: dict[str, Any] = {**SIM_SETTINGS, "rtol": 1e-5, "atol": 1e-7}
"""Integration tolerances of the quick fit (a smoke run): energy errors ~1e-4 J, still a tenth of a 2 %
parameter step's effect, for 0.6 of the CPU per run. Converging at them would stall (Gauss-Newton ran out
of descent after 25 runs), but the quick fit takes one step (:data:`QUICK_RUN_BUDGET`), whose direction the
integration noise turns: chi2 609.3 to 610.1 in trials (air factor 1.5 to 1.7, tau_b 1.2 to 1.3 mN.m)
against 608.9 at the default settings' converged optimum, about one standard error away."""
DIFF_STEP = 0.02
"""Finite-difference step in x = theta / theta_ref: 2 % of a parameter's reference value."""
SUSPENSION_K = 2e4
"""Fixed spring stiffness [N/m] of the suspension mechanism (the parameter default)."""
SUSPENSION_M = 2.0
"""Fixed suspension mass [kg] of the suspension mechanism (the parameter default)."""
LAG_FRAMES = round(AUTOCORRELATION_LAG_S * FPS)
"""Lag window [frames] of the residual autocorrelation (one slow swing)."""
RHO_AIR = AirDragParameters().rho_air


@dataclass(frozen=True)
class Parameter:
    """A free loss parameter: name (as in the summary), unit, reference value (start), bounds."""

    name: str
    unit: str
    ref: float
    bounds: tuple[float, float]
    description: str
    warm_scan: tuple[float, ...] = ()
    """Values tried when the parameter joins a fitted model (:func:`warm_starts`) where its loss is not
    monotonic in it; empty: it joins at :data:`WARM_START_FRACTION` of ``ref``, a negligible loss."""
    start_from: str = ""
    """The parameter of a nested mechanism (:attr:`Mechanism.generalises`) whose fitted value it starts at."""


@dataclass(frozen=True)
class Mechanism:
    """A loss mechanism: its parameters, the FMU start values they give, the work output it books."""

    name: str
    label: str
    work: str
    parameters: tuple[Parameter, ...]
    values: Callable[[Sequence[float]], dict[str, Any]]
    generalises: str = ""
    """The mechanism this one contains as a special case (``drag2`` with equal torques is ``drag``): a model
    with it nests the model with that mechanism instead (:func:`contains`)."""


def _air(x: Sequence[float]) -> dict[str, Any]:
    return {"air_drag": True, "rod_drag": True, "rho_air": RHO_AIR * x[0]}


def _bearing(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_friction": True, "c_R1": x[0], "c_R2": x[0]}


def _viscous(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_friction": True, "c_R1": 0.0, "c_R2": 0.0, "b_v1": x[0], "b_v2": x[0]}


def _drag(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_drag": True, "tau_b1": x[0], "tau_b2": x[0]}


def _drag2(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_drag": True, "tau_b1": x[0], "tau_b2": x[1]}


def _suspension(x: Sequence[float]) -> dict[str, Any]:
    k, m = SUSPENSION_K, SUSPENSION_M
    return {"suspension": True, "k_x": k, "k_y": k, "c_x": x[0], "c_y": x[0], "M_s": m}


MECHANISMS: dict[str, Mechanism] = {
    m.name: m
    for m in (
        Mechanism("air", "air drag", "W_air", (Parameter("air_factor", "1", 1.5, (1e-3, 50.0),
                  "factor on the default drag of bobs and rods (rho_air x factor)"),), _air),
        Mechanism("bearing", "load-proportional bearing friction", "W_bearing",
                  (Parameter("c_R", "1", 1e-3, (1e-7, 1.0), "rolling friction coefficient, both joints"),), _bearing),
        Mechanism("viscous", "viscous joint damping", "W_bearing",
                  (Parameter("b_v", "N.m.s/rad", 1e-4, (1e-9, 1e-1), "viscous joint damping, both joints"),),
                  _viscous),
        Mechanism("drag", "bearing drag torque", "W_bearing_drag",
                  (Parameter("tau_b", "N.m", 1e-3, (1e-7, 1.0), "bearing drag torque, both joints"),), _drag),
        Mechanism("drag2", "bearing drag torque", "W_bearing_drag",
                  (Parameter("tau_b1", "N.m", 1e-3, (1e-7, 1.0), "bearing drag torque, pivot", start_from="tau_b"),
                   Parameter("tau_b2", "N.m", 1e-3, (1e-7, 1.0), "bearing drag torque, elbow", start_from="tau_b")),
                  _drag2, generalises="drag"),
        Mechanism("suspension", "damped suspension", "W_suspension",
                  (Parameter("c_suspension", "N.s/m", 20.0, (1e-2, 1e5),
                             f"suspension damping c_x = c_y at k = {SUSPENSION_K:g} N/m, M_s = {SUSPENSION_M:g} kg",
                             warm_scan=(3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)),),
                  _suspension),
    )
}  # fmt: skip
"""The loss mechanisms a model combines (``drag2``: one drag torque per joint)."""

FULL_MODELS: tuple[str, ...] = (
    "air",
    "drag",
    "air+drag",
    "air+bearing",
    "air+viscous",
    "air+suspension",
)
"""Models of the default identification: mechanisms joined by '+'."""
THOROUGH_MODELS: tuple[str, ...] = (
    *FULL_MODELS,
    "air+drag2",
    "air+drag+bearing",
    "air+drag+viscous",
    "air+drag+suspension",
)
"""Models of the thorough identification: the default ones, ``air+drag2`` (one drag torque per joint: it
generalises air+drag, whose optimum it contains, and ended within 0.05 of its chi2 with a flat valley, dAIC
2.0, in a sequential round of its own) and the three-mechanism models (each the best model plus a third
loss; in the last default run two of them ended at their parent's optimum and the suspension one above
it, at about 90 s of CPU together)."""
QUICK_MODELS: tuple[str, ...] = ("air+drag",)
"""Models of the quick identification (a smoke run: the best model alone, no comparison)."""
QUICK_RUN_BUDGET = 6
"""Runs of each quick fit (:func:`fit_models` with ``max_runs``; the default and thorough fits: up to 30): the
residuals at the references, their Jacobian, one Gauss-Newton step and the Jacobian there, so the fit stops
at ``"run limit"`` after one step. On the seed's record air+drag then ends at chi2 609.2 against 608.9 at its
converged optimum (9 runs, both at :data:`SIM_SETTINGS`), for two thirds of the CPU."""

def mechanisms_of(model: str) -> list[Mechanism]:
    """The mechanisms of a model name such as ``"air+drag"``."""
    return [MECHANISMS[name] for name in model.split("+")]


def contains(model: str, other: str) -> bool:
    """True if ``other`` is nested in ``model`` (and not the same): each of its mechanisms is one of
    ``model``'s or a special case of one (:attr:`Mechanism.generalises`)."""
    mine = {name for m in mechanisms_of(model) for name in (m.name, m.generalises) if name}
    return model != other and set(other.split("+")) <= mine and set(other.split("+")) != set(model.split("+"))


def model_rank(model: str) -> int:
    """Fitting round of a model: its mechanisms, a generalising one (``drag2``) counting twice, so every
    model it contains is fitted in an earlier round and can warm-start it."""
    return sum(2 if m.generalises else 1 for m in mechanisms_of(model))


def parameters_of(model: str) -> list[Parameter]:
    """The free parameters of a model, in order."""
    return [p for m in mechanisms_of(model) for p in m.parameters]


def model_values(model: str, theta: Sequence[float]) -> dict[str, Any]:
    """FMU start values of ``model`` at parameter values ``theta`` (in :func:`parameters_of` order)."""
    values: dict[str, Any] = {}
    i = 0
    for mech in mechanisms_of(model):
        n = len(mech.parameters)
        values.update(mech.values(theta[i : i + n]))
        i += n
    return values


class ComponentRunner:
    """The FMU's co-simulation component in-process, with :class:`~double_pendulum.fmu.runner.FmuRunner`'s
    ``simulate`` signature (same numbers, no FMI layer)."""

    def simulate(self, start_values: Mapping[str, Any] | None = None, **kwargs: Any) -> np.ndarray:
        return simulate(start_values, **kwargs)


# --- the fit problem -----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FitProblem:
    """Measured energy on the fitted frames and the pendulum the models start from.

    ``t0`` [s]: start frame; ``offsets``: fitted frames after it; ``t`` [s], ``energy`` [J],
    ``sigma`` [J]: the measurement; ``base``: FMU start values of the pendulum (lengths, rods,
    start state, solver settings) to which a model's loss values are added.
    """

    t0: float
    offsets: np.ndarray
    t: np.ndarray
    energy: np.ndarray
    sigma: np.ndarray
    base: dict[str, Any]

    @property
    def duration(self) -> float:
        """Simulated time [s] from t0 to the last fitted frame."""
        return int(self.offsets[-1]) * FRAME_INTERVAL

    def simulate(self, values: Mapping[str, Any], outputs: Sequence[str] = ("E_pendulum",), runner: Any = None):
        """Run the pendulum with the loss ``values`` from t0 over the record (rows on the frame grid)."""
        runner = ComponentRunner() if runner is None else runner
        return runner.simulate(
            {**self.base, **values},
            start_time=self.t0,
            stop_time=self.t0 + self.duration,
            output_interval=FRAME_INTERVAL,
            outputs=tuple(outputs),
        )

    def digest(self) -> str:
        """Hash of the measurement and the pendulum: what a fit of this problem depends on."""
        h = hashlib.sha256(json.dumps({"t0": self.t0, "base": self.base}, sort_keys=True).encode())
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
    return FitProblem(f.t0, np.asarray(f.offsets), np.asarray(f.t), np.asarray(md.energy), np.asarray(f.sigma), base)


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
    are cached on disk (:func:`~double_pendulum.analysis.result_cache.cached`, kind ``loss_fits``)
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


def fit_item_of(model: str, fits: Sequence[ModelFit], *, short: bool = True) -> FitItem:
    """The fit item of ``model``: warm-started from the best-fitting (lowest chi2) of ``fits`` nested in it
    (:func:`contains`, :func:`warm_starts`), from the references if none; with :data:`SHORT_RUN_BUDGET`
    runs if it generalises its parent's mechanism or scans a parameter (``short``; the thorough run: 30)."""
    parents = [f for f in fits if contains(model, f.model)]
    if not parents:
        return FitItem(model)
    parent = min(parents, key=lambda f: f.chi2)
    params = parameters_of(model)
    short = short and (any(p.warm_scan for p in params) or any(p.start_from in parent.names for p in params))
    return FitItem(model, warm_starts(model, parent), SHORT_RUN_BUDGET if short else 30)


def run_budget(quick: bool) -> int | None:
    """The run budget :func:`fit_models` imposes on every fit of a mode: :data:`QUICK_RUN_BUDGET` in a quick run,
    none otherwise (each fit item's own, :func:`fit_item_of`)."""
    return QUICK_RUN_BUDGET if quick else None


def fit_models(
    models: Sequence[str], problem: FitProblem, max_workers: int | None = None, pool: Any = None,
    *, short: bool = True, max_runs: int | None = None,
) -> tuple[list[ModelFit], int]:
    """Fit every model, in rounds by :func:`model_rank`: one-mechanism models from the references, each
    larger one warm-started from the best-fitting model of an earlier round nested in it
    (:func:`fit_item_of`); the models of a round are fitted in parallel (on ``pool``'s workers if given,
    a :func:`~double_pendulum.analysis.sweep.worker_pool`); ``short``: see :func:`fit_item_of`;
    ``max_runs``: every fit's run budget instead of its item's (the quick run's, :func:`run_budget`)."""
    from ..sweep import parallel_map  # noqa: PLC0415 - process pools only when identifying

    fits: list[ModelFit] = []
    workers = 1
    for rank in sorted({model_rank(m) for m in models}):
        items = [fit_item_of(m, fits, short=short) for m in models if model_rank(m) == rank]
        if max_runs is not None:
            items = [replace(item, max_nfev=max_runs) for item in items]
        more, used = parallel_map(fit_item, items, shared=problem, max_workers=max_workers, label="loss models",
                                  pool=pool)  # fmt: skip
        fits += more
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


def shares(result: np.ndarray, model: str) -> dict[str, float]:
    """Each mechanism's share of the dissipated work at the end of the run (W_i / sum W) by its label."""
    works = {m.label: float(result[m.work][-1]) for m in mechanisms_of(model)}
    total = sum(works.values())
    return {name: w / total for name, w in works.items()}


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
    r = problem.simulate(_air([1.0]), outputs=("W_air",))
    w = float(r["W_air"][-1])
    return {"W_air_J": w, "share_of_measured_loss": w / measured_loss, "cw_rod": AirDragParameters().cw_rod}


def measured_loss(md: MeasuredDecay) -> float:
    """Energy lost [J] over the fitted frames according to the measured exponential fit."""
    a, b = md.fit.value("a"), md.fit.value("b")
    return a * (math.exp(b * md.frames.t[0]) - math.exp(b * md.frames.t[-1]))


def seed_reconstruction() -> Reconstruction:
    """The seed's track reconstructed with the rigid links :data:`SEED_RIGID_LINKS`."""
    return reconstruct(load_track(), rods=SEED_RIGID_LINKS)


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


def suspension_answer(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Does the suspension dominate the loss? From the suspension's share in every model that has it
    and the top model's composition (a plain sentence and the numbers); not asked (``None``) when no
    fitted model has a suspension (the quick run)."""
    label = MECHANISMS["suspension"].label
    if not any("suspension" in r["model"].split("+") for r in rows):
        return {"suspension_dominates": None, "suspension_share_by_model": {},
                "answer": "Not tested: no model with a suspension was fitted in this run (quick mode fits "
                          "air+drag alone); the default run fits air+suspension."}  # fmt: skip
    with_susp = {r["model"]: r["shares"].get(label) for r in rows if label in r["shares"] and r["converged"]}
    best = rows[0]
    dominates = bool(label in best["shares"] and best["shares"][label] > 0.5)
    if dominates:
        share = best["shares"][label]
        text = f"Yes: the top model ({best['model']}) loses {share:.0%} of its energy in the suspension."
    else:
        parts = ", ".join(f"{m}: {s:.0%} (delta AIC {next(r['delta_aic'] for r in rows if r['model'] == m):.1f})"
                          for m, s in with_susp.items())  # fmt: skip
        if label in best["shares"]:
            text = f"No: the suspension carries {best['shares'][label]:.0%} of the loss in the top model"
        else:
            text = f"No: the top model ({best['model']}) needs no suspension loss"
        text += f"; suspension share where it is fitted: {parts}." if parts else "."
    return {"suspension_dominates": dominates, "answer": text, "suspension_share_by_model": with_susp}


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
    runner: Any, *, quick: bool = False, thorough: bool = False, max_workers: int | None = None
) -> LossIdentification:
    """Fit every model (:data:`FULL_MODELS`; thorough: :data:`THOROUGH_MODELS`; quick: :data:`QUICK_MODELS`,
    in this process, at :data:`QUICK_SIM_SETTINGS` with :data:`QUICK_RUN_BUDGET` runs: one Gauss-Newton
    step) in parallel with the in-process component, compare them, profile the best one (thorough mode only:
    in the runs so far its intervals matched the curvature errors, for 8 more fits, about 18 s of CPU) and
    re-run it through ``runner`` (the FMU) for the headline numbers. One pool of worker processes serves
    every round and the profile. All modes fit the whole record (the first 8 s alone leave the losses
    unidentified); the fits are cached (:func:`fit_loss_model`), and ``measured_vs_sim`` obtains its
    ``air+drag`` by :func:`identified_fit` from the same problem (:func:`problem_from_track` in the same
    mode: the same start, budget and settings), so it reads this mode's fit."""
    from ..sweep import parallel_map, worker_pool  # noqa: PLC0415 - process pools only when identifying

    rec = seed_reconstruction()
    md = measured(rec)
    problem = problem_from_track(rec, md, quick=quick)
    models = QUICK_MODELS if quick else THOROUGH_MODELS if thorough else FULL_MODELS
    profile: dict[str, Any] = {}
    max_workers = 1 if quick else max_workers  # one model: no worker processes to start
    with worker_pool(max_workers) as pool:
        fits, workers = fit_models(models, problem, max_workers, pool, short=not thorough, max_runs=run_budget(quick))
        factor = common_factor(fits)
        rows = comparison_rows(fits, factor)
        best = next(f for f in fits if f.model == rows[0]["model"])
        if thorough:
            items = profile_items(best, factor)
            chi2s, _ = parallel_map(profile_item, items, shared=problem, max_workers=max_workers, label="profile",
                                    pool=pool)  # fmt: skip
            profile = profile_summary(best, factor, items, chi2s)
    works = sorted({m.work for m in mechanisms_of(best.model)})
    result = problem.simulate(model_values(best.model, best.theta), outputs=("E_pendulum", *works), runner=runner)
    e_sim = np.asarray(result["E_pendulum"])[problem.offsets]
    _, kappa = problem.scaled_residuals(e_sim)
    numbers = decay_numbers(problem, problem.energy, e_sim)
    halves = half_residuals(problem, e_sim, kappa, factor)
    loss = measured_loss(md)
    summary = {
        "scenario": "loss_identification",
        "source": "seed Table 1 (data/seed_table1.csv), rigid links SEED_RIGID_LINKS",
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
        "residual_halves": halves,
        "goal": goal_checks(numbers, halves),
        "measured_loss_J": loss,
        "simulated_loss_J": float(sum(float(result[w][-1]) for w in works)),
        **suspension_answer(rows),
        "supported_models": loss_claims.supported_models(rows),
        "b_sim_range_all_models_per_s": loss_claims.b_sim_range(rows),
        "drag_torque_against_seed_rolling_friction": next(
            (loss_claims.seed_rolling_friction(rec.params, r["parameters"]["tau_b"]["value"]) for r in rows
             if r["model"] == "air+drag"), None),
        "air_drag_at_defaults": air_share_at_defaults(problem, loss),
        "models": rows,
        "suspension_fixed": {"k_N_per_m": SUSPENSION_K, "M_s_kg": SUSPENSION_M},
        "omega_reg_rad_per_s": OMEGA_REG,
        "null_means": {"suspension_dominates": "not tested: no model with a suspension was fitted (quick mode)",
                       "profile_likelihood": "empty: profiled with --thorough only (its intervals matched the "
                                             "curvature errors in the runs so far)"},
        "start_state": {k: problem.base[k] for k in ("phi1_0", "phi2_0", "omega1_0", "omega2_0")},
    }
    t = problem.t
    return LossIdentification(summary, t, problem.energy, problem.sigma, kappa * e_sim,
                              {w: np.asarray(result[w])[problem.offsets] for w in works})  # fmt: skip
