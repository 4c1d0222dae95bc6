"""The ``cosimulation`` study: the pendulum on its suspension, monolithic against split in two.

Each *case* is a start (regular, chaotic) and a suspension (default; light and stiff). The
reference is the monolith (DoublePendulum with ``suspension`` on, in-process, the FMU's own
numbers). The split system runs with the schemes of :mod:`double_pendulum.fmu.masters.coupling`
in-process (``jacobi``, ``extrapolation``, ``iterative``) and on the two engines (``libcosim``:
the SSP file; ``container``: fmpy's container FMU), for a range of macro steps. Per run: the
errors at the stop time of the angles [rad], the pivot position [m] and the total energy [J], the
energy the coupling created, W_input + W_in [J], and the CPU time [s]. An unstable run is kept
as a row with ``stable = False`` and the message.
"""

from __future__ import annotations

import math
import tempfile
import time
import zipfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...component.cosimulation import DoublePendulumCoSimulation
from ...component.suspension import SuspensionCoSimulation
from ...fmu.masters.coupling import CouplingError, coupling_energy, run_coupled, split_values
from .stability import critical_mass_ratio, spectral_radius

STARTS: dict[str, dict[str, float]] = {
    "regular": {"phi1_0": 0.3, "phi2_0": 0.2},
    "chaotic": {"phi1_0": 2.0, "phi2_0": 2.5},
}
SUSPENSIONS: dict[str, dict[str, float]] = {
    "default": {},  # M_s = 2 kg, k = 2e4 N/m, c = 20 N s/m: omega = 100 rad/s, mu = 0.30
    "light stiff": {"M_s": 0.8, "k_x": 1e5, "k_y": 1e5, "c_x": 28.3, "c_y": 28.3},  # omega = 354 rad/s, mu = 0.75
}
IN_PROCESS = ("jacobi", "jacobi_sequential", "extrapolation", "iterative")
ENGINES = ("libcosim", "container")
METHODS = IN_PROCESS + ENGINES


def available_methods() -> tuple[list[str], dict[str, str]]:
    """The methods this installation can run, and why the others cannot (libcosim needs libcosimpy)."""
    import importlib.util

    if importlib.util.find_spec("libcosimpy") is None:
        reason = "libcosimpy is not installed (pip install libcosimpy, or the package's [test] extra)"
        return [m for m in METHODS if m != "libcosim"], {"libcosim": reason}
    return list(METHODS), {}


def case_values(start: str, suspension: str) -> dict[str, float]:
    """The monolith's start values of one case (``suspension`` added by the runs)."""
    return {**STARTS[start], **SUSPENSIONS[suspension]}


def monolith(values: Mapping[str, Any], stop_time: float, n_steps: int = 200) -> dict[str, float]:
    """The reference at ``stop_time`` [s]: DoublePendulum with its suspension on, in-process."""
    sim = DoublePendulumCoSimulation()
    for name, value in {**values, "suspension": True}.items():
        sim.set(name, value)
    sim.initialise()
    for k in range(n_steps):
        sim.do_step(k * stop_time / n_steps, stop_time / n_steps)
    return {n: float(sim.get(n)) for n in ("phi1", "phi2", "xs", "ys", "E_total")}


def _in_process(values: Mapping[str, Any], stop_time: float, h: float, scheme: str,
                load_factor: float = 1.0) -> np.ndarray:
    """The split system in-process; ``load_factor`` scales the suspension's static load ``F_static_y``."""
    pendulum_values, suspension_values = split_values(values)
    suspension_values["F_static_y"] *= load_factor
    pendulum, suspension = DoublePendulumCoSimulation(), SuspensionCoSimulation()
    for name, value in pendulum_values.items():
        pendulum.set(name, value)
    for name, value in suspension_values.items():
        suspension.set(name, value)
    pendulum.initialise()
    suspension.initialise()
    return run_coupled(pendulum, suspension, stop_time=stop_time, macro_step=h, scheme=scheme)


