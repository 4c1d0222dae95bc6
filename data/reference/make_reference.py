"""Generate the committed reference trajectories in ``data/reference/``.

Independent of the package's equations of motion: the reference integrates Hamilton's
equations in canonical momenta, with the Hamiltonian assembled numerically from the kinetic
energy's mass matrix (seed eq. 8) and the potential (seed eq. 9),

    H(phi, p) = 1/2 p^T M(phi)^-1 p + V(phi),
    M = [[(m1+m2) l1^2, m2 l1 l2 cos(phi1-phi2)], [m2 l1 l2 cos(phi1-phi2), m2 l2^2]],

and its partial derivatives taken by complex-step differentiation (exact to rounding), so no
hand-derived acceleration formula is involved.

The ``rigid_*`` cases add uniform rods (plates) to the links, centred between the joints, with
the seed's plates (70 g a member, 35 cm and 25 cm long). Their share of the mass matrix and the
potential is summed over mass points (three-point Gauss-Legendre along each plate, exact for
these quadratic integrands) with the plate's point at distance r along a link moving with
r phi' normal to it: M11 += sum dm r^2 (rod 1) + m_rod2 l1^2, M12 += sum dm l1 r cos(phi1-phi2),
M22 += sum dm r^2 (rod 2); V += g sum dm (height above the rest position). No closed-form
rod coefficient is used. SciPy's DOP853 at rtol = 1e-13 integrates it;
a second run with Radau at rtol = 1e-12 estimates the reference's own error, written to
``reference_meta.json``.

Usage: ``python data/reference/make_reference.py`` (needs numpy and scipy).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

HERE = Path(__file__).resolve().parent
# The seed pendulum (double_pendulum.model.parameters defaults), written out so this script stands alone.
M1, M2, L1, L2, G = 0.301, 0.297, 0.2964, 0.1971, 9.81
NO_RODS = {"m_rod1": 0.0, "m_rod2": 0.0, "L_rod1": 0.35, "L_rod2": 0.25}
SEED_RODS = {"m_rod1": 0.070, "m_rod2": 0.070, "L_rod1": 0.35, "L_rod2": 0.25}
CASES = {
    "regular": {"y0": (0.3, 0.3, 0.0, 0.0), "stop_time": 10.0, "rods": NO_RODS},
    "chaotic": {"y0": (2.0, 2.0, 0.0, 0.0), "stop_time": 3.0, "rods": NO_RODS},
    "rigid_chaotic": {"y0": (2.0, 2.0, 0.0, 0.0), "stop_time": 3.0, "rods": SEED_RODS},
}
NODES, WEIGHTS = np.polynomial.legendre.leggauss(3)
OUTPUT_INTERVAL = 0.01
STEP = 1e-20


def rod_points(length, plate, mass):
    """Distances from the upper joint and masses of the Gauss points of a plate centred on the link."""
    lo, hi = length / 2 - plate / 2, length / 2 + plate / 2
    return lo + (hi - lo) * (NODES + 1) / 2, mass * WEIGHTS / 2


def mass_matrix(phi1, phi2, rods):
    c = np.cos(phi1 - phi2)
    r1, dm1 = rod_points(L1, rods["L_rod1"], rods["m_rod1"])
    r2, dm2 = rod_points(L2, rods["L_rod2"], rods["m_rod2"])
    m11 = (M1 + M2) * L1**2 + np.sum(dm1 * r1**2) + np.sum(dm2) * L1**2
    m12 = M2 * L1 * L2 * c + np.sum(dm2 * L1 * r2) * c
    m22 = M2 * L2**2 + np.sum(dm2 * r2**2)
    return np.array([[m11, m12], [m12, m22]])


def potential(q, rods):
    r1, dm1 = rod_points(L1, rods["L_rod1"], rods["m_rod1"])
    r2, dm2 = rod_points(L2, rods["L_rod2"], rods["m_rod2"])
    lift1, lift2 = 1 - np.cos(q[0]), 1 - np.cos(q[1])
    bobs = (M1 + M2) * G * L1 * lift1 + M2 * G * L2 * lift2
    return bobs + G * np.sum(dm1 * r1) * lift1 + G * np.sum(dm2) * L1 * lift1 + G * np.sum(dm2 * r2) * lift2


def hamiltonian(q, p, rods):
    minv = np.linalg.inv(mass_matrix(*q, rods))
    return 0.5 * p @ minv @ p + potential(q, rods)


def hamilton_rhs(t, z, rods):
    q, p = z[:2].astype(complex), z[2:].astype(complex)
    dq, dp = np.zeros(2), np.zeros(2)
    for k in range(2):
        e = np.zeros(2)
        e[k] = STEP
        dq[k] = hamiltonian(q, p + 1j * e, rods).imag / STEP
        dp[k] = -hamiltonian(q + 1j * e, p, rods).imag / STEP
    return np.concatenate([dq, dp])


def to_momenta(y, rods):
    return np.concatenate([y[:2], mass_matrix(y[0], y[1], rods) @ y[2:]])


def to_velocities(z, rods):
    return np.concatenate([z[:2], np.linalg.solve(mass_matrix(z[0], z[1], rods), z[2:])])


def integrate(y0, stop_time, rods, method, rtol, atol):
    times = np.round(np.arange(0.0, stop_time + OUTPUT_INTERVAL / 2, OUTPUT_INTERVAL), 10)
    sol = solve_ivp(
        hamilton_rhs,
        (0.0, stop_time),
        to_momenta(np.array(y0, float), rods),
        method=method,
        rtol=rtol,
        atol=atol,
        t_eval=times,
        args=(rods,),
    )
    return times, np.array([to_velocities(z, rods) for z in sol.y.T])


def main() -> None:
    meta = {"parameters": {"m1": M1, "m2": M2, "l1": L1, "l2": L2, "g": G}, "cases": {}}
    for name, case in CASES.items():
        times, ref = integrate(case["y0"], case["stop_time"], case["rods"], "DOP853", 1e-13, 1e-14)
        _, check = integrate(case["y0"], case["stop_time"], case["rods"], "Radau", 1e-12, 1e-14)
        header = '"time [s]","phi1 [rad]","phi2 [rad]","omega1 [rad/s]","omega2 [rad/s]"'
        rows = [",".join(repr(float(v)) for v in (t, *y)) for t, y in zip(times, ref)]
        (HERE / f"{name}.csv").write_text(header + "\n" + "\n".join(rows) + "\n")
        meta["cases"][name] = {
            "start": dict(zip(("phi1_0", "phi2_0", "omega1_0", "omega2_0"), case["y0"])),
            "rods": case["rods"],
            "stop_time_s": case["stop_time"],
            "max_abs_difference_dop853_vs_radau": float(np.max(np.abs(ref - check))),
        }
    (HERE / "reference_meta.json").write_text(json.dumps(meta, indent=2) + "\n")
    print(json.dumps(meta, indent=2))


if __name__ == "__main__":
    main()
