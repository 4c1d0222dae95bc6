"""Run the FMI Compliance Checker (modelica/FMUComplianceChecker, ``fmuCheck.<platform>``) on a cross-check folder.

The Cross-Check rules (v4.1, 9.1.2) ask every exported FMU to run in the checker without error, with the
folder's ``_in.csv`` where it has inputs. The checker (FMI 1.0 and 2.0 only) instantiates the FMU
with its defaults, sets every column of the input file before the experiment and again before every
step, simulates to ``-s`` with steps of ``-h`` and writes the outputs (``-o``; at every step with ``-n 0``, else
at most 500 rows, skipping some) and its log (``-e``),
which ends with a summary of the warnings and errors the FMU and the checker reported.

The checker is not part of the project: :func:`find_checker` looks for it in
``$DOUBLE_PENDULUM_FMU_CHECKER`` and then as ``fmuCheck.linux64`` on ``PATH``.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any, NamedTuple

from .reference_cases import ReferenceCase, input_names

CHECKER_VARIABLE = "DOUBLE_PENDULUM_FMU_CHECKER"
CHECKER_NAME = "fmuCheck.linux64"


class CheckerReport(NamedTuple):
    """One run of the checker: its exit status, the counts of its summary, its log and its result."""

    returncode: int
    fmu_messages: int  # "FMU reported: N warning(s) and error(s)"
    warnings: int  # "Checker reported: N Warning(s)"
    errors: int  # "... N Error(s)"
    fatal: int  # "N Fatal error(s) occurred during processing"
    log: str
    result: Any  # the outputs as a structured array (None if it wrote none)


def find_checker() -> Path | None:
    """The checker's executable: ``$DOUBLE_PENDULUM_FMU_CHECKER``, else ``fmuCheck.linux64`` on PATH; None."""
    named = os.environ.get(CHECKER_VARIABLE)
    if named:
        return Path(named) if Path(named).is_file() and os.access(named, os.X_OK) else None
    found = shutil.which(CHECKER_NAME)
    return Path(found) if found else None


def _count(pattern: str, log: str) -> int:
    match = re.search(pattern, log)
    return int(match.group(1)) if match else 0


def run_checker(checker: str | Path, folder: str | Path, case: ReferenceCase, out: str | Path) -> CheckerReport:
    """Run ``checker`` on the FMU of the cross-check ``folder`` of ``case`` as its ReadMe says, writing
    ``<model>_cc.log`` and ``<model>_cc.csv`` into ``out``."""
    from fmpy.cross_check.validate_vendor_repo import read_csv

    folder, out = Path(folder), Path(out)
    out.mkdir(parents=True, exist_ok=True)
    log, result = out / f"{case.model}_cc.log", out / f"{case.model}_cc.csv"
    command = [str(checker), "-l", "3", "-e", str(log), "-o", str(result), "-c", ",", "-f", "-n", "0",
               "-s", f"{case.stop_time:g}", "-h", f"{case.step_size:g}"]
    if input_names(case):
        command += ["-i", str(folder / f"{case.model}_in.csv")]
    done = subprocess.run([*command, str(folder / f"{case.model}.fmu")], capture_output=True, text=True,
                          timeout=600, cwd=out)
    text = log.read_text(errors="replace") if log.is_file() else done.stderr
    rows = read_csv(str(result)) if result.is_file() and result.stat().st_size else None
    return CheckerReport(done.returncode, _count(r"FMU reported:\s*(\d+) warning", text),
                         _count(r"(\d+) Warning\(s\)", text), _count(r"(\d+) Error\(s\)", text),
                         _count(r"(\d+) Fatal error", text), text, rows)
