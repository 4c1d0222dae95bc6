"""Work-precision: errors, drift and the choice per band, and the report on a tiny configuration (FMU)."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis.solvers import work_precision as wp
from double_pendulum.analysis.solvers.reference import Reference


def test_work_precision_report_on_a_tiny_configuration(quick_results):
    tmp_path, summary = quick_scenario(quick_results, "work_precision")
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


# ---------------------------------------------------------------------------- errors, drift and the choice per band
def _reference(t: np.ndarray) -> Reference:
    states = {"phi1": np.sin(t), "phi2": np.cos(t), "omega1": np.cos(t), "omega2": -np.sin(t)}
    return Reference(t, states, np.ones_like(t), 1e-12)


def _result(t: np.ndarray, offset: np.ndarray) -> np.ndarray:
    columns = {"phi1": np.sin(t) + offset, "phi2": np.cos(t), "omega1": np.cos(t), "omega2": -np.sin(t)}
    return np.rec.fromarrays(list(columns.values()), names=list(columns)).view(np.ndarray)


def test_settings_sweep_tolerances_of_adaptive_and_steps_of_fixed_step_methods():
    adaptive = wp.settings_for("dop853", quick=True)
    assert [s["rtol"] for s in adaptive] == [1e-5, 1e-8]
    assert [s["atol"] for s in adaptive] == pytest.approx([1e-7, 1e-10], rel=1e-12)  # atol = rtol / 100
    assert [s["fixed_step"] for s in wp.settings_for("euler", quick=False)] == [1e-3, 1e-4]  # first order
    assert [s["fixed_step"] for s in wp.settings_for("euler", quick=False, thorough=True)] == [1e-3, 1e-4, 2e-5]
    assert [s["fixed_step"] for s in wp.settings_for("rk4", quick=False)] == [2e-2, 1e-2, 5e-3, 2e-3, 1e-3]


def test_errors_compare_the_run_with_the_reference_at_the_same_times():
    ref = _reference(np.arange(0, 101) * 0.01)  # 1 s on a 10 ms grid
    coarse = np.arange(0, 11) * 0.1
    final, largest = wp.errors(_result(coarse, 1e-6 * coarse), ref, 0.1)  # error growing linearly to 1e-6
    assert final == pytest.approx(1e-6) and largest == pytest.approx(1e-6)
    fine = np.arange(0, 201) * 0.005  # every other sample lies on the reference grid
    offset = np.where(np.arange(201) % 2 == 1, 1.0, 0.0) + np.where(np.arange(201) == 100, 3e-7, 0.0)
    final, largest = wp.errors(_result(fine, offset), ref, 0.005)
    assert final == 0.0 and largest == pytest.approx(3e-7)  # the off-grid samples are not compared


def test_energy_drift_is_relative_to_the_start_energy():
    result = np.rec.fromarrays(
        [np.array([2.0, 2.002, 1.999]), np.array([0.0, -1e-3, 4e-3])], names=["E_total", "energy_residual"]
    ).view(np.ndarray)
    assert wp.energy_drift(result, dissipative=False) == pytest.approx(1e-3)
    assert wp.energy_drift(result, dissipative=True) == pytest.approx(2e-3)


def test_timing_and_failure_columns():
    assert wp.timing_columns([0.3, 0.1, 0.2]) == {"cpu_time_s": 0.2, "cpu_spread": pytest.approx(1.0), "repeats": 3}
    assert wp.timing_columns([0.0]) == {"cpu_time_s": 0.0, "cpu_spread": 0.0, "repeats": 1}
    unstable = wp.failure_columns(RuntimeError("fmi2DoStep failed with status 2. FMU says: fmi2DoStep: the step was "
                                               "not completed: numerical instability at t = 1 s"))
    assert unstable == {"status": "unstable", "message": "numerical instability at t = 1 s"}
    long = "fmi2DoStep: the step was not completed: " + "word " * 60
    assert wp.failure_columns(RuntimeError(long)) == {"status": "failed", "message": "word " * 60}  # never cut


def test_cheap_runs_are_timed_several_times_and_expensive_ones_once():
    timing = wp.Timing(min_repeats=1, max_repeats=5, repeat_below_s=0.5)
    assert timing.more([]) and not timing.more([2.0])  # an expensive run: once
    assert timing.more([0.1, 0.1]) and not timing.more([0.1] * 5)  # cheap: up to 5 times
    assert not timing.more([0.2, 0.2, 0.2])  # until 0.5 s CPU in all
    assert wp.THOROUGH_TIMING.more([5.0, 5.0])  # thorough: at least 3 repeats
    assert [s["rtol"] for s in wp.settings_for("rodas4", quick=False)][-1] == 1e-8
    assert [s["rtol"] for s in wp.settings_for("rodas4", quick=False, thorough=True)][-1] == 1e-12
    assert [s["rtol"] for s in wp.settings_for("dopri5", quick=False)][-1] == 1e-10
    assert [s["rtol"] for s in wp.settings_for("dop853", quick=False)][-1] == 1e-12  # the default solver: all
    assert 1e-3 in wp.THOROUGH_COMM_STEPS and 1e-3 not in wp.COMM_STEPS


def test_the_cross_check_reference_floor_resolves_the_errors_the_bands_report(tmp_path):
    """SciPy's DOP853 cross-check: the chaotic case's floor lies far below the 1e-6 band it ranks, and the
    cheap check is keyed apart from the Radau one (--thorough)."""
    from double_pendulum.analysis.solvers import reference

    case = wp.CASES[1]
    ref = reference.reference_solution(case.start, 0.5, wp.BASE_COMM_STEP, cache_dir=tmp_path)
    assert 0.0 < ref.error_floor < 1e-9
    assert reference.cached_reference(case.start, 0.5, wp.BASE_COMM_STEP, cache_dir=tmp_path) is not None
    assert reference.cached_reference(case.start, 0.5, wp.BASE_COMM_STEP, cache_dir=tmp_path,
                                      cross_check=reference.THOROUGH_CROSS_CHECK) is None


def test_best_per_band_takes_the_fastest_run_within_each_bound_above_the_floor():
    rows = [
        {"case": "r", "status": "ok", "solver": "rk4", "fixed_step": 0.01, "comm_step_s": 0.01, "max_error": 5e-4,
         "cpu_time_s": 0.01},
        {"case": "r", "status": "ok", "solver": "dop853", "rtol": 1e-8, "comm_step_s": 0.01, "max_error": 1e-7,
         "cpu_time_s": 0.05},
        {"case": "r", "status": "ok", "solver": "dop853", "rtol": 1e-10, "comm_step_s": 0.01, "max_error": 1e-10,
         "cpu_time_s": 0.08},
        {"case": "r", "status": "unstable", "solver": "euler", "fixed_step": 0.01, "comm_step_s": 0.01},
        {"case": "other", "status": "ok", "solver": "rk4", "max_error": 0.0, "cpu_time_s": 0.0},
    ]
    best = wp.best_per_band(rows, "r", floor=1e-11)
    assert list(best) == ["max_error_le_1e-3", "max_error_le_1e-6", "max_error_le_1e-9"]
    assert [b["solver"] for b in best.values()] == ["rk4", "dop853", "dop853"]
    assert best["max_error_le_1e-6"]["rtol"] == 1e-8 and best["max_error_le_1e-9"]["rtol"] == 1e-10
    assert best["max_error_le_1e-3"]["fixed_step_s"] == 0.01 and "rtol" not in best["max_error_le_1e-3"]
    below = wp.best_per_band(rows, "r", floor=1e-8)["max_error_le_1e-9"]
    assert below == {"reached": False, "reason": "below the reference error floor 1.0e-08"}
    text = wp.report(rows, {"r": wp.best_per_band(rows, "r", floor=1e-8)}, {"r": 1e-8}, quick=True)
    assert "| 1e-3 | rk4 | h 0.01 s | 0.01 | 5.0e-04 | 0.010 |" in text
    assert "| 1e-9 | none: below the reference error floor 1.0e-08 | - | - | - | - |" in text
    assert "| euler | h 0.01 s | 0.01 | unstable |" in text