def _on_engine(values: Mapping[str, Any], stop_time: float, h: float, engine: str, fmus: Sequence[Path]) -> np.ndarray:
    from ...fmu.build.container import write_container
    from ...fmu.build.ssp import write_ssp
    from ...fmu.running.hosts import simulate_container, simulate_ssp_with_libcosim

    with tempfile.TemporaryDirectory(prefix="dp_cosim_") as tmp:
        if engine == "libcosim":
            ssp = write_ssp(Path(tmp) / "system.ssp", *fmus, values, macro_step=h)
            return simulate_ssp_with_libcosim(ssp, stop_time=stop_time, macro_step=h)
        container = write_container(Path(tmp) / "system.fmu", *fmus, values, macro_step=h,
                                    compression=zipfile.ZIP_STORED)  # run once: not worth compressing
        return simulate_container(container, stop_time=stop_time, macro_step=h)


def split_run(item: tuple[str, str, str, float, float, tuple[str, str]]) -> dict[str, Any]:
    """One split run ``(start, suspension, method, h [s], stop [s], fmus)``: its end values, CPU time, stability."""
    start, suspension, method, h, stop, fmus = item
    values = case_values(start, suspension)
    cpu = time.process_time()
    row: dict[str, Any] = {"start": start, "suspension": suspension, "method": method, "macro_step_s": h}
    try:
        rows = (_in_process(values, stop, h, method) if method in IN_PROCESS
                else _on_engine(values, stop, h, method, [Path(f) for f in fmus]))
        row.update(stable=True, message="")
    except CouplingError as error:
        rows = error.rows
        row.update(stable=False, message=str(error))
    except Exception as error:  # the engine itself failed, not the coupling: reported, the method left out
        if method in IN_PROCESS:
            raise
        return {**row, "engine_error": f"{method} failed to run: {error}"}
    row["cpu_s"] = time.process_time() - cpu
    row["rows_kept"] = len(rows)
    last = rows[-1] if len(rows) else None
    ok = row["stable"] and last is not None
    for name in ("phi1", "phi2", "x", "y", "E_pendulum", "E_suspension", "W_input", "W_in"):
        row[name] = float(last[name]) if ok else math.nan
    row["coupling_energy_J"] = coupling_energy(last) if ok else math.nan
    return row


def run_cost(method: str, h: float, stop: float) -> float:
    """A rough CPU estimate [s] of one split run (to start the long ones first): ~0.5 s fixed for an engine
    (writing, extracting and loading the system), and per macro step ~7 ms iterative, ~0.5 ms otherwise."""
    per_step = 7e-3 if method == "iterative" else 5e-4
    return (0.5 if method in ENGINES else 0.0) + per_step * stop / h


def drop_failed_engines(rows: list[dict[str, Any]], skipped: dict[str, str]) -> list[dict[str, Any]]:
    """Remove the runs of an engine that failed to run at all, naming it in ``skipped`` with its error.

    Seen with libcosim in a process that ran other scenarios first ("The FMU contains no binary for
    this platform" while the same SSP runs in a fresh process): the scenario then reports the engine
    as skipped instead of failing as a whole.
    """
    for row in rows:
        if "engine_error" in row:
            skipped.setdefault(row["method"], row["engine_error"])
    return [row for row in rows if row["method"] not in skipped]


def add_errors(rows: list[dict[str, Any]], references: Mapping[tuple[str, str], Mapping[str, float]]) -> None:
    """Add the errors against the monolith at the stop time: angles [rad], pivot [m], energy [J]."""
    for row in rows:
        ref = references[(row["start"], row["suspension"])]
        row["angle_error_rad"] = max(abs(row["phi1"] - ref["phi1"]), abs(row["phi2"] - ref["phi2"]))
        row["pivot_error_m"] = max(abs(row["x"] - ref["xs"]), abs(row["y"] - ref["ys"]))
        row["energy_error_J"] = abs(row["E_pendulum"] + row["E_suspension"] - ref["E_total"])


ORDER_MIN_R2 = 0.95
"""A fitted order counts as resolved if log|error| is that close to linear in log h (R^2 of the fit)."""


