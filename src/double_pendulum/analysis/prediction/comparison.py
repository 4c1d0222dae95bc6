r"""FMU predictions of the measured track: runs from a start frame, position errors and horizons.

A prediction starts the FMU at the time :math:`t_0` of a valid frame ``i0`` from a state
:math:`(\varphi_1, \varphi_2, \omega_1, \omega_2)` and compares its bob positions with the track on
the valid frames after ``i0``. Positions are relative to the pivot fitted by the measurement (the
FMU's origin is the pivot's rest position). The position errors [m] are

.. math::

    e_1 = |r_1^{FMU} - r_1^{track}|, \qquad e_2 = |r_2^{FMU} - r_2^{track}|, \qquad
    e_{both} = \max(e_1, e_2),

and the prediction horizon for a threshold is the first time after :math:`t_0` at which an error
exceeds it (:func:`horizon`). The per-frame error carries the track's frame-to-frame jitter (the
distance between the bobs alone varies by about +-1 cm), so the headline horizons
(:meth:`Prediction.smoothed_horizons`, 2 cm and 5 cm) use the error smoothed by a centred moving
median over :data:`SMOOTHING_S` = 0.25 s (:func:`smoothed`); the raw horizons are kept beside them.

A start may be fitted together with free geometry (:func:`least_squares_start` with ``geometry``,
:data:`FREE_GEOMETRY`: the camera's rotation against gravity, the pivot's offset from the measurement's
circle-fit pivot and the lower rod's length l2); a prediction then runs with the fitted l2 and its
positions are turned and shifted by the fitted rotation and offset.
The losses are those of one of the models the ``loss_identification`` scenario finds equally supported
(:func:`identified_losses`; the others: :mod:`.loss_models`).

Two floors limit the horizon: the track's own rod-length error
:math:`\big|\,|r_2 - r_1| - l_2\big|` (:func:`rod_length_floor`), which no rigid-rod model can match,
and chaos, the spread of runs from start states drawn from the fitted start's covariance
(:func:`chaos_spread`). :func:`regime` tells regular from chaotic motion at the fitted start's
energy by the largest Lyapunov exponent.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ...model.parameters import SEED_RIGID_LINKS, PendulumParameters
from ..chaos import flips, lyapunov, lyapunov_study
from ..chaos.ensemble import batch_energy, initial_states, pendulum_field
from ..losses import comparison, fitting, identification, mechanisms
from ..suspension.identification import START_FIT_FRAMES
from ..sweep import runner_map
from ..track.measurement import FRAME_INTERVAL, Reconstruction
from ..track.start_state import (
    POSITION_OUTPUTS,
    STATE_NAMES,
    StartStateFit,
    fit_start_state,
    output_matrix,
    shift_outputs,
    simulate_frames,
    split_geometry,
    state_start_values,
    track_window,
)
from .summary_types import Goal, HeadlineHorizon, Regime, RodLengthFloor

THRESHOLDS_M = (0.02, 0.05)
"""Position errors [m] whose first crossing defines the prediction horizons (raw and smoothed)."""
SMOOTHING_S = 0.25
"""Width [s] of the centred moving median that smooths the per-frame error (about 7 frames)."""
FREE_GEOMETRY: tuple[str, ...] = ("view_rotation", "pivot_offset_x", "pivot_offset_y", "l2")
"""Geometry fitted with the start state: the camera's rotation against gravity [rad] (the FMU's positions
turned about the pivot), the pivot's offset [m] from the circle-fit pivot and l2 [m]. l1 is left at the
track's value: freed as well, it trades off against the pivot's height over a few swings."""
LOSS_MODEL = "air+drag"
"""The loss model of the predictions (air drag with a free factor on rho_air, a bearing drag torque at both joints),
obtained here as the ``loss_identification`` scenario obtains it (:func:`identified_losses`): one of the models that
scenario finds within delta AIC 2 of the lowest, not a verdict (two separate mechanisms, each with a physical
origin; :mod:`.loss_models` runs the main start with each of the others)."""
FIT_TOLERANCE = 1e-6
"""Relative stopping tolerance of the least-squares starts (scipy's ``ftol``, ``xtol``): on the seed's track the
start and geometry fit then ends after about half the FMU runs of scipy's 1e-8, with chi2 1e-7 (relative) and
the geometry < 1 um and < 1e-3 deg from that fit's, far inside their standard errors."""
PREDICTION_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-8, "atol": 1e-10}
"""Integration of the predictions and the ensemble runs: a 20 s run from the seed's fitted start stays within
2 um of the fits' tighter :data:`~double_pendulum.analysis.track.start_state.FIT_SETTINGS` (which only the
finite-difference Jacobian needs) at half the cost; the horizons are about centimetres."""
LYAPUNOV_RENORM_S = 0.1
"""Renormalisation interval [s] of the Lyapunov estimate (:func:`regime`)."""
LYAPUNOV_STEP_S = 2e-3
"""RK4 step [s] of the Lyapunov estimate (:func:`regime`; the step the ``chaos`` scenario's checks support)."""
REGULAR_DECAY = 0.5
"""The motion counts as regular if the running exponent at T has fallen below this fraction of its
value at T/4 (a tangent that grows linearly gives lambda(T) ~ ln(T)/T); a converging positive exponent stays near 1."""
ENSEMBLE_SEED = 20240611
"""Seed of the random start states of :func:`chaos_spread`."""
RUN_OUTPUTS: tuple[str, ...] = (*POSITION_OUTPUTS, "phi1", "phi2", "omega1", "omega2", "E_pendulum")
"""FMU outputs recorded for each prediction (positions [m], angles [rad], rates [rad/s], energy [J])."""
PIVOT_SHIFT_GEOMETRY: tuple[str, ...] = ("pivot_offset_x", "pivot_offset_y", "l2")
"""The alternative to the camera's rotation: the same fit without it (the pivot moves sideways instead)."""
RUN_TITLES = {
    "seed_start_frictionless": "seed's start, frictionless model",
    "seed_start_identified": "seed's start, fitted losses",
    "lsq_start_identified": "least-squares start (state only), fitted losses",
    "lsq_fixed_geometry_identified": "least-squares start over the geometry fit's window, geometry fixed",
    "lsq_pivot_shift_identified": "least-squares start, pivot offset and l2 (no rotation), fitted losses",
    "lsq_geometry_identified": "least-squares start and geometry, fitted losses",
}
"""Plain words for the prediction labels (which also name their CSV files) in figures."""


