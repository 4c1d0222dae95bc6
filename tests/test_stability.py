"""The stability scenario on a shortened configuration: every hard case passes or fails loudly."""

from __future__ import annotations

import csv
import json

from double_pendulum.scenarios import stability


def test_every_stability_case_meets_its_criterion(runner, tmp_path):
    summary = stability.run(runner, tmp_path, quick=True)
    rows = summary["rows"]
    failed = [(r["case"], r["verdict"]) for r in rows if not r["passed"]]
    assert not failed
    # explicit solvers on stiff cases failed loudly, with a message naming the cause
    loud = [r for r in rows if r["expect_failure"]]
    assert len(loud) >= 3
    for r in loud:
        assert r["status"] == "failed"
        assert "non-finite" in r["message"] or "more than" in r["message"] or "instability" in r["message"]
    # and the stiff solver passes the same stiff suspension
    stiff = next(r for r in rows if r["case"].startswith("stiff suspension k=1e8") and r["solver"] == "rodas4")
    assert stiff["status"] == "finished" and stiff["max_rel_energy_residual"] < 1e-6
    with open(tmp_path / "stability.csv") as fh:
        assert len(list(csv.DictReader(fh))) == len(rows)
    assert "cases passed their criterion" in (tmp_path / "report.md").read_text()
    assert json.loads((tmp_path / "summary.json").read_text())["passed"] == len(rows)
    assert (tmp_path / "worst_residuals.png").is_file()