def _order_fit(steps: Sequence[float], errors: Sequence[float], floor: float = 1e-12) -> tuple[float, float]:
    """``(slope, R^2)`` of log|error| over log(h) (least squares) from the finite |errors| above ``floor``."""
    pairs = [(h, abs(e)) for h, e in zip(steps, errors) if math.isfinite(e) and abs(e) > floor]
    if len(pairs) < 3:
        return math.nan, math.nan
    x, y = np.log([p[0] for p in pairs]), np.log([p[1] for p in pairs])
    slope, intercept = np.polyfit(x, y, 1)
    residual = y - (slope * x + intercept)
    spread = float(np.sum((y - y.mean()) ** 2))
    return float(slope), 1.0 - float(np.sum(residual**2)) / spread if spread > 0.0 else math.nan


def fitted_order(steps: Sequence[float], errors: Sequence[float], floor: float = 1e-12) -> float:
    """Slope of log|error| over log(h) (least squares), from the finite |errors| above ``floor``."""
    return _order_fit(steps, errors, floor)[0]


def _order_runs(rows: list[dict[str, Any]], max_step: float) -> dict[str, list[dict[str, Any]]]:
    """The stable runs with h <= ``max_step`` per "start / suspension / method"."""
    return {" / ".join(key): [r for r in rows if (r["start"], r["suspension"], r["method"]) == key and r["stable"]
                              and r["macro_step_s"] <= max_step]
            for key in sorted({(r["start"], r["suspension"], r["method"]) for r in rows})}


def orders(rows: list[dict[str, Any]], quantity: str, max_step: float = 5e-3) -> dict[str, float]:
    """Fitted order of ``quantity`` per "start / suspension / method", over the stable runs with h <= ``max_step``."""
    return {key: fitted_order([r["macro_step_s"] for r in sel], [r[quantity] for r in sel])
            for key, sel in _order_runs(rows, max_step).items()}


def unresolved_orders(rows: list[dict[str, Any]], quantity: str, max_step: float = 5e-3) -> list[str]:
    """The "start / suspension / method" whose errors of ``quantity`` do not follow a power of h: the fit of
    log|error| over log h has R^2 below :data:`ORDER_MIN_R2` (or too few errors), so its slope is no order."""
    out = []
    for key, sel in _order_runs(rows, max_step).items():
        r2 = _order_fit([r["macro_step_s"] for r in sel], [r[quantity] for r in sel])[1]
        if not r2 >= ORDER_MIN_R2:
            out.append(key)
    return out


MAP_LOAD_STEP = 0.01
"""The stability map's excitation: the suspension's static load is set 1 % off the pendulum's weight, a
step of the load that sets the coupled loop moving from rest (any amount gives the same spectral radius:
the hanging pendulum's vertical loop is linear)."""
STABILITY_TOLERANCE = 1e-6
"""Unstable: the fitted spectral radius of the step map exceeds 1 by more than this (its fit error is
below 1e-8 on the map; a growth of 1e-4 % a step)."""


def step_map_spectral_radius(rows: np.ndarray, scheme: str) -> float:
    """Spectral radius of the coupled step map fitted to a run: least squares X_{n+1} = G X_n + b.

    X_n are the values a macro step carries over, as in
    :func:`~double_pendulum.analysis.coupling.stability.amplification_matrix`: the suspension's
    displacement and velocity and the pendulum's pivot force, (y_n, v_n, F_n) for ``jacobi_sequential`` and
    (y_n, v_n, F_n, F_{n-1}) for ``jacobi`` (columns ``y``, ``vy``, ``F_pivot_y`` of
    :func:`~double_pendulum.fmu.masters.coupling.run_coupled`; the constant b takes the static load). Returns the
    largest |eigenvalue| of G, the growth factor per macro step of the fastest mode; ``inf`` if the run
    ended before it had twice as many steps as unknowns.
    """
    y, v, f = rows["y"], rows["vy"], rows["F_pivot_y"]
    x = np.column_stack([y[1:], v[1:], f[1:], f[:-1]]) if scheme == "jacobi" else np.column_stack([y, v, f])
    if len(x) < 2 * (x.shape[1] + 1) + 1:
        return math.inf
    x = x / np.where(np.abs(x).max(axis=0) > 0.0, np.abs(x).max(axis=0), 1.0)  # columns of order 1
    coef, *_ = np.linalg.lstsq(np.column_stack([x[:-1], np.ones(len(x) - 1)]), x[1:], rcond=None)
    return float(max(abs(np.linalg.eigvals(coef[:-1].T))))


