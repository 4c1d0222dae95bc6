"""Extract Table 1 of the seed lab report into ``data/seed_table1.csv``.

Usage: ``python data/extract_seed_table.py REPORT.txt`` (REPORT.txt: path to the report's text)

The report's table has five tab-separated columns (t [s], x1, y1, x2, y2 [m]) split over
several pages with repeated headers and "Fortsetzung" lines; only rows of five numbers are kept,
in their original order, with the frame index added. Values are copied verbatim (no rounding).
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

HEADER = ["frame", "t_s", "x1_m", "y1_m", "x2_m", "y2_m"]


def parse_rows(text: str) -> list[list[str]]:
    """Return the table's numeric rows as strings, after the first table header."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("t\tx-Pos. m_1"))
    rows = []
    for line in lines[start + 1 :]:
        fields = line.split("\t")
        if len(fields) != 5:
            continue
        try:
            [float(f) for f in fields]
        except ValueError:
            continue
        rows.append([f.strip() for f in fields])
    return rows


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(f"usage: python {argv[0]} REPORT.txt  (path to the report's text)", file=sys.stderr)
        return 2
    source = Path(argv[1])
    target = Path(__file__).with_name("seed_table1.csv")
    rows = parse_rows(source.read_text(encoding="utf-8"))
    with target.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(HEADER)
        for frame, row in enumerate(rows):
            writer.writerow([frame, *row])
    print(f"wrote {len(rows)} rows to {target}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
