"""The interactive app (``double-pendulum app``) and the run page's player, in a real browser (headless Chromium over
the DevTools protocol, tests/browser.py): a run's final angle is the bare ``simulate_fmu``'s, a refused value says
why beside its field, a run the FMU cannot complete shows the FMU's message, and the page's player scrubs."""

from __future__ import annotations

import datetime
import importlib.util
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
from browser import Browser, find_chromium

from double_pendulum.app.form import check_form, default_values
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
    form = {**default_values(), "phi1_0": "9", "switches": ["air_drag"], "cw": "much"}
    errors = check_form(form).errors
    assert errors["phi1_0"] == "phi1_0 = 9 is out of range: -3.14159 to 3.14159 rad"
    assert errors["cw"] == "cw = 'much' is not a number (0 to 5)"
    checked = check_form({**default_values(), "phi1_0": "2", "pendulum": "frictionless", "switches": ["air_drag"]})
    assert checked.errors == {} and "air_drag" not in checked.start_values  # frictionless: no loss switched on
    assert checked.start_values["phi1_0"] == 2.0 and checked.stop_time == 20.0


@pytest.fixture(scope="module")
def app_url(fmu_path: Path, tmp_path_factory: pytest.TempPathFactory):
    """The app served by ``python -m double_pendulum.app.server`` on a free port: its address. What the server
    prints goes to a file (a pipe nobody reads while the tests run would fill and stop the server)."""
    if NO_DASH:
        pytest.skip("Dash is not installed (pip install -e \".[app]\")")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    printed = tmp_path_factory.mktemp("app") / "printed.txt"
    with printed.open("w") as out:
        server = subprocess.Popen([sys.executable, "-m", "double_pendulum.app.server", "--port", str(port), "--fmu",
                                   str(fmu_path)], stdout=out, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 60
        while True:  # the address is printed before the server listens
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert time.monotonic() < deadline and server.poll() is None, "the app did not start: " + (
                    printed.read_text())
                time.sleep(0.2)
        assert f"open http://127.0.0.1:{port}/ in a browser" in printed.read_text().splitlines()[0]
        yield f"http://127.0.0.1:{port}/"
    finally:
        server.send_signal(signal.SIGINT)  # as Ctrl-C: the app ends its runs and its fork server cleans up
        server.wait(timeout=60)
    text = printed.read_text()
    assert text.rstrip().endswith("double-pendulum app: ended") and '"GET ' not in text and '"POST ' not in text, text


@needs_browser
@needs_dash
def test_the_app_runs_the_fmu_as_simulate_fmu_and_refuses_a_bad_value_beside_its_field(app_url, fmu_path, tmp_path):
    from fmpy import simulate_fmu

    with Browser(BROWSER, width=1400, height=1000) as browser:
        browser.open(app_url)
        browser.type_into("#in-phi1_0", "2.0")
        browser.click("#switch-air_drag input")
        browser.click("#run")
        assert browser.wait_for(DONE) == "done"
        final = browser.wait_for("(() => { const g = document.querySelector('#angles .js-plotly-plot'); "
                                 "return g && g.data ? g.data.map(d => d.y[d.y.length - 1]) : null; })()")
        browser.screenshot(tmp_path / "app.png")
        form = {**default_values(), "phi1_0": "2.0", "switches": ["air_drag"]}
        checked = check_form(form)
        bare = simulate_fmu(str(fmu_path), start_values=checked.start_values, stop_time=checked.stop_time,
                            output_interval=0.01)
        assert final == [pytest.approx(bare["phi1"][-1], rel=1e-12), pytest.approx(bare["phi2"][-1], rel=1e-12)]
        assert "fmpy.simulate_fmu(" in browser.evaluate("document.querySelector('#fmpy-call').textContent")
        assert browser.evaluate("document.querySelector('#player').srcdoc.includes('dpPlayer')")

        browser.type_into("#in-phi1_0", "9")
        browser.click("#run")
        message = browser.wait_for("document.querySelector('#err-phi1_0').textContent")
        assert message == "phi1_0 = 9 is out of range: -3.14159 to 3.14159 rad"
        assert "refused" in browser.evaluate("document.querySelector('#status').textContent")
        assert browser.errors() == []


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
