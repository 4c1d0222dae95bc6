"""Run several scenarios at once in child processes: ``double-pendulum run all``.

A scenario alternates between sequential parts (a fit whose each step needs the last) and parallel
sweeps; run one after another, the sequential parts leave a core idle. Running ``jobs`` children at
a time (one per core by default) keeps the cores busy. Each child is ``python -m
double_pendulum.cli run NAME... --jobs 1 ...``, so it writes its results exactly as a single run
does (fresh folder, replaced on success).

What the pool knows of the scenarios, their expected CPU times and which reads another's cached fit, the
command line gives it (:class:`Costs`, from :mod:`double_pendulum.scenarios`): the pool imports no scenario.
A default or thorough run gives every scenario a child of its own, the longest first (by
:data:`double_pendulum.scenarios.EXPECTED_CPU_S`), so the run does not end on a long scenario started
last, and a scenario cannot disturb another's process; only the small ones (under
:data:`SMALL_SCENARIO_CPU_S`) share children of at most :data:`SMALL_GROUP_CPU_S` (:func:`pack_small`),
placed by their sums. A quick run is dominated by the imports
(NumPy, SciPy, Matplotlib, fmpy: some 2.5 s of CPU per process), so it starts only ``jobs`` children,
each running its share of the scenarios one after another (:func:`scenario_groups`: balanced by
:data:`double_pendulum.scenarios.EXPECTED_QUICK_CPU_S`; ``measured_vs_sim`` after ``loss_identification``
in the same group, so it reads that one's cached fit instead of fitting it again,
:data:`double_pendulum.scenarios.READS_FITS_OF`).

The children's lines reach the terminal as they come, each marked with the name of the scenario
running in its child (a child's header line ``[k/N] NAME: ...`` says which, k counting the scenarios in
the order they start); their progress counters are plain lines (``DOUBLE_PENDULUM_PROGRESS=lines``: two
tqdm bars would overwrite each other), while the parent shows one bar over the scenarios, each weighted
by its expected CPU time, so that its rate and time left mean something. A running scenario is credited
with the work it has done so far: the CPU time its child (with the child's own workers) has used since the
scenario started (:func:`tree_cpu_s`; where that cannot be read, the time it has run), so on a loaded machine
the bar moves as slowly as the work does, not with the clock. A scenario that needs more than its expected
CPU time is given more: its share grows to keep :data:`CREDIT_CAP` of it done while it runs, and the bar's
total with it (:func:`progress_state`), so the bar never stands still while work is done and its time left,
(total - done) over the rate of work, stays bounded. Its whole share is added when its ``wrote`` or ``FAILED``
line arrives, what is left of a child's share when the child ends.

Ctrl-C reaches the children too (they share the terminal's process group): each discards its unfinished
scenario and ends; the parent waits up to :data:`STOP_GRACE_S` for them, kills what is left, and a
second Ctrl-C ends that wait at once (:func:`double_pendulum.runs.interrupts.hurried`).
"""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from .interrupts import acknowledge, hurried
from .lines import FAILED, WROTE, failed_line, header_name, outcome, renumbered
from .progress import ENV as PROGRESS_ENV
from .progress import progress_bar, write_line
from .workers import WORKERS_ENV

POLL_S = 0.2
"""How often [s] the parent looks for finished children."""
STOP_GRACE_S = 5.0
"""How long [s] interrupted children may take to clean up before they are killed."""
CREDIT_CAP = 0.9
"""At most this fraction of a running scenario's share of the progress bar is credited before it reports: a
scenario that has done more work than that grows its share (:func:`progress_state`)."""


