"""The loss fits' noise model and out-of-sample test: the AR(1) likelihood and the criteria built on it; a known
mechanism recovered by fitting one half of a synthetic record and predicting the other.

The synthetic record is the energy of the FMU's own component (the simulation every fit uses) with one loss
mechanism, on the camera's frame grid over the seed's record length, plus AR(1) noise with the seed's lag-1
correlation and the seed's typical frame error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from double_pendulum.analysis.losses import fitting, holdout, mechanisms, noise
from double_pendulum.analysis.track.measurement import FRAME_INTERVAL
from double_pendulum.model.parameters import SEED_RIGID_LINKS

RECORD_RHO = 0.55
"""The AR(1) rho of the seed's residuals (summary noise_model/rho_of_lowest_aic: 0.55 in the default run)."""
RECORD_SIGMA = 0.023
"""The seed's typical calibrated frame error [J] (the mean of energy.csv's sigma_E)."""
RECORD_FRAMES = 622
"""Frames of the seed's record after the release (about 20.7 s)."""


def ar1_noise(n: int, rho: float, rng: np.random.Generator) -> np.ndarray:
    """A stationary AR(1) series of unit marginal variance."""
    e = rng.normal(0.0, math.sqrt(1.0 - rho * rho), n)
    x = np.empty(n)
    x[0] = rng.normal()
    for i in range(1, n):
        x[i] = rho * x[i - 1] + e[i]
    return x


def test_the_ar1_likelihood_is_the_gaussian_density_with_ar1_covariance():
    rng = np.random.default_rng(3)
    r, rho, s2 = ar1_noise(60, 0.4, rng) * 1.3, 0.4, 1.7
    cov = s2 * rho ** np.abs(np.subtract.outer(np.arange(60), np.arange(60)))
    assert noise.neg2_log_likelihood(r, rho, s2) == pytest.approx(-2.0 * multivariate_normal(cov=cov).logpdf(r))
    sigma = rng.uniform(0.01, 0.03, 60)  # the energies' density: the Jacobian of r = d / sigma
    direct = -2.0 * multivariate_normal(cov=cov * np.outer(sigma, sigma)).logpdf(r * sigma)
    assert noise.neg2_log_likelihood(r, rho, s2, sigma) == pytest.approx(direct)
    assert noise.whitened_chi2(r, 0.0) == pytest.approx(float(r @ r))  # rho = 0: plain chi2


def test_the_fitted_rho_recovers_an_ar1_process_within_its_error():
    rng = np.random.default_rng(11)
    n = 4000
    fit = noise.ar1_fit(2.0 * ar1_noise(n, 0.35, rng))
    assert abs(fit.rho - 0.35) < 3.0 * math.sqrt((1.0 - 0.35**2) / n)
    assert fit.s2 == pytest.approx(4.0, rel=0.1)
    assert max(abs(v) for v in noise.innovation_autocorrelation(2.0 * ar1_noise(n, 0.35, rng), 0.35)) < 3 / math.sqrt(n)


def test_aic_and_bic_follow_from_the_likelihood():
    rng = np.random.default_rng(5)
    base = ar1_noise(600, 0.5, rng)
    trend = np.linspace(-1.0, 1.0, 600)
    res = {"good": base, "misfit": base + 0.8 * trend}
    c = noise.ar1_criteria(res, {"good": 3, "misfit": 2})
    for m, k in (("good", 3), ("misfit", 2)):
        f = noise.ar1_fit(res[m])
        assert c[m]["neg2_log_likelihood"] == pytest.approx(f.neg2_log_l)
        assert c[m]["k"] == k + noise.NOISE_PARAMETERS
        assert c[m]["aic"] == pytest.approx(f.neg2_log_l + 2.0 * (k + 2))
        assert c[m]["bic"] == pytest.approx(f.neg2_log_l + (k + 2) * math.log(600 * (1 - c["good"]["rho"])
                                                                              / (1 + c["good"]["rho"])))
    assert c["good"]["delta_aic"] == 0.0 and c["misfit"]["delta_aic"] > 2.0  # the slow misfit costs likelihood
    assert noise.ties(c, "delta_aic") == ["good"]
    # at one rho, whitening shrinks a slow misfit's chi2 cost by about (1 + rho)/(1 - rho) = 3
    gain_white = float(res["misfit"] @ res["misfit"] - base @ base)
    gain_ar1 = noise.whitened_chi2(res["misfit"], 0.5) - noise.whitened_chi2(base, 0.5)
    assert gain_white / 4.0 < gain_ar1 < gain_white / 2.0


