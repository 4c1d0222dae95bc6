"""Loss identification: known losses recovered from a synthetic camera track; the real-data claim.

The synthetic track is made by the FMU's own component (rigid links of the seed, air drag with a
factor, bearing drag torque), sampled at the camera's 29.97 fps with 1.5 mm white position noise on
each bob and a pivot offset, and analysed exactly like the seed's track (reconstruction with the
package's energy function, calibrated errors, start state from the first frames).

The track lasts :data:`SECONDS` = 20 s, about the seed's 20.7 s after the release: over it the air+drag fit
converges from the references in 6 runs and identifies both losses (noise seeds 1, 2, 3 and 7: air factor
2.05 to 2.56 +- 0.71 to 0.78, drag torque 0.86 to 0.97 mN.m +- 22 % to 27 %, each within 0.8 standard errors
of the truth). Over 12 s the two losses trade off along a valley: with seed 7 the fit ran out of its 30 runs
near the air factor's lower bound, the drag torque's error 47 % of its value (just below the 50 % asserted),
and seeds 1 to 3 left it at 60 % to far above 100 %, for three times the CPU.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from conftest import quick_scenario

from double_pendulum.analysis.losses import claims as loss_claims
from double_pendulum.analysis.losses import comparison, fitting, holdout, identification, mechanisms
from double_pendulum.analysis.track import measurement as ms
from double_pendulum.fmu.masters.simulate import simulate
from double_pendulum.model.parameters import SEED_RIGID_LINKS

TRUE = {"air_factor": 2.0, "tau_b": 1.0e-3}
PIVOT = (0.0035, -0.0029)  # the pivot in the synthetic track's coordinates [m]
NOISE_M = 1.5e-3  # position noise of each bob [m], like the seed's track
SECONDS = 20.0


def _synthetic_track(seed: int = 7) -> ms.Track:
    values = {
        **mechanisms.SIM_SETTINGS, **SEED_RIGID_LINKS, "l1": 0.2964, "l2": 0.1971,
        "phi1_0": -0.34, "phi2_0": 0.89, "omega1_0": 3.97, "omega2_0": -6.31,
        **mechanisms.model_values("air+drag", [TRUE["air_factor"], TRUE["tau_b"]]),
    }  # fmt: skip
    r = simulate(values, stop_time=SECONDS, output_interval=ms.FRAME_INTERVAL, outputs=("x1", "y1", "x2", "y2"))
    rng = np.random.default_rng(seed)
    n = len(r)

    def noisy(name: str, offset: float) -> np.ndarray:
        return np.asarray(r[name]) + offset + rng.normal(0.0, NOISE_M, n)

    x1, y1, x2, y2 = noisy("x1", PIVOT[0]), noisy("y1", PIVOT[1]), noisy("x2", PIVOT[0]), noisy("y2", PIVOT[1])
    frame = np.arange(n)
    return ms.Track(frame, frame / ms.FPS, x1, y1, x2, y2, ms.flag_bad_frames(x1, y1, x2, y2))


@pytest.fixture(scope="module")
def synthetic_problem() -> fitting.FitProblem:
    rec = ms.reconstruct(_synthetic_track(), rods=SEED_RIGID_LINKS)
    # The synthetic track starts in free motion: begin at the first frame with a defined energy
    # (the seed's hand release ends later, where every derivative stencil fits).
    rec = dataclasses.replace(rec, release_frame=max(rec.release_frame, int(np.argmax(rec.energy_valid))))
    return fitting.problem_from_track(rec, identification.measured(rec))


@pytest.fixture(scope="module")
def synthetic_fit(synthetic_problem) -> tuple[fitting.ModelFit, float]:
    fit = fitting.fit_loss_model("air+drag", synthetic_problem)
    return fit, comparison.common_factor(synthetic_problem)


def test_identification_recovers_the_true_losses_within_its_stated_uncertainty(synthetic_fit):
    fit, factor = synthetic_fit
    err = fit.stderr(factor)
    for (name, true), value, sigma in zip(TRUE.items(), fit.theta, err):
        assert abs(value - true) < 3.0 * sigma, f"{name}: {value:.4g} +- {sigma:.2g}, true {true:.4g}"
    assert err[1] / fit.theta[1] < 0.5  # the drag torque is identified, not just compatible
    assert fit.kappa == pytest.approx(1.0, abs=0.02)  # camera energy and model energy agree
    assert fit.chi2 / (fit.n - fit.k) < 2.0


def test_shares_of_the_synthetic_fit_sum_to_one(synthetic_fit):
    fit, _ = synthetic_fit
    assert sum(fit.extra["shares"].values()) == pytest.approx(1.0, abs=1e-12)


def test_model_values_and_parameters_line_up():
    assert [p.name for p in mechanisms.parameters_of("air+drag2+suspension")] == ["air_factor", "tau_b1", "tau_b2",
                                                                          "c_suspension"]  # fmt: skip
    v = mechanisms.model_values("air+viscous", [1.0, 2e-4])
    assert v["rho_air"] == pytest.approx(1.2) and v["b_v1"] == v["b_v2"] == 2e-4 and v["c_R1"] == 0.0


def test_profile_interval_interpolates_the_crossings():
    lo, hi = comparison._profile_interval([1.0, 2.0, 3.0, 4.0, 5.0], [4.0, 0.5, 0.0, 0.5, 4.0])
    assert lo == pytest.approx(2.0 - 0.5 / 3.5) and hi == pytest.approx(4.0 + 0.5 / 3.5)


def test_top_model_on_the_real_data_quick(quick_results):
    """Quick settings (air+drag alone, no profiles): the shares sum to 1; the suspension question is not
    answered without a suspension model."""
    _, s = quick_scenario(quick_results, "loss_identification")
    assert s["top_model"] == "air+drag" and s["models_fitted"] == list(mechanisms.QUICK_MODELS)
    assert sum(s["top_model_shares"].values()) == pytest.approx(1.0, abs=1e-12)
    assert all(0.0 <= v <= 1.0 for v in s["top_model_shares"].values())
    # the fitted torque against the seed's rolling friction c_R r_b M g at the pivot
    seed = s["drag_torque_against_seed_rolling_friction"]
    assert seed["fitted_over_seed"][0] == pytest.approx(s["parameters"]["tau_b"]["value"] / seed["torque_N_m"][0])
    assert seed["fitted_over_seed"][0] == pytest.approx(2.0 * seed["fitted_over_seed"][1])  # c_R 0.5e-3 and 1e-3
    assert s["suspension_verdict"] is None and s["answer"].startswith("Not tested")
    assert s["profile_likelihood"] == {}
    for key in ("b_measured_per_s", "b_sim_per_s", "p_measured", "p_measured_stderr", "p_sim"):
        assert math.isfinite(s[key])
    # the AR(1) criteria of the one model, and the half-record test as a smoke run (air+drag both ways)
    crit = s["noise_model"]["criteria"]["air+drag"]
    assert 0.0 < crit["rho"] < 1.0 and crit["k"] == 3 + 2 and s["noise_model"]["ties"]["bic_ar1"] == ["air+drag"]
    assert s["models"][0]["ar1"]["aic"] == pytest.approx(crit["neg2_log_likelihood"] + 2 * crit["k"])
    oos = s["out_of_sample"]
    assert set(oos["directions"]) == {"first_predicts_second", "second_predicts_first"}
    assert all(math.isfinite(d["scores"]["air+drag"]["ar1_chi2_per_frame"]) for d in oos["directions"].values())


def test_a_fit_above_its_nested_model_counts_as_not_converged():
    def fake(model: str, chi2: float) -> fitting.ModelFit:
        n = len(mechanisms.parameters_of(model))
        return fitting.ModelFit(model, np.ones(n), chi2, 100, np.eye(100)[:, :n], np.zeros(100), 1.0, 1)

    fits = [fake("air+drag", 100.0), fake("air+drag+viscous", 120.0), fake("air", 130.0)]
    rows = comparison.comparison_rows(fits, 1.0)
    assert [r["model"] for r in rows] == ["air+drag", "air", "air+drag+viscous"]
    assert not rows[-1]["converged"] and rows[-1]["akaike_weight"] == 0.0
    assert rows[-1]["not_ranked_because"].startswith("the fit stalled")
    assert "not_ranked_because" not in rows[0]
    assert "c_suspension -> infinity" in comparison.not_ranked_because("air+suspension")



def test_a_nested_model_warm_started_from_its_parent_ends_no_worse(synthetic_problem, synthetic_fit):
    """air+drag+bearing from the air+drag optimum: the added friction starts with a negligible loss and
    Gauss-Newton only accepts steps that lower chi2, so the larger model cannot end above its parent
    (it would then count as not converged and drop out of the comparison)."""
    parent, _ = synthetic_fit
    ((start,),) = [item.starts for item in fitting.fit_items_of("air+drag+bearing", [parent])]
    assert start[:2] == pytest.approx(tuple(parent.theta))
    assert start[2] == pytest.approx(fitting.WARM_START_FRACTION * mechanisms.MECHANISMS["bearing"].parameters[0].ref)
    fit = fitting.fit_loss_model("air+drag+bearing", synthetic_problem, start=start, max_nfev=8)
    assert fit.chi2 <= parent.chi2 * (1.0 + 1e-3)
    assert comparison.converged(fit, [parent, fit])


def test_models_within_two_aic_are_reported_with_weights_and_the_range_of_the_air_share():
    rows = [
        {"model": "air+drag", "delta_aic": 0.0, "akaike_weight": 0.5, "converged": True,
         "shares": {"air drag": 0.4, "bearing drag torque": 0.6}, "b_sim_per_s": -0.0253},
        {"model": "air+viscous", "delta_aic": 1.2, "akaike_weight": 0.3, "converged": True,
         "shares": {"air drag": 0.1, "viscous joint damping": 0.9}, "b_sim_per_s": -0.0256},
        {"model": "air", "delta_aic": 23.5, "akaike_weight": 0.0, "converged": True, "shares": {"air drag": 1.0},
         "b_sim_per_s": -0.0252},
        {"model": "air+suspension", "delta_aic": 0.5, "akaike_weight": 0.0, "converged": False,
         "shares": {"damped suspension": 1.0}},
    ]
    out = loss_claims.supported_models(rows)
    assert list(out["models"]) == ["air+drag", "air+viscous"]  # the top model too: no winner
    assert out["air_share_range"] == [0.1, 0.4]
    assert ("air drag + viscous joint damping (delta AIC 1.20, weight 0.30: air drag 10%, viscous joint damping 90%)"
            in out["text"])
    assert "from 10% to 40%" in out["text"]
    assert loss_claims.b_sim_range(rows) == [-0.0256, -0.0252]  # air alone reproduces b as well
    alone = loss_claims.supported_models([{**rows[2], "delta_aic": 0.0}])
    assert alone["air_share_range"] == [1.0, 1.0]
    assert alone["text"].startswith("One model lies within delta AIC 2 of the lowest, the lowest itself: air drag")
    assert "It puts air drag's share of the loss at 100%" in alone["text"] and "ranges" not in alone["text"]


def test_the_suspension_joins_a_fitted_model_at_each_damping_of_its_scan():
    parent = fitting.ModelFit("air", np.array([2.5]), 1.0, 100, np.zeros((100, 1)), np.zeros(100), 1.0, 1)
    (item,) = fitting.fit_items_of("air+suspension", [parent])
    assert item.starts == tuple((2.5, c) for c in mechanisms.MECHANISMS["suspension"].parameters[0].warm_scan)
    assert fitting.fit_items_of("air", [parent]) == [fitting.FitItem("air")]


def test_drag_per_joint_nests_the_common_drag_torque_and_starts_at_its_optimum():
    """air+drag2 generalises air+drag (tau_b1 = tau_b2 = tau_b): it is fitted a round later, starts at the
    air+drag optimum with the short run budget, and counts as not converged if it ends above it."""
    assert mechanisms.contains("air+drag2", "air+drag") and mechanisms.contains("air+drag2", "air")
    assert not mechanisms.contains("air+drag", "air+drag2") and not mechanisms.contains("air+drag", "air+drag")
    assert not mechanisms.contains("air+bearing", "air+drag")
    assert mechanisms.model_rank("air+drag2") > mechanisms.model_rank("air+drag") > mechanisms.model_rank("air")
    parent = fitting.ModelFit("air+drag", np.array([2.2, 1.1e-3]), 600.0, 100, np.zeros((100, 2)), np.zeros(100),
                              1.0, 1)
    air = fitting.ModelFit("air", np.array([6.0]), 640.0, 100, np.zeros((100, 1)), np.zeros(100), 1.0, 1)
    (item,) = fitting.fit_items_of("air+drag2", [air, parent])  # air is nested in air+drag: no start of its own
    assert item.starts == ((2.2, 1.1e-3, 1.1e-3),) and item.max_nfev == fitting.SHORT_RUN_BUDGET
    assert fitting.fit_items_of("air+drag2", [air, parent], short=False)[0].max_nfev == 30
    assert fitting.fit_items_of("air+bearing", [air, parent])[0].max_nfev == 30  # a rival, not a generalisation
    worse = fitting.ModelFit("air+drag2", np.ones(3), 601.0, 100, np.zeros((100, 3)), np.zeros(100), 1.0, 1)
    assert not comparison.converged(worse, [parent, worse])


def test_a_pair_of_losses_starts_from_each_loss_alone_and_keeps_the_fit_that_ends_lowest(monkeypatch):
    """air+viscous nests air drag alone and viscous damping alone: one start from each optimum (the better parent
    first), and :func:`fitting.fit_models` keeps whichever ends lower, not the one from the better parent."""
    def fake(model: str, theta: list[float], chi2: float) -> fitting.ModelFit:
        return fitting.ModelFit(model, np.array(theta), chi2, 100, np.zeros((100, len(theta))), np.zeros(100), 1.0, 1)

    air, viscous = fake("air", [6.0], 640.0), fake("viscous", [1.7e-4], 610.6)
    items = fitting.fit_items_of("air+viscous", [air, viscous])
    w = fitting.WARM_START_FRACTION
    assert [i.starts for i in items] == [((w * 1.5, 1.7e-4),), ((6.0, w * 1e-4),)]

    def fake_fit_item(item: fitting.FitItem, problem: object) -> fitting.ModelFit:
        if item.model != "air+viscous":
            return {"air": air, "viscous": viscous}[item.model]
        from_air = item.starts[0][0] == 6.0
        return fake(item.model, list(item.starts[0]), 610.4 if from_air else 610.6)  # the worse parent ends lower

    monkeypatch.setattr(fitting, "fit_item", fake_fit_item)
    fits, _ = fitting.fit_models(("air", "viscous", "air+viscous"), object(), max_workers=1)
    assert [f.model for f in fits] == ["air", "viscous", "air+viscous"]
    assert fits[-1].chi2 == 610.4 and fits[-1].theta[0] == 6.0


def test_the_default_models_leave_the_three_mechanism_ones_and_air_drag2_to_the_thorough_run():
    assert set(mechanisms.FULL_MODELS) < set(mechanisms.THOROUGH_MODELS)
    extra = set(mechanisms.THOROUGH_MODELS) - set(mechanisms.FULL_MODELS)
    assert all(len(m.split("+")) == 3 for m in extra - {"air+drag2"}) and "air+drag2" in extra
    # the default identification takes two rounds: single mechanisms, then pairs (no sequential third round)
    assert {mechanisms.model_rank(m) for m in mechanisms.FULL_MODELS} == {1, 2}
    assert "air+drag" in mechanisms.FULL_MODELS and mechanisms.QUICK_MODELS == ("air+drag",)


def test_a_fit_reuses_the_run_at_its_optimum(synthetic_problem, synthetic_fit):
    """The shares come from the last accepted Gauss-Newton run: no run is repeated for them, and they are
    the ones a fresh run at the optimum gives."""
    fit, _ = synthetic_fit
    works = sorted({m.work for m in mechanisms.mechanisms_of("air+drag")})
    fresh = synthetic_problem.simulate(mechanisms.model_values("air+drag", fit.theta), outputs=("E_pendulum", *works))
    assert fit.extra["shares"] == mechanisms.shares(fresh, "air+drag")
    r, _ = synthetic_problem.scaled_residuals(np.asarray(fresh["E_pendulum"])[synthetic_problem.offsets])
    assert float(r @ r) == fit.chi2


def test_gauss_newton_says_why_it_stopped():
    a = np.array([[1.0, 0.5], [0.2, 2.0], [1.0, 1.0]])
    target = a @ np.array([3.0, -1.0])

    def residuals(x: np.ndarray) -> np.ndarray:
        return a @ x - target

    x, _, stop = fitting.gauss_newton(residuals, np.array([1.0, 1.0]))
    assert stop == "converged" and x == pytest.approx([3.0, -1.0], abs=1e-4)
    assert fitting.gauss_newton(residuals, np.array([1.0, 1.0]), max_runs=2)[2] == "run limit"


@pytest.mark.parametrize("quick", [False, True])
def test_identified_fit_fits_a_model_as_the_identification_of_its_mode_does(monkeypatch, quick):
    """``measured_vs_sim`` takes its losses from :func:`fitting.identified_fit`: the fit items (model, start, run
    budget) it fits must be the identification's own, so the cached fits of one scenario serve the other."""
    items: list[fitting.FitItem] = []

    def fake_fit_item(item: fitting.FitItem, problem: object) -> fitting.ModelFit:
        items.append(item)
        theta = np.array(item.starts[0] if item.starts else [p.ref for p in mechanisms.parameters_of(item.model)])
        chi2 = 1000.0 / (1 + len(item.model)) + 7.0 * len(items)  # differing chi2: the parent choice matters
        return fitting.ModelFit(item.model, 1.1 * theta, chi2, 100, np.zeros((100, len(theta))), np.zeros(100), 1.0, 1)

    monkeypatch.setattr(fitting, "fit_item", fake_fit_item)
    models = mechanisms.QUICK_MODELS if quick else mechanisms.FULL_MODELS
    problem = object()  # never simulated: the fake fits only record their items
    # the identification's rounds (identify_losses: short=True, the mode's run budget)
    fitting.fit_models(models, problem, max_workers=1, max_runs=fitting.run_budget(quick))
    identification = [i for i in items if i.model == "air+drag"]
    items.clear()
    fit = fitting.identified_fit("air+drag", problem, quick=quick)
    assert fit.model == "air+drag"
    assert {i.model for i in items} == ({"air+drag"} if quick else {"air", "drag", "air+drag"})
    mine = [i for i in items if i.model == "air+drag"]
    assert mine == identification and len(mine) == (1 if quick else 2)  # default: from air alone and drag alone
    assert all(bool(i.starts) != quick for i in mine)  # default: warm-started from a one-mechanism fit
    assert all(i.max_nfev == (mechanisms.QUICK_RUN_BUDGET if quick else 30) for i in mine)  # quick: one step
    with pytest.raises(ValueError):
        fitting.identified_fit("air+drag+bearing", problem)


