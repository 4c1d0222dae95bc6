"""The interactive app (``double-pendulum app``) and the run page's player, in a real browser (headless Chromium over
the DevTools protocol, tests/browser.py): a run's final angle is the bare ``simulate_fmu``'s and the fmpy call it
shows gives it, a refused value says why beside its field as it is typed, the fields that do not apply are disabled,
the run button is on the first screen and Enter runs, the player comes into view, 390 px fit, a run the FMU cannot
complete shows the FMU's message, the run against the measured track is the call it shows, the app takes a free port
and refuses a busy one in a line, and the page's player scrubs."""

from __future__ import annotations

import datetime
import importlib.util
import json
import math
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import pytest
from browser import Browser, find_chromium

from double_pendulum.app.form import LOSSES, NUMBER_FIELDS, OWN_PENDULUM, SUSPENSION, check_form, default_values
from double_pendulum.runs.page import RunInfo, ScenarioPage, page_html
from double_pendulum.runs.player import Animation, Drawn
from double_pendulum.runs.results_io import write_results_csv

BROWSER = find_chromium()
NO_DASH = importlib.util.find_spec("dash") is None
needs_browser = pytest.mark.skipif(BROWSER is None, reason="no Chromium on PATH (Debian: apt-get install chromium; "
                                                           ".ci/run installs it where it runs as root with apt)")
needs_dash = pytest.mark.skipif(NO_DASH, reason="Dash is not installed (pip install -e \".[app]\")")
DONE = ("(() => { const s = document.querySelector('#status').textContent; "
        "return s.startsWith('done') || s.startsWith('the FMU stopped') ? s : ''; })()")


def test_the_form_refuses_a_value_out_of_range_or_not_a_number_with_the_reason():
    form = {**default_values(), "phi1_0": "2e4", "switches": ["air_drag"], "cw": "much"}
    errors = check_form(form).errors  # the start angles' one rule, in the FMU's words (as the CLI has it)
    assert errors["phi1_0"].startswith("invalid phi1_0 = 20000.0 rad: a start angle must be a finite number from "
                                       "-10000 to 10000 rad")
    assert check_form({**default_values(), "phi1_0": "9"}).start_values["phi1_0"] == 9.0  # 9 - 2 pi's motion
    assert errors["cw"] == "cw = 'much' is not a number (0 to 5)"
    checked = check_form({**default_values(), "phi1_0": "2", "pendulum": "frictionless", "switches": ["air_drag"]})
    assert checked.errors == {} and "air_drag" not in checked.start_values  # frictionless: no loss switched on
    assert checked.start_values["phi1_0"] == 2.0 and checked.stop_time == 20.0


def test_a_field_that_does_not_apply_is_neither_checked_nor_used_and_one_that_does_is_refused_in_the_fmu_s_words():
    own = check_form({**default_values(), "pendulum": "own", "m1": "-0.3"})
    assert own.errors == {"m1": "invalid m1 = -0.3 kg: must be > 0"} and own.start_values == {}
    seed = check_form({**default_values(), "pendulum": "seed", "m1": "-0.3"})  # m1 is disabled then
    assert seed.errors == {} and "m1" not in seed.start_values and seed.start_values["m_rod1"] == 0.07
    assert check_form({**default_values(), "pendulum": "own", "m1": "2.0"}).start_values["m1"] == 2.0
    measured = check_form({**default_values(), "mode": "measured", "phi1_0": "x", "m1": "-1"})
    assert measured.errors == {} and measured.start_values == {}  # the form does not apply there


