r"""Map of the pendulum's decay rate b over the pivot suspension's stiffness k, damping c and mass M_s.

Each point of the map is one FMU run from the measured start (see
:mod:`double_pendulum.analysis.suspension.identification`) with an isotropic suspension k = k_x = k_y,
c = c_x = c_y, M_s, swept in parallel by :func:`double_pendulum.analysis.sweep.run_sweep`; b is fitted to
E_pendulum (and E_total) on the measured frames with the measured errors
(:func:`~double_pendulum.analysis.suspension.identification.simulated_decay_rate`), plus one run without
suspension for the base rate b0.

Physics of the map. :mod:`double_pendulum.analysis.suspension.response` predicts the suspension's share of b
from the spectrum of the force the pendulum exerts on a fixed pivot (linear response, one FMU run):
a stiff suspension gives

.. math::

    b - b_0 \approx -\frac{c\,\langle|\dot F|^2\rangle}{k^2 \bar E}

(iso-b curves c ~ k^2), a lightly damped one whose natural frequency sqrt(k/M) lies inside the force
spectrum takes :math:`\pi S_F(\omega_n)/(2M)` whatever c, an overdamped one :math:`\langle F^2\rangle/c`.
The map is checked against all three (:func:`law_agreement`); the stiff-limit law only in the region
where the suspension is much stiffer than the pendulum (:func:`stiff_region`):
:math:`\sqrt{k/M_y} \ge` :data:`STIFF_RATIO` :math:`\omega_F` and :math:`k \ge` :data:`STIFF_RATIO`
:math:`c\,\omega_F`, with the force's rms frequency
:math:`\omega_F = \sqrt{\langle|\dot F|^2\rangle/\langle F^2\rangle}`.

Iso-b curves. Along each row (fixed k) the c values where b crosses a level (log-interpolated,
:func:`row_crossings`) form the curve of suspensions with that decay rate: "rising" crossings lie on
the under-damped side (the loss grows with c), "falling" ones on the overdamped side.
:func:`trace_valley` refits c along the measured curve, started from the map's crossings.

Units: k in N/m, c in N s/m, M_s in kg, omega in rad/s, rates in 1/s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ..sweep import run_sweep
from ..track.measurement import FRAME_INTERVAL
from .identification import (
    FitFrames,
    Identification,
    MeasuredDecay,
    identify_damping,
    simulated_decay_rate,
    suspension_values,
)
from .response import ForceSpectrum

MAP_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-5, "atol": 1e-7}
"""Tolerances of the map's cells (with suspension): b within 1.5e-4 relative (mostly 1e-5) of rtol 1e-6,
for a quarter less CPU (checked on 3 k x 7 c cells at M_s = 2 kg; rtol 1e-6 was itself within 1e-6 of
1e-8). The suspension's oscillation bounds the step there, which keeps the error small."""
BASE_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-6, "atol": 1e-8}
"""Tolerances of the map's one run without suspension: no suspension bounds its step, and at rtol 1e-5 its
b moved by 1.5e-5 1/s, which every cell's b_suspension = b - b_base would carry."""
STIFF_DAMPING_RATE = 3000.0
"""c / M_s [1/s] from which a map cell runs the implicit ``rodas4`` (same tolerances) instead of ``dop853``:
the damper's rate c/M_s then bounds the explicit step (M_s = 0.5 kg, c = 3000 N s/m: 27 s of CPU with
dop853, 12 s with rodas4); b of the two agrees within 3e-5 relative there (checked at k = 5e3 and 2e5 N/m),
far below the map's stated 3 digits. Below it dop853 is the faster (at M_s = 2 kg, c = 3000 N s/m: 7 s
against 9 s)."""
MAP_UNITS: dict[str, str] = {
    "M_s": "kg",
    "k": "N/m",
    "c": "N.s/m",
    "omega_n_x": "rad/s",
    "omega_n_y": "rad/s",
    "b_E_pendulum": "1/s",
    "b_E_total": "1/s",
    "b_suspension": "1/s",
    "b_linear_response": "1/s",
    "b_quasi_static": "1/s",
}
"""Units of the columns of :meth:`DecayMap.rows`."""


