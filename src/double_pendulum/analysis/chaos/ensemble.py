r"""Batch integration: many trajectories of the same model at once, vectorised with NumPy.

State layout: ``Y`` has shape ``(d, N)``, one row per state component and one column per
trajectory; for the pendulum ``d = 4`` with rows :math:`\varphi_1, \varphi_2` [rad] and
:math:`\omega_1, \omega_2` [rad/s]. Every arithmetic operation of the model then runs once over
the whole ensemble, on contiguous rows.

One copy of the physics: :func:`pendulum_field` is the model's right-hand side
:math:`\dot\varphi_i = \omega_i`, :math:`\dot\omega_i = \ddot\varphi_i` with the accelerations from
:func:`double_pendulum.model.dynamics.link_accelerations` called with ``sin=np.sin, cos=np.cos``;
energies and positions come from :mod:`double_pendulum.model.energy` and
:mod:`double_pendulum.model.kinematics` the same way. The methods use the Butcher tableaus of
:mod:`double_pendulum.solvers.tableaus`.

Two methods, chosen for two jobs:

* **fixed-step RK4** (:func:`rk4_step`, :func:`rk4_iterate`, :func:`rk4_trajectory`) is the
  workhorse for maps and clouds. All trajectories share the grid :math:`t_0 + n h`, so the batch
  advances in lock-step without masks, output sampling and event detection (flips, section
  crossings) are plain array comparisons, and a trajectory-step costs only 4 evaluations. The stage
  arithmetic is that of :class:`double_pendulum.solvers.runge_kutta.ClassicRK4` in the same order,
  so a column equals the single-trajectory ``rk4`` result up to the last-bit differences between
  NumPy's and ``math``'s sine (``tests/test_ensemble.py``).
* **DOP853 with per-trajectory step control** (:func:`dop853_trajectory`) gives accurate
  references (Lyapunov estimates, checks). Each trajectory has its own step size and error test,
  with the controller of :mod:`double_pendulum.solvers.integrator`. A common adaptive step would be
  set by the hardest member of the batch (a fast flip near the upright position) and make every
  result depend on the batch it was computed in; per-trajectory control avoids both. Steps are
  shortened to land on the output times instead of using dense output.

Vector fields take ``(t, Y)`` and return ``dY/dt`` of the same shape; with per-trajectory steps
``t`` is an array of shape ``(N,)``. They may be called with complex ``Y`` (complex-step
derivatives in :mod:`double_pendulum.analysis.chaos.lyapunov`); :func:`pendulum_field` supports that.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.dynamics import link_accelerations
from ...model.energy import potential_energy, total_energy
from ...model.kinematics import positions
from ...model.links import link_coefficients
from ...model.parameters import PendulumParameters
from ...solvers import SolverError
from ...solvers import tableaus as tb

BatchField = Callable[[Any, np.ndarray], np.ndarray]
"""``f(t, Y) -> dY/dt`` for ``Y`` of shape ``(d, N)``; ``t`` a float or an ``(N,)`` array [s]."""

GeneralisedForces = Callable[[Any, np.ndarray], tuple[Any, Any]]
"""``forces(t, Y) -> (Q1, Q2)`` [N m], generalised non-conservative forces (e.g. friction)."""

SparseRow = Sequence[tuple[int, float]]

SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0


def _row(weights: Sequence[float]) -> tuple[tuple[int, float], ...]:
    """Dense weights as a sparse row ``((j, w_j), ...)`` of the non-zero entries."""
    return tuple((j, w) for j, w in enumerate(weights) if w != 0.0)


_RK4_B_ROW = _row(tb.RK4_B)
_DOP853_B_ROW = _row(tb.DOP853_B)
_DOP853_E5_ROW = _row(tb.DOP853_E5)
_DOP853_E3_ROW = _row(tb.DOP853_E3)
DOP853_ERROR_EXPONENT = -1.0 / 8.0  # error estimate of order 7


# ---------------------------------------------------------------------------- the model
def pendulum_field(params: PendulumParameters | None = None, forces: GeneralisedForces | None = None) -> BatchField:
    """Return the double pendulum's right-hand side for batches ``Y = [phi1, phi2, omega1, omega2]``.

    ``dY/dt = [omega1, omega2, phi1'', phi2'']`` with the accelerations [rad/s^2] of
    :func:`double_pendulum.model.dynamics.link_accelerations` (bobs and rods); ``forces`` adds generalised forces
    ``Q1, Q2`` [N m] (friction models plug in here), none by default (frictionless).
    """
    p = params if params is not None else PendulumParameters()
    c = link_coefficients(p)

    def field(t: Any, y: np.ndarray) -> np.ndarray:
        q1, q2 = (0.0, 0.0) if forces is None else forces(t, y)
        alpha1, alpha2 = link_accelerations(
            y[0], y[1], y[2], y[3], c.j1, c.j2, c.k, c.gs1, c.gs2, q1, q2, sin=np.sin, cos=np.cos
        )
        out = np.empty_like(y)
        out[0] = y[2]
        out[1] = y[3]
        out[2] = alpha1
        out[3] = alpha2
        return out

    return field


def columnwise_field(scalar_field: Callable[[float, list[float]], list[float]]) -> BatchField:
    """Wrap a single-trajectory vector field over floats as a batch field, one column at a time.

    For models that exist only as float code (e.g. with friction terms using ``math``): a Python
    loop over the trajectories, so it suits a few trajectories, not maps. Real states only (use
    central differences, not the complex step, for its tangents).
    """

    def field(t: Any, y: np.ndarray) -> np.ndarray:
        columns = np.asarray(y, dtype=float).T.tolist()
        times = np.asarray(t, dtype=float).tolist() if np.ndim(t) else [float(t)] * len(columns)
        return np.array([scalar_field(tj, yj) for tj, yj in zip(times, columns)], dtype=float).T

    return field


def rod_field(config: Any) -> Callable[[float, list[float]], list[float]]:
    """The scene ``config``'s own float vector field on the four rod states ``(phi1, phi2, omega1, omega2)``.

    :func:`double_pendulum.model.vector_field.build_vector_field` with the dissipated-work states it
    appends fed in as zeros and their rates dropped (no equation depends on them). The suspension adds
    dynamic states of its own and is not supported here.
    """
    from ...model.vector_field import build_vector_field, state_layout

    if config.suspension.suspension:
        raise ValueError("rod_field: scenes with the suspension have more than the four rod states")
    scalar = build_vector_field(config)
    padding = [0.0] * (state_layout(config).size - 4)

    def rods_only(t: float, y: list[float]) -> list[float]:
        return scalar(t, y + padding)[:4]

    return rods_only


def model_field(config: Any) -> BatchField:
    """The scene ``config`` (:class:`~double_pendulum.model.scene.ModelConfig`) as a batch field.

    Without any mechanism this is :func:`pendulum_field` (vectorised). With friction it evaluates
    the model's own float vector field (:func:`double_pendulum.model.vector_field.build_vector_field`) column by
    column (:func:`columnwise_field`): the dissipated-work states it appends are fed in as zeros and
    their rates dropped, since no equation depends on them. The suspension adds dynamic states of its
    own and is not supported here.
    """
    from ...model.vector_field import is_core

    if config.suspension.suspension:
        raise ValueError("model_field: scenes with the suspension have more than the four rod states")
    if is_core(config):
        return pendulum_field(config.pendulum)
    return columnwise_field(rod_field(config))


def initial_states(phi1: Any, phi2: Any, omega1: Any = 0.0, omega2: Any = 0.0) -> np.ndarray:
    """Stack start values (scalars or arrays, broadcast together, flattened) into a ``(4, N)`` batch."""
    parts = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (phi1, phi2, omega1, omega2)))
    return np.array([np.ravel(v) for v in parts], dtype=float)


def batch_energy(y: np.ndarray, params: PendulumParameters) -> np.ndarray:
    """Total energy T + V [J] of each column of ``y`` (:func:`double_pendulum.model.energy.total_energy`)."""
    return total_energy(y[0], y[1], y[2], y[3], params, cos=np.cos)


def batch_potential_energy(phi1: Any, phi2: Any, params: PendulumParameters) -> Any:
    """Potential energy V [J] for array angles (:func:`double_pendulum.model.energy.potential_energy`)."""
    return potential_energy(phi1, phi2, params, cos=np.cos)


def batch_positions(y: np.ndarray, params: PendulumParameters) -> tuple[np.ndarray, ...]:
    """Bob positions ``(x1, y1, x2, y2)`` [m] per column (:func:`double_pendulum.model.kinematics.positions`)."""
    return positions(y[0], y[1], params.l1, params.l2, sin=np.sin, cos=np.cos)


# ---------------------------------------------------------------------------- Runge-Kutta core
def _combine(y: np.ndarray, h: Any, row: SparseRow, ks: Sequence[np.ndarray]) -> np.ndarray:
    """Return ``y + sum_j (h a_j) k_j`` in the order of ``row`` (as the float solvers do)."""
    out = y.copy()
    for j, a in row:
        out += (h * a) * ks[j]
    return out


def _weighted(ks: Sequence[np.ndarray], row: SparseRow) -> np.ndarray:
    """Return ``sum_j w_j k_j``."""
    out = np.zeros_like(ks[0])
    for j, w in row:
        out += w * ks[j]
    return out


def rk4_step(field: BatchField, t: Any, y: np.ndarray, h: Any) -> np.ndarray:
    """One classic RK4 step of size ``h`` [s] from ``(t, y)``; returns the new state."""
    ks = [field(t, y)]
    for i in range(1, 4):
        ks.append(field(t + tb.RK4_C[i] * h, _combine(y, h, tb.RK4_A[i], ks)))
    return _combine(y, h, _RK4_B_ROW, ks)


def rk4_iterate(
    field: BatchField, y0: np.ndarray, h: float, n_steps: int, *, t0: float = 0.0
) -> Iterator[tuple[int, float, np.ndarray]]:
    """Yield ``(n, t_n, Y_n)`` after each of ``n_steps`` RK4 steps on the grid ``t_n = t0 + n h``.

    The step actually taken is ``t_n - t_{n-1}``, as in the single-trajectory integrator, so both
    walk the same grid. The yielded array is the integrator's own state: copy it to keep it.
    """
    y = np.array(y0, copy=True)
    t = t0
    for n in range(1, n_steps + 1):
        t_new = t0 + n * h
        y = rk4_step(field, t, y, t_new - t)
        t = t_new
        yield n, t, y


def n_fixed_steps(duration: float, h: float) -> int:
    """Number of steps ``h`` in ``duration`` [s]; raises unless ``duration`` is a multiple of ``h``."""
    if not (math.isfinite(h) and h > 0.0):
        raise ValueError(f"invalid step h = {h!r} s: must be > 0")
    n = round(duration / h)
    if n < 0 or not math.isclose(n * h, duration, rel_tol=1e-9, abs_tol=1e-12):
        raise ValueError(f"duration {duration!r} s is not a whole number of steps h = {h!r} s")
    return n


def rk4_trajectory(
    field: BatchField, y0: np.ndarray, t_end: float, h: float, *, t0: float = 0.0, every: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """Integrate a batch with RK4 and keep every ``every``-th step.

    Returns ``(t, Y)`` with ``t`` of shape ``(n_out,)`` [s] (the start included) and ``Y`` of shape
    ``(n_out, d, N)``.
    """
    n_steps = n_fixed_steps(t_end - t0, h)
    y0 = np.asarray(y0)
    times = [t0]
    states = [np.array(y0, copy=True)]
    for n, t, y in rk4_iterate(field, y0, h, n_steps, t0=t0):
        if n % every == 0 or n == n_steps:
            times.append(t)
            states.append(y.copy())
    return np.array(times), np.array(states)


# ---------------------------------------------------------------------------- DOP853, per-trajectory steps
@dataclass(frozen=True)
class AdaptiveResult:
    """Output of :func:`dop853_trajectory`.

    ``t`` [s] has shape ``(n_out,)``, ``y`` ``(n_out, d, N)``; ``n_steps``, ``n_rejected`` and
    ``nfev`` count accepted steps, rejected steps and right-hand side evaluations per trajectory.
    """

    t: np.ndarray
    y: np.ndarray
    n_steps: np.ndarray
    n_rejected: np.ndarray
    nfev: np.ndarray


def _rms(v: np.ndarray) -> np.ndarray:
    """Root mean square over the state components (axis 0), one value per trajectory."""
    return np.sqrt(np.mean(v * v, axis=0))


def _initial_step(field: BatchField, t: np.ndarray, y: np.ndarray, fy: np.ndarray, rtol: float, atol: float):
    """Hairer's starting step (Solving ODEs I, II.4), per trajectory, for an error order of 7."""
    scale = atol + rtol * np.abs(y)
    d0, d1 = _rms(y / scale), _rms(fy / scale)
    h0 = np.where((d0 < 1e-5) | (d1 < 1e-5), 1e-6, 0.01 * d0 / np.where(d1 > 0, d1, 1.0))
    f1 = field(t + h0, y + h0 * fy)
    d2 = _rms((f1 - fy) / scale) / h0
    dmax = np.maximum(d1, d2)
    h1 = np.where(dmax <= 1e-15, np.maximum(1e-6, h0 * 1e-3), (0.01 / np.where(dmax > 0, dmax, 1.0)) ** 0.125)
    return np.minimum(100.0 * h0, h1)


