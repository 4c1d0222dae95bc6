r"""Lyapunov exponents of one release, checked several ways (built on :mod:`.chaos`).

* :func:`compare_integrations`: the largest exponent :math:`\lambda_1` [1/s] of a start and a cloud of
  neighbours by several integrations (step halving), plus the two-trajectory estimate. A single
  finite-time estimate scatters by 10-20 % after 100 s; neighbours in the same chaotic sea share one
  exponent, so the cloud mean with its standard error :math:`s/\sqrt{N}` is the estimate.
* :func:`spectrum_summary`: all four exponents of one run (finite-time values); the frictionless flow
  pairs them as
  :math:`(\lambda, 0, 0, -\lambda)` and :math:`|\sum_i \lambda_i(T)| \le \ln\frac{m_1+m_2}{m_1} / T`.
* :func:`energy_scan`: :math:`\lambda_1` against the release angle :math:`\varphi_1 = \varphi_2 = \theta_0`
  from rest, with the energy over the flip threshold :math:`E / E_\mathrm{flip}`.
* :func:`exponent_with_friction`: finite-time :math:`\lambda_1` in windows while friction drains the energy.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ...model.parameters import PendulumParameters
from ...runs.results_io import table_from_columns
from .ensemble import BatchField, batch_energy, initial_states
from .flips import flip_energy_threshold
from .lyapunov import (
    Integration,
    LyapunovResult,
    local_exponents,
    lyapunov_benettin,
    lyapunov_single,
    lyapunov_two_trajectory,
    spectrum_sum_bound,
)

CHECKPOINTS = (5, 10, 20, 50, 100, 200)  # s, averaging times at which convergence is reported


def convergence_checkpoints(times: np.ndarray, running: np.ndarray) -> dict[str, float]:
    """The running estimate [1/s] at the renormalisation time nearest each of :data:`CHECKPOINTS` reached,
    keyed by the averaging time (``"lambda_per_s_after_5_s"``)."""
    return {f"lambda_per_s_after_{t:g}_s": float(running[np.argmin(np.abs(times - t))])
            for t in CHECKPOINTS if t <= times[-1]}


def standard_error(values: np.ndarray) -> float:
    """Standard error of the mean, ``s / sqrt(N)`` with the sample standard deviation ``s`` (ddof 1)."""
    return float(values.std(ddof=1) / math.sqrt(values.size))


# ---------------------------------------------------------------------------- largest exponent, step halving
@dataclass(frozen=True)
class IntegrationComparison:
    """Largest exponent of the same starts ``(4, N)`` (the nominal start first) by several integrations.

    ``results`` and ``wall_times`` [s] by integration name; ``two_trajectory`` the running two-trajectory
    estimates [1/s] ``(n_t, N)`` (RK4, :func:`.chaos.lyapunov_two_trajectory`); renormalised every
    ``renorm`` [s] up to ``t_end`` [s].
    """

    integrations: dict[str, Integration]
    results: dict[str, LyapunovResult]
    wall_times: dict[str, float]
    two_trajectory: np.ndarray
    renorm: float
    t_end: float

    @property
    def members(self) -> int:
        """Number of starts N."""
        return next(iter(self.results.values())).exponents.shape[1]

    @property
    def times(self) -> np.ndarray:
        """Renormalisation times [s] (the same for every integration)."""
        return next(iter(self.results.values())).times

    def nominal_running(self) -> dict[str, np.ndarray]:
        """Running estimate [1/s] of the nominal start, per integration."""
        return {name: r.running[:, 0, 0] for name, r in self.results.items()}

    def cloud_running(self) -> dict[str, np.ndarray]:
        """Running estimate [1/s] averaged over all starts, per integration."""
        return {name: r.running[:, 0, :].mean(axis=1) for name, r in self.results.items()}

    def cloud_exponents(self) -> dict[str, np.ndarray]:
        """Final estimates [1/s] ``(N,)`` of every start, per integration."""
        return {name: r.exponents[0] for name, r in self.results.items()}


def compare_integrations(
    field: BatchField,
    starts: np.ndarray,
    t_end: float,
    integrations: Mapping[str, Integration],
    *,
    renorm: float,
) -> IntegrationComparison:
    """Benettin's largest exponent of ``starts`` up to ``t_end`` [s] with each integration.

    Tangents renormalised every ``renorm`` [s]; the two-trajectory estimate uses RK4 (its default).
    """
    results, walls = {}, {}
    for name, integration in integrations.items():
        start = time.perf_counter()
        results[name] = lyapunov_benettin(field, starts, t_end, renorm_interval=renorm, integration=integration)
        walls[name] = time.perf_counter() - start
    _, two = lyapunov_two_trajectory(field, starts, t_end, renorm_interval=renorm)
    return IntegrationComparison(dict(integrations), results, walls, two, renorm, t_end)


def convergence_table(cmp: IntegrationComparison) -> tuple[np.ndarray, dict[str, str]]:
    """Running estimates [1/s] of the nominal start and of the cloud mean, per integration, and the cloud mean
    of the two-trajectory estimate: table and units."""
    columns = {f"lambda_{n}_nominal": v for n, v in cmp.nominal_running().items()}
    columns.update({f"lambda_{n}_cloud_mean": v for n, v in cmp.cloud_running().items()})
    columns["lambda_two_trajectory_rk4_cloud_mean"] = cmp.two_trajectory.mean(axis=1)
    return table_from_columns(time=cmp.times, **columns), {k: "1/s" for k in columns}


def convergence_curves(cmp: IntegrationComparison, cloud_label: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Labelled ``(times [s], running estimate [1/s])`` for the nominal start and the cloud mean per integration,
    and the cloud mean of the two-trajectory estimate."""
    curves = {f"{cmp.integrations[n].label()}, default start": (cmp.times, v) for n, v in cmp.nominal_running().items()}
    curves.update(
        {
            f"{cmp.integrations[n].label()}, mean of {cmp.members} {cloud_label}": (cmp.times, v)
            for n, v in cmp.cloud_running().items()
        }
    )
    two_label = f"two trajectories ({Integration().label()}), mean of {cmp.members} {cloud_label}"
    curves[two_label] = (cmp.times, cmp.two_trajectory.mean(axis=1))
    return curves


