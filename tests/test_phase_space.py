"""Flip map checks and Poincare sections at a given energy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from double_pendulum.analysis.chaos import flips, phase_space
from double_pendulum.analysis.chaos.ensemble import batch_potential_energy, pendulum_field
from double_pendulum.model.parameters import PendulumParameters

P = PendulumParameters()
E_ROD1 = 2 * (P.m1 + P.m2) * P.g * P.l1  # J, V(pi, 0)
E_ROD2 = 2 * P.m2 * P.g * P.l2  # J, V(0, pi)


def _flip_map(rod: np.ndarray, energy: np.ndarray) -> flips.FlipMap:
    axis = np.array([-1.0, 1.0])
    times = np.where(rod > 0, 1.0, np.nan)
    return flips.FlipMap(axis, axis, times, rod, energy, min(E_ROD1, E_ROD2), 2.0, 1e-3, 0.0, 1)


def test_rest_energy_is_the_potential_energy_of_the_release():
    expected = (P.m1 + P.m2) * P.g * P.l1 * (1 - math.cos(2.0)) + P.m2 * P.g * P.l2 * (1 - math.cos(0.5))
    assert phase_space.rest_energy(2.0, 0.5, P) == pytest.approx(expected, rel=1e-14)


def test_flips_below_the_energy_needed_for_that_rod_are_counted_as_violations():
    # rod 2 flipping just above V(0, pi) is allowed; rod 1 needs the larger V(pi, 0)
    rod = np.array([[2, 1], [0, 1]], dtype=np.int8)
    energy = np.array([[1.01 * E_ROD2, 0.99 * E_ROD1], [0.5 * E_ROD2, 1.01 * E_ROD1]])
    fmap = _flip_map(rod, energy)
    assert phase_space.flip_bound_violations(fmap, P) == 1
    summary = phase_space.flip_map_summary(fmap, P)
    assert summary["E_flip_rod1_J"] == pytest.approx(E_ROD1) and summary["E_flip_rod2_J"] == pytest.approx(E_ROD2)
    assert summary["fraction_flipped"] == 0.75 and summary["starts_below_bound"] == 1 and summary["grid"] == [2, 2]


def test_flip_map_table_has_one_row_per_start_in_grid_order():
    fmap = _flip_map(np.array([[0, 1], [2, 0]], dtype=np.int8), np.array([[1.0, 2.0], [3.0, 4.0]]))
    table, units = phase_space.flip_map_table(fmap)
    assert table["phi1_0"].tolist() == [-1.0, 1.0, -1.0, 1.0] and table["phi2_0"].tolist() == [-1.0, -1.0, 1.0, 1.0]
    assert table["E_0"].tolist() == [1.0, 2.0, 3.0, 4.0] and table["flipped_rod"].tolist() == [0, 1, 2, 0]
    assert units["flip_time"] == "s"


def test_phi2_reach_is_where_the_potential_alone_uses_up_the_energy():
    energy = float(batch_potential_energy(0.0, 1.2, P))
    reach = phase_space.phi2_reach(energy, P, margin=1.0)
    assert reach == pytest.approx(1.2, abs=math.pi / 2000)
    assert phase_space.phi2_reach(energy, P) == pytest.approx(0.95 * reach)


def test_poincare_section_at_an_energy_starts_and_stays_on_that_energy_surface():
    energy = phase_space.rest_energy(0.5, 0.5, P)
    section = phase_space.poincare_at_energy(pendulum_field(P), energy, 4, P, t_end=3.0, h=1e-3)
    summary = phase_space.section_summary(section, P)
    assert summary["starts"] == 4 and summary["points"] == section.points.shape[0] > 4
    assert summary["start_energy_relative_error"] < 1e-14
    np.testing.assert_allclose(section.points[:, 0], 0.0, atol=1e-12)
    label, (phi2, omega2, owner) = next(iter(phase_space.section_points({"regular": section}).items()))
    assert label == f"regular: E = {energy:.3f} J" and phi2.shape == omega2.shape == owner.shape