def _fake_fit(model: str, chi2: float, theta: list[float] | None = None) -> fitting.ModelFit:
    n = len(mechanisms.parameters_of(model))
    jac = np.eye(100)[:, :n] + 0.01  # a well-conditioned Jacobian: finite errors
    return fitting.ModelFit(model, np.ones(n) if theta is None else np.array(theta), chi2, 100, jac, np.zeros(100),
                            1.0, 1)


def test_a_supported_model_without_air_drag_sets_the_lower_end_of_the_air_share_to_zero():
    rows = [
        {"model": "viscous", "delta_aic": 0.0, "akaike_weight": 0.5, "converged": True,
         "shares": {"viscous joint damping": 1.0}},
        {"model": "air+drag", "delta_aic": 0.7, "akaike_weight": 0.4, "converged": True,
         "shares": {"air drag": 0.37, "bearing drag torque": 0.63}},
        {"model": "air+viscous", "delta_aic": 1.9, "akaike_weight": 0.1, "converged": True, "reduces_to": "viscous",
         "shares": {"air drag": 0.0, "viscous joint damping": 1.0}},
    ]
    out = loss_claims.supported_models(rows)
    assert out["air_share_range"] == [0.0, 0.37]
    assert list(out["models"]) == ["viscous", "air+drag"] and out["reduced"] == {"air+viscous": "viscous"}
    assert "viscous joint damping alone (delta AIC 0.00" in out["text"] and "no candidate of its own" in out["text"]