def tree_cpu_s(pid: int) -> float | None:
    """CPU time [s] (user and system) that process ``pid`` has used, with the children it has waited for and the
    descendants still running, from Linux's ``/proc``; None where that cannot be read (not Linux, or the process
    has gone)."""
    ticks, stack, first = 0, [pid], True
    while stack:
        process = stack.pop()
        try:
            fields = Path(f"/proc/{process}/stat").read_text().rsplit(")", 1)[1].split()
            ticks += sum(int(value) for value in fields[11:15])  # utime, stime, cutime, cstime
            for task in Path(f"/proc/{process}/task").iterdir():
                stack += [int(child) for child in (task / "children").read_text().split()]
        except (OSError, ValueError, IndexError):
            if first:
                return None
        first = False
    return ticks / os.sysconf("SC_CLK_TCK")


@dataclass(frozen=True)
class Costs:
    """What the pool knows of the scenarios it schedules, given by the caller (the command line passes
    :data:`double_pendulum.scenarios.EXPECTED_CPU_S`, ``EXPECTED_QUICK_CPU_S`` and ``READS_FITS_OF``): the expected
    CPU time [s] of each in a default and in a quick run, and which scenario reads a fit another one caches (by
    the name of that one)."""

    default: Mapping[str, float]
    quick: Mapping[str, float]
    reads_fits_of: Mapping[str, str] = field(default_factory=dict)

    def cpu_s(self, name: str, quick: bool) -> float:
        """The expected CPU time [s] of scenario ``name`` in a quick or a default run (1 s if unknown)."""
        return (self.quick if quick else self.default).get(name, 1.0)


def longest_first(names: Sequence[str], costs: Costs, quick: bool = False) -> list[str]:
    """``names`` ordered by expected CPU time, longest first (ties keep their order)."""
    return sorted(names, key=lambda name: -costs.cpu_s(name, quick))


def _units(names: Sequence[str], costs: Costs) -> list[list[str]]:
    """``names`` (longest first) as the units :func:`balanced_groups` places: one scenario each, except that a
    scenario reading another's cached fit (:attr:`Costs.reads_fits_of`) follows that one in its unit, if both are
    in ``names``."""
    order = longest_first(names, costs, quick=True)
    reads = costs.reads_fits_of
    units = {name: [name] for name in order if reads.get(name) not in order}
    for name in order:
        if name not in units:
            units[reads[name]].append(name)
    return list(units.values())


def balanced_groups(names: Sequence[str], count: int, costs: Costs) -> list[list[str]]:
    """``names`` shared out among ``count`` groups of about equal expected quick-run CPU time: each unit
    (a scenario; with fewer groups than scenarios, a scenario and those reading its cached fit,
    :func:`_units`), the longest first, joins the group with the least so far. Within a group the
    scenarios run in the order they joined (a reader after the scenario it reads from); the groups come
    largest first; none is empty."""
    units = _units(names, costs) if count < len(names) else [[name] for name in longest_first(names, costs, True)]
    units.sort(key=lambda unit: -sum(costs.cpu_s(name, quick=True) for name in unit))  # stable: ties keep order
    groups: list[list[str]] = [[] for _ in range(max(1, min(count, len(units))))]
    totals = [0.0] * len(groups)
    for unit in units:
        least = totals.index(min(totals))
        groups[least] += unit
        totals[least] += sum(costs.cpu_s(name, quick=True) for name in unit)
    order = sorted(range(len(groups)), key=lambda k: -totals[k])
    return [groups[k] for k in order if groups[k]]


SMALL_SCENARIO_CPU_S = 30.0
"""Default-run scenarios expected to take less CPU time [s] than this share children: a child of their
own would cost each some 3 s of CPU importing NumPy, SciPy, Matplotlib and fmpy."""
SMALL_GROUP_CPU_S = 40.0
"""At most this much expected CPU time [s] in one child of small scenarios (several small children, not
one large one: the last children to start are short, so the cores finish at about the same time)."""


