"""Ctrl-C on a real run: the signals go to the run's whole process group, as a terminal sends them."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

STOP_WITHIN_S = 10.0


def _group(pgid: int) -> list[int]:
    """The processes of process group ``pgid`` that still exist (zombies included)."""
    members = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:  # ended meanwhile
                continue
            if int(fields[2]) == pgid:
                members.append(int(entry.name))
    return members


def _start(args: list[str], tmp_path: Path, command: str = "run") -> tuple[subprocess.Popen, queue.Queue, Path]:
    """Start ``double-pendulum COMMAND ARGS`` in a process group of its own with an empty $TMPDIR; its stdout lines
    arrive in the queue."""
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    env = {**os.environ, "TMPDIR": str(tmpdir), "MPLBACKEND": "Agg", "DOUBLE_PENDULUM_PROGRESS": "off"}
    env.pop("DOUBLE_PENDULUM_WORKERS", None)  # a worker process per core, as a user's run has
    process = subprocess.Popen([sys.executable, "-m", "double_pendulum.cli", command, *args],
                               env=env, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)  # fmt: skip
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in process.stdout], daemon=True).start()
    return process, lines, tmpdir


def _wait_for(lines: queue.Queue, text: str, process: subprocess.Popen) -> None:
    """Wait until a line holding ``text`` is printed (the run is in the middle of its work then)."""
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        try:
            if text in lines.get(timeout=1):
                return
        except queue.Empty:
            assert process.poll() is None, process.stderr.read()
    pytest.fail(f"no line with {text!r}")


@pytest.mark.slow
@pytest.mark.parametrize(("args", "busy", "signals"), [
    (["chaos"], "parts", 1),  # one process, its parts on worker processes: one Ctrl-C acts at once
    (["all", "--quick"], "[2/11]", 2),  # child processes, one per core: two Ctrl-C
])  # fmt: skip
def test_ctrl_c_ends_every_process_of_the_run_and_leaves_no_temporary_file(tmp_path, fmu_path, args, busy, signals):
    out = tmp_path / "results"
    process, lines, tmpdir = _start([*args, "--fmu", str(fmu_path), "--out", str(out)], tmp_path)
    try:
        _wait_for(lines, busy, process)
        time.sleep(1.5)  # into the work: workers or children started
        assert len(_group(process.pid)) > 1  # the run has processes besides its main one
        os.killpg(process.pid, signal.SIGINT)
        sent = time.monotonic()
        for _ in range(signals - 1):
            time.sleep(0.3)
            os.killpg(process.pid, signal.SIGINT)
        code = process.wait(timeout=STOP_WITHIN_S)
        while _group(process.pid) and time.monotonic() - sent < STOP_WITHIN_S:
            time.sleep(0.1)
        assert _group(process.pid) == []  # no worker, child or orphan left
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    stderr = process.stderr.read()
    assert code == 130, stderr
    assert "Traceback" not in stderr and "interrupted" in stderr
    assert list(tmpdir.iterdir()) == []  # no extracted FMU, no temporary folder of the run
    assert not any(path.name.endswith(".incomplete") for path in out.iterdir())  # unfinished folders discarded


@pytest.mark.slow
def test_ctrl_c_on_a_case_of_one_s_own_keeps_the_rows_so_far_and_leaves_nothing_else(tmp_path, fmu_path):
    """The rows computed before Ctrl-C are in simulation.csv, every line whole, with a summary.json that says so
    (an earlier run's files replaced); no figure, no staging folder, no extracted FMU."""
    import json

    import numpy as np

    from double_pendulum.runs.results_io import read_results_csv

    out = tmp_path / "case"
    out.mkdir()
    (out / "summary.json").write_text("an earlier run's\n")
    (out / "simulation.png").write_text("an earlier run's\n")
    args = ["--stop", "200", "--step", "0.001", "--fmu", str(fmu_path), "--out", str(out)]  # long: 200,000 steps
    process, lines, tmpdir = _start(args, tmp_path, command="simulate")
    try:
        _wait_for(lines, "this run takes about", process)  # the probe's second is done
        time.sleep(1.0)  # into the FMU's run
        os.killpg(process.pid, signal.SIGINT)
        code = process.wait(timeout=120)  # a guard against a hang, not a bound on the time
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    stderr = process.stderr.read()
    assert code == 130, stderr
    assert "Traceback" not in stderr and "interrupted; wrote the " in stderr and "rows so far, to t = " in stderr
    assert list(tmpdir.iterdir()) == []  # no extracted FMU
    assert sorted(p.name for p in out.iterdir()) == ["simulation.csv", "summary.json"]  # no staging folder
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted by the user"
    assert (out / "simulation.csv").read_bytes().endswith(b"\n")
    rows = read_results_csv(out / "simulation.csv")
    assert len(rows) == summary["rows"] > 1000 and f"{len(rows)} rows so far" in stderr
    np.testing.assert_allclose(np.diff(rows["time"]), 0.001, rtol=1e-6)  # no row lost or doubled
    assert rows["time"][0] == 0.0 and rows["time"][-1] == summary["end_time_s"] < 200
