"""Command line: build the FMU, run scenarios through it, list them, print the FMU's variables.

Misuse and failures end with one line on stderr and a non-zero exit code, never a traceback:
2 for a bad command line or unusable files, 1 if a scenario failed, 130 on Ctrl-C, 141 when the reader of
the output went away (``double-pendulum variables | head -1``).

A run keeps its temporary files (the FMUs fmpy extracts, in this process, its workers and its child
processes) in a folder of its own under ``$TMPDIR`` and removes it when it ends, however it ends
(:func:`private_tempdir`).
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import datetime
import importlib
import importlib.util
import inspect
import json
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from . import __version__
from .component.variables import INTERFACES
from .fmu.build import DEFAULT_FMU_PATH, build_all
from .fmu.loader import LoaderUnavailable
from .runs.interrupts import acknowledge, handling_interrupts, interrupted
from .runs.lines import failed_line, header_line, wrote_line
from .scenarios import SCENARIOS

PROG = "double-pendulum"


class CliError(Exception):
    """A problem the user can fix (bad path, unusable FMU): reported as one line, exit code 2."""


def scenario_description(name: str) -> str:
    """The scenario's one-line ``DESCRIPTION``, read from its source without importing it (fast)."""
    spec = importlib.util.find_spec(f"double_pendulum.scenarios.{name}")
    tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "DESCRIPTION" for t in node.targets):
            return ast.literal_eval(node.value)
    return ""


def scenario_listing() -> str:
    """One line per scenario: name and description."""
    return "\n".join(f"  {name:22s} {scenario_description(name)}" for name in SCENARIOS)


def _check_scenarios(names: list[str]) -> tuple[str, ...]:
    """The scenarios the command line names (``all``: every one), each once, in the order given."""
    if "all" in names:
        if len(names) > 1:
            raise CliError("'all' runs every scenario: give it alone, not with other scenario names")
        return SCENARIOS
    for name in names:
        if name not in SCENARIOS:
            raise CliError(f"unknown scenario {name!r}; choose one of: {', '.join(SCENARIOS)} (or 'all')")
    return tuple(dict.fromkeys(names))


def _indices(index: str | None, count: int) -> list[str]:
    """The "k/N" of each of ``count`` scenarios in their header lines: ``--index`` (one per scenario,
    comma-separated, as a parent process passes them) or 1/count, 2/count, ..."""
    if index is None:
        return [f"{k}/{count}" for k in range(1, count + 1)]
    indices = index.split(",")
    if len(indices) != count:
        raise CliError(f"--index needs one k/N per scenario ({count}), got {index!r}")
    return indices


def _writable_folder(path: str, hint: str = "pass --out DIR to write elsewhere") -> Path:
    """Create ``path`` if needed and check that files can be written there (else a CliError with ``hint``; an
    empty name or an existing file is refused: Path("") is the current folder, which ``--out ''`` never means)."""
    if not path.strip():
        raise CliError("--out needs a folder name (got an empty one); use --out . for the current folder")
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise CliError(f"cannot write results to {folder}: it is a file, not a folder (pass --out DIR)")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".write-test-{time.monotonic_ns()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as error:
        reason = error.strerror or str(error)
        raise CliError(f"cannot write results to {folder}: {reason} ({hint})") from None
    return folder


def is_project_folder(folder: Path) -> bool:
    """Whether ``folder`` is this project's own source folder (its pyproject.toml names the project), where
    the README's commands keep the FMUs in ``build/``."""
    pyproject = folder / "pyproject.toml"
    try:
        return 'name = "double-pendulum-fmu"' in pyproject.read_text(encoding="utf-8")
    except OSError:
        return False


def default_fmu_path(out: Path) -> Path:
    """Where ``run`` keeps the FMUs unless ``--fmu`` says: ``build/DoublePendulum.fmu`` in the project's own
    folder, elsewhere ``OUT/fmu/DoublePendulum.fmu``, so that a run from any other folder writes only into
    its ``--out`` folder."""
    if is_project_folder(Path.cwd()):
        return DEFAULT_FMU_PATH
    return out / "fmu" / DEFAULT_FMU_PATH.name


