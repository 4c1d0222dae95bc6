r"""FMU predictions of the measured track: runs from a start frame, position errors and horizons.

A prediction starts the FMU at the time :math:`t_0` of a valid frame ``i0`` from a state
:math:`(\varphi_1, \varphi_2, \omega_1, \omega_2)` and compares its bob positions with the track on
the valid frames after ``i0``. Positions are relative to the pivot fitted by the measurement (the
FMU's origin is the pivot's rest position). The position errors [m] are

.. math::

    e_1 = |r_1^{FMU} - r_1^{track}|, \qquad e_2 = |r_2^{FMU} - r_2^{track}|, \qquad
    e_{both} = \max(e_1, e_2),

and the prediction horizon for a threshold is the first time after :math:`t_0` at which an error
exceeds it (:func:`horizon`). Two floors limit it: the track's own rod-length error
:math:`\big|\,|r_2 - r_1| - l_2\big|` (:func:`rod_length_floor`), which no rigid-rod model can match,
and chaos, the spread of runs from start states drawn from the fitted start's covariance
(:func:`chaos_spread`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..fmu.runner import FmuRunner
from .measurement import FRAME_INTERVAL, Reconstruction
from .start_state import (
    FIT_SETTINGS,
    POSITION_OUTPUTS,
    STATE_NAMES,
    StartStateFit,
    fit_start_state,
    output_matrix,
    simulate_frames,
    state_start_values,
    track_window,
)
from .suspension_identification import START_FIT_FRAMES, Identification, IdentifiedModel
from .sweep import runner_map

THRESHOLDS_M = (0.01, 0.05)
"""Position errors [m] whose first crossing defines the prediction horizons."""
ENSEMBLE_SEED = 20240611
"""Seed of the random start states of :func:`chaos_spread`."""
RUN_OUTPUTS: tuple[str, ...] = (*POSITION_OUTPUTS, "phi1", "phi2", "omega1", "omega2", "E_pendulum")
"""FMU outputs recorded for each prediction (positions [m], angles [rad], rates [rad/s], energy [J])."""
RUN_TITLES = {
    "seed_start_frictionless": "seed's start, frictionless model",
    "seed_start_identified": "seed's start, identified model (losses, suspension)",
    "lsq_start_identified": "least-squares start, identified model",
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


@dataclass(frozen=True, eq=False)
class Prediction:
    """One FMU run from t0 compared with the track on its valid frames.

    ``t`` [s] since t0; errors [m] of the upper bob ``e1``, the lower bob ``e2`` and both (the larger).
    """

    label: str
    state: np.ndarray
    result: np.ndarray
    t: np.ndarray
    e1: np.ndarray
    e2: np.ndarray

    @property
    def e_both(self) -> np.ndarray:
        """max(e1, e2) [m] per frame: the error of the worse bob."""
        return np.maximum(self.e1, self.e2)

    def horizons(self, thresholds: Sequence[float] = THRESHOLDS_M) -> dict[str, float | None]:
        """First time [s] after t0 the lower bob's / both bobs' error exceeds each threshold (None: never)."""
        out = {}
        for th in thresholds:
            out[f"lower_bob_{100 * th:g}cm_s"] = horizon(self.t, self.e2, th)
            out[f"both_bobs_{100 * th:g}cm_s"] = horizon(self.t, self.e_both, th)
        return out

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


def model_values(identified: IdentifiedModel) -> dict[str, Any]:
    """The identified model's start values without its start state (lengths, losses, suspension)."""
    return {k: v for k, v in identified.values.items() if k not in STATE_NAMES}


def least_squares_start(
    runner: FmuRunner, rec: Reconstruction, i0: int, values: Mapping[str, Any], n_frames: int = START_FIT_FRAMES
) -> StartStateFit:
    """Start state at frame ``i0`` fitted to the positions of ``n_frames`` frames, started from the reconstruction."""
    w = track_window(rec, i0, n_frames)
    return fit_start_state(runner, w.t0, w.offsets, w.positions, w.sigma_positions, w.guess, values)


def start_fit_summary(fit: StartStateFit, guess: np.ndarray) -> dict[str, Any]:
    """The fit as a dictionary plus its change from ``guess`` (rad, rad, rad/s, rad/s)."""
    return {**fit.as_dict(), "change_from_reconstruction": dict(zip(STATE_NAMES, (fit.state - guess).tolist()))}


# --- predictions ---------------------------------------------------------------------------------


def predict(
    runner: FmuRunner,
    label: str,
    values: Mapping[str, Any],
    state: np.ndarray,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
) -> Prediction:
    """Run the FMU from frame ``i0`` with ``state`` for ``n_frames`` frames and compare with the track."""
    result = simulate_frames(
        runner,
        {**FIT_SETTINGS, **values, **state_start_values(state)},
        float(rec.t[i0]),
        n_frames,
        outputs=RUN_OUTPUTS,
    )
    window = track_window(rec, i0, n_frames)
    d = output_matrix(result)[window.offsets] - window.positions
    return Prediction(
        label=label,
        state=np.asarray(state, dtype=float),
        result=result,
        t=window.offsets * FRAME_INTERVAL,
        e1=np.hypot(d[:, 0], d[:, 1]),
        e2=np.hypot(d[:, 2], d[:, 3]),
    )


