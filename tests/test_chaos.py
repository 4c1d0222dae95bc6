"""Chaos: tangent dynamics, Lyapunov exponents, flipping bound, predictability, sections, scenario."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis.chaos import flips, lyapunov, poincare, releases
from double_pendulum.analysis.chaos.ensemble import (
    batch_energy,
    batch_potential_energy,
    initial_states,
    model_field,
    pendulum_field,
)
from double_pendulum.model.dynamics import linearised_normal_modes
from double_pendulum.model.parameters import AirDragParameters, BearingParameters, PendulumParameters
from double_pendulum.model.vector_field import ModelConfig
from double_pendulum.runs.results_io import read_results_csv

P = PendulumParameters()
FIELD = pendulum_field(P)
CHAOTIC = (2.0, 0.0)  # the scenario's seed-like release: upper rod at 2 rad, lower rod hanging


def test_complex_step_jacobian_at_rest_has_the_normal_mode_frequencies():
    """J(0) = [[0, I], [-M0^-1 K, 0]] has eigenvalues +-i omega_k of the linearised modes."""
    rest = np.zeros((4, 4))
    jac = lyapunov.complex_step_jvp(FIELD, 0.0, rest, np.eye(4))  # column j: J e_j
    eig = np.sort(np.abs(np.linalg.eigvals(jac).imag))
    omegas, _ = linearised_normal_modes(P)
    np.testing.assert_allclose(eig, np.repeat(omegas, 2), rtol=1e-12)
    np.testing.assert_allclose(np.linalg.eigvals(jac).real, 0.0, atol=1e-12)


def test_complex_step_and_central_differences_agree_at_chaotic_states():
    rng = np.random.default_rng(3)
    y = np.vstack((rng.uniform(-3, 3, (2, 20)), rng.uniform(-8, 8, (2, 20))))
    v = rng.standard_normal((4, 20))
    exact = lyapunov.complex_step_jvp(FIELD, 0.0, y, v)
    approx = lyapunov.central_difference_jvp(FIELD, 0.0, y, v)
    np.testing.assert_allclose(approx, exact, rtol=1e-6, atol=1e-6 * np.abs(exact).max())


def test_field_and_central_jvp_in_one_call_equals_separate_calls():
    """The tangent field's single call on [y; y + s v; y - s v] gives bit for bit what separate calls give,
    for the vectorised field and a column-wise (friction) field, with per-column times too."""
    rng = np.random.default_rng(5)
    y = np.vstack((rng.uniform(-3, 3, (2, 3)), rng.uniform(-8, 8, (2, 3))))
    v = rng.standard_normal((4, 3))
    friction = model_field(ModelConfig(P, AirDragParameters(air_drag=True), BearingParameters(bearing_friction=True)))
    for field in (FIELD, friction):
        for t in (0.0, np.array([0.0, 0.5, 1.0])):
            value, jv = lyapunov.field_and_central_jvp(field, t, y, v, at=(t, y))
            np.testing.assert_array_equal(value, field(t, y))
            np.testing.assert_array_equal(jv, lyapunov.central_difference_jvp(field, t, y, v))
            norm_v = np.sqrt(np.sum(v * v, axis=0))
            s = 1e-6 * (1.0 + np.sqrt(np.sum(y * y, axis=0))) / norm_v
            np.testing.assert_array_equal(jv, (field(t, y + s * v) - field(t, y - s * v)) / (2.0 * s))


def test_tangent_and_two_trajectory_methods_agree_trajectory_by_trajectory():
    """Benettin's two methods: the tangent (complex step, exact) and a companion 1e-8 away, over 3 s (six
    renormalisations; 1.0 s of CPU, 6 s took 2.0 s): the two-trajectory estimates within 2e-5 of the tangent's, the
    central-difference tangent within 4e-9."""
    y0 = releases.release_ensemble(*CHAOTIC, 0.005, 6, P, seed=2)
    integration = lyapunov.Integration("rk4", h=2e-3)
    tangent = lyapunov.lyapunov_benettin(FIELD, y0, 3.0, renorm_interval=0.5, integration=integration)
    _, two = lyapunov.lyapunov_two_trajectory(FIELD, y0, 3.0, renorm_interval=0.5, integration=integration)
    np.testing.assert_allclose(two[-1], tangent.exponents[0], rtol=1e-3)
    augmented = lyapunov.lyapunov_benettin(FIELD, y0, 3.0, renorm_interval=0.5, integration=integration, jvp="central")
    np.testing.assert_allclose(augmented.exponents[0], tangent.exponents[0], rtol=1e-6)


def test_lyapunov_exponent_of_a_regular_start_converges_towards_zero():
    res = lyapunov.lyapunov_benettin(
        FIELD,
        initial_states(0.3, 0.3),
        40.0,
        renorm_interval=0.5,
        integration=lyapunov.Integration("rk4", h=5e-3),
    )
    lam = res.running[:, 0, 0]
    at = {t: lam[np.argmin(np.abs(res.times - t))] for t in (5.0, 10.0, 20.0, 40.0)}
    # a quasi-periodic orbit separates linearly: lambda(t) ~ ln(t)/t -> 0
    assert at[5.0] > at[10.0] > at[20.0] > at[40.0] > 0.0
    assert at[40.0] < 0.06


@pytest.fixture(scope="module")
def chaotic_estimates():
    """Largest exponent of the chaotic start, averaged over 64 starts within 5 mm (5 s each: 3.3 s of CPU, 10 s took
    7.1 s). Over 5 s the three integrations still follow the same trajectories (their errors, 1e-10 and below,
    grow e-fold every half second), so the estimates at h and h / 2 are within 0.6 % and 1e-5 of the reference's
    mean, not only within the finite-time scatter (over 10 s they had parted: within 1.8 % and 0.9 %)."""
    y0 = releases.release_ensemble(*CHAOTIC, 0.005, 64, P, seed=11, include_nominal=True)
    out = {}
    for label, integration in {
        "reference": lyapunov.Integration("dop853", rtol=1e-10, atol=1e-12),
        "h": lyapunov.Integration("rk4", h=2e-3),
        "h/2": lyapunov.Integration("rk4", h=1e-3),
    }.items():
        res = lyapunov.lyapunov_benettin(FIELD, y0, 5.0, renorm_interval=0.5, integration=integration)
        out[label] = res.exponents[0]
    return out


def test_lyapunov_exponent_of_the_chaotic_start_is_positive_and_stable_under_step_halving(chaotic_estimates):
    ref = chaotic_estimates["reference"].mean()
    assert ref > 1.0  # 1/s: clearly chaotic (2.25; a regular start gives 0.13 over the same 5 s)
    for label in ("h", "h/2"):
        lam = chaotic_estimates[label]
        assert np.all(lam > 0.0)
        assert abs(lam.mean() - ref) < 0.10 * ref, label


def test_lyapunov_spectrum_pairs_up_and_its_sum_obeys_the_phase_volume_bound():
    t_end = 20.0
    res = lyapunov.lyapunov_benettin(
        FIELD,
        initial_states(*CHAOTIC),
        t_end,
        renorm_interval=0.5,
        n_vectors=4,
        integration=lyapunov.Integration("rk4", h=2e-3),
    )
    lam = res.exponents[:, 0]
    assert lam[0] > 1.0 and np.all(np.diff(lam) < 0)
    assert abs(lam[0] + lam[3]) < 0.05 * lam[0]  # (lambda, ..., -lambda)
    assert abs(lam[1]) < 0.1 * lam[0] and abs(lam[2]) < 0.1 * lam[0]  # the two zeros
    # |sum| <= ln((m1+m2)/m1) / t at every renormalisation time (exact, up to integration error)
    total = np.abs(res.running[:, :, 0].sum(axis=1))
    assert np.all(total <= lyapunov.spectrum_sum_bound(P, res.times) + 1e-9)


def test_lyapunov_exponent_falls_as_damping_drains_the_energy():
    """Any vector field can be analysed: here joint torques Q = -c omega with c = 5e-4 N m s."""
    c = 5e-4
    field = pendulum_field(P, lambda t, y: (-c * y[2], -c * y[3]))
    y0 = releases.release_ensemble(*CHAOTIC, 0.005, 8, P, seed=1, include_nominal=True)
    rk4 = lyapunov.Integration("rk4", h=2e-3)
    res = lyapunov.lyapunov_benettin(field, y0, 40.0, renorm_interval=0.5, integration=rk4)
    centres, local = lyapunov.local_exponents(res, 10.0)
    energy = batch_energy(res.states[-1], P) / flips.flip_energy_threshold(P)
    assert np.all(energy < 1.0)  # every member has dropped below the flipping energy
    mean = local.mean(axis=1)
    assert centres.tolist() == [5.0, 15.0, 25.0, 35.0]
    assert mean[0] > 1.0
    assert mean[-1] < 0.3 and mean[-1] < 0.2 * mean[0]


def _starts_on_energy_contour(energy: float, phi1: np.ndarray) -> np.ndarray:
    """Release angles (phi1, phi2 >= 0) from rest with V(phi1, phi2) = energy, by bisection in phi2."""
    lo, hi = np.zeros_like(phi1), np.full_like(phi1, math.pi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = batch_potential_energy(phi1, mid, P) < energy
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return initial_states(phi1, 0.5 * (lo + hi))


def test_energetic_bound_on_flipping_is_respected_by_every_trajectory():
    bound1, bound2 = flips.flip_energy_bounds(P)
    assert bound1 == pytest.approx(2 * (P.m1 + P.m2) * P.g * P.l1, rel=1e-15)
    assert bound2 == pytest.approx(2 * P.m2 * P.g * P.l2, rel=1e-15)
    fmap = flips.flip_time_map(32, 32, P, t_max=5.0, max_workers=1)
    flipped = fmap.rod > 0
    assert not np.any(flipped & (fmap.energy < bound2))  # nothing flips below the threshold
    assert not np.any((fmap.rod == 1) & (fmap.energy < bound1))  # rod 1 needs V(pi, 0)
    # the bound is not vacuous: starts just above it do flip, the map has both outcomes
    near = (fmap.energy > bound2) & (fmap.energy < 1.5 * bound2)
    assert np.any(flipped & near) and np.any(~flipped)
    # starts just below the threshold, along the whole contour, never reach the upright position
    target = 0.999 * bound2
    phi1 = np.linspace(-math.pi, math.pi, 2001)
    phi1 = phi1[batch_potential_energy(phi1, 0.0, P) < target]  # where the contour exists
    y0 = _starts_on_energy_contour(target, np.linspace(phi1[0], phi1[-1], 40))
    np.testing.assert_allclose(batch_energy(y0, P), target, rtol=1e-9)
    times, rods = flips.first_flip_times(FIELD, y0, 20.0, h=2e-3)
    assert np.all(rods == 0) and np.all(np.isnan(times))


def test_flip_times_are_mirror_symmetric_and_the_mirrored_map_is_the_integrated_one_bit_for_bit():
    """(phi1, phi2) -> (-phi1, -phi2) mirrors the motion: the same flip time. Integrated over the whole grid
    (``mirror=False``) the map is symmetric to rounding, so mirroring half of it gives the same map. Flips up to 2 s
    (1.5 s of CPU; 3 s took 2.2 s): about half the cells flip by then, on both grids."""
    for n1, n2 in ((20, 20), (15, 21)):  # even and odd rows (the middle row of an odd grid is integrated)
        full = flips.flip_time_map(n1, n2, P, t_max=2.0, max_workers=1, mirror=False)
        np.testing.assert_allclose(full.time, full.time[::-1, ::-1], rtol=1e-12, equal_nan=True)
        np.testing.assert_array_equal(full.rod, full.rod[::-1, ::-1])
        assert np.any(np.isfinite(full.time)) and np.any(np.isnan(full.time))  # both outcomes on the grid
        half = flips.flip_time_map(n1, n2, P, t_max=2.0, max_workers=1)
        np.testing.assert_allclose(half.time, full.time, rtol=1e-12, equal_nan=True)
        np.testing.assert_array_equal(half.rod, full.rod)


def test_predictability_horizon_grows_by_one_over_lambda_per_e_fold_of_precision(chaotic_estimates):
    sigmas = np.array([1e-5, 1e-4, 1e-3])
    groups = [releases.release_ensemble(*CHAOTIC, s, 60, P, seed=5 + i) for i, s in enumerate(sigmas)]
    spread = releases.ensemble_spread(FIELD, groups, P, 6.0, h=2e-3, every=5)
    horizon = releases.predictability_horizon(spread.times, spread.spread, 0.01)
    assert np.all(np.isfinite(horizon)) and np.all(np.diff(horizon) < 0)
    # t_h ~ ln(d / sigma) / lambda: the slope against ln(sigma) is -1/lambda (finite-time scatter: x2)
    slope = -np.polyfit(np.log(sigmas), horizon, 1)[0]
    lam = chaotic_estimates["reference"].mean()
    assert 0.5 / lam < slope < 2.0 / lam
    # at release the hanging lower rod moves with the upper bob: both bobs are spread by sigma
    np.testing.assert_allclose(spread.spread[0], sigmas, rtol=0.25)


def test_poincare_points_lie_on_the_section_and_the_energy_surface():
    energy = float(batch_energy(initial_states(*CHAOTIC), P)[0])
    starts = poincare.section_starts(energy, np.linspace(-1.0, 1.0, 5), 0.0, P)
    np.testing.assert_allclose(batch_energy(starts, P), energy, rtol=1e-14)
    pts, owner = poincare.poincare_section(FIELD, starts, 8.0, h=1e-3)
    assert pts.shape[0] > 10 and set(owner) <= set(range(starts.shape[1]))
    np.testing.assert_allclose(pts[:, 0], 0.0, atol=1e-12)
    assert np.all(pts[:, 2] > 0.0)
    # cubic Hermite interpolation within a 1 ms RK4 step: energy error O(h^4)
    np.testing.assert_allclose(batch_energy(pts.T, P), energy, rtol=1e-7)


def test_chaos_scenario_writes_results_plots_and_summary(quick_results):
    import double_pendulum.scenarios.chaos as scenario

    tmp_path, written = quick_scenario(quick_results, "chaos")
    assert written["lyapunov_per_s"] > 0.5
    assert written["flip_map"]["bound_violations"] == 0
    assert written["fmu_vs_batch_dop853_max_angle_difference_rad_first_2s"] < 1e-6
    spectrum = written["lyapunov"]["spectrum"]["exponents_per_s"]
    assert spectrum[0] > 0 > spectrum[3]
    for name in (
        "release_traces",
        "phase_portraits",
        "ensemble_spread",
        "ensemble_clouds",
        "predictability",
        "lyapunov_convergence",
        "lyapunov_energy",
        "lyapunov_spectrum",
        "lyapunov_friction",
        "flip_map",
        "poincare_sections",
    ):
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000, name
    nominal = read_results_csv(tmp_path / "nominal.csv")
    assert nominal["phi1"][0] == scenario.DEFAULT_START["phi1_0"]
    fmap = read_results_csv(tmp_path / "flip_map.csv")
    assert len(fmap) == scenario.QUICK.flip_n**2
    assert set(np.unique(fmap["flipped_rod"])) <= {0.0, 1.0, 2.0}
