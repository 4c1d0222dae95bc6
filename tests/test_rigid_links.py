"""Rigid links (rods with mass) and the bearing drag torque, against an independent formulation.

The independent formulation (``independent_lagrangian.py``) assembles Lagrange's equations
numerically from positions of mass points; it shares no formula with the package. The point-mass
model is checked against results recorded before the rods existed (``data/point_mass_golden.json``:
the in-process component of commit f3d385d run with the file's start values and switches, every
model output at its output times): with ``m_rod1 = m_rod2 = 0`` every output must be bit-identical
(:func:`_run_golden_scene` re-runs a scene; rod drag then needs plates of joint-to-joint length,
the rod of the earlier model).
"""

from __future__ import annotations

import json
import math
import random

import numpy as np
import pytest
from conftest import REPO
from independent_lagrangian import IndependentPendulum
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from double_pendulum.fmu.masters.simulate import simulate
from double_pendulum.model.dynamics import fixed_pivot_vector_field, linearised_normal_modes
from double_pendulum.model.links import link_coefficients, plate_lengths
from double_pendulum.model.parameters import (
    SEED_RIGID_LINKS,
    AirDragParameters,
    BearingParameters,
    PendulumParameters,
    SuspensionParameters,
)
from double_pendulum.model.vector_field import ModelConfig, build_model, energies, state_layout

GOLDEN = json.loads((REPO / "tests" / "data" / "point_mass_golden.json").read_text())
RECORDED_DEFAULTS = {"cw_rod": 2.0}
"""Defaults that changed after the recording (cw_rod: 2 face-on, now 1.2 edge-on), passed as recorded."""
RIGID = PendulumParameters(**SEED_RIGID_LINKS)
# Heavy, long-overhanging rods make every rod term count (rod masses comparable to the bobs).
HEAVY = PendulumParameters(m_rod1=0.25, m_rod2=0.15, L_rod1=0.45, L_rod2=0.33)
SUSPENSION = SuspensionParameters(suspension=True, M_s=0.8, k_x=3e3, k_y=5e3, c_x=4.0, c_y=7.0)
SCENES = {
    "fixed pivot": ModelConfig(pendulum=HEAVY),
    "suspension": ModelConfig(pendulum=HEAVY, suspension=SUSPENSION),
    "suspension_y": ModelConfig(
        pendulum=HEAVY, suspension=SuspensionParameters(suspension=True, suspension_x=False, c_y=9.0)
    ),
    "air and rods": ModelConfig(
        pendulum=HEAVY, air=AirDragParameters(air_drag=True, rod_drag=True, rho_air=50.0), suspension=SUSPENSION
    ),
    "bearings": ModelConfig(
        pendulum=HEAVY,
        bearing=BearingParameters(
            bearing_friction=True, c_R1=0.05, c_R2=0.08, r_b1=0.01, r_b2=0.02, omega_reg=0.5, b_v1=1e-3,
            b_v2=2e-3, bearing_drag=True, tau_b1=0.02, tau_b2=0.03,
        ),
        air=AirDragParameters(air_drag=True, rod_drag=True, rho_air=50.0),
        suspension=SUSPENSION,
    ),  # fmt: skip
}


def _random_state(config: ModelConfig, rng: random.Random) -> list[float]:
    ranges = {"phi1": 3.0, "phi2": 3.0, "omega1": 5.0, "omega2": 8.0, "xs": 1e-2, "ys": 1e-2, "vxs": 0.3, "vys": 0.3}
    return [rng.uniform(-ranges[n], ranges[n]) if n in ranges else 0.0 for n in state_layout(config).names]


