r"""The prediction horizon over every uncertain input: what moves it, by how much, and its distribution.

The main prediction of ``measured_vs_sim`` (the least-squares start and camera geometry, :mod:`.comparison`) takes
every input at one value. Its lower bob's smoothed 5 cm horizon :math:`h` (:func:`~.comparison.headline_horizon`)
moves with each of them:

- **the rods' mass distribution**: the seed's words allow 70 +- 30 g a member
  (:data:`~double_pendulum.model.parameters.SEED_RIGID_LINKS`); both members are given the mass :math:`m_r`
  [kg] and the start and geometry are fitted again at each (:func:`rod_profile`). The fit's
  :math:`\chi^2(m_r)` over the start-fit window is a profile over the rods' inertia: its minimum and the
  :math:`m_r` where it rises by :math:`\chi^2_{red}` (one standard error, the fit's errors scaled by its own
  :math:`\chi^2_{red}`) say what the window can tell about the rods; the RMS error of each run's lower bob over the
  whole prediction says what the motion of the whole record prefers (in-sample: the losses are fitted with 70 g);
- **the start-fit window**: a stated choice (1.5 s), against :data:`WINDOWS_S`;
- **l1**: the circle fit's value +- its standard error, the start and geometry fitted again at each;
- **the losses**: each fitted loss coefficient +- its standard error, the other coefficients moved along their
  correlation with it (:math:`\Delta\theta = \pm C_{:,j}/\sqrt{C_{jj}}`: the ends of the coefficient's own +-1 sigma
  interval, where the energy fit is one standard error worse; alone, correlated coefficients would change the total
  damping far more than the record allows); the start and geometry kept (over the 1.5 s window every loss law
  dissipates about the same);
- **the start state and geometry**: their covariance from the least-squares fit.

**What moves it** (:func:`one_at_a_time`): :math:`h` at each input's two values, the others held, against the main
run's :math:`h_0`. A horizon never crossed within the record is censored at the prediction's length :math:`T`.

**Its distribution** (:func:`monte_carlo`): :data:`ENSEMBLE_SIZE` runs, each input drawn from its own block
(mean, covariance) independently of the others, :math:`x_b = \mu_b + w_b L_b z_b` (:math:`L_b L_b^T` the block's
covariance, :math:`z_b` standard normal, :math:`w_b` a width factor, 1 as fitted). The start and geometry of a run
follow its rods and l1 to first order, :math:`s = s_0 + J\,(\Delta m_r, \Delta l_1) + L_s z_s` with :math:`J`
the central differences of the refits, so that a run with other rods starts where a fit with those rods would.
:func:`horizon_interval` gives the median and the 16-84 % and 2.5-97.5 % ranges of :math:`h`, censored runs
counted as :math:`T` (a percentile at :math:`T` says "beyond the record").

Everything is in-sample: the losses and the start are fitted to the record the horizons are measured on.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ...runs.result_cache import cached
from ..track.measurement import Reconstruction
from ..track.start_state import StartStateFit
from .comparison import FREE_GEOMETRY, headline_horizon, least_squares_start, predict
from .loss_models import loss_values

ROD_MEMBER_KG = (0.025, 0.040, 0.055, 0.070, 0.085, 0.100)
"""Masses [kg] of each rod member of the profile (:func:`rod_profile`), about the seed's 70 g."""
ROD_RANGE_KG = (0.040, 0.100)
"""The rods' member mass [kg] at the two ends of the seed's stated 70 +- 30 g
(:data:`~double_pendulum.model.parameters.SEED_RIGID_LINKS`): the one-at-a-time row and the response of the start
(:func:`fmu_member`)."""
ROD_STATED_STDERR_KG = 0.030
"""The rods' member mass's standard error [kg] of the draws: the seed's words (the record does not pin it: the
start-fit window and the whole record's motion prefer masses 40 g apart, :func:`rod_profile`)."""
WINDOWS_S = (1.0, 2.0)
"""Other start-fit windows [s] against the stated 1.5 s."""
ENSEMBLE_SIZE = 40
"""Runs of :func:`monte_carlo` (about 0.8 s of CPU each for 20 s; cached). Quick: :data:`QUICK_ENSEMBLE_SIZE`."""
QUICK_ENSEMBLE_SIZE = 4
ENSEMBLE_SEED = 20261207
"""Seed of :func:`monte_carlo`'s draws (one stream per input block, so widening one block leaves the others' draws
as they were)."""
PERCENTILES = (2.5, 16.0, 50.0, 84.0, 97.5)
"""Percentiles of :func:`horizon_interval`."""


