"""Reference solutions for error measurements, computed once and cached.

A reference is the in-process simulation with DOP853 at rtol = 1e-13 (our integrator, on the
output grid), cross-checked against SciPy's own DOP853 implementation at rtol = 1e-13 (its step
control and arithmetic are independent of ours) on the same vector field, or, with
``cross_check=THOROUGH_CROSS_CHECK``, against SciPy's Radau (a different, implicit method) at
rtol = 1e-12. Their largest difference is the reference's *error floor*: errors below it cannot
be resolved. SciPy's DOP853 costs 0.2-9 s CPU per case and gives the smaller floor (Radau's own
error dominates its floor: 1.4e-12 against 4.2e-12 on the regular case, 4.8e-13 against 1.2e-12 on
the stiff one); Radau costs 15-50 s per case.

References are cached as ``.npz`` files in ``references/`` under the cache folder
(:func:`cache_dir`: ``$DOUBLE_PENDULUM_CACHE`` if set, else ``.cache/`` in the working directory;
not committed), named by a hash of the case (start values, horizon, output interval), the
reference settings and the runtime sources (``model/``, ``solvers/``, ``component/``): a change of
the equations or the integrators computes them anew. Delete the folder to force that by hand.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...component.cosimulation import DoublePendulumCoSimulation
from ...fmu.masters.simulate import simulate
from ...runs.result_cache import cache_root, key_hash, sources_hash

STATE_OUTPUTS = ("phi1", "phi2", "omega1", "omega2")
REFERENCE_SETTINGS = {"solver": "dop853", "rtol": 1e-13, "atol": 1e-15, "max_steps": 1e8}
CROSS_CHECK = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-15}
THOROUGH_CROSS_CHECK = {"method": "Radau", "rtol": 1e-12, "atol": 1e-14}
_RUNTIME = ("model", "solvers", "component")


def cache_dir() -> Path:
    """The folder of cached references: ``$DOUBLE_PENDULUM_CACHE/references`` or ``.cache/references``."""
    return cache_root() / "references"


def runtime_hash() -> str:
    """Hash of the runtime sources (model, solvers, component): references depend on nothing else."""
    return sources_hash(_RUNTIME)


@dataclass(frozen=True)
class Reference:
    """A reference trajectory on the output grid and its estimated error floor."""

    time: np.ndarray
    states: dict[str, np.ndarray]
    energy: np.ndarray
    error_floor: float


def _key(start: Mapping[str, Any], stop_time: float, interval: float, cross_check: Mapping[str, Any]) -> str:
    return key_hash({"start": dict(start), "stop": stop_time, "interval": interval,
                     "reference": REFERENCE_SETTINGS, "cross_check": dict(cross_check), "runtime": runtime_hash()})


def _scipy_cross_check(start: Mapping[str, Any], times: np.ndarray, cross_check: Mapping[str, Any]) -> np.ndarray:
    """Integrate the same vector field with SciPy (``cross_check``: method, rtol, atol); states at ``times``."""
    from scipy.integrate import solve_ivp

    sim = DoublePendulumCoSimulation()
    for name, value in start.items():
        sim.set(name, value)
    sim.initialise()
    f = sim.model.vector_field
    y0 = np.array(sim.integrator.y)
    sol = solve_ivp(lambda t, y: f(t, list(y)), (times[0], times[-1]), y0, method=cross_check["method"],
                    rtol=cross_check["rtol"], atol=cross_check["atol"], t_eval=times)
    if not sol.success:
        raise RuntimeError(f"reference cross-check failed: {sol.message}")
    return sol.y[:4]


def _path(start: Mapping[str, Any], stop_time: float, interval: float, folder: Path | None,
          cross_check: Mapping[str, Any]) -> Path:
    return Path(folder if folder is not None else cache_dir()) / f"{_key(start, stop_time, interval, cross_check)}.npz"


def cached_reference(
    start: Mapping[str, Any], stop_time: float, interval: float, cache_dir: Path | None = None,
    cross_check: Mapping[str, Any] = CROSS_CHECK,
) -> Reference | None:
    """The cached reference for the case, or None if it was not computed yet (with these sources)."""
    path = _path(start, stop_time, interval, cache_dir, cross_check)
    if not path.is_file():
        return None
    try:
        data = np.load(path)
        return Reference(data["time"], {n: data[n] for n in STATE_OUTPUTS}, data["energy"], float(data["floor"]))
    except (OSError, KeyError, ValueError):  # a damaged file: compute anew
        return None


def reference_solution(
    start: Mapping[str, Any], stop_time: float, interval: float, cache_dir: Path | None = None,
    cross_check: Mapping[str, Any] = CROSS_CHECK,
) -> Reference:
    """Return (and cache) the reference for ``start`` on ``0, interval, ..., stop_time``; its error floor from
    ``cross_check`` (:data:`CROSS_CHECK`, or :data:`THOROUGH_CROSS_CHECK`)."""
    cached = cached_reference(start, stop_time, interval, cache_dir, cross_check)
    if cached is not None:
        return cached
    tight = {**start, **REFERENCE_SETTINGS}
    ref = simulate(tight, stop_time=stop_time, output_interval=interval)
    check = _scipy_cross_check(tight, ref["time"], cross_check)
    floor = float(max(np.max(np.abs(ref[n] - check[i])) for i, n in enumerate(STATE_OUTPUTS)))
    path = _path(start, stop_time, interval, cache_dir, cross_check)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.stem}.{os.getpid()}.npz")  # written whole, then renamed
    np.savez(partial, time=ref["time"], energy=ref["E_total"], floor=floor, **{n: ref[n] for n in STATE_OUTPUTS})
    os.replace(partial, path)
    return Reference(ref["time"], {n: ref[n] for n in STATE_OUTPUTS}, ref["E_total"], floor)
