r"""Error budget of the exponential fit E = a exp(b t) of the measured energy (``energy_decay``).

The main fit (:mod:`double_pendulum.analysis.decay.summary`): Savitzky-Golay energies of point
masses, the calibrated errors of :func:`~double_pendulum.analysis.decay.fit.calibrate_error_model`,
the frames after the hand release. Its statistical error is the fit's under AR(1) residuals
(:func:`~double_pendulum.analysis.decay.noise.noise_model`: the sandwich error; a moving-block bootstrap
and the correlation factor F beside it). Each systematic row re-does the fit with one choice changed and
takes the shift of a [J] and b [1/s] from the main fit:

- velocity estimator: central differences (the seed's) instead of Savitzky-Golay;
- weights: the largest shift among the seed's eq. 25 weights, equal weights and the position-noise
  (inverse-variance) weights;
- first against second half: half the difference of the fits to the two halves of the frames (a
  taken at t = 0 for both). Each half's fit has its own statistical error (AR(1), about three times the
  whole record's), so this row holds mostly that noise again; :func:`halves` states the difference in
  units of its error;
- rod mass: rigid links :data:`~double_pendulum.model.parameters.SEED_RIGID_LINKS` instead of point
  masses (a bias of the point-mass energy, not a scatter), and half the difference between rods of
  70 +- 30 g a member;
- pivot: the pivot moved by its circle-fit standard errors in x and y (quadrature of the two shifts).

Total: the quadrature sum of the statistical error and every row (``total_a_J``, ``total_b_per_s``). It counts
the noise twice (the statistical row and the halves' row) and adds shifts of choices as if they were
independent errors: it is no confidence interval, and ``suspension_transfer`` alone still judges by it. b is
stated by :func:`b_statement`: the statistical error, and apart from it the range of b over named variants of
the weighting, the window and the energy (not added in quadrature).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ...model.parameters import SEED_RIGID_LINKS
from ..track.measurement import Geometry, Reconstruction, Track, reconstruct, same_pendulum
from .fit import (
    SEED_FIT,
    calibrate_error_model,
    fit_model,
    record_correlation_factor,
)
from .noise import ar1_gls_fit, noise_model
from .stationarity import stationarity
from .summary import r1_drift

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


ROD_ROW = "rod mass (point masses vs rigid links)"
"""The row of the seed's rods (none on a user's record)."""


def _row(name: str, shift: tuple[float, float], how: str) -> dict[str, Any]:
    return {"source": name, "a_J": abs(shift[0]), "b_per_s": abs(shift[1]),
            "a_shift_J": shift[0], "b_shift_per_s": shift[1], "how": how}  # fmt: skip


def systematic_rows(track: Track, rec: Reconstruction, main: tuple[float, float], sigma: np.ndarray,
                    rods: Mapping[str, float] | None = SEED_RIGID_LINKS) -> list[dict]:  # fmt: skip
    """The systematic rows (module docstring) for the main fit ``main`` = (a, b) with errors ``sigma``; the rod
    mass rows with the rods ``rods`` (the seed's members; None: a pendulum whose energy already holds its rods, or
    has none: no rod rows)."""
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
    if rods is not None:
        rows.append(_row(ROD_ROW, shift(_recipe(track, rec, rods=rods)),
                         "energies with the seed's 70 g acrylic members (a bias of the point-mass energy)"))
        m_rod, dm = rods["m_rod1"], ROD_MASS_UNCERTAINTY_KG
        lo, hi = (_recipe(track, rec, rods={**rods, "m_rod1": mr, "m_rod2": mr})
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
    other = reconstruct(track, **{"geometry": rec.geometry, **same_pendulum(rec), **kwargs})
    return _calibrated(other, rec.free_motion & other.energy_valid)


HALVES_RESAMPLES = 500
"""Bootstrap resamples for each half (its error to about 3 % of itself)."""
TRIM_S = 1.5
"""Time [s] cut from the start or the end of the record for the window variants of b (one slow swing)."""


def _variant_b(rec: Reconstruction, sigma: np.ndarray, gls_b: float, rows: list[dict], b0: float) -> dict[str, dict]:
    """b [1/s] of the main fit with one choice changed, by group (weighting, window, energy) and name."""
    m = rec.free_motion
    t, e = rec.t[m], rec.energy[m]

    def b_of(mask: np.ndarray, s: np.ndarray | None, energy: np.ndarray = e) -> float:
        return fit_model("exponential", t[mask], energy[mask], None if s is None else s[mask]).value("b")

    every = np.ones(len(t), dtype=bool)
    shifts = {r["source"]: r["b_shift_per_s"] for r in rows}
    return {
        "weighting": {"seed eq. 25": b_of(every, rec.sigma_energy_seed[m]), "equal": b_of(every, None),
                      "position noise": b_of(every, rec.sigma_energy[m]), "AR(1) GLS": gls_b},
        "window": {f"first {TRIM_S} s left out": b_of(t >= t[0] + TRIM_S, sigma),
                   f"last {TRIM_S} s left out": b_of(t <= t[-1] - TRIM_S, sigma)},
        "energy": {"central differences": b_of(every, sigma, rec.energy_cd[m]),
                   **({"rigid links (70 g members)": b0 + shifts[ROD_ROW]} if ROD_ROW in shifts else {}),
                   "pivot moved by its errors": b0 + shifts["pivot position"]},
    }  # fmt: skip


def halves(t: np.ndarray, e: np.ndarray, sigma: np.ndarray) -> dict[str, Any]:
    """The exponential fit to each half of the frames with its AR(1) and block-bootstrap errors [1/s], and their
    difference in units of its error sqrt(sigma_1^2 + sigma_2^2) for either noise description."""
    half = len(t) // 2
    fits = [noise_model(t[s], e[s], sigma[s], n_boot=HALVES_RESAMPLES) for s in (slice(None, half), slice(half, None))]
    diff = fits[1]["b_per_s"] - fits[0]["b_per_s"]
    out: dict[str, Any] = {"b_per_s": [f["b_per_s"] for f in fits], "rho": [f["rho"] for f in fits],
                           "difference_per_s": diff}  # fmt: skip
    for key in ("ar1", "bootstrap"):
        errs = [f[key]["b_per_s_stderr"] for f in fits]
        out[f"b_per_s_stderr_{key}"] = errs
        out[f"difference_in_sigma_{key}"] = diff / math.hypot(*errs)
    return out


def b_statement(noise: dict[str, Any], variants: dict[str, dict], halves_fit: dict[str, Any], factor: float,
                fit_error: float) -> dict[str, Any]:  # fmt: skip
    """b stated as what it is: the main fit's b [1/s] with its statistical error (AR(1) sandwich; the block
    bootstrap and the correlation factor beside it) and, apart, the range of b over the named variants."""
    b = noise["b_per_s"]
    flat = {f"{g}: {k}": v for g, vs in variants.items() for k, v in vs.items()}
    widest = max(flat, key=lambda k: abs(flat[k] - b))
    stat = noise["ar1"]["b_per_s_stderr"]
    lo, hi = min(flat.values()), max(flat.values())
    h = halves_fit
    boot = noise["bootstrap"]
    return {
        "b_per_s": b,
        "statistical_per_s": stat,
        "statistical": {"ar1_per_s": stat, "bootstrap_per_s": noise["bootstrap"]["b_per_s_stderr"],
                        "correlation_factor_per_s": fit_error * math.sqrt(factor), "rho": noise["rho"],
                        "block_s": noise["bootstrap"]["block_s"]},  # fmt: skip
        "systematic_range_per_s": [min(lo, b), max(hi, b)],
        "systematic_max_shift_per_s": abs(flat[widest] - b),
        "systematic_widest_variant": widest,
        "systematic_max_shift_without_seed_weights_per_s": max(abs(v - b) for k, v in flat.items()
                                                               if k != "weighting: seed eq. 25"),
        "variants_per_s": variants,
        "halves": h,
        "text": (f"b = {b:.4f} +- {stat:.4f} 1/s (statistical: AR(1) residuals, rho = {noise['rho']:.2f}; "
                 f"a {boot['block_s']:.1f} s block bootstrap gives {boot['b_per_s_stderr']:.5f}); "
                 f"the weighting, the window and the energy's recipe move it by up to {abs(flat[widest] - b):.4f} "
                 f"({widest}), over {lo:.4f} to {hi:.4f} 1/s"),  # fmt: skip
        "definitions": {"statistical_per_s": "standard error of b from the record's scatter alone (AR(1) sandwich)",
                        "systematic_range_per_s": "smallest and largest b over the named variants and the main fit: "
                                                  "a range of choices, not an error to add in quadrature"},
    }  # fmt: skip


def error_budget(rec: Reconstruction, sigma: np.ndarray, *, seed: bool = True) -> dict[str, Any]:
    """The whole budget: main a, b, statistical errors, systematic rows, totals, the seed's for comparison;
    the statement of b (:func:`b_statement`) and the non-stationarity study
    (:func:`~double_pendulum.analysis.decay.stationarity.stationarity`).

    ``sigma`` [J]: the main fit's calibrated errors on ``rec.free_motion``. ``seed``: the seed's record (its rod
    rows and its fit for comparison); False: a user's record (:mod:`~double_pendulum.analysis.track.user_track`),
    whose energy holds the rods its pendulum file gives, without the seed's rod rows or numbers.
    """
    m = rec.free_motion
    t, e = rec.t[m], rec.energy[m]
    fit = fit_model("exponential", t, e, sigma)
    a, b = fit.value("a"), fit.value("b")
    noise = noise_model(t, e, sigma)
    sa, sb = noise["ar1"]["a_J_stderr"], noise["ar1"]["b_per_s_stderr"]
    rows = [{"source": "statistical (with residual correlation)", "a_J": sa, "b_per_s": sb,
             "a_shift_J": None, "b_shift_per_s": None,
             "how": f"AR(1) residuals, rho = {noise['rho']:.2f} (block bootstrap: "
                    f"{noise['bootstrap']['b_per_s_stderr'] * 1e4:.2f}e-4 1/s)"}]  # fmt: skip
    rows += systematic_rows(rec.track, rec, (a, b), sigma, SEED_RIGID_LINKS if seed else None)
    total_a = math.sqrt(sum(r["a_J"] ** 2 for r in rows))
    total_b = math.sqrt(sum(r["b_per_s"] ** 2 for r in rows))
    halves_fit = halves(t, e, sigma)
    variants = _variant_b(rec, sigma, ar1_gls_fit(t, e, sigma).b, rows, b)
    factor = record_correlation_factor(t, e, sigma)

    def recipe(track: Track | None = None, **kwargs: Any) -> tuple[float, float]:
        """The main fit on another reconstruction, with the main fit's errors where the frames are the same."""
        other = reconstruct(rec.track if track is None else track,
                            **{"geometry": rec.geometry, **same_pendulum(rec), **kwargs})
        frames = m & other.energy_valid
        if not np.array_equal(frames, m):
            return _calibrated(other, frames)
        return exp_fit(t, other.energy[m], sigma)[:2]

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
        "noise_model": noise,
        "b_statement": b_statement(noise, variants, halves_fit, factor, fit.error("b")),
        "stationarity": stationarity(rec, sigma, r1_drift(rec), recipe, (a, b), rows),
        **({"seed": {"a_J": SEED_FIT["a_J"], "a_relative": SEED_FIT["a_rel_err"], "b_per_s": SEED_FIT["b_per_s"],
                     "b_relative": SEED_FIT["b_rel_err"]}} if seed else {}),  # fmt: skip
    }


