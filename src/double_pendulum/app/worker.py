"""The app's runs, each in a process of its own: started, watched and cancelled by the request that owns it.

A run is :func:`fmpy.simulate_fmu` on ``DoublePendulum.fmu`` through
:class:`~double_pendulum.fmu.running.runner.FmuRunner` (a new FMU instance a run, as a bare ``simulate_fmu`` call makes,
with the FMU's log collected so a failed run reports the FMU's own message). A process a run keeps two browser
tabs' runs apart (each has its FMU instance, its fmpy logger and its interpreter state) and makes a run
cancellable at any point: the process is terminated. The FMU is extracted once, by :class:`Runs`, which removes it
when closed, and a run's progress comes through its pipe: a run's process owns no file and no shared memory, so one
terminated or killed leaves nothing behind. The processes come from a fork server that has imported
fmpy, NumPy and the package once, so a run starts in milliseconds.

The kinds of run (:data:`KINDS`): ``case`` (the form's case), ``twins`` (the case and the same with ``phi1_0``
moved by :data:`~double_pendulum.scenarios.free_swing.NUDGE_RAD`, as ``free_swing`` runs its twin starts) and
``measured`` (``measured_vs_sim``'s main prediction of the camera's track: the start and camera geometry fitted to
the track, the losses fitted to the measured energy decay, :mod:`.measured`; the first such run fits them, later ones
read the fits from the cache).
"""

from __future__ import annotations

import math
import multiprocessing
import shutil
import threading
import uuid
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from time import monotonic
from typing import Any

KINDS = ("case", "twins", "measured")
Progress = Callable[[float], None]
"""What a run tells its progress to: the run's time [s]."""
PRELOAD = ["numpy", "fmpy", "double_pendulum.app.worker", "double_pendulum.fmu.running.runner"]


def _columns(result: Any) -> dict[str, list[float]]:
    return {name: result[name].tolist() for name in result.dtype.names}


def run_case(fmu: str, start_values: Mapping[str, Any], stop_time: float, output_interval: float,
             progress: Progress | None = None) -> dict[str, Any]:
    """One run of the FMU (an FMU file or its extracted folder): its columns (every output), or the FMU's message
    and the rows before it. ``progress`` is told the run's time [s] after each step."""
    from ..fmu.running.runner import FmuRunError, FmuRunner

    def step_finished(time: float, recorder: Any) -> bool:
        if progress is not None:
            progress(time)
        return True

    with FmuRunner(fmu, reuse_instance=False) as runner:
        try:
            result = runner.simulate(start_values, stop_time=stop_time, output_interval=output_interval,
                                     step_finished=step_finished)
        except FmuRunError as error:
            partial = error.partial_result
            return {"columns": _columns(partial) if partial is not None and len(partial) else None,
                    "message": str(error).split(" -- FMU says: ")[-1], "units": runner.units}
        return {"columns": _columns(result), "message": None, "units": runner.units}


def run_twins(fmu: str, start_values: Mapping[str, Any], stop_time: float, output_interval: float,
              progress: Progress | None = None) -> dict[str, Any]:
    """The case and its twin, ``phi1_0`` a hair larger (``free_swing``'s nudge)."""
    from double_pendulum.scenarios.free_swing import NUDGE_RAD

    first = run_case(fmu, start_values, stop_time, output_interval, progress)
    if first["message"]:
        return first
    nudged = {**start_values, "phi1_0": float(start_values.get("phi1_0", 0.0)) + NUDGE_RAD}
    second = run_case(fmu, nudged, stop_time, output_interval, progress)
    return {**first, "twin": second["columns"], "message": second["message"], "nudge_rad": NUDGE_RAD}


def run_measured(fmu: str, start_values: Mapping[str, Any], stop_time: float, output_interval: float,
                 progress: Progress | None = None) -> dict[str, Any]:
    """``measured_vs_sim``'s main prediction against the camera's track (:func:`.measured.run_measured`: the start and
    camera geometry fitted to the track, the fitted losses); the form's ``start_values``, ``stop_time`` and
    ``output_interval`` do not apply. ``progress`` is told ``stop_time`` times the fraction done."""
    from .measured import run_measured as measured

    return measured(fmu, progress=None if progress is None else lambda fraction: progress(fraction * stop_time))


RUNS = {"case": run_case, "twins": run_twins, "measured": run_measured}


def _progress_through(sender: Any) -> Progress:
    """A run's progress, sent to the app through the run's pipe at most every :data:`PROGRESS_EVERY_S` of wall
    time. A pipe, not shared memory: a run's process owns nothing that outlives it (multiprocessing's shared values
    can need a temporary folder that only a normal exit of the app removes)."""
    sent_at = -math.inf

    def report(time: float) -> None:
        nonlocal sent_at
        now = monotonic()
        if now - sent_at >= PROGRESS_EVERY_S:
            sender.send(("progress", time))
            sent_at = now

    return report


