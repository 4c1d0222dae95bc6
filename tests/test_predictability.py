"""Predictability of a hand release: drawn releases, parting of the runs, horizons and their slopes."""

from __future__ import annotations

import numpy as np
import pytest

from double_pendulum.analysis.chaos import predictability, releases
from double_pendulum.analysis.chaos.ensemble import dop853_trajectory, initial_states, pendulum_field
from double_pendulum.model.parameters import PendulumParameters

P = PendulumParameters()
START = {"phi1_0": 2.0, "phi2_0": 0.0, "omega1_0": 0.0, "omega2_0": 0.0}


def _run(time: np.ndarray, x2: np.ndarray, y2: np.ndarray) -> np.ndarray:
    return np.rec.fromarrays([time, x2, y2], names=["time", "x2", "y2"]).view(np.ndarray)


def test_drawn_releases_move_only_the_upper_angle_by_the_drawn_arc_over_l1():
    releases = predictability.drawn_releases(START, 0.005, 3, P, seed=41)
    assert list(releases) == ["nominal", "release_1", "release_2", "release_3"]
    assert releases["nominal"] == START
    arcs = np.random.default_rng(41).normal(0.0, 0.005, size=3)  # m, along the upper bob's circle
    for k, arc in enumerate(arcs):
        drawn = releases[f"release_{k + 1}"]
        assert drawn["phi1_0"] == pytest.approx(2.0 + arc / P.l1, rel=1e-15)
        assert {n: v for n, v in drawn.items() if n != "phi1_0"} == {n: v for n, v in START.items() if n != "phi1_0"}


def test_runs_part_when_the_largest_pairwise_distance_first_exceeds_the_threshold():
    t = np.linspace(0.0, 1.0, 101)
    runs = [_run(t, np.zeros_like(t), -0.4 + 0 * t), _run(t, 0.05 * t, -0.4 + 0 * t), _run(t, -0.05 * t, -0.4 + 0 * t)]
    t_part, (x, y) = predictability.lower_bob_parting(runs, 0.0105)
    # runs 2 and 3 are 0.1 t apart: more than 1.05 cm after t = 0.105 s, first sample after it t = 0.11 s
    assert t_part == pytest.approx(0.11)
    assert (x, y) == pytest.approx((0.0, -0.4))
    never, _ = predictability.lower_bob_parting(runs, 1.0)
    assert never == 1.0  # never apart: the last output time


def test_lower_bob_traces_are_cut_at_the_given_time():
    t = np.linspace(0.0, 2.0, 21)
    traces = predictability.lower_bob_traces({"a": _run(t, t, -t), "b": _run(t, 2 * t, t)}, 1.0)
    np.testing.assert_array_equal(traces["a"][0], t[:11])
    np.testing.assert_array_equal(traces["b"][1], t[:11])


def test_batch_angle_difference_measures_the_deviation_from_the_batch_dop853_run():
    times = np.linspace(0.0, 1.0, 11)
    exact = dop853_trajectory(pendulum_field(P), initial_states(1.0, 0.5), times[1:], rtol=1e-10, atol=1e-12)
    phi1 = np.concatenate(([1.0], exact.y[:, 0, 0]))
    phi2 = np.concatenate(([0.5], exact.y[:, 1, 0]))
    phi2[7] += 1e-3  # one output off by a milliradian
    result = np.rec.fromarrays([times, phi1, phi2], names=["time", "phi1", "phi2"]).view(np.ndarray)
    diff = predictability.batch_angle_difference(result, 1.0, 0.5, P, t_check=1.0, rtol=1e-10, atol=1e-12)
    assert diff == pytest.approx(1e-3, rel=1e-6)
    assert predictability.batch_angle_difference(result, 1.0, 0.5, P, t_check=0.5, rtol=1e-10, atol=1e-12) == 0.0


def test_horizon_slopes_recover_one_over_lambda_for_exponential_separation():
    lam, sigmas = 2.5, np.array([1e-5, 1e-4, 1e-3, 1e-2])
    horizons = {d: np.log(d / sigmas) / lam for d in (0.01, 0.10)}  # t_h = ln(d / sigma) / lambda
    horizons[0.01][-1] = np.nan  # not reached: left out of the fit
    slopes = predictability.horizon_slopes(sigmas, horizons)
    assert slopes == pytest.approx({"1cm": 1.0 / lam, "10cm": 1.0 / lam}, rel=1e-12)
    assert predictability.horizon_slopes(sigmas[:1], {0.01: horizons[0.10][:1]}) == {}


def test_release_predictability_starts_with_the_drawn_spread_and_keeps_the_chosen_clouds():
    sigmas = (1e-4, 1e-3)
    res = predictability.release_predictability(
        pendulum_field(P), P, 2.0, 0.0, sigmas, 30, 0.5, thresholds=(0.01, 0.10), h=1e-3, seed=7,
        snapshot_sigma=1e-3, snapshot_times=(0.0, 0.2, 3.0),
    )
    assert res.snapshot_group == 1 and sorted(res.spread.snapshots) == [0.0, 0.2]  # 3 s is past the end
    # at release the hanging lower bob moves with the upper one: its spread is the RMS of the drawn arcs
    for j, sigma in enumerate(sigmas):
        arcs = releases.release_ensemble(2.0, 0.0, sigma, 30, P, seed=7 + j)[0] - 2.0
        assert res.spread.spread[0, j] == pytest.approx(P.l1 * np.std(arcs), rel=1e-3)
    table, units = predictability.spread_table(res)
    assert table.dtype.names == ("time", "spread_sigma_0.1mm", "spread_sigma_1mm") and units["spread_sigma_1mm"] == "m"
    summary = predictability.predictability_summary(res, 2.0)
    assert summary["one_over_lyapunov_s"] == 0.5 and summary["members_per_ensemble"] == 30
    assert np.all(np.isnan(summary["horizon_10cm_s"]))  # 10 cm is not reached within 0.5 s