def run_title(label: str) -> str:
    """The plain-words title of a prediction ``label`` (:data:`RUN_TITLES`), else the label itself."""
    return RUN_TITLES.get(label, label.replace("_", " "))


ERROR_UNITS = {"t_since_t0": "s", "frame": "1", "x1": "m", "y1": "m", "x2": "m", "y2": "m", "rod2_deviation": "m"}
"""Units of :func:`errors_table`; the error columns ``e1_*``, ``e2_*`` are in m (:func:`errors_units`)."""


def horizon(t: np.ndarray, error: np.ndarray, threshold: float) -> float | None:
    """Time [s] of the first sample with ``error > threshold`` (0 if at once; None if never)."""
    above = np.flatnonzero(np.asarray(error) > threshold)
    return float(t[above[0]]) if len(above) else None


def smoothed(t: np.ndarray, error: np.ndarray, window_s: float = SMOOTHING_S) -> np.ndarray:
    """Centred moving median of ``error`` over the samples within +-``window_s``/2 [s] of each time ``t`` [s]
    (missing frames simply leave fewer samples; the window shrinks at the ends)."""
    t = np.asarray(t, dtype=float)
    error = np.asarray(error, dtype=float)
    lo = np.searchsorted(t, t - window_s / 2 - 1e-9, side="left")
    hi = np.searchsorted(t, t + window_s / 2 + 1e-9, side="right")
    return np.array([np.median(error[a:b]) for a, b in zip(lo, hi)])