def largest_exponent_summary(cmp: IntegrationComparison, reference: str, cloud_label: str) -> dict:
    """``lyapunov_per_s``: the cloud mean [1/s] of the ``reference`` integration, its standard error, and
    per integration the convergence and the deviation of its cloud mean from the reference's.

    ``cloud_label`` names the starts besides the nominal one (e.g. ``"starts within 5 mm"``).
    """
    nominal, cloud_running, cloud = cmp.nominal_running(), cmp.cloud_running(), cmp.cloud_exponents()
    best = float(cloud[reference].mean())
    method = (
        f"Benettin, complex-step tangent, renormalised every {cmp.renorm} s, {cmp.integrations[reference].label()}, "
        f"{cmp.t_end:g} s, mean over the default start and {cmp.members - 1} {cloud_label}"
    )
    return {
        "lyapunov_per_s": best,
        "lyapunov_sem_per_s": standard_error(cloud[reference]),
        "method": method,
        "default_start_alone_per_s": float(nominal[reference][-1]),
        "convergence_default_start": {n: convergence_checkpoints(cmp.times, v) for n, v in nominal.items()},
        "convergence_cloud_mean": {n: convergence_checkpoints(cmp.times, v) for n, v in cloud_running.items()},
        "step_halving": {
            cmp.integrations[name].label(): {
                "default_start": float(nominal[name][-1]),
                "cloud_mean": float(cloud[name].mean()),
                "cloud_sem": standard_error(cloud[name]),
                f"relative_to_{reference}_cloud_mean": float(cloud[name].mean() / cloud[reference].mean() - 1.0),
                "wall_time_s": cmp.wall_times[name],
            }
            for name in cmp.integrations
        },
        "cloud_members": cmp.members,
        "two_trajectory_rk4_default_start": float(cmp.two_trajectory[-1, 0]),
        "two_trajectory_rk4_cloud_mean": float(cmp.two_trajectory[-1].mean()),
    }


