r"""Chaos of the double pendulum: Lyapunov exponents, flip times, predictability, Poincare sections.

Everything here runs on batches (:mod:`double_pendulum.analysis.ensemble`) and uses the model's own
vector field; nothing re-derives the equations of motion.

**Lyapunov exponents** (Benettin et al., Meccanica 15 (1980) 9-20). A tangent vector
:math:`v` obeys the variational equation :math:`\dot v = J(y)\,v` with :math:`J = \partial f/\partial y`.
:math:`J v` is obtained from the vector field itself by the *complex step*
:math:`J v = \operatorname{Im} f(y + i\varepsilon v)/\varepsilon` (:math:`\varepsilon = 10^{-20}`):
:func:`double_pendulum.model.dynamics.link_accelerations` is analytic (sums, products, quotients,
sine, cosine), so this is exact to rounding, with no cancellation, and needs no hand-written
Jacobian. A central difference is available for vector fields that are not analytic (e.g. with
Coulomb friction). The tangent vectors are integrated together with the trajectory and
renormalised every ``renorm_interval``:

.. math::

    \lambda_1 = \lim_{T\to\infty} \frac{1}{T} \sum_k \ln \frac{|v(t_k)|}{|v(t_{k-1}^+)|}

and with ``n_vectors = 4`` Gram-Schmidt (QR) re-orthonormalisation gives the whole spectrum
:math:`\lambda_i = \lim \frac1T \sum_k \ln |R_{ii}(t_k)|`. For the frictionless pendulum (a
Hamiltonian flow) the spectrum pairs as :math:`(\lambda, 0, 0, -\lambda)`: one zero exponent
along the flow, one across the energy surface. In the coordinates :math:`(\varphi, \omega)` used here
the flow is not volume-preserving, but the map to the canonical :math:`(\varphi, p = M\omega)` has
Jacobian determinant :math:`\det M(\varphi) = m_2 l_1^2 l_2^2 (m_1 + m_2\sin^2\Delta)`, so
:math:`|\sum_i \lambda_i(T)| \le \ln\frac{m_1+m_2}{m_1} / T` at every finite :math:`T`.
A two-trajectory variant (:func:`lyapunov_two_trajectory`) cross-checks the tangent method.

**Energetic bound for flipping.** A rod flips over when its angle passes the upright position
:math:`\varphi_i = \pi \pmod{2\pi}`. With :math:`T \ge 0` (positive definite mass matrix) and
:math:`E = T + V` conserved (or decreasing with friction), :math:`V(\varphi_1(t), \varphi_2(t)) \le E`
at all times. :math:`V = (m_1+m_2) g l_1 (1-\cos\varphi_1) + m_2 g l_2 (1-\cos\varphi_2)` is a sum
of one term per angle, each smallest at 0, so on the set where rod 1 is upright
:math:`V \ge V(\pi, 0) = 2 (m_1+m_2) g l_1`, and where rod 2 is upright :math:`V \ge V(0, \pi) = 2 m_2 g l_2`.
Hence rod 1 can flip only if :math:`E \ge V(\pi, 0)`, rod 2 only if :math:`E \ge V(0, \pi)`, and no
rod can flip if :math:`E < \min(V(\pi,0), V(0,\pi))` (:func:`flip_energy_bounds`, evaluated with
:func:`double_pendulum.model.energy.potential_energy`). Released from rest,
:math:`E = V(\varphi_{1,0}, \varphi_{2,0})`: the curve :math:`V(\varphi_{1,0}, \varphi_{2,0}) = 2 m_2 g l_2`
bounds the region of the flip map where flipping is impossible.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..model.energy import kinetic_energy, potential_energy
from ..model.parameters import PendulumParameters
from .ensemble import (
    BatchField,
    Dop853Batch,
    batch_positions,
    initial_states,
    n_fixed_steps,
    pendulum_field,
    rk4_iterate,
    rk4_step,
)

COMPLEX_STEP = 1e-20
STATE_DIM = 4


# ---------------------------------------------------------------------------- tangent dynamics
def complex_step_jvp(field: BatchField, t: Any, y: np.ndarray, v: np.ndarray, eps: float = COMPLEX_STEP):
    """Return ``J(y) v = Im f(y + i eps v) / eps`` for batches ``y``, ``v`` of shape ``(d, M)``."""
    return field(t, y + (1j * eps) * v).imag / eps


def central_difference_jvp(field: BatchField, t: Any, y: np.ndarray, v: np.ndarray, rel_step: float = 1e-6):
    """Return ``J(y) v ~ (f(y + s v) - f(y - s v)) / (2 s)``, ``s = rel_step (1 + |y|) / |v|`` per column.

    Second-order accurate; use it for vector fields that are not analytic (``abs``, ``sign``).
    """
    return field_and_central_jvp(field, t, y, v, rel_step=rel_step)[1]


def field_and_central_jvp(
    field: BatchField, t: Any, y: np.ndarray, v: np.ndarray, *, at: tuple[Any, np.ndarray] | None = None,
    rel_step: float = 1e-6,
) -> tuple[np.ndarray | None, np.ndarray]:
    """``(f(t0, y0), J(y) v)`` with :func:`central_difference_jvp`'s ``J v``, from one call of ``field``.

    ``at = (t0, y0)``: columns at which ``f`` itself is wanted too (``None``: only ``J v``). All columns
    ``[y0; y + s v; y - s v]`` go to ``field`` in one call (a column-wise field pays its per-call overhead
    once, not three times); every column is evaluated on its own, so the values are those of separate calls.
    """
    norm_v = np.sqrt(np.sum(v * v, axis=0))
    s = rel_step * (1.0 + np.sqrt(np.sum(y * y, axis=0))) / np.where(norm_v > 0, norm_v, 1.0)
    t0, y0 = at if at is not None else (0.0, y[:, :0])
    columns = np.concatenate((y0, y + s * v, y - s * v), axis=1)
    if np.ndim(t):  # per-column times follow their columns
        t = np.broadcast_to(t, (y.shape[1],))
        t = np.concatenate((np.broadcast_to(t0, (y0.shape[1],)), t, t))
    f = field(t, columns)
    n0, m = y0.shape[1], y.shape[1]
    return (f[:, :n0] if at is not None else None), (f[:, n0:n0 + m] - f[:, n0 + m:]) / (2.0 * s)


JVP_METHODS: dict[str, Callable[..., np.ndarray]] = {
    "complex": complex_step_jvp,
    "central": central_difference_jvp,
}


def tangent_field(field: BatchField, n_vectors: int, jvp: str = "complex", dim: int = STATE_DIM) -> BatchField:
    """Return the flow with its variational equations, ``Z = [y; v_1; ...; v_k]`` of shape ``(d (1+k), N)``.

    ``dZ/dt = [f(y); J(y) v_1; ...; J(y) v_k]``; the ``k`` products ``J v`` are evaluated in one
    batch call of ``field`` on ``(d, k N)`` columns.
    """
    product = JVP_METHODS[jvp]
    k, d = n_vectors, dim

    def augmented(t: Any, z: np.ndarray) -> np.ndarray:
        n = z.shape[1]
        y = z[:d]
        v = z[d:].reshape(k, d, n).transpose(1, 0, 2).reshape(d, k * n)
        yk = np.broadcast_to(y[:, None, :], (d, k, n)).reshape(d, k * n)
        tk = np.tile(t, k) if np.ndim(t) else t  # per-trajectory times follow their columns
        if jvp == "central":  # f(y) in the same call of the field as the differences
            value, jv = field_and_central_jvp(field, tk, yk, v, at=(t, y))
        else:
            value, jv = field(t, y), product(field, tk, yk, v)
        return np.concatenate((value, jv.reshape(d, k, n).transpose(1, 0, 2).reshape(k * d, n)), axis=0)

    return augmented


# ---------------------------------------------------------------------------- steppers
class _Rk4Stepper:
    """Fixed-step RK4 on the grid ``t0 + n h`` that stops at multiples of ``h``."""

    def __init__(self, field: BatchField, z0: np.ndarray, h: float, t0: float = 0.0) -> None:
        self.field, self.h, self.t0 = field, h, t0
        self.z = np.array(z0, copy=True)  # real, or complex for complex-step tangents
        self.n = 0

    @property
    def t(self) -> float:
        return self.t0 + self.n * self.h

    def advance(self, target: float) -> None:
        n_target = self.n + n_fixed_steps(target - self.t, self.h)
        while self.n < n_target:
            t_new = self.t0 + (self.n + 1) * self.h
            self.z = rk4_step(self.field, self.t, self.z, t_new - self.t)
            self.n += 1

    def modified(self) -> None:
        """The state was changed from outside (renormalisation): nothing cached to refresh."""


class _Dop853Stepper:
    """Per-trajectory DOP853 (:mod:`double_pendulum.analysis.ensemble`) behind the stepper interface."""

    def __init__(self, field: BatchField, z0: np.ndarray, rtol: float, atol: float, t0: float = 0.0) -> None:
        self.batch = Dop853Batch(field, z0, t0, rtol, atol)

    @property
    def z(self) -> np.ndarray:
        return self.batch.y

    @z.setter
    def z(self, value: np.ndarray) -> None:
        self.batch.y = value

    def advance(self, target: float) -> None:
        self.batch.advance(target, max_steps=10_000_000)

    def modified(self) -> None:
        self.batch.fy = self.batch.field(self.batch.t, self.batch.y)


@dataclass(frozen=True)
class Integration:
    """How to integrate: ``method`` ``"rk4"`` with step ``h`` [s], or ``"dop853"`` with ``rtol``/``atol``."""

    method: str = "rk4"
    h: float = 1e-3
    rtol: float = 1e-10
    atol: float = 1e-12

    def stepper(self, field: BatchField, z0: np.ndarray, t0: float = 0.0):
        if self.method == "rk4":
            return _Rk4Stepper(field, z0, self.h, t0)
        if self.method == "dop853":
            return _Dop853Stepper(field, z0, self.rtol, self.atol, t0)
        raise ValueError(f"invalid method = {self.method!r}: must be 'rk4' or 'dop853'")

    def label(self) -> str:
        return f"rk4 h={self.h:g} s" if self.method == "rk4" else f"dop853 rtol={self.rtol:g}"


# ---------------------------------------------------------------------------- Lyapunov exponents
@dataclass(frozen=True)
class LyapunovResult:
    """Benettin estimates at the renormalisation times.

    ``times`` [s] ``(n,)``; ``running`` [1/s] ``(n, k, N)`` the estimates
    :math:`\\frac{1}{t}\\sum \\ln|R_{ii}|` up to each time (the convergence curve); ``log_growth``
    ``(n, k, N)`` the logarithmic growth in each interval; ``states`` ``(n, d, N)`` the trajectory at
    those times. ``exponents`` ``(k, N)`` are the final estimates.
    """

    times: np.ndarray
    running: np.ndarray
    log_growth: np.ndarray
    states: np.ndarray
    integration: Integration

    @property
    def exponents(self) -> np.ndarray:
        return self.running[-1]


def initial_tangents(n_vectors: int, n_traj: int, dim: int = STATE_DIM, seed: int = 0) -> np.ndarray:
    """Orthonormal start vectors ``(k, d, N)``: one seeded random orthonormal frame for every trajectory."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.standard_normal((dim, n_vectors)))
    return np.repeat(q.T[:, :, None], n_traj, axis=2)


