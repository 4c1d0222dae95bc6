"""Physics of the model itself: equations of motion, kinematics, energies, normal modes."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from double_pendulum.model.dynamics import angular_accelerations, fixed_pivot_vector_field, linearised_normal_modes
from double_pendulum.model.energy import kinetic_energy, potential_energy, total_energy
from double_pendulum.model.kinematics import positions, velocities
from double_pendulum.model.parameters import PendulumParameters

P = PendulumParameters()


def _random_states(n: int, seed: int = 1):
    rng = random.Random(seed)
    for _ in range(n):
        yield [
            rng.uniform(-math.pi, math.pi),
            rng.uniform(-math.pi, math.pi),
            rng.uniform(-8, 8),
            rng.uniform(-15, 15),
        ]


def test_energy_is_a_first_integral_of_the_vector_field():
    """dE/dt = grad(E) . f = 0 at any state: the equations of motion conserve the energy."""
    f = fixed_pivot_vector_field(P)
    h = 1e-6
    for y in _random_states(50):
        dy = f(0.0, y)
        grad = []
        for k in range(4):
            up, down = list(y), list(y)
            up[k] += h
            down[k] -= h
            grad.append((total_energy(*up, P) - total_energy(*down, P)) / (2 * h))
        rate = sum(g * d for g, d in zip(grad, dy))
        scale = sum(abs(g * d) for g, d in zip(grad, dy))
        assert abs(rate) <= 1e-7 * scale


def test_accelerations_match_seed_eq20_and_eq21_relabelled():
    """Seed eq. 20 is phi1''; seed eq. 21 (labelled phi1'' in the report) is phi2''."""
    m1, m2, l1, l2, g = P.m1, P.m2, P.l1, P.l2, P.g
    big_m = m1 + m2
    for phi1, phi2, w1, w2 in _random_states(20, seed=2):
        d = phi1 - phi2
        eq20 = (
            -m2 * l2 * w2**2 * math.sin(d)
            - g * big_m * math.sin(phi1)
            - m2 * l1 * w1**2 * math.sin(d) * math.cos(d)
            + g * m2 * math.sin(phi2) * math.cos(d)
        ) / (big_m * l1 - m2 * l1 * math.cos(d) ** 2)
        eq21 = (
            -m2 * l2 * w2**2 * math.sin(d) * math.cos(d)
            - g * big_m * math.sin(phi1) * math.cos(d)
            - big_m * l1 * w1**2 * math.sin(d)
            + g * big_m * math.sin(phi2)
        ) / (m2 * l2 * math.cos(d) ** 2 - big_m * l2)
        a1, a2 = angular_accelerations(phi1, phi2, w1, w2, m1, m2, l1, l2, g)
        assert a1 == pytest.approx(eq20, rel=1e-12, abs=1e-12)
        assert a2 == pytest.approx(eq21, rel=1e-12, abs=1e-12)


def test_velocities_are_time_derivatives_of_positions():
    h = 1e-6
    for phi1, phi2, w1, w2 in _random_states(20, seed=3):
        ahead = positions(phi1 + h * w1, phi2 + h * w2, P.l1, P.l2)
        behind = positions(phi1 - h * w1, phi2 - h * w2, P.l1, P.l2)
        numeric = [(a - b) / (2 * h) for a, b in zip(ahead, behind)]
        assert velocities(phi1, phi2, w1, w2, P.l1, P.l2) == pytest.approx(numeric, rel=1e-6, abs=1e-8)


def test_kinetic_energy_equals_half_m_v_squared_of_both_bobs():
    for phi1, phi2, w1, w2 in _random_states(20, seed=4):
        vx1, vy1, vx2, vy2 = velocities(phi1, phi2, w1, w2, P.l1, P.l2)
        expected = 0.5 * P.m1 * (vx1**2 + vy1**2) + 0.5 * P.m2 * (vx2**2 + vy2**2)
        assert kinetic_energy(phi1, phi2, w1, w2, P) == pytest.approx(expected, rel=1e-12)


def test_potential_energy_is_zero_at_rest_and_m_g_h_elsewhere():
    assert potential_energy(0.0, 0.0, P) == 0.0
    for phi1, phi2, _, _ in _random_states(10, seed=5):
        _, y1, _, y2 = positions(phi1, phi2, P.l1, P.l2)
        rest = P.m1 * P.g * (-P.l1) + P.m2 * P.g * (-P.l1 - P.l2)
        assert potential_energy(phi1, phi2, P) == pytest.approx(
            P.m1 * P.g * y1 + P.m2 * P.g * y2 - rest, rel=1e-12
        )


def test_numpy_arrays_give_the_same_accelerations_as_floats():
    states = np.array(list(_random_states(30, seed=6)))
    a1, a2 = angular_accelerations(*states.T, P.m1, P.m2, P.l1, P.l2, P.g, sin=np.sin, cos=np.cos)
    for row, b1, b2 in zip(states, a1, a2):
        c1, c2 = angular_accelerations(*row, P.m1, P.m2, P.l1, P.l2, P.g)
        assert (b1, b2) == pytest.approx((c1, c2), rel=1e-13, abs=1e-13)


def test_normal_modes_match_the_numerical_linearisation():
    """Frequencies from the closed form equal the eigenvalues of the Jacobian at rest."""
    f = fixed_pivot_vector_field(P)
    h = 1e-7
    jac = np.zeros((4, 4))
    for k in range(4):
        e = [0.0] * 4
        e[k] = h
        jac[:, k] = (np.array(f(0.0, e)) - np.array(f(0.0, [-v for v in e]))) / (2 * h)
    numeric = np.sort(np.abs(np.linalg.eigvals(jac).imag))[::2]
    (w_slow, w_fast), shapes = linearised_normal_modes(P)
    assert numeric == pytest.approx([w_slow, w_fast], rel=1e-7)
    assert shapes[0][1] > 0 > shapes[1][1]  # in phase, then in anti-phase