@dataclass(frozen=True)
class Block:
    """One uncertain input of :func:`monte_carlo`: names, mean and covariance of its values."""

    names: tuple[str, ...]
    mean: np.ndarray
    cov: np.ndarray


def block_draws(blocks: Mapping[str, Block], size: int, seed: int = ENSEMBLE_SEED,
                widths: Mapping[str, float] | None = None) -> dict[str, np.ndarray]:  # fmt: skip
    """``size`` draws (rows) of each block, ``mean + width * L z`` (L a square root of its covariance: a zero or
    singular covariance is allowed), each block from its own random stream (``seed`` and the block's position), so
    that a block's ``widths`` factor (default 1) moves only its own draws."""
    out = {}
    for index, (name, b) in enumerate(blocks.items()):
        z = np.random.default_rng([seed, index]).standard_normal((size, len(b.names)))
        cov = 0.5 * (np.asarray(b.cov, dtype=float) + np.asarray(b.cov, dtype=float).T)
        w, v = np.linalg.eigh(cov)
        root = v * np.sqrt(np.clip(w, 0.0, None))
        out[name] = np.asarray(b.mean, dtype=float) + (widths or {}).get(name, 1.0) * z @ root.T
    return out


def horizon_interval(horizons: Sequence[float], span_s: float) -> dict[str, Any]:
    """Median, 16-84 % and 2.5-97.5 % ranges [s] of ``horizons`` (censored ones given as ``span_s``), the
    censored fraction and the width of the 16-84 % range [s]; an end at ``span_s`` says "beyond the record"."""
    h = np.minimum(np.asarray(horizons, dtype=float), span_s)
    p2, p16, p50, p84, p97 = (float(x) for x in np.percentile(h, PERCENTILES))
    return {"median_s": p50, "range_16_84_s": [p16, p84], "range_2_97_s": [p2, p97], "width_16_84_s": p84 - p16,
            "n": int(len(h)), "censored_fraction": float(np.mean(h >= span_s)),
            "top_censored": bool(p84 >= span_s),
            "range_16_84_claim": f"{p16:.1f} s to beyond the record" if p84 >= span_s else f"{p16:.1f} to {p84:.1f} s"}


def monte_carlo(run: Callable[[Mapping[str, np.ndarray]], float], blocks: Mapping[str, Block], size: int,
                span_s: float, seed: int = ENSEMBLE_SEED,
                widths: Mapping[str, float] | None = None) -> dict[str, Any]:  # fmt: skip
    """``run`` (a member's values by block -> its horizon [s]) on :func:`block_draws`; the members' horizons and
    :func:`horizon_interval`."""
    draws = block_draws(blocks, size, seed, widths)
    members = [float(run({name: d[i] for name, d in draws.items()})) for i in range(size)]
    return {**horizon_interval(members, span_s), "members_s": members}