def _orthonormalise(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """QR of each frame ``v`` ``(k, d, N)``: returns ``Q`` ``(k, d, N)`` and ``ln|diag R|`` ``(k, N)``."""
    frames = v.transpose(2, 1, 0)  # (N, d, k)
    q, r = np.linalg.qr(frames)
    diag = np.diagonal(r, axis1=1, axis2=2)  # (N, k)
    q = q * np.sign(np.where(diag == 0, 1.0, diag))[:, None, :]
    return q.transpose(2, 1, 0), np.log(np.abs(diag)).T


class _AugmentedTangents:
    """Trajectory and tangent vectors as one real state ``[y; v_1; ...; v_k]`` (:func:`tangent_field`).

    Works with either integrator and either Jacobian-vector product; with DOP853 the tangent
    components take part in the error control.
    """

    def __init__(self, field: BatchField, y0: np.ndarray, v0: np.ndarray, integration: Integration, jvp: str):
        self.k, self.d, self.n = v0.shape
        z0 = np.concatenate((y0, v0.reshape(self.k * self.d, self.n)), axis=0)
        self.stepper = integration.stepper(tangent_field(field, self.k, jvp, dim=self.d), z0)

    def advance(self, target: float) -> None:
        self.stepper.advance(target)

    def base(self) -> np.ndarray:
        return self.stepper.z[: self.d]

    def tangents(self) -> np.ndarray:
        return self.stepper.z[self.d :].reshape(self.k, self.d, self.n)

    def set_tangents(self, v: np.ndarray) -> None:
        z = self.stepper.z
        z[self.d :] = v.reshape(self.k * self.d, self.n)
        self.stepper.z = z
        self.stepper.modified()


class _ComplexStepRk4Tangents:
    """RK4 on the complexified flow: ``k`` copies ``z_j = y + i eps v_j`` in one complex batch.

    Because the vector field is analytic, ``f(y + i eps v) = f(y) + i eps J(y) v + O(eps^2)``, so RK4
    applied to ``z`` is RK4 applied to the trajectory (real part) together with its variational
    equation (imaginary part / eps), at the cost of one complex evaluation per stage. The real parts
    of the copies are re-synchronised to the first copy at every renormalisation.
    """

    def __init__(self, field: BatchField, y0: np.ndarray, v0: np.ndarray, h: float, eps: float = COMPLEX_STEP):
        self.k, self.d, self.n = v0.shape
        self.eps = eps
        base = np.tile(np.asarray(y0, dtype=float), (1, self.k))
        self.stepper = _Rk4Stepper(field, base + (1j * eps) * self._columns(v0), h)

    def _columns(self, v: np.ndarray) -> np.ndarray:
        """``(k, d, N)`` frames as ``(d, k N)`` columns, copy ``j`` in columns ``j N .. (j+1) N - 1``."""
        return v.transpose(1, 0, 2).reshape(self.d, self.k * self.n)

    def advance(self, target: float) -> None:
        self.stepper.advance(target)

    def base(self) -> np.ndarray:
        return self.stepper.z[:, : self.n].real

    def tangents(self) -> np.ndarray:
        return (self.stepper.z.imag / self.eps).reshape(self.d, self.k, self.n).transpose(1, 0, 2)

    def set_tangents(self, v: np.ndarray) -> None:
        base = np.tile(self.base(), (1, self.k))
        self.stepper.z = base + (1j * self.eps) * self._columns(v)


def lyapunov_benettin(
    field: BatchField,
    y0: np.ndarray,
    t_end: float,
    *,
    renorm_interval: float = 0.1,
    n_vectors: int = 1,
    integration: Integration = Integration(),
    jvp: str = "complex",
    seed: int = 0,
) -> LyapunovResult:
    """Largest (``n_vectors = 1``) or first ``n_vectors`` Lyapunov exponents [1/s] of a batch of starts.

    ``y0`` ``(d, N)``; tangent vectors renormalised (QR) every ``renorm_interval`` [s] up to
    ``t_end`` [s]; ``field`` may include friction (any :data:`double_pendulum.analysis.ensemble.BatchField`).
    RK4 with the complex step integrates the complexified flow (:class:`_ComplexStepRk4Tangents`),
    otherwise trajectory and tangents are one augmented real state.
    """
    y0 = np.asarray(y0, dtype=float)
    d, n_traj = y0.shape
    v0 = initial_tangents(n_vectors, n_traj, d, seed)
    if integration.method == "rk4" and jvp == "complex":
        flow: Any = _ComplexStepRk4Tangents(field, y0, v0, integration.h)
    else:
        flow = _AugmentedTangents(field, y0, v0, integration, jvp)
    n_renorm = n_fixed_steps(t_end, renorm_interval)
    growth = np.empty((n_renorm, n_vectors, n_traj))
    states = np.empty((n_renorm, d, n_traj))
    times = renorm_interval * np.arange(1, n_renorm + 1)
    for i, target in enumerate(times):
        flow.advance(float(target))
        q, growth[i] = _orthonormalise(flow.tangents())
        flow.set_tangents(q)
        states[i] = flow.base()
    running = np.cumsum(growth, axis=0) / times[:, None, None]
    return LyapunovResult(times, running, growth, states, integration)


def central_difference_tangent_field(
    field: Callable[[float, list[float]], list[float]], rel_step: float = 1e-6,
) -> Callable[[float, list[float]], list[float]]:
    """The float twin of :func:`tangent_field` with central differences, for one trajectory and one vector.

    ``z = [y; v]`` (``d`` + ``d`` floats) -> ``[f(y); (f(y + s v) - f(y - s v)) / (2 s)]`` with
    ``s = rel_step (1 + |y|) / |v|`` as in :func:`central_difference_jvp`.
    """

    def augmented(t: float, z: list[float]) -> list[float]:
        d = len(z) // 2
        y, v = z[:d], z[d:]
        norm_v = math.sqrt(sum(x * x for x in v))
        s = rel_step * (1.0 + math.sqrt(sum(x * x for x in y))) / (norm_v if norm_v > 0.0 else 1.0)
        plus = field(t, [a + s * b for a, b in zip(y, v)])
        minus = field(t, [a - s * b for a, b in zip(y, v)])
        return field(t, y) + [(p - m) / (2.0 * s) for p, m in zip(plus, minus)]

    return augmented


def lyapunov_single(
    field: Callable[[float, list[float]], list[float]],
    y0: Sequence[float],
    t_end: float,
    *,
    renorm_interval: float,
    rtol: float = 1e-8,
    atol: float | None = None,
    seed: int = 0,
) -> LyapunovResult:
    """Largest exponent of one start ``y0`` under a float vector field ``field(t, y) -> dy/dt``.

    Benettin's method as in :func:`lyapunov_benettin` (tangent by central differences,
    :func:`central_difference_tangent_field`, renormalised every ``renorm_interval`` [s] up to ``t_end``
    [s]), integrated by the runtime's own DOP853 (:mod:`double_pendulum.solvers`, the FMU's integrator) at
    ``rtol``, ``atol`` (default rtol / 100) with the tangent in the error control. For one trajectory of a
    field that exists only as float code (friction) this is about four times faster than the batch
    integrators, whose NumPy overhead per step does not shrink with the batch. Returns a
    :class:`LyapunovResult` with ``N = 1``.
    """
    from ..solvers.registry import make_integrator  # noqa: PLC0415 - the runtime's integrator, only here

    atol = rtol * 1e-2 if atol is None else atol
    y0 = [float(v) for v in y0]
    v0 = initial_tangents(1, 1, len(y0), seed)[0, :, 0].tolist()
    integrator = make_integrator("dop853", central_difference_tangent_field(field), 0.0, y0 + v0, rtol=rtol,
                                 atol=atol, fixed_step=renorm_interval)
    times = renorm_interval * np.arange(1, n_fixed_steps(t_end, renorm_interval) + 1)
    growth = np.empty((len(times), 1, 1))
    states = np.empty((len(times), len(y0), 1))
    d = len(y0)
    for i, target in enumerate(times):
        while integrator.t < target:
            integrator.step(float(target))
        z = integrator.y
        norm = math.sqrt(sum(x * x for x in z[d:]))
        growth[i] = math.log(norm)
        states[i, :, 0] = z[:d]
        integrator.restart(float(target), z[:d] + [x / norm for x in z[d:]])  # the state changed: no stale stages
    running = np.cumsum(growth, axis=0) / times[:, None, None]
    return LyapunovResult(times, running, growth, states, Integration("dop853", rtol=rtol, atol=atol))


def lyapunov_two_trajectory(
    field: BatchField,
    y0: np.ndarray,
    t_end: float,
    *,
    separation: float = 1e-8,
    renorm_interval: float = 0.1,
    integration: Integration = Integration(),
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Benettin's two-trajectory estimate: ``(times, running)`` with ``running`` ``(n, N)`` [1/s].

    A companion starts ``separation`` away (state units, seeded random direction); every
    ``renorm_interval`` the distance ``d`` is measured, ``ln(d / separation)`` accumulated and the
    companion pulled back to ``separation`` along the current difference.
    """
    y0 = np.asarray(y0, dtype=float)
    d, n_traj = y0.shape
    direction = initial_tangents(1, n_traj, d, seed)[0]
    stepper = integration.stepper(field, np.concatenate((y0, y0 + separation * direction), axis=1))
    n_renorm = n_fixed_steps(t_end, renorm_interval)
    times = renorm_interval * np.arange(1, n_renorm + 1)
    total = np.zeros(n_traj)
    running = np.empty((n_renorm, n_traj))
    for i, target in enumerate(times):
        stepper.advance(float(target))
        z = stepper.z
        diff = z[:, n_traj:] - z[:, :n_traj]
        dist = np.sqrt(np.sum(diff * diff, axis=0))
        total += np.log(dist / separation)
        z[:, n_traj:] = z[:, :n_traj] + diff * (separation / dist)
        stepper.z = z
        stepper.modified()
        running[i] = total / target
    return times, running


def local_exponents(result: LyapunovResult, window: float) -> tuple[np.ndarray, np.ndarray]:
    """Finite-time largest exponents [1/s] over consecutive windows of ``window`` [s].

    Returns ``(centres, exponents)`` with ``exponents`` ``(n_windows, N)``: the mean log growth of the
    first tangent vector per unit time in each window. With friction they show the exponent falling as
    the motion decays.
    """
    dt = result.times[0]
    per = max(1, round(window / dt))
    n_win = len(result.times) // per
    growth = result.log_growth[: n_win * per, 0, :].reshape(n_win, per, -1)
    centres = (np.arange(n_win) + 0.5) * per * dt
    return centres, growth.sum(axis=1) / (per * dt)


def spectrum_sum_bound(params: PendulumParameters, t: Any) -> Any:
    r"""Bound on :math:`|\sum_i\lambda_i(t)|` [1/s] for the frictionless flow in :math:`(\varphi, \omega)`.

    :math:`\ln(\max\det M / \min\det M) / t = \ln((m_1+m_2)/m_1) / t` (see the module docstring).
    """
    return math.log((params.m1 + params.m2) / params.m1) / np.asarray(t)


# ---------------------------------------------------------------------------- flipping
def flip_energy_bounds(params: PendulumParameters) -> tuple[float, float]:
    """Least energies [J] at which rod 1, rod 2 can reach the upright position: ``V(pi, 0)``, ``V(0, pi)``."""
    return potential_energy(math.pi, 0.0, params), potential_energy(0.0, math.pi, params)


def flip_energy_threshold(params: PendulumParameters) -> float:
    """Energy [J] below which neither rod can flip: ``min(V(pi, 0), V(0, pi))``."""
    return min(flip_energy_bounds(params))


def _crossing_time(t_prev: float, h: float, a_prev: np.ndarray, a_new: np.ndarray) -> np.ndarray:
    """Linear interpolation of the time at which ``|phi|`` reaches pi within a step."""
    frac = (math.pi - a_prev) / np.where(a_new > a_prev, a_new - a_prev, 1.0)
    return t_prev + np.clip(frac, 0.0, 1.0) * h


def first_flip_times(
    field: BatchField, y0: np.ndarray, t_max: float, h: float = 1e-3, *, compact_every: int = 20
) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] until either rod first passes its upright position, and which rod (1 or 2).

    Starts must have ``|phi1|, |phi2| < pi``. Fixed-step RK4, trajectories that have flipped leave
    the batch (every ``compact_every`` steps). Returns ``(times, rods)``: NaN and 0 where no rod
    flipped before ``t_max``.
    """
    y = np.array(y0, dtype=float, copy=True)
    if np.any(np.abs(y[:2]) >= math.pi):
        raise ValueError("start angles must lie in (-pi, pi)")
    n_total = y.shape[1]
    times = np.full(n_total, np.nan)
    rods = np.zeros(n_total, dtype=np.int8)
    alive = np.arange(n_total)
    n_steps = n_fixed_steps(t_max, h)
    done = np.zeros(n_total, dtype=bool)
    t = 0.0
    for n in range(1, n_steps + 1):
        if alive.size == 0:
            break
        t_new = n * h
        prev = np.abs(y[:2])
        y = rk4_step(field, t, y, t_new - t)
        now = np.abs(y[:2])
        over = now >= math.pi
        hit = (over[0] | over[1]) & ~done[alive]
        if np.any(hit):
            tc1 = np.where(over[0], _crossing_time(t, t_new - t, prev[0], now[0]), np.inf)
            tc2 = np.where(over[1], _crossing_time(t, t_new - t, prev[1], now[1]), np.inf)
            idx = alive[hit]
            times[idx] = np.minimum(tc1, tc2)[hit]
            rods[idx] = np.where(tc1 <= tc2, 1, 2)[hit]
            done[idx] = True
        t = t_new
        if n % compact_every == 0 and np.any(done[alive]):
            keep = ~done[alive]
            alive, y = alive[keep], y[:, keep]
    return times, rods


@dataclass(frozen=True)
class FlipMap:
    """First-flip times on a grid of release angles (from rest).

    ``phi1``, ``phi2`` [rad] grid axes; ``time`` [s] and ``rod`` of shape ``(len(phi2), len(phi1))``
    (NaN / 0: no flip before ``t_max``); ``energy`` [J] of each start; ``threshold`` [J] the
    energetic bound; ``cpu_time`` [s] the time the map took, ``wall_time`` [s] likewise.
    """

    phi1: np.ndarray
    phi2: np.ndarray
    time: np.ndarray
    rod: np.ndarray
    energy: np.ndarray
    threshold: float
    t_max: float
    h: float
    wall_time: float
    workers: int


def _flip_chunk(args: tuple[dict, np.ndarray, np.ndarray, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Worker: flip times for the starts ``(phi1, phi2)`` from rest (top-level so it pickles)."""
    param_values, phi1, phi2, t_max, h = args
    field_ = pendulum_field(PendulumParameters(**param_values))
    return first_flip_times(field_, initial_states(phi1, phi2), t_max, h)


def flip_time_map(
    n_phi1: int,
    n_phi2: int,
    params: PendulumParameters | None = None,
    *,
    t_max: float = 10.0,
    h: float = 1e-3,
    max_workers: int | None = 1,
    progress: bool | None = None,
    mirror: bool = True,
) -> FlipMap:
    """Flip-time map over release angles in (-pi, pi)^2 (cell centres), released from rest.

    The rows of the grid are dealt round-robin into two chunks per worker (so every chunk gets
    low- and high-energy rows alike) and run on ``max_workers`` local processes (``None``: all
    cores) by :func:`double_pendulum.analysis.sweep.parallel_map`; each chunk is one RK4 batch.

    ``mirror``: the release ``(-phi1, -phi2)`` is the mirror image of ``(phi1, phi2)`` (the vector field
    is odd, ``f(-y) = -f(y)``, and so is every RK4 step) and the cell centres are symmetric about 0, so
    only the rows ``phi2 < 0`` (and the middle row of an odd grid) are integrated and the others are their
    mirror images: half the work, the same map to rounding (flip times within 1e-13 relative: NumPy's
    vectorised sine can round the last bit differently at different places in a batch, which moves the
    integrated map by as much between chunkings; ``tests/test_chaos.py`` compares).
    """
    from .sweep import default_workers, parallel_map

    p = params if params is not None else PendulumParameters()
    phi1 = -math.pi + (np.arange(n_phi1) + 0.5) * (2 * math.pi / n_phi1)
    phi2 = -math.pi + (np.arange(n_phi2) + 0.5) * (2 * math.pi / n_phi2)
    g1, g2 = np.meshgrid(phi1, phi2)
    values = {k: getattr(p, k) for k in ("m1", "m2", "l1", "l2", "g")}
    workers = default_workers() if max_workers is None else max_workers
    n_rows = (n_phi2 + 1) // 2 if mirror else n_phi2  # the rows integrated
    n_chunks = min(n_rows, 1 if workers <= 1 else 2 * workers)
    rows = [np.arange(j, n_rows, n_chunks) for j in range(n_chunks)]
    chunks = [(values, g1[r].ravel(), g2[r].ravel(), t_max, h) for r in rows]
    start = time.perf_counter()
    parts, used = parallel_map(
        _flip_chunk,
        chunks,
        max_workers=workers,
        progress=progress,
        label="flip map",
        weights=[r.size for r in rows],
        unit="row",
    )
    wall = time.perf_counter() - start
    times = np.empty(g1.shape)
    rods = np.empty(g1.shape, dtype=np.int8)
    for r, (t_part, rod_part) in zip(rows, parts):
        times[r] = t_part.reshape(r.size, n_phi1)
        rods[r] = rod_part.reshape(r.size, n_phi1)
    if mirror:  # row j is row n_phi2 - 1 - j reversed: the cell (-phi1, -phi2)
        times[n_rows:] = times[: n_phi2 - n_rows][::-1, ::-1]
        rods[n_rows:] = rods[: n_phi2 - n_rows][::-1, ::-1]
    energy = potential_energy(g1, g2, p, cos=np.cos)
    return FlipMap(phi1, phi2, times, rods, energy, flip_energy_threshold(p), t_max, h, wall, used)


# ---------------------------------------------------------------------------- ensembles, predictability
def release_ensemble(
    phi1_0: float,
    phi2_0: float,
    sigma: float,
    n: int,
    params: PendulumParameters,
    *,
    seed: int = 0,
    include_nominal: bool = False,
) -> np.ndarray:
    """Starts from rest with the upper bob's position uncertain by ``sigma`` [m] (seed 4.1).

    The seed held the upper bob against a threaded rod (position known to about 5 mm) with the
    lower rod hanging from it, then let go. Only the displacement along the upper bob's circle
    moves the start: ``phi1 = phi1_0 + s / l1`` with ``s ~ N(0, sigma^2)``; ``phi2 = phi2_0``.
    Returns ``(4, n)`` (the nominal start first if ``include_nominal``). Same ``seed``, same starts.
    """
    rng = np.random.default_rng(seed)
    s = rng.normal(0.0, sigma, size=n)
    if include_nominal:
        s = np.concatenate(([0.0], s[:-1]))
    return initial_states(phi1_0 + s / params.l1, np.full(n, phi2_0))


@dataclass(frozen=True)
class Spread:
    """Output of :func:`ensemble_spread`: ``times`` [s] ``(n_t,)``, ``spread`` [m] ``(n_t, n_groups)``,
    ``snapshots`` mapping a time [s] to the lower bob positions ``(x2, y2)`` [m] of one group."""

    times: np.ndarray
    spread: np.ndarray
    snapshots: dict[float, tuple[np.ndarray, np.ndarray]]


def ensemble_spread(
    field: BatchField,
    groups: Sequence[np.ndarray],
    params: PendulumParameters,
    t_end: float,
    *,
    h: float = 1e-3,
    every: int = 10,
    snapshot_times: Sequence[float] = (),
    snapshot_group: int = 0,
) -> Spread:
    """Spread [m] of the lower bob's position within each group of starts, over time.

    ``spread = sqrt(mean_i |r2_i - mean_j r2_j|^2)`` per group, sampled every ``every`` RK4 steps;
    all groups run in one batch. The positions of group ``snapshot_group`` are kept at the sample
    times nearest to ``snapshot_times``.
    """
    sizes = [g.shape[1] for g in groups]
    bounds = np.cumsum([0, *sizes])
    y0 = np.concatenate(groups, axis=1)
    wanted = {round(t / h): t for t in snapshot_times}
    lo, hi = bounds[snapshot_group], bounds[snapshot_group + 1]
    snapshots: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def sample(n: int, y: np.ndarray) -> list[float]:
        _, _, x2, y2 = batch_positions(y, params)
        if n in wanted:
            snapshots[wanted[n]] = (x2[lo:hi].copy(), y2[lo:hi].copy())
        out = []
        for a, b in zip(bounds[:-1], bounds[1:]):
            dx, dy = x2[a:b] - x2[a:b].mean(), y2[a:b] - y2[a:b].mean()
            out.append(float(np.sqrt(np.mean(dx * dx + dy * dy))))
        return out

    times, values = [0.0], [sample(0, y0)]
    for n, t, y in rk4_iterate(field, y0, h, n_fixed_steps(t_end, h)):
        if n % every == 0 or n in wanted:
            times.append(t)
            values.append(sample(n, y))
    return Spread(np.array(times), np.array(values), snapshots)


def predictability_horizon(times: np.ndarray, spread: np.ndarray, threshold: float) -> np.ndarray:
    """First time [s] the spread reaches ``threshold`` [m] (interpolated), per column; NaN if never."""
    spread = np.atleast_2d(np.asarray(spread).T).T
    out = np.full(spread.shape[1], np.nan)
    for j in range(spread.shape[1]):
        above = np.nonzero(spread[:, j] >= threshold)[0]
        if above.size == 0:
            continue
        i = above[0]
        if i == 0:
            out[j] = times[0]
            continue
        s0, s1 = spread[i - 1, j], spread[i, j]
        out[j] = times[i - 1] + (threshold - s0) / (s1 - s0) * (times[i] - times[i - 1])
    return out


# ---------------------------------------------------------------------------- Poincare sections
def section_starts(
    energy: float,
    phi2: np.ndarray,
    omega2: np.ndarray,
    params: PendulumParameters,
) -> np.ndarray:
    """Starts on the section ``phi1 = 0``, ``omega1 > 0`` with total energy ``energy`` [J].

    For each ``(phi2, omega2)`` the kinetic energy is a quadratic ``a w1^2 + b w1 + c`` in
    ``w1 = omega1``; its coefficients are read off :func:`double_pendulum.model.energy.kinetic_energy` at
    ``w1 = -1, 0, 1`` and the larger root of ``a w1^2 + b w1 + c = E - V`` is taken. Points without
    a real root are dropped. Returns ``(4, n)``.
    """
    phi2, omega2 = np.broadcast_arrays(np.asarray(phi2, float), np.asarray(omega2, float))
    zero = np.zeros_like(phi2)

    def t_kin(w1: float) -> np.ndarray:
        return kinetic_energy(zero, phi2, w1, omega2, params, cos=np.cos)

    t_m, t_0, t_p = t_kin(-1.0), t_kin(0.0), t_kin(1.0)
    a, b = 0.5 * (t_p + t_m) - t_0, 0.5 * (t_p - t_m)
    c = t_0 + potential_energy(zero, phi2, params, cos=np.cos) - energy
    disc = b * b - 4.0 * a * c
    ok = disc >= 0.0
    omega1 = (-b[ok] + np.sqrt(disc[ok])) / (2.0 * a[ok])
    keep = omega1 > 0.0
    return initial_states(0.0, phi2[ok][keep], omega1[keep], omega2[ok][keep])


def _hermite(ya: np.ndarray, yb: np.ndarray, fa: np.ndarray, fb: np.ndarray, h: float, theta: np.ndarray):
    """Cubic Hermite interpolant on a step and its derivative d/dt, at fractions ``theta`` of the step."""
    t2, t3 = theta * theta, theta * theta * theta
    value = (2 * t3 - 3 * t2 + 1) * ya + h * (t3 - 2 * t2 + theta) * fa + (3 * t2 - 2 * t3) * yb + h * (t3 - t2) * fb
    rate = ((6 * t2 - 6 * theta) * ya + (6 * theta - 6 * t2) * yb) / h + (3 * t2 - 4 * theta + 1) * fa
    return value, rate + (3 * t2 - 2 * theta) * fb


def poincare_section(field: BatchField, y0: np.ndarray, t_end: float, h: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Crossings of ``phi1 = 0 (mod 2 pi)`` with ``omega1 > 0``: ``(points (m, 4), trajectory index (m,))``.

    A crossing is a sign change of ``sin(phi1)`` from - to + with ``cos(phi1) > 0`` between RK4
    steps; it is located on the step's cubic Hermite interpolant (from the states and their
    derivatives at both ends, error O(h^4)) by Newton's method.
    """
    pts, owner = [], []
    y_prev = np.array(y0, dtype=float)
    s_prev = np.sin(y_prev[0])
    t_prev = 0.0
    for _, t, y in rk4_iterate(field, y_prev, h, n_fixed_steps(t_end, h)):
        s_new = np.sin(y[0])
        hit = (s_prev < 0.0) & (s_new >= 0.0) & (np.cos(y[0]) > 0.0)
        if np.any(hit):
            ya, yb, step = y_prev[:, hit], y[:, hit], t - t_prev
            fa, fb = field(t_prev, ya), field(t, yb)
            target = 2.0 * math.pi * np.round(yb[0] / (2.0 * math.pi))
            theta = (target - ya[0]) / (yb[0] - ya[0])
            for _ in range(4):
                value, rate = _hermite(ya, yb, fa, fb, step, theta)
                theta = np.clip(theta - (value[0] - target) / (rate[0] * step), 0.0, 1.0)
            point, _ = _hermite(ya, yb, fa, fb, step, theta)
            point[0] -= target
            pts.append(point.T)
            owner.append(np.nonzero(hit)[0])
        y_prev, s_prev, t_prev = y.copy(), s_new, t
    if not pts:
        return np.empty((0, y0.shape[0])), np.empty(0, dtype=int)
    return np.concatenate(pts), np.concatenate(owner)
