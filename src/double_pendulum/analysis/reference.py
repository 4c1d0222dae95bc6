"""Reference solutions for error measurements, computed once and cached.

A reference is the in-process simulation with DOP853 at rtol = 1e-13 (our integrator, on the
output grid), cross-checked against SciPy's Radau (a different, implicit method) at rtol = 1e-12
on the same vector field. Their largest difference is the reference's *error floor*: errors
below it cannot be resolved. References are cached as ``.npz`` files keyed by a hash of the case,
in ``.cache/references/`` (not committed).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..component.cosimulation import DoublePendulumCoSimulation
from ..fmu.simulate import simulate

STATE_OUTPUTS = ("phi1", "phi2", "omega1", "omega2")
CACHE_DIR = Path(".cache") / "references"


@dataclass(frozen=True)
class Reference:
    """A reference trajectory on the output grid and its estimated error floor."""

    time: np.ndarray
    states: dict[str, np.ndarray]
    energy: np.ndarray
    error_floor: float


def _key(start: Mapping[str, Any], stop_time: float, interval: float) -> str:
    text = json.dumps({"start": dict(start), "stop": stop_time, "interval": interval}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _scipy_cross_check(start: Mapping[str, Any], times: np.ndarray) -> np.ndarray:
    """Integrate the same vector field with SciPy's Radau at rtol 1e-12; states at ``times``."""
    from scipy.integrate import solve_ivp

    sim = DoublePendulumCoSimulation()
    for name, value in start.items():
        sim.set(name, value)
    sim.initialise()
    f = sim.model.vector_field
    y0 = np.array(sim.integrator.y)
    sol = solve_ivp(lambda t, y: f(t, list(y)), (times[0], times[-1]), y0, method="Radau", rtol=1e-12,
                    atol=1e-14, t_eval=times)
    if not sol.success:
        raise RuntimeError(f"reference cross-check failed: {sol.message}")
    return sol.y[:4]


def reference_solution(
    start: Mapping[str, Any], stop_time: float, interval: float, cache_dir: Path = CACHE_DIR
) -> Reference:
    """Return (and cache) the reference for ``start`` on ``0, interval, ..., stop_time``."""
    path = Path(cache_dir) / f"{_key(start, stop_time, interval)}.npz"
    if path.is_file():
        data = np.load(path)
        return Reference(data["time"], {n: data[n] for n in STATE_OUTPUTS}, data["energy"], float(data["floor"]))
    tight = {**start, "solver": "dop853", "rtol": 1e-13, "atol": 1e-15, "max_steps": 1e8}
    ref = simulate(tight, stop_time=stop_time, output_interval=interval)
    check = _scipy_cross_check(tight, ref["time"])
    floor = float(max(np.max(np.abs(ref[n] - check[i])) for i, n in enumerate(STATE_OUTPUTS)))
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, time=ref["time"], energy=ref["E_total"], floor=floor, **{n: ref[n] for n in STATE_OUTPUTS})
    return Reference(ref["time"], {n: ref[n] for n in STATE_OUTPUTS}, ref["E_total"], floor)
