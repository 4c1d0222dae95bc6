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
recorder only after it is in the file). :func:`read_spread` reads a long file back for a figure, at most a given
number of rows spread evenly over it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .results_io import column_header

BATCH_ROWS = 512
"""Rows written at a time (about 0.3 MB of CSV for the FMU's 28 quantities)."""


class RowStream:
    """The CSV file ``path`` of a run, written batch by batch from fmpy's recorder (see the module docstring).

    It keeps, for the summary, the number of ``rows`` written, the first and last ``time`` [s], the first and last
    ``E_total`` [J] and the largest ``|energy_residual|`` [J] (where the run records them)."""

    def __init__(self, path: str | Path, units: Mapping[str, str]) -> None:
        self.path = Path(path)
        self.units = units
        self.rows = 0
        self.first: dict[str, float] = {}
        self.last: dict[str, float] = {}
        self.max_abs_residual = 0.0
        self._file = open(self.path, "wb")  # noqa: SIM115 (open until finish())
        self._complete = 0  # bytes of the file written whole: the header and every batch before the last
        self._last_row: Any = None  # the last row written whole (the recorder's own tuple)
        self._names: tuple[str, ...] | None = None

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
        if self._file.tell() != self._complete:  # a batch cut short by an interrupt: it is still in the recorder
            self._file.truncate(self._complete)
            self._file.seek(self._complete)
        if recorder is not None:
            rows = recorder.rows
            written = next((k for k, row in enumerate(rows) if row is self._last_row), None)
            if written is not None:  # interrupted after that batch was written, before it left the recorder
                del rows[: written + 1]
            if rows:
                self._write(recorder, len(rows))
        elif result is not None and len(result):
            self._write_array(np.asarray(result))
        self._file.close()

    def _write(self, recorder: Any, n: int) -> None:
        self._write_array(np.array(recorder.rows[:n], dtype=recorder.cols))
        self._last_row = recorder.rows[n - 1]
        del recorder.rows[:n]

    def _write_array(self, batch: np.ndarray) -> None:
        names = batch.dtype.names
        if self._names is None:
            self._names = names
            header = ",".join(f'"{column_header(n, "s" if n == "time" else self.units.get(n, ""))}"' for n in names)
            self._file.write((header + "\n").encode())
            self.first = {n: float(batch[n][0]) for n in ("time", "E_total") if n in names}
        columns = [np.asarray(batch[n], dtype=float) for n in names]
        text = "".join(",".join(map(repr, row)) + "\n" for row in zip(*(c.tolist() for c in columns)))
        self._file.write(text.encode())
        self._file.flush()
        self._complete = self._file.tell()
        self.rows += len(batch)
        self.last = {n: float(batch[n][-1]) for n in ("time", "E_total") if n in names}
        if "energy_residual" in names and len(batch):
            self.max_abs_residual = max(self.max_abs_residual, float(np.max(np.abs(batch["energy_residual"]))))


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
