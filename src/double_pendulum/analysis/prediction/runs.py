r"""The runs of the ``measured_vs_sim`` scenario: its four least-squares starts and its six predictions.

The starts, all at frame ``i0`` (:func:`~.comparison.least_squares_start`): the state alone over the first
:data:`~double_pendulum.analysis.suspension.identification.START_FIT_FRAMES` frames (``state_only``); over the
geometry fit's frames the state with the free geometry :data:`~.comparison.FREE_GEOMETRY` (``geometry``: camera
rotation [rad], pivot offset [m], l2 [m]), the state alone with the geometry fixed (``fixed``) and the state with the
pivot offset and l2 (:data:`~.comparison.PIVOT_SHIFT_GEOMETRY`, ``pivot_shift``). The predictions run each start
over ``n_frames`` frames (:func:`~.comparison.predict`), the main one (the start and geometry) last.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from ..suspension.identification import START_FIT_FRAMES
from ..track.measurement import Reconstruction
from ..track.start_state import STATE_NAMES, StartStateFit
from .comparison import (
    FREE_GEOMETRY,
    PIVOT_SHIFT_GEOMETRY,
    Prediction,
    least_squares_start,
    predict,
    start_fit_summary,
)


@dataclass(frozen=True, eq=False)
class Starts:
    """The least-squares starts of the scenario (see the module docstring)."""

    state_only: StartStateFit
    geometry: StartStateFit
    fixed: StartStateFit
    pivot_shift: StartStateFit


def fitted_starts(runner: FmuRunner, rec: Reconstruction, i0: int, values: Mapping[str, Any],
                  geometry_frames: int, state_frames: int = START_FIT_FRAMES) -> Starts:  # fmt: skip
    """The four least-squares starts at frame ``i0`` with the losses ``values`` (FMU start values)."""
    return Starts(
        state_only=least_squares_start(runner, rec, i0, values, state_frames),
        geometry=least_squares_start(runner, rec, i0, values, geometry_frames, FREE_GEOMETRY),
        fixed=least_squares_start(runner, rec, i0, values, geometry_frames),
        pivot_shift=least_squares_start(runner, rec, i0, values, geometry_frames, PIVOT_SHIFT_GEOMETRY),
    )


def predictions(
    runner: FmuRunner,
    rec: Reconstruction,
    i0: int,
    n_frames: int,
    values: Mapping[str, Any],
    frictionless: Mapping[str, Any],
    seed_state: np.ndarray,
    starts: Starts,
) -> list[Prediction]:
    """The six predictions: the seed's start frictionless (``frictionless``: point masses) and with the losses
    ``values``, then each least-squares start with them, the main run (start and geometry) last."""
    s = starts
    return [
        predict(runner, "seed_start_frictionless", frictionless, seed_state, rec, i0, n_frames),
        predict(runner, "seed_start_identified", values, seed_state, rec, i0, n_frames),
        predict(runner, "lsq_start_identified", values, s.state_only.state, rec, i0, n_frames),
        predict(runner, "lsq_fixed_geometry_identified", values, s.fixed.state, rec, i0, n_frames),
        predict(runner, "lsq_pivot_shift_identified", values, s.pivot_shift.state, rec, i0, n_frames,
                s.pivot_shift.geometry),
        predict(runner, "lsq_geometry_identified", values, s.geometry.state, rec, i0, n_frames, s.geometry.geometry),
    ]


def starts_summary(seed_state: np.ndarray, starts: Starts) -> dict[str, Any]:
    """The summary's start states: the seed's reconstruction and each least-squares start with its change from it."""
    return {
        "seed_reconstruction": dict(zip(STATE_NAMES, seed_state.tolist())),
        "least_squares": start_fit_summary(starts.state_only, seed_state),
        "least_squares_geometry": start_fit_summary(starts.geometry, seed_state),
        "least_squares_fixed_geometry": start_fit_summary(starts.fixed, seed_state),
        "least_squares_pivot_shift": start_fit_summary(starts.pivot_shift, seed_state),
    }
