"""The FMUs in FMPy's own tools with their default settings: the web app (``python -m fmpy.webapp``) and the GUI
(``python -m fmpy.gui``, under Xvfb). Both plot every output of an FMU, one row each, and plotly refuses more
than 17 rows: the FMUs keep their outputs to what a master couples to and a user plots first (docs/fmu.md,
"Outputs and diagnostics")."""

from __future__ import annotations

import base64
import importlib.util
import json
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

HAS_WEBAPP = all(importlib.util.find_spec(m) is not None for m in ("dash", "dash_bootstrap_components", "plotly"))
MOST_ROWS = 17  # fmpy's create_plotly_figure: vertical_spacing 0.06 allows at most 1 / 0.06 + 1 rows


@pytest.fixture(scope="module")
def tool_fmus(fmu_path: Path, fmu3_path: Path) -> dict[str, Path]:
    """Every FMU the build writes: FMI 2 and 3 DoublePendulum, Suspension, the container of the coupled system."""
    folder = fmu_path.parent
    return {"fmi2": fmu_path, "fmi3": fmu3_path, "suspension": folder / "Suspension.fmu",
            "container": folder / "PendulumOnSuspension.fmu"}


@pytest.mark.parametrize("which", ["fmi2", "fmi3", "suspension", "container"])
def test_every_fmu_has_few_enough_outputs_for_fmpys_default_plot(tool_fmus, which):
    from fmpy import read_model_description

    md = read_model_description(tool_fmus[which])
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert 1 <= len(outputs) <= MOST_ROWS, outputs


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url: str, timeout: float = 5.0) -> bytes:
    with urllib.request.urlopen(url, timeout=timeout) as answer:
        return answer.read()


def _values(node, found: dict) -> dict:
    """The ``value`` of every component with an ``id`` in a Dash layout: the form as the page shows it."""
    if isinstance(node, dict):
        props = node.get("props")
        if isinstance(props, dict) and "id" in props and "value" in props:
            found[props["id"]] = props["value"]
        for child in node.values():
            _values(child, found)
    elif isinstance(node, list):
        for child in node:
            _values(child, found)
    return found


def _array(value) -> np.ndarray:
    """A plotly figure's data array: a list, or plotly's typed array ``{"dtype": ..., "bdata": base64}``."""
    if isinstance(value, dict):
        return np.frombuffer(base64.b64decode(value["bdata"]), dtype=value["dtype"])
    return np.asarray(value, dtype=float)


