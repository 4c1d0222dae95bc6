"""Parameter dataclasses: defaults from the seed, validation with clear messages."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from conftest import DATA

from double_pendulum.component.settings import SolverSettings
from double_pendulum.model.parameters import InitialState, ParameterError, PendulumParameters
from double_pendulum.solvers import UnknownSolverError


def test_defaults_are_the_seed_pendulum():
    p = PendulumParameters()
    assert (p.m1, p.m2, p.g) == (0.301, 0.297, 9.81)


def test_default_rod_lengths_are_measured_from_the_seed_track():
    """Circle fit of the upper bob (l1) and mean bob distance (l2) of Table 1, to 1 mm."""
    d = np.loadtxt(DATA / "seed_table1.csv", delimiter=",", skiprows=1)
    x1, y1, x2, y2 = d[:, 2], d[:, 3], d[:, 4], d[:, 5]
    a = np.c_[2 * x1, 2 * y1, np.ones_like(x1)]
    (xc, yc, c), *_ = np.linalg.lstsq(a, x1**2 + y1**2, rcond=None)
    l1 = math.sqrt(c + xc**2 + yc**2)
    l2 = float(np.mean(np.hypot(x2 - x1, y2 - y1)))
    p = PendulumParameters()
    assert p.l1 == pytest.approx(l1, abs=1e-3)
    assert p.l2 == pytest.approx(l2, abs=1e-3)


def test_parameters_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        PendulumParameters().m1 = 1.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("name", "value", "expected"),
    [
        ("l1", -0.3, "invalid l1 = -0.3 m: must be > 0"),
        ("m2", 0.0, "invalid m2 = 0.0 kg: must be > 0"),
        ("g", math.inf, "invalid g = inf m/s2: must be finite"),
        ("m1", math.nan, "invalid m1 = nan kg: must be finite"),
    ],
)
def test_invalid_physical_parameters_name_variable_and_value(name, value, expected):
    with pytest.raises(ParameterError, match=expected.replace("(", r"\(")):
        PendulumParameters(**{name: value})


def test_nan_start_value_is_rejected():
    with pytest.raises(ParameterError, match="phi2_0 = nan rad"):
        InitialState(phi2_0=math.nan)


def test_unknown_solver_lists_the_choices():
    with pytest.raises(UnknownSolverError, match="invalid solver = 'rk99': must be one of dop853, dopri5"):
        SolverSettings(solver="rk99")


@pytest.mark.parametrize("name", ["rtol", "atol", "fixed_step"])
def test_non_positive_solver_settings_are_rejected(name):
    with pytest.raises(ParameterError, match=f"invalid {name} = -1.0"):
        SolverSettings(**{name: -1.0})