def _coordinates(config: ModelConfig, y: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """``q = (phi1, phi2, xs, ys)`` and its rates from a state vector."""
    layout = state_layout(config)
    ix, iy = layout.index("xs"), layout.index("ys")
    q = np.array([y[0], y[1], y[ix] if ix is not None else 0.0, y[iy] if iy is not None else 0.0])
    qd = np.array([y[2], y[3], y[ix + 1] if ix is not None else 0.0, y[iy + 1] if iy is not None else 0.0])
    return q, qd


def _bearing_forces(config: ModelConfig, ind: IndependentPendulum, q, qd, qdd) -> np.ndarray:
    """Generalised forces of all bearing torques, with the loads the independent bodies carry."""
    b = config.bearing
    tau_p = tau_e = 0.0
    w_p, w_e = qd[0], qd[1] - qd[0]
    if b.bearing_friction:
        pivot, elbow = ind.joint_loads(q, qd, qdd)
        tau_p += b.c_R1 * b.r_b1 * np.hypot(*pivot) * math.tanh(w_p / b.omega_reg) + b.b_v1 * w_p
        tau_e += b.c_R2 * b.r_b2 * np.hypot(*elbow) * math.tanh(w_e / b.omega_reg) + b.b_v2 * w_e
    if b.bearing_drag:
        tau_p += b.tau_b1 * math.tanh(w_p / b.omega_reg)
        tau_e += b.tau_b2 * math.tanh(w_e / b.omega_reg)
    return ind.joint_torque_forces(tau_p, tau_e)


@pytest.mark.parametrize("scene", list(SCENES))
def test_accelerations_and_pivot_force_match_the_independent_lagrangian(scene):
    """At random states: angular and pivot accelerations, and the pivot force, to 1e-9 relative."""
    config = SCENES[scene]
    model, ind = build_model(config), IndependentPendulum(config)
    rng = random.Random(11)
    for _ in range(6):
        y = _random_state(config, rng)
        ev = model.evaluate(y)
        q, qd = _coordinates(config, y)
        qdd = np.array([ev.alpha1, ev.alpha2, ev.axs, ev.ays])
        forces = ind.air_forces(q, qd)[0] + ind.damping_forces(qd) + _bearing_forces(config, ind, q, qd, qdd)
        expected = ind.accelerations(q, qd, forces)
        got = qdd[ind.free]
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9 * np.max(np.abs(expected)))
        pivot, _ = ind.joint_loads(q, qd, qdd)
        np.testing.assert_allclose([ev.f_pivot_x, ev.f_pivot_y], -pivot, rtol=1e-9, atol=1e-9 * np.hypot(*pivot))


@pytest.mark.parametrize("scene", ["fixed pivot", "suspension"])
def test_energies_match_the_independent_bodies(scene):
    config = SCENES[scene]
    ind = IndependentPendulum(config)
    rng = random.Random(5)
    for _ in range(10):
        y = _random_state(config, rng)
        q, qd = _coordinates(config, y)
        e_kin, e_pot, e_sus = energies(config, y)
        s = config.suspension
        springs = 0.5 * s.k_x * q[2] ** 2 + 0.5 * s.k_y * q[3] ** 2 if s.suspension else 0.0
        mass_s = 0.5 * s.M_s * (qd[2] ** 2 + qd[3] ** 2) if s.suspension else 0.0
        assert e_kin == pytest.approx(ind.kinetic(q, qd) - mass_s, rel=1e-12)
        assert e_pot == pytest.approx(ind.potential(q) - springs, rel=1e-12, abs=1e-14)
        assert e_sus == pytest.approx(mass_s + springs, rel=1e-12, abs=1e-15)


def test_coefficients_are_the_derived_formulas_and_reduce_to_point_masses():
    p = HEAVY
    c = link_coefficients(p)
    m1, m2, r1, r2, l1, l2 = p.m1, p.m2, p.m_rod1, p.m_rod2, p.l1, p.l2
    assert c.j1 == pytest.approx((m1 + m2 + r2) * l1**2 + r1 * (p.L_rod1**2 / 12 + l1**2 / 4), rel=1e-15)
    assert c.j2 == pytest.approx(m2 * l2**2 + r2 * (p.L_rod2**2 / 12 + l2**2 / 4), rel=1e-15)
    assert c.k == pytest.approx((m2 + r2 / 2) * l1 * l2, rel=1e-15)
    assert c.s1 == pytest.approx((m1 + m2 + r2 + r1 / 2) * l1, rel=1e-15)
    assert c.s2 == pytest.approx((m2 + r2 / 2) * l2, rel=1e-15)
    assert c.mass == pytest.approx(m1 + m2 + r1 + r2, rel=1e-15)
    point = link_coefficients(PendulumParameters(L_rod1=0.9, L_rod2=0.7))  # massless rods: length irrelevant
    q = PendulumParameters()
    assert point.j1 == (q.m1 + q.m2) * q.l1 * q.l1 and point.k == q.m2 * q.l1 * q.l2
    assert point.gs1 == (q.m1 + q.m2) * q.g * q.l1 and point.gs2 == q.m2 * q.g * q.l2