def pack_small(names: Sequence[str], costs: Costs, cap: float = SMALL_GROUP_CPU_S) -> list[list[str]]:
    """``names`` (longest first) packed first-fit into groups of at most ``cap`` expected default-run CPU
    seconds (a scenario over ``cap`` alone)."""
    groups: list[list[str]] = []
    totals: list[float] = []
    for name in names:
        cost = costs.cpu_s(name, quick=False)
        fit = next((k for k, total in enumerate(totals) if total + cost <= cap), None)
        if fit is None:
            groups.append([name])
            totals.append(cost)
        else:
            groups[fit].append(name)
            totals[fit] += cost
    return groups


def scenario_groups(names: Sequence[str], costs: Costs, *, quick: bool, jobs: int,
                    thorough: bool = False) -> list[list[str]]:  # fmt: skip
    """The scenarios each child runs, in the order the children start: in a quick run ``jobs``
    balanced groups (:func:`balanced_groups`), otherwise one scenario per child, except that those
    under :data:`SMALL_SCENARIO_CPU_S` share children of at most :data:`SMALL_GROUP_CPU_S`
    (:func:`pack_small`); the children with the most expected CPU time first. ``thorough``: a scenario
    reading another's cached fits (:attr:`Costs.reads_fits_of`) runs after that one in its child, as in a quick
    run (``measured_vs_sim --thorough`` predicts the motion with ``loss_identification --thorough``'s half
    fits, which it would otherwise fit again, one after another)."""
    if quick:
        return balanced_groups(names, jobs, costs)
    order = longest_first(names, costs)
    readers = {r: w for r, w in costs.reads_fits_of.items() if thorough and r in order and w in order}
    small = [name for name in order if costs.cpu_s(name, quick=False) < SMALL_SCENARIO_CPU_S and name not in readers]
    groups = [[name] for name in order if name not in small and name not in readers] + pack_small(small, costs)
    for reader, writer in readers.items():
        next(group for group in groups if writer in group).append(reader)
    return sorted(groups, key=lambda group: -sum(costs.cpu_s(name, quick=False) for name in group))


def child_command(names: Sequence[str], indices: Sequence[str], out: Path, fmu: Path, quick: bool,
                  thorough: bool) -> list[str]:  # fmt: skip
    """The command line of the child that runs the scenarios ``names`` one after another in its own
    process (``indices``: their "k/N" in the parent's run, for their header lines)."""
    command = [sys.executable, "-m", "double_pendulum.cli", "run", *names, "--out", str(out), "--fmu", str(fmu),
               "--index", ",".join(indices), "--jobs", "1"]  # fmt: skip
    if quick:
        command.append("--quick")
    if thorough:
        command.append("--thorough")
    return command


