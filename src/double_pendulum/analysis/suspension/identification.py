r"""Identification of a damped pivot suspension from the measured energy decay of the pendulum.

The camera measured the pendulum's energy falling as E = a exp(b t) (the project's fit of Table 1,
``energy_decay``: b = -0.0252 1/s; the seed: b = -0.024 1/s). This module prepares that measurement
and fits the damping of an isotropic suspension of the pivot (mass M_s, springs k = k_x = k_y,
dampers c = c_x = c_y) to it through the FMU, with air drag (bobs and rods) and bearing friction
on (:data:`LOSSES`).

Measured decay (:func:`measured_decay`). The camera energy after the hand release with the
calibrated errors of :func:`~double_pendulum.analysis.decay.fit.calibrate_error_model`, fitted with
E = a exp(b t) (``decay_fit`` model ``exponential``); the error of b is inflated by
sqrt(F), F the record's residual-correlation factor
(:func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`, also the factor of the damping's error).
Every FMU run starts from the state the
pendulum was measured in after the release (fitted to the first :data:`START_FIT_FRAMES` frames by
:func:`double_pendulum.analysis.track.start_state.fit_start_state`).

Decay rate. b is fitted to the **pendulum's** energy E_pendulum (the two bobs, output of the FMU)
on the measured frames with the measured fit's calibrated errors (:func:`simulated_decay_rate`), so
a simulated b and the measured b are the same statistic of the same frames. The camera sees the
bobs only, so E_pendulum is the measured quantity; E_total = E_pendulum + E_suspension differs by
the energy stored in the suspension.

Identification (:func:`identify_damping`). At fixed k and M_s,

.. math::

    \chi^2(c) = \sum_i \frac{(E^{FMU}_i(c) - E_i)^2}{\sigma_i^2}

is minimised by Gauss-Newton in ln c (:func:`least_squares_1d`), started from the c at which the
linear response of :mod:`double_pendulum.analysis.suspension.response` gives the missing share of b
(:func:`guess_damping`); :math:`\sigma_c^2 = F / (J^T J)` with J = dr/dc at the optimum.

The valley (:func:`valley_fisher`). The energy fixes one combination of (k, c, M_s): the Jacobian of
the residuals in (ln k, ln c, ln M_s) gives the Fisher matrix :math:`J^T J`, its weakest direction
and the slope of the valley :math:`d\ln c/d\ln k = -J_k\cdot J_c / J_c\cdot J_c` (the stiff limit
b ~ c/k^2 would give 2). :func:`double_pendulum.analysis.suspension.decay_map.trace_valley` follows it.

Decay shape (:func:`decay_shape`). Besides b, the power law dE/dt = -k E^p (``decay_fit`` model
``power``) is fitted to the measured and the simulated energies: p tells how the loss depends on the
amplitude (1/2 for Coulomb friction, 1 for viscous losses, 3/2 for quadratic drag).

Units: k in N/m, c in N s/m, M_s in kg, energies in J, times in s, rates in 1/s.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ...model.parameters import SuspensionParameters
from ..decay.fit import FitResult, calibrate_error_model, fit_model, record_correlation_factor
from ..track.measurement import FRAME_INTERVAL, Reconstruction, load_track, reconstruct
from ..track.start_state import StartStateFit, fit_start_state, track_window
from ..track.tilt import seed_record_geometry
from .response import ForceSpectrum, pivot_force_spectrum

LOSSES: dict[str, bool] = {"air_drag": True, "rod_drag": True, "bearing_friction": True}
"""Air drag on bobs and rods and bearing friction, at their default (the seed's) coefficients."""
FIT_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-7, "atol": 1e-9}
"""Tolerances of the least-squares runs: integration errors (~1e-7 J) far below the energy change of a
finite-difference step (~1 mJ). The identified c moves by 4e-5 relative from rtol 1e-8 (a 600th of its
standard error) for a quarter less CPU."""
C_DIFF_STEP = 0.01
"""Finite-difference step in ln c of the damping fit (1 % in c)."""
C_XTOL = 0.01
"""Change of ln c [-] at which the damping fit stops (1 % in c, a tenth of its error)."""
QUICK_START_TOLERANCE = 1e-3
"""Relative stopping tolerance (chi2 and parameters) of the quick runs' release-state fits: 15 FMU runs instead
of 25 on the seed's release, the state within 1e-5 rad and 2e-5 rad/s of the default fit's (its errors:
3e-3 rad, 3e-2 rad/s)."""
QUICK_C_XTOL = 0.1
"""The same in the quick identification (10 % in c, about a quarter of its error on :data:`QUICK_WINDOW_S`): 6
FMU runs instead of 8, c = 17.3 +- 4.3 N s/m against 16.0 +- 4.2 (the first 8 s, to 1 %: 18.0 +- 3.4), the
simulated decay rate within 0.7 % of the measured one (with :data:`QUICK_START_TOLERANCE`)."""
DEFAULT_SUSPENSION = SuspensionParameters()
START_FIT_FRAMES = 10
"""Frames after the release fitted for the start state (1/3 s: long enough for the rates, short
enough that model error does not yet dominate; see ``measured_vs_sim``)."""
JACOBIAN_STEP = 0.02
"""Step in ln k, ln c, ln M_s for the valley's Jacobian columns (2 %)."""
QUICK_WINDOW_S = 7.0
"""Seconds after the release fitted by the quick identification (``quick=True``, a smoke run; the quick map
and the runs after it simulate this window too). 5 s would fit c as well within its error (17.9 +- 7.5
N s/m), but the simulated decay rate then ends 5 % from the measured one, outside the tests' tolerance."""