def stability_run(item: tuple[float, float, float, int, str]) -> dict[str, Any]:
    """One point of the stability map ``(mu, h omega, zeta, steps, scheme)``: in-process, its fitted growth.

    The suspension has omega = 100 rad/s and damping ratio zeta in both axes, M_s = (m1 + m2) / mu; the
    pendulum hangs straight at rest and the suspension's static load is :data:`MAP_LOAD_STEP` off its
    weight, so the run is the vertical loop of the derivation, set moving by a step of the load. Stable if
    the spectral radius of the step map fitted to the run (:func:`step_map_spectral_radius`) is at most
    1 + :data:`STABILITY_TOLERANCE`; a run that blew up (:class:`~double_pendulum.fmu.masters.coupling.CouplingError`)
    is fitted on the rows it kept.
    """
    from ...model.parameters import PendulumParameters

    mu, h_omega, zeta, steps, scheme = item
    p = PendulumParameters()
    omega = 100.0
    m_s = (p.m1 + p.m2) / mu
    k, c = m_s * omega**2, 2.0 * zeta * m_s * omega
    values = {"phi1_0": 0.0, "phi2_0": 0.0, "M_s": m_s, "k_x": k, "k_y": k, "c_x": c, "c_y": c}
    h = h_omega / omega
    try:
        rows, message = _in_process(values, steps * h, h, scheme, 1.0 + MAP_LOAD_STEP), ""
    except CouplingError as error:
        rows, message = error.rows, str(error)
    rho = step_map_spectral_radius(rows, scheme)
    return {"scheme": scheme, "mass_ratio": mu, "h_omega": h_omega, "zeta": zeta,
            "stable": bool(rho <= 1.0 + STABILITY_TOLERANCE), "spectral_radius_fitted": rho,
            "spectral_radius_derived": spectral_radius(mu, h_omega, zeta, scheme), "steps_run": len(rows) - 1,
            "derived_critical_mass_ratio": critical_mass_ratio(h_omega, zeta, scheme), "message": message}


def run_item(item: tuple[str, tuple]) -> dict[str, Any]:
    """Worker: a split run (``("split", ...)``, :func:`split_run`) or a point of the stability map (``("map", ...)``,
    :func:`stability_run`); here, not in the scenario module, so worker processes do not import Matplotlib."""
    kind, args = item
    return split_run(args) if kind == "split" else stability_run(args)  # type: ignore[arg-type]


def measured_limit(points: list[dict[str, Any]], scheme: str) -> dict[float, tuple[float, float]]:
    """Per h omega, the bracket of the limit: (largest bounded, smallest unbounded mass ratio above it)."""
    result = {}
    points = [p for p in points if p["scheme"] == scheme]
    for hw in sorted({p["h_omega"] for p in points}):
        col = [p for p in points if p["h_omega"] == hw]
        stable = [p["mass_ratio"] for p in col if p["stable"]]
        unstable = [p["mass_ratio"] for p in col if not p["stable"] and p["mass_ratio"] > max(stable, default=0)]
        if stable and unstable:
            result[hw] = (max(stable), min(unstable))
    return result


def cheapest(rows: list[dict[str, Any]], target: float = 1e-4) -> dict[str, dict[str, Any]]:
    """Per case, the stable run with the least CPU time whose angle error is <= ``target`` [rad]."""
    result = {}
    for case in sorted({(r["start"], r["suspension"]) for r in rows}):
        good = [r for r in rows if (r["start"], r["suspension"]) == case and r["stable"]
                and r["angle_error_rad"] <= target]
        if good:
            best = min(good, key=lambda r: r["cpu_s"])
            result[" / ".join(case)] = {k: best[k] for k in ("method", "macro_step_s", "angle_error_rad", "cpu_s")}
    return result