def test_a_model_that_fits_no_better_than_one_nested_in_it_reduces_to_that_model():
    fits = [_fake_fit("viscous", 610.60), _fake_fit("air", 641.0), _fake_fit("air+viscous", 610.61),
            _fake_fit("air+drag", 608.9), _fake_fit("drag", 619.0)]
    rows = {r["model"]: r for r in comparison.comparison_rows(fits, 1.28)}
    assert rows["air+viscous"]["reduces_to"] == "viscous"
    assert rows["air+drag"]["reduces_to"] is None  # it gains 10 in chi2 over drag alone
    assert rows["air+drag"]["model_in_words"] == "air drag + bearing drag torque"


def test_the_suspension_at_its_nested_limit_is_reported_as_a_bound_not_a_fit():
    fits = [_fake_fit("air", 641.06), _fake_fit("air+drag", 608.9), _fake_fit("drag", 619.0),
            _fake_fit("air+suspension", 833.6, [0.29, 112.0])]
    factor = 1.28
    rows = {r["model"]: r for r in comparison.comparison_rows(fits, factor)}
    susp = rows["air+suspension"]
    assert not susp["converged"] and susp["best_is_limit_model"] == "air"
    # at best it fits as the rigid pivot (air alone) plus one fitted number: 2 more in AIC
    assert susp["delta_aic_at_best"] == pytest.approx(rows["air"]["delta_aic"] + 2.0)
    assert susp["delta_aic_at_best"] < susp["delta_aic"]  # where the fit stopped is no bound
    assert all(p["stderr"] is None for p in susp["parameters"].values())  # no errors at a point that is no optimum
    bound = loss_claims.suspension_bound(list(rows.values()))
    assert bound["delta_aic_at_best"] == susp["delta_aic_at_best"] and bound["stopped_at"]["c_suspension"] == 112.0
    assert comparison.limit_model("air+drag") is None and comparison.limit_model("air+drag+suspension") == "air+drag"