@pytest.mark.parametrize("field", [f for f in NUMBER_FIELDS if f.name != "stop_time"], ids=lambda f: f.name)
def test_every_value_the_fmu_s_component_refuses_is_refused_beside_its_field(field):
    """The component's own check of a start value (what the FMU does with it before it runs) against the form's:
    whatever the component refuses, the form refuses, under that field, with the component's message."""
    from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
    from double_pendulum.model.parameters import ParameterError

    form = {**default_values(), "pendulum": "own", "switches": list(LOSSES), "suspension": True}
    refused = 0
    for value in (-1e6, -1.0, -1e-9, 0.0, 1e-9, 1.0, 2e4, 1e9, math.inf, -math.inf, math.nan):
        try:
            DoublePendulumCoSimulation().set(field.name, value)  # as the FMU sets a start value
        except ParameterError as error:
            refused += 1
            assert check_form({**form, field.name: repr(value)}).errors == {field.name: str(error)}
    assert refused >= 3  # nan and both infinities at least
    assert {f.name for f in (*OWN_PENDULUM, *SUSPENSION)} <= {f.name for f in NUMBER_FIELDS}


SERVER = ("import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
          "runpy.run_module('double_pendulum.app.server', run_name='__main__', alter_sys=True)")
"""``python -m double_pendulum.app.server`` with Python's own Ctrl-C handler, as a terminal starts it: a test session
started as a background job of a shell without job control ignores SIGINT, and its children would inherit that."""


def _launch(fmu_path: Path, printed: Path, *port: str) -> subprocess.Popen:
    with printed.open("w") as out:
        return subprocess.Popen([sys.executable, "-c", SERVER, *port, "--fmu", str(fmu_path)],
                                stdout=out, stderr=subprocess.STDOUT, text=True)


@pytest.fixture(scope="module")
def app_url(fmu_path: Path, tmp_path_factory: pytest.TempPathFactory):
    """The app served by ``python -m double_pendulum.app.server`` without ``--port``: on the free port it prints.
    What the server prints goes to a file (a pipe nobody reads while the tests run would fill and stop the
    server)."""
    if NO_DASH:
        pytest.skip("Dash is not installed (pip install -e \".[app]\")")
    printed = tmp_path_factory.mktemp("app") / "printed.txt"
    server = _launch(fmu_path, printed)
    try:
        deadline = time.monotonic() + 60
        while not (found := re.search(r"open http://127\.0\.0\.1:(\d+)/ in a browser", printed.read_text())):
            started = time.monotonic() < deadline and server.poll() is None
            assert started, f"the app did not start: {printed.read_text()}"
            time.sleep(0.1)
        port = int(found.group(1))
        assert port != 8050  # FMPy's web app's
        socket.create_connection(("127.0.0.1", port), timeout=5).close()  # it listens before it says so
        yield f"http://127.0.0.1:{port}/"
    finally:
        server.send_signal(signal.SIGINT)  # as Ctrl-C: the app ends its runs and its fork server cleans up
        server.wait(timeout=60)
    text = printed.read_text()
    assert text.rstrip().endswith("double-pendulum app: ended") and '"GET ' not in text and '"POST ' not in text, text


@needs_dash
def test_a_port_in_use_is_one_line_naming_it_and_exit_status_2(fmu_path, tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        printed = tmp_path / "printed.txt"
        server = _launch(fmu_path, printed, "--port", str(port))
        assert server.wait(timeout=60) == 2
    lines = printed.read_text().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"double-pendulum app: --port {port}: the port is in use"), lines


def _press_enter(browser: Browser, selector: str) -> None:
    """Focus the field ``selector`` and press Enter in it, as a user does."""
    browser.evaluate(f"document.querySelector({json.dumps(selector)}).focus()")
    for kind in ("keyDown", "keyUp"):
        browser.send("Input.dispatchKeyEvent", type=kind, key="Enter", code="Enter", windowsVirtualKeyCode=13,
                     nativeVirtualKeyCode=13, **({"text": "\r"} if kind == "keyDown" else {}))


def _run_the_call(text: str) -> Any:
    """The fmpy call the app shows, run: its ``result``."""
    namespace: dict[str, Any] = {}
    exec(compile(text, "<the app's fmpy call>", "exec"), namespace)  # the Python the page gives, as a user runs it
    return namespace["result"]


