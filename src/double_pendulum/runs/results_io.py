"""Result files: CSV with units in the header, summary JSON; written atomically.

CSV layout: a header row of ``"name [unit]"`` columns (``time [s]`` first), then one row per
output time with ``repr``-exact floats. :func:`fmpy.util.read_csv` reads it as is (the column
names then carry the units); :func:`read_results_csv` strips the units again.

Every file is written to a temporary name in the target folder and renamed into place, so an
interrupted run never leaves a half-written file and never destroys a file written earlier.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _current_umask()


def _atomic_write_text(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", newline="\n") as fh:
            fh.write(text)
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp creates 0600; give the file the usual permissions
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def column_header(name: str, unit: str) -> str:
    """Return ``"name [unit]"`` (or just ``name`` for a dimensionless column)."""
    return f"{name} [{unit}]" if unit and unit != "1" else name


def write_results_csv(path: str | Path, result: np.ndarray, units: Mapping[str, str]) -> Path:
    """Write a structured array (fields ``time`` and outputs) as CSV with units in the header."""
    path = Path(path)
    names = result.dtype.names
    header = ",".join(f'"{column_header(n, "s" if n == "time" else units.get(n, ""))}"' for n in names)
    columns = [np.asarray(result[n], dtype=float) for n in names]
    lines = [header]
    for row in zip(*columns):
        lines.append(",".join(repr(float(v)) for v in row))
    _atomic_write_text(path, "\n".join(lines) + "\n")
    return path


def table_from_columns(**columns: Any) -> np.ndarray:
    """Columns of equal length (flattened, as floats) as a structured array for :func:`write_results_csv`."""
    arrays = [np.asarray(v, dtype=float).ravel() for v in columns.values()]
    return np.rec.fromarrays(arrays, names=list(columns)).view(np.ndarray)


def read_results_csv(path: str | Path) -> np.ndarray:
    """Read a CSV written by :func:`write_results_csv` into a structured array (plain names)."""
    with open(path) as fh:
        header = fh.readline().rstrip("\n").split(",")
    names = [h.strip('"').split(" [")[0] for h in header]
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return np.rec.fromarrays(data.T, names=names).view(np.ndarray)


def _jsonable(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    return value


def write_json(path: str | Path, data: Mapping[str, Any]) -> Path:
    """Write ``data`` as indented JSON (NumPy scalars converted, non-finite floats as null)."""
    path = Path(path)
    _atomic_write_text(path, json.dumps(_jsonable(data), indent=2, sort_keys=False) + "\n")
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write a text file (e.g. a report) atomically."""
    path = Path(path)
    _atomic_write_text(path, text)
    return path


def write_table_csv(path: str | Path, rows: list[Mapping[str, Any]]) -> Path:
    """Write a list of records as CSV (columns: the union of the keys, in first-seen order).

    A record table, not a time series: it has text columns (case, solver, status, message), booleans
    (``True``/``False``) and empty cells where a column does not apply (e.g. ``rtol`` of a fixed-step
    solver). Read it back with :func:`read_table_csv` or ``pandas.read_csv``; ``fmpy.util.read_csv``
    and :func:`read_results_csv` read only the numeric CSVs of :func:`write_results_csv`.
    """
    import csv
    import io

    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _jsonable(v) for k, v in row.items()})
    path = Path(path)
    _atomic_write_text(path, buffer.getvalue())
    return path


def _table_value(text: str) -> Any:
    """A cell of :func:`write_table_csv` as a value: None (empty), bool, int, float or the text itself."""
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def read_table_csv(path: str | Path) -> list[dict[str, Any]]:
    """Read a record table written by :func:`write_table_csv`: one dict per row, cells typed
    (:func:`_table_value`), empty cells as None."""
    import csv

    with open(path, newline="") as fh:
        return [{k: _table_value(v) for k, v in row.items()} for row in csv.DictReader(fh)]


# --- reports -------------------------------------------------------------------------------------

IN_SHORT = "## In short"
"""The heading of the plain summary every report.md opens with (:func:`report_opening`)."""
WORDS_USED = "## Words used below"
"""The heading of the list of the terms a report uses, explained (:func:`report_opening`)."""


def report_opening(title: str, in_short: Sequence[str], terms: Mapping[str, str] | None = None) -> str:
    """The start of a scenario's ``report.md``: the title, "In short" (three to five plain sentences a student
    understands: what was measured, what was found, how sure) and "Words used below" (each technical term of the
    report with its meaning, before its first use), then a rule before the report's own sections."""
    lines = [f"# {title}", "", IN_SHORT, "", " ".join(s.strip() for s in in_short if s.strip()), ""]
    if terms:
        lines += [WORDS_USED, "", *(f"- **{term}**: {meaning}" for term, meaning in terms.items()), ""]
    return "\n".join([*lines, "---", "", ""])
