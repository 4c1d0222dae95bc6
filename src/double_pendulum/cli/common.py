"""What every command shares: the error a user can fix (:class:`CliError`), the output folder's check, the run's
private temporary folder and the check of a length of time."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from ..runs.interrupts import acknowledge, interrupted

PROG = "double-pendulum"


class CliError(Exception):
    """A problem the user can fix (bad path, unusable FMU): reported as one line, exit code 2."""


def writable_folder(path: str, hint: str = "pass --out DIR to write elsewhere") -> Path:
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


@contextlib.contextmanager
def private_tempdir() -> Iterator[Path]:
    """A temporary folder of this run under ``$TMPDIR``, made the temporary folder of this process and of the
    processes it starts (``TMPDIR``), removed with all it holds at the end, however the run ends; the runners
    this process keeps (:func:`~double_pendulum.analysis.sweep.close_runners`) are closed first."""
    from ..analysis.sweep import close_runners

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


def positive(option: str, value: float) -> float:
    """``value`` of ``option`` if it is a positive finite number, else a CliError."""
    if not (0.0 < value < float("inf")):
        raise CliError(f"{option} must be a positive number of seconds, got {value:g}")
    return value