RECT = "(s => {{ const r = document.querySelector(s).getBoundingClientRect(); return [r.top, r.bottom, r.right]; }})"
CUT = """(() => {
    const cut = [];
    for (const box of document.querySelectorAll('.results-panel > div[id$="-box"]')) {
        if (box.style.display === 'none') continue;
        const title = box.querySelector('h3'), svg = box.querySelector('.main-svg').getBoundingClientRect();
        if (title.scrollWidth > title.clientWidth || title.getBoundingClientRect().right > innerWidth)
            cut.push(box.id + ' title');
        for (const t of box.querySelectorAll('.legend text, .gtitle, .xtitle, .ytitle')) {
            const r = t.getBoundingClientRect();
            if (r.width && (r.left < svg.left - 1 || r.right > svg.right + 1 || r.left < 0 || r.right > innerWidth))
                cut.push(box.id + ': ' + t.textContent);
        }
    }
    return cut;
})()"""
"""What is cut among the visible plots: a title wider than its box or the screen, a legend entry or axis title that
reaches out of its figure or off the screen."""


@needs_browser
@needs_dash
def test_the_app_runs_the_fmu_as_simulate_fmu_and_refuses_a_bad_value_beside_its_field(app_url, fmu_path, tmp_path):
    with Browser(BROWSER, width=1280, height=800) as browser:
        browser.open(app_url)
        browser.emulate(1280, 800, mobile=False)
        browser.wait_for("document.querySelector('#in-m1') !== null")
        top, bottom, _ = browser.evaluate(f"{RECT}('#run')")
        assert 0 < top and bottom <= 800, "the run button must be on the first screen"
        browser.screenshot(tmp_path / "app-1280-before.png", clip={"x": 0, "y": 0, "width": 1280, "height": 800})
        # the seed's pendulum: its masses and lengths are disabled, and the page says why
        assert browser.evaluate("document.querySelector('#in-m1').disabled")
        assert "do not apply" in browser.wait_for("document.querySelector('#pendulum-note').textContent")
        browser.click("#pendulum input[value='own']")
        browser.wait_for("!document.querySelector('#in-m1').disabled")
        browser.type_into("#in-m1", "-0.3")  # refused beside m1 as it is typed, before any run
        assert browser.wait_for("document.querySelector('#err-m1').textContent") == "invalid m1 = -0.3 kg: must be > 0"
        browser.click("#run")
        assert browser.wait_for("document.querySelector('#status').textContent") == (
            "some values are refused: see the messages under them")
        assert browser.evaluate("document.activeElement.id") == "in-m1"  # the first refused field, in view
        browser.type_into("#in-m1", "2.0")
        browser.wait_for("document.querySelector('#err-m1').textContent === ''")
        browser.type_into("#in-phi1_0", "2.0")
        browser.click("#switch-air_drag input")
        browser.evaluate("window.scrollTo(0, document.body.scrollHeight)")  # as after typing far down the form
        _press_enter(browser, "#in-rtol")  # Enter in a field runs
        assert browser.wait_for(DONE) == "done"
        final = browser.wait_for("(() => { const g = document.querySelector('#angles .js-plotly-plot'); "
                                 "return g && g.data ? g.data.map(d => d.y[d.y.length - 1]) : null; })()")
        call = browser.evaluate("document.querySelector('#fmpy-call').textContent")
        # the app scrolls the player to the top 50 ms after its figure is drawn: wait for it to arrive there (the page
        # was scrolled to its bottom, so the player's top is far above until then, and 'below 60 px' held too early)
        arrived = f"(() => {{ const r = {RECT}('#player'); return Math.abs(r[0]) < 60 ? r : null; }})()"
        top, bottom, _ = browser.wait_for(arrived)
        assert -1 <= top and bottom > 300, "after a run the player is in view"
        browser.screenshot(tmp_path / "app-1280-after.png")
        form = {**default_values(), "phi1_0": "2.0", "switches": ["air_drag"], "pendulum": "own", "m1": "2.0"}
        checked = check_form(form)
        assert "'m1': 2.0" in call and f"start_values={checked.start_values!r}" in call, call
        shown = _run_the_call(call)  # the call shown, as a user runs it, gives the plotted run
        assert final == [pytest.approx(shown["phi1"][-1], rel=1e-12), pytest.approx(shown["phi2"][-1], rel=1e-12)]
        assert browser.evaluate("document.querySelector('#player').srcdoc.includes('dpPlayer')")

        browser.click("#mode input[value='twins']")  # the twins' plot: its title whole at 1280 px
        browser.type_into("#in-stop_time", "3")
        browser.click("#run")
        browser.wait_for("document.querySelector('#compare-box').style.display === 'block' && "
                         "document.querySelector('#status').textContent === 'done'")
        assert "a hair apart" in browser.evaluate("document.querySelector('#compare-title').textContent")
        assert browser.evaluate(CUT) == []

        browser.click("#mode input[value='measured']")  # against the measured track the form does not apply
        browser.wait_for("document.querySelector('#mode-note').style.display === 'block'")
        assert browser.evaluate("[...document.querySelectorAll('.form-panel fieldset input[type=text]')]"
                                ".every(e => e.disabled)")
        assert "does not apply" in browser.evaluate("document.querySelector('#mode-note').textContent")

        browser.click("#mode input[value='case']")  # back to one's case: a bad value is refused beside its field
        browser.wait_for("!document.querySelector('#in-phi1_0').disabled")
        browser.type_into("#in-phi1_0", "2e4")
        message = browser.wait_for("document.querySelector('#err-phi1_0').textContent")
        assert message.startswith("invalid phi1_0 = 20000.0 rad: a start angle must be a finite number")
        assert browser.errors() == []


