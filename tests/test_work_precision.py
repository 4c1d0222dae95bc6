"""The work-precision report generator on a tiny configuration (through the FMU)."""

from __future__ import annotations

import csv
import math

from double_pendulum.scenarios import work_precision


def test_work_precision_report_on_a_tiny_configuration(runner, tmp_path):
    summary = work_precision.run(runner, tmp_path, quick=True)
    with open(tmp_path / "work_precision.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == summary["configurations"] >= 4
    assert all(r["status"] == "ok" for r in rows)
    dop = sorted((float(r["rtol"]), float(r["max_error"])) for r in rows if r["solver"] == "dop853")
    assert dop[0][1] < dop[-1][1]  # tighter tolerance, smaller error
    rk4 = sorted((float(r["fixed_step"]), float(r["max_error"])) for r in rows if r["solver"] == "rk4")
    order = math.log(rk4[1][1] / rk4[0][1]) / math.log(rk4[1][0] / rk4[0][0])
    assert 3.0 < order < 5.0  # classic RK4 with cubic Hermite output
    assert summary["reference_error_floor"]["regular"] < 1e-10
    report = (tmp_path / "report.md").read_text()
    assert "fastest method" in report and "regular" in report
    assert (tmp_path / "work_precision_regular.png").is_file()