# --- measured decay and the frames everything is compared on -------------------------------------


@dataclass(frozen=True, eq=False)
class FitFrames:
    """Frames on which a decay rate is fitted: ``t0`` [s] of the start frame, ``offsets`` (frames
    after it), their times ``t`` [s] and energy errors ``sigma`` [J] (None: equal weights), ``dt`` [s]
    the frame interval."""

    t0: float
    offsets: np.ndarray
    t: np.ndarray
    sigma: np.ndarray | None
    dt: float = FRAME_INTERVAL

    @property
    def n_frames(self) -> int:
        """Frames to simulate (start frame up to the last fitted one)."""
        return int(self.offsets[-1]) + 1

    @property
    def duration(self) -> float:
        """Simulated time [s] from t0 to the last fitted frame."""
        return (self.n_frames - 1) * self.dt


@dataclass(frozen=True, eq=False)
class MeasuredDecay:
    """The measured energy after the release with calibrated errors and its exponential fit.

    ``factor`` is the record's residual-correlation variance factor
    (:func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`, the same for every fit to it);
    ``b_err`` is the fit error of b inflated by sqrt(factor).
    """

    rec: Reconstruction
    i0: int
    frames: FitFrames
    energy: np.ndarray
    fit: FitResult
    factor: float

    @property
    def b(self) -> float:
        return self.fit.value("b")

    @property
    def b_err(self) -> float:
        return self.fit.error("b") * math.sqrt(self.factor)


def measured_decay(rec: Reconstruction, window_s: float | None = None) -> MeasuredDecay:
    """Exponential fit of the measured energy after the release (as ``energy_decay``), optionally
    only the first ``window_s`` seconds [s] after it; errors from
    :func:`~double_pendulum.analysis.decay.fit.calibrate_error_model`."""
    i0 = rec.release_frame
    mask = rec.free_motion.copy()
    if window_s is not None:
        mask &= rec.t <= rec.t[i0] + window_s
    idx = np.flatnonzero(mask)
    t, e = rec.t[idx], rec.energy[idx]
    errors = calibrate_error_model(t, e, rec.sigma_energy[idx], rec.momentum[idx])
    fit = fit_model("exponential", t, e, errors.sigma)
    factor = record_correlation_factor(t, e, errors.sigma)
    frames = FitFrames(float(rec.t[i0]), idx - i0, t, errors.sigma, rec.track.dt)
    return MeasuredDecay(rec, int(i0), frames, e, fit, factor)