def _horizons(
    t: np.ndarray, lower: np.ndarray, both: np.ndarray, thresholds: Sequence[float]
) -> dict[str, float | None]:
    """:func:`horizon` of the lower bob's and both bobs' errors [m] per threshold, keyed as :func:`horizon_keys`."""
    out = {}
    for th in thresholds:
        out[f"lower_bob_{100 * th:g}cm_s"] = horizon(t, lower, th)
        out[f"both_bobs_{100 * th:g}cm_s"] = horizon(t, both, th)
    return out


def headline_horizon(prediction: Prediction, span_s: float, threshold: float = 0.05) -> HeadlineHorizon:
    """The lower bob's smoothed horizon at ``threshold`` [m] as a claim: ``horizon_s`` [s] (the prediction's
    length ``span_s`` if never exceeded), ``censored`` (True then: the horizon is only known to exceed the
    record), the largest smoothed error [m] and when [s], the margin below the threshold [m] and the first
    crossing of the raw per-frame error [s] (None: never)."""
    e2 = smoothed(prediction.t, prediction.e2)
    value = horizon(prediction.t, e2, threshold)
    peak = int(np.argmax(e2))
    return {"horizon_s": span_s if value is None else value, "censored": value is None,
            "smoothed_error_peak_m": float(e2[peak]), "smoothed_error_peak_at_s": float(prediction.t[peak]),
            "margin_below_threshold_m": threshold - float(e2[peak]),
            "raw_horizon_s": horizon(prediction.t, prediction.e2, threshold)}


def horizon_keys(thresholds: Sequence[float] = THRESHOLDS_M) -> list[str]:
    """Summary keys of the horizons per threshold: ``lower_bob_2cm_s``, ``both_bobs_2cm_s``, ..."""
    return [f"{bob}_{100 * th:g}cm_s" for th in thresholds for bob in ("lower_bob", "both_bobs")]


@dataclass(frozen=True, eq=False)
class Prediction:
    """One FMU run from t0 compared with the track on its valid frames.

    ``t`` [s] since t0; errors [m] of the upper bob ``e1``, the lower bob ``e2`` and both (the larger);
    ``geometry``: the fitted geometry it ran with (start values and pivot shifts [m]).
    """

    label: str
    state: np.ndarray
    result: np.ndarray
    t: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    geometry: Mapping[str, float] = field(default_factory=dict)

    @property
    def e_both(self) -> np.ndarray:
        """max(e1, e2) [m] per frame: the error of the worse bob."""
        return np.maximum(self.e1, self.e2)

    def horizons(self, thresholds: Sequence[float] = THRESHOLDS_M) -> dict[str, float | None]:
        """First time [s] after t0 the lower bob's / both bobs' error exceeds each threshold (None: never)."""
        return _horizons(self.t, self.e2, self.e_both, thresholds)

    def smoothed_horizons(
        self, thresholds: Sequence[float] = THRESHOLDS_M, window_s: float = SMOOTHING_S
    ) -> dict[str, float | None]:
        """As :meth:`horizons` on the errors smoothed by :func:`smoothed` over ``window_s`` [s]."""
        e2, both = smoothed(self.t, self.e2, window_s), smoothed(self.t, self.e_both, window_s)
        return _horizons(self.t, e2, both, thresholds)

    def rms_lower_bob_error(self, until_s: float) -> float:
        """sqrt(mean(e2^2)) [m] over the frames with t <= ``until_s`` [s] after t0."""
        return float(np.sqrt(np.mean(self.e2[self.t <= until_s] ** 2)))


# --- start frame and start states -----------------------------------------------------------------


def nearest_frame(rec: Reconstruction, t0: float) -> int:
    """Index of the valid frame whose time is nearest to ``t0`` [s] and whose rates are defined."""
    ok = rec.track.valid & np.isfinite(rec.omega1) & np.isfinite(rec.omega2)
    idx = np.flatnonzero(ok)
    return int(idx[np.argmin(np.abs(rec.t[idx] - t0))])