def test_the_suspension_verdict_states_the_k_and_m_s_it_holds_at_and_what_would_change_it():
    """No bare yes/no: the verdict names the assumed k and M_s and the record, and what could change it."""
    fits = [_fake_fit("air", 641.06), _fake_fit("air+drag", 608.9), _fake_fit("drag", 619.0),
            _fake_fit("air+suspension", 833.6, [0.29, 112.0])]
    rows = comparison.comparison_rows(fits, 1.28)
    answer = identification.suspension_answer(rows)
    v = answer["suspension_verdict"]
    assert "suspension_dominates" not in answer
    assert v["verdict"] == "not the main loss" and v["top_model"] == "air+drag"
    assert v["holds_at"]["k_N_per_m"] == mechanisms.SUSPENSION_K and v["holds_at"]["M_s_kg"] == mechanisms.SUSPENSION_M
    assert v["delta_aic_at_best_of_air_and_suspension"] == pytest.approx(
        next(r for r in rows if r["model"] == "air+suspension")["delta_aic_at_best"])
    assert any("stiffness k" in w for w in v["would_change_it"]) and any("c / k^2" in w for w in v["would_change_it"])
    text = answer["answer"]
    assert text.startswith("Not the main loss at the assumed k = 20000 N/m and M_s = 2 kg")
    assert "What would change it" in text and "reject" not in text and not text.startswith("No:")
    # a top model that loses most in the suspension: "main loss", still at these k and M_s only
    top = dict(rows[0], model="air+suspension", shares={mechanisms.MECHANISMS["suspension"].label: 0.9})
    v = identification.suspension_verdict([top, *rows[1:]])
    assert v["verdict"] == "main loss" and v["suspension_share_in_top_model"] == 0.9
    assert identification.suspension_verdict([r for r in rows if r["model"] != "air+suspension"]) is None


