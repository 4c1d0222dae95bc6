"""A run's rows streamed to its CSV file as fmpy records them, so memory stays flat however long the run.

fmpy's :func:`~fmpy.simulate_fmu` keeps every recorded row in its recorder (``recorder.rows``, a list of tuples;
about 1 kB a row for the FMU's 28 quantities) until the run ends. :class:`RowStream`, called from ``simulate_fmu``'s
``step_finished`` callback, writes the rows recorded so far to the CSV file every :data:`BATCH_ROWS` rows and
removes them from the recorder, keeping the last one (the runner reads the run's end time from the result).
:meth:`RowStream.finish` writes what is left, after the run ended, failed or was interrupted: the file then holds
every row recorded, each line whole, in :func:`~double_pendulum.runs.results_io.write_results_csv`'s layout
(``repr``-exact floats, units in the header), so :func:`~double_pendulum.runs.results_io.read_results_csv` reads it.

An interrupt (Ctrl-C) can land while a batch is written: :meth:`RowStream.finish` cuts the file back to the last
batch written whole and writes that batch again from the recorder, which still holds it (a batch leaves the
recorder only after it is in the file); a batch that reached the file whole is kept, and taken out of the recorder
if it is still there, whichever statement the interrupt fell on. :func:`read_spread` reads a long file back for a
figure, at most a given number of rows spread evenly over it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .results_io import column_header

BATCH_ROWS = 512
"""Rows written at a time (about 0.3 MB of CSV for the FMU's 28 quantities)."""


@dataclass(frozen=True)
class _Written:
    """What the file holds whole: its length [bytes], the rows in it, the recorder's tuple of its last row, and the
    summary's figures over them. Replaced in one assignment once a batch is in the file (see :class:`RowStream`)."""

    complete: int = 0
    rows: int = 0
    last_row: Any = None
    first: dict[str, float] = field(default_factory=dict)
    last: dict[str, float] = field(default_factory=dict)
    max_abs_residual: float = 0.0


class RowStream:
    """The CSV file ``path`` of a run, written batch by batch from fmpy's recorder (see the module docstring).

    It keeps, for the summary, the number of ``rows`` written, the first and last ``time`` [s], the first and last
    ``E_total`` [J] and the largest ``|energy_residual|`` [J] (where the run records them).

    An interrupt lands between two bytecodes, so every step of a batch leaves a state :meth:`finish` can read: the
    batch's bytes and figures are made first, the batch is announced (``_pending``, one assignment), written and
    flushed, then recorded as written (``_written``, one assignment), then taken out of the recorder (one ``del``).
    """

    def __init__(self, path: str | Path, units: Mapping[str, str]) -> None:
        self.path = Path(path)
        self.units = units
        self._file = open(self.path, "wb")  # noqa: SIM115 (open until finish())
        self._written = _Written()
        self._pending: _Written | None = None  # the batch being written, as _written will be once it is whole

    @property
    def rows(self) -> int:
        return self._written.rows

    @property
    def first(self) -> dict[str, float]:
        return self._written.first

    @property
    def last(self) -> dict[str, float]:
        return self._written.last

    @property
    def max_abs_residual(self) -> float:
        return self._written.max_abs_residual

    def take(self, recorder: Any, keep: int = 1) -> None:
        """Write the rows ``recorder`` (fmpy's) holds, but its last ``keep``, once there are :data:`BATCH_ROWS`
        of them, and remove them from it."""
        if len(recorder.rows) - keep >= BATCH_ROWS:
            self._write(recorder, len(recorder.rows) - keep)

    def finish(self, recorder: Any | None, result: np.ndarray | None = None) -> None:
        """Write what is left and close the file: the rows still in ``recorder`` (fmpy's; None if the run never
        finished a step), else those of ``result`` (the rows fmpy returned, or the partial result of a failed
        run). Call it once the interrupts are acknowledged: it must not be cut short. Once closed, it does nothing."""
        if self._file.closed:
            return
        self._file.flush()
        pending = self._pending
        if pending is not None and self._file.tell() == pending.complete:  # whole, but not yet recorded as written
            self._written = pending
        self._pending = None
        if self._file.tell() != self._written.complete:  # a batch cut short: it is still in the recorder
            self._file.truncate(self._written.complete)
            self._file.seek(self._written.complete)
        if recorder is not None:
            rows = recorder.rows
            last = self._written.last_row
            written = next((k for k, row in enumerate(rows) if row is last), None) if last is not None else None
            if written is not None:  # interrupted after that batch was written, before it left the recorder
                del rows[: written + 1]
            if rows:
                self._write(recorder, len(rows))
        elif result is not None and len(result):
            self._write_array(np.asarray(result), None)
        self._file.close()

    def _write(self, recorder: Any, n: int) -> None:
        self._write_array(np.array(recorder.rows[:n], dtype=recorder.cols), recorder.rows[n - 1])
        del recorder.rows[:n]

    def _write_array(self, batch: np.ndarray, last_row: Any) -> None:
        names = batch.dtype.names
        before = self._written
        header = ""
        if before.complete == 0:  # nothing whole in the file yet: the header first
            header = ",".join(f'"{column_header(n, "s" if n == "time" else self.units.get(n, ""))}"'
                              for n in names) + "\n"
        columns = [np.asarray(batch[n], dtype=float) for n in names]
        data = (header + "".join(",".join(map(repr, row)) + "\n"
                                 for row in zip(*(c.tolist() for c in columns)))).encode()
        residual = before.max_abs_residual
        if "energy_residual" in names and len(batch):
            residual = max(residual, float(np.max(np.abs(batch["energy_residual"]))))
        after = _Written(complete=before.complete + len(data), rows=before.rows + len(batch), last_row=last_row,
                         first=before.first if before.rows else {n: float(batch[n][0]) for n in ("time", "E_total")
                                                                 if n in names},
                         last={n: float(batch[n][-1]) for n in ("time", "E_total") if n in names},
                         max_abs_residual=residual)
        self._pending = after
        self._file.write(data)
        self._file.flush()
        self._written = after
        self._pending = None


def read_spread(path: str | Path, rows: int, max_rows: int) -> tuple[np.ndarray, int]:
    """The CSV file ``path`` of ``rows`` rows (as :class:`RowStream` or
    :func:`~double_pendulum.runs.results_io.write_results_csv` writes it) as a structured array of at most
    ``max_rows`` rows: every k-th row, k the smallest that fits (the last row always kept), read line by line so
    the whole file is never in memory. Also returns k."""
    every = max(1, math.ceil(rows / max_rows))
    with open(path) as fh:
        names = [h.strip('"').split(" [")[0] for h in fh.readline().rstrip("\n").split(",")]
        kept, line = [], ""
        for k, line in enumerate(fh):
            if k % every == 0:
                kept.append(line)
        if line and (rows - 1) % every:
            kept.append(line)
    data = np.loadtxt(kept, delimiter=",", ndmin=2) if kept else np.empty((0, len(names)))
    return np.rec.fromarrays(data.T, names=names).view(np.ndarray), every
