"""The implicit integrators: RODAS4 for stiff scenes, Gauss-Legendre for long frictionless runs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from double_pendulum.model.dynamics import fixed_pivot_vector_field
from double_pendulum.model.parameters import PendulumParameters, SuspensionParameters
from double_pendulum.model.vector_field import ModelConfig, build_model, energies
from double_pendulum.solvers import METHODS, Integrator, SolverError, make_integrator, make_method
from double_pendulum.solvers.linalg import SingularMatrixError, lu_factor, lu_solve

P = PendulumParameters()
F = fixed_pivot_vector_field(P)
Y0 = [0.3, 0.3, 0.0, 0.0]  # regular motion: smooth and non-chaotic
# A light, stiff, moderately damped suspension: fast mode ~3900 rad/s, decaying in ~6 ms.
STIFF = build_model(
    ModelConfig(
        suspension=SuspensionParameters(suspension=True, M_s=0.05, k_x=1e7, k_y=1e7, c_x=200.0, c_y=200.0)
    )
)
STIFF_Y0 = STIFF.initial_state(0.3, 0.3, 0.0, 0.0)


def _reference(t_end: float, y0: list[float] = Y0) -> list[float]:
    return make_integrator("dop853", F, 0.0, y0, rtol=1e-13, atol=1e-15, fixed_step=1.0).advance_to(t_end)


def _max_diff(a: list[float], b: list[float]) -> float:
    return max(abs(u - v) for u, v in zip(a, b))


# ---------------------------------------------------------------------------------------------- linalg
def test_lu_solves_systems_that_need_pivoting():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(9, 9))
    a[0, 0] = 0.0  # no LU without row exchanges
    b = rng.normal(size=9)
    x = lu_solve(lu_factor(a.tolist()), b.tolist())
    assert np.allclose(x, np.linalg.solve(a, b), rtol=1e-12, atol=1e-12)


def test_lu_reports_a_singular_matrix():
    with pytest.raises(SingularMatrixError):
        lu_factor([[1.0, 2.0], [2.0, 4.0]])


# ---------------------------------------------------------------------------------------------- rodas4
def test_rodas4_takes_far_fewer_steps_than_dop853_on_the_stiff_suspension():
    """Step counts are deterministic; the explicit method is held at its stability limit."""
    runs = {}
    for name in ("rodas4", "dop853"):
        it = make_integrator(name, STIFF.vector_field, 0.0, STIFF_Y0, rtol=1e-6, atol=1e-9, fixed_step=1.0)
        runs[name] = (it.advance_to(2.0), it)
    (y_stiff, stiff), (y_explicit, explicit) = runs["rodas4"], runs["dop853"]
    assert explicit.n_steps > 8 * stiff.n_steps, (stiff.n_steps, explicit.n_steps)
    assert explicit.nfev > 4 * stiff.nfev, (stiff.nfev, explicit.nfev)
    assert _max_diff(y_stiff[:4], y_explicit[:4]) < 1e-5  # the angles and rates agree


def test_rodas4_damps_a_stiff_oscillator_with_few_steps():
    """y'' = -(k/m) y - (c/m) y', k/m = 1e8, damping ratio 0.5: the fast mode dies out, the steps grow."""
    omega = 1e4

    def oscillator(t: float, y: list[float]) -> list[float]:
        return [y[1], -omega * omega * y[0] - omega * y[1]]

    counts = {}
    for name in ("rodas4", "dop853"):
        it = Integrator(oscillator, 0.0, [1e-3, 0.0], make_method(name), rtol=1e-6, atol=1e-9)
        y = it.advance_to(2.0)
        assert abs(y[0]) < 1e-9
        counts[name] = it.n_steps
    assert counts["dop853"] > 10 * counts["rodas4"], counts


def test_rodas4_counts_every_evaluation():
    """``nfev`` includes the Jacobians, and a rejected step reuses its Jacobian."""
    calls = [0]

    def counted(t: float, y: list[float]) -> list[float]:
        calls[0] += 1
        return STIFF.vector_field(t, y)

    it = make_integrator("rodas4", counted, 0.0, STIFF_Y0, rtol=1e-6, atol=1e-9, fixed_step=1.0)
    it.advance_to(0.2)
    assert it.n_rejected > 0
    assert it.nfev == calls[0]
    # f(t0, y0) and the initial step guess, 6 per attempt, one Jacobian (n + 1) per accepted step only
    attempts = it.n_steps + it.n_rejected
    assert it.nfev == 2 + 6 * attempts + (len(STIFF_Y0) + 1) * it.n_steps


def test_rodas4_singular_iteration_matrix_gives_a_rejected_step():
    """``1/(h gamma)`` an eigenvalue of J: the step is non-finite, so the integrator shrinks h."""
    method = make_method("rodas4")
    y_new, _, stages = method.step(lambda t, y: [8.0 * y[0]], 0.0, [0.0], [0.0], 0.5)  # 1/(0.5 * 0.25) = 8
    assert not math.isfinite(y_new[0])
    assert not method.error_norm([0.0], y_new, stages, 0.5, 1e-6, 1e-9) <= 1.0