@needs_browser
@needs_dash
def test_at_390_px_the_app_fits_the_screen_and_cuts_no_title_or_legend(app_url, tmp_path):
    with Browser(BROWSER, width=390, height=844) as browser:
        browser.open(app_url)
        browser.emulate(390, 844)
        browser.wait_for("document.querySelector('#run') !== null")
        assert browser.evaluate("document.documentElement.scrollWidth") <= 390
        assert browser.evaluate(f"{RECT}('#run')")[1] <= 844
        browser.screenshot(tmp_path / "app-390-before.png")
        browser.type_into("#in-stop_time", "4")
        browser.click("#switch-air_drag input")
        browser.click("#run")
        assert browser.wait_for(DONE) == "done"
        browser.wait_for("document.querySelector('#budget .legend') !== null")
        top, bottom, right = browser.wait_for(f"(() => {{ const r = {RECT}('#player'); "
                                              "return Math.abs(r[0]) < 2 ? r : null; })()")
        assert right <= 390 and bottom - top > 300  # in view, as wide as the screen allows, whole
        time.sleep(0.5)  # Plotly's responsive resize
        assert browser.evaluate("document.documentElement.scrollWidth") <= 390
        assert browser.evaluate(CUT) == []
        browser.screenshot(tmp_path / "app-390-after.png")
        assert browser.errors() == []


