r"""Predictability of a hand release (seed 4.1): drawn releases, where runs part, ensemble horizons.

The upper bob's start position is known to :math:`\sigma` [m] (:func:`.chaos.release_ensemble`).
Two runs whose starts differ by :math:`\delta_0` part as :math:`\delta(t) \approx \delta_0 e^{\lambda t}`,
so the time at which an ensemble's spread reaches a distance :math:`d` grows like

.. math::

    t_h(\sigma) \approx \frac{1}{\lambda} \ln\frac{d}{\sigma},

one :math:`1/\lambda` per e-fold of start precision: :func:`horizon_slopes` fits
:math:`-\mathrm{d}t_h / \mathrm{d}\ln\sigma`, to be compared with :math:`1/\lambda`.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ...model.parameters import PendulumParameters
from ...runs.results_io import table_from_columns
from . import releases
from .ensemble import BatchField, dop853_trajectory, initial_states, pendulum_field


# ---------------------------------------------------------------------------- single releases (FMU runs)
def drawn_releases(
    start: Mapping[str, float], sigma: float, n: int, params: PendulumParameters, *, seed: int
) -> dict[str, dict[str, float]]:
    """FMU start values by name: ``"nominal"`` (``start``) and ``release_1..n`` with ``phi1_0`` drawn.

    ``phi1_0 = start["phi1_0"] + s / l1`` with ``s ~ N(0, sigma^2)`` [m] (:func:`.chaos.release_ensemble`);
    the other start values are those of ``start``.
    """
    starts = releases.release_ensemble(start["phi1_0"], start["phi2_0"], sigma, n, params, seed=seed)
    out = {"nominal": dict(start)}
    for k in range(n):
        out[f"release_{k + 1}"] = {**start, "phi1_0": float(starts[0, k])}
    return out


def lower_bob_parting(results: Sequence[np.ndarray], threshold: float) -> tuple[float, tuple[float, float]]:
    """First time [s] the lower bobs of the runs are more than ``threshold`` [m] apart, and where.

    The distance at each output time is the largest over all pairs of runs,
    ``max_ij sqrt((x2_i - x2_j)^2 + (y2_i - y2_j)^2)``; the place is the mean lower bob position (x2, y2) [m]
    at that time. If the runs never part, the last output time is returned.
    """
    x = np.array([r["x2"] for r in results])
    y = np.array([r["y2"] for r in results])
    dist = np.max(np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :]), axis=(0, 1))
    i = int(np.argmax(dist > threshold)) if np.any(dist > threshold) else len(dist) - 1
    return float(results[0]["time"][i]), (float(x[:, i].mean()), float(y[:, i].mean()))


def lower_bob_traces(
    results: Mapping[str, np.ndarray], t_end: float
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The lower bob's trace (x2, y2) [m] of each labelled run up to ``t_end`` [s] (the first run's time grid)."""
    first = next(iter(results.values()))
    window = first["time"] <= t_end
    return {label: (r["x2"][window], r["y2"][window]) for label, r in results.items()}


def batch_angle_difference(
    result: np.ndarray,
    phi1_0: float,
    phi2_0: float,
    params: PendulumParameters,
    *,
    t_check: float,
    rtol: float,
    atol: float,
) -> float:
    """Largest ``|phi_i(FMU) - phi_i(batch)|`` [rad] up to ``t_check`` [s], from rest at (phi1_0, phi2_0).

    The batch run is :func:`.ensemble.dop853_trajectory` of the frictionless pendulum with the same
    tolerances, on the FMU result's output times after the start.
    """
    keep = result["time"] <= t_check + 1e-12
    times = result["time"][keep][1:]
    y0 = initial_states(phi1_0, phi2_0)
    batch = dop853_trajectory(pendulum_field(params), y0, times, rtol=rtol, atol=atol)
    return float(
        max(
            np.max(np.abs(batch.y[:, 0, 0] - result["phi1"][keep][1:])),
            np.max(np.abs(batch.y[:, 1, 0] - result["phi2"][keep][1:])),
        )
    )


# ---------------------------------------------------------------------------- ensembles
@dataclass(frozen=True)
class Predictability:
    """Release ensembles, one per start uncertainty, and their predictability horizons.

    ``sigmas`` [m] ``(G,)``; ``spread`` the lower bob's RMS spread over time (:class:`.chaos.Spread`,
    ``spread.spread`` [m] ``(n_t, G)``); ``horizons`` maps a threshold d [m] to the first time [s]
    each spread reaches it ``(G,)`` (NaN: never); ``snapshot_group`` the index of the ensemble whose
    clouds are kept; ``wall_time`` [s] of the integration.
    """

    sigmas: np.ndarray
    members: int
    spread: releases.Spread
    horizons: dict[float, np.ndarray]
    snapshot_group: int
    wall_time: float


