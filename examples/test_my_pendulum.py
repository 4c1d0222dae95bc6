"""Regression tests of a pendulum of one's own, written with the double_pendulum pytest plugin (docs/testing.md):
a reference comparison, the energy budget of a changed pendulum, and its normal modes.

Installing the package installs the plugin. Run the tests on the project's DoublePendulum.fmu (built when missing or
older than the sources) or on an FMU of yours:

    pytest examples/test_my_pendulum.py
    pytest examples/test_my_pendulum.py --fmu=path/to/DoublePendulum.fmu

A failed comparison names each variable that left the tube, when it first did and how far, and saves a plot in
pytest's temporary folder (the message gives its path).
"""

from __future__ import annotations

import pytest

from double_pendulum.testing import (
    ENERGY_COLUMNS,
    assert_energy_budget_closes,
    assert_energy_never_rises,
    assert_matches_reference,
    assert_normal_mode_periods,
    normal_mode_start,
    pendulum_parameters,
)

MY_PENDULUM = {"l2": 0.25, "m2": 0.35}  # a longer lower rod [m] with a heavier bob [kg]


def test_the_fmu_reproduces_the_reference_it_carries(simulate, reference):
    """The FMU run with its defaults, the experiment of its reference result, stays in a tight tube around it:
    1 ms either side, 1e-6 of each variable's nominal."""
    result = simulate.like(reference)
    assert_matches_reference(result, reference, time=0.001, rtol=1e-6)


def test_my_pendulum_loses_energy_only_to_friction(simulate):
    """With air drag and bearing friction the energy only falls, and what it loses is the friction's work."""
    start = {**MY_PENDULUM, "phi1_0": 1.5, "phi2_0": 0.0, "air_drag": True, "bearing_friction": True}
    result = simulate(start_values=start, stop_time=10.0, output_interval=0.01, outputs=list(ENERGY_COLUMNS))
    assert_energy_budget_closes(result, rtol=1e-6)
    assert_energy_never_rises(result)


@pytest.mark.parametrize("mode", ["slow", "fast"])
def test_my_pendulum_swings_at_its_normal_modes(fmu, simulate, mode):
    """Started in a normal mode, 0.01 rad, both rods swing with the period the linearised equations give."""
    parameters = pendulum_parameters(fmu.variables, MY_PENDULUM)
    start = {**MY_PENDULUM, **normal_mode_start(parameters, mode, amplitude=0.01)}
    result = simulate(start_values=start, stop_time=5.0, output_interval=0.002, outputs=["phi1", "phi2"])
    assert_normal_mode_periods(result, parameters, mode, rtol=1e-3)
