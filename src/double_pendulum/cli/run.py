"""``double-pendulum run``: scenarios through the FMU, one after another in this process or in child processes,
each into a folder of its own that replaces the earlier one only once it has finished; then the run's page."""

from __future__ import annotations

import argparse
import datetime
import importlib
import inspect
import json
import shutil
import sys
import time
from pathlib import Path
from typing import Any

from .. import __version__
from ..runs.interrupts import acknowledge, interrupted
from ..runs.lines import failed_line, header_line, wrote_line
from .catalogue import check_scenarios, scenario_description, scenario_listing
from .common import PROG, CliError, private_tempdir, writable_folder
from .fmus import FmuChoice, add_fmu_options, choose_fmu, load_fmu
from .track import add_track_options, read_record, record_line, track_flags


def _indices(index: str | None, count: int) -> list[str]:
    """The "k/N" of each of ``count`` scenarios in their header lines: ``--index`` (one per scenario,
    comma-separated, as a parent process passes them) or 1/count, 2/count, ..."""
    if index is None:
        return [f"{k}/{count}" for k in range(1, count + 1)]
    indices = index.split(",")
    if len(indices) != count:
        raise CliError(f"--index needs one k/N per scenario ({count}), got {index!r}")
    return indices


def _mark_quick(folder: Path, quick: bool) -> None:
    """Make sure the scenario's summary says whether it was a quick run."""
    summary_path = folder / "summary.json"
    if not summary_path.is_file():
        return
    summary = json.loads(summary_path.read_text())
    if summary.get("quick") != quick:
        summary["quick"] = quick
        summary_path.write_text(json.dumps(summary, indent=2) + "\n")


def accepts_thorough(module) -> bool:
    """Whether the scenario's ``run()`` takes ``thorough`` (a heavier, publication-grade setting)."""
    return "thorough" in inspect.signature(module.run).parameters


def run_scenario(module, name: str, runner, out: Path, quick: bool, thorough: bool = False,
                 record: Any = None) -> None:  # fmt: skip
    """Run one scenario into a fresh folder that replaces ``out/name`` only once it has finished (figures of
    quick runs at :data:`~double_pendulum.plots.style.DRAFT_DPI`).

    No stale file from an earlier run and no half-written folder survive: an interrupted run
    leaves the earlier results as they were; a failed one also keeps what it wrote, in
    ``out/name.failed/``, for diagnosis. ``record``: a user's own record (``--track``), passed to the scenario.
    """
    final = out / name
    staging = out / f".{name}.incomplete"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    from ..plots.style import draft_figures  # here, not at the top: matplotlib would slow down `list`

    try:
        options: dict[str, Any] = {"thorough": True} if thorough and accepts_thorough(module) else {}
        if record is not None:
            options["record"] = record
        with draft_figures(quick):  # quick runs draw their figures at a lower resolution
            module.run(runner, staging, quick=quick, **options)
        _mark_quick(staging, quick)
        if interrupted():  # Ctrl-C that the FMU turned into a failed run, which the scenario carried on from
            raise KeyboardInterrupt
    except KeyboardInterrupt:
        acknowledge()
        shutil.rmtree(staging, ignore_errors=True)
        raise
    except Exception:
        if interrupted():  # the failure is Ctrl-C, reported by the FMU as an error
            acknowledge()
            shutil.rmtree(staging, ignore_errors=True)
            raise KeyboardInterrupt from None
        failed = out / f"{name}.failed"
        shutil.rmtree(failed, ignore_errors=True)
        staging.rename(failed)
        raise
    old = out / f".{name}.old"
    shutil.rmtree(old, ignore_errors=True)
    if final.exists():
        final.rename(old)
    staging.rename(final)
    shutil.rmtree(old, ignore_errors=True)
    shutil.rmtree(out / f"{name}.failed", ignore_errors=True)


