"""Inputs of DoublePendulum (pivot motion, joint torques): through the FMU and in-process."""

from __future__ import annotations

import math
import zipfile
from xml.etree import ElementTree as ET

import numpy as np
import pytest

from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.fmu.masters.simulate import simulate
from double_pendulum.fmu.running.runner import FmuRunError
from double_pendulum.model.inputs import INPUT_NAMES
from double_pendulum.model.outputs import MODEL_OUTPUT_NAMES, OUTPUT_NAMES, PORT_NAMES
from double_pendulum.model.parameters import ParameterError, PendulumParameters

TIGHT = {"rtol": 1e-12, "atol": 1e-14}
DT = 0.01


def signals(stop_time: float, **columns) -> np.ndarray:
    """Input table on the communication grid ``n * DT`` (exact values at every point).

    Each keyword is an input name and a function of time.
    """
    t = np.arange(int(round(stop_time / DT)) + 2) * DT
    dtype = [("time", np.float64)] + [(name, np.float64) for name in columns]
    table = np.zeros(len(t), dtype=dtype)
    table["time"] = t
    for name, f in columns.items():
        table[name] = [f(ti) for ti in t]
    return table


def zeros(stop_time: float) -> np.ndarray:
    return signals(stop_time, **{name: (lambda t: 0.0) for name in INPUT_NAMES})


def shaker(amplitude: float, omega: float, phase: float = 0.0) -> dict:
    """Consistent position, velocity and acceleration of ``amplitude * sin(omega t + phase)``."""
    return {
        "pos": lambda t: amplitude * math.sin(omega * t + phase),
        "vel": lambda t: amplitude * omega * math.cos(omega * t + phase),
        "acc": lambda t: -amplitude * omega * omega * math.sin(omega * t + phase),
    }


def pivot_motion(x: dict | None = None, y: dict | None = None) -> dict:
    columns = {}
    for axis, motion in (("x", x), ("y", y)):
        if motion is not None:
            columns[f"pivot_{axis}"] = motion["pos"]
            columns[f"pivot_v{axis}"] = motion["vel"]
            columns[f"pivot_a{axis}"] = motion["acc"]
    return columns


@pytest.mark.parametrize("start", [{}, {"suspension": True, "air_drag": True, "bearing_friction": True}])
def test_zero_inputs_are_bit_identical_to_no_inputs(runner, start):
    plain = runner.simulate(start, stop_time=2.0, output_interval=DT)
    with_inputs = runner.simulate(start, stop_time=2.0, output_interval=DT, input=zeros(2.0))
    for name in OUTPUT_NAMES:
        np.testing.assert_array_equal(with_inputs[name], plain[name], err_msg=name)
    assert not np.any(with_inputs["W_input"])


def test_constant_upward_pivot_acceleration_acts_as_stronger_gravity(runner):
    a, g = 3.0, PendulumParameters().g
    lift = signals(2.0, pivot_y=lambda t: 0.5 * a * t * t, pivot_vy=lambda t: a * t, pivot_ay=lambda t: a)
    driven = runner.simulate(TIGHT, stop_time=2.0, output_interval=DT, input=lift)
    heavier = runner.simulate({**TIGHT, "g": g + a}, stop_time=2.0, output_interval=DT)
    for name in ("phi1", "phi2", "omega1", "omega2"):
        assert abs(driven[name][-1] - heavier[name][-1]) < 1e-10, name
    # the bobs ride up with the pivot
    np.testing.assert_allclose(driven["y2"] - heavier["y2"], 0.5 * a * driven["time"] ** 2, atol=1e-9)


def test_acceleration_alone_drives_the_angles(runner):
    """Inconsistent inputs are used as given: only pivot_ay set, the angles still see g + a."""
    a, g = 3.0, PendulumParameters().g
    driven = runner.simulate(TIGHT, stop_time=2.0, output_interval=DT, input=signals(2.0, pivot_ay=lambda t: a))
    heavier = runner.simulate({**TIGHT, "g": g + a}, stop_time=2.0, output_interval=DT)
    assert abs(driven["phi1"][-1] - heavier["phi1"][-1]) < 1e-9
    assert abs(driven["energy_residual"][-1]) < 1e-8


def test_sinusoidal_pivot_motion_through_the_fmu_matches_the_in_process_component(runner):
    start = {"phi1_0": 0.3, "phi2_0": -0.2, "air_drag": True}
    table = signals(3.0, **pivot_motion(shaker(0.02, 11.0), shaker(0.03, 17.0, 0.4)), tau1=lambda t: 0.05 * t)
    fmu = runner.simulate(start, stop_time=3.0, output_interval=DT, input=table)
    local = simulate(start, stop_time=3.0, output_interval=DT, input=table)
    for name in MODEL_OUTPUT_NAMES:
        np.testing.assert_allclose(fmu[name], local[name], rtol=0, atol=1e-12, err_msg=name)
    assert np.ptp(fmu["ys"]) > 0.05  # the pivot did move


