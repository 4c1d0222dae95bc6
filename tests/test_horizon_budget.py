"""The horizon's distribution over every uncertain input (:mod:`double_pendulum.analysis.prediction.horizon_budget`):
the draws, the interval, and that widening one input's covariance widens the horizon's interval.

The FMU's ensemble runs a 20 s prediction per member; here a member's error grows as the phase drift of a swing
whose frequency is off by a model error plus the drawn inputs' share (e = L |d omega| t, the lower bob's distance
for a small phase error), so the horizon is the first crossing of 5 cm, through the same draws, horizon and interval
code as the FMU's ensemble."""

from __future__ import annotations

import numpy as np
import pytest

from double_pendulum.analysis.prediction.comparison import horizon
from double_pendulum.analysis.prediction.horizon_budget import (
    Block,
    block_draws,
    horizon_interval,
    monte_carlo,
    profile_minimum,
)

SPAN_S = 20.0
T = np.arange(0.0, SPAN_S + 1e-9, 1 / 30)
L2 = 0.2
"""Length [m] of the lower rod of the synthetic drift."""
MODEL_ERROR = 0.02
"""The main run's frequency error [rad/s]: its horizon 0.05 / (L2 * 0.02) = 12.5 s."""
BLOCKS = {
    "start and geometry": Block(("a", "b"), np.zeros(2), np.array([[1e-6, 0.5e-6], [0.5e-6, 0.75e-6]])),
    "losses": Block(("c",), np.zeros(1), np.array([[2.25e-6]])),
    "l1": Block(("l1",), np.array([0.3]), np.array([[0.25e-8]])),
}


def _member(x) -> float:
    """The horizon [s] of a drift with the frequency error of the model plus the member's inputs."""
    d_omega = MODEL_ERROR + x["start and geometry"].sum() + x["losses"][0] + 30.0 * (x["l1"][0] - 0.3)
    h = horizon(T, L2 * abs(d_omega) * T, 0.05)
    return SPAN_S if h is None else h


def test_the_interval_of_known_horizons_and_censored_ones():
    h = np.linspace(1.0, 30.0, 1001)  # a third beyond the 20 s record: counted as its end
    out = horizon_interval(h, SPAN_S)
    assert out["median_s"] == pytest.approx(15.5) and out["range_16_84_s"][0] == pytest.approx(1 + 0.16 * 29)
    assert out["range_16_84_s"][1] == SPAN_S and out["top_censored"]
    assert out["censored_fraction"] == pytest.approx(10 / 29, abs=2e-3)
    assert out["width_16_84_s"] == pytest.approx(SPAN_S - 1 - 0.16 * 29)


def test_draws_follow_their_covariance_and_widening_moves_one_block_only():
    draws = block_draws(BLOCKS, 20000, seed=1)
    assert np.cov(draws["start and geometry"].T) == pytest.approx(BLOCKS["start and geometry"].cov, rel=0.05)
    assert np.std(draws["l1"]) == pytest.approx(0.5e-4, rel=0.03) and np.mean(draws["l1"]) == pytest.approx(0.3)
    wide = block_draws(BLOCKS, 20000, seed=1, widths={"losses": 3.0})
    assert np.array_equal(wide["start and geometry"], draws["start and geometry"])
    assert np.allclose(wide["losses"], 3.0 * draws["losses"])


@pytest.mark.parametrize("block", BLOCKS)
def test_widening_one_inputs_covariance_widens_the_horizons_interval(block):
    """For 20 seeds of 40 members each (the FMU ensemble's size): a block's covariance times 9 (its spread three
    times) widens the 16-84 % range of the horizons by at least 20 % (twice as wide on average; each block's spread is
    about 8 % of the model's frequency error), and the median stays near the main run's 12.5 s."""
    for seed in range(20):
        as_fitted = monte_carlo(_member, BLOCKS, 40, SPAN_S, seed=seed)
        wide = monte_carlo(_member, BLOCKS, 40, SPAN_S, seed=seed, widths={block: 3.0})
        assert wide["width_16_84_s"] > 1.2 * as_fitted["width_16_84_s"], (seed, as_fitted, wide)
        assert abs(as_fitted["median_s"] - 12.5) < 2.0


def test_a_profile_minimum_and_its_standard_error():
    x = np.array([0.04, 0.055, 0.07, 0.085, 0.1])
    chi2 = 1000.0 + 4.0 * ((x - 0.08) / 0.01) ** 2  # chi2_red 4: one standard error where chi2 rises by 4
    out = profile_minimum(x, chi2, chi2_red=4.0)
    assert out["best"] == pytest.approx(0.08) and out["stderr"] == pytest.approx(0.01) and not out["at_edge"]
    edge = profile_minimum(x, 1000.0 - 100 * x, chi2_red=4.0)
    assert edge["at_edge"] and edge["best"] is None and edge["lowest_at"] == 0.1