# ---------------------------------------------------------------------------- the spectrum
@dataclass(frozen=True)
class Spectrum:
    """Running estimates of all exponents [1/s] ``(n_t, 4)`` of one start and the bound on their sum [1/s] ``(n_t,)``.

    ``h`` [s] is the RK4 step used.
    """

    times: np.ndarray
    running: np.ndarray
    sum_bound: np.ndarray
    h: float


def lyapunov_spectrum(
    field: BatchField, y0: np.ndarray, t_end: float, params: PendulumParameters, *, renorm: float, h: float
) -> Spectrum:
    """All four exponents of the single start ``y0`` ``(4, 1)`` by QR of 4 complex-step tangents, RK4 step ``h``."""
    res = lyapunov_benettin(
        field, y0, t_end, renorm_interval=renorm, n_vectors=4, integration=Integration("rk4", h=h)
    )
    return Spectrum(res.times, res.running[:, :, 0], spectrum_sum_bound(params, res.times), h)


def spectrum_table(spectrum: Spectrum) -> tuple[np.ndarray, dict[str, str]]:
    """``lambda1..4``, their ``sum`` and ``sum_bound`` [1/s] over time: table and units."""
    run = spectrum.running
    table = table_from_columns(
        time=spectrum.times,
        **{f"lambda{i + 1}": run[:, i] for i in range(4)},
        sum=run.sum(axis=1),
        sum_bound=spectrum.sum_bound,
    )
    return table, {**{f"lambda{i + 1}": "1/s" for i in range(4)}, "sum": "1/s", "sum_bound": "1/s"}


def spectrum_summary(spectrum: Spectrum, t_end: float) -> dict:
    """Final exponents [1/s], the pairing ``lambda1 + lambda4``, their sum and its bound.

    The exponents are finite-time values of one run up to ``t_end`` [s], not the limit T -> infinity:
    the middle pair, 0 in the limit, is still of order ln(T)/T, and a single run's lambda1 scatters by
    10-20 % between neighbouring starts (:func:`compare_integrations` averages a cloud).
    """
    lam = spectrum.running[-1]
    return {
        "exponents_per_s": lam,
        "lambda1_plus_lambda4_per_s": float(lam[0] + lam[3]),
        "sum_per_s": float(lam.sum()),
        "sum_bound_per_s": float(spectrum.sum_bound[-1]),
        "t_end_s": t_end,
        "method": f"QR (Gram-Schmidt) of 4 complex-step tangent vectors, rk4 h = {spectrum.h * 1e3:g} ms",
        "note": f"finite-time spectrum of one {t_end:g} s run (not the T -> infinity limit; the middle pair "
        "tends to 0 like ln(T)/T or faster)",
    }


# ---------------------------------------------------------------------------- against the energy
@dataclass(frozen=True)
class EnergyScan:
    """Largest exponent [1/s] against the release angle theta0 [rad], with the start energy [J] and E / E_flip."""

    theta0: np.ndarray
    energy: np.ndarray
    energy_ratio: np.ndarray
    exponent: np.ndarray
    wall_time: float


def energy_scan(
    field: BatchField, thetas: Sequence[float], params: PendulumParameters, t_end: float, *, renorm: float, h: float
) -> EnergyScan:
    """Largest exponent of the releases from rest at ``phi1 = phi2 = theta0`` (RK4 step ``h``).

    ``E_0 = V(theta0, theta0)`` and ``E_flip = min(V(pi, 0), V(0, pi))`` (:func:`.chaos.flip_energy_threshold`).
    """
    theta = np.array(thetas)
    y0 = initial_states(theta, theta)
    start = time.perf_counter()
    res = lyapunov_benettin(field, y0, t_end, renorm_interval=renorm, integration=Integration("rk4", h=h))
    wall = time.perf_counter() - start
    energy = batch_energy(y0, params)
    return EnergyScan(theta, energy, energy / flip_energy_threshold(params), res.exponents[0], wall)