def reconstructed_state(rec: Reconstruction, i0: int) -> np.ndarray:
    """The seed's kind of start: angles [rad] and Savitzky-Golay rates [rad/s] of frame ``i0``."""
    return np.array([rec.phi1[i0], rec.phi2[i0], rec.omega1[i0], rec.omega2[i0]])


@dataclass(frozen=True, eq=False)
class IdentifiedLosses:
    """The loss model fitted to the measured energy decay: FMU start values of the pendulum (rods) and
    losses, the parameter table (value, stderr, unit), the record fitted [s] and the FMU runs it took."""

    model: str
    pendulum: dict[str, Any]
    losses: dict[str, Any]
    parameters: dict[str, dict[str, Any]]
    record_s: float
    n_runs: int
    t0_s: float = 0.0
    """Start [s] of the fitted record: the end of the release (the energy's first maximum)."""

    @property
    def values(self) -> dict[str, Any]:
        """Every FMU start value except the state: pendulum, losses and the friction regularisation."""
        return {**self.pendulum, **self.losses, "omega_reg": mechanisms.OMEGA_REG}


def identified_losses(rec: Reconstruction, window_s: float | None = None, *, quick: bool = False) -> IdentifiedLosses:
    """Fit :data:`LOSS_MODEL` to the measured energy decay of ``rec`` (a reconstruction, with rods where it has them),
    in-process, the way the ``loss_identification`` scenario's run in the same mode (``quick``) fits it
    (:func:`~double_pendulum.analysis.losses.identification.identified_fit`: the same start, run budget and
    integration settings, so the cached fit of either scenario serves the other); ``window_s``: only the
    first seconds after the release (None: the whole record)."""
    md = identification.measured(rec, window_s)
    problem = fitting.problem_from_track(rec, md, quick=quick)
    fit = fitting.identified_fit(LOSS_MODEL, problem, quick=quick)
    factor = comparison.common_factor(problem)
    pendulum = {k: problem.base[k] for k in ("l1", "l2", "m1", "m2", *SEED_RIGID_LINKS)}
    return IdentifiedLosses(
        model=LOSS_MODEL,
        pendulum=pendulum,
        losses=mechanisms.model_values(LOSS_MODEL, fit.theta),
        parameters=comparison.parameter_table(fit, factor),
        record_s=float(problem.t[-1] - problem.t[0]),
        n_runs=fit.n_runs,
        t0_s=float(problem.t0),
    )


def least_squares_start(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    values: Mapping[str, Any],
    n_frames: int = START_FIT_FRAMES,
    geometry: Sequence[str] = (),
    warm: StartStateFit | None = None,
    tolerance: float = FIT_TOLERANCE,
) -> StartStateFit:
    """Start state at frame ``i0`` (and the free ``geometry``, e.g. :data:`FREE_GEOMETRY`) fitted to the
    positions of ``n_frames`` frames, from the reconstruction (pivot offsets from 0, lengths from ``values``);
    ``tolerance``: the iteration's relative stopping tolerance on chi2 and the parameters."""
    w = track_window(rec, i0, n_frames)
    guess, geometry_guess = (w.guess, None) if warm is None else (warm.state, warm.geometry)
    return fit_start_state(runner, w.t0, w.offsets, w.positions, w.sigma_positions, guess, values, dt=rec.track.dt,
                           geometry=geometry, geometry_guess=geometry_guess, tolerance=tolerance)


def start_fit_summary(fit: StartStateFit, guess: np.ndarray) -> dict[str, Any]:
    """The fit as a dictionary plus its change from ``guess`` (rad, rad, rad/s, rad/s)."""
    return {**fit.as_dict(), "change_from_reconstruction": dict(zip(STATE_NAMES, (fit.state - guess).tolist()))}


# --- predictions ---------------------------------------------------------------------------------


