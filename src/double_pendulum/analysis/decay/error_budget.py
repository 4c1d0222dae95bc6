r"""Error budget of the exponential fit E = a exp(b t) of the measured energy (``energy_decay``).

The main fit (:mod:`double_pendulum.analysis.decay.summary`): Savitzky-Golay energies of point
masses, the calibrated errors of :func:`~double_pendulum.analysis.decay.fit.calibrate_error_model`,
the frames after the hand release. Its statistical error is the fit's, multiplied by
:math:`\sqrt F` (F the residual-correlation factor, n_eff = n/F). Each systematic row re-does the
fit with one choice changed and takes the shift of a [J] and b [1/s] from the main fit:

- velocity estimator: central differences (the seed's) instead of Savitzky-Golay;
- weights: the largest shift among the seed's eq. 25 weights, equal weights and the position-noise
  (inverse-variance) weights;
- first against second half: half the difference of the fits to the two halves of the frames (a
  taken at t = 0 for both): a decay that is not exactly exponential;
- rod mass: rigid links :data:`~double_pendulum.model.parameters.SEED_RIGID_LINKS` instead of point
  masses (a bias of the point-mass energy, not a scatter), and half the difference between rods of
  70 +- 30 g a member;
- pivot: the pivot moved by its circle-fit standard errors in x and y (quadrature of the two shifts).

Total: the quadrature sum of the statistical error and every systematic shift.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ...model.parameters import SEED_RIGID_LINKS
from ..track.measurement import Geometry, Reconstruction, Track, reconstruct
from .fit import (
    SEED_FIT,
    calibrate_error_model,
    fit_model,
    record_correlation_factor,
)

ROD_MASS_UNCERTAINTY_KG = 0.03
"""Uncertainty of each member's rod mass [kg] (see SEED_RIGID_LINKS)."""


def exp_fit(t: np.ndarray, e: np.ndarray, sigma: np.ndarray | None) -> tuple[float, float, float, float]:
    """(a [J], b [1/s], sigma_a, sigma_b) of E = a exp(b t); errors times sqrt(F) of the record
    (:func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`)."""
    fit = fit_model("exponential", t, e, sigma, absolute_sigma=sigma is not None)
    f = math.sqrt(record_correlation_factor(t, e, sigma))
    return fit.value("a"), fit.value("b"), fit.error("a") * f, fit.error("b") * f


def _calibrated(rec: Reconstruction, m: np.ndarray) -> tuple[float, float]:
    """a, b of the main recipe (calibrated errors) on the frames ``m`` of ``rec``."""
    t, e = rec.t[m], rec.energy[m]
    sigma = calibrate_error_model(t, e, rec.sigma_energy[m], rec.momentum[m]).sigma
    return exp_fit(t, e, sigma)[:2]


def _shifted_pivot(geometry: Geometry, dx: float, dy: float) -> Geometry:
    pivot = geometry.pivot._replace(xc=geometry.pivot.xc + dx, yc=geometry.pivot.yc + dy)
    return dataclasses.replace(geometry, pivot=pivot)


def _row(name: str, shift: tuple[float, float], how: str) -> dict[str, Any]:
    return {"source": name, "a_J": abs(shift[0]), "b_per_s": abs(shift[1]),
            "a_shift_J": shift[0], "b_shift_per_s": shift[1], "how": how}  # fmt: skip


def systematic_rows(track: Track, rec: Reconstruction, main: tuple[float, float], sigma: np.ndarray) -> list[dict]:
    """The systematic rows (module docstring) for the main fit ``main`` = (a, b) with errors ``sigma``."""
    m = rec.free_motion
    t = rec.t[m]
    a0, b0 = main

    def shift(fit: tuple[float, ...]) -> tuple[float, float]:
        return fit[0] - a0, fit[1] - b0

    rows = [_row("velocity estimator", shift(exp_fit(t, rec.energy_cd[m], sigma)),
                 "central differences instead of Savitzky-Golay (same errors)")]  # fmt: skip
    weights = {"seed eq. 25": rec.sigma_energy_seed[m], "equal": None, "position noise": rec.sigma_energy[m]}
    shifts = {k: shift(exp_fit(t, rec.energy[m], s)) for k, s in weights.items()}
    worst = max(shifts, key=lambda k: abs(shifts[k][1]))
    rows.append(_row("weights", (max((s[0] for s in shifts.values()), key=abs), shifts[worst][1]),
                     "largest shift among seed eq. 25, equal and position-noise weights (b: " + worst + ")"))
    half = len(t) // 2
    fits = [exp_fit(t[s], rec.energy[m][s], sigma[s]) for s in (slice(None, half), slice(half, None))]
    rows.append(_row("first vs second half", (0.5 * (fits[1][0] - fits[0][0]), 0.5 * (fits[1][1] - fits[0][1])),
                     f"half the difference of the halves' fits (b: {fits[0][1]:.5f} and {fits[1][1]:.5f} 1/s)"))
    rows.append(_row("rod mass (point masses vs rigid links)", shift(_recipe(track, rec, rods=SEED_RIGID_LINKS)),
                     "energies with the seed's 70 g acrylic members (a bias of the point-mass energy)"))
    m_rod, dm = SEED_RIGID_LINKS["m_rod1"], ROD_MASS_UNCERTAINTY_KG
    lo, hi = (_recipe(track, rec, rods={**SEED_RIGID_LINKS, "m_rod1": mr, "m_rod2": mr})
              for mr in (m_rod - dm, m_rod + dm))  # fmt: skip
    rows.append(_row("rod mass +-0.03 kg", (0.5 * (hi[0] - lo[0]), 0.5 * (hi[1] - lo[1])),
                     "half the difference between 40 g and 100 g members"))
    g = rec.geometry
    sx = shift(_recipe(track, rec, geometry=_shifted_pivot(g, g.pivot.sigma_xc, 0.0)))
    sy = shift(_recipe(track, rec, geometry=_shifted_pivot(g, 0.0, g.pivot.sigma_yc)))
    rows.append(_row("pivot position", (math.hypot(sx[0], sy[0]), math.hypot(sx[1], sy[1])),
                     f"pivot moved by its circle-fit errors ({g.pivot.sigma_xc * 1e3:.2f} mm, "
                     f"{g.pivot.sigma_yc * 1e3:.2f} mm)"))
    return rows


