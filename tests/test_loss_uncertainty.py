"""The horizon with the losses' uncertainty (``analysis.prediction.loss_uncertainty``): the ensemble over the
losses' and the start's covariance and the sensitivity to the damping level, on a model whose horizon is known."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from double_pendulum.analysis.losses import fitting
from double_pendulum.analysis.prediction import loss_uncertainty as lu
from double_pendulum.analysis.track.start_state import StartStateFit

SPAN = 20.0
T = np.linspace(0.0, SPAN, 601)
TAU_HAT = 1.0e-3
"""The fitted drag torque [N m] of the toy model below."""


def toy_prediction(tau_b: float, state: np.ndarray) -> SimpleNamespace:
    """A prediction whose lower-bob error grows linearly at a rate [m/s] that rises monotonically with the damping,
    as the seed's horizons fall with it: 5 mm/s at the fitted torque, e times that per 1 % more torque and per
    0.1 rad more start angle. Its 5 cm horizon is 0.05 / rate: 10 s at the fit, 3.7 s at 1 % more damping and
    27 s (censored in the 20 s record) at 1 % less."""
    rate = 5e-3 * np.exp((tau_b / TAU_HAT - 1.0) / 0.01 + (state[0] - 0.5) / 0.1)
    return SimpleNamespace(t=T, e2=rate * T)


def run_member(values, state, geometry):
    return toy_prediction(values["tau_b1"], np.asarray(state))


def drag_fit(factor_cov: float) -> tuple[fitting.ModelFit, float]:
    """A fit of the drag torque alone at TAU_HAT with relative standard error 1 % times sqrt(factor_cov)."""
    ref = fitting.parameters_of("drag")[0].ref
    jac = np.array([[ref / (0.01 * TAU_HAT)]])  # cov = factor ref^2 / J^2 = factor (0.01 tau)^2
    return fitting.ModelFit("drag", np.array([TAU_HAT]), 100.0, 100, jac, np.zeros(1), 1.0, 1), factor_cov


def start(cov_scale: float) -> StartStateFit:
    state = np.array([0.5, 0.2, 0.0, 0.0])
    cov = cov_scale * np.diag([1e-4, 1e-4, 1e-3, 1e-3])
    return StartStateFit(0.8, state, np.sqrt(np.diag(cov)), cov, 1.0, 10, 10, 1e-3, 1)


def ensemble(width: float, loss_factor: float = 1.0, start_scale: float = 1.0, size: int = 24) -> dict:
    fit, factor = drag_fit(loss_factor)
    return lu.horizon_ensemble(run_member, "drag", fit, factor, start(start_scale), SPAN, size, width=width)


def test_with_zero_covariance_every_member_is_the_point_horizon():
    point = lu._horizons(toy_prediction(TAU_HAT, start(0.0).state), SPAN)
    e = ensemble(1.0, loss_factor=0.0, start_scale=0.0, size=5)
    assert e["members_smoothed_5cm_s"] == [point[0]] * 5
    assert e["smoothed_5cm"]["median_s"] == point[0] == pytest.approx(10.0, abs=T[1])
    assert e["smoothed_5cm"]["range_16_84_s"] == [point[0], point[0]] and e["smoothed_5cm"]["censored_fraction"] == 0


def test_a_wider_covariance_never_narrows_the_range():
    """A horizon monotone in the damping and the start (the members keep their order), censored at the record's
    end: the 16-84 % range only widens as the draws widen. 12 members an ensemble (the ordering holds for any
    number; each member's horizon costs a moving median over the 601 samples): the range grows from 4.3 s at
    width 0.25 to 19.5 s at width 4 (24 members: 5.3 s to 19.9 s), well beyond the factor 2 asserted."""
    widths = []
    for width in (0.25, 0.5, 1.0, 2.0, 4.0):
        lo, hi = ensemble(width, size=12)["smoothed_5cm"]["range_16_84_s"]
        widths.append(hi - lo)
    assert all(b >= a - 1e-12 for a, b in zip(widths, widths[1:]))
    assert widths[-1] > 2.0 * widths[0]
    e = ensemble(4.0, size=12)
    assert e["smoothed_5cm"]["top_censored"] and e["smoothed_5cm"]["range_16_84_s"][1] == SPAN


def test_the_ensemble_draws_follow_the_fitted_covariance():
    fit, factor = drag_fit(1.0)
    assert fit.stderr(factor)[0] == pytest.approx(0.01 * TAU_HAT)
    z = np.random.default_rng(1).standard_normal((20000, 1))
    draws = lu.correlated_draws(fit.theta, fit.cov(factor), z)
    assert np.std(draws) == pytest.approx(0.01 * TAU_HAT, rel=0.03)
    assert np.allclose(lu.correlated_draws(fit.theta, np.zeros((1, 1)), z), TAU_HAT)


def test_damping_sensitivity_is_the_central_difference_of_the_horizon():
    def run_losses(values):
        return toy_prediction(values["tau_b1"], np.array([0.5]))

    central = run_losses(lu.loss_values("drag", [TAU_HAT]))
    d = lu.damping_sensitivity(run_losses, "drag", [TAU_HAT], SPAN, central)
    more = 0.05 / (5e-3 * np.e)  # 3.7 s; 1 % less: 27 s, beyond the 20 s record
    assert d["levels"]["more_damping"]["horizon_s"] == pytest.approx(more, abs=T[1])
    assert d["levels"]["less_damping"]["censored"] and not d["levels"]["fitted"]["censored"]
    assert d["slope_is_lower_bound"]  # the censored end counts as 20 s: the true slope is steeper
    assert d["smoothed_s_per_percent"] == pytest.approx((more - SPAN) / 2.0, abs=T[1])
    assert lu.loss_values("drag", [-1.0])["tau_b1"] == 0.0  # a drawn negative loss is clipped