def _dop853_attempt(field: BatchField, t: Any, y: np.ndarray, fy: np.ndarray, h: Any):
    """One DOP853 step: ``(y_new, f_new, ks)`` with ``ks`` the 12 stages plus ``f_new``."""
    ks = [fy]
    for i in range(1, 12):
        ks.append(field(t + tb.DOP853_C[i] * h, _combine(y, h, tb.DOP853_A[i], ks)))
    y_new = _combine(y, h, _DOP853_B_ROW, ks)
    f_new = field(t + h, y_new)
    ks.append(f_new)
    return y_new, f_new, ks


def _dop853_error(y: np.ndarray, y_new: np.ndarray, ks: list[np.ndarray], h: np.ndarray, rtol: float, atol: float):
    """Hairer's DOP853 error norm per trajectory (the step is accepted where it is <= 1)."""
    scale = atol + rtol * np.maximum(np.abs(y), np.abs(y_new))
    n5 = np.sum((_weighted(ks, _DOP853_E5_ROW) / scale) ** 2, axis=0)
    n3 = np.sum((_weighted(ks, _DOP853_E3_ROW) / scale) ** 2, axis=0)
    denom = np.sqrt((n5 + 0.01 * n3) * y.shape[0])
    return np.where(denom > 0.0, np.abs(h) * n5 / np.where(denom > 0.0, denom, 1.0), 0.0)


