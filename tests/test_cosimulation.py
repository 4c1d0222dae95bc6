"""The coupling schemes, the derived added-mass limit and the cosimulation study's helpers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis.coupling.cosimulation import fitted_order, stability_run
from double_pendulum.analysis.coupling.stability import critical_mass_ratio, oscillator_step, spectral_radius
from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.component.suspension import SuspensionCoSimulation
from double_pendulum.fmu.masters.coupling import CouplingError, run_coupled, split_values


def _split(values: dict, scheme: str, stop: float, h: float) -> np.ndarray:
    pv, sv = split_values(values)
    pendulum, suspension = DoublePendulumCoSimulation(), SuspensionCoSimulation()
    for name, value in pv.items():
        pendulum.set(name, value)
    for name, value in sv.items():
        suspension.set(name, value)
    pendulum.initialise()
    suspension.initialise()
    return run_coupled(pendulum, suspension, stop_time=stop, macro_step=h, scheme=scheme)


def test_oscillator_step_is_the_matrix_exponential():
    from scipy.linalg import expm

    h, zeta = 0.7, 0.05
    e = expm(np.array([[0.0, 1.0, 0.0], [-1.0, -2 * zeta, 1.0], [0.0, 0.0, 0.0]]) * h)
    phi, gamma = oscillator_step(h, zeta)
    np.testing.assert_allclose(phi, e[:2, :2], atol=1e-14)
    np.testing.assert_allclose(gamma, e[:2, 2], atol=1e-14)


@pytest.mark.parametrize("scheme", ["jacobi", "jacobi_sequential"])
def test_small_step_limit_is_a_mass_ratio_of_one(scheme):
    assert critical_mass_ratio(1e-3, 0.0, scheme) == pytest.approx(1.0, abs=1e-3)
    assert spectral_radius(0.5, 1e-3, 0.0, scheme) <= 1.0 + 1e-9


def test_split_values_give_the_suspension_the_pendulums_weight():
    pendulum, suspension = split_values({"phi1_0": 0.5, "m1": 1.0, "M_s": 3.0, "suspension": True})
    assert pendulum == {"phi1_0": 0.5, "m1": 1.0}
    assert suspension["M_s"] == 3.0
    assert suspension["F_static_y"] == pytest.approx(-(1.0 + 0.297) * 9.81)


def test_unstable_coupling_ends_with_a_message_and_its_rows():
    light = {"phi1_0": 0.2, "phi2_0": 0.0, "M_s": 0.3, "k_x": 3e3, "k_y": 3e3, "c_x": 0.0, "c_y": 0.0}
    with pytest.raises(CouplingError, match="unstable") as info:
        _split(light, "jacobi", 1.0, 1e-3)
    rows = info.value.rows
    assert 5 < len(rows) < 1000 and np.isfinite(rows["phi1"]).all()


def test_iterative_coupling_is_stable_beyond_the_limit_and_second_order():
    light = {"phi1_0": 0.2, "phi2_0": 0.0, "M_s": 0.3, "k_x": 3e3, "k_y": 3e3, "c_x": 0.0, "c_y": 0.0}
    assert np.isfinite(_split(light, "iterative", 0.05, 1e-3)["phi1"]).all()
    ref = _split({"phi1_0": 1.0, "phi2_0": 1.0}, "iterative", 0.1, 2.5e-4)[-1]
    errors = [abs(_split({"phi1_0": 1.0, "phi2_0": 1.0}, "iterative", 0.1, h)[-1]["phi1"] - ref["phi1"])
              for h in (4e-3, 2e-3, 1e-3)]
    assert 1.7 < fitted_order((4e-3, 2e-3, 1e-3), errors) < 2.4, errors


@pytest.mark.parametrize("scheme, mu, h_omega", [
    ("jacobi_sequential", 0.8, 0.3), ("jacobi_sequential", 1.25, 0.3),
    ("jacobi", 0.9, 1.0),  # grows 4.3 % a step: under 10-fold in 60 steps, a blow-up test called it stable
    ("jacobi", 0.8, 1.0),  # decays 0.5 % a step, just inside the limit 0.810
    ("jacobi_sequential", 0.9, 1.5),  # grows 0.7 % a step, just outside the limit 0.896
])
def test_fitted_spectral_radius_of_the_run_is_the_derived_one(scheme, mu, h_omega):
    point = stability_run((mu, h_omega, 0.05, 60, scheme))
    derived = spectral_radius(mu, h_omega, 0.05, scheme)
    assert point["spectral_radius_fitted"] == pytest.approx(derived, abs=1e-6)
    assert point["stable"] == (mu < critical_mass_ratio(h_omega, 0.05, scheme))


def test_fitted_order_ignores_non_finite_and_tiny_errors():
    assert fitted_order((1.0, 2.0, 4.0, 8.0), (1.0, 4.0, 16.0, math.nan)) == pytest.approx(2.0)


@pytest.mark.slow
def test_quick_scenario_writes_csv_plots_summary_and_report(quick_results):
    tmp_path, summary = quick_scenario(quick_results, "cosimulation")
    for name in ("runs.csv", "stability_map.csv", "summary.json", "report.md", "error_vs_macro_step.png",
                 "error_vs_cpu_time.png", "coupling_energy.png", "stability_map.png"):
        assert (tmp_path / name).is_file(), name
    assert 1.7 < summary["order_angles"]["regular / default / iterative"] < 2.3
    for engine in ("jacobi", "libcosim", "container"):
        assert 0.8 < summary["order_angles"][f"regular / default / {engine}"] < 1.3
    assert not (tmp_path / "fmus").exists()


def test_libcosim_is_skipped_with_a_reason_when_libcosimpy_is_missing(monkeypatch):
    import importlib.util

    from double_pendulum.analysis.coupling import cosimulation

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "libcosimpy" else real(name, *a))
    methods, missing = cosimulation.available_methods()
    assert "libcosim" not in methods and "container" in methods
    assert "libcosimpy" in missing["libcosim"]


def test_the_report_says_in_words_which_run_it_is_and_what_a_negative_slope_means(quick_results):
    from double_pendulum.analysis.coupling.report import _run_kind

    folder, _ = quick_scenario(quick_results, "cosimulation")
    report = (folder / "report.md").read_text()
    assert "This is a quick run" in report and "Quick run:" not in report and "False" not in report
    assert "A negative slope" in report
    assert _run_kind({"quick": False}) == "This is the default run."