def _run_golden_scene(name: str) -> np.ndarray:
    """Re-run a recorded scene with the default parameters (massless rods, plates joint to joint)."""
    switches = GOLDEN["scenes"][name]
    return simulate(
        {**GOLDEN["start"], **RECORDED_DEFAULTS, **switches},
        stop_time=GOLDEN["stop_time"],
        output_interval=GOLDEN["output_interval"],
    )


def test_default_plates_span_joint_to_joint():
    p = PendulumParameters()
    assert p.L_rod1 == p.L_rod2 == 0.0
    assert plate_lengths(p) == (p.l1, p.l2)
    assert plate_lengths(RIGID) == (0.35, 0.25)


def test_massless_rods_of_any_length_give_the_point_mass_arithmetic():
    """A plate length matters to massless rods only through their drag."""
    name = "bearing"
    result = simulate(
        {**GOLDEN["start"], **RECORDED_DEFAULTS, **GOLDEN["scenes"][name], "L_rod1": 0.5, "L_rod2": 0.4},
        stop_time=GOLDEN["stop_time"],
        output_interval=GOLDEN["output_interval"],
    )
    for quantity, recorded in GOLDEN["results"][name].items():
        assert [float(v) for v in result[quantity]] == recorded, quantity


@pytest.mark.parametrize("scene", list(GOLDEN["scenes"]))
def test_massless_rods_are_bit_identical_to_the_point_mass_model(scene):
    """Every output, exactly: the rigid-link arithmetic adds exact zeros for zero rod mass."""
    result = _run_golden_scene(scene)
    for name, recorded in GOLDEN["results"][scene].items():
        assert [float(v) for v in result[name]] == recorded, name


def test_massless_rods_are_bit_identical_through_the_fmu(runner):
    name = "all"
    switches = GOLDEN["scenes"][name]
    r = runner.simulate(
        {**GOLDEN["start"], **RECORDED_DEFAULTS, **switches},
        stop_time=GOLDEN["stop_time"],
        output_interval=GOLDEN["output_interval"],
    )
    for quantity, recorded in GOLDEN["results"][name].items():
        assert [float(v) for v in r[quantity]] == recorded, quantity


@pytest.mark.parametrize("start", [(0.4, -0.3, 0.0, 1.0), (2.0, 2.0, 0.0, 0.0)])
def test_trajectory_matches_the_independent_lagrangian(start):
    """Fixed pivot, seed rods, 1 s: the FMU component against SciPy's DOP853 on the independent equations, at
    rtol = atol = 1e-10: within 2.2e-9 of its solution at 1e-12, a ninth of the 2e-8 tolerance, for 60 % of the
    CPU (the independent equations cost 1.8 ms a call, 1,000 calls instead of 1,700-1,900)."""
    config = ModelConfig(pendulum=RIGID)
    ind = IndependentPendulum(config)
    zeros = np.zeros(4)

    def rhs(t, z):
        q, qd = np.array([z[0], z[1], 0.0, 0.0]), np.array([z[2], z[3], 0.0, 0.0])
        return [z[2], z[3], *ind.accelerations(q, qd, zeros)]

    times = np.linspace(0.0, 1.0, 11)
    ref = solve_ivp(rhs, (0.0, 1.0), start, method="DOP853", rtol=1e-10, atol=1e-10, t_eval=times).y
    r = simulate(
        {**SEED_RIGID_LINKS, **dict(zip(("phi1_0", "phi2_0", "omega1_0", "omega2_0"), start)), "rtol": 1e-12},
        stop_time=1.0,
        output_interval=0.1,
    )
    for k, name in enumerate(("phi1", "phi2", "omega1", "omega2")):
        np.testing.assert_allclose(r[name], ref[k], rtol=0.0, atol=2e-8 * max(1.0, np.max(np.abs(ref[k]))))


