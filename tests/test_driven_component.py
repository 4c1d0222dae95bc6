"""The driven component (issue 21): cheap input setting, short landing steps that keep the tolerance,
and pivot motion from positions alone (``pivot_input = position``) or a warning for it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.component.pivot_motion import POSITION_ONLY_WARNING, PositionSamples, parabola_rates
from double_pendulum.model.inputs import INPUT_NAMES
from double_pendulum.model.parameters import ParameterError

H = 1e-3  # communication step [s]
A, W = 0.01, 30.0  # shaker amplitude [m] and angular frequency [rad/s]


def shaker(t: float) -> list[float]:
    """All eight inputs at t [s]: a vertical shaker (consistent position, velocity, acceleration), torques."""
    return [0.0, A * math.sin(W * t), 0.0, A * W * math.cos(W * t), 0.0, -A * W * W * math.sin(W * t),
            1e-3 * math.sin(5 * t), -1e-3]  # fmt: skip


def from_rest(t: float) -> tuple[float, float, float]:
    """A vertical motion that starts at rest: position [m], velocity [m/s], acceleration [m/s2]."""
    return A * (1.0 - math.cos(W * t)), A * W * math.sin(W * t), A * W * W * math.cos(W * t)


def component(**values) -> DoublePendulumCoSimulation:
    sim = DoublePendulumCoSimulation()
    for name, value in {"phi1_0": 2.0, "phi2_0": 2.0, **values}.items():
        sim.set(name, value)
    sim.initialise()
    return sim


def driven_run(seconds: float, **values) -> dict[str, float]:
    sim = component(**values)
    indices = list(range(len(INPUT_NAMES)))
    for k in range(round(seconds / H)):
        sim.set_inputs_at(indices, shaker(k * H))
        sim.do_step(k * H, H)
    return {name: sim.get(name) for name in ("phi1", "phi2", "omega1", "omega2", "W_input", "energy_residual")}


def test_a_driven_run_at_the_default_tolerance_stays_within_it_against_a_tight_reference():
    """2 s from the chaotic start, all inputs set every 1 ms: the short landing steps (Dopri5) keep rtol."""
    got = driven_run(2.0)
    tight = driven_run(2.0, rtol=1e-13, atol=1e-15)
    for name in ("phi1", "phi2", "omega1", "omega2"):
        assert abs(got[name] - tight[name]) <= 1e-9 * max(1.0, abs(tight[name])), name
    assert abs(got["energy_residual"]) < 1e-9 and got["W_input"] == pytest.approx(tight["W_input"], abs=1e-9)


def test_setting_inputs_by_position_checks_each_value_and_names_a_bad_one():
    sim = component()
    u = shaker(0.3)
    bad = [*u[:3], math.nan, *u[4:]]
    with pytest.raises(ParameterError, match="invalid input pivot_vy = nan"):
        sim.set_inputs_at(range(8), bad)
    assert [sim.get(n) for n in INPUT_NAMES[:3]] == u[:3]  # those before it are set
    assert [sim.get(n) for n in INPUT_NAMES[3:]] == [0.0] * 5  # it and those after it are not
    sim.set_inputs_at([6], [2])  # an int is a number
    assert sim.get("tau1") == 2.0 and sim.driven


def test_the_parabola_through_three_samples_is_exact_for_a_quadratic():
    t, x = [0.1, 0.25, 0.3], [3.0 - 2.0 * s + 7.0 * s * s for s in (0.1, 0.25, 0.3)]
    v, a = parabola_rates(t, x)
    assert v == pytest.approx(-2.0 + 14.0 * 0.3, rel=1e-12) and a == pytest.approx(14.0, rel=1e-12)


def test_derived_velocity_is_second_order_and_acceleration_first_order():
    errors = {}
    for h in (4e-3, 2e-3, 1e-3):
        samples, ev, ea = PositionSamples(), 0.0, 0.0
        for k in range(300):
            x, v, a = from_rest(k * h)
            _, vy, _, ay = samples.rates_at(k * h, 0.0, x)
            if k >= 2:
                ev, ea = max(ev, abs(vy - v)), max(ea, abs(ay - a))
        errors[h] = (ev, ea)
    for coarse, fine in ((4e-3, 2e-3), (2e-3, 1e-3)):
        assert math.log2(errors[coarse][0] / errors[fine][0]) == pytest.approx(2.0, abs=0.1)
        assert math.log2(errors[coarse][1] / errors[fine][1]) == pytest.approx(1.0, abs=0.1)
    assert errors[1e-3][1] / (A * W * W) == pytest.approx(W * 1e-3, rel=0.05)  # the lag: relative error w h


def _vertical_run(mode: str, h: float, positions_only: bool, seconds: float = 2.0) -> dict[str, float]:
    sim = component(phi1_0=0.5, phi2_0=0.3, pivot_input=mode, rtol=1e-11, atol=1e-13)
    for k in range(round(seconds / h)):
        x, v, a = from_rest(k * h)
        sim.set_inputs_at([1] if positions_only else [1, 3, 5], [x] if positions_only else [x, v, a])
        sim.do_step(k * h, h)
    return {name: sim.get(name) for name in ("phi1", "phi2", "W_input")}


def test_position_only_driving_moves_the_pendulum_and_converges_to_the_exact_motion():
    still = _vertical_run("acceleration", 1e-3, positions_only=True)  # the trap: the angles do not see it
    resting = component(phi1_0=0.5, phi2_0=0.3)
    for k in range(2000):
        resting.do_step(k * 1e-3, 1e-3)
    assert still["phi1"] == pytest.approx(resting.get("phi1"), abs=1e-8) and still["W_input"] == 0.0
    deviation = []
    for h in (2e-3, 1e-3, 5e-4):
        exact = _vertical_run("acceleration", h, positions_only=False)
        derived = _vertical_run("position", h, positions_only=True)
        deviation.append(max(abs(exact[n] - derived[n]) for n in ("phi1", "phi2")))
    moved = abs(exact["phi1"] - resting.get("phi1"))  # what the motion does to the pendulum in 2 s
    assert deviation[1] < 1e-3 and moved > 100 * deviation[1]  # at 1 ms: within 1 % of the motion's effect
    assert deviation[0] > 2.0 * deviation[1] > 4.0 * deviation[2]  # and converging, at least at first order


def test_acceleration_mode_warns_once_when_only_positions_move():
    sim = component()
    for k in range(50):
        sim.set_input("pivot_x", A * math.sin(W * k * H))
        sim.do_step(k * H, H)
    assert sim.notices == [POSITION_ONLY_WARNING]
    quiet = component()  # consistent motion: no warning
    for k in range(50):
        quiet.set_inputs_at(range(8), shaker(k * H))
        quiet.do_step(k * H, H)
    assert quiet.notices == []


def test_position_only_warning_reaches_the_fmu_log_once(runner):
    t = np.arange(0.0, 0.31, 0.01)
    signal = np.array(list(zip(t, A * np.sin(W * t))), dtype=[("time", float), ("pivot_x", float)])
    messages: list[str] = []

    def logger(_env, _instance, status, _category, message):
        messages.append(message.decode() if isinstance(message, bytes) else str(message))

    from fmpy import simulate_fmu

    simulate_fmu(str(runner.fmu_path), stop_time=0.3, output_interval=0.01, input=signal, debug_logging=True,
                 logger=logger, start_values={"phi1_0": 0.2})  # fmt: skip
    assert sum(POSITION_ONLY_WARNING in m for m in messages) == 1


def test_a_restored_state_in_position_mode_continues_bit_identically():
    sim = component(pivot_input="position")
    for k in range(30):
        sim.set_input("pivot_y", from_rest(k * H)[0])
        sim.do_step(k * H, H)
    saved = sim.get_state()
    twin = DoublePendulumCoSimulation()
    twin.set_state(saved)
    for target in (sim, twin):
        for k in range(30, 60):
            target.set_input("pivot_y", from_rest(k * H)[0])
            target.do_step(k * H, H)
    assert [sim.get(n) for n in ("phi1", "omega2", "W_input")] == [twin.get(n) for n in ("phi1", "omega2", "W_input")]