def _press_simulate(base: str) -> dict:
    """Press the web app's Simulate button as the page does: call its callback with the form's values."""
    layout = json.loads(_get(base + "/_dash-layout"))
    dependencies = json.loads(_get(base + "/_dash-dependencies"))
    simulate = next(d for d in dependencies if d["output"] == "result-col.children")
    values = _values(layout, {})
    body = {
        "output": simulate["output"],
        "outputs": {"id": "result-col", "property": "children"},
        "inputs": [{"id": "simulate-button", "property": "n_clicks", "value": 1}],
        "state": [{**s, "value": values[s["id"]]} for s in simulate["state"]],
        "changedPropIds": ["simulate-button.n_clicks"],
    }
    request = urllib.request.Request(base + "/_dash-update-component", data=json.dumps(body).encode(),
                                     headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(request, timeout=120) as answer:
        return json.loads(answer.read())["response"]["result-col"]["children"]


@pytest.mark.skipif(not HAS_WEBAPP, reason="FMPy's web app needs dash, dash-bootstrap-components and plotly "
                    '(pip install -e ".[test]")')
@pytest.mark.parametrize("which", ["fmi2", "fmi3", "suspension", "container"])
def test_fmpys_web_app_plots_the_default_outputs(tool_fmus, which, tmp_path):
    """``python -m fmpy.webapp FMU`` on 127.0.0.1, Simulate pressed with the form as it comes: a graph with one row
    per output, each the result of fmpy's ``simulate_fmu`` with the same (default) settings."""
    from fmpy import read_model_description, simulate_fmu

    fmu = tool_fmus[which]
    port = _free_port()
    base = f"http://127.0.0.1:{port}"
    log = (tmp_path / "webapp.log").open("w")
    # the web app extracts the FMU into $TMPDIR and leaves it there when stopped: give it the test's own folder
    server = subprocess.Popen([sys.executable, "-m", "fmpy.webapp", str(fmu), "--port", str(port)],
                              stdout=log, stderr=subprocess.STDOUT, cwd=tmp_path,
                              env={**os.environ, "TMPDIR": str(tmp_path)})
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                _get(base + "/_dash-layout", timeout=2)
                break
            except (urllib.error.URLError, ConnectionError):
                assert server.poll() is None, (tmp_path / "webapp.log").read_text()
                assert time.monotonic() < deadline, "the web app did not answer within 60 s"
                time.sleep(0.2)
        children = _press_simulate(base)
    finally:
        server.terminate()
        server.wait(timeout=30)
        log.close()
    assert children["type"] == "Graph", f"no graph: {json.dumps(children)[:500]}"
    traces = children["props"]["figure"]["data"]
    md = read_model_description(fmu)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert [t["name"] for t in traces] == outputs
    expected = simulate_fmu(fmu)  # what the web app calls: the default experiment, default output interval
    for trace in traces:
        np.testing.assert_array_equal(_array(trace["x"]), expected["time"])
        np.testing.assert_array_equal(_array(trace["y"]), expected[trace["name"]])
        assert np.ptp(_array(trace["y"])) > 0 or which == "suspension"  # the unloaded suspension stays at rest


# ----------------------------------------------------------------------------------------------- the GUI

GUI_SCRIPT = Path(__file__).with_name("fmpy_gui_shot.py")


def _gui_missing() -> str | None:
    if importlib.util.find_spec("PySide6") is None or importlib.util.find_spec("pyqtgraph") is None:
        return 'FMPy\'s GUI needs PySide6 and pyqtgraph (pip install "fmpy[gui,plot]"); not installed'
    if shutil.which("xvfb-run") is None:
        return "the GUI test needs Xvfb (Debian: apt-get install xvfb xauth); xvfb-run is not on PATH"
    missing = _xcb_libraries_missing()
    if missing:
        return (f"Qt's xcb platform plugin cannot load without {', '.join(missing)} (Debian: apt-get install "
                f"libxcb-cursor0 libxkbcommon-x11-0 ..., as .ci/run does)")
    return None


def _xcb_libraries_missing() -> list[str]:
    """The libraries Qt's xcb plugin needs that this machine lacks: those ``ldd`` does not find for the plugin, and
    libxcb-cursor, which Qt 6.5 and later load only when the plugin starts."""
    import ctypes.util

    import PySide6

    plugin = Path(PySide6.__file__).parent / "Qt" / "plugins" / "platforms" / "libqxcb.so"
    missing = [] if ctypes.util.find_library("xcb-cursor") else ["libxcb-cursor.so.0"]
    if plugin.is_file() and shutil.which("ldd"):
        listed = subprocess.run(["ldd", str(plugin)], capture_output=True, text=True).stdout
        missing += sorted({line.split()[0] for line in listed.splitlines() if "not found" in line})
    return missing


@pytest.mark.skipif(_gui_missing() is not None, reason=_gui_missing() or "")
@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
def test_fmpys_gui_plots_the_default_outputs(tool_fmus, which, tmp_path):
    """``fmpy.gui`` opens the FMU, simulates with its defaults and plots every output: the window's screenshot
    (docs/images/fmpy_gui.png comes from this script) and the plotted names are checked."""
    shot = tmp_path / "gui.png"
    home = tmp_path / "home"  # FMPy's settings (CATIA-Systems/FMPy.conf), Qt's and Mesa's caches: never the user's
    env = {**os.environ, "QTWEBENGINE_CHROMIUM_FLAGS": "--no-sandbox", "QT_QPA_PLATFORM": "xcb",
           "TMPDIR": str(tmp_path),  # the GUI extracts the FMU there
           "HOME": str(home), "XDG_CONFIG_HOME": str(home / ".config"), "XDG_CACHE_HOME": str(home / ".cache"),
           "XDG_DATA_HOME": str(home / ".local" / "share")}
    done = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x900x24", sys.executable, str(GUI_SCRIPT),
                           str(tool_fmus[which]), str(shot)], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stdout + done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    from fmpy import read_model_description

    md = read_model_description(tool_fmus[which])
    assert sorted(report["plotted"]) == sorted(v.name for v in md.modelVariables if v.causality == "output")
    assert report["rows"] == len(report["plotted"]) and report["error"] is None
    assert shot.stat().st_size > 20_000  # a drawn window, not a blank one