def test_rigid_pendulum_conserves_energy_through_the_fmu(runner):
    """Seed rods, chaotic start, 10 s, dop853 at rtol 1e-10: relative energy drift below 1e-8."""
    r = runner.simulate(
        {**SEED_RIGID_LINKS, "phi1_0": 2.0, "phi2_0": 2.0, "rtol": 1e-10, "atol": 1e-12},
        stop_time=10.0,
        output_interval=0.01,
    )
    e = r["E_total"]
    assert np.max(np.abs(e - e[0])) <= 1e-8 * e[0]
    # the rods count: the same start with massless rods has a different energy
    assert e[0] != pytest.approx(simulate({"phi1_0": 2.0, "phi2_0": 2.0}, stop_time=0.0)["E_total"][0], rel=1e-2)


def test_rigid_pendulum_on_an_undamped_suspension_conserves_energy(runner):
    r = runner.simulate(
        {**SEED_RIGID_LINKS, "phi1_0": 1.5, "phi2_0": 1.0, "suspension": True, "c_x": 0.0, "c_y": 0.0,
         "k_x": 5e3, "k_y": 5e3, "rtol": 1e-10, "atol": 1e-12},
        stop_time=5.0,
        output_interval=0.01,
    )  # fmt: skip
    e = r["E_total"]
    assert np.max(np.abs(e - e[0])) <= 1e-8 * e[0]
    assert np.max(r["E_suspension"]) > 1e-6


@pytest.mark.parametrize("params", [RIGID, HEAVY], ids=["seed rods", "heavy rods"])
def test_normal_modes_solve_the_independent_linearised_problem(params):
    """det(K - w^2 M0) = 0 with M0 and K from the independent T and V, and the Jacobian's eigenvalues."""
    (w_slow, w_fast), shapes = linearised_normal_modes(params)
    ind = IndependentPendulum(ModelConfig(pendulum=params))
    rest = np.zeros(4)
    m0 = ind.mass_matrix(rest)
    stiffness = np.empty((2, 2))
    for i in range(2):
        for j in range(2):
            ei, ej = np.eye(4)[i], np.eye(4)[j]
            stiffness[i, j] = ind.derivative(
                lambda h, ei=ei, ej=ej: ind.derivative(lambda k: ind.potential(h * ei + k * ej))
            )
    expected = np.sqrt(eigh(stiffness, m0, eigvals_only=True))
    assert [w_slow, w_fast] == pytest.approx(expected, rel=1e-8)
    f = fixed_pivot_vector_field(params)
    h = 1e-7
    jac = np.array(
        [(np.array(f(0.0, list(h * e))) - np.array(f(0.0, list(-h * e)))) / (2 * h) for e in np.eye(4)]
    ).T
    numeric = np.sort(np.abs(np.linalg.eigvals(jac).imag))[::2]
    assert numeric == pytest.approx([w_slow, w_fast], rel=1e-7)
    assert shapes[0][1] > 0 > shapes[1][1]


def test_seed_rods_barely_move_the_frequencies_but_raise_the_energy_scale():
    """The plates' centres sit halfway up their links: g S / J changes little (frequencies +1.0 %
    and +0.3 %: 4.857 and 11.934 rad/s), but J1 and g S1 grow by 16 % and 18 %, so energies
    computed from a track with point masses come out too low by about that much."""
    (p_slow, p_fast), _ = linearised_normal_modes(PendulumParameters())
    (r_slow, r_fast), _ = linearised_normal_modes(RIGID)
    assert r_slow / p_slow - 1.0 == pytest.approx(0.010, abs=0.001)
    assert r_fast / p_fast - 1.0 == pytest.approx(0.003, abs=0.001)
    rods, points = link_coefficients(RIGID), link_coefficients(PendulumParameters())
    assert rods.j1 / points.j1 - 1.0 == pytest.approx(0.16, abs=0.01)
    assert rods.gs1 / points.gs1 - 1.0 == pytest.approx(0.18, abs=0.01)