def fmu_set(fmu: Path) -> list[Path]:
    """The files ``build`` writes with the DoublePendulum FMU ``fmu``: the other FMUs next to it, the coupled
    system (SSP and container FMU) and the FMI 3.0 FMU in ``fmi3/``."""
    others = [fmu.parent / f"{name}.fmu" for name in INTERFACES if f"{name}.fmu" != fmu.name]
    systems = [fmu.parent / "PendulumOnSuspension.ssp", fmu.parent / "PendulumOnSuspension.fmu"]
    return [fmu, *others, *systems, fmu.parent / "fmi3" / fmu.name]


def fmu_set_is_current(fmu: Path) -> bool:
    """Whether ``fmu`` is newer than its sources and, for an FMU named as ``build`` names it, the rest of
    :func:`fmu_set` is there and current too (an FMU of another name is checked alone)."""
    from .fmu.build import fmu_is_current

    if not fmu_is_current(fmu):
        return False
    if fmu.name != DEFAULT_FMU_PATH.name:
        return True
    from .fmu.build_fmi3 import adapter_sources as fmi3_sources

    built = fmu.stat().st_mtime
    others = fmu_set(fmu)[1:]
    interfaces = [path for path in others if path.stem in INTERFACES and path.parent == fmu.parent]
    fmi3 = fmu.parent / "fmi3" / fmu.name  # also built from its own adapter
    return all(fmu_is_current(path, path.stem) for path in interfaces) and all(
        path.is_file() and path.stat().st_mtime >= built for path in others if path not in interfaces
    ) and all(source.stat().st_mtime <= fmi3.stat().st_mtime for source in fmi3_sources())


def _load_fmu(path: str, rebuild: bool):
    """Build the FMUs if the FMU or the rest of its set is missing or stale (:func:`fmu_set_is_current`), then
    open the FMU with fmpy; unusable files become a CliError."""
    import zipfile

    from .fmu.runner import FmuRunner

    fmu = Path(path)
    if rebuild or not fmu_set_is_current(fmu):
        print(f"building the FMUs next to {fmu} (missing or older than the sources) ...", flush=True)
        try:
            build_all(fmu)
        except LoaderUnavailable as error:
            raise CliError(f"cannot build the FMUs: {error}") from None
        except OSError as error:
            raise CliError(f"cannot build the FMU at {fmu}: {error.strerror or error} "
                           "(pass --fmu PATH to build it elsewhere)") from None
    try:
        return FmuRunner(fmu)
    except (zipfile.BadZipFile, KeyError, OSError) as error:
        raise CliError(f"{fmu} is not a usable FMU ({type(error).__name__}: {error}); "
                       "delete it or pass --rebuild") from None
    except Exception as error:  # fmpy's own validation errors
        raise CliError(f"{fmu} is not a usable FMU: {error}") from None


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


def run_scenario(module, name: str, runner, out: Path, quick: bool, thorough: bool = False) -> None:
    """Run one scenario into a fresh folder that replaces ``out/name`` only once it has finished (figures of
    quick runs at :data:`~double_pendulum.plots.style.DRAFT_DPI`).

    No stale file from an earlier run and no half-written folder survive: an interrupted run
    leaves the earlier results as they were; a failed one also keeps what it wrote, in
    ``out/name.failed/``, for diagnosis.
    """
    final = out / name
    staging = out / f".{name}.incomplete"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    from .plots.style import draft_figures  # here, not at the top: matplotlib would slow down `list`

    try:
        options = {"thorough": True} if thorough and accepts_thorough(module) else {}
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


def cmd_build(args: argparse.Namespace) -> int:
    print(f"building the FMUs next to {args.output} ...", flush=True)
    try:
        paths = build_all(args.output)
    except LoaderUnavailable as error:
        raise CliError(f"cannot build the FMUs: {error}") from None
    except OSError as error:
        raise CliError(f"cannot build the FMUs at {args.output}: {error.strerror or error}") from None
    for path in paths:
        print(f"built {path}")
    return 0