def energy_scan_table(scan: EnergyScan) -> tuple[np.ndarray, dict[str, str]]:
    """``theta0`` [rad], ``E_0`` [J], ``E_over_E_flip``, ``lambda_max`` [1/s]: table and units."""
    table = table_from_columns(
        theta0=scan.theta0, E_0=scan.energy, E_over_E_flip=scan.energy_ratio, lambda_max=scan.exponent
    )
    return table, {"theta0": "rad", "E_0": "J", "lambda_max": "1/s"}


def energy_scan_summary(scan: EnergyScan, t_end: float) -> dict:
    """The scan as lists for ``summary.json``."""
    return {
        "theta0_rad": scan.theta0,
        "lambda_per_s": scan.exponent,
        "E_over_E_flip": scan.energy_ratio,
        "t_end_s": t_end,
        "wall_time_s": scan.wall_time,
    }


# ---------------------------------------------------------------------------- with friction
@dataclass(frozen=True)
class FrictionWindows:
    """Finite-time largest exponent [1/s] per window (``centres`` [s]) and E / E_flip along the trajectory."""

    centres: np.ndarray
    exponent: np.ndarray
    times: np.ndarray
    energy_ratio: np.ndarray
    wall_time: float

    @property
    def ratio_at_centres(self) -> np.ndarray:
        """E / E_flip interpolated linearly to the window centres."""
        return np.interp(self.centres, self.times, self.energy_ratio)


def exponent_with_friction(
    field: Callable[[float, list[float]], list[float]], y0: Sequence[float], t_end: float, params: PendulumParameters,
    *, renorm: float, window: float, rtol: float = 1e-8,
) -> FrictionWindows:
    """Largest exponent of the start ``y0`` (4 floats) in windows of ``window`` [s] under a dissipative float
    vector field ``field`` (:func:`~double_pendulum.analysis.chaos.ensemble.rod_field`).

    The field is not analytic (friction evaluated with ``math``), so the tangent uses central
    differences (:func:`.chaos.lyapunov_single`: the runtime's DOP853 at ``rtol``, atol = rtol / 100;
    rtol 1e-6 takes a third of the CPU time of 1e-8; either way the chaotic trajectory itself is lost
    after some 10 s, and each window's exponent is one sample of the chaotic sea). The energy is that
    of the frictionless pendulum ``E = T + V`` along the trajectory, over ``E_flip``.
    """
    start = time.perf_counter()
    res = lyapunov_single(field, y0, t_end, renorm_interval=renorm, rtol=rtol)
    wall = time.perf_counter() - start
    centres, local = local_exponents(res, window)
    ratio = batch_energy(res.states[:, :, 0].T, params) / flip_energy_threshold(params)
    return FrictionWindows(centres, local[:, 0], res.times, ratio, wall)


def friction_table(windows: FrictionWindows) -> tuple[np.ndarray, dict[str, str]]:
    """Window centres [s], ``lambda_window`` [1/s], ``E_over_E_flip``: table and units."""
    table = table_from_columns(
        time=windows.centres, lambda_window=windows.exponent, E_over_E_flip=windows.ratio_at_centres
    )
    return table, {"lambda_window": "1/s"}


def friction_summary(windows: FrictionWindows, window: float, mechanisms: Sequence[str]) -> dict:
    """Exponent per window and E / E_flip at the window centres for ``summary.json`` (``mechanisms``: which are on)."""
    return {
        "mechanisms": list(mechanisms),
        "window_s": window,
        "window_centres_s": windows.centres,
        "lambda_per_window_per_s": windows.exponent,
        "E_over_E_flip_at_centres": windows.ratio_at_centres,
        "wall_time_s": windows.wall_time,
    }