@pytest.mark.parametrize(
    ("start", "columns"),
    [
        (
            {"air_drag": True, "bearing_friction": True},
            {"tau1": lambda t: 0.3 * math.sin(4 * t), "tau2": lambda t: -0.1},
        ),
        ({"air_drag": True}, pivot_motion(shaker(0.02, 9.0), shaker(0.04, 13.0))),
        ({"suspension": True}, pivot_motion(shaker(0.002, 40.0), shaker(0.003, 55.0))),
        ({"suspension": True, "suspension_x": False}, pivot_motion(shaker(0.01, 8.0), shaker(0.003, 55.0))),
    ],
    ids=["torques", "pivot", "suspension-base", "half-suspended"],
)
def test_energy_budget_closes_with_inputs(runner, start, columns):
    result = runner.simulate(start, stop_time=3.0, output_interval=DT, input=signals(3.0, **columns))
    scale = max(abs(result["E_total"]).max(), abs(result["W_input"]).max())
    assert abs(result["W_input"][-1]) > 1e-3  # the inputs did work
    assert abs(result["energy_residual"]).max() < 1e-7 * scale


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_non_finite_input_is_refused_naming_it_and_the_rows_are_kept(runner, bad):
    table = signals(1.0, pivot_ay=lambda t: bad if t >= 0.5 - 1e-12 else 1.0)
    with pytest.raises(FmuRunError, match=rf"invalid input pivot_ay = {bad!r}") as info:
        runner.simulate({}, stop_time=1.0, output_interval=DT, input=table)
    rows = info.value.partial_result
    assert rows is not None and 0.4 < rows["time"][-1] < 0.5 + 1e-9
    assert np.all(np.isfinite(rows["phi1"]))


def test_input_change_restarts_the_integrator_at_the_communication_point():
    """A torque switched on at t = 1 s: nothing integrated with the old torque goes past 1 s."""
    sim = DoublePendulumCoSimulation()
    for name, value in TIGHT.items():
        sim.set(name, value)
    sim.initialise()
    for n in range(4):
        sim.do_step(0.25 * n, 0.25)
    assert sim.integrator.t > 1.0  # the integrator has stepped past the communication point
    state = [sim.outputs[n] for n in ("phi1", "phi2", "omega1", "omega2")]
    sim.set_input("tau1", 0.4)
    sim.do_step(1.0, 1.0)

    fresh = DoublePendulumCoSimulation(start_time=1.0)
    for name, value in zip(("phi1_0", "phi2_0", "omega1_0", "omega2_0"), state):
        fresh.set(name, value)
    for name, value in TIGHT.items():
        fresh.set(name, value)
    fresh.set_input("tau1", 0.4)
    fresh.initialise()
    fresh.do_step(1.0, 1.0)
    for name in ("phi1", "phi2", "omega1", "omega2", "W_input"):
        assert abs(sim.outputs[name] - fresh.outputs[name]) < 1e-9, name


def test_pivot_force_sees_a_new_input_before_the_step():
    sim = DoublePendulumCoSimulation()
    sim.set("phi1_0", 0.0)
    sim.set("phi2_0", 0.0)
    sim.initialise()
    weight = -(PendulumParameters().m1 + PendulumParameters().m2) * PendulumParameters().g
    assert sim.outputs["F_pivot_y"] == pytest.approx(weight)
    sim.set_input("pivot_ay", 2.0)
    assert sim.outputs["F_pivot_y"] == pytest.approx(weight * (1 + 2.0 / PendulumParameters().g))
    with pytest.raises(ParameterError, match="invalid input pivot_ay = nan m/s2"):
        sim.set_input("pivot_ay", math.nan)
    assert sim.get("pivot_ay") == 2.0


def test_restored_state_with_inputs_continues_bit_identically():
    def drive(sim, n):
        sim.set_input("tau1", 0.1 * math.sin(n))
        sim.set_input("pivot_vy", 0.05 * n)
        sim.do_step(0.05 * n, 0.05)

    sim = DoublePendulumCoSimulation()
    sim.initialise()
    for n in range(10):
        drive(sim, n)
    state = sim.get_state()
    copy = DoublePendulumCoSimulation()
    copy.set_state(state)
    for n in range(10, 20):
        drive(sim, n)
        drive(copy, n)
    for name in MODEL_OUTPUT_NAMES:
        assert copy.outputs[name] == sim.outputs[name], name


