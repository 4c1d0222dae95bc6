"""The stability cases and criteria, and the scenario on a shortened run: every case passes or fails loudly."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis.solvers import stability_cases
from double_pendulum.model.parameters import PendulumParameters


def test_every_stability_case_meets_its_criterion(quick_results):
    tmp_path, summary = quick_scenario(quick_results, "stability")
    rows = summary["rows"]
    failed = [(r["case"], r["verdict"]) for r in rows if not r["passed"]]
    assert not failed
    # explicit solvers on stiff cases failed loudly, with a message naming the cause
    loud = [r for r in rows if r["expect_failure"]]
    assert len(loud) >= 3
    for r in loud:
        assert r["status"] == "failed"
        assert "non-finite" in r["message"] or "more than" in r["message"] or "instability" in r["message"]
        assert r["cpu_time_s"] < 1.0  # and quickly: the blow-up or the step budget trips within the first doSteps
    # and the stiff solver passes the same stiff suspension
    stiff = next(r for r in rows if r["case"].startswith("stiff suspension k=1e8") and r["solver"] == "rodas4")
    assert stiff["status"] == "finished" and stiff["max_rel_energy_residual"] < 1e-6
    with open(tmp_path / "stability.csv") as fh:
        assert len(list(csv.DictReader(fh))) == len(rows)
    assert "cases passed their criterion" in (tmp_path / "report.md").read_text()
    assert json.loads((tmp_path / "summary.json").read_text())["passed"] == len(rows)
    assert (tmp_path / "worst_residuals.png").is_file()


# ---------------------------------------------------------------------------- the cases and criteria, without the FMU
def _result(**columns) -> np.ndarray:
    names = list(columns)
    return np.rec.fromarrays([np.asarray(columns[n], dtype=float) for n in names], names=names).view(np.ndarray)


def _row(**values) -> dict:
    return {"status": "finished", "message": "", "cpu_time_s": 1.0, "finite": True, "max_rel_energy_residual": 1e-9,
            **values}


def test_critical_damping_gives_a_damping_ratio_of_one():
    k, m = 1e6, 0.648
    c = stability_cases.critical_damping(k, m)
    assert c / (2.0 * math.sqrt(k * m)) == pytest.approx(1.0, rel=1e-15)
    # x'' + (c/m) x' + (k/m) x = 0 has a double root -c/(2m) = -sqrt(k/m)
    assert c / (2 * m) == pytest.approx(math.sqrt(k / m), rel=1e-15)
    critical = next(c for c in stability_cases.cases() if c.name == "critically damped suspension")
    p = PendulumParameters()
    assert critical.start["c_x"] == pytest.approx(2.0 * math.sqrt(critical.start["k_x"] * (0.05 + p.m1 + p.m2)))


def test_energy_scale_uses_the_case_parameters_or_the_defaults():
    p = PendulumParameters()
    assert stability_cases.energy_scale({"phi1_0": 1.0}) == pytest.approx((p.m1 + p.m2) * p.g * (p.l1 + p.l2))
    assert stability_cases.energy_scale({"m2": 1e-4 * p.m1, "l2": 1e-3}) == pytest.approx(
        (p.m1 + 1e-4 * p.m1) * p.g * (p.l1 + 1e-3)
    )


def test_quick_runs_use_the_quick_length_and_at_most_five_seconds():
    case = stability_cases.Case("c", {}, stop_time=1000.0, quick_stop_time=20.0)
    assert stability_cases.run_length(case, quick=False) == 1000.0
    assert stability_cases.run_length(case, quick=True) == 5.0
    assert stability_cases.run_length(stability_cases.Case("c", {}, stop_time=2.0), quick=True) == 2.0


def test_measured_columns_scale_the_residual_by_the_larger_of_e0_and_the_energy_scale():
    case = stability_cases.Case("c", {"phi1_0": 0.1})
    scale = stability_cases.energy_scale(case.start)  # E_total(0) is smaller: the scale wins
    result = _result(time=[0.0, 0.5, 1.0], E_total=[0.01, 0.01, 0.01], energy_residual=[0.0, -2e-6 * scale, 1e-6],
                     solver_steps=[0, 5, 9], solver_rhs_evaluations=[0, 60, 108])
    measured = stability_cases.measured_columns(case, result)
    assert measured == {"finite": True, "max_rel_energy_residual": pytest.approx(2e-6), "solver_steps": 9,
                        "rhs_evaluations": 108, "reached_time_s": 1.0}
    result["E_total"][1] = np.nan
    assert stability_cases.measured_columns(case, result)["finite"] is False
    assert stability_cases.measured_columns(case, None) == {} == stability_cases.measured_columns(case, result[:0])


def test_judge_applies_each_criterion():
    case = stability_cases.Case("c", {}, tol=1e-6, cpu_budget_s=10.0)
    assert stability_cases.judge(case, _row()) == (True, "ok")
    assert stability_cases.judge(case, _row(status="failed", message="gave up")) == (False, "solver gave up: gave up")
    assert stability_cases.judge(case, _row(finite=False)) == (False, "non-finite outputs")
    too_large = stability_cases.judge(case, _row(max_rel_energy_residual=2e-6))
    assert too_large == (False, "energy residual 2.00e-06 > 1e-06")
    assert stability_cases.judge(case, _row(cpu_time_s=12.0)) == (False, "CPU time 12.0 s > budget 10 s")
    loud = stability_cases.Case("c", {}, expect_failure=True)
    assert stability_cases.judge(loud, _row(status="failed", message="non-finite state"))[0]
    assert not stability_cases.judge(loud, _row(status="failed", message=""))[0]  # silent failure
    assert not stability_cases.judge(loud, _row())[0]  # finished although it should not


def test_expected_failures_are_explicit_solvers_and_every_case_has_its_own_name():
    table = stability_cases.cases()
    assert len({c.name for c in table}) == len(table)
    # the stiff suspension cases (the costly ones: Rodas4 resolves the suspension mode) stay short
    stiff = [c for c in table if c.start.get("suspension")]
    assert len(stiff) == 7 and all(c.stop_time <= stability_cases.STIFF_STOP for c in stiff)
    assert all(stability_cases.run_length(c, quick=True) == stability_cases.QUICK_STIFF_STOP for c in stiff)
    assert {c.start["solver"] for c in table if c.expect_failure} <= {"rk4", "dop853"}


def test_worst_passing_rows_and_the_report_tally():
    rows = [
        {"case": "a", "solver": "dop853", "status": "finished", "max_rel_energy_residual": 1e-9, "cpu_time_s": 0.1,
         "passed": True, "verdict": "ok", "solver_steps": 5},
        {"case": "b", "solver": "rk4", "status": "failed", "message": "blow-up", "cpu_time_s": 0.2,
         "passed": True, "verdict": "failure detected and reported, as expected"},
        {"case": "c", "solver": "dop853", "status": "finished", "max_rel_energy_residual": 1e-7, "cpu_time_s": 0.1,
         "passed": False, "verdict": "energy residual", "solver_steps": 7},
    ]
    assert [r["case"] for r in stability_cases.worst_passing(rows, 3)] == ["c", "a"]
    text = stability_cases.report(rows, quick=True)
    assert "| c | dop853 | **NO** | energy residual | 1.0e-07 | 0.10 |" in text
    assert "| b | rk4 | yes | failure detected and reported, as expected | - | 0.20 |" in text  # no residual
    assert "2 of 3 passed" in text.split("## Words used below")[0]  # the plain summary says so
    assert "- **b**: blow-up" in text
    assert stability_cases.summary_rows([{"case": "a", "note": "", "message": ""}]) == [{"case": "a"}]
    assert text.endswith("2 of 3 cases passed their criterion.\n")
