"""The docs quote the scenarios' figures, they do not restate them: each quoted headline figure carries a
marker naming the summary key it comes from, and this test fails when the number no longer matches.

A marker follows the number it belongs to, with at most a unit between (HTML comments do not render; a
dash right after a marker, as in a range 0.8<!-- ... -->-0.9<!-- ... -->, is no minus sign):

    the threshold is 48.65 mm<!-- fig base_excitation:kapitza_held_exact_amplitude_m*1e3 -->

``SCENARIO:PATH[*SCALE]``: PATH walks the scenario's ``summary.json`` by keys separated by ``/`` (a list by
its index, or by ``[name=value]`` for the entry whose ``name`` is ``value``); the value times SCALE must
round to the quoted number at the quoted number's last digit. The summaries quoted are the default runs'
(``docs/results/SCENARIO.json``, written by ``python scripts/record_figures.py RESULTS_DIR`` after
``double-pendulum run``): refreshing them after a change makes this test fail wherever the docs quote a
figure that moved. Every marked key must also exist in the quick run's summary of the current code, so a
renamed or removed key fails at once.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import pytest
from conftest import REPO, quick_scenario

from double_pendulum.runs.page import lookup  # the one path reader: the page shows the same figures

PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
RECORDED = REPO / "docs" / "results"
MARKER = re.compile(
    r"(?<![\d>.])(?P<number>[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?)(?P<unit>[^\d<>\n]{0,12}?)"
    r"<!-- fig (?P<scenario>\w+):(?P<path>[^*]+?)(?:\*(?P<scale>[-+.\deE]+))? -->"
)


def markers(text: str) -> list[re.Match]:
    """Every figure marker of a page's text (with the number before it)."""
    return list(MARKER.finditer(text))


def mismatch(match: re.Match, summary: Any) -> str | None:
    """Why a marked figure does not match its summary (None if it does, within the quoted rounding)."""
    quoted = match["number"]
    try:
        value = lookup(summary, match["path"])
    except (KeyError, IndexError, StopIteration, ValueError, TypeError):
        return f"{match['scenario']}:{match['path']} not in its summary"
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        return f"{match['scenario']}:{match['path']} is {value!r}, not a number"
    scaled = value * float(match["scale"] or 1.0)
    digits = len(quoted.split(".")[1].split("e")[0]) if "." in quoted else 0
    exponent = int(quoted.lower().split("e")[1]) if "e" in quoted.lower() else 0
    tolerance = 0.5 * 10.0 ** (exponent - digits) * (1.0 + 1e-9)
    if abs(scaled - float(quoted)) > tolerance:
        return f"quotes {quoted}, {match['scenario']}:{match['path']} gives {scaled:.6g}"
    return None


def recorded(scenario: str) -> dict:
    """The default run's summary of ``scenario`` as recorded in ``docs/results``."""
    return json.loads((RECORDED / f"{scenario}.json").read_text())


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_every_marked_figure_matches_the_recorded_default_run(page: Path):
    problems = [f"{page.relative_to(REPO)}: {why}" for m in markers(page.read_text())
                if (why := mismatch(m, recorded(m["scenario"])))]
    assert not problems, "\n".join(problems)


def test_the_headline_figures_are_marked():
    """The pages this project's claims live on quote their headline figures with markers."""
    counts = {p.name: len(markers(p.read_text())) for p in PAGES}
    assert counts["README.md"] >= 3 and counts["data-analysis.md"] >= 15 and counts["coupling.md"] >= 8
    # the README's findings are a short summary: every figure it quotes is quoted in docs/ too
    keys = {page.name: {(m["scenario"], m["path"]) for m in markers(page.read_text())} for page in PAGES}
    in_docs = set().union(*(found for name, found in keys.items() if name != "README.md"))
    assert keys["README.md"] <= in_docs
    assert {m["scenario"] for p in PAGES for m in markers(p.read_text())} >= {
        "energy_decay", "loss_identification", "measured_vs_sim", "suspension_transfer", "base_excitation",
        "cosimulation"}


def test_a_figure_that_moved_fails():
    text = "threshold 48.65 mm<!-- fig base_excitation:kapitza/held*1e3 --> and 37 %<!-- fig x:share*100 -->"
    first, second = markers(text)
    assert mismatch(first, {"kapitza": {"held": 0.048652}}) is None
    assert "gives 48.7" in mismatch(first, {"kapitza": {"held": 0.048702}})
    assert mismatch(second, {"share": 0.374}) is None and mismatch(second, {"share": 0.376}) is not None
    low, high = markers("0.8<!-- fig x:lo -->-0.9<!-- fig x:hi -->")
    assert (low["number"], high["number"]) == ("0.8", "0.9")
    assert "not in its summary" in mismatch(first, {"kapitza": {}})
    rows = {"models": [{"model": "air", "w": 0.2}, {"model": "air+drag", "w": 0.51}]}
    assert lookup(rows, "models/[model=air+drag]/w") == 0.51 and lookup(rows, "models/0/w") == 0.2


def test_every_marked_key_exists_in_the_current_quick_run(quick_results):
    """A marker's top-level key must still be written by the scenario's code (quick run of this session)."""
    missing = []
    for page in PAGES:
        for m in markers(page.read_text()):
            _, summary = quick_scenario(quick_results, m["scenario"])
            if m["path"].split("/")[0] not in summary:
                missing.append(f"{page.relative_to(REPO)}: {m['scenario']}:{m['path']}")
    assert not missing, "\n".join(missing)
