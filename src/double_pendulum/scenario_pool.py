"""Run several scenarios at once, each in a child process of its own: ``double-pendulum run all``.

A scenario alternates between sequential parts (a fit whose each step needs the last) and parallel
sweeps; run one after another, the sequential parts leave a core idle. Running ``jobs`` scenarios
at a time (one per core by default) keeps the cores busy. Each child is ``python -m
double_pendulum.cli run NAME ...``, so it writes its results exactly as a single run does (fresh
folder, replaced on success), and a scenario cannot disturb another's process (libcosim and fmpy's
container FMU failed to load their FMUs in a process that had already run the pythonfmu FMU).

The children's lines reach the terminal as they come, each marked with its scenario's name; their
progress counters are plain lines (``DOUBLE_PENDULUM_PROGRESS=lines``: two tqdm bars would
overwrite each other), while the parent shows one bar over the scenarios, each weighted by its
expected CPU time (:data:`double_pendulum.scenarios.EXPECTED_CPU_S`), so that its rate and time
left mean something. The longest scenarios start first, so the run does not end on a long scenario
started last.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from .analysis.progress import ENV as PROGRESS_ENV
from .analysis.progress import progress_bar, write_line
from .analysis.sweep import WORKERS_ENV
from .scenarios import EXPECTED_CPU_S

POLL_S = 0.2
"""How often [s] the parent looks for finished children."""
STOP_GRACE_S = 10.0
"""How long [s] interrupted children may take to clean up before they are killed."""


def longest_first(names: Sequence[str]) -> list[str]:
    """``names`` ordered by expected CPU time, longest first (ties keep their order)."""
    return sorted(names, key=lambda name: -EXPECTED_CPU_S.get(name, 0.0))


def child_command(name: str, index: str, out: Path, fmu: Path, quick: bool, thorough: bool) -> list[str]:
    """The command line of the child that runs scenario ``name`` (``index``: "k/N" for its header)."""
    command = [sys.executable, "-m", "double_pendulum.cli", "run", name, "--out", str(out), "--fmu", str(fmu),
               "--index", index]  # fmt: skip
    if quick:
        command.append("--quick")
    if thorough:
        command.append("--thorough")
    return command


def child_environment() -> dict[str, str]:
    """The parent's environment, with progress as plain lines (unless switched off), unbuffered output and
    one worker process per child (unless ``$DOUBLE_PENDULUM_WORKERS`` is set): the children already run
    one per core, and a pool of spawned workers costs each sweep some seconds of imports."""
    env = dict(os.environ)
    if env.get(PROGRESS_ENV, "").strip().lower() != "off":
        env[PROGRESS_ENV] = "lines"
    env["PYTHONUNBUFFERED"] = "1"
    env.setdefault(WORKERS_ENV, "1")
    return env


def marked(name: str, line: str) -> str:
    """A child's line as the parent prints it: its own header and result lines as they are, every
    other line indented under the scenario's name."""
    text = line.rstrip("\n")
    if text.startswith("[") or text.startswith(f"{name}:"):
        return text
    return f"  {name}: {text.strip()}"


@dataclass
class Child:
    """A running scenario: its process and the threads that relay its output."""

    name: str
    process: subprocess.Popen
    relays: list[threading.Thread] = field(default_factory=list)


def _relay(name: str, stream: IO[str], target: Callable[[], IO[str]], lock: threading.Lock) -> None:
    for line in stream:
        with lock:
            write_line(marked(name, line), target())
    stream.close()


def start_child(name: str, command: list[str], lock: threading.Lock) -> Child:
    """Start a scenario's process and the threads that relay its stdout and stderr."""
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1,
                               env=child_environment())  # fmt: skip
    child = Child(name, process)
    for stream, target in ((process.stdout, lambda: sys.stdout), (process.stderr, lambda: sys.stderr)):
        thread = threading.Thread(target=_relay, args=(name, stream, target, lock), daemon=True)
        thread.start()
        child.relays.append(thread)
    return child


def _pause(seconds: float) -> None:
    """Wait between looks at the children (Ctrl-C arrives here as KeyboardInterrupt)."""
    time.sleep(seconds)


def _finish(child: Child) -> int:
    code = child.process.wait()
    for thread in child.relays:
        thread.join()
    return code


def _stop(children: Sequence[Child]) -> None:
    """After Ctrl-C: the children got the signal too; give them time to discard their unfinished
    folders, then kill what is left."""
    deadline = time.monotonic() + STOP_GRACE_S
    for child in children:
        try:
            child.process.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            child.process.kill()
        _finish(child)


def run_in_children(
    names: Sequence[str], out: Path, fmu: Path, *, quick: bool, thorough: bool, jobs: int
) -> list[str]:
    """Run every scenario of ``names`` in a child process, ``jobs`` at a time, longest first; return
    the names of those that failed (a child's exit code other than 0). Ctrl-C stops every child and
    raises KeyboardInterrupt once they have cleaned up."""
    order = longest_first(names)
    number = {name: f"{names.index(name) + 1}/{len(names)}" for name in names}
    lock = threading.Lock()
    waiting, running, failed = list(order), [], []
    weight = {name: max(1, round(EXPECTED_CPU_S.get(name, 1.0))) for name in names}
    label = f"{len(names)} scenarios, progress in expected CPU seconds"
    with progress_bar(sum(weight.values()), label, unit="CPU s") as bar:
        try:
            while waiting or running:
                while waiting and len(running) < jobs:
                    name = waiting.pop(0)
                    running.append(start_child(name, child_command(name, number[name], out, fmu, quick, thorough),
                                               lock))  # fmt: skip
                _pause(POLL_S)
                for child in [c for c in running if c.process.poll() is not None]:
                    running.remove(child)
                    code = _finish(child)
                    if code != 0:
                        failed.append(child.name)
                        if code not in (1, 2):  # the child's own line says why for 1 and 2
                            with lock:
                                write_line(f"{child.name}: FAILED: its process ended with code {code}", sys.stderr)
                    bar.update(weight[child.name])
        except KeyboardInterrupt:
            _stop(running)
            raise
    return [name for name in names if name in failed]