def test_the_run_against_the_measured_track_is_the_fmpy_call_it_shows(fmu_path):
    """The fitted start of measured_vs_sim (quick mode here, the tests' stand-in for the same code: a 0.5 s fit
    window, 3 s of record): the call the app shows, run with fmpy, gives the app's run bit for bit, and moved by the
    fitted camera geometry it gives the positions the app compares with the camera's."""
    import numpy as np

    from double_pendulum.analysis.track.start_state import POSITION_OUTPUTS, output_matrix, shift_outputs
    from double_pendulum.app.measured import call_text, run_measured

    answer = run_measured(str(fmu_path), quick=True)
    call = call_text(str(fmu_path), answer)
    shown = _run_the_call(call)
    for name in shown.dtype.names:
        np.testing.assert_allclose(shown[name], answer["simulated"][name], rtol=1e-12, atol=1e-15)
    assert answer["start_time"] == pytest.approx(0.8008, abs=1e-4) and f"start_time={answer['start_time']!r}" in call
    for name, value in answer["start_values"].items():  # every start value it took is in the call and in the list
        assert f"{name!r}: {value!r}" in call
    assert {u["name"] for u in answer["used"]} == {*answer["start_values"], *answer["transforms"]}
    assert set(answer["transforms"]) == {"view_rotation", "pivot_offset_x", "pivot_offset_y"}
    fitted = {u["name"] for u in answer["used"] if u["what"].startswith("fitted to the track")}
    assert fitted == {"phi1_0", "phi2_0", "omega1_0", "omega2_0", "l2", *answer["transforms"]}
    moved = shift_outputs(output_matrix(shown), POSITION_OUTPUTS, answer["transforms"])
    frames = np.rint((np.asarray(answer["columns"]["time"]) - answer["start_time"]) / answer["output_interval"])
    np.testing.assert_allclose(moved[frames.astype(int), 2], answer["columns"]["x2_simulated"], rtol=1e-12, atol=1e-15)
    assert answer["horizon"]["horizon_s"] > 1.0  # the fitted start follows the track (quick: the 0.5 s fit)
    assert len(answer["error_smoothed"]) == len(answer["columns"]["time"])  # the horizon's curve, drawn beside


def test_a_run_the_fmu_cannot_complete_answers_the_fmu_s_own_message(fmu_path):
    from double_pendulum.app.callbacks import _answer_text
    from double_pendulum.app.worker import run_case

    answer = run_case(str(fmu_path), {"l1": -1.0}, 1.0, 0.01)  # past the form, as a value the FMU refuses
    assert answer["columns"] is None and "l1 = -1.0 m: must be > 0" in answer["message"]
    assert _answer_text(answer) == f"the FMU stopped the run: {answer['message']}"


