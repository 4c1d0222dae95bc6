"""Ensembles of hand releases (seed 4.1): drawn starts, the spread of the lower bob within a group over
time, and the predictability horizon at which the spread reaches a threshold."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ...model.parameters import PendulumParameters
from .ensemble import (
    BatchField,
    batch_positions,
    initial_states,
    n_fixed_steps,
    rk4_iterate,
)


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