START = {"phi1_0": -0.34, "phi2_0": 0.89, "omega1_0": 3.97, "omega2_0": -6.31}
TRUE_MODEL, TRUE_THETA = "viscous", [1.7e-4]  # about the seed's fitted viscous damping (b_v, N.m.s/rad)
CANDIDATES = ("air", "drag", "viscous")  # amplitude laws p = 1.5, 0.5 and 1 (dE/dt ~ -E^p)


@pytest.fixture(scope="module")
def synthetic_problem() -> fitting.FitProblem:
    """The true model's energy from the component over the record plus AR(1) noise of the record's rho."""
    base = {**mechanisms.SIM_SETTINGS, **SEED_RIGID_LINKS, "l1": 0.2964, "l2": 0.1971, **START}
    offsets = np.arange(RECORD_FRAMES)
    problem = fitting.FitProblem(0.0, offsets, offsets * FRAME_INTERVAL, np.zeros(RECORD_FRAMES),
                                 np.full(RECORD_FRAMES, RECORD_SIGMA), base)  # fmt: skip
    e_true = np.asarray(problem.simulate(mechanisms.model_values(TRUE_MODEL, TRUE_THETA))["E_pendulum"])[offsets]
    energy = e_true + RECORD_SIGMA * ar1_noise(RECORD_FRAMES, RECORD_RHO, np.random.default_rng(2))
    return fitting.FitProblem(0.0, offsets, problem.t, energy, problem.sigma, base)


def test_fitting_one_half_and_predicting_the_other_recovers_the_true_mechanism(synthetic_problem):
    """Each candidate fitted to the whole record, then to each half, predicting the other (the project's fits, the
    component's runs): the true law ranks first or ties in both directions and over both, and the law furthest
    from it (air drag, p = 1.5 against 1) predicts worse than the tie allows."""
    fits = [fitting.fit_loss_model(m, synthetic_problem, max_nfev=12) for m in CANDIDATES]
    hfits = holdout.holdout_fits(synthetic_problem, fits, max_runs=12, max_workers=1)
    out = holdout.out_of_sample(synthetic_problem, hfits)
    for name, d in out["directions"].items():
        assert TRUE_MODEL in d["ranking"]["tie"], (name, d["ranking"])
        assert "air" not in d["ranking"]["tie"], (name, d["ranking"])
        s = d["scores"][TRUE_MODEL]
        assert abs(s["mean_residual_J"]) < 3.0 * s["mean_residual_stderr_J"]  # no bias beyond its AR(1) error
        assert s["theta"]["b_v"] == pytest.approx(TRUE_THETA[0], rel=0.3)
        assert abs(s["rho_training"] - RECORD_RHO) < 0.15  # the noise model sees the noise put in
    assert TRUE_MODEL in out["both_directions"]["tie"]
    assert out["both_directions"]["order"][-1] == "air"
    assert len(hfits) == 2 * len(CANDIDATES) and {h.half for h in hfits} == set(holdout.HALVES)
    # the held-out frames are the other half's: together the two directions cover every frame once
    n = [d["scores"][TRUE_MODEL]["n_frames"] for d in out["directions"].values()]
    assert sum(n) == RECORD_FRAMES


def test_the_half_problems_split_the_frames_and_keep_the_start(synthetic_problem):
    first, second = (holdout.half_problem(synthetic_problem, h) for h in holdout.HALVES)
    assert len(first.t) + len(second.t) == len(synthetic_problem.t) and first.t[-1] < second.t[0]
    assert first.base == second.base == synthetic_problem.base and first.t0 == second.t0 == 0.0
    assert second.duration == synthetic_problem.duration and first.duration < synthetic_problem.duration