def _wait_for_answer(runs, run_id: str, timeout: float = 120.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        state = runs.poll(run_id)
        if state is not None and state[1] is not None:
            return state[1]
        time.sleep(0.05)
    raise AssertionError(f"run {run_id} gave no answer in {timeout} s")


@pytest.fixture
def runs(fmu_path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """The app's runs, with this test's tmp_path as the temporary folder; closed, they must have left nothing in it
    but multiprocessing's own folder (pymp-..., the fork server's socket, which only a normal exit of the process
    removes and an xdist worker ends with os._exit: pytest_unconfigure)."""
    from double_pendulum.app.worker import Runs

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    runs = Runs(fmu_path)
    yield runs
    runs.close()
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith("pymp-")) == []


def test_two_runs_at_once_each_get_their_own_answer_and_a_cancelled_one_leaves_no_process(runs):
    """Two tabs' runs in flight together come back with their own start's result; a long run cancelled ends its
    process at once and is forgotten (a poll of it answers None)."""
    long = runs.start("case", {"phi1_0": 2.0, "solver": "dop853", "rtol": 1e-12}, 3600.0, 0.01)
    first = runs.start("case", {"phi1_0": 0.1, "phi2_0": 0.1}, 2.0, 0.01)
    second = runs.start("case", {"phi1_0": -0.1, "phi2_0": -0.1}, 2.0, 0.01)
    process = runs.jobs[long].process
    deadline = time.monotonic() + 60
    while runs.poll(long)[0] == 0.0 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert process.is_alive() and runs.poll(long)[1] is None, "the hour-long run should be running"
    runs.cancel(long)
    assert not process.is_alive() and runs.poll(long) is None
    a, b = _wait_for_answer(runs, first), _wait_for_answer(runs, second)
    assert a["message"] is None and b["message"] is None
    assert a["columns"]["phi1"][0] == pytest.approx(0.1) and b["columns"]["phi1"][0] == pytest.approx(-0.1)
    assert a["columns"]["phi1"][-1] == pytest.approx(-b["columns"]["phi1"][-1], rel=1e-9)  # mirror images


def test_an_answer_is_given_as_often_as_asked_until_the_tab_collects_it(runs):
    """A tab's timer asks again before the reply to its last request is in, and the browser keeps only the latest
    reply (Dash drops a callback's overtaken requests): the answer must not be spent by a reply that is dropped."""
    run_id = runs.start("case", {"phi1_0": 0.1}, 0.5, 0.01)
    answer = _wait_for_answer(runs, run_id)
    assert answer["message"] is None and runs.poll(run_id) == (1.0, answer)
    assert runs.collect(run_id) is answer and runs.poll(run_id) is None and runs.collect(run_id) is None


def test_a_run_whose_process_dies_answers_so_and_does_not_raise(runs):
    """A run's process killed from outside (out of memory, a signal) is reported as ended without an answer."""
    run_id = runs.start("case", {"phi1_0": 2.0, "solver": "dop853", "rtol": 1e-12}, 3600.0, 0.01)
    process = runs.jobs[run_id].process
    deadline = time.monotonic() + 60
    while runs.poll(run_id)[0] == 0.0 and time.monotonic() < deadline:
        time.sleep(0.05)
    process.kill()
    process.join()
    answer = _wait_for_answer(runs, run_id)
    assert answer["columns"] is None and answer["message"] == (
        f"the run's process ended without an answer (exit code {-signal.SIGKILL})")


@needs_browser
def test_the_page_s_player_steps_and_scrubs_to_another_frame(fmu_path, tmp_path):
    from double_pendulum.fmu.running.runner import FmuRunner

    folder = tmp_path / "free_swing"
    folder.mkdir()
    with FmuRunner(fmu_path, reuse_instance=False) as runner:
        result = runner.simulate({"phi1_0": 2.0}, stop_time=3.0, output_interval=0.01)
        write_results_csv(folder / "chaotic.csv", result, runner.units)
    (folder / "summary.json").write_text("{}")
    animation = Animation("twin_starts.gif", "a test swing", (Drawn("one start", "C0", "chaotic.csv"),))
    (folder / "twin_starts.gif").write_bytes(b"GIF89a")
    page = ScenarioPage("free_swing", "a test", (), (("twin_starts.gif", "a GIF"),), animations=(animation,))
    run = RunInfo(datetime.datetime(2026, 12, 5, tzinfo=datetime.UTC), "0", "quick", 1.0, 1.0, "test",
                  ("free_swing",))
    index = tmp_path / "index.html"
    index.write_text(page_html(tmp_path, run, [page]), encoding="utf-8")
    assert "<script src" not in index.read_text() and "http" not in index.read_text().split("<body>")[1]
    with Browser(BROWSER) as browser:
        browser.open(index.as_uri())
        player = "document.querySelector('.dp-player')"
        before = browser.evaluate(f"{player}.querySelector('canvas').toDataURL()")
        browser.click(".dp-player .dp-step")
        assert browser.evaluate(f"{player}.dataset.frame") == "1"
        browser.evaluate(f"(() => {{ const s = {player}.querySelector('.dp-time'); s.value = 150; "
                         "s.dispatchEvent(new Event('input')); })()")
        assert browser.evaluate(f"{player}.dataset.frame") == "150"
        assert browser.evaluate(f"{player}.querySelector('.dp-clock').textContent").startswith("t = 1.50 s")
        assert browser.evaluate(f"{player}.querySelector('canvas').toDataURL()") != before
        browser.click(".dp-player .dp-play")
        browser.wait_for(f"{player}.dataset.frame !== '150'", timeout=30)
        browser.screenshot(tmp_path / "player.png")
        assert browser.errors() == []