def cmd_cross_check(args: argparse.Namespace) -> int:
    """Write the FMI Cross-Check tree into ``args.dir`` and check it (fmpy; with --simulate fmpy as importer;
    with --checker the FMI Compliance Checker). Exit status 1 if a check finds a problem."""
    from .data import data_path
    from .fmu.cross_check import case_of, import_with_fmpy, validate_tree, write_tree
    from .fmu.reference_runs import build_case_fmus

    checker = None
    if args.checker is not None:
        checker = Path(args.checker)
        if not (checker.is_file() and os.access(checker, os.X_OK)):
            raise CliError(f"--checker {args.checker}: not an executable file (the FMI Compliance Checker, "
                           "fmuCheck.linux64)")
    root = _writable_folder(args.dir, "give another DIR")
    print(f"building the cross-check FMUs and writing {root / 'fmus'} ...", flush=True)
    with private_tempdir() as tmp:
        folders = write_tree(root, build_case_fmus(tmp / "fmus"), data_path("reference/fmu"))
        count, problems = validate_tree(root)
        print(f"{len(folders)} FMU folders written; fmpy's cross-check validator checked {count}: "
              f"{len(problems)} problems", flush=True)
        failed = len(problems)
        for problem in problems:
            print(f"  {problem}", file=sys.stderr)
        for folder in folders if args.simulate else ():
            _, problem = import_with_fmpy(folder)
            failed += problem is not None
            print(f"  fmpy as importer, {folder.relative_to(root / 'fmus')}: {problem or 'passed'}", flush=True)
        for folder in folders if checker else ():
            failed += _check_with_compliance_checker(checker, folder, case_of(folder), root)
    return 1 if failed else 0


def _check_with_compliance_checker(checker: Path, folder: Path, case, root: Path) -> int:
    """Run the FMI Compliance Checker on one FMI 2.0 folder (its log and result go to
    ``DIR/compliance-checker/...``); print its summary; 1 if it reported an error."""
    from .fmu.compliance_checker import run_checker

    if case.fmi_version != "2.0":
        return 0
    out = root / "compliance-checker" / folder.relative_to(root / "fmus")
    report = run_checker(checker, folder, case, out)
    bad = report.errors + report.fatal + (report.returncode != 0)
    print(f"  FMI Compliance Checker, {folder.relative_to(root / 'fmus')}: {report.warnings} warnings, "
          f"{report.errors} errors{f', {report.fatal} fatal' if report.fatal else ''} (log: {out})", flush=True)
    return int(bool(bad))


def cmd_list(args: argparse.Namespace) -> int:
    print(scenario_listing())
    return 0


def cmd_variables(args: argparse.Namespace) -> int:
    """Print the FMU's variables as the Markdown table in docs/fmu.md."""
    from .component.variables import fmu_variables

    print("| name | causality | type | unit | start | description |")
    print("|---|---|---|---|---|---|")
    for v in fmu_variables():
        text = v.description.rsplit(" [", 1)[0] if v.unit else v.description
        start = "" if v.start is None else v.start
        print(f"| `{v.name}` | {v.causality} | {v.fmi_type} | {v.unit or '-'} | {start} | {text} |")
    return 0


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


def _run_in_this_process(names: tuple[str, ...], args: argparse.Namespace, out: Path) -> list[str]:
    """Run the scenarios one after another in this process, in the order given; return the names of those
    that failed."""
    failed = []
    order = list(names)
    indices = _indices(args.index, len(order))
    with _load_fmu(args.fmu, args.rebuild) as runner:
        for index, name in zip(indices, order):
            print(header_line(index, name, scenario_description(name)), flush=True)
            module = importlib.import_module(f"double_pendulum.scenarios.{name}")
            start, cpu_start = time.perf_counter(), _cpu_seconds()
            if args.thorough and not accepts_thorough(module):
                print(f"  ({name} has no --thorough setting: its normal run)", flush=True)
            try:
                run_scenario(module, name, runner, out, args.quick, args.thorough)
            except KeyboardInterrupt:
                raise
            except Exception as error:  # report, keep what was written, go on with the next
                failed.append(name)
                print(failed_line(name, f"{error} (partial results in {out / (name + '.failed')})"), file=sys.stderr)
                continue
            print(wrote_line(name, out / name, time.perf_counter() - start, _cpu_seconds() - cpu_start), flush=True)
    return [name for name in names if name in failed]