def release_predictability(
    field: BatchField,
    params: PendulumParameters,
    phi1_0: float,
    phi2_0: float,
    sigmas: Sequence[float],
    members: int,
    t_end: float,
    *,
    thresholds: Sequence[float],
    h: float,
    seed: int,
    snapshot_sigma: float,
    snapshot_times: Sequence[float],
) -> Predictability:
    """Integrate ``members`` releases per uncertainty ``sigmas[i]`` [m] (draws seeded ``seed + i``), RK4 step ``h``.

    All ensembles run in one batch up to ``t_end`` [s]; the clouds of the ensemble with
    ``sigma = snapshot_sigma`` are kept at ``snapshot_times`` [s] (those up to ``t_end``).
    """
    groups = [
        releases.release_ensemble(phi1_0, phi2_0, s, members, params, seed=seed + i) for i, s in enumerate(sigmas)
    ]
    snapshot_group = list(sigmas).index(snapshot_sigma)
    start = time.perf_counter()
    spread = releases.ensemble_spread(
        field,
        groups,
        params,
        t_end,
        h=h,
        snapshot_times=[t for t in snapshot_times if t <= t_end],
        snapshot_group=snapshot_group,
    )
    wall = time.perf_counter() - start
    horizons = {d: releases.predictability_horizon(spread.times, spread.spread, d) for d in thresholds}
    return Predictability(np.array(sigmas), members, spread, horizons, snapshot_group, wall)


def horizon_slopes(sigmas: np.ndarray, horizons: Mapping[float, np.ndarray]) -> dict[str, float]:
    """``-d t_h / d ln(sigma)`` [s] per threshold (least squares over the finite horizons; >= 2 needed).

    Keyed by the threshold in cm (``"1cm"``); for exponential separation it approaches ``1/lambda``.
    """
    slopes = {}
    for d, horizon in horizons.items():
        ok = np.isfinite(horizon)
        if np.count_nonzero(ok) >= 2:
            slopes[f"{d * 100:g}cm"] = float(-np.polyfit(np.log(sigmas[ok]), horizon[ok], 1)[0])
    return slopes


def spread_label(sigma: float) -> str:
    """Column name of an ensemble's spread, e.g. ``spread_sigma_5mm``."""
    return f"spread_sigma_{sigma * 1e3:g}mm"


def spread_table(result: Predictability) -> tuple[np.ndarray, dict[str, str]]:
    """Spread [m] of every ensemble over time: the table and its units."""
    labels = [spread_label(s) for s in result.sigmas]
    columns = {k: result.spread.spread[:, j] for j, k in enumerate(labels)}
    return table_from_columns(time=result.spread.times, **columns), {k: "m" for k in labels}


def horizon_table(result: Predictability) -> tuple[np.ndarray, dict[str, str]]:
    """Horizons [s] for 1 cm and 10 cm against the uncertainty sigma [m]: the table and its units."""
    table = table_from_columns(
        sigma=result.sigmas, horizon_1cm=result.horizons[0.01], horizon_10cm=result.horizons[0.10]
    )
    return table, {"sigma": "m", "horizon_1cm": "s", "horizon_10cm": "s"}


def predictability_summary(result: Predictability, lyapunov: float) -> dict:
    """Horizons [s] (all and at the snapshot uncertainty), their slopes and ``1/lambda`` [s]."""
    g = result.snapshot_group
    return {
        "members_per_ensemble": result.members,
        "sigmas_m": result.sigmas,
        "horizon_1cm_s": result.horizons[0.01],
        "horizon_10cm_s": result.horizons[0.10],
        "horizon_1cm_at_5mm_s": float(result.horizons[0.01][g]),
        "horizon_10cm_at_5mm_s": float(result.horizons[0.10][g]),
        "horizon_slope_per_ln_sigma_s": horizon_slopes(result.sigmas, result.horizons),
        "one_over_lyapunov_s": 1.0 / lyapunov if lyapunov > 0 else None,
        "wall_time_s": result.wall_time,
        "null_means": predictability_null_means(float(result.spread.times[-1])),
    }


def predictability_null_means(t_end: float) -> dict[str, str]:
    """What a null in :func:`predictability_summary` means, by key (``t_end``: the ensembles' length [s])."""
    never = f"the spread did not reach the threshold within the {t_end:g} s of the ensemble runs"
    keys = ("horizon_1cm_s", "horizon_10cm_s", "horizon_1cm_at_5mm_s", "horizon_10cm_at_5mm_s")
    return {**dict.fromkeys(keys, never),
            "horizon_slope_per_ln_sigma_s": "fewer than two uncertainties reached the threshold",
            "one_over_lyapunov_s": "the largest Lyapunov exponent is not positive"}
