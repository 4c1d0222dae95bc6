"""The app's page (Dash components): what to run and the run button on top, the form under them on the left, the
run's player and plots on the right (under the form on a narrow screen).

Every number field shows its name, unit and the range offered (:mod:`.form`) and has a message line under it
(``err-NAME``) where a refused value says why as it is typed; a field that does not apply is disabled. What a tab
has run lives in that tab's stores (``job``: the id of its running run, ``result``: its last answer), never on the
server, so two tabs do not see each other's runs.
"""

from __future__ import annotations

from typing import Any

from dash import dcc, html

from .form import (
    LOSSES,
    MODES,
    OWN_PENDULUM,
    PENDULUMS,
    SOLVERS,
    START,
    STOP_TIME,
    SUSPENSION,
    TOLERANCE,
    Field,
    applying,
    notes,
)
from .form import default_values as defaults

POLL_MS = 100
"""How often [ms] a tab asks after its running run."""
LOSS_NAMES = {"air_drag": "air drag on the bobs", "bearing_friction": "rolling friction in the bearings",
              "bearing_drag": "load-independent drag torque in the bearings"}
MEASURED_NOTE = ("Against the measured track runs measured_vs_sim's main prediction, the one the README's horizon "
                 "is about: the seed's pendulum with its rods, the losses fitted to the measured energy decay, and "
                 "the start state and camera geometry fitted to the track's first frames after t0. The form does "
                 "not apply (its fields are disabled); the values used are listed with the run. The first run fits "
                 "them (some 15 s), later runs read the fits from the cache.")
"""What the measured mode runs, shown while it is chosen."""


def number_field(field: Field, value: Any, disabled: bool = False) -> html.Div:
    """A field: its label with the unit, the text box (Enter runs), the range offered and the message line."""
    return html.Div([
        html.Label(field.label, htmlFor=f"in-{field.name}", title=field.description),
        dcc.Input(id=f"in-{field.name}", type="text", inputMode="decimal", value=str(value), debounce=False,
                  disabled=disabled, n_submit=0, style={"width": "7rem"}),
        html.Span(f" {field.range_text()}", className="hint"),
        html.Div(id=f"err-{field.name}", className="field-error", role="alert"),
    ], className="field", title=field.description)


def _group(title: str, children: list, note: tuple[str, str] | None = None) -> html.Fieldset:
    extra = [] if note is None else [html.Div(note[1], id=note[0], className="note")]
    return html.Fieldset([html.Legend(title), *children, *extra])


def actions() -> html.Div:
    """What to run, the run and cancel buttons, the status line and what the mode takes from the form."""
    return html.Div([
        dcc.RadioItems(id="mode", options=[{"label": f" {text}", "value": key} for key, text in MODES.items()],
                       value="case", inline=True, labelClassName="mode"),
        html.Div([html.Button("run", id="run", n_clicks=0, className="primary"),
                  html.Button("cancel", id="cancel", n_clicks=0),
                  html.Span("(or Enter in a field)", className="hint")], className="buttons"),
        html.Div(id="status", role="status"),
        html.Div(MEASURED_NOTE, id="mode-note", className="note", style={"display": "none"}),
    ], className="actions")


def form_panel() -> html.Div:
    """What to run and the run buttons first, then the inputs; the fields that do not apply are disabled
    (:func:`~.form.applying`)."""
    v = defaults()
    needed = {f.name for f in applying(v)[0]}
    pendulum_note, loss_note = notes(v)
    losses = []
    for name, fields in LOSSES.items():
        losses.append(dcc.Checklist(id=f"switch-{name}", options=[{"label": f" {LOSS_NAMES[name]} ({name})",
                                                                   "value": name}], value=[]))
        losses += [number_field(f, v[f.name], f.name not in needed) for f in fields]
    return html.Div([
        actions(),
        _group("start", [number_field(f, v[f.name]) for f in START]),
        _group("the pendulum", [
            dcc.RadioItems(id="pendulum", options=[{"label": f" {text}", "value": key}
                                                   for key, text in PENDULUMS.items()], value=v["pendulum"]),
            *(number_field(f, v[f.name], f.name not in needed) for f in OWN_PENDULUM)],
            ("pendulum-note", pendulum_note)),
        _group("losses (each switched on or off)", losses, ("loss-note", loss_note)),
        _group("the suspension (the pivot on springs and dampers)", [
            dcc.Checklist(id="suspension", options=[{"label": " on", "value": "on"}], value=[]),
            *(number_field(f, v[f.name], f.name not in needed) for f in SUSPENSION)]),
        _group("the run", [
            number_field(STOP_TIME, v["stop_time"]),
            html.Div([html.Label("solver", htmlFor="solver"),
                      dcc.Dropdown(id="solver", options=list(SOLVERS), value=v["solver"], clearable=False,
                                   className="solver"),
                      html.Div(id="err-solver", className="field-error")], className="field"),
            number_field(TOLERANCE, v["rtol"])]),
    ], className="form-panel")