def test_seed_preset_is_valid_and_overhangs_both_joints():
    p = RIGID
    assert p.m_rod1 == p.m_rod2 == 0.070
    for plate, length in ((p.L_rod1, p.l1), (p.L_rod2, p.l2)):
        assert 0.02 < (plate - length) / 2 < 0.03  # about 2.7 cm past each joint


def test_bearing_drag_dissipates_tau_omega_tanh():
    brg = BearingParameters(bearing_drag=True, tau_b1=1e-3, tau_b2=2e-3, omega_reg=0.1)
    model = build_model(ModelConfig(pendulum=RIGID, bearing=brg))
    assert model.layout.names[-1] == "W_bearing_drag"
    for y in ([1.0, 0.5, 2.0, -1.0], [-2.5, 2.0, -0.04, 0.03]):
        ev = model.evaluate(y + [0.0])
        w1, we = y[2], y[3] - y[2]
        expected = 1e-3 * math.tanh(w1 / 0.1) * w1 + 2e-3 * math.tanh(we / 0.1) * we
        assert ev.p_bearing_drag == pytest.approx(expected, rel=1e-14)
        assert ev.dydt[-1] == ev.p_bearing_drag and ev.p_bearing == 0.0


def test_bearing_drag_loss_per_cycle_is_amplitude_independent_so_decay_is_linear(runner):
    """A constant torque takes a fixed energy per swing: E falls linearly (p = 0.5 in dE/dt ~ E^p)."""
    r = runner.simulate(
        {**SEED_RIGID_LINKS, "phi1_0": 0.3, "phi2_0": 0.3, "bearing_drag": True, "tau_b1": 2e-3,
         "omega_reg": 1e-3, "rtol": 1e-9},
        stop_time=20.0,
        output_interval=0.01,
    )  # fmt: skip
    e = r["E_total"]
    assert np.all(np.diff(e) <= 1e-9 * e[0])
    assert np.max(np.abs(r["energy_residual"])) <= 1e-7 * e[0]
    assert r["W_bearing_drag"][-1] > 0.1 * e[0]
    # amplitude (sqrt E) decays linearly in time: the mean slope of sqrt(E) over the two halves agrees
    amp = np.sqrt(e)
    half = len(amp) // 2
    first, second = amp[0] - amp[half], amp[half] - amp[-1]
    assert second == pytest.approx(first, rel=0.15)


def test_batch_field_for_ensembles_has_the_rods_too():
    """The NumPy ensemble field (chaos, maps) uses the same rigid-link accelerations as the FMU's core."""
    from double_pendulum.analysis.chaos.ensemble import pendulum_field

    rng = np.random.default_rng(3)
    states = rng.uniform(-3, 3, size=(4, 20))
    batch = pendulum_field(HEAVY)(0.0, states)
    scalar = fixed_pivot_vector_field(HEAVY)
    for k in range(states.shape[1]):
        assert batch[:, k] == pytest.approx(scalar(0.0, list(states[:, k])), rel=1e-13, abs=1e-13)


def test_fmu_agrees_with_the_committed_rigid_reference_trajectory(runner):
    """data/reference/rigid_chaotic.csv: Hamilton's equations with the plates summed over mass points."""
    from double_pendulum.runs.results_io import read_results_csv

    meta = json.loads((REPO / "data" / "reference" / "reference_meta.json").read_text())["cases"]["rigid_chaotic"]
    assert meta["rods"] == dict(SEED_RIGID_LINKS)
    ref = read_results_csv(REPO / "data" / "reference" / "rigid_chaotic.csv")
    start = {**meta["rods"], **meta["start"], "rtol": 1e-12, "atol": 1e-14}
    r = runner.simulate(start, stop_time=float(ref["time"][-1]), output_interval=0.01)
    for name in ("phi1", "phi2", "omega1", "omega2"):
        np.testing.assert_allclose(r[name], ref[name], atol=1e-7, rtol=0)