def simulated_decay_rate(result: np.ndarray, frames: FitFrames, output: str = "E_pendulum") -> float:
    """b [1/s] of ``E = a exp(b t)`` fitted to a run's ``output`` on ``frames`` (rows = frames after t0)."""
    energy = np.asarray(result[output])[frames.offsets]
    return fit_model("exponential", frames.t, energy, frames.sigma).value("b")


# --- model values --------------------------------------------------------------------------------


def suspension_values(k: float, c: float, m_s: float) -> dict[str, Any]:
    """FMU start values of an isotropic suspension: k_x = k_y = k [N/m], c_x = c_y = c [N s/m], M_s [kg]."""
    return {"suspension": True, "k_x": k, "k_y": k, "c_x": c, "c_y": c, "M_s": m_s}


def pendulum_values(rec: Reconstruction) -> dict[str, float]:
    """The measured rod lengths (the masses are the defaults, as in the reconstruction)."""
    return {"l1": rec.params.l1, "l2": rec.params.l2}


def fit_release_state(
    runner: FmuRunner, rec: Reconstruction, model_values: Mapping[str, Any], *, quick: bool = False
) -> StartStateFit:
    """Least-squares start state at the end of the hand release over :data:`START_FIT_FRAMES` frames
    (``quick``: to :data:`QUICK_START_TOLERANCE`; otherwise to scipy's default 1e-8)."""
    window = track_window(rec, rec.release_frame, START_FIT_FRAMES)
    return fit_start_state(
        runner, window.t0, window.offsets, window.positions, window.sigma_positions, window.guess, model_values,
        dt=rec.track.dt, **({"tolerance": QUICK_START_TOLERANCE} if quick else {}),
    )


def simulate_frames_from(
    runner: FmuRunner,
    values: Mapping[str, Any],
    frames: FitFrames,
    settings: Mapping[str, Any] = FIT_SETTINGS,
    outputs: Sequence[str] = ("E_pendulum", "E_total"),
    interval: float | None = None,
) -> np.ndarray:
    """Run the FMU from ``frames.t0`` to the last fitted frame (rows on ``t0 + n interval``, default the frames'
    interval ``frames.dt``)."""
    return runner.simulate(
        {**settings, **values},
        start_time=frames.t0,
        stop_time=frames.t0 + frames.duration,
        output_interval=frames.dt if interval is None else interval,
        outputs=outputs,
    )


# --- identification ------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Identification:
    """Damping c [N s/m] fitted at fixed k [N/m] and M_s [kg] to the measured energy per frame.

    ``c_stderr`` is the Jacobian error inflated by sqrt(``factor``) (residual correlation),
    ``c_stderr_fit`` the plain one; ``residuals`` are normalised, ``jac_c`` is d r / d c [s m/N].
    """

    k: float
    m_s: float
    c: float
    c_stderr: float
    c_stderr_fit: float
    chi2: float
    n: int
    factor: float
    residuals: np.ndarray
    jac_c: np.ndarray
    n_fmu_runs: int

    @property
    def chi2_red(self) -> float:
        return self.chi2 / (self.n - 1)

    def values(self) -> dict[str, Any]:
        """The identified suspension as FMU start values."""
        return suspension_values(self.k, self.c, self.m_s)

    def as_dict(self) -> dict[str, Any]:
        return {
            "k_N_per_m": self.k,
            "M_s_kg": self.m_s,
            "c_N_s_per_m": self.c,
            "c_stderr": self.c_stderr,
            "c_stderr_uncorrelated": self.c_stderr_fit,
            "autocorrelation_factor": self.factor,
            "chi2": self.chi2,
            "chi2_red": self.chi2_red,
            "n_frames": self.n,
            "n_fmu_runs": self.n_fmu_runs,
        }


def energy_residuals(
    runner: FmuRunner, md: MeasuredDecay, base: Mapping[str, Any], suspension: Mapping[str, Any]
) -> np.ndarray:
    """(E_pendulum simulated - E measured) / sigma on the fitted frames."""
    result = simulate_frames_from(runner, {**base, **suspension}, md.frames, outputs=("E_pendulum",))
    return (np.asarray(result["E_pendulum"])[md.frames.offsets] - md.energy) / md.frames.sigma