# --- the FMU runs ---------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Setting:
    """Everything a prediction of the budget needs: the record, the main start, values and the span."""

    runner: FmuRunner
    rec: Reconstruction
    i0: int
    n_frames: int
    values: Mapping[str, Any]
    main: StartStateFit
    window_frames: int

    @property
    def span_s(self) -> float:
        return (self.n_frames - 1) * self.rec.track.dt

    def horizon(self, values: Mapping[str, Any], state: np.ndarray, geometry: Mapping[str, float]) -> dict[str, Any]:
        """The lower bob's smoothed 5 cm horizon of one run (:func:`~.comparison.headline_horizon`) and its RMS
        error [m] over the whole prediction."""
        p = predict(self.runner, "budget", values, state, self.rec, self.i0, self.n_frames, geometry)
        h = headline_horizon(p, self.span_s)
        return {"horizon_s": h["horizon_s"], "censored": h["censored"],
                "rms_error_m": float(np.sqrt(np.mean(p.e2**2)))}  # fmt: skip

    def refit(self, values: Mapping[str, Any], frames: int | None = None) -> StartStateFit:
        """The start and geometry fitted again with ``values`` (over ``frames``, default the main window), from
        the main fit."""
        return least_squares_start(self.runner, self.rec, self.i0, values, frames or self.window_frames,
                                   FREE_GEOMETRY, warm=self.main)  # fmt: skip


def _rods(values: Mapping[str, Any], member_kg: float) -> dict[str, Any]:
    return {**values, "m_rod1": member_kg, "m_rod2": member_kg}


def rod_profile(s: Setting, masses: Sequence[float] = ROD_MEMBER_KG,
                ) -> tuple[dict[str, Any], dict[float, StartStateFit]]:  # fmt: skip
    """The start and geometry fitted at each rod member's mass of ``masses`` [kg] (both members, the main fit at
    the values' own), chi2 of each fit, its prediction's horizon and whole-record RMS error; the parabola through
    chi2's lowest three points (:func:`profile_minimum`); and the fits by mass."""
    rows, fits = [], {}
    for m in masses:
        fit = s.main if m == s.values["m_rod1"] == s.values["m_rod2"] else s.refit(_rods(s.values, m))
        fits[m] = fit
        rows.append({"member_kg": m, "chi2": fit.chi2, "chi2_red": fit.chi2_red, "rms_residual_m": fit.rms_residual,
                     "geometry": dict(fit.geometry), **s.horizon(_rods(s.values, m), fit.state, fit.geometry)})
    masses_kg = [r["member_kg"] for r in rows]
    record = profile_minimum(masses_kg, [r["rms_error_m"] for r in rows], 1.0)
    return {"rows": rows, **profile_minimum(masses_kg, [r["chi2"] for r in rows], s.main.chi2_red),
            "record_rms_lowest_at_kg": record["lowest_at"], "record_rms_best_kg": record["best"]}, fits


def profile_minimum(x: Sequence[float], chi2: Sequence[float], chi2_red: float) -> dict[str, Any]:
    """Where a chi2 profile is lowest: a parabola through the lowest point and its neighbours; its minimum and the
    two points where it exceeds the minimum by ``chi2_red`` (one standard error with the errors scaled by the fit's
    own chi2_red). None where the parabola opens downwards or the lowest point is at the grid's end (then the record
    bounds the parameter on one side at most: ``at_edge``)."""
    x, c = np.asarray(x, dtype=float), np.asarray(chi2, dtype=float)
    k = int(np.argmin(c))
    out: dict[str, Any] = {"lowest_at": float(x[k]), "at_edge": k in (0, len(x) - 1),
                           "delta_chi2_over_chi2_red": ((c - c[k]) / chi2_red).tolist()}  # fmt: skip
    if out["at_edge"]:
        return {**out, "best": None, "stderr": None}
    a, b, _ = np.polyfit(x[k - 1:k + 2], c[k - 1:k + 2], 2)
    if a <= 0:
        return {**out, "best": None, "stderr": None}
    return {**out, "best": float(-b / (2 * a)), "stderr": float(np.sqrt(chi2_red / a))}


