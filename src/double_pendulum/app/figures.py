"""The app's plots (Plotly), drawn from a run's columns as the FMU reported them: nothing is recomputed.

* the angles over time;
* where the energy went: the pendulum's kinetic and potential energy, the suspension's energy, the work each
  loss mechanism dissipated and minus the work fed in, stacked, with the start's total energy as a line: the
  stack meets the line up to the FMU's ``energy_residual`` (:mod:`double_pendulum.model.outputs`), so the budget
  closes visibly;
* the lower bob's path in the x-y plane;
* two starts a hair apart: the distance of their lower bobs over time, on a log scale (chaos);
* against the measured track: the lower bob measured (camera) and simulated (FMU) in the x-y plane, and the
  distance between them over time.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import plotly.graph_objects as go

from ..model.outputs import OUTPUTS, WORK_NAMES

DESCRIPTIONS = {q.name: q.description for q in OUTPUTS}
BUDGET = ("E_kin", "E_pot", "E_suspension", *WORK_NAMES)
"""The budget's parts, in the order stacked [J]; minus ``W_input`` joins them when inputs fed work in."""
LAYOUT = dict(template="plotly_white", margin=dict(l=70, r=20, t=60, b=60), height=380,
              legend=dict(orientation="h", y=-0.25))


def _figure(title: str, x: str, y: str, **extra: Any) -> go.Figure:
    fig = go.Figure()
    fig.update_layout(title=title, xaxis_title=x, yaxis_title=y, **{**LAYOUT, **extra})
    return fig


def angles_figure(c: Mapping[str, Sequence[float]]) -> go.Figure:
    """Both rods' angles [rad] over time [s]."""
    fig = _figure("the rods' angles over time", "time t [s]", "angle from the downward vertical [rad]")
    for name, label in (("phi1", "upper rod, phi1"), ("phi2", "lower rod, phi2")):
        fig.add_scatter(x=c["time"], y=c[name], mode="lines", name=label)
    return fig


def budget_figure(c: Mapping[str, Sequence[float]]) -> go.Figure:
    """Where the energy went [J]: the stacked budget and the start's total (see the module docstring)."""
    fig = _figure("where the energy went: the budget stacked, and the energy at the start", "time t [s]",
                  "energy [J]")
    for name in BUDGET:
        if np.any(np.asarray(c[name]) != 0.0):
            fig.add_scatter(x=c["time"], y=c[name], mode="lines", stackgroup="budget", line=dict(width=0.5),
                            name=f"{name}: {DESCRIPTIONS[name]}")
    if np.any(np.asarray(c["W_input"]) != 0.0):
        fig.add_scatter(x=c["time"], y=(-np.asarray(c["W_input"])).tolist(), mode="lines", stackgroup="budget",
                        name="minus W_input: work fed in through the inputs")
    start = float(np.asarray(c["E_total"])[0])
    fig.add_scatter(x=[c["time"][0], c["time"][-1]], y=[start, start], mode="lines", name="E_total at the start",
                    line=dict(color="black", dash="dash"))
    residual = float(np.max(np.abs(c["energy_residual"])))
    fig.add_annotation(text=f"the budget closes to {residual:.1e} J (the FMU's energy_residual, largest)",
                       xref="paper", yref="paper", x=0, y=1.06, showarrow=False, xanchor="left")
    return fig


def path_figure(c: Mapping[str, Sequence[float]]) -> go.Figure:
    """The lower bob's path [m] in the x-y plane."""
    fig = _figure("the lower bob's path", "horizontal position x [m]", "vertical position y [m] (up)")
    fig.add_scatter(x=c["x2"], y=c["y2"], mode="lines", name="lower bob", line=dict(width=1))
    fig.update_yaxes(scaleanchor="x", scaleratio=1)
    return fig


def separation_figure(c: Mapping[str, Sequence[float]], twin: Mapping[str, Sequence[float]], nudge: float) -> go.Figure:
    """How far apart [m] the lower bobs of two starts ``nudge`` [rad] apart are over time [s]."""
    n = min(len(c["time"]), len(twin["time"]))
    distance = np.hypot(np.subtract(c["x2"][:n], twin["x2"][:n]), np.subtract(c["y2"][:n], twin["y2"][:n]))
    fig = _figure(f"two starts a hair apart (phi1_0 and phi1_0 + {nudge:g} rad): how far apart their lower bobs are",
                  "time t [s]", "distance of the lower bobs [m] (log scale)", yaxis_type="log")
    fig.add_scatter(x=c["time"][:n], y=np.maximum(distance, 1e-16).tolist(), mode="lines", name="distance")
    return fig


def measured_figures(c: Mapping[str, Sequence[float]], t0: float) -> tuple[go.Figure, go.Figure]:
    """The measured and simulated lower bob [m] in the x-y plane, and their distance [m] over time since t0 [s]."""
    paths = _figure(f"against the measured track: the lower bob from t0 = {t0:.2f} s", "horizontal position x [m]",
                    "vertical position y [m] (up)")
    paths.add_scatter(x=c["x2_measured"], y=c["y2_measured"], mode="markers", marker=dict(size=3, color="black"),
                      name="measured (camera, one dot a frame)")
    paths.add_scatter(x=c["x2_simulated"], y=c["y2_simulated"], mode="lines", line=dict(width=1),
                      name="simulated (FMU): the seed's start, the fitted losses")
    paths.update_yaxes(scaleanchor="x", scaleratio=1)
    error = np.hypot(np.subtract(c["x2_simulated"], c["x2_measured"]), np.subtract(c["y2_simulated"], c["y2_measured"]))
    errors = _figure("how far the simulated lower bob is from the measured one", "time since t0 [s]",
                     "distance [m]")
    errors.add_scatter(x=c["t_since_t0"], y=error.tolist(), mode="lines", name="lower bob")
    return paths, errors
