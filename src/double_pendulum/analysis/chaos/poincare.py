"""Poincare sections of the frictionless pendulum: starts on the section ``phi1 = 0``, ``omega1 > 0`` at a
given energy, and the crossings located on each RK4 step's cubic Hermite interpolant."""

from __future__ import annotations

import math

import numpy as np

from ...model.energy import kinetic_energy, potential_energy
from ...model.parameters import PendulumParameters
from .ensemble import (
    BatchField,
    initial_states,
    n_fixed_steps,
    rk4_iterate,
)


# ---------------------------------------------------------------------------- Poincare sections
def section_starts(
    energy: float,
    phi2: np.ndarray,
    omega2: np.ndarray,
    params: PendulumParameters,
) -> np.ndarray:
    """Starts on the section ``phi1 = 0``, ``omega1 > 0`` with total energy ``energy`` [J].

    For each ``(phi2, omega2)`` the kinetic energy is a quadratic ``a w1^2 + b w1 + c`` in
    ``w1 = omega1``; its coefficients are read off :func:`double_pendulum.model.energy.kinetic_energy` at
    ``w1 = -1, 0, 1`` and the larger root of ``a w1^2 + b w1 + c = E - V`` is taken. Points without
    a real root are dropped. Returns ``(4, n)``.
    """
    phi2, omega2 = np.broadcast_arrays(np.asarray(phi2, float), np.asarray(omega2, float))
    zero = np.zeros_like(phi2)

    def t_kin(w1: float) -> np.ndarray:
        return kinetic_energy(zero, phi2, w1, omega2, params, cos=np.cos)

    t_m, t_0, t_p = t_kin(-1.0), t_kin(0.0), t_kin(1.0)
    a, b = 0.5 * (t_p + t_m) - t_0, 0.5 * (t_p - t_m)
    c = t_0 + potential_energy(zero, phi2, params, cos=np.cos) - energy
    disc = b * b - 4.0 * a * c
    ok = disc >= 0.0
    omega1 = (-b[ok] + np.sqrt(disc[ok])) / (2.0 * a[ok])
    keep = omega1 > 0.0
    return initial_states(0.0, phi2[ok][keep], omega1[keep], omega2[ok][keep])


def _hermite(ya: np.ndarray, yb: np.ndarray, fa: np.ndarray, fb: np.ndarray, h: float, theta: np.ndarray):
    """Cubic Hermite interpolant on a step and its derivative d/dt, at fractions ``theta`` of the step."""
    t2, t3 = theta * theta, theta * theta * theta
    value = (2 * t3 - 3 * t2 + 1) * ya + h * (t3 - 2 * t2 + theta) * fa + (3 * t2 - 2 * t3) * yb + h * (t3 - t2) * fb
    rate = ((6 * t2 - 6 * theta) * ya + (6 * theta - 6 * t2) * yb) / h + (3 * t2 - 4 * theta + 1) * fa
    return value, rate + (3 * t2 - 2 * theta) * fb


def poincare_section(field: BatchField, y0: np.ndarray, t_end: float, h: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Crossings of ``phi1 = 0 (mod 2 pi)`` with ``omega1 > 0``: ``(points (m, 4), trajectory index (m,))``.

    A crossing is a sign change of ``sin(phi1)`` from - to + with ``cos(phi1) > 0`` between RK4
    steps; it is located on the step's cubic Hermite interpolant (from the states and their
    derivatives at both ends, error O(h^4)) by Newton's method.
    """
    pts, owner = [], []
    y_prev = np.array(y0, dtype=float)
    s_prev = np.sin(y_prev[0])
    t_prev = 0.0
    for _, t, y in rk4_iterate(field, y_prev, h, n_fixed_steps(t_end, h)):
        s_new = np.sin(y[0])
        hit = (s_prev < 0.0) & (s_new >= 0.0) & (np.cos(y[0]) > 0.0)
        if np.any(hit):
            ya, yb, step = y_prev[:, hit], y[:, hit], t - t_prev
            fa, fb = field(t_prev, ya), field(t, yb)
            target = 2.0 * math.pi * np.round(yb[0] / (2.0 * math.pi))
            theta = (target - ya[0]) / (yb[0] - ya[0])
            for _ in range(4):
                value, rate = _hermite(ya, yb, fa, fb, step, theta)
                theta = np.clip(theta - (value[0] - target) / (rate[0] * step), 0.0, 1.0)
            point, _ = _hermite(ya, yb, fa, fb, step, theta)
            point[0] -= target
            pts.append(point.T)
            owner.append(np.nonzero(hit)[0])
        y_prev, s_prev, t_prev = y.copy(), s_new, t
    if not pts:
        return np.empty((0, y0.shape[0])), np.empty(0, dtype=int)
    return np.concatenate(pts), np.concatenate(owner)
