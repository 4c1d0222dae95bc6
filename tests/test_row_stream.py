"""The rows a run streams to its CSV file (:class:`double_pendulum.runs.row_stream.RowStream`) survive a Ctrl-C that
lands on any statement of a batch's write: every row recorded is in the file exactly once, in order, and the
summary's count agrees. The interrupt is made certain rather than left to chance: a trace function raises
KeyboardInterrupt at the k-th line RowStream runs, for every k."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from double_pendulum.runs import row_stream
from double_pendulum.runs.results_io import read_results_csv

COLUMNS = [("time", np.float64), ("phi1", np.float64), ("E_total", np.float64)]


class Recorder:
    """fmpy's recorder as RowStream reads it: ``rows`` (a list of tuples) and ``cols`` (their dtype)."""

    def __init__(self) -> None:
        self.rows: list[tuple[float, ...]] = []
        self.cols = COLUMNS


def run(path, interrupt_at: int | None, n_rows: int = 23) -> tuple[int, int]:
    """Record ``n_rows`` rows in batches of 5, raising KeyboardInterrupt at the ``interrupt_at``-th line event in
    row_stream's code (None: never); then finish. Returns (the line events seen, the rows the stream says it wrote)."""
    stream = row_stream.RowStream(path, {"phi1": "rad", "E_total": "J"})
    recorder = Recorder()
    seen = 0

    def tracer(frame, event, arg):
        nonlocal seen
        if frame.f_code.co_filename != row_stream.__file__:
            return None
        if event == "line":
            seen += 1
            if seen == interrupt_at:
                raise KeyboardInterrupt
        return tracer

    try:
        sys.settrace(tracer)
        for k in range(n_rows):
            recorder.rows.append((0.01 * k, np.sin(k), 1.0 - 1e-3 * k))
            stream.take(recorder)
    except KeyboardInterrupt:
        pass
    finally:
        sys.settrace(None)
    stream.finish(recorder)
    return seen, stream.rows


def test_every_row_is_in_the_file_once_wherever_ctrl_c_lands(tmp_path, monkeypatch):
    monkeypatch.setattr(row_stream, "BATCH_ROWS", 5)
    events, _ = run(tmp_path / "whole.csv", None)
    assert events > 50  # the run passes through several batches' writes
    for k in range(1, events + 1):
        path = tmp_path / f"cut{k}.csv"
        _, said = run(path, k)
        table = read_results_csv(path)
        times = table["time"]
        kept = len(times)
        assert kept >= 1 and said == kept, (k, said, kept)
        # the rows recorded before the interrupt, each once and in order (the interrupt stops the recording)
        np.testing.assert_array_equal(times, 0.01 * np.arange(kept), err_msg=f"interrupt at line event {k}")
        np.testing.assert_array_equal(table["phi1"], np.sin(np.arange(kept)))


@pytest.mark.parametrize("batch", [1, 5, 64])
def test_without_an_interrupt_the_file_holds_every_row(tmp_path, monkeypatch, batch):
    monkeypatch.setattr(row_stream, "BATCH_ROWS", batch)
    _, said = run(tmp_path / "all.csv", None)
    table = read_results_csv(tmp_path / "all.csv")
    assert said == len(table) == 23
    np.testing.assert_array_equal(table["E_total"], 1.0 - 1e-3 * np.arange(23))
