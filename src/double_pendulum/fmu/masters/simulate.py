"""In-process simulation with the same co-simulation component the FMU runs.

:func:`simulate` mirrors :func:`fmpy.simulate_fmu` for this model: same start values by name,
same communication grid, same structured result array. Running the same settings through the
FMU gives the same numbers (``tests/test_fmu.py`` checks this), without the FMI layer's cost.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from ...component.cosimulation import DoublePendulumCoSimulation
from ...model.outputs import OUTPUT_NAMES


def communication_points(
    start_time: float, stop_time: float, interval: float
) -> Iterator[tuple[float, float]]:
    """Yield ``(current_time, step_size)`` pairs on fmpy's grid ``start + n * interval``.

    The last step is shortened to end at ``stop_time``, as fmpy does for FMUs that can
    handle a variable communication step size.
    """
    if not (math.isfinite(interval) and interval > 0.0):
        raise ValueError(f"invalid output_interval = {interval!r} s: must be > 0")
    time = start_time
    n = 0
    while not (time > stop_time or math.isclose(time, stop_time)):
        nxt = start_time + (n + 1) * interval
        if nxt > stop_time and not math.isclose(nxt, stop_time):
            nxt = stop_time
        yield time, nxt - time
        time = nxt
        n += 1


def apply_inputs(sim: DoublePendulumCoSimulation, signals: np.ndarray | None, time: float) -> None:
    """Set the inputs in ``signals`` at ``time`` [s], as fmpy's ``simulate_fmu(input=...)`` does.

    ``signals`` is a structured array: ``time`` first, then a column per input; each value is
    interpolated linearly in time (held before the first and after the last row; exact at the
    rows). Input events (repeated time rows) are not supported here.
    """
    if signals is None:
        return
    names = signals.dtype.names
    t = signals[names[0]]
    for name in names[1:]:
        sim.set_input(name, float(np.interp(time, t, signals[name])))


def simulate(
    start_values: Mapping[str, Any] | None = None,
    *,
    stop_time: float = 10.0,
    output_interval: float = 0.01,
    start_time: float = 0.0,
    outputs: Sequence[str] = OUTPUT_NAMES,
    input: np.ndarray | None = None,  # noqa: A002 - fmpy's name
) -> np.ndarray:
    """Simulate in-process and return a structured array with ``time`` and ``outputs``.

    ``input``: input signals as for :func:`fmpy.simulate_fmu` (see :func:`apply_inputs`), set
    before initialisation and before each step at its start time.
    """
    sim = DoublePendulumCoSimulation(start_time)
    for name, value in (start_values or {}).items():
        sim.set(name, value)
    apply_inputs(sim, input, start_time)
    sim.initialise()
    rows = [(sim.time, *(sim.outputs[n] for n in outputs))]
    for current, step in communication_points(start_time, stop_time, output_interval):
        apply_inputs(sim, input, current)
        sim.do_step(current, step)
        rows.append((sim.time, *(sim.outputs[n] for n in outputs)))
    dtype = [("time", np.float64)] + [(n, np.float64) for n in outputs]
    return np.array(rows, dtype=dtype)