def _cpu_seconds() -> float:
    """CPU time [s] of this process and of its finished worker processes (user + system; the workers of
    :mod:`double_pendulum.analysis.sweep` are spawned as this process's children)."""
    total = time.process_time()
    try:
        import resource
    except ImportError:  # not on POSIX: this process only
        return total
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return total + children.ru_utime + children.ru_stime


def _description(name: str, record: Any) -> str:
    """The scenario's one line: its own, or the one of a run on a user's ``record``."""
    from ..scenarios import page  # noqa: PLC0415 - the registry, on demand as in write_run_page

    return page(name, scenario_description(name), record.name if record is not None else "").description


def _run_in_this_process(names: tuple[str, ...], args: argparse.Namespace, out: Path, fmu: FmuChoice,
                         record: Any = None) -> list[str]:  # fmt: skip
    """Run the scenarios one after another in this process through the FMU ``fmu``, in the order given (on a user's
    ``record`` if given); return the names of those that failed."""
    failed = []
    order = list(names)
    indices = _indices(args.index, len(order))
    with load_fmu(fmu, args.rebuild) as runner:
        for index, name in zip(indices, order):
            print(header_line(index, name, _description(name, record)), flush=True)
            module = importlib.import_module(f"double_pendulum.scenarios.{name}")
            start, cpu_start = time.perf_counter(), _cpu_seconds()
            if args.thorough and not accepts_thorough(module):
                print(f"  ({name} has no --thorough setting: its normal run)", flush=True)
            try:
                run_scenario(module, name, runner, out, args.quick, args.thorough, record)
            except KeyboardInterrupt:
                raise
            except Exception as error:  # report, keep what was written, go on with the next
                failed.append(name)
                print(failed_line(name, f"{error} (partial results in {out / (name + '.failed')})"), file=sys.stderr)
                continue
            print(wrote_line(name, out / name, time.perf_counter() - start, _cpu_seconds() - cpu_start), flush=True)
    return [name for name in names if name in failed]


def _run_in_children(names: tuple[str, ...], args: argparse.Namespace, out: Path, fmu: FmuChoice,
                     jobs: int) -> list[str]:  # fmt: skip
    """Build the project's FMUs if needed (not a given FMU), then run the scenarios in child processes, ``jobs`` at a
    time, each given the FMU by ``--fmu`` (which it only reads)."""
    from ..runs.pool import Costs, run_in_children
    from ..scenarios import EXPECTED_CPU_S, EXPECTED_QUICK_CPU_S, READS_FITS_OF

    load_fmu(fmu, args.rebuild).close()  # build once here, and fail early on an unusable FMU
    if args.quick:
        print(f"running {len(names)} scenarios in {jobs} processes, each running its share one after another",
              flush=True)
    else:
        after = [f"{r} after {w}" for r, w in READS_FITS_OF.items() if args.thorough and {r, w} <= set(names)]
        print(f"running {len(names)} scenarios, {jobs} at a time in their own processes, the longest first"
              + (f" ({', '.join(after)} in one process: it reads its cached fits)" if after else ""), flush=True)
    costs = Costs(EXPECTED_CPU_S, EXPECTED_QUICK_CPU_S, READS_FITS_OF)
    return run_in_children(names, out, fmu.path, costs, quick=args.quick, thorough=args.thorough, jobs=jobs)


def _run_command(args: argparse.Namespace) -> str:
    """The ``run`` command line as the page shows it."""
    flags = [flag for flag, on in (("--quick", args.quick), ("--thorough", args.thorough)) if on]
    return " ".join([PROG, "run", *args.scenarios, *flags, *track_flags(args), "--out", args.out])


def write_run_page(out: Path, args: argparse.Namespace, names: tuple[str, ...], failed: list[str],
                   started: datetime.datetime, wall_s: float, cpu_s: float) -> Path:  # fmt: skip
    """Write ``out/index.html``, the page of this run (:mod:`double_pendulum.runs.page`)."""
    from ..runs.page import RunInfo, write_index
    from ..scenarios import READING_ORDER, page

    mode = "quick" if args.quick else "thorough" if args.thorough else "default"
    record = Path(args.track).name if args.track else ""
    run = RunInfo(started, __version__, mode, wall_s, cpu_s, _run_command(args), names, tuple(failed), record)
    return write_index(out, run, [page(name, scenario_description(name), record if name in names else "")
                                  for name in READING_ORDER])


