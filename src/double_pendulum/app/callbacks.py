"""The app's callbacks: check the form, start a run, follow it, cancel it, and draw its answer.

One callback owns a tab's run (:func:`register`): a click on a run button checks the form (:func:`~.form.check_form`)
and either writes each refusal under its field or starts the run (:class:`~.worker.Runs`) and keeps its id in the
tab's ``job`` store; the tab's timer then asks after it until its answer is in, and ``cancel`` ends it. A second
callback collects the answer (the FMU's message when the FMU stopped the run), a third draws it, a fourth gives it
as CSV.
"""

from __future__ import annotations

from typing import Any

from dash import Dash, Input, Output, State, ctx, dcc, no_update

from ..case import Case
from ..runs.player import player_data as player_table
from ..runs.player import standalone_html, swing_data
from ..runs.results_io import column_header
from . import figures
from .form import LOSSES, NUMBER_FIELDS, OUTPUT_INTERVAL_S, check_form
from .worker import Runs

BUTTONS = {"run": "case", "run-twins": "twins", "run-measured": "measured"}
HIDDEN, SHOWN = {"display": "none"}, {"display": "block"}


def _form(values: list[Any], pendulum: str, switches: list[list[str]], suspension: list[str],
          solver: str) -> dict[str, Any]:  # fmt: skip
    form = {f.name: v for f, v in zip(NUMBER_FIELDS, values)}
    return {**form, "pendulum": pendulum, "switches": [s for chosen in switches for s in chosen or ()],
            "suspension": bool(suspension), "solver": solver}


def _answer_text(answer: dict[str, Any]) -> str:
    if answer.get("message") == "cancelled":
        return "cancelled"
    if answer.get("message"):
        return f"the FMU stopped the run: {answer['message']}"
    return "done"


def register(app: Dash, runs: Runs) -> None:
    """Register the callbacks on ``app``, its runs in ``runs``."""
    errors = [Output(f"err-{f.name}", "children") for f in NUMBER_FIELDS] + [Output("err-solver", "children")]
    names = [f.name for f in NUMBER_FIELDS] + ["solver"]

    @app.callback(
        Output("job", "data"), Output("ready", "data"), Output("poll", "disabled"), Output("status", "children"),
        *errors,
        Input("run", "n_clicks"), Input("run-twins", "n_clicks"), Input("run-measured", "n_clicks"),
        Input("cancel", "n_clicks"), Input("poll", "n_intervals"),
        *(State(f"in-{f.name}", "value") for f in NUMBER_FIELDS), State("pendulum", "value"),
        *(State(f"switch-{name}", "value") for name in LOSSES), State("suspension", "value"), State("solver", "value"),
        State("job", "data"),
        prevent_initial_call=True,
    )
    def control(*args: Any) -> tuple:
        n = len(NUMBER_FIELDS)
        values, pendulum = args[5:5 + n], args[5 + n]
        switches = list(args[6 + n:6 + n + len(LOSSES)])
        suspension, solver, job = args[6 + n + len(LOSSES):]
        unchanged = [no_update] * len(errors)
        trigger = ctx.triggered_id
        if trigger == "cancel":
            if not job:
                return no_update, no_update, True, "nothing is running", *unchanged
            runs.cancel(job["id"])
            return None, no_update, True, "cancelled", *unchanged
        if trigger == "poll":
            if not job:
                return None, no_update, True, no_update, *unchanged
            polled = runs.poll(job["id"])
            if polled is None:  # its answer went to an earlier request of this tab
                return no_update, no_update, no_update, no_update, *unchanged
            done, answer = polled
            if answer is None:
                return no_update, no_update, False, f"running: {100 * done:.0f} % of {job['stop_time']:g} s", \
                    *unchanged
            # The timer stops and ``collect`` fetches the answer in a request of its own: a reply the browser drops
            # because the timer's next request overtook it (Dash keeps only a callback's latest) is a small one,
            # and the next tick says the same.
            return no_update, job["id"], True, "the run is done: reading its answer", *unchanged
        if job:
            return no_update, no_update, False, "a run is still going: cancel it first", *unchanged
        checked = check_form(_form(list(values), pendulum, switches, suspension, solver))
        messages = [checked.errors.get(name, "") for name in names]
        if checked.errors:
            return None, no_update, True, "some values are refused: see the messages under them", *messages
        kind = BUTTONS[trigger]
        run_id = runs.start(kind, checked.start_values, checked.stop_time, OUTPUT_INTERVAL_S)
        job = {"id": run_id, "kind": kind, "start_values": checked.start_values, "stop_time": checked.stop_time,
               "fmu": str(runs.fmu)}
        return job, no_update, False, f"running: 0 % of {checked.stop_time:g} s", *messages

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

    graphs = ("angles", "budget", "path", "compare", "compare2")

    @app.callback(
        Output("player", "srcDoc"), *(Output(g, "figure") for g in graphs), *(Output(g, "style") for g in graphs),
        Output("fmpy-call", "children"), Input("result", "data"), prevent_initial_call=True,
    )
    def draw(result: dict[str, Any] | None) -> tuple:
        if not result or not result.get("columns"):
            return (no_update,) * (2 + 2 * len(graphs))
        c = result["columns"]
        shown = {g: HIDDEN for g in graphs}
        out = dict.fromkeys(graphs, no_update)
        if result["kind"] == "measured":
            swings = [swing_data("camera", "k", *(c[f"{k}_measured"] for k in ("x1", "y1", "x2", "y2")), links=False),
                      swing_data("FMU", "C0", *(c[f"{k}_simulated"] for k in ("x1", "y1", "x2", "y2")),
                                 pivot=(c["pivot_x_simulated"][0], c["pivot_y_simulated"][0]))]
            data = player_table(c["t_since_t0"], swings, "measured (camera) and simulated (FMU) pendulum",
                                time_label="t - t0")
            out["compare"], out["compare2"] = figures.measured_figures(c, result["t0"])
            losses = (f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}" for k, v in result["losses"].items())
            call = "the seed's start with the losses fitted to the measured decay (measured_vs_sim): " + \
                   ", ".join(losses)
        else:
            swings = [swing_data("your case", "C0", c["x1"], c["y1"], c["x2"], c["y2"],
                                 pivot=(c["xs"], c["ys"]))]
            if result.get("twin"):
                t = result["twin"]
                swings.append(swing_data("a hair apart", "C3", t["x1"], t["y1"], t["x2"], t["y2"],
                                         pivot=(t["xs"], t["ys"])))
                out["compare"] = figures.separation_figure(c, t, result["nudge_rad"])
            data = player_table(c["time"], swings, "the pendulum, from the FMU's positions")
            out["angles"], out["budget"], out["path"] = (figures.angles_figure(c), figures.budget_figure(c),
                                                         figures.path_figure(c))
            call = "import fmpy\n" + Case(result["fmu"], result["start_values"], result["stop_time"],
                                          OUTPUT_INTERVAL_S).fmpy_call()
        for g in graphs:
            if out[g] is not no_update:
                shown[g] = SHOWN
        return standalone_html(data), *(out[g] for g in graphs), *(shown[g] for g in graphs), call

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