def one_at_a_time(s: Setting, rods: Mapping[float, StartStateFit] | None, loss_model: str, theta: np.ndarray,
                  theta_cov: np.ndarray, theta_names: Sequence[str], l1_stderr: float,
                  dt: float) -> tuple[list[dict[str, Any]], dict[str, StartStateFit]]:  # fmt: skip
    """Each input at its two values, the others held (module docstring): a row per input with the horizons [s]
    at the low and the high value and what they are; the refits by name (``l1-``, ``l1+``). ``rods``: the fits at
    the ends of :data:`ROD_RANGE_KG` (None: no rods' row)."""
    base = s.horizon(s.values, s.main.state, s.main.geometry)
    rows = []
    if rods is not None:
        lo_m, hi_m = ROD_RANGE_KG
        rows.append({"input": "rods' mass, each member", "low": f"{1e3 * lo_m:.0f} g", "high": f"{1e3 * hi_m:.0f} g",
                     "kind": "the seed's 70 +- 30 g", "low_s": _h(s, _rods(s.values, lo_m), rods[lo_m]),
                     "high_s": _h(s, _rods(s.values, hi_m), rods[hi_m])})  # fmt: skip
    windows = [s.refit(s.values, max(4, round(w / dt))) for w in WINDOWS_S]
    rows.append({"input": "start-fit window", "low": f"{WINDOWS_S[0]:g} s", "high": f"{WINDOWS_S[1]:g} s",
                 "kind": "a choice (1.5 s used)", "low_s": _h(s, s.values, windows[0]),
                 "high_s": _h(s, s.values, windows[1])})  # fmt: skip
    refits = {}
    for sign in (-1, 1):
        values = {**s.values, "l1": s.values["l1"] + sign * l1_stderr}
        refits[f"l1{'-+'[sign > 0]}"] = s.refit(values)
    rows.append({"input": "l1", "low": f"-{1e3 * l1_stderr:.2f} mm", "high": f"+{1e3 * l1_stderr:.2f} mm",
                 "kind": "+-1 standard error of the circle fit",
                 "low_s": _h(s, {**s.values, "l1": s.values["l1"] - l1_stderr}, refits["l1-"]),
                 "high_s": _h(s, {**s.values, "l1": s.values["l1"] + l1_stderr}, refits["l1+"])})  # fmt: skip
    return ranked(s, [*rows, *loss_rows(s, loss_model, theta, theta_cov, theta_names)], base), refits


def loss_rows(s: Setting, loss_model: str, theta: np.ndarray, theta_cov: np.ndarray,
              theta_names: Sequence[str]) -> list[dict[str, Any]]:  # fmt: skip
    """A row per loss coefficient: the horizons [s] with it at -+1 standard error and the others moved along their
    correlation with it (module docstring), the start and geometry kept."""
    cov, rows = np.asarray(theta_cov, dtype=float), []
    for j, name in enumerate(theta_names):
        if cov[j, j] <= 0:
            continue
        step = cov[:, j] / np.sqrt(cov[j, j])  # theta_j by one sigma, the others along their correlation
        ends = [_h(s, {**s.values, **loss_values(loss_model, np.asarray(theta) + sign * step)}, s.main)
                for sign in (-1, 1)]  # fmt: skip
        rows.append({"input": f"loss {name}", "low": "-1 sigma", "high": "+1 sigma",
                     "kind": "+-1 standard error of the energy fit", "low_s": ends[0], "high_s": ends[1]})
    return rows


def ranked(s: Setting, rows: list[dict[str, Any]], base: Mapping[str, Any] | None = None) -> list[dict[str, Any]]:
    """``rows`` with the main run's horizon [s] and each row's larger change from it [s], largest first."""
    base_s = (base or s.horizon(s.values, s.main.state, s.main.geometry))["horizon_s"]
    for r in rows:
        r["base_s"] = base_s
        r["largest_change_s"] = max(abs(r["low_s"] - base_s), abs(r["high_s"] - base_s))
    return sorted(rows, key=lambda r: -r["largest_change_s"])


def _h(s: Setting, values: Mapping[str, Any], fit: StartStateFit) -> float:
    return s.horizon(values, fit.state, fit.geometry)["horizon_s"]


