"""The batch integrator: same equations as the model, same numbers as the single-trajectory solvers."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import DATA

from double_pendulum.analysis.chaos.ensemble import (
    batch_energy,
    columnwise_field,
    dop853_trajectory,
    initial_states,
    model_field,
    n_fixed_steps,
    pendulum_field,
    rk4_trajectory,
)
from double_pendulum.model.dynamics import fixed_pivot_vector_field
from double_pendulum.model.parameters import AirDragParameters, PendulumParameters
from double_pendulum.model.vector_field import ModelConfig
from double_pendulum.runs.results_io import read_results_csv
from double_pendulum.solvers import make_integrator

P = PendulumParameters()
# regular, chaotic (seed-like release, equal angles), moving start, near the upright position
STARTS = initial_states([0.3, 2.0, 2.0, 1.0, 3.0], [0.3, 0.0, 2.0, -1.0, 3.1], [0, 0, 0, 1.0, 0], [0, 0, 0, 0, 0])


def _single(solver: str, y0: np.ndarray, times: np.ndarray, rtol: float = 1e-10) -> np.ndarray:
    """The project's single-trajectory integrator on the float vector field, at ``times``."""
    integ = make_integrator(solver, fixed_pivot_vector_field(P), 0.0, list(y0), rtol=rtol, atol=1e-12, fixed_step=1e-3)
    return np.array([integ.advance_to(float(t)) for t in times])


def test_batch_field_is_the_model_vector_field_column_by_column():
    rng = np.random.default_rng(5)
    y = np.vstack((rng.uniform(-3, 3, (2, 50)), rng.uniform(-10, 10, (2, 50))))
    batch = pendulum_field(P)(0.0, y)
    f = fixed_pivot_vector_field(P)
    single = np.array([f(0.0, list(y[:, j])) for j in range(y.shape[1])]).T
    np.testing.assert_allclose(batch, single, rtol=1e-13, atol=1e-13)
    np.testing.assert_array_equal(columnwise_field(f)(0.0, y), single)


def test_batch_rk4_equals_the_single_trajectory_rk4():
    """Same stages in the same order: only NumPy's vs math's last-bit sine differences remain."""
    times, ys = rk4_trajectory(pendulum_field(P), STARTS, 3.0, 1e-3, every=100)
    for k in range(STARTS.shape[1]):
        single = _single("rk4", STARTS[:, k], times[1:])
        assert np.max(np.abs(ys[1:, :, k] - single)) < 1e-10


def test_batch_dop853_agrees_with_the_single_dop853_and_takes_the_same_steps():
    times = np.linspace(0.1, 3.0, 30)
    batch = dop853_trajectory(pendulum_field(P), STARTS, times, rtol=1e-10, atol=1e-12)
    whole = dop853_trajectory(pendulum_field(P), STARTS, [3.0], rtol=1e-10, atol=1e-12)
    tight = dop853_trajectory(pendulum_field(P), STARTS, times, rtol=1e-13, atol=1e-15)
    for k in range(STARTS.shape[1]):
        single = _single("dop853", STARTS[:, k], times)
        # "to the tolerance": the two differ by no more than the single solver's own error (which the
        # chaotic starts amplify from 1e-10 per step to up to 1e-5 in 3 s)
        error_single = np.max(np.abs(single - tight.y[:, :, k]))
        assert np.max(np.abs(batch.y[:, :, k] - single)) <= max(10 * error_single, 1e-9)
        assert np.max(np.abs(batch.y[:, :, k] - tight.y[:, :, k])) <= max(10 * error_single, 1e-9)
        integ = make_integrator(
            "dop853",
            fixed_pivot_vector_field(P),
            0.0,
            list(STARTS[:, k]),
            rtol=1e-10,
            atol=1e-12,
            fixed_step=1,
        )
        integ.advance_to(3.0)
        # the same step-size controller: the same number of steps, up to an accept decision at err ~ 1
        assert abs(int(whole.n_steps[k]) - integ.n_steps) <= max(2, 0.02 * integ.n_steps)
    # per-trajectory control: the hard starts take many more steps than the regular one
    assert whole.n_steps[1] > 2 * whole.n_steps[0]