@dataclass(frozen=True, eq=False)
class LeastSquares1D:
    """Result of :func:`least_squares_1d`: parameter, residuals and Jacobian column there, runs used."""

    x: float
    residuals: np.ndarray
    jac: np.ndarray
    n_runs: int


def least_squares_1d(
    residuals: Any, x0: float, *, rel_step: float, rel_tol: float, bounds: tuple[float, float], max_iterations: int = 12
) -> LeastSquares1D:
    r"""Minimise :math:`|r(x)|^2` over one positive parameter x by Gauss-Newton in u = ln x.

    Each iteration evaluates r and the forward difference :math:`J_u = (r(x e^h) - r(x))/h`,
    h = ``rel_step`` (two FMU runs), steps :math:`\Delta u = -J_u\cdot r / J_u\cdot J_u`, halved
    while :math:`|r|^2` grows, within ``bounds`` (on x); stops when :math:`|\Delta u| <` ``rel_tol``.
    Returns x, r(x) and :math:`J = dr/dx = J_u / x` at the last evaluated point.
    """
    runs = 0

    def r(u: float) -> np.ndarray:
        nonlocal runs
        runs += 1
        return residuals(math.exp(u))

    lo, hi = math.log(bounds[0]), math.log(bounds[1])
    u, r0 = math.log(x0), r(math.log(x0))
    for _ in range(max_iterations):
        jac = (r(u + rel_step) - r0) / rel_step
        du = -float(jac @ r0) / float(jac @ jac)
        if abs(du) < rel_tol:
            break
        for _ in range(5):
            u_new = min(max(u + du, lo), hi)
            r_new = r(u_new)
            if r_new @ r_new <= r0 @ r0:
                break
            du *= 0.5
        else:
            break
        u, r0 = u_new, r_new
    return LeastSquares1D(math.exp(u), r0, jac / math.exp(u), runs)


C_BOUNDS = (0.1, 1e4)
"""Range of c [N s/m] the damping fit may search."""


def identify_damping(
    runner: FmuRunner,
    md: MeasuredDecay,
    base: Mapping[str, Any],
    k: float,
    m_s: float,
    c_guess: float,
    rel_tol: float = C_XTOL,
) -> Identification:
    r"""Least squares of E_pendulum against the measured energy over c (k, M_s fixed), until ln c changes by
    less than ``rel_tol``.

    :math:`\chi^2(c) = \sum_i (E^{FMU}_i(c) - E_i)^2/\sigma_i^2` with the calibrated errors,
    minimised by :func:`least_squares_1d`;
    :math:`\sigma_c^2 = F / (J^T J)` with J = d r / d c at the optimum and F the record's
    residual-correlation factor (``md.factor``: :func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`).
    """

    def residuals(c: float) -> np.ndarray:
        return energy_residuals(runner, md, base, suspension_values(k, c, m_s))

    gn = least_squares_1d(residuals, c_guess, rel_step=C_DIFF_STEP, rel_tol=rel_tol, bounds=C_BOUNDS)
    factor = md.factor
    s_c = 1.0 / math.sqrt(float(gn.jac @ gn.jac))
    return Identification(
        k=k,
        m_s=m_s,
        c=gn.x,
        c_stderr=s_c * math.sqrt(factor),
        c_stderr_fit=s_c,
        chi2=float(gn.residuals @ gn.residuals),
        n=len(gn.residuals),
        factor=factor,
        residuals=gn.residuals,
        jac_c=gn.jac,
        n_fmu_runs=gn.n_runs,
    )


