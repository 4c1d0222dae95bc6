"""Record the default runs' summaries the docs quote: copy RESULTS/SCENARIO/summary.json to docs/results/.

    python scripts/record_figures.py RESULTS [SCENARIO ...]

Without scenario names: every scenario the docs' figure markers name (tests/test_doc_figures.py). Run it
after ``double-pendulum run ...`` (default mode) has written RESULTS; then ``pytest tests/test_doc_figures.py``
lists every figure in README.md and docs/ that no longer matches. Timing keys are dropped (they differ from
run to run and no doc figure should quote them from here).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
MARKED = re.compile(r"<!-- fig (\w+):")
TIMING = ("wall_time_s", "wall_s", "map_wall_time_s")


def _drop_timing(value: object) -> object:
    if isinstance(value, dict):
        return {k: _drop_timing(v) for k, v in value.items() if k not in TIMING and not k.startswith("cpu_s")}
    if isinstance(value, list):
        return [_drop_timing(v) for v in value]
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("scenarios", nargs="*")
    args = parser.parse_args(argv)
    pages = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
    names = args.scenarios or sorted({n for p in pages for n in MARKED.findall(p.read_text())})
    out = REPO / "docs" / "results"
    out.mkdir(exist_ok=True)
    for name in names:
        summary = json.loads((args.results / name / "summary.json").read_text())
        if summary.get("quick") or summary.get("thorough"):
            print(f"{name}: not a default run (quick or thorough), not recorded", file=sys.stderr)
            return 1
        (out / f"{name}.json").write_text(json.dumps(_drop_timing(summary), indent=1, sort_keys=False) + "\n")
        print(f"recorded {name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
