"""The energy_decay scenario's figures: exponential-fit summaries, filter gains, weights, the seed comparison."""

from __future__ import annotations

import math

import numpy as np
import pytest

from double_pendulum.analysis.decay import summary as ds
from double_pendulum.analysis.decay.fit import SEED_FIT, fit_all
from double_pendulum.analysis.decay.report import plus_minus, variant_rows
from double_pendulum.analysis.track.measurement import FRAME_INTERVAL


def test_central_difference_gains_are_the_sinc_of_the_frame_step():
    """d/dt sin(w t) by (f(t + dt) - f(t - dt)) / (2 dt) is w cos(w t) sin(w dt) / (w dt); white noise of
    unit size gives a derivative of size sqrt(2) / (2 dt), i.e. a noise gain of 1/sqrt(2)."""
    cd = ds.filter_summary((10.0, 20.0))["central_difference"]
    assert cd["frames"] == 3
    assert cd["noise_gain"] == pytest.approx(1 / math.sqrt(2), rel=1e-12)
    for w in (10.0, 20.0):
        x = w * FRAME_INTERVAL
        assert cd["gain"][f"{w:g}_rad_s"] == pytest.approx(math.sin(x) / x, rel=1e-9)


def test_savitzky_golay_derivative_flattens_fast_swings_less_than_central_differences():
    f = ds.filter_summary()
    sg, cd = f["savgol"], f["central_difference"]
    assert sg["frames"] == 7
    for key in ("10_rad_s", "20_rad_s", "25_rad_s"):
        assert abs(1.0 - sg["gain"][key]) < abs(1.0 - cd["gain"][key])
    assert sg["gain"]["10_rad_s"] == pytest.approx(1.0, abs=1e-3)


def test_fit_exponential_recovers_a_known_decay_and_its_error():
    rng = np.random.default_rng(3)
    t = np.arange(600) * FRAME_INTERVAL
    sigma = np.full(t.size, 0.01)  # J
    e = 0.8 * np.exp(-0.025 * t) + rng.normal(0.0, 0.01, t.size)
    s = ds.fit_exponential(t, e, sigma, True)
    assert abs(s["a_J"] - 0.8) < 4 * s["a_J_stderr"]
    assert abs(s["b_per_s"] + 0.025) < 4 * s["b_per_s_stderr"]
    assert s["autocorrelation_factor"] == pytest.approx(1.0, abs=0.4)  # white residuals
    assert s["b_per_s_stderr_autocorr"] == pytest.approx(s["b_per_s_stderr"] * math.sqrt(s["autocorrelation_factor"]))
    assert 0.8 < s["chi2_red"] < 1.2 and s["n_points"] == 600
    assert ds.fit_exponential(t, e, None, False)["chi2_red"] is None  # relative weights: no chi2


def test_seed_comparison_counts_differences_in_the_seeds_sigma():
    s_b = abs(SEED_FIT["b_per_s"]) * SEED_FIT["b_rel_err"]
    main = {"a_J": SEED_FIT["a_J"], "a_J_stderr_autocorr": 0.01, "b_per_s": SEED_FIT["b_per_s"] + s_b}
    main["b_per_s_stderr_autocorr"] = s_b
    c = ds.seed_comparison(main)
    assert c["b_difference_in_seed_sigma"] == pytest.approx(1.0)
    assert c["b_difference_in_combined_sigma"] == pytest.approx(1 / math.sqrt(2))
    assert c["a_difference_J"] == 0.0 and c["a_J"] == SEED_FIT["a_J"]


def test_weight_share_is_the_share_of_inverse_variances():
    sigma = np.array([1.0, 1.0, 0.5, 0.5])  # weights 1, 1, 4, 4
    assert ds.weight_share(sigma, np.array([False, False, True, True])) == pytest.approx(0.8)
    assert ds.weight_share(np.ones(5), np.arange(5) < 2) == pytest.approx(0.4)


def test_on_all_frames_puts_values_on_the_masked_frames_and_nan_elsewhere():
    full = ds.on_all_frames(np.array([1.0, 2.0]), np.array([False, True, False, True]))
    np.testing.assert_array_equal(full, [np.nan, 1.0, np.nan, 2.0])


def test_decay_curves_start_at_the_fitted_and_the_seeds_energy():
    t = np.arange(300) * FRAME_INTERVAL
    e = 0.7 * np.exp(-0.03 * t) * (1 + 0.01 * np.sin(7 * t))
    fits = fit_all(t, e, np.full(t.size, 0.005), absolute_sigma=True)
    t_curve, curves, best_label = ds.decay_curves(fits, 10.0)
    assert t_curve[0] == 0.0 and t_curve[-1] == 10.0 and len(t_curve) == ds.CURVE_POINTS
    assert best_label == next(iter(curves)) and best_label.endswith("(dAIC 0.0)")  # residuals against the best
    exp_label = next(k for k in curves if k.startswith("exponential (dAIC "))
    assert curves[exp_label][0] == pytest.approx(0.7, rel=0.01)
    seed = curves["seed: 0.813 J exp(-0.024 t)"]
    assert seed[0] == SEED_FIT["a_J"] and seed[-1] == pytest.approx(0.813 * math.exp(-0.24))


def test_report_rows_scale_values_and_mark_relative_weights():
    assert plus_minus(0.01234, 0.0004, 1e3, 2) == "12.34 +- 0.40"
    fit = {"a_J": 0.8, "a_J_stderr_autocorr": 0.002, "b_per_s": -0.024, "b_per_s_stderr_autocorr": 0.0004}
    summary = {
        **fit,
        "chi2_red": 1.0,
        "n_points": 10,
        "weighting_variants": {"equal_weights": {**fit, "chi2_red": None, "n_points": 9}},
    }
    rows = variant_rows(summary).splitlines()
    assert (
        rows[2] == "| Savitzky-Golay energy, calibrated errors (main result) | 0.8000 +- 0.0020 | -0.02400 +- 0.00040 "
        "| 1.00 | 10 |"
    )
    assert rows[3].endswith("| - | 9 |")