def _run_in_children(names: tuple[str, ...], args: argparse.Namespace, out: Path, jobs: int) -> list[str]:
    """Build the FMU if needed, then run the scenarios in child processes, ``jobs`` at a time."""
    from .runs.pool import Costs, run_in_children
    from .scenarios import EXPECTED_CPU_S, EXPECTED_QUICK_CPU_S, READS_FITS_OF

    _load_fmu(args.fmu, args.rebuild).close()  # build once here, and fail early on an unusable FMU
    if args.quick:
        print(f"running {len(names)} scenarios in {jobs} processes, each running its share one after another",
              flush=True)
    else:
        after = [f"{r} after {w}" for r, w in READS_FITS_OF.items() if args.thorough and {r, w} <= set(names)]
        print(f"running {len(names)} scenarios, {jobs} at a time in their own processes, the longest first"
              + (f" ({', '.join(after)} in one process: it reads its cached fits)" if after else ""), flush=True)
    costs = Costs(EXPECTED_CPU_S, EXPECTED_QUICK_CPU_S, READS_FITS_OF)
    return run_in_children(names, out, Path(args.fmu), costs, quick=args.quick, thorough=args.thorough, jobs=jobs)


@contextlib.contextmanager
def private_tempdir() -> Iterator[Path]:
    """A temporary folder of this run under ``$TMPDIR``, made the temporary folder of this process and of the
    processes it starts (``TMPDIR``), removed with all it holds at the end, however the run ends; the runners
    this process keeps (:func:`~double_pendulum.analysis.sweep.close_runners`) are closed first."""
    from .analysis.sweep import close_runners

    folder = Path(tempfile.mkdtemp(prefix="double-pendulum-run-"))
    saved_env, saved_tempdir = os.environ.get("TMPDIR"), tempfile.tempdir
    os.environ["TMPDIR"], tempfile.tempdir = str(folder), str(folder)
    try:
        yield folder
    finally:
        if interrupted():  # the clean-up below must not be cut short by the repeated interrupt
            acknowledge()
        close_runners()
        if saved_env is None:
            os.environ.pop("TMPDIR", None)
        else:
            os.environ["TMPDIR"] = saved_env
        tempfile.tempdir = saved_tempdir
        shutil.rmtree(folder, ignore_errors=True)


def _run_command(args: argparse.Namespace) -> str:
    """The ``run`` command line as the page shows it."""
    flags = [flag for flag, on in (("--quick", args.quick), ("--thorough", args.thorough)) if on]
    return " ".join([PROG, "run", *args.scenarios, *flags, "--out", args.out])


def write_run_page(out: Path, args: argparse.Namespace, names: tuple[str, ...], failed: list[str],
                   started: datetime.datetime, wall_s: float, cpu_s: float) -> Path:  # fmt: skip
    """Write ``out/index.html``, the page of this run (:mod:`double_pendulum.runs.page`)."""
    from .runs.page import RunInfo, write_index
    from .scenarios import READING_ORDER, page

    mode = "quick" if args.quick else "thorough" if args.thorough else "default"
    run = RunInfo(started, __version__, mode, wall_s, cpu_s, _run_command(args), names, tuple(failed))
    return write_index(out, run, [page(name, scenario_description(name)) for name in READING_ORDER])


def cmd_run(args: argparse.Namespace) -> int:
    names = _check_scenarios(args.scenarios)
    if args.quick and args.thorough:
        raise CliError("--quick and --thorough exclude each other")
    if args.jobs is not None and args.jobs < 1:
        raise CliError(f"--jobs must be at least 1, got {args.jobs}")
    out = _writable_folder(args.out)
    if args.fmu is None:
        args.fmu = str(default_fmu_path(out))
    from .runs.workers import default_workers  # one scenario per core this process may use

    jobs = min(len(names), args.jobs or default_workers())
    started, start, cpu_start = datetime.datetime.now(datetime.UTC), time.perf_counter(), _cpu_seconds()
    with private_tempdir():
        failed = _run_in_children(names, args, out, jobs) if jobs > 1 else _run_in_this_process(names, args, out)
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