def child_environment(workers: int = 1) -> dict[str, str]:
    """The parent's environment, with progress as plain lines (unless switched off), unbuffered output and
    ``workers`` worker processes per child (unless ``$DOUBLE_PENDULUM_WORKERS`` is set): one when the children
    already run one per core (a pool of spawned workers costs each sweep some seconds of imports), more when
    there are fewer children than cores."""
    env = dict(os.environ)
    if env.get(PROGRESS_ENV, "").strip().lower() != "off":
        env[PROGRESS_ENV] = "lines"
    env["PYTHONUNBUFFERED"] = "1"
    env.setdefault(WORKERS_ENV, str(workers))
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
    """A running child: its scenarios, its process, the threads that relay its output, the scenario
    running in it now and the outcome (WROTE or FAILED) each scenario has reported so far."""

    names: tuple[str, ...]
    process: subprocess.Popen
    current: str
    outcomes: dict[str, str] = field(default_factory=dict)
    relays: list[threading.Thread] = field(default_factory=list)
    started: float = field(default_factory=time.monotonic)
    """When :attr:`current` started (time.monotonic)."""
    number: Callable[[], str] | None = None
    """The next "k/N" for a header line (the parent counts the scenarios in the order they start); None: the
    child's own."""
    cpu: Callable[[], float | None] | None = None
    """The CPU time [s] the child has used so far (:func:`tree_cpu_s` of its process); None: not known."""
    cpu_started: float | None = None
    """:attr:`cpu` when :attr:`current` started."""

    def __post_init__(self) -> None:
        self.cpu_started = self.cpu() if self.cpu else None

    def work_done(self, now: float) -> float:
        """The work [CPU s] done on :attr:`current` so far: the CPU time used since it started, or where that is
        not known the time [s] since it started (time.monotonic ``now``)."""
        used = self.cpu() if self.cpu and self.cpu_started is not None else None
        return now - self.started if used is None else max(0.0, used - self.cpu_started)

    def take(self, line: str) -> tuple[str, str | None]:
        """Read a line of the child: switch :attr:`current` on a header line (numbered in the order the
        scenarios start), note a first outcome; return the line as the parent prints it and the scenario
        that has just reported (or None)."""
        header = header_name(line, self.names)
        if header is not None:
            self.current, self.started = header, time.monotonic()
            self.cpu_started = self.cpu() if self.cpu else None
            line = line if self.number is None else renumbered(line, self.number())
        reported = outcome(line, self.names)
        text = marked(reported[0] if reported else self.current, line)
        if reported is None or reported[0] in self.outcomes:
            return text, None
        self.outcomes[reported[0]] = reported[1]
        return text, reported[0]

    def failures(self, code: int) -> list[str]:
        """The scenarios that failed, once the child ended with ``code``: those that said FAILED and,
        if the code is not 0, those that had not said WROTE."""
        return [name for name in self.names
                if self.outcomes.get(name) == FAILED or (code != 0 and self.outcomes.get(name) != WROTE)]  # fmt: skip

    def unreported(self) -> list[str]:
        """The scenarios that have reported no outcome."""
        return [name for name in self.names if name not in self.outcomes]


def _relay(child: Child, stream: IO[str], target: Callable[[], IO[str]], lock: threading.Lock,
           reported: Callable[[str], None]) -> None:  # fmt: skip
    """Print the lines of one of ``child``'s streams as they come; call ``reported(name)`` (under
    ``lock``) when a scenario reports its outcome."""
    for line in stream:
        with lock:
            text, name = child.take(line)
            write_line(text, target())
            if name is not None:
                reported(name)
    stream.close()


def start_child(names: Sequence[str], command: list[str], lock: threading.Lock,
                reported: Callable[[str], None], number: Callable[[], str] | None = None,
                workers: int = 1) -> Child:  # fmt: skip
    """Start a child running the scenarios ``names`` with ``workers`` worker processes (:func:`child_environment`)
    and the threads that relay its stdout and stderr (``number``: the "k/N" of the next scenario to start in the
    run, for its header line)."""
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1,
                               env=child_environment(workers))  # fmt: skip
    child = Child(tuple(names), process, current=names[0], number=number, cpu=lambda: tree_cpu_s(process.pid))
    for stream, target in ((process.stdout, lambda: sys.stdout), (process.stderr, lambda: sys.stderr)):
        thread = threading.Thread(target=_relay, args=(child, stream, target, lock, reported), daemon=True)
        thread.start()
        child.relays.append(thread)
    return child


def _pause(seconds: float) -> None:
    """Wait between looks at the children (Ctrl-C arrives here as KeyboardInterrupt)."""
    time.sleep(seconds)


def _finish(child: Child) -> int:
    """Wait for the child and for its relayed lines; return its exit code."""
    code = child.process.wait()
    for thread in child.relays:
        thread.join()
    return code


def _stop(children: Sequence[Child]) -> None:
    """After Ctrl-C: the children got the signal too; give them :data:`STOP_GRACE_S` to discard their
    unfinished folders (less if a second Ctrl-C hurries), then kill what is left."""
    deadline = time.monotonic() + STOP_GRACE_S
    while any(child.process.poll() is None for child in children):
        if hurried() or time.monotonic() >= deadline:
            break
        time.sleep(0.05)
    for child in children:
        if child.process.poll() is None:
            child.process.kill()
        _finish(child)


