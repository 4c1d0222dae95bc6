r"""Flip times of the double pendulum: the energetic bound for flipping and the flip-time map.

Everything here runs on batches (:mod:`double_pendulum.analysis.chaos.ensemble`).

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
from dataclasses import dataclass

import numpy as np

from ...model.energy import potential_energy
from ...model.parameters import PendulumParameters
from .ensemble import (
    BatchField,
    initial_states,
    n_fixed_steps,
    pendulum_field,
    rk4_step,
)


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
    from ..sweep import default_workers, parallel_map

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
