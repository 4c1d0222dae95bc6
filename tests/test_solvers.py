"""The integrators: tableau order conditions, convergence order, dense output, step control."""

from __future__ import annotations

import math

import numpy as np
import pytest

from double_pendulum.model.dynamics import fixed_pivot_vector_field
from double_pendulum.model.parameters import PendulumParameters
from double_pendulum.solvers import METHODS, Integrator, SolverError, make_integrator, make_method
from double_pendulum.solvers import tableaus as tb

P = PendulumParameters()
F = fixed_pivot_vector_field(P)
Y0 = [0.3, 0.3, 0.0, 0.0]  # regular motion: smooth and non-chaotic


def _dense(rows, n):
    a = np.zeros((n, n))
    for i, row in enumerate(rows[:n]):
        for j, v in row:
            a[i, j] = v
    return a


@pytest.mark.parametrize(
    ("a_rows", "b", "c", "order"),
    [
        (tb.DOPRI5_A, tb.DOPRI5_B, tb.DOPRI5_C, 5),
        (tb.DOP853_A, tb.DOP853_B, tb.DOP853_C, 8),
        (tb.RK4_A, tb.RK4_B, tb.RK4_C, 4),
    ],
)
def test_tableaus_satisfy_quadrature_and_row_sum_conditions(a_rows, b, c, order):
    n = len(b)
    a, b, c = _dense(a_rows, n), np.array(b), np.array(c[:n])
    assert a.sum(axis=1) == pytest.approx(c, abs=1e-14)  # row-sum condition
    for k in range(order):  # sum_i b_i c_i^k = 1 / (k + 1)
        assert b @ c**k == pytest.approx(1.0 / (k + 1), abs=1e-13)
    assert b @ a @ c == pytest.approx(1.0 / 6.0, abs=1e-13)  # a third-order tree


def _fixed_step_error(method, h: float, t_end: float = 1.0) -> float:
    """Global error at t_end of ``method`` with constant steps, against DOP853 at rtol 1e-13."""
    n = round(t_end / h)
    y, fy, t = list(Y0), F(0.0, Y0), 0.0
    for _ in range(n):
        y, fy, _ = method.step(F, t, y, fy, h)
        t += h
    ref = make_integrator("dop853", F, 0.0, Y0, rtol=1e-13, atol=1e-15, fixed_step=1.0).advance_to(t_end)
    return max(abs(a - b) for a, b in zip(y, ref))


@pytest.mark.parametrize(
    ("name", "steps"),
    [
        ("euler", (1e-3, 5e-4)),
        ("rk4", (2e-2, 1e-2)),
        ("dopri5", (4e-2, 2e-2)),
        ("dop853", (0.05, 0.025)),
        ("rodas4", (0.04, 0.02)),
        ("gauss4", (0.05, 0.025)),
        ("gauss2", (0.02, 0.01)),
    ],
)
def test_empirical_convergence_order_matches_theory(name, steps):
    method = make_method(name)
    e1, e2 = (_fixed_step_error(method, h) for h in steps)
    order = math.log(e1 / e2) / math.log(steps[0] / steps[1])
    assert order == pytest.approx(method.order, abs=0.5), (e1, e2)


@pytest.mark.parametrize(
    ("name", "steps"),
    [
        ("dopri5", (0.1, 0.05)),
        ("dop853", (0.1, 0.05)),
        ("rk4", (0.1, 0.05)),
        ("rodas4", (0.05, 0.025)),
        ("gauss4", (0.05, 0.025)),
        ("gauss2", (0.05, 0.025)),
    ],
)
def test_dense_output_order(name, steps):
    """Mid-step interpolation error shrinks like h^(dense_order + 1) (h in the asymptotic range)."""
    method = make_method(name)
    errors = []
    for h in steps:
        fy = F(0.0, Y0)
        y_new, f_new, stages = method.step(F, 0.0, Y0, fy, h)
        interp = method.interpolant(F, 0.0, Y0, y_new, fy, f_new, h, stages)
        exact = make_integrator("dop853", F, 0.0, Y0, rtol=1e-14, atol=1e-16, fixed_step=1.0).advance_to(
            0.37 * h
        )
        errors.append(max(abs(a - b) for a, b in zip(interp(0.37), exact)))
    order = math.log(errors[0] / errors[1]) / math.log(2.0)
    assert order >= method.dense_order + 1 - 0.5, errors