# --- the sweep -----------------------------------------------------------------------------------


def sweep_cases(k_grid: Sequence[float], c_grid: Sequence[float], m_s: float) -> list[dict]:
    """One case per (k, c) (c fastest) at suspension mass ``m_s`` [kg], with the sweep tolerances (``rodas4``
    from :data:`STIFF_DAMPING_RATE` on)."""
    return [{**MAP_SETTINGS, **suspension_values(k, c, m_s), **map_solver(c, m_s)} for k in k_grid for c in c_grid]


def map_solver(c: float, m_s: float) -> dict[str, str]:
    """The solver of a map cell with damping ``c`` [N s/m] at suspension mass ``m_s`` [kg]."""
    return {"solver": "rodas4" if c / m_s >= STIFF_DAMPING_RATE else "dop853"}


def decay_rate_sweep(
    fmu_path: str | Path,
    base: Mapping[str, Any],
    frames: FitFrames,
    cases: Sequence[Mapping[str, Any]],
    max_workers: int | None = None,
) -> list[dict[str, float]]:
    """b of E_pendulum and E_total for every case, run in parallel by :func:`double_pendulum.analysis.sweep.run_sweep`.

    run_sweep starts each run at t = 0; the model is autonomous (no explicit time dependence), so
    this is the run from ``frames.t0`` shifted in time, and row n is frame ``t0 + n / FPS``.
    """
    results = run_sweep(
        fmu_path,
        [{**base, **case} for case in cases],
        stop_time=frames.duration,
        output_interval=FRAME_INTERVAL,
        outputs=("E_pendulum", "E_total"),
        max_workers=max_workers,
    )
    return [
        {
            "b_E_pendulum": simulated_decay_rate(r, frames, "E_pendulum"),
            "b_E_total": simulated_decay_rate(r, frames, "E_total"),
        }
        for r in results
    ]


# --- the map -------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class DecayMap:
    """Simulated decay rates on a (k, c) grid at one suspension mass, with the linear-response ones.

    Arrays have shape (len(k), len(c)); ``b_base`` [1/s] is the rate without suspension.
    """

    m_s: float
    k: np.ndarray
    c: np.ndarray
    b: np.ndarray
    b_total: np.ndarray
    b_linear: np.ndarray
    b_quasi_static: np.ndarray
    b_base: float

    @property
    def b_suspension(self) -> np.ndarray:
        """The suspension's share b - b_base [1/s]."""
        return self.b - self.b_base

    def rows(self, m12: float) -> list[dict[str, float]]:
        """One row per grid point for the CSV table (:data:`MAP_UNITS`)."""
        out = []
        for i, k in enumerate(self.k):
            for j, c in enumerate(self.c):
                out.append(
                    {
                        "M_s": self.m_s,
                        "k": k,
                        "c": c,
                        "omega_n_x": math.sqrt(k / self.m_s),
                        "omega_n_y": math.sqrt(k / (self.m_s + m12)),
                        "b_E_pendulum": self.b[i, j],
                        "b_E_total": self.b_total[i, j],
                        "b_suspension": self.b_suspension[i, j],
                        "b_linear_response": self.b_base + self.b_linear[i, j],
                        "b_quasi_static": self.b_base + self.b_quasi_static[i, j],
                    }
                )
        return out


