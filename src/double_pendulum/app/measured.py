"""The app's run *against the measured track*: ``measured_vs_sim``'s main prediction, the one the README's horizon
is about, with the values it uses and the fmpy call that reproduces it.

The run (:func:`run_measured`) is the scenario's ``lsq_geometry_identified``:

* the seed's pendulum with its acrylic rods and the loss model fitted to the measured energy decay
  (:func:`~double_pendulum.analysis.prediction.comparison.identified_losses`, cached by the loss fit itself);
* the start state (phi1, phi2, omega1, omega2) at t0 = 0.8 s fitted by least squares together with the camera's
  geometry (its rotation against gravity [rad], the pivot's offset [m], l2 [m]) to the track's first
  ``GEOMETRY_FIT_FRAMES`` frames (1.5 s) after t0 (:func:`fitted_start`, through the FMU; cached in the result
  cache, :mod:`double_pendulum.runs.result_cache`, as ``app_measured_start``: with the loss fit, the first run takes
  some 15 s, later ones a few);
* the FMU run from t0 over the record's frames (20 s), its positions turned and shifted by the fitted camera
  geometry and compared with the camera's.

None of the form's values applies. ``quick`` is the scenario's quick mode (the quick loss fit, a 0.5 s geometry
window, 3 s of record): the tests' cheaper stand-in for the same code.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

MEASURED_OUTPUTS_NOTE = ("the FMU's positions are turned by view_rotation about the pivot, then shifted by "
                         "pivot_offset_x and pivot_offset_y (the fitted camera geometry)")


def _plain(value: Any) -> Any:
    """A start value as a plain Python number (NumPy's scalars print as ``np.float64(...)``)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (np.floating, float)):
        return float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def fitted_start(runner: Any, rec: Any, i0: int, values: Mapping[str, Any], frames: int) -> Any:
    """The start state and camera geometry at frame ``i0`` of ``rec`` fitted to ``frames`` frames with the losses
    ``values`` through the FMU of ``runner`` (an :class:`~double_pendulum.fmu.running.runner.FmuRunner`), as
    ``measured_vs_sim`` fits its main start (:func:`~double_pendulum.analysis.prediction.comparison.least_squares_start`
    with :data:`~double_pendulum.analysis.prediction.comparison.FREE_GEOMETRY`); cached, keyed by the record, the FMU's
    GUID, the losses and the fit's settings (and the sources, :func:`~double_pendulum.runs.result_cache.cached`)."""
    from ..analysis.prediction.comparison import FIT_TOLERANCE, FREE_GEOMETRY, least_squares_start
    from ..runs.result_cache import cached

    digest = hashlib.sha256()
    for column in (rec.t, rec.x1, rec.y1, rec.x2, rec.y2):
        digest.update(np.ascontiguousarray(column, dtype=float).tobytes())
    key = {"track": digest.hexdigest()[:16], "fmu": runner.model_description.guid, "i0": int(i0),
           "frames": int(frames), "geometry": list(FREE_GEOMETRY), "tolerance": FIT_TOLERANCE,
           "values": {k: _plain(v) for k, v in sorted(values.items())}}
    return cached("app_measured_start", key,
                  lambda: least_squares_start(runner, rec, i0, values, frames, FREE_GEOMETRY))


def run_measured(fmu: str, *, quick: bool = False, progress: Callable[[float], None] | None = None) -> dict[str, Any]:
    """The main prediction of ``measured_vs_sim`` run by the FMU ``fmu`` (a file or its extracted folder): the paths
    table (:func:`~double_pendulum.analysis.prediction.paths.paths_table`) as ``columns``, the FMU's own rows as
    ``simulated``, the run as fmpy is given it (``start_values``, ``start_time``, ``stop_time``,
    ``output_interval`` [s], ``outputs``: :func:`call_text`) and the camera geometry's ``transforms``, ``used``
    (every value the run takes, for the page), ``horizon`` (the lower bob's smoothed 5 cm horizon), the lower bob's
    error smoothed as the horizon smooths it (``error_smoothed`` [m], over ``smoothing_s``), ``t0`` [s] and
    ``losses``. ``progress`` is told the fraction done (0 to 1)."""
    from double_pendulum.scenarios.measured_vs_sim import (
        GEOMETRY_FIT_FRAMES,
        PREDICTION_S,
        QUICK_GEOMETRY_FIT_FRAMES,
        QUICK_PREDICTION_S,
        SEED_T0,
    )

    from ..analysis.losses.identification import seed_reconstruction
    from ..analysis.prediction.comparison import (
        RUN_OUTPUTS,
        SMOOTHING_S,
        headline_horizon,
        identified_losses,
        nearest_frame,
        predict,
        prediction_start_values,
        smoothed,
    )
    from ..analysis.prediction.paths import paths_table
    from ..analysis.track.measurement import FRAME_INTERVAL
    from ..fmu.running.runner import FmuRunner

    def told(fraction: float) -> None:
        if progress is not None:
            progress(fraction)

    rec = seed_reconstruction()
    losses = identified_losses(rec, quick=quick)
    told(0.4)
    i0 = nearest_frame(rec, SEED_T0)
    frames = min(round((QUICK_PREDICTION_S if quick else PREDICTION_S) / FRAME_INTERVAL) + 1, len(rec.t) - i0)
    values = {k: _plain(v) for k, v in losses.values.items()}
    with FmuRunner(fmu) as runner:  # the fit's runs reuse an instance, as the scenario's do
        fit = fitted_start(runner, rec, i0, values, QUICK_GEOMETRY_FIT_FRAMES if quick else GEOMETRY_FIT_FRAMES)
    told(0.8)
    with FmuRunner(fmu, reuse_instance=False) as runner:  # a new instance, as a bare simulate_fmu call makes
        prediction = predict(runner, "lsq_geometry_identified", values, fit.state, rec, i0, frames, fit.geometry)
    t0 = float(rec.t[i0])
    start_values = {k: _plain(v) for k, v in prediction_start_values(values, fit.state, fit.geometry).items()}
    transforms = {k: float(v) for k, v in fit.geometry.items() if k not in start_values}
    span = (frames - 1) * FRAME_INTERVAL
    told(1.0)
    stderr = dict(zip(fit.names, (*fit.stderr, *fit.geometry_stderr.values())))

    def source(name: str) -> str:
        if name in stderr:
            return "fitted to the track"
        if name in losses.losses:
            return "fitted to the measured decay"
        return "the seed's pendulum" if name in losses.pendulum else "a setting of the run"

    used = [{"name": k, "value": v, "stderr": stderr.get(k), "what": source(k)} for k, v in start_values.items()]
    used += [{"name": k, "value": v, "stderr": stderr[k], "what": "fitted to the track (camera geometry)"}
             for k, v in transforms.items()]
    table = paths_table(rec, i0, frames, prediction)
    return {"columns": {n: table[n].tolist() for n in table.dtype.names},
            "simulated": {n: prediction.result[n].tolist() for n in prediction.result.dtype.names},
            "start_values": start_values, "start_time": t0, "stop_time": t0 + span, "output_interval": FRAME_INTERVAL,
            "outputs": list(RUN_OUTPUTS), "transforms": transforms, "message": None, "used": used, "t0": t0,
            "span_s": span, "fit_frames": fit.n_frames, "smoothing_s": SMOOTHING_S,
            "error_smoothed": smoothed(prediction.t, prediction.e2).tolist(),
            "horizon": headline_horizon(prediction, span), "losses": {k: _plain(v) for k, v in losses.losses.items()}}


def call_text(fmu_file: str, answer: Mapping[str, Any]) -> str:
    """The Python that reproduces the FMU's rows of a :func:`run_measured` ``answer`` with fmpy, for the FMU file
    ``fmu_file``, and says how its positions are moved before they meet the camera's."""
    from ..case import Case

    case = Case(fmu_file, answer["start_values"], answer["stop_time"], answer["output_interval"],
                outputs=tuple(answer["outputs"]), start_time=answer["start_time"])
    return ("import fmpy\n\n# measured_vs_sim's main prediction: the FMU from the fitted start at t0, a row a camera "
            f"frame\nresult = {case.fmpy_call()}\n\n# to meet the camera's positions, {MEASURED_OUTPUTS_NOTE}:\n"
            + "".join(f"# {k} = {v!r}\n" for k, v in answer["transforms"].items()))
