"""The app's callbacks: check the form as it is typed, disable what does not apply, start a run, follow it, cancel
it, and draw its answer.

* :func:`register`'s ``check`` writes each refused value's message under its field as it is typed, and
  ``applies`` disables the fields that do not apply (:func:`~.form.applying`) and says why;
* one callback owns a tab's run: the run button, or Enter in a field, checks the form again
  (:func:`~.form.check_form`) and either says that values are refused (the page then scrolls to the first) or
  starts the run (:class:`~.worker.Runs`) and keeps its id in the tab's ``job`` store; the tab's timer then asks
  after it until its answer is in, and ``cancel`` ends it;
* a callback collects the answer (the FMU's message when the FMU stopped the run), one draws it and brings the
  player into view, one gives it as CSV.
"""

from __future__ import annotations

from typing import Any

from dash import Dash, Input, Output, State, ctx, dcc, html, no_update

from ..case import Case
from ..runs.player import player_data as player_table
from ..runs.player import standalone_html, swing_data
from ..runs.results_io import column_header
from . import figures
from .form import LOSSES, MODES, NUMBER_FIELDS, OUTPUT_INTERVAL_S, PENDULUMS, applying, check_form, notes
from .layout import GRAPHS, LOSS_NAMES
from .measured import call_text
from .worker import Runs

HIDDEN, SHOWN = {"display": "none"}, {"display": "block"}
NAMES = [f.name for f in NUMBER_FIELDS] + ["solver"]
"""The fields with a message line, in the order of the callbacks' outputs."""


def _form(kind: type = Input) -> dict[str, Any]:
    """The whole form as a callback reads it: each component's value as an Input (or a State)."""
    return dict(values=[kind(f"in-{f.name}", "value") for f in NUMBER_FIELDS], mode=kind("mode", "value"),
                pendulum=kind("pendulum", "value"), switches=[kind(f"switch-{name}", "value") for name in LOSSES],
                suspension=kind("suspension", "value"), solver=kind("solver", "value"))


FORM = _form()
REFUSED = "some values are refused: see the messages under them"
FOCUS_FIRST_REFUSED = """function(status) {
    if (status && status.startsWith('some values are refused')) {
        const message = [...document.querySelectorAll('.field-error')].find(e => e.textContent);
        const input = message && message.parentElement.querySelector('input');
        if (input) { input.scrollIntoView({block: 'center'}); input.focus({preventScroll: true}); }
    }
    return window.dash_clientside.no_update;
}"""
SHOW_PLAYER = """function(srcdoc) {
    const frame = document.getElementById('player');
    if (!srcdoc || !frame) { return window.dash_clientside.no_update; }
    const fit = () => {
        const doc = frame.contentDocument;
        if (doc && doc.body && doc.body.firstElementChild) {  // the body's bottom and margin: the page's height
            const margin = parseFloat(doc.defaultView.getComputedStyle(doc.body).marginBottom) || 0;
            frame.style.height = Math.ceil(doc.body.getBoundingClientRect().bottom + margin) + 'px';
        }
    };
    if (!frame.dataset.fitted) {
        frame.addEventListener('load', fit);
        new ResizeObserver(fit).observe(frame);
        frame.dataset.fitted = 'yes';
    }
    setTimeout(() => { fit(); frame.scrollIntoView({block: 'start', behavior: 'instant'}); }, 50);
    return window.dash_clientside.no_update;
}"""
"""After a run is drawn: the player's frame as high as what it holds (again when its width changes), and the
player scrolled into view."""


def form_of(values: list[Any], mode: str, pendulum: str, switches: list[list[str] | None], suspension: list[str],
            solver: str) -> dict[str, Any]:  # fmt: skip
    """The form as :func:`~.form.check_form` takes it, from the components' values."""
    form = {f.name: v for f, v in zip(NUMBER_FIELDS, values)}
    return {**form, "mode": mode, "pendulum": pendulum, "switches": [s for chosen in switches for s in chosen or ()],
            "suspension": bool(suspension), "solver": solver}


