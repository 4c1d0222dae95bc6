"""Compare two result folders written by ``double-pendulum run``: summaries and CSV files.

    python scripts/compare_results.py BEFORE AFTER [--rtol 0]

Used to check that a refactoring changes no result: every ``summary.json`` value and every CSV
cell must agree (to ``--rtol``; 0 means bit-identical), except values whose key names a wall-clock
or CPU time, which differ from run to run. Prints one line per difference and exits 1 if any.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path

TIMING_WORDS = ("time_s", "wall", "cpu", "seconds", "elapsed", "runtime", "duration")
# Choices made by measured CPU time (the fastest method per accuracy band, the cheapest coupling to an
# accuracy) differ between runs too.
TIMING_CHOICES = ("best_per_band", "cheapest_to_1e-4_rad")


def _is_timing(key: str) -> bool:
    key = key.lower()
    return any(word in key for word in TIMING_WORDS) or key in TIMING_CHOICES


def _equal(a: object, b: object, rtol: float) -> bool:
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        if math.isnan(a) and math.isnan(b):
            return True
        return a == b or abs(a - b) <= rtol * max(abs(a), abs(b))
    return a == b


def compare_json(a: object, b: object, where: str, rtol: float, out: list[str]) -> None:
    """Append a line to ``out`` for each leaf where ``a`` and ``b`` differ (timings skipped)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if _is_timing(key):
                continue
            if key not in a or key not in b:
                out.append(f"{where}.{key}: only in {'after' if key in b else 'before'}")
                continue
            compare_json(a[key], b[key], f"{where}.{key}", rtol, out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{where}: length {len(a)} != {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            compare_json(x, y, f"{where}[{i}]", rtol, out)
    elif isinstance(a, str) and isinstance(b, str):
        if a != b:
            out.append(f"{where}: {a[:60]!r} != {b[:60]!r}")
    elif not _equal(a, b, rtol):
        out.append(f"{where}: {a!r} != {b!r}")


def _cell(text: str) -> object:
    try:
        return float(text)
    except ValueError:
        return text


def compare_csv(a: Path, b: Path, rtol: float, out: list[str]) -> None:
    """Append a line to ``out`` for the first differing cell of each column (timing columns skipped)."""
    rows_a = list(csv.reader(a.open()))
    rows_b = list(csv.reader(b.open()))
    if not rows_a or not rows_b or rows_a[0] != rows_b[0]:
        out.append(f"{b}: header differs")
        return
    if len(rows_a) != len(rows_b):
        out.append(f"{b}: {len(rows_a)} != {len(rows_b)} rows")
        return
    for col, name in enumerate(rows_a[0]):
        if _is_timing(name):
            continue
        for i, (ra, rb) in enumerate(zip(rows_a[1:], rows_b[1:]), start=2):
            if not _equal(_cell(ra[col]), _cell(rb[col]), rtol):
                out.append(f"{b}:{i} column {name}: {ra[col]} != {rb[col]}")
                break


def compare_folders(before: Path, after: Path, rtol: float) -> list[str]:
    """Return the differences between two result folders."""
    out: list[str] = []
    names_a = {p.relative_to(before) for p in before.rglob("*") if p.suffix in (".json", ".csv")}
    names_b = {p.relative_to(after) for p in after.rglob("*") if p.suffix in (".json", ".csv")}
    for name in sorted(names_a ^ names_b):
        out.append(f"{name}: only in {'after' if name in names_b else 'before'}")
    for name in sorted(names_a & names_b):
        if name.suffix == ".json":
            compare_json(json.loads((before / name).read_text()), json.loads((after / name).read_text()),
                         str(name), rtol, out)
        else:
            compare_csv(before / name, after / name, rtol, out)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--rtol", type=float, default=0.0, help="relative tolerance (0: bit-identical)")
    args = parser.parse_args()
    differences = compare_folders(args.before, args.after, args.rtol)
    for line in differences:
        print(line)
    files = sum(1 for p in args.after.rglob("*") if p.suffix in (".json", ".csv"))
    mode = "bit-identical" if args.rtol == 0 else f"rtol {args.rtol}"
    print(f"{len(differences)} differences in {files} files ({mode})")
    return 1 if differences else 0


if __name__ == "__main__":
    sys.exit(main())