def test_the_air_share_interval_follows_the_profile_and_admits_no_air_only_within_the_level():
    """air_share_intervals on a known profile: Delta = k^2 at air factor 1 + 0.1 k with the share 0.2 + 0.05 k gives
    the share's interval 0.1 to 0.3 (k = -+2); a model without air drag 3 behind adds share 0 to the union, one 5
    behind does not; a model whose own optimum is beyond the level has no interval."""
    from double_pendulum.analysis.losses.air_profile import AirPoint, air_share_intervals

    def fit(model: str, theta: list[float], chi2: float, share: float) -> fitting.ModelFit:
        return fitting.ModelFit(model, np.array(theta), chi2, 100, np.eye(len(theta)), np.zeros(100), 1.0, 1,
                                extra={"shares": {"air drag": share}})  # fmt: skip

    factor, best = 2.0, 50.0
    fits = [fit("air+drag", [1.0, 1e-3], best, 0.2), fit("air+viscous", [0.5, 1e-4], best + 2 * 4.5, 0.05)]
    ks = [-3.0, -2.0, -1.0, 1.0, 2.0, 3.0]
    items = [AirPoint("air+drag", 0, 1.0 + 0.1 * k, (1.0 + 0.1 * k, 1e-3)) for k in ks]
    results = [(best + factor * k * k, 0.2 + 0.05 * k) for k in ks]
    for no_air, union_low in ((3.0, 0.0), (5.0, 0.1)):
        rows = [{"model": f.model, "chi2": f.chi2, "converged": True} for f in fits]
        rows.append({"model": "viscous", "chi2": best + factor * no_air, "converged": True})
        out = air_share_intervals(fits, rows, factor, items, results)
        assert out["models"]["air+drag"]["share_interval"] == pytest.approx([0.1, 0.3])
        assert out["models"]["air+viscous"]["share_interval"] is None  # its optimum is 4.5 behind
        assert out["share_interval"] == pytest.approx([union_low, 0.3])


def test_the_ar1_refit_ends_at_the_likelihoods_maximum_and_finds_the_true_law(synthetic_problem):
    """Each candidate re-fitted under the AR(1) likelihood (:mod:`.ar1_refit`): its -2 ln L is never above the
    least-squares optimum's; moving any loss parameter 3 % either way from the re-fit (kappa and rho maximised
    again) does not lower it by more than the fit's tolerance; the true law keeps its damping (within 30 %) and
    ranks first under AIC, air drag (p = 1.5 against 1) outside the tie; the re-fit's rho is the noise's."""
    from double_pendulum.analysis.losses import ar1_refit

    fits = [fitting.fit_loss_model(m, synthetic_problem, max_nfev=12) for m in CANDIDATES]
    refits = ar1_refit.refit_models(fits, synthetic_problem, max_workers=1)
    for f in fits:
        rf = refits[f.model]
        assert rf.neg2_log_l <= rf.neg2_log_l_least_squares + 1e-9, f.model
        assert rf.neg2_log_l_least_squares == pytest.approx(noise.ar1_fit(f.residuals).neg2_log_l)
        for j in range(len(rf.theta)):
            for step in (0.97, 1.03):
                theta = rf.theta.copy()
                theta[j] *= step
                e = np.asarray(synthetic_problem.simulate(mechanisms.model_values(f.model, theta))["E_pendulum"])
                rho = rf.rho
                for _ in range(3):  # kappa at rho, rho at kappa: the alternation's own steps
                    r, _ = ar1_refit.gls_residuals(synthetic_problem, e[synthetic_problem.offsets], rho)
                    value, rho = ar1_refit.neg2_log_l(r)
                assert value > rf.neg2_log_l - fitting.CHI2_TOLERANCE, (f.model, j, step, value, rf.neg2_log_l)
    assert refits[TRUE_MODEL].theta[0] == pytest.approx(TRUE_THETA[0], rel=0.3)
    assert abs(refits[TRUE_MODEL].rho - RECORD_RHO) < 0.1
    rows = [{"model": f.model, "k": f.k, "converged": True, "shares": {}, "delta_aic": 0.0, "delta_bic": 0.0}
            for f in fits]
    summary = noise.noise_model_summary(rows, {f.model: f.residuals for f in fits}, synthetic_problem.sigma, 1.0,
                                        refits)  # fmt: skip
    assert summary["refitted"] and summary["ties"]["aic_ar1"][0] == TRUE_MODEL
    assert "air" not in summary["ties"]["aic_ar1"]
    assert all(c["refit"]["gain_neg2_log_likelihood"] >= 0.0 for c in summary["criteria"].values())


def test_the_gls_calibration_is_the_weighted_one_for_independent_frames(synthetic_problem):
    """At rho = 0 the generalised least-squares kappa and residuals are the fit's weighted least-squares ones."""
    from double_pendulum.analysis.losses import ar1_refit

    e = synthetic_problem.energy * 1.02 + 0.003
    r, kappa = ar1_refit.gls_residuals(synthetic_problem, e, 0.0)
    r_w, kappa_w = synthetic_problem.scaled_residuals(e)
    assert kappa == pytest.approx(kappa_w) and np.allclose(r, r_w)