def test_batch_dop853_matches_the_independent_hamiltonian_reference():
    ref = read_results_csv(DATA / "reference" / "chaotic.csv")
    y0 = initial_states(ref["phi1"][0], ref["phi2"][0], ref["omega1"][0], ref["omega2"][0])
    res = dop853_trajectory(pendulum_field(P), y0, ref["time"][1:], rtol=1e-12, atol=1e-14)
    for i, name in enumerate(("phi1", "phi2", "omega1", "omega2")):
        assert np.max(np.abs(res.y[:, i, 0] - ref[name][1:])) < 1e-7


def test_a_trajectory_does_not_depend_on_the_rest_of_its_batch():
    alone = dop853_trajectory(pendulum_field(P), STARTS[:, 1:2], [1.0, 2.0])
    together = dop853_trajectory(pendulum_field(P), STARTS, [1.0, 2.0])
    np.testing.assert_allclose(together.y[:, :, 1], alone.y[:, :, 0], rtol=0, atol=1e-12)


def test_batch_integrators_conserve_the_energy_of_the_frictionless_pendulum():
    _, ys = rk4_trajectory(pendulum_field(P), STARTS, 5.0, 1e-3, every=500)
    e = np.array([batch_energy(y, P) for y in ys])
    assert np.max(np.abs(e - e[0]) / e[0]) < 1e-7
    res = dop853_trajectory(pendulum_field(P), STARTS, [5.0], rtol=1e-11, atol=1e-13)
    assert np.max(np.abs(batch_energy(res.y[-1], P) - e[0]) / e[0]) < 1e-9


def test_generalised_forces_enter_the_energy_balance():
    """With viscous joint torques Q = -c omega, dE/dt = Q . omega = -c (omega1^2 + omega2^2)."""
    c = 0.01  # N m s

    def damping(t, y):
        return -c * y[2], -c * y[3]

    h = 1e-3
    times, ys = rk4_trajectory(pendulum_field(P, damping), STARTS[:, :3], 5.0, h)
    e = batch_energy(ys.transpose(1, 0, 2), P)  # (n_t, N)
    power = -c * (ys[:, 2] ** 2 + ys[:, 3] ** 2)
    dissipated = np.concatenate(([np.zeros(3)], np.cumsum(0.5 * h * (power[1:] + power[:-1]), axis=0)))
    assert np.all(np.diff(e, axis=0) <= 1e-12)
    np.testing.assert_allclose(e - e[0], dissipated, rtol=0, atol=1e-5 * e[0].max())  # trapezoid error
    assert np.all(e[-1] < 0.99 * e[0])


def _energy_rate(field, y: np.ndarray) -> np.ndarray:
    """dE/dt = grad E . f(y) [W], by a complex step of the model's energy along the vector field."""
    return batch_energy(y + 1e-20j * field(0.0, y), P).imag / 1e-20


def test_model_field_is_the_core_field_without_friction_and_dissipates_with_it():
    y = initial_states([2.0, 0.5, 1.0], [0.0, -1.0, 2.5], [1.0, 0.0, -3.0], [-2.0, 3.0, 1.0])
    core = model_field(ModelConfig())
    np.testing.assert_array_equal(core(0.0, y), pendulum_field(P)(0.0, y))
    assert np.max(np.abs(_energy_rate(core, y))) < 1e-12  # the frictionless field conserves E exactly
    drag = model_field(ModelConfig(air=AirDragParameters(air_drag=True)))
    f = drag(0.0, y)
    np.testing.assert_array_equal(f[:2], y[2:])
    assert np.all(_energy_rate(drag, y) < -1e-6)  # air drag takes energy out of every moving state


def test_step_counts_must_divide_the_duration():
    assert n_fixed_steps(1.0, 1e-3) == 1000
    with pytest.raises(ValueError, match="whole number of steps"):
        n_fixed_steps(1.0, 3e-3)
    with pytest.raises(ValueError, match="must be > 0"):
        n_fixed_steps(1.0, 0.0)
