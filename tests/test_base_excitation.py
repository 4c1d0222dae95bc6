"""Scenario ``base_excitation``: Kapitza threshold, Acheson theory, resonance peaks, the quick run."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis import excitation_study as study
from double_pendulum.analysis.excitation import (
    bisect_threshold,
    drive_amplitude,
    peak_frequency,
    time_grid,
    torque_outcome,
    vertical_vibration,
)
from double_pendulum.analysis.excitation_theory import (
    averaging_matrix,
    equivalent_lengths,
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
        return {"stable": a > 0.3}, None

    b = bisect_threshold(probe, 0.0, 1.0, 10)
    assert abs(b.threshold - 0.3) < 1e-3 and b.falls_at <= 0.3 < b.stable_at and len(probes) == 12
    with pytest.raises(ValueError, match="bad bracket"):
        bisect_threshold(probe, 0.5, 1.0, 3)
    t = np.linspace(0.0, 10.0, 2001)
    x = 0.3 + 0.7 * np.sin(2.0 * t + 0.4) + 0.05 * np.sin(5.3 * t)
    assert drive_amplitude(t, x, 2.0) == pytest.approx(0.7, rel=5e-3)  # the 5.3 rad/s line leaks a little
    w = np.linspace(4.0, 6.0, 21)
    lorentz = 1.0 / np.sqrt((5.03**2 - w**2) ** 2 + (0.2 * w) ** 2)
    assert peak_frequency(w, lorentz, 5.0) == pytest.approx(5.03 * math.sqrt(1 - 0.5 * (0.2 / 5.03) ** 2), rel=2e-3)


def test_kapitza_threshold_within_5_percent_of_theory():
    """Cheap setting, in-process (same component as the FMU): bisection to +-0.7 %."""
    setup = study.KapitzaSetup(stop_time=2.5, steps_per_period=16, iterations=4)
    result = study.kapitza_study(None, setup)
    error = result.bisection.threshold / result.theory_point_mass - 1.0
    assert abs(error) < 0.05, error
    assert abs(result.effective_length / result.params.l1 - 1.0) < 1e-3  # the single-pendulum limit


def test_resonance_peaks_at_the_normal_modes():
    setup = study.ResonanceSetup(settle_time=10.0, window=5.0)
    start = study.resonance_start(setup)
    for mode in study.normal_modes():
        rows = [torque_outcome(study.TorqueCase(setup.torque, mode * (1 + o), start, setup.settle_time,
                                                setup.window, setup.step)) for o in (-0.04, -0.02, 0.0, 0.02, 0.04)]
        omegas = np.array([r["omega_rad_per_s"] for r in rows])
        for angle in ("phi1", "phi2"):
            peak = peak_frequency(omegas, np.array([r[f"{angle}_amplitude_rad"] for r in rows]), mode)
            assert abs(peak / mode - 1.0) < 0.02, (mode, angle, peak)


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
    assert abs(summary["kapitza_relative_error"]) < 0.05
    assert summary["acheson_agreement_fraction"] >= 0.75
    assert summary["resonance_max_abs_relative_error"] < 0.05
    for name in ("kapitza_threshold.png", "acheson_map.png", "acheson_examples.png", "resonance_curve.png",
                 "acheson_map.csv", "resonance_curve.csv", "kapitza_bisection.csv", "report.md"):
        assert (out / name).is_file(), name
