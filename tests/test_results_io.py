"""Result files: CSV with units readable by fmpy, atomic writes, JSON summaries."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from double_pendulum.runs import results_io
from double_pendulum.runs.results_io import (
    read_results_csv,
    read_table_csv,
    write_json,
    write_results_csv,
    write_table_csv,
)


def _result():
    return np.array(
        [(0.0, 1.0, 2.5), (0.1, 1.1, -3.25e-9)], dtype=[("time", float), ("phi1", float), ("E_total", float)]
    )


def test_csv_round_trip_is_exact_and_fmpy_reads_it(tmp_path):
    from fmpy.util import read_csv

    path = write_results_csv(tmp_path / "r.csv", _result(), {"phi1": "rad", "E_total": "J"})
    assert path.read_text().splitlines()[0] == '"time [s]","phi1 [rad]","E_total [J]"'
    back = read_results_csv(path)
    for name in ("time", "phi1", "E_total"):
        np.testing.assert_array_equal(back[name], _result()[name])
    via_fmpy = read_csv(path)
    np.testing.assert_array_equal(via_fmpy["E_total [J]"], _result()["E_total"])


def test_failed_write_keeps_the_previous_file(tmp_path, monkeypatch):
    path = write_results_csv(tmp_path / "r.csv", _result(), {})
    before = path.read_text()

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(results_io.os, "replace", broken_replace)
    with pytest.raises(OSError):
        write_results_csv(path, _result()[:1], {})
    assert path.read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["r.csv"]  # no temporary file left behind


def test_json_converts_numpy_and_non_finite_values(tmp_path):
    path = write_json(
        tmp_path / "s.json", {"a": np.float64(1.5), "b": [np.int64(2), math.nan], "c": {"d": np.inf}}
    )
    assert json.loads(path.read_text()) == {"a": 1.5, "b": [2, None], "c": {"d": None}}


def test_table_from_columns_flattens_grids_into_float_columns_that_round_trip(tmp_path):
    grid = np.arange(6).reshape(2, 3)
    table = results_io.table_from_columns(time=np.linspace(0.0, 0.5, 6), rod=grid.astype(np.int8), E_0=grid * 0.1)
    assert table.dtype.names == ("time", "rod", "E_0") and table["rod"].dtype == float
    assert table["rod"].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]  # row-major, as the grid's ravel
    write_results_csv(tmp_path / "t.csv", table, {"E_0": "J"})
    back = read_results_csv(tmp_path / "t.csv")
    assert back.dtype.names == table.dtype.names
    np.testing.assert_array_equal(back["E_0"], table["E_0"])


def test_record_table_round_trip_types_the_cells(tmp_path):
    rows = [{"case": "a, b", "solver": "rk4", "fixed_step": 0.01, "steps": 3, "passed": True, "message": ""},
            {"case": "c", "solver": "dop853", "rtol": 1e-8, "steps": 7, "passed": False, "message": "x: y"}]
    path = write_table_csv(tmp_path / "table.csv", rows)
    back = read_table_csv(path)
    assert back[0] == {"case": "a, b", "solver": "rk4", "fixed_step": 0.01, "steps": 3, "passed": True,
                       "message": None, "rtol": None}
    assert back[1]["rtol"] == 1e-8 and back[1]["fixed_step"] is None and back[1]["passed"] is False
