"""Scenario ``base_excitation``: Kapitza threshold, Acheson theory, resonance peaks, the quick run."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis.excitation import study
from double_pendulum.analysis.excitation.drive import (
    FloquetCase,
    bisect_threshold,
    drive_amplitude,
    floquet_outcome,
    peak_frequency,
    time_grid,
    torque_outcome,
    vertical_vibration,
)
from double_pendulum.analysis.excitation.theory import (
    averaging_matrix,
    damped_peak_frequency,
    equivalent_lengths,
    held_floquet_exponent,
    held_lower_amplitude,
    kapitza_amplitude,
    mathieu_lower_amplitude,
    mathieu_upper_amplitude,
    upright_stable,
)
from double_pendulum.model.dynamics import linearised_normal_modes
from double_pendulum.model.inputs import INPUT_NAMES
from double_pendulum.model.parameters import PendulumParameters


def test_vibration_signal_is_consistent_and_complete():
    t, stop = time_grid(1.0, 0.001)
    assert stop == pytest.approx(1.0) and t[-1] > stop
    sig = vertical_vibration(0.02, 30.0, t)
    assert sig.dtype.names == ("time", *INPUT_NAMES)
    # v is the derivative of y, a of v (central differences)
    dt = t[1] - t[0]
    assert np.allclose(np.gradient(sig["pivot_y"], dt)[1:-1], sig["pivot_vy"][1:-1], rtol=0, atol=3e-4)
    assert np.allclose(np.gradient(sig["pivot_vy"], dt)[1:-1], sig["pivot_ay"][1:-1], rtol=0, atol=1e-2)
    assert not np.any(sig["tau1"]) and not np.any(sig["pivot_x"])


def test_theory_limits():
    g, length = 9.81, 0.3
    # exact lower bound -> Kapitza's a^2 w^2 = 2 g L at high frequency (small a/L)
    assert mathieu_lower_amplitude(2000.0, length, g) / kapitza_amplitude(2000.0, length, g) == pytest.approx(1, 1e-4)
    # flutter bound -> 0.454 L at high frequency
    assert mathieu_upper_amplitude(1e5, length, g) / length == pytest.approx(0.454, abs=1e-3)
    # A = M0^-1 D has eigenvalues omega_i^2 / g; equivalent lengths are g / omega_i^2
    p = PendulumParameters()
    (w1, w2), _ = linearised_normal_modes(p)
    assert np.sort(np.linalg.eigvals(averaging_matrix(p)).real) == pytest.approx([w1**2 / p.g, w2**2 / p.g])
    assert equivalent_lengths(p) == pytest.approx((p.g / w1**2, p.g / w2**2))
    # a point inside the wedge is stable, below and above it not
    assert upright_stable(0.022, 200.0, p) and not upright_stable(0.010, 200.0, p)
    assert not upright_stable(0.036, 200.0, p)


def test_helpers_on_synthetic_data():
    probes = []

    def probe(a):
        probes.append(a)
        return {"stable": a > 0.3}

    b = bisect_threshold(probe, 0.0, 1.0, 10)
    assert abs(b.threshold - 0.3) < 1e-3 and b.unstable_at <= 0.3 < b.stable_at and len(probes) == 12
    with pytest.raises(ValueError, match="bad bracket"):
        bisect_threshold(probe, 0.5, 1.0, 3)
    t = np.linspace(0.0, 10.0, 2001)
    x = 0.3 + 0.7 * np.sin(2.0 * t + 0.4) + 0.05 * np.sin(5.3 * t)
    assert drive_amplitude(t, x, 2.0) == pytest.approx(0.7, rel=5e-3)  # the 5.3 rad/s line leaks a little
    w = np.linspace(4.0, 6.0, 21)
    lorentz = 1.0 / np.sqrt((5.03**2 - w**2) ** 2 + (0.2 * w) ** 2)
    assert peak_frequency(w, lorentz, 5.0) == pytest.approx(5.03 * math.sqrt(1 - 0.5 * (0.2 / 5.03) ** 2), rel=2e-3)


def test_held_input_bound_tends_to_the_mathieu_bound_and_lies_above_it():
    """The held input's exact bound converges to the continuous sinusoid's as the hold gets finer."""
    p = study.kapitza_parameters(study.KapitzaSetup())
    length = equivalent_lengths(p)[0]
    continuous = mathieu_lower_amplitude(50.0, length, p.g)
    held = [held_lower_amplitude(50.0, length, p.g, n) for n in (24, 96, 384)]
    assert held[0] > held[1] > held[2] > continuous
    assert held[2] / continuous - 1.0 < 1e-4 < held[0] / continuous - 1.0


def test_floquet_multipliers_as_simulated_match_the_held_input_theory():
    """In-process (the FMU's component): the monodromy of one period gives the held-input theory's growth."""
    setup = study.KapitzaSetup()
    p = study.kapitza_parameters(setup)
    length = equivalent_lengths(p)[0]
    masses = {"m1": p.m1, "m2": p.m2}
    for a in (0.0480, 0.048565, 0.0490):  # unstable, unstable (+0.1 % over the continuous bound), stable
        outcome = floquet_outcome(FloquetCase(a, 50.0, masses, 24))
        theory = held_floquet_exponent(a, 50.0, length, p.g, 24)
        assert outcome["floquet_exponent_per_s"] == pytest.approx(theory, abs=1e-5)
        assert outcome["stable"] == (theory == pytest.approx(0.0, abs=1e-8))
    # 48.565 mm grows by about 4 % a period: 4 s cannot show it as "fell over", the multiplier does
    assert not floquet_outcome(FloquetCase(0.048565, 50.0, masses, 24))["stable"]


def test_kapitza_threshold_is_the_held_inputs_floquet_bound():
    """Cheap setting, in-process: the bisection on the simulated multipliers lands on the exact held bound."""
    setup = study.KapitzaSetup(stop_time=0.5, steps_per_period=16, iterations=12)
    result = study.kapitza_study(None, setup)
    assert abs(result.bisection.threshold / result.held_exact - 1.0) < 2e-4
    assert result.held_exact > result.mathieu_exact > result.theory_point_mass
    assert abs(result.effective_length / result.params.l1 - 1.0) < 1e-3  # the single-pendulum limit


def test_resonance_peaks_at_the_damped_linear_response():
    setup = study.ResonanceSetup()  # 16 s to settle: the transient decays as exp(-zeta omega t), zeta about 0.04
    start = study.resonance_start(setup)
    params = PendulumParameters()
    for mode in study.normal_modes():
        rows = [torque_outcome(study.TorqueCase(setup.torque, mode * (1 + o), start, setup.settle_time,
                                                setup.window, setup.step)) for o in (-0.012, -0.006, 0.0, 0.006, 0.012)]
        omegas = np.array([r["omega_rad_per_s"] for r in rows])
        for i, angle in enumerate(("phi1", "phi2")):
            peak = peak_frequency(omegas, np.array([r[f"{angle}_amplitude_rad"] for r in rows]), mode)
            damped = damped_peak_frequency(mode, i, params, setup.b_v1)
            assert abs(peak / damped - 1.0) < 3e-3, (mode, angle, peak, damped)
    # damping moves the two rods' peaks to different sides of the slow mode
    slow = study.normal_modes()[0]
    assert damped_peak_frequency(slow, 0, params, setup.b_v1) < slow < damped_peak_frequency(slow, 1, params,
                                                                                             setup.b_v1)


def _numbers(value):
    if isinstance(value, dict):
        for v in value.values():
            yield from _numbers(v)
    elif isinstance(value, list):
        for v in value:
            yield from _numbers(v)
    else:
        yield value


def test_quick_run_through_the_fmu(quick_results):
    out, summary = quick_scenario(quick_results, "base_excitation")
    assert all(v is not None for v in _numbers(summary)), "null in summary.json"
    numeric = {k: v for k, v in summary.items() if isinstance(v, float)}
    assert all(math.isfinite(v) for v in numeric.values())
    assert abs(summary["kapitza_relative_error_vs_held_exact"]) < 1e-3
    assert summary["acheson_agreement_fraction"] == 1.0
    assert summary["resonance_max_abs_relative_error"] < 0.02
    for name in ("kapitza_threshold.png", "acheson_map.png", "acheson_examples.png", "resonance_curve.png",
                 "acheson_map.csv", "resonance_curve.csv", "kapitza_bisection.csv", "report.md"):
        assert (out / name).is_file(), name
