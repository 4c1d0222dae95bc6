"""Shared fixtures: the FMU is built once per test session into a temporary folder."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import tempfile
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import sanitize

from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.runs.result_cache import CACHE_ENV

if TYPE_CHECKING:
    from wine import Wine

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "data"


def session_shared(tmp_path_factory: pytest.TempPathFactory, name: str, make: Callable[[Path], object]) -> Path:
    """Folder ``name`` of the whole session, made and filled once by ``make(folder)``.

    With pytest-xdist the workers share it (the xdist documentation's recipe): the first worker that needs it
    fills it under a file lock in the session's common temporary folder (the parent of each worker's own), the
    others wait for the lock and read it. A ``make`` that raises leaves no marker, so the next worker tries again.
    """
    import fcntl

    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base  # one folder per session
    folder, done = shared / name, shared / f"{name}.done"
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.is_file():
            shutil.rmtree(folder, ignore_errors=True)  # what a failed make left
            make(folder)
            done.write_text("")
    return folder


BUILT_FMUS = ("DoublePendulum.fmu", "Suspension.fmu", "PendulumOnSuspension.ssp", "PendulumOnSuspension.fmu",
              "fmi3/DoublePendulum.fmu")
"""What :func:`~double_pendulum.fmu.build.systems.build_all` writes, relative to its folder, in its order."""


@pytest.fixture(scope="session")
def built_fmus(built_by_the_command: tuple[Path, int, str]) -> list[Path]:
    """Every FMU ``double-pendulum build`` writes (:data:`BUILT_FMUS`), freshly built once for the whole session
    by that command (:func:`built_by_the_command`). Tests read them; none writes into their folder."""
    folder, code, _ = built_by_the_command
    assert code == 0, built_by_the_command
    return [folder / name for name in BUILT_FMUS]


@pytest.fixture(scope="session")
def built_by_the_command(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int, str]:
    """``double-pendulum build -o FOLDER/DoublePendulum.fmu`` run once for the session (shared by the xdist workers:
    :func:`session_shared`), FOLDER not there before: FOLDER, the exit status and what the command printed.
    tests/test_cli.py checks the command by them; the other tests take the FMUs (:func:`built_fmus`)."""
    import io

    from double_pendulum.cli import main

    def build(record: Path) -> None:
        record.mkdir()
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            code = main(["build", "-o", str(record / "fmu" / "DoublePendulum.fmu")])
        (record / "command.json").write_text(json.dumps({"code": code, "out": out.getvalue()}))

    record = session_shared(tmp_path_factory, "build_command", build)
    command = json.loads((record / "command.json").read_text())
    return record / "fmu", command["code"], command["out"]


OLD = 1577836800.0
"""2020-01-01, an mtime older than any source of the project: the project would rebuild an FMU of its own this old."""


def users_folder(folder: Path, built_fmus: list[Path]) -> Path:
    """Make ``folder``, a user's folder with FMUs of theirs dated 2020 (:data:`OLD`, older than the sources) in
    ``models/``: ``Other.fmu`` (a copy of the project's DoublePendulum.fmu), ``Other3.fmu`` (of the FMI 3.0 one),
    ``Suspension.fmu`` beside them and ``Container.fmu`` (fmpy's container FMU of the coupled system: a real FMU,
    not the pendulum's), and a note of theirs; every entry, the folders too, dated 2020."""
    models = folder / "models"
    models.mkdir(parents=True)
    built = dict(zip(BUILT_FMUS, built_fmus))
    for source, name in (("DoublePendulum.fmu", "Other.fmu"), ("fmi3/DoublePendulum.fmu", "Other3.fmu"),
                         ("Suspension.fmu", "Suspension.fmu"), ("PendulumOnSuspension.fmu", "Container.fmu")):
        shutil.copyfile(built[source], models / name)
    (models / "notes.txt").write_text("the user's own file\n")
    for path in (*models.iterdir(), models, folder):
        os.utime(path, (OLD, OLD))
    return folder


def folder_state(folder: Path) -> dict[str, tuple[str, int, int]]:
    """Every entry under ``folder``, recursively, and the folder itself: its kind, size and mtime (ns), by path."""
    state = {}
    for path in [folder, *folder.rglob("*")]:
        info = path.lstat()
        kind = "folder" if path.is_dir() and not path.is_symlink() else "file"
        state[path.relative_to(folder).as_posix()] = (kind, info.st_size, info.st_mtime_ns)
    return state


@pytest.fixture(scope="session")
def fmu_path(built_fmus: list[Path]) -> Path:
    """A freshly built DoublePendulum.fmu, with the other FMUs and the coupled system next to it, as ``run``
    wants them (built once per session)."""
    return built_fmus[0]


@pytest.fixture(scope="session")
def fmu3_path(built_fmus: list[Path]) -> Path:
    """A freshly built FMI 3.0 DoublePendulum.fmu, Model Exchange and Co-Simulation (built once per session, by
    ``build_all`` into ``fmi3/`` beside the FMI 2.0 one, as ``double-pendulum build`` puts it)."""
    return built_fmus[-1]


@pytest.fixture(scope="session")
def wine(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Wine]:
    """A private Wine prefix of this test process (tests/wine.py's ``Wine``), to run the C hosts' Windows builds in:
    made on first use, its processes ended and the prefix removed at the end; skips where wine64 is missing."""
    from wine import Wine

    yield from Wine.session(tmp_path_factory)


@pytest.fixture(scope="session")
def cross_check_tree(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int, str]:
    """``double-pendulum cross-check DIR`` run once for the session (shared by the xdist workers:
    :func:`session_shared`) into a folder that already holds another vendor's files and a stale folder of ours:
    DIR, the exit status and what the command printed. Its FMUs, the reference cases' freshly built, are read by
    tests/test_cross_check.py and tests/test_reference_results.py; no test writes into DIR."""
    import io

    from double_pendulum import __version__
    from double_pendulum.cli import main
    from double_pendulum.fmu.crosscheck.tree import PLATFORM, TOOL

    def run(folder: Path) -> None:
        root = folder / "tree"
        other = root / "fmus" / "2.0" / "cs" / PLATFORM / "OtherTool" / "1.0" / "Model"
        other.mkdir(parents=True)
        (other / "keep.txt").write_text("another vendor's file")
        (other / "notCompliantWithLatestRules").write_text("")  # what fmpy's validator then skips
        (root / "fmus" / "2.0" / "cs" / PLATFORM / TOOL / __version__ / "Removed").mkdir(parents=True)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            code = main(["cross-check", str(root)])
        (folder / "command.json").write_text(json.dumps({"code": code, "out": out.getvalue()}))

    folder = session_shared(tmp_path_factory, "cross_check", run)
    command = json.loads((folder / "command.json").read_text())
    return folder / "tree", command["code"], command["out"]


@pytest.fixture(autouse=True)
def sigint_handler_kept(request: pytest.FixtureRequest) -> Iterator[None]:
    """No test leaves this process another Ctrl-C handler than it began with, in Python's table or in the kernel's:
    one that does is named in a warning and the handler put back. An ignored SIGINT is inherited through fork and
    exec, and Python started with it ignored keeps it so, so a leak would make every later test's child deaf to
    Ctrl-C. (On 2026-12-08 three Ctrl-C tests failed for that reason in runs started as background jobs of a shell
    without job control, which ignores SIGINT for the whole session: their children now set Python's handler
    themselves.)"""
    def keep(when: str) -> None:
        now, ignored = signal.getsignal(signal.SIGINT), kernel_ignores_sigint()
        if now is not SESSION_SIGINT or ignored != SESSION_SIGINT_IGNORED:
            signal.signal(signal.SIGINT, SESSION_SIGINT)  # sets the kernel's disposition to match Python's again
            warnings.warn(f"SIGINT's handler was {now!r} (kernel: {'ignored' if ignored else 'not ignored'}) {when} "
                          f"{request.node.nodeid}, not the session's {SESSION_SIGINT!r}: put back", stacklevel=1)

    keep("before")  # a session fixture's doing, or a test's whose own teardown ran after this check
    yield
    keep("after")


def kernel_ignores_sigint() -> bool:
    """Whether the kernel's disposition of SIGINT for this process is SIG_IGN (Linux: ``SigIgn`` of
    /proc/self/status; elsewhere Python's table, which is all there is to read)."""
    try:
        with open("/proc/self/status") as f:
            mask = next(int(line.split()[1], 16) for line in f if line.startswith("SigIgn:"))
    except (OSError, StopIteration, ValueError):
        return signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    return bool(mask >> (signal.SIGINT - 1) & 1)


SESSION_SIGINT = signal.getsignal(signal.SIGINT)
"""The Ctrl-C handler this test process began with (Python's own)."""
SESSION_SIGINT_IGNORED = kernel_ignores_sigint()
"""Whether the kernel ignored SIGINT for this test process when it began (no)."""


@pytest.fixture(scope="session", autouse=True)
def close_kept_runners() -> Iterator[None]:
    """At the end of each test process, close the FMU runners the sweeps keep per process (each holds an extracted
    FMU), as ``double-pendulum run`` does when it ends (``analysis.sweep.close_runners``)."""
    yield
    from double_pendulum.analysis.sweep import close_runners

    close_runners()


@pytest.fixture(scope="session")
def budget() -> dict:
    """The measured record's error budget of b (``analysis.decay.error_budget``), computed once per process."""
    from double_pendulum.analysis.decay.error_budget import error_budget
    from double_pendulum.analysis.decay.fit import calibrate_error_model
    from double_pendulum.analysis.track.measurement import load_track, reconstruct

    rec = reconstruct(load_track())
    m = rec.free_motion
    errors = calibrate_error_model(rec.t[m], rec.energy[m], rec.sigma_energy[m], rec.momentum[m])
    return error_budget(rec, errors.sigma)


@pytest.fixture(scope="session")
def runner(fmu_path: Path):
    """An fmpy runner for the session's FMU."""
    with FmuRunner(fmu_path) as r:
        yield r


@pytest.fixture(scope="session")
def quick_results(fmu_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Every scenario run once in quick mode (``double-pendulum run all --quick``) for the whole session.

    The scenarios' own tests read their results from here instead of running them again. With
    pytest-xdist the workers share one run: the first worker that needs it runs it under a file lock
    in the session's common temporary folder, the others wait and read it.
    """
    from double_pendulum.cli import main

    def run(out: Path) -> None:
        shared = out.parent
        tmpdir = shared / "quick_results.tmp"  # the run's $TMPDIR: what it leaves there is recorded
        shutil.rmtree(tmpdir, ignore_errors=True)
        tmpdir.mkdir()
        with temporary_folder(tmpdir):
            assert main(["run", "all", "--quick", "--fmu", str(fmu_path), "--out", str(out)]) == 0
        (shared / "quick_results.leftovers").write_text("".join(f"{p.name}\n" for p in tmpdir.iterdir()))

    return session_shared(tmp_path_factory, "quick_results", run)


@contextlib.contextmanager
def temporary_folder(folder: Path) -> Iterator[None]:
    """``folder`` as $TMPDIR (and :mod:`tempfile`'s folder) of this process and those it starts, in the block."""
    saved_env, saved = os.environ.get("TMPDIR"), tempfile.tempdir
    os.environ["TMPDIR"], tempfile.tempdir = str(folder), str(folder)
    try:
        yield
    finally:
        if saved_env is None:
            os.environ.pop("TMPDIR", None)
        else:
            os.environ["TMPDIR"] = saved_env
        tempfile.tempdir = saved


def quick_run_leftovers(results: Path) -> list[str]:
    """What the run of :func:`quick_results` left in its $TMPDIR."""
    return (results.parent / "quick_results.leftovers").read_text().split()


def quick_scenario(results: Path, name: str) -> tuple[Path, dict]:
    """The folder of scenario ``name`` in :func:`quick_results` and its summary."""
    folder = results / name
    return folder, json.loads((folder / "summary.json").read_text())


# --- the order the xdist workers take the modules in -----------------------------------------------------------
#
# Each module runs on one worker (--dist loadscope), handed out in collection order (--no-loadscope-reorder), a
# module to whichever worker is free: the longest first, so that no long module is left for the end while the
# other worker idles. LONGEST_FIRST are the modules of the most seconds (tests and module fixtures, measured on
# 2 workers, issue 36); the one second does not need the session's FMUs, so its worker works while the first
# builds them (conftest's built_fmus; the quick run needs them too). test_reference_results reads the
# cross-check's tree (cross_check_tree), which test_cross_check makes on the other worker: it comes last of them,
# where that tree is done, instead of beside test_cross_check, where its worker waited about 10 s for the tree.
# The rest follow by their number of tests, as pytest-xdist orders them itself, within a module the tests keep
# their order.
LONGEST_FIRST = (
    "test_host_hygiene", "test_loss_noise", "test_reports", "test_guard", "test_self_contained",
    "test_loss_identification", "test_python_host", "test_c_host", "test_python_choice", "test_cli",
    "test_cross_check", "test_state_matrix", "test_summary_types", "test_app", "test_page", "test_scenario_pool",
    "test_fmpy_tools", "test_wine", "test_bad_input", "test_chaos", "test_energy_budget", "test_reference_results",
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    rank = {name: k for k, name in enumerate(LONGEST_FIRST)}
    counts: dict[Path, int] = {}
    for item in items:
        counts[item.path] = counts.get(item.path, 0) + 1
    items.sort(key=lambda item: (rank.get(item.path.stem, len(rank)), -counts[item.path], str(item.path)))


# --- $TMPDIR: the suite leaves it as it found it -------------------------------------------------------------
#
# The controlling process gives the whole session (its workers inherit the environment) a $TMPDIR of its own, a
# folder in the user's: whatever a test or the code under test leaves in a temporary folder lands there. At the
# end the session fails if anything is left in it, naming it, and removes the folder, so the user's $TMPDIR holds
# nothing new either way. pytest's own tmp_path folders stay where pytest keeps them (PYTEST_DEBUG_TEMPROOT: the
# user's $TMPDIR, pytest-of-USER, which pytest rotates), so a failed test's files can still be looked at.
_SESSION_TMP: dict[str, object] = {}


def pytest_configure(config: pytest.Config) -> None:
    # DOUBLE_PENDULUM_SANITIZE=1 (scripts/check_memory.sh): the session's FMUs get a sanitized loader
    # (tests/sanitize.py); set here, before any FMU is built, in the controller and in each worker.
    sanitize.configure()
    if hasattr(config, "workerinput"):  # an xdist worker: the controller set $TMPDIR up
        return
    outer = tempfile.gettempdir()
    folder = Path(tempfile.mkdtemp(prefix="double-pendulum-tests-", dir=outer))
    cache = Path(tempfile.mkdtemp(prefix="double-pendulum-tests-cache-", dir=outer))
    _SESSION_TMP.update(folder=folder, cache=cache, saved=os.environ.get("TMPDIR"),
                        saved_root=os.environ.get(TEMPROOT), saved_cache=os.environ.get(CACHE_ENV))
    os.environ.setdefault(TEMPROOT, outer)
    os.environ["TMPDIR"], tempfile.tempdir = str(folder), None
    # The scenarios' result cache (runs.result_cache, read by analysis.solvers.reference too): one empty folder for
    # the session, shared by its workers and removed at its end, so that a run of the tests computes what a fresh
    # clone computes, whatever a working copy's .cache/ holds, and writes nothing there.
    os.environ[CACHE_ENV] = str(cache)


TEMPROOT = "PYTEST_DEBUG_TEMPROOT"
"""Where pytest puts its tmp_path folders (its own setting): the user's $TMPDIR, not the session's."""


def session_leftovers(folder: Path) -> list[str]:
    """What a session left in its $TMPDIR ``folder``: every entry, with the size of the folders among them."""
    def size(path: Path) -> int:
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) if path.is_dir() else path.stat().st_size

    return sorted(f"{p.name} ({size(p) / 1e6:.1f} MB)" for p in folder.iterdir())


# FMUs with pythonfmu's own binary (<= 0.7.0, upstream issue NTNU-IHB/PythonFMU#228), which the tests
# run as foreign neighbours of ours (tests/foreign_fmu.py), can corrupt the heap while the process tears
# down, aborting *after* every test has finished and turning a green run into exit code 134. Leave the
# finished session without the teardown. (The project's own FMUs are safe through exit:
# scripts/check_memory.sh.)
_exit_status: list[int] = []


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    folder = _SESSION_TMP.get("folder")
    if isinstance(folder, Path) and not hasattr(session.config, "workerinput"):
        left = session_leftovers(folder) if folder.is_dir() else []
        shutil.rmtree(folder, ignore_errors=True)
        shutil.rmtree(str(_SESSION_TMP["cache"]), ignore_errors=True)
        for name, saved in (("TMPDIR", _SESSION_TMP["saved"]), (TEMPROOT, _SESSION_TMP["saved_root"]),
                            (CACHE_ENV, _SESSION_TMP["saved_cache"])):
            if saved is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = str(saved)
        tempfile.tempdir = None
        if left:
            reporter = session.config.pluginmanager.get_plugin("terminalreporter")
            message = f"the test session left {len(left)} entries in its $TMPDIR (removed now): {', '.join(left)}"
            if reporter is not None:
                reporter.write_line(f"FAILED: {message}", red=True)
            exitstatus = session.exitstatus = pytest.ExitCode.TESTS_FAILED
    _exit_status.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    import os
    import sys

    if _exit_status:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_exit_status[-1])