def prediction_start_values(values: Mapping[str, Any], state: Sequence[float],
                            geometry: Mapping[str, float] | None = None) -> dict[str, Any]:  # fmt: skip
    """The FMU start values of a prediction (:func:`predict`): :data:`PREDICTION_SETTINGS`, ``values``, the fitted
    geometry's start values (e.g. l2 [m]; not its position transforms) and the ``state`` (rad, rad, rad/s,
    rad/s)."""
    start, _ = split_geometry(dict(geometry or {}))
    return {**PREDICTION_SETTINGS, **values, **start, **state_start_values(state)}


def predict(
    runner: FmuRunner,
    label: str,
    values: Mapping[str, Any],
    state: np.ndarray,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
    geometry: Mapping[str, float] | None = None,
) -> Prediction:
    """Run the FMU from frame ``i0`` with ``state`` for ``n_frames`` frames and compare with the track;
    ``geometry`` (fitted start values such as l2 and pivot shifts [m]) overrides ``values`` and moves the positions."""
    geometry = dict(geometry or {})
    _, shifts = split_geometry(geometry)
    result = simulate_frames(
        runner,
        prediction_start_values(values, state, geometry),
        float(rec.t[i0]),
        n_frames,
        dt=rec.track.dt,
        outputs=RUN_OUTPUTS,
    )
    window = track_window(rec, i0, n_frames)
    d = shift_outputs(output_matrix(result), POSITION_OUTPUTS, shifts)[window.offsets] - window.positions
    return Prediction(
        label=label,
        state=np.asarray(state, dtype=float),
        result=result,
        t=window.offsets * rec.track.dt,
        e1=np.hypot(d[:, 0], d[:, 1]),
        e2=np.hypot(d[:, 2], d[:, 3]),
        geometry=geometry,
    )


def chaos_spread(
    runner: FmuRunner,
    values: Mapping[str, Any],
    fit: StartStateFit,
    central: Prediction,
    n_frames: int,
    size: int,
    seed: int = ENSEMBLE_SEED,
    max_workers: int | None = 1,
    dt: float = FRAME_INTERVAL,
) -> tuple[np.ndarray, np.ndarray]:
    """Median distance [m] of the lower bob between runs drawn from the fit's covariance (state and
    any fitted geometry) and the central run, per frame (times [s] since t0, frames ``dt`` [s] apart): how fast the
    fit's own uncertainty grows. ``max_workers``: worker processes (1: here, with ``runner``; a few runs of about a
    second each cost less than starting workers; None: one per core)."""
    rng = np.random.default_rng(seed)
    draws = rng.multivariate_normal(fit.values, fit.covariance, size=size)
    _, central_shifts = split_geometry(central.geometry)
    ref = shift_outputs(output_matrix(central.result), POSITION_OUTPUTS, central_shifts)[:, 2:]
    items = []
    for x in draws:
        start, shifts = split_geometry(dict(zip(fit.names[4:], x[4:])))
        start_values = {**PREDICTION_SETTINGS, **values, **start, **state_start_values(x[:4])}
        items.append((start_values, shifts, fit.t0, n_frames, ref, dt))
    distances = runner_map(_spread_distance, items, runner, max_workers=max_workers, label="start-state ensemble")
    return np.arange(n_frames) * dt, np.median(np.array(distances), axis=0)


def _spread_distance(runner: FmuRunner,
                     item: tuple[dict[str, Any], dict[str, float], float, int, np.ndarray, float]):  # fmt: skip
    """Worker: the lower bob's distance [m] per frame of one ensemble run from the central prediction."""
    start, shifts, t0, n_frames, ref, dt = item
    r = simulate_frames(runner, start, t0, n_frames, dt=dt)
    return np.linalg.norm(shift_outputs(output_matrix(r), POSITION_OUTPUTS, shifts)[:, 2:] - ref, axis=1)


def chaos_horizons(spread: tuple[np.ndarray, np.ndarray]) -> dict[str, float | None]:
    """First time [s] the ensemble's spread of the lower bob exceeds each of :data:`THRESHOLDS_M`, keyed like
    ``lower_bob_2cm_s`` (None: not within the prediction window, see :func:`null_means`)."""
    return {f"lower_bob_{100 * th:g}cm_s": horizon(*spread, th) for th in THRESHOLDS_M}


