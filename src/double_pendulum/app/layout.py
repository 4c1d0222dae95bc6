"""The app's page (Dash components): the form on the left, the run's player and plots on the right.

Every number field shows its name, unit and the range offered (:mod:`.form`) and has a message line under it
(``err-NAME``) where a refused value says why. What a tab has run lives in that tab's stores (``job``: the id
of its running run, ``result``: its last answer), never on the server, so two tabs do not see each other's runs.
"""

from __future__ import annotations

from typing import Any

from dash import dcc, html

from .form import LOSSES, OWN_PENDULUM, PENDULUMS, SOLVERS, START, STOP_TIME, SUSPENSION, TOLERANCE, Field
from .form import default_values as defaults

POLL_MS = 100
"""How often [ms] a tab asks after its running run."""
LOSS_NAMES = {"air_drag": "air drag on the bobs", "bearing_friction": "rolling friction in the bearings",
              "bearing_drag": "load-independent drag torque in the bearings"}
STYLE = {"field": {"margin": "0.35rem 0"}, "error": {"color": "#b00020", "fontSize": "0.85rem"},
         "hint": {"color": "#666", "fontSize": "0.8rem"}}


def number_field(field: Field, value: Any) -> html.Div:
    """A field: its label with the unit, the text box, the range offered and the message line."""
    return html.Div([
        html.Label(field.label, htmlFor=f"in-{field.name}", title=field.description,
                   style={"display": "inline-block", "width": "8.5rem"}),
        dcc.Input(id=f"in-{field.name}", type="text", inputMode="decimal", value=str(value), debounce=False,
                  style={"width": "7rem"}),
        html.Span(f" {field.range_text()}", style=STYLE["hint"]),
        html.Div(id=f"err-{field.name}", className="field-error", style=STYLE["error"]),
    ], style=STYLE["field"], title=field.description)


def _group(title: str, children: list) -> html.Fieldset:
    return html.Fieldset([html.Legend(title), *children], style={"marginBottom": "0.6rem"})


def form_panel() -> html.Div:
    """The inputs, the run buttons and the status line."""
    v = defaults()
    losses = []
    for name, fields in LOSSES.items():
        losses.append(dcc.Checklist(id=f"switch-{name}", options=[{"label": f" {LOSS_NAMES[name]} ({name})",
                                                                   "value": name}], value=[]))
        losses += [number_field(f, v[f.name]) for f in fields]
    return html.Div([
        _group("start", [number_field(f, v[f.name]) for f in START]),
        _group("the pendulum", [
            dcc.RadioItems(id="pendulum", options=[{"label": f" {text}", "value": key}
                                                   for key, text in PENDULUMS.items()], value=v["pendulum"]),
            *(number_field(f, v[f.name]) for f in OWN_PENDULUM)]),
        _group("losses (each switched on or off)", losses),
        _group("the suspension (the pivot on springs and dampers)", [
            dcc.Checklist(id="suspension", options=[{"label": " on", "value": "on"}], value=[]),
            *(number_field(f, v[f.name]) for f in SUSPENSION)]),
        _group("the run", [
            number_field(STOP_TIME, v["stop_time"]),
            html.Div([html.Label("solver", htmlFor="solver", style={"display": "inline-block", "width": "8.5rem"}),
                      dcc.Dropdown(id="solver", options=list(SOLVERS), value=v["solver"], clearable=False,
                                   style={"width": "10rem", "display": "inline-block", "verticalAlign": "middle"}),
                      html.Div(id="err-solver", style=STYLE["error"])], style=STYLE["field"]),
            number_field(TOLERANCE, v["rtol"])]),
        html.Div([
            html.Button("run", id="run", n_clicks=0),
            html.Button("two starts a hair apart", id="run-twins", n_clicks=0, style={"marginLeft": "0.4rem"}),
            html.Button("against the measured track", id="run-measured", n_clicks=0, style={"marginLeft": "0.4rem"}),
            html.Button("cancel", id="cancel", n_clicks=0, style={"marginLeft": "0.4rem"}),
        ]),
        html.Div(id="status", role="status", style={"margin": "0.6rem 0", "whiteSpace": "pre-wrap"}),
    ], style={"flex": "0 0 31rem"})


def results_panel() -> html.Div:
    """The player, the plots, the CSV download and the fmpy call."""
    return html.Div([
        html.Iframe(id="player", style={"width": "520px", "height": "640px", "border": "none"}),
        dcc.Graph(id="angles", style={"display": "none"}),
        dcc.Graph(id="budget", style={"display": "none"}),
        dcc.Graph(id="path", style={"display": "none"}),
        dcc.Graph(id="compare", style={"display": "none"}),
        dcc.Graph(id="compare2", style={"display": "none"}),
        html.Div([html.Button("the run as CSV", id="csv", n_clicks=0), dcc.Download(id="download")]),
        html.P("the one fmpy call that reproduces the run:"),
        html.Pre(id="fmpy-call", style={"whiteSpace": "pre-wrap", "background": "#f6f6f6", "padding": "0.5rem"}),
    ], style={"flex": "1 1 40rem", "minWidth": "0"})


def page() -> html.Div:
    """The whole page."""
    return html.Div([
        html.H1("Double pendulum: change something and watch what happens", style={"fontSize": "1.5rem"}),
        html.P("Every run is the FMU DoublePendulum.fmu through fmpy, as the scenarios run it.",
               style={"color": "#555"}),
        html.Div([form_panel(), results_panel()], style={"display": "flex", "gap": "1.5rem", "flexWrap": "wrap"}),
        dcc.Store(id="job"), dcc.Store(id="ready"), dcc.Store(id="result"),
        dcc.Interval(id="poll", interval=POLL_MS, disabled=True),
    ], style={"fontFamily": "system-ui, sans-serif", "margin": "1rem"})
