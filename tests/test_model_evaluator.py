"""The general evaluator (double_pendulum.model.evaluator): named parts compiled into one function per
combination of switches, which give the same numbers as the plain equations."""

from __future__ import annotations

import itertools
import math
import random

import pytest

from double_pendulum.model.dynamics import fixed_pivot_vector_field
from double_pendulum.model.evaluator import build_evaluator
from double_pendulum.model.inputs import InputValues
from double_pendulum.model.parameters import (
    AirDragParameters,
    BearingParameters,
    PendulumParameters,
    SuspensionParameters,
)
from double_pendulum.model.scene import ModelConfig, ModelError, state_layout


def _scenes():
    """Every combination of the switches (rod drag only with air drag, x/y only with the suspension)."""
    for air, rods, friction, drag, sus, sx, sy, inputs in itertools.product((False, True), repeat=8):
        if (rods and not air) or (not sus and not (sx and sy)) or (sus and not (sx or sy)):
            continue
        yield ModelConfig(
            pendulum=PendulumParameters(m_rod1=0.01, m_rod2=0.02),
            air=AirDragParameters(air_drag=air, rod_drag=rods),
            bearing=BearingParameters(bearing_friction=friction, bearing_drag=drag),
            suspension=SuspensionParameters(suspension=sus, suspension_x=sx, suspension_y=sy),
            inputs=inputs,
        )


SCENES = list(_scenes())


def test_every_combination_of_switches_builds_and_evaluates():
    rng = random.Random(3)
    for config in SCENES:
        evaluate = build_evaluator(config)
        n = state_layout(config).size
        y = [rng.uniform(-2.0, 2.0) for _ in range(n)]
        u = InputValues(*(rng.uniform(-1.0, 1.0) for _ in range(8)))
        for ev in (evaluate(y), evaluate(y, u)):
            assert len(ev.dydt) == n and all(map(math.isfinite, ev.dydt)), config
            assert ev.dydt[:2] == y[2:4]  # the angles' rates are the rate states


def test_one_compiled_code_per_combination_of_switches_not_per_scene():
    """Two scenes with the same switches and other coefficients share the code, not the constants."""
    a = build_evaluator(ModelConfig(air=AirDragParameters(air_drag=True)))
    b = build_evaluator(ModelConfig(pendulum=PendulumParameters(m1=0.5), air=AirDragParameters(air_drag=True, cw=0.9)))
    c = build_evaluator(ModelConfig(air=AirDragParameters(air_drag=True, rod_drag=True)))
    assert a.__code__ is b.__code__ and a.__code__ is not c.__code__
    y = [1.0, 0.5, 0.3, -0.2, 0.0]
    assert a(y).dydt != b(y).dydt


def test_without_mechanisms_the_evaluator_is_the_frictionless_core_bit_for_bit():
    rng = random.Random(5)
    config = ModelConfig()
    evaluate, core = build_evaluator(config), fixed_pivot_vector_field(config.pendulum)
    for _ in range(50):
        y = [rng.uniform(-3.0, 3.0) for _ in range(4)]
        assert evaluate(y).dydt == core(0.0, y)


def test_zero_inputs_give_what_no_inputs_give_bit_for_bit():
    rng = random.Random(7)
    for config in (c for c in SCENES if c.inputs):
        evaluate = build_evaluator(config)
        y = [rng.uniform(-2.0, 2.0) for _ in range(state_layout(config).size)]
        assert evaluate(y, InputValues()) == evaluate(y)


def test_the_friction_iteration_that_does_not_converge_raises_model_error():
    config = ModelConfig(bearing=BearingParameters(bearing_friction=True, c_R1=50.0, c_R2=50.0, r_b1=0.5, r_b2=0.5))
    with pytest.raises(ModelError, match="joint-load iteration did not converge"):
        build_evaluator(config)([2.0, -1.0, 30.0, -40.0, 0.0])