def _recipe(track: Track, rec: Reconstruction, **kwargs: Any) -> tuple[float, float]:
    """The main recipe on the track reconstructed with other ``rods`` or ``geometry`` (same frames)."""
    other = reconstruct(track, **{"geometry": rec.geometry, **kwargs})
    return _calibrated(other, rec.free_motion & other.energy_valid)


def error_budget(rec: Reconstruction, sigma: np.ndarray) -> dict[str, Any]:
    """The whole budget: main a, b, statistical errors, systematic rows, totals, the seed's for comparison.

    ``sigma`` [J]: the main fit's calibrated errors on ``rec.free_motion``.
    """
    m = rec.free_motion
    a, b, sa, sb = exp_fit(rec.t[m], rec.energy[m], sigma)
    rows = [{"source": "statistical (with residual correlation)", "a_J": sa, "b_per_s": sb,
             "a_shift_J": None, "b_shift_per_s": None, "how": "fit error x sqrt(F)"}]  # fmt: skip
    rows += systematic_rows(rec.track, rec, (a, b), sigma)
    total_a = math.sqrt(sum(r["a_J"] ** 2 for r in rows))
    total_b = math.sqrt(sum(r["b_per_s"] ** 2 for r in rows))
    return {
        "a_J": a,
        "b_per_s": b,
        "rows": rows,
        "null_means": {"a_shift_J": "no shift: the statistical row is a spread, not a systematic change",
                       "b_shift_per_s": "no shift: the statistical row is a spread, not a systematic change"},
        "total_a_J": total_a,
        "total_b_per_s": total_b,
        "total_a_relative": total_a / a,
        "total_b_relative": total_b / abs(b),
        "seed": {"a_J": SEED_FIT["a_J"], "a_relative": SEED_FIT["a_rel_err"], "b_per_s": SEED_FIT["b_per_s"],
                 "b_relative": SEED_FIT["b_rel_err"]},  # fmt: skip
    }


def budget_table(budget: Mapping[str, Any]) -> str:
    """Markdown table of the budget: contributions to a [mJ] and b [1e-4 1/s], relative, and the seed's."""
    a, b = budget["a_J"], abs(budget["b_per_s"])
    fmt: Callable[[float, float, float], str] = lambda v, ref, s: f"{v * s:.2f} ({v / ref:.2%})"  # noqa: E731
    lines = ["| source | a [mJ] | b [1e-4 1/s] | how |", "|---|---|---|---|"]
    for r in budget["rows"]:
        lines.append(f"| {r['source']} | {fmt(r['a_J'], a, 1e3)} | {fmt(r['b_per_s'], b, 1e4)} | {r['how']} |")
    lines.append(f"| **total (quadrature)** | {fmt(budget['total_a_J'], a, 1e3)} | "
                 f"{fmt(budget['total_b_per_s'], b, 1e4)} | square root of the sum of the squared rows |")  # fmt: skip
    s = budget["seed"]
    lines.append(f"| the seed's quoted error | {s['a_relative'] * s['a_J'] * 1e3:.2f} ({s['a_relative']:.2%}) | "
                 f"{s['b_relative'] * abs(s['b_per_s']) * 1e4:.2f} ({s['b_relative']:.2%}) | "
                 f"a = {s['a_J']} J, b = {s['b_per_s']} 1/s |")  # fmt: skip
    return "\n".join(lines)
