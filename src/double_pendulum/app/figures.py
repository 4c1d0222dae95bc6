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

Each function returns the plot's title and the figure: the page sets the title above the figure as text, which
wraps on a narrow screen where a title inside the figure would be cut, and each legend (short names, the FMU's
description on hover) sits below its plot.
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
LAYOUT = dict(template="plotly_white", margin=dict(l=10, r=10, t=30, b=10), height=400,
              legend=dict(orientation="h", yanchor="top", y=-0.18, xanchor="left", x=0),
              xaxis=dict(automargin=True), yaxis=dict(automargin=True))
"""Each plot's layout: the margins grow to hold the axes' titles and numbers (``automargin``), the legend below."""
SHORT = {"E_kin": "kinetic", "E_pot": "potential", "E_suspension": "suspension's", "W_air": "air drag",
         "W_bearing": "bearing friction", "W_bearing_drag": "bearing drag", "W_suspension": "suspension dampers"}
"""The budget's legend: each part's name and a word (its full description shows on hover)."""
Titled = tuple[str, go.Figure]
"""A plot's title and its figure."""


def _figure(x: str, y: str, **extra: Any) -> go.Figure:
    fig = go.Figure()
    fig.update_layout(xaxis_title=x, yaxis_title=y, **{**LAYOUT, **extra})
    return fig


def angles_figure(c: Mapping[str, Sequence[float]]) -> Titled:
    """Both rods' angles [rad] over time [s]."""
    fig = _figure("time t [s]", "angle [rad]")
    for name, label in (("phi1", "upper rod, phi1"), ("phi2", "lower rod, phi2")):
        fig.add_scatter(x=c["time"], y=c[name], mode="lines", name=label)
    return "the rods' angles from the downward vertical", fig


def budget_figure(c: Mapping[str, Sequence[float]]) -> Titled:
    """Where the energy went [J]: the stacked budget and the start's total (see the module docstring); the title
    says how closely the budget closes (the FMU's ``energy_residual``, largest)."""
    fig = _figure("time t [s]", "energy [J]")
    for name in BUDGET:
        if np.any(np.asarray(c[name]) != 0.0):
            fig.add_scatter(x=c["time"], y=c[name], mode="lines", stackgroup="budget", line=dict(width=0.5),
                            name=f"{name} ({SHORT[name]})", hovertemplate=f"{DESCRIPTIONS[name]}: %{{y:.4g}} J")
    if np.any(np.asarray(c["W_input"]) != 0.0):
        fig.add_scatter(x=c["time"], y=(-np.asarray(c["W_input"])).tolist(), mode="lines", stackgroup="budget",
                        name="minus W_input (fed in)", hovertemplate=f"minus {DESCRIPTIONS['W_input']}: %{{y:.4g}} J")
    start = float(np.asarray(c["E_total"])[0])
    fig.add_scatter(x=[c["time"][0], c["time"][-1]], y=[start, start], mode="lines", name="E_total at the start",
                    line=dict(color="black", dash="dash"))
    residual = float(np.max(np.abs(c["energy_residual"])))
    return (f"where the energy went: the budget stacked against the energy at the start (it closes to "
            f"{residual:.1e} J, the FMU's energy_residual)"), fig


def path_figure(c: Mapping[str, Sequence[float]]) -> Titled:
    """The lower bob's path [m] in the x-y plane."""
    fig = _figure("horizontal position x [m]", "vertical position y [m] (up)", showlegend=False)
    fig.add_scatter(x=c["x2"], y=c["y2"], mode="lines", name="lower bob", line=dict(width=1))
    fig.update_yaxes(scaleanchor="x", scaleratio=1)
    return "the lower bob's path", fig


def separation_figure(c: Mapping[str, Sequence[float]], twin: Mapping[str, Sequence[float]], nudge: float) -> Titled:
    """How far apart [m] the lower bobs of two starts ``nudge`` [rad] apart are over time [s]."""
    n = min(len(c["time"]), len(twin["time"]))
    distance = np.hypot(np.subtract(c["x2"][:n], twin["x2"][:n]), np.subtract(c["y2"][:n], twin["y2"][:n]))
    fig = _figure("time t [s]", "distance [m] (log scale)", yaxis_type="log", showlegend=False)
    fig.add_scatter(x=c["time"][:n], y=np.maximum(distance, 1e-16).tolist(), mode="lines", name="distance")
    return (f"two starts a hair apart (phi1_0 and phi1_0 + {nudge:g} rad): how far apart their lower bobs are"), fig


def measured_figures(c: Mapping[str, Sequence[float]], t0: float, error_smoothed: Sequence[float],
                     smoothing_s: float) -> tuple[Titled, Titled]:  # fmt: skip
    """The measured and simulated lower bob [m] in the x-y plane, and their distance [m] over time since t0 [s],
    frame by frame and smoothed over ``smoothing_s`` [s] as the horizon is (``error_smoothed``)."""
    paths = _figure("horizontal position x [m]", "vertical position y [m] (up)")
    paths.add_scatter(x=c["x2_measured"], y=c["y2_measured"], mode="markers", marker=dict(size=3, color="black"),
                      name="measured (camera, one dot a frame)")
    paths.add_scatter(x=c["x2_simulated"], y=c["y2_simulated"], mode="lines", line=dict(width=1),
                      name="simulated (FMU): the fitted start")
    paths.update_yaxes(scaleanchor="x", scaleratio=1)
    error = np.hypot(np.subtract(c["x2_simulated"], c["x2_measured"]), np.subtract(c["y2_simulated"], c["y2_measured"]))
    errors = _figure("time since t0 [s]", "distance [m]")
    errors.add_scatter(x=c["t_since_t0"], y=error.tolist(), mode="lines", name="frame by frame",
                       line=dict(width=1, color="#9db4e8"))
    errors.add_scatter(x=c["t_since_t0"], y=list(error_smoothed), mode="lines", name=f"smoothed over {smoothing_s:g} s",
                       line=dict(width=2, color="#1f3f99"))
    errors.add_hline(y=0.05, line=dict(color="grey", dash="dot"), annotation_text="5 cm",
                     annotation_position="top left")
    return ((f"against the measured track: the lower bob from t0 = {t0:.2f} s", paths),
            ("how far the simulated lower bob is from the measured one", errors))