class Dop853Batch:
    """A batch under DOP853 with per-trajectory step control, kept between calls.

    ``y`` ``(d, N)`` and ``t`` ``(N,)`` are the current states and times, ``h`` the proposed steps,
    ``fy`` the derivatives at ``y`` (refresh it with ``field(t, y)`` after changing ``y`` from
    outside); :meth:`advance` steps every trajectory to a common time.
    """

    def __init__(self, field: BatchField, y0: np.ndarray, t0: float, rtol: float, atol: float) -> None:
        self.field, self.rtol, self.atol = field, rtol, atol
        self.y = np.array(y0, dtype=float, copy=True)
        n = self.y.shape[1]
        self.t = np.full(n, float(t0))
        self.fy = field(self.t, self.y)
        self.h = _initial_step(field, self.t, self.y, self.fy, rtol, atol)
        self.rejected = np.zeros(n, dtype=bool)
        self.n_steps = np.zeros(n, dtype=np.int64)
        self.n_rejected = np.zeros(n, dtype=np.int64)
        self.nfev = np.full(n, 2, dtype=np.int64)

    def advance(self, target: float, max_steps: int) -> None:
        """Step every trajectory until it reaches ``target`` [s] exactly."""
        for _ in range(max_steps):
            idx = np.nonzero(self.t < target)[0]
            if idx.size == 0:
                return
            self._attempt(idx, target)
        raise SolverError(f"dop853 (batch): more than {max_steps} step attempts before t = {target:.6g} s")

    def _attempt(self, idx: np.ndarray, target: float) -> None:
        t, y, fy, h_prop = self.t[idx], self.y[:, idx], self.fy[:, idx], self.h[idx]
        remaining = target - t
        clipped = h_prop >= remaining
        h = np.where(clipped, remaining, h_prop)
        if np.any(h < 16.0 * np.spacing(np.maximum(np.abs(t), 1.0))):
            raise SolverError(f"dop853 (batch): step size underflow at t = {t[np.argmin(h)]:.6g} s")
        y_new, f_new, ks = _dop853_attempt(self.field, t, y, fy, h)
        self.nfev[idx] += 12
        err = _dop853_error(y, y_new, ks, h, self.rtol, self.atol)
        finite = np.all(np.isfinite(y_new), axis=0) & np.all(np.isfinite(f_new), axis=0) & np.isfinite(err)
        ok = finite & (err <= 1.0)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            factor = np.where(err == 0.0, MAX_FACTOR, np.minimum(MAX_FACTOR, SAFETY * err**DOP853_ERROR_EXPONENT))
            shrink = np.where(finite, np.maximum(MIN_FACTOR, SAFETY * err**DOP853_ERROR_EXPONENT), MIN_FACTOR)
        factor = np.where(self.rejected[idx], np.minimum(1.0, factor), factor)
        acc, rej = idx[ok], idx[~ok]
        self.y[:, acc] = y_new[:, ok]
        self.fy[:, acc] = f_new[:, ok]
        self.t[acc] = np.where(clipped[ok], target, t[ok] + h[ok])
        # After a step shortened to hit an output time keep the earlier proposal.
        self.h[acc] = np.where(clipped[ok], np.maximum(h_prop[ok], h[ok] * factor[ok]), h[ok] * factor[ok])
        self.n_steps[acc] += 1
        self.rejected[acc] = False
        self.h[rej] = h[~ok] * np.minimum(shrink[~ok], 1.0)
        self.rejected[rej] = True
        self.n_rejected[rej] += 1