def chaos_spread(
    runner: FmuRunner,
    values: Mapping[str, Any],
    fit: StartStateFit,
    central: Prediction,
    n_frames: int,
    size: int,
    seed: int = ENSEMBLE_SEED,
) -> tuple[np.ndarray, np.ndarray]:
    """Median distance [m] of the lower bob between runs from states drawn from the fit's covariance
    and the central run, per frame (times [s] since t0): how fast the start state's own uncertainty grows."""
    rng = np.random.default_rng(seed)
    states = rng.multivariate_normal(fit.state, fit.cov, size=size)
    ref = output_matrix(central.result)[:, 2:]
    items = [({**FIT_SETTINGS, **values, **state_start_values(state)}, fit.t0, n_frames, ref) for state in states]
    distances = runner_map(_spread_distance, items, runner, label="start-state ensemble")
    return np.arange(n_frames) * FRAME_INTERVAL, np.median(np.array(distances), axis=0)


def _spread_distance(runner: FmuRunner, item: tuple[dict[str, Any], float, int, np.ndarray]) -> np.ndarray:
    """Worker: the lower bob's distance [m] per frame of one ensemble run from the central prediction."""
    start, t0, n_frames, ref = item
    r = simulate_frames(runner, start, t0, n_frames)
    return np.linalg.norm(output_matrix(r)[:, 2:] - ref, axis=1)


def chaos_horizons(spread: tuple[np.ndarray, np.ndarray]) -> dict[str, float | None]:
    """First time [s] the ensemble's spread of the lower bob exceeds each of :data:`THRESHOLDS_M`, keyed like
    ``lower_bob_1cm_s`` (None: not within the prediction window, see :func:`null_means`)."""
    return {f"lower_bob_{100 * th:g}cm_s": horizon(*spread, th) for th in THRESHOLDS_M}


def null_means(prediction_s: float) -> dict[str, str]:
    """What a null horizon in the summary means, by summary key."""
    never = f"the error or spread did not exceed the threshold within the {prediction_s:.1f} s prediction window"
    return {"horizons_s": never, "chaos_horizons_s": never, "fit_window_sensitivity": never}


def window_sensitivity(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    values: Mapping[str, Any],
    n_frames: int,
    windows: Sequence[int],
) -> list[dict[str, Any]]:
    """Horizons of least-squares starts fitted to other numbers of frames (``windows``)."""
    return runner_map(_window_fit, [(rec, i0, dict(values), n_frames, frames) for frames in windows], runner,
                      label="fit windows", unit="fit")


def _window_fit(runner: FmuRunner, item: tuple[Reconstruction, int, dict[str, Any], int, int]) -> dict[str, Any]:
    """Worker: the least-squares start fitted to ``frames`` frames and its prediction's horizons."""
    rec, i0, values, n_frames, frames = item
    fit = least_squares_start(runner, rec, i0, values, frames)
    p = predict(runner, f"lsq{frames}", values, fit.state, rec, i0, n_frames)
    return {"fit_frames": frames, "chi2_red": fit.chi2_red, "rms_residual_m": fit.rms_residual, **p.horizons()}


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
    return offsets * FRAME_INTERVAL, np.abs(signed)


def rod_floor_summary(rec: Reconstruction, i0: int, n_frames: int) -> dict[str, float]:
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


def model_summary(rec: Reconstruction, identification: Identification, lengths: Mapping[str, float]) -> dict[str, Any]:
    """The predicting model: rod ``lengths`` [m], total bob mass [kg], losses, the identified suspension."""
    ident = identification
    return {
        "lengths_m": lengths,
        "masses_kg": rec.params.m1 + rec.params.m2,
        "losses": "air drag (bobs + rods) and bearing friction at the defaults; suspension identified",
        "suspension": {"k_N_per_m": ident.k, "M_s_kg": ident.m_s, "c_N_s_per_m": ident.c, "c_stderr": ident.c_stderr},
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
    """Times [s] and the FMU's bob coordinates [m] shifted by the fitted pivot into the track's coordinates."""
    pivot = rec.geometry.pivot
    shift = {"x1": pivot.xc, "y1": pivot.yc, "x2": pivot.xc, "y2": pivot.yc}
    result = prediction.result
    return np.asarray(result["time"]), {n: np.asarray(result[n]) + shift[n] for n in shift}


def error_curves(
    predictions: Sequence[Prediction], spread: tuple[np.ndarray, np.ndarray]
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Curves (t [s] since t0, error [m]) for the error plot: each run's lower bob, the last run's
    both bobs, and the chaos spread."""
    curves = {f"{run_title(p.label)}: lower bob": (p.t, p.e2) for p in predictions}
    curves.update({f"{run_title(p.label)}: larger of both bobs": (p.t, p.e_both) for p in predictions[-1:]})
    curves["chaos: spread of runs from the fitted start's uncertainty (median)"] = spread
    return curves