# ---------------------------------------------------------------------------------------------- gauss
def _energy_errors(name: str, t_end: float, window: float, **settings) -> tuple[float, float]:
    """Largest |E - E0| [J] at the steps within the first and within the last ``window`` seconds."""
    config = ModelConfig(pendulum=P)
    e0 = sum(energies(config, Y0))
    it = make_integrator(name, F, 0.0, Y0, **settings)
    first = last = 0.0
    while it.t < t_end:
        it.step()
        error = abs(sum(energies(config, it.y)) - e0)
        if it.t <= window:
            first = max(first, error)
        elif it.t >= t_end - window:
            last = max(last, error)
    return first, last


def test_gauss4_energy_error_stays_bounded_over_200_s_while_dop853_drifts():
    """First and last 20 s of 200 s (1.4 s of CPU; 400 s took 2.9 s): Gauss's error ends within 1 % of where it
    started (1.8e-9 J), DOP853's grows 7.6 times (9.2 times over 400 s)."""
    first, last = _energy_errors("gauss4", 200.0, 20.0, rtol=1.0, atol=1.0, fixed_step=0.02)
    assert last <= 2.0 * first
    assert last < 1e-8  # J, of E0 = 0.103 J
    first, last = _energy_errors("dop853", 200.0, 20.0, rtol=1e-6, atol=1e-9, fixed_step=1.0)
    assert last > 5.0 * first  # the explicit method's energy error grows about linearly (7.6 times here)


def test_gauss_stage_iteration_failure_raises_solver_error():
    """The fixed-point iteration cannot converge on the stiff suspension at a 10 ms step."""
    it = make_integrator("gauss4", STIFF.vector_field, 0.0, STIFF_Y0, rtol=1.0, atol=1.0, fixed_step=0.01)
    with pytest.raises(SolverError, match="did not converge"):
        it.advance_to(0.1)


# ---------------------------------------------------------------------------------------------- state
@pytest.mark.parametrize(
    ("name", "f", "y0", "settings"),
    [
        ("rodas4", STIFF.vector_field, STIFF_Y0, {"rtol": 1e-6, "atol": 1e-9, "fixed_step": 1.0}),
        ("gauss4", F, [2.0, 2.0, 0.0, 0.0], {"rtol": 1.0, "atol": 1.0, "fixed_step": 0.005}),
        ("gauss2", F, [2.0, 2.0, 0.0, 0.0], {"rtol": 1.0, "atol": 1.0, "fixed_step": 0.002}),
    ],
)
def test_state_round_trip_continues_bit_identically(name, f, y0, settings):
    ref = make_integrator(name, f, 0.0, y0, **settings)
    ref.advance_to(0.3)
    saved = json.loads(json.dumps(ref.get_state()))  # as the FMU serialises it
    expected = [ref.advance_to(t) for t in (0.45, 0.6)]
    other = make_integrator(name, f, 0.0, [0.0] * len(y0), **settings)
    other.set_state(saved)
    assert [other.advance_to(t) for t in (0.45, 0.6)] == expected
    assert (other.nfev, other.n_steps, other.n_rejected) == (ref.nfev, ref.n_steps, ref.n_rejected)


def test_registry_names():
    assert set(METHODS) >= {"rodas4", "gauss4", "gauss2"}


@pytest.mark.parametrize("solver", ["rodas4", "gauss4"])
def test_cosimulation_state_round_trip_with_the_implicit_solvers(solver):
    """The FMU's get/set state (serialised as JSON) continues bit-identically with the new methods."""
    from double_pendulum.component.cosimulation import DoublePendulumCoSimulation

    def start() -> DoublePendulumCoSimulation:
        sim = DoublePendulumCoSimulation()
        settings = {"phi1_0": 0.3, "phi2_0": 0.3, "solver": solver, "rtol": 1e-6, "atol": 1e-9}
        if solver == "rodas4":
            settings.update(suspension=True, M_s=0.05, k_x=1e7, k_y=1e7, c_x=200.0, c_y=200.0)
        else:
            settings.update(fixed_step=0.01)
        for name, value in settings.items():
            sim.set(name, value)
        sim.initialise()
        return sim

    def run(sim: DoublePendulumCoSimulation, t0: float, n: int) -> list[dict[str, float]]:
        rows = []
        for k in range(n):
            sim.do_step(t0 + k * 0.05, 0.05)
            rows.append(dict(sim.outputs))
        return rows

    original = start()
    run(original, 0.0, 4)
    saved = json.loads(json.dumps(original.get_state()))
    expected = run(original, 0.2, 4)
    restored = DoublePendulumCoSimulation()
    restored.set_state(saved)
    assert run(restored, 0.2, 4) == expected
