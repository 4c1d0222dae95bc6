r"""Lyapunov exponents of the double pendulum: tangent dynamics, Benettin's method, two-trajectory checks.

Everything here runs on batches (:mod:`double_pendulum.analysis.chaos.ensemble`) and uses the model's own
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
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.parameters import PendulumParameters
from .ensemble import (
    BatchField,
    Dop853Batch,
    n_fixed_steps,
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
    """Per-trajectory DOP853 (:mod:`double_pendulum.analysis.chaos.ensemble`) behind the stepper interface."""

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
    ``t_end`` [s]; ``field`` may include friction (any :data:`double_pendulum.analysis.chaos.ensemble.BatchField`).
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
    from ...solvers.registry import make_integrator  # noqa: PLC0415 - the runtime's integrator, only here

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