def _map_from_rates(
    rates: Sequence[dict[str, float]], spectrum: ForceSpectrum, k_grid: Sequence[float], c_grid: Sequence[float],
    m_s: float,
) -> DecayMap:
    """A :class:`DecayMap` from the rates of the run without suspension (first) and of the grid (c fastest)."""
    shape = (len(k_grid), len(c_grid))
    k_arr, c_arr = np.asarray(k_grid, dtype=float), np.asarray(c_grid, dtype=float)
    return DecayMap(
        m_s=m_s,
        k=k_arr,
        c=c_arr,
        b=np.array([r["b_E_pendulum"] for r in rates[1:]]).reshape(shape),
        b_total=np.array([r["b_E_total"] for r in rates[1:]]).reshape(shape),
        b_linear=np.array([[spectrum.linear_response_rate(k, c, m_s) for c in c_arr] for k in k_arr]),
        b_quasi_static=np.array([[spectrum.quasi_static_rate(k, c) for c in c_arr] for k in k_arr]),
        b_base=rates[0]["b_E_pendulum"],
    )


def decay_map(
    fmu_path: str | Path,
    base: Mapping[str, Any],
    frames: FitFrames,
    spectrum: ForceSpectrum,
    k_grid: Sequence[float],
    c_grid: Sequence[float],
    m_s: float,
    max_workers: int | None = None,
) -> DecayMap:
    """Sweep (k, c) at ``m_s`` through the FMU (plus one run without suspension) and predict each point."""
    cases = [{**BASE_SETTINGS, "suspension": False}] + sweep_cases(k_grid, c_grid, m_s)
    rates = decay_rate_sweep(fmu_path, base, frames, cases, max_workers)
    return _map_from_rates(rates, spectrum, k_grid, c_grid, m_s)


def decay_maps(
    fmu_path: str | Path,
    base: Mapping[str, Any],
    frames: FitFrames,
    spectrum: ForceSpectrum,
    k_grid: Sequence[float],
    c_grid: Sequence[float],
    m_s_main: float,
    m_s_extra: Sequence[float] = (),
    extra_stride: int = 1,
    max_workers: int | None = None,
) -> list[DecayMap]:
    """The main (k, c) map at ``m_s_main`` [kg], then coarser ones at each of ``m_s_extra`` [kg] on every
    ``extra_stride``-th value of both grids (see :func:`decay_map`).

    All grids run in one sweep (one set of worker processes) with one run without suspension, which every
    map shares (the same start values, so the same run).
    """
    grids = [(k_grid, c_grid, m_s_main)]
    grids += [(k_grid[::extra_stride], c_grid[::extra_stride], m_s) for m_s in m_s_extra]
    cases = [{**BASE_SETTINGS, "suspension": False}]
    for k, c, m_s in grids:
        cases += sweep_cases(k, c, m_s)
    rates = decay_rate_sweep(fmu_path, base, frames, cases, max_workers)
    maps, i = [], 1
    for k, c, m_s in grids:
        n = len(k) * len(c)
        maps.append(_map_from_rates([rates[0], *rates[i:i + n]], spectrum, k, c, m_s))
        i += n
    return maps