def test_model_structure_states_the_outputs_dependencies_on_the_inputs(fmu_path):
    with zipfile.ZipFile(fmu_path) as fmu:
        root = ET.fromstring(fmu.read("modelDescription.xml"))
    variables = list(root.find("ModelVariables"))
    index = {sv.get("name"): i for i, sv in enumerate(variables, start=1)}
    inputs = [sv for sv in variables if sv.get("causality") == "input"]
    assert [sv.get("name") for sv in inputs] == list(INPUT_NAMES)
    for sv in inputs:
        assert sv.get("variability") == "continuous"
        assert float(sv.find("Real").get("start")) == 0.0
        assert sv.find("Real").get("unit")
    deps = {
        variables[int(u.get("index")) - 1].get("name"): u.get("dependencies")
        for u in root.find("ModelStructure/Outputs")
    }
    assert sorted(map(int, deps["F_pivot_y"].split())) == sorted(index[n] for n in INPUT_NAMES)
    assert deps["phi1"] == "" and deps["omega2"] == ""
    assert sorted(map(int, deps["E_total"].split())) == sorted(index[n] for n in INPUT_NAMES if n.startswith("pivot_")
                                                               and not n.startswith("pivot_a"))
    assert set(deps) == set(PORT_NAMES)  # the diagnostics are locals: no ports, no Outputs entry


def test_fmu_state_with_inputs_restores_through_the_fmu(runner):
    """fmi2GetFMUstate/fmi2SetFMUstate with inputs driving: the repeated steps are bit-identical."""
    from double_pendulum.fmu.masters.coupling import FmuSlave

    slave = FmuSlave(runner.unzipdir, runner.model_description, {"air_drag": True})

    def drive(n: int) -> None:
        slave.set_input("tau1", 0.2 * math.sin(0.3 * n))
        slave.set_input("pivot_vx", 0.01 * n)
        slave.do_step(0.01 * n, 0.01)

    try:
        for n in range(10):
            drive(n)
        state = slave.fmu.getFMUState()
        first = []
        for n in range(10, 20):
            drive(n)
            first.append([slave.get(name) for name in ("phi1", "omega2", "W_input", "F_pivot_x")])
        slave.fmu.setFMUState(state)
        again = []
        for n in range(10, 20):
            drive(n)
            again.append([slave.get(name) for name in ("phi1", "omega2", "W_input", "F_pivot_x")])
        slave.fmu.freeFMUState(state)
    finally:
        slave.close()
    assert again == first
    assert first[-1][2] != 0.0


@pytest.mark.parametrize("rods", [False, True])
def test_fast_driven_core_agrees_with_the_general_evaluator(rods):
    import random

    from double_pendulum.model.inputs import InputHold, InputValues
    from double_pendulum.model.vector_field import (
        ModelConfig,
        build_evaluator,
        build_vector_field,
        driven_core_vector_field,
    )

    pendulum = PendulumParameters(m_rod1=0.05, L_rod1=0.3, m_rod2=0.03, L_rod2=0.25) if rods else PendulumParameters()
    config = ModelConfig(pendulum=pendulum, inputs=True)
    evaluate = build_evaluator(config)
    rng = random.Random(11)
    for _ in range(200):
        hold = InputHold(rng.uniform(-1, 1), InputValues(*(rng.uniform(-3, 3) for _ in INPUT_NAMES)))
        fast = driven_core_vector_field(pendulum, hold)
        assert build_vector_field(config, evaluate, hold).__qualname__ == fast.__qualname__
        t = hold.t0 + rng.uniform(0, 0.01)
        y = [rng.uniform(-4, 4), rng.uniform(-4, 4), rng.uniform(-8, 8), rng.uniform(-8, 8), rng.uniform(-1, 1)]
        general = evaluate(y, hold.at(t))
        got = fast(t, y)
        scale = [1.0, 1.0, max(abs(general.alpha1), abs(general.alpha2)), max(abs(general.alpha1), abs(general.alpha2))]
        for a, b, s in zip(got[:4], general.dydt[:4], scale):
            assert abs(a - b) <= 1e-12 * s
        # the input power: rounding of its largest term
        u = hold.at(t)
        terms = (abs(general.f_pivot_x * u.pivot_vx) + abs(general.f_pivot_y * u.pivot_vy)
                 + abs(u.tau1 * y[2]) + abs(u.tau2 * (y[3] - y[2])) + abs(general.p_input))
        assert abs(got[4] - general.p_input) <= 1e-12 * terms
