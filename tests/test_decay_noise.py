"""The noise model of the measured decay rate b: AR(1) residuals and a moving-block bootstrap.

Synthetic records are exponential decays E = a exp(b t) at the seed's frame rate and length with AR(1)
noise of the record's rho and amplitude; the errors must cover the true b in about 68 % of them at 1 sigma.
"""

from __future__ import annotations

import numpy as np
import pytest

from double_pendulum.analysis.decay.noise import (
    ar1_coefficient,
    ar1_gls_fit,
    ar1_sandwich_errors,
    block_bootstrap,
    block_length_frames,
    gauss_newton_exponential,
)
from double_pendulum.analysis.track.measurement import FPS

A, B = 0.82, -0.0252  # J, 1/s: the record's fit
RHO, SCALE = 0.55, 0.02  # the record's lag-one autocorrelation and rms energy scatter [J]
T = 0.25 + np.arange(624) / FPS


def ar1_noise(rng: np.random.Generator, n: int, rho: float, scale: float) -> np.ndarray:
    """Stationary AR(1) series of standard deviation ``scale``."""
    eps = rng.standard_normal(n) * scale * np.sqrt(1.0 - rho**2)
    z = np.empty(n)
    z[0] = rng.standard_normal() * scale
    for i in range(1, n):
        z[i] = rho * z[i - 1] + eps[i]
    return z


def test_ar1_coefficient_recovers_a_known_rho_from_fit_residuals():
    rng = np.random.default_rng(1)
    w = np.full(len(T), SCALE)
    for rho in (0.0, 0.3, 0.55, 0.8):
        estimates = []
        for _ in range(40):
            e = A * np.exp(B * T) + ar1_noise(rng, len(T), rho, SCALE)
            a, b = gauss_newton_exponential(T, e, w, A, B)
            estimates.append(ar1_coefficient(e - a[0] * np.exp(b[0] * T)))
        # Yule-Walker on 624 points: sd about sqrt((1 - rho^2) / n) < 0.04 each, bias about -(1 + 3 rho) / n
        assert np.mean(estimates) == pytest.approx(rho, abs=0.03)
        assert np.std(estimates) < 0.06


def test_ar1_and_block_bootstrap_errors_cover_the_true_b_in_about_68_percent():
    rng = np.random.default_rng(7)
    w = np.full(len(T), SCALE)
    block = block_length_frames(T)
    hits = {"ar1": 0, "bootstrap": 0, "white": 0}
    n_records = 200
    for _ in range(n_records):
        e = A * np.exp(B * T) + ar1_noise(rng, len(T), RHO, SCALE)
        a, b = (float(x[0]) for x in gauss_newton_exponential(T, e, w, A, B))
        rho = ar1_coefficient((e - a * np.exp(b * T)) / w)
        s_ar1 = ar1_sandwich_errors(T, e, w, a, b, rho)[1]
        s_boot = block_bootstrap(T, e, w, a, b, block=block, n_boot=100, rng=rng)[1]
        s_white = ar1_sandwich_errors(T, e, w, a, b, 0.0)[1]  # independent residuals: too small
        hits["ar1"] += abs(b - B) < s_ar1
        hits["bootstrap"] += abs(b - B) < s_boot
        hits["white"] += abs(b - B) < s_white
    coverage = {k: v / n_records for k, v in hits.items()}
    assert 0.58 <= coverage["ar1"] <= 0.78, coverage
    assert 0.58 <= coverage["bootstrap"] <= 0.78, coverage
    assert coverage["white"] < 0.55, coverage  # ignoring the correlation under-covers


def test_gls_fit_recovers_the_decay_and_rho():
    rng = np.random.default_rng(3)
    e = A * np.exp(B * T) + ar1_noise(rng, len(T), RHO, SCALE)
    fit = ar1_gls_fit(T, e, np.full(len(T), SCALE))
    assert fit.rho == pytest.approx(RHO, abs=0.1)
    assert abs(fit.b - B) < 3.0 * fit.sigma_b and abs(fit.a - A) < 3.0 * fit.sigma_a


def test_statement_of_b_separates_statistical_and_systematic_parts(budget):
    st = budget["b_statement"]
    stat = st["statistical_per_s"]
    assert stat == st["statistical"]["ar1_per_s"] == budget["noise_model"]["ar1"]["b_per_s_stderr"]
    # the statistical error is the record's scatter only: AR(1), bootstrap and F agree within a factor 1.5
    others = [st["statistical"]["bootstrap_per_s"], st["statistical"]["correlation_factor_per_s"]]
    assert all(stat / 1.5 < s < stat * 1.5 for s in others)
    # the systematic part is a range over named variants, not a term added in quadrature to the error
    flat = {f"{g}: {k}": v for g, vs in st["variants_per_s"].items() for k, v in vs.items()}
    lo, hi = st["systematic_range_per_s"]
    assert lo == min([*flat.values(), st["b_per_s"]]) and hi == max([*flat.values(), st["b_per_s"]])
    assert st["systematic_max_shift_per_s"] == pytest.approx(abs(flat[st["systematic_widest_variant"]] - st["b_per_s"]))
    assert st["systematic_max_shift_per_s"] > 2.0 * stat  # the seed's weights move b by more than the noise
    assert st["systematic_max_shift_without_seed_weights_per_s"] < st["systematic_max_shift_per_s"]
    assert f"+- {stat:.4f}" in st["text"] and f"up to {st['systematic_max_shift_per_s']:.4f}" in st["text"]


def test_halves_are_stated_in_sigma_of_the_same_noise_model(budget):
    h = budget["b_statement"]["halves"]
    for key in ("ar1", "bootstrap"):
        errs = h[f"b_per_s_stderr_{key}"]
        assert h[f"difference_in_sigma_{key}"] == pytest.approx(h["difference_per_s"] / np.hypot(*errs))
        # each half carries more than twice the whole record's statistical error (a quarter of the swings each)
        assert min(errs) > 2.0 * budget["b_statement"]["statistical_per_s"]


def test_window_rates_and_drift_are_reported_with_errors(budget):
    st = budget["stationarity"]
    amp = st["amplitude"]
    energies = [w["mean_energy_J"] for w in amp["windows"]]
    assert energies == sorted(energies, reverse=True)  # the energy falls window by window
    assert all(w["b_per_s"] < 0 and w["b_per_s_stderr"] > 0 for w in amp["windows"])
    assert amp["slope_stderr"] > 0
    dr = st["calibration_drift"]
    assert -1.2e-3 < dr["r1_change_m"] < -0.5e-3  # about -0.8 mm over the record
    assert abs(dr["b_shift_per_s"]) < budget["b_statement"]["systematic_max_shift_per_s"]
