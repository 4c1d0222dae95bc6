"""``double-pendulum build`` (the FMUs) and ``double-pendulum cross-check`` (the FMI Cross-Check tree of the
reference cases, checked by fmpy and, if given, the FMI Compliance Checker)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from ..fmu.build.carried_python import PLATFORMS, CarriedPythonUnavailable
from ..fmu.build.fmi2 import DEFAULT_FMU_PATH
from ..fmu.build.loader import LoaderUnavailable
from ..fmu.build.systems import build_all
from .common import CliError, private_tempdir, writable_folder

NAMES = {"x86_64-linux": "Linux", "x86_64-windows": "Windows"}  # how the build's first line names the platforms
LINUX_ONLY = ("x86_64-linux",)


def cmd_build(args: argparse.Namespace) -> int:
    platforms = LINUX_ONLY if args.linux_only else PLATFORMS
    if args.lean and args.linux_only:
        raise CliError("--lean and --linux-only exclude each other: a lean FMU carries no CPython at all (its one "
                       "binary is Linux's)")
    if args.lean:
        print(f"building the lean FMUs next to {args.output} (Linux only; they need a CPython >= 3.11 where they "
              "run) ...", flush=True)
    else:
        names = " and ".join(NAMES[name] for name in platforms)
        print(f"building the FMUs next to {args.output} (each carries its own CPython for {names}) ...", flush=True)
    try:
        paths = build_all(args.output, lean=args.lean, platforms=platforms)
    except (LoaderUnavailable, CarriedPythonUnavailable) as error:
        raise CliError(f"cannot build the FMUs: {error}") from None
    except OSError as error:
        raise CliError(f"cannot build the FMUs at {args.output}: {error.strerror or error}") from None
    for path in paths:
        print(f"built {path}")
    return 0


def cmd_cross_check(args: argparse.Namespace) -> int:
    """Write the FMI Cross-Check tree into ``args.dir`` and check it (fmpy; with --simulate fmpy as importer;
    with --checker the FMI Compliance Checker). Exit status 1 if a check finds a problem."""
    from ..data import data_path
    from ..fmu.crosscheck.reference_runs import build_case_fmus
    from ..fmu.crosscheck.tree import case_of, import_with_fmpy, validate_tree, write_tree

    checker = None
    if args.checker is not None:
        checker = Path(args.checker)
        if not (checker.is_file() and os.access(checker, os.X_OK)):
            raise CliError(f"--checker {args.checker}: not an executable file (the FMI Compliance Checker, "
                           "fmuCheck.linux64)")
    root = writable_folder(args.dir, "give another DIR")
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
    from ..fmu.crosscheck.compliance_checker import run_checker

    if case.fmi_version != "2.0":
        return 0
    out = root / "compliance-checker" / folder.relative_to(root / "fmus")
    report = run_checker(checker, folder, case, out)
    bad = report.errors + report.fatal + (report.returncode != 0)
    print(f"  FMI Compliance Checker, {folder.relative_to(root / 'fmus')}: {report.warnings} warnings, "
          f"{report.errors} errors{f', {report.fatal} fatal' if report.fatal else ''} (log: {out})", flush=True)
    return int(bool(bad))


def add_build_parser(sub: argparse._SubParsersAction) -> None:
    """``build``'s options."""
    p_build = sub.add_parser("build", help="build DoublePendulum.fmu, Suspension.fmu, the coupled system and "
                             "fmi3/DoublePendulum.fmu",
                             description="Build DoublePendulum.fmu and, next to it, Suspension.fmu, "
                             "PendulumOnSuspension.ssp (SSP, for libcosim), PendulumOnSuspension.fmu "
                             "(fmpy's container FMU) and fmi3/DoublePendulum.fmu (FMI 3.0, Model Exchange and "
                             "Co-Simulation). Each FMU carries a CPython for x86_64 Linux and Windows and runs "
                             "where no Python is installed (in a Python host it uses the host's); --lean writes "
                             "FMUs without one.")
    p_build.add_argument("-o", "--output", default=str(DEFAULT_FMU_PATH), help="DoublePendulum FMU path or folder")
    p_build.add_argument("--linux-only", action="store_true",
                         help="carry a CPython for x86_64 Linux only, not for Windows too: each FMU about 8 MB "
                         "instead of 16")
    p_build.add_argument("--lean", action="store_true",
                         help="write lean FMUs: a Linux binary only, without a CPython of their own (about 0.6 MB "
                         "instead of 16 MB); they use the Python of a Python host, else the CPython they were built "
                         "with, python3 on PATH, or the one DOUBLE_PENDULUM_FMU_PYTHON names")
    p_build.set_defaults(func=cmd_build)


def add_cross_check_parser(sub: argparse._SubParsersAction) -> None:
    """``cross-check``'s options."""
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
