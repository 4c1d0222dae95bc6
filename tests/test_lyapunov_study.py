"""Lyapunov studies: step-halving comparison, convergence checkpoints, spectrum, energy scan, friction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from double_pendulum.analysis.chaos import lyapunov, lyapunov_study, releases
from double_pendulum.analysis.chaos.ensemble import initial_states, model_field, pendulum_field, rod_field
from double_pendulum.model.parameters import AirDragParameters, BearingParameters, PendulumParameters
from double_pendulum.model.vector_field import ModelConfig

P = PendulumParameters()
FIELD = pendulum_field(P)
METHODS = {"dop853": lyapunov.Integration("dop853", rtol=1e-10, atol=1e-12),
           "rk4_h": lyapunov.Integration("rk4", h=1e-3)}


def test_checkpoints_take_the_running_estimate_at_the_nearest_renormalisation_time():
    times = 0.5 * np.arange(1, 41)  # up to 20 s
    running = 1.0 / times
    assert lyapunov_study.convergence_checkpoints(times, running) == {
        "lambda_per_s_after_5_s": 0.2, "lambda_per_s_after_10_s": 0.1, "lambda_per_s_after_20_s": 0.05}


def test_standard_error_is_the_sample_deviation_over_root_n():
    assert lyapunov_study.standard_error(np.array([1.0, 2.0, 3.0, 4.0])) == pytest.approx(math.sqrt(5 / 3) / 2)


@pytest.fixture(scope="module")
def comparison() -> lyapunov_study.IntegrationComparison:
    starts = releases.release_ensemble(2.0, 0.0, 0.005, 4, P, seed=41, include_nominal=True)
    return lyapunov_study.compare_integrations(FIELD, starts, 4.0, METHODS, renorm=0.5)


def test_integrations_agree_on_the_chaotic_cloud_and_the_summary_reports_their_difference(comparison):
    cloud = comparison.cloud_exponents()
    assert comparison.members == 4 and comparison.times[-1] == 4.0
    np.testing.assert_allclose(cloud["rk4_h"], cloud["dop853"], rtol=1e-3)  # RK4 at 1 ms: converged
    summary = lyapunov_study.largest_exponent_summary(comparison, "dop853", "starts within 5 mm")
    assert summary["lyapunov_per_s"] == pytest.approx(cloud["dop853"].mean(), rel=1e-15)
    assert summary["lyapunov_per_s"] > 0.5  # chaotic
    assert summary["default_start_alone_per_s"] == cloud["dop853"][0]
    halving = summary["step_halving"]["rk4 h=0.001 s"]
    assert halving["relative_to_dop853_cloud_mean"] == pytest.approx(cloud["rk4_h"].mean() / cloud["dop853"].mean() - 1)
    assert summary["method"].endswith("dop853 rtol=1e-10, 4 s, mean over the default start and 3 starts within 5 mm")
    # the two-trajectory estimate (companion 1e-8 away) agrees with the tangent method
    assert summary["two_trajectory_rk4_cloud_mean"] == pytest.approx(cloud["rk4_h"].mean(), rel=1e-3)
    table, units = lyapunov_study.convergence_table(comparison)
    np.testing.assert_array_equal(table["lambda_dop853_cloud_mean"], comparison.cloud_running()["dop853"])
    np.testing.assert_array_equal(table["lambda_two_trajectory_rk4_cloud_mean"], comparison.two_trajectory.mean(axis=1))
    assert table["lambda_two_trajectory_rk4_cloud_mean"][-1] == pytest.approx(summary["two_trajectory_rk4_cloud_mean"])
    assert set(units.values()) == {"1/s"}


def test_spectrum_pairs_and_its_sum_stays_within_the_phase_volume_bound():
    spec = lyapunov_study.lyapunov_spectrum(FIELD, initial_states(2.0, 0.0), 4.0, P, renorm=0.5, h=1e-3)
    np.testing.assert_allclose(spec.sum_bound, math.log((P.m1 + P.m2) / P.m1) / spec.times, rtol=1e-15)
    assert np.all(np.abs(spec.running.sum(axis=1)) <= spec.sum_bound * (1 + 1e-9))
    summary = lyapunov_study.spectrum_summary(spec, 4.0)
    assert summary["exponents_per_s"][0] > 0 > summary["exponents_per_s"][3]
    assert summary["method"].endswith("rk4 h = 1 ms")
    table, _ = lyapunov_study.spectrum_table(spec)
    np.testing.assert_array_equal(table["sum"], spec.running.sum(axis=1))


def test_energy_scan_relates_each_release_angle_to_the_flip_energy():
    scan = lyapunov_study.energy_scan(FIELD, (0.3, 2.0), P, 1.0, renorm=0.5, h=1e-3)
    # E = V(theta, theta) = ((m1 + m2) g l1 + m2 g l2)(1 - cos theta); E_flip = V(0, pi) = 2 m2 g l2
    expected = ((P.m1 + P.m2) * P.g * P.l1 + P.m2 * P.g * P.l2) * (1.0 - np.cos([0.3, 2.0]))
    np.testing.assert_allclose(scan.energy, expected, rtol=1e-14)
    np.testing.assert_allclose(scan.energy_ratio, expected / (2 * P.m2 * P.g * P.l2), rtol=1e-14)
    assert scan.energy_ratio[0] < 1.0 < scan.energy_ratio[1]
    assert lyapunov_study.energy_scan_table(scan)[0]["lambda_max"].tolist() == scan.exponent.tolist()


def test_single_trajectory_benettin_on_the_runtime_integrator_agrees_with_the_batch_one():
    """lyapunov_single (float field, the FMU's DOP853) and lyapunov_benettin (batch DOP853, column-wise field)
    integrate the same equations with the same tangent: over 2 s, before the chaotic trajectory forgets
    the integrators' differences (rtol 1e-8), their log growths per 0.5 s agree to 1e-4 relative."""
    config = ModelConfig(P, AirDragParameters(air_drag=True), BearingParameters(bearing_friction=True))
    single = lyapunov.lyapunov_single(rod_field(config), [2.0, 0.0, 0.0, 0.0], 2.0, renorm_interval=0.5, rtol=1e-8)
    batch = lyapunov.lyapunov_benettin(model_field(config), initial_states(2.0, 0.0), 2.0, renorm_interval=0.5,
                                    integration=lyapunov.Integration("dop853", rtol=1e-8, atol=1e-10), jvp="central")
    np.testing.assert_allclose(single.times, batch.times)
    np.testing.assert_allclose(single.log_growth, batch.log_growth, rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(single.states, batch.states, rtol=1e-5, atol=1e-5)
    assert single.running.shape == batch.running.shape == (4, 1, 1)


def test_friction_drains_the_energy_seen_by_the_windowed_exponent():
    config = ModelConfig(P, AirDragParameters(air_drag=True), BearingParameters(bearing_friction=True))
    windows = lyapunov_study.exponent_with_friction(rod_field(config), [2.0, 0.0, 0.0, 0.0], 2.0, P, renorm=0.5,
                                                    window=1.0)
    np.testing.assert_allclose(windows.centres, [0.5, 1.5])
    assert np.all(np.diff(windows.energy_ratio) < 0.0)  # dissipation: E falls at every renormalisation
    np.testing.assert_allclose(windows.ratio_at_centres, np.interp([0.5, 1.5], windows.times, windows.energy_ratio))
    summary = lyapunov_study.friction_summary(windows, 1.0, ["air_drag (bobs)"])
    assert summary["mechanisms"] == ["air_drag (bobs)"] and summary["window_s"] == 1.0