def fmu_blocks(s: Setting, theta: np.ndarray, theta_cov: np.ndarray, rods_stderr: float | None,
               l1_stderr: float | None) -> dict[str, Block]:  # fmt: skip
    """The input blocks of the FMU's Monte Carlo: the start and geometry (deviations from the main fit, its
    covariance), the losses, and where given the rods' member mass [kg] and l1 [m] with their standard errors."""
    blocks = {"start and geometry": Block(s.main.names, np.zeros(len(s.main.names)), s.main.covariance),
              "losses": Block(tuple(f"theta{j}" for j in range(len(theta))), np.asarray(theta), theta_cov)}
    if rods_stderr is not None:
        blocks["rods"] = Block(("member_kg",), np.array([s.values["m_rod1"]]), np.array([[rods_stderr**2]]))
    if l1_stderr is not None:
        blocks["l1"] = Block(("l1",), np.array([s.values["l1"]]), np.array([[l1_stderr**2]]))
    return blocks


def fmu_member(s: Setting, loss_model: str, response: Mapping[str, np.ndarray]) -> Callable[[Mapping], float]:
    """One Monte Carlo run (:func:`monte_carlo`'s ``run``): the member's rods, l1 and losses, its start and geometry
    the main fit's moved by ``response`` (d(start, geometry)/d input, per unit of the rods' member mass [kg] and of
    l1 [m]) and its own draw; returns the smoothed 5 cm horizon [s]."""
    base = s.main.values

    def run(x: Mapping[str, np.ndarray]) -> float:
        values = {**s.values, **loss_values(loss_model, x["losses"])}
        shift = np.array(x["start and geometry"], dtype=float)
        if "rods" in x:
            member = max(float(x["rods"][0]), 0.0)
            values = _rods(values, member)
            shift = shift + response["rods"] * (member - s.values["m_rod1"])
        if "l1" in x:
            values["l1"] = float(x["l1"][0])
            shift = shift + response["l1"] * (values["l1"] - s.values["l1"])
        v = base + shift
        return s.horizon(values, v[:4], dict(zip(s.main.names[4:], map(float, v[4:]))))["horizon_s"]

    return run


def horizon_budget(s: Setting, loss_model: str, theta: np.ndarray, theta_cov: np.ndarray,
                   theta_names: Sequence[str], l1_stderr: float, *, rods: bool = True,
                   quick: bool = False) -> dict[str, Any]:  # fmt: skip
    """What moves the horizon (:func:`one_at_a_time`) and its distribution over every input (:func:`monte_carlo`),
    cached (``horizon_budget``); ``rods``: the rods' mass among the inputs (the seed's pendulum; a user's pendulum
    file states no uncertainty for its rods). Quick: a :data:`QUICK_ENSEMBLE_SIZE`-run ensemble over the start,
    geometry and losses alone and the losses one at a time (no refits: a smoke run)."""
    key = {"values": {k: v for k, v in s.values.items() if isinstance(v, (int, float, str, bool))},
           "t0": float(s.rec.t[s.i0]), "n_frames": s.n_frames, "dt": s.rec.track.dt,
           "main": s.main.values.tolist(), "cov": np.asarray(s.main.covariance).tolist(), "model": loss_model,
           "theta": np.asarray(theta).tolist(), "theta_cov": np.asarray(theta_cov).tolist(), "l1_stderr": l1_stderr,
           "window": s.window_frames, "quick": quick, "size": QUICK_ENSEMBLE_SIZE if quick else ENSEMBLE_SIZE,
           "seed": ENSEMBLE_SEED, "rods": ROD_MEMBER_KG if rods else None, "windows": WINDOWS_S}  # fmt: skip
    return cached("horizon_budget", key, lambda: _budget(s, loss_model, np.asarray(theta), np.asarray(theta_cov),
                                                         theta_names, l1_stderr, rods, quick))