def budget_table(budget: Mapping[str, Any]) -> str:
    """Markdown table of the budget: contributions to a [mJ] and b [1e-4 1/s], relative, and the seed's (if the
    budget has it: the seed's record)."""
    a, b = budget["a_J"], abs(budget["b_per_s"])
    fmt: Callable[[float, float, float], str] = lambda v, ref, s: f"{v * s:.2f} ({v / ref:.2%})"  # noqa: E731
    lines = ["| source | a [mJ] | b [1e-4 1/s] | how |", "|---|---|---|---|"]
    for r in budget["rows"]:
        lines.append(f"| {r['source']} | {fmt(r['a_J'], a, 1e3)} | {fmt(r['b_per_s'], b, 1e4)} | {r['how']} |")
    lines.append(f"| **total (quadrature)** | {fmt(budget['total_a_J'], a, 1e3)} | "
                 f"{fmt(budget['total_b_per_s'], b, 1e4)} | square root of the sum of the squared rows |")  # fmt: skip
    if "seed" not in budget:  # a user's record
        return "\n".join(lines)
    s = budget["seed"]
    lines.append(f"| the seed's quoted error | {s['a_relative'] * s['a_J'] * 1e3:.2f} ({s['a_relative']:.2%}) | "
                 f"{s['b_relative'] * abs(s['b_per_s']) * 1e4:.2f} ({s['b_relative']:.2%}) | "
                 f"a = {s['a_J']} J, b = {s['b_per_s']} 1/s |")  # fmt: skip
    return "\n".join(lines)