def guess_damping(spectrum: ForceSpectrum, b_target_susp: float, k: float, m_s: float) -> float:
    """c [N s/m] at which the linear response gives the suspension share ``b_target_susp`` [1/s].

    Searched on a logarithmic grid of c on the rising (under-damped) side; the default c if none fits.
    """
    cs = np.geomspace(0.1, 1e4, 200)
    rates = np.array([spectrum.linear_response_rate(k, c, m_s) for c in cs])
    below = np.flatnonzero(rates <= b_target_susp)
    if len(below) == 0 or below[0] == 0:
        return DEFAULT_SUSPENSION.c_x
    i = below[0]
    x = np.interp(b_target_susp, [rates[i], rates[i - 1]], [math.log(cs[i]), math.log(cs[i - 1])])
    return float(math.exp(x))


@dataclass(frozen=True)
class IdentifiedModel:
    """Everything another scenario needs to run the identified pendulum (lengths, losses, suspension)."""

    values: dict[str, Any]
    start: StartStateFit
    identification: Identification
    measured: MeasuredDecay
    spectrum: ForceSpectrum


def identify_suspension(
    runner: FmuRunner,
    rec: Reconstruction | None = None,
    *,
    quick: bool = False,
    k: float = DEFAULT_SUSPENSION.k_x,
    m_s: float = DEFAULT_SUSPENSION.M_s,
) -> IdentifiedModel:
    """Fit the release state and the damping c at fixed k, M_s (defaults: the parameter defaults).

    The cheap path other scenarios use: no sweep; the start of the c iteration comes from the linear
    response. ``quick`` fits only the first :data:`QUICK_WINDOW_S` seconds, to :data:`QUICK_C_XTOL`.

    The result is kept for the rest of the process, keyed by the FMU file's content, the track, ``quick``,
    ``k`` and ``m_s``, so repeated calls in one process (the tests' fixtures and ``suspension_transfer``)
    fit it once.
    """
    rec = reconstruct(load_track(), seed_record_geometry().geometry) if rec is None else rec
    key = (_file_digest(runner.fmu_path), _track_digest(rec), quick, k, m_s)
    if key not in _IDENTIFIED:
        _IDENTIFIED.clear()  # one entry is all a run needs
        _IDENTIFIED[key] = _identify_suspension(runner, rec, quick, k, m_s)
    return _IDENTIFIED[key]


_IDENTIFIED: dict[tuple, IdentifiedModel] = {}


def _file_digest(path: Any) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _track_digest(rec: Reconstruction) -> str:
    digest = hashlib.sha256(repr((rec.params, rec.release_frame, rec.sigma_pos1, rec.sigma_pos2)).encode())
    for name in ("t", "x1", "y1", "x2", "y2", "energy", "sigma_energy", "momentum", "free_motion"):
        digest.update(np.ascontiguousarray(getattr(rec, name)).tobytes())
    return digest.hexdigest()


def _identify_suspension(runner: FmuRunner, rec: Reconstruction, quick: bool, k: float, m_s: float) -> IdentifiedModel:
    md = measured_decay(rec, QUICK_WINDOW_S if quick else None)
    model = {**pendulum_values(rec), **LOSSES}
    start = fit_release_state(runner, rec, {**model, "suspension": True}, quick=quick)
    base = {**model, **start.start_values()}
    m12 = rec.params.m1 + rec.params.m2
    spectrum = pivot_force_spectrum(runner, base, md.frames.t0, md.frames.duration, m12, rec.params.g)
    base_rate = simulated_decay_rate(simulate_frames_from(runner, base, md.frames), md.frames)
    c_guess = guess_damping(spectrum, md.b - base_rate, k, m_s)
    ident = identify_damping(runner, md, base, k, m_s, c_guess, QUICK_C_XTOL if quick else C_XTOL)
    return IdentifiedModel({**base, **ident.values()}, start, ident, md, spectrum)


# --- the valley of the identification ------------------------------------------------------------