def dop853_trajectory(
    field: BatchField,
    y0: np.ndarray,
    t_out: Sequence[float] | np.ndarray,
    *,
    t0: float = 0.0,
    rtol: float = 1e-9,
    atol: float = 1e-12,
    max_steps: int = 10_000_000,
) -> AdaptiveResult:
    """Integrate a batch with DOP853, each trajectory with its own step size, to the times ``t_out``.

    ``t_out`` [s] must be increasing and >= ``t0``; the result includes only those times.
    Error control is Hairer's (scaled RMS of the 5th/3rd-order estimates, ``rtol``/``atol`` in the
    state's units); steps grow by at most 10, shrink by at most 5, never grow right after a
    rejection. Raises :class:`double_pendulum.solvers.SolverError` on step size underflow.
    """
    t_out = np.asarray(t_out, dtype=float)
    if np.any(np.diff(t_out) < 0.0) or (t_out.size and t_out[0] < t0):
        raise ValueError("t_out must be increasing and not before t0")
    batch = Dop853Batch(field, np.asarray(y0, dtype=float), t0, rtol, atol)
    states = []
    for target in t_out:
        batch.advance(float(target), max_steps)
        states.append(batch.y.copy())
    return AdaptiveResult(
        t=t_out,
        y=np.array(states),
        n_steps=batch.n_steps,
        n_rejected=batch.n_rejected,
        nfev=batch.nfev,
    )
