"""The measured and the simulated pendulum frame by frame in one frame of reference, for the animation of
``measured_vs_sim`` and the x-y overlay of the lower bob's paths.

Both are written to ``paths.csv`` by the scenario and drawn from there. The frame of reference is the one the
errors are measured in (:func:`~double_pendulum.analysis.prediction.comparison.predict`): positions [m] relative
to the pivot the measurement's circle fit found, x to the right and y up; the simulated bobs are turned and
shifted by the prediction's fitted camera geometry, and so is its pivot (the FMU's origin), which need not lie
at the circle fit's.
"""

from __future__ import annotations

import numpy as np

from ..track.measurement import Reconstruction
from ..track.start_state import POSITION_OUTPUTS, output_matrix, shift_outputs, split_geometry, track_window
from .comparison import Prediction

PATHS_UNITS: dict[str, str] = {
    "t_since_t0": "s",
    **{f"{name}_measured": "m" for name in POSITION_OUTPUTS},
    **{f"{name}_simulated": "m" for name in POSITION_OUTPUTS},
    "pivot_x_simulated": "m",
    "pivot_y_simulated": "m",
}
"""Units of :func:`paths_table`'s columns (besides ``time`` [s])."""


def paths_table(rec: Reconstruction, i0: int, n_frames: int, prediction: Prediction) -> np.ndarray:
    """Per valid frame from ``i0`` on: the time [s] (of the record, and since t0), the measured bob positions
    ``x1_measured`` ... ``y2_measured`` [m], the simulated ones of ``prediction`` (``*_simulated``) and the simulated
    pivot (``pivot_x_simulated``, ``pivot_y_simulated``) [m], all relative to the measurement's pivot."""
    window = track_window(rec, i0, n_frames)
    _, transforms = split_geometry(prediction.geometry)
    simulated = shift_outputs(output_matrix(prediction.result), POSITION_OUTPUTS, transforms)[window.offsets]
    pivot = shift_outputs(np.zeros((1, len(POSITION_OUTPUTS))), POSITION_OUTPUTS, transforms)[0, :2]
    rows = len(window.offsets)
    columns: dict[str, np.ndarray] = {
        "time": rec.t[i0 + window.offsets],
        "t_since_t0": window.offsets * rec.track.dt,
        **{f"{name}_measured": window.positions[:, k] for k, name in enumerate(POSITION_OUTPUTS)},
        **{f"{name}_simulated": simulated[:, k] for k, name in enumerate(POSITION_OUTPUTS)},
        "pivot_x_simulated": np.full(rows, pivot[0]),
        "pivot_y_simulated": np.full(rows, pivot[1]),
    }
    arrays = [np.asarray(v, dtype=float) for v in columns.values()]
    return np.rec.fromarrays(arrays, names=list(columns)).view(np.ndarray)