def _budget(s: Setting, loss_model: str, theta: np.ndarray, theta_cov: np.ndarray, theta_names: Sequence[str],
            l1_stderr: float, with_rods: bool, quick: bool) -> dict[str, Any]:  # fmt: skip
    if quick:
        rows = ranked(s, loss_rows(s, loss_model, theta, theta_cov, theta_names))
        mc = monte_carlo(fmu_member(s, loss_model, {}), fmu_blocks(s, theta, theta_cov, None, None),
                         QUICK_ENSEMBLE_SIZE, s.span_s)
        return {"main_horizon_s": rows[0]["base_s"], "span_s": s.span_s, "one_at_a_time": rows, "rod_profile": None,
                "rods_stderr_kg": None, "rods_stderr_from": None, "l1_stderr_m": l1_stderr, "distribution": mc,
                "inputs_drawn": ["start and geometry", "losses"], "dominant_input": None, **_words()}  # fmt: skip
    profile, rods, rods_stderr = None, None, None
    response: dict[str, np.ndarray] = {}
    if with_rods:
        profile, rods = rod_profile(s, ROD_MEMBER_KG)
        lo, hi = ROD_RANGE_KG
        response["rods"] = (rods[hi].values - rods[lo].values) / (hi - lo)
        rods_stderr = ROD_STATED_STDERR_KG  # the record does not pin it: see rods_stderr_from
    rows, refits = one_at_a_time(s, rods, loss_model, theta, theta_cov, theta_names, l1_stderr, s.rec.track.dt)
    response["l1"] = (refits["l1+"].values - refits["l1-"].values) / (2 * l1_stderr)
    blocks = fmu_blocks(s, theta, theta_cov, rods_stderr, l1_stderr)
    mc = monte_carlo(fmu_member(s, loss_model, response), blocks, ENSEMBLE_SIZE, s.span_s)
    uncertain = [r for r in rows if r["input"] != "start-fit window"]
    return {"main_horizon_s": rows[0]["base_s"], "span_s": s.span_s, "one_at_a_time": rows, "rod_profile": profile,
            "rods_stderr_kg": rods_stderr, "rods_stderr_from": None if profile is None else _rods_words(profile),
            "l1_stderr_m": l1_stderr, "distribution": mc, "inputs_drawn": list(blocks),
            "dominant_input": max(uncertain, key=lambda r: r["largest_change_s"])["input"], **_words()}  # fmt: skip


def _rods_words(profile: Mapping[str, Any]) -> str:
    """Why the draws take the seed's stated +-30 g for the rods: what the window's profile and the whole record's
    motion each prefer."""
    window = ("no minimum within the masses tried" if profile["best"] is None
              else f"{1e3 * profile['best']:.0f} +- {1e3 * profile['stderr']:.0f} g")
    record = (f"{1e3 * profile['record_rms_best_kg']:.0f} g" if profile["record_rms_best_kg"] is not None
              else f"the end of the masses tried ({1e3 * profile['record_rms_lowest_at_kg']:.0f} g)")
    return (f"the seed's words (70 +- 30 g a member): the start-fit window's chi2 prefers {window}, the lower bob's "
            f"error over the whole record is lowest at {record} (in-sample, the losses fitted for 70 g); the record "
            "does not pin the rods' inertia, so the draws keep the stated range")


def _words() -> dict[str, Any]:
    """What the budget's numbers are and what its nulls mean."""
    return {
        "statement": "the lower bob's smoothed 5 cm horizon [s] of the main start (start and camera geometry fitted "
                     "to the start-fit window): one_at_a_time, each input at two values with the others held (the "
                     "start and geometry fitted again for the rods, l1 and the window); distribution, every input "
                     "drawn from its covariance at once. A horizon at span_s is censored (beyond the record). "
                     "In-sample.",
        "null_means": {
            "rod_profile": "not run: a quick run, or a user's pendulum (its file states no uncertainty of its rods)",
            "rods_stderr_kg": "the rods are not drawn (quick run or a user's pendulum)",
            "rods_stderr_from": "the rods are not drawn (quick run or a user's pendulum)",
            "dominant_input": "a quick run: only the losses are changed one at a time",
            "best": "the profile's lowest point lies at the end of the masses tried (or the parabola through it "
                    "opens downwards): the record bounds the mass on one side at most",
            "stderr": "no minimum inside the masses tried (see best)",
            "record_rms_best_kg": "the whole record's RMS error is lowest at the end of the masses tried",
        },
    }