def _positive(option: str, value: float) -> float:
    """``value`` of ``option`` if it is a positive finite number, else a CliError."""
    if not (0.0 < value < float("inf")):
        raise CliError(f"{option} must be a positive number of seconds, got {value:g}")
    return value


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run a case of one's own through the FMU (:mod:`double_pendulum.case`): CSV, figure, animation, summary."""
    from fmpy import read_model_description

    from .case import Case, run_case
    from .fmu.start_values import StartValueError, parse_start_values

    if args.me and args.fmi != "3":
        raise CliError("--me needs --fmi 3: the FMI 2.0 FMU is co-simulation only")
    stop, step = _positive("--stop", args.stop), _positive("--step", args.step)
    if step > stop:
        raise CliError(f"--step {step:g} s is longer than the run (--stop {stop:g} s)")
    out = _writable_folder(args.out)
    fmu2 = Path(args.fmu) if args.fmu is not None else default_fmu_path(out)
    with private_tempdir():
        _load_fmu(str(fmu2), args.rebuild).close()  # builds the FMUs if they are missing or stale
        fmu = fmu2 if args.fmi == "2" else fmu2.parent / "fmi3" / fmu2.name
        try:
            values = parse_start_values(args.set, read_model_description(str(fmu)))
        except StartValueError as error:
            raise CliError(str(error)) from None
        case = Case(fmu, values, stop, step, "ModelExchange" if args.me else "CoSimulation")
        print(f"simulating {case.words()} through {fmu} with fmpy ...", flush=True)
        outcome = run_case(case, out, animate=not args.no_animation)
    names = ", ".join(path.name for path in outcome.files)
    if outcome.message is not None:
        print(f"{PROG}: the FMU stopped the run at t = {outcome.summary.get('end_time_s', 0.0):g} s: "
              f"{outcome.message} (wrote {names} in {out})", file=sys.stderr)
        return 1
    print(f"wrote {names} in {out} ({outcome.summary['rows']} rows, {outcome.summary['wall_time_s']:.1f} s)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser: plain-text help, the scenarios listed under ``run --help``."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="A planar double pendulum as an FMI 2.0 co-simulation FMU (and an FMI 3.0 Model Exchange "
        "and Co-Simulation FMU): build them, run the scenarios through fmpy, print the variables.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    parser.command_parsers = sub.choices  # type: ignore[attr-defined]  # main() reports unknown options by command

    p_build = sub.add_parser("build", help="build DoublePendulum.fmu, Suspension.fmu, the coupled system and "
                             "fmi3/DoublePendulum.fmu",
                             description="Build DoublePendulum.fmu and, next to it, Suspension.fmu, "
                             "PendulumOnSuspension.ssp (SSP, for libcosim), PendulumOnSuspension.fmu "
                             "(fmpy's container FMU) and fmi3/DoublePendulum.fmu (FMI 3.0, Model Exchange and "
                             "Co-Simulation).")
    p_build.add_argument("-o", "--output", default=str(DEFAULT_FMU_PATH), help="DoublePendulum FMU path or folder")
    p_build.set_defaults(func=cmd_build)

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
    p_run.add_argument("--fmu", default=None,
                       help=f"FMU to use, built with the other FMUs next to it if missing or older than the sources "
                       f"(default: {DEFAULT_FMU_PATH} in the project's folder, elsewhere OUT/fmu/"
                       f"{DEFAULT_FMU_PATH.name})")
    p_run.add_argument("--rebuild", action="store_true", help="rebuild the FMU first")
    p_run.add_argument("--quick", action="store_true", help="short runs, for smoke tests (about 30 s for all)")
    p_run.add_argument("--thorough", action="store_true",
                       help="heavier, publication-grade settings where a scenario has them (chaos, "
                       "work_precision, loss_identification, suspension_transfer, measured_vs_sim); the others "
                       "run as usual")
    p_run.add_argument("--jobs", type=int, default=None, metavar="N",
                       help="child processes at a time (default: one per core): each runs one scenario, "
                       "or with --quick its share of them one after another; 1 runs them all one after "
                       "another in this process")
    # a child's "k/N" in its header lines, one per scenario, comma-separated
    p_run.add_argument("--index", default=None, help=argparse.SUPPRESS)
    p_run.set_defaults(func=cmd_run)

    p_cross = sub.add_parser(
        "cross-check", help="write the FMI Cross-Check tree of the FMUs (with reference results) and check it",
        description="Build the FMUs of the reference cases and write DIR/fmus/<2.0|3.0>/<cs|me>/linux64/"
        "double-pendulum-fmu/<version>/<Model>/ with the FMU, <Model>_ref.csv, _ref.opt, _in.csv and ReadMe.md "
        "(FMI Cross-Check rules v4.1), then validate it with fmpy's cross-check validator.")
    p_cross.add_argument("dir", metavar="DIR", help="the cross-check repository (or any folder) to write into")
    p_cross.add_argument("--simulate", action="store_true",
                         help="also run every FMU in fmpy as an importer and compare with its reference")
    p_cross.add_argument("--checker", metavar="PATH", default=None,
                         help="also run the FMI Compliance Checker (fmuCheck.linux64) on every FMI 2.0 FMU with its "
                         "input file; logs go to DIR/compliance-checker/")
    p_cross.set_defaults(func=cmd_cross_check)

    p_sim = sub.add_parser(
        "simulate",
        help="run a case of your own through the FMU with fmpy: CSV, figure, animation, summary",
        description="Run the FMU once with fmpy, from the start values you give, and write simulation.csv\n"
        "(units in the column names), simulation.png (angles, energies and their budget, the bobs' paths),\n"
        "simulation.gif (the pendulum in real time) and summary.json (with the fmpy call that gives the\n"
        "same numbers) into OUT.",
        epilog="example:\n  double-pendulum simulate --set phi1_0=2 --set air_drag=true --stop 20 --out my_case\n"
        "parameters and their units: double-pendulum variables",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p_sim.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                       help="start value of a parameter of the FMU, by its FMU name (repeatable)")
    p_sim.add_argument("--stop", type=float, default=10.0, metavar="SECONDS", help="stop time (default: 10)")
    p_sim.add_argument("--step", type=float, default=0.01, metavar="SECONDS",
                       help="output interval, also the co-simulation step (default: 0.01)")
    p_sim.add_argument("--fmi", choices=("2", "3"), default="2", help="FMI version of the FMU (default: 2)")
    p_sim.add_argument("--me", action="store_true",
                       help="model exchange (with --fmi 3): fmpy integrates the FMU with its own solver")
    p_sim.add_argument("--out", default="results/simulate", help="output folder (default: results/simulate)")
    p_sim.add_argument("--fmu", default=None,
                       help="the FMI 2.0 FMU, built with the others next to it if missing or older than the sources "
                       "(--fmi 3 uses fmi3/ next to it; default as for run)")
    p_sim.add_argument("--rebuild", action="store_true", help="rebuild the FMUs first")
    p_sim.add_argument("--no-animation", action="store_true", help="write no simulation.gif")
    p_sim.set_defaults(func=cmd_simulate)

    p_list = sub.add_parser("list", help="list the scenarios", description="List the scenarios.")
    p_list.set_defaults(func=cmd_list)

    p_vars = sub.add_parser("variables", help="print the FMU's variables (Markdown table)",
                            description="Print the FMU's variables as a Markdown table.")
    p_vars.set_defaults(func=cmd_variables)
    __import__("double_pendulum.app.server", fromlist=["add_app_command"]).add_app_command(sub)  # issue 37
    return parser


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and run the command; return the exit code (errors as one line on stderr)."""
    parser = build_parser()
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # the command's own usage, not the top level's: the options that command takes
        parser.command_parsers[args.command].error(f"unrecognized arguments: {' '.join(unknown)}")
    try:
        with handling_interrupts():
            return args.func(args)
    except CliError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        kept = ("nothing was written" if args.command == "simulate"
                else "finished scenarios are kept, unfinished ones are discarded")
        print(f"{PROG}: interrupted; {kept}", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of stdout went away: say nothing more there
        _stdout_to_devnull()
        return 141


def _stdout_to_devnull() -> None:
    """Point stdout at /dev/null, so that flushing what is left of it cannot fail again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    with contextlib.suppress(OSError, ValueError):
        os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


def entry() -> None:
    """Console-script entry point: run :func:`main` and exit with its code, through the interpreter's
    ordinary teardown (the FMUs' binary is safe through exit: scripts/check_memory.sh)."""
    try:
        code = main()
    except KeyboardInterrupt:  # Ctrl-C while parsing or importing
        print(f"{PROG}: interrupted", file=sys.stderr)
        code = 130
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _stdout_to_devnull()
        code = code or 141
    sys.stderr.flush()
    raise SystemExit(code)


if __name__ == "__main__":
    entry()