def _answer_text(answer: dict[str, Any]) -> str:
    if answer.get("message") == "cancelled":
        return "cancelled"
    if answer.get("message"):
        return f"the FMU stopped the run: {answer['message']}"
    return "done"


def measured_info(result: dict[str, Any]) -> html.Div:
    """What the run against the measured track used (each value, its error where fitted, where it comes from) and
    how long its lower bob stayed within 5 cm of the camera's."""
    h = result["horizon"]
    horizon = (f"the whole {result['span_s']:.2f} s compared" if h["censored"] else f"{h['horizon_s']:.2f} s")
    raw = "the whole record" if h["raw_horizon_s"] is None else f"{h['raw_horizon_s']:.2f} s"
    rows = [html.Tr([html.Th("value"), html.Th(""), html.Th("from")])]
    for u in result["used"]:
        value = f"{u['value']:.6g}" if isinstance(u["value"], float) else str(u["value"])
        error = f" \u00b1 {u['stderr']:.2g}" if u["stderr"] is not None else ""
        rows.append(html.Tr([html.Td(u["name"]), html.Td(value + error), html.Td(u["what"])]))
    return html.Div([
        html.P(f"Against the measured track, from t0 = {result['t0']:.4f} s: the start and camera geometry fitted to "
               f"the track's first {result['fit_frames']} frames, the losses to the measured decay; the form did not "
               f"apply. The simulated lower bob stays within 5 cm of the measured one (smoothed over "
               f"{result['smoothing_s']:g} s) for "
               f"{horizon}, frame by frame for {raw} (measured_vs_sim's headline horizons, for this loss "
               "model).", className="note"),
        html.Details([html.Summary("the values this run used"), html.Table(rows, className="used")], open=False),
    ])


