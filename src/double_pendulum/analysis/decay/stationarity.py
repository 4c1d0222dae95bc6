r"""Is the measured decay E = a exp(b t) [J] stationary? What the record holds on the calibration drift, the
energy's biases and an amplitude-dependent loss.

- **Calibration drift.** The upper bob's distance from the fitted pivot falls by about 0.8 mm over the record
  (:func:`~double_pendulum.analysis.decay.summary.r1_drift`, slope d [m/s]). A change of the camera's scale
  about the pivot leaves the angles, and so the energy, unchanged. A pivot (mount) moving toward the bob by
  d (t - t_mid) along the bob's mean direction u does not: :func:`drift_corrected_track` moves every position
  back by d (t - t_mid) u, and the main fit on that track (with the main fit's errors) gives the shift of b.
  Its size in energy: a vertical pivot error dy changes the potential energy by about (m1 + m2) g dy (g = 9.81 m/s^2).
- **Energy biases.** The rods' mass (point masses against the seed's acrylic members) is a row of
  :mod:`~double_pendulum.analysis.decay.error_budget`; here also l2 moved by +-:data:`L2_SHIFT_M` (the
  table's resolution), fitted the same way.
- **Amplitude-dependent losses.** For a loss law dE/dt = -k E^p the local rate of an exponential fitted to a
  short window is b_w = -k E_w^(p-1) (E_w the window's mean energy), so ln|b_w| against ln E_w has the slope
  p - 1 (0 for losses proportional to E). :func:`window_rates` fits b in :data:`N_WINDOWS` consecutive,
  non-overlapping windows, each with the AR(1) errors of :mod:`~double_pendulum.analysis.decay.noise`, and a
  weighted straight line through (ln E_w, ln|b_w|) with the error of its slope.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..track.measurement import Reconstruction, Track
from .fit import exponential, fit_model
from .noise import ar1_coefficient, ar1_sandwich_errors

N_WINDOWS = 4
"""Non-overlapping windows of the record for the local decay rates (about 5.2 s, four slow swings, each)."""
L2_SHIFT_M = 0.001
"""Shift of l2 [m] for its row: the 1 mm resolution of the seed's table (the standard error, 0.16 mm,
treats correlated frames as independent)."""
G = 9.81
"""Gravitational acceleration [m/s^2] of the energy estimate (the model's default)."""


def bob_direction(rec: Reconstruction) -> np.ndarray:
    """Unit vector from the pivot to the upper bob's mean position (valid frames), in the track's axes."""
    v = rec.track.valid
    u = np.array([np.mean(rec.x1[v]), np.mean(rec.y1[v])])
    return u / np.hypot(*u)


def drift_corrected_track(rec: Reconstruction, drift: float) -> Track:
    """The track with every position moved back by ``drift`` (t - t_mid) along :func:`bob_direction`:
    as if a pivot moving toward the bob at ``drift`` [m/s] had stood still (t_mid the record's middle)."""
    tr = rec.track
    d = drift * (tr.t - 0.5 * (tr.t[0] + tr.t[-1]))
    ux, uy = bob_direction(rec)
    return dataclasses.replace(tr, x1=tr.x1 - d * ux, y1=tr.y1 - d * uy, x2=tr.x2 - d * ux, y2=tr.y2 - d * uy)


def window_rates(t: np.ndarray, energy: np.ndarray, sigma: np.ndarray, n_windows: int = N_WINDOWS) -> dict:
    """Exponential fits in ``n_windows`` consecutive windows of (t [s], E [J], sigma [J]) and the slope of
    ln|b_w| against ln E_w (module docstring; the slope's error from the windows' AR(1) errors of b)."""
    rows = []
    for idx in np.array_split(np.arange(len(t)), n_windows):
        tw, ew, sw = t[idx], energy[idx], sigma[idx]
        fit = fit_model("exponential", tw, ew, sw)
        a, b = fit.value("a"), fit.value("b")
        rho = ar1_coefficient((ew - exponential(tw, a, b)) / sw)
        rows.append({"t_start_s": float(tw[0]), "t_end_s": float(tw[-1]), "mean_energy_J": float(np.mean(ew)),
                     "b_per_s": b, "b_per_s_stderr": ar1_sandwich_errors(tw, ew, sw, a, b, rho)[1],
                     "rho": rho})  # fmt: skip
    x = np.log([r["mean_energy_J"] for r in rows])
    y = np.log([abs(r["b_per_s"]) for r in rows])
    w = np.array([(abs(r["b_per_s"]) / r["b_per_s_stderr"]) ** 2 for r in rows])  # 1 / var(ln|b|)
    xm = float(np.sum(w * x) / np.sum(w))
    sxx = float(np.sum(w * (x - xm) ** 2))
    slope = float(np.sum(w * (x - xm) * (y - np.sum(w * y) / np.sum(w))) / sxx)
    return {"windows": rows, "slope_dlnb_dlnE": slope, "slope_stderr": 1.0 / math.sqrt(sxx),
            "definition": "weighted line through (ln E_w, ln|b_w|); slope p - 1 for dE/dt = -k E^p"}  # fmt: skip


def stationarity(rec: Reconstruction, sigma: np.ndarray, drift: float, recipe: Callable[..., tuple[float, float]],
                 main: tuple[float, float], budget_rows: list[dict]) -> dict[str, Any]:  # fmt: skip
    """The non-stationarity study of the main fit ``main`` = (a [J], b [1/s]) with errors ``sigma`` [J].

    ``drift`` [m/s]: the upper bob's distance drift; ``recipe(track=..., geometry=...)``: the main recipe on
    another reconstruction, returning (a, b) (:func:`~double_pendulum.analysis.decay.error_budget.recipe_fit`);
    ``budget_rows``: the error budget's rows (the rod-mass rows are quoted from there).
    """
    m = rec.free_motion
    a0, b0 = main
    duration = float(rec.t[-1] - rec.t[0])
    corrected = recipe(track=drift_corrected_track(rec, drift))
    g = rec.geometry
    l2 = {s: recipe(geometry=dataclasses.replace(g, l2=g.l2 + s * L2_SHIFT_M)) for s in (-1, 1)}
    rods = {r["source"]: r for r in budget_rows if r["source"].startswith("rod mass")}
    total_mass = rec.params.m1 + rec.params.m2
    return {
        "calibration_drift": {
            "r1_change_m": drift * duration,
            "potential_energy_change_J": total_mass * G * abs(drift) * duration * abs(bob_direction(rec)[1]),
            "a_shift_J": corrected[0] - a0,
            "b_shift_per_s": corrected[1] - b0,
            "how": "positions moved back along the bob's mean direction as if the pivot had moved toward it; "
                   "a change of the camera's scale would leave the angles and the energy unchanged",
        },
        "l2": {"shift_m": L2_SHIFT_M, "a_shift_J": 0.5 * (l2[1][0] - l2[-1][0]),
               "b_shift_per_s": 0.5 * (l2[1][1] - l2[-1][1])},  # fmt: skip
        "rod_mass": {k: {"a_shift_J": r["a_shift_J"], "b_shift_per_s": r["b_shift_per_s"]} for k, r in rods.items()},
        "amplitude": window_rates(rec.t[m], rec.energy[m], sigma),
        "what_would_settle_it": [
            "releases from several small amplitudes (b against amplitude directly, each record stationary)",
            "a spin-down of each joint alone (the bearing's friction law without the other rod)",
            "a fixed marker at the pivot in every frame (the drift measured, not inferred)",
            "the rods weighed and l2 measured with a ruler (the energy's scale and partition)",
        ],
    }