def test_a_larger_correlation_factor_lets_models_with_fewer_numbers_join_the_tie():
    rows = [{"model": m, "chi2": chi2, "k": k, "converged": True}
            for m, chi2, k in (("air+drag", 608.9, 3), ("drag", 619.0, 2), ("air", 641.1, 2))]
    joins = loss_claims.supported_from_factor(rows, 1.28)
    assert set(joins) == {"drag", "air"}  # air+drag is in the tie at F = 1.28
    # drag alone: (619.0 - 608.9) / F - 2 < 2 from F = 10.1 / 4 on
    assert joins["drag"] == pytest.approx(10.1 / 4.0, rel=0.01) and joins["air"] is None  # air needs F > 8


def test_two_parameters_that_trade_off_are_not_identified_each():
    fit = _fake_fit("air+drag", 608.9, [2.2, 1.1e-3])
    jac = np.column_stack([np.linspace(0, 1, 100), np.linspace(0, 1, 100) + 1e-3 * np.sin(np.arange(100))])
    fit = dataclasses.replace(fit, jac=jac)
    ident = comparison.identifiability(fit, 1.0)
    assert ident["strongly_correlated"]["air_factor"] == ["tau_b"]
    assert ident["identified"] == {"air_factor": False, "tau_b": False}


def test_a_wider_friction_regularisation_moves_the_motion_more(synthetic_problem, synthetic_fit):
    """Over the record's first half (9.9 s; four runs at rtol 1e-10, half the CPU of the whole record): the largest
    angle difference to the near-sign function grows about a hundredfold per tenfold width (3.9e-8, 3.5e-6 and
    3.9e-4 rad at 1e-3, 1e-2 and 1e-1 rad/s), so the 1e-5 rad line lies far from the narrowest and the widest
    width (over the whole 20 s: 2.0e-7 and 1.4e-3 rad)."""
    fit, _ = synthetic_fit
    effect = comparison.regularisation_effect(holdout.half_problem(synthetic_problem, "first"), "air+drag", fit.theta)
    rows = effect["by_omega_reg_rad_per_s"]
    widths = [f"{w:g}" for w in sorted(comparison.REGULARISATION_WIDTHS)]  # 1e-3, 1e-2, 1e-1 rad/s
    angles = [rows[w]["max_angle_difference_rad"] for w in widths]
    assert angles == sorted(angles) and angles[0] < 1e-5 < angles[-1]
    assert all(rows[w]["joint_work_relative_change"] < 0 for w in widths)  # a soft sign function loses less


def test_gauss_newton_with_every_parameter_held_evaluates_once():
    """A one-parameter model's profile point holds its only parameter: nothing to fit, one run (the thorough
    run's profiles stopped with numpy's "need at least one array to concatenate" there)."""
    calls = []

    def residuals(x):
        calls.append(x)
        return np.array([1.0, -2.0, 0.5])

    x, jac, stop = fitting.gauss_newton(residuals, np.array([]))
    assert (len(x), jac.shape, stop, len(calls)) == (0, (3, 0), "converged", 1)