def _failures_of_ended(child: Child, lock: threading.Lock) -> tuple[list[str], list[str]]:
    """Once ``child`` has ended: the scenarios that failed, and those still unreported (each failed one
    among them gets a line that says how its process ended)."""
    code = _finish(child)
    failures, unreported = child.failures(code), child.unreported()
    with lock:
        for name in (n for n in unreported if n in failures):
            write_line(failed_line(name, f"its process ended with code {code}"), sys.stderr)
    return failures, unreported


def progress_state(weight: Mapping[str, float], done: Mapping[str, float], running: Sequence[Child],
                   now: float) -> tuple[float, float]:  # fmt: skip
    """(work done, whole work) [expected CPU s] at ``now`` (time.monotonic), and in :attr:`Child.work_done` terms:
    the scenarios ``done`` count what they were given (their share, or more if they overran), a running child's
    current scenario the work it has done so far, its share at least that over :data:`CREDIT_CAP` (one that
    overruns its expected CPU time grows the whole instead of standing still at the cap), every other scenario its
    ``weight``."""
    work = dict(weight)
    work.update(done)
    credit = 0.0
    for child in running:
        if child.current in done:
            continue
        used = child.work_done(now)
        work[child.current] = max(weight[child.current], used / CREDIT_CAP)
        credit += used
    return sum(done.values()) + credit, sum(work.values())


def run_in_children(
    names: Sequence[str], out: Path, fmu: Path, costs: Costs, *, quick: bool, thorough: bool, jobs: int
) -> list[str]:
    """Run the scenarios ``names`` in child processes, ``jobs`` at a time (:func:`scenario_groups`:
    one scenario per child, or in a quick run ``jobs`` children with a group each); return the names
    of those that failed, in the order of ``names``. Ctrl-C stops every child and raises
    KeyboardInterrupt once they have cleaned up."""
    weight = {name: float(max(1, round(costs.cpu_s(name, quick)))) for name in names}
    lock = threading.Lock()
    waiting, running, failed = scenario_groups(names, costs, quick=quick, jobs=jobs, thorough=thorough), [], []
    order = [name for group in waiting for name in group]  # the children's own "k/N": until their header is seen
    workers = max(1, jobs // max(1, len(waiting)))  # fewer children than cores: the spare cores to their sweeps
    starts = itertools.count(1)
    done: dict[str, float] = {}  # scenarios whose whole share the bar holds, and that share
    shares = dict(weight)  # each scenario's share as last seen (grown if it overran)

    def number() -> str:
        return f"{next(starts)}/{len(names)}"

    def reported(name: str) -> None:
        done[name] = shares[name]

    label = f"{len(names)} scenarios, progress in expected CPU seconds"
    with progress_bar(round(sum(weight.values())), label, unit="CPU s") as bar:
        try:
            while waiting or running:
                while waiting and len(running) < jobs:
                    group = waiting.pop(0)
                    indices = [f"{order.index(n) + 1}/{len(names)}" for n in group]
                    command = child_command(group, indices, out, fmu, quick, thorough)
                    running.append(start_child(group, command, lock, reported, number, workers))
                _pause(POLL_S)
                for child in [c for c in running if c.process.poll() is not None]:
                    running.remove(child)
                    failures, unreported = _failures_of_ended(child, lock)
                    failed.extend(failures)
                    with lock:
                        done.update((name, shares[name]) for name in unreported)
                with lock:
                    for child in running:
                        if child.current not in done:
                            shares[child.current] = max(weight[child.current],
                                                        child.work_done(time.monotonic()) / CREDIT_CAP)
                    work, whole = progress_state(weight, done, running, time.monotonic())
                    bar.set_total(max(round(whole), bar.total))
                    bar.update(max(0, int(work) - bar.n))
        except KeyboardInterrupt:
            acknowledge()
            _stop(running)
            raise
    return [name for name in names if name in failed]