def null_means(prediction_s: float) -> dict[str, str]:
    """What a null horizon in the summary means, by summary key."""
    never = f"the error or spread did not exceed the threshold within the {prediction_s:.1f} s prediction window"
    return {"horizons_smoothed_s": never, "horizons_raw_s": never, "chaos_horizons_s": never,
            "fit_window_sensitivity": never, "horizon_5cm_details": never}


def window_sensitivity(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    values: Mapping[str, Any],
    n_frames: int,
    windows: Sequence[int],
    geometry: Sequence[str] = FREE_GEOMETRY,
    warm: StartStateFit | None = None,
) -> list[dict[str, Any]]:
    """Smoothed horizons of least-squares starts (with the free ``geometry``) fitted to other numbers of frames,
    each started from the fit ``warm`` if given (fewer iterations), else from the reconstruction."""
    items = [(rec, i0, dict(values), n_frames, frames, tuple(geometry), warm) for frames in windows]
    return runner_map(_window_fit, items, runner, label="fit windows", unit="fit")


def _window_fit(runner: FmuRunner, item: tuple[Any, ...]) -> dict[str, Any]:
    """Worker: the least-squares start fitted to ``frames`` frames, its geometry and its prediction's horizons."""
    rec, i0, values, n_frames, frames, geometry, warm = item
    fit = least_squares_start(runner, rec, i0, values, frames, geometry, warm)
    p = predict(runner, f"lsq{frames}", values, fit.state, rec, i0, n_frames, fit.geometry)
    return {"fit_frames": frames, "fit_window_s": frames * rec.track.dt, "chi2_red": fit.chi2_red,
            "rms_residual_m": fit.rms_residual, "geometry": dict(fit.geometry),
            "geometry_units": fit.as_dict()["geometry_units"], **p.smoothed_horizons()}


# --- the regime ----------------------------------------------------------------------------------


def regime(params: PendulumParameters, state: Sequence[float], t_end: float) -> Regime:
    """Regular or chaotic at the energy of ``state`` (frictionless ``params``, rods included)?

    The largest Lyapunov exponent by Benettin's method
    (:func:`~double_pendulum.analysis.chaos.lyapunov.lyapunov_benettin`, RK4 at :data:`LYAPUNOV_STEP_S`,
    renormalised every :data:`LYAPUNOV_RENORM_S`) over ``t_end`` [s]; the motion is called regular if the running
    exponent at T = ``t_end`` has fallen below :data:`REGULAR_DECAY` of its value at T/4 (the ln(T)/T decay of a tangent
    that grows linearly), chaotic otherwise. The energy is
    compared with the least energy that lets the lower rod flip, V(0, pi).
    """
    y0 = initial_states(*state)
    res = lyapunov.lyapunov_benettin(pendulum_field(params), y0, t_end, renorm_interval=LYAPUNOV_RENORM_S,
                                  integration=lyapunov.Integration("rk4", h=LYAPUNOV_STEP_S))
    running = res.running[:, 0, 0]
    quarter = float(running[np.argmin(np.abs(res.times - t_end / 4))])
    final = float(running[-1])
    regular = final < REGULAR_DECAY * quarter or final <= 0.0
    energy = float(batch_energy(y0, params)[0])
    e_flip = flips.flip_energy_bounds(params)[1]
    return {
        "verdict": "regular" if regular else "chaotic",
        "largest_lyapunov_exponent_per_s": final,
        "averaging_time_s": float(res.times[-1]),
        "exponent_at_quarter_time_per_s": quarter,
        "checkpoints": lyapunov_study.convergence_checkpoints(res.times, running),
        "energy_J": energy,
        "lower_rod_flip_energy_J": e_flip,
        "energy_over_flip_energy": energy / e_flip,
        "method": (f"Benettin, frictionless, rods included, RK4 h = {1e3 * LYAPUNOV_STEP_S:g} ms, "
                   f"renormalised every {LYAPUNOV_RENORM_S:g} s; "
                   f"regular if lambda(T) < {REGULAR_DECAY:g} lambda(T/4)"),
    }


