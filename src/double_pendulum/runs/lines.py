"""The lines a scenario run prints about itself, defined once: printed by :mod:`double_pendulum.cli`,
read back by :mod:`double_pendulum.runs.pool` from its child processes.

* header (stdout): ``[k/N] NAME: description ...`` when the scenario starts;
* wrote (stdout): ``NAME: wrote FOLDER in X s (CPU Y s)`` when it finished;
* failed (stderr): ``NAME: FAILED: reason`` when it failed.
"""

from __future__ import annotations

import re
from collections.abc import Collection
from pathlib import Path

WROTE = "wrote"
FAILED = "FAILED"

_HEADER = re.compile(r"\[\d+/\d+\] (?P<name>\w+): ")
_HEADER_INDEX = re.compile(r"^\[\d+/\d+\]")
_OUTCOME = re.compile(rf"(?P<name>\w+): (?P<outcome>{WROTE}|{FAILED})\b")


def header_line(index: str, name: str, description: str) -> str:
    """The line that announces scenario ``name`` (``index``: its "k/N" in the run)."""
    return f"[{index}] {name}: {description} ..."


def renumbered(line: str, index: str) -> str:
    """A header ``line`` with its "k/N" replaced by ``index``."""
    return _HEADER_INDEX.sub(f"[{index}]", line, count=1)


def wrote_line(name: str, folder: Path, seconds: float, cpu_seconds: float) -> str:
    """The line that says scenario ``name`` finished and wrote ``folder``."""
    return f"{name}: {WROTE} {folder} in {seconds:.1f} s (CPU {cpu_seconds:.1f} s)"


def failed_line(name: str, reason: str) -> str:
    """The line that says scenario ``name`` failed, and why."""
    return f"{name}: {FAILED}: {reason}"


def header_name(line: str, names: Collection[str]) -> str | None:
    """The scenario of ``names`` that the header ``line`` announces, or None if it is no such header."""
    match = _HEADER.match(line)
    return match["name"] if match and match["name"] in names else None


def outcome(line: str, names: Collection[str]) -> tuple[str, str] | None:
    """``(name, WROTE or FAILED)`` if ``line`` is the wrote or failed line of a scenario of ``names``,
    else None."""
    match = _OUTCOME.match(line)
    return (match["name"], match["outcome"]) if match and match["name"] in names else None
