"""Friction and suspension terms in the equations: power balances at single states, force laws."""

from __future__ import annotations

import math
import random

import pytest
from scipy.integrate import quad

from double_pendulum.model.dynamics import fixed_pivot_vector_field
from double_pendulum.model.forces import bearing_torque, quadratic_drag, rod_drag_integrals
from double_pendulum.model.parameters import (
    SEED_RIGID_LINKS,
    AirDragParameters,
    BearingParameters,
    PendulumParameters,
    SuspensionParameters,
)
from double_pendulum.model.vector_field import ModelConfig, build_model, energies, state_layout

ALL_ON = ModelConfig(
    air=AirDragParameters(air_drag=True, rod_drag=True),
    bearing=BearingParameters(bearing_friction=True, b_v1=1e-4, b_v2=2e-4),
    suspension=SuspensionParameters(suspension=True),
)
SCENES = {
    "air": ModelConfig(air=AirDragParameters(air_drag=True)),
    "air+rods": ModelConfig(air=AirDragParameters(air_drag=True, rod_drag=True)),
    "bearing": ModelConfig(bearing=BearingParameters(bearing_friction=True)),
    "suspension": ModelConfig(suspension=SuspensionParameters(suspension=True)),
    "suspension_x": ModelConfig(suspension=SuspensionParameters(suspension=True, suspension_y=False)),
    "suspension_y": ModelConfig(suspension=SuspensionParameters(suspension=True, suspension_x=False)),
    "all": ALL_ON,
    "bearing_drag": ModelConfig(bearing=BearingParameters(bearing_drag=True, tau_b1=1e-3, tau_b2=2e-3)),
    "rigid, all": ModelConfig(
        pendulum=PendulumParameters(**SEED_RIGID_LINKS),
        air=AirDragParameters(air_drag=True, rod_drag=True),
        bearing=BearingParameters(bearing_friction=True, b_v1=1e-4, bearing_drag=True, tau_b1=1e-3, tau_b2=1e-3),
        suspension=SuspensionParameters(suspension=True),
    ),
}


def _random_state(config: ModelConfig, rng: random.Random) -> list[float]:
    layout = state_layout(config)
    y = []
    for name in layout.names:
        y.append(
            {
                "phi1": rng.uniform(-3, 3),
                "phi2": rng.uniform(-3, 3),
                "omega1": rng.uniform(-6, 6),
                "omega2": rng.uniform(-12, 12),
                "xs": rng.uniform(-1e-3, 1e-3),
                "ys": rng.uniform(-1e-3, 1e-3),
                "vxs": rng.uniform(-0.05, 0.05),
                "vys": rng.uniform(-0.05, 0.05),
            }.get(name, rng.uniform(0, 1))  # dissipated work: any value
        )
    return y


def _energy(config: ModelConfig, y: list[float]) -> float:
    return sum(energies(config, y))


@pytest.mark.parametrize("scene", list(SCENES))
def test_energy_rate_equals_minus_dissipated_power(scene):
    """dE_total/dt = grad(E) . f = -(P_air + P_bearing + P_bearing_drag + P_suspension) at any state."""
    config = SCENES[scene]
    model = build_model(config)
    rng = random.Random(7)
    for _ in range(30):
        y = _random_state(config, rng)
        ev = model.evaluate(y)
        rate = 0.0
        scale = 0.0
        for k in range(len(y)):
            h = 1e-5 * max(0.1, abs(y[k]))
            up, down = list(y), list(y)
            up[k] += h
            down[k] -= h
            term = (_energy(config, up) - _energy(config, down)) / (2 * h) * ev.dydt[k]
            rate += term
            scale += abs(term)
        dissipated = ev.p_air + ev.p_bearing + ev.p_bearing_drag + ev.p_suspension
        assert rate == pytest.approx(-dissipated, abs=1e-7 * scale)
        assert ev.p_air >= 0 and ev.p_bearing >= 0 and ev.p_bearing_drag >= 0 and ev.p_suspension >= 0


def test_undamped_suspension_conserves_energy_pointwise():
    config = ModelConfig(suspension=SuspensionParameters(suspension=True, c_x=0.0, c_y=0.0))
    model = build_model(config)
    ev = model.evaluate(_random_state(config, random.Random(3)))
    assert ev.p_suspension == 0.0