GRAPHS = ("angles", "budget", "path", "compare", "compare2")
"""The plots a run may show (which ones: :mod:`.callbacks`)."""


def results_panel() -> html.Div:
    """The player, what was run, the plots, the CSV download and the fmpy call; hidden until a run is in."""
    return html.Div([
        html.P("Run, and the pendulum swings here, with its plots below.", id="placeholder", className="note"),
        html.Iframe(id="player", title="the pendulum, animated", style={"display": "none"}),
        html.Div(id="run-info"),
        *(html.Div([html.H3(id=f"{g}-title"), dcc.Graph(id=g, responsive=True, config={"displaylogo": False})],
                   id=f"{g}-box", style={"display": "none"}) for g in GRAPHS),
        html.Div([
            html.Button("the run as CSV", id="csv", n_clicks=0), dcc.Download(id="download"),
            html.P("the one fmpy call that reproduces the run:"),
            html.Pre(id="fmpy-call"),
        ], id="gives", style={"display": "none"}),
    ], className="results-panel")


def page() -> html.Div:
    """The whole page."""
    return html.Div([
        html.H1("Double pendulum: change something and watch what happens"),
        html.P("Every run is the FMU DoublePendulum.fmu through fmpy, as the scenarios run it.", className="lead"),
        html.Div([form_panel(), results_panel()], className="columns"),
        dcc.Store(id="job"), dcc.Store(id="ready"), dcc.Store(id="result"),
        dcc.Interval(id="poll", interval=POLL_MS, disabled=True),
    ], className="app")


CSS = """
body { margin: 0; }
.app { font-family: system-ui, sans-serif; margin: 0.75rem 1rem; }
.app h1 { font-size: 1.4rem; margin: 0.2rem 0; }
.app .lead { color: #555; margin: 0.2rem 0 0.6rem; }
.columns { display: flex; flex-wrap: wrap; gap: 1.5rem; align-items: flex-start; }
.form-panel { flex: 0 1 31rem; min-width: 0; }
.results-panel { flex: 1 1 30rem; min-width: 0; }
fieldset { min-width: 0; margin: 0 0 0.6rem; }
.actions { position: sticky; top: 0; z-index: 5; background: #fff; padding: 0.4rem 0 0.5rem;
           border-bottom: 1px solid #ccc; margin-bottom: 0.6rem; }
.actions .mode { margin-right: 0.9rem; white-space: nowrap; }
.buttons { margin: 0.4rem 0; display: flex; flex-wrap: wrap; gap: 0.4rem; align-items: center; }
.buttons button { font-size: 1rem; padding: 0.3rem 0.9rem; }
.buttons button.primary { font-weight: 600; }
#status { white-space: pre-wrap; min-height: 1.2em; }
.field { margin: 0.35rem 0; }
.field label { display: inline-block; width: 8.5rem; }
.field input:disabled { background: #eee; color: #999; }
.field .solver { width: 10rem; display: inline-block; vertical-align: middle; }
.hint { color: #666; font-size: 0.8rem; white-space: nowrap; }
.field-error { color: #b00020; font-size: 0.85rem; }
.note { color: #444; font-size: 0.85rem; margin: 0.3rem 0; }
.note:empty { margin: 0; }
#player { width: 100%; max-width: 520px; height: 640px; border: none; display: block; }
.results-panel h3 { font-size: 1rem; font-weight: 600; margin: 1rem 0 0.2rem; }
#fmpy-call { white-space: pre-wrap; overflow-wrap: anywhere; background: #f6f6f6; padding: 0.5rem;
             font-size: 0.8rem; }
table.used { border-collapse: collapse; font-size: 0.85rem; }
table.used td, table.used th { padding: 0.1rem 0.5rem 0.1rem 0; text-align: left; vertical-align: top; }
@media (max-width: 700px) {
  .app { margin: 0.5rem; }
  .app h1 { font-size: 1.2rem; }
  .actions { position: static; }
  .field label { width: 7.5rem; }
}
"""
"""The page's style: the run buttons first and, on a wide screen, kept in view while the form scrolls; on a narrow
one the columns stack and nothing is wider than the screen. An empty note keeps its place (no ``display: none``):
in Chromium a note in a fieldset that went to ``display: none`` left the text boxes enabled with it without a
layout box (invisible, not focusable)."""
INDEX = ("<!DOCTYPE html>\n<html lang=\"en\"><head>{%metas%}<title>{%title%}</title>{%favicon%}{%css%}"
         f"<style>{CSS}</style></head><body>{{%app_entry%}}<footer>{{%config%}}{{%scripts%}}{{%renderer%}}</footer>"
         "</body></html>")
"""Dash's page template with :data:`CSS`."""