def register(app: Dash, runs: Runs) -> None:
    """Register the callbacks on ``app``, its runs in ``runs``."""

    # Neither runs when the page opens: the page is drawn with the defaults' messages (none) and disabled fields
    # (:mod:`.layout`), and a first reply that came after a user's first click would undo that click.
    @app.callback(output=[Output(f"err-{name}", "children") for name in NAMES], inputs=FORM, prevent_initial_call=True)
    def check(values: list[Any], mode: str, pendulum: str, switches: list, suspension: list, solver: str) -> list:
        errors = check_form(form_of(values, mode, pendulum, switches, suspension, solver)).errors
        return [errors.get(name, "") for name in NAMES]

    @app.callback(
        output=dict(disabled=[Output(f"in-{f.name}", "disabled") for f in NUMBER_FIELDS],
                    pendulum=Output("pendulum", "options"), solver=Output("solver", "disabled"),
                    switches=[Output(f"switch-{name}", "options") for name in LOSSES],
                    suspension=Output("suspension", "options"), mode_note=Output("mode-note", "style"),
                    pendulum_note=Output("pendulum-note", "children"), loss_note=Output("loss-note", "children")),
        inputs={k: v for k, v in FORM.items() if k not in ("values", "solver")}, prevent_initial_call=True,
    )
    def applies(mode: str, pendulum: str, switches: list, suspension: list) -> dict[str, Any]:
        form = form_of([], mode, pendulum, switches, suspension, "")
        needed = {f.name for f in applying(form)[0]}
        measured = mode == "measured"
        pendulum_note, loss_note = notes(form)
        return dict(
            disabled=[f.name not in needed for f in NUMBER_FIELDS],
            pendulum=[{"label": f" {text}", "value": key, "disabled": measured} for key, text in PENDULUMS.items()],
            solver=measured,
            switches=[[{"label": f" {LOSS_NAMES[name]} ({name})", "value": name,
                        "disabled": measured or pendulum == "frictionless"}] for name in LOSSES],
            suspension=[{"label": " on", "value": "on", "disabled": measured}],
            mode_note=SHOWN if measured else HIDDEN, pendulum_note=pendulum_note, loss_note=loss_note)

    app.clientside_callback(FOCUS_FIRST_REFUSED, Output("status", "title"), Input("status", "children"),
                            prevent_initial_call=True)
    app.clientside_callback(SHOW_PLAYER, Output("player", "title"), Input("player", "srcDoc"),
                            prevent_initial_call=True)

    @app.callback(
        output=dict(job=Output("job", "data"), ready=Output("ready", "data"), poll=Output("poll", "disabled"),
                    status=Output("status", "children")),
        inputs=dict(run=Input("run", "n_clicks"), cancel=Input("cancel", "n_clicks"),
                    tick=Input("poll", "n_intervals"),
                    enter=[Input(f"in-{f.name}", "n_submit") for f in NUMBER_FIELDS]),
        state=dict(**_form(State), job=State("job", "data")),
        prevent_initial_call=True,
    )
    def control(run: int, cancel: int, tick: int, enter: list, values: list, mode: str, pendulum: str,
                switches: list, suspension: list, solver: str, job: dict[str, Any] | None) -> dict[str, Any]:
        answer = dict(job=no_update, ready=no_update, poll=no_update, status=no_update)
        trigger = ctx.triggered_id
        if trigger == "cancel":
            if not job:
                return {**answer, "poll": True, "status": "nothing is running"}
            runs.cancel(job["id"])
            return {**answer, "job": None, "poll": True, "status": "cancelled"}
        if trigger == "poll":
            if not job:
                return {**answer, "job": None, "poll": True}
            polled = runs.poll(job["id"])
            if polled is None:  # its answer went to an earlier request of this tab
                return answer
            done, result = polled
            if result is None:
                what = MODES[job["kind"]]
                length = "" if job["kind"] == "measured" else f" of {job['stop_time']:g} s"
                return {**answer, "poll": False, "status": f"running {what}: {100 * done:.0f} %{length}"}
            # The timer stops and ``collect`` fetches the answer in a request of its own: a reply the browser drops
            # because the timer's next request overtook it (Dash keeps only a callback's latest) is a small one,
            # and the next tick says the same.
            return {**answer, "ready": job["id"], "poll": True, "status": "the run is done: reading its answer"}
        if job:
            return {**answer, "poll": False, "status": "a run is still going: cancel it first"}
        if trigger != "run" and not any(enter):
            return answer
        checked = check_form(form_of(values, mode, pendulum, switches, suspension, solver))
        if checked.errors:
            return {**answer, "job": None, "poll": True, "status": REFUSED}
        kind = mode if mode in MODES else "case"
        stop_time = 1.0 if kind == "measured" else checked.stop_time  # measured: progress as a fraction
        run_id = runs.start(kind, checked.start_values, stop_time, OUTPUT_INTERVAL_S)
        job = {"id": run_id, "kind": kind, "start_values": checked.start_values, "stop_time": stop_time,
               "fmu": str(runs.fmu)}
        return {**answer, "job": job, "poll": False, "status": f"running {MODES[kind]}: 0 %"}

    @app.callback(
        Output("result", "data"), Output("job", "data", allow_duplicate=True),
        Output("status", "children", allow_duplicate=True),
        Input("ready", "data"), State("job", "data"), prevent_initial_call=True,
    )
    def collect(ready: str | None, job: dict[str, Any] | None) -> tuple:
        if not ready or not job or job["id"] != ready:
            return no_update, no_update, no_update
        answer = runs.collect(ready)
        if answer is None:  # collected by an earlier request of this tab
            return no_update, no_update, no_update
        return {**job, **answer} if answer.get("columns") else no_update, None, _answer_text(answer)

    @app.callback(
        output=dict(player=Output("player", "srcDoc"), player_style=Output("player", "style"),
                    figures=[Output(g, "figure") for g in GRAPHS], titles=[Output(f"{g}-title", "children")
                                                                           for g in GRAPHS],
                    boxes=[Output(f"{g}-box", "style") for g in GRAPHS], info=Output("run-info", "children"),
                    call=Output("fmpy-call", "children"), gives=Output("gives", "style"),
                    placeholder=Output("placeholder", "style")),
        inputs=dict(result=Input("result", "data")), prevent_initial_call=True,
    )
    def draw(result: dict[str, Any] | None) -> dict[str, Any]:
        if not result or not result.get("columns"):
            return dict(player=no_update, player_style=no_update, figures=[no_update] * len(GRAPHS),
                        titles=[no_update] * len(GRAPHS), boxes=[no_update] * len(GRAPHS), info=no_update,
                        call=no_update, gives=no_update, placeholder=no_update)
        c = result["columns"]
        plots: dict[str, tuple[str, Any]] = {}
        if result["kind"] == "measured":
            swings = [swing_data("camera", "k", *(c[f"{k}_measured"] for k in ("x1", "y1", "x2", "y2")), links=False),
                      swing_data("FMU", "C0", *(c[f"{k}_simulated"] for k in ("x1", "y1", "x2", "y2")),
                                 pivot=(c["pivot_x_simulated"][0], c["pivot_y_simulated"][0]))]
            data = player_table(c["t_since_t0"], swings, "measured (camera) and simulated (FMU) pendulum",
                                time_label="t - t0")
            plots["compare"], plots["compare2"] = figures.measured_figures(c, result["t0"], result["error_smoothed"],
                                                                           result["smoothing_s"])
            info = measured_info(result)
            call = call_text(result["fmu"], result)
        else:
            swings = [swing_data("your case", "C0", c["x1"], c["y1"], c["x2"], c["y2"],
                                 pivot=(c["xs"], c["ys"]))]
            if result.get("twin"):
                t = result["twin"]
                swings.append(swing_data("a hair apart", "C3", t["x1"], t["y1"], t["x2"], t["y2"],
                                         pivot=(t["xs"], t["ys"])))
                plots["compare"] = figures.separation_figure(c, t, result["nudge_rad"])
            data = player_table(c["time"], swings, "the pendulum, from the FMU's positions")
            plots["angles"], plots["budget"], plots["path"] = (figures.angles_figure(c), figures.budget_figure(c),
                                                               figures.path_figure(c))
            info = None
            # The browser's store gives 2.0 back as 2: every number of the form is real, so it is a float again.
            start = {k: float(v) if type(v) is int else v for k, v in result["start_values"].items()}
            call = "import fmpy\n\nresult = " + Case(result["fmu"], start, float(result["stop_time"]),
                                                     OUTPUT_INTERVAL_S).fmpy_call()
        return dict(player=standalone_html(data), player_style=SHOWN,
                    figures=[plots[g][1] if g in plots else no_update for g in GRAPHS],
                    titles=[plots[g][0] if g in plots else no_update for g in GRAPHS],
                    boxes=[SHOWN if g in plots else HIDDEN for g in GRAPHS], info=info, call=call, gives=SHOWN,
                    placeholder=HIDDEN)

    @app.callback(Output("download", "data"), Input("csv", "n_clicks"), State("result", "data"),
                  prevent_initial_call=True)
    def download(_: int, result: dict[str, Any] | None) -> Any:
        if not result or not result.get("columns"):
            return no_update
        c, units = result["columns"], result.get("units") or {}
        names = list(c)
        lines = [",".join(column_header(n, units.get(n, "s" if n == "time" else "")) for n in names)]
        lines += [",".join(repr(c[n][i]) for n in names) for i in range(len(c[names[0]]))]
        return dcc.send_string("\n".join(lines) + "\n", f"double_pendulum_{result['kind']}.csv")