def linear_response_grid(
    spectrum: ForceSpectrum,
    b_base: float,
    k_range: tuple[float, float],
    c_range: tuple[float, float],
    m_s: float,
    n: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """b_base + linear-response share on an n x n logarithmic grid (for smooth predicted contours)."""
    ks = np.geomspace(*k_range, n)
    cs = np.geomspace(*c_range, n)
    return ks, cs, b_base + np.array([[spectrum.linear_response_rate(k, c, m_s) for c in cs] for k in ks])


def crossing(x: np.ndarray, y: np.ndarray, level: float) -> float | None:
    """First x (log-interpolated) where y crosses ``level`` going along x, or None."""
    d = y - level
    for i in range(len(x) - 1):
        if d[i] == 0.0:
            return float(x[i])
        if d[i] * d[i + 1] < 0.0:
            f = d[i] / (d[i] - d[i + 1])
            return float(math.exp(math.log(x[i]) + f * (math.log(x[i + 1]) - math.log(x[i]))))
    return None


def row_crossings(c: np.ndarray, b: np.ndarray, level: float) -> list[tuple[float, str]]:
    """Every c where b(c) at fixed k crosses ``level``, with the branch: "rising" where the loss grows
    with c through the crossing (under-damped side), "falling" where it shrinks (overdamped side)."""
    d = b - level
    return [
        (crossing(c[j : j + 2], b[j : j + 2], level), "rising" if d[j] > 0 else "falling")
        for j in range(len(c) - 1)
        if d[j] * d[j + 1] < 0.0
    ]


def contour_points(dmap: DecayMap, level: float) -> list[dict[str, Any]]:
    """Along each row (fixed k) of the map, the c values where b crosses ``level``: the iso-b curve."""
    return [
        {"k": float(k), "c": c, "branch": branch}
        for k, row in zip(dmap.k, dmap.b)
        for c, branch in row_crossings(dmap.c, row, level)
    ]


def monotonic_rows(dmap: DecayMap) -> dict[str, Any]:
    """Where b falls (grows in magnitude) monotonically with c: per k, the range of c before |b| peaks."""
    out = {}
    for i, k in enumerate(dmap.k):
        j_peak = int(np.argmin(dmap.b[i]))
        rising = bool(np.all(np.diff(dmap.b[i, : j_peak + 1]) < 0.0))
        out[k_key(k)] = {"c_at_largest_loss": float(dmap.c[j_peak]), "monotonic_below_it": rising}
    return out


# --- the valley of the identification along the map ----------------------------------------------


def trace_valley(
    runner: FmuRunner,
    md: MeasuredDecay,
    base: Mapping[str, Any],
    ident: Identification,
    dmap: DecayMap,
    factors: Sequence[float],
) -> list[Identification]:
    """Fit c again at k = factor * k_identified (same M_s): how chi2 runs along the iso-b valley.

    Each fit starts from the map's iso-b crossing on that row (interpolated in ln k), else from the
    identified c.
    """
    out = []
    for factor in factors:
        k = ident.k * factor
        rising = [c for c, branch in contour_points_at(dmap, k, md.b) if branch == "rising"]
        out.append(identify_damping(runner, md, base, k, ident.m_s, rising[0] if rising else ident.c))
    return out


def contour_points_at(dmap: DecayMap, k: float, level: float) -> list[tuple[float, str]]:
    """Iso-b crossings (c, branch) at stiffness ``k`` [N/m], the map's rows interpolated in ln k."""
    lk = np.log(dmap.k)
    i = int(np.clip(np.searchsorted(lk, math.log(k)) - 1, 0, len(lk) - 2))
    f = (math.log(k) - lk[i]) / (lk[i + 1] - lk[i])
    return row_crossings(dmap.c, (1.0 - f) * dmap.b[i] + f * dmap.b[i + 1], level)


def k_key(k: float) -> str:
    """Summary key of a per-stiffness entry: 20000 N/m -> ``"k_20000_N_per_m"``."""
    return f"k_{k:.0f}_N_per_m"


def k_of_key(key: str) -> float:
    """The stiffness [N/m] of a :func:`k_key`."""
    return float(key.removeprefix("k_").removesuffix("_N_per_m"))


# --- checks of the map against the physics -------------------------------------------------------


def law_agreement(
    share: np.ndarray,
    predicted: np.ndarray,
    k: np.ndarray,
    c: np.ndarray,
    tol: float,
    region: np.ndarray | None = None,
) -> dict:
    """Cells (within ``region``, a mask; default all) where the FMU's suspension share is within ``tol``
    (relative) of a prediction: the ratio table, how many, their k and c ranges, the largest share there."""
    region = np.ones(share.shape, dtype=bool) if region is None else region
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = share / predicted
    ok = (np.abs(ratio - 1.0) <= tol) & region
    ki, ci = np.nonzero(ok)
    return {
        "ratio_fmu_to_prediction": ratio.tolist(),
        "tolerance": tol,
        "n_cells_within": int(ok.sum()),
        "n_cells": int(region.sum()),
        "k_range_within_N_per_m": [float(k[ki].min()), float(k[ki].max())] if ok.any() else None,
        "c_range_within_N_s_per_m": [float(c[ci].min()), float(c[ci].max())] if ok.any() else None,
        "largest_share_within_per_s": float(np.max(-share[ok])) if ok.any() else None,
        "rows_within": {k_key(kk): [float(cc) for cc, o in zip(c, row) if o] for kk, row in zip(k, ok)},
    }


def reach(dmap: DecayMap, level: float) -> dict[str, Any]:
    """Largest loss (most negative b) per k over the c grid, and the stiffest k whose best c reaches ``level``."""
    best = dmap.b.min(axis=1)
    reached = dmap.k[best <= level]
    return {
        "most_negative_b_per_k": {k_key(k): float(b) for k, b in zip(dmap.k, best)},
        "c_of_most_negative_b": {k_key(k): float(dmap.c[j]) for k, j in zip(dmap.k, dmap.b.argmin(axis=1))},
        "stiffest_k_reaching_N_per_m": float(reached.max()) if reached.size else None,
    }


STIFF_RATIO = 3.0
"""Stiff region: natural frequencies at least this many times the force's rms frequency, and the
spring force at least this many times the damper force at that frequency."""


def stiff_region(dmap: DecayMap, spectrum: ForceSpectrum) -> np.ndarray:
    r"""Mask of the cells where the suspension is "much stiffer than the pendulum".

    With the force's rms frequency :math:`\omega_F = \sqrt{\langle|\dot F|^2\rangle/\langle F^2\rangle}`:
    :math:`\sqrt{k/M_y} \ge` :data:`STIFF_RATIO` :math:`\omega_F` (M_y the larger mass) and
    :math:`k \ge` :data:`STIFF_RATIO` :math:`c\,\omega_F`.
    """
    var_x, var_y = spectrum.force_variances()
    w_f = math.sqrt(spectrum.fdot_squared / (var_x + var_y))
    m_y = spectrum.masses(dmap.m_s)[1]
    k, c = np.meshgrid(dmap.k, dmap.c, indexing="ij")
    return (np.sqrt(k / m_y) >= STIFF_RATIO * w_f) & (k >= STIFF_RATIO * c * w_f)


def map_summary(dmap: DecayMap, spectrum: ForceSpectrum, md: MeasuredDecay, seed_b: float) -> dict[str, Any]:
    """The map, its iso-b curves (measured and seed b ``seed_b`` [1/s]), reach, monotonicity and the law checks.

    The stiff-limit law is checked in the stiff region only (:func:`stiff_region`).
    """
    stiff = stiff_region(dmap, spectrum)
    return {
        "M_s_kg": dmap.m_s,
        "k_N_per_m": dmap.k.tolist(),
        "c_N_s_per_m": dmap.c.tolist(),
        "b_base_no_suspension_per_s": dmap.b_base,
        "b_E_pendulum": dmap.b.tolist(),
        "max_abs_b_E_pendulum_minus_b_E_total": float(np.max(np.abs(dmap.b - dmap.b_total))),
        "iso_b_measured": contour_points(dmap, md.b),
        "iso_b_seed": contour_points(dmap, seed_b),
        "reach_measured_b": reach(dmap, md.b),
        "monotonic_in_c": monotonic_rows(dmap),
        "linear_response": law_agreement(dmap.b_suspension, dmap.b_linear, dmap.k, dmap.c, 0.25),
        "stiff_region": {
            "natural_frequency_over_force_frequency": STIFF_RATIO,
            "k_over_c_omega_F": STIFF_RATIO,
            "n_cells": int(stiff.sum()),
        },
        "quasi_static_c_over_k2": law_agreement(dmap.b_suspension, dmap.b_quasi_static, dmap.k, dmap.c, 0.2, stiff),
    }