# --- the track's floor ---------------------------------------------------------------------------


def _signed_rod2_deviation(rec: Reconstruction, i0: int, n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets of the valid frames after ``i0`` and |r2 - r1| - l2 [m] on them."""
    w = track_window(rec, i0, n_frames)
    p = w.positions
    return w.offsets, np.hypot(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]) - rec.params.l2


def rod_length_floor(rec: Reconstruction, i0: int, n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """| |r2 - r1| - l2 | [m] of the track on the valid frames after ``i0``: what no rigid-rod model can match.

    Returns the times [s] since frame ``i0`` and the deviations.
    """
    offsets, signed = _signed_rod2_deviation(rec, i0, n_frames)
    return offsets * rec.track.dt, np.abs(signed)


def rod_floor_summary(rec: Reconstruction, i0: int, n_frames: int) -> RodLengthFloor:
    """Size of the track's rod-length error and its correlation with the lower rod's rate squared.

    The signed deviation |r2 - r1| - l2 is correlated with omega2^2 (Savitzky-Golay rates): a
    negative coefficient means the bobs appear closer together the faster the lower rod turns.
    """
    offsets, signed = _signed_rod2_deviation(rec, i0, n_frames)
    w2 = rec.omega2[i0 + offsets] ** 2
    ok = np.isfinite(w2)
    return {
        "rms_m": float(np.sqrt(np.mean(signed**2))),
        "max_m": float(np.max(np.abs(signed))),
        "fraction_above_1cm": float(np.mean(np.abs(signed) > 0.01)),
        "correlation_with_omega2_squared": float(np.corrcoef(signed[ok], w2[ok])[0, 1]),
    }


# --- tables and plot data --------------------------------------------------------------------------


def model_summary(losses: IdentifiedLosses) -> dict[str, Any]:
    """The predicting model: lengths [m], bob and rod masses [kg], plate lengths [m], the fitted losses."""
    p = losses.pendulum
    return {
        "lengths_m": {"l1": p["l1"], "l2": p["l2"]},
        "bob_masses_kg": p["m1"] + p["m2"],
        "rods": {k: p[k] for k in SEED_RIGID_LINKS},
        "loss_model": losses.model,
        "loss_parameters": losses.parameters,
        "loss_fit_record_s": losses.record_s,
        "loss_fit_runs": losses.n_runs,
    }


def errors_units(predictions: Sequence[Prediction]) -> dict[str, str]:
    """Units of :func:`errors_table` for these predictions."""
    return {**ERROR_UNITS, **{f"e{j}_{p.label}": "m" for p in predictions for j in (1, 2)}}


def errors_table(rec: Reconstruction, i0: int, n_frames: int, predictions: Sequence[Prediction]) -> np.ndarray:
    """Per valid frame: the track (its own coordinates), the rod-length deviation and each run's errors [m]."""
    w = track_window(rec, i0, n_frames)
    idx = i0 + w.offsets
    t_rel, dev = rod_length_floor(rec, i0, n_frames)
    columns: dict[str, np.ndarray] = {
        "time": rec.t[idx],
        "t_since_t0": t_rel,
        "frame": rec.track.frame[idx],
        "x1": rec.track.x1[idx],
        "y1": rec.track.y1[idx],
        "x2": rec.track.x2[idx],
        "y2": rec.track.y2[idx],
        "rod2_deviation": dev,
    }
    for p in predictions:
        columns[f"e1_{p.label}"] = p.e1
        columns[f"e2_{p.label}"] = p.e2
    arrays = [np.asarray(v, dtype=float) for v in columns.values()]
    return np.rec.fromarrays(arrays, names=list(columns)).view(np.ndarray)


def measured_coordinates(
    rec: Reconstruction, i0: int, n_frames: int, lead: int = 10
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Times [s] and track coordinates x1, y1, x2, y2 [m] (the track's own origin) of the valid frames
    from ``lead`` frames before ``i0`` to the end of the prediction."""
    lo = max(0, i0 - lead)
    hi = min(len(rec.t), i0 + n_frames)
    v = np.zeros(len(rec.t), dtype=bool)
    v[lo:hi] = rec.track.valid[lo:hi]
    track = rec.track
    return rec.t[v], {"x1": track.x1[v], "y1": track.y1[v], "x2": track.x2[v], "y2": track.y2[v]}


def simulated_coordinates(rec: Reconstruction, prediction: Prediction) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Times [s] and the FMU's bob coordinates [m] moved into the track's coordinates: turned and shifted
    by the prediction's own fitted geometry (if any), then shifted by the measurement's circle-fit pivot."""
    pivot = rec.geometry.pivot
    _, transforms = split_geometry(prediction.geometry)
    moved = shift_outputs(output_matrix(prediction.result), POSITION_OUTPUTS, transforms)
    origin = {"x1": pivot.xc, "y1": pivot.yc, "x2": pivot.xc, "y2": pivot.yc}
    return np.asarray(prediction.result["time"]), {n: moved[:, i] + origin[n] for i, n in enumerate(POSITION_OUTPUTS)}


@dataclass(frozen=True)
class ErrorCurves:
    """The curves of the error plot, times [s] since t0 and errors [m]: each run's lower-bob error smoothed by
    :func:`smoothed` (by run title, in the runs' order), the main (last) run's per-frame error, the spread."""

    smoothed: dict[str, tuple[np.ndarray, np.ndarray]]
    per_frame: tuple[str, np.ndarray, np.ndarray]
    spread: tuple[np.ndarray, np.ndarray]


def error_curves(predictions: Sequence[Prediction], spread: tuple[np.ndarray, np.ndarray]) -> ErrorCurves:
    """:class:`ErrorCurves` of ``predictions`` (the main run last) and the ensemble ``spread``."""
    main = predictions[-1]
    return ErrorCurves({run_title(p.label): (p.t, smoothed(p.t, p.e2)) for p in predictions},
                       (run_title(main.label), main.t, main.e2), spread)


def headline_entries(headlines: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """The summary's headline horizons: the lower bob's smoothed 5 cm horizon of the least-squares start with
    geometry, with fixed geometry and with a pivot shift (``headlines`` by run label, from
    :func:`headline_horizon`), whether each is censored, and what they mean."""
    entries: dict[str, Any] = {}
    for suffix, label in (("", "lsq_geometry_identified"), ("_fixed_geometry", "lsq_fixed_geometry_identified"),
                          ("_pivot_shift", "lsq_pivot_shift_identified")):  # fmt: skip
        entries[f"horizon_5cm_s{suffix}"] = headlines[label]["horizon_s"]
        entries[f"horizon_5cm_censored{suffix}"] = headlines[label]["censored"]
    entries["horizon_5cm_details"] = headlines
    entries["horizon_statement"] = (
        "lower bob, smoothed error, 5 cm; censored: never exceeded within the record, so the horizon is only known "
        "to exceed the record's length. In-sample: the losses are fitted to the same record. The motion is regular, "
        "so a horizon measures how well frequencies and damping match, not predictability."
    )
    return entries


def goal_entry(reached: float | None, prediction_s: float, goal_s: float) -> Goal:
    """The goal: the lower bob's smoothed error below 5 cm for at least ``goal_s`` [s] after t0 (least-squares
    start and geometry); ``reached`` [s] is None where the error never exceeded 5 cm within ``prediction_s``."""
    return {
        "statement": f"the lower bob's smoothed error stays below 5 cm for at least {goal_s:g} s after t0, "
                     "least-squares start and geometry",
        "required_s": goal_s,
        "reached_s": prediction_s if reached is None else reached,
        "reached_is_lower_bound": reached is None,
        "met": bool(reached is None or reached >= goal_s),
    }