PROGRESS_EVERY_S = 0.05
KEEP_ANSWER_S = 600.0
"""How long [s] a run's answer waits to be collected before a later start forgets it."""


def _child(kind: str, fmu: str, start_values: dict[str, Any], stop_time: float, output_interval: float,
           sender: Any) -> None:
    try:
        answer = RUNS[kind](fmu, start_values, stop_time, output_interval, _progress_through(sender))
    except Exception as error:  # the run's own failure, shown in the app
        answer = {"columns": None, "message": f"{type(error).__name__}: {error}"}
    sender.send(("answer", answer))
    sender.close()


@dataclass
class Job:
    """A run in its process: the pipe its progress and its answer come through, its ``progress`` [s of run
    time] as last heard."""

    kind: str
    stop_time: float
    process: Any
    receiver: Any
    progress: float = 0.0
    answer: dict[str, Any] | None = None
    answered_at: float = math.inf  # monotonic time [s] the answer came (or the run ended without one)

    def poll(self) -> dict[str, Any] | None:
        """The run's answer once it has come (None while it runs); reads the progress sent so far."""
        while self.answer is None and self.receiver.poll():
            try:
                what, payload = self.receiver.recv()
            except EOFError:  # the process ended (or died) before it sent its answer
                self.process.join()
                self.answer = self._ended()
                break
            if what == "progress":
                self.progress = payload
            else:
                self.answer = payload
                self.process.join()
        if self.answer is None and not self.process.is_alive() and not self.receiver.poll():
            self.answer = self._ended()
        if self.answer is not None and self.answered_at == math.inf:
            self.answered_at = monotonic()
        return self.answer

    def _ended(self) -> dict[str, Any]:
        return {"columns": None, "message": f"the run's process ended without an answer "
                                            f"(exit code {self.process.exitcode})"}

    def cancel(self) -> None:
        """Stop the run now (its process is terminated)."""
        if self.process.is_alive():
            self.process.terminate()
        self.process.join()
        self.answer = self.answer or {"columns": None, "message": "cancelled"}


@dataclass
class Runs:
    """The runs of one app, by an id each browser tab keeps in its own store (no tab sees another's run)."""

    fmu: Path
    context: Any = None
    jobs: dict[str, Job] = field(default_factory=dict)
    lock: Any = field(default_factory=threading.Lock)  # the server answers requests on threads of its own
    unzipdir: str = ""  # the FMU extracted for every run (removed by close)

    def __post_init__(self) -> None:
        from fmpy import extract

        if self.context is None:
            self.context = multiprocessing.get_context("forkserver")
            self.context.set_forkserver_preload(PRELOAD)
        self.unzipdir = extract(str(self.fmu))

    def start(self, kind: str, start_values: Mapping[str, Any], stop_time: float, output_interval: float) -> str:
        """Start a run of ``kind`` (:data:`KINDS`); its id. Answers not collected :data:`KEEP_ANSWER_S` after they
        came (a tab closed before it read its run's) are forgotten now."""
        receiver, sender = self.context.Pipe(duplex=False)
        process = self.context.Process(target=_child, args=(kind, self.unzipdir, dict(start_values), stop_time,
                                                           output_interval, sender), daemon=True)
        process.start()
        sender.close()
        run_id = uuid.uuid4().hex
        with self.lock:
            now = monotonic()
            for old in [k for k, job in self.jobs.items() if now - job.answered_at > KEEP_ANSWER_S]:
                del self.jobs[old]
            self.jobs[run_id] = Job(kind, stop_time, process, receiver)
        return run_id

    def poll(self, run_id: str) -> tuple[float, dict[str, Any] | None] | None:
        """How far the run is (0 to 1) and its answer once it has come, as often as asked (a browser may drop the
        reply to one request when it sends the next); None for a run not known (collected, cancelled, or the app
        was restarted)."""
        with self.lock:
            job = self.jobs.get(run_id)
            if job is None:
                return None
            answer = job.poll()
            return (1.0 if answer is not None else min(1.0, job.progress / max(job.stop_time, 1e-12))), answer

    def collect(self, run_id: str) -> dict[str, Any] | None:
        """The run's answer, which is then forgotten here; None while it runs or for a run not known."""
        with self.lock:
            job = self.jobs.get(run_id)
            if job is None or job.poll() is None:
                return None
            del self.jobs[run_id]
            return job.answer

    def cancel(self, run_id: str) -> None:
        with self.lock:
            job = self.jobs.pop(run_id, None)
        if job is not None:
            job.cancel()

    def close(self) -> None:
        """Cancel the runs still going, then remove the extracted FMU."""
        for run_id in list(self.jobs):
            self.cancel(run_id)
        shutil.rmtree(self.unzipdir, ignore_errors=True)