@pytest.mark.parametrize(
    ("name", "rtol"),
    [("dopri5", 1e-6), ("dopri5", 1e-9), ("dop853", 1e-6), ("dop853", 1e-9), ("rodas4", 1e-6), ("rodas4", 1e-8)],
)
def test_adaptive_solvers_meet_their_tolerance_on_the_regular_case(name, rtol):
    it = make_integrator(name, F, 0.0, Y0, rtol=rtol, atol=rtol * 1e-2, fixed_step=1.0)
    ref = make_integrator("dop853", F, 0.0, Y0, rtol=1e-13, atol=1e-15, fixed_step=1.0)
    worst = max(
        max(abs(a - b) for a, b in zip(it.advance_to(t), ref.advance_to(t)))
        for t in np.arange(0.5, 5.01, 0.5)
    )
    assert worst <= 50 * rtol  # global error over ~4 periods stays within a small multiple of rtol


def test_output_times_do_not_change_the_steps():
    """Asking for output at 1 ms or 50 ms gives the same trajectory (dense output)."""
    a = make_integrator("dop853", F, 0.0, [2.0, 2.0, 0.0, 0.0], rtol=1e-10, atol=1e-12, fixed_step=1.0)
    b = make_integrator("dop853", F, 0.0, [2.0, 2.0, 0.0, 0.0], rtol=1e-10, atol=1e-12, fixed_step=1.0)
    for k in range(1, 3001):
        a.advance_to(k * 1e-3)
    for k in range(1, 61):
        b.advance_to(k * 0.05)
    assert a.n_steps == b.n_steps
    assert a.state_at(3.0) == b.state_at(3.0)


def test_state_round_trip_continues_bit_identically():
    ref = make_integrator("dopri5", F, 0.0, [2.0, 2.0, 0.0, 0.0], rtol=1e-8, atol=1e-10, fixed_step=1.0)
    ref.advance_to(1.0)
    saved = ref.get_state()
    expected = ref.advance_to(2.5)
    other = make_integrator("dopri5", F, 0.0, [0.0, 0.0, 0.0, 0.0], rtol=1e-8, atol=1e-10, fixed_step=1.0)
    other.set_state(saved)
    assert other.advance_to(2.5) == expected


def test_step_size_underflow_is_reported_not_hung():
    """y' = y^2, y(0) = 1 blows up at t = 1: the integrator must stop with a clear error."""
    it = Integrator(lambda t, y: [y[0] * y[0]], 0.0, [1.0], make_method("dopri5"), rtol=1e-8, atol=1e-10)
    with pytest.raises(SolverError, match="step size underflow|non-finite"):
        it.advance_to(2.0)


def test_step_budget_stops_an_endless_run():
    it = make_integrator("dopri5", F, 0.0, Y0, rtol=1e-8, atol=1e-10, fixed_step=1.0, max_steps_per_call=10)
    with pytest.raises(SolverError, match="more than 10 steps"):
        it.advance_to(100.0)


def test_cannot_go_back_in_time():
    it = make_integrator("rk4", F, 0.0, Y0, rtol=1e-8, atol=1e-10, fixed_step=1e-2)
    it.advance_to(1.0)
    with pytest.raises(SolverError, match="cannot return"):
        it.advance_to(0.5)


def test_registry_names():
    assert set(METHODS) >= {"dop853", "dopri5", "rk4", "euler"}


def test_landing_ends_the_last_step_on_the_output_time_without_dense_output():
    free = make_integrator("dop853", F, 0.0, Y0, rtol=1e-10, atol=1e-12, fixed_step=1.0)
    landed = make_integrator("dop853", F, 0.0, Y0, rtol=1e-10, atol=1e-12, fixed_step=1.0)
    for k in range(1, 40):
        t = k * 1e-3 * math.pi  # a time no step reaches by rounding
        expected = free.advance_to(t)
        got = landed.advance_to(t, land=True)
        assert landed.t == t  # exactly: no sliver left, no step past t
        assert max(abs(a - b) for a, b in zip(got, expected)) < 1e-9
    # no dense output was evaluated: at most 12 evaluations per step (and the start's 2)
    assert landed.nfev <= 2 + 12 * (landed.n_steps + landed.n_rejected)
    assert landed.fy is None  # the last landed step's f(t, y) waits until needed
    assert max(abs(a - b) for a, b in zip(landed.advance_to(0.2), free.advance_to(0.2))) < 1e-9


