"""Every scenario in quick mode: its reports, summaries and CSV files read cleanly.

- ``report.md``: no "nan", "None", "null" where a number belongs, no empty table cell;
- ``summary.json``: finite numbers, no empty texts, no bare numbers as keys (keys say what they hold,
  with their unit), and a null only where the summary explains it: a ``null_means`` object at or
  above it names the key (or one of its parents) and says what the missing value means;
- CSV files: numeric ones (time series and grids, ``"name [unit]"`` headers) read with
  ``fmpy.util.read_csv`` and :func:`read_results_csv`; the record tables (``stability.csv``,
  ``work_precision.csv``) with :func:`read_table_csv` and ``pandas.read_csv``.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from double_pendulum.scenarios import SCENARIOS
from fmpy.util import read_csv

from double_pendulum.runs.results_io import IN_SHORT, WORDS_USED, read_results_csv, read_table_csv

TABLES = {"stability.csv", "work_precision.csv", "acheson_bands.csv", "acheson_map.csv", "kapitza_bisection.csv",
          "resonance_peaks.csv", "resonance_curve.csv", "runs.csv", "stability_map.csv"}
"""The record tables (text, Boolean or missing cells); every other CSV is numeric."""
REPORTS = {"energy_decay", "loss_identification", "measured_vs_sim", "stability", "suspension_transfer",
           "work_precision",
           "cosimulation", "base_excitation"}
"""The scenarios that write a report.md."""

JARGON = ("AIC", "BIC", "Akaike weight", "chi2", "chi2_red", "VIF", "Floquet", "monodromy", "spectral radius",
          "Lyapunov", "Benettin", "Savitzky-Golay", "Gauss-Newton", "Levenberg-Marquardt", "Mathieu", "Jacobian",
          "Fisher", "rtol", "censored", "in-sample")
"""Terms a student may not know: a report that uses one explains it under "Words used below", before its first use."""
SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=[A-Z0-9])")

MISSING_WORDS = re.compile(r"\b(nan|NaN|None|null)\b")
EMPTY_CELL = re.compile(r"\|\s*\|")


@pytest.fixture(scope="module")
def quick_out(quick_results: Path) -> Path:
    """All scenarios run once in quick mode into one folder (the session's shared run)."""
    return quick_results


def _values(node: Any, path: tuple[str, ...], explained: frozenset[str]) -> Iterator[tuple[tuple[str, ...], Any, bool]]:
    """Every leaf of a summary with its path and whether a ``null_means`` at or above it names a key on the path."""
    if isinstance(node, dict):
        explained = explained | frozenset(node.get("null_means", {}))
        for key, value in node.items():
            if key != "null_means":
                yield from _values(value, (*path, key), explained)
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _values(value, (*path, str(i)), explained)
    else:
        yield path, node, bool(explained & set(path))


def _keys(node: Any) -> Iterator[str]:
    """Every key of a summary, nested ones included."""
    if isinstance(node, dict):
        for key, value in node.items():
            yield key
            yield from _keys(value)
    elif isinstance(node, list):
        for value in node:
            yield from _keys(value)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


@pytest.mark.parametrize("scenario", list(SCENARIOS))
def test_summary_has_explained_values_and_self_explaining_keys(quick_out, scenario):
    text = (quick_out / scenario / "summary.json").read_text()
    assert not re.search(r"\b(NaN|Infinity)\b", text)
    summary = json.loads(text)
    assert summary["scenario"] == scenario
    bad = []
    for path, value, explained in _values(summary, (), frozenset()):
        if value is None and not explained:
            bad.append(("/".join(path), "null without null_means"))
        elif isinstance(value, str) and not value.strip():
            bad.append(("/".join(path), "empty text"))
        elif isinstance(value, float) and not math.isfinite(value):
            bad.append(("/".join(path), value))
    assert not bad
    assert not [k for k in _keys(summary) if _is_number(k)]  # e.g. "0.001": say what it bounds
    for means in (node for key, node in _nested(summary) if key == "null_means"):
        assert all(isinstance(v, str) and v.strip() for v in means.values())


def _nested(node: Any) -> Iterator[tuple[str, Any]]:
    if isinstance(node, dict):
        for key, value in node.items():
            yield key, value
            yield from _nested(value)
    elif isinstance(node, list):
        for value in node:
            yield from _nested(value)


@pytest.mark.parametrize("scenario", [s for s in SCENARIOS if s in REPORTS])
def test_report_has_numbers_where_numbers_belong(quick_out, scenario):
    text = (quick_out / scenario / "report.md").read_text()
    assert text.strip()
    lines = [line for line in text.splitlines() if MISSING_WORDS.search(line)]
    assert not lines
    assert not [line for line in text.splitlines() if line.startswith("|") and EMPTY_CELL.search(line)]
    assert "0.00 s" not in text and "per k at c" not in text


def test_every_scenario_that_writes_a_report_is_checked(quick_out):
    with_report = {p.parent.name for p in quick_out.glob("*/report.md")}
    assert with_report == REPORTS


def _csv_files(out: Path) -> list[Path]:
    return sorted(out.glob("*/*.csv"))


def test_numeric_csvs_read_with_fmpy_and_the_project_reader(quick_out):
    numeric = [p for p in _csv_files(quick_out) if p.name not in TABLES]
    assert len(numeric) > 20
    for path in numeric:
        fmpy_table, own = read_csv(path), read_results_csv(path)
        assert len(fmpy_table) == len(own) > 0, path
        header = path.read_text().splitlines()[0].split(",")
        assert all(re.fullmatch(r'"[^"\[\]]+( \[[^\]]*\])?"', h) for h in header), (path, header)
        if "time [s]" in fmpy_table.dtype.names:
            assert (fmpy_table["time [s]"][1:] >= fmpy_table["time [s]"][:-1]).all(), path


def test_record_tables_read_with_the_table_reader_and_pandas(quick_out):
    pandas = pytest.importorskip("pandas")
    for name, scenario in (("stability.csv", "stability"), ("work_precision.csv", "work_precision")):
        path = quick_out / scenario / name
        rows = read_table_csv(path)
        frame = pandas.read_csv(path)
        assert len(rows) == len(frame) > 0
        assert list(frame.columns) == list(rows[0])
        assert all(isinstance(r["cpu_time_s"], float) for r in rows if r["status"] in ("ok", "finished"))
        assert all(isinstance(r["case"], str) and r["case"] for r in rows)
    for path in sorted([*(quick_out / "base_excitation").glob("*.csv"), *(quick_out / "cosimulation").glob("*.csv")]):
        if path.name in TABLES:
            assert len(read_table_csv(path)) == len(pandas.read_csv(path)) > 0, path


def _term(term: str) -> re.Pattern:
    """``term`` as a word of its own (``AIC`` not in ``dAIC``, ``chi2`` not in ``chi2_red``)."""
    return re.compile(rf"(?<![\w-]){re.escape(term)}(?![\w])")


@pytest.mark.parametrize("scenario", sorted(REPORTS))
def test_report_opens_with_a_plain_summary_and_explains_its_terms_before_using_them(quick_out, scenario):
    text = (quick_out / scenario / "report.md").read_text()
    lines = text.splitlines()
    assert lines[0].startswith("# ") and lines[2] == IN_SHORT, lines[:3]
    short = text.split(IN_SHORT, 1)[1].split("\n## ", 1)[0].strip()
    assert 3 <= len(SENTENCE_END.split(short)) <= 5, short
    words_at = text.find(WORDS_USED)
    defined = re.findall(r"^- \*\*(.+?)\*\*:", text[words_at:].split("\n---", 1)[0], re.M) if words_at >= 0 else []
    for term in JARGON:
        first = _term(term).search(text)
        if first is None:
            continue
        assert any(_term(term).search(d) for d in defined), f"{term!r} is used but not explained"
        assert first.start() > words_at, f"{term!r} is used before it is explained"


def test_the_plain_summary_check_catches_an_unexplained_term():
    text = "# T\n\n" + IN_SHORT + "\n\nOne. Two. Three uses AIC.\n"
    assert _term("AIC").search(text) and not _term("AIC").search("a dAIC of 2")
    assert text.find(WORDS_USED) == -1  # so the test above fails on it: AIC used, nothing explained
    assert len(SENTENCE_END.split("b = -0.0252 1/s is known. To 8 %. Fine.")) == 3  # decimals end no sentence