def test_switched_off_scene_is_the_core_vector_field_whatever_the_coefficients():
    config = ModelConfig(
        air=AirDragParameters(rho_air=9.0, cw=3.0),
        bearing=BearingParameters(c_R1=0.5, r_b1=0.1, tau_b1=0.3),
        suspension=SuspensionParameters(M_s=0.01, k_x=1.0),
    )
    model = build_model(config)
    assert model.layout.names == ("phi1", "phi2", "omega1", "omega2")
    y = [2.0, -1.0, 3.0, 0.5]
    assert model.vector_field(0.0, y) == fixed_pivot_vector_field(config.pendulum)(0.0, y)
    # the general evaluator agrees with the core too (up to rounding)
    assert model.evaluate(y).dydt == pytest.approx(model.vector_field(0.0, y), rel=1e-13, abs=1e-13)


def test_state_layout_holds_only_what_the_scene_needs():
    assert state_layout(SCENES["air"]).names == ("phi1", "phi2", "omega1", "omega2", "W_air")
    assert state_layout(SCENES["suspension_x"]).names == (
        "phi1",
        "phi2",
        "omega1",
        "omega2",
        "xs",
        "vxs",
        "W_suspension",
    )
    assert state_layout(ALL_ON).size == 4 + 4 + 3


def test_fixed_pivot_reaction_force_at_rest_is_the_weight():
    p = ModelConfig().pendulum
    ev = build_model(ModelConfig()).evaluate([0.0, 0.0, 0.0, 0.0])
    assert (ev.f_pivot_x, ev.f_pivot_y) == pytest.approx((0.0, -(p.m1 + p.m2) * p.g), abs=1e-12)


def test_bearing_torque_uses_the_joint_reaction_force():
    """With only the pivot bearing, P_bearing = c_R r_b |F_pivot| tanh(w1/w_reg) w1."""
    brg = BearingParameters(bearing_friction=True, c_R2=0.0, c_R1=2e-3, r_b1=5e-3)
    model = build_model(ModelConfig(bearing=brg))
    for y in ([1.0, 0.5, 2.0, -1.0], [-2.5, 2.0, -4.0, 7.0]):
        ev = model.evaluate(y + [0.0])
        load = math.hypot(ev.f_pivot_x, ev.f_pivot_y)
        expected = brg.c_R1 * brg.r_b1 * load * math.tanh(y[2] / brg.omega_reg) * y[2]
        assert ev.p_bearing == pytest.approx(expected, rel=1e-12)


def _kink(a: float, b: float, lo: float, hi: float) -> list[float] | None:
    """Where the normal velocity changes sign inside the rod (a kink of the integrand)."""
    return [-a / b] if b and lo < -a / b < hi else None


@pytest.mark.parametrize(
    ("a", "b", "lo", "hi"),
    [
        (0.3, 2.0, 0.0, 0.3),
        (0.5, -3.0, 0.0, 0.3),
        (-0.2, 0.1, 0.0, 0.2),
        (0.0, 5.0, 0.0, 0.25),
        (0.0, 5.0, -0.027, 0.323),  # plate overhanging the pivot: v_n changes sign at the joint
        (0.4, -2.0, -0.026, 0.223),
    ],
)
def test_rod_drag_integrals_are_exact(a, b, lo, hi):
    g = lambda s: abs(a + b * s) * (a + b * s)  # noqa: E731
    i0, i1, i3 = rod_drag_integrals(a, b, lo, hi)
    kink = _kink(a, b, lo, hi)
    assert i0 == pytest.approx(quad(g, lo, hi, points=kink, limit=200)[0], rel=1e-12, abs=1e-15)
    assert i1 == pytest.approx(quad(lambda s: g(s) * s, lo, hi, points=kink, limit=200)[0], rel=1e-12, abs=1e-15)
    assert i3 == pytest.approx(
        quad(lambda s: abs(a + b * s) ** 3, lo, hi, points=kink, limit=200)[0], rel=1e-12, abs=1e-15
    )


def test_quadratic_drag_opposes_velocity_with_v_squared_magnitude():
    fx, fy, power = quadratic_drag(3.0, -4.0, 0.01)
    assert (fx, fy) == pytest.approx((-0.15, 0.2))
    assert power == pytest.approx(0.01 * 125.0)


def test_bearing_torque_is_odd_and_regularised():
    assert bearing_torque(10.0, 1.0, 1e-3, 4e-3, 1e-3, 0.0) == pytest.approx(4e-5)
    assert bearing_torque(10.0, -1.0, 1e-3, 4e-3, 1e-3, 0.0) == pytest.approx(-4e-5)
    assert bearing_torque(10.0, 0.0, 1e-3, 4e-3, 1e-3, 0.0) == 0.0
    assert abs(bearing_torque(10.0, 1e-6, 1e-3, 4e-3, 1e-3, 0.0)) < 1e-3 * 4e-5
