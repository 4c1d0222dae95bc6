"""An independent formulation of the pendulum for the tests: Lagrange's equations assembled numerically.

Nothing here uses the package's equations (no J, K, S coefficients, no hand-derived terms): the
bodies are point masses, each rod a set of Gauss-Legendre points carrying its mass (exact for the
energies and accelerations, which are polynomials of degree <= 2 in the distance along the rod),
positions are written from the geometry, velocities come from positions by a complex step (exact
to rounding), and

    T(q, qd) = sum 1/2 dm |v|^2 + 1/2 M_s |s'|^2,
    V(q) = sum dm g (y - y_s) + 1/2 k_x x_s^2 + 1/2 k_y y_s^2

(the spring preload carries all weights, so the potential of the pendulum is taken relative to the
pivot). The mass matrix is the polarisation of the quadratic form T, the Lagrange equations

    M(q) qdd = dT/dq - (dM/dt) qd - dV/dq + Q

take their first derivatives by fourth-order central differences (error ~1e-12 relative), and the
generalised forces Q are virtual works: air drag as forces at the bobs and integrals over the rods'
plates (adaptive quadrature split at the sign change), joint torques as torques. Coordinates
q = (phi1, phi2, xs, ys); ``free`` selects the ones that move (fixed pivot: the two angles).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.integrate import quad

from double_pendulum.model.vector_field import ModelConfig

NODES, WEIGHTS = np.polynomial.legendre.leggauss(3)
CSTEP = 1e-20


class IndependentPendulum:
    """The scene ``config``'s pendulum, as bodies and Lagrange's equations (see the module docstring)."""

    def __init__(self, config: ModelConfig) -> None:
        p, s = config.pendulum, config.suspension
        self.config, self.g = config, p.g
        self.l1, self.l2 = p.l1, p.l2
        links, dists, masses = [1, 2], [p.l1, p.l2], [p.m1, p.m2]
        self.plates = []
        for link, length, plate, mass in ((1, p.l1, p.L_rod1, p.m_rod1), (2, p.l2, p.L_rod2, p.m_rod2)):
            plate = plate if plate > 0.0 else length  # L_rod = 0: the plate spans joint to joint
            lo, hi = length / 2 - plate / 2, length / 2 + plate / 2
            self.plates.append((link, lo, hi))
            for node, weight in zip(NODES, WEIGHTS):
                links.append(link)
                dists.append(lo + (hi - lo) * (node + 1) / 2)
                masses.append(mass * weight / 2)
        self.link = np.array(links)
        self.dist = np.array(dists, float)
        self.dm = np.array(masses, float)
        free = [0, 1]
        if s.suspension and s.suspension_x:
            free.append(2)
        if s.suspension and s.suspension_y:
            free.append(3)
        self.free = free
        self.m_s, self.k = s.M_s, (s.k_x, s.k_y)
        self.c = (s.c_x, s.c_y) if s.suspension else (0.0, 0.0)

    # ------------------------------------------------------------------ geometry
    def point(self, q: np.ndarray, link: int | np.ndarray, r: float | np.ndarray) -> np.ndarray:
        """Positions (x, y) [m] of points at distance ``r`` along ``link`` (rows: x, y)."""
        e1 = np.array([np.sin(q[0]), -np.cos(q[0])])[:, None]
        e2 = np.array([np.sin(q[1]), -np.cos(q[1])])[:, None]
        on2 = np.asarray(link) == 2
        r = np.asarray(r, float)
        # link 1: s + r e1; link 2: s + l1 e1 + r e2
        return q[2:4, None] + np.where(on2, self.l1, r) * e1 + np.where(on2, r, 0.0) * e2

    def velocity(self, q: np.ndarray, qd: np.ndarray, link, r) -> np.ndarray:
        """Velocities [m/s] of the points: the complex-step derivative of their positions along ``qd``."""
        return self.point(q + 1j * CSTEP * qd, link, r).imag / CSTEP

    # ------------------------------------------------------------------ energies
    def kinetic(self, q: np.ndarray, qd: np.ndarray) -> float:
        v = self.velocity(q, qd, self.link, self.dist)
        return float(0.5 * np.sum(self.dm * (v[0] ** 2 + v[1] ** 2)) + 0.5 * self.m_s * (qd[2] ** 2 + qd[3] ** 2))

    def potential(self, q: np.ndarray) -> float:
        y = self.point(q, self.link, self.dist)[1] - q[3]
        y_rest = self.point(np.zeros(4), self.link, self.dist)[1]
        return float(
            self.g * np.sum(self.dm * (y - y_rest)) + 0.5 * self.k[0] * q[2] ** 2 + 0.5 * self.k[1] * q[3] ** 2
        )

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        n = len(self.free)
        unit = np.zeros((n, 4))
        for a, i in enumerate(self.free):
            unit[a, i] = 1.0
        m = np.empty((n, n))
        for a in range(n):
            m[a, a] = 2.0 * self.kinetic(q, unit[a])
            for b in range(a):
                m[a, b] = m[b, a] = (
                    self.kinetic(q, unit[a] + unit[b]) - self.kinetic(q, unit[a]) - self.kinetic(q, unit[b])
                )
        return m

    # ------------------------------------------------------------------ equations
    @staticmethod
    def derivative(f: Callable[[float], np.ndarray | float], speed: float = 1.0) -> np.ndarray | float:
        """Fourth-order central difference of ``f`` at 0 (step 1e-3 / speed, ``speed`` the size of the direction)."""
        h = 1e-3 / max(1.0, speed)
        return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h)

    def accelerations(self, q: np.ndarray, qd: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """Solve Lagrange's equations for the free coordinates' accelerations; ``forces``: Q (4 entries)."""
        free = self.free
        m = self.mass_matrix(q)
        m_dot = self.derivative(lambda h: self.mass_matrix(q + h * qd), np.max(np.abs(qd)))
        rhs = np.empty(len(free))
        for a, i in enumerate(free):
            e = np.zeros(4)
            e[i] = 1.0
            dt_dq = self.derivative(lambda h: self.kinetic(q + h * e, qd))  # noqa: B023
            dv_dq = self.derivative(lambda h: self.potential(q + h * e))  # noqa: B023
            rhs[a] = dt_dq - dv_dq + forces[i]
        rhs -= m_dot @ qd[free]
        return np.linalg.solve(m, rhs)

    def damping_forces(self, qd: np.ndarray) -> np.ndarray:
        """Generalised forces of the suspension dampers [N]."""
        return np.array([0.0, 0.0, -self.c[0] * qd[2], -self.c[1] * qd[3]])

    @staticmethod
    def joint_torque_forces(tau_pivot: float, tau_elbow: float) -> np.ndarray:
        """Generalised forces of friction torques along omega1 (pivot) and omega2 - omega1 (elbow), opposing."""
        return np.array([-tau_pivot + tau_elbow, -tau_elbow, 0.0, 0.0])

    # ------------------------------------------------------------------ air drag
    def _jacobian_column(self, q: np.ndarray, k: int, link, r) -> np.ndarray:
        e = np.zeros(4)
        e[k] = 1.0
        return self.velocity(q, e, link, r)

    def bob_drag(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Drag forces on the two bobs (columns) [N]: -1/2 rho cw A |v| v."""
        air = self.config.air
        v = self.velocity(q, qd, np.array([1, 2]), np.array([self.l1, self.l2]))
        k = 0.5 * air.rho_air * air.cw * np.array([air.A1, air.A2])
        return -k * np.hypot(v[0], v[1]) * v, v

    def rod_drag_density(self, q: np.ndarray, qd: np.ndarray, link: int, r: float) -> np.ndarray:
        """Drag force per length [N/m] at distance ``r`` along a rod: -kappa |v_n| v_n n."""
        air = self.config.air
        kappa = 0.5 * air.rho_air * air.cw_rod * (air.d_rod1 if link == 1 else air.d_rod2)
        phi = q[link - 1]
        n = np.array([np.cos(phi), np.sin(phi)])
        v = self.velocity(q, qd, link, r)[:, 0]
        vn = v @ n
        return -kappa * abs(vn) * vn * n

    def _rod_integral(self, q, qd, link: int, integrand: Callable[[float], float]) -> float:
        _, lo, hi = self.plates[link - 1]
        phi = q[link - 1]
        n = np.array([np.cos(phi), np.sin(phi)])
        a = self.velocity(q, qd, link, lo)[:, 0] @ n
        b = self.velocity(q, qd, link, hi)[:, 0] @ n
        kink = [lo + (hi - lo) * a / (a - b)] if a * b < 0 else None
        return quad(integrand, lo, hi, points=kink, epsabs=0.0, epsrel=1e-13, limit=200)[0]

    def air_forces(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Generalised air forces Q, the total drag force on the pendulum and the drag on bob 2 [N]."""
        air = self.config.air
        forces, total = np.zeros(4), np.zeros(2)
        if not air.air_drag:
            return forces, total, np.zeros(2)
        drag, _ = self.bob_drag(q, qd)
        for k in range(4):
            cols = self._jacobian_column(q, k, np.array([1, 2]), np.array([self.l1, self.l2]))
            forces[k] += np.sum(drag * cols)
        total += drag.sum(axis=1)
        if air.rod_drag:
            for link in (1, 2):
                for k in range(4):
                    forces[k] += self._rod_integral(
                        q, qd, link,
                        lambda r, k=k, link=link: self.rod_drag_density(q, qd, link, r)
                        @ self._jacobian_column(q, k, link, r)[:, 0],
                    )  # fmt: skip
                for axis in (0, 1):
                    total[axis] += self._rod_integral(
                        q, qd, link, lambda r, axis=axis, link=link: self.rod_drag_density(q, qd, link, r)[axis]
                    )
        return forces, total, drag[:, 1]

    # ------------------------------------------------------------------ joint loads
    def point_accelerations(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """Accelerations [m/s^2] of all mass points: J qdd + (dJ/dt) qd."""
        along = self.velocity(q, qdd, self.link, self.dist)
        turn = self.derivative(lambda h: self.velocity(q + h * qd, qd, self.link, self.dist), np.max(np.abs(qd)))
        return along + turn

    def joint_loads(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forces [N] of the pivot on the pendulum and of the elbow on link 2 (bob 2 and rod 2).

        Newton for the bodies each joint carries: sum dm a = joint force + gravity + air drag
        (drag of rod 2 left out of the elbow load, as in the model).
        """
        acc = self.point_accelerations(q, qd, qdd)
        weight = self.g * np.array([0.0, 1.0])
        _, total, drag2 = self.air_forces(q, qd)
        pivot = np.sum(self.dm * acc, axis=1) + np.sum(self.dm) * weight - total
        on2 = self.link == 2
        elbow = np.sum(self.dm[on2] * acc[:, on2], axis=1) + np.sum(self.dm[on2]) * weight - drag2
        return pivot, elbow
