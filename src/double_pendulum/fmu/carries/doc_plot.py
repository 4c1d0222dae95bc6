"""The result plot of an FMU's documentation: its default run, computed and drawn at build.

Each FMU's ``documentation/result.png`` shows what the FMU computes from its own defaults (the start
values baked into the build included) over its default experiment, as Reference-FMUs' documentation
shows an fmusim run. It is computed in-process with the component the FMU runs (the same numbers as
the FMU, ``tests/test_fmu.py``); the pendulum on its suspension with the coupling the container steps
(:func:`double_pendulum.fmu.masters.coupling.run_coupled`, ``jacobi_sequential``, its macro step). The
Suspension's defaults leave it at rest, so its plot applies a load step (:data:`SUSPENSION_STEP`).

Plots are kept per process, keyed by everything they show (a build writes several FMUs of one
scene; the test session builds the set several times).
"""

from __future__ import annotations

import functools
import io
import json
from collections.abc import Mapping, Sequence
from typing import Any

from ...component.suspension import INPUT_START
from ...component.variables import INTERFACES
from .. import presets
from ..masters.simulate import communication_points

SUSPENSION_STEP = {"F_x": 1.0, "F_y": INPUT_START["F_y"] - 1.0}
"""The Suspension plot's load [N]: 1 N horizontally and 1 N down on top of the static load, from t = 0."""
PLOTTED = {
    "DoublePendulum": (("phi1", "phi2"), ("omega1", "omega2")),
    "Suspension": (("x", "y"), ("E_suspension", "W_suspension", "W_in")),
    "PendulumOnSuspension": (("DoublePendulum.phi1", "DoublePendulum.phi2"), ("Suspension.x", "Suspension.y")),
}


QUANTITY = {"rad": "angle", "rad/s": "angular velocity", "m": "position", "J": "energy"}


def unit_of(name: str) -> str:
    """The unit of a plotted output (``Suspension.x``: m), as its FMU's interface gives it."""
    owner, _, base = name.rpartition(".")
    interfaces = [INTERFACES[owner]] if owner else list(INTERFACES.values())
    return next(v.unit for interface in interfaces for v in interface.variables() if v.name == base)


def axis_label(names: list[str]) -> str:
    """A y-axis label in words with the unit: ``angle [rad]``."""
    units = list(dict.fromkeys(unit_of(n) for n in names))
    return " / ".join(f"{QUANTITY.get(unit, 'value')} [{unit}]" for unit in units)


def run(
    model: str, start_values: Mapping[str, Any], stop_time: float, interval: float,
    names: Sequence[str] | None = None, load: Mapping[str, float] | None = None, macro_step: float | None = None,
) -> dict[str, list[float]]:
    """The model's run from ``start_values`` to ``stop_time`` [s], every ``interval`` [s]: ``time`` and
    ``names`` (the outputs of :data:`PLOTTED` by default), as lists.

    ``load``: the Suspension's inputs (its default inputs leave it at rest; the plot applies
    :data:`SUSPENSION_STEP`); ``macro_step`` [s]: the coupled system's (``interval`` by default; ``interval``
    must be a multiple of it).

    Runs are kept per process for the same arguments, as plots are: a process that builds the FMUs again (the
    tests, the cross-check tree's cases) computes each reference once; each call gets lists of its own.
    """
    load_json = json.dumps(None if load is None else dict(load), sort_keys=True)
    rows = _run(model, json.dumps(dict(start_values), sort_keys=True), float(stop_time), float(interval),
                None if names is None else tuple(names), load_json, macro_step)
    return {name: list(values) for name, values in rows.items()}


@functools.lru_cache(maxsize=32)
def _run(model: str, start_json: str, stop_time: float, interval: float, names: tuple[str, ...] | None,
         load_json: str, macro_step: float | None) -> dict[str, list[float]]:
    start_values, load = json.loads(start_json), json.loads(load_json)
    names = list(names) if names is not None else [n for group in PLOTTED[model] for n in group]
    if model == "PendulumOnSuspension":
        return _coupled(start_values, stop_time, interval, names, macro_step or interval)
    component = presets.COMPONENTS[model]()
    for name, value in start_values.items():
        component.set(name, value)
    for name, value in (load or {}).items():
        component.set_input(name, value)
    component.initialise()
    rows = {"time": [component.time], **{n: [component.outputs[n]] for n in names}}
    for current, step in communication_points(0.0, stop_time, interval):
        component.do_step(current, step)
        rows["time"].append(component.time)
        for name in names:
            rows[name].append(component.outputs[name])
    return rows


def _coupled(values: Mapping[str, Any], stop_time: float, interval: float, names: Sequence[str],
             macro_step: float) -> dict[str, list[float]]:
    """The container's components as it couples them: ``values`` and ``names`` are the container's
    (``DoublePendulum.phi1_0``, ``Suspension.x``); rows every ``interval`` [s], a multiple of ``macro_step``.

    The container steps both components over a macro step, then passes the connections, the force first
    (``jacobi_sequential``, :func:`double_pendulum.fmu.masters.coupling.sequential_exchange`), and a host reads its
    outputs after that: the outputs that follow their inputs at once (the pivot force, the suspension's
    acceleration) are recorded after the exchange too.
    """
    from ..masters.coupling import sequential_exchange

    every = round(interval / macro_step)
    if every < 1 or abs(every * macro_step - interval) > 1e-9 * interval:
        raise ValueError(f"interval = {interval:g} s is no multiple of the macro step {macro_step:g} s")
    components = {name: presets.COMPONENTS[name]() for name in ("DoublePendulum", "Suspension")}
    for name, value in values.items():
        owner, _, parameter = name.partition(".")
        components[owner].set(parameter, value)
    for component in components.values():
        component.initialise()
    pendulum, suspension = components["DoublePendulum"], components["Suspension"]
    sources = [(components[owner], base) for owner, _, base in (n.partition(".") for n in names)]
    sequential_exchange(pendulum, suspension)
    rows = {"time": [0.0], **{n: [c.get(b)] for n, (c, b) in zip(names, sources)}}
    for k, (current, step) in enumerate(communication_points(0.0, stop_time, macro_step), start=1):
        pendulum.do_step(current, step)
        suspension.do_step(current, step)
        sequential_exchange(pendulum, suspension)
        if k % every == 0:
            rows["time"].append(k // every * interval)  # fmpy's grid: start + n * interval
            for name, (component, base) in zip(names, sources):
                rows[name].append(component.get(base))
    return rows


def result_plot(model: str, start_values: Mapping[str, Any], stop_time: float, interval: float) -> bytes:
    """The PNG of :func:`run` (kept per process for the same arguments)."""
    return _plot(model, json.dumps(dict(start_values), sort_keys=True), float(stop_time), float(interval))


@functools.lru_cache(maxsize=32)
def _plot(model: str, start_values: str, stop_time: float, interval: float) -> bytes:
    from matplotlib.figure import Figure

    rows = run(model, json.loads(start_values), stop_time, interval,
               load=SUSPENSION_STEP if model == "Suspension" else None)
    time = rows["time"]
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    for ax, group in zip(axes, PLOTTED[model]):
        shown = [n for n in group if any(rows[n])]
        for name in shown:
            ax.plot(time, rows[name], label=name, linewidth=1.0)
        ax.set_ylabel(axis_label(shown))
        ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), fontsize=8, ncols=max(len(shown), 1),
                  frameon=False, borderaxespad=0.1)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    return buffer.getvalue()