def test_deferred_f_new_of_a_landed_step_is_evaluated_for_dense_output():
    it = make_integrator("dop853", F, 0.0, Y0, rtol=1e-10, atol=1e-12, fixed_step=1.0)
    it.advance_to(0.05, land=True)
    ref = make_integrator("dop853", F, 0.0, Y0, rtol=1e-10, atol=1e-12, fixed_step=1.0)
    ref.advance_to(0.05, land=True)
    ref._complete_fy()
    mid = 0.5 * (it.t_prev + it.t)
    assert it.state_at(mid) == ref.state_at(mid)
    assert it.fy == F(it.t, it.y)


@pytest.mark.parametrize(
    ("a_rows", "c", "stages", "b"),
    [(tb.DOPRI5_A, tb.DOPRI5_C, 6, tb.DOPRI5_B), (tb.DOP853_A, tb.DOP853_C, 12, tb.DOP853_B),
     (tb.RK4_A, tb.RK4_C, 4, tb.RK4_B)],  # fmt: skip
)
def test_fused_stages_are_bit_identical_to_the_stage_by_stage_loop(a_rows, c, stages, b):
    from double_pendulum.solvers.combinations import explicit_stages, sparse, step_combination

    y, h, t = [2.0, -1.0, 0.7, 3.1, 0.25], 3e-3, 0.4
    f = fixed_pivot_vector_field(P)

    def field(t, y):  # a fifth state, as the driven pendulum's W_input
        return [*f(t, y[:4]), y[2] * y[3]]

    ks = [field(t, y)]
    for i in range(1, stages):
        ks.append(field(t + c[i] * h, step_combination(tuple(a_rows[i]), 5)(y, h, ks)))
    loop = step_combination(sparse(b), 5)(y, h, ks)
    fused, fused_ks = explicit_stages(a_rows, tuple(c), stages, sparse(b), 5)(field, t, y, ks[0], h)
    assert fused == loop and fused_ks == ks


@pytest.mark.parametrize("weights", [tb.DOPRI5_E, tb.DOP853_E5])
def test_compiled_error_norm_equals_the_loop(weights):
    from double_pendulum.solvers.combinations import scaled_error_norm, sparse, weighted_sum
    from double_pendulum.solvers.runge_kutta import scaled_rms

    rng = np.random.default_rng(3)
    ks = [list(rng.normal(size=5)) for _ in weights]
    y, y_new = list(rng.normal(size=5)), list(rng.normal(size=5))
    h, rtol, atol = 2e-3, 1e-9, 1e-12
    expected = scaled_rms([h * e for e in weighted_sum(sparse(weights), 5)(ks)], y, y_new, rtol, atol)
    assert scaled_error_norm(sparse(weights), 5)(y, y_new, ks, h, rtol, atol) == expected


def _restarted_landings(rtol: float, steps: int = 200, h_comm: float = 1e-3) -> Integrator:
    """DOP853 on the regular case, restarted at every communication point and landing on the next."""
    it = make_integrator("dop853", F, 0.0, Y0, rtol=rtol, atol=rtol * 1e-3, fixed_step=1.0)
    it.advance_to(0.05)  # the controller's step grows well beyond 1 ms
    t = 0.05
    for _ in range(steps):
        it.restart(t, it.state_at(t))
        it.advance_to(t + h_comm, land=True)
        t += h_comm
    return it


def test_a_short_landing_step_is_one_dopri5_step_within_the_tolerance_per_unit_step():
    it = _restarted_landings(1e-9)
    n0 = it.n_steps
    assert it.landing_method.name == "dopri5" and it.last_method is it.landing_method
    ref = make_integrator("dop853", F, 0.0, Y0, rtol=1e-13, atol=1e-15, fixed_step=1.0).advance_to(it.t)
    assert max(abs(a - b) for a, b in zip(it.y, ref)) < 1e-9
    before = it.nfev
    it.restart(it.t, list(it.y))
    it.advance_to(it.t + 1e-3, land=True)
    assert it.nfev - before == 1 + 6  # f(t, y) at the restart, then Dopri5's six further stages
    assert it.n_steps > n0 and it.h > 1e-3  # the controller's own step size is kept


def test_a_landing_step_whose_error_per_unit_step_is_too_large_falls_back_to_dop853():
    it = _restarted_landings(1e-14, steps=40)
    assert it.n_rejected > 0 and it.landing_rest > 0  # Dopri5 failed err <= H / h, now rests
    before = it.nfev
    it.restart(it.t, list(it.y))
    it.advance_to(it.t + 1e-3, land=True)
    assert it.nfev - before >= 1 + 11 and it.last_method is it.method  # DOP853 took the step