def valley_fisher(
    runner: FmuRunner, md: MeasuredDecay, base: Mapping[str, Any], ident: Identification
) -> dict[str, Any]:
    r"""Jacobian of the energy residuals in (ln k, ln c, ln M_s) at the identified point and what it says.

    Columns by forward differences of :data:`JACOBIAN_STEP` (ln c: the fit's own, times c). The
    Fisher matrix :math:`F = J^T J`; the covariance of (ln k, ln c) with k free too is
    :math:`f\,(F_{kc})^{-1}` (f the correlation factor). Along the valley the residuals do not change
    to first order: :math:`d\ln c/d\ln k = -J_k\cdot J_c / J_c\cdot J_c` (the stiff limit b ~ c/k^2
    would give 2).
    """
    r0 = ident.residuals
    cols = {"ln_c": ident.jac_c * ident.c}
    for name, k, m_s in (
        ("ln_k", ident.k * math.exp(JACOBIAN_STEP), ident.m_s),
        ("ln_M_s", ident.k, ident.m_s * math.exp(JACOBIAN_STEP)),
    ):
        cols[name] = (energy_residuals(runner, md, base, suspension_values(k, ident.c, m_s)) - r0) / JACOBIAN_STEP
    names = ("ln_k", "ln_c", "ln_M_s")
    jac = np.column_stack([cols[n] for n in names])
    fisher = jac.T @ jac
    cov_kc = ident.factor * np.linalg.inv(fisher[:2, :2])
    eigval, eigvec = np.linalg.eigh(fisher)
    jk, jc = cols["ln_k"], cols["ln_c"]
    return {
        "parameters": list(names),
        "fisher": fisher.tolist(),
        "eigenvalues": eigval.tolist(),
        "weakest_direction": dict(zip(names, eigvec[:, 0].tolist())),
        "cov_ln_k_ln_c_with_k_free": cov_kc.tolist(),
        "stderr_ln_k_with_k_free": math.sqrt(cov_kc[0, 0]),
        "stderr_ln_c_with_k_free": math.sqrt(cov_kc[1, 1]),
        "correlation_ln_k_ln_c": cov_kc[0, 1] / math.sqrt(cov_kc[0, 0] * cov_kc[1, 1]),
        "valley_slope_dlnc_dlnk": -float(jk @ jc) / float(jc @ jc),
        "stiff_limit_slope": 2.0,
        "sensitivity_ratio_M_s_to_c": math.sqrt(fisher[2, 2] / fisher[1, 1]),
        "cos_angle_ln_k_ln_M_s": fisher[0, 2] / math.sqrt(fisher[0, 0] * fisher[2, 2]),
    }


# --- decay shape and checks of the identification ------------------------------------------------


def decay_shape(t: np.ndarray, energy: np.ndarray, sigma: np.ndarray | None, factor: float = 1.0) -> dict[str, float]:
    """Exponent p of dE/dt = -k E^p fitted to E(t) [J] (``decay_fit`` model ``power``), error x sqrt(factor)."""
    fit = fit_model("power", t, energy, sigma)
    return {"p": fit.value("p"), "p_stderr": fit.error("p") * math.sqrt(factor)}


def point_summary(md: MeasuredDecay, fit: Identification, reference_chi2: float) -> dict[str, Any]:
    """A fitted (k, c) with its chi2 difference to the reference, b and p of its simulated energy."""
    energy = md.energy + fit.residuals * md.frames.sigma  # the simulated E_pendulum on the frames
    b = fit_model("exponential", md.frames.t, energy, md.frames.sigma).value("b")
    return {
        **fit.as_dict(),
        "delta_chi2": fit.chi2 - reference_chi2,
        "delta_chi2_over_factor": (fit.chi2 - reference_chi2) / fit.factor,
        "b_per_s": b,
        "b_relative_to_measured": (b - md.b) / md.b,
        "p": decay_shape(md.frames.t, energy, md.frames.sigma)["p"],
    }


def window_check(
    runner: FmuRunner, rec: Reconstruction, base: Mapping[str, Any], ident: Identification, window_s: float
) -> dict[str, Any]:
    """The damping fitted to the first ``window_s`` seconds only: one c should describe every window."""
    md = measured_decay(rec, window_s)
    fit = identify_damping(runner, md, base, ident.k, ident.m_s, ident.c)
    return {
        "window_s": window_s,
        "measured_b_per_s": md.b,
        "measured_b_stderr": md.b_err,
        **point_summary(md, fit, fit.chi2),
    }