def cmd_run(args: argparse.Namespace) -> int:
    names = check_scenarios(args.scenarios)
    if args.quick and args.thorough:
        raise CliError("--quick and --thorough exclude each other")
    if args.jobs is not None and args.jobs < 1:
        raise CliError(f"--jobs must be at least 1, got {args.jobs}")
    record = read_record(args, names)  # a user's track, checked before anything is built or written
    fmu = choose_fmu(args)  # before --out is made: a given FMU that is missing or unusable changes nothing
    out = writable_folder(args.out)
    from ..runs.workers import default_workers  # one scenario per core this process may use

    jobs = 1 if record is not None else min(len(names), args.jobs or default_workers())
    if record is not None:  # its scenarios in this process, one after another (loss_identification has its workers)
        print(record_line(record), flush=True)
    started, start, cpu_start = datetime.datetime.now(datetime.UTC), time.perf_counter(), _cpu_seconds()
    with private_tempdir():
        failed = (_run_in_children(names, args, out, fmu, jobs) if jobs > 1
                  else _run_in_this_process(names, args, out, fmu, record))
    wall_s, cpu_s = time.perf_counter() - start, _cpu_seconds() - cpu_start
    if len(names) > 1 and args.index is None:  # a child of run_in_children leaves the sum to its parent
        print(f"{len(names) - len(failed)} of {len(names)} scenarios wrote {out} in "
              f"{wall_s:.1f} s (CPU {cpu_s:.1f} s)", flush=True)
    if args.index is None:  # the page of the whole run, by the process that ran it all
        index = write_run_page(out, args, names, failed, started, wall_s, cpu_s)
        print(f"the whole run on one page: {index}", flush=True)
    if failed and args.index is None:
        print(f"{len(failed)} of {len(names)} scenarios failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


def add_run_parser(sub: argparse._SubParsersAction) -> None:
    """``run``'s options, with the scenarios listed in its help."""
    p_run = sub.add_parser(
        "run",
        help="run scenarios (or 'all') through the FMU with fmpy",
        description="Run one or more scenarios through the FMU with fmpy; write CSV files, plots,\n"
        "summary.json and a report into OUT/SCENARIO/ for each. Several names run like 'all',\n"
        "restricted to them.",
        epilog="scenarios:\n" + scenario_listing()
        + "\n  all                    every scenario above, in child processes, one per core at a time "
        "(see --jobs)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p_run.add_argument("scenarios", nargs="+", metavar="SCENARIO",
                       help="scenario names (see below), or 'all' alone")
    p_run.add_argument("--out", default="results", help="output folder (default: results)")
    add_fmu_options(p_run, "an FMU file of the double pendulum to run instead of the project's: read as it is, "
                    "never built or written (an error if it is missing or not usable); a scenario that needs "
                    "another FMU (cosimulation: Suspension.fmu) takes the current one beside it, else builds one in "
                    "the run's temporary folder")
    p_run.add_argument("--quick", action="store_true", help="short runs, for smoke tests (about 30 s for all)")
    p_run.add_argument("--thorough", action="store_true",
                       help="heavier, publication-grade settings where a scenario has them (chaos, "
                       "work_precision, loss_identification, suspension_transfer, measured_vs_sim); the others "
                       "run as usual")
    add_track_options(p_run)
    p_run.add_argument("--jobs", type=int, default=None, metavar="N",
                       help="child processes at a time (default: one per core): each runs one scenario, "
                       "or with --quick its share of them one after another; 1 runs them all one after "
                       "another in this process")
    # a child's "k/N" in its header lines, one per scenario, comma-separated
    p_run.add_argument("--index", default=None, help=argparse.SUPPRESS)
    p_run.set_defaults(func=cmd_run)
